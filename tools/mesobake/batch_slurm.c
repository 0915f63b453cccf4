/* batch_slurm.c — the Slurm engine of `mesobake batch` (batch.h).
 *
 * meso grows no scheduler of its own: the uncached jobs go to Slurm as job
 * arrays, `sbatch --wait --array=0-(N-1)%K`, whose task T runs
 *
 *   mesobake batch MANIFEST --cache DIR --run-job J --expect-key KEY --threads C
 *
 * for the T-th line "J KEY" of its list — the same `mesobake <command>` line
 * the local engine runs, so the bytes are the same — and publishes into the
 * shared cache. KEY is job J's key here: a task whose node computes another
 * (its mesobake build or its view of the inputs differs) refuses to bake; a
 * job without a key (an input that cannot be read) passes none. The cache
 * is the result channel: once the arrays have left the queue, a job whose
 * entry is there (and checks out in full) is baked and copied to its
 * output, whatever its log says; one whose entry is missing failed, and
 * its task's log (which ends with "mesobake batch: job J exit N seconds S")
 * says how. Tasks that failed for a reason other than
 * their input (a node lost, killed, out of memory, an I/O error, no status
 * line, exit 0 without an entry: any exit but 1, 3 and 5) are submitted
 * again, up to --retries times. Accounting (sacct) is not needed.
 *
 * Submission. sbatch's stdout and stderr go to separate files; the array was
 * submitted when stdout holds the job id (a line "ID" or "ID;CLUSTER" of
 * --parsable), whatever a site's job_submit plugin or a warning said on
 * stderr. An array holds at most MaxArraySize-1 tasks (`scontrol show
 * config`, 1001 when it cannot be read), so a larger batch is split into
 * chunks, each its own array, list and logs (attemptA.cK.*), all submitted
 * at once as concurrent `sbatch --wait` processes. --max-parallel K is
 * divided among the chunks (K/chunks each, the remainder to the first
 * ones, at least 1 each), so the batch keeps to K tasks at once unless it
 * has more chunks than K. After sbatch exits — normally, with an error, or
 * killed — each submitted array is waited for until `squeue -j ID` lists
 * none of its tasks (up to an hour), so a task still running is never
 * judged failed or submitted twice; tasks still queued after that are
 * failed and not resubmitted.
 *
 * Everything the tasks see must be on a file system the nodes share: the
 * manifest's directory, the cache, and this mesobake executable. The work
 * directory (task script, job lists, sbatch's output, logs) is made inside
 * the cache under slurm/ and removed, with slurm/ when that is left empty,
 * when every job succeeded; it is kept, and named in the errors, when one
 * failed. Its path is part of sbatch's --output filename pattern: a '%' in
 * it is written "%%"; a backslash would turn the patterns off, so a cache
 * path with one is refused.
 */
#include "batch.h"

#include <dirent.h>
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
          "# mesobake batch --engine slurm: array task T bakes the job on line T+1 (\"INDEX KEY\") of the list\n"
          "# in $1, refusing when this node computes another key for it.\n"
          "line=$(sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" \"$1\")\n"
          "job=${line%% *} key=${line#* }\n"
          "exec ",
          f);
    put_quoted(f, batch_self_exe());
    fputs(" batch ", f);
    put_quoted(f, manifest);
    fputs(" --cache ", f);
    put_quoted(f, c->dir);
    fputs(" --run-job \"$job\" ${key:+--expect-key \"$key\"} --threads \"${SLURM_CPUS_PER_TASK:-1}\"\n", f);
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

/* `in` with each '%' doubled (a literal '%' in a Slurm filename pattern);
 * 0 when it does not fit. */
static int escape_pattern(const char* in, char* out, size_t size)
{
    size_t n = 0;
    for (; *in; ++in) {
        if (n + 3 > size)
            return 0;
        if (*in == '%')
            out[n++] = '%';
        out[n++] = *in;
    }
    out[n] = 0;
    return 1;
}

