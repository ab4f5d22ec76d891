//! `f64` to text exactly as Rust's `{}` prints it, a few times faster.
//!
//! `trace.csv` holds tens of thousands of numbers per run, written with
//! `format!("{v}")` until now: the golden tests pin those bytes, so the
//! format cannot change. The standard library finds the shortest digits
//! that round-trip (Grisu with a Dragon4 fallback) and lays them out
//! without an exponent; that costs about a microsecond per number with the
//! `String` it allocates. Here the digits come from serde_json's float
//! printer (the same shortest round-trip digits, closest to the value, by
//! a faster algorithm, with an exponent) and are laid out again the way
//! `{}` does: `0.000123`, `12.5`, `1200`, `-0`. The two printers round an
//! exact tie differently; the values where one can occur (large ones and
//! short binary fractions, see `may_tie`) go to the standard library. A
//! test compares the two on millions of values spread over the whole range.

use std::io::Write;

/// Appends `v` (finite) to `out` exactly as `format!("{v}")` would print
/// it. `scratch` is a reusable buffer.
pub(crate) fn push_display(out: &mut Vec<u8>, v: f64, scratch: &mut Vec<u8>) {
    if !v.is_finite() || may_tie(v) {
        // Non-finite: not reached from the trace writer (it refuses
        // non-finite rows). A possible tie: rare in a trace.
        let _ = write!(out, "{v}");
        return;
    }
    let start = out.len();
    if serde_json::to_writer(&mut *out, &v).is_err() {
        out.truncate(start);
        let _ = write!(out, "{v}");
        return;
    }
    // Without an exponent (serde_json prints 1e-5 ≤ |v| < 1e16 in full,
    // so surely 1e-4 ≤ |v| < 1e15; and 0) the two agree but for the ".0"
    // serde_json puts after an integer ("1200.0", "-0.0").
    let a = v.abs();
    if a == 0.0 || (1e-4..1e15).contains(&a) || !out[start..].contains(&b'e') {
        if out.ends_with(b".0") {
            out.truncate(out.len() - 2);
        }
        return;
    }
    scratch.clear();
    scratch.extend_from_slice(&out[start..]);
    out.truncate(start);
    // scratch: [-]d[.ddd][e[±]x]; the value is 0.D × 10^point with D the
    // digits and point = (digits before '.') + x.
    let s = scratch.as_slice();
    let (neg, s) = match s.split_first() {
        Some((b'-', rest)) => (true, rest),
        _ => (false, s),
    };
    let (mant, exp) = match s.iter().position(|&c| c == b'e' || c == b'E') {
        Some(i) => (&s[..i], parse_exp(&s[i + 1..])),
        None => (s, 0),
    };
    let mut digits = [0u8; 40];
    let mut n = 0usize;
    let mut point = exp;
    let mut seen_dot = false;
    for &c in mant {
        if c == b'.' {
            seen_dot = true;
            continue;
        }
        if !seen_dot {
            point += 1;
        }
        if n == 0 && c == b'0' {
            // A leading zero moves the point, it is not a digit.
            point -= 1;
            continue;
        }
        if n < digits.len() {
            digits[n] = c;
            n += 1;
        }
    }
    while n > 0 && digits[n - 1] == b'0' {
        n -= 1;
    }
    if neg {
        out.push(b'-');
    }
    if n == 0 {
        out.push(b'0');
        return;
    }
    let d = &digits[..n];
    if point <= 0 {
        out.extend_from_slice(b"0.");
        out.extend(std::iter::repeat_n(b'0', point.unsigned_abs() as usize));
        out.extend_from_slice(d);
    } else {
        let p = point as usize;
        if p < n {
            out.extend_from_slice(&d[..p]);
            out.push(b'.');
            out.extend_from_slice(&d[p..]);
        } else {
            out.extend_from_slice(d);
            out.extend(std::iter::repeat_n(b'0', p - n));
        }
    }
}

