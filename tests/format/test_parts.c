/* test_parts.c — a mesh object's parts in the container (FORMAT.md §7.11):
 * PRTS and PMSH round-trip through the writer and meso_file_parts (counts,
 * each part level's chunk found by a brute-force scan of the TOC, bytes
 * and prefix from the TOC, neighbour pairs); the writer puts PRTS before
 * every payload chunk; each broken rule is refused with its issue code
 * (4931, 4932 by the content check, 6501 by the object check, 4001 and
 * 4003 by the type rules). */
#undef NDEBUG /* the checks are asserts: they must run in release builds too */
#include "meso_file.h"
#include "meso_layout.h"
#include "sample.h"

#include <assert.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void add(meso_writer* w, uint32_t type, uint32_t object, uint16_t lod, uint32_t dim0, const void* data,
                size_t size)
{
    meso_chunk_desc d = {.type = type,
                         .object = object,
                         .lod = lod,
                         .dtype = MESO_DTYPE_BYTES,
                         .components = 1,
                         .dims = {dim0, 1, 1}};
    meso_error e;
    if (meso_writer_add(w, &d, data, size, &e) != MESO_OK) {
        fprintf(stderr, "add: %s\n", e.message);
        abort();
    }
}

/* The good table: part 1 at lods 0 and 1, part 2 at lod 0; one pair. */
enum { RECORDS = 3, PAIRS = 1 };
static const meso_level_record recs[RECORDS] = {{1, 0, MESO_LEVEL_NATIVE, 0.0f, {0, 0, 0}, {0.5f, 1, 0}},
                                                {1, 1, MESO_LEVEL_NATIVE, 0.01f, {0, 0, 0}, {0.5f, 1, 0}},
                                                {2, 0, MESO_LEVEL_NATIVE, 0.0f, {0.5f, 0, 0}, {1, 1, 0}}};

static size_t prts_size(void) { return MESO_PRTS_HDR_SIZE + RECORDS * MESO_LODS_RECORD_SIZE + PAIRS * 8; }

static void encode_prts(uint8_t* buf, const meso_level_record* r, uint32_t parts, uint32_t a, uint32_t b)
{
    memset(buf, 0, prts_size());
    put32(buf + MESO_PRTS_OFF_PARTS, parts);
    put32(buf + MESO_PRTS_OFF_RECORDS, RECORDS);
    put32(buf + MESO_PRTS_OFF_EDGES, PAIRS);
    for (int i = 0; i < RECORDS; i++)
        meso_level_record_encode(&r[i], buf + MESO_PRTS_HDR_SIZE + (size_t)i * MESO_LODS_RECORD_SIZE);
    put32(buf + MESO_PRTS_HDR_SIZE + RECORDS * MESO_LODS_RECORD_SIZE, a);
    put32(buf + MESO_PRTS_HDR_SIZE + RECORDS * MESO_LODS_RECORD_SIZE + 4, b);
}

/* `skip`: a part level (index into recs) written without its PMSH; `kind`
 * of the object. */
static const meso_level_record* table = recs; /* the PRTS records make_file writes */

static uint8_t* make_file(int skip, uint32_t kind, size_t* size)
{
    static const char meta[] = "{\"tool\":\"test_parts\"}";
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    add(w, MESO_CHUNK_META, 0, 0, 1, meta, sizeof meta - 1);
    uint8_t objt[MESO_OBJT_RECORD_SIZE];
    meso_object_record o1 = {1, kind, {0, 0, 0}, {1, 1, 0}, "parted"};
    meso_object_record_encode(&o1, objt);
    add(w, MESO_CHUNK_OBJT, 0, 0, 1, objt, sizeof objt);
    size_t ms;
    uint8_t* m = sample_fan_mesh(16, &ms);
    add(w, MESO_CHUNK_MESH, 1, 0, 1, m, ms);
    free(m);
    static const uint32_t tris[RECORDS] = {8, 2, 8};
    for (int i = 0; i < RECORDS; i++) {
        if (i == skip)
            continue;
        m = sample_fan_mesh(tris[i], &ms);
        add(w, MESO_CHUNK_PMSH, 1, recs[i].lod, recs[i].object, m, ms);
        free(m);
    }
    uint8_t buf[256];
    assert(prts_size() <= sizeof buf);
    encode_prts(buf, table, 2, 1, 2);
    add(w, MESO_CHUNK_PRTS, 1, 0, 1, buf, prts_size());
    uint8_t* out = writer_to_memory(w, size);
    meso_writer_destroy(w);
    return out;
}

static uint32_t validate_issue(const uint8_t* file, size_t size)
{
    meso_error e;
    const meso_result r = open_and_validate(file, size, &e);
    return r == MESO_OK ? 0u : e.code;
}

