/* A shell drawn part by part (FORMAT.md §7.11, bake/shell_parts.c,
 * runtime/rt_parts.c; issue 14: "each part, where a kind has parts, e.g.
 * shell patches, so a long object near the camera is fine near and coarse
 * far"), on llvmpipe. spot_uv.obj with a bricks:64 height field, baked by
 * meso_bake_shell (its default parts), seen from close to its head:
 *  - the file validates in full, its parts' prisms list every base
 *    triangle once;
 *  - a lod-1 patch (the first stand-in's own triangles) shows the whole
 *    first stand-in's colours, and at every lod neighbouring patches give
 *    the vertices they share one colour (no seam at a part border);
 *  - at TAU px some parts draw their prisms and some their stand-in
 *    patch, the near end as prisms; every part's level keeps its error
 *    within the pixel error at that level's nearest bound point;
 *    neighbours within one level;
 *  - the surface drawn is the finest draw's within the largest error
 *    drawn: every pixel farther than that error (in pixels, rounded up)
 *    from the finest draw's silhouette is covered (no hole), and its view
 *    distance is within 1.5 times that error (in object units) of the
 *    finest draw's at some pixel that near (an edge moved by the error);
 *    where the parts draw prisms, the depth is the whole shell's exactly
 *    (counted: most of the image);
 *  - instanced with a far instance off screen, the near one draws the
 *    same part levels and depth image bit for bit;
 *  - streamed (stream requests, one a frame), it settles on the synchronous
 *    context's part levels and depth image, bit for bit, having read no
 *    more than it holds;
 *  - a damaged prism list (PTRI: an entry listed twice, CRCs fixed) is
 *    refused by the full check (6501), and a triangle-count mismatch of a
 *    part's colours (PVCL) too; not checked in full, an entry naming no
 *    triangle is left out of the draw (no crash).
 * With an output directory (argv[1]) it writes the two images there. */
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
#include "meso_layout.h"
#include "meso_rt.h"
#include "png_io.h"
#include "sample.h"

enum { W = 200, H = 150 };
#define TAU 4.0f
#define FOV 50.0
#define PC_W W
#define PC_H H
#define PC_FOV FOV
#include "parts_checks.h"

static test_fbo fb;

static void view(const meso_object_record* rec, meso_rt_draw_desc* d, double eye[3])
{
    near_end_view(rec, FOV, (double)W / H, d, eye);
    d->light_dir[0] = 0.3f, d->light_dir[1] = 0.8f, d->light_dir[2] = 0.5f;
}

static void draw(meso_rt* rt, meso_rt_object obj, const meso_rt_draw_desc* d, uint8_t* rgba, float* depth)
{
    test_fbo_clear(&fb, 0, 0, 0);
    assert(meso_rt_draw(rt, obj, d) == MESO_OK);
    test_fbo_read(&fb, rgba, depth);
}

static float* draw_depth(meso_rt* rt, meso_rt_object obj, const meso_rt_draw_desc* d)
{
    float* depth = malloc(sizeof(float) * W * H);
    assert(depth);
    draw(rt, obj, d, NULL, depth);
    return depth;
}

/* View distance of a depth-buffer value (the perspective above). */
static double view_distance(float z)
{
    const double n = 0.01, f = 100.0, ndc = 2.0 * z - 1.0;
    return 2.0 * n * f / (f + n - ndc * (f - n));
}

/* The stream: one request a frame (taken, run, given back, uploaded at
 * `budget` bytes a frame, 0: all) until none is left; then the draw's
 * depth image and part levels. With a budget, the shell's whole levels
 * (textures with their mips, texture buffers) go up over several frames
 * (rt_transfer.c) and no frame moves more than the budget plus one row
 * or 64 KB of a buffer. */
