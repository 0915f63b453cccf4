/* libmeso context creation on a real (llvmpipe) GL context: every entry
 * point resolves, the version and API (desktop or ES) are read, allocator
 * and logger are honoured, and a missing entry point or a bad desc fails
 * with the documented result and log item (STYLE.md §4 and §9: tests
 * assert on numbered items). Runs on the API tests/common/gl_api.h picks.
 * With the argument `too-old` it makes a context one version short
 * instead (ES 3.0, or core 3.2; Mesa grants them under
 * MESA_GLES_VERSION_OVERRIDE / MESA_GL_VERSION_OVERRIDE, which
 * tests/meson.build sets) and checks that it is refused. */
#include "test_util.h"

#include <GL/glcorearb.h>
#include <string.h>

#include "egl_context.h"
#include "gl_api.h"
#include "meso_rt.h"

typedef struct log_capture {
    int count;
    meso_log_item items[64];
    char last_message[256];
} log_capture;

static void capture(void* user, meso_log_level level, meso_log_item item, const char* message)
{
    (void)level;
    log_capture* c = user;
    if (c->count < 64)
        c->items[c->count] = item;
    c->count++;
    snprintf(c->last_message, sizeof(c->last_message), "%s", message ? message : "");
}

typedef struct counting {
    int live, total;
} counting;

static void* c_alloc(size_t size, void* user)
{
    counting* c = user;
    c->live++;
    c->total++;
    return malloc(size);
}

static void c_free(void* p, void* user)
{
    counting* c = user;
    c->live--;
    free(p);
}

static const char* hidden_name;

static meso_gl_fn gpa_without(const char* name)
{
    if (hidden_name && !strcmp(name, hidden_name))
        return NULL;
    return meso_egl_proc(name);
}

static void creates_with_real_context(void)
{
    log_capture log = {0};
    counting cnt = {0};
    meso_rt* rt = NULL;
    meso_rt_desc d = {.gl_get_proc_address = meso_egl_proc,
                      .allocator = {c_alloc, c_free, &cnt},
                      .log_fn = capture,
                      .log_user = &log};
    assert(meso_rt_create(&d, &rt) == MESO_OK);
    assert(rt);
    const int es = test_gl_api() == MESO_EGL_GLES;
    assert(meso_rt_gl_is_es(rt) == es);
    assert(meso_rt_gl_version(rt) >= (es ? 32 : 33));
    assert(log.count >= 1 && log.items[log.count - 1] == MESO_LOGITEM_CONTEXT_CREATED);
    assert(strstr(log.last_message, es ? "OpenGL ES" : "OpenGL") && (es || !strstr(log.last_message, "OpenGL ES")));
    assert(cnt.total >= 1 && cnt.live >= 1);
    meso_rt_destroy(rt);
    assert(cnt.live == 0);
}

static void missing_entry_point_names_the_function(void)
{
    log_capture log = {0};
    meso_rt* rt = (meso_rt*)&log; /* must be reset to NULL on failure */
    hidden_name = "glDrawElements";
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = gpa_without, .log_fn = capture, .log_user = &log},
                          &rt) == MESO_ERR_GL);
    assert(rt == NULL);
    assert(log.count == 1);
    assert(log.items[0] == MESO_LOGITEM_GL_ENTRY_POINT_MISSING);
    assert(!strcmp(log.last_message, "glDrawElements"));
    hidden_name = NULL;
}

/* Entry points one API lacks (glGetBufferSubData on ES) or only newer
 * versions have (glMemoryBarrier) never fail creation. */
static void optional_entry_points_may_be_missing(void)
{
    static const char* const optional[] = {"glGetBufferSubData", "glMemoryBarrier"};
    for (int i = 0; i < 2; ++i) {
        log_capture log = {0};
        meso_rt* rt = NULL;
        hidden_name = optional[i];
        assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = gpa_without, .log_fn = capture,
                                              .log_user = &log},
                              &rt) == MESO_OK);
        assert(log.items[log.count - 1] == MESO_LOGITEM_CONTEXT_CREATED);
        meso_rt_destroy(rt);
    }
    hidden_name = NULL;
}

/* `too-old`: a context one version short of what libmeso needs. */
static int refuses_old_context(void)
{
    const int api = test_gl_api();
    char why[256];
    meso_egl* e = api < 0 ? NULL : meso_egl_create_api((meso_egl_api)api, api == MESO_EGL_GLES ? 30 : 32, why,
                                                       sizeof(why));
    if (!e)
        fprintf(stderr, "EGL: %s\n", api < 0 ? "MESO_TEST_GL_API: neither gl nor gles" : why);
    assert(e);
    /* The driver may grant a newer version than asked: then this test
     * would prove nothing, so it fails. */
    PFNGLGETSTRINGPROC get_string = (PFNGLGETSTRINGPROC)meso_egl_proc("glGetString");
    const char* version = (const char*)get_string(GL_VERSION);
    printf("context: %s\n", version);
    assert(version && !strncmp(version, api == MESO_EGL_GLES ? "OpenGL ES 3.0" : "3.2", api == MESO_EGL_GLES ? 13 : 3));
    log_capture log = {0};
    meso_rt* rt = (meso_rt*)&log; /* must be reset to NULL on failure */
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .log_fn = capture, .log_user = &log},
                          &rt) == MESO_ERR_GL);
    assert(rt == NULL);
    assert(log.count == 1 && log.items[0] == MESO_LOGITEM_GL_VERSION_TOO_OLD);
    printf("refused: %s\n", log.last_message);
    meso_egl_destroy(e);
    return 0;
}

static void bad_desc_is_invalid_arg(void)
{
    meso_rt* rt = NULL;
    assert(meso_rt_create(NULL, &rt) == MESO_ERR_INVALID_ARG);
    assert(meso_rt_create(&(meso_rt_desc){0}, &rt) == MESO_ERR_INVALID_ARG);
    counting cnt = {0};
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .allocator = {c_alloc, NULL, &cnt}},
                          &rt) == MESO_ERR_INVALID_ARG);
    assert(cnt.total == 0);
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, NULL) == MESO_ERR_INVALID_ARG);
    meso_rt_destroy(NULL);
}

static void log_items_have_strings(void)
{
    for (int i = 0; i < MESO_LOGITEM_COUNT; ++i) {
        const char* s = meso_log_item_string((meso_log_item)i);
        assert(s && s[0]);
        assert(strcmp(s, "unknown log item") != 0);
    }
    assert(!strcmp(meso_log_item_string(MESO_LOGITEM_COUNT), "unknown log item"));
}

int main(int argc, char** argv)
{
    if (argc == 2 && !strcmp(argv[1], "too-old"))
        return refuses_old_context();
    assert(argc == 1);
    char why[256];
    meso_egl* e = test_egl_create(why, sizeof(why));
    if (!e)
        fprintf(stderr, "EGL: %s\n", why);
    assert(e);
    TEST_RUN(creates_with_real_context);
    TEST_RUN(missing_entry_point_names_the_function);
    TEST_RUN(optional_entry_points_may_be_missing);
    TEST_RUN(bad_desc_is_invalid_arg);
    TEST_RUN(log_items_have_strings);
    meso_egl_destroy(e);
    return 0;
}
