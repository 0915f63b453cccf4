/*
 * make_corpus.c — writes the seed corpus of fuzz_meso_file into a directory:
 *
 *   ./build/tests/fuzz/make_corpus tests/fuzz/corpus/meso_file
 *
 * Built by default, never run by the tests: the corpus is checked in (keep it
 * under 1 MB; libFuzzer works best on small seeds). Valid files come from the
 * writer (every chunk kind, raw and Draco MESH from tests/data/sphere.obj
 * through the bake library); files the writer cannot produce (newer minor,
 * larger TOC entries, unknown types/encodings/dtypes) are laid out by hand
 * here, and a few damaged variants seed the error paths. Deterministic.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake_bytes.h"
#include "frusta_chunks.h"
#include "frustum_model.h"
#include "meso_file.h"
#include "meso_layout.h"
#include "mesh_chunk.h"
#include "skeleton_swc.h"
#include "test_util.h"

static const char* out_dir;

/* >>bytes ----------------------------------------------------------------- */

static void st16(uint8_t* p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}
static void st32(uint8_t* p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (uint8_t)(v >> (8 * i));
}
static void st64(uint8_t* p, uint64_t v)
{
    st32(p, (uint32_t)v);
    st32(p + 4, (uint32_t)(v >> 32));
}
static void stf(uint8_t* p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    st32(p, u);
}
static uint32_t ld32(const uint8_t* p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static uint64_t ld64(const uint8_t* p) { return (uint64_t)ld32(p) | ((uint64_t)ld32(p + 4) << 32); }
static uint64_t align64(uint64_t v) { return (v + 63u) & ~(uint64_t)63u; }

static void fill(uint8_t* p, size_t n, uint32_t seed)
{
    uint64_t s = 0x9E3779B97F4A7C15ull ^ seed;
    for (size_t i = 0; i < n; i++)
        p[i] = (uint8_t)(test_rng_next(&s) >> 56);
}

/* Recompute payload CRCs of 64-byte-entry files, then TOC and header CRCs. */
static void fix_crcs(uint8_t* d)
{
    uint32_t count = ld32(d + MESO_HDR_OFF_CHUNK_COUNT), esize = ld32(d + MESO_HDR_OFF_TOC_ENTRY_SIZE);
    for (uint32_t i = 0; i < count; i++) {
        uint8_t* e = d + MESO_HDR_SIZE + (size_t)i * esize;
        st32(e + MESO_TOC_OFF_CRC,
             meso_crc32c(0, d + ld64(e + MESO_TOC_OFF_OFFSET), (size_t)ld64(e + MESO_TOC_OFF_STORED_SIZE)));
    }
    st32(d + MESO_HDR_OFF_TOC_CRC, meso_crc32c(0, d + MESO_HDR_SIZE, (size_t)count * esize));
    st32(d + MESO_HDR_OFF_HEADER_CRC, 0);
    st32(d + MESO_HDR_OFF_HEADER_CRC, meso_crc32c(0, d, MESO_HDR_SIZE));
}

static void save(const char* name, const uint8_t* d, size_t n)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", out_dir, name);
    FILE* fp = fopen(path, "wb");
    assert(fp);
    assert(n == 0 || fwrite(d, 1, n, fp) == n);
    assert(fclose(fp) == 0);
    printf("%-32s %7zu bytes\n", name, n);
}

/* >>writer helpers -------------------------------------------------------- */

static void add(meso_writer* w, uint32_t type, uint32_t flags, uint32_t object, uint16_t lod, uint16_t encoding,
                uint64_t decoded, uint16_t dtype, uint16_t comps, uint32_t d0, uint32_t d1, uint32_t d2,
                const void* data, size_t size)
{
    meso_chunk_desc c;
    memset(&c, 0, sizeof c);
    c.type = type;
    c.flags = flags;
    c.object = object;
    c.lod = lod;
    c.encoding = encoding;
    c.decoded_size = decoded;
    c.dtype = dtype;
    c.components = comps;
    c.dims[0] = d0;
    c.dims[1] = d1;
    c.dims[2] = d2;
    meso_error err;
    if (meso_writer_add(w, &c, data, size, &err) != MESO_OK) {
        fprintf(stderr, "make_corpus: writer refused a chunk: %s\n", err.message);
        exit(1);
    }
}