static void streamed_settles(meso_file* f, const meso_rt_draw_desc* d, const float* want, const uint8_t* want_lev,
                             uint32_t np, uint64_t budget)
{
    meso_rt* rt = NULL;
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc, .stream_requests = 1}, &rt) ==
           MESO_OK);
    meso_rt_object obj;
    assert(meso_rt_load_object_levels(rt, f, 1, &obj) == MESO_OK);
    float* got = malloc(sizeof(float) * W * H);
    uint8_t* lev = malloc(np);
    assert(got && lev);
    int frames = 0;
    uint64_t most = 0;
    for (;; ++frames) {
        assert(frames < (budget ? 4000 : 60));
        draw(rt, obj, d, NULL, got);
        meso_rt_frame_end(rt);
        meso_rt_request* reqs[1];
        const uint32_t taken = meso_rt_stream_take(rt, reqs, 1);
        for (uint32_t i = 0; i < taken; ++i)
            assert(meso_rt_stream_run(reqs[i]) == MESO_OK);
        meso_rt_stream_give(rt, reqs, taken);
        const uint64_t up = meso_rt_stream_upload(rt, budget);
        most = up > most ? up : most;
        meso_rt_stream_state ss;
        meso_rt_stream_state_get(rt, &ss);
        if (taken == 0 && up == 0 && ss.waiting == 0 && ss.decoded == 0) /* a level that came up asks for more */
            break;
    }
    draw(rt, obj, d, NULL, got);
    uint32_t n = 0;
    assert(meso_rt_parts_state_get(rt, obj, lev, np, &n) == MESO_OK && n == np);
    meso_rt_levels_state st;
    assert(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK);
    assert(memcmp(lev, want_lev, np) == 0);
    assert(memcmp(got, want, sizeof(float) * W * H) == 0);
    assert(st.bytes_read == st.bytes_resident);
    printf("streamed, one request a frame, %llu bytes a frame (0: all): %d frames, at most %llu bytes moved in "
           "one; then the synchronous part levels and depth image bit for bit (%llu bytes read, all held)\n",
           (unsigned long long)budget, frames, (unsigned long long)most, (unsigned long long)st.bytes_read);
    assert(!budget || most <= budget + (64u << 10));
    meso_rt_release_object(rt, obj);
    meso_rt_destroy(rt);
    free(got);
    free(lev);
}

/* `file` with the first chunk of `type` changed by `edit` (its payload p,
 * n bytes, and its TOC entry), CRCs fixed. */
static uint8_t* damaged(const uint8_t* file, size_t size, uint32_t type, void (*edit)(uint8_t* p, uint64_t n, uint8_t* entry))
{
    uint8_t* copy = malloc(size);
    assert(copy);
    memcpy(copy, file, size);
    int done = 0;
    for (uint32_t i = 0; i < get32(copy + MESO_HDR_OFF_CHUNK_COUNT); i++) {
        uint8_t* ent = copy + 64 + (size_t)i * 64;
        if (get32(ent + MESO_TOC_OFF_TYPE) == type && !done) {
            edit(copy + get64(ent + MESO_TOC_OFF_OFFSET), get64(ent + MESO_TOC_OFF_STORED_SIZE), ent);
            fix_payload_crc(copy, i);
            done = 1;
        }
    }
    assert(done);
    fix_crcs(copy);
    return copy;
}

/* Its full check's issue. */
static uint32_t damaged_issue(const uint8_t* file, size_t size, uint32_t type,
                              void (*edit)(uint8_t* p, uint64_t n, uint8_t* entry))
{
    uint8_t* copy = damaged(file, size, type, edit);
    meso_error e;
    const meso_result r = open_and_validate(copy, size, &e);
    free(copy);
    return r == MESO_OK ? 0u : e.code;
}

static void twice(uint8_t* p, uint64_t n, uint8_t* entry)
{
    (void)entry;
    assert(n >= 8);
    memcpy(p + 4, p, 4); /* entry 1 = entry 0 */
}

static void far_off(uint8_t* p, uint64_t n, uint8_t* entry)
{
    (void)entry;
    assert(n >= 4);
    put32(p + n - 4, 0xFFFFFFF0u); /* the last part's last prism (a near part): not a triangle of any shell */
}

static void other_components(uint8_t* p, uint64_t n, uint8_t* entry)
{
    (void)p;
    (void)n;
    const uint32_t c = entry[MESO_TOC_OFF_COMPONENTS];
    put16(entry + MESO_TOC_OFF_COMPONENTS, (uint16_t)(c == 4 ? 1 : 4)); /* as many bytes, other vertices */
}

/* A vertex's key (position and normal bits) and its colour bytes. */
typedef struct vkey {
    float key[6];
    uint8_t c[4];
    uint32_t part;
} vkey;

static int vkey_cmp(const void* a, const void* b)
{
    return memcmp(((const vkey*)a)->key, ((const vkey*)b)->key, sizeof(float) * 6);
}

