/*
 * rt_common.c — what the object kinds share: streaming and checking a
 * chunk, texture and texture-buffer uploads (with the formats OpenGL ES
 * lacks converted), the prelude every shader starts with (desktop or ES),
 * compiling and linking the shaders, and a draw's matrices, light, GL
 * state save/restore and work counters (read back by mapping on ES).
 *
 * The GL state contract of meso_rt_draw (meso_rt.h) lives here: every draw,
 * of every kind, goes through mesoi_draw_begin / mesoi_draw_end. Under
 * MESO_STATE_RESTORE they save and restore the program, vertex array,
 * active texture and the bindings of the units the kind uses, depth
 * test/func/mask, culling, the shader storage binding of the counters and,
 * in the depth pass, the colour mask;
 * under MESO_STATE_HOST_OWNS they query nothing and restore nothing
 * (meso_rt_draw_list, rt_instances.c, saves and restores once around its
 * items and draws them under MESO_STATE_HOST_OWNS). The
 * host's GL error queue is read only when the context was created with
 * check_gl_errors; uploads detect failure from the objects themselves
 * (a texture level's width, a buffer's size).
 */
#include "mat4_inverse.h"
#include "rt_internal.h"
#include "shaders_embedded.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* >>chunks ----------------------------------------------------------------- */

int32_t mesoi_find_chunk(const meso_rt* rt, meso_file* f, uint32_t type, uint32_t object)
{
    /* The level being loaded draws each type's chunk with the smallest lod
     * >= its own (FORMAT.md §7.10); a plain load is level 0: the finest. */
    return meso_file_find_level(f, type, object, rt->load_lod);
}

