/*
 * shell_directors.c — directors by integrating the Lp-averaged distance
 * gradient (volume-textures-lp-averaged-shells.md §4.1, Eq. 1 with d_p of
 * Eq. 3, and the adaptive explicit Euler loop of §4.2).
 *
 * The ODE ∂F/∂t = h g(F), t in [0, 1], g = ∇d_p, is integrated in the
 * paper's form with s = h t (so x moves by Δ g for a parameter step Δ):
 *
 *     x = x0; g = n; s = 0
 *     while s < h:
 *         Δ = 2 Δ0
 *         do  Δ = Δ / 2; x' = x + Δ g; g' = g(x')   while angle(g, g') > ε
 *         x = x'; s += Δ; g = g'
 *
 * Where the paper is silent we decided:
 *  - Start: g(x0) is singular on the surface; its direction there is the
 *    surface normal (§4.1), so the first direction is the vertex normal n
 *    (angle-weighted, sign by shell kind) and the first evaluation is at
 *    x0 + Δ n.
 *  - Δ0 = h / 8 and ε = 5° by default (--angle-tol); the last step is cut
 *    so s ends exactly at h; a step shorter than h / 1024 is accepted even if
 *    the field turns more (the medial axis region, where |g| -> 0, would
 *    otherwise halve forever). Δ doubles back after an accepted step.
 *  - |g| < 1 near the (fuzzy) medial axis shortens the step: that is the
 *    paper's compression, and why a director may be shorter than h. The
 *    paper says |g| stays close to 1 near the surface; it does not for
 *    p = 3: over a plane I(x) = 2π/dist, so d_p ∝ dist^(1/3) and |g| grows
 *    without bound towards the surface (we measured directors 1.4 h long on
 *    average on the bunny). We therefore move by Δ g / max(|g|, 1): unit
 *    speed where the field is strong, the paper's compression where it is
 *    weak, and never a director longer than h. Every point evaluated,
 *    trial steps included, is so within h of x0 (a trial step is at most
 *    h − s, at speed at most 1): an update's field is built for that box
 *    only (bake_shell.c field_for, lp_distance.h >>regions).
 *  - An evaluation that lands on the surface (possible only if a step
 *    crosses it) is treated like a large turn: the step is halved.
 *  - Localisation (§4.2): with opt->cutoff = 2h only the surface within
 *    2h of x counts (meso_lp_eval_local), by Barnes-Hut;
 *    tests/integration/test_shell_directors.c bounds the change of the
 *    directors against the whole-surface field (max 0.04 h on spot at
 *    10 %). Bakes use it (bake_shell.c directors): at 106k triangles
 *    (spot subdivided, 5 %, all-Lp) an evaluation visits 148 instead of
 *    160 nodes and 57 instead of 79 multipoles, and the hybrid bake's
 *    directors took 0.97 s instead of 1.05 (issue 15). It was left out
 *    before because spot_uv's 2 % envelope kept 2 inverted prisms (its
 *    two layers were repaired against the base only); the envelope stage
 *    (shell_envelope.h) now rights them.
 *    Exact summation within 2h (opt->near_radius = 2h) made tracing ~47x
 *    slower at 26k triangles.
 */
#include "shell_directors.h"
#include "vec3d.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#ifdef _OPENMP
#include <omp.h>
#endif

/* cos of the angle between a and b, 1 for a zero vector (no turn known). */
static double cos_angle(const double a[3], const double b[3])
{
    const double la = len3(a), lb = len3(b);
    if (la == 0.0 || lb == 0.0)
        return 1.0;
    return dot3(a, b) / (la * lb);
}

meso_result meso_shell_trace(const meso_lp_field* field, const double x0[3], const double n[3],
                             const meso_trace_options* opt, double d[3], meso_trace_stats* stats)
{
    const double h = opt->thickness;
    const double tol = opt->angle_tol > 0 ? opt->angle_tol : 5.0 * M_PI / 180.0;
    const double cos_tol = cos(tol);
    const double d0 = h * (opt->first_step > 0 ? opt->first_step : 1.0 / 8.0);
    const double dmin = h * (opt->min_step > 0 ? opt->min_step : 1.0 / 1024.0);
    const double near = opt->near_radius;
    double x[3] = {x0[0], x0[1], x0[2]}, g[3] = {n[0], n[1], n[2]};
    double s = 0.0, step = d0;
    meso_trace_stats st = {0, 0, 0};
    while (s < h * (1.0 - 1e-12)) {
        /* First trial min(step, h - s): the last step goes to h at once
         * (halving "min(2 step, h - s)" split the remaining distance in
         * two forever, ~35 evaluations per vertex spent at s ~ h). */
        double delta = 2.0 * fmin(step, h - s), xn[3], gn[3], dist;
        for (;;) {
            delta *= 0.5;
            const double speed = fmax(len3(g), 1.0);
            for (int k = 0; k < 3; ++k)
                xn[k] = x[k] + delta * g[k] / speed;
            st.evaluations++;
            meso_result r = opt->cutoff > 0 ? meso_lp_eval_local(field, xn, opt->theta, opt->cutoff, &dist, gn, NULL)
                                            : meso_lp_eval_ex(field, xn, opt->theta, near, &dist, gn, NULL);
            const int ok = r == MESO_OK && cos_angle(g, gn) >= cos_tol;
            if (ok || delta <= dmin) {
                if (r != MESO_OK) /* on the surface even at the smallest step: stop here */
                    goto done;
                break;
            }
            st.halvings++;
        }
        memcpy(x, xn, sizeof(x));
        memcpy(g, gn, sizeof(g));
        s += delta;
        step = delta * 2.0 > d0 ? d0 : delta * 2.0; /* grow back towards Δ0 */
        st.steps++;
    }
done:
    for (int k = 0; k < 3; ++k)
        d[k] = x[k] - x0[k];
    if (stats) {
        stats->evaluations += st.evaluations;
        stats->steps += st.steps;
        stats->halvings += st.halvings;
    }
    return MESO_OK;
}

