/* batch_cache.c — the content-addressed cache of `mesobake batch` (batch.h).
 *
 *   DIR/v1/ab/ab12…ef.meso   the baked file of key ab12…ef
 *   DIR/v1/ab/ab12…ef.json   its bake report (--report), when there is one
 *
 * A bake writes `mesobake <command> -o SCRATCH --report SCRATCH.json` (both
 * atomic: FORMAT.md §10) into a scratch name beside the entry; when it has
 * succeeded the key is computed again from the inputs as they are now, and
 * only if it is unchanged are the scratch files renamed into the entry
 * (report first, so a .meso is only ever seen whole). An input saved by an
 * artist while its bake ran therefore never lands under the old input's key.
 * Concurrent writers of one key — two batches, two machines on a shared
 * file system — each rename a complete file over the other's, which holds
 * the same bytes: the key names the inputs' bytes, the options and the
 * build (batch_key.c), and a bake is deterministic (rule 7). A lookup
 * still checks the entry in full (every CRC, every structure): a file damaged
 * on disk is a miss and is baked again rather than copied into a build.
 */
#include "batch.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli_util.h"

static char* concat(const char* a, const char* b, const char* c)
{
    size_t na = strlen(a), nb = strlen(b), nc = strlen(c);
    char* s = malloc(na + nb + nc + 1);
    if (s) {
        memcpy(s, a, na);
        memcpy(s + na, b, nb);
        memcpy(s + na + nb, c, nc + 1);
    }
    return s;
}

char* batch_cache_default_dir(void)
{
    const char* d = getenv("MESO_CACHE_DIR");
    if (d && d[0])
        return concat(d, "", "");
    d = getenv("XDG_CACHE_HOME");
    if (d && d[0] == '/')
        return concat(d, "/meso", "");
    d = getenv("HOME");
    if (d && d[0])
        return concat(d, "/.cache/meso", "");
    return NULL;
}

/* mkdir -p `dir` (every component). */
static meso_result mkdir_all(const char* dir, meso_error* err)
{
    char* p = concat(dir, "", "");
    if (!p)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "out of memory");
    meso_result r = MESO_OK;
    for (char* s = p + 1;; ++s) {
        const char c = *s;
        if (c != '/' && c != 0)
            continue;
        *s = 0;
        struct stat st;
        if (mkdir(p, 0777) != 0 && errno != EEXIST)
            r = meso_bake_fail(err, MESO_ERR_IO, 0, "%s: cannot create directory: %s", p, strerror(errno));
        else if (stat(p, &st) != 0 || !S_ISDIR(st.st_mode))
            r = meso_bake_fail(err, MESO_ERR_IO, 0, "%s: not a directory", p);
        *s = c;
        if (r != MESO_OK || c == 0)
            break;
    }
    free(p);
    return r;
}

meso_result batch_mkdir_parents(const char* path, meso_error* err)
{
    const char* slash = strrchr(path, '/');
    if (!slash || slash == path)
        return MESO_OK;
    char* dir = malloc((size_t)(slash - path) + 1);
    if (!dir)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "out of memory");
    memcpy(dir, path, (size_t)(slash - path));
    dir[slash - path] = 0;
    meso_result r = mkdir_all(dir, err);
    free(dir);
    return r;
}

meso_result batch_cache_open(batch_cache* c, const char* dir, meso_error* err)
{
    c->dir = NULL;
    meso_result r = mkdir_all(dir, err);
    if (r != MESO_OK)
        return r;
    if (!(c->dir = realpath(dir, NULL)))
        return meso_bake_fail(err, MESO_ERR_IO, 0, "%s: %s", dir, strerror(errno));
    return MESO_OK;
}

void batch_cache_close(batch_cache* c)
{
    free(c->dir);
    c->dir = NULL;
}

char* batch_cache_entry(const batch_cache* c, const char* key, const char* ext, int create)
{
    char sub[16];
    snprintf(sub, sizeof sub, "/v1/%.2s/", key);
    char* dir = concat(c->dir, sub, "");
    char* path = dir ? concat(dir, key, ext) : NULL;
    if (path && create && mkdir_all(dir, NULL) != MESO_OK) {
        free(path);
        path = NULL;
    }
    free(dir);
    return path;
}

/* 1 when `path` is a .meso file with no issue at MESO_CHECK_FULL. */
static int valid_meso(const char* path)
{
    meso_file* f = NULL;
    if (meso_file_open_path(path, NULL, &f, NULL) != MESO_OK)
        return 0;
    const int ok = meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK;
    meso_file_close(f);
    return ok;
}

int batch_cache_has(const batch_cache* c, const char* key)
{
    if (!c->dir || !key[0])
        return 0;
    char* path = batch_cache_entry(c, key, ".meso", 0);
    const int ok = path && access(path, F_OK) == 0 && valid_meso(path);
    free(path);
    return ok;
}

