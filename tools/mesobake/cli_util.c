/* cli_util.c — what mesobake's commands share: diagnostics, timing, input
 * loading with the checks every stage relies on. */
#include "cli_util.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cjson/cJSON.h>

#include "adapters.h"
#include "mesh_guard.h"
#include "mesh_orient.h"
#include "memory_budget.h"
#include "meso_layout.h"

int verbose;

void err_msg(const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("mesobake error: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}

void err_print(const meso_error* err)
{
    const char* msg = err->message[0] ? err->message : meso_result_string(err->result);
    if (err->code)
        fprintf(stderr, "mesobake error E%u: %s\n", (unsigned)err->code, msg);
    else
        fprintf(stderr, "mesobake error: %s\n", msg);
}

void print_help(const char* usage)
{
    fputs(usage, stdout);
    fputs("\n" MESOBAKE_HELP_EXIT_CODES, stdout);
}

int usage_error(const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("mesobake error: ", stderr);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputs("\nSee 'mesobake --help'.\n", stderr);
    return MESO_EXIT_USAGE;
}

int option_value(const char* opt, const char* value, const char* const* valued, size_t count)
{
    int known = 0;
    for (size_t k = 0; k < count && !known; ++k)
        known = !strcmp(opt, valued[k]);
    if (!known)
        return opt[0] == '-' ? usage_error("unrecognized option '%s'", opt)
                             : usage_error("unexpected argument '%s'", opt);
    if (!value)
        return usage_error("option '%s' needs a value", opt);
    return 0;
}

int path_option(const char* opt, const char* value, const char** in, const char** out, const char** report)
{
    const char** slot = !strcmp(opt, "-i") || !strcmp(opt, "--input")    ? in
                        : !strcmp(opt, "-o") || !strcmp(opt, "--output") ? out
                        : !strcmp(opt, "--report")                       ? report
                                                                         : NULL;
    if (slot)
        *slot = value;
    return slot != NULL;
}

const char* base_name(const char* path)
{
    const char* s = strrchr(path, '/');
    return s ? s + 1 : path;
}

int has_suffix(const char* s, const char* suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    if (n < m)
        return 0;
    for (size_t i = 0; i < m; ++i) {
        char c = s[n - m + i];
        if (c >= 'A' && c <= 'Z')
            c = (char)(c - 'A' + 'a');
        if (c != suffix[i])
            return 0;
    }
    return 1;
}

/* Read a whole file (for provenance checksums and .drc input). */
meso_result slurp(const char* path, uint8_t** data, size_t* size, meso_error* err)
{
    *data = NULL;
    *size = 0;
    FILE* f = fopen(path, "rb");
    if (!f)
        return meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: cannot open: %s", path, strerror(errno));
    if (fseek(f, 0, SEEK_END) != 0) {
        fclose(f);
        return meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: cannot seek: %s", path, strerror(errno));
    }
    long n = ftell(f);
    rewind(f);
    if (n < 0) {
        fclose(f);
        return meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: not a regular file", path);
    }
    uint8_t* buf = malloc((size_t)n + 1);
    if (!buf) {
        fclose(f);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "%s: out of memory", path);
    }
    if (fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        fclose(f);
        return meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: read failed", path);
    }
    fclose(f);
    *data = buf;
    *size = (size_t)n;
    return MESO_OK;
}

/* Check what every stage relies on: finite coordinates, indices in range,
 * no degenerate index triples. Problems are errors naming the element. */
static meso_result check_mesh(const char* path, const meso_mesh* m, meso_error* err)
{
    for (uint32_t i = 0; i < 3u * m->vertex_count; ++i)
        if (!(m->positions[i] == m->positions[i]) || m->positions[i] > 3.0e38f || m->positions[i] < -3.0e38f)
            return meso_bake_fail(err, MESO_ERR_CORRUPT, 3101, "%s: vertex %u has a non-finite coordinate", path,
                                  i / 3u);
    for (uint32_t t = 0; t < m->triangle_count; ++t) {
        const uint32_t* ix = m->indices + 3u * t;
        if (ix[0] >= m->vertex_count || ix[1] >= m->vertex_count || ix[2] >= m->vertex_count)
            return meso_bake_fail(err, MESO_ERR_CORRUPT, 3102, "%s: triangle %u refers to a missing vertex", path, t);
    }
    return MESO_OK;
}

/* What load_mesh changed in the mesh it loaded, for the bake report. */
static meso_mesh_orientation last_orientation;

/* Inside-out closed components are flipped with a warning (mesh_orient.h
 * says which, and why per component). */
static meso_result orient_mesh(const char* path, meso_mesh* m, meso_error* err)
{
    meso_result r = meso_mesh_orient_outward(m, &last_orientation, err);
    if (r == MESO_OK && last_orientation.reoriented_components)
        fprintf(stderr, "mesobake warning: %s: %u of %u closed components were inside-out (negative volume); "
                        "flipped their %u faces\n",
                path, last_orientation.reoriented_components, last_orientation.closed_components,
                last_orientation.reoriented_faces);
    if (r == MESO_OK && last_orientation.unchecked)
        fprintf(stderr, "mesobake warning: %s: too many nested closed components to check their orientation; "
                        "left as they are\n",
                path);
    return r;
}

void report_mesh_warnings(cJSON* report)
{
    const meso_mesh_orientation* o = &last_orientation;
    if (o->unchecked)
        cJSON_AddBoolToObject(report, "orientation_unchecked", 1);
    if (!o->reoriented_components)
        return; /* reports of well-formed inputs stay as they were */
    cJSON_AddNumberToObject(report, "reoriented_components", o->reoriented_components);
    char msg[160];
    snprintf(msg, sizeof msg, "E%u: %u inside-out closed components (%u faces) were flipped",
             MESO_ORIENT_ISSUE_REORIENTED, o->reoriented_components, o->reoriented_faces);
    cJSON_AddItemToArray(cJSON_AddArrayToObject(report, "warnings"), cJSON_CreateString(msg));
}

static meso_result load_mesh_unchecked(const char* path, uint64_t max_memory, meso_mesh* m, meso_error* err);

meso_result load_mesh(const char* path, uint64_t max_memory, meso_mesh* m, meso_error* err)
{
    meso_result r = load_mesh_unchecked(path, max_memory, m, err);
    /* Every failure carries a code: 3100 for an input the readers reject. */
    if (r != MESO_OK && err && err->code == 0)
        err->code = r == MESO_ERR_IO ? 5004 : 3100;
    return r;
}

static meso_result load_mesh_unchecked(const char* path, uint64_t max_memory, meso_mesh* m, meso_error* err)
{
    memset(m, 0, sizeof(*m));
    FILE* probe = fopen(path, "rb");
    if (!probe)
        return meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: cannot open: %s", path, strerror(errno));
    fclose(probe);
    meso_result r;
    /* No third-party reader sees a file the guard refuses (bake/mesh_guard.h). */
    if (meso_mesh_format_from_path(path) != MESO_MESH_FORMAT_UNKNOWN &&
        (r = meso_mesh_guard_check_file(path, max_memory, NULL, err)) != MESO_OK)
        return r;
    if (has_suffix(path, ".drc")) {
#if MESO_HAVE_DRACO
        uint8_t* data;
        size_t size;
        if ((r = slurp(path, &data, &size, err)) != MESO_OK)
            return r;
        r = meso_draco_decode(data, size, m, err);
        free(data);
        if (r != MESO_OK) {
            char msg[sizeof(err->message)];
            snprintf(msg, sizeof(msg), "%s", err->message);
            return meso_bake_fail(err, r, err->code, "%s: %s", path, msg);
        }
#else
        return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0, "%s: .drc input needs the Draco adapter", path);
#endif
    } else {
#if MESO_HAVE_OPENMESH
        uint32_t dropped = 0;
        if (!(has_suffix(path, ".obj") || has_suffix(path, ".off") || has_suffix(path, ".ply") ||
              has_suffix(path, ".stl") || has_suffix(path, ".om")))
            return meso_bake_fail(err, MESO_ERR_CORRUPT, 3251,
                                  "%s: not a mesh file we can read: unknown extension (expected .obj .off .ply "
                                  ".stl .om .drc)",
                                  path);
        r = meso_openmesh_read(path, m, &dropped, err);
        if (r != MESO_OK)
            return r == MESO_ERR_IO ? meso_bake_fail(err, MESO_ERR_CORRUPT, 3100, "%s", err->message) : r;
        if (dropped) {
            meso_mesh_free(m);
            return meso_bake_fail(err, MESO_ERR_CORRUPT, 3110,
                                  "%s: %u faces are non-manifold (complex edges or vertices) and could not be "
                                  "imported; repair the mesh (split non-manifold edges and vertices) and bake again",
                                  path, dropped);
        }
#else
        return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0, "%s: mesh import needs the OpenMesh adapter", path);
#endif
    }
    if (r == MESO_OK && m->triangle_count == 0) /* empty, or not a mesh at all */
        r = meso_bake_fail(err, MESO_ERR_CORRUPT, 3252, "%s: no triangles (an empty file, or not a mesh)", path);
    if (r == MESO_OK)
        r = check_mesh(path, m, err);
    if (r == MESO_OK)
        r = orient_mesh(path, m, err);
    if (r != MESO_OK)
        meso_mesh_free(m);
    return r;
}


