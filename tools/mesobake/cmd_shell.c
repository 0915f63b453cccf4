/*
 * cmd_shell.c — `mesobake shell`: a base mesh plus fold-free directors
 * (volume-textures-lp-averaged-shells.md §4), validated exactly, in one
 * .meso SHELL object: MESH (the base), SDIR (directors), STHK (thickness),
 * and optionally a texture function (TX2D height field or TX3D density) with
 * its distance map (DIST) and texture coordinates in the MESH (FORMAT.md
 * §7.2, "Shell prisms and texture space").
 */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "adapters.h"
#include "cli_util.h"
#include "distance_map.h"
#include "lp_distance.h"
#include "mesh_check.h"
#include "mesh_chunk.h"
#include "shell_hybrid.h"
#include "shell_validate.h"
#include "memory_budget.h"
#include "texture_function.h"

static const char* const usage_shell =
    "Usage: mesobake shell -i MESH -o OUT.meso [options]\n"
    "\n"
    "Build a shell over a triangle mesh: per vertex a director (direction x thickness)\n"
    "whose prisms do not fold, following the gradient of the Lp-averaged distance\n"
    "function where normal displacement would fold or collide. Every bake is validated\n"
    "exactly (inverted prisms, offset self-intersections) and reports the numbers.\n"
    "\n"
    "Input / output:\n"
    "  -i, --input FILE        mesh: .obj .off .ply .stl .om or .drc; open surfaces are fine\n"
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
    "  -j, --threads N         threads (default: all cores); the output does not depend on N\n"
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
    "      --tiling U[,V]      tiles along the texture coordinates (default 1,1). The mesh's own\n"
    "                          uvs are multiplied by it; a mesh without uvs is projected onto the\n"
    "                          plane of its two largest bounding-box extents, the longest spanning\n"
    "                          U tiles (the other V/U as densely), with a warning. At uv seams\n"
    "                          (OBJ f v/vt) a vertex is split, one copy per distinct uv\n"
    "      --dist-res WxHxD    distance-map cells (each 1..512; default: half the texture's\n"
    "                          resolution in s, t (8..128) and, in w, half a volume's depth or,\n"
    "                          for a height field, about one cell per typical height step)\n"
    "      --dist-type T       u8 (default), u16 or f32: distance-map store type\n"
    "Reporting:\n"
    "      --report FILE       the bake report as JSON (also stored in the file, without timings)\n";
/* (in two parts: one literal would pass the 4095 characters C11 promises) */
static const char* const usage_shell_end =
    MEMORY_OPTION_HELP
    "  -v, --verbose           one line per stage on stderr\n"
    "  -h, --help              this help\n"
    "\n"
    "Input meshes must be manifold, consistently oriented, without degenerate or\n"
    "duplicated faces, and must not intersect themselves; each problem is an error\n"
    "naming a face (exit 3), and nothing is written.\n";

static const char* const kind_names[] = {"exterior", "interior", "envelope"};
static const char* const mode_names[] = {"hybrid", "lp", "normal"};

static int lookup(const char* s, const char* const* names, int n)
{
    for (int i = 0; i < n; ++i)
        if (!strcmp(s, names[i]))
            return i;
    return -1;
}

typedef struct shell_args {
    const char *in, *out, *report, *texture;
    double thickness, thickness_rel, p, theta, angle_tol_deg;
    double tiling[2];     /* --tiling U,V */
    uint32_t dist_res[3]; /* --dist-res; 0 = the default for the texture */
    int dist_type;        /* index into dist_type_names */
    int kind, mode, repair;
    long threads, smooth;
    uint64_t max_memory; /* --max-memory; 0 until parsed = the default */
} shell_args;

static const char* const dist_type_names[] = {"u8", "u16", "f32"};
static const uint16_t dist_dtypes[] = {MESO_DTYPE_U8, MESO_DTYPE_U16, MESO_DTYPE_F32};

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
    if (!parse_double(buf, &t[0]) || t[0] > 1e6)
        return 0;
    t[1] = t[0];
    return !comma || (parse_double(comma + 1, &t[1]) && t[1] <= 1e6);
}

/* "WxHxD", each 1..MESO_DISTMAP_MAX_RES. */
static int parse_res(const char* v, uint32_t res[3])
{
    const char* p = v;
    for (int a = 0; a < 3; ++a) {
        char* end = NULL;
        if (*p < '0' || *p > '9')
            return 0;
        const unsigned long x = strtoul(p, &end, 10);
        if (x < 1 || x > MESO_DISTMAP_MAX_RES || (a < 2 ? *end != 'x' : *end != 0))
            return 0;
        res[a] = (uint32_t)x;
        p = end + 1;
    }
    return 1;
}

