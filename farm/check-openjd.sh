#!/usr/bin/env bash
# Validates farm/risotto-render.yaml with openjd-cli (installed from PyPI into a throwaway
# venv), runs it locally on farm/tiny.toml (2x2 tiles x 2 sample chunks, then the merge) and
# checks the merged image against a one-process render (equal up to the f64 summation
# order of the sample chunks: at most about one f32 ulp, far below the 1e-5 allowed here);
# the run uses Aovs=true, so the merge must also carry the AOVs (their layers' exactness is
# tests/farm.rs's).
set -euo pipefail
cd "$(dirname "$0")/.."
risotto="$PWD/${RISOTTO:-target/release/risotto}"
[ -x "$risotto" ] || cargo build --release --quiet
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 -m venv "$work/venv"
"$work/venv/bin/pip" install --quiet openjd-cli
openjd="$work/venv/bin/openjd"
"$openjd" check farm/risotto-render.yaml
"$openjd" run farm/risotto-render.yaml --step Merge --run-dependencies \
  -p Scene="$PWD/farm/tiny.toml" -p OutputDir="$work/out" -p Risotto="$risotto" \
  -p TileColumns=2 -p TileRows=2 -p SampleChunks=2 -p Aovs=true >"$work/openjd.log" 2>&1 \
  || { cat "$work/openjd.log"; exit 1; }
test "$(ls "$work"/out/parts/*.exr | wc -l)" -eq 8
"$risotto" info "$work/out/render.exr" | grep -q '"aovs":true' \
  || { echo "the merged image carries no AOVs"; exit 1; }
"$risotto" render farm/tiny.toml --partial --quiet --out "$work/one.exr"
"$risotto" compare "$work/out/render.exr" "$work/one.exr" | awk '
  /^all/ { found = 1; if ($5 + 0 > 1e-5) { print "merged differs from one-process render: maxabs " $5; bad = 1 } }
  END { if (!found) print "no comparison"; exit (!found || bad) }'
echo "OpenJD template: valid; its 2x2x2 run (with AOVs) merged to the one-process render"
