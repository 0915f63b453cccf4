/* mesh_check.h — what a bake needs to know about an input mesh before it
 * trusts it: edges, boundaries, manifoldness, orientation, degeneracy. */
#ifndef MESO_MESH_CHECK_H
#define MESO_MESH_CHECK_H

#include "meso_bake.h"

typedef struct meso_mesh_topology {
    uint32_t edges;               /* undirected edges */
    uint32_t boundary_edges;      /* edges with one face */
    uint32_t nonmanifold_edges;   /* edges with more than two faces */
    uint32_t misoriented_edges;   /* two faces traversing the edge the same way */
    uint32_t degenerate_faces;    /* repeated index or (near) zero area */
    uint32_t duplicate_faces;     /* same three vertices as an earlier face, either orientation */
    uint32_t unused_vertices;     /* referenced by no face */
    uint32_t first_bad_face;      /* a face to name in messages (UINT32_MAX when none) */
    /* Boundary edges as directed vertex pairs (a, b) with the face on their
     * left (the face traverses a -> b), sorted: 2 * boundary_edges entries,
     * malloc'd, may be NULL. Free with free(). */
    uint32_t* boundary;
} meso_mesh_topology;

/* Analyse `m`. Deterministic, O(n log n). `area_eps` is the smallest face
 * area that counts as non-degenerate (e.g. 1e-12 * diagonal^2). */
meso_result meso_mesh_topology_compute(const meso_mesh* m, double area_eps, meso_mesh_topology* out, meso_error* err);

/* Refuse what no shell can be built on, with a message naming the problem
 * and a face: non-manifold or misoriented edges, degenerate or duplicate
 * faces. Open boundaries are fine (they get artificial faces). */
meso_result meso_mesh_topology_require_shellable(const meso_mesh_topology* t, const char* what, meso_error* err);

#endif
