/*
 * dump.c — `mesoinspect dump FILE CHUNK -o OUT [--stored]`: write one chunk's
 * decoded bytes (Draco MESH decoded by the baker's decoder) or its stored
 * bytes. CHUNK is a TOC index or TYPE[:OBJECT[:LOD]].
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "inspect.h"

static const char* const usage_dump =
    "Usage: mesoinspect dump FILE CHUNK -o OUT [--stored]\n"
    "\n"
    "Write the bytes of one chunk to OUT ('-o -' writes to standard output).\n"
    "CHUNK is a TOC index (e.g. 3, as listed by 'mesoinspect info') or\n"
    "TYPE[:OBJECT[:LOD]] (e.g. MESH, MESH:1, TX2D:1:2); it must match one chunk.\n"
    "\n"
    "  -o, --output FILE   where to write ('-' for standard output); atomically, a\n"
    "                      symbolic link written through, a device, FIFO or directory refused\n"
    "      --stored        the bytes as stored in the file (default: decoded, i.e.\n"
    "                      a Draco MESH is decoded to the raw MESH layout)\n"
    "  -h, --help          this help\n"
    "\n"
    "The chunk's CRC32C is checked (and its contents, when decoded) before\n"
    "anything is written.\n"
    "Exit codes: 0 written, 1 bad arguments or CHUNK matches no chunk, 2 I/O failure,\n"
    "            3 invalid file or chunk (e.g. CRC mismatch), 5 encoding not supported.\n";

/* Parse a decimal number of at most `max`; 0 on error. */
static int parse_u32(const char* s, size_t n, uint32_t max, uint32_t* out)
{
    if (n == 0 || n > 10)
        return 0;
    uint64_t v = 0;
    for (size_t i = 0; i < n; ++i) {
        if (s[i] < '0' || s[i] > '9')
            return 0;
        v = 10 * v + (uint64_t)(s[i] - '0');
    }
    if (v > max)
        return 0;
    *out = (uint32_t)v;
    return 1;
}

typedef struct chunk_spec {
    int by_index;
    uint32_t index;
    uint32_t type;
    uint32_t object; /* UINT32_MAX: any */
    uint32_t lod;    /* UINT32_MAX: any */
} chunk_spec;

static int parse_spec(const char* s, chunk_spec* out)
{
    memset(out, 0, sizeof(*out));
    out->object = UINT32_MAX;
    out->lod = UINT32_MAX;
    if (parse_u32(s, strlen(s), UINT32_MAX, &out->index)) {
        out->by_index = 1;
        return 1;
    }
    const char* c1 = strchr(s, ':');
    size_t tn = c1 ? (size_t)(c1 - s) : strlen(s);
    if (tn != 4)
        return 0;
    for (size_t k = 0; k < 4; ++k)
        if ((unsigned char)s[k] < 0x20 || (unsigned char)s[k] > 0x7E)
            return 0;
    out->type = MESO_FOURCC(s[0], s[1], s[2], s[3]);
    if (!c1)
        return 1;
    const char* o = c1 + 1;
    const char* c2 = strchr(o, ':');
    if (!parse_u32(o, c2 ? (size_t)(c2 - o) : strlen(o), UINT32_MAX - 1, &out->object))
        return 0;
    if (!c2)
        return 1;
    return parse_u32(c2 + 1, strlen(c2 + 1), UINT16_MAX, &out->lod);
}

static int write_out(const char* out, const uint8_t* data, size_t size)
{
    if (!strcmp(out, "-")) {
        if (size && fwrite(data, 1, size, stdout) != size) {
            mi_error("cannot write to standard output: %s", strerror(errno));
            return MESO_EXIT_IO;
        }
        return mi_finish_stdout(MESO_EXIT_OK);
    }
    meso_output* o = NULL;
    int code = mi_stage_output(out, &o);
    if (code != MESO_EXIT_OK)
        return code;
    meso_error err;
    memset(&err, 0, sizeof(err));
    meso_result r = meso_output_write(o, data, size, &err);
    return r == MESO_OK ? mi_publish_outputs() : mi_output_failed(&err, r);
}

static int chunk_read_error(const char* path, const meso_error* err, meso_result r)
{
    char line[400];
    mi_format_issue(err, line, sizeof(line));
    mi_error("%s: %s", path, line);
    return r == MESO_ERR_INVALID_ARG ? MESO_EXIT_INTERNAL : meso_exit_for(r);
}