meso_result mesoi_read_whole(meso_rt* rt, meso_file* f, int32_t ci, void** out, size_t* size)
{
    const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)ci);
    *out = NULL;
    if (c->decoded_size > (uint64_t)PTRDIFF_MAX) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED, "chunk %d too large for this platform", ci);
        return MESO_ERR_UNSUPPORTED;
    }
    void* data = mesoi_stream_take_chunk(rt, ci); /* a streamed level: decoded already (rt_stream.c) */
    if (data) {
        *out = data;
        *size = (size_t)c->decoded_size;
        return MESO_OK;
    }
    data = mesoi_rt_alloc(rt, (size_t)c->decoded_size);
    if (!data)
        return MESO_ERR_OUT_OF_MEMORY;
    meso_error err;
    meso_result r = meso_file_read_chunk(f, (uint32_t)ci, data, (size_t)c->decoded_size, &err);
    if (r != MESO_OK) {
        if (r != MESO_ERR_PENDING) /* not arrived yet is not an error */
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

/* Bytes of one texel of (format, type) as the uploads use them. */
size_t mesoi_texel_bytes(GLenum format, GLenum type, int* components)
{
    *components = format == GL_RGBA ? 4 : format == GL_RG ? 2 : 1;
    const size_t size = type == GL_UNSIGNED_BYTE ? 1 : type == GL_UNSIGNED_SHORT ? 2 : 4;
    return size * (size_t)*components;
}

/* Levels 1.. of the bound texture from level 0's `data`, by the box filter
 * on the host (rt_mip_box.c): one level at a time, each from the one above. */
static meso_result upload_levels_host(meso_rt* rt, GLenum target, const uint32_t dims[3], int dims3, int levels,
                                      GLint internal, GLenum format, GLenum type, const void* data)
{
    mesoi_gl* gl = &rt->gl;
    int components = 1;
    const size_t bytes = mesoi_texel_bytes(format, type, &components);
    uint32_t d1[3];
    for (int k = 0; k < 3; ++k)
        d1[k] = mesoi_mip_size(dims[k], 1); /* a 2D texture has dims[2] = 1 */
    /* Level 1 is the largest: two buffers of its size, used in turn. */
    const size_t n1 = (size_t)d1[0] * d1[1] * d1[2] * bytes;
    uint8_t* buf = mesoi_rt_alloc(rt, 2 * n1);
    if (!buf)
        return MESO_ERR_OUT_OF_MEMORY;
    const void* fine = data;
    uint32_t fd[3] = {dims[0], dims[1], dims[2]};
    for (int l = 1; l < levels; ++l) {
        uint8_t* coarse = buf + (size_t)(l & 1) * n1;
        if (!dims3)
            fd[2] = 1; /* a 2D texture: the box stays in its plane */
        mesoi_mip_box(fine, fd, components, type, coarse);
        for (int k = 0; k < 3; ++k)
            fd[k] = mesoi_mip_size(fd[k], 1);
        if (rt->defer) /* the storage is there (upload_image) */
            mesoi_defer_texture(rt, 0, target, l, fd, format, type, bytes, 0, coarse);
        else if (dims3)
            gl->TexImage3D(target, l, internal, (GLsizei)fd[0], (GLsizei)fd[1], (GLsizei)fd[2], 0, format, type,
                           coarse);
        else
            gl->TexImage2D(target, l, internal, (GLsizei)fd[0], (GLsizei)fd[1], 0, format, type, coarse);
        fine = coarse;
    }
    mesoi_rt_free(rt, buf);
    return MESO_OK;
}

/* glGenerateMipmap takes the format: OpenGL (desktop) for every format the
 * uploads use; OpenGL ES only for colour-renderable, filterable ones, which
 * R8 and SRGB8_ALPHA8 are everywhere and R16_EXT, R16F, R32F are not (they
 * need further extensions), so those are filtered on the host. */
static int gl_generates(const meso_rt* rt, GLint internal)
{
    return !rt->gles || internal == GL_R8 || internal == GL_SRGB8_ALPHA8;
}

/* A new 2D or 3D texture of `dims` texels, repeating in s and t, clamped
 * in r. Without `mips` (or under MESO_FILTER_LEVEL0): level 0 only,
 * `filter` both ways. With: the full chain of levels down to 1 texel (by
 * glGenerateMipmap, or by the host where GL may not), trilinear when
 * minified (GL_LINEAR_MIPMAP_LINEAR), `filter` when magnified. The unit's
 * binding and the unpack state restored. */
static meso_result upload_image(meso_rt* rt, const uint32_t dims[3], int dims3, GLint internal, GLenum format,
                                GLenum type, GLint filter, int mips, const void* data, GLuint* out)
{
    mesoi_gl* gl = &rt->gl;
    const GLenum target = dims3 ? GL_TEXTURE_3D : GL_TEXTURE_2D;
    /* Refused before GL sees it: an invalid TexImage would raise an error
     * in the host's queue. */
    GLint limit = 0;
    gl->GetIntegerv(dims3 ? GL_MAX_3D_TEXTURE_SIZE : GL_MAX_TEXTURE_SIZE, &limit);
    for (int k = 0; k < (dims3 ? 3 : 2); ++k)
        if (dims[k] == 0 || dims[k] > (uint32_t)limit) {
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_ERROR,
                      "a %ux%ux%u texture exceeds this context's limit of %d texels a side", dims[0], dims[1],
                      dims[2], (int)limit);
            *out = 0;
            return MESO_ERR_GL;
        }
    const int levels = mips && rt->mipmaps ? mesoi_mip_levels(dims, dims3) : 1;
    GLint prev_tex = 0;
    gl->GetIntegerv(dims3 ? GL_TEXTURE_BINDING_3D : GL_TEXTURE_BINDING_2D, &prev_tex);
    mesoi_unpack unpack;
    mesoi_unpack_default(rt, &unpack);
    gl->GenTextures(1, out);
    gl->BindTexture(target, *out);
    /* Deferred (rt_transfer.c): every level's storage now, the data later. */
    const int defer = rt->defer != NULL;
    for (int l = 0; l < (defer ? levels : 1); ++l) {
        const uint32_t w = mesoi_mip_size(dims[0], l), h = mesoi_mip_size(dims[1], l);
        if (dims3)
            gl->TexImage3D(target, l, internal, (GLsizei)w, (GLsizei)h, (GLsizei)mesoi_mip_size(dims[2], l), 0,
                           format, type, defer ? NULL : data);
        else
            gl->TexImage2D(target, l, internal, (GLsizei)w, (GLsizei)h, 0, format, type, defer ? NULL : data);
    }
    gl->TexParameteri(target, GL_TEXTURE_MIN_FILTER, levels > 1 ? GL_LINEAR_MIPMAP_LINEAR : filter);
    gl->TexParameteri(target, GL_TEXTURE_MAG_FILTER, filter);
    gl->TexParameteri(target, GL_TEXTURE_WRAP_S, GL_REPEAT);
    gl->TexParameteri(target, GL_TEXTURE_WRAP_T, GL_REPEAT);
    if (dims3)
        gl->TexParameteri(target, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
    gl->TexParameteri(target, GL_TEXTURE_MAX_LEVEL, levels - 1);
    /* A refused or failed TexImage leaves level 0 empty: that is the check,
     * so the host's GL error queue is left alone. */
    GLint width = 0, last = 1;
    gl->GetTexLevelParameteriv(target, 0, GL_TEXTURE_WIDTH, &width);
    meso_result r = MESO_OK;
    if (defer && levels > 1 && width == (GLint)dims[0]) {
        gl->GetTexLevelParameteriv(target, levels - 1, GL_TEXTURE_WIDTH, &last);
    } else if (levels > 1 && width == (GLint)dims[0]) {
        if (gl_generates(rt, internal))
            gl->GenerateMipmap(target);
        else
            r = upload_levels_host(rt, target, dims, dims3, levels, internal, format, type, data);
        gl->GetTexLevelParameteriv(target, levels - 1, GL_TEXTURE_WIDTH, &last);
    }
    gl->BindTexture(target, (GLuint)prev_tex);
    mesoi_unpack_restore(rt, &unpack);
    if (r == MESO_OK && (width != (GLint)dims[0] || last != 1)) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_ERROR, "a %ux%ux%u texture could not be created%s", dims[0],
                  dims[1], dims[2], width == (GLint)dims[0] ? " (its mip levels)" : "");
        r = MESO_ERR_GL;
    }
    if (r == MESO_OK && defer) { /* the texture is sound: its data (and host-built levels) queued */
        int components = 1;
        const size_t texel = mesoi_texel_bytes(format, type, &components);
        const int generates = levels > 1 && gl_generates(rt, internal);
        const uint32_t first = rt->defer->count;
        mesoi_defer_texture(rt, *out, target, 0, dims, format, type, texel, generates, data);
        if (levels > 1 && !generates)
            r = upload_levels_host(rt, target, dims, dims3, levels, internal, format, type, data);
        for (uint32_t k = first; k < rt->defer->count; ++k)
            rt->defer->item[k].name = *out;
        if (r != MESO_OK) /* the texture goes: so does its data */
            mesoi_transfers_drop(rt, rt->defer, first);
    }
    if (r != MESO_OK) {
        gl->DeleteTextures(1, out);
        *out = 0;
    } else {
        uint64_t texels = 0;
        for (int l = 0; l < levels; ++l)
            texels += (uint64_t)mesoi_mip_size(dims[0], l) * mesoi_mip_size(dims[1], l) *
                      (dims3 ? mesoi_mip_size(dims[2], l) : 1);
        rt->gpu_count += texels * mesoi_internal_bytes(internal);
    }
    return r;
}

