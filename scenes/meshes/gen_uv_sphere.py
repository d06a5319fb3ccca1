#!/usr/bin/env python3
"""Writes uv_sphere.obj: a unit UV sphere (48 segments in phi, 24 rings in theta) with
vertex normals (`vn`, the unit position) and texture coordinates (`vt`, u = phi / 2pi from
+x towards +y, v = theta / pi from +z: the parameterisation of risotto's analytic sphere),
the seam and pole vertices duplicated so uv is continuous on every triangle, faces wound
counter-clockwise seen from outside, the degenerate pole triangles left out.

Usage: python3 gen_uv_sphere.py [NU NV] > uv_sphere.obj   (default 48 24)
"""
import math
import sys

nu, nv = (int(sys.argv[1]), int(sys.argv[2])) if len(sys.argv) > 2 else (48, 24)
pos, uv = [], []
for i in range(nv + 1):
    for j in range(nu + 1):
        u, v = j / nu, i / nv
        th, ph = v * math.pi, u * 2 * math.pi
        pos.append((math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)))
        uv.append((u, v))
out = [f"# unit UV sphere {nu} x {nv}, written by gen_uv_sphere.py"]
out += [f"v {x:.7f} {y:.7f} {z:.7f}" for x, y, z in pos]
out += [f"vt {u:.7f} {v:.7f}" for u, v in uv]
out += [f"vn {x:.7f} {y:.7f} {z:.7f}" for x, y, z in pos]
at = lambda i, j: i * (nu + 1) + j + 1
for i in range(nv):
    for j in range(nu):
        a, b, c, d = at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)
        if i + 1 < nv:
            out.append(f"f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}")
        if i > 0:
            out.append(f"f {a}/{a}/{a} {c}/{c}/{c} {d}/{d}/{d}")
print("\n".join(out))
