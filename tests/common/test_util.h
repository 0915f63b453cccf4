/* test_util.h — what the C tests share: assert that survives NDEBUG, data
 * paths, a seeded RNG (deterministic tests), approximate comparison. */
#ifndef MESO_TEST_UTIL_H
#define MESO_TEST_UTIL_H

#undef NDEBUG /* tests use assert() to verify behaviour */
#include <assert.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#ifndef MESO_TEST_DATA
#error "MESO_TEST_DATA must be defined by the build (tests/data)"
#endif

/* Path of a bundled test file: static buffer, valid until the next call. */
static inline const char* test_data(const char* name)
{
    static char buf[4096];
    snprintf(buf, sizeof(buf), "%s/%s", MESO_TEST_DATA, name);
    return buf;
}

/* A fresh directory for the files a test generates (bakes, renders):
 * /tmp/meso_NAME_XXXXXX into dir; test_temp_dir_remove deletes it and all
 * inside. Aborts when either fails. */
static inline void test_temp_dir(char* dir, size_t size, const char* name)
{
    snprintf(dir, size, "/tmp/meso_%s_XXXXXX", name);
    assert(mkdtemp(dir) != NULL);
}

static inline void test_temp_dir_remove(const char* dir)
{
    char cmd[4200];
    snprintf(cmd, sizeof(cmd), "rm -rf '%s'", dir);
    assert(system(cmd) == 0);
}

/* The whole file at `path` (malloc'd, *n bytes); aborts when unreadable. */
static inline uint8_t* test_read_file(const char* path, size_t* n)
{
    FILE* f = fopen(path, "rb");
    assert(f);
    assert(fseek(f, 0, SEEK_END) == 0);
    const long len = ftell(f);
    assert(len >= 0 && fseek(f, 0, SEEK_SET) == 0);
    *n = (size_t)len;
    uint8_t* b = malloc(*n ? *n : 1);
    assert(b && fread(b, 1, *n, f) == *n);
    fclose(f);
    return b;
}

/* xorshift64*: deterministic pseudo-random numbers for sampling tests. */
static inline uint64_t test_rng_next(uint64_t* s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return *s * 2685821657736338717ULL;
}

/* Uniform double in [lo, hi). */
static inline double test_rng_uniform(uint64_t* s, double lo, double hi)
{
    return lo + (hi - lo) * (double)(test_rng_next(s) >> 11) * (1.0 / 9007199254740992.0);
}

#define TEST_RUN(fn)                              \
    do {                                          \
        fprintf(stderr, "  %s ...\n", #fn);       \
        fn();                                     \
    } while (0)

#endif
