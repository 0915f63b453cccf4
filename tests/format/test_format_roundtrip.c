/* test_format_roundtrip.c — every chunk kind written and read back through
 * all four readers; ordering, determinism, Draco decoder hook, allocators. */
#undef NDEBUG
#include "meso_file.h"
#include "meso_layout.h"
#include "sample.h"

#include <assert.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char tmpdir[256];

static void make_tmpdir(void)
{
    const char* base = getenv("TMPDIR");
    snprintf(tmpdir, sizeof tmpdir, "%s/meso_rt_XXXXXX", base ? base : "/tmp");
    assert(mkdtemp(tmpdir) != NULL);
}

static void tmp_path(char* out, size_t n, const char* name) { snprintf(out, n, "%s/%s", tmpdir, name); }

static uint8_t* slurp(const char* path, size_t* size)
{
    FILE* fp = fopen(path, "rb");
    assert(fp);
    assert(fseek(fp, 0, SEEK_END) == 0);
    long n = ftell(fp);
    assert(n >= 0);
    rewind(fp);
    uint8_t* buf = (uint8_t*)malloc((size_t)n + 1);
    assert(buf);
    assert(fread(buf, 1, (size_t)n, fp) == (size_t)n);
    fclose(fp);
    *size = (size_t)n;
    return buf;
}

/* >>io callback over memory, counting reads */
typedef struct mem_io {
    const uint8_t* data;
    size_t size;
    int reads;
    uint64_t bytes;
} mem_io;

static int mem_read(void* user, uint64_t offset, void* dst, size_t size)
{
    mem_io* m = (mem_io*)user;
    if (offset > m->size || size > m->size - offset)
        return 1;
    memcpy(dst, m->data + offset, size);
    m->reads++;
    m->bytes += size;
    return 0;
}

enum { VIA_PATH, VIA_MMAP, VIA_MEMORY, VIA_IO, VIA_COUNT };

static meso_result open_via(int via, const char* path, const uint8_t* data, size_t size, mem_io* io_state,
                            const meso_open_desc* desc, meso_file** f, meso_error* err)
{
    switch (via) {
    case VIA_PATH: return meso_file_open_path(path, desc, f, err);
    case VIA_MMAP: return meso_file_open_mmap(path, desc, f, err);
    case VIA_MEMORY: return meso_file_open_memory(data, size, desc, f, err);
    default: {
        io_state->data = data;
        io_state->size = size;
        io_state->reads = 0;
        io_state->bytes = 0;
        meso_io io = {mem_read, size, io_state};
        return meso_file_open_io(&io, desc, f, err);
    }
    }
}

/* Every sample chunk is found and reads back byte-identical. */
static void check_contents(meso_file* f, int via)
{
    const sample_chunk* sc;
    size_t n = sample_chunks(&sc);
    assert(meso_file_chunk_count(f) == n);
    for (size_t i = 0; i < n; i++) {
        int32_t idx = meso_file_find(f, sc[i].desc.type, sc[i].desc.object, sc[i].desc.lod);
        assert(idx >= 0);
        const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)idx);
        assert(c && c->type == sc[i].desc.type && c->stored_size == sc[i].size && c->decoded_size == sc[i].size);
        assert(c->flags == sc[i].desc.flags && c->dtype == sc[i].desc.dtype);
        assert(c->offset % 64 == 0);
        uint8_t* buf = (uint8_t*)malloc(sc[i].size);
        meso_error e;
        assert(meso_file_read_chunk(f, (uint32_t)idx, buf, sc[i].size, &e) == MESO_OK);
        assert(memcmp(buf, sc[i].data, sc[i].size) == 0);
        memset(buf, 0, sc[i].size);
        assert(meso_file_read_stored(f, (uint32_t)idx, buf, sc[i].size, &e) == MESO_OK);
        assert(memcmp(buf, sc[i].data, sc[i].size) == 0);
        const void* view = NULL;
        meso_result vr = meso_file_chunk_view(f, (uint32_t)idx, &view, &e);
        if (via == VIA_MMAP || via == VIA_MEMORY) {
            assert(vr == MESO_OK && memcmp(view, sc[i].data, sc[i].size) == 0);
            assert(((uintptr_t)view & 63u) == 0 || via == VIA_MEMORY);
        } else {
            assert(vr == MESO_ERR_UNSUPPORTED && e.code == MESO_ISSUE_API_NO_VIEW);
        }
        free(buf);
    }
    assert(meso_file_validate(f, MESO_CHECK_CHEAP, NULL, NULL) == MESO_OK);
    assert(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);
}

