/* Levels of detail in libmeso (FORMAT.md §7.10, meso_rt_load_object_levels)
 * on llvmpipe, with levels whose error is known exactly: level k of a mesh
 * object is the unit square lifted to z = e_k, so the two-sided distance
 * to level 0's square is e_k.
 *  - At every distance the level drawn under pixel_error 1 moves the
 *    square's image by at most 1 pixel (+1 for rasterisation) against the
 *    finest level, and far away a coarse level is drawn: the error holds in
 *    pixels at the distances it is chosen for.
 *  - Streaming: a file prefix that ends at a level's prefix_bytes draws
 *    (every level boundary), with the finest level that has arrived; a
 *    prefix shorter than the coarsest level loads nothing, cleanly.
 *  - A reader that answers "not yet" (MESO_IO_PENDING): the object loads
 *    before anything has arrived, draws nothing, asks once per frame and
 *    draws each level as it arrives, the finest as the whole file does.
 *  - Stream requests (meso_rt_desc.stream_requests): no draw reads; the
 *    requests run on a worker thread, upload at a byte budget, and draw
 *    the synchronous loads' images; released-while-held and bad-bytes
 *    requests end cleanly.
 *  - The state reports what is resident and read.
 *  - A memory budget smaller than the finest levels settles under a static
 *    camera (the pixel-error factor and the levels drawn stop changing, no
 *    more evictions, resident bytes within the budget) and the factor comes
 *    back to 1 when the objects move away; it moves smoothly (at most one
 *    step of x 1.25 or / 1.1 a frame) and does not oscillate (under the
 *    static camera it never rises again once it has come down).
 *  - meso_rt_draw_instanced: each instance draws its own level (the image
 *    of separate draws, bit for bit).
 *  - A frusta object baked by mesobake (tests/data/saguaro.skel with a
 *    brick relief) draws its native level near and its tessellated
 *    stand-in (level 1, form mesh) far away, covering the same pixels as
 *    the native level there (its error is under a pixel); its native
 *    relief levels, each drawn from the file cut at its prefix, match the
 *    exact reference's level, not level 0's. */
#include "test_util.h"

#include <GL/glcorearb.h>
#include <string.h>
#include <threads.h>

#include "bake_bytes.h"
#include "camera.h"
#include "egl_context.h"
#include "frustum_reference.h"
#include "gl_api.h"
#include "gl_fbo.h"
#include "gpu_mesh_bytes.h"
#include "meso_bake.h"
#include "meso_layout.h"
#include "meso_rt.h"
#include "prefix_io.h"

enum { W = 160, H = 120, LEVELS = 4 };
static const float lift[LEVELS] = {0.0f, 0.004f, 0.016f, 0.064f};

static void add(meso_writer* w, uint32_t type, uint32_t object, uint16_t lod, const void* data, size_t size)
{
    meso_chunk_desc d = {.type = type, .object = object, .lod = lod, .dtype = MESO_DTYPE_BYTES, .components = 1};
    meso_error e;
    assert(meso_writer_add(w, &d, data, size, &e) == MESO_OK);
}

/* The unit square at height z as a g x g grid (finer levels hold more). */
static uint8_t* square_mesh(float z, uint32_t g, size_t* size)
{
    meso_mesh_layout l;
    const uint32_t nv = (g + 1) * (g + 1);
    assert(meso_mesh_compute_layout(nv, 6 * g * g, MESO_MESH_ATTR_POSITIONS | MESO_MESH_ATTR_NORMALS, &l) == MESO_OK);
    uint8_t* m = calloc(1, (size_t)l.size);
    assert(m);
    meso_mesh_write_header(&l, m);
    float* p = (float*)(m + l.positions_offset);
    float* n = (float*)(m + l.normals_offset);
    uint32_t* ix = (uint32_t*)(m + l.indices_offset);
    for (uint32_t j = 0; j <= g; ++j)
        for (uint32_t i = 0; i <= g; ++i) {
            const uint32_t v = j * (g + 1) + i;
            p[3 * v] = (float)i / (float)g, p[3 * v + 1] = (float)j / (float)g, p[3 * v + 2] = z;
            n[3 * v + 2] = 1.0f;
        }
    for (uint32_t j = 0; j < g; ++j)
        for (uint32_t i = 0; i < g; ++i) {
            const uint32_t a = j * (g + 1) + i, t[6] = {a, a + 1, a + g + 2, a, a + g + 2, a + g + 1};
            memcpy(ix + 6 * (j * g + i), t, sizeof t);
        }
    *size = (size_t)l.size;
    return m;
}

static uint8_t* levelled_file(size_t* size)
{
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    static const char meta[] = "{\"tool\":\"test_rt_levels\"}";
    add(w, MESO_CHUNK_META, 0, 0, meta, sizeof meta - 1);
    uint8_t objt[MESO_OBJT_RECORD_SIZE];
    meso_object_record o = {1, MESO_OBJECT_MESH, {0, 0, 0}, {1, 1, lift[LEVELS - 1]}, "lifted"};
    meso_object_record_encode(&o, objt);
    add(w, MESO_CHUNK_OBJT, 0, 0, objt, sizeof objt);
    uint8_t lods[LEVELS * MESO_LODS_RECORD_SIZE];
    for (uint16_t k = 0; k < LEVELS; ++k) {
        size_t ms;
        uint8_t* m = square_mesh(lift[k], 8u >> k, &ms);
        add(w, MESO_CHUNK_MESH, 1, k, m, ms);
        free(m);
        meso_level_record r = {1, k, MESO_LEVEL_NATIVE, lift[k], {0, 0, lift[k]}, {1, 1, lift[k]}};
        meso_level_record_encode(&r, lods + (size_t)k * MESO_LODS_RECORD_SIZE);
    }
    add(w, MESO_CHUNK_LODS, 0, 0, lods, sizeof lods);
    size_t need = 0;
    assert(meso_writer_finish(w, NULL, 0, &need) == MESO_OK);
    uint8_t* buf = malloc(need);
    assert(buf && meso_writer_finish(w, buf, need, &need) == MESO_OK);
    meso_writer_destroy(w);
    *size = need;
    return buf;
}

