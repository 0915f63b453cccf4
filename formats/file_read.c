/*
 * file_read.c — the .meso reader: four ways in (path, mmap, memory, host
 * callback), one parser. The parser sees the header and TOC as one buffer
 * (the first min(size, 64 KiB) bytes, re-read only when the TOC is larger)
 * and checks every field before it is used: nothing is allocated from a
 * count or size that was not first checked against the file size.
 */
#include "file_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

const uint8_t mesoi_magic[8] = {0x89, 'M', 'S', 'O', '\r', '\n', 0x1A, '\n'};

#define FIRST_READ (64u * 1024u) /* covers header + TOC of up to 1023 chunks */
#define DEFAULT_MAX_CHUNKS (1u << 20)

/* >>results & errors ------------------------------------------------------ */

const char* meso_result_string(meso_result r)
{
    switch (r) {
    case MESO_OK: return "ok";
    case MESO_ERR_TRUNCATED: return "truncated";
    case MESO_ERR_BAD_MAGIC: return "not a .meso file";
    case MESO_ERR_VERSION_TOO_NEW: return "format version too new";
    case MESO_ERR_CORRUPT: return "corrupt";
    case MESO_ERR_OUT_OF_MEMORY: return "out of memory";
    case MESO_ERR_IO: return "I/O error";
    case MESO_ERR_INVALID_ARG: return "invalid argument";
    case MESO_ERR_GL: return "OpenGL error";
    case MESO_ERR_UNSUPPORTED: return "not supported";
    case MESO_ERR_NOT_FOUND: return "not found";
    case MESO_ERR_PENDING: return "not arrived yet";
    default: return "unknown result";
    }
}