/// Whether the two printers may disagree on `v`: they find the same
/// shortest length L, and the same digits unless two L-digit candidates are
/// equally close to v (serde_json's printer then rounds half to even, the
/// standard library half up: 1125899906842624.25 prints as …4.2 and …4.3)
/// or a candidate lies exactly on the edge of v's rounding interval. Both
/// need an exact decimal expansion of at most 18 significant digits: of v
/// itself (v = m·2^(−f) with m odd has one of f + (integer digits) ≥ 0.7f
/// significant digits) or of v ± ulp/2 (f_ulp + 1 fraction bits, f_ulp the
/// fraction bits of an ulp). So a value with more than 26 fraction bits in
/// both senses, or an integer below 2^26, is safe; the rest (|v| ≥ 2^26,
/// or a short binary fraction such as 0.5 or 100 + 2^(−15)) is printed by
/// the standard library. Trace values are almost all safe.
fn may_tie(v: f64) -> bool {
    let bits = v.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    if biased == 0 {
        // Zero ("0", "-0"), or subnormal: more than 1022 fraction bits.
        return false;
    }
    let mant = (bits & ((1u64 << 52) - 1)) | (1u64 << 52);
    // v = mant·2^(biased − 1075).
    let f_ulp = 1075 - biased;
    let f_red = f_ulp - mant.trailing_zeros() as i32;
    !(f_ulp > 26 && (f_red <= 0 || f_red > 26))
}

fn parse_exp(s: &[u8]) -> i32 {
    let (neg, s) = match s.split_first() {
        Some((b'-', rest)) => (true, rest),
        Some((b'+', rest)) => (false, rest),
        _ => (false, s),
    };
    let v = s
        .iter()
        .fold(0i32, |a, &c| a * 10 + i32::from(c.wrapping_sub(b'0')));
    if neg {
        -v
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(v: f64, out: &mut Vec<u8>, scratch: &mut Vec<u8>) {
        out.clear();
        push_display(out, v, scratch);
        let want = format!("{v}");
        assert_eq!(
            std::str::from_utf8(out).unwrap(),
            want,
            "bits {:#018x}",
            v.to_bits()
        );
    }

    /// Byte for byte what `{}` prints: special values (infinities and NaN
    /// included), ties, short binary fractions at every scale, every power
    /// of ten,
    /// the extremes, and two million random bit patterns plus a million
    /// values of the size a trace holds.
    #[test]
    fn same_bytes_as_display() {
        let (mut out, mut scratch) = (Vec::new(), Vec::new());
        for v in [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.1,
            0.5,
            1.5,
            100.0,
            1200.0,
            123.456,
            1e-7,
            1e15,
            1e16,
            1e17,
            1e21,
            1e22,
            1e23,
            f64::MAX,
            f64::MIN,
            f64::MIN_POSITIVE,
            5e-324,
            -5e-324,
            f64::EPSILON,
            0.3,
            2.0f64.powi(60),
            17911.75472253525,
            0.5991464108384542,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ] {
            check(v, &mut out, &mut scratch);
        }
        for e in -330..=310 {
            let v: f64 = format!("1e{e}").parse().unwrap();
            check(v, &mut out, &mut scratch);
            check(-v * 3.0, &mut out, &mut scratch);
            check(v * 0.7, &mut out, &mut scratch);
        }
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut n = 0;
        while n < 2_000_000 {
            let v = f64::from_bits(next());
            check(v, &mut out, &mut scratch);
            n += 1;
        }
        // Ties and interval edges: values with few significant bits at
        // every scale (the cases `may_tie` sends to the standard printer),
        // and the tie that showed the difference.
        check(
            f64::from_bits(0xc310_565a_94b4_e5f5),
            &mut out,
            &mut scratch,
        );
        check(100.0 + 2f64.powi(-15), &mut out, &mut scratch);
        check(2f64.powi(46) + 0.125, &mut out, &mut scratch);
        for _ in 0..2_000_000 {
            let bits = 1 + (next() % 53) as u32;
            let m = (next() >> (64 - bits)) | 1;
            let e = (next() % 200) as i32 - 100;
            let v = m as f64 * 2f64.powi(e - bits as i32);
            check(v, &mut out, &mut scratch);
            check(-v, &mut out, &mut scratch);
            let w = f64::from_bits(v.to_bits() + 1);
            check(w, &mut out, &mut scratch);
        }
        for _ in 0..1_000_000 {
            let u = (next() >> 11) as f64 / (1u64 << 53) as f64;
            let e = ((next() % 24) as i32) - 12;
            let v = (u * 2.0 - 1.0) * 10f64.powi(e);
            check(v, &mut out, &mut scratch);
        }
    }
}
