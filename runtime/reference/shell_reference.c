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
#include "meso_layout.h"

#include "ref_bvh.h"
#include "ref_common.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _OPENMP
#include <omp.h>
#endif

/* >>loading ---------------------------------------------------------------- */

/* COLR + CMAP (FORMAT.md §7.2 "Shell colour"); none: MESO_OK, color.w 0. */
static meso_result load_color(meso_file* f, uint32_t object_id, uint16_t lod, meso_ref_shell* out, meso_error* err)
{
    const int32_t ci = meso_file_find_level(f, MESO_CHUNK_COLR, object_id, lod);
    const int32_t mi = meso_file_find_level(f, MESO_CHUNK_CMAP, object_id, lod);
    if (ci < 0 && mi < 0)
        return MESO_OK;
    const meso_chunk_info* c = ci >= 0 ? meso_file_chunk(f, (uint32_t)ci) : NULL;
    if (!c || mi < 0 || c->dtype != MESO_DTYPE_U8 || c->components != 4 ||
        meso_file_chunk(f, (uint32_t)mi)->decoded_size != MESO_CMAP_RECORD_SIZE ||
        (c->dims[2] != 1 && out->tex.kind != 2))
        return mesoi_ref_fail(err, MESO_ERR_CORRUPT, "shell", object_id,
                              "colour needs one U8 x 4 COLR (3D only over a TX3D) and its CMAP record (FORMAT.md 7.2)");
    uint8_t rec[MESO_CMAP_RECORD_SIZE];
    meso_result r = meso_file_read_chunk(f, (uint32_t)mi, rec, sizeof(rec), err);
    void* texels = NULL;
    size_t size = 0;
    if (r == MESO_OK)
        r = mesoi_ref_read_whole(f, ci, &texels, &size, err);
    if (r != MESO_OK)
        return r;
    meso_cmap_record m;
    meso_cmap_record_decode(rec, &m);
    out->color_texels = texels;
    out->color = (meso_ref_color){.w = c->dims[0], .h = c->dims[1], .d = c->dims[2], .rgba = out->color_texels,
                                  .scale = {m.scale[0], m.scale[1]}};
    return MESO_OK;
}

meso_result meso_ref_shell_load(meso_file* f, uint32_t object_id, meso_ref_shell* out, meso_error* err)
{
    return meso_ref_shell_load_level(f, object_id, 0, out, err);
}

meso_result meso_ref_shell_load_level(meso_file* f, uint32_t object_id, uint16_t lod, meso_ref_shell* out,
                                      meso_error* err)
{
    if (!f || !out)
        return mesoi_ref_fail(err, MESO_ERR_INVALID_ARG, "shell", object_id, "NULL file or output");
    memset(out, 0, sizeof(*out));
    meso_object_record rec;
    meso_result r = mesoi_ref_object(f, object_id, MESO_OBJECT_SHELL, "shell", &rec, err);
    if (r != MESO_OK)
        return r;
    memcpy(out->bbox_min, rec.bbox_min, sizeof(out->bbox_min));
    memcpy(out->bbox_max, rec.bbox_max, sizeof(out->bbox_max));

    const int32_t mi = meso_file_find_level(f, MESO_CHUNK_MESH, object_id, lod),
                  di = meso_file_find_level(f, MESO_CHUNK_SDIR, object_id, lod);
    if (mi < 0 || di < 0)
        return mesoi_ref_fail(err, MESO_ERR_NOT_FOUND, "shell", object_id, mi < 0 ? "no MESH chunk" : "no SDIR chunk");
    void *mesh = NULL, *dirs = NULL;
    size_t mesh_size = 0, dirs_size = 0;
    meso_mesh_view mv;
    if ((r = mesoi_ref_read_whole(f, mi, &mesh, &mesh_size, err)) != MESO_OK)
        goto done;
    if ((r = meso_mesh_parse(mesh, mesh_size, &mv, err)) != MESO_OK)
        goto done;
    const uint32_t nv = mv.layout.vertex_count, nt = mv.layout.index_count / 3;
    const meso_chunk_info* dc = meso_file_chunk(f, (uint32_t)di);
    if (nt == 0 || dc->dtype != MESO_DTYPE_F32 || dc->components != 3 || dc->dims[0] != nv ||
        (dc->dims[1] != 1 && dc->dims[1] != 2) || dc->dims[2] != 1 ||
        dc->decoded_size != (uint64_t)nv * dc->dims[1] * 12) {
        r = mesoi_ref_fail(err, MESO_ERR_CORRUPT, "shell", object_id,
                           "SDIR must be F32 x 3, N x (1|2) x 1 with N the MESH vertex count, and the MESH must have "
                           "triangles");
        goto done;
    }
    if ((r = mesoi_ref_read_whole(f, di, &dirs, &dirs_size, err)) != MESO_OK)
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
        r = mesoi_ref_fail(err, MESO_ERR_OUT_OF_MEMORY, "shell", object_id, "out of memory");
        goto done;
    }
    memcpy(out->positions, mv.positions, sizeof(float) * 3 * (size_t)nv);
    memcpy(out->indices, mv.indices, sizeof(uint32_t) * 3 * (size_t)nt);
    if (mv.uvs)
        memcpy(out->uvs, mv.uvs, sizeof(float) * 2 * (size_t)nv);

    /* The texture function: TX2D (height) before TX3D (density), as libmeso. */
    const int32_t hi = meso_file_find_level(f, MESO_CHUNK_TX2D, object_id, lod);
    const int32_t vi = meso_file_find_level(f, MESO_CHUNK_TX3D, object_id, lod);
    if (hi >= 0 || vi >= 0) {
        const int32_t ti = hi >= 0 ? hi : vi;
        const meso_chunk_info* tc = meso_file_chunk(f, (uint32_t)ti);
        r = hi >= 0 && tc->dims[2] != 1 ? MESO_ERR_UNSUPPORTED : mesoi_ref_read_unorm(f, ti, &out->tex_values, err);
        if (r == MESO_ERR_UNSUPPORTED) {
            r = mesoi_ref_fail(err, r, "shell", object_id, "texture function is not U8 or U16 x 1 (FORMAT.md 7.2)");
            goto done;
        }
        if (r != MESO_OK)
            goto done;
        out->tex.kind = hi >= 0 ? 1 : 2;
        out->tex.w = tc->dims[0];
        out->tex.h = tc->dims[1];
        out->tex.d = tc->dims[2];
        out->tex.values = out->tex_values;
    }
    r = load_color(f, object_id, lod, out, err);
