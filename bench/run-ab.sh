#!/bin/sh
# Two builds of the `ehservo` binary against each other on one whole
# process, on this machine, now: ROUNDS rounds of `perf stat -r N` of each
# (which goes first rotates), every run with the same arguments. Prints
# each one's smallest and median CPU time (task-clock) and the median of
# the rounds' ratios (B / A). For changes too small to see in one
# `perf stat`: build the old commit into another target directory, e.g.
#   git worktree add /tmp/old OLD && (cd /tmp/old && CARGO_TARGET_DIR=$PWD/target/old \
#       cargo build --release -p ehservo)
#   bench/run-ab.sh target/old/release/ehservo target/release/ehservo \
#       run scenarios/paper/fig2.toml --out /tmp/ab -q --no-plot
#
# usage: bench/run-ab.sh A B ARGS...   (ROUNDS=31 and N=10 from the environment)
set -eu
if [ $# -lt 3 ]; then
    echo "usage: bench/run-ab.sh A B ARGS...   (env: ROUNDS, default 31; N, default 10)" >&2
    exit 2
fi
a=$1
b=$2
shift 2
rounds=${ROUNDS:-31}
n=${N:-10}
for p in "$a" "$b"; do
    if [ ! -x "$p" ]; then
        echo "run-ab: $p is not an executable" >&2
        exit 2
    fi
done
if ! command -v perf >/dev/null 2>&1; then
    echo "run-ab: perf is not installed (Debian: linux-perf)" >&2
    exit 2
fi
# Both must run the command: a failing run would be timed all the same.
for p in "$a" "$b"; do
    if ! "$p" "$@" >/dev/null 2>&1; then
        echo "run-ab: the command fails with $p (try: $p $*)" >&2
        exit 1
    fi
done
tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT INT TERM
# Mean CPU ms per run over n runs (perf stat's task-clock).
cpu() {
    bin=$1
    shift
    perf stat -r "$n" -x, -e task-clock "$bin" "$@" 2>&1 >/dev/null | awk -F, '/task-clock/ { print $1 }'
}
r=1
while [ "$r" -le "$rounds" ]; do
    if [ $((r % 2)) = 0 ]; then
        ta=$(cpu "$a" "$@")
        tb=$(cpu "$b" "$@")
    else
        tb=$(cpu "$b" "$@")
        ta=$(cpu "$a" "$@")
    fi
    if [ -z "$ta" ] || [ -z "$tb" ]; then
        echo "run-ab: perf stat gave no task-clock" >&2
        exit 1
    fi
    echo "$ta $tb" >>"$tmp"
    r=$((r + 1))
done
"$(dirname "$0")/ab-summary.sh" "$tmp" ms "$a" "$b" "$rounds rounds of $n runs each"