static void every_chunk_kind_round_trips_through_all_four_readers(void)
{
    size_t size;
    uint8_t* mem = sample_file(&size);
    assert(size % 64 == 0);
    char path[512];
    tmp_path(path, sizeof path, "all.meso");
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    sample_add_all(w);
    meso_error e;
    assert(meso_writer_write_file(w, path, &e) == MESO_OK);
    meso_writer_destroy(w);
    size_t fsize;
    uint8_t* disk = slurp(path, &fsize);
    assert(fsize == size && memcmp(disk, mem, size) == 0);
    free(disk);
    for (int via = 0; via < VIA_COUNT; via++) {
        meso_file* f = NULL;
        mem_io io;
        assert(open_via(via, path, mem, size, &io, NULL, &f, &e) == MESO_OK);
        uint16_t major = 0, minor = 9;
        meso_file_version(f, &major, &minor);
        assert(major == 1 && minor == MESO_FORMAT_MINOR);
        assert(meso_file_size(f) == size);
        if (via == VIA_IO)
            assert(io.reads == 2); /* the header, then header + TOC (nothing past it: a stream prefix opens) */
        check_contents(f, via);
        meso_file_close(f);
    }
    remove(path);
    free(mem);
}

static void io_reader_fetches_only_the_requested_chunk(void)
{
    size_t size;
    uint8_t* mem = sample_file(&size);
    mem_io io;
    meso_file* f = NULL;
    assert(open_via(VIA_IO, NULL, mem, size, &io, NULL, &f, NULL) == MESO_OK);
    int32_t idx = meso_file_find(f, MESO_CHUNK_STHK, UINT32_MAX, UINT16_MAX);
    assert(idx >= 0);
    const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)idx);
    uint8_t buf[64];
    io.reads = 0;
    io.bytes = 0;
    assert(meso_file_read_chunk(f, (uint32_t)idx, buf, sizeof buf, NULL) == MESO_OK);
    assert(io.reads == 1 && io.bytes == c->stored_size);
    meso_file_close(f);
    free(mem);
}

/* >>large chunks: read and checksummed block by block */

static void write_bytes(const char* path, const uint8_t* data, size_t size)
{
    FILE* fp = fopen(path, "wb");
    assert(fp && fwrite(data, 1, size, fp) == size && fclose(fp) == 0);
}

/* A 3.125 MiB chunk spans four 1 MiB read blocks on path and io readers:
 * every reader returns the same bytes, the io reader fetches it in four
 * block reads (CRC'd as they arrive), and a flipped byte in any block,
 * including the short last one, is a payload CRC error on every reader. */
