/*
 * bake_shell.c — meso_bake_shell (`mesobake shell`): a base mesh plus
 * fold-free directors (volume-textures-lp-averaged-shells.md §4), validated
 * exactly, in one .meso SHELL object: MESH (the base), SDIR (directors),
 * STHK (thickness), and optionally a texture function (TX2D height field or
 * TX3D density) with its distance map (DIST) and texture coordinates in the
 * MESH (FORMAT.md §7.2, "Shell prisms and texture space"; the texture part
 * is bake_shell_texture.c).
 */
#include "bake_shell.h"
#include "shell_color.h"
#include "meso_layout.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifndef __STDC_NO_THREADS__
#include <threads.h>
#endif

#include <cjson/cJSON.h>

#include "adapters.h"
#include "bake_threads.h"
#include "lp_distance.h"
#include "mesh_check.h"
#include "mesh_chunk.h"
#include "meso_clock.h"
#include "shell_allowed.h"
#include "shell_base_levels.h"
#include "shell_bend.h"
#include "shell_envelope.h"
#include "shell_hybrid.h"
#include "shell_regrow.h"
#include "shell_update.h"
#include "shell_validate.h"
#include "shell_parts.h"
#include "standin_levels.h"
#include "volume_levels.h"
#include "surface_distance.h"

_Static_assert(MESO_BAKE_SHELL_MAX_LEVELS == MESOI_STANDIN_MAX_LEVELS, "the stand-ins hold every level");
_Static_assert(1 + MESOI_HEIGHT_MAX_NATIVE + 1 <= MESOI_STANDIN_MAX_LEVELS, "room for the base mesh stand-in");

meso_bake_shell_options meso_bake_shell_defaults(void)
{
    return (meso_bake_shell_options){.thickness_rel = 0.05, .p = 3.0, .theta = 0.5, .angle_tol_deg = 5.0,
                                     .tiling = {1.0, 1.0}, .dist_dtype = MESO_DTYPE_U8};
}

/* Zeroes to their defaults (theta excepted: 0 is exact summation), then the
 * ranges mesobake shell's options have. */
static meso_result normalise(const meso_bake_shell_options* o, meso_bake_shell_options* a, meso_error* err)
{
    *a = *o;
    if (!a->thickness_rel)
        a->thickness_rel = 0.05;
    if (!a->p)
        a->p = 3.0;
    if (!a->angle_tol_deg)
        a->angle_tol_deg = 5.0;
    for (int k = 0; k < 2; ++k)
        if (!a->tiling[k])
            a->tiling[k] = 1.0;
    if (!a->dist_dtype)
        a->dist_dtype = MESO_DTYPE_U8;
    const char* bad = !a->input && !a->mesh                                       ? "no input mesh given"
                      : (unsigned)a->kind >= MESO_SHELL_KIND_COUNT                ? "kind out of range"
                      : (unsigned)a->directors >= MESO_DIRECTORS_COUNT            ? "directors out of range"
                      : !(a->thickness >= 0 && a->thickness < 1e30)               ? "thickness must be >= 0"
                      : !(a->thickness_rel > 0 && a->thickness_rel <= 10)         ? "thickness_rel must be in (0, 10]"
                      : !(a->p > 2.0 && a->p <= MESO_BAKE_MAX_P)                  ? "p must be in (2, 16]"
                      : !(a->theta >= 0 && a->theta <= 1.5)                       ? "theta must be in [0, 1.5]"
                      : !(a->angle_tol_deg > 0 && a->angle_tol_deg <= 90)         ? "angle_tol_deg must be in (0, 90]"
                      : a->smooth < 0 || a->smooth > 1000                         ? "smooth must be in 0..1000"
                      : a->levels < 0 || a->levels > MESO_BAKE_SHELL_MAX_LEVELS    ? "levels must be in 0..9"
                      : a->parts < -1 || (a->parts > 0 && a->parts < 64)
                          ? "parts must be 0 (auto), -1 (none) or a triangle count of at least 64"
                      : !(a->tiling[0] > 0 && a->tiling[0] <= 1e6 && a->tiling[1] > 0 && a->tiling[1] <= 1e6)
                          ? "tiling must be in (0, 1e6]"
                      : a->dist_dtype != MESO_DTYPE_U8 && a->dist_dtype != MESO_DTYPE_U16 &&
                              a->dist_dtype != MESO_DTYPE_F32
                          ? "dist_dtype must be U8, U16 or F32"
                          : NULL;
    const double period = meso_texfn_period(a->texture);
    if (a->frames && !a->fps && period > 0)
        a->fps = a->frames / period;
    if (!bad && (a->time != 0 || a->frames || a->fps) && !(period > 0))
        bad = "time, frames and fps need a time-dependent texture (boil)";
    else if (!bad && !(a->time >= -1e6 && a->time <= 1e6))
        bad = "time must be in [-1e6, 1e6] seconds";
    else if (!bad && (a->frames > MESO_BAKE_MAX_FRAMES || (a->fps && !a->frames)))
        bad = "frames must be in 1..256 (fps needs frames)";
    else if (!bad && a->frames && !(a->fps > 0 && a->fps <= 1000))
        bad = "fps must be in (0, 1000]";
    for (int k = 0; !bad && k < 3; ++k)
        if (a->dist_res[k] > MESO_BAKE_MAX_DIST_RES || (!a->dist_res[k]) != (!a->dist_res[0]))
            bad = "dist_res must be 0, 0, 0 or each in 1..512";
    if (!bad && !a->texture &&
        (a->dist_res[0] || a->dist_dtype != MESO_DTYPE_U8 || a->tiling[0] != 1.0 || a->tiling[1] != 1.0))
        bad = "tiling, dist_res and dist_dtype need a texture";
    if (!bad && a->color && !a->texture)
        bad = "color needs a texture (its texture space)";
    return bad ? meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "shell options: %s", bad) : MESO_OK;
}

static void report_json(cJSON* rep, const meso_bake_shell_report* s)
{
    cJSON_AddNumberToObject(rep, "prisms", s->prisms);
    cJSON_AddNumberToObject(rep, "inverted_prisms", s->inverted_prisms);
    cJSON_AddNumberToObject(rep, "undecided_prisms", s->undecided_prisms);
    cJSON_AddNumberToObject(rep, "offset_self_intersections", (double)s->offset_self_intersections);
    cJSON_AddNumberToObject(rep, "offset_base_intersections", (double)s->offset_base_intersections);
    cJSON_AddNumberToObject(rep, "thickness_ratio_min", s->thickness_ratio_min);
    cJSON_AddNumberToObject(rep, "thickness_ratio_mean", s->thickness_ratio_mean);
    cJSON_AddNumberToObject(rep, "allowed_ratio_min", s->allowed_ratio_min);
    cJSON_AddNumberToObject(rep, "allowed_ratio_mean", s->allowed_ratio_mean);
    cJSON_AddNumberToObject(rep, "vertices_below_half_allowed", s->vertices_below_half_allowed);
    cJSON_AddNumberToObject(rep, "vertices_allowed_below_requested", s->vertices_allowed_below_requested);
    cJSON_AddNumberToObject(rep, "vertices_regrown", s->vertices_regrown);
    cJSON_AddNumberToObject(rep, "vertices_bent", s->vertices_bent);
    cJSON_AddNumberToObject(rep, "vertices_lp", s->vertices_lp);
    cJSON_AddNumberToObject(rep, "vertices_normal", s->vertices_normal);
    cJSON_AddNumberToObject(rep, "hybrid_rounds", s->hybrid_rounds);
    cJSON_AddNumberToObject(rep, "vertices_shortened", s->vertices_shortened);
    cJSON_AddNumberToObject(rep, "field_evaluations", (double)s->field_evaluations);
    cJSON_AddNumberToObject(rep, "artificial_faces", s->artificial_faces);
    if (s->vertices_recomputed || s->vertices_moved || s->update_radius > 0) {
        cJSON* u = cJSON_AddObjectToObject(rep, "update");
        cJSON_AddNumberToObject(u, "vertices_moved", s->vertices_moved);
        cJSON_AddNumberToObject(u, "vertices_recomputed", s->vertices_recomputed);
        cJSON_AddNumberToObject(u, "radius", s->update_radius);
        cJSON_AddNumberToObject(u, "moved_max", s->update_moved_max);
        cJSON_AddNumberToObject(u, "levels_kept", s->update_levels_kept);
        cJSON_AddNumberToObject(u, "chain_moved", s->update_chain_moved);
        cJSON_AddNumberToObject(u, "field_unsplit_opened", (double)s->update_field_unsplit);
    }
}

/* The input's self-intersection check (CGAL, one thread: its Parallel_tag
 * was slower, shell_bend.h) needs nothing the directors make and they need
 * nothing from it but its verdict. With more than one thread it runs on a
 * thread of its own from the moment the topology is known, beside the
 * texture coordinates, the field's construction (one thread) and the first
 * side's tracing, and is joined before repair (input_check_join): at 106k
 * triangles the 0.25 s check and the 0.17 s field took 0.42 s one after
 * the other. A self-intersecting input fails with the same error as with
 * one thread (E3114, also when something after it failed first:
 * meso_bake_shell), after the tracing. */
typedef struct input_check {
    const meso_mesh* m;
    const char* path;
    double seconds;
    meso_error err;
    meso_result r;
    int state; /* 0: not started (or done inline); 1: running on its thread; 2: joined */
#ifndef __STDC_NO_THREADS__
    thrd_t thread;
#endif
} input_check;

static meso_result input_check_run_in(input_check* c, meso_error* err)
{
    const double t = meso_seconds();
    meso_result r = MESO_OK;
#if MESO_HAVE_CGAL
    const meso_mesh* m = c->m;
    const uint32_t nv = m->vertex_count;
    double* xyz = malloc(sizeof(double) * 3 * (size_t)nv);
    meso_cgal_intersection_count n = {0, 0, 0};
    r = xyz ? MESO_OK : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "input check: out of memory");
    for (size_t i = 0; xyz && i < 3 * (size_t)nv; ++i)
        xyz[i] = m->positions[i];
    if (r == MESO_OK)
        r = meso_cgal_self_intersections(xyz, nv, m->indices, m->triangle_count, &n, err);
    free(xyz);
    if (r == MESO_OK && n.pairs)
        r = meso_bake_fail(err, MESO_ERR_CORRUPT, 3114,
                           "%s: the surface intersects itself (%llu triangle pairs); no shell over it can be "
                           "valid — repair the mesh first",
                           c->path, (unsigned long long)n.pairs);
#else
    (void)err;
#endif
    c->seconds = meso_seconds() - t;
    return r;
}

static int input_check_thread(void* arg)
{
    input_check* c = arg;
    c->r = input_check_run_in(c, &c->err);
    return 0;
}

/* The verdict: waits for the thread, or runs the check here if it was not
 * started on one. Idempotent; `err` may be NULL. */
