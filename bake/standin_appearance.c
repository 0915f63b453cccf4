/*
 * standin_appearance.c — see standin_appearance.h.
 *
 * Decided here (the papers have no stand-ins; issue 14 asks for "baked
 * normal/colour"): a stand-in carries one albedo and one occlusion per
 * vertex, interpolated across its triangles, not a texture. A stand-in is
 * drawn only where its geometric error is at most the pixel budget, so the
 * object covers few pixels per stand-in triangle and what is left to show
 * is the mean colour of each vertex's neighbourhood: a hat-weighted mean
 * (the L2 projection onto the piecewise-linear colours with a lumped mass
 * matrix), not a point sample, which would alias on bricks. A kind that
 * says so (a shell) also gives its surface's normal, and a stand-in vertex
 * takes the hat-weighted mean of it, normalised: where the relief tilts
 * over a vertex's part of the surface (a slope, a large bump, anything
 * coarser than the stand-in's triangles) the stand-in shades as that part
 * faces, where its own geometry (the base mesh, the mid-surface) is flat
 * (tests/integration/test_shell_standin_normals.c). What varies within
 * the part — bricks' mortar, texel-sized bumps — a mean normal cannot
 * show: the mean of Lambert shadings is not the shading of the mean
 * normal, and that error is measured, not bounded (test_rt_standin_colour).
 * Kinds without normals (cells, frusta) keep the stand-in's own.
 *
 * Each triangle's sums are computed on its own (in parallel) and added
 * into its vertices in triangle order afterwards, so the bytes do not
 * depend on the thread count.
 */
#include "standin_appearance.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake_threads.h"
#include "srgb.h"

enum { DEFAULT_SUBDIVISIONS = 4, SUMS = 8 }; /* per corner: w occ albedo (3), w occ, w, w normal (3) */

/* About this many samples a level at most: a large mesh's triangles get
 * fewer sub-triangles, at least 2 x 2 on the base stand-in (about 24
 * samples around a vertex of what the kind shows) and 1 on a simplified
 * level (which reads the base stand-in's colours, smooth already: about 6
 * around a vertex). The colours of a 94k-triangle brick shell's 7
 * stand-ins took 2.4 s with 8 x 8 everywhere (README, "Stand-ins show
 * their object's colours"). */
#define SAMPLE_BUDGET_BASE 131072.0
#define SAMPLE_BUDGET_SIMPLIFIED 32768.0

