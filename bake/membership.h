/*
 * membership.h — the cell membership map of a cell-based object
 * (cell-based-object-representation.md §3.1.5, §3.1.6, §4.4, §4.5).
 *
 * Input: the split cells of a tile map (split_cells.h), a voxel grid of
 * T0 x T1 x T2 tiles of R^3 voxels (voxelize.h; R = the tile map's
 * resolution), and the mesh (voxelized here by meso_voxelize_stream, never
 * held densely) or a voxelization already made (meso_voxels).
 * Output: a tag per split cell per tile, one of Table 4.1's:
 *     00 OUTSIDE   01 INSIDE   10 INTERSECTED   (11 UNSET: never in a result)
 *
 * >>definitions (ours, made precise)
 *  - Pre-merge tag of split cell s in tile t (§3.1.5, §4.4 Algorithm 4.4 and
 *    Table 4.2): over the voxel centres of s in t, INSIDE if all are inside,
 *    OUTSIDE if all are outside, INTERSECTED if both occur.
 *  - A COPY of a cell c anchored at tile A is the set of (A + offset(s), s)
 *    for the split cells s of c (offsets from split_cells.h: exact, from the
 *    voxels' border contacts, not Algorithm 4.7's face-code arithmetic). Every
 *    (tile, split cell) lies in exactly one copy: A = t - offset(s).
 *  - Merge (§4.5, Algorithm 4.6 with Table 4.2): the tag of every member of
 *    a copy is the combination of the members' pre-merge tags: all INSIDE ->
 *    INSIDE, all OUTSIDE -> OUTSIDE, anything else (an INTERSECTED member, or
 *    members that disagree) -> INTERSECTED. Members in tiles beyond the grid
 *    count as OUTSIDE: the grid is the voxelized region, and
 *    meso_voxel_grid_fit pads it so that nothing of the mesh is beyond.
 *    So a cell is INSIDE only if all of it, in every tile it reaches, is
 *    inside: every voxel centre the renderer draws is inside the base mesh
 *    (a native coarser level's cells inherit their tags instead:
 *    cells_levels.h).
 *  - WRAPPING cells (split_cells.h `wraps`: the cell touches its own copy in
 *    another tile, so in object space it is one unbounded object). Decision:
 *    they are merged like the others, per copy as split_cells' offsets define
 *    it (a spanning tree of the cell's border contacts). Each such "copy" is
 *    a bounded, connected piece of the unbounded object; pieces meet their
 *    neighbours only at the contacts left out of the tree. Why: the strict
 *    alternative (the unbounded object as one cell) can never be INSIDE a
 *    bounded mesh, so every wrapping cell would be INTERSECTED everywhere
 *    and never drawn; wrapping is common (Voronoi at R = 32: 100 % of cells
 *    for 2 seeds, 91 % for 4, 19 % for the thesis's 8, 0 % from 16 on), so
 *    the object would be full of holes at every tile. Per piece, drawn cells
 *    are still wholly inside the mesh; the cost is that two adjacent pieces
 *    may get different tags (one INSIDE, one INTERSECTED, near the surface),
 *    which shows as a flat cut where they touch. The report counts wrapping
 *    pieces (`wrapping_copies`) so a bake can say how much of it there is.
 *    The tests check this rule against a naive flood over (tile, split)
 *    pairs, and non-wrapping cells against a flood over voxels in object
 *    space (no offsets used).
 *
 * >>encoding (for FORMAT.md §7 MEMB; all words little-endian uint32)
 *   tile t = tx + T0 (ty + T1 tz).
 *   classes[ceil(T / 16)]   2 bits per tile, tile t at bits 2 (t % 16) of
 *                           word t / 16, LSB first: 0 every split cell of
 *                           the tile OUTSIDE (skip it), 1 every one INSIDE
 *                           (no record needed), 2 MIXED (has a record),
 *                           3 unused. Tiles without split cells are 0.
 *   rank[ceil(T / 16)]      MIXED tiles in all words before this one.
 *   records[M][W]           one per MIXED tile, in tile order; W = ceil(2 S /
 *                           32); split cell s (1..S) at bits 2 ((s - 1) %
 *                           16) of word (s - 1) / 16, LSB first (FORMAT.md:
 *                           "2 bits per split cell per tile, packed LSB
 *                           first"; this is Algorithm 4.5's shift and
 *                           channel with 0-based split ids).
 *   Record of MIXED tile t: rank[t / 16] + the number of class-2 fields
 *   below tile t in classes[t / 16] (popcount of the high bits under a mask;
 *   GLSL 3.3 can count them with shifts).
 *   Size: T / 2 bytes of index (4 bits per tile) + 4 W M bytes; the thesis
 *   stores 16 bytes per tile for every tile (Fig. 4.9).
 *
 * Cost: voxelization (voxelize.h), then O(R^3 / 64 + splits per word) per
 * MIXED tile (tags from 64-voxel words against precomputed per-word split
 * masks), O(T |D|) to find the tiles a merge can change (D: the offset
 * differences within cells) and O(sum over cells of splits^2) per such tile.
 * Working memory: two bytes per tile plus S bytes per MIXED tile.
 * Threads: OpenMP over tiles; results do not depend on the thread count.
 * Measured: the issue's goal setup, a 64^3 tile map (Voronoi, 8 seeds) x
 * 128^3 tiles (N = 8192) on the bunny, baked by mesobake cells: 8.1 s in
 * all (7.9 s of it voxelization + membership), peak RSS 165 MiB, a map of
 * 2.2 MB where the thesis's 128-bit tile codes take 32 MiB
 * (tests/bench/bench_cells_bake.c, results/cells_table51.csv; 2 threads on
 * a shared 2-core machine).
 */
