/*
 * test_mesh_levels.c — mesh levels of detail (bake/mesh_levels.c,
 * bake/surface_distance.c, bake/lod_table.c, meso_bake_mesh's levels):
 *
 * - the stated error of a level against brute force: random points on each
 *   surface (and every vertex), their distance to the other surface over
 *   every triangle, with a closest-point method of the test's own (plane
 *   projection + edge segments, not Ericson's Voronoi regions); the stated
 *   error is at least every brute distance and at most the brute maximum
 *   plus twice the sampling radius;
 * - a UV sphere split at every quad (each quad its own uv chart, vertices
 *   duplicated, as importers do at seams) gets >= 3 levels of decreasing
 *   triangle counts, while meshoptimizer 0.18 on the split mesh as given
 *   (split_seams) locks it: the welding makes the difference; level
 *   vertices keep their input attributes bit for bit; no level has two
 *   faces on the same three positions;
 * - errors non-decreasing; the baked file validates (full tier); its LODS
 *   levels match the report and the TOC (bytes, prefix recomputed here);
 *   two bakes with 1 and 2 threads are byte-identical; --levels 1 writes no
 *   LODS; levels N caps the chain.
 */
#include "test_util.h"

#include <string.h>

#include "mesh_levels.h"
#include "meso_bake.h"
#include "meso_layout.h"
#include "surface_distance.h"

/* ---- brute force -------------------------------------------------------- */

static double seg_dist(const double p[3], const double a[3], const double b[3])
{
    double ab[3], ap[3], l2 = 0, t = 0;
    for (int k = 0; k < 3; ++k) {
        ab[k] = b[k] - a[k];
        ap[k] = p[k] - a[k];
        l2 += ab[k] * ab[k];
        t += ab[k] * ap[k];
    }
    t = l2 > 0 ? t / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double d2 = 0;
    for (int k = 0; k < 3; ++k) {
        const double x = a[k] + t * ab[k] - p[k];
        d2 += x * x;
    }
    return sqrt(d2);
}

/* Projection onto the plane when it falls inside (same side of every edge
 * as the normal), else the nearest edge. */
