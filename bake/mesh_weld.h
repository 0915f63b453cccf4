/*
 * mesh_weld.h — one vertex per position: welding a triangle soup whose
 * vertices were split for their attributes (glTF splits a vertex wherever
 * its normal or uv differs, so a textured box arrives as 24 vertices, and
 * every primitive has vertices of its own).
 */
#ifndef MESO_MESH_WELD_H
#define MESO_MESH_WELD_H

#include <stddef.h>
#include <stdint.h>

#include "meso_bake.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A triangle soup: vertex_count positions (3 floats) with uvs (2 floats,
 * NULL when none), triangle_count index triples, and per triangle a value
 * carried along (material; NULL when none). */
typedef struct meso_weld_input {
    const float* positions;
    const float* uvs;
    size_t vertex_count;
    const uint32_t* indices;
    const uint32_t* triangle_tags;
    size_t triangle_count;
} meso_weld_input;

/* Weld vertices with bitwise equal positions (-0 equals +0), keeping the
 * soup's order of first appearance and dropping vertices no triangle uses, into *out: positions, indices, and, when the soup has uvs, the
 * uv of each corner kept as the OpenMesh reader keeps OBJ's (`uvs` the
 * vertex's last corner uv, `corner_uvs` set only when a vertex has two:
 * a seam; meso_bake.h). Triangles that welding leaves with a repeated corner
 * are dropped and counted in *dropped. Normals: the normalised sum of the
 * unit normals of the faces around each vertex, as the OpenMesh reader
 * computes them. *tags (may be NULL) gets the kept triangles' tags
 * (malloc'd, NULL when the input has none). Vertex indices must be in
 * range (the caller checked). */
meso_result meso_mesh_weld(const meso_weld_input* in, meso_mesh* out, uint32_t** tags, uint32_t* dropped,
                           meso_error* err);

#ifdef __cplusplus
}
#endif
#endif /* MESO_MESH_WELD_H */
