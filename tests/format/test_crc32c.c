/* test_crc32c.c — CRC32C known answers and hardware == software. */
#undef NDEBUG
#include "file_internal.h"
#include "meso_file.h"

#include <assert.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void known_answers_match_rfc3720(void)
{
    uint8_t buf[32];
    assert(meso_crc32c(0, "123456789", 9) == 0xE3069283u);
    memset(buf, 0, 32);
    assert(meso_crc32c(0, buf, 32) == 0x8A9136AAu);
    memset(buf, 0xFF, 32);
    assert(meso_crc32c(0, buf, 32) == 0x62A8AB43u);
    for (int i = 0; i < 32; i++)
        buf[i] = (uint8_t)i;
    assert(meso_crc32c(0, buf, 32) == 0x46DD794Eu);
    for (int i = 0; i < 32; i++)
        buf[i] = (uint8_t)(31 - i);
    assert(meso_crc32c(0, buf, 32) == 0x113FDB5Cu);
    assert(mesoi_crc32c_sw(0, "123456789", 9) == 0xE3069283u);
    assert(mesoi_crc32c_hw(0, "123456789", 9) == 0xE3069283u);
}

static void empty_input_returns_seed(void)
{
    assert(meso_crc32c(0, NULL, 0) == 0);
    assert(meso_crc32c(0x12345678u, "x", 0) == 0x12345678u);
}

static void chaining_equals_one_pass(void)
{
    const char* s = "123456789";
    for (size_t k = 0; k <= 9; k++)
        assert(meso_crc32c(meso_crc32c(0, s, k), s + k, 9 - k) == 0xE3069283u);
}

static void hardware_matches_software_on_all_lengths_and_alignments(void)
{
    enum { N = 4096 + 64 };
    uint8_t* buf = (uint8_t*)malloc(N);
    assert(buf);
    uint32_t x = 1;
    for (size_t i = 0; i < N; i++) {
        x = x * 1103515245u + 12345u;
        buf[i] = (uint8_t)(x >> 16);
    }
    for (size_t align = 0; align < 16; align++) {
        for (size_t len = 0; len < 300; len++) {
            uint32_t seed = (uint32_t)(len * 2654435761u);
            assert(mesoi_crc32c_hw(seed, buf + align, len) == mesoi_crc32c_sw(seed, buf + align, len));
        }
        for (size_t len = 300; len + align <= N; len += 97)
            assert(mesoi_crc32c_hw(0, buf + align, len) == mesoi_crc32c_sw(0, buf + align, len));
    }
    free(buf);
    printf("crc32c: hardware path %s\n", mesoi_crc32c_hw_available() ? "available (SSE4.2)" : "not available");
}

/* The hardware path runs three interleaved streams over 3 x 8 KiB and
 * 3 x 256 B blocks and combines them (crc32c.c): check every length around
 * each threshold and its multiples, at every alignment, with non-zero seeds,
 * and that splitting a buffer anywhere gives the one-pass result. */
static void hardware_matches_software_around_the_block_thresholds(void)
{
    enum { N = 4 * 3 * 8192 + 3 * 256 + 64 };
    uint8_t* buf = (uint8_t*)malloc(N);
    assert(buf);
    uint32_t x = 7;
    for (size_t i = 0; i < N; i++) {
        x = x * 1664525u + 1013904223u;
        buf[i] = (uint8_t)(x >> 24);
    }
    const size_t centres[] = {3 * 256, 2 * 3 * 256, 3 * 8192, 3 * 8192 + 3 * 256, 2 * 3 * 8192,
                              3 * 3 * 8192, 4 * 3 * 8192, 4 * 3 * 8192 + 3 * 256};
    size_t checked = 0;
    for (size_t k = 0; k < sizeof centres / sizeof centres[0]; k++) {
        for (size_t align = 0; align < 9; align++) {
            for (size_t len = centres[k] - 17; len <= centres[k] + 17; len++) {
                if (align + len > N)
                    continue;
                uint32_t seed = (uint32_t)(len * 2654435761u) ^ (uint32_t)align;
                assert(mesoi_crc32c_hw(seed, buf + align, len) == mesoi_crc32c_sw(seed, buf + align, len));
                checked++;
            }
        }
    }
    assert(checked > 2000);
    const uint32_t whole = mesoi_crc32c_sw(0, buf, N);
    assert(mesoi_crc32c_hw(0, buf, N) == whole);
    for (size_t cut = 0; cut <= N; cut += 1237)
        assert(meso_crc32c(meso_crc32c(0, buf, cut), buf + cut, N - cut) == whole);
    /* All-zero and all-ones runs (the combination must not depend on data). */
    memset(buf, 0, N);
    assert(mesoi_crc32c_hw(0, buf, N) == mesoi_crc32c_sw(0, buf, N));
    assert(mesoi_crc32c_hw(0xFFFFFFFFu, buf, N) == mesoi_crc32c_sw(0xFFFFFFFFu, buf, N));
    memset(buf, 0xFF, N);
    assert(mesoi_crc32c_hw(0, buf, N) == mesoi_crc32c_sw(0, buf, N));
    free(buf);
}

int main(void)
{
    known_answers_match_rfc3720();
    empty_input_returns_seed();
    chaining_equals_one_pass();
    hardware_matches_software_on_all_lengths_and_alignments();
    hardware_matches_software_around_the_block_thresholds();
    printf("test_crc32c: ok\n");
    return 0;
}
