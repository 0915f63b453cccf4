/*
 * cmd_batch.c — `mesobake batch MANIFEST`: every job of a JSON manifest
 * baked, in parallel, through a content-addressed cache, locally or on a
 * Slurm cluster (batch.h says which file does what). This file is the
 * command line, the progress display, the summary and the JSON report.
 */
#define _GNU_SOURCE /* sched_getaffinity, CPU_COUNT */
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "batch.h"
#include "cli_util.h"

static const char* const usage_batch =
    "Usage: mesobake batch MANIFEST.json [options]\n"
    "\n"
    "Bake every job of a manifest. Each job is the command line a person would type,\n"
    "`mesobake COMMAND -i INPUT -o OUTPUT ARGS`, run in the manifest's directory, so its\n"
    "output is byte-identical to that command's. Outputs come from a cache keyed by the\n"
    "SHA-256 of the input bytes (and of every file an argument names), the options that\n"
    "change the bytes and the baker's version: an unchanged job is a copy, a changed\n"
    "input or option re-bakes only its own jobs, and an output that already holds the\n"
    "right bytes is not rewritten. One failing job does not stop the others.\n"
    "\n"
    "Manifest (schema: tools/mesobake/schema/manifest.schema.json; paths relative to it):\n"
    "  {\"defaults\": {\"command\": \"shell\", \"args\": [\"--thickness-rel\", \"0.05\"]},\n"
    "   \"jobs\": [{\"name\": \"rock\", \"input\": \"rock.obj\", \"output\": \"out/rock.meso\",\n"
    "             \"args\": [\"--texture\", \"cobble\"]},\n"
    "            {\"command\": \"frusta\", \"input\": \"tree.swc\", \"output\": \"out/tree.meso\"}]}\n"
    "  A job's args follow the defaults' args; -i, -o, --report and --threads are the batch's.\n"
    "\n"
    "Options:\n"
    "  -j, --jobs N            bakes at once (default: the cores this process may use); each\n"
    "                          bake gets, when it starts, those cores divided among the bakes\n"
    "                          that can still run at once\n"
    "      --cache DIR         the cache (default: $MESO_CACHE_DIR, else $XDG_CACHE_HOME/meso,\n"
    "                          else ~/.cache/meso); safe to share between batches, and between\n"
    "                          machines that run the same build (the key names it)\n"
    "      --no-cache          bake every job straight to its output\n"
    "      --report FILE       the batch report as JSON: jobs_baked, jobs_cached, jobs_failed,\n"
    "                          seconds, cpu_busy and one entry per job with its bake report\n"
    "      --engine E          local (default; needs nothing installed) or slurm: the\n"
    "                          uncached jobs as a Slurm job array (sbatch --wait --array; split\n"
    "                          at the cluster's MaxArraySize), results through the cache,\n"
    "                          which the nodes must share\n"
    "      --partition P       slurm: the partition to submit to (default: the cluster's)\n"
    "      --max-parallel K    slurm: at most K array tasks at once (--array=...%K)\n"
    "      --cpus-per-task C   slurm: cores per task, and the bake's --threads (default 1)\n"
    "      --retries N         slurm: submit a task again up to N times when it may succeed\n"
    "                          another time: killed, its node lost, an I/O error (exit 2, e.g. a\n"
    "                          file not yet visible on a shared file system), exit 4; never\n"
    "                          after 1, 3 or 5, which fail the same way again (default 2)\n"
    "      --run-job J         bake job J (0-based) into the cache and exit: what a Slurm\n"
    "                          array task runs; --threads T gives its threads, --expect-key K\n"
    "                          refuses (exit 3) when this machine computes another key for J\n"
    "  -v, --verbose           a line for every job, cached ones too\n"
    "  -h, --help              this help\n"
    "\n"
    "Exit codes: 0 every job succeeded, 6 at least one job failed (the report and the\n"
    "lines above the summary say which and why); otherwise as for every command: 1\n"
    "command-line error, 2 I/O failure (an unreadable manifest, E3450), 3 invalid manifest\n"
    "(E3451..E3456), 4 internal error, 5 --engine slurm without sbatch.\n";

