/*
 * voxelize.c — sparse inside/outside voxelization by exact ray crossings
 * along x, per tile row. See voxelize.h for the method, the perturbation
 * and the two paths.
 */
#include "meso_clock.h"
#include "voxelize.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bake_threads.h"
#include "winding_number.h"

/* The error-free transformations below need every operation rounded on its
 * own: no fused multiply-add. GCC does not contract in ISO C mode (c_std =
 * c11); clang honours the pragma. */
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#endif

#define FOUR_PI 12.566370614359172953850573533118

/* >>exact predicates -----------------------------------------------------------
 * Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust
 * Geometric Predicates" (1997): the static filters of orient2d / orient3d
 * (ccwerrboundA, o3derrboundA) and, when they cannot decide, the exact
 * determinant as a nonoverlapping expansion (grow / scale with zero
 * elimination; products by Dekker splitting). Non-adaptive: the exact branch
 * is rare (counted in stats.exact_predicates), so it favours brevity. */

#define EPS 0x1p-53
#define SPLITTER 134217729.0 /* 2^27 + 1 */
static const double ccw_bound = (3.0 + 16.0 * EPS) * EPS;
static const double o3d_bound = (7.0 + 56.0 * EPS) * EPS;

static void two_sum(double a, double b, double* x, double* y)
{
    const double s = a + b, bv = s - a, av = s - bv;
    *x = s;
    *y = (a - av) + (b - bv);
}

static void two_diff(double a, double b, double e[2]) /* e = {low, high}: a - b exactly */
{
    const double s = a - b, bv = a - s, av = s + bv;
    e[1] = s;
    e[0] = (a - av) + (bv - b);
}

static void split(double a, double* hi, double* lo)
{
    const double c = SPLITTER * a, big = c - a;
    *hi = c - big;
    *lo = a - *hi;
}

static void two_product_presplit(double a, double b, double bhi, double blo, double* x, double* y)
{
    double ahi, alo;
    *x = a * b;
    split(a, &ahi, &alo);
    const double e1 = *x - ahi * bhi, e2 = e1 - alo * bhi, e3 = e2 - ahi * blo;
    *y = alo * blo - e3;
}

/* h = e + b; h may be e. Returns the length of h. */
static int grow(int n, const double* e, double b, double* h)
{
    double q = b;
    int m = 0;
    for (int i = 0; i < n; ++i) {
        double s, t;
        two_sum(q, e[i], &s, &t);
        if (t != 0.0)
            h[m++] = t;
        q = s;
    }
    if (q != 0.0 || m == 0)
        h[m++] = q;
    return m;
}

/* h = e * b (h must not be e). */
static int scale(int n, const double* e, double b, double* h)
{
    double bhi, blo, q, hh;
    split(b, &bhi, &blo);
    int m = 0;
    two_product_presplit(e[0], b, bhi, blo, &q, &hh);
    if (hh != 0.0)
        h[m++] = hh;
    for (int i = 1; i < n; ++i) {
        double p1, p0, s;
        two_product_presplit(e[i], b, bhi, blo, &p1, &p0);
        two_sum(q, p0, &s, &hh);
        if (hh != 0.0)
            h[m++] = hh;
        q = p1 + s; /* fast two-sum: |p1| >= |s| */
        hh = s - (q - p1);
        if (hh != 0.0)
            h[m++] = hh;
    }
    if (q != 0.0 || m == 0)
        h[m++] = q;
    return m;
}

/* h = e * f, f of length <= 2 (every factor here is a difference). */
static int mul2(int n, const double* e, const double f[2], double* h)
{
    double t[512];
    int m = scale(n, e, f[1], h);
    if (f[0] != 0.0) {
        const int k = scale(n, e, f[0], t);
        for (int i = 0; i < k; ++i)
            m = grow(m, h, t[i], h);
    }
    return m;
}

/* h = e - f. */
static int sub(int n, const double* e, int k, const double* f, double* h)
{
    memcpy(h, e, sizeof(double) * (size_t)n);
    for (int i = 0; i < k; ++i)
        n = grow(n, h, -f[i], h);
    return n;
}

static int sgn(double v)
{
    return (v > 0.0) - (v < 0.0);
}

/* Sign of (a - c) x (b - c) in the coordinates (u, v) = (p[U], p[V]). */
static int orient2d_exact(double au, double av, double bu, double bv, double cu, double cv)
{
    double acu[2], bcv[2], acv[2], bcu[2], l[8], r[8], d[16];
    two_diff(au, cu, acu);
    two_diff(bv, cv, bcv);
    two_diff(av, cv, acv);
    two_diff(bu, cu, bcu);
    const int nl = mul2(2, acu, bcv, l), nr = mul2(2, acv, bcu, r);
    const int nd = sub(nl, l, nr, r, d);
    return sgn(d[nd - 1]);
}

static int orient2d(double au, double av, double bu, double bv, double cu, double cv, uint64_t* exact)
{
    const double dl = (au - cu) * (bv - cv), dr = (av - cv) * (bu - cu), det = dl - dr;
    double sum;
    if (dl > 0.0) {
        if (dr <= 0.0)
            return sgn(det);
        sum = dl + dr;
    } else if (dl < 0.0) {
        if (dr >= 0.0)
            return sgn(det);
        sum = -dl - dr;
    } else {
        return sgn(det);
    }
    const double bound = ccw_bound * sum;
    if (det >= bound || -det >= bound)
        return sgn(det);
    ++*exact;
    return orient2d_exact(au, av, bu, bv, cu, cv);
}

/* Sign of det[a - d; b - d; c - d] (Shewchuk's orient3d: positive when d is
 * behind the plane of a, b, c as seen with a, b, c counter-clockwise). */
static int orient3d_exact(const double* a, const double* b, const double* c, const double* d)
{
    double A[3][2], B[3][2], C[3][2];
    for (int k = 0; k < 3; ++k) {
        two_diff(a[k], d[k], A[k]);
        two_diff(b[k], d[k], B[k]);
        two_diff(c[k], d[k], C[k]);
    }
    double acc[256], p[8], q[8], minor[16], term[64];
    int n = 0;
    for (int k = 0; k < 3; ++k) { /* A_k (B_k1 C_k2 - B_k2 C_k1), (k, k1, k2) cyclic */
        const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
        const int np = mul2(2, B[k1], C[k2], p), nq = mul2(2, B[k2], C[k1], q);
        const int nm = sub(np, p, nq, q, minor);
        const int nt = mul2(nm, minor, A[k], term);
        for (int i = 0; i < nt; ++i)
            n = grow(n, acc, term[i], acc);
    }
    return sgn(acc[n - 1]);
}

