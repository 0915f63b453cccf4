/*
 * meso_file.h — the .meso container: reader, writer and validator.
 *
 * C11, no dependencies beyond the C library (and POSIX for files/mmap).
 * Linked by mesobake, mesoinspect and libmeso, so all three parse files with
 * exactly the same code. The normative byte layout is formats/FORMAT.md;
 * formats/meso_layout.h has the byte offsets as #defines (shared with GLSL).
 *
 *   [header 64B][TOC: chunk_count x 64B][pad to 64][payload][pad]...[payload]
 *
 * Ownership: every object created here is freed with its matching destroy /
 * close call. Descs are zero-initialised to mean "defaults".
 * Errors: every call that can fail returns a meso_result and, when the caller
 * passes a meso_error*, fills in a stable issue code, a byte offset and a
 * message naming the problem (codes are for programs, messages for humans).
 */
#ifndef MESO_FILE_H
#define MESO_FILE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* MESO_API marks the functions libmeso exports (this header's and
 * meso_rt.h's). libmeso and the format library inside it are compiled with
 * -fvisibility=hidden and MESO_BUILDING_LIBRARY, so these are the only
 * symbols libmeso.so exports (tests/integration/check_exports.sh checks it).
 * A host may define MESO_API itself before including the header. */
#ifndef MESO_API
#if defined(MESO_BUILDING_LIBRARY) && defined(__GNUC__)
#define MESO_API __attribute__((visibility("default")))
#else
#define MESO_API
#endif
#endif

#define MESO_VERSION 100 /* tools/library 0.1.0 as one comparable integer */
#define MESO_VERSION_STRING "0.1.0"
#define MESO_FORMAT_MAJOR 1
#define MESO_FORMAT_MINOR 1

/* >>result ---------------------------------------------------------------- */

typedef enum meso_result {
    MESO_OK = 0,
    MESO_ERR_TRUNCATED,        /* the data ends before a structure it declares */
    MESO_ERR_BAD_MAGIC,        /* not a .meso file, or damaged by a text-mode transfer */
    MESO_ERR_VERSION_TOO_NEW,  /* major version newer than this reader */
    MESO_ERR_CORRUPT,          /* a checksum, range, count or enum is wrong */
    MESO_ERR_OUT_OF_MEMORY,
    MESO_ERR_IO,               /* the OS or the host read callback failed */
    MESO_ERR_INVALID_ARG,      /* caller contract violated (NULL, bad index, small buffer) */
    MESO_ERR_GL,               /* (runtime) a GL call or entry point failed */
    MESO_ERR_UNSUPPORTED,      /* valid but not supported by this build (e.g. Draco without a decoder) */
    MESO_ERR_NOT_FOUND,        /* no chunk / object matches */
    MESO_ERR_PENDING,          /* the host's reader has not received those bytes yet (MESO_IO_PENDING):
                                  nothing is wrong, ask again later */
    MESO_RESULT_COUNT
} meso_result;

/* Static string for a result, never NULL. */
MESO_API const char* meso_result_string(meso_result r);

/* Detail for one failure or validation issue. `code` is a stable issue
 * number from FORMAT.md §"Issue codes" (0 when none applies); `offset` is the
 * byte offset in the file the issue is about (UINT64_MAX when none). */
typedef struct meso_error {
    meso_result result;
    uint32_t code;
    uint64_t offset;
    int32_t chunk;      /* TOC index the issue is about, -1 when none */
    char message[240];  /* NUL-terminated, human readable */
} meso_error;

/* >>memory ---------------------------------------------------------------- */

/* Provide both functions or neither; zero means malloc/free. */
typedef struct meso_allocator {
    void* (*alloc_fn)(size_t size, void* user);
    void (*free_fn)(void* ptr, void* user);
    void* user;
} meso_allocator;

/* >>constants ------------------------------------------------------------- */

#define MESO_FOURCC(a, b, c, d) \
    ((uint32_t)(uint8_t)(a) | ((uint32_t)(uint8_t)(b) << 8) | ((uint32_t)(uint8_t)(c) << 16) | ((uint32_t)(uint8_t)(d) << 24))

