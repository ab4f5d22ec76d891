"""ehservo from Python: run scenarios and studies, step the controllers.

Every number is computed by the Rust crates the ``ehservo`` command line is
built from (the same functions, so the same bits)::

    import ehservo
    r = ehservo.run("scenarios/paper/fig2.toml")
    r.metrics["e_max_deg"]          # == summary.json's metrics.e_max_deg
    r.trace["e_deg"]                # trace.csv's columns (a DataFrame with pandas)

Overrides follow ``ehservo run --set key.path=value``: pass them as a dict
``set={"controller.gamma1": 200}``, as keywords with ``__`` for the dots
(``controller__gamma1=200``), or both (keywords last). A value may be a
Python number, bool, string or list; a string is read as the command line
reads the text after ``=`` (a TOML value, or a bare word such as ``vsc``).

``run``, ``sweep``, ``tune`` and ``league`` compute on a thread of their
own: Ctrl-C raises ``KeyboardInterrupt`` within about 0.1 s and leaves
nothing written. A trace too large for the memory there raises
``MemoryError`` before the run starts.
"""

from __future__ import annotations

import json
import math
import numbers
import os
from typing import Any, Dict, Iterable, List, Mapping, NamedTuple, Optional, Sequence, Tuple, Union

import numpy as np

from . import _ehservo
from ._ehservo import ScenarioError

__all__ = [
    "run",
    "sweep",
    "tune",
    "league",
    "check",
    "FLAGS",
    "Controller",
    "linearize",
    "Linearization",
    "freq",
    "RunResult",
    "Signal",
    "ScenarioError",
    "overrides",
    "__version__",
]

__version__: str = _ehservo.__version__

#: The flags of a sample (``Controller.step(...)["flags"]``), name → bit
#: value, the law's constants: test ``out["flags"] & FLAGS["SATURATED"]``
#: (docs/flags.md).
FLAGS: Dict[str, int] = dict(_ehservo.FLAGS)

PathLike = Union[str, "os.PathLike[str]"]
SetArg = Union[Mapping[str, Any], Iterable[str], None]


def _toml(value: Any) -> str:
    """A Python value as the TOML text ``--set key=value`` takes after ``=``."""
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        v = float(value)
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)  # shortest text that reads back to the same float
    if isinstance(value, str):
        return value  # as on the command line: TOML, or a bare word
    if isinstance(value, Mapping):
        items = ", ".join(f"{json.dumps(str(k))} = {_element(v)}" for k, v in value.items())
        return "{" + items + "}"
    if isinstance(value, (Sequence, np.ndarray)):
        return "[" + ", ".join(_element(v) for v in value) + "]"
    raise TypeError(f"cannot pass a {type(value).__name__} as a scenario value: {value!r}")


def _element(value: Any) -> str:
    """A value inside an array or table: strings are quoted."""
    if isinstance(value, str):
        return json.dumps(value)
    return _toml(value)


def overrides(set: SetArg = None, **keywords: Any) -> List[str]:
    """The ``key.path=value`` strings of ``set`` and ``keywords``, in order.

    ``set`` is a mapping ``{"controller.gamma1": 200}`` or an iterable of
    ``"key.path=value"`` strings (exactly the command line's ``--set``
    arguments); in keyword names ``__`` stands for ``.``.
    """
    out: List[str] = []
    if set is not None:
        if isinstance(set, Mapping):
            out.extend(f"{k}={_toml(v)}" for k, v in set.items())
        elif isinstance(set, str):
            out.append(set)
        else:
            out.extend(str(s) for s in set)
    out.extend(f"{k.replace('__', '.')}={_toml(v)}" for k, v in keywords.items())
    return out


def _source(scenario: Optional[PathLike]) -> Tuple[Optional[str], Optional[str]]:
    """(path, text): a path names a file; a string with a newline, or with
    ``=`` that is not a file's name, is TOML text; None is the defaults."""
    if scenario is None:
        return None, None
    if isinstance(scenario, os.PathLike):
        return os.fspath(scenario), None
    if isinstance(scenario, str):
        if "\n" in scenario or ("=" in scenario and not _ehservo.is_file(scenario)):
            return None, scenario
        return scenario, None
    raise TypeError(
        f"scenario: expected a path or TOML text, got {type(scenario).__name__}"
    )


def _pandas() -> Any:
    try:
        import pandas  # noqa: PLC0415

        return pandas
    except ImportError:
        return None


