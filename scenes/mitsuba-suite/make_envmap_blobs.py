# Generates scenes/mitsuba-suite/envmap_blobs.exr: a 32 x 16 latitude-longitude map with a
# dim vertical gradient and three coloured Gaussian blobs at different (u, v), so that any
# rotation or mirroring of the map changes the image.
import sys
import numpy as np
import mienv  # noqa: F401  (sets the variant)
import mitsuba as mi

w, h = 32, 16
u = (np.arange(w) + 0.5) / w
v = np.arange(h) / (h - 1)
U, V = np.meshgrid(u, v)
img = np.zeros((h, w, 3), np.float32)
img[...] = (0.05 + 0.15 * (1 - V))[..., None] * np.array([0.6, 0.8, 1.0])
for (bu, bv, r, rgb) in [
    (0.15, 0.30, 0.06, (8.0, 2.0, 0.5)),
    (0.55, 0.45, 0.09, (0.5, 4.0, 1.0)),
    (0.80, 0.20, 0.05, (1.0, 1.5, 12.0)),
]:
    du = np.minimum(abs(U - bu), 1 - abs(U - bu))
    g = np.exp(-(du**2 + (V - bv) ** 2) / (2 * r * r))
    img += g[..., None].astype(np.float32) * np.array(rgb, np.float32)
mi.Bitmap(img).write(sys.argv[1])
print(img.mean(axis=(0, 1)))
