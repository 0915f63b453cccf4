/*
 * frusta_model_reference.c — the exact CPU reference for whole frusta
 * objects (frustum_reference.h): the nearest hit over a model's segments
 * and balls (>>model), FORMAT.md records and files into reference segments
 * (>>records, >>files: meso_ref_frusta_load), and rendering (>>render: a BVH
 * over bounding spheres, rows on pthreads). One segment's geometry and
 * relief search are frustum_reference.c's.
 */
#include "frustum_reference.h"

#include "frustum_reference_internal.h"
#include "ref_bvh.h"
#include "ref_common.h"
#include "vec3d.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* >>model ------------------------------------------------------------------ */

/* A model's items: segments 0 .. seg_count − 1, then the balls. */
typedef struct model_ref {
    const meso_ref_frustum* segs;
    uint32_t seg_count;
    const meso_ref_ball* balls;
    uint32_t ball_count;
    const meso_ref_relief* relief;
} model_ref;

/* A sphere holding item i (a segment's outer cone when it has relief);
 * 0 when a segment has no bound (always tested). */
static int item_bound(const model_ref* m, uint32_t i, double c[3], double* rad)
{
    if (i >= m->seg_count) {
        const meso_ref_ball* b = &m->balls[i - m->seg_count];
        memcpy(c, b->center, sizeof(b->center));
        *rad = b->radius;
        return 1;
    }
    return mesoi_ref_segment_bound(&m->segs[i], m->relief, c, rad);
}

/* Nearest hit of item i in [tmin, best]; `bounded`: its sphere was tested. */
static int item_intersect(const model_ref* m, uint32_t i, int bounded, const double o[3], const double d[3],
    double tmin, double best, meso_ref_frustum_hit* h, uint32_t* samples)
{
    double c[3], rad, ts[2];
    if (!bounded && item_bound(m, i, c, &rad)) {
        const int n = mesoi_ref_ray_sphere(c, rad, o, d, ts);
        if (n < 2 || ts[1] < tmin || ts[0] > best)
            return 0;
    }
    if (i < m->seg_count) {
        const int got = mesoi_ref_segment_intersect(&m->segs[i], m->relief, o, d, tmin, best, h, samples);
        h->index = (int32_t)i;
        return got;
    }
    const meso_ref_ball* b = &m->balls[i - m->seg_count];
    const int n = mesoi_ref_ray_sphere(b->center, b->radius, o, d, ts);
    for (int j = 0; j < n; ++j) {
        if (ts[j] < tmin || ts[j] > best)
            continue;
        memset(h, 0, sizeof(*h));
        h->t = ts[j];
        for (int k = 0; k < 3; ++k) {
            h->p[k] = o[k] + ts[j] * d[k];
            h->normal[k] = h->p[k] - b->center[k];
        }
        normalize3(h->normal);
        memcpy(h->shading_normal, h->normal, sizeof(h->normal));
        h->index = (int32_t)(i - m->seg_count);
        h->part = MESO_REF_PART_BALL;
        return 1;
    }
    return 0;
}

static int model_intersect(const model_ref* m, const double o[3], const double d[3], double tmin, double tmax,
    meso_ref_frustum_hit* hit)
{
    int found = 0;
    double best = tmax;
    uint32_t samples = 0;
    meso_ref_frustum_hit h;
    for (uint32_t i = 0; i < m->seg_count + m->ball_count; ++i)
        if (item_intersect(m, i, 0, o, d, tmin, best, &h, &samples)) {
            best = h.t;
            *hit = h;
            found = 1;
        }
    if (found || m->relief)
        hit->steps = samples;
    return found;
}

int meso_ref_frusta_intersect(const meso_ref_frustum* segs, uint32_t seg_count, const meso_ref_ball* balls,
    uint32_t ball_count, const double o[3], const double d[3], double tmin, double tmax, meso_ref_frustum_hit* hit)
{
    const model_ref m = {segs, seg_count, balls, ball_count, NULL};
    return model_intersect(&m, o, d, tmin, tmax, hit);
}

