/* Fuzz target: the bake container (meso_bake_file_load) and every kind's loader that reads
 * one: VDM (meso_vdm_from_bake_file, meso_vdm_describe), relief layers
 * (meso_layers_from_bake_file, meso_layers_describe), GDM (meso_gdm_from_bake_file,
 * meso_gdm_describe) and the RTV (meso_rtv_from_bake_file, meso_rtv_describe). */
#include "fuzz_target.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    meso_context *ctx = fuzz_context();
    meso_bake_file *bake = NULL;
    if (meso_bake_file_load(ctx, fuzz_write_file(data, size, "mesobake"), &bake) != MESO_OK)
        return 0;
    meso_vdm *vdm = NULL;
    if (meso_vdm_from_bake_file(ctx, bake, "fuzz", &vdm) == MESO_OK) meso_vdm_destroy(vdm);
    meso_layers *layers = NULL;
    if (meso_layers_from_bake_file(ctx, bake, "fuzz", &layers) == MESO_OK)
        meso_layers_destroy(layers);
    meso_gdm *gdm = NULL;
    if (meso_gdm_from_bake_file(ctx, bake, "fuzz", &gdm) == MESO_OK) meso_gdm_destroy(gdm);
    meso_rtv *rtv = NULL;
    if (meso_rtv_from_bake_file(ctx, bake, "fuzz", &rtv) == MESO_OK) meso_rtv_destroy(rtv);
    char text[256];
    meso_vdm_describe(bake, text, sizeof text);
    meso_layers_describe(bake, text, sizeof text);
    meso_gdm_describe(bake, text, sizeof text);
    meso_rtv_describe(bake, text, sizeof text);
    meso_bake_file_destroy(bake);
    return 0;
}