static meso_result input_check_join(input_check* c, meso_bake_shell_report* rep, meso_error* err)
{
    if (!c->m)
        return MESO_OK; /* nothing to check (an update) */
#ifndef __STDC_NO_THREADS__
    if (c->state == 1)
        thrd_join(c->thread, NULL);
#endif
    if (c->state == 0)
        c->r = input_check_run_in(c, &c->err);
    c->state = 2;
    rep->seconds_check = c->seconds;
    if (c->r != MESO_OK && err)
        *err = c->err;
    return c->r;
}

/* Refuse what no shell can be built on: the topology (mesh_check.h), at
 * once, and with CGAL a surface that intersects itself, by the input check
 * run or started here (an update tests only the pairs its edit touched, once OLD
 * is read: mesoi_shell_update_base_check; `whole` 0). */
static meso_result require_shellable(const meso_mesh* m, const char* path, double diag, int whole, int threads,
                                     meso_mesh_topology* topo, input_check* check, meso_bake_shell_report* rep,
                                     meso_error* err)
{
    double t = meso_seconds();
    meso_result r = meso_mesh_topology_compute(m, 1e-14 * diag * diag, topo, err);
    if (r == MESO_OK)
        r = meso_mesh_topology_require_shellable(topo, path, err);
    rep->seconds_topology = meso_seconds() - t;
    if (r != MESO_OK || !whole || !MESO_HAVE_CGAL)
        return r;
    check->m = m;
    check->path = path;
#ifndef __STDC_NO_THREADS__
    if (meso_bake_thread_count(threads) >= 2 && thrd_create(&check->thread, input_check_thread, check) == thrd_success)
        check->state = 1;
#else
    (void)threads;
#endif
    return check->state ? MESO_OK : input_check_join(check, rep, err); /* one thread: here, as before */
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

/* The stand-in chain (the simplified base meshes of levels 2..) depends on
 * the base mesh only: e0, which every level adds to its own error, is not
 * known before the directors are final, so the chain samples its own
 * errors at a quarter of the thickness the directors may reach (e0_sampling:
 * the highest texel times the side's thickness; e0 itself is that or less,
 * less where repair shortened every longest director) and e0 is added when
 * the levels are stored. With more than one thread the chain is built on a
 * thread of its own from the moment the first side's directors are traced
 * (standin_begin): repair, regrow and bend that follow keep one core busy
 * most of the time. Joined in assemble(); built there with one thread: the
 * same bytes. At 106k triangles the wait in assemble went from 0.32 to
 * 0.01 s. Started after the directors instead (until this change, with the
 * chain sampled at e0) it overlapped only validation; started with the
 * normals, before tracing, it was no faster (3.29 against 3.45 s, medians of
 * 3): tracing keeps both cores busy. An update starts it after the
 * directors, as before: whether OLD's chain is kept needs e0. */
typedef struct standin_job {
    meso_mesh base;         /* the base mesh as its MESH chunk has it (shell_base) */
    float *pos, *normals;   /* base's own arrays when seam vertices are added */
    double e0_sampling;     /* sets the chain's sample spacing (above) */
    int levels, threads;
    mesoi_standin_levels out;
    meso_error err;
    meso_result r;
    int state;              /* 0: not started; 1: running on its thread; 2: built; 3: not to be started (assemble builds it) */
#ifndef __STDC_NO_THREADS__
    thrd_t thread;
#endif
} standin_job;

/* One shell bake's buffers, freed together by shell_free. */
typedef struct shell_bake {
    meso_bake_shell_options a; /* the options, defaults filled in */
    mesoi_bake_run run;
    meso_bake_shell_report* rep;
    mesoi_shell_texture tx;
    mesoi_shell_color col;     /* --color: dims 0 when none */
    meso_mesh_materials mats;  /* --color from-mesh: the input's materials */
    meso_mesh m;
    meso_mesh_topology topo;
    double lo[3], hi[3], h;
    float* normals;
    float* d;         /* directors: layers x 3 nv (envelope: top, then bottom) */
    double* allowed;  /* shell_allowed.h per layer (layers x nv), once computed */
    uint8_t* allowed_done; /* per layer */
    uint8_t *lp_mask, *lp_side;
    meso_field_surface fs;
    meso_lp_field* field;
    int field_all;           /* the field's tree is whole, not built for a region (field_for) */
    double field_box[6];     /* else the region it was built for */
    mesoi_shell_prior prior; /* --update: the old bake's directors and the region to redo */
    standin_job chain;       /* levels 2..: built beside repair and validation (standin_job) */
    float e0;                /* level 1's error (standin_error), once the directors are final */
    int keep_chain;          /* an update keeps OLD's chain (chain_kept) */
    input_check check;       /* the input's self-intersection check (require_shellable) */
} shell_bake;

static void standin_job_join(standin_job* j)
{
#ifndef __STDC_NO_THREADS__
    if (j->state == 1) {
        thrd_join(j->thread, NULL);
        j->state = 2;
    }
#else
    (void)j;
#endif
}

static void shell_free(shell_bake* s)
{
    standin_job_join(&s->chain);
    mesoi_standin_levels_free(&s->chain.out);
    free(s->chain.pos);
    free(s->chain.normals);
    mesoi_shell_texture_free(&s->tx);
    mesoi_shell_color_free(&s->col);
    meso_mesh_materials_free(&s->mats);
    meso_lp_field_destroy(s->field);
    meso_field_surface_free(&s->fs);
    free(s->normals);
    free(s->d);
    free(s->allowed);
    free(s->allowed_done);
    free(s->lp_mask);
    free(s->lp_side);
    free(s->topo.boundary);
    mesoi_shell_prior_free(&s->prior);
    meso_mesh_free(&s->m);
}

/* The thickness the geometry allows for one side (shell_allowed.h), into
 * s->allowed's layer, computed once. */
static meso_result allowed_side(shell_bake* s, int layer, int sign, double h_side, meso_error* err)
{
    const uint32_t nv = s->m.vertex_count;
    const int layers = s->a.kind == MESO_SHELL_ENVELOPE ? 2 : 1;
    if (!s->allowed) {
        s->allowed = malloc(sizeof(double) * (nv ? nv : 1) * (size_t)layers);
        s->allowed_done = calloc((size_t)layers, 1);
        if (!s->allowed || !s->allowed_done)
            return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "allowed thickness: out of memory");
    }
    if (s->allowed_done[layer])
        return MESO_OK;
    const double t = meso_seconds();
    meso_result r = meso_shell_allowed(&s->m, s->normals, sign, h_side, s->run.common.threads,
                                       s->allowed + (size_t)nv * (size_t)layer, err);
    s->allowed_done[layer] = r == MESO_OK;
    s->rep->seconds_allowed += meso_seconds() - t;
    return r;
}

/* Directors for each side (the Lp field, hybrid or normal), repaired unless
 * asked not to. Exterior: layer 0 along +n. Interior: layer 0 along -n.
 * Envelope: layer 0 (top) along +n, layer 1 (bottom) along -n. */
static void standin_begin(shell_bake* s);

/* The field for the pass about to run: redo NULL, every vertex (the whole
 * tree); else only redo's vertices are traced, and every evaluation of a
 * trace lies within h_side of its vertex (shell_directors.c), so the tree
 * is built for the box of those balls (lp_distance.h, >>regions: the same
 * bits there as the whole tree's, for a fraction of its build on a small
 * edit). Built again only when a grown region leaves the box. */
