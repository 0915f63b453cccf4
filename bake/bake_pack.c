/*
 * bake_pack.c — meso_bake_pack (`mesobake pack A.meso B.meso -o scene.meso`):
 * several .meso files into one, every object of every input kept as its own
 * object (issue 16, "several objects per file"; FORMAT.md §7.2: a file holds
 * any number of OBJT records, each chunk names its object).
 *
 * What is decided here:
 *  - Inputs are verified in full first (MESO_CHECK_FULL: every CRC, every
 *    structured chunk, every object against its kind, Draco meshes decoded),
 *    so a damaged input is refused, naming the file and the issue, before
 *    anything is written; a packed file is then valid when its inputs were.
 *  - Objects are numbered 1..N in input order, and within an input in its
 *    OBJT order. Each chunk is copied as stored (its encoding, lod, flags,
 *    element type and dims unchanged; the CRC checked on the way), only its
 *    `object` field renumbered: nothing is decoded and re-encoded, so a
 *    Draco mesh stays the bytes its bake wrote.
 *  - Names must address objects: a name already taken gets "~2", "~3", ...
 *    (the base shortened to fit OBJT's 31 bytes, at a UTF-8 boundary), and
 *    the report warns (E3482).
 *  - File-wide chunks: the inputs' META and RPRT are kept inside the packed
 *    file's, per object (META "objects"[k].meta, RPRT "objects"[k].report);
 *    the LODS records (levels of detail, FORMAT.md §7.10) of every object
 *    with more than one level go, renumbered, into the packed file's one
 *    LODS chunk (lod_table.c); any other file-wide chunk is refused
 *    (E3483): it would belong to no object and its meaning in a merged
 *    file is unknown.
 *  - Memory: the output's chunks are held until written (the writer owns the
 *    only copy), so the estimate is the inputs' total size, checked against
 *    --max-memory before anything is read.
 *  - Deterministic: the bytes depend only on the inputs' bytes and order
 *    (provenance by base name, as every bake).
 *
 * Issue codes 3480..3489 (meso_bake.h lists them).
 */
#include "bake_internal.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "lod_table.h"
#include "memory_budget.h"
#include "mesh_chunk.h"

/* The first issue full validation finds, into err (prefixed by the file). */
typedef struct first_issue {
    meso_error* err;
    const char* path;
    int seen;
} first_issue;

static int keep_first(void* user, const meso_error* issue)
{
    first_issue* fi = user;
    if (!fi->seen && fi->err) {
        *fi->err = *issue;
        snprintf(fi->err->message, sizeof(fi->err->message), "%.60s: %.170s", mesoi_base_name(fi->path),
                 issue->message);
    }
    fi->seen = 1;
    return 1; /* one is enough to refuse the input */
}

cJSON* mesoi_json_chunk(meso_file* f, uint32_t type)
{
    const int32_t idx = meso_file_find(f, type, 0, 0);
    if (idx < 0)
        return NULL;
    const meso_chunk_info* ci = meso_file_chunk(f, (uint32_t)idx);
    char* text = malloc((size_t)ci->decoded_size + 1);
    if (!text)
        return NULL;
    cJSON* j = NULL;
    if (meso_file_read_chunk(f, (uint32_t)idx, text, (size_t)ci->decoded_size, NULL) == MESO_OK) {
        text[ci->decoded_size] = 0;
        j = cJSON_Parse(text);
    }
    free(text);
    return j;
}

/* `name` made unique among the `count` names in `taken`: itself, or with
 * "~k" (k = 2, 3, ...) and the base cut to fit 31 bytes at a UTF-8 boundary. */
