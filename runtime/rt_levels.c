/*
 * rt_levels.c — levels of detail in libmeso (FORMAT.md §7.10): a levelled
 * object (meso_rt_load_object_levels) holds the file's level table and one
 * object slot per uploaded level; each draw picks the coarsest level whose
 * projected error is at most the draw's pixel error and uploads it on first
 * use.
 *
 * The projected error follows meshoptimizer's cluster-LOD demo and 3D
 * Tiles (../shared/notes/lod-anchors.md): a level's object-space error e,
 * at the distance d from the eye to the nearest point of the level's
 * bounding box, covers e / d · proj[1][1] · H / 2 pixels of a viewport H
 * pixels high (perspective: proj[1][1] = cot(fovy / 2); the model and view
 * matrices are similarities, whose scales multiply e and d alike); an
 * orthographic projection (proj[3][3] = 1) has no distance term:
 * e · s · proj[1][1] · H / 2, s the two scales. The box, not the bounding
 * sphere the demo and 3D Tiles use: every point the level draws lies in
 * it, so the bound holds as well, and its nearest point is up to a
 * half-diagonal farther (obj 12 of bench_lod_scene, a cells object 4.8
 * sizes away, drew its 377 KB level 0 at 1 px by the sphere's 1.04 px;
 * by the box its level 1 is within the pixel).
 * The eye inside a level's box (d = 0) makes its error unbounded, so a
 * level is never coarser than the object the camera is in allows. Since
 * the pixel count depends on H, a smaller window picks coarser levels for
 * the same view, as it should (the 3D Tiles bug in the notes is the
 * opposite: an error in pixels that ignored the window).
 *
 * Instanced draws pick one level for all instances: the finest any
 * instance needs.
 */
#include "rt_internal.h"

#include <math.h>
#include <string.h>

static void levels_free(meso_rt* rt, mesoi_levels* lv)
{
    if (!lv)
        return;
    mesoi_rt_free(rt, lv->info);
    mesoi_rt_free(rt, lv->slot);
    mesoi_rt_free(rt, lv->failed);
    mesoi_rt_free(rt, lv->used);
    mesoi_rt_free(rt, lv->pending);
    mesoi_rt_free(rt, lv->request);
    mesoi_rt_free(rt, lv->own_base);
    mesoi_rt_free(rt, lv->gpu);
    mesoi_rt_free(rt, lv);
}

/* A level's GPU bytes before its upload: no fewer than it will hold. A
 * mesh level (form mesh) draws its MESH and VCOL; a native level whatever
 * its kind resolves at its lod (FORMAT.md §7.10), of every type the object
 * has but the parts' and those read into host memory only. */
static uint64_t level_estimate(const meso_rt* rt, meso_file* f, uint32_t id, uint32_t kind,
                               const meso_level_info* info)
{
    uint64_t sum = 0;
    const uint16_t lod = info->rec.lod;
    for (uint32_t i = 0; i < meso_file_chunk_count(f); ++i) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        const uint32_t t = c->type;
        if (c->object != id || t == MESO_CHUNK_PRTS || t == MESO_CHUNK_PTRI || t == MESO_CHUNK_PMSH ||
            t == MESO_CHUNK_PVCL || t == MESO_CHUNK_ANIM || t == MESO_CHUNK_TXFR || t == MESO_CHUNK_DSFR ||
            (info->rec.form == MESO_LEVEL_MESH && t != MESO_CHUNK_MESH && t != MESO_CHUNK_VCOL))
            continue;
        const int32_t k = meso_file_find_level(f, t, id, lod);
        if (k != (int32_t)i)
            continue; /* not the chunk of this type the level resolves to */
        sum += mesoi_gpu_estimate(rt, c);
        /* A native shell level also holds its prisms sorted and their
         * neighbours (rt_shell.c order_buf, adj_buf): 24 bytes a triangle,
         * counted as the MESH's decoded bytes once more (12 of those a
         * triangle, 24 or more a vertex, about half a vertex a triangle). */
        if (t == MESO_CHUNK_MESH && kind == MESO_OBJECT_SHELL && info->rec.form == MESO_LEVEL_NATIVE &&
            rt->hull_reject_ok)
            sum += c->decoded_size;
    }
    return sum;
}

/* Upload level `l` into its own slot. A failure is remembered (a file that
 * cannot give the level now will not give it on the next frame either);
 * bytes that have not arrived yet are not: the level is asked for again
 * on a later frame. */
