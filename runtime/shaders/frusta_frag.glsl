// frusta_frag.glsl - ray casting one relief-mapped conical frustum (or one
// ball) per fragment: papers/relief-mapped-conical-frusta.md sec. 2.5 and 3,
// with the geometry, parametrisation, relief space and shading normals of
// FORMAT.md sec. 7.2 (kind 4). runtime/reference/frustum_reference.h is the
// double-precision reference this shader is measured against
// (tests/gl/test_rt_frusta.c); the conventions below are its.
//
// The cone is |q| = r(y) = r0 + k y (radius linear along the axis, so a
// cylinder needs no apex: the paper's eq. 1/10 rewritten without h'), on the
// nappe r(y) >= 0, cut by plane 0 (through c0) and plane 1 (through c1).
// Along a ray the inside of such a cone is where a quadratic is <= 0
// (one interval, or two half-lines of which the nappe keeps one), and each
// plane keeps a half-line: cone_interval() intersects them and says which
// constraint bounds each end. The surface is the lateral cone plus the caps
// whose FSEG flag is set; a ray hits the nearest surface point in front of
// the near plane, entering or leaving (a ray starting inside the solid - the
// camera inside a frustum - sees where it leaves).
//
// Relief (sec. 3): the shell between the cone (w = 0) and the parallel cone
// r(y) + D (w = 1), solid where w <= h(s, t). The ray's interval inside the
// outer solid is searched from its entry for the first change of solidity
// (or the entry itself when it comes through a cap onto solid), by
// u_relief_steps uniform samples and u_bisect_steps bisection steps (the
// paper's uniform sampling plus bisection). The always-solid inner cone's
// interval is computed analytically and skipped, so each march covers only
// the part of the ray inside the relief layer (before and after the core).
// u and v are computed exactly at every sample, v along the generator
// through the sample of the cone through it (r(y) + delta, delta = |q| -
// r(y)), between that generator's points on the two planes. The paper
// approximates v by linear interpolation between the ray's entry and exit
// (exact only for parallel planes; it reports relief "swimming" at joints
// sharper than 45 degrees); we do not, because the joint planes of a bent
// skeleton are never parallel and the exact v costs two dot products and a
// division per sample - less than the height fetch itself.
//
// Heights are sampled by hand (texelFetch of the 4 texels, bilinear weights
// in full float precision, wrap by mod) rather than by the texture unit:
// units interpolate with 8-bit weights (GPUs and llvmpipe alike), the
// reference does not, and the analytic derivative of the same bilinear
// interpolant gives the gradient for the shading normal.
//
// Colour (FORMAT.md sec. 7.2 kind 4, COLR): with a colour map the albedo of
// a frustum hit (lateral, relief or cap) is the map at the hit's relief
// coordinates (s, t) - the same (u, v) of the cone through the hit the
// relief uses - bilinear in linear colour between texel centres, wrapping,
// by hand like the heights (the SRGB8_ALPHA8 texture decodes each texel);
// balls take the map's mean linear colour (u_ball_color). Without a map:
// u_albedo everywhere. With mip levels (MESO_FILTER_MIPMAP) the shading
// normal's gradient and the colour read the levels of the pixel's footprint
// on the maps (map_levels below), by hand as well: trilinear between two
// levels' bilinear fetches; the march reads level 0.
//
// Shading: the reference's - albedo * (0.25 + 0.75 w) * (0.15 + 0.85
// max(0, n.l)), n the shading normal turned to face the ray, w the relief
// height at the hit on relief frusta (1 elsewhere); lateral normals are the
// paper's eq. 8 on the cone through the hit, N_l = P0 - c0, N_u = P1 - c1
// (c0, c1 the plane centres: "away from the base and top point of the
// medial axis"), tilted on relief hits by D times the surface gradient of
// h; caps and balls use their true normals. Depth: the hit's own.

flat in int v_prim;
// Outputs per pass (o_color, o_albedo, o_normal; emit): pass_out.glsl.

uniform sampler2D u_relief;  // RELF heights (value / max)
uniform ivec2 u_relief_size; // texels; (0, 0) without relief
// u_light_obj: instance.glsl
uniform vec3 u_albedo;
uniform int u_relief_steps;
uniform sampler2D u_color;   // COLR, SRGB8_ALPHA8: fetches are linear
uniform ivec2 u_color_size;  // texels; (0, 0) without a colour map
uniform vec3 u_ball_color;   // the map's mean linear colour
uniform int u_bisect_steps;

