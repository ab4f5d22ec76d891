# Instruction counts and a Cortex-M4 cycle estimate per control() call,
# from a QEMU instruction trace (one instruction per translation block,
# `-d exec,nochain`) and the firmware's disassembly (objdump -d).
#
#   awk -v entry=37e8 -v ret=4186 [-v mixcall=1] -f cycles.awk firmware.dis trace.log
#
# entry: control_step's address; ret: the return address of its one call
# (hex, no 0x). For each call prints
#   exact: <call#> <instructions, the bl included> <cycles low> <cycles high>
# and, for call number `mixcall` (default 1: the second, a typical one),
# its instruction mix by cost class ("mix:" lines) and by function ("sym:"
# lines: instructions executed in each function, callees excluded).
#
# Cycle model (Cortex-M4 TRM r0p1, Table 3-1 and the FPU chapter's table;
# zero wait states, i.e. no flash wait states or bus contention):
#   most ALU, MUL/MLA/MLS, UMULL/SMULL/UMLAL/SMLAL (single-cycle MAC)  1
#   taken branch (B, BL, BX, CBZ/CBNZ, TBB/TBH, writes to PC)          1+P, P = 1..3
#   LDR*/STR* single                                                  low 1 (pipelined with a neighbour), high 2
#   LDRD/STRD                                                         low 2, high 3
#   LDM/STM/PUSH/POP                                                  1+N (+P when POP loads PC)
#   SDIV/UDIV                                                         2..12
#   VADD/VSUB/VMUL/VNMUL/VABS/VNEG/VCMP/VCVT/VMRS.F32                 1
#   VMLA/VMLS/VNMLA/VNMLS/VFMA/VFMS/VFNMA/VFNMS.F32                   3
#   VDIV.F32, VSQRT.F32                                               14
#   VLDR/VSTR                                                         low 1, high 2
#   VLDM/VSTM/VPUSH/VPOP                                              1+N (N in words)
#   VMOV to/from two core registers                                   2; one core register: low 1, high 2
# A not-taken conditional branch is 1; a taken one is detected from the
# trace (the next PC is not the fall-through).

function norm(a) { a = tolower(a); sub(/^0x/, "", a); sub(/^0+/, "", a); return a == "" ? "0" : a }

function nregs(ops,   body, n, items, i, m, r, lo, hi, w) {
    # {r4, r5, lr} -> 3; {d8-d15} -> 8 doubles = 16 words
    if (!match(ops, /\{[^}]*\}/)) return 1
    body = substr(ops, RSTART + 1, RLENGTH - 2)
    n = split(body, items, ",")
    r = 0
    for (i = 1; i <= n; i++) {
        gsub(/ /, "", items[i])
        w = (items[i] ~ /^d/) ? 2 : 1
        if (split(items[i], m, "-") == 2) {
            lo = m[1]; hi = m[2]; gsub(/[^0-9]/, "", lo); gsub(/[^0-9]/, "", hi)
            r += (hi - lo + 1) * w
        } else r += w
    }
    return r
}

# Cost class and [low, high] cycles of one instruction, branch refill excluded.
function classify(mn, ops,   base, k) {
    base = mn; sub(/\.(w|n)$/, "", base)
    if (base ~ /^v/) {
        sub(/\.(f32|f64|32|64|s32|u32|f32\.s32|s32\.f32)$/, "", base)
        if (base ~ /^v(mla|mls|nmla|nmls|fma|fms|fnma|fnms)/) { cls = "fpu mac (3)"; lo = 3; hi = 3; return }
        if (base ~ /^v(div|sqrt)/) { cls = "vdiv/vsqrt (14)"; lo = 14; hi = 14; return }
        if (base ~ /^v(ldm|stm|push|pop)/) { k = nregs(ops); cls = "vldm/vstm/vpush/vpop (1+N)"; lo = 1 + k; hi = 1 + k; return }
        if (base ~ /^v(ldr|str)/) { cls = "vldr/vstr (1-2)"; lo = 1; hi = 2; return }
        if (base ~ /^vmov/) {
            if (ops ~ /(^|[ ,])(r[0-9]+|sl|fp|ip|lr|sb)[ ,].*(r[0-9]+|sl|fp|ip|lr|sb)([ ,]|$)/) { cls = "vmov 2 core regs (2)"; lo = 2; hi = 2; return }
            if (ops ~ /(^|[ ,])(r[0-9]+|sl|fp|ip|lr|sb)([ ,]|$)/) { cls = "vmov core<->fpu (1-2)"; lo = 1; hi = 2; return }
        }
        cls = "fpu 1-cycle"; lo = 1; hi = 1; return
    }
    if (base ~ /^(pop|ldm)/) { k = nregs(ops); cls = "ldm/pop (1+N)"; lo = 1 + k; hi = 1 + k; return }
    if (base ~ /^(push|stm)/) { k = nregs(ops); cls = "stm/push (1+N)"; lo = 1 + k; hi = 1 + k; return }
    if (base ~ /^(ldrd|strd)/) { cls = "ldrd/strd (2-3)"; lo = 2; hi = 3; return }
    if (base ~ /^(ldr|str)/) { cls = "ldr/str (1-2)"; lo = 1; hi = 2; return }
    if (base ~ /^(sdiv|udiv)/) { cls = "sdiv/udiv (2-12)"; lo = 2; hi = 12; return }
    if (base ~ /^(b|bl|blx|bx|cbz|cbnz|tbb|tbh)(eq|ne|cs|hs|cc|lo|mi|pl|vs|vc|hi|ls|ge|lt|gt|le|al)?$/) { cls = "branch"; lo = 1; hi = 1; return }
    cls = "alu/mul 1-cycle"; lo = 1; hi = 1
}

