/*
 * fuzz_manifest.c — libFuzzer target for `mesobake batch` manifests
 * (tools/mesobake/batch_manifest.c, batch_manifest_load). The input is the
 * manifest's bytes, written to a scratch file the loader reads.
 *
 *   # replay (any compiler, meson test --suite fuzz):
 *   ./build/tests/fuzz/fuzz_manifest tests/fuzz/corpus/manifest
 *   # fuzz (clang, -Dfuzzing_engine=libfuzzer; meson test --suite fuzz-session):
 *   cp -r tests/fuzz/corpus/manifest /tmp/c && ./build-fuzz/tests/fuzz/fuzz_manifest /tmp/c
 *
 * What it asserts beyond "no crash, no leak": a manifest is either loaded,
 * with at least one job, each with one of the four commands, a non-empty
 * input and output, an absolute output path and no argument the batch owns,
 * and no two jobs writing the same place — or refused with a message and
 * one of the manifest codes E3450..E3456 and nothing left allocated.
 */
#undef NDEBUG /* this file uses assert() to check the loader's contract */
#include <assert.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "batch.h"

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

static char path[64];

static int is_command(const char* c)
{
    return !strcmp(c, "mesh") || !strcmp(c, "shell") || !strcmp(c, "cells") || !strcmp(c, "frusta");
}

static int is_owned(const char* a)
{
    static const char* const owned[] = {"-i", "--input", "-o", "--output", "--report", "-j", "--threads"};
    for (size_t k = 0; k < sizeof owned / sizeof owned[0]; ++k)
        if (!strcmp(a, owned[k]))
            return 1;
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    if (!path[0]) {
        char dir[] = "/tmp/meso-fuzz-manifest.XXXXXX";
        if (!mkdtemp(dir))
            abort();
        snprintf(path, sizeof path, "%s/manifest.json", dir);
    }
    FILE* f = fopen(path, "wb");
    if (!f || fwrite(data, 1, size, f) != size || fclose(f) != 0)
        abort();
    batch_manifest m;
    meso_error err = {0};
    const meso_result r = batch_manifest_load(path, &m, &err);
    if (r != MESO_OK) {
        assert(err.code >= BATCH_ISSUE_UNREADABLE && err.code <= BATCH_ISSUE_NO_JOBS);
        assert(err.message[0] && strstr(err.message, path) == err.message);
        assert(m.jobs == NULL && m.count == 0);
        return 0;
    }
    assert(m.count >= 1 && m.dir && m.dir[0] == '/');
    for (size_t i = 0; i < m.count; ++i) {
        const batch_job* j = &m.jobs[i];
        assert(is_command(j->command) && j->input[0] && j->output[0] && j->name[0]);
        assert(j->output_path[0] == '/');
        for (size_t a = 0; a < j->arg_count; ++a)
            assert(!is_owned(j->args[a]));
        for (size_t k = 0; k < i; ++k)
            assert(strcmp(m.jobs[k].output_path, j->output_path) != 0);
    }
    batch_manifest_free(&m);
    return 0;
}