int meso_ref_frusta_intersect_relief(const meso_ref_frustum* segs, uint32_t seg_count, const meso_ref_ball* balls,
    uint32_t ball_count, const meso_ref_relief* relief, const double o[3], const double d[3], double tmin,
    double tmax, meso_ref_frustum_hit* hit)
{
    const model_ref m = {segs, seg_count, balls, ball_count, relief};
    return model_intersect(&m, o, d, tmin, tmax, hit);
}

/* >>records ---------------------------------------------------------------- */

void meso_ref_frustum_from_rec(const meso_frustum_rec* rec, meso_ref_frustum* out)
{
    memset(out, 0, sizeof(*out));
    for (int i = 0; i < 3; ++i) {
        out->c0[i] = rec->center[0][i];
        out->c1[i] = rec->center[1][i];
        out->frame_x[i] = rec->frame_x[i];
    }
    out->r0 = rec->radius[0];
    out->r1 = rec->radius[1];
    for (int e = 0; e < 2; ++e) {
        for (int i = 0; i < 3; ++i)
            out->plane_n[e][i] = rec->plane[e][i];
        out->plane_d[e] = dot3(out->plane_n[e], e ? out->c1 : out->c0);
    }
    out->cap[0] = (rec->flags & MESO_FSEG_CAP0) != 0;
    out->cap[1] = (rec->flags & MESO_FSEG_CAP1) != 0;
    out->u_offset = rec->u_offset;
    out->twist = rec->twist;
    out->u_scale = rec->u_scale;
    out->v_offset = rec->v_offset;
    out->v_scale = rec->v_scale;
    out->relief_depth = rec->relief_depth;
}

void meso_ref_ball_from_rec(const meso_frustum_ball_rec* rec, meso_ref_ball* out)
{
    for (int i = 0; i < 3; ++i)
        out->center[i] = rec->center[i];
    out->radius = rec->radius;
}

/* >>files ------------------------------------------------------------------ */

static double srgb_to_linear(double x)
{
    return x <= 0.04045 ? x / 12.92 : pow((x + 0.055) / 1.055, 2.4);
}

/* COLR chunk ci: texels to linear RGB, and their mean. */
static meso_result load_color(meso_file* f, int32_t ci, uint32_t object_id, meso_ref_frusta* out, meso_error* err)
{
    const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)ci);
    if (c->dtype != MESO_DTYPE_U8 || c->components != 4 || c->dims[2] != 1 || c->dims[0] == 0 || c->dims[1] == 0)
        return mesoi_ref_fail(err, MESO_ERR_UNSUPPORTED, "frusta", object_id,
            "COLR is not U8 x 4, W x H x 1 (FORMAT.md 7.2)");
    void* raw = NULL;
    size_t size = 0;
    meso_result r = mesoi_ref_read_whole(f, ci, &raw, &size, err);
    if (r != MESO_OK)
        return r;
    const size_t n = (size_t)c->dims[0] * c->dims[1];
    out->color = size == 4 * n ? malloc(sizeof(double) * 3 * n) : NULL;
    if (!out->color) {
        free(raw);
        return mesoi_ref_fail(err, size == 4 * n ? MESO_ERR_OUT_OF_MEMORY : MESO_ERR_CORRUPT, "frusta", object_id,
            "COLR: out of memory or a payload of the wrong size");
    }
    const uint8_t* px = raw;
    double sum[3] = {0, 0, 0};
    for (size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            out->color[3 * i + (size_t)k] = srgb_to_linear(px[4 * i + (size_t)k] / 255.0);
            sum[k] += out->color[3 * i + (size_t)k];
        }
    free(raw);
    for (int k = 0; k < 3; ++k)
        out->ball_color[k] = sum[k] / (double)n;
    out->color_w = c->dims[0];
    out->color_h = c->dims[1];
    return MESO_OK;
}

static int wrap_index(double i, uint32_t n)
{
    double m = fmod(i, (double)n);
    if (m < 0)
        m += n;
    const int k = (int)m;
    return k >= (int)n ? (int)n - 1 : k;
}

