/*
 * texture_function.c — see texture_function.h: SPEC parsing, file inputs
 * (PNG height maps, raw and OpenVDB densities), the procedural built-ins,
 * quantisation to the chunk encoding, and the runtime's filtering.
 */
#include "texture_function.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "adapters.h"
#include "memory_budget.h"
#include "png_io.h"

/* >>hash ------------------------------------------------------------------
 * "lowbias32" (Chris Wellons, "Prospecting for Hash Functions", 2018): a
 * 32-bit integer finaliser with a low avalanche bias. The built-ins draw all
 * their randomness from it, keyed by integer lattice coordinates taken
 * modulo the tile's period, so values repeat exactly across tiles. */
static uint32_t hash32(uint32_t x)
{
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

/* Uniform in [0, 1) from up to three integer coordinates and a channel. */
static double hash01(int a, int b, int c, uint32_t channel)
{
    uint32_t h = hash32((uint32_t)a * 0x9E3779B1u ^ channel * 0x85EBCA77u);
    h = hash32(h ^ (uint32_t)b * 0xC2B2AE3Du);
    h = hash32(h ^ (uint32_t)c * 0x27D4EB2Fu);
    return (h >> 8) * (1.0 / 16777216.0);
}

static int wrapi(int i, int n)
{
    const int r = i % n;
    return r < 0 ? r + n : r;
}

static double clamp01(double x)
{
    return x < 0 ? 0 : x > 1 ? 1 : x;
}

/* >>filtering -------------------------------------------------------------- */

void meso_texfn_axis(const meso_texfn* f, int axis, double x, uint32_t* i0, uint32_t* i1, double* frac)
{
    const uint32_t n = f->dims[axis];
    const double u = x * n - 0.5; /* texel units, centres at integers */
    if (axis == 2) {
        /* w: clamps to the first and last texel centres (a height field has
         * one layer, so it is constant in w). */
        if (!(u > 0)) {
            *i0 = *i1 = 0;
            *frac = 0;
        } else if (u >= n - 1.0) {
            *i0 = *i1 = n - 1;
            *frac = 0;
        } else {
            *i0 = (uint32_t)u;
            *frac = u - *i0;
            *i1 = *i0 + 1;
        }
        return;
    }
    const double fl = floor(u);
    *frac = u - fl;
    double m = fmod(fl, (double)n);
    if (m < 0)
        m += n;
    *i0 = (uint32_t)m;
    *i1 = *i0 + 1 == n ? 0 : *i0 + 1;
}

double meso_texfn_sample_at(const meso_texfn* f, const uint32_t i0[3], const uint32_t i1[3], const double frac[3])
{
    const size_t W = f->dims[0], sl = W * f->dims[1];
    double r[2];
    for (int k = 0; k < 2; ++k) {
        const float* p = f->values + (k ? i1[2] : i0[2]) * sl;
        const double a = p[i0[1] * W + i0[0]] + frac[0] * (p[i0[1] * W + i1[0]] - p[i0[1] * W + i0[0]]);
        const double b = p[i1[1] * W + i0[0]] + frac[0] * (p[i1[1] * W + i1[0]] - p[i1[1] * W + i0[0]]);
        r[k] = a + frac[1] * (b - a);
        if (i1[2] == i0[2])
            return r[0];
    }
    return r[0] + frac[2] * (r[1] - r[0]);
}

double meso_texfn_sample(const meso_texfn* f, double s, double t, double w)
{
    uint32_t i0[3], i1[3];
    double fr[3];
    meso_texfn_axis(f, 0, s, &i0[0], &i1[0], &fr[0]);
    meso_texfn_axis(f, 1, t, &i0[1], &i1[1], &fr[1]);
    meso_texfn_axis(f, 2, w, &i0[2], &i1[2], &fr[2]);
    return meso_texfn_sample_at(f, i0, i1, fr);
}

int meso_texfn_solid(const meso_texfn* f, double s, double t, double w)
{
    if (!(w >= 0.0 && w <= 1.0))
        return 0;
    const double v = meso_texfn_sample(f, s, t, w);
    return f->kind == MESO_TEXFN_HEIGHT ? w <= v : v >= 0.5;
}

/* >>construction ------------------------------------------------------------ */

void meso_texfn_free(meso_texfn* f)
{
    if (!f)
        return;
    free(f->values);
    free(f->encoded);
    memset(f, 0, sizeof(*f));
}

meso_result meso_texfn_from_values(meso_texfn_kind kind, const uint32_t dims[3], const float* values, uint16_t dtype,
                                   meso_texfn* out, meso_error* err)
{
    memset(out, 0, sizeof(*out));
    if (kind >= MESO_TEXFN_KIND_COUNT || !dims[0] || !dims[1] || !dims[2] ||
        (kind == MESO_TEXFN_HEIGHT && dims[2] != 1) || (dtype != MESO_DTYPE_U8 && dtype != MESO_DTYPE_U16) ||
        dims[0] > 65536 || dims[1] > 65536 || dims[2] > 65536)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TEXFN_ISSUE_SPEC, "texture: bad kind, size or type");
    const size_t n = (size_t)dims[0] * dims[1] * dims[2];
    const size_t bytes = dtype == MESO_DTYPE_U8 ? 1 : 2;
    if (n > ((size_t)1 << 31))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TEXFN_ISSUE_SPEC, "texture: %zu texels is too many", n);
    out->values = malloc(sizeof(float) * n);
    out->encoded = malloc(bytes * n);
    if (!out->values || !out->encoded) {
        meso_texfn_free(out);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "texture: out of memory");
    }
    const double max = dtype == MESO_DTYPE_U8 ? 255.0 : 65535.0;
    uint8_t* e = out->encoded;
    for (size_t i = 0; i < n; ++i) {
        const double x = values[i];
        const uint32_t q = (uint32_t)lrint(max * clamp01(x == x ? x : 0.0));
        out->values[i] = (float)(q / max);
        e[bytes * i] = (uint8_t)(q & 0xFF);
        if (bytes == 2)
            e[2 * i + 1] = (uint8_t)(q >> 8);
    }
    out->kind = kind;
    memcpy(out->dims, dims, sizeof(out->dims));
    out->dtype = dtype;
    out->encoded_size = bytes * n;
    return MESO_OK;
}

