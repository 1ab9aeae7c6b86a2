#!/usr/bin/env bash
# Checks that the Python module's build (`pip install ./python`, maturin: `cargo build -p
# dit-garment-python`) compiles every shared dependency with the features and profile that
# `cargo test --workspace` compiled it with, so the wheel reuses the tests' build instead of
# building the graph again. Cargo's workspace feature unification is not stable, so
# python/Cargo.toml lists the dependencies whose features would differ; this compares the two
# builds' unit graphs (a nightly cargo's `--unit-graph`, which only plans: nothing is built)
# and names any unit that the wheel would compile differently. Exit 1 when one would.
set -euo pipefail
cd "$(dirname "$0")/.."
dir="$(mktemp -d)"
trap 'rm -rf "$dir"' EXIT
cargo +nightly test --workspace --no-run --unit-graph -Z unstable-options > "$dir/test.json"
cargo +nightly build -p dit-garment-python --lib --unit-graph -Z unstable-options > "$dir/python.json"
python3 - "$dir/test.json" "$dir/python.json" <<'PY'
import json, sys

def units(path):
    """(package, target, mode) -> {(features, profile without its name)} of one build plan."""
    out = {}
    for unit in json.load(open(path))["units"]:
        profile = dict(unit["profile"])
        profile.pop("name")  # `test` and `dev` share artifacts: cargo hashes the settings only
        key = (unit["pkg_id"].split("#")[-1], unit["target"]["name"], unit["mode"])
        out.setdefault(key, set()).add((tuple(sorted(unit["features"])), json.dumps(profile, sort_keys=True)))
    return out

tests, wheel = units(sys.argv[1]), units(sys.argv[2])
differs = [(key, feats) for key, plans in wheel.items() if key in tests
           for feats, profile in plans if (feats, profile) not in tests[key]]
for (package, target, mode), feats in differs:
    print(f"the wheel would build {package} ({target}, {mode}) with features {list(feats)} "
          f"or another profile; the tests build {sorted(f for f, _ in tests[(package, target, mode)])}")
only = sorted({key[0] for key in wheel if key not in tests})
print(f"feature alignment: {len(differs)} units differ; built for the wheel only: {', '.join(only)}")
sys.exit(1 if differs else 0)
PY