static int orient3d(const double* a, const double* b, const double* c, const double* d, uint64_t* exact)
{
    const double adx = a[0] - d[0], bdx = b[0] - d[0], cdx = c[0] - d[0];
    const double ady = a[1] - d[1], bdy = b[1] - d[1], cdy = c[1] - d[1];
    const double adz = a[2] - d[2], bdz = b[2] - d[2], cdz = c[2] - d[2];
    const double bc = bdx * cdy, cb = cdx * bdy, ca = cdx * ady, ac = adx * cdy, ab = adx * bdy, ba = bdx * ady;
    const double det = adz * (bc - cb) + bdz * (ca - ac) + cdz * (ab - ba);
    const double perm =
        (fabs(bc) + fabs(cb)) * fabs(adz) + (fabs(ca) + fabs(ac)) * fabs(bdz) + (fabs(ab) + fabs(ba)) * fabs(cdz);
    const double bound = o3d_bound * perm;
    if (det > bound || -det > bound)
        return sgn(det);
    ++*exact;
    return orient3d_exact(a, b, c, d);
}

/* >>perturbed predicates ---------------------------------------------------------
 * The query q* = q + (delta, eps, eps^2) of voxelize.h. */

/* Side of q* against the projected edge a -> b in the (y, z) plane:
 * orient2d(a, b, q*) = orient2d(a, b, q) + eps (a_z - b_z) + eps^2 (b_y - a_y). */
static int edge_side(const double* a, const double* b, const double* q, uint64_t* exact)
{
    const int s = orient2d(a[1], a[2], b[1], b[2], q[1], q[2], exact);
    if (s)
        return s;
    if (a[2] != b[2])
        return a[2] > b[2] ? 1 : -1;
    return b[1] > a[1] ? 1 : b[1] < a[1] ? -1 : 0;
}

/* Sign of orient3d(a, b, c, q*) = n.(a - q*) with n = (b - a) x (c - a):
 * orient3d(a, b, c, q) - delta n_x - eps n_y - eps^2 n_z. 0 only when the
 * triangle is degenerate. */
static int side3(const double* a, const double* b, const double* c, const double* q, uint64_t* exact)
{
    const int s = orient3d(a, b, c, q, exact);
    if (s)
        return s;
    static const int uv[3][2] = {{1, 2}, {2, 0}, {0, 1}}; /* n_x, n_y, n_z as 2D orientations */
    for (int k = 0; k < 3; ++k) {
        const int u = uv[k][0], v = uv[k][1];
        const int nk = orient2d(a[u], a[v], b[u], b[v], c[u], c[v], exact);
        if (nk)
            return -nk;
    }
    return 0;
}

/* >>triangle soup ----------------------------------------------------------------
 * The mesh's triangles, then (WINDING) the closing cone: one triangle
 * (b, a, apex) per chain-boundary edge a -> b, as often as its multiplicity. */
typedef struct soup {
    const float* pos;     /* 3 per vertex */
    const uint32_t* idx;  /* 3 per triangle */
    uint32_t surface;     /* triangles 0 .. surface - 1 are the mesh's */
    uint32_t count;       /* all triangles */
    float* own_pos;       /* positions + apex, when there is a cone */
    uint32_t* own_idx;
    meso_winding* cone_tree; /* more than MESO_VOXELIZE_CONE_DIRECT cone triangles */
} soup;

static void soup_free(soup* s)
{
    free(s->own_pos);
    free(s->own_idx);
    meso_winding_free(s->cone_tree);
    memset(s, 0, sizeof(*s));
}

static void corner(const soup* s, uint32_t t, int c, double out[3])
{
    const float* p = s->pos + 3 * (size_t)s->idx[3 * (size_t)t + (size_t)c];
    out[0] = p[0];
    out[1] = p[1];
    out[2] = p[2];
}

static inline double dmin(double a, double b)
{
    return a < b ? a : b;
}

static inline double dmax(double a, double b)
{
    return a > b ? a : b;
}

static void tri_corners(const soup* s, uint32_t t, double v[3][3], double lo[3], double hi[3])
{
    for (int c = 0; c < 3; ++c)
        corner(s, t, c, v[c]);
    for (int k = 0; k < 3; ++k) {
        lo[k] = dmin(v[0][k], dmin(v[1][k], v[2][k]));
        hi[k] = dmax(v[0][k], dmax(v[1][k], v[2][k]));
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

static meso_result soup_build(const meso_mesh* m, meso_voxelizer* method, int threads, soup* s, meso_error* err)
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
        soup_free(s);
    return r;
}

/* w_C(q*): the cone's winding number. Next to a cone triangle's interior
 * (|term| near 1/2) the term's sign is the exact perturbed side, so that it
 * flips exactly where the crossing count X does. */
static double cone_winding(const soup* s, const double q[3], uint64_t* exact)
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
            const int side = side3(v[0], v[1], v[2], q, exact);
            wt = side > 0 ? fabs(wt) : side < 0 ? -fabs(wt) : 0.0;
        }
        w += wt;
    }
    return w;
}

/* >>triangle-box overlap ---------------------------------------------------------
 * Separating axes (Akenine-Moeller, "Fast 3D Triangle-Box Overlap Testing",
 * 2001): the box's three axes, the triangle's normal, and the nine edge x
 * box-axis products. Callers grow the box, so rounding can only add overlaps. */
static int tri_box(const double centre[3], const double half[3], const double* tv /* 3 corners */)
{
    double v[3][3], e[3][3];
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k)
            v[c][k] = tv[3 * c + k] - centre[k];
    for (int k = 0; k < 3; ++k) {
        if (dmin(v[0][k], dmin(v[1][k], v[2][k])) > half[k] || dmax(v[0][k], dmax(v[1][k], v[2][k])) < -half[k])
            return 0;
        for (int c = 0; c < 3; ++c)
            e[c][k] = v[(c + 1) % 3][k] - v[c][k];
    }
    const double n[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                         e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    const double rn = half[0] * fabs(n[0]) + half[1] * fabs(n[1]) + half[2] * fabs(n[2]);
    if (fabs(n[0] * v[0][0] + n[1] * v[0][1] + n[2] * v[0][2]) > rn)
        return 0;
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) { /* axis = unit_k x e_c */
            double ax[3] = {0, 0, 0};
            const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
            ax[k1] = -e[c][k2];
            ax[k2] = e[c][k1];
            double lo = INFINITY, hi = -INFINITY;
            for (int j = 0; j < 3; ++j) {
                const double p = ax[0] * v[j][0] + ax[1] * v[j][1] + ax[2] * v[j][2];
                lo = dmin(lo, p);
                hi = dmax(hi, p);
            }
            const double r = half[0] * fabs(ax[0]) + half[1] * fabs(ax[1]) + half[2] * fabs(ax[2]);
            if (lo > r || hi < -r)
                return 0;
        }
    return 1;
}

int meso_triangle_box_overlap(const double centre[3], const double half[3], const double tv[9])
{
    return tri_box(centre, half, tv);
}

/* >>grid ---------------------------------------------------------------------- */

typedef struct grid {
    double o[3], h, tile;   /* origin, voxel size, tile edge R h */
    uint32_t R, T[3], N[3];
    double margin;          /* growth of tile boxes for the overlap test */
} grid;

static double centre_coord(const grid* g, int axis, int64_t i)
{
    return g->o[axis] + ((double)i + 0.5) * g->h;
}

void meso_voxel_center(const meso_voxel_grid* g, uint32_t i, uint32_t j, uint32_t k, double out[3])
{
    out[0] = g->origin[0] + ((double)i + 0.5) * g->voxel_size;
    out[1] = g->origin[1] + ((double)j + 0.5) * g->voxel_size;
    out[2] = g->origin[2] + ((double)k + 0.5) * g->voxel_size;
}