static meso_result field_for(shell_bake* s, const uint8_t* redo, double h_side, meso_error* err)
{
    const meso_mesh* m = &s->m;
    double box[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
    for (uint32_t v = 0; redo && v < m->vertex_count; ++v)
        for (int k = 0; redo[v] && k < 3; ++k) {
            box[k] = fmin(box[k], m->positions[3 * (size_t)v + k]);
            box[3 + k] = fmax(box[3 + k], m->positions[3 * (size_t)v + k]);
        }
    if (redo && !(box[0] <= box[3]) && m->vertex_count) /* no redo vertex: nothing is traced, any tree */
        for (int k = 0; k < 3; ++k)                         /* serves; the cheapest, one split near a point */
            box[k] = box[3 + k] = m->positions[k];
    const double grow = 1.01 * h_side + 1e-6 * s->h;
    for (int k = 0; k < 3; ++k)
        box[k] -= grow, box[3 + k] += grow;
    /* theta 0 is exact summation over the triangles in tree order, which
     * an unsplit cluster would change: the whole tree. */
    const int all = !redo || !(box[0] <= box[3]) || !(s->a.theta > 0);
    if (s->field &&
        (s->field_all || (!all && box[0] >= s->field_box[0] && box[1] >= s->field_box[1] &&
                          box[2] >= s->field_box[2] && box[3] <= s->field_box[3] && box[4] <= s->field_box[4] &&
                          box[5] <= s->field_box[5])))
        return MESO_OK;
    const double t = meso_seconds();
    s->rep->update_field_unsplit += meso_lp_field_unsplit_opened(s->field);
    meso_lp_field_destroy(s->field);
    s->field = NULL;
    const meso_lp_options lo_opt = {
        .p = s->a.p, .theta = s->a.theta, .near_radius = 2.0 * h_side, .region = all ? NULL : box};
    const meso_result r = meso_lp_field_create(s->fs.positions, s->fs.vertex_count, s->fs.indices,
                                               s->fs.triangle_count, &lo_opt, &s->field, err);
    s->field_all = all;
    memcpy(s->field_box, box, sizeof(box));
    s->rep->seconds_field += meso_seconds() - t;
    return r;
}

static meso_result directors(shell_bake* s, meso_error* err)
{
    const meso_bake_shell_options* a = &s->a;
    const meso_mesh* m = &s->m;
    const uint32_t nv = m->vertex_count;
    const int layers = a->kind == MESO_SHELL_ENVELOPE ? 2 : 1;
    const double h_side = a->kind == MESO_SHELL_ENVELOPE ? 0.5 * s->h : s->h;
    s->normals = malloc(sizeof(float) * 3 * (size_t)nv);
    s->d = calloc(3 * (size_t)nv * (size_t)layers, sizeof(float));
    s->lp_mask = calloc(nv, 1);
    s->lp_side = calloc(nv, 1);
    meso_result r = s->normals && s->d && s->lp_mask && s->lp_side ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    double t = meso_seconds();
    if (r == MESO_OK)
        r = meso_vertex_normals(m, s->normals, err);
    if (r == MESO_OK)
        r = meso_field_surface_build(m, s->normals, s->topo.boundary, s->topo.boundary_edges, h_side, &s->fs, err);
    s->rep->seconds_field = meso_seconds() - t;
    if (r == MESO_OK && a->directors != MESO_DIRECTORS_NORMAL)
        r = field_for(s, a->update ? s->prior.redo : NULL, h_side, err);
    /* The paper's 2h localisation (§4.2; shell_directors.c has what it
     * changes), h the shell's thickness: an envelope's whole, though each
     * of its sides traces half of it. */
    const meso_trace_options topt = {.thickness = h_side, .cutoff = 2.0 * s->h,
                                     .angle_tol = a->angle_tol_deg * M_PI / 180.0,
                                     .theta = a->theta, .smooth_iterations = a->smooth,
                                     .progress = s->run.common.progress ? mesoi_run_tick : NULL,
                                     .progress_user = &s->run};
    meso_trace_stats ts = {0, 0, 0};
    for (int layer = 0; layer < layers && r == MESO_OK; ++layer) {
        const int sign = (a->kind == MESO_SHELL_INTERIOR || layer == 1) ? -1 : 1;
        const double f0 = 0.2 + 0.6 * layer / layers, f1 = 0.2 + 0.6 * (layer + 1) / layers;
        mesoi_run_stage(&s->run, "directors", f0, f1 - 0.05, NULL);
        float* dl = s->d + 3 * (size_t)nv * (size_t)layer;
        /* --update: the rounds again over a grown region while they leave
         * bad faces with a kept corner; after the last growth pass, over
         * every vertex as a full bake (shell_update.c, "Growth"). */
        for (int pass = 0;; ++pass) {
            const int everything = pass > MESOI_SHELL_UPDATE_GROWTH_PASSES;
            meso_hybrid_stats hs = {0};
            const uint8_t* redo = everything ? NULL : s->prior.redo; /* --update: only these; the rest OLD's */
            if (r == MESO_OK && a->directors != MESO_DIRECTORS_NORMAL)
                r = field_for(s, redo, h_side, err); /* a grown region may leave the tree's box */
            if (r != MESO_OK)
                break;
            if (redo)
                memcpy(dl, s->prior.d + 3 * (size_t)nv * (size_t)layer, sizeof(float) * 3 * (size_t)nv);
            else if (everything)
                memset(dl, 0, sizeof(float) * 3 * (size_t)nv); /* as a full bake starts */
            t = meso_seconds();
            /* One checker for hybrid rounds, repair and regrow: each starts
             * from the verdicts the one before left, not from a full check. */
            meso_shell_checker* ck = NULL;
            r = meso_shell_checker_create(m, sign, s->run.common.threads, &ck, err);
            if (r == MESO_OK && redo)
                r = meso_shell_checker_prime(ck, dl, redo, err);
            if (r == MESO_OK)
                r = meso_shell_side_directors_in(s->field, m, s->normals, sign, &topt, a->directors,
                                                 s->run.common.threads, redo, dl, s->lp_side, &hs, &ts, ck, err);
            s->rep->hybrid_rounds += hs.rounds;
            s->rep->seconds_directors += meso_seconds() - t;
            s->rep->seconds_directors_checks += hs.seconds_checks;
            if (r == MESO_OK) /* the input's verdict before anything repairs over it */
                r = input_check_join(&s->check, s->rep, err);
            if (r == MESO_OK && !a->update)
                standin_begin(s); /* beside repair, which keeps one core busy (standin_job) */
            if (r == MESO_OK)
                mesoi_run_stage(&s->run, "directors", f1 - 0.05, f1,
                                "directors (%s side, %s): %u Lp, %u normal, %u rounds, %llu field evaluations (%.0f "
                                "ms)",
                                sign > 0 ? "outer" : "inner", meso_bake_directors_name(a->directors), hs.vertices_lp,
                                hs.vertices_normal, hs.rounds, (unsigned long long)ts.evaluations,
                                mesoi_run_ms(&s->run));
            uint32_t shortened = 0, grown = 0, bent = 0;
            if (r == MESO_OK && !a->no_repair) {
                uint32_t rounds = 0, left = 0;
                float* before = malloc(sizeof(float) * 3 * (size_t)nv); /* for regrow: the lengths repair took */
                if (!before)
                    r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "repair: out of memory");
                else
                    memcpy(before, dl, sizeof(float) * 3 * (size_t)nv);
                t = meso_seconds();
                /* repair, regrow and bend; bend's allowed thickness is seconds_allowed's */
                const double allowed_before = s->rep->seconds_allowed;
                if (r == MESO_OK)
                    r = meso_shell_repair_in(m, dl, sign, MESO_SHELL_REPAIR_ROUNDS, s->run.common.threads, redo,
                                             &shortened, &rounds, &left, ck, err);
                if (r == MESO_OK)
                    mesoi_run_stage(&s->run, "repair", f1, f1,
                                    "repair: %u vertices shortened in %u rounds, %u faces still bad (%.0f ms)",
                                    shortened, rounds, left, mesoi_run_ms(&s->run));
                /* Not for envelopes: each layer is checked against the base
                 * only, and lengthening one can make top and bottom meet
                 * (spot's envelope did, tests/gl/test_rt_shell_baked.c). */
                if (r == MESO_OK && shortened && !left && a->kind != MESO_SHELL_ENVELOPE) {
                    r = meso_shell_regrow_in(m, dl, before, sign, MESO_SHELL_REGROW_ROUNDS, s->run.common.threads,
                                             redo, &grown, ck, err);
                    if (r == MESO_OK)
                        mesoi_run_stage(&s->run, "regrow", f1, f1, "regrow: %u directors lengthened again (%.0f ms)",
                                        grown, mesoi_run_ms(&s->run));
                    /* What regrow could not give back along the field's
                     * direction: bent towards the normal (shell_bend.h),
                     * only the directors repair left shorter. */
                    uint8_t* short_ = r == MESO_OK ? calloc(nv ? nv : 1, 1) : NULL;
                    if (r == MESO_OK && !short_)
                        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "bend: out of memory");
                    if (r == MESO_OK)
                        r = allowed_side(s, layer, sign, h_side, err);
                    if (r == MESO_OK) {
                        for (uint32_t v = 0; v < nv; ++v)
                            short_[v] = memcmp(dl + 3 * (size_t)v, before + 3 * (size_t)v, 3 * sizeof(float)) != 0;
                        r = meso_shell_bend(m, dl, s->normals, s->allowed + (size_t)nv * (size_t)layer, sign,
                                            s->run.common.threads, short_, ck, &bent, err);
                    }
                    if (r == MESO_OK)
                        mesoi_run_stage(&s->run, "bend", f1, f1, "bend: %u directors lengthened or turned (%.0f ms)",
                                        bent, mesoi_run_ms(&s->run));
                    free(short_);
                }
                s->rep->seconds_repair += meso_seconds() - t - (s->rep->seconds_allowed - allowed_before);
                free(before);
            }
            uint32_t added = 0;
            if (r == MESO_OK && redo) {
                t = meso_seconds();
                r = mesoi_shell_update_grow(m, ck, dl, &s->prior, &added, err);
                if (r == MESO_OK && added && pass == MESOI_SHELL_UPDATE_GROWTH_PASSES) {
                    memset(s->prior.redo, 1, nv);
                    s->prior.redo_count = nv;
                }
                s->rep->seconds_repair += meso_seconds() - t;
                if (r == MESO_OK && added)
                    mesoi_run_stage(&s->run, "update", f1, f1,
                                    "update: bad faces with kept corners left, %s (%u of %u vertices recomputed)",
                                    pass == MESOI_SHELL_UPDATE_GROWTH_PASSES ? "every vertex recomputed"
                                                                             : "region grown",
                                    s->prior.redo_count, nv);
            }
            meso_shell_checker_destroy(ck);
            if (r != MESO_OK || !added) {
                s->rep->vertices_shortened += shortened;
                s->rep->vertices_regrown += grown;
                s->rep->vertices_bent += bent;
                break;
            }
        }
        for (uint32_t v = 0; r == MESO_OK && v < nv; ++v)
            s->lp_mask[v] |= s->lp_side[v];
    }
    /* An envelope is drawn from bottom to top: repaired as such too
     * (shell_envelope.h; each layer above was repaired against the base). */
    if (r == MESO_OK && a->kind == MESO_SHELL_ENVELOPE && !a->no_repair) {
        t = meso_seconds();
        uint32_t shortened = 0, rounds = 0, left = 0;
        r = meso_shell_envelope_repair(m, s->d, MESO_SHELL_REPAIR_ROUNDS, s->run.common.threads, &shortened, &rounds,
                                       &left, err);
        s->rep->seconds_repair += meso_seconds() - t;
        s->rep->vertices_shortened += shortened;
        if (r == MESO_OK)
            mesoi_run_stage(&s->run, "repair", 0.8, 0.8,
                            "envelope: %u vertices shortened in %u rounds so that no prism inverts from bottom to "
                            "top, %u left (%.0f ms)",
                            shortened, rounds, left, mesoi_run_ms(&s->run));
    }
    uint32_t lp_count = 0;
    for (uint32_t v = 0; s->lp_mask && v < nv; ++v)
        lp_count += s->lp_mask[v];
    s->rep->vertices_lp = lp_count;
    /* an update: the recomputed vertices only (meso_bake.h) */
    s->rep->vertices_normal = (s->prior.redo ? s->prior.redo_count : nv) - lp_count;
    s->rep->field_evaluations = ts.evaluations;
    s->rep->update_field_unsplit += meso_lp_field_unsplit_opened(s->field);
    s->rep->artificial_faces = s->fs.artificial_faces;
    return r;
}

/* Validate the shell as it will be rendered: prisms from bottom to top (an
 * update of an exterior or interior shell: mesoi_shell_update_validate). */
static meso_result validate(shell_bake* s, meso_error* err)
{
    const meso_bake_shell_options* a = &s->a;
    const uint32_t nv = s->m.vertex_count;
    meso_shell_report val;
    memset(&val, 0, sizeof(val));
    meso_result r;
    if (a->kind == MESO_SHELL_ENVELOPE) {
        meso_mesh bottom = s->m;
        float* pos = malloc(sizeof(float) * 3 * (size_t)nv);
        float* span = malloc(sizeof(float) * 3 * (size_t)nv);
        r = pos && span ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
        for (size_t i = 0; r == MESO_OK && i < 3 * (size_t)nv; ++i) {
            pos[i] = s->m.positions[i] + s->d[3 * (size_t)nv + i];
            span[i] = s->d[i] - s->d[3 * (size_t)nv + i];
        }
        bottom.positions = pos;
        if (r == MESO_OK)
            r = meso_shell_validate(&bottom, span, NULL, s->h, 1, NULL, &val, err);
        free(pos);
        free(span);
    } else {
        const int sign = a->kind == MESO_SHELL_INTERIOR ? -1 : 1;
        int done = 0;
        r = s->prior.redo ? mesoi_shell_update_validate(&s->m, s->d, s->h, sign, &s->prior, s->run.common.threads,
                                                        &val, &done, err)
                          : MESO_OK;
        /* A full bake has counted the base's self-intersections (none) in
         * require_shellable: validation need not count them again. */
        if (r == MESO_OK && !done)
            r = a->update ? meso_shell_validate(&s->m, s->d, NULL, s->h, sign, NULL, &val, err)
                          : mesoi_shell_validate_checked_base(&s->m, s->d, s->h, sign, &val, err);
    }
    meso_bake_shell_report* rep = s->rep;
    rep->prisms = val.prisms;
    rep->inverted_prisms = val.inverted_prisms;
    rep->undecided_prisms = val.undecided_prisms;
    rep->offset_self_intersections = val.offset_self_intersections;
    rep->offset_base_intersections = val.offset_base_intersections;
    rep->thickness_ratio_min = val.thickness_ratio_min;
    rep->thickness_ratio_mean = val.thickness_ratio_mean;
    if (r == MESO_OK)
        mesoi_run_stage(&s->run, "validate", 0.9, 0.9,
                        "validated: %u/%u prisms inverted (%u undecided), %llu offset self-intersections, %llu "
                        "offset/base intersections, thickness ratio min %.3f mean %.3f (%.0f ms)",
                        val.inverted_prisms, val.prisms, val.undecided_prisms,
                        (unsigned long long)val.offset_self_intersections,
                        (unsigned long long)val.offset_base_intersections, val.thickness_ratio_min,
                        val.thickness_ratio_mean, mesoi_run_ms(&s->run));
    return r;
}

