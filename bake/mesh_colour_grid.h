/* mesh_colour_grid.h — `mesobake cells --colour from-mesh[:G]`: the base
 * colour of a textured mesh (glTF pbrMetallicRoughness: base-colour factor
 * times texture) carried into a cells object as a coarse object-space grid
 * (FORMAT.md §7.2 kind 3, the TX3D colour grid).
 *
 * Why a grid (decided here, issue 16 leaves the storage open): a cells hit
 * lies on a cell's voxel faces inside the mesh, not on the mesh, so its
 * colour is the mesh's at the NEAREST surface point; a grid of those
 * colours over the tile grid's box costs the runtime one trilinear lookup
 * (8 texel fetches) and no mesh, BVH or uv data. Per-vertex colours would
 * lose the texture's detail inside each triangle, and a nearest-point
 * search per fragment is what the runtime must not do.
 *
 * Sample points: the centres of G0 × G1 × G2 equal cells spanning the box
 * (G along its longest side, the others in proportion, at least 1). Each
 * holds, as sRGB RGBA8, the base colour at the point of the mesh nearest to
 * it (exact closest point over all triangles, triangle_grid.h; ties: the
 * lowest triangle): the triangle's uv at that point (its corner uvs,
 * barycentric), the material's texture there — glTF's default sampler:
 * bilinear between texel centres in linear colour, repeating, glTF's v =
 * 0 the image's first row (meso_mesh uvs hold 1 − v: OBJ's convention) — times the base-colour factor. A triangle without a
 * material, or a material without a texture, uses the factor alone (white
 * without a material). Alpha: the factor's times the texture's, linear.
 */
#ifndef MESO_MESH_COLOUR_GRID_H
#define MESO_MESH_COLOUR_GRID_H

#include <stdint.h>

#include "meso_bake.h"

#ifdef __cplusplus
extern "C" {
#endif

/* from-mesh issues: 3562 the input carries no base colour to take (not a
 * glTF with a material, or no uvs where a texture needs them). */
#define MESO_MESH_COLOUR_ISSUE_NONE 3562u

#define MESO_MESH_COLOUR_GRID_DEFAULT 64u
#define MESO_MESH_COLOUR_GRID_MAX 256u

/* The grid's dimensions for a box of extent `ext` and `g` samples along
 * its longest side. */
void meso_mesh_colour_grid_dims(const double ext[3], uint32_t g, uint32_t dims[3]);

/* Fills `rgba` (4 dims[0] dims[1] dims[2] bytes, x fastest) for the box at
 * `lo` of extent `ext`. */
meso_result meso_mesh_colour_grid_build(const meso_mesh* m, const meso_mesh_materials* mats, const double lo[3],
                                        const double ext[3], const uint32_t dims[3], uint8_t* rgba, meso_error* err);

#ifdef __cplusplus
}
#endif
#endif /* MESO_MESH_COLOUR_GRID_H */
