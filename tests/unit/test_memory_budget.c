/* test_memory_budget.c — the memory budget (bake/memory_budget.h): SIZE
 * parsing against a table of expected values, saturating arithmetic, and
 * the estimates against what real runs allocate: the buffers a small cells
 * bake holds (and the MIXED tiles it finds), the PNG reader's byte count at
 * its exact boundary, a raw volume's estimate at its exact boundary, and the
 * line count a skeleton estimate is made from. */
#include "test_util.h"

#include <string.h>
#include <unistd.h>

#include "adapters.h"
#include "cells_chunks.h"
#include "memory_budget.h"
#include "png_io.h"
#include "texture_function.h"

static char tmp_dir[64];

static const char* tmp_path(const char* name)
{
    static char buf[256];
    snprintf(buf, sizeof buf, "%s/%s", tmp_dir, name);
    return buf;
}

static void parse_size_table(void)
{
    static const struct {
        const char* s;
        uint64_t v;
    } good[] = {{"1", 1},
                {"4096", 4096},
                {"512M", 512ull << 20},
                {"512MiB", 512ull << 20},
                {"8G", 8ull << 30},
                {"8g", 8ull << 30},
                {"1.5G", 3ull << 29},
                {"1.5GiB", 3ull << 29},
                {"2T", 2ull << 40},
                {"64KB", 64ull << 10},
                {"4611686018427387904", 1ull << 62}};
    for (size_t i = 0; i < sizeof good / sizeof good[0]; ++i) {
        uint64_t v = 0;
        assert(meso_parse_size(good[i].s, &v) && v == good[i].v);
    }
    static const char* const bad[] = {"", "0", "-1", "+5", " 5", "5 ", "1.5", "1.", ".5G", "abc", "12Q", "8G8",
                                      "8GB8", "1e9", "4611686018427387905", "99999999999999999999", "4194305T",
                                      "0.0000001K", "0x10"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        uint64_t v = 77;
        assert(!meso_parse_size(bad[i], &v) && v == 77);
    }
}

static void format_and_saturate(void)
{
    char b[32];
    assert(!strcmp(meso_format_size(700, b, sizeof b), "700 bytes"));
    assert(!strcmp(meso_format_size(512ull << 20, b, sizeof b), "512 MiB"));
    assert(!strcmp(meso_format_size(3ull << 29, b, sizeof b), "1.5 GiB"));
    assert(meso_size_mul(UINT64_MAX / 2, 3) == UINT64_MAX && meso_size_mul(0, UINT64_MAX) == 0);
    assert(meso_size_add(UINT64_MAX - 1, 2) == UINT64_MAX && meso_size_add(2, 3) == 5);
    assert(meso_memory_physical() > 0);
    const uint64_t d = meso_memory_default_budget();
    assert(d > 0 && d <= meso_memory_physical() / 2 + 1);
    meso_error err = {0};
    assert(meso_budget_check(100, 100, MESO_LIMIT_ISSUE_REQUEST, &err, "x") == MESO_OK);
    assert(meso_budget_check(101, 100, MESO_LIMIT_ISSUE_REQUEST, &err, "x") == MESO_ERR_INVALID_ARG &&
           err.code == 3400 && strstr(err.message, "needs about"));
    assert(meso_budget_check(101, 100, MESO_LIMIT_ISSUE_PNG, &err, "x") == MESO_ERR_CORRUPT && err.code == 3401);
}

/* A real cells bake at R = 16 on 6^3 tiles: the buffers it holds at the end
 * (tile map, labels, chunks, membership map) plus the writer's copy of the
 * chunks must fit the estimate; the estimate's near-surface count must bound
 * the MIXED tiles before and after the merge; and the estimate must not be
 * absurdly loose (within 4x of what is held plus the 96 MiB fixed part). */
static void cells_estimate_bounds_a_real_bake(const char* mesh)
{
    meso_mesh m;
    meso_error err = {0};
    assert(meso_openmesh_read(test_data(mesh), &m, NULL, &err) == MESO_OK);
    meso_tile_map tm = {0};
    meso_split_cells sc = {0};
    meso_membership mb = {0};
    meso_cells_chunks cc = {0};
    meso_voxel_grid g;
    meso_tile_map_params p = {.kind = MESO_TILE_MAP_VORONOI, .res = 16, .count = 12, .rng_seed = 7};
    assert(meso_voxel_grid_fit(&m, 6, 16, 1.0, &g, &err) == MESO_OK);
    uint64_t near1 = 0, near = 0;
    const uint64_t before = meso_cells_estimate(&m, &g, 1, 2, &near1);
    assert(meso_tile_map_generate(&p, 2, &tm, &err) == MESO_OK);
    assert(meso_split_cells_compute(&tm, 2, &sc, &err) == MESO_OK);
    const uint64_t est = meso_cells_estimate(&m, &g, sc.split_count, 2, &near);
    assert(near == near1 && est >= before);
    assert(meso_membership_compute(&m, &g, &sc, MESO_VOXELIZE_AUTO, 2, &mb, &err) == MESO_OK);
    assert(meso_cells_chunks_build(&tm, &sc, &mb, g.origin, g.voxel_size, "hash:3", 2, &cc, &err) == MESO_OK);
    const uint64_t V = 16 * 16 * 16, T = 6 * 6 * 6;
    const uint64_t chunks = cc.tile_size + cc.splt_size + cc.memb_size + cc.nrmm_size + cc.colr_size;
    const uint64_t membership = 2 * 4 * ((T + 15) / 16) + 4 * mb.record_count * mb.words_per_tile;
    const uint64_t held = 2 * V /* tile map */ + 4 * V /* labels */ + membership + 2 * chunks /* + writer */;
    printf("%s: estimate %llu bytes (%llu beyond 96 MiB); held at the end %llu; near-surface tiles %llu, MIXED %llu "
           "before the merge, %llu after\n",
           mesh, (unsigned long long)est, (unsigned long long)(est - (96ull << 20)), (unsigned long long)held,
           (unsigned long long)near, (unsigned long long)mb.voxelize.tiles_mixed,
           (unsigned long long)mb.tiles_mixed);
    assert(est - (96ull << 20) >= held);
    assert(est - (96ull << 20) <= 4 * held + (1u << 20));
    assert(near >= mb.voxelize.tiles_mixed && near >= mb.tiles_mixed);
    meso_cells_chunks_free(&cc);
    meso_membership_free(&mb);
    meso_split_cells_free(&sc);
    meso_tile_map_free(&tm);
    meso_mesh_free(&m);
}

