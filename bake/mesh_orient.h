/* mesh_orient.h — turn inside-out closed meshes the right way out.
 *
 * A closed mesh whose faces all point inward is consistently oriented, so
 * the topology checks (mesh_check.h) pass it; every bake would then treat
 * its inside as its outside (an "exterior" shell grows inward). The sign of
 * the enclosed volume tells: positive when the faces are counter-clockwise
 * seen from outside.
 *
 * The decision is per connected component, not per mesh: a file may hold
 * several separate solids, and one of them inside-out is as wrong as all of
 * them (a per-mesh sum would let a large correct solid hide a small inverted
 * one). But a component is not judged alone either: a hollow solid is an
 * outer surface facing out plus a cavity surface facing in, and the cavity's
 * negative volume is right. So each closed component gets a nesting depth
 * (how many other closed components enclose it, by winding number) and:
 *   - an even depth (a solid, or an island inside a cavity) with a negative
 *     volume is inside-out and is flipped;
 *   - an odd depth (a cavity) with a positive volume is flipped only when the
 *     component directly enclosing it was flipped (the whole hollow solid was
 *     inside-out); a cavity alone is never "corrected" into an overlapping
 *     second solid.
 * A mesh whose closed components all have positive volume is never touched,
 * and only the components that can flip get a nesting depth.
 * Open or inconsistently oriented components have no volume sign and are
 * left alone (the topology checks judge them), as are closed components
 * with (near) zero volume.
 */
#ifndef MESO_MESH_ORIENT_H
#define MESO_MESH_ORIENT_H

#include "meso_bake.h"

/* Issue codes 3250..3299 (orientation of input meshes). */
#define MESO_ORIENT_ISSUE_REORIENTED 3250u /* a warning: closed components were inside-out and were flipped */

typedef struct meso_mesh_orientation {
    uint32_t components;            /* connected components (faces sharing a vertex) */
    uint32_t closed_components;     /* closed, consistently oriented, non-zero volume (only counted
                                       when some component has a negative volume; else 0) */
    uint32_t reoriented_components; /* flipped by meso_mesh_orient_outward */
    uint32_t reoriented_faces;      /* faces in them */
    int unchecked;                  /* 1: too many nested closed components to judge within
                                       MESO_ORIENT_MAX_WORK; nothing was flipped */
} meso_mesh_orientation;

/* Bound on the nesting tests (box tests plus triangles visited by winding
 * numbers, ~ a second): a mesh of many inverted components inside large
 * ones is left as it is (unchecked = 1) rather than judged for minutes. */
#define MESO_ORIENT_MAX_WORK 400000000ull

/* Flip every inside-out closed component of `m` (rules above): its faces'
 * winding (indices 1 and 2 swapped, `corner_uvs` with them) and its
 * vertices' normals (negated). Deterministic; O(n log n) plus a winding
 * number test per pair of closed components whose bounding boxes nest. */
meso_result meso_mesh_orient_outward(meso_mesh* m, meso_mesh_orientation* out, meso_error* err);

#endif
