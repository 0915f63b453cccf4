/*
 * fuzz_meso_file.c — libFuzzer target for the .meso reader (formats/), its
 * validator and the chunk decoders (MESH, OBJT, Draco through the bake's
 * decoder), and the level, part and prism-list tables (meso_file_levels,
 * meso_file_parts, meso_file_part_triangles). Pattern: parse -> validate ->
 * read every chunk and every object's tables -> free.
 *
 * How to run (STYLE.md §9):
 *
 *   # replay the corpus with any compiler (meson test --suite fuzz):
 *   meson setup build && meson test -C build --suite fuzz
 *   ./build/tests/fuzz/fuzz_meso_file tests/fuzz/corpus/meso_file [file...]
 *
 *   # real fuzzing with libFuzzer + ASan + UBSan (clang):
 *   CC=clang CXX=clang++ meson setup build-fuzz -Dfuzzing_engine=libfuzzer
 *   ninja -C build-fuzz
 *   meson test -C build-fuzz --suite fuzz-session      # 60 s bounded session
 *   # or by hand, on a scratch copy of the corpus (libFuzzer adds files to it):
 *   cp -r tests/fuzz/corpus/meso_file /tmp/c && \
 *     ./build-fuzz/tests/fuzz/fuzz_meso_file /tmp/c -dict=tests/fuzz/meso.dict -max_len=65536
 *   # reproduce a crash:  ./build-fuzz/tests/fuzz/fuzz_meso_file crash-<sha1>
 *
 * Every input runs twice: as given, and (when that changes anything) with
 * the header, TOC and payload CRC32Cs recomputed, so mutations get past the
 * checksums and reach the structure checks and the decoders.
 *
 * What it asserts beyond "no crash, no leak": the library allocates only
 * through the capped allocator below (nothing above MESO_FUZZ_ALLOC_LIMIT;
 * such requests are refused and counted, and abort() when the environment
 * sets MESO_FUZZ_STRICT_ALLOC=1), frees everything it allocates, reads only
 * inside the stream through the io callback, gives the same verdict over
 * memory and over the callback, and never hands back a structured chunk that
 * meso_mesh_parse rejects.
 */
#undef NDEBUG /* this file uses assert() to check the library's contracts */
#include <assert.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "meso_file.h"
#include "meso_layout.h"
#include "mesh_chunk.h"

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

#define MESO_FUZZ_MAX_DECODED ((uint64_t)64 << 20)  /* skip reading chunks larger than this */
#define MESO_FUZZ_ALLOC_LIMIT ((size_t)64 << 20)    /* refuse library allocations above this */

/* >>capped, counting allocator -------------------------------------------- */

typedef struct fuzz_heap {
    size_t live;    /* blocks allocated and not yet freed */
    size_t refused; /* requests above the limit */
    size_t largest; /* largest request seen */
    int strict;     /* abort on a refused request */
} fuzz_heap;

static void* heap_alloc(size_t size, void* user)
{
    fuzz_heap* h = (fuzz_heap*)user;
    if (size > h->largest)
        h->largest = size;
    if (size > MESO_FUZZ_ALLOC_LIMIT) {
        h->refused++;
        if (h->strict) {
            fprintf(stderr, "fuzz_meso_file: library asked for %zu bytes (limit %zu)\n", size,
                    MESO_FUZZ_ALLOC_LIMIT);
            abort();
        }
        return NULL;
    }
    void* p = malloc(size);
    if (p)
        h->live++;
    return p;
}

static void heap_free(void* p, void* user)
{
    fuzz_heap* h = (fuzz_heap*)user;
    assert(p != NULL);
    assert(h->live > 0);
    h->live--;
    free(p);
}

/* >>little-endian helpers & CRC fix-up ------------------------------------ */

