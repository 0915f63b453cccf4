/*
 * voxelize_internal.h — what the files of the voxelizer share (internal,
 * mesoi_ prefix). The method is in voxelize.h; the files:
 *
 *   voxel_predicates.c  exact orient2d / orient3d (Shewchuk 1997) and the
 *                       perturbed query q* of voxelize.h
 *   voxel_soup.c        the triangles, and for WINDING the closing cone over
 *                       the welded mesh's chain boundary
 *   voxel_grid.c        the tile grid, its spans, triangle-box overlap
 *   voxel_rows.c        one tile row: crossings along +x, the WINDING bound,
 *                       candidate tiles centre by centre
 *   voxelize.c          the driver (batches of tile rows on threads) and the
 *                       stored result
 */
#ifndef MESO_VOXELIZE_INTERNAL_H
#define MESO_VOXELIZE_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "voxelize.h"
#include "winding_number.h"

/* The error-free transformations need every operation rounded on its own:
 * no fused multiply-add. GCC does not contract in ISO C mode (c_std = c11);
 * clang honours the pragma, which holds for the rest of every file that
 * includes this header. */
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

static inline double mesoi_dmin(double a, double b)
{
    return a < b ? a : b;
}

static inline double mesoi_dmax(double a, double b)
{
    return a > b ? a : b;
}

/* >>predicates (voxel_predicates.c) ----------------------------------------- */

/* Side of q* against the projected edge a -> b in the (y, z) plane; *exact
 * counts the exact evaluations. */
int mesoi_edge_side(const double* a, const double* b, const double* q, uint64_t* exact);
/* Sign of orient3d(a, b, c, q*); 0 only when the triangle is degenerate. */
int mesoi_side3(const double* a, const double* b, const double* c, const double* q, uint64_t* exact);

/* >>triangle soup (voxel_soup.c) --------------------------------------------
 * The mesh's triangles, then (WINDING) the closing cone: one triangle
 * (b, a, apex) per chain-boundary edge a -> b, as often as its multiplicity. */
typedef struct mesoi_soup {
    const float* pos;     /* 3 per vertex */
    const uint32_t* idx;  /* 3 per triangle */
    uint32_t surface;     /* triangles 0 .. surface - 1 are the mesh's */
    uint32_t count;       /* all triangles */
    float* own_pos;       /* positions + apex, when there is a cone */
    uint32_t* own_idx;
    meso_winding* cone_tree; /* more than MESO_VOXELIZE_CONE_DIRECT cone triangles */
} mesoi_soup;

/* The soup of `m`; AUTO in *method becomes PARITY (closed) or WINDING. */
meso_result mesoi_soup_build(const meso_mesh* m, meso_voxelizer* method, int threads, mesoi_soup* s, meso_error* err);
void mesoi_soup_free(mesoi_soup* s);
/* Triangle t's corners (as doubles) and bounds. */
void mesoi_tri_corners(const mesoi_soup* s, uint32_t t, double v[3][3], double lo[3], double hi[3]);
/* w_C(q*): the cone's winding number. */
double mesoi_cone_winding(const mesoi_soup* s, const double q[3], uint64_t* exact);

/* >>grid (voxel_grid.c) ------------------------------------------------------ */

typedef struct mesoi_grid {
    double o[3], h, tile;   /* origin, voxel size, tile edge R h */
    uint32_t R, T[3], N[3];
    double margin;          /* growth of tile boxes for the overlap test */
} mesoi_grid;

/* Centre of voxel i along `axis` (the same arithmetic as meso_voxel_center). */
static inline double mesoi_centre_coord(const mesoi_grid* g, int axis, int64_t i)
{
    return g->o[axis] + ((double)i + 0.5) * g->h;
}

/* floor for |x| < 2^62 (libm's floor is a call without SSE4.1). */
static inline double mesoi_ffloor(double x)
{
    const double t = (double)(int64_t)x;
    return t > x ? t - 1.0 : t;
}