meso_result mesoi_file_error(meso_error* err, meso_result r, uint32_t code, uint64_t offset, int32_t chunk,
                             const char* fmt, ...)
{
    if (err) {
        err->result = r;
        err->code = code;
        err->offset = offset;
        err->chunk = chunk;
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return r;
}

void mesoi_file_error_clear(meso_error* err)
{
    if (err) {
        err->result = MESO_OK;
        err->code = MESO_ISSUE_NONE;
        err->offset = UINT64_MAX;
        err->chunk = -1;
        err->message[0] = 0;
    }
}

void mesoi_fourcc_str(uint32_t type, char out[5])
{
    for (int i = 0; i < 4; i++) {
        char ch = (char)(type >> (8 * i));
        out[i] = (ch >= 0x20 && ch <= 0x7E) ? ch : '?';
    }
    out[4] = 0;
}

/* >>memory ---------------------------------------------------------------- */

static void* default_alloc(size_t size, void* user)
{
    (void)user;
    return malloc(size);
}

static void default_free(void* p, void* user)
{
    (void)user;
    free(p);
}

meso_result mesoi_file_allocator_init(const meso_allocator* in, meso_allocator* out)
{
    if (in == NULL || (in->alloc_fn == NULL && in->free_fn == NULL)) {
        out->alloc_fn = default_alloc;
        out->free_fn = default_free;
        out->user = NULL;
        return MESO_OK;
    }
    if (in->alloc_fn == NULL || in->free_fn == NULL)
        return MESO_ERR_INVALID_ARG;
    *out = *in;
    return MESO_OK;
}

void* mesoi_file_alloc(const meso_allocator* a, size_t size) { return a->alloc_fn(size ? size : 1, a->user); }

void mesoi_file_free(const meso_allocator* a, void* p)
{
    if (p)
        a->free_fn(p, a->user);
}

/* >>byte sources ---------------------------------------------------------- */

meso_result mesoi_read_at(meso_file* f, uint64_t off, void* dst, size_t size, meso_error* err)
{
    switch (f->source) {
    case MESOI_SRC_MEMORY:
    case MESOI_SRC_MMAP:
        if (size)
            memcpy(dst, f->data + off, size);
        return MESO_OK;
    case MESOI_SRC_FD: {
        uint8_t* p = (uint8_t*)dst;
        while (size > 0) {
            size_t n = size > ((size_t)1 << 30) ? ((size_t)1 << 30) : size;
            ssize_t got = pread(f->fd, p, n, (off_t)off);
            if (got < 0 && errno == EINTR)
                continue;
            if (got <= 0)
                return mesoi_file_error(err, MESO_ERR_IO, MESO_ISSUE_IO_READ, off, -1,
                                        "read of %zu bytes at %llu failed: %s", n, (unsigned long long)off,
                                        got < 0 ? strerror(errno) : "unexpected end of file");
            p += got;
            off += (uint64_t)got;
            size -= (size_t)got;
        }
        return MESO_OK;
    }
    default: {
        const int rc = f->io.read_fn(f->io.user, off, dst, size);
        if (rc == MESO_IO_PENDING)
            return mesoi_file_error(err, MESO_ERR_PENDING, MESO_ISSUE_IO_READ, off, -1,
                                    "%zu bytes at offset %llu have not arrived yet", size, (unsigned long long)off);
        if (rc != 0)
            return mesoi_file_error(err, MESO_ERR_IO, MESO_ISSUE_IO_READ, off, -1,
                                    "read callback failed for %zu bytes at offset %llu", size, (unsigned long long)off);
        return MESO_OK;
    }
    }
}

meso_result mesoi_read_crc(meso_file* f, uint64_t off, void* dst, size_t size, uint32_t* crc, meso_error* err)
{
    uint8_t* p = (uint8_t*)dst;
    uint32_t c = *crc;
    while (size > 0) {
        size_t n = size < MESOI_READ_BLOCK ? size : MESOI_READ_BLOCK;
        meso_result r = mesoi_read_at(f, off, p, n, err);
        if (r != MESO_OK)
            return r;
        c = meso_crc32c(c, p, n);
        p += n;
        off += n;
        size -= n;
    }
    *crc = c;
    return MESO_OK;
}

const meso_decoder* mesoi_find_decoder(const meso_file* f, uint16_t encoding)
{
    for (uint32_t i = 0; i < f->decoder_count; i++)
        if (f->decoders[i].encoding == encoding && f->decoders[i].decode_fn)
            return &f->decoders[i];
    return NULL;
}

/* >>parsing --------------------------------------------------------------- */

/* Which kind of damage turned the magic into these bytes (issue code). */
static uint32_t magic_issue(const uint8_t* h)
{
    static const uint8_t lf_only[7] = {0x89, 'M', 'S', 'O', '\n', 0x1A, '\n'};
    static const uint8_t crlf_twice[8] = {0x89, 'M', 'S', 'O', '\r', '\r', '\n', 0x1A};
    if (memcmp(h, mesoi_magic, 8) == 0)
        return MESO_ISSUE_NONE;
    if (h[0] == 0x09 && memcmp(h + 1, mesoi_magic + 1, 7) == 0)
        return MESO_ISSUE_HDR_7BIT;
    if (memcmp(h, lf_only, 7) == 0 || memcmp(h, crlf_twice, 8) == 0 || (memcmp(h, mesoi_magic, 7) == 0 && h[7] == '\r'))
        return MESO_ISSUE_HDR_TEXT_MODE;
    return MESO_ISSUE_HDR_MAGIC;
}

typedef struct header {
    uint16_t major, minor;
    uint64_t file_size;
    uint32_t chunk_count, toc_entry_size, toc_crc;
} header;

static meso_result parse_header(const uint8_t* h, uint64_t actual, uint32_t max_chunks, header* out, meso_error* err)
{
    if (actual < MESO_HDR_SIZE)
        return mesoi_file_error(err, MESO_ERR_TRUNCATED, MESO_ISSUE_HDR_TRUNCATED, actual, -1,
                                "%llu bytes is shorter than the 64-byte .meso header", (unsigned long long)actual);
    uint32_t mi = magic_issue(h);
    if (mi == MESO_ISSUE_HDR_TEXT_MODE)
        return mesoi_file_error(
            err, MESO_ERR_BAD_MAGIC, mi, 0, -1,
            "the .meso magic was damaged by a text-mode (CR/LF) transfer; transfer the file as binary");
    if (mi == MESO_ISSUE_HDR_7BIT)
        return mesoi_file_error(err, MESO_ERR_BAD_MAGIC, mi, 0, -1,
                                "the .meso magic lost its high bit (7-bit transfer); transfer the file as binary");
    if (mi != MESO_ISSUE_NONE)
        return mesoi_file_error(err, MESO_ERR_BAD_MAGIC, mi, 0, -1, "not a .meso file (bad magic)");
    out->major = mesoi_ld16(h + MESO_HDR_OFF_MAJOR);
    out->minor = mesoi_ld16(h + MESO_HDR_OFF_MINOR);
    if (out->major == 0)
        return mesoi_file_error(err, MESO_ERR_BAD_MAGIC, MESO_ISSUE_HDR_LEGACY, MESO_HDR_OFF_MAJOR, -1,
                                "format %u.%u is a pre-release/legacy version this reader does not read", out->major,
                                out->minor);
    if (out->major > MESO_FORMAT_MAJOR)
        return mesoi_file_error(err, MESO_ERR_VERSION_TOO_NEW, MESO_ISSUE_HDR_TOO_NEW, MESO_HDR_OFF_MAJOR, -1,
                                "format %u.%u is newer than this reader (reads %d.x)", out->major, out->minor,
                                MESO_FORMAT_MAJOR);
    uint8_t tmp[MESO_HDR_SIZE];
    memcpy(tmp, h, MESO_HDR_SIZE);
    mesoi_st32(tmp + MESO_HDR_OFF_HEADER_CRC, 0);
    uint32_t want = mesoi_ld32(h + MESO_HDR_OFF_HEADER_CRC), got = meso_crc32c(0, tmp, MESO_HDR_SIZE);
    if (want != got)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_HDR_CRC, MESO_HDR_OFF_HEADER_CRC, -1,
                                "header CRC32C 0x%08X != stored 0x%08X", got, want);
    uint32_t flags = mesoi_ld32(h + MESO_HDR_OFF_FLAGS);
    if (flags != 0)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_HDR_FLAGS, MESO_HDR_OFF_FLAGS, -1,
                                "unknown header flags 0x%X", flags);
    for (int i = 0; i < MESO_HDR_SIZE_RESERVED; i++)
        if (h[MESO_HDR_OFF_RESERVED + i] != 0)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_HDR_RESERVED, (uint64_t)MESO_HDR_OFF_RESERVED + i,
                                    -1, "reserved header byte %d is not zero", MESO_HDR_OFF_RESERVED + i);
    uint64_t toc_offset = mesoi_ld64(h + MESO_HDR_OFF_TOC_OFFSET);
    if (toc_offset != MESO_HDR_SIZE)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_HDR_TOC_OFFSET, MESO_HDR_OFF_TOC_OFFSET, -1,
                                "toc_offset is %llu, must be 64", (unsigned long long)toc_offset);
    out->toc_entry_size = mesoi_ld32(h + MESO_HDR_OFF_TOC_ENTRY_SIZE);
    if (out->toc_entry_size < MESO_TOC_ENTRY_SIZE || out->toc_entry_size % 8 != 0)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_HDR_TOC_ENTRY_SIZE, MESO_HDR_OFF_TOC_ENTRY_SIZE, -1,
                                "toc_entry_size %u (must be a multiple of 8, at least 64)", out->toc_entry_size);
    out->file_size = mesoi_ld64(h + MESO_HDR_OFF_FILE_SIZE);
    if (out->file_size % MESO_ALIGN != 0 || out->file_size < MESO_HDR_SIZE)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_HDR_FILE_SIZE_ALIGN, MESO_HDR_OFF_FILE_SIZE, -1,
                                "file_size %llu is not a multiple of 64", (unsigned long long)out->file_size);
    if (actual < out->file_size)
        return mesoi_file_error(err, MESO_ERR_TRUNCATED, MESO_ISSUE_FILE_TRUNCATED, actual, -1,
                                "file is truncated: %llu bytes, header says %llu", (unsigned long long)actual,
                                (unsigned long long)out->file_size);
    if (actual > out->file_size)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_FILE_TRAILING, out->file_size, -1,
                                "%llu trailing bytes after the end of the file (file_size %llu)",
                                (unsigned long long)(actual - out->file_size), (unsigned long long)out->file_size);
    out->chunk_count = mesoi_ld32(h + MESO_HDR_OFF_CHUNK_COUNT);
    out->toc_crc = mesoi_ld32(h + MESO_HDR_OFF_TOC_CRC);
    if (out->chunk_count > max_chunks)
        return mesoi_file_error(err, MESO_ERR_UNSUPPORTED, MESO_ISSUE_TOC_TOO_MANY, MESO_HDR_OFF_CHUNK_COUNT, -1,
                                "%u chunks exceed this reader's limit of %u (meso_open_desc.max_chunks)",
                                out->chunk_count, max_chunks);
    if (out->chunk_count > (out->file_size - MESO_HDR_SIZE) / out->toc_entry_size)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_TOC_BOUNDS, MESO_HDR_OFF_CHUNK_COUNT, -1,
                                "a TOC of %u x %u bytes does not fit in a file of %llu bytes", out->chunk_count,
                                out->toc_entry_size, (unsigned long long)out->file_size);
    return MESO_OK;
}

