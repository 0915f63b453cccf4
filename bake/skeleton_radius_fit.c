/*
 * skeleton_radius_fit.c — the least-squares fit of stage 5 of
 * meso_skeleton_from_mesh: Levenberg–Marquardt on every kept node's position
 * and radius at once (MESO_SKELFIT_LSQ, the default).
 *
 * From skeleton_from_mesh.h, 5.: it starts from CGAL's positions and the
 * per-node radii and minimises Huber's loss (delta = tolerance: vertices a
 * frustum cannot reach, or that CGAL mis-assigned at a junction, pull with
 * a bounded force) of each vertex's distance to its segment's axis minus the
 * radius there (t clamped, so past an end it is the end ball), plus a weak
 * prior to CGAL's values (mesoi_skel_refit below). Why fit at all: the
 * flow rounds corners and stops short of rounded ends; with the fit the
 * test capsule is one segment with ends within 0.0004 of the caps' centres.
 * Which nodes are kept is skeleton_simplify.c's business.
 */
#include <float.h>
#include <math.h>
#include <string.h>

#include "skeleton_from_mesh_internal.h"

static inline uint32_t alias(const mesoi_fit_state* f, uint32_t i)
{
    return i < f->w->ncgal ? i : f->w->src[i];
}

/* Kept-children lists from sparent. */
static void rebuild_kids(mesoi_fit_state* f)
{
    memset(f->kstart, 0, sizeof(uint32_t) * (f->n + 1));
    for (uint32_t i = 0; i < f->n; ++i)
        if (f->keep[i] && f->sparent[i] >= 0)
            f->kstart[f->sparent[i] + 1]++;
    for (uint32_t i = 0; i < f->n; ++i)
        f->kstart[i + 1] += f->kstart[i];
    memcpy(f->path, f->kstart, sizeof(uint32_t) * f->n);
    for (uint32_t i = 0; i < f->n; ++i)
        if (f->keep[i] && f->sparent[i] >= 0)
            f->kids[f->path[f->sparent[i]]++] = i;
}

/* Every vertex to a segment: its CGAL node's, or for a kept node's own
 * vertices the nearest segment at the node (by the current fit). */
void mesoi_skel_assign_vertices(mesoi_fit_state* f)
{
    rebuild_kids(f);
    for (uint32_t v = 0; v < f->c->nv; ++v) {
        const uint32_t o = f->owner[v];
        if (!f->keep[o]) {
            f->vseg[v] = f->seg_child[o];
            continue;
        }
        const double* p = f->c->xyz + 3 * (size_t)v;
        const double* xo = f->x + 4 * (size_t)o;
        double best = DBL_MAX;
        uint32_t seg = UINT32_MAX;
        if (f->sparent[o] >= 0) {
            best = mesoi_dist_segment(f->x + 4 * (size_t)f->sparent[o], xo, p);
            seg = o;
        }
        for (uint32_t k = f->kstart[o]; k < f->kstart[o + 1]; ++k) {
            const double dk = mesoi_dist_segment(xo, f->x + 4 * (size_t)f->kids[k], p);
            if (dk < best) {
                best = dk;
                seg = f->kids[k];
            }
        }
        f->vseg[v] = seg;
    }
}

/* Residual of vertex v under parameters xs: its distance to the axis point
 * of its segment minus the radius there (t clamped to the segment, so past
 * an end it is the end ball's). Gradient blocks (position, radius) for the
 * segment's parent end in ga and child end in gb; *na / *nb the nodes
 * (*nb = UINT32_MAX for a lone ball). */
