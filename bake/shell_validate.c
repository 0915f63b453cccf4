/* shell_validate.c — shell validation: conservative prism inversion test,
 * thickness ratios, and the exact intersection counts through the CGAL
 * adapter. The derivation of the Bernstein form is in shell_validate.h. */
#include "shell_validate.h"

#include "adapters.h"
#include "vec3d.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifndef MESO_HAVE_CGAL
#define MESO_HAVE_CGAL 0
#endif

/* Relative size of ε against L²·max|d| (header). The coefficients are a few
 * double roundings away from exact (~1e-15 relative), so 1e-12 is a wide
 * margin that still only rejects prisms with det J ~ 1e-12 of its scale,
 * i.e. degenerate ones. */
#define EPS_REL 1e-12

void meso_shell_jacobian_bernstein(const double b[9], const double d[9], double c[9])
{
    double e1[3], e2[3], f1[3], f2[3], t1[3], t2[3], n[3][3], x[3], y[3];
    sub3(b + 3, b, e1);
    sub3(b + 6, b, e2);
    sub3(d + 3, d, f1);
    sub3(d + 6, d, f2);
    for (int k = 0; k < 3; ++k) {
        t1[k] = e1[k] + f1[k];
        t2[k] = e2[k] + f2[k];
    }
    cross3(e1, e2, n[0]);
    cross3(t1, t2, n[2]);
    /* N1 = ½ [e1 × (e2+f2) + (e1+f1) × e2] */
    cross3(e1, t2, x);
    cross3(t1, e2, y);
    for (int k = 0; k < 3; ++k)
        n[1][k] = 0.5 * (x[k] + y[k]);
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k)
            c[3 * i + k] = dot3(d + 3 * i, n[k]);
}

double meso_shell_jacobian_eval(const double c[9], double u, double v, double w)
{
    const double lam[3] = {1.0 - u - v, u, v};
    const double bw[3] = {(1.0 - w) * (1.0 - w), 2.0 * w * (1.0 - w), w * w};
    double s = 0.0;
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k)
            s += lam[i] * bw[k] * c[3 * i + k];
    return s;
}

enum { EDGE_VALID = 0, EDGE_INVERTED = 1, EDGE_UNDECIDED = 2 };

/* Is q(w) = a(1−w)² + 2m w(1−w) + e w² > 0 on the current interval? a and e
 * are exact point values already known to be > eps. Halves by de Casteljau:
 * left (a, (a+m)/2, q(½)), right (q(½), (m+e)/2, e). */
static int edge_check(double a, double m, double e, double eps, int depth)
{
    if (m > eps)
        return EDGE_VALID;
    if (depth >= MESO_SHELL_MAX_DEPTH)
        return EDGE_UNDECIDED;
    const double ml = 0.5 * (a + m), mr = 0.5 * (m + e);
    const double mid = 0.5 * (ml + mr);
    if (mid <= 0.0)
        return EDGE_INVERTED;
    if (mid <= eps)
        return EDGE_UNDECIDED;
    int l = edge_check(a, ml, mid, eps, depth + 1);
    if (l == EDGE_INVERTED)
        return l;
    int r = edge_check(mid, mr, e, eps, depth + 1);
    if (r == EDGE_INVERTED)
        return r;
    return l > r ? l : r;
}

