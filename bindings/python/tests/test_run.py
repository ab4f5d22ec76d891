"""ehservo.run against `ehservo run`: the same metrics and trace, bit for bit."""

import json

import numpy as np
import pandas as pd
import pytest

import ehservo

FIG2 = "scenarios/paper/fig2.toml"


def cli_run(cli, tmp_path, scenario, *sets):
    out = tmp_path / "out"
    args = ["run", scenario, "--out", out, "--no-plot", "-q"]
    for s in sets:
        args += ["--set", s]
    cli(*args)
    summary = json.loads((out / "summary.json").read_text())
    trace = pd.read_csv(out / "trace.csv")
    return summary, trace


def test_fig2_e_max_equals_the_cli_exactly(cli, repo, tmp_path, monkeypatch):
    monkeypatch.chdir(repo)
    summary, trace = cli_run(cli, tmp_path, FIG2)
    r = ehservo.run(FIG2)
    assert r.metrics["e_max_deg"] == summary["metrics"]["e_max_deg"]
    # Every metric, with summary.json's None for the undefined ones.
    assert r.metrics == summary["metrics"]
    assert r.divergence is None and summary["divergence"] is None
    assert r.faults == summary["faults"]
    assert r.name == "fig2"
    # The trace: trace.csv's columns in order, every value to the bit
    # (trace.csv prints the shortest decimal that reads back to the f64).
    assert list(r.trace.columns) == list(trace.columns)
    assert len(r.trace) == len(trace) == 1001
    for c in trace.columns:
        np.testing.assert_array_equal(r.trace[c].to_numpy(), trace[c].to_numpy(), err_msg=c)


def test_trace_without_pandas_is_a_dict_of_float_arrays(repo, monkeypatch):
    monkeypatch.chdir(repo)
    r = ehservo.run(FIG2, as_frame=False)
    assert isinstance(r.trace, dict)
    t = r.trace["t_s"]
    assert isinstance(t, np.ndarray) and t.dtype == np.float64 and t.shape == (1001,)
    # t_k = k·h, computed in Rust as k as f64 * h.
    np.testing.assert_array_equal(t, np.arange(1001) * 0.01)
    # e = θd − θ in the trace's own columns.
    np.testing.assert_allclose(
        r.trace["e_deg"], r.trace["theta_d_deg"] - r.trace["theta_deg"], rtol=0, atol=1e-12
    )


@pytest.mark.parametrize(
    "kwargs, sets",
    [
        ({"controller__gamma1": 2.0}, ["controller.gamma1=2.0"]),
        ({"set": {"controller.gamma1": 200}}, ["controller.gamma1=200"]),
        ({"set": ["controller.kind=pid"]}, ["controller.kind=pid"]),
        ({"controller__kind": "vsc-sat", "controller__mu": 0.5},
         ["controller.kind=vsc-sat", "controller.mu=0.5"]),
        ({"surface__poles": [-10, -20, -30.5]}, ["surface.poles=[-10,-20,-30.5]"]),
        ({"simulation__substeps": 4, "output__decimate": 7},
         ["simulation.substeps=4", "output.decimate=7"]),
    ],
)
def test_overrides_mean_what_set_means(cli, repo, tmp_path, monkeypatch, kwargs, sets):
    monkeypatch.chdir(repo)
    summary, trace = cli_run(cli, tmp_path, FIG2, *sets)
    r = ehservo.run(FIG2, **kwargs)
    assert r.metrics == summary["metrics"]
    assert list(r.trace.columns) == list(trace.columns)
    assert len(r.trace) == len(trace)
    np.testing.assert_array_equal(r.trace["u_V"].to_numpy(), trace["u_V"].to_numpy())


def test_keyword_overrides_come_after_set():
    assert ehservo.overrides({"a.b": 1}, a__b=2.5, c="vsc", d=True, e=[1, "x"]) == [
        "a.b=1",
        "a.b=2.5",
        "c=vsc",
        "d=true",
        'e=[1, "x"]',
    ]


def test_toml_text_and_defaults(repo, monkeypatch):
    monkeypatch.chdir(repo)
    by_file = ehservo.run(FIG2, controller__gamma1=200)
    by_text = ehservo.run('name = "fig2"\n[controller]\ngamma1 = 200\n')
    assert by_text.metrics == by_file.metrics
    # No scenario at all: the defaults, which are the paper's Fig. 2 case.
    assert ehservo.run().metrics == ehservo.run(FIG2).metrics


def test_check_prints_what_the_cli_prints(cli, repo, monkeypatch):
    monkeypatch.chdir(repo)
    out = cli("check", FIG2, "--set", "controller.gamma1=50").stdout
    assert ehservo.check(FIG2, controller__gamma1=50) + "" in (out, out.rstrip("\n"))


def test_a_diverging_run_reports_what_summary_json_reports(cli, repo, tmp_path, monkeypatch):
    """Fig. 3 (the traditional VSC at the printed set-up) leaves |θ| ≤ 1 rad."""
    monkeypatch.chdir(repo)
    summary, trace = cli_run(cli, tmp_path, "scenarios/paper/fig3.toml")
    r = ehservo.run("scenarios/paper/fig3.toml")
    assert summary["divergence"] is not None
    assert r.divergence == summary["divergence"]
    assert r.metrics == summary["metrics"] and r.metrics["diverged"] is True
    assert len(r.trace) == len(trace)
    np.testing.assert_array_equal(r.trace["theta_deg"].to_numpy(), trace["theta_deg"].to_numpy())


def test_a_cylinder_is_read_in_mm_as_the_cli_writes_it(cli, repo, tmp_path, monkeypatch):
    """On a linear axis (the shipped single-rod cylinder) the metrics carry
    e_max/e_rms with unit "mm" beside them, exactly summary.json's, no key
    or column says "deg", and the trace is trace.csv's, y_mm and e_mm among
    it, to the bit."""
    monkeypatch.chdir(repo)
    sc = "scenarios/cylinders/chrono-single-rod.toml"
    sets = ["simulation.horizon=1.0", "simulation.settle=0.5"]
    summary, trace = cli_run(cli, tmp_path, sc, *sets)
    r = ehservo.run(sc, set=sets)
    assert r.metrics["unit"] == "mm"
    assert r.metrics == summary["metrics"]
    assert not any("deg" in k for k in r.metrics), r.metrics
    assert list(r.trace.columns) == list(trace.columns)
    assert "y_mm" in trace.columns and "e_mm" in trace.columns
    assert not any("deg" in c for c in trace.columns), list(trace.columns)
    for c in trace.columns:
        np.testing.assert_array_equal(r.trace[c].to_numpy(), trace[c].to_numpy(), err_msg=c)
    # The rod starts at 142 mm on its reference (the scenario's x0).
    assert r.trace["y_mm"].iloc[0] == pytest.approx(142.0, abs=1e-9)
