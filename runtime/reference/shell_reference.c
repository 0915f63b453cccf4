/*
 * shell_reference.c — the exact CPU ray caster of shell objects
 * (shell_reference.h has the ray, hit, depth and shading rules).
 *
 * Per pixel: a BVH over the prisms' bounding boxes gives the candidate
 * prisms; the ray is clipped against each prism's convex hull (of its six
 * vertices; for curved shells of the six vertices at the prism's w̄ range,
 * which contains the bent levels), that interval is sampled densely and each
 * sample is inverted exactly (meso_phi_inverse / meso_phi_curved_inverse_in).
 * The first sample that is inside the prism and solid is bracketed with the
 * previous one and refined by bisection in the ray parameter, re-inverting
 * at every step. The nearest hit over all prisms wins.
 *
 * Determinism: every pixel is computed from the shared, read-only scene by
 * the same sequence of operations whatever the thread that runs it, so the
 * image does not depend on the thread count.
 */
#include "shell_reference.h"

#include "mat4_inverse.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _OPENMP
#include <omp.h>
#endif

/* >>loading ---------------------------------------------------------------- */

static meso_result fail(meso_error* err, meso_result r, const char* msg, uint32_t id)
{
    if (err) {
        memset(err, 0, sizeof(*err));
        err->result = r;
        err->offset = UINT64_MAX;
        err->chunk = -1;
        snprintf(err->message, sizeof(err->message), "shell %u: %s", id, msg);
    }
    return r;
}

/* Reads chunk `ci` whole into a new malloc'd buffer. */
static meso_result read_whole(meso_file* f, int32_t ci, void** out, size_t* size, meso_error* err)
{
    const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)ci);
    if (!c)
        return MESO_ERR_NOT_FOUND;
    if (c->decoded_size == 0 || c->decoded_size > (uint64_t)(SIZE_MAX / 2))
        return MESO_ERR_UNSUPPORTED;
    void* data = malloc((size_t)c->decoded_size);
    if (!data)
        return MESO_ERR_OUT_OF_MEMORY;
    const meso_result r = meso_file_read_chunk(f, (uint32_t)ci, data, (size_t)c->decoded_size, err);
    if (r != MESO_OK) {
        free(data);
        return r;
    }
    *out = data;
    *size = (size_t)c->decoded_size;
    return MESO_OK;
}

static int32_t find_chunk(const meso_file* f, uint32_t type, uint32_t id)
{
    const int32_t i = meso_file_find(f, type, id, 0);
    return i >= 0 ? i : meso_file_find(f, type, id, UINT16_MAX);
}

