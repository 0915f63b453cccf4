/*
 * standin_levels.h — mesh stand-ins of a native object (FORMAT.md §7.10,
 * form MESO_LEVEL_MESH), shared by the cells and shell bakes (internal,
 * mesoi_ prefix). Level 1 is the object's base mesh drawn as a plain mesh,
 * with the error the kind's bake measured for it (e0: cells_standin.c,
 * bake_shell.c's standin_error); levels 2 and up are the base mesh's
 * simplifications (mesh_levels.h, the chain `mesobake mesh` writes), each
 * with error e0 + its own distance to the base mesh: Hausdorff distances
 * obey the triangle inequality, so the sum bounds the distance to the
 * surface level 0 draws.
 */
#ifndef MESO_STANDIN_LEVELS_H
#define MESO_STANDIN_LEVELS_H

#include <math.h>

#include <cjson/cJSON.h>

#include "bake_internal.h"
#include "mesh_chunk.h"
#include "mesh_levels.h"
#include "meso_layout.h"
#include "standin_appearance.h"

/* Level 0, the base mesh and at most 7 simplified meshes. */
#define MESOI_STANDIN_MAX_LEVELS 9

/* f32 no smaller than x: a stored bound stays a bound. */
static inline float mesoi_f32_up(double x)
{
    float f = (float)x;
    if ((double)f < x)
        f = nextafterf(f, INFINITY);
    return f;
}

/* The native coarser levels `levels` (a bake's --levels: 0 auto, K at most
 * K in all) leaves room for, at most `max`: auto as many as there may be;
 * K >= 3 K - 2, since level 0 and the base-mesh stand-in come first;
 * K <= 2 none (FORMAT.md §7.10, what mesobake writes). */
static inline uint32_t mesoi_native_wanted(int levels, uint32_t max)
{
    const uint32_t want = levels == 0 ? max : levels >= 3 ? (uint32_t)levels - 2 : 0;
    return want < max ? want : max;
}

typedef struct mesoi_standin_levels {
    uint32_t count;          /* stand-in levels, the base mesh's included (0: none, no LODS) */
    /* Native coarser levels the caller made (cells_levels.h), lod 1..native,
     * between level 0 and the stand-ins, which then start at lod native + 1
     * (their MESH is what the native levels resolve theirs to). Set before
     * mesoi_standin_levels_append; 1 + native + count <= MESOI_STANDIN_MAX_LEVELS. */
    uint32_t native;
    double native_error[MESOI_STANDIN_MAX_LEVELS];
    /* The mesh native level L draws and its MESH chunk's size, at index
     * L - 1, where it is not `base` (a shell's coarser base meshes:
     * shell_base_levels.h); NULL: base. */
    const meso_mesh* native_mesh[MESOI_STANDIN_MAX_LEVELS];
    size_t native_mesh_bytes[MESOI_STANDIN_MAX_LEVELS];
    /* The bounds of native level L, at index L - 1, where native_bbox[L - 1]
     * is set (a frusta object's coarser skeletons); else level 0's. */
    uint8_t native_bbox[MESOI_STANDIN_MAX_LEVELS];
    float native_min[MESOI_STANDIN_MAX_LEVELS][3], native_max[MESOI_STANDIN_MAX_LEVELS][3];
    double e0;               /* level 1's error (the base mesh's, or standin_mesh's when set) */
    /* What the chain's errors add to their own distance to the base mesh:
     * the base mesh's error (0: e0). A shell whose level 1 is not the base
     * mesh but its mid-surface (bake_shell.c, standin_error) has a smaller
     * e0 than its chain, which was simplified from the base mesh. */
    double chain_e0;
    /* Level 1's mesh and MESH chunk when it is not `base` itself (NULL:
     * base and base_chunk); the same vertices and triangles as base, so
     * base's vertex colours serve it. */
    const meso_mesh* standin_mesh;
    const mesoi_chunk* standin_chunk;
    meso_mesh_level* chain;  /* the simplified meshes, chain_count = count - 1 of them */
    uint32_t chain_count;
    meso_mesh_chunk chunk[MESOI_STANDIN_MAX_LEVELS]; /* the simplified meshes' MESH chunks */
    uint8_t lods[MESOI_STANDIN_MAX_LEVELS * MESO_LODS_RECORD_SIZE];
    float error[MESOI_STANDIN_MAX_LEVELS];      /* per level by lod (0 for level 0), as stored */
    uint32_t triangles[MESOI_STANDIN_MAX_LEVELS]; /* per level by lod; native levels: the base mesh's */
    /* Per stand-in (0 the base mesh, 1.. the chain): its VCOL, vcol_components
     * (4: RGBA8, 1: occlusion alone) bytes per vertex, or NULL
     * (mesoi_standin_levels_appearance). */
    uint8_t* vcol[MESOI_STANDIN_MAX_LEVELS];
    int vcol_components;
    float* shows;            /* what level 0 shows over each base vertex (RGBA, linear), or NULL */
    /* With an appearance that gives normals (a shell's): each base vertex's
     * baked normal (3 floats), which level 1's MESH (l1_chunk, encoded anew)
     * and, interpolated and averaged again, the chain's MESH chunks carry
     * instead of the mesh's own; else NULL. */
    float* normals;
    meso_mesh_chunk l1_chunk;
} mesoi_standin_levels;

