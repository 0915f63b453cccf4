/*
 * cmd_shell.c — `mesobake shell`: a base mesh plus fold-free directors
 * (volume-textures-lp-averaged-shells.md §4), validated exactly, in one
 * .meso SHELL object: MESH (the base), SDIR (directors), STHK (thickness),
 * and optionally a texture function (TX2D height field or TX3D density) with
 * its distance map (DIST) and texture coordinates in the MESH (FORMAT.md
 * §7.2, "Shell prisms and texture space"), and optionally its colour (COLR +
 * CMAP, §7.2 "Shell colour"; bake/shell_color.h). The bake is meso_bake_shell
 * (bake/bake_shell.c); this file parses the options.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "cli_util.h"

static const char* const usage_shell =
    "Usage: mesobake shell -i MESH -o OUT.meso [options]\n"
    "\n"
    "Build a shell over a triangle mesh: per vertex a director (direction x thickness)\n"
    "whose prisms do not fold, following the gradient of the Lp-averaged distance\n"
    "function where normal displacement would fold or collide. Every bake is validated\n"
    "exactly (inverted prisms, offset self-intersections) and reports the numbers.\n"
    "\n"
    "Input / output:\n"
    "  -i, --input FILE        mesh: .obj .off .ply .stl .om .drc .gltf .glb; open surfaces ok\n"
    "  -o, --output FILE       .meso file to write (atomically)\n"
    "Shell:\n"
    "      --thickness ABS     shell thickness in mesh units\n"
    "      --thickness-rel F   thickness as a fraction of the bounding-box diagonal (default 0.05)\n"
    "      --kind K            exterior (default), interior, or envelope (half on each side)\n"
    "      --directors D       hybrid (default): normal displacement where it is provably safe,\n"
    "                          the Lp field elsewhere; lp: the field everywhere; normal: plain\n"
    "                          normal displacement (folds at concavities and saddles)\n"
    "Field and integration:\n"
    "      --p P               exponent of the averaged distance, in (2, 16] (default 3: closed form)\n"
    "      --theta T           Barnes-Hut opening angle, 0 = exact summation (default 0.5)\n"
    "      --angle-tol DEG     largest turn of the field per Euler step (default 5)\n"
    "      --smooth N          Laplacian smoothing rounds of traced directors (default 0):\n"
    "                          removes triangle-scale noise that flips prisms on finely\n"
    "                          tessellated scans; harmful across thin features\n"
    "      --no-repair         keep directors that still fold or collide (default: --repair,\n"
    "                          which shortens them locally until the shell is valid; the\n"
    "                          report says how much thickness that gave up)\n"
    "      --allow-defects     write the shell even if inverted prisms or intersections are\n"
    "                          left (default: such a bake exits 8, E3115, and writes only\n"
    "                          the --report file, which says what is left)\n"
    "      --update OLD.meso   incremental re-bake after an edit that moved vertices (same\n"
    "                          mesh topology, same options; without --thickness OLD's\n"
    "                          thickness is kept): recompute only the directors\n"
    "                          within 3 x thickness (+ the longest edge) of a moved face, keep\n"
    "                          OLD's elsewhere (the region grows where repair needs a kept\n"
    "                          director); validated exactly (the intersection tests of\n"
    "                          the faces near the edit only: the rest is OLD's valid shell);\n"
    "                          the report's \"update\" says how many vertices were\n"
    "                          recomputed. OLD's simplified stand-in levels are kept, each\n"
    "                          error raised by the farthest move, while their base mesh\n"
    "                          has moved no farther than the base mesh's error over all\n"
    "                          updates and --levels is OLD's (else built anew; the\n"
    "                          report's \"levels_kept\"). Other options\n"
    "                          are refused (E3117, exit 1), and so are a different topology\n"
    "                          (E3118) and an OLD that is not one valid shell (E3116, E3119),\n"
    "                          exit 3\n"
    "  -j, --threads N         threads (default: all cores); the output does not depend on N\n";
/* (in three parts: one literal would pass the 4095 characters C11 promises) */
static const char* const usage_shell_texture =
    "Texture function (what the shell holds; without one the whole shell is solid):\n"
    "      --texture SPEC      height:FILE.png        height field (8/16-bit; grey or first channel;\n"
    "                                                 the bottom image row is t = 0)\n"
    "                          volume:FILE.raw:WxHxD  u8 densities, s fastest, solid where >= 1/2\n"
    "                          volume:FILE.vdb[:GRID] OpenVDB float grid (default: the first) over its\n"
    "                                                 active box; fog volume: density = value; level\n"
    "                                                 set: density = 1/2 - phi / (2 voxel)\n"
    "                          bricks[:RES] cobble[:RES] ribs[:RES]  built-in heights (RES^2, default 256)\n"
    "                          weave[:RES]            built-in interlaced threads (RES x RES x RES/2,\n"
    "                                                 default 128)\n"
    "                          cells[:RES]            built-in 3D Voronoi cell walls (RES^3, default 64)\n"
    "                          boil[:RES]             built-in boiling liquid, bubbles rising and\n"
    "                                                 bursting (RES^3, default 64); loops every 2 s\n"
    "                          icospheres[:RES]       Figure 12's sphere with 12 spheres at icosahedron\n"
    "                                                 vertices, one per tile (RES^3, default 64)\n"
    "      --tiling U[,V]      tiles along the texture coordinates (default 1,1). The mesh's own\n"
    "                          uvs are multiplied by it; a mesh without uvs is projected onto the\n"
    "                          plane of its two largest bounding-box extents, the longest spanning\n"
    "                          U tiles (the other V/U as densely), with a warning. At uv seams\n"
    "                          (OBJ f v/vt) a vertex is split, one copy per distinct uv\n"
    "      --dist-res WxHxD    distance-map cells (each 1..512; default: half the texture's\n"
    "                          resolution in s, t (8..128) and, in w, half a volume's depth or,\n"
    "                          for a height field, about one cell per typical height step)\n"
    "      --dist-type T       u8 (default), u16 or f32: distance-map store type\n"
    "      --color SPEC        colour of the mesostructure (needs --texture; default: one albedo):\n"
    "                          FILE.png        RGB(A) PNG over texture space, tiled like the\n"
    "                                          height field (the bottom image row is t = 0)\n"
    "                          volume:FILE.raw:WxHxD  RGBA8 texels over a volume texture\n"
    "                                          (s fastest, then t, then w)\n"
    "                          from-mesh       the glTF input's base colour (texture x factor) at\n"
    "                                          the base point of each texel column (the mesh's\n"
    "                                          own uv, not tiled); one material, TEXCOORD_0;\n"
    "                                          other inputs: E3133, exit 3\n";
