#!/bin/sh
# A Fig. 2 run inside a sweep against the C yardstick, on this machine, now.
#
# Builds shared/peers/c/nnvsc.c as its README says (gcc -std=c99 -O3
# -march=native) and the `sweep_run` bench (release profile), then runs
# PAIRS pairs, interleaved and alternating which goes first:
#   nnvsc bench N fast 1      (N whole runs in C, CPU time per run)
#   sweep_run N 1             (N Fig. 2 runs through ehservo::study::execute
#                              on one thread, CPU time per run)
# and prints each pair, the medians of both, and the median of the pairs'
# ratios (Rust / C). The machine may be shared and loaded: read the paired
# ratio, not the absolute times.
#
# usage: bench/fig2-vs-c.sh [PAIRS (default 7)] [N (default 2000)]
#   NNVSC_C=path/to/nnvsc.c   the C source (default: ../shared/peers/c/nnvsc.c
#                             beside the workspace, else /work/shared/...)
#   CARGO_TARGET_DIR          as for cargo (default: target/ in the workspace)
set -eu
pairs=${1:-7}
n=${2:-2000}
root=$(cd "$(dirname "$0")/.." && pwd)
src=${NNVSC_C:-}
if [ -z "$src" ]; then
    for c in "$root/../shared/peers/c/nnvsc.c" /work/shared/peers/c/nnvsc.c; do
        if [ -f "$c" ]; then src=$c; break; fi
    done
fi
if [ -z "$src" ] || [ ! -f "$src" ]; then
    echo "fig2-vs-c: the C yardstick nnvsc.c was not found; set NNVSC_C" >&2
    exit 2
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT INT TERM
gcc -std=c99 -O3 -march=native -o "$tmp/nnvsc" "$src" -lm
cd "$root"
cargo bench -q -p ehservo --bench sweep_run --no-run 2>/dev/null ||
    cargo bench -p ehservo --bench sweep_run --no-run
target=${CARGO_TARGET_DIR:-$root/target}
rust=$(ls -t "$target"/release/deps/sweep_run-* | grep -v '\.d$' | head -n 1)
echo "C:    $tmp/nnvsc bench $n fast 1   ($src)"
echo "Rust: $rust $n 1"
# The CPU µs per run of one batch: the "(cpu)" figure of the batch line.
cpu() { sed -n 's/.*us per run (wall), \([0-9.]*\) us (cpu).*/\1/p' | head -n 1; }
"$tmp/nnvsc" bench 200 fast 1 >/dev/null # warm up both (page cache, clocks)
"$rust" 200 1 >/dev/null
i=1
: >"$tmp/pairs"
while [ "$i" -le "$pairs" ]; do
    if [ $((i % 2)) -eq 1 ]; then
        c=$("$tmp/nnvsc" bench "$n" fast 1 | cpu)
        r=$("$rust" "$n" 1 | cpu)
    else
        r=$("$rust" "$n" 1 | cpu)
        c=$("$tmp/nnvsc" bench "$n" fast 1 | cpu)
    fi
    echo "$c $r" >>"$tmp/pairs"
    awk -v i="$i" -v c="$c" -v r="$r" \
        'BEGIN { printf "pair %2d: C %8.1f us  Rust %8.1f us  ratio %.3f\n", i, c, r, r / c }'
    i=$((i + 1))
done
awk '
function median(a, n,   i, j, t) {
    for (i = 2; i <= n; i++) { t = a[i]; for (j = i - 1; j > 0 && a[j] > t; j--) a[j + 1] = a[j]; a[j + 1] = t }
    return n % 2 ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2
}
{ n++; c[n] = $1; r[n] = $2; q[n] = $2 / $1 }
END {
    printf "median of %d pairs (CPU per run): C %.1f us, Rust %.1f us; ratio of medians %.3f, median ratio %.3f\n",
        n, median(c, n), median(r, n), median(r, n) / median(c, n), median(q, n)
}' "$tmp/pairs"