/* Chunk types. FORMAT.md defines the element layout of each. */
#define MESO_CHUNK_META MESO_FOURCC('M', 'E', 'T', 'A') /* UTF-8 JSON: tool, version, bake parameters, provenance */
#define MESO_CHUNK_RPRT MESO_FOURCC('R', 'P', 'R', 'T') /* UTF-8 JSON: the bake's quality report */
#define MESO_CHUNK_OBJT MESO_FOURCC('O', 'B', 'J', 'T') /* object table: one 64B record per object */
#define MESO_CHUNK_MESH MESO_FOURCC('M', 'E', 'S', 'H') /* triangle mesh: header + positions, normals, uvs, indices */
#define MESO_CHUNK_SDIR MESO_FOURCC('S', 'D', 'I', 'R') /* shell directors: f32x3 per base vertex */
#define MESO_CHUNK_STHK MESO_FOURCC('S', 'T', 'H', 'K') /* shell thickness: f32 per base vertex */
#define MESO_CHUNK_TX2D MESO_FOURCC('T', 'X', '2', 'D') /* 2D texture (a shell's height field; a native coarser level's own at its lod, FORMAT.md §7.10) */
#define MESO_CHUNK_TX3D MESO_FOURCC('T', 'X', '3', 'D') /* 3D texture (a shell's density volume, a cells object's colour grid) */
#define MESO_CHUNK_DIST MESO_FOURCC('D', 'I', 'S', 'T') /* distance map for sphere tracing (3D) */
#define MESO_CHUNK_TILE MESO_FOURCC('T', 'I', 'L', 'E') /* tile map: split-cell index per voxel (3D) */
#define MESO_CHUNK_SPLT MESO_FOURCC('S', 'P', 'L', 'T') /* split-cell table: face codes per split cell */
#define MESO_CHUNK_MEMB MESO_FOURCC('M', 'E', 'M', 'B') /* membership map: 2 bits per split cell per tile */
#define MESO_CHUNK_NRMM MESO_FOURCC('N', 'R', 'M', 'M') /* normal map (3D, octahedral 2x16 bit) */
#define MESO_CHUNK_COLR MESO_FOURCC('C', 'O', 'L', 'R') /* colour map (3D, RGBA8) */
#define MESO_CHUNK_SKEL MESO_FOURCC('S', 'K', 'E', 'L') /* skeleton nodes */
#define MESO_CHUNK_FRUS MESO_FOURCC('F', 'R', 'U', 'S') /* conical frusta */
#define MESO_CHUNK_RELF MESO_FOURCC('R', 'E', 'L', 'F') /* relief map (2D height + normal) */
#define MESO_CHUNK_FSEG MESO_FOURCC('F', 'S', 'E', 'G') /* per-frustum topology and parametrisation */
#define MESO_CHUNK_BALL MESO_FOURCC('B', 'A', 'L', 'L') /* balls closing branch points */
#define MESO_CHUNK_CELL MESO_FOURCC('C', 'E', 'L', 'L') /* cells object grid: tiles, resolution, origin (one record) */
#define MESO_CHUNK_ANIM MESO_FOURCC('A', 'N', 'I', 'M') /* a shell's animated texture function: frames, rate, loop */
#define MESO_CHUNK_TXFR MESO_FOURCC('T', 'X', 'F', 'R') /* its frames: TX2D/TX3D slabs stacked along z */
#define MESO_CHUNK_DSFR MESO_FOURCC('D', 'S', 'F', 'R') /* their distance maps: DIST slabs stacked along z */
#define MESO_CHUNK_CMAP MESO_FOURCC('C', 'M', 'A', 'P') /* how a shell's COLR maps to texture space (one record) */
#define MESO_CHUNK_LODS MESO_FOURCC('L', 'O', 'D', 'S') /* levels of detail: error and bounds per object level (1.1) */
#define MESO_CHUNK_VCOL MESO_FOURCC('V', 'C', 'O', 'L') /* a MESH's vertex appearance: sRGB albedo + occlusion, U8 x 4 per vertex (1.1) */
#define MESO_CHUNK_PRTS MESO_FOURCC('P', 'R', 'T', 'S') /* a mesh or shell object's parts: levels per part and neighbours (1.1, §7.11) */
#define MESO_CHUNK_PMSH MESO_FOURCC('P', 'M', 'S', 'H') /* one part's mesh at one of its levels: MESH layout (1.1, §7.11) */
#define MESO_CHUNK_PTRI MESO_FOURCC('P', 'T', 'R', 'I') /* a shell's parts' prisms: its MESH triangles part after part, U32 x 1, dims T x 1 x 1, lod 0 (1.1, §7.11) */
#define MESO_CHUNK_PVCL MESO_FOURCC('P', 'V', 'C', 'L') /* a PMSH's vertex appearance, as VCOL: BYTES x 1 or 4 per vertex, dims part x 1 x 1 (1.1, §7.11) */

/* Chunk flags (TOC entry). Unknown bits must be zero in format 1.0. */
#define MESO_CHUNK_FLAG_REQUIRED 0x1u /* a reader that does not know the type must refuse the file */

/* Chunk encodings. */
typedef enum meso_encoding {
    MESO_ENCODING_RAW = 0,   /* stored bytes == decoded bytes */
    MESO_ENCODING_DRACO = 1, /* MESH only: the 64B MESH header, then the Draco bitstream */
    MESO_ENCODING_COUNT
} meso_encoding;

/* Element data types (TOC entry). */
typedef enum meso_dtype {
    MESO_DTYPE_BYTES = 0, /* opaque bytes (JSON, structured chunks) */
    MESO_DTYPE_U8,
    MESO_DTYPE_U16,
    MESO_DTYPE_U32,
    MESO_DTYPE_I8,
    MESO_DTYPE_I16,
    MESO_DTYPE_I32,
    MESO_DTYPE_F16,
    MESO_DTYPE_F32,
    MESO_DTYPE_COUNT
} meso_dtype;

/* Size in bytes of one component of `t`, 0 for unknown. BYTES is 1. */
MESO_API uint32_t meso_dtype_size(meso_dtype t);

/* >>chunk info ------------------------------------------------------------ */

/* One table-of-contents entry, decoded to host order. */
typedef struct meso_chunk_info {
    uint32_t type;          /* fourcc */
    uint32_t flags;         /* MESO_CHUNK_FLAG_* */
    uint32_t object;        /* object id the chunk belongs to (0 = file-wide) */
    uint16_t lod;           /* level of detail / mip level: 0 = finest */
    uint16_t encoding;      /* meso_encoding */
    uint64_t offset;        /* byte offset of the stored payload (64-aligned) */
    uint64_t stored_size;   /* bytes in the file */
    uint64_t decoded_size;  /* bytes after decoding */
    uint32_t crc32c;        /* CRC32C of the stored bytes */
    uint16_t dtype;         /* meso_dtype of one component */
    uint16_t components;    /* components per element (1..16) */
    uint32_t dims[3];       /* elements along x, y, z (1 for unused axes) */
} meso_chunk_info;

/* >>reader ---------------------------------------------------------------- */

typedef struct meso_file meso_file;

/* Host read callback (engine virtual file systems, network streams): read
 * exactly `size` bytes at `offset` into `dst`. Return 0 on success,
 * MESO_IO_PENDING when those bytes have not arrived yet (a stream still
 * downloading: the read gives MESO_ERR_PENDING and may be asked again
 * later), any other non-zero value on failure (MESO_ERR_IO). Reads of
 * different chunks may be asked from several threads at once when the host
 * runs libmeso's stream requests on worker threads (meso_rt_stream_run);
 * the path, mmap and memory readers allow that. */
