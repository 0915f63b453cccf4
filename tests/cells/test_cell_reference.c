/* The exact CPU reference for cell-based objects
 * (runtime/reference/cell_reference.c) against independent expectations:
 *  - traversal: random hand-built objects (random TILE maps with empty
 *    voxels, random tile classes and tags), thousands of random rays; the
 *    search for solid equals the nearest entry into a SOLID voxel cube by a
 *    slab test over every cube (solidity from the dense tags, not MEMB),
 *    the search for empty the first entry into the complement (beyond the
 *    grid included); the tie rule on exact diagonals; the MEMB words the
 *    helper writes decode to the dense tags;
 *  - tile skipping on = off (every search, and rendered images), with the
 *    work it saves;
 *  - a box through meso_ref_cells_render with a perspective camera: hit
 *    point, depth, normal and colour against the closed-form ray-box hit;
 *  - reflection off a floor onto a wall: the bounce point in closed form,
 *    the colour sum for B = 0, 1, 2;
 *  - refraction through a slab (Snell's lateral shift, final direction)
 *    and total internal reflection inside a box; the colour formula;
 *  - the normal and direction fallbacks;
 *  - a baked object (bake library) written, loaded: tags = meso_membership_get,
 *    normals = meso_octa_decode, colours and TILE equal; corrupted copies
 *    refused with MESO_ERR_CORRUPT naming the chunk;
 *  - threads 1 = 2, byte for byte.
 * One program of ~1,190 lines on purpose: the eight parts share the
 * hand-built objects and the brute-force slab test of >>helpers, and each
 * part is a numbered section that can be read alone. */
#include "test_util.h"

#include <math.h>
#include <string.h>

#include "adapters.h"
#include "camera.h"
#include "cell_reference.h"
#include "cells_chunks.h"
#include "meso_layout.h"
#include "ref_common.h"

/* >>helpers ---------------------------------------------------------------- */

typedef struct obj {
    meso_ref_cells c;
    uint8_t* dense; /* T x S tags as given */
} obj;

static void obj_alloc(obj* b, uint32_t T0, uint32_t T1, uint32_t T2, uint32_t R, uint32_t S, double h,
                      const double origin[3])
{
    memset(b, 0, sizeof *b);
    meso_ref_cells* c = &b->c;
    c->tiles[0] = T0;
    c->tiles[1] = T1;
    c->tiles[2] = T2;
    c->res = R;
    c->split_count = S;
    c->cell_count = S;
    c->voxel = h;
    for (int k = 0; k < 3; ++k)
        c->origin[k] = origin[k];
    const size_t n = (size_t)R * R * R, T = (size_t)T0 * T1 * T2;
    c->tile = calloc(n, sizeof *c->tile);
    c->normal = calloc(3 * n, sizeof *c->normal);
    c->colour = calloc(4 * n, 1);
    b->dense = calloc(T * S, 1);
    assert(c->tile && c->normal && c->colour && b->dense);
    for (size_t v = 0; v < n; ++v) {
        c->normal[3 * v + 1] = 1; /* +y unless set */
        c->colour[4 * v] = 200;
        c->colour[4 * v + 1] = 120;
        c->colour[4 * v + 2] = 40;
        c->colour[4 * v + 3] = 255;
    }
}

static void obj_finish(obj* b)
{
    assert(meso_ref_cells_set_tags(&b->c, b->dense) == MESO_OK);
}

static void obj_free(obj* b)
{
    meso_ref_cells_free(&b->c);
    free(b->dense);
}

/* One tile, S = R^3: tile-map voxel v has split id v + 1, so every voxel
 * of the object is set on its own (dense tag = 1: SOLID). */
static void one_tile(obj* b, uint32_t R, double h, const double origin[3])
{
    obj_alloc(b, 1, 1, 1, R, R * R * R, h, origin);
    for (uint32_t v = 0; v < R * R * R; ++v)
        b->c.tile[v] = v + 1;
}

static size_t vidx(const meso_ref_cells* c, int64_t i, int64_t j, int64_t k)
{
    const int64_t R = c->res;
    return (size_t)(i % R + R * (j % R + R * (k % R)));
}

static void set_solid(obj* b, int64_t i, int64_t j, int64_t k, int on)
{
    b->dense[vidx(&b->c, i, j, k)] = on ? 1 : 0;
}

static void set_normal(obj* b, int64_t i, int64_t j, int64_t k, double x, double y, double z)
{
    const double l = sqrt(x * x + y * y + z * z);
    float* n = &b->c.normal[3 * vidx(&b->c, i, j, k)];
    n[0] = (float)(x / l);
    n[1] = (float)(y / l);
    n[2] = (float)(z / l);
}

/* SOLID from the dense tags (not from MEMB). */
static int solid_dense(const obj* b, int64_t i, int64_t j, int64_t k)
{
    const meso_ref_cells* c = &b->c;
    const int64_t R = c->res;
    if (i < 0 || j < 0 || k < 0 || i >= R * c->tiles[0] || j >= R * c->tiles[1] || k >= R * c->tiles[2])
        return 0;
    const uint32_t s = c->tile[vidx(c, i, j, k)];
    const uint64_t t =
        (uint64_t)(i / R) + c->tiles[0] * ((uint64_t)(j / R) + (uint64_t)c->tiles[1] * (uint64_t)(k / R));
    return s != 0 && b->dense[t * c->split_count + s - 1] == 1;
}

/* Ray o + s u against the box [lo, hi]: entry and exit (s may be < 0). */
static int slab(const double lo[3], const double hi[3], const double o[3], const double u[3], double* s0, double* s1,
                int* axis_in)
{
    double a = -HUGE_VAL, b = HUGE_VAL;
    int ax = -1;
    for (int k = 0; k < 3; ++k) {
        if (u[k] == 0) {
            if (o[k] < lo[k] || o[k] > hi[k])
                return 0;
            continue;
        }
        double t0 = (lo[k] - o[k]) / u[k], t1 = (hi[k] - o[k]) / u[k];
        if (t0 > t1) {
            const double t = t0;
            t0 = t1;
            t1 = t;
        }
        if (t0 > a) {
            a = t0;
            ax = k;
        }
        b = fmin(b, t1);
    }
    *s0 = a;
    *s1 = b;
    if (axis_in)
        *axis_in = ax;
    return a <= b;
}

static void cube(const meso_ref_cells* c, int64_t i, int64_t j, int64_t k, double lo[3], double hi[3])
{
    const int64_t v[3] = {i, j, k};
    for (int a = 0; a < 3; ++a) {
        lo[a] = c->origin[a] + (double)v[a] * c->voxel;
        hi[a] = c->origin[a] + (double)(v[a] + 1) * c->voxel;
    }
}

static void random_unit(uint64_t* st, double u[3])
{
    double l;
    do {
        for (int k = 0; k < 3; ++k)
            u[k] = test_rng_uniform(st, -1, 1);
        l = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    } while (l < 0.1 || l > 1);
    for (int k = 0; k < 3; ++k)
        u[k] /= l;
}

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static double srgb(double x)
{
    return x <= 0.04045 ? x / 12.92 : pow((x + 0.055) / 1.055, 2.4);
}

/* The header's environment, written again here. */
static void env(const double u[3], double rgb[3])
{
    const double c = u[1] > 0 ? u[1] : 0, g = u[1] < 0 ? -u[1] : 0;
    const double sky[3] = {0.95 * (1 - c) + 0.30 * c, 0.92 * (1 - c) + 0.50 * c, 0.85 * (1 - c) + 0.90 * c};
    const double stripes = 0.12 * sin(12 * atan2(u[2], u[0])) * sin(12 * asin(g));
    const double ground[3] = {0.42 + stripes, 0.36 + stripes, 0.30 + stripes};
    const double m = 8 * g < 1 ? 8 * g : 1;
    for (int k = 0; k < 3; ++k)
        rgb[k] = u[1] >= 0 ? sky[k] : sky[k] * (1 - m) + ground[k] * m;
}

