#!/usr/bin/env bash
# Processor-in-the-loop in CI (docs/pil.md): builds the PIL firmware,
# runs `ehservo pil --qemu` on the paper's Fig. 2 at 1 kHz for 10 s and
# checks its trace.csv against `ehservo run --float f32` byte for byte,
# then a fault case (a corrupted reply, a dropped frame, a late reply, a
# board reset) whose faults must be named at their samples, then the QEMU
# tests of tests/it/pil.rs, required (EHSERVO_PIL_REQUIRE). Installs
# qemu-system-arm and the thumbv7em-none-eabihf target as .ci/run's
# firmware step does; prints one SKIPPED line where they cannot be had.
set -euo pipefail
cd "$(dirname "$0")/.."
skip=""
if ! command -v qemu-system-arm >/dev/null 2>&1; then
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo -n"; fi
  apt_install() {
    timeout 600 $sudo env DEBIAN_FRONTEND=noninteractive \
      apt-get install -y -q --no-install-recommends qemu-system-arm >/dev/null 2>&1
  }
  echo "installing qemu-system-arm"
  apt_install || { timeout 300 $sudo apt-get update -q >/dev/null 2>&1 && apt_install; } || true
  command -v qemu-system-arm >/dev/null 2>&1 \
    || skip="qemu-system-arm is not installed and apt-get could not install it"
fi
if [ -z "$skip" ] \
   && ! rustup target list --installed 2>/dev/null | grep -qx thumbv7em-none-eabihf \
   && ! timeout 180 rustup target add thumbv7em-none-eabihf >/dev/null 2>&1; then
  skip="the Rust target thumbv7em-none-eabihf is not installed and rustup could not add it"
fi
if [ -n "$skip" ]; then
  echo "SKIPPED the PIL run: $skip"
  exit 0
fi

cargo build --release -q -p ehservo
(cd examples/firmware-pil && cargo build --release -q)
bin=target/release/ehservo
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT

echo "-- Fig. 2 at 1 kHz, 10 s: the host's f32 run, then the board in QEMU"
$bin run scenarios/paper/fig2.toml --set simulation.step=0.001 --float f32 \
  --out "$d/host" --no-plot -q
start=$(date +%s%N)
$bin pil scenarios/paper/fig2.toml --set simulation.step=0.001 --qemu \
  --out "$d/board" --no-plot
secs=$(( ($(date +%s%N) - start) / 1000000 ))
if ! cmp "$d/host/trace.csv" "$d/board/trace.csv"; then
  echo "ci/pil.sh: the PIL trace differs from the host's f32 run"
  exit 1
fi
echo "PIL and host f32 traces identical ($(($(wc -l <"$d/board/trace.csv") - 1)) samples; the PIL run took $secs ms)"

echo "-- a fault case: corrupted reply at k = 50, dropped request at 120, late reply at 200, board reset at 300"
$bin pil scenarios/paper/fig2.toml --qemu --set simulation.horizon=4 --no-plot -q \
  --inject corrupt-reply@50 --inject drop-request@120 --inject late-reply@200 \
  --inject reset-board@300 --out "$d/faults" 2>"$d/faults.err"
cat "$d/faults.err"
for want in "k = 50: corrupt-reply" "k = 120: no-reply" "k = 200: late-reply" "k = 300: board-reset"; do
  if ! grep -q "link fault at $want" "$d/faults.err"; then
    echo "ci/pil.sh: expected 'link fault at $want'"
    exit 1
  fi
done
grep -q '"sessions": 2' "$d/faults/summary.json" || { echo "ci/pil.sh: no second session after the reset"; exit 1; }
echo "-- the QEMU tests of tests/it/pil.rs (skipped by cargo test before the firmware was built): Fig. 2 and the realistic case with the cycle budget, a PID in f64, the ADRC and STA, faults from a TCP proxy"
EHSERVO_PIL_REQUIRE=1 cargo test -q --workspace --test it -- pil::
echo "-- the guide's PIL blocks (README, docs/guide/board.md), which need QEMU and the firmware"
EHSERVO_GUIDE_REQUIRE=qemu cargo test -q --workspace --test it -- guide::readme guide::board
echo "ci/pil.sh: passed"
