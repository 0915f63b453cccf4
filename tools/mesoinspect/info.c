/*
 * info.c — `mesoinspect info FILE [--format text|json|mini-json]`: header,
 * objects (OBJT, with MESH counts and levels of detail), every chunk with its
 * recomputed CRC32C, and the META and RPRT JSON. Schema: schema/info.schema.json.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "inspect.h"
#include "meso_layout.h"

static const char* const usage_info =
    "Usage: mesoinspect info FILE [--format text|json|mini-json]\n"
    "\n"
    "Print the header, the objects (OBJT records with their MESH counts), each\n"
    "object's levels of detail (lod, form, error, triangles, bytes, prefix bytes), every\n"
    "chunk (type, flags, object, lod, encoding, element type, offset, stored and\n"
    "decoded size, CRC32C recomputed: ok or BAD), the bake metadata (META) and\n"
    "the quality report (RPRT).\n"
    "\n"
    "  --format FMT   text (default), json or mini-json (one line)\n"
    "  -h, --help     this help\n"
    "\n"
    "Exit codes: 0 printed, 2 I/O failure, 3 the file is not a valid .meso file.\n";

typedef struct info_state {
    const char* path;
    meso_file* f;
    mi_format fmt;
    cJSON* warnings; /* array of strings */
} info_state;

static void warn(info_state* s, const char* msg)
{
    mi_warning("%s: %s", s->path, msg);
    cJSON_AddItemToArray(s->warnings, cJSON_CreateString(msg));
}

/* CRC32C status of chunk i: 1 ok, 0 bad, -1 unknown (no view). */
static int crc_status(const meso_file* f, uint32_t i)
{
    const meso_chunk_info* c = meso_file_chunk(f, i);
    const uint8_t* p = mi_stored(f, i);
    if (!c || !p || c->stored_size > SIZE_MAX)
        return -1;
    return meso_crc32c(0, p, (size_t)c->stored_size) == c->crc32c;
}

/* The first file-wide JSON chunk of `type` (META / RPRT), parsed; NULL when
 * absent or unreadable (with a warning). */
static cJSON* read_json_chunk(info_state* s, uint32_t type)
{
    int32_t idx = meso_file_find(s->f, type, UINT32_MAX, UINT16_MAX);
    if (idx < 0)
        return NULL;
    char cc[5], msg[400];
    mi_fourcc(type, cc);
    uint8_t* data;
    size_t size;
    meso_error err;
    memset(&err, 0, sizeof(err));
    meso_result r = mi_read_decoded(s->f, (uint32_t)idx, &data, &size, &err);
    if (r != MESO_OK) {
        char line[300];
        mi_format_issue(&err, line, sizeof(line));
        snprintf(msg, sizeof(msg), "%s chunk %d is unreadable: %s", cc, (int)idx, line);
        warn(s, msg);
        return NULL;
    }
    cJSON* j = cJSON_ParseWithLength((const char*)data, size);
    free(data);
    if (!j) {
        snprintf(msg, sizeof(msg), "%s chunk %d: JSON not understood by cJSON", cc, (int)idx);
        warn(s, msg);
    }
    return j;
}

/* Objects from the OBJT chunk; *count records in a malloc'd array. */
static meso_object_record* read_objects(info_state* s, uint32_t* count)
{
    *count = 0;
    int32_t idx = meso_file_find(s->f, MESO_CHUNK_OBJT, UINT32_MAX, UINT16_MAX);
    if (idx < 0)
        return NULL;
    uint8_t* data;
    size_t size;
    meso_error err;
    memset(&err, 0, sizeof(err));
    meso_result r = mi_read_decoded(s->f, (uint32_t)idx, &data, &size, &err);
    if (r != MESO_OK) {
        char line[300], msg[400];
        mi_format_issue(&err, line, sizeof(line));
        snprintf(msg, sizeof(msg), "OBJT chunk %d is unreadable: %s", (int)idx, line);
        warn(s, msg);
        return NULL;
    }
    uint32_t n = (uint32_t)(size / 64u);
    meso_object_record* recs = calloc(n ? n : 1, sizeof(*recs));
    if (recs)
        for (uint32_t i = 0; i < n; ++i)
            meso_object_record_decode(data + 64u * i, &recs[i]);
    free(data);
    *count = recs ? n : 0;
    return recs;
}

