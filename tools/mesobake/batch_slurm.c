/* batch_slurm.c — the Slurm engine of `mesobake batch` (batch.h).
 *
 * meso grows no scheduler of its own: the uncached jobs go to Slurm as one
 * job array, `sbatch --wait --array=0-(N-1)%K`, whose task T runs
 *
 *   mesobake batch MANIFEST --cache DIR --run-job J --threads C
 *
 * for the T-th job J of the list — the same `mesobake <command>` line the
 * local engine runs, so the bytes are the same — and publishes into the
 * shared cache. The cache is the result channel: when sbatch returns, a job
 * whose entry is there (and checks out in full) is baked and copied to its
 * output; one whose entry is missing failed, and its task's log (which ends
 * with "mesobake batch: job J exit N seconds S") says how. Tasks that failed
 * for a reason other than their input (a node lost, killed, out of memory,
 * an I/O error: any exit but 1, 3 and 5) are submitted again, up to
 * --retries times. Accounting (sacct) is not needed.
 *
 * Everything the tasks see must be on a file system the nodes share: the
 * manifest's directory, the cache, and this mesobake executable. The work
 * directory (task script, job lists, logs) is made inside the cache and
 * removed when every job succeeded; it is kept, and named in the errors,
 * when one failed.
 */
#include "batch.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "cli_util.h"

/* Is `prog` an executable on $PATH? */
static int on_path(const char* prog)
{
    const char* path = getenv("PATH");
    if (!path)
        return 0;
    char dir[4096];
    for (const char* p = path; *p;) {
        size_t n = strcspn(p, ":");
        if (n && n + strlen(prog) + 2 < sizeof dir) {
            snprintf(dir, sizeof dir, "%.*s/%s", (int)n, p, prog);
            if (access(dir, X_OK) == 0)
                return 1;
        }
        p += n + (p[n] == ':');
    }
    return 0;
}

/* `s` in single quotes for sh, into f. */
static void put_quoted(FILE* f, const char* s)
{
    fputc('\'', f);
    for (; *s; ++s)
        if (*s == '\'')
            fputs("'\\''", f);
        else
            fputc(*s, f);
    fputc('\'', f);
}

static meso_result write_script(const char* path, const batch_manifest* m, const batch_cache* c, meso_error* err)
{
    char* manifest = realpath(m->path, NULL);
    FILE* f = manifest ? fopen(path, "w") : NULL;
    if (!f) {
        free(manifest);
        return meso_bake_fail(err, MESO_ERR_IO, 0, "%s: cannot write the Slurm task script: %s", path, strerror(errno));
    }
    fputs("#!/bin/sh\n"
          "# mesobake batch --engine slurm: array task T bakes the job on line T+1 of the list in $1.\n"
          "job=$(sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" \"$1\")\n"
          "exec ",
          f);
    put_quoted(f, batch_self_exe());
    fputs(" batch ", f);
    put_quoted(f, manifest);
    fputs(" --cache ", f);
    put_quoted(f, c->dir);
    fputs(" --run-job \"$job\" --threads \"${SLURM_CPUS_PER_TASK:-1}\"\n", f);
    free(manifest);
    const int bad = ferror(f) | fclose(f);
    if (bad || chmod(path, 0755) != 0)
        return meso_bake_fail(err, MESO_ERR_IO, 0, "%s: cannot write the Slurm task script", path);
    return MESO_OK;
}

/* From a task's log: the exit code and seconds of its status line (-1 when
 * the task never got that far) and the last line before it, as the error. */
static int read_task_log(const char* log, double* seconds, char* error, size_t size)
{
    char* text = batch_read_file(log, NULL);
    int code = -1;
    error[0] = 0;
    for (char* line = text; line && *line;) {
        char* end = strchr(line, '\n');
        if (end)
            *end = 0;
        size_t job;
        int c;
        double s;
        if (sscanf(line, "mesobake batch: job %zu exit %d seconds %lf", &job, &c, &s) == 3) {
            code = c;
            *seconds = s;
        } else if (*line) {
            snprintf(error, size, "%s", line);
        }
        if (!end)
            break;
        line = end + 1;
    }
    free(text);
    return code;
}

