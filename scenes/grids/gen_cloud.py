#!/usr/bin/env python3
"""Writes the density grid of scenes/cloud.toml, a Mitsuba .vol file (version 3, float32,
one channel), 48 x 32 x 48 voxels (295 KB), over the unit cube of the cloud's box:

- cloud_density.vol: a cumulus-like blob -- a few overlapping spheres, flattened at the
  base and billowing on top -- whose edge is eroded by fBm value noise (four octaves), so
  the density rises from 0 at a wispy, noisy boundary to about 1 in the core.

The noise is gen_flame.py's deterministic lattice hashing (no random module), so the file is the same on
every machine; pure Python, no numpy. scenes/cloud.toml gives the extinction as
sigma_t = scale * density with a colour `scale` (a chromatic medium, spectral tracking).

Usage: python3 gen_cloud.py [OUT_DIR]   (default: the directory of this script)
"""
import math
import os
import struct
import sys

# The lattice noise and smoothstep of the flame's generator beside this script.
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gen_flame import smoothstep, value_noise  # noqa: E402

NX, NY, NZ = 48, 32, 48

# The blob: spheres (centre u, v, w; radius) in the unit cube, v up. The box is 1.5 times
# wider than tall, so radii are in the box's units along each axis scaled below.
PUFFS = [
    (0.50, 0.42, 0.50, 0.30),
    (0.30, 0.38, 0.45, 0.22),
    (0.70, 0.40, 0.55, 0.22),
    (0.45, 0.62, 0.52, 0.20),
    (0.62, 0.58, 0.40, 0.17),
    (0.50, 0.38, 0.72, 0.18),
]


def fbm(x, y, z, seed, octaves=4):
    """fBm: octaves of value noise at doubling frequency and halving amplitude, in [0, 1)."""
    acc, amp, norm = 0.0, 0.5, 0.0
    for o in range(octaves):
        f = 2.0 ** o
        acc += amp * value_noise(f * x, f * y, f * z, seed + o)
        norm += amp
        amp *= 0.5
    return acc / norm


def cloud(u, v, w):
    """Density at unit-cube point (u, v, w); v is the height."""
    # Signed distance-like field: how far inside the nearest puff, in puff radii (1 at a
    # centre, 0 on its surface, negative outside: the noise cannot raise empty space). The box is 1.5 x 1 x 1.5: scale u, w so puffs are round.
    inside = -math.inf
    for (cu, cv, cw, r) in PUFFS:
        du, dv, dw = (u - cu) * 1.5, (v - cv), (w - cw) * 1.5
        d = math.sqrt(du * du + dv * dv + dw * dw) / (r * 1.5)
        inside = max(inside, 1.0 - d)
    # Erode the edge with noise; flatten the base.
    n = fbm(5.0 * u, 5.0 * v, 5.0 * w, 3)
    s = inside + 0.35 * (n - 0.5)
    base = smoothstep(0.12, 0.22, v)
    return max(smoothstep(0.0, 0.35, s) * base * (0.7 + 0.6 * n), 0.0)


def write_vol(path, data):
    with open(path, "wb") as f:
        f.write(b"VOL" + bytes([3]))
        f.write(struct.pack("<iiiii", 1, NX, NY, NZ, 1))
        f.write(struct.pack("<6f", 0, 0, 0, 1, 1, 1))
        f.write(struct.pack("<%df" % len(data), *data))


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    density = []
    for iz in range(NZ):
        for iy in range(NY):
            for ix in range(NX):
                density.append(cloud((ix + 0.5) / NX, (iy + 0.5) / NY, (iz + 0.5) / NZ))
    write_vol(os.path.join(out, "cloud_density.vol"), density)
    print("max density %.3f, mean %.3f, non-zero voxels %d of %d" % (
        max(density), sum(density) / len(density), sum(1 for d in density if d > 0),
        len(density)))


if __name__ == "__main__":
    main()
