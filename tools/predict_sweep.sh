#!/bin/bash
# The sampler sweep of docs/SURROGATE.md: steps 1, 2, 4, 8, 20 with and without guidance,
# per-frame noise, the push-out and a second seed, each predicted with `--config-from SIM`
# and scored against SIM by `compare`. One TSV row per run on stdout.
#
# Usage: tools/predict_sweep.sh RUN SIM.mcap OUT_DIR   (release build: cargo build --release)
set -euo pipefail
if [ $# -ne 3 ]; then
  echo "usage: $0 RUN SIM.mcap OUT_DIR" >&2
  exit 2
fi
run=$1 sim=$2 out=$3
bin=${DIT_GARMENT:-$(dirname "$0")/../target/release/dit-garment}
mkdir -p "$out"

one() {
  local tag=$1
  shift
  "$bin" predict --model "$run" --config-from "$sim" --out "$out/$tag.mcap" \
    --json "$out/$tag.json" --quiet "$@" >/dev/null
  "$bin" compare "$sim" "$out/$tag.mcap" --json "$out/$tag.compare.json" >/dev/null
  python3 - "$out" "$tag" "$*" <<'PY'
import json, sys
out, tag, flags = sys.argv[1:]
p = json.load(open(f"{out}/{tag}.json"))
c = json.load(open(f"{out}/{tag}.compare.json"))
print(f"{tag}\t{flags}\tE_v {c['E_v']:.3f}\tE_c {c['E_c']:.3f}\tE_c_vertex {c['E_c_vertex']:.3f}"
      f"\tmax_penetration_mm {1000 * p['max_penetration_m']:.1f}"
      f"\tjitter {c['jitter']:.4f} (simulation {c['jitter_a']:.4f})"
      f"\tframes_per_s {p['frames_per_s']:.1f}\tpushed {p['pushed_vertices']}", flush=True)
PY
}

for steps in 1 2 4 8 20; do
  for guidance in 0 5; do
    one "s${steps}g${guidance}" --steps "$steps" --guidance "$guidance"
  done
done
one s4_per_frame --steps 4 --per-frame-noise
one s8_per_frame --steps 8 --per-frame-noise
one s4_push_out --steps 4 --resolve-penetration
one s4_seed1 --steps 4 --seed 1
