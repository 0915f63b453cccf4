/*
 * file_levels.c — levels of detail (FORMAT.md §7.10, format 1.1): the LODS
 * record, its content check (issues 4921, 4922), the cross check of each
 * object's levels against OBJT and its chunks (6401), and what a reader
 * asks of them: which chunk a level draws, how many bytes it needs and how
 * long a file prefix holds it.
 *
 * Decided here (the format's own choice, not a paper's): a level is not a
 * list of chunks. Level L of an object draws, per chunk type, the object's
 * chunk with the smallest lod >= L. A coarse level therefore shares what
 * does not change (a frusta object's skeleton at lod 2 serves levels 0..2),
 * and because the writer lays chunks out lod descending, the chunks of
 * level L and of every coarser level sit in one prefix of the file. Byte
 * ranges are derived from the TOC rather than stored, so they cannot
 * disagree with it.
 */
#include "file_internal.h"

#include <math.h>

void meso_level_record_encode(const meso_level_record* rec, void* dst)
{
    uint8_t* p = (uint8_t*)dst;
    memset(p, 0, MESO_LODS_RECORD_SIZE);
    mesoi_st32(p + MESO_LODS_OFF_OBJECT, rec->object);
    mesoi_st16(p + MESO_LODS_OFF_LOD, rec->lod);
    mesoi_st16(p + MESO_LODS_OFF_FORM, rec->form);
    mesoi_stf32(p + MESO_LODS_OFF_ERROR, rec->error);
    for (int k = 0; k < 3; k++) {
        mesoi_stf32(p + MESO_LODS_OFF_BBOX_MIN + 4 * k, rec->bbox_min[k]);
        mesoi_stf32(p + MESO_LODS_OFF_BBOX_MAX + 4 * k, rec->bbox_max[k]);
    }
}

void meso_level_record_decode(const void* src, meso_level_record* rec)
{
    const uint8_t* p = (const uint8_t*)src;
    rec->object = mesoi_ld32(p + MESO_LODS_OFF_OBJECT);
    rec->lod = mesoi_ld16(p + MESO_LODS_OFF_LOD);
    rec->form = mesoi_ld16(p + MESO_LODS_OFF_FORM);
    rec->error = mesoi_ldf32(p + MESO_LODS_OFF_ERROR);
    for (int k = 0; k < 3; k++) {
        rec->bbox_min[k] = mesoi_ldf32(p + MESO_LODS_OFF_BBOX_MIN + 4 * k);
        rec->bbox_max[k] = mesoi_ldf32(p + MESO_LODS_OFF_BBOX_MAX + 4 * k);
    }
}

/* >>content check (4921, 4922) ---------------------------------------------- */

static const char* record_problem(const uint8_t* p, const meso_level_record* r, const meso_level_record* prev)
{
    for (int k = 0; k < 4; k++)
        if (p[MESO_LODS_OFF_RESERVED0 + k] != 0)
            return "reserved bytes not zero";
    for (int k = 0; k < MESO_LODS_SIZE_RESERVED1; k++)
        if (p[MESO_LODS_OFF_RESERVED1 + k] != 0)
            return "reserved bytes not zero";
    if (r->object == 0)
        return "object 0 (levels belong to an OBJT object)";
    if (r->form >= MESO_LEVEL_FORM_COUNT)
        return "unknown form";
    if (!isfinite(r->error) || r->error < 0.0f)
        return "error not finite and >= 0";
    for (int k = 0; k < 3; k++)
        if (!isfinite(r->bbox_min[k]) || !isfinite(r->bbox_max[k]) || r->bbox_min[k] > r->bbox_max[k])
            return "bounds not finite or inverted";
    const int first = prev == NULL || prev->object != r->object;
    if (prev && r->object < prev->object)
        return "objects not in ascending order";
    if (first && r->lod != 0)
        return "an object's first level is not lod 0";
    if (first && r->error != 0.0f)
        return "lod 0 has an error other than 0";
    if (!first && r->lod != prev->lod + 1)
        return "an object's lods are not consecutive";
    if (!first && r->error < prev->error)
        return "error decreases from a finer to a coarser level";
    return NULL;
}

