/*
 * surface_distance.c — conservative two-sided distance between two meshes'
 * surfaces from dense samples (surface_distance.h says what and why it is
 * an upper bound). The distance queries reuse triangle_grid.c (the grid the
 * skeleton bake measures its two-sided error with); each thread has its own
 * query stamps over the shared cells.
 */
#include "surface_distance.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake_threads.h"
#include "triangle_grid.h"

double meso_mesh_mean_edge(const meso_mesh* m)
{
    double sum = 0;
    for (uint32_t f = 0; f < m->triangle_count; ++f)
        for (int k = 0; k < 3; ++k) {
            const float* a = m->positions + 3 * (size_t)m->indices[3 * (size_t)f + (size_t)k];
            const float* b = m->positions + 3 * (size_t)m->indices[3 * (size_t)f + (size_t)((k + 1) % 3)];
            const double d[3] = {(double)a[0] - b[0], (double)a[1] - b[1], (double)a[2] - b[2]};
            sum += sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        }
    return m->triangle_count ? sum / (3.0 * m->triangle_count) : 0;
}

static double* to_double(const meso_mesh* m)
{
    double* xyz = malloc(sizeof(double) * 3 * (m->vertex_count ? (size_t)m->vertex_count : 1));
    for (size_t i = 0; xyz && i < 3 * (size_t)m->vertex_count; ++i)
        xyz[i] = m->positions[i];
    return xyz;
}

/* One thread's measuring state: the grid with its own query stamps, the
 * largest distance so far and the last measured sample (see measure). */
typedef struct sampler {
    mesoi_tri_grid g; /* shared cells, private stamps */
    double worst;
    int known;
    uint32_t known_tri;
    double known_d, known_p[3];
} sampler;

/* Only the largest distance is wanted, and the distance to a set is
 * 1-Lipschitz: d(p) <= d(q) + |p - q| for the last sample q this thread
 * measured, and d(p) <= the distance from p to q's nearest triangle. A
 * sample whose bound is not above the thread's largest so far cannot raise
 * the result, so it is not measured. The Lipschitz bound is widened by 16
 * ulps, so that its rounding can never skip a sample whose computed
 * distance is larger (the nearest-triangle bound is the same computation a
 * query makes). The result is bit for bit the one measuring every sample
 * gives (the max of the same numbers), whatever the thread count; on a
 * coarse level, whose error is many sample spacings, most samples are
 * skipped. Measured on a bumpy 180k-triangle torus (`mesobake mesh -j 1`, 8
 * levels, user CPU): 20.0 s before; 13.5 s with triangle_grid.c's finer
 * cells; 9.7 s with the Lipschitz bound; 6.2 s with the nearest-triangle
 * bound too. On 980k triangles (-j 2): 265 s -> 24 s wall. */
static void measure(sampler* m, const double p[3])
{
    if (m->known &&
        ((m->known_d + sqrt((p[0] - m->known_p[0]) * (p[0] - m->known_p[0]) +
                            (p[1] - m->known_p[1]) * (p[1] - m->known_p[1]) +
                            (p[2] - m->known_p[2]) * (p[2] - m->known_p[2]))) *
                 (1 + 16 * DBL_EPSILON) <=
             m->worst ||
         mesoi_tri_grid_triangle_distance(&m->g, m->known_tri, p) <= m->worst))
        return;
    double bw[2];
    const double d = mesoi_tri_grid_closest(&m->g, p, &m->known_tri, bw);
    m->worst = d > m->worst ? d : m->worst;
    m->known = 1, m->known_d = d;
    memcpy(m->known_p, p, 3 * sizeof(double));
}

/* Largest distance from the samples of `a`'s triangles to the grid's mesh;
 * *radius gets the largest sub-triangle edge / sqrt(3). The corners of the
 * sub-triangles that are the triangles' own vertices are measured once per
 * vertex (at the vertex's own coordinates), not once per triangle: on a
 * fine mesh whose triangles are smaller than the spacing they are all the
 * samples there are, and each vertex has about six triangles.
 * `used` (vertex count bytes, zeroed) is scratch. */
