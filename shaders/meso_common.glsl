// meso_common.glsl: what every meso fragment shader shares (GLSL 3.30 core). A technique's
// fragment shader is `#version 330 core` + this file + (for the relief family)
// meso_relief.glsl + the technique's file, in that order; the technique's first line names
// the files it needs. Conventions (docs/design.md):
//   - World space, right-handed, y up; everything here is in world units.
//   - Texture space: image column i <-> u = (i + 0.5) / W, image row j (row 0 = the top row of
//     the file) <-> v = 1 - (j + 0.5) / H. Lookups use texel-centre coordinates
//     x = u W - 0.5, y = (1 - v) H - 0.5 and read texel (i, j) with texelFetch at ivec2(i, j),
//     the texture uploaded top row first; bilinear between texel centres is done here, not by
//     the sampler, so every renderer computes the same numbers (set GL_NEAREST filtering).
//   - Depth runs inward: the mesh is the top of a shell of thickness u_depth; a height h in
//     [0, 1] lies (1 - h) u_depth below the mesh along N (white on the mesh, black at the
//     bottom). d = 1 - h is the depth in shell units.
//   - Shading (every technique and meso's ray-traced reference): linear RGB,
//     colour = albedo * colour_map(uv) * (ambient + sum_i c_i max(0, N.L_i) vis_i)
//              + sum_i specular c_i (N.H_i)^shininess vis_i   (Blinn-Phong, where N.L_i > 0).
//
// Inputs from meso.vert (interpolated): v_position, v_normal (renormalised here), v_tangent
// = dP/du, v_bitangent = dP/dv (unnormalised), v_uv, v_quadric.
//
// Uniforms:
//   vec3  u_eye                   camera position
//   vec3  u_forward               unit camera axis; view depth = dot(P - u_eye, u_forward)
//   float u_depth_range           gl_FragDepth = view depth / u_depth_range (linear depth,
//                                 a GL_DEPTH_COMPONENT32F buffer; replace meso_write for a
//                                 projective depth buffer)
//   vec3  u_ambient
//   int   u_num_lights            0..16
//   int   u_light_is_point[16]    0: directional (u_light_vector points toward the light),
//                                 1: point (u_light_vector is its position)
//   vec3  u_light_vector[16]
//   vec3  u_light_color[16]
//   vec3  u_albedo, u_specular; float u_shininess
//   bool  u_has_color_map; bool u_color_map_clamp (clamp-to-edge, else repeat)
//   sampler2D u_color_map         texture unit 0, RGBA32F (RGBA16F, RGBA8 work too),
//                                 linear colour, GL_NEAREST, level 0 only
//   sampler2D u_height            texture unit 1, R32F (R16 works too), h in [0, 1]
//   ivec2 u_height_size           its width and height in texels
//   bool  u_height_clamp          clamp-to-edge (else repeat)
//   float u_depth                 shell thickness, world units
// Outputs:
//   location 0  vec4  o_color     linear RGB, alpha 1 (coverage)
//   location 1  float o_view_depth view depth of the visible point (depth-corrected)

#define MESO_MAX_LIGHTS 16

in vec3 v_position;
in vec3 v_normal;
in vec3 v_tangent;
in vec3 v_bitangent;
in vec2 v_uv;
in vec2 v_quadric;

uniform vec3 u_eye;
uniform vec3 u_forward;
uniform float u_depth_range;
uniform vec3 u_ambient;
uniform int u_num_lights;
uniform int u_light_is_point[MESO_MAX_LIGHTS];
uniform vec3 u_light_vector[MESO_MAX_LIGHTS];
uniform vec3 u_light_color[MESO_MAX_LIGHTS];
uniform vec3 u_albedo;
uniform vec3 u_specular;
uniform float u_shininess;
uniform bool u_has_color_map;
uniform bool u_color_map_clamp;
uniform sampler2D u_color_map;
uniform sampler2D u_height;
uniform ivec2 u_height_size;
uniform bool u_height_clamp;
uniform float u_depth;

layout(location = 0) out vec4 o_color;
layout(location = 1) out float o_view_depth;

// ---- Textures ----------------------------------------------------------------------------