#define MESO_IO_PENDING (-11)
typedef struct meso_io {
    int (*read_fn)(void* user, uint64_t offset, void* dst, size_t size);
    uint64_t size; /* total size of the stream in bytes; required */
    void* user;
} meso_io;

/* Decoder for a non-raw encoding, supplied by the host (mesobake and
 * mesoinspect pass the Draco adapter's). Receives the whole stored payload
 * (CRC already verified; for MESH: the 64-byte mesh header, then the
 * bitstream) and writes exactly dst_size = decoded_size bytes: the complete
 * decoded layout, header included. The reader then checks the result. */
typedef struct meso_decoder {
    uint16_t encoding; /* meso_encoding it handles */
    meso_result (*decode_fn)(void* user, const meso_chunk_info* chunk, const void* src, size_t src_size, void* dst,
                             size_t dst_size, meso_error* err);
    void* user;
} meso_decoder;

/* Default of meso_open_desc.max_decoded_size: 1 GiB. */
#define MESO_DEFAULT_MAX_DECODED_SIZE ((uint64_t)1 << 30)
/* Format rule for Draco chunks (FORMAT.md §6, issue 2021): decoded_size <=
 * stored_size * MESO_DRACO_MAX_EXPANSION + MESO_DRACO_EXPANSION_SLACK. */
#define MESO_DRACO_MAX_EXPANSION 1024u
#define MESO_DRACO_EXPANSION_SLACK 65536u

typedef struct meso_open_desc {
    meso_allocator allocator;     /* default malloc/free */
    const meso_decoder* decoders; /* optional */
    uint32_t decoder_count;
    uint32_t max_chunks;          /* refuse TOCs larger than this (default 1 << 20) */
    /* Refuse, on open, any encoded (non-raw) chunk whose decoded_size is
     * above this (0 = MESO_DEFAULT_MAX_DECODED_SIZE, 1 GiB): issue 2022,
     * MESO_ERR_UNSUPPORTED. An encoded chunk's decoded_size is the one size
     * in a file not backed by bytes in it; readers (and callers, who size
     * read_chunk buffers from it) allocate it before decoding. Raw chunks
     * are exempt: their decoded_size equals stored_size, which open already
     * checked against the real file size. */
    uint64_t max_decoded_size;
} meso_open_desc;

/* Open and run the cheap checks (FORMAT.md §Validation, tier 1): size, magic,
 * version, header CRC, file_size, TOC bounds and CRC, every entry's range,
 * alignment, enums and sizes, and the decoded-size limits of encoded chunks
 * (so after a successful open every chunk's decoded_size is safe to
 * allocate: raw ones are backed by the file, encoded ones are at most
 * max_decoded_size and at most 1024 x stored_size + 64 KiB for Draco).
 * The header and TOC are read in one read. `desc` and `err` may be NULL.
 * On success *out must be closed. */
MESO_API meso_result meso_file_open_path(const char* path, const meso_open_desc* desc, meso_file** out,
                                         meso_error* err);
/* Same, mapping the file with mmap: chunk payloads can then be viewed without
 * copying (meso_file_chunk_view). */
MESO_API meso_result meso_file_open_mmap(const char* path, const meso_open_desc* desc, meso_file** out,
                                         meso_error* err);
/* Same, over caller memory that must outlive the meso_file (not copied). */
MESO_API meso_result meso_file_open_memory(const void* data, size_t size, const meso_open_desc* desc,
                                           meso_file** out, meso_error* err);
/* Same, over a host read callback; chunks are fetched on demand. */
MESO_API meso_result meso_file_open_io(const meso_io* io, const meso_open_desc* desc, meso_file** out,
                                       meso_error* err);
MESO_API void meso_file_close(meso_file* f);

MESO_API void meso_file_version(const meso_file* f, uint16_t* major, uint16_t* minor);
MESO_API uint64_t meso_file_size(const meso_file* f);
MESO_API uint32_t meso_file_chunk_count(const meso_file* f);
/* NULL when index is out of range. */
MESO_API const meso_chunk_info* meso_file_chunk(const meso_file* f, uint32_t index);
/* Index of the first chunk with this type/object/lod, or -1. Pass
 * object = UINT32_MAX or lod = UINT16_MAX to match any. */
MESO_API int32_t meso_file_find(const meso_file* f, uint32_t type, uint32_t object, uint16_t lod);

/* Read the stored bytes of chunk `index` into dst (dst_size >= stored_size)
 * and verify its CRC32C. Path and io readers read in blocks (1 MiB) and
 * checksum each block right after reading it, while it is in cache. */
MESO_API meso_result meso_file_read_stored(meso_file* f, uint32_t index, void* dst, size_t dst_size,
                                           meso_error* err);
/* Read and decode chunk `index` into dst (dst_size >= decoded_size), verifying
 * its CRC, its type's element/encoding rules (FORMAT.md §7 table) and, for
 * structured chunks, its internal layout. Raw chunks are copied; other
 * encodings go through the desc's decoders, or fail with
 * MESO_ERR_UNSUPPORTED naming the encoding.
 *
 * Verified loading: open (cheap tier) + read_chunk of each chunk you use
 * checks every byte you get (CRC, type rules, contents) and reads each byte
 * once; over every chunk it checks all MESO_CHECK_FULL checks except the
 * padding/gap bytes, which hold no data. That is the recommended way to load
 * a file. Validating FULL first and then reading reads and checks every
 * payload twice: the reader keeps no "already verified" state, because the
 * bytes under a path, mmap or memory reader can change between calls. Use
 * MESO_CHECK_FULL for whole-file verdicts (mesoinspect validate --full, CI,
 * before publishing a file), not as a step before reading. */
MESO_API meso_result meso_file_read_chunk(meso_file* f, uint32_t index, void* dst, size_t dst_size,
                                          meso_error* err);
/* Zero-copy pointer to the stored bytes (memory and mmap readers only;
 * MESO_ERR_UNSUPPORTED otherwise). The CRC is not checked here. */
