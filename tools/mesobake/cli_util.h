/* cli_util.h — mesobake's shared command-line helpers (internal). */
#ifndef MESO_CLI_UTIL_H
#define MESO_CLI_UTIL_H

#include <stddef.h>
#include <stdint.h>

#include "cli_common.h"
#include "cli_output.h"
#include "meso_clock.h"
#include "meso_bake.h"

#if defined(__GNUC__)
#define CLI_PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define CLI_PRINTF(a, b)
#endif

extern int verbose; /* -v: one line per stage on stderr */

/* `usage` on stdout, then the exit codes (README "Exit codes"): every
 * command's --help. */
void print_help(const char* usage);
#define MESOBAKE_HELP_EXIT_CODES                                                                                 \
    "Exit codes: 0 success, 1 command-line error, 2 I/O failure, 3 invalid input file\n"                        \
    "            (mesh, skeleton, texture, volume), 4 internal error, 5 not supported in\n"                      \
    "            this build (a missing adapter).\n"

/* "mesobake error: ..." on stderr. */
void err_msg(const char* fmt, ...) CLI_PRINTF(1, 2);
/* "mesobake error E<code>: message" (the code is FORMAT.md's issue number
 * or a bake code 31xx, omitted when 0). */
void err_print(const meso_error* err);
/* A usage error: the message, the hint "See 'mesobake --help'.", exit code 1. */
int usage_error(const char* fmt, ...) CLI_PRINTF(1, 2);

const char* base_name(const char* path);
int has_suffix(const char* s, const char* suffix);
/* Read a whole file (provenance checksums, .drc input). */
meso_result slurp(const char* path, uint8_t** data, size_t* size, meso_error* err);
/* Load a mesh by extension: its bytes through the guard (bake/mesh_guard.h,
 * with `max_memory` — the --max-memory budget, 0 = the guard's default — as
 * the bound on what its header counts may make a reader allocate), then
 * OpenMesh or Draco; then check it (finite coordinates, indices in range,
 * nothing the reader had to drop) and turn inside-out closed components
 * outward (bake/mesh_orient.h). */
meso_result load_mesh(const char* path, uint64_t max_memory, meso_mesh* m, meso_error* err);

typedef struct cJSON cJSON;
/* Adds what load_mesh changed in the input (inside-out components it
 * flipped: "reoriented_components" and a "warnings" array) to a bake
 * report; adds nothing when it changed nothing. */
void report_mesh_warnings(cJSON* report);

/* >>output ---------------------------------------------------------------- */

typedef struct cJSON cJSON;

/* Append {"name", "bytes", "crc32c"} of an input file to a META "inputs"
 * array: enough to tell which file an asset was baked from. */
meso_result add_input_provenance(cJSON* inputs, const char* path, meso_error* err);

typedef struct bake_chunk {
    meso_chunk_desc desc;
    const void* data;
    size_t size;
} bake_chunk;

/* Write META, RPRT, the one-object OBJT and `chunks` into a staged output
 * for `out` (cli_output.h; deterministic: the JSON holds no timings).
 * *file_size gets the size. Nothing is published until publish_outputs. */
meso_result write_meso(const char* out, const cJSON* meta, const cJSON* report, const meso_object_record* object,
                       const bake_chunk* chunks, int count, size_t* file_size, meso_error* err);

/* Stage the --report file (when `report_path` is not NULL: the report plus
 * "bytes" and "seconds_total", not stored in the .meso file so bakes stay
 * byte-identical), then publish every staged output; on any failure nothing
 * is published. Returns an exit code. */
int publish_outputs(const char* report_path, cJSON* report, size_t file_size, double seconds);

/* Refuse, before any work, an -o or --report that cannot be replaced
 * (meso_output_check). `report` may be NULL. Returns an exit code. */
int check_outputs(const char* out, const char* report);

/* The end of a bake command: under -v the "wrote OUT" line, then the error
 * (r != MESO_OK) or the --report file (report != NULL). Returns the exit code. */
int finish_bake(meso_result r, const meso_error* err, const char* out, const char* report, cJSON* rep,
                size_t file_size, double t0);

/* An option that takes a value: 0 when `opt` is one of the `count` names in
 * `valued` and `value` is not NULL, else the usage error's exit code
 * (unrecognized option, unexpected argument, or a missing value). */
int option_value(const char* opt, const char* value, const char* const* valued, size_t count);

/* The paths every bake command takes: 1 when `opt` is -i/--input,
 * -o/--output or --report, with `value` stored in its place; else 0. */
int path_option(const char* opt, const char* value, const char** in, const char** out, const char** report);

/* --max-memory SIZE (memory_budget.h): 1 when `opt` is --max-memory, with
 * `value` parsed into *budget, or *bad set to the usage error's exit code
 * when it does not parse; else 0. */
int memory_option(const char* opt, const char* value, uint64_t* budget, int* bad);
/* The --help line of --max-memory, shared by every bake command. */
#define MEMORY_OPTION_HELP \
    "      --max-memory SIZE   refuse, before allocating, a bake whose memory estimate is larger\n" \
    "                          (512M, 8G, 1.5GiB or bytes; default: half of physical memory)\n"

/* Parse a positive finite number; 0 on failure. */
int parse_double(const char* s, double* out);
int parse_int(const char* s, long lo, long hi, long* out);

int cmd_mesh(int argc, char** argv);
int cmd_shell(int argc, char** argv);
int cmd_frusta(int argc, char** argv);
int cmd_cells(int argc, char** argv);

#endif
