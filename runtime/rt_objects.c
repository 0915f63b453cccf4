/*
 * rt_objects.c — the object table and the dispatch for every kind: load a
 * record's object (MESH, SHELL, FRUSTA, CELLS) into a generation-checked
 * slot, release it, and route meso_rt_draw to the kind's renderer; plus the
 * MESH kind itself (streaming a MESH chunk into one GL buffer, drawn as the
 * shaded base mesh) and the shader compile/link helpers every kind uses.
 *
 * The decoded MESH chunk is uploaded as it is: its positions, normals and
 * indices arrays sit at 16-byte aligned offsets inside the chunk
 * (FORMAT.md), so one buffer serves as vertex and index buffer and the
 * attribute pointers are the chunk's own offsets. No repacking.
 */
#include "rt_internal.h"
#include "shaders_embedded.h"

#include <math.h>
#include <string.h>

GLuint mesoi_compile(meso_rt* rt, GLenum type, const char* const* src, int count, const char* name)
{
    mesoi_gl* gl = &rt->gl;
    GLuint s = gl->CreateShader(type);
    gl->ShaderSource(s, count, src, NULL);
    gl->CompileShader(s);
    GLint ok = 0;
    gl->GetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[2048];
        gl->GetShaderInfoLog(s, sizeof(log), NULL, log);
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_SHADER_COMPILE_FAILED, "%s: %s", name, log);
        gl->DeleteShader(s);
        return 0;
    }
    return s;
}

/* Links and deletes the two shaders; 0 (logged) on failure. */
GLuint mesoi_link(meso_rt* rt, GLuint vs, GLuint fs, const char* name)
{
    mesoi_gl* gl = &rt->gl;
    if (!vs || !fs) {
        if (vs)
            gl->DeleteShader(vs);
        if (fs)
            gl->DeleteShader(fs);
        return 0;
    }
    GLuint p = gl->CreateProgram();
    gl->AttachShader(p, vs);
    gl->AttachShader(p, fs);
    gl->LinkProgram(p);
    gl->DeleteShader(vs);
    gl->DeleteShader(fs);
    GLint ok = 0;
    gl->GetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[2048];
        gl->GetProgramInfoLog(p, sizeof(log), NULL, log);
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_PROGRAM_LINK_FAILED, "%s: %s", name, log);
        gl->DeleteProgram(p);
        return 0;
    }
    return p;
}

meso_result mesoi_mesh_program_create(meso_rt* rt)
{
    mesoi_gl* gl = &rt->gl;
    const char* vsrc = mesoi_glsl_mesh_vert;
    const char* fsrc = mesoi_glsl_mesh_frag;
    GLuint p = mesoi_link(rt, mesoi_compile(rt, GL_VERTEX_SHADER, &vsrc, 1, "mesh_vert.glsl"),
                          mesoi_compile(rt, GL_FRAGMENT_SHADER, &fsrc, 1, "mesh_frag.glsl"), "mesh");
    if (!p)
        return MESO_ERR_GL;
    rt->mesh_program = p;
    rt->u_view = gl->GetUniformLocation(p, "u_view");
    rt->u_proj = gl->GetUniformLocation(p, "u_proj");
    rt->u_model = gl->GetUniformLocation(p, "u_model");
    rt->u_light_dir = gl->GetUniformLocation(p, "u_light_dir");
    rt->u_albedo = gl->GetUniformLocation(p, "u_albedo");
    return MESO_OK;
}

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

