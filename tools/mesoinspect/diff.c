/*
 * diff.c — `mesoinspect diff A B [--format ...]`: compare two .meso files
 * structurally. Chunks are matched by (type, object, lod) — the n-th such
 * chunk of A with the n-th of B — and compared field by field and by their
 * decoded bytes (META/RPRT also by JSON path). Layout (offsets, TOC position)
 * is not content and is not compared. Schema: schema/diff.schema.json.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "inspect.h"

static const char* const usage_diff =
    "Usage: mesoinspect diff A B [--format text|json|mini-json]\n"
    "\n"
    "Compare two .meso files: the header version, the chunk list (chunks are\n"
    "matched by type, object and lod), each matched chunk's fields (flags,\n"
    "encoding, element type, sizes, CRC32C, MESH counts) and its decoded bytes\n"
    "(first differing offset and number of differing bytes; for META and RPRT\n"
    "also the JSON paths that differ). Offsets and TOC order are layout, not\n"
    "content, and are not compared.\n"
    "\n"
    "  --format FMT   text (default), json or mini-json (one line)\n"
    "  -h, --help     this help\n"
    "\n"
    "Exit codes: 0 identical in content, 7 different, 1 bad arguments,\n"
    "            2 I/O failure, 3 invalid input (a file or a chunk cannot be read).\n";

#define MAX_JSON_PATHS 64

typedef struct side {
    const char* path;
    meso_file* f;
} side;

typedef struct keyed {
    uint32_t type, object, nth, index;
    uint16_t lod;
} keyed;

static int key_cmp(const keyed* x, const keyed* y)
{
    if (x->type != y->type)
        return x->type < y->type ? -1 : 1;
    if (x->object != y->object)
        return x->object < y->object ? -1 : 1;
    if (x->lod != y->lod)
        return x->lod < y->lod ? -1 : 1;
    if (x->nth != y->nth)
        return x->nth < y->nth ? -1 : 1;
    return 0;
}

static int keyed_qsort(const void* a, const void* b)
{
    int c = key_cmp(a, b);
    if (c)
        return c;
    const keyed *x = a, *y = b;
    return x->index < y->index ? -1 : x->index > y->index;
}

/* Keys sorted by (type, object, lod, nth); nth counts earlier chunks of the
 * same (type, object, lod) in TOC order. */
static keyed* make_keys(const meso_file* f, uint32_t* count)
{
    const uint32_t n = meso_file_chunk_count(f);
    keyed* k = calloc(n ? n : 1, sizeof(*k));
    if (!k)
        return NULL;
    for (uint32_t i = 0; i < n; ++i) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        k[i].type = c->type;
        k[i].object = c->object;
        k[i].lod = c->lod;
        k[i].index = i;
    }
    qsort(k, n, sizeof(*k), keyed_qsort); /* TOC order within a key: index ascending */
    for (uint32_t i = 1; i < n; ++i)
        if (k[i].type == k[i - 1].type && k[i].object == k[i - 1].object && k[i].lod == k[i - 1].lod)
            k[i].nth = k[i - 1].nth + 1;
    *count = n;
    return k;
}

typedef struct pair {
    int64_t a, b; /* TOC indices, -1 when absent */
} pair;

static int pair_qsort(const void* x, const void* y)
{
    const pair *p = x, *q = y;
    /* A's TOC order first, then chunks only in B in B's order */
    int64_t pa = p->a >= 0 ? p->a : INT64_MAX, qa = q->a >= 0 ? q->a : INT64_MAX;
    if (pa != qa)
        return pa < qa ? -1 : 1;
    return p->b < q->b ? -1 : p->b > q->b;
}

/* >>field differences ----------------------------------------------------- */

typedef struct diff_out {
    mi_format fmt;
    cJSON* fields; /* JSON: array of {field, a, b}; text: printed lines */
    int count;
    const char* label; /* text: printed once before the first line */
    int* label_printed;
} diff_out;

static void text_label(diff_out* o)
{
    if (o->fmt == MI_FORMAT_TEXT && o->label && !*o->label_printed) {
        printf("%s\n", o->label);
        *o->label_printed = 1;
    }
}

/* Counts a differing field. Text: prints the chunk's label (once) and
 * returns NULL, the caller prints the line; JSON: returns the new
 * {"field": field} entry of o->fields, the caller adds "a" and "b". */
