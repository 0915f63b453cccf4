/* batch_local.c — the local engine of `mesobake batch` (batch.h): up to -j
 * `mesobake <command>` processes at once, each in the manifest's directory,
 * each baking into the cache (or straight to its output under --no-cache).
 *
 * Processes, not threads: a bake that crashes or runs out of memory takes
 * only its own job down, every job gets the same command line a person (or
 * a Slurm task) would run, and the baker library needs no re-entrancy
 * beyond what one bake uses. Threads per bake, fixed when it starts: the
 * cores divided among the bakes that can still run at once, so -j 2 on two
 * cores runs two one-thread bakes, and a bake that starts alone gets both.
 * The outputs do not depend on it (rule 7). The costliest jobs start first
 * (start_order).
 * A job without a key (an input that cannot be read) bakes straight to its
 * output, uncached, so that the bake's own error says what is missing.
 */
#include "batch.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cli_util.h"

const char* batch_self_exe(void)
{
    static char path[4096];
    if (!path[0]) {
        ssize_t n = readlink("/proc/self/exe", path, sizeof path - 1);
        if (n <= 0 || (size_t)n >= sizeof path - 1)
            return NULL;
        path[n] = 0;
    }
    return path;
}

int batch_retryable(int exit_code)
{
    return exit_code != MESO_EXIT_OK && exit_code != MESO_EXIT_USAGE && exit_code != MESO_EXIT_INVALID &&
           exit_code != MESO_EXIT_UNSUPPORTED;
}

pid_t batch_spawn(const batch_manifest* m, const batch_job* job, const char* dest, const char* report, int threads,
                  const char* log_path)
{
    const char* self = batch_self_exe();
    if (!self) {
        errno = ENOENT;
        return -1;
    }
    char tbuf[16];
    snprintf(tbuf, sizeof tbuf, "%d", threads);
    /* mesobake COMMAND -i IN -o OUT --report R ARGS --threads T, and NULL */
    const size_t n = 11 + job->arg_count;
    const char** argv = calloc(n, sizeof *argv);
    if (!argv)
        return -1;
    size_t k = 0;
    argv[k++] = self;
    argv[k++] = job->command;
    argv[k++] = "-i";
    argv[k++] = job->input;
    argv[k++] = "-o";
    argv[k++] = dest;
    if (report) {
        argv[k++] = "--report";
        argv[k++] = report;
    }
    for (size_t a = 0; a < job->arg_count; ++a)
        argv[k++] = job->args[a];
    if (threads > 0 && batch_command_threaded(job->command)) {
        argv[k++] = "--threads";
        argv[k++] = tbuf;
    }
    argv[k] = NULL;
    fflush(NULL);
    const pid_t parent = getpid();
    const pid_t pid = fork();
    if (pid != 0) {
        const int saved = errno;
        free(argv);
        errno = saved;
        return pid;
    }
    /* The child: only async-signal-safe calls until exec. */
#ifdef PR_SET_PDEATHSIG
    prctl(PR_SET_PDEATHSIG, SIGTERM); /* the batch killed: the bake cleans up and ends too */
    if (getppid() != parent)
        _exit(128 + SIGTERM);
#endif
    int in = open("/dev/null", O_RDONLY);
    if (in >= 0) {
        dup2(in, 0);
        close(in);
    }
    if (log_path) {
        int fd = open(log_path, O_WRONLY | O_CREAT | O_APPEND, 0666);
        if (fd < 0)
            _exit(MESO_EXIT_IO);
        dup2(fd, 1);
        dup2(fd, 2);
        close(fd);
    }
    if (chdir(m->dir) != 0) {
        static const char msg[] = "mesobake batch: cannot enter the manifest's directory\n";
        if (write(2, msg, sizeof msg - 1) < 0) { /* nothing more to say */
        }
        _exit(MESO_EXIT_IO);
    }
    execv(self, (char* const*)argv);
    static const char msg[] = "mesobake batch: cannot run mesobake\n";
    if (write(2, msg, sizeof msg - 1) < 0) { /* nothing more to say */
    }
    _exit(MESO_EXIT_INTERNAL);
}

/* The exit code of a wait status: the code, or 128 + the signal. */
static int exit_code_of(int status)
{
    return WIFEXITED(status) ? WEXITSTATUS(status) : WIFSIGNALED(status) ? 128 + WTERMSIG(status) : MESO_EXIT_INTERNAL;
}

/* The directory of the bakes' logs: $TMPDIR (when absolute and shorter
 * than this) or /tmp, then "/mesobake-batch-XXXXXX". */
#define BATCH_TMP_MAX 1024

typedef struct slot {
    pid_t pid;
    size_t job;
    double t0;
    char log[BATCH_TMP_MAX + 32];
    char report[BATCH_TMP_MAX + 32]; /* the --report path (scratch, when in the cache) */
    char scratch[4096];               /* the scratch .meso in the cache; "" when not cached */
} slot;