#ifndef MESO_MEMBERSHIP_H
#define MESO_MEMBERSHIP_H

#include "split_cells.h"
#include "voxelize.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Membership issue codes (meso_error.code), 3185..3189:
 *   3185 the split cells do not fit the grid (tile map resolution != R)
 *   3186 the map does not fit the encoding (more than 2^32 - 1 MIXED tiles or
 *        words) */
#define MESO_MEMB_ISSUE_MISMATCH 3185u
#define MESO_MEMB_ISSUE_SIZE 3186u

typedef enum meso_memb_tag {
    MESO_MEMB_OUTSIDE = 0,
    MESO_MEMB_INSIDE = 1,
    MESO_MEMB_INTERSECTED = 2,
    MESO_MEMB_UNSET = 3, /* Table 4.1; never in a finished map */
    MESO_MEMB_TAG_COUNT
} meso_memb_tag;

/* Combination of two tags (Table 4.2; UNSET is the identity). */
static inline meso_memb_tag meso_memb_combine(meso_memb_tag a, meso_memb_tag b)
{
    if (a == MESO_MEMB_UNSET)
        return b;
    if (b == MESO_MEMB_UNSET)
        return a;
    return a == b ? a : MESO_MEMB_INTERSECTED;
}

/* A finished membership map (encoding at the top of this file).
 * Zero-initialise; free with meso_membership_free. */
typedef struct meso_membership {
    uint32_t tiles[3];          /* T0, T1, T2 */
    uint32_t split_count;       /* S */
    uint32_t words_per_tile;    /* W = ceil(2 S / 32) */
    uint64_t tile_count;        /* T = T0 T1 T2 */
    uint32_t* classes;          /* ceil(T / 16) words */
    uint32_t* rank;             /* ceil(T / 16) words */
    uint64_t record_count;      /* M: MIXED tiles */
    uint32_t* records;          /* M W words */
    /* report (cells are copies, see the top; a wrapping cell's pieces count one each) */
    uint64_t cells_inside;
    uint64_t cells_outside;
    uint64_t cells_intersected;
    uint64_t wrapping_copies;   /* pieces of wrapping cells among the above */
    uint64_t tiles_outside;     /* tiles by class after the merge */
    uint64_t tiles_inside;
    uint64_t tiles_mixed;
    uint64_t tiles_merge_changed; /* tiles whose tags the merge changed */
    uint64_t bytes;             /* classes + rank + records */
    meso_voxelize_stats voxelize; /* the voxelization's (zero when given one) */
    double seconds;             /* the whole call, voxelization included */
} meso_membership;

/* Voxelize `m` over `g` with `method` (streaming: no tile's bits are kept
 * after its tags are taken) and build the map for the split cells `sc`
 * (sc->res must equal g->tile_res). threads <= 0: all cores. Failures:
 * MESO_ERR_INVALID_ARG (NULL; code 3185 for a resolution mismatch, or the
 * voxelizer's codes; 3186 when the map is too large for the encoding, which
 * the options chose), MESO_ERR_OUT_OF_MEMORY;
 * *out is then zeroed. */
meso_result meso_membership_compute(const meso_mesh* m, const meso_voxel_grid* g, const meso_split_cells* sc,
                                    meso_voxelizer method, int threads, meso_membership* out, meso_error* err);

/* The same from a kept voxelization. */
meso_result meso_membership_from_voxels(const meso_voxels* v, const meso_split_cells* sc, int threads,
                                        meso_membership* out, meso_error* err);

/* Class of tile (tx, ty, tz) after the merge (MESO_TILE_*); indices in range. */
meso_tile_class meso_membership_tile(const meso_membership* mb, uint32_t tx, uint32_t ty, uint32_t tz);

/* Tag of split cell `split` (1..S) in tile (tx, ty, tz); indices in range. */
meso_memb_tag meso_membership_get(const meso_membership* mb, uint32_t tx, uint32_t ty, uint32_t tz, uint32_t split);

void meso_membership_free(meso_membership* mb);

#ifdef __cplusplus
}
#endif
#endif /* MESO_MEMBERSHIP_H */
