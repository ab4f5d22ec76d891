#!/bin/sh
# Where a program's time goes, instruction by instruction: a cpu-clock
# profile (this VM has no hardware counters, but the kernel's clock
# sampling works) mapped back to the addresses and source lines of one
# function. A stall shows as samples piling up on the instruction that
# waits, e.g. the first user of a 16-byte load that straddles two 8-byte
# stores (x86 cannot forward those; BENCHMARKS.md, "Stores forwarded").
#
# usage: bench/hot-spots.sh PATTERN BIN [ARGS...]
#   PATTERN  part of the (mangled) symbol name, e.g. ControllerCfg5visit,
#            rk4_step_with_k1, b_and_d; every matching function is shown
#   BIN      the program, e.g. target/release/deps/sweep_run-HASH
#   ARGS     its arguments (default: 6000 1, which is sweep_run's 6 000
#            Fig. 2 runs on one thread; give your own for another program)
# Prints each function's share of all samples, its source lines by share
# and its hottest instructions. Needs perf, objdump (binutils) and python3.
set -eu
if [ $# -lt 2 ]; then
    echo "usage: bench/hot-spots.sh PATTERN BIN [ARGS...]" >&2
    exit 2
fi
pattern=$1
bin=$(readlink -f "$2")
shift 2
if [ $# -eq 0 ]; then set -- 6000 1; fi
for t in perf objdump nm readelf python3; do
    command -v "$t" >/dev/null || { echo "hot-spots: $t is not installed" >&2; exit 2; }
done
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT INT TERM
if ! perf record -q -e cpu-clock -F 25000 -o "$tmp/perf.data" "$bin" "$@" \
    >/dev/null 2>"$tmp/perf.err"; then
    echo "hot-spots: perf record $bin $* failed:" >&2
    cat "$tmp/perf.err" >&2
    exit 1
fi
perf script -i "$tmp/perf.data" -F ip 2>/dev/null | sort | uniq -c > "$tmp/ips"
# The load address: the executable mapping's start, less its file offset
# and the segment's virtual-address-to-offset difference.
map=$(perf script -i "$tmp/perf.data" --show-mmap-events 2>/dev/null |
    grep 'PERF_RECORD_MMAP' | grep "r-xp $bin\$" | head -n 1)
if [ -z "$map" ]; then
    echo "hot-spots: no executable mapping of $bin in the profile" >&2
    exit 1
fi
start=$(echo "$map" | sed 's/.*\[\(0x[0-9a-f]*\)(.*/\1/')
pgoff=$(echo "$map" | sed 's/.*@ \([0-9a-fx]*\) .*/\1/')
seg=$(readelf -lW "$bin" | awk '$1 == "LOAD" && $0 ~ / R E / { print $3, $2; exit }')
vaddr=${seg% *}
off=${seg#* }
base=$((start - pgoff - (vaddr - off)))
nm -S "$bin" | awk -v p="$pattern" '($3 == "t" || $3 == "T") && index($4, p) { print $1, $2, $4 }' |
while read -r addr size name; do
    objdump -d -l --no-show-raw-insn -M intel \
        --start-address=0x"$addr" --stop-address=$((0x$addr + 0x$size)) "$bin" > "$tmp/fn.dis"
    python3 - "$tmp/ips" "$tmp/fn.dis" "$base" "$name" <<'EOF'
import collections, re, sys
ips, dis, base, name = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
count = {}
for line in open(ips):
    n, ip = line.split()
    count[int(ip, 16) - base] = int(n)
total = sum(count.values()) or 1
line_of, by_line, hot = '?', collections.Counter(), []
for l in open(dis):
    m = re.match(r'^(/\S+):(\d+)', l)
    if m:
        line_of = '/'.join(m.group(1).split('/')[-2:]) + ':' + m.group(2)
        continue
    m = re.match(r'^\s+([0-9a-f]+):\s+(.*)', l)
    if m:
        c = count.get(int(m.group(1), 16), 0)
        by_line[line_of] += c
        if c:
            hot.append((c, m.group(1), line_of, m.group(2)[:70]))
share = sum(by_line.values()) / total * 100
if share < 0.1:
    sys.exit(0)
print('== %s: %.2f%% of %d samples' % (name, share, total))
for k, v in [kv for kv in by_line.most_common(12) if kv[1]]:
    print('  %5.2f%%  %s' % (v / total * 100, k))
print('  hottest instructions:')
for c, a, k, ins in sorted(hot, reverse=True)[:12]:
    print('  %5.2f%%  %s  %-22s %s' % (c / total * 100, a, k, ins))
EOF
done
