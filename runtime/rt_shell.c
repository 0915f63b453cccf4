/*
 * rt_shell.c — SHELL objects (FORMAT.md §7.2): streaming the base mesh,
 * directors and texture function of one shell into GL, and ray casting it
 * with one of three techniques (papers/smooth-and-curved-shell-mapping.md;
 * the shaders are runtime/shaders/shell_*.glsl, their maths is spelled out
 * in runtime/reference/shell_map.h).
 *
 * GL layout, chosen so the host can animate without re-baking:
 *  - one texture buffer of 2 RGBA32F texels per vertex, (bottom.xyz, s) and
 *    (top.xyz, t'): the prism corners and texture coordinates;
 *  - one R32UI texture buffer of triangle indices;
 *  - the texture function (2D height or 3D density) and the distance map.
 * The hull (or tetrahedra) triangles are generated in the vertex shader
 * from gl_VertexID, so meso_rt_shell_update is one buffer upload: no
 * triangulation on the CPU (the paper's claim that animated meshes need no
 * precomputation holds here too).
 */
#include "mat4_inverse.h"
#include "rt_internal.h"
#include "shaders_embedded.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

typedef struct mesoi_shell {
    uint32_t vertex_count, triangle_count, layers;
    float* positions; /* 3 per vertex (CPU copy for updates) */
    float* directors; /* 3 per vertex per layer */
    float* uvs;       /* 2 per vertex */
    GLuint vert_buf, vert_tex, index_buf, index_tex;
    GLuint func_tex, dist_tex;
    int tex_kind; /* 0 none, 1 height (2D), 2 density (3D) */
    float tex_size[3];
} mesoi_shell;

enum { UNIT_VERTS = 0, UNIT_INDEX, UNIT_HEIGHT, UNIT_VOLUME, UNIT_DIST, UNIT_COUNT };

int32_t mesoi_find_chunk(meso_file* f, uint32_t type, uint32_t object)
{
    int32_t ci = -1;
    for (uint32_t i = 0; i < meso_file_chunk_count(f); ++i) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        if (c->type == type && c->object == object && (ci < 0 || c->lod < meso_file_chunk(f, (uint32_t)ci)->lod))
            ci = (int32_t)i;
    }
    return ci;
}

/* Reads a whole chunk into a fresh allocation; logs and fails cleanly. */
static meso_result read_whole(meso_rt* rt, meso_file* f, int32_t ci, void** out, size_t* size)
{
    const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)ci);
    *out = NULL;
    if (c->decoded_size > (uint64_t)PTRDIFF_MAX) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED, "chunk %d too large for this platform", ci);
        return MESO_ERR_UNSUPPORTED;
    }
    void* data = mesoi_rt_alloc(rt, (size_t)c->decoded_size);
    if (!data)
        return MESO_ERR_OUT_OF_MEMORY;
    meso_error err;
    meso_result r = meso_file_read_chunk(f, (uint32_t)ci, data, (size_t)c->decoded_size, &err);
    if (r != MESO_OK) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED, "%s", err.message);
        mesoi_rt_free(rt, data);
        return r;
    }
    *out = data;
    *size = (size_t)c->decoded_size;
    return MESO_OK;
}

static void shell_free(meso_rt* rt, mesoi_shell* s)
{
    if (!s)
        return;
    mesoi_gl* gl = &rt->gl;
    GLuint tex[4] = {s->vert_tex, s->index_tex, s->func_tex, s->dist_tex};
    GLuint buf[2] = {s->vert_buf, s->index_buf};
    gl->DeleteTextures(4, tex);
    gl->DeleteBuffers(2, buf);
    mesoi_rt_free(rt, s->positions);
    mesoi_rt_free(rt, s->directors);
    mesoi_rt_free(rt, s->uvs);
    mesoi_rt_free(rt, s);
}

void mesoi_shell_release(meso_rt* rt, mesoi_object* o)
{
    shell_free(rt, o->shell);
    o->shell = NULL;
}

