"""ehservo.Controller: the sampled loop the simulator runs, stepped from
Python."""

import math

import numpy as np
import pytest

import ehservo

FIG2 = "scenarios/paper/fig2.toml"


@pytest.mark.parametrize("sets", [{}, {"controller.kind": "pid"}, {"controller.kind": "vsc-sat"}])
def test_replaying_a_run_gives_its_commands_bit_for_bit(repo, monkeypatch, sets):
    """Feed the controller what the simulator's controller saw at every
    sample (t, x, z from run(raw=True)): u and every logged part equal the
    trace's, to the bit. Only `uncertainty`, which needs the true plant, is
    unknown (NaN) outside the simulator."""
    monkeypatch.chdir(repo)
    r = ehservo.run(FIG2, set=sets, raw=True, as_frame=False)
    c = ehservo.Controller(FIG2, set=sets)
    tr = r.trace
    cols = {s.column: s.key for s in c.signals if s.column}
    assert [k for k in tr if k in cols] == list(cols)  # the trace's part columns, in order
    u = np.empty(len(tr["t_s"]))
    parts = {k: np.empty_like(u) for k in cols.values()}
    for k in range(len(u)):
        x = (tr["x0_ctrl_rad"][k], tr["x1_ctrl_rad_s"][k], tr["x2_ctrl_rad_s2"][k])
        z = (tr["z0_rad"][k], tr["z1_rad_s"][k], tr["z2_rad_s2"][k], tr["z3_rad_s3"][k])
        out = c.step(tr["t_s"][k], x, z)
        u[k] = out["u"]
        for key in parts:
            parts[key][k] = out[key]
    np.testing.assert_array_equal(u, tr["u_V"])
    for col, key in cols.items():
        if key == "uncertainty":
            assert np.isnan(parts[key]).all()
        else:
            np.testing.assert_array_equal(parts[key], tr[col], err_msg=col)
    # The weights moved (NNBVSC): ‖W‖ of the last step is the trace's.
    if c.kind == "nnvsc":
        assert np.linalg.norm(c.weights()) > 1.0


def test_reference_is_the_scenarios(repo, monkeypatch):
    monkeypatch.chdir(repo)
    c = ehservo.Controller(FIG2)
    a, w = math.radians(5.0), 2 * math.pi  # the paper's 5° at 1 Hz
    z = c.reference(0.1)
    np.testing.assert_allclose(
        z,
        [a * math.sin(w * 0.1), a * w * math.cos(w * 0.1),
         -a * w**2 * math.sin(w * 0.1), -a * w**3 * math.cos(w * 0.1)],
        rtol=1e-12,
    )
    assert c.dt == 0.01 and c.kind == "nnvsc"


def test_first_sample_by_hand(repo, monkeypatch):
    """At t = 0, x = 0, W = 0 (nnvsc.rs works this sample out by hand):
    σ = 90·θ̇d(0) = 90·A·2π with A = 5° in rad."""
    monkeypatch.chdir(repo)
    c = ehservo.Controller(FIG2)
    out = c.step(0.0, (0.0, 0.0, 0.0))
    assert out["sigma"] == pytest.approx(90 * math.radians(5.0) * 2 * math.pi, rel=1e-12)
    assert out["wphi"] == 0.0 and out["flags"] == 0
    assert out["u"] == pytest.approx(out["u_eq"] + out["u_sw"], rel=1e-12)


def test_pid_parts_and_a_bad_measurement(repo, monkeypatch):
    monkeypatch.chdir(repo)
    c = ehservo.Controller(FIG2, controller__kind="pid")
    keys = [s.key for s in c.signals]
    assert {"p", "i", "d"} <= set(keys)
    good = c.step(0.0, (0.0, 0.0, 0.0))
    bad = c.step(0.01, (float("nan"), 0.0, 0.0))
    assert bad["flags"] & 4  # MEASUREMENT_FAULT: the safe command (hold the last)
    assert bad["u"] == good["u"] and c.faults == 1
    c.reset()
    assert c.faults == 0
    with pytest.raises(ValueError, match="expected 3 values"):
        c.step(0.0, (0.0, 0.0))
