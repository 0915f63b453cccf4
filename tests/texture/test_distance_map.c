/* Texture functions and their distance maps (bake/texture_function.c,
 * bake/distance_map.c), against independent brute force:
 *  - the EDT against all-pairs distances (periodic and not, anisotropic);
 *  - cell maxima against dense sampling of the filtered function;
 *  - distance maps conservative: no densely sampled solid point is closer to
 *    any point of a cell than the stored value (box-to-point distance, with
 *    wrap), for height fields and densities, every store type; plus how
 *    tight the bound is (mean stored / sampled distance);
 *  - the built-ins tile seamlessly and are deterministic; thread counts do
 *    not change distance maps;
 *  - SPEC parsing and file inputs (PNG 8/16-bit, raw, .vdb) and their errors. */
#include "meso_clock.h"
#include "test_util.h"

#include <string.h>
#include <time.h>
#include <unistd.h>

#include "adapters.h"
#include "distance_map.h"
#include "png_io.h"
#include "texture_function.h"


static char tmpdir[256];

static const char* tmp_path(const char* name)
{
    static char buf[512];
    snprintf(buf, sizeof(buf), "%s/%s", tmpdir, name);
    return buf;
}

/* >>EDT --------------------------------------------------------------------- */

static void edt_case(const uint32_t dims[3], const int periodic[3], double density, uint64_t seed)
{
    const size_t n = (size_t)dims[0] * dims[1] * dims[2];
    uint8_t* mask = calloc(n, 1);
    double* sq = malloc(sizeof(double) * n);
    uint64_t rng = seed;
    for (size_t c = 0; c < n; ++c)
        mask[c] = test_rng_uniform(&rng, 0, 1) < density;
    const double sp[3] = {1.0 / dims[0], 0.7 / dims[1], 1.3 / dims[2]};
    meso_error err;
    assert(meso_distmap_edt(mask, dims, sp, periodic, sq, 2, &err) == MESO_OK);
    int any = 0;
    for (size_t c = 0; c < n; ++c)
        any |= mask[c];
    for (size_t c = 0; c < n; ++c) {
        const long p[3] = {(long)(c % dims[0]), (long)(c / dims[0] % dims[1]), (long)(c / ((size_t)dims[0] * dims[1]))};
        double best = INFINITY;
        for (size_t q = 0; q < n; ++q) {
            if (!mask[q])
                continue;
            const long r[3] = {(long)(q % dims[0]), (long)(q / dims[0] % dims[1]),
                               (long)(q / ((size_t)dims[0] * dims[1]))};
            double d2 = 0;
            for (int a = 0; a < 3; ++a) {
                long dl = labs(p[a] - r[a]);
                if (periodic[a] && (long)dims[a] - dl < dl)
                    dl = (long)dims[a] - dl;
                d2 += (sp[a] * (double)dl) * (sp[a] * (double)dl);
            }
            best = fmin(best, d2);
        }
        if (!any)
            assert(isinf(sq[c]));
        else
            assert(fabs(sq[c] - best) <= 1e-12);
    }
    free(mask);
    free(sq);
}

static void edt_matches_brute_force(void)
{
    const uint32_t d1[3] = {7, 5, 6}, d2[3] = {16, 3, 9}, d3[3] = {1, 11, 4};
    const int per[3] = {1, 1, 0}, none[3] = {0, 0, 0}, all[3] = {1, 1, 1};
    for (uint64_t seed = 1; seed <= 4; ++seed) {
        edt_case(d1, per, 0.05, seed);
        edt_case(d2, per, 0.02, seed + 10);
        edt_case(d3, none, 0.1, seed + 20);
        edt_case(d1, all, 0.03, seed + 30);
        edt_case(d2, none, 0.01, seed + 40);
    }
    edt_case(d1, per, 0.0, 99); /* empty: infinite everywhere */
    edt_case(d1, per, 1.0, 98); /* full: zero everywhere */
}

/* >>random functions ------------------------------------------------------------ */

static void random_height(uint32_t w, uint32_t h, uint64_t seed, meso_texfn* f)
{
    float* v = malloc(sizeof(float) * w * h);
    uint64_t rng = seed;
    /* Low ground with a few tall peaks, so upper cells have room. */
    for (size_t i = 0; i < (size_t)w * h; ++i)
        v[i] = (float)(test_rng_uniform(&rng, 0, 1) < 0.08 ? test_rng_uniform(&rng, 0.5, 0.9)
                                                         : test_rng_uniform(&rng, 0.0, 0.3));
    const uint32_t dims[3] = {w, h, 1};
    meso_error err;
    assert(meso_texfn_from_values(MESO_TEXFN_HEIGHT, dims, v, MESO_DTYPE_U8, f, &err) == MESO_OK);
    free(v);
}

