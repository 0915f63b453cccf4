/* Shell validation on meshes (bake/shell_validate.c with the CGAL adapter's
 * exact intersection counts): the unit sphere, the open saddle, hand-made
 * cases with known answers (zero directors, degenerate and non-manifold
 * triangles), and the issue #4 baseline (offsets along four normal
 * weightings) on the bundled spot and wingnut, every count checked against
 * a brute force over all triangle pairs (see issue_baseline for why not the
 * bunny and armadillo any more). */
#include "meso_clock.h"
#include "test_util.h"

#include <string.h>
#include <time.h>

#include "adapters.h"
#include "shell_validate.h"

#if MESO_HAVE_CGAL


static void load(const char* path, meso_mesh* m)
{
    meso_error err = {0};
    meso_result r = meso_openmesh_read(path, m, NULL, &err);
    if (r != MESO_OK)
        fprintf(stderr, "%s: %s\n", path, err.message);
    assert(r == MESO_OK && m->normals);
}

/* directors = t · normals (unit vectors). */
static float* scaled(const float* normals, uint32_t nv, double t)
{
    float* d = malloc(3 * (size_t)nv * sizeof(float));
    assert(d);
    for (size_t j = 0; j < 3 * (size_t)nv; ++j)
        d[j] = (float)(t * normals[j]);
    return d;
}

/* Vertex normals by weighting: 0 angle-weighted (Thürmer–Wüthrich), 1 the
 * plain mean of the unit face normals (what OpenMesh's update_normals()
 * gives: the counts below are identical), 2 area-weighted. */
static float* weighted_normals(const meso_mesh* m, int weighting)
{
    double* acc = calloc(3 * (size_t)m->vertex_count, sizeof(double));
    float* n = malloc(3 * (size_t)m->vertex_count * sizeof(float));
    assert(acc && n);
    for (uint32_t t = 0; t < m->triangle_count; ++t) {
        const uint32_t* ix = m->indices + 3 * t;
        double p[3][3], fn[3];
        for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k)
                p[i][k] = m->positions[3 * ix[i] + k];
        double e1[3], e2[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = p[1][k] - p[0][k];
            e2[k] = p[2][k] - p[0][k];
        }
        fn[0] = e1[1] * e2[2] - e1[2] * e2[1];
        fn[1] = e1[2] * e2[0] - e1[0] * e2[2];
        fn[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double ln = sqrt(fn[0] * fn[0] + fn[1] * fn[1] + fn[2] * fn[2]);
        if (ln == 0.0)
            continue;
        for (int i = 0; i < 3; ++i) {
            double a[3], b[3], la = 0, lb = 0, dot = 0;
            for (int k = 0; k < 3; ++k) {
                a[k] = p[(i + 1) % 3][k] - p[i][k];
                b[k] = p[(i + 2) % 3][k] - p[i][k];
                la += a[k] * a[k];
                lb += b[k] * b[k];
                dot += a[k] * b[k];
            }
            double c = dot / sqrt(la * lb);
            double ang = weighting == 1 ? 1.0 : weighting == 2 ? ln : acos(c < -1 ? -1 : c > 1 ? 1 : c);
            for (int k = 0; k < 3; ++k)
                acc[3 * ix[i] + k] += ang * fn[k] / ln;
        }
    }
    for (uint32_t v = 0; v < m->vertex_count; ++v) {
        double* a = acc + 3 * v;
        double ln = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        for (int k = 0; k < 3; ++k)
            n[3 * v + k] = ln > 0 ? (float)(a[k] / ln) : 0.0f;
    }
    free(acc);
    return n;
}

static meso_shell_report validate(const meso_mesh* m, const float* dir, double t, int sign, double* seconds)
{
    meso_shell_report rep;
    meso_error err = {0};
    double t0 = meso_seconds();
    meso_result r = meso_shell_validate(m, dir, NULL, t, sign, NULL, &rep, &err);
    if (seconds)
        *seconds = meso_seconds() - t0;
    if (r != MESO_OK)
        fprintf(stderr, "validate: %s\n", err.message);
    assert(r == MESO_OK);
    return rep;
}

