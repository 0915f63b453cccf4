/* test_levels.c — levels of detail in the container (FORMAT.md §7.10):
 * LODS records round-trip; a level resolves each chunk type to the smallest
 * lod >= its own (checked against a brute-force scan of the TOC); its bytes
 * and prefix come from the TOC; the writer lays levels out coarse first; and
 * every broken rule is refused with its issue code (4921, 4922, 6401); a
 * VCOL goes with the MESH at its own lod (6002). */
#undef NDEBUG /* the checks are asserts: they must run in release builds too */
#include "meso_file.h"
#include "meso_layout.h"
#include "sample.h"

#include <assert.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void add(meso_writer* w, uint32_t type, uint32_t object, uint16_t lod, const void* data, size_t size)
{
    meso_chunk_desc d = {.type = type, .object = object, .lod = lod, .dtype = MESO_DTYPE_BYTES, .components = 1};
    meso_error e;
    if (meso_writer_add(w, &d, data, size, &e) != MESO_OK) {
        fprintf(stderr, "add: %s\n", e.message);
        abort();
    }
}

static const char meta[] = "{\"tool\":\"test_levels\"}";

/* Vertex colours (FORMAT.md §7.3 VCOL) make_file adds, as bits: */
enum {
    VCOL_L1 = 1,       /* object 1, lod 1: U8 x 4 for its 18 vertices */
    VCOL_L2_OCC = 2,   /* object 1, lod 2: U8 x 1 (occlusion alone) for its 6 vertices */
    VCOL_O2_SHORT = 4  /* object 2, lod 0: U8 x 4, one short of its 10 vertices (6002) */
};

static void add_vcol(meso_writer* w, uint32_t object, uint16_t lod, uint16_t components, uint32_t n)
{
    uint8_t* c = (uint8_t*)calloc((size_t)components * n, 1);
    assert(c);
    const meso_chunk_desc d = {.type = MESO_CHUNK_VCOL, .object = object, .lod = lod, .dtype = MESO_DTYPE_U8,
                               .components = components, .dims = {n, 1, 1}};
    meso_error e;
    assert(meso_writer_add(w, &d, c, (size_t)components * n, &e) == MESO_OK);
    free(c);
}

/* Object 1: a mesh with levels 0..2 (64, 16, 4 triangles), object 2: a mesh
 * with no LODS records. `recs`/`n` are the LODS records written (none when
 * n == 0); lods_raw replaces them with raw bytes (for corruption tests);
 * `vcol`: the VCOL bits above. */
static uint8_t* make_file_vcol(const meso_level_record* recs, size_t n, const uint8_t* lods_raw,
                               size_t lods_raw_size, int vcol, size_t* size)
{
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    add(w, MESO_CHUNK_META, 0, 0, meta, sizeof meta - 1);
    uint8_t objt[2 * MESO_OBJT_RECORD_SIZE];
    meso_object_record o1 = {1, MESO_OBJECT_MESH, {0, 0, 0}, {1, 1, 0}, "levelled"};
    meso_object_record o2 = {2, MESO_OBJECT_MESH, {0, 0, 0}, {1, 1, 0}, "plain"};
    meso_object_record_encode(&o1, objt);
    meso_object_record_encode(&o2, objt + MESO_OBJT_RECORD_SIZE);
    add(w, MESO_CHUNK_OBJT, 0, 0, objt, sizeof objt);
    /* Added finest first, on purpose: the writer must put them coarse first. */
    static const uint32_t tris[3] = {64, 16, 4};
    for (uint16_t lod = 0; lod < 3; lod++) {
        size_t ms;
        uint8_t* m = sample_fan_mesh(tris[lod], &ms);
        add(w, MESO_CHUNK_MESH, 1, lod, m, ms);
        free(m);
    }
    size_t ms;
    uint8_t* m = sample_fan_mesh(8, &ms);
    add(w, MESO_CHUNK_MESH, 2, 0, m, ms);
    free(m);
    if (vcol & VCOL_L1)
        add_vcol(w, 1, 1, 4, 18);
    if (vcol & VCOL_L2_OCC)
        add_vcol(w, 1, 2, 1, 6);
    if (vcol & VCOL_O2_SHORT)
        add_vcol(w, 2, 0, 4, 9);
    if (lods_raw) {
        add(w, MESO_CHUNK_LODS, 0, 0, lods_raw, lods_raw_size);
    } else if (n) {
        uint8_t* buf = (uint8_t*)calloc(n, MESO_LODS_RECORD_SIZE);
        assert(buf);
        for (size_t i = 0; i < n; i++)
            meso_level_record_encode(&recs[i], buf + i * MESO_LODS_RECORD_SIZE);
        add(w, MESO_CHUNK_LODS, 0, 0, buf, n * MESO_LODS_RECORD_SIZE);
        free(buf);
    }
    uint8_t* out = writer_to_memory(w, size);
    meso_writer_destroy(w);
    return out;
}