static const char* const usage_shell_end =
    "      --time T            seconds: sample a time-dependent texture (boil) at T (default 0)\n"
    "      --frames N          store N frames (1..256) at T + k / FPS, looped (FORMAT.md 7.2\n"
    "                          \"Animated texture functions\"); frame k equals a bake at that time\n"
    "      --fps F             frames per second (default: N / the texture's period: a seamless loop)\n"
    "Levels of detail:\n"
    "      --levels auto|N     auto (default): a static height field's native levels first (the\n"
    "                          shell again with the height field halved and its own distance map;\n"
    "                          error: the exact sup of the height change times the longest\n"
    "                          top - bottom; a static volume's likewise, halved along s, t and w,\n"
    "                          with a measured bound of how far its surface moved (none where the\n"
    "                          texture coordinates hold a sliver); up to 4, kept while each draws\n"
    "                          from at most 9/10 of the bytes of the level before), then with a\n"
    "                          static texture up to 3 coarser base meshes with their directors\n"
    "                          (the level's vertices a subset of the base's, uv seams and folds\n"
    "                          kept; error: the exact largest move of a texture point, kept while\n"
    "                          below the next; smooth mapping only), then the base\n"
    "                          mesh (over a height field its mid-surface), drawn as a plain\n"
    "                          mesh where the whole shell is thinner than the error on screen, with\n"
    "                          its error (the largest offset of the surface drawn), then the base\n"
    "                          mesh's simplified levels (meshoptimizer, as mesobake mesh --levels\n"
    "                          auto), each with the base's error plus its own (LODS); with a static\n"
    "                          texture each carries the colour (--color) and darkening seen over\n"
    "                          each vertex (VCOL) and the mean normal of the surface there (MESH\n"
    "                          normals). N (1..9): at most N levels; 1 = level 0 only (no LODS\n"
    "                          chunk), 2 = the base mesh only, N >= 3: the base mesh, then\n"
    "                          texture levels, then simplified ones, then coarser base meshes with\n"
    "                          what is left\n"
    "      --parts auto|none|N the shell also cut into parts (FORMAT.md 7.11), so a reader can\n"
    "                          draw the near end as prisms and the far end as stand-in patches:\n"
    "                          each part's prisms, then its patch of the first stand-in and the\n"
    "                          patch's simplifications (their borders fixed, so patches meet edge\n"
    "                          to edge), with colours as the stand-ins'. auto (default): parts of\n"
    "                          about 1024 triangles when there are stand-ins and at least 2048\n"
    "                          triangles; N (64..): parts of about N triangles; none\n"
    "Reporting:\n"
    "      --report FILE       the bake report as JSON (also stored in the file, without timings)\n"
    MEMORY_OPTION_HELP
    NODE_OPTION_HELP
    "  -v, --verbose           one line per stage on stderr\n"
    "  -h, --help              this help\n"
    "\n"
    "Input meshes must be manifold, consistently oriented, without degenerate or\n"
    "duplicated faces, and must not intersect themselves; each problem is an error\n"
    "naming a face (exit 3), and nothing is written.\n";