/* The cluster's MaxArraySize (array indices run 0..MaxArraySize-1), or
 * Slurm's default 1001 when `scontrol show config` cannot tell. */
static size_t max_array_size(void)
{
    size_t max = 1001;
    fflush(NULL);
    FILE* f = popen("scontrol show config 2>/dev/null", "r");
    if (!f)
        return max;
    char line[512];
    unsigned long v;
    while (fgets(line, sizeof line, f))
        if (sscanf(line, "MaxArraySize = %lu", &v) == 1 && v >= 1)
            max = v;
    pclose(f);
    return max;
}

/* Is Slurm job `id` still queued (pending, running, completing)? 1 yes,
 * 0 gone, -1 cannot tell (squeue failed: the controller busy or down). */
static int job_queued(const char* id)
{
    char cmd[128], line[512];
    snprintf(cmd, sizeof cmd, "squeue -h -j %s -o %%i 2>&1", id); /* id: digits only; one task id a line */
    fflush(NULL);
    FILE* f = popen(cmd, "r");
    if (!f)
        return -1;
    int any = 0, invalid = 0;
    while (fgets(line, sizeof line, f)) {
        invalid |= strstr(line, "Invalid job id") != NULL;
        any |= line[0] >= '0' && line[0] <= '9';
    }
    const int status = pclose(f);
    if (invalid)
        return 0; /* already purged */
    if (status != 0)
        return -1;
    return any;
}

/* The job id sbatch --parsable printed on stdout: a line ^[0-9]+(;.*)?$.
 * 0 when there is none. */
static int read_job_id(const char* out, char* id, size_t size)
{
    char* text = batch_read_file(out, NULL);
    int found = 0;
    for (char* line = text; line && *line && !found;) {
        char* end = strchr(line, '\n');
        if (end)
            *end = 0;
        const size_t digits = strspn(line, "0123456789");
        if (digits > 0 && digits < size && (line[digits] == 0 || line[digits] == ';')) {
            snprintf(id, size, "%.*s", (int)digits, line);
            found = 1;
        }
        line = end ? end + 1 : NULL;
    }
    free(text);
    return found;
}

/* One array of an attempt: the tasks list[first .. first + n). */
typedef struct chunk {
    size_t first, n;
    pid_t pid;       /* its sbatch; -1 when it did not start */
    int code;        /* sbatch's exit code */
    char id[32];     /* the Slurm job id; "" when nothing was submitted */
    int queued;      /* still in the queue when we stopped waiting */
    char base[4200]; /* WORK/attemptA.cK */
} chunk;

/* Start `sbatch --wait` of chunk `ch` (list file written here); stdout to
 * BASE.out, stderr to BASE.err. */
static meso_result start_chunk(const batch_manifest* m, const batch_options* o, const char* script,
                               const size_t* list, chunk* ch, int throttle, meso_error* err)
{
    char jobs_path[4300], out[4300], errp[4300], array[64], output[8600], part[256], cpus[32];
    char pattern[8500];
    snprintf(jobs_path, sizeof jobs_path, "%s.jobs", ch->base);
    snprintf(out, sizeof out, "%s.out", ch->base);
    snprintf(errp, sizeof errp, "%s.err", ch->base);
    FILE* f = fopen(jobs_path, "w");
    if (!f)
        return meso_bake_fail(err, MESO_ERR_IO, 0, "%s: %s", jobs_path, strerror(errno));
    for (size_t k = 0; k < ch->n; ++k)
        fprintf(f, "%zu %s\n", list[ch->first + k], m->jobs[list[ch->first + k]].key);
    if ((ferror(f) | fclose(f)) != 0)
        return meso_bake_fail(err, MESO_ERR_IO, 0, "%s: cannot write", jobs_path);
    if (throttle > 0)
        snprintf(array, sizeof array, "--array=0-%zu%%%d", ch->n - 1, throttle);
    else
        snprintf(array, sizeof array, "--array=0-%zu", ch->n - 1);
    if (!escape_pattern(ch->base, pattern, sizeof pattern))
        return meso_bake_fail(err, MESO_ERR_IO, 0, "%s: path too long", ch->base);
    snprintf(output, sizeof output, "--output=%s.%%a.log", pattern);
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
    argv[k++] = (char*)script;
    argv[k++] = jobs_path;
    argv[k] = NULL;
    fflush(NULL);
    ch->pid = fork();
    if (ch->pid == 0) {
        if (!freopen(out, "w", stdout) || !freopen(errp, "w", stderr))
            _exit(MESO_EXIT_IO);
        execvp(argv[0], argv);
        _exit(127);
    }
    if (ch->pid < 0)
        return meso_bake_fail(err, MESO_ERR_IO, 0, "cannot start sbatch: %s", strerror(errno));
    return MESO_OK;
}

