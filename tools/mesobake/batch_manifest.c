/* batch_manifest.c — read and check a `mesobake batch` manifest (batch.h).
 *
 *   {"defaults": {"command": "shell", "args": ["--thickness-rel", "0.05"]},
 *    "jobs": [{"name": "a", "command": "shell", "input": "a.obj",
 *              "output": "out/a.meso", "args": ["--texture", "bricks"]}]}
 *
 * The schema is tools/mesobake/schema/manifest.schema.json; this file checks
 * the same rules, so a manifest is refused before any job runs, with the
 * JSON path of the problem. Decided where a person would have to guess:
 * unknown and repeated fields are errors (a misspelt "ouput" must not bake
 * to nowhere, a second "output" must not be ignored); a job's args follow
 * the defaults' args (a later option wins in every command); paths are
 * relative to the manifest's directory; the options the batch sets itself
 * are refused in args rather than silently overridden, and so is --help
 * (a job that bakes nothing).
 */
#include "batch.h"

#include <errno.h>
#include <limits.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "cli_util.h"

static const char* const commands[] = {"mesh", "shell", "cells", "frusta"};
static const char* const owned_options[] = {"-i", "--input", "-o", "--output", "--report", "-j", "--threads"};
/* A job is a bake: with these the command prints its help, exits 0 and
 * writes nothing, which --no-cache would report as baked. */
static const char* const no_bake_options[] = {"-h", "--help"};

int batch_command_threaded(const char* command)
{
    return !strcmp(command, "shell") || !strcmp(command, "cells");
}

static meso_result fail(meso_error* err, const char* path, uint32_t code, const char* fmt, ...) CLI_PRINTF(4, 5);
static meso_result fail(meso_error* err, const char* path, uint32_t code, const char* fmt, ...)
{
    char msg[200];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return meso_bake_fail(err, code == BATCH_ISSUE_UNREADABLE ? MESO_ERR_IO : MESO_ERR_CORRUPT, code, "%s: %s", path,
                          msg);
}

/* "prefix" "/" "rest", or a copy of `rest` when it is absolute. */
static char* join_path(const char* dir, const char* rest)
{
    if (rest[0] == '/')
        return strdup(rest);
    size_t a = strlen(dir), b = strlen(rest);
    char* s = malloc(a + b + 2);
    if (s) {
        memcpy(s, dir, a);
        s[a] = '/';
        memcpy(s + a + 1, rest, b + 1);
    }
    return s;
}

/* A copy of the absolute `path` spelt one way: "." and empty components
 * dropped, "dir/.." folded (lexically: a symbolic link before ".." is not
 * followed). So "out/a.meso", "out/./a.meso" and "out//a.meso" are one
 * output. NULL when out of memory. */
static char* plain_path(const char* path)
{
    char* s = strdup(path);
    if (!s)
        return NULL;
    size_t n = 0; /* s[0..n) is the result; it never overtakes the reading */
    for (const char* in = path; *in;) {
        while (*in == '/')
            ++in;
        const char* end = in;
        while (*end && *end != '/')
            ++end;
        const size_t len = (size_t)(end - in);
        if (len == 2 && in[0] == '.' && in[1] == '.') {
            while (n > 0 && s[n - 1] != '/')
                --n;
            n -= n > 0; /* and its slash */
        } else if (len > 0 && !(len == 1 && in[0] == '.')) {
            s[n++] = '/';
            memmove(s + n, in, len);
            n += len;
        }
        in = end;
    }
    if (n == 0)
        s[n++] = '/';
    s[n] = 0;
    return s;
}

typedef struct named_index {
    const char* name;
    size_t index;
} named_index;

static int by_name_then_index(const void* a, const void* b)
{
    const named_index *x = a, *y = b;
    const int c = strcmp(x->name, y->name);
    return c ? c : (x->index > y->index) - (x->index < y->index);
}

int batch_group_equal(const char* const* names, size_t n, size_t* first_of)
{
    named_index* v = malloc((n ? n : 1) * sizeof *v);
    if (!v)
        return 0;
    for (size_t i = 0; i < n; ++i)
        v[i] = (named_index){names[i], i};
    qsort(v, n, sizeof *v, by_name_then_index);
    for (size_t i = 0; i < n; ++i)
        first_of[v[i].index] = i > 0 && !strcmp(v[i - 1].name, v[i].name) ? first_of[v[i - 1].index] : v[i].index;
    free(v);
    return 1;
}

