#!/usr/bin/env bash
# Regenerates docs/converge/emission/: error against time of light sampling an emissive
# medium (`lighting = mis`, the only technique that samples volume lights) against
# gathering its emission along path rays alone (`lighting = bxdf`) on scenes/fire.toml, a
# room lit only by a flame (a heterogeneous medium with an emission grid), 1 to 32 spp, two
# seeds per point, against a 1024-spp MIS reference whose own noise is subtracted. (`nee`
# samples no volume light, so in this room it is `bxdf`.) Run from the repository root:
#
#   docs/converge/emission.sh
#
# Render times depend on the machine and its load: compare the curves with each other.
set -euo pipefail
mkdir -p docs/converge/emission
cargo run --release -- converge scenes/fire.toml \
    --reference-spp 1024 --reference-technique lighting=mis \
    --techniques lighting=mis,lighting=bxdf \
    --spp 1,2,4,8,16,32 --repeats 2 --out docs/converge/emission \
    | tee docs/converge/emission/table.txt
