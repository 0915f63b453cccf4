/*
 * rt_instances.c — many objects per frame (issue 18 item 3): one object
 * drawn with many transforms in one instanced GL draw call
 * (meso_rt_draw_instanced), and a list of objects drawn in one call, sorted
 * so that each program is bound once and the GL state is saved and
 * restored once (meso_rt_draw_list).
 *
 * Instanced draws compute each instance's values on the CPU, in double
 * precision exactly as a single draw computes its uniforms
 * (mesoi_draw_model: object -> clip and back, the light in object space,
 * the model), add the kind's own (the shells' error-bound scale, the
 * frusta's pose slot, the cells' environment rotation) and upload them into
 * one RGBA32F texture buffer, MESOI_INSTANCE_TEXELS texels per instance,
 * that shaders/instance.glsl reads by gl_InstanceID in the vertex stage and
 * by a flat varying in the fragment stage. The shaders are the ones a
 * single draw uses (u_instanced selects the buffer over the uniforms), so
 * an instance draws the same values a single draw with its model would:
 * tests/gl/test_rt_instances.c compares the images.
 */
#include "rt_internal.h"

#include <stdlib.h>
#include <string.h>

/* >>instance buffer ---------------------------------------------------------- */

/* The staging array for `count` instances (grown, never shrunk). */
static float* staging(meso_rt* rt, uint32_t count)
{
    const size_t need = (size_t)count * MESOI_INSTANCE_TEXELS * 4;
    if (need > rt->inst_texels_capacity) {
        float* grown = mesoi_rt_alloc(rt, need * sizeof(float));
        if (!grown)
            return NULL;
        mesoi_rt_free(rt, rt->inst_texels);
        rt->inst_texels = grown;
        rt->inst_texels_capacity = need;
    }
    return rt->inst_texels;
}

/* Uploads `floats` of the staging array into the instance buffer (made on
 * first use). A buffer large enough is orphaned (glBufferData with no data:
 * the driver renames it instead of waiting for the previous draw) and
 * written, with no query; a larger one is made and its size checked (out
 * of memory shows there, the host's error queue is left alone). The
 * texture buffer binding is put back under MESO_STATE_RESTORE, left at 0
 * otherwise; the texture unit bindings are not touched (the texture is made
 * through unit 0's buffer binding, restored, once). */
static meso_result upload(meso_rt* rt, size_t floats, int restore)
{
    mesoi_gl* gl = &rt->gl;
    GLint prev_buf = 0;
    if (restore)
        gl->GetIntegerv(GL_TEXTURE_BUFFER_BINDING, &prev_buf);
    if (!rt->inst_tex) {
        GLint prev_active = 0, prev_tex = 0;
        gl->GetIntegerv(GL_ACTIVE_TEXTURE, &prev_active);
        gl->ActiveTexture(GL_TEXTURE0);
        gl->GetIntegerv(GL_TEXTURE_BINDING_BUFFER, &prev_tex);
        gl->GenBuffers(1, &rt->inst_buf);
        gl->BindBuffer(GL_TEXTURE_BUFFER, rt->inst_buf);
        gl->BufferData(GL_TEXTURE_BUFFER, 16 * MESOI_INSTANCE_TEXELS, NULL, GL_STREAM_DRAW);
        gl->GenTextures(1, &rt->inst_tex);
        gl->BindTexture(GL_TEXTURE_BUFFER, rt->inst_tex);
        gl->TexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, rt->inst_buf);
        gl->BindTexture(GL_TEXTURE_BUFFER, (GLuint)prev_tex);
        gl->ActiveTexture((GLenum)prev_active);
        rt->inst_capacity = 16 * MESOI_INSTANCE_TEXELS;
    }
    const size_t bytes = floats * sizeof(float);
    gl->BindBuffer(GL_TEXTURE_BUFFER, rt->inst_buf);
    if (bytes <= rt->inst_capacity) {
        gl->BufferData(GL_TEXTURE_BUFFER, (GLsizeiptr)rt->inst_capacity, NULL, GL_STREAM_DRAW);
        gl->BufferSubData(GL_TEXTURE_BUFFER, 0, (GLsizeiptr)bytes, rt->inst_texels);
        gl->BindBuffer(GL_TEXTURE_BUFFER, (GLuint)prev_buf);
        return MESO_OK;
    }
    gl->BufferData(GL_TEXTURE_BUFFER, (GLsizeiptr)bytes, rt->inst_texels, GL_STREAM_DRAW);
    GLint stored = 0;
    gl->GetBufferParameteriv(GL_TEXTURE_BUFFER, GL_BUFFER_SIZE, &stored);
    gl->BindBuffer(GL_TEXTURE_BUFFER, (GLuint)prev_buf);
    if ((size_t)stored != bytes) { /* out of memory: no store; the error queue stays the host's */
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_ERROR, "instances: a %zu-byte buffer could not be created",
                  bytes);
        rt->inst_capacity = 0;
        return MESO_ERR_GL;
    }
    rt->inst_capacity = bytes;
    return MESO_OK;
}

