#!/usr/bin/env python3
"""Hopsan's "Position Servo" as ordinary differential equations (no TLM).

An independent re-implementation (plain Python 3, standard library only) of
the continuous-time system written out in docs/hopsan/position-servo.md,
section "The model as ODEs". It exists to check that specification: run at a
small fixed step it should land on Hopsan's own simulation at a small time
step (the doc gives the comparison). It is not ehservo's model and shares no
code with it.

Usage:
    python3 position_servo_ode.py OUT.csv [--dt 1e-5] [--samples 2048]

OUT.csv has the columns of tests/data/hopsan/position-servo.csv plus the
pressures: t_s,position_m,reference_m,spool_xv_m,relief_xv,p_s_Pa,p_1_Pa,p_2_Pa
(relief_xv is Hopsan's relief "xv": a flow coefficient in m^3/(s*Pa^0.5)).
It is sampled like Hopsan's log: `samples` points from 0 to the stop time,
each at the nearest integration step. Integration: classical RK4 at a fixed
step dt. The only addition to the physics is a linear orifice law for
|dp| < P_LAM (see `orifice`), which Hopsan does not have: it keeps the
explicit integrator stable where sqrt(dp) has an infinite slope (Hopsan's
TLM solves the same orifice against the lines' impedances instead).
"""

import argparse
import math
import os
import sys

# --- parameters: the .hmf's values (line numbers of "Position Servo.hmf") ---
P_TANK = 1e5            # Pa, Tank_C/_1/_2 "p" (lines 92, 256, 298)
# pump (lines 431-433)
N_P = 200.0             # rad/s
D_P = 25e-5             # m^3/rev
C_LP = 1e-12            # (m^3/s)/Pa
# supply volume (lines 192-193)
V_S = 1e-3              # m^3
BETA_S = 1e9            # Pa
# relief valve (lines 357-362) and its source's fixed nominal pressure
P_MAX = 2e7             # Pa
TAU = 1e-3              # s
K_CS = 1e-8             # (m^3/s)/Pa
K_CF = 1e-8             # (m^3/s)/Pa
Q_NOM = 0.01            # m^3/s
P_NOM = 7e6             # Pa, HydraulicPressureReliefValve.hpp line 100
X0_MAX = Q_NOM / math.sqrt(P_NOM)          # line 104
C_S = math.sqrt(P_NOM) / K_CS              # line 105
C_F = 1.0 / (K_CF * math.sqrt(P_NOM))      # line 106
# 4/3 valve (lines 596-609)
C_Q = 0.67
RHO = 890.0             # kg/m^3
D_SPOOL = 0.01          # m
F_PA = F_PB = F_AT = F_BT = 1.0
X_PA = X_PB = X_AT = X_BT = 1e-4   # m, positive = overlap
X_VMAX = 0.01           # m
OMEGA_V = 200.0         # rad/s
DELTA_V = 1.0
# cylinder (lines 692-699)
A_1 = A_2 = 1e-3        # m^2
S_L = 1.0               # m
V_01 = V_02 = 3e-4      # m^3
B_P = 0.0               # N s/m
BETA_E = 1e9            # Pa
C_LEAK = 0.0            # (m^3/s)/Pa
# mass (lines 110-114) and spring (line 539)
M = 100.0               # kg
B_M = 0.0               # N s/m
X_MIN, X_MAX = 0.0, 1.0  # m
K_SPRING = 100.0        # N/m
# controller (lines 275, 407-409, 468)
K_P = 0.0264249         # m/m
K_I = 0.000672426       # m/(m s)
Y_0, Y_A, T_STEP = 0.2, 0.5, 1.0
T_STOP = 3.0            # line 13

P_LAM = 1e3             # Pa: linear orifice below this |dp| (not Hopsan's)
KV = C_Q * math.pi * D_SPOOL * math.sqrt(2.0 / RHO)   # m^2/s/sqrt(Pa) per m of opening


def orifice(k, p_from, p_to):
    """Turbulent orifice q = k*sgn(dp)*sqrt(|dp|), linear below P_LAM."""
    dp = p_from - p_to
    a = abs(dp)
    if a >= P_LAM:
        return k * math.copysign(math.sqrt(a), dp)
    return k * dp / math.sqrt(P_LAM)


