/* test_format_atomic.c — meso_writer_write_file is atomic: on failure the
 * target is untouched and no temporary file remains; a symbolic link is
 * written through to its target and anything not a regular file is refused
 * untouched (FORMAT.md §10); a writer killed with
 * SIGKILL at any moment leaves the target either the complete old file or
 * the complete new one. A killed process cannot clean up, so it may leave a
 * ".NAME.tmp.XXXXXX" file next to the target (never the target itself);
 * this test removes those.
 *
 * MESO_ATOMIC_MB (default 64) sets the size of the file written while the
 * writer is being killed; the kill moments scale with it (they were chosen
 * for 200 MB, where a write takes about 0.5 s here). */
#undef NDEBUG
#include "meso_file.h"
#include "sample.h"

#include "test_dir.h"

#include <assert.h>
#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

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
    assert(e.code == MESO_ISSUE_IO_DESTINATION && strstr(e.message, p) && strstr(e.message, strerror(ENOENT)));
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

    /* rename fails (the directory is not writable after the temporary file
     * exists): temp removed, target kept. Root ignores permissions, so the
     * failure is made by a destination that turns into a directory. */
    meso_output o;
    meso_error e;
    assert(meso_output_open(target, NULL, &o, &e) == MESO_OK);
    assert(count_entries(".keep.meso.tmp.") == 1);
    assert(meso_output_write(&o, old, old_size, &e) == MESO_OK);
    char moved[600];
    snprintf(moved, sizeof moved, "%s.moved", target);
    assert(rename(target, moved) == 0 && mkdir(target, 0755) == 0);
    assert(meso_output_commit(&o, &e) == MESO_ERR_IO && e.code == MESO_ISSUE_IO_DESTINATION);
    assert(strstr(e.message, "directory") && o.temp == NULL && o.fd == -1);
    assert(count_entries(".tmp.") == 0);
    assert(rmdir(target) == 0 && rename(moved, target) == 0);
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
    size_t mb = env ? (size_t)atoi(env) : 64;
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

    /* Kill at increasing delays: early (old file), mid-write, after renames
     * (for 200 MB; scaled to the size written). */
    static const int delays_200mb_ms[] = {0, 5, 40, 150, 400, 900, 1500, 2500};
    int saw_old = 0, saw_new = 0;
    for (size_t k = 0; k < sizeof delays_200mb_ms / sizeof delays_200mb_ms[0]; k++) {
        const long delay_ms = (long)((double)delays_200mb_ms[k] * (double)mb / 200.0);
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
        struct timespec ts = {delay_ms / 1000, (delay_ms % 1000) * 1000000L};
        nanosleep(&ts, NULL);
        assert(kill(pid, SIGKILL) == 0);
        int status;
        assert(waitpid(pid, &status, 0) == pid);
        assert(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);
        int is_old = files_equal(target, old_ref), is_new = !is_old && files_equal(target, new_ref);
        if (!is_old && !is_new)
            fprintf(stderr, "after a kill at %ld ms the target is neither the old nor the new file\n", delay_ms);
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

static void write_file(const char* p, const void* data, size_t n)
{
    FILE* fp = fopen(p, "wb");
    assert(fp && fwrite(data, 1, n, fp) == n);
    fclose(fp);
}

/* Exactly the bytes `data` in file p. */
static int file_is(const char* p, const void* data, size_t n)
{
    FILE* fp = fopen(p, "rb");
    assert(fp);
    uint8_t* got = (uint8_t*)malloc(n + 1);
    size_t m = fread(got, 1, n + 1, fp);
    fclose(fp);
    int eq = m == n && memcmp(got, data, n) == 0;
    free(got);
    return eq;
}

static uint8_t* sample_bytes(size_t* n)
{
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    sample_add_all(w);
    assert(meso_writer_finish(w, NULL, 0, n) == MESO_OK);
    uint8_t* b = (uint8_t*)malloc(*n);
    assert(meso_writer_finish(w, b, *n, n) == MESO_OK);
    meso_writer_destroy(w);
    return b;
}

/* A symbolic link (and a chain of two) is written through: the final target
 * gets the new bytes, replaced atomically in its own directory with its
 * permissions kept; the links stay links to the same place. */
static void symlink_is_written_through_to_its_target(void)
{
    char sub[512], target[600], link1[512], link2[512], want[600];
    path_in(sub, sizeof sub, "real");
    assert(mkdir(sub, 0755) == 0);
    snprintf(target, sizeof target, "%s/t.meso", sub);
    write_file(target, "old", 3);
    assert(chmod(target, 0640) == 0);
    path_in(link1, sizeof link1, "link.meso");
    path_in(link2, sizeof link2, "link2.meso");
    assert(symlink("real/t.meso", link1) == 0 && symlink("link.meso", link2) == 0);
    size_t n;
    uint8_t* bytes = sample_bytes(&n);
    const char* via[2] = {link1, link2};
    for (int k = 0; k < 2; ++k) {
        write_file(target, "old", 3);
        write_sample(via[k]);
        assert(file_is(target, bytes, n));
        struct stat st;
        assert(lstat(link1, &st) == 0 && S_ISLNK(st.st_mode));
        assert(lstat(link2, &st) == 0 && S_ISLNK(st.st_mode));
        ssize_t len = readlink(link1, want, sizeof want - 1);
        assert(len == 11 && memcmp(want, "real/t.meso", 11) == 0);
        assert(lstat(target, &st) == 0 && S_ISREG(st.st_mode) && (st.st_mode & 0777) == 0640);
        /* nothing else appeared: in the link's directory or the target's */
        assert(count_entries(".tmp.") == 0 && count_entries("") == 3);
        char ls[700];
        snprintf(ls, sizeof ls, "test \"$(ls -A '%s')\" = t.meso", sub);
        assert(system(ls) == 0);
    }
    /* meso_output_open reports where the file goes. */
    meso_output o;
    assert(meso_output_open(link2, NULL, &o, NULL) == MESO_OK);
    assert(strstr(o.path, "/real/t.meso") && strstr(o.temp, "/real/.t.meso.tmp."));
    meso_output_abort(&o);
    assert(o.temp == NULL && file_is(target, bytes, n));
    free(bytes);
    unlink(link2);
    unlink(link1);
    unlink(target);
    rmdir(sub);
}

/* Refused without being opened or replaced: MESO_ERR_IO, issue
 * IO_DESTINATION, the message names the path and what it is; the node is
 * still there, of the same kind, and no temporary file appears. */
static void expect_refused(const char* p, const char* what)
{
    struct stat before, after;
    assert(lstat(p, &before) == 0);
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    sample_add_all(w);
    meso_error e;
    assert(meso_writer_write_file(w, p, &e) == MESO_ERR_IO);
    if (!strstr(e.message, what))
        fprintf(stderr, "%s: expected '%s' in: %s\n", p, what, e.message);
    assert(e.code == MESO_ISSUE_IO_DESTINATION && strstr(e.message, p) && strstr(e.message, what));
    meso_writer_destroy(w);
    memset(&e, 0, sizeof e);
    assert(meso_output_check(p, &e) == MESO_ERR_IO && e.code == MESO_ISSUE_IO_DESTINATION);
    meso_output o;
    assert(meso_output_open(p, NULL, &o, NULL) == MESO_ERR_IO && o.temp == NULL && o.fd == -1);
    assert(lstat(p, &after) == 0 && (after.st_mode & S_IFMT) == (before.st_mode & S_IFMT));
    assert(after.st_ino == before.st_ino && after.st_rdev == before.st_rdev);
    assert(count_entries(".tmp.") == 0);
}

/* A symbolic link `name` -> `to` is refused as `what`, then removed. */
static void expect_link_refused(const char* name, const char* to, const char* what)
{
    char p[512];
    path_in(p, sizeof p, name);
    assert(symlink(to, p) == 0);
    expect_refused(p, what);
    unlink(p);
}

static void non_regular_destinations_are_refused(void)
{
    char p[512];
    /* A FIFO: were it opened for writing, this test would block here. */
    path_in(p, sizeof p, "fifo");
    assert(mkfifo(p, 0644) == 0);
    expect_refused(p, "a FIFO");
    expect_link_refused("to_fifo", "fifo", "a symbolic link to a FIFO");
    unlink(p);
    expect_link_refused("dangling", "nothing/here.meso", "a dangling symbolic link");
    expect_link_refused("loop", "loop", "a symbolic link loop");

    path_in(p, sizeof p, "adir.meso");
    assert(mkdir(p, 0755) == 0);
    expect_refused(p, "a directory");
    expect_link_refused("to_dir", "adir.meso", "a symbolic link to a directory");
    char slash[600];
    snprintf(slash, sizeof slash, "%s/", p);
    expect_refused(slash, "a directory");
    rmdir(p);

    path_in(p, sizeof p, "sock");
    int s = socket(AF_UNIX, SOCK_STREAM, 0);
    struct sockaddr_un addr;
    memset(&addr, 0, sizeof addr);
    addr.sun_family = AF_UNIX;
    assert(strlen(p) < sizeof addr.sun_path);
    strcpy(addr.sun_path, p);
    assert(s >= 0 && bind(s, (struct sockaddr*)&addr, sizeof addr) == 0);
    expect_refused(p, "a socket");
    close(s);
    unlink(p);

    /* A device node of our own (never the real /dev/null): the same major
     * and minor as /dev/null. Making one needs root (CI runs as root). */
    path_in(p, sizeof p, "null");
    if (mknod(p, S_IFCHR | 0666, makedev(1, 3)) == 0) {
        expect_refused(p, "a character device");
        unlink(p);
        printf("atomic: device node refused\n");
    } else {
        assert(errno == EPERM);
        printf("atomic: not root, no device node test (FIFO, socket, directory tested)\n");
    }
    assert(count_entries("") == 0);
}

/* open, abort: the temporary file existed, then it is gone and the old file
 * is untouched; open, write, commit: the new bytes. */
static void output_abort_and_commit(void)
{
    char p[512];
    path_in(p, sizeof p, "staged.meso");
    write_file(p, "old", 3);
    meso_output o;
    meso_error e;
    assert(meso_output_open(p, NULL, &o, &e) == MESO_OK && o.fd >= 0);
    assert(strcmp(o.path, p) == 0 && count_entries(".staged.meso.tmp.") == 1);
    assert(meso_output_write(&o, "new!", 4, &e) == MESO_OK);
    meso_output_abort(&o);
    meso_output_abort(&o); /* a closed output: nothing */
    assert(count_entries(".tmp.") == 0 && file_is(p, "old", 3));
    assert(meso_output_open(p, NULL, &o, &e) == MESO_OK);
    assert(meso_output_write(&o, "new!", 4, &e) == MESO_OK);
    assert(meso_output_commit(&o, &e) == MESO_OK && o.temp == NULL && o.fd == -1);
    assert(count_entries(".tmp.") == 0 && file_is(p, "new!", 4));
    assert(meso_output_commit(&o, &e) == MESO_ERR_INVALID_ARG);
    unlink(p);
}

int main(void)
{
    make_test_dir("meso_atomic");
    missing_directory_fails_and_creates_nothing();
    successful_write_replaces_target_and_leaves_no_temp();
    failed_write_keeps_the_old_target_and_leaves_no_temp();
    symlink_is_written_through_to_its_target();
    non_regular_destinations_are_refused();
    output_abort_and_commit();
    killed_writer_leaves_old_or_new_never_partial();
    assert(count_entries("") == 0);
    assert(rmdir(dir) == 0);
    printf("test_format_atomic: ok\n");
    return 0;
}