/* A stream still arriving: bytes past `arrived` answer MESO_IO_PENDING;
 * past `broken` (when not 0) the read fails. Counts the reads. */
typedef struct growing_io {
    const uint8_t* data;
    _Atomic uint64_t arrived, reads;
    uint64_t broken;
} growing_io;

static int growing_read(void* user, uint64_t off, void* dst, size_t n)
{
    growing_io* g = user;
    g->reads++;
    if (g->broken && off + n > g->broken)
        return -1;
    if (off > g->arrived || n > g->arrived - off)
        return MESO_IO_PENDING;
    memcpy(dst, g->data + off, n);
    return 0;
}

static test_fbo fb;

/* Clears, draws `obj` with `d` and returns the depth buffer (malloc'd). */
static float* draw_depth(meso_rt* rt, meso_rt_object obj, const meso_rt_draw_desc* d)
{
    test_fbo_clear(&fb, 0, 0, 0);
    assert(meso_rt_draw(rt, obj, d) == MESO_OK);
    float* depth = malloc(sizeof(float) * W * H);
    assert(depth);
    test_fbo_read(&fb, NULL, depth);
    return depth;
}

/* Draws `obj` seen from distance `dist` (square's centre, 60 degrees off
 * its normal) and returns per column the highest covered row (-1: none). */
static void draw_at(meso_rt* rt, meso_rt_object obj, double dist, float tau, int top[W])
{
    meso_rt_draw_desc d = {0};
    const double c[3] = {0.5, 0.5, 0.0}, up[3] = {0, 0, 1};
    const double eye[3] = {0.5, 0.5 - dist * sin(M_PI / 3), dist * cos(M_PI / 3)};
    meso_camera_look_at(d.view, eye, c, up);
    meso_camera_perspective(d.proj, 30.0 * M_PI / 180.0, (double)W / H, 0.01, 1000.0);
    d.pixel_error = tau;
    float* depth = draw_depth(rt, obj, &d);
    for (int x = 0; x < W; ++x) {
        top[x] = -1;
        for (int y = 0; y < H; ++y)
            if (depth[y * W + x] < 1.0f)
                top[x] = y;
    }
    free(depth);
}

static void error_holds_in_pixels_where_chosen(meso_rt* rt, meso_file* f)
{
    meso_rt_object obj;
    assert(meso_rt_load_object_levels(rt, f, 1, &obj) == MESO_OK);
    meso_rt_levels_state st;
    assert(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK);
    assert(st.level_count == LEVELS && st.resident_mask == 1u << (LEVELS - 1) && st.last_drawn == -1);
    int coarse_seen = 0;
    for (double dist = 1.5; dist < 110.0; dist *= 1.6) {
        int fine[W], lod[W];
        draw_at(rt, obj, dist, -1.0f, fine);
        assert(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK && st.last_drawn == 0);
        draw_at(rt, obj, dist, 1.0f, lod);
        assert(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK);
        const int chosen = st.last_drawn;
        int worst = 0, covered = 0;
        for (int x = 0; x < W; ++x) {
            if (!((fine[x] < 0) == (lod[x] < 0) || abs(fine[x] - lod[x]) <= 2))
                printf("  column %d: top %d (finest) against %d (level %d)\n", x, fine[x], lod[x], chosen);
            assert((fine[x] < 0) == (lod[x] < 0) || abs(fine[x] - lod[x]) <= 2);
            if (fine[x] >= 0 && lod[x] >= 0) {
                worst = abs(fine[x] - lod[x]) > worst ? abs(fine[x] - lod[x]) : worst;
                ++covered;
            }
        }
        printf("  distance %7.2f: level %d, top edge moved %d px (%d columns)\n", dist, chosen, worst, covered);
        fflush(stdout);
        assert(covered > 0);
        assert(worst <= 2); /* 1 px of error budget + 1 px of rasterisation */
        coarse_seen = coarse_seen > chosen ? coarse_seen : chosen;
    }
    assert(coarse_seen == LEVELS - 1); /* far away the coarsest level is drawn */
    assert(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK && st.resident_mask == (1u << LEVELS) - 1);
    meso_level_info li[LEVELS];
    uint32_t n = 0;
    assert(meso_file_levels(f, 1, li, LEVELS, &n, NULL) == MESO_OK && n == LEVELS);
    uint64_t all = 0;
    for (int k = 0; k < LEVELS; ++k)
        all += li[k].bytes;
    assert(st.bytes_resident == all && st.bytes_read == all);
    /* On the GPU each level of a mesh holds one buffer of its MESH as
     * meso_rt.h states it (no vertex colours here): the memory budget's
     * unit, and the estimate the budget made room for before each upload
     * is no smaller. */
    uint64_t gpu = 0;
    for (int k = 0; k < LEVELS; ++k) {
        assert(meso_file_find_vertex_colours(f, 1, (uint16_t)k) < 0);
        gpu += gpu_mesh_bytes(f, (uint32_t)meso_file_find_level(f, MESO_CHUNK_MESH, 1, (uint16_t)k));
    }
    printf("  GPU bytes of all levels: %llu (estimated %llu before upload)\n", (unsigned long long)st.gpu_bytes_resident,
           (unsigned long long)st.gpu_bytes_estimated);
    assert(st.gpu_bytes_resident == gpu && st.gpu_bytes_estimated >= gpu);
    meso_rt_release_object(rt, obj);
}

