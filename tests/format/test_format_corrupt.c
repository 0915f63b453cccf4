/* test_format_corrupt.c — every corruption class is rejected with the right
 * meso_result and issue code. Where a corruption would otherwise be caught by
 * a checksum, the CRCs are recomputed (fix_crcs) to reach the deeper check.
 * One file of ~1,060 lines on purpose: it is a table of corruption cases, one
 * short function per FORMAT.md rule, all built on the same sample file and
 * CRC fix-up, and reads top to bottom in FORMAT.md's order. */
#undef NDEBUG
#include "meso_file.h"
#include "meso_layout.h"
#include "sample.h"

#include <assert.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static uint8_t* entry(uint8_t* mem, uint32_t i) { return mem + MESO_HDR_SIZE + (size_t)i * MESO_TOC_ENTRY_SIZE; }

static uint32_t chunk_of(const uint8_t* mem, uint32_t type)
{
    uint32_t n = get32(mem + MESO_HDR_OFF_CHUNK_COUNT);
    for (uint32_t i = 0; i < n; i++)
        if (get32(mem + MESO_HDR_SIZE + (size_t)i * 64) == type)
            return i;
    assert(0 && "chunk type not in sample");
    return 0;
}

static uint8_t* payload(uint8_t* mem, uint32_t i) { return mem + get64(entry(mem, i) + MESO_TOC_OFF_OFFSET); }

static void expect(const uint8_t* mem, size_t size, meso_result want, uint32_t code, int line)
{
    meso_error e;
    memset(&e, 0, sizeof e);
    meso_result r = open_and_validate_copy(mem, size, &e);
    if (r != want || e.code != code) {
        fprintf(stderr, "line %d: want %s/%u, got %s/%u: %s\n", line, meso_result_string(want), code,
                meso_result_string(r), e.code, e.message);
        assert(0);
    }
}
#define EXPECT(mem, size, want, code) expect(mem, size, want, code, __LINE__)

/* A fresh copy of the sample file. */
static uint8_t* fresh(size_t* size) { return sample_file(size); }

static void sample_is_valid(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    EXPECT(m, size, MESO_OK, 0);
    free(m);
}

static void every_truncated_prefix_is_rejected(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    for (size_t n = 0; n < size; n++) {
        meso_error e;
        meso_result r = open_and_validate_copy(m, n, &e);
        assert(r == MESO_ERR_TRUNCATED);
        assert(e.code == (n < 64 ? MESO_ISSUE_HDR_TRUNCATED : MESO_ISSUE_FILE_TRUNCATED));
    }
    free(m);
}

static void every_header_and_toc_bit_flip_and_sampled_payload_flips_are_detected(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    uint32_t n = get32(m + MESO_HDR_OFF_CHUNK_COUNT);
    size_t toc_end = 64 + (size_t)n * 64;
    for (size_t bit = 0; bit < size * 8; bit += (bit < toc_end * 8 ? 1 : 5)) {
        m[bit / 8] ^= (uint8_t)(1u << (bit % 8));
        meso_error e;
        meso_result r = open_and_validate(m, size, &e);
        if (r == MESO_OK) {
            fprintf(stderr, "bit flip at byte %zu bit %zu went undetected\n", bit / 8, bit % 8);
            assert(0);
        }
        m[bit / 8] ^= (uint8_t)(1u << (bit % 8));
    }
    EXPECT(m, size, MESO_OK, 0);
    free(m);
}

static void wrong_magic_is_bad_magic(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    memcpy(m, "PK\x03\x04\x14\x00\x00\x00", 8);
    EXPECT(m, size, MESO_ERR_BAD_MAGIC, MESO_ISSUE_HDR_MAGIC);
    free(m);
}

/* Simulate whole-file transfers, as FTP ASCII mode would do them. */
static void text_mode_and_7bit_damage_have_their_own_codes(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    uint8_t* out = (uint8_t*)malloc(size * 2);
    size_t k = 0;
    for (size_t i = 0; i < size; i++) /* CRLF -> LF */
        if (!(m[i] == '\r' && i + 1 < size && m[i + 1] == '\n'))
            out[k++] = m[i];
    EXPECT(out, k, MESO_ERR_BAD_MAGIC, MESO_ISSUE_HDR_TEXT_MODE);
    k = 0;
    for (size_t i = 0; i < size; i++) { /* LF -> CRLF */
        if (m[i] == '\n')
            out[k++] = '\r';
        out[k++] = m[i];
    }
    EXPECT(out, k, MESO_ERR_BAD_MAGIC, MESO_ISSUE_HDR_TEXT_MODE);
    for (size_t i = 0; i < size; i++)
        out[i] = m[i] & 0x7F;
    EXPECT(out, size, MESO_ERR_BAD_MAGIC, MESO_ISSUE_HDR_7BIT);
    free(out);
    free(m);
}

static void newer_major_is_refused_and_major_zero_is_legacy(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    put16(m + MESO_HDR_OFF_MAJOR, 2);
    EXPECT(m, size, MESO_ERR_VERSION_TOO_NEW, MESO_ISSUE_HDR_TOO_NEW); /* even before the CRC */
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_VERSION_TOO_NEW, MESO_ISSUE_HDR_TOO_NEW);
    put16(m + MESO_HDR_OFF_MAJOR, 0);
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_BAD_MAGIC, MESO_ISSUE_HDR_LEGACY);
    free(m);
}

static void newer_minor_is_read_and_skips_unknown_optional_chunks(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    put16(m + MESO_HDR_OFF_MINOR, 3);
    fix_crcs(m);
    EXPECT(m, size, MESO_OK, 0);
    uint32_t i = chunk_of(m, MESO_CHUNK_STHK);
    put32(entry(m, i) + MESO_TOC_OFF_TYPE, MESO_FOURCC('Z', 'Z', 'Z', '1'));
    put32(entry(m, i) + MESO_TOC_OFF_FLAGS, 0);
    fix_crcs(m);
    EXPECT(m, size, MESO_OK, 0);
    meso_file* f = NULL;
    assert(meso_file_open_memory(m, size, NULL, &f, NULL) == MESO_OK);
    assert(meso_file_find(f, MESO_CHUNK_STHK, UINT32_MAX, UINT16_MAX) == -1);
    uint16_t major, minor;
    meso_file_version(f, &major, &minor);
    assert(major == 1 && minor == 3);
    meso_file_close(f);
    /* The same chunk marked REQUIRED: refused, naming the fourcc. */
    put32(entry(m, i) + MESO_TOC_OFF_FLAGS, MESO_CHUNK_FLAG_REQUIRED);
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_UNSUPPORTED, MESO_ISSUE_CHUNK_UNKNOWN_REQUIRED);
    meso_error e;
    assert(meso_file_open_memory(m, size, NULL, &f, &e) == MESO_ERR_UNSUPPORTED && strstr(e.message, "'ZZZ1'"));
    assert(e.chunk == (int32_t)i);
    free(m);
}

static void unknown_encoding_is_corrupt_in_known_minors_and_unsupported_at_read_in_newer_ones(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    uint32_t i = chunk_of(m, MESO_CHUNK_STHK);
    put16(entry(m, i) + MESO_TOC_OFF_ENCODING, 7);
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_ENCODING);
    put16(m + MESO_HDR_OFF_MINOR, MESO_FORMAT_MINOR + 1);
    fix_crcs(m);
    meso_file* f = NULL;
    meso_error e;
    assert(meso_file_open_memory(m, size, NULL, &f, &e) == MESO_OK);
    uint8_t buf[64];
    assert(meso_file_read_chunk(f, i, buf, sizeof buf, &e) == MESO_ERR_UNSUPPORTED);
    assert(e.code == MESO_ISSUE_ENCODING_UNSUPPORTED);
    meso_file_close(f);
    free(m);
}

