"""Estimates what an ensemble of trained models would score on a dataset's `test` split,
without code in the product: each model predicts every sequence (`dit-garment predict
--config-from`, its default sampler), the predictions are averaged vertex by vertex, and E_v
is computed on the frames `evaluate` scores (every 5th motion frame). Single-model rows
reproduce `evaluate`'s E_v, which checks the scoring. docs/SURROGATE_ARMS.md, "An ensemble".

usage: python3 tools/ensemble_estimate.py BIN DATA OUT NAME=MODEL [NAME=MODEL ...]
  BIN   the dit-garment binary; DATA a dataset folder (`synth --out`); OUT a folder for the
  predictions and ensemble.json; MODEL a run or ensemble folder, `builtin` or `builtin-single`.
"""
import itertools
import json
import os
import subprocess
import sys
import tomllib

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from read_recording import read  # noqa: E402


def main(binary, data, out, models):
    os.makedirs(out, exist_ok=True)
    with open(f"{data}/spec.toml", "rb") as f:
        sequence = tomllib.load(f)["sequence"]
    # The first scored frame: after the blend-in and settle frames.
    first = sequence["blend_frames"] + sequence["settle_frames"]
    lines = [json.loads(line) for line in open(f"{data}/manifest.jsonl")]
    sequences = [s for s in lines if s["split"] == "test" and s["status"] == "ok"]
    results = {}
    for s in sequences:
        truth_path = f"{data}/sequences/{s['id']}.mcap"
        truth = read(truth_path)[2]
        predicted = {}
        for name, model in models.items():
            path = f"{out}/{name}-{s['id']}.mcap"
            if not os.path.exists(path):
                subprocess.run(
                    [binary, "predict", "--model", model, "--config-from", truth_path, "--out", path,
                     "--threads", "1", "--quiet"],
                    check=True, stdout=subprocess.DEVNULL)
            predicted[name] = read(path)[2]
        frames = range(first, truth.shape[0], 5)

        def e_v(p):
            return float(np.mean([np.linalg.norm(p[f] - truth[f], axis=1).mean() for f in frames]) * 100)

        row = {}
        for k in range(1, len(models) + 1):
            for combo in itertools.combinations(models, k):
                row["+".join(combo)] = e_v(np.mean([predicted[c] for c in combo], axis=0))
        results[s["id"]] = row
        print(s["id"], s["garment"], {k: round(v, 2) for k, v in row.items()}, flush=True)
    mean = {k: float(np.mean([r[k] for r in results.values()])) for k in next(iter(results.values()))}
    for k, v in sorted(mean.items(), key=lambda kv: kv[1]):
        print(f"{v:.3f}  {k}")
    with open(f"{out}/ensemble.json", "w") as f:
        json.dump({"first_scored_frame": first, "per_sequence": results, "mean": mean}, f, indent=1)


if __name__ == "__main__":
    if len(sys.argv) < 5:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], sys.argv[3], dict(a.split("=", 1) for a in sys.argv[4:]))
