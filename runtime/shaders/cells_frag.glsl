// cells_frag.glsl - ray tracing a cells object (FORMAT.md sec. 7.2 kind 3;
// cell-based-object-representation.md sec. 3.2): first hit, specular
// self-reflection, refraction. The rules (the solid, the traversal, normals,
// shading, environment, the secondary-ray fallbacks) are
// runtime/reference/cell_reference.h's, which this file follows line by
// line; the reference is what it is measured against.
//
// Data (runtime/rt_cells.c): u_tile the tile map (split-cell id per voxel),
// u_memb the MEMB words as stored (classes, rank, records), u_nrmm the
// octahedral normals, u_colr the colours (sRGB texture: fetched linear),
// u_grid the mesh's colour grid when the object has one (u_grid_size > 0:
// FORMAT.md sec. 7.2 kind 3 TX3D; sRGB, fetched linear, trilinear by hand
// in float as the reference does; it replaces u_colr as the albedo).
//
// Searches: exact voxel traversal (Amanatides-Woo, lowest axis first on
// ties) over the grid's voxels with whole-tile skipping (OUTSIDE tiles when
// looking for solid, INSIDE tiles of a full map when looking for empty)
// and, inside other tiles, whole-cube skipping (u_id_bits > 0: the largest
// cube of one split cell around the voxel, runtime/rt_cells_skip.c),
// or with u_step > 0 the thesis's linear search plus bisection
// (Algorithm 3.1), which can step over thin cells at grazing angles.
// The environment is the host's cube map when it passes one, else the
// built-in sky.

in vec3 v_pos;
in vec3 v_nrm;
// Outputs per pass (o_color, o_albedo, o_normal; emit): pass_out.glsl.

uniform usampler3D u_tile;
uniform usamplerBuffer u_memb;
uniform sampler3D u_nrmm;
uniform sampler3D u_colr;
uniform sampler3D u_grid;
uniform ivec3 u_grid_size;  // (0, 0, 0): no colour grid
uniform samplerCube u_env;  // the host's environment (u_has_env == 1)
uniform int u_has_env;
// u_env_rot, u_light_obj: instance.glsl
uniform vec3 u_origin;      // grid origin
uniform float u_h;          // voxel size
uniform ivec3 u_tiles;      // T0, T1, T2
uniform int u_res;          // R
uniform int u_class_words;  // ceil(T / 16)
uniform int u_words;        // W, words per MEMB record
uniform int u_map_full;     // 1: no empty voxel in the tile map
uniform int u_id_bits;      // > 0: u_tile holds the split id in these bits, the skip radius above
uniform int u_from_near;    // 1: back-face fragments start at the near plane (camera inside the grid)
uniform int u_mode;         // 0 first hit, 1 reflection, 2 refraction
uniform int u_bounces;
uniform float u_refl;
uniform float u_ior;
uniform float u_tau;
uniform float u_step;       // linear search step in voxels; 0: exact traversal
uniform int u_fixed_step;
uniform int u_bisect;       // bisection steps of the linear search
uniform int u_max_steps;    // per search
uniform int u_footprint_rays; // N: up to N x N rays across a far pixel (meso_rt_cells_draw.footprint_rays)

// >>membership ---------------------------------------------------------------

ivec3 g_tile = ivec3(-1);
int g_cls = 0;  // class of g_tile: 0 OUTSIDE, 1 INSIDE, 2 MIXED
int g_rec = 0;  // its record (MIXED)

uint popcount32(uint x)
{
    x = x - ((x >> 1) & 0x55555555u);
    x = (x & 0x33333333u) + ((x >> 2) & 0x33333333u);
    x = (x + (x >> 4)) & 0x0F0F0F0Fu;
    return (x * 0x01010101u) >> 24;
}

void enter_tile(ivec3 t)
{
    if (t == g_tile)
        return;
    g_tile = t;
    int ti = t.x + u_tiles.x * (t.y + u_tiles.y * t.z);
    uint w = texelFetch(u_memb, ti >> 4).r;
    int f = ti & 15;
    g_cls = int((w >> uint(2 * f)) & 3u);
    if (g_cls == 2) {
        uint below = f == 0 ? 0u : (w & ((1u << uint(2 * f)) - 1u));
        uint mixed = (below >> 1) & ~below & 0x55555555u; // fields equal to 2
        g_rec = int(texelFetch(u_memb, u_class_words + (ti >> 4)).r + popcount32(mixed));
    }
}