meso_result mesoi_levels_upload(meso_rt* rt, mesoi_levels* lv, uint32_t l)
{
    if (lv->slot[l].id)
        return MESO_OK;
    meso_rt_object slot = {0};
    uint64_t gpu = 0;
    const meso_result r = mesoi_levels_load(rt, lv, l, &slot, &gpu);
    if (r == MESO_OK)
        mesoi_levels_publish(lv, l, slot, gpu);
    return r;
}

void mesoi_levels_publish(mesoi_levels* lv, uint32_t l, meso_rt_object slot, uint64_t gpu)
{
    lv->slot[l] = slot;
    lv->gpu[l] = gpu;
}

meso_result mesoi_levels_load(meso_rt* rt, mesoi_levels* lv, uint32_t l, meso_rt_object* slot, uint64_t* gpu)
{
    if (lv->failed[l])
        return MESO_ERR_NOT_FOUND;
    if (lv->pending[l] == rt->frame + 1 && !rt->prefetch)
        return MESO_ERR_PENDING; /* asked already this frame */
    const uint32_t kind = lv->info[l].rec.form == MESO_LEVEL_MESH ? (uint32_t)MESO_OBJECT_MESH : lv->rec.kind;
    const meso_result r = mesoi_load_slot(rt, lv->file, &lv->rec, kind, lv->info[l].rec.lod, slot);
    if (!rt->prefetch && r != MESO_ERR_PENDING)
        lv->bytes_read += lv->info[l].bytes; /* a request counts its own reads */
    if (r == MESO_OK) {
        *gpu = mesoi_lookup(rt, *slot)->gpu_bytes;
        rt->bytes_resident += *gpu;
    } else if (r == MESO_ERR_PENDING) {
        lv->pending[l] = rt->frame + 1;
    } else {
        lv->failed[l] = 1;
        mesoi_log(rt, MESO_LOG_WARNING, MESO_LOGITEM_CHUNK_READ_FAILED,
                  "object %u: level %u could not be uploaded; drawing the nearest level uploaded", lv->rec.id, l);
    }
    return r;
}

