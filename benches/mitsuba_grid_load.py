#!/usr/bin/env python3
"""Mitsuba 3's side of issue 36's media figures (benches/README.md, "Media memory (issue
36)"): the scene of benches/blob512.toml (a heterogeneous medium over a .vol grid in the box
[-0.5, 0.5]^3, scale 10, albedo 0.9, isotropic phase, under a constant environment of 1;
64x64, fov 30 from (0, 0, 4)) built with mi.load_dict, then one render at the same size and
spp as risotto's.

Usage (from the Mitsuba harness, which provides the `mitsuba` module):
  ../shared/refs/mitsuba/run.sh $PWD/benches/mitsuba_grid_load.py target/blob512.vol [SPP [WxH]]
  ../shared/refs/mitsuba/run.sh $PWD/benches/mitsuba_grid_load.py --empty

Prints one JSON line: load_seconds (mi.load_dict: the .vol read, the grid's texture and its
majorant), render_seconds (mi.render, forced; the first render includes Dr.Jit's kernel
compilation, so a second render is timed too), peak_resident_bytes (ru_maxrss of this process,
the whole run). `--empty` loads the scene without the medium: the baseline of the peak.
"""
import json
import os
import resource
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(
    0, os.environ.get("MI_HARNESS", os.path.join(HERE, "../../shared/refs/mitsuba"))
)
import mienv  # noqa: E402


def main():
    args = sys.argv[1:]
    empty = "--empty" in args
    rest = [a for a in args if not a.startswith("--")]
    if not empty and not rest:
        sys.exit(__doc__)
    path = None if empty else rest.pop(0)
    spp = int(rest[0]) if rest else 4
    w, h = (int(v) for v in (rest[1] if len(rest) > 1 else "64x64").split("x"))
    mi = mienv.init("llvm_ad_rgb")
    T = mi.ScalarTransform4f
    scene = {
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": -1},
        "sensor": {
            "type": "perspective",
            "fov": 30,
            "fov_axis": "x",
            "to_world": T().look_at(origin=[0, 0, 4], target=[0, 0, 0], up=[0, 1, 0]),
            "film": {"type": "hdrfilm", "width": w, "height": h, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": spp},
        },
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
    }
    if not empty:
        scene["box"] = {
            "type": "cube",
            "to_world": T().scale(0.5),
            "bsdf": {"type": "null"},
            "interior": {
                "type": "heterogeneous",
                "sigma_t": {
                    "type": "gridvolume",
                    "filename": os.path.abspath(path),
                    "filter_type": "trilinear",
                    "wrap_mode": "clamp",
                    "to_world": T().translate([-0.5, -0.5, -0.5]),
                },
                "scale": 10.0,
                "albedo": {"type": "rgb", "value": 0.9},
                "phase": {"type": "isotropic"},
            },
        }
    t0 = time.perf_counter()
    s = mi.load_dict(scene)
    t1 = time.perf_counter()
    img = mi.render(s, spp=spp)
    mi.TensorXf(img).numpy()  # force the evaluation
    t2 = time.perf_counter()
    img = mi.render(s, spp=spp, seed=1)
    mi.TensorXf(img).numpy()
    t3 = time.perf_counter()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # KiB on Linux
    print(json.dumps({
        "load_seconds": round(t1 - t0, 3),
        "render_seconds": round(t2 - t1, 3),
        "second_render_seconds": round(t3 - t2, 3),
        "peak_resident_bytes": peak,
    }))


if __name__ == "__main__":
    main()