bool outside_grid(ivec3 v)
{
    return any(lessThan(v, ivec3(0))) || any(greaterThanEqual(v, u_tiles * u_res));
}

uint g_radius = 0u; // the skip radius of the voxel solid_in_tile last looked at

// SOLID (cell_reference.h) for a voxel inside the grid, in tile g_tile.
bool solid_in_tile(ivec3 v)
{
    uint s = texelFetch(u_tile, v - g_tile * u_res, 0).r;
    g_radius = u_id_bits > 0 ? s >> uint(u_id_bits) : 0u;
    if (u_id_bits > 0)
        s &= (1u << uint(u_id_bits)) - 1u;
    if (s == 0u || g_cls == 0)
        return false;
    if (g_cls == 1)
        return true;
    int i = int(s) - 1;
    uint w = texelFetch(u_memb, 2 * u_class_words + g_rec * u_words + (i >> 4)).r;
    return ((w >> uint(2 * (i & 15))) & 3u) == 1u;
}

// The same for any voxel inside the grid; sets g_tile.
bool solid(ivec3 v)
{
    enter_tile(v / u_res);
    return solid_in_tile(v);
}

bool solid_or_out(ivec3 v)
{
    return !outside_grid(v) && solid(v);
}

// >>searches -----------------------------------------------------------------

struct Hit {
    float s;     // distance from the search's origin
    float s_lo;  // the last distance before the end: = s for the exact search, the bisection's low end
    ivec3 vox;   // the voxel the search ended in
    ivec3 last;  // the voxel before it
    int axis;    // axis stepped into vox; -1 unknown (linear search: see face_axis)
};

float axis_t(vec3 g0, vec3 inv, ivec3 stp, ivec3 v, int a)
{
    float b = float(stp[a] > 0 ? v[a] + 1 : v[a]);
    return inv[a] == 0.0 ? 1e30 : (b - g0[a]) * inv[a];
}

int argmin3(vec3 t)
{
    return t.x <= t.y ? (t.x <= t.z ? 0 : 2) : (t.y <= t.z ? 1 : 2);
}

// Exact: from voxel `start` (containing o or with o on its boundary).
bool search_exact(vec3 o, vec3 u, ivec3 start, float s_max, bool want_solid, out Hit h)
{
    vec3 g0 = (o - u_origin) / u_h;
    ivec3 stp = ivec3(u.x >= 0.0 ? 1 : -1, u.y >= 0.0 ? 1 : -1, u.z >= 0.0 ? 1 : -1);
    vec3 inv = vec3(u.x == 0.0 ? 0.0 : u_h / u.x, u.y == 0.0 ? 0.0 : u_h / u.y, u.z == 0.0 ? 0.0 : u_h / u.z);
    vec3 dt = vec3(inv.x == 0.0 ? 1e30 : abs(inv.x), inv.y == 0.0 ? 1e30 : abs(inv.y),
                   inv.z == 0.0 ? 1e30 : abs(inv.z));
    ivec3 v = start;
    vec3 tn = vec3(axis_t(g0, inv, stp, v, 0), axis_t(g0, inv, stp, v, 1), axis_t(g0, inv, stp, v, 2));
    float s = 0.0;
    h.last = start;
    h.axis = -1;
    bool first = true;
    for (int i = 0; i < u_max_steps; ++i) {
        ++g_steps;
        if (outside_grid(v)) {
            if (want_solid || first)
                return false;
            h.s = h.s_lo = s;
            h.vox = v;
            return true;
        }
        enter_tile(v / u_res);
        bool skip = want_solid ? g_cls == 0 : (g_cls == 1 && u_map_full == 1);
        ivec3 lo = g_tile * u_res, hi = lo + u_res;
        if (!skip) {
            // enter_tile above set g_tile
            bool state = solid_in_tile(v);
            if (!first && state == want_solid) {
                h.s = h.s_lo = s;
                h.vox = v;
                return true;
            }
            // The cube of v's split cell, all in v's state; else one voxel.
            // (A search may start in a voxel of the state it wants: that one
            // is stepped out of, as the walk does.)
            skip = g_radius > 0u && state != want_solid;
            lo = v - int(g_radius);
            hi = v + int(g_radius) + 1;
        }
        first = false;
        if (skip) { // leave the box [lo, hi) where the voxel walk would
            vec3 te;
            for (int a = 0; a < 3; ++a)
                te[a] = inv[a] == 0.0 ? 1e30 : (float(stp[a] > 0 ? hi[a] : lo[a]) - g0[a]) * inv[a];
            int a = argmin3(te);
            if (te[a] > s_max)
                return false;
            s = te[a];
            ivec3 nv = clamp(ivec3(floor(g0 + s / u_h * u)), lo, hi - 1);
            nv[a] = stp[a] > 0 ? hi[a] : lo[a] - 1;
            h.last = nv;
            h.last[a] -= stp[a];
            h.axis = a;
            v = nv;
            tn = vec3(axis_t(g0, inv, stp, v, 0), axis_t(g0, inv, stp, v, 1), axis_t(g0, inv, stp, v, 2));
            continue;
        }
        int a = argmin3(tn);
        s = tn[a];
        if (s > s_max)
            return false;
        h.last = v;
        h.axis = a;
        v[a] += stp[a];
        tn[a] += dt[a];
    }
    return false;
}

