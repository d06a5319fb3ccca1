#!/usr/bin/env bash
# Regenerates docs/converge/lighting/: error against time of the direct-lighting techniques
# (`lighting = mis | nee | bxdf`) on scenes/near-lamp.toml, a large lamp just above a diffuse
# floor, where sampling the Bxdf beats sampling the light and MIS beats both (the Cornell
# box's light is small and far, and there MIS and NEE tie: docs/converge/cornell.sh). 1 to
# 256 spp, three seeds per point, against a reference the tool renders with MIS (4096 spp,
# its own noise estimated from two halves and subtracted). Run from the repository root:
#
#   docs/converge/lighting.sh
set -euo pipefail
mkdir -p docs/converge/lighting
cargo run --release -- converge scenes/near-lamp.toml --reference-spp 4096 \
    --reference-technique lighting=mis --techniques lighting=mis,lighting=nee,lighting=bxdf \
    --spp 1,2,4,8,16,32,64,128,256 --repeats 3 --out docs/converge/lighting \
    | tee docs/converge/lighting/table.txt
