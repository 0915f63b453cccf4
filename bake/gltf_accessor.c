/*
 * gltf_accessor.c — reading one glTF 2.0 accessor, every byte checked.
 *
 * glTF 2.0 section 3.6.2 (accessors) and 3.6.2.4 (data alignment): element
 * i of an accessor starts at bufferView.byteOffset + accessor.byteOffset +
 * i * stride, stride being the view's byteStride or the element size. The
 * accessor, its view and its buffer are looked up and bounded here before
 * one byte is read (codes in gltf_model.h); an accessor without a
 * bufferView is all zeros, as the specification says.
 */
#include <stdlib.h>
#include <string.h>

#include "gltf_model.h"

static size_t component_size(int type)
{
    switch (type) {
    case MESO_GLTF_BYTE:
    case MESO_GLTF_UNSIGNED_BYTE: return 1;
    case MESO_GLTF_SHORT:
    case MESO_GLTF_UNSIGNED_SHORT: return 2;
    case MESO_GLTF_UNSIGNED_INT:
    case MESO_GLTF_FLOAT: return 4;
    default: return 0;
    }
}

/* The accessor's first element's bytes (NULL when it has no bufferView) and
 * its stride, after every bound is checked (base and stride are only written
 * for an accessor that exists). */
static meso_result locate(const char* path, const meso_gltf_model* g, int index, const char* place,
                          const uint8_t** base, size_t* stride, meso_error* err)
{
    if (index < 0 || (uint32_t)index >= g->accessor_count)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_REFERENCE,
                              "%s: %s: accessor %d does not exist (%u accessors)", path, place, index,
                              g->accessor_count);
    const meso_gltf_accessor* a = &g->accessors[index];
    if (a->sparse)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_UNSUPPORTED,
                              "%s: %s (accessors[%d]): sparse accessors are not read", path, place, index);
    const size_t cs = component_size(a->component_type);
    if (cs == 0 || a->components <= 0)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_TYPE,
                              "%s: %s (accessors[%d]): componentType %d / type not valid here", path, place, index,
                              a->component_type);
    *base = NULL;
    *stride = 0;
    if (a->view < 0)
        return MESO_OK;
    if ((uint32_t)a->view >= g->view_count)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_REFERENCE,
                              "%s: accessors[%d].bufferView: bufferView %d does not exist (%u bufferViews)", path,
                              index, a->view, g->view_count);
    const meso_gltf_view* v = &g->views[a->view];
    if (v->buffer < 0 || (uint32_t)v->buffer >= g->buffer_count)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_REFERENCE,
                              "%s: bufferViews[%d].buffer: buffer %d does not exist (%u buffers)", path, a->view,
                              v->buffer, g->buffer_count);
    const meso_gltf_buffer* b = &g->buffers[v->buffer];
    if (v->offset > b->size || v->length > b->size - v->offset)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_BOUNDS,
                              "%s: bufferViews[%d]: bytes %zu..%zu lie outside buffers[%d] (%zu bytes)", path,
                              a->view, v->offset, v->offset + v->length, v->buffer, b->size);
    const size_t elem = cs * (size_t)a->components;
    const size_t s = v->stride ? v->stride : elem;
    if (s < elem || s % cs != 0 || (a->offset + v->offset) % cs != 0)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_BOUNDS,
                              "%s: %s (accessors[%d]): byteStride %zu / byteOffset %zu misfit %zu-byte elements",
                              path, place, index, s, a->offset, elem);
    if (a->count > 0) {
        /* offset + s * (count - 1) + elem <= length, without overflow */
        const size_t room = v->length >= a->offset ? v->length - a->offset : 0;
        if (room < elem || (a->count - 1) > (room - elem) / s)
            return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_BOUNDS,
                                  "%s: %s (accessors[%d]): %zu elements from byte %zu overrun bufferViews[%d] "
                                  "(%zu bytes)",
                                  path, place, index, a->count, a->offset, a->view, v->length);
    }
    *base = b->data + v->offset + a->offset;
    *stride = s;
    return MESO_OK;
}

static float component(const uint8_t* p, int type)
{
    switch (type) {
    case MESO_GLTF_UNSIGNED_BYTE: return (float)p[0] / 255.0f;
    case MESO_GLTF_UNSIGNED_SHORT: {
        uint16_t u;
        memcpy(&u, p, 2);
        return (float)u / 65535.0f;
    }
    default: {
        float f;
        memcpy(&f, p, 4);
        return f;
    }
    }
}

/* An accessor without a bufferView reads as zeros (glTF 2.0 §3.6.2.3), so
 * no byte of the file backs its count: it may not claim more elements of
 * `elem` bytes than all the document's buffers hold, which keeps what it
 * makes us allocate within what the mesh guard's budget let in (a 411-byte
 * file claiming 1.5e8 vertices allocated 600 MB before the budget check). */
