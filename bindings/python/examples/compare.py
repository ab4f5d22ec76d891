"""Two controllers on the paper's Fig. 2 case: the NNBVSC of Theorem 3 and
the PID with feedforward, from Python. Prints each one's metrics (the
numbers `ehservo run` writes to summary.json, to the last digit) and draws
their tracking errors and commands into a PNG.

    python bindings/python/examples/compare.py [SCENARIO] [--out compare.png]

Run from the repository root (the default scenario is
scenarios/paper/fig2.toml). Needs matplotlib (pip install matplotlib).
"""

import argparse
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no window
import matplotlib.pyplot as plt  # noqa: E402

import ehservo  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario", nargs="?", default="scenarios/paper/fig2.toml")
    ap.add_argument("--out", default="compare.png", help="the PNG to write")
    args = ap.parse_args()

    cases = {
        "NNBVSC (Theorem 3)": {},
        "PID + feedforward": {"controller.kind": "pid"},
    }
    try:
        runs = {label: ehservo.run(args.scenario, set=sets, as_frame=False)
                for label, sets in cases.items()}
    except ehservo.ScenarioError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2

    print(f"{'controller':<20} {'e_max_deg':>20} {'e_rms_deg':>20} {'u_max':>20} {'chattering':>20}")
    for label, r in runs.items():
        m = r.metrics
        # repr: the shortest text that reads back to the same float, as
        # summary.json writes it.
        print(f"{label:<20} {m['e_max_deg']!r:>20} {m['e_rms_deg']!r:>20} "
              f"{m['u_max']!r:>20} {m['chattering']!r:>20}")

    fig, (ax_e, ax_u) = plt.subplots(2, 1, sharex=True, figsize=(8, 6), constrained_layout=True)
    for label, r in runs.items():
        t = r.trace["t_s"]
        ax_e.plot(t, r.trace["e_deg"], lw=0.9,
                  label=f"{label}: e_max = {r.metrics['e_max_deg']:.4f}° (t ≥ 2 s)")
        ax_u.plot(t, r.trace["u_V"], lw=0.9, label=label)
    ax_e.set_ylabel("e = θd − θ (°)")
    ax_e.set_title(f"{next(iter(runs.values())).name}: tracking error and command")
    ax_e.legend(loc="upper right", fontsize=8)
    ax_e.grid(alpha=0.3)
    ax_u.set_ylabel("u (V)")
    ax_u.set_xlabel("t (s)")
    ax_u.legend(loc="upper right", fontsize=8)
    ax_u.grid(alpha=0.3)
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
