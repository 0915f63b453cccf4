/*
 * voxel_soup.c — the triangles the voxelizer traces: the mesh's, and for
 * MESO_VOXELIZE_WINDING the closing cone C of voxelize.h ("w(q) = X(q) -
 * w_C(q)"). The chain boundary of the mesh (vertices welded by exact position
 * first, so unwelded seams are no boundary; every directed edge +1, its
 * reverse -1; edges with a non-zero sum, as often as the sum says) splits
 * into closed loops, and C is one fan per loop to the mean of its vertices.
 * AUTO picks PARITY when that boundary is empty and every edge has two uses.
 * w_C is the exact sum of the fans' solid angles (Jacobson et al. 2013) up to
 * MESO_VOXELIZE_CONE_DIRECT triangles, the Barill hierarchy beyond.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "voxelize_internal.h"

/* >>triangle soup ---------------------------------------------------------------- */

void mesoi_soup_free(mesoi_soup* s)
{
    free(s->own_pos);
    free(s->own_idx);
    meso_winding_free(s->cone_tree);
    memset(s, 0, sizeof(*s));
}

static void corner(const mesoi_soup* s, uint32_t t, int c, double out[3])
{
    const float* p = s->pos + 3 * (size_t)s->idx[3 * (size_t)t + (size_t)c];
    out[0] = p[0];
    out[1] = p[1];
    out[2] = p[2];
}

void mesoi_tri_corners(const mesoi_soup* s, uint32_t t, double v[3][3], double lo[3], double hi[3])
{
    for (int c = 0; c < 3; ++c)
        corner(s, t, c, v[c]);
    for (int k = 0; k < 3; ++k) {
        lo[k] = mesoi_dmin(v[0][k], mesoi_dmin(v[1][k], v[2][k]));
        hi[k] = mesoi_dmax(v[0][k], mesoi_dmax(v[1][k], v[2][k]));
    }
}

/* LSD radix sort of 64-bit keys (deterministic, O(n)); tmp has n entries. */
static void radix_sort(uint64_t* key, uint64_t* tmp, size_t n)
{
    size_t count[256];
    for (int shift = 0; shift < 64; shift += 8) {
        memset(count, 0, sizeof(count));
        for (size_t i = 0; i < n; ++i)
            count[(key[i] >> shift) & 255]++;
        if (count[(key[0] >> shift) & 255] == n)
            continue; /* every key has this byte */
        size_t sum = 0;
        for (int b = 0; b < 256; ++b) {
            const size_t c = count[b];
            count[b] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; ++i)
            tmp[count[(key[i] >> shift) & 255]++] = key[i];
        memcpy(key, tmp, n * sizeof(uint64_t));
    }
}

/* Vertices welded by exact position: canon[v] = the smallest id with v's
 * coordinates. Unwelded seams (a texture seam, a soup) are then no boundary. */
typedef struct vkey {
    float p[3];
    uint32_t id;
} vkey;

static int cmp_vkey(const void* pa, const void* pb)
{
    const vkey *a = pa, *b = pb;
    for (int k = 0; k < 3; ++k)
        if (a->p[k] != b->p[k])
            return a->p[k] < b->p[k] ? -1 : 1;
    return a->id < b->id ? -1 : a->id > b->id;
}

static uint32_t* weld(const meso_mesh* m)
{
    const size_t nv = m->vertex_count;
    vkey* k = malloc(sizeof(vkey) * nv);
    uint32_t* canon = malloc(sizeof(uint32_t) * nv);
    if (!k || !canon) {
        free(k);
        free(canon);
        return NULL;
    }
    for (size_t v = 0; v < nv; ++v)
        k[v] = (vkey){{m->positions[3 * v], m->positions[3 * v + 1], m->positions[3 * v + 2]}, (uint32_t)v};
    qsort(k, nv, sizeof(vkey), cmp_vkey);
    for (size_t i = 0, first = 0; i < nv; ++i) {
        if (i && (k[i].p[0] != k[i - 1].p[0] || k[i].p[1] != k[i - 1].p[1] || k[i].p[2] != k[i - 1].p[2]))
            first = i;
        canon[k[i].id] = k[first].id;
    }
    free(k);
    return canon;
}

/* Chain boundary of the welded mesh: every directed edge a -> b adds +1 to
 * the undirected edge {a, b} when a < b and -1 otherwise. *closed = 1 when
 * every undirected edge has exactly two uses summing to 0 (auto's PARITY
 * test). *edges (malloc'd, NULL when none) receives the boundary as directed
 * pairs (from, to), each repeated |sum| times, sorted by (from, to); *count
 * their number. Keys: min << 33 | max << 1 | (a > b), vertex ids < 2^31. */
