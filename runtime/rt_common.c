/*
 * rt_common.c — what the object kinds share: streaming and checking a
 * chunk, texture and texture-buffer uploads (with the formats OpenGL ES
 * lacks converted), the prelude every shader starts with (desktop or ES),
 * compiling and linking the shaders, and a draw's matrices, light, GL
 * state save/restore and work counters (read back by mapping on ES).
 *
 * The GL state contract of meso_rt_draw (meso_rt.h) lives here: every draw,
 * of every kind, goes through mesoi_draw_begin / mesoi_draw_end, which save
 * and restore the program, vertex array, active texture and the bindings of
 * the units the kind uses, depth test/func/mask, culling and the shader
 * storage binding of the counters.
 */
#include "mat4_inverse.h"
#include "rt_internal.h"

#include <math.h>
#include <string.h>

/* >>chunks ----------------------------------------------------------------- */

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

meso_result mesoi_read_whole(meso_rt* rt, meso_file* f, int32_t ci, void** out, size_t* size)
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

/* >>uploads ---------------------------------------------------------------- */

static int dtype_gl(uint16_t dtype, GLenum* internal, GLenum* type)
{
    switch (dtype) {
    case MESO_DTYPE_U8:
        *internal = GL_R8;
        *type = GL_UNSIGNED_BYTE;
        return 1;
    case MESO_DTYPE_U16:
        *internal = GL_R16; /* = GL_R16_EXT of GL_EXT_texture_norm16 on ES */
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

float* mesoi_unorm16_to_float(meso_rt* rt, const void* texels, size_t count)
{
    float* f = mesoi_rt_alloc(rt, sizeof(float) * count);
    if (!f)
        return NULL;
    const uint16_t* v = texels;
    for (size_t i = 0; i < count; ++i)
        f[i] = (float)v[i] / 65535.0f;
    return f;
}

meso_result mesoi_upload_texels(meso_rt* rt, const uint32_t dims[3], uint16_t dtype, int dims3, int nearest,
                                const void* data, GLuint* out)
{
    GLenum internal, type;
    if (!dtype_gl(dtype, &internal, &type) || (!nearest && dtype == MESO_DTYPE_F32) || (!dims3 && dims[2] != 1))
        return MESO_ERR_UNSUPPORTED;
    /* OpenGL ES without GL_EXT_texture_norm16 has no R16: U16 texels go up
     * as floats, R32F (exact) where they are sampled nearest or R32F
     * filters linearly (GL_OES_texture_float_linear), else R16F (11
     * significant bits, meso_rt.h says what that costs). */
    float* converted = NULL;
    if (dtype == MESO_DTYPE_U16 && !rt->norm16) {
        converted = mesoi_unorm16_to_float(rt, data, (size_t)dims[0] * dims[1] * dims[2]);
        if (!converted)
            return MESO_ERR_OUT_OF_MEMORY;
        internal = nearest || rt->float_linear ? GL_R32F : GL_R16F;
        type = GL_FLOAT;
        data = converted;
    }
    mesoi_gl* gl = &rt->gl;
    const GLenum target = dims3 ? GL_TEXTURE_3D : GL_TEXTURE_2D;
    GLint prev_unpack = 4, prev_tex = 0;
    gl->GetIntegerv(GL_UNPACK_ALIGNMENT, &prev_unpack);
    gl->GetIntegerv(dims3 ? GL_TEXTURE_BINDING_3D : GL_TEXTURE_BINDING_2D, &prev_tex);
    gl->PixelStorei(GL_UNPACK_ALIGNMENT, 1);
    gl->GenTextures(1, out);
    gl->BindTexture(target, *out);
    if (dims3)
        gl->TexImage3D(target, 0, (GLint)internal, (GLsizei)dims[0], (GLsizei)dims[1], (GLsizei)dims[2], 0, GL_RED,
                       type, data);
    else
        gl->TexImage2D(target, 0, (GLint)internal, (GLsizei)dims[0], (GLsizei)dims[1], 0, GL_RED, type, data);
    const GLint filter = nearest ? GL_NEAREST : GL_LINEAR;
    gl->TexParameteri(target, GL_TEXTURE_MIN_FILTER, filter);
    gl->TexParameteri(target, GL_TEXTURE_MAG_FILTER, filter);
    gl->TexParameteri(target, GL_TEXTURE_WRAP_S, GL_REPEAT);
    gl->TexParameteri(target, GL_TEXTURE_WRAP_T, GL_REPEAT);
    if (dims3)
        gl->TexParameteri(target, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
    gl->TexParameteri(target, GL_TEXTURE_MAX_LEVEL, 0);
    gl->BindTexture(target, (GLuint)prev_tex);
    gl->PixelStorei(GL_UNPACK_ALIGNMENT, prev_unpack);
    mesoi_rt_free(rt, converted);
    return MESO_OK;
}

meso_result mesoi_upload_texture(meso_rt* rt, meso_file* f, int32_t ci, int dims3, int nearest, GLuint* out)
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
    meso_result r = mesoi_read_whole(rt, f, ci, &data, &size);
    if (r == MESO_OK)
        r = mesoi_upload_texels(rt, c->dims, c->dtype, dims3, nearest, data, out);
    mesoi_rt_free(rt, data);
    return r;
}

GLuint mesoi_texture_buffer(meso_rt* rt, GLenum format, const void* data, size_t size, GLuint* buf)
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

GLint mesoi_upload_begin(meso_rt* rt)
{
    GLint prev = 0;
    rt->gl.GetIntegerv(GL_TEXTURE_BUFFER_BINDING, &prev);
    while (rt->gl.GetError() != GL_NO_ERROR) {
    }
    return prev;
}

meso_result mesoi_upload_end(meso_rt* rt, GLint prev, meso_result r, const char* what)
{
    rt->gl.BindBuffer(GL_TEXTURE_BUFFER, (GLuint)prev);
    const GLenum e = rt->gl.GetError();
    if (r == MESO_OK && e != GL_NO_ERROR) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_ERROR, "%s: GL error 0x%04x", what, e);
        return MESO_ERR_GL;
    }
    return r;
}