static void add_typed(meso_writer* w, uint32_t type, uint32_t object, uint16_t lod, uint16_t dtype, uint16_t comps,
                      uint32_t d0, uint32_t d1, uint32_t d2, uint32_t seed)
{
    size_t n = (size_t)meso_dtype_size((meso_dtype)dtype) * comps * d0 * d1 * d2;
    uint8_t* p = malloc(n);
    assert(p);
    fill(p, n, seed);
    if (dtype == MESO_DTYPE_F32 || dtype == MESO_DTYPE_F16) /* keep floats finite: small values */
        for (size_t i = 0; i < n; i += meso_dtype_size((meso_dtype)dtype))
            p[i + meso_dtype_size((meso_dtype)dtype) - 1] &= 0x3F;
    add(w, type, 0, object, lod, MESO_ENCODING_RAW, 0, dtype, comps, d0, d1, d2, p, n);
    free(p);
}

static uint8_t* finish(meso_writer* w, size_t* n)
{
    assert(meso_writer_finish(w, NULL, 0, n) == MESO_OK);
    uint8_t* d = malloc(*n);
    assert(d);
    size_t again = 0;
    assert(meso_writer_finish(w, d, *n, &again) == MESO_OK && again == *n);
    meso_writer_destroy(w);
    return d;
}

static void add_json(meso_writer* w, uint32_t type, const char* s)
{
    add(w, type, 0, 0, 0, MESO_ENCODING_RAW, 0, MESO_DTYPE_BYTES, 1, 1, 1, 1, s, strlen(s));
}

static void add_objt(meso_writer* w, uint32_t count)
{
    uint8_t recs[3 * MESO_OBJT_RECORD_SIZE];
    static const char* names[3] = {"mesh", "shell", "cells"};
    assert(count <= 3);
    for (uint32_t i = 0; i < count; i++) {
        meso_object_record r;
        memset(&r, 0, sizeof r);
        r.id = i + 1;
        r.kind = i + 1;
        for (int k = 0; k < 3; k++) {
            r.bbox_min[k] = -1.0f;
            r.bbox_max[k] = 1.0f;
        }
        snprintf(r.name, sizeof r.name, "%s", names[i]);
        meso_object_record_encode(&r, recs + i * MESO_OBJT_RECORD_SIZE);
    }
    add(w, MESO_CHUNK_OBJT, MESO_CHUNK_FLAG_REQUIRED, 0, 0, MESO_ENCODING_RAW, 0, MESO_DTYPE_BYTES, 1, count, 1, 1,
        recs, (size_t)count * MESO_OBJT_RECORD_SIZE);
}

static void add_mesh(meso_writer* w, const meso_mesh* m, uint32_t object, const meso_draco_options* draco)
{
    meso_mesh_chunk mc;
    meso_error err;
    if (meso_bake_mesh_chunk(m, draco, &mc, &err) != MESO_OK) {
        fprintf(stderr, "make_corpus: %s\n", err.message);
        exit(1);
    }
    add(w, MESO_CHUNK_MESH, MESO_CHUNK_FLAG_REQUIRED, object, 0, mc.encoding, mc.decoded_size, MESO_DTYPE_BYTES, 1, 1,
        1, 1, mc.data, mc.size);
    free(mc.data);
}

/* >>meshes ---------------------------------------------------------------- */