meso_result meso_rt_load_object_levels(meso_rt* rt, meso_file* f, uint32_t object_id, meso_rt_object* out)
{
    if (!out)
        return MESO_ERR_INVALID_ARG;
    out->id = 0;
    if (!rt || !f || object_id == 0) {
        if (rt)
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                      "meso_rt_load_object_levels: NULL file or object 0");
        return MESO_ERR_INVALID_ARG;
    }
    mesoi_levels* lv = mesoi_rt_alloc(rt, sizeof *lv);
    if (!lv)
        return MESO_ERR_OUT_OF_MEMORY;
    memset(lv, 0, sizeof *lv);
    lv->file = f;
    lv->last_drawn = -1;
    meso_result r = mesoi_find_record(rt, f, object_id, &lv->rec);
    if (r == MESO_OK && !mesoi_kind_drawn(lv->rec.kind)) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_OBJECT_NOT_FOUND,
                  "object %u has kind %u; this runtime draws MESH, SHELL, CELLS and FRUSTA objects", object_id,
                  lv->rec.kind);
        r = MESO_ERR_UNSUPPORTED;
    }
    meso_error err;
    if (r == MESO_OK && (r = meso_file_levels(f, object_id, NULL, 0, &lv->count, &err)) != MESO_OK &&
        r != MESO_ERR_PENDING)
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED, "%s", err.message);
    if (r == MESO_OK) {
        lv->info = mesoi_rt_alloc(rt, sizeof(meso_level_info) * lv->count);
        lv->slot = mesoi_rt_alloc(rt, sizeof(meso_rt_object) * lv->count);
        lv->failed = mesoi_rt_alloc(rt, lv->count);
        lv->used = mesoi_rt_alloc(rt, sizeof(uint64_t) * lv->count);
        lv->pending = mesoi_rt_alloc(rt, sizeof(uint64_t) * lv->count);
        lv->request = mesoi_rt_alloc(rt, sizeof(struct meso_rt_request*) * lv->count);
        lv->own_base = mesoi_rt_alloc(rt, lv->count);
        lv->gpu = mesoi_rt_alloc(rt, sizeof(uint64_t) * 2 * lv->count);
        if (!lv->info || !lv->slot || !lv->failed || !lv->used || !lv->pending || !lv->request || !lv->own_base ||
            !lv->gpu)
            r = MESO_ERR_OUT_OF_MEMORY;
    }
    if (r == MESO_OK) {
        memset(lv->slot, 0, sizeof(meso_rt_object) * lv->count);
        memset(lv->failed, 0, lv->count);
        memset(lv->used, 0, sizeof(uint64_t) * lv->count);
        memset(lv->pending, 0, sizeof(uint64_t) * lv->count);
        memset(lv->request, 0, sizeof(struct meso_rt_request*) * lv->count);
        if ((r = meso_file_levels(f, object_id, lv->info, lv->count, &lv->count, &err)) != MESO_OK)
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED, "%s", err.message);
        const int32_t mesh0 = meso_file_find_level(f, MESO_CHUNK_MESH, object_id, 0);
        for (uint32_t l = 0; l < lv->count; ++l) {
            lv->own_base[l] = lv->rec.kind == MESO_OBJECT_SHELL && lv->info[l].rec.form == MESO_LEVEL_NATIVE &&
                              meso_file_find_level(f, MESO_CHUNK_MESH, object_id, (uint16_t)l) != mesh0;
            lv->gpu[l] = lv->gpu[lv->count + l] = level_estimate(rt, f, object_id, lv->rec.kind, &lv->info[l]);
        }
    }
    /* A mesh or shell object's parts table (rt_parts.c), read with the levels
     * table: no draw reads the file under stream requests. */
    if (r == MESO_OK && (lv->rec.kind == MESO_OBJECT_MESH || lv->rec.kind == MESO_OBJECT_SHELL))
        r = mesoi_parts_load(rt, f, &lv->rec, &lv->parts);
    /* The coarsest level now, so that every draw has something to show; a
     * stream that has not delivered it yet shows the object once it has. */
    if (r == MESO_OK && rt->stream_requests)
        r = mesoi_stream_request(rt, lv, lv->count - 1);
    else if (r == MESO_OK && (r = mesoi_levels_upload(rt, lv, lv->count - 1)) == MESO_ERR_PENDING)
        r = MESO_OK;
    meso_rt_object parent = {0};
    if (r == MESO_OK)
        r = mesoi_empty_slot(rt, &lv->rec, &parent);
    if (r != MESO_OK) {
        if (lv->request)
            mesoi_stream_detach(rt, lv); /* the coarsest level's request, filed above */
        mesoi_parts_free(rt, lv->parts);
        for (uint32_t l = 0; lv->slot && l < lv->count; ++l)
            meso_rt_release_object(rt, lv->slot[l]);
        levels_free(rt, lv);
        return r;
    }
    mesoi_lookup(rt, parent)->levels = lv;
    *out = parent;
    return MESO_OK;
}

void mesoi_levels_release(meso_rt* rt, mesoi_object* o)
{
    mesoi_levels* lv = o->levels;
    if (!lv)
        return;
    o->levels = NULL;
    mesoi_stream_detach(rt, lv);
    mesoi_parts_free(rt, lv->parts);
    for (uint32_t l = 0; l < lv->count; ++l)
        if (lv->slot[l].id) {
            meso_rt_release_object(rt, lv->slot[l]);
            rt->bytes_resident -= lv->gpu[l];
        }
    levels_free(rt, lv);
}

/* >>picking --------------------------------------------------------------- */

static const float identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

static int all_zero(const float* m, int n)
{
    for (int i = 0; i < n; ++i)
        if (m[i] != 0.0f)
            return 0;
    return 1;
}

/* Pixels that `error` (object units) covers for a level bounded by
 * [lo, hi] drawn with `model` (column-major, a similarity): error / d ·
 * focal, d the distance in object units from the eye to the nearest point
 * of the box (model and view scale the error and the distance alike, so
 * they cancel). A similarity x -> A x + t with A = s R has the inverse
 * y -> A^T (y - t) / s^2, which takes the eye (the view's origin) back to
 * object space without a general inverse. */