static void every_level_prefix_draws(meso_rt* rt, const uint8_t* data, size_t size)
{
    meso_file* whole = NULL;
    assert(meso_file_open_memory(data, size, NULL, &whole, NULL) == MESO_OK);
    meso_level_info li[LEVELS];
    uint32_t n = 0;
    assert(meso_file_levels(whole, 1, li, LEVELS, &n, NULL) == MESO_OK && n == LEVELS);
    for (int k = LEVELS - 1; k >= 0; --k) {
        prefix_io p = {data, li[k].prefix_bytes};
        const meso_io io = {.read_fn = prefix_read, .size = size, .user = &p};
        meso_file* f = NULL;
        assert(meso_file_open_io(&io, NULL, &f, NULL) == MESO_OK);
        meso_rt_object obj;
        assert(meso_rt_load_object_levels(rt, f, 1, &obj) == MESO_OK);
        int top[W];
        draw_at(rt, obj, 2.0, -1.0f, top); /* wants level 0: gets the finest that arrived */
        meso_rt_levels_state st;
        assert(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK);
        printf("  prefix %llu bytes of %zu: level %d drawn\n", (unsigned long long)p.limit, size, st.last_drawn);
        assert(st.last_drawn == k);
        int covered = 0;
        for (int x = 0; x < W; ++x)
            covered += top[x] >= 0;
        assert(covered > W / 4);
        meso_rt_release_object(rt, obj);
        meso_file_close(f);
    }
    /* Less than the coarsest level: nothing to draw, refused cleanly. */
    prefix_io p = {data, li[LEVELS - 1].prefix_bytes - 1};
    const meso_io io = {.read_fn = prefix_read, .size = size, .user = &p};
    meso_file* f = NULL;
    assert(meso_file_open_io(&io, NULL, &f, NULL) == MESO_OK);
    meso_rt_object obj = {7};
    assert(meso_rt_load_object_levels(rt, f, 1, &obj) != MESO_OK && obj.id == 0);
    meso_file_close(f);
    meso_file_close(whole);
}

static int covered_columns(const int top[W])
{
    int c = 0;
    for (int x = 0; x < W; ++x)
        c += top[x] >= 0;
    return c;
}

/* A reader that answers "not yet": the object loads before its coarsest
 * level has arrived and draws nothing (MESO_OK), a level that has not
 * arrived is asked for once per frame, not once per draw, and each level
 * draws once it has arrived, as the whole file draws it. */
static void pending_reads_are_asked_again(meso_rt* rt, const uint8_t* data, size_t size, const meso_level_info* li)
{
    int want[W], top[W];
    {
        meso_file* whole = NULL;
        assert(meso_file_open_memory(data, size, NULL, &whole, NULL) == MESO_OK);
        meso_rt_object o;
        assert(meso_rt_load_object_levels(rt, whole, 1, &o) == MESO_OK);
        draw_at(rt, o, 2.0, -1.0f, want); /* the finest level, from the whole file */
        meso_rt_release_object(rt, o);
        meso_file_close(whole);
    }
    growing_io g = {.data = data, .arrived = li[LEVELS - 1].prefix_bytes - 1};
    const meso_io io = {.read_fn = growing_read, .size = size, .user = &g};
    meso_file* f = NULL;
    assert(meso_file_open_io(&io, NULL, &f, NULL) == MESO_OK);
    meso_rt_object obj;
    assert(meso_rt_load_object_levels(rt, f, 1, &obj) == MESO_OK && obj.id != 0);
    meso_rt_levels_state st;
    draw_at(rt, obj, 2.0, -1.0f, top);
    assert(covered_columns(top) == 0);
    assert(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK && st.resident_mask == 0 && st.last_drawn == -1);
    const uint64_t reads = g.reads;
    draw_at(rt, obj, 2.0, -1.0f, top); /* the same frame: not asked again */
    assert(g.reads == reads && covered_columns(top) == 0);
    for (int k = LEVELS - 1; k >= 0; --k) {
        g.arrived = li[k].prefix_bytes;
        meso_rt_frame_end(rt);
        draw_at(rt, obj, 2.0, -1.0f, top);
        assert(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK);
        printf("  arrived %llu bytes: level %d drawn, %d columns\n", (unsigned long long)g.arrived, st.last_drawn,
               covered_columns(top));
        assert(st.last_drawn == k && covered_columns(top) > W / 4);
    }
    assert(memcmp(top, want, sizeof top) == 0);
    meso_rt_release_object(rt, obj);
    meso_file_close(f);
}

static int run_requests(void* arg)
{
    meso_rt_request** reqs = arg;
    for (; *reqs; ++reqs)
        meso_rt_stream_run(*reqs);
    return 0;
}

/* Take, run on a worker thread, give back: how many were taken. */
static uint32_t stream_step(meso_rt* rt)
{
    meso_rt_request* reqs[9] = {0};
    const uint32_t n = meso_rt_stream_take(rt, reqs, 8);
    thrd_t t;
    assert(thrd_create(&t, run_requests, reqs) == thrd_success);
    assert(thrd_join(t, NULL) == thrd_success);
    meso_rt_stream_give(rt, reqs, n);
    return n;
}