/* Two jobs writing one file, however its path is spelt: MESO_OK or E3455.
 * Sorted, not compared pairwise: a manifest of 50,000 jobs loads at once. */
static meso_result check_outputs_distinct(const batch_manifest* m, meso_error* err)
{
    char** plain = calloc(m->count, sizeof *plain);
    meso_result r = plain ? MESO_OK : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "%s: out of memory", m->path);
    for (size_t a = 0; a < m->count && r == MESO_OK; ++a)
        if (!(plain[a] = plain_path(m->jobs[a].output_path)))
            r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "%s: out of memory", m->path);
    size_t* first_of = r == MESO_OK ? malloc((m->count ? m->count : 1) * sizeof *first_of) : NULL;
    if (r == MESO_OK && !(first_of && batch_group_equal((const char* const*)plain, m->count, first_of)))
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "%s: out of memory", m->path);
    size_t a = 0;
    while (r == MESO_OK && a < m->count && first_of[a] == a)
        ++a;
    if (r == MESO_OK && a < m->count) {
        const size_t b = first_of[a];
        const char *first = m->jobs[b].output, *second = m->jobs[a].output;
        if (strcmp(first, second))
            r = fail(err, m->path, BATCH_ISSUE_DUPLICATE_OUTPUT, "jobs[%zu] and jobs[%zu] both write \"%s\" (as \"%s\")",
                     b, a, first, second);
        else
            r = fail(err, m->path, BATCH_ISSUE_DUPLICATE_OUTPUT, "jobs[%zu] and jobs[%zu] both write \"%s\"", b, a,
                     first);
    }
    for (size_t i = 0; plain && i < m->count; ++i)
        free(plain[i]);
    free(plain);
    free(first_of);
    return r;
}

/* Only the keys in `known` may appear in `obj`, each once (cJSON keeps a
 * repeated key and finds the first, so a second "output" would be ignored). */
static meso_result check_keys(const cJSON* obj, const char* const* known, size_t n, const char* mpath,
                              const char* where, meso_error* err)
{
    for (const cJSON* it = obj->child; it; it = it->next) {
        size_t k = 0;
        while (k < n && strcmp(it->string, known[k]))
            ++k;
        if (k == n)
            return fail(err, mpath, BATCH_ISSUE_FIELD, "%s: unknown field \"%s\"", where, it->string);
        for (const cJSON* before = obj->child; before != it; before = before->next)
            if (!strcmp(before->string, it->string))
                return fail(err, mpath, BATCH_ISSUE_FIELD, "%s: field \"%s\" given twice", where, it->string);
    }
    return MESO_OK;
}

/* A string field: NULL when absent, error when not a non-empty string. */
static meso_result get_string(const cJSON* obj, const char* key, const char** out, const char* mpath,
                              const char* where, meso_error* err)
{
    const cJSON* v = cJSON_GetObjectItemCaseSensitive(obj, key);
    *out = NULL;
    if (!v)
        return MESO_OK;
    if (!cJSON_IsString(v) || !v->valuestring[0])
        return fail(err, mpath, BATCH_ISSUE_FIELD, "%s.%s: expected a non-empty string", where, key);
    *out = v->valuestring;
    return MESO_OK;
}

static meso_result check_args(const cJSON* args, const char* mpath, const char* where, meso_error* err)
{
    if (!args)
        return MESO_OK;
    if (!cJSON_IsArray(args))
        return fail(err, mpath, BATCH_ISSUE_FIELD, "%s.args: expected an array of strings", where);
    int i = 0;
    for (const cJSON* a = args->child; a; a = a->next, ++i) {
        if (!cJSON_IsString(a))
            return fail(err, mpath, BATCH_ISSUE_FIELD, "%s.args[%d]: expected a string", where, i);
        for (size_t k = 0; k < sizeof owned_options / sizeof owned_options[0]; ++k)
            if (!strcmp(a->valuestring, owned_options[k]))
                return fail(err, mpath, BATCH_ISSUE_OWNED_OPTION,
                            "%s.args[%d]: '%s' is set by the batch (use \"input\"/\"output\"; threads follow -j)",
                            where, i, a->valuestring);
        for (size_t k = 0; k < sizeof no_bake_options / sizeof no_bake_options[0]; ++k)
            if (!strcmp(a->valuestring, no_bake_options[k]))
                return fail(err, mpath, BATCH_ISSUE_OWNED_OPTION, "%s.args[%d]: '%s' bakes nothing", where, i,
                            a->valuestring);
    }
    return MESO_OK;
}

