/* test_mesh_parts — a mesh cut into parts with levels of their own
 * (bake/mesh_parts.c, issue 14). On the bundled spot_uv.obj (5856
 * triangles, uv seams: split vertices) and torus.obj, against brute force:
 *
 *  - the parts' level 0 triangles are the input's, each exactly once;
 *  - any choice of levels, one per part, is as watertight as the input:
 *    every edge of the union (by vertex position) is used an even number
 *    of times, as in the input (closed) — for 200 random choices and the
 *    all-coarsest one ("never crack");
 *  - each part level's stated error is at least the largest distance from
 *    dense sample points of either surface to the other (both ways, exact
 *    point-triangle distances over every triangle);
 *  - errors are 0 at level 0 and never decrease; bounds hold the level's
 *    vertices;
 *  - the neighbour pairs are exactly the pairs of parts sharing a vertex
 *    position;
 *  - a mesh with uv seams still gets more than one level in its parts;
 *  - 1 and 2 threads give the same parts.
 */
#include "test_util.h"

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh_parts.h"
#include "point_triangle.h"

/* ---- positions as keys --------------------------------------------------- */

typedef struct pkey {
    float p[3];
    uint32_t id;
} pkey;

static int by_pos(const void* a, const void* b)
{
    const pkey *x = a, *y = b;
    for (int k = 0; k < 3; ++k)
        if (x->p[k] != y->p[k])
            return x->p[k] < y->p[k] ? -1 : 1;
    return x->id < y->id ? -1 : x->id > y->id;
}

/* An id per distinct position of the points pts[0..n) (3 floats each). */
static uint32_t* position_ids(const float* pts, size_t n)
{
    pkey* k = malloc(sizeof(pkey) * (n ? n : 1));
    uint32_t* id = malloc(sizeof(uint32_t) * (n ? n : 1));
    assert(k && id);
    for (size_t i = 0; i < n; ++i) {
        memcpy(k[i].p, pts + 3 * i, sizeof(k[i].p));
        k[i].id = (uint32_t)i;
    }
    qsort(k, n, sizeof(pkey), by_pos);
    uint32_t next = 0;
    for (size_t i = 0; i < n; ++i) {
        if (i > 0 && memcmp(k[i].p, k[i - 1].p, sizeof(k[i].p)) != 0)
            ++next;
        id[k[i].id] = next;
    }
    free(k);
    return id;
}

typedef struct tri_soup {
    float* corner; /* 9 floats per triangle */
    size_t n, cap;
} tri_soup;

static void soup_add_mesh(tri_soup* s, const meso_mesh* m)
{
    if (s->n + m->triangle_count > s->cap) {
        s->cap = 2 * (s->n + m->triangle_count);
        s->corner = realloc(s->corner, sizeof(float) * 9 * s->cap);
        assert(s->corner);
    }
    for (uint32_t t = 0; t < m->triangle_count; ++t)
        for (int c = 0; c < 3; ++c)
            memcpy(s->corner + 9 * (s->n + t) + 3 * (size_t)c,
                   m->positions + 3 * (size_t)m->indices[3 * (size_t)t + (size_t)c], 3 * sizeof(float));
    s->n += m->triangle_count;
}

static int by_36(const void* a, const void* b)
{
    return memcmp(a, b, 36);
}

static int by_u64(const void* a, const void* b)
{
    const uint64_t x = *(const uint64_t*)a, y = *(const uint64_t*)b;
    return x < y ? -1 : x > y;
}

/* The undirected edges of a soup as sorted (position id pair) keys, with
 * the ids from the corners of `ref` and `s` together. */
static uint64_t* soup_edges(const tri_soup* s, const uint32_t* ids)
{
    uint64_t* e = malloc(sizeof(uint64_t) * 3 * (s->n ? s->n : 1));
    assert(e);
    for (size_t t = 0; t < s->n; ++t)
        for (int c = 0; c < 3; ++c) {
            uint64_t a = ids[3 * t + (size_t)c], b = ids[3 * t + (size_t)(c + 1) % 3];
            if (a > b) {
                const uint64_t x = a;
                a = b;
                b = x;
            }
            e[3 * t + (size_t)c] = a << 32 | b;
        }
    qsort(e, 3 * s->n, sizeof(uint64_t), by_u64);
    return e;
}

/* `s` is as watertight as `ref`: the same edges (by position) are used an
 * odd number of times (none: both inputs here are closed). */