meso_result mesoi_buffer_update(meso_rt* rt, GLuint buf, const void* data, size_t size, const char* what)
{
    const GLint prev = mesoi_upload_begin(rt);
    rt->gl.BindBuffer(GL_TEXTURE_BUFFER, buf);
    rt->gl.BufferSubData(GL_TEXTURE_BUFFER, 0, (GLsizeiptr)size, data);
    return mesoi_upload_end(rt, prev, MESO_OK, what);
}

/* >>shaders ---------------------------------------------------------------- */

/* ES has no default precision for floats in fragment shaders nor for most
 * sampler types; highp everywhere keeps the desktop arithmetic (IEEE
 * single precision) and 32-bit integers. */
#define ES_PRECISIONS                                                                                   \
    "precision highp float;\nprecision highp int;\nprecision highp sampler2D;\n"                         \
    "precision highp sampler3D;\nprecision highp samplerCube;\nprecision highp samplerBuffer;\n"         \
    "precision highp usampler3D;\nprecision highp usamplerBuffer;\nprecision highp isamplerBuffer;\n"

const char* mesoi_glsl_prelude(const meso_rt* rt, int stats)
{
    static const char* const prelude[2][2] = {
        {"#version 330 core\n", "#version 430 core\n#define MESO_STATS 1\n"},
        {"#version 320 es\n" ES_PRECISIONS, "#version 320 es\n" ES_PRECISIONS "#define MESO_STATS 1\n"},
    };
    return prelude[rt->gles ? 1 : 0][stats ? 1 : 0];
}

/* 1 when the shader compiled (`program` 0) or the program linked (1); else
 * logs its info log under `name`, deletes it and returns 0. */
static int built(meso_rt* rt, GLuint obj, int program, const char* name)
{
    mesoi_gl* gl = &rt->gl;
    GLint ok = 0;
    (program ? gl->GetProgramiv : gl->GetShaderiv)(obj, program ? GL_LINK_STATUS : GL_COMPILE_STATUS, &ok);
    if (ok)
        return 1;
    char log[2048];
    (program ? gl->GetProgramInfoLog : gl->GetShaderInfoLog)(obj, sizeof(log), NULL, log);
    mesoi_log(rt, MESO_LOG_ERROR, program ? MESO_LOGITEM_PROGRAM_LINK_FAILED : MESO_LOGITEM_SHADER_COMPILE_FAILED,
              "%s: %s", name, log);
    (program ? gl->DeleteProgram : gl->DeleteShader)(obj);
    return 0;
}