/* Tiles whose closed (grown) box along `axis` can meet [lo, hi], clamped to
 * the grid; returns 0 when none. */
static int tile_span(const grid* g, int axis, double lo, double hi, uint32_t* t0, uint32_t* t1)
{
    const double a = floor((lo - g->o[axis]) / g->tile - 1e-6), b = floor((hi - g->o[axis]) / g->tile + 1e-6);
    if (b < 0 || a >= g->T[axis] || !(a <= b))
        return 0;
    *t0 = a < 0 ? 0 : (uint32_t)a;
    *t1 = b >= g->T[axis] ? g->T[axis] - 1 : (uint32_t)b;
    return 1;
}

/* floor for |x| < 2^62 (libm's floor is a call without SSE4.1). */
static inline double ffloor(double x)
{
    const double t = (double)(int64_t)x;
    return t > x ? t - 1.0 : t;
}

/* Voxel centres along `axis` within [lo, hi] (one more on each side), in
 * [first, last] clamped to [c0, c1]; returns 0 when none. */
static int centre_span(const grid* g, int axis, double lo, double hi, int64_t c0, int64_t c1, int64_t* i0,
                       int64_t* i1)
{
    double fa = (lo - g->o[axis]) / g->h, fb = (hi - g->o[axis]) / g->h;
    if (!(fa <= fb) || fb < (double)c0 - 2.0 || fa > (double)c1 + 2.0)
        return 0;
    fa = dmax(fa, (double)c0 - 4.0); /* keeps the conversions below in range */
    fb = dmin(fb, (double)c1 + 4.0);
    const double a = -ffloor(0.5 - fa) - 1, b = ffloor(fb - 0.5) + 1; /* ceil(fa - 1/2) - 1, floor(fb - 1/2) + 1 */
    if (!(a <= b) || b < (double)c0 || a > (double)c1)
        return 0;
    *i0 = a < (double)c0 ? c0 : (int64_t)a;
    *i1 = b > (double)c1 ? c1 : (int64_t)b;
    return 1;
}

uint64_t meso_voxel_tile_words(uint32_t tile_res)
{
    const uint64_t r = tile_res;
    return (r * r * r + 63) / 64;
}

const char* meso_voxelizer_name(meso_voxelizer v)
{
    switch (v) {
    case MESO_VOXELIZE_AUTO: return "auto";
    case MESO_VOXELIZE_PARITY: return "parity";
    case MESO_VOXELIZE_WINDING: return "winding";
    default: return "?";
    }
}

static meso_result check_grid(const meso_voxel_grid* vg, grid* g, meso_error* err)
{
    if (!(vg->voxel_size > 0.0) || !isfinite(vg->voxel_size) || vg->tile_res < 1 ||
        vg->tile_res > MESO_VOXELIZE_MAX_TILE_RES)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_GRID,
                              "voxelize: voxel size %g or tile resolution %u out of range (1..%u)", vg->voxel_size,
                              vg->tile_res, MESO_VOXELIZE_MAX_TILE_RES);
    memset(g, 0, sizeof(*g));
    g->R = vg->tile_res;
    g->h = vg->voxel_size;
    g->tile = g->h * g->R;
    double extent = 0.0;
    for (int a = 0; a < 3; ++a) {
        if (vg->tiles[a] < 1 || (uint64_t)vg->tiles[a] * vg->tile_res > MESO_VOXELIZE_MAX_RES ||
            !isfinite(vg->origin[a]))
            return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_GRID,
                                  "voxelize: %u tiles of %u voxels along axis %d: more than %u voxels (or a "
                                  "non-finite origin)",
                                  vg->tiles[a], vg->tile_res, a, MESO_VOXELIZE_MAX_RES);
        g->o[a] = vg->origin[a];
        g->T[a] = vg->tiles[a];
        g->N[a] = vg->tiles[a] * vg->tile_res;
        extent = dmax(extent, fabs(g->o[a]) + g->N[a] * g->h);
    }
    g->margin = 1e-6 * g->h + 1e-12 * extent;
    return MESO_OK;
}

meso_result meso_voxel_grid_fit(const meso_mesh* m, uint32_t tiles, uint32_t tile_res, double pad,
                                meso_voxel_grid* out, meso_error* err)
{
    if (!m || !out || !m->positions || m->vertex_count == 0)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_GRID, "voxel grid: no mesh");
    memset(out, 0, sizeof(*out));
    const uint64_t n = (uint64_t)tiles * tile_res;
    if (tiles < 1 || tile_res < 1 || tile_res > MESO_VOXELIZE_MAX_TILE_RES || n > MESO_VOXELIZE_MAX_RES ||
        !(pad >= 0.0) || !(2.0 * pad < (double)n))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_GRID,
                              "voxel grid: %u tiles x %u voxels with %g voxels of padding: out of range (at most "
                              "%u voxels per axis)",
                              tiles, tile_res, pad, MESO_VOXELIZE_MAX_RES);
    double lo[3], hi[3];
    (void)meso_mesh_bounds(m, lo, hi);
    const double ext = dmax(hi[0] - lo[0], dmax(hi[1] - lo[1], hi[2] - lo[2]));
    if (!(ext > 0.0) || !isfinite(ext))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_GRID,
                              "voxel grid: the mesh's bounding box is empty or not finite");
    out->voxel_size = ext / ((double)n - 2.0 * pad);
    out->tile_res = tile_res;
    for (int a = 0; a < 3; ++a) {
        out->tiles[a] = tiles;
        out->origin[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * (double)n * out->voxel_size;
    }
    return MESO_OK;
}

/* >>rows ------------------------------------------------------------------------ */

typedef struct xing {
    uint32_t k;  /* centres 0 .. k-1 of the row see this crossing ahead of them */
    int32_t s;   /* +1 leaving through a triangle facing +x, -1 entering */
} xing;

/* A triangle of the current tile row, unpacked once. */
typedef struct ltri {
    double v[3][3];
    double lo[3], hi[3];
} ltri;

typedef struct counters {
    uint64_t rows, crossings, exact, evaluated, candidates;
} counters;

/* Per-thread working memory, grown as needed. */
typedef struct scratch {
    xing* xs;
    size_t xs_cap;
    ltri* lt;          /* the row's triangles */
    size_t lt_cap;
    uint32_t* bstart;  /* R^2 + 1 */
    uint32_t* bucket;
    size_t bucket_cap;
    uint8_t* cand;     /* T0: bits 1 mesh triangle meets the tile, 2 WINDING bound undecided, 4 cone meets it */
    uint32_t* ctx;     /* T0: candidate tiles' tx */
    double* twc;       /* T0: WINDING, per candidate: w_C at its centre (NaN where the cone meets it) */
    double* tspread;   /* T0: and the bound on its variation over the tile */
    counters n;
    int oom;
} scratch;

typedef struct row_out {
    uint8_t* classes;  /* T0 */
    uint32_t mixed_count;
    uint32_t* mixed_tx;
    uint64_t* bits;
} row_out;