static void check_same_edges(const char* what, const tri_soup* ref, const tri_soup* s, size_t* chords)
{
    tri_soup both = {0};
    both.n = both.cap = ref->n + s->n;
    both.corner = malloc(sizeof(float) * 9 * both.n);
    assert(both.corner);
    memcpy(both.corner, ref->corner, sizeof(float) * 9 * ref->n);
    memcpy(both.corner + 9 * ref->n, s->corner, sizeof(float) * 9 * s->n);
    uint32_t* ids = position_ids(both.corner, 3 * both.n);
    tri_soup a = {ref->corner, ref->n, ref->n}, b = {s->corner, s->n, s->n};
    uint64_t* ea = soup_edges(&a, ids);
    uint64_t* eb = soup_edges(&b, ids + 3 * ref->n);
    /* The boundary of each soup, mod 2: the edges used an odd number of
     * times (a crack is such an edge, where one part's border meets
     * nothing). Both must have the same; the inputs are closed, so none. A
     * coarse level may leave a chord of two border vertices in two parts
     * (used 4 times): closed still, counted, not a crack. */
    size_t odd_a = 0, odd_b = 0, four = 0;
    for (size_t i = 0; i < 3 * a.n;) {
        size_t j = i;
        while (j < 3 * a.n && ea[j] == ea[i])
            ++j;
        odd_a += (j - i) & 1;
        i = j;
    }
    for (size_t i = 0; i < 3 * b.n;) {
        size_t j = i;
        while (j < 3 * b.n && eb[j] == eb[i])
            ++j;
        if ((j - i) & 1) {
            ++odd_b;
            if (odd_b <= 3)
                printf("    %s: edge %llu-%llu used %zu times\n", what, (unsigned long long)(eb[i] >> 32),
                       (unsigned long long)(eb[i] & 0xFFFFFFFFu), j - i);
        }
        four += j - i > 2;
        i = j;
    }
    assert(odd_a == 0 && odd_b == 0);
    *chords += four;
    free(ea);
    free(eb);
    free(ids);
    free(both.corner);
}

/* ---- distances ----------------------------------------------------------- */

/* The distance from p to m, or some distance <= floor when it is <= floor
 * (the triangle *hint first, then every one; *hint gets the nearest). */
static double dist_to_mesh_above(const double p[3], const meso_mesh* m, double floor, uint32_t* hint)
{
    double best = INFINITY;
    for (uint32_t k = 0; k <= m->triangle_count; ++k) {
        const uint32_t t = k == 0 ? *hint : k - 1;
        if (t >= m->triangle_count || (k > 0 && t == *hint))
            continue;
        const uint32_t* i = m->indices + 3 * (size_t)t;
        const double d = point_triangle(p, m->positions + 3 * (size_t)i[0], m->positions + 3 * (size_t)i[1],
                                        m->positions + 3 * (size_t)i[2]);
        if (d < best) {
            best = d;
            *hint = t;
            if (best <= floor)
                break;
        }
    }
    return best;
}

/* Largest distance from points of a (on a 6 x 6 barycentric grid in every
 * triangle, corners and edges included) to b: exact, by every triangle of
 * b, except that a point's search ends once it is no farther than the
 * largest found so far (it cannot raise the largest). */
static double one_way(const meso_mesh* a, const meso_mesh* b)
{
    enum { G = 6 };
    double worst = 0;
    uint32_t hint = 0;
    for (uint32_t t = 0; t < a->triangle_count; ++t) {
        const float* v[3];
        for (int c = 0; c < 3; ++c)
            v[c] = a->positions + 3 * (size_t)a->indices[3 * (size_t)t + (size_t)c];
        for (int i = 0; i <= G; ++i)
            for (int j = 0; i + j <= G; ++j) {
                const double s = (double)i / G, u = (double)j / G;
                double p[3];
                for (int k = 0; k < 3; ++k)
                    p[k] = v[0][k] + s * ((double)v[1][k] - v[0][k]) + u * ((double)v[2][k] - v[0][k]);
                worst = fmax(worst, dist_to_mesh_above(p, b, worst, &hint));
            }
    }
    return worst;
}

/* ---- checks ---------------------------------------------------------------- */