meso_result mesoi_instances_upload(meso_rt* rt, mesoi_draw* ds, mesoi_object* o, const meso_rt_draw_desc* d,
                                   const meso_rt_instance* inst, const uint32_t* order, uint32_t count,
                                   int need_inverse, mesoi_instance_fn fn, void* user, GLuint* tex)
{
    if (!rt->inst_max_texels) /* asked once: no query per draw */
        rt->gl.GetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &rt->inst_max_texels);
    if ((uint64_t)count * MESOI_INSTANCE_TEXELS > (uint64_t)rt->inst_max_texels || count > (uint32_t)INT32_MAX) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                  "meso_rt_draw_instanced: %u instances exceed this context's texture buffer size (%d texels)",
                  count, (int)rt->inst_max_texels);
        return MESO_ERR_INVALID_ARG;
    }
    float* all = staging(rt, count);
    if (!all)
        return MESO_ERR_OUT_OF_MEMORY;
    int mirrored = 0;
    for (uint32_t i = 0; i < count; ++i) {
        const uint32_t j = order ? order[i] : i; /* the caller's index, for the logs */
        meso_result r = mesoi_draw_model(rt, ds, inst[j].model, need_inverse, (int64_t)j);
        if (r != MESO_OK)
            return r;
        if (i == 0)
            mirrored = ds->mirrored;
        else if (ds->mirrored != mirrored) {
            /* The winding (front faces) is one GL state per draw call. */
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                      "meso_rt_draw_instanced: instance %u is %smirrored and instance %u is %s; draw mirrored "
                      "instances in a call of their own",
                      j, ds->mirrored ? "" : "not ", order ? order[0] : 0, mirrored ? "" : "not");
            return MESO_ERR_INVALID_ARG;
        }
        float* t = all + (size_t)i * MESOI_INSTANCE_TEXELS * 4;
        memset(t, 0, sizeof(float) * MESOI_INSTANCE_TEXELS * 4);
        memcpy(t, ds->mvp, sizeof(ds->mvp));
        memcpy(t + 16, ds->inv_mvp, sizeof(ds->inv_mvp));
        memcpy(t + 32, ds->light_obj, sizeof(ds->light_obj));
        memcpy(t + 40, ds->model, sizeof(ds->model));
        if (fn && (r = fn(rt, o, ds, d, &inst[j], j, t, user)) != MESO_OK)
            return r;
    }
    ds->mirrored = mirrored;
    const meso_result r = upload(rt, (size_t)count * MESOI_INSTANCE_TEXELS * 4, ds->restore);
    *tex = r == MESO_OK ? rt->inst_tex : 0;
    return r;
}

void mesoi_instances_destroy(meso_rt* rt)
{
    if (rt->inst_tex)
        rt->gl.DeleteTextures(1, &rt->inst_tex);
    if (rt->inst_buf)
        rt->gl.DeleteBuffers(1, &rt->inst_buf);
    rt->inst_tex = rt->inst_buf = 0;
    rt->inst_capacity = 0;
    mesoi_rt_free(rt, rt->inst_texels);
    rt->inst_texels = NULL;
    rt->inst_texels_capacity = 0;
}

/* >>instanced draws ---------------------------------------------------------- */

static meso_result draw_kind(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d, const meso_rt_instance* inst,
                             uint32_t count)
{
    switch (o->kind) {
    case MESO_OBJECT_SHELL: return mesoi_shell_draw(rt, o, d, inst, count);
    case MESO_OBJECT_FRUSTA: return mesoi_frusta_draw(rt, o, d, inst, count);
    case MESO_OBJECT_CELLS: return mesoi_cells_draw(rt, o, d, inst, count);
    default: return mesoi_mesh_draw(rt, o, d, inst, count);
    }
}