static meso_result find_record(meso_rt* rt, meso_file* f, uint32_t id, meso_object_record* rec)
{
    /* Records are few (a 64-byte record per object); read them in batches. */
    meso_object_record batch[16];
    uint32_t count = 0;
    meso_error err;
    meso_result r = meso_file_objects(f, batch, 16, &count, &err);
    if (r != MESO_OK) {
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

meso_result mesoi_mesh_upload(meso_rt* rt, meso_file* f, uint32_t object_id, mesoi_object* o)
{
    const int32_t ci = mesoi_find_chunk(f, MESO_CHUNK_MESH, object_id);
    if (ci < 0) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_OBJECT_NOT_FOUND, "object %u has no MESH chunk", object_id);
        return MESO_ERR_NOT_FOUND;
    }
    const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)ci);
    if (c->decoded_size > (uint64_t)PTRDIFF_MAX) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED, "MESH chunk too large for this platform");
        return MESO_ERR_UNSUPPORTED;
    }
    void* data = mesoi_rt_alloc(rt, (size_t)c->decoded_size);
    if (!data)
        return MESO_ERR_OUT_OF_MEMORY;
    meso_error err;
    meso_mesh_view mv;
    meso_result r = meso_file_read_chunk(f, (uint32_t)ci, data, (size_t)c->decoded_size, &err);
    if (r == MESO_OK)
        r = meso_mesh_parse(data, (size_t)c->decoded_size, &mv, &err);
    if (r != MESO_OK) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED, "%s", err.message);
        mesoi_rt_free(rt, data);
        return r;
    }
    if (mv.layout.index_count > (uint32_t)INT32_MAX || !mv.normals) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED,
                  "object %u: MESH without normals or with too many indices", object_id);
        mesoi_rt_free(rt, data);
        return MESO_ERR_UNSUPPORTED;
    }
    mesoi_gl* gl = &rt->gl;
    GLint prev_vao = 0, prev_array = 0;
    gl->GetIntegerv(GL_VERTEX_ARRAY_BINDING, &prev_vao);
    gl->GetIntegerv(GL_ARRAY_BUFFER_BINDING, &prev_array);
    while (gl->GetError() != GL_NO_ERROR) {
    }
    gl->GenVertexArrays(1, &o->vao);
    gl->GenBuffers(1, &o->buffer);
    gl->BindVertexArray(o->vao);
    gl->BindBuffer(GL_ARRAY_BUFFER, o->buffer);
    gl->BufferData(GL_ARRAY_BUFFER, (GLsizeiptr)c->decoded_size, data, GL_STATIC_DRAW);
    gl->BindBuffer(GL_ELEMENT_ARRAY_BUFFER, o->buffer);
    gl->VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 12, (const void*)(uintptr_t)mv.layout.positions_offset);
    gl->EnableVertexAttribArray(0);
    gl->VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 12, (const void*)(uintptr_t)mv.layout.normals_offset);
    gl->EnableVertexAttribArray(1);
    gl->BindVertexArray((GLuint)prev_vao);
    gl->BindBuffer(GL_ARRAY_BUFFER, (GLuint)prev_array);
    mesoi_rt_free(rt, data);
    const GLenum e = gl->GetError();
    if (e != GL_NO_ERROR) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_ERROR, "uploading object %u: GL error 0x%04x", object_id, e);
        gl->DeleteVertexArrays(1, &o->vao);
        gl->DeleteBuffers(1, &o->buffer);
        o->vao = o->buffer = 0;
        return MESO_ERR_GL;
    }
    o->index_count = (GLsizei)mv.layout.index_count;
    o->indices_offset = mv.layout.indices_offset;
    return MESO_OK;
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
    meso_result r = find_record(rt, f, object_id, &rec);
    if (r != MESO_OK)
        return r;
    if (rec.kind != MESO_OBJECT_MESH && rec.kind != MESO_OBJECT_SHELL && rec.kind != MESO_OBJECT_FRUSTA &&
        rec.kind != MESO_OBJECT_CELLS) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_OBJECT_NOT_FOUND,
                  "object %u has kind %u; this runtime draws MESH, SHELL, CELLS and FRUSTA objects", object_id, rec.kind);
        return MESO_ERR_UNSUPPORTED;
    }
    uint32_t slot;
    mesoi_object* o = alloc_slot(rt, &slot);
    if (!o)
        return MESO_ERR_OUT_OF_MEMORY;
    r = rec.kind == MESO_OBJECT_MESH     ? mesoi_mesh_upload(rt, f, object_id, o)
        : rec.kind == MESO_OBJECT_SHELL  ? mesoi_shell_load(rt, f, object_id, o)
        : rec.kind == MESO_OBJECT_FRUSTA ? mesoi_frusta_load(rt, f, object_id, o)
                                         : mesoi_cells_load(rt, f, object_id, o);
    if (r != MESO_OK)
        return r;
    o->generation = next_generation(o->generation);
    o->live = 1;
    o->kind = rec.kind;
    memcpy(o->bbox_min, rec.bbox_min, sizeof(o->bbox_min));
    memcpy(o->bbox_max, rec.bbox_max, sizeof(o->bbox_max));
    out->id = slot | (o->generation << 16);
    return MESO_OK;
}