static double tri_dist(const double p[3], const double* v[3])
{
    double e1[3], e2[3], n[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = v[1][k] - v[0][k];
        e2[k] = v[2][k] - v[0][k];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    const double nn = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (nn > 0) {
        double h = 0, q[3];
        for (int k = 0; k < 3; ++k)
            h += (p[k] - v[0][k]) * n[k] / nn;
        for (int k = 0; k < 3; ++k)
            q[k] = p[k] - h * n[k] / nn;
        int inside = 1;
        for (int e = 0; e < 3 && inside; ++e) {
            const double* a = v[e];
            const double* b = v[(e + 1) % 3];
            const double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
            const double aq[3] = {q[0] - a[0], q[1] - a[1], q[2] - a[2]};
            const double c[3] = {ab[1] * aq[2] - ab[2] * aq[1], ab[2] * aq[0] - ab[0] * aq[2],
                                 ab[0] * aq[1] - ab[1] * aq[0]};
            inside = c[0] * n[0] + c[1] * n[1] + c[2] * n[2] >= 0;
        }
        if (inside)
            return fabs(h);
    }
    double d = seg_dist(p, v[0], v[1]);
    const double d2 = seg_dist(p, v[1], v[2]), d3 = seg_dist(p, v[2], v[0]);
    return d2 < d ? (d3 < d2 ? d3 : d2) : (d3 < d ? d3 : d);
}

/* The distance from p to m, or some distance <= floor when it is <= floor:
 * the triangle *hint first (it gets the nearest), then every one. A point
 * no farther than the largest distance found so far cannot raise it, so
 * its search ends there: the largest stays exact. */
static double mesh_dist_above(const double p[3], const meso_mesh* m, double floor, uint32_t* hint)
{
    double best = INFINITY;
    for (uint32_t k = 0; k <= m->triangle_count; ++k) {
        const uint32_t f = k == 0 ? *hint : k - 1;
        if (f >= m->triangle_count || (k > 0 && f == *hint))
            continue;
        double c[3][3];
        const double* v[3] = {c[0], c[1], c[2]};
        for (int j = 0; j < 3; ++j)
            for (int q = 0; q < 3; ++q)
                c[j][q] = m->positions[3 * (size_t)m->indices[3 * (size_t)f + (size_t)j] + (size_t)q];
        const double d = tri_dist(p, v);
        if (d < best) {
            best = d;
            *hint = f;
            if (best <= floor)
                break;
        }
    }
    return best;
}

static double tri_area(const meso_mesh* m, uint32_t f)
{
    double n[3];
    return meso_mesh_face_normal(m, f, n);
}

/* Largest brute distance from a's vertices and `count` area-uniform random
 * points of a to b. */
static double brute_one_way(const meso_mesh* a, const meso_mesh* b, int count, uint64_t* rng)
{
    double worst = 0;
    uint32_t hint = 0;
    for (uint32_t v = 0; v < a->vertex_count; ++v) {
        const double p[3] = {a->positions[3 * (size_t)v], a->positions[3 * (size_t)v + 1],
                             a->positions[3 * (size_t)v + 2]};
        const double d = mesh_dist_above(p, b, worst, &hint);
        worst = d > worst ? d : worst;
    }
    double* cdf = malloc(sizeof(double) * a->triangle_count);
    assert(cdf);
    double total = 0;
    for (uint32_t f = 0; f < a->triangle_count; ++f)
        cdf[f] = total += tri_area(a, f);
    for (int i = 0; i < count; ++i) {
        const double x = test_rng_uniform(rng, 0, total);
        uint32_t lo = 0, hi = a->triangle_count - 1;
        while (lo < hi) {
            const uint32_t mid = (lo + hi) / 2;
            if (cdf[mid] < x)
                lo = mid + 1;
            else
                hi = mid;
        }
        double s = test_rng_uniform(rng, 0, 1), t = test_rng_uniform(rng, 0, 1);
        if (s + t > 1)
            s = 1 - s, t = 1 - t;
        double p[3];
        for (int k = 0; k < 3; ++k) {
            const double v0 = a->positions[3 * (size_t)a->indices[3 * (size_t)lo] + (size_t)k];
            const double v1 = a->positions[3 * (size_t)a->indices[3 * (size_t)lo + 1] + (size_t)k];
            const double v2 = a->positions[3 * (size_t)a->indices[3 * (size_t)lo + 2] + (size_t)k];
            p[k] = v0 + s * (v1 - v0) + t * (v2 - v0);
        }
        const double d = mesh_dist_above(p, b, worst, &hint);
        worst = d > worst ? d : worst;
    }
    free(cdf);
    return worst;
}

/* The stated error of a level against brute force. */
static void check_error_brute(const char* what, const meso_mesh* level0, const meso_mesh_level* L)
{
    uint64_t rng = 12345;
    const double ab = brute_one_way(&L->mesh, level0, 3000, &rng);
    const double ba = brute_one_way(level0, &L->mesh, 3000, &rng);
    const double brute = ab > ba ? ab : ba;
    printf("    %s, %u triangles: stated %.6g (own %.6g, radius %.3g), brute force %.6g\n", what,
           L->mesh.triangle_count, L->error, L->measured, L->sample_radius, brute);
    assert(L->measured >= brute * (1 - 1e-12));
    assert(L->error >= L->measured);
    assert(L->measured <= brute + 2 * L->sample_radius + 1e-12);
    assert(L->sample_radius > 0);
}

/* ---- meshes --------------------------------------------------------------- */

/* A unit UV sphere of nu x nv quads (triangles at the poles) whose every
 * K x K block of quads is its own uv chart: vertices on chart borders are
 * duplicated (same position, other uv), as an importer splits at seams.
 * Normals = positions. */
static meso_mesh split_sphere(int nu, int nv, int K)
{
    meso_mesh m = {0};
    m.positions = malloc(sizeof(float) * 3 * 4 * (size_t)nu * nv);
    m.normals = malloc(sizeof(float) * 3 * 4 * (size_t)nu * nv);
    m.uvs = malloc(sizeof(float) * 2 * 4 * (size_t)nu * nv);
    m.indices = malloc(sizeof(uint32_t) * 6 * (size_t)nu * nv);
    int* map = malloc(sizeof(int) * (size_t)(nu + 1) * (nv + 1));
    assert(m.positions && m.normals && m.uvs && m.indices && map);
    for (int cj = 0; cj < nv; cj += K)
        for (int ci = 0; ci < nu; ci += K) {
            for (int q = 0; q < (nu + 1) * (nv + 1); ++q)
                map[q] = -1;
            for (int j = cj; j < cj + K && j < nv; ++j)
                for (int i = ci; i < ci + K && i < nu; ++i) {
                    const int c[4][2] = {{i, j}, {i + 1, j}, {i + 1, j + 1}, {i, j + 1}};
                    uint32_t id[4] = {0, 0, 0, 0};
                    for (int k = 0; k < 4; ++k) {
                        if ((j == 0 && k == 1) || (j == nv - 1 && k == 2))
                            continue; /* the cap triangles' unused corner */
                        const int ii = c[k][0], jj = c[k][1], q = jj * (nu + 1) + ii;
                        if (map[q] < 0) {
                            const double th = M_PI * jj / nv, ph = 2 * M_PI * (ii % nu) / nu;
                            const int pole = jj == 0 || jj == nv;
                            float* p = m.positions + 3 * (size_t)m.vertex_count;
                            p[0] = pole ? 0.0f : (float)(sin(th) * cos(ph));
                            p[1] = pole ? 0.0f : (float)(sin(th) * sin(ph));
                            p[2] = (float)cos(th);
                            memcpy(m.normals + 3 * (size_t)m.vertex_count, p, 3 * sizeof(float));
                            m.uvs[2 * (size_t)m.vertex_count] = (float)(ii - ci) / (float)K;
                            m.uvs[2 * (size_t)m.vertex_count + 1] = (float)(jj - cj) / (float)K;
                            map[q] = (int)m.vertex_count++;
                        }
                        id[k] = (uint32_t)map[q];
                    }
                    uint32_t* t = m.indices + 3 * (size_t)m.triangle_count;
                    if (j == 0) { /* north cap: (i,0) is the pole */
                        t[0] = id[0], t[1] = id[3], t[2] = id[2];
                        m.triangle_count += 1;
                    } else if (j == nv - 1) { /* south cap: (i,nv) is the pole */
                        t[0] = id[0], t[1] = id[3], t[2] = id[1];
                        m.triangle_count += 1;
                    } else {
                        t[0] = id[0], t[1] = id[3], t[2] = id[2];
                        t[3] = id[0], t[4] = id[2], t[5] = id[1];
                        m.triangle_count += 2;
                    }
                }
        }
    free(map);
    return m;
}

/* ---- checks ---------------------------------------------------------------- */

static int cmp_triple(const void* a, const void* b)
{
    return memcmp(a, b, 3 * sizeof(uint32_t));
}

/* Faces of `m` on the same three positions (either winding): 0 expected. */
static int duplicate_faces(const meso_mesh* m)
{
    uint32_t* pos_id = malloc(sizeof(uint32_t) * m->vertex_count);
    uint32_t* t = malloc(sizeof(uint32_t) * 3 * m->triangle_count);
    assert(pos_id && t);
    for (uint32_t v = 0; v < m->vertex_count; ++v) { /* the first vertex at the same position */
        pos_id[v] = v;
        for (uint32_t u = 0; u < v; ++u)
            if (!memcmp(m->positions + 3 * (size_t)u, m->positions + 3 * (size_t)v, 12)) {
                pos_id[v] = u;
                break;
            }
    }
    for (uint32_t f = 0; f < m->triangle_count; ++f) {
        uint32_t a = pos_id[m->indices[3 * f]], b = pos_id[m->indices[3 * f + 1]], c = pos_id[m->indices[3 * f + 2]], x;
        if (a > b)
            x = a, a = b, b = x;
        if (b > c)
            x = b, b = c, c = x;
        if (a > b)
            x = a, a = b, b = x;
        t[3 * f] = a, t[3 * f + 1] = b, t[3 * f + 2] = c;
    }
    qsort(t, m->triangle_count, 3 * sizeof(uint32_t), cmp_triple);
    int dup = 0;
    for (uint32_t f = 1; f < m->triangle_count; ++f)
        dup += !memcmp(t + 3 * f, t + 3 * f - 3, 3 * sizeof(uint32_t));
    free(pos_id);
    free(t);
    return dup;
}

static void check_chain(const char* what, const meso_mesh* m, const meso_mesh_level* lv, uint32_t n)
{
    uint32_t prev = m->triangle_count;
    double prev_err = 0;
    for (uint32_t i = 0; i < n; ++i) {
        const meso_mesh_level* L = &lv[i];
        printf("    %s level %u: %u triangles, %u vertices, error %.6g\n", what, i + 1, L->mesh.triangle_count,
               L->mesh.vertex_count, L->error);
        assert(L->mesh.triangle_count < prev);                       /* decreasing */
        assert(L->mesh.triangle_count <= (uint32_t)(0.85 * prev));  /* not terminal */
        assert(prev > MESO_MESH_LEVELS_MIN_TRIANGLES);
        assert(L->error >= prev_err);                                 /* non-decreasing */
        assert(isfinite(L->error) && L->error > 0);
        assert(duplicate_faces(&L->mesh) == 0); /* no face twice on the same vertices */
        prev = L->mesh.triangle_count;
        prev_err = L->error;
        /* bounds: the level's own vertices */
        for (uint32_t v = 0; v < L->mesh.vertex_count; ++v)
            for (int k = 0; k < 3; ++k) {
                const double x = L->mesh.positions[3 * (size_t)v + (size_t)k];
                assert(x >= L->bbox_min[k] && x <= L->bbox_max[k]);
            }
        /* every level vertex is an input vertex, attributes and all */
        for (uint32_t v = 0; v < L->mesh.vertex_count; ++v) {
            int found = 0;
            for (uint32_t u = 0; u < m->vertex_count && !found; ++u)
                found = !memcmp(L->mesh.positions + 3 * (size_t)v, m->positions + 3 * (size_t)u, 12) &&
                        (!m->normals || !memcmp(L->mesh.normals + 3 * (size_t)v, m->normals + 3 * (size_t)u, 12)) &&
                        (!m->uvs || !memcmp(L->mesh.uvs + 2 * (size_t)v, m->uvs + 2 * (size_t)u, 8));
            assert(found);
        }
        assert((L->mesh.normals != NULL) == (m->normals != NULL) && (L->mesh.uvs != NULL) == (m->uvs != NULL));
    }
}

static void seam_split_sphere_gets_levels(void)
{
    printf("  seam-split sphere (every quad its own chart)\n");
    meso_mesh m = split_sphere(64, 32, 1);
    assert(m.triangle_count == 3968 && m.vertex_count == 4 * 64 * 30 + 2 * 3 * 64);
    meso_error err = {0};
    meso_mesh_level* lv = NULL;
    uint32_t n = 0;
    meso_mesh_levels_options o = {0};
    assert(meso_mesh_levels_build(&m, &o, &lv, &n, &err) == MESO_OK);
    check_chain("welded", &m, lv, n);
    assert(n + 1 >= 3);
    check_error_brute("welded level 1", &m, &lv[0]);
    check_error_brute("welded last level", &m, &lv[n - 1]);
    meso_mesh_levels_free(lv, n);

    /* The same mesh as given: 0.18 locks the vertices where 3+ copies meet. */
    o.split_seams = 1;
    uint32_t n_split = 0;
    assert(meso_mesh_levels_build(&m, &o, &lv, &n_split, &err) == MESO_OK);
    printf("    split as given: %u levels\n", n_split + 1);
    check_chain("split", &m, lv, n_split);
    meso_mesh_levels_free(lv, n_split);
    assert(n_split + 1 < 3);

    /* One seam only (a chart per 64 x 32 block): 0.18 pairs it itself,
     * and the welded chain does no worse. */
    meso_mesh one = split_sphere(64, 32, 64);
    assert(meso_mesh_levels_build(&one, &(meso_mesh_levels_options){0}, &lv, &n, &err) == MESO_OK);
    check_chain("one seam", &one, lv, n);
    assert(n + 1 >= 4);
    meso_mesh_levels_free(lv, n);
    meso_mesh_free(&one);
    meso_mesh_free(&m);
}

static void bundled_meshes_error_brute(void)
{
    /* spot_uv.obj: meshopt 0.18 leaves a face twice in its 5th level */
    const char* names[3] = {"torus.obj", "spot_low_resolution.obj", "spot_uv.obj"};
    for (int i = 0; i < 3; ++i) {
        meso_mesh m;
        meso_error err = {0};
        const meso_result r = meso_bake_load_mesh(test_data(names[i]), NULL, &m, NULL, &err);
        if (r == MESO_ERR_UNSUPPORTED) {
            printf("  %s: no mesh import in this build\n", names[i]);
            continue;
        }
        assert(r == MESO_OK);
        printf("  %s (%u triangles)\n", names[i], m.triangle_count);
        meso_mesh_level* lv = NULL;
        uint32_t n = 0;
        assert(meso_mesh_levels_build(&m, &(meso_mesh_levels_options){0}, &lv, &n, &err) == MESO_OK);
        check_chain(names[i], &m, lv, n);
        assert(n >= 2);
        check_error_brute("level 1", &m, &lv[0]);
        check_error_brute("last level", &m, &lv[n - 1]);
        /* the error grows with coarseness here (not only by the running max) */
        assert(lv[n - 1].measured > lv[0].measured);
        meso_mesh_levels_free(lv, n);
        meso_mesh_free(&m);
    }
}

/* Two unit squares 0.25 apart: the distance is exact (0.25 + radius). */
static void parallel_planes_known_answer(void)
{
    float pa[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    float pb[12] = {0, 0, 0.25f, 1, 0, 0.25f, 1, 1, 0.25f, 0, 1, 0.25f};
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    const meso_mesh a = {4, 2, pa, NULL, NULL, idx, NULL};
    const meso_mesh b = {4, 2, pb, NULL, NULL, idx, NULL};
    double bound = 0, radius = 0;
    meso_error err = {0};
    assert(meso_surface_distance(&a, &b, 0.1, 1, &bound, &radius, &err) == MESO_OK);
    /* diagonal sqrt(2) in ceil(sqrt(2)/0.1) = 15 steps */
    assert(fabs(radius - sqrt(2.0) / 15 / sqrt(3.0)) < 1e-12);
    assert(fabs(bound - (0.25 + radius)) < 1e-7);
    /* a square against itself shifted sideways by 0.5: the far strip is 0.5 away */
    float pc[12] = {0.5f, 0, 0, 1.5f, 0, 0, 1.5f, 1, 0, 0.5f, 1, 0};
    const meso_mesh c = {4, 2, pc, NULL, NULL, idx, NULL};
    assert(meso_surface_distance(&a, &c, 0.1, 2, &bound, &radius, &err) == MESO_OK);
    assert(fabs(bound - (0.5 + radius)) < 1e-7);
}

/* surface_distance.c skips samples that cannot raise the max (Lipschitz
 * and nearest-triangle bounds). Its result must be exactly the max over
 * every sample of its scheme (corners of n x n sub-triangles, n = ceil(
 * longest edge / spacing)), here measured sample by sample with the test's
 * own closest point over every triangle: a coarse sphere against a fine one
 * (the coarse level's error is many spacings: most samples are skipped),
 * and against itself rotated (errors about one spacing). */
static double brute_scheme(const meso_mesh* a, const meso_mesh* b, double spacing, double* radius)
{
    double worst = 0;
    uint32_t hint = 0;
    for (uint32_t f = 0; f < a->triangle_count; ++f) {
        double v[3][3], longest = 0;
        for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k)
                v[j][k] = a->positions[3 * (size_t)a->indices[3 * (size_t)f + (size_t)j] + (size_t)k];
        for (int j = 0; j < 3; ++j) {
            double l2 = 0;
            for (int k = 0; k < 3; ++k)
                l2 += (v[j][k] - v[(j + 1) % 3][k]) * (v[j][k] - v[(j + 1) % 3][k]);
            longest = sqrt(l2) > longest ? sqrt(l2) : longest;
        }
        const int n = (int)fmax(1, ceil(longest / spacing));
        *radius = fmax(*radius, longest / n / sqrt(3.0));
        for (int i = 0; i <= n; ++i)
            for (int j = 0; j <= n - i; ++j) {
                double p[3];
                for (int k = 0; k < 3; ++k)
                    p[k] = v[0][k] + (double)i / n * (v[1][k] - v[0][k]) + (double)j / n * (v[2][k] - v[0][k]);
                const double d = mesh_dist_above(p, b, worst, &hint);
                worst = d > worst ? d : worst;
            }
    }
    return worst;
}

static void skipped_samples_change_nothing(void)
{
    meso_mesh fine = split_sphere(24, 12, 24), coarse = split_sphere(6, 4, 6), turned = split_sphere(24, 12, 24);
    for (uint32_t v = 0; v < turned.vertex_count; ++v) { /* 0.1 rad about z */
        float* p = turned.positions + 3 * (size_t)v;
        const double x = p[0], y = p[1];
        p[0] = (float)(cos(0.1) * x - sin(0.1) * y);
        p[1] = (float)(sin(0.1) * x + cos(0.1) * y);
    }
    const meso_mesh* other[2] = {&coarse, &turned};
    const double spacing = 0.05;
    for (int c = 0; c < 2; ++c) {
        double brute_radius = 0;
        const double ab = brute_scheme(other[c], &fine, spacing, &brute_radius);
        const double ba = brute_scheme(&fine, other[c], spacing, &brute_radius);
        const double want = (ab > ba ? ab : ba) + brute_radius;
        for (int threads = 1; threads <= 2; ++threads) {
            double bound = 0, radius = 0;
            meso_error err = {0};
            assert(meso_surface_distance(other[c], &fine, spacing, threads, &bound, &radius, &err) == MESO_OK);
            printf("    every sample measured (%s, %d threads): %.9g, surface_distance %.9g\n",
                   c ? "rotated" : "coarse", threads, want, bound);
            assert(fabs(radius - brute_radius) <= 1e-12);
            assert(fabs(bound - want) <= 1e-9);
            /* Against a reference built once (mesh_levels.c's chain): the
             * same numbers. */
            meso_surface_ref ref;
            double ref_bound = 0, ref_radius = 0;
            assert(meso_surface_ref_build(&fine, &ref, &err) == MESO_OK);
            assert(meso_surface_distance_to_ref(other[c], &ref, spacing, threads, &ref_bound, &ref_radius, &err) ==
                   MESO_OK);
            assert(ref_bound == bound && ref_radius == radius);
            meso_surface_ref_free(&ref);
        }
    }
    /* A mesh reaching outside the reference's box is measured with both
     * grids built anew over both boxes (the reference's grid does not hold
     * its samples): the same number as meso_surface_distance. */
    for (uint32_t i = 0; i < 3 * coarse.vertex_count; ++i)
        coarse.positions[i] *= 1.25f;
    meso_surface_ref ref;
    meso_error err = {0};
    double bound = 0, ref_bound = 0, radius = 0, ref_radius = 0;
    assert(meso_surface_ref_build(&fine, &ref, &err) == MESO_OK);
    assert(meso_surface_distance(&coarse, &fine, spacing, 2, &bound, &radius, &err) == MESO_OK);
    assert(meso_surface_distance_to_ref(&coarse, &ref, spacing, 2, &ref_bound, &ref_radius, &err) == MESO_OK);
    assert(ref_bound == bound && ref_radius == radius && bound > 0.2);
    meso_surface_ref_free(&ref);
    meso_mesh_free(&fine);
    meso_mesh_free(&coarse);
    meso_mesh_free(&turned);
}

/* ---- the bake --------------------------------------------------------------- */

static uint8_t* bake(const meso_mesh* m, int levels, int threads, size_t* size, meso_bake_mesh_report* rep)
{
    meso_bake_mesh_options o = meso_bake_mesh_defaults();
    o.mesh = m;
    o.levels = levels;
    o.common.threads = threads;
    meso_bake_output* out = NULL;
    meso_error err = {0};
    const meso_result r = meso_bake_mesh(&o, &out, rep, &err);
    if (r != MESO_OK)
        fprintf(stderr, "    bake: %s\n", err.message);
    assert(r == MESO_OK);
    size_t need = 0;
    assert(meso_bake_output_copy(out, NULL, 0, &need) == MESO_OK || need > 0);
    uint8_t* buf = malloc(need);
    assert(buf);
    assert(meso_bake_output_copy(out, buf, need, size) == MESO_OK && *size == need);
    meso_bake_output_free(out);
    return buf;
}

static int count_issue(void* user, const meso_error* issue)
{
    fprintf(stderr, "    issue %u: %s\n", issue->code, issue->message);
    ++*(int*)user;
    return 0;
}

static void baked_file_levels(void)
{
    printf("  baked file (seam-split sphere in memory)\n");
    meso_mesh m = split_sphere(64, 32, 1);
    meso_bake_mesh_report rep;
    size_t size = 0, size2 = 0;
    uint8_t* a = bake(&m, 0, 1, &size, &rep);
    uint8_t* b = bake(&m, 0, 2, &size2, NULL);
    assert(size == size2 && memcmp(a, b, size) == 0); /* 1 vs 2 threads: byte-identical */
    assert(rep.level_count >= 3);

    meso_file* f = NULL;
    meso_error err = {0};
    assert(meso_file_open_memory(a, size, NULL, &f, &err) == MESO_OK);
    int issues = 0;
    assert(meso_file_validate(f, MESO_CHECK_FULL, count_issue, &issues) == MESO_OK);
    assert(issues == 0);
    meso_level_info lv[MESO_BAKE_MESH_MAX_LEVELS];
    uint32_t n = 0;
    assert(meso_file_levels(f, 1, lv, MESO_BAKE_MESH_MAX_LEVELS, &n, &err) == MESO_OK);
    assert(n == rep.level_count);
    /* bytes and prefix recomputed from the TOC: level L draws the MESH of lod L */
    uint64_t head_end = 0;
    for (uint32_t i = 0; i < meso_file_chunk_count(f); ++i) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        if (c->type == MESO_CHUNK_META || c->type == MESO_CHUNK_OBJT || c->type == MESO_CHUNK_LODS) {
            const uint64_t end = c->offset + c->stored_size; /* stored bytes end (padding not needed) */
            head_end = end > head_end ? end : head_end;
        }
    }
    double prev = -1;
    for (uint32_t L = 0; L < n; ++L) {
        assert(lv[L].rec.lod == L && lv[L].rec.form == MESO_LEVEL_NATIVE);
        const meso_chunk_info* mc = NULL;
        for (uint32_t i = 0; i < meso_file_chunk_count(f); ++i) {
            const meso_chunk_info* c = meso_file_chunk(f, i);
            if (c->type == MESO_CHUNK_MESH && c->lod == L) {
                assert(!mc); /* one MESH per level */
                mc = c;
            }
        }
        assert(mc);
        const uint64_t end = mc->offset + mc->stored_size; /* stored bytes end (padding not needed) */
        assert(lv[L].bytes == mc->stored_size);
        assert(lv[L].prefix_bytes == (end > head_end ? end : head_end));
        assert(rep.level[L].mesh_bytes == mc->stored_size);
        /* triangles from the chunk's own header */
        const uint8_t* p = (const uint8_t*)a + mc->offset;
        uint32_t ic;
        memcpy(&ic, p + MESO_MESH_OFF_INDEX_COUNT, 4);
        assert(ic / 3 == rep.level[L].triangles);
        /* the stored error: the report's, rounded up to f32, non-decreasing */
        assert((double)lv[L].rec.error >= rep.level[L].error);
        assert((double)lv[L].rec.error <= rep.level[L].error * (1 + 1e-6));
        assert((double)lv[L].rec.error >= prev);
        prev = lv[L].rec.error;
        if (L > 0) /* a prefix holding level L also holds every coarser one (written first) */
            assert(lv[L].prefix_bytes < lv[L - 1].prefix_bytes);
    }
    assert(lv[0].rec.error == 0.0f);
    meso_file_close(f);
    free(b);

    /* levels 1: no LODS chunk, one MESH; levels 2: exactly two levels */
    uint8_t* one = bake(&m, 1, 0, &size2, &rep);
    assert(meso_file_open_memory(one, size2, NULL, &f, &err) == MESO_OK);
    assert(meso_file_find(f, MESO_CHUNK_LODS, 0, UINT16_MAX) < 0 && rep.level_count == 1);
    assert(meso_file_levels(f, 1, lv, MESO_BAKE_MESH_MAX_LEVELS, &n, &err) == MESO_OK && n == 1);
    meso_file_close(f);
    free(one);
    uint8_t* two = bake(&m, 2, 0, &size2, &rep);
    assert(meso_file_open_memory(two, size2, NULL, &f, &err) == MESO_OK);
    assert(meso_file_levels(f, 1, lv, MESO_BAKE_MESH_MAX_LEVELS, &n, &err) == MESO_OK && n == 2);
    meso_file_close(f);
    free(two);
    free(a);
    meso_mesh_free(&m);
}

int main(void)
{
    printf("mesh levels:\n");
    parallel_planes_known_answer();
    skipped_samples_change_nothing();
    seam_split_sphere_gets_levels();
    bundled_meshes_error_brute();
    baked_file_levels();
    printf("ok\n");
    return 0;
}
