/* A mesh object drawn part by part (FORMAT.md §7.11, runtime/rt_parts.c,
 * issue 14: "each part ... draws the coarsest level whose projected error
 * is ≤ τ; neighbouring parts may differ by at most one level and never
 * crack"), on llvmpipe. spot_uv.obj baked by meso_bake_mesh (its default
 * parts), seen from close to its head, so that the head is near and the
 * tail far:
 *  - the object's parts are read and drawn, at more than one level, the
 *    near end finer than the far end;
 *  - every part's level keeps its error within the pixel error at that
 *    level's nearest bound point (computed here from the bounds and the
 *    eye in doubles; the runtime picks by the same distance);
 *  - neighbouring parts (PRTS pairs) differ by at most one level;
 *  - no crack: every pixel inside the finest draw's silhouette (all 8
 *    neighbours covered) is covered by the parts draw too;
 *  - it holds fewer bytes than the finest level (levels state), and the
 *    finest draw (pixel error < 0) draws every part at level 0;
 *  - instanced, the near instance decides: the parts draw at the finest
 *    level either instance needs (the image equals the near one's alone
 *    where the far one is off screen);
 *  - streamed (stream requests), the part levels are requested and
 *    uploaded as levels are, and settle on the synchronous image;
 *  - where the whole object would draw a coarser level (larger pixel
 *    errors), the parts draw instead when they hold fewer bytes, and
 *    never hold more than the whole level;
 *  - a file without parts (--parts none) draws as before: no parts. */
#include "test_util.h"

#include <GL/glcorearb.h>
#include <math.h>
#include <string.h>

#include "bake_bytes.h"
#include "camera.h"
#include "egl_context.h"
#include "gl_api.h"
#include "gl_fbo.h"
#include "near_end_view.h"
#include "meso_bake.h"
#include "meso_rt.h"

enum { W = 160, H = 120 };
#define PC_W W
#define PC_H H
#define PC_FOV 50.0
#include "parts_checks.h"
#define TAU 2.0f /* pixels: where spot's part levels (0.5-1 % of its diagonal) separate at this size */

static test_fbo fb;

static uint8_t* bake_spot(int parts, size_t* size)
{
    meso_bake_mesh_options o = meso_bake_mesh_defaults();
    o.input = test_data("spot_uv.obj");
    o.parts = parts;
    meso_bake_output* out = NULL;
    meso_error err;
    assert(meso_bake_mesh(&o, &out, NULL, &err) == MESO_OK);
    return bake_bytes(out, size);
}

static void view(const meso_object_record* rec, meso_rt_draw_desc* d, double eye[3])
{
    near_end_view(rec, PC_FOV, (double)W / H, d, eye);
}

static float* draw(meso_rt* rt, meso_rt_object obj, const meso_rt_draw_desc* d)
{
    test_fbo_clear(&fb, 0, 0, 0);
    assert(meso_rt_draw(rt, obj, d) == MESO_OK);
    float* depth = malloc(sizeof(float) * W * H);
    assert(depth);
    test_fbo_read(&fb, NULL, depth);
    return depth;
}

static void parts_near_and_far(meso_rt* rt, meso_file* f, const meso_object_record* rec)
{
    parts_table pt = parts_table_read(f, rec->id);
    const meso_part_level* pl = pt.pl;
    const uint32_t np = pt.np, nl = pt.nl;
    meso_rt_object obj;
    assert(meso_rt_load_object_levels(rt, f, rec->id, &obj) == MESO_OK);
    meso_rt_draw_desc d = {0};
    double eye[3];
    view(rec, &d, eye);

    /* The finest: every part at level 0. */
    d.pixel_error = -1.0f;
    float* fine = draw(rt, obj, &d);
    uint8_t* lev = malloc(np);
    uint32_t count = 0;
    assert(lev && meso_rt_parts_state_get(rt, obj, lev, np, &count) == MESO_OK && count == np);
    for (uint32_t q = 0; q < np; ++q)
        assert(lev[q] == 0);
    meso_rt_levels_state st;
    assert(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK);
    uint64_t finest = 0;
    for (uint32_t i = 0; i < nl; ++i)
        finest += pl[i].rec.lod == 0 ? pl[i].bytes : 0;

    /* At TAU px. */
    d.pixel_error = TAU;
    float* one = draw(rt, obj, &d);
    const parts_drawn pd = check_part_levels(rt, obj, &pt, eye, TAU, lev);
    printf("  bytes of the parts drawn %llu against %llu at level 0\n", (unsigned long long)pd.bytes,
           (unsigned long long)finest);
    assert(pd.hi > pd.lo); /* near finer than far */
    assert(pd.bytes < finest);
    check_no_crack(fine, one, 1, TAU);

    /* Instanced: a second instance far away off to the side changes
     * nothing for the near one's parts. */
    meso_rt_instance inst[2];
    memset(inst, 0, sizeof inst);
    for (int k = 0; k < 4; ++k)
        inst[0].model[5 * k] = inst[1].model[5 * k] = 1.0f;
    inst[1].model[12] = -1000.0f;
    test_fbo_clear(&fb, 0, 0, 0);
    assert(meso_rt_draw_instanced(rt, obj, &d, inst, 2) == MESO_OK);
    float* both = malloc(sizeof(float) * W * H);
    assert(both);
    test_fbo_read(&fb, NULL, both);
    uint8_t* lev2 = malloc(np);
    assert(lev2 && meso_rt_parts_state_get(rt, obj, lev2, np, &count) == MESO_OK);
    assert(memcmp(lev, lev2, np) == 0);
    assert(memcmp(both, one, sizeof(float) * W * H) == 0);
    printf("  instanced with a far instance: the same part levels and the same depth image\n");

    meso_rt_release_object(rt, obj);
    free(both);
    free(lev2);
    free(fine);
    free(one);
    free(lev);
    parts_table_free(&pt);
}