/* >>built-ins ----------------------------------------------------------------
 * Each is evaluated at texel centres ((i + 1/2)/W, ...) of one tile, from
 * functions periodic in s and t with period 1, so the texture tiles
 * seamlessly. Constants are in tile units (s, t) and shell units (w) and were
 * chosen by eye for plausible proportions at the default resolutions. */

/* Quarter-circle bevel: 0 at the edge, 1 from `width` inwards. */
static double bevel(double inside, double width)
{
    if (inside <= 0)
        return 0;
    const double q = 1.0 - fmin(inside / width, 1.0);
    return sqrt(1.0 - q * q);
}

/* Running bond: 6 courses of 2 bricks (3:1), odd courses shifted by half a
 * brick; mortar 0.016 wide at height 0.25, bricks at 0.85 ± 0.06 with a 0.02
 * bevel. 6 courses: an even count keeps the alternation periodic in t. */
static double bricks_height(double s, double t)
{
    enum { COURSES = 6, PER_COURSE = 2 };
    const double mortar_half = 0.008, bevel_w = 0.02, mortar_h = 0.25;
    const double y = t * COURSES;
    const int row = (int)floor(y);
    const double ly = y - row;
    const double x = s * PER_COURSE - 0.5 * (row & 1);
    const int col = (int)floor(x);
    const double lx = x - col;
    const double edge = fmin(fmin(lx, 1 - lx) / PER_COURSE, fmin(ly, 1 - ly) / COURSES);
    const int r = wrapi(row, COURSES), c = wrapi(col, PER_COURSE);
    const double top = 0.85 + 0.12 * (hash01(r, c, 0, 1) - 0.5);
    /* A faint tilt per brick, so faces are not all parallel. */
    const double tilt = 0.03 * (hash01(r, c, 0, 2) - 0.5) * (2 * lx - 1);
    return mortar_h + (top + tilt - mortar_h) * bevel(edge - mortar_half, bevel_w);
}

/* Periodic Voronoi over a jittered 5 x 5 lattice of seeds. The nearest two
 * seeds (5 x 5 neighbourhood: jitter up to 0.35 of a cell can not hide a
 * nearer one beyond it) give the distance to the cell's border,
 * (d2² − d1²) / (2 |p2 − p1|). */
