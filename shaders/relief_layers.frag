// meso:requires meso_common.glsl meso_relief.glsl
// relief_layers.frag: relief mapping of non-height-field surface details (Policarpo & Oliveira
// 2006, §3) with a multilayer relief map: up to 4 (or 8) depths per texel, a ray at depth d
// being inside the solid where an odd number of them are <= d (§3.1). Algorithm 1's linear
// search and Algorithm 2's binary search, then a secant step; the interface rule of §3.2 for
// the texel whose normals shade the hit; self-shadows by a search toward each light;
// silhouettes, depth correction and shading as relief (meso_relief.glsl). Height fields are one
// layer (§3, Fig. 10) and shade with the field's own gradient (u_height). Back faces (the
// culling is off for this technique): the ray left a closed mesh there, so the mirrored map is
// searched from where it crossed the shell's bottom (the far wall seen through holes of the near
// one; §4: a relief impostor's quad seen from behind).
//
// Uniforms (meso's option table for `relief_layers`; "automatic" values resolved by meso):
//   int  u_linear_steps (32, or 64 for an impostor), u_binary_steps (6), u_shadow_steps (16)
//   bool u_shadows (true), u_silhouettes (true), u_missed (false: a ray that meets nothing is
//        discarded; true: drawn on the shell's floor), u_filter (false: nearest depths and
//        normals, the paper; true: bilinear where the four texels hold the layer)
//   bool u_curved (true): the texture walk scaled by the surface's curvature (meso_relief.glsl)
//   int  u_layers (4 or 8), u_size, u_float: the bake's (informational)
// and: int u_num_layers (layers searched: the most a texel holds), u_layer_groups (RGBA groups
//   of four), ivec2 u_layer_size, bool u_layer_clamp, u_layer_heightfield, u_impostor (§4: the
//   quad lies at the middle of the shell), u_enclosed (the inside of a closed mesh is unlit),
//   u_has_below (a solid: back faces are searched)
// Textures (texelFetch, row 0 at v = 1):
//   unit 2  u_layer_maps        RGBA32F array: layers [0, G) the depths of layers 4g..4g+3
//           (unused: 1.0; 0 at the mesh, 1 at the bottom), [G, 2G) their normals' x, [2G, 3G)
//           their y (texture space, z = sqrt(1 - x^2 - y^2) toward the mesh)
//   unit 3  u_layer_count       R32F: layers a texel holds
//   unit 4, 5  u_layer_maps_below, u_layer_count_below: the same of the mirrored map

uniform int u_linear_steps;
uniform int u_binary_steps;
uniform int u_shadow_steps;
uniform bool u_missed;
uniform bool u_filter;
uniform bool u_curved;
uniform int u_layers;
uniform int u_size;
uniform int u_float;

uniform sampler2DArray u_layer_maps;
uniform sampler2D u_layer_count;
uniform sampler2DArray u_layer_maps_below;
uniform sampler2D u_layer_count_below;
uniform int u_num_layers;
uniform int u_layer_groups;
uniform ivec2 u_layer_size;
uniform bool u_layer_clamp;
uniform bool u_layer_heightfield;
uniform bool u_impostor;
uniform bool u_enclosed;
uniform bool u_has_below;

const float LAYERS_SHADOW_BIAS = RELIEF_SHADOW_BIAS;

bool g_below = false; // searching the mirrored map (a back face)

// Texel (i, j) of the padded map: i = W repeats column 0 (or W - 1 when clamped).
ivec2 layers_texel(ivec2 ij) {
    if (u_layer_clamp) return min(ij, u_layer_size - 1);
    return ivec2(ij.x >= u_layer_size.x ? 0 : ij.x, ij.y >= u_layer_size.y ? 0 : ij.y);
}

// plane 0: depths, 1: normal x, 2: normal y; layer k at texel ij.
float layers_fetch(int plane, int k, ivec2 ij) {
    ivec3 at = ivec3(layers_texel(ij), plane * u_layer_groups + k / 4);
    vec4 v = g_below ? texelFetch(u_layer_maps_below, at, 0) : texelFetch(u_layer_maps, at, 0);
    return v[k & 3];
}

float layers_count(ivec2 ij) {
    ivec2 at = layers_texel(ij);
    return g_below ? texelFetch(u_layer_count_below, at, 0).r : texelFetch(u_layer_count, at, 0).r;
}

// The four texels around texel-centre position p, the fractions and the nearest of them.
struct layers_cell {
    ivec2 ij, nearest;
    vec2 frac;
};