uint64_t mesoi_gpu_estimate(const meso_rt* rt, const meso_chunk_info* c)
{
    const uint64_t widen = c->dtype == MESO_DTYPE_U16 && !rt->norm16 ? 2 : 1; /* R32F for R16 */
    return c->decoded_size * widen * 4 / 3 + 16; /* + a mesh buffer's alignment of its VCOL (rt_mesh.c) */
}

size_t mesoi_internal_bytes(GLint internal)
{
    switch (internal) {
    case GL_R8:
    case GL_R8UI:
        return 1;
    case GL_R16:
    case GL_R16F:
    case GL_R16UI:
        return 2;
    case GL_RG32F:
        return 8;
    case GL_RGBA32F:
        return 16;
    default: /* R32F, R32UI, SRGB8_ALPHA8, RGBA8 */
        return 4;
    }
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
    const meso_result r = upload_image(rt, dims, dims3, (GLint)internal, GL_RED, type, nearest ? GL_NEAREST : GL_LINEAR,
                                       !nearest, data, out);
    mesoi_rt_free(rt, converted);
    return r;
}

meso_result mesoi_upload_srgba8(meso_rt* rt, const uint32_t dims[3], int dims3, const void* data, GLuint* out)
{
    return upload_image(rt, dims, dims3, GL_SRGB8_ALPHA8, GL_RGBA, GL_UNSIGNED_BYTE, GL_LINEAR, 1, data, out);
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
    GLint stored = 0, prev_tex = 0;
    gl->GetIntegerv(GL_TEXTURE_BINDING_BUFFER, &prev_tex); /* the active unit's: the host's */
    gl->GenBuffers(1, buf);
    gl->BindBuffer(GL_TEXTURE_BUFFER, *buf);
    gl->BufferData(GL_TEXTURE_BUFFER, (GLsizeiptr)size, rt->defer ? NULL : data, GL_DYNAMIC_DRAW);
    gl->GetBufferParameteriv(GL_TEXTURE_BUFFER, GL_BUFFER_SIZE, &stored);
    if (rt->defer && (size_t)stored == size)
        mesoi_defer_buffer(rt, *buf, 0, size, data);
    gl->GenTextures(1, &tex);
    gl->BindTexture(GL_TEXTURE_BUFFER, tex);
    gl->TexBuffer(GL_TEXTURE_BUFFER, format, *buf);
    gl->BindTexture(GL_TEXTURE_BUFFER, (GLuint)prev_tex);
    gl->BindBuffer(GL_TEXTURE_BUFFER, 0);
    if ((size_t)stored == size) {
        rt->gpu_count += size;
    } else { /* out of memory: no store; the error queue stays the host's */
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_ERROR, "a %zu-byte buffer could not be created", size);
        gl->DeleteTextures(1, &tex);
        gl->DeleteBuffers(1, buf);
        *buf = 0;
        return 0;
    }
    return tex;
}