// The axis of the voxel face between two voxels of a bisection (the first
// that differs), else the ray's dominant axis.
int face_axis(ivec3 a, ivec3 b, vec3 u)
{
    if (a.x != b.x)
        return 0;
    if (a.y != b.y)
        return 1;
    if (a.z != b.z)
        return 2;
    vec3 au = abs(u);
    return au.x >= au.y ? (au.x >= au.z ? 0 : 2) : (au.y >= au.z ? 1 : 2);
}

// Algorithm 3.1 (and 3.2 / 3.3's loops): samples every `step` along the ray
// (whole tiles skipped as above), then bisection between the last two.
bool search_linear(vec3 o, vec3 u, float dstep, float s_max, bool want_solid, out Hit h)
{
    vec3 g0 = (o - u_origin) / u_h;
    float s = 0.0;
    for (int i = 0; i < u_max_steps; ++i) {
        ++g_steps;
        float sn = s + dstep;
        if (sn > s_max)
            return false;
        ivec3 v = ivec3(floor(g0 + sn / u_h * u));
        bool state;
        if (outside_grid(v)) {
            if (want_solid)
                return false;
            state = false;
        } else {
            enter_tile(v / u_res);
            bool skip = want_solid ? g_cls == 0 : (g_cls == 1 && u_map_full == 1);
            if (skip) { // sec. 3.2.3: "hit position = exit point"
                ivec3 lo = g_tile * u_res, hi = lo + u_res;
                float te = 1e30;
                for (int a = 0; a < 3; ++a)
                    if (u[a] != 0.0)
                        te = min(te, (float(u[a] > 0.0 ? hi[a] : lo[a]) - g0[a]) * u_h / u[a]);
                s = max(te, sn);
                continue;
            }
            state = solid_in_tile(v);
        }
        if (state == want_solid) {
            float lo = s, hi = sn;
            for (int k = 0; k < u_bisect; ++k) {
                ++g_steps;
                float mid = 0.5 * (lo + hi);
                if (solid_or_out(ivec3(floor(g0 + mid / u_h * u))) == want_solid)
                    hi = mid;
                else
                    lo = mid;
            }
            h.s = hi;
            h.s_lo = lo;
            h.vox = ivec3(floor(g0 + hi / u_h * u));
            h.last = ivec3(floor(g0 + lo / u_h * u));
            h.axis = face_axis(h.vox, h.last, u);
            return true;
        }
        s = sn;
    }
    return false;
}

bool search(vec3 o, vec3 u, ivec3 start, float dstep, float s_max, bool want_solid, out Hit h)
{
    if (u_step > 0.0)
        return search_linear(o, u, dstep, s_max, want_solid, h);
    return search_exact(o, u, start, s_max, want_solid, h);
}

// >>shading ------------------------------------------------------------------

vec3 nrmm(ivec3 v)
{
    vec2 f = texelFetch(u_nrmm, v - (v / u_res) * u_res, 0).rg * 2.0 - 1.0;
    vec3 n = vec3(f, 1.0 - abs(f.x) - abs(f.y));
    if (n.z < 0.0)
        n.xy = (1.0 - abs(f.yx)) * vec2(f.x >= 0.0 ? 1.0 : -1.0, f.y >= 0.0 ? 1.0 : -1.0);
    return normalize(n);
}

// The face normal of axis a, pointing against direction u.
vec3 face_against(int a, vec3 u)
{
    vec3 f = vec3(0.0);
    f[a] = u[a] >= 0.0 ? -1.0 : 1.0;
    return f;
}