static int parse_args(int argc, char** argv, shell_args* a)
{
    *a = (shell_args){.thickness_rel = 0.05, .p = 3.0, .theta = 0.5, .angle_tol_deg = 5.0, .repair = 1,
                      .smooth = 0, .tiling = {1.0, 1.0}};
    int have_abs = 0, have_rel = 0;
    for (int i = 0; i < argc; ++i) {
        const char* s = argv[i];
        const char* v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(s, "-h") || !strcmp(s, "--help")) {
            fputs(usage_shell, stdout);
            print_help(usage_shell_end);
            return -1;
        } else if (!strcmp(s, "-v") || !strcmp(s, "--verbose")) {
            verbose = 1;
            continue;
        } else if (!strcmp(s, "--repair") || !strcmp(s, "--no-repair")) {
            a->repair = s[2] == 'r';
            continue;
        }
        static const char* const valued[] = {"-i", "--input", "-o", "--output", "--report", "--max-memory", "--thickness",
            "--thickness-rel", "--kind", "--directors", "--p", "--theta", "--angle-tol", "-j", "--threads",
            "--smooth", "--texture", "--tiling", "--dist-res", "--dist-type"};
        const int bad = option_value(s, v, valued, sizeof valued / sizeof valued[0]);
        if (bad)
            return bad;
        ++i;
        if (path_option(s, v, &a->in, &a->out, &a->report))
            continue;
        int bad_size = 0;
        if (memory_option(s, v, &a->max_memory, &bad_size)) {
            if (bad_size)
                return bad_size;
            continue;
        }
        if (!strcmp(s, "--texture"))
            a->texture = v;
        else if (!strcmp(s, "--tiling")) {
            if (!parse_tiling(v, a->tiling))
                return usage_error("--tiling expects U or U,V (positive numbers), got '%s'", v);
        } else if (!strcmp(s, "--dist-res")) {
            if (!parse_res(v, a->dist_res))
                return usage_error("--dist-res expects WxHxD, each in 1..%u, got '%s'", MESO_DISTMAP_MAX_RES, v);
        } else if (!strcmp(s, "--dist-type")) {
            if ((a->dist_type = lookup(v, dist_type_names, 3)) < 0)
                return usage_error("--dist-type expects u8, u16 or f32, got '%s'", v);
        } else if (!strcmp(s, "--thickness")) {
            if (!parse_double(v, &a->thickness))
                return usage_error("--thickness expects a positive length, got '%s'", v);
            have_abs = 1;
        } else if (!strcmp(s, "--thickness-rel")) {
            if (!parse_double(v, &a->thickness_rel) || a->thickness_rel > 10)
                return usage_error("--thickness-rel expects a fraction in (0, 10], got '%s'", v);
            have_rel = 1;
        } else if (!strcmp(s, "--kind")) {
            if ((a->kind = lookup(v, kind_names, 3)) < 0)
                return usage_error("--kind expects exterior, interior or envelope, got '%s'", v);
        } else if (!strcmp(s, "--directors")) {
            if ((a->mode = lookup(v, mode_names, 3)) < 0)
                return usage_error("--directors expects hybrid, lp or normal, got '%s'", v);
        } else if (!strcmp(s, "--p")) {
            if (!parse_double(v, &a->p) || !(a->p > 2.0) || a->p > MESO_LP_MAX_P)
                return usage_error("--p expects a number in (2, 16], got '%s'", v);
        } else if (!strcmp(s, "--theta")) {
            char* end = NULL;
            a->theta = strtod(v, &end);
            if (!end || end == v || *end || !(a->theta >= 0 && a->theta <= 1.5))
                return usage_error("--theta expects an angle in [0, 1.5], got '%s'", v);
        } else if (!strcmp(s, "--angle-tol")) {
            if (!parse_double(v, &a->angle_tol_deg) || a->angle_tol_deg > 90)
                return usage_error("--angle-tol expects degrees in (0, 90], got '%s'", v);
        } else if (!strcmp(s, "--smooth")) {
            if (!parse_int(v, 0, 1000, &a->smooth))
                return usage_error("--smooth expects a round count in 0..1000, got '%s'", v);
        } else if (!parse_int(v, 1, 256, &a->threads)) {
            return usage_error("-j expects a thread count in 1..256, got '%s'", v);
        }
    }
    if (have_abs && have_rel)
        return usage_error("%s", "option --thickness can not be used together with --thickness-rel");
    if (!have_abs)
        a->thickness = 0; /* from --thickness-rel once the mesh is known */
    if (!a->in || !a->out) {
        fputs(usage_shell, stderr);
        fputs(usage_shell_end, stderr);
        return MESO_EXIT_USAGE;
    }
    if (!a->texture && (a->dist_res[0] || a->dist_type || a->tiling[0] != 1.0 || a->tiling[1] != 1.0))
        return usage_error("%s", "--tiling, --dist-res and --dist-type need --texture");
    return check_outputs(a->out, a->report);
}