static double residual(const mesoi_fit_state* f, const double* xs, uint32_t v, double ga[4], double gb[4], uint32_t* na,
                       uint32_t* nb)
{
    const double* p = f->c->xyz + 3 * (size_t)v;
    const uint32_t b = f->vseg[v];
    double u[3], t = 0;
    const double *xa, *xb;
    if (b == UINT32_MAX) {
        *na = f->owner[v];
        *nb = UINT32_MAX;
        xa = xb = xs + 4 * (size_t)*na;
    } else {
        *na = (uint32_t)f->sparent[b];
        *nb = b;
        xa = xs + 4 * (size_t)*na;
        xb = xs + 4 * (size_t)b;
        t = mesoi_seg_param(xa, xb, p);
        t = t < 0 ? 0 : t > 1 ? 1 : t;
    }
    for (int k = 0; k < 3; ++k)
        u[k] = p[k] - (xa[k] + t * (xb[k] - xa[k]));
    const double dl = sqrt(dot3(u, u));
    if (dl > 0)
        for (int k = 0; k < 3; ++k)
            u[k] /= dl;
    for (int k = 0; k < 3; ++k) {
        ga[k] = -(1 - t) * u[k];
        gb[k] = -t * u[k];
    }
    ga[3] = -(1 - t);
    gb[3] = -t;
    return dl - ((1 - t) * xa[3] + t * xb[3]);
}

/* Huber's loss (quadratic up to delta, then linear) and its IRLS weight:
 * vertices far from their segment's surface — a protrusion the segment
 * cannot have, or a correspondence CGAL got wrong at a junction — pull
 * with a bounded force instead of dragging the frustum to them. */
static inline double huber(double res, double delta)
{
    const double a = fabs(res);
    return a <= delta ? res * res : delta * (2 * a - delta);
}

static inline double huber_weight(double res, double delta)
{
    const double a = fabs(res);
    return a <= delta ? 1 : delta / a;
}

/* Robust cost plus the prior pulling positions to CGAL's. */
static double fit_cost(const mesoi_fit_state* f, const double* xs)
{
    double cost = 0, ga[4], gb[4];
    uint32_t na, nb;
    for (uint32_t v = 0; v < f->c->nv; ++v)
        cost += huber(residual(f, xs, v, ga, gb, &na, &nb), f->tol);
    for (uint32_t i = 0; i < f->w->ncgal; ++i)
        if (f->var[i] != UINT32_MAX) {
            const double* k = f->kappa + 4 * (size_t)f->var[i];
            const double* xi = xs + 4 * (size_t)i;
            const double* p0 = f->w->pos + 3 * (size_t)i;
            const double dr = xi[3] - f->w->rad[i];
            cost += k[0] * (xi[0] - p0[0]) * (xi[0] - p0[0]) + k[1] * (xi[1] - p0[1]) * (xi[1] - p0[1]) +
                    k[2] * (xi[2] - p0[2]) * (xi[2] - p0[2]) + k[3] * dr * dr;
        }
    return cost;
}

static void add_outer(double* m, const double a[4], const double b[4])
{
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            m[4 * i + j] += a[i] * b[j];
}

/* Cholesky factor L (lower, row-major) of the 4x4 block h + mu diag(h) +
 * eps I (symmetric positive definite: eps > 0). */
static void block_cholesky(const double* h, double mu, double eps, double* L)
{
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j <= i; ++j) {
            double sum = h[4 * i + j] + (i == j ? mu * h[5 * i] + eps : 0);
            for (int k = 0; k < j; ++k)
                sum -= L[4 * i + k] * L[4 * j + k];
            L[4 * i + j] = i == j ? sqrt(sum > eps ? sum : eps) : sum / L[5 * j];
        }
}

static void block_solve(const double* L, const double* b, double* x)
{
    double y[4];
    for (int i = 0; i < 4; ++i) {
        double sum = b[i];
        for (int k = 0; k < i; ++k)
            sum -= L[4 * i + k] * y[k];
        y[i] = sum / L[5 * i];
    }
    for (int i = 3; i >= 0; --i) {
        double sum = y[i];
        for (int k = i + 1; k < 4; ++k)
            sum -= L[4 * k + i] * x[k];
        x[i] = sum / L[5 * i];
    }
}

