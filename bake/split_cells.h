/*
 * split_cells.h — split cells, face codes and split-cell indices of a tile
 * map (cell-based-object-representation.md §3.1.6, §4.2, §4.3; used by the
 * membership stage, §4.4–4.5).
 *
 * Definitions (ours, made precise):
 *  - A SPLIT CELL is a connected component of the voxels of one non-zero
 *    tile-map index inside the tile, WITHOUT wrap, in 26-connectivity (two
 *    voxels are neighbours when they differ by at most 1 along every axis).
 *    The thesis's split-cell shader (Algorithm 4.2) ORs over "26 directions",
 *    so 26 it is: a cell is what the thesis's propagation reaches. (With 6-
 *    connectivity, digital Voronoi cells can fall apart at thin corners.)
 *  - A CELL is a connected component of the same voxels WITH periodic wrap,
 *    i.e. on the 3-torus: the split cells that continue each other across the
 *    tile's faces, edges and corners (26-connectivity across borders too).
 *    The thesis identifies a cell with its tile-map index; we do not: a raw
 *    map may use one index for several separate blobs, and each is a cell.
 *    For the generated maps (tile_map.h) each non-empty index is one cell.
 *  - FACE CODE of a split cell: the OR of the faces its voxels lie on:
 *      bit 0 (1)  x = 0      bit 2 (4)   y = 0      bit 4 (16) z = 0
 *      bit 1 (2)  x = R − 1  bit 3 (8)   y = R − 1  bit 5 (32) z = R − 1
 *    The thesis's Fig. 4.3 is not in our copy; this order follows from its
 *    Algorithm 4.7 (x in bits 0–1, y in 2–3, z in 4–5; "xShift = 2 (code & 3)
 *    − 3" gives −1 for bit 0, i.e. the neighbouring tile towards −x) and its
 *    Table 4.3 example. It equals the fixpoint of Algorithm 4.2's OR
 *    propagation started from per-voxel face codes (the tests check that).
 *
 * How (no N ping-pong passes; linear up to the inverse Ackermann factor):
 *  1. Union-find over voxels: each voxel is joined with its 13 "earlier"
 *     26-neighbours inside the tile that hold the same index. Roots are the
 *     smallest linear index of their set, so one scan labels split cells in
 *     order of their first voxel and accumulates face codes and sizes.
 *  2. Union-find over split cells with tile offsets: for every pair of
 *     same-index voxels that are 26-neighbours across the border (voxel v in
 *     tile t touches voxel u, wrapped, in tile t + w, w ∈ {−1,0,1}³), join
 *     split(v) and split(u) with "u's copy sits in tile t + w". If the two are
 *     already joined with a different offset, the cell reaches a copy of
 *     itself in another tile: it WRAPS (is unbounded in object space: e.g.
 *     K = 1 Voronoi, or a tube through the tile). Otherwise every split cell
 *     gets its offset relative to its cell's first split cell: one connected
 *     copy of the cell anchored at tile T consists of split cell s in tile
 *     T + offset(s). The membership merge (§4.5) needs exactly that; the
 *     thesis derives it from face codes (Algorithm 4.7), which is ambiguous
 *     when a split cell touches two opposite faces and wrong when a cell
 *     touches one face in several places. Ours is exact.
 *  3. Cells are numbered by (tile-map index, first voxel); split cells are
 *     renumbered so each cell owns a contiguous range of split ids (1..S in
 *     total, 0 = empty), ordered within the cell by (face code, first voxel).
 *
 * The thesis's split-cell index (§4.3) gives every cell a fixed range of 8
 * indices ("1 to 8, 9 to 15 [sic: 16] and so on") and converts face codes to
 * "ascending" indices in it; its membership map then packs 64 split cells ×
 * 2 bits into a 128-bit tile code (Fig. 4.9, Algorithm 4.5: channel =
 * index >> 4, shift = (index & 15) << 1). Those two do not fit together as
 * printed: 1-based index 64 would need a fifth channel. We keep the scheme
 * 0-based: thesis_slot = 8 (cell − 1) + rank, rank = position of the split
 * cell in its cell's range (ascending face code, as Fig. 4.10 shows: face
 * code 1 → 9, face code 2 → 10), and a tile fits the thesis packing iff every
 * slot is < 64: at most 8 cells, each with at most 8 split cells. Nothing
 * here is limited to that: with more split cells, a caller can use the dense
 * ids (MESO_SPLIT_PACK_DENSE64 when S <= 64) or wider tile codes, or refuse
 * clearly with meso_split_cells_check_packing.
 *
 * Wrapping cells are common, not exotic. A periodic Voronoi cell whose
 * region reaches the bisector between its seed and one of the seed's own
 * periodic images touches its own copy in the next tile (26-connectivity
 * also counts contact along an edge or at a corner). Measured at R = 32 over
 * 8 seeds each (tests/cells/test_split_cells.c): K = 2: 100 % of cells wrap,
 * K = 4: 91 %, K = 8 (the thesis's Fig. 3.2 setup): 19 %, K >= 16: 0 %.
 * The thesis does not see this: its merge (Algorithm 4.7) pairs split cells
 * by face codes and never asks whether a cell meets its own copy. By the
 * definition above such a cell is one unbounded object, and that is what we
 * report (`wraps`, `wrapping_cells`), never mis-numbered; its offsets follow
 * one spanning tree of its border contacts. What the membership stage does
 * with it (treat it as one object, or tell copies apart for generated maps,
 * where the nearest seed IMAGE of every voxel is known) is decided there.
 */
