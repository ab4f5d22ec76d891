#!/usr/bin/env bash
# Builds the image of deploy/k8s/sweep-job.yaml from the Dockerfile, as it
# is, and runs the manifest's command in it for every index of a small
# study; the shards merged must give the single-machine results.csv, byte
# for byte (docs/cluster.md, "The container image").
#
# The engine is Docker when a Docker daemon answers, else Podman (installed
# from Debian's packages when missing: it needs no daemon). The Dockerfile's
# base images (rust:1.95-slim-bookworm, debian:bookworm-slim) are pulled
# when a registry answers. Where none does (a machine that reaches only
# Debian's and the language registries, as this project's CI), stand-ins
# of the same names are made locally and the build is told not to pull:
#   debian:bookworm-slim     <- debootstrap --variant=minbase bookworm
#   rust:1.95-slim-bookworm  <- that + gcc, libc6-dev, ca-certificates and
#                               this machine's Rust toolchain, laid out as
#                               the official image lays it out
#                               (/usr/local/rustup, /usr/local/cargo)
# plus this machine's CA bundle in the Rust stand-in, so that its cargo can
# reach crates.io through the same TLS proxy as the host. The build runs
# with the host's network (cargo fetches the locked crates).
#
# usage: ci/image.sh [TAG]     (default localhost/ehservo:ci)
# Prints "SKIPPED ..." and exits 0 when no engine can be had; exits 1 when
# the image does not build or its results differ.
set -euo pipefail
cd "$(dirname "$0")/.."
tag=${1:-localhost/ehservo:ci}
study=scenarios/studies/cluster-smoke.toml
job=deploy/k8s/sweep-job.yaml

skip() {
  echo "SKIPPED the image build: $*"
  exit 0
}
sudo=()
if [ "$(id -u)" -ne 0 ]; then sudo=(sudo -n); fi
apt_get() {
  timeout 900 "${sudo[@]}" env DEBIAN_FRONTEND=noninteractive apt-get -q "$@" >/dev/null 2>&1
}
apt_install() {
  apt_get install -y --no-install-recommends "$@" \
    || { apt_get update && apt_get install -y --no-install-recommends "$@"; }
}

if docker info >/dev/null 2>&1; then
  engine=(docker)
else
  if ! command -v podman >/dev/null 2>&1; then
    echo "no Docker daemon: installing podman"
    apt_install podman crun fuse-overlayfs || true
  fi
  command -v podman >/dev/null 2>&1 \
    || skip "no Docker daemon answers and podman could not be installed"
  engine=("${sudo[@]}" podman)
fi
echo "engine: ${engine[*]}"
# Flags for `build` and `run`. Docker: none (a local base image is used
# without pulling). Podman: never pull (the bases are made here when no
# registry answers), and the runtime and limits this machine allows, found
# by probe() once a base image exists.
bflags=()
rflags=()
if [ "${engine[-1]}" = podman ]; then bflags=(--pull=never); fi
probed=""
probe() { # $1 = an image to probe with
  [ -n "$probed" ] && return 0
  probed=1
  [ "${engine[-1]}" = podman ] || return 0 # (before a runtime is added to it)
  # Limits the runtime may set: a sandbox may refuse podman's defaults
  # (nofile 1048576) and even this shell's own hard limits, so modest ones
  # (ehservo needs a handful of files and threads).
  local lim rt
  for rt in crun runc; do
    command -v "$rt" >/dev/null 2>&1 || apt_install "$rt" || continue
    for lim in 4096 1024; do
      if "${engine[@]}" --runtime "$rt" run --rm --ulimit "nofile=$lim:$lim" \
           --ulimit "nproc=$lim:$lim" "$1" true >"$work/probe.log" 2>&1; then
        engine+=(--runtime "$rt")
        rflags=(--ulimit "nofile=$lim:$lim" --ulimit "nproc=$lim:$lim")
        bflags+=("${rflags[@]}")
        echo "podman runtime: $rt, nofile and nproc $lim"
        return 0
      fi
    done
    echo "podman with $rt cannot start a container here: $(tail -n 1 "$work/probe.log")"
  done
  skip "podman cannot start a container on this machine (neither crun nor runc)"
}

work=$(mktemp -d)
trap '"${sudo[@]}" rm -rf "$work"' EXIT

