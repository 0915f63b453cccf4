/*
 * mesoinspect — look inside .meso files with exactly the parser the runtime
 * uses (meso_format): header, objects and chunks (info), every issue
 * (validate), raw chunk bytes (dump), structural differences (diff), a
 * headless render (preview) and a glTF 2.0 copy for engines without libmeso
 * (export).
 *
 * One file per command (info.c, validate.c, dump.c, diff.c, preview.c,
 * export.c); this file has the dispatcher and the helpers they share
 * (inspect.h).
 * CLI conventions: STYLE.md §8 (exit codes in cli_common.h).
 */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_output.h"
#include "inspect.h"
#include "mesh_chunk.h"
#include "meso_layout.h"

static const char* const usage_short =
    "Usage: mesoinspect <command> [options]\n"
    "\n"
    "Commands:\n"
    "  info      FILE                     header, objects, chunks, bake metadata\n"
    "  validate  [--full] FILE            report every format issue\n"
    "  dump      FILE CHUNK -o OUT        write one chunk's bytes\n"
    "  diff      A B                      compare two files chunk by chunk\n"
    "  preview   FILE -o OUT.png          render a preview image headlessly\n"
    "  export    FILE -o OUT.glb          write the objects as a glTF 2.0 binary\n"
    "\n"
    "Run 'mesoinspect --help' or 'mesoinspect <command> --help' for all options.\n";

static const char* const usage_full =
    "mesoinspect " MESO_VERSION_STRING " — look inside .meso files\n"
    "\n"
    "Usage: mesoinspect <command> [options]\n"
    "       mesoinspect --help | --version\n"
    "\n"
    "Commands:\n"
    "  info     FILE [--format text|json]          header, objects, chunks (with CRC32C\n"
    "                                              status), bake metadata and report\n"
    "  validate [--full] FILE [--format text|json] report every issue: the checks done\n"
    "                                              on open, and with --full every payload\n"
    "  dump     FILE CHUNK -o OUT [--stored]       write a chunk's decoded (or stored)\n"
    "                                              bytes; CHUNK is a TOC index or\n"
    "                                              TYPE[:OBJECT[:LOD]], e.g. MESH:1\n"
    "  diff     A B [--format text|json]           compare two files chunk by chunk\n"
    "  preview  FILE -o OUT.png [--size WxH]       render a preview image headlessly (EGL)\n"
    "           [--technique smooth|curved|tetra]  shell technique (default smooth)\n"
    "           [--cells first|reflect|refract]    cells mode (default first), with\n"
    "           [--bounces N] [--cell-step S]      bounces and the linear search step\n"
    "           [--yaw D] [--pitch D] [--zoom Z]   camera\n"
    "           [--api gl|gles]                    desktop OpenGL (default) or OpenGL ES 3.2\n"
    "           [--reference [--samples N]         shells, frusta and cells by the exact\n"
    "            [--level L]]                      CPU references instead (no EGL), at\n"
    "                                              level 0 or a native level L\n"
    "  export   FILE -o OUT.glb [--object ID]      every object (or one) as glTF 2.0 (.glb)\n"
    "           [--frusta-grid N]                  for engines without libmeso: meshes as\n"
    "                                              they are, shells as their base mesh with\n"
    "                                              baked normal and colour maps, cells in\n"
    "                                              their mean colour, frusta tessellated\n"
    "\n"
    "Output:\n"
    "  --format text        aligned text for humans (default)\n"
    "  --format json        one JSON document on stdout (schemas: tools/mesoinspect/schema/)\n"
    "  --format mini-json   the same JSON on one line\n"
    "\n"
    "Exit codes: 0 success, 1 command-line error, 2 I/O failure, 3 invalid input,\n"
    "            4 internal error, 5 not supported in this build, 7 diff found a difference.\n"
    "\n"
    "Files written by dump -o, preview -o and export -o appear complete or not at all\n"
    "(also on SIGINT, SIGTERM, SIGHUP). An output that is a symbolic link is written\n"
    "through to its target; a dangling link, directory, device, FIFO or socket is\n"
    "refused (exit 2).\n"
    "\n"
    "Run 'mesoinspect <command> --help' for the options of one command.\n";