def reference(t):
    return Y_0 + Y_A if t >= T_STEP else Y_0


def deriv(t, s, u_held=None):
    """dS/dt for S = [x, v, p1~, p2~, ps~, xv, xv', x0, z].

    With u_held (the sampled controller's output) the PI is not integrated
    here: u = u_held and dz/dt = 0.
    """
    x, v, p1t, p2t, pst, xv, xvd, x0, z = s
    # cavitation: the pressure states may go below zero (a cavity to refill);
    # what acts on orifices and the piston is max(p~, 0)
    p1, p2, ps = max(p1t, 0.0), max(p2t, 0.0), max(pst, 0.0)
    # PI controller on the valve's desired spool position, limited to x_vmax
    e = reference(t) - x
    if u_held is None:
        u = min(max(K_P * e + K_I * z, -X_VMAX), X_VMAX)
    else:
        u, e = u_held, 0.0
    # spool: second order, output within +/- x_vmax
    xvl = min(max(xv, -X_VMAX), X_VMAX)
    xva = OMEGA_V * OMEGA_V * (u - xv) - 2.0 * DELTA_V * OMEGA_V * xvd
    if (xv >= X_VMAX and xvd >= 0.0 and xva > 0.0) or (xv <= -X_VMAX and xvd <= 0.0 and xva < 0.0):
        xva = 0.0
    # edges: opening = max(+/-xv - lap, 0)
    q_pa = orifice(KV * F_PA * max(xvl - X_PA, 0.0), ps, p1)
    q_pb = orifice(KV * F_PB * max(-xvl - X_PB, 0.0), ps, p2)
    q_at = orifice(KV * F_AT * max(-xvl - X_AT, 0.0), p1, P_TANK)
    q_bt = orifice(KV * F_BT * max(xvl - X_BT, 0.0), p2, P_TANK)
    # relief valve: first-order spool towards its static opening
    b1 = C_S + max(ps - P_TANK, 0.0) * C_F
    xs = (ps - P_MAX) / b1
    x0d = (xs - x0) / TAU
    if (x0 <= 0.0 and x0d < 0.0) or (x0 >= X0_MAX and x0d > 0.0):
        x0d = 0.0
    q_rv = orifice(min(max(x0, 0.0), X0_MAX), ps, P_TANK)
    q_pump = D_P * N_P / (2.0 * math.pi) - C_LP * (ps - P_TANK)
    # volumes
    v1 = V_01 + A_1 * x
    v2 = V_02 + A_2 * (S_L - x)
    q_leak = C_LEAK * (p1 - p2)
    dp1 = BETA_E / v1 * (q_pa - q_at - A_1 * v - q_leak)
    dp2 = BETA_E / v2 * (q_pb - q_bt + A_2 * v + q_leak)
    dps = BETA_S / V_S * (q_pump - q_rv - q_pa - q_pb)
    # mass with spring; inelastic stops at x_min/x_max
    f = A_1 * p1 - A_2 * p2 - (B_P + B_M) * v - K_SPRING * x
    a = f / M
    dx = v
    if (x <= X_MIN and v <= 0.0 and a < 0.0) or (x >= X_MAX and v >= 0.0 and a > 0.0):
        a = 0.0
        dx = 0.0
    return [dx, a, dp1, dp2, dps, xvd, xva, x0d, e]


def clamp_state(s):
    """Keep the position inside the stops (and still there) after a step."""
    if s[0] < X_MIN:
        s[0], s[1] = X_MIN, max(s[1], 0.0)
    elif s[0] > X_MAX:
        s[0], s[1] = X_MAX, min(s[1], 0.0)
    s[7] = min(max(s[7], 0.0), X0_MAX)
    return s


def rk4(t, s, h, u_held=None):
    k1 = deriv(t, s, u_held)
    k2 = deriv(t + h / 2, [a + h / 2 * b for a, b in zip(s, k1)], u_held)
    k3 = deriv(t + h / 2, [a + h / 2 * b for a, b in zip(s, k2)], u_held)
    k4 = deriv(t + h, [a + h * b for a, b in zip(s, k3)], u_held)
    return clamp_state([a + h / 6 * (b + 2 * c + 2 * d + e) for a, b, c, d, e in zip(s, k1, k2, k3, k4)])