/* A newer minor may grow TOC entries: readers use the first 64 bytes. */
static void larger_toc_entries_from_a_newer_minor_are_read(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    uint32_t n = get32(m + MESO_HDR_OFF_CHUNK_COUNT);
    uint64_t delta = (uint64_t)n * 64;
    size_t big_size = size + (size_t)delta;
    uint8_t* b = (uint8_t*)calloc(1, big_size);
    memcpy(b, m, 64);
    for (uint32_t i = 0; i < n; i++) {
        uint8_t* e = b + 64 + (size_t)i * 128;
        memcpy(e, entry(m, i), 64);
        memset(e + 64, 0xAB, 64); /* fields this reader does not know */
        put64(e + MESO_TOC_OFF_OFFSET, get64(entry(m, i) + MESO_TOC_OFF_OFFSET) + delta);
    }
    memcpy(b + 64 + (size_t)n * 128, m + 64 + (size_t)n * 64, size - 64 - (size_t)n * 64);
    put16(b + MESO_HDR_OFF_MINOR, 1);
    put32(b + MESO_HDR_OFF_TOC_ENTRY_SIZE, 128);
    put64(b + MESO_HDR_OFF_FILE_SIZE, big_size);
    fix_crcs(b);
    EXPECT(b, big_size, MESO_OK, 0);
    meso_file* f = NULL;
    assert(meso_file_open_memory(b, big_size, NULL, &f, NULL) == MESO_OK);
    const sample_chunk* sc;
    size_t count = sample_chunks(&sc);
    assert(meso_file_chunk_count(f) == count);
    for (size_t k = 0; k < count; k++) {
        int32_t idx = meso_file_find(f, sc[k].desc.type, sc[k].desc.object, sc[k].desc.lod);
        uint8_t buf[1024];
        assert(idx >= 0 && meso_file_read_chunk(f, (uint32_t)idx, buf, sizeof buf, NULL) == MESO_OK);
        assert(memcmp(buf, sc[k].data, sc[k].size) == 0);
    }
    meso_file_close(f);
    /* Smaller than 64 is never valid. */
    put32(b + MESO_HDR_OFF_TOC_ENTRY_SIZE, 32);
    fix_crcs(b);
    EXPECT(b, big_size, MESO_ERR_CORRUPT, MESO_ISSUE_HDR_TOC_ENTRY_SIZE);
    free(b);
    free(m);
}

static void chunk_ranges_order_and_alignment_are_checked(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    uint8_t* e3 = entry(m, 3);
    uint64_t off3 = get64(e3 + MESO_TOC_OFF_OFFSET), off2 = get64(entry(m, 2) + MESO_TOC_OFF_OFFSET);
    uint64_t off4 = get64(entry(m, 4) + MESO_TOC_OFF_OFFSET);

    put64(e3 + MESO_TOC_OFF_OFFSET, off2); /* same start as the previous chunk */
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_OVERLAP);
    put64(e3 + MESO_TOC_OFF_OFFSET, off4); /* swapped with the next one */
    put64(entry(m, 4) + MESO_TOC_OFF_OFFSET, off3);
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_ORDER);
    put64(entry(m, 4) + MESO_TOC_OFF_OFFSET, off4);
    put64(e3 + MESO_TOC_OFF_OFFSET, off2 - 64);
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_ORDER);
    put64(e3 + MESO_TOC_OFF_OFFSET, off3 + 8);
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_ALIGN);
    put64(e3 + MESO_TOC_OFF_OFFSET, 64);
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_IN_TOC);
    put64(e3 + MESO_TOC_OFF_OFFSET, size);
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_BOUNDS);
    put64(e3 + MESO_TOC_OFF_OFFSET, UINT64_MAX - 63); /* offset + size would wrap */
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_BOUNDS);
    put64(e3 + MESO_TOC_OFF_OFFSET, off3);
    fix_crcs(m);
    EXPECT(m, size, MESO_OK, 0);
    /* Absurd sizes on a BYTES chunk (META is chunk 0). */
    put64(entry(m, 0) + MESO_TOC_OFF_STORED_SIZE, UINT64_MAX - 1);
    put64(entry(m, 0) + MESO_TOC_OFF_DECODED_SIZE, UINT64_MAX - 1);
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_BOUNDS);
    free(m);
}

typedef struct biggest {
    size_t max;
} biggest;

static void* track_alloc(size_t size, void* user)
{
    biggest* b = (biggest*)user;
    if (size > b->max)
        b->max = size;
    return malloc(size);
}

static void track_free(void* p, void* user)
{
    (void)user;
    free(p);
}

static void absurd_chunk_count_allocates_nothing_large(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    put32(m + MESO_HDR_OFF_CHUNK_COUNT, 0xFFFFFFFFu);
    /* Only the header CRC is fixed: a TOC CRC over what the count claims
     * cannot even be computed. */
    put32(m + MESO_HDR_OFF_HEADER_CRC, 0);
    put32(m + MESO_HDR_OFF_HEADER_CRC, meso_crc32c(0, m, 64));
    EXPECT(m, size, MESO_ERR_UNSUPPORTED, MESO_ISSUE_TOC_TOO_MANY);
    biggest b = {0};
    meso_open_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.allocator.alloc_fn = track_alloc;
    desc.allocator.free_fn = track_free;
    desc.allocator.user = &b;
    desc.max_chunks = UINT32_MAX;
    meso_file* f = NULL;
    meso_error e;
    assert(meso_file_open_memory(m, size, &desc, &f, &e) == MESO_ERR_CORRUPT && e.code == MESO_ISSUE_TOC_BOUNDS);
    assert(b.max < 4096);
    /* The limit in the desc applies. */
    put32(m + MESO_HDR_OFF_CHUNK_COUNT, 5);
    fix_crcs(m);
    desc.max_chunks = 4;
    assert(meso_file_open_memory(m, size, &desc, &f, &e) == MESO_ERR_UNSUPPORTED && e.code == MESO_ISSUE_TOC_TOO_MANY);
    free(m);
}

static void header_size_fields_are_checked(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    put64(m + MESO_HDR_OFF_FILE_SIZE, UINT64_MAX - 63);
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_TRUNCATED, MESO_ISSUE_FILE_TRUNCATED);
    put64(m + MESO_HDR_OFF_FILE_SIZE, size + 1);
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_HDR_FILE_SIZE_ALIGN);
    put64(m + MESO_HDR_OFF_FILE_SIZE, size - 64);
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_FILE_TRAILING);
    put64(m + MESO_HDR_OFF_FILE_SIZE, size);
    put64(m + MESO_HDR_OFF_TOC_OFFSET, 128);
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_HDR_TOC_OFFSET);
    put64(m + MESO_HDR_OFF_TOC_OFFSET, 64);
    put32(m + MESO_HDR_OFF_FLAGS, 1);
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_HDR_FLAGS);
    put32(m + MESO_HDR_OFF_FLAGS, 0);
    m[MESO_HDR_OFF_RESERVED + 15] = 1;
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_HDR_RESERVED);
    m[MESO_HDR_OFF_RESERVED + 15] = 0;
    fix_crcs(m);
    EXPECT(m, size, MESO_OK, 0);
    free(m);
}

