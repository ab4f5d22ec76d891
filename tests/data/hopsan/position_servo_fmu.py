"""Hopsan's Position Servo plant as an FMI 2.0 co-simulation FMU (pythonfmu).

The plant of tests/data/hopsan/position_servo_ode.py (pump, relief valve,
line volume, 4/3 valve with its second-order spool, cylinder, mass and
spring; independent of ehservo's model), with the PI taken out: the input
`u` (V) is the spool command, limited to +-10 V and scaled by
Kv = x_vmax / 10 V = 1e-3 m/V as scenarios/hopsan/position-servo.toml's
actuator and valve do. Outputs `x` (m) and `v` (m/s). Each doStep of h is
`substeps` classical RK4 steps of h/substeps with the command held.

Build:
    pythonfmu build -f position_servo_fmu.py position_servo_ode.py
pythonfmu 0.7 writes no units, and ehservo needs the position's: the test
(crates/ehservo/tests/it/fmu_import_fmi2.rs) adds unit="m" to x and
unit="m/s" to v in the built FMU's modelDescription.xml. Its binary does
not link libpython (it expects a Python host): a host that is not Python
preloads it (LD_PRELOAD=.../libpython3.X.so).
"""

from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Integer, Real

import position_servo_ode as ode


class PositionServo(Fmi2Slave):
    author = "ehservo tests"
    description = "Hopsan's Position Servo plant (position_servo_ode.py), spool command in V"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.u = 0.0
        self.x = 0.0
        self.v = 0.0
        self.substeps = 10
        self.s = [0.0, 0.0, ode.P_TANK, ode.P_TANK, ode.P_TANK, 0.0, 0.0, 0.0, 0.0]
        self.register_variable(Real("u", causality=Fmi2Causality.input))
        self.register_variable(Real("x", causality=Fmi2Causality.output))
        self.register_variable(Real("v", causality=Fmi2Causality.output))
        self.register_variable(
            Integer("substeps", causality=Fmi2Causality.parameter, variability=Fmi2Variability.fixed)
        )

    def do_step(self, current_time, step_size):
        n = max(int(self.substeps), 1)
        hs = step_size / n
        spool = min(max(self.u, -10.0), 10.0) * ode.X_VMAX / 10.0
        for i in range(n):
            self.s = ode.rk4(current_time + i * hs, self.s, hs, u_held=spool)
        self.x, self.v = self.s[0], self.s[1]
        return True
