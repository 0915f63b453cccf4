/* test_cli_output.c — the programs' staged outputs (tools/common/cli_output.c,
 * shared by mesobake and mesoinspect): a signal removes every staged
 * temporary file and ends the process with that signal, whichever thread it
 * is delivered to; a signal inherited as ignored stays ignored (nohup);
 * discard publishes nothing; a destination that changed into a directory
 * after staging stops the whole publish (no output renamed); one file named
 * by two outputs is refused. Each case runs in a child process. */
#undef NDEBUG
#include "cli_output.h"

#include "test_dir.h"

#include <assert.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

static void write_text(const char* p, const char* text)
{
    FILE* fp = fopen(p, "wb");
    assert(fp && fputs(text, fp) >= 0);
    fclose(fp);
}

static int has_text(const char* p, const char* text)
{
    char buf[64] = {0};
    FILE* fp = fopen(p, "rb");
    if (!fp)
        return 0;
    size_t n = fread(buf, 1, sizeof buf - 1, fp);
    fclose(fp);
    return n == strlen(text) && memcmp(buf, text, n) == 0;
}

/* In the child: stage a.out and b.out with "new" in them (both temporary
 * files exist), or _exit(9). */
static void stage_two(void)
{
    char a[512], b[512];
    path_in(a, sizeof a, "a.out");
    path_in(b, sizeof b, "b.out");
    meso_output *oa, *ob;
    meso_error e;
    if (cli_output_stage(a, &oa, &e) != MESO_OK || cli_output_stage(b, &ob, &e) != MESO_OK)
        _exit(9);
    if (meso_output_write(oa, "new", 3, &e) != MESO_OK || meso_output_write(ob, "new", 3, &e) != MESO_OK)
        _exit(9);
    if (access(oa->temp, F_OK) != 0 || access(ob->temp, F_OK) != 0 || count_entries(".tmp.") != 2)
        _exit(9);
}

static void reset_old_files(void)
{
    char p[512];
    path_in(p, sizeof p, "a.out");
    write_text(p, "old");
    path_in(p, sizeof p, "b.out");
    write_text(p, "old");
}

static void expect_old_files_and_no_temp(void)
{
    char a[512], b[512];
    path_in(a, sizeof a, "a.out");
    path_in(b, sizeof b, "b.out");
    assert(has_text(a, "old") && has_text(b, "old"));
    assert(count_entries(".tmp.") == 0 && count_entries("") == 2);
}

/* Reset a.out and b.out to "old", run `body` in a child process (it ends
 * with _exit or a signal) and return the child's wait status. */
static int in_child(void (*body)(void))
{
    reset_old_files();
    pid_t pid = fork();
    assert(pid >= 0);
    if (pid == 0) {
        body();
        _exit(8);
    }
    int status;
    assert(waitpid(pid, &status, 0) == pid);
    return status;
}

static int child_signal;

static void stage_then_raise(void)
{
    cli_signals_install();
    stage_two();
    raise(child_signal);
}

static void signal_on_the_main_thread_removes_the_temporaries(int sig)
{
    child_signal = sig;
    int st = in_child(stage_then_raise);
    assert(WIFSIGNALED(st) && WTERMSIG(st) == sig);
    expect_old_files_and_no_temp();
}

static void* idle_thread(void* arg)
{
    (void)arg;
    for (;;)
        pause();
    return NULL;
}

static void stage_then_signal_a_worker(void)
{
    cli_signals_install();
    stage_two();
    pthread_t t;
    if (pthread_create(&t, NULL, idle_thread, NULL) != 0)
        _exit(7);
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set, NULL); /* only the worker can take it */
    kill(getpid(), SIGTERM);
    for (;;)
        pause();
}

/* The bake's worker threads (OpenMP, TBB) can receive the signal. */
static void signal_on_a_worker_thread_removes_the_temporaries(void)
{
    int st = in_child(stage_then_signal_a_worker);
    assert(WIFSIGNALED(st) && WTERMSIG(st) == SIGTERM);
    expect_old_files_and_no_temp();
}

static void stage_ignore_hup_publish(void)
{
    signal(SIGHUP, SIG_IGN); /* as nohup does */
    cli_signals_install();
    stage_two();
    raise(SIGHUP);
    meso_error e;
    _exit(cli_outputs_publish(&e) == MESO_OK ? 0 : 6);
}

static void ignored_signal_stays_ignored(void)
{
    int st = in_child(stage_ignore_hup_publish);
    assert(WIFEXITED(st) && WEXITSTATUS(st) == 0);
    char a[512], b[512];
    path_in(a, sizeof a, "a.out");
    path_in(b, sizeof b, "b.out");
    assert(has_text(a, "new") && has_text(b, "new") && count_entries(".tmp.") == 0);
}

static void stage_discard(void)
{
    stage_two();
    cli_outputs_discard();
    _exit(count_entries(".tmp.") == 0 ? 0 : 5);
}

/* b.out becomes a directory after staging: a.out (first) is not renamed either. */
static void stage_break_b_publish(void)
{
    stage_two();
    char b[512];
    path_in(b, sizeof b, "b.out");
    if (unlink(b) != 0 || mkdir(b, 0755) != 0)
        _exit(4);
    meso_error e;
    meso_result r = cli_outputs_publish(&e);
    rmdir(b);
    write_text(b, "old");
    _exit(r == MESO_ERR_IO && e.code == MESO_ISSUE_IO_DESTINATION && strstr(e.message, "directory") ? 0 : 4);
}

static void discard_and_failed_publish_publish_nothing(void)
{
    int st = in_child(stage_discard);
    assert(WIFEXITED(st) && WEXITSTATUS(st) == 0);
    expect_old_files_and_no_temp();
    st = in_child(stage_break_b_publish);
    assert(WIFEXITED(st) && WEXITSTATUS(st) == 0);
    expect_old_files_and_no_temp();
}

static void one_file_named_by_two_outputs_is_refused(void)
{
    char a[512], l[512];
    path_in(a, sizeof a, "a.out");
    path_in(l, sizeof l, "link");
    assert(symlink("a.out", l) == 0);
    meso_output *o1, *o2;
    meso_error e;
    assert(cli_output_stage(a, &o1, &e) == MESO_OK);
    assert(cli_output_stage(l, &o2, &e) == MESO_ERR_INVALID_ARG && o2 == NULL && strstr(e.message, "two outputs"));
    assert(count_entries(".tmp.") == 1);
    cli_outputs_discard();
    assert(count_entries(".tmp.") == 0);
    unlink(l);
}

int main(void)
{
    make_test_dir("meso_cli_output");
    signal_on_the_main_thread_removes_the_temporaries(SIGINT);
    signal_on_the_main_thread_removes_the_temporaries(SIGTERM);
    signal_on_the_main_thread_removes_the_temporaries(SIGHUP);
    signal_on_a_worker_thread_removes_the_temporaries();
    ignored_signal_stays_ignored();
    discard_and_failed_publish_publish_nothing();
    one_file_named_by_two_outputs_is_refused();
    char p[512];
    path_in(p, sizeof p, "a.out");
    unlink(p);
    path_in(p, sizeof p, "b.out");
    unlink(p);
    assert(count_entries("") == 0);
    assert(rmdir(dir) == 0);
    printf("test_cli_output: ok\n");
    return 0;
}