#ifndef MESO_SPLIT_CELLS_H
#define MESO_SPLIT_CELLS_H

#include "tile_map.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_FACE_X0 0x01u /* the split cell touches x = 0 */
#define MESO_FACE_X1 0x02u /* ... x = R - 1 */
#define MESO_FACE_Y0 0x04u
#define MESO_FACE_Y1 0x08u
#define MESO_FACE_Z0 0x10u
#define MESO_FACE_Z1 0x20u

typedef struct meso_split_cell {
    uint32_t cell;         /* 1..cell_count */
    uint32_t voxel_count;
    uint32_t first_voxel;  /* linear index (x fastest) of its first voxel */
    uint32_t thesis_slot;  /* 8 (cell - 1) + rank (see the top of this file) */
    int32_t offset[3];     /* tile of this split cell in a copy of its cell, relative to the cell's
                            * first split cell (which has 0, 0, 0); for a wrapping cell: along one
                            * spanning tree of its border contacts, not a copy */
    uint16_t tile_index;   /* the tile-map value, 1..K */
    uint8_t face_code;     /* MESO_FACE_* bits */
    uint8_t rank;          /* position in its cell's range, saturated at 255 */
} meso_split_cell;

typedef struct meso_cell {
    uint32_t first_split;  /* its split cells are ids first_split .. first_split + split_count - 1 */
    uint32_t split_count;
    uint64_t voxel_count;
    uint16_t tile_index;
    uint8_t wraps;         /* 1: connected to its own copy in another tile (unbounded in object space) */
} meso_cell;

/* Split cells of one tile map. Zero-initialise; free with meso_split_cells_free. */
typedef struct meso_split_cells {
    uint32_t res;               /* R */
    uint32_t split_count;       /* S */
    uint32_t cell_count;        /* C */
    uint32_t max_splits_per_cell;
    uint32_t wrapping_cells;    /* cells with wraps = 1 */
    uint32_t* voxel_split;      /* R³ split ids (1..S; 0 = empty), x fastest */
    meso_split_cell* splits;    /* S entries: splits[s - 1] is split id s */
    meso_cell* cells;           /* C entries: cells[c - 1] is cell c */
} meso_split_cells;

/* Compute the split cells of `m`. threads <= 0: all cores (only the final
 * relabelling is parallel; results never depend on threads). Returns
 * MESO_ERR_OUT_OF_MEMORY or MESO_ERR_INVALID_ARG on failure, *out zeroed. */
meso_result meso_split_cells_compute(const meso_tile_map* m, int threads, meso_split_cells* out, meso_error* err);

void meso_split_cells_free(meso_split_cells* sc);

/* Ways to pack a tile's split-cell memberships (2 bits each, §4.4). */
typedef enum meso_split_packing {
    MESO_SPLIT_PACK_THESIS = 0,  /* fixed 8-slot range per cell, slots < 64: a 128-bit tile code as in the thesis */
    MESO_SPLIT_PACK_DENSE64 = 1, /* contiguous ranges (split ids − 1), S <= 64: a 128-bit tile code */
    MESO_SPLIT_PACK_WIDE = 2,    /* S > 64: no 128-bit tile code holds the tile */
    MESO_SPLIT_PACK_COUNT
} meso_split_packing;

/* The tightest packing the tile fits: THESIS if it fits the thesis's, else
 * DENSE64 if S <= 64, else WIDE. */
meso_split_packing meso_split_cells_packing(const meso_split_cells* sc);

/* MESO_OK when the tile fits `packing` (WIDE always fits); otherwise
 * MESO_ERR_INVALID_ARG (the tile map the options chose is too dense for the
 * encoding: a command-line error, exit 1), code 3153 and a message with the
 * counts that do not fit (split cells, cells, most split cells of one cell). */
meso_result meso_split_cells_check_packing(const meso_split_cells* sc, meso_split_packing packing, meso_error* err);

#ifdef __cplusplus
}
#endif
#endif /* MESO_SPLIT_CELLS_H */
