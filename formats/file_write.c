/*
 * file_write.c — the .meso writer.
 *
 * meso_writer_add checks each chunk with the reader's own rules
 * (file_validate.c), so a file the writer emits always opens and passes full
 * validation. Layout is a pure function of the chunks added: META, OBJT,
 * LODS, PRTS, RPRT first (small, describe the rest), then every other chunk coarsest
 * level first (lod descending), ties in insertion order. A prefix of the file
 * therefore already holds the coarse levels. No timestamps, no host data.
 */
#include "file_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#define WRITER_MAX_CHUNKS (1u << 20) /* = the reader's default max_chunks */

typedef struct wchunk {
    meso_chunk_info info;
    uint8_t* data;
    uint32_t group; /* 0 META, 1 OBJT, 2 LODS, 3 PRTS, 4 RPRT, 5 everything else */
    uint64_t seq;   /* insertion order */
} wchunk;

struct meso_writer {
    meso_allocator alloc;
    wchunk* chunks; /* kept sorted in file order */
    uint32_t count;
    uint32_t cap;
    uint64_t seq;
    uint64_t payload_bytes; /* sum of stored sizes padded to 64 */
};

meso_result meso_writer_create(const meso_allocator* allocator, meso_writer** out)
{
    meso_allocator a;
    if (out == NULL)
        return MESO_ERR_INVALID_ARG;
    *out = NULL;
    if (mesoi_file_allocator_init(allocator, &a) != MESO_OK)
        return MESO_ERR_INVALID_ARG;
    meso_writer* w = (meso_writer*)mesoi_file_alloc(&a, sizeof *w);
    if (!w)
        return MESO_ERR_OUT_OF_MEMORY;
    memset(w, 0, sizeof *w);
    w->alloc = a;
    *out = w;
    return MESO_OK;
}

void meso_writer_destroy(meso_writer* w)
{
    if (w == NULL)
        return;
    for (uint32_t i = 0; i < w->count; i++)
        mesoi_file_free(&w->alloc, w->chunks[i].data);
    mesoi_file_free(&w->alloc, w->chunks);
    meso_allocator a = w->alloc;
    mesoi_file_free(&a, w);
}

static uint32_t group_of(uint32_t type)
{
    return type == MESO_CHUNK_META   ? 0u
           : type == MESO_CHUNK_OBJT ? 1u
           : type == MESO_CHUNK_LODS ? 2u
           : type == MESO_CHUNK_PRTS ? 3u
           : type == MESO_CHUNK_RPRT ? 4u
                                     : 5u;
}

/* File order: group, then lod descending, then insertion. */
static int before(const wchunk* a, const wchunk* b)
{
    if (a->group != b->group)
        return a->group < b->group;
    if (a->info.lod != b->info.lod)
        return a->info.lod > b->info.lod;
    return a->seq < b->seq;
}

/* A reader-side rule failed: the caller passed a bad chunk. */
static meso_result as_arg_error(meso_result r, meso_error* err)
{
    if (r == MESO_OK)
        return r;
    if (err)
        err->result = MESO_ERR_INVALID_ARG;
    return MESO_ERR_INVALID_ARG;
}

