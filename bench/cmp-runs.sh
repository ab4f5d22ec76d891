#!/bin/bash
# Two builds of `ehservo` give the same outputs, bit for bit: every shipped
# scenario (scenarios/{paper,examples,realistic}) is run by both with
# `run --no-plot`, and their trace.csv and summary.json (but for its
# elapsed time) compared byte by byte; so is the exit code. For a change
# meant to keep the bits (a speed-up), before it lands.
#
# usage: bench/cmp-runs.sh OLD NEW   (paths of two ehservo executables)
set -u
if [ $# -ne 2 ] || [ ! -x "$1" ] || [ ! -x "$2" ]; then
    echo "usage: bench/cmp-runs.sh OLD NEW   (two ehservo executables)" >&2
    exit 2
fi
old=$1
new=$2
root=$(cd "$(dirname "$0")/.." && pwd)
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT INT TERM
n=0
bad=0
for f in "$root"/scenarios/paper/*.toml "$root"/scenarios/examples/*.toml "$root"/scenarios/realistic/*.toml; do
    n=$((n + 1))
    b=$(basename "$f" .toml)
    "$old" run "$f" --out "$d/o-$b" -q --no-plot >/dev/null 2>&1
    r1=$?
    "$new" run "$f" --out "$d/n-$b" -q --no-plot >/dev/null 2>&1
    r2=$?
    if [ "$r1" != "$r2" ]; then
        echo "exit codes differ: $f ($r1, $r2)"
        bad=$((bad + 1))
        continue
    fi
    [ -d "$d/o-$b" ] || continue
    if ! cmp -s "$d/o-$b/trace.csv" "$d/n-$b/trace.csv"; then
        echo "trace.csv differs: $f"
        bad=$((bad + 1))
    fi
    if ! cmp -s <(grep -v elapsed "$d/o-$b/summary.json") <(grep -v elapsed "$d/n-$b/summary.json"); then
        echo "summary.json differs: $f"
        bad=$((bad + 1))
    fi
done
echo "$n scenarios, $bad differences"
[ "$bad" -eq 0 ]