/* meso_rt_desc.stream_requests: no draw reads the file; the requests are
 * read and decoded on another thread, uploaded at a byte budget per call,
 * and the levels they upload draw exactly as the synchronous loads do. A
 * request whose object is released while taken is freed when given back;
 * one whose bytes are bad marks its level failed. */
static void requests_decode_off_thread(const uint8_t* data, size_t size, const meso_level_info* li)
{
    int want[LEVELS][W], top[W];
    uint64_t coarsest_moves = 0; /* what the coarsest level hands to GL: its MESH as the GPU holds it (meso_rt.h) */
    meso_rt* rt = NULL;
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &rt) == MESO_OK);
    {
        meso_file* whole = NULL;
        assert(meso_file_open_memory(data, size, NULL, &whole, NULL) == MESO_OK);
        coarsest_moves =
            gpu_mesh_bytes(whole, (uint32_t)meso_file_find_level(whole, MESO_CHUNK_MESH, 1, (uint16_t)(LEVELS - 1)));
        for (int k = 0; k < LEVELS; k += LEVELS - 1) { /* the finest and coarsest, drawn synchronously */
            meso_rt_object o;
            assert(meso_rt_load_object_levels(rt, whole, 1, &o) == MESO_OK);
            draw_at(rt, o, 2.0, k == LEVELS - 1 ? 1e9f : -1.0f, want[k]);
            meso_rt_levels_state st;
            assert(meso_rt_levels_state_get(rt, o, &st) == MESO_OK);
            assert(st.last_drawn == (k == LEVELS - 1 ? k : 0));
            meso_rt_release_object(rt, o);
        }
        meso_file_close(whole);
    }
    meso_rt_destroy(rt);
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .stream_requests = 1}, &rt) ==
           MESO_OK);
    growing_io g = {.data = data, .arrived = li[LEVELS - 1].prefix_bytes};
    const meso_io io = {.read_fn = growing_read, .size = size, .user = &g};
    meso_file* f = NULL;
    assert(meso_file_open_io(&io, NULL, &f, NULL) == MESO_OK);
    meso_rt_object obj[2];
    for (int i = 0; i < 2; ++i)
        assert(meso_rt_load_object_levels(rt, f, 1, &obj[i]) == MESO_OK);
    meso_rt_stream_state ss;
    meso_rt_stream_state_get(rt, &ss);
    assert(ss.waiting == 2 && ss.taken == 0 && ss.decoded == 0);
    uint64_t reads = g.reads;
    draw_at(rt, obj[0], 2.0, -1.0f, top); /* wants level 0: requests it, draws nothing yet */
    assert(g.reads == reads && covered_columns(top) == 0);
    meso_rt_stream_state_get(rt, &ss);
    assert(ss.waiting == 3);
    assert(stream_step(rt) == 3); /* the two coarsest decode, level 0 has not arrived */
    meso_rt_stream_state_get(rt, &ss);
    assert(ss.waiting == 1 && ss.decoded == 2 && ss.taken == 0);
    /* One byte of budget uploads one level (at least one per call), as
     * pieces: those count the bytes handed to GL, the level's MESH as the
     * GPU holds it; a whole level (budget 0) counts its chunk bytes. */
    assert(meso_rt_stream_upload(rt, 1) == coarsest_moves);
    meso_rt_stream_state_get(rt, &ss);
    assert(ss.decoded == 1 && ss.uploads == 1);
    assert(meso_rt_stream_upload(rt, 0) == li[LEVELS - 1].bytes);
    meso_rt_frame_end(rt);
    reads = g.reads;
    draw_at(rt, obj[0], 2.0, -1.0f, top);
    meso_rt_levels_state st;
    assert(meso_rt_levels_state_get(rt, obj[0], &st) == MESO_OK && st.last_drawn == LEVELS - 1);
    assert(g.reads == reads && memcmp(top, want[LEVELS - 1], sizeof top) == 0);
    g.arrived = size;
    assert(stream_step(rt) == 1);
    assert(meso_rt_stream_upload(rt, 0) == li[0].bytes);
    meso_rt_frame_end(rt);
    draw_at(rt, obj[0], 2.0, -1.0f, top);
    assert(meso_rt_levels_state_get(rt, obj[0], &st) == MESO_OK && st.last_drawn == 0);
    assert(memcmp(top, want[0], sizeof top) == 0);
    meso_rt_stream_state_get(rt, &ss);
    assert(ss.uploads == 3);
    printf("  requests: level 0 drawn after %llu uploads, %llu bytes read, the same image as a synchronous load\n",
           (unsigned long long)ss.uploads, (unsigned long long)st.bytes_read);
    /* Released while the host holds its request: freed when given back. */
    draw_at(rt, obj[1], 2.0, -1.0f, top); /* requests level 0 of the second object */
    meso_rt_request* held[2] = {0};
    assert(meso_rt_stream_take(rt, held, 2) == 1);
    meso_rt_release_object(rt, obj[1]);
    assert(meso_rt_stream_run(held[0]) == MESO_OK);
    meso_rt_stream_give(rt, held, 1);
    meso_rt_stream_state_get(rt, &ss);
    assert(ss.waiting == 0 && ss.taken == 0 && ss.decoded == 0);
    meso_rt_release_object(rt, obj[0]);
    meso_file_close(f);
    /* Bad bytes: the level is marked failed, never asked for again. */
    growing_io b = {.data = data, .arrived = size, .broken = li[0].prefix_bytes - 1};
    const meso_io bio = {.read_fn = growing_read, .size = size, .user = &b};
    assert(meso_file_open_io(&bio, NULL, &f, NULL) == MESO_OK);
    meso_rt_object o;
    assert(meso_rt_load_object_levels(rt, f, 1, &o) == MESO_OK);
    assert(stream_step(rt) == 1 && meso_rt_stream_upload(rt, 0) == li[LEVELS - 1].bytes);
    meso_rt_frame_end(rt);
    draw_at(rt, o, 2.0, -1.0f, top);
    meso_rt_request* one[2] = {0};
    assert(meso_rt_stream_take(rt, one, 2) == 1);
    assert(meso_rt_stream_run(one[0]) == MESO_ERR_IO);
    meso_rt_stream_give(rt, one, 1);
    meso_rt_frame_end(rt);
    /* Level 0 failed: the draw asks for the finest level that can still be
     * had (level 1, which lies before the broken bytes) and draws it. */
    draw_at(rt, o, 2.0, -1.0f, top);
    assert(meso_rt_levels_state_get(rt, o, &st) == MESO_OK && st.last_drawn == LEVELS - 1);
    assert(stream_step(rt) == 1 && meso_rt_stream_upload(rt, 0) == li[1].bytes);
    meso_rt_frame_end(rt);
    draw_at(rt, o, 2.0, -1.0f, top);
    meso_rt_stream_state_get(rt, &ss);
    assert(meso_rt_levels_state_get(rt, o, &st) == MESO_OK && st.last_drawn == 1 && ss.waiting == 0);
    meso_rt_release_object(rt, o);
    meso_file_close(f);
    meso_rt_destroy(rt);
    /* A budget smaller than the coarsest level: the coarsest still comes in
     * and stays (as a synchronous load's does). */
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .stream_requests = 1,
                                          .memory_budget = 1},
                          &rt) == MESO_OK);
    assert(meso_file_open_memory(data, size, NULL, &f, NULL) == MESO_OK);
    assert(meso_rt_load_object_levels(rt, f, 1, &o) == MESO_OK);
    assert(stream_step(rt) == 1 && meso_rt_stream_upload(rt, 0) == li[LEVELS - 1].bytes);
    for (int k = 0; k < 3; ++k) {
        draw_at(rt, o, 2.0, -1.0f, top); /* wants level 0, which never fits */
        stream_step(rt);
        meso_rt_stream_upload(rt, 0);
        meso_rt_frame_end(rt);
    }
    draw_at(rt, o, 2.0, -1.0f, top);
    assert(meso_rt_levels_state_get(rt, o, &st) == MESO_OK && st.last_drawn == LEVELS - 1);
    assert(memcmp(top, want[LEVELS - 1], sizeof top) == 0);
    /* Level 0 was read and decoded once, and waits decoded while it is
     * wanted (not read again every frame); wanted no more, it is dropped. */
    assert(st.bytes_read == li[LEVELS - 1].bytes + li[0].bytes);
    meso_rt_stream_state_get(rt, &ss);
    assert(ss.decoded == 1 && ss.waiting == 0);
    meso_rt_frame_end(rt);
    draw_at(rt, o, 200.0, 1.0f, top); /* far: the coarsest is wanted */
    meso_rt_stream_upload(rt, 0);
    meso_rt_stream_state_get(rt, &ss);
    assert(ss.decoded == 0 && ss.waiting == 0);
    meso_rt_release_object(rt, o);
    meso_file_close(f);
    meso_rt_destroy(rt);
}

