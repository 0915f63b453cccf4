/* libmeso frusta objects (FORMAT.md §7.2 kind 4) on llvmpipe against the
 * exact CPU reference (runtime/reference/frustum_reference.h:
 * meso_ref_frusta_render, double precision, relief by dense sampling plus
 * bisection to 1e-9): a single cone, cylinder and pointed tip, a bent
 * chain (3 segments, 60° bends), a tapered chain (seam gaps), a sharp fold
 * whose caps cross (kept, so the bound falls back to a box; and as mesobake
 * bakes it, with a ball joint), a branch point (one node with 3 children, a
 * ball), NeuroM's radius jump (tests/data/neurom_fat_end.swc), the camera
 * inside a frustum, relief-mapped chains and branches (from outside,
 * grazing, and the camera inside the relief layer, with relief_steps swept
 * from 8 to 256: error against cost; twisted, mesobake frusta --twist), colour maps
 * (COLR at the relief coordinates: plain, relief, caps, twist, balls), animation through
 * meso_rt_frusta_set_pose, the GL state contract and malformed objects.
 *
 * Files are built here from SWC text through mesobake's own code
 * (tests/common/frusta_scene.h: skeleton → frustum model → frusta records)
 * and the format library's writer, with a synthetic tileable relief map.
 *
 * Metrics (tests/common/shell_scene.h's compare(), printed per case):
 *  - coverage mismatch: pixels covered in one image whose 3x3 neighbourhood
 *    in the other is entirely uncovered, over the pixels covered in either;
 *  - off > 1 px: GL hits (unprojected from the depth buffer) farther than 2
 *    pixel footprints from every reference hit in the 3x3 neighbourhood;
 *  - hit error: mean distance from the GL hit to the reference hit of the
 *    same pixel, in pixel footprints at that depth;
 *  - colour MAE over pixels covered in both (0..1);
 *  - holes: pixels whose whole 3x3 neighbourhood is covered by the
 *    reference (inside its silhouette, not on an edge) and which GL leaves
 *    as background. Must be 0 everywhere, joints and branches included.
 * Tolerances: see check_close() below.
 * MESO_TEST_PNG=DIR writes each case's GL, reference and difference images. */
#include "gl_api.h"
#include "meso_clock.h"
#include "test_util.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "frusta_pose.h"
#include "frusta_scene.h"
#include "frustum_reference.h"
#include "gl_fbo.h"
#include "gl_log.h"
#include "meso_rt.h"
#include "shell_scene.h"

enum { W = 160, H = 120 };

#define TEST_GLF(X)                                                                                              \
    X(PFNGLGETINTEGERVPROC, GetIntegerv) X(PFNGLISENABLEDPROC, IsEnabled) X(PFNGLENABLEPROC, Enable)             \
    X(PFNGLDISABLEPROC, Disable) X(PFNGLDEPTHFUNCPROC, DepthFunc) X(PFNGLCULLFACEPROC, CullFace)                 \
    X(PFNGLACTIVETEXTUREPROC, ActiveTexture) X(PFNGLFRONTFACEPROC, FrontFace) X(PFNGLDEPTHMASKPROC, DepthMask)   \
    X(PFNGLGETERRORPROC, GetError)

typedef struct test_gl {
#define TEST_M(t, n) t n;
    TEST_GLF(TEST_M)
#undef TEST_M
} test_gl;

/* A capturing logger: the last error item. */
typedef struct ctx {
    meso_rt* rt;
    test_fbo fbo;
    test_gl gl;
    uint8_t* rgba;
    float* depth;
    log_capture log;
} ctx;

/* >>rendering and comparing ------------------------------------------------ */

/* A camera looking at the file's bounding box from direction `dir`. */
static camera auto_camera(const uint8_t* file, size_t size, const double dir[3], double fovy, double dist_scale)
{
    meso_file* f = NULL;
    meso_error err;
    CHECK(meso_file_open_memory(file, size, NULL, &f, &err) == MESO_OK);
    meso_object_record rec;
    uint32_t n = 0;
    CHECK(meso_file_objects(f, &rec, 1, &n, &err) == MESO_OK && n == 1);
    meso_file_close(f);
    double lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
        lo[k] = rec.bbox_min[k];
        hi[k] = rec.bbox_max[k];
    }
    return camera_view_box(lo, hi, dir, fovy, dist_scale, 0.02);
}


/* Reference pixels inside its silhouette (3x3 covered) that GL leaves empty. */
static long holes(const ctx* c, const meso_ref_image* ref)
{
    long n = 0;
    for (int y = 1; y + 1 < H; ++y)
        for (int x = 1; x + 1 < W; ++x) {
            int inside = 1;
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx)
                    inside &= ref->coverage[(size_t)(y + dy) * W + (size_t)(x + dx)] != 0;
            n += inside && !(c->depth[(size_t)y * W + x] < 1.0f);
        }
    return n;
}