MESO_API meso_result meso_file_chunk_view(const meso_file* f, uint32_t index, const void** data, meso_error* err);

/* >>validation ------------------------------------------------------------ */

typedef enum meso_check {
    MESO_CHECK_CHEAP = 0, /* what open already did */
    MESO_CHECK_FULL = 1,  /* + every payload CRC, padding zero, structured chunk contents, JSON well-formed */
    MESO_CHECK_COUNT
} meso_check;

/* Called once per issue found; return non-zero to stop early. */
typedef int (*meso_issue_fn)(void* user, const meso_error* issue);

/* Validate an open file. Returns MESO_OK when no issue was found, otherwise
 * the result of the first issue; every issue goes to `fn` (may be NULL).
 * MESO_CHECK_CHEAP returns MESO_OK at once (open already refused any file
 * failing it). MESO_CHECK_FULL reads every payload once; with a decoder for
 * an encoded MESH it also decodes and checks it. */
MESO_API meso_result meso_file_validate(meso_file* f, meso_check level, meso_issue_fn fn, void* user);

/* Check the chunks of cells object `object` against its CELL record
 * (FORMAT.md §7.8): TILE, SPLT, MEMB, NRMM and COLR present at lod 0 with
 * the element types and dims CELL implies (issue 4803), TILE values <= S
 * (4804), the SPLT table (4805) and the MEMB structure (4806). Reads CELL,
 * TILE, SPLT and MEMB with meso_file_read_chunk (so their CRCs and contents
 * are checked too). MESO_CHECK_FULL runs it for every CELL chunk. */
MESO_API meso_result meso_file_check_cells(meso_file* f, uint32_t object, meso_error* err);
/* The same for the chunks level `lod` draws (FORMAT.md §7.10: per type the
 * object's chunk with the smallest lod >= `lod`); lod 0 is
 * meso_file_check_cells. A native coarser level of a cells object has its
 * own CELL record and chunks. */
MESO_API meso_result meso_file_check_cells_level(meso_file* f, uint32_t object, uint16_t lod, meso_error* err);

/* Check object `object` (an OBJT record) against what its kind is made of
 * (FORMAT.md §7.2, issues 6001..6301): the chunks the kind requires, the
 * counts that tie them together (SDIR and STHK per MESH vertex, one FSEG
 * per FRUS, SKEL node references in range) and the values a renderer relies
 * on (finite directors, thickness > 0, texture types, non-degenerate
 * frusta). Reads the MESH header (64 bytes) and, for shells and frusta, the
 * SDIR, STHK, DIST (F32), SKEL, FRUS, FSEG and BALL chunks with
 * meso_file_read_chunk, so their CRCs and contents are checked too; a cells
 * object's CELL rules are meso_file_check_cells'. Returns the first issue
 * (MESO_ERR_CORRUPT), MESO_ERR_NOT_FOUND when no OBJT record has this id.
 * MESO_CHECK_FULL runs it for every object; libmeso's loader runs it before
 * it uploads an object. */
MESO_API meso_result meso_file_check_object(meso_file* f, uint32_t object, meso_error* err);

/* >>writer ---------------------------------------------------------------- */

typedef struct meso_writer meso_writer;

typedef struct meso_chunk_desc {
    uint32_t type;
    uint32_t flags;
    uint32_t object;
    uint16_t lod;
    uint16_t encoding;
    uint64_t decoded_size; /* 0 means: same as the data size (raw) */
    uint16_t dtype;
    uint16_t components;   /* 0 means 1 */
    uint32_t dims[3];      /* 0 means 1 */
} meso_chunk_desc;

/* `allocator` may be NULL. */
MESO_API meso_result meso_writer_create(const meso_allocator* allocator, meso_writer** out);
MESO_API void meso_writer_destroy(meso_writer* w);
/* Add a chunk; the data is copied. Chunks are laid out coarsest level first
 * (lod descending), then in the order added; the writer is deterministic. */
MESO_API meso_result meso_writer_add(meso_writer* w, const meso_chunk_desc* desc, const void* data, size_t size,
                                     meso_error* err);
/* Serialise into dst. With dst == NULL only *needed is set. */
MESO_API meso_result meso_writer_finish(meso_writer* w, void* dst, size_t dst_size, size_t* needed);
/* Serialise to `path` atomically (meso_output_open, meso_writer_write_output,
 * meso_output_commit): a temporary file beside the destination, fsync, then
 * rename over it. A symbolic link is written through to its final target; a
 * destination that is not a regular file is refused (see meso_output_check).
 * On failure the destination is untouched and no temporary file is left. */
MESO_API meso_result meso_writer_write_file(meso_writer* w, const char* path, meso_error* err);

/* >>atomic output (FORMAT.md §10) -----------------------------------------
 * One file written atomically, in three steps, so that a program can publish
 * several files together and clean up on a signal: meso_output_open creates
 * the temporary file and returns its path (a program registers `temp` with
 * its own signal handler; this library installs none), the program writes,
 * then meso_output_commit publishes it or meso_output_abort removes it. */

typedef struct meso_output {
    char* path;  /* read-only: the destination, `path` or a symbolic link's final target */
    char* temp;  /* read-only: ".NAME.tmp.XXXXXX" in the destination's directory; NULL when closed */
    int fd;      /* read-only: open for writing on `temp`, -1 when closed */
    uint32_t mode; /* permissions of the file being replaced (kept), 0 for a new file */
    meso_allocator allocator;
} meso_output;

/* May `path` be replaced by an atomic write? Yes when it does not exist (and
 * its directory does), when it is a regular file, or when it is a symbolic
 * link whose final target is a regular file. A dangling or looping symbolic
 * link, a directory, a character or block device, a FIFO, a socket or any
 * other non-regular file is refused: MESO_ERR_IO with issue
 * MESO_ISSUE_IO_DESTINATION and a message naming the path and what it is.
 * Never opens `path`, so a FIFO cannot block. */
