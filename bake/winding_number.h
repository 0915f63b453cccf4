/*
 * winding_number.h — inside/outside classification by the generalized winding
 * number, for meshes that are not closed: holes, duplicated faces, triangle
 * soups (issue #6, "a generalized-winding-number path ... that does not leak").
 *
 * The winding number of a point q with respect to oriented triangles T is
 *
 *     w(q) = sum over t in T of  Omega_t(q) / (4 pi)
 *
 * with Omega_t the signed solid angle of t seen from q (Jacobson, Kavan,
 * Sorkine-Hornung, "Robust Inside-Outside Segmentation using Generalized
 * Winding Numbers", SIGGRAPH 2013). For a closed, consistently oriented
 * surface (counter-clockwise seen from outside, as meso_mesh says) it is 1
 * inside and 0 outside; a hole only removes the hole's own solid angle, so w
 * degrades smoothly instead of flipping a whole region the way a flood fill or
 * a ray-parity test leaks through a gap.
 *
 * Inside means w >= 0.5 (MESO_WINDING_INSIDE). What that gives on imperfect
 * input:
 *   - a hole: w = 1 - Omega_hole/4pi inside and Omega_hole/4pi (in magnitude)
 *     outside. A planar hole subtends less than 2 pi from either side, so an
 *     open box missing one face is still classified exactly (tests on
 *     tests/data/cube_no_bottom.obj: 5/6 at the centre; on a 0.05 grid,
 *     min w inside 0.503 and max w outside 0.481, both next to the opening);
 *   - every face twice, same orientation: w doubles (2 inside, 0 outside), the
 *     threshold still separates them;
 *   - a face pair with opposite orientations cancels; a fully inverted mesh
 *     has w = -1 inside and so classifies as outside. Orientation must be
 *     consistent up to local defects; this module does not repair it.
 *
 * Evaluation (Barill, Dickson, Schmidt, Levin, Jacobson, "Fast Winding
 * Numbers for Soups and Clouds", SIGGRAPH 2018, §3-4): a BVH over the
 * triangles stores, per node, the area-weighted centre p~, the radius r of a
 * ball around p~ holding every vertex in the node, and the first two moments
 * of the far-field expansion of the node's triangles about p~:
 *     order 1 (dipole)  N = sum_t a_t n_t           (area-weighted normal)
 *     order 2           M = sum_t a_t n_t (c_t - p~)^T  (3 x 3)
 * (a_t area, n_t unit normal, c_t centroid). A query at q uses the node's
 * expansion when |q - p~| > beta r, and otherwise descends; leaves sum the
 * exact solid angle of each triangle (Van Oosterom & Strackee, "The solid
 * angle of a plane triangle", IEEE TBME 1983, atan2 form). All in double.
 *
 * beta = MESO_WINDING_BETA = 3. The paper uses 2; measured here (3000 points
 * in and around the bounds, tests/cells/test_winding_number.c), the largest
 * |fast - exact| on sphere / torus / spot / wingnut was 6.7e-2 / 2.7e-2 /
 * 3.8e-2 / 3.0e-2 at beta 2, 3.2e-2 / 6.8e-3 / 9.0e-3 / 1.1e-2 at beta 3 and
 * 1.7e-2 / 2.9e-3 / 3.0e-3 / 4.4e-3 at beta 4 (means 2-5e-3, 0.8-1.9e-3,
 * 0.3-0.8e-3). The error of a node's expansion is O((r/d)^3) of its own
 * contribution and those errors add up, so a point deep inside a closed
 * surface, which sees all of it, collects the most; with every face twice
 * the error doubles with w. 3 keeps the error well below the 0.5 margin of
 * the classification at about 1.5x the cost of 2.
 *
 * BVH construction is deterministic: a node's triangles are split at the
 * median (ties broken by triangle index) of their centroids along the longest
 * axis of the centroid bounds; leaves hold at most MESO_WINDING_LEAF_SIZE
 * triangles. Queries are independent of each other, so the many-point query
 * gives the same bits for any thread count.
 */
#ifndef MESO_WINDING_NUMBER_H
#define MESO_WINDING_NUMBER_H

#include "meso_bake.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Winding-number issue codes (meso_error.code), 3160..3169:
 *   3160 the mesh has no triangles (or no vertices)
 *   3161 a face refers to a missing vertex
 *   3162 a vertex coordinate is not finite
 *   (3163..3169 reserved for the winding-number path) */
#define MESO_WINDING_ISSUE_EMPTY 3160u
#define MESO_WINDING_ISSUE_INDEX 3161u
#define MESO_WINDING_ISSUE_NONFINITE 3162u

#define MESO_WINDING_BETA 3.0      /* far-field test: |q - p~| > beta * radius */
#define MESO_WINDING_LEAF_SIZE 8u  /* most triangles in a BVH leaf */
#define MESO_WINDING_INSIDE 0.5    /* inside when w >= this */

/* The hierarchy (opaque). Build once, query from any number of threads. */
typedef struct meso_winding meso_winding;

/* Build the hierarchy of `m` (positions and indices only; the mesh is copied,
 * so it may be freed afterwards). threads <= 0: all cores (the build itself is
 * serial today; the argument is there so callers need not change). On success
 * *out must be freed with meso_winding_free. Failures: MESO_ERR_INVALID_ARG
 * for NULL arguments (code 0) or codes 3160..3162, MESO_ERR_OUT_OF_MEMORY;
 * *out is then NULL. */
meso_result meso_winding_build(const meso_mesh* m, int threads, meso_winding** out, meso_error* err);

/* Winding number at q = (x, y, z), fast (hierarchical) evaluation. On the
 * surface itself the value is whatever the nearest triangles give (between
 * the two sides); a non-finite q gives NaN. */
double meso_winding_query(const meso_winding* t, const double q[3]);

/* Winding numbers at `count` points xyz[3i..3i+2] into w[i]. threads <= 0:
 * all cores (meso_bake_thread_count). Points are independent, so the result
 * does not depend on the thread count. */
void meso_winding_query_many(const meso_winding* t, const double* xyz, size_t count, double* w, int threads);

/* The exact sum over all triangles of `m`, in index order (reference for
 * tests; O(triangle_count) per point). Indices are not checked. */
double meso_winding_exact(const meso_mesh* m, const double q[3]);

/* Signed solid angle of triangle (a, b, c) seen from q, divided by 4 pi:
 * positive when q is behind the triangle (on the side its counter-clockwise
 * normal points away from). */
double meso_winding_triangle(const double a[3], const double b[3], const double c[3], const double q[3]);

/* Inside test: w >= MESO_WINDING_INSIDE. */
static inline int meso_winding_inside(double w)
{
    return w >= MESO_WINDING_INSIDE;
}

/* Number of BVH nodes and the depth of the deepest leaf (for reports). */
void meso_winding_stats(const meso_winding* t, uint32_t* nodes, uint32_t* depth);

/* Frees the hierarchy. NULL is allowed. */
void meso_winding_free(meso_winding* t);

#ifdef __cplusplus
}
#endif
#endif /* MESO_WINDING_NUMBER_H */
