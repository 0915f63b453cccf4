/*
 * mesobake — the offline baker: meshes, skeletons and texture functions in,
 * one .meso file out. Deterministic (same inputs and options give the same
 * bytes: no timestamps, input paths recorded by base name) and atomic (the
 * output appears complete or not at all).
 *
 * CLI conventions: STYLE.md §8 (exit codes in cli_common.h).
 */
#include <cjson/cJSON.h>
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "adapters.h"
#include "cli_common.h"
#include "mesh_chunk.h"
#include "meso_bake.h"
#include "meso_layout.h"

static const char* const usage_short =
    "Usage: mesobake <command> [options]\n"
    "\n"
    "Commands:\n"
    "  mesh     import a mesh (OBJ, OFF, PLY, STL, OM or DRC) as a MESH object\n"
    "\n"
    "Run 'mesobake --help' or 'mesobake <command> --help' for all options.\n";

static const char* const usage_full =
    "mesobake " MESO_VERSION_STRING " — bake fine surface detail into .meso files\n"
    "\n"
    "Usage: mesobake <command> [options]\n"
    "       mesobake --help | --version\n"
    "\n"
    "Commands:\n"
    "  mesh     import a mesh (OBJ, OFF, PLY, STL, OM or DRC) as a MESH object\n"
    "\n"
    "Exit codes: 0 success, 1 command-line error, 2 I/O failure, 3 invalid input,\n"
    "            4 internal error, 5 not supported in this build.\n"
    "Outputs are written atomically: a failed bake never leaves a partial file.\n";

static const char* const usage_mesh =
    "Usage: mesobake mesh -i MESH -o OUT.meso [options]\n"
    "\n"
    "Import a triangle mesh into a .meso file as one MESH object, with vertex\n"
    "normals (computed by OpenMesh) and texture coordinates when the file has them.\n"
    "\n"
    "Input / output:\n"
    "  -i, --input FILE        mesh: .obj .off .ply .stl .om (OpenMesh) or .drc (Draco)\n"
    "  -o, --output FILE       .meso file to write\n"
    "      --name NAME         object name (default: the input's base name, 31 bytes max)\n"
    "Compression:\n"
    "      --draco             store the mesh Draco-compressed (quantised)\n"
    "      --draco-bits P,N,T  quantisation bits for positions, normals, uvs (default 14,10,12)\n"
    "Reporting:\n"
    "      --report FILE       write the bake report as JSON (also stored in the file)\n"
    "  -v, --verbose           one line per stage on stderr\n"
    "  -h, --help              this help\n";

static int verbose;