MESO_API meso_result meso_output_check(const char* path, meso_error* err);
/* Check `path` as meso_output_check does, then create the temporary file in
 * the destination's directory (exclusive create; a replaced file's
 * permissions are kept, a new file gets 0666 minus the umask). `allocator`
 * may be NULL. On failure *out is closed (temp NULL, fd -1). */
MESO_API meso_result meso_output_open(const char* path, const meso_allocator* allocator, meso_output* out,
                                      meso_error* err);
/* Append bytes to the temporary file. A program may also write `temp` by
 * name (e.g. a PNG library) as long as it closes its own handle first. */
MESO_API meso_result meso_output_write(meso_output* out, const void* data, size_t size, meso_error* err);
/* Serialise a writer into an open output. */
MESO_API meso_result meso_writer_write_output(meso_writer* w, meso_output* out, meso_error* err);
/* fsync and close the temporary file, check the destination again, rename
 * the temporary file over it and fsync the directory (best effort). On
 * failure the temporary file is removed and the destination untouched.
 * Either way *out is closed afterwards. */
MESO_API meso_result meso_output_commit(meso_output* out, meso_error* err);
/* Close and remove the temporary file; the destination is untouched. Does
 * nothing on a closed output. */
MESO_API void meso_output_abort(meso_output* out);

/* >>chunk contents -------------------------------------------------------- */

/* Issue codes (FORMAT.md §"Issue codes" gives each one's meso_result and
 * meaning): 1xxx header, 2xxx TOC, 3xxx payload, 4xxx structured chunk
 * contents, 5xxx I/O and API. The numbers are stable; new ones are appended. */