static void random_density(const uint32_t dims[3], uint64_t seed, meso_texfn* f)
{
    const size_t n = (size_t)dims[0] * dims[1] * dims[2];
    float* v = malloc(sizeof(float) * n);
    uint64_t rng = seed;
    /* Mostly empty with some dense texels, so there are blobs and gaps. */
    for (size_t i = 0; i < n; ++i)
        v[i] = (float)(test_rng_uniform(&rng, 0, 1) < 0.15 ? test_rng_uniform(&rng, 0.5, 1.0)
                                                          : test_rng_uniform(&rng, 0.0, 0.45));
    meso_error err;
    assert(meso_texfn_from_values(MESO_TEXFN_DENSITY, dims, v, MESO_DTYPE_U16, f, &err) == MESO_OK);
    free(v);
}

/* >>cell maxima -------------------------------------------------------------- */

static void cell_max_bounds_samples(void)
{
    meso_texfn hf, df;
    random_height(16, 12, 7, &hf);
    const uint32_t dd[3] = {8, 8, 8};
    random_density(dd, 8, &df);
    const uint32_t res[3] = {5, 7, 6};
    float* hm = malloc(sizeof(float) * 5 * 7);
    float* dm = malloc(sizeof(float) * 5 * 7 * 6);
    meso_error err;
    assert(meso_distmap_cell_max(&hf, res, 1, hm, &err) == MESO_OK);
    assert(meso_distmap_cell_max(&df, res, 2, dm, &err) == MESO_OK);
    uint64_t rng = 5;
    double worst_gap_h = 0; /* how close sampling gets to the bound: it must reach it */
    for (int i = 0; i < 200000; ++i) {
        const double s = test_rng_uniform(&rng, 0, 1), t = test_rng_uniform(&rng, 0, 1), w = test_rng_uniform(&rng, 0, 1);
        const int ci = (int)(s * 5), cj = (int)(t * 7), ck = (int)(w * 6);
        const double h = meso_texfn_sample(&hf, s, t, 0), a = meso_texfn_sample(&df, s, t, w);
        assert(h <= hm[cj * 5 + ci] + 1e-9);
        assert(a <= dm[(ck * 7 + cj) * 5 + ci] + 1e-9);
        worst_gap_h = fmax(worst_gap_h, h - hm[cj * 5 + ci]);
    }
    /* Exactness: the max is attained (at a breakpoint), so dense sampling of
     * each footprint comes close to it. */
    for (int c = 0; c < 35; ++c) {
        const int ci = c % 5, cj = c / 5;
        double m = 0;
        for (int a = 0; a <= 64; ++a)
            for (int b = 0; b <= 64; ++b)
                m = fmax(m, meso_texfn_sample(&hf, (ci + a / 64.0) / 5, (cj + b / 64.0) / 7, 0));
        if (!(m <= hm[c] + 1e-9 && m >= hm[c] - 0.02))
            fprintf(stderr, "cell %d: sampled max %.6f, cell max %.6f\n", c, m, hm[c]);
        assert(m <= hm[c] + 1e-9 && m >= hm[c] - 0.02);
    }
    fprintf(stderr, "    cell maxima bound 200000 samples (closest %.2g below)\n", -worst_gap_h);
    free(hm);
    free(dm);
    meso_texfn_free(&hf);
    meso_texfn_free(&df);
}

/* >>conservative distance maps ---------------------------------------------------- */

typedef struct solid_samples {
    double* p; /* (s, t, w_lo, w_hi): a vertical solid segment per sample */
    size_t count;
} solid_samples;

/* Solid of a height field as vertical segments [0, h(s, t)] on a fine grid;
 * of a density as points (s, t, w) with alpha >= 1/2 on a fine grid. */
