/* Portable builds (issue 14 item 10): the techniques' AVX2 copy, chosen at run time, and the
 * baseline x86-64 code draw the same bits, on examples that take every technique (height
 * fields, solids, a curved mesh). MESO_ISA=baseline makes the registry hand out the baseline
 * copy. Skipped where the build has no AVX2 copy (a -DMESO_NATIVE=ON build, another
 * architecture) or the CPU cannot run it. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

static const char *const examples[] = {"bricks-plane", "bumps-sphere", "weave-torus"};

/* Small bakes for the techniques that bake, keyed by technique as --set passes them. */
static const meso_option small_bakes[] = {
    {"vdm", "resolution", 32},    {"vdm", "num_theta", 16},
    {"vdm", "num_curvatures", 4}, {"relief_layers", "size", 64},
};

static meso_framebuffer *render(const meso_scene *scene, const char *technique, const char *isa) {
    if (isa)
        setenv("MESO_ISA", isa, 1);
    else
        unsetenv("MESO_ISA");
    meso_context *ctx = test_context(2);
    meso_render_desc desc = {.technique = technique,
                             .fallback = true,
                             .options = small_bakes,
                             .num_options = (int)(sizeof small_bakes / sizeof small_bakes[0])};
    meso_framebuffer *fb = NULL;
    if (meso_render_scene(ctx, scene, &desc, &fb) != MESO_OK)
        fail_msg("%s with %s (%s): %s", scene->path, technique, meso_technique_isa(),
                 meso_context_last_error(ctx));
    meso_context_destroy(ctx);
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
        char path[1024];
        snprintf(path, sizeof path, "%s/examples/%s.json", MESO_SOURCE_DIR, examples[e]);
        meso_context *ctx = test_context(1);
        meso_scene *scene = NULL;
        if (meso_scene_load(ctx, path, &scene) != MESO_OK)
            fail_msg("%s: %s", path, meso_context_last_error(ctx));
        scene->width = scene->height = 64;
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
