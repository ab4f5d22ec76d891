"""Shared fixtures: the repository, and the `ehservo` command line whose
outputs the bindings must reproduce to the bit."""

import os
import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]


def _find_cli():
    env = os.environ.get("EHSERVO_CLI")
    if env:
        if not Path(env).is_file():
            raise RuntimeError(f"EHSERVO_CLI={env}: no such file")
        return env
    for p in (
        REPO / "target" / "release" / "ehservo",
        REPO / "target" / "debug" / "ehservo",
        REPO / "bindings" / "python" / "target" / "debug" / "ehservo",
    ):
        if p.is_file():
            return str(p)
    return shutil.which("ehservo")


@pytest.fixture(scope="session")
def repo():
    return REPO


@pytest.fixture(scope="session")
def cli():
    """Runs the CLI from the repository root; returns the CompletedProcess."""
    exe = _find_cli()
    if exe is None:
        pytest.skip(
            "no ehservo binary: build it (cargo build -p ehservo) or set EHSERVO_CLI"
        )

    def call(*args, check=True):
        return subprocess.run(
            [exe, *map(str, args)],
            cwd=REPO,
            capture_output=True,
            text=True,
            check=check,
        )

    return call
