/* cli_common.h — what mesobake's and mesoinspect's command lines share:
 * exit codes (STYLE.md §8), diagnostics, timing. */
#ifndef MESO_CLI_COMMON_H
#define MESO_CLI_COMMON_H

#include "meso_file.h"

enum {
    MESO_EXIT_OK = 0,
    MESO_EXIT_USAGE = 1,       /* command-line error */
    MESO_EXIT_IO = 2,          /* IO failure */
    MESO_EXIT_INVALID = 3,     /* invalid input file */
    MESO_EXIT_INTERNAL = 4,    /* runtime/internal error */
    MESO_EXIT_UNSUPPORTED = 5, /* not supported in this build */
    MESO_EXIT_JOBS_FAILED = 6, /* mesobake batch: at least one job failed */
    MESO_EXIT_DIFFERENT = 7,   /* diff found a difference */
    MESO_EXIT_DEFECTS = 8,     /* mesobake shell: the shell keeps inverted prisms or intersections */
};

/* Exit code for a failed library call. */
static inline int meso_exit_for(meso_result r)
{
    switch (r) {
    case MESO_OK: return MESO_EXIT_OK;
    case MESO_ERR_IO:
    case MESO_ERR_PENDING: return MESO_EXIT_IO; /* a stream that has not delivered the bytes asked for */
    case MESO_ERR_TRUNCATED:
    case MESO_ERR_BAD_MAGIC:
    case MESO_ERR_VERSION_TOO_NEW:
    case MESO_ERR_CORRUPT: return MESO_EXIT_INVALID;
    case MESO_ERR_UNSUPPORTED: return MESO_EXIT_UNSUPPORTED;
    case MESO_ERR_INVALID_ARG: return MESO_EXIT_USAGE;
    default: return MESO_EXIT_INTERNAL;
    }
}

#endif