def log_steps(n_steps, samples, h):
    """Hopsan's choice of logged steps (ComponentSystem.cpp lines 1717-1741)."""
    dt_log = T_STOP / (samples - 1)
    steps, log_t, sim_t = [0], 0.0, 0.0
    while len(steps) < samples:
        log_t += dt_log
        n = int((log_t - sim_t) / h + 0.5)
        sim_t += n * h
        steps.append(steps[-1] + n)
    return [min(k, n_steps) for k in steps]


def simulate(h, samples, control_period=0.0):
    """Integrate 0..T_STOP at step h; log `samples` points.

    control_period = 0: the PI is continuous (the ODE of the doc).
    control_period = Ts > 0 (a whole number of steps h): the PI runs as
    Hopsan's signal components do at a time step Ts (ComponentSystem.cpp
    lines 3380-3400, SignalIntegrator2, Integrator.h lines 61-67): at the
    n-th sample, time t_n accumulated as t_n = t_(n-1) + Ts, e_n =
    r(t_n) - x(t_(n-1)) (the sensor reads the position the mass wrote one
    step earlier), z_n = z_(n-1) + Ts/2*(e_n + e_(n-1)), u_n = Kp*e_n +
    Ki*z_n limited to x_vmax, held over (t_(n-1), t_n].
    """
    n_steps = int(round(T_STOP / h))
    want = log_steps(n_steps, samples, h)
    s = [0.0, 0.0, P_TANK, P_TANK, P_TANK, 0.0, 0.0, 0.0, 0.0]
    m = int(round(control_period / h)) if control_period > 0.0 else 0
    t_acc, e_prev, z_pi, u_held = 0.0, reference(0.0) - s[0], 0.0, None
    rows, j = [], 0
    for k in range(n_steps + 1):
        t = k * h
        while j < len(want) and want[j] == k:
            if not all(math.isfinite(v) for v in s):
                raise ArithmeticError(f"state not finite at t = {t}: {s}")
            rows.append((t, s[0], reference(t), min(max(s[5], -X_VMAX), X_VMAX), s[7],
                         max(s[4], 0.0), max(s[2], 0.0), max(s[3], 0.0)))
            j += 1
        if k < n_steps:
            if m and k % m == 0:
                t_acc += control_period
                e_n = reference(t_acc) - s[0]
                z_pi += control_period / 2.0 * (e_n + e_prev)
                e_prev = e_n
                u_held = min(max(K_P * e_n + K_I * z_pi, -X_VMAX), X_VMAX)
            s = rk4(t, s, h, u_held)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out")
    ap.add_argument("--dt", type=float, default=1e-5, help="RK4 step, s (default 1e-5)")
    ap.add_argument("--samples", type=int, default=2048, help="logged samples (default 2048, the .hmf's)")
    ap.add_argument("--control-period", type=float, default=0.0,
                    help="run the PI sampled like Hopsan's signal components at this period, s (default 0: continuous)")
    a = ap.parse_args(argv)
    if not (a.dt > 0.0 and a.dt <= 1e-3 and math.isfinite(a.dt)):
        print(f"error: --dt: {a.dt!r} is not in (0, 1e-3] s", file=sys.stderr)
        return 2
    if not (2 <= a.samples <= int(round(T_STOP / a.dt)) + 1):
        print(f"error: --samples: {a.samples} is not in [2, steps + 1]", file=sys.stderr)
        return 2
    cp = a.control_period
    if not (math.isfinite(cp) and cp >= 0.0) or (cp > 0.0 and (cp < a.dt or abs(cp / a.dt - round(cp / a.dt)) > 1e-9)):
        print(f"error: --control-period: {cp!r} is not 0 or a whole number of --dt steps", file=sys.stderr)
        return 2
    try:
        rows = simulate(a.dt, a.samples, cp)
    except ArithmeticError as err:
        print(f"error: diverged: {err}", file=sys.stderr)
        return 1
    tmp = a.out + ".part"
    with open(tmp, "w") as f:
        f.write("t_s,position_m,reference_m,spool_xv_m,relief_xv,p_s_Pa,p_1_Pa,p_2_Pa\n")
        for r in rows:
            f.write(",".join(repr(v) for v in r) + "\n")
    os.replace(tmp, a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