static double cobble_height(double s, double t)
{
    enum { G = 5 };
    const int cx = (int)floor(s * G), cy = (int)floor(t * G);
    double d1 = INFINITY, d2 = INFINITY, p1[2] = {0, 0}, p2[2] = {0, 0};
    int id1[2] = {0, 0};
    for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) {
            const int a = wrapi(cx + dx, G), b = wrapi(cy + dy, G);
            const double px = (cx + dx + 0.15 + 0.7 * hash01(a, b, 0, 11)) / G;
            const double py = (cy + dy + 0.15 + 0.7 * hash01(a, b, 0, 12)) / G;
            const double d = (px - s) * (px - s) + (py - t) * (py - t);
            if (d < d1) {
                d2 = d1;
                p2[0] = p1[0];
                p2[1] = p1[1];
                d1 = d;
                p1[0] = px;
                p1[1] = py;
                id1[0] = a;
                id1[1] = b;
            } else if (d < d2) {
                d2 = d;
                p2[0] = px;
                p2[1] = py;
            }
        }
    const double sep = hypot(p2[0] - p1[0], p2[1] - p1[1]);
    const double border = (d2 - d1) / (2 * sep);
    const double sand = 0.1, gap = 0.01;
    const double peak = 0.8 + 0.14 * (hash01(id1[0], id1[1], 0, 13) - 0.5);
    /* Dome: rounded rim (bevel) times a gentle crown towards the seed. */
    const double crown = 1.0 - 0.3 * fmin(1.0, d1 * G * G * 2.0);
    return sand + (peak - sand) * bevel(border - gap, 0.06) * crown;
}

/* Plain weave: 4 warp threads along s and 4 weft threads along t per tile.
 * Warp j's centre line rises and falls as w = 1/2 + A sin(4π s + π j), weft
 * i's as w = 1/2 − A sin(4π t + π i): at every crossing one is at 1/2 + A
 * and the other at 1/2 − A, so they alternate over/under, with empty space
 * under each arch (overhangs a height field can not hold). Threads have an
 * elliptic section (half-width 0.1 tile, half-height 0.13 shell) and a soft
 * rim a quarter of their radius wide, so the trilinear surface is smooth. */
static double weave_density(double s, double t, double w)
{
    enum { N = 4 };
    const double A = 0.19, rt = 0.4 / N, rw = 0.13;
    double best = 0;
    for (int j = 0; j < N; ++j) {
        double dt = t - (j + 0.5) / N;
        dt -= floor(dt + 0.5); /* periodic: nearest copy */
        const double dw = w - (0.5 + A * sin(M_PI * N * s + M_PI * j));
        best = fmax(best, 0.5 + 2.0 * (1.0 - hypot(dt / rt, dw / rw)));
    }
    for (int i = 0; i < N; ++i) {
        double ds = s - (i + 0.5) / N;
        ds -= floor(ds + 0.5);
        const double dw = w - (0.5 - A * sin(M_PI * N * t + M_PI * i));
        best = fmax(best, 0.5 + 2.0 * (1.0 - hypot(ds / rt, dw / rw)));
    }
    return clamp01(best);
}

/* 3D Voronoi foam: seeds jittered on a 3 x 3 lattice per tile in s and t
 * (periodic) and 3 layers in w (not periodic: seeds continue above and
 * below the shell), walls 0.05 thick where the distance to the border of the
 * nearest seed's cell is small. */
static double cells_density(double s, double t, double w)
{
    enum { G = 3 };
    const int c[3] = {(int)floor(s * G), (int)floor(t * G), (int)floor(w * G)};
    const double p[3] = {s, t, w};
    double d1 = INFINITY, d2 = INFINITY, q1[3] = {0, 0, 0}, q2[3] = {0, 0, 0};
    /* The 27 nearest lattice cells first, then the outer shell of the
     * 5 x 5 x 5 block, skipping cells whose seed box (jitter range) is
     * farther than the second-nearest seed found so far. */
    for (int ring = 1; ring <= 2; ++ring) {
        for (int dz = -ring; dz <= ring; ++dz)
            for (int dy = -ring; dy <= ring; ++dy)
                for (int dx = -ring; dx <= ring; ++dx) {
                    if (ring == 2) {
                        if (abs(dx) < 2 && abs(dy) < 2 && abs(dz) < 2)
                            continue;
                        const int cc[3] = {c[0] + dx, c[1] + dy, c[2] + dz};
                        double lb = 0;
                        for (int e = 0; e < 3; ++e) {
                            const double lo = (cc[e] + 0.2) / G, hi = (cc[e] + 0.8) / G;
                            const double g = p[e] < lo ? lo - p[e] : p[e] > hi ? p[e] - hi : 0.0;
                            lb += g * g;
                        }
                        if (lb >= d2)
                            continue;
                    }
                    const int a = wrapi(c[0] + dx, G), b = wrapi(c[1] + dy, G), k = c[2] + dz;
                    const double q[3] = {(c[0] + dx + 0.2 + 0.6 * hash01(a, b, k, 21)) / G,
                                         (c[1] + dy + 0.2 + 0.6 * hash01(a, b, k, 22)) / G,
                                         (k + 0.2 + 0.6 * hash01(a, b, k, 23)) / G};
                    const double d = (q[0] - p[0]) * (q[0] - p[0]) + (q[1] - p[1]) * (q[1] - p[1]) +
                                     (q[2] - p[2]) * (q[2] - p[2]);
                    if (d < d1) {
                        d2 = d1;
                        memcpy(q2, q1, sizeof(q1));
                        d1 = d;
                        memcpy(q1, q, sizeof(q1));
                    } else if (d < d2) {
                        d2 = d;
                        memcpy(q2, q, sizeof(q2));
                    }
                }
    }
    const double sep = sqrt((q2[0] - q1[0]) * (q2[0] - q1[0]) + (q2[1] - q1[1]) * (q2[1] - q1[1]) +
                            (q2[2] - q1[2]) * (q2[2] - q1[2]));
    const double border = (d2 - d1) / (2 * sep);
    const double half_wall = 0.025, soft = 0.015;
    return clamp01(0.5 + (half_wall - border) / (2 * soft));
}

