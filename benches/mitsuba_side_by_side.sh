#!/usr/bin/env bash
# Interleaved side-by-side efficiency: R rounds (default 5) of (1 risotto run, 1 Mitsuba process
# with 2 repeats, the second timed), round k with seed k in both renderers; medians of the render
# times; errors from all R images of each (benches/side_by_side_error.py).
# REF=path.exr (and REF_NOISE_MSE) measure against another reference than the harness's.
# The analysis alone, on kept images: $MI/run.sh benches/side_by_side_error.py SCENE $MI DIR R "TIMES" "TIMES".
set -euo pipefail
S=$1; R=${R:-5}
ROOT=$(cd "$(dirname "$0")/.." && pwd); BIN=${BIN:-$ROOT/target/release/risotto}; MI=${MI:-$ROOT/../shared/refs/mitsuba}
D=${OUT:-$(mktemp -d)}; mkdir -p $D; cd $D
rt=(); mt=()
for k in $(seq $R); do
  $BIN render $ROOT/scenes/mitsuba-suite/$S.toml --spp 64 --threads 2 --quiet --seed $k --out r$k.exr --stats s.json
  rt+=($(python3 -c "import json;print(json.load(open('s.json'))['wall_seconds'])"))
  ( cd $MI && ./run.sh render.py $S --variant llvm_ad_rgb --spp 64 --repeats 2 --seed $k -D sampler=ldsampler --out $D/m$k.exr --json $D/m.json ) > m.log 2>&1
  mt+=($(python3 -c "import json;print(json.load(open('m.json'))['render_times_s'][1])"))
done
$MI/run.sh $ROOT/benches/side_by_side_error.py "$S" "$MI" "$D" "$R" "${rt[*]}" "${mt[*]}"