/* out = (H + mu diag(H) + eps) in, H block-sparse: H[nv] diagonal blocks,
 * E[s] the block of segment s between its parent end's unknowns (rows) and
 * its child end's (columns). */
static void lm_matvec(const mesoi_fit_state* f, uint32_t nvar, uint32_t nseg, double mu, double eps, const double* in,
                      double* out)
{
    for (uint32_t v = 0; v < nvar; ++v)
        for (int i = 0; i < 4; ++i) {
            const double* h = f->H + 16 * (size_t)v + 4 * i;
            double s = (mu * h[i] + eps) * in[4 * v + i];
            for (int j = 0; j < 4; ++j)
                s += h[j] * in[4 * v + j];
            out[4 * v + i] = s;
        }
    for (uint32_t s = 0; s < nseg; ++s) {
        const uint32_t b = f->segs[s];
        const uint32_t va = f->var[alias(f, (uint32_t)f->sparent[b])], vb = f->var[alias(f, b)];
        const double* e = f->E + 16 * (size_t)s;
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) {
                out[4 * va + i] += e[4 * i + j] * in[4 * vb + j];
                out[4 * vb + j] += e[4 * i + j] * in[4 * va + i];
            }
    }
}

/* x back to CGAL's positions and per-node radii (so the result depends
 * only on which nodes are kept), the vertices assigned, the unknowns
 * numbered (var; a kept copy shares its original's) and the segments listed
 * (segs; f->path holds per child end its index in segs). Returns the
 * number of unknown blocks; *nseg the segments. */
static uint32_t fit_setup(mesoi_fit_state* f, uint32_t* nseg)
{
    for (uint32_t i = 0; i < f->n; ++i) {
        memcpy(f->x + 4 * (size_t)i, f->w->pos + 3 * (size_t)alias(f, i), sizeof(double) * 3);
        f->x[4 * (size_t)i + 3] = f->w->rad[alias(f, i)];
    }
    mesoi_skel_assign_vertices(f);
    uint32_t nvar = 0, ns = 0;
    for (uint32_t i = 0; i < f->n; ++i)
        f->var[i] = f->keep[i] && i < f->w->ncgal ? nvar++ : UINT32_MAX;
    for (uint32_t i = f->w->ncgal; i < f->n; ++i) /* a kept copy's original is kept (pinned) */
        f->var[i] = f->var[alias(f, i)];
    for (uint32_t i = 0; i < f->n; ++i)
        if (f->keep[i] && f->sparent[i] >= 0)
            f->segs[ns++] = i;
    uint32_t* segidx = f->path; /* per child end: its index in segs */
    for (uint32_t s = 0; s < ns; ++s)
        segidx[f->segs[s]] = s;
    *nseg = ns;
    return nvar;
}

/* The Gauss–Newton normal equations of the data term at f->x, each row
 * scaled by the square root of its Huber (IRLS) weight: H's diagonal
 * blocks, E's segment blocks and the gradient g. */
static void assemble(mesoi_fit_state* f, uint32_t nvar, uint32_t nseg)
{
    const uint32_t* segidx = f->path;
    memset(f->H, 0, sizeof(double) * 16 * nvar);
    memset(f->E, 0, sizeof(double) * 16 * (nseg ? nseg : 1));
    memset(f->g, 0, sizeof(double) * 4 * (size_t)nvar);
    for (uint32_t v = 0; v < f->c->nv; ++v) {
        double ga[4], gb[4];
        uint32_t na, nb;
        double res = residual(f, f->x, v, ga, gb, &na, &nb);
        const double wt = sqrt(huber_weight(res, f->tol)); /* IRLS: scale the row by sqrt(w) */
        res *= wt;
        for (int k = 0; k < 4; ++k) {
            ga[k] *= wt;
            gb[k] *= wt;
        }
        const uint32_t va = f->var[na];
        if (nb == UINT32_MAX) { /* a lone ball: t = 0 */
            add_outer(f->H + 16 * (size_t)va, ga, ga);
            for (int k = 0; k < 4; ++k)
                f->g[4 * va + k] += ga[k] * res;
            continue;
        }
        const uint32_t vb = f->var[nb];
        add_outer(f->H + 16 * (size_t)va, ga, ga);
        add_outer(f->H + 16 * (size_t)vb, gb, gb);
        add_outer(f->E + 16 * (size_t)segidx[nb], ga, gb);
        for (int k = 0; k < 4; ++k) {
            f->g[4 * va + k] += ga[k] * res;
            f->g[4 * vb + k] += gb[k] * res;
        }
    }
}

