#!/usr/bin/env bash
# CI step of the C ABI and the FMI 3.0 export (issue #15), called by .ci/run:
#
# 1. examples/c/ehservo_run.c, compiled by gcc against include/ehservo.h and
#    linked both to libehservo_ffi.so and to libehservo_ffi.a, steps the
#    Fig. 2 loop from C and must print the e_max_deg of `ehservo run`'s
#    summary.json as the same double; its controller handle must return the
#    loop's command at every sample, bit for bit; misuse (a null handle,
#    NaN arguments) and a scenario that does not validate must give the
#    messages the library promises (the CLI's message for the scenario).
# 2. `ehservo fmu` exports the controller and the closed-loop FMUs, and
#    ci/fmu_check.py checks them with FMPy: validation, the closed loop's
#    e_max_deg, the controller's commands, the controller on a Python plant;
#    and a single-rod cylinder's closed-loop FMU read in mm (its variables,
#    units and e_max against its run's summary.json).
#
# Missing tools are installed when possible; what cannot be had is reported
# as "SKIPPED ...: reason" and does not fail CI.
set -euo pipefail
cd "$(dirname "$0")/.."

echo "== C ABI and FMU export (ci/ffi.sh)"
cargo build -q -p ehservo -p ehservo-ffi
bin=target/debug
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT

"$bin/ehservo" run scenarios/paper/fig2.toml --out "$d/fig2" --no-plot -q
cli_emax=$(sed -n 's/.*"e_max_deg": *\([-0-9.eE+]*\).*/\1/p' "$d/fig2/summary.json" | head -1)
[ -n "$cli_emax" ] || { echo "no e_max_deg in $d/fig2/summary.json"; exit 1; }

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo -n"; fi
if ! command -v gcc >/dev/null 2>&1; then
  echo "installing gcc"
  timeout 600 $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends gcc libc6-dev >/dev/null 2>&1 \
    || { timeout 300 $sudo apt-get update -q >/dev/null 2>&1 \
         && timeout 600 $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends gcc libc6-dev >/dev/null 2>&1; } || true
fi
if ! command -v gcc >/dev/null 2>&1; then
  echo "SKIPPED the C example: gcc is not installed and apt-get could not install it"
else
  cflags=(-std=c11 -Wall -Wextra -Werror -O2 -I crates/ehservo-ffi/include)
  gcc "${cflags[@]}" examples/c/ehservo_run.c -L "$bin" -lehservo_ffi \
      -Wl,-rpath,"$PWD/$bin" -o "$d/ehservo_run"
  gcc "${cflags[@]}" examples/c/ehservo_run.c "$bin/libehservo_ffi.a" \
      -lpthread -ldl -lm -o "$d/ehservo_run_static"
  for exe in ehservo_run ehservo_run_static; do
    "$d/$exe" scenarios/paper/fig2.toml --controller >"$d/$exe.out"
    c_emax=$(sed -n 's/^e_max_deg=//p' "$d/$exe.out")
    # awk reads both decimals as doubles: equal only if they are the same
    # double (the CLI writes the shortest round-trip form, C %.17g).
    if ! awk -v a="$c_emax" -v b="$cli_emax" 'BEGIN { exit !(a + 0 == b + 0) }'; then
      echo "$exe: e_max_deg=$c_emax, ehservo run: $cli_emax"
      exit 1
    fi
    grep -q '^controller: 0 of 1001 commands differ' "$d/$exe.out" \
      || { cat "$d/$exe.out"; exit 1; }
    echo "$exe: e_max_deg = $c_emax = ehservo run's; the controller handle gave the loop's 1001 commands"
  done

  # The flags from C, by their header constants: the samples the C loop
  # sees with EHSERVO_FLAG_SATURATED set are summary.json's
  # saturated_samples of the same scenario with a 0.3 V valve.
  printf '[actuator]\nlimit = 0.3\n' >"$d/sat.toml"
  "$bin/ehservo" run "$d/sat.toml" --out "$d/sat" --no-plot -q
  cli_sat=$(sed -n 's/.*"saturated_samples": *\([0-9]*\).*/\1/p' "$d/sat/summary.json" | head -1)
  c_sat=$("$d/ehservo_run" "$d/sat.toml" | sed -n 's/^saturated_samples=//p')
  if [ -z "$cli_sat" ] || [ "$cli_sat" = 0 ] || [ "$c_sat" != "$cli_sat" ]; then
    echo "saturated samples: C (EHSERVO_FLAG_SATURATED) $c_sat, ehservo run $cli_sat"; exit 1
  fi
  echo "flags from C: $c_sat samples with EHSERVO_FLAG_SATURATED = ehservo run's saturated_samples"

  # Misuse from C: a step on a handle never made, NaN arguments.
  "$d/ehservo_run" --misuse scenarios/paper/fig2.toml >"$d/misuse.out"
  for want in \
    'null sim: status -1: ehservo_sim_step: `sim` is null (make it with ehservo_sim_new and check its status)' \
    'null controller: status -1: ehservo_controller_step: `ctl` is null (make it with ehservo_controller_new and check its status)' \
    'NaN t: status -2: ehservo_controller_step: `t` must be finite (got NaN)' \
    'NaN x: status 2: u = 0: ehservo_controller_step: a measurement fault at t = 0 s: `x[0]` is NaN; u = 0 V is the safe command of `fault.safe_command`, the controller'"'"'s state is unchanged'; do
    grep -qxF "$want" "$d/misuse.out" || { echo "missing from --misuse: $want"; cat "$d/misuse.out"; exit 1; }
  done
  echo "misuse from C: 4 errors with their messages"

  # A scenario that does not validate: C prints the CLI's message.
  printf '[plant.params]\nJt = -0.05\n' >"$d/bad.toml"
  set +e
  "$d/ehservo_run" "$d/bad.toml" 2>"$d/bad.c" >/dev/null; c_rc=$?
  "$bin/ehservo" check "$d/bad.toml" 2>"$d/bad.cli" >/dev/null; cli_rc=$?
  set -e
  if [ "$c_rc" -ne 2 ] || [ "$cli_rc" -ne 2 ] || ! cmp -s "$d/bad.c" "$d/bad.cli"; then
    echo "bad scenario: C (exit $c_rc) and CLI (exit $cli_rc) differ:"; cat "$d/bad.c" "$d/bad.cli"; exit 1
  fi
  echo "bad scenario from C: exit 2 and the CLI's message: $(cat "$d/bad.c")"
