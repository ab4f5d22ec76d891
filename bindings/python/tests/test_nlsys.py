"""ehservo.Controller inside python-control (``Controller.nlsys``): the
discrete-time system python-control simulates gives the simulator's
commands to the bit, and closes a loop with a plant written in
python-control as a hand-written loop does. Skipped without python-control
(``pip install control``)."""

import math

import numpy as np
import pytest

import ehservo

ct = pytest.importorskip("control")

FIG2 = "scenarios/paper/fig2.toml"


def test_nlsys_replays_a_run_bit_for_bit(repo, monkeypatch):
    """Drive the controller's nlsys with what the simulator's controller saw
    (x and z at every sample): python-control's output is the run's u, to
    the bit; a second simulation starts from a reset controller."""
    monkeypatch.chdir(repo)
    r = ehservo.run(FIG2, set={"simulation.horizon": 1.0}, raw=True, as_frame=False)
    tr = r.trace
    c = ehservo.Controller(FIG2)
    sys = c.nlsys()
    assert sys.dt == c.dt and sys.ninputs == 7 and sys.noutputs == 1
    assert list(sys.input_labels) == list(ehservo.Controller.NLSYS_INPUTS)
    t = np.asarray(tr["t_s"])
    U = np.vstack([
        tr["x0_ctrl_rad"], tr["x1_ctrl_rad_s"], tr["x2_ctrl_rad_s2"],
        tr["z0_rad"], tr["z1_rad_s"], tr["z2_rad_s2"], tr["z3_rad_s3"],
    ])
    for _ in range(2):
        resp = ct.input_output_response(sys, t, U, X0=[0.0])
        np.testing.assert_array_equal(np.ravel(resp.outputs), tr["u_V"])
        np.testing.assert_array_equal(resp.states[0], np.arange(len(t)))


def test_an_update_out_of_order_is_an_error(repo, monkeypatch):
    monkeypatch.chdir(repo)
    c = ehservo.Controller(FIG2)
    sys = c.nlsys()
    v = [0.0] * 7
    # Evaluating the output any number of times changes nothing.
    u0 = sys._out(0.0, [0.0], v)
    assert sys._out(0.0, [0.0], v) == u0
    sys._rhs(0.0, [0.0], v)
    with pytest.raises(RuntimeError, match="update at k = 5"):
        sys._rhs(0.05, [5.0], v)
    with pytest.raises(RuntimeError, match="output at k = 3"):
        sys._out(0.03, [3.0], v)
    # k = 0 again: a fresh start, the first output as before.
    assert sys._out(0.0, [0.0], v) == u0


def _plant(h):
    """The paper's third-order model at its nominal values (SPEC §2: ā1,
    ā2, ā3 and b̄ at Pl = 0), without load or variation: a linear plant,
    discretised exactly (zero-order hold) by python-control."""
    a1, a2, a3, b = 0.39982, 13000.2711, 169.98043, 17912.0
    A = [[0, 1, 0], [0, 0, 1], [-a1, -a2, -a3]]
    B = [[0], [0], [b]]
    return ct.sample_system(
        ct.ss(A, B, np.eye(3), np.zeros((3, 1)), inputs=["u"],
              outputs=["theta", "theta_dot", "theta_ddot"]),
        h, method="zoh", name="plant",
    )


def test_a_loop_closed_in_python_control_is_the_hand_written_loop(repo, monkeypatch):
    """interconnect(plant, controller) simulated by python-control gives the
    same commands, to the bit, as stepping the same two systems by hand
    (u_k from x_k and z(t_k), then x_{k+1} = Ad·x_k + Bd·u_k). And the
    controller controls: e_max is under a tenth of the 5° amplitude."""
    monkeypatch.chdir(repo)
    c = ehservo.Controller(FIG2)
    plant = _plant(c.dt)
    t = np.arange(0, 201) * c.dt  # 2 s
    Z = np.array([c.reference(tk) for tk in t]).T
    # Signals join by name: the plant's theta, theta_dot, theta_ddot are
    # the controller's x inputs; its u is the plant's input.
    loop = ct.interconnect(
        [plant, c.nlsys(name="ctl")],
        inplist=["ctl.theta_d", "ctl.theta_d_dot", "ctl.theta_d_ddot", "ctl.theta_d_dddot"],
        outlist=["plant.theta", "ctl.u"],
    )
    resp = ct.input_output_response(loop, t, Z)
    theta, u = resp.outputs

    # By hand, with a fresh controller and the same Ad, Bd.
    d = ehservo.Controller(FIG2)
    Ad, Bd = np.asarray(plant.A), np.asarray(plant.B)[:, 0]
    x = np.zeros(3)
    u_hand = np.empty(len(t))
    for k, tk in enumerate(t):
        u_hand[k] = d.step(tk, x, Z[:, k])["u"]
        x = Ad @ x + Bd * u_hand[k]
    np.testing.assert_array_equal(u, u_hand)
    e_max = np.max(np.abs(Z[0] - theta))
    assert e_max < 0.1 * math.radians(5.0), math.degrees(e_max)