meso_result meso_vertex_faces(const meso_mesh* m, uint32_t** first, uint32_t** faces, const char* what,
                              meso_error* err)
{
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    uint32_t* fi = calloc((size_t)nv + 1, sizeof(uint32_t));
    uint32_t* fa = malloc(sizeof(uint32_t) * (3 * (size_t)nt + 1));
    uint32_t* fill = malloc(sizeof(uint32_t) * ((size_t)nv + 1));
    *first = *faces = NULL;
    if (!fi || !fa || !fill) {
        free(fi), free(fa), free(fill);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "%s: out of memory", what);
    }
    for (size_t i = 0; i < 3 * (size_t)nt; ++i)
        ++fi[m->indices[i] + 1];
    for (uint32_t v = 0; v < nv; ++v)
        fi[v + 1] += fi[v];
    memcpy(fill, fi, sizeof(uint32_t) * nv);
    for (size_t i = 0; i < 3 * (size_t)nt; ++i)
        fa[fill[m->indices[i]]++] = (uint32_t)(i / 3);
    free(fill);
    *first = fi;
    *faces = fa;
    return MESO_OK;
}

meso_result meso_vertex_normals(const meso_mesh* m, float* normals, meso_error* err)
{
    double* acc = calloc((size_t)m->vertex_count * 3 + 1, sizeof(double));
    if (!acc)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "normals: out of memory");
    for (uint32_t f = 0; f < m->triangle_count; ++f) {
        const uint32_t* ix = m->indices + 3 * (size_t)f;
        double p[3][3];
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k)
                p[c][k] = m->positions[3 * (size_t)ix[c] + k];
        double fn[3];
        if (meso_mesh_face_normal(m, f, fn) == 0.0)
            continue;
        for (int c = 0; c < 3; ++c) {
            double a[3], b[3];
            for (int k = 0; k < 3; ++k) {
                a[k] = p[(c + 1) % 3][k] - p[c][k];
                b[k] = p[(c + 2) % 3][k] - p[c][k];
            }
            const double la = len3(a), lb = len3(b);
            if (la == 0.0 || lb == 0.0)
                continue;
            const double angle = acos(fmax(-1.0, fmin(1.0, dot3(a, b) / (la * lb))));
            for (int k = 0; k < 3; ++k)
                acc[3 * (size_t)ix[c] + k] += angle * fn[k];
        }
    }
    for (uint32_t v = 0; v < m->vertex_count; ++v) {
        double* a = acc + 3 * (size_t)v;
        const double len = len3(a);
        for (int k = 0; k < 3; ++k)
            normals[3 * (size_t)v + k] = len > 0 ? (float)(a[k] / len) : (k == 2 ? 1.0f : 0.0f);
    }
    free(acc);
    return MESO_OK;
}

