/*
 * golden_spec.h — the content of the format 1.0 golden files, shared by the
 * generator (make_golden.c) and the reader test (test_format_golden.c).
 * Typed chunks hold byte i = (i * 31 + seed * 17) mod 256, so the test derives
 * every expected byte itself. NEVER change these values: the checked-in
 * files in golden/v1_0/ were written from them and must be read forever.
 */
#ifndef MESO_GOLDEN_SPEC_H
#define MESO_GOLDEN_SPEC_H

#include "meso_file.h"

typedef struct golden_typed {
    uint32_t type, object;
    uint16_t lod, dtype, components;
    uint32_t dims[3];
    uint32_t seed;
} golden_typed;

static const golden_typed golden_typed_chunks[] = {
    {MESO_CHUNK_SDIR, 1, 0, MESO_DTYPE_F32, 3, {4, 1, 1}, 1},
    {MESO_CHUNK_STHK, 1, 0, MESO_DTYPE_F32, 1, {4, 1, 1}, 2},
    {MESO_CHUNK_TX2D, 1, 0, MESO_DTYPE_U8, 4, {8, 8, 1}, 3},
    {MESO_CHUNK_TX2D, 1, 1, MESO_DTYPE_U8, 4, {4, 4, 1}, 4},
    {MESO_CHUNK_TX2D, 1, 2, MESO_DTYPE_U8, 4, {2, 2, 1}, 5},
    {MESO_CHUNK_TX3D, 1, 0, MESO_DTYPE_F16, 1, {4, 4, 4}, 6},
    {MESO_CHUNK_DIST, 1, 0, MESO_DTYPE_F32, 1, {4, 4, 4}, 7},
    {MESO_CHUNK_TILE, 1, 0, MESO_DTYPE_U16, 1, {4, 4, 4}, 8},
    {MESO_CHUNK_SPLT, 1, 0, MESO_DTYPE_U32, 6, {5, 1, 1}, 9},
    {MESO_CHUNK_MEMB, 1, 0, MESO_DTYPE_U32, 1, {3, 2, 1}, 10},
    {MESO_CHUNK_NRMM, 1, 1, MESO_DTYPE_U16, 2, {4, 4, 4}, 11},
    {MESO_CHUNK_COLR, 1, 1, MESO_DTYPE_U8, 4, {4, 4, 4}, 12},
    {MESO_CHUNK_RELF, 1, 0, MESO_DTYPE_F16, 4, {8, 8, 1}, 13},
};
#define GOLDEN_TYPED_COUNT (sizeof golden_typed_chunks / sizeof golden_typed_chunks[0])

#define GOLDEN_META "{\"generator\":\"make_golden\",\"format\":\"1.0\"}"
#define GOLDEN_RPRT "{\"hausdorff\":0.0,\"warnings\":[]}"

/* Unit tetrahedron, positions only. */
static const float golden_tetra_positions[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
static const uint32_t golden_tetra_indices[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};

/* Thickness values of tetra.meso's STHK chunk. */
static const float golden_tetra_thickness[4] = {0.25f, 0.5f, 0.75f, 1.0f};

#endif
