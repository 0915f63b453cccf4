/*
 * mesh_chunk.c — a bake mesh as a MESH chunk (FORMAT.md "MESH"), raw or
 * Draco-encoded, and the Draco decoder that readers register.
 *
 * Draco payloads keep the 64-byte MESH header in front of the bitstream, with
 * the quantisation bits filled in, so a reader knows the decoded layout (and
 * can allocate exactly) before decoding, and a reader without Draco can still
 * say what the chunk holds. The decoder requires the canonical layout of
 * meso_mesh_compute_layout, which is the only one mesobake writes.
 */
#include "mesh_chunk.h"

#include <stdlib.h>
#include <string.h>

#include "meso_layout.h"

#if MESO_HAVE_DRACO /* only the Draco header check reads stored fields */
static uint32_t rd32(const uint8_t* p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static uint64_t rd64(const uint8_t* p)
{
    return (uint64_t)rd32(p) | ((uint64_t)rd32(p + 4) << 32);
}
#endif

static uint32_t mesh_attributes(const meso_mesh* m)
{
    return MESO_MESH_ATTR_POSITIONS | (m->normals ? MESO_MESH_ATTR_NORMALS : 0u) | (m->uvs ? MESO_MESH_ATTR_UVS : 0u);
}

/* Copy the arrays of `m` into a decoded-layout buffer. */
static void fill_arrays(const meso_mesh* m, const meso_mesh_layout* l, uint8_t* dst)
{
    memcpy(dst + l->positions_offset, m->positions, (size_t)m->vertex_count * 12u);
    if (l->normals_offset)
        memcpy(dst + l->normals_offset, m->normals, (size_t)m->vertex_count * 12u);
    if (l->uvs_offset)
        memcpy(dst + l->uvs_offset, m->uvs, (size_t)m->vertex_count * 8u);
    memcpy(dst + l->indices_offset, m->indices, (size_t)m->triangle_count * 12u);
}

meso_result meso_bake_mesh_chunk(const meso_mesh* m, const meso_draco_options* draco, meso_mesh_chunk* out,
                                 meso_error* err)
{
    memset(out, 0, sizeof(*out));
    meso_mesh_layout l;
    meso_result r = meso_mesh_compute_layout(m->vertex_count, m->triangle_count * 3u, mesh_attributes(m), &l);
    if (r != MESO_OK)
        return meso_bake_fail(err, r, 0, "mesh of %u vertices and %u triangles does not fit a MESH chunk",
                              m->vertex_count, m->triangle_count);
    out->decoded_size = l.size;
    if (!draco) {
        uint8_t* buf = calloc(1, (size_t)l.size);
        if (!buf)
            return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "MESH chunk: out of memory (%llu bytes)",
                                  (unsigned long long)l.size);
        meso_mesh_write_header(&l, buf);
        fill_arrays(m, &l, buf);
        out->data = buf;
        out->size = (size_t)l.size;
        out->encoding = MESO_ENCODING_RAW;
        return MESO_OK;
    }
#if MESO_HAVE_DRACO
    void* bits = NULL;
    size_t nbits = 0;
    r = meso_draco_encode(m, draco, &bits, &nbits, err);
    if (r != MESO_OK)
        return r;
    uint8_t* buf = malloc(MESO_MESH_HDR_SIZE + nbits);
    if (!buf) {
        free(bits);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "MESH chunk: out of memory");
    }
    l.quant_bits_position = (uint8_t)(draco->position_bits ? draco->position_bits : 14);
    l.quant_bits_normal = (uint8_t)(l.normals_offset ? (draco->normal_bits ? draco->normal_bits : 10) : 0);
    l.quant_bits_uv = (uint8_t)(l.uvs_offset ? (draco->uv_bits ? draco->uv_bits : 12) : 0);
    meso_mesh_write_header(&l, buf);
    memcpy(buf + MESO_MESH_HDR_SIZE, bits, nbits);
    free(bits);
    out->data = buf;
    out->size = MESO_MESH_HDR_SIZE + nbits;
    out->encoding = MESO_ENCODING_DRACO;
    return MESO_OK;
#else
    return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0, "Draco mesh chunks: this build has no Draco adapter");
#endif
}

