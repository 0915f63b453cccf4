/*
 * test_bake_api.c — libmeso_bake in-process (bake/meso_bake.h, the only
 * bake header included): mesh, shell (built-in textures), cells and frusta
 * bakes of tests/data files give the bytes `mesobake` writes with the same
 * options (the program is argv[1]); progress fractions never decrease and
 * end at 1; -v lines and warnings arrive through the callback (E3250 also in
 * the report); the library writes nothing to stdout or stderr; malformed
 * inputs are errors with a code and a message, and the process goes on; a
 * mesh in memory bakes to the file's chunks (all but META's provenance and
 * OBJT's name), and a broken one is refused as a broken file is.
 *
 * usage: test_bake_api MESOBAKE
 */
#undef NDEBUG
#include <assert.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "meso_bake.h"
#include "meso_file.h"

#include "defective_meshes.h"

static const char* mesobake;
static char dir[] = "/tmp/meso_bake_api_XXXXXX";

/* >>silence: the library must not write to stdout or stderr ---------------- */

static int saved_out = -1, saved_err = -1, capture = -1;

static void quiet_begin(void)
{
    char path[256];
    snprintf(path, sizeof path, "%s/captured", dir);
    fflush(stdout);
    fflush(stderr);
    capture = open(path, O_RDWR | O_CREAT | O_TRUNC, 0600);
    assert(capture >= 0);
    saved_out = dup(1);
    saved_err = dup(2);
    assert(saved_out >= 0 && saved_err >= 0);
    assert(dup2(capture, 1) == 1 && dup2(capture, 2) == 2);
}

static void quiet_end(const char* what)
{
    fflush(stdout);
    fflush(stderr);
    assert(dup2(saved_out, 1) == 1 && dup2(saved_err, 2) == 2);
    close(saved_out);
    close(saved_err);
    struct stat st;
    assert(fstat(capture, &st) == 0);
    close(capture);
    if (st.st_size != 0)
        fprintf(stderr, "FAIL: %s: the library wrote %lld bytes to stdout/stderr\n", what, (long long)st.st_size);
    assert(st.st_size == 0);
}

/* >>progress ------------------------------------------------------------------ */

typedef struct progress_log {
    int calls, stages, lines, ticks, warnings, decreased;
    double last;
    uint32_t warning_code;
} progress_log;

static void on_progress(void* user, const meso_bake_progress* p)
{
    progress_log* log = user;
    assert(p->fraction >= 0.0 && p->fraction <= 1.0);
    assert(p->stage && p->stage[0]);
    if (p->fraction < log->last)
        log->decreased = 1;
    log->last = p->fraction;
    log->calls++;
    if (p->event == MESO_BAKE_EVENT_STAGE) {
        log->stages++;
        log->lines += p->message != NULL;
    } else if (p->event == MESO_BAKE_EVENT_TICK) {
        log->ticks++;
        assert(p->done <= p->total);
    } else {
        assert(p->event == MESO_BAKE_EVENT_WARNING && p->message && p->message[0]);
        log->warnings++;
        log->warning_code = p->code;
    }
}

static void check_progress(const progress_log* log, const char* what)
{
    if (log->decreased || log->last != 1.0 || log->lines < 1)
        fprintf(stderr, "FAIL: %s: progress decreased %d, last %g, %d lines\n", what, log->decreased, log->last,
                log->lines);
    assert(!log->decreased && log->last == 1.0 && log->lines >= 1);
}

/* The common options of a bake that logs its progress into `log`. */
static meso_bake_common logged(progress_log* log, int threads)
{
    memset(log, 0, sizeof(*log));
    return (meso_bake_common){.threads = threads, .progress = on_progress, .user = log};
}

/* A bake call with stdout and stderr captured (they must stay empty). */
static meso_result quiet_result;
#define QUIET(what, call) (quiet_begin(), quiet_result = (call), quiet_end(what), quiet_result)

/* A bake that must succeed, with its progress as check_progress wants it. */
static void expect_baked(const char* what, meso_result r, const meso_bake_output* out, const progress_log* log,
                         const meso_error* err)
{
    if (r != MESO_OK)
        fprintf(stderr, "FAIL: %s: E%u %s\n", what, err->code, err->message);
    assert(r == MESO_OK && out);
    check_progress(log, what);
}

