#!/usr/bin/env python3
"""Checks the FMUs of `ehservo fmu` with FMPy (ci/ffi.sh runs it).

  python3 ci/fmu_check.py CONTROLLER.fmu CLOSED_LOOP.fmu SUMMARY.json \
      [--linear LINEAR_CLOSED_LOOP.fmu LINEAR_SUMMARY.json] \
      [--plant PLANT.fmu TRACE.csv]...

1. FMPy's model-description validation passes for both FMUs.
2. The closed-loop FMU simulated by fmpy.simulate_fmu (its default
   experiment: 10 s, output every 0.01 s) gives summary.json's e_max_deg:
   the FMU's own e_max_deg output at the end, and max |e_deg| over
   t >= 2 s of the recorded outputs.
3. The controller FMU, driven sample by sample through FMPy's FMU3Slave,
   fed the closed-loop FMU's measurements (theta, theta_dot, theta_ddot)
   at every sample, returns the closed loop's command u every sample.
4. The controller FMU closing the loop on a plant simulated in Python (the
   independent NumPy plant of bench/peers/nnvsc_numpy.py, eq. (8) with the
   Fig. 2 bias, RK4 at 0.01 s) gives summary.json's e_max_deg.

5. Calls made wrong (a step before initialisation, a NaN input, an unknown
   value reference, a step that is not a whole number of periods) return
   fmi3Error.

6. With --linear, a closed-loop FMU of a cylinder (a linear axis) reads
   in mm: its variables are y (m), y_dot, y_ddot, y_d, e (m), e_mm and
   e_max (mm), no name or unit says deg or rad, and simulated by
   fmpy.simulate_fmu over its default experiment its e_max output at the
   end and max |e_mm| over t >= settle (the FMU's resources/scenario.toml)
   are the run's summary.json metrics.e_max (unit "mm").

7. With --plant (repeatable), a plant FMU (`ehservo fmu --plant`) passes
   FMPy's validation, declares its position in m (linear) or rad (rotary)
   and its pressures in Pa displayed in bar, and simulated by
   fmpy.simulate_fmu with the input table u(t) = the run's u_V column of
   TRACE.csv (the run of the same scenario) gives the run's position,
   velocity and pressures in the trace's units (mm or deg, Pa), every
   sample, to 1e-9 of each column's largest magnitude.

Relative tolerance 1e-6 for the e_max comparisons; u in check 3 must be
the same double. Exit 1 on any failure.
"""

import atexit
import json
import math
import os
import shutil
import sys
import types

import fmpy
from fmpy import read_model_description, extract, simulate_fmu
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

REL = 1e-6
SETTLE = 2.0


def rel_err(a, b):
    return abs(a - b) / abs(b)


def extracted(path):
    """The FMU unzipped into a temporary folder removed at exit."""
    d = extract(path)
    atexit.register(shutil.rmtree, d, ignore_errors=True)
    return d


def instantiate(path):
    md = read_model_description(path)
    d = extracted(path)
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=d,
                    modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName=os.path.basename(path))
    fmu.instantiate()
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    return md, fmu, vrs


def check_linear(loop_path, summary_path, check):
    """6: a cylinder's closed-loop FMU, in mm."""
    import tomllib

    with open(summary_path) as f:
        metrics = json.load(f)["metrics"]
    expected = metrics["e_max"]
    check(metrics.get("unit") == "mm", f"linear: summary.json's metrics unit is {metrics.get('unit')!r}")
    problems = validate_fmu(loop_path)
    check(not problems, f"{os.path.basename(loop_path)}: FMPy validation "
          + ("passes" if not problems else f"fails: {problems}"))
    md = read_model_description(loop_path)
    units = {v.name: v.unit or (v.declaredType.unit if v.declaredType else None)
             for v in md.modelVariables}
    want = {"y": "m", "y_dot": "m/s", "y_ddot": "m/s2", "y_d": "m", "e": "m",
            "e_mm": "mm", "e_max": "mm"}
    got = {k: units.get(k) for k in want}
    check(got == want, f"linear: variables and units {got}")
    stray = [n for n, u in units.items() if "deg" in n or "theta" in n or (u or "") in ("deg", "rad")]
    check(not stray, f"linear: no variable in degrees or radians ({stray})")
    with open(os.path.join(extracted(loop_path), "resources", "scenario.toml"), "rb") as f:
        settle = tomllib.load(f)["simulation"]["settle"]
    res = simulate_fmu(loop_path, output=["e_mm", "e_max", "y"])
    t = res["time"]
    e_max_out = float(res["e_max"][-1])
    e_max_rec = max(abs(float(e)) for tt, e in zip(t, res["e_mm"]) if tt >= settle - 1e-9)
    check(rel_err(e_max_out, expected) <= REL,
          f"linear closed loop: output e_max = {e_max_out!r} mm, run {expected!r} mm "
          f"(rel. diff {rel_err(e_max_out, expected):.2e})")
    check(rel_err(e_max_rec, expected) <= REL,
          f"linear closed loop: max |e_mm| over t >= {settle} s = {e_max_rec!r} mm "
          f"(rel. diff {rel_err(e_max_rec, expected):.2e})")


