/* A mesh stand-in shows its object's colours (FORMAT.md §7.3 VCOL, issue
 * 14: "the base mesh with baked appearance"), measured on llvmpipe.
 *
 * Four objects baked by the baker's own API: spot as a cells object (the
 * bundled tests/data/spot_low_resolution.obj, the default Voronoi tile
 * map: cells of many colours); spot_uv.obj as a brick shell (bricks:256,
 * --tiling 8,8, 2 %) coloured by the bundled brick colours, and the same
 * shell without a colour (its stand-ins' VCOL holds the occlusion alone:
 * level 0 shows the draw's albedo darkened where the surface is low); the
 * saguaro with a 256-texel brick relief and colour map repeated 8 times
 * around. For each:
 *  - the file passes the full validation, every stand-in level has a VCOL
 *    at its MESH's lod with one colour per vertex, and a VCOL whose count
 *    does not fit its MESH is refused (6002);
 *  - each stand-in level is drawn from the file cut at its prefix_bytes
 *    (so the VCOL is inside the level's bytes, or the load fails) and
 *    compared with level 0 drawn from the whole file at 4x4 samples per
 *    pixel, by the mean colour of each 16 x 16 pixel block both cover (what
 *    the object looks like from where the stand-in is drawn: a few pixels
 *    per block). The same level with its VCOL chunks left out of the file
 *    (drawn with the draw's albedo, what libmeso did before) is the
 *    baseline. Asserted: with colours the blocks' mean error is at most
 *    half the baseline's at every stand-in level (measured 0.04-0.22), with
 *    the occlusion alone at most 0.75 of it (measured 0.54-0.62: what is
 *    left is the shading of the bricks' scattered normals, which no vertex
 *    colour holds), and the images are not flat (the blocks' colours vary
 *    as much as a third of the reference's).
 * Printed: both errors per level. MESO_TEST_PNG=DIR writes the images. */
#include "test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake_bytes.h"
#include "camera.h"
#include "egl_context.h"
#include "gl_api.h"
#include "gl_fbo.h"
#include "meso_bake.h"
#include "meso_layout.h"
#include "meso_rt.h"
#include "png_io.h"
#include "prefix_io.h"

enum { W = 256, SS = 4, BLOCK = 16, MAXL = 16 };

static test_fbo fb1, fbs;

static int first_issue(void* user, const meso_error* issue)
{
    *(meso_error*)user = *issue;
    return 1;
}

/* The file without its VCOL chunks (every other chunk as it was); with
 * `short_vcol`, a VCOL of grey one colour short of the coarsest MESH's
 * vertices at that MESH's lod instead. */
static uint8_t* rewritten(const uint8_t* data, size_t size, int short_vcol, size_t* out_size)
{
    meso_file* f = NULL;
    assert(meso_file_open_memory(data, size, NULL, &f, NULL) == MESO_OK);
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    uint32_t dropped = 0, nv = 0;
    uint16_t lod = 0;
    for (uint32_t i = 0; i < meso_file_chunk_count(f); ++i) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        if (c->type == MESO_CHUNK_VCOL) {
            ++dropped;
            continue;
        }
        assert(c->encoding == MESO_ENCODING_RAW);
        void* buf = malloc(c->decoded_size ? (size_t)c->decoded_size : 1);
        assert(buf && meso_file_read_chunk(f, i, buf, (size_t)c->decoded_size, NULL) == MESO_OK);
        const meso_chunk_desc d = {.type = c->type, .flags = c->flags, .object = c->object, .lod = c->lod,
                                   .dtype = c->dtype, .components = c->components,
                                   .dims = {c->dims[0], c->dims[1], c->dims[2]}};
        assert(meso_writer_add(w, &d, buf, (size_t)c->decoded_size, NULL) == MESO_OK);
        if (c->type == MESO_CHUNK_MESH && c->lod >= lod) {
            meso_mesh_view mv;
            assert(meso_mesh_parse(buf, (size_t)c->decoded_size, &mv, NULL) == MESO_OK);
            lod = c->lod;
            nv = mv.layout.vertex_count;
        }
        free(buf);
    }
    assert(dropped > 0 && nv > 1);
    if (short_vcol) {
        uint8_t* grey = calloc(4 * (size_t)nv, 1);
        const meso_chunk_desc d = {.type = MESO_CHUNK_VCOL, .object = 1, .lod = lod, .dtype = MESO_DTYPE_U8,
                                   .components = 4, .dims = {nv - 1, 1, 1}};
        assert(grey && meso_writer_add(w, &d, grey, 4 * (size_t)(nv - 1), NULL) == MESO_OK);
        free(grey);
    }
    assert(meso_writer_finish(w, NULL, 0, out_size) == MESO_OK);
    uint8_t* out = malloc(*out_size);
    assert(out && meso_writer_finish(w, out, *out_size, out_size) == MESO_OK);
    meso_writer_destroy(w);
    meso_file_close(f);
    return out;
}

