// meso_solid.glsl: meso's procedural solids' signed distance bounds over texture space
// (u, v, w) (src/mesostructure/mesostructure_solid.c, docs/mesostructure.md), ported line by
// line: the same constants (from meso_solid_get_shape), the same candidates and order of
// operations, so a probe lands on the same side of the surface as the C's. Each kind is
// modelled in cell space (x, y, z) = (count u, count v, depth_cells w) and scaled back by
// u_solid_scale, so the result is a distance bound with Lipschitz constant 1 in (u, v, w); the
// slab 0 <= w <= 1 closes it above and below. A tile mesh's solid (kind 7) interpolates its
// distance grid trilinearly (mesostructure_tile_mesh.c, meso_solid_grid_distance).
//
// Uniforms (meso_solid_shape of meso/mesostructure.h):
//   int   u_solid_kind          1 weave, 2 chain, 3 grid, 4 squama, 5 helix, 6 slab, 7 mesh
//   float u_solid_count         repeats a tile; u_solid_thickness (a cell's fraction)
//   float u_solid_depth_cells, u_solid_scale, u_solid_cap, u_solid_amplitude (weave),
//         u_solid_major, u_solid_half_length (chain; major: helix), u_solid_radius (squama)
//   vec2  u_solid_tilt          squama's (cos, sin)
//   samplerBuffer u_solid_grid  R32F, kind 7: n^3 samples, index (k n + j) n + i at
//                               (i / n, j / n, k / (n - 1)); u_solid_grid_side = n,
//                               bool u_solid_grid_clamped (a model's grid: nodes at i / (n-1))

uniform int u_solid_kind;
uniform float u_solid_count;
uniform float u_solid_thickness;
uniform float u_solid_depth_cells;
uniform float u_solid_scale;
uniform float u_solid_cap;
uniform float u_solid_amplitude;
uniform float u_solid_major;
uniform float u_solid_half_length;
uniform vec2 u_solid_tilt;
uniform float u_solid_radius;
uniform samplerBuffer u_solid_grid;
uniform int u_solid_grid_side;
uniform bool u_solid_grid_clamped;

const float MESO_SOLID_PI = 3.14159265358979323846;

float meso_solid_length2(float x, float y) { return sqrt(x * x + y * y); }

float meso_solid_weave(float x, float y, float z) {
    float r = u_solid_thickness, zc = 0.5 * u_solid_depth_cells, a = u_solid_amplitude;
    float best = u_solid_cap;
    float row = floor(y), column = floor(x);
    float rows[2] = float[2](row, y - row < 0.5 ? row - 1.0 : row + 1.0);
    float columns[2] = float[2](column, x - column < 0.5 ? column - 1.0 : column + 1.0);
    for (int k = 0; k < 2; ++k) {
        float centre = zc - a * cos(MESO_SOLID_PI * (x - 0.5 - rows[k]));
        best = min(best, meso_solid_length2(y - (rows[k] + 0.5), z - centre) - r);
        float centre_v = zc + a * cos(MESO_SOLID_PI * (y - 0.5 - columns[k]));
        best = min(best, meso_solid_length2(x - (columns[k] + 0.5), z - centre_v) - r);
    }
    return best;
}

float meso_solid_link(float along, float across, float normal, float half_length, float major,
                      float r) {
    float q = max(abs(along) - half_length, 0.0);
    return meso_solid_length2(meso_solid_length2(q, across) - major, normal) - r;
}

float meso_solid_chain(float x, float y, float z) {
    float r = u_solid_thickness, zc = 0.5 * u_solid_depth_cells;
    float best = u_solid_cap;
    float row = floor(y), link = floor(x);
    float rows[2] = float[2](row, y - row < 0.5 ? row - 1.0 : row + 1.0);
    for (int k = 0; k < 2; ++k)
        for (int di = -1; di <= 1; ++di) {
            float i = link + float(di);
            float along = x - (i + 0.5), across = y - (rows[k] + 0.5), normal = z - zc;
            bool lies_flat = (int(i) & 1) == 0; // wrap_index(i, 2) == 0, any sign
            float d = lies_flat ? meso_solid_link(along, across, normal, u_solid_half_length,
                                             u_solid_major, r)
                           : meso_solid_link(along, normal, across, u_solid_half_length,
                                             u_solid_major, r);
            best = min(best, d);
        }
    return best;
}

float meso_solid_box(float x, float y, float z, float hx, float hy, float hz) {
    float qx = abs(x) - hx, qy = abs(y) - hy, qz = abs(z) - hz;
    vec3 o = vec3(max(qx, 0.0), max(qy, 0.0), max(qz, 0.0));
    float outside = sqrt(o.x * o.x + o.y * o.y + o.z * o.z);
    return outside + min(max(qx, max(qy, qz)), 0.0);
}

float meso_solid_grid_bars(float x, float y, float z) {
    float t = u_solid_thickness, depth = u_solid_depth_cells;
    float dy = y - floor(y + 0.5), dx = x - floor(x + 0.5);
    float upper = meso_solid_box(0.0, dy, z - 0.275 * depth, 1e30, t, 0.275 * depth);
    float lower = meso_solid_box(dx, 0.0, z - 0.725 * depth, t, 1e30, 0.275 * depth);
    return min(upper, lower);
}

