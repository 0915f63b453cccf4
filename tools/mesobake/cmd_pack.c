/* cmd_pack.c — `mesobake pack`: several .meso files into one, each object
 * kept as its own (meso_bake_pack, bake/bake_pack.c). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli_util.h"

static const char* const usage_pack =
    "Usage: mesobake pack IN.meso [IN.meso ...] -o OUT.meso [options]\n"
    "\n"
    "Put every object of the inputs into one .meso file: objects are numbered 1..N in\n"
    "input order (each input's in its own order) and keep their names, kind, bounds and\n"
    "chunks byte for byte (only the object id changes; Draco meshes stay as they are).\n"
    "A name already taken gets \"~2\", \"~3\", ... (warning E3482). Each input is verified\n"
    "in full first (every CRC and structure, as 'mesoinspect validate --full'); a damaged\n"
    "one is refused, naming it, and nothing is written. The inputs' bake metadata and\n"
    "reports are kept per object in the new file's (mesoinspect info shows them).\n"
    "\n"
    "  -o, --output FILE       .meso file to write (atomically)\n"
    "      --report FILE       write the pack report as JSON (also stored in the file)\n"
    MEMORY_OPTION_HELP
    "  -v, --verbose           one line per input on stderr\n"
    "  -h, --help              this help\n"
    "\n"
    "Example: mesobake pack rock.meso cactus.meso -o scene.meso\n";

int cmd_pack(int argc, char** argv)
{
    const char *out = NULL, *report = NULL;
    meso_bake_pack_options o = {0};
    o.common.progress = cli_progress;
    const char** inputs = calloc((size_t)argc + 1, sizeof(*inputs));
    if (!inputs) {
        fprintf(stderr, "mesobake error: out of memory\n");
        return MESO_EXIT_INTERNAL;
    }
    int code = -1;
    uint32_t n = 0;
    for (int i = 0; i < argc && code < 0; ++i) {
        const char* a = argv[i];
        const int has_val = i + 1 < argc;
        if (!strcmp(a, "-h") || !strcmp(a, "--help")) {
            print_help(usage_pack); /* help only, whatever else is on the line */
            free(inputs);
            return MESO_EXIT_OK;
        } else if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && has_val) {
            out = argv[++i];
        } else if (!strcmp(a, "--report") && has_val) {
            report = argv[++i];
        } else if (!strcmp(a, "--max-memory") && has_val) {
            int bad = 0;
            memory_option(a, argv[++i], &o.common.max_memory, &bad);
            if (bad)
                code = bad;
        } else if (!strcmp(a, "-v") || !strcmp(a, "--verbose")) {
            verbose = 1;
        } else if (a[0] == '-' && a[1] != '\0') {
            const int known = !strcmp(a, "-o") || !strcmp(a, "--output") || !strcmp(a, "--report") ||
                              !strcmp(a, "--max-memory");
            code = usage_error(known ? "option '%s' needs a value" : "unrecognized option '%s'", a);
        } else if (n >= MESO_BAKE_MAX_PACK_INPUTS) {
            code = usage_error("more than %u inputs", MESO_BAKE_MAX_PACK_INPUTS);
        } else {
            inputs[n++] = a;
        }
    }
    if (code < 0 && (!n || !out)) {
        fputs(usage_pack, stderr);
        code = MESO_EXIT_USAGE;
    }
    for (uint32_t k = 0; code < 0 && k < n; ++k)
        if (!strcmp(inputs[k], out))
            code = usage_error("the output '%s' is also an input", out);
    if (code < 0)
        code = check_outputs(out, report);
    if (code == MESO_EXIT_OK && n) {
        o.inputs = inputs;
        o.input_count = n;
        const double t0 = meso_seconds();
        meso_error err = {0};
        meso_bake_output* packed = NULL;
        const meso_result r = meso_bake_pack(&o, &packed, NULL, &err);
        code = finish_bake(r, &err, packed, out, report, t0, ", packed");
    }
    free(inputs);
    return code;
}
