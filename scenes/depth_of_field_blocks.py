"""Usage (in the Mitsuba harness dir): ./run.sh THIS risotto_seed0.exr risotto_seed1.exr
mitsuba_seed0.exr mitsuba_seed100.exr [BLOCK_PX]

Block check: risotto (two seeds) vs Mitsuba (two seeds); per-pixel variance of each
renderer's 1-render mean estimated from its two seeds, (a - b)^2 / 2, summed per block."""
import os
import sys
# The harness beside the repository: ../shared/refs/mitsuba from its root.
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "refs", "mitsuba"))
from rmse import load_rgb
import numpy as np
r1, r2, m1, m2 = (load_rgb(p).astype(np.float64) for p in sys.argv[1:5])
B = int(sys.argv[5]) if len(sys.argv) > 5 else 16
r, m = (r1 + r2) / 2, (m1 + m2) / 2
var = ((r1 - r2) ** 2 / 2 + (m1 - m2) ** 2 / 2) / 2  # variance of r - m per pixel
h, w, _ = r.shape
zs = []
for y in range(0, h, B):
    for x in range(0, w, B):
        d = (r - m)[y:y+B, x:x+B].reshape(-1, 3)
        v = var[y:y+B, x:x+B].reshape(-1, 3)
        n = d.shape[0]
        zs.append(d.mean(0) / np.sqrt(v.sum(0) / n**2))
zs = np.array(zs)
flat = np.isnan(zs).sum()
assert np.all(np.isfinite(zs) | np.isnan(zs)), 'a block differs with zero noise'
zs = np.nan_to_num(zs)  # noiseless, identical blocks (pure sky)
print('noiseless identical block channels:', flat)
print(f"blocks {len(zs)} of {B}x{B} px, 3 channels: max |z| = {np.abs(zs).max():.2f}, "
      f"mean z = {zs.mean():.3f}, std z = {zs.std():.3f}, |z|>4: {(np.abs(zs)>4).sum()}")
print("channel means risotto", r.mean((0, 1)), "mitsuba", m.mean((0, 1)),
      "rel diff %", 100 * (r.mean((0, 1)) / m.mean((0, 1)) - 1))
