/*
 * bake_output.c — the pieces every bake behind meso_bake.h shares: progress
 * events (the -v lines of mesobake, ticks, warnings), the finished file
 * (meso_bake_output: a meso_writer holding the encoded chunks, written out
 * chunk by chunk), the JSON of META and the report, and the names of the
 * shell enums.
 */
#include "bake_internal.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "memory_budget.h"
#include "meso_clock.h"
#include "meso_layout.h"
#include "mesh_orient.h"

_Static_assert(MESO_BAKE_ISSUE_REORIENTED == MESO_ORIENT_ISSUE_REORIENTED, "one number for E3250");

/* >>run ---------------------------------------------------------------------------- */

void mesoi_run_begin(mesoi_bake_run* run, const meso_bake_common* c)
{
    memset(run, 0, sizeof(*run));
    if (c)
        run->common = *c;
    if (!run->common.max_memory)
        run->common.max_memory = meso_memory_default_budget();
    run->t0 = meso_seconds();
    run->stage = "start";
}

double mesoi_run_ms(const mesoi_bake_run* run)
{
    return 1e3 * (meso_seconds() - run->t0);
}

static void emit(mesoi_bake_run* run, meso_bake_event ev, double fraction, const char* message, uint32_t code,
                 uint64_t done, uint64_t total)
{
    if (fraction > run->fraction)
        run->fraction = fraction > 1.0 ? 1.0 : fraction;
    if (!run->common.progress)
        return;
    const meso_bake_progress p = {.event = ev, .stage = run->stage, .fraction = run->fraction, .message = message,
                                  .code = code, .done = done, .total = total};
    run->common.progress(run->common.user, &p);
}

void mesoi_run_stage(mesoi_bake_run* run, const char* stage, double fraction, double next, const char* fmt, ...)
{
    char line[512];
    if (fmt) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(line, sizeof line, fmt, ap);
        va_end(ap);
    }
    run->stage = stage;
    run->tick_lo = fraction;
    run->tick_hi = next > fraction ? next : fraction;
    emit(run, MESO_BAKE_EVENT_STAGE, fraction, fmt ? line : NULL, 0, 0, 0);
}