/* Appends chunk i (a MESH or PMSH) with its colours (chunk ci) as keys. */
static size_t add_keys(meso_file* f, uint32_t i, uint32_t ci, uint32_t part, vkey** keys, size_t n)
{
    const meso_chunk_info* c = meso_file_chunk(f, i);
    const meso_chunk_info* cc = meso_file_chunk(f, ci);
    uint32_t* mesh = malloc((size_t)c->decoded_size + 4);
    uint8_t* col = malloc((size_t)cc->decoded_size + 1);
    assert(mesh && col && meso_file_read_chunk(f, i, mesh, (size_t)c->decoded_size, NULL) == MESO_OK &&
           meso_file_read_chunk(f, ci, col, (size_t)cc->decoded_size, NULL) == MESO_OK);
    meso_mesh_view mv;
    assert(meso_mesh_parse(mesh, (size_t)c->decoded_size, &mv, NULL) == MESO_OK && mv.normals);
    const uint32_t nv = mv.layout.vertex_count, comp = cc->components;
    assert(cc->decoded_size == (uint64_t)comp * nv);
    *keys = realloc(*keys, sizeof(vkey) * (n + nv));
    assert(*keys);
    for (uint32_t v = 0; v < nv; ++v) {
        vkey* k = &(*keys)[n + v];
        memset(k, 0, sizeof *k);
        memcpy(k->key, mv.positions + 3 * (size_t)v, sizeof(float) * 3);
        memcpy(k->key + 3, mv.normals + 3 * (size_t)v, sizeof(float) * 3);
        memcpy(k->c, col + (size_t)comp * v, comp);
        k->part = part;
    }
    free(mesh);
    free(col);
    return n + nv;
}

/* The chunk of `type` for (object 1, lod, dims[0] = part; 0: any), or -1. */
static int64_t chunk_of(meso_file* f, uint32_t type, uint16_t lod, uint32_t part)
{
    for (uint32_t i = 0; i < meso_file_chunk_count(f); ++i) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        if (c->type == type && c->object == 1 && c->lod == lod && (!part || c->dims[0] == part))
            return i;
    }
    return -1;
}

/* The patches' colours: at lod 1 (the first stand-in's own triangles) each
 * patch vertex shows what the whole first stand-in's vertex with the same
 * position and normal shows; at every lod, a vertex two patches share
 * (their border) has one colour in both. Returns the border vertices
 * compared. */
static size_t patch_colours_agree(meso_file* f, uint32_t np, const meso_part_level* pl, uint32_t nl)
{
    vkey* whole = NULL;
    const int64_t wm = chunk_of(f, MESO_CHUNK_MESH, 1, 0), wc = chunk_of(f, MESO_CHUNK_VCOL, 1, 0);
    assert(wm >= 0 && wc >= 0);
    const size_t nw = add_keys(f, (uint32_t)wm, (uint32_t)wc, 0, &whole, 0);
    qsort(whole, nw, sizeof(vkey), vkey_cmp);
    size_t borders = 0, lod1 = 0;
    for (uint16_t lod = 1;; ++lod) {
        vkey* keys = NULL;
        size_t n = 0;
        for (uint32_t i = 0; i < nl; ++i)
            if (pl[i].rec.lod == lod && pl[i].colours >= 0)
                n = add_keys(f, (uint32_t)pl[i].chunk, (uint32_t)pl[i].colours, pl[i].rec.object, &keys, n);
        if (!n)
            break;
        qsort(keys, n, sizeof(vkey), vkey_cmp);
        for (size_t a = 0; a < n; ++a) {
            if (lod == 1) {
                const vkey* w = bsearch(&keys[a], whole, nw, sizeof(vkey), vkey_cmp);
                assert(w && memcmp(w->c, keys[a].c, 4) == 0);
                ++lod1;
            }
            if (a > 0 && vkey_cmp(&keys[a - 1], &keys[a]) == 0 && keys[a - 1].part != keys[a].part) {
                assert(memcmp(keys[a - 1].c, keys[a].c, 4) == 0);
                ++borders;
            }
        }
        free(keys);
    }
    free(whole);
    printf("patch colours: %zu lod-1 vertices show the whole stand-in's colour, %zu shared border vertices "
           "agree (%u parts)\n",
           lod1, borders, np);
    assert(lod1 > 0 && borders > 0);
    return borders;
}

