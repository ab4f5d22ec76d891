"""The frequency domain against python-control: the models ``ehservo.linearize``
exports give ``control.margin`` and ``control.frequency_response`` the
margins and responses ``ehservo freq`` writes, to 1e-6 relative; and the
PID's Fig. 2 loop assembled here from the plant's equations (9) and the
PID's (crates/ehservo-core/src/control/pid.rs), discretised by scipy's
``c2d``, gives the same margins. Skipped without python-control
(``pip install control``); ci/python.sh installs it."""

import csv
import json
import math

import numpy as np
import pytest

import ehservo

ct = pytest.importorskip("control")

REL = 1e-6

# (scenario, overrides): linear controllers on the Fig. 2 servo, with and
# without a valve and delays.
CASES = {
    "pid-fig2": ("docs/league/suite/scenarios/pid/fig2.toml", []),
    "pid-valve-delays": (
        "scenarios/realistic/base.toml",
        ["controller.kind=pid", "sensor.delay=3", "simulation.computation_delay=true"],
    ),
    "adrc-fig2": ("scenarios/league/adrc-fig2.toml", []),
    "pid-10ms-valve": ("scenarios/realistic/base-10ms.toml", ["controller.kind=pid"]),
    # The state feedback reads (θ, θ̇, θ̈): its loop closes through the
    # plant's three measured channels (ω_h·h ≤ 1 wants the 1 ms sample;
    # the delays give L a phase crossover).
    "sf-fig2-1ms-delays": (
        "docs/league/suite/scenarios/pid/fig2.toml",
        [
            "controller.kind=state-feedback",
            "simulation.step=0.001",
            "sensor.delay=2",
            "simulation.computation_delay=true",
        ],
    ),
}


def _freq(cli, tmp_path, path, sets):
    """Runs `ehservo freq` (computed only); returns freq.json and
    response.csv's columns as arrays."""
    out = tmp_path / "f"
    args = ["freq", path, "--out", out, "--measure", "none", "--no-plot", "-q"]
    for s in sets:
        args += ["--set", s]
    cli(*args)
    summary = json.loads((out / "freq.json").read_text())
    with open(out / "response.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    cols = {
        k: np.array([float(r[k]) if r[k] else np.nan for r in rows]) for k in rows[0]
    }
    return summary, cols


def _rel(a, b):
    return abs(a - b) / max(abs(a), abs(b))


def _curve(cols, name):
    re = [k for k in cols if k.startswith(f"{name}_re")][0]
    im = [k for k in cols if k.startswith(f"{name}_im")][0]
    return cols[re] + 1j * cols[im]


def _response(sys, omega):
    r = ct.frequency_response(sys, omega)
    return np.ravel(r.complex)


@pytest.mark.parametrize("case", sorted(CASES))
def test_margins_match_python_control(case, cli, repo, tmp_path, monkeypatch):
    monkeypatch.chdir(repo)
    path, sets = CASES[case]
    lin = ehservo.linearize(path, set=sets)
    summary, _ = _freq(cli, tmp_path, path, sets)
    m = summary["computed"]["margins"]
    # Every crossover ehservo reports, checked on python-control's own
    # evaluation of the exported L: |L| = 1 at a gain crossover with the
    # phase margin there, ∠L = −180° at a phase crossover with |L| = 1/GM.
    for g in m["gain_crossovers"]:
        L = _response(lin.loop, [g["omega_rad_s"]])[0]
        assert abs(abs(L) - 1.0) < REL, (g, abs(L))
    pmw = m["phase_margin"]
    L = _response(lin.loop, [pmw["omega_rad_s"]])[0]
    assert abs(((math.degrees(np.angle(L)) + 180.0) % 360.0) - pmw["phase_margin_deg"]) < 1e-6
    for p in m["phase_crossovers"]:
        L = _response(lin.loop, [p["omega_rad_s"]])[0]
        assert abs(L.imag) < REL * abs(L) and L.real < 0, (p, L)
    how = {}  # python-control's default: poly, or frd where it doubts poly
    gm, pm, wpc, wgc = ct.margin(lin.loop)
    if abs(abs(_response(lin.loop, [wgc])[0]) - 1.0) > REL:
        # python-control's default ('poly') method puts the state
        # feedback's gain crossover where its own frequency_response has
        # |L| = 0.93 (python-control 0.10.2): its 'frd' method is the one its
        # responses confirm.
        how = {"method": "frd"}
        gm, pm, _, wpc, wgc, _ = ct.stability_margins(lin.loop, **how)
    assert math.isfinite(gm) and math.isfinite(pm), (gm, pm)
    assert _rel(gm, m["gain_margin"]["gain_margin"]) < REL, (gm, m["gain_margin"])
    assert _rel(wpc, m["gain_margin"]["omega_rad_s"]) < REL, (wpc, m["gain_margin"])
    assert _rel(pm, m["phase_margin"]["phase_margin_deg"]) < REL, (pm, m["phase_margin"])
    assert _rel(wgc, m["phase_margin"]["omega_rad_s"]) < REL, (wgc, m["phase_margin"])
    # Every crossover python-control finds (at ω > 0) is ehservo's.
    gms, pms, sms, wpcs, wgcs, wms = ct.stability_margins(lin.loop, returnall=True, **how)
    ours_p = sorted(p["omega_rad_s"] for p in m["phase_crossovers"])
    theirs_p = sorted(w for w, g in zip(wpcs, gms) if w > 0 and math.isfinite(g) and g > 1e-10)
    assert len(ours_p) == len(theirs_p), (ours_p, theirs_p)
    for a, b in zip(ours_p, theirs_p):
        assert _rel(a, b) < REL
    ours_g = sorted(g["omega_rad_s"] for g in m["gain_crossovers"])
    assert len(ours_g) == len(wgcs) and all(_rel(a, b) < REL for a, b in zip(ours_g, sorted(wgcs)))
    # The stability margin is 1/Ms.
    assert _rel(min(sms), 1.0 / summary["computed"]["Ms"]["value"]) < REL
    # The closed loop's poles.
    cl = ct.feedback(lin.loop, 1)
    ours = summary["computed"]["closed_loop_stable"]
    assert ours == bool(np.all(np.abs(cl.poles()) < 1.0))