static void decode_entry(const uint8_t* e, meso_chunk_info* c, uint32_t* reserved)
{
    c->type = mesoi_ld32(e + MESO_TOC_OFF_TYPE);
    c->flags = mesoi_ld32(e + MESO_TOC_OFF_FLAGS);
    c->object = mesoi_ld32(e + MESO_TOC_OFF_OBJECT);
    c->lod = mesoi_ld16(e + MESO_TOC_OFF_LOD);
    c->encoding = mesoi_ld16(e + MESO_TOC_OFF_ENCODING);
    c->offset = mesoi_ld64(e + MESO_TOC_OFF_OFFSET);
    c->stored_size = mesoi_ld64(e + MESO_TOC_OFF_STORED_SIZE);
    c->decoded_size = mesoi_ld64(e + MESO_TOC_OFF_DECODED_SIZE);
    c->crc32c = mesoi_ld32(e + MESO_TOC_OFF_CRC);
    c->dtype = mesoi_ld16(e + MESO_TOC_OFF_DTYPE);
    c->components = mesoi_ld16(e + MESO_TOC_OFF_COMPONENTS);
    for (int k = 0; k < 3; k++)
        c->dims[k] = mesoi_ld32(e + MESO_TOC_OFF_DIMS + 4 * k);
    *reserved = mesoi_ld32(e + MESO_TOC_OFF_RESERVED);
}

