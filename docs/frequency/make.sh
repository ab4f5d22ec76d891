#!/usr/bin/env bash
# Re-makes every output of docs/frequency.md (about a minute on 2 cores;
# EHSERVO=path/to/ehservo to use another build). Each `ehservo freq`
# replaces its folder as a whole.
set -euo pipefail
cd "$(dirname "$0")/../.."
B=${EHSERVO:-target/release/ehservo}
out=docs/frequency
# §3: the league's controllers on the Fig. 2 servo (the league's tuned
# parameters, and the paper's NNBVSC), and the ADRC with its model-assisted
# defaults.
for c in nnvsc-paper nnvsc nn-robust pid backstepping sta arc vsc-sat adrc; do
  plot=--no-plot
  case $c in pid | nnvsc-paper) plot= ;; esac
  $B freq docs/league/suite/scenarios/$c/fig2.toml --out $out/league/$c --points 60 $plot -q
done
$B freq scenarios/league/adrc-fig2.toml --out $out/league/adrc-model-assisted --points 60 --no-plot -q
# §4: the realistic delay study's loops (1 kHz and 100 Hz, 150 Hz valve).
for base in base base-10ms; do
  for c in nnvsc vsc-sat pid; do
    $B freq scenarios/realistic/$base.toml --set controller.kind=$c --out $out/delay/$base-$c --points 60 --no-plot -q
  done
done
# §5: a linear loop, and the PID on the paper's plant at three amplitudes.
$B freq scenarios/frequency/pid-nominal.toml --out $out/linear/pid-nominal \
  --amplitude-deg 0.01 --disturbance 0.002 --measure sine,multisine --points 200 -q
for a in 0.05 0.5 2; do
  d=$(python3 -c "print($a / 10)")
  $B freq docs/league/suite/scenarios/pid/fig2.toml --discretise rk4 --amplitude-deg $a \
    --disturbance "$d" --out $out/amplitude/pid-rk4-$a --points 60 --no-plot -q
done
# §3: the NNBVSC's tracking at other amplitudes, disturbances and rates.
for a in 0.05 2 5; do
  $B freq scenarios/paper/fig2.toml --amplitude-deg $a --out $out/amplitude/nnvsc-$a --points 60 --no-plot -q
done
for d in 0.01 0.2; do
  $B freq scenarios/paper/fig2.toml --disturbance $d --out $out/amplitude/nnvsc-d$d --points 40 --no-plot -q
done
$B freq scenarios/paper/fig2.toml --set simulation.step=0.001 --amplitude-deg 5 --measure-f-max 10 \
  --out $out/amplitude/nnvsc-5-1ms --points 60 --no-plot -q