static uint8_t* make_file(const meso_level_record* recs, size_t n, const uint8_t* lods_raw, size_t lods_raw_size,
                          size_t* size)
{
    return make_file_vcol(recs, n, lods_raw, lods_raw_size, 0, size);
}

static meso_level_record level(uint32_t object, uint16_t lod, uint16_t form, float error)
{
    meso_level_record r = {object, lod, form, error, {0, 0, 0}, {1, 1, 0}};
    return r;
}

static const meso_level_record good[3] = {{1, 0, MESO_LEVEL_NATIVE, 0.0f, {0, 0, 0}, {1, 1, 0}},
                                          {1, 1, MESO_LEVEL_NATIVE, 0.01f, {0, 0, 0}, {1, 1, 0}},
                                          {1, 2, MESO_LEVEL_NATIVE, 0.05f, {0, 0, 0}, {1, 1, 0}}};

static void levels_resolve_and_measure_against_the_toc(void)
{
    size_t size;
    uint8_t* file = make_file(good, 3, NULL, 0, &size);
    meso_file* f = NULL;
    meso_error e;
    assert(meso_file_open_memory(file, size, NULL, &f, &e) == MESO_OK);
    uint16_t major, minor;
    meso_file_version(f, &major, &minor);
    assert(major == 1 && minor == 1); /* LODS is format 1.1 */
    assert(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);

    /* Coarse first: MESH lod 2 before lod 1 before lod 0 in the file. */
    uint64_t at[3] = {0, 0, 0};
    for (uint32_t i = 0; i < meso_file_chunk_count(f); i++) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        if (c->type == MESO_CHUNK_MESH && c->object == 1)
            at[c->lod] = c->offset;
    }
    assert(at[2] < at[1] && at[1] < at[0]);

    /* find_level against brute force, for every type/object/lod asked. */
    const uint32_t types[3] = {MESO_CHUNK_MESH, MESO_CHUNK_SDIR, MESO_CHUNK_LODS};
    for (int t = 0; t < 3; t++)
        for (uint32_t obj = 0; obj < 3; obj++)
            for (uint16_t lod = 0; lod < 5; lod++) {
                int32_t want = -1;
                for (uint32_t i = 0; i < meso_file_chunk_count(f); i++) {
                    const meso_chunk_info* c = meso_file_chunk(f, i);
                    if (c->type == types[t] && c->object == obj && c->lod >= lod &&
                        (want < 0 || c->lod < meso_file_chunk(f, (uint32_t)want)->lod))
                        want = (int32_t)i;
                }
                assert(meso_file_find_level(f, types[t], obj, lod) == want);
            }

    meso_level_info li[4];
    uint32_t count = 0;
    assert(meso_file_levels(f, 1, NULL, 0, &count, &e) == MESO_OK && count == 3);
    assert(meso_file_levels(f, 1, li, 4, &count, &e) == MESO_OK && count == 3);
    uint64_t header_end = 0; /* META, OBJT, LODS end */
    for (uint32_t i = 0; i < meso_file_chunk_count(f); i++) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        if (c->object == 0 && c->type != MESO_CHUNK_RPRT && c->offset + c->stored_size > header_end)
            header_end = c->offset + c->stored_size;
    }
    for (uint16_t lod = 0; lod < 3; lod++) {
        assert(li[lod].rec.lod == lod && li[lod].rec.error == good[lod].error);
        const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)meso_file_find(f, MESO_CHUNK_MESH, 1, lod));
        assert(li[lod].bytes == c->stored_size);
        const uint64_t end = (c->offset + c->stored_size);
        assert(li[lod].prefix_bytes == (end > header_end ? end : header_end));
    }
    assert(li[2].prefix_bytes < li[1].prefix_bytes && li[1].prefix_bytes < li[0].prefix_bytes);

    /* Object 2 has no records: one native level with OBJT's bounds. */
    assert(meso_file_levels(f, 2, li, 4, &count, &e) == MESO_OK && count == 1);
    assert(li[0].rec.lod == 0 && li[0].rec.error == 0.0f && li[0].rec.form == MESO_LEVEL_NATIVE);
    assert(li[0].rec.bbox_max[0] == 1.0f && li[0].rec.bbox_max[1] == 1.0f);
    const meso_chunk_info* c2 = meso_file_chunk(f, (uint32_t)meso_file_find(f, MESO_CHUNK_MESH, 2, 0));
    assert(li[0].bytes == c2->stored_size && li[0].prefix_bytes == (c2->offset + c2->stored_size));
    assert(meso_file_levels(f, 7, li, 4, &count, &e) == MESO_ERR_NOT_FOUND);
    meso_file_close(f);
    free(file);
}