meso_result meso_ref_shell_load(meso_file* f, uint32_t object_id, meso_ref_shell* out, meso_error* err)
{
    if (!f || !out)
        return fail(err, MESO_ERR_INVALID_ARG, "NULL file or output", object_id);
    memset(out, 0, sizeof(*out));
    uint32_t count = 0;
    meso_result r = meso_file_objects(f, NULL, 0, &count, err);
    if (r != MESO_OK)
        return r;
    meso_object_record* recs = count ? malloc(sizeof(*recs) * count) : NULL;
    if (count && !recs)
        return fail(err, MESO_ERR_OUT_OF_MEMORY, "out of memory", object_id);
    if ((r = meso_file_objects(f, recs, count, &count, err)) != MESO_OK) {
        free(recs);
        return r;
    }
    const meso_object_record* rec = NULL;
    for (uint32_t i = 0; i < count; ++i)
        if (recs[i].id == object_id)
            rec = &recs[i];
    if (!rec) {
        free(recs);
        return fail(err, MESO_ERR_NOT_FOUND, "no such object in the OBJT table", object_id);
    }
    if (rec->kind != MESO_OBJECT_SHELL) {
        free(recs);
        return fail(err, MESO_ERR_INVALID_ARG, "not a shell object (kind 2)", object_id);
    }
    memcpy(out->bbox_min, rec->bbox_min, sizeof(out->bbox_min));
    memcpy(out->bbox_max, rec->bbox_max, sizeof(out->bbox_max));
    free(recs);

    const int32_t mi = find_chunk(f, MESO_CHUNK_MESH, object_id), di = find_chunk(f, MESO_CHUNK_SDIR, object_id);
    if (mi < 0 || di < 0)
        return fail(err, MESO_ERR_NOT_FOUND, mi < 0 ? "no MESH chunk" : "no SDIR chunk", object_id);
    void *mesh = NULL, *dirs = NULL, *tex = NULL;
    size_t mesh_size = 0, dirs_size = 0, tex_size = 0;
    meso_mesh_view mv;
    if ((r = read_whole(f, mi, &mesh, &mesh_size, err)) != MESO_OK)
        goto done;
    if ((r = meso_mesh_parse(mesh, mesh_size, &mv, err)) != MESO_OK)
        goto done;
    const uint32_t nv = mv.layout.vertex_count, nt = mv.layout.index_count / 3;
    const meso_chunk_info* dc = meso_file_chunk(f, (uint32_t)di);
    if (nt == 0 || dc->dtype != MESO_DTYPE_F32 || dc->components != 3 || dc->dims[0] != nv ||
        (dc->dims[1] != 1 && dc->dims[1] != 2) || dc->dims[2] != 1 ||
        dc->decoded_size != (uint64_t)nv * dc->dims[1] * 12) {
        r = fail(err, MESO_ERR_CORRUPT, "SDIR must be F32 x 3, N x (1|2) x 1 with N the MESH vertex count, and the "
                                        "MESH must have triangles", object_id);
        goto done;
    }
    if ((r = read_whole(f, di, &dirs, &dirs_size, err)) != MESO_OK)
        goto done;
    out->vertex_count = nv;
    out->triangle_count = nt;
    out->layers = dc->dims[1];
    out->directors = dirs;
    dirs = NULL;
    out->positions = malloc(sizeof(float) * 3 * (size_t)nv);
    out->indices = malloc(sizeof(uint32_t) * 3 * (size_t)nt);
    out->uvs = mv.uvs ? malloc(sizeof(float) * 2 * (size_t)nv) : NULL;
    if (!out->positions || !out->indices || (mv.uvs && !out->uvs)) {
        r = fail(err, MESO_ERR_OUT_OF_MEMORY, "out of memory", object_id);
        goto done;
    }
    memcpy(out->positions, mv.positions, sizeof(float) * 3 * (size_t)nv);
    memcpy(out->indices, mv.indices, sizeof(uint32_t) * 3 * (size_t)nt);
    if (mv.uvs)
        memcpy(out->uvs, mv.uvs, sizeof(float) * 2 * (size_t)nv);

    /* The texture function: TX2D (height) before TX3D (density), as libmeso. */
    const int32_t hi = meso_file_find(f, MESO_CHUNK_TX2D, object_id, 0);
    const int32_t vi = meso_file_find(f, MESO_CHUNK_TX3D, object_id, 0);
    if (hi >= 0 || vi >= 0) {
        const int32_t ti = hi >= 0 ? hi : vi;
        const meso_chunk_info* tc = meso_file_chunk(f, (uint32_t)ti);
        const uint32_t es = tc->dtype == MESO_DTYPE_U8 ? 1 : tc->dtype == MESO_DTYPE_U16 ? 2 : 0;
        const uint64_t texels = (uint64_t)tc->dims[0] * tc->dims[1] * tc->dims[2];
        if (es == 0 || tc->components != 1 || (hi >= 0 && tc->dims[2] != 1) || tc->decoded_size != texels * es ||
            texels == 0 || texels > (uint64_t)(SIZE_MAX / sizeof(float))) {
            r = fail(err, MESO_ERR_UNSUPPORTED, "texture function is not U8 or U16 x 1 (FORMAT.md 7.2)", object_id);
            goto done;
        }
        if ((r = read_whole(f, ti, &tex, &tex_size, err)) != MESO_OK)
            goto done;
        out->tex_values = malloc(sizeof(float) * (size_t)texels);
        if (!out->tex_values) {
            r = fail(err, MESO_ERR_OUT_OF_MEMORY, "out of memory", object_id);
            goto done;
        }
        for (size_t i = 0; i < (size_t)texels; ++i) {
            if (es == 1) {
                out->tex_values[i] = (float)(((const uint8_t*)tex)[i] / 255.0);
            } else {
                uint16_t x;
                memcpy(&x, (const uint8_t*)tex + 2 * i, 2);
                out->tex_values[i] = (float)(x / 65535.0);
            }
        }
        out->tex.kind = hi >= 0 ? 1 : 2;
        out->tex.w = tc->dims[0];
        out->tex.h = tc->dims[1];
        out->tex.d = tc->dims[2];
        out->tex.values = out->tex_values;
    }
    r = MESO_OK;
done:
    free(mesh);
    free(dirs);
    free(tex);
    if (r != MESO_OK)
        meso_ref_shell_free(out);
    return r;
}

