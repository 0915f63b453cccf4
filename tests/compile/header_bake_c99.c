/* meso_bake.h compiles alone as strict C99, with nothing but meso_file.h
 * beside it, and links against the shared libmeso_bake (STYLE.md §9). */
#include "meso_bake.h"

#include <stdio.h>
#include <string.h>

int main(void)
{
    meso_bake_shell_options o = meso_bake_shell_defaults();
    int bad = o.directors != MESO_DIRECTORS_HYBRID || o.kind != MESO_SHELL_EXTERIOR;
    bad |= strcmp(meso_bake_directors_name(MESO_DIRECTORS_NORMAL), "normal") != 0;
    bad |= MESO_BAKE_EVENT_COUNT != 3 || MESO_DIRECTORS_COUNT != 3;
    if (bad)
        fprintf(stderr, "meso_bake.h disagrees with libmeso_bake\n");
    return bad;
}
