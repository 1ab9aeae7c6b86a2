"""Prints the ablation table of docs/SURROGATE_ARMS.md from `tools/ablation.sh` results: per arm
and split, E_v (cm) / E_c (%) / stretch_p99 / fps of the guided and unguided model, beside the
no-learning baselines.

    python3 tools/ablation_table.py OUT [ARM ...]
"""

import json
import sys
from pathlib import Path

SPLITS = [("shipped", "train"), ("shipped", "test_garment"), ("shipped", "test_motion"),
          ("shipped", "test"), ("heldout", "test")]
NAMES = {("shipped", "train"): "train (2 seq.)", ("shipped", "test_garment"): "test_garment",
         ("shipped", "test_motion"): "test_motion",
         ("shipped", "test"): "test, unseen shape + material",
         ("heldout", "test"): "held-out test (paper's)"}


def load(path):
    return json.loads(path.read_text()) if path.exists() else None


def cell(row, fps=True):
    if row is None:
        return "-"
    text = f"{row['E_v']:.2f} / {row['E_c']:.2f} / {row['stretch_p99']:.2f}"
    return text + (f" / {row['fps']:.1f}" if fps else "")


def main(out, arms):
    evals = out / "eval"
    if not arms:
        arms = sorted({p.name.rsplit("-", 1)[0] for p in evals.glob("a*-shipped.json")})
    header = ["split"] + [f"{a} guided" for a in arms] + [f"{a} unguided" for a in arms] + \
        ["lbs", "lbs_nearest", "rest", "floor"]
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for data, split in SPLITS:
        base = load(evals / f"baselines-{data}.json")
        row = [NAMES[(data, split)]]
        for method in ("model", "model_no_guidance"):
            for arm in arms:
                j = load(evals / f"{arm}-{data}.json")
                row.append(cell(j and j["splits"].get(split, {}).get(method)))
        for b in ("lbs", "lbs_nearest", "rest", "floor"):
            row.append(cell(base and base["splits"].get(split, {}).get(b), fps=False))
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main(Path(sys.argv[1]), sys.argv[2:])