layers_cell layers_locate(vec2 p) {
    vec2 size = vec2(u_layer_size);
    if (u_layer_clamp)
        p = clamp(p, vec2(0.0), size - 1.0);
    else
        p -= size * floor(p * (1.0 / size));
    layers_cell c;
    c.ij = min(ivec2(p), u_layer_size - 1);
    c.frac = p - vec2(c.ij);
    c.nearest = c.ij + ivec2(c.frac.x >= 0.5 ? 1 : 0, c.frac.y >= 0.5 ? 1 : 0);
    return c;
}

// A plane of layer k at the cell: solids the nearest texel (u_filter 0, the paper: layers are
// not mixed across §3.2's interfaces), or bilinear where the layer exists in all four texels
// (a mix with the unused 1.0 of a texel without it would be a surface that is not there);
// height fields always bilinear, like relief.
float layers_plane(int plane, int k, layers_cell c) {
    if (!u_filter && !u_layer_heightfield) return layers_fetch(plane, k, c.nearest);
    float p00 = layers_fetch(plane, k, c.ij), p10 = layers_fetch(plane, k, c.ij + ivec2(1, 0));
    float p01 = layers_fetch(plane, k, c.ij + ivec2(0, 1));
    float p11 = layers_fetch(plane, k, c.ij + ivec2(1, 1));
    float top = p00 + (p10 - p00) * c.frac.x, bottom = p01 + (p11 - p01) * c.frac.x;
    float mixed = top + (bottom - top) * c.frac.y;
    if (u_layer_heightfield) return mixed;
    bool full = layers_fetch(0, k, c.ij) < 1.0 && layers_fetch(0, k, c.ij + ivec2(1, 0)) < 1.0 &&
                layers_fetch(0, k, c.ij + ivec2(0, 1)) < 1.0 &&
                layers_fetch(0, k, c.ij + ivec2(1, 1)) < 1.0;
    if (full) return mixed;
    bool right = c.frac.x >= 0.5, down = c.frac.y >= 0.5;
    return down ? (right ? p11 : p01) : (right ? p10 : p00);
}

// §3.1: inside where an odd number of the texel's depths are <= d; f: + or - the distance in
// depth to the nearest layer (the secant step's function).
bool layers_inside(vec2 p, float d, out float f) {
    layers_cell c = layers_locate(p);
    bool odd = false;
    float nearest = 2.0;
    float dt = u_layer_heightfield ? d : min(d, 0.99999); // unused layers (1.0) at the floor
    bool quads = !u_filter && !u_layer_heightfield; // nearest: a group of four in one fetch
    vec4 group = vec4(1.0);
    ivec2 at = layers_texel(c.nearest);
    for (int k = 0; k < u_num_layers; k++) {
        if (quads && (k & 3) == 0)
            group = g_below ? texelFetch(u_layer_maps_below, ivec3(at, k / 4), 0)
                            : texelFetch(u_layer_maps, ivec3(at, k / 4), 0);
        float D = quads ? group[k & 3] : layers_plane(0, k, c);
        if (dt >= D) odd = !odd;
        float gap = abs(d - D);
        bool present = u_layer_heightfield || D < 1.0;
        if (present && gap < nearest) nearest = gap;
    }
    nearest = min(nearest, 1.0);
    f = odd ? nearest : -nearest;
    return odd;
}

// Algorithm 1 (move forward while outside), Algorithm 2 (halve the bracket), a secant step.
bool relief_search(relief_ray r, out float t) {
    bool floor_counts = (u_layer_heightfield || u_missed) && r.floor_hit;
    float f;
    bool found = layers_inside(r.start, 0.0, f) || r.flat_hit;
    float t_lo = 0.0, t_hi = 0.0, f_lo = -1.0, f_hi = f;
    float t_prev = 0.0, f_prev = f;
    float inv_n = 1.0 / float(u_linear_steps);
    for (int k = 1; k <= u_linear_steps && !found; ++k) {
        float tk = r.t_end * (float(k) * inv_n);
        float d = tk * (r.a - r.b * tk);
        float tt = tk * relief_lateral_scale(r, d);
        bool inside = layers_inside(r.start + r.step * tt, d, f);
        if (k == u_linear_steps && floor_counts) inside = true; // a height field's floor is solid
        if (inside) {
            t_lo = t_prev;
            f_lo = f_prev;
            t_hi = tk;
            f_hi = max(f, 0.0);
            found = true;
        }
        t_prev = tk;
        f_prev = f;
    }
    for (int k = 0; k < u_binary_steps; ++k) {
        float tk = (t_lo + t_hi) * 0.5;
        float d = tk * (r.a - r.b * tk);
        float tt = tk * relief_lateral_scale(r, d);
        if (layers_inside(r.start + r.step * tt, d, f)) {
            t_hi = tk;
            f_hi = f;
        } else {
            t_lo = tk;
            f_lo = f;
        }
    }
    float span = f_hi - f_lo;
    float w = clamp(span > 1e-12 ? -f_lo / max(span, 1e-12) : 1.0, 0.0, 1.0);
    t = t_hi <= t_lo ? t_hi : t_lo + (t_hi - t_lo) * w;
    return found;
}