meso_result add_input_provenance(cJSON* inputs, const char* path, meso_error* err)
{
    uint8_t* bytes = NULL;
    size_t size = 0;
    meso_result r = slurp(path, &bytes, &size, err);
    if (r != MESO_OK)
        return r;
    char crc_hex[16];
    snprintf(crc_hex, sizeof(crc_hex), "%08x", meso_crc32c(0, bytes, size));
    free(bytes);
    cJSON* inp = cJSON_CreateObject();
    cJSON_AddStringToObject(inp, "name", base_name(path));
    cJSON_AddNumberToObject(inp, "bytes", (double)size);
    cJSON_AddStringToObject(inp, "crc32c", crc_hex);
    cJSON_AddItemToArray(inputs, inp);
    return MESO_OK;
}

meso_result write_meso(const char* out, const cJSON* meta, const cJSON* report, const meso_object_record* object,
                       const bake_chunk* chunks, int count, size_t* file_size, meso_error* err)
{
    char* meta_s = cJSON_PrintUnformatted(meta);
    char* rep_s = cJSON_PrintUnformatted(report);
    uint8_t objt[MESO_OBJT_RECORD_SIZE];
    meso_object_record_encode(object, objt);
    meso_writer* w = NULL;
    meso_result r = meta_s && rep_s ? meso_writer_create(NULL, &w) : MESO_ERR_OUT_OF_MEMORY;
    if (r == MESO_OK)
        r = meso_writer_add(w, &(meso_chunk_desc){.type = MESO_CHUNK_META}, meta_s, strlen(meta_s), err);
    if (r == MESO_OK)
        r = meso_writer_add(w, &(meso_chunk_desc){.type = MESO_CHUNK_RPRT}, rep_s, strlen(rep_s), err);
    if (r == MESO_OK)
        r = meso_writer_add(w, &(meso_chunk_desc){.type = MESO_CHUNK_OBJT, .flags = MESO_CHUNK_FLAG_REQUIRED}, objt,
                            sizeof(objt), err);
    for (int i = 0; i < count && r == MESO_OK; ++i)
        r = meso_writer_add(w, &chunks[i].desc, chunks[i].data, chunks[i].size, err);
    if (r == MESO_OK)
        r = meso_writer_finish(w, NULL, 0, file_size);
    meso_output* o = NULL;
    if (r == MESO_OK)
        r = cli_output_stage(out, &o, err);
    if (r == MESO_OK)
        r = meso_writer_write_output(w, o, err);
    if (r != MESO_OK)
        cli_outputs_discard();
    meso_writer_destroy(w);
    cJSON_free(meta_s);
    cJSON_free(rep_s);
    return r;
}