def _frame(columns: Dict[str, Any], as_frame: Optional[bool]) -> Any:
    pd = _pandas() if as_frame is not False else None
    if as_frame and pd is None:
        raise ImportError("as_frame=True needs pandas (pip install pandas)")
    if pd is None:
        return columns
    # A list (text, or booleans/integers with gaps) stays as it is: an
    # object column, not floats with NaN for the gaps.
    return pd.DataFrame(
        {k: np.array(v, dtype=object) if isinstance(v, list) else v for k, v in columns.items()},
        copy=False,
    )


class RunResult(NamedTuple):
    """What ``run`` returns; unpacks as ``metrics, trace = ehservo.run(...)[:2]``."""

    metrics: Dict[str, Any]
    """summary.json's ``metrics``: e_max_deg, e_final_deg, ... (None when undefined)."""
    trace: Any
    """trace.csv's columns: a pandas DataFrame, or a dict of numpy arrays."""
    name: str
    """The scenario's name."""
    divergence: Optional[Dict[str, Any]]
    """summary.json's ``divergence``: None, or {t, reason, message}."""
    faults: Dict[str, int]
    """summary.json's ``faults`` (the counts of guarded numerical faults)."""


def run(
    scenario: Optional[PathLike] = None,
    *,
    set: SetArg = None,
    raw: bool = False,
    as_frame: Optional[bool] = None,
    **keywords: Any,
) -> RunResult:
    """Runs a scenario as ``ehservo run`` does, without writing files.

    ``scenario`` is a scenario file, TOML text, or None for the defaults
    (the paper's Fig. 2 case). Overrides: see the module's documentation.
    The trace has trace.csv's columns and rows (every ``output.decimate``-th
    sample); ``raw=True`` adds z (``z0_rad`` ... ``z3_rad_s3``) and the x
    the controller was given (``x0_ctrl_rad`` ...), in SI units, which
    ``Controller.step`` replays exactly. ``as_frame``: None gives a
    DataFrame when pandas is installed, else a dict of numpy arrays.

    Raises ``ScenarioError`` (a ``ValueError``) with the command line's
    message for a bad file, key or value.
    """
    path, text = _source(scenario)
    name, metrics, names, arrays, info = _ehservo.run(
        path, text, overrides(set, **keywords), raw
    )
    extra = json.loads(info)
    trace = _frame(dict(zip(names, arrays)), as_frame)
    return RunResult(metrics, trace, name, extra["divergence"], extra["faults"])


def check(scenario: Optional[PathLike] = None, *, set: SetArg = None, **keywords: Any) -> str:
    """Validates a scenario; returns it with every default filled in, as
    TOML (what ``ehservo check`` prints). Raises ``ScenarioError``."""
    path, text = _source(scenario)
    return _ehservo.check(path, text, overrides(set, **keywords))


def sweep(
    study: PathLike,
    *,
    threads: Optional[int] = None,
    out: Optional[PathLike] = None,
    as_frame: Optional[bool] = None,
) -> Any:
    """Runs a study as ``ehservo sweep`` does; returns results.csv's table.

    Columns: ``run``, the varied keys, ``seed``, the metrics and ``error``,
    one row per run in run order; an undefined metric is NaN, a run without
    an error has ``None``. With ``out``, the CLI's output folder is written
    too (results.csv, study.json, plots). ``threads`` as ``--threads``
    (default: all cores). A DataFrame with pandas, else a dict of arrays
    (text columns are lists).
    """
    names, cols = _ehservo.sweep(
        os.fspath(study), threads, None if out is None else os.fspath(out)
    )
    return _frame(dict(zip(names, cols)), as_frame)


def tune(
    file: PathLike,
    *,
    threads: Optional[int] = None,
    out: Optional[PathLike] = None,
    plot: bool = True,
) -> Dict[str, Any]:
    """Tunes a controller as ``ehservo tune`` does; returns tune.json's
    ``result`` (``params``, ``objective``, ``defaults``, ``kept_defaults``,
    ``evaluations``, ``history``). With ``out``, the CLI's output folder is
    written too. Raises ``ScenarioError`` for a bad tune file (and for one
    that asks for more work than the limit, stated in the message)."""
    return json.loads(
        _ehservo.tune(os.fspath(file), threads, None if out is None else os.fspath(out), plot)
    )


