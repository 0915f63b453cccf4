/* cmd_mesh.c — `mesobake mesh`: import a mesh as a MESH object. */
#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_util.h"
#include "memory_budget.h"
#include "mesh_chunk.h"

static const char* const usage_mesh =
    "Usage: mesobake mesh -i MESH -o OUT.meso [options]\n"
    "\n"
    "Import a triangle mesh into a .meso file as one MESH object, with vertex\n"
    "normals (computed by OpenMesh) and texture coordinates when the file has them.\n"
    "\n"
    "Input / output:\n"
    "  -i, --input FILE        mesh: .obj .off .ply .stl .om (OpenMesh) or .drc (Draco)\n"
    "  -o, --output FILE       .meso file to write (atomically; a symbolic link is written\n"
    "                          through, a device, FIFO or directory refused)\n"
    "      --name NAME         object name (default: the input's base name, 31 bytes max)\n"
    "Compression:\n"
    "      --draco             store the mesh Draco-compressed (quantised)\n"
    "      --draco-bits P,N,T  quantisation bits for positions (1..30), normals (2..30: Draco's\n"
    "                          octahedral normals need two) and uvs (1..30); default 14,10,12\n"
    "Reporting:\n"
    "      --report FILE       write the bake report as JSON (also stored in the file)\n"
    MEMORY_OPTION_HELP
    "  -v, --verbose           one line per stage on stderr\n"
    "  -h, --help              this help\n"
    "\n"
    "A closed mesh (or closed part) whose faces point inward is turned outward with a\n"
    "warning, which the report records (\"reoriented_components\", \"warnings\").\n";

/* "P,N,T": integers in 1..30, N in 2..30 (Draco refuses one-bit normals),
 * overflow-checked by parse_int. */
static int parse_bits(const char* s, meso_draco_options* o)
{
    long bits[3];
    char buf[64];
    if (strlen(s) >= sizeof buf)
        return 0;
    memcpy(buf, s, strlen(s) + 1);
    char* field = buf;
    for (int k = 0; k < 3; ++k) {
        char* comma = strchr(field, ',');
        if ((k < 2) != (comma != NULL))
            return 0;
        if (comma)
            *comma = 0;
        if (!parse_int(field, k == 1 ? 2 : 1, 30, &bits[k]))
            return 0;
        field = comma + 1;
    }
    o->position_bits = (int)bits[0];
    o->normal_bits = (int)bits[1];
    o->uv_bits = (int)bits[2];
    return 1;
}