/* (bottom.xyz, s), (top.xyz, t') per vertex, FORMAT.md §7.2. */
static void fill_vertex_texels(const mesoi_shell* s, float* out)
{
    for (uint32_t v = 0; v < s->vertex_count; ++v) {
        const float* p = s->positions + 3 * (size_t)v;
        const float* d0 = s->directors + 3 * (size_t)v;
        const float* d1 = s->layers == 2 ? s->directors + 3 * ((size_t)s->vertex_count + v) : NULL;
        float* o = out + 8 * (size_t)v;
        for (int k = 0; k < 3; ++k) {
            o[k] = d1 ? p[k] + d1[k] : p[k];
            o[4 + k] = p[k] + d0[k];
        }
        o[3] = s->uvs[2 * (size_t)v];
        o[7] = s->uvs[2 * (size_t)v + 1];
    }
}

static int dtype_gl(uint16_t dtype, GLenum* internal, GLenum* type)
{
    switch (dtype) {
    case MESO_DTYPE_U8:
        *internal = GL_R8;
        *type = GL_UNSIGNED_BYTE;
        return 1;
    case MESO_DTYPE_U16:
        *internal = GL_R16;
        *type = GL_UNSIGNED_SHORT;
        return 1;
    case MESO_DTYPE_F32:
        *internal = GL_R32F;
        *type = GL_FLOAT;
        return 1;
    default:
        return 0;
    }
}

/* Uploads TX2D / TX3D / DIST. `nearest` for the distance map. */
static meso_result upload_texture(meso_rt* rt, meso_file* f, int32_t ci, int dims3, int nearest, GLuint* out)
{
    const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)ci);
    GLenum internal, type;
    if (c->components != 1 || !dtype_gl(c->dtype, &internal, &type) ||
        (!nearest && c->dtype == MESO_DTYPE_F32) || (!dims3 && c->dims[2] != 1)) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED,
                  "chunk %d: texture type %u x %u is not one FORMAT.md §7.2 allows", ci, c->dtype, c->components);
        return MESO_ERR_UNSUPPORTED;
    }
    void* data = NULL;
    size_t size = 0;
    meso_result r = read_whole(rt, f, ci, &data, &size);
    if (r != MESO_OK)
        return r;
    mesoi_gl* gl = &rt->gl;
    GLint prev_unpack = 4;
    gl->GetIntegerv(GL_UNPACK_ALIGNMENT, &prev_unpack);
    gl->PixelStorei(GL_UNPACK_ALIGNMENT, 1);
    const GLenum target = dims3 ? GL_TEXTURE_3D : GL_TEXTURE_2D;
    gl->GenTextures(1, out);
    gl->BindTexture(target, *out);
    if (dims3)
        gl->TexImage3D(target, 0, (GLint)internal, (GLsizei)c->dims[0], (GLsizei)c->dims[1], (GLsizei)c->dims[2], 0,
                       GL_RED, type, data);
    else
        gl->TexImage2D(target, 0, (GLint)internal, (GLsizei)c->dims[0], (GLsizei)c->dims[1], 0, GL_RED, type, data);
    const GLint filter = nearest ? GL_NEAREST : GL_LINEAR;
    gl->TexParameteri(target, GL_TEXTURE_MIN_FILTER, filter);
    gl->TexParameteri(target, GL_TEXTURE_MAG_FILTER, filter);
    gl->TexParameteri(target, GL_TEXTURE_WRAP_S, GL_REPEAT);
    gl->TexParameteri(target, GL_TEXTURE_WRAP_T, GL_REPEAT);
    if (dims3)
        gl->TexParameteri(target, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
    gl->TexParameteri(target, GL_TEXTURE_MAX_LEVEL, 0);
    gl->BindTexture(target, 0);
    gl->PixelStorei(GL_UNPACK_ALIGNMENT, prev_unpack);
    mesoi_rt_free(rt, data);
    return MESO_OK;
}

static GLuint texture_buffer(meso_rt* rt, GLenum format, const void* data, size_t size, GLuint* buf)
{
    mesoi_gl* gl = &rt->gl;
    GLuint tex = 0;
    gl->GenBuffers(1, buf);
    gl->BindBuffer(GL_TEXTURE_BUFFER, *buf);
    gl->BufferData(GL_TEXTURE_BUFFER, (GLsizeiptr)size, data, GL_DYNAMIC_DRAW);
    gl->GenTextures(1, &tex);
    gl->BindTexture(GL_TEXTURE_BUFFER, tex);
    gl->TexBuffer(GL_TEXTURE_BUFFER, format, *buf);
    gl->BindTexture(GL_TEXTURE_BUFFER, 0);
    gl->BindBuffer(GL_TEXTURE_BUFFER, 0);
    return tex;
}

