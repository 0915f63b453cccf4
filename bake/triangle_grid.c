/*
 * triangle_grid.c — exact point-to-mesh distance: a uniform grid of
 * triangles and Ericson's closest point on a triangle (triangle_grid.h).
 * meso_skeleton_from_mesh measures the model -> mesh direction with it
 * (skeleton_model.c, mesoi_model_to_mesh).
 *
 * Why not CGAL's AABB tree (issue 20 asked to measure it): an AABB_tree of
 * AABB_triangle_primitive (CGAL 5.5.1, Epick, accelerate_distance_queries,
 * sqrt of squared_distance) on the same sample points as mesoi_model_to_mesh,
 * `mesobake frusta -i MESH`, build + queries, median of 5 runs (gcc 12 -O2,
 * a shared 2-core machine, so +-20 %):
 *
 *   mesh (triangles, samples)        grid      AABB tree   distances differing
 *   torus.obj (4608, 15735)          22.9 ms   33.8 ms     13289 (<= 4.9e-16)
 *   spot_low_resolution (1654, 5858)  9.1 ms   13.8 ms      4523 (<= 2.8e-16)
 *   bunny.obj (6598, 6627)           57.3 ms   43.7 ms      4029 (<= 3.1e-16)
 *   armadillo.obj (29170, 7647)      48.6 ms   62.6 ms      5960 (<= 3.3e-16)
 *
 * The tree constructs its closest point in another order, so most distances
 * differ in the last bits, and on the torus and spot so does the largest,
 * which the frusta bake writes (frusta_to_mesh_max in the report chunk): the
 * bytes would change. The grid is also faster on three of the four meshes
 * (the bunny, fitted to 10 % of its diagonal, has samples far from the
 * surface, where the grid's shells grow). So the grid stays.
 */
#include "triangle_grid.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "skeleton_from_mesh_internal.h" /* mesoi_dist_at */

/* Exact distance from p to triangle (a, b, c): the closest point by Voronoi
 * regions (Ericson, "Real-Time Collision Detection", 5.1.5). The closest
 * point's barycentrics of b and c go to bw[0], bw[1] (the distance is
 * computed as it always was, so bakes that write it keep their bytes). */
static double point_triangle_distance(const double p[3], const double a[3], const double b[3], const double c[3],
                                      double bw[2])
{
    double ab[3], ac[3], ap[3], bp[3], cp[3], q[3];
    sub3(b, a, ab);
    sub3(c, a, ac);
    sub3(p, a, ap);
    const double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
    bw[0] = bw[1] = 0;
    if (d1 <= 0 && d2 <= 0)
        return dist3(p, a);
    sub3(p, b, bp);
    const double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
    bw[0] = 1;
    if (d3 >= 0 && d4 <= d3)
        return dist3(p, b);
    const double vc = d1 * d4 - d3 * d2;
    bw[0] = d1 / (d1 - d3);
    if (vc <= 0 && d1 >= 0 && d3 <= 0)
        return mesoi_dist_at(a, b, bw[0], p);
    sub3(p, c, cp);
    const double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
    bw[0] = 0, bw[1] = 1;
    if (d6 >= 0 && d5 <= d6)
        return dist3(p, c);
    const double vb = d5 * d2 - d1 * d6;
    bw[1] = d2 / (d2 - d6);
    if (vb <= 0 && d2 >= 0 && d6 <= 0)
        return mesoi_dist_at(a, c, bw[1], p);
    const double va = d3 * d6 - d5 * d4;
    bw[1] = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    bw[0] = 1 - bw[1];
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return mesoi_dist_at(b, c, bw[1], p);
    const double den = 1 / (va + vb + vc), v = vb * den, w = vc * den;
    bw[0] = v, bw[1] = w;
    for (int k = 0; k < 3; ++k)
        q[k] = a[k] + ab[k] * v + ac[k] * w;
    return dist3(p, q);
}

double mesoi_tri_grid_triangle_distance(const mesoi_tri_grid* g, uint32_t f, const double p[3])
{
    const uint32_t* t = g->tri + 3 * (size_t)f;
    double bw[2];
    return point_triangle_distance(p, g->xyz + 3 * (size_t)t[0], g->xyz + 3 * (size_t)t[1], g->xyz + 3 * (size_t)t[2],
                                   bw);
}

