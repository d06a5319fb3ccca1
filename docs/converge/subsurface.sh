#!/usr/bin/env bash
# Regenerates docs/converge/subsurface/: error against time of the two subsurface modes
# (`subsurface = random_walk | diffusion`) on scenes/subsurface-thin.toml (a back-lit thin
# slab and fin, where diffusion's half-space profile is wrong), 4 to 64 spp, two seeds per
# point, against a reference rendered with the random walk (1024 spp, its own noise
# estimated from two halves and subtracted). Diffusion is faster per sample; its error stops
# falling at its bias. Run from the repository root:
#
#   docs/converge/subsurface.sh
set -euo pipefail
mkdir -p docs/converge/subsurface
cargo run --release -- converge scenes/subsurface-thin.toml \
    --techniques subsurface=random_walk,subsurface=diffusion \
    --reference-technique subsurface=random_walk --reference-spp 1024 \
    --spp 4,8,16,32,64 --repeats 2 --out docs/converge/subsurface \
    | tee docs/converge/subsurface/table.txt
