/*
 * fuzz_mesh.h — the body of the mesh guard's fuzz targets
 * (fuzz_mesh_obj.c, fuzz_mesh_off.c, fuzz_mesh_ply.c, fuzz_mesh_stl.c): each
 * feeds the input to meso_mesh_guard_check (bake/mesh_guard.c) as its format.
 *
 *   # replay a corpus with any compiler (meson test --suite fuzz):
 *   ./build/tests/fuzz/fuzz_mesh_ply tests/fuzz/corpus/mesh_ply
 *   # real fuzzing (clang, -Dfuzzing_engine=libfuzzer), on a scratch copy:
 *   cp -r tests/fuzz/corpus/mesh_ply /tmp/c && \
 *     ./build-fuzz/tests/fuzz/fuzz_mesh_ply /tmp/c -dict=tests/fuzz/mesh.dict
 *
 * What it asserts beyond "no crash, no overread, no leak, no hang": the
 * verdict is MESO_OK or MESO_ERR_CORRUPT with a code in 3200..3249 and a
 * message; an accepted file has vertices, faces and at least one triangle
 * per face; the verdict does not change when the guard runs again (it keeps
 * no state) or with a budget just large enough for what it counted.
 */
#ifndef MESO_FUZZ_MESH_H
#define MESO_FUZZ_MESH_H

#undef NDEBUG /* this file uses assert() to check the guard's contract */
#include <assert.h>
#include <stdint.h>
#include <string.h>

#include "mesh_guard.h"

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

static inline void fuzz_mesh_one(meso_mesh_format format, const uint8_t* data, size_t size)
{
    meso_error err;
    memset(&err, 0, sizeof(err));
    meso_mesh_guard_stats st;
    meso_result r = meso_mesh_guard_check(format, data, size, 0, &st, &err);
    if (r != MESO_OK) {
        assert(r == MESO_ERR_CORRUPT);
        assert(err.code >= 3200 && err.code <= 3249);
        assert(err.message[0] != 0);
        assert(err.offset <= size);
    } else {
        assert(st.vertices > 0 && st.faces > 0 && st.triangles >= st.faces);
    }
    meso_error again;
    memset(&again, 0, sizeof(again));
    meso_mesh_guard_stats st2;
    assert(meso_mesh_guard_check(format, data, size, 0, &st2, &again) == r);
    assert(again.code == err.code && strcmp(again.message, err.message) == 0);
    if (r == MESO_OK) {
        assert(memcmp(&st, &st2, sizeof(st)) == 0);
        uint64_t need = st.vertices * MESO_MESH_GUARD_BYTES_PER_VERTEX +
                        st.triangles * MESO_MESH_GUARD_BYTES_PER_TRIANGLE + size;
        /* DRC and OM are not fuzzed here; for the others the budget is the estimate */
        assert(meso_mesh_guard_check(format, data, size, need, NULL, &again) == MESO_OK);
    }
}

#endif /* MESO_FUZZ_MESH_H */
