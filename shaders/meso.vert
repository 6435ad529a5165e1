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
// Uniforms:
//   mat4 u_view_projection        projection * view (column-major, OpenGL clip space)
// Outputs: the same quantities, interpolated perspective-correct; the fragment shaders read T
// and B unnormalised and renormalise N.
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec3 a_tangent;
layout(location = 3) in vec3 a_bitangent;
layout(location = 4) in vec2 a_uv;
layout(location = 5) in vec2 a_quadric;

uniform mat4 u_view_projection;

out vec3 v_position;
out vec3 v_normal;
out vec3 v_tangent;
out vec3 v_bitangent;
out vec2 v_uv;
out vec2 v_quadric;

void main() {
    v_position = a_position;
    v_normal = a_normal;
    v_tangent = a_tangent;
    v_bitangent = a_bitangent;
    v_uv = a_uv;
    v_quadric = a_quadric;
    gl_Position = u_view_projection * vec4(a_position, 1.0);
}