// The shading normal of solid voxel v at face f (cell_reference.h).
vec3 shading_normal(ivec3 v, vec3 f)
{
    vec3 m = nrmm(v);
    return dot(m, f) > 0.0 ? m : f;
}

// The albedo of a hit at p in voxel v (linear: the textures are sRGB): the
// colour map's texel of v, or the colour grid trilinear at p (sample
// coordinates clamped to [0, G - 1]).
vec3 colr(ivec3 v, vec3 p)
{
    if (u_grid_size.x <= 0)
        return texelFetch(u_colr, v - (v / u_res) * u_res, 0).rgb;
    vec3 g = vec3(u_grid_size);
    vec3 x = clamp((p - u_origin) / (vec3(u_tiles * u_res) * u_h) * g - 0.5, vec3(0.0), g - 1.0);
    ivec3 i0 = min(ivec3(x), u_grid_size - 1);
    ivec3 i1 = min(i0 + 1, u_grid_size - 1);
    vec3 f = x - vec3(i0);
    vec3 c00 = mix(texelFetch(u_grid, i0, 0).rgb, texelFetch(u_grid, ivec3(i1.x, i0.y, i0.z), 0).rgb, f.x);
    vec3 c10 = mix(texelFetch(u_grid, ivec3(i0.x, i1.y, i0.z), 0).rgb, texelFetch(u_grid, ivec3(i1.x, i1.y, i0.z), 0).rgb, f.x);
    vec3 c01 = mix(texelFetch(u_grid, ivec3(i0.x, i0.y, i1.z), 0).rgb, texelFetch(u_grid, ivec3(i1.x, i0.y, i1.z), 0).rgb, f.x);
    vec3 c11 = mix(texelFetch(u_grid, ivec3(i0.x, i1.y, i1.z), 0).rgb, texelFetch(u_grid, i1, 0).rgb, f.x);
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}

vec3 shade(ivec3 v, vec3 n, vec3 p)
{
    vec3 c = colr(v, p);
    return c * (0.15 + 0.85 * max(0.0, dot(n, u_light_obj)));
}

// Forward shading at a hit p of voxel v, normal n, reached by direction u:
// the built-in Lambert, or the host's hook (pass_out.glsl).
vec3 lit(ivec3 v, vec3 n, vec3 p, vec3 u)
{
#ifdef MESO_HOOK
    return meso_shade(colr(v, p), world_normal(n), world_point(p), world_view(u));
#else
    return shade(v, n, p);
#endif
}

// >>footprint: a far pixel's first hit, averaged over the pixel
// (MESO_FILTER_MIPMAP and meso_rt_cells_draw.footprint_rays = N >= 2). A
// cells object has no texture to prefilter: each voxel's colour and normal
// belong to one cell, and a 3D mip level averages the cells hidden behind
// the surface too (measured on test_rt_mips's torus: 2.6x the error of one
// ray, the picture a uniform grey). So where a pixel is more than two
// voxels across, the forward pass casts more rays across it and shades
// their mean.
//
// footprint_level: log2 of the pixel's footprint in voxels (0 up to one
// voxel): the rays half a pixel either side meeting the plane through p of
// normal g (raycast_common.glsl plane_offset), OpenGL's isotropic measure.
// The caller passes the plane facing the ray: a voxel face seen at a
// grazing angle stretches the footprint along it, and counting that
// (tried) cast extra rays over most pixels of bench_lod_scene's cells at
// 1 px, where one ray is as good.
float footprint_level(vec3 p, vec3 g)
{
    if (u_mips == 0)
        return 0.0;
    float far = 1e6 * u_h;
    vec3 dx = plane_offset(g, p, gl_FragCoord.xy + vec2(0.5, 0.0), far) -
              plane_offset(g, p, gl_FragCoord.xy - vec2(0.5, 0.0), -far);
    vec3 dy = plane_offset(g, p, gl_FragCoord.xy + vec2(0.0, 0.5), far) -
              plane_offset(g, p, gl_FragCoord.xy - vec2(0.0, 0.5), -far);
    float rho = max(length(dx), length(dy)) / u_h;
    return rho > 1.0 ? log2(rho) : 0.0;
}