meso_result mesoi_check_lods(const uint8_t* d, size_t n, int32_t chunk, uint64_t base, meso_error* err)
{
    if (n % MESO_LODS_RECORD_SIZE != 0)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_LODS_SIZE, base, chunk,
                                "chunk %d (LODS): size %zu is not a multiple of 48", (int)chunk, n);
    meso_level_record prev = {0}, r;
    for (size_t i = 0; i < n / MESO_LODS_RECORD_SIZE; i++) {
        const uint8_t* p = d + i * MESO_LODS_RECORD_SIZE;
        meso_level_record_decode(p, &r);
        const char* why = record_problem(p, &r, i ? &prev : NULL);
        if (why)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_LODS_VALUE,
                                    base == UINT64_MAX ? UINT64_MAX : base + i * MESO_LODS_RECORD_SIZE, chunk,
                                    "chunk %d (LODS): record %zu (object %u, lod %u): %s", (int)chunk, i, r.object,
                                    r.lod, why);
        prev = r;
    }
    return MESO_OK;
}

/* >>queries ------------------------------------------------------------------ */

int32_t meso_file_find_level(const meso_file* f, uint32_t type, uint32_t object, uint16_t lod)
{
    int32_t best = -1;
    for (uint32_t i = 0; f && i < f->chunk_count; i++) {
        const meso_chunk_info* c = &f->chunks[i];
        if (c->type == type && c->object == object && c->lod >= lod && (best < 0 || c->lod < f->chunks[best].lod))
            best = (int32_t)i;
    }
    return best;
}

int32_t meso_file_find_vertex_colours(const meso_file* f, uint32_t object, uint16_t lod)
{
    const int32_t m = meso_file_find_level(f, MESO_CHUNK_MESH, object, lod);
    if (m < 0)
        return -1;
    /* exactly the MESH's lod (meso_file_find takes lod 65535 for any) */
    for (uint32_t i = 0; i < f->chunk_count; i++) {
        const meso_chunk_info* c = &f->chunks[i];
        if (c->type == MESO_CHUNK_VCOL && c->object == object && c->lod == f->chunks[m].lod)
            return (int32_t)i;
    }
    return -1;
}

/* Where the chunk's stored bytes end (its padding is not needed to read it). */
static uint64_t stored_end(const meso_chunk_info* c) { return c->offset + c->stored_size; }

/* Bytes and prefix of level `lod` of `object`: the chunks it draws are, per
 * type the object has, the one with the smallest lod >= `lod` (MESH alone
 * for a MESH stand-in, with the VCOL at its own lod if there is one, as
 * every level of a mesh object; a frusta object's native levels draw no
 * MESH: its MESH is the stand-in's; native levels of the other kinds draw
 * no VCOL); the prefix also covers the file-wide chunks. */
static void level_extent(const meso_file* f, uint32_t object, uint32_t kind, uint16_t lod, uint16_t form,
                         meso_level_info* out)
{
    uint64_t bytes = 0, end = 64u + (uint64_t)f->chunk_count * f->toc_entry_size;
    for (uint32_t i = 0; i < f->chunk_count; i++) {
        const meso_chunk_info* c = &f->chunks[i];
        if (c->object == 0 && (c->type == MESO_CHUNK_META || c->type == MESO_CHUNK_OBJT || c->type == MESO_CHUNK_LODS))
            end = stored_end(c) > end ? stored_end(c) : end;
        const int plain_mesh = form == MESO_LEVEL_MESH || kind == MESO_OBJECT_MESH; /* draws MESH as a mesh */
        if (c->object != object || mesoi_part_chunk(c->type) || /* §7.11 */
            (form == MESO_LEVEL_MESH && c->type != MESO_CHUNK_MESH && c->type != MESO_CHUNK_VCOL) ||
            (form == MESO_LEVEL_NATIVE && kind == MESO_OBJECT_FRUSTA && c->type == MESO_CHUNK_MESH) ||
            (!plain_mesh && c->type == MESO_CHUNK_VCOL))
            continue;
        if ((c->type == MESO_CHUNK_VCOL ? meso_file_find_vertex_colours(f, object, lod)
                                        : meso_file_find_level(f, c->type, object, lod)) != (int32_t)i)
            continue;
        bytes += c->stored_size;
        end = stored_end(c) > end ? stored_end(c) : end;
    }
    out->bytes = bytes;
    out->prefix_bytes = end < f->file_size ? end : f->file_size;
}

/* Reads the LODS chunk (NULL, 0 when the file has none). */
static meso_result read_lods(meso_file* f, uint8_t** out, size_t* n, meso_error* err)
{
    *out = NULL;
    *n = 0;
    const int32_t li = meso_file_find(f, MESO_CHUNK_LODS, 0, UINT16_MAX);
    if (li < 0)
        return MESO_OK;
    const meso_chunk_info* c = &f->chunks[li];
    uint8_t* buf = (uint8_t*)mesoi_file_alloc(&f->alloc, c->decoded_size ? (size_t)c->decoded_size : 1);
    if (!buf)
        return mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, li,
                                "chunk %d (LODS): out of memory", (int)li);
    meso_result r = meso_file_read_chunk(f, (uint32_t)li, buf, (size_t)c->decoded_size, err);
    if (r != MESO_OK) {
        mesoi_file_free(&f->alloc, buf);
        return r;
    }
    *out = buf;
    *n = (size_t)c->decoded_size / MESO_LODS_RECORD_SIZE;
    return MESO_OK;
}