/* COLR (200, 120, 40) shaded with normal n under light l. */
static void shade_expect(const double n[3], const double l[3], double rgb[3])
{
    const double k = 0.15 + 0.85 * fmax(0.0, dot(n, l));
    const double col[3] = {200, 120, 40};
    for (int i = 0; i < 3; ++i)
        rgb[i] = srgb(col[i] / 255.0) * k;
}

static const double LIGHT[3] = {0.3 / 0.9899494936611665, 0.8 / 0.9899494936611665, 0.5 / 0.9899494936611665};

static void voxel_of(const meso_ref_cells* c, const double p[3], int64_t v[3])
{
    for (int k = 0; k < 3; ++k)
        v[k] = (int64_t)floor((p[k] - c->origin[k]) / c->voxel);
}

/* >>1, 2: traversal against brute force; skipping on = off ----------------- */

static void random_object(obj* b, uint64_t* st, int full)
{
    const uint32_t R = 1 + (uint32_t)(test_rng_next(st) % 5);
    const uint32_t T0 = 1 + (uint32_t)(test_rng_next(st) % 4), T1 = 1 + (uint32_t)(test_rng_next(st) % 4),
                   T2 = 1 + (uint32_t)(test_rng_next(st) % 4);
    const uint32_t S = 1 + (uint32_t)(test_rng_next(st) % 7);
    const double origin[3] = {test_rng_uniform(st, -2, 0), test_rng_uniform(st, -2, 0), test_rng_uniform(st, -2, 0)};
    obj_alloc(b, T0, T1, T2, R, S, test_rng_uniform(st, 0.1, 0.7), origin);
    for (uint32_t v = 0; v < R * R * R; ++v)
        b->c.tile[v] = full ? 1 + (uint32_t)(test_rng_next(st) % S) : (uint32_t)(test_rng_next(st) % (S + 1));
    const uint64_t T = (uint64_t)T0 * T1 * T2;
    for (uint64_t t = 0; t < T; ++t) {
        const unsigned cls = (unsigned)(test_rng_next(st) % 3);
        for (uint32_t s = 0; s < S; ++s)
            b->dense[t * S + s] = cls == 0 ? 0 : cls == 1 ? 1 : (uint8_t)(test_rng_next(st) % 3);
    }
    obj_finish(b);
}

typedef struct res {
    int found, axis;
    double s;
    int64_t v[3], last[3];
} res;

static res run_search(const meso_ref_cells* c, const double o[3], const double u[3], double s_max, int want_solid,
                      uint64_t* steps)
{
    res r;
    memset(&r, 0, sizeof r);
    int64_t start[3];
    voxel_of(c, o, start);
    r.found = meso_ref_cells_search(c, o, u, start, s_max, want_solid, &r.s, r.v, r.last, &r.axis, steps);
    return r;
}

typedef struct ray_stats {
    long searches[2], found[2], none[2], zero[2], beyond;
    double worst;
    uint64_t steps_on[2], steps_off[2];
} ray_stats;

/* `rays` random rays against object c, whose SOLID voxels are given
 * independently by `solid` (N0 x N1 x N2 bytes, x fastest): each ray
 * searched for solid (from anywhere around the grid) and for empty (mostly
 * from inside a SOLID voxel), with skipping on and off, against the nearest
 * entry into a cube of the wanted kind (slab test, positive length inside;
 * for empty also the grid box's exit). */
static void check_rays(const meso_ref_cells* c, const uint8_t* solid, uint64_t* st, int rays, ray_stats* rs)
{
    const int64_t N[3] = {(int64_t)c->tiles[0] * c->res, (int64_t)c->tiles[1] * c->res, (int64_t)c->tiles[2] * c->res};
#define SOLID_AT(i, j, k)                                                                                          \
    ((i) >= 0 && (j) >= 0 && (k) >= 0 && (i) < N[0] && (j) < N[1] && (k) < N[2] &&                               \
     solid[(size_t)((i) + N[0] * ((j) + N[1] * (k)))])
    double glo[3], ghi[3];
    for (int a = 0; a < 3; ++a) {
        glo[a] = c->origin[a];
        ghi[a] = c->origin[a] + (double)N[a] * c->voxel;
    }
    for (int ray = 0; ray < rays; ++ray) {
        for (int want = 0; want < 2; ++want) {
            double o[3], u[3];
            int placed = 0;
            for (int tries = 0; !want && ray % 4 != 0 && tries < 200 && !placed; ++tries) {
                int64_t v[3];
                for (int a = 0; a < 3; ++a)
                    v[a] = (int64_t)(test_rng_next(st) % (uint64_t)N[a]);
                if (!SOLID_AT(v[0], v[1], v[2]))
                    continue;
                for (int a = 0; a < 3; ++a)
                    o[a] = c->origin[a] + ((double)v[a] + test_rng_uniform(st, 0.01, 0.99)) * c->voxel;
                placed = 1;
            }
            for (int a = 0; a < 3 && !placed; ++a) {
                const double ext = ghi[a] - glo[a];
                o[a] = test_rng_uniform(st, glo[a] - 0.3 * ext, ghi[a] + 0.3 * ext);
            }
            if (want && ray % 2 == 0) { /* aimed at a random point of the grid box */
                double l = 0;
                for (int a = 0; a < 3; ++a) {
                    u[a] = test_rng_uniform(st, glo[a], ghi[a]) - o[a];
                    l += u[a] * u[a];
                }
                l = sqrt(l);
                for (int a = 0; a < 3; ++a)
                    u[a] /= l;
            } else
                random_unit(st, u);
            const double s_max = ray % 5 == 4 ? test_rng_uniform(st, 0, (ghi[0] - glo[0]) * 1.5) : HUGE_VAL;
            /* brute force */
            double best = HUGE_VAL;
            int64_t bv[3] = {0, 0, 0};
            int bax = -1;
            int64_t o_v[3];
            voxel_of(c, o, o_v);
            if (SOLID_AT(o_v[0], o_v[1], o_v[2]) == want) {
                best = 0;
                memcpy(bv, o_v, sizeof bv);
            } else {
                for (int64_t k = 0; k < N[2]; ++k)
                    for (int64_t j = 0; j < N[1]; ++j)
                        for (int64_t i = 0; i < N[0]; ++i) {
                            if (solid[(size_t)(i + N[0] * (j + N[1] * k))] != want)
                                continue;
                            double lo[3], hi[3], s0, s1;
                            int ax;
                            cube(c, i, j, k, lo, hi);
                            if (!slab(lo, hi, o, u, &s0, &s1, &ax) || !(s1 > s0 + 1e-12) || s1 <= 0 || !(s0 < best))
                                continue;
                            best = s0;
                            bv[0] = i;
                            bv[1] = j;
                            bv[2] = k;
                            bax = ax;
                        }
                double s0, s1;
                if (!want && slab(glo, ghi, o, u, &s0, &s1, NULL) && s1 > 0 && s1 < best) {
                    best = s1; /* beyond the grid is empty */
                    bax = -2;
                }
            }
            const int bfound = best < HUGE_VAL && best <= s_max;
            meso_ref_cells_skipping = 0;
            const res off = run_search(c, o, u, s_max, want, &rs->steps_off[want]);
            meso_ref_cells_skipping = 1;
            const res on = run_search(c, o, u, s_max, want, &rs->steps_on[want]);
            /* 2: skipping changes nothing, bit for bit */
            assert(on.found == off.found);
            if (on.found) {
                assert(on.s == off.s && on.axis == off.axis);
                assert(!memcmp(on.v, off.v, sizeof on.v) && !memcmp(on.last, off.last, sizeof on.last));
            }
            rs->searches[want]++;
            if (bfound != on.found) {
                fprintf(stderr, "want %d: brute %d (s %.17g) search %d (s %.17g) s_max %g\n", want, bfound, best,
                        on.found, on.s, s_max);
                assert(0);
            }
            if (!on.found) {
                rs->none[want]++;
                continue;
            }
            const double err = fabs(on.s - best);
            rs->worst = fmax(rs->worst, err);
            assert(err < 1e-9);
            if (best == 0) {
                rs->zero[want]++;
                assert(on.axis == -1 && on.s == 0);
                continue;
            }
            rs->found[want]++;
            if (bax >= 0) {
                assert(!memcmp(on.v, bv, sizeof bv) && on.axis == bax);
                assert(SOLID_AT(on.v[0], on.v[1], on.v[2]) == want);
            } else { /* ended beyond the grid */
                rs->beyond++;
                assert(on.v[0] < 0 || on.v[1] < 0 || on.v[2] < 0 || on.v[0] >= N[0] || on.v[1] >= N[1] ||
                       on.v[2] >= N[2]);
            }
            /* last: the voxel before, one step back along the axis; for empty the last SOLID voxel */
            for (int a = 0; a < 3; ++a)
                assert(on.last[a] == on.v[a] - (a == on.axis ? (u[a] > 0 ? 1 : -1) : 0));
            if (!want)
                assert(SOLID_AT(on.last[0], on.last[1], on.last[2]));
        }
    }
#undef SOLID_AT
}