/* The finest-lod MESH chunk of `object`, or -1. */
static int32_t object_mesh(const meso_file* f, uint32_t object)
{
    int32_t best = -1;
    for (uint32_t i = 0; i < meso_file_chunk_count(f); ++i) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        if (c->type == MESO_CHUNK_MESH && c->object == object &&
            (best < 0 || c->lod < meso_file_chunk(f, (uint32_t)best)->lod))
            best = (int32_t)i;
    }
    return best;
}

static int mesh_stats(const meso_file* f, int32_t idx, mi_mesh_stats* st)
{
    if (idx < 0)
        return 0;
    const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)idx);
    return mi_mesh_header(mi_stored(f, (uint32_t)idx), (size_t)(c->stored_size < 64 ? c->stored_size : 64), st);
}

/* The levels of object `id`, finest first (meso_file_levels: one level for
 * an object without LODS records); NULL with *n = 0 and a warning when the
 * LODS chunk cannot be read. */
static meso_level_info* object_levels(info_state* s, uint32_t id, uint32_t* n)
{
    *n = 0;
    meso_error err = {0};
    uint32_t count = 0;
    meso_level_info* lv = NULL;
    meso_result r = meso_file_levels(s->f, id, NULL, 0, &count, &err);
    if (r == MESO_OK) {
        lv = calloc(count ? count : 1, sizeof(*lv));
        r = lv ? meso_file_levels(s->f, id, lv, count, &count, &err) : MESO_ERR_OUT_OF_MEMORY;
    }
    if (r != MESO_OK) {
        char msg[400];
        snprintf(msg, sizeof(msg), "levels of object %u: %s", id, err.message[0] ? err.message : meso_result_string(r));
        warn(s, msg);
        free(lv);
        return NULL;
    }
    *n = count;
    return lv;
}

/* The part levels of object `id` (FORMAT.md §7.11), by part then lod;
 * NULL with *n = 0 for an object without parts, and with a warning when
 * its PRTS chunk cannot be read. *parts and *pairs get the counts. */
static meso_part_level* object_parts(info_state* s, uint32_t id, uint32_t* n, uint32_t* parts, uint32_t* pairs)
{
    *n = *parts = *pairs = 0;
    meso_error err = {0};
    uint32_t nl = 0, np = 0, ne = 0;
    meso_part_level* pl = NULL;
    meso_result r = meso_file_parts(s->f, id, NULL, 0, &nl, &np, NULL, 0, &ne, &err);
    if (r == MESO_OK && nl) {
        pl = calloc(nl, sizeof(*pl));
        r = pl ? meso_file_parts(s->f, id, pl, nl, &nl, &np, NULL, 0, &ne, &err) : MESO_ERR_OUT_OF_MEMORY;
    }
    if (r != MESO_OK) {
        char msg[400];
        snprintf(msg, sizeof(msg), "parts of object %u: %s", id, err.message[0] ? err.message : meso_result_string(r));
        warn(s, msg);
        free(pl);
        return NULL;
    }
    *n = nl;
    *parts = np;
    *pairs = ne;
    return pl;
}

static const char* form_name(uint16_t form)
{
    return form == MESO_LEVEL_NATIVE ? "native" : form == MESO_LEVEL_MESH ? "mesh" : "unknown";
}

/* Triangles of the MESH chunk level `lod` of `id` draws, or -1 when none. */
static int64_t level_triangles(const meso_file* f, uint32_t id, uint16_t lod)
{
    mi_mesh_stats st;
    return mesh_stats(f, meso_file_find_level(f, MESO_CHUNK_MESH, id, lod), &st) ? (int64_t)(st.index_count / 3)
                                                                                : -1;
}

static cJSON* vec3(const float v[3])
{
    cJSON* a = cJSON_CreateArray();
    for (int k = 0; k < 3; ++k)
        cJSON_AddItemToArray(a, cJSON_CreateNumber((double)v[k]));
    return a;
}

static void flags_text(uint32_t flags, char* dst, size_t n)
{
    if (flags == 0)
        snprintf(dst, n, "-");
    else if (flags == MESO_CHUNK_FLAG_REQUIRED)
        snprintf(dst, n, "REQUIRED");
    else if (flags & MESO_CHUNK_FLAG_REQUIRED)
        snprintf(dst, n, "REQUIRED|0x%x", flags & ~MESO_CHUNK_FLAG_REQUIRED);
    else
        snprintf(dst, n, "0x%x", flags);
}

