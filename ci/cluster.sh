#!/usr/bin/env bash
# The cluster path (docs/cluster.md): the Slurm job array end to end on a
# one-node Slurm (ci/slurm.sh), then the Kubernetes manifest and the
# Dockerfile checked (ci/deploy.sh), and, when EHSERVO_IMAGE_TEST=1, the
# image built and the manifest's command run in it (ci/image.sh: about 7
# minutes, more than CI's budget leaves). Each prints "SKIPPED ..." and
# passes when what it needs cannot be installed here.
set -euo pipefail
cd "$(dirname "$0")/.."
echo "== Slurm job array on a one-node Slurm"
ci/slurm.sh
echo "== Kubernetes manifest and Dockerfile"
ci/deploy.sh
echo "== The container image"
if [ "${EHSERVO_IMAGE_TEST:-0}" = 1 ]; then
  ci/image.sh
else
  echo "SKIPPED the image build and run (ci/image.sh, about 7 minutes): set EHSERVO_IMAGE_TEST=1 to run it"
fi