meso_result meso_rt_draw(meso_rt* rt, meso_rt_object h, const meso_rt_draw_desc* d)
{
    mesoi_object* o = mesoi_lookup(rt, h);
    if (!o || !d) {
        if (rt)
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT, "meso_rt_draw: stale handle or NULL desc");
        return MESO_ERR_INVALID_ARG;
    }
    mesoi_levels_draw_begin(rt, h);
    meso_result r = mesoi_levels_pick(rt, h, d, NULL, 0, &h);
    if (r != MESO_OK || h.id == 0)
        return r; /* h.id 0: no level has arrived yet */
    return draw_kind(rt, mesoi_lookup(rt, h), d, NULL, 0);
}

meso_result meso_rt_draw_instanced(meso_rt* rt, meso_rt_object h, const meso_rt_draw_desc* d,
                                   const meso_rt_instance* instances, uint32_t count)
{
    mesoi_object* o = mesoi_lookup(rt, h);
    if (!o || !d || !instances || count == 0) {
        if (rt)
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                      "meso_rt_draw_instanced: stale handle, NULL desc, NULL instances or count 0 (%u)", count);
        return MESO_ERR_INVALID_ARG;
    }
    mesoi_levels_draw_begin(rt, h);
    /* Per-instance levels: each instance draws the level it would draw
     * alone, one instanced call per level, finest first (so the nearest
     * instances fill the depth buffer before the far ones are shaded). */
    uint8_t* level = count > 1 && o->levels ? mesoi_rt_alloc(rt, count) : NULL; /* plain objects: no allocation per draw */
    uint32_t groups = level ? mesoi_levels_per_instance(rt, h, d, instances, count, level) : 0;
    int mirrored0 = 0, mirrored = 0;
    for (uint32_t i = 0; groups > 1 && i < count; ++i) /* refused as one call, not group by group */
        if (!mesoi_model_similarity(instances[i].model, &mirrored) || (i > 0 && mirrored != mirrored0))
            groups = 0;
        else
            mirrored0 = mirrored;
    if (groups < 2) {
        mesoi_rt_free(rt, level);
        meso_result r = mesoi_levels_pick(rt, h, d, instances, count, &h);
        if (r != MESO_OK || h.id == 0)
            return r; /* h.id 0: no level has arrived yet */
        return draw_kind(rt, mesoi_lookup(rt, h), d, instances, count);
    }
    meso_rt_instance* group = mesoi_rt_alloc(rt, sizeof(meso_rt_instance) * count);
    if (!group) {
        mesoi_rt_free(rt, level);
        return MESO_ERR_OUT_OF_MEMORY;
    }
    meso_rt_draw_stats sum = {0}, one;
    meso_rt_draw_desc gd = *d;
    gd.stats = d->stats ? &one : NULL;
    meso_result r = MESO_OK;
    for (uint32_t l = 0, left = groups; r == MESO_OK && left > 0 && l < 32; ++l) {
        uint32_t n = 0;
        for (uint32_t i = 0; i < count; ++i)
            if (level[i] == l)
                group[n++] = instances[i];
        if (!n)
            continue;
        --left;
        meso_rt_object lh = h;
        r = mesoi_levels_pick(rt, h, &gd, group, n, &lh);
        if (r == MESO_OK && lh.id != 0)
            r = draw_kind(rt, mesoi_lookup(rt, lh), &gd, group, n);
        if (r == MESO_OK && d->stats && lh.id != 0) {
            sum.supported |= one.supported;
            sum.fragments += one.fragments;
            sum.steps += one.steps;
            sum.hits += one.hits;
            sum.rejected += one.rejected;
        }
    }
    if (d->stats)
        *d->stats = sum;
    mesoi_rt_free(rt, group);
    mesoi_rt_free(rt, level);
    return r;
}

/* >>lists -------------------------------------------------------------------- */

/* The GL state meso_rt_draw may change (meso_rt.h), saved once per list:
 * units 0..MESOI_DRAW_MAX_UNITS-1 for each texture target the kinds bind. */
static const GLenum list_targets[4] = {GL_TEXTURE_BUFFER, GL_TEXTURE_2D, GL_TEXTURE_3D, GL_TEXTURE_CUBE_MAP};
static const GLenum list_bindings[4] = {GL_TEXTURE_BINDING_BUFFER, GL_TEXTURE_BINDING_2D, GL_TEXTURE_BINDING_3D,
                                        GL_TEXTURE_BINDING_CUBE_MAP};