/* Run sbatch (stdout and stderr to `out`), waiting; meanwhile redraw the
 * progress as entries appear in the cache. Returns sbatch's exit code. */
static int run_sbatch(char** argv, const char* out, const batch_manifest* m, const batch_cache* c,
                      const size_t* list, size_t n, batch_progress* p)
{
    fflush(NULL);
    const pid_t pid = fork();
    if (pid == 0) {
        FILE* f = freopen(out, "w", stdout);
        if (!f || dup2(1, 2) < 0)
            _exit(MESO_EXIT_IO);
        execvp(argv[0], argv);
        _exit(127);
    }
    if (pid < 0)
        return -1;
    const size_t running0 = p->running, baked0 = p->baked;
    int status = 0;
    for (;;) {
        const pid_t w = waitpid(pid, &status, WNOHANG);
        if (w == pid || (w < 0 && errno != EINTR))
            break;
        size_t done = 0;
        for (size_t k = 0; k < n; ++k) {
            char* e = batch_cache_entry(c, m->jobs[list[k]].key, ".meso", 0);
            done += e && access(e, F_OK) == 0;
            free(e);
        }
        p->running = running0 - done;
        p->baked = baked0 + done;
        batch_progress_draw(p);
        const struct timespec tick = {0, 250 * 1000 * 1000};
        nanosleep(&tick, NULL);
    }
    p->running = running0;
    p->baked = baked0;
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

/* One submission of the pending jobs; returns MESO_OK when sbatch took it. */
static meso_result submit(batch_manifest* m, const batch_cache* c, const batch_options* o, const char* work,
                          int attempt, const size_t* list, size_t n, batch_progress* p, meso_error* err)
{
    char jobs_path[4200], out_path[4200], script[4200], array[64], output[4200], part[256], cpus[32], listing[4300];
    snprintf(script, sizeof script, "%s/task.sh", work);
    snprintf(jobs_path, sizeof jobs_path, "%s/attempt%d.jobs", work, attempt);
    snprintf(out_path, sizeof out_path, "%s/attempt%d.sbatch", work, attempt);
    FILE* f = fopen(jobs_path, "w");
    if (!f)
        return meso_bake_fail(err, MESO_ERR_IO, 0, "%s: %s", jobs_path, strerror(errno));
    for (size_t k = 0; k < n; ++k)
        fprintf(f, "%zu\n", list[k]);
    if (fclose(f) != 0)
        return meso_bake_fail(err, MESO_ERR_IO, 0, "%s: cannot write", jobs_path);
    if (o->max_parallel > 0)
        snprintf(array, sizeof array, "--array=0-%zu%%%d", n - 1, o->max_parallel);
    else
        snprintf(array, sizeof array, "--array=0-%zu", n - 1);
    snprintf(output, sizeof output, "--output=%s/attempt%d.%%a.log", work, attempt);
    snprintf(cpus, sizeof cpus, "--cpus-per-task=%d", o->cpus_per_task);
    char* argv[12];
    int k = 0;
    argv[k++] = "sbatch";
    argv[k++] = "--wait";
    argv[k++] = "--parsable";
    argv[k++] = "--job-name=mesobake-batch";
    argv[k++] = array;
    argv[k++] = output;
    argv[k++] = cpus;
    if (o->partition) {
        snprintf(part, sizeof part, "--partition=%s", o->partition);
        argv[k++] = part;
    }
    argv[k++] = script;
    snprintf(listing, sizeof listing, "%s", jobs_path);
    argv[k++] = listing;
    argv[k] = NULL;
    for (size_t j = 0; j < n; ++j) {
        m->jobs[list[j]].status = BATCH_RUNNING;
        m->jobs[list[j]].attempts++;
    }
    p->running += n;
    const int code = run_sbatch(argv, out_path, m, c, list, n, p);
    p->running -= n;
    /* --parsable prints the job id first; without one nothing was submitted. */
    char first[256];
    char* text = batch_read_file(out_path, NULL);
    const int submitted = text && text[0] >= '0' && text[0] <= '9';
    free(text);
    if (!submitted) {
        batch_last_line(out_path, first, sizeof first);
        return meso_bake_fail(err, MESO_ERR_IO, 0, "sbatch did not submit the job array (exit %d): %s", code,
                              first[0] ? first : "no output");
    }
    return MESO_OK;
}

meso_result batch_run_slurm(batch_manifest* m, const batch_cache* c, const batch_options* o, batch_progress* p,
                            meso_error* err)
{
    size_t todo = 0;
    for (size_t i = 0; i < m->count; ++i)
        todo += m->jobs[i].status == BATCH_PENDING && m->jobs[i].same_as == (size_t)-1;
    if (todo == 0)
        return MESO_OK; /* all cached: nothing to submit, no Slurm needed */
    if (!on_path("sbatch"))
        return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0,
                              "--engine slurm needs Slurm's sbatch on PATH (Debian: slurm-client) and a cluster to "
                              "submit to; --engine local needs nothing");
    size_t* list = calloc(m->count ? m->count : 1, sizeof *list);
    char work[4096], host[64] = "host";
    gethostname(host, sizeof host - 1);
    snprintf(work, sizeof work, "%s/slurm/%.60s-%ld-%ld", c->dir, host, (long)getpid(), (long)time(NULL));
    char probe[4200];
    snprintf(probe, sizeof probe, "%s/task.sh", work);
    meso_result r = list ? batch_mkdir_parents(probe, err) : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "out of memory");
    if (r == MESO_OK)
        r = write_script(probe, m, c, err);
    int any_failed = 0;
    for (int attempt = 1; r == MESO_OK; ++attempt) {
        size_t n = 0;
        for (size_t i = 0; i < m->count; ++i)
            if (m->jobs[i].status == BATCH_PENDING && m->jobs[i].same_as == (size_t)-1)
                list[n++] = i;
        if (n == 0)
            break;
        r = submit(m, c, o, work, attempt, list, n, p, err);
        for (size_t k = 0; k < n && r == MESO_OK; ++k) {
            batch_job* job = &m->jobs[list[k]];
            char log[4200];
            snprintf(log, sizeof log, "%s/attempt%d.%zu.log", work, attempt, k);
            meso_error e = {0};
            job->exit_code = read_task_log(log, &job->seconds, job->error, sizeof job->error);
            job->threads = batch_command_threaded(job->command) ? o->cpus_per_task : 0;
            if (job->exit_code == 0 && batch_cache_has(c, job->key) && batch_cache_copy_out(c, job, &e) == MESO_OK) {
                job->status = BATCH_BAKED;
                job->error[0] = 0;
            } else {
                if (job->exit_code == 0)
                    snprintf(job->error, sizeof job->error, "%s",
                             e.message[0] ? e.message : "the task exited 0 but left no valid cache entry");
                const int again = batch_retryable(job->exit_code) && job->attempts <= o->retries;
                job->status = again ? BATCH_PENDING : BATCH_FAILED;
                if (!again) {
                    any_failed = 1;
                    const size_t len = strlen(job->error);
                    snprintf(job->error + len, sizeof job->error - len, " (log: %.300s)", log);
                }
            }
            if (job->status != BATCH_PENDING)
                batch_progress_job(p, job);
        }
    }
    for (size_t i = 0; i < m->count; ++i)
        if (m->jobs[i].same_as == (size_t)-1 &&
            (m->jobs[i].status == BATCH_PENDING || m->jobs[i].status == BATCH_RUNNING)) {
            m->jobs[i].status = BATCH_FAILED;
            snprintf(m->jobs[i].error, sizeof m->jobs[i].error, "%s", err && err->message[0] ? err->message : "not run");
            batch_progress_job(p, &m->jobs[i]);
        }
    if (r == MESO_OK && !any_failed) { /* nothing to look at: remove the work directory */
        char cmd[4200];
        for (int a = 1; a < 64; ++a) {
            snprintf(cmd, sizeof cmd, "%s/attempt%d.jobs", work, a);
            if (unlink(cmd) != 0)
                break;
            snprintf(cmd, sizeof cmd, "%s/attempt%d.sbatch", work, a);
            unlink(cmd);
            for (size_t k = 0; k < m->count; ++k) {
                snprintf(cmd, sizeof cmd, "%s/attempt%d.%zu.log", work, a, k);
                unlink(cmd);
            }
        }
        unlink(probe);
        rmdir(work);
    }
    free(list);
    return r;
}