static void multi_block_chunks_read_once_and_verify_every_block(void)
{
    enum { W = 160, H = 128, D = 160 };
    const size_t n = (size_t)W * H * D;
    uint8_t* data = (uint8_t*)malloc(n);
    fill_pattern(data, n, 42);
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    meso_chunk_desc d;
    memset(&d, 0, sizeof d);
    d.type = MESO_CHUNK_TX3D;
    d.object = 1;
    d.dtype = MESO_DTYPE_U8;
    d.dims[0] = W, d.dims[1] = H, d.dims[2] = D;
    meso_error e;
    assert(meso_writer_add(w, &d, data, n, &e) == MESO_OK);
    size_t size;
    uint8_t* mem = writer_to_memory(w, &size);
    meso_writer_destroy(w);
    char path[512];
    tmp_path(path, sizeof path, "big.meso");
    const uint64_t off = get64(mem + 64 + MESO_TOC_OFF_OFFSET);
    uint8_t* buf = (uint8_t*)malloc(n);
    const size_t flips[] = {0, (size_t)5 << 19, n - 1}; /* first block, third block, last (short) block */
    for (int round = -1; round < 3; round++) {
        if (round >= 0)
            mem[off + flips[round]] ^= 0x40;
        write_bytes(path, mem, size);
        for (int via = 0; via < VIA_COUNT; via++) {
            meso_file* f = NULL;
            mem_io io;
            assert(open_via(via, path, mem, size, &io, NULL, &f, &e) == MESO_OK);
            io.reads = 0;
            memset(buf, 0, n);
            meso_result r = meso_file_read_chunk(f, 0, buf, n, &e);
            meso_result v = meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL);
            if (round < 0) {
                assert(r == MESO_OK && v == MESO_OK && memcmp(buf, data, n) == 0);
                if (via == VIA_IO)
                    assert(io.reads == 4 + 4); /* read_chunk, then validate: four blocks each */
            } else {
                assert(r == MESO_ERR_CORRUPT && e.code == MESO_ISSUE_PAYLOAD_CRC && v == MESO_ERR_CORRUPT);
                assert(meso_file_read_stored(f, 0, buf, n, &e) == MESO_ERR_CORRUPT);
            }
            meso_file_close(f);
        }
        if (round >= 0)
            mem[off + flips[round]] ^= 0x40;
    }
    remove(path);
    free(buf);
    free(mem);
    free(data);
}

static void header_fields_sit_at_layout_offsets(void)
{
    size_t size;
    uint8_t* mem = sample_file(&size);
    const sample_chunk* sc;
    size_t n = sample_chunks(&sc);
    static const uint8_t magic[8] = {0x89, 'M', 'S', 'O', '\r', '\n', 0x1A, '\n'};
    assert(memcmp(mem + MESO_HDR_OFF_MAGIC, magic, 8) == 0);
    assert(mem[MESO_HDR_OFF_MAJOR] == 1 && mem[MESO_HDR_OFF_MINOR] == MESO_FORMAT_MINOR);
    assert(get64(mem + MESO_HDR_OFF_FILE_SIZE) == size);
    assert(get64(mem + MESO_HDR_OFF_TOC_OFFSET) == 64);
    assert(get32(mem + MESO_HDR_OFF_CHUNK_COUNT) == n);
    assert(get32(mem + MESO_HDR_OFF_TOC_ENTRY_SIZE) == 64);
    assert(get32(mem + MESO_HDR_OFF_TOC_CRC) == meso_crc32c(0, mem + 64, n * 64));
    /* First payload right after the TOC. */
    assert(get64(mem + 64 + MESO_TOC_OFF_OFFSET) == 64 + n * 64);
    free(mem);
}