// The colour map at uv: bilinear between texel centres at level 0 with its wrap; 0 for a
// non-finite uv.
vec3 meso_color_map(vec2 uv) {
    if (isnan(uv.x) || isnan(uv.y) || isinf(uv.x) || isinf(uv.y)) return vec3(0.0);
    ivec2 size = textureSize(u_color_map, 0);
    if (!u_color_map_clamp) uv -= floor(uv);
    float x = uv.x * float(size.x) - 0.5, y = (1.0 - uv.y) * float(size.y) - 0.5;
    float fx = floor(x), fy = floor(y);
    float tx = x - fx, ty = y - fy;
    fx = clamp(fx, -1.0, float(size.x));
    fy = clamp(fy, -1.0, float(size.y));
    ivec2 i0 = ivec2(int(fx), int(fy)), i1 = i0 + 1;
    if (u_color_map_clamp) {
        i0 = clamp(i0, ivec2(0), size - 1);
        i1 = clamp(i1, ivec2(0), size - 1);
    } else {
        i0 += ivec2(i0.x < 0 ? size.x : 0, i0.y < 0 ? size.y : 0);
        i1 -= ivec2(i1.x >= size.x ? size.x : 0, i1.y >= size.y ? size.y : 0);
    }
    vec3 a = texelFetch(u_color_map, ivec2(i0.x, i0.y), 0).rgb;
    vec3 b = texelFetch(u_color_map, ivec2(i1.x, i0.y), 0).rgb;
    vec3 c = texelFetch(u_color_map, ivec2(i0.x, i1.y), 0).rgb;
    vec3 d = texelFetch(u_color_map, ivec2(i1.x, i1.y), 0).rgb;
    vec3 top = a + (b - a) * tx, bottom = c + (d - c) * tx;
    return top + (bottom - top) * ty;
}

// h at texel-centre coordinates p: the bilinear surface between texel centres, wrapped or
// clamped.
float meso_height_at(vec2 p) {
    vec2 size = vec2(u_height_size);
    if (u_height_clamp)
        p = clamp(p, vec2(0.0), size - 1.0);
    else
        p -= size * floor(p * (1.0 / size));
    ivec2 i0 = min(ivec2(p), u_height_size - 1);
    vec2 f = p - vec2(i0);
    ivec2 i1 = i0 + 1;
    if (u_height_clamp)
        i1 = min(i1, u_height_size - 1);
    else
        i1 -= ivec2(i1.x >= u_height_size.x ? u_height_size.x : 0,
                    i1.y >= u_height_size.y ? u_height_size.y : 0);
    float h00 = texelFetch(u_height, ivec2(i0.x, i0.y), 0).r;
    float h10 = texelFetch(u_height, ivec2(i1.x, i0.y), 0).r;
    float h01 = texelFetch(u_height, ivec2(i0.x, i1.y), 0).r;
    float h11 = texelFetch(u_height, ivec2(i1.x, i1.y), 0).r;
    float top = h00 + (h10 - h00) * f.x, bottom = h01 + (h11 - h01) * f.x;
    return top + (bottom - top) * f.y;
}

// Texel-centre coordinates of uv.
vec2 meso_height_texel(vec2 uv) {
    return vec2(uv.x * float(u_height_size.x) - 0.5, (1.0 - uv.y) * float(u_height_size.y) - 0.5);
}

// (dh/du, dh/dv) at texel-centre coordinates p: central differences one texel apart.
vec2 meso_height_gradient(vec2 p) {
    return vec2((meso_height_at(p + vec2(1.0, 0.0)) - meso_height_at(p - vec2(1.0, 0.0))) *
                    (0.5 * float(u_height_size.x)),
                (meso_height_at(p - vec2(0.0, 1.0)) - meso_height_at(p + vec2(0.0, 1.0))) *
                    (0.5 * float(u_height_size.y)));
}

// ---- Surface ------------------------------------------------------------------------------

// The fragment's frame: N unit, T, B as interpolated, and the dual basis (B x N, N x T, T x B)
// / det that writes a world direction D as D = du T + dv B + dn N by three dot products.
struct meso_frame {
    vec3 position, normal, tangent, bitangent, view; // view = position - eye
    vec3 bn, nt, tb;
    bool ok;                                         // false: degenerate frame (no UVs)
};

// The frame of a point on the base mesh with normal N (unit), T and B.
meso_frame meso_frame_make(vec3 position, vec3 normal, vec3 tangent, vec3 bitangent) {
    meso_frame f;
    f.position = position;
    f.normal = normal;
    f.tangent = tangent;
    f.bitangent = bitangent;
    f.view = position - u_eye;
    vec3 bn = cross(f.bitangent, f.normal), nt = cross(f.normal, f.tangent);
    vec3 tb = cross(f.tangent, f.bitangent);
    float det = dot(f.tangent, bn);
    f.ok = abs(det) > 1e-20;
    float inv = f.ok ? 1.0 / det : 0.0;
    f.bn = bn * inv;
    f.nt = nt * inv;
    f.tb = tb * inv;
    return f;
}