static float tetra_pos[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
static float tetra_nrm[12] = {-0.577f, -0.577f, -0.577f, 1, 0, 0, 0, 1, 0, 0, 0, 1};
static float tetra_uv[8] = {0, 0, 1, 0, 0, 1, 1, 1};
static uint32_t tetra_idx[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};

static meso_mesh tetra(int normals, int uvs)
{
    meso_mesh m = {4, 4, tetra_pos, normals ? tetra_nrm : NULL, uvs ? tetra_uv : NULL, tetra_idx, NULL};
    return m;
}

/* >>hand-made layouts ----------------------------------------------------- */

typedef struct raw_chunk {
    meso_chunk_info info; /* offset and crc are filled in */
    const void* data;
} raw_chunk;

/* Lay out chunks with any entry size / minor / values the writer refuses. */
static uint8_t* layout(raw_chunk* c, uint32_t n, uint16_t minor, uint32_t esize, size_t* size)
{
    uint64_t off = align64(MESO_HDR_SIZE + (uint64_t)n * esize);
    for (uint32_t i = 0; i < n; i++) {
        c[i].info.offset = off;
        c[i].info.crc32c = meso_crc32c(0, c[i].data, (size_t)c[i].info.stored_size);
        off = align64(off + c[i].info.stored_size);
    }
    *size = (size_t)off;
    uint8_t* d = calloc(1, *size);
    assert(d);
    static const uint8_t magic[8] = {0x89, 'M', 'S', 'O', '\r', '\n', 0x1A, '\n'};
    memcpy(d, magic, 8);
    st16(d + MESO_HDR_OFF_MAJOR, 1);
    st16(d + MESO_HDR_OFF_MINOR, minor);
    st64(d + MESO_HDR_OFF_FILE_SIZE, off);
    st64(d + MESO_HDR_OFF_TOC_OFFSET, MESO_HDR_SIZE);
    st32(d + MESO_HDR_OFF_CHUNK_COUNT, n);
    st32(d + MESO_HDR_OFF_TOC_ENTRY_SIZE, esize);
    for (uint32_t i = 0; i < n; i++) {
        const meso_chunk_info* ci = &c[i].info;
        uint8_t* e = d + MESO_HDR_SIZE + (size_t)i * esize;
        st32(e + MESO_TOC_OFF_TYPE, ci->type);
        st32(e + MESO_TOC_OFF_FLAGS, ci->flags);
        st32(e + MESO_TOC_OFF_OBJECT, ci->object);
        st16(e + MESO_TOC_OFF_LOD, ci->lod);
        st16(e + MESO_TOC_OFF_ENCODING, ci->encoding);
        st64(e + MESO_TOC_OFF_OFFSET, ci->offset);
        st64(e + MESO_TOC_OFF_STORED_SIZE, ci->stored_size);
        st64(e + MESO_TOC_OFF_DECODED_SIZE, ci->decoded_size);
        st32(e + MESO_TOC_OFF_CRC, ci->crc32c);
        st16(e + MESO_TOC_OFF_DTYPE, ci->dtype);
        st16(e + MESO_TOC_OFF_COMPONENTS, ci->components);
        for (int k = 0; k < 3; k++)
            st32(e + MESO_TOC_OFF_DIMS + 4 * k, ci->dims[k]);
        memcpy(d + ci->offset, c[i].data, (size_t)ci->stored_size);
    }
    st32(d + MESO_HDR_OFF_TOC_CRC, meso_crc32c(0, d + MESO_HDR_SIZE, (size_t)n * esize));
    st32(d + MESO_HDR_OFF_HEADER_CRC, meso_crc32c(0, d, MESO_HDR_SIZE));
    return d;
}

static raw_chunk raw(uint32_t type, uint32_t flags, uint16_t encoding, uint16_t dtype, uint16_t comps, uint32_t d0,
                     const void* data, uint64_t stored, uint64_t decoded)
{
    raw_chunk c;
    memset(&c, 0, sizeof c);
    c.info.type = type;
    c.info.flags = flags;
    c.info.encoding = encoding;
    c.info.dtype = dtype;
    c.info.components = comps;
    c.info.dims[0] = d0;
    c.info.dims[1] = 1;
    c.info.dims[2] = 1;
    c.info.stored_size = stored;
    c.info.decoded_size = decoded;
    c.data = data;
    return c;
}

/* Expect the reader's verdict on a corpus file (documents what each seeds). */
static void expect(const uint8_t* d, size_t n, meso_result want_open, meso_result want_valid)
{
    meso_decoder dec = meso_bake_draco_decoder();
    meso_open_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.decoders = &dec;
    desc.decoder_count = 1;
    meso_file* f = NULL;
    meso_error err;
    meso_result r = meso_file_open_memory(d, n, &desc, &f, &err);
    if (r != want_open) {
        fprintf(stderr, "make_corpus: open gave %s (%s), expected %s\n", meso_result_string(r), err.message,
                meso_result_string(want_open));
        exit(1);
    }
    if (r == MESO_OK) {
        r = meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL);
        meso_file_close(f);
        if (r != want_valid) {
            fprintf(stderr, "make_corpus: validate gave %s, expected %s\n", meso_result_string(r),
                    meso_result_string(want_valid));
            exit(1);
        }
    }
}