static solid_samples sample_solid(const meso_texfn* f, int per_texel)
{
    const uint32_t ns = f->dims[0] * (uint32_t)per_texel, nt = f->dims[1] * (uint32_t)per_texel;
    const uint32_t nw = f->kind == MESO_TEXFN_HEIGHT ? 1 : f->dims[2] * (uint32_t)per_texel + 1;
    solid_samples out = {malloc(sizeof(double) * 4 * (size_t)ns * nt * nw), 0};
    for (uint32_t k = 0; k < nw; ++k)
        for (uint32_t j = 0; j < nt; ++j)
            for (uint32_t i = 0; i < ns; ++i) {
                const double s = (double)i / ns, t = (double)j / nt, w = nw > 1 ? (double)k / (nw - 1) : 0;
                double* p = out.p + 4 * out.count;
                if (f->kind == MESO_TEXFN_HEIGHT) {
                    p[0] = s, p[1] = t, p[2] = 0, p[3] = meso_texfn_sample(f, s, t, 0);
                    ++out.count;
                } else if (meso_texfn_solid(f, s, t, w)) {
                    p[0] = s, p[1] = t, p[2] = w, p[3] = w;
                    ++out.count;
                }
            }
    return out;
}

/* Distance from x to [a, b] along an axis of period 1 (x, a, b in [0, 1]). */
static double gap_periodic(double x, double a, double b)
{
    const double d0 = x < a ? a - x : x > b ? x - b : 0.0;
    const double d1 = x + 1 - b, d2 = a - (x - 1); /* the copies to the right and left */
    return fmin(d0, fmin(d1 > 0 ? d1 : 0, d2 > 0 ? d2 : 0));
}

/* best[c] = min over solid samples of the distance from cell c's box to the
 * sample: no point of the cell is closer to the sampled solid. */
static double* sampled_distances(const uint32_t res[3], const solid_samples* ss)
{
    const size_t n = (size_t)res[0] * res[1] * res[2];
    double* best = malloc(sizeof(double) * n);
#ifdef _OPENMP
#pragma omp parallel for schedule(dynamic, 4)
#endif
    for (long cl = 0; cl < (long)n; ++cl) {
        const size_t c = (size_t)cl;
        const uint32_t i = (uint32_t)(c % res[0]), j = (uint32_t)(c / res[0] % res[1]),
                       k = (uint32_t)(c / ((size_t)res[0] * res[1]));
        const double s0 = (double)i / res[0], s1 = (double)(i + 1) / res[0];
        const double t0 = (double)j / res[1], t1 = (double)(j + 1) / res[1];
        const double w0 = (double)k / res[2], w1 = (double)(k + 1) / res[2];
        double b = INFINITY;
        for (size_t q = 0; q < ss->count; ++q) {
            const double* p = ss->p + 4 * q;
            /* Segment [p2, p3] vs [w0, w1]. */
            const double gw = p[3] < w0 ? w0 - p[3] : p[2] > w1 ? p[2] - w1 : 0.0;
            if (gw * gw >= b)
                continue;
            const double gs = gap_periodic(p[0], s0, s1), gt = gap_periodic(p[1], t0, t1);
            b = fmin(b, gs * gs + gt * gt + gw * gw);
        }
        best[c] = sqrt(b);
    }
    return best;
}

/* For every cell and store type: stored <= the sampled distance. Prints
 * the mean of stored / sampled over cells with a sampled distance in (0, 1)
 * and the share of zero cells. */
static void check_conservative(const char* what, const meso_texfn* f, const uint32_t res[3], const solid_samples* ss)
{
    double* best = sampled_distances(res, ss);
    const size_t n = (size_t)res[0] * res[1] * res[2];
    const uint16_t types[] = {MESO_DTYPE_U8, MESO_DTYPE_U16, MESO_DTYPE_F32};
    const char* names[] = {"u8", "u16", "f32"};
    for (int ty = 0; ty < 3; ++ty) {
        meso_distmap dm;
        meso_error err;
        assert(meso_distmap_build(f, res, types[ty], 2, &dm, &err) == MESO_OK);
        double ratio = 0;
        size_t rated = 0, zeros = 0;
        for (size_t c = 0; c < n; ++c) {
            const double stored = meso_distmap_stored(&dm, c);
            if (!(stored <= best[c] + 1e-9 && dm.dist[c] <= best[c] + 1e-9)) {
                fprintf(stderr, "%s: cell %zu: stored %.6f > sampled distance %.6f\n", what, c, stored, best[c]);
                assert(0);
            }
            zeros += stored == 0;
            if (best[c] > 0 && best[c] < 1) {
                ratio += stored / best[c];
                ++rated;
            }
        }
        fprintf(stderr, "    %s, dist %ux%ux%u %-3s: conservative; mean stored/sampled %.3f, %.0f%% of cells zero\n",
                what, res[0], res[1], res[2], names[ty], rated ? ratio / (double)rated : 1.0,
                100.0 * (double)zeros / (double)n);
        assert(zeros < n); /* not trivially zero */
        meso_distmap_free(&dm);
    }
    free(best);
}