/* The thickness the geometry allows, per side, against the directors
 * (shell_allowed.h): the report's allowed_* fields. */
static meso_result allowed(shell_bake* s, meso_error* err)
{
    const meso_bake_shell_options* a = &s->a;
    const uint32_t nv = s->m.vertex_count;
    const int layers = a->kind == MESO_SHELL_ENVELOPE ? 2 : 1;
    const double h_side = layers == 2 ? 0.5 * s->h : s->h;
    meso_result r = MESO_OK;
    meso_shell_allowed_summary sum;
    memset(&sum, 0, sizeof(sum));
    for (int layer = 0; layer < layers && r == MESO_OK; ++layer) {
        const int sign = (a->kind == MESO_SHELL_INTERIOR || layer == 1) ? -1 : 1;
        r = allowed_side(s, layer, sign, h_side, err);
        if (r == MESO_OK)
            meso_shell_allowed_add(&s->m, s->d + 3 * (size_t)nv * (size_t)layer,
                                   s->allowed + (size_t)nv * (size_t)layer, h_side, &sum, NULL);
    }
    meso_bake_shell_report* rep = s->rep;
    rep->allowed_ratio_min = sum.counted ? sum.ratio_min : 0.0;
    rep->allowed_ratio_mean = sum.counted ? sum.ratio_sum / sum.counted : 0.0;
    rep->vertices_below_half_allowed = sum.below_half;
    rep->vertices_allowed_below_requested = sum.limited;
    if (r == MESO_OK)
        mesoi_run_stage(&s->run, "allowed", 0.92, 0.92,
                        "allowed thickness: %u vertices limited by the geometry; achieved/allowed min %.3f mean "
                        "%.3f, %u below half (%.0f ms)",
                        sum.limited, rep->allowed_ratio_min, rep->allowed_ratio_mean, sum.below_half,
                        mesoi_run_ms(&s->run));
    return r;
}

/* META.parameters.color: the SPEC, where the texels came from, their size
 * and how they map (the CMAP record says the same in binary). */
static void color_json(cJSON* params, const meso_bake_shell_options* a, const mesoi_shell_color* c)
{
    cJSON* o = cJSON_AddObjectToObject(params, "color");
    cJSON_AddStringToObject(o, "spec", a->color);
    cJSON_AddStringToObject(o, "source", c->source);
    const double d[3] = {c->dims[0], c->dims[1], c->dims[2]};
    cJSON_AddItemToObject(o, "res", cJSON_CreateDoubleArray(d, c->dims[2] > 1 ? 3 : 2));
    cJSON_AddStringToObject(o, "mapping", c->mapping == MESO_CMAP_BASE ? "base" : "tiled");
}

/* --color: a file is read before any mesh work (a bad one fails fast);
 * from-mesh once the mesh, its materials and its uvs are known. */
static meso_result color_prepare(shell_bake* s, int from_mesh, meso_error* err)
{
    const meso_bake_shell_options* a = &s->a;
    double t = meso_seconds();
    meso_result r;
    if (from_mesh)
        r = mesoi_shell_color_from_mesh(a->input, &s->m, &s->mats, s->tx.plane[0] == 0 && s->m.uvs != NULL, &s->col,
                                        err);
    else
        r = mesoi_shell_color_load(a->color, s->run.common.max_memory, &s->col, err);
    if (r == MESO_OK && s->col.dims[2] > 1 && s->tx.fn.kind != MESO_TEXFN_DENSITY)
        r = meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_COLOR_ISSUE_SPEC,
                           "--color '%s': a 3D colour needs a volume texture function (--texture volume:..., weave, "
                           "cells, ...)",
                           a->color);
    if (r == MESO_OK)
        mesoi_run_stage(&s->run, "colour", from_mesh ? 0.2 : 0.1, from_mesh ? 0.2 : 0.1, "colour %s (%s): %ux%ux%u RGBA8, %s (%.0f ms)", a->color,
                        s->col.source, s->col.dims[0], s->col.dims[1], s->col.dims[2],
                        s->col.mapping == MESO_CMAP_BASE ? "at the mesh's own uv" : "tiled like the texture",
                        1e3 * (meso_seconds() - t));
    return r;
}

/* The lowest and highest texel a height field stores, of every frame, as
 * fractions of the shell's thickness (lowest 1, highest 0 when it stores
 * none); 0 when the texture is not a height field (then nothing is said of
 * where its surface lies in w). */
static int texel_range(const shell_bake* s, double* lo, double* hi)
{
    const meso_bake_shell_options* a = &s->a;
    const mesoi_shell_texture* tx = &s->tx;
    if (!a->texture || tx->fn.kind != MESO_TEXFN_HEIGHT)
        return 0;
    const size_t n = (size_t)tx->fn.dims[0] * tx->fn.dims[1] * tx->fn.dims[2] * (a->frames ? a->frames : 1);
    const uint8_t* b = a->frames ? tx->fn_frames : (const uint8_t*)tx->fn.encoded;
    const int wide = tx->fn.dtype == MESO_DTYPE_U16;
    uint32_t bottom = wide ? 65535u : 255u, top = 0;
    for (size_t i = 0; i < n; ++i) {
        const uint32_t v = wide ? (uint32_t)b[2 * i] | (uint32_t)b[2 * i + 1] << 8 : b[i];
        top = v > top ? v : top;
        bottom = v < bottom ? v : bottom;
    }
    *lo = bottom / (wide ? 65535.0 : 255.0);
    *hi = top / (wide ? 65535.0 : 255.0);
    return 1;
}

/* The largest texel an exterior shell's height field stores, of every
 * frame, as a fraction of the shell's thickness (1 for volumes, shells
 * without a texture and the other kinds). */
static double texel_max(const shell_bake* s)
{
    double lo = 0.0, hi = 1.0;
    return s->a.kind == MESO_SHELL_EXTERIOR && texel_range(s, &lo, &hi) ? hi : 1.0;
}

/* The error of the base mesh drawn in the shell's place (FORMAT.md §7.10,
 * level 1, form MESO_LEVEL_MESH): a point the shell draws is
 * Phi(u, v, w) = sum l_k bottom_k + w sum l_k (top_k - bottom_k) (§7.2),
 * at most max_k max(|bottom_k - p_k|, |top_k - p_k|) from the base point
 * sum l_k p_k (a convex combination of the corner offsets); an exterior
 * shell's bottom is the base, so a height field that never rises above
 * hmax puts it within hmax max_k |d_k|. The other way, the surface a ray
 * meets above a base point lies in the same column, so the same bound
 * holds: two-sided, as §7.10 asks. hmax is the largest stored texel of
 * every frame (1 for volumes and shells without a texture: their surface
 * may reach w = 1). Rounded up to f32. */
static float standin_error(const shell_bake* s)
{
    const meso_bake_shell_options* a = &s->a;
    const uint32_t nv = s->m.vertex_count;
    const int layers = a->kind == MESO_SHELL_ENVELOPE ? 2 : 1;
    double dmax = 0.0;
    for (size_t i = 0; i < (size_t)nv * (size_t)layers; ++i) {
        const float* d = s->d + 3 * i;
        dmax = fmax(dmax, sqrt((double)d[0] * d[0] + (double)d[1] * d[1] + (double)d[2] * d[2]));
    }
    return mesoi_f32_up(texel_max(s) * dmax);
}

/* Level 1 of a height-field shell: its mid-surface, not its base mesh
 * (decided here; the frusta stand-in is raised to its relief's mid height
 * the same way, frusta_standin.h). Every point the shell draws is
 * Phi(u, v, w) = sum l_k (bottom_k + w d_k), d_k = top_k - bottom_k
 * (§7.2), with w in [wlo, whi]: on the height surface w = h(s, t), which
 * bilinear texels keep within [lowest, highest texel]; on a uv seam's
 * wall between the two sides' heights, also within it; on an open mesh's
 * border the prisms' side walls reach down to w = 0, so there wlo = 0.
 * The mesh whose vertex k is bottom_k + m d_k, m = (wlo + whi) / 2, draws
 * Phi(u, v, m) over the same (u, v) (a flat triangle, as the smooth
 * mapping at fixed w is), so the two surfaces are within
 * |w - m| |sum l_k d_k| <= (whi - wlo) / 2 max_k |d_k| of each other, both
 * ways: over every point of either there is one of the other. That is at
 * most half the base mesh's bound (hmax max_k |d_k| for an exterior
 * shell), and less where the texels do not reach 0. The stored vertices
 * are f32: each within half an ulp per coordinate of bottom_k + m d_k,
 * and the corresponding points of a triangle by as much, so 2 f32 epsilons
 * of the largest coordinate are added. Volumes and shells without a
 * texture keep the base mesh (a volume's column may be empty: no surface
 * point over it to pair with). `pos`/`sdir` are the output vertices'
 * (sdir_layers as SDIR); `mid` gets 3 nv floats. Returns the error, or a
 * negative value when the base mesh stays level 1. */
static double midsurface(const shell_bake* s, const float* pos, const float* sdir, uint32_t nv, int sdir_layers,
                         float* mid)
{
    double lo = 0.0, hi = 0.0;
    if (!texel_range(s, &lo, &hi) || hi < lo)
        return -1.0;
    if (s->topo.boundary_edges > 0)
        lo = 0.0;
    const double m = 0.5 * (lo + hi);
    double dmax = 0.0, big = 0.0;
    for (size_t v = 0; v < nv; ++v) {
        double d2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double top = (double)pos[3 * v + (size_t)k] + sdir[3 * v + (size_t)k];
            const double bottom =
                (double)pos[3 * v + (size_t)k] + (sdir_layers == 2 ? sdir[3 * ((size_t)nv + v) + (size_t)k] : 0.0f);
            const float x = (float)(bottom + m * (top - bottom));
            mid[3 * v + (size_t)k] = x;
            big = fmax(big, fabs((double)x));
            d2 += (top - bottom) * (top - bottom);
        }
        dmax = fmax(dmax, sqrt(d2));
    }
    return 0.5 * (hi - lo) * dmax + 2.0 * FLT_EPSILON * big;
}