meso_result mesoi_shell_load(meso_rt* rt, meso_file* f, uint32_t id, mesoi_object* o)
{
    const int32_t mi = mesoi_find_chunk(f, MESO_CHUNK_MESH, id), di = mesoi_find_chunk(f, MESO_CHUNK_SDIR, id);
    if (mi < 0 || di < 0) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_OBJECT_NOT_FOUND, "shell %u lacks its %s chunk", id,
                  mi < 0 ? "MESH" : "SDIR");
        return MESO_ERR_NOT_FOUND;
    }
    const int32_t hi = mesoi_find_chunk(f, MESO_CHUNK_TX2D, id), vi = mesoi_find_chunk(f, MESO_CHUNK_TX3D, id);
    const int32_t xi = mesoi_find_chunk(f, MESO_CHUNK_DIST, id);
    mesoi_shell* s = mesoi_rt_alloc(rt, sizeof(*s));
    if (!s)
        return MESO_ERR_OUT_OF_MEMORY;
    memset(s, 0, sizeof(*s));
    void* mesh = NULL;
    size_t mesh_size = 0;
    meso_result r = read_whole(rt, f, mi, &mesh, &mesh_size);
    meso_mesh_view mv;
    meso_error err;
    if (r == MESO_OK && (r = meso_mesh_parse(mesh, mesh_size, &mv, &err)) != MESO_OK)
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED, "%s", err.message);
    const meso_chunk_info* dc = meso_file_chunk(f, (uint32_t)di);
    if (r == MESO_OK) {
        s->vertex_count = mv.layout.vertex_count;
        s->triangle_count = mv.layout.index_count / 3;
        s->layers = dc->dims[1];
        if (dc->dtype != MESO_DTYPE_F32 || dc->components != 3 || dc->dims[0] != s->vertex_count ||
            (s->layers != 1 && s->layers != 2) || dc->dims[2] != 1 || s->triangle_count == 0) {
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED,
                      "shell %u: SDIR is %ux%ux%u F32x3? (dtype %u x %u) for a MESH of %u vertices and %u "
                      "triangles; FORMAT.md §7.2 wants N x 1|2 x 1 with N the vertex count",
                      id, dc->dims[0], dc->dims[1], dc->dims[2], dc->dtype, dc->components, s->vertex_count,
                      s->triangle_count);
            r = MESO_ERR_CORRUPT;
        }
    }
    GLint max_texels = 0;
    rt->gl.GetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
    if (r == MESO_OK && ((uint64_t)s->vertex_count * 2 > (uint64_t)max_texels ||
                         (uint64_t)s->triangle_count * 3 > (uint64_t)max_texels ||
                         (uint64_t)s->triangle_count * 36 > (uint64_t)INT32_MAX)) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED,
                  "shell %u: %u vertices / %u triangles exceed this context's texture buffer size (%d texels)",
                  id, s->vertex_count, s->triangle_count, max_texels);
        r = MESO_ERR_UNSUPPORTED;
    }
    void* dirs = NULL;
    size_t dirs_size = 0;
    if (r == MESO_OK)
        r = read_whole(rt, f, di, &dirs, &dirs_size);
    const size_t nv = s->vertex_count;
    if (r == MESO_OK) {
        s->directors = dirs;
        s->positions = mesoi_rt_alloc(rt, sizeof(float) * 3 * nv);
        s->uvs = mesoi_rt_alloc(rt, sizeof(float) * 2 * nv);
        if (!s->positions || !s->uvs)
            r = MESO_ERR_OUT_OF_MEMORY;
    }
    float* texels = NULL;
    if (r == MESO_OK) {
        memcpy(s->positions, mv.positions, sizeof(float) * 3 * nv);
        if (mv.uvs)
            memcpy(s->uvs, mv.uvs, sizeof(float) * 2 * nv);
        else
            memset(s->uvs, 0, sizeof(float) * 2 * nv);
        texels = mesoi_rt_alloc(rt, sizeof(float) * 8 * nv);
        if (!texels)
            r = MESO_ERR_OUT_OF_MEMORY;
    }
    mesoi_gl* gl = &rt->gl;
    GLint prev_tex_buffer = 0;
    gl->GetIntegerv(GL_TEXTURE_BUFFER_BINDING, &prev_tex_buffer);
    while (gl->GetError() != GL_NO_ERROR) {
    }
    if (r == MESO_OK) {
        fill_vertex_texels(s, texels);
        s->vert_tex = texture_buffer(rt, GL_RGBA32F, texels, sizeof(float) * 8 * nv, &s->vert_buf);
        s->index_tex = texture_buffer(rt, GL_R32UI, mv.indices, sizeof(uint32_t) * 3 * (size_t)s->triangle_count,
                                      &s->index_buf);
    }
    mesoi_rt_free(rt, texels);
    mesoi_rt_free(rt, mesh);
    if (r == MESO_OK && (hi >= 0 || vi >= 0)) {
        const int32_t ti = hi >= 0 ? hi : vi;
        const meso_chunk_info* tc = meso_file_chunk(f, (uint32_t)ti);
        s->tex_kind = hi >= 0 ? 1 : 2;
        for (int k = 0; k < 3; ++k)
            s->tex_size[k] = (float)tc->dims[k];
        r = upload_texture(rt, f, ti, s->tex_kind == 2, 0, &s->func_tex);
    }
    if (r == MESO_OK && xi >= 0)
        r = upload_texture(rt, f, xi, 1, 1, &s->dist_tex);
    gl->BindBuffer(GL_TEXTURE_BUFFER, (GLuint)prev_tex_buffer);
    const GLenum e = gl->GetError();
    if (r == MESO_OK && e != GL_NO_ERROR) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_ERROR, "uploading shell %u: GL error 0x%04x", id, e);
        r = MESO_ERR_GL;
    }
    if (r != MESO_OK) {
        shell_free(rt, s);
        return r;
    }
    o->shell = s;
    return MESO_OK;
}