void mesoi_tri_grid_free(mesoi_tri_grid* g)
{
    free(g->start);
    free(g->items);
    free(g->stamp);
}

static inline int grid_coord(const mesoi_tri_grid* g, int k, double x)
{
    int i = (int)floor((x - g->lo[k]) / g->cell);
    return i < 0 ? 0 : i >= g->dim[k] ? g->dim[k] - 1 : i;
}

/* The grid covers [lo, hi] (the mesh and every query point). */
meso_result mesoi_tri_grid_build(const double* xyz, const uint32_t* tri, uint32_t nt, const double lo[3],
                                 const double hi[3], mesoi_tri_grid* g, meso_error* err)
{
    memset(g, 0, sizeof(*g));
    g->xyz = xyz;
    g->tri = tri;
    g->nt = nt;
    double ext = 0;
    for (int k = 0; k < 3; ++k)
        ext = hi[k] - lo[k] > ext ? hi[k] - lo[k] : ext;
    /* About one triangle per surface cell: sqrt(triangles) cells along the
     * longest side, and at most GRID_CELLS_MAX cells in all (64 MiB of
     * starts), the cells grown by 1/8 at a time until they fit. The cap
     * was 160 cells a side: a 1M-triangle mesh then held ~20 triangles a
     * cell and a query tested ~600, which made measuring its levels' errors
     * take minutes (mesh_levels.c); 2^22 cells took 1.4x the CPU of 2^24
     * on 980k triangles. The price: up to 64 MiB of starts per grid, and
     * surface_distance.c holds two, or three while a chain measures its
     * levels against level 0's (the --max-memory estimates do not count
     * them yet). And at most 32 cells per triangle: sqrt(triangles) a side
     * is ~triangles^1.5 cells, and on 106k triangles the grid was 160 per
     * triangle, most of them empty, and building the chain's grids (page
     * faults and prefix sums over 64 MiB) took 1.5 s of a 5 s shell bake;
     * 32 gave 3.3 s with the same bytes, and 16 cost 15 % more CPU on a
     * 467k-triangle mesh's levels (`mesobake mesh --levels auto`).
     * Which cells a query visits changes
     * nothing it returns: the distance is exact and ties go to the lowest
     * triangle whatever the order. */
    enum { GRID_CELLS_MAX = 1 << 24, GRID_CELLS_PER_TRIANGLE = 32 };
    int res = (int)ceil(sqrt((double)g->nt));
    res = res < 4 ? 4 : res;
    g->cell = ext > 0 ? ext / res : 1;
    for (;;) {
        double cells_d = 1;
        for (int k = 0; k < 3; ++k) {
            g->lo[k] = lo[k];
            g->dim[k] = (int)floor((hi[k] - lo[k]) / g->cell) + 1;
            cells_d *= g->dim[k];
        }
        if (cells_d <= GRID_CELLS_MAX && cells_d <= GRID_CELLS_PER_TRIANGLE * (double)(g->nt > 4 ? g->nt : 4))
            break;
        g->cell *= 1.125;
    }
    const size_t cells = (size_t)g->dim[0] * g->dim[1] * g->dim[2];
    g->start = calloc(cells + 1, sizeof(uint32_t));
    g->stamp = calloc(g->nt ? g->nt : 1, sizeof(uint32_t));
    if (!g->start || !g->stamp)
        goto oom;
    for (int pass = 0; pass < 2; ++pass) {
        for (uint32_t f = 0; f < g->nt; ++f) {
            int b0[3], b1[3];
            for (int k = 0; k < 3; ++k) {
                double mn = DBL_MAX, mx = -DBL_MAX;
                for (int j = 0; j < 3; ++j) {
                    const double x = g->xyz[3 * (size_t)g->tri[3 * f + j] + k];
                    mn = x < mn ? x : mn;
                    mx = x > mx ? x : mx;
                }
                b0[k] = grid_coord(g, k, mn);
                b1[k] = grid_coord(g, k, mx);
            }
            for (int z = b0[2]; z <= b1[2]; ++z)
                for (int y = b0[1]; y <= b1[1]; ++y)
                    for (int x = b0[0]; x <= b1[0]; ++x) {
                        const size_t cell = ((size_t)z * g->dim[1] + y) * g->dim[0] + x;
                        if (pass == 0)
                            g->start[cell + 1]++;
                        else
                            g->items[g->start[cell]++] = f;
                    }
        }
        if (pass == 0) {
            for (size_t i = 0; i < cells; ++i)
                g->start[i + 1] += g->start[i];
            g->items = malloc(sizeof(uint32_t) * (g->start[cells] ? g->start[cells] : 1));
            if (!g->items)
                goto oom;
        } else {
            for (size_t i = cells; i > 0; --i) /* the fill advanced each start to the next one's */
                g->start[i] = g->start[i - 1];
            g->start[0] = 0;
        }
    }
    return MESO_OK;
oom:
    mesoi_tri_grid_free(g);
    return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
}

