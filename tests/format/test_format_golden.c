/* test_format_golden.c — the checked-in format 1.0 files (golden/v1_0/) open,
 * pass full validation and hold the content derived here independently.
 * Each file's size and CRC32C are pinned: if one changes, someone
 * regenerated it, which must never happen silently. */
#undef NDEBUG
#include "golden_spec.h"
#include "meso_file.h"
#include "meso_layout.h"

#include <assert.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef MESO_GOLDEN_DIR
#define MESO_GOLDEN_DIR "tests/format/golden/v1_0"
#endif

static uint32_t ld32(const uint8_t* p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}
static uint64_t ld64(const uint8_t* p) { return (uint64_t)ld32(p) | (uint64_t)ld32(p + 4) << 32; }
static float ldf(const uint8_t* p)
{
    uint32_t u = ld32(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}

static uint8_t* load(const char* name, size_t* size, char* path, size_t path_size)
{
    snprintf(path, path_size, "%s/%s", MESO_GOLDEN_DIR, name);
    FILE* fp = fopen(path, "rb");
    if (!fp)
        fprintf(stderr, "cannot open %s\n", path);
    assert(fp);
    static uint8_t buf[1 << 16];
    *size = fread(buf, 1, sizeof buf, fp);
    fclose(fp);
    uint8_t* out = (uint8_t*)malloc(*size);
    memcpy(out, buf, *size);
    return out;
}

/* Open by path and by mmap, validate FULL, then check the raw bytes. */
static meso_file* open_golden(const char* name, uint64_t want_size, uint32_t want_crc, uint8_t** raw)
{
    char path[512];
    size_t size;
    uint8_t* m = load(name, &size, path, sizeof path);
    assert(size == want_size);
    assert(meso_crc32c(0, m, size) == want_crc);
    /* Header fields by hand. */
    static const uint8_t magic[8] = {0x89, 'M', 'S', 'O', '\r', '\n', 0x1A, '\n'};
    assert(memcmp(m, magic, 8) == 0 && m[8] == 1 && m[9] == 0 && m[10] == 0 && m[11] == 0);
    assert(ld64(m + 16) == size && ld64(m + 24) == 64 && ld32(m + 36) == 64);
    uint32_t n = ld32(m + 32);
    assert(ld32(m + 40) == meso_crc32c(0, m + 64, (size_t)n * 64));
    uint8_t h[64];
    memcpy(h, m, 64);
    memset(h + 44, 0, 4);
    assert(ld32(m + 44) == meso_crc32c(0, h, 64));
    for (uint32_t i = 0; i < n; i++) { /* every payload CRC, recomputed */
        const uint8_t* e = m + 64 + 64 * i;
        assert(ld32(e + 40) == meso_crc32c(0, m + ld64(e + 16), (size_t)ld64(e + 24)));
    }
    meso_file* f = NULL;
    meso_error err;
    assert(meso_file_open_mmap(path, NULL, &f, &err) == MESO_OK);
    assert(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);
    meso_file_close(f);
    f = NULL;
    assert(meso_file_open_path(path, NULL, &f, &err) == MESO_OK);
    assert(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);
    assert(meso_file_chunk_count(f) == n && meso_file_size(f) == size);
    *raw = m;
    return f;
}

static uint8_t* read_chunk(meso_file* f, uint32_t type, uint32_t object, uint16_t lod, size_t* size)
{
    int32_t i = meso_file_find(f, type, object, lod);
    assert(i >= 0);
    const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)i);
    uint8_t* buf = (uint8_t*)malloc((size_t)c->decoded_size + 16);
    assert(meso_file_read_chunk(f, (uint32_t)i, buf, (size_t)c->decoded_size, NULL) == MESO_OK);
    *size = (size_t)c->decoded_size;
    return buf;
}

static void check_tetra_content(meso_file* f)
{
    size_t n;
    uint8_t* meta = read_chunk(f, MESO_CHUNK_META, 0, 0, &n);
    assert(n == strlen(GOLDEN_META) && memcmp(meta, GOLDEN_META, n) == 0);
    free(meta);
    uint8_t* objt = read_chunk(f, MESO_CHUNK_OBJT, 0, 0, &n);
    assert(n == 64);
    meso_object_record r;
    meso_object_record_decode(objt, &r);
    assert(r.id == 1 && r.kind == MESO_OBJECT_MESH && strcmp(r.name, "tetra") == 0 && r.bbox_max[1] == 1.0f);
    free(objt);
    uint8_t* mesh = read_chunk(f, MESO_CHUNK_MESH, 1, 0, &n);
    /* 64-byte header, 4 x 12 bytes of positions, 12 x 4 bytes of indices (at 112). */
    assert(n == 64 + 48 + 48);
    assert(ld32(mesh) == 4 && ld32(mesh + 4) == 12 && ld32(mesh + 8) == 1);
    assert(ld64(mesh + 16) == 64 && ld64(mesh + 24) == 0 && ld64(mesh + 32) == 0 && ld64(mesh + 40) == 112);
    meso_mesh_view v;
    assert(meso_mesh_parse(mesh, n, &v, NULL) == MESO_OK);
    for (int i = 0; i < 12; i++) {
        assert(v.positions[i] == ((i % 3 == i / 3 - 1) ? 1.0f : 0.0f)); /* vertex k>0 has a 1 on axis k-1 */
        assert(v.indices[i] == golden_tetra_indices[i]);
    }
    free(mesh);
}

