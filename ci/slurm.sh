#!/usr/bin/env bash
# The cluster path on a real Slurm (docs/cluster.md): a one-node cluster
# (munged, slurmctld, slurmd of Debian's slurm-wlm) started here in a
# private folder, the shipped job array deploy/slurm/sweep.sbatch submitted
# for scenarios/studies/cluster-smoke.toml in 4 shards, one shard cancelled
# in mid-run (SIGTERM), the missing shard found by `ehservo merge` and
# resubmitted, a damaged shard redone by resubmitting the whole array
# (--resume skips the whole ones), and every merge compared byte for byte
# with the same study run on one machine. Needs root (it starts daemons);
# installs slurm-wlm and munge with apt-get when missing and prints
# "SKIPPED ..." when they cannot be had. Leaves nothing behind: the daemons
# are stopped by their process ids and the folder removed on exit.
#
# Usage: ci/slurm.sh            (builds target/release/ehservo if needed)
#        EHSERVO=path/to/ehservo ci/slurm.sh
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$PWD

skip() {
  echo "SKIPPED the Slurm test: $*"
  exit 0
}
fail() {
  echo "FAILED the Slurm test: $*" >&2
  exit 1
}

if [ -z "${EHSERVO:-}" ]; then
  cargo build -q --release -p ehservo
  EHSERVO=$repo/target/release/ehservo
fi
EHSERVO=$(realpath "$EHSERVO")
export EHSERVO

