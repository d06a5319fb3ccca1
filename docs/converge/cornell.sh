#!/usr/bin/env bash
# Regenerates docs/converge/cornell.{png,svg,csv,json}, the "Accuracy and its cost" figure of
# the README: every technique that applies to the Mitsuba cornell box (lighting mis / nee /
# bxdf, sampler sobol / independent) at 1 to 256 spp, three seeds per point, against the
# Mitsuba reference (8192 spp). Run from the repository root:
#
#   docs/converge/cornell.sh [REFERENCE.exr]
#
# REFERENCE defaults to the Mitsuba harness's ../shared/refs/mitsuba/ref/cornell.exr; when it
# is missing the reference is rendered (4096 spp, its noise estimated and subtracted).
# Render times depend on the machine and its load: compare the curves with each other.
set -euo pipefail
ref="${1:-../shared/refs/mitsuba/ref/cornell.exr}"
if [[ -f "$ref" ]]; then
    reference=(--reference "$ref")
else
    echo "cornell.sh: $ref not found, rendering the reference" >&2
    reference=(--reference-spp 4096)
fi
cargo run --release -- converge scenes/mitsuba-suite/cornell.toml "${reference[@]}" \
    --spp 1,2,4,8,16,32,64,128,256 --repeats 3 --out docs/converge/cornell \
    | tee docs/converge/cornell/table.txt