/* The stand-ins of `base` whose own error is e0. levels: 0 = auto (the base
 * mesh and its simplified chain), N >= 2 = at most N levels in all, level
 * 0 included (2: the base mesh only). Built without meshoptimizer, the base
 * mesh is the only stand-in. */
meso_result mesoi_standin_levels_build(const meso_mesh* base, double e0, int levels, int threads,
                                       mesoi_standin_levels* out, meso_error* err);

/* Gives every stand-in of `lv` (built for `base`) its vertex colours:
 * what `a` says level 0 shows over each vertex's part of the base mesh,
 * sampled `spacing` apart at most (standin_appearance.h); the simplified
 * levels take it at the nearest point of the base mesh. With a->normals,
 * the baked normals too (lv->normals; the stand-ins' MESH chunks encoded
 * again with them): set lv->standin_mesh first. */
meso_result mesoi_standin_levels_appearance(mesoi_standin_levels* lv, const meso_mesh* base, double spacing,
                                            const mesoi_appearance* a, int threads, meso_error* err);

/* Appends to `chunks` the stand-ins' chunks: `base_chunk` (the object's
 * base MESH, level 0's) again at lod N + 1, the simplified meshes at lod
 * N + 2.. (N = lv->native), and the LODS chunk of every level (level 0's
 * and the native levels' bounds l0_min/l0_max), and adds the report's
 * "levels" array to `rep`; with vertex colours, each stand-in's VCOL at
 * its lod. Returns the chunks appended (at most
 * 2 MESOI_STANDIN_MAX_LEVELS + 1). `lv` keeps the chunks' bytes. */
size_t mesoi_standin_levels_append(mesoi_standin_levels* lv, const meso_mesh* base, const mesoi_chunk* base_chunk,
                                   const float l0_min[3], const float l0_max[3], mesoi_chunk* chunks, cJSON* rep);

/* Vertex colours of meshes near `from` (a stand-in with `shows`, RGBA
 * linear per vertex): at each vertex of meshes[k], what `from` shows at
 * the nearest point, sampled as the simplified levels' are; out[k] gets
 * `components` bytes per vertex (malloc'd, as VCOL stores them). With
 * from_normals (3 floats per vertex of `from`; else NULL), normals_out[k]
 * gets meshes[k]'s baked normals the same way (malloc'd, 3 floats each). */
meso_result mesoi_standin_colours(const meso_mesh* from, const float* shows, const float* from_normals,
                                  const meso_mesh* const* meshes, uint32_t count, double spacing, int components,
                                  int threads, uint8_t** out, float** normals_out, meso_error* err);

void mesoi_standin_levels_free(mesoi_standin_levels* lv);

#endif /* MESO_STANDIN_LEVELS_H */
