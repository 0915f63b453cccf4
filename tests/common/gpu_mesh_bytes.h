/* gpu_mesh_bytes.h — the bytes libmeso holds on the GPU for one MESH (or
 * PMSH) chunk, as meso_rt.h states it (meso_rt_desc.memory_budget): 12 a
 * vertex of positions, 4 of normals, 2 an index (4 from 65536 vertices),
 * each array from a multiple of 16; vertex colours not included. Computed
 * from the chunk's own header; aborts when the chunk is not a MESH. Shared
 * by test_rt_levels and test_rt_cells. */
#ifndef MESO_TEST_GPU_MESH_BYTES_H
#define MESO_TEST_GPU_MESH_BYTES_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "meso_file.h"

static inline uint64_t gpu_mesh_bytes(meso_file* f, uint32_t chunk)
{
    const meso_chunk_info* c = meso_file_chunk(f, chunk);
    uint32_t* data = c ? malloc((size_t)c->decoded_size + 4) : NULL;
    meso_mesh_view mv;
    if (!data || meso_file_read_chunk(f, chunk, data, (size_t)c->decoded_size, NULL) != MESO_OK ||
        meso_mesh_parse(data, (size_t)c->decoded_size, &mv, NULL) != MESO_OK) {
        fprintf(stderr, "FAILED: gpu_mesh_bytes: chunk %u is not a readable MESH\n", chunk);
        abort(); /* a 0 would let a lower bound pass */
    }
    free(data);
    const uint64_t v = mv.layout.vertex_count, i = mv.layout.index_count;
    const uint64_t at = (12 * v + 15) / 16 * 16 + (4 * v + 15) / 16 * 16;
    return at + (v <= 65535 ? 2 : 4) * i;
}

#endif