int meso_ref_frusta_albedo(const meso_ref_frusta* m, const meso_ref_frustum_hit* hit, double albedo[3])
{
    if (!m || !m->color || !hit)
        return 0;
    if (hit->part == MESO_REF_PART_BALL) {
        memcpy(albedo, m->ball_color, sizeof(m->ball_color));
        return 1;
    }
    double st[2];
    meso_ref_frustum_relief_coords(&m->segs[hit->index], hit->p, &st[0], &st[1], NULL);
    const uint32_t n[2] = {m->color_w, m->color_h};
    int i0[2], i1[2];
    double fr[2];
    for (int a = 0; a < 2; ++a) {
        const double x = st[a] * n[a] - 0.5, fl = floor(x);
        fr[a] = x - fl;
        i0[a] = wrap_index(fl, n[a]);
        i1[a] = wrap_index(fl + 1, n[a]);
    }
    for (int k = 0; k < 3; ++k) {
        const double* c = m->color;
        const size_t W = m->color_w;
        const double c00 = c[3 * ((size_t)i0[1] * W + (size_t)i0[0]) + (size_t)k];
        const double c10 = c[3 * ((size_t)i0[1] * W + (size_t)i1[0]) + (size_t)k];
        const double c01 = c[3 * ((size_t)i1[1] * W + (size_t)i0[0]) + (size_t)k];
        const double c11 = c[3 * ((size_t)i1[1] * W + (size_t)i1[0]) + (size_t)k];
        albedo[k] = (1 - fr[1]) * ((1 - fr[0]) * c00 + fr[0] * c10) + fr[1] * ((1 - fr[0]) * c01 + fr[0] * c11);
    }
    return 1;
}

meso_result meso_ref_frusta_load(meso_file* f, uint32_t object_id, meso_ref_frusta* out, meso_error* err)
{
    return meso_ref_frusta_load_level(f, object_id, 0, out, err);
}

meso_result meso_ref_frusta_load_level(meso_file* f, uint32_t object_id, uint16_t lod, meso_ref_frusta* out,
                                       meso_error* err)
{
    if (!f || !out)
        return mesoi_ref_fail(err, MESO_ERR_INVALID_ARG, "frusta", object_id, "NULL file or output");
    memset(out, 0, sizeof(*out));
    meso_object_record rec;
    meso_result r = mesoi_ref_object(f, object_id, MESO_OBJECT_FRUSTA, "frusta", &rec, err);
    if (r != MESO_OK)
        return r;
    memcpy(out->bbox_min, rec.bbox_min, sizeof(out->bbox_min));
    memcpy(out->bbox_max, rec.bbox_max, sizeof(out->bbox_max));
    const int32_t fi = meso_file_find_level(f, MESO_CHUNK_FRUS, object_id, lod);
    const int32_t si = meso_file_find_level(f, MESO_CHUNK_FSEG, object_id, lod);
    const int32_t bi = meso_file_find_level(f, MESO_CHUNK_BALL, object_id, lod);
    const int32_t ri = meso_file_find_level(f, MESO_CHUNK_RELF, object_id, lod);
    const int32_t ci = meso_file_find_level(f, MESO_CHUNK_COLR, object_id, lod);
    if (fi < 0 || si < 0)
        return mesoi_ref_fail(err, MESO_ERR_NOT_FOUND, "frusta", object_id, fi < 0 ? "no FRUS chunk" : "no FSEG chunk");
    void *frus = NULL, *fseg = NULL, *ball = NULL;
    size_t nf = 0, ns = 0, nb = 0;
    if ((r = mesoi_ref_read_whole(f, fi, &frus, &nf, err)) != MESO_OK ||
        (r = mesoi_ref_read_whole(f, si, &fseg, &ns, err)) != MESO_OK ||
        (bi >= 0 && (r = mesoi_ref_read_whole(f, bi, &ball, &nb, err)) != MESO_OK))
        goto done;
    if (nf % MESO_FRUS_RECORD_SIZE || ns % MESO_FSEG_RECORD_SIZE || nb % MESO_BALL_RECORD_SIZE ||
        nf / MESO_FRUS_RECORD_SIZE != ns / MESO_FSEG_RECORD_SIZE || nf == 0) {
        r = mesoi_ref_fail(err, MESO_ERR_CORRUPT, "frusta", object_id,
            "FRUS and FSEG must hold the same (non-zero) number of records");
        goto done;
    }
    out->seg_count = (uint32_t)(nf / MESO_FRUS_RECORD_SIZE);
    out->ball_count = (uint32_t)(nb / MESO_BALL_RECORD_SIZE);
    out->segs = malloc(sizeof(*out->segs) * out->seg_count);
    out->balls = out->ball_count ? malloc(sizeof(*out->balls) * out->ball_count) : NULL;
    if (!out->segs || (out->ball_count && !out->balls)) {
        r = mesoi_ref_fail(err, MESO_ERR_OUT_OF_MEMORY, "frusta", object_id, "out of memory");
        goto done;
    }
    for (uint32_t i = 0; i < out->seg_count; ++i) {
        meso_frustum_rec fr;
        meso_frustum_rec_decode((const uint8_t*)frus + (size_t)i * MESO_FRUS_RECORD_SIZE,
            (const uint8_t*)fseg + (size_t)i * MESO_FSEG_RECORD_SIZE, &fr);
        meso_ref_frustum_from_rec(&fr, &out->segs[i]);
    }
    for (uint32_t i = 0; i < out->ball_count; ++i) {
        meso_frustum_ball_rec br;
        meso_frustum_ball_decode((const uint8_t*)ball + (size_t)i * MESO_BALL_RECORD_SIZE, &br);
        meso_ref_ball_from_rec(&br, &out->balls[i]);
    }
    if (ri >= 0) {
        const meso_chunk_info* rc = meso_file_chunk(f, (uint32_t)ri);
        r = rc->dims[2] != 1 ? MESO_ERR_UNSUPPORTED : mesoi_ref_read_unorm(f, ri, &out->relief_values, err);
        if (r == MESO_ERR_UNSUPPORTED)
            r = mesoi_ref_fail(err, r, "frusta", object_id, "RELF is not U8 or U16 x 1, W x H x 1 (FORMAT.md 7.2)");
        if (r != MESO_OK)
            goto done;
        out->relief.height.kind = 1;
        out->relief.height.w = rc->dims[0];
        out->relief.height.h = rc->dims[1];
        out->relief.height.d = 1;
        out->relief.height.values = out->relief_values;
    }
    if (ci >= 0 && (r = load_color(f, ci, object_id, out, err)) != MESO_OK)
        goto done;
    r = MESO_OK;
done:
    free(frus);
    free(fseg);
    free(ball);
    if (r != MESO_OK)
        meso_ref_frusta_free(out);
    return r;
}