static cJSON* field_begin(diff_out* o, const char* field)
{
    o->count++;
    if (o->fmt == MI_FORMAT_TEXT) {
        text_label(o);
        return NULL;
    }
    cJSON* j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "field", field);
    cJSON_AddItemToArray(o->fields, j);
    return j;
}

static void field_num(diff_out* o, const char* field, double a, double b)
{
    if (a == b)
        return;
    cJSON* j = field_begin(o, field);
    if (!j) {
        printf("  %-18s %.17g -> %.17g\n", field, a, b);
        return;
    }
    cJSON_AddNumberToObject(j, "a", a);
    cJSON_AddNumberToObject(j, "b", b);
}

static void field_str(diff_out* o, const char* field, const char* a, const char* b)
{
    if (!strcmp(a, b))
        return;
    cJSON* j = field_begin(o, field);
    if (!j) {
        printf("  %-18s %s -> %s\n", field, a, b);
        return;
    }
    cJSON_AddStringToObject(j, "a", a);
    cJSON_AddStringToObject(j, "b", b);
}

/* >>JSON paths ------------------------------------------------------------ */

static void add_path(cJSON* paths, const char* path)
{
    if (cJSON_GetArraySize(paths) < MAX_JSON_PATHS)
        cJSON_AddItemToArray(paths, cJSON_CreateString(path[0] ? path : "$"));
}

static void json_paths(const cJSON* a, const cJSON* b, char* path, size_t cap, cJSON* out)
{
    const size_t len = strlen(path);
    if (cJSON_IsObject(a) && cJSON_IsObject(b)) {
        const cJSON* x;
        cJSON_ArrayForEach(x, a)
        {
            snprintf(path + len, cap - len, "%s%s", len ? "." : "", x->string);
            const cJSON* y = cJSON_GetObjectItemCaseSensitive(b, x->string);
            if (!y)
                add_path(out, path);
            else
                json_paths(x, y, path, cap, out);
            path[len] = '\0';
        }
        cJSON_ArrayForEach(x, b)
        {
            if (!cJSON_GetObjectItemCaseSensitive(a, x->string)) {
                snprintf(path + len, cap - len, "%s%s", len ? "." : "", x->string);
                add_path(out, path);
                path[len] = '\0';
            }
        }
    } else if (cJSON_IsArray(a) && cJSON_IsArray(b) && cJSON_GetArraySize(a) == cJSON_GetArraySize(b)) {
        int i = 0;
        for (const cJSON *x = a->child, *y = b->child; x && y; x = x->next, y = y->next, ++i) {
            snprintf(path + len, cap - len, "[%d]", i);
            json_paths(x, y, path, cap, out);
            path[len] = '\0';
        }
    } else if (!cJSON_Compare(a, b, 1)) {
        add_path(out, path);
    }
}

/* >>payload --------------------------------------------------------------- */

typedef struct payload {
    uint8_t* owned;
    const uint8_t* data;
    size_t size;
    int decoded;       /* 1 decoded bytes, 0 stored bytes */
    meso_result r;     /* of the decoded read */
    char error[400];   /* when r != MESO_OK */
} payload;

static void load_payload(side* s, uint32_t index, int want_stored, payload* p)
{
    memset(p, 0, sizeof(*p));
    meso_error err;
    memset(&err, 0, sizeof(err));
    if (!want_stored) {
        p->r = mi_read_decoded(s->f, index, &p->owned, &p->size, &err);
        if (p->r == MESO_OK) {
            p->data = p->owned;
            p->decoded = 1;
            return;
        }
        mi_format_issue(&err, p->error, sizeof(p->error));
    }
    /* fall back to the stored bytes, unchecked */
    const meso_chunk_info* c = meso_file_chunk(s->f, index);
    p->data = mi_stored(s->f, index);
    p->size = p->data && c->stored_size <= SIZE_MAX ? (size_t)c->stored_size : 0;
}

/* The arguments: both paths and the format. Returns -1 to go on, else the
 * exit code (help printed, or a usage error). */
