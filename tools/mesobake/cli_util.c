/* cli_util.c — what mesobake's commands share: diagnostics, option parsing,
 * progress lines, staging and publishing the outputs. */
#include "cli_util.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cjson/cJSON.h>


int verbose;

void err_msg(const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("mesobake error: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}

void err_print(const meso_error* err)
{
    const char* msg = err->message[0] ? err->message : meso_result_string(err->result);
    if (err->code)
        fprintf(stderr, "mesobake error E%u: %s\n", (unsigned)err->code, msg);
    else
        fprintf(stderr, "mesobake error: %s\n", msg);
}

void print_help(const char* usage)
{
    fputs(usage, stdout);
    fputs("\n" MESOBAKE_HELP_EXIT_CODES, stdout);
}

int usage_error(const char* fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("mesobake error: ", stderr);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputs("\nSee 'mesobake --help'.\n", stderr);
    return MESO_EXIT_USAGE;
}

int option_value(const char* opt, const char* value, const char* const* valued, size_t count)
{
    int known = 0;
    for (size_t k = 0; k < count && !known; ++k)
        known = !strcmp(opt, valued[k]);
    if (!known)
        return opt[0] == '-' ? usage_error("unrecognized option '%s'", opt)
                             : usage_error("unexpected argument '%s'", opt);
    if (!value)
        return usage_error("option '%s' needs a value", opt);
    return 0;
}

int path_option(const char* opt, const char* value, const char** in, const char** out, const char** report)
{
    const char** slot = !strcmp(opt, "-i") || !strcmp(opt, "--input")    ? in
                        : !strcmp(opt, "-o") || !strcmp(opt, "--output") ? out
                        : !strcmp(opt, "--report")                       ? report
                                                                         : NULL;
    if (slot)
        *slot = value;
    return slot != NULL;
}

/* Stage the --report file (when `report_path` is not NULL), then publish
 * every staged output; on any failure nothing is published. */
static int publish_outputs(const char* report_path, const char* report_json, size_t file_size, double seconds,
                           const finish_extra* x)
{
    meso_error err = {0};
    meso_result r = MESO_OK;
    cJSON* report = report_path ? cJSON_Parse(report_json) : NULL;
    if (report_path && !report)
        r = MESO_ERR_OUT_OF_MEMORY;
    if (report) {
        if (x && x->refuse)
            cJSON_AddBoolToObject(report, "output_written", 0);
        else
            cJSON_AddNumberToObject(report, "bytes", (double)file_size);
        cJSON_AddNumberToObject(report, "seconds_total", seconds);
        if (x && x->add_report)
            x->add_report(report, x->user);
        char* s = cJSON_Print(report);
        size_t n = s ? strlen(s) : 0;
        meso_output* o = NULL;
        r = s ? cli_output_stage(report_path, &o, &err) : MESO_ERR_OUT_OF_MEMORY;
        if (r == MESO_OK)
            s[n] = '\n'; /* the terminator becomes the final newline */
        if (r == MESO_OK)
            r = meso_output_write(o, s, n + 1, &err);
        cJSON_free(s);
        cJSON_Delete(report);
    }
    if (r == MESO_OK)
        r = cli_outputs_publish(&err);
    if (r == MESO_OK)
        return MESO_EXIT_OK;
    cli_outputs_discard();
    if (err.message[0])
        err_print(&err);
    else
        err_msg("%s: cannot write report: out of memory", report_path);
    return meso_exit_for(r);
}

int check_outputs(const char* out, const char* report)
{
    meso_error err = {0};
    meso_result r = meso_output_check(out, &err);
    if (r == MESO_OK && report)
        r = meso_output_check(report, &err);
    if (r == MESO_OK)
        return MESO_EXIT_OK;
    err_print(&err);
    return meso_exit_for(r);
}

int memory_option(const char* opt, const char* value, uint64_t* budget, int* bad)
{
    if (strcmp(opt, "--max-memory"))
        return 0;
    *bad = meso_bake_parse_size(value, budget)
               ? 0
               : usage_error("--max-memory expects a size such as 512M, 8G or a byte count (1 .. 2^62), got '%s'",
                             value);
    return 1;
}

int parts_option(const char* value, int* parts, int* code)
{
    long n;
    if (!strcmp(value, "auto"))
        *parts = 0;
    else if (!strcmp(value, "none"))
        *parts = -1;
    else if (meso_bake_parse_long(value, 64, 1L << 30, &n))
        *parts = (int)n;
    else {
        *code = usage_error("--parts expects auto, none or a triangle count of at least 64, got '%s'", value);
        return 0;
    }
    return 1;
}

static meso_bake_common* node_slot; /* where --node goes (cli_bake_common) */

void cli_bake_common(meso_bake_common* c)
{
    c->progress = cli_progress;
    node_slot = c;
}

int bake_option(const char* opt, const char* value, const char* const* valued, size_t count, const char** in,
                const char** out, const char** report, uint64_t* max_memory, int* handled, int* code)
{
    *handled = 0;
    if (!strcmp(opt, "--node") && node_slot) {
        *code = value ? 0 : usage_error("option '%s' needs a value", opt);
        node_slot->gltf_node = value;
        *handled = 1;
        return *code == 0;
    }
    if ((*code = option_value(opt, value, valued, count)) != 0)
        return 0;
    if (path_option(opt, value, in, out, report) || memory_option(opt, value, max_memory, code))
        *handled = 1;
    return *code == 0;
}

/* A one-line progress bar on a terminal (-v): redrawn in place with \r. */
static void progress_bar(const char* what, uint64_t done, uint64_t total)
{
    const int width = 30, filled = total ? (int)(width * done / total) : width;
    fprintf(stderr, "\rmesobake: %s [%.*s%*s] %3d%%", what, filled, "##############################", width - filled,
            "", total ? (int)(100 * done / total) : 100);
    if (done >= total)
        fputs("\r\033[K", stderr);
    fflush(stderr);
}

void cli_progress(void* user, const meso_bake_progress* p)
{
    (void)user;
    if (p->event == MESO_BAKE_EVENT_WARNING)
        fprintf(stderr, "mesobake warning: %s\n", p->message);
    else if (p->event == MESO_BAKE_EVENT_STAGE && verbose && p->message)
        fprintf(stderr, "mesobake: %s\n", p->message);
    else if (p->event == MESO_BAKE_EVENT_TICK && verbose && isatty(2))
        progress_bar("tracing directors", p->done, p->total);
}

int finish_bake(meso_result r, const meso_error* err, meso_bake_output* o, const char* out, const char* report,
                double t0, const char* detail)
{
    return finish_bake_ex(r, err, o, out, report, t0, detail, NULL);
}

int finish_bake_ex(meso_result r, const meso_error* err, meso_bake_output* o, const char* out, const char* report,
                   double t0, const char* detail, const finish_extra* x)
{
    meso_error werr = {0};
    if (r == MESO_OK && x && x->refuse) {
        /* Only the report: it says what is left. */
        const int code = publish_outputs(report, meso_bake_output_report_json(o), 0, meso_seconds() - t0, x);
        meso_bake_output_free(o);
        err_print(x->refuse);
        return code == MESO_EXIT_OK ? x->refuse_exit : code;
    }
    if (r == MESO_OK) {
        meso_output* staged = NULL;
        err = &werr;
        r = cli_output_stage(out, &staged, &werr);
        if (r == MESO_OK)
            r = meso_bake_output_write(o, staged, &werr);
    }
    if (r != MESO_OK) {
        cli_outputs_discard();
        meso_bake_output_free(o);
        err_print(err);
        return meso_exit_for(r);
    }
    const size_t file_size = meso_bake_output_size(o);
    const double t_end = meso_seconds();
    const int code = publish_outputs(report, meso_bake_output_report_json(o), file_size, t_end - t0, x);
    meso_bake_output_free(o);
    if (verbose && code == MESO_EXIT_OK)
        fprintf(stderr, "mesobake: wrote %s: %zu bytes%s (%.0f ms total)\n", out, file_size, detail ? detail : "",
                1e3 * (t_end - t0));
    return code;
}
