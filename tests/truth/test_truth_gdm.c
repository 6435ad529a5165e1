/* Agreement with the truth: gdm against `reference` on the scenes of tests/data/truth/, held to
 * the floors of truth_table.h. A separate executable from test_truth.c, as test_truth_vdm.c,
 * so that ctest runs GDM's bakes beside the other techniques. */
#include "truth_suite.h"

static bool select_gdm(const char *technique) { return strcmp(technique, "gdm") == 0; }

int main(void) { return truth_run("truth_gdm", select_gdm); }