static uint32_t ld32(const uint8_t* p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static uint64_t ld64(const uint8_t* p) { return (uint64_t)ld32(p) | ((uint64_t)ld32(p + 4) << 32); }
static void st32(uint8_t* p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (uint8_t)(v >> (8 * i));
}

/* Recompute every CRC the data declares (payloads, TOC, header) where the
 * ranges are in bounds. Returns non-zero when a byte changed. */
static int fix_crcs(uint8_t* d, size_t size)
{
    if (size < MESO_HDR_SIZE)
        return 0;
    uint8_t before[MESO_HDR_SIZE];
    memcpy(before, d, MESO_HDR_SIZE);
    int changed = 0;
    const uint32_t count = ld32(d + MESO_HDR_OFF_CHUNK_COUNT), esize = ld32(d + MESO_HDR_OFF_TOC_ENTRY_SIZE);
    if (esize >= MESO_TOC_ENTRY_SIZE && count <= (size - MESO_HDR_SIZE) / esize) {
        for (uint32_t i = 0; i < count; i++) {
            uint8_t* e = d + MESO_HDR_SIZE + (size_t)i * esize;
            const uint64_t off = ld64(e + MESO_TOC_OFF_OFFSET), n = ld64(e + MESO_TOC_OFF_STORED_SIZE);
            if (off <= size && n <= size - off) {
                const uint32_t crc = meso_crc32c(0, d + off, (size_t)n);
                changed |= crc != ld32(e + MESO_TOC_OFF_CRC);
                st32(e + MESO_TOC_OFF_CRC, crc);
            }
        }
        st32(d + MESO_HDR_OFF_TOC_CRC, meso_crc32c(0, d + MESO_HDR_SIZE, (size_t)count * esize));
    }
    st32(d + MESO_HDR_OFF_HEADER_CRC, 0);
    st32(d + MESO_HDR_OFF_HEADER_CRC, meso_crc32c(0, d, MESO_HDR_SIZE));
    return changed || memcmp(before, d, MESO_HDR_SIZE) != 0;
}

/* >>io callback ----------------------------------------------------------- */

typedef struct io_src {
    const uint8_t* data;
    size_t size;
    unsigned reads;
} io_src;

static int io_read(void* user, uint64_t offset, void* dst, size_t size)
{
    io_src* s = (io_src*)user;
    /* The reader range-checks everything before reading: never out of bounds. */
    assert(offset <= s->size && size <= s->size - offset);
    s->reads++;
    if (size)
        memcpy(dst, s->data + offset, size);
    return 0;
}

/* >>checks ---------------------------------------------------------------- */

static int first_issue(void* user, const meso_error* issue)
{
    meso_error* first = (meso_error*)user;
    assert(issue->result != MESO_OK);
    assert(memchr(issue->message, 0, sizeof issue->message) != NULL);
    if (first->result == MESO_OK)
        *first = *issue;
    return 0; /* keep going: exercise every check */
}

static void check_mesh(const void* buf, size_t n)
{
    meso_mesh_view v;
    meso_error err;
    /* read_chunk already ran the MESH content checks: parse must agree. */
    meso_result r = meso_mesh_parse(buf, n, &v, &err);
    assert(r == MESO_OK);
    assert(v.layout.vertex_count >= 1 && v.layout.index_count % 3 == 0 && v.layout.size == n);
    assert(v.positions != NULL);
    for (uint32_t i = 0; i < v.layout.index_count; i++)
        assert(v.indices[i] < v.layout.vertex_count);
    /* Touch both ends of every array so ASan sees any range error. */
    volatile float sink = v.positions[0] + v.positions[(size_t)v.layout.vertex_count * 3 - 1];
    if (v.normals)
        sink += v.normals[0] + v.normals[(size_t)v.layout.vertex_count * 3 - 1];
    if (v.uvs)
        sink += v.uvs[0] + v.uvs[(size_t)v.layout.vertex_count * 2 - 1];
    (void)sink;
}

static void check_objt(const uint8_t* buf, size_t n)
{
    assert(n % MESO_OBJT_RECORD_SIZE == 0);
    for (size_t o = 0; o < n; o += MESO_OBJT_RECORD_SIZE) {
        meso_object_record rec;
        meso_object_record_decode(buf + o, &rec);
        assert(memchr(rec.name, 0, sizeof rec.name) != NULL);
        assert(rec.id >= 1 && rec.kind > MESO_OBJECT_INVALID && rec.kind < MESO_OBJECT_KIND_COUNT);
        /* Round trip: encode(decode(x)) == x for a record the reader accepted. */
        uint8_t again[MESO_OBJT_RECORD_SIZE];
        meso_object_record_encode(&rec, again);
        assert(memcmp(again, buf + o, MESO_OBJT_RECORD_SIZE) == 0);
    }
}

/* Read every chunk of an open file into exactly-sized buffers. */
static void read_chunks(meso_file* f, size_t input_size, int have_view)
{
    const uint32_t n = meso_file_chunk_count(f);
    assert(meso_file_chunk(f, n) == NULL);
    for (uint32_t i = 0; i < n; i++) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        assert(c != NULL);
        /* Open checked every range against the input. */
        assert(c->stored_size >= 1 && c->offset % MESO_ALIGN == 0);
        assert(c->offset <= input_size && c->stored_size <= input_size - c->offset);
        if (c->encoding == MESO_ENCODING_RAW)
            assert(c->decoded_size == c->stored_size);
        (void)meso_file_find(f, c->type, c->object, c->lod);

        meso_error err;
        /* Stored bytes, exactly sized. */
        uint8_t* stored = (uint8_t*)malloc((size_t)c->stored_size);
        assert(stored);
        meso_result rs = meso_file_read_stored(f, i, stored, (size_t)c->stored_size, &err);
        assert(rs == MESO_OK || rs == MESO_ERR_CORRUPT);
        if (have_view) {
            const void* view = NULL;
            assert(meso_file_chunk_view(f, i, &view, &err) == MESO_OK && view != NULL);
            assert(memcmp(view, stored, (size_t)c->stored_size) == 0);
        }
        free(stored);

        if (c->decoded_size > MESO_FUZZ_MAX_DECODED || c->decoded_size == 0)
            continue;
        const size_t dn = (size_t)c->decoded_size;
        uint8_t* buf = (uint8_t*)malloc(dn);
        assert(buf);
        /* One byte short must be refused before anything is written. */
        assert(meso_file_read_chunk(f, i, buf, dn - 1, &err) == MESO_ERR_INVALID_ARG);
        meso_result r = meso_file_read_chunk(f, i, buf, dn, &err);
        if (r == MESO_OK) {
            if (c->type == MESO_CHUNK_MESH)
                check_mesh(buf, dn);
            else if (c->type == MESO_CHUNK_OBJT)
                check_objt(buf, dn);
        } else {
            assert(err.result == r && err.code != MESO_ISSUE_NONE);
            assert(memchr(err.message, 0, sizeof err.message) != NULL);
        }
        free(buf);
    }
}