static meso_result chain_boundary(const meso_mesh* m, const uint32_t* canon, int* closed, uint32_t** edges,
                                  uint32_t* count, meso_error* err)
{
    const size_t nf = m->triangle_count;
    uint64_t* key = malloc(sizeof(uint64_t) * 3 * nf);
    uint64_t* tmp = malloc(sizeof(uint64_t) * 3 * nf);
    *edges = NULL;
    *count = 0;
    if (!key || !tmp) {
        free(key);
        free(tmp);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "voxelize: out of memory (%zu edges)", 3 * nf);
    }
    size_t n = 0;
    for (size_t f = 0; f < nf; ++f)
        for (int c = 0; c < 3; ++c) {
            const uint64_t a = canon[m->indices[3 * f + (size_t)c]], b = canon[m->indices[3 * f + (size_t)(c + 1) % 3]];
            if (a != b)
                key[n++] = a < b ? (a << 33 | b << 1) : (b << 33 | a << 1 | 1u);
        }
    if (n)
        radix_sort(key, tmp, n);
    *closed = 1;
    size_t nb = 0;
    for (int pass = 0; pass < 2; ++pass) {
        nb = 0;
        for (size_t i = 0; i < n;) {
            size_t j = i;
            long sum = 0;
            while (j < n && key[j] >> 1 == key[i] >> 1)
                sum += (key[j++] & 1u) ? -1 : 1;
            if (pass == 0 && (j - i != 2 || sum != 0))
                *closed = 0;
            const uint64_t lo = key[i] >> 33, hi = (key[i] >> 1) & 0xFFFFFFFFu;
            for (long r = 0; r < labs(sum); ++r, ++nb)
                if (pass == 1)
                    tmp[nb] = sum > 0 ? (lo << 32 | hi) : (hi << 32 | lo); /* from << 32 | to */
            i = j;
        }
        if (pass == 0 && nb == 0)
            break;
    }
    if (nb) {
        radix_sort(tmp, key, nb);
        if (nb > UINT32_MAX / 4 || !(*edges = malloc(sizeof(uint32_t) * 2 * nb))) {
            free(key);
            free(tmp);
            return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "voxelize: out of memory");
        }
        for (size_t e = 0; e < nb; ++e) {
            (*edges)[2 * e] = (uint32_t)(tmp[e] >> 32);
            (*edges)[2 * e + 1] = (uint32_t)tmp[e];
        }
        *count = (uint32_t)nb;
    }
    free(key);
    free(tmp);
    return MESO_OK;
}

/* Split the boundary (sorted by from; every vertex has as many edges in as
 * out) into closed loops: walk from the first unused edge, always on along
 * the first unused edge out of the current vertex, until back at the start.
 * order[] receives the edges loop by loop, loop_end[l] the end of loop l in
 * it; returns the loop count. */
static uint32_t boundary_loops(const uint32_t* e, uint32_t n, uint32_t* order, uint32_t* loop_end, uint8_t* used,
                               uint32_t* cursor)
{
    for (uint32_t i = 0; i < n; ++i)
        cursor[i] = i;
    memset(used, 0, n);
    uint32_t m = 0, loops = 0;
    for (uint32_t first = 0; first < n; ++first) {
        if (used[first])
            continue;
        const uint32_t start = e[2 * first];
        uint32_t cur = first;
        for (;;) {
            used[cur] = 1;
            order[m++] = cur;
            const uint32_t v = e[2 * cur + 1];
            if (v == start)
                break;
            uint32_t lo = 0, hi = n; /* first edge out of v */
            while (lo < hi) {
                const uint32_t mid = lo + (hi - lo) / 2;
                if (e[2 * mid] < v)
                    lo = mid + 1;
                else
                    hi = mid;
            }
            uint32_t c = cursor[lo];
            while (c < n && e[2 * c] == v && used[c])
                ++c;
            cursor[lo] = c;
            if (c >= n || e[2 * c] != v)
                break; /* cannot happen for a boundary; ends the loop defensively */
            cur = c;
        }
        loop_end[loops++] = m;
    }
    return loops;
}