char* batch_read_file(const char* path, size_t* size)
{
    FILE* f = fopen(path, "rb");
    if (!f)
        return NULL;
    char* data = NULL;
    size_t n = 0, cap = 0;
    for (;;) {
        if (n + 1 >= cap) {
            cap = cap ? 2 * cap : 1 << 16;
            char* grown = realloc(data, cap);
            if (!grown) {
                free(data);
                fclose(f);
                errno = ENOMEM;
                return NULL;
            }
            data = grown;
        }
        size_t got = fread(data + n, 1, cap - n - 1, f);
        n += got;
        if (got == 0)
            break;
    }
    const int bad = ferror(f);
    fclose(f);
    if (bad) {
        free(data);
        errno = EIO;
        return NULL;
    }
    data[n] = 0;
    if (size)
        *size = n;
    return data;
}

void batch_last_line(const char* path, char* line, size_t size)
{
    line[0] = 0;
    char* text = batch_read_file(path, NULL);
    if (!text)
        return;
    /* The bake's own "mesobake error ..." line when there is one (a usage
     * error ends with the hint "See 'mesobake --help'."), else the last. */
    const char *last = NULL, *error = NULL;
    for (char* l = text; l && *l;) {
        char* nl = strchr(l, '\n');
        if (nl)
            *nl = 0;
        for (size_t n = strlen(l); n > 0 && (l[n - 1] == '\r' || l[n - 1] == ' '); --n)
            l[n - 1] = 0;
        if (*l)
            last = l;
        if (!strncmp(l, "mesobake error", 14))
            error = l;
        l = nl ? nl + 1 : NULL;
    }
    snprintf(line, size, "%s", error ? error : last ? last : "");
    free(text);
}

meso_result batch_cache_copy_out(const batch_cache* c, batch_job* job, meso_error* err)
{
    char* from = batch_cache_entry(c, job->key, ".meso", 0);
    char* from_report = batch_cache_entry(c, job->key, ".json", 0);
    size_t size = 0, old_size = 0;
    char* data = from ? batch_read_file(from, &size) : NULL;
    meso_result r = MESO_OK;
    if (!data)
        r = meso_bake_fail(err, MESO_ERR_IO, 0, "%s: cannot read the cache entry: %s", from ? from : job->key,
                           strerror(errno));
    if (r == MESO_OK)
        r = batch_mkdir_parents(job->output_path, err);
    /* Compare only with a regular file of the same size (never open a FIFO). */
    struct stat st;
    char* old = r == MESO_OK && stat(job->output_path, &st) == 0 && S_ISREG(st.st_mode) && (size_t)st.st_size == size
                    ? batch_read_file(job->output_path, &old_size)
                    : NULL;
    if (r == MESO_OK && !(old && old_size == size && !memcmp(old, data, size))) {
        meso_output* o = NULL;
        r = cli_output_stage(job->output_path, &o, err);
        if (r == MESO_OK)
            r = meso_output_write(o, data, size, err);
        if (r == MESO_OK)
            r = cli_outputs_publish(err);
        else
            cli_outputs_discard();
    }
    if (r == MESO_OK && from_report) {
        free(job->report_json);
        job->report_json = batch_read_file(from_report, NULL); /* NULL when the entry has none */
    }
    free(old);
    free(data);
    free(from);
    free(from_report);
    return r;
}

char* batch_cache_scratch(const batch_cache* c, const char* key, const char* ext)
{
    static unsigned seq;
    char tail[64];
    snprintf(tail, sizeof tail, ".pending-%ld-%u%s", (long)getpid(), seq++, ext);
    return batch_cache_entry(c, key, tail, 1);
}

meso_result batch_cache_publish(const batch_cache* c, const batch_manifest* m, batch_job* job,
                                const char* scratch_meso, const char* scratch_json, meso_error* err)
{
    char before[sizeof job->key];
    memcpy(before, job->key, sizeof before);
    meso_result r = batch_job_key(m, job, err);
    const int same = r == MESO_OK && !strcmp(before, job->key);
    memcpy(job->key, before, sizeof before);
    char* entry = batch_cache_entry(c, job->key, ".meso", 1);
    char* entry_json = batch_cache_entry(c, job->key, ".json", 1);
    if (r == MESO_OK && !same)
        r = meso_bake_fail(err, MESO_ERR_IO, 0,
                           "an input of %s changed while it was baked: its bytes were not kept; bake again", job->name);
    else if (r == MESO_OK && (!entry || !entry_json))
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "out of memory");
    /* The report first: an entry's .meso appears only when it is whole. */
    if (r == MESO_OK && access(scratch_json, F_OK) == 0 && rename(scratch_json, entry_json) != 0)
        r = meso_bake_fail(err, MESO_ERR_IO, 0, "%s: cannot publish: %s", entry_json, strerror(errno));
    if (r == MESO_OK && rename(scratch_meso, entry) != 0)
        r = meso_bake_fail(err, MESO_ERR_IO, 0, "%s: cannot publish: %s", entry, strerror(errno));
    unlink(scratch_meso);
    unlink(scratch_json);
    free(entry);
    free(entry_json);
    return r;
}