static int append_args(batch_job* job, const cJSON* args)
{
    for (const cJSON* a = args ? args->child : NULL; a; a = a->next) {
        char** grown = realloc(job->args, (job->arg_count + 1) * sizeof *grown);
        if (!grown)
            return 0;
        job->args = grown;
        if (!(job->args[job->arg_count] = strdup(a->valuestring)))
            return 0;
        job->arg_count++;
    }
    return 1;
}

static meso_result load_job(batch_manifest* m, batch_job* job, const cJSON* j, const cJSON* defaults, int index,
                            meso_error* err)
{
    static const char* const job_keys[] = {"name", "command", "input", "output", "args"};
    char where[32];
    snprintf(where, sizeof where, "jobs[%d]", index);
    if (!cJSON_IsObject(j))
        return fail(err, m->path, BATCH_ISSUE_FIELD, "%s: expected an object", where);
    meso_result r = check_keys(j, job_keys, 5, m->path, where, err);
    const char *name = NULL, *command = NULL, *input = NULL, *output = NULL, *dcommand = NULL;
    if (r == MESO_OK)
        r = get_string(j, "name", &name, m->path, where, err);
    if (r == MESO_OK)
        r = get_string(j, "command", &command, m->path, where, err);
    if (r == MESO_OK)
        r = get_string(j, "input", &input, m->path, where, err);
    if (r == MESO_OK)
        r = get_string(j, "output", &output, m->path, where, err);
    if (r == MESO_OK)
        r = check_args(cJSON_GetObjectItemCaseSensitive(j, "args"), m->path, where, err);
    if (r != MESO_OK)
        return r;
    if (defaults)
        get_string(defaults, "command", &dcommand, m->path, "defaults", err); /* checked by the caller */
    if (!command)
        command = dcommand;
    if (!command)
        return fail(err, m->path, BATCH_ISSUE_FIELD, "%s: no \"command\" (and none in \"defaults\")", where);
    size_t c = 0;
    while (c < 4 && strcmp(command, commands[c]))
        ++c;
    if (c == 4)
        return fail(err, m->path, BATCH_ISSUE_COMMAND, "%s.command: unknown command \"%s\" (mesh, shell, cells, frusta)",
                    where, command);
    if (!input)
        return fail(err, m->path, BATCH_ISSUE_FIELD, "%s: missing \"input\"", where);
    if (!output)
        return fail(err, m->path, BATCH_ISSUE_FIELD, "%s: missing \"output\"", where);
    job->name = strdup(name ? name : output);
    job->command = strdup(command);
    job->input = strdup(input);
    job->output = strdup(output);
    job->output_path = join_path(m->dir, output);
    job->same_as = (size_t)-1;
    job->exit_code = -1;
    if (!job->name || !job->command || !job->input || !job->output || !job->output_path ||
        !append_args(job, defaults ? cJSON_GetObjectItemCaseSensitive(defaults, "args") : NULL) ||
        !append_args(job, cJSON_GetObjectItemCaseSensitive(j, "args")))
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "%s: out of memory", m->path);
    return MESO_OK;
}

/* Line and column of byte `at` in `text`, for JSON syntax errors. */
static void line_col(const char* text, const char* at, int* line, int* col)
{
    *line = 1;
    *col = 1;
    for (const char* p = text; p < at && *p; ++p) {
        if (*p == '\n') {
            ++*line;
            *col = 1;
        } else {
            ++*col;
        }
    }
}