static void toc_entry_fields_are_checked(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    uint32_t i = chunk_of(m, MESO_CHUNK_SDIR);
    uint8_t* e = entry(m, i);
    uint8_t saved[64];
    memcpy(saved, e, 64);
#define FIELD_CASE(stmt, want, code) \
    do {                             \
        stmt;                        \
        fix_crcs(m);                 \
        EXPECT(m, size, want, code); \
        memcpy(e, saved, 64);        \
    } while (0)
    FIELD_CASE(put32(e + MESO_TOC_OFF_RESERVED, 1), MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_RESERVED);
    FIELD_CASE(put32(e + MESO_TOC_OFF_FLAGS, 2), MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_FLAGS);
    FIELD_CASE(put32(e + MESO_TOC_OFF_TYPE, 0x00444953u), MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_TYPE);
    FIELD_CASE(put16(e + MESO_TOC_OFF_DTYPE, 42), MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_DTYPE);
    FIELD_CASE(put16(e + MESO_TOC_OFF_COMPONENTS, 17), MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_COMPONENTS);
    FIELD_CASE(put16(e + MESO_TOC_OFF_COMPONENTS, 0), MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_COMPONENTS);
    FIELD_CASE(put32(e + MESO_TOC_OFF_DIMS + 4, 0), MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_DIMS);
    FIELD_CASE(put64(e + MESO_TOC_OFF_DECODED_SIZE, 47), MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_RAW_SIZE);
    FIELD_CASE(put32(e + MESO_TOC_OFF_DIMS, 5), MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_TYPED_SIZE);
    /* dims product overflows u64: 4 x 16 x 2^32 x 2^32 x 2^32. */
    FIELD_CASE((put16(e + MESO_TOC_OFF_COMPONENTS, 16), put32(e + MESO_TOC_OFF_DIMS, 0xFFFFFFFFu),
                put32(e + MESO_TOC_OFF_DIMS + 4, 0xFFFFFFFFu), put32(e + MESO_TOC_OFF_DIMS + 8, 0xFFFFFFFFu)),
               MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_TYPED_SIZE);
    FIELD_CASE((put64(e + MESO_TOC_OFF_STORED_SIZE, 0), put64(e + MESO_TOC_OFF_DECODED_SIZE, 0)), MESO_ERR_CORRUPT,
               MESO_ISSUE_CHUNK_EMPTY);
    /* Full tier: the type's element rules (SDIR must be F32 x 3). */
    FIELD_CASE(put16(e + MESO_TOC_OFF_DTYPE, MESO_DTYPE_U32), MESO_ERR_CORRUPT, MESO_ISSUE_TYPE_ELEMENT);
    FIELD_CASE(put16(e + MESO_TOC_OFF_ENCODING, MESO_ENCODING_DRACO), MESO_ERR_CORRUPT, MESO_ISSUE_TYPE_ENCODING);
    uint32_t meta = chunk_of(m, MESO_CHUNK_META);
    e = entry(m, meta);
    memcpy(saved, e, 64);
    FIELD_CASE(put32(e + MESO_TOC_OFF_OBJECT, 3), MESO_ERR_CORRUPT, MESO_ISSUE_TYPE_OBJECT);
#undef FIELD_CASE
    fix_crcs(m);
    EXPECT(m, size, MESO_OK, 0);
    free(m);
}

static void checksum_mismatches_are_detected(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    uint32_t i = chunk_of(m, MESO_CHUNK_DIST);
    payload(m, i)[5] ^= 0x10;
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_PAYLOAD_CRC);
    meso_file* f = NULL;
    meso_error e;
    assert(meso_file_open_memory(m, size, NULL, &f, &e) == MESO_OK); /* cheap tier does not read payloads */
    uint8_t buf[256];
    assert(meso_file_read_chunk(f, i, buf, sizeof buf, &e) == MESO_ERR_CORRUPT && e.code == MESO_ISSUE_PAYLOAD_CRC);
    assert(e.chunk == (int32_t)i && strstr(e.message, "DIST"));
    meso_file_close(f);
    payload(m, i)[5] ^= 0x10;
    put32(entry(m, 1) + MESO_TOC_OFF_CRC, get32(entry(m, 1) + MESO_TOC_OFF_CRC) ^ 1);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_TOC_CRC);
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_PAYLOAD_CRC); /* the entry's CRC is now wrong */
    fix_payload_crc(m, 1);
    fix_crcs(m);
    EXPECT(m, size, MESO_OK, 0);
    m[MESO_HDR_OFF_RESERVED] = 1;
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_HDR_CRC);
    free(m);
}

static void trailing_bytes_and_padding_are_checked(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    uint8_t* big = (uint8_t*)calloc(1, size + 64);
    memcpy(big, m, size);
    EXPECT(big, size + 1, MESO_ERR_CORRUPT, MESO_ISSUE_FILE_TRAILING);
    EXPECT(big, size + 64, MESO_ERR_CORRUPT, MESO_ISSUE_FILE_TRAILING);
    put64(big + MESO_HDR_OFF_FILE_SIZE, size + 64); /* claims the extra block */
    fix_crcs(big);
    EXPECT(big, size + 64, MESO_ERR_CORRUPT, MESO_ISSUE_FILE_END);
    free(big);
    /* STHK is 16 bytes: 48 bytes of padding follow it. */
    uint32_t i = chunk_of(m, MESO_CHUNK_STHK);
    payload(m, i)[16 + 20] = 0x5A;
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_PAYLOAD_PADDING);
    meso_error e;
    assert(open_and_validate(m, size, &e) == MESO_ERR_CORRUPT);
    assert(e.offset == get64(entry(m, i) + MESO_TOC_OFF_OFFSET) + 36);
    free(m);
}

static void set_payload(uint8_t* m, uint32_t i, const char* s)
{
    size_t n = (size_t)get64(entry(m, i) + MESO_TOC_OFF_STORED_SIZE);
    assert(strlen(s) == n);
    memcpy(payload(m, i), s, n);
    fix_payload_crc(m, i);
    fix_crcs(m);
}

static void bad_json_in_meta_is_rejected(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    uint32_t i = chunk_of(m, MESO_CHUNK_META);
    size_t n = (size_t)get64(entry(m, i) + MESO_TOC_OFF_STORED_SIZE);
    char* s = (char*)malloc(n + 1);
    assert(n >= 140);
    /* Syntax: a trailing comma, padded with spaces to the same length. */
    memset(s, ' ', n);
    s[n] = 0;
    memcpy(s, "{\"a\":1,}", 8);
    set_payload(m, i, s);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_JSON_SYNTAX);
    memcpy(s, "{\"a\":01}", 8);
    set_payload(m, i, s);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_JSON_SYNTAX);
    memcpy(s, "{\"a\":\"\x01\"}", 9);
    set_payload(m, i, s);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_JSON_SYNTAX);
    memcpy(s, "{} {}    ", 9);
    set_payload(m, i, s);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_JSON_SYNTAX);
    memcpy(s, "\"\xED\xA0\x80\"  ", 7); /* a UTF-16 surrogate encoded in UTF-8 */
    set_payload(m, i, s);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_JSON_UTF8);
    /* Nesting deeper than the limit: [[[[...]]]] */
    memset(s, ' ', n);
    for (size_t k = 0; k < 70; k++) {
        s[k] = '[';
        s[139 - k] = ']';
    }
    set_payload(m, i, s);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_JSON_DEPTH);
    memset(s, ' ', n);
    for (size_t k = 0; k < 60; k++) {
        s[k] = '[';
        s[119 - k] = ']';
    }
    set_payload(m, i, s);
    EXPECT(m, size, MESO_OK, 0);
    free(s);
    free(m);
}