// Self-shadows (§3.1): blocked where a sample of the light ray lies inside by more than the
// bias; the inside of a closed mesh is reached by light only through walls this map does not
// hold: taken as blocked.
bool relief_shadow(relief_light_ray s) {
    if (u_enclosed && g_below) return true;
    float inv = 1.0 / float(u_shadow_steps);
    for (int k = 1; k < u_shadow_steps; ++k) {
        float frac = float(k) * inv, f;
        layers_inside(s.start + s.step * frac, (s.d + s.bulge * frac) * (1.0 - frac), f);
        if (f > LAYERS_SHADOW_BIAS) return true;
    }
    return false;
}

// Solids: the layer normals at the hit. §3.2: of the nearest texels of the binary search's
// last outside and inside points (one bracket either side of the hit) the one with more layers
// is read; its entry layer nearest in depth gives (x, y), z = sqrt(1 - x^2 - y^2), taken to
// world space through the gradients of u, v and -w. Height fields: the field's own gradient.
vec3 relief_hit_normal(meso_frame f, relief_ray r, float t, vec2 hit, float hd) {
    if (u_layer_heightfield) return relief_gradient_normal(f, hit);
    float delta = r.t_end / (float(u_linear_steps) * float(1 << u_binary_steps));
    layers_cell a = layers_locate(hit - r.step * delta), b = layers_locate(hit + r.step * delta);
    ivec2 texel = layers_count(b.nearest) > layers_count(a.nearest) ? b.nearest : a.nearest;
    float x = 0.0, y = 0.0, best = 3.0;
    for (int k = 0; k < u_num_layers; k += 2) { // entries: the even layers
        float D = layers_fetch(0, k, texel);
        float gap = abs(hd - D);
        if (gap < best && D < 1.0) {
            x = layers_fetch(1, k, texel);
            y = layers_fetch(2, k, texel);
            best = gap;
        }
    }
    float z = sqrt(max(0.0, 1.0 - (x * x + y * y)));
    float inv_depth = u_depth > 0.0 ? 1.0 / u_depth : 0.0;
    vec3 n = x * f.bn + y * f.nt + z * inv_depth * f.tb;
    float len2 = dot(n, n);
    bool ok = len2 > 1e-30 && len2 < 1e30 && best < 2.0;
    if (u_missed) ok = ok && (best < 0.02 || hd < 0.999); // drawn on the floor: the mesh's
    if (!ok) return f.normal;
    n *= 1.0 / sqrt(len2);
    return dot(n, f.normal) < 0.0 ? -n : n;
}

// Move a point along its view ray by t (in units of position - eye): position and uv.
void move_along_ray(inout meso_frame f, inout vec2 uv, float t) {
    float cu = dot(f.view, f.bn), cv = dot(f.view, f.nt);
    if (f.ok) uv += t * vec2(cu, cv);
    f = meso_frame_make(f.position + f.view * t, f.normal, f.tangent, f.bitangent);
}

void main() {
    meso_frame f = meso_frame_get();
    vec2 uv = v_uv;
    if (gl_FrontFacing) {
        if (u_impostor) { // §4: the search starts where the ray crosses the top, depth / 2 up
            float vn = dot(f.view, f.normal);
            if (vn < 0.0) move_along_ray(f, uv, 0.5 * u_depth / vn);
        }
        relief_shade(f, uv, v_quadric, u_silhouettes, u_shadows, u_curved);
        return;
    }
    if (!u_has_below) discard; // a height field's floor is solid: nothing shows through it
    // A back face: the view ray left the mesh here after crossing the shell from its bottom.
    // Going back along the ray by tau, the depth below the curved surface is tau (a - b tau);
    // a ray that never reached the bottom skimmed the shell (the front face covered it).
    float a = dot(f.view, f.normal) / u_depth, b = 0.0;
    if (u_silhouettes) {
        vec2 xy = relief_along_frame(f, f.view);
        b = (v_quadric.x * xy.x * xy.x + v_quadric.y * xy.y * xy.y) / u_depth;
    }
    if (u_impostor) a *= 2.0; // §4: the bottom lies half the depth below the quad
    float disc = a * a - 4.0 * b;
    float tau = disc >= 0.0 && a > 0.0 ? 2.0 / (a + sqrt(disc)) : 2.0;
    if (!(tau < 1.0)) discard;
    move_along_ray(f, uv, -tau);
    f = meso_frame_make(f.position, -f.normal, f.tangent, f.bitangent);
    g_below = true;
    relief_shade(f, uv, v_quadric, false, u_shadows, false);
}