static double edge(const float* a, const float* b)
{
    const double d[3] = {(double)a[0] - b[0], (double)a[1] - b[1], (double)a[2] - b[2]};
    return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* A thread's copy of a grid: the cells shared, the query stamps its own. */
static int grid_copy(const mesoi_tri_grid* g, mesoi_tri_grid* out)
{
    if (!g)
        return 1;
    *out = *g;
    out->query = 0;
    out->stamp = calloc(g->nt ? g->nt : 1, sizeof(uint32_t));
    return out->stamp != NULL;
}

/* Triangle t's sums over its sub-triangle centroids, SUMS per corner. */
static void triangle_sums(const meso_mesh* m, uint32_t t, double spacing, int most, const mesoi_appearance* a,
                          mesoi_tri_grid* mine_a, mesoi_tri_grid* mine_src, double* s)
{
    const uint32_t* ix = m->indices + 3 * (size_t)t;
    const float* P[3] = {m->positions + 3 * (size_t)ix[0], m->positions + 3 * (size_t)ix[1],
                         m->positions + 3 * (size_t)ix[2]};
    const double longest = fmax(edge(P[0], P[1]), fmax(edge(P[1], P[2]), edge(P[2], P[0])));
    const double q = spacing > 0 ? ceil(longest / spacing) : 1;
    const int n = q < 1 || !isfinite(q) ? 1 : q > most ? most : (int)q;
    memset(s, 0, sizeof(double) * 3 * SUMS);
    /* The n² sub-triangles of equal area: (i, j) upright with centroid
     * ((i + 1/3), (j + 1/3)) / n and, where i + j < n - 1, the inverted one
     * at ((i + 2/3), (j + 2/3)) / n, in the coordinates of corners 1, 2. */
    for (int j = 0; j < n; ++j)
        for (int i = 0; i + j < n; ++i)
            for (int inv = 0; inv < 2; ++inv) {
                if (inv && i + j >= n - 1)
                    continue;
                const double off = inv ? 2.0 / 3.0 : 1.0 / 3.0;
                const double b1 = (i + off) / n, b2 = (j + off) / n, b[3] = {1 - b1 - b2, b1, b2};
                double p[3];
                for (int k = 0; k < 3; ++k)
                    p[k] = b[0] * P[0][k] + b[1] * P[1][k] + b[2] * P[2][k];
                float v[7] = {0, 0, 0, 0, 0, 0, 0};
                if (mine_src) { /* a simplified level: what the base stand-in shows nearest */
                    uint32_t bt = 0;
                    double bw[2] = {0, 0};
                    mesoi_tri_grid_closest(mine_src, p, &bt, bw);
                    const double bb[3] = {1 - bw[0] - bw[1], bw[0], bw[1]};
                    const uint32_t* bi = mine_src->tri + 3 * (size_t)bt;
                    double bp[3];
                    for (int k = 0; k < 3; ++k)
                        bp[k] = bb[0] * mine_src->xyz[3 * (size_t)bi[0] + k] + bb[1] * mine_src->xyz[3 * (size_t)bi[1] + k] +
                                bb[2] * mine_src->xyz[3 * (size_t)bi[2] + k];
                    a->at(a, mine_a, bt, bb, bp, v);
                } else {
                    a->at(a, mine_a, t, b, p, v);
                }
                if (v[3] < 0) /* nothing drawn there */
                    continue;
                for (int c = 0; c < 3; ++c) {
                    double* sc = s + SUMS * c;
                    for (int k = 0; k < 3; ++k)
                        sc[k] += b[c] * (double)v[3] * (double)v[k];
                    sc[3] += b[c] * (double)v[3];
                    sc[4] += b[c];
                    for (int k = 0; k < 3; ++k)
                        sc[5 + k] += b[c] * (double)v[4 + k];
                }
            }
    /* Every sub-triangle has the same area: the triangle's over n². */
    const double d1[3] = {(double)P[1][0] - P[0][0], (double)P[1][1] - P[0][1], (double)P[1][2] - P[0][2]};
    const double d2[3] = {(double)P[2][0] - P[0][0], (double)P[2][1] - P[0][1], (double)P[2][2] - P[0][2]};
    const double cr[3] = {d1[1] * d2[2] - d1[2] * d2[1], d1[2] * d2[0] - d1[0] * d2[2], d1[0] * d2[1] - d1[1] * d2[0]};
    const double area = 0.5 * sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]) / ((double)n * n);
    for (int k = 0; k < 3 * SUMS; ++k)
        s[k] *= area;
}

/* Copies of one vertex (the same position and normal: a uv seam splits a
 * smooth surface's vertices, a crease's copies have other normals) pool
 * their sums, so the two sides of a seam get one colour, not each its own
 * side's. In position order, ties by index: the same sums whatever the
 * order the copies come in. Returns 0 when out of memory. */
typedef struct vkey {
    float p[6];
    uint32_t v;
} vkey;

static int vkey_cmp(const void* a, const void* b)
{
    const vkey *x = a, *y = b;
    for (int k = 0; k < 6; ++k)
        if (x->p[k] != y->p[k])
            return x->p[k] < y->p[k] ? -1 : 1;
    return (x->v > y->v) - (x->v < y->v);
}

static int same_place(const vkey* a, const vkey* b)
{
    for (int k = 0; k < 6; ++k)
        if (a->p[k] != b->p[k])
            return 0;
    return 1;
}

static int pool_copies(const meso_mesh* m, double* acc)
{
    vkey* keys = malloc(sizeof *keys * (m->vertex_count ? m->vertex_count : 1));
    if (!keys)
        return 0;
    for (uint32_t v = 0; v < m->vertex_count; ++v) {
        for (int k = 0; k < 3; ++k) {
            keys[v].p[k] = m->positions[3 * (size_t)v + k];
            keys[v].p[3 + k] = m->normals ? m->normals[3 * (size_t)v + k] : 0.0f;
        }
        keys[v].v = v;
    }
    qsort(keys, m->vertex_count, sizeof *keys, vkey_cmp);
    for (uint32_t i = 0, j; i < m->vertex_count; i = j) {
        double pooled[SUMS] = {0};
        for (j = i; j < m->vertex_count && same_place(&keys[j], &keys[i]); ++j)
            for (int k = 0; k < SUMS; ++k)
                pooled[k] += acc[SUMS * (size_t)keys[j].v + k];
        if (j - i > 1)
            for (uint32_t q = i; q < j; ++q)
                memcpy(acc + SUMS * (size_t)keys[q].v, pooled, sizeof pooled);
    }
    free(keys);
    return 1;
}