/* A one-line progress bar on a terminal (-v): redrawn in place with \r. */
static void progress_bar(void* user, uint64_t done, uint64_t total)
{
    const char* what = user;
    const int width = 30, filled = total ? (int)(width * done / total) : width;
    fprintf(stderr, "\rmesobake: %s [%.*s%*s] %3d%%", what, filled, "##############################", width - filled,
            "", total ? (int)(100 * done / total) : 100);
    if (done >= total)
        fputs("\r\033[K", stderr);
    fflush(stderr);
}

static cJSON* report_json(const meso_shell_report* v, const meso_hybrid_stats* hs, uint32_t lp_vertices,
                          uint32_t shortened, uint32_t nv, const meso_trace_stats* ts, const meso_field_surface* fs)
{
    cJSON* rep = cJSON_CreateObject();
    cJSON_AddNumberToObject(rep, "prisms", v->prisms);
    cJSON_AddNumberToObject(rep, "inverted_prisms", v->inverted_prisms);
    cJSON_AddNumberToObject(rep, "undecided_prisms", v->undecided_prisms);
    cJSON_AddNumberToObject(rep, "offset_self_intersections", (double)v->offset_self_intersections);
    cJSON_AddNumberToObject(rep, "offset_base_intersections", (double)v->offset_base_intersections);
    cJSON_AddNumberToObject(rep, "thickness_ratio_min", v->thickness_ratio_min);
    cJSON_AddNumberToObject(rep, "thickness_ratio_mean", v->thickness_ratio_mean);
    cJSON_AddNumberToObject(rep, "vertices_lp", lp_vertices);
    cJSON_AddNumberToObject(rep, "vertices_normal", nv - lp_vertices);
    cJSON_AddNumberToObject(rep, "hybrid_rounds", hs->rounds);
    cJSON_AddNumberToObject(rep, "vertices_shortened", shortened);
    cJSON_AddNumberToObject(rep, "field_evaluations", (double)ts->evaluations);
    cJSON_AddNumberToObject(rep, "artificial_faces", fs->artificial_faces);
    return rep;
}

/* >>texture ------------------------------------------------------------------ */

typedef struct shell_texture {
    meso_texfn fn;
    meso_distmap dist;
    float* uvs;            /* 2 per output vertex: texture coordinates, tiling included */
    const char* uv_source; /* "mesh" or "planar" */
    char plane[3];         /* planar: the two axes, e.g. "xz" (s along the first) */
    /* Split at uv seams (a mesh with corner uvs), else 0, NULL, NULL. */
    uint32_t seam_vertices; /* copies added: the output has the mesh's vertices plus these */
    uint32_t* source;       /* each output vertex's mesh vertex */
    uint32_t* indices;      /* 3 * triangle_count: the triangles over the output vertices */
} shell_texture;

static void texture_free(shell_texture* tx)
{
    meso_texfn_free(&tx->fn);
    meso_distmap_free(&tx->dist);
    free(tx->uvs);
    free(tx->source);
    free(tx->indices);
}

/* Parse the spec, sample the function, bake its distance map. */
static meso_result texture_prepare(const shell_args* a, shell_texture* tx, meso_error* err)
{
    double t = meso_seconds();
    meso_result r = meso_texfn_from_spec_max(a->texture, a->max_memory, &tx->fn, err);
    if (r != MESO_OK)
        return r;
    const uint32_t* td = tx->fn.dims;
    if (verbose)
        fprintf(stderr, "mesobake: texture %s: %s %ux%ux%u %s (%.0f ms)\n", a->texture,
                tx->fn.kind == MESO_TEXFN_HEIGHT ? "height field" : "density volume", td[0], td[1], td[2],
                tx->fn.dtype == MESO_DTYPE_U8 ? "u8" : "u16", 1e3 * (meso_seconds() - t));
    uint32_t res[3] = {a->dist_res[0], a->dist_res[1], a->dist_res[2]};
    if (!res[0])
        meso_distmap_default_res(&tx->fn, res);
    /* Limits up front: the texture is held, the distance map not yet made. */
    const uint64_t cells = (uint64_t)res[0] * res[1] * res[2];
    const uint64_t texels = (uint64_t)td[0] * td[1] * td[2];
    r = meso_budget_check(meso_size_add(meso_texture_estimate(texels), meso_distmap_estimate(cells)), a->max_memory,
                          MESO_LIMIT_ISSUE_REQUEST, err, "distance map %ux%ux%u (%s) of a %ux%ux%u texture", res[0],
                          res[1], res[2], a->dist_res[0] ? "--dist-res" : "default", td[0], td[1], td[2]);
    if (r != MESO_OK)
        return r;
    t = meso_seconds();
    r = meso_distmap_build(&tx->fn, res, dist_dtypes[a->dist_type], (int)a->threads, &tx->dist, err);
    if (r == MESO_OK && verbose)
        fprintf(stderr, "mesobake: distance map %ux%ux%u %s (%s): %llu of %llu cells touch the solid (%.0f ms)\n",
                res[0], res[1], res[2], dist_type_names[a->dist_type], a->dist_res[0] ? "--dist-res" : "default",
                (unsigned long long)tx->dist.solid_cells, (unsigned long long)res[0] * res[1] * res[2],
                1e3 * (meso_seconds() - t));
    return r;
}

