"""Errors and efficiency ratios of `mitsuba_side_by_side.sh` (run with the harness's Python).

For each renderer, from its R images (seeds 1..R) of the same scene:
- MSE: the mean over the images of the MSE against the harness reference (RGB mean);
- variance: the image's own variance, mean((a - b)^2) / 2 averaged over all pairs of images
  (independent seeds), which needs no reference;
- efficiency = 1 / (error x median render time), reported three ways: against the reference
  as it is (the issue's definition), with the manifest's `noise_rmse^2` subtracted from both
  MSEs, and from the variances alone. MSE minus variance is what the reference adds (its own
  noise, and any bias of the renderer): the same number for both renderers means it is the
  reference's.
"""
import itertools
import json
import os
import statistics
import sys

import numpy as np

scene, mi, d, r = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
rt = [float(x) for x in sys.argv[5].split()]
mt = [float(x) for x in sys.argv[6].split()]
sys.path.insert(0, mi)
from rmse import load_rgb  # noqa: E402

# `REF=path.exr` measures against another reference (e.g. a longer Mitsuba render, see
# benches/README.md); its own noise is then taken as `REF_NOISE_MSE` (default 0).
if os.environ.get("REF"):
    ref = load_rgb(os.environ["REF"]).astype(np.float64)
    noise = float(os.environ.get("REF_NOISE_MSE", "0"))
else:
    ref = load_rgb(f"{mi}/ref/{scene}.exr").astype(np.float64)
    noise = json.load(open(f"{mi}/ref/manifest.json"))[scene]["noise_rmse"] ** 2


def errors(prefix):
    ims = [load_rgb(f"{d}/{prefix}{k}.exr").astype(np.float64) for k in range(1, r + 1)]
    mse = statistics.mean(float(((a - ref) ** 2).mean()) for a in ims)
    pairs = [float(((a - b) ** 2).mean()) / 2 for a, b in itertools.combinations(ims, 2)]
    return mse, (statistics.mean(pairs) if pairs else float("nan"))


(mr, vr), (mm, vm) = errors("r"), errors("m")
tr, tm = statistics.median(rt), statistics.median(mt)
raw = (mm * tm) / (mr * tr)
sub = ((mm - noise) * tm) / ((mr - noise) * tr) if mr > noise else float("inf")
# A renderer whose images do not vary (the furnace: every pixel exactly 1) is infinitely
# efficient by its variance.
var = (vm * tm) / (vr * tr) if vr > 0 else float("inf")
fmt = lambda xs: "[" + ", ".join(f"{x:.2f}" for x in xs) + "]"  # noqa: E731
print(
    f"{scene}: risotto {tr:.3f}s {fmt(rt)} RMSE {mr ** 0.5:.5f} | mitsuba {tm:.3f}s {fmt(mt)} "
    f"RMSE {mm ** 0.5:.5f} | ratio {raw:.2f}x (reference noise {noise ** 0.5:.5f} subtracted: "
    f"{sub:.2f}x; from the images' own variance: {var:.2f}x) | MSE {mr:.3e} / {mm:.3e}, "
    f"variance {vr:.3e} / {vm:.3e}, reference's part {mr - vr:.2e} / {mm - vm:.2e}"
)