static void cells_estimates(void)
{
    cells_estimate_bounds_a_real_bake("sphere.obj");
    cells_estimate_bounds_a_real_bake("spot_low_resolution.obj");
}

/* The PNG reader's need is exactly its allocations plus the caller's bytes
 * a pixel: a budget of `need` reads the image, `need - 1` refuses it. */
static void png_budget_boundary(void)
{
    const int w = 40, h = 24;
    uint16_t px[40 * 24];
    for (int i = 0; i < w * h; ++i)
        px[i] = (uint16_t)(i * 37);
    char why[256];
    for (int depth = 8; depth <= 16; depth += 8) {
        for (int i = 0; i < w * h; ++i)
            px[i] = (uint16_t)(depth == 8 ? px[i] & 255 : px[i]);
        assert(meso_png_write_gray(tmp_path("g.png"), px, w, h, depth, why, sizeof why) == 0);
        const uint64_t rowbytes = (uint64_t)w * (uint64_t)depth / 8;
        const uint64_t need = rowbytes * h + sizeof(void*) * (uint64_t)h + (2 + 10) * (uint64_t)w * h;
        uint16_t* out = NULL;
        int ow = 0, oh = 0, od = 0;
        uint64_t got = 0;
        FILE* fp = fopen(tmp_path("g.png"), "rb");
        assert(meso_png_read_channel0_fp(fp, "g.png", need - 1, 10, &out, &ow, &oh, &od, &got, why, sizeof why) == -2);
        assert(out == NULL && got == need && strstr(why, "40x24 pixels"));
        rewind(fp);
        assert(meso_png_read_channel0_fp(fp, "g.png", need, 10, &out, &ow, &oh, &od, &got, why, sizeof why) == 0);
        fclose(fp);
        assert(ow == w && oh == h && od == depth && !memcmp(out, px, sizeof px));
        free(out);
    }
}

/* A raw volume's estimate, at its exact boundary, through the spec; a file
 * of the wrong length is refused as content before the budget is looked at. */
static void raw_volume_budget_boundary(void)
{
    uint8_t v[6 * 5 * 4];
    for (size_t i = 0; i < sizeof v; ++i)
        v[i] = (uint8_t)(i * 3);
    FILE* fp = fopen(tmp_path("v.raw"), "wb");
    assert(fp && fwrite(v, 1, sizeof v, fp) == sizeof v && fclose(fp) == 0);
    char spec[300];
    snprintf(spec, sizeof spec, "volume:%s:6x5x4", tmp_path("v.raw"));
    const uint64_t est = meso_texture_estimate(sizeof v);
    assert(est == (96ull << 20) + 11 * sizeof v);
    meso_texfn f;
    meso_error err = {0};
    assert(meso_texfn_from_spec_max(spec, est - 1, &f, &err) == MESO_ERR_INVALID_ARG && err.code == 3400);
    assert(f.values == NULL);
    assert(meso_texfn_from_spec_max(spec, est, &f, &err) == MESO_OK && f.dims[2] == 4);
    meso_texfn_free(&f);
    snprintf(spec, sizeof spec, "volume:%s:4096x4096x4096", tmp_path("v.raw"));
    assert(meso_texfn_from_spec_max(spec, 1, &f, &err) == MESO_ERR_CORRUPT && err.code == 3122);
    assert(strstr(err.message, "has 120 bytes, expected exactly 68719476736"));
}

static void skeleton_lines(void)
{
    FILE* fp = fopen(tmp_path("s.swc"), "wb");
    assert(fp && fputs("# c\n1 1 0 0 0 1 -1\n2 3 1 0 0 1 1", fp) >= 0 && fclose(fp) == 0);
    uint64_t bytes = 0, lines = 0;
    meso_error err = {0};
    assert(meso_count_lines(tmp_path("s.swc"), &bytes, &lines, &err) == MESO_OK && bytes == 32 && lines == 3);
    assert(meso_skeleton_estimate(bytes, lines) == (96ull << 20) + 32 + 3 * 1024);
    assert(meso_count_lines(tmp_path("missing.swc"), &bytes, &lines, &err) == MESO_ERR_IO);
}

int main(void)
{
    snprintf(tmp_dir, sizeof tmp_dir, "/tmp/meso_budget_XXXXXX");
    assert(mkdtemp(tmp_dir));
    TEST_RUN(parse_size_table);
    TEST_RUN(format_and_saturate);
    TEST_RUN(cells_estimates);
    TEST_RUN(png_budget_boundary);
    TEST_RUN(raw_volume_budget_boundary);
    TEST_RUN(skeleton_lines);
    const char* names[] = {"g.png", "v.raw", "s.swc"};
    for (size_t i = 0; i < 3; ++i)
        unlink(tmp_path(names[i]));
    rmdir(tmp_dir);
    return 0;
}
