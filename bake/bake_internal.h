/*
 * bake_internal.h — what the pipeline files behind meso_bake.h share
 * (bake_output.c, bake_load.c, bake_mesh.c, bake_shell*.c, bake_cells.c,
 * bake_frusta.c): one bake's progress reporting, the .meso file builder,
 * the JSON pieces every bake's META and report have, input loading. Not
 * installed; nothing here is exported from the shared library.
 */
#ifndef MESO_BAKE_INTERNAL_H
#define MESO_BAKE_INTERNAL_H

#include <stdint.h>

#include "meso_bake.h"

#if defined(__GNUC__)
#define MESOI_PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define MESOI_PRINTF(a, b)
#endif

typedef struct cJSON cJSON;

/* >>run: one bake's progress --------------------------------------------------- */

typedef struct mesoi_bake_run {
    meso_bake_common common; /* the caller's, max_memory resolved (never 0) */
    double t0;               /* meso_seconds() when the bake started: the "(N ms)" of stage lines */
    double fraction;         /* the last fraction reported (they never decrease) */
    double tick_lo, tick_hi; /* TICK events of the current stage map into [lo, hi] */
    const char* stage;       /* the current stage's name */
} mesoi_bake_run;

/* Start a bake: copy `c` (may be NULL), resolve max_memory 0 to the default
 * budget, start the clock. */
void mesoi_run_begin(mesoi_bake_run* run, const meso_bake_common* c);
/* Milliseconds since mesoi_run_begin. */
double mesoi_run_ms(const mesoi_bake_run* run);
/* A finished stage: its -v line (printf-style, no "mesobake: " prefix; fmt
 * NULL for none), the bake now `fraction` done. Later TICK events map into
 * [fraction, next] until the next stage. */
void mesoi_run_stage(mesoi_bake_run* run, const char* stage, double fraction, double next, const char* fmt, ...)
    MESOI_PRINTF(5, 6);
/* A warning (issue `code`, 0 for none). */
void mesoi_run_warning(mesoi_bake_run* run, uint32_t code, const char* fmt, ...) MESOI_PRINTF(3, 4);
/* The last event of a successful bake: stage "done", fraction 1. */
void mesoi_run_done(mesoi_bake_run* run);
/* meso_trace_options.progress: `user` is the mesoi_bake_run. */
void mesoi_run_tick(void* user, uint64_t done, uint64_t total);

/* >>file: building the output ---------------------------------------------------- */

typedef struct mesoi_chunk {
    meso_chunk_desc desc;
    const void* data;
    size_t size;
} mesoi_chunk;

/* The output from a writer holding the objects' chunks: adds META, RPRT and
 * the OBJT chunk of `object_count` records, and takes the writer (*writer is
 * NULL afterwards, on failure too). */
meso_result mesoi_output_finish(const cJSON* meta, const cJSON* report, const meso_object_record* objects,
                                uint32_t object_count, meso_writer** writer, meso_bake_output** out, meso_error* err);
/* META, RPRT (both compact JSON: deterministic, no timings), the one-object
 * OBJT and `chunks`, in that order, into a new output. The chunks are copied. */
meso_result mesoi_output_build(const cJSON* meta, const cJSON* report, const meso_object_record* object,
                               const mesoi_chunk* chunks, int count, meso_bake_output** out, meso_error* err);

/* A META object with "generator" and "command". NULL when out of memory. */
cJSON* mesoi_meta_new(const char* command);
/* Append {"name", "bytes", "crc32c"} of an input file to a META "inputs"
 * array: enough to tell which file an asset was baked from. */
meso_result mesoi_add_input_provenance(cJSON* inputs, const char* path, meso_error* err);
/* Adds what loading changed in the input mesh (inside-out components
 * flipped: "reoriented_components" and a "warnings" array; and
 * "orientation_unchecked") to a report; adds nothing when it changed nothing. */
void mesoi_report_fixes(cJSON* report, const meso_bake_mesh_fixes* fixes);

/* A .meso input (bake_pack.c; also shell --update): open `path` and verify
 * it in full (Draco meshes decoded); err gets the first issue, prefixed by
 * the file's base name. */
meso_result mesoi_open_verified(const char* path, meso_file** f, meso_error* err);
/* A JSON chunk of `f` (file-wide `type`) parsed, or NULL when absent; a
 * chunk that does not parse cannot pass full validation, so NULL then too. */
cJSON* mesoi_json_chunk(meso_file* f, uint32_t type);

/* >>load --------------------------------------------------------------------------- */

const char* mesoi_base_name(const char* path);
int mesoi_has_suffix(const char* s, const char* suffix); /* ASCII case-insensitive */
/* Read a whole file (provenance checksums, .drc input). */
meso_result mesoi_slurp(const char* path, uint8_t** data, size_t* size, meso_error* err);
/* How messages and META name an input mesh the host passed in memory. */
#define MESOI_MEMORY_INPUT "(memory)"
/* A bake's input mesh: the file at `path`, or (path NULL) a copy of `mem`,
 * checked as a loaded file is. Exactly one of the two. */
meso_result mesoi_load_input(mesoi_bake_run* run, const char* path, const meso_mesh* mem, meso_mesh* m,
                             meso_bake_mesh_fixes* fixes, meso_error* err);
/* The same, with the materials' base colour of a glTF file into *mats
 * (zeroed for other formats and for a mesh in memory). */
meso_result mesoi_load_input_materials(mesoi_bake_run* run, const char* path, const meso_mesh* mem, meso_mesh* m,
                                       meso_mesh_materials* mats, meso_bake_mesh_fixes* fixes, meso_error* err);
/* The object's default name: the input's base name, or "mesh" in memory. */
const char* mesoi_input_label(const char* path);
/* META "inputs": the file's provenance, or for a mesh in memory its name
 * "(memory)", the bytes of its positions and indices and their crc32c. */
meso_result mesoi_add_provenance(cJSON* inputs, const char* path, const meso_mesh* mem, meso_error* err);
/* meso_bake_load_mesh within a bake (warnings through `run`). */
meso_result mesoi_load_mesh(mesoi_bake_run* run, const char* path, meso_mesh* m, meso_bake_mesh_fixes* fixes,
                            meso_error* err);
/* The same with the glTF materials (meso_bake_load_mesh_materials). */
meso_result mesoi_load_mesh_materials(mesoi_bake_run* run, const char* path, meso_mesh* m,
                                      meso_mesh_materials* materials, meso_bake_mesh_fixes* fixes, meso_error* err);

#endif
