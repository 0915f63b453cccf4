/* The public headers compile alone as strict C99 (STYLE.md §9) and their
 * constants agree with the layout header. */
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
    bad |= MESO_RESULT_COUNT <= MESO_ERR_NOT_FOUND;
    bad |= MESO_LOGITEM_COUNT <= MESO_LOGITEM_OK;
    if (bad)
        fprintf(stderr, "header constants disagree\n");
    return bad;
}
