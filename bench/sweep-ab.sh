#!/bin/sh
# Two builds of the `sweep_run` bench against each other, on this machine,
# now: ROUNDS rounds of N Fig. 2 runs each, the two alternated (which goes
# first rotates). Prints each one's smallest and median CPU time per run,
# and the median of the rounds' ratios (B / A). For changes too small for
# bench/fig2-vs-c.sh to resolve: build the old commit into another target
# directory, e.g.
#   git worktree add /tmp/old OLD && (cd /tmp/old && CARGO_TARGET_DIR=$PWD/target/old \
#       cargo bench -p ehservo --bench sweep_run --no-run)
#   bench/sweep-ab.sh target/old/release/deps/sweep_run-HASH target/release/deps/sweep_run-HASH
#
# usage: bench/sweep-ab.sh A B [ROUNDS (default 40)] [N (default 300)]
set -eu
if [ $# -lt 2 ]; then
    echo "usage: bench/sweep-ab.sh A B [ROUNDS] [N]" >&2
    exit 2
fi
a=$1
b=$2
rounds=${3:-40}
n=${4:-300}
for p in "$a" "$b"; do
    if [ ! -x "$p" ]; then
        echo "sweep-ab: $p is not an executable sweep_run bench" >&2
        exit 2
    fi
done
tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT INT TERM
# CPU µs per run from the bench's first line.
cpu() { "$1" "$n" 1 | sed -n 's/.*(wall), \([0-9.]*\) us (cpu).*/\1/p' | head -n 1; }
r=1
while [ "$r" -le "$rounds" ]; do
    if [ $((r % 2)) = 0 ]; then
        ta=$(cpu "$a")
        tb=$(cpu "$b")
    else
        tb=$(cpu "$b")
        ta=$(cpu "$a")
    fi
    echo "$ta $tb" >>"$tmp"
    r=$((r + 1))
done
"$(dirname "$0")/ab-summary.sh" "$tmp" us "$a" "$b" "$rounds rounds of $n runs"