void meso_ref_shell_free(meso_ref_shell* s)
{
    if (!s)
        return;
    free(s->positions);
    free(s->directors);
    free(s->uvs);
    free(s->indices);
    free(s->tex_values);
    memset(s, 0, sizeof(*s));
}

void meso_ref_shell_prism(const meso_ref_shell* s, uint32_t f, double uv_scale, meso_prism* out)
{
    const size_t nv = s->vertex_count;
    for (int k = 0; k < 3; ++k) {
        const size_t i = s->indices[3 * (size_t)f + (size_t)k];
        for (int c = 0; c < 3; ++c) {
            const double pos = s->positions[3 * i + (size_t)c], top = pos + s->directors[3 * i + (size_t)c];
            const double bottom = s->layers == 2 ? pos + s->directors[3 * (nv + i) + (size_t)c] : pos;
            out->b[k][c] = bottom;
            out->n[k][c] = top - bottom;
        }
        out->uv[k][0] = s->uvs ? uv_scale * s->uvs[2 * i] : 0.0;
        out->uv[k][1] = s->uvs ? uv_scale * s->uvs[2 * i + 1] : 0.0;
    }
    /* A triangle whose texture coordinates have no area (a mesh without uvs,
     * or planar uvs on a face seen edge-on) uses its barycentrics instead:
     * (0,0), (1,0), (0,1) — FORMAT.md §7.2, the same absolute threshold as
     * shell_common.glsl's load_prism. */
    const double e1s = out->uv[1][0] - out->uv[0][0], e1t = out->uv[1][1] - out->uv[0][1];
    const double e2s = out->uv[2][0] - out->uv[0][0], e2t = out->uv[2][1] - out->uv[0][1];
    if (!(fabs(e1s * e2t - e2s * e1t) >= 1e-12)) {
        static const double bary[3][2] = {{0, 0}, {1, 0}, {0, 1}};
        memcpy(out->uv, bary, sizeof(bary));
    }
}

/* >>matrices --------------------------------------------------------------- */

/* Column-major 4×4: c = a · b. */
static void mat_mul(const double a[16], const double b[16], double c[16])
{
    for (int col = 0; col < 4; ++col)
        for (int row = 0; row < 4; ++row) {
            double s = 0;
            for (int k = 0; k < 4; ++k)
                s += a[4 * k + row] * b[4 * col + k];
            c[4 * col + row] = s;
        }
}

static void mat_apply(const double m[16], const double x[4], double y[4])
{
    for (int r = 0; r < 4; ++r)
        y[r] = m[r] * x[0] + m[4 + r] * x[1] + m[8 + r] * x[2] + m[12 + r] * x[3];
}

/* >>scene ------------------------------------------------------------------ */

#define MAX_PLANES 20

typedef struct ref_prism {
    meso_prism P;
    double wlo, whi;            /* w̄ range (curved) or [0,1] */
    double lo[3], hi[3];        /* bounding box of the hull */
    double plane[MAX_PLANES][4]; /* hull: n·x ≤ d, (n, d) */
    int planes;
} ref_prism;

typedef struct bvh_node {
    double lo[3], hi[3];
    uint32_t first, count; /* leaf: items[first..first+count); inner: count 0, children first, first + 1 */
} bvh_node;

typedef struct scene {
    const meso_ref_shell* shell;
    const meso_ref_view* view;
    ref_prism* prisms;
    uint32_t* items;
    bvh_node* nodes;
    uint32_t node_count;
    int curved, samples;
    double mvp[16], inv[16], light[3], albedo[3];
} scene;

/* The supporting planes of the convex hull of six points: every plane
 * through three of them with the other three on one side. A tiny outward
 * padding keeps samples on the prism's own boundary inside the interval. */