/* Per-corner uvs into one uv per vertex: each distinct (vertex, corner uv)
 * pair (exact float bits) becomes one output vertex. Vertex v keeps index v
 * and the uv of its first corner (faces in order, corners in order); every
 * further uv it has appends a copy, numbered from nv in order of first
 * appearance. A vertex no face uses keeps its per-vertex uv. Copies share
 * position and director, so the shell stays closed across the seam. */
static meso_result split_seams(const shell_args* a, const meso_mesh* m, shell_texture* tx, meso_error* err)
{
    const uint32_t nv = m->vertex_count, none = UINT32_MAX;
    const size_t nc = 3 * (size_t)m->triangle_count, cap = (size_t)nv + nc; /* < 2^32: the reader's limits */
    uint32_t* next = malloc(sizeof(uint32_t) * cap); /* next copy of the same vertex, or `none` */
    float* uv = malloc(sizeof(float) * 2 * cap);
    uint8_t* used = calloc(nv ? nv : 1, 1);
    tx->source = malloc(sizeof(uint32_t) * cap);
    tx->indices = malloc(sizeof(uint32_t) * (nc ? nc : 1));
    meso_result r = next && uv && used && tx->source && tx->indices ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    uint32_t n = nv;
    for (uint32_t v = 0; r == MESO_OK && v < nv; ++v) {
        next[v] = none;
        tx->source[v] = v;
        memcpy(uv + 2 * (size_t)v, m->uvs + 2 * (size_t)v, 2 * sizeof(float));
    }
    for (size_t c = 0; r == MESO_OK && c < nc; ++c) {
        const uint32_t v = m->indices[c];
        const float* cu = m->corner_uvs + 2 * c;
        uint32_t o = v, last = v;
        if (!used[v]) {
            used[v] = 1;
            memcpy(uv + 2 * (size_t)v, cu, 2 * sizeof(float));
        }
        while (o != none && memcmp(uv + 2 * (size_t)o, cu, 2 * sizeof(float)) != 0) {
            last = o;
            o = next[o];
        }
        if (o == none) {
            o = n++;
            next[last] = o;
            next[o] = none;
            tx->source[o] = v;
            memcpy(uv + 2 * (size_t)o, cu, 2 * sizeof(float));
        }
        tx->indices[c] = o;
    }
    if (r == MESO_OK) {
        tx->uvs = malloc(sizeof(float) * 2 * (size_t)n);
        r = tx->uvs ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    }
    for (size_t o = 0; r == MESO_OK && o < n; ++o) {
        tx->uvs[2 * o] = (float)(uv[2 * o] * a->tiling[0]);
        tx->uvs[2 * o + 1] = (float)(uv[2 * o + 1] * a->tiling[1]);
    }
    tx->seam_vertices = n - nv;
    free(next);
    free(uv);
    free(used);
    return r == MESO_OK ? MESO_OK : meso_bake_fail(err, r, 0, "out of memory");
}

/* Texture coordinates: the mesh's own times the tiling (split at seams when
 * the mesh has per-corner uvs), or (documented fallback) a planar projection
 * onto the two largest bounding-box extents, the longest spanning U tiles and
 * the other V/U as densely. */
