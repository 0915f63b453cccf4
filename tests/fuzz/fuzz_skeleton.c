/*
 * fuzz_skeleton.c — libFuzzer target for the skeleton readers
 * (bake/skeleton_swc.c): built twice, as fuzz_skeleton_swc
 * (-DFUZZ_SKELETON_FORMAT=MESO_SKELETON_SWC) and fuzz_skeleton_text
 * (MESO_SKELETON_TEXT). Pattern: parse -> check what the reader promises ->
 * the drawability check -> the frustum model (what `mesobake frusta` builds
 * next) -> free.
 *
 * How to run (STYLE.md §9):
 *
 *   # replay the corpus with any compiler (meson test --suite fuzz):
 *   ./build/tests/fuzz/fuzz_skeleton_swc tests/fuzz/corpus/skeleton_swc
 *
 *   # real fuzzing with libFuzzer + ASan + UBSan (clang):
 *   CC=clang CXX=clang++ meson setup build-fuzz -Dfuzzing_engine=libfuzzer
 *   meson test -C build-fuzz --suite fuzz-session      # bounded session
 *   cp -r tests/fuzz/corpus/skeleton_swc /tmp/c && \
 *     ./build-fuzz/tests/fuzz/fuzz_skeleton_swc /tmp/c -dict=tests/fuzz/skeleton.dict
 *
 * What it asserts beyond "no crash, no leak, no UB": the reader reads only
 * inside the input (it gets an exactly-sized copy, no terminating NUL); a
 * refusal is MESO_ERR_CORRUPT or MESO_ERR_OUT_OF_MEMORY with an issue code
 * in the skeleton ranges (3140..3149, 3300..3349) and a message, and leaves
 * the output zeroed; an accepted skeleton is a forest (parents in range,
 * roots counted, every node reaches a root, child lists a permutation of
 * the non-roots), with finite coordinates and radii within
 * MESO_SKEL_MAX_COORD and radii >= 0; a drawable one builds a frustum model
 * (or is refused as CORRUPT) whose segments have finite ends and radii.
 */
#undef NDEBUG /* this file uses assert() to check the library's contracts */
#include <assert.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "frustum_model.h"
#include "skeleton_swc.h"

#ifndef FUZZ_SKELETON_FORMAT
#define FUZZ_SKELETON_FORMAT MESO_SKELETON_SWC
#endif

/* The frustum model is O(n log n) but with a large constant; larger
 * accepted skeletons are checked as skeletons only (libFuzzer inputs are
 * small anyway). */
#define FUZZ_MODEL_MAX_NODES 4096u

static int code_in_range(uint32_t code)
{
    return (code >= 3140u && code <= 3149u) || (code >= 3300u && code <= 3349u);
}

static void check_forest(const meso_skeleton* s)
{
    assert(s->node_count >= 1 && s->node_count <= MESO_SKEL_MAX_NODES);
    assert(s->nodes && s->children);
    uint32_t roots = 0;
    uint8_t* seen = calloc(s->node_count, 1);
    assert(seen);
    for (uint32_t i = 0; i < s->node_count; ++i) {
        const meso_skeleton_node* n = &s->nodes[i];
        for (int k = 0; k < 3; ++k)
            assert(isfinite(n->pos[k]) && fabs(n->pos[k]) <= MESO_SKEL_MAX_COORD);
        assert(isfinite(n->radius) && n->radius >= 0 && n->radius <= MESO_SKEL_MAX_COORD);
        assert(n->parent >= -1 && n->parent < (int64_t)s->node_count && n->parent != (int32_t)i);
        roots += n->parent < 0;
        /* Every chain of parents reaches a root within node_count steps. */
        int32_t j = n->parent;
        uint32_t steps = 0;
        while (j >= 0) {
            assert(++steps <= s->node_count);
            j = s->nodes[j].parent;
        }
        /* Child lists: inside the array, and each child names this parent. */
        assert((uint64_t)n->first_child + n->child_count <= s->node_count - s->root_count);
        for (uint32_t c = 0; c < n->child_count; ++c) {
            const uint32_t ch = s->children[n->first_child + c];
            assert(ch < s->node_count && s->nodes[ch].parent == (int32_t)i && !seen[ch]);
            seen[ch] = 1;
        }
    }
    assert(roots == s->root_count && roots >= 1);
    for (uint32_t i = 0; i < s->node_count; ++i)
        assert(seen[i] == (s->nodes[i].parent >= 0));
    free(seen);
}

static void check_model(const meso_skeleton* s)
{
    meso_frustum_model m;
    meso_error err = {0};
    const meso_result r = meso_frustum_model_build(s, NULL, &m, &err);
    if (r != MESO_OK) {
        assert(r == MESO_ERR_CORRUPT || r == MESO_ERR_OUT_OF_MEMORY);
        return;
    }
    assert(m.segment_count >= 1);
    for (uint32_t i = 0; i < m.segment_count; ++i) {
        const meso_frustum_segment* g = &m.segments[i];
        for (int k = 0; k < 3; ++k)
            assert(isfinite(g->c0[k]) && isfinite(g->c1[k]));
        assert(isfinite(g->r0) && isfinite(g->r1) && g->r0 >= 0 && g->r1 >= 0);
    }
    meso_frustum_model_free(&m);
}

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    /* An exactly-sized copy: ASan sees any read past the end. */
    char* text = malloc(size ? size : 1);
    if (!text)
        return 0;
    if (size)
        memcpy(text, data, size);
    meso_skeleton s;
    meso_error err = {0};
    const meso_result r = meso_skeleton_parse(text, size, FUZZ_SKELETON_FORMAT, &s, &err);
    free(text);
    if (r != MESO_OK) {
        assert(r == MESO_ERR_CORRUPT || r == MESO_ERR_OUT_OF_MEMORY);
        assert(r == MESO_ERR_OUT_OF_MEMORY || (code_in_range(err.code) && err.message[0]));
        assert(s.node_count == 0 && s.nodes == NULL && s.children == NULL);
        return 0;
    }
    check_forest(&s);
    const meso_result d = meso_skeleton_require_drawable(&s, &err);
    assert(d == MESO_OK || (d == MESO_ERR_CORRUPT && code_in_range(err.code) && err.message[0]));
    if (d == MESO_OK && s.node_count <= FUZZ_MODEL_MAX_NODES)
        check_model(&s);
    meso_skeleton_free(&s);
    return 0;
}