static void print_stats(const char* what, const ray_stats* rs)
{
    printf("%s: %ld searches for solid (%ld hits, %ld none, %ld starting in SOLID), %ld for empty (%ld ends, %ld of "
           "them beyond the grid, %ld none, %ld starting empty): |s - brute force| <= %.3g, same voxel, face and "
           "previous voxel; skipping on = off bit for bit, voxel + tile steps with / without skipping: solid %llu / "
           "%llu, empty %llu / %llu\n",
           what, rs->searches[1], rs->found[1], rs->none[1], rs->zero[1], rs->searches[0], rs->found[0], rs->beyond,
           rs->none[0], rs->zero[0], rs->worst, (unsigned long long)rs->steps_on[1],
           (unsigned long long)rs->steps_off[1], (unsigned long long)rs->steps_on[0],
           (unsigned long long)rs->steps_off[0]);
}

static void traversal_matches_brute_force(void)
{
    uint64_t st = 0x5eedULL;
    ray_stats rs;
    memset(&rs, 0, sizeof rs);
    long ties = 0;
    for (int ob = 0; ob < 30; ++ob) {
        obj b;
        random_object(&b, &st, ob % 3 == 2);
        const meso_ref_cells* c = &b.c;
        /* the helper's MEMB words decode to the dense tags */
        const uint64_t T = (uint64_t)c->tiles[0] * c->tiles[1] * c->tiles[2];
        for (uint64_t t = 0; t < T; ++t) {
            int all_out = 1, all_in = 1;
            for (uint32_t s = 1; s <= c->split_count; ++s) {
                assert(meso_ref_cells_tag(c, t, s) == b.dense[t * c->split_count + s - 1]);
                all_out &= b.dense[t * c->split_count + s - 1] == 0;
                all_in &= b.dense[t * c->split_count + s - 1] == 1;
            }
            assert(meso_ref_cells_class(c, t) == (all_out ? 0u : all_in ? 1u : 2u));
        }
        const int64_t N[3] = {(int64_t)c->tiles[0] * c->res, (int64_t)c->tiles[1] * c->res,
                              (int64_t)c->tiles[2] * c->res};
        uint8_t* solid = malloc((size_t)(N[0] * N[1] * N[2]));
        assert(solid);
        for (int64_t k = 0; k < N[2]; ++k)
            for (int64_t j = 0; j < N[1]; ++j)
                for (int64_t i = 0; i < N[0]; ++i) {
                    solid[(size_t)(i + N[0] * (j + N[1] * k))] = (uint8_t)solid_dense(&b, i, j, k);
                    assert(meso_ref_cells_solid(c, i, j, k) == solid_dense(&b, i, j, k));
                }
        check_rays(c, solid, &st, 400, &rs);
        free(solid);
        obj_free(&b);
    }
    /* ties: exact diagonals through voxel edges and corners step x, then y, then z */
    {
        obj b;
        const double origin[3] = {0, 0, 0};
        one_tile(&b, 4, 1.0, origin);
        set_solid(&b, 1, 0, 0, 1);
        set_solid(&b, 0, 1, 0, 1);
        obj_finish(&b);
        const double o[3] = {0.5, 0.5, 0.5}, u[3] = {sqrt(0.5), sqrt(0.5), 0};
        res r = run_search(&b.c, o, u, HUGE_VAL, 1, NULL);
        assert(r.found && r.v[0] == 1 && r.v[1] == 0 && r.v[2] == 0 && r.axis == 0 && fabs(r.s - sqrt(0.5)) < 1e-15);
        ++ties;
        set_solid(&b, 1, 0, 0, 0);
        set_solid(&b, 1, 1, 0, 1);
        obj_finish(&b);
        r = run_search(&b.c, o, u, HUGE_VAL, 1, NULL); /* (0, 1, 0) is not on the walk */
        assert(r.found && r.v[0] == 1 && r.v[1] == 1 && r.v[2] == 0 && r.axis == 1 && r.last[0] == 1 &&
               r.last[1] == 0);
        ++ties;
        set_solid(&b, 1, 1, 0, 0);
        set_solid(&b, 1, 1, 1, 1);
        set_solid(&b, 0, 1, 1, 1);
        set_solid(&b, 1, 0, 1, 1);
        set_solid(&b, 0, 0, 1, 1);
        obj_finish(&b);
        const double u3[3] = {sqrt(1.0 / 3), sqrt(1.0 / 3), sqrt(1.0 / 3)};
        r = run_search(&b.c, o, u3, HUGE_VAL, 1, NULL); /* corner: (1,0,0), (1,1,0), then (1,1,1) by z */
        assert(r.found && r.v[0] == 1 && r.v[1] == 1 && r.v[2] == 1 && r.axis == 2);
        ++ties;
        /* absurd rays end, with no hit: non-finite or astronomically far */
        const int64_t z3[3] = {0, 0, 0};
        const double far_o[3] = {1e300, 0.5, 0.5}, back[3] = {-1, 0, 0}, nan_u[3] = {NAN, 0, 0};
        double s_;
        int64_t v_[3];
        int ax_;
        assert(!meso_ref_cells_search(&b.c, far_o, back, z3, HUGE_VAL, 1, &s_, v_, NULL, &ax_, NULL));
        assert(!meso_ref_cells_search(&b.c, o, nan_u, z3, HUGE_VAL, 1, &s_, v_, NULL, &ax_, NULL));
        const double tiny_u[3] = {1e-320, 1, 0}, tiny_d[3] = {1e-320, 0, -1}; /* x crossings at s = inf */
        assert(meso_ref_cells_search(&b.c, o, tiny_u, z3, HUGE_VAL, 1, &s_, v_, NULL, &ax_, NULL) && s_ == 0.5 &&
               v_[0] == 0 && v_[1] == 1 && v_[2] == 0 && ax_ == 1);
        assert(!meso_ref_cells_search(&b.c, o, tiny_d, z3, HUGE_VAL, 1, &s_, v_, NULL, &ax_, NULL));
        meso_ref_cells_path path;
        meso_ref_cells_trace(&b.c, far_o, back, HUGE_VAL, LIGHT, NULL, &path);
        assert(!path.hit);
        obj_free(&b);
    }
    print_stats("traversal, 30 random objects", &rs);
    printf("ties: %ld exact diagonals through edges and corners step x, then y, then z\n", ties);
    assert(rs.found[0] > 3000 && rs.found[1] > 1500 && rs.none[1] > 100 && rs.beyond > 100);
    assert(rs.steps_on[0] < rs.steps_off[0] && rs.steps_on[1] < rs.steps_off[1]);
}