typedef struct job {
    const grid* g;
    const soup* s;
    meso_voxelizer method;
    const uint32_t* list; /* the tile row's triangles */
    uint32_t list_count;
    uint32_t ty, tz;
    /* WINDING bound */
    const float (*bedge)[6]; /* chain-boundary edges: from, to */
    uint32_t bedge_count;
} job;

static int grow_buf(void** p, size_t* cap, size_t need, size_t elem)
{
    if (need <= *cap)
        return 1;
    size_t c = *cap ? *cap : 64;
    while (c < need)
        c *= 2;
    void* q = realloc(*p, c * elem);
    if (!q)
        return 0;
    *p = q;
    *cap = c;
    return 1;
}

static int cmp_xing(const void* pa, const void* pb)
{
    const xing *a = pa, *b = pb;
    return a->k < b->k ? -1 : a->k > b->k;
}

/* Crossings of the ray from centre row (j, k) with the row's triangles
 * sc->lt[items[0..n)] (items NULL: the first n), sorted by k. Returns the
 * count, or -1 when out of memory. */
static long trace(const job* jb, scratch* sc, uint32_t j, uint32_t k, const uint32_t* items, uint32_t n)
{
    const grid* g = jb->g;
    const int64_t N0 = g->N[0];
    double q[3] = {centre_coord(g, 0, 0), centre_coord(g, 1, j), centre_coord(g, 2, k)};
    size_t m = 0;
    uint64_t* ex = &sc->n.exact;
    for (uint32_t i = 0; i < n; ++i) {
        const ltri* t = &sc->lt[items ? items[i] : i];
        const double(*v)[3] = t->v;
        const double *lo = t->lo, *hi = t->hi;
        if (q[1] < lo[1] || q[1] > hi[1] || q[2] < lo[2] || q[2] > hi[2])
            continue;
        const int e0 = edge_side(v[0], v[1], q, ex);
        if (!e0 || edge_side(v[1], v[2], q, ex) != e0 || edge_side(v[2], v[0], q, ex) != e0)
            continue;
        /* Centres strictly before the crossing see it: cross(i) <=> e0 side3(q_i*) > 0, which is
         * true for i < K and false from K on. Search K in the centres the triangle's x-extent
         * leaves open, starting from the rounded crossing point. */
        int64_t a, b;
        if (!centre_span(g, 0, lo[0], hi[0], 0, N0 - 1, &a, &b)) {
            a = b = hi[0] < g->o[0] + 0.5 * g->h ? 0 : N0; /* wholly before or after the row's centres */
        } else {
            b += 1; /* K in [a, b] */
        }
        const double nx = (v[1][1] - v[0][1]) * (v[2][2] - v[0][2]) - (v[1][2] - v[0][2]) * (v[2][1] - v[0][1]);
        const double ny = (v[1][2] - v[0][2]) * (v[2][0] - v[0][0]) - (v[1][0] - v[0][0]) * (v[2][2] - v[0][2]);
        const double nz = (v[1][0] - v[0][0]) * (v[2][1] - v[0][1]) - (v[1][1] - v[0][1]) * (v[2][0] - v[0][0]);
        const double xi = v[0][0] - (ny * (q[1] - v[0][1]) + nz * (q[2] - v[0][2])) / nx;
        int64_t guess = (int64_t)a;
        if (isfinite(xi)) {
            const double f = -ffloor(0.5 - (xi - g->o[0]) / g->h); /* ceil(. - 1/2) */
            guess = f < (double)a ? a : f > (double)b ? b : (int64_t)f;
        }
        /* invariant: cross(i) for i < lo_k, !cross(i) for i >= hi_k. The first two probes are
         * the guess and its neighbour (usually settling K), then bisection. */
        int64_t lo_k = a, hi_k = b, probe = guess;
        for (int step = 0; lo_k < hi_k; ++step) {
            if (step >= 2 || probe < lo_k || probe >= hi_k)
                probe = lo_k + (hi_k - lo_k) / 2;
            q[0] = centre_coord(g, 0, probe);
            if (e0 * side3(v[0], v[1], v[2], q, ex) > 0) {
                lo_k = probe + 1;
                probe = probe + 1;
            } else {
                hi_k = probe;
                probe = probe - 1;
            }
        }
        if (!grow_buf((void**)&sc->xs, &sc->xs_cap, m + 1, sizeof(xing)))
            return -1;
        sc->xs[m++] = (xing){(uint32_t)lo_k, e0};
    }
    if (m > 16) {
        qsort(sc->xs, m, sizeof(xing), cmp_xing);
    } else {
        for (size_t a = 1; a < m; ++a) /* usually a handful */
            for (size_t b = a; b > 0 && sc->xs[b - 1].k > sc->xs[b].k; --b) {
                const xing t = sc->xs[b];
                sc->xs[b] = sc->xs[b - 1];
                sc->xs[b - 1] = t;
            }
    }
    sc->n.rows++;
    sc->n.crossings += m;
    return (long)m;
}

/* X at centre i of a traced row: sum of s over crossings with k > i. */
static long crossings_ahead(const xing* xs, long n, int64_t i)
{
    long x = 0;
    for (long t = 0; t < n; ++t)
        x += xs[t].k > (uint64_t)i ? xs[t].s : 0;
    return x;
}

/* WINDING: |grad w| bound over a box (Biot-Savart of the chain boundary). */
static double gradient_bound(const job* jb, const double lo[3], const double hi[3])
{
    double G = 0.0;
    for (uint32_t e = 0; e < jb->bedge_count; ++e) {
        const float* p = jb->bedge[e];
        double d2 = 0.0, len2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double a = dmin(p[k], p[3 + k]), b = dmax(p[k], p[3 + k]);
            const double gap = dmax(0.0, dmax(a - hi[k], lo[k] - b));
            d2 += gap * gap;
            len2 += (b - a) * (b - a);
        }
        if (!(d2 > 0.0))
            return INFINITY;
        G += sqrt(len2) / (FOUR_PI * d2);
    }
    return G;
}

/* WINDING: w at centre (i, j, k) = X - w_C, and the bound G rho + margin on
 * |w(q) - w(centre)| over the centres of tiles [t0, t1) of the job's row (a
 * box where w is harmonic: no mesh triangle meets it). */
static double winding_at(const job* jb, scratch* sc, long X, int64_t i, uint32_t j, uint32_t k, uint32_t t0,
                         uint32_t t1, double* spread)
{
    const grid* g = jb->g;
    const uint32_t R = g->R;
    const double q[3] = {centre_coord(g, 0, i), centre_coord(g, 1, j), centre_coord(g, 2, k)};
    const double lo[3] = {centre_coord(g, 0, (int64_t)t0 * R), centre_coord(g, 1, (int64_t)jb->ty * R),
                          centre_coord(g, 2, (int64_t)jb->tz * R)};
    const double hi[3] = {centre_coord(g, 0, (int64_t)t1 * R - 1), centre_coord(g, 1, (int64_t)jb->ty * R + R - 1),
                          centre_coord(g, 2, (int64_t)jb->tz * R + R - 1)};
    double rho2 = 0.0;
    for (int a = 0; a < 3; ++a) {
        const double d = dmax(q[a] - lo[a], hi[a] - q[a]);
        rho2 += d * d;
    }
    *spread = gradient_bound(jb, lo, hi) * sqrt(rho2) + (jb->s->cone_tree ? 0.05 : 1e-9);
    return (double)X - cone_winding(jb->s, q, &sc->n.exact);
}