meso_result meso_rt_shell_update(meso_rt* rt, meso_rt_object h, const float* positions, const float* directors,
                                 uint32_t vertex_count)
{
    mesoi_object* o = mesoi_lookup(rt, h);
    if (!o || !o->shell || vertex_count != o->shell->vertex_count) {
        if (rt)
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                      "meso_rt_shell_update: not a live shell, or vertex_count %u differs", vertex_count);
        return MESO_ERR_INVALID_ARG;
    }
    mesoi_shell* s = o->shell;
    const size_t nv = s->vertex_count;
    if (positions)
        memcpy(s->positions, positions, sizeof(float) * 3 * nv);
    if (directors)
        memcpy(s->directors, directors, sizeof(float) * 3 * nv * s->layers);
    float* texels = mesoi_rt_alloc(rt, sizeof(float) * 8 * nv);
    if (!texels)
        return MESO_ERR_OUT_OF_MEMORY;
    fill_vertex_texels(s, texels);
    mesoi_gl* gl = &rt->gl;
    GLint prev = 0;
    gl->GetIntegerv(GL_TEXTURE_BUFFER_BINDING, &prev);
    while (gl->GetError() != GL_NO_ERROR) {
    }
    gl->BindBuffer(GL_TEXTURE_BUFFER, s->vert_buf);
    gl->BufferSubData(GL_TEXTURE_BUFFER, 0, (GLsizeiptr)(sizeof(float) * 8 * nv), texels);
    gl->BindBuffer(GL_TEXTURE_BUFFER, (GLuint)prev);
    mesoi_rt_free(rt, texels);
    const GLenum e = gl->GetError();
    if (e != GL_NO_ERROR) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_ERROR, "meso_rt_shell_update: GL error 0x%04x", e);
        return MESO_ERR_GL;
    }
    return MESO_OK;
}

meso_result meso_rt_shell_info(const meso_rt* rt, meso_rt_object h, uint32_t* vertex_count, uint32_t* layers)
{
    const mesoi_object* o = mesoi_lookup(rt, h);
    if (!o)
        return MESO_ERR_INVALID_ARG;
    if (vertex_count)
        *vertex_count = o->shell ? o->shell->vertex_count : 0;
    if (layers)
        *layers = o->shell ? o->shell->layers : 0;
    return MESO_OK;
}

/* --- programs ------------------------------------------------------------ */

/* Programs per technique, with or without the stats counters (atomics
 * cost time, so draws that do not ask for stats run without them). */