/* >>3: a box through the renderer, in closed form --------------------------- */

static meso_ref_view make_view(const double eye[3], const double at[3], int W, int H)
{
    meso_ref_view v;
    memset(&v, 0, sizeof v);
    const double up[3] = {0, 1, 0};
    meso_camera_look_at_d(v.view, eye, at, up);
    meso_camera_perspective_d(v.proj, 0.8, (double)W / H, 0.5, 20);
    v.width = W;
    v.height = H;
    v.threads = 2;
    return v;
}

/* Ray of pixel (x, y), built here from the matrices (not ref_common's):
 * eye + s dir through the pixel centre on the near plane. */
static void pixel_ray_here(const meso_ref_view* v, const double eye[3], int x, int y, double dir[3])
{
    const double ndc_x = (2.0 * x + 1) / v->width - 1, ndc_y = (2.0 * y + 1) / v->height - 1;
    /* camera space direction (ndc_x / P0, ndc_y / P5, -1), to world with the view's rotation transposed */
    const double cd[3] = {ndc_x / v->proj[0], ndc_y / v->proj[5], -1};
    for (int k = 0; k < 3; ++k)
        dir[k] = v->view[4 * k + 0] * cd[0] + v->view[4 * k + 1] * cd[1] + v->view[4 * k + 2] * cd[2];
    const double l = sqrt(dot(dir, dir));
    for (int k = 0; k < 3; ++k)
        dir[k] /= l;
    (void)eye;
}

static void box_first_hit_through_the_renderer(void)
{
    obj b;
    const double origin[3] = {-1, -1, -1};
    one_tile(&b, 16, 0.125, origin);
    /* box [-0.5, 0.5] x [-0.75, 0] x [-0.25, 0.5]: i 4..11, j 2..7, k 6..11 */
    for (int k = 6; k <= 11; ++k)
        for (int j = 2; j <= 7; ++j)
            for (int i = 4; i <= 11; ++i)
                set_solid(&b, i, j, k, 1);
    obj_finish(&b); /* NRMM +y everywhere: the top uses it, the sides (m . f = 0) their face */
    const double lo[3] = {-0.5, -0.75, -0.25}, hi[3] = {0.5, 0, 0.5};
    const double eye[3] = {1.3, 1.7, 2.6}, at[3] = {0, -0.3, 0};
    const int W = 96, H = 80;
    meso_ref_view v = make_view(eye, at, W, H);
    meso_ref_image img;
    assert(meso_ref_cells_render(&b.c, &v, NULL, &img) == MESO_OK);
    double worst_p = 0, worst_d = 0, worst_c = 0;
    long covered = 0, faces[3] = {0, 0, 0};
    const double zn = 0.5, zf = 20;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const size_t px = (size_t)y * W + x;
            double dir[3], s0, s1;
            int ax;
            pixel_ray_here(&v, eye, x, y, dir);
            const int hit = slab(lo, hi, eye, dir, &s0, &s1, &ax) && s1 - s0 > 1e-9;
            assert(img.coverage[px] == hit);
            if (!hit) {
                assert(img.depth[px] == 1.0f && isnan(img.hit[3 * px]));
                continue;
            }
            ++covered;
            double p[3], n[3] = {0, 0, 0};
            for (int k = 0; k < 3; ++k)
                p[k] = eye[k] + s0 * dir[k];
            n[ax] = dir[ax] > 0 ? -1 : 1;
            faces[ax]++;
            for (int k = 0; k < 3; ++k) {
                worst_p = fmax(worst_p, fabs(img.hit[3 * px + k] - p[k]));
                assert(img.normal[3 * px + k] == (float)n[k]);
            }
            /* depth: camera-space z of p, perspective divide */
            double zc = 0;
            for (int k = 0; k < 3; ++k)
                zc += v.view[4 * k + 2] * p[k];
            zc += v.view[14];
            const double ndc_z = (-(zf + zn) / (zf - zn) * zc - 2 * zf * zn / (zf - zn)) / -zc;
            worst_d = fmax(worst_d, fabs(img.depth[px] - (0.5 * ndc_z + 0.5)));
            double rgb[3];
            shade_expect(n, LIGHT, rgb);
            for (int k = 0; k < 3; ++k)
                worst_c = fmax(worst_c, fabs(img.rgb[3 * px + k] - rgb[k]));
        }
    printf("box through the renderer: %ld of %d pixels covered (faces x %ld, y %ld, z %ld), coverage = closed form "
           "everywhere; |hit - closed form| <= %.3g, |depth - closed form| <= %.3g, |rgb - formula| <= %.3g, normals "
           "exact\n",
           covered, W * H, faces[0], faces[1], faces[2], worst_p, worst_d, worst_c);
    assert(covered > 500 && faces[0] > 50 && faces[1] > 50 && faces[2] > 50);
    assert(worst_p < 1e-6 && worst_d < 1e-6 && worst_c < 1e-6);
    /* skipping off: the same image */
    meso_ref_image img2;
    meso_ref_cells_skipping = 0;
    assert(meso_ref_cells_render(&b.c, &v, NULL, &img2) == MESO_OK);
    meso_ref_cells_skipping = 1;
    assert(!memcmp(img.rgb, img2.rgb, sizeof(float) * 3 * W * H));
    assert(!memcmp(img.depth, img2.depth, sizeof(float) * W * H));
    meso_ref_image_free(&img2);
    meso_ref_image_free(&img);
    /* a camera inside the solid: hit at the near plane, normal -u */
    {
        const double o[3] = {0.01, -0.3, 0.1}, u[3] = {0, 0, -1};
        meso_ref_cells_path path;
        meso_ref_cells_trace(&b.c, o, u, 10, LIGHT, NULL, &path);
        assert(path.hit && path.s0 == 0 && path.n[0][2] == 1); /* m = +y is not facing f = -u = +z: f */
    }
    obj_free(&b);
}

/* >>4: reflection ------------------------------------------------------------- */

