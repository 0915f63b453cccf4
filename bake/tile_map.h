/*
 * tile_map.h — tile maps of cell-based objects (cell-based-object-representation.md
 * §3.1.3 "Cell Tiles", §4.1 "Tile Map").
 *
 * A tile map is an R × R × R grid of cell indices over one tile: 0 is empty
 * space, 1..K a cell. Tiles repeat over object space, so a generated map must
 * tile seamlessly in all six directions: a cell leaving the tile through one
 * face continues on the opposite face.
 *
 * Layout: voxel (x, y, z), 0 <= x, y, z < R, is cells[x + R * (y + R * z)]
 * (x fastest); its centre is at ((x + 1/2) / R, (y + 1/2) / R, (z + 1/2) / R)
 * in tile units (one tile = 1 along each axis).
 *
 * Generators (the thesis gives no construction beyond "randomly set some
 * seed points" and "spheres with a certain radius"; what follows is ours):
 *
 *   Voronoi   K seeds; every voxel takes the index (1..K) of the seed nearest
 *             to its centre, distances Euclidean on the 3-torus (each axis
 *             wraps with period 1), so the map is periodic by construction.
 *   spheres   K centres and a radius r (tile edges); a voxel whose centre is
 *             within r of some centre (on the torus) takes the index of the
 *             nearest such centre, others are 0. Overlapping spheres split
 *             their overlap by nearest centre, so every sphere's cell is a
 *             ball cut by planes: convex and connected.
 *
 * Exact arithmetic: positions are integers on a lattice of M = 2 R S points
 * per tile edge (S = MESO_TILE_MAP_SUBSTEPS); voxel centre x is at (2x + 1) S.
 * The per-axis torus distance is min(|a − b| mod M, M − |a − b| mod M) and
 * squared distances are summed in 64 bits (at most 3 (M/2)² < 2⁵⁴), so
 * there is no rounding anywhere: ties are real ties, broken towards the lower
 * index, and an independent brute force over the 27 periodic images gives
 * bit-identical maps.
 *
 * Seeds: splitmix64 (S. Vigna, public domain; the generator of Java's
 * SplittableRandom) started at `rng_seed`. Seed k's coordinates are drawn in
 * the order x, y, z, seed 0 first; each coordinate is ((u >> 32) * M) >> 32
 * for the next 64-bit output u. Same parameters, same map, on any platform
 * and any thread count (lines of voxels are independent; OpenMP threads
 * split them).
 *
 * Cost: O(R³ K) (every voxel against every seed, seeds whose y, z part
 * alone is too far skipped). R = 128, K = 64: 0.17 s on one core here; it is
 * not meant for K in the thousands.
 *
 * Raw files (mesobake's `FILE.raw:R`): exactly R³ little-endian uint16 cell
 * indices, x fastest, then y, then z, no header. K is the largest index in
 * the file. Nothing is assumed about the file's periodicity: the split-cell
 * stage (split_cells.h) treats whatever is there correctly.
 */
#ifndef MESO_TILE_MAP_H
#define MESO_TILE_MAP_H

#include "meso_bake.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Tile-map issue codes (meso_error.code):
 *   3150 parameters out of range (resolution, count, radius)
 *   3151 tile-map file missing or unreadable
 *   3152 tile-map file content unusable (wrong size for R)
 *   3153 a tile does not fit the requested split-cell packing (split_cells.h) */
#define MESO_TILEMAP_ISSUE_PARAMS 3150u
#define MESO_TILEMAP_ISSUE_FILE 3151u
#define MESO_TILEMAP_ISSUE_CONTENT 3152u
#define MESO_TILEMAP_ISSUE_PACKING 3153u

#define MESO_TILE_MAP_MAX_RES MESO_BAKE_MAX_TILE_RES /* largest R: 1024 (meso_bake.h) */
#define MESO_TILE_MAP_MAX_CELLS 65535u  /* largest K (indices are uint16) */
#define MESO_TILE_MAP_SUBSTEPS 65536u   /* S: lattice points per half voxel */

typedef enum meso_tile_map_kind {
    MESO_TILE_MAP_VORONOI = 0,
    MESO_TILE_MAP_SPHERES = 1,
    MESO_TILE_MAP_RAW = 2, /* read from a file or bytes; not generated */
    MESO_TILE_MAP_KIND_COUNT
} meso_tile_map_kind;

/* What to generate. Zero-initialise, then set: */
typedef struct meso_tile_map_params {
    meso_tile_map_kind kind; /* VORONOI or SPHERES */
    uint32_t res;            /* R, voxels per axis: 1..MESO_TILE_MAP_MAX_RES */
    uint32_t count;          /* K, seeds or spheres: 1..MESO_TILE_MAP_MAX_CELLS */
    double radius;           /* spheres: radius in tile edges, (0, 1]; ignored for Voronoi */
    uint64_t rng_seed;       /* splitmix64 start state (any value, 0 included) */
} meso_tile_map_params;

/* A tile map. Zero-initialise; free with meso_tile_map_free. */
typedef struct meso_tile_map {
    meso_tile_map_kind kind;
    uint32_t res;        /* R */
    uint32_t cell_count; /* K: indices are 0..K (a generated index may own no voxel) */
    uint16_t* cells;     /* R³ indices, x fastest; 0 = empty space */
    /* Generated maps only (NULL / 0 for raw ones): */
    uint32_t* seeds;     /* 3 K lattice coordinates in [0, M), seed k at seeds[3k..3k+2] */
    uint64_t radius_sq;  /* spheres: squared radius in lattice units (round(r M))² */
} meso_tile_map;

/* One splitmix64 step: advances *state and returns the next output. */
uint64_t meso_splitmix64(uint64_t* state);

/* Generate a map (see the top of this file). threads <= 0: all cores. On
 * failure returns MESO_ERR_INVALID_ARG (code 3150) or MESO_ERR_OUT_OF_MEMORY
 * and leaves *out zeroed. */
meso_result meso_tile_map_generate(const meso_tile_map_params* p, int threads, meso_tile_map* out,
                                   meso_error* err);

/* A map from R³ little-endian uint16 values in `bytes` (copied). `size` must
 * be exactly 2 R³: otherwise MESO_ERR_CORRUPT with code 3152 and a message
 * giving both sizes (and the R the size would fit, if any). */
meso_result meso_tile_map_from_raw(const void* bytes, size_t size, uint32_t res, meso_tile_map* out,
                                   meso_error* err);

/* The same from a file: MESO_ERR_IO with code 3151 when it can not be read,
 * 3152 when its size is not 2 R³. */
meso_result meso_tile_map_read_raw(const char* path, uint32_t res, meso_tile_map* out, meso_error* err);

/* The index of voxel (x, y, z) for ANY integers: generated maps evaluate
 * their generator at that voxel's centre (outside the tile too, which is how
 * tests see that the function itself is periodic); raw maps wrap the
 * coordinates. */
uint16_t meso_tile_map_eval(const meso_tile_map* m, int64_t x, int64_t y, int64_t z);

void meso_tile_map_free(meso_tile_map* m);

#ifdef __cplusplus
}
#endif
#endif /* MESO_TILE_MAP_H */