static void bad_mesh_contents_are_rejected(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    uint32_t i = chunk_of(m, MESO_CHUNK_MESH);
    uint8_t* p = payload(m, i);
    size_t n = (size_t)get64(entry(m, i) + MESO_TOC_OFF_STORED_SIZE);
    uint8_t* saved = (uint8_t*)malloc(n);
    memcpy(saved, p, n);
    uint64_t idx_off = get64(p + MESO_MESH_OFF_INDICES), pos_off = get64(p + MESO_MESH_OFF_POSITIONS);
#define MESH_CASE(stmt, code)                    \
    do {                                         \
        stmt;                                    \
        fix_payload_crc(m, i);                   \
        fix_crcs(m);                             \
        EXPECT(m, size, MESO_ERR_CORRUPT, code); \
        memcpy(p, saved, n);                     \
    } while (0)
    MESH_CASE(put32(p + idx_off + 8, 4), MESO_ISSUE_MESH_INDEX);
    MESH_CASE(put64(p + MESO_MESH_OFF_NORMALS, pos_off), MESO_ISSUE_MESH_OVERLAP);
    MESH_CASE(put64(p + MESO_MESH_OFF_INDICES, idx_off + 4), MESO_ISSUE_MESH_ALIGN);
    MESH_CASE(put64(p + MESO_MESH_OFF_INDICES, idx_off + 16), MESO_ISSUE_MESH_BOUNDS);
    MESH_CASE(put64(p + MESO_MESH_OFF_INDICES, idx_off - 16), MESO_ISSUE_MESH_OVERLAP);
    MESH_CASE(put32(p + MESO_MESH_OFF_INDEX_COUNT, 11), MESO_ISSUE_MESH_COUNTS);
    MESH_CASE(put32(p + MESO_MESH_OFF_INDEX_COUNT, 9), MESO_ISSUE_MESH_TRAILING);
    MESH_CASE(put32(p + MESO_MESH_OFF_VERTEX_COUNT, 0), MESO_ISSUE_MESH_COUNTS);
    MESH_CASE(put32(p + MESO_MESH_OFF_VERTEX_COUNT, 0x40000000u), MESO_ISSUE_MESH_BOUNDS);
    MESH_CASE(put32(p + MESO_MESH_OFF_ATTRIBUTES, 6), MESO_ISSUE_MESH_ATTRIBUTES);
    MESH_CASE(put32(p + MESO_MESH_OFF_ATTRIBUTES, 0xF), MESO_ISSUE_MESH_ATTRIBUTES);
    MESH_CASE(put32(p + MESO_MESH_OFF_ATTRIBUTES, 3), MESO_ISSUE_MESH_PRESENCE);
    MESH_CASE(p[MESO_MESH_OFF_QUANT_POSITION] = 31, MESO_ISSUE_MESH_QUANT);
    MESH_CASE(p[MESO_MESH_OFF_RESERVED0] = 1, MESO_ISSUE_MESH_RESERVED);
    MESH_CASE(p[MESO_MESH_OFF_RESERVED1 + 3] = 1, MESO_ISSUE_MESH_RESERVED);
#undef MESH_CASE
    /* read_chunk checks the mesh too. */
    put32(p + idx_off + 8, 4);
    fix_payload_crc(m, i);
    fix_crcs(m);
    meso_file* f = NULL;
    meso_error e;
    assert(meso_file_open_memory(m, size, NULL, &f, &e) == MESO_OK);
    uint8_t* buf = (uint8_t*)malloc(n);
    assert(meso_file_read_chunk(f, i, buf, n, &e) == MESO_ERR_CORRUPT && e.code == MESO_ISSUE_MESH_INDEX);
    meso_mesh_view v;
    assert(meso_mesh_parse(buf, n, &v, &e) == MESO_ERR_CORRUPT && e.code == MESO_ISSUE_MESH_INDEX);
    meso_file_close(f);
    free(buf);
    free(saved);
    free(m);
}

static void bad_records_are_rejected(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    uint32_t o = chunk_of(m, MESO_CHUNK_OBJT), s = chunk_of(m, MESO_CHUNK_SKEL), fr = chunk_of(m, MESO_CHUNK_FRUS);
    uint8_t saved[128];
#define REC_CASE(i, stmt, code)                  \
    do {                                         \
        memcpy(saved, payload(m, i), 96);        \
        stmt;                                    \
        fix_payload_crc(m, i);                   \
        fix_crcs(m);                             \
        EXPECT(m, size, MESO_ERR_CORRUPT, code); \
        memcpy(payload(m, i), saved, 96);        \
        fix_payload_crc(m, i);                   \
    } while (0)
    uint8_t* p = payload(m, o);
    REC_CASE(o, put32(p + 64, 1), MESO_ISSUE_OBJT_DUPLICATE);
    REC_CASE(o, put32(p + 0, 0), MESO_ISSUE_OBJT_ID);
    REC_CASE(o, put32(p + 4, 0), MESO_ISSUE_OBJT_KIND);
    REC_CASE(o, put32(p + 4, 5), MESO_ISSUE_OBJT_KIND);
    REC_CASE(o, memset(p + 32, 'a', 32), MESO_ISSUE_OBJT_NAME);
    REC_CASE(o, p[32 + 10] = 'z', MESO_ISSUE_OBJT_NAME);          /* garbage after the NUL */
    REC_CASE(o, put32(p + 8, 0x7FC00000u), MESO_ISSUE_OBJT_BBOX); /* NaN */
    REC_CASE(o, put32(p + 8, 0x40000000u), MESO_ISSUE_OBJT_BBOX); /* min 2 > max 1 */
    p = payload(m, s);
    REC_CASE(s, put32(p + 32 + 16, 1), MESO_ISSUE_SKEL_PARENT);     /* its own parent */
    REC_CASE(s, put32(p + 16, 2), MESO_ISSUE_SKEL_PARENT);          /* a later node */
    REC_CASE(s, put32(p + 12, 0xBF800000u), MESO_ISSUE_SKEL_VALUE); /* radius -1 */
    p = payload(m, fr);
    REC_CASE(fr, put32(p + 28, 0xBF800000u), MESO_ISSUE_FRUS_VALUE);
    REC_CASE(fr, put32(p + 60, 1), MESO_ISSUE_FRUS_VALUE);
#undef REC_CASE
    fix_crcs(m);
    EXPECT(m, size, MESO_OK, 0);
    free(m);
}

/* FSEG and BALL records (FORMAT.md §7.6, §7.7): a valid pair is accepted,
 * and each broken rule is refused by the writer with the reader's code. */
static void putf(uint8_t* p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put32(p, u);
}

