/* test_need.h — need(ok, fmt, ...): abort with a printf-style message
 * unless `ok`, and CHECK(x) naming the failed expression (header-only,
 * test code; the GL tests that compare images use it). */
#ifndef MESO_TEST_NEED_H
#define MESO_TEST_NEED_H

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

#if defined(__GNUC__)
static void need(int ok, const char* fmt, ...) __attribute__((format(printf, 2, 3)));
#endif
static void need(int ok, const char* fmt, ...)
{
    if (ok)
        return;
    va_list ap;
    va_start(ap, fmt);
    fputs("FAILED: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputs("\n", stderr);
    va_end(ap);
    abort();
}
#define CHECK(x) need((x), "%s", #x)

#endif /* MESO_TEST_NEED_H */
