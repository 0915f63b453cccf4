/*
 * lp_distance.h — the Lp-averaged distance function of a triangle mesh, its
 * analytic gradient, and a Barnes–Hut evaluator (issue #4).
 *
 * Source: Peng, Kristjansson, Zorin, "Interactive modeling of topologically
 * complex geometric detail", SIGGRAPH 2004, §4.1–4.2
 * (../shared/papers/volume-textures-lp-averaged-shells.md). The extracted text
 * of its formulas is partly garbled; what follows is re-derived, not copied.
 *
 * >>definition (§4.1, Eq. 3)
 *   I(x)   = ∫_M |x−y|^−p dy                    (surface integral, dy = area)
 *   d_p(x) = (I(x) / A)^(−1/p),   A = total area of M.
 * Far from M, I ≈ A |x|^−p, so d_p ≈ |x|: the area normalisation makes d_p a
 * length and its gradient dimensionless with |∇d_p| → 1 at infinity.
 *
 * >>gradient
 *   ∇_x |x−y|^−p = −p |x−y|^(−p−2) (x−y), so with
 *   J(x) = ∫_M (x−y) |x−y|^(−p−2) dy          (∇I = −p J)
 *   ∇d_p = −(1/p) (I/A)^(−1/p−1) (1/A) ∇I = d_p^(p+1) J / A = d_p · J / I
 * (the last form uses d_p^p = A/I; it is what the code evaluates, it neither
 * overflows nor needs A). ∇d_p points away from the surface: d_p grows away
 * from M, so inside a closed sphere the gradient points towards the centre.
 *
 * >>p = 3 per triangle (closed form; §4.2 "Computing integrals per face")
 * The paper integrates r^−3 over three wedges (its Eq. 4, garbled in our
 * copy). We use the equivalent solid-angle form instead: for a flat triangle T
 * and a point x at distance h from T's plane, the solid angle T subtends is
 * Ω = ∫_T cosθ / r² dy = ∫_T h / r³ dy, hence
 *   ∫_T |x−y|^−3 dy = Ω_T(x) / h.
 * Van Oosterom–Strackee with u = a−x, v = b−x, w = c−x:
 *   tan(Ω/2) = |u·(v×w)| / D,  D = |u||v||w| + (u·v)|w| + (u·w)|v| + (v·w)|u|,
 * and |u·(v×w)| = 2·area(T)·h =: Y. So ∫_T r^−3 = 2·atan2(Y, D) / h.
 * On the plane outside T (h → 0, D > 0) this is 0/0; writing
 * 2·atan2(Y, D)/h = (4·area/D) · F(Y/D) with F(t) = atan(t)/t (a series for
 * small t) removes the cancellation: the in-plane limit is 4·area/D. On the
 * closed triangle (h = 0 and D ≤ 0) the integral diverges (+∞).
 * The gradient integral needs no second formula: for p = 3,
 * ∫_T (x−y) r^−5 dy = −(1/3) ∇_x ∫_T r^−3 dy, and the closed form above is
 * differentiated analytically (∇h = ±n, ∇D from the products above), again
 * in the F(t) form when t = Y/D ≤ 1 so the normal component stays accurate
 * near the plane.
 *
 * >>other p (semi-analytic quadrature)
 * For p ≠ 3 (real p in (2, 16], e.g. the CLI's --p) each triangle is split
 * into the signed sub-triangles (x0, P, Q) of its edges about the foot x0 of
 * x on its plane; in polar coordinates about x0 the radial integral of
 * ρ (ρ²+h²)^(−q/2) is elementary, which leaves one smooth 1-D integral over
 * the polar angle per edge. J·n = h·I_(p+2), and the in-plane part of J is
 * the edge line integral (1/p) ∮ r^−p ν ds (divergence theorem). The 1-D
 * integrals use adaptive 5-point Gauss–Legendre; details in lp_distance.c.
 * At p = 3 this agrees with the closed form to ~1e-10 or better, an
 * independent check of both. It is ~20–100× slower than the closed form and
 * is used only for triangles that Barnes–Hut does not approximate.
 *
 * >>Barnes–Hut (§4.2 "Accelerating integral computation")
 * A bounding volume hierarchy over triangles (median split of centroids on
 * the longest axis, at most 4 triangles per leaf) stores per node the area,
 * area-weighted centroid c, second moment M = ∫ (y−c)(y−c)ᵀ dy and radius
 * ρ (largest distance of a node vertex from c). A node is approximated when
 * ρ < θ·|x−c| and it lies entirely outside the near ball; the approximation
 * is its monopole (area at c) plus, with order 2 (default), the quadrupole
 * term ½ ∇∇|R|^−p : M (the dipole vanishes about the area centroid), so the
 * relative error per node is O(θ³) instead of O(θ²). The kernels r^−p and
 * r^−(p+2) are steeper than gravity's, so θ must be smaller than the usual
 * 0.5–0.7 (measured in tests/unit/test_lp_distance.c). Triangles of an opened
 * leaf that pass the same test use the 3-point edge-midpoint rule (exact for
 * quadratics: same order); the others are integrated exactly.
 *
 * >>regions
 * An incremental re-bake (shell_update.h) evaluates only near the edit, but
 * the tree over every triangle was a sixth of its time (armadillo, 2 %, a
 * 1 % edit). With opt.region, a node that is far (the test above, with
 * opt.theta and no near ball) for every point of the box, with 1e-9 of
 * relative margin, is not split: it stays one leaf of its triangles. An
 * evaluation inside the box meets it as a far cluster exactly where the
 * whole tree's evaluation would, with the same moments summed in the same
 * order, so it gives the same bits; one outside the box, or with a smaller
 * theta or a near ball, that finds it not far sums its triangles one by
 * one as any opened leaf's (correct, slower, other bits). Exact summation
 * (theta 0) visits the triangles in tree order, which unsplit clusters
 * leave unsorted: other bits too (the shell bake builds the whole tree
 * for it).
 *
 * >>localisation
 * The paper integrates only over the surface within 2h of x (h = thickness).
 * meso_lp_eval_local does that: nodes and triangles whose bounding sphere
 * lies entirely beyond the cut-off are skipped, those that straddle it count
 * whole (so d_p jumps by one small far triangle's share as x moves — far
 * below the Barnes–Hut error for triangles small against h), the rest is
 * Barnes–Hut as usual. The director tracer offers it (meso_trace_options.
 * cutoff) and bakes use it at 2h (shell_directors.c's header has the
 * measurements). The other reading, every triangle that may come
 * within near_radius of x integrated exactly whatever θ says
 * (meso_lp_eval_ex), is kept for callers that want it; with near_radius =
 * 2h in the tracer, tracing was ~47x slower at 26k triangles.
 *
 * >>determinism and threads
 * The tree is built once, deterministically (ties broken by triangle index).
 * An evaluation walks it in a fixed order that depends only on x, uses a
 * fixed-size stack and allocates nothing, so meso_lp_eval* may be called
 * concurrently on one const field and gives bit-identical results for any
 * thread count.
 *
 * >>surface points
 * d_p is 0 on M and ∇d_p is singular there (I = +∞ for p > 2). Points on the
 * surface are never evaluated: the director ODE starts at a small offset along
 * the vertex normal. A point found on a triangle returns MESO_ERR_INVALID_ARG.
 */