static void fseg_record(uint8_t* r, uint32_t flags, int32_t other0, int32_t other1, int32_t align)
{
    memset(r, 0, MESO_FSEG_RECORD_SIZE);
    put32(r + MESO_FSEG_OFF_NODE0, 0);
    put32(r + MESO_FSEG_OFF_NODE1, 1);
    putf(r + MESO_FSEG_OFF_NODE_RADIUS0, 0.3f);
    putf(r + MESO_FSEG_OFF_NODE_RADIUS1, 0.2f);
    put32(r + MESO_FSEG_OFF_OTHER0, (uint32_t)other0);
    put32(r + MESO_FSEG_OFF_OTHER1, (uint32_t)other1);
    put32(r + MESO_FSEG_OFF_FLAGS, flags);
    put32(r + MESO_FSEG_OFF_ALIGN_FROM, (uint32_t)align);
    putf(r + MESO_FSEG_OFF_FRAME_X, 1.0f);
    putf(r + MESO_FSEG_OFF_U_SCALE, 1.0f);
    putf(r + MESO_FSEG_OFF_V_SCALE, 1.0f);
}

static meso_result add_records(uint32_t type, const uint8_t* data, size_t size, meso_error* e)
{
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    meso_chunk_desc d = {.type = type, .object = 1, .dims = {1, 1, 1}};
    meso_result r = meso_writer_add(w, &d, data, size, e);
    meso_writer_destroy(w);
    return r;
}

static void bad_frusta_records_are_rejected(void)
{
    const uint32_t joint1 = MESO_FSEG_END_JOINT << MESO_FSEG_KIND1_SHIFT;
    const uint32_t joint0 = MESO_FSEG_END_JOINT << MESO_FSEG_KIND0_SHIFT;
    uint8_t seg[2 * MESO_FSEG_RECORD_SIZE], ball[MESO_BALL_RECORD_SIZE];
    meso_error e;
    /* frustum 0 (tip, cap | joint with 1), frustum 1 (joint with 0 | ball), aligned from 0 */
    fseg_record(seg, joint1 | MESO_FSEG_CAP0, -1, 1, -1);
    fseg_record(seg + MESO_FSEG_RECORD_SIZE, joint0 | (MESO_FSEG_END_BALL << MESO_FSEG_KIND1_SHIFT), 0, -1, 0);
    assert(add_records(MESO_CHUNK_FSEG, seg, sizeof seg, &e) == MESO_OK);
    memset(ball, 0, sizeof ball);
    putf(ball + MESO_BALL_OFF_RADIUS, 0.25f);
    put32(ball + MESO_BALL_OFF_NODE, 2);
    assert(add_records(MESO_CHUNK_BALL, ball, sizeof ball, &e) == MESO_OK);
    uint8_t* r1 = seg + MESO_FSEG_RECORD_SIZE;
#define FSEG_CASE(stmt, want)                                                            \
    do {                                                                                 \
        uint8_t keep[sizeof seg];                                                        \
        memcpy(keep, seg, sizeof seg);                                                   \
        stmt;                                                                            \
        memset(&e, 0, sizeof e);                                                         \
        assert(add_records(MESO_CHUNK_FSEG, seg, sizeof seg, &e) == MESO_ERR_INVALID_ARG); \
        assert(e.code == (want));                                                        \
        memcpy(seg, keep, sizeof seg);                                                   \
    } while (0)
    const uint32_t V = MESO_ISSUE_FSEG_VALUE;
    FSEG_CASE(put32(r1 + MESO_FSEG_OFF_FLAGS, get32(r1 + MESO_FSEG_OFF_FLAGS) | (1u << 8)), V); /* unknown bit */
    FSEG_CASE(put32(seg + MESO_FSEG_OFF_FLAGS, 3u), V);                         /* end kind 3 */
    FSEG_CASE(put32(seg + MESO_FSEG_OFF_ALIGN_FROM, 1), V);                     /* aligned from a later one */
    FSEG_CASE(put32(r1 + MESO_FSEG_OFF_ALIGN_FROM, 0xFFFFFFFEu), V);            /* -2 */
    FSEG_CASE(put32(r1 + MESO_FSEG_OFF_OTHER0, 0xFFFFFFFFu), V);                /* joint without a partner */
    FSEG_CASE(put32(seg + MESO_FSEG_OFF_OTHER0, 1), V);                         /* partner at a tip */
    FSEG_CASE(put32(r1 + MESO_FSEG_OFF_OTHER0, 1), V);                          /* its own partner */
    FSEG_CASE(put32(r1 + MESO_FSEG_OFF_OTHER0, 5), V);                          /* out of range */
    FSEG_CASE(put32(seg + MESO_FSEG_OFF_FRAME_X + 4, 0x7FC00000u), V);          /* NaN */
    FSEG_CASE(putf(seg + MESO_FSEG_OFF_RELIEF_DEPTH, -1.0f), V);                /* negative depth */
    FSEG_CASE(putf(r1 + MESO_FSEG_OFF_NODE_RADIUS1, -0.5f), V);                 /* negative radius */
    FSEG_CASE(seg[MESO_FSEG_OFF_RESERVED + 11] = 1, V);                         /* reserved */
#undef FSEG_CASE
    assert(add_records(MESO_CHUNK_FSEG, seg, sizeof seg - 1, &e) == MESO_ERR_INVALID_ARG &&
           e.code == MESO_ISSUE_FSEG_SIZE);
    uint8_t b2[sizeof ball];
#define BALL_CASE(stmt, want)                                                              \
    do {                                                                                   \
        memcpy(b2, ball, sizeof ball);                                                     \
        stmt;                                                                              \
        memset(&e, 0, sizeof e);                                                           \
        assert(add_records(MESO_CHUNK_BALL, b2, sizeof b2, &e) == MESO_ERR_INVALID_ARG);   \
        assert(e.code == (want));                                                          \
    } while (0)
    BALL_CASE(putf(b2 + MESO_BALL_OFF_RADIUS, -1.0f), MESO_ISSUE_BALL_VALUE);
    BALL_CASE(put32(b2 + MESO_BALL_OFF_CENTER + 8, 0x7F800000u), MESO_ISSUE_BALL_VALUE); /* inf */
    BALL_CASE(b2[MESO_BALL_OFF_RESERVED] = 1, MESO_ISSUE_BALL_VALUE);
#undef BALL_CASE
    assert(add_records(MESO_CHUNK_BALL, ball, sizeof ball - 4, &e) == MESO_ERR_INVALID_ARG &&
           e.code == MESO_ISSUE_BALL_SIZE);
    /* FSEG and BALL must be BYTES x 1 */
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    meso_chunk_desc d = {.type = MESO_CHUNK_BALL, .object = 1, .dtype = MESO_DTYPE_F32, .components = 4,
                         .dims = {2, 1, 1}};
    assert(meso_writer_add(w, &d, ball, sizeof ball, &e) == MESO_ERR_INVALID_ARG &&
           e.code == MESO_ISSUE_TYPE_ELEMENT);
    meso_writer_destroy(w);
}

/* >>decoded sizes of encoded chunks (issues 2021, 2022) */

typedef struct never_decoder {
    int calls;
} never_decoder;


/* >>cells objects (FORMAT.md §7.8): a hand-built object of 2 x 1 x 1 tiles of
 * 2^3 voxels, 2 split cells of one cell; tile 0 MIXED (split 1 INSIDE, split
 * 2 INTERSECTED), tile 1 INSIDE. */
typedef struct cells_bytes {
    uint8_t cell[MESO_CELL_RECORD_SIZE];
    uint16_t tile[8];
    uint32_t splt[2 * MESO_SPLT_COMPONENTS];
    uint32_t memb[3];
    uint32_t tile_dims[3], memb_words;
    int skip_colr;
    uint16_t lod; /* > 0: these chunks at this lod, beside a sound copy at lod 0 (a native coarser level) */
} cells_bytes;