static void sphere_offset_is_clean(void)
{
    meso_mesh m;
    load(test_data("sphere.obj"), &m);
    assert(m.vertex_count == 642 && m.triangle_count == 1280);
    for (int sign = 1; sign >= -1; sign -= 2) { /* exterior, then interior shell */
        float* d = scaled(m.normals, m.vertex_count, 0.1 * sign);
        meso_shell_report rep = validate(&m, d, 0.1, sign, NULL);
        assert(rep.prisms == 1280 && rep.inverted_prisms == 0);
        assert(rep.offset_self_intersections == 0 && rep.offset_base_intersections == 0);
        assert(rep.base_self_intersections == 0);
        assert(rep.degenerate_base_triangles == 0 && rep.degenerate_offset_triangles == 0);
        assert(fabs(rep.thickness_ratio_min - 1.0) < 1e-6 && fabs(rep.thickness_ratio_mean - 1.0) < 1e-6);
        /* The wrong sign inverts every prism. */
        uint8_t* per = malloc(m.triangle_count);
        meso_error err = {0};
        uint32_t inv = 0;
        assert(meso_shell_count_inverted(&m, d, -sign, per, &inv, NULL, &err) == MESO_OK);
        assert(inv == 1280);
        free(per);
        free(d);
    }
    meso_mesh_free(&m);
}

static void saddle_folds_when_thick(void)
{
    meso_mesh m;
    load(test_data("saddle.obj"), &m);
    double lo[3], hi[3];
    const double diag = meso_mesh_bounds(&m, lo, hi);
    fprintf(stderr, "    saddle: %u vertices, %u triangles, diagonal %.4f\n", m.vertex_count, m.triangle_count, diag);
    const double fr[] = {0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5};
    meso_shell_report reps[2][7];
    for (int sgn = 0; sgn < 2; ++sgn) {
        const int sign = sgn ? -1 : 1;
        for (int i = 0; i < 7; ++i) {
            float* d = scaled(m.normals, m.vertex_count, sign * fr[i] * diag);
            meso_shell_report rep = validate(&m, d, fr[i] * diag, sign, NULL);
            fprintf(stderr,
                    "    saddle %s %4.0f %%: inverted %u (undecided %u), offset self %llu, offset/base %llu, base self "
                    "%llu\n",
                    sign > 0 ? "+n" : "-n", 100 * fr[i], rep.inverted_prisms, rep.undecided_prisms,
                    (unsigned long long)rep.offset_self_intersections,
                    (unsigned long long)rep.offset_base_intersections,
                    (unsigned long long)rep.base_self_intersections);
            assert(rep.base_self_intersections == 0);
            reps[sgn][i] = rep;
            free(d);
        }
    }
    /* Thin: clean on both sides. */
    for (int sgn = 0; sgn < 2; ++sgn) {
        assert(reps[sgn][0].inverted_prisms == 0 && reps[sgn][0].offset_self_intersections == 0 &&
               reps[sgn][0].offset_base_intersections == 0);
    }
    /* Thick (50 % of the diagonal): past the smallest radius of curvature,
     * normal displacement folds on both sides of the saddle. */
    for (int sgn = 0; sgn < 2; ++sgn)
        assert(reps[sgn][6].inverted_prisms > 0 && reps[sgn][6].offset_self_intersections > 0);
    meso_mesh_free(&m);
}

/* One triangle in z = 0 (CCW from +z) as base, with given directors. */
static uint64_t one_triangle_cross(const float d[9], uint64_t* offset_self)
{
    static float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    static uint32_t idx[3] = {0, 1, 2};
    meso_mesh m = {3, 1, pos, NULL, NULL, idx, NULL};
    meso_shell_report rep;
    meso_error err = {0};
    assert(meso_shell_validate(&m, d, NULL, 0.3, 1, NULL, &rep, &err) == MESO_OK);
    if (offset_self)
        *offset_self = rep.offset_self_intersections;
    return rep.offset_base_intersections;
}