/* Draws object 1 of `data` cut at `limit` bytes (0: whole) into `fb`
 * (n x n), the finest level that has arrived, and returns its RGBA and
 * depth (malloc'd) and the level drawn. */
static int draw(meso_rt* rt, test_fbo* fb, int n, const uint8_t* data, size_t size, uint64_t limit,
                const meso_rt_draw_desc* d, uint8_t** rgba, float** depth)
{
    prefix_io p = {data, limit ? limit : size};
    const meso_io io = {.read_fn = prefix_read, .size = size, .user = &p};
    meso_file* f = NULL;
    assert(meso_file_open_io(&io, NULL, &f, NULL) == MESO_OK);
    meso_rt_object obj;
    assert(meso_rt_load_object_levels(rt, f, 1, &obj) == MESO_OK);
    fb->BindFramebuffer(GL_FRAMEBUFFER, fb->fbo);
    fb->Viewport(0, 0, n, n);
    test_fbo_clear(fb, 0, 0, 0);
    assert(meso_rt_draw(rt, obj, d) == MESO_OK);
    *rgba = malloc(4 * (size_t)n * n);
    *depth = malloc(sizeof(float) * n * n);
    assert(*rgba && *depth);
    test_fbo_read(fb, *rgba, *depth);
    meso_rt_levels_state st;
    assert(meso_rt_levels_state_get(rt, obj, &st) == MESO_OK);
    meso_rt_release_object(rt, obj);
    meso_file_close(f);
    return st.last_drawn;
}

/* Per BLOCK x BLOCK block of the W x W image: the mean colour of the
 * samples covered (an image n = W s across, s x s samples a pixel) and the
 * covered share. */
static void block_means(const uint8_t* rgba, const float* depth, int n, double* mean, double* cover)
{
    const int s = n / W, nb = W / BLOCK, bs = BLOCK * s;
    for (int by = 0; by < nb; ++by)
        for (int bx = 0; bx < nb; ++bx) {
            double sum[3] = {0, 0, 0}, c = 0;
            for (int y = by * bs; y < (by + 1) * bs; ++y)
                for (int x = bx * bs; x < (bx + 1) * bs; ++x)
                    if (depth[y * n + x] < 1.0f) {
                        for (int k = 0; k < 3; ++k)
                            sum[k] += rgba[4 * (y * n + x) + k];
                        c += 1;
                    }
            const int b = by * nb + bx;
            for (int k = 0; k < 3; ++k)
                mean[3 * b + k] = c > 0 ? sum[k] / c : 0;
            cover[b] = c / ((double)bs * bs);
        }
}

/* Mean over blocks both cover at least half of: |colour difference|
 * (RGB bytes), and the standard deviation of `a`'s block luma. */
static double block_error(const double* ma, const double* ca, const double* mb, const double* cb, double* spread,
                          int* blocks)
{
    const int nb = (W / BLOCK) * (W / BLOCK);
    double e = 0, l = 0, l2 = 0;
    int n = 0;
    for (int b = 0; b < nb; ++b) {
        if (ca[b] < 0.5 || cb[b] < 0.5)
            continue;
        for (int k = 0; k < 3; ++k)
            e += fabs(ma[3 * b + k] - mb[3 * b + k]) / 3;
        const double y = 0.2126 * ma[3 * b] + 0.7152 * ma[3 * b + 1] + 0.0722 * ma[3 * b + 2];
        l += y;
        l2 += y * y;
        ++n;
    }
    assert(n > 0);
    *spread = sqrt(fmax(0, l2 / n - (l / n) * (l / n)));
    *blocks = n;
    return e / n;
}

static void write_png(const char* name, const uint8_t* rgba, int n)
{
    const char* dir = getenv("MESO_TEST_PNG");
    if (!dir)
        return;
    char path[512];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    char w[128];
    assert(meso_png_write_rgba8(path, rgba, n, n, 1, w, sizeof w) == 0);
}

enum { KINDS = 4 };
static const char* const kind_names[KINDS] = {"cells", "shell", "frusta", "shell_grey"};

/* Bakes the case of kind 0 cells, 1 shell, 2 frusta (the top), 3 the
 * shell without a colour (a VCOL of the occlusion alone: level 0 shows the
 * draw's albedo, darkened where it is low). */
