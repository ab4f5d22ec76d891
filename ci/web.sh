#!/usr/bin/env bash
# CI: the browser playground (web/) in a real browser. Builds it
# (web/build.sh), then drives Debian's Chromium headless with playwright-core
# (web/test/e2e.mjs): no console error, a slider moves e_max, the e_max shown
# equals `ehservo run`'s, the URL restores the set-up, bad input is named
# beside its field, a Fig. 2 run is under 5 ms. Screenshot:
# target/web-test/screenshot.png.
#
# What it needs and cannot have (the wasm target, wasm-bindgen-cli, npm,
# Chromium) makes it print "SKIPPED the browser playground test: <reason>"
# and exit 0; a build or a check that fails fails CI.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)

skip() {
  echo "SKIPPED the browser playground test: $1"
  exit 0
}

# The wasm target.
if ! rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown \
   && ! timeout 300 rustup target add wasm32-unknown-unknown >/dev/null 2>&1; then
  skip "the Rust target wasm32-unknown-unknown is not installed and rustup could not add it"
fi

# wasm-bindgen-cli of the lock file's version: no prebuilt binary can be
# downloaded here, so cargo install (about 5-8 minutes on two cores, once);
# under .ci/run it is already building in the background
# (ci/wasm-bindgen-bg.sh), and this waits for it.
version=$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/version = |"/, ""); print; exit }' Cargo.lock)
have_bindgen() {
  local b
  for b in wasm-bindgen "$HOME/.cargo/bin/wasm-bindgen"; do
    command -v "$b" >/dev/null 2>&1 && [ "$("$b" --version 2>/dev/null | awk '{print $2}')" = "$version" ] && return 0
  done
  return 1
}
if ! have_bindgen; then
  # .ci/run must stay within 30 minutes: the install gets what is left of
  # 27 minutes after the steps before it (CI_STARTED, set by .ci/run), less
  # 3 minutes for the build and the browser test themselves.
  budget=900
  if [ -n "${CI_STARTED:-}" ]; then
    budget=$(( 27 * 60 - ($(date +%s) - CI_STARTED) - 180 ))
    [ "$budget" -gt 900 ] && budget=900
  fi
  used() { echo "$(( $(date +%s) - ${CI_STARTED:-$(date +%s)} )) s used"; }
  if [ "$(ci/wasm-bindgen-bg.sh status)" = running ]; then
    # .ci/run started it in the background (ci/wasm-bindgen-bg.sh).
    echo "waiting for the background wasm-bindgen-cli $version build (up to $budget s)"
    if ! ci/wasm-bindgen-bg.sh wait "$(( budget > 0 ? budget : 0 ))"; then
      ci/wasm-bindgen-bg.sh stop
      skip "wasm-bindgen-cli $version was still building in the background when CI's 30-minute budget ran out ($(used)); $(ci/wasm-bindgen-bg.sh status)"
    fi
  else
    if [ "$budget" -lt 240 ]; then
      skip "wasm-bindgen-cli $version is not installed and building it (5-8 minutes) would take CI past its 30-minute budget ($(used))"
    fi
    echo "installing wasm-bindgen-cli $version (cargo install, up to $budget s)"
    timeout "$budget" cargo install -q wasm-bindgen-cli --version "$version" >/dev/null 2>&1 || true
  fi
  have_bindgen || skip "wasm-bindgen-cli $version is not installed and cargo install could not build it ($(ci/wasm-bindgen-bg.sh status))"
fi

command -v npm >/dev/null 2>&1 \
  || timeout 600 env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends nodejs npm >/dev/null 2>&1 || true
command -v npm >/dev/null 2>&1 || skip "npm is not installed and apt-get could not install it"

chromium=${CHROMIUM:-}
if [ -z "$chromium" ]; then
  if ! command -v chromium >/dev/null 2>&1; then
    echo "installing chromium (apt-get)"
    apt_install() {
      timeout 600 env DEBIAN_FRONTEND=noninteractive \
        apt-get install -y -q --no-install-recommends chromium >/dev/null 2>&1
    }
    apt_install || { timeout 300 apt-get update -q >/dev/null 2>&1 && apt_install; } || true
  fi
  chromium=$(command -v chromium || true)
fi
[ -n "$chromium" ] || skip "chromium is not installed and apt-get could not install it"

# Build the page (installs nothing more: everything is checked above).
WEB_NO_INSTALL=1 web/build.sh || {
  rc=$?
  [ "$rc" -eq 3 ] && skip "web/build.sh found something missing (above)"
  exit "$rc"
}

# The CLI the page is compared with (the debug build the tests made).
cargo build -q -p ehservo
rm -rf target/web-test
node web/test/e2e.mjs --ehservo "$root/target/debug/ehservo" --out "$root/target/web-test" --chromium "$chromium"
echo "screenshot kept: $root/target/web-test/screenshot.png"