static meso_result texture_uvs(const shell_args* a, const meso_mesh* m, const double lo[3], const double hi[3],
                               shell_texture* tx, meso_error* err)
{
    const uint32_t nv = m->vertex_count;
    tx->uv_source = "mesh";
    if (m->corner_uvs)
        return split_seams(a, m, tx, err);
    tx->uvs = malloc(sizeof(float) * 2 * (size_t)nv);
    if (!tx->uvs)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "out of memory");
    if (m->uvs) {
        for (size_t v = 0; v < nv; ++v) {
            tx->uvs[2 * v] = (float)(m->uvs[2 * v] * a->tiling[0]);
            tx->uvs[2 * v + 1] = (float)(m->uvs[2 * v + 1] * a->tiling[1]);
        }
        return MESO_OK;
    }
    int ax[3] = {0, 1, 2}; /* by decreasing extent; ties keep x, y, z order */
    for (int i = 0; i < 3; ++i)
        for (int j = i + 1; j < 3; ++j)
            if (hi[ax[j]] - lo[ax[j]] > hi[ax[i]] - lo[ax[i]]) {
                const int k = ax[i];
                ax[i] = ax[j];
                ax[j] = k;
            }
    const double ext = hi[ax[0]] - lo[ax[0]] > 0 ? hi[ax[0]] - lo[ax[0]] : 1.0;
    for (size_t v = 0; v < nv; ++v) {
        tx->uvs[2 * v] = (float)((m->positions[3 * v + (size_t)ax[0]] - lo[ax[0]]) / ext * a->tiling[0]);
        tx->uvs[2 * v + 1] = (float)((m->positions[3 * v + (size_t)ax[1]] - lo[ax[1]]) / ext * a->tiling[1]);
    }
    tx->uv_source = "planar";
    tx->plane[0] = (char)('x' + ax[0]);
    tx->plane[1] = (char)('x' + ax[1]);
    tx->plane[2] = 0;
    fprintf(stderr, "mesobake warning: %s has no texture coordinates; projecting it onto its %s plane (the two "
                    "largest bounding-box extents), %c spanning %g tiles\n",
            base_name(a->in), tx->plane, tx->plane[0], a->tiling[0]);
    return MESO_OK;
}

/* META.parameters.texture and the report's "texture". */
static void texture_json(cJSON* parent, const shell_args* a, const shell_texture* tx, int report)
{
    cJSON* o = cJSON_AddObjectToObject(parent, "texture");
    cJSON_AddStringToObject(o, "spec", a->texture);
    cJSON_AddStringToObject(o, "kind", tx->fn.kind == MESO_TEXFN_HEIGHT ? "height" : "density");
    const double tex_dims[3] = {tx->fn.dims[0], tx->fn.dims[1], tx->fn.dims[2]};
    cJSON_AddItemToObject(o, "texture_res", cJSON_CreateDoubleArray(tex_dims, tx->fn.kind == MESO_TEXFN_HEIGHT ? 2 : 3));
    cJSON_AddItemToObject(o, "tiling", cJSON_CreateDoubleArray(a->tiling, 2));
    const double dd[3] = {tx->dist.dims[0], tx->dist.dims[1], tx->dist.dims[2]};
    cJSON_AddItemToObject(o, "dist_res", cJSON_CreateDoubleArray(dd, 3));
    cJSON_AddStringToObject(o, "dist_type", dist_type_names[a->dist_type]);
    cJSON_AddStringToObject(o, "uv_source", tx->uv_source);
    if (tx->plane[0])
        cJSON_AddStringToObject(o, "uv_plane", tx->plane);
    if (report) {
        cJSON_AddNumberToObject(o, "dist_solid_cells", (double)tx->dist.solid_cells);
        cJSON_AddNumberToObject(o, "seam_vertices", tx->seam_vertices);
    }
}

/* The output's per-vertex floats from the mesh's: `layers` stacked arrays
 * of 3 floats per vertex, output vertex o taking mesh vertex source[o].
 * Returns NULL when out of memory. */
static float* gather3(const float* in, uint32_t nv, const uint32_t* source, uint32_t n, int layers)
{
    float* out = malloc(sizeof(float) * 3 * (size_t)n * (size_t)layers);
    for (size_t l = 0; out && l < (size_t)layers; ++l)
        for (size_t o = 0; o < n; ++o)
            memcpy(out + 3 * (l * n + o), in + 3 * (l * nv + source[o]), 3 * sizeof(float));
    return out;
}

