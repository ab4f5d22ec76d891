#!/usr/bin/env python3
"""Independent NumPy reference of Hwang's NNBVSC / traditional VSC closed loop.

Written from the paper text (paper/000_561f1166d3e58fa4.txt) and SPEC.md only,
as a cross-check of the project's Rust implementation.  Plain Python floats for
the scalar algebra, NumPy for the 130-long RBF vector Phi and the weights W.

Usage:
  python3 bench/peers/nnvsc_numpy.py --controller nnvsc|vsc --mode sampled|continuous \
      --step 0.01 --substeps 1 --horizon 10 [--a-bias 1 --b-bias 0.5 --gamma1 100 \
      --eta 0.25 --alphabar 5] [--csv out.csv]
  python3 bench/peers/nnvsc_numpy.py --check      # nominal coefficients self-check
"""

import argparse
import csv
import itertools
import json
import math
import sys
import time

import numpy as np

# ---------------------------------------------------------------------------
# 1. Plant parameters (SPEC section 1), SI units
# ---------------------------------------------------------------------------
PS = 13.795e6        # Pa, supply pressure
BETA_E = 344.875e6   # Pa, bulk modulus
VT = 1.639e-4        # m^3
KCE = 2.376e-12      # m^3/(s Pa)
DM = 8.195e-6        # m^3/rad
JT = 5.652e-2        # N m s^2
BM = 8.477           # N m s
KV = 0.508           # m/V
G = 1.13e-3          # N m/rad
RHO = 850.0          # kg/m^3
CD = 0.67
AG = 3.385e-7        # m

# load Tl = A sin(k theta)
LOAD_A = 2.0
LOAD_K = 4.0

# nominal coefficients, eq. (9)
A1 = 4.0 * BETA_E * KCE * G / (VT * JT)
A2 = G / JT + 4.0 * BETA_E * DM ** 2 / (VT * JT) + 4.0 * BETA_E * KCE * BM / (VT * JT)
A3 = BM / JT + 4.0 * BETA_E * KCE / VT

# switching surface, poles -20, -30, -40
P1, P2, P3 = 90.0, 2600.0, 24000.0

# reference
DR = math.pi / 180.0
REF_AMP = 5.0 * DR
REF_W = 2.0 * math.pi

# RBF network geometry (SPEC section 5)
XT_SCALE = np.array([6.25 * DR, 12.5 * math.pi * DR, 25.0 * math.pi ** 2 * DR])
GRID = (-1.0, -0.5, 0.0, 0.5, 1.0)
# first component varying slowest: j = 25*i1 + 5*i2 + i3
CENTRES = np.array(list(itertools.product(GRID, GRID, GRID)), dtype=float)  # (125, 3)
DELTA = 0.5
N_PHI = 1 + CENTRES.shape[0] + 4   # 130


# A diverging run may put inf/nan into an RK4 stage before the post-step check
# catches it: let that propagate as IEEE values instead of raising.
np.seterr(all="ignore")


def fsin(v):
    return math.sin(v) if math.isfinite(v) else math.nan


def fcos(v):
    return math.cos(v) if math.isfinite(v) else math.nan


def fdiv(a, b):
    """a / b with IEEE semantics (b == 0 gives +-inf or nan, never an exception)."""
    if b != 0.0:
        return a / b
    if a == 0.0 or math.isnan(a):
        return math.nan
    return math.copysign(math.inf, a) * (math.copysign(1.0, b))


def sgn(v):
    """sign in {-1, 0, 1}"""
    if v > 0.0:
        return 1.0
    if v < 0.0:
        return -1.0
    return 0.0


# ---------------------------------------------------------------------------
# 2. Plant model pieces
# ---------------------------------------------------------------------------
def load_torque(x1):
    return LOAD_A * fsin(LOAD_K * x1)


def load_torque_dot(x1, x2):
    return LOAD_A * LOAD_K * fcos(LOAD_K * x1) * x2


def load_pressure(x1, x2, x3):
    """Pl from the torque balance (4)."""
    return (JT * x3 + BM * x2 + G * x1 + load_torque(x1)) / DM


