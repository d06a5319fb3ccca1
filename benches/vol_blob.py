#!/usr/bin/env python3
"""Writes an N^3 Mitsuba .vol density grid (one channel, float32): a smooth blob,
max(0, 1 - 4 |p - c|^2) over the unit cube, deterministic. For the media memory and load
figures of benches/README.md ("Media memory").

    python3 benches/vol_blob.py 512 target/blob512.vol
"""
import array
import struct
import sys


def main():
    n, out = int(sys.argv[1]), sys.argv[2]
    coord = [((i + 0.5) / n - 0.5) ** 2 for i in range(n)]
    with open(out, "wb") as f:
        f.write(b"VOL" + bytes([3]) + struct.pack("<iiiii", 1, n, n, n, 1))
        f.write(struct.pack("<6f", 0, 0, 0, 1, 1, 1))
        for z in range(n):
            for y in range(n):
                base = coord[y] + coord[z]
                row = array.array("f", (max(0.0, 1.0 - 4.0 * (base + cx)) for cx in coord))
                if sys.byteorder != "little":
                    row.byteswap()
                f.write(row.tobytes())


if __name__ == "__main__":
    main()