meso_result meso_file_levels(meso_file* f, uint32_t object, meso_level_info* out, uint32_t cap, uint32_t* count,
                             meso_error* err)
{
    mesoi_file_error_clear(err);
    if (f == NULL || count == NULL || (out == NULL && cap != 0))
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1,
                                "meso_file_levels: NULL file or count, or NULL out with cap > 0");
    *count = 0;
    /* The object's OBJT record: its bounds are lod 0's when LODS is silent. */
    uint32_t objects = 0;
    meso_result r = meso_file_objects(f, NULL, 0, &objects, err);
    if (r != MESO_OK)
        return r;
    meso_object_record* recs =
        (meso_object_record*)mesoi_file_alloc(&f->alloc, sizeof(meso_object_record) * (objects ? objects : 1));
    if (!recs)
        return mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, -1, "out of memory");
    if ((r = meso_file_objects(f, recs, objects, &objects, err)) != MESO_OK) {
        mesoi_file_free(&f->alloc, recs);
        return r;
    }
    const meso_object_record* rec = NULL;
    for (uint32_t i = 0; i < objects; i++)
        if (recs[i].id == object)
            rec = &recs[i];
    if (!rec) {
        mesoi_file_free(&f->alloc, recs);
        return mesoi_file_error(err, MESO_ERR_NOT_FOUND, MESO_ISSUE_API_ARG, UINT64_MAX, -1,
                                "object %u is not in the OBJT table", object);
    }
    uint8_t* lods = NULL;
    size_t n = 0;
    if ((r = read_lods(f, &lods, &n, err)) != MESO_OK) {
        mesoi_file_free(&f->alloc, recs);
        return r;
    }
    uint32_t k = 0;
    for (size_t i = 0; i < n; i++) {
        meso_level_record lr;
        meso_level_record_decode(lods + i * MESO_LODS_RECORD_SIZE, &lr);
        if (lr.object != object)
            continue;
        if (k < cap) {
            out[k].rec = lr;
            level_extent(f, object, rec->kind, lr.lod, lr.form, &out[k]);
        }
        k++;
    }
    if (k == 0) { /* no records: one native level from OBJT */
        if (cap > 0) {
            memset(&out[0], 0, sizeof out[0]);
            out[0].rec.object = object;
            memcpy(out[0].rec.bbox_min, rec->bbox_min, sizeof rec->bbox_min);
            memcpy(out[0].rec.bbox_max, rec->bbox_max, sizeof rec->bbox_max);
            level_extent(f, object, rec->kind, 0, MESO_LEVEL_NATIVE, &out[0]);
        }
        k = 1;
    }
    *count = k;
    mesoi_file_free(&f->alloc, lods);
    mesoi_file_free(&f->alloc, recs);
    return MESO_OK;
}

/* >>parts (FORMAT.md §7.11; 4931, 4932) -------------------------------------- */

