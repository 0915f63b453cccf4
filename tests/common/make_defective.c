/* make_defective DIR — writes the generated defective meshes of
 * defective_meshes.h into DIR as NAME.obj, and two_boxes also as a binary
 * PLY, for the command-line tests (tests/integration/shell_cli.sh). */
#include <stdio.h>

#include "defective_meshes.h"

int main(int argc, char** argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: make_defective DIR\n");
        return 1;
    }
    for (size_t i = 0; i < DM_CASE_COUNT; ++i) {
        dm_mesh m = dm_cases[i].make();
        char path[4096];
        snprintf(path, sizeof(path), "%s/%s.obj", argv[1], dm_cases[i].name);
        int ok = dm_write_obj(path, &m);
        if (ok && !strcmp(dm_cases[i].name, "two_boxes")) {
            snprintf(path, sizeof(path), "%s/%s.ply", argv[1], dm_cases[i].name);
            ok = dm_write_ply(path, &m);
        }
        dm_free(&m);
        if (!ok) {
            fprintf(stderr, "make_defective: cannot write %s\n", path);
            return 2;
        }
    }
    return 0;
}