def b_nom(x1, x2, x3, s):
    """Nominal control gain b of (9), with sgn(xv) = sgn(u) = s in {-1,0,1}."""
    pl = load_pressure(x1, x2, x3)
    arg = PS - s * pl
    if math.isnan(arg):
        return math.nan
    # valve cannot deliver flow against a load pressure above supply: clamp at 0
    kg = CD * AG * math.sqrt(max(0.0, arg) / RHO)
    return 4.0 * BETA_E * DM * kg * KV / (VT * JT)


def d_load(x1, x2):
    """d(t) of (9) (the nominal load; also the true one)."""
    return 4.0 * BETA_E * KCE * load_torque(x1) / (VT * JT) + load_torque_dot(x1, x2) / JT


def b_nom_zero_pl():
    kg = CD * AG * math.sqrt(PS / RHO)
    return 4.0 * BETA_E * DM * kg * KV / (VT * JT)


# ---------------------------------------------------------------------------
# 3. Reference
# ---------------------------------------------------------------------------
def reference(t):
    """z = [thd, thd', thd'', thd''']"""
    s = fsin(REF_W * t)
    c = fcos(REF_W * t)
    return (REF_AMP * s,
            REF_AMP * REF_W * c,
            -REF_AMP * REF_W ** 2 * s,
            -REF_AMP * REF_W ** 3 * c)


# ---------------------------------------------------------------------------
# 4. Configuration
# ---------------------------------------------------------------------------
class Config:
    def __init__(self, args):
        self.controller = args.controller
        self.mode = args.mode
        self.h = args.step
        self.substeps = args.substeps
        self.horizon = args.horizon
        self.a_bias = args.a_bias
        self.b_bias = args.b_bias
        self.gamma1 = args.gamma1
        self.eta = args.eta
        self.alphabar = args.alphabar
        self.alpha = args.alpha
        self.wmax = args.wmax
        self.eps0 = args.eps0
        self.eps1 = args.eps1
        self.eps2 = args.eps2
        self.hii = args.hii
        self.bound_b = args.bound_b
        self.alpha_bound = args.alpha_bound
        # true variation (bias only)
        self.da = (abs(A1) * self.a_bias, abs(A2) * self.a_bias, abs(A3) * self.a_bias)
        self.b_factor = 1.0 + 0.5 * self.b_bias
        # bounds the VSC knows: alpha_i = alpha_bound * |abar_i|
        self.alpha_i = (self.alpha_bound * abs(A1), self.alpha_bound * abs(A2),
                        self.alpha_bound * abs(A3))


# ---------------------------------------------------------------------------
# 5. True plant (8) with the variation
# ---------------------------------------------------------------------------
def plant_deriv(cfg, x1, x2, x3, u):
    s = sgn(u)
    bt = b_nom(x1, x2, x3, s) * cfg.b_factor
    x3dot = (-(A1 + cfg.da[0]) * x1 - (A2 + cfg.da[1]) * x2 - (A3 + cfg.da[2]) * x3
             + bt * u - d_load(x1, x2))
    return x2, x3, x3dot


# ---------------------------------------------------------------------------
# 6. Control laws
# ---------------------------------------------------------------------------
def rbf_phi(x1, x2, x3, z):
    """Phi(x, z) of (20): [1, 125 Gaussians, thd, thd', thd'', thd''']."""
    xt = np.array([x1, x2, x3]) / XT_SCALE
    diff = CENTRES - xt
    gauss = np.exp(-np.sum(diff * diff, axis=1) / DELTA ** 2)
    phi = np.empty(N_PHI)
    phi[0] = 1.0
    phi[1:126] = gauss
    phi[126:130] = z
    return phi