static void hand_made_cross_cases(void)
{
    /* Straight prism: no contact. */
    const float up[9] = {0, 0, 0.3f, 0, 0, 0.3f, 0, 0, 0.3f};
    assert(one_triangle_cross(up, NULL) == 0);
    /* Offset triangle tilted through the base triangle. */
    const float through[9] = {0, 0, 0.5f, 0, 0, -0.5f, 0, 0, 0.5f};
    assert(one_triangle_cross(through, NULL) == 1);
    /* d0 = 0: offset and base share corner 0 and touch only there. */
    const float pinch[9] = {0, 0, 0, 0, 0, 0.3f, 0, 0, 0.3f};
    assert(one_triangle_cross(pinch, NULL) == 0);
    /* d0 = 0 and the offset's opposite edge crosses the base at (0.55, 0.25, 0). */
    const float pinch_cross[9] = {0, 0, 0, 0, 0, 0.3f, 0.1f, -0.5f, -0.3f};
    assert(one_triangle_cross(pinch_cross, NULL) == 1);
    /* d0 = d1 = 0: a shared edge, not coplanar — no count. */
    const float hinge[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0.3f};
    assert(one_triangle_cross(hinge, NULL) == 0);
    /* d0 = d1 = 0, offset folded into the base plane on the same side: overlap. */
    const float folded[9] = {0, 0, 0, 0, 0, 0, 0.1f, -0.5f, 0};
    assert(one_triangle_cross(folded, NULL) == 1);
    /* ... and on the other side of the shared edge: touching along it only. */
    const float unfolded[9] = {0, 0, 0, 0, 0, 0, 0.1f, -1.5f, 0};
    assert(one_triangle_cross(unfolded, NULL) == 0);
    /* All zero: the prism collapsed onto its base, never counted here. */
    const float flat[9] = {0};
    assert(one_triangle_cross(flat, NULL) == 0);
}

static void degenerate_triangles(void)
{
    /* A unit square (2 triangles) + a collinear triangle + a repeated index. */
    float pos[18] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 0, 0, 3, 0, 0};
    uint32_t idx[12] = {0, 1, 2, 0, 2, 3, 1, 4, 5, 2, 2, 3};
    meso_mesh m = {6, 4, pos, NULL, NULL, idx, NULL};
    float d[18];
    for (int v = 0; v < 6; ++v) {
        d[3 * v] = d[3 * v + 1] = 0;
        d[3 * v + 2] = 0.1f;
    }
    meso_shell_report rep;
    meso_error err = {0};
    assert(meso_shell_validate(&m, d, NULL, 0.1, 1, NULL, &rep, &err) == MESO_OK);
    assert(rep.degenerate_base_triangles == 2 && rep.degenerate_offset_triangles == 2);
    assert(rep.base_self_intersections == 0 && rep.offset_self_intersections == 0);
    assert(rep.offset_base_intersections == 0);
    assert(rep.inverted_prisms == 2); /* zero-area prisms have det J = 0 */
    /* Directly, for the cross count's per-embedding degenerate counts. */
    double a[18], b[18];
    for (int j = 0; j < 18; ++j) {
        a[j] = pos[j];
        b[j] = (double)pos[j] + d[j];
    }
    meso_cgal_intersection_count c;
    assert(meso_cgal_cross_intersections(b, a, 6, idx, 4, &c, &err) == MESO_OK);
    assert(c.degenerate_a == 2 && c.degenerate_b == 2);
}

static void non_manifold_fin(void)
{
    /* Edge a–b used by three triangles: Surface_mesh refuses the third, the
     * soup fallback applies the same adjacency rules. */
    double xyz[15] = {0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, 0, 0.5, 0, 1};
    uint32_t idx[9] = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    meso_cgal_intersection_count c;
    meso_error err = {0};
    assert(meso_cgal_self_intersections(xyz, 5, idx, 3, &c, &err) == MESO_OK);
    assert(c.pairs == 0 && c.degenerate_a == 0);
    xyz[13] = 0.5; /* e = (0.5, 0.5, 0): coplanar with a b c, same side: overlaps it */
    xyz[14] = 0.0;
    assert(meso_cgal_self_intersections(xyz, 5, idx, 3, &c, &err) == MESO_OK);
    assert(c.pairs == 1);
    /* The unit square as two triangles is manifold (PMP path): its coplanar
     * neighbours do not overlap. A third triangle 0-1-4 on edge 0-1 makes it
     * non-manifold (soup path); it overlaps 0-1-2 (shared edge, same side)
     * and touches 0-2-3 along the diagonal beyond the shared vertex 0. */
    double sq[15] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 0.5, 0};
    uint32_t sqi[9] = {0, 1, 2, 0, 2, 3, 0, 1, 4};
    assert(meso_cgal_self_intersections(sq, 5, sqi, 2, &c, &err) == MESO_OK);
    assert(c.pairs == 0);
    assert(meso_cgal_self_intersections(sq, 5, sqi, 3, &c, &err) == MESO_OK);
    assert(c.pairs == 2);
    uint32_t bad[3] = {0, 1, 7};
    assert(meso_cgal_self_intersections(sq, 5, bad, 1, &c, &err) == MESO_ERR_INVALID_ARG);
}

