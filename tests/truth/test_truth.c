/* Agreement with the truth: every technique but vdm and gdm against `reference` on the scenes
 * of tests/data/truth/, held to the floors of truth_table.h (VDM's and GDM's rows run in
 * test_truth_vdm.c and test_truth_gdm.c, so ctest runs their slower bakes in parallel). */
#include "truth_suite.h"

static bool select_all_but_vdm(const char *technique) {
    return strcmp(technique, "vdm") != 0 && strcmp(technique, "gdm") != 0;
}

/* The table has a row for every scene and every technique that can draw a height field, so a
 * technique added to the registry is measured against the truth from its first day. */
static void test_truth_table_covers_every_technique_and_scene(void **state) {
    (void)state;
    for (size_t t = 0; t < meso_technique_count(); t++) {
        const meso_technique_info *info = meso_technique_get(t);
        if (info->kind == MESO_TECHNIQUE_REFERENCE ||
            !(info->accepts & MESO_TECHNIQUE_ACCEPTS_HEIGHT_FIELD))
            continue;
        for (size_t s = 0; s < TRUTH_NUM_SCENES; s++) {
            bool found = false;
            for (size_t r = 0; r < sizeof(truth_rows) / sizeof(truth_rows[0]); r++)
                found |= strcmp(truth_rows[r].scene, truth_scenes[s]) == 0 &&
                         strcmp(truth_rows[r].technique, info->name) == 0;
            if (!found) fail_msg("truth_table.h: no row for %s on %s", info->name, truth_scenes[s]);
        }
    }
    for (size_t r = 0; r < sizeof(truth_rows) / sizeof(truth_rows[0]); r++) {
        bool known = false;
        for (size_t s = 0; s < TRUTH_NUM_SCENES; s++)
            known |= strcmp(truth_rows[r].scene, truth_scenes[s]) == 0;
        if (!known)
            fail_msg("truth_table.h: row %zu: scene %s is not in truth_scenes[]", r,
                     truth_rows[r].scene);
    }
}

int main(void) {
    const struct CMUnitTest table_tests[] = {
        cmocka_unit_test(test_truth_table_covers_every_technique_and_scene),
    };
    int failed = cmocka_run_group_tests(table_tests, NULL, NULL);
    return failed + truth_run("truth", select_all_but_vdm);
}