const float INV_TAU = 0.15915494309189535;
const float TAU = 6.283185307179586;
const float BIG = 1e30;

struct Frustum {
    vec3 c0;
    float r0;
    vec3 a; // unit axis
    float h;
    vec3 n0; // outward normal of plane 0 (through c0)
    float k; // dr/dy
    vec3 n1; // outward normal of plane 1 (through c1 = c0 + h a)
    float D; // relief depth, 0: none
    vec3 fx; // frame_x
    float u_off;
    vec3 fz; // frame_x x a
    float twist, u_scale, v_off, v_scale;
    float n0a, n1a; // n0.a, n1.a
    bool cap0, cap1;
};

Frustum fetch_frustum(int prim)
{
    int b = MESO_FRUSTA_TEXELS * prim;
    vec4 t0 = texelFetch(u_prims, b), t1 = texelFetch(u_prims, b + 1), t2 = texelFetch(u_prims, b + 2);
    vec4 t3 = texelFetch(u_prims, b + 3), t4 = texelFetch(u_prims, b + 4), t5 = texelFetch(u_prims, b + 5);
    vec4 t6 = texelFetch(u_prims, b + 6);
    Frustum F;
    F.c0 = t0.xyz;
    F.r0 = t0.w;
    F.a = t1.xyz;
    F.h = t1.w;
    F.n0 = t2.xyz;
    F.k = t2.w;
    F.n1 = t3.xyz;
    F.D = u_relief_size.x > 0 ? t3.w : 0.0; // without RELF every depth is ignored
    F.fx = t4.xyz;
    F.u_off = t4.w;
    F.twist = t5.x;
    F.u_scale = t5.y;
    F.v_off = t5.z;
    F.v_scale = t5.w;
    F.cap0 = t6.y != 0.0;
    F.cap1 = t6.z != 0.0;
    F.fz = cross(F.fx, F.a);
    F.n0a = dot(F.n0, F.a);
    F.n1a = dot(F.n1, F.a);
    return F;
}

// --- intervals along the ray -----------------------------------------------

// Constraint kinds bounding an interval end.
const int K_LATERAL = 0, K_PLANE0 = 1, K_PLANE1 = 2, K_NONE = 3;

// Keep the s with alpha + beta s <= 0.
void clip_linear(float alpha, float beta, int kind, inout float lo, inout float hi, inout int klo, inout int khi)
{
    if (beta == 0.0) {
        if (alpha > 0.0) {
            lo = BIG;
            hi = -BIG;
        }
    } else if (beta > 0.0) {
        float s = -alpha / beta;
        if (s < hi) {
            hi = s;
            khi = kind;
        }
    } else {
        float s = -alpha / beta;
        if (s > lo) {
            lo = s;
            klo = kind;
        }
    }
}

// The interval of o + s d (o relative to c0, d unit) inside the cone
// |q| <= rb + k y on its nappe rb + k y >= 0, and inside both planes.
bool cone_interval(Frustum F, float rb, vec3 o, vec3 d, out float lo, out float hi, out int klo, out int khi)
{
    lo = -BIG;
    hi = BIG;
    klo = K_NONE;
    khi = K_NONE;
    float yo = dot(o, F.a), yd = dot(d, F.a);
    vec3 qo = o - yo * F.a, qd = d - yd * F.a;
    float ro = rb + F.k * yo;
    // nappe: ro + k yd s >= 0
    int knappe_lo = 0;
    if (F.k * yd != 0.0)
        knappe_lo = F.k * yd > 0.0 ? 1 : -1;
    clip_linear(-ro, -F.k * yd, K_NONE, lo, hi, klo, khi);
    float A = dot(qd, qd) - F.k * F.k * yd * yd;
    float B = 2.0 * (dot(qo, qd) - F.k * yd * ro);
    float C = dot(qo, qo) - ro * ro;
    float scale = abs(A) + abs(B) + abs(C);
    if (abs(A) <= 1e-7 * scale) {
        clip_linear(C, B, K_LATERAL, lo, hi, klo, khi); // a ray along a generator
    } else {
        float disc = B * B - 4.0 * A * C;
        if (disc < 0.0) {
            if (A > 0.0)
                return false; // misses the double cone
            // A < 0 with no roots: inside the double cone throughout (rounding
            // of a ray through the apex); the nappe already chose the half.
        } else {
            float sq = sqrt(disc);
            float qq = -0.5 * (B + (B >= 0.0 ? sq : -sq));
            float x0 = qq / A, x1 = qq != 0.0 ? C / qq : x0;
            float s1 = min(x0, x1), s2 = max(x0, x1);
            if (A > 0.0) {
                if (s1 > lo) {
                    lo = s1;
                    klo = K_LATERAL;
                }
                if (s2 < hi) {
                    hi = s2;
                    khi = K_LATERAL;
                }
            } else if (knappe_lo > 0) { // the nappe is s >= s_apex: the half-line [s2, inf)
                if (s2 > lo) {
                    lo = s2;
                    klo = K_LATERAL;
                }
            } else { // (-inf, s1]
                if (s1 < hi) {
                    hi = s1;
                    khi = K_LATERAL;
                }
            }
        }
    }
    clip_linear(dot(F.n0, o), dot(F.n0, d), K_PLANE0, lo, hi, klo, khi);
    clip_linear(dot(F.n1, o) - F.h * F.n1a, dot(F.n1, d), K_PLANE1, lo, hi, klo, khi);
    return lo <= hi;
}

