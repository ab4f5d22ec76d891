"""examples/compare.py prints the CLI's numbers and writes its PNG."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "compare.py"


def test_compare_example(cli, repo, tmp_path):
    pytest.importorskip("matplotlib")
    png = tmp_path / "compare.png"
    p = subprocess.run(
        [sys.executable, str(EXAMPLE), "--out", str(png)],
        cwd=repo, capture_output=True, text=True, check=True,
    )
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    printed = {}
    for line in p.stdout.splitlines():
        if line.startswith(("NNBVSC", "PID")):
            printed[line.split()[0]] = float(line.split()[-4])  # e_max_deg
    for label, sets in (("NNBVSC", []), ("PID", ["--set", "controller.kind=pid"])):
        out = tmp_path / label
        cli("run", "scenarios/paper/fig2.toml", "--out", out, "--no-plot", "-q", *sets)
        e_max = json.loads((out / "summary.json").read_text())["metrics"]["e_max_deg"]
        assert printed[label] == e_max


NLSYS = EXAMPLE.parent / "nlsys_loop.py"


def test_nlsys_example(repo, tmp_path):
    """examples/nlsys_loop.py closes the loop in python-control and prints
    e_max; it must track (e_max under a tenth of the 5° amplitude, as in
    test_nlsys.py, whose hand-written loop it equals)."""
    pytest.importorskip("control")
    p = subprocess.run(
        [sys.executable, str(NLSYS)], cwd=tmp_path, capture_output=True, text=True, check=True,
    )
    e_max = float(p.stdout.split("e_max = ")[1].split()[0])
    assert 0 < e_max < 0.5, p.stdout