def league(
    file: PathLike,
    *,
    threads: Optional[int] = None,
    out: Optional[PathLike] = None,
    plot: bool = True,
) -> Dict[str, Any]:
    """Runs a league as ``ehservo league`` does; returns ``standings`` (per
    controller: its table, tune and margin) and ``rows`` (league.csv's).
    With ``out``, the CLI's output folder is written too."""
    return json.loads(
        _ehservo.league(os.fspath(file), threads, None if out is None else os.fspath(out), plot)
    )


class Signal(NamedTuple):
    """One named part of a controller's law."""

    key: str
    """The key in ``Controller.step``'s result (``"sigma"``, ``"p"``)."""
    column: str
    """Its trace.csv column ("" when it is not written)."""
    unit: str
    doc: str


class Controller:
    """A scenario's controller in its sampled loop, stepped from Python.

    Exactly what the simulator's sampled mode runs at each sample
    (``SampledController``: the law, the fault policy and valve range of
    ``[fault]``/``[actuator]``, then forward Euler on the controller's
    state, with period ``dt`` = ``simulation.step``). The sensors,
    estimator and actuator of the scenario are not part of it: ``x`` is what
    the controller measures.

    ``step(t, x, z)`` takes x = (θ, θ̇, θ̈) in rad, rad/s, rad/s² and z =
    (θd, θ̇d, θ̈d, θ⃛d) (by default the scenario's reference at t) and returns
    ``{"u": volts, "flags": bits, <part>: value, ...}`` with the kind's named
    parts (``signals``). ``uncertainty`` (the lumped uncertainty, which needs
    the true plant) is NaN here.
    """

    def __init__(
        self, scenario: Optional[PathLike] = None, *, set: SetArg = None, **keywords: Any
    ) -> None:
        path, text = _source(scenario)
        self._raw = _ehservo.RawController(path, text, overrides(set, **keywords))
        self._steps = 0
        self.signals: List[Signal] = [Signal(*s) for s in self._raw.signals()]

    @property
    def kind(self) -> str:
        """``controller.kind``."""
        return self._raw.kind

    @property
    def dt(self) -> float:
        """The sample period (s): the scenario's ``simulation.step``."""
        return self._raw.dt

    @property
    def name(self) -> str:
        return self._raw.name

    @property
    def faults(self) -> int:
        """Steps that returned the safe command (bad measurement or law)."""
        return self._raw.faults

    def reference(self, t: float) -> Tuple[float, float, float, float]:
        """z = (θd, θ̇d, θ̈d, θ⃛d) of the scenario's reference at t (rad, s)."""
        z = self._raw.reference(float(t))
        return (z[0], z[1], z[2], z[3])

    def step(
        self, t: float, x: Sequence[float], z: Optional[Sequence[float]] = None
    ) -> Dict[str, float]:
        """One sample at time t: the command and the law's parts; the state
        (∫e, W) advances by dt."""
        if z is None:
            z = self._raw.reference(float(t))
        out = self._raw.step(float(t), list(map(float, x)), list(map(float, z)))
        self._steps += 1
        return out

    def peek(self, t: float, x: Sequence[float], z: Optional[Sequence[float]] = None) -> float:
        """The command ``step(t, x, z)`` would return now, without advancing
        the state: the output map of the sampled-data system whose state
        update is ``step``."""
        if z is None:
            z = self._raw.reference(float(t))
        return self._raw.peek(float(t), list(map(float, x)), list(map(float, z)))[0]

    def reset(self) -> None:
        """Back to the initial state (∫e = 0, W = 0)."""
        self._raw.reset()
        self._steps = 0

    #: The inputs of :meth:`nlsys`, in order: x = (θ, θ̇, θ̈), then z.
    NLSYS_INPUTS = (
        "theta", "theta_dot", "theta_ddot",
        "theta_d", "theta_d_dot", "theta_d_ddot", "theta_d_dddot",
    )

    def nlsys(self, name: Optional[str] = None) -> Any:
        """This controller as a python-control discrete-time system
        (``control.nlsys`` with ``dt`` = the sample period), for
        ``control.interconnect`` and ``control.input_output_response``.

        Inputs: ``NLSYS_INPUTS`` (x, then the reference z); output: ``u``
        (V). Its python-control state is the sample counter ``k``; the
        law's own state (∫e, W) lives in this object and advances once per
        update, as python-control's discrete-time simulation calls it (the
        output is :meth:`peek`, so evaluating it any number of times
        changes nothing). A simulation starting again from k = 0 resets the
        controller; an output or update at any other k than the number of
        steps taken raises ``RuntimeError`` rather than give a wrong
        command (so python-control's linearisation, which perturbs the
        state, is refused).
        """
        import control  # python-control; not a dependency of ehservo

        def sync(k: Any, what: str) -> int:
            # The law's state must be the one after k steps: k = 0 starts
            # again from the initial state, any other k must be where the
            # controller is.
            k0 = int(np.asarray(k).reshape(-1)[0])
            if k0 == 0 and self._steps != 0:
                self.reset()
            elif k0 != self._steps:
                raise RuntimeError(
                    f"ehservo.Controller.nlsys: {what} at k = {k0}, but the controller has "
                    f"taken {self._steps} steps (a discrete-time simulation calls it once per "
                    "sample, in order; start again from k = 0 to reset it)"
                )
            return k0

        def updfcn(t: float, k: Any, v: Any, params: Any) -> List[float]:
            k0 = sync(k, "update")
            v = np.asarray(v, dtype=float)
            self.step(float(t), v[0:3], v[3:7])
            return [k0 + 1.0]

        def outfcn(t: float, k: Any, v: Any, params: Any) -> List[float]:
            sync(k, "output")
            v = np.asarray(v, dtype=float)
            return [self.peek(float(t), v[0:3], v[3:7])]

        return control.nlsys(
            updfcn,
            outfcn,
            inputs=list(self.NLSYS_INPUTS),
            outputs=["u"],
            states=["k"],
            dt=self.dt,
            name=name or self.name,
        )

    def weights(self) -> "np.ndarray":
        """The network weights W now (empty for a law without a network)."""
        return self._raw.weights()

    def __repr__(self) -> str:
        return f"ehservo.Controller({self.name!r}, kind={self.kind!r}, dt={self.dt})"