bool is_surface(Frustum F, int kind)
{
    return kind == K_LATERAL || (kind == K_PLANE0 && F.cap0) || (kind == K_PLANE1 && F.cap1);
}

// --- parametrisation (FORMAT.md sec. 7.2) ----------------------------------

// A point op = p - c0 on the cone through it (r(y) + delta): its axial
// coordinate, radial distance and direction, the generator's axial
// coordinates y0, y1 on the two planes, u, v and w.
struct ConePoint {
    float y, qlen, rb; // rb = r0 + delta: the cone through p at y = 0
    vec3 q, wd;
    float y0, y1, u, v, w;
};

ConePoint cone_point(Frustum F, vec3 op)
{
    ConePoint P;
    P.y = dot(op, F.a);
    P.q = op - P.y * F.a;
    P.qlen = length(P.q);
    P.wd = P.qlen > 0.0 ? P.q / P.qlen : F.fx;
    P.rb = P.qlen - F.k * P.y;
    float n0w = dot(F.n0, P.wd), n1w = dot(F.n1, P.wd);
    float den0 = F.n0a + F.k * n0w, den1 = F.n1a + F.k * n1w;
    P.y0 = den0 != 0.0 ? -P.rb * n0w / den0 : 0.0;
    P.y1 = den1 != 0.0 ? (F.h * F.n1a - P.rb * n1w) / den1 : F.h;
    P.v = P.y1 != P.y0 ? (P.y - P.y0) / (P.y1 - P.y0) : 0.0;
    float ang = P.qlen > 0.0 ? atan(dot(P.q, F.fx), dot(P.q, F.fz)) * INV_TAU : 0.0;
    P.u = fract(ang - F.u_off + P.v * F.twist * INV_TAU);
    P.w = F.D > 0.0 ? (P.qlen - (F.r0 + F.k * P.y)) / F.D : 0.0;
    return P;
}

// Eq. 8 on the cone through the point. P_e lies on plane e, so
// P_e - c_e = rho_e (wd - (n_e.wd / n_e.a) a), rho_e the radius there: its
// direction is computed from that form, which stays exact where rho_e -> 0
// (a pointed tip, where P1 - c1 itself is rounding noise) and is the limit
// of eq. 8 there.
vec3 eq8_normal(Frustum F, ConePoint P)
{
    vec3 nl = normalize(P.wd - (dot(F.n0, P.wd) / F.n0a) * F.a); // P0 - c0
    vec3 nu = normalize(P.wd - (dot(F.n1, P.wd) / F.n1a) * F.a); // P1 - c1
    vec3 n = (1.0 - P.v) * nl + P.v * nu;
    float l = length(n);
    return l > 0.0 ? n / l : P.wd;
}

// --- relief ------------------------------------------------------------------

vec2 relief_st(Frustum F, ConePoint P)
{
    return vec2(P.u * F.u_scale, F.v_off + P.v * F.v_scale);
}

// The texels of level L of a map of `size` (OpenGL 4.6 eq. 8.20: halved,
// rounded down, at least 1). Not textureSize(sampler, L): llvmpipe answered
// it with another level's size in one of two draws of the same texture
// (tests/gl/test_rt_conventions.c, the mirrored frusta).
ivec2 level_size(ivec2 size, int L)
{
    return max(size >> L, ivec2(1));
}

