#!/usr/bin/env python3
"""Writes beachball.png (64 x 32, 8-bit sRGB RGB), the `image` pattern of
scenes/patterns.toml: six coloured gores around the ball (u = phi / 2pi) and white caps at
the poles (v = theta / pi near 0 and 1), with a thin dark seam between gores. Standard
library only (zlib + struct), so the texture can be regenerated anywhere."""
import struct
import zlib

W, H = 64, 32
GORES = [(230, 57, 70), (255, 255, 255), (255, 183, 3), (255, 255, 255), (33, 118, 174), (255, 255, 255)]


def texel(x, y):
    v = (y + 0.5) / H
    if v < 0.12 or v > 0.88:
        return (250, 250, 250)
    u = (x + 0.5) / W
    g = int(u * len(GORES)) % len(GORES)
    if g != int((x - 0.5) / W * len(GORES)) % len(GORES):
        return (40, 40, 40)  # the first texel of a gore: the seam
    return GORES[g]


def chunk(kind, data):
    body = kind + data
    return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)


rows = b"".join(b"\x00" + bytes(c for x in range(W) for c in texel(x, y)) for y in range(H))
png = b"\x89PNG\r\n\x1a\n"
png += chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 8, 2, 0, 0, 0))
png += chunk(b"sRGB", b"\x00")
png += chunk(b"IDAT", zlib.compress(rows, 9))
png += chunk(b"IEND", b"")
with open(__file__.replace("make_beachball.py", "beachball.png"), "wb") as f:
    f.write(png)