static void cells_sample(cells_bytes* c)
{
    memset(c, 0, sizeof *c);
    put32(c->cell + MESO_CELL_OFF_TILES, 2);
    put32(c->cell + MESO_CELL_OFF_TILES + 4, 1);
    put32(c->cell + MESO_CELL_OFF_TILES + 8, 1);
    put32(c->cell + MESO_CELL_OFF_TILE_RES, 2);
    put32(c->cell + MESO_CELL_OFF_SPLIT_COUNT, 2);
    put32(c->cell + MESO_CELL_OFF_CELL_COUNT, 1);
    putf(c->cell + MESO_CELL_OFF_VOXEL_SIZE, 0.5f);
    put32(c->cell + MESO_CELL_OFF_MIXED_TILES, 1);
    static const uint16_t tile[8] = {0, 1, 1, 2, 0, 0, 2, 1};
    memcpy(c->tile, tile, sizeof tile);
    static const uint32_t splt[12] = {1, 1, 1, 0, 0, 0, 1, 2, 1, 0, 0, 0};
    memcpy(c->splt, splt, sizeof splt);
    c->memb[0] = 2u | (1u << 2); /* tile 0 MIXED, tile 1 INSIDE */
    c->memb[1] = 0;               /* rank */
    c->memb[2] = 1u | (2u << 2);  /* split 1 INSIDE, split 2 INTERSECTED */
    c->tile_dims[0] = c->tile_dims[1] = c->tile_dims[2] = 2;
    c->memb_words = 3;
}

static int first_issue(void* user, const meso_error* issue)
{
    meso_error* e = (meso_error*)user;
    if (e->code == 0)
        *e = *issue;
    return 0;
}

/* Add the object's six cells chunks at `lod`. */
static void cells_add(meso_writer* w, const cells_bytes* c, uint16_t lod, meso_error* e)
{
    static uint16_t nrmm[16];
    static uint8_t colr[32];
    const uint32_t REQ = MESO_CHUNK_FLAG_REQUIRED;
    meso_chunk_desc d[6] = {
        {.type = MESO_CHUNK_CELL, .flags = REQ, .object = 1},
        {.type = MESO_CHUNK_TILE, .flags = REQ, .object = 1, .dtype = MESO_DTYPE_U16,
         .dims = {c->tile_dims[0], c->tile_dims[1], c->tile_dims[2]}},
        {.type = MESO_CHUNK_SPLT, .flags = REQ, .object = 1, .dtype = MESO_DTYPE_U32, .components = 6, .dims = {2, 1, 1}},
        {.type = MESO_CHUNK_MEMB, .flags = REQ, .object = 1, .dtype = MESO_DTYPE_U32, .dims = {c->memb_words, 1, 1}},
        {.type = MESO_CHUNK_NRMM, .object = 1, .dtype = MESO_DTYPE_U16, .components = 2, .dims = {2, 2, 2}},
        {.type = MESO_CHUNK_COLR, .object = 1, .dtype = MESO_DTYPE_U8, .components = 4, .dims = {2, 2, 2}},
    };
    const void* data[6] = {c->cell, c->tile, c->splt, c->memb, nrmm, colr};
    const size_t size[6] = {sizeof c->cell, 2u * c->tile_dims[0] * c->tile_dims[1] * c->tile_dims[2], sizeof c->splt,
                            4u * c->memb_words, sizeof nrmm, sizeof colr};
    for (int i = 0; i < 6 - c->skip_colr; i++) {
        d[i].lod = lod;
        assert(meso_writer_add(w, &d[i], data[i], size[i], e) == MESO_OK);
    }
}

/* Write the object, open it, return meso_file_check_cells_level's result
 * at c->lod (lod 0: meso_file_check_cells); the full validator must report
 * the same code, and a sound lod 0 beside a broken level must pass. */
static meso_result cells_check(const cells_bytes* c, meso_error* e)
{
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    cells_add(w, c, c->lod, e);
    if (c->lod) {
        cells_bytes good;
        cells_sample(&good);
        cells_add(w, &good, 0, e);
    }
    size_t n = 0;
    assert(meso_writer_finish(w, NULL, 0, &n) == MESO_OK);
    uint8_t* mem = (uint8_t*)malloc(n);
    assert(mem && meso_writer_finish(w, mem, n, &n) == MESO_OK);
    meso_writer_destroy(w);
    meso_file* f = NULL;
    assert(meso_file_open_memory(mem, n, NULL, &f, e) == MESO_OK);
    memset(e, 0, sizeof *e);
    meso_result r = c->lod ? meso_file_check_cells_level(f, 1, c->lod, e) : meso_file_check_cells(f, 1, e);
    if (c->lod) {
        meso_error e0;
        assert(meso_file_check_cells(f, 1, &e0) == MESO_OK);
    }
    meso_error first;
    memset(&first, 0, sizeof first);
    meso_result full = meso_file_validate(f, MESO_CHECK_FULL, first_issue, &first);
    assert(full == r && first.code == e->code);
    meso_file_close(f);
    free(mem);
    return r;
}