static GLuint shell_program(meso_rt* rt, meso_shell_technique t, int stats)
{
    if (rt->shell_programs[stats][t])
        return rt->shell_programs[stats][t];
    char head[160];
    snprintf(head, sizeof(head), "#version %s core\n%s#define MESO_TECHNIQUE %d\n", stats ? "430" : "330",
             stats ? "#define MESO_STATS 1\n" : "", (int)t);
    const char* vs[3] = {head, mesoi_glsl_shell_common, mesoi_glsl_shell_vert};
    const char* fs[3] = {head, mesoi_glsl_shell_common, mesoi_glsl_shell_frag};
    static const char* const names[MESO_SHELL_TECHNIQUE_COUNT] = {"shell smooth", "shell curved", "shell tetra",
                                                                  "shell segment"};
    GLuint p = mesoi_link(rt, mesoi_compile(rt, GL_VERTEX_SHADER, vs, 3, "shell_vert.glsl"),
                          mesoi_compile(rt, GL_FRAGMENT_SHADER, fs, 3, "shell_frag.glsl"), names[t]);
    rt->shell_programs[stats][t] = p;
    return p;
}

void mesoi_shell_programs_destroy(meso_rt* rt)
{
    for (int st = 0; st < 2; ++st)
        for (int t = 0; t < MESO_SHELL_TECHNIQUE_COUNT; ++t)
            if (rt->shell_programs[st][t])
                rt->gl.DeleteProgram(rt->shell_programs[st][t]);
    if (rt->empty_vao)
        rt->gl.DeleteVertexArrays(1, &rt->empty_vao);
    if (rt->stats_buffer)
        rt->gl.DeleteBuffers(1, &rt->stats_buffer);
    memset(rt->shell_programs, 0, sizeof(rt->shell_programs));
    rt->empty_vao = rt->stats_buffer = 0;
}

/* --- drawing ------------------------------------------------------------- */

static void mat4_mul(const double a[16], const double b[16], double out[16])
{
    double r[16];
    for (int c = 0; c < 4; ++c)
        for (int i = 0; i < 4; ++i) {
            double s = 0.0;
            for (int k = 0; k < 4; ++k)
                s += a[4 * k + i] * b[4 * c + k];
            r[4 * c + i] = s;
        }
    memcpy(out, r, sizeof(r));
}

static int zero16(const float* v)
{
    for (int i = 0; i < 16; ++i)
        if (v[i] != 0.0f)
            return 0;
    return 1;
}