static void hull_planes(ref_prism* rp, const double pts[6][3])
{
    double scale = 0;
    for (int c = 0; c < 3; ++c)
        scale = fmax(scale, rp->hi[c] - rp->lo[c]);
    if (!(scale > 0))
        scale = 1;
    const double eps = 1e-9 * scale, pad = 1e-7 * scale;
    rp->planes = 0;
    for (int i = 0; i < 6; ++i)
        for (int j = i + 1; j < 6; ++j)
            for (int k = j + 1; k < 6; ++k) {
                double e1[3], e2[3], n[3];
                for (int c = 0; c < 3; ++c) {
                    e1[c] = pts[j][c] - pts[i][c];
                    e2[c] = pts[k][c] - pts[i][c];
                }
                n[0] = e1[1] * e2[2] - e1[2] * e2[1];
                n[1] = e1[2] * e2[0] - e1[0] * e2[2];
                n[2] = e1[0] * e2[1] - e1[1] * e2[0];
                const double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                if (!(len > 1e-12 * scale * scale))
                    continue;
                for (int c = 0; c < 3; ++c)
                    n[c] /= len;
                const double d = n[0] * pts[i][0] + n[1] * pts[i][1] + n[2] * pts[i][2];
                int above = 0, below = 0;
                for (int m = 0; m < 6; ++m) {
                    const double s = n[0] * pts[m][0] + n[1] * pts[m][1] + n[2] * pts[m][2] - d;
                    above += s > eps;
                    below += s < -eps;
                }
                for (int side = 0; side < 2; ++side) {
                    if ((side == 0 && above) || (side == 1 && below) || rp->planes >= MAX_PLANES)
                        continue;
                    const double sg = side == 0 ? 1.0 : -1.0;
                    double* pl = rp->plane[rp->planes++];
                    pl[0] = sg * n[0];
                    pl[1] = sg * n[1];
                    pl[2] = sg * n[2];
                    pl[3] = sg * d + pad;
                }
            }
}

static void prepare_prism(ref_prism* rp, const meso_ref_shell* s, uint32_t f, double uv_scale, int curved)
{
    meso_ref_shell_prism(s, f, uv_scale, &rp->P);
    rp->wlo = 0;
    rp->whi = 1;
    if (curved)
        meso_curved_wbar_range(&rp->P, &rp->wlo, &rp->whi);
    double pts[6][3];
    for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c) {
            pts[k][c] = rp->P.b[k][c] + rp->wlo * rp->P.n[k][c];
            pts[k + 3][c] = rp->P.b[k][c] + rp->whi * rp->P.n[k][c];
        }
    for (int c = 0; c < 3; ++c) {
        rp->lo[c] = INFINITY;
        rp->hi[c] = -INFINITY;
        for (int k = 0; k < 6; ++k) {
            rp->lo[c] = fmin(rp->lo[c], pts[k][c]);
            rp->hi[c] = fmax(rp->hi[c], pts[k][c]);
        }
    }
    hull_planes(rp, (const double(*)[3])pts);
    double scale = 0;
    for (int c = 0; c < 3; ++c)
        scale = fmax(scale, rp->hi[c] - rp->lo[c]);
    for (int c = 0; c < 3; ++c) {
        rp->lo[c] -= 1e-6 * scale;
        rp->hi[c] += 1e-6 * scale;
    }
}

typedef struct sort_item {
    double key;
    uint32_t idx;
} sort_item;

static int cmp_item(const void* a, const void* b)
{
    const sort_item *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return x->idx < y->idx ? -1 : x->idx > y->idx;
}

/* Median split along the longest axis of the centroids, leaves of ≤ 4. */
static void bvh_build(scene* sc, uint32_t node, uint32_t first, uint32_t count, sort_item* tmp)
{
    bvh_node* nd = &sc->nodes[node];
    double clo[3] = {INFINITY, INFINITY, INFINITY}, chi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int c = 0; c < 3; ++c) {
        nd->lo[c] = INFINITY;
        nd->hi[c] = -INFINITY;
    }
    for (uint32_t i = first; i < first + count; ++i) {
        const ref_prism* rp = &sc->prisms[sc->items[i]];
        for (int c = 0; c < 3; ++c) {
            nd->lo[c] = fmin(nd->lo[c], rp->lo[c]);
            nd->hi[c] = fmax(nd->hi[c], rp->hi[c]);
            const double m = 0.5 * (rp->lo[c] + rp->hi[c]);
            clo[c] = fmin(clo[c], m);
            chi[c] = fmax(chi[c], m);
        }
    }
    if (count <= 4) {
        nd->first = first;
        nd->count = count;
        return;
    }
    int axis = 0;
    for (int c = 1; c < 3; ++c)
        if (chi[c] - clo[c] > chi[axis] - clo[axis])
            axis = c;
    for (uint32_t i = 0; i < count; ++i) {
        const ref_prism* rp = &sc->prisms[sc->items[first + i]];
        tmp[i].key = rp->lo[axis] + rp->hi[axis];
        tmp[i].idx = sc->items[first + i];
    }
    qsort(tmp, count, sizeof(*tmp), cmp_item);
    for (uint32_t i = 0; i < count; ++i)
        sc->items[first + i] = tmp[i].idx;
    const uint32_t half = count / 2, left = sc->node_count;
    sc->node_count += 2;
    nd->first = left;
    nd->count = 0;
    bvh_build(sc, left, first, half, tmp);
    bvh_build(sc, left + 1, first + half, count - half, tmp);
}