def _ss(model: Optional[Mapping[str, Any]], name: str) -> Any:
    """A python-control ``ss`` of a model of ``ehservo linearize``'s JSON."""
    import control  # python-control; not a dependency of ehservo

    if model is None:
        return None
    m = model["ss"] if "ss" in model else model
    n = len(m["states"])
    p, q = len(m["outputs"]), len(m["inputs"])

    def mat(rows: Any, r: int, c: int) -> "np.ndarray":
        return np.array(rows, dtype=float).reshape(r, c)

    return control.ss(
        mat(m["A"], n, n),
        mat(m["B"], n, q),
        mat(m["C"], p, n),
        mat(m["D"], p, q),
        0 if m["dt_s"] is None else float(m["dt_s"]),
        states=[s["name"] for s in m["states"]] or None,
        inputs=[s["name"] for s in m["inputs"]],
        outputs=[s["name"] for s in m["outputs"]],
        name=name,
    )


class Linearization:
    """What :func:`linearize` returns: the loop's models as python-control
    ``ss`` objects (None where the scenario has none), and ``data``, the
    JSON of ``ehservo linearize`` (the operating point, poles, zeros, DC
    gains, damping, the kinks and notes, the units of every signal).

    ``plant`` is the plant with its actuator, continuous, from the command
    u (V) to θ (rad; on a linear axis, a cylinder, y in m: every signal
    named for the angle is then y, in m); ``plant_alone`` and ``actuator`` its two parts;
    ``plant_discrete`` G at the sample period (ZOH, or the simulator's RK4
    map with ``discretise="rk4"``); ``sensor_delay`` and
    ``computation_delay`` the z⁻ⁿ of ``sensor.delay`` and
    ``simulation.computation_delay``; ``controller`` a linear law (PID,
    ADRC, state feedback) in the loop's time base with inputs (θm, θd, θ̇d,
    θ̈d, θ⃛d) and output u (the state feedback's: (θm, θ̇m, θ̈m, θd, …));
    ``feedback`` its path C = −u/θm (the state feedback's row
    −∂u/∂(θm, θ̇m, θ̈m)); ``measured`` the plant's path to the three
    measured channels (θ, θ̇, θ̈) for the state feedback, else None;
    ``loop`` L =
    C·z⁻ⁿˢ·G_d·z⁻ⁿᶜ; ``parts`` the ADRC's ``observer`` and ``law``;
    ``estimator`` a Luenberger or Kalman observer (inputs θm, u_prev)."""

    def __init__(self, data: Dict[str, Any]) -> None:
        self.data = data
        ctrl = data.get("controller") or {}
        self.plant = _ss(data["plant_with_actuator"], "G")
        self.plant_alone = _ss(data["plant"], "plant")
        self.actuator = _ss(data["actuator"], "actuator")
        self.plant_discrete = _ss(data.get("plant_discrete"), "Gd")
        self.sensor_delay = _ss((data.get("sensor_delay") or {}).get("model"), "sensor_delay")
        self.computation_delay = _ss(
            (data.get("computation_delay") or {}).get("model"), "computation_delay"
        )
        self.controller = _ss(ctrl.get("in_loop"), "controller")
        self.controller_law = _ss(ctrl.get("law"), "law")
        self.feedback = _ss(ctrl.get("feedback"), "C")
        self.parts = {k: _ss(v, k) for k, v in (ctrl.get("parts") or {}).items()}
        self.measured = _ss(data.get("measured_channels"), "G3")
        self.loop = _ss((data.get("loop") or {}).get("model"), "L")
        self.estimator = _ss(data.get("estimator"), "estimator")

    @property
    def operating_point(self) -> Dict[str, Any]:
        """Where the loop was linearised (``data["operating_point"]``)."""
        return self.data["operating_point"]

    @property
    def axis(self) -> str:
        """``"rotary"`` (θ in rad, shown in degrees) or ``"linear"`` (y in m,
        shown in mm), from the operating point."""
        return "rotary" if "theta_deg" in self.operating_point else "linear"

    def __repr__(self) -> str:
        op = self.operating_point
        where = (
            f"θ = {op['theta_deg']:.6g}°"
            if self.axis == "rotary"
            else f"y = {op['x_mm']:.6g} mm"
        )
        return (
            f"ehservo.Linearization({self.data['scenario']!r}, {op['kind']} at "
            f"{where}, controller={'none' if self.controller is None else 'linear'})"
        )