/* Under stream requests (meso_rt_desc.stream_requests): no draw reads the
 * file; part levels are requested, run, given back and uploaded as levels
 * are, the object draws its best whole level uploaded until every part has
 * one, it never asks for its whole level 0, and once the requests settle
 * it draws the part levels, and the depth image, of a synchronous
 * context bit for bit. With every level of part 1 damaged (`broken`: a
 * byte of each PMSH flipped, so its CRC fails), its requests fail one by
 * one and the object then asks for, and draws, its whole level 0, as a
 * synchronous context does. */
static void parts_streamed(const uint8_t* bytes, size_t size, int broken)
{
    uint8_t* data = malloc(size);
    assert(data);
    memcpy(data, bytes, size);
    meso_file* f = NULL;
    assert(meso_file_open_memory(data, size, NULL, &f, NULL) == MESO_OK);
    meso_object_record recs[1];
    const meso_object_record* rec = recs;
    uint32_t n = 0;
    assert(meso_file_objects(f, recs, 1, &n, NULL) == MESO_OK && n == 1);
    int damaged = 0;
    for (uint32_t i = 0; broken && i < meso_file_chunk_count(f); ++i) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        if (c->type == MESO_CHUNK_PMSH && c->dims[0] == 1) {
            data[c->offset + c->stored_size / 2] ^= 0x40;
            ++damaged;
        }
    }
    assert(!broken || damaged >= 2);
    meso_rt_draw_desc d = {0};
    double eye[3];
    view(rec, &d, eye);
    d.pixel_error = TAU;

    meso_rt* sync = NULL;
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &sync) == MESO_OK);
    meso_rt_object so;
    assert(meso_rt_load_object_levels(sync, f, rec->id, &so) == MESO_OK);
    float* want = draw(sync, so, &d);
    uint32_t np = 0;
    assert(meso_rt_parts_state_get(sync, so, NULL, 0, &np) == MESO_OK && np >= 2);
    uint8_t* want_lev = malloc(np);
    uint8_t* lev = malloc(np);
    assert(want_lev && lev && meso_rt_parts_state_get(sync, so, want_lev, np, &np) == MESO_OK);

    meso_rt* rt = NULL;
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .stream_requests = 1}, &rt) ==
           MESO_OK);
    meso_rt_object obj;
    assert(meso_rt_load_object_levels(rt, f, rec->id, &obj) == MESO_OK);
    assert(meso_rt_parts_state_get(rt, obj, lev, np, &n) == MESO_OK && n == np); /* read with the levels */
    int frames = 0, part_uploads = 0;
    meso_rt_levels_state st;
    for (;; ++frames) {
        assert(frames < 40);
        meso_rt_levels_state before;
        assert(meso_rt_levels_state_get(rt, obj, &before) == MESO_OK);
        free(draw(rt, obj, &d));
        assert(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK);
        assert(st.bytes_read == before.bytes_read); /* the draw read nothing */
        assert(broken || !(st.resident_mask & 1u)); /* never the whole level 0 */
        /* One request a frame, the oldest (the coarsest level, filed by
         * the load): drawn alone while the parts arrive. */
        if (frames == 0)
            assert(st.last_drawn == -1);
        else if (frames < (int)np)
            assert(st.last_drawn == (int32_t)st.level_count - 1);
        meso_rt_frame_end(rt);
        meso_rt_request* reqs[1];
        const uint32_t taken = meso_rt_stream_take(rt, reqs, 1);
        for (uint32_t i = 0; i < taken; ++i)
            assert(meso_rt_stream_run(reqs[i]) == MESO_OK || broken);
        meso_rt_stream_give(rt, reqs, taken);
        meso_rt_stream_state ss;
        meso_rt_stream_upload(rt, 0);
        meso_rt_stream_state_get(rt, &ss);
        if (taken == 0 && ss.waiting == 0 && ss.decoded == 0)
            break;
        part_uploads += (int)taken;
    }
    float* got = draw(rt, obj, &d);
    assert(memcmp(got, want, sizeof(float) * W * H) == 0);
    assert(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK);
    if (broken) {
        meso_rt_levels_state ss;
        assert(meso_rt_levels_state_get(sync, so, &ss) == MESO_OK && ss.last_drawn == 0 && (ss.resident_mask & 1u));
        assert(st.last_drawn == 0 && (st.resident_mask & 1u));
        printf("streamed with part 1's %d levels damaged: %d frames of requests (%d taken), then the whole level 0, "
               "the depth image of a synchronous context bit for bit\n",
               damaged, frames, part_uploads);
    } else {
        assert(meso_rt_parts_state_get(rt, obj, lev, np, &n) == MESO_OK && n == np);
        assert(memcmp(lev, want_lev, np) == 0);
        assert(!(st.resident_mask & 1u));
        assert(st.bytes_read == st.bytes_resident); /* each request read its level's chunks, no more */
        printf("streamed, one request a frame: the coarsest whole level from frame 1, %d frames of requests (%d "
               "taken), then the part levels and the depth image of a synchronous context bit for bit; no draw read "
               "the file, the whole level 0 never uploaded\n",
               frames, part_uploads);
    }

    meso_rt_release_object(rt, obj);
    meso_rt_destroy(rt);
    meso_rt_release_object(sync, so);
    meso_rt_destroy(sync);
    free(want);
    free(got);
    free(want_lev);
    free(lev);
    meso_file_close(f);
    free(data);
}