/* >>ray casting ------------------------------------------------------------ */

typedef struct ray {
    double o[3], d[3], inv[3];
} ray;

typedef struct hit {
    double t, uvw[3];
    uint32_t prism;
} hit;

static int box_interval(const double lo[3], const double hi[3], const ray* r, double* t0, double* t1)
{
    double a = *t0, b = *t1;
    for (int c = 0; c < 3; ++c) {
        if (r->d[c] == 0) {
            if (r->o[c] < lo[c] || r->o[c] > hi[c])
                return 0;
            continue;
        }
        double ta = (lo[c] - r->o[c]) * r->inv[c], tb = (hi[c] - r->o[c]) * r->inv[c];
        if (ta > tb) {
            const double x = ta;
            ta = tb;
            tb = x;
        }
        a = fmax(a, ta);
        b = fmin(b, tb);
        if (a > b)
            return 0;
    }
    *t0 = a;
    *t1 = b;
    return 1;
}

static int hull_interval(const ref_prism* rp, const ray* r, double* t0, double* t1)
{
    double a = *t0, b = *t1;
    for (int i = 0; i < rp->planes; ++i) {
        const double* pl = rp->plane[i];
        const double den = pl[0] * r->d[0] + pl[1] * r->d[1] + pl[2] * r->d[2];
        const double num = pl[3] - (pl[0] * r->o[0] + pl[1] * r->o[1] + pl[2] * r->o[2]);
        if (den == 0) {
            if (num < 0)
                return 0;
            continue;
        }
        const double t = num / den;
        if (den > 0)
            b = fmin(b, t);
        else
            a = fmax(a, t);
        if (a > b)
            return 0;
    }
    *t0 = a;
    *t1 = b;
    return 1;
}

/* Inside the prism and solid at ray parameter t; (u,v,w) out. */
static int solid_at(const scene* sc, const ref_prism* rp, const ray* r, double t, double uvw[3])
{
    const double p[3] = {r->o[0] + t * r->d[0], r->o[1] + t * r->d[1], r->o[2] + t * r->d[2]};
    const double tol = 1e-9;
    const int in = sc->curved ? meso_phi_curved_inverse_in(&rp->P, p, rp->wlo, rp->whi, tol, uvw)
                              : meso_phi_inverse(&rp->P, p, 0.0, 1.0, tol, uvw);
    if (!in)
        return 0;
    const meso_prism* P = &rp->P;
    const double tt = 1 - uvw[0] - uvw[1];
    const double s = tt * P->uv[0][0] + uvw[0] * P->uv[1][0] + uvw[1] * P->uv[2][0];
    const double tp = tt * P->uv[0][1] + uvw[0] * P->uv[1][1] + uvw[1] * P->uv[2][1];
    return meso_ref_texfn_solid(&sc->shell->tex, s, tp, uvw[2]);
}

/* The first solid point of prism `pi` on [t0, t1] before `best->t`. */
static void march_prism(const scene* sc, uint32_t pi, const ray* r, double t0, double t1, hit* best)
{
    const ref_prism* rp = &sc->prisms[pi];
    const int n = sc->samples;
    double prev = t0, uvw[3];
    for (int i = 0; i < n; ++i) {
        const double t = n > 1 ? t0 + (t1 - t0) * ((double)i / (n - 1)) : 0.5 * (t0 + t1);
        if (t >= best->t)
            return;
        if (!solid_at(sc, rp, r, t, uvw)) {
            prev = t;
            continue;
        }
        double lo = prev, hi = t, huvw[3] = {uvw[0], uvw[1], uvw[2]};
        if (i > 0)
            for (int it = 0; it < 60; ++it) {
                const double m = 0.5 * (lo + hi);
                if (solid_at(sc, rp, r, m, uvw)) {
                    hi = m;
                    memcpy(huvw, uvw, sizeof(huvw));
                } else {
                    lo = m;
                }
            }
        if (hi < best->t) {
            best->t = hi;
            memcpy(best->uvw, huvw, sizeof(huvw));
            best->prism = pi;
        }
        return;
    }
}