#ifndef MESO_LP_DISTANCE_H
#define MESO_LP_DISTANCE_H

#include <stdint.h>

#include "meso_bake.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_LP_DEFAULT_P 3.0
#define MESO_LP_DEFAULT_THETA 0.3
#define MESO_LP_DEFAULT_QUAD_TOL 1e-6
#define MESO_LP_MAX_P MESO_BAKE_MAX_P /* 16, and p > 2 (meso_bake.h) */

typedef struct meso_lp_field meso_lp_field;

/* Zero-initialise for defaults. */
typedef struct meso_lp_options {
    double p;           /* exponent of d_p, in (2, 16] (default 3; 3 uses closed forms, others quadrature) */
    double theta;       /* Barnes–Hut opening angle in (0, 1.5] (default 0.3: max gradient error ~0.3%
                         * on the test meshes; 0.5: ~4%, 0.2: ~0.05%); exact: see meso_lp_eval_ex */
    double near_radius; /* mesh units, >= 0: triangles that may be this close to x are exact (default 0) */
    double quad_tol;    /* p != 3: relative halving test of the 1-D quadrature (default 1e-6, which
                         * measured ~1e-10 actual error at p = 3) */
    int order;          /* far-field expansion: 1 monopole, 2 monopole + quadrupole (default 2) */
    const double* region; /* NULL (default): the whole tree. Else lo[3], hi[3] in mesh units: the box that
                           * holds every point the caller will evaluate at (with this theta, near radius 0),
                           * and only what such evaluations open is built (>>regions); read at create */
} meso_lp_options;

