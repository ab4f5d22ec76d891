#!/usr/bin/env bash
# CI step for the Python package (bindings/python): build it with maturin
# in the dev profile (no fat LTO; the ehservo crates at opt-level 3, and the
# workspace's target directory, so the dependencies `cargo test` already
# built are reused), install it into a fresh venv, and run its pytest suite
# against the CLI (bit-for-bit comparisons) and its example.
# Prints "SKIPPED ...: reason" and exits 0 when Python, venv or the PyPI
# packages cannot be had; a build or test failure fails CI.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
skip() {
  echo "SKIPPED the Python package tests: $*"
  exit 0
}
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo -n"; fi
apt_install() {
  timeout 300 $sudo env DEBIAN_FRONTEND=noninteractive \
    apt-get install -y -q --no-install-recommends "$@" >/dev/null 2>&1 \
    || { timeout 300 $sudo apt-get update -q >/dev/null 2>&1 \
      && timeout 300 $sudo env DEBIAN_FRONTEND=noninteractive \
        apt-get install -y -q --no-install-recommends "$@" >/dev/null 2>&1; }
}

echo "== cargo fmt --check (bindings/python)"
cargo fmt --manifest-path bindings/python/Cargo.toml -- --check

py=$(command -v python3 || true)
if [ -z "$py" ]; then
  echo "installing python3"
  apt_install python3 python3-venv || true
  py=$(command -v python3 || true)
fi
[ -n "$py" ] || skip "no python3, and apt-get could not install it"
"$py" -c 'import sys; sys.exit(sys.version_info < (3, 9))' \
  || skip "$("$py" --version 2>&1) is older than the package's 3.9"

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
venv="$work/venv"
if ! "$py" -m venv "$venv" >/dev/null 2>&1; then
  echo "installing python3-venv"
  apt_install python3-venv || true
  rm -rf "$venv"
  "$py" -m venv "$venv" >/dev/null 2>&1 || skip "python3 -m venv fails and apt-get could not install python3-venv"
fi
vpy="$venv/bin/python"

echo "== pip install maturin pytest numpy pandas matplotlib"
timeout 600 "$vpy" -m pip install -q --disable-pip-version-check \
  "maturin>=1.7,<2" pytest numpy pandas \
  || skip "pip could not install maturin, pytest, numpy and pandas"
# The example's test needs matplotlib; without it that test skips.
timeout 300 "$vpy" -m pip install -q --disable-pip-version-check matplotlib \
  || echo "note: pip could not install matplotlib: the example's test will skip"
# Controller.nlsys's tests and example need python-control.
timeout 300 "$vpy" -m pip install -q --disable-pip-version-check control \
  || echo "note: pip could not install control (python-control): the nlsys tests will skip"

echo "== maturin build --profile dev"
start=$(date +%s)
(
  cd bindings/python
  CARGO_TARGET_DIR="$root/target" "$venv/bin/maturin" build --profile dev --locked \
    --interpreter "$vpy" -o "$work/wheels" --quiet
)
"$vpy" -m pip install -q --disable-pip-version-check --no-deps "$work"/wheels/ehservo-*.whl
echo "built and installed in $(($(date +%s) - start)) s"

# The CLI the tests compare with: the one CI built already, else a build.
cli="$root/target/release/ehservo"
[ -x "$cli" ] || cli="$root/target/debug/ehservo"
[ -x "$cli" ] || { cargo build -q -p ehservo && cli="$root/target/debug/ehservo"; }

echo "== the guide's Python blocks, with the package installed (docs/guide/README.md)"
EHSERVO_GUIDE_PYTHON="$vpy" EHSERVO_GUIDE_REQUIRE=python \
  cargo test -q --workspace --test it -- guide::readme guide::python_c_fmi guide::troubleshooting

echo "== pytest (bindings/python/tests)"
cd bindings/python
EHSERVO_CLI="$cli" "$vpy" -m pytest -q -p no:cacheprovider tests