meso_result meso_field_surface_build(const meso_mesh* m, const float* normals, const uint32_t* boundary,
                                     uint32_t boundary_edges, double h, meso_field_surface* out, meso_error* err)
{
    memset(out, 0, sizeof(*out));
    const uint32_t nv = m->vertex_count, nb = boundary_edges;
    /* new_index[v]: index of v's artificial copy, or UINT32_MAX. */
    uint32_t* copy = malloc(sizeof(uint32_t) * (nv ? nv : 1));
    double* tangent = calloc((size_t)nv * 3 + 1, sizeof(double));
    if (!copy || !tangent) {
        free(copy);
        free(tangent);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "boundary faces: out of memory");
    }
    for (uint32_t v = 0; v < nv; ++v)
        copy[v] = UINT32_MAX;
    uint32_t extra = 0;
    for (uint32_t e = 0; e < nb; ++e) {
        const uint32_t a = boundary[2 * e], b = boundary[2 * e + 1];
        /* The face lies left of a->b seen from the normal side: e x n points away from it. */
        for (int end = 0; end < 2; ++end) {
            const uint32_t v = end ? b : a;
            const float* nv3 = normals + 3 * (size_t)v;
            double ed[3], out_dir[3];
            for (int k = 0; k < 3; ++k)
                ed[k] = (double)m->positions[3 * (size_t)b + k] - m->positions[3 * (size_t)a + k];
            out_dir[0] = ed[1] * nv3[2] - ed[2] * nv3[1];
            out_dir[1] = ed[2] * nv3[0] - ed[0] * nv3[2];
            out_dir[2] = ed[0] * nv3[1] - ed[1] * nv3[0];
            const double l = len3(out_dir);
            if (l > 0)
                for (int k = 0; k < 3; ++k)
                    tangent[3 * (size_t)v + k] += out_dir[k] / l;
            if (copy[v] == UINT32_MAX)
                copy[v] = nv + extra++;
        }
    }
    out->vertex_count = nv + extra;
    out->triangle_count = m->triangle_count + 2 * nb;
    out->artificial_faces = 2 * nb;
    out->positions = malloc(sizeof(float) * 3 * (size_t)out->vertex_count);
    out->indices = malloc(sizeof(uint32_t) * 3 * (size_t)out->triangle_count);
    if (!out->positions || !out->indices) {
        free(copy);
        free(tangent);
        meso_field_surface_free(out);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "boundary faces: out of memory");
    }
    memcpy(out->positions, m->positions, sizeof(float) * 3 * (size_t)nv);
    memcpy(out->indices, m->indices, sizeof(uint32_t) * 3 * (size_t)m->triangle_count);
    for (uint32_t v = 0; v < nv; ++v) {
        if (copy[v] == UINT32_MAX)
            continue;
        /* Tangent across the boundary: project out the normal, normalise. */
        double* t = tangent + 3 * (size_t)v;
        const float* n = normals + 3 * (size_t)v;
        const double tn = t[0] * n[0] + t[1] * n[1] + t[2] * n[2];
        for (int k = 0; k < 3; ++k)
            t[k] -= tn * n[k];
        const double l = len3(t);
        for (int k = 0; k < 3; ++k)
            out->positions[3 * (size_t)copy[v] + k] =
                (float)(m->positions[3 * (size_t)v + k] + (l > 0 ? h * t[k] / l : 0.0));
    }
    uint32_t* f = out->indices + 3 * (size_t)m->triangle_count;
    for (uint32_t e = 0; e < nb; ++e) {
        const uint32_t a = boundary[2 * e], b = boundary[2 * e + 1], a2 = copy[a], b2 = copy[b];
        /* The quad b, a, a', b' continues the surface across a->b, oriented alike. */
        f[0] = b, f[1] = a, f[2] = a2;
        f[3] = b, f[4] = a2, f[5] = b2;
        f += 6;
    }
    free(copy);
    free(tangent);
    return MESO_OK;
}

void meso_field_surface_free(meso_field_surface* s)
{
    if (!s)
        return;
    free(s->positions);
    free(s->indices);
    memset(s, 0, sizeof(*s));
}

meso_result meso_shell_trace_all(const meso_lp_field* field, const meso_mesh* m, const float* normals, double sign,
                                 const meso_trace_options* opt, const uint8_t* mask, int threads, float* d,
                                 meso_trace_stats* stats, meso_error* err)
{
    (void)err;
    const long nv = (long)m->vertex_count;
    uint64_t evals = 0, steps = 0, halvings = 0;
    long todo = 0;
    for (long v = 0; v < nv; ++v)
        todo += !mask || mask[v];
    atomic_long done = 0;
    const long every = todo / 100 > 0 ? todo / 100 : 1;
#ifdef _OPENMP
    const int nt = threads > 0 ? threads : omp_get_max_threads();
#pragma omp parallel for schedule(dynamic, 32) num_threads(nt) reduction(+ : evals, steps, halvings)
#else
    (void)threads;
#endif
    for (long v = 0; v < nv; ++v) {
        if (mask && !mask[v])
            continue;
        double x0[3], n[3], dv[3];
        for (int k = 0; k < 3; ++k) {
            x0[k] = m->positions[3 * v + k];
            n[k] = sign * normals[3 * v + k];
        }
        meso_trace_stats st = {0, 0, 0};
        meso_shell_trace(field, x0, n, opt, dv, &st);
        for (int k = 0; k < 3; ++k)
            d[3 * v + k] = (float)dv[k];
        evals += st.evaluations;
        steps += st.steps;
        halvings += st.halvings;
        const long k = atomic_fetch_add(&done, 1) + 1;
        if (opt->progress && k % every == 0) {
#ifdef _OPENMP
#pragma omp critical(meso_progress)
#endif
            opt->progress(opt->progress_user, (uint64_t)k, (uint64_t)todo);
        }
    }
    if (stats) {
        stats->evaluations += evals;
        stats->steps += steps;
        stats->halvings += halvings;
    }
    return MESO_OK;
}