static double one_way(const double* axyz, uint32_t anv, const uint32_t* atri, uint32_t ant, const mesoi_tri_grid* g,
                      double spacing, int threads, uint8_t* used, double* radius, int* oom)
{
    double worst = 0, rad = 0;
    const int nth = meso_bake_thread_count(threads);
    int failed = 0;
    for (size_t i = 0; i < 3 * (size_t)ant; ++i)
        used[atri[i]] = 1;
#ifdef _OPENMP
#pragma omp parallel num_threads(nth) reduction(max : worst, rad) reduction(| : failed)
#endif
    {
        sampler m = {.g = *g};
        m.g.stamp = calloc(g->nt ? g->nt : 1, sizeof(uint32_t));
        m.g.query = 0;
        if (!m.g.stamp)
            failed = 1;
#ifdef _OPENMP
#pragma omp for schedule(dynamic, 256)
#endif
        for (int64_t v = 0; v < (int64_t)anv; ++v)
            if (m.g.stamp && used[v])
                measure(&m, axyz + 3 * (size_t)v);
#ifdef _OPENMP
#pragma omp for schedule(dynamic, 64)
#endif
        for (int64_t f = 0; f < (int64_t)ant; ++f) {
            if (!m.g.stamp)
                continue;
            const double* v[3];
            for (int k = 0; k < 3; ++k)
                v[k] = axyz + 3 * (size_t)atri[3 * (size_t)f + (size_t)k];
            double longest = 0;
            for (int k = 0; k < 3; ++k) {
                const double* p = v[k];
                const double* q = v[(k + 1) % 3];
                const double d = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                                      (p[2] - q[2]) * (p[2] - q[2]));
                longest = d > longest ? d : longest;
            }
            const double nd = ceil(longest / spacing);
            const int n = nd < 1 ? 1 : nd > 4096 ? 4096 : (int)nd;
            const double r = longest / n / sqrt(3.0);
            rad = r > rad ? r : rad;
            for (int i = 0; i <= n; ++i)
                for (int j = 0; j <= n - i; ++j) {
                    if ((i == 0 || i == n) && (j == 0 || j == n - i))
                        continue; /* a corner of the triangle: measured above */
                    const double s = (double)i / n, t = (double)j / n;
                    double p[3];
                    for (int k = 0; k < 3; ++k)
                        p[k] = v[0][k] + s * (v[1][k] - v[0][k]) + t * (v[2][k] - v[0][k]);
                    measure(&m, p);
                }
        }
        free(m.g.stamp);
        worst = m.worst > worst ? m.worst : worst;
    }
#ifndef _OPENMP
    (void)nth;
#endif
    memset(used, 0, anv);
    *radius = rad;
    *oom = failed;
    return worst;
}

/* Both ways between a (samples axyz, grid ga) and b: the bound of the
 * header. `used` holds max(a, b vertex count) zeroed bytes. */
static meso_result both_ways(const meso_mesh* a, const double* axyz, const mesoi_tri_grid* ga, const meso_mesh* b,
                             const double* bxyz, const mesoi_tri_grid* gb, double spacing, int threads, uint8_t* used,
                             double* bound, double* radius)
{
    double ra = 0, rb = 0;
    int oom_a = 0, oom_b = 0;
    const double dab = one_way(axyz, a->vertex_count, a->indices, a->triangle_count, gb, spacing, threads, used, &ra,
                               &oom_a);
    const double dba = one_way(bxyz, b->vertex_count, b->indices, b->triangle_count, ga, spacing, threads, used, &rb,
                               &oom_b);
    const double rad = ra > rb ? ra : rb;
    *bound = (dab > dba ? dab : dba) + rad;
    if (radius)
        *radius = rad;
    return oom_a || oom_b ? MESO_ERR_OUT_OF_MEMORY : MESO_OK;
}

static meso_result check_args(const meso_mesh* a, const meso_mesh* b, double spacing, meso_error* err)
{
    if (!a || !b || !a->triangle_count || !b->triangle_count || !(spacing > 0))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "surface distance: empty mesh or spacing not > 0");
    return MESO_OK;
}

