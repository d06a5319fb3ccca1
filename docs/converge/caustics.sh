#!/usr/bin/env bash
# Regenerates docs/converge/caustics-NAME/ for the three scenes of scenes/caustics/: error
# against time of the global integrators (`integrator = path | bdpt | vcm`), 1 to 64 spp, two
# seeds per point, against a bdpt reference rendered by converge itself (REF_SPP spp as two
# independent halves whose difference, its own noise, is subtracted from every error),
# compared by the relMSE: the plain MSE of the two sphere scenes is almost all in the few
# pixels of the lamp's images in the glass, which every integrator samples alike (see
# scenes/caustics/README.md).
# Run from the repository root:
#
#   docs/converge/caustics.sh [REF_SPP]      # default 1024
set -euo pipefail
ref_spp="${1:-1024}"
for name in glass-sphere-caustic fog-caustic window-room; do
    out="docs/converge/caustics-$name"
    mkdir -p "$out"
    cargo run --release -- converge "scenes/caustics/$name.toml" \
        --techniques integrator=path,integrator=bdpt,integrator=vcm \
        --reference-technique integrator=bdpt --reference-spp "$ref_spp" \
        --spp 1,4,16,64 --repeats 2 --metric relmse --out "$out" \
        | tee "$out/table.txt"
done