GLint mesoi_upload_begin(meso_rt* rt)
{
    GLint prev = 0;
    rt->gl.GetIntegerv(GL_TEXTURE_BUFFER_BINDING, &prev);
    if (rt->check_gl_errors)
        while (rt->gl.GetError() != GL_NO_ERROR) {
        }
    return prev;
}

meso_result mesoi_upload_end(meso_rt* rt, GLint prev, meso_result r, const char* what)
{
    rt->gl.BindBuffer(GL_TEXTURE_BUFFER, (GLuint)prev);
    const GLenum e = rt->check_gl_errors ? rt->gl.GetError() : GL_NO_ERROR;
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

/* The unpack state of glPixelStorei that TexImage reads, GL's defaults.
 * The last two are desktop only: OpenGL ES has neither (unpack_count). */
static const GLenum unpack_names[] = {GL_UNPACK_ALIGNMENT, GL_UNPACK_ROW_LENGTH, GL_UNPACK_IMAGE_HEIGHT,
                                      GL_UNPACK_SKIP_PIXELS, GL_UNPACK_SKIP_ROWS, GL_UNPACK_SKIP_IMAGES,
                                      GL_UNPACK_SWAP_BYTES, GL_UNPACK_LSB_FIRST};
static const GLint unpack_default[] = {1, 0, 0, 0, 0, 0, 0, 0}; /* alignment 1: texel rows are packed */
enum { UNPACK_COUNT = (int)(sizeof(unpack_names) / sizeof(unpack_names[0])) };

static int unpack_count(const meso_rt* rt)
{
    return rt->gles ? UNPACK_COUNT - 2 : UNPACK_COUNT;
}

void mesoi_unpack_default(meso_rt* rt, mesoi_unpack* u)
{
    mesoi_gl* gl = &rt->gl;
    _Static_assert(UNPACK_COUNT <= (int)(sizeof(u->saved) / sizeof(u->saved[0])), "mesoi_unpack too small");
    for (int i = 0; i < unpack_count(rt); ++i) {
        gl->GetIntegerv(unpack_names[i], &u->saved[i]);
        if (u->saved[i] != unpack_default[i])
            gl->PixelStorei(unpack_names[i], unpack_default[i]);
    }
    u->pbo = 0;
    gl->GetIntegerv(GL_PIXEL_UNPACK_BUFFER_BINDING, &u->pbo);
    if (u->pbo)
        gl->BindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
}

void mesoi_unpack_restore(meso_rt* rt, const mesoi_unpack* u)
{
    for (int i = 0; i < unpack_count(rt); ++i)
        if (u->saved[i] != unpack_default[i])
            rt->gl.PixelStorei(unpack_names[i], u->saved[i]);
    if (u->pbo)
        rt->gl.BindBuffer(GL_PIXEL_UNPACK_BUFFER, (GLuint)u->pbo);
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

int mesoi_frag_sources(const meso_rt* rt, meso_rt_pass pass, const char** src, const char* const* pre,
                       int pre_count, char pass_text[64])
{
    const int hook = pass == MESO_PASS_FORWARD && rt->hook;
    snprintf(pass_text, 64, "#define MESO_PASS %d\n%s", (int)pass, hook ? "#define MESO_HOOK 1\n#line 1\n" : "");
    int n = 1;
    src[n++] = pass_text;
    src[n++] = hook ? rt->hook : "";
    src[n++] = hook ? "\n" : ""; /* a snippet without a final newline */
    for (int i = 0; i < pre_count; ++i)
        src[n++] = pre[i];
    src[n++] = mesoi_glsl_pass_out;
    return n;
}

const char* mesoi_frag_name(const meso_rt* rt, meso_rt_pass pass, const char* file, char buf[96])
{
    if (pass != MESO_PASS_FORWARD || !rt->hook)
        return file;
    snprintf(buf, 96, "%s + shading hook (meso_rt_desc.shading_hook)", file);
    return buf;
}

static const char* const uniform_names[MESOI_U_COUNT] = {
#define MESOI_X_NAME(name) "u_" #name,
    MESOI_UNIFORMS(MESOI_X_NAME)
#undef MESOI_X_NAME
};

GLuint mesoi_program_init(meso_rt* rt, mesoi_program* p, GLuint vs, GLuint fs, const char* name,
                          const char* const* samplers, int sampler_count)
{
    mesoi_gl* gl = &rt->gl;
    p->id = mesoi_link(rt, vs, fs, name);
    p->instanced = 0; /* GL starts every uniform at 0 */
    if (!p->id)
        return 0;
    for (int u = 0; u < MESOI_U_COUNT; ++u)
        p->loc[u] = gl->GetUniformLocation(p->id, uniform_names[u]);
    /* The shading hook's data (meso_rt_desc.shading_hook_binding). */
    const GLuint block = rt->hook ? gl->GetUniformBlockIndex(p->id, "MesoHook") : GL_INVALID_INDEX;
    if (block != GL_INVALID_INDEX)
        gl->UniformBlockBinding(p->id, block, rt->hook_binding);
    const GLint mips = gl->GetUniformLocation(p->id, "u_mips");
    if (sampler_count > 0 || mips >= 0) { /* units and the context's filter never change: set once */
        GLint prev = 0;
        gl->GetIntegerv(GL_CURRENT_PROGRAM, &prev);
        gl->UseProgram(p->id);
        for (int i = 0; i < sampler_count; ++i)
            gl->Uniform1i(gl->GetUniformLocation(p->id, samplers[i]), i);
        gl->Uniform1i(mips, rt->mipmaps); /* raycast_common.glsl tex_level; -1: ignored */
        gl->UseProgram((GLuint)prev);
    }
    return p->id;
}

const mesoi_program* mesoi_program_build(meso_rt* rt, mesoi_program* p, meso_rt_pass pass,
                                         const mesoi_program_src* src)
{
    enum { MAX_FS = 16 };
    const char* fs[MAX_FS] = {src->vs[0]};
    char pass_text[64], fname[96];
    int n = 1;
    if (src->pre_count > MAX_FS - 6)
        return NULL;
    if (src->own_outputs)
        for (int i = 0; i < src->pre_count; ++i)
            fs[n++] = src->pre[i];
    else
        n = mesoi_frag_sources(rt, pass, fs, src->pre, src->pre_count, pass_text);
    fs[n++] = src->frag;
    const char* fname_used = src->own_outputs ? src->frag_file : mesoi_frag_name(rt, pass, src->frag_file, fname);
    const GLuint fsh = mesoi_compile(rt, GL_FRAGMENT_SHADER, fs, n, fname_used);
    mesoi_program_init(rt, p, mesoi_compile(rt, GL_VERTEX_SHADER, src->vs, src->vs_count, src->vs_file), fsh,
                       src->name, src->samplers, src->sampler_count);
    return p->id ? p : NULL;
}

int mesoi_program_owned(const meso_rt* rt, GLuint id)
{
    /* Every program array of struct meso_rt, whatever its dimensions. */
#define MESOI_PROGRAMS(a) {(const mesoi_program*)(a), sizeof(a) / sizeof(mesoi_program)}
    const struct {
        const mesoi_program* p;
        size_t n;
    } lists[] = {MESOI_PROGRAMS(rt->mesh_programs), MESOI_PROGRAMS(rt->shell_programs),
                 MESOI_PROGRAMS(rt->frusta_programs), MESOI_PROGRAMS(rt->cells_programs),
                 MESOI_PROGRAMS(rt->slice_programs)};
#undef MESOI_PROGRAMS
    for (size_t l = 0; l < sizeof(lists) / sizeof(lists[0]); ++l)
        for (size_t i = 0; i < lists[l].n; ++i)
            if (lists[l].p[i].id == id)
                return 1;
    return 0;
}

void mesoi_program_delete(meso_rt* rt, mesoi_program* p)
{
    if (p->id)
        rt->gl.DeleteProgram(p->id);
    memset(p, 0, sizeof(*p));
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

/* A similarity: the three columns of the upper 3x3 orthogonal and of one
 * length, nothing projective. Relative tolerance 1e-4 (float matrices
 * built by hosts carry rounding). */
static int similarity(const double m[16], double* scale, int* mirrored)
{
    double len[3], dot[3];
    for (int c = 0; c < 3; ++c)
        len[c] = sqrt(m[4 * c] * m[4 * c] + m[4 * c + 1] * m[4 * c + 1] + m[4 * c + 2] * m[4 * c + 2]);
    for (int c = 0; c < 3; ++c) {
        const int d = (c + 1) % 3;
        dot[c] = m[4 * c] * m[4 * d] + m[4 * c + 1] * m[4 * d + 1] + m[4 * c + 2] * m[4 * d + 2];
    }
    *scale = len[0];
    const double tol = 1e-4 * len[0];
    const double det = m[0] * (m[5] * m[10] - m[9] * m[6]) - m[4] * (m[1] * m[10] - m[9] * m[2]) +
                       m[8] * (m[1] * m[6] - m[5] * m[2]);
    *mirrored = det < 0.0;
    return len[0] > 0.0 && fabs(len[1] - len[0]) <= tol && fabs(len[2] - len[0]) <= tol &&
           fabs(dot[0]) <= tol * len[0] && fabs(dot[1]) <= tol * len[0] && fabs(dot[2]) <= tol * len[0] &&
           m[3] == 0.0 && m[7] == 0.0 && m[11] == 0.0 && m[15] == 1.0;
}

int mesoi_model_similarity(const float* model_in, int* mirrored)
{
    double model[16], scale;
    const int identity = zero16(model_in);
    for (int i = 0; i < 16; ++i)
        model[i] = identity ? (i % 5 == 0 ? 1.0 : 0.0) : model_in[i];
    return similarity(model, &scale, mirrored);
}

meso_result mesoi_draw_model(meso_rt* rt, mesoi_draw* out, const float* model_in, int need_inverse, int64_t index)
{
    double model[16], mvp[16], inv[16];
    const int identity = zero16(model_in);
    for (int i = 0; i < 16; ++i)
        model[i] = identity ? (i % 5 == 0 ? 1.0 : 0.0) : model_in[i];
    char who[64] = "meso_rt_draw";
    if (index >= 0)
        snprintf(who, sizeof(who), "meso_rt_draw_instanced: instance %lld", (long long)index);
    if (!similarity(model, &out->model_scale, &out->mirrored)) {
        /* The ray casters' error bounds and shading assume one scale; a
         * sheared or stretched object would be drawn wrong, so say so. */
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                  "%s: model matrix is not rotation + uniform scale + translation (column lengths "
                  "%g %g %g); bake the scale into the object instead",
                  who, sqrt(model[0] * model[0] + model[1] * model[1] + model[2] * model[2]),
                  sqrt(model[4] * model[4] + model[5] * model[5] + model[6] * model[6]),
                  sqrt(model[8] * model[8] + model[9] * model[9] + model[10] * model[10]));
        return MESO_ERR_INVALID_ARG;
    }
    mat4_mul(out->pv, model, mvp);
    const int invertible = meso_mat4_inverse(mvp, inv);
    if (!invertible && need_inverse) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT, "%s: singular view/projection", who);
        return MESO_ERR_INVALID_ARG;
    }
    for (int i = 0; i < 16; ++i) {
        out->model[i] = (float)model[i];
        out->mvp[i] = (float)mvp[i];
        out->inv_mvp[i] = invertible ? (float)inv[i] : 0.0f;
    }
    const double* light = out->light_world;
    double ll = 0.0;
    for (int k = 0; k < 3; ++k) { /* transpose(mat3(model)) · light */
        const double v = model[4 * k] * light[0] + model[4 * k + 1] * light[1] + model[4 * k + 2] * light[2];
        out->light_obj[k] = (float)v;
        ll += v * v;
    }
    for (int k = 0; k < 3; ++k)
        out->light_obj[k] = ll > 0.0 ? (float)(out->light_obj[k] / sqrt(ll)) : 0.0f;
    return MESO_OK;
}