// Bilinear height at (s, t) on mip level L (0: the map), texel centres at
// (i + 1/2) / W_L, wrapping, and the derivatives of the interpolant
// (dh/ds, dh/dt).
float relief_bilinear(vec2 st, int L, out vec2 grad)
{
    ivec2 isz = level_size(u_relief_size, L);
    vec2 size = vec2(isz);
    vec2 x = st * size - 0.5;
    vec2 i0 = floor(x), f = x - i0;
    ivec2 a = ivec2(mod(i0, size)), b = ivec2(mod(i0 + 1.0, size));
    a = min(a, isz - 1); // mod may round up to size itself
    b = min(b, isz - 1);
    float h00 = texelFetch(u_relief, ivec2(a.x, a.y), L).r, h10 = texelFetch(u_relief, ivec2(b.x, a.y), L).r;
    float h01 = texelFetch(u_relief, ivec2(a.x, b.y), L).r, h11 = texelFetch(u_relief, ivec2(b.x, b.y), L).r;
    grad = vec2(mix(h10 - h00, h11 - h01, f.y) * size.x, mix(h01 - h00, h11 - h10, f.x) * size.y);
    return mix(mix(h00, h10, f.x), mix(h01, h11, f.x), f.y);
}

// The search's height: level 0.
float relief_height(vec2 st, out vec2 grad)
{
    return relief_bilinear(st, 0, grad);
}

// The two mip levels around `lod` (clamped to the last, 1 x 1, level of a
// map of `size` texels) and the weight of the coarser.
ivec3 lod_pair(float lod, ivec2 size, out float f)
{
    int last = 0; // floor(log2(the longer side)), exactly (findMSB is GLSL 4.00 / ES 3.10)
    for (int n = max(size.x, size.y); n > 1; n >>= 1)
        ++last;
    float l = clamp(lod, 0.0, float(last));
    int L0 = int(floor(l));
    f = l - float(L0);
    return ivec3(L0, min(L0 + 1, last), 0);
}

// Height and gradient for shading: trilinear between the levels around lod.
float relief_height_lod(vec2 st, float lod, out vec2 grad)
{
    if (lod <= 0.0)
        return relief_bilinear(st, 0, grad);
    float f;
    ivec3 L = lod_pair(lod, u_relief_size, f);
    vec2 g0, g1;
    float h0 = relief_bilinear(st, L.x, g0), h1 = relief_bilinear(st, L.y, g1);
    grad = mix(g0, g1, f);
    return mix(h0, h1, f);
}

// The colour map bilinear on level L (texel centres at (i + 1/2) / W_L,
// wrapping).
vec3 color_bilinear(vec2 st, int L)
{
    ivec2 isz = level_size(u_color_size, L);
    vec2 size = vec2(isz);
    vec2 x = st * size - 0.5;
    vec2 i0 = floor(x), f = x - i0;
    ivec2 a = min(ivec2(mod(i0, size)), isz - 1), b = min(ivec2(mod(i0 + 1.0, size)), isz - 1);
    vec3 c00 = texelFetch(u_color, ivec2(a.x, a.y), L).rgb, c10 = texelFetch(u_color, ivec2(b.x, a.y), L).rgb;
    vec3 c01 = texelFetch(u_color, ivec2(a.x, b.y), L).rgb, c11 = texelFetch(u_color, ivec2(b.x, b.y), L).rgb;
    return mix(mix(c00, c10, f.x), mix(c01, c11, f.x), f.y);
}

// The albedo at relief coordinates st, trilinear between the levels around
// lod (0: the map, bilinear), or u_albedo without a map.
vec3 color_at(vec2 st, float lod)
{
    if (u_color_size.x <= 0)
        return u_albedo;
    if (lod <= 0.0)
        return color_bilinear(st, 0);
    float f;
    ivec3 L = lod_pair(lod, u_color_size, f);
    return mix(color_bilinear(st, L.x), color_bilinear(st, L.y), f);
}

bool solid_at(Frustum F, vec3 op)
{
    ++g_steps;
    ConePoint P = cone_point(F, op);
    vec2 g;
    return P.w <= relief_height(relief_st(F, P), g);
}

