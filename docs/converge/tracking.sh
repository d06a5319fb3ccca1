#!/usr/bin/env bash
# Regenerates docs/converge/tracking/: error against time of the heterogeneous-medium
# estimators (`tracking = ratio | residual | delta | ray_marching | unbiased_ray_marching`)
# on the Mitsuba hetero_grid scene, 1 to 64 spp, two seeds per point, against the Mitsuba
# reference (6144 spp). Run from the repository root:
#
#   docs/converge/tracking.sh [REFERENCE.exr]
#
# REFERENCE defaults to the harness's ../shared/refs/mitsuba/ref/hetero_grid.exr; when it is
# missing the reference is rendered (2048 spp with ratio tracking, its noise subtracted).
# Render times depend on the machine and its load: compare the curves with each other.
set -euo pipefail
ref="${1:-../shared/refs/mitsuba/ref/hetero_grid.exr}"
if [[ -f "$ref" ]]; then
    reference=(--reference "$ref")
else
    echo "tracking.sh: $ref not found, rendering the reference" >&2
    reference=(--reference-spp 2048 --reference-technique tracking=ratio)
fi
mkdir -p docs/converge/tracking
cargo run --release -- converge scenes/mitsuba-suite/hetero_grid.toml "${reference[@]}" \
    --techniques tracking=ratio,tracking=residual,tracking=delta,tracking=ray_marching,tracking=unbiased_ray_marching \
    --spp 1,2,4,8,16,32,64 --repeats 2 --out docs/converge/tracking \
    | tee docs/converge/tracking/table.txt
