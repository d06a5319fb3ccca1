#!/usr/bin/env python3
"""Mitsuba 3's side of issue 36's load and memory figures (benches/README.md, "Load and
memory (issue 36)"): the scene of benches/displaced_sphere.toml built with mi.load_dict
(the OBJ read and the acceleration structure built), then one 1-spp render at 256x256.

Usage (from the Mitsuba harness, which provides the `mitsuba` module):
  ../shared/refs/mitsuba/run.sh $PWD/benches/mitsuba_mesh_load.py target/displaced_sphere.obj
  ../shared/refs/mitsuba/run.sh $PWD/benches/mitsuba_mesh_load.py --empty

Prints one JSON line: load_seconds (mi.load_dict), render_seconds (mi.render, forced),
peak_resident_bytes (ru_maxrss of this process, the whole run). `--empty` loads the same
scene without the mesh: its peak is the baseline subtracted for bytes per triangle, as
benches/empty.toml is for risotto.
"""
import json
import os
import resource
import sys
import time

# The harness is the repository's sibling ../shared/refs/mitsuba, or $MI_HARNESS.
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(
    0, os.environ.get("MI_HARNESS", os.path.join(HERE, "../../shared/refs/mitsuba"))
)
import mienv  # noqa: E402


def main():
    args = sys.argv[1:]
    empty = "--empty" in args
    paths = [a for a in args if not a.startswith("--")]
    if not empty and len(paths) != 1:
        sys.exit(__doc__)
    mi = mienv.init("llvm_ad_rgb")
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 4},
        "sensor": {
            "type": "perspective",
            "fov": 40,
            "fov_axis": "y",
            "to_world": mi.ScalarTransform4f().look_at(
                origin=[0, 0.5, 3.5], target=[0, 0, 0], up=[0, 1, 0]
            ),
            "film": {"type": "hdrfilm", "width": 256, "height": 256},
            "sampler": {"type": "independent", "sample_count": 1},
        },
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
    }
    if not empty:
        scene["m"] = {
            "type": "obj",
            "filename": os.path.abspath(paths[0]),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": 0.6}},
        }
    t0 = time.perf_counter()
    s = mi.load_dict(scene)
    t1 = time.perf_counter()
    img = mi.render(s, spp=1)
    mi.TensorXf(img).numpy()  # force the evaluation
    t2 = time.perf_counter()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # KiB on Linux
    print(json.dumps({
        "load_seconds": round(t1 - t0, 3),
        "render_seconds": round(t2 - t1, 3),
        "peak_resident_bytes": peak,
    }))


if __name__ == "__main__":
    main()