static void empty_file_has_no_chunks(void)
{
    uint8_t* raw;
    meso_file* f = open_golden("empty.meso", 64, 0x1A86DD81u, &raw);
    assert(meso_file_chunk_count(f) == 0);
    meso_file_close(f);
    free(raw);
}

static void tetra_file_holds_the_unit_tetrahedron(void)
{
    uint8_t* raw;
    meso_file* f = open_golden("tetra.meso", 704, 0xAAA86F05u, &raw);
    assert(meso_file_chunk_count(f) == 4);
    assert(meso_file_chunk(f, 0)->type == MESO_CHUNK_META && meso_file_chunk(f, 1)->type == MESO_CHUNK_OBJT);
    assert(meso_file_chunk(f, 2)->type == MESO_CHUNK_MESH && meso_file_chunk(f, 3)->type == MESO_CHUNK_STHK);
    assert(meso_file_chunk(f, 2)->flags == MESO_CHUNK_FLAG_REQUIRED);
    check_tetra_content(f);
    size_t n;
    uint8_t* t = read_chunk(f, MESO_CHUNK_STHK, 1, 0, &n);
    assert(n == 16);
    for (int i = 0; i < 4; i++)
        assert(ldf(t + 4 * i) == 0.25f * (float)(i + 1));
    free(t);
    /* Payload offsets: after a 64 + 4 x 64 byte header + TOC, 64-aligned. */
    assert(meso_file_chunk(f, 0)->offset == 320 && meso_file_chunk(f, 1)->offset == 384);
    assert(meso_file_chunk(f, 2)->offset == 448 && meso_file_chunk(f, 3)->offset == 640);
    meso_file_close(f);
    free(raw);
}

static void all_chunks_file_holds_every_type(void)
{
    uint8_t* raw;
    meso_file* f = open_golden("all_chunks.meso", 4032, 0x789D2735u, &raw);
    assert(meso_file_chunk_count(f) == 6 + GOLDEN_TYPED_COUNT);
    check_tetra_content(f);
    size_t n;
    uint8_t* p = read_chunk(f, MESO_CHUNK_RPRT, 0, 0, &n);
    assert(n == strlen(GOLDEN_RPRT) && memcmp(p, GOLDEN_RPRT, n) == 0);
    free(p);
    p = read_chunk(f, MESO_CHUNK_SKEL, 1, 0, &n);
    assert(n == 64 && (int32_t)ld32(p + 16) == -1 && ld32(p + 48) == 0 && ldf(p + 40) == 1.0f);
    free(p);
    p = read_chunk(f, MESO_CHUNK_FRUS, 1, 0, &n);
    assert(n == 64 && ldf(p + 12) == 0.5f && ldf(p + 28) == 0.25f);
    free(p);
    for (size_t k = 0; k < GOLDEN_TYPED_COUNT; k++) {
        const golden_typed* g = &golden_typed_chunks[k];
        int32_t i = meso_file_find(f, g->type, g->object, g->lod);
        assert(i >= 0);
        const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)i);
        assert(c->dtype == g->dtype && c->components == g->components && c->dims[0] == g->dims[0] &&
               c->dims[1] == g->dims[1] && c->dims[2] == g->dims[2]);
        p = read_chunk(f, g->type, g->object, g->lod, &n);
        assert(n ==
               (size_t)meso_dtype_size((meso_dtype)g->dtype) * g->components * g->dims[0] * g->dims[1] * g->dims[2]);
        for (size_t b = 0; b < n; b++)
            assert(p[b] == (uint8_t)(b * 31u + g->seed * 17u));
        free(p);
    }
    /* Coarse levels first. */
    assert(meso_file_find(f, MESO_CHUNK_TX2D, 1, 2) < meso_file_find(f, MESO_CHUNK_TX2D, 1, 1));
    assert(meso_file_find(f, MESO_CHUNK_TX2D, 1, 1) < meso_file_find(f, MESO_CHUNK_MESH, 1, 0));
    meso_file_close(f);
    free(raw);
}

int main(void)
{
    empty_file_has_no_chunks();
    tetra_file_holds_the_unit_tetrahedron();
    all_chunks_file_holds_every_type();
    printf("test_format_golden: ok\n");
    return 0;
}