static void trace(const scene* sc, const ray* r, hit* best)
{
    uint32_t stack[128];
    int sp = 0;
    stack[sp++] = 0;
    while (sp > 0) {
        const bvh_node* nd = &sc->nodes[stack[--sp]];
        double t0 = 0, t1 = fmin(1.0, best->t);
        if (!box_interval(nd->lo, nd->hi, r, &t0, &t1))
            continue;
        if (nd->count == 0) {
            /* Nearer child last, so it is popped first. */
            const bvh_node *a = &sc->nodes[nd->first], *b = &sc->nodes[nd->first + 1];
            double ta0 = 0, ta1 = 1, tb0 = 0, tb1 = 1;
            const int ha = box_interval(a->lo, a->hi, r, &ta0, &ta1), hb = box_interval(b->lo, b->hi, r, &tb0, &tb1);
            const int a_first = !hb || (ha && ta0 <= tb0);
            if (sp + 2 <= 128) {
                stack[sp++] = a_first ? nd->first + 1 : nd->first;
                stack[sp++] = a_first ? nd->first : nd->first + 1;
            }
            continue;
        }
        for (uint32_t i = nd->first; i < nd->first + nd->count; ++i) {
            const uint32_t pi = sc->items[i];
            const ref_prism* rp = &sc->prisms[pi];
            double a = 0, b = fmin(1.0, best->t);
            if (!box_interval(rp->lo, rp->hi, r, &a, &b) || !hull_interval(rp, r, &a, &b))
                continue;
            march_prism(sc, pi, r, a, b, best);
        }
    }
}

/* Normal and colour of a hit (shell_reference.h). */
static void shade(const scene* sc, const ray* r, const hit* h, float rgb[3], float nrm[3])
{
    const meso_prism* P = &sc->prisms[h->prism].P;
    const double u = h->uvw[0], v = h->uvw[1], w = h->uvw[2], del = 1e-3;
    const double tt = 1 - u - v;
    const double s = tt * P->uv[0][0] + u * P->uv[1][0] + v * P->uv[2][0];
    const double tp = tt * P->uv[0][1] + u * P->uv[1][1] + v * P->uv[2][1];
    double g[3];
    meso_ref_texfn_gradient(&sc->shell->tex, s, tp, w, g);
    /* ∂Φ/∂(u,v,w) by central differences. */
    double J[3][3]; /* columns */
    for (int c = 0; c < 3; ++c) {
        double qa[3] = {u, v, w}, qb[3] = {u, v, w}, pa[3], pb[3];
        qa[c] += del;
        qb[c] -= del;
        if (sc->curved) {
            meso_phi_curved(P, qa[0], qa[1], qa[2], pa);
            meso_phi_curved(P, qb[0], qb[1], qb[2], pb);
        } else {
            meso_phi(P, qa[0], qa[1], qa[2], pa);
            meso_phi(P, qb[0], qb[1], qb[2], pb);
        }
        for (int i = 0; i < 3; ++i)
            J[c][i] = (pa[i] - pb[i]) / (2 * del);
    }
    /* (u,v) → (s,t') is affine with matrix S = [uv1−uv0, uv2−uv0];
     * ∂Φ/∂(s,t') = [J_u J_v] S⁻¹. Without usable uvs (S singular) the
     * (u,v) columns are kept: for the all-solid shell only ∇w matters, which
     * does not depend on how the tangent columns are mixed. */
    const double s00 = P->uv[1][0] - P->uv[0][0], s01 = P->uv[2][0] - P->uv[0][0];
    const double s10 = P->uv[1][1] - P->uv[0][1], s11 = P->uv[2][1] - P->uv[0][1];
    const double sd = s00 * s11 - s01 * s10;
    const double sn = fabs(s00) + fabs(s01) + fabs(s10) + fabs(s11);
    if (fabs(sd) > 1e-12 * sn * sn && sn > 0) {
        const double i00 = s11 / sd, i01 = -s01 / sd, i10 = -s10 / sd, i11 = s00 / sd;
        double js[3], jt[3];
        for (int i = 0; i < 3; ++i) {
            js[i] = J[0][i] * i00 + J[1][i] * i10;
            jt[i] = J[0][i] * i01 + J[1][i] * i11;
        }
        memcpy(J[0], js, sizeof(js));
        memcpy(J[1], jt, sizeof(jt));
    }
    /* n = J⁻ᵀ g: the rows of J⁻¹ are (J1×J2, J2×J0, J0×J1) / det. */
    double c12[3], c20[3], c01[3];
    c12[0] = J[1][1] * J[2][2] - J[1][2] * J[2][1];
    c12[1] = J[1][2] * J[2][0] - J[1][0] * J[2][2];
    c12[2] = J[1][0] * J[2][1] - J[1][1] * J[2][0];
    c20[0] = J[2][1] * J[0][2] - J[2][2] * J[0][1];
    c20[1] = J[2][2] * J[0][0] - J[2][0] * J[0][2];
    c20[2] = J[2][0] * J[0][1] - J[2][1] * J[0][0];
    c01[0] = J[0][1] * J[1][2] - J[0][2] * J[1][1];
    c01[1] = J[0][2] * J[1][0] - J[0][0] * J[1][2];
    c01[2] = J[0][0] * J[1][1] - J[0][1] * J[1][0];
    const double det = J[0][0] * c12[0] + J[0][1] * c12[1] + J[0][2] * c12[2];
    double n[3];
    for (int i = 0; i < 3; ++i)
        n[i] = (g[0] * c12[i] + g[1] * c20[i] + g[2] * c01[i]) / (det != 0 ? det : 1);
    double nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (nl > 0)
        for (int i = 0; i < 3; ++i)
            n[i] /= nl;
    if (n[0] * r->d[0] + n[1] * r->d[1] + n[2] * r->d[2] > 0)
        for (int i = 0; i < 3; ++i)
            n[i] = -n[i];
    const double ndl = n[0] * sc->light[0] + n[1] * sc->light[1] + n[2] * sc->light[2];
    const double k = (0.25 + 0.75 * w) * (0.15 + 0.85 * fmax(0.0, ndl));
    for (int i = 0; i < 3; ++i) {
        rgb[i] = (float)(sc->albedo[i] * k);
        nrm[i] = (float)n[i];
    }
}

