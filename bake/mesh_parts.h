/*
 * mesh_parts.h — a mesh cut into parts, each with its own levels of detail
 * (internal; FORMAT.md §7.11, issue 14: "each part ... draws the coarsest
 * level whose projected error is ≤ τ; neighbouring parts may differ by at
 * most one level and never crack"). mesh_parts.c says how.
 */
#ifndef MESO_MESH_PARTS_H
#define MESO_MESH_PARTS_H

#include <stdint.h>

#include "meso_bake.h"

/* Parts of about this many triangles (between half and all of it). */
#define MESO_MESH_PARTS_TRIANGLES 1024u
/* About the most parts a mesh is cut into (FORMAT.md §7.11 allows 65535):
 * a larger mesh gets larger parts. Each part is a draw call, a TOC entry
 * per level and, streamed, a level to ask for each frame: bench_stream's
 * 2.2 M-triangle torus at 4096 parts (the cap before) was 227 MB, its
 * first image needed 1.8 % of it and its synchronous frames took 61 ms
 * (median); at 256, 212 MB, 0.43 % and 20 ms. */
#define MESO_MESH_PARTS_MAX 256u

typedef struct meso_mesh_parts_options {
    uint32_t part_triangles; /* 0 = MESO_MESH_PARTS_TRIANGLES */
    int max_levels;          /* per part, level 0 included: 0 = auto (as mesh_levels.h), 1 = level 0 only */
    int threads;             /* error measurement; never changes the result */
} meso_mesh_parts_options;

typedef struct meso_mesh_part_level {
    meso_mesh mesh;                  /* level 0: the part's triangles of the input, as they are */
    double error;                    /* two-sided distance bound to the part's level 0 (0 at level 0),
                                        non-decreasing */
    double bbox_min[3], bbox_max[3]; /* of the level's vertices */
} meso_mesh_part_level;

typedef struct meso_mesh_part {
    uint32_t level_count; /* >= 1 */
    meso_mesh_part_level* level;
} meso_mesh_part;

typedef struct meso_mesh_parts {
    uint32_t count;      /* 0: the mesh was not cut (too few triangles) */
    meso_mesh_part* part;
    uint32_t edge_count; /* pairs of parts that share a vertex position */
    uint32_t* edges;     /* 2 * edge_count, a < b, ascending */
    uint32_t* part_of;   /* [the input's triangle count]: each triangle's part (0-based); a part's level 0
                            holds its triangles in the input's order */
} meso_mesh_parts;

/* Cut `m` into parts and simplify each with its border locked. A mesh of
 * fewer than 2 * part_triangles triangles is not cut (out->count 0).
 * MESO_ERR_UNSUPPORTED in a build without meshoptimizer. Free with
 * meso_mesh_parts_free (also after a failure). */
meso_result meso_mesh_parts_build(const meso_mesh* m, const meso_mesh_parts_options* o, meso_mesh_parts* out,
                                  meso_error* err);
void meso_mesh_parts_free(meso_mesh_parts* p);

#endif /* MESO_MESH_PARTS_H */
