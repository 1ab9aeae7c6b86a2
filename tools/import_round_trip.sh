#!/usr/bin/env bash
# Issue 57's round trip (docs/GARMENTS.md, "The worked example"): a GarmentCode pattern sewn into
# a template, simulated on a posed, shaped body, one frame written as a plain mesh (no UVs),
# imported back from that frame's pose, then predicted through the motion and scored against
# the engine's frames with the correspondence-free metrics, beside the prediction made from the
# pattern's own template. Usage: tools/import_round_trip.sh BINARY WORKDIR [PATTERN or DESIGN] [MODEL]
# IMPORT_FLAGS (environment) are passed to `garments import` (e.g. "--guide-stiffness 0"); the
# simulation and the original's prediction are kept in WORKDIR and reused.
set -euo pipefail
bin=$(realpath "$1"); work=$2
pattern=${3:-../shared/testdata/garmentcode/shirt_mean_specification.json}
[ -e "$pattern" ] && pattern=$(realpath "$pattern")  # else a library design's name
model=${4:-builtin}
motion=(--motion walk --betas 1.0,-0.5 --blend-frames 10 --settle-frames 5 --frames 35)
mkdir -p "$work" && cd "$work"
[ -f original.obj ] || "$bin" garments make "$pattern" --out original.obj --report original.json
if [ ! -f sim/rec.mcap ]; then
  "$bin" simulate --garment original.obj "${motion[@]}" --out sim/rec.mcap --obj-dir sim/obj --obj-every 1
fi
rm -rf cap && mkdir cap && cp sim/obj/garment_*.obj cap/
grep -v '^vt' cap/garment_0034.obj \
  | sed -E 's#^f ([0-9]+)/[0-9]+ ([0-9]+)/[0-9]+ ([0-9]+)/[0-9]+#f \1 \2 \3#' > worn.obj
"$bin" garments import worn.obj --motion walk --frame 19 --betas 1.0,-0.5 \
  --out imported.obj --report imported.json ${IMPORT_FLAGS:-} || echo "import: a gate failed (template written)"
for t in original imported; do
  [ "$t" = original ] && [ -f score_original.json ] && continue
  "$bin" predict --model "$model" --garment "$t.obj" "${motion[@]}" --out "pred_$t.mcap"
  "$bin" compare cap "pred_$t.mcap" --json "score_$t.json" > /dev/null
done
python3 - <<'PY'
import json
import numpy as np
def mesh(path):
    v, f = [], []
    for l in open(path):
        if l.startswith("v "):
            v.append([float(x) for x in l.split()[1:4]])
        elif l.startswith("f "):
            f.append([int(t.split("/")[0]) - 1 for t in l.split()[1:4]])
    return np.array(v), np.array(f)
def samples(v, f, n, rng):
    # Area-uniform points on the surface (METRICS.md: 50,000 per mesh, seeded).
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    area = np.linalg.norm(np.cross(b - a, c - a), axis=1)
    k = rng.choice(len(f), n, p=area / area.sum())
    r1, r2 = np.sqrt(rng.random(n)), rng.random(n)
    return (1 - r1)[:, None] * a[k] + (r1 * (1 - r2))[:, None] * b[k] + (r1 * r2)[:, None] * c[k]
def one_way(a, b):
    # Mean distance from each point of a to its nearest of b, in chunks (no SciPy needed).
    b2 = (b ** 2).sum(1)
    d = [np.sqrt(np.maximum(((p ** 2).sum(1)[:, None] - 2 * p @ b.T + b2).min(1), 0))
         for p in np.array_split(a, max(1, len(a) // 256))]
    return np.concatenate(d).mean()
def chamfer_cm(a, b):
    return 50 * (one_way(a, b) + one_way(b, a))
(va, fa), (vb, fb) = mesh("original.obj"), mesh("imported.obj")
rng = np.random.default_rng(0)
sa, sb = samples(va, fa, 50000, rng), samples(vb, fb, 50000, rng)
print(f"template E_CD_cm {chamfer_cm(sa, sb):.3f} (50,000 surface samples each, METRICS.md; "
      f"the original against 50,000 more of its own: {chamfer_cm(sa, samples(va, fa, 50000, rng)):.3f}); "
      f"vertices to nearest vertices {chamfer_cm(va, vb):.3f}")
for t in ("original", "imported"):
    s = json.load(open(f"score_{t}.json"))
    print(t, {k: s[k] for k in ("E_CD_cm", "distance_p90_cm", "E_n", "E_c") if k in s})
PY