void meso_rt_release_object(meso_rt* rt, meso_rt_object h)
{
    mesoi_object* o = mesoi_lookup(rt, h);
    if (!o)
        return;
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

static int all_zero(const float* v, int n)
{
    for (int i = 0; i < n; ++i)
        if (v[i] != 0.0f)
            return 0;
    return 1;
}

meso_result meso_rt_draw(meso_rt* rt, meso_rt_object h, const meso_rt_draw_desc* d)
{
    mesoi_object* o = mesoi_lookup(rt, h);
    if (!o || !d) {
        if (rt)
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT, "meso_rt_draw: stale handle or NULL desc");
        return MESO_ERR_INVALID_ARG;
    }
    if (o->kind == MESO_OBJECT_SHELL)
        return mesoi_shell_draw(rt, o, d);
    if (o->kind == MESO_OBJECT_FRUSTA)
        return mesoi_frusta_draw(rt, o, d);
    if (o->kind == MESO_OBJECT_CELLS)
        return mesoi_cells_draw(rt, o, d);
    static const float identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    float light[3] = {0.3f, 0.8f, 0.5f}, albedo[3] = {0.80f, 0.74f, 0.66f};
    if (!all_zero(d->light_dir, 3))
        memcpy(light, d->light_dir, sizeof(light));
    if (!all_zero(d->albedo, 3))
        memcpy(albedo, d->albedo, sizeof(albedo));
    const float len = sqrtf(light[0] * light[0] + light[1] * light[1] + light[2] * light[2]);
    for (int k = 0; k < 3; ++k)
        light[k] /= len;

    mesoi_gl* gl = &rt->gl;
    GLint prev_program = 0, prev_vao = 0, prev_func = 0, prev_mask = 0;
    gl->GetIntegerv(GL_CURRENT_PROGRAM, &prev_program);
    gl->GetIntegerv(GL_VERTEX_ARRAY_BINDING, &prev_vao);
    gl->GetIntegerv(GL_DEPTH_FUNC, &prev_func);
    gl->GetIntegerv(GL_DEPTH_WRITEMASK, &prev_mask);
    const GLboolean prev_test = gl->IsEnabled(GL_DEPTH_TEST);
    while (gl->GetError() != GL_NO_ERROR) {
    }

    gl->Enable(GL_DEPTH_TEST);
    gl->DepthFunc(GL_LESS);
    gl->DepthMask(GL_TRUE);
    gl->UseProgram(rt->mesh_program);
    gl->UniformMatrix4fv(rt->u_view, 1, GL_FALSE, d->view);
    gl->UniformMatrix4fv(rt->u_proj, 1, GL_FALSE, d->proj);
    gl->UniformMatrix4fv(rt->u_model, 1, GL_FALSE, all_zero(d->model, 16) ? identity : d->model);
    gl->Uniform3fv(rt->u_light_dir, 1, light);
    gl->Uniform3fv(rt->u_albedo, 1, albedo);
    gl->BindVertexArray(o->vao);
    gl->DrawElements(GL_TRIANGLES, o->index_count, GL_UNSIGNED_INT, (const void*)(uintptr_t)o->indices_offset);
    const GLenum e = gl->GetError();

    gl->BindVertexArray((GLuint)prev_vao);
    gl->UseProgram((GLuint)prev_program);
    gl->DepthFunc((GLenum)prev_func);
    gl->DepthMask(prev_mask ? GL_TRUE : GL_FALSE);
    if (!prev_test)
        gl->Disable(GL_DEPTH_TEST);
    if (e != GL_NO_ERROR) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_ERROR, "meso_rt_draw: GL error 0x%04x", e);
        return MESO_ERR_GL;
    }
    return MESO_OK;
}