static int unique_name(const char* name, char (*taken)[32], uint32_t count, char out[32])
{
    int renamed = 0;
    snprintf(out, 32, "%s", name);
    for (uint32_t k = 2;; ++k) {
        int clash = 0;
        for (uint32_t i = 0; i < count && !clash; ++i)
            clash = !strcmp(taken[i], out);
        if (!clash)
            return renamed;
        renamed = 1;
        char suffix[16];
        snprintf(suffix, sizeof(suffix), "~%u", k);
        size_t keep = strlen(name);
        if (keep > 31 - strlen(suffix))
            keep = 31 - strlen(suffix);
        while (keep > 0 && ((unsigned char)name[keep] & 0xC0) == 0x80)
            --keep; /* never split a UTF-8 sequence */
        memcpy(out, name, keep);
        memcpy(out + keep, suffix, strlen(suffix) + 1);
    }
}

/* The packed file's pieces while inputs are added. */
typedef struct pack_state {
    mesoi_bake_run run;
    meso_writer* writer;
    meso_object_record* recs;
    char (*names)[32];
    uint32_t objects, cap;
    cJSON *meta, *meta_objects, *inputs, *rep, *rep_objects, *warnings;
    meso_bake_pack_report* report;
    mesoi_lod_table lods; /* the objects' levels, renumbered */
} pack_state;

/* The levels of input object `src` as object `id` of the packed file
 * (nothing for an object of one level: no record says the same). */
static meso_result add_levels(pack_state* p, meso_file* f, uint32_t src, uint32_t id, meso_error* err)
{
    uint32_t n = 0;
    meso_result r = meso_file_levels(f, src, NULL, 0, &n, err);
    if (r != MESO_OK || n < 2)
        return r;
    meso_level_info* lv = calloc(n, sizeof(*lv));
    if (!lv)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "pack: out of memory");
    r = meso_file_levels(f, src, lv, n, &n, err);
    for (uint32_t i = 0; i < n && r == MESO_OK; ++i) {
        meso_level_record rec = lv[i].rec;
        rec.object = id;
        r = mesoi_lod_table_add(&p->lods, &rec, err);
    }
    free(lv);
    return r;
}

/* Every object of input `k` (open, verified): OBJT records renumbered and
 * renamed, chunks copied as stored. */