static void bad_cells_objects_are_rejected(void)
{
    cells_bytes c;
    meso_error e;
    cells_sample(&c);
    assert(cells_check(&c, &e) == MESO_OK);
    /* CELL itself (the writer refuses it) */
    uint8_t rec[MESO_CELL_RECORD_SIZE];
#define CELL_CASE(stmt, want)                                                                  \
    do {                                                                                       \
        memcpy(rec, c.cell, sizeof rec);                                                       \
        stmt;                                                                                  \
        memset(&e, 0, sizeof e);                                                               \
        assert(add_records(MESO_CHUNK_CELL, rec, sizeof rec, &e) == MESO_ERR_INVALID_ARG);     \
        assert(e.code == (want));                                                              \
    } while (0)
    const uint32_t V = MESO_ISSUE_CELL_VALUE;
    assert(add_records(MESO_CHUNK_CELL, c.cell, sizeof c.cell, &e) == MESO_OK);
    CELL_CASE(put32(rec + MESO_CELL_OFF_TILES + 4, 0), V);              /* no tiles */
    CELL_CASE(put32(rec + MESO_CELL_OFF_TILES, 16385), V);              /* too many */
    CELL_CASE(put32(rec + MESO_CELL_OFF_TILE_RES, 1025), V);            /* R too large */
    CELL_CASE(put32(rec + MESO_CELL_OFF_SPLIT_COUNT, 0), V);            /* no split cells */
    CELL_CASE(put32(rec + MESO_CELL_OFF_CELL_COUNT, 3), V);             /* more cells than split cells */
    CELL_CASE(putf(rec + MESO_CELL_OFF_VOXEL_SIZE, 0.0f), V);           /* h = 0 */
    CELL_CASE(put32(rec + MESO_CELL_OFF_ORIGIN + 4, 0x7FC00000u), V);   /* NaN */
    CELL_CASE(put32(rec + MESO_CELL_OFF_MIXED_TILES, 3), V);            /* M > T */
    CELL_CASE(rec[MESO_CELL_OFF_RESERVED + 15] = 1, V);                 /* reserved */
#undef CELL_CASE
    assert(add_records(MESO_CHUNK_CELL, c.cell, sizeof c.cell - 4, &e) == MESO_ERR_INVALID_ARG &&
           e.code == MESO_ISSUE_CELL_SIZE);
    /* the chunks against CELL */
#define CELLS_CASE(stmt, want)                                                 \
    do {                                                                       \
        cells_sample(&c);                                                      \
        stmt;                                                                  \
        assert(cells_check(&c, &e) == MESO_ERR_CORRUPT && e.code == (want));   \
    } while (0)
    CELLS_CASE(c.skip_colr = 1, MESO_ISSUE_CELL_CHUNKS);                         /* COLR missing */
    CELLS_CASE(c.tile_dims[2] = 1, MESO_ISSUE_CELL_CHUNKS);                      /* TILE 2 x 2 x 1 */
    CELLS_CASE(put32(c.cell + MESO_CELL_OFF_MIXED_TILES, 0), MESO_ISSUE_CELL_CHUNKS); /* MEMB longer than CELL says */
    CELLS_CASE(c.tile[5] = 3, MESO_ISSUE_CELL_TILE);                             /* split cell 3 of 2 */
    CELLS_CASE(c.splt[MESO_SPLT_COMPONENTS] = 3, MESO_ISSUE_CELL_SPLT);          /* cell ids 1, 3 */
    CELLS_CASE(c.splt[0] = 2, MESO_ISSUE_CELL_SPLT);                             /* not starting at 1 */
    CELLS_CASE(c.splt[MESO_SPLT_FACE_CODE] = 64, MESO_ISSUE_CELL_SPLT);          /* face code */
    CELLS_CASE(c.splt[MESO_SPLT_TILE_INDEX] = 0, MESO_ISSUE_CELL_SPLT);          /* tile-map index 0 */
    CELLS_CASE(c.memb[0] = 2u | (3u << 2), MESO_ISSUE_CELL_MEMB);                /* class 3 */
    CELLS_CASE(c.memb[0] |= 1u << 4, MESO_ISSUE_CELL_MEMB);                      /* bits past tile 1 */
    CELLS_CASE(c.memb[1] = 1, MESO_ISSUE_CELL_MEMB);                             /* rank */
    CELLS_CASE(c.memb[0] = 1u | (1u << 2), MESO_ISSUE_CELL_MEMB);                /* no MIXED tile, CELL says 1 */
    CELLS_CASE(c.memb[2] = 3u, MESO_ISSUE_CELL_MEMB);                            /* tag 3 */
    CELLS_CASE(c.memb[2] |= 1u << 4, MESO_ISSUE_CELL_MEMB);                      /* bits past split cell 2 */
    /* a native coarser level's own chunks (FORMAT.md 7.10), checked at its lod */
    CELLS_CASE((c.lod = 1, c.tile[5] = 3), MESO_ISSUE_CELL_TILE);
    CELLS_CASE((c.lod = 2, c.memb[1] = 1), MESO_ISSUE_CELL_MEMB);
    CELLS_CASE((c.lod = 1, c.skip_colr = 1), MESO_ISSUE_CELL_CHUNKS); /* resolves to... nothing at lod >= 1 */
    cells_sample(&c);
    c.lod = 1;
    assert(cells_check(&c, &e) == MESO_OK);
#undef CELLS_CASE
}

static meso_result must_not_decode(void* user, const meso_chunk_info* chunk, const void* src, size_t src_size,
                                   void* dst, size_t dst_size, meso_error* err)
{
    (void)chunk, (void)src, (void)src_size, (void)dst, (void)dst_size, (void)err;
    ((never_decoder*)user)->calls++;
    return MESO_ERR_CORRUPT;
}

typedef struct io_over_memory {
    const uint8_t* data;
    size_t size;
} io_over_memory;

static int io_over_memory_read(void* user, uint64_t off, void* dst, size_t n)
{
    io_over_memory* m = (io_over_memory*)user;
    if (off > m->size || n > m->size - off)
        return 1;
    memcpy(dst, m->data + off, n);
    return 0;
}

/* Open over memory and over the io callback with a tracking allocator and a
 * decoder that must never run; validate FULL when open succeeds. Both
 * readers must agree; returns the open result, *e the open error. */
static meso_result open_both_tracked(const uint8_t* m, size_t size, uint64_t max_decoded, meso_error* e,
                                     size_t* largest)
{
    biggest b = {0};
    never_decoder nd = {0};
    meso_decoder dec = {MESO_ENCODING_DRACO, must_not_decode, &nd};
    meso_open_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.allocator.alloc_fn = track_alloc;
    desc.allocator.free_fn = track_free;
    desc.allocator.user = &b;
    desc.decoders = &dec;
    desc.decoder_count = 1;
    desc.max_decoded_size = max_decoded;
    meso_file* f = NULL;
    meso_result r = meso_file_open_memory(m, size, &desc, &f, e);
    if (r == MESO_OK) {
        meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL);
        meso_file_close(f);
    } else {
        assert(f == NULL && e->result == r);
    }
    io_over_memory src = {m, size};
    meso_io io = {io_over_memory_read, size, &src};
    meso_error e2;
    meso_result r2 = meso_file_open_io(&io, &desc, &f, &e2);
    assert(r2 == r && (r == MESO_OK || e2.code == e->code));
    if (r2 == MESO_OK) {
        meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL);
        meso_file_close(f);
    }
    *largest = b.max;
    return r;
}

/* One unknown optional BYTES chunk ('ZZZ1', allowed to use any encoding on
 * open) of `stored` bytes, Draco-encoded with the given decoded_size, which
 * is patched in after writing (the writer refuses what the reader would). */
static uint8_t* encoded_file(size_t stored, uint64_t decoded, size_t* size)
{
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    uint8_t* data = (uint8_t*)malloc(stored);
    fill_pattern(data, stored, 7);
    meso_chunk_desc d;
    memset(&d, 0, sizeof d);
    d.type = MESO_FOURCC('Z', 'Z', 'Z', '1');
    d.encoding = MESO_ENCODING_DRACO;
    d.decoded_size = stored;
    meso_error e;
    assert(meso_writer_add(w, &d, data, stored, &e) == MESO_OK);
    uint8_t* m = writer_to_memory(w, size);
    meso_writer_destroy(w);
    free(data);
    put64(entry(m, 0) + MESO_TOC_OFF_DECODED_SIZE, decoded);
    fix_crcs(m);
    return m;
}

static void draco_expansion_is_bounded_on_open(void)
{
    const size_t stored = 300;
    const uint64_t bound = (uint64_t)stored * MESO_DRACO_MAX_EXPANSION + MESO_DRACO_EXPANSION_SLACK;
    size_t size, largest;
    meso_error e;
    uint8_t* m = encoded_file(stored, bound, &size);
    assert(open_both_tracked(m, size, 0, &e, &largest) == MESO_OK); /* at the bound: fine */
    free(m);
    m = encoded_file(stored, bound + 1, &size);
    assert(open_both_tracked(m, size, 0, &e, &largest) == MESO_ERR_CORRUPT);
    assert(e.code == MESO_ISSUE_CHUNK_EXPANSION && e.chunk == 0);
    assert(e.offset == MESO_HDR_SIZE + MESO_TOC_OFF_DECODED_SIZE && strstr(e.message, "decoded_size"));
    assert(largest < 65536);
    /* No overflow in stored_size x 1024 for absurd sizes: bounds catch those. */
    put64(entry(m, 0) + MESO_TOC_OFF_STORED_SIZE, UINT64_MAX / 2);
    put64(entry(m, 0) + MESO_TOC_OFF_DECODED_SIZE, UINT64_MAX);
    fix_crcs(m);
    EXPECT(m, size, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_BOUNDS);
    free(m);
    /* The writer refuses it too, with the reader's code. */
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    uint8_t data[300] = {0};
    meso_chunk_desc d;
    memset(&d, 0, sizeof d);
    d.type = MESO_FOURCC('Z', 'Z', 'Z', '1');
    d.encoding = MESO_ENCODING_DRACO;
    d.decoded_size = bound + 1;
    assert(meso_writer_add(w, &d, data, sizeof data, &e) == MESO_ERR_INVALID_ARG);
    assert(e.code == MESO_ISSUE_CHUNK_EXPANSION);
    d.decoded_size = bound;
    assert(meso_writer_add(w, &d, data, sizeof data, &e) == MESO_OK);
    meso_writer_destroy(w);
}