static void height_map_is_conservative(void)
{
    meso_texfn f;
    random_height(16, 16, 42, &f);
    solid_samples ss = sample_solid(&f, 8);
    const uint32_t res[][3] = {{8, 8, 8}, {6, 10, 5}, {16, 16, 12}, {32, 32, 16}};
    for (size_t r = 0; r < sizeof(res) / sizeof(res[0]); ++r)
        check_conservative("height 16x16 random", &f, res[r], &ss);
    free(ss.p);
    meso_texfn_free(&f);
    /* A smooth one: the built-in cobble at 32 x 32. */
    meso_error err;
    assert(meso_texfn_from_spec("cobble:32", &f, &err) == MESO_OK);
    ss = sample_solid(&f, 4);
    const uint32_t res2[3] = {16, 16, 16};
    check_conservative("cobble:32", &f, res2, &ss);
    free(ss.p);
    meso_texfn_free(&f);
}

/* Three soft balls (texel centres sampled), so the solid is compact. */
static void balls_density(const uint32_t dims[3], meso_texfn* f)
{
    const double c[3][4] = {{0.3, 0.4, 0.5, 0.18}, {0.85, 0.8, 0.3, 0.12}, {0.6, 0.05, 0.75, 0.1}};
    const size_t n = (size_t)dims[0] * dims[1] * dims[2];
    float* v = malloc(sizeof(float) * n);
    for (size_t i = 0; i < n; ++i) {
        const double p[3] = {(i % dims[0] + 0.5) / dims[0], (i / dims[0] % dims[1] + 0.5) / dims[1],
                             (i / ((size_t)dims[0] * dims[1]) + 0.5) / dims[2]};
        double a = 0;
        for (int b = 0; b < 3; ++b) {
            double d2 = 0;
            for (int k = 0; k < 3; ++k) {
                double d = p[k] - c[b][k];
                if (k < 2)
                    d -= floor(d + 0.5); /* periodic in s, t */
                d2 += d * d;
            }
            a = fmax(a, 0.5 + 3.0 * (c[b][3] - sqrt(d2)));
        }
        v[i] = (float)(a < 0 ? 0 : a > 1 ? 1 : a);
    }
    meso_error err;
    assert(meso_texfn_from_values(MESO_TEXFN_DENSITY, dims, v, MESO_DTYPE_U8, f, &err) == MESO_OK);
    free(v);
}

static void density_map_is_conservative(void)
{
    const uint32_t dims[3] = {8, 8, 8};
    meso_texfn f;
    random_density(dims, 1234, &f);
    solid_samples ss = sample_solid(&f, 6);
    assert(ss.count > 0);
    const uint32_t res[3] = {8, 8, 8};
    check_conservative("density 8^3 random", &f, res, &ss);
    free(ss.p);
    meso_texfn_free(&f);

    const uint32_t bd[3] = {16, 16, 16};
    balls_density(bd, &f);
    ss = sample_solid(&f, 3);
    assert(ss.count > 0);
    const uint32_t bres[][3] = {{8, 8, 8}, {6, 5, 7}, {16, 16, 16}};
    for (size_t r = 0; r < sizeof(bres) / sizeof(bres[0]); ++r)
        check_conservative("density 16^3 balls", &f, bres[r], &ss);
    free(ss.p);
    meso_texfn_free(&f);
}

/* A function without solid: every cell is far (capped at 1, or 1e30 as f32). */
static void empty_density(void)
{
    const uint32_t dims[3] = {4, 4, 4};
    float v[64];
    for (int i = 0; i < 64; ++i)
        v[i] = 0.25f;
    meso_texfn f;
    meso_error err;
    assert(meso_texfn_from_values(MESO_TEXFN_DENSITY, dims, v, MESO_DTYPE_U8, &f, &err) == MESO_OK);
    meso_distmap dm;
    assert(meso_distmap_build(&f, dims, MESO_DTYPE_U8, 1, &dm, &err) == MESO_OK);
    assert(dm.solid_cells == 0 && meso_distmap_stored(&dm, 0) == 1.0);
    meso_distmap_free(&dm);
    assert(meso_distmap_build(&f, dims, MESO_DTYPE_F32, 1, &dm, &err) == MESO_OK);
    assert(meso_distmap_stored(&dm, 5) >= 1e29);
    meso_distmap_free(&dm);
    meso_texfn_free(&f);
}