typedef struct result {
    metrics m;
    long holes;
    double draw_ms;
    meso_rt_draw_stats stats;
} result;

/* Draws `obj` with GL and `ref` with the reference, compares. */
static result render_compare(ctx* c, const char* name, meso_rt_object obj, const meso_ref_frusta* ref,
                             const camera* cam, const meso_rt_draw_desc* knobs)
{
    meso_rt_draw_desc d = knobs ? *knobs : (meso_rt_draw_desc){0};
    camera_matrices(cam, d.view, d.proj);
    result res = {0};
    d.stats = &res.stats;
    test_fbo_clear(&c->fbo, 0.0f, 0.0f, 0.0f);
    CHECK(meso_rt_draw(c->rt, obj, &d) == MESO_OK); /* warm-up: shader JIT */
    test_fbo_clear(&c->fbo, 0.0f, 0.0f, 0.0f);
    c->fbo.Finish();
    const double t0 = (1e3 * meso_seconds());
    CHECK(meso_rt_draw(c->rt, obj, &d) == MESO_OK);
    c->fbo.Finish();
    res.draw_ms = (1e3 * meso_seconds()) - t0;
    test_fbo_read(&c->fbo, c->rgba, c->depth);

    meso_ref_view v = {.width = W, .height = H};
    for (int i = 0; i < 16; ++i)
        v.view[i] = d.view[i], v.proj[i] = d.proj[i];
    meso_ref_image img;
    CHECK(meso_ref_frusta_render(ref, &v, &img) == MESO_OK);
    res.m = compare(c->rgba, c->depth, &img, d.view, d.proj, cam->fovy, name);
    res.holes = holes(c, &img);
    printf("%-26s covered gl %5ld ref %5ld  coverage mismatch %.4f  off >1px %.4f  hit error %.3f px (>1 px: %.4f)  "
           "colour MAE %.4f  holes %ld  draw %.2f ms  steps/fragment %.1f\n",
           name, res.m.covered_gl, res.m.covered_ref, res.m.coverage_mismatch, res.m.off_pixel, res.m.hit_err_px,
           res.m.hit_gt1, res.m.colour_mae, res.holes, res.draw_ms,
           res.stats.fragments ? (double)res.stats.steps / (double)res.stats.fragments : 0.0);
    meso_ref_image_free(&img);
    return res;
}

/* The tolerances (measured margins in the log): coverage mismatch and
 * > 1 px hits at most 0.5% of the pixels, mean hit error at most a quarter
 * pixel, mean colour error at most `colour_tol`, and no holes. */
static void check_close(const char* what, result r, double colour_tol)
{
    CHECK_MSG(r.m.coverage_mismatch <= 0.005 && r.m.off_pixel <= 0.005 && r.m.hit_err_px <= 0.25 &&
                  r.m.colour_mae <= colour_tol && r.holes == 0,
              "%s vs reference: coverage %.4f, off > 1 px %.4f, hit error %.3f px, colour %.4f, holes %ld", what,
              r.m.coverage_mismatch, r.m.off_pixel, r.m.hit_err_px, r.m.colour_mae, r.holes);
}

/* Loads object 1 into libmeso and the reference. */
static meso_rt_object load_both(ctx* c, const uint8_t* file, size_t size, meso_ref_frusta* ref)
{
    meso_file* f = NULL;
    meso_error err;
    CHECK(meso_file_open_memory(file, size, NULL, &f, &err) == MESO_OK);
    meso_rt_object obj;
    CHECK_MSG(meso_rt_load_object(c->rt, f, 1, &obj) == MESO_OK, "%s", c->log.message);
    CHECK_MSG(meso_ref_frusta_load(f, 1, ref, &err) == MESO_OK, "%s", err.message);
    meso_file_close(f);
    return obj;
}

/* One case: build, load, render from each direction, check. */
static result run_case(ctx* c, const char* name, const char* swc, const frusta_file_opts* o, const double dir[3],
                       double colour_tol)
{
    size_t size;
    uint8_t* file = frusta_file(swc, o, &size);
    meso_ref_frusta ref;
    meso_rt_object obj = load_both(c, file, size, &ref);
    const camera cam = auto_camera(file, size, dir, 0.7, 0.85);
    result r = render_compare(c, name, obj, &ref, &cam, NULL);
    CHECK(r.m.covered_ref > 300);
    check_close(name, r, colour_tol);
    meso_ref_frusta_free(&ref);
    meso_rt_release_object(c->rt, obj);
    free(file);
    return r;
}

/* GL's image of `swc` baked with `o` against the reference of it baked
 * with `other`: the colour MAE (a difference the options must make). */
