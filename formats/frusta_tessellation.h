/*
 * frusta_tessellation.h — a triangle mesh of a frusta object's surface
 * (FORMAT.md §7.2 kind 4): each frustum's lateral surface sampled on a
 * (u, v) grid and triangulated, flagged caps as fans, balls as
 * latitude–longitude spheres. Shared by the baker (a frusta object's mesh
 * stand-in level, bake/frusta_standin.c) and the CPU references
 * (runtime/reference/frusta_tessellate.h: the benchmarks' polygon baseline
 * and `mesoinspect export`), so both tessellate the same way.
 *
 * The grid point (u, v) of a frustum lies on the parallel cone r(y) + δ,
 * δ = h(s, t) · relief_depth, through it: angle φ = 2π (u + u_offset) −
 * v · twist around the axis, and the axial coordinate y = y0 + v (y1 − y0)
 * between where that cone's generator meets the two planes — the exact
 * inverse of the reference's (u, v) (frustum_reference.h), so a finer grid
 * converges to the surface the reference renders. h is the caller's height
 * function at the relief coordinates (s, t) = (u · u_scale, v_offset +
 * v · v_scale); none (NULL) or a frustum with relief_depth 0: δ = 0.
 * Normals are central differences of the grid (outward). Neighbouring
 * frusta meet at the joint plane along the same curve, but their grids do
 * not share vertices (u frames agree at one point only), so a coarse
 * tessellation can show hairline cracks there, as it would in an engine.
 *
 * For a fixed (u, v) the point is affine in δ (y0 and y1 are, see
 * meso_frustum_rec_cut, and the point is affine in y and δ) and, without
 * twist, affine in v for a fixed u (a generator): bake/frusta_standin.c
 * bounds its error with both facts.
 */
#ifndef MESO_FRUSTA_TESSELLATION_H
#define MESO_FRUSTA_TESSELLATION_H

#include <stdint.h>

#include "frusta_pose.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Relief height in [0, 1] at texture coordinates (s, t). */
typedef double (*meso_frusta_height_fn)(const void* ctx, double s, double t);

/* A height function of one height everywhere: *(const double*)ctx. */
double meso_frusta_height_constant(const void* ctx, double s, double t);

/* An indexed triangle mesh (malloc'd arrays; free with meso_frusta_tess_free). */
typedef struct meso_frusta_tess_mesh {
    uint32_t vertex_count, index_count;
    float* positions; /* 3 per vertex */
    float* normals;   /* 3 per vertex, unit (0 where the grid degenerates) */
    uint32_t* owner;  /* per vertex: frustum i (its lateral grid or caps) < count, else ball count + j */
    float* uv;        /* 2 per vertex: its grid's (u, v) (a frustum's as meso_frusta_tess_point takes them,
                         a ball's latitude-longitude ones); a cap's vertex: (u, -1) at end 0, (u, 2) at
                         end 1 (its rim point's u; v outside [0, 1] says it is a cap's) */
    uint32_t* indices;
} meso_frusta_tess_mesh;

/* The grid of every part. */
typedef struct meso_frusta_tess_grid {
    const uint32_t* nu;      /* per frustum: cells around (>= 1) */
    const uint32_t* nv;      /* per frustum: cells along the axis (>= 1) */
    const uint32_t* ball_nu; /* per ball: cells around (>= 1; nu / 2, at least 1, from pole to pole) */
    meso_frusta_height_fn height; /* NULL: no relief */
    const void* height_ctx;
    /* Non-NULL: set to the largest distance, over every grid edge (both
     * sides of each cell and its diagonal) of the lateral grids and balls,
     * between the surface point at the edge's midpoint (u, v) and the
     * midpoint of the edge's two surface points, in double precision (the
     * vertices before their rounding to float). Caps are left out: a cap
     * is a convex plane region fanned from its centre to the lateral grid's
     * rim points, within the rim edges' sag of its fan. */
    double* edge_sag;
} meso_frusta_tess_grid;

/* The whole object. Returns 1, or 0 (nothing allocated) when a grid is 0,
 * a count would not fit in 32 bits or memory runs out. */
int meso_frusta_tessellate(const meso_frustum_rec* recs, uint32_t count, const meso_frustum_ball_rec* balls,
    uint32_t ball_count, const meso_frusta_tess_grid* grid, meso_frusta_tess_mesh* out);

/* Surface point of frustum f at grid coordinates (u, v) ∈ [0, 1]² with the
 * relief displacement (above). */
void meso_frusta_tess_point(const meso_frustum_rec* f, meso_frusta_height_fn height, const void* ctx, double u,
    double v, double p[3]);

void meso_frusta_tess_free(meso_frusta_tess_mesh* m);

#ifdef __cplusplus
}
#endif
#endif /* MESO_FRUSTA_TESSELLATION_H */
