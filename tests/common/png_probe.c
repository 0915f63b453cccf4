/* png_probe — test helper: `png_probe FILE` prints "W H" and the RGBA of the
 * four corner pixels and the centre, one per line, so shell tests can assert
 * on images without another dependency. */
#include <stdio.h>
#include <stdlib.h>

#include "png_io.h"

int main(int argc, char** argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: png_probe FILE.png\n");
        return 1;
    }
    uint8_t* px;
    int w, h;
    char why[256];
    if (meso_png_read_rgba8(argv[1], &px, &w, &h, why, sizeof(why)) != 0) {
        fprintf(stderr, "png_probe: %s\n", why);
        return 3;
    }
    printf("%d %d\n", w, h);
    const int at[5][2] = {{0, 0}, {w - 1, 0}, {0, h - 1}, {w - 1, h - 1}, {w / 2, h / 2}};
    for (int i = 0; i < 5; ++i) {
        const uint8_t* p = px + 4 * ((size_t)at[i][1] * (size_t)w + (size_t)at[i][0]);
        printf("%d %d %d %d\n", p[0], p[1], p[2], p[3]);
    }
    free(px);
    return 0;
}