/* The longest top - bottom over the vertices of SDIR `sdir` (FORMAT.md
 * §7.2; `layers` 1 or 2). */
static double longest_span(const float* sdir, uint32_t nv, int layers)
{
    double dmax = 0.0;
    for (size_t v = 0; v < nv; ++v) {
        double d2 = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double top = sdir[3 * v + (size_t)k];
            const double bottom = layers == 2 ? sdir[3 * ((size_t)nv + v) + (size_t)k] : 0.0;
            d2 += (top - bottom) * (top - bottom);
        }
        dmax = fmax(dmax, sqrt(d2));
    }
    return dmax;
}

/* Volume levels' errors (volume_levels.c) into d[0..count-1] (INFINITY
 * where none is stated), g and k for turning them into object units; a
 * stage line says what was measured, or why not. */
static meso_result volume_distances(shell_bake* s, const meso_mesh* base, const float* sdir, int sdir_layers,
                                    double e1, double g[2], double* k, double* d, meso_error* err)
{
    const mesoi_shell_texture* tx = &s->tx;
    for (uint32_t l = 0; l < tx->native_count; ++l)
        d[l] = INFINITY;
    const double t = meso_seconds();
    const int scaled = mesoi_volume_level_scales(base, sdir, sdir_layers, g[1], g, k);
    const double floor = scaled ? *k * mesoi_volume_level_floor(&tx->fn, g) : INFINITY;
    const uint64_t need = mesoi_volume_level_bytes(&tx->fn);
    const char* why = !scaled          ? "a degenerate texture triangle"
                      : !(floor < e1)  ? "even one lattice cell bounds no nearer than the base mesh"
                      : need > s->run.common.max_memory ? "the measurement would exceed --max-memory"
                                                        : NULL;
    meso_result r = MESO_OK;
    if (!why)
        r = mesoi_volume_level_distances(&tx->fn, tx->native, tx->native_count, g, e1 / *k, s->run.common.threads, d,
                                         err);
    if (r == MESO_OK)
        mesoi_run_stage(&s->run, "texture levels", 0.99, 0.99,
                        "halved volumes %s%s%s: a texture tile stretched up to %g object units, a lattice "
                        "cell's error %g, the base mesh's %g (%.0f ms)",
                        why ? "not measured (" : "measured against level 0", why ? why : "", why ? ")" : "", g[0],
                        floor, e1, 1e3 * (meso_seconds() - t));
    return r;
}

/* The errors of the native levels (height_field_levels.h, volume_levels.h)
 * into lv->native_error, and how many are kept into lv->native. A height
 * field level's error is its heights' sup distance from level 0's times the
 * longest top - bottom of the output vertices (height_field_levels.c
 * derives it), with 4 float ulps of slack in the heights for the runtime's
 * arithmetic. A volume level's is the texture-space Hausdorff bound of its
 * surface against level 0's times the mapping's factor k
 * (volume_levels.c), with as much slack. Levels whose error reaches the
 * base mesh's (e0) are dropped, the base mesh being as close and cheaper. */
static meso_result native_errors(shell_bake* s, const meso_mesh* base, const float* sdir, int sdir_layers,
                                 mesoi_standin_levels* lv, meso_error* err)
{
    const double e1 = lv->e0; /* level 1's, the stand-in a native level must beat */
    const mesoi_shell_texture* tx = &s->tx;
    lv->native = 0;
    if (!tx->native_count)
        return MESO_OK;
    const int volume = tx->fn.kind == MESO_TEXFN_DENSITY;
    double g[2] = {0.0, longest_span(sdir, base->vertex_count, sdir_layers)}, k = INFINITY;
    double d[MESOI_HEIGHT_MAX_NATIVE];
    meso_result r = volume ? volume_distances(s, base, sdir, sdir_layers, e1, g, &k, d, err) : MESO_OK;
    uint32_t N = 0;
    double rho = 0.0;
    for (; r == MESO_OK && N < tx->native_count; ++N) {
        rho = volume ? fmax(rho, d[N]) : 0.0; /* errors never decrease (FORMAT.md §7.10): still a bound */
        const double e = volume ? k * (rho + 4.0 * FLT_EPSILON * (g[0] + g[1]))
                                : (tx->native[N].sup + 4.0 * FLT_EPSILON) * g[1];
        const float f = mesoi_f32_up(e);
        if (!(f < e1))
            break;
        lv->native_error[N] = f;
    }
    lv->native = r == MESO_OK ? N : 0;
    return r;
}

/* A shell's coarser base meshes (shell_base_levels.h) and their MESH chunks. */
typedef struct base_levels {
    mesoi_shell_base_level* lv;
    uint32_t count;
    meso_mesh_chunk chunk[MESOI_SHELL_BASE_LEVELS_MAX];
} base_levels;

static void base_levels_free(base_levels* b)
{
    mesoi_shell_base_levels_free(b->lv, b->count);
    for (uint32_t c = 0; c < MESOI_SHELL_BASE_LEVELS_MAX; ++c)
        free(b->chunk[c].data);
    memset(b, 0, sizeof *b);
}

/* The coarser base meshes as native levels after the texture levels
 * (lv->native of them, native_errors): level N + c draws base mesh c with
 * level N's texture function. Its error is level N's plus D_c, the largest
 * distance between the two mappings (shell_base_levels.c: Φ_c(T) is within
 * D_c of Φ(T), which is within level N's error of level 0's surface), plus
 * as much float slack as the texture levels allow; made non-decreasing,
 * and kept while it is below the stand-in's. Static texture functions
 * only (an animated one's frames would need moving too); at most what
 * --levels leaves after the stand-ins. */
static meso_result base_levels_make(shell_bake* s, const meso_mesh* base, const float* sdir, int sdir_layers,
                                    const float* thick, const float lo[3], const float hi[3],
                                    mesoi_standin_levels* lv, base_levels* bl, cJSON* rep, meso_error* err)
{
    memset(bl, 0, sizeof *bl);
    if (!s->a.texture || s->a.frames)
        return MESO_OK;
    const uint32_t N = lv->native, total = s->a.levels ? (uint32_t)s->a.levels : MESOI_STANDIN_MAX_LEVELS,
                   used = 1 + N + lv->count;
    const double e1 = lv->e0, e_tex = N ? lv->native_error[N - 1] : 0.0;
    double extent = 0.0;
    for (int k = 0; k < 3; ++k)
        extent = fmax(extent, fmax(fabs((double)lo[k]), fabs((double)hi[k])));
    const double slack = 4.0 * FLT_EPSILON * (extent + longest_span(sdir, base->vertex_count, sdir_layers));
    const double t = meso_seconds();
    const mesoi_shell_base_levels_input in = {.base = base, .sdir = sdir, .layers = sdir_layers, .thick = thick,
                                              .max_levels = total > used ? total - used : 0,
                                              .limit = e1 - e_tex - slack};
    const char* why = NULL;
    double too_far = -1.0;
    meso_result r = mesoi_shell_base_levels_build(&in, &bl->lv, &bl->count, &why, &too_far, err);
    uint32_t kept = 0;
    double prev = e_tex;
    for (; r == MESO_OK && kept < bl->count; ++kept) {
        const float f = mesoi_f32_up(fmax(prev, e_tex + bl->lv[kept].distance + slack));
        if (!(f < e1)) {
            why = "its distance to level 0 is not below the stand-in's error";
            too_far = bl->lv[kept].distance;
            break;
        }
        r = meso_bake_mesh_chunk(&bl->lv[kept].mesh, NULL, &bl->chunk[kept], err);
        lv->native_error[N + kept] = prev = f;
        lv->native_mesh[N + kept] = &bl->lv[kept].mesh;
        lv->native_mesh_bytes[N + kept] = bl->chunk[kept].size;
    }
    if (r != MESO_OK)
        return r;
    lv->native = N + kept;
    cJSON* jb = cJSON_AddObjectToObject(rep, "base_levels");
    cJSON_AddNumberToObject(jb, "count", kept);
    if (why)
        cJSON_AddStringToObject(jb, "stopped", why);
    if (too_far >= 0.0) {
        cJSON_AddNumberToObject(jb, "distance", too_far);
        cJSON_AddNumberToObject(jb, "standin_error", e1);
    }
    char far[96] = "";
    if (too_far >= 0.0)
        snprintf(far, sizeof far, ": %.3g, the stand-in's %.3g", too_far, e1);
    if (in.max_levels)
        mesoi_run_stage(&s->run, "levels", 0.99, 0.99, "%u coarser base meshes kept%s%s%s%s (%.0f ms)", kept,
                        why ? " (the next: " : "", why ? why : "", far, why ? ")" : "", 1e3 * (meso_seconds() - t));
    return MESO_OK;
}

/* The native levels kept (lv->native, native_errors, base_levels_make) and
 * their chunks, appended to chunks[0..n-1]. T texture levels, then C
 * coarser base meshes (lv->native = T + C):
 * - each texture level's TX2D or TX3D and DIST at its own lod 1..T;
 * - the base mesh's SDIR and STHK at lod T, which levels 0..T all resolve
 *   them to (FORMAT.md §7.10: per type the smallest lod >= the level), and
 *   its MESH too where a later level has a MESH of its own (the coarser
 *   bases, or level T + C + 1 when the stand-in is not the base mesh);
 * - each coarser base's MESH, SDIR and STHK at lod T + c;
 * - what is drawn in texture space, level T's texture function and its
 *   distance map, COLR and CMAP, at lod T + C, which levels T..T + C share.
 * Returns the chunks appended. */
