/*
 * meso_bake.h — the baker's C pipeline API.
 *
 * Every bake stage is a C11 module in bake/ named after its algorithm. The
 * heavy C++ libraries are reached only through the adapters declared in
 * bake/adapters/adapters.h. This header holds what the stages share.
 */
#ifndef MESO_BAKE_H
#define MESO_BAKE_H

#include <stddef.h>
#include <stdint.h>

#include "meso_file.h"

#ifdef __cplusplus
extern "C" {
#endif

/* An indexed triangle mesh in host memory (the bake's working form).
 * Arrays are malloc'd and owned by the struct: free with meso_mesh_free. */
typedef struct meso_mesh {
    uint32_t vertex_count;
    uint32_t triangle_count;
    float* positions; /* 3 * vertex_count */
    float* normals;   /* 3 * vertex_count, or NULL */
    float* uvs;       /* 2 * vertex_count, or NULL */
    uint32_t* indices; /* 3 * triangle_count, counter-clockwise seen from outside */
    /* 6 * triangle_count (uv of each face corner, in `indices` order), or NULL.
     * The OpenMesh reader sets it when the input has per-corner texture
     * coordinates (OBJ `f v/vt`) and some vertex has more than one (a texture
     * seam); `uvs` is then set too (one uv per vertex, as without it). NULL
     * means `uvs` says it all. Last, so positional initialisers stay valid. */
    float* corner_uvs;
} meso_mesh;

/* Frees the arrays and zeroes the struct. NULL is allowed. */
void meso_mesh_free(meso_mesh* m);

/* Unit normal of face f (CCW seen from outside) into n; returns twice the
 * face's area (0, with n = 0, for a degenerate face). */
double meso_mesh_face_normal(const meso_mesh* m, uint32_t f, double n[3]);

/* Axis-aligned bounds of the positions; returns the diagonal length. */
double meso_mesh_bounds(const meso_mesh* m, double lo[3], double hi[3]);

/* Issue codes of bake inputs (meso_error.code; mesobake prints "E<code>").
 * Format issues keep FORMAT.md's numbers (1xxx-5xxx); inputs use 31xx:
 *   3100 the mesh reader rejected the file     3110 non-manifold edges/vertices
 *   3101 non-finite coordinate                 3111 inconsistent orientation
 *   3102 face refers to a missing vertex       3112 duplicated faces
 *                                              3113 degenerate faces
 *                                              3114 the surface intersects itself
 * Texture functions (mesobake shell --texture, bake/texture_function.h):
 *   3120 the texture SPEC does not parse       3122 texture file content unusable
 *   3121 texture file missing or unreadable    3123 .vdb: no such float grid, or empty
 *   (3124..3129 reserved for texture functions and distance maps)
 * Skeletons (bake/skeleton_swc.h): 3140..3149, each listed there.
 * Cell tile maps and split cells (bake/tile_map.h, bake/split_cells.h):
 *   3150..3153, listed in tile_map.h.
 * Winding numbers (bake/winding_number.h): 3160..3169, listed there.
 * Skeletons from meshes (bake/skeleton_from_mesh.h): 3170..3179, listed there.
 * Voxelization and membership maps (bake/voxelize.h, bake/membership.h):
 *   3180..3189, listed there.
 * Cells-object chunks (bake/cells_chunks.h): 3190..3194, listed there.
 * Mesh files before any reader sees them (bake/mesh_guard.h): 3200..3249,
 *   listed there.
 * Input meshes, whole-file and orientation: 3250..3299 —
 *   3250 (a warning) inside-out closed components were flipped (mesh_orient.h)
 *   3251 not a mesh file mesobake can read (unknown extension, e.g. /dev/null)
 *   3252 no triangles (an empty file, or not a mesh)
 * Skeletons, continued (bake/skeleton_swc.h): 3300..3349, listed there.
 * Limits up front, --max-memory (bake/memory_budget.h): 3400..3449, listed
 *   there (3400 a request from the options, 3401.. sizes input files dictate). */
#define MESO_BAKE_ISSUE_UNREADABLE 3100u

/* Fill an error struct (printf-style message). Returns `r`. */
meso_result meso_bake_fail(meso_error* err, meso_result r, uint32_t code, const char* fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

#ifdef __cplusplus
}
#endif
#endif /* MESO_BAKE_H */