typedef struct list_state {
    GLint program, vao, func, mask, active, cull_mode, front, tex_buffer;
    mesoi_ssbo ssbo;
    mesoi_image_unit image;
    GLboolean test, cull, color_mask[4];
    GLint bind[MESOI_DRAW_MAX_UNITS][4];
} list_state;

static void list_save(meso_rt* rt, list_state* s)
{
    mesoi_gl* gl = &rt->gl;
    gl->GetIntegerv(GL_CURRENT_PROGRAM, &s->program);
    gl->GetIntegerv(GL_VERTEX_ARRAY_BINDING, &s->vao);
    gl->GetIntegerv(GL_DEPTH_FUNC, &s->func);
    gl->GetIntegerv(GL_DEPTH_WRITEMASK, &s->mask);
    gl->GetIntegerv(GL_ACTIVE_TEXTURE, &s->active);
    gl->GetIntegerv(GL_CULL_FACE_MODE, &s->cull_mode);
    gl->GetIntegerv(GL_FRONT_FACE, &s->front);
    gl->GetIntegerv(GL_TEXTURE_BUFFER_BINDING, &s->tex_buffer);
    if (rt->stats_ok)
        mesoi_ssbo_save(rt, &s->ssbo);
    if (rt->hull_reject_ok)
        mesoi_image_save(rt, &s->image);
    gl->GetBooleanv(GL_COLOR_WRITEMASK, s->color_mask); /* the depth pass masks colour */
    s->test = gl->IsEnabled(GL_DEPTH_TEST);
    s->cull = gl->IsEnabled(GL_CULL_FACE);
    for (int u = 0; u < MESOI_DRAW_MAX_UNITS; ++u) {
        gl->ActiveTexture(GL_TEXTURE0 + (GLenum)u);
        for (int t = 0; t < 4; ++t)
            gl->GetIntegerv(list_bindings[t], &s->bind[u][t]);
    }
}

static void list_restore(meso_rt* rt, const list_state* s)
{
    mesoi_gl* gl = &rt->gl;
    for (int u = 0; u < MESOI_DRAW_MAX_UNITS; ++u) {
        gl->ActiveTexture(GL_TEXTURE0 + (GLenum)u);
        for (int t = 0; t < 4; ++t)
            gl->BindTexture(list_targets[t], (GLuint)s->bind[u][t]);
    }
    gl->ActiveTexture((GLenum)s->active);
    gl->BindVertexArray((GLuint)s->vao);
    gl->UseProgram((GLuint)s->program);
    gl->DepthFunc((GLenum)s->func);
    gl->DepthMask(s->mask ? GL_TRUE : GL_FALSE);
    gl->CullFace((GLenum)s->cull_mode);
    gl->FrontFace((GLenum)s->front);
    gl->BindBuffer(GL_TEXTURE_BUFFER, (GLuint)s->tex_buffer);
    if (rt->stats_ok)
        mesoi_ssbo_restore(rt, &s->ssbo);
    if (rt->hull_reject_ok)
        mesoi_image_restore(rt, &s->image);
    gl->ColorMask(s->color_mask[0], s->color_mask[1], s->color_mask[2], s->color_mask[3]);
    (s->test ? gl->Enable : gl->Disable)(GL_DEPTH_TEST);
    (s->cull ? gl->Enable : gl->Disable)(GL_CULL_FACE);
}

/* The item's draw desc: `common` with the item's model and, when it has
 * knobs, their albedo, kind knobs and stats. */
static void item_desc(const meso_rt_draw_item* it, const meso_rt_draw_desc* common, meso_rt_draw_desc* out)
{
    *out = *common;
    memcpy(out->model, it->model, sizeof(out->model));
    if (it->knobs) {
        memcpy(out->albedo, it->knobs->albedo, sizeof(out->albedo));
        out->shell = it->knobs->shell;
        out->frusta = it->knobs->frusta;
        out->cells = it->knobs->cells;
        out->stats = it->knobs->stats;
    }
}

/* Sort key: kind, then the program the item draws with, then the object;
 * ties keep the caller's order. */
typedef struct list_key {
    uint32_t kind, program, object, index;
    meso_rt_object drawn; /* the item's object, or the level of it the draw picked (rt_levels.c); 0: none */
} list_key;