# The base images: present, pulled, or made.
mapfile -t bases < <(sed -n 's/^FROM \([^ ]*\).*/\1/p' Dockerfile)
have() { "${engine[@]}" image inspect "$1" >/dev/null 2>&1; }
full() { case $1 in */*) echo "$1" ;; *) echo "docker.io/library/$1" ;; esac; }
make_debian() { # the minbase root file system, imported as $1
  command -v debootstrap >/dev/null 2>&1 || apt_install debootstrap || true
  command -v debootstrap >/dev/null 2>&1 \
    || skip "no registry answers for the base images and debootstrap could not be installed"
  echo "making a stand-in for $1 with debootstrap (minbase bookworm)"
  "${sudo[@]}" debootstrap --variant=minbase bookworm "$work/rootfs" http://deb.debian.org/debian \
    >"$work/debootstrap.log" 2>&1 || { tail -n 20 "$work/debootstrap.log"; exit 1; }
  "${sudo[@]}" tar -C "$work/rootfs" -c . | "${engine[@]}" import - "$1" >/dev/null 2>"$work/import.log" \
    || { cat "$work/import.log"; exit 1; }
}
make_rust() { # $1 = the rust image's name; needs the machine's toolchain
  local sysroot ver ctx
  sysroot=$(rustc --print sysroot)
  ver=$(rustc --version | awk '{print $2}')
  case $1 in *:"$ver"-*|*:"$ver"|*:"${ver%.*}"-*|*:"${ver%.*}") ;;
    *) echo "note: $1 asks for a Rust other than this machine's $ver: the stand-in has $ver" ;;
  esac
  have docker.io/library/debian:bookworm-slim || make_debian docker.io/library/debian:bookworm-slim
  ctx="$work/rust-ctx"
  mkdir -p "$ctx/toolchain"
  echo "making a stand-in for $1 with this machine's Rust $ver ($sysroot)"
  # The host's toolchain without its docs and other targets' libraries.
  tar -C "$sysroot" -c --exclude=./share/doc --exclude='./lib/rustlib/thumb*' \
    --exclude='./lib/rustlib/wasm*' --exclude=./lib/rustlib/src . | tar -C "$ctx/toolchain" -x
  cp /etc/ssl/certs/ca-certificates.crt "$ctx/ca-certificates.crt"
  cat >"$ctx/Containerfile" <<EOF
FROM docker.io/library/debian:bookworm-slim
RUN apt-get update && apt-get install -y --no-install-recommends gcc libc6-dev ca-certificates \\
 && rm -rf /var/lib/apt/lists/*
COPY ca-certificates.crt /etc/ssl/certs/ca-certificates.crt
COPY toolchain /usr/local/rustup/toolchains/$ver-x86_64-unknown-linux-gnu
RUN mkdir -p /usr/local/cargo/bin && for b in cargo rustc rustdoc; do \\
      ln -s /usr/local/rustup/toolchains/$ver-x86_64-unknown-linux-gnu/bin/\$b /usr/local/cargo/bin/\$b; done
ENV RUSTUP_HOME=/usr/local/rustup CARGO_HOME=/usr/local/cargo RUST_VERSION=$ver \\
    PATH=/usr/local/cargo/bin:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
EOF
  probe docker.io/library/debian:bookworm-slim
  "${engine[@]}" build -q "${bflags[@]}" --network=host -t "$1" -f "$ctx/Containerfile" "$ctx" >/dev/null
}
for b in "${bases[@]}"; do
  case $b in build) continue ;; esac # a stage, not an image
  f=$(full "$b")
  if have "$f"; then
    echo "base $f: present"
  elif timeout 120 "${engine[@]}" pull -q "$f" >/dev/null 2>&1; then
    echo "base $f: pulled"
  else
    case $b in
      rust:*) make_rust "$f" ;;
      debian:bookworm*) make_debian "$f" ;;
      *) skip "the base image $f cannot be pulled and there is no recipe for a stand-in" ;;
    esac
  fi
done

probe "$(full "${bases[-1]}")"
echo "building $tag from the Dockerfile"
start=$(date +%s)
"${engine[@]}" build "${bflags[@]}" --network=host -t "$tag" . >"$work/build.log" 2>&1 \
  || { tail -n 40 "$work/build.log"; echo "the image did not build (log above)"; exit 1; }
echo "built $tag in $(($(date +%s) - start)) s"
"${engine[@]}" run "${rflags[@]}" --rm --network=none "$tag" ehservo --version

# The manifest's command, for every index, in the image, as the manifest's
# user, with the study and the results where the manifest mounts them.
n=$(sed -n 's/^  completions: *\([0-9]*\)$/\1/p' "$job")
cmd=$(python3 -c '
import sys, yaml
job = yaml.safe_load(open(sys.argv[1]))
c = job["spec"]["template"]["spec"]["containers"][0]
print(c["command"][2])' "$job")
echo "the manifest's command (index K of $n): $cmd"
mkdir -p "$work/study" "$work/results"
# The ConfigMap of docs/cluster.md: the study as study.toml, its base
# scenario beside it as base.toml.
base=$(sed -n 's/^base = "\(.*\)"$/\1/p' "$study")
sed 's/^base = ".*"$/base = "base.toml"/' "$study" >"$work/study/study.toml"
[ -z "$base" ] || cp "$(dirname "$study")/$base" "$work/study/base.toml"
chmod -R a+rwX "$work/results"
start=$(date +%s)
for k in $(seq 0 $((n - 1))); do
  "${engine[@]}" run "${rflags[@]}" --rm --network=none --user 10001:10001 -e JOB_COMPLETION_INDEX="$k" \
    -v "$work/study:/study:ro" -v "$work/results:/results" \
    "$tag" sh -c "$cmd"
done
echo "$n shards in the image in $(($(date +%s) - start)) s"
"${engine[@]}" run "${rflags[@]}" --rm --network=none -v "$work/results:/results" "$tag" \
  sh -c 'ehservo merge /results/shards/* --out /results/merged'
ehservo=target/release/ehservo
[ -x "$ehservo" ] || cargo build --release -q -p ehservo
"$ehservo" sweep "$study" --out "$work/single" --quiet
if cmp "$work/single/results.csv" "$work/results/merged/results.csv"; then
  echo "the image's $n shards, merged, give the single-machine results.csv byte for byte"
else
  echo "the image's merged results.csv differs from the single-machine one" >&2
  exit 1
fi