static uint8_t* bake(int kind, size_t* size)
{
    meso_bake_output* out = NULL;
    meso_error err;
    char colour[4096]; /* test_data's buffer is overwritten by the next call */
    snprintf(colour, sizeof colour, "%s", test_data("color/bricks_color.png"));
    if (kind == 0) {
        meso_bake_cells_options o = meso_bake_cells_defaults();
        o.input = test_data("spot_low_resolution.obj");
        assert(meso_bake_cells(&o, &out, NULL, &err) == MESO_OK);
    } else if (kind == 1 || kind == 3) {
        meso_bake_shell_options o = meso_bake_shell_defaults();
        o.input = test_data("spot_uv.obj");
        o.texture = "bricks:256";
        o.tiling[0] = o.tiling[1] = 8;
        o.thickness_rel = 0.02;
        o.color = kind == 1 ? colour : NULL;
        assert(meso_bake_shell(&o, &out, NULL, &err) == MESO_OK);
    } else {
        meso_bake_frusta_options o = meso_bake_frusta_defaults();
        o.input = test_data("saguaro.skel");
        o.relief = "bricks:256";
        o.relief_repeat = 8;
        o.relief_color = colour;
        assert(meso_bake_frusta(&o, &out, NULL, &err) == MESO_OK);
    }
    return bake_bytes(out, size);
}