def control_law(cfg, t, x1, x2, x3, int_e, W):
    """Evaluate the law at time t. Returns a dict with u, Wdot, e and trace values."""
    z = reference(t)
    thd, thd1, thd2, thd3 = z
    e = thd - x1
    edot = thd1 - x2
    eddot = thd2 - x3
    sigma = eddot + P1 * edot + P2 * e + P3 * int_e
    # nominal part of (12)/(24)
    N = (thd3 + A1 * x1 + A2 * x2 + A3 * x3
         + P1 * (thd2 - x3) + P2 * (thd1 - x2) + P3 * (thd - x1))
    denom = 1.0 - cfg.bound_b
    dval = d_load(x1, x2)

    if cfg.controller == "vsc":
        k_num = (cfg.alpha_i[0] * abs(x1) + cfg.alpha_i[1] * abs(x2) + cfg.alpha_i[2] * abs(x3)
                 + abs(dval) + cfg.bound_b * abs(N))
        v = N + sgn(sigma) * k_num / denom
        s = sgn(v)
        bbar = b_nom(x1, x2, x3, s)
        u = fdiv(v, bbar)
        u_eq = fdiv(N, bbar)
        u_sw = u - u_eq
        sigma_delta = sigma   # no dead zone in Theorem 1 (choice, see report)
        wphi = 0.0
        xi = 0.0
        Wdot = None
    else:
        phi = rbf_phi(x1, x2, x3, z)
        E0, E1, E2 = int_e, e, edot
        Ed0, Ed1, Ed2 = e, edot, eddot
        norm_e = math.sqrt(E0 * E0 + E1 * E1 + E2 * E2)
        norm_phi = float(np.sqrt(np.dot(phi, phi)))
        c = cfg.eta * cfg.wmax ** 2 / 4.0 + cfg.eps0 * norm_phi + cfg.eps1
        gamma2 = c + cfg.eps2
        if norm_e == 0.0:
            sigma_delta = 0.0
            mu = 0.0
            xi = 0.0
        else:
            delta = cfg.alphabar * norm_e
            if abs(sigma) > delta:
                sigma_delta = sigma - delta * sgn(sigma)
            else:
                sigma_delta = 0.0
            mu = (cfg.alpha - cfg.alphabar) * norm_e * cfg.eps2 / c
            xi = cfg.alphabar * (E0 * Ed0 + E1 * Ed1 + E2 * Ed2) * sgn(sigma) / norm_e
        den_sw = abs(sigma_delta) + mu
        sw2 = fdiv(gamma2 * sigma_delta, den_sw) if den_sw != 0.0 else 0.0
        wphi = float(np.dot(W, phi))
        v = N + wphi + (cfg.gamma1 * sigma_delta + sw2) / denom
        s = sgn(v)
        bbar = b_nom(x1, x2, x3, s)
        u = fdiv(v, bbar)
        u_eq = fdiv(N + wphi, bbar)
        u_sw = u - u_eq
        Wdot = (sigma_delta * phi - cfg.eta * abs(sigma_delta) * W) / cfg.hii

    db = bbar * cfg.b_factor - bbar
    uncertainty = (cfg.da[0] * x1 + cfg.da[1] * x2 + cfg.da[2] * x3
                   - db * u_eq + dval - xi)
    return {
        "u": u, "u_eq": u_eq, "u_sw": u_sw, "sigma": sigma, "sigma_delta": sigma_delta,
        "wphi": wphi, "uncertainty": uncertainty, "e": e, "thd": thd, "Wdot": Wdot,
    }


# ---------------------------------------------------------------------------
# 7. Simulation
# ---------------------------------------------------------------------------
TRACE_COLS = ["t", "theta_d_deg", "theta_deg", "e_deg", "u", "u_eq", "u_sw", "sigma",
              "sigma_delta", "wphi", "uncertainty", "w_norm", "w_1", "w_128"]


def trace_row(t, x1, W, law):
    return [t, law["thd"] / DR, x1 / DR, law["e"] / DR, law["u"], law["u_eq"], law["u_sw"],
            law["sigma"], law["sigma_delta"], law["wphi"], law["uncertainty"],
            float(np.linalg.norm(W)), float(W[1]), float(W[128])]


def state_ok(x1, x2, x3, int_e, W):
    if not (math.isfinite(x1) and math.isfinite(x2) and math.isfinite(x3)
            and math.isfinite(int_e)):
        return False
    if not np.all(np.isfinite(W)):
        return False
    return abs(x1) <= 1.0