static size_t native_chunks(const shell_bake* s, const mesoi_standin_levels* lv, const base_levels* bl,
                            mesoi_chunk* chunks, size_t n)
{
    const mesoi_shell_texture* tx = &s->tx;
    const uint32_t N = lv->native, C = bl->count < N ? bl->count : N, T = N - C;
    if (N == 0)
        return 0;
    size_t m = 0;
    for (uint32_t l = 1; l <= T; ++l) {
        const mesoi_height_level* t = &tx->native[l - 1];
        chunks[n + m++] = (mesoi_chunk){
            .desc = {.type = tx->fn.kind == MESO_TEXFN_DENSITY ? MESO_CHUNK_TX3D : MESO_CHUNK_TX2D, .object = 1,
                     .lod = (uint16_t)l, .dtype = t->fn.dtype, .components = 1,
                     .dims = {t->fn.dims[0], t->fn.dims[1], t->fn.dims[2]}},
            .data = t->fn.encoded, .size = t->fn.encoded_size};
        chunks[n + m++] = (mesoi_chunk){
            .desc = {.type = MESO_CHUNK_DIST, .object = 1, .lod = (uint16_t)l, .dtype = t->dist.dtype,
                     .components = 1, .dims = {t->dist.dims[0], t->dist.dims[1], t->dist.dims[2]}},
            .data = t->dist.encoded, .size = t->dist.encoded_size};
    }
    for (size_t k = 0; k < n + m; ++k) {
        meso_chunk_desc* d = &chunks[k].desc;
        if (d->type == MESO_CHUNK_SDIR || d->type == MESO_CHUNK_STHK ||
            (d->type == MESO_CHUNK_MESH && (lv->standin_mesh || C)))
            d->lod = (uint16_t)T;
        else if (d->type == MESO_CHUNK_COLR || d->type == MESO_CHUNK_CMAP ||
                 ((d->type == MESO_CHUNK_TX2D || d->type == MESO_CHUNK_TX3D || d->type == MESO_CHUNK_DIST) &&
                  d->lod == T))
            d->lod = (uint16_t)N;
    }
    for (uint32_t c = 0; c < C; ++c) {
        const mesoi_shell_base_level* b = &bl->lv[c];
        const uint32_t nv = b->mesh.vertex_count, L = (uint32_t)(s->a.kind == MESO_SHELL_EXTERIOR ? 1 : 2);
        const uint16_t lod = (uint16_t)(T + 1 + c);
        chunks[n + m++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_MESH, .flags = MESO_CHUNK_FLAG_REQUIRED,
                                                 .object = 1, .lod = lod, .encoding = bl->chunk[c].encoding,
                                                 .decoded_size = bl->chunk[c].decoded_size},
                                        .data = bl->chunk[c].data, .size = bl->chunk[c].size};
        chunks[n + m++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_SDIR, .flags = MESO_CHUNK_FLAG_REQUIRED,
                                                 .object = 1, .lod = lod, .dtype = MESO_DTYPE_F32, .components = 3,
                                                 .dims = {nv, L, 1}},
                                        .data = b->sdir, .size = sizeof(float) * 3 * (size_t)nv * L};
        chunks[n + m++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_STHK, .object = 1, .lod = lod,
                                                 .dtype = MESO_DTYPE_F32, .components = 1, .dims = {nv, 1, 1}},
                                        .data = b->thick, .size = sizeof(float) * (size_t)nv};
    }
    return m;
}

/* The native levels worth a place (mesoi_height_levels_trim): what every
 * level shares, the base mesh, directors, thickness and colour, estimated
 * from the vertex and triangle counts as mesh_chunk.c lays a MESH out
 * (e.g. spot_uv with bricks:64 keeps one, 243 KB against 364 KB, where a
 * second would have saved 16 KB). */
static void native_trim(shell_bake* s)
{
    mesoi_shell_texture* tx = &s->tx;
    const uint64_t nv = (uint64_t)s->m.vertex_count + tx->seam_vertices, layers = s->a.kind == MESO_SHELL_EXTERIOR ? 1 : 2;
    const uint64_t shared = nv * (12 + 12 + 8 + 12 * layers + 4) + 12 * (uint64_t)s->m.triangle_count +
                            4 * (uint64_t)s->col.dims[0] * s->col.dims[1] * s->col.dims[2];
    const uint32_t keep = mesoi_height_levels_trim(tx->native, tx->native_count, shared,
                                                   shared + tx->fn.encoded_size + tx->dist.encoded_size);
    if (tx->native_count)
        mesoi_run_stage(&s->run, "texture levels", 0.2, 0.2,
                        "%u of %u halved %s kept as native levels (each draws from at most 9/10 of the "
                        "bytes of the level before)",
                        keep, tx->native_count, tx->fn.kind == MESO_TEXFN_DENSITY ? "volumes" : "height fields");
    tx->native_count = keep;
}

/* The base mesh as the MESH chunk has it: seam vertices added where the
 * texture coordinates split (their arrays in *pos, *normals, owned by the
 * caller). Returns 0 when out of memory. */
static int shell_base(const shell_bake* s, meso_mesh* base, float** pos, float** normals)
{
    const mesoi_shell_texture* tx = &s->tx;
    const uint32_t nv = s->m.vertex_count, nv_out = nv + tx->seam_vertices;
    *base = s->m;
    base->normals = s->normals;
    *pos = *normals = NULL;
    if (tx->uvs)
        base->uvs = tx->uvs;
    if (tx->source) {
        *pos = gather3(s->m.positions, nv, tx->source, nv_out, 1);
        *normals = gather3(s->normals, nv, tx->source, nv_out, 1);
        base->vertex_count = nv_out;
        base->positions = *pos;
        base->normals = *normals;
        base->indices = tx->indices;
        base->corner_uvs = NULL;
    }
    return !tx->source || (*pos && *normals);
}

/* Stand-ins of an update. OLD's chain simplified OLD's base mesh; the
 * edited base mesh has the same triangles with no vertex moved farther than
 * moved_max, and a point on a triangle moves by a convex combination of its
 * corners' moves, so the two base meshes are within moved_max of each
 * other both ways: each kept level is within its own bound against OLD's
 * base plus moved_max of the new one (the triangle inequality), and its
 * error is stored as e0 + that. The chain is kept while its base mesh has
 * moved no farther than e0 in all since it was simplified (over a series
 * of updates: the report's update.chain_moved), e0 being the error every
 * stand-in has anyway, and when the update asks for the levels OLD was
 * baked with (META.parameters.levels); otherwise it is built anew, as a
 * full bake builds it. Simplifying and measuring the chain again was 0.42
 * s of a 0.6 s armadillo update. */
static int chain_kept(const shell_bake* s)
{
    const mesoi_shell_prior* p = &s->prior;
    return s->a.update && s->a.levels != 1 && p->chain_count && p->chain_levels == s->a.levels &&
           p->chain_moved + p->moved_max <= s->e0 &&
           1 + s->tx.native_count + 1 + p->chain_count <=
               (uint32_t)(s->a.levels ? s->a.levels : MESOI_STANDIN_MAX_LEVELS);
}

static meso_result chain_take(shell_bake* s, mesoi_standin_levels* out, meso_error* err)
{
    mesoi_shell_prior* p = &s->prior;
    memset(out, 0, sizeof *out);
    out->chain = calloc(p->chain_count, sizeof *out->chain);
    if (!out->chain)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "update: out of memory");
    out->e0 = s->e0;
    out->chain_count = p->chain_count;
    out->count = 1 + p->chain_count;
    for (uint32_t k = 0; k < p->chain_count; ++k) {
        meso_mesh_level* c = &out->chain[k];
        c->error = c->measured = p->chain_own[k] + p->moved_max;
        c->mesh.triangle_count = p->chain_triangles[k];
        for (int i = 0; i < 3; ++i) {
            c->bbox_min[i] = p->chain_bbox[k][i];
            c->bbox_max[i] = p->chain_bbox[k][3 + i];
        }
        out->chunk[k] = p->chain_chunk[k]; /* the bytes move to `out` */
        p->chain_chunk[k].data = NULL;
        /* The mesh, for its vertex colours and baked normals (its MESH is
         * encoded again with them: standin_levels.c); a mesh left empty
         * gets none. */
        meso_mesh_view mv;
        const meso_mesh_chunk* mc = &out->chunk[k];
        if (mc->encoding == MESO_ENCODING_RAW && meso_mesh_parse(mc->data, mc->size, &mv, NULL) == MESO_OK) {
            const uint32_t nv = mv.layout.vertex_count, ni = mv.layout.index_count;
            c->mesh.positions = malloc(sizeof(float) * 3 * (size_t)nv);
            c->mesh.indices = malloc(sizeof(uint32_t) * (ni ? (size_t)ni : 1));
            c->mesh.normals = mv.normals ? malloc(sizeof(float) * 3 * (size_t)nv) : NULL;
            c->mesh.uvs = mv.uvs ? malloc(sizeof(float) * 2 * (size_t)nv) : NULL;
            if (!c->mesh.positions || !c->mesh.indices || (mv.normals && !c->mesh.normals) ||
                (mv.uvs && !c->mesh.uvs))
                return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "update: out of memory");
            memcpy(c->mesh.positions, mv.positions, sizeof(float) * 3 * (size_t)nv);
            memcpy(c->mesh.indices, mv.indices, sizeof(uint32_t) * (size_t)ni);
            if (mv.normals)
                memcpy(c->mesh.normals, mv.normals, sizeof(float) * 3 * (size_t)nv);
            if (mv.uvs)
                memcpy(c->mesh.uvs, mv.uvs, sizeof(float) * 2 * (size_t)nv);
            c->mesh.vertex_count = nv;
        }
    }
    p->chain_count = 0;
    return MESO_OK;
}

/* What the chain's samples are spaced for (the comment above standin_job). */
static double standin_e0_sampling(const shell_bake* s)
{
    return texel_max(s) * (s->a.kind == MESO_SHELL_ENVELOPE ? 0.5 * s->h : s->h);
}

/* The `levels` the stand-ins are built for: what is left of --levels (0:
 * as many as there may be) after level 0 and the native levels. */
static int chain_levels(const shell_bake* s)
{
    return (s->a.levels ? s->a.levels : MESOI_STANDIN_MAX_LEVELS) - (int)s->tx.native_count;
}

static int standin_run(void* arg)
{
    standin_job* j = arg;
    j->r = mesoi_standin_levels_build(&j->base, j->e0_sampling, j->levels, j->threads, &j->out, &j->err);
    return 0;
}

/* The chain started on its own thread, if there are threads for it and it
 * is wanted: once the normals are known (shell_base), for a full bake
 * from the first side's traced directors (directors()), for an update
 * after them (standin_start). */
static void standin_begin(shell_bake* s)
{
    standin_job* j = &s->chain;
    if (j->state || s->a.levels == 1 || meso_bake_thread_count(s->run.common.threads) < 2 ||
        !MESO_HAVE_MESHOPTIMIZER || s->keep_chain)
        return;
    j->state = 3; /* tried: once (shell_base's arrays stay in j until shell_free) */
    if (!shell_base(s, &j->base, &j->pos, &j->normals))
        return;
    j->e0_sampling = standin_e0_sampling(s);
    j->levels = chain_levels(s);
    j->threads = s->run.common.threads;
#ifndef __STDC_NO_THREADS__
    if (thrd_create(&j->thread, standin_run, j) == thrd_success)
        j->state = 1;
#endif
}

/* Once the directors are final: e0, whether an update keeps OLD's chain,
 * and otherwise the chain started if it is not yet; with one thread, or no
 * thread to be had, assemble() builds it. */
static void standin_start(shell_bake* s)
{
    s->e0 = standin_error(s);
    s->keep_chain = chain_kept(s);
    standin_begin(s);
}