/* WINDING: decide tiles [t0, t1) of the row (no mesh triangle meets them)
 * from the representative row (j, k), or mark the undecidable ones
 * candidates (cand bit 2). */
static void certify(const job* jb, scratch* sc, const xing* xs, long nx, uint32_t j, uint32_t k, uint32_t t0,
                    uint32_t t1, uint8_t* classes)
{
    const int64_t i = ((int64_t)t0 + t1) * jb->g->R / 2;
    double spread;
    const double w = winding_at(jb, sc, crossings_ahead(xs, nx, i), i, j, k, t0, t1, &spread);
    if (fabs(w - MESO_WINDING_INSIDE) > spread) {
        for (uint32_t t = t0; t < t1; ++t)
            classes[t] = meso_winding_inside(w) ? MESO_TILE_INSIDE : MESO_TILE_OUTSIDE;
    } else if (t1 - t0 == 1) {
        sc->cand[t0] |= 2;
    } else {
        const uint32_t mid = t0 + (t1 - t0) / 2;
        certify(jb, sc, xs, nx, j, k, t0, mid, classes);
        certify(jb, sc, xs, nx, j, k, mid, t1, classes);
    }
}

/* Lists in CSR form are built in two passes: count into start[k + 1], then
 * (after csr_counted) fill at start[k]++, then csr_filled. */
static int csr_counted(uint32_t* start, uint64_t n, uint32_t** items, size_t* cap)
{
    for (uint64_t k = 0; k < n; ++k) {
        if (start[k + 1] > UINT32_MAX - start[k])
            return 0;
        start[k + 1] += start[k];
    }
    return grow_buf((void**)items, cap, (size_t)start[n] + 1, sizeof(uint32_t));
}

static void csr_filled(uint32_t* start, uint64_t n) /* the fill advanced each start to the next one's */
{
    memmove(start + 1, start, sizeof(uint32_t) * (size_t)n);
    start[0] = 0;
}

/* Bin the row's triangles into its R^2 voxel rows by their (y, z) bounds. */
static int bin_rows(const job* jb, scratch* sc)
{
    const grid* g = jb->g;
    const uint32_t R = g->R;
    const int64_t j0 = (int64_t)jb->ty * R, k0 = (int64_t)jb->tz * R;
    memset(sc->bstart, 0, sizeof(uint32_t) * ((size_t)R * R + 1));
    for (int pass = 0; pass < 2; ++pass) {
        for (uint32_t i = 0; i < jb->list_count; ++i) {
            const double *lo = sc->lt[i].lo, *hi = sc->lt[i].hi;
            int64_t a0, a1, b0, b1;
            if (!centre_span(g, 1, lo[1], hi[1], j0, j0 + R - 1, &a0, &a1) ||
                !centre_span(g, 2, lo[2], hi[2], k0, k0 + R - 1, &b0, &b1))
                continue;
            for (int64_t b = b0; b <= b1; ++b)
                for (int64_t a = a0; a <= a1; ++a) {
                    const size_t cell = (size_t)(a - j0) + (size_t)R * (size_t)(b - k0);
                    if (pass == 0)
                        sc->bstart[cell + 1]++;
                    else
                        sc->bucket[sc->bstart[cell]++] = i;
                }
        }
        if (pass == 0 && !csr_counted(sc->bstart, (uint64_t)R * R, &sc->bucket, &sc->bucket_cap))
            return 0;
    }
    csr_filled(sc->bstart, (uint64_t)R * R);
    return 1;
}

/* Set bits [from, to) of a bit array. */
static void set_bits(uint64_t* w, uint64_t from, uint64_t to)
{
    while (from < to) {
        const uint64_t word = from >> 6, lo = from & 63, hi = to - (word << 6) < 64 ? to - (word << 6) : 64;
        const uint64_t mask = (hi == 64 ? ~(uint64_t)0 : (((uint64_t)1 << hi) - 1)) & ~(((uint64_t)1 << lo) - 1);
        w[word] |= mask;
        from = (word << 6) + hi;
    }
}

