/*
 * sample.h — shared fixtures for the format tests: a deterministic set of
 * chunks of every kind, serialisation helpers and a "patch a field and fix
 * the checksums" helper for corruption tests.
 */
#ifndef MESO_TEST_SAMPLE_H
#define MESO_TEST_SAMPLE_H

#include "meso_file.h"

#include <stddef.h>
#include <stdint.h>

typedef struct sample_chunk {
    meso_chunk_desc desc;
    const uint8_t* data;
    size_t size;
} sample_chunk;

/* Every chunk kind (META, RPRT, OBJT, MESH, SDIR, STHK, TX2D x3 mips, TX3D,
 * DIST, TILE, SPLT, MEMB, NRMM, COLR, SKEL, FRUS, RELF), in insertion order.
 * The data stays valid for the whole program. */
size_t sample_chunks(const sample_chunk** out);
/* Add them all to w (asserts success). */
void sample_add_all(meso_writer* w);
/* Serialise the full sample (or a small META+OBJT+MESH+STHK one) into a
 * malloc'd buffer. */
uint8_t* sample_file(size_t* size);
uint8_t* sample_small_file(size_t* size);
/* A MESH chunk (decoded layout): a fan of `tris` triangles around the
 * origin in z = 0, with normals; malloc'd. */
uint8_t* sample_fan_mesh(uint32_t tris, size_t* size);
/* Serialise a writer into a malloc'd buffer. */
uint8_t* writer_to_memory(meso_writer* w, size_t* size);

/* Little-endian field access for patching. */
uint32_t get32(const uint8_t* p);
uint64_t get64(const uint8_t* p);
void put16(uint8_t* p, uint16_t v);
void put32(uint8_t* p, uint32_t v);
void put64(uint8_t* p, uint64_t v);
/* Recompute the payload CRC of TOC entry `index` (64-byte entries). */
void fix_payload_crc(uint8_t* file, uint32_t index);
/* Recompute the TOC CRC and then the header CRC. */
void fix_crcs(uint8_t* file);

/* Open over memory and, when that succeeds, validate FULL. Returns the first
 * failure (OK if none); *err gets its details. */
meso_result open_and_validate(const uint8_t* data, size_t size, meso_error* err);
/* Same over a copy of exactly `size` bytes in a fresh malloc block. */
meso_result open_and_validate_copy(const uint8_t* data, size_t size, meso_error* err);

/* Deterministic bytes. */
void fill_pattern(uint8_t* dst, size_t n, uint32_t seed);

#endif