static void reflection_floor_to_wall(void)
{
    obj b;
    const double origin[3] = {-1, -1, -1};
    one_tile(&b, 16, 0.125, origin);
    /* floor y in [-1, -0.5] (j 0..3), wall x in [0.5, 1] (i 12..15) above it */
    for (int k = 0; k < 16; ++k)
        for (int j = 0; j < 16; ++j)
            for (int i = 0; i < 16; ++i) {
                const int floor_v = j <= 3, wall_v = i >= 12 && j >= 4;
                set_solid(&b, i, j, k, floor_v || wall_v);
                if (wall_v)
                    set_normal(&b, i, j, k, -1, 0, 0);
            }
    obj_finish(&b);
    const double o[3] = {-0.7, 0.3, 0.05};
    double u[3] = {0.6, -0.5, 0.1};
    const double ul = sqrt(dot(u, u));
    for (int k = 0; k < 3; ++k)
        u[k] /= ul;
    /* closed form */
    const double s1 = (-0.5 - o[1]) / u[1];
    const double p1[3] = {o[0] + s1 * u[0], -0.5, o[2] + s1 * u[2]};
    const double r1[3] = {u[0], -u[1], u[2]};
    const double s2 = (0.5 - p1[0]) / r1[0];
    const double p2[3] = {0.5, p1[1] + s2 * r1[1], p1[2] + s2 * r1[2]};
    const double r2[3] = {-r1[0], r1[1], r1[2]};
    assert(p2[1] > -0.5 && p2[1] < 1 && fabs(p2[2]) < 1);
    const double k = 0.3;
    const double ny[3] = {0, 1, 0}, nx[3] = {-1, 0, 0};
    double sh0[3], sh1[3], e1[3], e2[3];
    shade_expect(ny, LIGHT, sh0);
    shade_expect(nx, LIGHT, sh1);
    env(r1, e1);
    env(r2, e2);
    double worst_p = 0, worst_c = 0;
    for (int B = 0; B <= 2; ++B) {
        meso_ref_cells_opts op = {.mode = MESO_REF_CELLS_REFLECT, .bounces = B, .reflectivity = k};
        meso_ref_cells_path path;
        meso_ref_cells_trace(&b.c, o, u, 10, LIGHT, &op, &path);
        assert(path.hit && path.events == (B == 0 ? 0 : 1));
        for (int a = 0; a < 3; ++a) {
            worst_p = fmax(worst_p, fabs(path.p[0][a] - p1[a]));
            if (B > 0)
                worst_p = fmax(worst_p, fabs(path.p[1][a] - p2[a]));
        }
        double want[3];
        for (int a = 0; a < 3; ++a)
            want[a] = B == 0 ? (1 - k) * sh0[a] + k * e1[a] : (1 - k) * sh0[a] + k * (1 - k) * sh1[a] + k * k * e2[a];
        for (int a = 0; a < 3; ++a)
            worst_c = fmax(worst_c, fabs(path.rgb[a] - want[a]));
        printf("reflection B = %d: rgb (%.6f %.6f %.6f), expected (%.6f %.6f %.6f)\n", B, path.rgb[0], path.rgb[1],
               path.rgb[2], want[0], want[1], want[2]);
    }
    { /* entering the grid box into a SOLID voxel on its boundary: hit on its face, not at s = 0 with -u */
        const double o2[3] = {0.1, -1.5, 0.2};
        double u2[3] = {0.1, 1, 0.05};
        const double l2 = sqrt(dot(u2, u2));
        for (int a = 0; a < 3; ++a)
            u2[a] /= l2;
        meso_ref_cells_path path;
        meso_ref_cells_trace(&b.c, o2, u2, 10, LIGHT, NULL, &path);
        assert(path.hit && fabs(path.s0 - 0.5 / u2[1]) < 1e-15 && path.n[0][0] == 0 && path.n[0][1] == -1);
        meso_ref_cells_trace(&b.c, o2, u2, 0.4 / u2[1], LIGHT, NULL, &path); /* the far plane before it */
        assert(!path.hit);
    }
    printf("reflection floor -> wall: |bounce points - closed form| <= %.3g, |rgb - formula| <= %.3g (B = 0, 1, 2, "
           "k = %.1f)\n",
           worst_p, worst_c, k);
    assert(worst_p < 1e-12 && worst_c < 1e-12);
    obj_free(&b);
}

/* >>5: refraction ----------------------------------------------------------------- */

/* Snell in closed form: unit d through a surface of unit normal n (n . d <
 * 0), index ratio eta = n1 / n2. */
static int snell(const double d[3], const double n[3], double eta, double t[3])
{
    const double ci = -dot(n, d), si2 = 1 - ci * ci, st2 = eta * eta * si2;
    if (st2 > 1)
        return 0;
    const double ct = sqrt(1 - st2);
    double tang[3]; /* the tangential part of d */
    for (int k = 0; k < 3; ++k)
        tang[k] = d[k] + ci * n[k];
    for (int k = 0; k < 3; ++k)
        t[k] = eta * tang[k] - ct * n[k];
    return 1;
}

static void refraction_slab_and_tir(void)
{
    const double origin[3] = {-1, -1, -1};
    const double tau = 0.6, ior = 1.5;
    double worst_p = 0, worst_d = 0, worst_c = 0;
    { /* slab y in [-0.25, 0.25] (j 6..9), every x, z */
        obj b;
        one_tile(&b, 16, 0.125, origin);
        for (int k = 0; k < 16; ++k)
            for (int i = 0; i < 16; ++i)
                for (int j = 6; j <= 9; ++j) {
                    set_solid(&b, i, j, k, 1);
                    set_normal(&b, i, j, k, 0, j == 6 ? -1 : 1, 0);
                }
        obj_finish(&b);
        const double o[3] = {-0.5, 0.8, -0.1};
        double u[3] = {0.4, -1, 0.2};
        const double ul = sqrt(dot(u, u));
        for (int k = 0; k < 3; ++k)
            u[k] /= ul;
        const double s0 = (0.25 - o[1]) / u[1];
        const double p0[3] = {o[0] + s0 * u[0], 0.25, o[2] + s0 * u[2]};
        /* lateral shift: inside the ray makes angle theta_t with -y, sin theta_t = sin theta_i / ior */
        const double sin_i = sqrt(u[0] * u[0] + u[2] * u[2]), sin_t = sin_i / ior;
        const double tan_t = sin_t / sqrt(1 - sin_t * sin_t);
        const double run = 0.5 * tan_t; /* horizontal distance covered inside */
        const double p1[3] = {p0[0] + run * u[0] / sin_i, -0.25, p0[2] + run * u[2] / sin_i};
        const double ny[3] = {0, 1, 0};
        double t_in[3], sh0[3], ef[3], et[3];
        assert(snell(u, ny, 1 / ior, t_in));
        shade_expect(ny, LIGHT, sh0);
        env(u, ef);
        env(t_in, et);
        for (int B = 0; B <= 2; ++B) {
            meso_ref_cells_opts op = {.mode = MESO_REF_CELLS_REFRACT, .bounces = B, .ior = ior, .transparency = tau};
            meso_ref_cells_path path;
            meso_ref_cells_trace(&b.c, o, u, 10, LIGHT, &op, &path);
            assert(path.hit && path.events == (B == 0 ? 0 : 1));
            for (int a = 0; a < 3; ++a) {
                worst_p = fmax(worst_p, fabs(path.p[0][a] - p0[a]));
                worst_d = fmax(worst_d, fabs(path.dir[0][a] - t_in[a]));
                if (B > 0) {
                    worst_p = fmax(worst_p, fabs(path.p[1][a] - p1[a]));
                    worst_d = fmax(worst_d, fabs(path.dir[1][a] - u[a])); /* leaves parallel to u */
                }
            }
            for (int a = 0; a < 3; ++a)
                worst_c = fmax(worst_c, fabs(path.rgb[a] - ((1 - tau) * sh0[a] + tau * (B ? ef[a] : et[a]))));
        }
        printf("refraction through a slab: entry (%.6f, %.6f), exit (%.6f, %.6f) after a lateral run of %.6f\n", p0[0],
               p0[2], p1[0], p1[2], run);
        obj_free(&b);
    }
    { /* box x in [-0.5, 0.5] (i 4..11), y in [-0.75, 0.5] (j 2..11), every z: total internal reflection on its side */
        obj b;
        one_tile(&b, 16, 0.125, origin);
        for (int k = 0; k < 16; ++k)
            for (int j = 2; j <= 11; ++j)
                for (int i = 4; i <= 11; ++i) {
                    set_solid(&b, i, j, k, 1);
                    if (j == 11)
                        set_normal(&b, i, j, k, 0, 1, 0);
                    else if (j == 2)
                        set_normal(&b, i, j, k, 0, -1, 0);
                    else if (i == 11)
                        set_normal(&b, i, j, k, 1, 0, 0);
                    else if (i == 4)
                        set_normal(&b, i, j, k, -1, 0, 0);
                }
        obj_finish(&b);
        const double o[3] = {0.05, 1.0, 0.2};
        double u[3] = {0.5, -1, 0};
        const double ul = sqrt(dot(u, u));
        for (int k = 0; k < 3; ++k)
            u[k] /= ul;
        const double ny[3] = {0, 1, 0}, nx_in[3] = {-1, 0, 0}, ny_in[3] = {0, 1, 0};
        const double s0 = (0.5 - o[1]) / u[1];
        const double p0[3] = {o[0] + s0 * u[0], 0.5, o[2]};
        double t1[3], t2[3], t3[3], dummy[3];
        assert(snell(u, ny, 1 / ior, t1));
        const double p1[3] = {0.5, p0[1] + (0.5 - p0[0]) / t1[0] * t1[1], p0[2]};
        /* at the side: incidence sin = |t1 . y| > 1 / ior: total internal reflection */
        assert(!snell(t1, nx_in, ior, dummy));
        t2[0] = -t1[0];
        t2[1] = t1[1];
        t2[2] = t1[2];
        const double p2[3] = {p1[0] + (-0.75 - p1[1]) / t2[1] * t2[0], -0.75, p1[2]};
        assert(p2[0] > -0.375 && p2[0] < 0.375); /* not a corner voxel */
        assert(snell(t2, ny_in, ior, t3));
        double sh0[3], e3[3];
        shade_expect(ny, LIGHT, sh0);
        env(t3, e3);
        meso_ref_cells_opts op = {.mode = MESO_REF_CELLS_REFRACT, .bounces = 3, .ior = ior, .transparency = tau};
        meso_ref_cells_path path;
        meso_ref_cells_trace(&b.c, o, u, 10, LIGHT, &op, &path);
        assert(path.hit && path.events == 2);
        const double* want_p[3] = {p0, p1, p2};
        const double* want_d[3] = {t1, t2, t3};
        for (int e = 0; e < 3; ++e)
            for (int a = 0; a < 3; ++a) {
                worst_p = fmax(worst_p, fabs(path.p[e][a] - want_p[e][a]));
                worst_d = fmax(worst_d, fabs(path.dir[e][a] - want_d[e][a]));
            }
        for (int a = 0; a < 3; ++a)
            worst_c = fmax(worst_c, fabs(path.rgb[a] - ((1 - tau) * sh0[a] + tau * e3[a])));
        /* B = 1: the path ends after the internal reflection */
        op.bounces = 1;
        meso_ref_cells_trace(&b.c, o, u, 10, LIGHT, &op, &path);
        double e2[3];
        env(t2, e2);
        assert(path.events == 1);
        for (int a = 0; a < 3; ++a)
            worst_c = fmax(worst_c, fabs(path.rgb[a] - ((1 - tau) * sh0[a] + tau * e2[a])));
        printf("refraction with total internal reflection: side hit y = %.6f, bottom exit x = %.6f, leaving "
               "(%.6f, %.6f, %.6f)\n",
               p1[1], p2[0], t3[0], t3[1], t3[2]);
        obj_free(&b);
    }
    printf("refraction: |points - Snell| <= %.3g, |directions - Snell| <= %.3g, |rgb - (1 - tau) shade + tau env| <= "
           "%.3g\n",
           worst_p, worst_d, worst_c);
    assert(worst_p < 1e-12 && worst_d < 1e-12 && worst_c < 1e-12);
}