static void parts_round_trip(void)
{
    size_t size;
    uint8_t* file = make_file(-1, MESO_OBJECT_MESH, &size);
    assert(validate_issue(file, size) == 0);
    meso_file* f = NULL;
    meso_error e;
    assert(meso_file_open_memory(file, size, NULL, &f, &e) == MESO_OK);
    uint32_t nl = 0, np = 0, ne = 0;
    meso_part_level pl[RECORDS];
    uint32_t edges[2 * PAIRS];
    assert(meso_file_parts(f, 1, pl, RECORDS, &nl, &np, edges, PAIRS, &ne, &e) == MESO_OK);
    assert(nl == RECORDS && np == 2 && ne == PAIRS && edges[0] == 1 && edges[1] == 2);
    uint64_t prts_end = 0, first_payload = UINT64_MAX;
    for (uint32_t i = 0; i < meso_file_chunk_count(f); i++) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        if (c->type == MESO_CHUNK_PRTS)
            prts_end = c->offset + c->stored_size;
        if (c->type == MESO_CHUNK_MESH || c->type == MESO_CHUNK_PMSH)
            first_payload = c->offset < first_payload ? c->offset : first_payload;
    }
    assert(prts_end > 0 && prts_end <= first_payload); /* the table comes before what it describes */
    for (int i = 0; i < RECORDS; i++) {
        assert(memcmp(&pl[i].rec, &recs[i], sizeof recs[i]) == 0);
        int32_t brute = -1;
        for (uint32_t k = 0; k < meso_file_chunk_count(f); k++) {
            const meso_chunk_info* c = meso_file_chunk(f, k);
            if (c->type == MESO_CHUNK_PMSH && c->object == 1 && c->lod == recs[i].lod && c->dims[0] == recs[i].object)
                brute = (int32_t)k;
        }
        assert(brute >= 0 && pl[i].chunk == brute);
        const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)brute);
        assert(pl[i].bytes == c->stored_size);
        assert(pl[i].prefix_bytes >= c->offset + c->stored_size && pl[i].prefix_bytes >= prts_end);
        assert(pl[i].prefix_bytes <= size);
    }
    /* Counting only; an object without parts has none. */
    assert(meso_file_parts(f, 1, NULL, 0, &nl, &np, NULL, 0, &ne, &e) == MESO_OK && nl == RECORDS);
    assert(meso_file_parts(f, 7, NULL, 0, &nl, &np, NULL, 0, &ne, &e) == MESO_OK && nl == 0 && np == 0 && ne == 0);
    assert(meso_file_parts(f, 1, NULL, 1, &nl, &np, NULL, 0, &ne, &e) == MESO_ERR_INVALID_ARG);
    meso_file_close(f);
    free(file);
    puts("  PRTS and PMSH round-trip; each part level's chunk, bytes and prefix agree with the TOC");
}

/* A good file with the PRTS payload replaced by `buf` (same size). */
static void expect_prts_issue(const uint8_t* buf, uint32_t code, const char* what)
{
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    meso_chunk_desc d = {.type = MESO_CHUNK_PRTS, .object = 1, .dtype = MESO_DTYPE_BYTES, .components = 1};
    meso_error e;
    const meso_result added = meso_writer_add(w, &d, buf, prts_size(), &e);
    meso_writer_destroy(w);
    assert(added != MESO_OK && e.code == code); /* the writer refuses it too */
    size_t size;
    uint8_t* file = make_file(-1, MESO_OBJECT_MESH, &size);
    for (uint32_t i = 0; i < get32(file + MESO_HDR_OFF_CHUNK_COUNT); i++) {
        uint8_t* ent = file + 64 + (size_t)i * 64;
        if (get32(ent + MESO_TOC_OFF_TYPE) == MESO_CHUNK_PRTS) {
            memcpy(file + get64(ent + MESO_TOC_OFF_OFFSET), buf, prts_size());
            fix_payload_crc(file, i);
        }
    }
    fix_crcs(file);
    const uint32_t got = validate_issue(file, size);
    printf("  %s: issue %u\n", what, got);
    assert(got == code);
    free(file);
}

static int collect_6501(void* user, const meso_error* issue)
{
    if (issue->code == MESO_ISSUE_PARTS)
        *(int*)user = 1;
    return 0; /* go on */
}