static double against_other_reference(ctx* c, const char* name, const char* swc, const frusta_file_opts* o,
                                      const frusta_file_opts* other, const double dir[3])
{
    size_t size, size0;
    uint8_t* file = frusta_file(swc, o, &size);
    uint8_t* file0 = frusta_file(swc, other, &size0);
    meso_ref_frusta ref, ref0;
    meso_rt_object obj = load_both(c, file, size, &ref);
    meso_file* f0 = NULL;
    meso_error err;
    CHECK(meso_file_open_memory(file0, size0, NULL, &f0, &err) == MESO_OK);
    CHECK(meso_ref_frusta_load(f0, 1, &ref0, &err) == MESO_OK);
    meso_file_close(f0);
    const camera cam = auto_camera(file, size, dir, 0.7, 0.85);
    result r = render_compare(c, name, obj, &ref0, &cam, NULL);
    printf("%s: colour MAE %.4f (must be large)\n", name, r.m.colour_mae);
    meso_ref_frusta_free(&ref);
    meso_ref_frusta_free(&ref0);
    meso_rt_release_object(c->rt, obj);
    free(file);
    free(file0);
    return r.m.colour_mae;
}

/* >>cases ------------------------------------------------------------------ */

static const char* const swc_cone = "1 1 0 0 0 0.5 -1\n2 1 0.3 1.6 0.1 0.2 1\n";
static const char* const swc_cylinder = "1 1 0 0 0 0.35 -1\n2 1 1.6 0.3 -0.2 0.35 1\n";
static const char* const swc_tip = "1 1 0 0 0 0.45 -1\n2 1 0.2 1.5 0.3 0 1\n";
/* Three segments, each turned 60° from the previous (in a plane). */
static const char* const swc_bent = "1 1 0 0 0 0.22 -1\n2 1 1 0 0 0.22 1\n3 1 1.5 0.8660254 0 0.22 2\n"
                                    "4 1 1 1.7320508 0 0.22 3\n";
/* A tapered bent chain (seam gaps at the joints). */
static const char* const swc_tapered = "1 1 0 0 0 0.3 -1\n2 1 1.2 0 0 0.24 1\n3 1 1.8 1.0 0.1 0.18 2\n"
                                       "4 1 1.3 1.9 0.3 0.12 3\n";
/* One node with three children (and a parent): a branch point with a ball. */
static const char* const swc_branch = "1 1 0 0 0 0.3 -1\n2 1 1.2 0 0 0.3 1\n3 1 2.0 0.7 0.1 0.2 2\n"
                                      "4 1 1.9 -0.8 0 0.2 2\n5 1 2.1 0 0.8 0.15 2\n";

static void test_single(ctx* c)
{
    const double dir[3] = {1.0, 0.4, 0.8};
    const frusta_file_opts plain = {0};
    run_case(c, "single_cone", swc_cone, &plain, dir, 0.01);
    run_case(c, "single_cylinder", swc_cylinder, &plain, dir, 0.01);
    /* A pointed tip: eq. 8's N_u = unit(P1 - c1) with P1 - c1 -> 0; both
     * renderers take its exact limit (frusta_frag.glsl and
     * frustum_reference.c, eq8_normal). */
    run_case(c, "zero_radius_tip", swc_tip, &plain, dir, 0.01);
    const double end_on[3] = {0.1, 1.0, 0.15}; /* looking into the cap */
    run_case(c, "cone_end_on", swc_cone, &plain, end_on, 0.01);
}

static void test_chains(ctx* c)
{
    const frusta_file_opts plain = {0};
    const double front[3] = {0.1, 0.2, 1.0}, oblique[3] = {-0.8, 0.5, 0.6};
    run_case(c, "bent_chain_60deg", swc_bent, &plain, front, 0.01);
    run_case(c, "bent_chain_oblique", swc_bent, &plain, oblique, 0.01);
    run_case(c, "tapered_chain", swc_tapered, &plain, oblique, 0.01);
    /* A ~160° fold with thick segments, baked with the paper's joint plane
     * kept although the caps cross inside the segments (mesobake would
     * turn the joint into a ball): the §2.6 pyramid cut by crossing planes
     * is no hexahedron, and the bound falls back to a box. */
    const char* fold = "1 1 0 0 0 0.4 -1\n2 1 1 0 0 0.4 1\n3 1 0.06 0.35 0 0.4 2\n";
    run_case(c, "crossing_caps_kept", fold, &(frusta_file_opts){.keep_crossing_caps = 1}, front, 0.01);
    run_case(c, "crossing_caps_kept_obl", fold, &(frusta_file_opts){.keep_crossing_caps = 1}, oblique, 0.01);
    run_case(c, "crossing_caps_ball_joint", fold, &plain, oblique, 0.01);
    run_case(c, "branch_ball", swc_branch, &plain, front, 0.01);
    run_case(c, "branch_ball_oblique", swc_branch, &plain, oblique, 0.01);
    /* NeuroM's fat end: radius 0.5 -> 13 over a length of 1. */
    char path[4096];
    snprintf(path, sizeof(path), "%s", test_data("neurom_fat_end.swc"));
    const double side[3] = {1.0, 0.3, 0.2};
    run_case(c, "neurom_radius_jump", path, &plain, side, 0.01);
    run_case(c, "neurom_radius_jump_obl", path, &plain, oblique, 0.01);
}

