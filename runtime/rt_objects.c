/*
 * rt_objects.c — the object table and the dispatch for every kind: load a
 * record's object (MESH, SHELL, FRUSTA, CELLS) into a generation-checked
 * slot through its kind's loader, release it and report its bounds
 * (rt_instances.c routes the draws to the kinds' renderers).
 */
#include "rt_internal.h"

#include <string.h>

mesoi_object* mesoi_lookup(const meso_rt* rt, meso_rt_object h)
{
    const uint32_t slot = h.id & 0xFFFFu, gen = h.id >> 16;
    if (!rt || h.id == 0 || slot >= rt->object_capacity)
        return NULL;
    mesoi_object* o = &rt->objects[slot];
    return o->live && o->generation == gen ? o : NULL;
}

/* A free slot (growing the table), or NULL when out of memory / handles. */
static mesoi_object* alloc_slot(meso_rt* rt, uint32_t* slot_out)
{
    for (uint32_t i = 0; i < rt->object_capacity; ++i)
        if (!rt->objects[i].live) {
            *slot_out = i;
            return &rt->objects[i];
        }
    const uint32_t cap = rt->object_capacity ? 2 * rt->object_capacity : 16;
    if (cap > 0x10000u)
        return NULL;
    mesoi_object* grown = mesoi_rt_alloc(rt, sizeof(mesoi_object) * cap);
    if (!grown)
        return NULL;
    memset(grown, 0, sizeof(mesoi_object) * cap);
    if (rt->objects)
        memcpy(grown, rt->objects, sizeof(mesoi_object) * rt->object_capacity);
    mesoi_rt_free(rt, rt->objects);
    rt->objects = grown;
    *slot_out = rt->object_capacity;
    rt->object_capacity = cap;
    return &rt->objects[*slot_out];
}

/* Generations go 1..0xFFFF and wrap, skipping 0 (id 0 is never valid). */
static uint32_t next_generation(uint32_t last)
{
    uint32_t g = (last + 1u) & 0xFFFFu;
    return g ? g : 1u;
}

meso_result mesoi_find_record(meso_rt* rt, meso_file* f, uint32_t id, meso_object_record* rec)
{
    /* Records are few (a 64-byte record per object); read them in batches. */
    meso_object_record batch[16];
    uint32_t count = 0;
    meso_error err;
    meso_result r = meso_file_objects(f, batch, 16, &count, &err);
    if (r != MESO_OK) {
        if (r != MESO_ERR_PENDING) /* not arrived yet: the result says so, nothing is wrong */
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED, "%s", err.message);
        return r;
    }
    if (count > 16) {
        meso_object_record* all = mesoi_rt_alloc(rt, sizeof(meso_object_record) * count);
        if (!all)
            return MESO_ERR_OUT_OF_MEMORY;
        r = meso_file_objects(f, all, count, &count, &err);
        for (uint32_t i = 0; r == MESO_OK && i < count; ++i)
            if (all[i].id == id) {
                *rec = all[i];
                mesoi_rt_free(rt, all);
                return MESO_OK;
            }
        mesoi_rt_free(rt, all);
    } else {
        for (uint32_t i = 0; i < count; ++i)
            if (batch[i].id == id) {
                *rec = batch[i];
                return MESO_OK;
            }
    }
    mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_OBJECT_NOT_FOUND, "object %u", id);
    return MESO_ERR_NOT_FOUND;
}

meso_result mesoi_load_slot(meso_rt* rt, meso_file* f, const meso_object_record* rec, uint32_t kind, uint16_t lod,
                            meso_rt_object* out)
{
    out->id = 0;
    uint32_t slot;
    mesoi_object* o = alloc_slot(rt, &slot);
    if (!o)
        return MESO_ERR_OUT_OF_MEMORY;
    rt->load_lod = lod;
    const uint64_t before = rt->gpu_count;
    const meso_result r = kind == MESO_OBJECT_MESH     ? mesoi_mesh_upload(rt, f, rec->id, 1, o)
                          : kind == MESO_OBJECT_SHELL  ? mesoi_shell_load(rt, f, rec->id, o)
                          : kind == MESO_OBJECT_FRUSTA ? mesoi_frusta_load(rt, f, rec->id, o)
                                                       : mesoi_cells_load(rt, f, rec->id, o);
    rt->load_lod = 0;
    if (r != MESO_OK)
        return r;
    o->generation = next_generation(o->generation);
    o->live = 1;
    o->kind = kind;
    o->gpu_bytes = rt->gpu_count - before;
    memcpy(o->bbox_min, rec->bbox_min, sizeof(o->bbox_min));
    memcpy(o->bbox_max, rec->bbox_max, sizeof(o->bbox_max));
    out->id = slot | (o->generation << 16);
    return MESO_OK;
}