static uint32_t ld_u32(const uint8_t* p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float ld_f32(const uint8_t* p)
{
    uint32_t u = ld_u32(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}

/* One line about a frusta object's FSEG (end kinds, caps, relief) or BALL
 * chunk, a cells object's CELL record, or a shell's ANIM record (its
 * frames and their times, FORMAT.md §7.2), for someone checking what a bake made of a skeleton. Nothing when
 * the chunk is not raw, its CRC fails or its size is not whole records. */
static void frusta_detail(const meso_file* f, uint32_t i)
{
    const meso_chunk_info* c = meso_file_chunk(f, i);
    const uint8_t* p = mi_stored(f, i);
    if (!p || c->encoding != MESO_ENCODING_RAW || crc_status(f, i) <= 0)
        return;
    if (c->type == MESO_CHUNK_FSEG && c->stored_size % MESO_FSEG_RECORD_SIZE == 0) {
        uint64_t n = c->stored_size / MESO_FSEG_RECORD_SIZE, kinds[3] = {0, 0, 0}, caps = 0, roots = 0, relief = 0;
        double dmax = 0;
        for (uint64_t k = 0; k < n; ++k) {
            const uint8_t* r = p + k * MESO_FSEG_RECORD_SIZE;
            uint32_t fl = ld_u32(r + MESO_FSEG_OFF_FLAGS);
            for (int e = 0; e < 2; ++e) {
                uint32_t kind = (fl >> (e ? MESO_FSEG_KIND1_SHIFT : MESO_FSEG_KIND0_SHIFT)) & 3u;
                kinds[kind < 3 ? kind : 0]++;
            }
            caps += ((fl & MESO_FSEG_CAP0) != 0) + ((fl & MESO_FSEG_CAP1) != 0);
            roots += (int32_t)ld_u32(r + MESO_FSEG_OFF_ALIGN_FROM) < 0;
            double d = ld_f32(r + MESO_FSEG_OFF_RELIEF_DEPTH);
            relief += d > 0;
            dmax = d > dmax ? d : dmax;
        }
        printf("  chunk %u FSEG: %llu frusta; ends: %llu tip, %llu joint, %llu ball; %llu caps; %llu u-frame roots; "
               "relief on %llu (depth up to %g)\n",
               i, (unsigned long long)n, (unsigned long long)kinds[0], (unsigned long long)kinds[1],
               (unsigned long long)kinds[2], (unsigned long long)caps, (unsigned long long)roots,
               (unsigned long long)relief, dmax);
    } else if (c->type == MESO_CHUNK_BALL && c->stored_size % MESO_BALL_RECORD_SIZE == 0) {
        uint64_t n = c->stored_size / MESO_BALL_RECORD_SIZE;
        double lo = n ? ld_f32(p + MESO_BALL_OFF_RADIUS) : 0, hi = lo;
        for (uint64_t k = 0; k < n; ++k) {
            double r = ld_f32(p + k * MESO_BALL_RECORD_SIZE + MESO_BALL_OFF_RADIUS);
            lo = r < lo ? r : lo;
            hi = r > hi ? r : hi;
        }
        printf("  chunk %u BALL: %llu balls, radius %g to %g\n", i, (unsigned long long)n, lo, hi);
    } else if (c->type == MESO_CHUNK_ANIM && c->stored_size == MESO_ANIM_RECORD_SIZE) {
        meso_anim_record a;
        meso_anim_record_decode(p, &a);
        printf("  chunk %u ANIM: %u frames at %g fps (%g s), frame k at t = %g + k/%g s, %s; in TXFR/DSFR of "
               "object %u\n",
               i, a.frame_count, (double)a.fps, a.fps > 0 ? a.frame_count / (double)a.fps : 0.0, (double)a.time0,
               (double)a.fps, a.flags & MESO_ANIM_FLAG_LOOP ? "looped" : "held at the end", c->object);
    } else if (c->type == MESO_CHUNK_CELL && c->stored_size == MESO_CELL_RECORD_SIZE) {
        /* the cells object's grid (FORMAT.md §7.8) */
        const uint32_t R = ld_u32(p + MESO_CELL_OFF_TILE_RES);
        const uint64_t mixed = ld_u32(p + MESO_CELL_OFF_MIXED_TILES) |
                               (uint64_t)ld_u32(p + MESO_CELL_OFF_MIXED_TILES + 4) << 32;
        printf("  chunk %u CELL: %ux%ux%u tiles of %u^3 voxels (voxel %g, origin %g,%g,%g); %u split cells of %u "
               "cells per tile; %llu mixed tiles\n",
               i, ld_u32(p + MESO_CELL_OFF_TILES), ld_u32(p + MESO_CELL_OFF_TILES + 4),
               ld_u32(p + MESO_CELL_OFF_TILES + 8), R, ld_f32(p + MESO_CELL_OFF_VOXEL_SIZE),
               ld_f32(p + MESO_CELL_OFF_ORIGIN), ld_f32(p + MESO_CELL_OFF_ORIGIN + 4),
               ld_f32(p + MESO_CELL_OFF_ORIGIN + 8), ld_u32(p + MESO_CELL_OFF_SPLIT_COUNT),
               ld_u32(p + MESO_CELL_OFF_CELL_COUNT), (unsigned long long)mixed);
    }
}

static void print_text(info_state* s, const meso_object_record* objs, uint32_t nobj, cJSON* meta, cJSON* rprt)
{
    meso_file* f = s->f;
    uint16_t major, minor;
    meso_file_version(f, &major, &minor);
    const uint32_t n = meso_file_chunk_count(f);
    printf("File:     %s\n", s->path);
    printf("Format:   %u.%u\n", major, minor);
    printf("Size:     %llu bytes\n", (unsigned long long)meso_file_size(f));
    printf("Chunks:   %u\n", n);

    printf("\nObjects (%u):\n", nobj);
    if (nobj) {
        mi_table t;
        mi_table_init(&t, 8, (1u << 0) | (1u << 5) | (1u << 6));
        const char* head[8] = {"id", "kind", "name", "bbox_min", "bbox_max", "vertices", "indices", "mesh"};
        mi_table_row(&t, head);
        for (uint32_t i = 0; i < nobj; ++i) {
            const meso_object_record* o = &objs[i];
            char id[16], lo[64], hi[64], nv[16] = "-", ni[16] = "-", mesh[64] = "-";
            snprintf(id, sizeof(id), "%u", o->id);
            snprintf(lo, sizeof(lo), "%g,%g,%g", (double)o->bbox_min[0], (double)o->bbox_min[1],
                     (double)o->bbox_min[2]);
            snprintf(hi, sizeof(hi), "%g,%g,%g", (double)o->bbox_max[0], (double)o->bbox_max[1],
                     (double)o->bbox_max[2]);
            int32_t mi = object_mesh(f, o->id);
            mi_mesh_stats st;
            if (mesh_stats(f, mi, &st)) {
                const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)mi);
                snprintf(nv, sizeof(nv), "%u", st.vertex_count);
                snprintf(ni, sizeof(ni), "%u", st.index_count);
                snprintf(mesh, sizeof(mesh), "chunk %d, lod %u, %s%s%s", (int)mi, (unsigned)c->lod,
                         mi_encoding_name(c->encoding), (st.attributes & MESO_MESH_ATTR_NORMALS) ? ", normals" : "",
                         (st.attributes & MESO_MESH_ATTR_UVS) ? ", uvs" : "");
            }
            const char* row[8] = {id, mi_kind_name(o->kind), o->name[0] ? o->name : "-", lo, hi, nv, ni, mesh};
            mi_table_row(&t, row);
        }
        mi_table_print(&t, 2);
        mi_table_free(&t);

        /* Levels of detail: one line per object and level (FORMAT.md §7.10). */
        printf("\nLevels:\n");
        mi_table_init(&t, 8, (1u << 0) | (1u << 1) | (1u << 3) | (1u << 4) | (1u << 5) | (1u << 6));
        const char* lhead[8] = {"object", "lod", "form", "error", "triangles", "bytes", "prefix_bytes", "colours"};
        mi_table_row(&t, lhead);
        for (uint32_t i = 0; i < nobj; ++i) {
            uint32_t nl = 0;
            meso_level_info* lv = object_levels(s, objs[i].id, &nl);
            for (uint32_t k = 0; k < nl; ++k) {
                char id[16], lod[16], err[32], tri[24] = "-", bytes[24], prefix[24];
                snprintf(id, sizeof(id), "%u", objs[i].id);
                snprintf(lod, sizeof(lod), "%u", (unsigned)lv[k].rec.lod);
                snprintf(err, sizeof(err), "%.6g", (double)lv[k].rec.error);
                const int64_t nt = level_triangles(f, objs[i].id, lv[k].rec.lod);
                if (nt >= 0)
                    snprintf(tri, sizeof(tri), "%lld", (long long)nt);
                snprintf(bytes, sizeof(bytes), "%llu", (unsigned long long)lv[k].bytes);
                snprintf(prefix, sizeof(prefix), "%llu", (unsigned long long)lv[k].prefix_bytes);
                /* a stand-in's vertex colours (FORMAT.md 7.3 VCOL): "-" for none or a native level */
                const int32_t vc = lv[k].rec.form == MESO_LEVEL_MESH
                                       ? meso_file_find_vertex_colours(f, objs[i].id, lv[k].rec.lod)
                                       : -1;
                char colours[24] = "-";
                if (vc >= 0)
                    snprintf(colours, sizeof(colours), "VCOL %d", (int)vc);
                const char* row[8] = {id, lod, form_name(lv[k].rec.form), err, tri, bytes, prefix, colours};
                mi_table_row(&t, row);
            }
            free(lv);
        }
        mi_table_print(&t, 2);
        mi_table_free(&t);
    }
    for (uint32_t i = 0; i < nobj; ++i) {
        uint32_t nl = 0, np = 0, ne = 0;
        meso_part_level* pl = object_parts(s, objs[i].id, &nl, &np, &ne);
        if (!pl)
            continue;
        /* One line per part: its levels' errors and bytes. */
        printf("\nParts of object %u (FORMAT.md 7.11): %u parts, %u part levels, %u neighbour pairs\n", objs[i].id, np,
               nl, ne);
        for (uint32_t k = 0; k < nl;) {
            uint32_t e = k;
            while (e < nl && pl[e].rec.object == pl[k].rec.object)
                ++e;
            printf("  part %u: %u levels", pl[k].rec.object, e - k);
            if (pl[k].triangle_count) /* a shell's: lod 0 its prisms, lods 1.. stand-in patches */
                printf(" (lod 0: %u prisms, list entries %u..%u; then stand-in patches)", pl[k].triangle_count,
                       pl[k].first_triangle, pl[k].first_triangle + pl[k].triangle_count - 1);
            printf("; error");
            for (uint32_t j = k; j < e; ++j)
                printf(" %.4g", (double)pl[j].rec.error);
            printf("; bytes");
            for (uint32_t j = k; j < e; ++j)
                printf(" %llu", (unsigned long long)pl[j].bytes);
            printf("\n");
            k = e;
        }
        free(pl);
    }

    printf("\nChunks (%u):\n", n);
    if (n) {
        mi_table t;
        /* right-align the numeric columns */
        mi_table_init(&t, 14, (1u << 0) | (1u << 3) | (1u << 4) | (1u << 7) | (1u << 9) | (1u << 10) | (1u << 11));
        const char* head[14] = {"#",     "type",  "flags", "object", "lod",    "encoding", "dtype",
                                "comp",  "dims",  "offset", "stored", "decoded", "crc32c",  "crc"};
        mi_table_row(&t, head);
        for (uint32_t i = 0; i < n; ++i) {
            const meso_chunk_info* c = meso_file_chunk(f, i);
            char idx[16], cc[5], fl[32], obj[16], lod[16], comp[16], dims[48], off[24], st[24], dec[24], crc[16];
            snprintf(idx, sizeof(idx), "%u", i);
            mi_fourcc(c->type, cc);
            flags_text(c->flags, fl, sizeof(fl));
            snprintf(obj, sizeof(obj), "%u", c->object);
            snprintf(lod, sizeof(lod), "%u", (unsigned)c->lod);
            snprintf(comp, sizeof(comp), "%u", (unsigned)c->components);
            snprintf(dims, sizeof(dims), "%ux%ux%u", c->dims[0], c->dims[1], c->dims[2]);
            snprintf(off, sizeof(off), "%llu", (unsigned long long)c->offset);
            snprintf(st, sizeof(st), "%llu", (unsigned long long)c->stored_size);
            snprintf(dec, sizeof(dec), "%llu", (unsigned long long)c->decoded_size);
            snprintf(crc, sizeof(crc), "%08x", c->crc32c);
            const int ok = crc_status(f, i);
            const char* row[14] = {idx, cc,   fl,  obj, lod, mi_encoding_name(c->encoding), mi_dtype_name(c->dtype),
                                   comp, dims, off, st,  dec, crc, ok < 0 ? "?" : ok ? "ok" : "BAD"};
            mi_table_row(&t, row);
        }
        mi_table_print(&t, 2);
        mi_table_free(&t);
        /* per-MESH (and frusta) detail lines */
        for (uint32_t i = 0; i < n; ++i) {
            const meso_chunk_info* c = meso_file_chunk(f, i);
            frusta_detail(f, i);
            mi_mesh_stats ms;
            if (c->type != MESO_CHUNK_MESH || !mesh_stats(f, (int32_t)i, &ms))
                continue;
            printf("  chunk %u MESH: %u vertices, %u indices (%u triangles), attributes%s%s%s", i, ms.vertex_count,
                   ms.index_count, ms.index_count / 3u, (ms.attributes & MESO_MESH_ATTR_POSITIONS) ? " positions" : "",
                   (ms.attributes & MESO_MESH_ATTR_NORMALS) ? " normals" : "",
                   (ms.attributes & MESO_MESH_ATTR_UVS) ? " uvs" : "");
            if (ms.quant_bits[0] || ms.quant_bits[1] || ms.quant_bits[2])
                printf(", quantised %u/%u/%u bits", ms.quant_bits[0], ms.quant_bits[1], ms.quant_bits[2]);
            fputc('\n', stdout);
        }
    }

    char* js;
    printf("\nMetadata (META):\n");
    if (meta && (js = cJSON_Print(meta)) != NULL) {
        printf("%s\n", js);
        cJSON_free(js);
    } else {
        printf("  (none)\n");
    }
    printf("\nReport (RPRT):\n");
    if (rprt && (js = cJSON_Print(rprt)) != NULL) {
        printf("%s\n", js);
        cJSON_free(js);
    } else {
        printf("  (none)\n");
    }
}