/* Redraw the progress, counting the jobs of `list` whose entries appeared. */
static void draw(const batch_manifest* m, const batch_cache* c, const size_t* list, size_t n, batch_progress* p)
{
    const size_t running0 = p->running, baked0 = p->baked;
    size_t done = 0;
    for (size_t k = 0; k < n; ++k) {
        char* e = batch_cache_entry(c, m->jobs[list[k]].key, ".meso", 0);
        done += e && access(e, F_OK) == 0;
        free(e);
    }
    p->running = running0 - (done < running0 ? done : running0);
    p->baked = baked0 + done;
    batch_progress_draw(p);
    p->running = running0;
    p->baked = baked0;
}

static void pause_seconds(double s)
{
    const struct timespec t = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    nanosleep(&t, NULL);
}

/* Wait for every sbatch, then until no submitted array has a task left in
 * the queue (each squeue every 0.5 s, for up to an hour). */
static void wait_chunks(chunk* ch, size_t nch, const batch_manifest* m, const batch_cache* c, const size_t* list,
                        size_t n, batch_progress* p)
{
    for (size_t alive = nch; alive > 0;) {
        alive = 0;
        for (size_t k = 0; k < nch; ++k) {
            if (ch[k].pid <= 0)
                continue;
            int status = 0;
            const pid_t w = waitpid(ch[k].pid, &status, WNOHANG);
            if (w == ch[k].pid || (w < 0 && errno != EINTR)) {
                ch[k].code = w == ch[k].pid && WIFEXITED(status) ? WEXITSTATUS(status)
                             : w == ch[k].pid && WIFSIGNALED(status) ? 128 + WTERMSIG(status)
                                                                       : -1;
                ch[k].pid = -1;
            } else {
                alive++;
            }
        }
        if (alive) {
            draw(m, c, list, n, p);
            pause_seconds(0.25);
        }
    }
    for (size_t k = 0; k < nch; ++k) {
        char out[4300];
        snprintf(out, sizeof out, "%s.out", ch[k].base);
        ch[k].id[0] = 0;
        read_job_id(out, ch[k].id, sizeof ch[k].id);
        ch[k].queued = ch[k].id[0] != 0;
    }
    const time_t until = time(NULL) + 3600;
    for (;;) {
        size_t left = 0;
        for (size_t k = 0; k < nch; ++k)
            if (ch[k].queued) {
                ch[k].queued = job_queued(ch[k].id) != 0;
                left += ch[k].queued != 0;
            }
        if (left == 0 || time(NULL) >= until)
            break;
        draw(m, c, list, n, p);
        pause_seconds(0.5);
    }
}

/* Judge one task after its array left the queue: the cache entry first,
 * then the log. Returns 1, leaving the job RUNNING, when it exited 0 but its
 * entry is not (yet) visible and `final` is 0: the caller looks again after a
 * moment (NFS attribute caches). */