double mesoi_projected_px(double error, const float lo[3], const float hi[3], const float* model,
                          const meso_rt_draw_desc* d, double height)
{
    if (error <= 0.0)
        return 0.0;
    const float* m = all_zero(model, 16) ? identity : model;
    const float* v = d->view;
    const double sm2 = (double)m[0] * m[0] + (double)m[1] * m[1] + (double)m[2] * m[2];
    const double sv2 = (double)v[0] * v[0] + (double)v[1] * v[1] + (double)v[2] * v[2];
    const double focal = fabs((double)d->proj[5]) * 0.5 * height;
    if (d->proj[15] != 0.0f) /* orthographic */
        return error * sqrt(sm2 * sv2) * focal;
    if (!(sm2 > 0.0) || !(sv2 > 0.0))
        return INFINITY;
    double w[3], o[3]; /* the eye in world space, then in object space */
    for (int r = 0; r < 3; ++r)
        w[r] = -((double)v[4 * r] * v[12] + (double)v[4 * r + 1] * v[13] + (double)v[4 * r + 2] * v[14]) / sv2;
    for (int r = 0; r < 3; ++r)
        o[r] = ((double)m[4 * r] * (w[0] - m[12]) + (double)m[4 * r + 1] * (w[1] - m[13]) +
                (double)m[4 * r + 2] * (w[2] - m[14])) /
               sm2;
    double dist2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        const double g = fmax(fmax((double)lo[k] - o[k], o[k] - (double)hi[k]), 0.0);
        dist2 += g * g;
    }
    if (!(dist2 > 0.0))
        return INFINITY;
    return error * focal / sqrt(dist2);
}

/* Whether a draw with `d` may draw level l: a shell level with a base
 * mesh of its own was measured for the smooth mapping (and what shares it:
 * segment only, slices), not for the curved or tetra mappings, which move
 * differently with the base (bake/shell_base_levels.c). */
static int usable(const mesoi_levels* lv, uint32_t l, const meso_rt_draw_desc* d)
{
    return !lv->own_base[l] || (d->shell.technique != MESO_SHELL_CURVED && d->shell.technique != MESO_SHELL_TETRA);
}

/* The coarsest level whose projected error is at most `tau` pixels (for
 * every instance) and that this draw may draw (usable); 0 when none is,
 * or tau < 0. */
static uint32_t choose(const mesoi_levels* lv, const meso_rt_draw_desc* d, const meso_rt_instance* inst,
                       uint32_t count, double tau, double height)
{
    if (tau < 0.0)
        return 0;
    for (uint32_t l = lv->count - 1; l > 0; --l) {
        const meso_level_record* r = &lv->info[l].rec;
        if (!usable(lv, l, d))
            continue;
        double px = 0.0;
        if (inst)
            for (uint32_t i = 0; i < count && px <= tau; ++i)
                px = fmax(px, mesoi_projected_px(r->error, r->bbox_min, r->bbox_max, inst[i].model, d, height));
        else
            px = mesoi_projected_px(r->error, r->bbox_min, r->bbox_max, d->model, d, height);
        if (px <= tau)
            return l;
    }
    return 0;
}

/* >>budget ------------------------------------------------------------------ */

/* Evict the least recently used level or part level (any object's) that no
 * draw of this frame used and that is not its object's coarsest; 0 when
 * there is none. */
int mesoi_evict_one(meso_rt* rt)
{
    mesoi_levels* best = NULL;
    uint32_t best_l = 0;
    int best_part = 0;
    uint64_t oldest = UINT64_MAX;
    for (uint32_t i = 0; i < rt->object_capacity; ++i) {
        mesoi_levels* lv = rt->objects[i].live ? rt->objects[i].levels : NULL;
        for (uint32_t l = 0; lv && l + 1 < lv->count; ++l)
            if (lv->slot[l].id && lv->used[l] != rt->frame + 1 && (!best || lv->used[l] < oldest)) {
                best = lv;
                best_l = l;
                best_part = 0;
                oldest = lv->used[l];
            }
        uint32_t which = 0;
        if (lv && lv->parts && mesoi_parts_oldest(rt, lv->parts, &oldest, &which)) {
            best = lv;
            best_l = which;
            best_part = 1;
        }
    }
    if (!best)
        return 0;
    if (best_part) {
        mesoi_parts_evict(rt, best->parts, best_l);
        return 1;
    }
    meso_rt_release_object(rt, best->slot[best_l]);
    best->slot[best_l].id = 0;
    rt->bytes_resident -= best->gpu[best_l];
    rt->evictions++;
    return 1;
}

