/*
 * meso_rt.c — runtime context: allocator, logger, GL function table.
 *
 * Loading follows sokol's X-macro table (STYLE.md §6) with one departure:
 * the table lives inside meso_rt, not in statics, so the library keeps no
 * global state. A missing entry point fails creation and names the function.
 * The context is OpenGL 3.3 core or newer, or OpenGL ES 3.2 (told apart by
 * GL_VERSION); rt_gl.h lists what both have.
 */
#include "rt_internal.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char* const log_item_strings[MESO_LOGITEM_COUNT] = {
#define MESO_X_STRING(id, text) text,
    MESO_LOG_ITEMS(MESO_X_STRING)
#undef MESO_X_STRING
};

const char* meso_log_item_string(meso_log_item item)
{
    return (unsigned)item < MESO_LOGITEM_COUNT ? log_item_strings[item] : "unknown log item";
}

static void* default_alloc(size_t size, void* user)
{
    (void)user;
    return malloc(size);
}

static void default_free(void* p, void* user)
{
    (void)user;
    free(p);
}

void* mesoi_rt_alloc(meso_rt* rt, size_t size)
{
    void* p = rt->alloc.alloc_fn(size ? size : 1, rt->alloc.user);
    if (!p)
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_OUT_OF_MEMORY, "%zu bytes", size);
    return p;
}

void mesoi_rt_free(meso_rt* rt, void* p)
{
    if (p)
        rt->alloc.free_fn(p, rt->alloc.user);
}

void mesoi_log(meso_rt* rt, meso_log_level level, meso_log_item item, const char* fmt, ...)
{
    if (!rt->log_fn)
        return;
    char msg[512];
    const char* detail = NULL;
    if (fmt) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg, sizeof(msg), fmt, ap);
        va_end(ap);
        detail = msg;
    }
    rt->log_fn(rt->log_user, level, item, detail);
}