/* >>6: fallbacks ---------------------------------------------------------------- */

static void normal_and_direction_fallbacks(void)
{
    obj b;
    const double origin[3] = {-1, -1, -1};
    one_tile(&b, 16, 0.125, origin);
    for (int k = 0; k < 16; ++k)
        for (int i = 0; i < 16; ++i)
            for (int j = 0; j <= 7; ++j)
                set_solid(&b, i, j, k, 1); /* the half space y <= 0 */
    /* hit voxel (8, 7, 8): its normal disagrees with the face (+y) */
    set_normal(&b, 8, 7, 8, 0.3, -0.8, 0.2);
    /* voxel (12, 7, 8): a tilted normal that still faces out */
    set_normal(&b, 12, 7, 8, 0.8, 0.6, 0);
    obj_finish(&b);
    const double up[3] = {0, 1, 0};
    meso_ref_cells_path path;
    {
        const double o[3] = {0.06, 0.5, 0.06}, u[3] = {0, -1, 0}; /* x, z in voxel 8 */
        meso_ref_cells_trace(&b.c, o, u, 10, LIGHT, NULL, &path);
        assert(path.hit && path.n[0][0] == 0 && path.n[0][1] == 1 && path.n[0][2] == 0);
        double rgb[3];
        shade_expect(up, LIGHT, rgb);
        for (int a = 0; a < 3; ++a)
            assert(fabs(path.rgb[a] - rgb[a]) < 1e-12);
    }
    {
        /* x in voxel 12: n = m = (0.8, 0.6, 0) (as stored in float) */
        double u[3] = {1, -0.2, 0};
        const double ul = sqrt(dot(u, u));
        for (int k = 0; k < 3; ++k)
            u[k] /= ul;
        const double o[3] = {0.56 - 0.5 / u[1] * -u[0], 0.5, 0.06}; /* reaches y = 0 at x = 0.56 */
        meso_ref_cells_opts op = {.mode = MESO_REF_CELLS_REFLECT, .reflectivity = 0.5};
        meso_ref_cells_trace(&b.c, o, u, 10, LIGHT, &op, &path);
        const float* m = &b.c.normal[3 * vidx(&b.c, 12, 7, 8)];
        assert(path.hit && path.n[0][0] == m[0] && path.n[0][1] == m[1] && path.n[0][2] == m[2]);
        /* reflect(u, m) would go down into the face: the face's reflection instead */
        const double um = u[0] * m[0] + u[1] * m[1];
        assert(u[1] - 2 * um * m[1] < 0);
        assert(fabs(path.dir[0][0] - u[0]) < 1e-15 && fabs(path.dir[0][1] + u[1]) < 1e-15 && path.dir[0][2] == 0);
        double rgb[3], sh[3], e[3];
        const double md[3] = {m[0], m[1], m[2]};
        shade_expect(md, LIGHT, sh);
        env(path.dir[0], e);
        for (int a = 0; a < 3; ++a)
            rgb[a] = 0.5 * sh[a] + 0.5 * e[a];
        for (int a = 0; a < 3; ++a)
            assert(fabs(path.rgb[a] - rgb[a]) < 1e-12);
        /* refraction in with the same normal: GLSL refract(u, m, 1 / 1.5) goes in (entering never needs the
         * fallback: eta (n . u) + sqrt k >= 0), and differs from the face's */
        meso_ref_cells_opts opr = {.mode = MESO_REF_CELLS_REFRACT, .ior = 1.5, .transparency = 0.5};
        meso_ref_cells_trace(&b.c, o, u, 10, LIGHT, &opr, &path);
        double t[3], tf[3];
        const double eta = 1 / 1.5, kk = 1 - eta * eta * (1 - um * um);
        for (int a = 0; a < 3; ++a)
            t[a] = eta * u[a] - (eta * um + sqrt(kk)) * md[a];
        const double tl = sqrt(dot(t, t));
        assert(snell(u, up, eta, tf));
        for (int a = 0; a < 3; ++a)
            assert(fabs(path.dir[0][a] - t[a] / tl) < 1e-12);
        assert(t[1] < 0 && fabs(path.dir[0][0] - tf[0]) > 0.1);
    }
    obj_free(&b);
    {
        /* leaving a slab through a face whose normal map tilts (0.9, -0.44, 0): with n = -m the event is a
         * total internal reflection that would go out through the face: the face's refraction instead */
        one_tile(&b, 16, 0.125, origin);
        for (int k = 0; k < 16; ++k)
            for (int i = 0; i < 16; ++i)
                for (int j = 6; j <= 9; ++j) {
                    set_solid(&b, i, j, k, 1);
                    if (j == 6)
                        set_normal(&b, i, j, k, 0.9, -sqrt(1 - 0.81), 0);
                }
        obj_finish(&b);
        double u[3] = {0.4, -1, 0};
        const double ul = sqrt(dot(u, u));
        for (int k = 0; k < 3; ++k)
            u[k] /= ul;
        const double o[3] = {-0.6, 0.6, 0.06};
        meso_ref_cells_opts opr = {.mode = MESO_REF_CELLS_REFRACT, .bounces = 1, .ior = 1.5, .transparency = 0.5};
        meso_ref_cells_trace(&b.c, o, u, 10, LIGHT, &opr, &path);
        double t[3], n[3], tmp[3];
        assert(snell(u, up, 1 / 1.5, t));
        const float* m = &b.c.normal[3 * vidx(&b.c, 0, 6, 0)];
        for (int a = 0; a < 3; ++a)
            n[a] = -m[a];
        assert(!snell(t, n, 1.5, tmp)); /* TIR with n ... */
        const double tn = dot(t, n);
        assert(t[1] - 2 * tn * n[1] < 0); /* ... whose reflection would leave through the bottom face */
        assert(path.hit && path.events == 1 && fabs(path.p[1][1] + 0.25) < 1e-12);
        for (int a = 0; a < 3; ++a)
            assert(fabs(path.dir[1][a] - u[a]) < 1e-12); /* the face's refraction: parallel to u */
    }
    printf("fallbacks: a normal facing into the solid gives the face normal; reflected and refracted directions "
           "that would cross back are the face's\n");
    obj_free(&b);
}