#define MESO_ISSUE_NONE 0u
#define MESO_ISSUE_HDR_TRUNCATED 1001u       /* shorter than the 64-byte header */
#define MESO_ISSUE_HDR_MAGIC 1002u           /* not a .meso file */
#define MESO_ISSUE_HDR_TEXT_MODE 1003u       /* magic damaged by CR/LF conversion */
#define MESO_ISSUE_HDR_7BIT 1004u            /* magic damaged by a 7-bit transfer */
#define MESO_ISSUE_HDR_LEGACY 1005u          /* major version 0 */
#define MESO_ISSUE_HDR_TOO_NEW 1006u         /* major version newer than this reader */
#define MESO_ISSUE_HDR_CRC 1007u
#define MESO_ISSUE_HDR_FLAGS 1008u
#define MESO_ISSUE_HDR_RESERVED 1009u
#define MESO_ISSUE_HDR_TOC_OFFSET 1010u
#define MESO_ISSUE_HDR_TOC_ENTRY_SIZE 1011u
#define MESO_ISSUE_HDR_FILE_SIZE_ALIGN 1012u
#define MESO_ISSUE_FILE_TRUNCATED 1013u      /* fewer bytes than file_size */
#define MESO_ISSUE_FILE_TRAILING 1014u       /* more bytes than file_size */
#define MESO_ISSUE_TOC_TOO_MANY 2001u        /* chunk_count > max_chunks */
#define MESO_ISSUE_TOC_BOUNDS 2002u
#define MESO_ISSUE_TOC_CRC 2003u
#define MESO_ISSUE_CHUNK_TYPE 2004u
#define MESO_ISSUE_CHUNK_FLAGS 2005u
#define MESO_ISSUE_CHUNK_RESERVED 2006u
#define MESO_ISSUE_CHUNK_ALIGN 2007u
#define MESO_ISSUE_CHUNK_BOUNDS 2008u
#define MESO_ISSUE_CHUNK_IN_TOC 2009u
#define MESO_ISSUE_CHUNK_ORDER 2010u
#define MESO_ISSUE_CHUNK_OVERLAP 2011u
#define MESO_ISSUE_CHUNK_EMPTY 2012u
#define MESO_ISSUE_CHUNK_ENCODING 2013u
#define MESO_ISSUE_CHUNK_DTYPE 2014u
#define MESO_ISSUE_CHUNK_COMPONENTS 2015u
#define MESO_ISSUE_CHUNK_DIMS 2016u
#define MESO_ISSUE_CHUNK_RAW_SIZE 2017u
#define MESO_ISSUE_CHUNK_TYPED_SIZE 2018u
#define MESO_ISSUE_CHUNK_UNKNOWN_REQUIRED 2019u
#define MESO_ISSUE_FILE_END 2020u
#define MESO_ISSUE_CHUNK_EXPANSION 2021u     /* Draco decoded_size > 1024 x stored_size + 64 KiB */
#define MESO_ISSUE_CHUNK_DECODED_LIMIT 2022u /* encoded decoded_size > meso_open_desc.max_decoded_size */
#define MESO_ISSUE_PAYLOAD_CRC 3001u
#define MESO_ISSUE_PAYLOAD_PADDING 3002u
#define MESO_ISSUE_ENCODING_UNSUPPORTED 3003u
#define MESO_ISSUE_DECODE_FAILED 3004u
#define MESO_ISSUE_TYPE_ELEMENT 4001u        /* dtype/components/dims wrong for the chunk type */
#define MESO_ISSUE_TYPE_ENCODING 4002u
#define MESO_ISSUE_TYPE_OBJECT 4003u
#define MESO_ISSUE_JSON_UTF8 4101u
#define MESO_ISSUE_JSON_SYNTAX 4102u
#define MESO_ISSUE_JSON_DEPTH 4103u
#define MESO_ISSUE_OBJT_SIZE 4201u
#define MESO_ISSUE_OBJT_ID 4202u
#define MESO_ISSUE_OBJT_DUPLICATE 4203u
#define MESO_ISSUE_OBJT_KIND 4204u
#define MESO_ISSUE_OBJT_NAME 4205u
#define MESO_ISSUE_OBJT_BBOX 4206u
#define MESO_ISSUE_MESH_SIZE 4301u
#define MESO_ISSUE_MESH_ATTRIBUTES 4302u
#define MESO_ISSUE_MESH_COUNTS 4303u
#define MESO_ISSUE_MESH_RESERVED 4304u
#define MESO_ISSUE_MESH_QUANT 4305u
#define MESO_ISSUE_MESH_PRESENCE 4306u
#define MESO_ISSUE_MESH_ALIGN 4307u
#define MESO_ISSUE_MESH_OVERLAP 4308u
#define MESO_ISSUE_MESH_BOUNDS 4309u
#define MESO_ISSUE_MESH_TRAILING 4310u
#define MESO_ISSUE_MESH_INDEX 4311u
#define MESO_ISSUE_MESH_VALUE 4312u          /* non-finite position, normal or uv */
#define MESO_ISSUE_SKEL_SIZE 4401u
#define MESO_ISSUE_SKEL_PARENT 4402u
#define MESO_ISSUE_SKEL_VALUE 4403u
#define MESO_ISSUE_FRUS_SIZE 4501u
#define MESO_ISSUE_FRUS_VALUE 4502u
#define MESO_ISSUE_FSEG_SIZE 4601u
#define MESO_ISSUE_FSEG_VALUE 4602u
#define MESO_ISSUE_BALL_SIZE 4701u
#define MESO_ISSUE_BALL_VALUE 4702u
#define MESO_ISSUE_CELL_SIZE 4801u
#define MESO_ISSUE_CELL_VALUE 4802u
#define MESO_ISSUE_CELL_CHUNKS 4803u
#define MESO_ISSUE_CELL_TILE 4804u
#define MESO_ISSUE_CELL_SPLT 4805u
#define MESO_ISSUE_CELL_MEMB 4806u
#define MESO_ISSUE_ANIM_SIZE 4901u           /* ANIM is not one 32-byte record */
#define MESO_ISSUE_ANIM_VALUE 4902u          /* ANIM field out of range or reserved bytes not zero */
#define MESO_ISSUE_CMAP_SIZE 4911u           /* CMAP is not one 32-byte record */
#define MESO_ISSUE_CMAP_VALUE 4912u          /* CMAP field out of range or reserved bytes not zero */
#define MESO_ISSUE_LODS_SIZE 4921u           /* LODS size not a multiple of 48 */
#define MESO_ISSUE_LODS_VALUE 4922u          /* LODS record out of order, out of range, or reserved bytes not zero */
#define MESO_ISSUE_PRTS_SIZE 4931u           /* PRTS size does not match its header's counts */
#define MESO_ISSUE_PRTS_VALUE 4932u          /* PRTS record or neighbour pair out of order or range, reserved not zero */
#define MESO_ISSUE_OBJ_CHUNKS 6001u          /* an object lacks a chunk its kind requires */
#define MESO_ISSUE_MESH_VCOL 6002u           /* VCOL count != the vertex count of its lod's MESH */
#define MESO_ISSUE_SHELL_COUNT 6101u         /* SDIR/STHK count != MESH vertex count, or no triangles */
#define MESO_ISSUE_SHELL_SDIR 6102u          /* non-finite director */
#define MESO_ISSUE_SHELL_STHK 6103u          /* thickness not finite or not > 0 */
#define MESO_ISSUE_SHELL_TEXTURE 6104u       /* texture function chunks not as FORMAT.md 7.2 */
#define MESO_ISSUE_SHELL_ANIM 6105u          /* ANIM/TXFR/DSFR do not fit the shell's texture function */
#define MESO_ISSUE_SHELL_COLOR 6106u         /* COLR/CMAP of a shell not as FORMAT.md 7.2 */
#define MESO_ISSUE_FRUSTA_COUNT 6201u        /* FSEG and FRUS record counts differ */
#define MESO_ISSUE_FRUSTA_NODE 6202u         /* a SKEL node reference out of range */
#define MESO_ISSUE_FRUSTA_AXIS 6203u         /* zero-length axis or zero cutting-plane normal */
#define MESO_ISSUE_FRUSTA_RELF 6204u         /* RELF not U8 or U16 x 1 */
#define MESO_ISSUE_FRUSTA_COLR 6205u         /* frusta COLR not one U8 x 4, W x H x 1 chunk */
#define MESO_ISSUE_CELLS_COLOUR_GRID 6301u   /* cells TX3D (mesh colour grid) not one U8 x 4 chunk */
#define MESO_ISSUE_LEVELS 6401u              /* an object's LODS levels do not fit its OBJT record or its chunks */
#define MESO_ISSUE_PARTS 6501u               /* PRTS does not fit its object or its PMSH chunks */
#define MESO_ISSUE_API_ARG 5001u
#define MESO_ISSUE_API_BUFFER 5002u
#define MESO_ISSUE_API_MEMORY 5003u
#define MESO_ISSUE_IO_OPEN 5004u
#define MESO_ISSUE_IO_READ 5005u
#define MESO_ISSUE_IO_MMAP 5006u
#define MESO_ISSUE_IO_WRITE 5007u
#define MESO_ISSUE_API_NO_VIEW 5008u
#define MESO_ISSUE_API_TOO_LARGE 5009u
#define MESO_ISSUE_API_WRITER_LIMIT 5010u
#define MESO_ISSUE_IO_DESTINATION 5011u /* an output path that must not be replaced */

/* MESH attribute bits (mesh header field `attributes`). */
#define MESO_MESH_ATTR_POSITIONS 0x1u /* f32x3 per vertex; always present */
#define MESO_MESH_ATTR_NORMALS 0x2u   /* f32x3 per vertex */
#define MESO_MESH_ATTR_UVS 0x4u       /* f32x2 per vertex */

/* The decoded layout of a MESH chunk: 64-byte header, then positions,
 * normals, uvs and indices, each 16-byte aligned (offsets from chunk start,
 * 0 when absent). `size` is the decoded chunk size (end of the last array). */
