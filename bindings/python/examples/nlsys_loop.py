"""The paper's NNBVSC inside python-control: the controller of a scenario
as a discrete-time ``control.nlsys``, closed around a plant written in
python-control (the paper's third-order model at its nominal values, linear,
zero-order-hold discretised), simulated by ``control.input_output_response``.

    pip install control
    python examples/nlsys_loop.py [--plot out.png]

Prints e_max and u_max of the loop over 2 s.
"""

import argparse
import math
import os

import numpy as np

import control as ct
import ehservo

HERE = os.path.dirname(os.path.abspath(__file__))
FIG2 = os.path.join(HERE, "..", "..", "..", "scenarios", "paper", "fig2.toml")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--plot", help="write θd, θ and u against t to this PNG")
    args = ap.parse_args()

    ctl = ehservo.Controller(FIG2)
    # ā1, ā2, ā3 and b̄ at Pl = 0 (docs/paper-notes.md, SPEC §2).
    a1, a2, a3, b = 0.39982, 13000.2711, 169.98043, 17912.0
    plant = ct.sample_system(
        ct.ss([[0, 1, 0], [0, 0, 1], [-a1, -a2, -a3]], [[0], [0], [b]], np.eye(3),
              np.zeros((3, 1)), inputs=["u"], outputs=list(ctl.NLSYS_INPUTS[:3])),
        ctl.dt, method="zoh", name="plant")
    loop = ct.interconnect(
        [plant, ctl.nlsys(name="ctl")],
        inplist=["ctl." + n for n in ctl.NLSYS_INPUTS[3:]],
        outlist=["plant.theta", "ctl.u"])
    t = np.arange(0, 201) * ctl.dt
    z = np.array([ctl.reference(tk) for tk in t]).T
    theta, u = ct.input_output_response(loop, t, z).outputs
    e_max = math.degrees(np.max(np.abs(z[0] - theta)))
    print(f"e_max = {e_max:.6g} deg, u_max = {np.max(np.abs(u)):.6g} V over {t[-1]:g} s")
    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(7, 5))
        ax1.plot(t, np.degrees(z[0]), label="θd")
        ax1.plot(t, np.degrees(theta), "--", label="θ")
        ax1.set_ylabel("deg")
        ax1.legend()
        ax2.step(t, u, where="post")
        ax2.set_ylabel("u (V)")
        ax2.set_xlabel("t (s)")
        fig.tight_layout()
        fig.savefig(args.plot, dpi=120)
        print(f"wrote {args.plot}")


if __name__ == "__main__":
    main()