static int verbose_jobs;

static const char* status_word(batch_status s)
{
    switch (s) {
    case BATCH_BAKED: return "baked";
    case BATCH_CACHED: return "cached";
    case BATCH_FAILED: return "failed";
    case BATCH_RUNNING: return "running";
    default: return "pending";
    }
}

void batch_progress_draw(const batch_progress* p)
{
    if (!p->tty)
        return;
    const size_t done = p->baked + p->cached + p->failed;
    const int width = 24, filled = p->total ? (int)(width * done / p->total) : width;
    fprintf(stderr, "\r\033[Kmesobake batch: [%.*s%*s] %zu/%zu  baked %zu  cached %zu  failed %zu  running %zu",
            filled, "########################", width - filled, "", done, p->total, p->baked, p->cached, p->failed,
            p->running);
    fflush(stderr);
}

void batch_progress_job(batch_progress* p, const batch_job* job)
{
    p->baked += job->status == BATCH_BAKED;
    p->cached += job->status == BATCH_CACHED;
    p->failed += job->status == BATCH_FAILED;
    const size_t done = p->baked + p->cached + p->failed;
    if (job->status != BATCH_CACHED || verbose_jobs) {
        if (p->tty)
            fputs("\r\033[K", stderr);
        if (job->status == BATCH_FAILED)
            fprintf(stderr, "mesobake batch: [%zu/%zu] FAILED %s (exit %d): %s\n", done, p->total, job->name,
                    job->exit_code, job->error);
        else if (job->status == BATCH_BAKED)
            fprintf(stderr, "mesobake batch: [%zu/%zu] baked %s (%.1f s)\n", done, p->total, job->name, job->seconds);
        else
            fprintf(stderr, "mesobake batch: [%zu/%zu] cached %s\n", done, p->total, job->name);
    }
    batch_progress_draw(p);
}

/* The batch report (--report): totals, then one entry per job. */
static char* report_json(const batch_manifest* m, const batch_cache* c, const batch_options* o,
                         const batch_progress* p, double seconds, double cpu_seconds)
{
    cJSON* r = cJSON_CreateObject();
    cJSON_AddStringToObject(r, "tool", "mesobake batch");
    cJSON_AddStringToObject(r, "version", MESO_VERSION_STRING);
    cJSON_AddStringToObject(r, "manifest", m->path);
    cJSON_AddStringToObject(r, "engine", o->engine);
    if (c->dir)
        cJSON_AddStringToObject(r, "cache", c->dir);
    else
        cJSON_AddNullToObject(r, "cache");
    cJSON_AddNumberToObject(r, "parallel_jobs", o->jobs);
    cJSON_AddNumberToObject(r, "jobs_total", (double)m->count);
    cJSON_AddNumberToObject(r, "jobs_baked", (double)p->baked);
    cJSON_AddNumberToObject(r, "jobs_cached", (double)p->cached);
    cJSON_AddNumberToObject(r, "jobs_failed", (double)p->failed);
    cJSON_AddNumberToObject(r, "seconds", seconds);
    cJSON_AddNumberToObject(r, "cpu_seconds", cpu_seconds);
    cJSON_AddNumberToObject(r, "cpus", o->cpus);
    cJSON_AddNumberToObject(r, "cpu_busy", seconds > 0 ? cpu_seconds / (seconds * o->cpus) : 0);
    cJSON* jobs = cJSON_AddArrayToObject(r, "jobs");
    for (size_t i = 0; i < m->count; ++i) {
        const batch_job* j = &m->jobs[i];
        cJSON* e = cJSON_CreateObject();
        cJSON_AddStringToObject(e, "name", j->name);
        cJSON_AddStringToObject(e, "command", j->command);
        cJSON_AddStringToObject(e, "input", j->input);
        cJSON_AddStringToObject(e, "output", j->output);
        cJSON_AddStringToObject(e, "status", status_word(j->status));
        if (j->key[0])
            cJSON_AddStringToObject(e, "key", j->key);
        else
            cJSON_AddNullToObject(e, "key");
        cJSON_AddNumberToObject(e, "exit_code", j->exit_code);
        cJSON_AddNumberToObject(e, "attempts", j->attempts);
        cJSON_AddNumberToObject(e, "threads", j->threads);
        cJSON_AddNumberToObject(e, "seconds", j->seconds);
        if (j->status == BATCH_FAILED)
            cJSON_AddStringToObject(e, "error", j->error);
        cJSON* bake = j->report_json ? cJSON_Parse(j->report_json) : NULL;
        if (bake)
            cJSON_AddItemToObject(e, "report", bake);
        cJSON_AddItemToArray(jobs, e);
    }
    char* s = cJSON_Print(r);
    cJSON_Delete(r);
    return s;
}

