/* Bake the RTV of the examples' mesostructures and print its size and RMSE per eigenfunction
 * count (docs/techniques/gdm-gi.md): scripts/measure-rtv.sh builds and runs this.
 *
 *   measure_rtv WIDTH LAYERS NUM_THETA NUM_PHI
 */
#include <stdio.h>
#include <stdlib.h>

#include <meso/meso.h>

static void report(const char *name, const meso_rtv *rtv) {
    printf("%s: %dx%dx%d voxels, %dx%d views, %d eigenfunctions: %.1f s; raw %.2f MB, "
           "compressed %.2f MB\n  RMSE k=1..8:",
           name, rtv->width, rtv->height, rtv->layers, rtv->num_theta, rtv->num_phi, rtv->num_eigen,
           rtv->bake_seconds, rtv->raw_bytes / 1e6, rtv->compressed_bytes / 1e6);
    for (int k = 0; k < 8; k++) printf(" %.4f", rtv->rmse[k]);
    printf("\n");
}

int main(int argc, char **argv) {
    if (argc != 5) {
        fprintf(stderr, "usage: measure_rtv WIDTH LAYERS NUM_THETA NUM_PHI\n");
        return 2;
    }
    int width = atoi(argv[1]), layers = atoi(argv[2]);
    meso_context *ctx = NULL;
    if (meso_context_create(&(meso_context_desc){0}, &ctx) != MESO_OK) return 1;
    meso_heightfield *bark = NULL;
    meso_solid *weave = NULL;
    meso_rtv *rtv = NULL;
    meso_rtv_desc desc = {.width = width,
                          .height = width,
                          .layers = layers,
                          .num_theta = atoi(argv[3]),
                          .num_phi = atoi(argv[4])};
    /* examples/bark-cylinder.json: depth 0.08 over tiles about 0.94 x 1.2 wide */
    meso_heightfield_desc bark_desc = {
        .kind = MESO_HEIGHTFIELD_BARK, .resolution = 512, .bevel = 0.01f};
    meso_result r = meso_heightfield_create_procedural(ctx, &bark_desc, &bark, NULL);
    if (r == MESO_OK) {
        desc.heightfield = bark, desc.aspect = 0.08f / 1.07f;
        if ((r = meso_rtv_bake(ctx, &desc, &rtv)) == MESO_OK) report("bark-cylinder", rtv);
        meso_rtv_destroy(rtv);
        rtv = NULL;
    }
    /* examples/weave-teapot.json: depth 0.04, a tile about 0.2 wide on the body */
    if (r == MESO_OK &&
        (r = meso_solid_create_procedural(ctx, &(meso_solid_desc){.kind = MESO_SOLID_WEAVE},
                                          &weave)) == MESO_OK) {
        desc.heightfield = NULL, desc.solid = weave, desc.aspect = 0.2f;
        if ((r = meso_rtv_bake(ctx, &desc, &rtv)) == MESO_OK) report("weave-teapot", rtv);
        meso_rtv_destroy(rtv);
    }
    if (r != MESO_OK) fprintf(stderr, "meso: %s\n", meso_context_last_error(ctx));
    meso_solid_destroy(weave);
    meso_heightfield_destroy(bark);
    meso_context_destroy(ctx);
    return r == MESO_OK ? 0 : 1;
}
