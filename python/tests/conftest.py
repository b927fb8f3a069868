"""Shared fixtures: the repository's root, and the compiled modules' right-hand sides."""

import json
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


@pytest.fixture(scope="session")
def compiled_rhs():
    """Every committed module's f(t, x) at states near its initial one, built by rustc
    (`generated/examples/rhs_values.rs`); `MULTIBODY_RHS_VALUES` may name a file it wrote."""
    given = os.environ.get("MULTIBODY_RHS_VALUES")
    if given:
        return json.loads(Path(given).read_text())
    out = subprocess.run(
        ["cargo", "run", "--release", "-q", "-p", "generated", "--example", "rhs_values"],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(out.stdout)