done:
    free(mesh);
    free(dirs);
    if (r != MESO_OK)
        meso_ref_shell_free(out);
    return r;
}

meso_result meso_ref_shell_set_time(meso_file* f, uint32_t object_id, double t, meso_ref_shell* s, meso_error* err)
{
    const int32_t ai = meso_file_find(f, MESO_CHUNK_ANIM, object_id, 0);
    const int32_t fi = meso_file_find(f, MESO_CHUNK_TXFR, object_id, 0);
    if (ai < 0)
        return MESO_OK;
    uint8_t rec[MESO_ANIM_RECORD_SIZE];
    const meso_chunk_info* ac = meso_file_chunk(f, (uint32_t)ai);
    if (fi < 0 || !s->tex.kind || ac->decoded_size != sizeof(rec))
        return mesoi_ref_fail(err, MESO_ERR_CORRUPT, "shell", object_id,
                              "ANIM without TXFR frames of a texture function (FORMAT.md 7.2)");
    meso_result r = meso_file_read_chunk(f, (uint32_t)ai, rec, sizeof(rec), err);
    if (r != MESO_OK)
        return r;
    meso_anim_record a;
    meso_anim_record_decode(rec, &a);
    const meso_chunk_info* fc = meso_file_chunk(f, (uint32_t)fi);
    const size_t n = (size_t)s->tex.w * s->tex.h * s->tex.d;
    if (fc->dims[0] != s->tex.w || fc->dims[1] != s->tex.h || (uint64_t)fc->dims[2] != (uint64_t)s->tex.d * a.frame_count)
        return mesoi_ref_fail(err, MESO_ERR_CORRUPT, "shell", object_id,
                              "TXFR is not ANIM's frame_count frames of the texture function (FORMAT.md 7.2)");
    float* all = NULL;
    r = mesoi_ref_read_unorm(f, fi, &all, err);
    if (r != MESO_OK)
        return r;
    memcpy(s->tex_values, all + n * meso_anim_frame_at(&a, t), sizeof(float) * n);
    free(all);
    return MESO_OK;
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
    free(s->color_texels);
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
        /* Element-wise: gcc 12 -O3 misreads a memcpy of the whole
         * array here as an overflow (-Wstringop-overflow). */
        static const double bary[3][2] = {{0, 0}, {1, 0}, {0, 1}};
        for (int k = 0; k < 3; ++k) {
            out->uv[k][0] = bary[k][0];
            out->uv[k][1] = bary[k][1];
        }
    }
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

