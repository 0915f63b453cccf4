/*
 * shell_map.h — the shell mappings in double precision: Φ (smooth), Φ_c
 * (curved, Coons patches), their exact inverses, and the texture-function
 * sampling of FORMAT.md §7.2. The CPU reference ray caster
 * (shell_reference.c) is built on this; the GLSL in runtime/shaders/
 * mirrors it operation by operation in single precision, so GL images can be
 * compared with the reference pixel by pixel.
 *
 * Specification: papers/smooth-and-curved-shell-mapping.md §3 (mapping),
 * §4 (rendering). Notation: a prism has bottom vertices B0 B1 B2 (w = 0) and
 * top vertices B_k + N_k (w = 1); N_k is the director. Barycentrics
 * λ = (t, u, v), t = 1 - u - v.
 *
 *   Φ(u,v,w) = Σ λ_k B_k + w Σ λ_k N_k                               (eq. 1)
 *   T(w)     = triangle (B_k + w N_k)  — barycentric correspondence: Φ(u,v,w)
 *              has barycentrics (u,v) in T(w).
 *
 * Exact inverse (reference only): p lies in the plane of T(w) iff
 * det[A1−A0, A2−A0, p−A0] = 0 with A_k = B_k + w N_k, a cubic in w. Every
 * real root is tried; a root whose barycentrics (u,v) are inside the
 * triangle (with a 1e-9 tolerance) and w ∈ [0,1] is a preimage. Where Φ is
 * not injective (folded prisms) the smallest such w is returned — decided
 * here, the paper assumes bijectivity.
 *
 * Curved shells (§3.2). The paper repeats the construction of Smits et al.
 * only in words; this is what meso decided and what the GLSL computes.
 *   m_k = N_k / |N_k| (unit directors), w' = w/2 + 1/4 (the paper's
 *   compression), A_k = B_k + w' N_k (the vertices of T(w')).
 *   Edge curve i→j (s ∈ [0,1], s = 0 at A_i), a cubic Hermite height over
 *   the chord with zero end heights and end slopes taken from the vertex
 *   normals:  e = A_j − A_i, a = −e·m_i, b = −e·m_j,
 *             H_ij(s) = s (1 − s) (a (1 − s) − b s).      (H_ji(1−s) = H_ij(s))
 *   Vertex-i interpolant D_i(λ), {j, k} the other two vertices: σ = 1 − λ_i,
 *   Q_j = A_i + σ (A_j − A_i), Q_k = A_i + σ (A_k − A_i), heights
 *   h_j = H_ij(σ), h_k = H_ik(σ), unit normals there
 *   M_j = normalize((1−σ) m_i + σ m_j), M_k = normalize((1−σ) m_i + σ m_k),
 *   d = Q_k − Q_j, slopes g_j = −d·M_j, g_k = −d·M_k, and with
 *   r = λ_k / (λ_j + λ_k) the Hermite cubic
 *     D_i = (2r³−3r²+1) h_j + (r³−2r²+r) g_j + (−2r³+3r²) h_k + (r³−r²) g_k;
 *   D_i = 0 where λ_j + λ_k < 1e-12 (at vertex i). On edge jk (λ_i = 0) D_i
 *   is the edge curve jk itself, so every D_i has the right boundary values.
 *   Blend: Coons(λ) = Σ ω_i D_i, ω_i = λ_i² / (λ0² + λ1² + λ2²): ω_i vanishes
 *   to second order on the edge opposite i, where D_i's cross-boundary slope
 *   is not controlled, so across each edge only the two interpolants whose
 *   slopes come from the shared edge normals matter.
 *   Φ_c(u,v,w) = Φ(u,v,w') + n̂(u,v) Coons(λ),  n(u,v) = Σ λ_k N_k,
 *   which equals Φ(u,v,w̄) with w̄ = w' + Coons(λ)/|n(u,v)|: the barycentric
 *   correspondence holds and only w changes.
 *   Exact inverse (reference): invert Φ for (u,v,w̄) — allowing w̄ a margin
 *   outside [0,1] — then solve w̄(u,v,w) = w̄ for w ∈ [0,1] on a sign change
 *   (bracketed false position with bisection fallback, ≤ 60 steps; w̄ is
 *   monotone in w in every test mesh).
 *   The GL shader uses the paper's eq. 2 instead (linear in w̄ between
 *   w̄(u,v,0) and w̄(u,v,1)). With this construction eq. 2 is exact, not an
 *   approximation: A_k = B_k + w' N_k is affine in w' and nothing else (m_k,
 *   M_j, M_k, ω_i, σ, r) depends on w', so every height and slope, hence
 *   Coons(λ), is affine in w' and w̄(u,v,·) is affine in w. Tests measure
 *   the difference (rounding only, ~1e-15).
 *
 * Texture space (FORMAT.md §7.2): (s,t') = uv_scale · Σ λ_k uv_k, w.
 */
#ifndef MESO_SHELL_MAP_H
#define MESO_SHELL_MAP_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* One prism, object space. */
typedef struct meso_prism {
    double b[3][3];  /* bottom vertices B_k (w = 0) */
    double n[3][3];  /* directors N_k: top = B_k + N_k */
    double uv[3][2]; /* texture coordinates (tiling and uv_scale applied) */
} meso_prism;

