/* test_format_atomic.c — meso_writer_write_file is atomic: on failure the
 * target is untouched and no temporary file remains; a writer killed with
 * SIGKILL at any moment leaves the target either the complete old file or
 * the complete new one. A killed process cannot clean up, so it may leave a
 * ".NAME.tmp.XXXXXX" file next to the target (never the target itself);
 * this test removes those.
 *
 * MESO_ATOMIC_MB (default 200) sets the size of the file written while the
 * writer is being killed. */
#undef NDEBUG
#include "meso_file.h"
#include "sample.h"

#include <assert.h>
#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static char dir[256];

static void path_in(char* out, size_t n, const char* name) { snprintf(out, n, "%s/%s", dir, name); }

/* Number of entries in dir whose name contains `needle`. */
static int count_entries(const char* needle)
{
    DIR* d = opendir(dir);
    assert(d);
    int n = 0;
    struct dirent* e;
    while ((e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..") && strstr(e->d_name, needle))
            n++;
    closedir(d);
    return n;
}

static void remove_temps(void)
{
    DIR* d = opendir(dir);
    assert(d);
    struct dirent* e;
    char p[600];
    while ((e = readdir(d)) != NULL) {
        if (strstr(e->d_name, ".tmp.")) {
            assert(e->d_name[0] == '.'); /* ".NAME.tmp.XXXXXX" */
            snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
            assert(unlink(p) == 0);
        }
    }
    closedir(d);
}

static int files_equal(const char* a, const char* b)
{
    FILE* fa = fopen(a, "rb");
    FILE* fb = fopen(b, "rb");
    assert(fa && fb);
    enum { BLK = 1 << 20 };
    uint8_t* ba = (uint8_t*)malloc(BLK);
    uint8_t* bb = (uint8_t*)malloc(BLK);
    int eq = 1;
    for (;;) {
        size_t na = fread(ba, 1, BLK, fa), nb = fread(bb, 1, BLK, fb);
        if (na != nb || memcmp(ba, bb, na) != 0) {
            eq = 0;
            break;
        }
        if (na == 0)
            break;
    }
    free(ba);
    free(bb);
    fclose(fa);
    fclose(fb);
    return eq;
}

static void validate_path(const char* p)
{
    meso_file* f = NULL;
    meso_error e;
    meso_result r = meso_file_open_path(p, NULL, &f, &e);
    if (r != MESO_OK)
        fprintf(stderr, "%s: %s\n", p, e.message);
    assert(r == MESO_OK);
    assert(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);
    meso_file_close(f);
}

static void write_sample(const char* p)
{
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    sample_add_all(w);
    assert(meso_writer_write_file(w, p, NULL) == MESO_OK);
    meso_writer_destroy(w);
}

static void missing_directory_fails_and_creates_nothing(void)
{
    char p[512];
    path_in(p, sizeof p, "no/such/dir/x.meso");
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    sample_add_all(w);
    meso_error e;
    assert(meso_writer_write_file(w, p, &e) == MESO_ERR_IO);
    assert(e.code == MESO_ISSUE_IO_WRITE && strstr(e.message, p) && strstr(e.message, strerror(ENOENT)));
    assert(count_entries("") == 0);
    assert(meso_writer_write_file(w, "", &e) == MESO_ERR_INVALID_ARG);
    meso_writer_destroy(w);
}

/* A write that fails half way (file size limit) leaves the old target. */
static void failed_write_keeps_the_old_target_and_leaves_no_temp(void)
{
    char target[512];
    path_in(target, sizeof target, "keep.meso");
    size_t old_size;
    uint8_t* old = sample_small_file(&old_size);
    FILE* fp = fopen(target, "wb");
    assert(fp && fwrite(old, 1, old_size, fp) == old_size);
    fclose(fp);
    pid_t pid = fork();
    assert(pid >= 0);
    if (pid == 0) {
        struct rlimit rl = {2048, 2048};
        signal(SIGXFSZ, SIG_IGN);
        if (setrlimit(RLIMIT_FSIZE, &rl) != 0)
            _exit(2);
        meso_writer* w = NULL;
        if (meso_writer_create(NULL, &w) != MESO_OK)
            _exit(3);
        sample_add_all(w);
        meso_error e;
        meso_result r = meso_writer_write_file(w, target, &e);
        meso_writer_destroy(w);
        _exit(r == MESO_ERR_IO && e.code == MESO_ISSUE_IO_WRITE && strstr(e.message, target) ? 0 : 1);
    }
    int status;
    assert(waitpid(pid, &status, 0) == pid && WIFEXITED(status) && WEXITSTATUS(status) == 0);
    size_t got_size;
    FILE* rp = fopen(target, "rb");
    uint8_t* got = (uint8_t*)malloc(old_size + 1);
    got_size = fread(got, 1, old_size + 1, rp);
    fclose(rp);
    assert(got_size == old_size && memcmp(got, old, old_size) == 0);
    assert(count_entries(".tmp.") == 0);

    /* rename fails (the target is a non-empty directory): temp removed. */
    char d[512], inner[600];
    path_in(d, sizeof d, "adir.meso");
    assert(mkdir(d, 0755) == 0);
    snprintf(inner, sizeof inner, "%s/x", d);
    fp = fopen(inner, "wb");
    assert(fp);
    fclose(fp);
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    sample_add_all(w);
    meso_error e;
    assert(meso_writer_write_file(w, d, &e) == MESO_ERR_IO && strstr(e.message, "rename"));
    meso_writer_destroy(w);
    assert(count_entries(".tmp.") == 0);
    unlink(inner);
    rmdir(d);
    unlink(target);
    free(got);
    free(old);
}

/* A big file whose contents depend on `seed`. */
static meso_writer* big_writer(size_t mb, uint32_t seed)
{
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    char meta[64];
    snprintf(meta, sizeof meta, "{\"seed\":%u}", seed);
    meso_chunk_desc d;
    memset(&d, 0, sizeof d);
    d.type = MESO_CHUNK_META;
    assert(meso_writer_add(w, &d, meta, strlen(meta), NULL) == MESO_OK);
    size_t chunk = 4u << 20;
    uint8_t* buf = (uint8_t*)malloc(chunk);
    assert(buf);
    for (size_t i = 0; i < mb / 4; i++) {
        fill_pattern(buf, chunk, seed * 1000u + (uint32_t)i);
        memset(&d, 0, sizeof d);
        d.type = MESO_CHUNK_TX3D;
        d.object = 1;
        d.dtype = MESO_DTYPE_U8;
        d.components = 1;
        d.dims[0] = 256;
        d.dims[1] = 128;
        d.dims[2] = 128;
        assert(meso_writer_add(w, &d, buf, chunk, NULL) == MESO_OK);
    }
    free(buf);
    return w;
}

static void killed_writer_leaves_old_or_new_never_partial(void)
{
    const char* env = getenv("MESO_ATOMIC_MB");
    size_t mb = env ? (size_t)atoi(env) : 200;
    if (mb < 4)
        mb = 4;
    char target[512], old_ref[512], new_ref[512];
    path_in(target, sizeof target, "big.meso");
    path_in(old_ref, sizeof old_ref, "ref_old");
    path_in(new_ref, sizeof new_ref, "ref_new");
    meso_writer* w = big_writer(mb, 1);
    assert(meso_writer_write_file(w, old_ref, NULL) == MESO_OK);
    assert(meso_writer_write_file(w, target, NULL) == MESO_OK);
    meso_writer_destroy(w);
    w = big_writer(mb, 2);
    assert(meso_writer_write_file(w, new_ref, NULL) == MESO_OK);
    meso_writer_destroy(w);
    validate_path(old_ref);
    validate_path(new_ref);
    assert(!files_equal(old_ref, new_ref));

    /* Kill at increasing delays: early (old file), mid-write, after renames. */
    static const int delays_ms[] = {0, 5, 40, 150, 400, 900, 1500, 2500};
    int saw_old = 0, saw_new = 0;
    for (size_t k = 0; k < sizeof delays_ms / sizeof delays_ms[0]; k++) {
        int fds[2];
        assert(pipe(fds) == 0);
        pid_t pid = fork();
        assert(pid >= 0);
        if (pid == 0) {
            close(fds[0]);
            meso_writer* cw = big_writer(mb, 2);
            char ready = 'r';
            if (write(fds[1], &ready, 1) != 1)
                _exit(1);
            for (;;)
                if (meso_writer_write_file(cw, target, NULL) != MESO_OK)
                    _exit(2);
        }
        close(fds[1]);
        char ready;
        assert(read(fds[0], &ready, 1) == 1);
        close(fds[0]);
        struct timespec ts = {delays_ms[k] / 1000, (long)(delays_ms[k] % 1000) * 1000000L};
        nanosleep(&ts, NULL);
        assert(kill(pid, SIGKILL) == 0);
        int status;
        assert(waitpid(pid, &status, 0) == pid);
        assert(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
        int is_old = files_equal(target, old_ref), is_new = !is_old && files_equal(target, new_ref);
        if (!is_old && !is_new)
            fprintf(stderr, "after a kill at %d ms the target is neither the old nor the new file\n", delays_ms[k]);
        assert(is_old || is_new);
        validate_path(target);
        saw_old += is_old;
        saw_new += is_new;
        assert(count_entries(".tmp.") <= 1);
        remove_temps();
    }
    printf("atomic: %zu MB, %d kills saw the old file, %d the new one\n", mb, saw_old, saw_new);
    assert(saw_old >= 1);
    unlink(target);
    unlink(old_ref);
    unlink(new_ref);
}

static void successful_write_replaces_target_and_leaves_no_temp(void)
{
    char target[512];
    path_in(target, sizeof target, "ok.meso");
    write_sample(target);
    write_sample(target);
    validate_path(target);
    assert(count_entries(".tmp.") == 0 && count_entries("ok.meso") == 1);
    struct stat st;
    assert(stat(target, &st) == 0 && (st.st_mode & 0444) != 0);
    unlink(target);
}

int main(void)
{
    const char* base = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/meso_atomic_XXXXXX", base ? base : "/tmp");
    assert(mkdtemp(dir) != NULL);
    missing_directory_fails_and_creates_nothing();
    successful_write_replaces_target_and_leaves_no_temp();
    failed_write_keeps_the_old_target_and_leaves_no_temp();
    killed_writer_leaves_old_or_new_never_partial();
    assert(count_entries("") == 0);
    assert(rmdir(dir) == 0);
    printf("test_format_atomic: ok\n");
    return 0;
}
