/*
 * cells_chunks.h — a cells object's chunks (FORMAT.md §7.2 kind 3, §7.8):
 * CELL, TILE, SPLT, MEMB, NRMM and COLR from a tile map, its split cells
 * and a membership map (tile_map.h, split_cells.h, membership.h).
 *
 * >>normal map (cell-based-object-representation.md §4.6 "or better")
 * The thesis stores one 3 x f32 normal per tile-map voxel. We store the same
 * voxel grid as octahedral U16 x 2 (a third of the bytes; worst angular
 * error about 0.005 degrees: 65536 steps over the octahedron's diagonal).
 * WHICH normal: the surface the runtime draws is the voxel boundary of the
 * tile map (it samples nearest voxels), not the analytic Voronoi or sphere
 * surface the map was generated from, so the normal is that of the voxel
 * cell, smoothed: the gradient of the cell's indicator convolved with a
 * Gaussian (sigma = 1 voxel, 5^3 support), pointing out of the cell:
 *     n(v) = normalize( sum_{d in [-2,2]^3} exp(-|d|^2 / 2) [idx(v + d) != idx(v)] d )
 * with idx the tile-map index and v + d wrapped periodically (the map
 * tiles, so the normal field tiles too). It works the same for generated
 * and raw maps. Every voxel on a cell's border (a 26-neighbour of another
 * index) has a non-zero sum except in contrived symmetric cases; voxels two
 * or more voxels deep inside a cell (sum 0) store +z: a first hit (the ray
 * enters a drawn cell through its border) never reads them.
 * Octahedral mapping (FORMAT.md §7.8 states the decoder): p = n / |n|_1;
 * for n.z < 0, (p.x, p.y) = ((1 - |p.y|) sgn p.x, (1 - |p.x|) sgn p.y),
 * sgn 0 = +1; u = round((p + 1) / 2 * 65535).
 *
 * >>colour map
 * RGBA8 per tile-map voxel (so it tiles with the map): `hash[:SEED]` gives
 * every tile-map index a colour from splitmix64(SEED, index), each channel
 * in [48, 232], plus a per-voxel hash noise of +-10 (deterministic and
 * periodic: it depends on the voxel's coordinates in the tile only); empty
 * voxels (index 0) are (0, 0, 0, 0). `FILE.raw:R`: R^3 RGBA8 texels, x
 * fastest, no header; R must equal the tile-map resolution.
 */
#ifndef MESO_CELLS_CHUNKS_H
#define MESO_CELLS_CHUNKS_H

#include "membership.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Cells-chunk issue codes (meso_error.code), 3190..3194:
 *   3190 colour specification not understood
 *   3191 colour file unreadable, or its size is not 4 R^3
 *   3192 the object does not fit the format (MEMB longer than 2^32 - 1 words) */
#define MESO_CELLS_ISSUE_COLOUR_SPEC 3190u
#define MESO_CELLS_ISSUE_COLOUR_FILE 3191u
#define MESO_CELLS_ISSUE_SIZE 3192u

/* Encoded chunks of one cells object. Zero-initialise; free with
 * meso_cells_chunks_free. Sizes in bytes. */
typedef struct meso_cells_chunks {
    uint8_t cell[64];        /* CELL record */
    void* tile;              /* TILE: R^3 split ids, U16 (S <= 65535) or U32 */
    size_t tile_size;
    uint16_t tile_dtype;     /* MESO_DTYPE_U16 or _U32 */
    uint32_t* splt;          /* SPLT: S x 6 u32 */
    size_t splt_size;
    uint32_t* memb;          /* MEMB: classes, rank, records (membership.h) */
    size_t memb_size;
    uint16_t* nrmm;          /* NRMM: R^3 x 2 u16 */
    size_t nrmm_size;
    uint8_t* colr;           /* COLR: R^3 x 4 u8 */
    size_t colr_size;
    uint64_t border_voxels;  /* voxels with a non-zero normal sum */
} meso_cells_chunks;

/* Octahedral U16 x 2 encoding of a unit vector, and its decoder (returns a unit vector). */
void meso_octa_encode(const double n[3], uint16_t out[2]);
void meso_octa_decode(const uint16_t in[2], double n[3]);

/* The normal of tile-map voxel (x, y, z) (top of this file), unnormalised;
 * zero deep inside a cell. */
void meso_cells_normal_sum(const meso_tile_map* m, uint32_t x, uint32_t y, uint32_t z, double out[3]);

/* Encode everything. `origin` / `voxel_size` are the grid's (stored as f32:
 * pass values already rounded to f32 so the file says exactly what was
 * classified). `colour` is the spec above (NULL: "hash"). threads <= 0: all
 * cores; the bytes do not depend on it. */
meso_result meso_cells_chunks_build(const meso_tile_map* m, const meso_split_cells* sc, const meso_membership* mb,
                                    const double origin[3], double voxel_size, const char* colour, int threads,
                                    meso_cells_chunks* out, meso_error* err);

void meso_cells_chunks_free(meso_cells_chunks* c);

#ifdef __cplusplus
}
#endif
#endif /* MESO_CELLS_CHUNKS_H */
