/* rt_mesh_repack.h — a MESH-layout chunk repacked for the GPU
 * (rt_mesh_repack.c). Internal to libmeso; no GL. */
#ifndef MESOI_RT_MESH_REPACK_H
#define MESOI_RT_MESH_REPACK_H

#include <stddef.h>
#include <stdint.h>

#include "meso_file.h"

/* Where the repacked arrays lie in the chunk's buffer. */
typedef struct mesoi_mesh_gpu {
    size_t bytes;      /* used, from the buffer's start */
    size_t normals_at; /* positions at 0, f32 x 3; normals here, 4 bytes a vertex: 511 x the unit
                          normal, rounded, as signed 10-bit x, y, z (GL_INT_2_10_10_10_REV) */
    size_t indices_at; /* index_size bytes each */
    uint32_t vertex_count, index_count;
    uint32_t index_size; /* 2 when vertex_count <= 65535, else 4 */
} mesoi_mesh_gpu;

/* Parses the decoded chunk `data` of `size` bytes (4-byte aligned, as
 * meso_mesh_parse asks) and repacks it in place. Any thread. The parse's
 * error, or MESO_ERR_UNSUPPORTED for a mesh without normals or with more
 * than INT32_MAX indices; err says what was wrong. */
meso_result mesoi_mesh_repack(void* data, size_t size, mesoi_mesh_gpu* out, meso_error* err);

#endif
