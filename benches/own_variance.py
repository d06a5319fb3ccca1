"""Per-pixel variance across `benches/own_variance.sh`'s seeds (run with the harness's Python)."""
import json
import statistics
import sys

import numpy as np

mi, d, r, block = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
sys.path.insert(0, mi)
from rmse import load_rgb  # noqa: E402

ims = np.stack([load_rgb(f"{d}/r{k}.exr").astype(np.float64) for k in range(1, r + 1)])
var = ims.var(axis=0, ddof=1).mean(axis=2)
t = statistics.median(json.load(open(f"{d}/s{k}.json"))["wall_seconds"] for k in range(1, r + 1))
line = f"{d}: {r} seeds, variance {var.mean():.4e}, median time {t:.3f} s, variance x time {var.mean() * t:.4e}"
if block:
    (y0, y1), (x0, x1) = ([int(v) for v in part.split(":")] for part in block.split(","))
    line += f"; block rows {y0}:{y1}, columns {x0}:{x1}: {var[y0:y1, x0:x1].sum() / var.size:.4e} of it"
print(line)
