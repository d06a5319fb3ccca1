#!/usr/bin/env python3
"""Writes the two grids of scenes/fire.toml, Mitsuba .vol files (version 3, float32, one
channel), 24 x 36 x 24 voxels each (83 KB), over the unit cube of the flame's box:

- flame_density.vol: a flickering teardrop of soot and glowing gas, densest in the core,
  fading to 0 at its edge and towards the tip, with deterministic value noise (no random
  module, so the files are the same on every machine);
- flame_temperature.vol: the flame's glow in [0, 1], hottest in the core just above the
  base and cooling outwards and upwards (it is 0 wherever the density is).

scenes/fire.toml gives the density as `density` (sigma_t = scale * density) and the glow
as an independent emission grid (j = scale * glow, radiance per unit length).

Usage: python3 gen_flame.py [OUT_DIR]   (default: the directory of this script)
"""
import math
import os
import struct
import sys

NX, NY, NZ = 24, 36, 24


def hash3(ix, iy, iz, seed):
    """A deterministic pseudo-random number in [0, 1) per lattice point."""
    h = (ix * 73856093) ^ (iy * 19349663) ^ (iz * 83492791) ^ (seed * 2654435761)
    h &= 0xFFFFFFFF
    h = ((h >> 16) ^ h) * 0x45D9F3B & 0xFFFFFFFF
    h = ((h >> 16) ^ h) * 0x45D9F3B & 0xFFFFFFFF
    h = (h >> 16) ^ h
    return (h & 0xFFFFFF) / float(1 << 24)


def value_noise(x, y, z, seed):
    """Trilinearly interpolated lattice noise with smoothstep weights, in [0, 1)."""
    x0, y0, z0 = math.floor(x), math.floor(y), math.floor(z)
    fx, fy, fz = x - x0, y - y0, z - z0
    sx, sy, sz = (f * f * (3 - 2 * f) for f in (fx, fy, fz))
    acc = 0.0
    for dz in (0, 1):
        for dy in (0, 1):
            for dx in (0, 1):
                w = (sx if dx else 1 - sx) * (sy if dy else 1 - sy) * (sz if dz else 1 - sz)
                acc += w * hash3(x0 + dx, y0 + dy, z0 + dz, seed)
    return acc


def fbm(x, y, z, seed):
    """Three octaves of value noise, in about [0, 1)."""
    return (0.55 * value_noise(x, y, z, seed)
            + 0.3 * value_noise(2 * x, 2 * y, 2 * z, seed + 1)
            + 0.15 * value_noise(4 * x, 4 * y, 4 * z, seed + 2))


def smoothstep(e0, e1, x):
    t = min(max((x - e0) / (e1 - e0), 0.0), 1.0)
    return t * t * (3 - 2 * t)


def flame(u, v, w):
    """(density, glow) at unit-cube point (u, v, w); v is the height."""
    # The flame leans and sways a little with height.
    cx = 0.5 + 0.06 * math.sin(5.0 * v) * v
    cz = 0.5 + 0.04 * math.cos(4.0 * v) * v
    # Teardrop radius: zero at the base, widest at a quarter of the height, to a tip.
    radius = 0.42 * math.sqrt(min(v / 0.25, 1.0)) * (1.0 - v) ** 0.8 if v < 1.0 else 0.0
    r = math.hypot(u - cx, w - cz)
    n = fbm(4.0 * u, 5.0 * v - 1.0, 4.0 * w, 7)
    edge = radius * (0.75 + 0.5 * n)
    if edge <= 1e-6:
        return 0.0, 0.0
    s = r / edge
    density = (1.0 - smoothstep(0.35, 1.0, s)) * (0.6 + 0.8 * n) * (1.0 - smoothstep(0.7, 1.0, v))
    # Glow: a hot core above the base, cooling outwards and upwards.
    core = 1.0 - smoothstep(0.0, 1.0, s)
    height = smoothstep(0.0, 0.05, v) * (1.0 - smoothstep(0.3, 1.0, v))
    glow = core * height * (0.7 + 0.6 * fbm(6.0 * u, 6.0 * v, 6.0 * w, 11))
    return max(density, 0.0), min(max(glow, 0.0), 1.0) if density > 0.0 else 0.0


def write_vol(path, data):
    with open(path, "wb") as f:
        f.write(b"VOL" + bytes([3]))
        f.write(struct.pack("<iiiii", 1, NX, NY, NZ, 1))
        f.write(struct.pack("<6f", 0, 0, 0, 1, 1, 1))
        f.write(struct.pack("<%df" % len(data), *data))


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    density, glow = [], []
    for iz in range(NZ):
        for iy in range(NY):
            for ix in range(NX):
                d, g = flame((ix + 0.5) / NX, (iy + 0.5) / NY, (iz + 0.5) / NZ)
                density.append(d)
                glow.append(g)
    write_vol(os.path.join(out, "flame_density.vol"), density)
    write_vol(os.path.join(out, "flame_temperature.vol"), glow)
    print("max density %.3f, max glow %.3f, glowing voxels %d of %d" % (
        max(density), max(glow), sum(1 for g in glow if g > 0), len(glow)))


if __name__ == "__main__":
    main()