int publish_outputs(const char* report_path, cJSON* report, size_t file_size, double seconds)
{
    meso_error err = {0};
    meso_result r = MESO_OK;
    if (report_path) {
        cJSON_AddNumberToObject(report, "bytes", (double)file_size);
        cJSON_AddNumberToObject(report, "seconds_total", seconds);
        char* s = cJSON_Print(report);
        size_t n = s ? strlen(s) : 0;
        meso_output* o = NULL;
        r = s ? cli_output_stage(report_path, &o, &err) : MESO_ERR_OUT_OF_MEMORY;
        if (r == MESO_OK)
            s[n] = '\n'; /* the terminator becomes the final newline */
        if (r == MESO_OK)
            r = meso_output_write(o, s, n + 1, &err);
        cJSON_free(s);
    }
    if (r == MESO_OK)
        r = cli_outputs_publish(&err);
    if (r == MESO_OK)
        return MESO_EXIT_OK;
    cli_outputs_discard();
    if (err.message[0])
        err_print(&err);
    else
        err_msg("%s: cannot write report: out of memory", report_path);
    return meso_exit_for(r);
}

int check_outputs(const char* out, const char* report)
{
    meso_error err = {0};
    meso_result r = meso_output_check(out, &err);
    if (r == MESO_OK && report)
        r = meso_output_check(report, &err);
    if (r == MESO_OK)
        return MESO_EXIT_OK;
    err_print(&err);
    return meso_exit_for(r);
}

int memory_option(const char* opt, const char* value, uint64_t* budget, int* bad)
{
    if (strcmp(opt, "--max-memory"))
        return 0;
    *bad = meso_parse_size(value, budget)
               ? 0
               : usage_error("--max-memory expects a size such as 512M, 8G or a byte count (1 .. 2^62), got '%s'",
                             value);
    return 1;
}

int parse_double(const char* s, double* out)
{
    char* end = NULL;
    errno = 0;
    const double v = strtod(s, &end);
    if (!end || end == s || *end || errno || !(v > 0) || !(v < 1e30))
        return 0;
    *out = v;
    return 1;
}

int parse_int(const char* s, long lo, long hi, long* out)
{
    char* end = NULL;
    errno = 0;
    const long v = strtol(s, &end, 10);
    if (!end || end == s || *end || errno || v < lo || v > hi)
        return 0;
    *out = v;
    return 1;
}

int finish_bake(meso_result r, const meso_error* err, const char* out, const char* report, cJSON* rep,
                size_t file_size, double t0)
{
    const double t_end = meso_seconds();
    if (r != MESO_OK) {
        cli_outputs_discard();
        err_print(err);
        return meso_exit_for(r);
    }
    const int code = publish_outputs(report, rep, file_size, t_end - t0);
    if (verbose && code == MESO_EXIT_OK)
        fprintf(stderr, "mesobake: wrote %s: %zu bytes (%.0f ms total)\n", out, file_size, 1e3 * (t_end - t0));
    return code;
}