void mesoi_run_warning(mesoi_bake_run* run, uint32_t code, const char* fmt, ...)
{
    char line[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    emit(run, MESO_BAKE_EVENT_WARNING, run->fraction, line, code, 0, 0);
}

void mesoi_run_done(mesoi_bake_run* run)
{
    run->stage = "done";
    emit(run, MESO_BAKE_EVENT_STAGE, 1.0, NULL, 0, 0, 0);
}

void mesoi_run_tick(void* user, uint64_t done, uint64_t total)
{
    mesoi_bake_run* run = user;
    const double f = total ? (double)done / (double)total : 1.0;
    emit(run, MESO_BAKE_EVENT_TICK, run->tick_lo + (run->tick_hi - run->tick_lo) * (f > 1.0 ? 1.0 : f), NULL, 0, done,
         total);
}

/* >>names and numbers -------------------------------------------------------------------------- */

const char* meso_bake_shell_kind_name(meso_shell_kind k)
{
    static const char* const names[MESO_SHELL_KIND_COUNT] = {"exterior", "interior", "envelope"};
    return (unsigned)k < MESO_SHELL_KIND_COUNT ? names[k] : NULL;
}

const char* meso_bake_directors_name(meso_shell_directors d)
{
    static const char* const names[MESO_DIRECTORS_COUNT] = {"hybrid", "lp", "normal"};
    return (unsigned)d < MESO_DIRECTORS_COUNT ? names[d] : NULL;
}

int meso_bake_parse_size(const char* s, uint64_t* out)
{
    return meso_parse_size(s, out);
}

int meso_bake_parse_long(const char* s, long lo, long hi, long* out)
{
    char* end = NULL;
    errno = 0;
    const long v = strtol(s, &end, 10);
    if (!end || end == s || *end || errno || v < lo || v > hi)
        return 0;
    *out = v;
    return 1;
}

int meso_bake_parse_positive(const char* s, double* out)
{
    char* end = NULL;
    errno = 0;
    const double v = strtod(s, &end);
    if (!end || end == s || *end || errno || !(v > 0) || !(v < 1e30))
        return 0;
    *out = v;
    return 1;
}

/* >>json --------------------------------------------------------------------------- */

cJSON* mesoi_meta_new(const char* command)
{
    cJSON* meta = cJSON_CreateObject();
    cJSON_AddStringToObject(meta, "generator", "mesobake " MESO_VERSION_STRING);
    cJSON_AddStringToObject(meta, "command", command);
    return meta;
}

meso_result mesoi_add_input_provenance(cJSON* inputs, const char* path, meso_error* err)
{
    uint8_t* bytes = NULL;
    size_t size = 0;
    meso_result r = mesoi_slurp(path, &bytes, &size, err);
    if (r != MESO_OK)
        return r;
    char crc_hex[16];
    snprintf(crc_hex, sizeof(crc_hex), "%08x", meso_crc32c(0, bytes, size));
    free(bytes);
    cJSON* inp = cJSON_CreateObject();
    cJSON_AddStringToObject(inp, "name", mesoi_base_name(path));
    cJSON_AddNumberToObject(inp, "bytes", (double)size);
    cJSON_AddStringToObject(inp, "crc32c", crc_hex);
    cJSON_AddItemToArray(inputs, inp);
    return MESO_OK;
}

meso_result mesoi_add_provenance(cJSON* inputs, const char* path, const meso_mesh* mem, meso_error* err)
{
    if (!mem)
        return mesoi_add_input_provenance(inputs, path, err);
    const size_t pb = sizeof(float) * 3 * (size_t)mem->vertex_count;
    const size_t ib = sizeof(uint32_t) * 3 * (size_t)mem->triangle_count;
    char crc_hex[16];
    snprintf(crc_hex, sizeof(crc_hex), "%08x", meso_crc32c(meso_crc32c(0, mem->positions, pb), mem->indices, ib));
    cJSON* inp = cJSON_CreateObject();
    cJSON_AddStringToObject(inp, "name", MESOI_MEMORY_INPUT);
    cJSON_AddNumberToObject(inp, "bytes", (double)(pb + ib));
    cJSON_AddStringToObject(inp, "crc32c", crc_hex);
    cJSON_AddItemToArray(inputs, inp);
    return MESO_OK;
}

void mesoi_report_fixes(cJSON* report, const meso_bake_mesh_fixes* o)
{
    if (o->orientation_unchecked)
        cJSON_AddBoolToObject(report, "orientation_unchecked", 1);
    if (!o->reoriented_components)
        return; /* reports of well-formed inputs stay as they were */
    cJSON_AddNumberToObject(report, "reoriented_components", o->reoriented_components);
    char msg[160];
    snprintf(msg, sizeof msg, "E%u: %u inside-out closed components (%u faces) were flipped",
             MESO_BAKE_ISSUE_REORIENTED, o->reoriented_components, o->reoriented_faces);
    cJSON_AddItemToArray(cJSON_AddArrayToObject(report, "warnings"), cJSON_CreateString(msg));
}

/* >>output ------------------------------------------------------------------------- */

struct meso_bake_output {
    meso_writer* writer; /* every chunk, encoded: the only copy of the file's payloads */
    char* report_json;   /* the RPRT chunk's text */
    size_t size;         /* of the file */
};

meso_result mesoi_output_finish(const cJSON* meta, const cJSON* report, const meso_object_record* objects,
                                uint32_t object_count, meso_writer** writer, meso_bake_output** out, meso_error* err)
{
    *out = NULL;
    meso_bake_output* o = calloc(1, sizeof(*o));
    char* meta_s = cJSON_PrintUnformatted(meta);
    char* rep_s = cJSON_PrintUnformatted(report);
    uint8_t* objt = malloc((size_t)MESO_OBJT_RECORD_SIZE * (object_count ? object_count : 1));
    meso_result r = o && meta_s && rep_s && objt ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    if (o)
        o->writer = *writer; /* the output owns the writer from here, whatever happens */
    else
        meso_writer_destroy(*writer);
    *writer = NULL;
    for (uint32_t i = 0; r == MESO_OK && i < object_count; ++i)
        meso_object_record_encode(&objects[i], objt + (size_t)MESO_OBJT_RECORD_SIZE * i);
    /* The file-wide chunks go first in the file whenever they are added
     * (the writer orders META, OBJT, RPRT, then the rest). */
    if (r == MESO_OK)
        r = meso_writer_add(o->writer, &(meso_chunk_desc){.type = MESO_CHUNK_META}, meta_s, strlen(meta_s), err);
    if (r == MESO_OK)
        r = meso_writer_add(o->writer, &(meso_chunk_desc){.type = MESO_CHUNK_RPRT}, rep_s, strlen(rep_s), err);
    if (r == MESO_OK)
        r = meso_writer_add(o->writer, &(meso_chunk_desc){.type = MESO_CHUNK_OBJT, .flags = MESO_CHUNK_FLAG_REQUIRED},
                            objt, (size_t)MESO_OBJT_RECORD_SIZE * object_count, err);
    if (r == MESO_OK)
        r = meso_writer_finish(o->writer, NULL, 0, &o->size);
    if (r == MESO_OK) {
        o->report_json = malloc(strlen(rep_s) + 1);
        r = o->report_json ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
        if (o->report_json)
            memcpy(o->report_json, rep_s, strlen(rep_s) + 1);
    }
    cJSON_free(meta_s);
    cJSON_free(rep_s);
    free(objt);
    if (r != MESO_OK) {
        meso_bake_output_free(o);
        return r == MESO_ERR_OUT_OF_MEMORY && !(err && err->message[0])
                   ? meso_bake_fail(err, r, 0, "writing the .meso file: out of memory")
                   : r;
    }
    *out = o;
    return MESO_OK;
}

meso_result mesoi_output_build(const cJSON* meta, const cJSON* report, const meso_object_record* object,
                               const mesoi_chunk* chunks, int count, meso_bake_output** out, meso_error* err)
{
    *out = NULL;
    meso_writer* w = NULL;
    meso_result r = meso_writer_create(NULL, &w);
    for (int i = 0; i < count && r == MESO_OK; ++i)
        r = meso_writer_add(w, &chunks[i].desc, chunks[i].data, chunks[i].size, err);
    if (r == MESO_OK)
        return mesoi_output_finish(meta, report, object, 1, &w, out, err);
    meso_writer_destroy(w);
    return r == MESO_ERR_OUT_OF_MEMORY && !(err && err->message[0])
               ? meso_bake_fail(err, r, 0, "writing the .meso file: out of memory")
               : r;
}

size_t meso_bake_output_size(const meso_bake_output* o)
{
    return o ? o->size : 0;
}

const char* meso_bake_output_report_json(const meso_bake_output* o)
{
    return o ? o->report_json : NULL;
}

meso_result meso_bake_output_write_file(meso_bake_output* o, const char* path, meso_error* err)
{
    if (!o)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "meso_bake_output_write_file: NULL output");
    return meso_writer_write_file(o->writer, path, err);
}

meso_result meso_bake_output_write(meso_bake_output* o, meso_output* staged, meso_error* err)
{
    if (!o)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "meso_bake_output_write: NULL output");
    return meso_writer_write_output(o->writer, staged, err);
}

meso_result meso_bake_output_copy(meso_bake_output* o, void* dst, size_t dst_size, size_t* needed)
{
    if (!o)
        return MESO_ERR_INVALID_ARG;
    return meso_writer_finish(o->writer, dst, dst_size, needed);
}

void meso_bake_output_free(meso_bake_output* o)
{
    if (!o)
        return;
    meso_writer_destroy(o->writer);
    free(o->report_json);
    free(o);
}