def check_plant(plant_path, trace_path, check):
    """7: a plant FMU under the run's commands gives the run's trace."""
    import csv

    import numpy as np

    name = os.path.basename(plant_path)
    problems = validate_fmu(plant_path)
    check(not problems, f"{name}: FMPy validation "
          + ("passes" if not problems else f"fails: {problems}"))
    with open(trace_path, newline="") as f:
        rows = list(csv.DictReader(f))
    cols = rows[0].keys()
    linear = "y_mm" in cols
    md = read_model_description(plant_path)
    var = {v.name: v for v in md.modelVariables}
    # FMU name -> (trace column, factor from the FMU's SI unit to the trace's)
    if linear:
        pos = {"y": ("y_mm", 1e3), "y_dot": ("y_dot_mm_s", 1e3)}
        check(var["y"].unit == "m" and var["f_load"].unit == "N",
              f"{name}: y in {var['y'].unit}, f_load in {var['f_load'].unit}")
    else:
        pos = {"theta": ("theta_deg", 180.0 / math.pi), "theta_dot": ("theta_dot_deg_s", 180.0 / math.pi)}
        check(var["theta"].unit == "rad", f"{name}: theta in {var['theta'].unit}")
    pressures = [n for n, v in var.items() if v.unit == "Pa"]
    check(pressures and all(getattr(var[n], "displayUnit", "bar") == "bar" for n in pressures),
          f"{name}: pressures {pressures} in Pa, displayed in bar")
    compare = dict(pos)
    compare.update({n: (f"{n}_Pa", 1.0) for n in pressures if f"{n}_Pa" in cols})
    t = np.array([float(r["t_s"]) for r in rows])
    # Every input in the table (f_load, on a cylinder, at 0 N as in the run).
    inputs = ["u"] + (["f_load"] if "f_load" in var else [])
    signals = np.array([(tt, float(r["u_V"])) + (0.0,) * (len(inputs) - 1) for tt, r in zip(t, rows)],
                       dtype=[("time", np.float64)] + [(n, np.float64) for n in inputs])
    h = float(md.defaultExperiment.stepSize)
    res = simulate_fmu(plant_path, input=signals, output=list(compare), stop_time=float(t[-1]),
                       output_interval=h)
    check(len(res) == len(rows) and np.allclose(res["time"], t, rtol=0, atol=1e-9 * h),
          f"{name}: {len(res)} samples to t = {res['time'][-1]} (the trace: {len(rows)})")
    for n, (col, factor) in compare.items():
        want = np.array([float(r[col]) for r in rows])
        got = res[n][: len(want)] * factor
        worst = float(np.max(np.abs(got - want)))
        scale = float(np.max(np.abs(want))) or 1.0
        check(worst <= 1e-9 * scale,
              f"{name}: {n} under the run's u against the trace's {col}: "
              f"worst difference {worst:.3g} (largest |{col}| {scale:.6g})")


