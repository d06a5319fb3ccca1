#!/usr/bin/env bash
# Regenerates docs/converge/adaptive/: error against time of adaptive sampling
# (`adaptive=on`, the window stopping rule, and `adaptive=unbiased`: renders at noise
# targets 0.4, 0.2, 0.1, 0.05, at most 2048 spp per pixel, 16 at least) against uniform sampling (16 to 2048 spp) on scenes/adaptive-smoke-ball.toml, a
# noisy smoky glass ball beside smooth lit walls. Two seeds per point, against a reference
# the tool renders uniformly (16384 spp, its own noise estimated from two halves and
# subtracted). Run from the repository root:
#
#   docs/converge/adaptive.sh
set -euo pipefail
mkdir -p docs/converge/adaptive
cargo run --release -- converge scenes/adaptive-smoke-ball.toml \
    --techniques lighting=mis,adaptive=on,adaptive=unbiased \
    --spp 16,32,64,128,256,512,1024,2048 --noise-targets 0.4,0.2,0.1,0.05 \
    --reference-spp 16384 --repeats 2 --threads 2 \
    --out docs/converge/adaptive --quiet \
    | tee docs/converge/adaptive/table.txt
