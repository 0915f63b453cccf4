/*
 * shell_allowed.c — the thickness the geometry allows per vertex (half the
 * gap along the normal to the next part of the surface) and the share of it
 * a shell keeps. Definition, what it bounds and how it is computed:
 * shell_allowed.h.
 */
#include "shell_allowed.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "triangle_grid.h"
#include "vec3d.h"

/* Möller–Trumbore: the t > 0 at which o + t·u meets triangle (a, b, c),
 * edges and corners included; INFINITY when it does not (or the ray runs
 * in the triangle's plane). */
static double ray_triangle(const double o[3], const double u[3], const double a[3], const double b[3],
                           const double c[3])
{
    double e1[3], e2[3], p[3], s[3], q[3];
    sub3(b, a, e1);
    sub3(c, a, e2);
    cross3(u, e2, p);
    const double det = dot3(e1, p);
    if (det == 0.0)
        return INFINITY;
    const double inv = 1.0 / det;
    sub3(o, a, s);
    const double bu = dot3(s, p) * inv;
    if (bu < 0.0 || bu > 1.0)
        return INFINITY;
    cross3(s, e1, q);
    const double bv = dot3(u, q) * inv;
    if (bv < 0.0 || bu + bv > 1.0)
        return INFINITY;
    const double t = dot3(e2, q) * inv;
    return t > 0.0 ? t : INFINITY;
}

static inline int cell_of(const mesoi_tri_grid* g, int k, double x)
{
    int i = (int)floor((x - g->lo[k]) / g->cell);
    return i < 0 ? 0 : i >= g->dim[k] ? g->dim[k] - 1 : i;
}

/* g_v (shell_allowed.h) up to tmax: the nearest hit of o + t·u, t in
 * (0, tmax], on a triangle without corner v; INFINITY when none. Marches
 * in steps of one cell: every hit point lies in the padded box of the step
 * that contains it, hence in a cell searched then (grid binning and cell_of
 * are monotone in x), so once the best hit is within the steps done, no
 * later step can beat it. */
static double gap_along(const mesoi_tri_grid* g, const double o[3], const double u[3], uint32_t v, double tmax)
{
    const double pad = 1e-9 * g->cell * (g->dim[0] + g->dim[1] + g->dim[2]);
    double best = INFINITY;
    for (double t0 = 0.0; t0 < tmax && best > t0; t0 += g->cell) {
        const double t1 = fmin(t0 + g->cell, tmax);
        int c0[3], c1[3], out = 0;
        for (int k = 0; k < 3; ++k) {
            const double x0 = o[k] + t0 * u[k], x1 = o[k] + t1 * u[k];
            const double a = fmin(x0, x1) - pad, b = fmax(x0, x1) + pad;
            out |= b < g->lo[k] || a > g->lo[k] + g->dim[k] * g->cell;
            c0[k] = cell_of(g, k, a);
            c1[k] = cell_of(g, k, b);
        }
        if (out) /* the ray has left the grid (a convex box) for good */
            break;
        for (int z = c0[2]; z <= c1[2]; ++z)
            for (int y = c0[1]; y <= c1[1]; ++y)
                for (int x = c0[0]; x <= c1[0]; ++x) {
                    const size_t cell = ((size_t)z * g->dim[1] + y) * g->dim[0] + x;
                    for (uint32_t i = g->start[cell]; i < g->start[cell + 1]; ++i) {
                        const uint32_t* t = g->tri + 3 * (size_t)g->items[i];
                        if (t[0] == v || t[1] == v || t[2] == v)
                            continue;
                        const double hit = ray_triangle(o, u, g->xyz + 3 * (size_t)t[0], g->xyz + 3 * (size_t)t[1],
                                                        g->xyz + 3 * (size_t)t[2]);
                        best = hit <= tmax && hit < best ? hit : best;
                    }
                }
        if (best <= t1)
            break;
    }
    return best;
}

meso_result meso_shell_allowed(const meso_mesh* m, const float* normals, int sign, double h, int threads,
                               double* allowed, meso_error* err)
{
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    if (!(h > 0 && isfinite(h)) || (sign != 1 && sign != -1))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "allowed thickness: h must be > 0, sign +-1");
    for (uint32_t v = 0; v < nv; ++v)
        allowed[v] = h;
    if (!nt)
        return MESO_OK;
    double* xyz = malloc(sizeof(double) * 3 * (size_t)nv);
    if (!xyz)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "allowed thickness: out of memory");
    /* The grid covers the mesh and every ray to t = 2h (cells outside
     * the mesh's box are empty but keep the padded steps in range). */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < 3 * (size_t)nv; ++i) {
        xyz[i] = m->positions[i];
        lo[i % 3] = fmin(lo[i % 3], xyz[i]);
        hi[i % 3] = fmax(hi[i % 3], xyz[i]);
    }
    mesoi_tri_grid g;
    meso_result r = mesoi_tri_grid_build(xyz, m->indices, nt, lo, hi, &g, err);
    if (r != MESO_OK) {
        free(xyz);
        return r;
    }
    const long n = (long)nv;
#ifdef _OPENMP
    const int nth = threads > 0 ? threads : omp_get_max_threads();
#pragma omp parallel for schedule(dynamic, 64) num_threads(nth)
#else
    (void)threads;
#endif
    for (long v = 0; v < n; ++v) {
        double u[3];
        for (int k = 0; k < 3; ++k)
            u[k] = sign * (double)normals[3 * v + k];
        if (len3(u) == 0.0)
            continue;
        const double gap = gap_along(&g, xyz + 3 * v, u, (uint32_t)v, 2.0 * h);
        allowed[v] = fmin(h, 0.5 * gap);
    }
    mesoi_tri_grid_free(&g);
    free(xyz);
    return MESO_OK;
}

void meso_shell_allowed_add(const meso_mesh* m, const float* d, const double* allowed, double h,
                            meso_shell_allowed_summary* s, double* ratios)
{
    const uint32_t nv = m->vertex_count;
    if (!s->counted)
        s->ratio_min = 1.0;
    uint8_t* used = calloc(nv ? nv : 1, 1);
    for (size_t j = 0; used && j < 3 * (size_t)m->triangle_count; ++j)
        used[m->indices[j]] = 1;
    for (uint32_t v = 0; v < nv; ++v) {
        const float* dv = d + 3 * (size_t)v;
        const double len = sqrt((double)dv[0] * dv[0] + (double)dv[1] * dv[1] + (double)dv[2] * dv[2]);
        const double q = allowed[v] > 0 ? fmin(1.0, len / allowed[v]) : 1.0;
        const int counted = !used || used[v]; /* (without memory: every vertex) */
        if (ratios)
            ratios[v] = counted ? q : 1.0;
        if (!counted)
            continue;
        s->counted++;
        s->below_half += q < 0.5;
        s->limited += allowed[v] < h;
        s->ratio_min = fmin(s->ratio_min, q);
        s->ratio_sum += q;
    }
    free(used);
}