/* One tile row: classes of its T0 tiles and bits of its MIXED ones. */
static void process_row(const job* jb, scratch* sc, row_out* out)
{
    const grid* g = jb->g;
    const soup* s = jb->s;
    const uint32_t R = g->R, T0 = g->T[0];
    const uint64_t words = meso_voxel_tile_words(R);
    memset(sc->cand, 0, T0);
    memset(out->classes, MESO_TILE_OUTSIDE, T0);
    out->mixed_count = 0;

    /* 1. Candidates: tiles whose grown box a mesh triangle meets (cand bit
     * 1); tiles a cone triangle meets (bit 4), where w_C jumps. */
    if (!grow_buf((void**)&sc->lt, &sc->lt_cap, (size_t)jb->list_count + 1, sizeof(ltri))) {
        sc->oom = 1;
        return;
    }
    for (uint32_t i = 0; i < jb->list_count; ++i)
        tri_corners(s, jb->list[i], sc->lt[i].v, sc->lt[i].lo, sc->lt[i].hi);
    const double half[3] = {0.5 * g->tile + g->margin, 0.5 * g->tile + g->margin, 0.5 * g->tile + g->margin};
    for (uint32_t i = 0; i < jb->list_count; ++i) {
        const uint8_t bit = jb->list[i] < s->surface ? 1 : 4;
        uint32_t a, b;
        if (!tile_span(g, 0, sc->lt[i].lo[0], sc->lt[i].hi[0], &a, &b))
            continue;
        for (uint32_t t = a; t <= b; ++t) {
            if (sc->cand[t] & bit)
                continue;
            const double ct[3] = {g->o[0] + (t + 0.5) * g->tile, g->o[1] + (jb->ty + 0.5) * g->tile,
                                  g->o[2] + (jb->tz + 0.5) * g->tile};
            if (tri_box(ct, half, &sc->lt[i].v[0][0]))
                sc->cand[t] |= bit;
        }
    }

    /* 2. The other tiles, from one representative row. */
    const uint32_t jr = jb->ty * R + R / 2, kr = jb->tz * R + R / 2;
    if (jb->list_count || jb->method == MESO_VOXELIZE_WINDING) {
        const long nx = trace(jb, sc, jr, kr, NULL, jb->list_count);
        if (nx < 0) {
            sc->oom = 1;
            return;
        }
        if (jb->method == MESO_VOXELIZE_PARITY) {
            for (uint32_t t = 0; t < T0; ++t)
                if (!(sc->cand[t] & 1))
                    out->classes[t] = (crossings_ahead(sc->xs, nx, (int64_t)t * R + R / 2) & 1) ? MESO_TILE_INSIDE
                                                                                              : MESO_TILE_OUTSIDE;
        } else {
            for (uint32_t t = 0; t < T0;) {
                if (sc->cand[t] & 1) {
                    ++t;
                    continue;
                }
                uint32_t e = t;
                while (e < T0 && !(sc->cand[e] & 1))
                    ++e;
                certify(jb, sc, sc->xs, nx, jr, kr, t, e, out->classes);
                t = e;
            }
        }
    }
    uint32_t nc = 0;
    for (uint32_t t = 0; t < T0; ++t)
        if (sc->cand[t] & 3)
            sc->ctx[nc++] = t;
    if (nc == 0)
        return;
    sc->n.candidates += nc;

    /* 3. Candidate tiles, centre by centre along every voxel row. X is
     * constant between crossings, so without a cone whole runs of bits are
     * set at once. With one, w = X - w_C; in a tile no cone triangle meets,
     * w_C is harmonic and within spread of its value at the tile's centre,
     * so a run is decided at once unless X - w_C(centre) is within spread of
     * 1/2; the rest (and tiles the cone meets) evaluate w_C centre by centre. */
    const int cone = s->count > s->surface;
    for (uint32_t c = 0; cone && c < nc; ++c) {
        const uint32_t t = sc->ctx[c];
        sc->twc[c] = NAN;
        sc->tspread[c] = 0.0;
        if (!(sc->cand[t] & 4))
            sc->twc[c] = -winding_at(jb, sc, 0, (int64_t)t * R + R / 2, jr, kr, t, t + 1, &sc->tspread[c]);
    }
    if (!bin_rows(jb, sc)) {
        sc->oom = 1;
        return;
    }
    out->mixed_tx = malloc(sizeof(uint32_t) * nc);
    out->bits = calloc(nc * words, sizeof(uint64_t));
    if (!out->mixed_tx || !out->bits) {
        sc->oom = 1;
        return;
    }
    for (uint32_t lz = 0; lz < R; ++lz)
        for (uint32_t ly = 0; ly < R; ++ly) {
            const uint32_t cell = ly + R * lz, j = jb->ty * R + ly, k = jb->tz * R + lz;
            const long n = trace(jb, sc, j, k, sc->bucket + sc->bstart[cell], sc->bstart[cell + 1] - sc->bstart[cell]);
            if (n < 0) {
                sc->oom = 1;
                return;
            }
            long ptr = 0, acc = 0;
            for (long t = 0; t < n; ++t)
                acc += sc->xs[t].s;
            for (uint32_t c = 0; c < nc; ++c) {
                const int64_t i0 = (int64_t)sc->ctx[c] * R, i1 = i0 + R;
                const uint64_t base = (uint64_t)R * cell; /* bit of (0, ly, lz) */
                uint64_t* bits = out->bits + c * words;
                while (ptr < n && sc->xs[ptr].k <= (uint64_t)i0)
                    acc -= sc->xs[ptr++].s;
                for (int64_t i = i0; i < i1;) { /* X = acc on [i, next) */
                    const int64_t next = ptr < n && sc->xs[ptr].k < (uint64_t)i1 ? (int64_t)sc->xs[ptr].k : i1;
                    const double v = cone ? (double)acc - sc->twc[c] : 0.0; /* w near the tile's centre */
                    if (!cone) {
                        if (jb->method == MESO_VOXELIZE_PARITY ? (acc & 1) : acc >= 1)
                            set_bits(bits, base + (uint64_t)(i - i0), base + (uint64_t)(next - i0));
                    } else if (fabs(v - MESO_WINDING_INSIDE) > sc->tspread[c]) { /* NaN (cone tile) is not */
                        if (v > MESO_WINDING_INSIDE)
                            set_bits(bits, base + (uint64_t)(i - i0), base + (uint64_t)(next - i0));
                    } else {
                        for (int64_t x = i; x < next; ++x) {
                            const double q[3] = {centre_coord(g, 0, x), centre_coord(g, 1, j), centre_coord(g, 2, k)};
                            if (meso_winding_inside((double)acc - cone_winding(s, q, &sc->n.exact)))
                                set_bits(bits, base + (uint64_t)(x - i0), base + (uint64_t)(x - i0) + 1);
                        }
                    }
                    i = next;
                    while (ptr < n && sc->xs[ptr].k <= (uint64_t)i)
                        acc -= sc->xs[ptr++].s;
                }
            }
        }
    sc->n.evaluated += (uint64_t)nc * R * R * R;

    /* 4. Candidates whose centres all agree are uniform; keep the others. */
    const uint64_t all = (uint64_t)R * R * R, tail = all % 64 ? ((uint64_t)1 << (all % 64)) - 1 : ~(uint64_t)0;
    for (uint32_t c = 0; c < nc; ++c) {
        const uint64_t* bits = out->bits + c * words;
        int zeros = bits[words - 1] == 0, ones = bits[words - 1] == tail;
        for (uint64_t w = 0; w + 1 < words && (zeros || ones); ++w) {
            zeros &= bits[w] == 0;
            ones &= bits[w] == ~(uint64_t)0;
        }
        const uint32_t t = sc->ctx[c];
        if (zeros || ones) {
            out->classes[t] = ones ? MESO_TILE_INSIDE : MESO_TILE_OUTSIDE;
            continue;
        }
        out->classes[t] = MESO_TILE_MIXED;
        if (out->mixed_count != c)
            memmove(out->bits + out->mixed_count * words, bits, words * sizeof(uint64_t));
        out->mixed_tx[out->mixed_count++] = t;
    }
}

/* >>driver ----------------------------------------------------------------------- */


static meso_result check_mesh(const meso_mesh* m, meso_error* err)
{
    if (m->triangle_count == 0 || m->vertex_count == 0 || !m->positions || !m->indices)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_MESH, "voxelize: the mesh is empty");
    if (m->vertex_count >= 0x7FFFFFFFu)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_MESH,
                              "voxelize: %u vertices: at most 2^31 - 2", m->vertex_count);
    for (size_t i = 0; i < 3 * (size_t)m->triangle_count; ++i)
        if (m->indices[i] >= m->vertex_count)
            return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_MESH,
                                  "voxelize: face %zu refers to vertex %u of %u", i / 3, m->indices[i],
                                  m->vertex_count);
    for (size_t i = 0; i < 3 * (size_t)m->vertex_count; ++i)
        if (!isfinite(m->positions[i]))
            return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_MESH,
                                  "voxelize: vertex %zu has a non-finite coordinate", i / 3);
    return MESO_OK;
}

/* Triangles per z-layer of tiles, as CSR: start[T2 + 1], items. */
static int bin_layers(const grid* g, const soup* s, uint32_t* start, uint32_t** items, size_t* cap)
{
    const uint32_t T = g->T[2];
    memset(start, 0, sizeof(uint32_t) * ((size_t)T + 1));
    for (int pass = 0; pass < 2; ++pass) {
        for (uint32_t t = 0; t < s->count; ++t) {
            double v[3][3], lo[3], hi[3];
            uint32_t a, b, c, d;
            tri_corners(s, t, v, lo, hi);
            if (!tile_span(g, 2, lo[2], hi[2], &a, &b) || !tile_span(g, 1, lo[1], hi[1], &c, &d))
                continue; /* outside the grid in z or y: no row of it meets the triangle */
            for (uint32_t k = a; k <= b; ++k) {
                if (pass == 0)
                    start[k + 1]++;
                else
                    (*items)[start[k]++] = t;
            }
        }
        if (pass == 0 && !csr_counted(start, T, items, cap))
            return 0;
    }
    csr_filled(start, T);
    return 1;
}