int mesoi_make_room(meso_rt* rt, uint64_t bytes)
{
    if (!rt->budget)
        return 1;
    while (rt->bytes_resident + bytes > rt->budget)
        if (!mesoi_evict_one(rt))
            return 0;
    return 1;
}

void meso_rt_frame_end(meso_rt* rt)
{
    if (!rt)
        return;
    uint64_t now = 0, lower = 0;
    for (uint32_t i = 0; i < rt->object_capacity; ++i) {
        const mesoi_levels* lv = rt->objects[i].live ? rt->objects[i].levels : NULL;
        if (!lv || lv->want_frame != rt->frame + 1)
            continue;
        const uint64_t coarsest = lv->gpu[lv->count - 1];
        uint64_t wanted = lv->gpu[lv->want_now]; /* or the parts this frame drew instead (a shell's prisms
                                                    draw with its native level) */
        if (lv->parts && lv->parts_frame == rt->frame + 1) {
            wanted = lv->parts->bytes_wanted;
            wanted += lv->parts_native ? lv->gpu[lv->want_now] : 0;
        }
        now += wanted + (lv->want_now + 1 < lv->count ? coarsest : 0);
        lower += lv->gpu[lv->want_lower] + (lv->want_lower + 1 < lv->count ? coarsest : 0);
    }
    rt->bytes_wanted = now;
    if (rt->budget) {
        if (now > rt->budget)
            rt->tau_scale = fmin(rt->tau_scale * 1.25, 1e6);
        else if (rt->tau_scale > 1.0 && lower <= rt->budget)
            rt->tau_scale = fmax(1.0, rt->tau_scale / 1.1);
        while (rt->bytes_resident > rt->budget && mesoi_evict_one(rt)) {
        }
    }
    rt->frame++;
}

void meso_rt_budget_state_get(const meso_rt* rt, meso_rt_budget_state* out)
{
    if (!out)
        return;
    memset(out, 0, sizeof *out);
    if (!rt)
        return;
    out->budget = rt->budget;
    out->bytes_resident = rt->bytes_resident;
    out->bytes_wanted = rt->bytes_wanted;
    out->pixel_error_scale = rt->tau_scale;
    out->frames = rt->frame;
    out->evictions = rt->evictions;
}

/* The viewport height a draw's pixel error refers to. */
static double draw_height(meso_rt* rt, const meso_rt_draw_desc* d)
{
    if (d->viewport[2] != 0 || d->viewport[3] != 0)
        return d->viewport[3];
    GLint vp[4] = {0, 0, 0, 0};
    rt->gl.GetIntegerv(GL_VIEWPORT, vp);
    return vp[3];
}

uint32_t mesoi_levels_per_instance(meso_rt* rt, meso_rt_object h, const meso_rt_draw_desc* d,
                                   const meso_rt_instance* inst, uint32_t count, uint8_t* level)
{
    const mesoi_object* o = mesoi_lookup(rt, h);
    const double tau = d->pixel_error == 0.0f ? 1.0 : (double)d->pixel_error;
    if (!o || !o->levels || o->levels->count < 2 || o->levels->count > 32 || tau < 0.0 || count < 2)
        return 0;
    const double height = draw_height(rt, d);
    uint32_t seen = 0, distinct = 0;
    for (uint32_t i = 0; i < count; ++i) {
        level[i] = (uint8_t)choose(o->levels, d, inst + i, 1, tau * rt->tau_scale, height);
        distinct += !(seen >> level[i] & 1u);
        seen |= 1u << level[i];
    }
    return distinct;
}

/* The finest whole level from `from` on whose stated error is below
 * `error`, uploaded, or (no stream requests) uploaded now; -1 when there
 * is none. */
static int32_t whole_finer_than(meso_rt* rt, mesoi_levels* lv, uint32_t from, double error)
{
    for (uint32_t l = from; l < lv->count && (double)lv->info[l].rec.error < error; ++l) {
        if (lv->slot[l].id)
            return (int32_t)l;
        if (!rt->stream_requests && !lv->failed[l] && mesoi_make_room(rt, lv->gpu[l]) &&
            mesoi_levels_upload(rt, lv, l) == MESO_OK)
            return (int32_t)l;
    }
    return -1;
}

/* The parts the last pick chose (`ph`, its finest part level `finest`)
 * draw, unless some part had to draw coarser than it wanted (its level
 * still arriving): then the finest whole level from `from` on with a
 * smaller error than the worst part drawn, if one is there, draws instead
 * (a prefix of the file holds whole levels before the parts' finer ones). */
