/* Placeholder until the reference tracer lands (issue 3). */
#include "render_internal.h"

meso_result meso_reference_create(meso_context *ctx, const meso_scene *scene,
                                  meso_reference **out_reference) {
    (void)scene;
    *out_reference = NULL;
    return meso_log_error(ctx, MESO_ERROR_UNSUPPORTED, "reference: not implemented yet");
}
meso_result meso_reference_render(meso_context *ctx, const meso_reference *reference,
                                  const meso_frame *frame, float *color, float *coverage,
                                  float *depth) {
    return meso_log_error(ctx, MESO_ERROR_UNSUPPORTED, "reference: not implemented yet");
}
size_t meso_reference_memory(const meso_reference *reference) { return 0; }
uint64_t meso_reference_triangle_count(const meso_reference *reference) { return 0; }
void meso_reference_destroy(meso_reference *reference) {}