GLuint mesoi_compile(meso_rt* rt, GLenum type, const char* const* src, int count, const char* name)
{
    mesoi_gl* gl = &rt->gl;
    GLuint s = gl->CreateShader(type);
    gl->ShaderSource(s, count, src, NULL);
    gl->CompileShader(s);
    return built(rt, s, 0, name) ? s : 0;
}

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
    return built(rt, p, 1, name) ? p : 0;
}

/* >>draws ------------------------------------------------------------------ */

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

meso_result mesoi_draw_prepare(meso_rt* rt, const meso_rt_draw_desc* d, int need_inverse, mesoi_draw* out)
{
    memset(out, 0, sizeof(*out));
    if (d->stats)
        memset(d->stats, 0, sizeof(*d->stats));
    double view[16], proj[16], model[16], mvp[16], inv[16];
    for (int i = 0; i < 16; ++i) {
        view[i] = d->view[i];
        proj[i] = d->proj[i];
        model[i] = zero16(d->model) ? (i % 5 == 0 ? 1.0 : 0.0) : d->model[i];
    }
    mat4_mul(proj, view, mvp);
    mat4_mul(mvp, model, mvp);
    const int invertible = meso_mat4_inverse(mvp, inv);
    if (!invertible && need_inverse) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT, "meso_rt_draw: singular view/projection");
        return MESO_ERR_INVALID_ARG;
    }
    for (int i = 0; i < 16; ++i) {
        out->model[i] = (float)model[i];
        out->mvp[i] = (float)mvp[i];
        out->inv_mvp[i] = invertible ? (float)inv[i] : 0.0f;
    }
    out->viewport[2] = out->viewport[3] = 1;
    rt->gl.GetIntegerv(GL_VIEWPORT, out->viewport);
    out->proj11 = fabs(proj[5]);
    out->model_scale = sqrt(model[0] * model[0] + model[1] * model[1] + model[2] * model[2]);
    double light[3] = {0.3, 0.8, 0.5};
    if (d->light_dir[0] != 0.0f || d->light_dir[1] != 0.0f || d->light_dir[2] != 0.0f)
        for (int k = 0; k < 3; ++k)
            light[k] = d->light_dir[k];
    double ll = 0.0;
    for (int k = 0; k < 3; ++k) { /* transpose(mat3(model)) · light */
        const double v = model[4 * k] * light[0] + model[4 * k + 1] * light[1] + model[4 * k + 2] * light[2];
        out->light_obj[k] = (float)v;
        ll += v * v;
    }
    for (int k = 0; k < 3; ++k)
        out->light_obj[k] = ll > 0.0 ? (float)(out->light_obj[k] / sqrt(ll)) : 0.0f;
    const float albedo[3] = {0.80f, 0.74f, 0.66f};
    memcpy(out->albedo, albedo, sizeof(albedo));
    if (d->albedo[0] != 0.0f || d->albedo[1] != 0.0f || d->albedo[2] != 0.0f)
        memcpy(out->albedo, d->albedo, sizeof(out->albedo));
    out->stats = d->stats && rt->stats_ok;
    return MESO_OK;
}

static GLenum binding_of(GLenum target)
{
    switch (target) {
    case GL_TEXTURE_BUFFER: return GL_TEXTURE_BINDING_BUFFER;
    case GL_TEXTURE_2D: return GL_TEXTURE_BINDING_2D;
    case GL_TEXTURE_CUBE_MAP: return GL_TEXTURE_BINDING_CUBE_MAP;
    default: return GL_TEXTURE_BINDING_3D;
    }
}