static void no_parts_as_before(meso_rt* rt)
{
    size_t size = 0;
    uint8_t* data = bake_spot(-1, &size);
    meso_file* f = NULL;
    assert(meso_file_open_memory(data, size, NULL, &f, NULL) == MESO_OK);
    uint32_t nl = 1, np = 1, ne = 1;
    assert(meso_file_parts(f, 1, NULL, 0, &nl, &np, NULL, 0, &ne, NULL) == MESO_OK && nl == 0 && np == 0);
    meso_object_record rec;
    uint32_t n = 0;
    assert(meso_file_objects(f, &rec, 1, &n, NULL) == MESO_OK && n == 1);
    meso_rt_object obj;
    assert(meso_rt_load_object_levels(rt, f, 1, &obj) == MESO_OK);
    meso_rt_draw_desc d = {0};
    double eye[3];
    view(&rec, &d, eye);
    d.pixel_error = TAU;
    free(draw(rt, obj, &d));
    uint32_t count = 1;
    assert(meso_rt_parts_state_get(rt, obj, NULL, 0, &count) == MESO_OK && count == 0);
    meso_rt_release_object(rt, obj);
    meso_file_close(f);
    free(data);
    printf("without parts (parts -1): none read, drawn by whole levels\n");
}

int main(void)
{
    setvbuf(stdout, NULL, _IONBF, 0);
    char why[256];
    meso_egl* egl = test_egl_create(why, sizeof(why));
    if (!egl) {
        fprintf(stderr, "test_rt_parts: no EGL context: %s\n", why);
        return 1;
    }
    assert(test_fbo_create(&fb, W, H));
    meso_rt* rt = NULL;
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &rt) == MESO_OK);

    size_t size = 0;
    uint8_t* data = bake_spot(0, &size);
    meso_file* f = NULL;
    meso_error err;
    assert(meso_file_open_memory(data, size, NULL, &f, &err) == MESO_OK);
    assert(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);
    meso_object_record rec;
    uint32_t n = 0;
    assert(meso_file_objects(f, &rec, 1, &n, NULL) == MESO_OK && n == 1);
    parts_near_and_far(rt, f, &rec);
    meso_file_close(f);
    parts_streamed(data, size, 0);
    parts_streamed(data, size, 1);
    size_t none_size = 0;
    uint8_t* none = bake_spot(-1, &none_size);
    static const float taus[] = {1.0f, 2.0f, 3.0f, 6.0f}; /* whole levels 0, 1, 2, 4 */
    parts_coarser_than_level_0(data, size, none, none_size, taus, 4, view, draw);
    free(none);
    free(data);
    no_parts_as_before(rt);

    meso_rt_destroy(rt);
    test_fbo_destroy(&fb);
    meso_egl_destroy(egl);
    printf("ok   test_rt_parts\n");
    return 0;
}