static void err_msg(const char* fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;
static void err_msg(const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("mesobake error: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}

static int usage_error(const char* fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;
static int usage_error(const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("mesobake error: ", stderr);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputs("\nSee 'mesobake --help'.\n", stderr);
    return MESO_EXIT_USAGE;
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static const char* base_name(const char* path)
{
    const char* s = strrchr(path, '/');
    return s ? s + 1 : path;
}

static int has_suffix(const char* s, const char* suffix)
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
static meso_result slurp(const char* path, uint8_t** data, size_t* size, meso_error* err)
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

static meso_result load_mesh(const char* path, meso_mesh* m, meso_error* err)
{
    memset(m, 0, sizeof(*m));
    FILE* probe = fopen(path, "rb");
    if (!probe)
        return meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: cannot open: %s", path, strerror(errno));
    fclose(probe);
    meso_result r;
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
            return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0,
                                  "%s: unknown mesh extension (expected .obj .off .ply .stl .om .drc)", path);
        r = meso_openmesh_read(path, m, &dropped, err);
        if (r != MESO_OK)
            return r == MESO_ERR_IO ? meso_bake_fail(err, MESO_ERR_CORRUPT, 3100, "%s", err->message) : r;
#else
        return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0, "%s: mesh import needs the OpenMesh adapter", path);
#endif
    }
    if ((r = check_mesh(path, m, err)) != MESO_OK)
        meso_mesh_free(m);
    return r;
}

static int parse_bits(const char* s, meso_draco_options* o)
{
    int p, n, t;
    char tail;
    if (sscanf(s, "%d,%d,%d%c", &p, &n, &t, &tail) != 3)
        return 0;
    if (p < 1 || p > 30 || n < 1 || n > 30 || t < 1 || t > 30)
        return 0;
    o->position_bits = p;
    o->normal_bits = n;
    o->uv_bits = t;
    return 1;
}

static char* json_print(cJSON* j)
{
    char* s = cJSON_PrintUnformatted(j);
    return s;
}

static int cmd_mesh(int argc, char** argv)
{
    const char *in = NULL, *out = NULL, *name = NULL, *report = NULL;
    int use_draco = 0;
    meso_draco_options dopt = {14, 10, 12, 7};
    for (int i = 0; i < argc; ++i) {
        const char* a = argv[i];
        const int has_val = i + 1 < argc;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            fputs(usage_mesh, stdout);
            return MESO_EXIT_OK;
        } else if ((!strcmp(a, "-i") || !strcmp(a, "--input")) && has_val) {
            in = argv[++i];
        } else if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && has_val) {
            out = argv[++i];
        } else if (!strcmp(a, "--name") && has_val) {
            name = argv[++i];
        } else if (!strcmp(a, "--report") && has_val) {
            report = argv[++i];
        } else if (!strcmp(a, "--draco")) {
            use_draco = 1;
        } else if (!strcmp(a, "--draco-bits") && has_val) {
            if (!parse_bits(argv[++i], &dopt))
                return usage_error("--draco-bits expects P,N,T with each in 1..30, got '%s'", argv[i]);
            use_draco = 1;
        } else if (!strcmp(a, "-v") || !strcmp(a, "--verbose")) {
            verbose = 1;
        } else if (a[0] == '-' && a[1] != '\0') {
            int known = !strcmp(a, "-i") || !strcmp(a, "--input") || !strcmp(a, "-o") || !strcmp(a, "--output") ||
                        !strcmp(a, "--name") || !strcmp(a, "--report") || !strcmp(a, "--draco-bits");
            return usage_error(known ? "option '%s' needs a value" : "unrecognized option '%s'", a);
        } else {
            return usage_error("unexpected argument '%s'", a);
        }
    }
    if (!in || !out) {
        fputs(usage_mesh, stderr);
        return MESO_EXIT_USAGE;
    }
    const double t0 = now_seconds();
    meso_error err = {0};
    meso_mesh m;
    meso_result r = load_mesh(in, &m, &err);
    if (r != MESO_OK) {
        err_msg("%s", err.message);
        return meso_exit_for(r);
    }
    const double t_read = now_seconds();
    if (verbose)
        fprintf(stderr, "mesobake: read %s: %u vertices, %u triangles%s%s (%.0f ms)\n", base_name(in), m.vertex_count,
                m.triangle_count, m.normals ? ", normals" : "", m.uvs ? ", uvs" : "", 1e3 * (t_read - t0));

    uint8_t* in_bytes = NULL;
    size_t in_size = 0;
    if ((r = slurp(in, &in_bytes, &in_size, &err)) != MESO_OK) {
        meso_mesh_free(&m);
        err_msg("%s", err.message);
        return meso_exit_for(r);
    }
    char crc_hex[16];
    snprintf(crc_hex, sizeof(crc_hex), "%08x", meso_crc32c(0, in_bytes, in_size));
    free(in_bytes);

    meso_mesh_chunk chunk;
    r = meso_bake_mesh_chunk(&m, use_draco ? &dopt : NULL, &chunk, &err);
    if (r != MESO_OK) {
        meso_mesh_free(&m);
        err_msg("%s", err.message);
        return meso_exit_for(r);
    }

    double lo[3], hi[3];
    const double diag = meso_mesh_bounds(&m, lo, hi);
    meso_object_record rec;
    memset(&rec, 0, sizeof(rec));
    rec.id = 1;
    rec.kind = MESO_OBJECT_MESH;
    for (int k = 0; k < 3; ++k) {
        rec.bbox_min[k] = (float)lo[k];
        rec.bbox_max[k] = (float)hi[k];
    }
    snprintf(rec.name, sizeof(rec.name), "%s", name ? name : base_name(in));
    uint8_t objt[MESO_OBJT_RECORD_SIZE];
    meso_object_record_encode(&rec, objt);

    cJSON* meta = cJSON_CreateObject();
    cJSON_AddStringToObject(meta, "generator", "mesobake " MESO_VERSION_STRING);
    cJSON_AddStringToObject(meta, "command", "mesh");
    cJSON* params = cJSON_AddObjectToObject(meta, "parameters");
    cJSON_AddStringToObject(params, "encoding", use_draco ? "draco" : "raw");
    if (use_draco) {
        cJSON_AddNumberToObject(params, "draco_position_bits", dopt.position_bits);
        cJSON_AddNumberToObject(params, "draco_normal_bits", dopt.normal_bits);
        cJSON_AddNumberToObject(params, "draco_uv_bits", dopt.uv_bits);
    }
    cJSON* inputs = cJSON_AddArrayToObject(meta, "inputs");
    cJSON* inp = cJSON_CreateObject();
    cJSON_AddStringToObject(inp, "name", base_name(in));
    cJSON_AddNumberToObject(inp, "bytes", (double)in_size);
    cJSON_AddStringToObject(inp, "crc32c", crc_hex);
    cJSON_AddItemToArray(inputs, inp);

    cJSON* rep = cJSON_CreateObject();
    cJSON_AddNumberToObject(rep, "vertices", m.vertex_count);
    cJSON_AddNumberToObject(rep, "triangles", m.triangle_count);
    cJSON_AddNumberToObject(rep, "bbox_diagonal", diag);
    cJSON_AddStringToObject(rep, "encoding", use_draco ? "draco" : "raw");
    cJSON_AddNumberToObject(rep, "mesh_bytes", (double)chunk.size);
    char* meta_s = json_print(meta);
    char* rep_s = json_print(rep); /* stored without timings: deterministic */

    meso_writer* w = NULL;
    r = meso_writer_create(NULL, &w);
    if (r == MESO_OK)
        r = meso_writer_add(w, &(meso_chunk_desc){.type = MESO_CHUNK_META, .flags = 0}, meta_s, strlen(meta_s), &err);
    if (r == MESO_OK)
        r = meso_writer_add(w, &(meso_chunk_desc){.type = MESO_CHUNK_RPRT}, rep_s, strlen(rep_s), &err);
    if (r == MESO_OK)
        r = meso_writer_add(w, &(meso_chunk_desc){.type = MESO_CHUNK_OBJT, .flags = MESO_CHUNK_FLAG_REQUIRED}, objt,
                            sizeof(objt), &err);
    if (r == MESO_OK)
        r = meso_writer_add(w,
                            &(meso_chunk_desc){.type = MESO_CHUNK_MESH,
                                               .flags = MESO_CHUNK_FLAG_REQUIRED,
                                               .object = 1,
                                               .encoding = chunk.encoding,
                                               .decoded_size = chunk.decoded_size},
                            chunk.data, chunk.size, &err);
    size_t file_size = 0;
    if (r == MESO_OK)
        r = meso_writer_finish(w, NULL, 0, &file_size);
    if (r == MESO_OK)
        r = meso_writer_write_file(w, out, &err);
    meso_writer_destroy(w);
    free(chunk.data);
    cJSON_free(meta_s);
    cJSON_free(rep_s);
    cJSON_Delete(meta);
    meso_mesh_free(&m);
    if (r != MESO_OK) {
        cJSON_Delete(rep);
        err_msg("%s: %s", out, err.message[0] ? err.message : meso_result_string(r));
        return meso_exit_for(r);
    }
    const double t_end = now_seconds();
    if (verbose)
        fprintf(stderr, "mesobake: wrote %s: %zu bytes, mesh %s (%.0f ms total)\n", out, file_size,
                use_draco ? "draco" : "raw", 1e3 * (t_end - t0));
    int code = MESO_EXIT_OK;
    if (report) {
        cJSON_AddNumberToObject(rep, "bytes", (double)file_size);
        cJSON_AddNumberToObject(rep, "seconds_total", t_end - t0);
        char* s = cJSON_Print(rep);
        FILE* f = fopen(report, "w");
        if (!f || fputs(s, f) < 0 || fputc('\n', f) == EOF) {
            err_msg("%s: cannot write report: %s", report, strerror(errno));
            code = MESO_EXIT_IO;
        }
        if (f && fclose(f) != 0 && code == MESO_EXIT_OK) {
            err_msg("%s: cannot write report: %s", report, strerror(errno));
            code = MESO_EXIT_IO;
        }
        cJSON_free(s);
    }
    cJSON_Delete(rep);
    return code;
}

int main(int argc, char** argv)
{
    if (argc < 2) {
        fputs(usage_short, stderr);
        return MESO_EXIT_USAGE;
    }
    const char* cmd = argv[1];
    if (!strcmp(cmd, "-h") || !strcmp(cmd, "--help")) {
        fputs(usage_full, stdout);
        return MESO_EXIT_OK;
    }
    if (!strcmp(cmd, "--version")) {
        printf("mesobake %s (format %d.%d)\n", MESO_VERSION_STRING, MESO_FORMAT_MAJOR, MESO_FORMAT_MINOR);
        return MESO_EXIT_OK;
    }
    if (!strcmp(cmd, "mesh"))
        return cmd_mesh(argc - 2, argv + 2);
    if (cmd[0] == '-')
        return usage_error("unrecognized option '%s'", cmd);
    return usage_error("unknown command '%s'", cmd);
}