void mesoi_draw_begin(meso_rt* rt, mesoi_draw* s, GLuint program, int units, const GLenum* targets,
                      const GLuint* textures)
{
    mesoi_gl* gl = &rt->gl;
    s->units = units < MESOI_DRAW_MAX_UNITS ? units : MESOI_DRAW_MAX_UNITS;
    gl->GetIntegerv(GL_CURRENT_PROGRAM, &s->prev_program);
    gl->GetIntegerv(GL_VERTEX_ARRAY_BINDING, &s->prev_vao);
    gl->GetIntegerv(GL_DEPTH_FUNC, &s->prev_func);
    gl->GetIntegerv(GL_DEPTH_WRITEMASK, &s->prev_mask);
    gl->GetIntegerv(GL_ACTIVE_TEXTURE, &s->prev_active);
    gl->GetIntegerv(GL_CULL_FACE_MODE, &s->prev_cull_mode);
    gl->GetIntegerv(GL_FRONT_FACE, &s->prev_front);
    s->prev_test = gl->IsEnabled(GL_DEPTH_TEST);
    s->prev_cull = gl->IsEnabled(GL_CULL_FACE);
    for (int u = 0; u < s->units; ++u) {
        s->target[u] = targets[u];
        gl->ActiveTexture(GL_TEXTURE0 + (GLenum)u);
        gl->GetIntegerv(binding_of(targets[u]), &s->prev_bind[u]);
    }
    if (s->stats)
        gl->GetIntegerv(GL_SHADER_STORAGE_BUFFER_BINDING, &s->prev_ssbo);
    while (gl->GetError() != GL_NO_ERROR) {
    }

    for (int u = 0; u < s->units; ++u) {
        gl->ActiveTexture(GL_TEXTURE0 + (GLenum)u);
        gl->BindTexture(targets[u], textures[u]);
    }
    if (s->stats) {
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
    gl->UseProgram(program);
    gl->UniformMatrix4fv(gl->GetUniformLocation(program, "u_mvp"), 1, GL_FALSE, s->mvp);
    gl->UniformMatrix4fv(gl->GetUniformLocation(program, "u_inv_mvp"), 1, GL_FALSE, s->inv_mvp);
    const float viewport[4] = {(float)s->viewport[0], (float)s->viewport[1], (float)s->viewport[2],
                               (float)s->viewport[3]};
    gl->Uniform4fv(gl->GetUniformLocation(program, "u_viewport"), 1, viewport);
    gl->Uniform3fv(gl->GetUniformLocation(program, "u_light_obj"), 1, s->light_obj);
    gl->Uniform3fv(gl->GetUniformLocation(program, "u_albedo"), 1, s->albedo);

    gl->Enable(GL_DEPTH_TEST);
    gl->DepthFunc(GL_LESS);
    gl->DepthMask(GL_TRUE);
    gl->Enable(GL_CULL_FACE);
    gl->CullFace(GL_FRONT); /* back faces: one fragment per solid, camera inside or not */
    gl->FrontFace(GL_CCW);
    if (!rt->empty_vao)
        gl->GenVertexArrays(1, &rt->empty_vao);
    gl->BindVertexArray(rt->empty_vao); /* both kinds draw from gl_VertexID alone */
}

meso_result mesoi_draw_end(meso_rt* rt, mesoi_draw* s, meso_rt_draw_stats* stats, const char* what)
{
    mesoi_gl* gl = &rt->gl;
    if (s->stats) {
        uint32_t counts[3] = {0, 0, 0};
        gl->MemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        if (rt->gles) { /* ES has no glGetBufferSubData: map the buffer */
            const void* mapped = gl->MapBufferRange(GL_SHADER_STORAGE_BUFFER, 0, sizeof(counts), GL_MAP_READ_BIT);
            if (mapped)
                memcpy(counts, mapped, sizeof(counts));
            gl->UnmapBuffer(GL_SHADER_STORAGE_BUFFER);
        } else {
            gl->GetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof(counts), counts);
        }
        stats->supported = 1;
        stats->fragments = counts[0];
        stats->steps = counts[1];
        stats->hits = counts[2];
        gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, (GLuint)s->prev_ssbo);
    } else if (stats) {
        memset(stats, 0, sizeof(*stats));
    }
    const GLenum e = gl->GetError();

    for (int u = 0; u < s->units; ++u) {
        gl->ActiveTexture(GL_TEXTURE0 + (GLenum)u);
        gl->BindTexture(s->target[u], (GLuint)s->prev_bind[u]);
    }
    gl->ActiveTexture((GLenum)s->prev_active);
    gl->BindVertexArray((GLuint)s->prev_vao);
    gl->UseProgram((GLuint)s->prev_program);
    gl->DepthFunc((GLenum)s->prev_func);
    gl->DepthMask(s->prev_mask ? GL_TRUE : GL_FALSE);
    gl->CullFace((GLenum)s->prev_cull_mode);
    gl->FrontFace((GLenum)s->prev_front);
    if (!s->prev_test)
        gl->Disable(GL_DEPTH_TEST);
    if (s->prev_cull) /* the kind may have changed it after begin */
        gl->Enable(GL_CULL_FACE);
    else
        gl->Disable(GL_CULL_FACE);
    if (e != GL_NO_ERROR) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_ERROR, "meso_rt_draw (%s): GL error 0x%04x", what, e);
        return MESO_ERR_GL;
    }
    return MESO_OK;
}