static void writer_orders_meta_objt_rprt_then_coarse_lod_first(void)
{
    size_t size;
    uint8_t* mem = sample_file(&size);
    meso_file* f = NULL;
    assert(meso_file_open_memory(mem, size, NULL, &f, NULL) == MESO_OK);
    uint32_t n = meso_file_chunk_count(f);
    assert(meso_file_chunk(f, 0)->type == MESO_CHUNK_META);
    assert(meso_file_chunk(f, 1)->type == MESO_CHUNK_OBJT);
    assert(meso_file_chunk(f, 2)->type == MESO_CHUNK_RPRT);
    int prev_lod = 65536;
    for (uint32_t i = 3; i < n; i++) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        assert(c->lod <= prev_lod);
        prev_lod = c->lod;
        assert(c->offset > meso_file_chunk(f, i - 1)->offset);
    }
    /* TX2D mips were added 0,1,2 and must appear 2,1,0. */
    int32_t l2 = meso_file_find(f, MESO_CHUNK_TX2D, 2, 2), l1 = meso_file_find(f, MESO_CHUNK_TX2D, 2, 1),
            l0 = meso_file_find(f, MESO_CHUNK_TX2D, 2, 0);
    assert(l2 >= 0 && l2 < l1 && l1 < l0);
    /* Same lod keeps insertion order: NRMM was added before COLR (both lod 1). */
    assert(meso_file_find(f, MESO_CHUNK_NRMM, UINT32_MAX, 1) < meso_file_find(f, MESO_CHUNK_COLR, UINT32_MAX, 1));
    /* First lod-0 chunk after all lod-1 and lod-2 chunks: a prefix holds the coarse levels. */
    assert(meso_file_find(f, MESO_CHUNK_MESH, 1, 0) > l1);
    assert(meso_file_find(f, 0x12345678u, UINT32_MAX, UINT16_MAX) == -1);
    meso_file_close(f);
    free(mem);
}

static void writer_is_deterministic(void)
{
    size_t a_size, b_size;
    uint8_t* a = sample_file(&a_size);
    uint8_t* b = sample_file(&b_size);
    assert(a_size == b_size && memcmp(a, b, a_size) == 0);
    free(a);
    free(b);
}

static void empty_writer_makes_a_valid_64_byte_file(void)
{
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    size_t size;
    uint8_t* mem = writer_to_memory(w, &size);
    assert(size == 64);
    assert(open_and_validate(mem, size, NULL) == MESO_OK);
    free(mem);
    meso_writer_destroy(w);
}

static void mesh_view_gives_the_tetrahedron(void)
{
    size_t size;
    uint8_t* mem = sample_file(&size);
    meso_file* f = NULL;
    assert(meso_file_open_memory(mem, size, NULL, &f, NULL) == MESO_OK);
    int32_t idx = meso_file_find(f, MESO_CHUNK_MESH, 1, 0);
    const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)idx);
    float* buf = (float*)malloc((size_t)c->decoded_size);
    assert(meso_file_read_chunk(f, (uint32_t)idx, buf, (size_t)c->decoded_size, NULL) == MESO_OK);
    meso_mesh_view v;
    meso_error e;
    assert(meso_mesh_parse(buf, (size_t)c->decoded_size, &v, &e) == MESO_OK);
    assert(v.layout.vertex_count == 4 && v.layout.index_count == 12);
    assert(v.positions[3] == 1.0f && v.positions[7] == 1.0f && v.positions[11] == 1.0f && v.positions[0] == 0.0f);
    assert(v.normals && v.uvs && v.uvs[6] == 1.0f && v.indices[1] == 2 && v.indices[11] == 3);
    assert(meso_mesh_parse((const uint8_t*)buf + 1, 64, &v, &e) == MESO_ERR_INVALID_ARG);
    /* Positions only, no indices: a point set is a valid mesh. */
    meso_mesh_layout l;
    assert(meso_mesh_compute_layout(3, 0, MESO_MESH_ATTR_POSITIONS, &l) == MESO_OK);
    assert(l.size == 64 + 36 && l.indices_offset == 0 && l.normals_offset == 0);
    assert(meso_mesh_compute_layout(0, 0, 1, &l) == MESO_ERR_INVALID_ARG);
    assert(meso_mesh_compute_layout(3, 4, 1, &l) == MESO_ERR_INVALID_ARG);
    assert(meso_mesh_compute_layout(3, 3, 2, &l) == MESO_ERR_INVALID_ARG);
    assert(meso_mesh_compute_layout(3, 3, 9, &l) == MESO_ERR_INVALID_ARG);
    free(buf);
    meso_file_close(f);
    free(mem);
}