meso_result mesoi_draw_prepare(meso_rt* rt, const meso_rt_draw_desc* d, int need_inverse, int instanced,
                               mesoi_draw* out)
{
    memset(out, 0, sizeof(*out));
    if (d->stats)
        memset(d->stats, 0, sizeof(*d->stats));
    if ((unsigned)d->depth > MESO_DEPTH_REVERSED || (unsigned)d->clip_depth > MESO_CLIP_DEPTH_ZERO_TO_ONE ||
        d->viewport[2] < 0 || d->viewport[3] < 0 || (unsigned)d->pass >= MESO_PASS_COUNT ||
        (d->depth_func && (d->depth_func < GL_NEVER || d->depth_func > GL_ALWAYS))) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                  "meso_rt_draw: depth %d, clip_depth %d, viewport %dx%d, pass %d or depth_func 0x%04x out of range",
                  (int)d->depth, (int)d->clip_depth, (int)d->viewport[2], (int)d->viewport[3], (int)d->pass,
                  (unsigned)d->depth_func);
        return MESO_ERR_INVALID_ARG;
    }
    double view[16], proj[16];
    for (int i = 0; i < 16; ++i) {
        view[i] = d->view[i];
        proj[i] = d->proj[i];
    }
    mat4_mul(proj, view, out->pv);
    double light[3] = {0.3, 0.8, 0.5};
    if (d->light_dir[0] != 0.0f || d->light_dir[1] != 0.0f || d->light_dir[2] != 0.0f)
        for (int k = 0; k < 3; ++k)
            light[k] = d->light_dir[k];
    memcpy(out->light_world, light, sizeof(light));
    if (!instanced) {
        const meso_result r = mesoi_draw_model(rt, out, d->model, need_inverse, -1);
        if (r != MESO_OK)
            return r;
    }
    if (d->viewport[2] > 0 && d->viewport[3] > 0) {
        memcpy(out->viewport, d->viewport, sizeof(out->viewport));
    } else {
        out->viewport[2] = out->viewport[3] = 1;
        rt->gl.GetIntegerv(GL_VIEWPORT, out->viewport);
    }
    /* NDC depth of the near plane, a point between (finite even when the far
     * plane is at infinity, where proj maps it to w = 0) and the far plane. */
    const float lo = d->clip_depth == MESO_CLIP_DEPTH_ZERO_TO_ONE ? 0.0f : -1.0f;
    out->reversed = d->depth == MESO_DEPTH_REVERSED;
    out->depth_ndc[0] = out->reversed ? 1.0f : lo;
    out->depth_ndc[2] = out->reversed ? lo : 1.0f;
    out->depth_ndc[1] = 0.5f * (out->depth_ndc[0] + out->depth_ndc[2]);
    out->depth_ndc[3] = d->clip_depth == MESO_CLIP_DEPTH_ZERO_TO_ONE ? 1.0f : 0.0f;
    out->depth_func = (GLenum)d->depth_func;
    out->restore = rt->state_policy == MESO_STATE_RESTORE;
    out->proj11 = fabs(proj[5]);
    out->instanced = instanced;
    const float albedo[3] = {0.80f, 0.74f, 0.66f};
    memcpy(out->albedo, albedo, sizeof(albedo));
    if (d->albedo[0] != 0.0f || d->albedo[1] != 0.0f || d->albedo[2] != 0.0f)
        memcpy(out->albedo, d->albedo, sizeof(out->albedo));
    out->stats = d->stats && rt->stats_ok;
    out->pass = d->pass;
    return MESO_OK;
}

