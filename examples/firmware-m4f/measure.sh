#!/usr/bin/env bash
# Reproduces the firmware's figures: flash/RAM (text/data/bss), stack
# high-water mark, and instructions per control() step in f32 and f64 on
# thumbv7em-none-eabihf, under QEMU's mps2-an386.
#
#   examples/firmware-m4f/measure.sh            # both float types, 100 000 steps each
#   STEPS=20000 examples/firmware-m4f/measure.sh
#   FLOATS=f32 OPT_LEVEL=s examples/firmware-m4f/measure.sh
#
# Method. QEMU runs with `-icount shift=0,align=off,sleep=off`: virtual time
# advances exactly 1 ns per guest instruction (no host time involved), so
# the SysTick, clocked from the 25 MHz SYSCLK (40 ns), ticks once every 40
# guest instructions. The firmware reads SysTick right before and after each
# control() call. The factor is checked on every run with counted loops
# (subs+bne, 2n instructions), and a short run (TRACE_STEPS) is traced one
# instruction per translation block (`-d exec,nochain` with single-stepping)
# to count each call's instructions exactly and compare.
#
# The f32 build is also traced over its first WORST_STEPS steps for the
# step with the most estimated cycles: by default the first 100 (the
# start-up transient) or, if later, up to and including the step with the
# most SysTick ticks of the full run; WORST_STEPS=100000 traces the whole
# run (about 15 minutes); 0 skips it.
#
# Environment: STEPS (default 100000), FLOATS (default "f32 f64"),
# OPT_LEVEL (overrides the release profile's opt-level), TRACE_STEPS
# (default 5; 0 skips the trace), WORST_STEPS (default: see above; f32 only),
# OUT (default target/firmware-m4f), OBJDUMP (default arm-none-eabi-objdump,
# else llvm-objdump: the cycle model reads either one's disassembly).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
cd "$here"

STEPS="${STEPS:-100000}"
FLOATS="${FLOATS:-f32 f64}"
TRACE_STEPS="${TRACE_STEPS:-5}"
WORST_STEPS="${WORST_STEPS:-auto}"
if ! [[ "$WORST_STEPS" =~ ^(auto|[0-9]+)$ ]]; then
  echo "measure.sh: WORST_STEPS must be 'auto' or a number of steps, not '$WORST_STEPS'" >&2
  exit 2
fi
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$root/target}"
OUT="${OUT:-$CARGO_TARGET_DIR/firmware-m4f}"
mkdir -p "$OUT"
if [ -n "${OPT_LEVEL:-}" ]; then
  export CARGO_PROFILE_RELEASE_OPT_LEVEL="$OPT_LEVEL"
fi
opt="$(sed -n 's/^opt-level *= *//p' Cargo.toml | head -1)"
opt="${OPT_LEVEL:-$opt}"

QEMU=(qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic
      -semihosting-config enable=on,target=native)
ICOUNT=(-icount shift=0,align=off,sleep=off)
IPT=40  # instructions per SysTick tick under ICOUNT: 1 ns each, 25 MHz; checked below
# One instruction per translation block: QEMU >= 8.1 spells it as an accel
# property, older ones as -singlestep.
qv="$(qemu-system-arm --version | sed -n 's/^QEMU emulator version \([0-9]*\)\.\([0-9]*\).*/\1 \2/p')"
read -r qmaj qmin <<<"$qv"
if [ "$qmaj" -gt 8 ] || { [ "$qmaj" -eq 8 ] && [ "$qmin" -ge 1 ]; }; then
  ONE_INSN=(-accel tcg,one-insn-per-tb=on)
else
  ONE_INSN=(-singlestep)
fi

pick() { for t in "$@"; do if command -v "$t" >/dev/null 2>&1; then echo "$t"; return; fi; done; }
SIZE="$(pick arm-none-eabi-size llvm-size size)"
OBJDUMP="${OBJDUMP:-$(pick arm-none-eabi-objdump llvm-objdump)}"
[ -n "$OBJDUMP" ] || { echo "measure.sh: no objdump for Arm: install binutils-arm-none-eabi (or LLVM's llvm-objdump)" >&2; exit 1; }
NM="$(pick arm-none-eabi-nm llvm-nm nm)"
CXXFILT="$(pick arm-none-eabi-c++filt c++filt llvm-cxxfilt cat)"

