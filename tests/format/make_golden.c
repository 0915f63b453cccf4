/*
 * make_golden.c — writes the format 1.0 golden files into DIR:
 *   empty.meso       no chunks
 *   tetra.meso       META, OBJT, MESH (unit tetrahedron), STHK
 *   all_chunks.meso  every chunk type of format 1.0
 * Built but never run by the test suite. The files in golden/v1_0/ are
 * checked in and must be read by every future reader: do not regenerate them
 * (a new format version gets a new directory, e.g. golden/v1_1/).
 * Usage: make_golden DIR
 */
#include "golden_spec.h"
#include "meso_file.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void put32(uint8_t* p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (uint8_t)(v >> (8 * i));
}
static void putf(uint8_t* p, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put32(p, u);
}

static int add(meso_writer* w, uint32_t type, uint32_t flags, uint32_t object, const void* data, size_t size)
{
    meso_chunk_desc d;
    memset(&d, 0, sizeof d);
    d.type = type;
    d.flags = flags;
    d.object = object;
    meso_error e;
    if (meso_writer_add(w, &d, data, size, &e) != MESO_OK) {
        fprintf(stderr, "make_golden: %s\n", e.message);
        return 1;
    }
    return 0;
}

static int add_common(meso_writer* w)
{
    int bad = add(w, MESO_CHUNK_META, 0, 0, GOLDEN_META, strlen(GOLDEN_META));
    uint8_t objt[64];
    meso_object_record rec = {1, MESO_OBJECT_MESH, {0, 0, 0}, {1, 1, 1}, "tetra"};
    meso_object_record_encode(&rec, objt);
    bad |= add(w, MESO_CHUNK_OBJT, MESO_CHUNK_FLAG_REQUIRED, 0, objt, sizeof objt);
    meso_mesh_layout l;
    if (meso_mesh_compute_layout(4, 12, MESO_MESH_ATTR_POSITIONS, &l) != MESO_OK)
        return 1;
    uint8_t* mesh = (uint8_t*)calloc(1, (size_t)l.size);
    meso_mesh_write_header(&l, mesh);
    for (int i = 0; i < 12; i++) {
        putf(mesh + l.positions_offset + 4 * i, golden_tetra_positions[i]);
        put32(mesh + l.indices_offset + 4 * i, golden_tetra_indices[i]);
    }
    bad |= add(w, MESO_CHUNK_MESH, MESO_CHUNK_FLAG_REQUIRED, 1, mesh, (size_t)l.size);
    free(mesh);
    return bad;
}

static int write(meso_writer* w, const char* dir, const char* name)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    meso_error e;
    if (meso_writer_write_file(w, path, &e) != MESO_OK) {
        fprintf(stderr, "make_golden: %s\n", e.message);
        return 1;
    }
    meso_writer_destroy(w);
    printf("wrote %s\n", path);
    return 0;
}

int main(int argc, char** argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: make_golden DIR\n");
        return 1;
    }
    meso_writer* w = NULL;
    if (meso_writer_create(NULL, &w) != MESO_OK || write(w, argv[1], "empty.meso"))
        return 2;

    if (meso_writer_create(NULL, &w) != MESO_OK || add_common(w))
        return 2;
    uint8_t sthk[16];
    for (int i = 0; i < 4; i++)
        putf(sthk + 4 * i, golden_tetra_thickness[i]);
    meso_chunk_desc d;
    memset(&d, 0, sizeof d);
    d.type = MESO_CHUNK_STHK;
    d.object = 1;
    d.dtype = MESO_DTYPE_F32;
    d.dims[0] = 4;
    if (meso_writer_add(w, &d, sthk, sizeof sthk, NULL) != MESO_OK || write(w, argv[1], "tetra.meso"))
        return 2;

    if (meso_writer_create(NULL, &w) != MESO_OK || add_common(w))
        return 2;
    if (add(w, MESO_CHUNK_RPRT, 0, 0, GOLDEN_RPRT, strlen(GOLDEN_RPRT)))
        return 2;
    uint8_t skel[64] = {0}; /* root at the origin, child at (0,0,1) */
    putf(skel + 12, 0.5f);
    put32(skel + 16, 0xFFFFFFFFu);
    putf(skel + 32 + 8, 1.0f);
    putf(skel + 32 + 12, 0.25f);
    put32(skel + 32 + 20, 2);
    if (add(w, MESO_CHUNK_SKEL, 0, 1, skel, sizeof skel))
        return 2;
    uint8_t frus[64] = {0};
    putf(frus + 12, 0.5f);
    putf(frus + 16 + 8, 1.0f);
    putf(frus + 28, 0.25f);
    putf(frus + 32 + 8, -1.0f);
    putf(frus + 44 + 8, 1.0f);
    if (add(w, MESO_CHUNK_FRUS, 0, 1, frus, sizeof frus))
        return 2;
    for (size_t k = 0; k < GOLDEN_TYPED_COUNT; k++) {
        const golden_typed* g = &golden_typed_chunks[k];
        size_t n = (size_t)meso_dtype_size((meso_dtype)g->dtype) * g->components * g->dims[0] * g->dims[1] * g->dims[2];
        uint8_t* p = (uint8_t*)malloc(n);
        for (size_t i = 0; i < n; i++)
            p[i] = (uint8_t)(i * 31u + g->seed * 17u);
        memset(&d, 0, sizeof d);
        d.type = g->type;
        d.object = g->object;
        d.lod = g->lod;
        d.dtype = g->dtype;
        d.components = g->components;
        memcpy(d.dims, g->dims, sizeof d.dims);
        meso_error e;
        if (meso_writer_add(w, &d, p, n, &e) != MESO_OK) {
            fprintf(stderr, "make_golden: %s\n", e.message);
            return 2;
        }
        free(p);
    }
    return write(w, argv[1], "all_chunks.meso") ? 2 : 0;
}