def linearize(
    scenario: Optional[PathLike] = None,
    *,
    at: Optional[float] = None,
    trim: Optional[float] = None,
    side: Optional[str] = None,
    discretise: str = "zoh",
    set: SetArg = None,
    **keywords: Any,
) -> Linearization:
    """Linearises a scenario's loop as ``ehservo linearize`` does and returns
    its models as python-control ``ss`` objects (:class:`Linearization`).

    ``at``: a time along the run (s); ``trim``: the position of a trim point
    for a constant reference in the axis's unit (θ0 in degrees on a rotary
    axis, mm on a linear one); neither: a trim at θd(0). ``side`` ("minus" or
    "plus"): the one-sided model at a point that is not differentiable
    (otherwise such a point raises ``ScenarioError`` naming it).
    ``discretise``: "zoh" (exact) or "rk4" (the simulator's map). Needs
    python-control (``pip install control``).
    """
    path, text = _source(scenario)
    raw = _ehservo.linearize(
        path, text, overrides(set, **keywords), at, trim, side, discretise
    )
    return Linearization(json.loads(raw))


def freq(
    scenario: Optional[PathLike] = None,
    *,
    out: PathLike,
    at: Optional[float] = None,
    trim: Optional[float] = None,
    side: Optional[str] = None,
    discretise: str = "zoh",
    measure: Union[str, Sequence[str]] = "sine",
    points: Optional[int] = None,
    amplitude: Optional[float] = None,
    threads: Optional[int] = None,
    plot: bool = True,
    set: SetArg = None,
    **keywords: Any,
) -> Dict[str, Any]:
    """Computes and measures the loop's frequency responses as ``ehservo
    freq`` does, writes its folder to ``out`` (freq.json, response.csv,
    the measured CSVs, the Bode and Nyquist plots unless ``plot=False``)
    and returns freq.json as a dict: the margins, Ms, Mt and bandwidths,
    with the position in the axis's units (``x_mm`` and m/V on a
    cylinder, ``theta_deg`` and rad/V on a rotary axis).

    ``at``, ``trim`` and ``side`` choose the operating point as for
    :func:`linearize` (``trim`` in degrees or mm). ``measure``: "sine",
    "multisine", "chirp", a list of them, or "none". ``amplitude``: the
    tracking sine's, in the axis's unit (default 0.5). ``points``: the
    computed grid's.
    """
    path, text = _source(scenario)
    methods = [measure] if isinstance(measure, str) else list(measure)
    raw = _ehservo.freq(
        path,
        text,
        overrides(set, **keywords),
        os.fspath(out),
        at,
        trim,
        side,
        discretise,
        methods,
        points,
        amplitude,
        threads,
        plot,
    )
    return json.loads(raw)