/* Triangles per tile row r = ty + T1 tz for rows [r0, r1), as CSR over
 * r - r0, from the layer lists. */
static int bin_rows_of_batch(const grid* g, const soup* s, const uint32_t* lstart, const uint32_t* litems,
                             uint64_t r0, uint64_t r1, uint32_t* start, uint32_t** items, size_t* cap)
{
    const uint32_t T1 = g->T[1];
    const uint64_t n = r1 - r0;
    memset(start, 0, sizeof(uint32_t) * ((size_t)n + 1));
    for (int pass = 0; pass < 2; ++pass) {
        for (uint32_t tz = (uint32_t)(r0 / T1); tz <= (uint32_t)((r1 - 1) / T1); ++tz)
            for (uint32_t i = lstart[tz]; i < lstart[tz + 1]; ++i) {
                double v[3][3], lo[3], hi[3];
                uint32_t a, b;
                tri_corners(s, litems[i], v, lo, hi);
                if (!tile_span(g, 1, lo[1], hi[1], &a, &b))
                    continue;
                for (uint32_t ty = a; ty <= b; ++ty) {
                    const uint64_t r = ty + (uint64_t)T1 * tz;
                    if (r < r0 || r >= r1)
                        continue;
                    if (pass == 0)
                        start[r - r0 + 1]++;
                    else
                        (*items)[start[r - r0]++] = litems[i];
                }
            }
        if (pass == 0 && !csr_counted(start, n, items, cap))
            return 0;
    }
    csr_filled(start, n);
    return 1;
}

/* Tile rows handed to the caller at once, in (tz, ty) order: as many as
 * keep the MIXED bits of a batch near BATCH_BITS_BYTES (assuming 4
 * candidate tiles per row) and its classes near BATCH_CLASS_BYTES, but at
 * least BATCH_PER_THREAD per thread. Few, long parallel regions matter on a
 * loaded machine: with more threads than free cores, an OpenMP barrier per
 * handful of rows made 2 threads 30x slower than 1 here. */
#define BATCH_PER_THREAD 4
#define BATCH_BITS_BYTES ((uint64_t)64 << 20)
#define BATCH_CLASS_BYTES ((uint64_t)16 << 20)

meso_result meso_voxelize_stream(const meso_mesh* m, const meso_voxel_grid* vg, meso_voxelizer method, int threads,
                                 meso_voxel_rows_fn fn, void* user, meso_voxelize_stats* stats, meso_error* err)
{
    const double t_start = meso_seconds();
    if (!m || !vg || !fn || method < 0 || method >= MESO_VOXELIZE_COUNT)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "voxelize: NULL or bad argument");
    grid g;
    meso_result r = check_grid(vg, &g, err);
    if (r == MESO_OK)
        r = check_mesh(m, err);
    if (r != MESO_OK)
        return r;
    const int nt = meso_bake_thread_count(threads);
    soup s;
    r = soup_build(m, &method, nt, &s, err);
    if (r != MESO_OK)
        return r;

    const uint32_t R = g.R, T0 = g.T[0], T1 = g.T[1], T2 = g.T[2];
    const uint64_t total_rows = (uint64_t)T1 * T2, words = meso_voxel_tile_words(R);
    uint64_t want = BATCH_BITS_BYTES / (4 * words * 8);
    if (want > BATCH_CLASS_BYTES / T0)
        want = BATCH_CLASS_BYTES / T0;
    if (want < (uint64_t)nt * BATCH_PER_THREAD)
        want = (uint64_t)nt * BATCH_PER_THREAD;
    const uint32_t batch = (uint32_t)(want < total_rows ? want : total_rows);
    uint32_t *lstart = malloc(sizeof(uint32_t) * ((size_t)T2 + 1)), *ystart = malloc(sizeof(uint32_t) * ((size_t)batch + 1));
    uint32_t *litems = NULL, *yitems = NULL;
    size_t lcap = 0, ycap = 0;
    float(*bedge)[6] = NULL;
    scratch* sc = calloc((size_t)nt, sizeof(scratch));
    row_out* outs = calloc(batch, sizeof(row_out));
    meso_voxel_row* rows = calloc(batch, sizeof(meso_voxel_row));
    int ok = lstart && ystart && sc && outs && rows;
    for (int t = 0; ok && t < nt; ++t) {
        sc[t].bstart = malloc(sizeof(uint32_t) * ((size_t)R * R + 1));
        sc[t].cand = malloc(T0);
        sc[t].ctx = malloc(sizeof(uint32_t) * T0);
        sc[t].twc = malloc(sizeof(double) * T0);
        sc[t].tspread = malloc(sizeof(double) * T0);
        ok = sc[t].bstart && sc[t].cand && sc[t].ctx && sc[t].twc && sc[t].tspread;
    }
    for (uint32_t b = 0; ok && b < batch; ++b)
        ok = (outs[b].classes = malloc(T0)) != NULL;
    const uint32_t ncone = s.count - s.surface;
    if (ok && ncone) {
        ok = (bedge = malloc(sizeof(*bedge) * ncone)) != NULL;
        for (uint32_t e = 0; ok && e < ncone; ++e) /* cone triangle (b, a, apex) of edge a -> b */
            for (int k = 0; k < 3; ++k) {
                bedge[e][k] = s.pos[3 * (size_t)s.idx[3 * ((size_t)s.surface + e) + 1] + (size_t)k];
                bedge[e][3 + k] = s.pos[3 * (size_t)s.idx[3 * ((size_t)s.surface + e)] + (size_t)k];
            }
    }
    if (ok)
        ok = bin_layers(&g, &s, lstart, &litems, &lcap);
    if (!ok)
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "voxelize: out of memory");

    meso_voxelize_stats st = {0};
    st.method = method;
    st.voxels = (uint64_t)g.N[0] * g.N[1] * g.N[2];
    st.tiles = (uint64_t)T0 * T1 * T2;
    st.boundary_edges = st.cone_triangles = ncone;
    for (uint64_t r0 = 0; r == MESO_OK && r0 < total_rows; r0 += batch) {
        const uint32_t nb = (uint32_t)(total_rows - r0 < batch ? total_rows - r0 : batch);
        if (!bin_rows_of_batch(&g, &s, lstart, litems, r0, r0 + nb, ystart, &yitems, &ycap)) {
            r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "voxelize: out of memory");
            break;
        }
        int oom = 0;