/* The file: base mesh with the normals the directors started from (and the
 * texture coordinates of the texture function), SDIR, STHK, the texture
 * function and its distance map. Everything per vertex is written for the
 * output vertices: the mesh's, plus the copies split off at uv seams. */
static meso_result assemble(shell_bake* s, meso_bake_output** out, meso_error* err)
{
    const meso_bake_shell_options* a = &s->a;
    const mesoi_shell_texture* tx = &s->tx;
    const meso_mesh* m = &s->m;
    const uint32_t nv = m->vertex_count, nv_out = nv + tx->seam_vertices;
    const int layers = a->kind == MESO_SHELL_ENVELOPE ? 2 : 1;
    float *pos_out = NULL, *normals_out = NULL, *sdir_out = NULL, *thick = NULL;
    meso_mesh_chunk chunk = {0}, mid_chunk = {0};
    mesoi_standin_levels standins = {0};
    mesoi_shell_parts parts = {0};
    base_levels bases = {0};
    mesoi_chunk* all = NULL;
    meso_mesh base, mid_mesh;
    mesoi_chunk mid;
    float* mid_pos = NULL;
    meso_result r = shell_base(s, &base, &pos_out, &normals_out)
                        ? meso_bake_mesh_chunk(&base, NULL, &chunk, err)
                        : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "out of memory");
    /* SDIR as FORMAT.md §7.2 has it: L = 1 for exterior shells; L = 2 for
     * envelopes (top, bottom) and for interior shells, whose layer 0 is zero
     * (top = the base surface) and layer 1 the inward director (bottom). */
    const int sdir_layers = a->kind == MESO_SHELL_EXTERIOR ? 1 : 2;
    float* sdir = s->d;
    if (r == MESO_OK && a->kind == MESO_SHELL_INTERIOR) {
        sdir = calloc(3 * (size_t)nv * 2, sizeof(float));
        r = sdir ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
        if (sdir)
            memcpy(sdir + 3 * (size_t)nv, s->d, sizeof(float) * 3 * (size_t)nv);
    }
    if (r == MESO_OK && tx->source) {
        sdir_out = gather3(sdir, nv, tx->source, nv_out, sdir_layers);
        r = sdir_out ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    }
    if (r == MESO_OK) {
        thick = malloc(sizeof(float) * (size_t)nv_out);
        r = thick ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
        for (uint32_t v = 0; thick && v < nv_out; ++v)
            thick[v] = (float)s->h;
    }
    cJSON *meta = NULL, *rep = NULL;
    if (r == MESO_OK) {
        meso_object_record rec = {.id = 1, .kind = MESO_OBJECT_SHELL};
        for (int k = 0; k < 3; ++k) {
            rec.bbox_min[k] = (float)s->lo[k];
            rec.bbox_max[k] = (float)s->hi[k];
        }
        for (size_t i = 0; i < (size_t)nv * (size_t)layers; ++i)
            for (int k = 0; k < 3; ++k) {
                const float x = m->positions[3 * (i % nv) + (size_t)k] + s->d[3 * i + (size_t)k];
                rec.bbox_min[k] = fminf(rec.bbox_min[k], x);
                rec.bbox_max[k] = fmaxf(rec.bbox_max[k], x);
            }
        snprintf(rec.name, sizeof(rec.name), "%s", mesoi_input_label(a->input));

        meta = mesoi_meta_new("shell");
        cJSON* params = cJSON_AddObjectToObject(meta, "parameters");
        cJSON_AddNumberToObject(params, "thickness", s->h);
        cJSON_AddStringToObject(params, "kind", meso_bake_shell_kind_name(a->kind));
        cJSON_AddStringToObject(params, "directors", meso_bake_directors_name(a->directors));
        cJSON_AddNumberToObject(params, "p", a->p);
        cJSON_AddNumberToObject(params, "theta", a->theta);
        cJSON_AddNumberToObject(params, "angle_tol_deg", a->angle_tol_deg);
        cJSON_AddNumberToObject(params, "smooth", (double)a->smooth);
        cJSON_AddNumberToObject(params, "levels", (double)a->levels);
        cJSON_AddBoolToObject(params, "repair", !a->no_repair);
        if (a->texture)
            mesoi_shell_texture_json(params, a, tx, 0);
        if (s->col.rgba)
            color_json(params, a, &s->col);
        cJSON* inputs = cJSON_AddArrayToObject(meta, "inputs");
        r = mesoi_add_provenance(inputs, a->input, a->mesh, err);
        if (r == MESO_OK && a->update) {
            cJSON_AddStringToObject(params, "update_of", mesoi_base_name(a->update));
            r = mesoi_add_input_provenance(inputs, a->update, err);
        }
        rep = cJSON_CreateObject();
        if (s->keep_chain) {
            s->rep->update_levels_kept = s->prior.chain_count;
            s->rep->update_chain_moved = s->prior.chain_moved + s->prior.moved_max;
        }
        report_json(rep, s->rep);
        mesoi_report_fixes(rep, &s->rep->fixes);
        if (a->texture)
            mesoi_shell_texture_json(rep, a, tx, 1);
        const int height = tx->fn.kind == MESO_TEXFN_HEIGHT;
        /* Animated: the ANIM record (FORMAT.md §7.2 "Animated texture
         * functions"), then every frame stacked along z. */
        uint8_t anim[MESO_ANIM_RECORD_SIZE];
        const meso_anim_record ar = {.frame_count = a->frames, .flags = MESO_ANIM_FLAG_LOOP, .fps = (float)a->fps,
                                     .time0 = (float)a->time};
        meso_anim_record_encode(&ar, anim);
        /* Colour: COLR and the CMAP record that maps it (FORMAT.md §7.2 "Shell colour"). */
        uint8_t cmap[MESO_CMAP_RECORD_SIZE];
        const int base_map = s->col.mapping == MESO_CMAP_BASE;
        const meso_cmap_record cr = {.mapping = s->col.mapping,
                                     .scale = {base_map ? (float)(1.0 / a->tiling[0]) : 1.0f,
                                               base_map ? (float)(1.0 / a->tiling[1]) : 1.0f}};
        meso_cmap_record_encode(&cr, cmap);
        mesoi_chunk chunks[11 + 2 * MESOI_HEIGHT_MAX_NATIVE + 3 * MESOI_SHELL_BASE_LEVELS_MAX +
                           2 * MESOI_STANDIN_MAX_LEVELS] = { /* stand-ins: MESH and VCOL each */
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
            {.desc = {.type = height ? MESO_CHUNK_TX2D : MESO_CHUNK_TX3D, .object = 1, .dtype = tx->fn.dtype,
                      .components = 1, .dims = {tx->fn.dims[0], tx->fn.dims[1], tx->fn.dims[2]}},
             .data = tx->fn.encoded, .size = tx->fn.encoded_size},
            {.desc = {.type = MESO_CHUNK_DIST, .object = 1, .dtype = tx->dist.dtype, .components = 1,
                      .dims = {tx->dist.dims[0], tx->dist.dims[1], tx->dist.dims[2]}},
             .data = tx->dist.encoded, .size = tx->dist.encoded_size},
            {.desc = {.type = MESO_CHUNK_ANIM, .object = 1, .dtype = MESO_DTYPE_BYTES, .components = 1,
                      .dims = {1, 1, 1}},
             .data = anim, .size = sizeof(anim)},
            {.desc = {.type = MESO_CHUNK_TXFR, .object = 1, .dtype = tx->fn.dtype, .components = 1,
                      .dims = {tx->fn.dims[0], tx->fn.dims[1], tx->fn.dims[2] * a->frames}},
             .data = tx->fn_frames, .size = tx->fn.encoded_size * a->frames},
            {.desc = {.type = MESO_CHUNK_DSFR, .object = 1, .dtype = tx->dist.dtype, .components = 1,
                      .dims = {tx->dist.dims[0], tx->dist.dims[1], tx->dist.dims[2] * a->frames}},
             .data = tx->dist_frames, .size = tx->dist.encoded_size * a->frames},
        };
        size_t n = a->frames ? 8 : a->texture ? 5 : 3;
        if (s->col.rgba) {
            const uint32_t* cd = s->col.dims;
            chunks[n++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_COLR, .object = 1, .dtype = MESO_DTYPE_U8,
                                                 .components = 4, .dims = {cd[0], cd[1], cd[2]}},
                                        .data = s->col.rgba, .size = 4 * (size_t)cd[0] * cd[1] * cd[2]};
            chunks[n++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_CMAP, .object = 1, .dtype = MESO_DTYPE_BYTES,
                                                 .components = 1, .dims = {1, 1, 1}},
                                        .data = cmap, .size = sizeof(cmap)};
        }
        /* Level 1: the base mesh as a stand-in (the same MESH bytes at lod
         * 1), levels 2..: its simplifications, and the LODS records
         * (FORMAT.md §7.10; standin_levels.h). */
        if (r == MESO_OK && a->levels != 1) {
            standin_job* j = &s->chain;
            standin_job_join(j);
            if (s->keep_chain) {
                r = chain_take(s, &standins, err);
            } else if (j->state == 2 && j->r != MESO_OK) {
                *err = j->err;
                r = j->r;
            } else if (j->state == 2) {
                standins = j->out; /* taken: freed below */
                memset(&j->out, 0, sizeof j->out);
            } else {
                r = mesoi_standin_levels_build(&base, standin_e0_sampling(s), chain_levels(s), s->run.common.threads,
                                               &standins, err);
            }
            standins.e0 = s->e0; /* sampled for e0_sampling, stored with e0 */
            /* Level 1 the mid-surface when that is nearer (midsurface). */
            mid_pos = r == MESO_OK ? malloc(sizeof(float) * 3 * (size_t)nv_out) : NULL;
            if (r == MESO_OK && !mid_pos)
                r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "stand-in: out of memory");
            const double e1 = r == MESO_OK ? midsurface(s, base.positions, sdir_out ? sdir_out : sdir, nv_out,
                                                        sdir_layers, mid_pos)
                                           : -1.0;
            if (e1 >= 0.0 && e1 < s->e0) {
                mid_mesh = base;
                mid_mesh.positions = mid_pos;
                r = meso_bake_mesh_chunk(&mid_mesh, NULL, &mid_chunk, err);
                mid = chunks[0];
                mid.data = mid_chunk.data;
                mid.size = mid_chunk.size;
                mid.desc.encoding = mid_chunk.encoding;
                mid.desc.decoded_size = mid_chunk.decoded_size;
                standins.standin_mesh = &mid_mesh;
                standins.standin_chunk = &mid;
                standins.chain_e0 = s->e0;
                standins.e0 = e1;
            }
            /* The stand-ins' vertex colours (FORMAT.md §7.3 VCOL): with a
             * colour, what it shows and the occlusion; without one the
             * occlusion alone (level 0 shows the draw's albedo, darkened
             * where the surface is low in the shell). */
            mesoi_shell_colours sc;
            mesoi_appearance shows;
            if (r == MESO_OK && a->texture && base.uvs && !a->frames) {
                const double tc = meso_seconds();
                mesoi_shell_appearance(&base, &s->tx.fn, s->col.rgba ? &s->col : NULL,
                                       (const double[2]){cr.scale[0], cr.scale[1]}, sdir_out ? sdir_out : sdir,
                                       sdir_layers, &sc, &shows);
                r = mesoi_standin_levels_appearance(&standins, &base, 0.25 * meso_mesh_mean_edge(&base), &shows,
                                                    s->run.common.threads, err);
                if (r == MESO_OK)
                    mesoi_run_stage(&s->run, "levels", 0.99, 0.99, "stand-in colours: %u levels (%.0f ms)",
                                    standins.count, 1e3 * (meso_seconds() - tc));
            }
            if (r == MESO_OK)
                r = native_errors(s, &base, sdir_out ? sdir_out : sdir, sdir_layers, &standins, err);
            if (r == MESO_OK)
                r = base_levels_make(s, &base, sdir_out ? sdir_out : sdir, sdir_layers, thick, rec.bbox_min,
                                     rec.bbox_max, &standins, &bases, rep, err);
            if (r == MESO_OK)
                n += native_chunks(s, &standins, &bases, chunks, n);
            if (r == MESO_OK)
                n += mesoi_standin_levels_append(&standins, &base, &chunks[0], rec.bbox_min, rec.bbox_max,
                                                 chunks + n, rep);
            if (r == MESO_OK && standins.standin_mesh) {
                /* Level 1's record says it is the mid-surface; the chain's
                 * errors are the base mesh's plus their own, which an
                 * update reads back (shell_update.c read_chain). */
                cJSON* l1 = cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(rep, "levels"), 1 + (int)standins.native);
                cJSON_AddStringToObject(l1, "surface", "mid");
                cJSON_AddNumberToObject(rep, "standin_chain_base_error", (double)mesoi_f32_up(s->e0));
            }
            /* The shell in parts (shell_parts.c): prisms near, stand-in patches far. */
            if (r == MESO_OK && a->parts >= 0 && MESO_HAVE_MESHOPTIMIZER) {
                const double tp = meso_seconds();
                /* The patches are the stand-in's triangles, with its baked normals. */
                meso_mesh standin = standins.standin_mesh ? *standins.standin_mesh : base;
                if (standins.normals)
                    standin.normals = standins.normals;
                const mesoi_shell_parts_input pin = {
                    .standin = &standin,
                    .baked_normals = standins.normals != NULL,
                    .standin_error = standins.e0,
                    .base = &base,
                    .sdir = sdir_out ? sdir_out : sdir,
                    .layers = sdir_layers,
                    .shows = standins.shows,
                    .vcol_components = standins.vcol_components,
                    .colour_spacing = 0.25 * meso_mesh_mean_edge(&base),
                    .object = 1,
                    .part_triangles = a->parts > 0 ? (uint32_t)a->parts : 0,
                    .threads = s->run.common.threads};
                r = mesoi_shell_parts_build(&pin, &parts, err);
                if (r == MESO_OK && parts.count) {
                    s->rep->parts = parts.count;
                    s->rep->part_levels = parts.records;
                    s->rep->part_bytes = parts.bytes;
                    cJSON* jp = cJSON_AddObjectToObject(rep, "parts");
                    cJSON_AddNumberToObject(jp, "count", parts.count);
                    cJSON_AddNumberToObject(jp, "levels", parts.records);
                    cJSON_AddNumberToObject(jp, "neighbour_pairs", parts.edges);
                    cJSON_AddNumberToObject(jp, "bytes", (double)parts.bytes);
                    mesoi_run_stage(&s->run, "parts", 0.99, 0.99, "%u parts, %u part levels, %zu bytes (%.0f ms)",
                                    parts.count, parts.records, parts.bytes, 1e3 * (meso_seconds() - tp));
                }
            }
        }
        if (r == MESO_OK && parts.chunk_count) {
            all = malloc(sizeof(mesoi_chunk) * (n + parts.chunk_count));
            if (!all)
                r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "shell parts: out of memory");
            else {
                memcpy(all, chunks, sizeof(mesoi_chunk) * n);
                memcpy(all + n, parts.chunks, sizeof(mesoi_chunk) * parts.chunk_count);
            }
        }
        if (r == MESO_OK)
            r = mesoi_output_build(meta, rep, &rec, all ? all : chunks, all ? n + parts.chunk_count : n, out, err);
    }
    cJSON_Delete(meta);
    cJSON_Delete(rep);
    mesoi_standin_levels_free(&standins);
    base_levels_free(&bases);
    mesoi_shell_parts_free(&parts);
    free(all);
    free(chunk.data);
    free(mid_chunk.data);
    free(mid_pos);
    free(thick);
    free(pos_out);
    free(normals_out);
    free(sdir_out);
    if (sdir != s->d)
        free(sdir);
    return r;
}