static void object_records_round_trip(void)
{
    meso_object_record r = {7, MESO_OBJECT_CELLS, {1, 2, 3}, {4, 5, 6}, ""};
    memset(r.name, 'x', sizeof r.name); /* 32 characters, no NUL: encode truncates to 31 */
    uint8_t buf[64];
    meso_object_record_encode(&r, buf);
    assert(buf[32 + 31] == 0);
    meso_object_record d;
    meso_object_record_decode(buf, &d);
    assert(d.id == 7 && d.kind == MESO_OBJECT_CELLS && d.bbox_max[2] == 6.0f);
    assert(strlen(d.name) == 31 && strncmp(d.name, r.name, 31) == 0);
    assert(meso_crc32c(0, buf, 64) == meso_crc32c(0, buf, 64));
}

/* >>Draco hook */
typedef struct fake_draco {
    int calls;
} fake_draco;

/* "Decodes" a payload that is the 64-byte header followed by the raw arrays. */
static meso_result fake_decode(void* user, const meso_chunk_info* chunk, const void* src, size_t src_size, void* dst,
                               size_t dst_size, meso_error* err)
{
    (void)err;
    fake_draco* d = (fake_draco*)user;
    d->calls++;
    assert(chunk->type == MESO_CHUNK_MESH && chunk->encoding == MESO_ENCODING_DRACO);
    assert(src_size == dst_size + 8 && memcmp((const uint8_t*)src + 64, "FAKEDRCO", 8) == 0);
    memcpy(dst, src, 64);
    memcpy((uint8_t*)dst + 64, (const uint8_t*)src + 72, dst_size - 64);
    return MESO_OK;
}

static uint8_t* draco_file(size_t* size, const sample_chunk** mesh_out)
{
    const sample_chunk* sc;
    size_t n = sample_chunks(&sc);
    const sample_chunk* mesh = NULL;
    const sample_chunk* sthk = NULL;
    for (size_t i = 0; i < n; i++) {
        if (sc[i].desc.type == MESO_CHUNK_MESH && !mesh)
            mesh = &sc[i];
        if (sc[i].desc.type == MESO_CHUNK_STHK)
            sthk = &sc[i];
    }
    size_t enc_size = mesh->size + 8;
    uint8_t* enc = (uint8_t*)malloc(enc_size);
    memcpy(enc, mesh->data, 64);
    enc[12] = 14; /* quant bits as a Draco encoder would record them */
    enc[13] = 10;
    enc[14] = 12;
    memcpy(enc + 64, "FAKEDRCO", 8);
    memcpy(enc + 72, mesh->data + 64, mesh->size - 64);
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    meso_chunk_desc d = mesh->desc;
    d.encoding = MESO_ENCODING_DRACO;
    d.decoded_size = mesh->size;
    meso_error e;
    assert(meso_writer_add(w, &d, enc, enc_size, &e) == MESO_OK);
    assert(meso_writer_add(w, &sthk->desc, sthk->data, sthk->size, &e) == MESO_OK);
    uint8_t* mem = writer_to_memory(w, size);
    meso_writer_destroy(w);
    free(enc);
    *mesh_out = mesh;
    return mem;
}

