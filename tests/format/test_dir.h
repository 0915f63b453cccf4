/* test_dir.h — a private temporary directory for the tests that write files
 * (test_format_atomic, test_cli_output) and the questions they ask of it. */
#ifndef MESO_TEST_DIR_H
#define MESO_TEST_DIR_H

#include <assert.h>
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static char dir[256];

/* $TMPDIR/NAME_XXXXXX, created. */
static inline void make_test_dir(const char* name)
{
    const char* base = getenv("TMPDIR");
    snprintf(dir, sizeof dir, "%s/%s_XXXXXX", base ? base : "/tmp", name);
    assert(mkdtemp(dir) != NULL);
}

static inline void path_in(char* out, size_t n, const char* name) { snprintf(out, n, "%s/%s", dir, name); }

/* Number of entries in dir whose name contains `needle`. */
static inline int count_entries(const char* needle)
{
    DIR* d = opendir(dir);
    assert(d);
    int n = 0;
    struct dirent* e;
    while ((e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..") && strstr(e->d_name, needle))
            n++;
    closedir(d);
    return n;
}

#endif