typedef struct shell_args {
    const char *out, *report;
    int allow_defects;
    meso_bake_shell_options o;
} shell_args;

static const char* const dist_type_names[] = {"u8", "u16", "f32"};
static const uint16_t dist_dtypes[] = {MESO_DTYPE_U8, MESO_DTYPE_U16, MESO_DTYPE_F32};

static int lookup(const char* s, const char* const* names, int n)
{
    for (int i = 0; i < n; ++i)
        if (!strcmp(s, names[i]))
            return i;
    return -1;
}

/* A meso_shell_kind or meso_shell_directors by its word (meso_bake.h); -1 if none. */
static int lookup_kind(const char* s)
{
    for (int k = 0; k < MESO_SHELL_KIND_COUNT; ++k)
        if (!strcmp(s, meso_bake_shell_kind_name((meso_shell_kind)k)))
            return k;
    return -1;
}

static int lookup_directors(const char* s)
{
    for (int d = 0; d < MESO_DIRECTORS_COUNT; ++d)
        if (!strcmp(s, meso_bake_directors_name((meso_shell_directors)d)))
            return d;
    return -1;
}

/* "U" or "U,V": positive finite numbers. */
static int parse_tiling(const char* v, double t[2])
{
    char buf[64];
    if (strlen(v) >= sizeof(buf))
        return 0;
    memcpy(buf, v, strlen(v) + 1);
    char* comma = strchr(buf, ',');
    if (comma)
        *comma = 0;
    if (!meso_bake_parse_positive(buf, &t[0]) || t[0] > 1e6)
        return 0;
    t[1] = t[0];
    return !comma || (meso_bake_parse_positive(comma + 1, &t[1]) && t[1] <= 1e6);
}

/* "WxHxD", each 1..MESO_BAKE_MAX_DIST_RES. */
static int parse_res(const char* v, uint32_t res[3])
{
    const char* p = v;
    for (int a = 0; a < 3; ++a) {
        char* end = NULL;
        if (*p < '0' || *p > '9')
            return 0;
        const unsigned long x = strtoul(p, &end, 10);
        if (x < 1 || x > MESO_BAKE_MAX_DIST_RES || (a < 2 ? *end != 'x' : *end != 0))
            return 0;
        res[a] = (uint32_t)x;
        p = end + 1;
    }
    return 1;
}