/* Tiles whose closed (grown) box along `axis` can meet [lo, hi], clamped to
 * the grid; returns 0 when none. */
int mesoi_tile_span(const mesoi_grid* g, int axis, double lo, double hi, uint32_t* t0, uint32_t* t1);
/* Voxel centres along `axis` within [lo, hi] (one more on each side), in
 * [first, last] clamped to [c0, c1]; returns 0 when none. */
int mesoi_centre_span(const mesoi_grid* g, int axis, double lo, double hi, int64_t c0, int64_t c1, int64_t* i0,
                      int64_t* i1);
/* Triangle-box overlap (meso_triangle_box_overlap; tv: 3 corners). */
int mesoi_tri_box(const double centre[3], const double half[3], const double* tv);
/* The grid of `vg`, checked (issue MESO_VOXELIZE_ISSUE_GRID). */
meso_result mesoi_check_grid(const meso_voxel_grid* vg, mesoi_grid* g, meso_error* err);

/* >>rows (voxel_rows.c) ------------------------------------------------------ */

typedef struct mesoi_xing {
    uint32_t k;  /* centres 0 .. k-1 of the row see this crossing ahead of them */
    int32_t s;   /* +1 leaving through a triangle facing +x, -1 entering */
} mesoi_xing;

/* A triangle of the current tile row, unpacked once. */
typedef struct mesoi_ltri {
    double v[3][3];
    double lo[3], hi[3];
} mesoi_ltri;

typedef struct mesoi_counters {
    uint64_t rows, crossings, exact, evaluated, candidates;
} mesoi_counters;

/* Per-thread working memory, grown as needed. */
typedef struct mesoi_scratch {
    mesoi_xing* xs;
    size_t xs_cap;
    mesoi_ltri* lt;          /* the row's triangles */
    size_t lt_cap;
    uint32_t* bstart;  /* R^2 + 1 */
    uint32_t* bucket;
    size_t bucket_cap;
    uint8_t* cand;     /* T0: bits 1 mesh triangle meets the tile, 2 WINDING bound undecided, 4 cone meets it */
    uint32_t* ctx;     /* T0: candidate tiles' tx */
    double* twc;       /* T0: WINDING, per candidate: w_C at its centre (NaN where the cone meets it) */
    double* tspread;   /* T0: and the bound on its variation over the tile */
    mesoi_counters n;
    int oom;
} mesoi_scratch;

typedef struct mesoi_row_out {
    uint8_t* classes;  /* T0 */
    uint32_t mixed_count;
    uint32_t* mixed_tx;
    uint64_t* bits;
} mesoi_row_out;

typedef struct mesoi_job {
    const mesoi_grid* g;
    const mesoi_soup* s;
    meso_voxelizer method;
    const uint32_t* list; /* the tile row's triangles */
    uint32_t list_count;
    uint32_t ty, tz;
    /* WINDING bound */
    const float (*bedge)[6]; /* chain-boundary edges: from, to */
    uint32_t bedge_count;
} mesoi_job;

/* Grow *p (of *cap elements of `elem` bytes) to hold `need`; 0 when out of
 * memory. */
int mesoi_grow_buf(void** p, size_t* cap, size_t need, size_t elem);
/* Lists in CSR form are built in two passes: count into start[k + 1], then
 * (after mesoi_csr_counted) fill at start[k]++, then mesoi_csr_filled. */
int mesoi_csr_counted(uint32_t* start, uint64_t n, uint32_t** items, size_t* cap);
void mesoi_csr_filled(uint32_t* start, uint64_t n);
/* One tile row: classes of its T0 tiles and bits of its MIXED ones
 * (sc->oom set when out of memory). */
void mesoi_process_row(const mesoi_job* jb, mesoi_scratch* sc, mesoi_row_out* out);

#endif /* MESO_VOXELIZE_INTERNAL_H */