/* >>diagnostics ----------------------------------------------------------- */

void mi_error(const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("mesoinspect error: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}

void mi_warning(const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("mesoinspect warning: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}

int mi_usage_error(const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("mesoinspect error: ", stderr);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputs("\nSee 'mesoinspect --help'.\n", stderr);
    return MESO_EXIT_USAGE;
}

/* >>options --------------------------------------------------------------- */

int mi_is_help(const char* a) { return !strcmp(a, "-h") || !strcmp(a, "--help"); }

int mi_format_option(int argc, char** argv, int* i, mi_format* out)
{
    const char* a = argv[*i];
    const char* v;
    if (!strncmp(a, "--format=", 9)) {
        v = a + 9;
    } else if (!strcmp(a, "--format")) {
        if (*i + 1 >= argc) {
            mi_usage_error("option '--format' needs a value (text, json or mini-json)");
            return -1;
        }
        v = argv[++*i];
    } else {
        return 0;
    }
    if (!strcmp(v, "text")) {
        *out = MI_FORMAT_TEXT;
    } else if (!strcmp(v, "json")) {
        *out = MI_FORMAT_JSON;
    } else if (!strcmp(v, "mini-json")) {
        *out = MI_FORMAT_MINI_JSON;
    } else {
        mi_usage_error("--format expects text, json or mini-json, got '%s'", v);
        return -1;
    }
    return 1;
}

/* >>files ----------------------------------------------------------------- */

meso_result mi_open(const char* path, meso_file** out, meso_error* err)
{
    const meso_decoder draco = meso_bake_draco_decoder(); /* copied by open */
    meso_open_desc desc;
    memset(&desc, 0, sizeof(desc));
    if (draco.decode_fn) {
        desc.decoders = &draco;
        desc.decoder_count = 1;
    }
    return meso_file_open_mmap(path, &desc, out, err);
}

void mi_format_issue(const meso_error* e, char* dst, size_t dst_size)
{
    char where[64] = "", chunk[32] = "";
    if (e->offset != UINT64_MAX)
        snprintf(where, sizeof(where), " at offset %llu", (unsigned long long)e->offset);
    if (e->chunk >= 0)
        snprintf(chunk, sizeof(chunk), " (chunk %d)", (int)e->chunk);
    snprintf(dst, dst_size, "error %u%s%s: %s", e->code, where, chunk,
             e->message[0] ? e->message : meso_result_string(e->result));
}

int mi_open_or_report(const char* path, meso_file** out)
{
    meso_error err;
    memset(&err, 0, sizeof(err));
    meso_result r = mi_open(path, out, &err);
    if (r == MESO_OK)
        return MESO_EXIT_OK;
    char line[400];
    mi_format_issue(&err, line, sizeof(line));
    mi_error("%s: %s", path, line);
    *out = NULL;
    return meso_exit_for(r);
}

const uint8_t* mi_stored(const meso_file* f, uint32_t index)
{
    const void* p = NULL;
    if (meso_file_chunk_view(f, index, &p, NULL) != MESO_OK)
        return NULL;
    return (const uint8_t*)p;
}

meso_result mi_read_decoded(meso_file* f, uint32_t index, uint8_t** out, size_t* size, meso_error* err)
{
    *out = NULL;
    *size = 0;
    const meso_chunk_info* c = meso_file_chunk(f, index);
    if (!c)
        return MESO_ERR_INVALID_ARG;
    if (c->decoded_size > SIZE_MAX - 16) {
        if (err) {
            memset(err, 0, sizeof(*err));
            err->result = MESO_ERR_UNSUPPORTED;
            err->code = MESO_ISSUE_API_TOO_LARGE;
            err->offset = c->offset;
            err->chunk = (int32_t)index;
            snprintf(err->message, sizeof(err->message), "chunk %u: %llu decoded bytes do not fit in memory", index,
                     (unsigned long long)c->decoded_size);
        }
        return MESO_ERR_UNSUPPORTED;
    }
    /* malloc is suitably aligned for meso_mesh_parse; +1 so 0 bytes still allocate */
    uint8_t* buf = malloc((size_t)c->decoded_size + 1);
    if (!buf) {
        if (err) {
            memset(err, 0, sizeof(*err));
            err->result = MESO_ERR_OUT_OF_MEMORY;
            err->code = MESO_ISSUE_API_MEMORY;
            err->offset = UINT64_MAX;
            err->chunk = (int32_t)index;
            snprintf(err->message, sizeof(err->message), "chunk %u: out of memory for %llu decoded bytes", index,
                     (unsigned long long)c->decoded_size);
        }
        return MESO_ERR_OUT_OF_MEMORY;
    }
    meso_result r = meso_file_read_chunk(f, index, buf, (size_t)c->decoded_size, err);
    if (r != MESO_OK) {
        free(buf);
        return r;
    }
    *out = buf;
    *size = (size_t)c->decoded_size;
    return MESO_OK;
}

/* >>objects --------------------------------------------------------------- */

meso_object_record* mi_all_records(meso_file* f, uint32_t* count, meso_result* r)
{
    meso_error err = {0};
    *count = 0;
    if ((*r = meso_file_objects(f, NULL, 0, count, &err)) == MESO_OK) {
        meso_object_record* recs = calloc(*count ? *count : 1, sizeof(*recs));
        if (!recs) {
            *r = MESO_ERR_OUT_OF_MEMORY;
            mi_error("out of memory");
            return NULL;
        }
        if ((*r = meso_file_objects(f, recs, *count, count, &err)) == MESO_OK)
            return recs;
        free(recs);
    }
    mi_error("%s", err.message);
    return NULL;
}

int mi_object_option(const char* v, unsigned long* id, const char** name)
{
    char* end = NULL;
    errno = 0;
    *name = NULL;
    *id = strtoul(v, &end, 10);
    /* all digits: an id; anything else ("3d.obj" too): a name */
    if (v[0] < '0' || v[0] > '9' || !end || *end) {
        *id = 0;
        *name = v; /* OBJT names are UTF-8, at most 31 bytes */
        if (!v[0] || strlen(v) > 31)
            return mi_usage_error("--object expects an id >= 1 or a name of 1..31 bytes, got '%s'", v);
    } else if (errno || *id == 0 || *id > UINT32_MAX) {
        return mi_usage_error("--object expects an object id >= 1, got '%s'", v);
    }
    return MESO_EXIT_OK;
}

int mi_object_by_name(const char* path, const char* name, unsigned long* id)
{
    meso_file* f = NULL;
    meso_error err;
    meso_result r = meso_file_open_path(path, NULL, &f, &err);
    if (r != MESO_OK) {
        mi_error("%s: %s", path, err.message);
        return meso_exit_for(r);
    }
    uint32_t count = 0;
    meso_object_record* recs = mi_all_records(f, &count, &r);
    meso_file_close(f);
    if (!recs)
        return meso_exit_for(r);
    *id = 0;
    for (uint32_t i = 0; i < count && !*id; ++i)
        if (!strcmp(recs[i].name, name))
            *id = recs[i].id;
    if (!*id) {
        fprintf(stderr, "mesoinspect error: --object: %s has no object named '%s'; its objects:", path, name);
        for (uint32_t i = 0; i < count; ++i)
            fprintf(stderr, "%s %u '%s'", i ? "," : "", recs[i].id, recs[i].name);
        fprintf(stderr, "\n");
    }
    free(recs);
    return *id ? MESO_EXIT_OK : MESO_EXIT_USAGE;
}

/* >>validation ------------------------------------------------------------ */

typedef struct full_issues {
    const char* path;
    size_t count;
    int code;
} full_issues;

static int print_issue(void* user, const meso_error* e)
{
    full_issues* p = user;
    char line[400];
    mi_format_issue(e, line, sizeof(line));
    mi_error("%s: %s", p->path, line);
    const int c = e->result == MESO_ERR_IO              ? MESO_EXIT_IO
                  : e->result == MESO_ERR_OUT_OF_MEMORY ? MESO_EXIT_INTERNAL
                                                        : MESO_EXIT_INVALID;
    if (p->code == MESO_EXIT_OK || c == MESO_EXIT_IO)
        p->code = c;
    p->count++;
    return 0;
}

int mi_validate_full(const char* path, const char* not_what)
{
    meso_file* f = NULL;
    int code = mi_open_or_report(path, &f);
    if (code != MESO_EXIT_OK)
        return code;
    full_issues p = {path, 0, MESO_EXIT_OK};
    meso_file_validate(f, MESO_CHECK_FULL, print_issue, &p);
    meso_file_close(f);
    if (p.count)
        mi_error("%s: %zu issue%s; not %s (see 'mesoinspect validate --full')", path, p.count,
                 p.count == 1 ? "" : "s", not_what);
    return p.code;
}

/* >>names ----------------------------------------------------------------- */

void mi_fourcc(uint32_t type, char out[5])
{
    for (int k = 0; k < 4; ++k) {
        unsigned char ch = (unsigned char)(type >> (8 * k));
        out[k] = (ch >= 0x20 && ch <= 0x7E) ? (char)ch : '?';
    }
    out[4] = '\0';
}

const char* mi_encoding_name(uint32_t encoding)
{
    switch (encoding) {
    case MESO_ENCODING_RAW: return "raw";
    case MESO_ENCODING_DRACO: return "draco";
    default: return "unknown";
    }
}

const char* mi_dtype_name(uint32_t dtype)
{
    static const char* const names[MESO_DTYPE_COUNT] = {"bytes", "u8", "u16", "u32", "i8", "i16", "i32", "f16", "f32"};
    return dtype < MESO_DTYPE_COUNT ? names[dtype] : "unknown";
}

const char* mi_kind_name(uint32_t kind)
{
    static const char* const names[MESO_OBJECT_KIND_COUNT] = {"invalid", "mesh", "shell", "cells", "frusta"};
    return kind < MESO_OBJECT_KIND_COUNT ? names[kind] : "unknown";
}

const char* mi_result_id(meso_result r)
{
    switch (r) {
    case MESO_OK: return "ok";
    case MESO_ERR_TRUNCATED: return "truncated";
    case MESO_ERR_BAD_MAGIC: return "bad_magic";
    case MESO_ERR_VERSION_TOO_NEW: return "version_too_new";
    case MESO_ERR_CORRUPT: return "corrupt";
    case MESO_ERR_OUT_OF_MEMORY: return "out_of_memory";
    case MESO_ERR_IO: return "io";
    case MESO_ERR_INVALID_ARG: return "invalid_arg";
    case MESO_ERR_GL: return "gl";
    case MESO_ERR_UNSUPPORTED: return "unsupported";
    case MESO_ERR_NOT_FOUND: return "not_found";
    case MESO_ERR_PENDING: return "pending";
    default: return "unknown";
    }
}

const char* mi_issue_name(uint32_t code)
{
    /* FORMAT.md §9; numbers are stable and only appended. */
    static const struct {
        uint32_t code;
        const char* name;
    } names[] = {
        {1001, "HDR_TRUNCATED"},     {1002, "HDR_MAGIC"},
        {1003, "HDR_TEXT_MODE"},     {1004, "HDR_7BIT"},
        {1005, "HDR_LEGACY"},        {1006, "HDR_TOO_NEW"},
        {1007, "HDR_CRC"},           {1008, "HDR_FLAGS"},
        {1009, "HDR_RESERVED"},      {1010, "HDR_TOC_OFFSET"},
        {1011, "HDR_TOC_ENTRY_SIZE"}, {1012, "HDR_FILE_SIZE_ALIGN"},
        {1013, "FILE_TRUNCATED"},    {1014, "FILE_TRAILING"},
        {2001, "TOC_TOO_MANY"},      {2002, "TOC_BOUNDS"},
        {2003, "TOC_CRC"},           {2004, "CHUNK_TYPE"},
        {2005, "CHUNK_FLAGS"},       {2006, "CHUNK_RESERVED"},
        {2007, "CHUNK_ALIGN"},       {2008, "CHUNK_BOUNDS"},
        {2009, "CHUNK_IN_TOC"},      {2010, "CHUNK_ORDER"},
        {2011, "CHUNK_OVERLAP"},     {2012, "CHUNK_EMPTY"},
        {2013, "CHUNK_ENCODING"},    {2014, "CHUNK_DTYPE"},
        {2015, "CHUNK_COMPONENTS"},  {2016, "CHUNK_DIMS"},
        {2017, "CHUNK_RAW_SIZE"},    {2018, "CHUNK_TYPED_SIZE"},
        {2019, "CHUNK_UNKNOWN_REQUIRED"}, {2020, "FILE_END"},
        {2021, "CHUNK_EXPANSION"},   {2022, "CHUNK_DECODED_LIMIT"},
        {3001, "PAYLOAD_CRC"},       {3002, "PAYLOAD_PADDING"},
        {3003, "ENCODING_UNSUPPORTED"}, {3004, "DECODE_FAILED"},
        {4001, "TYPE_ELEMENT"},      {4002, "TYPE_ENCODING"},
        {4003, "TYPE_OBJECT"},       {4101, "JSON_UTF8"},
        {4102, "JSON_SYNTAX"},       {4103, "JSON_DEPTH"},
        {4201, "OBJT_SIZE"},         {4202, "OBJT_ID"},
        {4203, "OBJT_DUPLICATE"},    {4204, "OBJT_KIND"},
        {4205, "OBJT_NAME"},         {4206, "OBJT_BBOX"},
        {4301, "MESH_SIZE"},         {4302, "MESH_ATTRIBUTES"},
        {4303, "MESH_COUNTS"},       {4304, "MESH_RESERVED"},
        {4305, "MESH_QUANT"},        {4306, "MESH_PRESENCE"},
        {4307, "MESH_ALIGN"},        {4308, "MESH_OVERLAP"},
        {4309, "MESH_BOUNDS"},       {4310, "MESH_TRAILING"},
        {4311, "MESH_INDEX"},        {4312, "MESH_VALUE"},
        {4401, "SKEL_SIZE"},
        {4402, "SKEL_PARENT"},       {4403, "SKEL_VALUE"},
        {4501, "FRUS_SIZE"},         {4502, "FRUS_VALUE"},
        {4601, "FSEG_SIZE"},         {4602, "FSEG_VALUE"},
        {4701, "BALL_SIZE"},         {4702, "BALL_VALUE"},
        {4801, "CELL_SIZE"},         {4802, "CELL_VALUE"},
        {4803, "CELL_CHUNKS"},       {4804, "CELL_TILE"},
        {4805, "CELL_SPLT"},         {4806, "CELL_MEMB"},
        {4901, "ANIM_SIZE"},         {4902, "ANIM_VALUE"},
        {4911, "CMAP_SIZE"},         {4912, "CMAP_VALUE"},
        {4921, "LODS_SIZE"},         {4922, "LODS_VALUE"},
        {4931, "PRTS_SIZE"},         {4932, "PRTS_VALUE"},
        {5001, "API_ARG"},           {5002, "API_BUFFER"},
        {5003, "API_MEMORY"},        {5004, "IO_OPEN"},
        {5005, "IO_READ"},           {5006, "IO_MMAP"},
        {5007, "IO_WRITE"},          {5008, "API_NO_VIEW"},
        {5009, "API_TOO_LARGE"},     {5010, "API_WRITER_LIMIT"},
        {5011, "IO_DESTINATION"},
        {6001, "OBJ_CHUNKS"},        {6002, "MESH_VCOL"},
        {6101, "SHELL_COUNT"},
        {6102, "SHELL_SDIR"},        {6103, "SHELL_STHK"},
        {6104, "SHELL_TEXTURE"},     {6105, "SHELL_ANIM"},
        {6106, "SHELL_COLOR"},
        {6201, "FRUSTA_COUNT"},
        {6202, "FRUSTA_NODE"},       {6203, "FRUSTA_AXIS"},
        {6204, "FRUSTA_RELF"},       {6205, "FRUSTA_COLR"},
        {6301, "CELLS_COLOUR_GRID"},
        {6401, "LEVELS"},            {6501, "PARTS"},
    };
    for (size_t i = 0; i < sizeof(names) / sizeof(names[0]); ++i)
        if (names[i].code == code)
            return names[i].name;
    return NULL;
}

void mi_chunk_label(const meso_chunk_info* c, char* dst, size_t dst_size)
{
    char cc[5];
    mi_fourcc(c->type, cc);
    snprintf(dst, dst_size, "%s:%u:%u", cc, c->object, (unsigned)c->lod);
}

/* >>MESH header ----------------------------------------------------------- */

static uint32_t ld32(const uint8_t* p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

int mi_mesh_header(const uint8_t* p, size_t n, mi_mesh_stats* out)
{
    memset(out, 0, sizeof(*out));
    if (!p || n < MESO_MESH_HDR_SIZE)
        return 0;
    out->vertex_count = ld32(p + MESO_MESH_OFF_VERTEX_COUNT);
    out->index_count = ld32(p + MESO_MESH_OFF_INDEX_COUNT);
    out->attributes = ld32(p + MESO_MESH_OFF_ATTRIBUTES);
    out->quant_bits[0] = p[MESO_MESH_OFF_QUANT_POSITION];
    out->quant_bits[1] = p[MESO_MESH_OFF_QUANT_NORMAL];
    out->quant_bits[2] = p[MESO_MESH_OFF_QUANT_UV];
    return 1;
}

cJSON* mi_mesh_stats_json(const mi_mesh_stats* s)
{
    cJSON* j = cJSON_CreateObject();
    cJSON_AddNumberToObject(j, "vertex_count", s->vertex_count);
    cJSON_AddNumberToObject(j, "index_count", s->index_count);
    cJSON_AddNumberToObject(j, "triangle_count", s->index_count / 3u);
    cJSON* a = cJSON_AddArrayToObject(j, "attributes");
    if (s->attributes & MESO_MESH_ATTR_POSITIONS)
        cJSON_AddItemToArray(a, cJSON_CreateString("positions"));
    if (s->attributes & MESO_MESH_ATTR_NORMALS)
        cJSON_AddItemToArray(a, cJSON_CreateString("normals"));
    if (s->attributes & MESO_MESH_ATTR_UVS)
        cJSON_AddItemToArray(a, cJSON_CreateString("uvs"));
    cJSON* q = cJSON_AddObjectToObject(j, "quant_bits");
    cJSON_AddNumberToObject(q, "position", s->quant_bits[0]);
    cJSON_AddNumberToObject(q, "normal", s->quant_bits[1]);
    cJSON_AddNumberToObject(q, "uv", s->quant_bits[2]);
    return j;
}

/* >>output ---------------------------------------------------------------- */

int mi_output_failed(const meso_error* e, meso_result r)
{
    char line[400];
    mi_format_issue(e, line, sizeof(line));
    mi_error("%s", line);
    cli_outputs_discard();
    return meso_exit_for(r);
}

int mi_check_output(const char* path)
{
    meso_error err;
    memset(&err, 0, sizeof(err));
    meso_result r = meso_output_check(path, &err);
    return r == MESO_OK ? MESO_EXIT_OK : mi_output_failed(&err, r);
}

int mi_stage_output(const char* path, meso_output** out)
{
    meso_error err;
    memset(&err, 0, sizeof(err));
    meso_result r = cli_output_stage(path, out, &err);
    return r == MESO_OK ? MESO_EXIT_OK : mi_output_failed(&err, r);
}

int mi_publish_outputs(void)
{
    meso_error err;
    memset(&err, 0, sizeof(err));
    meso_result r = cli_outputs_publish(&err);
    return r == MESO_OK ? MESO_EXIT_OK : mi_output_failed(&err, r);
}

void mi_print_json(const cJSON* doc, mi_format fmt)
{
    char* s = fmt == MI_FORMAT_MINI_JSON ? cJSON_PrintUnformatted(doc) : cJSON_Print(doc);
    if (s) {
        fputs(s, stdout);
        fputc('\n', stdout);
        cJSON_free(s);
    }
}

int mi_finish_stdout(int code)
{
    if (fflush(stdout) != 0 || ferror(stdout)) {
        mi_error("cannot write to standard output");
        return MESO_EXIT_IO;
    }
    return code;
}

void mi_table_init(mi_table* t, int cols, unsigned right_align)
{
    memset(t, 0, sizeof(*t));
    t->cols = cols;
    t->right_align = right_align;
}

static char* dup_str(const char* s)
{
    size_t n = strlen(s) + 1;
    char* d = malloc(n);
    if (d)
        memcpy(d, s, n);
    return d;
}

void mi_table_row(mi_table* t, const char* const* cells)
{
    if (t->rows == t->cap) {
        int cap = t->cap ? 2 * t->cap : 16;
        char** c = realloc(t->cells, (size_t)cap * (size_t)t->cols * sizeof(char*));
        if (!c)
            return;
        t->cells = c;
        t->cap = cap;
    }
    for (int k = 0; k < t->cols; ++k)
        t->cells[t->rows * t->cols + k] = dup_str(cells[k] ? cells[k] : "");
    t->rows++;
}

void mi_table_print(const mi_table* t, int indent)
{
    size_t w[32] = {0};
    const int cols = t->cols < 32 ? t->cols : 32;
    for (int r = 0; r < t->rows; ++r)
        for (int k = 0; k < cols; ++k) {
            const char* s = t->cells[r * t->cols + k];
            size_t n = s ? strlen(s) : 0;
            if (n > w[k])
                w[k] = n;
        }
    for (int r = 0; r < t->rows; ++r) {
        printf("%*s", indent, "");
        for (int k = 0; k < cols; ++k) {
            const char* s = t->cells[r * t->cols + k];
            if (!s)
                s = "";
            const int width = (int)w[k];
            const int last = k == cols - 1;
            if (t->right_align & (1u << k))
                printf("%*s", width, s);
            else if (last)
                fputs(s, stdout);
            else
                printf("%-*s", width, s);
            if (!last)
                fputs("  ", stdout);
        }
        fputc('\n', stdout);
    }
}

void mi_table_free(mi_table* t)
{
    for (int i = 0; i < t->rows * t->cols; ++i)
        free(t->cells[i]);
    free(t->cells);
    memset(t, 0, sizeof(*t));
}

/* >>main ------------------------------------------------------------------ */

int main(int argc, char** argv)
{
    if (argc < 2) {
        fputs(usage_short, stderr);
        return MESO_EXIT_USAGE;
    }
    cli_signals_install();
    const char* cmd = argv[1];
    if (mi_is_help(cmd)) {
        fputs(usage_full, stdout);
        return mi_finish_stdout(MESO_EXIT_OK);
    }
    if (!strcmp(cmd, "--version")) {
        printf("mesoinspect %s (format %d.%d)\n", MESO_VERSION_STRING, MESO_FORMAT_MAJOR, MESO_FORMAT_MINOR);
        return mi_finish_stdout(MESO_EXIT_OK);
    }
    if (!strcmp(cmd, "info"))
        return mesoinspect_info(argc - 2, argv + 2);
    if (!strcmp(cmd, "validate"))
        return mesoinspect_validate(argc - 2, argv + 2);
    if (!strcmp(cmd, "dump"))
        return mesoinspect_dump(argc - 2, argv + 2);
    if (!strcmp(cmd, "diff"))
        return mesoinspect_diff(argc - 2, argv + 2);
    if (!strcmp(cmd, "preview"))
        return mesoinspect_preview(argc - 2, argv + 2);
    if (!strcmp(cmd, "export"))
        return mesoinspect_export(argc - 2, argv + 2);
    if (cmd[0] == '-')
        return mi_usage_error("unrecognized option '%s'", cmd);
    return mi_usage_error("unknown command '%s'", cmd);
}