static uint32_t validate_issue(const uint8_t* file, size_t size)
{
    meso_error e;
    meso_result r = open_and_validate(file, size, &e);
    return r == MESO_OK ? 0u : e.code;
}

/* A VCOL belongs to the MESH at its own lod: it is found for the levels
 * that draw that MESH (not for a finer level whose own MESH has none, as
 * the smallest-lod->=-L rule alone would), it counts in their bytes, U8 x 4
 * and U8 x 1 are valid, and a count that is not the MESH's vertex count
 * (6002) or another component count (4001, by the writer) is refused. */
static void vertex_colours_go_with_their_mesh(void)
{
    size_t size;
    uint8_t* file = make_file_vcol(good, 3, NULL, 0, VCOL_L1 | VCOL_L2_OCC, &size);
    meso_file* f = NULL;
    meso_error e;
    assert(meso_file_open_memory(file, size, NULL, &f, &e) == MESO_OK);
    assert(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);
    int32_t vc[3];
    for (uint16_t lod = 0; lod < 3; lod++) {
        vc[lod] = -1; /* brute force: the VCOL at exactly the lod of the MESH the level draws */
        const int32_t mi = meso_file_find_level(f, MESO_CHUNK_MESH, 1, lod);
        for (uint32_t i = 0; i < meso_file_chunk_count(f); i++) {
            const meso_chunk_info* c = meso_file_chunk(f, i);
            if (c->type == MESO_CHUNK_VCOL && c->object == 1 && c->lod == meso_file_chunk(f, (uint32_t)mi)->lod)
                vc[lod] = (int32_t)i;
        }
        assert(meso_file_find_vertex_colours(f, 1, lod) == vc[lod]);
    }
    assert(vc[0] < 0 && vc[1] >= 0 && vc[2] >= 0);
    assert(meso_file_find_vertex_colours(f, 2, 0) == -1 && meso_file_find_vertex_colours(f, 9, 0) == -1);
    meso_level_info li[3];
    uint32_t count = 0;
    assert(meso_file_levels(f, 1, li, 3, &count, &e) == MESO_OK && count == 3);
    for (uint16_t lod = 0; lod < 3; lod++) {
        const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)meso_file_find(f, MESO_CHUNK_MESH, 1, lod));
        uint64_t want = c->stored_size, end = c->offset + c->stored_size;
        if (vc[lod] >= 0) {
            const meso_chunk_info* v = meso_file_chunk(f, (uint32_t)vc[lod]);
            want += v->stored_size;
            end = v->offset + v->stored_size > end ? v->offset + v->stored_size : end;
        }
        assert(li[lod].bytes == want && li[lod].prefix_bytes >= end);
    }
    meso_file_close(f);
    free(file);

    file = make_file_vcol(good, 3, NULL, 0, VCOL_O2_SHORT, &size);
    assert(validate_issue(file, size) == MESO_ISSUE_MESH_VCOL);
    free(file);
    /* U8 x 3: refused already by the writer (the element rules, 4001) */
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    uint8_t rgb[30] = {0};
    const meso_chunk_desc d = {.type = MESO_CHUNK_VCOL, .object = 2, .dtype = MESO_DTYPE_U8, .components = 3,
                               .dims = {10, 1, 1}};
    assert(meso_writer_add(w, &d, rgb, sizeof rgb, &e) != MESO_OK && e.code == MESO_ISSUE_TYPE_ELEMENT);
    meso_writer_destroy(w);
}

