"""Reference images and per-sample variance for scenes of Mitsuba 3's own test data, made as
Mitsuba's own `test_render.py` makes its references (`render_ref_images`): the scene's `moment`
integrator wrapper gives the first and second moments per pixel (in XYZ); the mean and the
per-sample variance m2 - m1^2 are written as RGB EXRs, NAME_ref_rgb.exr and NAME_ref_rgb_var.exr.

    cd tests/data/mitsuba-data/tests/scenes
    ../../../../../../shared/refs/mitsuba/run.sh ../../make_refs.py ../../refs DIR/SCENE.xml \
        --spp 16384 --pass-spp 1024

(the harness is the repository's sibling `../shared/refs/mitsuba`, or `$MI_HARNESS`).
"""
import argparse
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(
    0, os.environ.get("MI_HARNESS", os.path.join(HERE, "../../../../shared/refs/mitsuba"))
)
import mienv  # noqa: E402

ap = argparse.ArgumentParser()
ap.add_argument("outdir")
ap.add_argument("scenes", nargs="+")
ap.add_argument("--spp", type=int, default=32000)
ap.add_argument("--pass-spp", type=int, default=1000)
ap.add_argument("--variant", default="llvm_ad_rgb")
args = ap.parse_args()

mi = mienv.init(args.variant)
import numpy as np  # noqa: E402

for scene_path in args.scenes:
    name = os.path.splitext(os.path.basename(scene_path))[0]
    t0 = time.time()
    m1 = m2 = None
    passes = max(1, args.spp // args.pass_spp)
    for p in range(passes):
        scene = mi.load_file(scene_path, spp=args.pass_spp)
        scene.integrator().render(scene, seed=p, spp=args.pass_spp, develop=False)
        bmp = scene.sensors()[0].film().bitmap(raw=False)
        split = bmp.split()
        a = np.array(split[1][1], copy=True)
        b = np.array(split[2][1], copy=True)
        m1 = a if m1 is None else m1 + a
        m2 = b if m2 is None else m2 + b
    m1 /= passes
    m2 /= passes
    var = m2 - m1 * m1

    def write(arr, path):
        xyz = mi.Bitmap(arr.astype(np.float32), mi.Bitmap.PixelFormat.XYZ)
        xyz.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, False).write(path)

    os.makedirs(args.outdir, exist_ok=True)
    write(m1, os.path.join(args.outdir, name + "_ref_rgb.exr"))
    write(var, os.path.join(args.outdir, name + "_ref_rgb_var.exr"))
    print(f"{name}: {m1.shape[1]}x{m1.shape[0]}, {passes * args.pass_spp} spp, "
          f"{time.time() - t0:.1f} s, mean {m1.mean():.5f}", flush=True)