/* Φ(u,v,w) → p. */
void meso_phi(const meso_prism* P, double u, double v, double w, double p[3]);
/* Vertices of T(w). */
void meso_prism_level(const meso_prism* P, double w, double a[3][3]);
/* Barycentrics (u, v) of p (projected onto the triangle's plane) in triangle a. Returns 0 for a degenerate triangle. */
int meso_barycentric(const double a[3][3], const double p[3], double* u, double* v);
/* Exact inverse of Φ (cubic roots, see above). Returns 1 and (u,v,w) when p
 * has a preimage with u,v,t ≥ −tol and w ∈ [w_lo, w_hi]; else 0. */
int meso_phi_inverse(const meso_prism* P, const double p[3], double w_lo, double w_hi, double tol, double uvw[3]);

/* Coons(λ) for the prism's level w' (see above) and w̄ of the curved map. */
double meso_coons(const meso_prism* P, double wprime, double u, double v);
double meso_curved_wbar(const meso_prism* P, double u, double v, double w);
/* Φ_c(u,v,w) → p. */
void meso_phi_curved(const meso_prism* P, double u, double v, double w, double p[3]);
/* Exact inverse of Φ_c; 1 and (u,v,w) when p has a preimage with w ∈ [0,1].
 * The margin for w̄ is meso_curved_wbar_range's. */
int meso_phi_curved_inverse(const meso_prism* P, const double p[3], double tol, double uvw[3]);
/* A conservative range of w̄ over the prism — the curved shell
 * Φ(u,v,w̄) lies in the convex hull of B_k + lo N_k, B_k + hi N_k, which is
 * what both renderers rasterise / clip against. Derived from the
 * construction above (w' ∈ [¼,¾]):
 *   |Coons| ≤ max_i |D_i|  (ω is a partition of unity);
 *   Hermite: h00 + h01 = 1, |h10|, |h11| ≤ 4/27, so |D_i| ≤ max|h| + (8/27) max|g|;
 *   |H_ij(σ)| ≤ ¼ max(|a|, |b|) ≤ E/4;
 *   |g_j| = σ |e_jk·((1−σ) m_i + σ m_j)| / |(1−σ) m_i + σ m_j| ≤ E / c,
 *     c = min over vertex pairs |m_i + m_j| / 2 (the shortest blend);
 *   E = max |e·m_l| over the edges e of T(¼) and T(¾) (e is affine in w')
 *     and the three unit directors m_l;
 *   |n(u,v)| ≥ min_k N_k·m̂, m̂ = normalize(m_0 + m_1 + m_2).
 * So w̄ ∈ [¼ − K, ¾ + K], K = E (¼ + 8/(27 c)) / min_k N_k·m̂, widened to
 * include [0,1]. Opposed directors (c or the n bound ≤ 0): [−1, 2].
 * tests/reference checks it against dense sampling; it costs a handful of
 * dot products, so the GLSL (shell_common.glsl) recomputes it per vertex. */
void meso_curved_wbar_range(const meso_prism* P, double* lo, double* hi);
/* meso_phi_curved_inverse with an explicit w̄ range (the renderer computes
 * meso_curved_wbar_range once per prism). */
int meso_phi_curved_inverse_in(const meso_prism* P, const double p[3], double wbar_lo, double wbar_hi, double tol,
                               double uvw[3]);

/* The texture function of a shell (FORMAT.md §7.2), values already
 * normalised to [0,1]. kind 0: none (all solid), 1: height field (W×H),
 * 2: density volume (W×H×D). */
typedef struct meso_ref_texfn {
    int kind;
    uint32_t w, h, d;
    const float* values; /* w*h*d, x fastest */
} meso_ref_texfn;

/* Filtered value at texture point (s, t, w): bilinear height or trilinear
 * density with the wrap/clamp rules of FORMAT.md §7.2. */
double meso_ref_texfn_value(const meso_ref_texfn* tf, double s, double t, double w);
/* 1 when (s,t,w) is solid: w ≤ h(s,t), or α ≥ ½; kind 0: always. */
int meso_ref_texfn_solid(const meso_ref_texfn* tf, double s, double t, double w);
/* Texture-space outward normal direction g (not normalised): height
 * (−∂h/∂s, −∂h/∂t, 1), density −∇α, central differences one texel apart
 * (δ = 1/W, 1/H, 1/D); kind 0: (0,0,1). */
void meso_ref_texfn_gradient(const meso_ref_texfn* tf, double s, double t, double w, double g[3]);

/* A shell's colour (FORMAT.md §7.2 "Shell colour"): COLR texels (RGBA8,
 * sRGB) and the CMAP scale. */
typedef struct meso_ref_color {
    uint32_t w, h, d;    /* 0: no colour */
    const uint8_t* rgba; /* w*h*d texels, x fastest */
    double scale[2];     /* the CMAP record's */
} meso_ref_color;

/* Linear RGB at texture point (s, t, w): looked up at (s·scale[0],
 * t·scale[1], w), each texel decoded from sRGB (the exact curve: x ≤ 0.04045:
 * x/12.92, else ((x + 0.055)/1.055)^2.4) and then filtered trilinearly with
 * the wrap (s, t) / clamp (w) rules of the texture function — what an
 * SRGB8_ALPHA8 texture fetch with GL_LINEAR returns. Returns 0 (rgb
 * untouched) without colour. */
int meso_ref_color_value(const meso_ref_color* c, double s, double t, double w, double rgb[3]);

#ifdef __cplusplus
}
#endif
#endif /* MESO_SHELL_MAP_H */