static int parse_args(int argc, char** argv, shell_args* a)
{
    *a = (shell_args){.o = meso_bake_shell_defaults()};
    meso_bake_shell_options* o = &a->o;
    cli_bake_common(&o->common);
    int have_abs = 0, have_rel = 0, k;
    long n;
    for (int i = 0; i < argc; ++i) {
        const char* s = argv[i];
        const char* v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(s, "-h") || !strcmp(s, "--help")) {
            fputs(usage_shell, stdout);
            fputs(usage_shell_texture, stdout);
            print_help(usage_shell_end);
            return -1;
        } else if (!strcmp(s, "-v") || !strcmp(s, "--verbose")) {
            verbose = 1;
            continue;
        } else if (!strcmp(s, "--repair") || !strcmp(s, "--no-repair")) {
            o->no_repair = s[2] != 'r';
            continue;
        } else if (!strcmp(s, "--allow-defects")) {
            a->allow_defects = 1;
            continue;
        }
        static const char* const valued[] = {"-i", "--input", "-o", "--output", "--report", "--max-memory", "--thickness",
            "--thickness-rel", "--kind", "--directors", "--p", "--theta", "--angle-tol", "-j", "--threads",
            "--smooth", "--texture", "--color", "--tiling", "--dist-res", "--dist-type", "--time", "--frames", "--fps",
            "--update", "--levels", "--parts"};
        int handled, code;
        if (!bake_option(s, v, valued, sizeof valued / sizeof valued[0], &o->input, &a->out, &a->report,
                         &o->common.max_memory, &handled, &code))
            return code;
        ++i;
        if (handled)
            continue;
        if (!strcmp(s, "--texture"))
            o->texture = v;
        else if (!strcmp(s, "--update"))
            o->update = v;
        else if (!strcmp(s, "--levels")) {
            long count = 0;
            if (!strcmp(v, "auto"))
                o->levels = 0;
            else if (meso_bake_parse_long(v, 1, MESO_BAKE_SHELL_MAX_LEVELS, &count))
                o->levels = (int)count;
            else
                return usage_error("--levels expects auto or a level count in 1..%u, got '%s'",
                                   MESO_BAKE_SHELL_MAX_LEVELS, v);
        }
        else if (!strcmp(s, "--parts")) {
            if (!parts_option(v, &o->parts, &code))
                return code;
        } else if (!strcmp(s, "--color"))
            o->color = v;
        else if (!strcmp(s, "--time")) {
            char* end = NULL;
            o->time = strtod(v, &end);
            if (!end || end == v || *end || !(o->time >= -1e6 && o->time <= 1e6))
                return usage_error("--time expects seconds in [-1e6, 1e6], got '%s'", v);
        } else if (!strcmp(s, "--frames")) {
            if (!meso_bake_parse_long(v, 1, MESO_BAKE_MAX_FRAMES, &n))
                return usage_error("--frames expects a frame count in 1..%u, got '%s'", MESO_BAKE_MAX_FRAMES, v);
            o->frames = (uint32_t)n;
        } else if (!strcmp(s, "--fps")) {
            if (!meso_bake_parse_positive(v, &o->fps) || o->fps > 1000)
                return usage_error("--fps expects frames per second in (0, 1000], got '%s'", v);
        }
        else if (!strcmp(s, "--tiling")) {
            if (!parse_tiling(v, o->tiling))
                return usage_error("--tiling expects U or U,V (positive numbers), got '%s'", v);
        } else if (!strcmp(s, "--dist-res")) {
            if (!parse_res(v, o->dist_res))
                return usage_error("--dist-res expects WxHxD, each in 1..%u, got '%s'", MESO_BAKE_MAX_DIST_RES, v);
        } else if (!strcmp(s, "--dist-type")) {
            if ((k = lookup(v, dist_type_names, 3)) < 0)
                return usage_error("--dist-type expects u8, u16 or f32, got '%s'", v);
            o->dist_dtype = dist_dtypes[k];
        } else if (!strcmp(s, "--thickness")) {
            if (!meso_bake_parse_positive(v, &o->thickness))
                return usage_error("--thickness expects a positive length, got '%s'", v);
            have_abs = 1;
        } else if (!strcmp(s, "--thickness-rel")) {
            if (!meso_bake_parse_positive(v, &o->thickness_rel) || o->thickness_rel > 10)
                return usage_error("--thickness-rel expects a fraction in (0, 10], got '%s'", v);
            have_rel = 1;
        } else if (!strcmp(s, "--kind")) {
            if ((k = lookup_kind(v)) < 0)
                return usage_error("--kind expects exterior, interior or envelope, got '%s'", v);
            o->kind = (meso_shell_kind)k;
        } else if (!strcmp(s, "--directors")) {
            if ((k = lookup_directors(v)) < 0)
                return usage_error("--directors expects hybrid, lp or normal, got '%s'", v);
            o->directors = (meso_shell_directors)k;
        } else if (!strcmp(s, "--p")) {
            if (!meso_bake_parse_positive(v, &o->p) || !(o->p > 2.0) || o->p > MESO_BAKE_MAX_P)
                return usage_error("--p expects a number in (2, 16], got '%s'", v);
        } else if (!strcmp(s, "--theta")) {
            char* end = NULL;
            o->theta = strtod(v, &end);
            if (!end || end == v || *end || !(o->theta >= 0 && o->theta <= 1.5))
                return usage_error("--theta expects an angle in [0, 1.5], got '%s'", v);
        } else if (!strcmp(s, "--angle-tol")) {
            if (!meso_bake_parse_positive(v, &o->angle_tol_deg) || o->angle_tol_deg > 90)
                return usage_error("--angle-tol expects degrees in (0, 90], got '%s'", v);
        } else if (!strcmp(s, "--smooth")) {
            if (!meso_bake_parse_long(v, 0, 1000, &n))
                return usage_error("--smooth expects a round count in 0..1000, got '%s'", v);
            o->smooth = (int)n;
        } else if (!meso_bake_parse_long(v, 1, 256, &n)) {
            return usage_error("-j expects a thread count in 1..256, got '%s'", v);
        } else {
            o->common.threads = (int)n;
        }
    }
    if (have_abs && have_rel)
        return usage_error("%s", "option --thickness can not be used together with --thickness-rel");
    if (!have_abs)
        o->thickness = 0; /* from --thickness-rel once the mesh is known */
    if (!o->input || !a->out) {
        fputs(usage_shell, stderr);
        fputs(usage_shell_texture, stderr);
        fputs(usage_shell_end, stderr);
        return MESO_EXIT_USAGE;
    }
    if (!o->texture &&
        (o->dist_res[0] || o->dist_dtype != MESO_DTYPE_U8 || o->tiling[0] != 1.0 || o->tiling[1] != 1.0))
        return usage_error("%s", "--tiling, --dist-res and --dist-type need --texture");
    if (o->color && !o->texture)
        return usage_error("%s", "--color needs --texture (the colour lives in its texture space)");
    return check_outputs(a->out, a->report);
}

