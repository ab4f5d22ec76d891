#!/bin/sh
# The summary that bench/sweep-ab.sh and bench/run-ab.sh print: from a file
# of rounds, one line "A B" each (the two builds' times), each build's
# smallest and median time and the median of the rounds' ratios (B / A).
#
# usage: bench/ab-summary.sh FILE UNIT A B WHAT   (WHAT: e.g. "40 rounds of 300 runs")
set -eu
file=$1
unit=$2
a=$3
b=$4
what=$5
# The median of a column of numbers (one per line).
median() { sort -g | awk '{ v[NR] = $1 } END { if (NR % 2) print v[(NR + 1) / 2]; else print (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
mina=$(cut -d' ' -f1 "$file" | sort -g | head -n 1)
minb=$(cut -d' ' -f2 "$file" | sort -g | head -n 1)
meda=$(cut -d' ' -f1 "$file" | median)
medb=$(cut -d' ' -f2 "$file" | median)
ratio=$(awk '{ print $2 / $1 }' "$file" | median)
echo "machine load average $(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo '?'); $what"
echo "A: min $mina $unit, median $meda $unit per run   ($a)"
echo "B: min $minb $unit, median $medb $unit per run   ($b)"
awk -v a="$mina" -v b="$minb" -v r="$ratio" 'BEGIN { printf "B/A: minima %.3f, median of the rounds'"'"' ratios %.3f\n", b / a, r }'
