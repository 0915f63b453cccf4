/* sample.c — see sample.h. */
#undef NDEBUG
#include "sample.h"

#include "meso_layout.h"

#include <assert.h>
#include <stdlib.h>
#include <string.h>

uint32_t get32(const uint8_t* p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
uint64_t get64(const uint8_t* p) { return (uint64_t)get32(p) | (uint64_t)get32(p + 4) << 32; }
void put16(uint8_t* p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}
void put32(uint8_t* p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (uint8_t)(v >> (8 * i));
}
void put64(uint8_t* p, uint64_t v)
{
    put32(p, (uint32_t)v);
    put32(p + 4, (uint32_t)(v >> 32));
}
static void putf(uint8_t* p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put32(p, u);
}

void fill_pattern(uint8_t* dst, size_t n, uint32_t seed)
{
    uint32_t x = seed * 2654435761u + 12345u;
    for (size_t i = 0; i < n; i++) {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        dst[i] = (uint8_t)(x >> 24);
    }
}

void fix_payload_crc(uint8_t* file, uint32_t index)
{
    uint8_t* e = file + MESO_HDR_SIZE + (size_t)index * MESO_TOC_ENTRY_SIZE;
    uint64_t off = get64(e + MESO_TOC_OFF_OFFSET), n = get64(e + MESO_TOC_OFF_STORED_SIZE);
    put32(e + MESO_TOC_OFF_CRC, meso_crc32c(0, file + off, (size_t)n));
}

void fix_crcs(uint8_t* file)
{
    uint32_t count = get32(file + MESO_HDR_OFF_CHUNK_COUNT), esize = get32(file + MESO_HDR_OFF_TOC_ENTRY_SIZE);
    put32(file + MESO_HDR_OFF_TOC_CRC, meso_crc32c(0, file + MESO_HDR_SIZE, (size_t)count * esize));
    put32(file + MESO_HDR_OFF_HEADER_CRC, 0);
    put32(file + MESO_HDR_OFF_HEADER_CRC, meso_crc32c(0, file, MESO_HDR_SIZE));
}

static int capture_first(void* user, const meso_error* issue)
{
    *(meso_error*)user = *issue;
    return 1; /* stop at the first issue */
}

meso_result open_and_validate(const uint8_t* data, size_t size, meso_error* err)
{
    meso_file* f = NULL;
    meso_result r = meso_file_open_memory(data, size, NULL, &f, err);
    if (r != MESO_OK) {
        assert(f == NULL);
        assert(err == NULL || (err->result == r && err->code != 0));
        return r;
    }
    meso_error first;
    memset(&first, 0, sizeof first);
    r = meso_file_validate(f, MESO_CHECK_FULL, capture_first, &first);
    if (r != MESO_OK && err)
        *err = first;
    assert(r == MESO_OK || (first.result == r && first.code != 0));
    meso_file_close(f);
    return r;
}

meso_result open_and_validate_copy(const uint8_t* data, size_t size, meso_error* err)
{
    uint8_t* copy = (uint8_t*)malloc(size ? size : 1);
    assert(copy);
    if (size)
        memcpy(copy, data, size);
    meso_result r = open_and_validate(copy, size, err);
    free(copy);
    return r;
}

/* >>fixtures */

enum { MAX_SAMPLE = 24 };
static sample_chunk chunks[MAX_SAMPLE];
static size_t nchunks;
static uint8_t* storage[MAX_SAMPLE];

static const uint8_t* keep(uint8_t* p)
{
    storage[nchunks] = p;
    return p;
}

static void add(uint32_t type, uint32_t object, uint16_t lod, uint16_t dtype, uint16_t comps, uint32_t d0, uint32_t d1,
                uint32_t d2, uint8_t* data, size_t size)
{
    assert(nchunks < MAX_SAMPLE);
    sample_chunk* c = &chunks[nchunks];
    memset(c, 0, sizeof *c);
    c->desc.type = type;
    c->desc.flags = (type == MESO_CHUNK_MESH || type == MESO_CHUNK_OBJT) ? MESO_CHUNK_FLAG_REQUIRED : 0;
    c->desc.object = object;
    c->desc.lod = lod;
    c->desc.dtype = dtype;
    c->desc.components = comps;
    c->desc.dims[0] = d0;
    c->desc.dims[1] = d1;
    c->desc.dims[2] = d2;
    c->data = keep(data);
    c->size = size;
    nchunks++;
}

static uint8_t* typed(uint32_t esize, uint32_t comps, uint32_t d0, uint32_t d1, uint32_t d2, uint32_t seed,
                      size_t* size)
{
    *size = (size_t)esize * comps * d0 * d1 * d2;
    uint8_t* p = (uint8_t*)malloc(*size);
    assert(p);
    fill_pattern(p, *size, seed);
    return p;
}

static uint8_t* floats(const float* v, size_t n)
{
    uint8_t* p = (uint8_t*)malloc(n * 4);
    assert(p);
    for (size_t i = 0; i < n; i++)
        putf(p + 4 * i, v[i]);
    return p;
}

static uint8_t* dup_str(const char* s)
{
    size_t n = strlen(s);
    uint8_t* p = (uint8_t*)malloc(n);
    assert(p);
    memcpy(p, s, n);
    return p;
}

static void build(void)
{
    if (nchunks)
        return;
    const char* meta = "{\"tool\":\"mesobake\",\"version\":\"0.1.0\",\"params\":{\"voxel_size\":0.01,\"thickness\":"
                       "[1e-3,2.5E+2]},\"source\":\"tetra.obj\",\"ok\":true,\"none\":null,\"text\":\"\\u00e9\\n\"}";
    add(MESO_CHUNK_META, 0, 0, MESO_DTYPE_BYTES, 1, 1, 1, 1, dup_str(meta), strlen(meta));

    /* Unit tetrahedron with normals and uvs. */
    meso_mesh_layout l;
    assert(meso_mesh_compute_layout(4, 12, MESO_MESH_ATTR_POSITIONS | MESO_MESH_ATTR_NORMALS | MESO_MESH_ATTR_UVS,
                                    &l) == MESO_OK);
    uint8_t* mesh = (uint8_t*)calloc(1, (size_t)l.size);
    assert(mesh);
    meso_mesh_write_header(&l, mesh);
    static const float pos[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    static const float nrm[12] = {-0.577f, -0.577f, -0.577f, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    static const float uv[8] = {0, 0, 1, 0, 0, 1, 1, 1};
    static const uint32_t idx[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    for (int i = 0; i < 12; i++) {
        putf(mesh + l.positions_offset + 4 * i, pos[i]);
        putf(mesh + l.normals_offset + 4 * i, nrm[i]);
        put32(mesh + l.indices_offset + 4 * i, idx[i]);
    }
    for (int i = 0; i < 8; i++)
        putf(mesh + l.uvs_offset + 4 * i, uv[i]);
    add(MESO_CHUNK_MESH, 1, 0, MESO_DTYPE_BYTES, 1, 1, 1, 1, mesh, (size_t)l.size);

    uint8_t* objt = (uint8_t*)calloc(2, 64);
    assert(objt);
    meso_object_record rec = {1, MESO_OBJECT_MESH, {0, 0, 0}, {1, 1, 1}, "tetra"};
    meso_object_record_encode(&rec, objt);
    /* Object 2 is a mesh (its own MESH is added last, so the chunk indices
     * of the rest stay put): its SDIR..RELF exercise every chunk type's
     * rules without making it a shell, whose texture function and values
     * the object checks (FORMAT.md 6xxx) would hold these patterns to. */
    meso_object_record rec2 = {2, MESO_OBJECT_MESH, {-0.1f, -0.1f, -0.1f}, {1.1f, 1.1f, 1.1f}, "tetra shell"};
    meso_object_record_encode(&rec2, objt + 64);
    add(MESO_CHUNK_OBJT, 0, 0, MESO_DTYPE_BYTES, 1, 2, 1, 1, objt, 128);

    const char* rprt = "{\"hausdorff\":0.001,\"warnings\":[],\"stages\":[{\"name\":\"voxelize\",\"ms\":12}]}";
    add(MESO_CHUNK_RPRT, 0, 0, MESO_DTYPE_BYTES, 1, 1, 1, 1, dup_str(rprt), strlen(rprt));

    size_t n;
    uint8_t* p;
    static const float sdir[12] = {-1, -1, -1, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    add(MESO_CHUNK_SDIR, 2, 0, MESO_DTYPE_F32, 3, 4, 1, 1, floats(sdir, 12), 48);
    static const float sthk[4] = {0.05f, 0.04f, 0.04f, 0.03f};
    add(MESO_CHUNK_STHK, 2, 0, MESO_DTYPE_F32, 1, 4, 1, 1, floats(sthk, 4), 16);
    /* Three mips, finest added first: the writer must put lod 2 first. */
    for (uint16_t lod = 0; lod < 3; lod++) {
        uint32_t s = 8u >> lod;
        p = typed(1, 4, s, s, 1, 100u + lod, &n);
        add(MESO_CHUNK_TX2D, 2, lod, MESO_DTYPE_U8, 4, s, s, 1, p, n);
    }
    p = typed(2, 1, 4, 4, 4, 7, &n);
    add(MESO_CHUNK_TX3D, 2, 0, MESO_DTYPE_F16, 1, 4, 4, 4, p, n);
    static float dist[64];
    for (int i = 0; i < 64; i++)
        dist[i] = (float)i * 0.125f - 2.0f;
    add(MESO_CHUNK_DIST, 2, 0, MESO_DTYPE_F32, 1, 4, 4, 4, floats(dist, 64), 256);
    p = typed(2, 1, 4, 4, 4, 9, &n);
    add(MESO_CHUNK_TILE, 3, 0, MESO_DTYPE_U16, 1, 4, 4, 4, p, n);
    p = typed(4, 6, 5, 1, 1, 10, &n);
    add(MESO_CHUNK_SPLT, 3, 0, MESO_DTYPE_U32, 6, 5, 1, 1, p, n);
    p = typed(4, 1, 3, 2, 1, 11, &n);
    add(MESO_CHUNK_MEMB, 3, 0, MESO_DTYPE_U32, 1, 3, 2, 1, p, n);
    p = typed(2, 2, 4, 4, 4, 12, &n);
    add(MESO_CHUNK_NRMM, 2, 1, MESO_DTYPE_U16, 2, 4, 4, 4, p, n);
    p = typed(1, 4, 4, 4, 4, 13, &n);
    add(MESO_CHUNK_COLR, 2, 1, MESO_DTYPE_U8, 4, 4, 4, 4, p, n);

    uint8_t* skel = (uint8_t*)calloc(3, 32);
    assert(skel);
    for (int i = 0; i < 3; i++) {
        putf(skel + 32 * i + 0, 0.1f * (float)i);
        putf(skel + 32 * i + 4, 0.2f);
        putf(skel + 32 * i + 8, 0.3f);
        putf(skel + 32 * i + 12, 0.05f);
        put32(skel + 32 * i + 16, (uint32_t)(i - 1)); /* -1, 0, 1 */
        put32(skel + 32 * i + 20, i == 2 ? 2u : 1u);
    }
    add(MESO_CHUNK_SKEL, 4, 0, MESO_DTYPE_BYTES, 1, 3, 1, 1, skel, 96);

    uint8_t* frus = (uint8_t*)calloc(2, 64);
    assert(frus);
    for (int i = 0; i < 2; i++) {
        uint8_t* r = frus + 64 * i;
        putf(r + 0, 0.1f * (float)i);
        putf(r + 12, 0.05f);
        putf(r + 16, 0.1f * (float)(i + 1));
        putf(r + 28, 0.04f);
        putf(r + 32, 1.0f);
        putf(r + 44, -1.0f);
        put32(r + 56, (uint32_t)i);
    }
    add(MESO_CHUNK_FRUS, 4, 0, MESO_DTYPE_BYTES, 1, 2, 1, 1, frus, 128);
    p = typed(2, 4, 8, 8, 1, 14, &n);
    add(MESO_CHUNK_RELF, 2, 0, MESO_DTYPE_F16, 4, 8, 8, 1, p, n);
    uint8_t* mesh2 = (uint8_t*)malloc((size_t)l.size);
    assert(mesh2);
    memcpy(mesh2, mesh, (size_t)l.size);
    add(MESO_CHUNK_MESH, 2, 0, MESO_DTYPE_BYTES, 1, 1, 1, 1, mesh2, (size_t)l.size);
}

size_t sample_chunks(const sample_chunk** out)
{
    build();
    *out = chunks;
    return nchunks;
}

void sample_add_all(meso_writer* w)
{
    const sample_chunk* c;
    size_t n = sample_chunks(&c);
    for (size_t i = 0; i < n; i++) {
        meso_error e;
        meso_result r = meso_writer_add(w, &c[i].desc, c[i].data, c[i].size, &e);
        assert(r == MESO_OK);
    }
}

uint8_t* writer_to_memory(meso_writer* w, size_t* size)
{
    size_t need = 0;
    assert(meso_writer_finish(w, NULL, 0, &need) == MESO_OK);
    uint8_t* buf = (uint8_t*)malloc(need);
    assert(buf);
    assert(meso_writer_finish(w, buf, need, size) == MESO_OK);
    assert(*size == need);
    return buf;
}

uint8_t* sample_file(size_t* size)
{
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    sample_add_all(w);
    uint8_t* buf = writer_to_memory(w, size);
    meso_writer_destroy(w);
    return buf;
}

uint8_t* sample_small_file(size_t* size)
{
    const sample_chunk* c;
    size_t n = sample_chunks(&c);
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    for (size_t i = 0; i < n; i++) {
        uint32_t t = c[i].desc.type;
        if (t == MESO_CHUNK_META || t == MESO_CHUNK_OBJT || t == MESO_CHUNK_MESH || t == MESO_CHUNK_STHK)
            assert(meso_writer_add(w, &c[i].desc, c[i].data, c[i].size, NULL) == MESO_OK);
    }
    uint8_t* buf = writer_to_memory(w, size);
    meso_writer_destroy(w);
    return buf;
}

/* A fan of `tris` triangles around the origin, with normals. */
uint8_t* sample_fan_mesh(uint32_t tris, size_t* size)
{
    meso_mesh_layout l;
    const uint32_t verts = tris + 2;
    assert(meso_mesh_compute_layout(verts, 3 * tris, MESO_MESH_ATTR_POSITIONS | MESO_MESH_ATTR_NORMALS, &l) ==
           MESO_OK);
    uint8_t* m = (uint8_t*)calloc(1, (size_t)l.size);
    assert(m);
    meso_mesh_write_header(&l, m);
    float* p = (float*)(m + l.positions_offset);
    float* n = (float*)(m + l.normals_offset);
    for (uint32_t v = 0; v < verts; v++) {
        p[3 * v + 0] = v == 0 ? 0.0f : (float)(v - 1) / (float)tris;
        p[3 * v + 1] = v == 0 ? 0.0f : 1.0f;
        n[3 * v + 2] = 1.0f;
    }
    uint32_t* ix = (uint32_t*)(m + l.indices_offset);
    for (uint32_t t = 0; t < tris; t++) {
        ix[3 * t + 0] = 0;
        ix[3 * t + 1] = t + 1;
        ix[3 * t + 2] = t + 2;
    }
    *size = (size_t)l.size;
    return m;
}
