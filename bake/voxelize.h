/*
 * voxelize.h — sparse inside/outside voxelization of a base mesh
 * (cell-based-object-representation.md §3.1.4; issue #6 "without ever
 * holding a dense grid").
 *
 * The grid: N0 x N1 x N2 voxels, Na = tiles[a] * tile_res, cut into tiles of
 * tile_res^3 voxels (the tiles of the cell-based object, §3.1.3). Voxel
 * (i, j, k) has its centre at origin + ((i + 1/2) h, (j + 1/2) h, (k + 1/2) h),
 * computed by meso_voxel_center and by nothing else, so a reference that
 * wants the same points calls it too. What is classified is that centre.
 *
 * Output per tile: OUTSIDE (every centre outside), INSIDE (every centre
 * inside) or MIXED, and for MIXED tiles only their R^3 bits (1 = inside).
 * Nothing of size N^3 is ever allocated: working memory is per tile row
 * (R^2 voxel rows and the triangles over them), the stored result is one
 * byte per tile plus R^3 / 8 bytes per MIXED tile, and the streaming call
 * (meso_voxelize_stream) hands rows of tiles to the caller and forgets them.
 *
 * >>method
 * Both paths count ray crossings along +x (voxel rows) with exact predicates
 * and one fixed symbolic perturbation; they differ in what they do with them.
 *
 *   The perturbation. Every query point q is replaced by
 *       q* = q + (delta, eps, eps^2),   delta >> eps >> eps^2 > 0 infinitesimal,
 *   (Edelsbrunner & Muecke's simulation of simplicity, applied to the query
 *   only). A ray from q* along +x meets no vertex or edge of any triangle and
 *   lies in no triangle's plane, so every crossing is a clean one, and two
 *   triangles sharing an edge agree about it: the edge test is a function of
 *   the edge alone. A centre exactly ON the surface is classified as the
 *   point just beyond it in +x (delta dominates): it takes the side the +x
 *   direction leaves it on. Predicates: orient2d / orient3d in double with
 *   Shewchuk's static error bounds ("Adaptive Precision Floating-Point
 *   Arithmetic and Fast Robust Geometric Predicates", 1997); when the bound
 *   cannot decide, the exact sign from expansion arithmetic (two-sum,
 *   two-product by Dekker splitting). Mesh coordinates are floats, centres
 *   doubles; every sign below is exact for those numbers.
 *
 *   MESO_VOXELIZE_PARITY (closed meshes): inside = odd number of crossings of
 *   the ray from q*. This is the exact point-in-mesh answer (CGAL's
 *   Side_of_triangle_mesh shoots rays and counts the same parity); the tests
 *   compare every centre of 64^3..128^3 grids of the bundled meshes with it.
 *   On an open mesh the parity leaks (a ray through a hole counts wrong):
 *   that is what WINDING is for. Where closed parts overlap, parity calls
 *   the overlap outside (winding number 2); AUTO does not look for
 *   self-intersections, so pass WINDING for such unions.
 *
 *   MESO_VOXELIZE_WINDING (holes, duplicated faces, inconsistent orientation,
 *   soups): inside = generalized winding number w(q*) >= 1/2 (Jacobson et al.
 *   2013; winding_number.h). w is computed as
 *       w(q) = X(q) - w_C(q)
 *   where C is a surface closing the mesh. The chain boundary of the mesh
 *   (vertices welded by exact position first, so unwelded seams are no
 *   boundary; every directed edge counted +1, its reverse -1; edges with a
 *   non-zero sum, as often as the sum says) splits into closed loops, and C
 *   is one fan per loop: a triangle (b, a, apex) per edge a -> b, the apex
 *   the mean of the loop's vertices. S + C has no boundary, so its winding
 *   number is its signed crossing count X along any ray (+1 where the ray
 *   leaves through a triangle facing +x, -1 where it enters): exact, with
 *   the predicates above. w_C is the winding number of the fans alone: the
 *   exact sum of their solid angles for <= MESO_VOXELIZE_CONE_DIRECT fan
 *   triangles, where next to a fan triangle's interior the term's sign is
 *   the exact perturbed side, so that X and w_C jump together; the Barill
 *   hierarchy of winding_number.h beyond that (then accurate to its stated
 *   error; 0.05 of margin is added to every bound below). On a closed,
 *   consistently oriented mesh C is empty and WINDING equals PARITY bit for
 *   bit (tested). Only the boundary term is computed in floating point, and
 *   it is smooth at the surface, where w jumps.
 *
 *   Tiles. A tile's closed box (grown by a relative 1e-6 of a voxel) is a
 *   CANDIDATE when a mesh triangle meets it (triangle-box separating axes,
 *   Akenine-Moeller 2001). A box no triangle meets holds no surface, so:
 *     PARITY: all its centres have the parity of one of them;
 *     WINDING: w is harmonic in it, and its gradient is the Biot-Savart field
 *       of the chain boundary (only the boundary of a surface moves its solid
 *       angle), so |grad w| <= sum_e |m_e| len_e / (4 pi d_e^2), d_e the
 *       distance from edge e to the box. A run of such tiles is decided from
 *       one centre q0 when |w(q0) - 1/2| > G rho + margin (rho: the farthest
 *       centre of the run from q0); otherwise it is halved, and a single tile
 *       that still cannot be decided becomes a candidate.
 *   Candidate tiles are classified centre by centre along their R^2 voxel
 *   rows: X is constant between crossings, so PARITY sets whole runs of
 *   bits at once; WINDING does too where w_C cannot move the run across 1/2
 *   (a tile no fan triangle meets: w_C at its centre plus the same gradient
 *   bound), and evaluates w_C at each centre of the rest. A candidate whose
 *   centres all agree is reported as uniform, so the MIXED set is exactly
 *   the set of tiles with centres on both sides.
 *   The gradient bound ignores cancellation between boundary edges, so for
 *   meshes with long boundaries (a CAD-export triangle soup of ~1570 fan
 *   triangles, like the generated `soup` of tests/common/defective_meshes.h)
 *   it decides little and most tiles are
 *   evaluated centre by centre: correct, but slow (2.6 s at 64^3).
 *
 *   Order of work: tiles are processed in rows along x (one ray per voxel row
 *   of a tile row gives every crossing on it), rows grouped by z-layer;
 *   OpenMP threads take whole tile rows, every row's result depends on that
 *   row alone, and rows are handed on in (z, y) order: results and
 *   statistics do not depend on the thread count.
 *
 *   Why not OpenVDB (the issue's `--voxelizer vdb`): meshToLevelSet's sign
 *   is not exact near the surface (the issue measured 55 of 2.1 M points
 *   wrong at 512), so it would need the exact test above near the surface
 *   anyway, and the exact path alone is faster than OpenVDB's narrow band on
 *   the same mesh (tests/bench/bench_voxelize.c prints both). It is not
 *   offered; MESO_VOXELIZE_AUTO never needs it.
 *
 * Cost: O(triangle coverage of tile rows) to bin triangles, one ray per voxel
 * row through a tile row that has a candidate tile, O(crossings + words) per
 * candidate tile per voxel row to write bits, and (WINDING) O(fan
 * triangles) per centre where the bound does not decide.
 * Measured (2 threads on a shared 2-core machine, tests/bench/results/
 * voxelize.csv): the bunny (6598 triangles) at 512 / 1024 voxels across in
 * 0.10 / 0.31 s, OpenVDB's narrow band at the same voxel size 3.3 / 8.5 s;
 * split to 1.69 M triangles 0.98 / 1.28 s against OpenVDB's 14.8 / 41.6 s;
 * peak RSS 36..116 MiB (OpenVDB 183..603). The sphere at N = 4096 (128^3
 * tiles of 32^3): 13.4 M rays, 2-4 s, peak RSS +78 MiB (a dense bit grid
 * would be 8 GiB). Exactness: every centre of 64^3..128^3 grids of the
 * bundled meshes equals CGAL's answer (tests/cells/test_voxelize.c).
 */
