/* batch.h — `mesobake batch`: many bakes from one JSON manifest, each job a
 * `mesobake <command>` process, outputs kept in a content-addressed cache
 * (internal to the mesobake program).
 *
 *   batch_manifest.c  the manifest: jobs, defaults, paths, its errors (E3450..)
 *   batch_key.c       a job's cache key: SHA-256 over what decides its bytes
 *   batch_cache.c     the cache directory: entries, lookups, copies out
 *   batch_local.c     the local engine: a pool of `mesobake` processes
 *   batch_slurm.c     the Slurm engine: job arrays, waited for, retried
 *   cmd_batch.c       the command line, the progress display, the report
 *
 * A job runs exactly the command line a person would type — `mesobake
 * COMMAND -i INPUT -o OUT ARGS` in the manifest's directory — so a batch
 * bake is byte-identical to the single command, whatever engine ran it and
 * with how many threads (rule 7: the output does not depend on --threads).
 */
#ifndef MESO_BATCH_H
#define MESO_BATCH_H

#include <stddef.h>
#include <stdio.h>
#include <sys/types.h>

#include "meso_file.h"

/* Bump whenever a change to the baker can change the bytes of any bake (an
 * algorithm, a default, the format writer): the cache key includes it, so
 * entries of an older baker are never served. tests/integration/batch_cache_version.sh
 * holds known-answer digests of bakes under this number and fails when the
 * bytes change but the number did not. */
#define MESO_BATCH_CACHE_VERSION 26

/* Manifest issue codes (meso_error.code, "E<code>"; exit 3 unless noted):
 *   3450 the manifest cannot be read (exit 2)
 *   3451 not JSON (the message gives line and column)
 *   3452 a field is missing, of the wrong type, or not known
 *   3453 an unknown command
 *   3454 an option the batch sets itself (-i, -o, --report, -j, --threads),
 *        or -h/--help (a job that would bake nothing)
 *   3455 two jobs write the same output
 *   3456 no jobs */
#define BATCH_ISSUE_UNREADABLE 3450u
#define BATCH_ISSUE_JSON 3451u
#define BATCH_ISSUE_FIELD 3452u
#define BATCH_ISSUE_COMMAND 3453u
#define BATCH_ISSUE_OWNED_OPTION 3454u
#define BATCH_ISSUE_DUPLICATE_OUTPUT 3455u
#define BATCH_ISSUE_NO_JOBS 3456u

typedef enum batch_status {
    BATCH_PENDING = 0,
    BATCH_RUNNING,
    BATCH_BAKED,  /* baked by this batch */
    BATCH_CACHED, /* copied from the cache (or the output already held it) */
    BATCH_FAILED
} batch_status;

typedef struct batch_job {
    /* From the manifest. */
    char* name;        /* "name", or the output as written */
    char* command;     /* mesh | shell | cells | frusta */
    char* input;       /* as written: relative to the manifest's directory */
    char* output;      /* as written */
    char* output_path; /* where it goes: absolute */
    char** args;       /* the defaults' args, then the job's */
    size_t arg_count;
    /* Filled in by the batch. */
    char key[65];      /* hex SHA-256 (batch_key.c); "" when it cannot be computed */
    size_t same_as;    /* index of an earlier job with the same key, or (size_t)-1 */
    batch_status status;
    int exit_code;     /* of the last attempt; -1 when it never ran */
    int attempts;
    int threads;       /* --threads given to the bake, 0 when the command takes none */
    double seconds;    /* wall time of the bake (0 for a cache hit) */
    char error[400];   /* why it failed: the bake's last line on stderr, or ours */
    char* report_json; /* the bake's --report, NULL when none */
} batch_job;

typedef struct batch_manifest {
    char* path;     /* as given */
    char* dir;      /* its directory, absolute: every relative path starts here */
    batch_job* jobs;
    size_t count;
} batch_manifest;

/* Read and check a manifest (schema: tools/mesobake/schema/manifest.schema.json).
 * On failure *err names the manifest, the JSON path of the problem
 * ("jobs[3].args[1]") and the issue code above; nothing is allocated. */
meso_result batch_manifest_load(const char* path, batch_manifest* m, meso_error* err);
void batch_manifest_free(batch_manifest* m);
/* first_of[i] = the smallest index whose string equals names[i] (i itself
 * for the first of each); sorted, so O(n log n) for manifests of many
 * thousands of jobs. 0 when out of memory. */
int batch_group_equal(const char* const* names, size_t n, size_t* first_of);
/* Does `command` take --threads? (shell and cells do) */
int batch_command_threaded(const char* command);

/* The cache key of a job, hex SHA-256 into job->key, over: the cache format,
 * mesobake's version, the format version, MESO_BATCH_CACHE_VERSION, the
 * machine architecture, the command, the input as written, every argument except those that cannot
 * change the bytes (-v, --verbose, --max-memory N), and the SHA-256 of the
 * contents of the input and of every file an argument names (an argument, or
 * a ':'-separated part of one such as height:FILE.png, that is a regular
 * file relative to the manifest's directory). Content, not time stamps: a
 * touched file keeps its key, a changed byte does not. A missing input
 * leaves job->key empty (the bake then fails and says why). */
