/*
 * shell_map.c — Φ, Φ_c and their exact inverses in double precision, and the
 * texture-function sampling of FORMAT.md §7.2. shell_map.h is the
 * specification; runtime/shaders/shell_frag.glsl mirrors the forward maps
 * and the sampling operation by operation.
 */
#include "shell_map.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

#include "vec3d.h"

/* >>vectors ---------------------------------------------------------------- */

static double det3(const double a[3], const double b[3], const double c[3])
{
    double bc[3];
    cross3(b, c, bc);
    return dot3(a, bc);
}

/* >>smooth map ------------------------------------------------------------- */

void meso_phi(const meso_prism* P, double u, double v, double w, double p[3])
{
    const double t = 1.0 - u - v;
    for (int i = 0; i < 3; ++i)
        p[i] = t * P->b[0][i] + u * P->b[1][i] + v * P->b[2][i] +
               w * (t * P->n[0][i] + u * P->n[1][i] + v * P->n[2][i]);
}

void meso_prism_level(const meso_prism* P, double w, double a[3][3])
{
    for (int k = 0; k < 3; ++k)
        for (int i = 0; i < 3; ++i)
            a[k][i] = P->b[k][i] + w * P->n[k][i];
}

int meso_barycentric(const double a[3][3], const double p[3], double* u, double* v)
{
    double e1[3], e2[3], d[3];
    for (int i = 0; i < 3; ++i) {
        e1[i] = a[1][i] - a[0][i];
        e2[i] = a[2][i] - a[0][i];
        d[i] = p[i] - a[0][i];
    }
    const double d11 = dot3(e1, e1), d12 = dot3(e1, e2), d22 = dot3(e2, e2);
    const double d1 = dot3(d, e1), d2 = dot3(d, e2);
    const double den = d11 * d22 - d12 * d12;
    /* Relative test: den = |e1|²|e2|² sin²θ. */
    if (!(den > 1e-24 * d11 * d22) || !(den > 0))
        return 0;
    *u = (d22 * d1 - d12 * d2) / den;
    *v = (d11 * d2 - d12 * d1) / den;
    return 1;
}

/* >>cubic roots ------------------------------------------------------------- */

/* c[0] + c[1] x + c[2] x² + c[3] x³ and a bound on its rounding error. */
static double poly3(const double c[4], double x)
{
    return ((c[3] * x + c[2]) * x + c[1]) * x + c[0];
}

static double poly3_err(const double c[4], double x)
{
    const double ax = fabs(x);
    return 16 * DBL_EPSILON * (((fabs(c[3]) * ax + fabs(c[2])) * ax + fabs(c[1])) * ax + fabs(c[0]));
}

/* Real roots of a x² + b x + c (a = 0: linear; nothing when all vanish), in
 * the cancellation-free form (q = −½(b + sign(b)√Δ), roots q/a and c/q). */
static int quad_roots(double a, double b, double c, double out[2])
{
    if (a == 0) {
        if (b == 0)
            return 0;
        out[0] = -c / b;
        return 1;
    }
    const double disc = b * b - 4 * a * c;
    if (disc < 0)
        return 0;
    const double q = -0.5 * (b + copysign(sqrt(disc), b));
    if (q == 0) {
        out[0] = 0;
        return 1;
    }
    out[0] = q / a;
    out[1] = c / q;
    if (out[0] > out[1]) {
        const double t = out[0];
        out[0] = out[1];
        out[1] = t;
    }
    return 2;
}

/* Root of the cubic in [a, b] where it changes sign (fa·fb < 0): Newton
 * steps kept inside the bracket, bisection when a step would leave it. */