#ifndef MESO_VOXELIZE_H
#define MESO_VOXELIZE_H

#include "meso_bake.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Voxelization issue codes (meso_error.code), 3180..3184:
 *   3180 grid parameters out of range (resolution, tile counts, voxel size)
 *   3181 the mesh has no triangles, a face refers to a missing vertex, or a
 *        coordinate is not finite
 *   3182 the caller's row function stopped the voxelization
 *   (3183, 3184 reserved; membership.h uses 3185..3189) */
#define MESO_VOXELIZE_ISSUE_GRID 3180u
#define MESO_VOXELIZE_ISSUE_MESH 3181u
#define MESO_VOXELIZE_ISSUE_STOPPED 3182u

#define MESO_VOXELIZE_MAX_RES 16384u      /* largest N along an axis */
#define MESO_VOXELIZE_MAX_TILE_RES 1024u  /* largest R (as tile_map.h) */
#define MESO_VOXELIZE_CONE_DIRECT 1024u   /* WINDING: exact boundary term up to this many fan triangles */

typedef enum meso_voxelizer {
    MESO_VOXELIZE_AUTO = 0,    /* PARITY when, vertices welded by position, every edge has two faces
                                * traversing it in opposite directions (closed, consistently oriented, no
                                * duplicate faces), else WINDING */
    MESO_VOXELIZE_PARITY = 1,  /* exact ray-crossing parity: closed meshes */
    MESO_VOXELIZE_WINDING = 2, /* generalized winding number >= 1/2: open or defective meshes */
    MESO_VOXELIZE_COUNT
} meso_voxelizer;

