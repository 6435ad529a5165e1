// meso:requires meso_common.glsl
// bump.frag: bump mapping (Blinn 1978, "Simulation of wrinkled surfaces"): the shading normal
// of the displaced surface P' = P - (1 - h) depth N from the height field's gradient at the
// fragment's own uv; the geometry stays flat, so no parallax, no self-shadowing, no silhouette.
// No options. Textures: u_height (unit 1) and the colour map (unit 0), as in meso_common.glsl.

void main() {
    meso_frame f = meso_frame_get();
    vec3 n = meso_displaced_normal(f, u_depth, meso_height_gradient(meso_height_texel(v_uv)));
    float visibility[MESO_MAX_LIGHTS];
    meso_all_visible(visibility);
    meso_write(meso_shade(f.position, n, v_uv, visibility), dot(f.view, u_forward));
}