meso_result mesoi_check_prts(const uint8_t* d, size_t n, int32_t chunk, uint64_t base, meso_error* err)
{
    if (n < MESO_PRTS_HDR_SIZE)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_PRTS_SIZE, base, chunk,
                                "chunk %d (PRTS): %zu bytes, less than its 16-byte header", (int)chunk, n);
    const uint32_t parts = mesoi_ld32(d + MESO_PRTS_OFF_PARTS), records = mesoi_ld32(d + MESO_PRTS_OFF_RECORDS),
                   edges = mesoi_ld32(d + MESO_PRTS_OFF_EDGES);
    const uint64_t want = MESO_PRTS_HDR_SIZE + (uint64_t)records * MESO_LODS_RECORD_SIZE +
                          (uint64_t)edges * MESO_PRTS_EDGE_SIZE;
    if (want != n)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_PRTS_SIZE, base, chunk,
                                "chunk %d (PRTS): %zu bytes, but its header counts %u records and %u neighbour "
                                "pairs (%llu bytes)",
                                (int)chunk, n, records, edges, (unsigned long long)want);
    const char* why = mesoi_ld32(d + MESO_PRTS_OFF_RESERVED) ? "reserved header bytes not zero"
                      : parts < 2 || parts > 65535 ? "a part count outside 2..65535"
                      : records < parts            ? "fewer records than parts"
                                                   : NULL;
    if (why)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_PRTS_VALUE, base, chunk,
                                "chunk %d (PRTS): %s (%u parts, %u records)", (int)chunk, why, parts, records);
    meso_level_record prev = {0}, r;
    uint64_t next = 0; /* where the next part's triangles start in the list */
    for (uint32_t i = 0; i < records; i++) {
        const uint8_t* p = d + MESO_PRTS_HDR_SIZE + (size_t)i * MESO_LODS_RECORD_SIZE;
        meso_level_record_decode(p, &r);
        /* A lod-0 record may name a range of triangles in bytes 40..47
         * (a shell part's prisms); the rest are the LODS rules. */
        uint8_t q[MESO_LODS_RECORD_SIZE];
        memcpy(q, p, sizeof q);
        if (r.lod == 0)
            memset(q + MESO_LODS_OFF_RESERVED1, 0, MESO_LODS_SIZE_RESERVED1);
        why = record_problem(q, &r, i ? &prev : NULL);
        const uint32_t first = mesoi_ld32(p + MESO_PRTS_OFF_FIRST_TRIANGLE),
                       count = mesoi_ld32(p + MESO_PRTS_OFF_TRIANGLE_COUNT);
        if (!why && r.lod == 0 && r.form != MESO_LEVEL_NATIVE)
            why = "a part's lod 0 that is not native";
        else if (!why && r.lod == 0 && (first || count) && (first != next || count == 0))
            why = "its triangles do not follow the previous part's in the list";
        else if (!why && r.lod == 0 && i > 0 && (count == 0) != (next == 0))
            why = "some parts name triangles and some do not";
        else if (!why && (i == 0 ? r.object != 1 : r.object != prev.object && r.object != prev.object + 1))
            why = "parts not numbered 1, 2, ... in order";
        else if (!why && (r.object > parts || (i + 1 == records && r.object != parts)))
            why = "records do not cover the parts 1..count";
        if (why)
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_PRTS_VALUE,
                                    base == UINT64_MAX ? UINT64_MAX : base + MESO_PRTS_HDR_SIZE + i * 48ull, chunk,
                                    "chunk %d (PRTS): record %u (part %u, lod %u): %s", (int)chunk, i, r.object,
                                    r.lod, why);
        if (r.lod == 0)
            next = first + (uint64_t)count;
        prev = r;
    }
    const uint8_t* e = d + MESO_PRTS_HDR_SIZE + (size_t)records * MESO_LODS_RECORD_SIZE;
    for (uint32_t i = 0; i < edges; i++) {
        const uint32_t a = mesoi_ld32(e + 8 * (size_t)i), b = mesoi_ld32(e + 8 * (size_t)i + 4);
        const uint32_t pa = i ? mesoi_ld32(e + 8 * (size_t)i - 8) : 0, pb = i ? mesoi_ld32(e + 8 * (size_t)i - 4) : 0;
        if (a < 1 || a >= b || b > parts || (i > 0 && (a < pa || (a == pa && b <= pb))))
            return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_PRTS_VALUE, base, chunk,
                                    "chunk %d (PRTS): neighbour pair %u (%u, %u) is not a < b within 1..%u in "
                                    "ascending order",
                                    (int)chunk, i, a, b, parts);
    }
    return MESO_OK;
}

int32_t mesoi_find_part(const meso_file* f, uint32_t type, uint32_t object, uint32_t part, uint16_t lod)
{
    for (uint32_t i = 0; f && i < f->chunk_count; i++) {
        const meso_chunk_info* c = &f->chunks[i];
        if (c->type == type && c->object == object && c->lod == lod && c->dims[0] == part)
            return (int32_t)i;
    }
    return -1;
}

