/*
 * cells_standin.h — the error of a mesh drawn in a cells object's place
 * (internal; FORMAT.md §7.10 form MESH, issue 14): a measured upper bound
 * of the two-sided distance between the surface the cells object draws
 * and a stand-in mesh. cells_standin.c says what is measured and why it is
 * a bound.
 */
#ifndef MESO_CELLS_STANDIN_H
#define MESO_CELLS_STANDIN_H

#include <stdint.h>

#include "membership.h"
#include "split_cells.h"
#include "standin_appearance.h"
#include "voxelize.h"

/* The largest surface measured: about 170 bytes per face are held while
 * measuring (cells_standin.c). */
#define MESO_CELLS_STANDIN_MAX_FACES (1u << 20)

typedef struct meso_cells_standin_error {
    double bound;      /* the error to store: two-sided, object units */
    double sampled;    /* largest sample distance, either way (max(d_A, d_B) in cells_standin.c) */
    double radius;     /* the larger sampling radius included in bound (h / sqrt(2) or the stand-in's) */
    uint64_t faces;    /* voxel faces of the cells surface (counted up to the limit) */
    int too_many;      /* 1: more than MESO_CELLS_STANDIN_MAX_FACES faces; bound = +inf, not measured */
    /* Native levels (meso_cells_level_measure): the clipped surfaces'
     * bound, and the chained one that stands in where that is not measured
     * (+inf: not computed); 0 for a stand-in. */
    double chained, clipped;
} meso_cells_standin_error;

/* The surface a cells object draws at level 0 (its voxel faces), collected
 * once and gridded for every measurement of a bake: the solid of the split
 * cells `sc` tagged INSIDE by `mb` over grid `g`, with `base` the object's
 * base mesh (the grid's box holds it). Free with meso_cells_surface_free. */
typedef struct meso_cells_surface meso_cells_surface;
meso_result meso_cells_surface_build(const meso_mesh* base, const meso_voxel_grid* g, const meso_split_cells* sc,
                                     const meso_membership* mb, meso_cells_surface** out, meso_error* err);
/* Its faces (counted up to the limit), and whether there were more than
 * MESO_CELLS_STANDIN_MAX_FACES (then none are held). */
uint64_t meso_cells_surface_faces(const meso_cells_surface* f, int* too_many);
void meso_cells_surface_free(meso_cells_surface* f);

/* The bound for stand-in mesh `m` (at least one triangle, inside the box
 * of the tile grid and the base mesh) against the surface `f`. A solid
 * without faces (nothing INSIDE) gets bound = +inf (no stand-in can be
 * within a finite distance of nothing), one with more than
 * MESO_CELLS_STANDIN_MAX_FACES too (too_many = 1: not measured). threads
 * <= 0: all cores; the result does not depend on it. */
meso_result meso_cells_standin_measure(const meso_mesh* m, meso_cells_surface* f, int threads,
                                       meso_cells_standin_error* out, meso_error* err);

/* The error of a native coarser level (grid gl, split cells scl, tags mbl;
 * cells_levels.h) against level 0's surface f0: measured on the two
 * surfaces clipped to the base mesh (cells_standin.c, >>clipped levels),
 * or where that cannot be, the stand-in's bound with level L's voxel faces
 * in the stand-in's place plus the clipping term sqrt(3) hL derived there.
 * Nothing INSIDE at either level, or more than
 * MESO_CELLS_STANDIN_MAX_FACES faces at either, gives bound = +inf. */
meso_result meso_cells_level_measure(meso_cells_surface* f0, const meso_voxel_grid* gl, const meso_split_cells* scl,
                                     const meso_membership* mbl, int threads, meso_cells_standin_error* out,
                                     meso_error* err);

/* The colours a cells object draws at level 0 (FORMAT.md §7.2 kind 3):
 * COLR (R³ RGBA8 sRGB, one texel per voxel of a tile) or, when `grid` is
 * set, the mesh's colour grid (TX3D, grid_dims, RGBA8 sRGB) over the tile
 * grid's box (origin, extent). `vox` is set by meso_cells_surface_appearance. */
typedef struct meso_cells_colours {
    const uint8_t* colr;
    const uint8_t* grid;
    uint32_t grid_dims[3];
    double origin[3], extent[3];
    const uint32_t* vox;
} meso_cells_colours;

/* What level 0 shows on a stand-in (standin_appearance.h): at each point,
 * the colour of the voxel whose face of `f` is nearest. `c` and `f` are
 * borrowed by `out`. Returns 0 when `f` holds no faces (nothing to show). */
int meso_cells_surface_appearance(const meso_cells_surface* f, meso_cells_colours* c, mesoi_appearance* out);

#endif /* MESO_CELLS_STANDIN_H */