/* >>files ---------------------------------------------------------------------- */

static uint8_t* read_all(const char* path, size_t* size)
{
    FILE* f = fopen(path, "rb");
    assert(f);
    assert(fseek(f, 0, SEEK_END) == 0);
    const long n = ftell(f);
    assert(n >= 0);
    rewind(f);
    uint8_t* b = malloc((size_t)n + 1);
    assert(b && fread(b, 1, (size_t)n, f) == (size_t)n);
    fclose(f);
    *size = (size_t)n;
    return b;
}

/* mesobake COMMAND -i INPUT ARGS... -o OUT, its output silenced; returns
 * the exit code. */
static int run_cli(const char* out, const char* const* args)
{
    const char* argv[32];
    int n = 0;
    argv[n++] = mesobake;
    while (*args)
        argv[n++] = *args++;
    argv[n++] = "-o";
    argv[n++] = out;
    argv[n] = NULL;
    fflush(stdout);
    fflush(stderr);
    const pid_t pid = fork();
    assert(pid >= 0);
    if (pid == 0) {
        const int null = open("/dev/null", O_WRONLY);
        dup2(null, 1);
        dup2(null, 2);
        execv(mesobake, (char* const*)argv);
        _exit(127);
    }
    int status = 0;
    assert(waitpid(pid, &status, 0) == pid);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/* The output's bytes (through meso_bake_output_copy and, for the first
 * check, meso_bake_output_write_file) equal what the CLI wrote. */
static void same_as_cli(meso_bake_output* o, const char* name, const char* const* args)
{
    char cli[512], lib[512];
    snprintf(cli, sizeof cli, "%s/%s.cli.meso", dir, name);
    snprintf(lib, sizeof lib, "%s/%s.lib.meso", dir, name);
    assert(run_cli(cli, args) == 0);
    size_t cli_size = 0, needed = 0;
    uint8_t* want = read_all(cli, &cli_size);
    assert(meso_bake_output_copy(o, NULL, 0, &needed) == MESO_OK);
    assert(needed == meso_bake_output_size(o));
    uint8_t* got = malloc(needed);
    assert(got);
    assert(meso_bake_output_copy(o, got, needed - 1, &needed) == MESO_ERR_INVALID_ARG);
    assert(meso_bake_output_copy(o, got, needed, &needed) == MESO_OK);
    if (needed != cli_size || memcmp(got, want, needed) != 0)
        fprintf(stderr, "FAIL: %s: %zu bytes in-process, %zu from mesobake\n", name, needed, cli_size);
    assert(needed == cli_size && memcmp(got, want, needed) == 0);
    meso_error err = {0};
    assert(QUIET(name, meso_bake_output_write_file(o, lib, &err)) == MESO_OK);
    size_t lib_size = 0;
    uint8_t* written = read_all(lib, &lib_size);
    assert(lib_size == cli_size && memcmp(written, want, lib_size) == 0);
    assert(strstr(meso_bake_output_report_json(o), "{") == meso_bake_output_report_json(o));
    free(want);
    free(got);
    free(written);
    printf("  %-28s %zu bytes, same as mesobake\n", name, needed);
}

#define DATA(f) MESO_TEST_DATA "/" f

/* >>cases ---------------------------------------------------------------------- */

static void mesh_bakes_match_the_cli(void)
{
    for (int draco = 0; draco < 2; ++draco) {
        progress_log log;
        meso_bake_mesh_options o = meso_bake_mesh_defaults();
        o.input = DATA("spot_uv.obj");
        o.draco = draco;
        o.common = logged(&log, 0);
        meso_bake_mesh_report rep;
        meso_bake_output* out = NULL;
        meso_error err = {0};
        const meso_result r = QUIET("mesh", meso_bake_mesh(&o, &out, &rep, &err));
        expect_baked("mesh", r, out, &log, &err);
        assert(rep.vertices > 0 && rep.triangles > 0 && rep.has_uvs && rep.draco == draco);
        const char* raw[] = {"mesh", "-i", DATA("spot_uv.obj"), NULL};
        const char* dr[] = {"mesh", "-i", DATA("spot_uv.obj"), "--draco", NULL};
        same_as_cli(out, draco ? "mesh_draco" : "mesh", draco ? dr : raw);
        meso_bake_output_free(out);
    }
}

static void shell_bakes_match_the_cli(void)
{
    /* Bricks on a mesh with uvs; a cells volume on one without (the planar
     * projection's warning comes through the callback, not stderr). */
    const struct {
        const char *name, *input, *texture;
        double tiling;
        meso_shell_kind kind;
        meso_shell_directors directors;
        int warnings;
        const char* args[12];
    } cases[] = {
        {"shell_bricks", DATA("spot_uv.obj"), "bricks:64", 4, MESO_SHELL_EXTERIOR, MESO_DIRECTORS_HYBRID, 0,
         {"shell", "-i", DATA("spot_uv.obj"), "--texture", "bricks:64", "--tiling", "4", "-j", "2", NULL}},
        {"shell_cells_lp", DATA("torus.obj"), "cells:32", 1, MESO_SHELL_ENVELOPE, MESO_DIRECTORS_LP, 1,
         {"shell", "-i", DATA("torus.obj"), "--texture", "cells:32", "--kind", "envelope", "--directors", "lp", "-j",
          "2", NULL}},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        progress_log log;
        meso_bake_shell_options o = meso_bake_shell_defaults();
        o.input = cases[c].input;
        o.texture = cases[c].texture;
        o.tiling[0] = o.tiling[1] = cases[c].tiling;
        o.kind = cases[c].kind;
        o.directors = cases[c].directors;
        o.common = logged(&log, 2);
        meso_bake_shell_report rep;
        meso_bake_output* out = NULL;
        meso_error err = {0};
        const char* name = cases[c].name;
        const meso_result r = QUIET(name, meso_bake_shell(&o, &out, &rep, &err));
        expect_baked(name, r, out, &log, &err);
        assert(log.warnings == cases[c].warnings && rep.planar_uvs == cases[c].warnings);
        assert(rep.prisms == rep.triangles && rep.thickness > 0 && rep.dist_res[0] > 0);
        assert(rep.vertices_lp + rep.vertices_normal == rep.vertices);
        assert(cases[c].directors != MESO_DIRECTORS_LP || log.ticks > 0); /* tracing reports progress */
        same_as_cli(out, cases[c].name, cases[c].args);
        meso_bake_output_free(out);
    }
}

static void cells_bake_matches_the_cli(void)
{
    progress_log log;
    meso_bake_cells_options o = meso_bake_cells_defaults();
    o.input = DATA("torus.obj");
    o.tiles = 4;
    o.tile_res = 16;
    o.common = logged(&log, 2);
    meso_bake_cells_report rep;
    meso_bake_output* out = NULL;
    meso_error err = {0};
    const meso_result r = QUIET("cells", meso_bake_cells(&o, &out, &rep, &err));
    expect_baked("cells", r, out, &log, &err);
    assert(rep.tile_res == 16 && rep.cells_intersected > 0 && rep.split_cells > 0 && rep.memory_estimate > 0);
    assert(rep.tiles == (uint64_t)rep.tiles_per_axis[0] * rep.tiles_per_axis[1] * rep.tiles_per_axis[2]);
    const char* args[] = {"cells", "-i", DATA("torus.obj"), "--tiles", "4", "--tile-res", "16", "-j", "2", NULL};
    same_as_cli(out, "cells", args);
    meso_bake_output_free(out);
}

static void frusta_bakes_match_the_cli(void)
{
    for (int relief = 0; relief < 2; ++relief) {
        progress_log log;
        meso_bake_frusta_options o = meso_bake_frusta_defaults();
        o.input = relief ? DATA("saguaro.skel") : DATA("neurom_simple.swc");
        o.relief = relief ? "bricks:64" : NULL;
        o.common = logged(&log, 0);
        meso_bake_frusta_report rep;
        meso_bake_output* out = NULL;
        meso_error err = {0};
        const meso_result r = QUIET("frusta", meso_bake_frusta(&o, &out, &rep, &err));
        expect_baked("frusta", r, out, &log, &err);
        assert(rep.segments > 0 && !strcmp(rep.skeleton.input, relief ? "text" : "swc"));
        assert((rep.relief_depth > 0) == relief);
        const char* plain[] = {"frusta", "-i", DATA("neurom_simple.swc"), NULL};
        const char* rel[] = {"frusta", "-i", DATA("saguaro.skel"), "--relief", "bricks:64", NULL};
        same_as_cli(out, relief ? "frusta_relief" : "frusta", relief ? rel : plain);
        meso_bake_output_free(out);
    }
    /* The skeleton alone, then baked as it is: the bytes of a bake of its
     * file (an SWC, and one extracted from a mesh with its fit). */
    const char* inputs[] = {DATA("neurom_simple.swc"), DATA("torus.obj")};
    for (int k = 0; k < 2; ++k) {
        meso_bake_skeleton* sk = NULL;
        meso_bake_skeleton_info info;
        meso_error err = {0};
        assert(QUIET("skeleton", meso_bake_skeleton_load(inputs[k], 0, NULL, &sk, &info, &err)) == MESO_OK);
        assert(sk && info.node_count > 1 && info.root_count >= 1 && !strcmp(info.input, k ? "mesh" : "swc"));
        meso_bake_frusta_options o = meso_bake_frusta_defaults();
        o.skeleton = sk;
        meso_bake_output* out = NULL;
        assert(QUIET("frusta from a loaded skeleton", meso_bake_frusta(&o, &out, NULL, &err)) == MESO_OK);
        const char* args[] = {"frusta", "-i", inputs[k], NULL};
        same_as_cli(out, k ? "frusta_loaded_mesh" : "frusta_loaded_swc", args);
        meso_bake_output_free(out);
        o.input = inputs[k]; /* both at once is an argument error */
        assert(meso_bake_frusta(&o, &out, NULL, &err) == MESO_ERR_INVALID_ARG && !out);
        meso_bake_skeleton_free(sk);
    }
}

/* A closed cube whose faces all point inward: turned outward with warning
 * E3250, through the callback and into the report. */
static void inside_out_mesh_is_a_warning(void)
{
    dm_mesh m = {0};
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    dm_box_faces(&m, lo, hi, 2, 0);
    dm_weld(&m);
    for (uint32_t f = 0; f < m.nf; ++f) {
        const uint32_t t = m.f[3 * f + 1];
        m.f[3 * f + 1] = m.f[3 * f + 2];
        m.f[3 * f + 2] = t;
    }
    char path[512];
    snprintf(path, sizeof path, "%s/inside_out.obj", dir);
    assert(dm_write_obj(path, &m));
    dm_free(&m);
    progress_log log;
    meso_bake_mesh_options o = meso_bake_mesh_defaults();
    o.input = path;
    o.common = logged(&log, 0);
    meso_bake_mesh_report rep;
    meso_bake_output* out = NULL;
    meso_error err = {0};
    const meso_result r = QUIET("inside-out", meso_bake_mesh(&o, &out, &rep, &err));
    expect_baked("inside-out", r, out, &log, &err);
    assert(log.warnings == 1 && log.warning_code == MESO_BAKE_ISSUE_REORIENTED);
    assert(rep.fixes.reoriented_components == 1);
    assert(strstr(meso_bake_output_report_json(out), "\"E3250: 1 inside-out closed components"));
    meso_bake_output_free(out);
}

/* Malformed inputs: an error code and a message naming the file; the
 * process goes on (no exit). */
/* >>meshes in memory ---------------------------------------------------------- */

/* Every chunk of `a` equals `b`'s but META (provenance) and OBJT (the name);
 * returns the number of chunks compared. */
static uint32_t same_chunks_but_provenance(meso_bake_output* a, meso_bake_output* b)
{
    size_t na = 0, nb = 0;
    assert(meso_bake_output_copy(a, NULL, 0, &na) == MESO_OK && meso_bake_output_copy(b, NULL, 0, &nb) == MESO_OK);
    uint8_t *ba = malloc(na), *bb = malloc(nb);
    assert(ba && bb && meso_bake_output_copy(a, ba, na, &na) == MESO_OK && meso_bake_output_copy(b, bb, nb, &nb) == MESO_OK);
    meso_file *fa = NULL, *fb = NULL;
    meso_error err = {0};
    assert(meso_file_open_memory(ba, na, NULL, &fa, &err) == MESO_OK);
    assert(meso_file_open_memory(bb, nb, NULL, &fb, &err) == MESO_OK);
    assert(meso_file_chunk_count(fa) == meso_file_chunk_count(fb));
    uint32_t compared = 0;
    for (uint32_t i = 0; i < meso_file_chunk_count(fa); ++i) {
        const meso_chunk_info *ca = meso_file_chunk(fa, i), *cb = meso_file_chunk(fb, i);
        assert(ca->type == cb->type && ca->object == cb->object);
        if (ca->type == MESO_CHUNK_META || ca->type == MESO_CHUNK_OBJT)
            continue;
        const void *da = NULL, *db = NULL;
        assert(ca->stored_size == cb->stored_size);
        assert(meso_file_chunk_view(fa, i, &da, &err) == MESO_OK && meso_file_chunk_view(fb, i, &db, &err) == MESO_OK);
        assert(memcmp(da, db, (size_t)ca->stored_size) == 0);
        compared++;
    }
    int32_t meta = meso_file_find(fa, MESO_CHUNK_META, 0, 0);
    const void* md = NULL;
    assert(meta >= 0 && meso_file_chunk_view(fa, (uint32_t)meta, &md, &err) == MESO_OK);
    const size_t ml = (size_t)meso_file_chunk(fa, (uint32_t)meta)->stored_size;
    char* mtext = malloc(ml + 1);
    assert(mtext);
    memcpy(mtext, md, ml);
    mtext[ml] = 0;
    assert(strstr(mtext, "\"name\":\"(memory)\""));
    free(mtext);
    meso_file_close(fa);
    meso_file_close(fb);
    free(ba);
    free(bb);
    return compared;
}

/* Keeps the last warning's text (a char[512] as `user`). */
static void warning_text(void* user, const meso_bake_progress* p)
{
    if (p->event == MESO_BAKE_EVENT_WARNING && p->message)
        snprintf((char*)user, 512, "%s", p->message);
}

/* A host's mesh in memory bakes to the same chunks as the file it came from,
 * for every command that takes a mesh; and a broken one is refused as a
 * broken file is, with a code naming "(memory)". */
static void memory_meshes_bake_as_files(void)
{
    meso_mesh m;
    meso_error err = {0};
    assert(meso_bake_load_mesh(DATA("spot_uv.obj"), NULL, &m, NULL, &err) == MESO_OK);
    meso_bake_output *from_file = NULL, *from_memory = NULL;

    meso_bake_mesh_options mo = meso_bake_mesh_defaults();
    mo.input = DATA("spot_uv.obj");
    assert(QUIET("mesh file", meso_bake_mesh(&mo, &from_file, NULL, &err)) == MESO_OK);
    mo.input = NULL;
    mo.mesh = &m;
    assert(QUIET("mesh memory", meso_bake_mesh(&mo, &from_memory, NULL, &err)) == MESO_OK);
    assert(same_chunks_but_provenance(from_memory, from_file) >= 2);
    meso_bake_output_free(from_file);
    meso_bake_output_free(from_memory);

    meso_bake_shell_options so = meso_bake_shell_defaults();
    so.input = DATA("spot_uv.obj");
    so.texture = "bricks:64";
    so.tiling[0] = so.tiling[1] = 4;
    so.common.threads = 2;
    assert(QUIET("shell file", meso_bake_shell(&so, &from_file, NULL, &err)) == MESO_OK);
    so.input = NULL;
    so.mesh = &m;
    assert(QUIET("shell memory", meso_bake_shell(&so, &from_memory, NULL, &err)) == MESO_OK);
    assert(same_chunks_but_provenance(from_memory, from_file) >= 6); /* RPRT MESH SDIR STHK TX2D DIST */
    meso_bake_output_free(from_file);
    meso_bake_output_free(from_memory);
    so.input = DATA("spot_uv.obj"); /* both at once is an argument error */
    assert(meso_bake_shell(&so, &from_memory, NULL, &err) == MESO_ERR_INVALID_ARG && !from_memory);
    meso_mesh_free(&m);
    /* Without uvs (projected onto a plane, with a warning naming the
     * input: "(memory)"; it once named a NULL path and crashed). */
    assert(meso_bake_load_mesh(DATA("sphere.obj"), NULL, &m, NULL, &err) == MESO_OK && !m.uvs);
    so = meso_bake_shell_defaults();
    so.input = DATA("sphere.obj");
    so.texture = "bricks:16";
    assert(QUIET("shell file, no uvs", meso_bake_shell(&so, &from_file, NULL, &err)) == MESO_OK);
    so.input = NULL;
    so.mesh = &m;
    char said[512] = "";
    so.common.progress = warning_text;
    so.common.user = said;
    assert(QUIET("shell memory, no uvs", meso_bake_shell(&so, &from_memory, NULL, &err)) == MESO_OK);
    assert(strncmp(said, "(memory) has no texture coordinates", 35) == 0);
    assert(same_chunks_but_provenance(from_memory, from_file) >= 6);
    meso_bake_output_free(from_file);
    meso_bake_output_free(from_memory);
    meso_mesh_free(&m);

    assert(meso_bake_load_mesh(DATA("torus.obj"), NULL, &m, NULL, &err) == MESO_OK);
    meso_bake_cells_options co = meso_bake_cells_defaults();
    co.input = DATA("torus.obj");
    co.tiles = 3;
    co.tile_res = 8;
    assert(QUIET("cells file", meso_bake_cells(&co, &from_file, NULL, &err)) == MESO_OK);
    co.input = NULL;
    co.mesh = &m;
    assert(QUIET("cells memory", meso_bake_cells(&co, &from_memory, NULL, &err)) == MESO_OK);
    assert(same_chunks_but_provenance(from_memory, from_file) >= 7);
    meso_bake_output_free(from_file);
    meso_bake_output_free(from_memory);

    /* Broken in memory: what the readers and the guard refuse in a file. */
    float nan_pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    nan_pos[4] = NAN;
    uint32_t tri[3] = {0, 1, 2}, missing[3] = {0, 1, 7};
    const meso_mesh bad[] = {
        {.vertex_count = 3, .triangle_count = 1, .positions = nan_pos, .indices = tri},
        {.vertex_count = 3, .triangle_count = 1, .positions = m.positions, .indices = missing},
        {.vertex_count = 3, .triangle_count = 0, .positions = m.positions, .indices = tri},
    };
    const uint32_t codes[] = {3101, 3102, 3252};
    for (int k = 0; k < 3; ++k) {
        mo = meso_bake_mesh_defaults();
        mo.mesh = &bad[k];
        memset(&err, 0, sizeof err);
        from_memory = NULL;
        assert(QUIET("broken memory mesh", meso_bake_mesh(&mo, &from_memory, NULL, &err)) == MESO_ERR_CORRUPT);
        printf("  memory mesh %d: E%u %s\n", k, err.code, err.message);
        assert(!from_memory && err.code == codes[k] && strstr(err.message, "(memory)"));
    }
    /* Two faces sharing an edge the same way (a flipped neighbour). */
    const float quad[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    const uint32_t flipped[6] = {0, 1, 2, 0, 1, 3};
    const meso_mesh mis = {.vertex_count = 4, .triangle_count = 2, .positions = (float*)quad, .indices = (uint32_t*)flipped};
    mo = meso_bake_mesh_defaults();
    mo.mesh = &mis;
    assert(QUIET("misoriented memory mesh", meso_bake_mesh(&mo, &from_memory, NULL, &err)) == MESO_ERR_CORRUPT);
    assert(err.code == 3111);
    meso_mesh_free(&m);
}

static void malformed_inputs_are_errors(void)
{
    char bad[512], doubled[512];
    snprintf(bad, sizeof bad, "%s/bad.obj", dir);
    snprintf(doubled, sizeof doubled, "%s/doubled.obj", dir);
    FILE* f = fopen(bad, "w");
    assert(f);
    fputs("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", f); /* a face on a vertex that does not exist */
    fclose(f);
    dm_mesh m = dm_doubled_faces();
    assert(dm_write_obj(doubled, &m));
    dm_free(&m);

    meso_error err = {0};
    meso_bake_output* out = NULL;
    meso_bake_mesh_options mo = meso_bake_mesh_defaults();
    mo.input = bad;
    meso_result r = QUIET("bad mesh", meso_bake_mesh(&mo, &out, NULL, &err));
    printf("  bad.obj: E%u %s\n", err.code, err.message);
    assert(r != MESO_OK && out == NULL && err.code != 0 && strstr(err.message, "bad.obj"));

    meso_bake_shell_options so = meso_bake_shell_defaults();
    so.input = doubled;
    memset(&err, 0, sizeof err);
    r = QUIET("doubled faces", meso_bake_shell(&so, &out, NULL, &err));
    printf("  doubled.obj: E%u %s\n", err.code, err.message);
    assert(r == MESO_ERR_CORRUPT && out == NULL && err.code >= 3100 && err.code < 3300 && err.message[0]);

    so.input = DATA("sphere.obj");
    so.texture = "nonsense:3";
    memset(&err, 0, sizeof err);
    r = QUIET("bad texture", meso_bake_shell(&so, &out, NULL, &err));
    assert(r != MESO_OK && err.code == 3120 && strstr(err.message, "nonsense"));
    meso_bake_texture_info ti;
    assert(meso_bake_texture_probe("nonsense:3", NULL, &ti, &err) != MESO_OK && err.code == 3120);
    assert(meso_bake_texture_probe("weave:16", NULL, &ti, &err) == MESO_OK && ti.density && ti.dims[2] == 8);

    so.texture = NULL;
    so.p = 40; /* out of range: an argument error, not a crash */
    assert(meso_bake_shell(&so, &out, NULL, &err) == MESO_ERR_INVALID_ARG);
    so.p = 0;
    so.parts = 63; /* parts below 64 triangles: refused with the options, before any work */
    memset(&err, 0, sizeof err);
    assert(meso_bake_shell(&so, &out, NULL, &err) == MESO_ERR_INVALID_ARG && !out && strstr(err.message, "parts"));
    so.parts = 0;
    mo = meso_bake_mesh_defaults();
    mo.input = DATA("sphere.obj");
    mo.parts = 63;
    memset(&err, 0, sizeof err);
    assert(QUIET("mesh parts 63", meso_bake_mesh(&mo, &out, NULL, &err)) == MESO_ERR_INVALID_ARG && !out &&
           strstr(err.message, "parts"));

    meso_mesh mesh;
    r = QUIET("missing file", meso_bake_load_mesh(DATA("nonexistent.obj"), NULL, &mesh, NULL, &err));
    assert(r == MESO_ERR_IO && err.code != 0 && mesh.vertex_count == 0);
    assert(meso_bake_load_mesh(DATA("sphere.obj"), NULL, &mesh, NULL, &err) == MESO_OK && mesh.triangle_count > 0);
    meso_mesh_free(&mesh);
}

int main(int argc, char** argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: %s MESOBAKE\n", argv[0]);
        return 2;
    }
    mesobake = argv[1];
    assert(mkdtemp(dir));
    assert(!strcmp(meso_bake_directors_name(MESO_DIRECTORS_LP), "lp"));
    assert(!strcmp(meso_bake_shell_kind_name(MESO_SHELL_ENVELOPE), "envelope"));
    assert(meso_bake_directors_name(MESO_DIRECTORS_COUNT) == NULL);
    mesh_bakes_match_the_cli();
    shell_bakes_match_the_cli();
    cells_bake_matches_the_cli();
    frusta_bakes_match_the_cli();
    inside_out_mesh_is_a_warning();
    malformed_inputs_are_errors();
    memory_meshes_bake_as_files();
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    assert(system(cmd) == 0);
    printf("bake API: in-process bakes equal mesobake's bytes\n");
    return 0;
}