static int parse_args(int argc, char** argv, side* sa, side* sb, mi_format* fmt)
{
    int only_positional = 0;
    for (int i = 0; i < argc; ++i) {
        const char* a = argv[i];
        int k;
        if (!only_positional && mi_is_help(a)) {
            fputs(usage_diff, stdout);
            return mi_finish_stdout(MESO_EXIT_OK);
        } else if (!only_positional && (k = mi_format_option(argc, argv, &i, fmt)) != 0) {
            if (k < 0)
                return MESO_EXIT_USAGE;
        } else if (!only_positional && !strcmp(a, "--")) {
            only_positional = 1;
        } else if (!only_positional && a[0] == '-' && a[1] != '\0') {
            return mi_usage_error("unrecognized option '%s'", a);
        } else if (!sa->path) {
            sa->path = a;
        } else if (!sb->path) {
            sb->path = a;
        } else {
            return mi_usage_error("unexpected argument '%s' (diff compares two files)", a);
        }
    }
    if (!sa->path || !sb->path) {
        fputs(usage_diff, stderr);
        return MESO_EXIT_USAGE;
    }
    return -1;
}

/* Chunks of A and B matched by (type, object, lod, nth), in A's TOC order,
 * then those only in B in B's; NULL when out of memory. */
static pair* match_chunks(const side* sa, const side* sb, size_t* count)
{
    uint32_t na = 0, nb = 0;
    keyed* ka = make_keys(sa->f, &na);
    keyed* kb = make_keys(sb->f, &nb);
    pair* pairs = calloc((size_t)na + nb + 1, sizeof(*pairs));
    if (!ka || !kb || !pairs) {
        free(ka);
        free(kb);
        free(pairs);
        return NULL;
    }
    size_t np = 0;
    for (uint32_t i = 0, j = 0; i < na || j < nb;) {
        int c = i >= na ? 1 : j >= nb ? -1 : key_cmp(&ka[i], &kb[j]);
        pairs[np].a = c <= 0 ? (int64_t)ka[i].index : -1;
        pairs[np].b = c >= 0 ? (int64_t)kb[j].index : -1;
        np++;
        if (c <= 0)
            i++;
        if (c >= 0)
            j++;
    }
    qsort(pairs, np, sizeof(*pairs), pair_qsort);
    free(ka);
    free(kb);
    *count = np;
    return pairs;
}

/* The JSON entry of a matched pair (label, type, object, lod, indices). */
static cJSON* chunk_json(cJSON* jchunks, const meso_chunk_info* c, const char* label, const char* cc, pair pr)
{
    cJSON* jc = cJSON_CreateObject();
    cJSON_AddStringToObject(jc, "label", label);
    cJSON_AddStringToObject(jc, "type", cc);
    cJSON_AddNumberToObject(jc, "object", c->object);
    cJSON_AddNumberToObject(jc, "lod", c->lod);
    if (pr.a >= 0)
        cJSON_AddNumberToObject(jc, "index_a", (double)pr.a);
    else
        cJSON_AddNullToObject(jc, "index_a");
    if (pr.b >= 0)
        cJSON_AddNumberToObject(jc, "index_b", (double)pr.b);
    else
        cJSON_AddNullToObject(jc, "index_b");
    cJSON_AddItemToArray(jchunks, jc);
    return jc;
}

/* The TOC fields of two matched chunks (and a MESH chunk's header). */
static void diff_fields(diff_out* o, const side* sa, const side* sb, pair pr, const meso_chunk_info* ca,
                        const meso_chunk_info* cb)
{
    field_num(o, "flags", ca->flags, cb->flags);
    field_str(o, "encoding", mi_encoding_name(ca->encoding), mi_encoding_name(cb->encoding));
    field_str(o, "dtype", mi_dtype_name(ca->dtype), mi_dtype_name(cb->dtype));
    field_num(o, "components", ca->components, cb->components);
    char da[48], db[48];
    snprintf(da, sizeof(da), "%ux%ux%u", ca->dims[0], ca->dims[1], ca->dims[2]);
    snprintf(db, sizeof(db), "%ux%ux%u", cb->dims[0], cb->dims[1], cb->dims[2]);
    field_str(o, "dims", da, db);
    field_num(o, "stored_size", (double)ca->stored_size, (double)cb->stored_size);
    field_num(o, "decoded_size", (double)ca->decoded_size, (double)cb->decoded_size);
    char xa[16], xb[16];
    snprintf(xa, sizeof(xa), "%08x", ca->crc32c);
    snprintf(xb, sizeof(xb), "%08x", cb->crc32c);
    field_str(o, "crc32c", xa, xb);
    if (ca->type != MESO_CHUNK_MESH)
        return;
    mi_mesh_stats ma, mb;
    const int ha =
        mi_mesh_header(mi_stored(sa->f, (uint32_t)pr.a), (size_t)(ca->stored_size < 64 ? ca->stored_size : 64), &ma);
    const int hb =
        mi_mesh_header(mi_stored(sb->f, (uint32_t)pr.b), (size_t)(cb->stored_size < 64 ? cb->stored_size : 64), &mb);
    if (ha && hb) {
        field_num(o, "mesh.vertex_count", ma.vertex_count, mb.vertex_count);
        field_num(o, "mesh.index_count", ma.index_count, mb.index_count);
        field_num(o, "mesh.attributes", ma.attributes, mb.attributes);
        snprintf(da, sizeof(da), "%u/%u/%u", ma.quant_bits[0], ma.quant_bits[1], ma.quant_bits[2]);
        snprintf(db, sizeof(db), "%u/%u/%u", mb.quant_bits[0], mb.quant_bits[1], mb.quant_bits[2]);
        field_str(o, "mesh.quant_bits", da, db);
    }
}