/* The issue #4 baseline: offset along the vertex normals by f × bbox
 * diagonal. Returns the offset self-intersection count. */
static uint64_t baseline(const char* name, const meso_mesh* m, const float* normals, const char* weighting, double f)
{
    double lo[3], hi[3];
    const double diag = meso_mesh_bounds(m, lo, hi);
    float* d = scaled(normals, m->vertex_count, f * diag);
    double secs;
    meso_shell_report rep = validate(m, d, f * diag, 1, &secs);
    fprintf(stderr,
            "    %s (%u tris) %s normals %4.1f %%: offset self %llu, offset/base %llu, base self %llu, inverted %u "
            "(undecided %u), degenerate %u — validate %.3f s\n",
            name, m->triangle_count, weighting, 100 * f, (unsigned long long)rep.offset_self_intersections,
            (unsigned long long)rep.offset_base_intersections, (unsigned long long)rep.base_self_intersections,
            rep.inverted_prisms, rep.undecided_prisms, rep.degenerate_base_triangles, secs);
    free(d);
    return rep.offset_self_intersections;
}

/* The PMP path vs the soup fallback on one real offset: add a far-away
 * non-manifold fin (3 triangles on one edge, no contacts) to force the
 * fallback; the counts must agree. */
static void pmp_vs_soup(const meso_mesh* m, double f)
{
    double lo[3], hi[3];
    const double diag = meso_mesh_bounds(m, lo, hi);
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    double* xyz = malloc(3 * ((size_t)nv + 5) * sizeof(double));
    uint32_t* idx = malloc(3 * ((size_t)nt + 3) * sizeof(uint32_t));
    assert(xyz && idx);
    for (size_t j = 0; j < 3 * (size_t)nv; ++j)
        xyz[j] = (double)m->positions[j] + (double)(float)(f * diag * m->normals[j]);
    const double fin[15] = {0, 0, 0, 1, 0, 0, 0.5, 1, 0, 0.5, -1, 0, 0.5, 0, 1};
    for (int j = 0; j < 15; ++j)
        xyz[3 * nv + j] = fin[j] + hi[j % 3] + 10 * diag;
    memcpy(idx, m->indices, 3 * (size_t)nt * sizeof(uint32_t));
    const uint32_t fi[9] = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    for (int j = 0; j < 9; ++j)
        idx[3 * nt + j] = nv + fi[j];
    meso_cgal_intersection_count pmp, soup;
    meso_error err = {0};
    double t0 = meso_seconds();
    assert(meso_cgal_self_intersections(xyz, nv + 5, idx, nt, &pmp, &err) == MESO_OK);
    double t1 = meso_seconds();
    assert(meso_cgal_self_intersections(xyz, nv + 5, idx, nt + 3, &soup, &err) == MESO_OK);
    double t2 = meso_seconds();
    fprintf(stderr, "    PMP %llu pairs (%.3f s), soup fallback %llu pairs (%.3f s)\n", (unsigned long long)pmp.pairs,
            t1 - t0, (unsigned long long)soup.pairs, t2 - t1);
    assert(pmp.pairs == soup.pairs && pmp.degenerate_a == soup.degenerate_a);
    free(xyz);
    free(idx);
}

/* >>brute force ---------------------------------------------------------- */

/* An independent count of self-intersecting triangle pairs: every pair
 * tested (no boxes, no CGAL), double-precision orientation predicates, and
 * the adjacency rules CGAL's PMP::self_intersections documents: no shared
 * corner — the triangles meet; one — an edge opposite it meets the other
 * triangle; two — coplanar with the third corners on the same side of the
 * shared edge; closed sets, coplanar cases included. Degenerate (zero-area)
 * triangles are left out, as CGAL does. Double predicates can only disagree
 * with exact ones on near-degenerate configurations, which the 0.5 % bound
 * below leaves room for. */
static double orient(const double* a, const double* b, const double* c, const double* d)
{
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]},
                 w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
}

static int sgn(double x)
{
    return (x > 0) - (x < 0);
}

static double orient2(const double* a, const double* b, const double* c)
{
    return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
}