static void render_row(const scene* sc, meso_ref_image* img, int y)
{
    const int W = img->width, H = img->height;
    for (int x = 0; x < W; ++x) {
        const size_t px = (size_t)y * (size_t)W + (size_t)x;
        const double ndc_x = (2.0 * x + 1) / W - 1, ndc_y = (2.0 * y + 1) / H - 1;
        const double cn[4] = {ndc_x, ndc_y, -1, 1}, cf[4] = {ndc_x, ndc_y, 1, 1};
        double on[4], of[4];
        mat_apply(sc->inv, cn, on);
        mat_apply(sc->inv, cf, of);
        ray r;
        for (int c = 0; c < 3; ++c) {
            r.o[c] = on[c] / on[3];
            r.d[c] = of[c] / of[3] - r.o[c];
            r.inv[c] = r.d[c] != 0 ? 1.0 / r.d[c] : INFINITY;
        }
        hit h = {.t = INFINITY};
        trace(sc, &r, &h);
        if (!(h.t <= 1.0)) {
            img->rgb[3 * px] = img->rgb[3 * px + 1] = img->rgb[3 * px + 2] = 0.0f;
            img->depth[px] = 1.0f;
            img->coverage[px] = 0;
            img->hit[3 * px] = img->hit[3 * px + 1] = img->hit[3 * px + 2] = NAN;
            img->normal[3 * px] = img->normal[3 * px + 1] = img->normal[3 * px + 2] = 0.0f;
            continue;
        }
        const double p[4] = {r.o[0] + h.t * r.d[0], r.o[1] + h.t * r.d[1], r.o[2] + h.t * r.d[2], 1};
        double clip[4];
        mat_apply(sc->mvp, p, clip);
        img->depth[px] = (float)(0.5 * clip[2] / clip[3] + 0.5);
        img->coverage[px] = 1;
        for (int c = 0; c < 3; ++c)
            img->hit[3 * px + (size_t)c] = (float)p[c];
        shade(sc, &r, &h, &img->rgb[3 * px], &img->normal[3 * px]);
    }
}

