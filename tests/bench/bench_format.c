/*
 * bench_format.c — read throughput of the .meso container vs plain read().
 *
 *   bench_format [DIR [CSV [CHUNKS]]]
 *
 * Writes a DIR/bench_format.meso of CHUNKS (default 16) x 64 MiB chunks
 * (TX3D u8 and DIST u16, deterministic pseudo-random bytes: ~1.07 GB),
 * reads it once to warm the page cache (it is cached anyway, just written),
 * then times, RUNS (7) runs each, and reports the median of each (GB = 1e9
 * bytes; every run's time is in the CSV):
 *
 *   read()            plain read() of the whole file into one buffer
 *   path+read         open_path + read_chunk of every chunk: the recommended
 *                     verified load (meso_file.h, FORMAT.md §8): every byte
 *                     is read once and its CRC (and type rules) checked
 *   path+full+read    open_path + validate FULL + read_chunk of every chunk
 *                     (every payload read and checksummed twice)
 *   path+full         open_path + validate FULL only
 *   mmap+full+view    open_mmap + validate FULL + chunk_view of every chunk
 *   mmap+read         open_mmap + read_chunk of every chunk
 *   crc32c (memory)   meso_crc32c over an in-memory buffer of the same size
 *                     (DRAM bound)
 *   crc32c (1 MiB)    meso_crc32c over one 1 MiB buffer, repeated to the same
 *                     total (L2 resident: the CPU's CRC speed, which is what
 *                     the block-wise readers see)
 *   memcpy            one memcpy of the same size (memory bandwidth)
 *
 * The table goes to stdout and CSV (default tests/bench/results/
 * format_throughput.csv when run by run_benchmarks.sh). The file is deleted
 * at the end. Goal (issue): a validated read >= 4 GB/s and >= half of
 * read(); the line after the table reports the recommended path+read and
 * path+full+read against it.
 */
#include "meso_clock.h"
#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "meso_file.h"

#define CHUNK_BYTES ((size_t)64 << 20)
#define RUNS 7


static void die(const char* what, const meso_error* err)
{
    fprintf(stderr, "bench_format: %s%s%s\n", what, err ? ": " : "", err ? err->message : "");
    exit(1);
}

static void fill(uint8_t* p, size_t n, uint64_t seed)
{
    uint64_t s = seed * 0x9E3779B97F4A7C15ull + 1;
    for (size_t i = 0; i + 8 <= n; i += 8) {
        s ^= s >> 12;
        s ^= s << 25;
        s ^= s >> 27;
        uint64_t v = s * 2685821657736338717ull;
        memcpy(p + i, &v, 8);
    }
}

typedef struct method {
    const char* name;
    double t[RUNS];
} method;

static int cmp_double(const void* a, const void* b)
{
    double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

static double median(const method* m)
{
    double s[RUNS];
    memcpy(s, m->t, sizeof s);
    qsort(s, RUNS, sizeof s[0], cmp_double);
    return s[RUNS / 2];
}

/* >>the measured operations ----------------------------------------------- */

static volatile uint32_t sink;

static void plain_read(const char* path, uint8_t* buf, size_t size)
{
    int fd = open(path, O_RDONLY);
    if (fd < 0)
        die("open failed", NULL);
    size_t got = 0;
    while (got < size) {
        size_t want = size - got > ((size_t)1 << 30) ? ((size_t)1 << 30) : size - got;
        ssize_t n = read(fd, buf + got, want);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0)
            die("read failed", NULL);
        got += (size_t)n;
    }
    close(fd);
}

/* which: 3 = validate + read_chunk, 1 = validate only, 2 = read_chunk only;
 * use_mmap: open_mmap instead of open_path. */