/* Six levelled objects side by side at depth `dist`, one frame. */
enum { OBJS = 6 };
static void frame(meso_rt* rt, const meso_rt_object* objs, double dist)
{
    meso_rt_draw_desc d = {0};
    const double eye[3] = {0.5, 0.5 - dist * sin(M_PI / 3), dist * cos(M_PI / 3)}, c[3] = {0.5, 0.5, 0}, up[3] = {0, 0, 1};
    meso_camera_look_at(d.view, eye, c, up);
    meso_camera_perspective(d.proj, 30.0 * M_PI / 180.0, (double)W / H, 0.01, 1000.0);
    test_fbo_clear(&fb, 0, 0, 0);
    for (int i = 0; i < OBJS; ++i) {
        memset(d.model, 0, sizeof d.model);
        d.model[0] = d.model[5] = d.model[10] = d.model[15] = 1.0f;
        d.model[12] = (float)(1.2 * (i - OBJS / 2));
        d.model[13] = (float)(1.5 * i); /* further away, one after the other */
        assert(meso_rt_draw(rt, objs[i], &d) == MESO_OK);
    }
    meso_rt_frame_end(rt);
}

/* Covered pixels of the frusta object seen from `dist` times its radius. */
static int frusta_coverage(meso_rt* rt, meso_rt_object obj, const double c[3], double radius, double dist, float tau,
                           uint8_t* mask)
{
    meso_rt_draw_desc d = {0};
    const double eye[3] = {c[0] + 0.3 * dist * radius, c[1] + 0.2 * dist * radius, c[2] + dist * radius};
    const double up[3] = {0, 1, 0};
    meso_camera_look_at(d.view, eye, c, up);
    meso_camera_perspective(d.proj, 30.0 * M_PI / 180.0, (double)W / H, 0.05 * radius, 1000.0 * radius);
    d.pixel_error = tau;
    float* depth = draw_depth(rt, obj, &d);
    int n = 0;
    for (int i = 0; i < W * H; ++i)
        n += mask[i] = depth[i] < 1.0f;
    free(depth);
    return n;
}

/* tests/data/saguaro.skel baked by mesobake's code with a brick relief
 * and `levels`, in memory (malloc'd, *size bytes), and the centre and
 * radius of level 0's box. */