static cJSON* build_json(info_state* s, const meso_object_record* objs, uint32_t nobj, cJSON* meta, cJSON* rprt)
{
    meso_file* f = s->f;
    uint16_t major, minor;
    meso_file_version(f, &major, &minor);
    const uint32_t n = meso_file_chunk_count(f);
    cJSON* doc = cJSON_CreateObject();
    cJSON_AddStringToObject(doc, "file", s->path);
    cJSON* h = cJSON_AddObjectToObject(doc, "header");
    char ver[16];
    snprintf(ver, sizeof(ver), "%u.%u", major, minor);
    cJSON_AddStringToObject(h, "version", ver);
    cJSON_AddNumberToObject(h, "major", major);
    cJSON_AddNumberToObject(h, "minor", minor);
    cJSON_AddNumberToObject(h, "file_size", (double)meso_file_size(f));
    cJSON_AddNumberToObject(h, "chunk_count", n);

    cJSON* oa = cJSON_AddArrayToObject(doc, "objects");
    for (uint32_t i = 0; i < nobj; ++i) {
        const meso_object_record* o = &objs[i];
        cJSON* jo = cJSON_CreateObject();
        cJSON_AddNumberToObject(jo, "id", o->id);
        cJSON_AddNumberToObject(jo, "kind", o->kind);
        cJSON_AddStringToObject(jo, "kind_name", mi_kind_name(o->kind));
        cJSON_AddStringToObject(jo, "name", o->name);
        cJSON_AddItemToObject(jo, "bbox_min", vec3(o->bbox_min));
        cJSON_AddItemToObject(jo, "bbox_max", vec3(o->bbox_max));
        int32_t mi = object_mesh(f, o->id);
        mi_mesh_stats st;
        if (mesh_stats(f, mi, &st)) {
            cJSON* m = mi_mesh_stats_json(&st);
            const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)mi);
            cJSON_AddNumberToObject(m, "chunk", mi);
            cJSON_AddNumberToObject(m, "lod", c->lod);
            cJSON_AddStringToObject(m, "encoding", mi_encoding_name(c->encoding));
            cJSON_AddItemToObject(jo, "mesh", m);
        } else {
            cJSON_AddNullToObject(jo, "mesh");
        }
        cJSON* ja = cJSON_AddArrayToObject(jo, "levels");
        uint32_t nl = 0;
        meso_level_info* lv = object_levels(s, o->id, &nl);
        for (uint32_t k = 0; k < nl; ++k) {
            cJSON* jl = cJSON_CreateObject();
            cJSON_AddNumberToObject(jl, "lod", lv[k].rec.lod);
            cJSON_AddStringToObject(jl, "form", form_name(lv[k].rec.form));
            cJSON_AddNumberToObject(jl, "error", (double)lv[k].rec.error);
            cJSON_AddNumberToObject(jl, "bytes", (double)lv[k].bytes);
            cJSON_AddNumberToObject(jl, "prefix_bytes", (double)lv[k].prefix_bytes);
            /* the chunk of a stand-in's vertex colours (FORMAT.md 7.3), or null */
            const int32_t vc = lv[k].rec.form == MESO_LEVEL_MESH ? meso_file_find_vertex_colours(f, o->id, lv[k].rec.lod)
                                                                 : -1;
            if (vc >= 0)
                cJSON_AddNumberToObject(jl, "vertex_colours", vc);
            else
                cJSON_AddNullToObject(jl, "vertex_colours");
            cJSON_AddItemToObject(jl, "bbox_min", vec3(lv[k].rec.bbox_min));
            cJSON_AddItemToObject(jl, "bbox_max", vec3(lv[k].rec.bbox_max));
            const int64_t nt = level_triangles(f, o->id, lv[k].rec.lod);
            if (nt >= 0)
                cJSON_AddNumberToObject(jl, "triangles", (double)nt);
            else
                cJSON_AddNullToObject(jl, "triangles");
            cJSON_AddItemToArray(ja, jl);
        }
        free(lv);
        uint32_t np = 0, ne = 0;
        meso_part_level* pl = object_parts(s, o->id, &nl, &np, &ne);
        if (pl) {
            cJSON* jp = cJSON_AddObjectToObject(jo, "parts");
            cJSON_AddNumberToObject(jp, "count", np);
            cJSON_AddNumberToObject(jp, "neighbour_pairs", ne);
            cJSON* jl = cJSON_AddArrayToObject(jp, "levels");
            for (uint32_t k = 0; k < nl; ++k) {
                cJSON* e = cJSON_CreateObject();
                cJSON_AddNumberToObject(e, "part", pl[k].rec.object);
                cJSON_AddNumberToObject(e, "lod", pl[k].rec.lod);
                cJSON_AddNumberToObject(e, "error", (double)pl[k].rec.error);
                cJSON_AddNumberToObject(e, "bytes", (double)pl[k].bytes);
                cJSON_AddNumberToObject(e, "prefix_bytes", (double)pl[k].prefix_bytes);
                cJSON_AddNumberToObject(e, "chunk", pl[k].chunk);
                cJSON_AddStringToObject(e, "form", pl[k].rec.form == MESO_LEVEL_MESH ? "mesh" : "native");
                if (pl[k].triangle_count) { /* a shell part's prisms: PTRI entries */
                    cJSON_AddNumberToObject(e, "first_triangle", pl[k].first_triangle);
                    cJSON_AddNumberToObject(e, "triangle_count", pl[k].triangle_count);
                }
                if (pl[k].colours >= 0)
                    cJSON_AddNumberToObject(e, "colours_chunk", pl[k].colours);
                cJSON_AddItemToArray(jl, e);
            }
            free(pl);
        } else {
            cJSON_AddNullToObject(jo, "parts");
        }
        cJSON_AddItemToArray(oa, jo);
    }

    cJSON* ca = cJSON_AddArrayToObject(doc, "chunks");
    for (uint32_t i = 0; i < n; ++i) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        cJSON* jc = cJSON_CreateObject();
        char cc[5], crc[16];
        mi_fourcc(c->type, cc);
        cJSON_AddNumberToObject(jc, "index", i);
        cJSON_AddStringToObject(jc, "type", cc);
        cJSON_AddNumberToObject(jc, "flags", c->flags);
        cJSON_AddBoolToObject(jc, "required", (c->flags & MESO_CHUNK_FLAG_REQUIRED) != 0);
        cJSON_AddNumberToObject(jc, "object", c->object);
        cJSON_AddNumberToObject(jc, "lod", c->lod);
        cJSON_AddNumberToObject(jc, "encoding", c->encoding);
        cJSON_AddStringToObject(jc, "encoding_name", mi_encoding_name(c->encoding));
        cJSON_AddNumberToObject(jc, "dtype", c->dtype);
        cJSON_AddStringToObject(jc, "dtype_name", mi_dtype_name(c->dtype));
        cJSON_AddNumberToObject(jc, "components", c->components);
        cJSON* d = cJSON_AddArrayToObject(jc, "dims");
        for (int k = 0; k < 3; ++k)
            cJSON_AddItemToArray(d, cJSON_CreateNumber(c->dims[k]));
        cJSON_AddNumberToObject(jc, "offset", (double)c->offset);
        cJSON_AddNumberToObject(jc, "stored_size", (double)c->stored_size);
        cJSON_AddNumberToObject(jc, "decoded_size", (double)c->decoded_size);
        snprintf(crc, sizeof(crc), "%08x", c->crc32c);
        cJSON_AddStringToObject(jc, "crc32c", crc);
        const int ok = crc_status(f, i);
        if (ok < 0)
            cJSON_AddNullToObject(jc, "crc_ok");
        else
            cJSON_AddBoolToObject(jc, "crc_ok", ok);
        mi_mesh_stats ms;
        if (c->type == MESO_CHUNK_MESH && mesh_stats(f, (int32_t)i, &ms))
            cJSON_AddItemToObject(jc, "mesh", mi_mesh_stats_json(&ms));
        cJSON_AddItemToArray(ca, jc);
    }
    cJSON_AddItemToObject(doc, "meta", meta ? cJSON_Duplicate(meta, 1) : cJSON_CreateNull());
    cJSON_AddItemToObject(doc, "report", rprt ? cJSON_Duplicate(rprt, 1) : cJSON_CreateNull());
    cJSON_AddItemToObject(doc, "warnings", cJSON_Duplicate(s->warnings, 1));
    return doc;
}