/* The payloads of a matched pair: decoded bytes when both decode, else
 * both stored (keeping the decode errors). */
static void load_payloads(side* sa, side* sb, pair pr, payload* pa, payload* pb)
{
    load_payload(sa, (uint32_t)pr.a, 0, pa);
    load_payload(sb, (uint32_t)pr.b, 0, pb);
    if (pa->decoded == pb->decoded)
        return;
    free(pa->owned);
    free(pb->owned);
    meso_result ra = pa->r, rb = pb->r;
    char ea[400], eb[400];
    memcpy(ea, pa->error, sizeof(ea));
    memcpy(eb, pb->error, sizeof(eb));
    load_payload(sa, (uint32_t)pr.a, 1, pa);
    load_payload(sb, (uint32_t)pr.b, 1, pb);
    pa->r = ra;
    pb->r = rb;
    memcpy(pa->error, ea, sizeof(ea));
    memcpy(pb->error, eb, sizeof(eb));
}

/* How two payloads differ. */
typedef struct payload_diff {
    uint64_t ndiff, first; /* differing bytes (a size difference counts); first offset, UINT64_MAX: none */
    int equal;
    const char* compared; /* "decoded" or "stored" */
    cJSON* jpaths;        /* META/RPRT: JSON paths that differ, or NULL */
} payload_diff;

static payload_diff compare_payloads(const payload* pa, const payload* pb, uint32_t type)
{
    payload_diff d = {0, UINT64_MAX, 0, pa->decoded && pb->decoded ? "decoded" : "stored", NULL};
    const size_t common = pa->size < pb->size ? pa->size : pb->size;
    if (pa->data && pb->data) {
        for (size_t i = 0; i < common; ++i)
            if (pa->data[i] != pb->data[i]) {
                if (d.first == UINT64_MAX)
                    d.first = i;
                d.ndiff++;
            }
    }
    if (pa->size != pb->size) {
        d.ndiff += (uint64_t)(pa->size > pb->size ? pa->size - pb->size : pb->size - pa->size);
        if (d.first == UINT64_MAX)
            d.first = common;
    }
    d.equal = d.ndiff == 0 && pa->data && pb->data;
    if (!d.equal && pa->decoded && pb->decoded && (type == MESO_CHUNK_META || type == MESO_CHUNK_RPRT)) {
        cJSON* ja = cJSON_ParseWithLength((const char*)pa->data, pa->size);
        cJSON* jb = cJSON_ParseWithLength((const char*)pb->data, pb->size);
        if (ja && jb) {
            char path[512] = "";
            d.jpaths = cJSON_CreateArray();
            json_paths(ja, jb, path, sizeof(path), d.jpaths);
        }
        cJSON_Delete(ja);
        cJSON_Delete(jb);
    }
    return d;
}

