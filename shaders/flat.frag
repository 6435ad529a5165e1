// meso:requires meso_common.glsl
// flat.frag: the base mesh shaded with its interpolated normal; the mesostructure is ignored.
// The baseline every other technique improves on. No options; no textures besides the
// colour map (meso_common.glsl lists the uniforms).

void main() {
    meso_frame f = meso_frame_get();
    float visibility[MESO_MAX_LIGHTS];
    meso_all_visible(visibility);
    meso_write(meso_shade(f.position, f.normal, v_uv, visibility), dot(f.view, u_forward));
}