meso_result meso_writer_add(meso_writer* w, const meso_chunk_desc* desc, const void* data, size_t size, meso_error* err)
{
    mesoi_file_error_clear(err);
    if (w == NULL || desc == NULL || (data == NULL && size > 0))
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1, "NULL argument");
    int32_t ci = (int32_t)w->count;
    if (w->count >= WRITER_MAX_CHUNKS)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_WRITER_LIMIT, UINT64_MAX, ci,
                                "more than %u chunks", WRITER_MAX_CHUNKS);
    meso_chunk_info c;
    memset(&c, 0, sizeof c);
    c.type = desc->type;
    c.flags = desc->flags;
    c.object = desc->object;
    c.lod = desc->lod;
    c.encoding = desc->encoding;
    c.stored_size = size;
    c.decoded_size = desc->decoded_size ? desc->decoded_size : (desc->encoding == MESO_ENCODING_RAW ? size : 0);
    c.dtype = desc->dtype;
    c.components = desc->components ? desc->components : 1;
    for (int k = 0; k < 3; k++)
        c.dims[k] = desc->dims[k] ? desc->dims[k] : 1;
    if (c.decoded_size == 0 && size > 0)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, ci,
                                "an encoded chunk needs desc->decoded_size");
    /* The same rules the reader applies (a 1.0 file: no unknown enums). */
    meso_result r = mesoi_check_entry(&c, 0, MESO_FORMAT_MINOR, ci, UINT64_MAX, err);
    if (r == MESO_OK)
        r = mesoi_check_type_rules(&c, ci, err);
    if (r == MESO_OK && mesoi_known_type(c.type)) {
        if (c.encoding == MESO_ENCODING_RAW)
            r = mesoi_check_contents(&c, (const uint8_t*)data, size, ci, UINT64_MAX, err);
        else if (mesoi_mesh_layout(c.type) && size < MESO_MESH_HDR_SIZE)
            r = mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_MESH_SIZE, UINT64_MAX, ci,
                                 "chunk %d (MESH layout): encoded payload is smaller than the 64-byte mesh header",
                                 (int)ci);
        else if (mesoi_mesh_layout(c.type))
            r = mesoi_check_mesh_header((const uint8_t*)data, c.decoded_size, NULL, ci, UINT64_MAX, err);
    }
    if (r != MESO_OK)
        return as_arg_error(r, err);
    uint64_t padded = mesoi_align64(size);
    if (w->payload_bytes > UINT64_MAX / 2 - padded)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_WRITER_LIMIT, UINT64_MAX, ci,
                                "total file size overflows");
    if (w->count == w->cap) {
        uint32_t cap = w->cap ? w->cap * 2 : 16;
        wchunk* grown = (wchunk*)mesoi_file_alloc(&w->alloc, (size_t)cap * sizeof(wchunk));
        if (!grown)
            return mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, ci,
                                    "out of memory");
        if (w->count)
            memcpy(grown, w->chunks, (size_t)w->count * sizeof(wchunk));
        mesoi_file_free(&w->alloc, w->chunks);
        w->chunks = grown;
        w->cap = cap;
    }
    wchunk n;
    n.info = c;
    n.info.crc32c = meso_crc32c(0, data, size);
    n.group = group_of(c.type);
    n.seq = w->seq;
    n.data = (uint8_t*)mesoi_file_alloc(&w->alloc, size);
    if (!n.data)
        return mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, ci,
                                "out of memory copying %zu bytes", size);
    if (size)
        memcpy(n.data, data, size);
    /* Upper bound: the new chunk goes after every chunk that sorts before it. */
    uint32_t lo = 0, hi = w->count;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (before(&w->chunks[mid], &n))
            lo = mid + 1;
        else
            hi = mid;
    }
    memmove(&w->chunks[lo + 1], &w->chunks[lo], (size_t)(w->count - lo) * sizeof(wchunk));
    w->chunks[lo] = n;
    w->count++;
    w->seq++;
    w->payload_bytes += padded;
    return MESO_OK;
}

/* >>serialisation ---------------------------------------------------------- */

static uint64_t header_toc_size(const meso_writer* w)
{
    return (uint64_t)MESO_HDR_SIZE + (uint64_t)w->count * MESO_TOC_ENTRY_SIZE; /* already 64-aligned */
}