static void save_expect(const char* name, const uint8_t* d, size_t n, meso_result want_open, meso_result want_valid)
{
    expect(d, n, want_open, want_valid);
    save(name, d, n);
}

/* >>corpus ---------------------------------------------------------------- */

static void every_kind(void)
{
    meso_writer* w;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    add_json(w, MESO_CHUNK_META, "{\"tool\":\"mesobake\",\"version\":\"0.1.0\",\"p\":[1e-3,-2.5E+2,true,false,null],"
                                 "\"s\":\"\\u00e9\\n\\\"\"}");
    add_objt(w, 3);
    add_json(w, MESO_CHUNK_RPRT, "{\"hausdorff\":0.001,\"warnings\":[],\"stages\":[{\"ms\":12}]}");
    meso_mesh t = tetra(1, 1);
    add_mesh(w, &t, 1, NULL);
    static const float sdir[12] = {-1, -1, -1, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    add(w, MESO_CHUNK_SDIR, 0, 2, 0, 0, 0, MESO_DTYPE_F32, 3, 4, 1, 1, sdir, sizeof sdir);
    static const float sthk[4] = {0.05f, 0.04f, 0.04f, 0.03f};
    add(w, MESO_CHUNK_STHK, 0, 2, 0, 0, 0, MESO_DTYPE_F32, 1, 4, 1, 1, sthk, sizeof sthk);
    for (uint16_t lod = 0; lod < 3; lod++)
        add_typed(w, MESO_CHUNK_TX2D, 2, lod, MESO_DTYPE_U8, 4, 4u >> lod, 4u >> lod, 1, 10u + lod);
    add_typed(w, MESO_CHUNK_TX3D, 2, 0, MESO_DTYPE_F16, 1, 2, 2, 2, 20);
    add_typed(w, MESO_CHUNK_DIST, 2, 0, MESO_DTYPE_F32, 1, 2, 2, 2, 21);
    add_typed(w, MESO_CHUNK_TILE, 3, 0, MESO_DTYPE_U16, 1, 2, 2, 2, 22);
    add_typed(w, MESO_CHUNK_SPLT, 3, 0, MESO_DTYPE_U8, 6, 3, 1, 1, 23);
    add_typed(w, MESO_CHUNK_MEMB, 3, 0, MESO_DTYPE_U32, 1, 2, 2, 1, 24);
    add_typed(w, MESO_CHUNK_NRMM, 2, 1, MESO_DTYPE_U16, 2, 2, 2, 2, 25);
    add_typed(w, MESO_CHUNK_COLR, 2, 1, MESO_DTYPE_U8, 4, 2, 2, 2, 26);
    add_typed(w, MESO_CHUNK_RELF, 2, 0, MESO_DTYPE_F32, 4, 2, 2, 1, 27);
    uint8_t skel[3 * MESO_SKEL_RECORD_SIZE];
    memset(skel, 0, sizeof skel);
    for (int i = 0; i < 3; i++) {
        uint8_t* r = skel + i * MESO_SKEL_RECORD_SIZE;
        stf(r + MESO_SKEL_OFF_POSITION, 0.1f * (float)i);
        stf(r + MESO_SKEL_OFF_RADIUS, 0.05f);
        st32(r + MESO_SKEL_OFF_PARENT, (uint32_t)(i - 1));
        st32(r + MESO_SKEL_OFF_NODE_TYPE, i == 2 ? 2u : 1u);
    }
    add(w, MESO_CHUNK_SKEL, 0, 3, 0, 0, 0, MESO_DTYPE_BYTES, 1, 3, 1, 1, skel, sizeof skel);
    uint8_t frus[2 * MESO_FRUS_RECORD_SIZE];
    memset(frus, 0, sizeof frus);
    for (int i = 0; i < 2; i++) {
        uint8_t* r = frus + i * MESO_FRUS_RECORD_SIZE;
        stf(r + MESO_FRUS_OFF_RADIUS0, 0.05f);
        stf(r + MESO_FRUS_OFF_CENTER1 + 8, 1.0f);
        stf(r + MESO_FRUS_OFF_RADIUS1, 0.04f);
        stf(r + MESO_FRUS_OFF_PLANE0 + 8, -1.0f);
        stf(r + MESO_FRUS_OFF_PLANE1 + 8, 1.0f);
        st32(r + MESO_FRUS_OFF_SKEL_NODE, i ? 0xFFFFFFFFu : 1u);
    }
    add(w, MESO_CHUNK_FRUS, 0, 3, 0, 0, 0, MESO_DTYPE_BYTES, 1, 2, 1, 1, frus, sizeof frus);
    size_t n;
    uint8_t* d = finish(w, &n);
    /* Every chunk kind in one file, not a whole object of each kind: it
     * seeds the chunk readers, and the full check's object rules (FORMAT.md
     * §9, 6xxx: a shell without its MESH, ...) refuse it. */
    save_expect("every_kind.meso", d, n, MESO_OK, MESO_ERR_CORRUPT);

    /* Damaged variants of the same file, each seeding one error path. */
    uint8_t* v = malloc(n);
    assert(v);
    memcpy(v, d, n);
    v[n - 70] ^= 0x40; /* inside the last payload: CRC mismatch */
    save_expect("bad_payload_crc.meso", v, n, MESO_OK, MESO_ERR_CORRUPT);
    memcpy(v, d, n);
    v[4] = '\n'; /* CR/LF damage */
    save_expect("text_mode_magic.meso", v, 64, MESO_ERR_BAD_MAGIC, MESO_OK);
    memcpy(v, d, n);
    save_expect("truncated.meso", v, n - 64, MESO_ERR_TRUNCATED, MESO_OK);
    memcpy(v, d, n);
    st16(v + MESO_HDR_OFF_MAJOR, 2);
    fix_crcs(v);
    save_expect("major_2.meso", v, 64, MESO_ERR_VERSION_TOO_NEW, MESO_OK);
    free(v);
    free(d);
}

static void header_only(void)
{
    meso_writer* w;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    size_t n;
    uint8_t* d = finish(w, &n);
    save_expect("zero_chunks.meso", d, n, MESO_OK, MESO_OK);
    free(d);
    save_expect("empty_input.bin", (const uint8_t*)"", 0, MESO_ERR_TRUNCATED, MESO_OK);
}

static void meshes(void)
{
    meso_draco_options dopt = {14, 10, 12, 7};
    /* Small Draco tetra: the cheapest way into the Draco decoder. */
    meso_writer* w;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    meso_mesh t = tetra(1, 1);
    add_mesh(w, &t, 1, &dopt);
    meso_mesh p = tetra(0, 0);
    add_mesh(w, &p, 2, &dopt);
    size_t n;
    uint8_t* d = finish(w, &n);
    save_expect("tetra_draco.meso", d, n, MESO_OK, MESO_OK);
    free(d);

    /* A raw mesh with an index out of range (CRC fixed): content check. */
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    add_mesh(w, &p, 0, NULL);
    d = finish(w, &n);
    meso_mesh_layout l;
    assert(meso_mesh_compute_layout(4, 12, MESO_MESH_ATTR_POSITIONS, &l) == MESO_OK);
    size_t first = (size_t)align64(MESO_HDR_SIZE + MESO_TOC_ENTRY_SIZE);
    st32(d + first + l.indices_offset + 8, 4);
    fix_crcs(d);
    save_expect("mesh_bad_index.meso", d, n, MESO_OK, MESO_ERR_CORRUPT);
    free(d);

    /* sphere.obj through the bake library: raw and Draco, with an OBJT. */
    meso_mesh s;
    meso_error err;
    if (meso_openmesh_read(test_data("sphere.obj"), &s, NULL, &err) != MESO_OK) {
        fprintf(stderr, "make_corpus: %s\n", err.message);
        exit(1);
    }
    for (int draco = 0; draco < 2; draco++) {
        assert(meso_writer_create(NULL, &w) == MESO_OK);
        add_json(w, MESO_CHUNK_META, "{\"source\":\"sphere.obj\"}");
        add_objt(w, 1);
        add_mesh(w, &s, 1, draco ? &dopt : NULL);
        d = finish(w, &n);
        save_expect(draco ? "sphere_draco.meso" : "sphere_raw.meso", d, n, MESO_OK, MESO_OK);
        free(d);
    }
    meso_mesh_free(&s);
}

static void hand_made(void)
{
    static const char meta[] = "{\"minor\":1}";
    uint8_t blob[80];
    fill(blob, sizeof blob, 7);
    size_t n;
    uint8_t* d;

    /* A newer minor than this reader's, with 72-byte TOC entries, an
     * unknown optional chunk type, an unknown encoding and an unknown dtype:
     * readable, those chunks not. */
    raw_chunk c[4] = {
        raw(MESO_CHUNK_META, 0, MESO_ENCODING_RAW, MESO_DTYPE_BYTES, 1, 1, meta, sizeof meta - 1, sizeof meta - 1),
        raw(MESO_FOURCC('X', 'T', 'R', 'A'), 0, MESO_ENCODING_RAW, MESO_DTYPE_U8, 1, 80, blob, 80, 80),
        raw(MESO_FOURCC('Z', 'S', 'T', 'D'), 0, 7, MESO_DTYPE_BYTES, 1, 1, blob, 40, 4096),
        raw(MESO_FOURCC('H', 'A', 'L', 'F'), 0, MESO_ENCODING_RAW, 12, 1, 1, blob, 16, 16),
    };
    d = layout(c, 4, MESO_FORMAT_MINOR + 1, 72, &n);
    save_expect("newer_minor_72b_entries.meso", d, n, MESO_OK, MESO_OK);
    free(d);

    /* The same unknown encoding in a 1.0 file is corrupt. */
    d = layout(c, 3, 0, 64, &n);
    save_expect("v1_0_unknown_encoding.meso", d, n, MESO_ERR_CORRUPT, MESO_OK);
    free(d);

    /* Unknown type marked REQUIRED: refused. */
    raw_chunk r[1] = {raw(MESO_FOURCC('N', 'E', 'W', '!'), MESO_CHUNK_FLAG_REQUIRED, MESO_ENCODING_RAW,
                          MESO_DTYPE_BYTES, 1, 1, blob, 8, 8)};
    d = layout(r, 1, 1, 64, &n);
    save_expect("unknown_required.meso", d, n, MESO_ERR_UNSUPPORTED, MESO_OK);
    free(d);

    /* Non-zero padding after a payload (CRCs fine): full tier only. */
    raw_chunk p[1] = {raw(MESO_CHUNK_META, 0, MESO_ENCODING_RAW, MESO_DTYPE_BYTES, 1, 1, meta, sizeof meta - 1,
                          sizeof meta - 1)};
    d = layout(p, 1, 0, 64, &n);
    d[n - 1] = 1;
    save_expect("nonzero_padding.meso", d, n, MESO_OK, MESO_ERR_CORRUPT);
    free(d);

    /* Bad JSON and a bad OBJT record (CRCs fine). */
    static const char bad_json[] = "{\"a\":[1,2,}";
    raw_chunk j[1] = {raw(MESO_CHUNK_META, 0, MESO_ENCODING_RAW, MESO_DTYPE_BYTES, 1, 1, bad_json,
                          sizeof bad_json - 1, sizeof bad_json - 1)};
    d = layout(j, 1, 0, 64, &n);
    save_expect("bad_json.meso", d, n, MESO_OK, MESO_ERR_CORRUPT);
    free(d);
    uint8_t objt[128];
    meso_object_record rec = {2, MESO_OBJECT_MESH, {0, 0, 0}, {1, 1, 1}, "b"};
    meso_object_record_encode(&rec, objt);
    rec.id = 1; /* not ascending */
    meso_object_record_encode(&rec, objt + 64);
    raw_chunk o[1] = {raw(MESO_CHUNK_OBJT, 0, MESO_ENCODING_RAW, MESO_DTYPE_BYTES, 1, 2, objt, 128, 128)};
    d = layout(o, 1, 0, 64, &n);
    save_expect("objt_unsorted.meso", d, n, MESO_OK, MESO_ERR_CORRUPT);
    free(d);
}

/* A frusta object (kind 4) as mesobake writes it: a bent, branching
 * skeleton with a ball, plus a variant whose FSEG names a joint partner at
 * a tip (CRC fixed, so only the record check finds it). */
static void frusta(void)
{
    static const char text[] = "0 0 0 0.3\n0 2 0 0.3\n1 3 0 0.2\n2 3.5 0 0.1\n-1 3 0 0.2 2\n";
    meso_skeleton sk;
    meso_frustum_model m;
    meso_frusta_object o;
    meso_error e;
    assert(meso_skeleton_parse(text, sizeof text - 1, MESO_SKELETON_TEXT, &sk, &e) == MESO_OK);
    assert(meso_frustum_model_build(&sk, NULL, &m, &e) == MESO_OK);
    meso_frusta_relief_params rp = {.depth = 0.05, .u_repeat = 3};
    assert(meso_frusta_object_build(&sk, &m, &rp, &o, &e) == MESO_OK);
    uint8_t *frus, *fseg, *ball;
    assert(meso_frusta_object_encode(&o, &frus, &fseg, &ball, &e) == MESO_OK);
    meso_writer* w;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    meso_object_record r = {.id = 1, .kind = MESO_OBJECT_FRUSTA};
    memcpy(r.bbox_min, o.bbox_min, sizeof r.bbox_min);
    memcpy(r.bbox_max, o.bbox_max, sizeof r.bbox_max);
    snprintf(r.name, sizeof r.name, "frusta");
    uint8_t objt[MESO_OBJT_RECORD_SIZE];
    meso_object_record_encode(&r, objt);
    add(w, MESO_CHUNK_OBJT, MESO_CHUNK_FLAG_REQUIRED, 0, 0, MESO_ENCODING_RAW, 0, MESO_DTYPE_BYTES, 1, 1, 1, 1, objt,
        sizeof objt);
    add(w, MESO_CHUNK_SKEL, 0, 1, 0, MESO_ENCODING_RAW, 0, MESO_DTYPE_BYTES, 1, o.node_count, 1, 1, o.skel,
        (size_t)o.node_count * MESO_SKEL_RECORD_SIZE);
    add(w, MESO_CHUNK_FRUS, MESO_CHUNK_FLAG_REQUIRED, 1, 0, MESO_ENCODING_RAW, 0, MESO_DTYPE_BYTES, 1, o.count, 1, 1,
        frus, (size_t)o.count * MESO_FRUS_RECORD_SIZE);
    add(w, MESO_CHUNK_FSEG, MESO_CHUNK_FLAG_REQUIRED, 1, 0, MESO_ENCODING_RAW, 0, MESO_DTYPE_BYTES, 1, o.count, 1, 1,
        fseg, (size_t)o.count * MESO_FSEG_RECORD_SIZE);
    add(w, MESO_CHUNK_BALL, MESO_CHUNK_FLAG_REQUIRED, 1, 0, MESO_ENCODING_RAW, 0, MESO_DTYPE_BYTES, 1, o.ball_count, 1,
        1, ball, (size_t)o.ball_count * MESO_BALL_RECORD_SIZE);
    add_typed(w, MESO_CHUNK_RELF, 1, 0, MESO_DTYPE_U8, 1, 8, 8, 1, 31);
    size_t n;
    uint8_t* d = finish(w, &n);
    save_expect("frusta.meso", d, n, MESO_OK, MESO_OK);
    /* The first FSEG record: a joint partner at its tip end (kind 0). */
    uint32_t count = ld32(d + MESO_HDR_OFF_CHUNK_COUNT);
    for (uint32_t i = 0; i < count; i++) {
        const uint8_t* en = d + MESO_HDR_SIZE + (size_t)i * MESO_TOC_ENTRY_SIZE;
        if (ld32(en) != MESO_CHUNK_FSEG)
            continue;
        uint8_t* rec = d + ld64(en + MESO_TOC_OFF_OFFSET);
        st32(rec + MESO_FSEG_OFF_FLAGS, ld32(rec + MESO_FSEG_OFF_FLAGS) & ~3u);
        st32(rec + MESO_FSEG_OFF_OTHER0, 1);
    }
    fix_crcs(d);
    save_expect("frusta_bad_fseg.meso", d, n, MESO_OK, MESO_ERR_CORRUPT);
    free(d);
    free(frus);
    free(fseg);
    free(ball);
    meso_frusta_object_free(&o);
    meso_frustum_model_free(&m);
    meso_skeleton_free(&sk);
}

/* A closed UV sphere of radius 1 in memory: `nu` around, `nv` bands (the
 * poles single vertices), normals = positions, counter-clockwise seen from
 * outside. Free with free() of positions, normals and indices. */
static meso_mesh uv_sphere(uint32_t nu, uint32_t nv)
{
    const uint32_t nvert = nu * (nv - 1) + 2, ntri = 2 * nu * (nv - 1);
    meso_mesh m = {nvert, ntri, malloc(sizeof(float) * 3 * nvert), malloc(sizeof(float) * 3 * nvert), NULL,
                   malloc(sizeof(uint32_t) * 3 * ntri), NULL};
    assert(m.positions && m.normals && m.indices);
    for (uint32_t j = 1; j < nv; ++j)
        for (uint32_t i = 0; i < nu; ++i) {
            const double th = M_PI * j / nv, ph = 2 * M_PI * i / nu;
            float* p = m.positions + 3 * (size_t)(1 + (j - 1) * nu + i);
            p[0] = (float)(sin(th) * cos(ph)), p[1] = (float)(sin(th) * sin(ph)), p[2] = (float)cos(th);
        }
    float* top = m.positions;
    float* bottom = m.positions + 3 * (size_t)(nvert - 1);
    top[0] = top[1] = bottom[0] = bottom[1] = 0.0f;
    top[2] = 1.0f, bottom[2] = -1.0f;
    memcpy(m.normals, m.positions, sizeof(float) * 3 * nvert);
    uint32_t* t = m.indices;
    for (uint32_t i = 0; i < nu; ++i) { /* the caps */
        const uint32_t a = 1 + i, b = 1 + (i + 1) % nu;
        *t++ = 0, *t++ = a, *t++ = b;
        const uint32_t c = 1 + (nv - 2) * nu + i, d = 1 + (nv - 2) * nu + (i + 1) % nu;
        *t++ = nvert - 1, *t++ = d, *t++ = c;
    }
    for (uint32_t j = 1; j + 1 < nv; ++j) /* the bands */
        for (uint32_t i = 0; i < nu; ++i) {
            const uint32_t a = 1 + (j - 1) * nu + i, b = 1 + (j - 1) * nu + (i + 1) % nu;
            const uint32_t c = a + nu, d = b + nu;
            *t++ = a, *t++ = c, *t++ = d;
            *t++ = a, *t++ = d, *t++ = b;
        }
    return m;
}

/* Levels and parts (FORMAT.md §7.10, §7.11): spheres of 360 and 224
 * triangles baked by the library as a mesh and as a shell (bricks:8), each with three
 * levels and cut into parts of about 64 triangles, so the LODS, PRTS,
 * PTRI, PMSH, PVCL and VCOL readers get seeds of their own (each under the
 * session's -max_len of 64 KB). */
static void levels(void)
{
    meso_mesh finer = uv_sphere(20, 10), sphere = uv_sphere(16, 8);
    meso_error err;
    meso_bake_mesh_options mo = meso_bake_mesh_defaults();
    mo.mesh = &finer; /* 360 triangles: a mesh under 256 gets no coarser level, hence no parts */
    mo.levels = 3;
    mo.parts = 64;
    meso_bake_output* out = NULL;
    if (meso_bake_mesh(&mo, &out, NULL, &err) != MESO_OK) {
        fprintf(stderr, "make_corpus: %s\n", err.message);
        exit(1);
    }
    size_t n;
    uint8_t* d = bake_bytes(out, &n);
    assert(n <= 65536);
    save_expect("sphere_levels_parts.meso", d, n, MESO_OK, MESO_OK);
    free(d);
    meso_bake_shell_options so = meso_bake_shell_defaults();
    so.mesh = &sphere;
    so.texture = "bricks:8";
    so.levels = 3;
    so.parts = 64;
    if (meso_bake_shell(&so, &out, NULL, &err) != MESO_OK) {
        fprintf(stderr, "make_corpus: %s\n", err.message);
        exit(1);
    }
    d = bake_bytes(out, &n);
    assert(n <= 65536);
    save_expect("sphere_shell_parts.meso", d, n, MESO_OK, MESO_OK);
    free(d);
    for (meso_mesh* m = &finer; m; m = m == &finer ? &sphere : NULL) {
        free(m->positions);
        free(m->normals);
        free(m->indices);
    }
}

int main(int argc, char** argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: make_corpus DIR (e.g. tests/fuzz/corpus/meso_file)\n");
        return 2;
    }
    out_dir = argv[1];
    header_only();
    every_kind();
    meshes();
    hand_made();
    frusta();
    levels();
    return 0;
}