int cmd_mesh(int argc, char** argv)
{
    const char *in = NULL, *out = NULL, *name = NULL, *report = NULL;
    int use_draco = 0;
    meso_draco_options dopt = {14, 10, 12, 7};
    /* --max-memory: parsed like every bake command's; the mesh readers'
     * limits (the mesh guard) take their byte budget from it. */
    uint64_t max_memory = 0;
    for (int i = 0; i < argc; ++i) {
        const char* a = argv[i];
        const int has_val = i + 1 < argc;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            print_help(usage_mesh);
            return MESO_EXIT_OK;
        } else if ((!strcmp(a, "-i") || !strcmp(a, "--input")) && has_val) {
            in = argv[++i];
        } else if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && has_val) {
            out = argv[++i];
        } else if (!strcmp(a, "--name") && has_val) {
            name = argv[++i];
        } else if (!strcmp(a, "--report") && has_val) {
            report = argv[++i];
        } else if (!strcmp(a, "--max-memory") && has_val) {
            int bad = 0;
            memory_option(a, argv[++i], &max_memory, &bad);
            if (bad)
                return bad;
        } else if (!strcmp(a, "--draco")) {
            use_draco = 1;
        } else if (!strcmp(a, "--draco-bits") && has_val) {
            if (!parse_bits(argv[++i], &dopt))
                return usage_error("--draco-bits expects P,N,T in 1..30 (N in 2..30), got '%s'", argv[i]);
            use_draco = 1;
        } else if (!strcmp(a, "-v") || !strcmp(a, "--verbose")) {
            verbose = 1;
        } else if (a[0] == '-' && a[1] != '\0') {
            int known = !strcmp(a, "-i") || !strcmp(a, "--input") || !strcmp(a, "-o") || !strcmp(a, "--output") ||
                        !strcmp(a, "--name") || !strcmp(a, "--report") || !strcmp(a, "--draco-bits") ||
                        !strcmp(a, "--max-memory");
            return usage_error(known ? "option '%s' needs a value" : "unrecognized option '%s'", a);
        } else {
            return usage_error("unexpected argument '%s'", a);
        }
    }
    if (!in || !out) {
        fputs(usage_mesh, stderr);
        return MESO_EXIT_USAGE;
    }
    const int checked = check_outputs(out, report);
    if (checked != MESO_EXIT_OK)
        return checked;
    const double t0 = meso_seconds();
    meso_error err = {0};
    meso_mesh m;
    if (!max_memory)
        max_memory = meso_memory_default_budget();
    meso_result r = load_mesh(in, max_memory, &m, &err);
    if (r != MESO_OK) {
        err_print(&err);
        return meso_exit_for(r);
    }
    if (verbose)
        fprintf(stderr, "mesobake: read %s: %u vertices, %u triangles%s%s (%.0f ms)\n", base_name(in), m.vertex_count,
                m.triangle_count, m.normals ? ", normals" : "", m.uvs ? ", uvs" : "", 1e3 * (meso_seconds() - t0));

    meso_mesh_chunk chunk;
    r = meso_bake_mesh_chunk(&m, use_draco ? &dopt : NULL, &chunk, &err);
    if (r != MESO_OK) {
        meso_mesh_free(&m);
        err_print(&err);
        return meso_exit_for(r);
    }
    double lo[3], hi[3];
    const double diag = meso_mesh_bounds(&m, lo, hi);
    meso_object_record rec = {.id = 1, .kind = MESO_OBJECT_MESH};
    for (int k = 0; k < 3; ++k) {
        rec.bbox_min[k] = (float)lo[k];
        rec.bbox_max[k] = (float)hi[k];
    }
    snprintf(rec.name, sizeof(rec.name), "%s", name ? name : base_name(in));

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
    r = add_input_provenance(cJSON_AddArrayToObject(meta, "inputs"), in, &err);

    cJSON* rep = cJSON_CreateObject();
    report_mesh_warnings(rep);
    cJSON_AddNumberToObject(rep, "vertices", m.vertex_count);
    cJSON_AddNumberToObject(rep, "triangles", m.triangle_count);
    cJSON_AddNumberToObject(rep, "bbox_diagonal", diag);
    cJSON_AddStringToObject(rep, "encoding", use_draco ? "draco" : "raw");
    cJSON_AddNumberToObject(rep, "mesh_bytes", (double)chunk.size);

    const bake_chunk chunks[1] = {{.desc = {.type = MESO_CHUNK_MESH,
                                            .flags = MESO_CHUNK_FLAG_REQUIRED,
                                            .object = 1,
                                            .encoding = chunk.encoding,
                                            .decoded_size = chunk.decoded_size},
                                   .data = chunk.data,
                                   .size = chunk.size}};
    size_t file_size = 0;
    if (r == MESO_OK)
        r = write_meso(out, meta, rep, &rec, chunks, 1, &file_size, &err);
    free(chunk.data);
    cJSON_Delete(meta);
    meso_mesh_free(&m);
    if (r != MESO_OK) {
        cJSON_Delete(rep);
        err_print(&err);
        return meso_exit_for(r);
    }
    const double t_end = meso_seconds();
    const int code = publish_outputs(report, rep, file_size, t_end - t0);
    if (verbose && code == MESO_EXIT_OK)
        fprintf(stderr, "mesobake: wrote %s: %zu bytes, mesh %s (%.0f ms total)\n", out, file_size,
                use_draco ? "draco" : "raw", 1e3 * (t_end - t0));
    cJSON_Delete(rep);
    return code;
}
