/* bake_bytes.h — a bake's file as bytes in memory, for the tests that bake
 * through the library and hand the file to the runtime without a file on
 * disk. */
#ifndef MESO_TEST_BAKE_BYTES_H
#define MESO_TEST_BAKE_BYTES_H

#include "meso_bake.h"
#include "test_util.h"

/* The bytes of `out` (malloc'd, *size of them); frees `out`. Aborts on
 * failure. */
static inline uint8_t* bake_bytes(meso_bake_output* out, size_t* size)
{
    assert(out);
    *size = meso_bake_output_size(out);
    uint8_t* data = malloc(*size);
    assert(data && meso_bake_output_copy(out, data, *size, NULL) == MESO_OK);
    meso_bake_output_free(out);
    return data;
}

#endif