static double bracketed_root(const double c[4], double a, double b, double fa)
{
    double x = 0.5 * (a + b);
    for (int it = 0; it < 200; ++it) {
        const double fx = poly3(c, x);
        if (fx == 0)
            return x;
        if ((fx < 0) == (fa < 0)) {
            a = x;
            fa = fx;
        } else {
            b = x;
        }
        if (b - a <= 2 * DBL_EPSILON * fmax(fabs(a), fabs(b)) || b - a < 1e-300)
            break;
        const double df = (3 * c[3] * x + 2 * c[2]) * x + c[1];
        double xn = df != 0 ? x - fx / df : 0.5 * (a + b);
        if (!(xn > a && xn < b))
            xn = 0.5 * (a + b);
        x = xn;
    }
    return x;
}

/* Real roots of the cubic in [lo, hi], ascending (at most 3). The interval is
 * cut at the critical points (roots of the derivative, so every degenerate
 * case — quadratic, linear, constant — goes through the same code), then
 * each monotone piece holds at most one root, found by bracketed Newton.
 * Values within the rounding bound of zero count as zero, so double roots
 * (a tangent ray) at a critical point are found too. */
static int cubic_roots_in(const double c[4], double lo, double hi, double out[3])
{
    double cuts[4];
    int nc = 0;
    cuts[nc++] = lo;
    double cp[2];
    const int ncp = quad_roots(3 * c[3], 2 * c[2], c[1], cp);
    for (int i = 0; i < ncp; ++i)
        if (cp[i] > lo && cp[i] < hi)
            cuts[nc++] = cp[i];
    cuts[nc++] = hi;
    int n = 0;
    double f_prev = poly3(c, cuts[0]);
    if (fabs(f_prev) <= poly3_err(c, cuts[0])) {
        f_prev = 0;
        out[n++] = cuts[0];
    }
    for (int s = 1; s < nc; ++s) {
        const double x = cuts[s];
        double fx = poly3(c, x);
        if (fabs(fx) <= poly3_err(c, x))
            fx = 0;
        if (f_prev != 0 && fx != 0 && (f_prev < 0) != (fx < 0) && n < 3)
            out[n++] = bracketed_root(c, cuts[s - 1], x, f_prev);
        if (fx == 0 && n < 3 && (n == 0 || out[n - 1] < x))
            out[n++] = x;
        f_prev = fx;
    }
    return n;
}

/* >>smooth inverse ---------------------------------------------------------- */

/* Newton on Φ(u,v,w) = p in all three unknowns, kept only while the residual
 * shrinks: the cubic's coefficients carry cancellation the direct residual
 * does not. */
static void polish(const meso_prism* P, const double p[3], double q[3])
{
    double r[3], x[3];
    meso_phi(P, q[0], q[1], q[2], x);
    for (int i = 0; i < 3; ++i)
        r[i] = x[i] - p[i];
    double rr = dot3(r, r);
    for (int it = 0; it < 3 && rr > 0; ++it) {
        double ju[3], jv[3], jw[3];
        const double t = 1 - q[0] - q[1];
        for (int i = 0; i < 3; ++i) {
            ju[i] = P->b[1][i] - P->b[0][i] + q[2] * (P->n[1][i] - P->n[0][i]);
            jv[i] = P->b[2][i] - P->b[0][i] + q[2] * (P->n[2][i] - P->n[0][i]);
            jw[i] = t * P->n[0][i] + q[0] * P->n[1][i] + q[1] * P->n[2][i];
        }
        const double det = det3(ju, jv, jw);
        if (!(fabs(det) > 0))
            return;
        /* Cramer: J δ = −r. */
        const double du = -det3(r, jv, jw) / det, dv = -det3(ju, r, jw) / det, dw = -det3(ju, jv, r) / det;
        const double nq[3] = {q[0] + du, q[1] + dv, q[2] + dw};
        double nr[3];
        meso_phi(P, nq[0], nq[1], nq[2], x);
        for (int i = 0; i < 3; ++i)
            nr[i] = x[i] - p[i];
        const double nrr = dot3(nr, nr);
        if (!(nrr < rr))
            return;
        q[0] = nq[0];
        q[1] = nq[1];
        q[2] = nq[2];
        r[0] = nr[0];
        r[1] = nr[1];
        r[2] = nr[2];
        rr = nrr;
    }
}

