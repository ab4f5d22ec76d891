#!/usr/bin/env python3
"""Step-response metrics of a sampled trace, one block per step of the reference.

Independent of ehservo (plain Python 3, standard library only, so it runs
anywhere and shares no code with the Rust metrics it is meant to check).

Usage:
    python3 step_metrics.py TRACE.csv --time t_s --output position_m \
        --reference reference_m [--step-times 1.0] [--initial] [--json]

The CSV has one header row; the three named columns must hold finite numbers
and the time column must be strictly increasing. Bad input exits with code 2
and one line naming the file, the column (or row) and the reason.

Definitions (all times are in the time column's unit, values in the output
column's unit; "t0" is the step's time):

Steps
    A step is a sample i >= 1 where |r[i] - r[i-1]| > 1e-9 * max(1, max|r|).
    Its window runs from t0 to the sample before the next step (or to the
    end of the trace). By default t0 = t[i], the first sample at the new
    value (so t0 is known only to one sample interval); --step-times gives
    the true times (one per step, each in (t[i-1], t[i]]). With --initial the
    start of the trace is analysed as a step too: from the output's first
    value to the reference's first value, t0 = t[0].
y0, target, delta
    y0 is the output at t0 (linear interpolation between samples); target
    is the reference after the step; delta = target - y0 (the change the
    output must make; the reference before the step is printed too).
    s(t) = (y(t) - y0) / delta is the normalised response.
Rise times t10, t50, t90
    The first time after t0 at which s reaches 0.10, 0.50, 0.90 (linear
    interpolation between the two samples that bracket the crossing), minus
    t0. rise_10_90 = t90 - t10. "none" if s never reaches the level.
Peak
    The sample of the window with the largest s (the first one if tied):
    its output value and its time minus t0. A later oscillation peak can be
    the peak when the first overshoot is smaller.
Overshoot
    max(0, s_peak - 1) * 100, in per cent of |delta|.
Settling time (2 %)
    The band is target +/- 0.02 * |delta|. The settling time is the time
    (minus t0) at which the output enters the band for the last time and
    then stays in it until the end of the window (interpolated entry). It is
    "none" (not settled) when the output leaves the band anywhere in the
    second half of the window (so a trace that merely ends inside the band,
    or crosses it while oscillating, does not count as settled: it must stay
    in the band for at least half the window).
Sustained oscillation
    Taken on the tail: the samples in the second half of the window. Let
    m be the tail's mean and e = y - m. The upward zero crossings of e
    (interpolated) cut the tail into cycles; each cycle has a length and a
    peak-to-peak value (max - min of its samples). The oscillation is
    reported as sustained when there are at least 2 whole cycles, the last
    cycle's peak-to-peak is at least half the first one's (it does not die
    out within the tail), and the mean half peak-to-peak exceeds
    max(1e-12, 1e-4 * |delta|). Then: period = mean cycle length (with its
    min and max), amplitude = half the mean peak-to-peak, and the tail's
    offset m - target (the mean steady-state error). When the tail is not
    sustained, the tail's mean, offset and max |y - target| are still given.
"""

import argparse
import csv
import json
import math
import os
import sys

MAX_BYTES = 64 * 1024 * 1024  # refuse anything larger: a bounded read
LEVELS = (0.10, 0.50, 0.90)
BAND = 0.02
MIN_CYCLES = 2
DECAY_LIMIT = 0.5


class InputError(Exception):
    """Bad input: reported as one line, exit code 2."""


