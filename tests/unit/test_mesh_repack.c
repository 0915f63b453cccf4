/* test_mesh_repack.c — a MESH chunk repacked for the GPU
 * (runtime/rt_mesh_repack.c) against the chunk it came from, element by
 * element:
 *  - the bytes and offsets are what meso_rt.h states a MESH holds (12 a
 *    vertex of positions, 4 of normals, 2 an index up to 65535 vertices
 *    and 4 from 65536, so that no 16-bit index is the restart index
 *    0xFFFF; each array from a multiple of 16);
 *  - positions and indices are the chunk's, bit for bit;
 *  - each normal, the signed 10-bit integers c that GL reads as they are
 *    (not normalised) divided by 511, lies within 1/1022 a component of
 *    the chunk's normal made unit length, whatever its length (tiny, huge,
 *    unit) and direction (float rounding allowed: 1e-6); a zero normal
 *    stays zero;
 *  - a chunk with a bad index or without normals is refused with the
 *    parse's error or MESO_ERR_UNSUPPORTED and a message.
 * Meshes: random ones of 1, 300 and 65535 vertices (u16), 65536 and 70000
 * (u32), with and without uvs, and a point set (no indices).
 */
#include "test_need.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "rt_mesh_repack.h"

static uint64_t rng = 0x2545f4914f6cdd1dull;
static uint32_t next(uint32_t n)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (uint32_t)((rng >> 11) % n);
}
static float uniform(float lo, float hi) { return lo + (hi - lo) * (float)next(1u << 24) / (float)(1u << 24); }

/* A random MESH chunk (meso_mesh_compute_layout's layout) in a 4-byte
 * aligned buffer; *layout gets its layout. */
static uint32_t* make_mesh(uint32_t nv, uint32_t ni, uint32_t attributes, meso_mesh_layout* layout)
{
    need(meso_mesh_compute_layout(nv, ni, attributes, layout) == MESO_OK, "layout of %u vertices", nv);
    uint32_t* buf = calloc((size_t)layout->size / 4 + 1, 4);
    need(buf != NULL, "out of memory");
    uint8_t* b = (uint8_t*)buf;
    meso_mesh_write_header(layout, b);
    float* p = (float*)(b + layout->positions_offset);
    for (size_t k = 0; k < 3 * (size_t)nv; ++k)
        p[k] = uniform(-100.0f, 100.0f);
    if (attributes & MESO_MESH_ATTR_NORMALS) {
        float* n = (float*)(b + layout->normals_offset);
        for (uint32_t v = 0; v < nv; ++v) {
            /* Lengths from 1e-30 to 1e30 and unit; now and then zero, or
             * one component only, or a negative axis. */
            static const float lengths[] = {1.0f, 1e-30f, 1e30f, 0.25f, 3.0e5f};
            const float len = lengths[next(5)];
            for (int k = 0; k < 3; ++k)
                n[3 * v + k] = uniform(-1.0f, 1.0f) * len;
            const uint32_t kind = next(20);
            if (kind == 0)
                n[3 * v] = n[3 * v + 1] = n[3 * v + 2] = 0.0f;
            else if (kind == 1)
                n[3 * v] = -len, n[3 * v + 1] = n[3 * v + 2] = 0.0f;
        }
    }
    if (attributes & MESO_MESH_ATTR_UVS) {
        float* t = (float*)(b + layout->uvs_offset);
        for (size_t k = 0; k < 2 * (size_t)nv; ++k)
            t[k] = uniform(0.0f, 1.0f);
    }
    uint32_t* idx = (uint32_t*)(b + layout->indices_offset);
    for (uint32_t i = 0; i < ni; ++i)
        idx[i] = i < nv ? nv - 1 - i : next(nv); /* every vertex, the last and first included */
    return buf;
}

static size_t up16(size_t n) { return (n + 15) / 16 * 16; }

/* Component k of a packed normal over 511: the unit normal it stands for. */
static double int10(uint32_t packed, int k)
{
    int32_t c = (int32_t)((packed >> (10 * k)) & 0x3FFu);
    if (c >= 512)
        c -= 1024;
    return c / 511.0;
}

