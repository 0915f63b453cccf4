/*
 * fuzz_raw_volume.c — libFuzzer target for raw density volumes as
 * `--texture volume:FILE.raw:WxHxD` reads them (bake/texture_function.c,
 * meso_texfn_from_spec_max). The input is "DIMS\n" followed by the file's
 * bytes: DIMS (up to 63 bytes, any text but ':' and ".vdb") becomes the spec's WxHxD,
 * the rest is written to a scratch file that the spec names. Budget 256 MiB.
 *
 *   # replay (any compiler, meson test --suite fuzz):
 *   ./build/tests/fuzz/fuzz_raw_volume tests/fuzz/corpus/raw_volume
 *   # fuzz (clang, -Dfuzzing_engine=libfuzzer; meson test --suite fuzz-session):
 *   cp -r tests/fuzz/corpus/raw_volume /tmp/c && ./build-fuzz/tests/fuzz/fuzz_raw_volume /tmp/c
 *
 * What it asserts beyond "no crash, no leak": a volume is accepted exactly
 * when DIMS parses as three sides in 1..4096 and the file holds W*H*D
 * bytes (checked independently here), with every value the file's byte /
 * 255; a file of the wrong length is MESO_ERR_CORRUPT (exit 3), never an
 * allocation of the declared size.
 */
#undef NDEBUG /* this file uses assert() to check the reader's contract */
#include <assert.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "texture_function.h"

#define BUDGET ((uint64_t)256 << 20) /* the estimate counts 96 MiB for the program */

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

static char scratch[64];

/* The sides of "WxHxD" (each 1..4096, digits only), as the spec documents
 * them; 0 when it does not parse. */
static int expected_dims(const char* s, uint64_t d[3])
{
    for (int i = 0; i < 3; ++i) {
        if (*s < '0' || *s > '9')
            return 0;
        uint64_t v = 0;
        while (*s >= '0' && *s <= '9' && v <= 4096)
            v = 10 * v + (uint64_t)(*s++ - '0');
        if (v < 1 || v > 4096 || (i < 2 && *s++ != 'x'))
            return 0;
        d[i] = v;
    }
    return *s == 0;
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    const uint8_t* nl = memchr(data, '\n', size < 64 ? size : 64);
    if (!nl)
        return 0;
    const size_t dl = (size_t)(nl - data);
    char dims[64];
    memcpy(dims, data, dl);
    dims[dl] = 0;
    /* The path stays the scratch file: no ':' (it would move the split), no
     * ".vdb" (the spec would name an OpenVDB file: not this target's). */
    if (strlen(dims) != dl || strchr(dims, ':') || strstr(dims, ".vdb"))
        return 0;
    if (!scratch[0])
        snprintf(scratch, sizeof scratch, "/tmp/meso_fuzz_raw_%ld.raw", (long)getpid());
    const uint8_t* body = nl + 1;
    const size_t n = size - dl - 1;
    FILE* fp = fopen(scratch, "wb");
    assert(fp && fwrite(body, 1, n, fp) == n && fclose(fp) == 0);
    char spec[160];
    snprintf(spec, sizeof spec, "volume:%s:%s", scratch, dims);
    meso_texfn f;
    meso_error err;
    memset(&err, 0, sizeof err);
    const meso_result r = meso_texfn_from_spec_max(spec, BUDGET, &f, &err);
    uint64_t d[3];
    const int parses = expected_dims(dims, d);
    if (r == MESO_OK) {
        assert(parses && d[0] * d[1] * d[2] == n);
        assert(f.kind == MESO_TEXFN_DENSITY && f.dims[0] == d[0] && f.dims[1] == d[1] && f.dims[2] == d[2]);
        for (size_t i = 0; i < n; ++i)
            assert(f.values[i] == (float)(body[i] / 255.0));
        meso_texfn_free(&f);
    } else {
        assert(f.values == NULL && f.encoded == NULL && err.message[0]);
        if (!parses)
            assert(r == MESO_ERR_INVALID_ARG);
        else if (d[0] * d[1] * d[2] != n)
            assert(r == MESO_ERR_CORRUPT);
    }
    unlink(scratch);
    return 0;
}