static meso_result add_input(pack_state* p, meso_file* f, const char* path, uint32_t k, meso_error* err)
{
    uint32_t n = 0;
    meso_result r = meso_file_objects(f, NULL, 0, &n, err);
    if (r == MESO_OK && n == 0)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 3481, "%s: holds no object to pack", mesoi_base_name(path));
    meso_object_record* in = r == MESO_OK ? calloc(n, sizeof(*in)) : NULL;
    if (r == MESO_OK && !in)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "pack: out of memory");
    if (r == MESO_OK)
        r = meso_file_objects(f, in, n, &n, err);
    if (r == MESO_OK && p->objects + n > p->cap) {
        const uint32_t cap = p->objects + n > 2 * p->cap ? p->objects + n : 2 * p->cap;
        meso_object_record* recs = realloc(p->recs, sizeof(*recs) * cap);
        char(*names)[32] = recs ? realloc(p->names, sizeof(*names) * cap) : NULL;
        if (recs)
            p->recs = recs;
        if (names)
            p->names = names;
        r = recs && names ? MESO_OK : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "pack: out of memory");
        if (r == MESO_OK)
            p->cap = cap;
    }
    cJSON* src_meta = r == MESO_OK ? mesoi_json_chunk(f, MESO_CHUNK_META) : NULL;
    cJSON* src_rep = r == MESO_OK ? mesoi_json_chunk(f, MESO_CHUNK_RPRT) : NULL;
    const uint32_t chunks = meso_file_chunk_count(f);
    for (uint32_t c = 0; c < chunks && r == MESO_OK; ++c) {
        const meso_chunk_info* ci = meso_file_chunk(f, c);
        if (ci->object == 0 && ci->type != MESO_CHUNK_META && ci->type != MESO_CHUNK_RPRT &&
            ci->type != MESO_CHUNK_OBJT && ci->type != MESO_CHUNK_LODS) {
            char cc[5] = {(char)ci->type, (char)(ci->type >> 8), (char)(ci->type >> 16), (char)(ci->type >> 24), 0};
            for (int i = 0; i < 4; ++i)
                if (cc[i] < 0x20 || cc[i] > 0x7e)
                    cc[i] = '?';
            r = meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 3483,
                               "%s: chunk %u (%s) is file-wide and belongs to no object; pack cannot place it",
                               mesoi_base_name(path), c, cc);
        }
    }
    for (uint32_t i = 0; i < n && r == MESO_OK; ++i) {
        const uint32_t id = p->objects + 1;
        meso_object_record rec = in[i];
        rec.id = id;
        if (unique_name(in[i].name, p->names, p->objects, rec.name)) {
            ++p->report->renamed;
            char msg[200];
            snprintf(msg, sizeof(msg), "E3482: %s object %u '%s' renamed '%s' (the name was taken)",
                     mesoi_base_name(path), in[i].id, in[i].name, rec.name);
            cJSON_AddItemToArray(p->warnings, cJSON_CreateString(msg));
            mesoi_run_warning(&p->run, 3482, "%s", msg + 7);
        }
        p->recs[p->objects] = rec;
        memcpy(p->names[p->objects], rec.name, 32);
        ++p->objects;
        r = add_levels(p, f, in[i].id, id, err);
        for (uint32_t c = 0; c < chunks && r == MESO_OK; ++c) {
            const meso_chunk_info* ci = meso_file_chunk(f, c);
            if (ci->object != in[i].id)
                continue;
            void* bytes = malloc(ci->stored_size ? (size_t)ci->stored_size : 1);
            r = bytes ? meso_file_read_stored(f, c, bytes, (size_t)ci->stored_size, err)
                      : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "pack: out of memory");
            const meso_chunk_desc desc = {.type = ci->type, .flags = ci->flags, .object = id, .lod = ci->lod,
                                          .encoding = ci->encoding, .decoded_size = ci->decoded_size,
                                          .dtype = ci->dtype, .components = ci->components,
                                          .dims = {ci->dims[0], ci->dims[1], ci->dims[2]}};
            if (r == MESO_OK)
                r = meso_writer_add(p->writer, &desc, bytes, (size_t)ci->stored_size, err);
            free(bytes);
            ++p->report->chunks;
        }
        cJSON* mo = cJSON_CreateObject();
        cJSON_AddNumberToObject(mo, "id", id);
        cJSON_AddStringToObject(mo, "name", rec.name);
        cJSON_AddNumberToObject(mo, "input", k);
        cJSON_AddNumberToObject(mo, "source_id", in[i].id);
        cJSON_AddStringToObject(mo, "source_name", in[i].name);
        cJSON* ro = cJSON_Duplicate(mo, 1);
        if (src_meta)
            cJSON_AddItemToObject(mo, "meta", cJSON_Duplicate(src_meta, 1));
        if (src_rep)
            cJSON_AddItemToObject(ro, "report", cJSON_Duplicate(src_rep, 1));
        cJSON_AddItemToArray(p->meta_objects, mo);
        cJSON_AddItemToArray(p->rep_objects, ro);
    }
    cJSON_Delete(src_meta);
    cJSON_Delete(src_rep);
    free(in);
    return r;
}

meso_result mesoi_open_verified(const char* path, meso_file** f, meso_error* err)
{
    const meso_decoder dec = meso_bake_draco_decoder();
    const meso_open_desc desc = {.decoders = &dec, .decoder_count = dec.decode_fn ? 1 : 0};
    meso_result r = meso_file_open_path(path, &desc, f, err);
    if (r != MESO_OK) {
        if (err) {
            char m[sizeof(err->message)];
            snprintf(m, sizeof(m), "%s", err->message);
            snprintf(err->message, sizeof(err->message), "%.60s: %.170s", mesoi_base_name(path), m);
        }
        return r;
    }
    first_issue fi = {err, path, 0};
    r = meso_file_validate(*f, MESO_CHECK_FULL, keep_first, &fi);
    if (r != MESO_OK) {
        meso_file_close(*f);
        *f = NULL;
    }
    return r;
}