/* Every preimage of p with w ∈ [w_lo, w_hi] and u, v, t ≥ −tol, ascending
 * in w (at most 3). */
static int phi_preimages(const meso_prism* P, const double p[3], double w_lo, double w_hi, double tol,
                         double out[3][3])
{
    /* det[A1−A0, A2−A0, p−A0](w) with A_k = B_k + w N_k: each column is
     * linear in w, (a + w b), (c + w d), (e + w f). */
    double a[3], b[3], c[3], d[3], e[3], f[3];
    for (int i = 0; i < 3; ++i) {
        a[i] = P->b[1][i] - P->b[0][i];
        b[i] = P->n[1][i] - P->n[0][i];
        c[i] = P->b[2][i] - P->b[0][i];
        d[i] = P->n[2][i] - P->n[0][i];
        e[i] = p[i] - P->b[0][i];
        f[i] = -P->n[0][i];
    }
    const double coef[4] = {
        det3(a, c, e),
        det3(b, c, e) + det3(a, d, e) + det3(a, c, f),
        det3(a, d, f) + det3(b, c, f) + det3(b, d, e),
        det3(b, d, f),
    };
    if (coef[0] == 0 && coef[1] == 0 && coef[2] == 0 && coef[3] == 0)
        return 0; /* p is in the plane of every T(w): w is undetermined */
    double roots[3];
    const int nr = cubic_roots_in(coef, w_lo, w_hi, roots);
    int n = 0;
    for (int i = 0; i < nr; ++i) {
        double a3[3][3], q[3];
        meso_prism_level(P, roots[i], a3);
        if (!meso_barycentric((const double(*)[3])a3, p, &q[0], &q[1]))
            continue;
        q[2] = roots[i];
        polish(P, p, q);
        q[2] = fmin(fmax(q[2], w_lo), w_hi);
        if (q[0] >= -tol && q[1] >= -tol && 1 - q[0] - q[1] >= -tol) {
            out[n][0] = q[0];
            out[n][1] = q[1];
            out[n][2] = q[2];
            ++n;
        }
    }
    return n;
}

int meso_phi_inverse(const meso_prism* P, const double p[3], double w_lo, double w_hi, double tol, double uvw[3])
{
    double c[3][3];
    if (phi_preimages(P, p, w_lo, w_hi, tol, c) == 0)
        return 0;
    uvw[0] = c[0][0];
    uvw[1] = c[0][1];
    uvw[2] = c[0][2];
    return 1;
}

/* >>curved map -------------------------------------------------------------- */

/* H_ij(s): cubic Hermite height over the chord A_i → A_j. */
static double hermite_edge(const double ai[3], const double aj[3], const double mi[3], const double mj[3], double s)
{
    const double e[3] = {aj[0] - ai[0], aj[1] - ai[1], aj[2] - ai[2]};
    const double a = -dot3(e, mi), b = -dot3(e, mj);
    return s * (1 - s) * (a * (1 - s) - b * s);
}