/* Assign offsets and fill the header + TOC (header_toc_size bytes). */
static void build_header_toc(meso_writer* w, uint8_t* buf)
{
    uint64_t toc_size = (uint64_t)w->count * MESO_TOC_ENTRY_SIZE;
    uint64_t off = header_toc_size(w);
    memset(buf, 0, (size_t)off);
    for (uint32_t i = 0; i < w->count; i++) {
        meso_chunk_info* c = &w->chunks[i].info;
        uint8_t* e = buf + MESO_HDR_SIZE + (size_t)i * MESO_TOC_ENTRY_SIZE;
        c->offset = off;
        off += mesoi_align64(c->stored_size);
        mesoi_st32(e + MESO_TOC_OFF_TYPE, c->type);
        mesoi_st32(e + MESO_TOC_OFF_FLAGS, c->flags);
        mesoi_st32(e + MESO_TOC_OFF_OBJECT, c->object);
        mesoi_st16(e + MESO_TOC_OFF_LOD, c->lod);
        mesoi_st16(e + MESO_TOC_OFF_ENCODING, c->encoding);
        mesoi_st64(e + MESO_TOC_OFF_OFFSET, c->offset);
        mesoi_st64(e + MESO_TOC_OFF_STORED_SIZE, c->stored_size);
        mesoi_st64(e + MESO_TOC_OFF_DECODED_SIZE, c->decoded_size);
        mesoi_st32(e + MESO_TOC_OFF_CRC, c->crc32c);
        mesoi_st16(e + MESO_TOC_OFF_DTYPE, c->dtype);
        mesoi_st16(e + MESO_TOC_OFF_COMPONENTS, c->components);
        for (int k = 0; k < 3; k++)
            mesoi_st32(e + MESO_TOC_OFF_DIMS + 4 * k, c->dims[k]);
    }
    memcpy(buf + MESO_HDR_OFF_MAGIC, mesoi_magic, MESO_HDR_SIZE_MAGIC);
    mesoi_st16(buf + MESO_HDR_OFF_MAJOR, MESO_FORMAT_MAJOR);
    mesoi_st16(buf + MESO_HDR_OFF_MINOR, MESO_FORMAT_MINOR);
    mesoi_st64(buf + MESO_HDR_OFF_FILE_SIZE, off);
    mesoi_st64(buf + MESO_HDR_OFF_TOC_OFFSET, MESO_HDR_SIZE);
    mesoi_st32(buf + MESO_HDR_OFF_CHUNK_COUNT, w->count);
    mesoi_st32(buf + MESO_HDR_OFF_TOC_ENTRY_SIZE, MESO_TOC_ENTRY_SIZE);
    mesoi_st32(buf + MESO_HDR_OFF_TOC_CRC, meso_crc32c(0, buf + MESO_HDR_SIZE, (size_t)toc_size));
    mesoi_st32(buf + MESO_HDR_OFF_HEADER_CRC, meso_crc32c(0, buf, MESO_HDR_SIZE));
}

static uint64_t total_size(const meso_writer* w) { return header_toc_size(w) + w->payload_bytes; }

meso_result meso_writer_finish(meso_writer* w, void* dst, size_t dst_size, size_t* needed)
{
    if (w == NULL)
        return MESO_ERR_INVALID_ARG;
    uint64_t total = total_size(w);
    if (total > SIZE_MAX)
        return MESO_ERR_UNSUPPORTED;
    if (needed)
        *needed = (size_t)total;
    if (dst == NULL)
        return needed ? MESO_OK : MESO_ERR_INVALID_ARG;
    if (dst_size < total)
        return MESO_ERR_INVALID_ARG;
    uint8_t* out = (uint8_t*)dst;
    build_header_toc(w, out);
    for (uint32_t i = 0; i < w->count; i++) {
        const meso_chunk_info* c = &w->chunks[i].info;
        size_t n = (size_t)c->stored_size, pad = (size_t)(mesoi_align64(c->stored_size) - c->stored_size);
        memcpy(out + c->offset, w->chunks[i].data, n);
        memset(out + c->offset + n, 0, pad);
    }
    return MESO_OK;
}

/* >>atomic file write ------------------------------------------------------ */

static int write_all(int fd, const void* data, uint64_t size)
{
    const uint8_t* p = (const uint8_t*)data;
    while (size > 0) {
        size_t n = size > ((uint64_t)1 << 30) ? ((size_t)1 << 30) : (size_t)size;
        ssize_t got = write(fd, p, n);
        if (got < 0 && errno == EINTR)
            continue;
        if (got <= 0)
            return got < 0 ? errno : EIO;
        p += got;
        size -= (uint64_t)got;
    }
    return 0;
}

