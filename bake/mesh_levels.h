/*
 * mesh_levels.h — levels of detail of a triangle mesh (internal): a chain of
 * meshoptimizer simplifications, each with its error measured against
 * level 0 (FORMAT.md §7.10, issue 14). mesh_levels.c says how.
 */
#ifndef MESO_MESH_LEVELS_H
#define MESO_MESH_LEVELS_H

#include <stddef.h>
#include <stdint.h>

#include "meso_bake.h"

/* The chain's limits: at most this many levels (level 0 included), and no
 * level is simplified from one of at most MESO_MESH_LEVELS_MIN_TRIANGLES.
 * 64 (256 before): the far objects of bench_lod_scene then draw 45-90
 * triangles, not 180-250, within the same pixel error (at 1 px the scene's
 * resident bytes 2.75 -> 2.60 MB, its mean error 0.98 -> 0.99 px), and the
 * first image of a streamed mesh needs 30 % fewer bytes (spot: 11.7 -> 8.2
 * KB). */
#define MESO_MESH_LEVELS_MAX 8
#define MESO_MESH_LEVELS_MIN_TRIANGLES 64u

typedef struct meso_mesh_levels_options {
    int max_levels;  /* levels wanted, level 0 included: 0 = auto (MESO_MESH_LEVELS_MAX); 1 = level 0 only */
    int split_seams; /* 0 (default): vertices at the same position are one vertex for the simplifier's
                        topology (seams); 1: simplify the mesh as given (tests: what the seam handling changes) */
    int threads;     /* error measurement; 0 = all cores; never changes the result */
    double spacing;  /* sample spacing of the error measurement; 0 = half level 0's mean edge length */
    int lock_border; /* 1: meshopt_SimplifyLockBorder (a part's border stays as it is at every level:
                        mesh_parts.c) */
    uint32_t min_triangles; /* no level from one of at most this many; 0 = MESO_MESH_LEVELS_MIN_TRIANGLES */
} meso_mesh_levels_options;

/* A coarse level (lod >= 1). */
typedef struct meso_mesh_level {
    meso_mesh mesh;        /* the simplified mesh: a subset of level 0's vertices with their normals and uvs
                              (corner_uvs NULL), new triangles */
    double error;          /* upper bound of the two-sided distance between this surface and level 0's,
                              made non-decreasing over the chain (see mesh_levels.c) */
    double measured;       /* this level's own bound before the running max */
    double sample_radius;  /* the sampling radius included in `measured` */
    double bbox_min[3], bbox_max[3]; /* of this level's vertices */
} meso_mesh_level;

/* The coarse levels of `m` (level 0 is `m` itself): *levels gets *count
 * entries, level L at index L - 1 (0 entries when the chain stops at once:
 * too few triangles, or no simplification reaches 85 % of the triangles).
 * Free with meso_mesh_levels_free. MESO_ERR_UNSUPPORTED (and no levels)
 * in a build without meshoptimizer when more than one level is asked for. */
meso_result meso_mesh_levels_build(const meso_mesh* m, const meso_mesh_levels_options* o, meso_mesh_level** levels,
                                   uint32_t* count, meso_error* err);
void meso_mesh_levels_free(meso_mesh_level* levels, uint32_t count);

/* The triangles `corners` (3 * nt of m's vertex indices) as a mesh of their
 * own: the vertices they use, in m's order, with their normals and uvs
 * (corner_uvs NULL). MESO_ERR_OUT_OF_MEMORY (and *out zeroed) on failure. */
meso_result meso_mesh_subset(const meso_mesh* m, const uint32_t* corners, uint32_t nt, meso_mesh* out);

/* Of the faces idx[0..n) (3 indices each) left twice on the same three
 * vertices, the first stays (mesh_levels.c drop_duplicate_faces says why);
 * returns the new index count, SIZE_MAX when out of memory. */
size_t mesoi_drop_duplicate_faces(uint32_t* idx, size_t n);
#endif /* MESO_MESH_LEVELS_H */
