#!/usr/bin/env bash
# Regenerates docs/converge/fire-bidir/: error against time of the global integrators
# (`integrator = path | light | bdpt | vcm`) on scenes/fire.toml at 160x120, a room lit only
# by a flame of emissive, scattering gas: the flame is a volume light to every one of them
# (light subpaths start in it, camera vertices sample it and connect to those subpaths; the
# path tracer samples it under `lighting = mis`). 1 to 64 spp, two seeds per point, against
# a 2048-spp path-traced reference rendered by converge (two halves, their noise
# subtracted), compared by the relMSE (the flame seen directly, which every integrator
# sees alike, would dominate the plain MSE). Run from the repository root:
#
#   docs/converge/fire-bidir.sh
#
# Render times depend on the machine and its load: compare the curves with each other.
set -euo pipefail
out=docs/converge/fire-bidir
mkdir -p "$out"
cargo run --release -- converge scenes/fire.toml -D render.width=160 -D render.height=120 \
    --techniques integrator=path,integrator=light,integrator=bdpt,integrator=vcm \
    --reference-technique integrator=path --reference-spp 2048 \
    --spp 1,4,16,64 --repeats 2 --threads 2 --metric relmse --out "$out" --quiet \
    | tee "$out/table.txt"
