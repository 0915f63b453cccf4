/*
 * file_internal.h — internals shared by the .meso reader, writer and
 * validator (not installed). Names use the mesoi_ prefix (STYLE.md §2).
 *
 * Every on-disk field is read and written through the little-endian helpers
 * below with the offsets of meso_layout.h: byte shifts, never pointer casts,
 * so unaligned data and big-endian hosts are both fine.
 */
#ifndef MESO_FILE_INTERNAL_H
#define MESO_FILE_INTERNAL_H

#include "meso_file.h"
#include "meso_layout.h"

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#if defined(__GNUC__) || defined(__clang__)
#define MESOI_PRINTF(fmt, args) __attribute__((format(printf, fmt, args)))
#else
#define MESOI_PRINTF(fmt, args)
#endif

/* >>little-endian --------------------------------------------------------- */

static inline uint16_t mesoi_ld16(const uint8_t* p) { return (uint16_t)(p[0] | (p[1] << 8)); }
static inline uint32_t mesoi_ld32(const uint8_t* p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static inline uint64_t mesoi_ld64(const uint8_t* p)
{
    return (uint64_t)mesoi_ld32(p) | ((uint64_t)mesoi_ld32(p + 4) << 32);
}
static inline float mesoi_ldf32(const uint8_t* p)
{
    uint32_t u = mesoi_ld32(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}
static inline void mesoi_st16(uint8_t* p, uint16_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
}
static inline void mesoi_st32(uint8_t* p, uint32_t v)
{
    p[0] = (uint8_t)v;
    p[1] = (uint8_t)(v >> 8);
    p[2] = (uint8_t)(v >> 16);
    p[3] = (uint8_t)(v >> 24);
}
static inline void mesoi_st64(uint8_t* p, uint64_t v)
{
    mesoi_st32(p, (uint32_t)v);
    mesoi_st32(p + 4, (uint32_t)(v >> 32));
}
static inline void mesoi_stf32(uint8_t* p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    mesoi_st32(p, u);
}

/* Round up to a multiple of 64; callers make sure v <= UINT64_MAX - 63. */
static inline uint64_t mesoi_align64(uint64_t v) { return (v + 63u) & ~(uint64_t)63u; }

/* The magic: PNG-style, catches 7-bit transfers and CR/LF conversion. */
extern const uint8_t mesoi_magic[8];

/* >>crc ------------------------------------------------------------------- */

uint32_t mesoi_crc32c_sw(uint32_t crc, const void* data, size_t size);
/* SSE4.2 path when available, else the portable one. */
uint32_t mesoi_crc32c_hw(uint32_t crc, const void* data, size_t size);
int mesoi_crc32c_hw_available(void);

/* >>memory & errors ------------------------------------------------------- */

/* Fill in malloc/free for a zero allocator; INVALID_ARG when only one
 * function is given. */
meso_result mesoi_file_allocator_init(const meso_allocator* in, meso_allocator* out);
void* mesoi_file_alloc(const meso_allocator* a, size_t size);
void mesoi_file_free(const meso_allocator* a, void* p);

/* Fill *err (may be NULL) and return r. */
meso_result mesoi_file_error(meso_error* err, meso_result r, uint32_t code, uint64_t offset, int32_t chunk,
                             const char* fmt, ...) MESOI_PRINTF(6, 7);
void mesoi_file_error_clear(meso_error* err);
/* Printable form of a fourcc ('?' for bytes outside 0x20..0x7E). */
void mesoi_fourcc_str(uint32_t type, char out[5]);

/* >>reader ---------------------------------------------------------------- */

enum { MESOI_SRC_MEMORY, MESOI_SRC_MMAP, MESOI_SRC_FD, MESOI_SRC_IO };

struct meso_file {
    meso_allocator alloc;
    int source;          /* MESOI_SRC_* */
    const uint8_t* data; /* MEMORY, MMAP: the whole file */
    size_t map_size;     /* MMAP: length passed to munmap */
    int fd;              /* FD: open descriptor */
    meso_io io;          /* IO */
    uint64_t file_size;
    uint16_t major;
    uint16_t minor;
    uint32_t toc_entry_size;
    uint32_t chunk_count;
    meso_chunk_info* chunks;
    meso_decoder* decoders; /* copy of the desc's array */
    uint32_t decoder_count;
    uint64_t max_decoded_size; /* desc's, default applied */
};

/* Read `size` bytes at file offset `off` (already range-checked). */
meso_result mesoi_read_at(meso_file* f, uint64_t off, void* dst, size_t size, meso_error* err);
/* Block size of mesoi_read_crc: small enough that a block read by pread or
 * memcpy is still in L2 when it is checksummed, large enough that the
 * syscall per block costs nothing measurable. */
#define MESOI_READ_BLOCK ((size_t)1 << 20)
/* mesoi_read_at + CRC32C of the bytes, one pass: reads MESOI_READ_BLOCK at a
 * time and checksums each block right after it arrives. *crc is the running
 * CRC (pass 0 to start). */
meso_result mesoi_read_crc(meso_file* f, uint64_t off, void* dst, size_t size, uint32_t* crc, meso_error* err);
const meso_decoder* mesoi_find_decoder(const meso_file* f, uint16_t encoding);

/* >>checks (file_validate.c) ---------------------------------------------- */

int mesoi_known_type(uint32_t type);

/* Per-entry checks that need no other entry (cheap tier): type, flags,
 * reserved, enums, sizes, the Draco expansion bound, unknown REQUIRED types.
 * `minor` is the file's minor version (unknown encodings are CORRUPT in 1.0
 * files only). Issues are reported with result CORRUPT/UNSUPPORTED and
 * offset `entry_off`. The reader-side max_decoded_size limit is not here
 * (the writer has no limit): parse_toc in file_read.c applies it. */
meso_result mesoi_check_entry(const meso_chunk_info* c, uint32_t reserved, uint16_t minor, int32_t chunk,
                              uint64_t entry_off, meso_error* err);
/* meso_file_check_cells_level that hands the TILE and MEMB payloads it
 * read and checked to the caller (allocated with f->alloc; free with
 * mesoi_file_free) when it succeeds, so a loader reads them once. Either
 * pointer may be NULL: that payload is freed as usual. */
meso_result mesoi_file_check_cells_keep(meso_file* f, uint32_t object, uint16_t lod, uint8_t** tile, uint8_t** memb,
                                        meso_error* err);
/* Type-specific element/encoding rules (full tier, and the writer). */
/* a * b without wrapping; returns 0 on overflow. */
static inline int mesoi_mul_u64(uint64_t a, uint64_t b, uint64_t* out)
{
    if (a != 0 && b > UINT64_MAX / a)
        return 0;
    *out = a * b;
    return 1;
}
/* Is the chunk's dtype in `mask` (bits MESOI_DT(U8) | ...)? */
#define MESOI_DT(t) (1u << MESO_DTYPE_##t)
static inline int mesoi_is_dtype(const meso_chunk_info* c, unsigned mask)
{
    return c->dtype < 16 && ((mask >> c->dtype) & 1u);
}
/* The object tier of the full check (file_validate_objects.c): `rec`
 * against its kind's chunks, counts and values; every issue goes to fn
 * (NULL: stop at the first), including the chunk issues of chunks it reads.
 * Returns the first issue's result. */
meso_result mesoi_check_object(meso_file* f, const meso_object_record* rec, meso_issue_fn fn, void* user);
/* Every LODS record against OBJT and the chunks its level draws (6401). */
void mesoi_check_levels(meso_file* f, const meso_object_record* recs, uint32_t count, meso_issue_fn fn, void* user);
void mesoi_check_parts(meso_file* f, const meso_object_record* recs, uint32_t count, meso_issue_fn fn, void* user);
/* LODS contents (file_levels.c, issues 4921, 4922). */
meso_result mesoi_check_lods(const uint8_t* d, size_t n, int32_t chunk, uint64_t base, meso_error* err);
/* PRTS content (FORMAT.md §7.11), and the chunk of `type` (PMSH or PVCL)
 * of `object`'s part `part` at `lod` (-1 if none). */
meso_result mesoi_check_prts(const uint8_t* d, size_t n, int32_t chunk, uint64_t base, meso_error* err);
int32_t mesoi_find_part(const meso_file* f, uint32_t type, uint32_t object, uint32_t part, uint16_t lod);
/* The chunk types of an object's parts (§7.11): no whole level draws them. */
static inline int mesoi_part_chunk(uint32_t type)
{
    return type == MESO_CHUNK_PRTS || type == MESO_CHUNK_PMSH || type == MESO_CHUNK_PVCL || type == MESO_CHUNK_PTRI;
}
/* MESH or PMSH: the chunk types with the MESH layout (§7.3). */
static inline int mesoi_mesh_layout(uint32_t type) { return type == MESO_CHUNK_MESH || type == MESO_CHUNK_PMSH; }
meso_result mesoi_check_type_rules(const meso_chunk_info* c, int32_t chunk, meso_error* err);
/* Contents of a decoded structured chunk (META/RPRT JSON, OBJT, MESH, SKEL,
 * FRUS); OK for other types. `base` is the file offset for reports
 * (UINT64_MAX when the bytes are decoded, not stored). */
meso_result mesoi_check_contents(const meso_chunk_info* c, const uint8_t* data, size_t size, int32_t chunk,
                                 uint64_t base, meso_error* err);
/* ANIM contents (file_anim.c, issues 4901, 4902). */
meso_result mesoi_check_anim(const uint8_t* d, size_t n, int32_t chunk, uint64_t base, meso_error* err);
/* CMAP contents (file_cmap.c, issues 4911, 4912). */
meso_result mesoi_check_cmap(const uint8_t* d, size_t n, int32_t chunk, uint64_t base, meso_error* err);
/* The 64-byte header stored in front of a Draco MESH bitstream, checked
 * against the chunk's decoded_size. */
meso_result mesoi_check_mesh_header(const uint8_t* hdr, uint64_t decoded_size, meso_mesh_layout* out, int32_t chunk,
                                    uint64_t base, meso_error* err);

/* file_validate_json.c (FORMAT.md §7.1). The offset of the first byte that
 * is not valid UTF-8, or SIZE_MAX when all n bytes are. */
size_t mesoi_utf8_invalid(const uint8_t* s, size_t n);
/* 1 when d[0..n) is one strict RFC 8259 value with optional surrounding
 * whitespace; else 0 with the issue code, what is wrong and its offset. */
int mesoi_json_check(const uint8_t* d, size_t n, uint32_t* code, const char** what, size_t* pos);

#endif /* MESO_FILE_INTERNAL_H */