static void meso_path(const char* path, uint8_t* buf, size_t size, int which, int use_mmap)
{
    meso_file* f;
    meso_error err;
    if ((use_mmap ? meso_file_open_mmap : meso_file_open_path)(path, NULL, &f, &err) != MESO_OK)
        die("open", &err);
    if ((which & 1) && meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) != MESO_OK)
        die("validate FULL failed", NULL);
    if (which & 2) {
        size_t off = 0;
        for (uint32_t i = 0; i < meso_file_chunk_count(f); i++) {
            const meso_chunk_info* c = meso_file_chunk(f, i);
            if (off + c->decoded_size > size)
                die("buffer too small", NULL);
            if (meso_file_read_chunk(f, i, buf + off, (size_t)c->decoded_size, &err) != MESO_OK)
                die("read_chunk", &err);
            off += (size_t)c->decoded_size;
        }
    }
    meso_file_close(f);
}

static void meso_mmap(const char* path)
{
    meso_file* f;
    meso_error err;
    if (meso_file_open_mmap(path, NULL, &f, &err) != MESO_OK)
        die("open_mmap", &err);
    if (meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) != MESO_OK)
        die("validate FULL failed", NULL);
    uint32_t acc = 0;
    for (uint32_t i = 0; i < meso_file_chunk_count(f); i++) {
        const void* p;
        if (meso_file_chunk_view(f, i, &p, &err) != MESO_OK)
            die("chunk_view", &err);
        acc += *(const uint8_t*)p;
    }
    sink = acc;
    meso_file_close(f);
}