static meso_result zeros_bound(const char* path, const meso_gltf_model* g, int index, const char* place, size_t elem,
                               meso_error* err)
{
    const meso_gltf_accessor* a = &g->accessors[index];
    size_t held = 0;
    for (uint32_t b = 0; b < g->buffer_count; ++b)
        held += g->buffers[b].size;
    if (a->count > held / (elem ? elem : 1))
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_BOUNDS,
                              "%s: %s (accessors[%d]): %zu elements without a bufferView (zeros), more than the "
                              "document's buffers hold (%zu bytes)",
                              path, place, index, a->count, held);
    return MESO_OK;
}

meso_result meso_gltf_read_floats(const char* path, const meso_gltf_model* g, int accessor, const char* place,
                                  int components, int allow_normalized, float** out, size_t* count, meso_error* err)
{
    *out = NULL;
    *count = 0;
    if (accessor < 0 || (uint32_t)accessor >= g->accessor_count)
        return locate(path, g, accessor, place, NULL, NULL, err); /* the reference error */
    const meso_gltf_accessor* a = &g->accessors[accessor];
    const int ct = a->component_type;
    const int ok_type = ct == MESO_GLTF_FLOAT || (allow_normalized && a->normalized &&
                                                  (ct == MESO_GLTF_UNSIGNED_BYTE || ct == MESO_GLTF_UNSIGNED_SHORT));
    if (!ok_type || a->components != components || a->is_matrix)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_TYPE,
                              "%s: %s (accessors[%d]): %d components of componentType %d%s, expected VEC%d of FLOAT%s",
                              path, place, accessor, a->components, ct, a->normalized ? " (normalized)" : "",
                              components, allow_normalized ? " or normalized UNSIGNED_BYTE/SHORT" : "");
    const uint8_t* base;
    size_t stride;
    meso_result r = locate(path, g, accessor, place, &base, &stride, err);
    if (r == MESO_OK && !base)
        r = zeros_bound(path, g, accessor, place, component_size(ct) * (size_t)components, err);
    if (r != MESO_OK)
        return r;
    const size_t cs = component_size(ct);
    float* f = calloc(a->count ? a->count * (size_t)components : 1, sizeof(float));
    if (!f)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "%s: %s: out of memory", path, place);
    for (size_t i = 0; base && i < a->count; ++i)
        for (int k = 0; k < components; ++k)
            f[i * (size_t)components + (size_t)k] = component(base + i * stride + (size_t)k * cs, ct);
    *out = f;
    *count = a->count;
    return MESO_OK;
}

meso_result meso_gltf_read_indices(const char* path, const meso_gltf_model* g, int accessor, const char* place,
                                   size_t vertex_count, uint32_t** out, size_t* count, meso_error* err)
{
    *out = NULL;
    *count = 0;
    if (accessor < 0 || (uint32_t)accessor >= g->accessor_count)
        return locate(path, g, accessor, place, NULL, NULL, err); /* the reference error */
    const meso_gltf_accessor* a = &g->accessors[accessor];
    const int ct = a->component_type;
    if (a->components != 1 || a->is_matrix ||
        !(ct == MESO_GLTF_UNSIGNED_BYTE || ct == MESO_GLTF_UNSIGNED_SHORT || ct == MESO_GLTF_UNSIGNED_INT))
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_TYPE,
                              "%s: %s (accessors[%d]): %d components of componentType %d, expected SCALAR of "
                              "UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT",
                              path, place, accessor, a->components, ct);
    const uint8_t* base;
    size_t stride;
    meso_result r = locate(path, g, accessor, place, &base, &stride, err);
    if (r == MESO_OK && !base)
        r = zeros_bound(path, g, accessor, place, component_size(ct), err);
    if (r != MESO_OK)
        return r;
    uint32_t* ix = calloc(a->count ? a->count : 1, sizeof(uint32_t));
    if (!ix)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "%s: %s: out of memory", path, place);
    for (size_t i = 0; i < a->count; ++i) {
        uint32_t v = 0;
        if (base) {
            const uint8_t* p = base + i * stride;
            if (ct == MESO_GLTF_UNSIGNED_BYTE)
                v = p[0];
            else if (ct == MESO_GLTF_UNSIGNED_SHORT) {
                uint16_t u;
                memcpy(&u, p, 2);
                v = u;
            } else
                memcpy(&v, p, 4);
        }
        if (v >= vertex_count) {
            free(ix);
            return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_GLTF_ISSUE_INDEX,
                                  "%s: %s: index %u out of range (%zu vertices)", path, place, v, vertex_count);
        }
        ix[i] = v;
    }
    *out = ix;
    *count = a->count;
    return MESO_OK;
}