// The first change of solidity from `from` along o + s d, s in [sa, sb]:
// u_relief_steps uniform samples, then u_bisect_steps bisection steps on the
// bracketing pair; the hit is the final bracket's midpoint. `end_flips`: the
// state at sb is known to differ (the inner cone's entry).
bool march(Frustum F, vec3 o, vec3 d, float sa, float sb, bool from, bool end_flips, out float s_hit)
{
    s_hit = sb;
    float prev = sa;
    for (int i = 1; i <= u_relief_steps; ++i) {
        float s = mix(sa, sb, float(i) / float(u_relief_steps));
        bool st = (i == u_relief_steps && end_flips) ? !from : solid_at(F, o + s * d);
        if (st != from) {
            float lo = prev, hi = s;
            for (int j = 0; j < u_bisect_steps; ++j) {
                float m = 0.5 * (lo + hi);
                if (solid_at(F, o + m * d) == from)
                    lo = m;
                else
                    hi = m;
            }
            s_hit = 0.5 * (lo + hi);
            return true;
        }
        prev = s;
    }
    return false;
}

// Relief shading normal (FORMAT.md sec. 7.2): eq. 8 tilted by D grad h.
// --- filtered for the pixel's footprint (raycast_common.glsl tex_footprint) --
//
// The march reads level 0 (relief_height); what shades the hit - the relief
// normal's gradient and the colour - reads the level of the pixel's
// footprint on the maps: the rays half a pixel either side (in x, in y) meet
// the plane through the hit of normal nrm (the cone's eq. 8 normal or the
// cap's: the surface the maps lie on, not the relief's facet, as for
// shells), and the relief coordinates of those points, differenced, are
// the derivatives of (s, t) per pixel (s wraps around the axis: a
// difference is taken modulo one turn, so a footprint wider than half a
// turn reads as narrower - the frustum is then a few pixels across).

vec2 st_at(Frustum F, vec3 op)
{
    return relief_st(F, cone_point(F, op));
}

vec2 st_differential(Frustum F, vec3 op, vec3 nrm, vec2 axis)
{
    float far = 1e6 * (F.h + F.r0 + F.D + 1.0);
    vec3 p = F.c0 + op;
    vec2 d = st_at(F, op + plane_offset(nrm, p, gl_FragCoord.xy + 0.5 * axis, far)) -
             st_at(F, op + plane_offset(nrm, p, gl_FragCoord.xy - 0.5 * axis, -far));
    if (F.u_scale > 0.0)
        d.x -= F.u_scale * round(d.x / F.u_scale);
    return d;
}

// The levels of the relief map (.x) and the colour map (.y) at the hit op
// (relative to c0) on the surface of normal nrm; 0 without mip levels.
vec2 map_levels(Frustum F, vec3 op, vec3 nrm)
{
    if (u_mips == 0 || (F.D <= 0.0 && u_color_size.x <= 0)) // nothing to filter
        return vec2(0.0);
    vec2 dx = st_differential(F, op, nrm, vec2(1.0, 0.0)), dy = st_differential(F, op, nrm, vec2(0.0, 1.0));
    mat2x3 fp = mat2x3(vec3(dx, 0.0), vec3(dy, 0.0));
    return vec2(tex_level(fp, vec3(vec2(u_relief_size), 1.0)), tex_level(fp, vec3(vec2(u_color_size), 1.0)));
}

vec3 relief_normal(Frustum F, ConePoint P, float lod)
{
    vec2 g;
    relief_height_lod(relief_st(F, P), lod, g);
    vec3 N = eq8_normal(F, P);
    vec3 tu = cross(F.a, P.wd);
    vec3 gen = F.a + F.k * P.wd;
    float lu = TAU * P.qlen, lv = abs(P.y1 - P.y0) * length(gen);
    vec3 tv = normalize(gen) * (P.y1 >= P.y0 ? 1.0 : -1.0);
    vec3 grad = vec3(0.0);
    if (lu > 0.0)
        grad += g.x * F.u_scale * tu / lu;
    if (lv > 0.0) // twist: u grows by twist/2pi per unit of v, so dh/ds has a share along T_v
        grad += (g.y * F.v_scale + g.x * F.u_scale * F.twist * INV_TAU) * tv / lv;
    vec3 n = N - F.D * grad;
    float l = length(n);
    return l > 0.0 ? n / l : N;
}

// --- output (fragment_ray, write_depth, finish: raycast_common.glsl) -------

vec3 shade(vec3 albedo, vec3 n, float w, vec3 rd)
{
    if (dot(n, rd) > 0.0)
        n = -n;
    return albedo * (0.25 + 0.75 * clamp(w, 0.0, 1.0)) * (0.15 + 0.85 * max(dot(n, u_light_obj), 0.0));
}

// --- primitives --------------------------------------------------------------