typedef struct scene {
    const meso_ref_shell* shell;
    const meso_ref_view* view;
    ref_prism* prisms;
    mesoi_ref_bvh bvh; /* over the prisms' boxes */
    int curved, samples;
    mesoi_ref_camera cam;
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

/* >>ray casting ------------------------------------------------------------ */

typedef struct ray {
    double o[3], d[3], inv[3];
} ray;

typedef struct hit {
    double t, uvw[3];
    uint32_t prism;
} hit;

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

typedef struct trace_ctx {
    const scene* sc;
    const ray* r;
    hit* best;
} trace_ctx;

static void trace_leaf(const void* user, const uint32_t* items, uint32_t count, double* tmax)
{
    const trace_ctx* c = user;
    for (uint32_t i = 0; i < count; ++i) {
        const ref_prism* rp = &c->sc->prisms[items[i]];
        double a = 0, b = fmin(1.0, c->best->t);
        if (!mesoi_ref_box_interval(rp->lo, rp->hi, c->r->o, c->r->d, c->r->inv, &a, &b) ||
            !hull_interval(rp, c->r, &a, &b))
            continue;
        march_prism(c->sc, items[i], c->r, a, b, c->best);
    }
    *tmax = fmin(1.0, c->best->t);
}

static void trace(const scene* sc, const ray* r, hit* best)
{
    const trace_ctx c = {sc, r, best};
    double tmax = fmin(1.0, best->t);
    mesoi_ref_bvh_trace(&sc->bvh, r->o, r->d, r->inv, &tmax, trace_leaf, &c);
}

/* Normal and colour of a hit (shell_reference.h). */
static void shade(const scene* sc, const ray* r, const hit* h, float rgb[3], float nrm[3], float alb[3])
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
    double albedo[3] = {sc->cam.albedo[0], sc->cam.albedo[1], sc->cam.albedo[2]};
    meso_ref_color_value(&sc->shell->color, s, tp, w, albedo);
    for (int i = 0; i < 3; ++i)
        alb[i] = (float)albedo[i];
    mesoi_ref_shade_albedo(&sc->cam, albedo, r->d, n, w, rgb, nrm);
}

static void render_row(const scene* sc, meso_ref_image* img, int y)
{
    const int W = img->width, H = img->height;
    for (int x = 0; x < W; ++x) {
        const size_t px = (size_t)y * (size_t)W + (size_t)x;
        ray r;
        mesoi_ref_pixel_ray(&sc->cam, x, y, W, H, r.o, r.d);
        for (int c = 0; c < 3; ++c)
            r.inv[c] = r.d[c] != 0 ? 1.0 / r.d[c] : INFINITY;
        hit h = {.t = INFINITY};
        trace(sc, &r, &h);
        if (!(h.t <= 1.0)) {
            mesoi_ref_image_miss(img, px);
            continue;
        }
        const double p[3] = {r.o[0] + h.t * r.d[0], r.o[1] + h.t * r.d[1], r.o[2] + h.t * r.d[2]};
        img->depth[px] = mesoi_ref_depth(&sc->cam, p);
        img->coverage[px] = 1;
        for (int c = 0; c < 3; ++c)
            img->hit[3 * px + (size_t)c] = (float)p[c];
        shade(sc, &r, &h, &img->rgb[3 * px], &img->normal[3 * px], &img->albedo[3 * px]);
    }
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
    if (!mesoi_ref_camera_init(v, &sc.cam))
        return MESO_ERR_INVALID_ARG;
    const double uv_scale = v->uv_scale != 0 ? v->uv_scale : 1.0;

    const uint32_t nt = s->triangle_count;
    sc.prisms = malloc(sizeof(*sc.prisms) * (nt ? nt : 1));
    double(*box)[6] = malloc(sizeof(*box) * (nt ? nt : 1));
    uint32_t* items = malloc(sizeof(*items) * (nt ? nt : 1));
    meso_result r = mesoi_ref_image_alloc(out, v->width, v->height);
    if (r == MESO_OK && (!sc.prisms || !box || !items))
        r = MESO_ERR_OUT_OF_MEMORY;
    if (r != MESO_OK)
        goto done;
    for (uint32_t f = 0; f < nt; ++f) {
        prepare_prism(&sc.prisms[f], s, f, uv_scale, sc.curved);
        memcpy(box[f], sc.prisms[f].lo, sizeof(sc.prisms[f].lo));
        memcpy(box[f] + 3, sc.prisms[f].hi, sizeof(sc.prisms[f].hi));
        items[f] = f;
    }
    r = mesoi_ref_bvh_build(&sc.bvh, (const double(*)[6])box, items, nt);
    if (r != MESO_OK)
        goto done;

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
    free(box);
    free(items);
    mesoi_ref_bvh_free(&sc.bvh);
    if (r != MESO_OK)
        meso_ref_image_free(out);
    return r;
}
