/* Portable builds: the techniques' AVX2 copy, chosen at run time, and the
 * baseline x86-64 code draw the same bits, on examples that take every technique (height
 * fields, solids, a curved mesh). MESO_ISA=baseline makes the registry hand out the baseline
 * copy. Skipped where the build has no AVX2 copy (a -DMESO_NATIVE=ON build, another
 * architecture) or the CPU cannot run it. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "example_renders.h"

static const char *const examples[] = {"bricks-plane", "bumps-sphere", "weave-torus"};

/* The example drawn with `technique` through the copy `isa` names (NULL: the CPU's choice). */
static meso_framebuffer *render(const meso_scene *scene, const char *technique, const char *isa) {
    if (isa)
        setenv("MESO_ISA", isa, 1);
    else
        unsetenv("MESO_ISA");
    meso_framebuffer *fb = example_render(scene, technique, 2);
    unsetenv("MESO_ISA");
    return fb;
}

static void test_avx2_and_baseline_techniques_draw_the_same_bits(void **state) {
    (void)state;
    setenv("MESO_ISA", "baseline", 1);
    assert_string_not_equal(meso_technique_isa(), "avx2");
    unsetenv("MESO_ISA");
    if (strcmp(meso_technique_isa(), "avx2") != 0) {
        print_message("techniques run as '%s': no AVX2 copy to compare\n", meso_technique_isa());
        skip();
    }
    int compared = 0;
    for (size_t e = 0; e < sizeof examples / sizeof examples[0]; e++) {
        meso_context *ctx = test_context(1);
        meso_scene *scene = example_scene_load(ctx, examples[e], 64);
        for (size_t t = 0; t < meso_technique_count(); t++) {
            const char *name = meso_technique_get(t)->name;
            if (strcmp(name, "reference") == 0) continue; /* not a rasterized technique */
            meso_framebuffer *avx2 = render(scene, name, NULL);
            meso_framebuffer *baseline = render(scene, name, "baseline");
            size_t pixels = (size_t)avx2->width * (size_t)avx2->height;
            if (memcmp(avx2->color, baseline->color, sizeof(float) * 3 * pixels) != 0 ||
                memcmp(avx2->depth, baseline->depth, sizeof(float) * pixels) != 0)
                fail_msg("%s with %s: the AVX2 and baseline images differ", examples[e], name);
            meso_framebuffer_destroy(avx2);
            meso_framebuffer_destroy(baseline);
            compared++;
        }
        meso_scene_destroy(scene);
        meso_context_destroy(ctx);
    }
    print_message("%d comparisons, all identical\n", compared);
    assert_true(compared >= 3 * 10);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_avx2_and_baseline_techniques_draw_the_same_bits),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