meso_result mesoi_vertex_appearance(const meso_mesh* m, double spacing, const mesoi_appearance* a,
                                    const mesoi_tri_grid* source_grid, int threads, float* shows, float* normals,
                                    meso_error* err)
{
    double* sums = malloc(sizeof(double) * 3 * SUMS * (m->triangle_count ? m->triangle_count : 1));
    if (!sums)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "stand-in appearance: out of memory");
    int bad = 0;
    const int nth = meso_bake_thread_count(threads);
    /* The most sub-triangles along an edge: the kind's, within the budget. */
    const int kind_most = a->subdivisions > 0 ? a->subdivisions : DEFAULT_SUBDIVISIONS;
    const double budget = source_grid ? SAMPLE_BUDGET_SIMPLIFIED : SAMPLE_BUDGET_BASE;
    const int least = source_grid ? 1 : 2;
    const double fit = floor(sqrt(budget / (m->triangle_count ? m->triangle_count : 1)));
    const int most = fit < least ? (kind_most < least ? kind_most : least) : fit < kind_most ? (int)fit : kind_most;
#ifdef _OPENMP
#pragma omp parallel num_threads(nth) reduction(| : bad)
#else
    (void)nth;
#endif
    {
        mesoi_tri_grid ga, gs;
        const int ok_a = grid_copy(a->grid, &ga), ok_s = grid_copy(source_grid, &gs);
        bad |= !ok_a || !ok_s;
#ifdef _OPENMP
#pragma omp for schedule(dynamic, 64)
#endif
        for (int64_t t = 0; t < (int64_t)m->triangle_count; ++t)
            if (ok_a && ok_s)
                triangle_sums(m, (uint32_t)t, spacing, most, a, a->grid ? &ga : NULL, source_grid ? &gs : NULL,
                              sums + 3 * SUMS * (size_t)t);
        if (a->grid)
            free(ga.stamp);
        if (source_grid)
            free(gs.stamp);
    }
    double* acc = bad ? NULL : calloc((size_t)m->vertex_count * SUMS, sizeof(double));
    if (!acc) {
        free(sums);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "stand-in appearance: out of memory");
    }
    for (uint32_t t = 0; t < m->triangle_count; ++t)
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < SUMS; ++k)
                acc[SUMS * (size_t)m->indices[3 * (size_t)t + c] + k] += sums[3 * SUMS * (size_t)t + SUMS * c + k];
    if (!pool_copies(m, acc)) {
        free(acc);
        free(sums);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "stand-in appearance: out of memory");
    }
    for (uint32_t v = 0; v < m->vertex_count; ++v) {
        const double* s = acc + SUMS * (size_t)v;
        float* o = shows + 4 * (size_t)v;
        /* A vertex on no triangle, or on only degenerate ones, or whose
         * every sample showed nothing (the empty columns of a volume
         * shell): mid grey, not darkened; fully occluded: black. */
        for (int k = 0; k < 3; ++k)
            o[k] = (float)(s[3] > 0 ? s[k] / s[3] : s[4] > 0 ? 0 : 0.5);
        o[3] = (float)(s[4] > 0 ? s[3] / s[4] : 1);
        if (normals) {
            const double len = sqrt(s[5] * s[5] + s[6] * s[6] + s[7] * s[7]);
            for (int k = 0; k < 3; ++k)
                normals[3 * (size_t)v + k] = len > 1e-12 ? (float)(s[5 + k] / len)
                                             : m->normals ? m->normals[3 * (size_t)v + k]
                                                          : 0.0f;
        }
    }
    free(acc);
    free(sums);
    return MESO_OK;
}

void mesoi_appearance_encode(const float* shows, uint32_t vertex_count, int components, uint8_t* out)
{
    for (size_t v = 0; v < vertex_count; ++v) {
        const float* s = shows + 4 * v;
        uint8_t* o = out + (size_t)components * v;
        if (components == 4)
            for (int k = 0; k < 3; ++k)
                o[k] = (uint8_t)lrint(255 * meso_linear_to_srgb(s[k]));
        o[components - 1] = (uint8_t)lrint(255 * (s[3] < 0 ? 0 : s[3] > 1 ? 1 : s[3]));
    }
}