/* Text: the payload line (and its JSON paths) and unreadable payloads. */
static void print_payload(diff_out* o, const side* sa, const side* sb, const payload* pa, const payload* pb,
                          const payload_diff* d)
{
    if (!d->equal) {
        text_label(o);
        printf("  %-18s %s bytes differ: %llu (sizes %zu -> %zu), first at offset %llu\n", "payload", d->compared,
               (unsigned long long)d->ndiff, pa->size, pb->size, (unsigned long long)d->first);
        if (d->jpaths && cJSON_GetArraySize(d->jpaths) > 0) {
            printf("  %-16s", "json");
            const cJSON* x;
            int k = 0;
            cJSON_ArrayForEach(x, d->jpaths) printf("%s%s", k++ ? ", " : " ", x->valuestring);
            fputc('\n', stdout);
        }
    }
    for (int s = 0; s < 2; ++s) {
        const payload* q = s ? pb : pa;
        if (q->r != MESO_OK) {
            text_label(o);
            printf("  %-18s %s: %s\n", "unreadable", s ? sb->path : sa->path, q->error);
        }
    }
}

/* JSON: the chunk's "payload" object (takes d->jpaths). */
static void payload_json(cJSON* jc, const payload* pa, const payload* pb, payload_diff* d)
{
    cJSON* jp = cJSON_AddObjectToObject(jc, "payload");
    cJSON_AddStringToObject(jp, "compared", d->compared);
    cJSON_AddBoolToObject(jp, "equal", d->equal);
    cJSON_AddNumberToObject(jp, "size_a", (double)pa->size);
    cJSON_AddNumberToObject(jp, "size_b", (double)pb->size);
    if (d->first == UINT64_MAX)
        cJSON_AddNullToObject(jp, "first_difference");
    else
        cJSON_AddNumberToObject(jp, "first_difference", (double)d->first);
    cJSON_AddNumberToObject(jp, "differing_bytes", (double)d->ndiff);
    if (d->jpaths) {
        cJSON_AddItemToObject(jp, "json_paths", d->jpaths);
        d->jpaths = NULL;
    }
    if (pa->r != MESO_OK)
        cJSON_AddStringToObject(jp, "error_a", pa->error);
    else
        cJSON_AddNullToObject(jp, "error_a");
    if (pb->r != MESO_OK)
        cJSON_AddStringToObject(jp, "error_b", pb->error);
    else
        cJSON_AddNullToObject(jp, "error_b");
}

/* Chunk counts by outcome. */
typedef struct diff_summary {
    int same, diff, only_a, only_b, invalid;
} diff_summary;

/* One matched pair: reported (text lines, or an entry of jchunks) and
 * counted. */
static void diff_chunk(side* sa, side* sb, pair pr, mi_format fmt, cJSON* jchunks, diff_summary* sum)
{
    const meso_chunk_info* ca = pr.a >= 0 ? meso_file_chunk(sa->f, (uint32_t)pr.a) : NULL;
    const meso_chunk_info* cb = pr.b >= 0 ? meso_file_chunk(sb->f, (uint32_t)pr.b) : NULL;
    const meso_chunk_info* c = ca ? ca : cb;
    char label[48], cc[5], text_label_buf[160];
    mi_chunk_label(c, label, sizeof(label));
    mi_fourcc(c->type, cc);
    cJSON* jc = jchunks ? chunk_json(jchunks, c, label, cc, pr) : NULL;
    if (!ca || !cb) {
        if (ca)
            sum->only_a++;
        else
            sum->only_b++;
        if (jc) {
            cJSON_AddStringToObject(jc, "status", ca ? "only_a" : "only_b");
            cJSON_AddArrayToObject(jc, "fields");
            cJSON_AddNullToObject(jc, "payload");
        } else {
            printf("%s  only in %s (chunk %lld)\n", label, ca ? sa->path : sb->path, (long long)(ca ? pr.a : pr.b));
        }
        return;
    }

    int label_printed = 0;
    snprintf(text_label_buf, sizeof(text_label_buf), "%s  chunk %lld -> %lld", label, (long long)pr.a,
             (long long)pr.b);
    diff_out o = {fmt, NULL, 0, text_label_buf, &label_printed};
    cJSON* jstatus = NULL;
    if (jc) {
        jstatus = cJSON_AddStringToObject(jc, "status", "same");
        o.fields = cJSON_AddArrayToObject(jc, "fields");
    }
    diff_fields(&o, sa, sb, pr, ca, cb);

    payload pa, pb;
    load_payloads(sa, sb, pr, &pa, &pb);
    for (int s = 0; s < 2; ++s) {
        const payload* q = s ? &pb : &pa;
        if (q->r != MESO_OK && q->r != MESO_ERR_UNSUPPORTED) {
            sum->invalid = 1;
            mi_warning("%s: %s", s ? sb->path : sa->path, q->error);
        }
    }
    payload_diff d = compare_payloads(&pa, &pb, c->type);
    if (!d.equal)
        o.count++;
    if (fmt == MI_FORMAT_TEXT)
        print_payload(&o, sa, sb, &pa, &pb, &d);
    if (jc) {
        payload_json(jc, &pa, &pb, &d);
        if (o.count)
            cJSON_SetValuestring(jstatus, "different");
    }
    cJSON_Delete(d.jpaths);
    free(pa.owned);
    free(pb.owned);
    if (o.count)
        sum->diff++;
    else
        sum->same++;
}

