/*
 * cells_levels.h — native coarser levels of a cells object (internal;
 * FORMAT.md §7.10 form NATIVE, issue 14 "coarser tile-map / membership
 * levels"). Level l >= 1 is the object again over the same tiles, with
 * the tile map at half the voxels per edge of level l - 1 (so voxels twice
 * as large), its own split cells, membership, normal and colour maps, and
 * its error measured against level 0 (cells_standin.h). The runtime draws
 * it exactly as level 0 (same kind, same chunks, same shaders), at an
 * eighth of the voxels: the TILE, NRMM and COLR bytes shrink 8x a level,
 * and the rays' voxel walk takes half the steps.
 *
 * Decisions (the thesis has no levels):
 *  - Halving, not regenerating: every tile map (generated or a raw file)
 *    is halved the same way. A coarse voxel takes the index most of its
 *    2 x 2 x 2 fine voxels hold (ties: the smallest index, so empty space,
 *    index 0, wins a tie). Indices keep their meaning, so a cell keeps its
 *    hash colour. Split cells are computed anew at the coarse resolution.
 *  - Tags are inherited, not classified again against the mesh: a cell
 *    keeps the tag it has at the finer level. Voxelizing the mesh at the
 *    coarse resolution flips cells near the surface (a coarse voxel centre
 *    falls outside where no fine one did), and a flipped cell moves the
 *    surface by a whole cell: on spot that was an error of 0.146 at level
 *    1 (21 voxels of level 0). So the coarse level's "voxelization" is the
 *    finer level's drawn solid: a coarse voxel is inside when a fine voxel
 *    of its block that holds its index is SOLID, and meso_membership's
 *    merge does the rest (a coarse split cell joining fine ones of
 *    different tags comes out INTERSECTED: carved, as a cut cell is).
 *  - Colours are prefiltered: a coarse voxel's colour is the mean, in
 *    linear light, of the fine voxels of its block that hold its index
 *    (at least one does); empty voxels stay (0, 0, 0, 0).
 *  - Normals are the coarse map's own (cells_chunks.h's smoothed indicator
 *    gradient at the coarse voxels): they shade the surface that level
 *    draws.
 */
#ifndef MESO_CELLS_LEVELS_H
#define MESO_CELLS_LEVELS_H

#include "cells_chunks.h"
#include "cells_standin.h"

typedef struct meso_cells_level {
    meso_tile_map tm;                /* R_l^3 indices */
    meso_split_cells sc;
    meso_voxel_grid g;               /* level 0's tiles and origin, voxel size 2^l h */
    meso_membership mb;
    meso_cells_chunks cc;            /* the level's CELL, TILE, SPLT, MEMB, NRMM, COLR */
    meso_cells_standin_error error;  /* against level 0; bound = +inf: not measured */
} meso_cells_level;

/* The tile map at half the resolution (fine->res even, >= 2), halved as
 * above; out->kind is MESO_TILE_MAP_RAW (no seeds). */
meso_result meso_tile_map_halve(const meso_tile_map* fine, meso_tile_map* out, meso_error* err);

/* The colour map of `coarse` (halved from `fine`) from fine's RGBA8 sRGB
 * texels, as above: 4 R^3 bytes of coarse->res into `out`. */
void meso_cells_colours_halve(const meso_tile_map* fine, const uint8_t* fine_rgba, const meso_tile_map* coarse,
                              uint8_t* out);

/* The level below the finer one (finer_*: level 0 or a level made here)
 * of the object whose level 0 draws surface f0 (cells_standin.h). threads <= 0: all cores;
 * the bytes do not depend on it. A halved map without cells (ties go to
 * empty space: small spheres vanish) gives MESO_OK with error.bound =
 * +inf, which the caller takes as "no such level". */
meso_result meso_cells_level_build(meso_cells_surface* f0, const meso_voxel_grid* finer_g, const meso_tile_map* finer_tm,
                                   const meso_split_cells* finer_sc, const meso_membership* finer_mb,
                                   const meso_cells_chunks* finer_cc, int threads, meso_cells_level* out,
                                   meso_error* err);

void meso_cells_level_free(meso_cells_level* l);

#endif /* MESO_CELLS_LEVELS_H */
