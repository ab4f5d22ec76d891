#!/usr/bin/env python3
"""Tests of step_metrics.py against closed forms (plain Python, unittest).

Run: python3 -m unittest discover -s tests/data/hopsan -p 'test_*.py'

Every expected value below is derived by hand from the signal's formula, not
from the script's output:
- first-order step y = 1 - exp(-t/tau): s(t) reaches level L at
  t = -tau*ln(1 - L), so t10 = tau*ln(1/0.9), t50 = tau*ln 2,
  t90 = tau*ln 10, and |y - 1| = exp(-t/tau) falls to 0.02 at tau*ln 50;
- second-order step, zeta < 1: overshoot = exp(-pi*zeta/sqrt(1 - zeta^2)),
  first peak at pi/(wn*sqrt(1 - zeta^2));
- a sine of amplitude A and period T on top of a settled step: period T,
  amplitude A (sampled 430 times a period: the sampled peak-to-peak is within
  1 - cos(pi/430) ~ 2.7e-5 of 2A).
"""

import math
import os
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import step_metrics as sm  # noqa: E402

DT = 1e-4


def grid(t_end):
    n = int(round(t_end / DT))
    return [k * DT for k in range(n + 1)]


def first_order(t, t0, tau, y_from, y_to):
    if t < t0:
        return y_from
    return y_to + (y_from - y_to) * math.exp(-(t - t0) / tau)


def second_order(t, t0, zeta, wn):
    if t < t0:
        return 0.0
    wd = wn * math.sqrt(1 - zeta * zeta)
    phi = math.acos(zeta)
    tt = t - t0
    return 1.0 - math.exp(-zeta * wn * tt) / math.sqrt(1 - zeta * zeta) * math.sin(wd * tt + phi)


class FirstOrder(unittest.TestCase):
    def setUp(self):
        self.tau = 0.1
        self.t = grid(5.5)
        # steps: 0 -> 1 at t = 0.5, 1 -> 0 at t = 3.0 (exact sample times)
        self.r = [0.0 if tk < 0.5 - 1e-12 else (1.0 if tk < 3.0 - 1e-12 else 0.0) for tk in self.t]
        y = []
        for tk in self.t:
            if tk < 3.0 - 1e-12:
                y.append(first_order(tk, 0.5, self.tau, 0.0, 1.0))
            else:
                y_at3 = first_order(3.0, 0.5, self.tau, 0.0, 1.0)
                y.append(first_order(tk, 3.0, self.tau, y_at3, 0.0))
        self.y = y

    def test_rise_and_settling(self):
        res = sm.metrics(self.t, self.y, self.r)
        self.assertEqual(len(res), 2)
        tau = self.tau
        for k in (0, 1):
            with self.subTest(step=k + 1):
                m = res[k]
                self.assertAlmostEqual(m["t10"], tau * math.log(1 / 0.9), delta=1e-6)
                self.assertAlmostEqual(m["t50"], tau * math.log(2.0), delta=1e-6)
                self.assertAlmostEqual(m["t90"], tau * math.log(10.0), delta=1e-6)
                self.assertAlmostEqual(m["settling_2pct"], tau * math.log(50.0), delta=1e-6)
                self.assertLess(m["overshoot_pct"], 1e-9)
                self.assertFalse(m["oscillation"]["sustained"])
        self.assertAlmostEqual(res[0]["t_step"], 0.5, delta=1e-12)
        self.assertAlmostEqual(res[1]["delta"], -1.0 + math.exp(-25.0), delta=1e-12)


class SecondOrder(unittest.TestCase):
    def test_overshoot_and_peak(self):
        zeta, wn = 0.3, 20.0
        t = grid(1.5)
        r = [0.0 if tk < 0.5 - 1e-12 else 1.0 for tk in t]
        y = [second_order(tk, 0.5, zeta, wn) for tk in t]
        m = sm.metrics(t, y, r)[0]
        os_expected = 100.0 * math.exp(-math.pi * zeta / math.sqrt(1 - zeta * zeta))
        tp_expected = math.pi / (wn * math.sqrt(1 - zeta * zeta))
        self.assertAlmostEqual(m["overshoot_pct"], os_expected, delta=1e-4)
        self.assertAlmostEqual(m["t_peak"], tp_expected, delta=DT)
        # a decaying oscillation (envelope exp(-6 t)) is not sustained
        self.assertFalse(m["oscillation"]["sustained"])


class Sustained(unittest.TestCase):
    def test_period_and_amplitude(self):
        a, period, tau = 0.03, 0.043, 0.02
        t = grid(2.5)
        r = [0.2 if tk < 0.5 - 1e-12 else 0.7 for tk in t]
        y = [first_order(tk, 0.5, tau, 0.2, 0.7) + (a * math.sin(2 * math.pi * (tk - 0.5) / period) if tk >= 0.5 else 0.0) for tk in t]
        m = sm.metrics(t, y, r)[0]
        osc = m["oscillation"]
        self.assertTrue(osc["sustained"])
        self.assertAlmostEqual(osc["period"], period, delta=1e-6)
        self.assertAlmostEqual(osc["amplitude"], a, delta=a * 1e-3)
        self.assertAlmostEqual(osc["tail_offset"], 0.0, delta=a * 0.05)
        # 0.03 is outside the 2 % band of a 0.5 step (0.01): never settled
        self.assertIsNone(m["settling_2pct"])


class BadInput(unittest.TestCase):
    def run_script(self, text, *args):
        with tempfile.TemporaryDirectory() as d:
            p = os.path.join(d, "trace.csv")
            with open(p, "w") as f:
                f.write(text)
            cmd = [sys.executable, os.path.join(HERE, "step_metrics.py"), p,
                   "--time", "t_s", "--output", "y_m", "--reference", "r_m", *args]
            return subprocess.run(cmd, capture_output=True, text=True)

    def check(self, proc, *words):
        self.assertEqual(proc.returncode, 2, proc.stderr)
        self.assertEqual(proc.stdout, "")
        lines = proc.stderr.strip().split("\n")
        self.assertEqual(len(lines), 1, proc.stderr)
        for w in words:
            self.assertIn(w, lines[0])

    def test_missing_column(self):
        self.check(self.run_script("t_s,y_m\n0,0\n1,1\n2,1\n"), "trace.csv", "'r_m'")

    def test_not_finite(self):
        self.check(self.run_script("t_s,y_m,r_m\n0,0,0\n1,nan,1\n2,1,1\n"), "row 3", "'y_m'", "not finite")

    def test_time_not_increasing(self):
        self.check(self.run_script("t_s,y_m,r_m\n0,0,0\n1,0,1\n1,1,1\n"), "row 4", "'t_s'", "increasing")

    def test_step_times_count(self):
        self.check(self.run_script("t_s,y_m,r_m\n0,0,0\n1,0,1\n2,1,1\n", "--step-times", "1,2"), "--step-times")

    def test_good_input_exits_zero(self):
        proc = self.run_script("t_s,y_m,r_m\n0,0,0\n1,0,1\n2,1,1\n3,1,1\n")
        self.assertEqual(proc.returncode, 0, proc.stderr)
        self.assertIn("step 1", proc.stdout)


if __name__ == "__main__":
    unittest.main()