static meso_result oom(meso_error* err)
{
    return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "measuring a level's error: out of memory");
}

/* The reference over [lo, hi] (which holds m and every mesh measured
 * against it). */
static meso_result ref_build_over(const meso_mesh* m, const double lo[3], const double hi[3], meso_surface_ref* ref,
                                  meso_error* err)
{
    memset(ref, 0, sizeof *ref);
    if (!m || !m->triangle_count)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "surface distance: empty reference mesh");
    ref->mesh = m;
    memcpy(ref->lo, lo, sizeof ref->lo);
    memcpy(ref->hi, hi, sizeof ref->hi);
    ref->xyz = to_double(m);
    meso_result r = ref->xyz ? MESO_OK : oom(err);
    if (r == MESO_OK && (r = mesoi_tri_grid_build(ref->xyz, m->indices, m->triangle_count, ref->lo, ref->hi,
                                                  &ref->grid, err)) == MESO_OK)
        ref->built = 1;
    if (r != MESO_OK)
        meso_surface_ref_free(ref);
    return r;
}

/* Both meshes' grids over both boxes: b as a reference over the union. */
meso_result meso_surface_distance(const meso_mesh* a, const meso_mesh* b, double spacing, int threads, double* bound,
                                  double* radius, meso_error* err)
{
    meso_result r = check_args(a, b, spacing, err);
    if (r != MESO_OK)
        return r;
    double lo[3], hi[3], lo2[3], hi2[3];
    meso_mesh_bounds(a, lo, hi);
    meso_mesh_bounds(b, lo2, hi2);
    for (int k = 0; k < 3; ++k) {
        lo[k] = lo2[k] < lo[k] ? lo2[k] : lo[k];
        hi[k] = hi2[k] > hi[k] ? hi2[k] : hi[k];
    }
    meso_surface_ref ref;
    if ((r = ref_build_over(b, lo, hi, &ref, err)) != MESO_OK)
        return r;
    r = meso_surface_distance_to_ref(a, &ref, spacing, threads, bound, radius, err);
    meso_surface_ref_free(&ref);
    return r;
}

meso_result meso_surface_ref_build(const meso_mesh* m, meso_surface_ref* ref, meso_error* err)
{
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    if (m)
        meso_mesh_bounds(m, lo, hi);
    return ref_build_over(m, lo, hi, ref, err);
}

meso_result meso_surface_distance_to_ref(const meso_mesh* a, const meso_surface_ref* ref, double spacing,
                                         int threads, double* bound, double* radius, meso_error* err)
{
    meso_result r = check_args(a, ref ? ref->mesh : NULL, spacing, err);
    if (r != MESO_OK)
        return r;
    double lo[3], hi[3];
    meso_mesh_bounds(a, lo, hi);
    for (int k = 0; k < 3; ++k)
        if (lo[k] < ref->lo[k] || hi[k] > ref->hi[k]) /* outside the reference's grid */
            return meso_surface_distance(a, ref->mesh, spacing, threads, bound, radius, err);
    double* axyz = to_double(a);
    uint8_t* used = calloc(a->vertex_count > ref->mesh->vertex_count ? a->vertex_count : ref->mesh->vertex_count, 1);
    mesoi_tri_grid ga;
    r = axyz && used ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    if (r == MESO_OK &&
        (r = mesoi_tri_grid_build(axyz, a->indices, a->triangle_count, ref->lo, ref->hi, &ga, err)) == MESO_OK) {
        r = both_ways(a, axyz, &ga, ref->mesh, ref->xyz, &ref->grid, spacing, threads, used, bound, radius);
        mesoi_tri_grid_free(&ga);
    }
    free(axyz);
    free(used);
    return r == MESO_ERR_OUT_OF_MEMORY ? oom(err) : r;
}

void meso_surface_ref_free(meso_surface_ref* ref)
{
    if (ref->built)
        mesoi_tri_grid_free(&ref->grid);
    free(ref->xyz);
    memset(ref, 0, sizeof *ref);
}