uint8_t meso_shell_prism_check(const double b[9], const double d[9], int sign)
{
    double c[9];
    meso_shell_jacobian_bernstein(b, d, c);
    /* ε = EPS_REL · L² · max|d_i| (header). */
    double top[9], r[3], l2 = 0.0, dmax = 0.0;
    for (int k = 0; k < 9; ++k)
        top[k] = b[k] + d[k];
    for (int t = 0; t < 2; ++t) {
        const double* p = t ? top : b;
        for (int i = 0; i < 3; ++i) {
            sub3(p + 3 * ((i + 1) % 3), p + 3 * i, r);
            double s = dot3(r, r);
            l2 = s > l2 ? s : l2;
        }
    }
    for (int i = 0; i < 3; ++i) {
        double s = len3(d + 3 * i);
        dmax = s > dmax ? s : dmax;
    }
    const double eps = EPS_REL * l2 * dmax;
    const double sg = sign < 0 ? -1.0 : 1.0;

    uint8_t verdict = 0;
    int proven = 0;
    for (int i = 0; i < 3; ++i) {
        const double a = sg * c[3 * i], m = sg * c[3 * i + 1], e = sg * c[3 * i + 2];
        int s;
        if (a <= 0.0 || e <= 0.0 || !(a == a && m == m && e == e)) /* a corner, or NaN input */
            s = EDGE_INVERTED;
        else if (a <= eps || e <= eps)
            s = EDGE_UNDECIDED;
        else
            s = edge_check(a, m, e, eps, 0);
        if (s != EDGE_VALID)
            verdict |= (uint8_t)(1u << i);
        proven |= s == EDGE_INVERTED;
    }
    if (verdict && !proven)
        verdict |= MESO_PRISM_UNDECIDED;
    return verdict;
}

static meso_result check_mesh(const meso_mesh* base, const float* directors, meso_error* err)
{
    if (!base || !directors || (base->vertex_count && !base->positions) || (base->triangle_count && !base->indices))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "shell: NULL mesh or directors");
    for (uint64_t j = 0; j < 3 * (uint64_t)base->triangle_count; ++j)
        if (base->indices[j] >= base->vertex_count)
            return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "shell: triangle %u: index out of range",
                                  (unsigned)(j / 3));
    return MESO_OK;
}

meso_result meso_shell_count_inverted(const meso_mesh* base, const float* directors, int sign, uint8_t* per_prism,
                                      uint32_t* inverted, uint32_t* undecided, meso_error* err)
{
    if (sign != 1 && sign != -1)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "shell: sign must be +1 or -1, not %d", sign);
    meso_result r = check_mesh(base, directors, err);
    if (r != MESO_OK)
        return r;
    uint32_t n_inv = 0, n_und = 0;
    for (uint32_t t = 0; t < base->triangle_count; ++t) {
        double b[9], d[9];
        for (int i = 0; i < 3; ++i) {
            uint32_t v = base->indices[3 * t + i];
            for (int k = 0; k < 3; ++k) {
                b[3 * i + k] = base->positions[3 * v + k];
                d[3 * i + k] = directors[3 * v + k];
            }
        }
        uint8_t s = meso_shell_prism_check(b, d, sign);
        n_inv += s != 0;
        n_und += (s & MESO_PRISM_UNDECIDED) != 0;
        if (per_prism)
            per_prism[t] = s;
    }
    if (inverted)
        *inverted = n_inv;
    if (undecided)
        *undecided = n_und;
    return MESO_OK;
}

meso_result meso_shell_thickness_ratio(const meso_mesh* base, const float* directors, const float* requested,
                                       double thickness, double* min, double* mean, uint32_t* counted,
                                       meso_error* err)
{
    meso_result r = check_mesh(base, directors, err);
    if (r != MESO_OK)
        return r;
    if (!requested && !isfinite(thickness))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "shell: requested thickness is not finite");
    uint8_t* used = calloc(base->vertex_count ? base->vertex_count : 1, 1);
    if (!used)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "shell: out of memory");
    for (uint64_t j = 0; j < 3 * (uint64_t)base->triangle_count; ++j)
        used[base->indices[j]] = 1;
    double lo = INFINITY, sum = 0.0;
    uint32_t n = 0;
    for (uint32_t v = 0; v < base->vertex_count; ++v) {
        if (!used[v])
            continue;
        double h = requested ? (double)requested[v] : thickness;
        if (!isfinite(h)) {
            free(used);
            return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "shell: vertex %u: requested thickness is not finite",
                                  v);
        }
        if (h <= 0.0)
            continue;
        const float* dv = directors + 3 * (size_t)v;
        double q = sqrt((double)dv[0] * dv[0] + (double)dv[1] * dv[1] + (double)dv[2] * dv[2]) / h;
        lo = q < lo ? q : lo;
        sum += q;
        ++n;
    }
    free(used);
    *min = n ? lo : 0.0;
    *mean = n ? sum / n : 0.0;
    if (counted)
        *counted = n;
    return MESO_OK;
}