meso_result meso_file_parts(meso_file* f, uint32_t object, meso_part_level* out, uint32_t cap,
                            uint32_t* level_count, uint32_t* part_count, uint32_t* edges, uint32_t edge_cap,
                            uint32_t* edge_count, meso_error* err)
{
    mesoi_file_error_clear(err);
    if (!f || !level_count || !part_count || !edge_count || (!out && cap) || (!edges && edge_cap))
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1,
                                "meso_file_parts: NULL file or count, or NULL array with a capacity");
    *level_count = *part_count = *edge_count = 0;
    const int32_t pi = meso_file_find(f, MESO_CHUNK_PRTS, object, UINT16_MAX);
    if (pi < 0)
        return MESO_OK;
    const meso_chunk_info* c = &f->chunks[pi];
    uint8_t* d = (uint8_t*)mesoi_file_alloc(&f->alloc, c->decoded_size ? (size_t)c->decoded_size : 1);
    if (!d)
        return mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, pi,
                                "chunk %d (PRTS): out of memory", (int)pi);
    meso_result r = meso_file_read_chunk(f, (uint32_t)pi, d, (size_t)c->decoded_size, err); /* checks it */
    if (r == MESO_OK) {
        const uint32_t records = mesoi_ld32(d + MESO_PRTS_OFF_RECORDS);
        const uint32_t ne = mesoi_ld32(d + MESO_PRTS_OFF_EDGES);
        uint64_t head = 64u + (uint64_t)f->chunk_count * f->toc_entry_size;
        for (uint32_t i = 0; i < f->chunk_count; i++) {
            const meso_chunk_info* h = &f->chunks[i];
            if ((h->object == 0 && (h->type == MESO_CHUNK_META || h->type == MESO_CHUNK_OBJT ||
                                    h->type == MESO_CHUNK_LODS)) ||
                (int32_t)i == pi)
                head = stored_end(h) > head ? stored_end(h) : head;
        }
        for (uint32_t i = 0; i < records && i < cap; i++) {
            const uint8_t* p = d + MESO_PRTS_HDR_SIZE + (size_t)i * MESO_LODS_RECORD_SIZE;
            meso_level_record_decode(p, &out[i].rec);
            out[i].first_triangle = out[i].rec.lod == 0 ? mesoi_ld32(p + MESO_PRTS_OFF_FIRST_TRIANGLE) : 0;
            out[i].triangle_count = out[i].rec.lod == 0 ? mesoi_ld32(p + MESO_PRTS_OFF_TRIANGLE_COUNT) : 0;
            const uint32_t part = out[i].rec.object;
            const uint16_t lod = out[i].rec.lod;
            out[i].chunk = out[i].triangle_count ? meso_file_find(f, MESO_CHUNK_PTRI, object, 0)
                                                 : mesoi_find_part(f, MESO_CHUNK_PMSH, object, part, lod);
            out[i].colours = mesoi_find_part(f, MESO_CHUNK_PVCL, object, part, lod);
            const meso_chunk_info* m = out[i].chunk >= 0 ? &f->chunks[out[i].chunk] : NULL;
            const meso_chunk_info* v = out[i].colours >= 0 ? &f->chunks[out[i].colours] : NULL;
            out[i].bytes = (m ? m->stored_size : 0) + (v ? v->stored_size : 0);
            uint64_t end = m && stored_end(m) > head ? stored_end(m) : head;
            end = v && stored_end(v) > end ? stored_end(v) : end;
            out[i].prefix_bytes = end < f->file_size ? end : f->file_size;
        }
        const uint8_t* e = d + MESO_PRTS_HDR_SIZE + (size_t)records * MESO_LODS_RECORD_SIZE;
        for (uint32_t i = 0; i < 2 * ne && i < 2 * edge_cap; i++)
            edges[i] = mesoi_ld32(e + 4 * (size_t)i);
        *level_count = records;
        *part_count = mesoi_ld32(d + MESO_PRTS_OFF_PARTS);
        *edge_count = ne;
    }
    mesoi_file_free(&f->alloc, d);
    return r;
}

meso_result meso_file_part_triangles(meso_file* f, uint32_t object, uint32_t* out, uint32_t cap, uint32_t* count,
                                     meso_error* err)
{
    mesoi_file_error_clear(err);
    if (!f || !count || (!out && cap))
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1,
                                "meso_file_part_triangles: NULL file or count, or NULL array with a capacity");
    *count = 0;
    const int32_t ti = meso_file_find(f, MESO_CHUNK_PTRI, object, 0);
    if (ti < 0)
        return MESO_OK;
    const meso_chunk_info* c = &f->chunks[ti];
    const uint32_t n = c->dims[0]; /* U32 x 1, dims n x 1 x 1: the type rules */
    if (cap >= n) {
        meso_result r = meso_file_read_chunk(f, (uint32_t)ti, out, sizeof(uint32_t) * (size_t)n, err);
        if (r != MESO_OK)
            return r;
    } else if (cap) {
        uint32_t* all = (uint32_t*)mesoi_file_alloc(&f->alloc, sizeof(uint32_t) * (size_t)n);
        if (!all)
            return mesoi_file_error(err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, ti,
                                    "chunk %d (PTRI): out of memory", (int)ti);
        meso_result r = meso_file_read_chunk(f, (uint32_t)ti, all, sizeof(uint32_t) * (size_t)n, err);
        if (r == MESO_OK)
            memcpy(out, all, sizeof(uint32_t) * cap);
        mesoi_file_free(&f->alloc, all);
        if (r != MESO_OK)
            return r;
    }
    *count = n;
    return MESO_OK;
}