/* The level, part and prism-list tables of every object (FORMAT.md §7.10,
 * §7.11): whatever the bytes, each call returns a result and stays within
 * the arrays it is given (counted first, then read into arrays of exactly
 * that size, so ASan sees any write past them). */
static void read_tables(meso_file* f)
{
    enum { MOST = 64 };
    meso_object_record recs[MOST];
    uint32_t n = 0;
    if (meso_file_objects(f, recs, MOST, &n, NULL) != MESO_OK)
        return;
    for (uint32_t i = 0; i < n && i < MOST; ++i) {
        const uint32_t id = recs[i].id;
        uint32_t count = 0;
        if (meso_file_levels(f, id, NULL, 0, &count, NULL) == MESO_OK && count > 0 && count <= 4096) {
            meso_level_info* lv = malloc(sizeof(meso_level_info) * count);
            assert(lv);
            uint32_t again = 0;
            (void)meso_file_levels(f, id, lv, count, &again, NULL);
            free(lv);
        }
        uint32_t nl = 0, np = 0, ne = 0;
        if (meso_file_parts(f, id, NULL, 0, &nl, &np, NULL, 0, &ne, NULL) == MESO_OK && nl <= 65536 &&
            ne <= 65536) {
            meso_part_level* pl = malloc(sizeof(meso_part_level) * (nl ? nl : 1));
            uint32_t* edges = malloc(sizeof(uint32_t) * 2 * (ne ? ne : 1));
            assert(pl && edges);
            (void)meso_file_parts(f, id, pl, nl, &nl, &np, edges, ne, &ne, NULL);
            free(pl);
            free(edges);
        }
        uint32_t nt = 0;
        if (meso_file_part_triangles(f, id, NULL, 0, &nt, NULL) == MESO_OK && nt > 0 && nt <= (1u << 20)) {
            uint32_t* tri = malloc(sizeof(uint32_t) * nt);
            assert(tri);
            (void)meso_file_part_triangles(f, id, tri, nt, &nt, NULL);
            free(tri);
        }
    }
}