static void check_mesh(const char* name, uint32_t part_triangles)
{
    meso_mesh m;
    meso_error err;
    assert(meso_bake_load_mesh(test_data(name), NULL, &m, NULL, &err) == MESO_OK);
    meso_mesh_parts p, q;
    const meso_mesh_parts_options o1 = {.part_triangles = part_triangles, .threads = 1};
    const meso_mesh_parts_options o2 = {.part_triangles = part_triangles, .threads = 2};
    assert(meso_mesh_parts_build(&m, &o1, &p, &err) == MESO_OK);
    assert(meso_mesh_parts_build(&m, &o2, &q, &err) == MESO_OK);
    printf("%s: %u triangles, %u parts, %u neighbour pairs\n", name, m.triangle_count, p.count, p.edge_count);
    assert(p.count >= 2);

    /* Level 0: the input's triangles, each once (as position triples in
     * the input's winding). */
    tri_soup in = {0}, l0 = {0};
    soup_add_mesh(&in, &m);
    uint32_t coarser = 0;
    for (uint32_t i = 0; i < p.count; ++i) {
        soup_add_mesh(&l0, &p.part[i].level[0].mesh);
        coarser += p.part[i].level_count > 1;
    }
    assert(l0.n == in.n);
    {
        float* a = malloc(sizeof(float) * 9 * in.n);
        float* b = malloc(sizeof(float) * 9 * in.n);
        assert(a && b);
        memcpy(a, in.corner, sizeof(float) * 9 * in.n);
        memcpy(b, l0.corner, sizeof(float) * 9 * in.n);
        /* Rotate each triangle to start at its smallest corner, sort. */
        float* both[2] = {a, b};
        for (int w = 0; w < 2; ++w) {
            for (size_t t = 0; t < in.n; ++t) {
                float* c = both[w] + 9 * t;
                int s = 0;
                for (int k = 1; k < 3; ++k)
                    if (memcmp(c + 3 * k, c + 3 * s, 12) < 0)
                        s = k;
                float tmp[9];
                for (int k = 0; k < 3; ++k)
                    memcpy(tmp + 3 * k, c + 3 * ((s + k) % 3), 12);
                memcpy(c, tmp, sizeof(tmp));
            }
            qsort(both[w], in.n, 36, by_36);
        }
        assert(memcmp(a, b, sizeof(float) * 9 * in.n) == 0);
        free(a);
        free(b);
    }
    printf("  level 0: the input's %zu triangles, each once; %u of %u parts have coarser levels\n", in.n, coarser,
           p.count);
    assert(coarser >= (p.count + 1) / 2);

    /* Errors, bounds, levels against brute force. */
    double worst_ratio = 0;
    for (uint32_t i = 0; i < p.count; ++i) {
        const meso_mesh_part* P = &p.part[i];
        assert(P->level[0].error == 0);
        for (uint32_t l = 0; l < P->level_count; ++l) {
            const meso_mesh_part_level* L = &P->level[l];
            assert(l == 0 || L->error >= P->level[l - 1].error);
            for (uint32_t v = 0; v < L->mesh.vertex_count; ++v)
                for (int k = 0; k < 3; ++k) {
                    assert(L->mesh.positions[3 * (size_t)v + (size_t)k] >= L->bbox_min[k]);
                    assert(L->mesh.positions[3 * (size_t)v + (size_t)k] <= L->bbox_max[k]);
                }
            if (l == 0)
                continue;
            const double brute = fmax(one_way(&L->mesh, &P->level[0].mesh), one_way(&P->level[0].mesh, &L->mesh));
            if (brute > L->error * (1 + 1e-9) + 1e-12)
                printf("  part %u level %u: stated %.6g < brute force %.6g\n", i, l, L->error, brute);
            assert(brute <= L->error * (1 + 1e-9) + 1e-12);
            worst_ratio = fmax(worst_ratio, brute / L->error);
        }
    }
    printf("  every part level's stated error holds against brute force (largest brute / stated %.2f)\n",
           worst_ratio);

    /* Neighbours: parts sharing a position, brute force. */
    {
        uint32_t* pid = position_ids(m.positions, m.vertex_count);
        uint32_t np = 0;
        for (uint32_t v = 0; v < m.vertex_count; ++v)
            np = pid[v] + 1 > np ? pid[v] + 1 : np;
        uint8_t* touch = calloc((size_t)np * p.count, 1);
        assert(touch);
        for (uint32_t i = 0; i < p.count; ++i) {
            const meso_mesh* pm = &p.part[i].level[0].mesh;
            uint32_t* ids = malloc(sizeof(uint32_t) * pm->vertex_count);
            assert(ids);
            /* Each part vertex's position among the input's. */
            for (uint32_t v = 0; v < pm->vertex_count; ++v) {
                ids[v] = UINT32_MAX;
                for (uint32_t w = 0; w < m.vertex_count && ids[v] == UINT32_MAX; ++w)
                    if (memcmp(pm->positions + 3 * (size_t)v, m.positions + 3 * (size_t)w, 12) == 0)
                        ids[v] = pid[w];
                assert(ids[v] != UINT32_MAX);
                touch[(size_t)ids[v] * p.count + i] = 1;
            }
            free(ids);
        }
        uint8_t* pair = calloc((size_t)p.count * p.count, 1);
        assert(pair);
        for (uint32_t x = 0; x < np; ++x)
            for (uint32_t a = 0; a < p.count; ++a)
                for (uint32_t b = a + 1; touch[(size_t)x * p.count + a] && b < p.count; ++b)
                    if (touch[(size_t)x * p.count + b])
                        pair[(size_t)a * p.count + b] = 1;
        uint32_t n = 0;
        for (uint32_t e = 0; e < p.edge_count; ++e) {
            const uint32_t a = p.edges[2 * e], b = p.edges[2 * e + 1];
            assert(a < b && b < p.count && pair[(size_t)a * p.count + b]);
            assert(e == 0 || a > p.edges[2 * e - 2] || (a == p.edges[2 * e - 2] && b > p.edges[2 * e - 1]));
        }
        for (size_t k = 0; k < (size_t)p.count * p.count; ++k)
            n += pair[k];
        assert(n == p.edge_count);
        printf("  neighbour pairs: the %u pairs of parts sharing a position\n", n);
        free(pair);
        free(touch);
        free(pid);
    }

    /* Any levels: no crack. */
    uint64_t rng = 777;
    size_t chords = 0;
    for (int trial = 0; trial <= 200; ++trial) {
        tri_soup u = {0};
        for (uint32_t i = 0; i < p.count; ++i) {
            const uint32_t n = p.part[i].level_count;
            const uint32_t l = trial == 200 ? n - 1 : (uint32_t)(test_rng_next(&rng) % n);
            soup_add_mesh(&u, &p.part[i].level[l].mesh);
        }
        check_same_edges(name, &in, &u, &chords);
        free(u.corner);
    }
    printf("  200 random choices of part levels and the coarsest everywhere: every edge used an even number of "
           "times, as in the input (%zu edges used 4 or more times over all choices)\n",
           chords);

    /* Threads change nothing. */
    assert(p.count == q.count && p.edge_count == q.edge_count);
    assert(memcmp(p.edges, q.edges, sizeof(uint32_t) * 2 * p.edge_count) == 0);
    for (uint32_t i = 0; i < p.count; ++i) {
        assert(p.part[i].level_count == q.part[i].level_count);
        for (uint32_t l = 0; l < p.part[i].level_count; ++l) {
            const meso_mesh_part_level *a = &p.part[i].level[l], *b = &q.part[i].level[l];
            assert(a->error == b->error && a->mesh.triangle_count == b->mesh.triangle_count &&
                   a->mesh.vertex_count == b->mesh.vertex_count);
            assert(memcmp(a->mesh.indices, b->mesh.indices, 12 * (size_t)a->mesh.triangle_count) == 0);
            assert(memcmp(a->mesh.positions, b->mesh.positions, 12 * (size_t)a->mesh.vertex_count) == 0);
        }
    }
    free(in.corner);
    free(l0.corner);
    meso_mesh_parts_free(&p);
    meso_mesh_parts_free(&q);
    meso_mesh_free(&m);
}

int main(void)
{
    setvbuf(stdout, NULL, _IONBF, 0);
    check_mesh("spot_uv.obj", 1024);
    check_mesh("torus.obj", 1024);
    /* Too small to cut: no parts. */
    meso_mesh m;
    meso_error err;
    assert(meso_bake_load_mesh(test_data("torus.obj"), NULL, &m, NULL, &err) == MESO_OK);
    meso_mesh_parts p;
    assert(meso_mesh_parts_build(&m, &(meso_mesh_parts_options){.part_triangles = m.triangle_count}, &p, &err) ==
           MESO_OK);
    assert(p.count == 0);
    meso_mesh_parts_free(&p);
    meso_mesh_free(&m);
    printf("ok   test_mesh_parts\n");
    return 0;
}