int main(int argc, char** argv)
{
    setvbuf(stdout, NULL, _IONBF, 0);
    char why[256];
    meso_egl* egl = test_egl_create(why, sizeof(why));
    if (!egl) {
        fprintf(stderr, "test_rt_shell_parts: no EGL context: %s\n", why);
        return 1;
    }
    assert(test_fbo_create(&fb, W, H));
    meso_rt* rt = NULL;
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &rt) == MESO_OK);

    meso_bake_shell_options o = meso_bake_shell_defaults();
    o.input = test_data("spot_uv.obj");
    o.texture = "bricks:64";
    o.thickness_rel = 0.02;
    meso_bake_output* out = NULL;
    meso_error err;
    assert(meso_bake_shell(&o, &out, NULL, &err) == MESO_OK);
    size_t size = 0;
    uint8_t* data = bake_bytes(out, &size);
    meso_file* f = NULL;
    assert(meso_file_open_memory(data, size, NULL, &f, &err) == MESO_OK);
    assert(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);
    meso_object_record rec;
    uint32_t n = 0;
    assert(meso_file_objects(f, &rec, 1, &n, NULL) == MESO_OK && n == 1);
    parts_table pt = parts_table_read(f, 1);
    const meso_part_level* pl = pt.pl;
    const uint32_t np = pt.np, nl = pt.nl;
    uint32_t nt = 0;
    assert(meso_file_part_triangles(f, 1, NULL, 0, &nt, &err) == MESO_OK && nt > 0);
    printf("spot_uv shell: %u parts, %u part levels, %u prisms listed\n", np, nl, nt);
    patch_colours_agree(f, np, pl, nl);

    meso_rt_object obj;
    assert(meso_rt_load_object_levels(rt, f, 1, &obj) == MESO_OK);
    meso_rt_draw_desc d = {0};
    double eye[3];
    view(&rec, &d, eye);
    uint8_t* fine_rgba = malloc((size_t)4 * W * H);
    uint8_t* part_rgba = malloc((size_t)4 * W * H);
    float* fine = malloc(sizeof(float) * W * H);
    float* part = malloc(sizeof(float) * W * H);
    uint8_t* lev = malloc(np);
    assert(fine_rgba && part_rgba && fine && part && lev);

    d.pixel_error = -1.0f; /* the finest: level 0, no parts */
    draw(rt, obj, &d, fine_rgba, fine);
    meso_rt_levels_state st;
    assert(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK && st.last_drawn == 0);

    d.pixel_error = TAU;
    draw(rt, obj, &d, part_rgba, part);
    const parts_drawn pd = check_part_levels(rt, obj, &pt, eye, TAU, lev); /* level 0: prisms, else patches */
    const uint32_t prisms = pd.at_0, coarse = np - pd.at_0;
    const double worst_px = pd.worst_px, worst_error = pd.worst_error;
    assert(prisms >= 1 && coarse >= 1);

    if (argc > 1) {
        char path[512];
        snprintf(path, sizeof path, "%s/shell_parts_fine.png", argv[1]);
        assert(meso_png_write_rgba8(path, fine_rgba, W, H, 1, why, sizeof why) == 0);
        snprintf(path, sizeof path, "%s/shell_parts_tau.png", argv[1]);
        assert(meso_png_write_rgba8(path, part_rgba, W, H, 1, why, sizeof why) == 0);
    }

    /* Interior: farther than the largest projected error (rounded up) from
     * the finest draw's silhouette, where a stand-in patch, up to its
     * error inside the shell's surface, may leave the silhouette early. */
    const int r = (int)ceil(worst_px);
    long interior = 0, holes = 0, same = 0, within = 0, beyond = 0;
    for (int y = r; y < H - r; ++y)
        for (int x = r; x < W - r; ++x) {
            int all = 1;
            for (int j = -r; j <= r; ++j)
                for (int i = -r; i <= r; ++i)
                    all &= fine[(y + j) * W + x + i] < 1.0f;
            if (!all)
                continue;
            ++interior;
            const size_t p = (size_t)y * W + (size_t)x;
            if (part[p] >= 1.0f) {
                ++holes;
                continue;
            }
            /* The surface drawn is within the error of the finest's, in
             * depth and, where it moves an edge in front of another
             * surface, by up to r pixels: the nearest match in depth
             * among the finest's pixels within r. */
            double dz = INFINITY;
            for (int j = -r; j <= r; ++j)
                for (int i = -r; i <= r; ++i)
                    dz = fmin(dz, fabs(view_distance(part[p]) - view_distance(fine[(y + j) * W + x + i])));
            same += part[p] == fine[p];
            within += dz <= worst_error * 1.5; /* along a ray, a surface within e can be further: grazing */
            beyond += dz > worst_error * 1.5;
        }
    printf("at %g px: %u parts as prisms, %u as stand-in patches; largest projected error %.2f px\n"
           "  %ld interior pixels: %ld the finest's depth exactly, %ld within 1.5x the largest error drawn (%.4g) of "
           "the finest's within %d px, %ld beyond, %ld holes\n",
           (double)TAU, prisms, coarse, worst_px, interior, same, within, (double)worst_error, r, beyond, holes);
    assert(interior > 5000 && holes == 0);
    assert(same > interior / 10);
    assert(beyond == 0);

    /* Instanced, with a second instance far off to the side (its own,
     * coarser, level group): the near one draws the same part levels and
     * the same depth image, bit for bit. */
    {
        meso_rt_instance inst[2];
        memset(inst, 0, sizeof inst);
        for (int k = 0; k < 16; ++k)
            assert(d.model[k] == 0.0f); /* the view's model: the identity */
        for (int k = 0; k < 4; ++k)
            inst[0].model[5 * k] = inst[1].model[5 * k] = 1.0f;
        inst[1].model[12] = -1000.0f;
        test_fbo_clear(&fb, 0, 0, 0);
        assert(meso_rt_draw_instanced(rt, obj, &d, inst, 2) == MESO_OK);
        float* both = malloc(sizeof(float) * W * H);
        uint8_t* lev2 = malloc(np);
        assert(both && lev2);
        test_fbo_read(&fb, NULL, both);
        uint32_t m = 0;
        assert(meso_rt_parts_state_get(rt, obj, lev2, np, &m) == MESO_OK && m == np);
        assert(memcmp(lev, lev2, np) == 0);
        assert(memcmp(both, part, sizeof(float) * W * H) == 0);
        printf("instanced with a far instance: the same part levels and the same depth image\n");
        free(both);
        free(lev2);
    }

    streamed_settles(f, &d, part, lev, np, 0);
    streamed_settles(f, &d, part, lev, np, 8192);

    uint32_t issue = damaged_issue(data, size, MESO_CHUNK_PTRI, twice);
    printf("a prism list with an entry twice: issue %u\n", issue);
    assert(issue == MESO_ISSUE_PARTS);
    issue = damaged_issue(data, size, MESO_CHUNK_PVCL, other_components);
    printf("a part's colours for another vertex count: issue %u\n", issue);
    assert(issue == MESO_ISSUE_PARTS);

    /* Not checked in full, a list naming a triangle the shell has not is
     * drawn without it: no crash, and every other pixel as before. */
    {
        uint8_t* bad = damaged(data, size, MESO_CHUNK_PTRI, far_off);
        meso_file* bf = NULL;
        assert(meso_file_open_memory(bad, size, NULL, &bf, NULL) == MESO_OK);
        meso_rt_object bo;
        assert(meso_rt_load_object_levels(rt, bf, 1, &bo) == MESO_OK);
        float* bd = malloc(sizeof(float) * W * H);
        assert(bd);
        draw(rt, bo, &d, NULL, bd);
        long differ = 0;
        for (size_t p = 0; p < (size_t)W * H; ++p)
            differ += bd[p] != part[p];
        printf("a prism list naming triangle 0xFFFFFFF0, not checked in full: drawn without it, %ld pixels differ\n",
               differ);
        assert(differ * 20 < (long)W * H);
        meso_rt_release_object(rt, bo);
        meso_file_close(bf);
        free(bd);
        free(bad);
    }

    /* Farther off, where the whole shell draws a stand-in level: its parts'
     * patches instead where they hold fewer bytes (parts_checks.h). */
    o.parts = -1;
    assert(meso_bake_shell(&o, &out, NULL, &err) == MESO_OK);
    size_t none_size = 0;
    uint8_t* none = bake_bytes(out, &none_size);
    static const float taus[] = {1.0f, 2.0f, 4.0f, 8.0f, 16.0f};
    parts_coarser_than_level_0(data, size, none, none_size, taus, sizeof taus / sizeof taus[0], view, draw_depth);
    free(none);

    meso_rt_release_object(rt, obj);
    meso_file_close(f);
    free(data);
    parts_table_free(&pt);
    free(fine_rgba);
    free(part_rgba);
    free(fine);
    free(part);
    free(lev);
    meso_rt_destroy(rt);
    test_fbo_destroy(&fb);
    meso_egl_destroy(egl);
    puts("ok   test_rt_shell_parts");
    return 0;
}
