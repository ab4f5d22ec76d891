"""Wall time of one Fig. 2 run from Python: ehservo.run in the process,
against the command line in a subprocess followed by reading its
trace.csv and summary.json (what a script without the bindings does).

    python bindings/python/examples/bench_run.py [--cli target/release/ehservo] [-n 50]

Run from the repository root. Prints min and median over n repetitions
(after one warm-up call each) and checks that both give the same e_max.
"""

import argparse
import json
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import ehservo

FIG2 = "scenarios/paper/fig2.toml"


def timed(f, n):
    f()  # warm-up (imports, page cache)
    ts = []
    for _ in range(n):
        t0 = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t0)
    return min(ts), statistics.median(ts)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", default="target/release/ehservo")
    ap.add_argument("-n", type=int, default=50)
    args = ap.parse_args()
    try:
        import pandas as pd
    except ImportError:
        pd = None

    rows = [
        ("ehservo.run, dict of numpy arrays", lambda: ehservo.run(FIG2, as_frame=False)),
    ]
    if pd is not None:
        rows.append(("ehservo.run, pandas DataFrame", lambda: ehservo.run(FIG2)))

    out = Path(tempfile.mkdtemp()) / "fig2"

    def subprocess_csv():
        subprocess.run([args.cli, "run", FIG2, "--out", str(out), "--no-plot", "-q"], check=True)
        summary = json.loads((out / "summary.json").read_text())
        trace = pd.read_csv(out / "trace.csv") if pd is not None else \
            (out / "trace.csv").read_text().splitlines()
        return summary, trace

    rows.append((f"{args.cli} run --no-plot + read trace.csv, summary.json", subprocess_csv))
    for label, f in rows:
        lo, med = timed(f, args.n)
        print(f"{label:<62} min {lo * 1e3:8.2f} ms   median {med * 1e3:8.2f} ms")
    same = ehservo.run(FIG2).metrics["e_max_deg"] == subprocess_csv()[0]["metrics"]["e_max_deg"]
    print(f"same e_max_deg: {same}")


if __name__ == "__main__":
    main()