@pytest.mark.parametrize("case", sorted(CASES))
def test_responses_match_python_control(case, cli, repo, tmp_path, monkeypatch):
    monkeypatch.chdir(repo)
    path, sets = CASES[case]
    lin = ehservo.linearize(path, set=sets)
    _, cols = _freq(cli, tmp_path, path, sets)
    w = cols["omega_rad_s"]
    L = lin.loop
    models = {
        "G": lin.plant,
        "Gd": ct.series(lin.computation_delay, lin.plant_discrete, lin.sensor_delay),
        "C": lin.feedback,
        "L": L,
        "S": ct.feedback(ct.ss([], [], [], [[1.0]], L.dt), L),
        "T": ct.feedback(L, 1),
    }
    if lin.measured is not None:
        # C is then the feedback on θm equivalent to the row: L/Gd.
        models["C"] = None
    for name, sys in models.items():
        if sys is None:
            theirs = _response(L, w) / _response(models["Gd"], w)
        else:
            theirs = _response(sys, w)
        ours = _curve(cols, name)
        err = np.max(np.abs(ours - theirs) / np.abs(theirs))
        assert err < REL, f"{name}: relative error {err:.3e}"


def test_the_pid_loop_from_the_plants_equations(cli, repo, tmp_path, monkeypatch):
    """The tuned PID on Fig. 2 (kp, ki, kd given; Tf = max(kd/kp/10, dt) =
    dt = 0.01 s), written out here: the third-order model (8)–(9) with the
    Fig. 2 variation (Δa_i = ā_i, δb = 0.25) and the load 2·sin 4θ
    linearised at θ = 0, discretised by python-control's c2d (scipy's expm);
    the PID's forward-Euler filter and integral. Its margins and L are
    ehservo's."""
    monkeypatch.chdir(repo)
    path = "docs/league/suite/scenarios/pid/fig2.toml"
    summary, cols = _freq(cli, tmp_path, path, [])
    # Section IV's parameters (SI).
    Ps, be, Vt, Kce, Dm = 13.795e6, 344.875e6, 1.639e-4, 2.376e-12, 8.195e-6
    Jt, Bm, Kv, G, rho, Cd, Ag = 5.652e-2, 8.477, 0.508, 1.13e-3, 850.0, 0.67, 3.385e-7
    k = 4 * be / (Vt * Jt)
    a1 = k * Kce * G
    a2 = G / Jt + k * Dm * Dm + k * Kce * Bm
    a3 = Bm / Jt + 4 * be * Kce / Vt
    b0 = 4 * be * Dm * Kv / (Vt * Jt) * Cd * Ag * math.sqrt(Ps / rho)
    # The true plant: 2ā_i, 1.25·b̄; the load A·sin(kθ) ≈ A·k·θ adds
    # 4βe·Kce/(Vt·Jt)·A·k to a1 (through d) and A·k/Jt to a2 (Ṫl/Jt).
    Ak = 2.0 * 4.0
    A1 = 2 * a1 + 4 * be * Kce / (Vt * Jt) * Ak
    A2 = 2 * a2 + Ak / Jt
    A3 = 2 * a3
    Gc = ct.ss([[0, 1, 0], [0, 0, 1], [-A1, -A2, -A3]], [[0], [0], [1.25 * b0]], [[1, 0, 0]], [[0]])
    dt = 0.01
    Gd = ct.c2d(Gc, dt, "zoh")
    kp, ki, kd = 48.54715122129958, 847.2086758795634, 0.8646373394270577
    Tf = max(kd / kp / 10, dt)
    z = ct.tf([1, 0], [1], dt)
    C = kp + ki * dt / (z - 1) + (kd / Tf) * (1 - (dt / Tf) / (z - 1 + dt / Tf))
    L = C * Gd
    gm, pm, wpc, wgc = ct.margin(L)
    m = summary["computed"]["margins"]
    assert _rel(gm, m["gain_margin"]["gain_margin"]) < REL
    assert _rel(pm, m["phase_margin"]["phase_margin_deg"]) < REL
    assert _rel(wgc, m["phase_margin"]["omega_rad_s"]) < REL
    w = cols["omega_rad_s"]
    err = np.max(np.abs(_curve(cols, "L") - _response(L, w)) / np.abs(_response(L, w)))
    assert err < REL, err
    # And the continuous plant's poles are ehservo's.
    lin = ehservo.linearize(path)
    ours = np.sort_complex(np.array([complex(*p) for p in lin.data["plant_with_actuator"]["poles"]]))
    theirs = np.sort_complex(Gc.poles())
    assert np.max(np.abs(ours - theirs) / np.abs(theirs)) < 1e-9


