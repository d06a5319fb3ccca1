#!/usr/bin/env bash
# Interleaved side-by-side efficiency: R rounds of (1 risotto run, 1 Mitsuba process with
# 2 repeats, the second timed); medians of the render times; RMSE of the last images.
set -euo pipefail
S=$1; R=${R:-5}
ROOT=$(cd "$(dirname "$0")/.." && pwd); BIN=${BIN:-$ROOT/target/release/risotto}; MI=${MI:-$ROOT/../shared/refs/mitsuba}
D=${OUT:-$(mktemp -d)}; mkdir -p $D; cd $D
REF=$MI/ref/$S.exr
rt=(); mt=()
for k in $(seq $R); do
  $BIN render $ROOT/scenes/mitsuba-suite/$S.toml --spp 64 --threads 2 --quiet --out r.exr --stats s.json
  rt+=($(python3 -c "import json;print(json.load(open('s.json'))['wall_seconds'])"))
  ( cd $MI && ./run.sh render.py $S --variant llvm_ad_rgb --spp 64 --repeats 2 -D sampler=ldsampler --out $D/m.exr --json $D/m.json ) > m.log 2>&1
  mt+=($(python3 -c "import json;print(json.load(open('m.json'))['render_times_s'][1])"))
done
rr=$($BIN compare r.exr $REF | awk '$1=="all"{print $2}')
rm_=$($BIN compare m.exr $REF | awk '$1=="all"{print $2}')
python3 - "$S" "$rr" "$rm_" "${rt[*]}" "${mt[*]}" "$MI/ref/manifest.json" <<'PY'
import json,sys,statistics as st
s,rr,rm=sys.argv[1],float(sys.argv[2]),float(sys.argv[3])
rt=[float(x) for x in sys.argv[4].split()]; mt=[float(x) for x in sys.argv[5].split()]
noise=json.load(open(sys.argv[6]))[s]['noise_rmse']
Tr,Tm=st.median(rt),st.median(mt)
raw=(rm*rm*Tm)/(rr*rr*Tr)
mr,mm=rr*rr-noise**2, rm*rm-noise**2
sub=(mm*Tm)/(mr*Tr) if mr>0 else float('inf')
print(f"{s}: risotto {Tr:.3f}s {['%.2f'%x for x in rt]} RMSE {rr:.5f} | mitsuba {Tm:.3f}s {['%.2f'%x for x in mt]} RMSE {rm:.5f} | ratio {raw:.2f}x (reference noise {noise:.5f} subtracted: {sub:.2f}x)")
PY