static int judge(const batch_cache* c, const batch_options* o, batch_job* job, const char* log,
                 int final, int* any_failed)
{
    job->threads = batch_command_threaded(job->command) ? o->cpus_per_task : 0;
    char error[sizeof job->error];
    const int code = read_task_log(log, &job->seconds, error, sizeof error);
    if (job->key[0] && batch_cache_has(c, job->key)) {
        meso_error e = {0};
        job->exit_code = 0; /* the entry checks out, whatever the log says */
        if (batch_cache_copy_out(c, job, &e) == MESO_OK) {
            job->status = BATCH_BAKED;
            job->error[0] = 0;
        } else { /* a problem here, not on the node: another bake would not help */
            job->status = BATCH_FAILED;
            snprintf(job->error, sizeof job->error, "%s", e.message);
            *any_failed = 1;
        }
        return 0;
    }
    if (code == 0 && !final && job->key[0])
        return 1;
    job->exit_code = code;
    if (code < 0)
        snprintf(job->error, sizeof job->error,
                 "the task ended without a status line (killed, or its node failed)%s%.200s", error[0] ? ": " : "",
                 error);
    else if (code == 0)
        snprintf(job->error, sizeof job->error, "the task exited 0 but left no valid cache entry");
    else
        snprintf(job->error, sizeof job->error, "%s", error);
    const int again = (code == 0 || batch_retryable(code)) && job->attempts <= o->retries;
    job->status = again ? BATCH_PENDING : BATCH_FAILED;
    if (!again) {
        *any_failed = 1;
        const size_t len = strlen(job->error);
        snprintf(job->error + len, sizeof job->error - len, " (log: %.300s)", log);
    }
    return 0;
}

/* One attempt: the pending jobs list[0..n) as arrays of at most
 * `per_array` tasks. MESO_OK unless an array could not be submitted. */
static meso_result attempt_once(batch_manifest* m, const batch_cache* c, const batch_options* o, const char* work,
                                int attempt, const size_t* list, size_t n, size_t per_array, batch_progress* p,
                                int* any_failed, meso_error* err)
{
    const size_t nch = (n + per_array - 1) / per_array;
    chunk* ch = calloc(nch, sizeof *ch);
    if (!ch)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "out of memory");
    char script[4200];
    snprintf(script, sizeof script, "%s/task.sh", work);
    for (size_t j = 0; j < n; ++j) {
        m->jobs[list[j]].status = BATCH_RUNNING;
        m->jobs[list[j]].attempts++;
    }
    p->running += n;
    meso_result r = MESO_OK;
    for (size_t k = 0; k < nch; ++k) {
        ch[k].first = k * per_array;
        ch[k].n = k + 1 < nch ? per_array : n - k * per_array;
        ch[k].pid = -1;
        snprintf(ch[k].base, sizeof ch[k].base, "%s/attempt%d.c%zu", work, attempt, k);
        int throttle = 0;
        if (o->max_parallel > 0) {
            throttle = (int)((size_t)o->max_parallel / nch + (k < (size_t)o->max_parallel % nch));
            throttle = throttle < 1 ? 1 : throttle;
        }
        if (r == MESO_OK)
            r = start_chunk(m, o, script, list, &ch[k], throttle, err);
    }
    wait_chunks(ch, nch, m, c, list, n, p);
    p->running -= n;
    size_t deferred = 0;
    for (int final = 0; final < 2; ++final) {
        if (final) {
            if (!deferred)
                break;
            pause_seconds(1.0);
        }
        for (size_t k = 0; k < nch; ++k) {
            if (!ch[k].id[0]) { /* nothing submitted: the batch cannot go on */
                if (r == MESO_OK) {
                    char why[256], path[4300];
                    snprintf(path, sizeof path, "%s.err", ch[k].base);
                    batch_last_line(path, why, sizeof why);
                    if (!why[0]) {
                        snprintf(path, sizeof path, "%s.out", ch[k].base);
                        batch_last_line(path, why, sizeof why);
                    }
                    r = meso_bake_fail(err, MESO_ERR_IO, 0, "sbatch did not submit the job array (exit %d): %s",
                                       ch[k].code, why[0] ? why : "no output");
                }
                continue;
            }
            for (size_t t = 0; t < ch[k].n; ++t) {
                batch_job* job = &m->jobs[list[ch[k].first + t]];
                if (job->status != BATCH_RUNNING)
                    continue;
                char log[4300];
                snprintf(log, sizeof log, "%s.%zu.log", ch[k].base, t);
                if (ch[k].queued) {
                    snprintf(job->error, sizeof job->error,
                             "Slurm job %s still had tasks queued an hour after sbatch ended: not resubmitted "
                             "(log: %.300s)",
                             ch[k].id, log);
                    job->status = BATCH_FAILED;
                    *any_failed = 1;
                } else if (judge(c, o, job, log, final, any_failed)) {
                    deferred++;
                    continue;
                }
                if (job->status != BATCH_PENDING)
                    batch_progress_job(p, job);
            }
        }
    }
    free(ch);
    return r;
}