echo "== one-node Slurm (ci/slurm-cluster.sh)"
up_log=$(mktemp)
set +e
env=$(ci/slurm-cluster.sh up 2>"$up_log")
rc=$?
set -e
cat "$up_log" >&2
why=$(tail -n 1 "$up_log")
rm -f "$up_log"
[ "$rc" -eq 3 ] && skip "$why"
[ "$rc" -eq 0 ] || fail "ci/slurm-cluster.sh up exited $rc"
eval "$env"
W=$(dirname "$SLURM_CONF")
finish() {
  local rc=$?
  trap - EXIT INT TERM
  cd "$repo"
  if [ "$rc" -ne 0 ]; then
    # What the tasks themselves said (the folder goes with the cluster).
    local f
    for f in "$W"/job/*.out; do
      [ -e "$f" ] || continue
      echo "--- $f (last 30 lines)" >&2
      tail -n 30 "$f" >&2 || true
    done
    ci/slurm-cluster.sh down --logs || true
  else
    ci/slurm-cluster.sh down
  fi
  exit "$rc"
}
trap finish EXIT
trap 'exit 130' INT TERM
mkdir "$W/job"

# The job's state and exit code ("STATE code:signal") of array task $1.
state() { scontrol -o show job "$1" | grep -o 'JobState=[A-Z_]*' | cut -d= -f2; }
exit_code() { scontrol -o show job "$1" | grep -o ' ExitCode=[0-9:]*' | cut -d= -f2; }
# Waits (at most $2 s) until no task of job $1 is queued or running.
wait_job() {
  for _ in $(seq "$2"); do
    [ -z "$(squeue -h -j "$1" 2>/dev/null)" ] && return 0
    sleep 1
  done
  fail "job $1 still queued or running after $2 s: $(squeue -j "$1" 2>&1)"
}

study=$repo/scenarios/studies/cluster-smoke.toml
cd "$W/job"
sub() { sbatch --parsable --cpus-per-task=1 --output="$W/job/%x-%A_%a.out" "$@"; }

echo "== the job array, shard 1/4 cancelled in mid-run"
start=$(date +%s)
job=$(sub --array=0-3 "$repo/deploy/slurm/sweep.sbatch" "$study" shards 4)
for _ in $(seq 120); do [ "$(state "${job}_1")" = RUNNING ] && break; sleep 0.5; done
[ "$(state "${job}_1")" = RUNNING ] \
  || fail "task 1 did not start: $(state "${job}_1") ExitCode=$(exit_code "${job}_1"); $(squeue 2>&1)"
# Its ehservo has started (a shard lasts seconds, the start milliseconds).
for _ in $(seq 100); do pgrep -f -- "--out shards/1 --shard 1/4" >/dev/null && break; sleep 0.1; done
pgrep -f -- "--out shards/1 --shard 1/4" >/dev/null || fail "task 1's ehservo is not running"
sleep 0.5
[ ! -e shards/1 ] || fail "shard 1/4 was done before it could be cancelled: the study is too short"
scancel "${job}_1"
wait_job "$job" 600
for k in 0 2 3; do
  [ "$(state "${job}_$k")" = COMPLETED ] || fail "task $k: $(state "${job}_$k") $(exit_code "${job}_$k")"
done
[ "$(state "${job}_1")" = CANCELLED ] || fail "task 1 was not cancelled: $(state "${job}_1")"
# 130:0 is ehservo's own exit after SIGTERM (its handler ran); 0:9 or 0:15
# would be the signal killing it.
[ "$(exit_code "${job}_1")" = 130:0 ] \
  || fail "task 1 did not stop through its SIGTERM handler: ExitCode=$(exit_code "${job}_1")"
[ ! -e shards/1 ] || fail "the cancelled shard left shards/1: $(ls -la shards/1)"
leftover=$(find shards -mindepth 1 -maxdepth 1 -name '.*')
[ -z "$leftover" ] || fail "the cancelled shard left $leftover"
echo "task 1 cancelled in mid-run (exit 130 after SIGTERM); no shards/1, no staging folder"

echo "== merge names the missing shard; --missing lists it; resubmit only it"
set +e
msg=$("$EHSERVO" merge shards/* --out merged 2>&1)
rc=$?
set -e
echo "$msg"
[ "$rc" -eq 2 ] || fail "merge with a shard missing exited $rc"
grep -q 'shard 1/4 (runs 80..160) is missing.*rerun it with --shard 1/4' <<<"$msg" \
  || fail "merge's message does not name shard 1/4"
[ ! -e merged ] || fail "a refused merge wrote merged/"
todo=$("$EHSERVO" merge --missing shards/*)
[ "$todo" = 1 ] || fail "merge --missing printed '$todo', not 1"
job2=$(sub --array="$todo" "$repo/deploy/slurm/sweep.sbatch" "$study" shards 4)
wait_job "$job2" 600
[ "$(state "${job2}_1")" = COMPLETED ] || fail "the resubmitted task 1: $(state "${job2}_1")"
"$EHSERVO" merge shards/* --out merged
echo "array, cancel, resubmission and merge: $(($(date +%s) - start)) s"

echo "== the same study on one machine"
t0=$(date +%s)
"$EHSERVO" sweep "$study" --out single --no-plot --quiet
echo "one machine: $(($(date +%s) - t0)) s"
cmp single/results.csv merged/results.csv
echo "merged results.csv is byte-identical to the single-machine run ($(($(wc -l <merged/results.csv) - 1)) runs)"

echo "== a damaged shard redone by resubmitting the whole array (--resume)"
stamp() { stat -c '%i %Y' shards/"$1"/results.csv; }
before=$(for k in 0 1 3; do stamp "$k"; done)
head -n 40 shards/2/results.csv >cut.csv
mv cut.csv shards/2/results.csv
set +e
msg=$("$EHSERVO" merge shards/* --out merged 2>&1)
rc=$?
set -e
echo "$msg"
if [ "$rc" -ne 2 ] || ! grep -q 'shards/2/results.csv.*truncated or incomplete' <<<"$msg"; then
  fail "merge did not refuse the truncated shard 2 clearly (exit $rc)"
fi
todo=$("$EHSERVO" merge --missing shards/* 2>/dev/null)
[ "$todo" = 2 ] || fail "merge --missing printed '$todo', not 2"
job3=$(sub --array=0-3 "$repo/deploy/slurm/sweep.sbatch" "$study" shards 4)
wait_job "$job3" 600
for k in 0 1 2 3; do
  [ "$(state "${job3}_$k")" = COMPLETED ] || fail "task $k of the resubmission: $(state "${job3}_$k")"
done
for k in 0 1 3; do
  grep -q "shard $k/4: already complete" "ehservo-sweep-${job3}_$k.out" \
    || fail "task $k did not skip its whole shard: $(cat "ehservo-sweep-${job3}_$k.out")"
done
[ "$before" = "$(for k in 0 1 3; do stamp "$k"; done)" ] || fail "a whole shard was rewritten"
grep -q 'running again' "ehservo-sweep-${job3}_2.out" \
  || fail "task 2 did not say why it reran: $(cat "ehservo-sweep-${job3}_2.out")"
"$EHSERVO" merge shards/* --out merged
cmp single/results.csv merged/results.csv
echo "shards 0, 1, 3 skipped, shard 2 redone; merged results.csv byte-identical again"
echo "Slurm test passed"