int main(int argc, char** argv)
{
    const char* dir = argc > 1 ? argv[1] : ".";
    const char* csv = argc > 2 ? argv[2] : "format_throughput.csv";
    const uint32_t nchunks = argc > 3 ? (uint32_t)strtoul(argv[3], NULL, 10) : 16u;
    if (nchunks == 0 || nchunks > 64)
        die("CHUNKS must be 1..64", NULL);
    char path[4096];
    snprintf(path, sizeof path, "%s/bench_format.meso", dir);

    /* >>write */
    uint8_t* chunk = malloc(CHUNK_BYTES);
    if (!chunk)
        die("out of memory", NULL);
    meso_writer* w;
    meso_error err;
    if (meso_writer_create(NULL, &w) != MESO_OK)
        die("writer_create", NULL);
    for (uint32_t i = 0; i < nchunks; i++) {
        fill(chunk, CHUNK_BYTES, i + 1);
        meso_chunk_desc d;
        memset(&d, 0, sizeof d);
        d.object = 1;
        if (i % 2 == 0) { /* 512 x 512 x 256 u8 */
            d.type = MESO_CHUNK_TX3D;
            d.dtype = MESO_DTYPE_U8;
            d.dims[0] = 512, d.dims[1] = 512, d.dims[2] = 256;
        } else { /* 512 x 256 x 256 u16 */
            d.type = MESO_CHUNK_DIST;
            d.dtype = MESO_DTYPE_U16;
            d.dims[0] = 512, d.dims[1] = 256, d.dims[2] = 256;
        }
        d.components = 1;
        if (meso_writer_add(w, &d, chunk, CHUNK_BYTES, &err) != MESO_OK)
            die("writer_add", &err);
    }
    free(chunk);
    double t0 = meso_seconds();
    if (meso_writer_write_file(w, path, &err) != MESO_OK)
        die("write_file", &err);
    meso_writer_destroy(w);
    struct stat st;
    if (stat(path, &st) != 0)
        die("stat failed", NULL);
    const size_t size = (size_t)st.st_size;
    printf("wrote %s: %u chunks, %zu bytes (%.2f GB) in %.2f s (incl. fsync)\n", path, nchunks, size, 1e-9 * (double)size,
           meso_seconds() - t0);

    /* Buffers allocated and touched once, outside the timings. */
    uint8_t* buf = malloc(size);
    uint8_t* buf2 = malloc(size);
    if (!buf || !buf2)
        die("out of memory", NULL);
    memset(buf, 1, size);
    memset(buf2, 2, size);
    plain_read(path, buf, size); /* warm the page cache */

    enum {
        M_READ,
        M_PATH_READ,
        M_PATH_FULL_READ,
        M_PATH_FULL,
        M_MMAP_FULL_VIEW,
        M_MMAP_READ,
        M_CRC,
        M_CRC_CACHED,
        M_MEMCPY,
        M_COUNT
    };
    method m[M_COUNT] = {{"read()", {0}},          {"path+read", {0}},      {"path+full+read", {0}},
                         {"path+full", {0}},       {"mmap+full+view", {0}}, {"mmap+read", {0}},
                         {"crc32c (memory)", {0}}, {"crc32c (1 MiB)", {0}}, {"memcpy (memory)", {0}}};
    const size_t block = (size_t)1 << 20;
    for (int r = 0; r < RUNS; r++) {
        double s;
        s = meso_seconds();
        plain_read(path, buf, size);
        m[M_READ].t[r] = meso_seconds() - s;
        s = meso_seconds();
        meso_path(path, buf, size, 2, 0);
        m[M_PATH_READ].t[r] = meso_seconds() - s;
        s = meso_seconds();
        meso_path(path, buf, size, 3, 0);
        m[M_PATH_FULL_READ].t[r] = meso_seconds() - s;
        s = meso_seconds();
        meso_path(path, buf, size, 1, 0);
        m[M_PATH_FULL].t[r] = meso_seconds() - s;
        s = meso_seconds();
        meso_mmap(path);
        m[M_MMAP_FULL_VIEW].t[r] = meso_seconds() - s;
        s = meso_seconds();
        meso_path(path, buf, size, 2, 1);
        m[M_MMAP_READ].t[r] = meso_seconds() - s;
        s = meso_seconds();
        sink = meso_crc32c(0, buf, size);
        m[M_CRC].t[r] = meso_seconds() - s;
        s = meso_seconds();
        {
            uint32_t c = 0;
            for (size_t done = 0; done < size; done += block)
                c = meso_crc32c(c, buf, size - done < block ? size - done : block);
            sink = c;
        }
        m[M_CRC_CACHED].t[r] = meso_seconds() - s;
        s = meso_seconds();
        memcpy(buf2, buf, size);
        m[M_MEMCPY].t[r] = meso_seconds() - s;
        sink = buf2[size / 2];
    }
    if (unlink(path) != 0)
        fprintf(stderr, "bench_format: could not delete %s\n", path);
    free(buf);
    free(buf2);

    FILE* out = fopen(csv, "w");
    if (!out)
        die("cannot write the CSV", NULL);
    fprintf(out, "method,bytes");
    for (int r = 0; r < RUNS; r++)
        fprintf(out, ",run%d_s", r + 1);
    fprintf(out, ",median_GBps,median_vs_read\n");
    const double read_median = (double)size / median(&m[M_READ]) * 1e-9;
    printf("\n%-18s %12s %10s   (median of %d runs)\n", "method", "median GB/s", "vs read()", RUNS);
    for (int i = 0; i < M_COUNT; i++) {
        const double md = (double)size / median(&m[i]) * 1e-9;
        printf("%-18s %12.2f %9.2fx\n", m[i].name, md, md / read_median);
        fprintf(out, "%s,%zu", m[i].name, size);
        for (int r = 0; r < RUNS; r++)
            fprintf(out, ",%.4f", m[i].t[r]);
        fprintf(out, ",%.3f,%.3f\n", md, md / read_median);
    }
    fclose(out);
    const double verified = (double)size / median(&m[M_PATH_READ]) * 1e-9;
    const double twice = (double)size / median(&m[M_PATH_FULL_READ]) * 1e-9;
    printf("\nverified load (open + read_chunk of every chunk): %.2f GB/s = %.0f%% of read() "
           "(goal: >= 4 GB/s and >= 50%%)\n",
           verified, 100.0 * verified / read_median);
    printf("validate FULL, then read_chunk of every chunk: %.2f GB/s = %.0f%% of read() (reads everything twice)\n",
           twice, 100.0 * twice / read_median);
    return 0;
}