// footprint_mean: the mean of the first hit's shading over the pixel, n x
// n rays on a regular grid across it (n = 2 up to four voxels, else N;
// on test_rt_mips's torus, medians of 3 runs: N = 2 took
// the mean error from 13.9 to 6.0 at 2.1x the frame time, 3 to 3.9 at 3.5x,
// 4 to 2.3 at 5.4x). Each ray enters where it meets the plane through pe
// of normal ge (the base mesh's tangent plane where the pixel's own ray
// enters: a pixel wide, the mesh is that plane to well within its
// footprint), searches at most s_max past it and is shaded as the pixel's
// own ray is; rays that miss are left out (the pixel's coverage and depth
// are its own ray's). Blended in between two and four voxels, so where a
// pixel covers at most two nothing changes and the exact reference still
// holds (runtime/reference/cell_reference.h casts one ray per pixel).
vec3 footprint_mean(vec3 centre, float lod, vec3 pe, vec3 ge, float dstep, float s_max)
{
    if (lod <= 1.0 || u_footprint_rays < 2)
        return centre;
    int n = lod < 2.0 ? 2 : u_footprint_rays;
    vec3 sum = vec3(0.0);
    float hits = 0.0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            vec2 off = (vec2(i, j) + 0.5) / float(n) - 0.5;
            vec3 o = unproject(gl_FragCoord.xy + off, u_depth_ndc.x);
            vec3 u = normalize(unproject(gl_FragCoord.xy + off, u_depth_ndc.y) - o);
            float den = dot(ge, u);
            float se = abs(den) > 1e-6 ? dot(ge, pe - o) / den : dot(pe - o, u);
            vec3 q = o + max(se, 0.0) * u;
            ivec3 v = clamp(ivec3(floor((q - u_origin) / u_h)), ivec3(0), u_tiles * u_res - 1);
            Hit h;
            vec3 f;
            bool ok;
            if (solid(v)) {
                ok = true;
                h.s = 0.0;
                h.vox = v;
                f = -u;
            } else {
                ok = search(q, u, v, dstep, s_max, true, h);
                f = ok ? face_against(h.axis, u) : vec3(0.0);
            }
            if (ok) {
                sum += lit(h.vox, shading_normal(h.vox, f), q + h.s * u, u);
                hits += 1.0;
            }
        }
    return hits > 0.0 ? mix(centre, sum / hits, min(lod - 1.0, 1.0)) : centre;
}

vec3 env(vec3 u)
{
    if (u_has_env == 1)
        return textureLod(u_env, u_env_rot * u, 0.0).rgb;
    float c = max(u.y, 0.0), g = max(-u.y, 0.0);
    vec3 sky = vec3(0.95, 0.92, 0.85) * (1.0 - c) + vec3(0.30, 0.50, 0.90) * c;
    if (u.y >= 0.0)
        return sky;
    vec3 ground = vec3(0.42, 0.36, 0.30) + 0.12 * sin(12.0 * atan(u.z, u.x)) * sin(12.0 * asin(g));
    float m = min(1.0, 8.0 * g);
    return sky * (1.0 - m) + ground * m;
}

// One refraction event (cell_reference.h): ray d meets a face whose normal
// g faces it, shading normal ns facing it too. A refraction must cross the
// face (g . t < 0), a total internal reflection stay (g . r > 0); otherwise
// the event is recomputed with g. Returns true when the ray crossed.
bool cross_face(vec3 d, vec3 ns, vec3 g, float eta, out vec3 t)
{
    t = refract(d, ns, eta);
    if (t != vec3(0.0)) {
        if (dot(g, t) < 0.0)
            return true;
    } else {
        t = reflect(d, ns);
        if (dot(g, t) > 0.0)
            return false;
    }
    t = refract(d, g, eta);
    if (t != vec3(0.0))
        return true;
    t = reflect(d, g);
    return false;
}

// >>main ---------------------------------------------------------------------