meso_result mesoi_empty_slot(meso_rt* rt, const meso_object_record* rec, meso_rt_object* out)
{
    out->id = 0;
    uint32_t slot;
    mesoi_object* o = alloc_slot(rt, &slot);
    if (!o)
        return MESO_ERR_OUT_OF_MEMORY;
    o->generation = next_generation(o->generation);
    o->live = 1;
    o->kind = rec->kind;
    memcpy(o->bbox_min, rec->bbox_min, sizeof(o->bbox_min));
    memcpy(o->bbox_max, rec->bbox_max, sizeof(o->bbox_max));
    out->id = slot | (o->generation << 16);
    return MESO_OK;
}

int mesoi_kind_drawn(uint32_t kind)
{
    return kind == MESO_OBJECT_MESH || kind == MESO_OBJECT_SHELL || kind == MESO_OBJECT_FRUSTA ||
           kind == MESO_OBJECT_CELLS;
}

meso_result meso_rt_load_object(meso_rt* rt, meso_file* f, uint32_t object_id, meso_rt_object* out)
{
    if (!out)
        return MESO_ERR_INVALID_ARG;
    out->id = 0;
    if (!rt || !f || object_id == 0) {
        if (rt)
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT, "meso_rt_load_object: NULL file or object 0");
        return MESO_ERR_INVALID_ARG;
    }
    meso_object_record rec;
    meso_result r = mesoi_find_record(rt, f, object_id, &rec);
    if (r != MESO_OK)
        return r;
    if (!mesoi_kind_drawn(rec.kind)) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_OBJECT_NOT_FOUND,
                  "object %u has kind %u; this runtime draws MESH, SHELL, CELLS and FRUSTA objects", object_id, rec.kind);
        return MESO_ERR_UNSUPPORTED;
    }
    return mesoi_load_slot(rt, f, &rec, rec.kind, 0, out);
}

void meso_rt_release_object(meso_rt* rt, meso_rt_object h)
{
    mesoi_object* o = mesoi_lookup(rt, h);
    if (!o)
        return;
    mesoi_levels_release(rt, o); /* its levels' slots (a levelled object has no GL resources itself) */
    o = mesoi_lookup(rt, h);
    mesoi_shell_release(rt, o);
    mesoi_frusta_release(rt, o);
    mesoi_cells_release(rt, o);
    rt->gl.DeleteVertexArrays(1, &o->vao);
    rt->gl.DeleteBuffers(1, &o->buffer);
    const uint32_t gen = o->generation; /* kept: the next occupant gets a new one */
    memset(o, 0, sizeof(*o));
    o->generation = gen;
}

meso_result meso_rt_object_bounds(const meso_rt* rt, meso_rt_object h, float lo[3], float hi[3])
{
    const mesoi_object* o = mesoi_lookup(rt, h);
    if (!o)
        return MESO_ERR_INVALID_ARG;
    memcpy(lo, o->bbox_min, sizeof(o->bbox_min));
    memcpy(hi, o->bbox_max, sizeof(o->bbox_max));
    return MESO_OK;
}

void mesoi_objects_destroy(meso_rt* rt)
{
    for (uint32_t i = 0; i < rt->object_capacity; ++i) {
        mesoi_object* o = &rt->objects[i];
        if (o->live) {
            mesoi_levels_release(rt, o); /* never grows the table: `o` stays valid */
            mesoi_shell_release(rt, o);
            mesoi_frusta_release(rt, o);
            mesoi_cells_release(rt, o);
            rt->gl.DeleteVertexArrays(1, &o->vao);
            rt->gl.DeleteBuffers(1, &o->buffer);
        }
    }
    mesoi_rt_free(rt, rt->objects);
    rt->objects = NULL;
    rt->object_capacity = 0;
}
