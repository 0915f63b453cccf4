/* gl_log.h — a libmeso logger for the GL tests that keeps the last error
 * (header-only, test code): pass on_log_error with a log_capture as
 * meso_rt_desc.log_fn / log_user. */
#ifndef MESO_TEST_GL_LOG_H
#define MESO_TEST_GL_LOG_H

#include <stdio.h>

#include "meso_rt.h"

typedef struct log_capture {
    int errors;
    meso_log_item last;
    char message[512];
} log_capture;

static inline void on_log_error(void* user, meso_log_level level, meso_log_item item, const char* message)
{
    log_capture* c = user;
    if (level != MESO_LOG_ERROR)
        return;
    ++c->errors;
    c->last = item;
    snprintf(c->message, sizeof(c->message), "%s", message ? message : "");
}

#endif /* MESO_TEST_GL_LOG_H */