static meso_result validate(const meso_mesh* base, const float* directors, const float* requested_thickness,
                            double thickness, int sign, int base_checked, uint8_t* inverted_per_prism,
                            meso_shell_report* out, meso_error* err);

meso_result meso_shell_validate(const meso_mesh* base, const float* directors, const float* requested_thickness,
                                double thickness, int sign, uint8_t* inverted_per_prism, meso_shell_report* out,
                                meso_error* err)
{
    return validate(base, directors, requested_thickness, thickness, sign, 0, inverted_per_prism, out, err);
}

meso_result mesoi_shell_validate_checked_base(const meso_mesh* base, const float* directors, double thickness,
                                              int sign, meso_shell_report* out, meso_error* err)
{
    return validate(base, directors, NULL, thickness, sign, 1, NULL, out, err);
}

static meso_result validate(const meso_mesh* base, const float* directors, const float* requested_thickness,
                            double thickness, int sign, int base_checked, uint8_t* inverted_per_prism,
                            meso_shell_report* out, meso_error* err)
{
    if (!out)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "shell: NULL report");
    memset(out, 0, sizeof(*out));
    out->offset_self_intersections = UINT64_MAX;
    out->offset_base_intersections = UINT64_MAX;
    out->base_self_intersections = UINT64_MAX;
    meso_result r = meso_shell_count_inverted(base, directors, sign, inverted_per_prism, &out->inverted_prisms,
                                              &out->undecided_prisms, err);
    if (r != MESO_OK)
        return r;
    out->prisms = base->triangle_count;
    r = meso_shell_thickness_ratio(base, directors, requested_thickness, thickness, &out->thickness_ratio_min,
                                   &out->thickness_ratio_mean, NULL, err);
    if (r != MESO_OK)
        return r;
#if MESO_HAVE_CGAL
    const size_t n = 3 * (size_t)base->vertex_count;
    double* xyz = malloc((n ? n : 1) * 2 * sizeof(double));
    if (!xyz)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "shell: out of memory");
    double* off = xyz + n;
    for (size_t j = 0; j < n; ++j) {
        xyz[j] = base->positions[j];
        off[j] = (double)base->positions[j] + (double)directors[j];
    }
    /* The three counts are independent: one thread each (OpenMP sections,
     * all cores; each count is sequential and exact, so the result does not
     * depend on the thread count). The first failure in this order is
     * returned. base_checked: the caller has counted the base's own (the
     * shell bake refuses a base that intersects itself before any work):
     * two sections, which two cores run at once. */
    meso_cgal_intersection_count c[3];
    meso_result rs[3];
    meso_error es[3];
    memset(es, 0, sizeof(es));
    const uint32_t nv = base->vertex_count, nt = base->triangle_count;
#ifdef _OPENMP
#pragma omp parallel sections
#endif
    {
#ifdef _OPENMP
#pragma omp section
#endif
        rs[0] = base_checked ? MESO_OK : meso_cgal_self_intersections(xyz, nv, base->indices, nt, &c[0], &es[0]);
#ifdef _OPENMP
#pragma omp section
#endif
        rs[1] = meso_cgal_self_intersections(off, nv, base->indices, nt, &c[1], &es[1]);
#ifdef _OPENMP
#pragma omp section
#endif
        rs[2] = meso_cgal_cross_intersections(off, xyz, nv, base->indices, nt, &c[2], &es[2]);
    }
    for (int k = 0; k < 3 && r == MESO_OK; ++k)
        if ((r = rs[k]) != MESO_OK && err)
            *err = es[k];
    if (r == MESO_OK && !base_checked) {
        out->base_self_intersections = c[0].pairs;
        out->degenerate_base_triangles = c[0].degenerate_a;
    }
    if (r == MESO_OK) {
        out->offset_self_intersections = c[1].pairs;
        out->degenerate_offset_triangles = c[1].degenerate_a;
        out->offset_base_intersections = c[2].pairs;
    }
    free(xyz);
    return r;
#else
    (void)base_checked;
    return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0,
                          "shell: built without CGAL, the intersection counts are not available");
#endif
}
