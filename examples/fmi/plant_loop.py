#!/usr/bin/env python3
"""A loop closed in Python around an ehservo plant FMU (docs/guide/python-c-fmi.md).

  python3 examples/fmi/plant_loop.py PLANT.fmu [KP_V_PER_M] [SECONDS]

The plant FMU of a cylinder scenario (`ehservo fmu SCENARIO --plant`) is
driven through FMPy's FMU3Slave by a proportional position controller
written here, u = Kp·(y_ref − y) within ±10 V, sampled at the FMU's step
(the scenario's sample period), with the command held over each step, as
any importing tool would do. The reference is the scenario's x0 + 20 mm,
from t = 0.1 s. Prints the position at the end and the largest chamber
pressure on the way, in the FMU's display units (mm, bar).
"""

import shutil
import sys

from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Slave


def main():
    path = sys.argv[1]
    kp = float(sys.argv[2]) if len(sys.argv) > 2 else 10.0  # V/m
    seconds = float(sys.argv[3]) if len(sys.argv) > 3 else 8.0
    md = read_model_description(path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    if "y" not in vr:
        print(f"{path}: not a linear axis's plant FMU (no output y)")
        return 2
    h = float(md.defaultExperiment.stepSize)
    d = extract(path)
    try:
        fmu = FMU3Slave(guid=md.guid, unzipDirectory=d,
                        modelIdentifier=md.coSimulation.modelIdentifier, instanceName="plant")
        fmu.instantiate()
        fmu.enterInitializationMode(startTime=0.0)
        fmu.exitInitializationMode()
        (y0,) = fmu.getFloat64([vr["y"]])
        p_max = 0.0
        steps = round(seconds / h)
        for k in range(steps):
            t = k * h
            y, pa, pb = fmu.getFloat64([vr["y"], vr["p_a"], vr["p_b"]])
            p_max = max(p_max, pa, pb)
            y_ref = y0 + (0.020 if t >= 0.1 else 0.0)
            u = max(-10.0, min(10.0, kp * (y_ref - y)))
            fmu.setFloat64([vr["u"]], [u])
            fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
        (y,) = fmu.getFloat64([vr["y"]])
        fmu.terminate()
        fmu.freeInstance()
    finally:
        shutil.rmtree(d, ignore_errors=True)
    print(f"Kp = {kp} V/m, {steps} steps of {h} s")
    print(f"y: {1e3 * y0:.3f} mm -> {1e3 * y:.3f} mm (reference {1e3 * (y0 + 0.020):.3f} mm)")
    print(f"largest chamber pressure: {1e-5 * p_max:.1f} bar")
    return 0


if __name__ == "__main__":
    sys.exit(main())