/* The prior's weights kappa, from the data at CGAL's positions (see
 * mesoi_skel_refit). */
static void prior_weights(mesoi_fit_state* f, uint32_t nvar)
{
    double mean_p = 0, mean_r = 0;
    for (uint32_t v = 0; v < nvar; ++v) {
        const double* h = f->H + 16 * (size_t)v;
        mean_p += (h[0] + h[5] + h[10]) / 3 / nvar;
        mean_r += h[15] / nvar;
    }
    for (uint32_t v = 0; v < nvar; ++v) {
        const double* h = f->H + 16 * (size_t)v;
        const double kp = (h[0] + h[5] + h[10]) / 3;
        for (int k = 0; k < 3; ++k)
            f->kappa[4 * (size_t)v + k] = MESO_SKELFIT_PRIOR * (kp > mean_p ? kp : mean_p);
        f->kappa[4 * (size_t)v + 3] = MESO_SKELFIT_PRIOR * (h[15] > mean_r ? h[15] : mean_r);
    }
}

/* The prior's gradient and curvature, added to g and H. */
static void add_prior(mesoi_fit_state* f)
{
    for (uint32_t i = 0; i < f->w->ncgal; ++i)
        if (f->var[i] != UINT32_MAX) {
            const uint32_t v = f->var[i];
            for (int k = 0; k < 4; ++k) {
                const double x0 = k < 3 ? f->w->pos[3 * (size_t)i + k] : f->w->rad[i];
                f->g[4 * v + k] += f->kappa[4 * (size_t)v + k] * (f->x[4 * (size_t)i + k] - x0);
                f->H[16 * (size_t)v + 5 * k] += f->kappa[4 * (size_t)v + k];
            }
        }
}

/* Solve (H + mu diag H + eps) dx = -g by conjugate gradients,
 * preconditioned by the damped 4x4 diagonal blocks (Cholesky). */
static void solve_step(mesoi_fit_state* f, uint32_t nvar, uint32_t nseg, double mu, double eps)
{
    const size_t nu = 4 * (size_t)nvar;
    for (uint32_t v = 0; v < nvar; ++v)
        block_cholesky(f->H + 16 * (size_t)v, mu, eps, f->L + 16 * (size_t)v);
    double rz = 0, g2 = 0;
    for (size_t i = 0; i < nu; ++i) {
        f->dx[i] = 0;
        f->r[i] = -f->g[i];
        g2 += f->g[i] * f->g[i];
    }
    for (uint32_t v = 0; v < nvar; ++v)
        block_solve(f->L + 16 * (size_t)v, f->r + 4 * (size_t)v, f->z + 4 * (size_t)v);
    for (size_t i = 0; i < nu; ++i) {
        f->d[i] = f->z[i];
        rz += f->r[i] * f->z[i];
    }
    for (int cg = 0; cg < MESO_SKELFIT_CG_ITERATIONS; ++cg) {
        double r2 = 0;
        for (size_t i = 0; i < nu; ++i)
            r2 += f->r[i] * f->r[i];
        if (r2 <= 1e-20 * g2)
            break;
        lm_matvec(f, nvar, nseg, mu, eps, f->d, f->q);
        double dq = 0;
        for (size_t i = 0; i < nu; ++i)
            dq += f->d[i] * f->q[i];
        if (!(dq > 0))
            break;
        const double alpha = rz / dq;
        for (size_t i = 0; i < nu; ++i) {
            f->dx[i] += alpha * f->d[i];
            f->r[i] -= alpha * f->q[i];
        }
        double rz1 = 0;
        for (uint32_t v = 0; v < nvar; ++v)
            block_solve(f->L + 16 * (size_t)v, f->r + 4 * (size_t)v, f->z + 4 * (size_t)v);
        for (size_t i = 0; i < nu; ++i)
            rz1 += f->r[i] * f->z[i];
        for (size_t i = 0; i < nu; ++i)
            f->d[i] = f->z[i] + (rz1 / rz) * f->d[i];
        rz = rz1;
    }
}

