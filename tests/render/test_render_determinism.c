/* Determinism (docs/design.md): every example x every technique that draws it, and the
 * reference, gives the same image bytes with 1, 2 and 7 threads. Small images and small bakes
 * keep it short; the bakes go through the build tree's cache, so the 2- and 7-thread runs read
 * what the 1-thread run baked — and the bakes' own thread independence is tested beside them
 * (test_bake_vdm, test_bake_layers). */
#include <stdio.h>
#include <string.h>

#include "example_renders.h"

/* The examples as shipped in examples/ (the effect scenes there are bricks-plane re-lit). */
static const char *const examples[] = {"bricks-plane",   "bricks-teapot", "bumps-sphere",
                                       "weave-plane",    "weave-torus",   "chainmail-plane",
                                       "teapot-impostor"};

static void test_every_example_and_technique_is_identical_for_1_2_and_7_threads(void **state) {
    (void)state;
    int compared = 0;
    for (size_t e = 0; e < sizeof examples / sizeof examples[0]; e++) {
        meso_context *ctx = test_context(1);
        meso_scene *scene = example_scene_load(ctx, examples[e], 48);
        for (size_t t = 0; t < meso_technique_count(); t++) {
            const meso_technique_info *technique = meso_technique_get(t);
            /* GDM's bake needs a solid that tiles; the impostor's model is refused with a
             * message (docs/techniques/gdm.md) */
            if (strcmp(technique->name, "gdm") == 0 && strcmp(examples[e], "teapot-impostor") == 0)
                continue;
            /* with fallback, an object the technique cannot draw uses its own technique */
            meso_framebuffer *one = example_render(scene, technique->name, 1);
            size_t bytes = sizeof(float) * 3 * (size_t)one->width * (size_t)one->height;
            for (int threads = 2; threads <= 7; threads += 5) {
                meso_framebuffer *many = example_render(scene, technique->name, threads);
                if (memcmp(one->color, many->color, bytes) != 0 ||
                    memcmp(one->depth, many->depth, bytes / 3) != 0)
                    fail_msg("%s with %s: 1 and %d threads differ", examples[e], technique->name,
                             threads);
                meso_framebuffer_destroy(many);
                compared++;
            }
            meso_framebuffer_destroy(one);
        }
        meso_scene_destroy(scene);
        meso_context_destroy(ctx);
    }
    print_message("%d comparisons, all identical\n", compared);
    assert_true(compared >= 2 * 7 * 10);
}

/* Footprint filtering (docs/techniques.md, "Filtering") reads per-fragment derivatives and mip
 * chains: the same bytes for 1 and 7 threads on the examples with colour maps, with every
 * technique. */
static void test_filtered_examples_are_identical_for_1_and_7_threads(void **state) {
    (void)state;
    static const char *const filtered[] = {"tiles-floor", "bricks-plane", "bricks-teapot"};
    int compared = 0;
    for (size_t e = 0; e < sizeof filtered / sizeof filtered[0]; e++) {
        meso_context *ctx = test_context(1);
        meso_scene *scene = example_scene_load(ctx, filtered[e], 40);
        for (size_t t = 0; t < meso_technique_count(); t++) {
            const char *name = meso_technique_get(t)->name;
            meso_framebuffer *one =
                example_render_filtered(scene, name, 1, MESO_RENDER_FILTER_FOOTPRINT);
            meso_framebuffer *many =
                example_render_filtered(scene, name, 7, MESO_RENDER_FILTER_FOOTPRINT);
            size_t bytes = sizeof(float) * 3 * (size_t)one->width * (size_t)one->height;
            if (memcmp(one->color, many->color, bytes) != 0)
                fail_msg("%s with %s, filter 1: 1 and 7 threads differ", filtered[e], name);
            meso_framebuffer_destroy(one);
            meso_framebuffer_destroy(many);
            compared++;
        }
        meso_scene_destroy(scene);
        meso_context_destroy(ctx);
    }
    assert_true(compared >= 3 * 10);
}

int main(void) {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_example_and_technique_is_identical_for_1_2_and_7_threads),
        cmocka_unit_test(test_filtered_examples_are_identical_for_1_and_7_threads),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