static void expect_issue(const meso_level_record* recs, size_t n, uint32_t code, const char* what)
{
    /* The writer refuses what the content check refuses; build the chunk
     * raw and patch it in, so the reader's check is what is tested. */
    uint8_t* buf = (uint8_t*)calloc(n ? n : 1, MESO_LODS_RECORD_SIZE);
    assert(buf);
    for (size_t i = 0; i < n; i++)
        meso_level_record_encode(&recs[i], buf + i * MESO_LODS_RECORD_SIZE);
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    meso_chunk_desc d = {.type = MESO_CHUNK_LODS, .dtype = MESO_DTYPE_BYTES, .components = 1};
    meso_error e;
    const meso_result added = meso_writer_add(w, &d, buf, n * MESO_LODS_RECORD_SIZE, &e);
    meso_writer_destroy(w);
    if (code == MESO_ISSUE_LODS_VALUE)
        assert(added != MESO_OK && e.code == code);
    /* Write good records of the same size, then overwrite the payload. */
    meso_level_record filler[8];
    for (size_t i = 0; i < n; i++)
        filler[i] = level(1, (uint16_t)i, 0, (float)i);
    size_t size;
    uint8_t* file = make_file(filler, n, NULL, 0, &size);
    for (uint32_t i = 0; i < get32(file + MESO_HDR_OFF_CHUNK_COUNT); i++) {
        uint8_t* ent = file + 64 + (size_t)i * 64;
        if (get32(ent + MESO_TOC_OFF_TYPE) == MESO_CHUNK_LODS) {
            memcpy(file + get64(ent + MESO_TOC_OFF_OFFSET), buf, n * MESO_LODS_RECORD_SIZE);
            fix_payload_crc(file, i);
        }
    }
    fix_crcs(file);
    const uint32_t got = validate_issue(file, size);
    if (got != code) {
        fprintf(stderr, "%s: issue %u, expected %u\n", what, got, code);
        abort();
    }
    free(file);
    free(buf);
}

static void broken_levels_are_refused_with_their_issue(void)
{
    meso_level_record r[3];
    memcpy(r, good, sizeof r);
    expect_issue(r, 3, 0, "good records");

    memcpy(r, good, sizeof r);
    r[1].lod = 2, r[2].lod = 3;
    expect_issue(r, 3, MESO_ISSUE_LODS_VALUE, "a gap in the lods");
    memcpy(r, good, sizeof r);
    r[2].error = 0.001f;
    expect_issue(r, 3, MESO_ISSUE_LODS_VALUE, "error decreasing");
    memcpy(r, good, sizeof r);
    r[0].error = 0.5f, r[1].error = 0.6f, r[2].error = 0.7f;
    expect_issue(r, 3, MESO_ISSUE_LODS_VALUE, "lod 0 with an error");
    memcpy(r, good, sizeof r);
    r[1].bbox_min[0] = 2.0f;
    expect_issue(r, 3, MESO_ISSUE_LODS_VALUE, "inverted bounds");
    memcpy(r, good, sizeof r);
    r[1].form = 9;
    expect_issue(r, 3, MESO_ISSUE_LODS_VALUE, "unknown form");
    memcpy(r, good, sizeof r);
    r[0].object = 0;
    expect_issue(r, 3, MESO_ISSUE_LODS_VALUE, "object 0");

    /* Cross checks against OBJT and the chunks (6401). */
    meso_level_record four[4];
    memcpy(four, good, sizeof good);
    four[3] = level(1, 3, MESO_LEVEL_NATIVE, 0.1f);
    expect_issue(four, 4, MESO_ISSUE_LEVELS, "a level with no MESH at or above its lod");
    memcpy(r, good, sizeof r);
    for (int i = 0; i < 3; i++)
        r[i].object = 5;
    expect_issue(r, 3, MESO_ISSUE_LEVELS, "an object OBJT does not have");
    memcpy(r, good, sizeof r);
    r[0].form = MESO_LEVEL_MESH;
    expect_issue(r, 3, MESO_ISSUE_LEVELS, "lod 0 as a stand-in");

    /* A size that is not a whole number of records. */
    size_t size;
    uint8_t raw[MESO_LODS_RECORD_SIZE + 16];
    memset(raw, 0, sizeof raw);
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    meso_chunk_desc d = {.type = MESO_CHUNK_LODS, .dtype = MESO_DTYPE_BYTES, .components = 1};
    meso_error e;
    assert(meso_writer_add(w, &d, raw, sizeof raw, &e) != MESO_OK && e.code == MESO_ISSUE_LODS_SIZE);
    meso_writer_destroy(w);
    (void)size;
}

int main(void)
{
    levels_resolve_and_measure_against_the_toc();
    broken_levels_are_refused_with_their_issue();
    vertex_colours_go_with_their_mesh();
    puts("test_levels: ok");
    return 0;
}
