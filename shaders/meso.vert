// meso.vert: the vertex shader of every meso technique (GLSL 3.30 core).
//
// Inputs (one vertex of the base mesh, world space: meso applies the object's transform and
// uv_scale on the CPU; an engine multiplies by its model matrix here instead):
//   location 0  vec3 a_position   point on the base mesh (the top of the shell)
//   location 1  vec3 a_normal     unit outward normal N
//   location 2  vec3 a_tangent    T = dP/du, unnormalised (its length is world units per u)
//   location 3  vec3 a_bitangent  B = dP/dv, unnormalised; T x B points along N unless the
//                                 UVs are mirrored
//   location 4  vec2 a_uv         texture coordinates, OpenGL convention (v = 0 at the bottom
//                                 row of an image file)
//   location 5  vec2 a_quadric    (a, b): the surface falls away below the tangent plane by
//                                 a x^2 + b y^2 along T^, B^ (Oliveira & Policarpo 2005);
//                                 (0, 0) on flat meshes
//   location 6  vec2 a_curvature  principal curvatures (k_max, k_min), 1 / world units
//   location 7  vec3 a_curvature_dir_max, location 8 vec3 a_curvature_dir_min: their unit
//                                 directions in the tangent plane (vdm only; zero elsewhere)
// Uniforms:
//   mat4 u_view_projection        projection * view (column-major, OpenGL clip space)
//   vec3 u_eye                    camera position
// Outputs: the same quantities, interpolated perspective-correct; the fragment shaders read T
// and B unnormalised and renormalise N.
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec3 a_tangent;
layout(location = 3) in vec3 a_bitangent;
layout(location = 4) in vec2 a_uv;
layout(location = 5) in vec2 a_quadric;
layout(location = 6) in vec2 a_curvature;
layout(location = 7) in vec3 a_curvature_dir_max;
layout(location = 8) in vec3 a_curvature_dir_min;

uniform mat4 u_view_projection;
uniform vec3 u_eye;

out vec3 v_position;
out vec3 v_normal;
out vec3 v_tangent;
out vec3 v_bitangent;
out vec2 v_uv;
out vec2 v_quadric;
out float v_curvature_view; // the curvature along the view direction (VDM §3.2), per vertex

// VDM §3.2: c_V = (c_max (V.C_max)^2 + c_min (V.C_min)^2) / (1 - (V.N)^2) at this vertex.
float curvature_along_view() {
    vec3 view = normalize(u_eye - a_position);
    float vn = dot(view, a_normal);
    float a = dot(view, a_curvature_dir_max), b = dot(view, a_curvature_dir_min);
    float denominator = 1.0 - vn * vn;
    if (denominator < 1e-6) return 0.5 * (a_curvature.x + a_curvature.y); // V along N: the mean
    return (a_curvature.x * a * a + a_curvature.y * b * b) / denominator;
}

void main() {
    v_position = a_position;
    v_normal = a_normal;
    v_tangent = a_tangent;
    v_bitangent = a_bitangent;
    v_uv = a_uv;
    v_quadric = a_quadric;
    v_curvature_view = curvature_along_view();
    gl_Position = u_view_projection * vec4(a_position, 1.0);
}
