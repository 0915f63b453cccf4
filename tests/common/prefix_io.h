/* prefix_io.h — a meso_io reader that has received only the first `limit`
 * bytes of a file in memory (reads past them fail): a stream cut at a
 * level boundary (FORMAT.md §7.10 prefix_bytes). Shared by test_rt_levels,
 * test_rt_cells and test_rt_prefixes. */
#ifndef MESO_TEST_PREFIX_IO_H
#define MESO_TEST_PREFIX_IO_H

#include <stdint.h>
#include <string.h>

#include "meso_file.h"

typedef struct prefix_io {
    const uint8_t* data;
    uint64_t limit;
} prefix_io;

static inline int prefix_read(void* user, uint64_t off, void* dst, size_t n)
{
    const prefix_io* p = user;
    if (off > p->limit || n > p->limit - off)
        return -1;
    memcpy(dst, p->data + off, n);
    return 0;
}

/* The same for a stream still arriving: past `limit` the bytes have not
 * arrived yet (MESO_IO_PENDING), which a reader may ask again later. */
static inline int prefix_read_pending(void* user, uint64_t off, void* dst, size_t n)
{
    const prefix_io* p = user;
    if (off > p->limit || n > p->limit - off)
        return MESO_IO_PENDING;
    memcpy(dst, p->data + off, n);
    return 0;
}

#endif /* MESO_TEST_PREFIX_IO_H */