/* Closed 2D segments ab and cd meet. */
static int segments_meet2(const double* a, const double* b, const double* c, const double* d)
{
    const int s1 = sgn(orient2(a, b, c)), s2 = sgn(orient2(a, b, d)), s3 = sgn(orient2(c, d, a)),
              s4 = sgn(orient2(c, d, b));
    if (s1 == 0 && s2 == 0) /* collinear: overlapping extents */
        for (int k = 0; k < 2; ++k)
            if (fmax(a[k], b[k]) < fmin(c[k], d[k]) || fmax(c[k], d[k]) < fmin(a[k], b[k]))
                return 0;
    return s1 * s2 <= 0 && s3 * s4 <= 0;
}

/* p in the closed 2D triangle abc. */
static int inside2(const double* p, const double* a, const double* b, const double* c)
{
    const int s1 = sgn(orient2(a, b, p)), s2 = sgn(orient2(b, c, p)), s3 = sgn(orient2(c, a, p));
    return (s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0);
}

/* Segment pq in the plane of triangle abc meets it: in 2D, dropping the
 * normal's largest coordinate. */
static int coplanar_segment_meets_triangle(const double* p, const double* q, const double* a, const double* b,
                                           const double* c)
{
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double n[3] = {fabs(u[1] * v[2] - u[2] * v[1]), fabs(u[2] * v[0] - u[0] * v[2]), fabs(u[0] * v[1] - u[1] * v[0])};
    const int drop = n[0] >= n[1] && n[0] >= n[2] ? 0 : n[1] >= n[2] ? 1 : 2;
    const int i0 = drop == 0 ? 1 : 0, i1 = drop == 2 ? 1 : 2;
    const double P[2] = {p[i0], p[i1]}, Q[2] = {q[i0], q[i1]}, A[2] = {a[i0], a[i1]}, B[2] = {b[i0], b[i1]},
                 C[2] = {c[i0], c[i1]};
    return inside2(P, A, B, C) || inside2(Q, A, B, C) || segments_meet2(P, Q, A, B) || segments_meet2(P, Q, B, C) ||
           segments_meet2(P, Q, C, A);
}

/* Closed segment pq meets closed triangle abc. */
static int segment_meets_triangle(const double* p, const double* q, const double* a, const double* b, const double* c)
{
    const int sp = sgn(orient(a, b, c, p)), sq = sgn(orient(a, b, c, q));
    if (sp == 0 && sq == 0)
        return coplanar_segment_meets_triangle(p, q, a, b, c);
    if (sp == sq) /* both strictly on one side */
        return 0;
    const int s1 = sgn(orient(p, q, a, b)), s2 = sgn(orient(p, q, b, c)), s3 = sgn(orient(p, q, c, a));
    return (s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0);
}

