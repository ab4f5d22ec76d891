#!/usr/bin/env python3
"""Held-out check of the paper-suite tunes (docs/league.md): each kind's
tuned parameters (docs/league/tune-KIND-paper/tune.json) on the Fig. 8
case with uncertainty seeds 10–29, which the tune never saw; prints the
worst and the median e_max (deg) per kind as a markdown table.

    python3 scenarios/league/held_out.py [path/to/ehservo]
"""
import json, os, statistics, subprocess, sys, tempfile

exe = sys.argv[1] if len(sys.argv) > 1 else "target/release/ehservo"
kinds = ["backstepping", "nn-robust", "nnvsc", "pid", "sta", "vsc-sat", "arc", "adrc"]
print("| kind | tuned parameters | worst e_max (°), seeds 10–29 | median | unbounded |")
print("|---|---|---|---|---|")
with tempfile.TemporaryDirectory() as tmp:
    for k in kinds:
        r = json.load(open(f"docs/league/tune-{k}-paper/tune.json"))["result"]
        sets = ["--set", f"controller.kind={k}"]
        if not r["kept_defaults"]:
            for key, v in r["params"]:
                sets += ["--set", f"controller.{key}={v!r}"]
        e, unbounded = [], 0
        for seed in range(10, 30):
            out = os.path.join(tmp, f"{k}-{seed}")
            subprocess.run([exe, "run", "scenarios/paper/fig8.toml", "--out", out, "--no-plot", "-q",
                            "--set", f"uncertainty.seed={seed}"] + sets, check=True)
            m = json.load(open(os.path.join(out, "summary.json")))["metrics"]
            if m["diverged"] or m["e_max_deg"] is None:
                unbounded += 1
            else:
                e.append(m["e_max_deg"])
        params = "defaults (kept)" if r["kept_defaults"] else ", ".join(f"{a} = {b:.4g}" for a, b in r["params"])
        worst = f"{max(e):.4f}" if e and not unbounded else "—"
        med = f"{statistics.median(e):.4f}" if e else "—"
        print(f"| {k} | {params} | {worst} | {med} | {unbounded}/20 |")
