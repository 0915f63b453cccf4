/* cmd_mesh.c — `mesobake mesh`: import a mesh as a MESH object, with its
 * levels of detail (bake/mesh_levels.c). */
#include <stdio.h>
#include <string.h>

#include "cli_util.h"

static const char* const usage_mesh =
    "Usage: mesobake mesh -i MESH -o OUT.meso [options]\n"
    "\n"
    "Import a triangle mesh into a .meso file as one MESH object, with vertex\n"
    "normals (computed by OpenMesh) and texture coordinates when the file has them.\n"
    "\n"
    "Input / output:\n"
    "  -i, --input FILE        mesh: .obj .off .ply .stl .om (OpenMesh), .drc (Draco) or\n"
    "                          .gltf .glb (glTF 2.0: every mesh of the scene, welded)\n"
    NODE_OPTION_HELP
    "  -o, --output FILE       .meso file to write (atomically; a symbolic link is written\n"
    "                          through, a device, FIFO or directory refused)\n"
    "      --name NAME         object name (default: the input's base name, 31 bytes max)\n"
    "Levels of detail:\n"
    "      --levels auto|N     auto (default): simplified levels (meshoptimizer), each with half\n"
    "                          the previous one's triangles, while a level keeps under 85 % of\n"
    "                          them and the previous had more than 64, at most 8 levels; each\n"
    "                          level's error (its largest distance to the finest surface, both\n"
    "                          ways) is measured and stored (LODS). N (1..16): at most N levels;\n"
    "                          1 = the finest only (no LODS chunk). Vertices split at uv or\n"
    "                          normal seams are welded for the simplifier and keep their own\n"
    "                          normals and uvs\n"
    "      --parts auto|none|N the mesh also cut into parts, each with levels of its own, so a\n"
    "                          reader can draw the near end finer than the far end (FORMAT.md\n"
    "                          7.11): auto (default) parts of about 1024 triangles when there are\n"
    "                          levels and at least 2048 triangles; N (64..): parts of about N\n"
    "                          triangles; none. Part borders stay fixed at every level, so any\n"
    "                          mix of part levels is closed; the file grows by about its level 0\n"
    "  -j, --threads N         threads for measuring the errors (default: all cores); the\n"
    "                          output does not depend on N\n"
    "Compression:\n"
    "      --draco             store the mesh (every level) Draco-compressed (quantised)\n"
    "      --draco-bits P,N,T  quantisation bits for positions (1..24), normals (2..24: Draco's\n"
    "                          octahedral normals need two) and uvs (1..24); default 14,10,12\n"
    "                          (24: a float's precision; Draco's cost doubles per bit)\n"
    "Reporting:\n"
    "      --report FILE       write the bake report as JSON (also stored in the file)\n"
    MEMORY_OPTION_HELP
    "  -v, --verbose           one line per stage on stderr\n"
    "  -h, --help              this help\n"
    "\n"
    "A closed mesh (or closed part) whose faces point inward is turned outward with a\n"
    "warning, which the report records (\"reoriented_components\", \"warnings\").\n";

/* "P,N,T": integers in 1..MESO_DRACO_MAX_BITS, N from 2 (Draco refuses one-bit normals),
 * overflow-checked by parse_int. */
static int parse_bits(const char* s, meso_bake_mesh_options* o)
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
        if (!meso_bake_parse_long(field, k == 1 ? 2 : 1, MESO_DRACO_MAX_BITS, &bits[k]))
            return 0;
        field = comma + 1;
    }
    o->draco_position_bits = (int)bits[0];
    o->draco_normal_bits = (int)bits[1];
    o->draco_uv_bits = (int)bits[2];
    return 1;
}

int cmd_mesh(int argc, char** argv)
{
    const char *out = NULL, *report = NULL;
    meso_bake_mesh_options o = meso_bake_mesh_defaults();
    o.common.progress = cli_progress;
    for (int i = 0; i < argc; ++i) {
        const char* a = argv[i];
        const int has_val = i + 1 < argc;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            print_help(usage_mesh);
            return MESO_EXIT_OK;
        } else if ((!strcmp(a, "-i") || !strcmp(a, "--input")) && has_val) {
            o.input = argv[++i];
        } else if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && has_val) {
            out = argv[++i];
        } else if (!strcmp(a, "--node") && has_val) {
            o.common.gltf_node = argv[++i];
        } else if (!strcmp(a, "--name") && has_val) {
            o.name = argv[++i];
        } else if (!strcmp(a, "--report") && has_val) {
            report = argv[++i];
        } else if (!strcmp(a, "--max-memory") && has_val) {
            /* the mesh readers' limits (the mesh guard) take their byte budget from it */
            int bad = 0;
            memory_option(a, argv[++i], &o.common.max_memory, &bad);
            if (bad)
                return bad;
        } else if (!strcmp(a, "--levels") && has_val) {
            long n;
            const char* v = argv[++i];
            if (!strcmp(v, "auto"))
                o.levels = 0;
            else if (meso_bake_parse_long(v, 1, MESO_BAKE_MESH_MAX_LEVELS, &n))
                o.levels = (int)n;
            else
                return usage_error("--levels expects auto or a level count in 1..%d, got '%s'",
                                   MESO_BAKE_MESH_MAX_LEVELS, v);
        } else if (!strcmp(a, "--parts") && has_val) {
            int code;
            if (!parts_option(argv[++i], &o.parts, &code))
                return code;
        } else if ((!strcmp(a, "-j") || !strcmp(a, "--threads")) && has_val) {
            long n;
            if (!meso_bake_parse_long(argv[++i], 1, 256, &n))
                return usage_error("-j expects a thread count in 1..256, got '%s'", argv[i]);
            o.common.threads = (int)n;
        } else if (!strcmp(a, "--draco")) {
            o.draco = 1;
        } else if (!strcmp(a, "--draco-bits") && has_val) {
            if (!parse_bits(argv[++i], &o))
                return usage_error("--draco-bits expects P,N,T in 1..%d (N in 2..%d), got '%s'", MESO_DRACO_MAX_BITS,
                                   MESO_DRACO_MAX_BITS, argv[i]);
            o.draco = 1;
        } else if (!strcmp(a, "-v") || !strcmp(a, "--verbose")) {
            verbose = 1;
        } else if (a[0] == '-' && a[1] != '\0') {
            int known = !strcmp(a, "-i") || !strcmp(a, "--input") || !strcmp(a, "-o") || !strcmp(a, "--output") ||
                        !strcmp(a, "--name") || !strcmp(a, "--report") || !strcmp(a, "--draco-bits") ||
                        !strcmp(a, "--max-memory") || !strcmp(a, "--node") || !strcmp(a, "--levels") ||
                        !strcmp(a, "--parts") ||
                        !strcmp(a, "-j") || !strcmp(a, "--threads");
            return usage_error(known ? "option '%s' needs a value" : "unrecognized option '%s'", a);
        } else {
            return usage_error("unexpected argument '%s'", a);
        }
    }
    if (!o.input || !out) {
        fputs(usage_mesh, stderr);
        return MESO_EXIT_USAGE;
    }
    const int checked = check_outputs(out, report);
    if (checked != MESO_EXIT_OK)
        return checked;
    const double t0 = meso_seconds();
    meso_error err = {0};
    meso_bake_output* baked = NULL;
    const meso_result r = meso_bake_mesh(&o, &baked, NULL, &err);
    return finish_bake(r, &err, baked, out, report, t0, o.draco ? ", mesh draco" : ", mesh raw");
}