/* Remove the work directory (every file in it is ours) and slurm/ when empty. */
static void remove_work(const char* work)
{
    DIR* d = opendir(work);
    if (d) {
        char path[4400];
        for (struct dirent* e; (e = readdir(d)) != NULL;) {
            if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
                continue;
            snprintf(path, sizeof path, "%s/%s", work, e->d_name);
            unlink(path);
        }
        closedir(d);
    }
    rmdir(work);
    char parent[4096];
    snprintf(parent, sizeof parent, "%s", work);
    char* slash = strrchr(parent, '/');
    if (slash) {
        *slash = 0;
        rmdir(parent); /* fails, as it should, while another batch's work is there */
    }
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
    if (strchr(c->dir, '\\'))
        return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0,
                              "%s: the Slurm engine cannot use a cache path with a backslash (it turns off sbatch's "
                              "--output patterns); choose another --cache",
                              c->dir);
    size_t* list = calloc(m->count ? m->count : 1, sizeof *list);
    char work[4096], host[64] = "host";
    gethostname(host, sizeof host - 1);
    snprintf(work, sizeof work, "%s/slurm/%.60s-%ld-%ld", c->dir, host, (long)getpid(), (long)time(NULL));
    char probe[4200];
    snprintf(probe, sizeof probe, "%s/task.sh", work);
    meso_result r = list ? batch_mkdir_parents(probe, err) : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "out of memory");
    if (r == MESO_OK)
        r = write_script(probe, m, c, err);
    const size_t max = r == MESO_OK ? max_array_size() : 2;
    const size_t per_array = max > 1 ? max - 1 : 1;
    int any_failed = 0;
    for (int attempt = 1; r == MESO_OK; ++attempt) {
        size_t n = 0;
        for (size_t i = 0; i < m->count; ++i)
            if (m->jobs[i].status == BATCH_PENDING && m->jobs[i].same_as == (size_t)-1)
                list[n++] = i;
        if (n == 0)
            break;
        r = attempt_once(m, c, o, work, attempt, list, n, per_array, p, &any_failed, err);
    }
    for (size_t i = 0; i < m->count; ++i)
        if (m->jobs[i].same_as == (size_t)-1 &&
            (m->jobs[i].status == BATCH_PENDING || m->jobs[i].status == BATCH_RUNNING)) {
            m->jobs[i].status = BATCH_FAILED;
            snprintf(m->jobs[i].error, sizeof m->jobs[i].error, "%s", err && err->message[0] ? err->message : "not run");
            batch_progress_job(p, &m->jobs[i]);
        }
    if (r == MESO_OK && !any_failed) /* nothing to look at: remove the work directory */
        remove_work(work);
    free(list);
    return r;
}