/* >>built-ins ---------------------------------------------------------------- */

static void builtins_tile_and_repeat(void)
{
    const char* specs[] = {"bricks:64", "cobble:64", "ribs:64", "weave:32", "cells:16", "bricks", "weave"};
    for (size_t k = 0; k < sizeof(specs) / sizeof(specs[0]); ++k) {
        meso_texfn a, b;
        meso_error err;
        assert(meso_texfn_from_spec(specs[k], &a, &err) == MESO_OK);
        assert(meso_texfn_from_spec(specs[k], &b, &err) == MESO_OK);
        assert(a.encoded_size == b.encoded_size && !memcmp(a.encoded, b.encoded, a.encoded_size));
        const uint32_t W = a.dims[0], H = a.dims[1], D = a.dims[2];
        /* Filtered values repeat with period 1 in s and t. */
        uint64_t rng = 77;
        for (int i = 0; i < 2000; ++i) {
            const double s = test_rng_uniform(&rng, 0, 1), t = test_rng_uniform(&rng, 0, 1), w = test_rng_uniform(&rng, 0, 1);
            const double v = meso_texfn_sample(&a, s, t, w);
            assert(fabs(meso_texfn_sample(&a, s + 1, t, w) - v) < 1e-6);
            assert(fabs(meso_texfn_sample(&a, s, t - 1, w) - v) < 1e-6);
            assert(fabs(meso_texfn_sample(&a, s - 3, t + 2, w) - v) < 1e-6);
        }
        /* Seamless: the continuous function repeats with period 1 in s and
         * t (value at s = 0 equals s = 1), so the tile's texels sample one
         * period of it. */
        char name[16];
        snprintf(name, sizeof(name), "%.*s", (int)strcspn(specs[k], ":"), specs[k]);
        double worst = 0;
        for (int i = 0; i < 4000; ++i) {
            const double s = test_rng_uniform(&rng, 0, 1), t = test_rng_uniform(&rng, 0, 1), w = test_rng_uniform(&rng, 0, 1);
            const double v = meso_texfn_builtin_value(name, s, t, w);
            worst = fmax(worst, fabs(meso_texfn_builtin_value(name, s + 1, t, w) - v));
            worst = fmax(worst, fabs(meso_texfn_builtin_value(name, s, t + 1, w) - v));
            worst = fmax(worst, fabs(meso_texfn_builtin_value(name, s - 1, t - 2, w) - v));
            worst = fmax(worst, fabs(meso_texfn_builtin_value(name, 0, t, w) - meso_texfn_builtin_value(name, 1, t, w)));
            worst = fmax(worst, fabs(meso_texfn_builtin_value(name, s, 0, w) - meso_texfn_builtin_value(name, s, 1, w)));
        }
        fprintf(stderr, "    %-9s %ux%ux%u: deterministic; |f(s + 1) - f(s)| <= %.2g over 4000 random points\n",
                specs[k], W, H, D, worst);
        assert(worst < 1e-9);
        /* Not flat, and the solid is neither empty nor everything. */
        meso_distmap d1, d2;
        uint32_t res[3];
        meso_distmap_default_res(&a, res);
        assert(meso_distmap_build(&a, res, MESO_DTYPE_U8, 1, &d1, &err) == MESO_OK);
        assert(meso_distmap_build(&a, res, MESO_DTYPE_U8, 2, &d2, &err) == MESO_OK);
        assert(!memcmp(d1.encoded, d2.encoded, d1.encoded_size)); /* thread count does not matter */
        const uint64_t cells = (uint64_t)res[0] * res[1] * res[2];
        assert(d1.solid_cells > 0 && d1.solid_cells < cells);
        meso_distmap_free(&d1);
        meso_distmap_free(&d2);
        meso_texfn_free(&a);
        meso_texfn_free(&b);
    }
}

/* The weave has real overhangs: some (s, t) column is solid, then empty,
 * then solid again going up in w (a height field can not do that). */