void meso_ref_image_free(meso_ref_image* img)
{
    if (!img)
        return;
    free(img->rgb);
    free(img->depth);
    free(img->coverage);
    free(img->hit);
    free(img->normal);
    memset(img, 0, sizeof(*img));
}

meso_result meso_ref_render(const meso_ref_shell* s, const meso_ref_view* v, meso_ref_image* out)
{
    if (!s || !v || !out || v->width < 1 || v->height < 1 || v->width > 65536 || v->height > 65536 ||
        s->triangle_count == 0 || !s->positions || !s->directors || !s->indices)
        return MESO_ERR_INVALID_ARG;
    memset(out, 0, sizeof(*out));
    scene sc;
    memset(&sc, 0, sizeof(sc));
    sc.shell = s;
    sc.view = v;
    sc.curved = v->curved != 0;
    sc.samples = v->samples_per_prism > 0 ? v->samples_per_prism : 1024;
    double model[16], pv[16];
    int model_zero = 1;
    for (int i = 0; i < 16; ++i)
        model_zero &= v->model[i] == 0;
    for (int i = 0; i < 16; ++i)
        model[i] = model_zero ? (i % 5 == 0) : v->model[i];
    mat_mul(v->proj, v->view, pv);
    mat_mul(pv, model, sc.mvp);
    if (!meso_mat4_inverse(sc.mvp, sc.inv))
        return MESO_ERR_INVALID_ARG;
    double l[3] = {v->light_dir[0], v->light_dir[1], v->light_dir[2]};
    if (l[0] == 0 && l[1] == 0 && l[2] == 0) {
        l[0] = 0.3;
        l[1] = 0.8;
        l[2] = 0.5;
    }
    for (int i = 0; i < 3; ++i) /* transpose(mat3(model)) · l */
        sc.light[i] = model[4 * i] * l[0] + model[4 * i + 1] * l[1] + model[4 * i + 2] * l[2];
    const double ll = sqrt(sc.light[0] * sc.light[0] + sc.light[1] * sc.light[1] + sc.light[2] * sc.light[2]);
    for (int i = 0; i < 3; ++i)
        sc.light[i] = ll > 0 ? sc.light[i] / ll : 0;
    const int no_albedo = v->albedo[0] == 0 && v->albedo[1] == 0 && v->albedo[2] == 0;
    const double def_albedo[3] = {0.80, 0.74, 0.66};
    for (int i = 0; i < 3; ++i)
        sc.albedo[i] = no_albedo ? def_albedo[i] : v->albedo[i];
    const double uv_scale = v->uv_scale != 0 ? v->uv_scale : 1.0;

    const uint32_t nt = s->triangle_count;
    const size_t npx = (size_t)v->width * (size_t)v->height;
    sc.prisms = malloc(sizeof(*sc.prisms) * nt);
    sc.items = malloc(sizeof(*sc.items) * nt);
    sc.nodes = malloc(sizeof(*sc.nodes) * 2 * (size_t)nt);
    sort_item* tmp = malloc(sizeof(*tmp) * nt);
    out->rgb = malloc(sizeof(float) * 3 * npx);
    out->depth = malloc(sizeof(float) * npx);
    out->coverage = malloc(npx);
    out->hit = malloc(sizeof(float) * 3 * npx);
    out->normal = malloc(sizeof(float) * 3 * npx);
    meso_result r = MESO_OK;
    if (!sc.prisms || !sc.items || !sc.nodes || !tmp || !out->rgb || !out->depth || !out->coverage || !out->hit ||
        !out->normal) {
        r = MESO_ERR_OUT_OF_MEMORY;
        goto done;
    }
    out->width = v->width;
    out->height = v->height;
    for (uint32_t f = 0; f < nt; ++f) {
        prepare_prism(&sc.prisms[f], s, f, uv_scale, sc.curved);
        sc.items[f] = f;
    }
    sc.node_count = 1;
    bvh_build(&sc, 0, 0, nt, tmp);

    int threads = v->threads;
#ifdef _OPENMP
    if (threads <= 0)
        threads = omp_get_max_threads();
#pragma omp parallel for schedule(dynamic) num_threads(threads)
#endif
    for (int y = 0; y < v->height; ++y)
        render_row(&sc, out, y);
    (void)threads;
done:
    free(sc.prisms);
    free(sc.items);
    free(sc.nodes);
    free(tmp);
    if (r != MESO_OK)
        meso_ref_image_free(out);
    return r;
}