void meso_ref_frusta_free(meso_ref_frusta* m)
{
    if (!m)
        return;
    free(m->segs);
    free(m->balls);
    free(m->relief_values);
    free(m->color);
    memset(m, 0, sizeof(*m));
}

/* >>render ----------------------------------------------------------------- */

/* A bounding-volume hierarchy (ref_bvh.h) over the items' bounding spheres
 * (as boxes); items without a bound are tested for every ray. */
typedef struct frusta_scene {
    const meso_ref_frusta* obj;
    model_ref m;
    mesoi_ref_camera cam;
    double (*box)[6];      /* per item: lo, hi */
    uint32_t* order;       /* the bounded items */
    uint32_t bounded;
    uint32_t* unbounded;
    uint32_t unbounded_count;
    mesoi_ref_bvh bvh;
} frusta_scene;

typedef struct trace_ctx {
    const frusta_scene* sc;
    const double *o, *d;
    meso_ref_frustum_hit* hit;
    int found;
    uint32_t samples;
} trace_ctx;

static void trace_leaf(const void* user, const uint32_t* items, uint32_t count, double* tmax)
{
    trace_ctx* c = (trace_ctx*)user;
    meso_ref_frustum_hit h;
    for (uint32_t i = 0; i < count; ++i)
        if (item_intersect(&c->sc->m, items[i], 0, c->o, c->d, 0, *tmax, &h, &c->samples)) {
            *tmax = h.t;
            *c->hit = h;
            c->found = 1;
        }
}

static int scene_trace(const frusta_scene* sc, const double o[3], const double d[3], meso_ref_frustum_hit* hit)
{
    double best = 1.0; /* the far plane */
    trace_ctx c = {sc, o, d, hit, 0, 0};
    meso_ref_frustum_hit h;
    for (uint32_t k = 0; k < sc->unbounded_count; ++k)
        if (item_intersect(&sc->m, sc->unbounded[k], 1, o, d, 0, best, &h, &c.samples)) {
            best = h.t;
            *hit = h;
            c.found = 1;
        }
    const double inv[3] = {1 / d[0], 1 / d[1], 1 / d[2]};
    mesoi_ref_bvh_trace(&sc->bvh, o, d, inv, &best, trace_leaf, &c);
    return c.found;
}