double meso_coons(const meso_prism* P, double wprime, double u, double v)
{
    const double lam[3] = {1 - u - v, u, v};
    double A[3][3], m[3][3];
    meso_prism_level(P, wprime, A);
    for (int k = 0; k < 3; ++k) {
        for (int i = 0; i < 3; ++i)
            m[k][i] = P->n[k][i];
        normalize3(m[k]);
    }
    double num = 0, den = 0;
    for (int i = 0; i < 3; ++i) {
        const int j = i == 2 ? 0 : i + 1, k = i == 0 ? 2 : i - 1;
        const double wi = lam[i] * lam[i];
        den += wi;
        const double sjk = lam[j] + lam[k];
        if (fabs(sjk) < 1e-12)
            continue; /* D_i = 0 at vertex i */
        const double sig = 1 - lam[i];
        double qj[3], qk[3], mj[3], mk[3], dd[3];
        for (int c = 0; c < 3; ++c) {
            qj[c] = A[i][c] + sig * (A[j][c] - A[i][c]);
            qk[c] = A[i][c] + sig * (A[k][c] - A[i][c]);
            mj[c] = (1 - sig) * m[i][c] + sig * m[j][c];
            mk[c] = (1 - sig) * m[i][c] + sig * m[k][c];
            dd[c] = qk[c] - qj[c];
        }
        normalize3(mj);
        normalize3(mk);
        const double hj = hermite_edge(A[i], A[j], m[i], m[j], sig);
        const double hk = hermite_edge(A[i], A[k], m[i], m[k], sig);
        const double gj = -dot3(dd, mj), gk = -dot3(dd, mk);
        const double r = lam[k] / sjk, r2 = r * r, r3 = r2 * r;
        const double di = (2 * r3 - 3 * r2 + 1) * hj + (r3 - 2 * r2 + r) * gj + (-2 * r3 + 3 * r2) * hk + (r3 - r2) * gk;
        num += wi * di;
    }
    return den > 0 ? num / den : 0;
}

double meso_curved_wbar(const meso_prism* P, double u, double v, double w)
{
    const double wp = 0.5 * w + 0.25, t = 1 - u - v;
    double n[3];
    for (int i = 0; i < 3; ++i)
        n[i] = t * P->n[0][i] + u * P->n[1][i] + v * P->n[2][i];
    const double len = sqrt(dot3(n, n));
    return len > 0 ? wp + meso_coons(P, wp, u, v) / len : wp;
}

void meso_phi_curved(const meso_prism* P, double u, double v, double w, double p[3])
{
    meso_phi(P, u, v, meso_curved_wbar(P, u, v, w), p);
}

void meso_curved_wbar_range(const meso_prism* P, double* lo, double* hi)
{
    /* The bound of shell_map.h, term by term. */
    double m[3][3];
    for (int k = 0; k < 3; ++k) {
        const double len = sqrt(dot3(P->n[k], P->n[k]));
        for (int c = 0; c < 3; ++c)
            m[k][c] = len > 0 ? P->n[k][c] / len : 0;
    }
    double E = 0; /* max |e·m_l| over the edges of T(¼) and T(¾) */
    for (int lev = 0; lev < 2; ++lev) {
        const double wp = lev ? 0.75 : 0.25;
        for (int i = 0; i < 3; ++i) {
            const int j = (i + 1) % 3;
            double e[3];
            for (int c = 0; c < 3; ++c)
                e[c] = (P->b[j][c] + wp * P->n[j][c]) - (P->b[i][c] + wp * P->n[i][c]);
            for (int l = 0; l < 3; ++l)
                E = fmax(E, fabs(dot3(e, m[l])));
        }
    }
    double cmin = 1, msum[3] = {0, 0, 0};
    for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3;
        double h[3];
        for (int c = 0; c < 3; ++c) {
            h[c] = 0.5 * (m[i][c] + m[j][c]);
            msum[c] += m[i][c];
        }
        cmin = fmin(cmin, sqrt(dot3(h, h)));
    }
    const double ms = sqrt(dot3(msum, msum));
    double nmin = INFINITY;
    for (int k = 0; k < 3; ++k)
        nmin = fmin(nmin, ms > 0 ? dot3(P->n[k], msum) / ms : 0);
    if (!(cmin > 1e-6 && nmin > 0) || !isfinite(E)) {
        *lo = -1.0; /* directors opposed or a degenerate prism: no bound, a wide default */
        *hi = 2.0;
        return;
    }
    const double K = E * (0.25 + 8.0 / (27.0 * cmin)) / nmin;
    *lo = fmin(0.25 - K, 0.0);
    *hi = fmax(0.75 + K, 1.0);
}