GLenum mesoi_near_func(const mesoi_draw* s)
{
    return s->reversed ? GL_GREATER : GL_LESS;
}

float mesoi_far_clear(const mesoi_draw* s)
{
    return s->reversed ? 0.0f : 1.0f;
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

void mesoi_ssbo_save(meso_rt* rt, mesoi_ssbo* b)
{
    mesoi_gl* gl = &rt->gl;
    gl->GetIntegerv(GL_SHADER_STORAGE_BUFFER_BINDING, &b->generic);
    gl->GetIntegeri_v(GL_SHADER_STORAGE_BUFFER_BINDING, 0, &b->indexed);
    gl->GetInteger64i_v(GL_SHADER_STORAGE_BUFFER_START, 0, &b->start);
    gl->GetInteger64i_v(GL_SHADER_STORAGE_BUFFER_SIZE, 0, &b->size);
}

void mesoi_ssbo_restore(meso_rt* rt, const mesoi_ssbo* b)
{
    mesoi_gl* gl = &rt->gl;
    if (b->indexed && b->size > 0)
        gl->BindBufferRange(GL_SHADER_STORAGE_BUFFER, 0, (GLuint)b->indexed, (GLintptr)b->start,
                            (GLsizeiptr)b->size);
    else
        gl->BindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, (GLuint)b->indexed);
    gl->BindBuffer(GL_SHADER_STORAGE_BUFFER, (GLuint)b->generic); /* after: BindBufferBase sets it too */
}