void main()
{
    instance_begin();
    vec3 ro, rd;
    fragment_ray(ro, rd);
    // Up to the far plane; an infinite one (w = 0 there) does not limit.
    vec4 fa = u_inv_mvp * vec4((gl_FragCoord.xy - u_viewport.xy) / u_viewport.zw * 2.0 - 1.0, u_depth_ndc.z, 1.0);
    float s_far = abs(fa.w) > 1e-30 * length(fa.xyz) ? length(fa.xyz / fa.w - ro) : 3.4e38;
    vec3 gmin = u_origin, gmax = u_origin + vec3(u_tiles * u_res) * u_h;
    float s0;
    if (gl_FrontFacing) {
        s0 = max(dot(v_pos - ro, rd), 0.0);
    } else {
        if (u_from_near == 0)
            discard;
        vec3 inv = 1.0 / rd;
        vec3 t0 = (gmin - ro) * inv, t1 = (gmax - ro) * inv;
        vec3 tl = min(t0, t1);
        s0 = max(max(max(tl.x, tl.y), tl.z), 0.0);
    }
    vec3 p0 = ro + s0 * rd;
    ivec3 v0 = clamp(ivec3(floor((p0 - u_origin) / u_h)), ivec3(0), u_tiles * u_res - 1);
    float big = 4.0 * length(gmax - gmin);
    float dstep = u_step * u_h;
    float dstep0 = dstep;
    if (u_step > 0.0 && u_fixed_step == 0 && gl_FrontFacing)
        dstep0 = dstep * max(abs(dot(normalize(v_nrm), rd)), 0.125);

    Hit h;
    vec3 f;
    bool hit;
    if (solid(v0)) {
        hit = true;
        h.s = h.s_lo = 0.0;
        h.vox = v0;
        h.last = v0;
        h.axis = -1;
        f = -rd;
    } else {
        hit = search(p0, rd, v0, dstep0, s_far - s0, true, h);
        f = hit ? face_against(h.axis, rd) : vec3(0.0);
    }
    if (!hit) {
        finish(false);
        return;
    }
    vec3 p = p0 + h.s * rd;
    write_depth(p);
#if MESO_PASS == MESO_PASS_GBUFFER // the first hit's material and normal; no bounces
    vec3 n = shading_normal(h.vox, f);
    emit_obj(vec3(0.0), colr(h.vox, p), 1.0, n, p, rd);
#elif MESO_PASS == MESO_PASS_FORWARD
    vec3 n = shading_normal(h.vox, f);
    vec3 col = lit(h.vox, n, p, rd);
    if (u_mode == 0) {
        vec3 ge = gl_FrontFacing ? normalize(v_nrm) : -rd;
        float lod = footprint_level(p, -rd);
        // Each ray searches as far past its entry as this one found its hit,
        // plus two footprints and two voxels.
        col = footprint_mean(col, lod, p0, ge, dstep, h.s + (2.0 * exp2(lod) + 2.0) * u_h);
    }

    if (u_mode == 1 && h.axis >= 0) { // sec. 3.2.3 Algorithm 3.2
        vec3 u = rd;
        float w = u_refl;
        col *= 1.0 - u_refl;
        vec3 r = reflect(u, n);
        if (dot(r, f) <= 0.0)
            r = reflect(u, f);
        ivec3 from = h.last;
        vec3 o = p0 + h.s_lo * rd; // the empty side of the face
        for (int b = 0; b < u_bounces; ++b) {
            Hit hb;
            if (!search(o, r, from, dstep, big, true, hb))
                break;
            p = o + hb.s * r;
            o = o + hb.s_lo * r; // the next ray starts on the empty side
            vec3 fb = face_against(hb.axis, r);
            vec3 nb = shading_normal(hb.vox, fb);
            col += w * (1.0 - u_refl) * lit(hb.vox, nb, p, r);
            w *= u_refl;
            u = r;
            r = reflect(u, nb);
            if (dot(r, fb) <= 0.0)
                r = reflect(u, fb);
            from = hb.last;
        }
        col += w * env(r);
    } else if (u_mode == 1) {
        col = (1.0 - u_refl) * col + u_refl * env(reflect(rd, n));
    } else if (u_mode == 2) { // sec. 3.2.4 Algorithm 3.3
        vec3 u;
        bool inside = cross_face(rd, n, f, 1.0 / u_ior, u);
        ivec3 cur = inside ? h.vox : h.last;
        vec3 o = p;
        for (int b = 0; b < (h.axis >= 0 ? u_bounces : 0); ++b) {
            Hit e;
            if (!search(o, u, cur, dstep, big, !inside, e))
                break;
            o = o + e.s * u;
            vec3 t;
            if (inside) { // leaving through a face of the last SOLID voxel
                vec3 fo = -face_against(e.axis, u);
                inside = !cross_face(u, -shading_normal(e.last, fo), -fo, u_ior, t);
                cur = inside ? e.last : e.vox;
            } else { // entering SOLID voxel e.vox
                vec3 fi = face_against(e.axis, u);
                inside = cross_face(u, shading_normal(e.vox, fi), fi, 1.0 / u_ior, t);
                cur = inside ? e.vox : e.last;
            }
            u = t;
        }
        col = (1.0 - u_tau) * col + u_tau * env(u);
    }
    o_color = vec4(col, 1.0);
#endif
    finish(true);
}