static void start_job(batch_manifest* m, const batch_cache* c, size_t i, int threads, slot* s, const char* tmp,
                      batch_progress* p)
{
    batch_job* job = &m->jobs[i];
    const int cached = c->dir && job->key[0];
    char *dest = NULL, *report = NULL;
    meso_error e = {0};
    s->job = i;
    s->scratch[0] = 0;
    snprintf(s->log, sizeof s->log, "%s/%zu.log", tmp, i);
    snprintf(s->report, sizeof s->report, "%s/%zu.json", tmp, i);
    if (cached) {
        dest = batch_cache_scratch(c, job->key, ".meso");
        report = dest ? batch_cache_scratch(c, job->key, ".json") : NULL;
        snprintf(s->scratch, sizeof s->scratch, "%s", dest ? dest : "");
        snprintf(s->report, sizeof s->report, "%s", report ? report : "");
    } else if (batch_mkdir_parents(job->output_path, &e) == MESO_OK) {
        dest = strdup(job->output_path);
        report = strdup(s->report);
    }
    job->threads = batch_command_threaded(job->command) ? threads : 0;
    job->attempts++;
    s->t0 = meso_seconds();
    s->pid = dest && report ? batch_spawn(m, job, dest, report, threads, s->log) : -1;
    if (s->pid < 0) {
        job->status = BATCH_FAILED;
        job->exit_code = MESO_EXIT_IO;
        snprintf(job->error, sizeof job->error, "cannot start the bake: %s",
                 e.message[0] ? e.message : strerror(errno));
        batch_progress_job(p, job);
    } else {
        job->status = BATCH_RUNNING;
        p->running++;
        batch_progress_draw(p);
    }
    free(dest);
    free(report);
}

static void finish_job(batch_manifest* m, const batch_cache* c, slot* s, int status, batch_progress* p)
{
    batch_job* job = &m->jobs[s->job];
    job->seconds = meso_seconds() - s->t0;
    job->exit_code = exit_code_of(status);
    p->running--;
    job->status = BATCH_FAILED;
    meso_error e = {0};
    if (job->exit_code != 0) {
        batch_last_line(s->log, job->error, sizeof job->error);
        if (!job->error[0] || job->exit_code > 128)
            snprintf(job->error, sizeof job->error, "the bake %s %d", job->exit_code > 128 ? "died of signal" : "exited",
                     job->exit_code > 128 ? job->exit_code - 128 : job->exit_code);
    } else if (s->scratch[0]) {
        if (batch_cache_publish(c, m, job, s->scratch, s->report, &e) != MESO_OK ||
            !batch_cache_has(c, job->key) || batch_cache_copy_out(c, job, &e) != MESO_OK) {
            snprintf(job->error, sizeof job->error, "%s",
                     e.message[0] ? e.message : "the bake exited 0 but left no valid cache entry");
            job->exit_code = MESO_EXIT_IO;
        } else {
            job->status = BATCH_BAKED;
        }
    } else {
        free(job->report_json);
        job->report_json = batch_read_file(s->report, NULL);
        job->status = BATCH_BAKED;
    }
    unlink(s->log);
    unlink(s->report);
    if (s->scratch[0])
        unlink(s->scratch);
    s->pid = 0;
    batch_progress_job(p, job);
}

/* A guess at a job's cost, for the start order: the input's size times
 * how much work a command does per input byte (shells trace and validate
 * every vertex; cells voxelize; frusta fit a skeleton; mesh copies). */
static double cost_guess(const batch_manifest* m, const batch_job* job)
{
    const double weight = !strcmp(job->command, "shell")   ? 8
                          : !strcmp(job->command, "cells") ? 4
                          : !strcmp(job->command, "frusta") ? 2
                                                            : 1;
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", m->dir, job->input);
    struct stat st;
    const int found = stat(job->input[0] == '/' ? job->input : path, &st) == 0;
    return found ? weight * (double)st.st_size : 0;
}

static const double* sort_costs;
static int by_cost_descending(const void* a, const void* b)
{
    const size_t i = *(const size_t*)a, j = *(const size_t*)b;
    if (sort_costs[i] != sort_costs[j])
        return sort_costs[i] < sort_costs[j] ? 1 : -1;
    return (i > j) - (i < j);
}

/* The order bakes start in: the costliest first (longest-processing-time
 * first keeps the cores busy at the end of a batch, where a long bake that
 * started last would run alone), manifest order among equals. The bytes
 * do not depend on it. NULL when out of memory. */
static size_t* start_order(const batch_manifest* m)
{
    size_t* order = malloc((m->count ? m->count : 1) * sizeof *order);
    double* cost = malloc((m->count ? m->count : 1) * sizeof *cost);
    for (size_t i = 0; order && i < m->count; ++i)
        order[i] = i;
    if (order && cost) { /* (without `cost`: manifest order) */
        for (size_t i = 0; i < m->count; ++i)
            cost[i] = cost_guess(m, &m->jobs[i]);
        sort_costs = cost;
        qsort(order, m->count, sizeof *order, by_cost_descending);
    }
    free(cost);
    return order;
}

