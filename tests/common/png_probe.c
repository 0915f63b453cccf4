/* png_probe — test helper: `png_probe FILE` prints "W H" and the RGBA of the
 * four corner pixels and the centre, one per line, so shell tests can assert
 * on images without another dependency. `png_probe --diff A B` prints the
 * number of pixels whose RGB differs by more than 2 (of 255) in a channel
 * and the largest difference (exit 1 when the sizes differ). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "png_io.h"

int main(int argc, char** argv)
{
    if (argc == 4 && !strcmp(argv[1], "--diff")) {
        uint8_t *a, *b;
        int w, h, w2, h2;
        char why[256];
        if (meso_png_read_rgba8(argv[2], &a, &w, &h, why, sizeof(why)) != 0 ||
            meso_png_read_rgba8(argv[3], &b, &w2, &h2, why, sizeof(why)) != 0) {
            fprintf(stderr, "png_probe: %s\n", why);
            return 3;
        }
        if (w != w2 || h != h2) {
            fprintf(stderr, "png_probe: sizes differ: %dx%d and %dx%d\n", w, h, w2, h2);
            return 1;
        }
        long differing = 0;
        int worst = 0;
        for (size_t i = 0; i < (size_t)w * (size_t)h; ++i) {
            int m = 0;
            for (int k = 0; k < 3; ++k)
                m = abs(a[4 * i + k] - b[4 * i + k]) > m ? abs(a[4 * i + k] - b[4 * i + k]) : m;
            differing += m > 2;
            worst = m > worst ? m : worst;
        }
        printf("%ld %d\n", differing, worst);
        free(a);
        free(b);
        return 0;
    }
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
