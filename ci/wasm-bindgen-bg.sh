#!/usr/bin/env bash
# wasm-bindgen-cli for the browser step (ci/web.sh), built in the background
# at the lowest CPU priority while the other CI steps run.
#
# No prebuilt wasm-bindgen can be downloaded here, so a fresh machine must
# `cargo install` it: 5-8 minutes of two cores, which would not fit after
# the other steps in CI's 30 minutes. Started first thing by .ci/run under
# `nice -n 19` (its scheduler autogroup niced too), it takes only the CPU the
# steps before the browser test leave idle (links, the single-threaded tests, QEMU, Slurm's waits); ci/web.sh
# then waits for it with what is left of the budget.
#
#   ci/wasm-bindgen-bg.sh start   # start it if the CLI of Cargo.lock's version is missing
#   ci/wasm-bindgen-bg.sh wait S  # wait up to S seconds; exit 0 when it is installed
#   ci/wasm-bindgen-bg.sh stop    # kill a build still running (.ci/run's exit)
#
# State in target/ci-wasm-bindgen/ (pid, log, rc); the build's own target
# directory is target/ci-wasm-bindgen/build, apart from the workspace's, so
# it never waits on the main build's lock (nor the main build on it).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
state="$root/target/ci-wasm-bindgen"
version=$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/version = |"/, ""); print; exit }' Cargo.lock)

have_bindgen() {
  local b
  for b in wasm-bindgen "$HOME/.cargo/bin/wasm-bindgen"; do
    command -v "$b" >/dev/null 2>&1 \
      && [ "$("$b" --version 2>/dev/null | awk '{print $2}')" = "$version" ] && return 0
  done
  return 1
}

running() {
  [ -f "$state/pid" ] && [ ! -f "$state/rc" ] && kill -0 "$(cat "$state/pid")" 2>/dev/null
}

case "${1:-}" in
  start)
    have_bindgen && exit 0
    running && exit 0
    rm -rf "$state"
    mkdir -p "$state"
    # setsid: its own process group, so `stop` can end cargo and rustc too.
    # shellcheck disable=SC2016 # expanded by the inner bash, from "$@"
    setsid nohup bash -c '
      # A new session is a new scheduler autogroup, and the kernel shares
      # the CPU fairly between autogroups whatever the nice values inside
      # them: the autogroup itself must be niced, or this build takes half
      # the machine from the steps it should only fill in behind.
      echo 19 >/proc/self/autogroup 2>/dev/null || true
      rc=0
      { rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown \
          || timeout 300 rustup target add wasm32-unknown-unknown; } || rc=$?
      if [ "$rc" -eq 0 ]; then
        CARGO_TARGET_DIR="$1/build" nice -n 19 cargo install -q \
          wasm-bindgen-cli --version "$2" || rc=$?
      fi
      rm -rf "$1/build"
      echo "$rc" >"$1/rc.tmp" && mv "$1/rc.tmp" "$1/rc"
    ' _ "$state" "$version" >"$state/log" 2>&1 </dev/null &
    echo $! >"$state/pid"
    echo "building wasm-bindgen-cli $version in the background (nice 19) for ci/web.sh"
    ;;
  wait)
    budget=${2:?seconds}
    start=$(date +%s)
    while running; do
      if [ $(($(date +%s) - start)) -ge "$budget" ]; then
        exit 1
      fi
      sleep 5
    done
    have_bindgen
    ;;
  stop)
    if running; then
      kill -TERM -- "-$(cat "$state/pid")" 2>/dev/null || true
      echo "stopped the background wasm-bindgen-cli build (not finished)"
    fi
    ;;
  status)
    if have_bindgen; then echo installed
    elif running; then echo running
    elif [ -f "$state/rc" ]; then echo "failed (rc $(cat "$state/rc")): see $state/log"
    else echo absent
    fi
    ;;
  *)
    echo "usage: $0 start | wait SECONDS | stop | status" >&2
    exit 2
    ;;
esac