/* Cactus ribs: one rib per tile along t (a relief repeated N times around
 * a frustum gives N ribs), a cosine profile from 0.15 in the valley to 0.75
 * on the crest, and 4 areoles (spine cushions, domes 0.07 wide, +0.25) per
 * tile along the crest. */
static double ribs_height(double s, double t)
{
    const double ds = s - floor(s) - 0.5;
    const double profile = 0.15 + 0.6 * (0.5 + 0.5 * cos(2 * M_PI * ds));
    const double y = t * 4 - floor(t * 4) - 0.5;
    const double rho = hypot(ds, y / 4);
    const double bump = 0.25 * fmax(0.0, 1.0 - (rho / 0.07) * (rho / 0.07));
    return fmin(1.0, profile + bump);
}

/* Boiling (papers/volume-textures-lp-averaged-shells.md §6, the "boiling
 * man"): a liquid layer whose surface ripples around w = 0.35, and per tile
 * 4 x 4 cells of 2 bubbles each (hashed position and phase) that rise from
 * inside the liquid (w = 0.15), break through its surface, grow to an
 * ellipsoid 0.09 tile wide and 0.12 shell high, and at 80 % of their life
 * burst: the bubble turns into a thin skin that opens from the top until
 * nothing is left at the end of the life. Everything is a function of
 * frac(time / BOIL_PERIOD) (bubble ages, ripple phase with whole cycles
 * per period), so the texture loops with period BOIL_PERIOD seconds, and
 * it tiles in s and t (integer frequencies, bubbles at their nearest copy). */
#define BOIL_PERIOD 2.0
static double boil_density_at(double s, double t, double w, double time)
{
    enum { G = 4, PER_CELL = 2 };
    const double tau = time / BOIL_PERIOD - floor(time / BOIL_PERIOD);
    const double level = 0.35 + 0.025 * sin(2 * M_PI * (s + tau)) * sin(2 * M_PI * (2 * t - tau));
    double best = 0.5 + (level - w) / 0.08;
    const double rs = 0.09, rw = 0.12, k = 2.5;
    for (int i = 0; i < G; ++i)
        for (int j = 0; j < G; ++j)
            for (int b = 0; b < PER_CELL; ++b) {
                const double phase = hash01(i, j, b, 31);
                double age = tau + phase;
                age -= floor(age);
                const double cs = (i + 0.2 + 0.6 * hash01(i, j, b, 32)) / G + 0.015 * sin(2 * M_PI * (2 * age + phase));
                const double ct = (j + 0.2 + 0.6 * hash01(i, j, b, 33)) / G;
                const double cw = 0.15 + 0.7 * age;
                const double size = 0.35 + 0.65 * fmin(1.0, age / 0.3);
                double ds = s - cs, dt = t - ct;
                ds -= floor(ds + 0.5); /* periodic: nearest copy */
                dt -= floor(dt + 0.5);
                const double dw = w - cw;
                const double q = sqrt((ds / rs) * (ds / rs) + (dt / rs) * (dt / rs) + (dw / rw) * (dw / rw)) / size;
                double a;
                if (age < 0.8) {
                    a = 0.5 + (1.0 - q) * k;
                } else {
                    /* the skin (q in [0.75, 1]) minus a cap whose opening grows to the whole bubble */
                    const double open = 1.0 - 2.0 * (age - 0.8) / 0.2; /* cos of the cap's half-angle */
                    const double up = q > 1e-9 ? (dw / rw) / (q * size) : 0.0;
                    a = fmin(0.5 + (0.125 - fabs(q - 0.875)) * 4 * k, 0.5 + (open - up) * 4);
                }
                best = fmax(best, a);
            }
    return clamp01(best);
}