meso_result meso_bake_pack(const meso_bake_pack_options* o, meso_bake_output** out, meso_bake_pack_report* report,
                           meso_error* err)
{
    if (!o || !out)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "meso_bake_pack: NULL options or output");
    *out = NULL;
    meso_bake_pack_report rep_local;
    pack_state p;
    memset(&p, 0, sizeof(p));
    p.report = report ? report : &rep_local;
    memset(p.report, 0, sizeof(*p.report));
    if (!o->inputs || o->input_count == 0 || o->input_count > MESO_BAKE_MAX_PACK_INPUTS)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 3480, "pack: %u inputs (1..%u .meso files)",
                              o->input_count, MESO_BAKE_MAX_PACK_INPUTS);
    mesoi_run_begin(&p.run, &o->common);
    /* The estimate: every input's bytes, held once by the writer. */
    uint64_t need = 0;
    meso_result r = MESO_OK;
    for (uint32_t k = 0; k < o->input_count && r == MESO_OK; ++k) {
        FILE* fp = o->inputs[k] ? fopen(o->inputs[k], "rb") : NULL;
        uint64_t size = 0;
        if (!fp)
            r = meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: cannot open: %s", o->inputs[k] ? o->inputs[k] : "(null)",
                               strerror(errno));
        else if (!meso_regular_file_size(fp, &size))
            r = meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: not a regular file", o->inputs[k]);
        if (fp)
            fclose(fp);
        need = meso_size_add(need, size);
    }
    const uint64_t budget = o->common.max_memory ? o->common.max_memory : meso_memory_default_budget();
    if (r == MESO_OK)
        r = meso_budget_check(need, budget, MESO_LIMIT_ISSUE_REQUEST, err, "packing %u files", o->input_count);
    if (r == MESO_OK)
        r = meso_writer_create(NULL, &p.writer);
    p.meta = mesoi_meta_new("pack");
    p.inputs = cJSON_AddArrayToObject(p.meta, "inputs");
    p.meta_objects = cJSON_AddArrayToObject(p.meta, "objects");
    p.rep = cJSON_CreateObject();
    p.rep_objects = cJSON_AddArrayToObject(p.rep, "objects");
    p.warnings = cJSON_CreateArray();
    for (uint32_t k = 0; k < o->input_count && r == MESO_OK; ++k) {
        meso_file* f = NULL;
        r = mesoi_open_verified(o->inputs[k], &f, err);
        if (r == MESO_OK)
            r = mesoi_add_input_provenance(p.inputs, o->inputs[k], err);
        if (r == MESO_OK)
            r = add_input(&p, f, o->inputs[k], k, err);
        if (f)
            meso_file_close(f);
        if (r == MESO_OK)
            mesoi_run_stage(&p.run, "pack", (k + 1.0) / o->input_count, (k + 1.0) / o->input_count,
                            "%s: %u objects so far (%.0f ms)", mesoi_base_name(o->inputs[k]), p.objects,
                            mesoi_run_ms(&p.run));
    }
    p.report->inputs = o->input_count;
    p.report->objects = p.objects;
    p.report->bytes_in = need;
    cJSON_AddNumberToObject(p.rep, "inputs", o->input_count);
    cJSON_AddNumberToObject(p.rep, "objects_packed", p.objects);
    cJSON_AddNumberToObject(p.rep, "chunks", p.report->chunks);
    cJSON_AddNumberToObject(p.rep, "renamed", p.report->renamed);
    if (cJSON_GetArraySize(p.warnings))
        cJSON_AddItemToObject(p.rep, "warnings", p.warnings);
    else
        cJSON_Delete(p.warnings);
    if (r == MESO_OK)
        r = mesoi_lod_table_write(&p.lods, p.writer, err);
    if (r == MESO_OK)
        r = mesoi_output_finish(p.meta, p.rep, p.recs, p.objects, &p.writer, out, err);
    meso_writer_destroy(p.writer);
    mesoi_lod_table_free(&p.lods);
    cJSON_Delete(p.meta);
    cJSON_Delete(p.rep);
    free(p.recs);
    free(p.names);
    if (r == MESO_OK)
        mesoi_run_done(&p.run);
    return r;
}