fi

echo "== FMI 3.0 export checked by FMPy"
"$bin/ehservo" fmu scenarios/paper/fig2.toml --out "$d/controller.fmu"
"$bin/ehservo" fmu scenarios/paper/fig2.toml --closed-loop --out "$d/closed-loop.fmu"
# A linear axis: the single-rod cylinder, over 3 s (one period after settle).
cyl=(scenarios/cylinders/chrono-single-rod.toml --set simulation.horizon=3.0)
"$bin/ehservo" run "${cyl[@]}" --out "$d/cyl" --no-plot -q
"$bin/ehservo" fmu "${cyl[@]}" --closed-loop --out "$d/cyl-loop.fmu"
# The plants alone, to be driven by the runs' commands: the cylinder (with
# its spool) and the paper's servo.
"$bin/ehservo" fmu "${cyl[@]}" --plant --out "$d/cyl-plant.fmu"
"$bin/ehservo" fmu scenarios/paper/fig2.toml --plant --out "$d/fig2-plant.fmu"
fmpy_skip=""
if ! command -v python3 >/dev/null 2>&1; then
  fmpy_skip="python3 is not installed"
elif ! python3 -c 'import fmpy' >/dev/null 2>&1; then
  echo "installing fmpy"
  if ! timeout 300 python3 -m pip install -q fmpy >/dev/null 2>&1 \
     && ! timeout 300 python3 -m pip install -q --break-system-packages fmpy >/dev/null 2>&1; then
    fmpy_skip="pip could not install fmpy"
  fi
fi
if [ -n "$fmpy_skip" ]; then
  echo "SKIPPED the FMPy checks: $fmpy_skip"
else
  python3 ci/fmu_check.py "$d/controller.fmu" "$d/closed-loop.fmu" "$d/fig2/summary.json" \
    --linear "$d/cyl-loop.fmu" "$d/cyl/summary.json" \
    --plant "$d/cyl-plant.fmu" "$d/cyl/trace.csv" --plant "$d/fig2-plant.fmu" "$d/fig2/trace.csv"
fi

echo "-- the guide's C and FMU blocks (docs/guide/python-c-fmi.md), and FMPy's where it is installed"
EHSERVO_GUIDE_REQUIRE=ffi cargo test -q --workspace --test it -- guide::python_c_fmi