static void weave_overhangs(void)
{
    meso_texfn f;
    meso_error err;
    assert(meso_texfn_from_spec("weave:64", &f, &err) == MESO_OK);
    assert(f.kind == MESO_TEXFN_DENSITY && f.dims[2] == 32);
    int overhangs = 0;
    for (int j = 0; j < 64; ++j)
        for (int i = 0; i < 64; ++i) {
            int runs = 0, prev = 0;
            for (int k = 0; k <= 200; ++k) {
                const int sol = meso_texfn_solid(&f, (i + 0.5) / 64, (j + 0.5) / 64, k / 200.0);
                runs += sol && !prev;
                prev = sol;
            }
            overhangs += runs >= 2;
        }
    fprintf(stderr, "    weave: %d of 4096 columns have two or more solid runs\n", overhangs);
    assert(overhangs > 100);
    meso_texfn_free(&f);
}

static void default_resolutions(void)
{
    meso_texfn f;
    meso_error err;
    uint32_t res[3];
    assert(meso_texfn_from_spec("weave", &f, &err) == MESO_OK);
    meso_distmap_default_res(&f, res);
    assert(res[0] == 64 && res[1] == 64 && res[2] == 32);
    meso_texfn_free(&f);
    assert(meso_texfn_from_spec("bricks", &f, &err) == MESO_OK);
    meso_distmap_default_res(&f, res);
    assert(res[0] == 128 && res[1] == 128 && res[2] >= 8 && res[2] <= 128 && res[2] % 8 == 0);
    const double t0 = meso_seconds();
    meso_distmap dm;
    assert(meso_distmap_build(&f, res, MESO_DTYPE_U8, 0, &dm, &err) == MESO_OK);
    fprintf(stderr, "    bricks 256^2: default dist-res %ux%ux%u, built in %.0f ms\n", res[0], res[1], res[2],
            1e3 * (meso_seconds() - t0));
    meso_distmap_free(&dm);
    meso_texfn_free(&f);
    const float flat[64] = {0};
    const uint32_t dims[3] = {8, 8, 1};
    assert(meso_texfn_from_values(MESO_TEXFN_HEIGHT, dims, flat, MESO_DTYPE_U8, &f, &err) == MESO_OK);
    meso_distmap_default_res(&f, res);
    assert(res[0] == 8 && res[1] == 8 && res[2] == 8);
    meso_texfn_free(&f);
}

/* >>files and specs ------------------------------------------------------------ */

static void png_heights(void)
{
    enum { W = 5, H = 3 };
    uint16_t px[W * H];
    for (int i = 0; i < W * H; ++i)
        px[i] = (uint16_t)(i * 4000 + 7);
    char why[256];
    const char* p16 = tmp_path("h16.png");
    assert(meso_png_write_gray(p16, px, W, H, 16, why, sizeof(why)) == 0);
    char spec[600];
    snprintf(spec, sizeof(spec), "height:%s", p16);
    meso_texfn f;
    meso_error err;
    assert(meso_texfn_from_spec(spec, &f, &err) == MESO_OK);
    assert(f.kind == MESO_TEXFN_HEIGHT && f.dtype == MESO_DTYPE_U16 && f.dims[0] == W && f.dims[1] == H);
    /* Bottom image row is t = 0. */
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            assert(f.values[y * W + x] == (float)(px[(H - 1 - y) * W + x] / 65535.0));
    meso_texfn_free(&f);

    for (int i = 0; i < W * H; ++i)
        px[i] = (uint16_t)(i * 17);
    const char* p8 = tmp_path("h8.png");
    assert(meso_png_write_gray(p8, px, W, H, 8, why, sizeof(why)) == 0);
    snprintf(spec, sizeof(spec), "height:%s", p8);
    assert(meso_texfn_from_spec(spec, &f, &err) == MESO_OK);
    assert(f.dtype == MESO_DTYPE_U8 && f.values[0] == (float)(px[(H - 1) * W] / 255.0));
    meso_texfn_free(&f);

    /* RGBA: the first channel, no gamma. */
    uint8_t rgba[4 * W * H];
    for (int i = 0; i < W * H; ++i) {
        rgba[4 * i] = (uint8_t)(i * 13);
        rgba[4 * i + 1] = 200;
        rgba[4 * i + 2] = 10;
        rgba[4 * i + 3] = 255;
    }
    const char* prgb = tmp_path("rgba.png");
    assert(meso_png_write_rgba8(prgb, rgba, W, H, 0, why, sizeof(why)) == 0);
    snprintf(spec, sizeof(spec), "height:%s", prgb);
    assert(meso_texfn_from_spec(spec, &f, &err) == MESO_OK);
    assert(f.values[W + 2] == (float)(rgba[4 * (W + 2)] / 255.0));
    meso_texfn_free(&f);
}