static void draco_chunks_use_the_registered_decoder_or_fail_alone(void)
{
    size_t size;
    const sample_chunk* mesh;
    uint8_t* mem = draco_file(&size, &mesh);
    fake_draco fd = {0};
    meso_decoder dec = {MESO_ENCODING_DRACO, fake_decode, &fd};
    meso_open_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.decoders = &dec;
    desc.decoder_count = 1;
    for (int via = VIA_MEMORY; via <= VIA_IO; via++) {
        meso_file* f = NULL;
        mem_io io;
        meso_error e;
        assert(open_via(via, NULL, mem, size, &io, &desc, &f, &e) == MESO_OK);
        int32_t mi = meso_file_find(f, MESO_CHUNK_MESH, 1, 0);
        uint8_t* buf = (uint8_t*)malloc(mesh->size);
        fd.calls = 0;
        assert(meso_file_read_chunk(f, (uint32_t)mi, buf, mesh->size, &e) == MESO_OK);
        assert(fd.calls == 1);
        assert(memcmp(buf + 64, mesh->data + 64, mesh->size - 64) == 0 && buf[12] == 14);
        meso_mesh_view v;
        assert(meso_mesh_parse(buf, mesh->size, &v, &e) == MESO_OK && v.layout.quant_bits_position == 14);
        assert(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);
        assert(fd.calls == 2); /* full validation decodes and checks the mesh */
        meso_file_close(f);

        /* Without a decoder: UNSUPPORTED for the mesh, the rest reads fine. */
        assert(open_via(via, NULL, mem, size, &io, NULL, &f, &e) == MESO_OK);
        assert(meso_file_read_chunk(f, (uint32_t)mi, buf, mesh->size, &e) == MESO_ERR_UNSUPPORTED);
        assert(e.code == MESO_ISSUE_ENCODING_UNSUPPORTED && e.chunk == mi);
        assert(strstr(e.message, "'draco'") && strstr(e.message, "MESH") && strstr(e.message, "no decoder"));
        int32_t ti = meso_file_find(f, MESO_CHUNK_STHK, UINT32_MAX, UINT16_MAX);
        assert(meso_file_read_chunk(f, (uint32_t)ti, buf, mesh->size, &e) == MESO_OK);
        assert(meso_file_read_stored(f, (uint32_t)mi, buf, mesh->size, &e) == MESO_ERR_INVALID_ARG);
        assert(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);
        meso_file_close(f);
        free(buf);
    }
    free(mem);
}

static void reader_rejects_bad_arguments(void)
{
    size_t size;
    uint8_t* mem = sample_small_file(&size);
    meso_file* f = NULL;
    meso_error e;
    assert(meso_file_open_memory(NULL, 10, NULL, &f, &e) == MESO_ERR_INVALID_ARG && e.code == MESO_ISSUE_API_ARG);
    assert(meso_file_open_memory(mem, size, NULL, &f, &e) == MESO_OK);
    uint8_t small[8];
    assert(meso_file_read_chunk(f, 0, small, sizeof small, &e) == MESO_ERR_INVALID_ARG);
    assert(e.code == MESO_ISSUE_API_BUFFER);
    assert(meso_file_read_chunk(f, 99, small, sizeof small, &e) == MESO_ERR_INVALID_ARG &&
           e.code == MESO_ISSUE_API_ARG);
    assert(meso_file_chunk(f, 99) == NULL);
    assert(meso_file_validate(f, (meso_check)7, NULL, NULL) == MESO_ERR_INVALID_ARG);
    meso_file_close(f);
    meso_file_close(NULL);
    assert(meso_file_open_path("/nonexistent/dir/x.meso", NULL, &f, &e) == MESO_ERR_IO && e.code == MESO_ISSUE_IO_OPEN);
    assert(strstr(e.message, "/nonexistent/dir/x.meso") != NULL);
    assert(meso_file_open_mmap("/nonexistent/dir/x.meso", NULL, &f, &e) == MESO_ERR_IO && f == NULL);
    assert(strcmp(meso_result_string(MESO_ERR_CORRUPT), "corrupt") == 0);
    assert(meso_result_string((meso_result)1000) != NULL);
    free(mem);
}

static void count_free_any(void* p, void* user)
{
    (void)user;
    free(p);
}