int cmd_shell(int argc, char** argv)
{
    shell_args a;
    int rc = parse_args(argc, argv, &a);
    if (rc != 0)
        return rc < 0 ? MESO_EXIT_OK : rc;
    if (!a.max_memory)
        a.max_memory = meso_memory_default_budget();
    const double t0 = meso_seconds();
    meso_error err = {0};
    shell_texture tx;
    memset(&tx, 0, sizeof(tx));
    /* The texture first: a bad spec fails before any mesh work. */
    meso_result r = a.texture ? texture_prepare(&a, &tx, &err) : MESO_OK;
    if (r != MESO_OK) {
        texture_free(&tx);
        err_print(&err);
        return meso_exit_for(r);
    }
    meso_mesh m;
    r = load_mesh(a.in, a.max_memory, &m, &err);
    if (r != MESO_OK) {
        texture_free(&tx);
        err_print(&err);
        return meso_exit_for(r);
    }
    double lo[3], hi[3];
    const double diag = meso_mesh_bounds(&m, lo, hi);
    const double h = a.thickness > 0 ? a.thickness : a.thickness_rel * diag;
    const uint32_t nv = m.vertex_count, nt = m.triangle_count;

    /* Refuse what no shell can be built on, before any work. */
    meso_mesh_topology topo;
    r = meso_mesh_topology_compute(&m, 1e-14 * diag * diag, &topo, &err);
    if (r == MESO_OK)
        r = meso_mesh_topology_require_shellable(&topo, a.in, &err);
#if MESO_HAVE_CGAL
    if (r == MESO_OK) {
        double* xyz = malloc(sizeof(double) * 3 * (size_t)nv);
        meso_cgal_intersection_count c = {0, 0, 0};
        r = xyz ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
        for (size_t i = 0; xyz && i < 3 * (size_t)nv; ++i)
            xyz[i] = m.positions[i];
        if (r == MESO_OK)
            r = meso_cgal_self_intersections(xyz, nv, m.indices, nt, &c, &err);
        free(xyz);
        if (r == MESO_OK && c.pairs)
            r = meso_bake_fail(&err, MESO_ERR_CORRUPT, 3114,
                               "%s: the surface intersects itself (%llu triangle pairs); no shell over it can be "
                               "valid — repair the mesh first",
                               a.in, (unsigned long long)c.pairs);
    }
#endif
    if (r == MESO_OK && a.texture)
        r = texture_uvs(&a, &m, lo, hi, &tx, &err);
    if (r != MESO_OK) {
        free(topo.boundary);
        meso_mesh_free(&m);
        texture_free(&tx);
        err_print(&err);
        return meso_exit_for(r);
    }
    if (verbose)
        fprintf(stderr, "mesobake: %s: %u vertices, %u triangles, %u boundary edges; thickness %g (%.3g of the "
                        "diagonal) (%.0f ms)\n",
                base_name(a.in), nv, nt, topo.boundary_edges, h, h / diag, 1e3 * (meso_seconds() - t0));
    if (verbose && a.texture)
        fprintf(stderr, "mesobake: texture coordinates (%s): %u seam vertices added, %u output vertices\n",
                tx.uv_source, tx.seam_vertices, nv + tx.seam_vertices);

    float* normals = malloc(sizeof(float) * 3 * (size_t)nv);
    const int layers = a.kind == MESO_SHELL_ENVELOPE ? 2 : 1;
    float* d = calloc(3 * (size_t)nv * (size_t)layers, sizeof(float));
    uint8_t* lp_mask = calloc(nv, 1);
    uint8_t* lp_side = calloc(nv, 1);
    meso_field_surface fs = {0};
    meso_lp_field* field = NULL;
    cJSON *meta = NULL, *rep = NULL;
    meso_mesh_chunk chunk = {0};
    float* thick = NULL;
    meso_hybrid_stats hs_total = {0};
    uint32_t shortened_total = 0; /* vertices the repair shortened, over both sides */
    meso_trace_stats ts = {0, 0, 0};
    const double h_side = a.kind == MESO_SHELL_ENVELOPE ? 0.5 * h : h;
    r = normals && d && lp_mask && lp_side ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    if (r == MESO_OK)
        r = meso_vertex_normals(&m, normals, &err);
    if (r == MESO_OK)
        r = meso_field_surface_build(&m, normals, topo.boundary, topo.boundary_edges, h_side, &fs, &err);
    if (r == MESO_OK && a.mode != 2) {
        const meso_lp_options lo_opt = {.p = a.p, .theta = a.theta, .near_radius = 2.0 * h_side};
        r = meso_lp_field_create(fs.positions, fs.vertex_count, fs.indices, fs.triangle_count, &lo_opt, &field, &err);
    }
    const meso_trace_options topt = {.thickness = h_side, .angle_tol = a.angle_tol_deg * M_PI / 180.0,
                                     .theta = a.theta, .smooth_iterations = (int)a.smooth,
                                     .progress = verbose && isatty(2) ? progress_bar : NULL,
                                     .progress_user = (void*)"tracing directors"};
    /* Exterior: layer 0 along +n. Interior: layer 0 along -n. Envelope:
     * layer 0 (top) along +n, layer 1 (bottom) along -n. */
    for (int layer = 0; layer < layers && r == MESO_OK; ++layer) {
        const int sign = (a.kind == MESO_SHELL_INTERIOR || layer == 1) ? -1 : 1;
        meso_hybrid_stats hs;
        r = meso_shell_side_directors(field, &m, normals, sign, &topt, a.mode, (int)a.threads,
                                      d + 3 * (size_t)nv * (size_t)layer, lp_side, &hs, &ts, &err);
        for (uint32_t v = 0; v < nv; ++v)
            lp_mask[v] |= lp_side[v];
        hs_total.rounds += hs.rounds;
        if (verbose && r == MESO_OK)
            fprintf(stderr, "mesobake: directors (%s side, %s): %u Lp, %u normal, %u rounds, %llu field evaluations "
                            "(%.0f ms)\n",
                    sign > 0 ? "outer" : "inner", mode_names[a.mode], hs.vertices_lp, hs.vertices_normal, hs.rounds,
                    (unsigned long long)ts.evaluations, 1e3 * (meso_seconds() - t0));
        if (r == MESO_OK && a.repair) {
            uint32_t shortened = 0, rounds = 0, left = 0;
            r = meso_shell_repair(&m, d + 3 * (size_t)nv * (size_t)layer, sign, 30, &shortened, &rounds, &left, &err);
            shortened_total += shortened;
            if (verbose && r == MESO_OK)
                fprintf(stderr, "mesobake: repair: %u vertices shortened in %u rounds, %u faces still bad\n",
                        shortened, rounds, left);
        }
    }

    /* Validate the shell as it will be rendered: prisms from bottom to top. */
    meso_shell_report val;
    memset(&val, 0, sizeof(val));
    if (r == MESO_OK) {
        if (a.kind == MESO_SHELL_ENVELOPE) {
            meso_mesh bottom = m;
            float* pos = malloc(sizeof(float) * 3 * (size_t)nv);
            float* span = malloc(sizeof(float) * 3 * (size_t)nv);
            r = pos && span ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
            for (size_t i = 0; r == MESO_OK && i < 3 * (size_t)nv; ++i) {
                pos[i] = m.positions[i] + d[3 * (size_t)nv + i];
                span[i] = d[i] - d[3 * (size_t)nv + i];
            }
            bottom.positions = pos;
            if (r == MESO_OK)
                r = meso_shell_validate(&bottom, span, NULL, h, 1, NULL, &val, &err);
            free(pos);
            free(span);
        } else {
            r = meso_shell_validate(&m, d, NULL, h, a.kind == MESO_SHELL_INTERIOR ? -1 : 1, NULL, &val, &err);
        }
        if (verbose && r == MESO_OK)
            fprintf(stderr, "mesobake: validated: %u/%u prisms inverted (%u undecided), %llu offset self-intersections, %llu "
                            "offset/base intersections, thickness ratio min %.3f mean %.3f (%.0f ms)\n",
                    val.inverted_prisms, val.prisms, val.undecided_prisms,
                    (unsigned long long)val.offset_self_intersections,
                    (unsigned long long)val.offset_base_intersections, val.thickness_ratio_min,
                    val.thickness_ratio_mean, 1e3 * (meso_seconds() - t0));
    }

    size_t file_size = 0;
    /* Everything per vertex below is written for the output vertices: the
     * mesh's, plus the copies split off at uv seams (tx.source). */
    const uint32_t nv_out = nv + tx.seam_vertices;
    float *pos_out = NULL, *normals_out = NULL, *sdir_out = NULL;
    if (r == MESO_OK) {
        /* Base mesh with the normals the directors started from (and the
         * texture coordinates of the texture function). */
        meso_mesh out = m;
        out.normals = normals;
        if (tx.uvs)
            out.uvs = tx.uvs;
        if (tx.source) {
            pos_out = gather3(m.positions, nv, tx.source, nv_out, 1);
            normals_out = gather3(normals, nv, tx.source, nv_out, 1);
            out.vertex_count = nv_out;
            out.positions = pos_out;
            out.normals = normals_out;
            out.indices = tx.indices;
            out.corner_uvs = NULL;
        }
        r = !tx.source || (pos_out && normals_out) ? meso_bake_mesh_chunk(&out, NULL, &chunk, &err)
                                                   : meso_bake_fail(&err, MESO_ERR_OUT_OF_MEMORY, 0, "out of memory");
    }
    /* SDIR as FORMAT.md §7.2 has it: L = 1 for exterior shells; L = 2 for
     * envelopes (top, bottom) and for interior shells, whose layer 0 is zero
     * (top = the base surface) and layer 1 the inward director (bottom). */
    const int sdir_layers = a.kind == MESO_SHELL_EXTERIOR ? 1 : 2;
    float* sdir = d;
    if (r == MESO_OK && a.kind == MESO_SHELL_INTERIOR) {
        sdir = calloc(3 * (size_t)nv * 2, sizeof(float));
        r = sdir ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
        if (sdir)
            memcpy(sdir + 3 * (size_t)nv, d, sizeof(float) * 3 * (size_t)nv);
    }
    if (r == MESO_OK && tx.source) {
        sdir_out = gather3(sdir, nv, tx.source, nv_out, sdir_layers);
        r = sdir_out ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    }
    if (r == MESO_OK) {
        thick = malloc(sizeof(float) * (size_t)nv_out);
        r = thick ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
        for (uint32_t v = 0; thick && v < nv_out; ++v)
            thick[v] = (float)h;
    }
    if (r == MESO_OK) {
        meso_object_record rec = {.id = 1, .kind = MESO_OBJECT_SHELL};
        for (int k = 0; k < 3; ++k) {
            rec.bbox_min[k] = (float)lo[k];
            rec.bbox_max[k] = (float)hi[k];
        }
        for (size_t i = 0; i < (size_t)nv * (size_t)layers; ++i)
            for (int k = 0; k < 3; ++k) {
                const float x = m.positions[3 * (i % nv) + (size_t)k] + d[3 * i + (size_t)k];
                rec.bbox_min[k] = fminf(rec.bbox_min[k], x);
                rec.bbox_max[k] = fmaxf(rec.bbox_max[k], x);
            }
        snprintf(rec.name, sizeof(rec.name), "%s", base_name(a.in));

        meta = cJSON_CreateObject();
        cJSON_AddStringToObject(meta, "generator", "mesobake " MESO_VERSION_STRING);
        cJSON_AddStringToObject(meta, "command", "shell");
        cJSON* params = cJSON_AddObjectToObject(meta, "parameters");
        cJSON_AddNumberToObject(params, "thickness", h);
        cJSON_AddStringToObject(params, "kind", kind_names[a.kind]);
        cJSON_AddStringToObject(params, "directors", mode_names[a.mode]);
        cJSON_AddNumberToObject(params, "p", a.p);
        cJSON_AddNumberToObject(params, "theta", a.theta);
        cJSON_AddNumberToObject(params, "angle_tol_deg", a.angle_tol_deg);
        cJSON_AddNumberToObject(params, "smooth", (double)a.smooth);
        cJSON_AddBoolToObject(params, "repair", a.repair);
        if (a.texture)
            texture_json(params, &a, &tx, 0);
        r = add_input_provenance(cJSON_AddArrayToObject(meta, "inputs"), a.in, &err);
        uint32_t lp_count = 0;
        for (uint32_t v = 0; v < nv; ++v)
            lp_count += lp_mask[v];
        rep = report_json(&val, &hs_total, lp_count, shortened_total, nv, &ts, &fs);
        report_mesh_warnings(rep);
        if (a.texture)
            texture_json(rep, &a, &tx, 1);
        const int height = tx.fn.kind == MESO_TEXFN_HEIGHT;
        const bake_chunk chunks[5] = {
            {.desc = {.type = MESO_CHUNK_MESH, .flags = MESO_CHUNK_FLAG_REQUIRED, .object = 1,
                      .encoding = chunk.encoding, .decoded_size = chunk.decoded_size},
             .data = chunk.data, .size = chunk.size},
            {.desc = {.type = MESO_CHUNK_SDIR, .flags = MESO_CHUNK_FLAG_REQUIRED, .object = 1,
                      .dtype = MESO_DTYPE_F32, .components = 3, .dims = {nv_out, (uint32_t)sdir_layers, 1}},
             .data = sdir_out ? sdir_out : sdir, .size = sizeof(float) * 3 * (size_t)nv_out * (size_t)sdir_layers},
            {.desc = {.type = MESO_CHUNK_STHK, .object = 1, .dtype = MESO_DTYPE_F32, .components = 1,
                      .dims = {nv_out, 1, 1}},
             .data = thick, .size = sizeof(float) * (size_t)nv_out},
            /* The texture function and its distance map (object 1, lod 0). */
            {.desc = {.type = height ? MESO_CHUNK_TX2D : MESO_CHUNK_TX3D, .object = 1, .dtype = tx.fn.dtype,
                      .components = 1, .dims = {tx.fn.dims[0], tx.fn.dims[1], tx.fn.dims[2]}},
             .data = tx.fn.encoded, .size = tx.fn.encoded_size},
            {.desc = {.type = MESO_CHUNK_DIST, .object = 1, .dtype = tx.dist.dtype, .components = 1,
                      .dims = {tx.dist.dims[0], tx.dist.dims[1], tx.dist.dims[2]}},
             .data = tx.dist.encoded, .size = tx.dist.encoded_size},
        };
        if (r == MESO_OK)
            r = write_meso(a.out, meta, rep, &rec, chunks, a.texture ? 5 : 3, &file_size, &err);
    }
    const int code = finish_bake(r, &err, a.out, a.report, rep, file_size, t0);
    cJSON_Delete(meta);
    cJSON_Delete(rep);
    free(chunk.data);
    free(thick);
    free(pos_out);
    free(normals_out);
    free(sdir_out);
    if (sdir != d)
        free(sdir);
    texture_free(&tx);
    meso_lp_field_destroy(field);
    meso_field_surface_free(&fs);
    free(normals);
    free(d);
    free(lp_mask);
    free(lp_side);
    free(topo.boundary);
    meso_mesh_free(&m);
    return code;
}