meso_result meso_bake_shell(const meso_bake_shell_options* o, meso_bake_output** out, meso_bake_shell_report* report,
                            meso_error* err)
{
    if (!o || !out)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "meso_bake_shell: NULL options or output");
    *out = NULL;
    meso_bake_shell_report rep_local;
    shell_bake s;
    memset(&s, 0, sizeof(s));
    s.rep = report ? report : &rep_local;
    memset(s.rep, 0, sizeof(*s.rep));
    meso_result r = normalise(o, &s.a, err);
    if (r != MESO_OK)
        return r;
    const meso_bake_shell_options* a = &s.a;
    mesoi_run_begin(&s.run, &a->common);
    double t = meso_seconds();
    /* The texture first: a bad spec fails before any mesh work. */
    const int from_mesh = mesoi_shell_color_is_from_mesh(a->color);
    if (a->texture)
        r = mesoi_shell_texture_prepare(&s.run, a, &s.tx, err);
    if (r == MESO_OK && a->color && !from_mesh)
        r = color_prepare(&s, 0, err);
    if (r == MESO_OK && from_mesh)
        r = mesoi_load_input_materials(&s.run, a->input, a->mesh, &s.m, &s.mats, &s.rep->fixes, err);
    else if (r == MESO_OK)
        r = mesoi_load_input(&s.run, a->input, a->mesh, &s.m, &s.rep->fixes, err);
    const double diag = r == MESO_OK ? meso_mesh_bounds(&s.m, s.lo, s.hi) : 0;
    s.rep->seconds_load = meso_seconds() - t;
    s.h = a->thickness > 0 ? a->thickness : a->thickness_rel * diag;
    if (r == MESO_OK)
        r = require_shellable(&s.m, a->input ? a->input : MESOI_MEMORY_INPUT, diag, !a->update,
                              s.run.common.threads, &s.topo, &s.check, s.rep, err);
    t = meso_seconds();
    if (r == MESO_OK && a->texture)
        r = mesoi_shell_texture_uvs(&s.run, a, &s.m, s.lo, s.hi, &s.tx, err);
    if (r == MESO_OK && from_mesh)
        r = color_prepare(&s, 1, err);
    if (r == MESO_OK)
        native_trim(&s);
    s.rep->seconds_texture = meso_seconds() - t;
    if (r == MESO_OK && a->update) {
        t = meso_seconds();
        r = mesoi_shell_prior_load(a->update, a, &s.h, &s.m, s.tx.source, s.tx.indices,
                                   s.m.vertex_count + s.tx.seam_vertices, &s.prior, err);
        s.rep->vertices_moved = s.prior.moved;
        s.rep->vertices_recomputed = s.prior.redo_count;
        s.rep->update_radius = s.prior.radius;
        s.rep->update_moved_max = s.prior.moved_max;
        s.rep->seconds_load += meso_seconds() - t; /* OLD's read, and the region */
        t = meso_seconds();
        if (r == MESO_OK)
            r = mesoi_shell_update_base_check(&s.m, &s.prior, a->input ? a->input : MESOI_MEMORY_INPUT,
                                              s.run.common.threads, err);
        s.rep->seconds_check += meso_seconds() - t;
        if (r == MESO_OK)
            mesoi_run_stage(&s.run, "update", 0.2, 0.2,
                            "update of %s: %u vertices moved, %u of %u recomputed (within %g of a moved face)",
                            mesoi_base_name(a->update), s.prior.moved, s.prior.redo_count, s.m.vertex_count,
                            s.prior.radius);
    }
    meso_bake_shell_report* rep = s.rep;
    rep->vertices = s.m.vertex_count;
    rep->triangles = s.m.triangle_count;
    rep->boundary_edges = s.topo.boundary_edges;
    rep->thickness = s.h;
    rep->bbox_diagonal = diag;
    rep->density = s.tx.fn.kind == MESO_TEXFN_DENSITY;
    memcpy(rep->texture_res, s.tx.fn.dims, sizeof(rep->texture_res));
    memcpy(rep->dist_res, s.tx.dist.dims, sizeof(rep->dist_res));
    rep->dist_solid_cells = s.tx.dist.solid_cells;
    rep->seam_vertices = s.tx.seam_vertices;
    rep->planar_uvs = s.tx.plane[0] != 0;
    if (r == MESO_OK)
        mesoi_run_stage(&s.run, "load", 0.15, 0.15,
                        "%s: %u vertices, %u triangles, %u boundary edges; thickness %g (%.3g of the diagonal) "
                        "(%.0f ms)",
                        mesoi_input_label(a->input), s.m.vertex_count, s.m.triangle_count, s.topo.boundary_edges, s.h,
                        s.h / diag, mesoi_run_ms(&s.run));
    if (r == MESO_OK && a->texture)
        mesoi_run_stage(&s.run, "texture coordinates", 0.2, 0.2,
                        "texture coordinates (%s): %u seam vertices added, %u output vertices", s.tx.uv_source,
                        s.tx.seam_vertices, s.m.vertex_count + s.tx.seam_vertices);
    if (r == MESO_OK)
        r = directors(&s, err);
    if (r == MESO_OK)
        standin_start(&s);
    if (a->update)
        rep->vertices_recomputed = s.prior.redo_count; /* with the region's growth (shell_update.c) */
    t = meso_seconds();
    if (r == MESO_OK)
        r = validate(&s, err);
    rep->seconds_validate = meso_seconds() - t;
    if (r == MESO_OK)
        r = allowed(&s, err); /* seconds_allowed: allowed_side's */
    t = meso_seconds();
    if (r == MESO_OK)
        r = assemble(&s, out, err);
    rep->seconds_assemble = meso_seconds() - t;
    if (s.check.state == 1) { /* failed before the verdict was read: the input's error first, as with one thread */
        meso_error ce;
        const meso_result cr = input_check_join(&s.check, rep, &ce);
        if (cr != MESO_OK && r != MESO_OK) {
            r = cr;
            if (err)
                *err = ce;
        }
    }
    shell_free(&s);
    if (r == MESO_OK)
        mesoi_run_done(&s.run);
    return r;
}
