/* standin_check.h — what the stand-in level tests (test_shell_standin,
 * test_frusta_standin) share: point_triangle.h's exact distance for
 * checking a mesh level's stated error by brute force over its triangles,
 * reading that mesh, and the one-level file of `--levels 1`. Include after test_util.h. */
#ifndef MESO_TEST_STANDIN_CHECK_H
#define MESO_TEST_STANDIN_CHECK_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "meso_file.h"
#include "meso_layout.h"
#include "point_triangle.h" /* point_triangle: the exact point-triangle distance */

static inline uint8_t* test_read_level_mesh(meso_file* f, uint16_t lod, meso_mesh_view* mv)
{
    const int32_t mi = meso_file_find(f, MESO_CHUNK_MESH, 1, lod);
    assert(mi >= 0);
    const meso_chunk_info* mc = meso_file_chunk(f, (uint32_t)mi);
    uint8_t* mb = malloc((size_t)mc->decoded_size);
    assert(mb && meso_file_read_chunk(f, (uint32_t)mi, mb, (size_t)mc->decoded_size, NULL) == MESO_OK);
    assert(meso_mesh_parse(mb, (size_t)mc->decoded_size, mv, NULL) == MESO_OK);
    return mb;
}

/* Object 1's levels of `f` (at most 16; counting level 0 and the mesh
 * stand-ins, at least min_levels): level 0 native, then any native coarser levels
 * (a halved texture or relief: tests of their own check them), then mesh
 * stand-ins only, each with an error no smaller than the finer one's, in a
 * shorter prefix of the file. Returns the count; *first the first
 * stand-in's level. */
static inline uint32_t test_standin_chain(meso_file* f, meso_level_info li[16], uint32_t min_levels, uint32_t* first)
{
    uint32_t n = 0, S = 1;
    assert(meso_file_levels(f, 1, li, 16, &n, NULL) == MESO_OK && n <= 9);
    assert(li[0].rec.form == MESO_LEVEL_NATIVE);
    while (S < n && li[S].rec.form == MESO_LEVEL_NATIVE)
        ++S;
    assert(n >= S + min_levels - 1);
    for (uint32_t L = 1; L < n; ++L) {
        assert((L < S || li[L].rec.form == MESO_LEVEL_MESH) && li[L].rec.error > 0);
        assert(li[L].rec.error >= li[L - 1].rec.error); /* never finer when coarser */
        assert(li[L].prefix_bytes < li[L - 1].prefix_bytes);
    }
    *first = S;
    return n;
}

/* `mesobake KIND -i INPUT ARGS -o DIR/NAME.meso`, with `--report
 * DIR/NAME.json` when `report` is not NULL (its path written there, 512
 * bytes): the file opened and valid in the full tier. */
static inline meso_file* test_bake_open(const char* mesobake, const char* kind, const char* input, const char* args,
                                        const char* dir, const char* name, char* report)
{
    char path[512], rep[600] = "", cmd[10240];
    snprintf(path, sizeof path, "%s/%s.meso", dir, name);
    if (report) {
        snprintf(report, 512, "%s/%s.json", dir, name);
        snprintf(rep, sizeof rep, "--report '%s'", report);
    }
    snprintf(cmd, sizeof cmd, "'%s' %s -i '%s' %s -o '%s' %s >/dev/null", mesobake, kind, input, args, path, rep);
    assert(system(cmd) == 0);
    meso_file* f = NULL;
    assert(meso_file_open_path(path, NULL, &f, NULL) == MESO_OK);
    assert(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);
    return f;
}

/* A bake report (JSON text, under `size` bytes) into buf, NUL-ended. */
static inline void test_read_report(const char* path, char* buf, size_t size)
{
    FILE* rf = fopen(path, "rb");
    assert(rf);
    const size_t n = fread(buf, 1, size - 1, rf);
    assert(n < size - 1);
    buf[n] = 0;
    fclose(rf);
}

/* The file at `path` (a bake with --levels 1) has one level and no LODS. */
static inline void test_assert_one_level(const char* path)
{
    meso_file* f = NULL;
    assert(meso_file_open_path(path, NULL, &f, NULL) == MESO_OK);
    uint32_t n = 0;
    assert(meso_file_levels(f, 1, NULL, 0, &n, NULL) == MESO_OK && n == 1);
    assert(meso_file_find(f, MESO_CHUNK_LODS, UINT32_MAX, UINT16_MAX) < 0);
    meso_file_close(f);
}

/* The file at `path` (a bake with --levels 2) has level 0 and the base
 * mesh as a mesh stand-in: no native coarser level, no simplified one. */
static inline void test_assert_base_mesh_only(const char* path)
{
    meso_file* f = NULL;
    meso_level_info li[4];
    uint32_t n = 0;
    assert(meso_file_open_path(path, NULL, &f, NULL) == MESO_OK);
    assert(meso_file_levels(f, 1, li, 4, &n, NULL) == MESO_OK && n == 2 && li[1].rec.form == MESO_LEVEL_MESH);
    meso_file_close(f);
}

#endif /* MESO_TEST_STANDIN_CHECK_H */