/* Work counters of evaluations, added to (zero them before the first call). */
typedef struct meso_lp_stats {
    uint64_t nodes_visited;   /* tree nodes tested */
    uint64_t multipoles;      /* nodes approximated by their expansion */
    uint64_t far_triangles;   /* triangles approximated by the 3-point (order 1: centroid) rule */
    uint64_t exact_triangles; /* triangles integrated exactly (closed form or adaptive quadrature) */
} meso_lp_stats;

/* Build the field of a triangle mesh: positions (3 * nv floats) and indices
 * (3 * nt, any orientation — d_p does not depend on it). The mesh is copied
 * (as doubles, recentred and scaled by its bounding-box diagonal so that the
 * sums stay well conditioned), so the arrays may be freed afterwards.
 * Degenerate (zero-area) triangles are allowed and contribute nothing.
 * Errors (MESO_ERR_INVALID_ARG, with a message in *err when err is not NULL):
 * NULL arrays, nv or nt of 0, a non-finite coordinate, an index >= nv, a total
 * area of 0, options out of range; MESO_ERR_OUT_OF_MEMORY. On success the
 * caller owns *out and frees it with meso_lp_field_destroy. */
meso_result meso_lp_field_create(const float* positions, uint32_t nv, const uint32_t* indices, uint32_t nt,
                                 const meso_lp_options* opt, meso_lp_field** out, meso_error* err);

/* NULL is allowed. */
void meso_lp_field_destroy(meso_lp_field* f);

/* How many times evaluations of f opened a node that opt.region left
 * unsplit (>>regions) since it was built: every such evaluation summed
 * those triangles one by one and gave other bits than the whole tree's.
 * 0 for a field without a region, and for one evaluated only inside its
 * box with its own theta and no near ball. Thread-safe; 0 for NULL. */
uint64_t meso_lp_field_unsplit_opened(const meso_lp_field* f);

/* Total area A of the mesh (mesh units squared). */
double meso_lp_field_area(const meso_lp_field* f);

/* The options in effect (defaults filled in). */
meso_lp_options meso_lp_field_options(const meso_lp_field* f);

/* d_p(x) (mesh units) and ∇d_p(x) (dimensionless, |∇d_p| → 1 far away) with
 * the field's θ and near_radius. grad may be NULL. Thread-safe on a const
 * field, allocation-free. Returns MESO_ERR_INVALID_ARG for a NULL argument or
 * a non-finite x, and for x on the surface (then *d = 0 and grad = 0). */
meso_result meso_lp_eval(const meso_lp_field* f, const double x[3], double* d, double grad[3]);

/* Same by exact summation over every triangle (no Barnes–Hut): O(nt). */
meso_result meso_lp_eval_exact(const meso_lp_field* f, const double x[3], double* d, double grad[3]);

/* Same with this call's θ (<= 0: exact summation) and near radius (mesh
 * units; lets a caller pass 2h for a per-vertex thickness h). stats may be
 * NULL; it is added to, so one struct can sum many calls (per thread). */
meso_result meso_lp_eval_ex(const meso_lp_field* f, const double x[3], double theta, double near_radius, double* d,
                            double grad[3], meso_lp_stats* stats);

/* The paper's localisation (>>localisation): the same as meso_lp_eval_ex
 * (near_radius 0) over only the surface within `cutoff` (mesh units, > 0)
 * of x. MESO_ERR_INVALID_ARG also when no triangle is that close (then
 * *d = 0 and grad = 0). */
meso_result meso_lp_eval_local(const meso_lp_field* f, const double x[3], double theta, double cutoff, double* d,
                               double grad[3], meso_lp_stats* stats);

/* >>per-triangle primitives (exposed for tests and for callers that sum
 * their own subsets). a, b, c: the triangle; x: the evaluation point. */

/* ∫_T |x−y|^−3 dy (closed form). If j is not NULL, j = ∫_T (x−y)|x−y|^−5 dy.
 * +∞ (and j = 0) when x lies on the closed triangle; 0 for a degenerate one. */
double meso_lp_triangle_p3(const double a[3], const double b[3], const double c[3], const double x[3], double j[3]);

/* ∫_T |x−y|^−p dy and (j not NULL) ∫_T (x−y)|x−y|^(−p−2) dy for any p > 2 by
 * the semi-analytic quadrature above (rel_tol <= 0: the default 1e-6).
 * +∞ (and j = 0) when x lies on the closed triangle; NaN for p <= 2. */
double meso_lp_triangle_quad(const double a[3], const double b[3], const double c[3], const double x[3], double p,
                             double rel_tol, double j[3]);

#ifdef __cplusplus
}
#endif
#endif /* MESO_LP_DISTANCE_H */
