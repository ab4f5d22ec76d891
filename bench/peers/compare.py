#!/usr/bin/env python3
"""Rust against the independent NumPy peer on the paper's Fig. 2 case.

The case: NNBVSC, third-order plant, sampled at 0.01 s with one RK4
sub-step, 10 s, the paper's gains, a_i bias 100 %, b bias 50 % of beta
(the scenario defaults, `scenarios/paper/fig2.toml`).

1. Results: runs `ehservo run scenarios/paper/fig2.toml` and the peer with
   `--csv`, and compares the metrics (relative difference) and every column
   of the two 1001-row traces (difference relative to the column's largest
   magnitude, so zero crossings do not blow up the ratio). The `chattering`
   metric is left out: the two programs define its window differently by one
   sample (see crates/ehservo/tests/it/independent.rs).
2. Speed, in one session: the peer's own `wall_s` (its simulation loop, no
   interpreter start-up, no I/O) over `--runs` runs, against criterion's
   median for `fig2/sampled_0.01_run` (`ehservo::run::run` of the same
   scenario, metrics only), measured by running that bench now.

Prints the max relative differences, both times and the ratio; exits 1 if a
difference exceeds 1e-9. Usage (from anywhere in the repository):

    python3 bench/peers/compare.py [--runs 10] [--skip-bench]

`--skip-bench` reuses the last criterion estimate in target/criterion.
"""

import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
PEER = os.path.join(ROOT, "bench", "peers", "nnvsc_numpy.py")
PEER_ARGS = ["--controller", "nnvsc", "--mode", "sampled", "--step", "0.01",
             "--substeps", "1", "--horizon", "10"]
TARGET = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
METRICS = ["e_max_deg", "e_final_deg", "e_rms_deg", "u_max", "w_norm_max", "w_norm_final"]
# peer column -> ehservo trace.csv column
COLUMNS = {
    "theta_d_deg": "theta_d_deg", "theta_deg": "theta_deg", "e_deg": "e_deg",
    "u": "u_V", "u_eq": "u_eq_V", "u_sw": "u_sw_V", "sigma": "sigma_rad_s2",
    "sigma_delta": "sigma_delta_rad_s2", "wphi": "wphi_rad_s3",
    "uncertainty": "uncertainty_rad_s3", "w_norm": "w_norm", "w_1": "w_1", "w_128": "w_128",
}
TOL = 1e-9


def sh(cmd, **kw):
    return subprocess.run(cmd, cwd=ROOT, check=True, text=True, **kw)


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=10, help="peer runs to time (default 10)")
    ap.add_argument("--skip-bench", action="store_true",
                    help="reuse target/criterion/fig2/sampled_0.01_run instead of benchmarking")
    args = ap.parse_args()

    sh(["cargo", "build", "--release", "-q", "-p", "ehservo", "--bin", "ehservo"])
    exe = os.path.join(TARGET, "release", "ehservo")
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "fig2")
        sh([exe, "run", "scenarios/paper/fig2.toml", "--out", out, "--no-plot", "--quiet"],
           stdout=subprocess.DEVNULL)
        with open(os.path.join(out, "summary.json")) as f:
            rust = json.load(f)["metrics"]
        rust_trace = read_csv(os.path.join(out, "trace.csv"))
        peer_csv = os.path.join(tmp, "peer.csv")
        peer = json.loads(sh([sys.executable, PEER, *PEER_ARGS, "--csv", peer_csv],
                             capture_output=True).stdout)
        peer_trace = read_csv(peer_csv)

    worst = 0.0
    print("metric              rust                    numpy                   rel. diff")
    for k in METRICS:
        a, b = rust[k], peer[k]
        d = abs(a - b) / abs(b)
        worst = max(worst, d)
        print(f"{k:<18}  {a:<22.16g}  {b:<22.16g}  {d:.1e}")
    n_rust, n_peer = len(rust_trace["t_s"]), len(peer_trace["t"])
    if n_rust != n_peer:
        sys.exit(f"trace lengths differ: rust {n_rust}, numpy {n_peer}")
    worst_trace, where = 0.0, ""
    for pc, rc in COLUMNS.items():
        b, a = peer_trace[pc], rust_trace[rc]
        scale = max(abs(v) for v in b) or 1.0
        for i, (x, y) in enumerate(zip(a, b)):
            d = abs(x - y) / scale
            if d > worst_trace:
                worst_trace, where = d, f"{rc} at t = {peer_trace['t'][i]:.2f} s"
    print(f"traces ({n_rust} rows x {len(COLUMNS)} columns): max |rust - numpy| / max|column|"
          f" = {worst_trace:.1e} ({where})")
    print(f"metrics: max relative difference = {worst:.1e}")

    if not args.skip_bench:
        sh(["cargo", "bench", "-q", "-p", "ehservo", "--bench", "fig2", "--",
            "fig2/sampled_0.01_run"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    est = os.path.join(TARGET, "criterion", "fig2", "sampled_0.01_run", "new", "estimates.json")
    with open(est) as f:
        rust_s = json.load(f)["median"]["point_estimate"] * 1e-9

    walls = []
    for _ in range(args.runs):
        r = json.loads(sh([sys.executable, PEER, *PEER_ARGS], capture_output=True).stdout)
        walls.append(r["wall_s"])
    peer_s = statistics.median(walls)
    print(f"numpy peer: median {peer_s * 1e3:.2f} ms per run over {args.runs} runs "
          f"(min {min(walls) * 1e3:.2f}, max {max(walls) * 1e3:.2f})")
    print(f"rust (criterion median, ehservo::run::run): {rust_s * 1e3:.4f} ms per run")
    print(f"ratio numpy / rust = {peer_s / rust_s:.0f}x")
    if max(worst, worst_trace) > TOL:
        print(f"FAIL: a difference exceeds {TOL:g}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