static void test_camera_inside(ctx* c)
{
    /* A thick cylinder; the eye inside it near one end, looking along the
     * axis and a little sideways: every pixel sees the inner wall. */
    const frusta_file_opts plain = {0};
    size_t size;
    uint8_t* file = frusta_file("1 1 0 0 0 0.6 -1\n2 1 0 0 3 0.6 1\n3 1 0 0.8 4.2 0.4 2\n", &plain, &size);
    meso_ref_frusta ref;
    meso_rt_object obj = load_both(c, file, size, &ref);
    const camera cam = {.eye = {0.1, -0.15, 0.4}, .at = {0.3, 0.1, 3.0}, .fovy = 1.1, .zn = 0.05, .zf = 20};
    result r = render_compare(c, "camera_inside", obj, &ref, &cam, NULL);
    CHECK(r.m.covered_gl == W * H && r.m.covered_ref == W * H);
    check_close("camera inside a frustum", r, 0.01);
    meso_ref_frusta_free(&ref);
    meso_rt_release_object(c->rt, obj);
    free(file);
}

/* The RELF options for a height texture. */
#define RELIEF(t) .relief = (t)->texels, .relief_w = (t)->w, .relief_h = (t)->h

static void test_relief(ctx* c, const texture* height)
{
    const frusta_file_opts rel = {.depth = 0.08, .u_repeat = 3, RELIEF(height)};
    const double front[3] = {0.1, 0.2, 1.0}, oblique[3] = {-0.8, 0.5, 0.6};
    run_case(c, "relief_bent_chain", swc_bent, &rel, front, 0.02);
    run_case(c, "relief_bent_chain_obl", swc_bent, &rel, oblique, 0.02);
    run_case(c, "relief_tapered_chain", swc_tapered, &rel, oblique, 0.02);
    run_case(c, "relief_branch", swc_branch, &rel, front, 0.02);
    /* Twisted (§2.3, mesobake frusta --twist): the ribs become helices;
     * u = ... + v·twist/2π in frusta_frag.glsl against the reference. */
    const frusta_file_opts twisted = {.depth = 0.08, .u_repeat = 3, .twist = 120, RELIEF(height)};
    run_case(c, "relief_twisted_cylinder", swc_cylinder, &twisted, front, 0.02);
    /* The twist shows: GL's twisted image against the untwisted reference
     * is far off (so the agreement above is not vacuous). */
    CHECK(against_other_reference(c, "twisted_vs_untwisted_ref", swc_cylinder, &twisted, &rel, front) > 0.01);
    run_case(c, "relief_twisted_bent_chain", swc_bent, &twisted, oblique, 0.02);
    run_case(c, "relief_twisted_tapered", swc_tapered, &(frusta_file_opts){.depth = 0.08, .u_repeat = 3,
                                                            .twist = -200, RELIEF(height)}, front, 0.02);
    /* Grazing: along the first segment's axis. */
    const double along[3] = {-1.0, 0.05, 0.08};
    run_case(c, "relief_grazing", swc_bent, &rel, along, 0.02);
    /* Camera inside the relief layer of a thick cylinder. */
    size_t size;
    const frusta_file_opts thick = {.depth = 0.25, .u_repeat = 4, RELIEF(height)};
    uint8_t* file = frusta_file("1 1 0 0 0 0.6 -1\n2 1 0 0 3 0.6 1\n", &thick, &size);
    meso_ref_frusta ref;
    meso_rt_object obj = load_both(c, file, size, &ref);
    const camera cam = {.eye = {0.0, 0.72, 0.3}, .at = {0.1, 0.5, 2.0}, .fovy = 1.1, .zn = 0.02, .zf = 20};
    result r = render_compare(c, "inside_the_relief_layer", obj, &ref, &cam, NULL);
    CHECK(r.m.covered_gl > W * H / 2);
    check_close("camera inside the relief layer", r, 0.02);
    /* The knob relief_steps trades cost for accuracy here (grazing rays
     * with long chords through the layer): error against the reference
     * and counted samples per fragment, 8 .. 256 uniform steps. */
    const int steps[6] = {8, 16, 32, 64, 128, 256};
    result sweep[6];
    for (int i = 0; i < 6; ++i) {
        char name[64];
        snprintf(name, sizeof(name), "relief_steps_%d", steps[i]);
        sweep[i] = render_compare(c, name, obj, &ref, &cam, &(meso_rt_draw_desc){.frusta = {.relief_steps = steps[i]}});
        CHECK(sweep[i].stats.supported && (i == 0 || sweep[i].stats.steps > sweep[i - 1].stats.steps));
    }
    CHECK(sweep[0].m.hit_err_px > 4 * sweep[3].m.hit_err_px && sweep[5].m.hit_err_px < sweep[3].m.hit_err_px);
    CHECK(sweep[5].m.hit_err_px <= 0.1 && sweep[5].holes == 0);
    meso_ref_frusta_free(&ref);
    meso_rt_release_object(c->rt, obj);
    free(file);
}

