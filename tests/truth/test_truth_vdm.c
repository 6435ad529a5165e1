/* Agreement with the truth: vdm against `reference` on the scenes of tests/data/truth/, held to
 * the floors of truth_table.h. A separate executable from test_truth.c so that ctest runs VDM's
 * bakes, the slowest part of the suite, beside the other techniques. */
#include "truth_suite.h"

static bool select_vdm(const char *technique) { return strcmp(technique, "vdm") == 0; }

int main(void) { return truth_run("truth_vdm", select_vdm); }
