"""Writes leaf_alpha.png (RGBA: green, alpha = a leaf shape) and leaf_alpha_grey.png (the
same alpha as grey, for Mitsuba's `mask` with `raw`), 32 x 32, and leaf_quad.obj (a unit
quad in the xz plane facing +y with texture coordinates). Run from this directory."""
import math, struct, zlib

N = 32

def alpha(x, y):
    # A leaf: an ellipse pointed at both ends along the image's diagonal, with a notch.
    u, v = (x + 0.5) / N * 2 - 1, (y + 0.5) / N * 2 - 1
    a, b = (u + v) / math.sqrt(2), (u - v) / math.sqrt(2)
    inside = abs(b) < 0.45 * (1 - a * a) and abs(a) < 0.95
    notch = a > 0.2 and abs(b) < 0.08
    return 255 if inside and not notch else 0

def png(path, rows, colour_type, channels):
    raw = b"".join(b"\0" + bytes(r) for r in rows)
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    ihdr = struct.pack(">IIBBBBB", N, N, 8, colour_type, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))

rgba = [[c for x in range(N) for c in (60, 160, 70, alpha(x, y))] for y in range(N)]
grey = [[alpha(x, y) for x in range(N)] for y in range(N)]
png("leaf_alpha.png", rgba, 6, 4)
png("leaf_alpha_grey.png", grey, 0, 1)
with open("leaf_quad.obj", "w") as f:
    f.write("# a unit quad in the xz plane, facing +y, with texture coordinates\n")
    f.write("v -0.5 0 0.5\nv 0.5 0 0.5\nv 0.5 0 -0.5\nv -0.5 0 -0.5\n")
    f.write("vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 1 0\n")
    f.write("f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n")