/* Decode and check every TOC entry: ranges, alignment, order, enums. */
static meso_result parse_toc(meso_file* f, const uint8_t* toc, uint64_t toc_end, meso_error* err)
{
    uint64_t payload_start = mesoi_align64(toc_end);
    uint64_t prev_end = payload_start, prev_off = 0;
    for (uint32_t i = 0; i < f->chunk_count; i++) {
        meso_chunk_info* c = &f->chunks[i];
        uint64_t eo = (uint64_t)MESO_HDR_SIZE + (uint64_t)i * f->toc_entry_size;
        uint32_t reserved;
        int32_t ci = (int32_t)i;
        char cc[5];
        decode_entry(toc + (size_t)i * f->toc_entry_size, c, &reserved);
        mesoi_fourcc_str(c->type, cc);
        meso_result r = mesoi_check_entry(c, reserved, f->minor, ci, eo, err);
        if (r != MESO_OK)
            return r;
        if (c->offset % MESO_ALIGN != 0)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_ALIGN, eo + MESO_TOC_OFF_OFFSET, ci,
                                    "chunk %u (%s): offset %llu is not a multiple of 64", i, cc,
                                    (unsigned long long)c->offset);
        if (c->offset > f->file_size || c->stored_size > f->file_size - c->offset)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_BOUNDS, eo + MESO_TOC_OFF_OFFSET, ci,
                                    "chunk %u (%s): bytes [%llu, +%llu) exceed the file size %llu", i, cc,
                                    (unsigned long long)c->offset, (unsigned long long)c->stored_size,
                                    (unsigned long long)f->file_size);
        if (c->offset < payload_start)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_IN_TOC, eo + MESO_TOC_OFF_OFFSET, ci,
                                    "chunk %u (%s): offset %llu is inside the header/TOC (payloads start at %llu)", i,
                                    cc, (unsigned long long)c->offset, (unsigned long long)payload_start);
        if (i > 0 && c->offset < prev_off)
            return mesoi_file_error(
                err, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_ORDER, eo + MESO_TOC_OFF_OFFSET, ci,
                "chunk %u (%s): offset %llu is below the previous chunk's %llu (TOC must be in file "
                "order)",
                i, cc, (unsigned long long)c->offset, (unsigned long long)prev_off);
        if (c->offset < prev_end)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CHUNK_OVERLAP, eo + MESO_TOC_OFF_OFFSET, ci,
                                    "chunk %u (%s): offset %llu overlaps the previous chunk (ends at %llu)", i, cc,
                                    (unsigned long long)c->offset, (unsigned long long)prev_end);
        /* A reader limit, not a format rule: checked after the entry's
         * format rules so that a corrupt entry is reported as corrupt. */
        if (c->encoding != MESO_ENCODING_RAW && c->decoded_size > f->max_decoded_size)
            return mesoi_file_error(err, MESO_ERR_UNSUPPORTED, MESO_ISSUE_CHUNK_DECODED_LIMIT,
                                    eo + MESO_TOC_OFF_DECODED_SIZE, ci,
                                    "chunk %u (%s): decoded_size %llu exceeds this reader's limit of %llu bytes for "
                                    "encoded chunks (meso_open_desc.max_decoded_size)",
                                    i, cc, (unsigned long long)c->decoded_size,
                                    (unsigned long long)f->max_decoded_size);
        prev_off = c->offset;
        /* offset + stored_size <= file_size, itself a multiple of 64. */
        prev_end = mesoi_align64(c->offset + c->stored_size);
    }
    if (prev_end != f->file_size)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_FILE_END, MESO_HDR_OFF_FILE_SIZE, -1,
                                "file_size %llu, but the last chunk's padding ends at %llu",
                                (unsigned long long)f->file_size, (unsigned long long)prev_end);
    return MESO_OK;
}