static double boil_density(double s, double t, double w)
{
    return boil_density_at(s, t, w, 0.0);
}

/* Figure 12 of papers/volume-textures-lp-averaged-shells.md (§5): "the
 * distance field for a large sphere with smaller spheres attached at
 * vertices of a regular icosahedron". One copy per tile, not periodic (the
 * tile's border is empty): a sphere of radius 0.25 at the centre of the unit
 * cube (s, t, w) and twelve of radius 0.09 centred at distance 0.29 from it
 * in the directions of the icosahedron's vertices (0, ±1, ±φ) and their
 * cyclic permutations, so each sits 0.04 deep in the large one and all stay
 * within 0.38 of the centre (0.12 from the cube's faces). Density
 * 1/2 − 2 d, d the signed distance to the union (negative inside),
 * clamped to [0, 1]: linear over ±0.25 of the surface, so α = ½ lies
 * between any two slices at least 1/15 apart (16 slices of a unit shell) and
 * the paper's interpolation between them is exact for a single sphere. */
static double icospheres_density(double s, double t, double w)
{
    const double phi = 0.5 * (1.0 + sqrt(5.0)), len = sqrt(1.0 + phi * phi);
    const double p[3] = {s - 0.5, t - 0.5, w - 0.5};
    double d = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 0.25;
    for (int v = 0; v < 12; ++v) {
        /* (0, ±1, ±φ) rotated cyclically by v / 4 places. */
        const double a = (v & 1) ? -1.0 : 1.0, b = (v & 2) ? -phi : phi;
        const double e[3] = {0.0, a / len, b / len};
        const int r = v / 4;
        double c[3];
        for (int k = 0; k < 3; ++k)
            c[(k + r) % 3] = 0.29 * e[k];
        const double dx = p[0] - c[0], dy = p[1] - c[1], dz = p[2] - c[2];
        d = fmin(d, sqrt(dx * dx + dy * dy + dz * dz) - 0.09);
    }
    return clamp01(0.5 - 2.0 * d);
}

typedef struct builtin {
    const char* name;
    meso_texfn_kind kind;
    uint32_t default_res, max_res;
    double (*height)(double s, double t);
    double (*density)(double s, double t, double w);
    int depth_div; /* D = RES / depth_div */
    double (*density_at)(double s, double t, double w, double time); /* time-dependent built-ins, else NULL */
    double period;                                                   /* their loop period, seconds */
} builtin;

static const builtin builtins[] = {
    {"bricks", MESO_TEXFN_HEIGHT, 256, 1024, bricks_height, NULL, 0, NULL, 0},
    {"cobble", MESO_TEXFN_HEIGHT, 256, 1024, cobble_height, NULL, 0, NULL, 0},
    {"ribs", MESO_TEXFN_HEIGHT, 256, 1024, ribs_height, NULL, 0, NULL, 0},
    {"weave", MESO_TEXFN_DENSITY, 128, 256, NULL, weave_density, 2, NULL, 0},
    {"cells", MESO_TEXFN_DENSITY, 64, 256, NULL, cells_density, 1, NULL, 0},
    {"boil", MESO_TEXFN_DENSITY, 64, 256, NULL, boil_density, 1, boil_density_at, BOIL_PERIOD},
    {"icospheres", MESO_TEXFN_DENSITY, 64, 256, NULL, icospheres_density, 1, NULL, 0},
};

double meso_texfn_builtin_value(const char* name, double s, double t, double w)
{
    for (size_t i = 0; i < sizeof(builtins) / sizeof(builtins[0]); ++i)
        if (!strcmp(name, builtins[i].name))
            return builtins[i].height ? builtins[i].height(s, t) : builtins[i].density(s, t, w);
    return NAN;
}