// The fragment's frame, from meso.vert's outputs.
meso_frame meso_frame_get() {
    float len2 = dot(v_normal, v_normal);
    return meso_frame_make(v_position, len2 > 0.0 ? v_normal * (1.0 / sqrt(len2)) : v_normal,
                           v_tangent, v_bitangent);
}

// The normal of the height-field surface P' = P - (1 - h) depth N over a point of frame f
// with height gradient g = (dh/du, dh/dv): normalize(cross(T + depth h_u N, B + depth h_v N))
// turned to N's side (Blinn 1978). meso_displaced_normal of meso's C.
vec3 meso_displaced_normal(meso_frame f, float depth, vec2 g) {
    vec3 n = cross(f.tangent + f.normal * (g.x * depth), f.bitangent + f.normal * (g.y * depth));
    float len2 = dot(n, n);
    if (!(len2 > 0.0) || isinf(len2)) return f.normal;
    n *= 1.0 / sqrt(len2);
    return dot(n, f.normal) < 0.0 ? -n : n;
}

// The same for the relief family and parallax (relief_normal8 of meso's C): a zero gradient
// keeps the interpolated N itself, so a flat field draws exactly the `flat` image.
vec3 meso_relief_normal(meso_frame f, float depth, vec2 g) {
    vec3 du = f.tangent + f.normal * (g.x * depth);
    vec3 dv = f.bitangent + f.normal * (g.y * depth);
    vec3 n = cross(du, dv);
    float len2 = dot(n, n);
    bool ok = len2 > 1e-30 && len2 < 1e30;
    if (!ok || (g.x == 0.0 && g.y == 0.0)) return f.normal;
    float inv = 1.0 / sqrt(len2);
    return dot(n, f.normal) < 0.0 ? -n * inv : n * inv;
}

// ---- Shading ------------------------------------------------------------------------------

// Unit direction from `position` toward light i.
vec3 meso_light_direction(int i, vec3 position) {
    if (u_light_is_point[i] == 0) return u_light_vector[i];
    vec3 l = u_light_vector[i] - position;
    float len2 = dot(l, l);
    return len2 > 0.0 ? l * (1.0 / sqrt(len2)) : l;
}

// The shading model (top of this file) at a surface point with unit normal n, colour-map
// coordinates uv and light i's visibility in visibility[i] (1: lit, 0: in shadow).
vec3 meso_shade(vec3 position, vec3 n, vec2 uv, float visibility[MESO_MAX_LIGHTS]) {
    vec3 base = u_albedo;
    if (u_has_color_map) base *= meso_color_map(uv);
    bool has_specular = u_specular.x > 0.0 || u_specular.y > 0.0 || u_specular.z > 0.0;
    vec3 v = u_eye - position;
    float v2 = dot(v, v);
    if (v2 > 0.0) v *= 1.0 / sqrt(v2);
    vec3 diffuse = u_ambient, specular = vec3(0.0);
    for (int i = 0; i < u_num_lights; ++i) {
        vec3 l = meso_light_direction(i, position);
        float ndl = dot(n, l);
        if (!(ndl > 0.0 && visibility[i] > 0.0)) continue;
        diffuse += u_light_color[i] * (ndl * visibility[i]);
        if (!has_specular) continue;
        vec3 h = l + v;
        float h2 = dot(h, h);
        if (h2 > 0.0) h *= 1.0 / sqrt(h2);
        float ndh = dot(n, h);
        if (ndh > 0.0) specular += u_light_color[i] * u_specular * (pow(ndh, u_shininess) * visibility[i]);
    }
    return base * diffuse + specular;
}

// Every light visible.
void meso_all_visible(out float visibility[MESO_MAX_LIGHTS]) {
    for (int i = 0; i < MESO_MAX_LIGHTS; ++i) visibility[i] = 1.0;
}

// Write the fragment: colour, and the view depth of the visible point (depth correction).
void meso_write(vec3 color, float view_depth) {
    o_color = vec4(color, 1.0);
    o_view_depth = view_depth;
    gl_FragDepth = clamp(view_depth / u_depth_range, 0.0, 1.0);
}
