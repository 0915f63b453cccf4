/* The public headers compile alone as strict C99 (STYLE.md §9), their
 * constants agree with the layout header, and draw descs mean the defaults
 * when zeroed and take designated initialisers, nested ones included. */
#include "meso_file.h"
#include "meso_layout.h"
#include "meso_rt.h"

#include <stdio.h>

int main(void)
{
    int bad = 0;
    bad |= MESO_FORMAT_MAJOR != 1;
    bad |= MESO_HDR_SIZE != 64 || MESO_TOC_ENTRY_SIZE != 64 || MESO_ALIGN != 64;
    bad |= MESO_CHUNK_MESH != 0x4853454Du; /* 'M' 'E' 'S' 'H' little-endian */
    bad |= MESO_RESULT_COUNT <= MESO_ERR_PENDING;
    bad |= MESO_LOGITEM_COUNT <= MESO_LOGITEM_OK;
    /* A zero draw desc means every default; common fields and each kind's
     * knobs take designated initialisers. */
    meso_rt_draw_desc zero = {0};
    meso_rt_draw_desc d = {.view = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1},
                           .light_dir = {0, 1, 0},
                           .shell = {.technique = MESO_SHELL_CURVED, .max_steps = 64},
                           .frusta = {.relief_steps = 128},
                           .cells = {.mode = MESO_CELLS_REFLECT, .bounces = 2}};
    bad |= zero.shell.technique != MESO_SHELL_SMOOTH || zero.cells.mode != MESO_CELLS_FIRST_HIT || zero.stats != NULL;
    bad |= d.view[15] != 1.0f || d.shell.error_px != 0.0f || d.frusta.bisection_steps != 0 || d.cells.environment != 0;
    if (bad)
        fprintf(stderr, "header constants or draw desc defaults disagree\n");
    return bad;
}
