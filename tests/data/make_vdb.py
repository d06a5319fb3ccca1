#!/usr/bin/env python3
"""Writes tests/data/small.vdb and tests/data/tile.vdb, the OpenVDB files of the grid-reader
tests (engine/loader/src/grid_file/vdb.rs). Needs OpenVDB's Python module (Debian: python3-openvdb;
run with /usr/bin/python3). The committed files are what this wrote; CI never runs it.

small.vdb: grids "density" (float), "temperature" (float), "velocity" (vec3s). density has
5 x 4 x 3 active voxels at index (i - 2, j + 3, k + 7) with value 1 + i + 10 j + 100 k,
voxel size 0.5. tile.vdb: "density", one active 8^3 tile of 0.25 at index (0, 0, 0).
"""
import pyopenvdb as vdb

g = vdb.FloatGrid()
g.name = "density"
acc = g.getAccessor()
for i in range(5):
    for j in range(4):
        for k in range(3):
            acc.setValueOn((i - 2, j + 3, k + 7), 1.0 + i + 10 * j + 100 * k)
g.transform = vdb.createLinearTransform(voxelSize=0.5)
t = vdb.FloatGrid()
t.name = "temperature"
t.getAccessor().setValueOn((0, 0, 0), 2.0)
v = vdb.Vec3SGrid()
v.name = "velocity"
v.getAccessor().setValueOn((0, 0, 0), (1, 2, 3))
vdb.write("small.vdb", grids=[g, t, v])

h = vdb.FloatGrid()
h.name = "density"
h.fill((0, 0, 0), (7, 7, 7), 0.25, True)
h.prune()
vdb.write("tile.vdb", grids=[h])