/* Sway: rotate each node about its parent by a multiple of `angle`
 * (radians) about z, accumulated down the tree (parents come first). */
static void sway(const int32_t* parents, uint32_t n, const float* rest, float* out, double angle)
{
    memcpy(out, rest, sizeof(float) * 3 * n);
    for (uint32_t i = 0; i < n; ++i) {
        const int32_t p = parents[i];
        if (p < 0)
            continue;
        const double dx = rest[3 * i] - rest[3 * p], dy = rest[3 * i + 1] - rest[3 * p + 1];
        const double cs = cos(angle * (i % 3 + 1)), sn = sin(angle * (i % 3 + 1));
        out[3 * i] = (float)(out[3 * p] + cs * dx - sn * dy);
        out[3 * i + 1] = (float)(out[3 * p + 1] + sn * dx + cs * dy);
        out[3 * i + 2] = out[3 * p + 2] + (rest[3 * i + 2] - rest[3 * p + 2]);
    }
}

/* The records of object 1 as the reference sees them after the same pose. */
static void pose_reference(const uint8_t* file, size_t size, meso_ref_frusta* ref, const float* pos, uint32_t n)
{
    meso_frustum_rec* recs;
    meso_frustum_ball_rec* balls;
    uint32_t count, ball_count;
    frusta_file_records(file, size, &recs, &count, &balls, &ball_count);
    CHECK(count == ref->seg_count && ball_count == ref->ball_count);
    CHECK(meso_frusta_pose(recs, count, balls, ball_count, pos, n) == 0);
    for (uint32_t i = 0; i < count; ++i)
        meso_ref_frustum_from_rec(&recs[i], &ref->segs[i]);
    for (uint32_t b = 0; b < ball_count; ++b)
        meso_ref_ball_from_rec(&balls[b], &ref->balls[b]);
    free(recs);
    free(balls);
}

static void test_animation(ctx* c, const texture* height)
{
    const char* swc = swc_branch;
    const frusta_file_opts rel = {.depth = 0.06, .u_repeat = 3, RELIEF(height)};
    size_t size;
    uint8_t* file = frusta_file(swc, &rel, &size);
    meso_ref_frusta ref;
    meso_rt_object obj = load_both(c, file, size, &ref);
    uint32_t nf = 0, nn = 0;
    CHECK(meso_rt_frusta_info(c->rt, obj, &nf, &nn) == MESO_OK && nf == ref.seg_count && nn > 0);
    float* rest = malloc(sizeof(float) * 3 * nn);
    float* pos = malloc(sizeof(float) * 3 * nn);
    int32_t* parents = malloc(sizeof(int32_t) * nn);
    CHECK(meso_rt_frusta_rest_pose(c->rt, obj, rest, parents, nn) == MESO_OK);
    CHECK(meso_rt_frusta_rest_pose(c->rt, obj, rest, NULL, nn + 1) == MESO_ERR_INVALID_ARG);
    /* Rest pose set explicitly: the same image as loaded. */
    CHECK(meso_rt_frusta_set_pose(c->rt, obj, rest, nn) == MESO_OK);
    const double dir[3] = {0.1, 0.2, 1.0};
    const camera cam = auto_camera(file, size, dir, 0.8, 1.15);
    result r0 = render_compare(c, "animation_rest_pose", obj, &ref, &cam, NULL);
    check_close("rest pose through set_pose", r0, 0.02);
    /* Moved nodes: GL against the reference of meso_frusta_pose'd records. */
    sway(parents, nn, rest, pos, 0.25);
    CHECK(meso_rt_frusta_set_pose(c->rt, obj, pos, nn) == MESO_OK);
    pose_reference(file, size, &ref, pos, nn);
    result r1 = render_compare(c, "animation_swayed", obj, &ref, &cam, NULL);
    check_close("swayed pose", r1, 0.02);
    sway(parents, nn, rest, pos, -0.4);
    CHECK(meso_rt_frusta_set_pose(c->rt, obj, pos, nn) == MESO_OK);
    pose_reference(file, size, &ref, pos, nn);
    result r2 = render_compare(c, "animation_swayed_back", obj, &ref, &cam, NULL);
    check_close("swayed back", r2, 0.02);
    /* Bounds follow the pose. */
    float lo[3], hi[3];
    CHECK(meso_rt_object_bounds(c->rt, obj, lo, hi) == MESO_OK);
    for (uint32_t i = 0; i < nn; ++i)
        for (int k = 0; k < 3; ++k)
            CHECK(pos[3 * i + k] >= lo[k] && pos[3 * i + k] <= hi[k]);
    /* Bad calls fail cleanly and change nothing. */
    c->log.errors = 0;
    CHECK(meso_rt_frusta_set_pose(c->rt, obj, pos, nn - 1) == MESO_ERR_INVALID_ARG);
    CHECK(c->log.errors == 1 && c->log.last == MESO_LOGITEM_INVALID_ARGUMENT);
    float* collapsed = malloc(sizeof(float) * 3 * nn);
    memcpy(collapsed, pos, sizeof(float) * 3 * nn);
    memcpy(collapsed + 3, collapsed, sizeof(float) * 3); /* node 1 onto node 0 */
    CHECK(meso_rt_frusta_set_pose(c->rt, obj, collapsed, nn) == MESO_ERR_INVALID_ARG);
    result r3 = render_compare(c, "after_a_refused_pose", obj, &ref, &cam, NULL);
    check_close("a refused pose keeps the last one", r3, 0.02);
    free(collapsed);
    free(parents);
    free(rest);
    free(pos);
    meso_ref_frusta_free(&ref);
    meso_rt_release_object(c->rt, obj);
    free(file);
}