/* Unsigned distance from p to the mesh. After the cells within Chebyshev
 * distance k of p's cell are done, every other triangle is farther than
 * k * cell, so the search stops once the best is no more than that. */
double mesoi_tri_grid_distance(mesoi_tri_grid* g, const double p[3])
{
    uint32_t tri;
    double bw[2];
    return mesoi_tri_grid_closest(g, p, &tri, bw);
}

static double closest_within(mesoi_tri_grid* g, const double p[3], double r, uint32_t* tri, double bw[2]);

double mesoi_tri_grid_closest(mesoi_tri_grid* g, const double p[3], uint32_t* tri, double bw[2])
{
    return closest_within(g, p, INFINITY, tri, bw);
}

double mesoi_tri_grid_distance_within(mesoi_tri_grid* g, const double p[3], double r)
{
    uint32_t tri;
    double bw[2];
    return closest_within(g, p, r, &tri, bw);
}

/* Shells of cells around p until every triangle nearer than the best so
 * far, or than r, has been seen. */
static double closest_within(mesoi_tri_grid* g, const double p[3], double r, uint32_t* tri, double bw[2])
{
    int ci[3];
    for (int k = 0; k < 3; ++k)
        ci[k] = grid_coord(g, k, p[k]);
    const int kmax = g->dim[0] > g->dim[1] ? (g->dim[0] > g->dim[2] ? g->dim[0] : g->dim[2])
                                            : (g->dim[1] > g->dim[2] ? g->dim[1] : g->dim[2]);
    double best = DBL_MAX, w[2];
    *tri = UINT32_MAX;
    bw[0] = bw[1] = 0;
    ++g->query;
    for (int k = 0; k <= kmax; ++k) {
        for (int z = ci[2] - k; z <= ci[2] + k; ++z) {
            if (z < 0 || z >= g->dim[2])
                continue;
            for (int y = ci[1] - k; y <= ci[1] + k; ++y) {
                if (y < 0 || y >= g->dim[1])
                    continue;
                const int shell_yz = abs(z - ci[2]) == k || abs(y - ci[1]) == k;
                for (int x = ci[0] - k; x <= ci[0] + k; x += shell_yz ? 1 : 2 * k) {
                    if (x >= 0 && x < g->dim[0]) {
                        const size_t cell = ((size_t)z * g->dim[1] + y) * g->dim[0] + x;
                        for (uint32_t i = g->start[cell]; i < g->start[cell + 1]; ++i) {
                            const uint32_t f = g->items[i];
                            if (g->stamp[f] == g->query)
                                continue;
                            g->stamp[f] = g->query;
                            const uint32_t* t = g->tri + 3 * (size_t)f;
                            const double d = point_triangle_distance(p, g->xyz + 3 * (size_t)t[0],
                                                                     g->xyz + 3 * (size_t)t[1], g->xyz + 3 * (size_t)t[2], w);
                            if (d < best || (d == best && f < *tri)) { /* ties: the lowest triangle, whatever the order */
                                best = d;
                                *tri = f;
                                bw[0] = w[0], bw[1] = w[1];
                            }
                        }
                    }
                    if (k == 0)
                        break;
                }
            }
        }
        if (best <= k * g->cell || r <= k * g->cell)
            break;
    }
    return best;
}