static void writer_rejects_chunks_the_reader_would_refuse(void)
{
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    meso_error e;
    meso_chunk_desc d;
    memset(&d, 0, sizeof d);
    d.type = MESO_CHUNK_META;
    assert(meso_writer_add(w, &d, "{\"a\":1,}", 8, &e) == MESO_ERR_INVALID_ARG && e.code == MESO_ISSUE_JSON_SYNTAX);
    assert(meso_writer_add(w, &d, "{\"a\":\xC0\x80}", 7, &e) == MESO_ERR_INVALID_ARG && e.code == MESO_ISSUE_JSON_UTF8);
    assert(meso_writer_add(w, &d, "", 0, &e) == MESO_ERR_INVALID_ARG && e.code == MESO_ISSUE_CHUNK_EMPTY);
    d.type = MESO_FOURCC('Z', 'Z', 'Z', 'Z');
    d.flags = MESO_CHUNK_FLAG_REQUIRED;
    assert(meso_writer_add(w, &d, "abc", 3, &e) == MESO_ERR_INVALID_ARG && e.code == MESO_ISSUE_CHUNK_UNKNOWN_REQUIRED);
    d.flags = 0;
    assert(meso_writer_add(w, &d, "abc", 3, &e) == MESO_OK); /* unknown optional chunks are fine */
    d.flags = 0x4;
    assert(meso_writer_add(w, &d, "abc", 3, &e) == MESO_ERR_INVALID_ARG && e.code == MESO_ISSUE_CHUNK_FLAGS);
    d.flags = 0;
    d.type = MESO_CHUNK_STHK;
    d.dtype = MESO_DTYPE_F32;
    d.dims[0] = 2;
    assert(meso_writer_add(w, &d, "abcd", 4, &e) == MESO_ERR_INVALID_ARG && e.code == MESO_ISSUE_CHUNK_TYPED_SIZE);
    d.dtype = MESO_DTYPE_U32;
    assert(meso_writer_add(w, &d, "abcdefgh", 8, &e) == MESO_ERR_INVALID_ARG && e.code == MESO_ISSUE_TYPE_ELEMENT);
    d.dtype = MESO_DTYPE_F32;
    d.encoding = MESO_ENCODING_DRACO;
    d.decoded_size = 8;
    assert(meso_writer_add(w, &d, "abcdefgh", 8, &e) == MESO_ERR_INVALID_ARG && e.code == MESO_ISSUE_TYPE_ENCODING);
    d.encoding = 9;
    assert(meso_writer_add(w, &d, "abcdefgh", 8, &e) == MESO_ERR_INVALID_ARG && e.code == MESO_ISSUE_CHUNK_ENCODING);
    assert(meso_writer_add(NULL, &d, "a", 1, &e) == MESO_ERR_INVALID_ARG);
    assert(meso_writer_finish(w, NULL, 0, NULL) == MESO_ERR_INVALID_ARG);
    size_t need;
    assert(meso_writer_finish(w, NULL, 0, &need) == MESO_OK && need == 128 + 64);
    uint8_t small[64];
    assert(meso_writer_finish(w, small, sizeof small, &need) == MESO_ERR_INVALID_ARG);
    meso_allocator half = {NULL, count_free_any, NULL};
    meso_writer* w2 = NULL;
    assert(meso_writer_create(&half, &w2) == MESO_ERR_INVALID_ARG && w2 == NULL);
    meso_writer_destroy(w);
}

/* >>allocators */
typedef struct counting {
    long live;
    long total;
    long fail_at; /* fail the allocation with this 0-based number; -1 never */
} counting;

static void* count_alloc(size_t size, void* user)
{
    counting* c = (counting*)user;
    if (c->fail_at >= 0 && c->total == c->fail_at) {
        c->total++;
        return NULL;
    }
    c->total++;
    void* p = malloc(size);
    if (p)
        c->live++;
    return p;
}

static void count_free(void* p, void* user)
{
    counting* c = (counting*)user;
    if (p) {
        c->live--;
        free(p);
    }
}

/* Everything the library does, with allocator `a`. Returns the first
 * non-OK result (every one must be OUT_OF_MEMORY when allocation fails). */