/* Whether triangle tv (3 corners, xyz) meets the closed box centre +- half
 * (separating axes; the test the voxelizer uses for candidate tiles: grow
 * the box, and rounding can only add overlaps). For estimates of the
 * tiles a mesh meets (memory_budget.h). */
int meso_triangle_box_overlap(const double centre[3], const double half[3], const double tv[9]);

/* "auto", "parity", "winding"; "?" for anything else. Never NULL. */
const char* meso_voxelizer_name(meso_voxelizer v);

/* The voxel grid. Zero-initialise, then set every field (or use
 * meso_voxel_grid_fit). */
typedef struct meso_voxel_grid {
    double origin[3];   /* min corner of voxel (0, 0, 0), mesh units */
    double voxel_size;  /* h > 0 */
    uint32_t tile_res;  /* R: voxels per tile edge, 1..MESO_VOXELIZE_MAX_TILE_RES */
    uint32_t tiles[3];  /* T0, T1, T2 >= 1; Na = Ta R <= MESO_VOXELIZE_MAX_RES */
} meso_voxel_grid;

/* A cubic grid of tiles^3 tiles of R^3 voxels around the mesh: the cube is
 * centred on the mesh's bounding box, and its side N h leaves `pad` voxels
 * (>= 0; 1 is a good default) between the box's longest extent and the
 * grid's faces: h = longest extent / (N - 2 pad). MESO_ERR_INVALID_ARG (code
 * 3180) for parameters out of range or an empty / flat-in-every-axis mesh. */
meso_result meso_voxel_grid_fit(const meso_mesh* m, uint32_t tiles, uint32_t tile_res, double pad,
                                meso_voxel_grid* out, meso_error* err);

/* The centre of voxel (i, j, k): origin + (index + 0.5) h per axis. */
void meso_voxel_center(const meso_voxel_grid* g, uint32_t i, uint32_t j, uint32_t k, double out[3]);

/* Tile classes. Values match the membership tags of §4.4 Table 4.1. */
typedef enum meso_tile_class {
    MESO_TILE_OUTSIDE = 0, /* every voxel centre of the tile is outside */
    MESO_TILE_INSIDE = 1,  /* every one inside */
    MESO_TILE_MIXED = 2,   /* both: the tile's bits are stored */
    MESO_TILE_CLASS_COUNT
} meso_tile_class;

