/* write_height_png OUT.png BITS [SIZE] — a test height map: a tileable
 * SIZE x SIZE (default 32) bumps pattern, grey, 8 or 16 bits per sample
 * (bake/image/png_io.h). For tests/integration/shell_texture_cli.sh. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "png_io.h"

int main(int argc, char** argv)
{
    if (argc < 3) {
        fputs("usage: write_height_png OUT.png 8|16 [SIZE]\n", stderr);
        return 1;
    }
    const int bits = atoi(argv[2]), n = argc > 3 ? atoi(argv[3]) : 32;
    if ((bits != 8 && bits != 16) || n < 1 || n > 4096) {
        fputs("write_height_png: bad bit depth or size\n", stderr);
        return 1;
    }
    uint16_t* px = malloc(sizeof(uint16_t) * (size_t)n * (size_t)n);
    if (!px)
        return 1;
    const double max = bits == 16 ? 65535.0 : 255.0;
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
            const double h = 0.5 + 0.25 * sin(2 * M_PI * 2 * (x + 0.5) / n) * sin(2 * M_PI * 3 * (y + 0.5) / n);
            px[y * n + x] = (uint16_t)lrint(h * max);
        }
    char why[256];
    const int rc = meso_png_write_gray(argv[1], px, n, n, bits, why, (int)sizeof(why));
    free(px);
    if (rc != 0)
        fprintf(stderr, "write_height_png: %s\n", why);
    return rc != 0;
}