#if MESO_HAVE_DRACO
static meso_result draco_decode(void* user, const meso_chunk_info* chunk, const void* src, size_t src_size, void* dst,
                                size_t dst_size, meso_error* err)
{
    (void)user;
    const uint8_t* s = src;
    if (src_size < MESO_MESH_HDR_SIZE)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 4301, "Draco MESH chunk shorter than its 64-byte header");
    const uint32_t vc = rd32(s + MESO_MESH_OFF_VERTEX_COUNT), ic = rd32(s + MESO_MESH_OFF_INDEX_COUNT);
    const uint32_t attrs = rd32(s + MESO_MESH_OFF_ATTRIBUTES);
    meso_mesh_layout l;
    if (meso_mesh_compute_layout(vc, ic, attrs, &l) != MESO_OK || l.size != chunk->decoded_size ||
        l.size > dst_size || rd64(s + MESO_MESH_OFF_POSITIONS) != l.positions_offset ||
        rd64(s + MESO_MESH_OFF_NORMALS) != l.normals_offset || rd64(s + MESO_MESH_OFF_UVS) != l.uvs_offset ||
        rd64(s + MESO_MESH_OFF_INDICES) != l.indices_offset)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 4301,
                              "Draco MESH header (%u vertices, %u indices) does not match the decoded size %llu", vc,
                              ic, (unsigned long long)chunk->decoded_size);
    meso_mesh m;
    meso_result r = meso_draco_decode(s + MESO_MESH_HDR_SIZE, src_size - MESO_MESH_HDR_SIZE, &m, err);
    if (r != MESO_OK)
        return r;
    if (m.vertex_count != vc || m.triangle_count * 3u != ic || (m.normals != NULL) != (l.normals_offset != 0) ||
        (m.uvs != NULL) != (l.uvs_offset != 0)) {
        /* meso_mesh_free zeroes the struct: keep the counts for the message. */
        const uint32_t got_vc = m.vertex_count, got_ic = m.triangle_count * 3u;
        const int got_n = m.normals != NULL, got_uv = m.uvs != NULL;
        meso_mesh_free(&m);
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 4303,
                              "Draco bitstream holds %u vertices / %u indices%s%s, the header says %u / %u%s%s", got_vc,
                              got_ic, got_n ? ", normals" : "", got_uv ? ", uvs" : "", vc, ic,
                              l.normals_offset ? ", normals" : "", l.uvs_offset ? ", uvs" : "");
    }
    l.quant_bits_position = s[MESO_MESH_OFF_QUANT_POSITION];
    l.quant_bits_normal = s[MESO_MESH_OFF_QUANT_NORMAL];
    l.quant_bits_uv = s[MESO_MESH_OFF_QUANT_UV];
    memset(dst, 0, (size_t)l.size);
    meso_mesh_write_header(&l, dst);
    fill_arrays(&m, &l, dst);
    meso_mesh_free(&m);
    return MESO_OK;
}
#endif

meso_decoder meso_bake_draco_decoder(void)
{
    meso_decoder d;
    memset(&d, 0, sizeof(d));
    d.encoding = MESO_ENCODING_DRACO;
#if MESO_HAVE_DRACO
    d.decode_fn = draco_decode;
#endif
    return d;
}

meso_result meso_bake_mesh_from_view(const meso_mesh_view* v, meso_mesh* out, meso_error* err)
{
    memset(out, 0, sizeof(*out));
    const uint32_t nv = v->layout.vertex_count, ni = v->layout.index_count;
    out->vertex_count = nv;
    out->triangle_count = ni / 3u;
    out->positions = malloc((size_t)nv * 12u);
    out->indices = malloc((size_t)(ni ? ni : 1) * 4u);
    if (v->normals)
        out->normals = malloc((size_t)nv * 12u);
    if (v->uvs)
        out->uvs = malloc((size_t)nv * 8u);
    if (!out->positions || !out->indices || (v->normals && !out->normals) || (v->uvs && !out->uvs)) {
        meso_mesh_free(out);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "mesh copy: out of memory");
    }
    memcpy(out->positions, v->positions, (size_t)nv * 12u);
    if (ni)
        memcpy(out->indices, v->indices, (size_t)ni * 4u);
    if (v->normals)
        memcpy(out->normals, v->normals, (size_t)nv * 12u);
    if (v->uvs)
        memcpy(out->uvs, v->uvs, (size_t)nv * 8u);
    return MESO_OK;
}
