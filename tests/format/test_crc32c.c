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

int main(void)
{
    known_answers_match_rfc3720();
    empty_input_returns_seed();
    chaining_equals_one_pass();
    hardware_matches_software_on_all_lengths_and_alignments();
    printf("test_crc32c: ok\n");
    return 0;
}
