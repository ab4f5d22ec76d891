#!/usr/bin/env bash
# Builds the browser playground into web/dist (then: cd web/dist &&
# python3 -m http.server 8000, and open http://localhost:8000/).
#
#   1. the wasm32-unknown-unknown target (rustup adds it when missing);
#   2. crates/ehservo-web for it, profile `wasm` (release without debug info);
#   3. wasm-bindgen's JS glue, by the wasm-bindgen CLI of the exact version
#      of the wasm-bindgen crate in Cargo.lock (cargo install when missing);
#   4. uPlot from web/package-lock.json (npm ci), its dist files copied in;
#   5. the page (web/src).
#
# With WEB_NO_INSTALL=1 it installs nothing and exits 3 naming what is
# missing (ci/web.sh uses it to tell "cannot be had" from "broken").
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
dist="$root/web/dist"

missing() {
  echo "missing: $1" >&2
  exit 3
}

# wasm-bindgen's version, from the lock file: the CLI must match it exactly.
version=$(awk '/^name = "wasm-bindgen"$/ { getline; gsub(/version = |"/, ""); print; exit }' Cargo.lock)
[ -n "$version" ] || { echo "no wasm-bindgen in Cargo.lock" >&2; exit 1; }

if ! rustup target list --installed 2>/dev/null | grep -qx wasm32-unknown-unknown; then
  [ "${WEB_NO_INSTALL:-0}" = 1 ] && missing "the Rust target wasm32-unknown-unknown"
  rustup target add wasm32-unknown-unknown
fi

bindgen=""
for c in wasm-bindgen "$HOME/.cargo/bin/wasm-bindgen"; do
  if command -v "$c" >/dev/null 2>&1 && [ "$("$c" --version 2>/dev/null | awk '{print $2}')" = "$version" ]; then
    bindgen=$(command -v "$c")
    break
  fi
done
if [ -z "$bindgen" ]; then
  [ "${WEB_NO_INSTALL:-0}" = 1 ] && missing "wasm-bindgen-cli $version"
  echo "installing wasm-bindgen-cli $version (cargo install: several minutes)"
  cargo install wasm-bindgen-cli --version "$version"
  bindgen="$HOME/.cargo/bin/wasm-bindgen"
fi

command -v npm >/dev/null 2>&1 || missing "npm"

echo "== cargo build -p ehservo-web --target wasm32-unknown-unknown --profile wasm"
cargo build -q -p ehservo-web --target wasm32-unknown-unknown --profile wasm

stage=$(mktemp -d "$root/web/.dist-tmp.XXXXXX")
trap 'rm -rf "$stage"' EXIT
"$bindgen" --target web --no-typescript --out-dir "$stage/pkg" \
  "$root/target/wasm32-unknown-unknown/wasm/ehservo_web.wasm"

echo "== npm ci (uPlot, pinned by web/package-lock.json)"
(cd web && timeout 300 npm ci --no-audit --no-fund --loglevel=error >/dev/null) \
  || missing "uPlot and playwright-core: npm ci could not install them from the registry"
mkdir -p "$stage/vendor"
cp web/node_modules/uplot/dist/uPlot.esm.js web/node_modules/uplot/dist/uPlot.min.css \
  web/node_modules/uplot/LICENSE "$stage/vendor/"
cp web/src/* "$stage/"

# Replace the old dist as a whole (nothing half-written is served).
rm -rf "$dist.old"
[ -d "$dist" ] && mv "$dist" "$dist.old"
mv "$stage" "$dist"
rm -rf "$dist.old"
trap - EXIT
echo "built $dist ($(du -sh "$dist/pkg/ehservo_web_bg.wasm" | cut -f1) of wasm)"
echo "serve it: (cd web/dist && python3 -m http.server 8000), then open http://localhost:8000/"