def step_sampled(cfg, t, x1, x2, x3, int_e, W, law):
    """Zero-order hold of u over [t, t+h); plant by RK4 substeps; int_e, W by Euler."""
    u = law["u"]
    hs = cfg.h / cfg.substeps
    for _ in range(cfg.substeps):
        k1 = plant_deriv(cfg, x1, x2, x3, u)
        k2 = plant_deriv(cfg, x1 + 0.5 * hs * k1[0], x2 + 0.5 * hs * k1[1],
                         x3 + 0.5 * hs * k1[2], u)
        k3 = plant_deriv(cfg, x1 + 0.5 * hs * k2[0], x2 + 0.5 * hs * k2[1],
                         x3 + 0.5 * hs * k2[2], u)
        k4 = plant_deriv(cfg, x1 + hs * k3[0], x2 + hs * k3[1], x3 + hs * k3[2], u)
        x1 = x1 + hs / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0])
        x2 = x2 + hs / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1])
        x3 = x3 + hs / 6.0 * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2])
    int_e = int_e + cfg.h * law["e"]
    if law["Wdot"] is not None:
        W = W + cfg.h * law["Wdot"]
    return x1, x2, x3, int_e, W


def aug_deriv(cfg, t, x1, x2, x3, int_e, W, law=None):
    """Derivative of the augmented state (x, int_e, W) with the law evaluated here."""
    if law is None:
        law = control_law(cfg, t, x1, x2, x3, int_e, W)
    dx1, dx2, dx3 = plant_deriv(cfg, x1, x2, x3, law["u"])
    dW = law["Wdot"] if law["Wdot"] is not None else np.zeros_like(W)
    return (dx1, dx2, dx3, law["e"], dW)


def step_continuous(cfg, t, x1, x2, x3, int_e, W, law):
    """One classic RK4 step of the augmented state; law re-evaluated at each stage."""
    h = cfg.h
    k1 = aug_deriv(cfg, t, x1, x2, x3, int_e, W, law)
    k2 = aug_deriv(cfg, t + 0.5 * h, x1 + 0.5 * h * k1[0], x2 + 0.5 * h * k1[1],
                   x3 + 0.5 * h * k1[2], int_e + 0.5 * h * k1[3], W + 0.5 * h * k1[4])
    k3 = aug_deriv(cfg, t + 0.5 * h, x1 + 0.5 * h * k2[0], x2 + 0.5 * h * k2[1],
                   x3 + 0.5 * h * k2[2], int_e + 0.5 * h * k2[3], W + 0.5 * h * k2[4])
    k4 = aug_deriv(cfg, t + h, x1 + h * k3[0], x2 + h * k3[1], x3 + h * k3[2],
                   int_e + h * k3[3], W + h * k3[4])
    x1 = x1 + h / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0])
    x2 = x2 + h / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1])
    x3 = x3 + h / 6.0 * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2])
    int_e = int_e + h / 6.0 * (k1[3] + 2.0 * k2[3] + 2.0 * k3[3] + k4[3])
    W = W + h / 6.0 * (k1[4] + 2.0 * k2[4] + 2.0 * k3[4] + k4[4])
    return x1, x2, x3, int_e, W


def simulate(cfg):
    h = cfg.h
    n_steps = int(round(cfg.horizon / h))
    x1 = x2 = x3 = 0.0
    int_e = 0.0
    W = np.zeros(N_PHI)
    rows = []
    diverged = False
    t_div = None
    stepper = step_sampled if cfg.mode == "sampled" else step_continuous
    for k in range(n_steps + 1):
        t = k * h
        law = control_law(cfg, t, x1, x2, x3, int_e, W)
        rows.append(trace_row(t, x1, W, law))
        if k == n_steps:
            break
        x1, x2, x3, int_e, W = stepper(cfg, t, x1, x2, x3, int_e, W, law)
        if not state_ok(x1, x2, x3, int_e, W):
            diverged = True
            t_div = (k + 1) * h
            break
    return np.array(rows), diverged, t_div