/* The temporary name is ".NAME.tmp.XXXXXX" in the destination's directory,
 * so the rename stays within one file system. open(O_EXCL, 0666) instead of
 * mkstemp so a new file gets the usual umask permissions. */
static int create_temp(char* tmp, size_t cap, size_t dir_len, const char* base, int* fd)
{
    static const char digits[] = "0123456789abcdefghijklmnopqrstuvwxyz";
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    uint64_t seed =
        ((uint64_t)ts.tv_nsec * 0x9E3779B97F4A7C15u) ^ ((uint64_t)getpid() << 32) ^ (uint64_t)(uintptr_t)tmp;
    for (int attempt = 0; attempt < 100; attempt++) {
        char suffix[7];
        for (int k = 0; k < 6; k++) {
            seed = seed * 6364136223846793005u + 1442695040888963407u;
            suffix[k] = digits[(seed >> 33) % 36];
        }
        suffix[6] = 0;
        snprintf(tmp + dir_len, cap - dir_len, ".%s.tmp.%s", base, suffix);
        int d = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (d >= 0) {
            *fd = d;
            return 0;
        }
        if (errno != EEXIST && errno != EINTR)
            return errno;
    }
    return EEXIST;
}

static const char* file_kind(mode_t m)
{
    return S_ISDIR(m)    ? "a directory"
           : S_ISCHR(m)  ? "a character device"
           : S_ISBLK(m)  ? "a block device"
           : S_ISFIFO(m) ? "a FIFO"
           : S_ISSOCK(m) ? "a socket"
           : S_ISLNK(m)  ? "a symbolic link"
                         : "not a regular file";
}

static meso_result refuse(meso_error* err, const char* path, const char* what)
{
    return mesoi_file_error(err, MESO_ERR_IO, MESO_ISSUE_IO_DESTINATION, UINT64_MAX, -1,
                            "refusing to replace '%s': it is %s (outputs replace regular files only)", path, what);
}

static char* copy_string(const meso_allocator* a, const char* s, size_t n)
{
    char* c = (char*)mesoi_file_alloc(a, n + 1);
    if (c) {
        memcpy(c, s, n);
        c[n] = 0;
    }
    return c;
}

/* Where an atomic write of `path` goes: *dest (allocated) is `path`, or the
 * final target of a symbolic link; *mode the permissions of the regular file
 * there (0 when there is none). Refuses everything else without opening it. */