static void expect_error(const char* spec, meso_result r, uint32_t code)
{
    meso_texfn f;
    meso_error err;
    memset(&err, 0, sizeof(err));
    const meso_result got = meso_texfn_from_spec(spec, &f, &err);
    if (got != r || err.code != code) {
        fprintf(stderr, "spec '%s': got %d E%u (%s), expected %d E%u\n", spec, got, err.code, err.message, r, code);
        assert(0);
    }
    assert(f.values == NULL && f.encoded == NULL && err.message[0]);
}

static void raw_volumes_and_errors(void)
{
    const char* raw = tmp_path("v.raw");
    FILE* fp = fopen(raw, "wb");
    uint8_t v[4 * 3 * 2];
    for (int i = 0; i < 24; ++i)
        v[i] = (uint8_t)(i * 10);
    assert(fp && fwrite(v, 1, 24, fp) == 24 && fclose(fp) == 0);
    char spec[600];
    snprintf(spec, sizeof(spec), "volume:%s:4x3x2", raw);
    meso_texfn f;
    meso_error err;
    assert(meso_texfn_from_spec(spec, &f, &err) == MESO_OK);
    assert(f.kind == MESO_TEXFN_DENSITY && f.dims[0] == 4 && f.dims[1] == 3 && f.dims[2] == 2);
    assert(f.values[23] == (float)(230 / 255.0) && ((uint8_t*)f.encoded)[5] == 50);
    meso_texfn_free(&f);

    snprintf(spec, sizeof(spec), "volume:%s:4x3x3", raw);
    expect_error(spec, MESO_ERR_CORRUPT, MESO_TEXFN_ISSUE_CONTENT); /* too short */
    snprintf(spec, sizeof(spec), "volume:%s:4x3x1", raw);
    expect_error(spec, MESO_ERR_CORRUPT, MESO_TEXFN_ISSUE_CONTENT); /* too long */
    snprintf(spec, sizeof(spec), "volume:%s", raw);
    expect_error(spec, MESO_ERR_INVALID_ARG, MESO_TEXFN_ISSUE_SPEC); /* no size */
    snprintf(spec, sizeof(spec), "volume:%s:4x3", raw);
    expect_error(spec, MESO_ERR_INVALID_ARG, MESO_TEXFN_ISSUE_SPEC);
    expect_error("volume:/nonexistent/v.raw:2x2x2", MESO_ERR_IO, MESO_TEXFN_ISSUE_FILE);
    expect_error("height:/nonexistent/h.png", MESO_ERR_IO, MESO_TEXFN_ISSUE_FILE);
    snprintf(spec, sizeof(spec), "height:%s", raw);
    expect_error(spec, MESO_ERR_CORRUPT, MESO_TEXFN_ISSUE_CONTENT); /* not a PNG */
    expect_error("height", MESO_ERR_INVALID_ARG, MESO_TEXFN_ISSUE_SPEC);
    expect_error("marble", MESO_ERR_INVALID_ARG, MESO_TEXFN_ISSUE_SPEC);
    expect_error("bricks:7", MESO_ERR_INVALID_ARG, MESO_TEXFN_ISSUE_SPEC);
    expect_error("bricks:64x", MESO_ERR_INVALID_ARG, MESO_TEXFN_ISSUE_SPEC);
    expect_error("weave:33", MESO_ERR_INVALID_ARG, MESO_TEXFN_ISSUE_SPEC);
    expect_error("cells:", MESO_ERR_INVALID_ARG, MESO_TEXFN_ISSUE_SPEC);
    expect_error("", MESO_ERR_INVALID_ARG, MESO_TEXFN_ISSUE_SPEC);
}