# ---------------------------------------------------------------------------
# 8. Metrics
# ---------------------------------------------------------------------------
def metrics(cfg, rows, diverged, t_div):
    h = cfg.h
    tol = 1e-9 * h
    t = rows[:, 0]
    e = rows[:, 3]
    u = rows[:, 4]
    wn = rows[:, 11]
    sd = rows[:, 8]
    after = t >= 2.0 - tol
    last = t >= cfg.horizon - 1.0 - tol

    def fmax(a):
        return float(np.max(np.abs(a))) if a.size else None

    out = {
        "controller": cfg.controller, "mode": cfg.mode, "step": cfg.h,
        "substeps": cfg.substeps if cfg.mode == "sampled" else None,
        "horizon": cfg.horizon, "a_bias": cfg.a_bias, "b_bias": cfg.b_bias,
        "gamma1": cfg.gamma1, "eta": cfg.eta, "alphabar": cfg.alphabar,
        "diverged": diverged, "t_diverged": t_div, "n_rows": int(rows.shape[0]),
        "e_max_deg": fmax(e[after]),
        "e_final_deg": fmax(e[last]),
        "e_rms_deg": float(np.sqrt(np.mean(e[after] ** 2))) if np.any(after) else None,
        "u_max": fmax(u),
        "chattering": None,
        "w_norm_max": float(np.max(wn)),
        "w_norm_final": float(wn[-1]),
        "dead_zone_fraction": float(np.mean(sd[after] == 0.0)) if np.any(after) else None,
    }
    if np.any(after):
        ks = int(np.argmax(after))
        du = np.diff(u)[ks:]          # u_k - u_{k-1}, k = ks+1..
        uu = u[ks + 1:]
        if uu.size and np.sum(uu ** 2) > 0.0:
            out["chattering"] = float(math.sqrt(np.sum(du ** 2)) / math.sqrt(np.sum(uu ** 2)))
    return out


# ---------------------------------------------------------------------------
# 9. Self-check
# ---------------------------------------------------------------------------
def self_check():
    poles = np.roots([1.0, A3, A2, A1])
    out = {
        "a1": A1, "a2": A2, "a3": A3,
        "b_nom_Pl0": b_nom_zero_pl(),
        "b_nom_state0_s+1": b_nom(0.0, 0.0, 0.0, 1.0),
        "open_loop_poles": [[float(p.real), float(p.imag)] for p in poles],
        "expected": {"a1": 0.39982, "a2": 13000.2711, "a3": 169.98043, "b_nom_Pl0": 17911.75},
        "n_phi": N_PHI,
        "centre_0": CENTRES[0].tolist(), "centre_1": CENTRES[1].tolist(),
        "centre_25": CENTRES[25].tolist(),
    }
    print(json.dumps(out, indent=2))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--check", action="store_true", help="print nominal coefficients and exit")
    ap.add_argument("--controller", choices=["nnvsc", "vsc"], default="nnvsc")
    ap.add_argument("--mode", choices=["sampled", "continuous"], default="sampled")
    ap.add_argument("--step", type=float, default=0.01)
    ap.add_argument("--substeps", type=int, default=1)
    ap.add_argument("--horizon", type=float, default=10.0)
    ap.add_argument("--a-bias", type=float, default=1.0)
    ap.add_argument("--b-bias", type=float, default=0.5)
    ap.add_argument("--gamma1", type=float, default=100.0)
    ap.add_argument("--eta", type=float, default=0.25)
    ap.add_argument("--alphabar", type=float, default=5.0)
    ap.add_argument("--alpha", type=float, default=250.0)
    ap.add_argument("--wmax", type=float, default=4.0)
    ap.add_argument("--eps0", type=float, default=0.1)
    ap.add_argument("--eps1", type=float, default=0.1)
    ap.add_argument("--eps2", type=float, default=0.01)
    ap.add_argument("--hii", type=float, default=1.0, help="H = hii * I")
    ap.add_argument("--bound-b", type=float, default=0.5, help="beta = bound_b * bbar")
    ap.add_argument("--alpha-bound", type=float, default=1.0,
                    help="VSC bounds alpha_i = alpha_bound * |abar_i|")
    ap.add_argument("--csv", default=None, help="write the trace CSV here")
    args = ap.parse_args(argv)

    if args.check:
        self_check()
        return 0

    cfg = Config(args)
    t0 = time.perf_counter()
    rows, diverged, t_div = simulate(cfg)
    wall = time.perf_counter() - t0
    out = metrics(cfg, rows, diverged, t_div)
    out["wall_s"] = wall
    if args.csv:
        with open(args.csv, "w", newline="") as f:
            wr = csv.writer(f)
            wr.writerow(TRACE_COLS)
            for r in rows:
                wr.writerow([repr(float(v)) for v in r])
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
