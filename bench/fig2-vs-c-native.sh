#!/bin/sh
# bench/fig2-vs-c.sh with a third program: the same Rust bench built with
# the C's flags (RUSTFLAGS="-C target-cpu=native", into target/native), so
# that the two Rust builds and the C run interleaved, the order rotated.
# Prints each triple and the median ratios to C.
#
# usage: bench/fig2-vs-c-native.sh [TRIPLES (default 9)] [N (default 2000)]
set -eu
triples=${1:-9}
n=${2:-2000}
root=$(cd "$(dirname "$0")/.." && pwd)
src=${NNVSC_C:-}
for c in "$root/../shared/peers/c/nnvsc.c" /work/shared/peers/c/nnvsc.c; do
    if [ -z "$src" ] && [ -f "$c" ]; then src=$c; fi
done
if [ -z "$src" ] || [ ! -f "$src" ]; then
    echo "the C yardstick nnvsc.c was not found; set NNVSC_C" >&2
    exit 2
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT INT TERM
gcc -std=c99 -O3 -march=native -o "$tmp/nnvsc" "$src" -lm
cd "$root"
cargo bench -q -p ehservo --bench sweep_run --no-run
RUSTFLAGS="-C target-cpu=native" CARGO_TARGET_DIR="$root/target/native" \
    cargo bench -q -p ehservo --bench sweep_run --no-run
# The newest bench executable (not its .d file) under $1.
latest() {
    # shellcheck disable=SC2010 # cargo's hashed names: no spaces
    ls -t "$1"/release/deps/sweep_run-* | grep -v '\.d$' | head -n 1
}
c="$tmp/nnvsc"
r=$(latest "${CARGO_TARGET_DIR:-$root/target}")
rn=$(latest "$root/target/native")
echo "C: $c ($src); Rust: $r; Rust native: $rn"
cpu() { sed -n 's/.*us per run (wall), \([0-9.]*\) us (cpu).*/\1/p' | head -n 1; }
"$c" bench 200 fast 1 >/dev/null; "$r" 200 1 >/dev/null; "$rn" 200 1 >/dev/null
i=1
while [ "$i" -le "$triples" ]; do
    case $((i % 3)) in
    0) tc=$("$c" bench "$n" fast 1 | cpu); tr=$("$r" "$n" 1 | cpu); tn=$("$rn" "$n" 1 | cpu) ;;
    1) tr=$("$r" "$n" 1 | cpu); tn=$("$rn" "$n" 1 | cpu); tc=$("$c" bench "$n" fast 1 | cpu) ;;
    *) tn=$("$rn" "$n" 1 | cpu); tc=$("$c" bench "$n" fast 1 | cpu); tr=$("$r" "$n" 1 | cpu) ;;
    esac
    echo "$tc $tr $tn" >>"$tmp/t"
    echo "$i $tc $tr $tn" | awk '{ printf "triple %2d: C %7.1f us  Rust %7.1f us (%.3f)  Rust native %7.1f us (%.3f)\n", $1, $2, $3, $3 / $2, $4, $4 / $2 }'
    i=$((i + 1))
done
awk '
function median(a, n,   i, j, t) {
    for (i = 2; i <= n; i++) { t = a[i]; for (j = i - 1; j > 0 && a[j] > t; j--) a[j + 1] = a[j]; a[j + 1] = t }
    return n % 2 ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2
}
{ n++; r[n] = $2 / $1; q[n] = $3 / $1 }
END { printf "median ratio to C over %d triples: Rust %.3f, Rust native %.3f\n", n, median(r, n), median(q, n) }' "$tmp/t"
