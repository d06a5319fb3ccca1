# Writes hetero_rgb_density.vol (next to hetero_rgb.toml / .xml): a 16^3 Mitsuba .vol with 3
# channels (float32, x fastest, channel fastest of all) whose channels vary differently in
# space. Usage: python3 gen_hetero_rgb.py hetero_rgb_density.vol
import struct, math, sys
n = 16
out = bytearray(b"VOL\x03")
out += struct.pack("<iiiii", 1, n, n, n, 3)
out += struct.pack("<6f", 0, 0, 0, 1, 1, 1)
for z in range(n):
    for y in range(n):
        for x in range(n):
            p = [(x + 0.5) / n, (y + 0.5) / n, (z + 0.5) / n]
            d1 = sum((a - b) ** 2 for a, b in zip(p, (0.35, 0.5, 0.5)))
            d2 = sum((a - b) ** 2 for a, b in zip(p, (0.65, 0.45, 0.4)))
            r = math.exp(-d1 / 0.06)
            g = 0.1 + 0.6 * p[0] * p[1]
            b = math.exp(-d2 / 0.03) + 0.05
            out += struct.pack("<3f", r, g, b)
open(sys.argv[1], "wb").write(out)