/* meso_rt_draw restores what it changes (meso_rt.h). */
static void test_state_contract(ctx* c)
{
    const frusta_file_opts plain = {0};
    size_t size;
    uint8_t* file = frusta_file(swc_branch, &plain, &size);
    meso_file* f = NULL;
    meso_error err;
    CHECK(meso_file_open_memory(file, size, NULL, &f, &err) == MESO_OK);
    test_gl* gl = &c->gl;
    while (gl->GetError() != GL_NO_ERROR) {
    }
    meso_rt_object obj;
    CHECK(meso_rt_load_object(c->rt, f, 1, &obj) == MESO_OK);
    meso_file_close(f);
    gl->Disable(GL_DEPTH_TEST);
    gl->DepthFunc(GL_GEQUAL);
    gl->DepthMask(GL_FALSE);
    gl->Enable(GL_CULL_FACE);
    gl->CullFace(GL_BACK);
    gl->FrontFace(GL_CW);
    gl->ActiveTexture(GL_TEXTURE3);
    const double dir[3] = {0, 0, 1};
    const camera cam = auto_camera(file, size, dir, 0.7, 1.1);
    meso_rt_draw_desc d = {0};
    camera_matrices(&cam, d.view, d.proj);
    CHECK(meso_rt_draw(c->rt, obj, &d) == MESO_OK);
    GLint v = 0;
    gl->GetIntegerv(GL_DEPTH_FUNC, &v);
    CHECK(v == GL_GEQUAL);
    gl->GetIntegerv(GL_DEPTH_WRITEMASK, &v);
    CHECK(v == GL_FALSE);
    gl->GetIntegerv(GL_CULL_FACE_MODE, &v);
    CHECK(v == GL_BACK);
    gl->GetIntegerv(GL_FRONT_FACE, &v);
    CHECK(v == GL_CW);
    gl->GetIntegerv(GL_ACTIVE_TEXTURE, &v);
    CHECK(v == GL_TEXTURE3);
    gl->GetIntegerv(GL_CURRENT_PROGRAM, &v);
    CHECK(v == 0);
    CHECK(!gl->IsEnabled(GL_DEPTH_TEST) && gl->IsEnabled(GL_CULL_FACE));
    /* Neither the upload nor the draw raised a GL error (every query and
     * call exists on the API the test runs on: desktop or ES). */
    CHECK(gl->GetError() == GL_NO_ERROR);
    gl->Enable(GL_DEPTH_TEST);
    gl->DepthFunc(GL_LESS);
    gl->DepthMask(GL_TRUE);
    gl->Disable(GL_CULL_FACE);
    gl->CullFace(GL_BACK);
    gl->FrontFace(GL_CCW);
    gl->ActiveTexture(GL_TEXTURE0);
    meso_rt_release_object(c->rt, obj);
    /* Stale handles and the wrong kind are refused. */
    uint32_t nf = 7;
    CHECK(meso_rt_frusta_info(c->rt, obj, &nf, NULL) == MESO_ERR_INVALID_ARG);
    float p[3] = {0, 0, 0};
    CHECK(meso_rt_frusta_set_pose(c->rt, obj, p, 1) == MESO_ERR_INVALID_ARG);
    free(file);
}

/* Malformed objects: load fails with a logged error, nothing leaks or crashes. */
/* >>colour ------------------------------------------------------------------ */

/* A colour map (RGBA8 sRGB, n x n/2): hues that change over a few texels,
 * with some sharp edges (a checker of two brightnesses). */