static meso_result build_builtin(const builtin* b, uint32_t res, double time, uint64_t budget, meso_texfn* out,
                                 meso_error* err)
{
    const uint32_t dims[3] = {res, res, b->kind == MESO_TEXFN_HEIGHT ? 1 : res / (uint32_t)b->depth_div};
    const size_t n = (size_t)dims[0] * dims[1] * dims[2];
    meso_result r = meso_budget_check(meso_texture_estimate(n), budget, MESO_LIMIT_ISSUE_REQUEST, err,
                                      "texture %s:%u (%ux%ux%u texels)", b->name, res, dims[0], dims[1], dims[2]);
    if (r != MESO_OK)
        return r;
    float* v = malloc(sizeof(float) * n);
    if (!v)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "texture: out of memory");
    /* Texels are independent, so the result does not depend on the thread count. */
#ifdef _OPENMP
#pragma omp parallel for schedule(static)
#endif
    for (long z = 0; z < (long)dims[2]; ++z)
        for (uint32_t y = 0; y < dims[1]; ++y)
            for (uint32_t x = 0; x < dims[0]; ++x) {
                const double s = (x + 0.5) / dims[0], t = (y + 0.5) / dims[1], w = (z + 0.5) / dims[2];
                v[((size_t)z * dims[1] + y) * dims[0] + x] =
                    (float)(b->height       ? b->height(s, t)
                            : b->density_at ? b->density_at(s, t, w, time)
                                            : b->density(s, t, w));
            }
    r = meso_texfn_from_values(b->kind, dims, v,
                                                 b->kind == MESO_TEXFN_HEIGHT ? MESO_DTYPE_U16 : MESO_DTYPE_U8, out,
                                                 err);
    free(v);
    if (r == MESO_OK)
        snprintf(out->source, sizeof(out->source), "%s", b->name);
    return r;
}

/* >>files ----------------------------------------------------------------- */

static meso_result spec_error(meso_error* err, const char* spec, const char* what)
{
    return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TEXFN_ISSUE_SPEC,
                          "texture '%s': %s (expected height:FILE.png, volume:FILE.raw:WxHxD, "
                          "volume:FILE.vdb[:GRID], bricks[:RES], cobble[:RES], ribs[:RES], weave[:RES], cells[:RES], boil[:RES] or icospheres[:RES])",
                          spec, what);
}

#if MESO_HAVE_OPENVDB /* the .vdb reader is the only user */
static meso_result check_readable(const char* path, meso_error* err)
{
    FILE* fp = fopen(path, "rb");
    if (!fp)
        return meso_bake_fail(err, MESO_ERR_IO, MESO_TEXFN_ISSUE_FILE, "texture file %s: %s", path, strerror(errno));
    fclose(fp);
    return MESO_OK;
}
#endif

/* Bytes a pixel that load_png_height holds beside the reader's: the floats
 * (4 B), then the function's values (4 B) and payload (2 B). */
#define PNG_EXTRA_PER_PIXEL 10u

static meso_result load_png_height(const char* path, uint64_t budget, meso_texfn* out, meso_error* err)
{
    FILE* fp = fopen(path, "rb");
    if (!fp)
        return meso_bake_fail(err, MESO_ERR_IO, MESO_TEXFN_ISSUE_FILE, "texture file %s: %s", path, strerror(errno));
    uint16_t* px = NULL;
    int w = 0, h = 0, depth = 0;
    uint64_t need = 0;
    char why[600];
    const int rc = meso_png_read_channel0_fp(fp, path, budget, PNG_EXTRA_PER_PIXEL, &px, &w, &h, &depth, &need, why,
                                             (int)sizeof(why));
    fclose(fp);
    if (rc == -2) /* the header asks for more than the budget: nothing was allocated */
        return meso_budget_check(need, budget, MESO_LIMIT_ISSUE_PNG, err, "texture file %s", why);
    if (rc != 0)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_TEXFN_ISSUE_CONTENT, "texture file %s", why);
    meso_result r;
    const size_t n = (size_t)w * (size_t)h;
    float* v = malloc(sizeof(float) * n);
    if (!v) {
        free(px);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "texture: out of memory");
    }
    const double max = depth == 16 ? 65535.0 : 255.0;
    /* Image rows run top to bottom; t = 0 is the bottom row. */
    for (size_t y = 0; y < (size_t)h; ++y)
        for (size_t x = 0; x < (size_t)w; ++x)
            v[y * (size_t)w + x] = (float)(px[((size_t)h - 1 - y) * (size_t)w + x] / max);
    free(px);
    const uint32_t dims[3] = {(uint32_t)w, (uint32_t)h, 1};
    r = meso_texfn_from_values(MESO_TEXFN_HEIGHT, dims, v, depth == 16 ? MESO_DTYPE_U16 : MESO_DTYPE_U8, out, err);
    free(v);
    return r;
}

