#!/usr/bin/env bash
# Builds the firmware (f32, release) and runs it in QEMU's mps2-an386:
# 100 000 steps of the Fig. 2 loop at 10 kHz. Prints the firmware's output
# and keeps it in OUTFILE (first argument; default
# $CARGO_TARGET_DIR/firmware-m4f/run-f32.out). Fails when the build fails,
# when the firmware exits non-zero (panic, non-finite value) or runs longer
# than FW_TIMEOUT seconds (default 600), or when its output lacks the ten
# checkpoints and e_max. Called by .ci/run; needs qemu-system-arm and the
# thumbv7em-none-eabihf target.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$root/target}"
out="${1:-$CARGO_TARGET_DIR/firmware-m4f/run-f32.out}"
mkdir -p "$(dirname "$out")"
cd "$here"

cargo build --release -q
start=$(date +%s)
status=0
timeout "${FW_TIMEOUT:-600}" cargo run --release -q >"$out" || status=$?
cat "$out"
if [ "$status" -ne 0 ]; then
  echo "firmware-m4f: QEMU exited with status $status (124: timed out)" >&2
  exit 1
fi
checkpoints=$(grep -c '^checkpoint ' "$out" || true)
if [ "$checkpoints" -ne 10 ] || ! grep -q '^e_max_deg=' "$out"; then
  echo "firmware-m4f: expected 10 checkpoint lines and e_max_deg, got $checkpoints checkpoints" >&2
  exit 1
fi
echo "firmware-m4f: ran in QEMU in $(($(date +%s) - start)) s, output in $out"
