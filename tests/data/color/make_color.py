#!/usr/bin/env python3
"""Writes the colour inputs of tests/integration/shell_color_cli.sh (standard
library only; run from the repository root):
  bricks_color.png  96 x 96 RGB: the built-in `bricks` layout (see brick()),
                    each brick its own red-brown, grey mortar joints
  color8.png        8 x 8 RGBA: r = 16 + 28 x, g = 16 + 28 y (y from the top),
                    b = 200 - 12 (x + y), alpha 255
  volume4.raw       4 x 4 x 2 RGBA8 texels, s fastest: (64 s, 64 t, 255 w, 255)"""
import os
import struct
import zlib

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)))


def png(path, w, h, pixel, channels):
    raw = b"".join(b"\x00" + bytes(c for x in range(w) for c in pixel(x, y)) for y in range(h))

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    colour_type = 6 if channels == 4 else 2
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, colour_type, 0, 0, 0)) +
                chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def brick(x, y):
    """The layout of the built-in `bricks` height field (bake/texture_function.c
    bricks_height: 6 courses of 2 bricks, odd courses shifted by half a
    brick), rows top to bottom with the bottom row at t = 0: each brick its own
    red-brown, the joints (within 0.02 of a brick's edge) grey mortar."""
    n = 96
    s = (x + 0.5) / n
    t = (n - 1 - y + 0.5) / n
    row = int(t * 6)
    ly = t * 6 - row
    bx = s * 2 - 0.5 * (row & 1)
    col = int(bx // 1)
    lx = bx - col
    edge = min(min(lx, 1 - lx) / 2, min(ly, 1 - ly) / 6)
    if edge < 0.02:
        return (160, 156, 148)   # mortar
    k = ((row % 6) * 7 + (col % 2) * 13) % 5
    return (140 + 20 * k, 50 + 9 * k, 36 + 6 * k)


if __name__ == "__main__":
    png(os.path.join(OUT, "bricks_color.png"), 96, 96, brick, 3)
    png(os.path.join(OUT, "color8.png"), 8, 8, lambda x, y: (16 + 28 * x, 16 + 28 * y, 200 - 12 * (x + y), 255), 4)
    with open(os.path.join(OUT, "volume4.raw"), "wb") as f:
        f.write(bytes(c for w in range(2) for t in range(4) for s in range(4) for c in (64 * s, 64 * t, 255 * w, 255)))