def test_python_models_are_the_json(repo, monkeypatch):
    """The ss objects carry the JSON's matrices, time bases and names."""
    monkeypatch.chdir(repo)
    lin = ehservo.linearize("scenarios/league/adrc-fig2.toml")
    assert lin.plant.dt == 0 and lin.loop.dt == 0.01
    assert list(lin.controller.input_labels) == [
        "theta_m", "theta_d", "theta_d_dot", "theta_d_ddot", "theta_d_dddot",
    ]
    assert set(lin.parts) == {"observer", "law"}
    assert lin.parts["observer"].dt == 0.01 and lin.controller.dt == 0.01
    A = np.array(lin.data["plant_with_actuator"]["ss"]["A"])
    np.testing.assert_array_equal(lin.plant.A, A)
    # A kink is refused with the key, and built one-sided on request.
    text = "[plant.params]\nKce = 0.0\n[controller]\nkind = \"pid\"\n"
    with pytest.raises(ehservo.ScenarioError) as e:
        ehservo.linearize(text, trim=10.0)
    assert e.value.key == "--trim" and "not differentiable" in e.value.reason
    lo = ehservo.linearize(text, trim=10.0, side="minus")
    hi = ehservo.linearize(text, trim=10.0, side="plus")
    assert lo.plant.B[2, 0] > hi.plant.B[2, 0]


def test_freq_from_python_is_the_clis_on_a_cylinder(cli, repo, tmp_path, monkeypatch):
    """``ehservo.freq`` writes the CLI's folder and returns its freq.json:
    on the slide (a linear axis, mm and m/V) with the state feedback, equal
    to the CLI's to the bit, and nothing in it is in degrees or radians of
    the position."""
    monkeypatch.chdir(repo)
    path = "scenarios/cylinders/slide.toml"
    ours = ehservo.freq(path, out=tmp_path / "py", side="plus", measure="none", plot=False)
    cli("freq", path, "--side", "plus", "--measure", "none", "--no-plot", "-q", "--out", tmp_path / "cli")
    theirs = json.loads((tmp_path / "cli" / "freq.json").read_text())
    assert ours == theirs
    assert (tmp_path / "py" / "response.csv").read_bytes() == (tmp_path / "cli" / "response.csv").read_bytes()
    text = json.dumps(ours)
    assert "theta" not in text and "rad/V" not in text and "_deg" not in text.replace("phase_margin_deg", "")
    m = ours["computed"]["margins"]
    assert m["gain_margin"]["gain_margin_dB"] > 0 and m["phase_margin"]["phase_margin_deg"] > 0
    lin = ehservo.linearize(path, side="plus")
    assert lin.axis == "linear" and "y = 180 mm" in repr(lin)
    assert lin.measured is not None and lin.feedback.ninputs == 3
