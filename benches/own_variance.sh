#!/usr/bin/env bash
# A render's own variance and time, no reference needed: R seeds (default 6) of SCENE (a scene
# file) at its own spp, 2 threads; prints the per-pixel variance across the seeds (RGB mean,
# unbiased), the same restricted to an optional pixel block, and the median render time.
# Extra arguments go to `risotto render` (e.g. `--technique sampler=independent`).
# Uses the Mitsuba harness's Python (numpy, EXR loading): ../shared/refs/mitsuba/setup.sh.
#   benches/own_variance.sh scenes/mitsuba-suite/smoke_homog.toml
#   BLOCK=32:64,96:160 benches/own_variance.sh scenes/mitsuba-suite/smoke_homog.toml
set -euo pipefail
S=$1; shift; R=${R:-6}
ROOT=$(cd "$(dirname "$0")/.." && pwd); BIN=${BIN:-$ROOT/target/release/risotto}; MI=${MI:-$ROOT/../shared/refs/mitsuba}
D=${OUT:-$(mktemp -d)}; mkdir -p "$D"
for k in $(seq "$R"); do
  "$BIN" render "$S" --threads 2 --quiet --seed "$k" --out "$D/r$k.exr" --stats "$D/s$k.json" "$@"
done
"$MI/run.sh" "$ROOT/benches/own_variance.py" "$MI" "$D" "$R" "${BLOCK:-}"