static void max_decoded_size_limits_encoded_chunks_only(void)
{
    size_t size, largest;
    meso_error e;
    /* Within the expansion bound, above the caller's limit: UNSUPPORTED. */
    uint8_t* m = encoded_file(300, 100000, &size);
    assert(open_both_tracked(m, size, 100000, &e, &largest) == MESO_OK);
    assert(open_both_tracked(m, size, 99999, &e, &largest) == MESO_ERR_UNSUPPORTED);
    assert(e.code == MESO_ISSUE_CHUNK_DECODED_LIMIT && e.chunk == 0 && strstr(e.message, "max_decoded_size"));
    assert(largest < 65536);
    free(m);
    /* The default is 1 GiB (a 1 MiB payload may expand that far). */
    m = encoded_file((size_t)1 << 20, MESO_DEFAULT_MAX_DECODED_SIZE, &size);
    assert(open_both_tracked(m, size, 0, &e, &largest) == MESO_OK);
    put64(entry(m, 0) + MESO_TOC_OFF_DECODED_SIZE, MESO_DEFAULT_MAX_DECODED_SIZE + 1);
    fix_crcs(m);
    assert(open_both_tracked(m, size, 0, &e, &largest) == MESO_ERR_UNSUPPORTED);
    assert(e.code == MESO_ISSUE_CHUNK_DECODED_LIMIT);
    assert(open_both_tracked(m, size, MESO_DEFAULT_MAX_DECODED_SIZE + 1, &e, &largest) == MESO_OK);
    free(m);
    /* A corrupt entry is reported as corrupt, not as over the limit. */
    m = encoded_file(300, 100000, &size);
    put32(entry(m, 0) + MESO_TOC_OFF_RESERVED, 1);
    fix_crcs(m);
    assert(open_both_tracked(m, size, 1000, &e, &largest) == MESO_ERR_CORRUPT && e.code == MESO_ISSUE_CHUNK_RESERVED);
    free(m);
    /* Raw chunks are backed by the file: the limit does not apply. */
    m = fresh(&size);
    assert(open_both_tracked(m, size, 1, &e, &largest) == MESO_OK);
    free(m);
}

/* The fuzzer's reproducer, rebuilt: a Draco MESH of a few hundred bytes whose
 * (self-consistent) mesh header claims 10^9 vertices. Open refuses it before
 * anything is allocated or decoded, on every reader. */
static void tiny_draco_mesh_claiming_a_billion_vertices_allocates_nothing(void)
{
    meso_mesh_layout l;
    assert(meso_mesh_compute_layout(1000000000u, 12, MESO_MESH_ATTR_POSITIONS | MESO_MESH_ATTR_NORMALS, &l) ==
           MESO_OK);
    uint8_t payload_bytes[256];
    memset(payload_bytes, 0xA5, sizeof payload_bytes);
    meso_mesh_write_header(&l, payload_bytes);
    /* Write it with an honest decoded_size, then patch in the claim. */
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    meso_chunk_desc d;
    memset(&d, 0, sizeof d);
    d.type = MESO_FOURCC('Z', 'Z', 'Z', '1');
    d.encoding = MESO_ENCODING_DRACO;
    d.decoded_size = sizeof payload_bytes;
    meso_error e;
    assert(meso_writer_add(w, &d, payload_bytes, sizeof payload_bytes, &e) == MESO_OK);
    size_t size, largest;
    uint8_t* m = writer_to_memory(w, &size);
    meso_writer_destroy(w);
    put32(entry(m, 0) + MESO_TOC_OFF_TYPE, MESO_CHUNK_MESH);
    put32(entry(m, 0) + MESO_TOC_OFF_OBJECT, 1);
    put64(entry(m, 0) + MESO_TOC_OFF_DECODED_SIZE, l.size);
    fix_crcs(m);
    assert(l.size > ((uint64_t)20 << 30)); /* 24 GB */
    assert(open_both_tracked(m, size, 0, &e, &largest) == MESO_ERR_CORRUPT);
    assert(e.code == MESO_ISSUE_CHUNK_EXPANSION && largest < 65536);
    /* Even a caller that lifts the limit gets the format rule. */
    assert(open_both_tracked(m, size, UINT64_MAX, &e, &largest) == MESO_ERR_CORRUPT);
    assert(e.code == MESO_ISSUE_CHUNK_EXPANSION && largest < 65536);
    free(m);
}

/* read_chunk applies the type's element/encoding rules (FORMAT.md §7 table),
 * so open + read_chunk checks what validate FULL checks for that chunk. */
static void read_chunk_applies_the_type_rules(void)
{
    size_t size;
    uint8_t* m = fresh(&size);
    uint32_t i = chunk_of(m, MESO_CHUNK_SDIR);
    put16(entry(m, i) + MESO_TOC_OFF_DTYPE, MESO_DTYPE_U32); /* SDIR must be F32 x 3; same size */
    fix_crcs(m);
    meso_file* f = NULL;
    meso_error e;
    assert(meso_file_open_memory(m, size, NULL, &f, &e) == MESO_OK);
    uint8_t buf[4096];
    assert(meso_file_read_chunk(f, i, buf, sizeof buf, &e) == MESO_ERR_CORRUPT && e.code == MESO_ISSUE_TYPE_ELEMENT);
    assert(meso_file_read_stored(f, i, buf, sizeof buf, &e) == MESO_OK); /* stored bytes: CRC only */
    meso_file_close(f);
    free(m);
}

int main(void)
{
    sample_is_valid();
    every_truncated_prefix_is_rejected();
    every_header_and_toc_bit_flip_and_sampled_payload_flips_are_detected();
    wrong_magic_is_bad_magic();
    text_mode_and_7bit_damage_have_their_own_codes();
    newer_major_is_refused_and_major_zero_is_legacy();
    newer_minor_is_read_and_skips_unknown_optional_chunks();
    unknown_encoding_is_corrupt_in_known_minors_and_unsupported_at_read_in_newer_ones();
    larger_toc_entries_from_a_newer_minor_are_read();
    chunk_ranges_order_and_alignment_are_checked();
    absurd_chunk_count_allocates_nothing_large();
    header_size_fields_are_checked();
    toc_entry_fields_are_checked();
    checksum_mismatches_are_detected();
    trailing_bytes_and_padding_are_checked();
    bad_json_in_meta_is_rejected();
    bad_mesh_contents_are_rejected();
    bad_records_are_rejected();
    bad_frusta_records_are_rejected();
    bad_cells_objects_are_rejected();
    draco_expansion_is_bounded_on_open();
    max_decoded_size_limits_encoded_chunks_only();
    tiny_draco_mesh_claiming_a_billion_vertices_allocates_nothing();
    read_chunk_applies_the_type_rules();
    printf("test_format_corrupt: ok\n");
    return 0;
}