static int parse_dims(const char* s, uint32_t dims[3])
{
    unsigned long v[3];
    char* end = NULL;
    const char* p = s;
    for (int i = 0; i < 3; ++i) {
        if (*p < '0' || *p > '9')
            return 0;
        v[i] = strtoul(p, &end, 10);
        if (v[i] == 0 || v[i] > 4096)
            return 0;
        if (i < 2 && *end != 'x')
            return 0;
        p = end + (i < 2);
    }
    if (*end)
        return 0;
    for (int i = 0; i < 3; ++i)
        dims[i] = (uint32_t)v[i];
    return 1;
}

static meso_result load_raw_volume(const char* path, const uint32_t dims[3], uint64_t budget, meso_texfn* out,
                                   meso_error* err)
{
    FILE* fp = fopen(path, "rb");
    if (!fp)
        return meso_bake_fail(err, MESO_ERR_IO, MESO_TEXFN_ISSUE_FILE, "texture file %s: %s", path, strerror(errno));
    const uint64_t n = (uint64_t)dims[0] * dims[1] * dims[2];
    /* First what the file can hold (a regular file's length must be the
     * declared size exactly: exit 3), then what the request costs (exit 1);
     * both before anything is allocated. A pipe is read and its length
     * checked after. */
    uint64_t file_size = 0;
    meso_result r = MESO_OK;
    if (meso_regular_file_size(fp, &file_size) && file_size != n)
        r = meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_TEXFN_ISSUE_CONTENT,
                           "texture file %s: has %llu bytes, expected exactly %llu (%ux%ux%u u8 densities)", path,
                           (unsigned long long)file_size, (unsigned long long)n, dims[0], dims[1], dims[2]);
    if (r == MESO_OK)
        r = meso_budget_check(meso_texture_estimate(n), budget, MESO_LIMIT_ISSUE_REQUEST, err,
                              "texture volume %s:%ux%ux%u", path, dims[0], dims[1], dims[2]);
    if (r != MESO_OK) {
        fclose(fp);
        return r;
    }
    uint8_t* raw = malloc(n + 1);
    float* v = malloc(sizeof(float) * n);
    r = raw && v ? MESO_OK : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "texture: out of memory");
    if (r == MESO_OK) {
        const size_t got = fread(raw, 1, n + 1, fp);
        if (ferror(fp))
            r = meso_bake_fail(err, MESO_ERR_IO, MESO_TEXFN_ISSUE_FILE, "texture file %s: read error", path);
        else if (got != n)
            r = meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_TEXFN_ISSUE_CONTENT,
                               "texture file %s: has %s%zu bytes, expected exactly %zu (%ux%ux%u u8 densities)",
                               path, got > n ? "more than " : "", got > n ? n : got, n, dims[0], dims[1], dims[2]);
    }
    fclose(fp);
    for (size_t i = 0; r == MESO_OK && i < n; ++i)
        v[i] = (float)(raw[i] / 255.0);
    if (r == MESO_OK)
        r = meso_texfn_from_values(MESO_TEXFN_DENSITY, dims, v, MESO_DTYPE_U8, out, err);
    free(raw);
    free(v);
    return r;
}

/* .vdb: fog volumes give alpha = value (clamped to [0, 1]); level sets give
 * alpha = 1/2 − φ / (2 · voxel size), clamped: alpha = 1/2 exactly on the zero
 * crossing, so the solid is the level set's interior, and the ramp is two
 * voxels wide, which keeps the trilinear surface close to the level set's. */
static meso_result load_vdb_volume(const char* path, const char* grid, meso_texfn* out, meso_error* err)
{
#if MESO_HAVE_OPENVDB
    meso_result r = check_readable(path, err);
    if (r != MESO_OK)
        return r;
    meso_vdb_dense dense;
    r = meso_vdb_read_dense(path, grid, 256, MESO_TEXFN_ISSUE_VDB, &dense, err);
    if (r == MESO_ERR_IO)
        err->code = MESO_TEXFN_ISSUE_FILE;
    if (r != MESO_OK)
        return r;
    const size_t n = (size_t)dense.dims[0] * dense.dims[1] * dense.dims[2];
    for (size_t i = 0; i < n; ++i) {
        const double x = dense.values[i];
        dense.values[i] = (float)clamp01(dense.is_level_set ? 0.5 - x / (2.0 * dense.voxel_size) : x);
    }
    r = meso_texfn_from_values(MESO_TEXFN_DENSITY, dense.dims, dense.values, MESO_DTYPE_U16, out, err);
    free(dense.values);
    return r;
#else
    (void)grid;
    (void)out;
    return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, MESO_TEXFN_ISSUE_VDB,
                          "texture file %s: .vdb input needs OpenVDB (built without it)", path);
