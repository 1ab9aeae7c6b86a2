#!/usr/bin/env bash
# The UV round-trip floor of every library design on `walk` at 32, 64 and 128 texels, for both
# targets (docs/SURROGATE.md): simulates each design once (skipped when its recording exists,
# so a stopped run resumes), then runs `dit-garment uv` on it and prints a Markdown table.
# Usage: tools/uv_floor.sh [OUT_DIR]   (default out/uv-floor; needs a release build)
set -euo pipefail
cd "$(dirname "$0")/.."
BIN="${DIT_GARMENT_BIN:-target/release/dit-garment}"
OUT="${1:-out/uv-floor}"
mkdir -p "$OUT"
designs=$("$BIN" garments list --json "$OUT/designs.json" >/dev/null && python3 -c "
import json, sys
print(' '.join(d['name'] for d in json.load(open(sys.argv[1]))))" "$OUT/designs.json")
for d in skirt $designs; do
  [ -f "$OUT/$d.mcap" ] || "$BIN" simulate --garment "$d" --motion walk --quiet \
      --out "$OUT/$d.mcap" --json "$OUT/$d.sim.json" >/dev/null
  for r in 32 64 128; do
    for t in displacement lbs_residual; do
      j="$OUT/$d.$r.$t.json"
      [ -f "$j" ] || "$BIN" uv "$OUT/$d.mcap" --resolution "$r" --target "$t" \
          --out "$OUT/pictures/$d-$r-$t" --json "$j" >/dev/null
    done
  done
done
python3 - "$OUT" skirt $designs <<'PY'
import json, sys
out, names = sys.argv[1], sys.argv[2:]
print("| design | R | coverage | charts | texel cm | floor mean / p95 / max cm (displacement) | mean target cm (displacement) | floor mean / p95 / max cm (lbs_residual) | mean target cm (lbs_residual) |")
print("|---|---|---|---|---|---|---|---|---|")
for n in names:
    for r in (32, 64, 128):
        d = json.load(open(f"{out}/{n}.{r}.displacement.json"))
        l = json.load(open(f"{out}/{n}.{r}.lbs_residual.json"))
        f = lambda x: f"{x['roundtrip_E_v_cm']:.3f} / {x['roundtrip_p95_cm']:.3f} / {x['roundtrip_max_cm']:.2f}"
        print(f"| {n} | {r} | {d['coverage']:.2f} | {d['charts']} | {d['texel_cm']:.2f} | {f(d)} | {d['target_mean_cm']:.2f} | {f(l)} | {l['target_mean_cm']:.2f} |")
PY