static uint8_t* make_color(uint32_t n)
{
    uint8_t* t = malloc(4 * (size_t)n * (n / 2));
    for (uint32_t j = 0; j < n / 2; ++j)
        for (uint32_t i = 0; i < n; ++i) {
            uint8_t* p = t + 4 * ((size_t)j * n + i);
            const double a = 6.283185307179586 * i / n, b = 6.283185307179586 * j / (n / 2);
            const double k = ((i / 4 + j / 4) & 1) ? 1.0 : 0.7;
            p[0] = (uint8_t)lround(k * (150 + 100 * sin(a)));
            p[1] = (uint8_t)lround(k * (130 + 90 * sin(b + 1.0)));
            p[2] = (uint8_t)lround(k * (120 + 100 * cos(a + b)));
            p[3] = 255;
        }
    return t;
}

#define COLOR(t, n) .color = (t), .color_w = (n), .color_h = (n) / 2

/* GL against the reference with a colour map (FORMAT.md §7.2 kind 4 COLR):
 * plain and relief-mapped frusta, caps, twist, balls (the map's mean). */
static void test_color(ctx* c, const texture* height)
{
    enum { N = 32 };
    uint8_t* col = make_color(N);
    const double front[3] = {0.1, 0.2, 1.0}, oblique[3] = {-0.8, 0.5, 0.6}, dir[3] = {1.0, 0.4, 0.8};
    const frusta_file_opts plain = {.u_repeat = 2, COLOR(col, N)};
    run_case(c, "color_cylinder", swc_cylinder, &plain, dir, 0.01);
    run_case(c, "color_cone_end_on", swc_cone, &plain, (double[3]){0.1, 1.0, 0.15}, 0.01);
    run_case(c, "color_bent_chain", swc_bent, &plain, oblique, 0.01);
    run_case(c, "color_branch_ball", swc_branch, &plain, front, 0.01);
    const frusta_file_opts rel = {.depth = 0.08, .u_repeat = 3, RELIEF(height), COLOR(col, N)};
    run_case(c, "color_relief_bent_chain", swc_bent, &rel, oblique, 0.02);
    run_case(c, "color_relief_branch", swc_branch, &rel, front, 0.02);
    const frusta_file_opts twisted = {.depth = 0.08, .u_repeat = 3, .twist = 120, RELIEF(height), COLOR(col, N)};
    run_case(c, "color_relief_twisted", swc_cylinder, &twisted, front, 0.02);
    /* The map shows: GL with it against the reference without it (the
     * default albedo) is far off, so the agreement is not vacuous. */
    const frusta_file_opts uncolored = {.depth = 0.08, .u_repeat = 3, RELIEF(height)};
    CHECK(against_other_reference(c, "color_vs_uncolored_ref", swc_bent, &rel, &uncolored, oblique) > 0.05);
    free(col);
}

static void expect_load_failure(ctx* c, const char* what, const uint8_t* file, size_t size, meso_result want,
                                meso_log_item item)
{
    meso_file* f = NULL;
    meso_error err;
    CHECK(meso_file_open_memory(file, size, NULL, &f, &err) == MESO_OK);
    c->log.errors = 0;
    meso_rt_object obj = {.id = 12345};
    const meso_result r = meso_rt_load_object(c->rt, f, 1, &obj);
    printf("malformed: %-34s -> %s, logged [%d] %s\n", what, meso_result_string(r), (int)c->log.last, c->log.message);
    CHECK_MSG(r == want && obj.id == 0 && c->log.errors >= 1 && c->log.last == item, "%s: got %s", what,
              meso_result_string(r));
    meso_file_close(f);
}