/* >>7, 8: a baked file; threads ------------------------------------------------- */

typedef struct baked {
    meso_tile_map tm;
    meso_split_cells sc;
    meso_membership mb;
    meso_cells_chunks cc;
    meso_voxel_grid g;
} baked;

static uint8_t* write_object(const meso_cells_chunks* c, uint32_t R, uint32_t S, uint32_t memb_words, size_t* size)
{
    meso_writer* w = NULL;
    meso_error err = {0};
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    meso_object_record rec;
    memset(&rec, 0, sizeof rec);
    rec.id = 1;
    rec.kind = MESO_OBJECT_CELLS;
    strcpy(rec.name, "cells");
    uint8_t objt[64];
    meso_object_record_encode(&rec, objt);
    meso_chunk_desc d[7] = {
        {.type = MESO_CHUNK_OBJT, .flags = MESO_CHUNK_FLAG_REQUIRED, .object = 0, .dtype = MESO_DTYPE_BYTES,
         .components = 1, .dims = {1, 1, 1}},
        {.type = MESO_CHUNK_CELL, .object = 1},
        {.type = MESO_CHUNK_TILE, .object = 1, .dtype = c->tile_dtype, .dims = {R, R, R}},
        {.type = MESO_CHUNK_SPLT, .object = 1, .dtype = MESO_DTYPE_U32, .components = 6, .dims = {S, 1, 1}},
        {.type = MESO_CHUNK_MEMB, .object = 1, .dtype = MESO_DTYPE_U32, .dims = {memb_words, 1, 1}},
        {.type = MESO_CHUNK_NRMM, .object = 1, .dtype = MESO_DTYPE_U16, .components = 2, .dims = {R, R, R}},
        {.type = MESO_CHUNK_COLR, .object = 1, .dtype = MESO_DTYPE_U8, .components = 4, .dims = {R, R, R}},
    };
    const void* data[7] = {objt, c->cell, c->tile, c->splt, c->memb, c->nrmm, c->colr};
    const size_t sizes[7] = {64, sizeof c->cell, c->tile_size, c->splt_size, (size_t)memb_words * 4, c->nrmm_size,
                             c->colr_size};
    for (int i = 0; i < 7; ++i) {
        const meso_result r = meso_writer_add(w, &d[i], data[i], sizes[i], &err);
        if (r != MESO_OK)
            printf("writer: %s\n", err.message);
        assert(r == MESO_OK);
    }
    assert(meso_writer_finish(w, NULL, 0, size) == MESO_OK);
    uint8_t* mem = malloc(*size);
    assert(mem && meso_writer_finish(w, mem, *size, size) == MESO_OK);
    meso_writer_destroy(w);
    return mem;
}

static meso_result load_mem(const uint8_t* mem, size_t size, meso_ref_cells* c, meso_error* err)
{
    meso_file* f = NULL;
    assert(meso_file_open_memory(mem, size, NULL, &f, err) == MESO_OK);
    const meso_result r = meso_ref_cells_load(f, 1, c, err);
    meso_file_close(f);
    return r;
}