def load(path, names):
    """Read the named columns of a CSV with one header row, as float lists."""
    try:
        size = os.stat(path).st_size
    except OSError as err:
        raise InputError(f"{path}: cannot read: {err.strerror}")
    if size > MAX_BYTES:
        raise InputError(f"{path}: {size} bytes is more than the {MAX_BYTES} allowed")
    try:
        with open(path, newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        raise InputError(f"{path}: cannot read as CSV: {err}")
    if not rows:
        raise InputError(f"{path}: empty file (a header row is needed)")
    header = [h.strip() for h in rows[0]]
    idx = []
    for n in names:
        if n not in header:
            raise InputError(f"{path}: column {n!r}: not in the header {header}")
        idx.append(header.index(n))
    cols = [[] for _ in names]
    for r, row in enumerate(rows[1:], start=2):
        if not row or all(not c.strip() for c in row):
            continue
        for k, j in enumerate(idx):
            if j >= len(row):
                raise InputError(f"{path}: row {r}, column {names[k]!r}: missing value")
            try:
                v = float(row[j])
            except ValueError:
                raise InputError(f"{path}: row {r}, column {names[k]!r}: not a number: {row[j]!r}")
            if not math.isfinite(v):
                raise InputError(f"{path}: row {r}, column {names[k]!r}: not finite: {row[j]!r}")
            cols[k].append(v)
    if len(cols[0]) < 3:
        raise InputError(f"{path}: {len(cols[0])} data rows; at least 3 are needed")
    t = cols[0]
    for i in range(1, len(t)):
        if not t[i] > t[i - 1]:
            raise InputError(f"{path}: row {i + 2}, column {names[0]!r}: time not increasing ({t[i - 1]!r} then {t[i]!r})")
    return cols


def interp(t, y, tq):
    """y at tq by linear interpolation (tq within [t[0], t[-1]])."""
    lo, hi = 0, len(t) - 1
    if tq <= t[0]:
        return y[0]
    if tq >= t[-1]:
        return y[-1]
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if t[mid] <= tq:
            lo = mid
        else:
            hi = mid
    w = (tq - t[lo]) / (t[hi] - t[lo])
    return y[lo] + w * (y[hi] - y[lo])


def crossing(ta, tb, va, vb, level):
    """Time at which the segment (ta, va)-(tb, vb) reaches level."""
    if vb == va:
        return tb
    return ta + (level - va) / (vb - va) * (tb - ta)


def find_steps(r):
    """Indices i >= 1 where the reference changes."""
    tol = 1e-9 * max(1.0, max(abs(v) for v in r))
    return [i for i in range(1, len(r)) if abs(r[i] - r[i - 1]) > tol]


def oscillation(t, y, target, delta):
    """Sustained-oscillation analysis of a tail (see the module docstring)."""
    n = len(t)
    mean = sum(y) / n
    out = {
        "tail_from": t[0],
        "tail_mean": mean,
        "tail_offset": mean - target,
        "tail_max_abs_error": max(abs(v - target) for v in y),
        "sustained": False,
        "cycles": 0,
    }
    e = [v - mean for v in y]
    ups = []  # (interpolated time, index of the first sample after it)
    for i in range(1, n):
        if e[i - 1] < 0.0 <= e[i]:
            ups.append((crossing(t[i - 1], t[i], e[i - 1], e[i], 0.0), i))
    cycles = []
    for (ta, ia), (tb, ib) in zip(ups, ups[1:]):
        seg = y[ia - 1:ib + 1]
        cycles.append((tb - ta, max(seg) - min(seg)))
    out["cycles"] = len(cycles)
    if len(cycles) < MIN_CYCLES:
        return out
    periods = [c[0] for c in cycles]
    p2p = [c[1] for c in cycles]
    amp = sum(p2p) / len(p2p) / 2.0
    floor = max(1e-12, 1e-4 * abs(delta))
    out.update({
        "period": sum(periods) / len(periods),
        "period_min": min(periods),
        "period_max": max(periods),
        "amplitude": amp,
        "first_last_p2p_ratio": p2p[-1] / p2p[0] if p2p[0] > 0.0 else float("inf"),
    })
    out["sustained"] = bool(p2p[0] > 0.0 and p2p[-1] >= DECAY_LIMIT * p2p[0] and amp > floor)
    return out


def analyse(t, y, r, i0, i1, t0, y0, r_before):
    """Metrics of the window [i0, i1) for a step at t0 (see the docstring)."""
    target = r[i0]
    delta = target - y0
    res = {
        "t_step": t0,
        "window_end": t[i1 - 1],
        "reference_before": r_before,
        "target": target,
        "y0": y0,
        "delta": delta,
    }
    if delta == 0.0:
        res["note"] = "output already at the target: no step to analyse"
        return res
    tw = [t0] + [t[i] for i in range(i0, i1) if t[i] > t0]
    yw = [y0] + [y[i] for i in range(i0, i1) if t[i] > t0]
    s = [(v - y0) / delta for v in yw]
    for lev in LEVELS:
        key = f"t{int(round(lev * 100))}"
        res[key] = None
        for k in range(1, len(s)):
            if s[k - 1] < lev <= s[k]:
                res[key] = crossing(tw[k - 1], tw[k], s[k - 1], s[k], lev) - t0
                break
    res["rise_10_90"] = (res["t90"] - res["t10"]) if res["t10"] is not None and res["t90"] is not None else None
    kp = max(range(len(s)), key=lambda k: (s[k], -k))
    res["peak"] = yw[kp]
    res["t_peak"] = tw[kp] - t0
    res["overshoot_pct"] = max(0.0, s[kp] - 1.0) * 100.0
    half = BAND * abs(delta)
    inside = [abs(v - target) <= half for v in yw]
    tmid = t0 + (tw[-1] - t0) / 2.0
    if not all(ok for ok, tk in zip(inside, tw) if tk >= tmid):
        res["settling_2pct"] = None
    else:
        k = len(inside) - 1
        while k > 0 and inside[k - 1]:
            k -= 1
        if k == 0:
            res["settling_2pct"] = 0.0
        else:
            ea, eb = abs(yw[k - 1] - target), abs(yw[k] - target)
            res["settling_2pct"] = crossing(tw[k - 1], tw[k], ea, eb, half) - t0
    tail = [k for k in range(len(tw)) if tw[k] >= tmid]
    if len(tail) >= 3:
        res["oscillation"] = oscillation([tw[k] for k in tail], [yw[k] for k in tail], target, delta)
    return res


def metrics(t, y, r, step_times=None, initial=False):
    """All steps of a trace: a list of result dicts (see the docstring)."""
    steps = find_steps(r)
    if step_times is not None:
        if len(step_times) != len(steps):
            raise InputError(f"--step-times: {len(step_times)} times given, the reference has {len(steps)} steps")
        for ts, i in zip(step_times, steps):
            if not (t[i - 1] < ts <= t[i]):
                raise InputError(f"--step-times: {ts!r} is not in ({t[i - 1]!r}, {t[i]!r}] where the reference steps")
    bounds = steps + [len(t)]
    out = []
    if initial:
        res = analyse(t, y, r, 0, bounds[0], t[0], y[0], None)
        res["step"] = "initial"
        out.append(res)
    for n, i in enumerate(steps):
        t0 = step_times[n] if step_times is not None else t[i]
        res = analyse(t, y, r, i, bounds[n + 1], t0, interp(t, y, t0), r[i - 1])
        res["step"] = n + 1
        out.append(res)
    return out


def fmt(v, unit=""):
    if v is None:
        return "none"
    if isinstance(v, bool):
        return "yes" if v else "no"
    return f"{v:.6g}{unit}"


def report(results):
    lines = []
    for res in results:
        lines.append(f"step {res['step']}: t0 = {fmt(res['t_step'])}, window to {fmt(res['window_end'])}, "
                     f"reference {fmt(res['reference_before'])} -> {fmt(res['target'])}, y0 = {fmt(res['y0'])}, delta = {fmt(res['delta'])}")
        if "note" in res:
            lines.append(f"  {res['note']}")
            continue
        lines.append(f"  rise: t10 = {fmt(res['t10'])}, t50 = {fmt(res['t50'])}, t90 = {fmt(res['t90'])}, 10-90 % = {fmt(res['rise_10_90'])}")
        lines.append(f"  peak = {fmt(res['peak'])} at {fmt(res['t_peak'])} after t0; overshoot = {fmt(res['overshoot_pct'])} %")
        lines.append(f"  2 % settling = {fmt(res['settling_2pct'])}" + ("" if res["settling_2pct"] is not None else " (not settled: leaves the band in the window's second half)"))
        osc = res.get("oscillation")
        if osc:
            lines.append(f"  tail from {fmt(osc['tail_from'])}: mean = {fmt(osc['tail_mean'])}, offset = {fmt(osc['tail_offset'])}, "
                         f"max |error| = {fmt(osc['tail_max_abs_error'])}, cycles = {osc['cycles']}")
            if "period" in osc:
                lines.append(f"  oscillation: sustained = {fmt(osc['sustained'])}, period = {fmt(osc['period'])} "
                             f"(min {fmt(osc['period_min'])}, max {fmt(osc['period_max'])}), amplitude = {fmt(osc['amplitude'])}, "
                             f"last/first peak-to-peak = {fmt(osc['first_last_p2p_ratio'])}")
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("csv")
    ap.add_argument("--time", required=True, help="name of the time column")
    ap.add_argument("--output", required=True, help="name of the output column")
    ap.add_argument("--reference", required=True, help="name of the reference column")
    ap.add_argument("--step-times", help="comma-separated true step times, one per step")
    ap.add_argument("--initial", action="store_true", help="also analyse the start as a step from y[0] to r[0]")
    ap.add_argument("--json", action="store_true", help="print JSON instead of text")
    a = ap.parse_args(argv)
    try:
        st = None
        if a.step_times is not None:
            try:
                st = [float(x) for x in a.step_times.split(",")]
            except ValueError:
                raise InputError(f"--step-times: not a comma-separated list of numbers: {a.step_times!r}")
        t, y, r = load(a.csv, [a.time, a.output, a.reference])
        results = metrics(t, y, r, st, a.initial)
    except InputError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    if a.json:
        print(json.dumps(results, indent=1))
    else:
        print(report(results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