static void test_malformed(ctx* c, const texture* height)
{
    size_t size;
    uint8_t* file;
    file = frusta_file(swc_bent, &(frusta_file_opts){.drop = MESO_CHUNK_FRUS}, &size);
    expect_load_failure(c, "missing FRUS", file, size, MESO_ERR_NOT_FOUND, MESO_LOGITEM_OBJECT_NOT_FOUND);
    free(file);
    file = frusta_file(swc_bent, &(frusta_file_opts){.drop = MESO_CHUNK_SKEL}, &size);
    expect_load_failure(c, "missing SKEL", file, size, MESO_ERR_NOT_FOUND, MESO_LOGITEM_OBJECT_NOT_FOUND);
    free(file);
    file = frusta_file(swc_bent, &(frusta_file_opts){.frus_short = 1}, &size);
    expect_load_failure(c, "FRUS one record short of FSEG", file, size, MESO_ERR_CORRUPT,
                        MESO_LOGITEM_CHUNK_READ_FAILED);
    free(file);
    file = frusta_file(swc_bent, &(frusta_file_opts){.bad_node = 1}, &size);
    expect_load_failure(c, "FSEG node outside SKEL", file, size, MESO_ERR_CORRUPT, MESO_LOGITEM_CHUNK_READ_FAILED);
    free(file);
    file = frusta_file(swc_bent, &(frusta_file_opts){.depth = 0.05, .u_repeat = 2, RELIEF(height), .relief_f32 = 1},
                       &size);
    expect_load_failure(c, "RELF as F32", file, size, MESO_ERR_UNSUPPORTED, MESO_LOGITEM_CHUNK_READ_FAILED);
    free(file);
    /* COLR 16 x 4 x 2 (a volume; frusta colour maps are W x H x 1): refused
     * by the loader and by the full check (6205); so is a second COLR. */
    uint8_t* col = make_color(16);
    file = frusta_file(swc_bent, &(frusta_file_opts){COLOR(col, 16), .color_depth = 2}, &size);
    expect_load_failure(c, "COLR 16 x 4 x 2", file, size, MESO_ERR_UNSUPPORTED, MESO_LOGITEM_CHUNK_READ_FAILED);
    for (int k = 0; k < 2; ++k) {
        meso_file* f = NULL;
        meso_error err;
        CHECK(meso_file_open_memory(file, size, NULL, &f, &err) == MESO_OK);
        const meso_result vr = meso_file_check_object(f, 1, &err);
        printf("validate: %-30s -> %s, issue %u: %s\n", k ? "two COLR chunks" : "COLR 16 x 4 x 2",
               meso_result_string(vr), err.code, err.message);
        CHECK(vr == MESO_ERR_CORRUPT && err.code == MESO_ISSUE_FRUSTA_COLR);
        meso_file_close(f);
        free(file);
        file = frusta_file(swc_bent, &(frusta_file_opts){COLOR(col, 16), .color_twice = 1}, &size);
    }
    free(file);
    file = frusta_file(swc_bent, &(frusta_file_opts){COLOR(col, 16)}, &size);
    {
        meso_file* f = NULL;
        meso_error err;
        CHECK(meso_file_open_memory(file, size, NULL, &f, &err) == MESO_OK);
        CHECK_MSG(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK && meso_file_check_object(f, 1, &err) == MESO_OK,
                  "a good COLR: %s", err.message);
        meso_file_close(f);
    }
    free(file);
    free(col);
    /* FSEG bytes damaged after writing: an unknown flag bit in record 0.
     * The CRC catches it on the read (the content check would too). */
    file = frusta_file(swc_bent, &(frusta_file_opts){0}, &size);
    {
        meso_file* f = NULL;
        meso_error err;
        CHECK(meso_file_open_memory(file, size, NULL, &f, &err) == MESO_OK);
        uint64_t off = 0;
        for (uint32_t i = 0; i < meso_file_chunk_count(f); ++i)
            if (meso_file_chunk(f, i)->type == MESO_CHUNK_FSEG)
                off = meso_file_chunk(f, i)->offset;
        meso_file_close(f);
        CHECK(off > 0);
        file[off + MESO_FSEG_OFF_FLAGS + 1] ^= 0x80;
    }
    expect_load_failure(c, "FSEG bytes damaged", file, size, MESO_ERR_CORRUPT, MESO_LOGITEM_CHUNK_READ_FAILED);
    free(file);
}

int main(void)
{
    setvbuf(stdout, NULL, _IONBF, 0);
    scene_w = W;
    scene_h = H;
    char why[256];
    meso_egl* egl = test_egl_create(why, sizeof(why));
    CHECK_MSG(egl != NULL, "%s", why);
    ctx c = {0};
    CHECK(test_fbo_create(&c.fbo, W, H));
#define TEST_L(t, n)                                  \
    {                                                 \
        void (*fn)(void) = meso_egl_proc("gl" #n);    \
        CHECK(fn != NULL);                            \
        memcpy(&c.gl.n, &fn, sizeof(fn));             \
    }
    TEST_GLF(TEST_L)
#undef TEST_L
    /* MESO_FILTER_LEVEL0: the exact reference shades from level 0 (it has
     * no texture levels), and the relief scenes minify their maps in
     * places, where the default mip-mapped shading differs from it by
     * design (measured: colour MAE 0.0365 on relief_bent_chain, over its
     * tolerance, which bounds the ray casting this test is about). The
     * filtering is measured by tests/gl/test_rt_mips.c against a
     * supersampled render. */
    const meso_rt_desc desc = {.gl_get_proc_address = meso_egl_proc, .log_fn = on_log_error, .log_user = &c.log,
                               .texture_filter = MESO_FILTER_LEVEL0};
    CHECK(meso_rt_create(&desc, &c.rt) == MESO_OK);
    CHECK(meso_rt_gl_is_es(c.rt) == (test_gl_api() == MESO_EGL_GLES)); /* the API asked for */
    c.rgba = malloc((size_t)W * H * 4);
    c.depth = malloc(sizeof(float) * W * H);
    texture height = make_height(64);

    test_single(&c);
    test_chains(&c);
    test_camera_inside(&c);
    test_relief(&c, &height);
    test_color(&c, &height);
    test_animation(&c, &height);
    test_state_contract(&c);
    test_malformed(&c, &height);

    free(height.texels);
    free(c.rgba);
    free(c.depth);
    meso_rt_destroy(c.rt);
    test_fbo_destroy(&c.fbo);
    meso_egl_destroy(egl);
    printf("ok\n");
    return 0;
}
