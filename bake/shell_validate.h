/*
 * shell_validate.h — validation of a baked shell (issue #4, item 4):
 * inverted prisms (conservative Jacobian test), offset-surface
 * self-intersections and offset/base intersections (exact, through CGAL), and
 * achieved ÷ requested thickness.
 *
 * A shell is a base triangle mesh b_i (meso_mesh, CCW seen from outside) plus
 * a director d_i per vertex; the offset surface has the vertices b_i + d_i and
 * the same triangles. The prism over triangle (b0, b1, b2) is
 *   Φ(u,v,w) = B(u,v) + w·D(u,v),   (u,v) in the unit triangle, w in [0,1],
 *   B = λ0 b0 + λ1 b1 + λ2 b2,  D = λ0 d0 + λ1 d1 + λ2 d2,
 *   λ0 = 1−u−v, λ1 = u, λ2 = v.
 * A prism is inverted when det J, J = [Φ_u Φ_v Φ_w], is not > 0 everywhere in
 * it (≤ 0 somewhere: folded, or collapsed to zero volume).
 *
 * >>Bernstein form of det J (degree 1 in (u,v) × degree 2 in w)
 * With e1 = b1−b0, e2 = b2−b0, f1 = d1−d0, f2 = d2−d0:
 *   Φ_u = e1 + w f1,  Φ_v = e2 + w f2,  Φ_w = D(u,v),
 *   det J = (Φ_u × Φ_v) · Φ_w = N(w) · D(u,v),
 *   N(w) = (e1 + w f1) × (e2 + w f2)            (constant in u,v; quadratic in w)
 *        = N0 (1−w)² + N1 2w(1−w) + N2 w²       (Bernstein, degree 2)
 *   N0 = e1 × e2                                 (base normal, w = 0)
 *   N2 = (e1+f1) × (e2+f2)                       (top normal, w = 1)
 *   N1 = e1 × e2 + ½ (e1 × f2 + f1 × e2)         (= ½[e1×(e2+f2) + (e1+f1)×e2])
 * and D is linear, i.e. already in degree-1 Bernstein form over the triangle
 * with the coefficients d_i. Hence
 *   det J(u,v,w) = Σ_i Σ_k λ_i B_k(w) c[i][k],   c[i][k] = d_i · N_k,
 *   B_0 = (1−w)², B_1 = 2w(1−w), B_2 = w²  — 3 × 3 = 9 coefficients.
 * c[i][0] and c[i][2] are the exact values at the 6 prism corners; c[i][1]
 * is a control coefficient (the value at vertex i, w = ½ is
 * ¼c[i][0] + ½c[i][1] + ¼c[i][2]).
 *
 * >>the test
 * All 9 coefficients > ε  ⇒  det J > 0 on the whole prism (convex hull
 * property of Bernstein polynomials): valid. Since det J is linear in (u,v),
 * for every fixed w it is a convex combination of the three "vertical edge"
 * quadratics q_i(w) = det J(vertex i, w) = Σ_k B_k(w) c[i][k]; its minimum over
 * the triangle is at a vertex, so the degree-1 triangle coefficients are
 * exact and splitting the triangle (into 4) gains nothing: only w is refined.
 * For each edge i whose coefficients are not all > ε, [0,1] is split in
 * halves by de Casteljau (up to MESO_SHELL_MAX_DEPTH levels, only the halves
 * still undecided); a split point value q_i(w) ≤ 0 (or a corner value) proves
 * the prism inverted, and an edge still undecided at the deepest level — or a
 * value in (0, ε] — is declared inverted too (conservative: never a false
 * "valid", up to the floating-point error that ε covers).
 * ε is scale-aware: 1e-12 · L² · max_i |d_i|, L = the longest of |e1|, |e2|,
 * |e1+f1|, |e2+f2|, |e2−e1|, |(e2+f2)−(e1+f1)| (det J has units of length³).
 * Exterior shells (directors outward, CCW triangles) have det J > 0: sign = +1;
 * interior shells (directors inward) use sign = −1, i.e. −det J.
 *
 * >>intersections (CGAL, exact predicates on double coordinates)
 * Offset positions are b_i + d_i evaluated in double from the float inputs.
 * - offset_self_intersections / base_self_intersections: pairs of triangles of
 *   one surface that intersect, not counting what adjacent triangles share
 *   (CGAL::Polygon_mesh_processing::self_intersections semantics: edge
 *   neighbours count only when they overlap coplanarly, vertex neighbours only
 *   when they meet beyond the shared vertex).
 * - offset_base_intersections: pairs (offset triangle s, base triangle t) that
 *   intersect. Offset vertex i and base vertex i coincide exactly when d_i = 0
 *   (the shell is compressed to nothing there); such shared corners are
 *   treated like shared vertices of adjacent triangles — a pair counts only if
 *   the triangles meet beyond them (and offset t over base t with all three
 *   directors zero, the same triangle twice, never counts: that collapsed
 *   prism is already reported as inverted).
 * - Zero-area triangles (repeated index, or collinear corners) are skipped and
 *   counted in degenerate_{base,offset}_triangles.
 * Counts are deterministic (sequential, exact).
 */
#ifndef MESO_SHELL_VALIDATE_H
#define MESO_SHELL_VALIDATE_H

#include <stdint.h>

#include "meso_bake.h"

