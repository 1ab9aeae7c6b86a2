"""Reads a `dit-garment dataset tensors` folder with the public safetensors and numpy packages
and prints the shapes of every split's first shard and of the templates as JSON.

    python3 tests/readers/read_tensors.py T

An independent check of the format for the tests (public packages only); users read tensors
with the Python package (`dit_garment.TensorShards`, python/examples/read_tensors.py).
"""

import json
import sys
from pathlib import Path

import numpy as np
from safetensors.numpy import load_file


def main(folder: Path) -> None:
    manifest = json.loads((folder / "manifest.json").read_text())
    out = {}
    for split, info in manifest["splits"].items():
        shard = load_file(folder / info["shards"][0]["file"])
        assert shard["conditions"].dtype == np.float32
        assert shard["targets"].shape[1:] == (3, manifest["resolution"], manifest["resolution"])
        out[split] = {name: list(array.shape) for name, array in shard.items()}
    templates = load_file(folder / "templates.safetensors")
    out["templates"] = {name: list(array.shape) for name, array in templates.items()}
    # Normalized targets, as a training loader would use them.
    stats = manifest["normalization"]["targets"]
    first = load_file(folder / manifest["splits"]["train"]["shards"][0]["file"])["targets"]
    mean = np.array(stats["mean"], dtype=np.float32)[None, :, None, None]
    std = np.array(stats["std"], dtype=np.float32)[None, :, None, None]
    normalized = (first - mean) / std
    out["normalized_finite"] = bool(np.isfinite(normalized).all())
    print(json.dumps(out))


if __name__ == "__main__":
    main(Path(sys.argv[1]))
