/*
 * rt_mesh_repack.c — a MESH-layout chunk (MESH, PMSH; FORMAT.md §7.3) as
 * libmeso holds it on the GPU (meso_rt.h, meso_rt_desc.memory_budget),
 * made in the chunk's own buffer: positions as stored, normals as signed
 * 10-bit x, y, z (GL_INT_2_10_10_10_REV), indices in 16 bits where every
 * index is below 0xFFFF (a host's fixed primitive restart would cut at
 * 0xFFFF), no uvs (no shader reads them).
 *
 * A mesh of V vertices and T triangles then holds about 16 V + 6 T bytes
 * where the chunk has 32 V + 12 T. On bench_lod_scene the 1 px frame,
 * mostly meshes and stand-ins, went from 0.219 of the finest frame's GPU
 * bytes to 0.185 (README, "Levels of detail").
 *
 * Decided: a normal is made unit length and scaled by 511 before it is
 * rounded (FORMAT.md asks a file's normals only to be finite), and GL
 * reads the integers as they are (not normalised): every shader
 * normalises the normal, so the scale does not matter, and GL 3.3-4.1's
 * decoding of normalised 10-bit values ((2c + 1) / 1023, which would make
 * a zero normal non-zero) never applies. The rounding moves a component of
 * the unit normal by at most 1/1022, under half a level of 255 in the
 * Lambert term (the scene's error against its supersampled render did not
 * move). A zero normal stays zero. It touches no context, so a
 * stream request repacks its level's mesh off the GL thread, with the
 * decode (rt_stream.c); tests/unit/test_mesh_repack.c checks it against
 * the chunk it came from.
 */
#include "rt_mesh_repack.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* Positions move to 0, normals to the next multiple of 16 as
 * signed 10-bit x, y, z, then the indices, u16 when vertex_count <= 65535,
 * else u32. Each array lands at or before where the chunk had it and is
 * written front to back, never larger per element than it was, so no
 * element is overwritten before it is read. */
meso_result mesoi_mesh_repack(void* buffer, size_t size, mesoi_mesh_gpu* out, meso_error* err)
{
    meso_mesh_view mv;
    const meso_result r = meso_mesh_parse(buffer, size, &mv, err);
    if (r != MESO_OK)
        return r;
    const meso_mesh_layout* L = &mv.layout;
    if (L->index_count > (uint32_t)INT32_MAX || !mv.normals) {
        *err = (meso_error){.result = MESO_ERR_UNSUPPORTED, .chunk = -1};
        snprintf(err->message, sizeof err->message, "MESH without normals or with too many indices (%u)",
                 L->index_count);
        return MESO_ERR_UNSUPPORTED;
    }
    uint8_t* data = buffer;
    const size_t nv = L->vertex_count, ni = L->index_count;
    memmove(data, data + L->positions_offset, 12 * nv);
    size_t at = (12 * nv + 15) & ~(size_t)15;
    out->normals_at = at;
    const uint8_t* src = data + L->normals_offset;
    for (size_t v = 0; v < nv; ++v) {
        float n[3];
        memcpy(n, src + 12 * v, 12);
        /* The shaders normalise the normal; a file's need not be unit
         * length (FORMAT.md asks only for finite), so it is made so here,
         * where 10 bits would otherwise clamp its direction. In double, a
         * float's square neither overflows nor underflows. */
        const double len = sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]);
        const double scale = len > 0.0 ? 511.0 / len : 0.0;
        uint32_t packed = 0;
        for (int k = 0; k < 3; ++k)
            packed |= ((uint32_t)(int32_t)lrint(fmin(fmax(n[k] * scale, -511.0), 511.0)) & 0x3FFu) << (10 * k);
        memcpy(data + at + 4 * v, &packed, 4);
    }
    at = (at + 4 * nv + 15) & ~(size_t)15;
    out->indices_at = at;
    out->vertex_count = L->vertex_count;
    out->index_count = L->index_count;
    src = data + L->indices_offset;
    if (nv <= 65535) { /* no index is 0xFFFF, the fixed primitive-restart index (ES 3, GL 4.3) */
        out->index_size = 2;
        for (size_t i = 0; i < ni; ++i) {
            uint32_t x;
            memcpy(&x, src + 4 * i, 4);
            const uint16_t y = (uint16_t)x;
            memcpy(data + at + 2 * i, &y, 2);
        }
        out->bytes = at + 2 * ni;
    } else {
        out->index_size = 4;
        memmove(data + at, src, 4 * ni);
        out->bytes = at + 4 * ni;
    }
    return MESO_OK;
}
