// meso:requires meso_common.glsl meso_relief.glsl
// relief_exact.frag: relief mapping without the linear search's misses and stair-steps: the
// view ray (and each shadow ray) is traced through the maximum mip-map of the height field
// (Tevs, Ihrke & Seidel 2008, "Maximum mipmaps for fast, accurate, and scalable dynamic height
// field rendering", §3-4): a cell whose highest point lies above the ray over the ray's whole
// span in the cell is skipped to its exit, otherwise the traversal descends; at level 0 the
// ray meets the bilinear patch between four texel centres, solved exactly (the ray's depth
// and the bilinear height are both quadratics in the ray parameter). Silhouettes, depth
// correction, shading and the shadow rays' set-up are relief's (meso_relief.glsl).
// Repeating fields need power-of-two sides (each level a regular periodic grid, as meso's
// 8-wide CPU traversal, whose float arithmetic this is); clamp-to-edge fields are not
// periodic and use relief's search with 64 + 8 steps (64 shadow steps), as the CPU.
//
// Uniforms (meso's option table for `relief_exact`):
//   bool u_shadows (true), u_silhouettes (true)   (meso_relief.glsl)
// Textures: u_height (unit 1), the colour map (unit 0) and
//   unit 2  u_max_mip   R32F with u_max_mip_levels mip levels: level l holds, per cell of
//           2^l x 2^l bilinear patches (cell (i, j) spans texel centres i..i+2^l), the
//           highest height in it (meso's minmax pyramid, row 0 at v = 1)

uniform sampler2D u_max_mip;
uniform int u_max_mip_levels;

const int EXACT_MAX_ITERATIONS = 20000; // guards pathological input only
const int EXACT_START_LEVEL_CAP = 4;
const float EXACT_BIG = 3.4e38;

// A ray in texel-centre coordinates, depth d(t) = c0 + c1 t + c2 t^2 over [t0, t1]; it hits
// where d >= 1 - h + bias.
struct exact_ray {
    vec2 origin, dir;
    float c0, c1, c2, t0, t1, bias;
};

float exact_depth(exact_ray r, float t) { return r.c0 + t * (r.c1 + t * r.c2); }

// Tevs et al. 2008 §4: the hierarchical traversal; t of the first hit, false when none.
bool exact_trace(exact_ray r, out float t_hit) {
    // start where cells are as long as the ray's footprint
    float extent = (abs(r.dir.x) + abs(r.dir.y)) * (r.t1 - r.t0);
    int level = 0;
    int start_cap = min(u_max_mip_levels, EXACT_START_LEVEL_CAP + 1);
    for (int l = 1; l < start_cap; ++l) level += extent > float(1 << (l - 1)) ? 1 : 0;
    float t = r.t0;
    vec2 inv = vec2(r.dir.x != 0.0 ? 1.0 / r.dir.x : 0.0, r.dir.y != 0.0 ? 1.0 / r.dir.y : 0.0);
    // a point on a cell border belongs to the cell the ray enters
    vec2 nudge = vec2(r.dir.x > 0.0 ? 1e-5 : (r.dir.x < 0.0 ? -1e-5 : 0.0),
                      r.dir.y > 0.0 ? 1e-5 : (r.dir.y < 0.0 ? -1e-5 : 0.0));
    bool curved = r.c2 < 0.0;
    for (int i = 0; i < EXACT_MAX_ITERATIONS; ++i) {
        vec2 p = r.origin + r.dir * t;
        ivec2 cell = ivec2(floor(p + nudge * (1.0 + abs(p)))) >> level; // sign-extending
        vec2 lo = vec2(cell << level);
        float size = float(1 << level);
        float tx = r.dir.x == 0.0 ? EXACT_BIG
                                  : (lo.x + (r.dir.x > 0.0 ? size : 0.0) - r.origin.x) * inv.x;
        float ty = r.dir.y == 0.0 ? EXACT_BIG
                                  : (lo.y + (r.dir.y > 0.0 ? size : 0.0) - r.origin.y) * inv.y;
        float t_exit = min(min(tx, ty), r.t1);
        t_exit = max(t_exit, t + (1e-6 * t + 1e-12)); // a border rounded behind t
        ivec2 cells = max(u_height_size >> level, ivec2(1));
        ivec2 wrapped = cell & (cells - 1);
        float top_depth = 1.0 - texelFetch(u_max_mip, wrapped, level).r;
        // the deepest point of the ray in the cell: its ends or the parabola's vertex
        float dmax = max(exact_depth(r, t), exact_depth(r, t_exit));
        if (curved) {
            float tv = -r.c1 / (2.0 * r.c2);
            if (tv > t && tv < t_exit) dmax = max(dmax, exact_depth(r, tv));
        }
        bool overlap = dmax >= top_depth + r.bias;
        if (overlap && level > 0) {
            --level;
            continue;
        }
        if (overlap) {
            // level 0: the bilinear patch of texels (x..x+1, y..y+1) along the ray;
            // f(tau) = d(t + tau) - 1 + h(sx + xd tau, sy + yd tau) - bias = A tau^2 + B tau + C
            ivec2 next = (wrapped + 1) & (u_height_size - 1);
            float h00 = texelFetch(u_height, wrapped, 0).r;
            float h10 = texelFetch(u_height, ivec2(next.x, wrapped.y), 0).r;
            float h01 = texelFetch(u_height, ivec2(wrapped.x, next.y), 0).r;
            float h11 = texelFetch(u_height, next, 0).r;
            float hx = h10 - h00, hy = h01 - h00, hxy = h00 - h10 - h01 + h11;
            vec2 s = p - lo;
            float C = exact_depth(r, t) - 1.0 + h00 + hx * s.x + hy * s.y + hxy * s.x * s.y - r.bias;
            float B = r.c1 + 2.0 * r.c2 * t + hx * r.dir.x + hy * r.dir.y +
                      hxy * (s.x * r.dir.y + s.y * r.dir.x);
            float A = r.c2 + hxy * r.dir.x * r.dir.y;
            // the smallest root in [0, t_exit - t]; C >= 0: at once
            float best;
            if (C >= 0.0) {
                best = 0.0;
            } else if (abs(A) < 1e-7 * (abs(B) + abs(C) + 1e-30)) {
                best = B > 0.0 ? -C / B : EXACT_BIG;
            } else {
                float disc = B * B - 4.0 * A * C;
                float q = -0.5 * (B + (B < 0.0 ? -1.0 : 1.0) * sqrt(max(disc, 0.0)));
                float r1 = q / A, r2 = q != 0.0 ? C / q : EXACT_BIG;
                best = disc >= 0.0 ? min(r1 >= 0.0 ? r1 : EXACT_BIG, r2 >= 0.0 ? r2 : EXACT_BIG)
                                   : EXACT_BIG;
            }
            if (best <= t_exit - t) {
                t_hit = t + best;
                return true;
            }
        }
        // skip the cell; climb when its exit is also the parent's border (§4)
        bool exit_x = tx <= ty;
        int c = exit_x ? cell.x : cell.y;
        bool odd = (c & 1) != 0;
        bool border = (exit_x ? r.dir.x : r.dir.y) > 0.0 ? odd : !odd;
        if (border && level < u_max_mip_levels - 1) ++level;
        if (t_exit >= r.t1) return false;
        t = t_exit;
    }
    t_hit = t; // the cap: where the traversal got to
    return true;
}