BEGIN { FS = "\t"; entry = norm(entry); ret = norm(ret); if (mixcall == "") mixcall = 1 }

# Pass 1: the disassembly, GNU objdump's or llvm-objdump's:
#   GNU   "    d50:\tb5f0      \tpush\t{r4, r5, r6, r7, lr}"
#   LLVM  "     d50: f0 b5        \tpush\t{r4, r5, r6, r7, lr}"
FNR == NR {
    if ($1 ~ /^ *[0-9a-f]+:$/ && NF >= 3) {
        a = $1; raw = $2; m = $3; o = (NF >= 4) ? $4 : ""
    } else if ($1 ~ /^ *[0-9a-f]+:( [0-9a-f][0-9a-f])+ *$/ && NF >= 2) {
        a = $1; sub(/:.*/, "", a); raw = $1; sub(/^[^:]*:/, "", raw)
        m = $2; o = (NF >= 3) ? $3 : ""
    } else next
    gsub(/[ :]/, "", a); a = norm(a)
    gsub(/ /, "", raw)
    size[a] = length(raw) / 2
    mnem[a] = m; opnd[a] = o
    next
}

# Pass 2: the trace, "Trace 0: 0x... [flags/PC/...] symbol". Under -icount
# a TB can be logged and then not run ("Stopped execution of TB chain
# before ..." follows when its instruction budget ran out): it runs, and is
# logged, again later, so a Trace line followed by a Stopped line is dropped.
/^Stopped execution of TB chain before/ { pend = ""; stopped++; next }
/^Trace / { if (pend != "") trace(pend); pend = $0; next }
END { if (pend != "") trace(pend) }

function trace(line,   s, f, pc) {
    if (!match(line, /\[[0-9a-fA-F]+\/[0-9a-fA-F]+\//)) return
    s = substr(line, RSTART + 1, RLENGTH - 2); split(s, f, "/"); pc = norm(f[2])
    if (pc == entry && !on) {
        # The bl that got here: 1 instruction, a taken branch.
        on = 1; n = 1; clo = 2; chi = 4; first = (calls == mixcall)
        if (first) { mix["branch"]++; mixlo["branch"]++; mixhi["branch"]++; refills = 1 }
        nextpc = pc
    }
    if (!on) return
    # A pipeline refill when the previous instruction went anywhere but
    # its fall-through.
    if (pc != nextpc) { clo += 1; chi += 3; if (first) refills++ }
    if (pc == ret) {
        printf "exact: %d %d %d %d\n", calls, n, clo, chi
        if (first) {
            printf "mix: call %d, by cost class:\n", calls
            for (c in mix) printf "mix: %-28s %7d instructions %8d..%d cycles\n", c, mix[c], mixlo[c], mixhi[c]
            printf "mix: %-28s %7d refills      %8d..%d cycles\n", "taken branches (P = 1..3)", refills, refills, 3 * refills
            for (c in syms) printf "sym: %d %s\n", syms[c], c
        }
        calls++; on = 0
        return
    }
    if (!(pc in mnem)) { unknown++; lo = 1; hi = 1; cls = "unknown" } else classify(mnem[pc], opnd[pc])
    n++; clo += lo; chi += hi
    if (first) {
        mix[cls]++; mixlo[cls] += lo; mixhi[cls] += hi
        sym = line; sub(/^[^]]*\] */, "", sym); sym = sym == "" ? "?" : sym
        syms[sym]++
    }
    nextpc = sprintf("%x", hex(pc) + size[pc])
}

function hex(h,   i, c, v) { v = 0; h = tolower(h); for (i = 1; i <= length(h); i++) { c = index("0123456789abcdef", substr(h, i, 1)) - 1; v = v * 16 + c }; return v }

# A traced instruction of a call that the disassembly does not have would
# be costed as one cycle: the cycle figures would be wrong, so fail.
END {
    if (unknown) {
        printf "error: %d traced instructions of control() are not in the disassembly (an objdump whose format this script does not read?)\n", unknown > "/dev/stderr"
        exit 1
    }
}