static int write_report(const char* path, char* json)
{
    meso_error err = {0};
    meso_output* o = NULL;
    const size_t n = json ? strlen(json) : 0;
    meso_result r = json ? cli_output_stage(path, &o, &err) : MESO_ERR_OUT_OF_MEMORY;
    if (r == MESO_OK) {
        json[n] = '\n'; /* the terminator becomes the final newline */
        r = meso_output_write(o, json, n + 1, &err);
    }
    r = r == MESO_OK ? cli_outputs_publish(&err) : (cli_outputs_discard(), r);
    cJSON_free(json);
    if (r == MESO_OK)
        return MESO_EXIT_OK;
    if (err.message[0])
        err_print(&err);
    else
        err_msg("%s: cannot write the report: out of memory", path);
    return meso_exit_for(r);
}

/* Jobs with the key of an earlier job: copied from the cache once that one is. */
static void finish_duplicates(batch_manifest* m, const batch_cache* c, batch_progress* p)
{
    for (size_t i = 0; i < m->count; ++i) {
        batch_job* j = &m->jobs[i];
        if (j->same_as == (size_t)-1 || j->status != BATCH_PENDING)
            continue;
        const batch_job* first = &m->jobs[j->same_as];
        meso_error e = {0};
        if (!batch_cache_has(c, j->key)) /* (the first may have failed only in its own copy-out) */
            snprintf(j->error, sizeof j->error, "the same bake as %s, which failed", first->name);
        else if (batch_cache_copy_out(c, j, &e) != MESO_OK)
            snprintf(j->error, sizeof j->error, "%s", e.message);
        j->exit_code = j->error[0] && first->exit_code == 0 ? MESO_EXIT_IO : first->exit_code;
        j->status = j->error[0] ? BATCH_FAILED : BATCH_CACHED;
        batch_progress_job(p, j);
    }
}

/* Keys, cache hits, and which jobs repeat an earlier one. */
static void look_up(batch_manifest* m, const batch_cache* c, batch_progress* p)
{
    const char** keys = calloc(m->count ? m->count : 1, sizeof *keys);
    size_t* first_of = calloc(m->count ? m->count : 1, sizeof *first_of);
    for (size_t i = 0; i < m->count; ++i) {
        batch_job* j = &m->jobs[i];
        meso_error e = {0};
        /* An output that is there but cannot be replaced (a directory, a
         * FIFO, a dangling link) is refused before its bake runs. */
        struct stat st;
        if (lstat(j->output_path, &st) == 0 && meso_output_check(j->output_path, &e) != MESO_OK) {
            j->status = BATCH_FAILED;
            j->exit_code = MESO_EXIT_IO;
            snprintf(j->error, sizeof j->error, "%s", e.message);
            batch_progress_job(p, j);
            continue;
        }
        if (c->dir)
            batch_job_key(m, j, &e);
    }
    /* Jobs with the same key bake once (sorted: fine for many thousands). */
    for (size_t i = 0; i < m->count && keys; ++i)
        keys[i] = m->jobs[i].status == BATCH_PENDING && m->jobs[i].key[0] ? m->jobs[i].key : "";
    const int grouped = keys && first_of && batch_group_equal(keys, m->count, first_of);
    for (size_t i = 0; i < m->count; ++i) {
        batch_job* j = &m->jobs[i];
        meso_error e = {0};
        if (j->status != BATCH_PENDING || !j->key[0])
            continue;
        if (grouped && first_of[i] != i)
            j->same_as = first_of[i];
        if (j->same_as != (size_t)-1 || !batch_cache_has(c, j->key))
            continue;
        if (batch_cache_copy_out(c, j, &e) == MESO_OK) {
            j->status = BATCH_CACHED;
            j->exit_code = 0;
        } else {
            j->status = BATCH_FAILED;
            j->exit_code = MESO_EXIT_IO;
            snprintf(j->error, sizeof j->error, "%s", e.message);
        }
        batch_progress_job(p, j);
    }
    free(keys);
    free(first_of);
}