int meso_phi_curved_inverse_in(const meso_prism* P, const double p[3], double wbar_lo, double wbar_hi, double tol,
                               double uvw[3])
{
    double c[3][3];
    const int n = phi_preimages(P, p, wbar_lo, wbar_hi, tol, c);
    for (int i = 0; i < n; ++i) {
        const double u = c[i][0], v = c[i][1], target = c[i][2];
        double f0 = meso_curved_wbar(P, u, v, 0) - target, f1 = meso_curved_wbar(P, u, v, 1) - target;
        double w;
        if (fabs(f0) <= 1e-12) {
            w = 0;
        } else if (fabs(f1) <= 1e-12) {
            w = 1;
        } else if ((f0 < 0) != (f1 < 0)) {
            /* Bracketed false position (Illinois), bisecting whenever it
             * stalls; at most 60 evaluations. w̄ is affine in w (header), so
             * the first secant step is already the root up to rounding. */
            double a = 0, b = 1, fa = f0, fb = f1;
            int side = 0;
            w = 0.5;
            for (int it = 0; it < 60; ++it) {
                double m = (a * fb - b * fa) / (fb - fa);
                if (!(m > a && m < b) || it % 4 == 3)
                    m = 0.5 * (a + b);
                const double fm = meso_curved_wbar(P, u, v, m) - target;
                w = m;
                if (fm == 0 || b - a <= 4 * DBL_EPSILON)
                    break;
                if ((fm < 0) == (fa < 0)) {
                    a = m;
                    fa = fm;
                    if (side == -1)
                        fb *= 0.5;
                    side = -1;
                } else {
                    b = m;
                    fb = fm;
                    if (side == 1)
                        fa *= 0.5;
                    side = 1;
                }
                if (fabs(fm) <= 4 * DBL_EPSILON * (fabs(target) + 1))
                    break;
            }
        } else {
            continue;
        }
        uvw[0] = u;
        uvw[1] = v;
        uvw[2] = w;
        return 1;
    }
    return 0;
}

int meso_phi_curved_inverse(const meso_prism* P, const double p[3], double tol, double uvw[3])
{
    double lo, hi;
    meso_curved_wbar_range(P, &lo, &hi);
    return meso_phi_curved_inverse_in(P, p, lo, hi, tol, uvw);
}

/* >>texture function -------------------------------------------------------- */

/* Texel pair and weight along a wrapping axis of n texels (centres at
 * (i + ½)/n, GL_REPEAT). */
static void axis_wrap(double s, uint32_t n, uint32_t* i0, uint32_t* i1, double* f)
{
    if (!isfinite(s))
        s = 0;
    const double x = (s - floor(s)) * n - 0.5; /* [−½, n − ½] */
    const double fl = floor(x);
    *f = x - fl;
    const long long i = (long long)fl; /* −1 .. n */
    *i0 = (uint32_t)(((i % (long long)n) + (long long)n) % (long long)n);
    *i1 = (*i0 + 1) % n;
}

/* Same along a clamped axis (GL_CLAMP_TO_EDGE). */
static void axis_clamp(double s, uint32_t n, uint32_t* i0, uint32_t* i1, double* f)
{
    if (!isfinite(s))
        s = 0;
    double x = s * n - 0.5;
    x = fmin(fmax(x, 0.0), (double)(n - 1));
    const double fl = floor(x);
    *f = x - fl;
    *i0 = (uint32_t)fl;
    *i1 = *i0 + 1 < n ? *i0 + 1 : n - 1;
}