report="$OUT/measure-opt${opt}.txt"
: >"$report"
say() { echo "$@" | tee -a "$report"; }

say "== firmware-m4f measurements ($(date -u +%Y-%m-%d), $(qemu-system-arm --version | head -1), $(rustc --version))"
say "opt-level=$opt steps=$STEPS trace_steps=$TRACE_STEPS size_tool=$SIZE objdump=$OBJDUMP"

for fl in $FLOATS; do
  feat=()
  [ "$fl" = f64 ] && feat=(--features f64)
  cargo build --release -q "${feat[@]}"
  elf="$OUT/ehservo-firmware-m4f-$fl-opt$opt.elf"
  cp "$CARGO_TARGET_DIR/thumbv7em-none-eabihf/release/ehservo-firmware-m4f" "$elf"

  say ""
  say "-- $fl"
  say "size ($SIZE $(basename "$elf")):"
  "$SIZE" "$elf" | tee -a "$report"

  dis="$OUT/$fl-opt$opt.dis"
  "$OBJDUMP" -d "$elf" >"$dis"
  hw=$(grep -cE '\sv(add|sub|mul|mla|mls|nmul|div|sqrt|fma|abs|neg|cmp)\.f32\s' "$dis" || true)
  soft=$(grep -cE 'bl.*<(__aeabi_d(add|sub|mul|div)|__(add|sub|mul|div)df3)>' "$dis" || true)
  say "hardware f32 instructions (vadd/vmul/vmla/vdiv.f32 …) in the binary: $hw; calls to software f64 add/sub/mul/div: $soft"
  # The f32 build must compute on the FPU (the f64 one cannot: the M4F's
  # FPU is single precision, so f64 is software).
  if [ "$fl" = f32 ] && [ "$hw" -eq 0 ]; then
    say "error: no hardware-float instruction in the f32 build"
    exit 1
  fi

  # Full run under icount.
  log="$OUT/icount-$fl-opt$opt.out"
  start=$(date +%s)
  "${QEMU[@]}" "${ICOUNT[@]}" -kernel "$elf" -append "$STEPS" >"$log"
  secs=$(($(date +%s) - start))
  grep -E '^(timing|calib|stack|e_max_deg)' "$log" | tee -a "$report"
  awk -v fl="$fl" -v secs="$secs" '
    /^calib:/ { split($2, a, "="); split($3, b, "="); n++; ins[n] = a[2]; tk[n] = b[2] }
    /^timing: control\(\)/ {
      for (i = 4; i <= NF; i++) { split($i, kv, "="); v[kv[1]] = kv[2] }
    }
    /^timing: sense\(\)/ {
      for (i = 4; i <= NF; i++) { split($i, kv, "="); sv[kv[1]] = kv[2] }
    }
    END {
      ipt = (ins[2] - ins[1]) / (tk[2] - tk[1])
      printf "calibration: %d instructions in %d ticks, %d in %d: %.4f instructions per tick (each reading +-1 tick)\n", ins[1], tk[1], ins[2], tk[2], ipt
      if (ipt < 39.99 || ipt > 40.01) { printf "error: expected 40 instructions per SysTick tick (25 MHz, 1 ns per instruction)\n"; exit 1 }
      ipt = 40
      printf "%s control() = SampledController::step: mean %.1f instructions/step over %d steps; worst step %d ticks = %d..%d instructions (k=%d); qemu %ds\n",
        fl, v["total"] * ipt / v["steps"], v["steps"], v["max"], (v["max"] - 1) * ipt, (v["max"] + 1) * ipt, v["max_at_k"], secs
      printf "%s sense() = reference z(t) and e: mean %.1f instructions/step; worst %d..%d\n",
        fl, sv["total"] * ipt / v["steps"], (sv["max"] - 1) * ipt, (sv["max"] + 1) * ipt
    }' "$log" | tee -a "$report"

  # Exact cross-check on a short run: count the traced instructions from
  # control_step's entry to its return address (one instruction per TB, so
  # one trace line per instruction).
  entry=$("$NM" "$elf" | awk '/control_step/ && !e { e = $1 } END { print e }')
  ret=$(awk '/[ \t]bl[ \t].*control_step/ && !r { r = $1; sub(":", "", r) } END { print r }' "$dis")
  [ -n "$entry" ] && [ -n "$ret" ] || { say "error: control_step or its call not found"; exit 1; }
  ret=$(printf '%x' $((0x$ret + 4)))
  entry=$(printf '%x' $((0x$entry)))
  if [ "$TRACE_STEPS" -gt 0 ]; then
    tmp=$(mktemp -d)
    mkfifo "$tmp/trace"
    awk -v entry="$entry" -v ret="$ret" -f "$here/cycles.awk" "$dis" "$tmp/trace" >"$tmp/exact" &
    apid=$!
    "${QEMU[@]}" "${ICOUNT[@]}" "${ONE_INSN[@]}" -d exec,nochain -D "$tmp/trace" \
      -kernel "$elf" -append "$TRACE_STEPS" >"$tmp/fw.out"
    wait "$apid"
    say "cross-check ($fl, first $TRACE_STEPS steps traced): instructions per control() call, exact (trace, bl included)"
    say "  vs SysTick ticks x $IPT (icount), and a Cortex-M4 cycle estimate (cycles.awk: TRM cycle counts, zero wait states):"
    paste -d' ' <(grep '^exact:' "$tmp/exact") <(grep '^step:' "$tmp/fw.out") | awk -v ipt="$IPT" '
      { split($8, t, "="); d = t[2] * ipt - $3; if (d < 0) d = -d
        if ($7 != "k=" $2) { print "  step order mismatch: " $0; bad = 1 }
        printf "  k=%d exact=%d systick_ticks=%d x%d=%d |diff|=%d cycles=%d..%d CPI=%.2f..%.2f\n",
          $2, $3, t[2], ipt, t[2] * ipt, d, $4, $5, $4 / $3, $5 / $3
        if (d > ipt + 8) bad = 1
        if ($2 > 0) { if (!lo || $4 / $3 < lo) lo = $4 / $3; if ($5 / $3 > hi) hi = $5 / $3 } }
      END { if (NR == 0) { print "  no step traced"; exit 1 }
            if (bad) { print "  MISMATCH beyond one tick (+ a few glue instructions)"; exit 1 }
            printf "  agree within one tick; CPI over steps k>=1: %.2f..%.2f\n", lo, hi }' | tee -a "$report"
    grep '^mix:' "$tmp/exact" | sed 's/^mix:/ /' | tee -a "$report"
    say "  call 1, instructions by function (callees excluded), top 12:"
    grep '^sym:' "$tmp/exact" | sort -k2,2nr | head -12 | "$CXXFILT" \
      | awk '{ n = $2; $1 = ""; $2 = ""; sub(/^ +/, ""); printf "  %7d  %s\n", n, $0 }' | tee -a "$report"
    rm -rf "$tmp"
  fi

  # The costliest of the first WORST_STEPS steps by the cycle model (f32
  # only: an f64 step is 150 000 instructions to trace).
  worst_steps="$WORST_STEPS"
  if [ "$worst_steps" = auto ]; then
    worst_k=$(sed -n 's/^timing: control().* max_at_k=\([0-9]*\).*/\1/p' "$log")
    worst_steps=$(( ${worst_k:-0} + 1 > 100 ? ${worst_k:-0} + 1 : 100 ))
  fi
  if [ "$fl" = f32 ] && [ "$worst_steps" -gt 0 ]; then
    say "tracing the first $worst_steps f32 steps for the one with the most cycles (about 1 s per 100 steps)"
    tmp=$(mktemp -d)
    mkfifo "$tmp/trace"
    awk -v entry="$entry" -v ret="$ret" -f "$here/cycles.awk" "$dis" "$tmp/trace" >"$tmp/exact" &
    apid=$!
    "${QEMU[@]}" "${ICOUNT[@]}" "${ONE_INSN[@]}" -d exec,nochain -D "$tmp/trace" \
      -kernel "$elf" -append "$worst_steps" >/dev/null
    wait "$apid"
    grep '^exact:' "$tmp/exact" | sort -k5,5n -k3,3n | tail -1 | awk -v n="$worst_steps" '
      { printf "worst of the first %d steps by the cycle model (traced): k=%d exact=%d cycles=%d..%d CPI=%.2f..%.2f\n",
          n, $2, $3, $4, $5, $4 / $3, $5 / $3 }' | tee -a "$report"
    rm -rf "$tmp"
  fi
done
say ""
say "report: $report"