meso_result mesoi_shell_draw(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d)
{
    const mesoi_shell* s = o->shell;
    if (d->stats)
        memset(d->stats, 0, sizeof(*d->stats));
    if ((unsigned)d->technique >= MESO_SHELL_TECHNIQUE_COUNT) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT, "meso_rt_draw: technique %d",
                  (int)d->technique);
        return MESO_ERR_INVALID_ARG;
    }
    const int stats = d->stats && rt->gl_version >= 43 && rt->gl.MemoryBarrier;
    const GLuint prog = shell_program(rt, d->technique, stats);
    if (!prog)
        return MESO_ERR_GL;
    mesoi_gl* gl = &rt->gl;
    if (!rt->empty_vao)
        gl->GenVertexArrays(1, &rt->empty_vao);

    double view[16], proj[16], model[16], mvp[16], inv[16];
    for (int i = 0; i < 16; ++i) {
        view[i] = d->view[i];
        proj[i] = d->proj[i];
        model[i] = zero16(d->model) ? (i % 5 == 0 ? 1.0 : 0.0) : d->model[i];
    }
    mat4_mul(proj, view, mvp);
    mat4_mul(mvp, model, mvp);
    if (!meso_mat4_inverse(mvp, inv)) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT, "meso_rt_draw: singular view/projection");
        return MESO_ERR_INVALID_ARG;
    }
    float mvpf[16], invf[16];
    for (int i = 0; i < 16; ++i) {
        mvpf[i] = (float)mvp[i];
        invf[i] = (float)inv[i];
    }
    GLint vp[4] = {0, 0, 1, 1};
    gl->GetIntegerv(GL_VIEWPORT, vp);
    const double scale = sqrt(model[0] * model[0] + model[1] * model[1] + model[2] * model[2]);
    const double error_px = d->error_px > 0.0f ? d->error_px : 1.0;
    /* One pixel spans 2 w_clip / (proj[1][1] · height) eye units at clip w. */
    const double err_scale = error_px * 2.0 / (fabs(proj[5]) * (vp[3] > 0 ? vp[3] : 1)) / (scale > 0 ? scale : 1);
    double light[3] = {0.3, 0.8, 0.5};
    if (d->light_dir[0] != 0.0f || d->light_dir[1] != 0.0f || d->light_dir[2] != 0.0f)
        for (int k = 0; k < 3; ++k)
            light[k] = d->light_dir[k];
    float light_obj[3];
    double ll = 0.0;
    for (int k = 0; k < 3; ++k) { /* transpose(mat3(model)) · light */
        const double v = model[4 * k] * light[0] + model[4 * k + 1] * light[1] + model[4 * k + 2] * light[2];
        light_obj[k] = (float)v;
        ll += v * v;
    }
    for (int k = 0; k < 3; ++k)
        light_obj[k] = ll > 0.0 ? (float)(light_obj[k] / sqrt(ll)) : 0.0f;
    float albedo[3] = {0.80f, 0.74f, 0.66f};
    if (d->albedo[0] != 0.0f || d->albedo[1] != 0.0f || d->albedo[2] != 0.0f)
        memcpy(albedo, d->albedo, sizeof(albedo));
    float max_tex = fmaxf(s->tex_size[0], fmaxf(s->tex_size[1], s->tex_size[2]));

    /* Save what we change. */
    GLint prev_program = 0, prev_vao = 0, prev_func = 0, prev_mask = 0, prev_active = 0, prev_cull_mode = 0;
    GLint prev_front = 0, prev_ssbo = 0;
    GLint prev_bind[UNIT_COUNT] = {0};
    static const GLenum unit_target[UNIT_COUNT] = {GL_TEXTURE_BUFFER, GL_TEXTURE_BUFFER, GL_TEXTURE_2D,
                                                   GL_TEXTURE_3D, GL_TEXTURE_3D};
    static const GLenum unit_binding[UNIT_COUNT] = {GL_TEXTURE_BINDING_BUFFER, GL_TEXTURE_BINDING_BUFFER,
                                                    GL_TEXTURE_BINDING_2D, GL_TEXTURE_BINDING_3D,
                                                    GL_TEXTURE_BINDING_3D};
    gl->GetIntegerv(GL_CURRENT_PROGRAM, &prev_program);
    gl->GetIntegerv(GL_VERTEX_ARRAY_BINDING, &prev_vao);
    gl->GetIntegerv(GL_DEPTH_FUNC, &prev_func);
    gl->GetIntegerv(GL_DEPTH_WRITEMASK, &prev_mask);
    gl->GetIntegerv(GL_ACTIVE_TEXTURE, &prev_active);
    gl->GetIntegerv(GL_CULL_FACE_MODE, &prev_cull_mode);
    gl->GetIntegerv(GL_FRONT_FACE, &prev_front);
    const GLboolean prev_test = gl->IsEnabled(GL_DEPTH_TEST), prev_cull = gl->IsEnabled(GL_CULL_FACE);
    for (int u = 0; u < UNIT_COUNT; ++u) {
        gl->ActiveTexture(GL_TEXTURE0 + (GLenum)u);
        gl->GetIntegerv(unit_binding[u], &prev_bind[u]);
    }
    if (stats)
        gl->GetIntegerv(GL_SHADER_STORAGE_BUFFER_BINDING, &prev_ssbo);
    while (gl->GetError() != GL_NO_ERROR) {
    }

    const GLuint bind[UNIT_COUNT] = {s->vert_tex, s->index_tex, s->tex_kind == 1 ? s->func_tex : 0,
                                     s->tex_kind == 2 ? s->func_tex : 0, s->dist_tex};
    for (int u = 0; u < UNIT_COUNT; ++u) {
        gl->ActiveTexture(GL_TEXTURE0 + (GLenum)u);
        gl->BindTexture(unit_target[u], bind[u]);
    }
    if (stats) {
        const uint32_t zero[3] = {0, 0, 0};
        if (!rt->stats_buffer) {
            gl->GenBuffers(1, &rt->stats_buffer);
            gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, rt->stats_buffer);
            gl->BufferData(GL_SHADER_STORAGE_BUFFER, sizeof(zero), zero, GL_DYNAMIC_READ);
        } else {
            gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, rt->stats_buffer);
            gl->BufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof(zero), zero);
        }
        gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, rt->stats_buffer);
    }
    gl->UseProgram(prog);
    static const char* const samplers[UNIT_COUNT] = {"u_verts", "u_index", "u_height", "u_volume", "u_dist"};
    for (int u = 0; u < UNIT_COUNT; ++u)
        gl->Uniform1i(gl->GetUniformLocation(prog, samplers[u]), u);
    const float viewport[4] = {(float)vp[0], (float)vp[1], (float)vp[2], (float)vp[3]};
    gl->UniformMatrix4fv(gl->GetUniformLocation(prog, "u_mvp"), 1, GL_FALSE, mvpf);
    gl->UniformMatrix4fv(gl->GetUniformLocation(prog, "u_inv_mvp"), 1, GL_FALSE, invf);
    gl->Uniform4fv(gl->GetUniformLocation(prog, "u_viewport"), 1, viewport);
    gl->Uniform1f(gl->GetUniformLocation(prog, "u_uv_scale"), d->uv_scale > 0.0f ? d->uv_scale : 1.0f);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_tex_kind"), s->tex_kind);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_has_dist"), s->dist_tex && !d->no_distance_map);
    gl->Uniform3fv(gl->GetUniformLocation(prog, "u_tex_size"), 1, s->tex_size);
    gl->Uniform3fv(gl->GetUniformLocation(prog, "u_light_obj"), 1, light_obj);
    gl->Uniform3fv(gl->GetUniformLocation(prog, "u_albedo"), 1, albedo);
    gl->Uniform1f(gl->GetUniformLocation(prog, "u_err_scale"), (float)err_scale);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_max_steps"), d->max_steps > 0 ? d->max_steps : 256);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_bisect_steps"), d->bisection_steps > 0 ? d->bisection_steps : 4);
    gl->Uniform1i(gl->GetUniformLocation(prog, "u_segment_steps"), d->segment_steps > 0 ? d->segment_steps : 12);
    gl->Uniform1f(gl->GetUniformLocation(prog, "u_fixed_step"), d->fixed_step > 0.0f ? d->fixed_step : 1.0f / 256);
    /* Where the distance map says 0 (a cell touching the solid), step a
     * quarter texel: finer than the texture's own detail. */
    gl->Uniform1f(gl->GetUniformLocation(prog, "u_min_step"), max_tex > 1.0f ? 0.25f / max_tex : 1.0f / 1024);

    gl->Enable(GL_DEPTH_TEST);
    gl->DepthFunc(GL_LESS);
    gl->DepthMask(GL_TRUE);
    gl->Enable(GL_CULL_FACE);
    gl->CullFace(GL_FRONT); /* back faces: one fragment per solid, camera inside or not */
    gl->FrontFace(GL_CCW);
    gl->BindVertexArray(rt->empty_vao);
    const GLsizei per = d->technique == MESO_SHELL_TETRA ? 36 : 24;
    gl->DrawArrays(GL_TRIANGLES, 0, per * (GLsizei)s->triangle_count);
    if (stats) {
        uint32_t counts[3] = {0, 0, 0};
        gl->MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        gl->GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof(counts), counts);
        d->stats->supported = 1;
        d->stats->fragments = counts[0];
        d->stats->steps = counts[1];
        d->stats->hits = counts[2];
        gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, (GLuint)prev_ssbo);
    } else if (d->stats) {
        memset(d->stats, 0, sizeof(*d->stats));
    }
    const GLenum e = gl->GetError();

    for (int u = 0; u < UNIT_COUNT; ++u) {
        gl->ActiveTexture(GL_TEXTURE0 + (GLenum)u);
        gl->BindTexture(unit_target[u], (GLuint)prev_bind[u]);
    }
    gl->ActiveTexture((GLenum)prev_active);
    gl->BindVertexArray((GLuint)prev_vao);
    gl->UseProgram((GLuint)prev_program);
    gl->DepthFunc((GLenum)prev_func);
    gl->DepthMask(prev_mask ? GL_TRUE : GL_FALSE);
    gl->CullFace((GLenum)prev_cull_mode);
    gl->FrontFace((GLenum)prev_front);
    if (!prev_test)
        gl->Disable(GL_DEPTH_TEST);
    if (!prev_cull)
        gl->Disable(GL_CULL_FACE);
    if (e != GL_NO_ERROR) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_ERROR, "meso_rt_draw (shell): GL error 0x%04x", e);
        return MESO_ERR_GL;
    }
    return MESO_OK;
}