double meso_ref_texfn_value(const meso_ref_texfn* tf, double s, double t, double w)
{
    if (!tf || tf->kind == 0 || !tf->values || tf->w == 0 || tf->h == 0)
        return 1.0;
    uint32_t x0, x1, y0, y1, z0 = 0, z1 = 0;
    double fx, fy, fz = 0;
    axis_wrap(s, tf->w, &x0, &x1, &fx);
    axis_wrap(t, tf->h, &y0, &y1, &fy);
    const size_t W = tf->w, H = tf->h;
    if (tf->kind == 2 && tf->d > 0)
        axis_clamp(w, tf->d, &z0, &z1, &fz);
#define TX(x, y, z) ((double)tf->values[((size_t)(z) * H + (y)) * W + (x)])
    const double c0 = (1 - fy) * ((1 - fx) * TX(x0, y0, z0) + fx * TX(x1, y0, z0)) +
                      fy * ((1 - fx) * TX(x0, y1, z0) + fx * TX(x1, y1, z0));
    if (tf->kind != 2)
        return c0;
    const double c1 = (1 - fy) * ((1 - fx) * TX(x0, y0, z1) + fx * TX(x1, y0, z1)) +
                      fy * ((1 - fx) * TX(x0, y1, z1) + fx * TX(x1, y1, z1));
#undef TX
    return (1 - fz) * c0 + fz * c1;
}

int meso_ref_texfn_solid(const meso_ref_texfn* tf, double s, double t, double w)
{
    if (!tf || tf->kind == 0)
        return 1;
    const double val = meso_ref_texfn_value(tf, s, t, w);
    return tf->kind == 1 ? w <= val : val >= 0.5;
}

void meso_ref_texfn_gradient(const meso_ref_texfn* tf, double s, double t, double w, double g[3])
{
    if (!tf || tf->kind == 0 || tf->w == 0 || tf->h == 0) {
        g[0] = 0;
        g[1] = 0;
        g[2] = 1;
        return;
    }
    const double ds = 1.0 / tf->w, dt = 1.0 / tf->h;
    const double hs = (meso_ref_texfn_value(tf, s + ds, t, w) - meso_ref_texfn_value(tf, s - ds, t, w)) / (2 * ds);
    const double ht = (meso_ref_texfn_value(tf, s, t + dt, w) - meso_ref_texfn_value(tf, s, t - dt, w)) / (2 * dt);
    if (tf->kind == 1) {
        g[0] = -hs;
        g[1] = -ht;
        g[2] = 1;
        return;
    }
    const double dw = 1.0 / (tf->d > 0 ? tf->d : 1);
    const double hw = (meso_ref_texfn_value(tf, s, t, w + dw) - meso_ref_texfn_value(tf, s, t, w - dw)) / (2 * dw);
    g[0] = -hs;
    g[1] = -ht;
    g[2] = -hw;
}

/* >>colour ------------------------------------------------------------------ */

static double srgb_to_linear(double x)
{
    return x <= 0.04045 ? x / 12.92 : pow((x + 0.055) / 1.055, 2.4);
}

int meso_ref_color_value(const meso_ref_color* c, double s, double t, double w, double rgb[3])
{
    if (!c || !c->rgba || c->w == 0 || c->h == 0 || c->d == 0)
        return 0;
    uint32_t x[2], y[2], z[2];
    double fx, fy, fz;
    axis_wrap(s * c->scale[0], c->w, &x[0], &x[1], &fx);
    axis_wrap(t * c->scale[1], c->h, &y[0], &y[1], &fy);
    axis_clamp(w, c->d, &z[0], &z[1], &fz);
    const double wx[2] = {1 - fx, fx}, wy[2] = {1 - fy, fy}, wz[2] = {1 - fz, fz};
    rgb[0] = rgb[1] = rgb[2] = 0;
    for (int k = 0; k < 8; ++k) {
        const int a = k & 1, b = (k >> 1) & 1, e = k >> 2;
        const double wt = wx[a] * wy[b] * wz[e];
        const uint8_t* p = c->rgba + 4 * (((size_t)z[e] * c->h + y[b]) * c->w + x[a]);
        for (int i = 0; i < 3; ++i)
            rgb[i] += wt * srgb_to_linear(p[i] / 255.0);
    }
    return 1;
}