/* The trial point xt = x + dx, radii clamped at 0 (a kept copy moves with
 * its original: they share unknowns). */
static void trial_point(mesoi_fit_state* f)
{
    memcpy(f->xt, f->x, sizeof(double) * 4 * f->n);
    for (uint32_t i = 0; i < f->n; ++i)
        if (f->var[i] != UINT32_MAX) {
            for (int k = 0; k < 4; ++k)
                f->xt[4 * (size_t)i + k] += f->dx[4 * (size_t)f->var[i] + k];
            if (f->xt[4 * (size_t)i + 3] < 0)
                f->xt[4 * (size_t)i + 3] = 0;
        }
}

/* Levenberg–Marquardt on all kept nodes' positions and radii, from CGAL's
 * positions and the per-node radii (so the result depends only on which
 * nodes are kept): minimise the Huber cost of the residuals plus a prior
 * sum_i kappa_i . (x_i - x_i(CGAL))^2 on positions and radii. Some
 * directions cost the data (almost) nothing — a node sliding along a
 * straight axis, the radius at the end of a segment whose vertices all lie
 * near its other end — and would wander (a radius grew to 2.6 on the
 * armadillo without the radius prior); the prior pins them. kappa is
 * MESO_SKELFIT_PRIOR x the larger of the node's own data curvature (per
 * position axis: trace / 3; radius: its diagonal entry) and the mean over
 * the nodes, so it biases well-determined moves by about that fraction and
 * holds data-poor nodes near CGAL. The normal system is solved by
 * conjugate gradients preconditioned with the 4x4 diagonal blocks. */
void mesoi_skel_refit(mesoi_fit_state* f, int iterations)
{
    if (!f->refit)
        return;
    uint32_t nseg = 0;
    const uint32_t nvar = fit_setup(f, &nseg);
    memset(f->kappa, 0, sizeof(double) * 4 * (nvar ? nvar : 1));
    double mu = 1e-3, cost = 0;
    for (int it = 0; it < iterations; ++it) {
        assemble(f, nvar, nseg);
        if (it == 0) {
            prior_weights(f, nvar);
            cost = fit_cost(f, f->x);
        }
        add_prior(f);
        double hmax = 0;
        for (uint32_t v = 0; v < nvar; ++v)
            for (int i = 0; i < 4; ++i)
                hmax = f->H[16 * (size_t)v + 5 * i] > hmax ? f->H[16 * (size_t)v + 5 * i] : hmax;
        const double eps = 1e-9 * hmax + 1e-300;
        int accepted = 0;
        for (int tries = 0; tries < 8 && !accepted; ++tries) {
            solve_step(f, nvar, nseg, mu, eps);
            trial_point(f);
            const double trial = fit_cost(f, f->xt);
            if (trial < cost) {
                accepted = 1;
                const double gain = (cost - trial) / (cost > 0 ? cost : 1);
                memcpy(f->x, f->xt, sizeof(double) * 4 * f->n);
                cost = trial;
                mu = mu / 3 > 1e-9 ? mu / 3 : 1e-9;
                if (gain < 1e-6)
                    it = iterations; /* converged */
            } else
                mu *= 4;
        }
        if (!accepted)
            break;
    }
}