static meso_result open_common(meso_file* f, uint64_t actual, const meso_open_desc* desc, meso_error* err)
{
    uint32_t max_chunks = desc && desc->max_chunks ? desc->max_chunks : DEFAULT_MAX_CHUNKS;
    f->max_decoded_size =
        desc && desc->max_decoded_size ? desc->max_decoded_size : MESO_DEFAULT_MAX_DECODED_SIZE;
    uint8_t* owned = NULL;
    const uint8_t* buf = f->data;
    uint8_t small[MESO_HDR_SIZE] = {0};
    header h;
    memset(&h, 0, sizeof h);
    meso_result r;
    if (actual < MESO_HDR_SIZE)
        return parse_header(small, actual, max_chunks, &h, err);
    if (buf == NULL) {
        /* A host reader (meso_io) may be a stream that has received only
         * part of the file: ask it for the header alone, then exactly the
         * TOC, so that opening needs nothing past the TOC (FORMAT.md §7.10:
         * a prefix draws). Path readers take one larger read. */
        const uint64_t first_read = f->source == MESOI_SRC_IO ? MESO_HDR_SIZE : FIRST_READ;
        size_t first = (size_t)(actual < first_read ? actual : first_read);
        owned = (uint8_t*)mesoi_file_alloc(&f->alloc, first);
        if (!owned)
            return mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, -1,
                                    "out of memory reading the header");
        r = mesoi_read_at(f, 0, owned, first, err);
        if (r == MESO_OK)
            r = parse_header(owned, actual, max_chunks, &h, err);
        /* chunk_count * entry size <= file_size - 64 was checked above. */
        uint64_t need = (uint64_t)MESO_HDR_SIZE + (uint64_t)h.chunk_count * h.toc_entry_size;
        if (r == MESO_OK && need > first) {
            mesoi_file_free(&f->alloc, owned);
            owned = NULL;
            if (need > SIZE_MAX)
                return mesoi_file_error(err, MESO_ERR_UNSUPPORTED, MESO_ISSUE_API_TOO_LARGE, 0, -1,
                                        "TOC of %llu bytes does not fit in memory", (unsigned long long)need);
            owned = (uint8_t*)mesoi_file_alloc(&f->alloc, (size_t)need);
            if (!owned)
                return mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, -1,
                                        "out of memory for a TOC of %u chunks", h.chunk_count);
            r = mesoi_read_at(f, 0, owned, (size_t)need, err);
        }
        if (r != MESO_OK) {
            mesoi_file_free(&f->alloc, owned);
            return r;
        }
        buf = owned;
    } else {
        r = parse_header(buf, actual, max_chunks, &h, err);
        if (r != MESO_OK)
            return r;
    }
    f->major = h.major;
    f->minor = h.minor;
    f->file_size = h.file_size;
    f->chunk_count = h.chunk_count;
    f->toc_entry_size = h.toc_entry_size;
    size_t toc_bytes = (size_t)h.chunk_count * h.toc_entry_size;
    uint32_t crc = meso_crc32c(0, buf + MESO_HDR_SIZE, toc_bytes);
    if (crc != h.toc_crc) {
        mesoi_file_free(&f->alloc, owned);
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_TOC_CRC, MESO_HDR_SIZE, -1,
                                "TOC CRC32C 0x%08X != stored 0x%08X", crc, h.toc_crc);
    }
    if (h.chunk_count > 0) {
        /* count <= max_chunks and count * 64 <= file size: no overflow. */
        f->chunks = (meso_chunk_info*)mesoi_file_alloc(&f->alloc, (size_t)h.chunk_count * sizeof(meso_chunk_info));
        if (!f->chunks) {
            mesoi_file_free(&f->alloc, owned);
            return mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, -1,
                                    "out of memory for %u chunk entries", h.chunk_count);
        }
    }
    r = parse_toc(f, buf + MESO_HDR_SIZE, (uint64_t)MESO_HDR_SIZE + toc_bytes, err);
    mesoi_file_free(&f->alloc, owned);
    return r;
}

/* >>open ------------------------------------------------------------------ */

static meso_result file_new(const meso_open_desc* desc, meso_file** out, meso_error* err)
{
    meso_allocator a;
    if (out == NULL)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1, "out is NULL");
    *out = NULL;
    if (mesoi_file_allocator_init(desc ? &desc->allocator : NULL, &a) != MESO_OK)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1,
                                "allocator: provide both alloc_fn and free_fn or neither");
    if (desc && desc->decoder_count > 0 && desc->decoders == NULL)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1,
                                "decoder_count is %u but decoders is NULL", desc->decoder_count);
    meso_file* f = (meso_file*)mesoi_file_alloc(&a, sizeof *f);
    if (!f)
        return mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, -1, "out of memory");
    memset(f, 0, sizeof *f);
    f->alloc = a;
    f->fd = -1;
    if (desc && desc->decoder_count > 0) {
        f->decoders = (meso_decoder*)mesoi_file_alloc(&a, (size_t)desc->decoder_count * sizeof(meso_decoder));
        if (!f->decoders) {
            mesoi_file_free(&a, f);
            return mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, -1,
                                    "out of memory");
        }
        memcpy(f->decoders, desc->decoders, (size_t)desc->decoder_count * sizeof(meso_decoder));
        f->decoder_count = desc->decoder_count;
    }
    *out = f;
    return MESO_OK;
}