static void broken_parts_are_refused(void)
{
    uint8_t buf[256];
    meso_level_record r[RECORDS];

    memcpy(r, recs, sizeof r);
    r[2].object = 3; /* parts 1, 3 */
    encode_prts(buf, r, 2, 1, 2);
    expect_prts_issue(buf, MESO_ISSUE_PRTS_VALUE, "parts not numbered 1, 2, ...");
    memcpy(r, recs, sizeof r);
    r[1].error = -1.0f;
    encode_prts(buf, r, 2, 1, 2);
    expect_prts_issue(buf, MESO_ISSUE_PRTS_VALUE, "a negative error");
    memcpy(r, recs, sizeof r);
    r[1].lod = 2;
    encode_prts(buf, r, 2, 1, 2);
    expect_prts_issue(buf, MESO_ISSUE_PRTS_VALUE, "lods not consecutive");
    memcpy(r, recs, sizeof r);
    r[0].form = MESO_LEVEL_MESH;
    encode_prts(buf, r, 2, 1, 2);
    expect_prts_issue(buf, MESO_ISSUE_PRTS_VALUE, "a part's lod 0 that is a stand-in");
    encode_prts(buf, recs, 2, 1, 2);
    put32(buf + MESO_PRTS_HDR_SIZE + MESO_PRTS_OFF_FIRST_TRIANGLE, 5);
    expect_prts_issue(buf, MESO_ISSUE_PRTS_VALUE, "a first triangle without a count");
    encode_prts(buf, recs, 2, 1, 2);
    put32(buf + MESO_PRTS_HDR_SIZE + MESO_LODS_RECORD_SIZE + MESO_PRTS_OFF_TRIANGLE_COUNT, 5);
    expect_prts_issue(buf, MESO_ISSUE_PRTS_VALUE, "triangles named at lod 1");
    encode_prts(buf, recs, 2, 2, 1);
    expect_prts_issue(buf, MESO_ISSUE_PRTS_VALUE, "a neighbour pair not a < b");
    encode_prts(buf, recs, 2, 1, 3);
    expect_prts_issue(buf, MESO_ISSUE_PRTS_VALUE, "a neighbour pair past the part count");
    encode_prts(buf, recs, 3, 1, 2);
    expect_prts_issue(buf, MESO_ISSUE_PRTS_VALUE, "records that do not cover the parts");
    encode_prts(buf, recs, 2, 1, 2);
    put32(buf + MESO_PRTS_OFF_RESERVED, 1);
    expect_prts_issue(buf, MESO_ISSUE_PRTS_VALUE, "reserved header bytes");
    encode_prts(buf, recs, 2, 1, 2);
    put32(buf + MESO_PRTS_OFF_EDGES, 2);
    expect_prts_issue(buf, MESO_ISSUE_PRTS_SIZE, "a header that counts more than the chunk holds");

    /* Object rules (6501). */
    size_t size;
    uint8_t* file = make_file(2, MESO_OBJECT_MESH, &size);
    uint32_t got = validate_issue(file, size);
    printf("  a part level without its PMSH: issue %u\n", got);
    assert(got == MESO_ISSUE_PARTS);
    free(file);
    memcpy(r, recs, sizeof r);
    r[1].form = MESO_LEVEL_MESH; /* a shell part's form, on a mesh object */
    table = r;
    file = make_file(-1, MESO_OBJECT_MESH, &size);
    table = recs;
    got = validate_issue(file, size);
    printf("  a mesh object's part level that is a stand-in: issue %u\n", got);
    assert(got == MESO_ISSUE_PARTS);
    free(file);
    file = make_file(-1, MESO_OBJECT_SHELL, &size);
    meso_file* f = NULL;
    assert(meso_file_open_memory(file, size, NULL, &f, NULL) == MESO_OK);
    int saw = 0;
    assert(meso_file_validate(f, MESO_CHECK_FULL, collect_6501, &saw) != MESO_OK);
    meso_file_close(f);
    printf("  parts on a shell object: issue %u among its issues: %s\n", MESO_ISSUE_PARTS, saw ? "yes" : "no");
    assert(saw);
    free(file);
    meso_error e;

    /* Type rules: a PMSH of object 0, or with dims other than part x 1 x 1. */
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    size_t ms;
    uint8_t* m = sample_fan_mesh(2, &ms);
    meso_chunk_desc d = {.type = MESO_CHUNK_PMSH, .object = 0, .dtype = MESO_DTYPE_BYTES, .components = 1};
    assert(meso_writer_add(w, &d, m, ms, &e) != MESO_OK && e.code == MESO_ISSUE_TYPE_ELEMENT);
    d.object = 1;
    d.dims[1] = 2;
    assert(meso_writer_add(w, &d, m, ms, &e) != MESO_OK && e.code == MESO_ISSUE_TYPE_ELEMENT);
    d = (meso_chunk_desc){.type = MESO_CHUNK_PRTS, .object = 0, .dtype = MESO_DTYPE_BYTES, .components = 1};
    uint8_t tbl[256];
    encode_prts(tbl, recs, 2, 1, 2);
    assert(meso_writer_add(w, &d, tbl, prts_size(), &e) != MESO_OK && e.code == MESO_ISSUE_TYPE_OBJECT);
    free(m);
    meso_writer_destroy(w);
    puts("  PMSH of object 0 or of other dims, PRTS of object 0: refused by the type rules");
}

int main(void)
{
    parts_round_trip();
    broken_parts_are_refused();
    puts("test_parts: ok");
    return 0;
}