int mesoinspect_dump(int argc, char** argv)
{
    const char *path = NULL, *spec_s = NULL, *out = NULL;
    int stored = 0, only_positional = 0;
    for (int i = 0; i < argc; ++i) {
        const char* a = argv[i];
        if (!only_positional && mi_is_help(a)) {
            fputs(usage_dump, stdout);
            return mi_finish_stdout(MESO_EXIT_OK);
        } else if (!only_positional && (!strcmp(a, "-o") || !strcmp(a, "--output"))) {
            if (i + 1 >= argc)
                return mi_usage_error("option '%s' needs a value", a);
            out = argv[++i];
        } else if (!only_positional && !strcmp(a, "--stored")) {
            stored = 1;
        } else if (!only_positional && !strcmp(a, "--")) {
            only_positional = 1;
        } else if (!only_positional && a[0] == '-' && a[1] != '\0') {
            return mi_usage_error("unrecognized option '%s'", a);
        } else if (!path) {
            path = a;
        } else if (!spec_s) {
            spec_s = a;
        } else {
            return mi_usage_error("unexpected argument '%s'", a);
        }
    }
    if (!path || !spec_s || !out) {
        fputs(usage_dump, stderr);
        return MESO_EXIT_USAGE;
    }
    chunk_spec spec;
    if (!parse_spec(spec_s, &spec))
        return mi_usage_error("bad chunk '%s': expected a TOC index or TYPE[:OBJECT[:LOD]], e.g. MESH:1:0", spec_s);
    const int checked = strcmp(out, "-") ? mi_check_output(out) : MESO_EXIT_OK;
    if (checked != MESO_EXIT_OK)
        return checked;

    meso_file* f;
    int code = mi_open_or_report(path, &f);
    if (code != MESO_EXIT_OK)
        return code;
    const uint32_t n = meso_file_chunk_count(f);
    uint32_t index = 0;
    if (spec.by_index) {
        if (spec.index >= n) {
            mi_error("%s: no chunk %u (the file has %u chunk%s)", path, spec.index, n, n == 1 ? "" : "s");
            meso_file_close(f);
            return MESO_EXIT_USAGE;
        }
        index = spec.index;
    } else {
        uint32_t matches = 0;
        char list[128] = "";
        for (uint32_t i = 0; i < n; ++i) {
            const meso_chunk_info* c = meso_file_chunk(f, i);
            if (c->type != spec.type || (spec.object != UINT32_MAX && c->object != spec.object) ||
                (spec.lod != UINT32_MAX && c->lod != spec.lod))
                continue;
            if (matches++ == 0)
                index = i;
            size_t used = strlen(list);
            if (used < sizeof(list) - 16)
                snprintf(list + used, sizeof(list) - used, "%s%u", used ? ", " : "", i);
        }
        if (matches == 0) {
            mi_error("%s: no chunk matches '%s'", path, spec_s);
            meso_file_close(f);
            return MESO_EXIT_USAGE;
        }
        if (matches > 1) {
            mi_error("%s: '%s' matches %u chunks (%s); give TYPE:OBJECT:LOD or a TOC index", path, spec_s, matches,
                     list);
            meso_file_close(f);
            return MESO_EXIT_USAGE;
        }
    }

    const meso_chunk_info* c = meso_file_chunk(f, index);
    meso_error err;
    memset(&err, 0, sizeof(err));
    uint8_t* data = NULL;
    size_t size = 0;
    meso_result r;
    if (stored) {
        if (c->stored_size > SIZE_MAX - 1) {
            mi_error("%s: chunk %u is too large for this platform", path, index);
            meso_file_close(f);
            return MESO_EXIT_UNSUPPORTED;
        }
        size = (size_t)c->stored_size;
        data = malloc(size + 1);
        if (!data) {
            mi_error("out of memory for %zu bytes", size);
            meso_file_close(f);
            return MESO_EXIT_INTERNAL;
        }
        r = meso_file_read_stored(f, index, data, size, &err);
    } else {
        r = mi_read_decoded(f, index, &data, &size, &err);
    }
    if (r != MESO_OK) {
        code = chunk_read_error(path, &err, r);
        free(data);
        meso_file_close(f);
        return code;
    }
    code = write_out(out, data, size);
    free(data);
    meso_file_close(f);
    return code;
}
