/*
 * shell_allowed.h — the thickness the geometry allows at each vertex of a
 * shell, and how much of it a baked shell keeps (issue 15, "thickness
 * kept"). Internal.
 *
 * >>definition
 * For vertex v with base position b_v, unit vertex normal n_v (the one the
 * directors start from, meso_vertex_normals) and shell side s (+1 exterior,
 * −1 interior; an envelope's top and bottom layers are one side each, with
 * half the thickness):
 *
 *   g_v       = min { t > 0 : b_v + t·s·n_v lies on a base triangle that
 *                     does not have v as a corner }      (∞ when none)
 *   allowed_v = min(h, g_v / 2)                           h = requested (per side)
 *
 * i.e. half the gap along the normal to the next part of the surface.
 *
 * >>what it bounds
 * In a valid shell (no inverted prism, no offset/base intersection) the
 * segment b_v + w·d_v, w in (0, 1], lies strictly between the base and the
 * offset surface, so it cannot meet the base: a director along s·n_v is at
 * most g_v long. The part of the surface the ray meets at q faces the ray
 * (an exterior ray travels outside the solid and meets faces from outside,
 * an interior ray from inside), so q's own shell grows towards v, into the
 * same gap; two such directors facing each other share g_v, and the larger
 * of their common lengths is g_v / 2. allowed_v is therefore the largest
 * thickness that v and the part it faces can both have at once along the
 * normal. It is not a bound on a director that bends away from the normal
 * (the Lp field's directors do, at concave creases), which can be longer:
 * achieved/allowed is capped at 1 per vertex before it is averaged, so a
 * vertex cannot pay for another.
 * Inside a sphere of radius R g_v = 2R, so allowed_v = min(h, R): the
 * inscribed-ball bound the issue names. In general the largest ball inside
 * the solid tangent at v has a diameter along n_v of at most g_v, so the
 * inscribed-ball radius is at most g_v / 2: the ray bound is the looser, more
 * demanding of the two, and it is exactly computable (below) and checkable.
 *
 * >>computation
 * Triangles binned in a uniform grid (triangle_grid.h); each ray is marched
 * in steps of one cell up to t = 2h (beyond it g_v / 2 > h no longer
 * matters), every cell meeting the step's bounding box (padded by 1e-9 of
 * the grid) is searched, and the march stops once the nearest hit lies
 * within the steps done. Ray/triangle by Möller–Trumbore in double, edges
 * inclusive, so a ray through an edge or corner is not lost. Each vertex is
 * independent and the minimum does not depend on the order triangles are
 * met in: the result is the same for any thread count.
 */
#ifndef MESO_SHELL_ALLOWED_H
#define MESO_SHELL_ALLOWED_H

#include <stdint.h>

#include "meso_bake.h"

/* allowed[v] (vertex_count doubles) as defined above: rays along
 * sign * normals[v] (3 floats per vertex, unit; a zero normal gets h),
 * requested thickness h > 0. threads: 0 = all. Vertices used by no
 * triangle get h. */
meso_result meso_shell_allowed(const meso_mesh* m, const float* normals, int sign, double h, int threads,
                               double* allowed, meso_error* err);

/* How much of the allowed thickness one side's directors keep, over the
 * vertices used by some triangle: ratio_v = min(1, |d_v| / allowed_v)
 * (1 where allowed_v = 0). Summaries of several sides (an envelope's two
 * layers) add up with meso_shell_allowed_add. */
typedef struct meso_shell_allowed_summary {
    uint32_t counted;          /* vertices (vertex-sides) counted */
    uint32_t below_half;       /* ratio_v < 0.5 */
    uint32_t limited;          /* allowed_v < h: the geometry, not the request, sets the bound */
    double ratio_min;          /* min ratio_v (1 when none counted) */
    double ratio_sum;          /* sum of ratio_v */
} meso_shell_allowed_summary;

/* Adds the side with directors d (3 floats per vertex) and allowed (from
 * meso_shell_allowed with thickness h) to *s; ratios, if not NULL, gets
 * ratio_v per vertex (vertices used by no triangle: 1). Start *s zeroed. */
void meso_shell_allowed_add(const meso_mesh* m, const float* d, const double* allowed, double h,
                            meso_shell_allowed_summary* s, double* ratios);

#endif /* MESO_SHELL_ALLOWED_H */