static uint8_t* bake_saguaro(const char* relief, int levels, size_t* size, double c[3], double* radius)
{
    meso_bake_frusta_options o = meso_bake_frusta_defaults();
    o.input = test_data("saguaro.skel");
    o.relief = relief;
    o.levels = levels;
    meso_bake_output* out = NULL;
    meso_error err;
    assert(meso_bake_frusta(&o, &out, NULL, &err) == MESO_OK);
    uint8_t* data = bake_bytes(out, size);
    meso_object_record rec;
    meso_file* f = NULL;
    uint32_t n = 0;
    assert(meso_file_open_memory(data, *size, NULL, &f, NULL) == MESO_OK);
    assert(meso_file_objects(f, &rec, 1, &n, NULL) == MESO_OK && n == 1);
    meso_file_close(f);
    *radius = 0;
    for (int k = 0; k < 3; ++k) {
        c[k] = 0.5 * ((double)rec.bbox_min[k] + rec.bbox_max[k]);
        *radius += 0.25 * pow((double)rec.bbox_max[k] - rec.bbox_min[k], 2);
    }
    *radius = sqrt(*radius);
    return data;
}

static void frusta_standin_far_away(meso_rt* rt)
{
    /* --levels 2: the tessellation only (its simplifications: test_frusta_standin) */
    size_t size = 0;
    double c[3], radius = 0;
    uint8_t* data = bake_saguaro("bricks:32", 2, &size, c, &radius);
    meso_file* f = NULL;
    assert(meso_file_open_memory(data, size, NULL, &f, NULL) == MESO_OK);
    meso_level_info li[2];
    uint32_t n = 0;
    assert(meso_file_levels(f, 1, li, 2, &n, NULL) == MESO_OK && n == 2 && li[1].rec.form == MESO_LEVEL_MESH);
    meso_rt_object obj;
    assert(meso_rt_load_object_levels(rt, f, 1, &obj) == MESO_OK);
    uint8_t* fine = malloc(W * H);
    uint8_t* lod = malloc(W * H);
    assert(fine && lod);
    meso_rt_levels_state st;
    int far_seen = 0;
    for (double dist = 3; dist < 100; dist *= 2) {
        const int nf = frusta_coverage(rt, obj, c, radius, dist, -1.0f, fine);
        const int nl = frusta_coverage(rt, obj, c, radius, dist, 1.0f, lod);
        assert(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK);
        int differ = 0;
        for (int i = 0; i < W * H; ++i)
            differ += fine[i] != lod[i];
        printf("  frusta at %5.0f radii: level %d, %d px covered (finest %d), %d differ\n", dist, st.last_drawn, nl, nf,
               differ);
        fflush(stdout);
        assert(nf > 0 && nl > 0);
        if (dist < 4)
            assert(st.last_drawn == 0); /* near: the native level */
        if (st.last_drawn == 1)
            assert(differ <= nf / 3 + 4); /* the stand-in covers what the native level covers, give or take
                                             its silhouette's pixels */
        far_seen |= st.last_drawn == 1;
    }
    assert(far_seen); /* far away: the stand-in */
    free(fine);
    free(lod);
    meso_rt_release_object(rt, obj);
    meso_file_close(f);
    free(data);
}

/* A frusta object's native relief levels (bake/height_field_levels.h):
 * the file cut at level L's prefix_bytes draws level L (the finest that
 * has arrived), and its depth image is the exact reference's level L
 * (runtime/reference, its own RELF), much nearer to it than to the
 * reference's level 0: libmeso draws the level's own relief, marching it
 * as many samples per texel as level 0 (fewer steps per fragment). */