int mesoinspect_diff(int argc, char** argv)
{
    side sa = {NULL, NULL}, sb = {NULL, NULL};
    mi_format fmt = MI_FORMAT_TEXT;
    int code = parse_args(argc, argv, &sa, &sb, &fmt);
    if (code >= 0)
        return code;
    code = mi_open_or_report(sa.path, &sa.f);
    if (code != MESO_EXIT_OK)
        return code;
    code = mi_open_or_report(sb.path, &sb.f);
    if (code != MESO_EXIT_OK) {
        meso_file_close(sa.f);
        return code;
    }

    cJSON* doc = NULL;
    cJSON* jchunks = NULL;
    int header_label = 0;
    diff_out hdr = {fmt, NULL, 0, "header", &header_label};
    if (fmt != MI_FORMAT_TEXT) {
        doc = cJSON_CreateObject();
        cJSON_AddStringToObject(doc, "a", sa.path);
        cJSON_AddStringToObject(doc, "b", sb.path);
        hdr.fields = cJSON_AddArrayToObject(doc, "header");
        jchunks = cJSON_AddArrayToObject(doc, "chunks");
    } else {
        printf("--- %s\n+++ %s\n", sa.path, sb.path);
    }

    /* header */
    uint16_t amaj, amin, bmaj, bmin;
    meso_file_version(sa.f, &amaj, &amin);
    meso_file_version(sb.f, &bmaj, &bmin);
    char va[16], vb[16];
    snprintf(va, sizeof(va), "%u.%u", amaj, amin);
    snprintf(vb, sizeof(vb), "%u.%u", bmaj, bmin);
    field_str(&hdr, "version", va, vb);
    field_num(&hdr, "file_size", (double)meso_file_size(sa.f), (double)meso_file_size(sb.f));
    field_num(&hdr, "chunk_count", meso_file_chunk_count(sa.f), meso_file_chunk_count(sb.f));

    size_t np = 0;
    pair* pairs = match_chunks(&sa, &sb, &np);
    if (!pairs) {
        mi_error("out of memory");
        cJSON_Delete(doc);
        meso_file_close(sa.f);
        meso_file_close(sb.f);
        return MESO_EXIT_INTERNAL;
    }
    diff_summary sum = {0, 0, 0, 0, 0};
    for (size_t p = 0; p < np; ++p)
        diff_chunk(&sa, &sb, pairs[p], fmt, jchunks, &sum);
    free(pairs);

    const int identical = hdr.count == 0 && sum.diff == 0 && sum.only_a == 0 && sum.only_b == 0;
    if (doc) {
        cJSON_AddBoolToObject(doc, "identical", identical);
        cJSON* js = cJSON_AddObjectToObject(doc, "summary");
        cJSON_AddNumberToObject(js, "same", sum.same);
        cJSON_AddNumberToObject(js, "different", sum.diff);
        cJSON_AddNumberToObject(js, "only_a", sum.only_a);
        cJSON_AddNumberToObject(js, "only_b", sum.only_b);
        mi_print_json(doc, fmt);
        cJSON_Delete(doc);
    } else if (identical) {
        printf("%s and %s are identical in content (%d chunks)\n", sa.path, sb.path, sum.same);
    } else {
        printf("%s and %s differ: %d chunk%s, %d only in %s, %d only in %s, %d same%s\n", sa.path, sb.path,
               sum.diff, sum.diff == 1 ? " differs" : "s differ", sum.only_a, sa.path, sum.only_b, sb.path, sum.same,
               hdr.count ? "; header differs" : "");
    }
    meso_file_close(sa.f);
    meso_file_close(sb.f);
    return mi_finish_stdout(sum.invalid ? MESO_EXIT_INVALID : identical ? MESO_EXIT_OK : MESO_EXIT_DIFFERENT);
}