static meso_result finish_open(meso_file* f, uint64_t actual, const meso_open_desc* desc, meso_file** out,
                               meso_error* err)
{
    meso_result r = open_common(f, actual, desc, err);
    if (r != MESO_OK) {
        meso_file_close(f);
        *out = NULL;
        return r;
    }
    *out = f;
    return MESO_OK;
}

meso_result meso_file_open_memory(const void* data, size_t size, const meso_open_desc* desc, meso_file** out,
                                  meso_error* err)
{
    mesoi_file_error_clear(err);
    if (data == NULL && size > 0)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1, "data is NULL");
    meso_file* f;
    meso_result r = file_new(desc, &f, err);
    if (r != MESO_OK)
        return r;
    static const uint8_t empty[1] = {0};
    f->source = MESOI_SRC_MEMORY;
    f->data = data ? (const uint8_t*)data : empty;
    return finish_open(f, size, desc, out, err);
}

meso_result meso_file_open_io(const meso_io* io, const meso_open_desc* desc, meso_file** out, meso_error* err)
{
    mesoi_file_error_clear(err);
    if (io == NULL || io->read_fn == NULL)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1,
                                "io or io->read_fn is NULL");
    meso_file* f;
    meso_result r = file_new(desc, &f, err);
    if (r != MESO_OK)
        return r;
    f->source = MESOI_SRC_IO;
    f->io = *io;
    return finish_open(f, io->size, desc, out, err);
}

static meso_result open_fd(const char* path, int* fd, uint64_t* size, meso_error* err)
{
    if (path == NULL)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1, "path is NULL");
    int d;
    do
        d = open(path, O_RDONLY | O_CLOEXEC);
    while (d < 0 && errno == EINTR);
    if (d < 0)
        return mesoi_file_error(err, MESO_ERR_IO, MESO_ISSUE_IO_OPEN, UINT64_MAX, -1, "cannot open '%s': %s", path,
                                strerror(errno));
    struct stat st;
    if (fstat(d, &st) != 0) {
        int e = errno;
        close(d);
        return mesoi_file_error(err, MESO_ERR_IO, MESO_ISSUE_IO_OPEN, UINT64_MAX, -1, "cannot stat '%s': %s", path,
                                strerror(e));
    }
    if (!S_ISREG(st.st_mode)) {
        close(d);
        return mesoi_file_error(err, MESO_ERR_IO, MESO_ISSUE_IO_OPEN, UINT64_MAX, -1,
                                "cannot open '%s': not a regular file", path);
    }
    *fd = d;
    *size = (uint64_t)st.st_size;
    return MESO_OK;
}

meso_result meso_file_open_path(const char* path, const meso_open_desc* desc, meso_file** out, meso_error* err)
{
    mesoi_file_error_clear(err);
    meso_file* f;
    meso_result r = file_new(desc, &f, err);
    if (r != MESO_OK)
        return r;
    uint64_t size;
    r = open_fd(path, &f->fd, &size, err);
    if (r != MESO_OK) {
        meso_file_close(f);
        *out = NULL;
        return r;
    }
    f->source = MESOI_SRC_FD;
    return finish_open(f, size, desc, out, err);
}

meso_result meso_file_open_mmap(const char* path, const meso_open_desc* desc, meso_file** out, meso_error* err)
{
    mesoi_file_error_clear(err);
    meso_file* f;
    meso_result r = file_new(desc, &f, err);
    if (r != MESO_OK)
        return r;
    int fd = -1;
    uint64_t size;
    r = open_fd(path, &fd, &size, err);
    if (r != MESO_OK) {
        meso_file_close(f);
        *out = NULL;
        return r;
    }
    if (size > SIZE_MAX) {
        close(fd);
        meso_file_close(f);
        *out = NULL;
        return mesoi_file_error(err, MESO_ERR_UNSUPPORTED, MESO_ISSUE_API_TOO_LARGE, UINT64_MAX, -1,
                                "'%s' is too large to map on this platform", path);
    }
    f->source = MESOI_SRC_MMAP;
    if (size >= MESO_HDR_SIZE) {
        void* m = mmap(NULL, (size_t)size, PROT_READ, MAP_PRIVATE, fd, 0);
        if (m == MAP_FAILED) {
            int e = errno;
            close(fd);
            meso_file_close(f);
            *out = NULL;
            return mesoi_file_error(err, MESO_ERR_IO, MESO_ISSUE_IO_MMAP, UINT64_MAX, -1, "cannot map '%s': %s", path,
                                    strerror(e));
        }
        f->data = (const uint8_t*)m;
        f->map_size = (size_t)size;
    }
    close(fd); /* the mapping keeps the file alive */
    return finish_open(f, size, desc, out, err);
}

void meso_file_close(meso_file* f)
{
    if (f == NULL)
        return;
    if (f->source == MESOI_SRC_MMAP && f->map_size > 0)
        munmap((void*)(uintptr_t)f->data, f->map_size);
    if (f->fd >= 0)
        close(f->fd);
    meso_allocator a = f->alloc;
    mesoi_file_free(&a, f->chunks);
    mesoi_file_free(&a, f->decoders);
    mesoi_file_free(&a, f);
}