static int key_cmp(const void* a, const void* b)
{
    const list_key *x = a, *y = b;
    if (x->kind != y->kind)
        return x->kind < y->kind ? -1 : 1;
    if (x->program != y->program)
        return x->program < y->program ? -1 : 1;
    if (x->object != y->object)
        return x->object < y->object ? -1 : 1;
    return x->index < y->index ? -1 : x->index > y->index;
}

meso_result meso_rt_draw_list(meso_rt* rt, const meso_rt_draw_item* items, uint32_t count,
                              const meso_rt_draw_desc* common)
{
    if (!rt)
        return MESO_ERR_INVALID_ARG;
    if (!items || !common || count == 0) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                  "meso_rt_draw_list: NULL items or common desc, or count 0 (%u)", count);
        return MESO_ERR_INVALID_ARG;
    }
    list_key* keys = mesoi_rt_alloc(rt, sizeof(list_key) * count);
    if (!keys)
        return MESO_ERR_OUT_OF_MEMORY;
    for (uint32_t i = 0; i < count; ++i) {
        const mesoi_object* o = mesoi_lookup(rt, items[i].object);
        if (!o || (items[i].instance_count > 0 && !items[i].instances)) {
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                      "meso_rt_draw_list: item %u has a stale handle, or instance_count %u without instances", i,
                      items[i].instance_count);
            mesoi_rt_free(rt, keys);
            return MESO_ERR_INVALID_ARG;
        }
        keys[i].index = i;
    }
    /* Levels are picked (and uploaded) once the whole list is known to be
     * valid; the key sorts by what is drawn. */
    meso_result result = MESO_OK;
    for (uint32_t i = 0; i < count; ++i)
        mesoi_levels_draw_begin(rt, items[i].object);
    for (uint32_t i = 0; i < count; ++i) {
        meso_rt_draw_desc d;
        item_desc(&items[i], common, &d);
        const meso_result r = mesoi_levels_pick(rt, items[i].object, &d,
                                                items[i].instance_count ? items[i].instances : NULL,
                                                items[i].instance_count, &keys[i].drawn);
        if (r != MESO_OK) {
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_OBJECT_NOT_FOUND,
                      "meso_rt_draw_list: item %u: no level of its object could be uploaded", i);
            keys[i].drawn.id = 0;
            if (result == MESO_OK)
                result = r;
        }
        const mesoi_object* o = keys[i].drawn.id ? mesoi_lookup(rt, keys[i].drawn) : mesoi_lookup(rt, items[i].object);
        const meso_rt_draw_desc* k = items[i].knobs ? items[i].knobs : common;
        keys[i].kind = o->kind;
        keys[i].program = o->kind == MESO_OBJECT_SHELL ? (uint32_t)k->shell.technique : 0;
        keys[i].program = 2 * keys[i].program + (k->stats != NULL);
        keys[i].object = keys[i].drawn.id & 0xFFFFu;
    }
    qsort(keys, count, sizeof(list_key), key_cmp);

    /* The draws inside run under MESO_STATE_HOST_OWNS (no queries, no
     * restores) and skip binding a program that is bound already; the list
     * saves and restores the state once. Slices draw with the context's
     * policy: their offscreen passes look after themselves. */
    const meso_rt_state_policy policy = rt->state_policy;
    list_state saved;
    if (policy == MESO_STATE_RESTORE)
        list_save(rt, &saved);
    rt->in_list = 1;
    rt->list_program = 0;
    for (uint32_t n = 0; n < count; ++n) {
        const meso_rt_draw_item* it = &items[keys[n].index];
        mesoi_object* o = mesoi_lookup(rt, keys[n].drawn);
        if (!o)
            continue; /* no level (logged above) */
        meso_rt_draw_desc d;
        item_desc(it, common, &d);
        const int slices = o->kind == MESO_OBJECT_SHELL && d.shell.technique == MESO_SHELL_SLICES;
        rt->state_policy = slices ? policy : MESO_STATE_HOST_OWNS;
        if (slices)
            rt->list_program = 0;
        const meso_result r = draw_kind(rt, o, &d, it->instance_count ? it->instances : NULL, it->instance_count);
        if (slices)
            rt->list_program = 0;
        if (r != MESO_OK && result == MESO_OK)
            result = r; /* the other items are still drawn */
    }
    rt->state_policy = policy;
    rt->in_list = 0;
    rt->list_program = 0;
    if (policy == MESO_STATE_RESTORE)
        list_restore(rt, &saved);
    mesoi_rt_free(rt, keys);
    return result;
}