static uint64_t brute_self_intersections(const double* xyz, const uint32_t* idx, uint32_t nt)
{
    double* box = malloc(6 * (size_t)nt * sizeof(double));
    uint8_t* ok = malloc(nt);
    assert(box && ok);
    for (uint32_t t = 0; t < nt; ++t) {
        const double *a = xyz + 3 * idx[3 * t], *b = xyz + 3 * idx[3 * t + 1], *c = xyz + 3 * idx[3 * t + 2];
        const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        ok[t] = n[0] != 0 || n[1] != 0 || n[2] != 0;
        for (int k = 0; k < 3; ++k) {
            box[6 * t + k] = fmin(a[k], fmin(b[k], c[k]));
            box[6 * t + 3 + k] = fmax(a[k], fmax(b[k], c[k]));
        }
    }
    uint64_t pairs = 0;
    for (uint32_t f = 0; f < nt; ++f) {
        if (!ok[f])
            continue;
        const uint32_t* fa = idx + 3 * f;
        const double* P[3] = {xyz + 3 * fa[0], xyz + 3 * fa[1], xyz + 3 * fa[2]};
        for (uint32_t g = f + 1; g < nt; ++g) {
            if (!ok[g])
                continue;
            const double *bf = box + 6 * f, *bg = box + 6 * g;
            if (bf[0] > bg[3] || bg[0] > bf[3] || bf[1] > bg[4] || bg[1] > bf[4] || bf[2] > bg[5] || bg[2] > bf[5])
                continue;
            const uint32_t* ga = idx + 3 * g;
            const double* Q[3] = {xyz + 3 * ga[0], xyz + 3 * ga[1], xyz + 3 * ga[2]};
            int shared = 0, si = -1, sj = -1;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j)
                    if (fa[i] == ga[j])
                        ++shared, si = i, sj = j;
            int hit = 0;
            if (shared == 0) {
                for (int e = 0; e < 3 && !hit; ++e)
                    hit = segment_meets_triangle(P[e], P[(e + 1) % 3], Q[0], Q[1], Q[2]) ||
                          segment_meets_triangle(Q[e], Q[(e + 1) % 3], P[0], P[1], P[2]);
            } else if (shared == 1) {
                hit = segment_meets_triangle(Q[(sj + 1) % 3], Q[(sj + 2) % 3], P[0], P[1], P[2]) ||
                      segment_meets_triangle(P[(si + 1) % 3], P[(si + 2) % 3], Q[0], Q[1], Q[2]);
            } else if (shared == 2) {
                /* the corners not shared */
                int pi = 0, qj = 0;
                for (int i = 0; i < 3; ++i)
                    if (fa[i] != ga[0] && fa[i] != ga[1] && fa[i] != ga[2])
                        pi = i;
                for (int j = 0; j < 3; ++j)
                    if (ga[j] != fa[0] && ga[j] != fa[1] && ga[j] != fa[2])
                        qj = j;
                if (orient(P[0], P[1], P[2], Q[qj]) == 0) {
                    /* same side of the shared edge (e0, e1) in their common plane */
                    const double *e0 = P[(pi + 1) % 3], *e1 = P[(pi + 2) % 3];
                    double nrm[3];
                    const double u[3] = {e1[0] - e0[0], e1[1] - e0[1], e1[2] - e0[2]};
                    const double v[3] = {P[pi][0] - e0[0], P[pi][1] - e0[1], P[pi][2] - e0[2]};
                    nrm[0] = u[1] * v[2] - u[2] * v[1], nrm[1] = u[2] * v[0] - u[0] * v[2], nrm[2] = u[0] * v[1] - u[1] * v[0];
                    const double top[3] = {e0[0] + nrm[0], e0[1] + nrm[1], e0[2] + nrm[2]};
                    hit = sgn(orient(e0, e1, top, P[pi])) == sgn(orient(e0, e1, top, Q[qj]));
                }
            } else {
                hit = 1; /* the same triangle twice */
            }
            pairs += (uint64_t)hit;
        }
    }
    free(box);
    free(ok);
    return pairs;
}

/* The brute force on the offset exactly as meso_shell_validate builds it. */
static uint64_t brute_offset(const meso_mesh* m, const float* normals, double f)
{
    double lo[3], hi[3];
    const double diag = meso_mesh_bounds(m, lo, hi);
    float* d = scaled(normals, m->vertex_count, f * diag);
    double* off = malloc(3 * (size_t)m->vertex_count * sizeof(double));
    assert(off);
    for (size_t j = 0; j < 3 * (size_t)m->vertex_count; ++j)
        off[j] = (double)m->positions[j] + (double)d[j];
    const uint64_t n = brute_self_intersections(off, m->indices, m->triangle_count);
    free(off);
    free(d);
    return n;
}

/* The brute force itself on cases with known answers. */
static void brute_force_known_answers(void)
{
    /* two triangles crossing like a plus sign; then moved apart */
    double x[18] = {0, 0, 0, 2, 0, 0, 1, 2, 0, 1, 1, -1, 1, 1, 1, 1, -1, 0};
    const uint32_t two[6] = {0, 1, 2, 3, 4, 5};
    assert(brute_self_intersections(x, two, 2) == 1);
    x[9] = x[12] = x[15] = 5;
    assert(brute_self_intersections(x, two, 2) == 0);
    /* a fan sharing corner 0: clean; one blade through another: 1 */
    double fan[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    const uint32_t tri3[6] = {0, 1, 2, 0, 3, 4};
    assert(brute_self_intersections(fan, tri3, 2) == 0);
    fan[9] = 0.2, fan[10] = 0.2, fan[11] = -1; /* blade 0-3-4 now pierces 0-1-2 along its opposite edge */
    fan[12] = 0.2, fan[13] = 0.2, fan[14] = 1;
    assert(brute_self_intersections(fan, tri3, 2) == 1);
    /* the unit square: manifold neighbours do not count; a third triangle on
     * edge 0-1, folded onto 0-1-2's side, does (as in non_manifold_fin) */
    const double sq[15] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 0.5, 0};
    const uint32_t sqi[9] = {0, 1, 2, 0, 2, 3, 0, 1, 4};
    assert(brute_self_intersections(sq, sqi, 2) == 0);
    assert(brute_self_intersections(sq, sqi, 3) == 2);
}