meso_result mesoi_soup_build(const meso_mesh* m, meso_voxelizer* method, int threads, mesoi_soup* s, meso_error* err)
{
    memset(s, 0, sizeof(*s));
    s->pos = m->positions;
    s->idx = m->indices;
    s->surface = s->count = m->triangle_count;
    if (*method == MESO_VOXELIZE_PARITY)
        return MESO_OK;
    uint32_t* canon = weld(m);
    if (!canon)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "voxelize: out of memory (weld)");
    int closed = 1;
    uint32_t *edges = NULL, ne = 0;
    meso_result r = chain_boundary(m, canon, &closed, &edges, &ne, err);
    free(canon);
    if (r != MESO_OK)
        return r;
    if (*method == MESO_VOXELIZE_AUTO)
        *method = closed ? MESO_VOXELIZE_PARITY : MESO_VOXELIZE_WINDING;
    if (*method == MESO_VOXELIZE_PARITY || ne == 0) {
        free(edges);
        return MESO_OK;
    }
    const size_t nv = m->vertex_count, nt = (size_t)m->triangle_count + ne;
    uint32_t* order = malloc(sizeof(uint32_t) * ne);
    uint32_t* loop_end = malloc(sizeof(uint32_t) * ne);
    uint32_t* cursor = malloc(sizeof(uint32_t) * ne);
    uint8_t* used = malloc(ne);
    s->own_pos = malloc(sizeof(float) * 3 * (nv + ne));
    s->own_idx = nt <= UINT32_MAX ? malloc(sizeof(uint32_t) * 3 * nt) : NULL;
    if (!order || !loop_end || !cursor || !used || !s->own_pos || !s->own_idx) {
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "voxelize: out of memory (cone of %u edges)", ne);
        goto done;
    }
    memcpy(s->own_pos, m->positions, sizeof(float) * 3 * nv);
    memcpy(s->own_idx, m->indices, sizeof(uint32_t) * 3 * m->triangle_count);
    /* One fan per loop, to the mean of the loop's vertices: the cone stays
     * where the holes are (and the hierarchy, when used, sees local pieces). */
    const uint32_t loops = boundary_loops(edges, ne, order, loop_end, used, cursor);
    uint32_t t = m->triangle_count;
    for (uint32_t l = 0, b = 0; l < loops; b = loop_end[l++]) {
        double apex[3] = {0, 0, 0};
        for (uint32_t i = b; i < loop_end[l]; ++i)
            for (int k = 0; k < 3; ++k)
                apex[k] += m->positions[3 * (size_t)edges[2 * order[i]] + (size_t)k];
        const size_t av = nv + l;
        for (int k = 0; k < 3; ++k)
            s->own_pos[3 * av + (size_t)k] = (float)(apex[k] / (loop_end[l] - b));
        for (uint32_t i = b; i < loop_end[l]; ++i, ++t) { /* (b, a, apex) for edge a -> b */
            s->own_idx[3 * (size_t)t] = edges[2 * order[i] + 1];
            s->own_idx[3 * (size_t)t + 1] = edges[2 * order[i]];
            s->own_idx[3 * (size_t)t + 2] = (uint32_t)av;
        }
    }
    s->pos = s->own_pos;
    s->idx = s->own_idx;
    s->count = (uint32_t)nt;
    if (ne > MESO_VOXELIZE_CONE_DIRECT) {
        const meso_mesh cone = {.vertex_count = (uint32_t)(nv + loops),
                                .triangle_count = ne,
                                .positions = s->own_pos,
                                .indices = s->own_idx + 3 * (size_t)m->triangle_count};
        r = meso_winding_build(&cone, threads, &s->cone_tree, err);
    }
done:
    free(order);
    free(loop_end);
    free(cursor);
    free(used);
    free(edges);
    if (r != MESO_OK)
        mesoi_soup_free(s);
    return r;
}

/* w_C(q*): the cone's winding number. Next to a cone triangle's interior
 * (|term| near 1/2) the term's sign is the exact perturbed side, so that it
 * flips exactly where the crossing count X does. */
double mesoi_cone_winding(const mesoi_soup* s, const double q[3], uint64_t* exact)
{
    if (s->cone_tree)
        return meso_winding_query(s->cone_tree, q);
    double w = 0.0;
    for (uint32_t t = s->surface; t < s->count; ++t) {
        double v[3][3];
        for (int c = 0; c < 3; ++c)
            corner(s, t, c, v[c]);
        double wt = meso_winding_triangle(v[0], v[1], v[2], q);
        if (fabs(wt) > 0.5 - 1e-7) {
            const int side = mesoi_side3(v[0], v[1], v[2], q, exact);
            wt = side > 0 ? fabs(wt) : side < 0 ? -fabs(wt) : 0.0;
        }
        w += wt;
    }
    return w;
}
