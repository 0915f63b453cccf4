/*
 * validate.c — `mesoinspect validate [--full] FILE [--format ...]`: the cheap
 * checks every open runs, and with --full meso_file_validate(MESO_CHECK_FULL)
 * over every payload. Every issue is listed, not just the first.
 * Schema: schema/validate.schema.json.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "inspect.h"

static const char* const usage_validate =
    "Usage: mesoinspect validate [--full] FILE [--format text|json|mini-json]\n"
    "\n"
    "Check FILE with the runtime's reader and list every issue found, one line\n"
    "each: 'FILE: error CODE at offset N (chunk I): message' (codes: FORMAT.md §9),\n"
    "then 'FILE: valid' or 'FILE: N issues'.\n"
    "\n"
    "  --full         also check every payload: CRC32C, zero padding, element types,\n"
    "                 the contents of META, RPRT, OBJT, MESH (Draco decoded), SKEL,\n"
    "                 FRUS, FSEG, BALL and CELL, and every object against its kind\n"
    "                 (required chunks, cross-chunk counts and references, finite\n"
    "                 values; issues 6xxx). Without it only the checks done on open\n"
    "                 run (header, TOC, chunk ranges; no payload bytes are read).\n"
    "  --format FMT   text (default), json or mini-json (one line)\n"
    "  -h, --help     this help\n"
    "\n"
    "Exit codes: 0 valid, 2 I/O failure, 3 invalid, 4 out of memory.\n";

typedef struct issue_list {
    meso_error* items;
    size_t count;
    size_t cap;
} issue_list;

static int collect(void* user, const meso_error* issue)
{
    issue_list* l = user;
    if (l->count == l->cap) {
        size_t cap = l->cap ? 2 * l->cap : 16;
        meso_error* p = realloc(l->items, cap * sizeof(*p));
        if (!p)
            return 1; /* stop: keep what we have */
        l->items = p;
        l->cap = cap;
    }
    l->items[l->count++] = *issue;
    return 0;
}

static cJSON* issue_json(const meso_error* e)
{
    cJSON* j = cJSON_CreateObject();
    cJSON_AddNumberToObject(j, "code", e->code);
    const char* name = mi_issue_name(e->code);
    if (name)
        cJSON_AddStringToObject(j, "name", name);
    else
        cJSON_AddNullToObject(j, "name");
    cJSON_AddStringToObject(j, "result", mi_result_id(e->result));
    if (e->offset == UINT64_MAX)
        cJSON_AddNullToObject(j, "offset");
    else
        cJSON_AddNumberToObject(j, "offset", (double)e->offset);
    if (e->chunk < 0)
        cJSON_AddNullToObject(j, "chunk");
    else
        cJSON_AddNumberToObject(j, "chunk", e->chunk);
    cJSON_AddStringToObject(j, "message", e->message[0] ? e->message : meso_result_string(e->result));
    return j;
}

int mesoinspect_validate(int argc, char** argv)
{
    const char* path = NULL;
    int full = 0, only_positional = 0;
    mi_format fmt = MI_FORMAT_TEXT;
    for (int i = 0; i < argc; ++i) {
        const char* a = argv[i];
        int k;
        if (!only_positional && mi_is_help(a)) {
            fputs(usage_validate, stdout);
            return mi_finish_stdout(MESO_EXIT_OK);
        } else if (!only_positional && !strcmp(a, "--full")) {
            full = 1;
        } else if (!only_positional && (k = mi_format_option(argc, argv, &i, &fmt)) != 0) {
            if (k < 0)
                return MESO_EXIT_USAGE;
        } else if (!only_positional && !strcmp(a, "--")) {
            only_positional = 1;
        } else if (!only_positional && a[0] == '-' && a[1] != '\0') {
            return mi_usage_error("unrecognized option '%s'", a);
        } else if (!path) {
            path = a;
        } else {
            return mi_usage_error("unexpected argument '%s' (validate takes one file)", a);
        }
    }
    if (!path) {
        fputs(usage_validate, stderr);
        return MESO_EXIT_USAGE;
    }

    issue_list issues = {NULL, 0, 0};
    meso_file* f = NULL;
    meso_error err;
    memset(&err, 0, sizeof(err));
    meso_result r = mi_open(path, &f, &err);
    if (r == MESO_ERR_IO) {
        /* not an issue of the file: it could not be read at all */
        char line[400];
        mi_format_issue(&err, line, sizeof(line));
        mi_error("%s: %s", path, line);
        return MESO_EXIT_IO;
    }
    if (r != MESO_OK) {
        collect(&issues, &err);
    } else {
        meso_file_validate(f, full ? MESO_CHECK_FULL : MESO_CHECK_CHEAP, collect, &issues);
        meso_file_close(f);
    }

    int code = MESO_EXIT_OK;
    for (size_t i = 0; i < issues.count; ++i) {
        int c = issues.items[i].result == MESO_ERR_IO              ? MESO_EXIT_IO
                : issues.items[i].result == MESO_ERR_OUT_OF_MEMORY ? MESO_EXIT_INTERNAL
                                                                   : MESO_EXIT_INVALID;
        if (code == MESO_EXIT_OK || c == MESO_EXIT_IO)
            code = c;
    }

    if (fmt == MI_FORMAT_TEXT) {
        char line[400];
        for (size_t i = 0; i < issues.count; ++i) {
            mi_format_issue(&issues.items[i], line, sizeof(line));
            printf("%s: %s\n", path, line);
        }
        if (issues.count == 0)
            printf("%s: valid\n", path);
        else
            printf("%s: %zu issue%s\n", path, issues.count, issues.count == 1 ? "" : "s");
    } else {
        cJSON* doc = cJSON_CreateObject();
        cJSON_AddStringToObject(doc, "file", path);
        cJSON_AddBoolToObject(doc, "valid", issues.count == 0);
        cJSON_AddStringToObject(doc, "level", full ? "full" : "cheap");
        cJSON* arr = cJSON_AddArrayToObject(doc, "issues");
        for (size_t i = 0; i < issues.count; ++i)
            cJSON_AddItemToArray(arr, issue_json(&issues.items[i]));
        mi_print_json(doc, fmt);
        cJSON_Delete(doc);
    }
    free(issues.items);
    return mi_finish_stdout(code);
}