/* Was the issue #4 baseline on the Stanford bunny and armadillo of
 * the project's wider data set (outside the repository), against the
 * issue's published counts (OpenMesh normals
 * within 20 %, area-weighted within 0.5 %). Those models' terms forbid
 * commercial use, so they cannot be in this MIT repository, and the issue's
 * numbers exist only for them. Now the bundled, permissively licensed spot
 * (public domain, 1654 triangles) and wingnut (CC BY 4.0, 6090 triangles
 * with needles) are offset the same way (10 % and 2 % of the bounding-box
 * diagonal, four normal weightings), and every count is checked against an
 * independent brute force over all triangle pairs, within the 0.5 % the
 * area-weighted comparison allowed (tighter than the 20 % the OpenMesh one
 * did). The thin offsets are also asserted to have fewer pairs than the
 * thick ones, and the thick ones some pairs, so the comparison is never
 * between two zeros only. */
static void issue_baseline(void)
{
    const char* names[2] = {"spot_low_resolution", "wingnut"};
    for (int k = 0; k < 2; ++k) {
        char file[64];
        snprintf(file, sizeof(file), "%s.obj", names[k]);
        meso_mesh m;
        load(test_data(file), &m);
        float* aw = weighted_normals(&m, 0);
        float* uw = weighted_normals(&m, 1);
        float* arw = weighted_normals(&m, 2);
        const float* nrm[4] = {m.normals, aw, uw, arw};
        const char* wname[4] = {"OpenMesh", "angle   ", "uniform ", "area-w  "};
        uint64_t n[4][2], ref[4][2]; /* [OpenMesh, angle, uniform, area][fraction] */
        const double fr[2] = {0.10, 0.02};
        for (int i = 0; i < 2; ++i)
            for (int w = 0; w < 4; ++w) {
                n[w][i] = baseline(names[k], &m, nrm[w], wname[w], fr[i]);
                const double t0 = meso_seconds();
                ref[w][i] = brute_offset(&m, nrm[w], fr[i]);
                fprintf(stderr, "      brute force over all pairs: %llu (%.2f s)\n", (unsigned long long)ref[w][i],
                        meso_seconds() - t0);
                const double e = (double)ref[w][i];
                assert(fabs((double)n[w][i] - e) <= 0.005 * e);
            }
        for (int w = 0; w < 4; ++w)
            assert(ref[w][0] > 0 && ref[w][1] < ref[w][0]);
        /* The base itself (wingnut intersects itself: 3 pairs, per mesobake). */
        double* xyz = malloc(3 * (size_t)m.vertex_count * sizeof(double));
        assert(xyz);
        for (size_t j = 0; j < 3 * (size_t)m.vertex_count; ++j)
            xyz[j] = m.positions[j];
        meso_cgal_intersection_count base;
        meso_error err = {0};
        assert(meso_cgal_self_intersections(xyz, m.vertex_count, m.indices, m.triangle_count, &base, &err) == MESO_OK);
        const uint64_t base_ref = brute_self_intersections(xyz, m.indices, m.triangle_count);
        fprintf(stderr, "    %s base: CGAL %llu pairs, brute force %llu\n", names[k], (unsigned long long)base.pairs,
                (unsigned long long)base_ref);
        assert(base.pairs == base_ref);
        free(xyz);
        free(aw);
        free(uw);
        free(arw);
        if (k == 0)
            pmp_vs_soup(&m, 0.10);
        meso_mesh_free(&m);
    }
}

int main(void)
{
    TEST_RUN(sphere_offset_is_clean);
    TEST_RUN(saddle_folds_when_thick);
    TEST_RUN(hand_made_cross_cases);
    TEST_RUN(degenerate_triangles);
    TEST_RUN(non_manifold_fin);
    TEST_RUN(brute_force_known_answers);
    TEST_RUN(issue_baseline);
    return 0;
}

#else
int main(void)
{
    fprintf(stderr, "built without CGAL: skipped\n");
    return 77; /* meson: skipped */
}
#endif
