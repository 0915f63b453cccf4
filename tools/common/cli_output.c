/* cli_output.c — staged outputs and their signal cleanup; see cli_output.h.
 * Shared by mesobake and mesoinspect (the library, formats/, installs no
 * signal handler). */
#include "cli_output.h"

#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static meso_output staged[CLI_MAX_OUTPUTS];
static int staged_count;
/* What the signal handler unlinks: copies of the temporary paths. */
static char* volatile staged_temp[CLI_MAX_OUTPUTS];

static const int cleanup_signals[] = {SIGINT, SIGTERM, SIGHUP};

/* The registry is changed only between enter() and leave(). A signal may be
 * handled on any thread (the bake runs OpenMP and TBB workers), so a mask on
 * the main thread is not enough; instead the handler and the main thread
 * meet through two sequentially consistent atomics: the handler stores
 * `signalled`, then reads `busy`; enter() stores `busy`, then reads
 * `signalled`. At least one of them sees the other: either the handler
 * defers to leave(), or enter() knows the process is going down before it
 * creates a file the handler would not know about. */
static atomic_int busy;
static atomic_int signalled;

static void unlink_staged(void)
{
    for (int i = 0; i < CLI_MAX_OUTPUTS; ++i) {
        const char* t = staged_temp[i];
        if (t)
            unlink(t);
    }
}

/* Remove the temporary files and end the process with signal `sig`. */
static void die_of(int sig)
{
    unlink_staged();
    signal(sig, SIG_DFL);
    raise(sig);
    /* `sig` is blocked while its handler runs: it ends the process on return. */
}

/* Async-signal-safe: atomics (lock-free), unlink, signal and raise only. */
static void on_signal(int sig)
{
    atomic_store(&signalled, sig);
    if (atomic_load(&busy))
        return; /* leave() finishes the job */
    die_of(sig);
}

static int enter(void)
{
    atomic_store(&busy, 1);
    return atomic_load(&signalled);
}

static void leave(void)
{
    atomic_store(&busy, 0);
    const int sig = atomic_load(&signalled);
    if (sig) {
        die_of(sig);
        for (;;)
            pause(); /* the signal is delivered (to this or another thread) */
    }
}

void cli_signals_install(void)
{
    for (size_t i = 0; i < sizeof cleanup_signals / sizeof cleanup_signals[0]; ++i) {
        struct sigaction old;
        if (sigaction(cleanup_signals[i], NULL, &old) == 0 && old.sa_handler == SIG_IGN)
            continue; /* nohup and friends: keep ignoring */
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_signal;
        sigemptyset(&sa.sa_mask);
        for (size_t k = 0; k < sizeof cleanup_signals / sizeof cleanup_signals[0]; ++k)
            sigaddset(&sa.sa_mask, cleanup_signals[k]);
        sigaction(cleanup_signals[i], &sa, NULL);
    }
}

static meso_result stage_error(meso_error* err, meso_result r, const char* path, const char* what)
{
    memset(err, 0, sizeof *err);
    err->result = r;
    err->chunk = -1;
    snprintf(err->message, sizeof err->message, "%s: %s", path, what);
    return r;
}

meso_result cli_output_stage(const char* path, meso_output** out, meso_error* err)
{
    *out = NULL;
    if (staged_count == CLI_MAX_OUTPUTS)
        return stage_error(err, MESO_ERR_INVALID_ARG, path, "too many outputs");
    if (enter())
        leave(); /* does not return */
    meso_output* o = &staged[staged_count];
    meso_result r = meso_output_open(path, NULL, o, err);
    for (int i = 0; r == MESO_OK && i < staged_count; ++i)
        if (!strcmp(staged[i].path, o->path)) {
            meso_output_abort(o);
            r = stage_error(err, MESO_ERR_INVALID_ARG, path, "the same file is named by two outputs");
        }
    /* The handler gets its own copy: the library frees `temp` when a write fails. */
    char* copy = r == MESO_OK ? strdup(o->temp) : NULL;
    if (r == MESO_OK && !copy) {
        meso_output_abort(o);
        r = stage_error(err, MESO_ERR_OUT_OF_MEMORY, path, "out of memory");
    }
    if (r == MESO_OK) {
        staged_temp[staged_count++] = copy;
        *out = o;
    }
    leave();
    return r;
}

static meso_result finish_all(int publish, meso_error* err)
{
    if (enter())
        leave(); /* does not return: the handler may be unlinking right now */
    meso_result r = publish ? MESO_OK : MESO_ERR_IO;
    /* Every destination is checked again before the first rename, so one
     * that changed since it was staged stops the whole run, not half of it. */
    for (int i = 0; i < staged_count && r == MESO_OK; ++i)
        r = meso_output_check(staged[i].path, err);
    for (int i = 0; i < staged_count; ++i) {
        if (r == MESO_OK)
            r = meso_output_commit(&staged[i], err);
        else
            meso_output_abort(&staged[i]);
        char* copy = (char*)staged_temp[i];
        staged_temp[i] = NULL;
        free(copy);
    }
    staged_count = 0;
    leave();
    return publish ? r : MESO_OK;
}

meso_result cli_outputs_publish(meso_error* err)
{
    if (staged_count > 0 && getenv("MESO_TEST_HOLD_OUTPUTS"))
        for (;;)
            pause(); /* test hook (cli_output.h): only a signal ends this */
    return finish_all(1, err);
}

void cli_outputs_discard(void) { (void)finish_all(0, NULL); }
