/* Animated texture functions (papers/volume-textures-lp-averaged-shells.md
 * §6, the boiling textures; FORMAT.md §7.2 "Animated texture functions") on
 * llvmpipe, with shells baked by the real `mesobake shell` (argv[1]):
 *
 *  - a sequence `--texture boil:32 --frames 4 --fps 8` and static bakes
 *    `--time k/8` of the same mesh: frame k of the sequence (slab k of
 *    TXFR and DSFR) is byte for byte the static bake's TX3D and DIST, the
 *    static bakes differ from each other (the texture does move), and the
 *    ANIM record says 4 frames, 8 fps, looped;
 *  - libmeso: after meso_rt_shell_set_time(t_k) (and t_k plus whole loops)
 *    the sequence renders pixel- and depth-identical to the static bake of
 *    frame k (same mesh, same textures: exactly the same draw);
 *  - meso_rt_shell_set_texture with frame 2's TX3D + DIST taken from the
 *    static file renders identical to that file, and one with other dims
 *    (a 1 x 1 x 1 all-solid volume, no distance map) draws;
 *  - every bad argument (stale handle, NULL desc or data, unknown kind or
 *    dtype, zero or oversized dims, a height field of depth 2, distance data
 *    without dims, a NaN F32 distance) returns MESO_ERR_INVALID_ARG and the
 *    object still renders exactly as before;
 *  - the host's 3D texture binding and unpack alignment survive the calls.
 */
#include "test_util.h"

#include <assert.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "camera.h"
#include "gl_api.h"
#include "gl_fbo.h"
#include "meso_layout.h"
#include "meso_rt.h"
#include "test_need.h"


enum { W = 96, H = 72, FRAMES = 4 };

typedef struct ctx {
    meso_rt* rt;
    test_fbo fbo;
    const char* mesobake;
    char dir[64];
    float view[16], proj[16];
} ctx;

static void bake(ctx* c, const char* name, const char* args)
{
    char cmd[1024];
    snprintf(cmd, sizeof(cmd),
             "'%s' shell -i '%s/torus.obj' -o '%s/%s.meso' -j 2 --thickness-rel 0.12 --texture boil:32 %s "
             "2>'%s/%s.log'",
             c->mesobake, MESO_TEST_DATA, c->dir, name, args, c->dir, name);
    need(system(cmd) == 0, "bake failed: %s", cmd);
}

static meso_file* open_bake(ctx* c, const char* name)
{
    char path[256];
    snprintf(path, sizeof(path), "%s/%s.meso", c->dir, name);
    meso_file* f = NULL;
    meso_error e;
    need(meso_file_open_path(path, NULL, &f, &e) == MESO_OK, "%s", e.message);
    return f;
}

/* The whole payload of the object's chunk of `type`. */
static uint8_t* chunk(meso_file* f, uint32_t type, size_t* size, const meso_chunk_info** info)
{
    for (uint32_t i = 0; i < meso_file_chunk_count(f); ++i) {
        const meso_chunk_info* k = meso_file_chunk(f, i);
        if (k->type != type)
            continue;
        uint8_t* p = malloc((size_t)k->decoded_size);
        meso_error e;
        need(meso_file_read_chunk(f, i, p, (size_t)k->decoded_size, &e) == MESO_OK, "%s", e.message);
        *size = (size_t)k->decoded_size;
        if (info)
            *info = k;
        return p;
    }
    need(0, "no chunk of type %08x", type);
    return NULL;
}

static meso_rt_object load(ctx* c, meso_file* f)
{
    meso_rt_object o;
    CHECK(meso_rt_load_object(c->rt, f, 1, &o) == MESO_OK);
    return o;
}

/* Draw into fresh rgba/depth buffers (caller frees). */
static void render(ctx* c, meso_rt_object o, uint8_t** rgba, float** depth)
{
    *rgba = malloc((size_t)W * H * 4);
    *depth = malloc(sizeof(float) * W * H);
    meso_rt_draw_desc d = {0};
    memcpy(d.view, c->view, sizeof(d.view));
    memcpy(d.proj, c->proj, sizeof(d.proj));
    test_fbo_clear(&c->fbo, 0.0f, 0.0f, 0.0f);
    CHECK(meso_rt_draw(c->rt, o, &d) == MESO_OK);
    test_fbo_read(&c->fbo, *rgba, *depth);
}