#endif
}

static int ends_with(const char* s, size_t len, const char* suffix)
{
    const size_t k = strlen(suffix);
    return len >= k && !strncmp(s + len - k, suffix, k);
}

meso_result meso_texfn_from_spec(const char* spec, meso_texfn* out, meso_error* err)
{
    return meso_texfn_from_spec_max(spec, UINT64_MAX, out, err);
}

meso_result meso_texfn_from_spec_max(const char* spec, uint64_t max_bytes, meso_texfn* out, meso_error* err)
{
    return meso_texfn_from_spec_at(spec, 0.0, max_bytes, out, err);
}

/* The built-in `spec` names (its head before ':'), or NULL. */
static const builtin* find_builtin(const char* spec)
{
    const char* colon = strchr(spec, ':');
    const size_t head = colon ? (size_t)(colon - spec) : strlen(spec);
    for (size_t i = 0; i < sizeof(builtins) / sizeof(builtins[0]); ++i)
        if (strlen(builtins[i].name) == head && !strncmp(spec, builtins[i].name, head))
            return &builtins[i];
    return NULL;
}

double meso_texfn_period(const char* spec)
{
    const builtin* b = spec ? find_builtin(spec) : NULL;
    return b && b->density_at ? b->period : 0.0;
}

meso_result meso_texfn_from_spec_at(const char* spec, double time, uint64_t max_bytes, meso_texfn* out,
                                    meso_error* err)
{
    memset(out, 0, sizeof(*out));
    const char* colon = strchr(spec, ':');
    const size_t head = colon ? (size_t)(colon - spec) : strlen(spec);
    const char* rest = colon ? colon + 1 : NULL;
    for (size_t i = 0; i < sizeof(builtins) / sizeof(builtins[0]); ++i) {
        const builtin* b = &builtins[i];
        if (strlen(b->name) != head || strncmp(spec, b->name, head))
            continue;
        unsigned long res = b->default_res;
        if (rest) {
            char* end = NULL;
            res = *rest >= '0' && *rest <= '9' ? strtoul(rest, &end, 10) : 0;
            if (!end || *end || res < 8 || res > b->max_res || (b->depth_div && res % (unsigned long)b->depth_div))
                return spec_error(err, spec, b->max_res == 1024 ? "RES must be an integer in 8..1024"
                                                                : "RES must be an even integer in 8..256");
        }
        return build_builtin(b, (uint32_t)res, time, max_bytes, out, err);
    }
    meso_result r;
    if (head == 6 && !strncmp(spec, "height", 6)) {
        if (!rest || !*rest)
            return spec_error(err, spec, "height needs a PNG file");
        r = load_png_height(rest, max_bytes, out, err);
    } else if (head == 6 && !strncmp(spec, "volume", 6)) {
        if (!rest || !*rest)
            return spec_error(err, spec, "volume needs a .raw or .vdb file");
        const size_t len = strlen(rest);
        const char* last = strrchr(rest, ':');
        char path[4096];
        if (ends_with(rest, len, ".vdb") || (last && ends_with(rest, (size_t)(last - rest), ".vdb"))) {
            const int has_grid = !ends_with(rest, len, ".vdb");
            const size_t plen = has_grid ? (size_t)(last - rest) : len;
            if (plen >= sizeof(path) || (has_grid && !last[1]))
                return spec_error(err, spec, "bad .vdb path or grid name");
            memcpy(path, rest, plen);
            path[plen] = 0;
            r = load_vdb_volume(path, has_grid ? last + 1 : NULL, out, err);
        } else {
            uint32_t dims[3];
            if (!last || !parse_dims(last + 1, dims))
                return spec_error(err, spec, "a .raw volume needs its size, volume:FILE.raw:WxHxD (each 1..4096)");
            const size_t plen = (size_t)(last - rest);
            if (!plen || plen >= sizeof(path))
                return spec_error(err, spec, "bad .raw path");
            memcpy(path, rest, plen);
            path[plen] = 0;
            r = load_raw_volume(path, dims, max_bytes, out, err);
        }
    } else {
        return spec_error(err, spec, "unknown texture source");
    }
    if (r == MESO_OK)
        snprintf(out->source, sizeof(out->source), "%.*s", (int)head, spec);
    return r;
}
