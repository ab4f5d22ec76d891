#!/bin/sh
# A Fig. 2 run inside a sweep against the C yardstick, on this machine, now.
#
# Builds shared/peers/c/nnvsc.c as its README says (gcc -std=c99 -O3
# -march=native) and the `sweep_run` bench (release profile), then runs
# ROUNDS rounds, the programs interleaved and the one that goes first
# rotated:
#   nnvsc bench N fast 1      (N whole runs in C, CPU time per run)
#   sweep_run N 1             (N Fig. 2 runs through ehservo::study::execute
#                              on one thread, CPU time per run)
# With --native, a third program: the same bench built with the C's own
# flags (RUSTFLAGS="-C target-cpu=native", into target/native).
# Prints each round, the medians, and the median of the rounds' ratios
# (Rust / C). The machine may be shared and loaded: read the ratio of a
# round, not the absolute times.
#
# usage: bench/fig2-vs-c.sh [--native] [ROUNDS (default 7)] [N (default 2000)]
#   NNVSC_C=path/to/nnvsc.c   the C source (default: ../shared/peers/c/nnvsc.c
#                             beside the workspace, else /work/shared/...)
#   CARGO_TARGET_DIR          as for cargo (default: target/ in the workspace)
set -eu
native=0
if [ "${1:-}" = --native ]; then native=1; shift; fi
rounds=${1:-7}
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
# The newest bench executable (not its .d file) under the target dir $1.
latest() {
    # shellcheck disable=SC2010 # cargo's hashed names: no spaces
    ls -t "$1"/release/deps/sweep_run-* | grep -v '\.d$' | head -n 1
}
cargo bench -q -p ehservo --bench sweep_run --no-run
rust=$(latest "${CARGO_TARGET_DIR:-$root/target}")
# The ratio depends on the CPU and on its neighbours' load (BENCHMARKS.md
# gives it for an Intel Xeon and an AMD EPYC VM): say which one this is.
cpu_model=$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo 2>/dev/null | head -n 1)
echo "machine: ${cpu_model:-unknown CPU}, $(nproc 2>/dev/null || echo '?') cores, load average $(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo '?')"
echo "C:    $tmp/nnvsc bench $n fast 1   ($src)"
echo "Rust: $rust $n 1"
progs="c r"
if [ "$native" = 1 ]; then
    RUSTFLAGS="-C target-cpu=native" CARGO_TARGET_DIR="$root/target/native" \
        cargo bench -q -p ehservo --bench sweep_run --no-run
    rust_native=$(latest "$root/target/native")
    echo "Rust native: $rust_native $n 1"
    progs="c r rn"
fi
# The CPU µs per run of one batch: the "(cpu)" figure of the batch line.
cpu() { sed -n 's/.*us per run (wall), \([0-9.]*\) us (cpu).*/\1/p' | head -n 1; }
# One batch of program $1 (c, r or rn) with $2 runs, its CPU µs per run.
batch() {
    case $1 in
    c) "$tmp/nnvsc" bench "$2" fast 1 | cpu ;;
    r) "$rust" "$2" 1 | cpu ;;
    rn) "$rust_native" "$2" 1 | cpu ;;
    esac
}
for p in $progs; do batch "$p" 200 >/dev/null; done # warm up (page cache, clocks)
k=$(echo "$progs" | wc -w)
i=1
: >"$tmp/rounds"
while [ "$i" -le "$rounds" ]; do
    # This round's order: the list rotated by i.
    order=$(echo "$progs" | tr ' ' '\n' | awk -v s=$((i % k)) '{ a[NR - 1] = $0 } END { for (j = 0; j < NR; j++) print a[(j + s) % NR] }')
    c=""; r=""; rn=""
    for p in $order; do
        t=$(batch "$p" "$n")
        case $p in c) c=$t ;; r) r=$t ;; rn) rn=$t ;; esac
    done
    echo "$c $r $rn" >>"$tmp/rounds"
    echo "$i $c $r $rn" | awk '{
        printf "round %2d: C %8.1f us  Rust %8.1f us  ratio %.3f", $1, $2, $3, $3 / $2
        if (NF > 3) printf "  Rust native %8.1f us  ratio %.3f", $4, $4 / $2
        printf "\n" }'
    i=$((i + 1))
done
awk '
function median(a, n,   i, j, t) {
    for (i = 2; i <= n; i++) { t = a[i]; for (j = i - 1; j > 0 && a[j] > t; j--) a[j + 1] = a[j]; a[j + 1] = t }
    return n % 2 ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2
}
{ n++; c[n] = $1; r[n] = $2; q[n] = $2 / $1; if (NF > 2) { rn[n] = $3; qn[n] = $3 / $1 }
  if (n == 1 || $1 < cmin) cmin = $1; if (n == 1 || $2 < rmin) rmin = $2 }
END {
    printf "median of %d rounds (CPU per run): C %.1f us, Rust %.1f us; ratio of medians %.3f, median ratio %.3f\n",
        n, median(c, n), median(r, n), median(r, n) / median(c, n), median(q, n)
    # A neighbour only ever slows a batch down: the fastest batch of each
    # program is the least disturbed estimate of its speed.
    printf "fastest batch: C %.1f us, Rust %.1f us; ratio %.3f\n", cmin, rmin, rmin / cmin
    if (n in rn)
        printf "Rust native: median %.1f us, median ratio %.3f\n", median(rn, n), median(qn, n)
}' "$tmp/rounds"
