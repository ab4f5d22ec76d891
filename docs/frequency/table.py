#!/usr/bin/env python3
"""Markdown tables from `ehservo freq` outputs (stdlib only), for
docs/frequency.md.

    python3 docs/frequency/table.py margins DIR...    # one row per output folder
    python3 docs/frequency/table.py compare DIR...    # measured against computed

`margins`: the computed loop's gain, phase and delay margins, Ms and the
−3 dB bandwidths (linear controllers), and the measured tracking bandwidth
and the margins of the loop measured at the plant's input (every
controller). `compare`: the largest |measured − computed| of θ/θd, θ/d and S
(dB and degrees) over the sinestream points of quality ≥ 0.99, below and
above --split Hz.
"""
import argparse
import csv
import json
import math
import os


def fmt(v, digits=3, unit=""):
    if v is None:
        return "—"
    if isinstance(v, float) and (math.isnan(v) or math.isinf(v)):
        return "—"
    return f"{v:.{digits}g}{unit}"


def name_of(d):
    return os.path.basename(os.path.normpath(d))


def margins(dirs):
    print(
        "| run | controller | h (s) | GM (dB) | PM (°) | DM (ms) | Ms | T −3 dB (Hz) "
        "| measured θ/θd −3 dB (Hz) | measured PM (°) | measured DM (ms) | quality there | unbounded runs |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for d in dirs:
        f = json.load(open(os.path.join(d, "freq.json")))
        c = f.get("computed", {})
        m = c.get("margins") or {}
        gm = (m.get("gain_margin") or {}).get("gain_margin_dB")
        pm = (m.get("phase_margin") or {}).get("phase_margin_deg")
        dm = (m.get("delay_margin") or {}).get("delay_margin_s")
        ms = (c.get("Ms") or {}).get("value")
        bt = (c.get("bandwidth_Hz") or {}).get("T")
        meas = f["measured"]["methods"].get("sine", {})
        bw = meas.get("tracking_bandwidth", {})
        if bw.get("bandwidth_Hz") is not None:
            mbw = fmt(bw["bandwidth_Hz"])
        elif bw.get("above_Hz") is not None:
            mbw = f"> {fmt(bw['above_Hz'])}"
        else:
            mbw = "—"
        lm = meas.get("loop_margins", {})
        mpm = (lm.get("phase_margin") or {}).get("phase_margin_deg")
        mdm = (lm.get("delay_margin") or {}).get("delay_margin_s")
        q = (lm.get("delay_margin") or {}).get("quality")
        qtext = "—" if q is None else f"{q:.3f}"
        print(
            f"| {name_of(d)} | {f['controller']} | {f['dt_s']} | {fmt(gm)} | {fmt(pm)} "
            f"| {fmt(None if dm is None else dm * 1e3)} | {fmt(ms)} | {fmt(bt)} | {mbw} "
            f"| {fmt(mpm)} | {fmt(None if mdm is None else mdm * 1e3)} | {qtext} "
            f"| {meas.get('unbounded_runs', '—')} |"
        )


def compare(dirs, split):
    print(
        "| run | band | θ/θd max Δ (dB, °) | θ/d max Δ (dB, °) | S max Δ (dB, °) | points |"
    )
    print("|---|---|---|---|---|---|")
    for d in dirs:
        rows = list(csv.DictReader(open(os.path.join(d, "measured_sine.csv"))))
        for lo, hi, band in ((0.0, split, f"< {split} Hz"), (split, math.inf, f"≥ {split} Hz")):
            worst = {}
            n = 0
            for r in rows:
                f = float(r["f_Hz"])
                if not lo <= f < hi:
                    continue
                n += 1
                for k, q in (("track", "track_quality"), ("dist", "dist_quality"), ("S", "S_quality")):
                    qv = r[q] or r["dist_quality"]
                    if not r[f"{k}_gain_dB"] or not r[f"{k}_computed_gain_dB"] or not qv:
                        continue
                    if float(qv) < 0.99:
                        continue
                    dg = abs(float(r[f"{k}_gain_dB"]) - float(r[f"{k}_computed_gain_dB"]))
                    dp = float(r[f"{k}_phase_deg"]) - float(r[f"{k}_computed_phase_deg"])
                    dp = abs((dp + 180.0) % 360.0 - 180.0)
                    g0, p0 = worst.get(k, (0.0, 0.0))
                    worst[k] = (max(g0, dg), max(p0, dp))
            cells = [
                f"{fmt(worst[k][0])}, {fmt(worst[k][1])}" if k in worst else "—"
                for k in ("track", "dist", "S")
            ]
            print(f"| {name_of(d)} | {band} | {' | '.join(cells)} | {n} |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("what", choices=["margins", "compare"])
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--split", type=float, default=5.0)
    a = ap.parse_args()
    if a.what == "margins":
        margins(a.dirs)
    else:
        compare(a.dirs, a.split)


if __name__ == "__main__":
    main()