typedef struct meso_mesh_layout {
    uint32_t vertex_count;
    uint32_t index_count;        /* multiple of 3 */
    uint32_t attributes;         /* MESO_MESH_ATTR_* */
    uint8_t quant_bits_position; /* 0 = never quantised */
    uint8_t quant_bits_normal;
    uint8_t quant_bits_uv;
    uint64_t positions_offset;
    uint64_t normals_offset;
    uint64_t uvs_offset;
    uint64_t indices_offset;
    uint64_t size;
} meso_mesh_layout;

/* Fill *out with the canonical layout for these counts (quant bits 0).
 * MESO_ERR_INVALID_ARG when vertex_count is 0, index_count is not a multiple
 * of 3, positions are missing, unknown bits are set or the size overflows. */
MESO_API meso_result meso_mesh_compute_layout(uint32_t vertex_count, uint32_t index_count, uint32_t attributes,
                                              meso_mesh_layout* out);
/* Write the 64-byte MESH header described by `layout` to dst. */
MESO_API void meso_mesh_write_header(const meso_mesh_layout* layout, void* dst);

/* Typed pointers into a decoded MESH chunk (NULL for absent arrays). */
typedef struct meso_mesh_view {
    meso_mesh_layout layout;
    const float* positions;  /* vertex_count x 3 */
    const float* normals;    /* vertex_count x 3 or NULL */
    const float* uvs;        /* vertex_count x 2 or NULL */
    const uint32_t* indices; /* index_count or NULL when index_count is 0 */
} meso_mesh_view;

/* Parse and validate a decoded MESH chunk (header, layout and every index).
 * `data` must be 4-byte aligned (MESO_ERR_INVALID_ARG otherwise) and outlive
 * the view. The arrays are little-endian, i.e. host order on every target
 * meso supports. */
MESO_API meso_result meso_mesh_parse(const void* data, size_t size, meso_mesh_view* out, meso_error* err);

/* OBJT record kinds. */
typedef enum meso_object_kind {
    MESO_OBJECT_INVALID = 0,
    MESO_OBJECT_MESH = 1,
    MESO_OBJECT_SHELL = 2,
    MESO_OBJECT_CELLS = 3,
    MESO_OBJECT_FRUSTA = 4,
    MESO_OBJECT_KIND_COUNT
} meso_object_kind;

/* One 64-byte OBJT record, decoded. */
typedef struct meso_object_record {
    uint32_t id;          /* >= 1, unique in the chunk; chunks refer to it by `object` */
    uint32_t kind;        /* meso_object_kind */
    float bbox_min[3];
    float bbox_max[3];
    char name[32];        /* NUL-terminated, NUL-padded (at most 31 characters) */
} meso_object_record;

/* Encode one record into 64 bytes at dst (the name is truncated to 31
 * bytes and NUL-padded) / decode 64 bytes at src. */
MESO_API void meso_object_record_encode(const meso_object_record* rec, void* dst);
MESO_API void meso_object_record_decode(const void* src, meso_object_record* rec);

/* One 32-byte ANIM record (FORMAT.md §7.2 "Animated texture functions"),
 * decoded: frame k of the shell's texture function holds time
 * time0 + k / fps seconds and is slab k of its TXFR (and DSFR) chunk. */
typedef struct meso_anim_record {
    uint32_t frame_count; /* 1..MESO_ANIM_MAX_FRAMES */
    uint32_t flags;       /* MESO_ANIM_FLAG_LOOP or 0 */
    float fps;            /* frames per second, finite and > 0 */
    float time0;          /* time of frame 0, seconds, finite */
} meso_anim_record;
#define MESO_ANIM_FLAG_LOOP 0x1u /* after the last frame the sequence starts again (else it holds) */
#define MESO_ANIM_MAX_FRAMES 4096u

/* Encode one record into 32 bytes at dst (reserved bytes zero) / decode 32
 * bytes at src (no checks: the full tier and meso_file_read_chunk check). */
MESO_API void meso_anim_record_encode(const meso_anim_record* rec, void* dst);
MESO_API void meso_anim_record_decode(const void* src, meso_anim_record* rec);
/* The frame shown at time t: k = floor((t - time0) fps + 1e-4), wrapped into
 * 0..frame_count-1 with LOOP, else clamped (the 1e-4 frame keeps t = time0
 * + k / fps on frame k despite rounding). */
MESO_API uint32_t meso_anim_frame_at(const meso_anim_record* rec, double t);

/* One 32-byte CMAP record (FORMAT.md §7.2 "Shell colour"), decoded: a
 * shell's COLR is looked up at (s · scale[0], t' · scale[1], w) for the
 * texture point (s, t', w) of a hit (wraps in s and t', clamps in w). */
typedef struct meso_cmap_record {
    uint32_t mapping; /* MESO_CMAP_TILED or MESO_CMAP_BASE: what the colour follows (scale says how) */
    uint32_t flags;   /* 0 (no flags defined) */
    float scale[2];   /* finite, > 0; TILED: 1, 1; BASE: 1 / the bake's tiling */
} meso_cmap_record;
#define MESO_CMAP_TILED 0u /* one COLR tile per texture tile, like the texture function */
#define MESO_CMAP_BASE 1u  /* the COLR spans the base mesh's own uv square once (colour of the mesh) */

/* Encode one record into 32 bytes at dst (reserved bytes zero) / decode 32
 * bytes at src (no checks: the full tier and meso_file_read_chunk check). */
MESO_API void meso_cmap_record_encode(const meso_cmap_record* rec, void* dst);
MESO_API void meso_cmap_record_decode(const void* src, meso_cmap_record* rec);

/* Levels of detail (FORMAT.md §7.10). Level `lod` of an object draws, for
 * each chunk type it needs, the object's chunk of that type with the
 * smallest lod >= `lod` (meso_file_find_level); a level's `form` says what
 * draws it. An object without LODS records has one level, lod 0, error 0,
 * its OBJT bounds, form NATIVE. */
