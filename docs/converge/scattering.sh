#!/usr/bin/env bash
# Regenerates docs/converge/scattering/: error against time of the scattering techniques of
# homogeneous media (`scattering = multiple | walk | bounce | single`) on the Mitsuba
# smoke_homog scene (a smoke cube with a diffuse sphere inside, lit by an area light), 1 to
# 64 spp, two seeds per point, against the Mitsuba reference. `single` is an approximation
# (no higher orders): its error stops falling at its bias. Run from the repository root:
#
#   docs/converge/scattering.sh [REFERENCE.exr]
#
# REFERENCE defaults to the harness's ../shared/refs/mitsuba/ref/smoke_homog.exr; when it is
# missing the reference is rendered (2048 spp, its noise subtracted).
set -euo pipefail
ref="${1:-../shared/refs/mitsuba/ref/smoke_homog.exr}"
if [[ -f "$ref" ]]; then
    reference=(--reference "$ref")
else
    echo "scattering.sh: $ref not found, rendering the reference" >&2
    reference=(--reference-spp 2048)
fi
mkdir -p docs/converge/scattering
cargo run --release -- converge scenes/mitsuba-suite/smoke_homog.toml "${reference[@]}" \
    --techniques scattering=multiple,scattering=walk,scattering=bounce,scattering=single \
    --spp 1,2,4,8,16,32,64 --repeats 2 --out docs/converge/scattering \
    | tee docs/converge/scattering/table.txt
