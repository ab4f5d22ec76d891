#!/usr/bin/env bash
# The small measured table of docs/solvers.md: CPU per simulated second and
# the largest position error against a fine RK4 reference, for RK4 at its
# sub-steps and the adaptive solvers at their tolerances, on one cylinder
# cylinder scenario. Needs a release binary:
#   cargo build --release -p ehservo
#   bench/solvers.sh path/to/ehservo SCENARIO HORIZON_S > table.md
# e.g. bench/solvers.sh target/release/ehservo scenarios/cylinders/chrono-single-rod.toml 6
# CPU is user+sys of `/usr/bin/time` for the whole `ehservo run` (reading,
# building, writing trace.csv included), best of 3.
set -euo pipefail
BIN=$1
SCEN=$2
HORIZON=$3
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT

run() { # name, --set args...
    local name=$1; shift
    local best=""
    for _ in 1 2 3; do
        local t
        t=$( { /usr/bin/time -f "%U %S" "$BIN" run "$SCEN" --no-plot --quiet --out "$OUT/$name" --set "simulation.horizon=$HORIZON" "$@" >/dev/null; } 2>&1 | tail -1 | awk '{print $1 + $2}')
        if [ -z "$best" ] || awk "BEGIN{exit !($t < $best)}"; then best=$t; fi
    done
    echo "$best"
}

maxerr() { # reference dir, run dir: max |y − y_ref| in m (trace.csv's y_mm / 1000)
    python3 - "$1/trace.csv" "$2/trace.csv" <<'PY'
import csv, sys
def col(p):
    return [float(r["y_mm"]) for r in csv.DictReader(open(p))]
a, b = col(sys.argv[1]), col(sys.argv[2])
assert len(a) == len(b), (len(a), len(b))
print(f"{max(abs(x - y) for x, y in zip(a, b)) / 1000:.2e}")
PY
}

"$BIN" run "$SCEN" --no-plot --quiet --out "$OUT/ref" --set simulation.substeps=1000 --set "simulation.horizon=$HORIZON"   # RK4 at step/1000: the reference
echo "| solver | settings | CPU s per simulated s | max \|y − y_ref\| (m) | steps accepted / rejected |"
echo "|---|---|---|---|---|"
row() { # label, settings text, name, --set args...
    local label=$1 text=$2 name=$3; shift 3
    local cpu err steps
    cpu=$(run "$name" "$@")
    err=$(maxerr "$OUT/ref" "$OUT/$name")
    steps=$(python3 -c "import json,sys; s=json.load(open('$OUT/$name/summary.json'))['solver']; print(f\"{s['accepted_steps']} / {s['rejected_steps']}\" if 'accepted_steps' in s else '—')")
    echo "| $label | $text | $(awk "BEGIN{printf \"%.3f\", $cpu / $HORIZON}") | $err | $steps |"
}
row rk4 "substeps = 1" rk1 --set simulation.substeps=1
row rk4 "substeps = 10" rk10 --set simulation.substeps=10
row rk4 "substeps = 100" rk100 --set simulation.substeps=100
for tol in 1e-3 1e-6 1e-9; do
    row dopri5 "rtol = $tol" "d$tol" --set simulation.substeps=1 --set 'simulation.solver="dopri5"' --set "simulation.rtol=$tol" --set 'simulation.atol=[1e-12, 1e-9, 1.0, 1.0, 1.0, 1e-12]'
done
for tol in 1e-3 1e-6; do
    row bs32 "rtol = $tol" "b$tol" --set simulation.substeps=1 --set 'simulation.solver="bs32"' --set "simulation.rtol=$tol" --set 'simulation.atol=[1e-12, 1e-9, 1.0, 1.0, 1.0, 1e-12]'
done
for tol in 1e-3 1e-6; do
    row rosenbrock23 "rtol = $tol" "r$tol" --set simulation.substeps=1 --set 'simulation.solver="rosenbrock23"' --set "simulation.rtol=$tol" --set 'simulation.atol=[1e-12, 1e-9, 1.0, 1.0, 1.0, 1e-12]'
done
