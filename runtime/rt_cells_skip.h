/* rt_cells_skip.h — how far a cells ray may jump from a tile-map voxel
 * without passing another split cell (rt_cells_skip.c). Pure C, no GL. */
#ifndef MESO_RT_CELLS_SKIP_H
#define MESO_RT_CELLS_SKIP_H

#include <stdint.h>

#include <stddef.h>

#include "meso_file.h"

/* Largest radius stored (31 fits the five bits the packing leaves), and
 * the largest tile map that gets radii (R^3 voxels). */
enum { MESOI_CELLS_SKIP_MAX = 31, MESOI_CELLS_SKIP_RES = 1024 };

/* For each voxel v of the R^3 tile map `ids` (x fastest), the largest r <=
 * MESOI_CELLS_SKIP_MAX such that every voxel of the cube [v - r, v + r]^3
 * lies in the tile and has v's split id; written to radius[v]. */
void mesoi_cells_skip_radii(const uint32_t* ids, uint32_t res, uint8_t* radius);

/* Bytes of scratch mesoi_cells_skip_pack needs for an R^3 map; 0 above
 * MESOI_CELLS_SKIP_RES (no radii). */
size_t mesoi_cells_skip_scratch(uint32_t res);

/* Packs the radii into the tile map in place (u16 or u32 values,
 * little-endian, as TILE stores them) above the split ids' bits, and
 * returns the number of bits the ids keep (the shader's u_id_bits), or 0
 * when an id leaves no room (S >= 2^11 in u16, 2^27 in u32) or R is above MESOI_CELLS_SKIP_RES (the map is
 * left as it is, no radii). `scratch` holds mesoi_cells_skip_scratch(res)
 * bytes, suitably aligned for uint32_t. */
int mesoi_cells_skip_pack(uint8_t* tile, int wide, uint32_t res, void* scratch);

/* The same for the TILE chunk of (object, lod) in f, whose checked copy is
 * `tile` (meso_file_check_cells' keep), with scratch from `alloc`; 0 when
 * there is no such chunk or no memory for it (nothing packed). */
int mesoi_cells_skip_level(const meso_file* f, uint32_t object, uint16_t lod, uint8_t* tile,
                           const meso_allocator* alloc);

/* Test hook: 0 packs no radii at load (the walk goes voxel by voxel, as
 * before them); default 1. Set it before loading, from one thread. */
extern int mesoi_cells_skipping;

#endif