void mesoi_image_save(meso_rt* rt, mesoi_image_unit* u)
{
    static const GLenum names[6] = {GL_IMAGE_BINDING_NAME,  GL_IMAGE_BINDING_LEVEL,  GL_IMAGE_BINDING_LAYERED,
                                    GL_IMAGE_BINDING_LAYER, GL_IMAGE_BINDING_ACCESS, GL_IMAGE_BINDING_FORMAT};
    GLint* out[6] = {&u->name, &u->level, &u->layered, &u->layer, &u->access, &u->format};
    for (int i = 0; i < 6; ++i)
        rt->gl.GetIntegeri_v(names[i], 0, out[i]);
}

void mesoi_image_restore(meso_rt* rt, const mesoi_image_unit* u)
{
    rt->gl.BindImageTexture(0, (GLuint)u->name, u->level, u->layered ? GL_TRUE : GL_FALSE, u->layer,
                            (GLenum)u->access, (GLenum)u->format);
}

void mesoi_draw_use(meso_rt* rt, const mesoi_draw* s, const mesoi_program* p)
{
    mesoi_gl* gl = &rt->gl;
    if (!rt->in_list || rt->list_program != p->id) /* a list binds each program once */
        gl->UseProgram(p->id);
    rt->list_program = p->id;
    gl->UniformMatrix4fv(p->loc[MESOI_U_mvp], 1, GL_FALSE, s->mvp);
    gl->UniformMatrix4fv(p->loc[MESOI_U_inv_mvp], 1, GL_FALSE, s->inv_mvp);
    const float viewport[4] = {(float)s->viewport[0], (float)s->viewport[1], (float)s->viewport[2],
                               (float)s->viewport[3]};
    gl->Uniform4fv(p->loc[MESOI_U_viewport], 1, viewport);
    gl->Uniform3fv(p->loc[MESOI_U_light_obj], 1, s->light_obj);
    gl->Uniform3fv(p->loc[MESOI_U_albedo], 1, s->albedo);
    gl->Uniform4fv(p->loc[MESOI_U_depth_ndc], 1, s->depth_ndc);
    if (p->instanced != s->instanced) { /* the program's cache of its own uniform */
        gl->Uniform1i(p->loc[MESOI_U_instanced], s->instanced);
        ((mesoi_program*)p)->instanced = s->instanced;
    }
    if (s->instanced)
        gl->Uniform1i(p->loc[MESOI_U_instance_base], 0);
    gl->UniformMatrix4fv(p->loc[MESOI_U_model], 1, GL_FALSE, s->model); /* pass_out.glsl: world space */
}