typedef enum meso_level_form {
    MESO_LEVEL_NATIVE = 0, /* the object's own kind draws it (shell, cells, frusta, mesh) */
    MESO_LEVEL_MESH = 1,   /* a stand-in: the object's MESH at this level drawn as a plain mesh */
    MESO_LEVEL_FORM_COUNT
} meso_level_form;

/* One 48-byte LODS record, decoded. */
typedef struct meso_level_record {
    uint32_t object; /* OBJT id */
    uint16_t lod;    /* 0 = finest; an object's records are lod 0, 1, .. K-1 */
    uint16_t form;   /* meso_level_form */
    float error;     /* object units: the largest distance between this level's surface and lod 0's;
                        finite, >= 0, 0 at lod 0, non-decreasing with lod */
    float bbox_min[3], bbox_max[3]; /* what this level draws lies inside */
} meso_level_record;

MESO_API void meso_level_record_encode(const meso_level_record* rec, void* dst);
MESO_API void meso_level_record_decode(const void* src, meso_level_record* rec);

/* A level as a reader sees it: the record plus its place in the file. */
typedef struct meso_level_info {
    meso_level_record rec;
    uint64_t bytes;        /* stored bytes of the chunks this level draws */
    uint64_t prefix_bytes; /* the shortest prefix of the file that holds them all (and the header, TOC, META,
                              OBJT and LODS): where the last of their stored bytes ends */
} meso_level_info;

/* Index of the chunk of `type` and `object` with the smallest lod >= `lod`
 * (what level `lod` draws), or -1. */
MESO_API int32_t meso_file_find_level(const meso_file* f, uint32_t type, uint32_t object, uint16_t lod);

/* The VCOL chunk (vertex colours, FORMAT.md §7.3) that goes with the MESH
 * level `lod` of `object` draws: the one at that MESH's own lod, or -1
 * (no MESH, or none there: the mesh is drawn with the draw's albedo). */
MESO_API int32_t meso_file_find_vertex_colours(const meso_file* f, uint32_t object, uint16_t lod);
/* The levels of `object`: reads and checks the LODS chunk (when there is
 * one) and writes up to `cap` entries finest first (NULL with cap 0 only
 * counts); *count gets the number of levels (>= 1 for an object in OBJT).
 * MESO_ERR_NOT_FOUND when no OBJT record has this id. */
MESO_API meso_result meso_file_levels(meso_file* f, uint32_t object, meso_level_info* out, uint32_t cap,
                                      uint32_t* count, meso_error* err);

/* Parts (FORMAT.md §7.11): a mesh object may also be stored cut into
 * parts, each with levels of its own (PMSH chunks, one per part and
 * level), so that a reader can draw the near end of an object finer than
 * the far end. One part level as a reader sees it: */
typedef struct meso_part_level {
    meso_level_record rec;   /* rec.object = the part, 1..part_count; rec.lod its level; error against the
                                part's level 0, bounds of the level. A mesh object's part levels are form
                                NATIVE; a shell's lod 0 is NATIVE (its prisms, drawn by the shell's native
                                levels) and its lods 1.. form MESH (a stand-in of the part) */
    uint32_t first_triangle; /* a shell part's lod 0: its prisms are the level-0 MESH triangles the PTRI */
    uint32_t triangle_count; /*   chunk holds at first_triangle .. + triangle_count - 1
                                  (meso_file_part_triangles); 0, 0 otherwise */
    int32_t chunk;           /* its PMSH chunk (-1 when missing: the full tier refuses that); a shell part's
                                lod 0: the object's PTRI chunk */
    int32_t colours;         /* its PVCL chunk (vertex colours of that PMSH), -1 when it has none */
    uint64_t bytes;          /* stored bytes of those chunks (0 for a shell part's lod 0) */
    uint64_t prefix_bytes;   /* the shortest prefix holding it, the header, TOC, META, OBJT, LODS and PRTS */
} meso_part_level;

/* The parts of `object`: reads and checks its PRTS chunk and writes up to
 * `cap` part levels (by part, then lod; NULL with cap 0 only counts) and
 * up to `edge_cap` neighbour pairs (2 part numbers each, a < b; NULL with
 * edge_cap 0 only counts). *level_count, *part_count and *edge_count get
 * the totals; all 0 for an object stored without parts. */
MESO_API meso_result meso_file_parts(meso_file* f, uint32_t object, meso_part_level* out, uint32_t cap,
                                     uint32_t* level_count, uint32_t* part_count, uint32_t* edges,
                                     uint32_t edge_cap, uint32_t* edge_count, meso_error* err);
/* A shell's parts' triangle list, its PTRI chunk (the level-0 MESH
 * triangle of each prism, part after part; meso_part_level.first_triangle
 * indexes it): up to `cap` entries (NULL with cap 0 only counts), *count
 * the total (0 for a mesh object's parts, or an object without parts). */
MESO_API meso_result meso_file_part_triangles(meso_file* f, uint32_t object, uint32_t* out, uint32_t cap,
                                              uint32_t* count, meso_error* err);

/* The file's objects: reads and checks the OBJT chunk (CRC and records) and
 * writes up to `cap` records to `out` (NULL with cap 0 only counts); *count
 * gets the number of objects. A file without an OBJT chunk has none. */
MESO_API meso_result meso_file_objects(meso_file* f, meso_object_record* out, uint32_t cap, uint32_t* count,
                                       meso_error* err);

/* >>checksum -------------------------------------------------------------- */

/* CRC32C (Castagnoli), hardware-accelerated with SSE4.2 when the CPU has it.
 * Pass 0 as `crc` to start. */
MESO_API uint32_t meso_crc32c(uint32_t crc, const void* data, size_t size);

#ifdef __cplusplus
}
#endif
#endif /* MESO_FILE_H */