static meso_result resolve_destination(const meso_allocator* a, const char* path, char** dest, uint32_t* mode,
                                       meso_error* err)
{
    *dest = NULL;
    *mode = 0;
    if (path == NULL || path[0] == 0)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1, "NULL or empty path");
    struct stat st;
    char* target = NULL;
    if (lstat(path, &st) == 0) {
        if (S_ISLNK(st.st_mode)) {
            target = realpath(path, NULL);
            if (target == NULL) {
                int e = errno;
                return e == ENOENT   ? refuse(err, path, "a dangling symbolic link")
                       : e == ELOOP  ? refuse(err, path, "a symbolic link loop")
                                     : mesoi_file_error(err, MESO_ERR_IO, MESO_ISSUE_IO_DESTINATION, UINT64_MAX, -1,
                                                        "cannot resolve the symbolic link '%s': %s", path, strerror(e));
            }
            const int gone = stat(target, &st) != 0;
            if (gone || !S_ISREG(st.st_mode)) {
                char what[64];
                snprintf(what, sizeof what, "a symbolic link to %s", gone ? "nothing" : file_kind(st.st_mode));
                meso_result r = refuse(err, path, what);
                free(target);
                return r;
            }
        } else if (!S_ISREG(st.st_mode)) {
            return refuse(err, path, file_kind(st.st_mode));
        }
        *mode = (uint32_t)(st.st_mode & 07777);
    } else if (errno != ENOENT) {
        return mesoi_file_error(err, MESO_ERR_IO, MESO_ISSUE_IO_DESTINATION, UINT64_MAX, -1, "cannot write '%s': %s",
                                path, strerror(errno));
    }
    const char* d = target ? target : path;
    const char* slash = strrchr(d, '/');
    meso_result r = MESO_OK;
    if (slash && slash[1] == 0) {
        r = refuse(err, path, "a directory name (it ends in '/')");
    } else {
        /* The directory must exist (and be one); checked even when the file
         * exists, so the work (and the allocations) never depend on it. */
        char* dir = slash ? copy_string(a, d, slash == d ? 1 : (size_t)(slash - d)) : copy_string(a, ".", 1);
        if (!dir) {
            r = mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, -1, "out of memory");
        } else {
            /* access: the real user may create the temporary file there */
            if (stat(dir, &st) != 0 || (S_ISDIR(st.st_mode) && access(dir, W_OK | X_OK) != 0))
                r = mesoi_file_error(err, MESO_ERR_IO, MESO_ISSUE_IO_DESTINATION, UINT64_MAX, -1,
                                     "cannot write '%s': directory '%s': %s", path, dir, strerror(errno));
            else if (!S_ISDIR(st.st_mode))
                r = mesoi_file_error(err, MESO_ERR_IO, MESO_ISSUE_IO_DESTINATION, UINT64_MAX, -1,
                                     "cannot write '%s': '%s' is not a directory", path, dir);
            mesoi_file_free(a, dir);
        }
    }
    if (r == MESO_OK && (*dest = copy_string(a, d, strlen(d))) == NULL)
        r = mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, -1, "out of memory");
    free(target);
    return r;
}

meso_result meso_output_check(const char* path, meso_error* err)
{
    mesoi_file_error_clear(err);
    meso_allocator a;
    mesoi_file_allocator_init(NULL, &a);
    char* dest = NULL;
    uint32_t mode;
    meso_result r = resolve_destination(&a, path, &dest, &mode, err);
    mesoi_file_free(&a, dest);
    return r;
}

static void output_close(meso_output* out)
{
    if (out->fd >= 0)
        close(out->fd);
    mesoi_file_free(&out->allocator, out->temp);
    mesoi_file_free(&out->allocator, out->path);
    out->fd = -1;
    out->temp = NULL;
    out->path = NULL;
}

meso_result meso_output_open(const char* path, const meso_allocator* allocator, meso_output* out, meso_error* err)
{
    mesoi_file_error_clear(err);
    if (out == NULL)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1, "NULL output");
    memset(out, 0, sizeof *out);
    out->fd = -1;
    if (mesoi_file_allocator_init(allocator, &out->allocator) != MESO_OK)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1, "bad allocator");
    meso_result r = resolve_destination(&out->allocator, path, &out->path, &out->mode, err);
    if (r != MESO_OK)
        return r;
    const char* slash = strrchr(out->path, '/');
    const char* base = slash ? slash + 1 : out->path;
    size_t dir_len = (size_t)(base - out->path), cap = strlen(out->path) + 16;
    if ((out->temp = (char*)mesoi_file_alloc(&out->allocator, cap)) == NULL) {
        output_close(out);
        return mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, -1, "out of memory");
    }
    memcpy(out->temp, out->path, dir_len);
    int e = create_temp(out->temp, cap, dir_len, base, &out->fd);
    if (e == 0 && out->mode != 0 && fchmod(out->fd, (mode_t)out->mode) != 0)
        e = errno;
    if (e != 0) {
        if (out->fd >= 0)
            unlink(out->temp);
        r = mesoi_file_error(err, MESO_ERR_IO, MESO_ISSUE_IO_WRITE, UINT64_MAX, -1,
                             "cannot create a temporary file for '%s' in '%.*s': %s", path, (int)(dir_len ? dir_len : 1),
                             dir_len ? out->path : ".", strerror(e));
        output_close(out);
    }
    return r;
}