void ball_main(int prim, vec3 ro, vec3 rd)
{
    vec4 s = texelFetch(u_prims, MESO_FRUSTA_TEXELS * prim);
    vec3 o = ro - s.xyz;
    float b = dot(o, rd), c = dot(o, o) - s.w * s.w;
    // Move the origin next to the ball first (float cancellation in c).
    float ts = max(0.0, -b - s.w);
    o += ts * rd;
    b = dot(o, rd);
    c = dot(o, o) - s.w * s.w;
    float disc = b * b - c;
    if (disc < 0.0) {
        finish(false);
        return;
    }
    float sq = sqrt(disc), t = -b - sq;
    if (t < -ts)
        t = -b + sq; // the near root is behind the near plane: inside the ball
    if (t < -ts) {
        finish(false);
        return;
    }
    vec3 p = o + t * rd;
#if MESO_PASS != MESO_PASS_DEPTH
    vec3 albedo = u_color_size.x > 0 ? u_ball_color : u_albedo;
    emit_obj(shade(albedo, p / s.w, 1.0, rd), albedo, 1.0, facing(p, rd), s.xyz + p, rd);
#endif
    write_depth(s.xyz + p);
    finish(true);
}

void frustum_main(int prim, vec3 ro, vec3 rd)
{
    Frustum F = fetch_frustum(prim);
    // Start the ray next to the primitive's bounding sphere: the quadratic's
    // constant term cancels badly in float for far-away origins.
    vec4 bs = texelFetch(u_prims, MESO_FRUSTA_TEXELS * prim + 7);
    float ts = max(0.0, dot(bs.xyz - ro, rd) - bs.w);
    vec3 o = ro + ts * rd - F.c0;
    float smin = -ts; // the near plane
    float lo, hi;
    int klo, khi;
    if (!cone_interval(F, F.r0 + F.D, o, rd, lo, hi, klo, khi)) {
        finish(false);
        return;
    }
    float sa = max(lo, smin);
    bool entered = lo >= smin;
    if (sa > hi) {
        finish(false);
        return;
    }
    float s_hit = 0.0;
    int kind = -1; // -1 relief surface, else the constraint kind that was hit
    bool found = false;
    if (F.D <= 0.0) {
        if (entered && is_surface(F, klo)) {
            s_hit = lo;
            kind = klo;
            found = true;
        } else if (is_surface(F, khi)) {
            s_hit = hi;
            kind = khi;
            found = true;
        }
    } else {
        float ilo, ihi;
        int kil, kih;
        bool inner = cone_interval(F, F.r0, o, rd, ilo, ihi, kil, kih) && ihi >= sa && ilo <= hi;
        bool in_core = inner && ilo <= sa;
        bool s0 = in_core ? true : solid_at(F, o + sa * rd);
        if (entered && s0 && is_surface(F, klo)) {
            s_hit = sa;
            kind = klo;
            found = true;
        } else {
            if (!in_core) // before the core (or the whole interval when the ray misses it)
                found = march(F, o, rd, sa, inner ? ilo : hi, s0, inner && !s0, s_hit);
            if (!found && s0 && inner && ihi < hi) // after the core
                found = march(F, o, rd, max(ihi, sa), hi, true, false, s_hit);
            if (!found && s0 && is_surface(F, khi)) { // leaving the solid through a cap
                s_hit = hi;
                kind = khi;
                found = true;
            }
        }
    }
    if (!found || s_hit >= BIG) {
        finish(false);
        return;
    }
    vec3 op = o + s_hit * rd;
#if MESO_PASS != MESO_PASS_DEPTH
    ConePoint P = cone_point(F, op);
    vec3 base_n = kind == K_PLANE0 ? F.n0 : kind == K_PLANE1 ? F.n1 : eq8_normal(F, P);
    vec2 lod = map_levels(F, op, base_n);
    vec3 n = base_n;
    if (kind != K_PLANE0 && kind != K_PLANE1 && F.D > 0.0)
        n = relief_normal(F, P, lod.x);
    float w = F.D > 0.0 ? P.w : 1.0;
    vec3 albedo = color_at(relief_st(F, P), lod.y);
    emit_obj(shade(albedo, n, w, rd), albedo, occlusion(w), facing(n, rd), F.c0 + op, rd);
#endif
    write_depth(F.c0 + op);
    finish(true);
}

void main()
{
    instance_begin();
    vec3 ro, rd;
    fragment_ray(ro, rd);
    if (texelFetch(u_prims, MESO_FRUSTA_TEXELS * v_prim + 6).x != 0.0)
        ball_main(v_prim, ro, rd);
    else
        frustum_main(v_prim, ro, rd);
}