meso_result batch_job_key(const batch_manifest* m, batch_job* job, meso_error* err);

/* The cache: DIR/v1/<first two hex digits>/<key>.meso and <key>.json. */
typedef struct batch_cache {
    char* dir; /* absolute; NULL = no cache (--no-cache) */
} batch_cache;

/* The default directory: $MESO_CACHE_DIR, else $XDG_CACHE_HOME/meso, else
 * $HOME/.cache/meso. Returns a malloc'd path, or NULL when none is known. */
char* batch_cache_default_dir(void);
/* Create `dir` (and its parents) and make it absolute. */
meso_result batch_cache_open(batch_cache* c, const char* dir, meso_error* err);
void batch_cache_close(batch_cache* c);
/* malloc'd path of `key`'s entry with `ext` (".meso" or ".json"); creates
 * the entry's directory when `create`. */
char* batch_cache_entry(const batch_cache* c, const char* key, const char* ext, int create);
/* 1 when the entry of `key` exists and passes MESO_CHECK_FULL (an entry
 * damaged on disk is a miss: it is baked again and replaced). */
int batch_cache_has(const batch_cache* c, const char* key);
/* The job's output from its cache entry: left alone when it already holds
 * the same bytes (no new time stamp for a build system to chase), else
 * written atomically (cli_output.h). Creates the output's directory.
 * Also reads the entry's report into job->report_json. */
meso_result batch_cache_copy_out(const batch_cache* c, batch_job* job, meso_error* err);

/* A scratch path beside `key`'s entry, unique in this process (malloc'd). */
char* batch_cache_scratch(const batch_cache* c, const char* key, const char* ext);
/* After a successful bake into the scratch files: compute the job's key
 * again and, only if the inputs still give the same key, rename the scratch
 * report and file into the entry. Otherwise (an input changed while it was
 * baked) MESO_ERR_IO, and nothing is kept. The scratch files are gone
 * either way. */
meso_result batch_cache_publish(const batch_cache* c, const batch_manifest* m, batch_job* job,
                                const char* scratch_meso, const char* scratch_json, meso_error* err);
/* Create the directories above `path` (mkdir -p of its dirname). */
meso_result batch_mkdir_parents(const char* path, meso_error* err);
/* Read a whole file (NUL-terminated); NULL on failure. */
char* batch_read_file(const char* path, size_t* size);
/* The last non-empty line of a log file into `line` (for error messages). */
void batch_last_line(const char* path, char* line, size_t size);

/* Start a bake of `job` as a child process, in the manifest's directory:
 * `mesobake COMMAND -i INPUT -o DEST --report REPORT ARGS [--threads T]`
 * with stdout and stderr appended to `log_path`. Returns its pid, or -1
 * with errno set. */
pid_t batch_spawn(const batch_manifest* m, const batch_job* job, const char* dest, const char* report,
                  int threads, const char* log_path);
/* The running executable's path (for the children and Slurm tasks). */
const char* batch_self_exe(void);

/* What the engines report as jobs finish (cmd_batch.c prints it). */
typedef struct batch_progress {
    size_t total, baked, cached, failed, running;
    int tty; /* redraw one line in place */
} batch_progress;
void batch_progress_job(batch_progress* p, const batch_job* job);
void batch_progress_draw(const batch_progress* p);

typedef struct batch_options {
    int jobs;            /* -j: bakes at once (local) */
    int cpus;            /* cores on this machine */
    const char* engine;  /* "local" or "slurm" */
    const char* partition;
    int max_parallel;    /* Slurm: %K of the array, 0 = no limit */
    int retries;         /* Slurm: extra attempts for a task that failed for a reason other than its input */
    int cpus_per_task;   /* Slurm: --cpus-per-task, and the bake's --threads */
} batch_options;

/* Bake the jobs whose status is BATCH_PENDING, until each is BATCH_BAKED
 * (copied out), BATCH_CACHED or BATCH_FAILED. Returns MESO_OK unless the
 * engine itself failed (then *err says why and pending jobs stay failed). */
meso_result batch_run_local(batch_manifest* m, const batch_cache* c, const batch_options* o, batch_progress* p,
                            meso_error* err);
meso_result batch_run_slurm(batch_manifest* m, const batch_cache* c, const batch_options* o, batch_progress* p,
                            meso_error* err);
/* One job of a Slurm array (--run-job I): bake job `index` into the cache
 * unless it is there. With `expect_key` (--expect-key, the submitter's key
 * of the job) a different key here is refused, exit 3: a node whose build
 * or inputs differ must not publish under the submitter's name. Prints
 * "mesobake batch: job I exit N seconds S". Returns the exit code. */
int batch_run_one(batch_manifest* m, const batch_cache* c, size_t index, int threads, const char* expect_key);
/* Is a failed bake's exit code worth another attempt? (Not when the input
 * or the command line is wrong: 1, 3, 5; those fail the same way again.) */
int batch_retryable(int exit_code);

#endif