/* Resolve every entry of MESO_GL_FUNCS; report each missing one. */
static int load_gl(meso_rt* rt, meso_gl_get_proc_fn gpa)
{
    int missing = 0;
#define MESO_X_LOAD(type, name)                                                             \
    {                                                                                       \
        meso_gl_fn fn = gpa("gl" #name);                                                    \
        if (!fn) {                                                                          \
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_ENTRY_POINT_MISSING, "gl" #name); \
            ++missing;                                                                      \
        }                                                                                   \
        /* Function pointer conversion between GL prototypes is how every loader works. */ \
        memcpy(&rt->gl.name, &fn, sizeof(fn));                                              \
    }
    MESO_GL_FUNCS(MESO_X_LOAD)
#undef MESO_X_LOAD
#define MESO_X_LOAD_OPTIONAL(type, name)         \
    {                                            \
        meso_gl_fn fn = gpa("gl" #name);         \
        memcpy(&rt->gl.name, &fn, sizeof(fn));   \
    }
    MESO_GL_FUNCS_OPTIONAL(MESO_X_LOAD_OPTIONAL)
#undef MESO_X_LOAD_OPTIONAL
    return missing == 0;
}

/* What the context offers beyond the required version: on ES the two
 * texture extensions the uploads use when present, and on both APIs
 * whether fragment shaders may write shader storage (the stats counters). */
static void query_features(meso_rt* rt)
{
    mesoi_gl* gl = &rt->gl;
    rt->norm16 = rt->float_linear = !rt->gles;
    int images = 0, clear = !rt->gles && rt->gl_version >= 44;
    GLint n = 0;
    gl->GetIntegerv(GL_NUM_EXTENSIONS, &n);
    for (GLint i = 0; i < n; ++i) {
        const char* e = (const char*)gl->GetStringi(GL_EXTENSIONS, (GLuint)i);
        if (!e)
            continue;
        if (rt->gles && strcmp(e, "GL_EXT_texture_norm16") == 0)
            rt->norm16 = 1;
        if (rt->gles && strcmp(e, "GL_OES_texture_float_linear") == 0)
            rt->float_linear = 1;
        if (strcmp(e, rt->gles ? "GL_EXT_clear_texture" : "GL_ARB_clear_texture") == 0)
            clear = 1;
        if (!rt->gles && strcmp(e, "GL_ARB_shader_image_load_store") == 0)
            images = 1; /* the shells' #extension directive names it (rt_shell.c) */
    }
    /* The shells' hit image (rt_shell.c): an R32UI image with atomics in
     * fragment shaders (OpenGL 4.2 and the extension named; ES 3.2), immutable
     * storage and a clear per draw. */
    GLint frag_images = 0;
    if (rt->gles || images)
        gl->GetIntegerv(GL_MAX_FRAGMENT_IMAGE_UNIFORMS, &frag_images);
    if (rt->gles)
        gl->ClearTexSubImage = gl->ClearTexSubImageEXT;
    rt->hull_reject_ok = (rt->gles || (images && rt->gl_version >= 42)) && frag_images > 0 && clear &&
                         gl->BindImageTexture && gl->TexStorage2D && gl->ClearTexSubImage && gl->MemoryBarrier;
    /* Fragment shader storage: OpenGL 4.3 guarantees 8 blocks, ES 3.1+ may have 0. */
    GLint blocks = 0;
    if (rt->gles || rt->gl_version >= 43)
        gl->GetIntegerv(GL_MAX_FRAGMENT_SHADER_STORAGE_BLOCKS, &blocks);
    rt->stats_ok = (rt->gles || rt->gl_version >= 43) && blocks > 0 && gl->MemoryBarrier &&
                   (rt->gles || gl->GetBufferSubData);
}

/* The host's shading hook alone, called once with its documented
 * signature: a broken snippet is reported here, named, rather than inside
 * some kind's shader at its first draw. */
static int hook_compiles(meso_rt* rt)
{
    const char* src[4] = {mesoi_glsl_prelude(rt, 0), "#line 1\n", rt->hook,
                          "\nout vec4 meso_check;\nvoid main() { meso_check = vec4(meso_shade(vec3(0.5), "
                          "vec3(0.0, 0.0, 1.0), vec3(0.0), vec3(0.0, 0.0, 1.0)), 1.0); }\n"};
    const GLuint s = mesoi_compile(rt, GL_FRAGMENT_SHADER, src, 4, "shading hook (meso_rt_desc.shading_hook)");
    if (s)
        rt->gl.DeleteShader(s);
    return s != 0;
}

meso_result meso_rt_create(const meso_rt_desc* desc, meso_rt** out)
{
    if (!out)
        return MESO_ERR_INVALID_ARG;
    *out = NULL;
    if (!desc || !desc->gl_get_proc_address)
        return MESO_ERR_INVALID_ARG;
    if (!desc->allocator.alloc_fn != !desc->allocator.free_fn)
        return MESO_ERR_INVALID_ARG; /* both or neither (STYLE.md §5) */
    if ((unsigned)desc->state_policy > MESO_STATE_HOST_OWNS || (unsigned)desc->texture_filter >= MESO_FILTER_COUNT) {
        if (desc->log_fn)
            desc->log_fn(desc->log_user, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                         (unsigned)desc->texture_filter >= MESO_FILTER_COUNT ? "meso_rt_desc.texture_filter"
                                                                             : "meso_rt_desc.state_policy");
        return MESO_ERR_INVALID_ARG;
    }

    meso_allocator a = desc->allocator;
    if (!a.alloc_fn) {
        a.alloc_fn = default_alloc;
        a.free_fn = default_free;
        a.user = NULL;
    }
    meso_rt* rt = a.alloc_fn(sizeof(meso_rt), a.user);
    if (!rt) {
        if (desc->log_fn)
            desc->log_fn(desc->log_user, MESO_LOG_ERROR, MESO_LOGITEM_OUT_OF_MEMORY, "meso_rt");
        return MESO_ERR_OUT_OF_MEMORY;
    }
    memset(rt, 0, sizeof(*rt));
    rt->alloc = a;
    rt->log_fn = desc->log_fn;
    rt->log_user = desc->log_user;

    if (!load_gl(rt, desc->gl_get_proc_address)) {
        meso_rt_destroy(rt);
        return MESO_ERR_GL;
    }
    /* The version from GL_VERSION ("3.3 ...", "4.5 (Core Profile) Mesa ..."):
     * GL_MAJOR_VERSION would raise an error on contexts older than 3.0, and
     * the host's GL error queue is not the runtime's to touch. */
    const GLubyte* version = rt->gl.GetString(GL_VERSION);
    int major = 0, minor = 0;
    if (version) {
        const char* v = (const char*)version;
        while (*v && (*v < '0' || *v > '9'))
            ++v;
        if (sscanf(v, "%d.%d", &major, &minor) != 2)
            major = minor = 0;
    }
    rt->gl_version = major * 10 + minor;
    rt->state_policy = desc->state_policy;
    rt->check_gl_errors = desc->check_gl_errors != 0;
    rt->budget = desc->memory_budget;
    rt->stream_requests = desc->stream_requests != 0;
    rt->tau_scale = 1.0;
    rt->mipmaps = desc->texture_filter == MESO_FILTER_MIPMAP;
    /* OpenGL ES says so at the start of GL_VERSION ("OpenGL ES 3.2 Mesa ..."). */
    rt->gles = version && strncmp((const char*)version, "OpenGL ES", 9) == 0;
    if (rt->gl_version < (rt->gles ? 32 : 33)) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_VERSION_TOO_OLD, "context reports \"%s\" (needs %s)",
                  version ? (const char*)version : "(null)", rt->gles ? "OpenGL ES 3.2" : "OpenGL 3.3 core");
        meso_rt_destroy(rt);
        return MESO_ERR_GL;
    }
    query_features(rt);
    rt->hook_binding = desc->shading_hook_binding;
    if (desc->shading_hook) {
        const size_t len = strlen(desc->shading_hook);
        rt->hook = mesoi_rt_alloc(rt, len + 1);
        if (!rt->hook) {
            meso_rt_destroy(rt);
            return MESO_ERR_OUT_OF_MEMORY;
        }
        memcpy(rt->hook, desc->shading_hook, len + 1);
        if (!hook_compiles(rt)) {
            meso_rt_destroy(rt);
            return MESO_ERR_GL;
        }
    }
    meso_result pr = mesoi_mesh_prepare(rt, MESO_PASS_FORWARD);
    if (pr != MESO_OK) {
        meso_rt_destroy(rt);
        return pr;
    }
    if (desc->prepare && (pr = meso_rt_prepare(rt, 0)) != MESO_OK) {
        meso_rt_destroy(rt);
        return pr;
    }
    const GLubyte* renderer = rt->gl.GetString(GL_RENDERER);
    mesoi_log(rt, MESO_LOG_INFO, MESO_LOGITEM_CONTEXT_CREATED, "OpenGL %s%d.%d, %s", rt->gles ? "ES " : "", major,
              minor, renderer ? (const char*)renderer : "unknown renderer");
    *out = rt;
    return MESO_OK;
}