static void frusta_native_levels(meso_rt* rt)
{
    size_t size = 0;
    double c[3], radius = 0;
    uint8_t* data = bake_saguaro("bricks:64", 0, &size, c, &radius);
    meso_file* wf = NULL;
    assert(meso_file_open_memory(data, size, NULL, &wf, NULL) == MESO_OK);
    meso_level_info li[16];
    uint32_t n = 0;
    assert(meso_file_levels(wf, 1, li, 16, &n, NULL) == MESO_OK && n >= 3 && li[1].rec.form == MESO_LEVEL_NATIVE);
    meso_rt_draw_desc d = {.pixel_error = -1.0f};
    const double eye[3] = {c[0] + 0.6 * radius, c[1] + 0.4 * radius, c[2] + 2.0 * radius}, up[3] = {0, 1, 0};
    meso_camera_look_at(d.view, eye, c, up);
    meso_camera_perspective(d.proj, 30.0 * M_PI / 180.0, (double)W / H, 0.05 * radius, 100.0 * radius);
    meso_ref_view v = {.width = W, .height = H};
    for (int k = 0; k < 16; ++k) {
        v.view[k] = d.view[k];
        v.proj[k] = d.proj[k];
    }
    meso_ref_frusta r0;
    meso_ref_image i0;
    assert(meso_ref_frusta_load(wf, 1, &r0, NULL) == MESO_OK && meso_ref_frusta_render(&r0, &v, &i0) == MESO_OK);
    /* Steps per fragment at level 0 (the whole file), against which each
     * coarser relief's march, as many samples per texel, takes fewer. */
    meso_rt_draw_stats s0 = {0};
    {
        meso_rt_object obj;
        assert(meso_rt_load_object_levels(rt, wf, 1, &obj) == MESO_OK);
        meso_rt_draw_desc d0 = d;
        d0.stats = &s0;
        free(draw_depth(rt, obj, &d0));
        meso_rt_release_object(rt, obj);
    }
    const double steps0 = s0.fragments ? (double)s0.steps / (double)s0.fragments : 0.0;
    for (uint32_t L = 1; L < n && li[L].rec.form == MESO_LEVEL_NATIVE; ++L) {
        prefix_io p = {data, li[L].prefix_bytes};
        const meso_io io = {.read_fn = prefix_read, .size = (uint64_t)size, .user = &p};
        meso_file* f = NULL;
        assert(meso_file_open_io(&io, NULL, &f, NULL) == MESO_OK);
        meso_rt_object obj;
        assert(meso_rt_load_object_levels(rt, f, 1, &obj) == MESO_OK);
        meso_rt_draw_stats sl = {0};
        meso_rt_draw_desc dl = d;
        dl.stats = &sl;
        float* depth = draw_depth(rt, obj, &dl);
        meso_rt_levels_state st;
        assert(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK && st.last_drawn == (int)L);
        const double steps = sl.fragments ? (double)sl.steps / (double)sl.fragments : 0.0;
        meso_ref_frusta rl;
        meso_ref_image il;
        assert(meso_ref_frusta_load_level(wf, 1, (uint16_t)L, &rl, NULL) == MESO_OK &&
               meso_ref_frusta_render(&rl, &v, &il) == MESO_OK);
        int covered = 0, mismatch = 0, both = 0;
        double to_l = 0, to_0 = 0;
        for (int i = 0; i < W * H; ++i) {
            const int g = depth[i] < 1.0f;
            covered += g;
            mismatch += g != (il.coverage[i] != 0);
            if (g && il.coverage[i] && i0.coverage[i]) {
                ++both;
                to_l += fabs((double)depth[i] - il.depth[i]);
                to_0 += fabs((double)depth[i] - i0.depth[i]);
            }
        }
        printf("  frusta native level %u from its %llu-byte prefix: %d px, %d differ in coverage from the "
               "reference's level %u; mean depth difference %.3g to it, %.3g to level 0's; %.1f steps per "
               "fragment (level 0: %.1f)\n",
               L, (unsigned long long)li[L].prefix_bytes, covered, mismatch, L, to_l / both, to_0 / both, steps,
               steps0);
        fflush(stdout);
        assert(covered > W * H / 20 && mismatch <= covered / 50 + 4);
        assert(to_l < 0.5 * to_0);
        assert(!sl.supported || steps < (L == 1 ? 0.8 : 0.6) * steps0);
        free(depth);
        meso_ref_image_free(&il);
        meso_ref_frusta_free(&rl);
        meso_rt_release_object(rt, obj);
        meso_file_close(f);
    }
    meso_ref_image_free(&i0);
    meso_ref_frusta_free(&r0);
    meso_file_close(wf);
    free(data);
}

static void budget_settles_and_comes_back(const uint8_t* data, size_t size)
{
    meso_file* f = NULL;
    assert(meso_file_open_memory(data, size, NULL, &f, NULL) == MESO_OK);
    meso_level_info li[LEVELS];
    uint32_t n = 0;
    assert(meso_file_levels(f, 1, li, LEVELS, &n, NULL) == MESO_OK);
    /* What the six objects hold unbudgeted, close up: measured. */
    uint64_t free_bytes = 0;
    {
        meso_rt* rt = NULL;
        assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &rt) == MESO_OK);
        meso_rt_object objs[OBJS];
        for (int i = 0; i < OBJS; ++i)
            assert(meso_rt_load_object_levels(rt, f, 1, &objs[i]) == MESO_OK);
        frame(rt, objs, 2.0);
        meso_rt_budget_state bs;
        meso_rt_budget_state_get(rt, &bs);
        free_bytes = bs.bytes_wanted;
        assert(bs.pixel_error_scale == 1.0 && bs.frames == 1);
        meso_rt_destroy(rt);
    }
    const uint64_t budget = free_bytes * 6 / 10;
    meso_rt* rt = NULL;
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .memory_budget = budget}, &rt) ==
           MESO_OK);
    meso_rt_object objs[OBJS];
    for (int i = 0; i < OBJS; ++i)
        assert(meso_rt_load_object_levels(rt, f, 1, &objs[i]) == MESO_OK);
    int32_t drawn[OBJS];
    double scale = 0.0, prev = 1.0;
    int came_down = 0;
    uint64_t evictions = 0;
    for (int k = 0; k < 60; ++k) {
        frame(rt, objs, 2.0);
        meso_rt_budget_state bs;
        meso_rt_budget_state_get(rt, &bs);
        assert(bs.bytes_resident <= budget || k < 5);
        /* Smoothly: at most one step a frame (x 1.25 up, / 1.1 down,
         * meso_rt_frame_end's rule), and no oscillation: once it has come
         * down it never goes up again under this static camera (measured:
         * 1.25, 1.56, 1.95, 2.44, 2.22, then 2.02 from frame 6 on). */
        const double sc = bs.pixel_error_scale;
        assert(sc <= prev * 1.25 * (1.0 + 1e-12) && sc >= prev / 1.1 * (1.0 - 1e-12));
        assert(!(came_down && sc > prev));
        came_down |= sc < prev;
        prev = sc;
        if (k == 40) {
            scale = bs.pixel_error_scale;
            evictions = bs.evictions;
            for (int i = 0; i < OBJS; ++i) {
                meso_rt_levels_state ls;
                meso_rt_levels_state_get(rt, objs[i], &ls);
                drawn[i] = ls.last_drawn;
            }
        }
        if (k > 40) { /* settled: nothing changes any more */
            assert(bs.pixel_error_scale == scale && bs.evictions == evictions && bs.bytes_wanted <= budget);
            for (int i = 0; i < OBJS; ++i) {
                meso_rt_levels_state ls;
                meso_rt_levels_state_get(rt, objs[i], &ls);
                assert(ls.last_drawn == drawn[i]);
            }
        }
    }
    printf("  budget %llu of %llu bytes: pixel error x %.3f, %llu evictions, levels", (unsigned long long)budget,
           (unsigned long long)free_bytes, scale, (unsigned long long)evictions);
    for (int i = 0; i < OBJS; ++i)
        printf(" %d", drawn[i]);
    printf("\n");
    assert(scale > 1.0);
    /* Far away everything fits at factor 1 again, coming down by at most
     * one step (/ 1.1) a frame. */
    meso_rt_budget_state bs;
    for (int k = 0; k < 80; ++k) {
        frame(rt, objs, 60.0);
        meso_rt_budget_state_get(rt, &bs);
        assert(bs.pixel_error_scale <= prev && bs.pixel_error_scale >= prev / 1.1 * (1.0 - 1e-12));
        prev = bs.pixel_error_scale;
    }
    printf("  far away: pixel error x %.3f, %llu bytes resident\n", bs.pixel_error_scale,
           (unsigned long long)bs.bytes_resident);
    assert(bs.pixel_error_scale == 1.0 && bs.bytes_resident <= budget);
    meso_rt_destroy(rt);
    meso_file_close(f);
}