// The origin wrapped into the first tile keeps the floats small.
vec2 exact_wrap(vec2 p) {
    vec2 size = vec2(u_height_size);
    return p - size * floor(p * (1.0 / size));
}

bool relief_search(relief_ray r, out float t) {
    if (u_height_clamp) return relief_linear_search(r, 64, 8, t);
    t = 0.0;
    if (r.flat_hit || meso_height_at(r.start) >= 1.0) return true; // hit where it enters
    exact_ray e = exact_ray(exact_wrap(r.start), r.step, 0.0, r.a, -r.b, 0.0, r.t_end, 0.0);
    // where a probe at 1/4, 1/16 or 1/64 of the ray is already below the surface, the first
    // hit lies before it: a shorter ray starts at a finer level (the same first hit)
    for (int k = 0; k < 3; ++k) {
        float tp = r.t_end * (k == 0 ? 0.25 : (k == 1 ? 0.0625 : 0.015625));
        if (tp * (r.a - r.b * tp) - 1.0 + meso_height_at(r.start + r.step * tp) >= 0.0) e.t1 = tp;
    }
    if (exact_trace(e, t)) return true;
    t = r.t_end; // d = 1 at t_end: a ray that reaches the floor hits it whatever rounding says
    return r.floor_hit;
}

bool relief_shadow(relief_light_ray s) {
    if (u_height_clamp) return relief_linear_shadow(s, 64);
    // a probe below the surface proves the light blocked; the others need the traversal
    for (int k = 1; k <= 3; ++k) {
        float sp = 0.25 * float(k);
        if ((s.d + s.bulge * sp) * (1.0 - sp) - 1.0 + meso_height_at(s.start + s.step * sp) >
            RELIEF_SHADOW_BIAS)
            return true;
    }
    // from the hit (depth d) up to the mesh (depth 0): d (1 - s) + bulge s (1 - s)
    exact_ray e = exact_ray(exact_wrap(s.start), s.step, s.d, s.bulge - s.d, -s.bulge, 0.0, 1.0,
                            RELIEF_SHADOW_BIAS);
    float t;
    return exact_trace(e, t);
}

vec3 relief_hit_normal(meso_frame f, relief_ray r, float t, vec2 hit, float hd) {
    return relief_gradient_normal(f, hit);
}

void main() { relief_main(); }