static void check_one(uint32_t nv, uint32_t ni, uint32_t attributes)
{
    meso_mesh_layout L;
    uint32_t* chunk = make_mesh(nv, ni, attributes, &L);
    uint32_t* copy = malloc((size_t)L.size + 4);
    need(copy != NULL, "out of memory");
    memcpy(copy, chunk, (size_t)L.size);
    mesoi_mesh_gpu g;
    meso_error err;
    need(mesoi_mesh_repack(copy, (size_t)L.size, &g, &err) == MESO_OK, "%u vertices: %s", nv, err.message);
    const size_t isize = nv <= 65535 ? 2 : 4;
    need(g.vertex_count == nv && g.index_count == ni && g.index_size == isize, "%u vertices: counts or index size",
         nv);
    need(g.normals_at == up16(12 * (size_t)nv) && g.indices_at == g.normals_at + up16(4 * (size_t)nv) &&
             g.bytes == g.indices_at + isize * ni,
         "%u vertices: layout %zu %zu %zu", nv, g.normals_at, g.indices_at, g.bytes);
    need(g.bytes <= L.size, "%u vertices: repacked larger than the chunk", nv);
    const uint8_t *src = (const uint8_t*)chunk, *dst = (const uint8_t*)copy;
    need(memcmp(dst, src + L.positions_offset, 12 * (size_t)nv) == 0, "%u vertices: positions differ", nv);
    double worst = 0.0;
    uint32_t zeros = 0;
    for (uint32_t v = 0; v < nv; ++v) {
        double n[3], len = 0.0;
        for (int k = 0; k < 3; ++k) {
            float f;
            memcpy(&f, src + L.normals_offset + 12 * (size_t)v + 4 * (size_t)k, 4);
            n[k] = f;
            len += n[k] * n[k];
        }
        len = sqrt(len);
        uint32_t packed;
        memcpy(&packed, dst + g.normals_at + 4 * (size_t)v, 4);
        for (int k = 0; k < 3; ++k) {
            const double want = len > 0.0 ? n[k] / len : 0.0;
            const double d = fabs(int10(packed, k) - want);
            worst = d > worst ? d : worst;
        }
        zeros += len == 0.0;
        if (len == 0.0)
            need((packed & 0x3FFFFFFFu) == 0, "vertex %u: a zero normal packed as %08x", v, packed);
    }
    need(worst <= 1.0 / 1022.0 + 1e-6, "%u vertices: a normal off by %.6f a component", nv, worst);
    for (uint32_t i = 0; i < ni; ++i) {
        uint32_t want, got = 0;
        memcpy(&want, src + L.indices_offset + 4 * (size_t)i, 4);
        memcpy(&got, dst + g.indices_at + isize * i, isize); /* little-endian: the low bytes */
        need(got == want, "%u vertices: index %u is %u, not %u", nv, i, got, want);
    }
    printf("%6u vertices, %6u indices%s: %zu bytes for the chunk's %llu, normals within %.6f (bound %.6f), "
           "%u zero\n",
           nv, ni, attributes & MESO_MESH_ATTR_UVS ? ", uvs" : "", g.bytes, (unsigned long long)L.size, worst,
           1.0 / 1022.0, zeros);
    free(copy);
    free(chunk);
}

static void check_refused(void)
{
    meso_mesh_layout L;
    meso_error err;
    mesoi_mesh_gpu g;
    uint32_t* bad = make_mesh(4, 6, MESO_MESH_ATTR_POSITIONS | MESO_MESH_ATTR_NORMALS, &L);
    uint32_t four = 4; /* index 4 of a 4-vertex mesh */
    memcpy((uint8_t*)bad + L.indices_offset + 8, &four, 4);
    const meso_result r = mesoi_mesh_repack(bad, (size_t)L.size, &g, &err);
    need(r != MESO_OK && r != MESO_ERR_UNSUPPORTED && err.message[0], "an index past the vertices was taken");
    printf("bad index refused: %s\n", err.message);
    free(bad);
    uint32_t* bare = make_mesh(4, 6, MESO_MESH_ATTR_POSITIONS, &L);
    need(mesoi_mesh_repack(bare, (size_t)L.size, &g, &err) == MESO_ERR_UNSUPPORTED && strstr(err.message, "normals"),
         "a mesh without normals was taken");
    printf("no normals refused: %s\n", err.message);
    free(bare);
}

int main(void)
{
    const uint32_t pn = MESO_MESH_ATTR_POSITIONS | MESO_MESH_ATTR_NORMALS;
    check_one(1, 3, pn);
    check_one(300, 900, pn);
    check_one(300, 900, pn | MESO_MESH_ATTR_UVS);
    check_one(65535, 3 * 65535, pn | MESO_MESH_ATTR_UVS);
    check_one(65536, 3 * 65536, pn);
    check_one(70000, 3 * 70000, pn);
    check_one(5, 0, pn); /* a point set */
    check_refused();
    return 0;
}