/* The per-stage seconds of the bake, in the --report file only. */
static void stage_seconds(struct cJSON* report, const void* user)
{
    const meso_bake_shell_report* r = user;
    const struct {
        const char* key;
        double v;
    } t[] = {{"seconds_load", r->seconds_load},         {"seconds_topology", r->seconds_topology},
             {"seconds_check", r->seconds_check},       {"seconds_texture", r->seconds_texture},
             {"seconds_field", r->seconds_field},       {"seconds_directors", r->seconds_directors},
             {"seconds_directors_checks", r->seconds_directors_checks},
             {"seconds_repair", r->seconds_repair},     {"seconds_validate", r->seconds_validate},
             {"seconds_allowed", r->seconds_allowed},   {"seconds_assemble", r->seconds_assemble}};
    for (size_t k = 0; k < sizeof t / sizeof t[0]; ++k)
        cJSON_AddNumberToObject(report, t[k].key, t[k].v);
}

int cmd_shell(int argc, char** argv)
{
    shell_args a;
    const int rc = parse_args(argc, argv, &a);
    if (rc != 0)
        return rc < 0 ? MESO_EXIT_OK : rc;
    const double t0 = meso_seconds();
    meso_error err = {0};
    meso_bake_output* baked = NULL;
    meso_bake_shell_report rep;
    const meso_result r = meso_bake_shell(&a.o, &baked, &rep, &err);
    /* Defects left (--no-repair, or what repair could not fix): not written
     * unless asked for; the report still is, and says what is left. */
    meso_error defects = {0};
    const uint64_t left = (uint64_t)rep.inverted_prisms + rep.offset_self_intersections + rep.offset_base_intersections;
    if (r == MESO_OK && left && !a.allow_defects) {
        defects.code = MESO_BAKE_ISSUE_SHELL_DEFECTS;
        defects.result = MESO_ERR_CORRUPT;
        defects.chunk = -1;
        snprintf(defects.message, sizeof defects.message,
                 "%s: shell left with %u inverted prisms, %llu offset self- and %llu offset/base intersections%s; "
                 "nothing written (--allow-defects writes it)",
                 a.o.input, rep.inverted_prisms, (unsigned long long)rep.offset_self_intersections,
                 (unsigned long long)rep.offset_base_intersections, a.o.no_repair ? " (--no-repair)" : "");
    }
    const finish_extra x = {.add_report = stage_seconds, .user = &rep, .refuse = defects.code ? &defects : NULL,
                            .refuse_exit = MESO_EXIT_DEFECTS};
    return finish_bake_ex(r, &err, baked, a.out, a.report, t0, NULL, &x);
}