#ifdef _OPENMP
#pragma omp parallel for schedule(dynamic, 1) num_threads(nt) reduction(| : oom)
#endif
        for (long b = 0; b < (long)nb; ++b) {
#ifdef _OPENMP
            scratch* mine = &sc[omp_get_thread_num()];
#else
            scratch* mine = &sc[0];
#endif
            const uint64_t row = r0 + (uint64_t)b;
            const job jb = {.g = &g,
                            .s = &s,
                            .method = method,
                            .list = yitems + ystart[b],
                            .list_count = ystart[b + 1] - ystart[b],
                            .ty = (uint32_t)(row % T1),
                            .tz = (uint32_t)(row / T1),
                            .bedge = (const float(*)[6])bedge,
                            .bedge_count = ncone};
            mine->oom = 0;
            process_row(&jb, mine, &outs[b]);
            oom |= mine->oom;
        }
        if (oom) {
            r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "voxelize: out of memory (tile row)");
        } else {
            for (uint32_t b = 0; b < nb; ++b) {
                const uint64_t row = r0 + b;
                rows[b] = (meso_voxel_row){(uint32_t)(row % T1), (uint32_t)(row / T1), outs[b].classes,
                                           outs[b].mixed_count, outs[b].mixed_tx, outs[b].bits};
                for (uint32_t t = 0; t < T0; ++t) {
                    st.tiles_outside += outs[b].classes[t] == MESO_TILE_OUTSIDE;
                    st.tiles_inside += outs[b].classes[t] == MESO_TILE_INSIDE;
                    st.tiles_mixed += outs[b].classes[t] == MESO_TILE_MIXED;
                }
            }
            const meso_result rf = fn(user, rows, nb, err);
            if (rf != MESO_OK) {
                if (err)
                    err->code = MESO_VOXELIZE_ISSUE_STOPPED;
                r = rf;
            }
        }
        for (uint32_t b = 0; b < nb; ++b) {
            free(outs[b].mixed_tx);
            free(outs[b].bits);
            outs[b].mixed_tx = NULL;
            outs[b].bits = NULL;
        }
    }
    for (int t = 0; sc && t < nt; ++t) {
        st.rows += sc[t].n.rows;
        st.crossings += sc[t].n.crossings;
        st.exact_predicates += sc[t].n.exact;
        st.voxels_evaluated += sc[t].n.evaluated;
        st.tiles_candidate += sc[t].n.candidates;
        free(sc[t].xs);
        free(sc[t].lt);
        free(sc[t].bstart);
        free(sc[t].bucket);
        free(sc[t].cand);
        free(sc[t].ctx);
        free(sc[t].twc);
        free(sc[t].tspread);
    }
    for (uint32_t b = 0; outs && b < batch; ++b)
        free(outs[b].classes);
    free(sc);
    free(outs);
    free(rows);
    free(lstart);
    free(ystart);
    free(litems);
    free(yitems);
    free(bedge);
    soup_free(&s);
    st.seconds = meso_seconds() - t_start;
    if (stats)
        *stats = st;
    return r;
}

/* >>stored result ------------------------------------------------------------------ */

typedef struct store {
    meso_voxels* v;
    uint64_t cap;
} store;

static meso_result store_rows(void* user, const meso_voxel_row* rows, uint32_t n, meso_error* err)
{
    store* st = user;
    meso_voxels* v = st->v;
    const uint32_t T0 = v->grid.tiles[0], T1 = v->grid.tiles[1];
    for (uint32_t r = 0; r < n; ++r) {
        const meso_voxel_row* row = &rows[r];
        const uint64_t base = (uint64_t)T0 * (row->ty + (uint64_t)T1 * row->tz);
        memcpy(v->tile_class + base, row->classes, T0);
        if (v->mixed_count + row->mixed_count > st->cap) {
            uint64_t c = st->cap ? st->cap : 64;
            while (c < v->mixed_count + row->mixed_count)
                c *= 2;
            uint64_t* ids = realloc(v->mixed_tiles, c * sizeof(uint64_t));
            if (ids)
                v->mixed_tiles = ids;
            uint64_t* bits = ids ? realloc(v->bits, c * v->tile_words * sizeof(uint64_t)) : NULL;
            if (!bits)
                return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "voxelize: out of memory (%llu mixed tiles)",
                                      (unsigned long long)c);
            v->bits = bits;
            st->cap = c;
        }
        if (!row->mixed_count)
            continue;
        for (uint32_t i = 0; i < row->mixed_count; ++i)
            v->mixed_tiles[v->mixed_count + i] = base + row->mixed_tx[i];
        memcpy(v->bits + v->mixed_count * v->tile_words, row->bits,
               (size_t)row->mixed_count * v->tile_words * sizeof(uint64_t));
        v->mixed_count += row->mixed_count;
    }
    return MESO_OK;
}

meso_result meso_voxelize(const meso_mesh* m, const meso_voxel_grid* g, meso_voxelizer method, int threads,
                          meso_voxels* out, meso_error* err)
{
    if (!out || !g)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "voxelize: NULL argument");
    memset(out, 0, sizeof(*out));
    grid gi;
    meso_result r = check_grid(g, &gi, err);
    if (r != MESO_OK)
        return r;
    out->grid = *g;
    out->tile_words = meso_voxel_tile_words(g->tile_res);
    const uint64_t tiles = (uint64_t)g->tiles[0] * g->tiles[1] * g->tiles[2];
    out->tile_class = malloc(tiles);
    if (!out->tile_class)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "voxelize: out of memory (%llu tiles)",
                              (unsigned long long)tiles);
    store st = {out, 0};
    r = meso_voxelize_stream(m, g, method, threads, store_rows, &st, &out->stats, err);
    if (r != MESO_OK)
        meso_voxels_free(out);
    return r;
}

meso_tile_class meso_voxels_tile(const meso_voxels* v, uint32_t tx, uint32_t ty, uint32_t tz)
{
    return (meso_tile_class)
        v->tile_class[tx + (uint64_t)v->grid.tiles[0] * (ty + (uint64_t)v->grid.tiles[1] * tz)];
}

const uint64_t* meso_voxels_tile_bits(const meso_voxels* v, uint32_t tx, uint32_t ty, uint32_t tz)
{
    const uint64_t id = tx + (uint64_t)v->grid.tiles[0] * (ty + (uint64_t)v->grid.tiles[1] * tz);
    uint64_t lo = 0, hi = v->mixed_count;
    while (lo < hi) {
        const uint64_t mid = lo + (hi - lo) / 2;
        if (v->mixed_tiles[mid] < id)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < v->mixed_count && v->mixed_tiles[lo] == id ? v->bits + lo * v->tile_words : NULL;
}

int meso_voxels_inside(const meso_voxels* v, uint32_t i, uint32_t j, uint32_t k)
{
    const uint32_t R = v->grid.tile_res;
    const meso_tile_class c = meso_voxels_tile(v, i / R, j / R, k / R);
    if (c != MESO_TILE_MIXED)
        return c == MESO_TILE_INSIDE;
    const uint64_t* bits = meso_voxels_tile_bits(v, i / R, j / R, k / R);
    const uint64_t bit = i % R + (uint64_t)R * (j % R + (uint64_t)R * (k % R));
    return (int)((bits[bit >> 6] >> (bit & 63)) & 1u);
}

void meso_voxels_free(meso_voxels* v)
{
    if (!v)
        return;
    free(v->tile_class);
    free(v->mixed_tiles);
    free(v->bits);
    memset(v, 0, sizeof(*v));
}
