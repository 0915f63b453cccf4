/* cli_util.h — mesobake's shared command-line helpers (internal). */
#ifndef MESO_CLI_UTIL_H
#define MESO_CLI_UTIL_H

#include <stddef.h>
#include <stdint.h>

#include "cli_common.h"
#include "cli_output.h"
#include "meso_bake.h"
#include "meso_clock.h"

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
    "            this build (a missing adapter), 8 shell: the shell keeps inverted prisms or\n"                  \
    "            intersections (nothing written but --report; --allow-defects writes it).\n"

/* "mesobake error: ..." on stderr. */
void err_msg(const char* fmt, ...) CLI_PRINTF(1, 2);
/* "mesobake error E<code>: message" (the code is FORMAT.md's issue number
 * or a bake code 31xx, omitted when 0). */
void err_print(const meso_error* err);
/* A usage error: the message, the hint "See 'mesobake --help'.", exit code 1. */
int usage_error(const char* fmt, ...) CLI_PRINTF(1, 2);

/* The progress callback of every bake command (meso_bake_common.progress):
 * under -v each stage's line as "mesobake: LINE" and, on a terminal, a
 * progress bar while directors are traced; always "mesobake warning: ..." */
void cli_progress(void* user, const meso_bake_progress* p);

/* The end of a bake command: on failure (r != MESO_OK) the error; else
 * stage `out` and write the baked file into it, stage the --report file
 * (when `report` is not NULL: the file's report plus "bytes" and
 * "seconds_total", not stored in the .meso file so bakes stay
 * byte-identical) and publish both together (cli_output.h); under -v the
 * line "wrote OUT: N bytes`detail` (T ms total)". On any failure nothing is
 * published. Frees `o`. Returns the exit code. */
int finish_bake(meso_result r, const meso_error* err, meso_bake_output* o, const char* out, const char* report,
                double t0, const char* detail);
struct cJSON;
/* finish_bake with what a command adds: add_report(report, user), when not
 * NULL, adds keys to the --report file only (timings: they are not in the
 * .meso file); with refuse set (a bake that succeeded but must not be
 * written, e.g. a shell with defects) `out` is not written, the --report
 * file is, with "output_written": false, the error is printed and the exit
 * code is refuse_exit. */
typedef struct finish_extra {
    void (*add_report)(struct cJSON* report, const void* user);
    const void* user;
    const meso_error* refuse;
    int refuse_exit;
} finish_extra;
int finish_bake_ex(meso_result r, const meso_error* err, meso_bake_output* o, const char* out, const char* report,
                   double t0, const char* detail, const finish_extra* x);

/* Refuse, before any work, an -o or --report that cannot be replaced
 * (meso_output_check). `report` may be NULL. Returns an exit code. */
int check_outputs(const char* out, const char* report);

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
/* --parts auto|none|N (mesh, shell) into *parts (0, -1, N); 0 after a
 * usage error (its exit code in *code). */
int parts_option(const char* value, int* parts, int* code);
/* The start of every valued option of shell, frusta and cells: 0 after a
 * usage error's exit code in *code (unknown option, missing value); else 1,
 * with *code 0, and *handled 1 when `opt` was a path (-i, -o, --report),
 * --max-memory or --node (into cli_bake_common's slot) and was stored, or 0
 * when the command parses it. */
int bake_option(const char* opt, const char* value, const char* const* valued, size_t count, const char** in,
                const char** out, const char** report, uint64_t* max_memory, int* handled, int* code);
/* Every bake command's meso_bake_common before its options are parsed: the
 * progress callback, and the slot bake_option fills from --node. */
void cli_bake_common(meso_bake_common* c);
/* The --help line of --node, shared by every command that takes a mesh. */
#define NODE_OPTION_HELP \
    "      --node NAME|INDEX   glTF input: only this node and its children (its world\n" \
    "                          transform kept); default: every mesh of the scene\n"
/* The --help line of --max-memory, shared by every bake command. */
#define MEMORY_OPTION_HELP \
    "      --max-memory SIZE   refuse, before allocating, a bake whose memory estimate is larger\n" \
    "                          (512M, 8G, 1.5GiB or bytes; default: half of physical memory)\n"

/* Numbers: meso_bake_parse_positive, meso_bake_parse_long (meso_bake.h). */

int cmd_mesh(int argc, char** argv);
int cmd_shell(int argc, char** argv);
int cmd_frusta(int argc, char** argv);
int cmd_cells(int argc, char** argv);
int cmd_batch(int argc, char** argv);
int cmd_pack(int argc, char** argv);

#endif
