/*
 * inspect.h — internal to mesoinspect: one file per command (info.c,
 * validate.c, dump.c, diff.c, preview.c, export.c) and the helpers they share
 * (main.c). CLI conventions: STYLE.md §8, exit codes in cli_common.h.
 */
#ifndef MESO_INSPECT_H
#define MESO_INSPECT_H

#include <cjson/cJSON.h>
#include <stddef.h>
#include <stdint.h>

#include "cli_common.h"
#include "meso_file.h"

/* Commands: argc/argv after the command word. Each returns an exit code. */
int mesoinspect_info(int argc, char** argv);
int mesoinspect_validate(int argc, char** argv);
int mesoinspect_dump(int argc, char** argv);
int mesoinspect_diff(int argc, char** argv);
int mesoinspect_preview(int argc, char** argv); /* preview.c */
int mesoinspect_export(int argc, char** argv);  /* export.c */

/* >>diagnostics ----------------------------------------------------------- */

#if defined(__GNUC__)
#define MI_PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define MI_PRINTF(a, b)
#endif

/* "mesoinspect error: ..." / "mesoinspect warning: ..." on stderr. */
void mi_error(const char* fmt, ...) MI_PRINTF(1, 2);
void mi_warning(const char* fmt, ...) MI_PRINTF(1, 2);
/* One line plus "See 'mesoinspect --help'." on stderr; returns MESO_EXIT_USAGE. */
int mi_usage_error(const char* fmt, ...) MI_PRINTF(1, 2);

/* >>options --------------------------------------------------------------- */

typedef enum mi_format { MI_FORMAT_TEXT = 0, MI_FORMAT_JSON, MI_FORMAT_MINI_JSON } mi_format;

/* Handle `--format X` / `--format=X` at argv[*i]. Returns 1 when consumed
 * (*i advanced past the value), 0 when argv[*i] is not --format, and -1 after
 * printing a usage error. */
int mi_format_option(int argc, char** argv, int* i, mi_format* out);
/* Is `a` -h or --help? */
int mi_is_help(const char* a);

/* >>files ----------------------------------------------------------------- */

/* Open with the runtime's parser (memory-mapped, cheap checks) and the
 * baker's Draco decoder when this build has one. */
meso_result mi_open(const char* path, meso_file** out, meso_error* err);
/* mi_open; on failure print "mesoinspect error: PATH: error CODE at offset
 * N: message" and return the exit code (0 on success). */
int mi_open_or_report(const char* path, meso_file** out);
/* Text form of a coded error: "error 3001 at offset 128 (chunk 1): msg". */
void mi_format_issue(const meso_error* e, char* dst, size_t dst_size);

/* Stored bytes of chunk `index` without any check (zero-copy, mmap), NULL when
 * unavailable. */
const uint8_t* mi_stored(const meso_file* f, uint32_t index);
/* Decoded bytes of chunk `index` in a malloc'd buffer (free() it), checked
 * like the runtime reads them (CRC, decoder, contents). */
meso_result mi_read_decoded(meso_file* f, uint32_t index, uint8_t** out, size_t* size, meso_error* err);

/* >>objects --------------------------------------------------------------- */

/* Every OBJT record of `f` (malloc'd, *count of them; a file without OBJT has
 * none). NULL and a message on stderr when the table cannot be read (*r
 * says why). */
meso_object_record* mi_all_records(meso_file* f, uint32_t* count, meso_result* r);
/* The value of --object: all digits is an id (*id, 1..2^32-1), anything
 * else a name of 1..31 bytes (*name = v). Returns 0, or prints a usage
 * error and returns its exit code. */
int mi_object_option(const char* v, unsigned long* id, const char** name);
/* The id of the object named `name` in `path` (already validated): exit 0,
 * or a usage error naming the file's objects when none has that name. */
int mi_object_by_name(const char* path, const char* name, unsigned long* id);

/* >>validation ------------------------------------------------------------ */

/* The full check before a command uses a file, so nothing downstream ever
 * sees a file the validator refuses: every issue is listed on stderr as
 * `validate --full` lists them, then "N issues; not <not_what>"; exit 3
 * (2 on a read failure), 0 when the file is clean. */
int mi_validate_full(const char* path, const char* not_what);

/* >>names ----------------------------------------------------------------- */

/* Four characters; bytes outside 0x20..0x7E become '?'. */
void mi_fourcc(uint32_t type, char out[5]);
const char* mi_encoding_name(uint32_t encoding); /* "raw", "draco", "unknown" */
const char* mi_dtype_name(uint32_t dtype);       /* "bytes", "u8", ... "f32", "unknown" */
const char* mi_kind_name(uint32_t kind);         /* "mesh", "shell", ... "unknown" */
const char* mi_result_id(meso_result r);         /* "corrupt", "truncated", ... (stable) */
const char* mi_issue_name(uint32_t code);        /* "PAYLOAD_CRC", ... or NULL */
/* "TYPE:object:lod", the dump command's chunk spec. */
void mi_chunk_label(const meso_chunk_info* c, char* dst, size_t dst_size);

/* >>MESH header ----------------------------------------------------------- */

typedef struct mi_mesh_stats {
    uint32_t vertex_count;
    uint32_t index_count;
    uint32_t attributes;
    uint8_t quant_bits[3]; /* position, normal, uv */
} mi_mesh_stats;

/* Counts from the 64-byte MESH header at the start of a stored payload (the
 * same header for raw and Draco chunks). 0 when n < 64. */
int mi_mesh_header(const uint8_t* p, size_t n, mi_mesh_stats* out);
cJSON* mi_mesh_stats_json(const mi_mesh_stats* s);

/* >>output ---------------------------------------------------------------- */

/* Print `doc` to stdout (formatted or compact) and a newline. */
void mi_print_json(const cJSON* doc, mi_format fmt);
/* Flush stdout; on a write failure print an error and return MESO_EXIT_IO,
 * else `code`. */
int mi_finish_stdout(int code);

/* Output files (dump -o, preview -o) go through staged outputs
 * (tools/common/cli_output.h): refused unless a regular file or a symbolic link to
 * one, written beside the destination, renamed into place when complete.
 * Each of these prints the error and returns the exit code (0 on success);
 * a failure discards every staged output. */
int mi_check_output(const char* path);
int mi_stage_output(const char* path, meso_output** out);
int mi_publish_outputs(void);
int mi_output_failed(const meso_error* e, meso_result r);

/* A text table with columns sized to their widest cell. */
typedef struct mi_table {
    int cols;
    int rows;
    int cap;
    char** cells;          /* rows x cols, malloc'd strings */
    unsigned right_align;  /* bit c: column c is right-aligned */
} mi_table;

void mi_table_init(mi_table* t, int cols, unsigned right_align);
/* Append a row of `cols` cells. */
void mi_table_row(mi_table* t, const char* const* cells);
/* Print every row with `indent` leading spaces and two spaces between columns. */
void mi_table_print(const mi_table* t, int indent);
void mi_table_free(mi_table* t);

#endif