meso_result batch_run_local(batch_manifest* m, const batch_cache* c, const batch_options* o, batch_progress* p,
                            meso_error* err)
{
    const char* tmpdir = getenv("TMPDIR");
    static const char name[] = "/mesobake-batch-XXXXXX";
    char tmp[BATCH_TMP_MAX];
    snprintf(tmp, sizeof tmp, "%s%s",
             tmpdir && tmpdir[0] == '/' && strlen(tmpdir) + sizeof name <= sizeof tmp ? tmpdir : "/tmp", name);
    if (!mkdtemp(tmp))
        return meso_bake_fail(err, MESO_ERR_IO, 0, "%s: cannot create a directory for the logs: %s", tmp,
                              strerror(errno));
    const int width = o->jobs > 0 ? o->jobs : 1;
    slot* slots = calloc((size_t)width, sizeof *slots);
    if (!slots) {
        rmdir(tmp);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "out of memory");
    }
    size_t left = 0; /* jobs to bake not yet finished */
    for (size_t i = 0; i < m->count; ++i)
        left += m->jobs[i].status == BATCH_PENDING && m->jobs[i].same_as == (size_t)-1;
    size_t* order = start_order(m);
    if (!order) {
        free(slots);
        rmdir(tmp);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "out of memory");
    }
    size_t next = 0;
    int running = 0;
    for (;;) {
        for (int s = 0; s < width && next < m->count; ++s) {
            if (slots[s].pid)
                continue;
            while (next < m->count &&
                   !(m->jobs[order[next]].status == BATCH_PENDING && m->jobs[order[next]].same_as == (size_t)-1))
                ++next;
            if (next == m->count)
                break;
            const size_t at_once = left < (size_t)width ? left : (size_t)width;
            const int threads = at_once ? (int)((size_t)o->cpus / at_once) : 1;
            start_job(m, c, order[next++], threads > 0 ? threads : 1, &slots[s], tmp, p);
            if (slots[s].pid > 0)
                ++running;
            else
                slots[s].pid = 0, --left;
        }
        if (running == 0 && next >= m->count)
            break;
        if (running == 0)
            continue; /* every slot's start failed this pass: start the next jobs */
        int status = 0;
        const pid_t pid = waitpid(-1, &status, 0);
        if (pid < 0) {
            if (errno == EINTR)
                continue;
            break; /* ECHILD: nothing left to wait for */
        }
        for (int s = 0; s < width; ++s)
            if (slots[s].pid == pid) {
                finish_job(m, c, &slots[s], status, p);
                --running;
                --left;
            }
    }
    free(slots);
    free(order);
    rmdir(tmp);
    return MESO_OK;
}

int batch_run_one(batch_manifest* m, const batch_cache* c, size_t index, int threads, const char* expect_key)
{
    batch_job* job = &m->jobs[index];
    const double t0 = meso_seconds();
    int code = MESO_EXIT_OK;
    if (expect_key && strcmp(expect_key, job->key)) {
        fprintf(stderr,
                "mesobake error: jobs[%zu]: its key here is %s, the submitter's %s: this node's mesobake build or "
                "an input differs from the submitting machine's, so what it bakes would not be what was asked for\n",
                index, job->key[0] ? job->key : "(none: an input cannot be read)", expect_key);
        code = MESO_EXIT_INVALID;
    } else if (!batch_cache_has(c, job->key)) {
        /* Without a key (an input that cannot be read) the bake still runs,
         * into a scratch entry, so that its own error and exit code tell the
         * batch what is wrong; whatever it writes is not kept. */
        const char* key = job->key[0] ? job->key : "unkeyed";
        char* dest = batch_cache_scratch(c, key, ".meso");
        char* report = batch_cache_scratch(c, key, ".json");
        const pid_t pid = dest && report ? batch_spawn(m, job, dest, report, threads, NULL) : -1;
        int status = 0;
        while (pid > 0 && waitpid(pid, &status, 0) < 0 && errno == EINTR) {
        }
        code = pid > 0 ? exit_code_of(status) : MESO_EXIT_INTERNAL;
        meso_error e = {0};
        if (code == MESO_EXIT_OK && !job->key[0]) {
            fprintf(stderr, "mesobake error: jobs[%zu]: an input could not be read to make the cache key\n", index);
            code = MESO_EXIT_IO;
        } else if (code == MESO_EXIT_OK && batch_cache_publish(c, m, job, dest, report, &e) != MESO_OK) {
            fprintf(stderr, "mesobake error: jobs[%zu]: %s\n", index, e.message);
            code = meso_exit_for(e.result);
        }
        if (dest && report) {
            unlink(dest);
            unlink(report);
        }
        free(dest);
        free(report);
    }
    printf("mesobake batch: job %zu exit %d seconds %.3f\n", index, code, meso_seconds() - t0);
    fflush(stdout);
    return code;
}