static void draw_parts(meso_rt* rt, mesoi_levels* lv, uint32_t from, int finest, meso_rt_object ph,
                       meso_rt_object* out)
{
    const double fallback = lv->parts->fallback_error;
    const int32_t whole = fallback > 0.0 ? whole_finer_than(rt, lv, from, fallback) : -1;
    if (whole >= 0) {
        lv->last_drawn = whole;
        lv->used[whole] = rt->frame + 1;
        *out = lv->slot[whole];
        return;
    }
    lv->last_drawn = finest;
    lv->parts_frame = rt->frame + 1;
    lv->parts_last = 1;
    lv->parts_native = 0;
    *out = ph;
}

void mesoi_levels_draw_begin(meso_rt* rt, meso_rt_object h)
{
    mesoi_object* o = mesoi_lookup(rt, h);
    if (o && o->levels)
        o->levels->parts_last = 0;
}

meso_result mesoi_levels_pick(meso_rt* rt, meso_rt_object h, const meso_rt_draw_desc* d, const meso_rt_instance* inst,
                              uint32_t count, meso_rt_object* out)
{
    *out = h;
    mesoi_object* o = mesoi_lookup(rt, h);
    if (!o || !o->levels)
        return MESO_OK;
    mesoi_levels* lv = o->levels; /* stable: only the slot table moves */
    const double tau = d->pixel_error == 0.0f ? 1.0 : (double)d->pixel_error;
    const double height = tau >= 0.0 && lv->count > 1 ? draw_height(rt, d) : d->viewport[3];
    const uint32_t want = choose(lv, d, inst, count, tau * rt->tau_scale, height);
    const uint32_t lower = rt->tau_scale > 1.0 ? choose(lv, d, inst, count, tau * fmax(1.0, rt->tau_scale / 1.1), height)
                                               : want;
    if (lv->want_frame != rt->frame + 1) { /* the first draw of the object this frame */
        lv->want_frame = rt->frame + 1;
        lv->want_now = want;
        lv->want_lower = lower;
    } else {
        lv->want_now = want < lv->want_now ? want : lv->want_now;
        lv->want_lower = lower < lv->want_lower ? lower : lv->want_lower;
    }
    /* Stored with parts: the level each part wants for this draw, once
     * (every pick below draws from it). */
    int prisms_wanted = 0;
    const uint64_t parts_bytes =
        lv->parts ? mesoi_parts_want(lv->parts, d, inst, count, tau * rt->tau_scale, height, &prisms_wanted) : 0;
    /* Level 0 of a mesh object stored with parts: each part at its own
     * level (rt_parts.c), when every part has one to draw (draw_parts). */
    int parts_pending = 0; /* streamed parts arriving: no whole level asked for meanwhile */
    if (want == 0 && lv->parts && !lv->parts->shell) {
        meso_rt_object ph;
        const meso_result pr = mesoi_parts_pick(rt, lv, (meso_rt_object){0}, &ph);
        if (pr == MESO_OK) {
            draw_parts(rt, lv, 0, mesoi_parts_finest_patch(lv->parts), ph, out);
            return MESO_OK;
        }
        if (pr == MESO_ERR_OUT_OF_MEMORY)
            return pr;
        parts_pending = pr == MESO_ERR_PENDING;
    }
    /* Coarser than level 0, or a shell none of whose parts wants its
     * prisms: the parts instead where their own levels hold fewer bytes
     * than the whole level (rt_parts.c), no native level needed; a whole
     * level from the wanted one on where some part fell back (draw_parts). */
    if (lv->parts && (want > 0 || lv->parts->shell) && !prisms_wanted && parts_bytes < lv->info[want].bytes) {
        meso_rt_object ph;
        const meso_result pr = mesoi_parts_pick(rt, lv, (meso_rt_object){0}, &ph);
        if (pr == MESO_ERR_OUT_OF_MEMORY)
            return pr;
        const int finest = pr == MESO_OK ? mesoi_parts_finest_patch(lv->parts) : -1;
        if (finest >= 0) {
            draw_parts(rt, lv, want, finest, ph, out);
            return MESO_OK;
        }
        parts_pending |= pr == MESO_ERR_PENDING;
    }
    /* The level wanted, else the finest coarser one that can be had, else
     * the nearest finer one uploaded before. With stream requests, a level
     * not uploaded is requested and never read here. */
    int32_t got = -1;
    int waiting = parts_pending; /* some level (or part level) is still arriving */
    for (uint32_t l = want; got < 0 && l < lv->count; ++l) {
        if (!usable(lv, l, d)) {
            continue;
        } else if (lv->slot[l].id) {
            got = (int32_t)l;
        } else if (lv->failed[l] || parts_pending) {
            continue; /* parts arriving: whole levels only as uploaded */
        } else if (rt->stream_requests) {
            /* The finest level at or above the wanted one that can still
             * be had (the wanted one unless it failed). */
            if (!waiting && mesoi_stream_request(rt, lv, l) != MESO_OK)
                return MESO_ERR_OUT_OF_MEMORY;
            waiting = 1;
        } else if (lv->pending[l] == rt->frame + 1) {
            waiting = 1; /* asked this frame already: no eviction for it */
        } else if (mesoi_make_room(rt, lv->gpu[l])) {
            const meso_result r = mesoi_levels_upload(rt, lv, l);
            if (r == MESO_OK)
                got = (int32_t)l;
            waiting |= r == MESO_ERR_PENDING;
        }
    }
    for (uint32_t l = want; got < 0 && l-- > 0;)
        if (lv->slot[l].id && usable(lv, l, d))
            got = (int32_t)l;
    if (got < 0) {
        out->id = 0; /* nothing has arrived yet: nothing to draw */
        return waiting ? MESO_OK : MESO_ERR_NOT_FOUND;
    }
    lv->last_drawn = got;
    lv->used[got] = rt->frame + 1;
    *out = lv->slot[got];
    /* A shell drawing a native level, stored with parts: each part its
     * prisms (with this level) or its stand-in patch (rt_parts.c), where
     * some part is far enough for its patch. Smooth and curved shells only:
     * the prisms of a subset are drawn in the order the whole set is
     * sorted in, which tetra and segment do not use (their ties on shared
     * faces keep the mesh's order), and only where there is a sorted copy
     * to draw them from (rt->hull_reject_ok). The parts' prism lists
     * number level 0's base triangles: not with a level's own base mesh. */
    if (lv->parts && lv->parts->shell && lv->info[got].rec.form == MESO_LEVEL_NATIVE && !lv->own_base[got] &&
        rt->hull_reject_ok &&
        (d->shell.technique == MESO_SHELL_SMOOTH || d->shell.technique == MESO_SHELL_CURVED)) {
        meso_rt_object ph;
        const meso_result pr = mesoi_parts_pick(rt, lv, *out, &ph);
        if (pr == MESO_ERR_OUT_OF_MEMORY)
            return pr;
        if (pr == MESO_OK && mesoi_parts_coarse(lv->parts)) {
            lv->parts_frame = rt->frame + 1;
            lv->parts_last = 1;
            lv->parts_native = 1;
            *out = ph;
        }
    }
    return MESO_OK;
}

