"""Fixtures shared by the package's tests: the command-line binary (to compare against) and a
tiny dataset synthesized once per session."""

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


def _binary() -> Path | None:
    given = os.environ.get("DIT_GARMENT_BIN")
    if given:
        return Path(given)
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    for profile in ("debug", "release"):
        candidate = target / profile / "dit-garment"
        if candidate.is_file():
            return candidate
    return None


@pytest.fixture(scope="session")
def cli():
    """Runs the command line; fails the test where it exits non-zero."""
    binary = _binary()
    if binary is None:
        if os.environ.get("DIT_GARMENT_REQUIRE_BIN"):
            pytest.fail("DIT_GARMENT_BIN is required here and no dit-garment binary was found")
        pytest.skip("no dit-garment binary (set DIT_GARMENT_BIN or build the workspace)")

    def run(*args: str) -> subprocess.CompletedProcess:
        out = subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True)
        assert out.returncode == 0, f"{args}: {out.stderr}"
        return out

    return run


@pytest.fixture(scope="session")
def tiny_dataset(cli, tmp_path_factory) -> Path:
    """The tiny example spec synthesized (3 test sequences and 1 train sequence)."""
    root = tmp_path_factory.mktemp("tiny")
    spec = root / "spec.toml"
    spec.write_text(cli("synth", "--example-spec", "tiny").stdout)
    out = root / "data"
    cli("synth", "--spec", spec, "--out", out, "--quiet")
    return out


@pytest.fixture(scope="session")
def tiny_tensors(cli, tiny_dataset, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("tensors") / "t"
    cli("dataset", "tensors", tiny_dataset, "--out", out, "--quiet")
    return out


def pytest_runtest_logreport(report):
    """A skip is never silent: appended to `$DIT_GARMENT_SKIP_LOG` (test, what, why) as the
    Rust tests' skips are, which `.ci/run` lists after the tests."""
    log = os.environ.get("DIT_GARMENT_SKIP_LOG")
    if not report.skipped or not log:
        return
    reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else str(report.longrepr)
    with open(log, "a") as f:
        f.write(f"{report.nodeid}\tPYTHON\t{reason}\n")