/* Open over memory and over the io callback, validate FULL, read every chunk.
 * `d` is an exactly-sized heap block. */
static void run_one(const uint8_t* d, size_t size, const meso_decoder* dec, int strict)
{
    fuzz_heap heap = {0, 0, 0, strict};
    meso_open_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.allocator.alloc_fn = heap_alloc;
    desc.allocator.free_fn = heap_free;
    desc.allocator.user = &heap;
    desc.decoders = dec;
    desc.decoder_count = 1;
    /* Encoded chunks above the allocation cap are refused on open (issue
     * 2022), so the fuzzer exercises that limit rather than the cap. */
    desc.max_decoded_size = MESO_FUZZ_ALLOC_LIMIT;

    /* Memory reader. */
    meso_file* f = NULL;
    meso_error err;
    meso_result open_mem = meso_file_open_memory(d, size, &desc, &f, &err);
    meso_result valid_mem = MESO_OK;
    if (open_mem == MESO_OK) {
        assert(f != NULL);
        uint16_t major = 0, minor = 0;
        meso_file_version(f, &major, &minor);
        assert(major == MESO_FORMAT_MAJOR && meso_file_size(f) == size);
        assert(meso_file_validate(f, MESO_CHECK_CHEAP, NULL, NULL) == MESO_OK);
        meso_error first;
        memset(&first, 0, sizeof first);
        valid_mem = meso_file_validate(f, MESO_CHECK_FULL, first_issue, &first);
        assert(valid_mem == first.result);
        read_chunks(f, size, 1);
        read_tables(f);
        meso_file_close(f);
    } else {
        assert(f == NULL && err.result == open_mem && err.code != MESO_ISSUE_NONE);
    }
    assert(heap.live == 0); /* everything the reader allocated was freed */

    /* Host callback reader over the same bytes: same verdicts. */
    io_src src = {d, size, 0};
    meso_io io = {io_read, size, &src};
    f = NULL;
    meso_result open_io = meso_file_open_io(&io, &desc, &f, &err);
    assert(open_io == open_mem);
    if (open_io == MESO_OK) {
        meso_error first;
        memset(&first, 0, sizeof first);
        meso_result valid_io = meso_file_validate(f, MESO_CHECK_FULL, first_issue, &first);
        assert(valid_io == valid_mem);
        const void* view = NULL;
        if (meso_file_chunk_count(f) > 0)
            assert(meso_file_chunk_view(f, 0, &view, &err) == MESO_ERR_UNSUPPORTED);
        read_chunks(f, size, 0);
        meso_file_close(f);
    }
    assert(heap.live == 0);
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    static int strict = -1;
    if (strict < 0) {
        const char* s = getenv("MESO_FUZZ_STRICT_ALLOC");
        strict = s != NULL && s[0] == '1';
    }
    const meso_decoder dec = meso_bake_draco_decoder();

    /* Exactly-sized copy: ASan flags any read past the end. */
    uint8_t* copy = (uint8_t*)malloc(size ? size : 1);
    assert(copy);
    if (size)
        memcpy(copy, data, size);
    run_one(copy, size, &dec, strict);

    /* Raw decoders on the input itself (no CRC in the way). */
    meso_mesh_view v;
    if (meso_mesh_parse(copy, size, &v, NULL) == MESO_OK)
        check_mesh(copy, size);
    if (size >= MESO_OBJT_RECORD_SIZE) {
        meso_object_record rec;
        meso_object_record_decode(copy, &rec);
        assert(memchr(rec.name, 0, sizeof rec.name) != NULL);
    }

    /* Again with every checksum made to match. */
    if (fix_crcs(copy, size))
        run_one(copy, size, &dec, strict);
    free(copy);
    return 0;
}