void mesoi_draw_begin(meso_rt* rt, mesoi_draw* s, const mesoi_program* program, int raycast, int units,
                      const GLenum* targets, const GLuint* textures)
{
    mesoi_gl* gl = &rt->gl;
    s->units = units < MESOI_DRAW_MAX_UNITS ? units : MESOI_DRAW_MAX_UNITS;
    if (s->restore) {
        gl->GetIntegerv(GL_CURRENT_PROGRAM, &s->prev_program);
        gl->GetIntegerv(GL_VERTEX_ARRAY_BINDING, &s->prev_vao);
        gl->GetIntegerv(GL_DEPTH_FUNC, &s->prev_func);
        gl->GetIntegerv(GL_DEPTH_WRITEMASK, &s->prev_mask);
        gl->GetIntegerv(GL_ACTIVE_TEXTURE, &s->prev_active);
        gl->GetIntegerv(GL_CULL_FACE_MODE, &s->prev_cull_mode);
        gl->GetIntegerv(GL_FRONT_FACE, &s->prev_front);
        s->prev_test = gl->IsEnabled(GL_DEPTH_TEST);
        s->prev_cull = gl->IsEnabled(GL_CULL_FACE);
        if (s->stats)
            mesoi_ssbo_save(rt, &s->prev_ssbo);
        if (s->pass == MESO_PASS_DEPTH)
            gl->GetBooleanv(GL_COLOR_WRITEMASK, s->prev_color_mask);
    }
    if (s->pass == MESO_PASS_DEPTH) /* the depth shaders have no colour output: nothing undefined lands */
        gl->ColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    if (rt->check_gl_errors)
        while (gl->GetError() != GL_NO_ERROR) {
        }

    for (int u = 0; u < s->units; ++u) {
        s->target[u] = targets[u];
        gl->ActiveTexture(GL_TEXTURE0 + (GLenum)u);
        if (s->restore)
            gl->GetIntegerv(binding_of(targets[u]), &s->prev_bind[u]);
        gl->BindTexture(targets[u], textures[u]);
    }
    if (s->stats) {
        const uint32_t zero[4] = {0, 0, 0, 0};
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
    mesoi_draw_use(rt, s, program);

    gl->Enable(GL_DEPTH_TEST);
    if (s->depth_func)
        gl->DepthFunc(s->depth_func);
    gl->DepthMask(GL_TRUE);
    if (raycast) {
        gl->Enable(GL_CULL_FACE);
        gl->CullFace(GL_FRONT); /* back faces: one fragment per solid, camera inside or not */
        gl->FrontFace(s->mirrored ? GL_CW : GL_CCW); /* a mirroring model turns the winding over */
    }
    if (!rt->empty_vao)
        gl->GenVertexArrays(1, &rt->empty_vao);
    gl->BindVertexArray(rt->empty_vao); /* both kinds draw from gl_VertexID alone */
}

meso_result mesoi_draw_end(meso_rt* rt, mesoi_draw* s, meso_rt_draw_stats* stats, const char* what)
{
    mesoi_gl* gl = &rt->gl;
    if (s->stats) {
        uint32_t counts[4] = {0, 0, 0, 0};
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
        stats->rejected = counts[3];
        if (s->restore)
            mesoi_ssbo_restore(rt, &s->prev_ssbo);
    } else if (stats) {
        memset(stats, 0, sizeof(*stats));
    }
    const GLenum e = rt->check_gl_errors ? gl->GetError() : GL_NO_ERROR;

    if (s->restore) {
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
        if (s->pass == MESO_PASS_DEPTH)
            gl->ColorMask(s->prev_color_mask[0], s->prev_color_mask[1], s->prev_color_mask[2],
                          s->prev_color_mask[3]);
        if (!s->prev_test)
            gl->Disable(GL_DEPTH_TEST);
        if (s->prev_cull) /* the kind may have changed it after begin */
            gl->Enable(GL_CULL_FACE);
        else
            gl->Disable(GL_CULL_FACE);
    }
    if (e != GL_NO_ERROR) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_ERROR, "meso_rt_draw (%s): GL error 0x%04x", what, e);
        return MESO_ERR_GL;
    }
    return MESO_OK;
}