/* >>queries --------------------------------------------------------------- */

void meso_file_version(const meso_file* f, uint16_t* major, uint16_t* minor)
{
    if (major)
        *major = f ? f->major : 0;
    if (minor)
        *minor = f ? f->minor : 0;
}

uint64_t meso_file_size(const meso_file* f) { return f ? f->file_size : 0; }

uint32_t meso_file_chunk_count(const meso_file* f) { return f ? f->chunk_count : 0; }

const meso_chunk_info* meso_file_chunk(const meso_file* f, uint32_t index)
{
    return (f && index < f->chunk_count) ? &f->chunks[index] : NULL;
}

int32_t meso_file_find(const meso_file* f, uint32_t type, uint32_t object, uint16_t lod)
{
    if (f == NULL)
        return -1;
    for (uint32_t i = 0; i < f->chunk_count && i <= (uint32_t)INT32_MAX; i++) {
        const meso_chunk_info* c = &f->chunks[i];
        if (c->type == type && (object == UINT32_MAX || c->object == object) && (lod == UINT16_MAX || c->lod == lod))
            return (int32_t)i;
    }
    return -1;
}

/* >>chunk access ---------------------------------------------------------- */

static meso_result check_index(const meso_file* f, uint32_t index, const void* dst, meso_error* err)
{
    if (f == NULL || dst == NULL)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1, "NULL argument");
    if (index >= f->chunk_count)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1,
                                "chunk index %u out of range (%u chunks)", index, f->chunk_count);
    return MESO_OK;
}

meso_result meso_file_read_stored(meso_file* f, uint32_t index, void* dst, size_t dst_size, meso_error* err)
{
    mesoi_file_error_clear(err);
    meso_result r = check_index(f, index, dst, err);
    if (r != MESO_OK)
        return r;
    const meso_chunk_info* c = &f->chunks[index];
    char cc[5];
    mesoi_fourcc_str(c->type, cc);
    if (dst_size < c->stored_size)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_BUFFER, UINT64_MAX, (int32_t)index,
                                "chunk %u (%s): buffer of %zu bytes is smaller than stored_size %llu", index, cc,
                                dst_size, (unsigned long long)c->stored_size);
    uint32_t crc = 0;
    r = mesoi_read_crc(f, c->offset, dst, (size_t)c->stored_size, &crc, err);
    if (r != MESO_OK)
        return r;
    if (crc != c->crc32c)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_PAYLOAD_CRC, c->offset, (int32_t)index,
                                "chunk %u (%s, object %u): payload CRC32C 0x%08X != 0x%08X in the TOC", index, cc,
                                c->object, crc, c->crc32c);
    return MESO_OK;
}

static const char* encoding_name(uint16_t e)
{
    switch (e) {
    case MESO_ENCODING_RAW: return "raw";
    case MESO_ENCODING_DRACO: return "draco";
    default: return "unknown";
    }
}

