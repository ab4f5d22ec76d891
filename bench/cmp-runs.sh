#!/bin/bash
# Two builds of `ehservo` give the same outputs, bit for bit: every shipped
# scenario (every folder of scenarios/ but studies/) is run by both with
# `run --no-plot`, and their trace.csv and summary.json compared byte by
# byte; so is the exit code. A file that `run` refuses in both builds is
# tried as a study (`sweep --no-plot`: results.csv and study.json
# compared), and otherwise counted apart (scenarios/paper/manifest.toml,
# the paper's list of cases). With STUDIES=1 the studies of
# scenarios/studies are swept too (fig8-monte-carlo: 10 000 runs). For a
# change meant to keep the bits (a speed-up), before it lands. The plots
# are not compared.
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
trap 'rm -rf "$d"' EXIT
trap 'exit 130' INT TERM
n=0
skipped=0
bad=0
files=()
for f in "$root"/scenarios/*/*.toml; do
    case "$f" in */scenarios/studies/*) ;; *) files+=("$f") ;; esac
done
if [ "${STUDIES:-0}" = 1 ]; then
    files+=("$root"/scenarios/studies/*.toml)
fi
studies=0
# Both builds sweep study $1; compares what they write.
study() {
    "$old" sweep "$1" --out "$d/o-$2" -q --no-plot >/dev/null 2>&1 || return 1
    "$new" sweep "$1" --out "$d/n-$2" -q --no-plot >/dev/null 2>&1 || {
        echo "sweep fails with the new build only: $1"
        bad=$((bad + 1))
        return 0
    }
    studies=$((studies + 1))
    for out in results.csv study.json; do
        if ! cmp -s "$d/o-$2/$out" "$d/n-$2/$out"; then
            echo "$out differs: $1"
            bad=$((bad + 1))
        fi
    done
}
for f in "${files[@]}"; do
    b=$(basename "$f" .toml)
    rm -rf "$d/o-$b" "$d/n-$b"
    "$old" run "$f" --out "$d/o-$b" -q --no-plot >/dev/null 2>&1
    r1=$?
    "$new" run "$f" --out "$d/n-$b" -q --no-plot >/dev/null 2>&1
    r2=$?
    if [ "$r1" != "$r2" ]; then
        echo "exit codes differ: $f ($r1, $r2)"
        bad=$((bad + 1))
        continue
    fi
    if [ ! -d "$d/o-$b" ]; then
        study "$f" "$b" || skipped=$((skipped + 1))
        rm -rf "$d/o-$b" "$d/n-$b"
        continue
    fi
    n=$((n + 1))
    if ! cmp -s "$d/o-$b/trace.csv" "$d/n-$b/trace.csv"; then
        echo "trace.csv differs: $f"
        bad=$((bad + 1))
    fi
    if ! cmp -s "$d/o-$b/summary.json" "$d/n-$b/summary.json"; then
        echo "summary.json differs: $f"
        bad=$((bad + 1))
    fi
    rm -rf "$d/o-$b" "$d/n-$b"
done
echo "$n scenarios and $studies studies compared, $bad differences ($skipped files neither a scenario nor a study)"
[ "$bad" -eq 0 ]