/* The cores this process may run on (its affinity mask: taskset, a Slurm
 * allocation, a container's cpuset), not every core of the machine. */
static int usable_cpus(void)
{
#ifdef CPU_COUNT
    cpu_set_t set;
    if (sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) > 0)
        return CPU_COUNT(&set);
#endif
    const long online = sysconf(_SC_NPROCESSORS_ONLN);
    return online > 0 ? (int)online : 1;
}

static int parse_count(const char* opt, const char* v, int lo, int* out)
{
    const long hi = !strcmp(opt, "--run-job") ? 1000000000L : 4096;
    long n = 0;
    if (!meso_bake_parse_long(v, lo, hi, &n))
        return usage_error("%s expects a whole number in %d..%ld, got '%s'", opt, lo, hi, v);
    *out = (int)n;
    return 0;
}

int cmd_batch(int argc, char** argv)
{
    batch_options o = {.jobs = 0, .cpus = usable_cpus(), .engine = "local", .retries = 2,
                       .cpus_per_task = 1};
    const char *manifest = NULL, *cache_dir = NULL, *report = NULL, *expect_key = NULL;
    int no_cache = 0, run_job = -1, threads = 0, code = 0;
    for (int i = 0; i < argc && !code; ++i) {
        const char* s = argv[i];
        const char* v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(s, "-h") || !strcmp(s, "--help")) {
            fputs(usage_batch, stdout);
            return MESO_EXIT_OK;
        } else if (!strcmp(s, "-v") || !strcmp(s, "--verbose")) {
            verbose_jobs = 1;
        } else if (!strcmp(s, "--no-cache")) {
            no_cache = 1;
        } else if (s[0] != '-' && !manifest) {
            manifest = s;
        } else {
            static const char* const valued[] = {"-j", "--jobs", "--cache", "--report", "--engine", "--partition",
                "--max-parallel", "--cpus-per-task", "--retries", "--run-job", "--threads", "--expect-key"};
            if ((code = option_value(s, v, valued, sizeof valued / sizeof valued[0])) != 0)
                break;
            ++i;
            if (!strcmp(s, "-j") || !strcmp(s, "--jobs"))
                code = parse_count(s, v, 1, &o.jobs);
            else if (!strcmp(s, "--cache"))
                cache_dir = v;
            else if (!strcmp(s, "--report"))
                report = v;
            else if (!strcmp(s, "--engine")) {
                if (strcmp(v, "local") && strcmp(v, "slurm"))
                    code = usage_error("--engine expects local or slurm, got '%s'", v);
                o.engine = v;
            } else if (!strcmp(s, "--partition"))
                o.partition = v;
            else if (!strcmp(s, "--max-parallel"))
                code = parse_count(s, v, 1, &o.max_parallel);
            else if (!strcmp(s, "--cpus-per-task"))
                code = parse_count(s, v, 1, &o.cpus_per_task);
            else if (!strcmp(s, "--retries"))
                code = parse_count(s, v, 0, &o.retries);
            else if (!strcmp(s, "--run-job"))
                code = parse_count(s, v, 0, &run_job);
            else if (!strcmp(s, "--expect-key"))
                expect_key = v;
            else
                code = parse_count(s, v, 1, &threads);
        }
    }
    if (code)
        return code;
    if (!manifest)
        return usage_error("batch needs a manifest: mesobake batch MANIFEST.json");
    if (no_cache && (cache_dir || run_job >= 0 || !strcmp(o.engine, "slurm")))
        return usage_error("--no-cache cannot go with --cache, --run-job or --engine slurm (Slurm tasks hand their "
                           "results back through the cache)");
    if (report && (code = check_outputs(report, NULL)) != 0)
        return code;
    if (o.jobs == 0)
        o.jobs = o.cpus;

    const double t0 = meso_seconds();
    meso_error err = {0};
    batch_manifest m;
    meso_result r = batch_manifest_load(manifest, &m, &err);
    if (r != MESO_OK) {
        err_print(&err);
        return meso_exit_for(r);
    }
    batch_cache c = {0};
    char* default_dir = no_cache || cache_dir ? NULL : batch_cache_default_dir();
    if (!no_cache && !cache_dir && !default_dir)
        r = meso_bake_fail(&err, MESO_ERR_INVALID_ARG, 0, "no cache directory: set --cache DIR, $MESO_CACHE_DIR or $HOME");
    if (r == MESO_OK && !no_cache)
        r = batch_cache_open(&c, cache_dir ? cache_dir : default_dir, &err);
    free(default_dir);
    if (r == MESO_OK && run_job >= 0 && (size_t)run_job >= m.count)
        r = meso_bake_fail(&err, MESO_ERR_INVALID_ARG, 0, "--run-job %d: the manifest has %zu jobs", run_job, m.count);
    if (r != MESO_OK) {
        err_print(&err);
        batch_manifest_free(&m);
        batch_cache_close(&c);
        return meso_exit_for(r);
    }
    if (run_job >= 0) { /* a Slurm array task */
        batch_job_key(&m, &m.jobs[run_job], &err);
        code = batch_run_one(&m, &c, (size_t)run_job, threads > 0 ? threads : 1, expect_key);
        batch_manifest_free(&m);
        batch_cache_close(&c);
        return code;
    }

    batch_progress p = {.total = m.count, .tty = isatty(2)};
    look_up(&m, &c, &p);
    r = !strcmp(o.engine, "slurm") ? batch_run_slurm(&m, &c, &o, &p, &err) : batch_run_local(&m, &c, &o, &p, &err);
    if (r != MESO_OK)
        err_print(&err);
    for (size_t i = 0; i < m.count; ++i) /* what an engine that failed left behind */
        if (m.jobs[i].same_as == (size_t)-1 && (m.jobs[i].status == BATCH_PENDING || m.jobs[i].status == BATCH_RUNNING)) {
            m.jobs[i].status = BATCH_FAILED;
            snprintf(m.jobs[i].error, sizeof m.jobs[i].error, "not baked: %s", err.message);
            batch_progress_job(&p, &m.jobs[i]);
        }
    finish_duplicates(&m, &c, &p);

    const double seconds = meso_seconds() - t0;
    struct rusage ru;
    getrusage(RUSAGE_CHILDREN, &ru);
    const double cpu = (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec + (double)ru.ru_stime.tv_sec +
                       1e-6 * (double)ru.ru_stime.tv_usec;
    if (p.tty)
        fputs("\r\033[K", stderr);
    fprintf(stderr, "mesobake batch: %zu jobs: %zu baked, %zu cached, %zu failed in %.2f s", m.count, p.baked,
            p.cached, p.failed, seconds);
    if (!strcmp(o.engine, "local"))
        fprintf(stderr, " (bakes used %.1f cpu s: %.0f%% of %d cores)", cpu, 100 * cpu / (seconds * o.cpus), o.cpus);
    fputc('\n', stderr);
    code = r != MESO_OK ? meso_exit_for(r) : p.failed ? MESO_EXIT_JOBS_FAILED : MESO_EXIT_OK;
    if (report) {
        const int rc = write_report(report, report_json(&m, &c, &o, &p, seconds, cpu));
        if (rc && !code)
            code = rc;
    }
    batch_manifest_free(&m);
    batch_cache_close(&c);
    return code;
}
