"""ehservo.sweep against `ehservo sweep`'s results.csv."""

import math

import numpy as np
import pandas as pd

import ehservo

STUDY = """
name = "py-sweep"
base = "{base}"
seed = 3
set = ["simulation.horizon=3"]

[[axis]]
key = "controller.kind"
values = ["vsc", "nnvsc", "pid"]

[[axis]]
key = "uncertainty.a_bias"
values = [0.5, 1.0]

[monte_carlo]
runs = 2
draw = [{{ key = "controller.gamma1", dist = "loguniform", low = 50.0, high = 200.0 }}]
"""


def missing(v):
    return v is None or (isinstance(v, float) and math.isnan(v))


def test_sweep_equals_results_csv(cli, repo, tmp_path):
    study = tmp_path / "study.toml"
    study.write_text(STUDY.format(base=(repo / "scenarios/paper/fig2.toml").as_posix()))
    cli("sweep", study, "--out", tmp_path / "cli", "--quiet", "--no-plot")
    want = pd.read_csv(tmp_path / "cli" / "results.csv", keep_default_na=False)
    got = ehservo.sweep(study, threads=2)
    assert list(got.columns) == list(want.columns)
    assert len(got) == len(want) == 3 * 2 * 2
    for c in want.columns:
        for i, (g, w) in enumerate(zip(got[c], want[c])):
            if w == "":  # an empty cell: an undefined metric, or no error
                assert missing(g), (c, i, g)
            elif isinstance(w, str):
                assert str(g).lower() == w.lower(), (c, i, g, w)
            else:
                assert g == w, (c, i, g, w)  # exact: results.csv round-trips
    # The numbers are typed: e_max is float64, the run index an integer.
    assert got["e_max_deg"].dtype == np.float64
    assert got["run"].dtype.kind == "i"


def test_sweep_writes_the_cli_folder_when_asked(repo, tmp_path):
    study = tmp_path / "study.toml"
    study.write_text(STUDY.format(base=(repo / "scenarios/paper/fig2.toml").as_posix()))
    got = ehservo.sweep(study, out=tmp_path / "out", as_frame=False)
    assert isinstance(got, dict)
    written = pd.read_csv(tmp_path / "out" / "results.csv")
    np.testing.assert_array_equal(got["e_max_deg"], written["e_max_deg"].to_numpy())
    assert (tmp_path / "out" / "study.json").is_file()