static meso_result load_root(batch_manifest* m, const cJSON* root, meso_error* err)
{
    static const char* const root_keys[] = {"$schema", "defaults", "jobs"};
    static const char* const default_keys[] = {"command", "args"};
    if (!cJSON_IsObject(root))
        return fail(err, m->path, BATCH_ISSUE_FIELD, "expected a JSON object with \"jobs\"");
    meso_result r = check_keys(root, root_keys, 3, m->path, "(top level)", err);
    const cJSON* defaults = cJSON_GetObjectItemCaseSensitive(root, "defaults");
    if (r == MESO_OK && defaults) {
        const char* dcommand = NULL;
        if (!cJSON_IsObject(defaults))
            return fail(err, m->path, BATCH_ISSUE_FIELD, "defaults: expected an object");
        r = check_keys(defaults, default_keys, 2, m->path, "defaults", err);
        if (r == MESO_OK)
            r = get_string(defaults, "command", &dcommand, m->path, "defaults", err);
        if (r == MESO_OK)
            r = check_args(cJSON_GetObjectItemCaseSensitive(defaults, "args"), m->path, "defaults", err);
    }
    if (r != MESO_OK)
        return r;
    const cJSON* jobs = cJSON_GetObjectItemCaseSensitive(root, "jobs");
    if (!jobs || !cJSON_IsArray(jobs))
        return fail(err, m->path, BATCH_ISSUE_FIELD, "\"jobs\": expected an array of jobs");
    const int n = cJSON_GetArraySize(jobs);
    if (n == 0)
        return fail(err, m->path, BATCH_ISSUE_NO_JOBS, "\"jobs\" is empty: nothing to bake");
    if (!(m->jobs = calloc((size_t)n, sizeof *m->jobs)))
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "%s: out of memory", m->path);
    m->count = (size_t)n;
    int i = 0;
    for (const cJSON* j = jobs->child; j && r == MESO_OK; j = j->next, ++i)
        r = load_job(m, &m->jobs[i], j, defaults, i, err);
    return r == MESO_OK ? check_outputs_distinct(m, err) : r;
}

meso_result batch_manifest_load(const char* path, batch_manifest* m, meso_error* err)
{
    memset(m, 0, sizeof *m);
    size_t size = 0;
    char* text = batch_read_file(path, &size);
    if (!text)
        return fail(err, path, BATCH_ISSUE_UNREADABLE, "cannot read the manifest: %s", strerror(errno));
    m->path = strdup(path);
    /* The directory every relative path of the manifest starts from. */
    char* slash = strrchr(m->path ? m->path : "", '/');
    char* dir = slash ? malloc((size_t)(slash - m->path) + 2) : strdup(".");
    if (dir && slash) {
        memcpy(dir, m->path, (size_t)(slash - m->path));
        dir[slash - m->path] = 0;
        if (!dir[0])
            strcpy(dir, "/");
    }
    m->dir = dir ? realpath(dir, NULL) : NULL;
    free(dir);
    meso_result r = MESO_OK;
    if (!m->path || !m->dir)
        r = fail(err, path, BATCH_ISSUE_UNREADABLE, "cannot resolve the manifest's directory: %s", strerror(errno));
    const char* end = NULL;
    cJSON* root = r == MESO_OK ? cJSON_ParseWithOpts(text, &end, 1) : NULL;
    if (r == MESO_OK && !root) {
        int line, col;
        line_col(text, end ? end : text, &line, &col);
        r = fail(err, path, BATCH_ISSUE_JSON, "not valid JSON at line %d, column %d", line, col);
    }
    if (r == MESO_OK && strlen(text) != size)
        r = fail(err, path, BATCH_ISSUE_JSON, "a NUL byte inside the manifest");
    if (r == MESO_OK)
        r = load_root(m, root, err);
    cJSON_Delete(root);
    free(text);
    if (r != MESO_OK)
        batch_manifest_free(m);
    return r;
}

void batch_manifest_free(batch_manifest* m)
{
    for (size_t i = 0; i < m->count; ++i) {
        batch_job* j = &m->jobs[i];
        for (size_t a = 0; a < j->arg_count; ++a)
            free(j->args[a]);
        free(j->args);
        free(j->name);
        free(j->command);
        free(j->input);
        free(j->output);
        free(j->output_path);
        free(j->report_json);
    }
    free(m->jobs);
    free(m->path);
    free(m->dir);
    memset(m, 0, sizeof *m);
}
