#!/usr/bin/env python3
"""Writes slivers.obj: the square [-1, 1]^2 of the plane y = 0, facing +y, as a fan of 256
sliver triangles from the corner (-1, 0, -1) (angles down to 0.2 degrees, the thinnest
needle 1e-6 wide), with zero-area triangles mixed in (a repeated vertex, three collinear
vertices on the diagonal). The scenes that use it (../degenerate-triangles.toml,
../sliver-lamp.toml) see the square from above: a ray through a crack between slivers
would see the black background.

Run from this directory: python3 gen_slivers.py
"""

def main():
    corner = (-1.0, 0.0, -1.0)
    # The far edges: z = 1 from x = -1 to 1, then x = 1 from z = 1 to -1.
    rim = []
    n = 128
    for i in range(n + 1):
        rim.append((-1.0 + 2.0 * i / n, 0.0, 1.0))
    for i in range(1, n + 1):
        rim.append((1.0, 0.0, 1.0 - 2.0 * i / n))
    # A needle: one more rim point 1e-6 from the far corner.
    rim.insert(n + 1, (1.0, 0.0, 1.0 - 1e-6))
    verts = [corner] + rim
    faces = []

    def facing_up(a, b, c):
        (ax, _, az), (bx, _, bz), (cx, _, cz) = verts[a], verts[b], verts[c]
        # y component of (b - a) x (c - a)
        y = (bz - az) * (cx - ax) - (bx - ax) * (cz - az)
        return (a, b, c) if y > 0 else (a, c, b)

    for i in range(1, len(verts) - 1):
        faces.append(facing_up(0, i, i + 1))
    # Zero-area triangles: a repeated vertex, and three collinear points on the diagonal.
    diag = len(verts)
    verts += [(-0.5, 0.0, -0.5), (0.0, 0.0, 0.0), (0.5, 0.0, 0.5)]
    faces.append((0, 5, 5))
    faces.append((diag, diag + 1, diag + 2))
    faces.append((diag + 2, diag + 1, diag))
    with open("slivers.obj", "w") as f:
        f.write("# written by gen_slivers.py: a square as slivers and degenerate triangles\n")
        for v in verts:
            f.write("v %.9g %.9g %.9g\n" % v)
        for a, b, c in faces:
            f.write("f %d %d %d\n" % (a + 1, b + 1, c + 1))


main()