def main():
    ctl_path, loop_path, summary_path = sys.argv[1:4]
    linear = None
    plants = []
    rest = sys.argv[4:]
    while rest:
        if rest[0] not in ("--linear", "--plant") or len(rest) < 3:
            print(__doc__)
            return 2
        if rest[0] == "--linear":
            linear = rest[1:3]
        else:
            plants.append(rest[1:3])
        rest = rest[3:]
    with open(summary_path) as f:
        expected = json.load(f)["metrics"]["e_max_deg"]
    failures = []

    def check(ok, what):
        print(("ok   " if ok else "FAIL ") + what)
        if not ok:
            failures.append(what)

    print(f"FMPy {fmpy.__version__}; ehservo run's e_max_deg = {expected!r}")

    # 1. validation
    for p in (ctl_path, loop_path):
        problems = validate_fmu(p)
        check(not problems, f"{os.path.basename(p)}: FMPy validation "
              + ("passes" if not problems else f"fails: {problems}"))

    # 2. the closed loop through simulate_fmu
    res = simulate_fmu(loop_path, output=["e_deg", "e_max_deg", "theta"])
    t = res["time"]
    n = len(t)
    e_max_out = float(res["e_max_deg"][-1])
    e_max_rec = max(abs(float(e)) for tt, e in zip(t, res["e_deg"]) if tt >= SETTLE - 1e-9)
    check(n == 1001 and abs(t[-1] - 10.0) < 1e-9, f"closed loop: {n} samples to t = {t[-1]}")
    check(rel_err(e_max_out, expected) <= REL,
          f"closed loop: output e_max_deg = {e_max_out!r} (rel. diff {rel_err(e_max_out, expected):.2e})")
    check(rel_err(e_max_rec, expected) <= REL,
          f"closed loop: max |e_deg| over t >= 2 s = {e_max_rec!r} (rel. diff {rel_err(e_max_rec, expected):.2e})")

    # 3. the controller FMU fed the loop's measurements
    md_c, ctl, vc = instantiate(ctl_path)
    md_l, loop, vl = instantiate(loop_path)
    h = float(md_c.defaultExperiment.stepSize)
    steps = round(float(md_c.defaultExperiment.stopTime) / h)
    xs = [vl["theta"], vl["theta_dot"], vl["theta_ddot"]]
    xin = [vc["theta"], vc["theta_dot"], vc["theta_ddot"]]
    differ = 0
    for k in range(steps + 1):
        x = loop.getFloat64(xs)
        ctl.setFloat64(xin, x)
        (u_c,) = ctl.getFloat64([vc["u"]])
        (u_l,) = loop.getFloat64([vl["u"]])
        if u_c != u_l:
            differ += 1
        if k < steps:
            tk = k * h
            ctl.doStep(currentCommunicationPoint=tk, communicationStepSize=h)
            loop.doStep(currentCommunicationPoint=tk, communicationStepSize=h)
    check(differ == 0, f"controller FMU fed the loop's x: {differ} of {steps + 1} commands differ from the loop's u")
    for f in (ctl, loop):
        f.terminate()
        f.freeInstance()

    # 4. the controller FMU against a plant in Python
    here = os.path.dirname(os.path.abspath(__file__))
    sys.path.insert(0, os.path.join(here, "..", "bench", "peers"))
    import nnvsc_numpy as ref  # the independent NumPy reference's plant (8)

    cfg = types.SimpleNamespace(da=(abs(ref.A1) * 1.0, abs(ref.A2) * 1.0, abs(ref.A3) * 1.0),
                                b_factor=1.0 + 0.5 * 0.5)
    md_c, ctl, vc = instantiate(ctl_path)
    x1 = x2 = x3 = 0.0
    e_max = 0.0
    for k in range(steps + 1):
        tk = k * h
        ctl.setFloat64(xin, [x1, x2, x3])
        u, thd = ctl.getFloat64([vc["u"], vc["theta_d"]])
        if tk >= SETTLE - 1e-9 * h:
            e_max = max(e_max, abs(thd - x1) / ref.DR)
        if k == steps:
            break
        f = lambda a, b, c: ref.plant_deriv(cfg, a, b, c, u)
        k1 = f(x1, x2, x3)
        k2 = f(x1 + 0.5 * h * k1[0], x2 + 0.5 * h * k1[1], x3 + 0.5 * h * k1[2])
        k3 = f(x1 + 0.5 * h * k2[0], x2 + 0.5 * h * k2[1], x3 + 0.5 * h * k2[2])
        k4 = f(x1 + h * k3[0], x2 + h * k3[1], x3 + h * k3[2])
        x1 += h / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0])
        x2 += h / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1])
        x3 += h / 6.0 * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2])
        ctl.doStep(currentCommunicationPoint=tk, communicationStepSize=h)
    ctl.terminate()
    ctl.freeInstance()
    check(rel_err(e_max, expected) <= REL,
          f"controller FMU on the Python plant: e_max_deg = {e_max!r} (rel. diff {rel_err(e_max, expected):.2e})")

    # 5. calls made wrong are errors, not crashes
    md = read_model_description(ctl_path)
    d = extracted(ctl_path)
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=d,
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="misuse")
    fmu.instantiate()
    refused = []
    for what, call in [
        ("fmi3DoStep before initialisation", lambda: fmu.doStep(0.0, h)),
        ("a NaN input", lambda: fmu.setFloat64([vc["theta"]], [math.nan])),
        ("an unknown value reference", lambda: fmu.getFloat64([99])),
    ]:
        try:
            call()
        except fmpy.fmi1.FMICallException:
            refused.append(what)
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    try:
        fmu.doStep(0.0, 0.5 * h)
    except fmpy.fmi1.FMICallException:
        refused.append("a step of half a period")
    fmu.freeInstance()
    check(len(refused) == 4, f"controller FMU: fmi3Error for {', '.join(refused)}")

    if linear:
        check_linear(*linear, check)
    for plant in plants:
        check_plant(*plant, check)

    if failures:
        print(f"{len(failures)} check(s) failed")
        return 1
    print("all FMU checks pass")
    return 0


if __name__ == "__main__":
    sys.exit(main())