void meso_rt_destroy(meso_rt* rt)
{
    if (!rt)
        return;
    /* Requests first (those of released objects the host held, and levels
     * part way up, whose objects they release while the table is whole). */
    mesoi_stream_destroy(rt);
    mesoi_objects_destroy(rt);
    /* A deleted program stays current (MESO_STATE_HOST_OWNS leaves the last
     * one bound) and its name turns invalid: unbind ours first, so the
     * host's next glGetIntegerv(GL_CURRENT_PROGRAM) / glUseProgram pair
     * does not raise GL_INVALID_VALUE. */
    GLint current = 0;
    rt->gl.GetIntegerv(GL_CURRENT_PROGRAM, &current);
    if (current && mesoi_program_owned(rt, (GLuint)current))
        rt->gl.UseProgram(0);
    mesoi_instances_destroy(rt);
    mesoi_frusta_programs_destroy(rt);
    mesoi_cells_programs_destroy(rt);
    mesoi_shell_programs_destroy(rt);
    for (int pass = 0; pass < MESO_PASS_COUNT; ++pass)
        mesoi_program_delete(rt, &rt->mesh_programs[pass]);
    mesoi_rt_free(rt, rt->hook);
    meso_allocator a = rt->alloc;
    a.free_fn(rt, a.user);
}

int meso_rt_gl_version(const meso_rt* rt)
{
    return rt ? rt->gl_version : 0;
}

int meso_rt_gl_is_es(const meso_rt* rt)
{
    return rt ? rt->gles : 0;
}

meso_result meso_rt_prepare(meso_rt* rt, uint32_t flags)
{
    if (!rt || (flags & ~(MESO_PREPARE_STATS | MESO_PREPARE_ALL_PASSES)))
        return MESO_ERR_INVALID_ARG;
    const int passes = flags & MESO_PREPARE_ALL_PASSES ? MESO_PASS_COUNT : 1;
    for (int pass = 0; pass < passes; ++pass) {
        const meso_rt_pass p = (meso_rt_pass)pass;
        meso_result r = mesoi_mesh_prepare(rt, p);
        for (int stats = 0; r == MESO_OK && stats <= ((flags & MESO_PREPARE_STATS) && rt->stats_ok ? 1 : 0);
             ++stats) {
            r = mesoi_shell_prepare(rt, stats, p);
            if (r == MESO_OK)
                r = mesoi_frusta_prepare(rt, stats, p);
            if (r == MESO_OK)
                r = mesoi_cells_prepare(rt, stats, p);
        }
        if (r != MESO_OK)
            return r;
    }
    return MESO_OK;
}
