/* standin_check.h — what the stand-in level tests (test_shell_standin,
 * test_frusta_standin) share: point_triangle.h's exact distance for
 * checking a mesh level's stated error by brute force over its triangles,
 * reading that mesh, and the one-level file of `--levels 1`. Include after test_util.h. */
#ifndef MESO_TEST_STANDIN_CHECK_H
#define MESO_TEST_STANDIN_CHECK_H

#include <math.h>
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

#endif /* MESO_TEST_STANDIN_CHECK_H */