meso_result meso_rt_levels_state_get(const meso_rt* rt, meso_rt_object h, meso_rt_levels_state* out)
{
    const mesoi_object* o = mesoi_lookup(rt, h);
    if (!o || !out)
        return MESO_ERR_INVALID_ARG;
    memset(out, 0, sizeof *out);
    const mesoi_levels* lv = o->levels;
    if (!lv) {
        out->level_count = 1;
        out->resident_mask = 1;
        out->last_drawn = 0;
        return MESO_OK;
    }
    out->level_count = lv->count;
    out->last_drawn = lv->last_drawn;
    out->bytes_read = lv->bytes_read;
    if (lv->parts) {
        uint64_t read = 0;
        out->bytes_resident += mesoi_parts_bytes(lv->parts, &read);
        out->bytes_read += read;
    }
    if (lv->parts)
        out->gpu_bytes_resident += mesoi_parts_gpu(lv->parts, &out->gpu_bytes_estimated);
    for (uint32_t l = 0; l < lv->count; ++l)
        if (lv->slot[l].id) {
            if (l < 32)
                out->resident_mask |= 1u << l;
            out->bytes_resident += lv->info[l].bytes;
            out->gpu_bytes_resident += lv->gpu[l];
            out->gpu_bytes_estimated += lv->gpu[lv->count + l];
        }
    return MESO_OK;
}