#ifdef __cplusplus
extern "C" {
#endif

/* De Casteljau levels in w before an undecided edge is declared inverted. */
#define MESO_SHELL_MAX_DEPTH 12

/* Per-prism verdict of meso_shell_prism_check: 0 = valid (det J > 0 proven).
 * Otherwise bit i (i = 0, 1, 2) is set when det J along the vertical edge over
 * triangle corner i was not proven positive (a repair step shortens or bends
 * those directors), and MESO_PRISM_UNDECIDED is set when no non-positive
 * value was found, i.e. the verdict "inverted" is the conservative default. */
#define MESO_PRISM_EDGE0 0x01u
#define MESO_PRISM_EDGE1 0x02u
#define MESO_PRISM_EDGE2 0x04u
#define MESO_PRISM_UNDECIDED 0x08u

/* The 9 Bernstein coefficients c[3*i + k] = c[i][k] = d_i · N_k of det J (see
 * above) for the prism with base corners b[3*i..3*i+2] and directors
 * d[3*i..3*i+2], i = 0..2. Not sign-adjusted. */
void meso_shell_jacobian_bernstein(const double b[9], const double d[9], double c[9]);

/* det J at (u,v,w) from the Bernstein coefficients. */
double meso_shell_jacobian_eval(const double c[9], double u, double v, double w);

/* Conservative inversion test of one prism: returns 0 when sign·det J > 0 is
 * proven on the whole prism, else the MESO_PRISM_* bits above. sign is +1
 * (exterior shell) or −1 (interior shell). */
uint8_t meso_shell_prism_check(const double b[9], const double d[9], int sign);

/* Runs meso_shell_prism_check on every triangle of `base` with the per-vertex
 * `directors` (3 * vertex_count floats). per_prism (triangle_count bytes) may
 * be NULL. *inverted counts the nonzero verdicts, *undecided those among them
 * with MESO_PRISM_UNDECIDED (either may be NULL).
 * MESO_ERR_INVALID_ARG on NULL arrays, an index out of range, or sign ∉ {±1}. */
meso_result meso_shell_count_inverted(const meso_mesh* base, const float* directors, int sign, uint8_t* per_prism,
                                      uint32_t* inverted, uint32_t* undecided, meso_error* err);

/* Achieved ÷ requested thickness |d_i| / h_i over the vertices used by some
 * triangle, with h_i = requested[i] when requested is not NULL, else
 * `thickness` for all. Vertices with h_i ≤ 0 are not counted. *min and *mean
 * are 0 when no vertex is counted (*counted = 0; counted may be NULL).
 * MESO_ERR_INVALID_ARG on NULL arrays, a bad index, or a non-finite h_i. */
meso_result meso_shell_thickness_ratio(const meso_mesh* base, const float* directors, const float* requested,
                                       double thickness, double* min, double* mean, uint32_t* counted,
                                       meso_error* err);

/* The validation block of the bake report (JSON keys = field names). */
typedef struct meso_shell_report {
    uint32_t prisms;                      /* = triangle_count */
    uint32_t inverted_prisms;             /* det J not proven > 0 (conservative) */
    uint32_t undecided_prisms;            /* among inverted_prisms: no non-positive value found */
    uint64_t offset_self_intersections;   /* triangle pairs; UINT64_MAX when not computed */
    uint64_t offset_base_intersections;   /* (offset, base) triangle pairs; UINT64_MAX when not computed */
    uint64_t base_self_intersections;     /* defects of the input itself; UINT64_MAX when not computed */
    uint32_t degenerate_base_triangles;   /* zero-area base triangles, skipped by the counts */
    uint32_t degenerate_offset_triangles; /* zero-area offset triangles, skipped by the counts */
    double thickness_ratio_min;           /* min_i |d_i| / h_i */
    double thickness_ratio_mean;          /* mean_i |d_i| / h_i */
} meso_shell_report;

/* Validate a shell: everything above in one call, filling *out.
 * directors: 3 * vertex_count floats. requested_thickness: per-vertex h_i, or
 * NULL to use `thickness` everywhere. sign: +1 exterior, −1 interior shell.
 * inverted_per_prism: triangle_count bytes of MESO_PRISM_* verdicts, or NULL.
 * Built without CGAL (MESO_HAVE_CGAL == 0), the prism and thickness fields are
 * still filled, the three intersection counts are UINT64_MAX and the call
 * returns MESO_ERR_UNSUPPORTED. Other errors: MESO_ERR_INVALID_ARG (see the
 * functions above), MESO_ERR_OUT_OF_MEMORY, MESO_ERR_CORRUPT (CGAL failed). */
meso_result meso_shell_validate(const meso_mesh* base, const float* directors, const float* requested_thickness,
                                double thickness, int sign, uint8_t* inverted_per_prism, meso_shell_report* out,
                                meso_error* err);

/* meso_shell_validate for a base the caller has already found free of
 * self-intersections (bake_shell.c's require_shellable): the same counts
 * but base_self_intersections, left UINT64_MAX (not counted here). */
meso_result mesoi_shell_validate_checked_base(const meso_mesh* base, const float* directors, double thickness,
                                              int sign, meso_shell_report* out, meso_error* err);

#ifdef __cplusplus
}
#endif
#endif /* MESO_SHELL_VALIDATE_H */