float meso_solid_squama(float x, float y, float z) {
    float half_thickness = u_solid_thickness, radius = u_solid_radius;
    float round_ = 0.5 * half_thickness, zc = 0.5 * u_solid_depth_cells;
    float best = u_solid_cap;
    float row = floor(y);
    for (int dj = -1; dj <= 1; ++dj) {
        float j = row + float(dj);
        float shift = (int(j) & 1) != 0 ? 0.5 : 0.0;
        float column = floor(x - shift);
        for (int di = -1; di <= 1; ++di) {
            float cx = column + float(di) + 0.5 + shift, cy = j + 0.5;
            float px = x - cx, py = y - cy, pz = z - zc;
            float ly = u_solid_tilt.x * py + u_solid_tilt.y * pz;
            float lz = u_solid_tilt.x * pz - u_solid_tilt.y * py;
            float radial = meso_solid_length2(px, ly) - radius + round_;
            float axial = abs(lz) - half_thickness + round_;
            float d = min(max(radial, axial), 0.0) +
                      meso_solid_length2(max(radial, 0.0), max(axial, 0.0)) - round_;
            best = min(best, d);
        }
    }
    return best;
}

float meso_solid_helix(float x, float y, float z) {
    float r = u_solid_thickness, zc = 0.5 * u_solid_depth_cells, major = u_solid_major;
    float best = u_solid_cap;
    float row = floor(y);
    float rows[2] = float[2](row, y - row < 0.5 ? row - 1.0 : row + 1.0);
    float angle = 2.0 * MESO_SOLID_PI * x;
    float c = cos(angle), sn = sin(angle);
    for (int k = 0; k < 2; ++k) {
        float py = y - (rows[k] + 0.5), pz = z - zc;
        best = min(best, meso_solid_length2(py - major * c, pz - major * sn) - r);
        best = min(best, meso_solid_length2(py + major * c, pz + major * sn) - r);
    }
    return best;
}

float meso_solid_grid_at(int i, int j, int k) {
    int n = u_solid_grid_side;
    return texelFetch(u_solid_grid, (k * n + j) * n + i).r;
}

// meso_solid_grid_distance: trilinear in the tile mesh's grid, u, v periodic (or clamped for
// a model), the slab closing it.
float meso_solid_mesh(vec3 uvw) {
    int n = u_solid_grid_side;
    float x, y;
    if (u_solid_grid_clamped) {
        x = min(max(uvw.x, 0.0), 0.99999) * float(n - 1);
        y = min(max(uvw.y, 0.0), 0.99999) * float(n - 1);
    } else {
        x = (uvw.x - floor(uvw.x)) * float(n);
        y = (uvw.y - floor(uvw.y)) * float(n);
    }
    float z = min(max(uvw.z, 0.0), 1.0) * float(n - 1);
    int i = int(x), j = int(y), k = int(z);
    i = i >= n ? n - 1 : i;
    j = j >= n ? n - 1 : j;
    k = k >= n - 1 ? n - 2 : k;
    float tx = x - float(i), ty = y - float(j), tz = z - float(k);
    int i1 = i + 1 == n ? 0 : i + 1, j1 = j + 1 == n ? 0 : j + 1;
    float a = meso_solid_grid_at(i, j, k);
    float c00 = a + (meso_solid_grid_at(i1, j, k) - a) * tx;
    float b = meso_solid_grid_at(i, j1, k);
    float c10 = b + (meso_solid_grid_at(i1, j1, k) - b) * tx;
    float c = meso_solid_grid_at(i, j, k + 1);
    float c01 = c + (meso_solid_grid_at(i1, j, k + 1) - c) * tx;
    float e = meso_solid_grid_at(i, j1, k + 1);
    float c11 = e + (meso_solid_grid_at(i1, j1, k + 1) - e) * tx;
    float c0 = c00 + (c10 - c00) * ty, c1 = c01 + (c11 - c01) * ty;
    float d = (c0 + (c1 - c0) * tz) * 0.57735027;
    return max(d, max(-uvw.z, uvw.z - 1.0));
}

// meso_solid_distance: the signed distance bound at (u, v, w); u, v taken modulo 1.
float meso_solid_distance(vec3 uvw) {
    if (u_solid_kind == 7) return meso_solid_mesh(uvw);
    float x = (uvw.x - floor(uvw.x)) * u_solid_count, y = (uvw.y - floor(uvw.y)) * u_solid_count;
    float z = uvw.z * u_solid_depth_cells;
    float f;
    if (u_solid_kind == 1)
        f = meso_solid_weave(x, y, z);
    else if (u_solid_kind == 2)
        f = meso_solid_chain(x, y, z);
    else if (u_solid_kind == 3)
        f = meso_solid_grid_bars(x, y, z);
    else if (u_solid_kind == 4)
        f = meso_solid_squama(x, y, z);
    else if (u_solid_kind == 5)
        f = meso_solid_helix(x, y, z);
    else if (u_solid_kind == 6)
        f = (1.0 - u_solid_thickness) * u_solid_depth_cells - z;
    else
        f = 1.0;
    float slab = max(-z, z - u_solid_depth_cells);
    return max(f, slab) * u_solid_scale;
}

// meso_solid_gradient: central differences of step 1e-3, pointing outward (not normalised).
vec3 meso_solid_gradient(vec3 uvw) {
    const float h = 1e-3;
    float gx = meso_solid_distance(vec3(uvw.x + h, uvw.y, uvw.z)) -
               meso_solid_distance(vec3(uvw.x - h, uvw.y, uvw.z));
    float gy = meso_solid_distance(vec3(uvw.x, uvw.y + h, uvw.z)) -
               meso_solid_distance(vec3(uvw.x, uvw.y - h, uvw.z));
    float gz = meso_solid_distance(vec3(uvw.x, uvw.y, uvw.z + h)) -
               meso_solid_distance(vec3(uvw.x, uvw.y, uvw.z - h));
    float inv = 1.0 / (2.0 * h);
    return vec3(gx * inv, gy * inv, gz * inv);
}
