"""Issue #39 from Python: Ctrl-C stops ehservo.run, sweep, tune and league
within about a second (KeyboardInterrupt, nothing left behind); a
Controller can be stepped from another thread; a run too long for the
memory there is raises MemoryError instead of aborting the interpreter;
tune and league are there, refusing bad input as ScenarioError; the flags
are named."""

import os
import re
import signal
import subprocess
import sys
import textwrap
import threading
import time

import pytest

import ehservo

FIG2 = "scenarios/paper/fig2.toml"


def child(code, cwd):
    """A Python process running `code` (after `import ehservo`)."""
    return subprocess.Popen(
        [sys.executable, "-c", "import ehservo, sys\n" + textwrap.dedent(code)],
        cwd=cwd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def interrupted(code, cwd):
    """Starts `code`, which prints "go" and then computes for far longer
    than a minute; sends SIGINT one second after "go"; returns (seconds
    from the signal to the process's end, its stderr)."""
    p = child(code, cwd)
    assert p.stdout.readline().strip() == "go", p.stderr.read()
    time.sleep(1.0)
    sent = time.monotonic()
    p.send_signal(signal.SIGINT)
    try:
        _, err = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        p.kill()
        p.communicate()
        pytest.fail("not interrupted within 60 s of SIGINT")
    return time.monotonic() - sent, err, p.returncode


# Each call below would compute for minutes: a 2·10⁷-step run (the
# documented maximal one), a 10⁵-run Monte Carlo, a tune of 10⁵
# evaluations, a league tuning with that budget.
LONG = {
    "run": f"""
        print("go", flush=True)
        ehservo.run({FIG2!r}, simulation__horizon=200, simulation__step=1e-5,
                    output__decimate=100000)
    """,
    "sweep": """
        open("study.toml", "w").write(
            'name = "long"\\nbase = "{base}"\\n[monte_carlo]\\nruns = 100000\\n'
            'draw = [{{ key = "controller.gamma1", dist = "uniform", low = 50.0, high = 200.0 }}]\\n'
            .format(base=BASE))
        print("go", flush=True)
        ehservo.sweep("study.toml", out="sweep-out")
    """,
    "tune": """
        open("tune.toml", "w").write(
            'scenarios = ["{base}"]\\ncontroller = "pid"\\nbudget = 100000\\n'.format(base=BASE))
        print("go", flush=True)
        ehservo.tune("tune.toml", out="tune-out")
    """,
    "league": """
        open("suite.toml", "w").write(
            '[[controller]]\\nkind = "pid"\\n[tuning]\\nscenarios = ["{base}"]\\nbudget = 100000\\n'
            '[[scenario]]\\nfile = "{base}"\\n'.format(base=BASE))
        print("go", flush=True)
        ehservo.league("suite.toml", out="league-out")
    """,
}


@pytest.mark.parametrize("what", list(LONG))
def test_ctrl_c_interrupts_a_long_call_within_a_second(what, repo, tmp_path):
    base = (repo / FIG2).as_posix()
    code = f"BASE = {base!r}\n" + textwrap.dedent(LONG[what])
    cwd = repo if what == "run" else tmp_path
    took, err, rc = interrupted(code, cwd)
    assert rc != 0
    assert "KeyboardInterrupt" in err, err
    assert "PanicException" not in err and "panicked" not in err, err
    # Polled every 0.1 s; a run stops at its next chunk of 2^16 evaluations.
    assert took < 5.0, f"{took:.2f} s from SIGINT to the end"
    if what != "run":
        # Nothing written, nothing half-written.
        left = sorted(p.name for p in tmp_path.iterdir())
        assert not any(n.endswith("-out") or n.startswith(".ehservo") for n in left), left


def test_a_controller_can_be_stepped_from_another_thread(repo, monkeypatch):
    """Made on this thread, stepped on another: the commands of a controller
    stepped here, bit for bit (pyo3 raised PanicException before)."""
    monkeypatch.chdir(repo)
    here, there = ehservo.Controller(FIG2), ehservo.Controller(FIG2)
    xs = [(0.01 * k, 0.1, -0.2) for k in range(50)]
    want = [here.step(0.01 * k, x)["u"] for k, x in enumerate(xs)]
    got, errors = [], []

    def work():
        try:
            got.extend(there.step(0.01 * k, x)["u"] for k, x in enumerate(xs))
        except BaseException as e:  # the test reports it below
            errors.append(e)

    t = threading.Thread(target=work)
    t.start()
    t.join()
    assert errors == []
    assert got == want


# An address-space limit of what the process has mapped now plus 500 MB.
LIMIT_MEMORY = """
import resource
size = next(int(l.split()[1]) * 1024 for l in open("/proc/self/status")
            if l.startswith("VmSize:"))
resource.setrlimit(resource.RLIMIT_AS, (size + 500_000_000, size + 500_000_000))
"""


def test_a_run_too_long_for_the_memory_raises_memory_error(repo):
    """With 500 MB of address space to spare, the documented maximal run
    (2·10⁷ steps, every sample kept: 160 MB a column, 3.2 GB in all) raises
    MemoryError before it starts, and the interpreter goes on (it aborted
    before)."""
    pytest.importorskip("resource")
    p = child(
        LIMIT_MEMORY
        + f"""
try:
    ehservo.run({FIG2!r}, simulation__horizon=200, simulation__step=1e-5)
except MemoryError as e:
    print("MemoryError:", e)
print("alive")
""",
        repo,
    )
    out, err = p.communicate(timeout=300)
    assert p.returncode == 0, err
    assert "MemoryError: the trace of 20000001 rows" in out, out + err
    assert out.strip().endswith("alive")


def test_a_sweep_too_large_for_the_memory_raises_memory_error(repo, tmp_path):
    """The same for a study's results: 2·10⁶ runs need about 1.4 GB of
    rows and columns, asked for before the first run."""
    pytest.importorskip("resource")
    study = tmp_path / "s.toml"
    study.write_text(
        f'name = "big"\nbase = "{(repo / FIG2).as_posix()}"\n[monte_carlo]\nruns = 2000000\n'
        'draw = [{ key = "controller.gamma1", dist = "uniform", low = 50.0, high = 200.0 }]\n'
    )
    p = child(
        LIMIT_MEMORY
        + f"""
try:
    ehservo.sweep({str(study)!r})
except MemoryError as e:
    print("MemoryError:", e)
print("alive")
""",
        repo,
    )
    out, err = p.communicate(timeout=300)
    assert p.returncode == 0, err
    assert "MemoryError: the results of 2000000 runs" in out, out + err
    assert out.strip().endswith("alive")


def test_tune_and_league_from_python(repo, tmp_path):
    base = (repo / FIG2).as_posix()
    t = tmp_path / "t.toml"
    t.write_text(f'scenarios = ["{base}"]\ncontroller = "pid"\nbudget = 40\nparticles = 20\n')
    r = ehservo.tune(t, threads=1)
    assert r["evaluations"] == 40
    assert len(r["history"]) == 1  # one iteration after the initial swarm
    out = tmp_path / "out"
    r2 = ehservo.tune(t, threads=2, out=out, plot=False)
    assert r2 == r  # the thread count changes nothing
    assert (out / "tune.json").is_file()
    ehservo.tune(t, out=out, plot=False)  # re-run into its own folder
    s = tmp_path / "s.toml"
    s.write_text(
        f'[[controller]]\nkind = "pid"\ntune = false\n[[scenario]]\nfile = "{base}"\n'
        'set = ["simulation.horizon=1", "simulation.settle=0.5"]\n'
    )
    lg = ehservo.league(s)
    assert [row["controller"] for row in lg["rows"]] == ["pid"]
    assert lg["standings"][0]["parameters"] == "given"


def test_tune_refuses_bad_and_unbounded_work_as_scenario_error(repo, tmp_path):
    base = (repo / FIG2).as_posix()
    t = tmp_path / "t.toml"
    t.write_text(
        f'scenarios = ["{base}"]\ncontroller = "pid"\nbudget = 1000000\ndraws = 10000\n'
    )
    with pytest.raises(ehservo.ScenarioError, match="more than the limit of 1e12"):
        ehservo.tune(t)
    t.write_text(
        f'scenarios = ["{base}"]\ncontroller = "pid"\nbudget = 40\nparticles = 20\n'
        '[[param]]\nkey = "feedforward"\nlow = 0.0\nhigh = 1.0\n'
    )
    with pytest.raises(ehservo.ScenarioError, match="not a real number"):
        ehservo.tune(t)


def test_flags_are_named_by_the_law_s_constants(repo, monkeypatch):
    """FLAGS is the law's constants, as docs/flags.md's table names them
    (name, value); a command clamped to a 1 V valve range raises SATURATED
    (bit 4, value 16)."""
    monkeypatch.chdir(repo)
    table = {
        m.group(1): int(m.group(2))
        for m in re.finditer(
            r"^\| `EHSERVO_FLAG_(\w+)` \| `(\d+)` \|",
            (repo / "docs" / "flags.md").read_text(),
            re.MULTILINE,
        )
    }
    assert table, "docs/flags.md has no flag table"
    assert ehservo.FLAGS == table
    assert ehservo.FLAGS["SATURATED"] == 16
    # one bit each, none shared
    assert sorted(ehservo.FLAGS.values()) == [1 << i for i in range(len(table))]
    c = ehservo.Controller(FIG2, actuator__limit=1.0)
    out = c.step(0.0, [0.5, 0.0, 0.0])  # a 0.5 rad error: far beyond 1 V
    assert abs(out["u"]) == 1.0
    assert out["flags"] & ehservo.FLAGS["SATURATED"]