static meso_result output_failed(meso_output* out, const char* step, int e, meso_error* err)
{
    unlink(out->temp);
    meso_result r = mesoi_file_error(err, MESO_ERR_IO, MESO_ISSUE_IO_WRITE, UINT64_MAX, -1,
                                     "cannot write '%s' (%s of '%s'): %s", out->path, step, out->temp, strerror(e));
    output_close(out);
    return r;
}

meso_result meso_output_write(meso_output* out, const void* data, size_t size, meso_error* err)
{
    if (out == NULL || out->fd < 0)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1, "output not open");
    int e = write_all(out->fd, data, size);
    return e ? output_failed(out, "write", e, err) : MESO_OK;
}

meso_result meso_output_commit(meso_output* out, meso_error* err)
{
    if (out == NULL || out->fd < 0)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1, "output not open");
    if (fsync(out->fd) != 0)
        return output_failed(out, "fsync", errno, err);
    int fd = out->fd;
    out->fd = -1;
    if (close(fd) != 0)
        return output_failed(out, "close", errno, err);
    /* The destination may have changed since meso_output_open. */
    struct stat st;
    if (lstat(out->path, &st) == 0 && !S_ISREG(st.st_mode)) {
        unlink(out->temp);
        meso_result r = refuse(err, out->path, file_kind(st.st_mode));
        output_close(out);
        return r;
    }
    if (rename(out->temp, out->path) != 0)
        return output_failed(out, "rename", errno, err);
    /* Make the rename durable; best effort (some file systems refuse). */
    char* slash = strrchr(out->path, '/');
    if (slash)
        *slash = 0;
    int dfd = open(slash == out->path ? "/" : slash ? out->path : ".", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dfd >= 0) {
        (void)fsync(dfd);
        close(dfd);
    }
    output_close(out);
    return MESO_OK;
}

void meso_output_abort(meso_output* out)
{
    if (out == NULL || out->temp == NULL)
        return;
    if (out->fd >= 0)
        close(out->fd);
    out->fd = -1;
    unlink(out->temp);
    output_close(out);
}

meso_result meso_writer_write_output(meso_writer* w, meso_output* out, meso_error* err)
{
    if (w == NULL || out == NULL || out->fd < 0)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1,
                                "NULL writer or output not open");
    uint64_t ht = header_toc_size(w);
    if (ht > SIZE_MAX)
        return mesoi_file_error(err, MESO_ERR_UNSUPPORTED, MESO_ISSUE_API_TOO_LARGE, UINT64_MAX, -1, "TOC too large");
    uint8_t* head = (uint8_t*)mesoi_file_alloc(&w->alloc, (size_t)ht);
    if (!head)
        return mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, -1, "out of memory");
    build_header_toc(w, head);
    static const uint8_t zeros[MESO_ALIGN] = {0};
    int e = write_all(out->fd, head, ht);
    for (uint32_t i = 0; i < w->count && e == 0; i++) {
        const meso_chunk_info* c = &w->chunks[i].info;
        e = write_all(out->fd, w->chunks[i].data, c->stored_size);
        if (e == 0)
            e = write_all(out->fd, zeros, mesoi_align64(c->stored_size) - c->stored_size);
    }
    mesoi_file_free(&w->alloc, head);
    return e ? output_failed(out, "write", e, err) : MESO_OK;
}

meso_result meso_writer_write_file(meso_writer* w, const char* path, meso_error* err)
{
    mesoi_file_error_clear(err);
    if (w == NULL || path == NULL || path[0] == 0)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1, "NULL or empty path");
    meso_output out;
    meso_result r = meso_output_open(path, &w->alloc, &out, err);
    if (r == MESO_OK)
        r = meso_writer_write_output(w, &out, err);
    if (r == MESO_OK)
        r = meso_output_commit(&out, err);
    meso_output_abort(&out);
    return r;
}