static void baked_file_loads_and_renders(void)
{
    meso_mesh m;
    meso_error err = {0};
    assert(meso_openmesh_read(test_data("sphere.obj"), &m, NULL, &err) == MESO_OK);
    baked b;
    memset(&b, 0, sizeof b);
    meso_tile_map_params p = {.kind = MESO_TILE_MAP_VORONOI, .res = 16, .count = 12, .rng_seed = 7};
    assert(meso_tile_map_generate(&p, 2, &b.tm, &err) == MESO_OK);
    assert(meso_split_cells_compute(&b.tm, 2, &b.sc, &err) == MESO_OK);
    assert(meso_voxel_grid_fit(&m, 6, 16, 1.0, &b.g, &err) == MESO_OK);
    for (int k = 0; k < 3; ++k)
        b.g.origin[k] = (double)(float)b.g.origin[k];
    b.g.voxel_size = (double)(float)b.g.voxel_size;
    assert(meso_membership_compute(&m, &b.g, &b.sc, MESO_VOXELIZE_AUTO, 2, &b.mb, &err) == MESO_OK);
    assert(meso_cells_chunks_build(&b.tm, &b.sc, &b.mb, b.g.origin, b.g.voxel_size, "hash:3", 2, &b.cc, &err) ==
           MESO_OK);
    const uint32_t R = b.tm.res, S = b.sc.split_count, L = (uint32_t)(b.cc.memb_size / 4);
    size_t size = 0;
    uint8_t* mem = write_object(&b.cc, R, S, L, &size);
    meso_ref_cells c;
    if (load_mem(mem, size, &c, &err) != MESO_OK)
        printf("load: %s\n", err.message);
    assert(err.result == MESO_OK || err.result == 0);
    assert(c.res == R && c.split_count == S && c.voxel == b.g.voxel_size);
    for (int k = 0; k < 3; ++k)
        assert(c.tiles[k] == b.g.tiles[k] && c.origin[k] == b.g.origin[k]);
    const size_t n = (size_t)R * R * R;
    for (size_t v = 0; v < n; ++v) {
        assert(c.tile[v] == b.sc.voxel_split[v]);
        double nrm[3];
        meso_octa_decode(b.cc.nrmm + 2 * v, nrm);
        for (int k = 0; k < 3; ++k)
            assert(fabs(c.normal[3 * v + k] - nrm[k]) < 1e-7);
        assert(!memcmp(c.colour + 4 * v, b.cc.colr + 4 * v, 4));
    }
    uint64_t tags[3] = {0, 0, 0}, solid = 0;
    for (uint32_t tz = 0; tz < c.tiles[2]; ++tz)
        for (uint32_t ty = 0; ty < c.tiles[1]; ++ty)
            for (uint32_t tx = 0; tx < c.tiles[0]; ++tx) {
                const uint64_t t = tx + (uint64_t)c.tiles[0] * (ty + (uint64_t)c.tiles[1] * tz);
                assert(meso_ref_cells_class(&c, t) == (unsigned)meso_membership_tile(&b.mb, tx, ty, tz));
                for (uint32_t s = 1; s <= S; ++s) {
                    const unsigned g = meso_ref_cells_tag(&c, t, s);
                    assert(g == (unsigned)meso_membership_get(&b.mb, tx, ty, tz, s));
                    tags[g]++;
                }
            }
    /* SOLID from the bake's own accessors (not MEMB) */
    const int64_t N[3] = {(int64_t)c.tiles[0] * R, (int64_t)c.tiles[1] * R, (int64_t)c.tiles[2] * R};
    uint8_t* sol = malloc((size_t)(N[0] * N[1] * N[2]));
    assert(sol);
    for (int64_t k = 0; k < N[2]; ++k)
        for (int64_t j = 0; j < N[1]; ++j)
            for (int64_t i = 0; i < N[0]; ++i) {
                const uint32_t sp = b.sc.voxel_split[(size_t)(i % R + R * (j % R + R * (k % R)))];
                const int s_ = sp != 0 && meso_membership_get(&b.mb, (uint32_t)(i / R), (uint32_t)(j / R),
                                                             (uint32_t)(k / R), sp) == MESO_MEMB_INSIDE;
                sol[(size_t)(i + N[0] * (j + N[1] * k))] = (uint8_t)s_;
                assert(meso_ref_cells_solid(&c, i, j, k) == s_);
                solid += (uint64_t)s_;
            }
    ray_stats rs;
    memset(&rs, 0, sizeof rs);
    uint64_t st = 77;
    check_rays(&c, sol, &st, 60, &rs);
    print_stats("traversal, baked sphere", &rs);
    fflush(stdout);
    assert(rs.found[0] > 20 && rs.found[1] > 20 && rs.steps_on[1] < rs.steps_off[1]);
    free(sol);
    printf("baked sphere: %u^3 tiles of R = %u, S = %u: tags = meso_membership_get for every tile and split cell "
           "(%llu outside, %llu inside, %llu intersected), %llu SOLID voxels, normals = meso_octa_decode\n",
           c.tiles[0], R, S, (unsigned long long)tags[0], (unsigned long long)tags[1], (unsigned long long)tags[2],
           (unsigned long long)solid);
    assert(tags[0] && tags[1] && tags[2] && solid > 0);

    /* 8: threads 1 = 2 (and skipping off), all three modes */
    double ctr[3], ext = 0;
    for (int k = 0; k < 3; ++k) {
        const double span = c.tiles[k] * (double)R * c.voxel;
        ctr[k] = c.origin[k] + span / 2;
        ext = fmax(ext, span);
    }
    const double eye[3] = {ctr[0] + 0.9 * ext, ctr[1] + 0.5 * ext, ctr[2] + 1.2 * ext};
    const int W = 64, H = 56;
    meso_ref_view v = make_view(eye, ctr, W, H);
    long covered = 0;
    for (int mode = 0; mode < 3; ++mode) {
        const meso_ref_cells_opts op = {.mode = mode, .bounces = 2, .reflectivity = 0, .ior = 0, .transparency = 0};
        meso_ref_image i1, i2, i3;
        v.threads = 1;
        assert(meso_ref_cells_render(&c, &v, &op, &i1) == MESO_OK);
        v.threads = 2;
        assert(meso_ref_cells_render(&c, &v, &op, &i2) == MESO_OK);
        meso_ref_cells_skipping = 0;
        assert(meso_ref_cells_render(&c, &v, &op, &i3) == MESO_OK);
        meso_ref_cells_skipping = 1;
        const size_t np = (size_t)W * H;
        assert(!memcmp(i1.rgb, i2.rgb, 12 * np) && !memcmp(i1.depth, i2.depth, 4 * np) &&
               !memcmp(i1.coverage, i2.coverage, np) && !memcmp(i1.hit, i2.hit, 12 * np) &&
               !memcmp(i1.normal, i2.normal, 12 * np));
        assert(!memcmp(i1.rgb, i3.rgb, 12 * np) && !memcmp(i1.depth, i3.depth, 4 * np) &&
               !memcmp(i1.coverage, i3.coverage, np));
        for (size_t q = 0; q < np; ++q)
            covered += i1.coverage[q];
        meso_ref_image_free(&i1);
        meso_ref_image_free(&i2);
        meso_ref_image_free(&i3);
    }
    printf("baked sphere rendered %dx%d in the three modes: threads 1 = 2 and skipping on = off, byte for byte (%ld "
           "covered pixels)\n",
           W, H, covered);
    assert(covered > 300);
    meso_ref_cells_free(&c);

    /* 7: corrupted copies are refused, naming the chunk */
    {
        uint8_t* bad = write_object(&b.cc, R, S, L - 1, &size); /* MEMB one word short */
        assert(load_mem(bad, size, &c, &err) == MESO_ERR_CORRUPT && strstr(err.message, "MEMB"));
        printf("refused: %s\n", err.message);
        free(bad);
        uint32_t keep = b.cc.memb[0];
        b.cc.memb[0] |= 3u; /* tile 0: class 3 */
        bad = write_object(&b.cc, R, S, L, &size);
        assert(load_mem(bad, size, &c, &err) == MESO_ERR_CORRUPT && strstr(err.message, "MEMB"));
        printf("refused: %s\n", err.message);
        free(bad);
        b.cc.memb[0] = keep;
        const uint32_t cw = (uint32_t)((b.mb.tile_count + 15) / 16);
        keep = b.cc.memb[cw + 1];
        b.cc.memb[cw + 1] += 1; /* a wrong rank */
        bad = write_object(&b.cc, R, S, L, &size);
        assert(load_mem(bad, size, &c, &err) == MESO_ERR_CORRUPT && strstr(err.message, "MEMB"));
        free(bad);
        b.cc.memb[cw + 1] = keep;
        ((uint16_t*)b.cc.tile)[5] = (uint16_t)(S + 1); /* a split id above S */
        bad = write_object(&b.cc, R, S, L, &size);
        assert(load_mem(bad, size, &c, &err) == MESO_ERR_CORRUPT && strstr(err.message, "TILE"));
        printf("refused: %s\n", err.message);
        free(bad);
        ((uint16_t*)b.cc.tile)[5] = (uint16_t)b.sc.voxel_split[5];
        uint8_t cell_keep[64];
        memcpy(cell_keep, b.cc.cell, 64);
        b.cc.cell[MESO_CELL_OFF_TILE_RES] = (uint8_t)(R / 2); /* R disagrees with TILE's dims */
        bad = write_object(&b.cc, R, S, L, &size);
        const meso_result r = load_mem(bad, size, &c, &err);
        assert(r == MESO_ERR_CORRUPT && (strstr(err.message, "TILE") || strstr(err.message, "MEMB")));
        printf("refused: %s\n", err.message);
        free(bad);
        memcpy(b.cc.cell, cell_keep, 64);
        /* every truncation of MEMB's words and of TILE to a shorter MEMB: refused, never a crash */
        for (uint32_t cut = 1; cut < L && cut < 40; ++cut) {
            bad = write_object(&b.cc, R, S, L - cut, &size);
            assert(load_mem(bad, size, &c, &err) == MESO_ERR_CORRUPT);
            free(bad);
        }
        /* the intact file still loads */
        bad = write_object(&b.cc, R, S, L, &size);
        assert(load_mem(bad, size, &c, &err) == MESO_OK);
        meso_ref_cells_free(&c);
        free(bad);
    }
    free(mem);
    meso_cells_chunks_free(&b.cc);
    meso_membership_free(&b.mb);
    meso_split_cells_free(&b.sc);
    meso_tile_map_free(&b.tm);
    meso_mesh_free(&m);
}

int main(void)
{
    TEST_RUN(traversal_matches_brute_force);
    TEST_RUN(box_first_hit_through_the_renderer);
    TEST_RUN(reflection_floor_to_wall);
    TEST_RUN(refraction_slab_and_tir);
    TEST_RUN(normal_and_direction_fallbacks);
    TEST_RUN(baked_file_loads_and_renders);
    printf("test_cell_reference: ok\n");
    return 0;
}