static void vdb_volumes(void)
{
#if MESO_HAVE_OPENVDB
    const double c[3] = {0.5, 0.5, 0.5};
    meso_error err;
    char ls_path[512], fog_path[512], spec[600];
    snprintf(ls_path, sizeof(ls_path), "%s", tmp_path("ls.vdb"));
    snprintf(fog_path, sizeof(fog_path), "%s", tmp_path("fog.vdb"));
    assert(meso_vdb_write_sphere(ls_path, "sphere", c, 0.4, 0.02, 0, &err) == MESO_OK);
    assert(meso_vdb_write_sphere(fog_path, "density", c, 0.4, 0.02, 1, &err) == MESO_OK);
    for (int k = 0; k < 3; ++k) {
        if (k == 0)
            snprintf(spec, sizeof(spec), "volume:%s", ls_path);
        else if (k == 1)
            snprintf(spec, sizeof(spec), "volume:%s:sphere", ls_path);
        else
            snprintf(spec, sizeof(spec), "volume:%s:density", fog_path);
        meso_texfn f;
        assert(meso_texfn_from_spec(spec, &f, &err) == MESO_OK);
        assert(f.kind == MESO_TEXFN_DENSITY && f.dims[0] >= 38 && f.dims[0] == f.dims[1] && f.dims[1] == f.dims[2]);
        /* The box spans the sphere (plus the narrow band for the level set):
         * its centre is solid, its corners are not, and the solid's extent
         * along s through the centre matches the radius. */
        assert(meso_texfn_solid(&f, 0.5, 0.5, 0.5));
        assert(!meso_texfn_solid(&f, 0.01, 0.01, 0.01) && !meso_texfn_solid(&f, 0.99, 0.99, 0.99));
        int solid = 0;
        for (int i = 0; i < 1000; ++i)
            solid += meso_texfn_solid(&f, (i + 0.5) / 1000, 0.5, 0.5);
        /* Box width in world units: the active box (sphere + band). */
        const double box = f.dims[0] * 0.02;
        const double diameter = solid / 1000.0 * box;
        /* Level set: solid where phi <= 0, diameter 0.8. Fog (OpenVDB's
         * sdfToFogVolume ramps 0 at phi = 0 to 1 at phi = -3 voxels): alpha
         * = 1/2 at phi = -1.5 voxels, diameter 0.8 - 2 * 0.03 = 0.74. */
        const double expected = k == 2 ? 0.74 : 0.8;
        fprintf(stderr, "    %s: %ux%ux%u, solid diameter %.3f (expected %.2f)\n", k == 2 ? "fog" : "level set",
                f.dims[0], f.dims[1], f.dims[2], diameter, expected);
        assert(fabs(diameter - expected) < 0.02);
        meso_texfn_free(&f);
    }
    snprintf(spec, sizeof(spec), "volume:%s:nope", ls_path);
    expect_error(spec, MESO_ERR_CORRUPT, MESO_TEXFN_ISSUE_VDB);
    expect_error("volume:/nonexistent/x.vdb", MESO_ERR_IO, MESO_TEXFN_ISSUE_FILE);
    snprintf(spec, sizeof(spec), "volume:%s", tmp_path("h8.png"));
    expect_error(spec, MESO_ERR_INVALID_ARG, MESO_TEXFN_ISSUE_SPEC); /* neither .vdb nor .raw with a size */
    snprintf(spec, sizeof(spec), "%s", tmp_path("garbage.vdb"));
    FILE* fp = fopen(spec, "wb");
    assert(fp && fputs("not a vdb", fp) >= 0 && fclose(fp) == 0);
    char spec2[700];
    snprintf(spec2, sizeof(spec2), "volume:%s", spec);
    meso_texfn f;
    assert(meso_texfn_from_spec(spec2, &f, &err) != MESO_OK && err.code >= 3120 && err.code <= 3123);
#else
    fprintf(stderr, "    (built without OpenVDB: .vdb input not tested)\n");
#endif
}

int main(void)
{
    snprintf(tmpdir, sizeof(tmpdir), "/tmp/meso_texture_XXXXXX");
    assert(mkdtemp(tmpdir));
    TEST_RUN(edt_matches_brute_force);
    TEST_RUN(cell_max_bounds_samples);
    TEST_RUN(height_map_is_conservative);
    TEST_RUN(density_map_is_conservative);
    TEST_RUN(empty_density);
    TEST_RUN(builtins_tile_and_repeat);
    TEST_RUN(weave_overhangs);
    TEST_RUN(default_resolutions);
    TEST_RUN(png_heights);
    TEST_RUN(raw_volumes_and_errors);
    TEST_RUN(vdb_volumes);
    char cmd[400];
    snprintf(cmd, sizeof(cmd), "rm -rf '%s'", tmpdir);
    assert(system(cmd) == 0);
    fprintf(stderr, "texture/distance_map: all passed\n");
    return 0;
}