static meso_result exercise(const meso_allocator* a, const char* path)
{
    meso_writer* w = NULL;
    meso_result r = meso_writer_create(a, &w);
    if (r != MESO_OK)
        return r;
    const sample_chunk* sc;
    size_t n = sample_chunks(&sc);
    meso_error e;
    for (size_t i = 0; i < n && r == MESO_OK; i++)
        r = meso_writer_add(w, &sc[i].desc, sc[i].data, sc[i].size, &e);
    if (r == MESO_OK)
        r = meso_writer_write_file(w, path, &e);
    meso_writer_destroy(w);
    if (r != MESO_OK)
        return r;
    size_t size;
    uint8_t* mem = slurp(path, &size);
    fake_draco fd = {0};
    meso_decoder dec = {MESO_ENCODING_DRACO, fake_decode, &fd};
    meso_open_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.allocator = *a;
    desc.decoders = &dec;
    desc.decoder_count = 1;
    for (int via = 0; via < VIA_COUNT && r == MESO_OK; via++) {
        meso_file* f = NULL;
        mem_io io;
        r = open_via(via, path, mem, size, &io, &desc, &f, &e);
        if (r != MESO_OK)
            break;
        r = meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL);
        uint8_t buf[4096];
        for (uint32_t i = 0; i < meso_file_chunk_count(f) && r == MESO_OK; i++)
            r = meso_file_read_chunk(f, i, buf, sizeof buf, &e);
        meso_file_close(f);
    }
    free(mem);
    if (r != MESO_OK)
        return r;
    /* Draco through the io reader allocates a staging buffer. */
    const sample_chunk* mesh;
    mem = draco_file(&size, &mesh);
    mem_io io;
    meso_file* f = NULL;
    r = open_via(VIA_IO, NULL, mem, size, &io, &desc, &f, &e);
    if (r == MESO_OK) {
        uint8_t buf[4096];
        r = meso_file_read_chunk(f, (uint32_t)meso_file_find(f, MESO_CHUNK_MESH, 1, 0), buf, sizeof buf, &e);
        if (r == MESO_OK)
            r = meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL);
        meso_file_close(f);
    }
    free(mem);
    return r;
}

static void counting_allocator_sees_every_allocation_freed(void)
{
    counting c = {0, 0, -1};
    meso_allocator a = {count_alloc, count_free, &c};
    char path[512];
    tmp_path(path, sizeof path, "alloc.meso");
    assert(exercise(&a, path) == MESO_OK);
    assert(c.total > 10 && c.live == 0);
    remove(path);
}

static void failing_allocator_returns_out_of_memory_at_every_step(void)
{
    char path[512];
    tmp_path(path, sizeof path, "fail.meso");
    counting probe = {0, 0, -1};
    meso_allocator a = {count_alloc, count_free, &probe};
    assert(exercise(&a, path) == MESO_OK);
    long total = probe.total;
    for (long n = 0; n < total; n++) {
        counting c = {0, 0, n};
        meso_allocator fa = {count_alloc, count_free, &c};
        meso_result r = exercise(&fa, path);
        assert(r == MESO_ERR_OUT_OF_MEMORY);
        assert(c.live == 0);
    }
    remove(path);
    /* No temporary files may remain from failed writes. */
    char cmd[600];
    snprintf(cmd, sizeof cmd, "ls -A '%s' | grep -q tmp", tmpdir);
    assert(system(cmd) != 0);
}

int main(void)
{
    make_tmpdir();
    every_chunk_kind_round_trips_through_all_four_readers();
    io_reader_fetches_only_the_requested_chunk();
    multi_block_chunks_read_once_and_verify_every_block();
    header_fields_sit_at_layout_offsets();
    writer_orders_meta_objt_rprt_then_coarse_lod_first();
    writer_is_deterministic();
    empty_writer_makes_a_valid_64_byte_file();
    mesh_view_gives_the_tetrahedron();
    object_records_round_trip();
    draco_chunks_use_the_registered_decoder_or_fail_alone();
    reader_rejects_bad_arguments();
    writer_rejects_chunks_the_reader_would_refuse();
    counting_allocator_sees_every_allocation_freed();
    failing_allocator_returns_out_of_memory_at_every_step();
    rmdir(tmpdir);
    printf("test_format_roundtrip: ok\n");
    return 0;
}