static void frusta_row(const frusta_scene* sc, meso_ref_image* img, int y)
{
    const int W = img->width, H = img->height;
    for (int x = 0; x < W; ++x) {
        const size_t px = (size_t)y * (size_t)W + (size_t)x;
        double o[3], d[3];
        mesoi_ref_pixel_ray(&sc->cam, x, y, W, H, o, d);
        meso_ref_frustum_hit h;
        if (!scene_trace(sc, o, d, &h)) {
            mesoi_ref_image_miss(img, px);
            continue;
        }
        img->depth[px] = mesoi_ref_depth(&sc->cam, h.p);
        img->coverage[px] = 1;
        for (int c = 0; c < 3; ++c)
            img->hit[3 * px + (size_t)c] = (float)h.p[c];
        const double w = h.relief ? fmin(fmax(h.w, 0.0), 1.0) : 1.0;
        mesoi_ref_camera cam = sc->cam;
        meso_ref_frusta_albedo(sc->obj, &h, cam.albedo);
        mesoi_ref_shade(&cam, d, h.shading_normal, w, &img->rgb[3 * px], &img->normal[3 * px]);
    }
}

/* mesoi_ref_rows' callback: pixels are independent and read only the
 * shared scene, so the image does not depend on the partition. (pthreads
 * rather than OpenMP: this file is linked into C++ executables, and a
 * clang-built object needs clang's OpenMP runtime, which the g++ driver
 * does not link.) */
typedef struct row_ctx {
    const frusta_scene* sc;
    meso_ref_image* img;
} row_ctx;

static void row_cb(const void* user, int y)
{
    const row_ctx* r = user;
    frusta_row(r->sc, r->img, y);
}

meso_result meso_ref_frusta_render(const meso_ref_frusta* m, const meso_ref_view* v, meso_ref_image* out)
{
    if (!m || !v || !out || v->width < 1 || v->height < 1 || v->width > 65536 || v->height > 65536 ||
        (m->seg_count && !m->segs) || (m->ball_count && !m->balls))
        return MESO_ERR_INVALID_ARG;
    memset(out, 0, sizeof(*out));
    frusta_scene sc;
    memset(&sc, 0, sizeof(sc));
    sc.obj = m;
    sc.m = (model_ref){m->segs, m->seg_count, m->balls, m->ball_count, &m->relief};
    if (!mesoi_ref_camera_init(v, &sc.cam))
        return MESO_ERR_INVALID_ARG;
    const uint32_t n = m->seg_count + m->ball_count;
    sc.box = malloc(sizeof(*sc.box) * (n ? n : 1));
    sc.order = malloc(sizeof(*sc.order) * (n ? n : 1));
    sc.unbounded = malloc(sizeof(*sc.unbounded) * (n ? n : 1));
    meso_result r = mesoi_ref_image_alloc(out, v->width, v->height);
    if (r == MESO_OK && (!sc.box || !sc.order || !sc.unbounded))
        r = MESO_ERR_OUT_OF_MEMORY;
    if (r != MESO_OK)
        goto done;
    for (uint32_t i = 0; i < n; ++i) {
        double c[3], rad;
        if (!item_bound(&sc.m, i, c, &rad)) {
            sc.unbounded[sc.unbounded_count++] = i;
            continue;
        }
        for (int k = 0; k < 3; ++k) {
            sc.box[i][k] = c[k] - rad;
            sc.box[i][3 + k] = c[k] + rad;
        }
        sc.order[sc.bounded++] = i;
    }
    r = mesoi_ref_bvh_build(&sc.bvh, (const double(*)[6])sc.box, sc.order, sc.bounded);
    if (r != MESO_OK)
        goto done;
    const row_ctx rc = {&sc, out};
    mesoi_ref_rows(v->height, v->threads, row_cb, &rc);
done:
    free(sc.box);
    free(sc.order);
    free(sc.unbounded);
    mesoi_ref_bvh_free(&sc.bvh);
    if (r != MESO_OK)
        meso_ref_image_free(out);
    return r;
}