meso_result meso_file_read_chunk(meso_file* f, uint32_t index, void* dst, size_t dst_size, meso_error* err)
{
    mesoi_file_error_clear(err);
    meso_result r = check_index(f, index, dst, err);
    if (r != MESO_OK)
        return r;
    const meso_chunk_info* c = &f->chunks[index];
    int32_t ci = (int32_t)index;
    char cc[5];
    mesoi_fourcc_str(c->type, cc);
    if (dst_size < c->decoded_size)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_BUFFER, UINT64_MAX, ci,
                                "chunk %u (%s): buffer of %zu bytes is smaller than decoded_size %llu", index, cc,
                                dst_size, (unsigned long long)c->decoded_size);
    r = mesoi_check_type_rules(c, ci, err);
    if (r != MESO_OK)
        return r;
    if (c->encoding == MESO_ENCODING_RAW) {
        r = meso_file_read_stored(f, index, dst, dst_size, err);
        if (r == MESO_OK && mesoi_known_type(c->type))
            r = mesoi_check_contents(c, (const uint8_t*)dst, (size_t)c->decoded_size, ci, c->offset, err);
        return r;
    }
    const meso_decoder* dec = mesoi_find_decoder(f, c->encoding);
    if (dec == NULL)
        return mesoi_file_error(
            err, MESO_ERR_UNSUPPORTED, MESO_ISSUE_ENCODING_UNSUPPORTED, c->offset, ci,
            "chunk %u (%s, object %u): encoding '%s' (%u) is not supported by this reader (no decoder)", index, cc,
            c->object, encoding_name(c->encoding), c->encoding);
    const uint8_t* src = NULL;
    uint8_t* owned = NULL;
    uint32_t crc = 0;
    if (f->data) {
        src = f->data + c->offset;
        crc = meso_crc32c(0, src, (size_t)c->stored_size);
    } else {
        if (c->stored_size > SIZE_MAX)
            return mesoi_file_error(err, MESO_ERR_UNSUPPORTED, MESO_ISSUE_API_TOO_LARGE, c->offset, ci,
                                    "chunk %u (%s): %llu stored bytes do not fit in memory", index, cc,
                                    (unsigned long long)c->stored_size);
        owned = (uint8_t*)mesoi_file_alloc(&f->alloc, (size_t)c->stored_size);
        if (!owned)
            return mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, c->offset, ci,
                                    "chunk %u (%s): out of memory for %llu stored bytes", index, cc,
                                    (unsigned long long)c->stored_size);
        r = mesoi_read_crc(f, c->offset, owned, (size_t)c->stored_size, &crc, err);
        if (r != MESO_OK) {
            mesoi_file_free(&f->alloc, owned);
            return r;
        }
        src = owned;
    }
    if (crc != c->crc32c) {
        r = mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_PAYLOAD_CRC, c->offset, ci,
                             "chunk %u (%s, object %u): payload CRC32C 0x%08X != 0x%08X in the TOC", index, cc,
                             c->object, crc, c->crc32c);
    } else if (mesoi_mesh_layout(c->type) && c->stored_size < MESO_MESH_HDR_SIZE) {
        r = mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_MESH_SIZE, c->offset, ci,
                             "chunk %u (%s): encoded payload is smaller than the 64-byte mesh header", index, cc);
    } else if (mesoi_mesh_layout(c->type) &&
               (r = mesoi_check_mesh_header(src, c->decoded_size, NULL, ci, c->offset, err)) != MESO_OK) {
        /* r set */
    } else {
        meso_error derr;
        mesoi_file_error_clear(&derr);
        r = dec->decode_fn(dec->user, c, src, (size_t)c->stored_size, dst, (size_t)c->decoded_size, &derr);
        if (r != MESO_OK) {
            if (derr.result == MESO_OK)
                mesoi_file_error(&derr, r, MESO_ISSUE_DECODE_FAILED, c->offset, ci, "decoder reported %s",
                                 meso_result_string(r));
            mesoi_file_error(err, r, derr.code ? derr.code : MESO_ISSUE_DECODE_FAILED, c->offset, ci,
                             "chunk %u (%s, object %u): '%s' decoding failed: %s", index, cc, c->object,
                             encoding_name(c->encoding), derr.message);
        } else if (mesoi_known_type(c->type)) {
            r = mesoi_check_contents(c, (const uint8_t*)dst, (size_t)c->decoded_size, ci, UINT64_MAX, err);
        }
    }
    mesoi_file_free(&f->alloc, owned);
    return r;
}

meso_result meso_file_chunk_view(const meso_file* f, uint32_t index, const void** data, meso_error* err)
{
    mesoi_file_error_clear(err);
    meso_result r = check_index(f, index, data, err);
    if (r != MESO_OK)
        return r;
    if (f->data == NULL)
        return mesoi_file_error(err, MESO_ERR_UNSUPPORTED, MESO_ISSUE_API_NO_VIEW, UINT64_MAX, (int32_t)index,
                                "chunk views need a memory or mmap reader");
    *data = f->data + f->chunks[index].offset;
    return MESO_OK;
}

meso_result meso_file_objects(meso_file* f, meso_object_record* out, uint32_t cap, uint32_t* count, meso_error* err)
{
    mesoi_file_error_clear(err);
    if (!f || !count || (cap && !out))
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1,
                                "meso_file_objects: NULL file, count or output");
    *count = 0;
    const int32_t ci = meso_file_find(f, MESO_CHUNK_OBJT, UINT32_MAX, UINT16_MAX);
    if (ci < 0)
        return MESO_OK;
    const meso_chunk_info* c = &f->chunks[ci];
    /* Open bounded decoded_size (raw: by the file size; encoded: by
     * max_decoded_size and the expansion rule); records are 64 B. */
    uint8_t* buf = mesoi_file_alloc(&f->alloc, (size_t)c->decoded_size);
    if (!buf)
        return mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, c->offset, ci,
                                "chunk %d (OBJT): out of memory", (int)ci);
    meso_result r = meso_file_read_chunk(f, (uint32_t)ci, buf, (size_t)c->decoded_size, err);
    if (r == MESO_OK) {
        const uint32_t n = (uint32_t)(c->decoded_size / MESO_OBJT_RECORD_SIZE);
        for (uint32_t i = 0; i < n && i < cap; ++i)
            meso_object_record_decode(buf + (size_t)i * MESO_OBJT_RECORD_SIZE, &out[i]);
        *count = n;
    }
    mesoi_file_free(&f->alloc, buf);
    return r;
}