/* What one voxelization did (every count is independent of the thread count). */
typedef struct meso_voxelize_stats {
    meso_voxelizer method;       /* the path used: PARITY or WINDING (AUTO resolved) */
    uint64_t voxels;             /* N0 N1 N2: every centre is classified, whole tiles or one by one */
    uint64_t voxels_evaluated;   /* centres classified one by one (in candidate tiles) */
    uint64_t tiles;              /* T0 T1 T2 */
    uint64_t tiles_outside;
    uint64_t tiles_inside;
    uint64_t tiles_mixed;
    uint64_t tiles_candidate;    /* tiles evaluated centre by centre (see the top of this file) */
    uint64_t rows;               /* voxel rows traced (rays) */
    uint64_t crossings;          /* ray-triangle crossings found on them */
    uint64_t exact_predicates;   /* signs the floating-point filter could not decide */
    uint32_t boundary_edges;     /* WINDING: chain-boundary edges after welding, with multiplicity */
    uint32_t cone_triangles;     /* WINDING: triangles of the closing fans (= boundary_edges) */
    double seconds;              /* wall time of the call */
} meso_voxelize_stats;

/* One row of tiles (ty, tz), as handed to a meso_voxel_rows_fn. */
typedef struct meso_voxel_row {
    uint32_t ty, tz;
    const uint8_t* classes;   /* T0 entries: meso_tile_class of tile (tx, ty, tz) */
    uint32_t mixed_count;     /* MIXED tiles in the row */
    const uint32_t* mixed_tx; /* their tx, increasing */
    /* mixed_count blocks of meso_voxel_tile_words(R) words: local voxel
     * (x, y, z) of the tile is bit (x + R (y + R z)) % 64 of word
     * (x + R (y + R z)) / 64; 1 = inside. */
    const uint64_t* bits;
} meso_voxel_row;

/* Called with consecutive rows in (tz, ty) order, from the calling thread
 * (outside any parallel region, so it may run its own). The data is valid
 * during the call only. Return MESO_OK to go on; anything else stops the
 * voxelization, which then returns that result with code 3182. */
typedef meso_result (*meso_voxel_rows_fn)(void* user, const meso_voxel_row* rows, uint32_t row_count,
                                          meso_error* err);

/* 64-bit words holding one tile's bits: ceil(R^3 / 64). */
uint64_t meso_voxel_tile_words(uint32_t tile_res);

/* Voxelize `m` over `g`, handing every row of tiles to `fn` (see above).
 * threads <= 0: all cores. stats may be NULL. Failures: MESO_ERR_INVALID_ARG
 * (NULL arguments; codes 3180, 3181), MESO_ERR_OUT_OF_MEMORY, or whatever
 * `fn` returned (code 3182). */
meso_result meso_voxelize_stream(const meso_mesh* m, const meso_voxel_grid* g, meso_voxelizer method, int threads,
                                 meso_voxel_rows_fn fn, void* user, meso_voxelize_stats* stats, meso_error* err);

/* The whole result, kept: one byte per tile, bits for MIXED tiles only.
 * Zero-initialise; free with meso_voxels_free. */
typedef struct meso_voxels {
    meso_voxel_grid grid;
    uint8_t* tile_class;       /* T0 T1 T2 meso_tile_class values, tile (tx, ty, tz) at tx + T0 (ty + T1 tz) */
    uint64_t mixed_count;
    uint64_t* mixed_tiles;     /* linear ids of the MIXED tiles, increasing */
    uint64_t* bits;            /* mixed_count blocks of tile_words words, in mixed_tiles order */
    uint64_t tile_words;       /* meso_voxel_tile_words(R) */
    meso_voxelize_stats stats;
} meso_voxels;

/* Voxelize and keep the result (meso_voxelize_stream into a meso_voxels).
 * On failure *out is zeroed. */
meso_result meso_voxelize(const meso_mesh* m, const meso_voxel_grid* g, meso_voxelizer method, int threads,
                          meso_voxels* out, meso_error* err);

/* Class of tile (tx, ty, tz); indices must be in range. */
meso_tile_class meso_voxels_tile(const meso_voxels* v, uint32_t tx, uint32_t ty, uint32_t tz);

/* The bits of a MIXED tile (layout as in meso_voxel_row), NULL for others. */
const uint64_t* meso_voxels_tile_bits(const meso_voxels* v, uint32_t tx, uint32_t ty, uint32_t tz);

/* 1 when the centre of voxel (i, j, k) is inside; indices must be in range. */
int meso_voxels_inside(const meso_voxels* v, uint32_t i, uint32_t j, uint32_t k);

void meso_voxels_free(meso_voxels* v);

#ifdef __cplusplus
}
#endif
#endif /* MESO_VOXELIZE_H */