static void check_kind(meso_rt* rt, const char* name, const uint8_t* data, size_t size)
{
    /* The chunks: a VCOL per stand-in, at its MESH's lod, a colour a vertex. */
    meso_file* f = NULL;
    assert(meso_file_open_memory(data, size, NULL, &f, NULL) == MESO_OK);
    assert(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);
    meso_level_info li[MAXL];
    uint32_t nl = 0;
    assert(meso_file_levels(f, 1, li, MAXL, &nl, NULL) == MESO_OK && nl >= 3);
    meso_object_record rec;
    uint32_t no = 0;
    assert(meso_file_objects(f, &rec, 1, &no, NULL) == MESO_OK && no == 1);
    int standins = 0, with_albedo = 0; /* with_albedo: the VCOLs hold the occlusion alone (U8 x 1) */
    for (uint32_t l = 0; l < nl; ++l) {
        const int32_t vi = meso_file_find_vertex_colours(f, 1, (uint16_t)l);
        if (li[l].rec.form != MESO_LEVEL_MESH) {
            continue;
        }
        ++standins;
        const int32_t mi = meso_file_find_level(f, MESO_CHUNK_MESH, 1, (uint16_t)l);
        assert(mi >= 0 && vi >= 0 && meso_file_chunk(f, (uint32_t)vi)->lod == meso_file_chunk(f, (uint32_t)mi)->lod);
        const size_t ms = (size_t)meso_file_chunk(f, (uint32_t)mi)->decoded_size;
        void* mesh = malloc(ms);
        meso_mesh_view mv;
        assert(mesh && meso_file_read_chunk(f, (uint32_t)mi, mesh, ms, NULL) == MESO_OK);
        assert(meso_mesh_parse(mesh, ms, &mv, NULL) == MESO_OK);
        assert(meso_file_chunk(f, (uint32_t)vi)->dims[0] == mv.layout.vertex_count);
        with_albedo = meso_file_chunk(f, (uint32_t)vi)->components == 1;
        free(mesh);
    }
    assert(standins >= 2);
    meso_file_close(f);

    /* A VCOL one colour short is refused by the full check (6002). */
    {
        size_t bn = 0;
        uint8_t* bad = rewritten(data, size, 1, &bn);
        meso_file* h = NULL;
        assert(meso_file_open_memory(bad, bn, NULL, &h, NULL) == MESO_OK);
        meso_error e = {0};
        assert(meso_file_validate(h, MESO_CHECK_FULL, first_issue, &e) == MESO_ERR_CORRUPT);
        assert(e.code == MESO_ISSUE_LEVELS);
        printf("  %s, a VCOL one colour short: %s\n", name, e.message);
        assert(strstr(e.message, "VCOL") != NULL);
        meso_file_close(h);
        free(bad);
    }

    /* The view: the bounds' sphere fills about 0.8 of the image. */
    double c[3], r = 0;
    for (int k = 0; k < 3; ++k) {
        c[k] = 0.5 * ((double)rec.bbox_min[k] + rec.bbox_max[k]);
        r += 0.25 * pow((double)rec.bbox_max[k] - rec.bbox_min[k], 2);
    }
    r = sqrt(r);
    const double fov = 30.0 * M_PI / 180.0, dist = r / sin(0.4 * fov);
    const double eye[3] = {c[0] + 0.55 * dist, c[1] + 0.35 * dist, c[2] + 0.76 * dist}, up[3] = {0, 1, 0};
    meso_rt_draw_desc d = {0};
    meso_camera_look_at(d.view, eye, c, up);
    meso_camera_perspective(d.proj, fov, 1.0, 0.01 * dist, 10 * dist);
    d.pixel_error = -1.0f; /* the finest level that has arrived */

    const int nb = (W / BLOCK) * (W / BLOCK);
    double *mr = malloc(sizeof(double) * 3 * nb), *cr = malloc(sizeof(double) * nb);
    double *m1 = malloc(sizeof(double) * 3 * nb), *c1 = malloc(sizeof(double) * nb);
    assert(mr && cr && m1 && c1);
    uint8_t* rgba;
    float* depth;
    assert(draw(rt, &fbs, W * SS, data, size, 0, &d, &rgba, &depth) == 0);
    block_means(rgba, depth, W * SS, mr, cr);
    char ref_name[64];
    snprintf(ref_name, sizeof ref_name, "standin_colour_%s_ref.png", name);
    write_png(ref_name, rgba, W * SS);
    free(rgba);
    free(depth);

    size_t psize = 0;
    uint8_t* plain = rewritten(data, size, 0, &psize);
    meso_file* pf = NULL;
    assert(meso_file_open_memory(plain, psize, NULL, &pf, NULL) == MESO_OK);
    assert(meso_file_validate(pf, MESO_CHECK_FULL, NULL, NULL) == MESO_OK); /* stand-ins without VCOL are valid */
    meso_level_info pli[MAXL];
    uint32_t pn = 0;
    assert(meso_file_levels(pf, 1, pli, MAXL, &pn, NULL) == MESO_OK && pn == nl);
    meso_file_close(pf);
    for (uint32_t l = 0; l < nl; ++l) {
        if (li[l].rec.form != MESO_LEVEL_MESH)
            continue;
        assert(li[l].bytes > pli[l].bytes); /* the level's bytes hold its VCOL */
        double e[2], spread[2], sref = 0;
        int blocks[2];
        for (int with = 1; with >= 0; --with) {
            const int drawn = with ? draw(rt, &fb1, W, data, size, li[l].prefix_bytes, &d, &rgba, &depth)
                                   : draw(rt, &fb1, W, plain, psize, pli[l].prefix_bytes, &d, &rgba, &depth);
            assert(drawn == (int)l);
            block_means(rgba, depth, W, m1, c1);
            e[with] = block_error(m1, c1, mr, cr, &spread[with], &blocks[with]);
            char png[64];
            snprintf(png, sizeof png, "standin_colour_%s_l%u_%s.png", name, l, with ? "vcol" : "albedo");
            write_png(png, rgba, W);
            free(rgba);
            free(depth);
        }
        block_error(mr, cr, m1, c1, &sref, &blocks[0]);
        printf("  %s level %u (error %.4g, %llu bytes, %d blocks): block colour error %.2f with VCOL, %.2f with the "
               "albedo (ratio %.2f); block luma spread %.1f (reference %.1f)\n",
               name, l, (double)li[l].rec.error, (unsigned long long)li[l].bytes, blocks[1], e[1], e[0], e[1] / e[0],
               spread[1], sref);
        fflush(stdout);
        assert(e[1] <= (with_albedo ? 0.75 : 0.5) * e[0]);
        assert(spread[1] >= sref / 3);
    }
    free(plain);
    free(mr);
    free(cr);
    free(m1);
    free(c1);
}

int main(void)
{
    char why[256];
    meso_egl* egl = test_egl_create(why, sizeof why);
    if (!egl) {
        fprintf(stderr, "test_rt_standin_colour: no EGL context: %s\n", why);
        return 1;
    }
    assert(test_fbo_create(&fb1, W, W) && test_fbo_create(&fbs, W * SS, W * SS));
    meso_rt* rt = NULL;
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &rt) == MESO_OK);

    for (int kind = 0; kind < KINDS; ++kind) {
        size_t size = 0;
        uint8_t* data = bake(kind, &size);
        check_kind(rt, kind_names[kind], data, size);
        free(data);
    }
    meso_rt_destroy(rt);
    test_fbo_destroy(&fb1);
    test_fbo_destroy(&fbs);
    meso_egl_destroy(egl);
    puts("test_rt_standin_colour: ok");
    return 0;
}