int mesoinspect_info(int argc, char** argv)
{
    info_state s;
    memset(&s, 0, sizeof(s));
    int only_positional = 0;
    for (int i = 0; i < argc; ++i) {
        const char* a = argv[i];
        int k;
        if (!only_positional && mi_is_help(a)) {
            fputs(usage_info, stdout);
            return mi_finish_stdout(MESO_EXIT_OK);
        } else if (!only_positional && (k = mi_format_option(argc, argv, &i, &s.fmt)) != 0) {
            if (k < 0)
                return MESO_EXIT_USAGE;
        } else if (!only_positional && !strcmp(a, "--")) {
            only_positional = 1;
        } else if (!only_positional && a[0] == '-' && a[1] != '\0') {
            return mi_usage_error("unrecognized option '%s'", a);
        } else if (!s.path) {
            s.path = a;
        } else {
            return mi_usage_error("unexpected argument '%s'", a);
        }
    }
    if (!s.path) {
        fputs(usage_info, stderr);
        return MESO_EXIT_USAGE;
    }
    int code = mi_open_or_report(s.path, &s.f);
    if (code != MESO_EXIT_OK)
        return code;
    s.warnings = cJSON_CreateArray();
    uint32_t nobj = 0;
    meso_object_record* objs = read_objects(&s, &nobj);
    cJSON* meta = read_json_chunk(&s, MESO_CHUNK_META);
    cJSON* rprt = read_json_chunk(&s, MESO_CHUNK_RPRT);
    for (uint32_t i = 0; i < meso_file_chunk_count(s.f); ++i)
        if (crc_status(s.f, i) == 0) {
            char cc[5], msg[128];
            mi_fourcc(meso_file_chunk(s.f, i)->type, cc);
            snprintf(msg, sizeof(msg), "chunk %u (%s): payload CRC32C does not match the TOC", i, cc);
            warn(&s, msg);
        }
    if (s.fmt == MI_FORMAT_TEXT) {
        print_text(&s, objs, nobj, meta, rprt);
    } else {
        cJSON* doc = build_json(&s, objs, nobj, meta, rprt);
        mi_print_json(doc, s.fmt);
        cJSON_Delete(doc);
    }
    free(objs);
    cJSON_Delete(meta);
    cJSON_Delete(rprt);
    cJSON_Delete(s.warnings);
    meso_file_close(s.f);
    return mi_finish_stdout(MESO_EXIT_OK);
}