/* meso_rt_draw_instanced on a levelled object: each instance draws the
 * level it would draw alone. Three squares at distances 2, 6 and 30 drawn
 * in one instanced call give, colour and depth, exactly the image of three
 * separate meso_rt_draw calls, which pick three different levels (one
 * level for all, the nearest's, would lift the far squares differently). */
static void instances_draw_their_own_levels(meso_rt* rt, meso_file* f)
{
    meso_rt_object obj;
    assert(meso_rt_load_object_levels(rt, f, 1, &obj) == MESO_OK);
    static const double dist[3] = {2.0, 6.0, 30.0}, x0[3] = {-0.95, 0.6, 10.0};
    meso_rt_instance inst[3];
    memset(inst, 0, sizeof inst);
    for (int i = 0; i < 3; ++i) {
        inst[i].model[0] = inst[i].model[5] = inst[i].model[10] = inst[i].model[15] = 1.0f;
        inst[i].model[12] = (float)x0[i];
        inst[i].model[13] = -0.5f;
        inst[i].model[14] = (float)-dist[i];
    }
    meso_rt_draw_desc d = {0};
    const double eye[3] = {0, 0, 0}, at[3] = {0, 0, -1}, up[3] = {0, 1, 0};
    meso_camera_look_at(d.view, eye, at, up);
    meso_camera_perspective(d.proj, 40.0 * M_PI / 180.0, (double)W / H, 0.05, 100.0);
    d.pixel_error = 1.0f;
    uint8_t *ca = malloc(4 * W * H), *cb = malloc(4 * W * H);
    float *za = malloc(sizeof(float) * W * H), *zb = malloc(sizeof(float) * W * H);
    assert(ca && cb && za && zb);
    test_fbo_clear(&fb, 0, 0, 0);
    assert(meso_rt_draw_instanced(rt, obj, &d, inst, 3) == MESO_OK);
    test_fbo_read(&fb, ca, za);
    test_fbo_clear(&fb, 0, 0, 0);
    int level[3];
    for (int i = 0; i < 3; ++i) {
        memcpy(d.model, inst[i].model, sizeof d.model);
        assert(meso_rt_draw(rt, obj, &d) == MESO_OK);
        meso_rt_levels_state st;
        assert(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK);
        level[i] = st.last_drawn;
    }
    test_fbo_read(&fb, cb, zb);
    size_t covered = 0;
    for (size_t p = 0; p < (size_t)W * H; ++p)
        covered += zb[p] < 1.0f;
    printf("  instanced: levels %d, %d, %d at distances 2, 6, 30; %zu pixels, %s separate draws\n", level[0],
           level[1], level[2], covered, memcmp(za, zb, sizeof(float) * W * H) ? "NOT as" : "as");
    assert(level[0] < level[1] && level[1] < level[2]);
    assert(covered > 100);
    assert(memcmp(ca, cb, 4 * W * H) == 0 && memcmp(za, zb, sizeof(float) * W * H) == 0);
    free(ca), free(cb), free(za), free(zb);
    meso_rt_release_object(rt, obj);
}

int main(void)
{
    char why[256];
    meso_egl* egl = test_egl_create(why, sizeof why);
    if (!egl) {
        fprintf(stderr, "test_rt_levels: no EGL context: %s\n", why);
        return 1;
    }
    assert(test_fbo_create(&fb, W, H));
    meso_rt* rt = NULL;
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &rt) == MESO_OK);
    size_t size;
    uint8_t* data = levelled_file(&size);
    meso_file* f = NULL;
    assert(meso_file_open_memory(data, size, NULL, &f, NULL) == MESO_OK);
    assert(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);
    error_holds_in_pixels_where_chosen(rt, f);
    instances_draw_their_own_levels(rt, f);
    every_level_prefix_draws(rt, data, size);
    {
        meso_level_info li[LEVELS];
        uint32_t n = 0;
        assert(meso_file_levels(f, 1, li, LEVELS, &n, NULL) == MESO_OK && n == LEVELS);
        pending_reads_are_asked_again(rt, data, size, li);
        requests_decode_off_thread(data, size, li);
    }
    frusta_standin_far_away(rt);
    frusta_native_levels(rt);
    budget_settles_and_comes_back(data, size);
    meso_file_close(f);
    meso_rt_destroy(rt);
    test_fbo_destroy(&fb);
    meso_egl_destroy(egl);
    free(data);
    puts("test_rt_levels: ok");
    return 0;
}