static long covered(const float* depth)
{
    long n = 0;
    for (int i = 0; i < W * H; ++i)
        n += depth[i] < 1.0f;
    return n;
}

/* Renders `o` and requires it identical (colour and depth) to the images given. */
static void expect_same(ctx* c, meso_rt_object o, const uint8_t* rgba, const float* depth, const char* what)
{
    uint8_t* r;
    float* z;
    render(c, o, &r, &z);
    long diff = 0;
    for (int i = 0; i < W * H * 4; ++i)
        diff += r[i] != rgba[i];
    need(diff == 0 && memcmp(z, depth, sizeof(float) * W * H) == 0, "%s: %ld colour bytes differ%s", what, diff,
              memcmp(z, depth, sizeof(float) * W * H) ? ", depth differs" : "");
    printf("ok   %s (%ld px covered)\n", what, covered(z));
    free(r);
    free(z);
}

int main(int argc, char** argv)
{
    setvbuf(stdout, NULL, _IONBF, 0);
    need(argc == 2, "usage: test_rt_shell_anim MESOBAKE");
    ctx c = {.mesobake = argv[1]};
    test_temp_dir(c.dir, sizeof(c.dir), "rt_shell_anim");
    char why[256];
    meso_egl* egl = test_egl_create(why, sizeof(why));
    need(egl != NULL, "%s", why);
    CHECK(test_fbo_create(&c.fbo, W, H));
    CHECK(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &c.rt) == MESO_OK);
    CHECK(meso_rt_gl_is_es(c.rt) == (test_gl_api() == MESO_EGL_GLES)); /* the API asked for */
    const double eye[3] = {0.4, 2.6, 2.2}, at[3] = {0, 0, 0}, up[3] = {0, 1, 0};
    meso_camera_look_at(c.view, eye, at, up);
    meso_camera_perspective(c.proj, 0.8, (double)W / H, 0.1, 10.0);

    /* >>the bakes: frame k of the sequence = the static bake at t_k = k / 8 */
    bake(&c, "seq", "--frames 4 --fps 8");
    char name[32], args[64];
    for (int k = 0; k < FRAMES; ++k) {
        snprintf(name, sizeof(name), "t%d", k);
        snprintf(args, sizeof(args), "--time %.17g", k / 8.0);
        bake(&c, name, args);
    }
    meso_file* seq = open_bake(&c, "seq");
    size_t n_anim, n_fr, n_ds;
    const meso_chunk_info *fr_info, *ds_info;
    uint8_t* anim = chunk(seq, MESO_CHUNK_ANIM, &n_anim, NULL);
    uint8_t* txfr = chunk(seq, MESO_CHUNK_TXFR, &n_fr, &fr_info);
    uint8_t* dsfr = chunk(seq, MESO_CHUNK_DSFR, &n_ds, &ds_info);
    meso_anim_record rec;
    CHECK(n_anim == MESO_ANIM_RECORD_SIZE);
    meso_anim_record_decode(anim, &rec);
    CHECK(rec.frame_count == FRAMES && rec.fps == 8.0f && rec.time0 == 0.0f && rec.flags == MESO_ANIM_FLAG_LOOP);
    meso_file* stat[FRAMES];
    uint8_t *tx[FRAMES], *dist[FRAMES];
    size_t n_tx = 0, n_dist = 0;
    const meso_chunk_info *tx_info = NULL, *dist_info = NULL;
    for (int k = 0; k < FRAMES; ++k) {
        snprintf(name, sizeof(name), "t%d", k);
        stat[k] = open_bake(&c, name);
        tx[k] = chunk(stat[k], MESO_CHUNK_TX3D, &n_tx, &tx_info);
        dist[k] = chunk(stat[k], MESO_CHUNK_DIST, &n_dist, &dist_info);
        CHECK(n_fr == FRAMES * n_tx && n_ds == FRAMES * n_dist);
        need(memcmp(txfr + k * n_tx, tx[k], n_tx) == 0, "TXFR frame %d differs from the bake at t = %d/8", k, k);
        need(memcmp(dsfr + k * n_dist, dist[k], n_dist) == 0, "DSFR frame %d differs from the bake at t = %d/8",
                  k, k);
        need(k == 0 || memcmp(tx[k], tx[k - 1], n_tx) != 0, "frames %d and %d are the same", k - 1, k);
        printf("ok   frame %d: TX3D %zu bytes and DIST %zu bytes equal the static bake at t = %g s\n", k, n_tx,
               n_dist, k / 8.0);
    }

    /* >>set_time: the sequence draws exactly as the static bake of frame k */
    meso_rt_object so = load(&c, seq);
    uint32_t frames = 0, shown = 0;
    float fps = 0;
    CHECK(meso_rt_shell_anim_info(c.rt, so, &frames, &fps, &shown) == MESO_OK);
    CHECK(frames == FRAMES && fps == 8.0f && shown == 0);
    uint8_t* rgba[FRAMES];
    float* depth[FRAMES];
    for (int k = 0; k < FRAMES; ++k) {
        meso_rt_object o = load(&c, stat[k]);
        CHECK(meso_rt_shell_anim_info(c.rt, o, &frames, NULL, &shown) == MESO_OK && frames == 0);
        CHECK(meso_rt_shell_set_time(c.rt, o, 1.0) == MESO_OK); /* no stored frames: left alone */
        render(&c, o, &rgba[k], &depth[k]);
        CHECK(covered(depth[k]) > W * H / 10);
        meso_rt_release_object(c.rt, o);
    }
    for (int loop = 0; loop < 3; ++loop)
        for (int k = 0; k < FRAMES; ++k) {
            const int j = loop == 1 ? FRAMES - 1 - k : k; /* backwards too */
            const double t = j / 8.0 + (loop == 2 ? 5 * FRAMES / 8.0 : 0.0);
            CHECK(meso_rt_shell_set_time(c.rt, so, t) == MESO_OK);
            CHECK(meso_rt_shell_anim_info(c.rt, so, NULL, NULL, &shown) == MESO_OK && shown == (uint32_t)j);
            char what[96];
            snprintf(what, sizeof(what), "set_time(%g) draws the static bake of frame %d", t, j);
            expect_same(&c, so, rgba[j], depth[j], what);
        }
    CHECK(meso_rt_shell_set_time(c.rt, so, 0.5 / 8 + 2 / 8.0) == MESO_OK); /* mid-frame 2 */
    CHECK(meso_rt_shell_anim_info(c.rt, so, NULL, NULL, &shown) == MESO_OK && shown == 2);

    /* >>set_texture: frame 1 from host memory, the host's GL state kept */
    GLint prev_unit = 0, prev_align = 0, prev_3d = 0, host_tex = 0;
    PFNGLGETINTEGERVPROC GetIntegerv = (PFNGLGETINTEGERVPROC)meso_egl_proc("glGetIntegerv");
    PFNGLGENTEXTURESPROC GenTextures = (PFNGLGENTEXTURESPROC)meso_egl_proc("glGenTextures");
    PFNGLBINDTEXTUREPROC BindTexture = (PFNGLBINDTEXTUREPROC)meso_egl_proc("glBindTexture");
    PFNGLPIXELSTOREIPROC PixelStorei = (PFNGLPIXELSTOREIPROC)meso_egl_proc("glPixelStorei");
    GenTextures(1, (GLuint*)&host_tex);
    BindTexture(GL_TEXTURE_3D, (GLuint)host_tex);
    PixelStorei(GL_UNPACK_ALIGNMENT, 8);
    meso_rt_shell_texture good = {.kind = MESO_RT_TEXTURE_DENSITY,
                                  .dims = {tx_info->dims[0], tx_info->dims[1], tx_info->dims[2]},
                                  .dtype = tx_info->dtype,
                                  .data = tx[1],
                                  .dist_dims = {dist_info->dims[0], dist_info->dims[1], dist_info->dims[2]},
                                  .dist_dtype = dist_info->dtype,
                                  .dist_data = dist[1]};
    CHECK(meso_rt_shell_set_texture(c.rt, so, &good) == MESO_OK);
    GetIntegerv(GL_ACTIVE_TEXTURE, &prev_unit);
    GetIntegerv(GL_UNPACK_ALIGNMENT, &prev_align);
    GetIntegerv(GL_TEXTURE_BINDING_3D, &prev_3d);
    need(prev_align == 8 && prev_3d == host_tex, "GL state changed: unpack alignment %d, 3D texture %d",
              prev_align, prev_3d);
    CHECK(meso_rt_shell_anim_info(c.rt, so, NULL, NULL, &shown) == MESO_OK && shown == UINT32_MAX);
    expect_same(&c, so, rgba[1], depth[1], "set_texture(frame 1 from host memory) draws the static bake of frame 1");

    /* >>bad arguments: refused, the object unchanged */
    static const uint8_t solid = 255;
    float nan_dist[8];
    for (int i = 0; i < 8; ++i)
        nan_dist[i] = i == 5 ? NAN : 0.1f;
    meso_rt_shell_texture bad[11];
    for (int i = 0; i < 11; ++i)
        bad[i] = good;
    bad[0].kind = (meso_rt_texture_kind)0;
    bad[1].dtype = MESO_DTYPE_F32;
    bad[2].data = NULL;
    bad[3].dims[1] = 0;
    bad[4].dims[2] = 1u << 20;
    bad[5].kind = MESO_RT_TEXTURE_HEIGHT; /* with dims[2] = 32 */
    bad[6].dist_dims[0] = bad[6].dist_dims[1] = bad[6].dist_dims[2] = 0; /* dist_data without dims */
    bad[7].dist_data = NULL;
    bad[8].dist_dtype = MESO_DTYPE_I8;
    bad[9].dist_dtype = MESO_DTYPE_F32;
    bad[9].dist_data = nan_dist;
    bad[9].dist_dims[0] = bad[9].dist_dims[1] = bad[9].dist_dims[2] = 2;
    bad[10].dist_dims[2] = 0;
    for (int i = 0; i < 11; ++i)
        need(meso_rt_shell_set_texture(c.rt, so, &bad[i]) == MESO_ERR_INVALID_ARG, "bad desc %d accepted", i);
    CHECK(meso_rt_shell_set_texture(c.rt, so, NULL) == MESO_ERR_INVALID_ARG);
    CHECK(meso_rt_shell_set_texture(c.rt, (meso_rt_object){0}, &good) == MESO_ERR_INVALID_ARG);
    CHECK(meso_rt_shell_set_time(c.rt, so, NAN) == MESO_ERR_INVALID_ARG);
    expect_same(&c, so, rgba[1], depth[1], "after 14 refused calls the object draws as before");

    /* >>other dims: a 1 x 1 x 1 all-solid volume without a distance map */
    const meso_rt_shell_texture one = {.kind = MESO_RT_TEXTURE_DENSITY, .dims = {1, 1, 1}, .dtype = MESO_DTYPE_U8,
                                       .data = &solid};
    CHECK(meso_rt_shell_set_texture(c.rt, so, &one) == MESO_OK);
    uint8_t* r1;
    float* z1;
    render(&c, so, &r1, &z1);
    need(covered(z1) >= covered(depth[1]), "the solid shell covers %ld px, boil %ld", covered(z1),
              covered(depth[1]));
    printf("ok   set_texture(1x1x1 solid, no distance map) draws %ld px\n", covered(z1));
    /* and back to a stored frame through set_time (uploads: the host texture was shown) */
    CHECK(meso_rt_shell_set_time(c.rt, so, 3 / 8.0) == MESO_OK);
    expect_same(&c, so, rgba[3], depth[3], "set_time after set_texture draws the static bake of frame 3");

    meso_rt_release_object(c.rt, so);
    CHECK(meso_rt_shell_set_time(c.rt, so, 0.0) == MESO_ERR_INVALID_ARG);
    CHECK(meso_rt_shell_set_texture(c.rt, so, &good) == MESO_ERR_INVALID_ARG);
    free(r1);
    free(z1);
    for (int k = 0; k < FRAMES; ++k) {
        free(rgba[k]);
        free(depth[k]);
        free(tx[k]);
        free(dist[k]);
        meso_file_close(stat[k]);
    }
    free(anim);
    free(txfr);
    free(dsfr);
    meso_file_close(seq);
    meso_rt_destroy(c.rt);
    test_fbo_destroy(&c.fbo);
    meso_egl_destroy(egl);
    test_temp_dir_remove(c.dir);
    printf("rt_shell_anim: all checks passed\n");
    return 0;
}
