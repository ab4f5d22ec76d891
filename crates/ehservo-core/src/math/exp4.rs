//! Four `exp`s at once, with the bits of the platform's own `exp` on an
//! x86-64 Linux host (glibc ≥ 2.28) with FMA and AVX2.
//!
//! glibc's `exp` is Szabolcs Nagy's algorithm from Arm's
//! optimized-routines (`math/exp.c`, `math/exp_data.c`; MIT OR Apache-2.0
//! WITH LLVM-exception): x = k·ln2/128 + r, exp(x) = 2^(k/128)·exp(r), with a
//! 128-entry table of 2^(i/128) and a degree-5 polynomial in r. On a CPU with
//! FMA and AVX2, glibc runs the copy of it compiled with `-mfma -mavx2`
//! (its ifunc picks `__exp_fma`), in which GCC fused eight products into
//! their sums. [`exp4`] is that code, the same constants, table and fused
//! operations (read from the disassembly of Debian 12's libm), in four
//! AVX2 lanes, without the call, the PLT and the `errno` wrapper around
//! each of four scalar calls. The NNBVSC law's four exponentials
//! (`Rbf::gaussians`) take it: 218 fewer instructions a law (1 472 → 1 254).
//!
//! It answers only where those bits are the platform's:
//! - arguments with 2^−54 ≤ |x| < 512 in every lane (glibc's own fast
//!   path; anything else, 0, tiny, huge, ±∞ or NaN, is left to the scalar
//!   `exp`);
//! - a CPU with FMA and AVX2 (where glibc takes `__exp_fma`), glibc ≥ 2.28
//!   (older ones have another `exp` altogether, IBM's), and
//! - a self-test passed on first use: the platform's `exp` gives this
//!   code's bits on [`PROBES`], arguments on which glibc's FMA and
//!   non-FMA copies differ. This catches what the CPU flags and the
//!   version cannot: `GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA` (glibc
//!   then runs its SSE2 copy on the same CPU), an `exp` interposed by
//!   another library, a glibc compiled with other fusions.
//!
//! Elsewhere it returns `None` and the caller computes four scalar
//! `exp`s: the same bits either way. With `std` on such a host,
//! `exp4_is_the_platform_exp_to_the_bit` holds it to the platform's `exp`
//! over 2·10⁵ arguments (`.ci/run` sets `EHSERVO_REQUIRE_EXP4=1` on a CPU
//! with AVX2 and FMA, so that the tests fail rather than skip there).
//!
//! Which fusions matter, measured with a scalar copy: over 10⁶ arguments,
//! leaving the last product (`scale + scale·tmp`) unfused changes 666
//! results by an ulp; `r²·(C2 + r·C3)` changes 4 in 2·10⁷; the other six
//! none in 2·10⁷. So glibc's SSE2 copy (nothing fused) differs from its
//! FMA copy in about one result in 1 500, and the probes include
//! arguments of both kinds.
#![allow(unsafe_code)]

use std::sync::atomic::{AtomicU8, Ordering};

use core::arch::x86_64::{
    __m256i, _mm256_add_epi64, _mm256_add_pd, _mm256_and_si256, _mm256_castpd_si256,
    _mm256_castsi256_pd, _mm256_cmpgt_epi64, _mm256_fmadd_pd, _mm256_loadu_pd, _mm256_mul_pd,
    _mm256_or_si256, _mm256_set1_epi64x, _mm256_set1_pd, _mm256_set_epi64x, _mm256_set_pd,
    _mm256_setzero_si256, _mm256_slli_epi64, _mm256_srli_epi64, _mm256_storeu_pd,
    _mm256_storeu_si256, _mm256_sub_epi64, _mm256_sub_pd, _mm256_testz_si256,
};

/// `N/ln 2`, N = 128 (0x1.71547652b82fep7).
const INV_LN2_N: u64 = 0x4067_1547_652b_82fe;
/// `−ln 2/N`, its high part (−0x1.62e42fefa0000p−8).
const NEG_LN2_HI_N: u64 = 0xbf76_2e42_fefa_0000;
/// `−ln 2/N`, its low part (−0x1.cf79abc9e3b3ap−47).
const NEG_LN2_LO_N: u64 = 0xbd0c_f79a_bc9e_3b3a;
/// 1.5·2⁵²: adding it rounds k·N/ln 2 to an integer in the low bits.
const SHIFT: u64 = 0x4338_0000_0000_0000;
/// The polynomial's C2..C5 (0x1.ffffffffffdbdp−2, 0x1.555555555543cp−3,
/// 0x1.55555cf172b91p−5, 0x1.1111167a4d017p−7).
const C: [u64; 4] = [
    0x3fdf_ffff_ffff_fdbd,
    0x3fc5_5555_5555_543c,
    0x3fa5_5555_cf17_2b91,
    0x3f81_1111_67a4_d017,
];

/// `exp_data.c`'s `tab` for N = 128: for i = 0..128, the pair
/// (tail_i, bits(2^(i/128)) − (i << 45)), 2^(i/128) ≈ scale·(1 + tail).
#[rustfmt::skip]
static TAB: [u64; 256] = [
    0x0000000000000000, 0x3ff0000000000000, 0x3c9b3b4f1a88bf6e, 0x3feff63da9fb3335,
    0xbc7160139cd8dc5d, 0x3fefec9a3e778061, 0xbc905e7a108766d1, 0x3fefe315e86e7f85,
    0x3c8cd2523567f613, 0x3fefd9b0d3158574, 0xbc8bce8023f98efa, 0x3fefd06b29ddf6de,
    0x3c60f74e61e6c861, 0x3fefc74518759bc8, 0x3c90a3e45b33d399, 0x3fefbe3ecac6f383,
    0x3c979aa65d837b6d, 0x3fefb5586cf9890f, 0x3c8eb51a92fdeffc, 0x3fefac922b7247f7,
    0x3c3ebe3d702f9cd1, 0x3fefa3ec32d3d1a2, 0xbc6a033489906e0b, 0x3fef9b66affed31b,
    0xbc9556522a2fbd0e, 0x3fef9301d0125b51, 0xbc5080ef8c4eea55, 0x3fef8abdc06c31cc,
    0xbc91c923b9d5f416, 0x3fef829aaea92de0, 0x3c80d3e3e95c55af, 0x3fef7a98c8a58e51,
    0xbc801b15eaa59348, 0x3fef72b83c7d517b, 0xbc8f1ff055de323d, 0x3fef6af9388c8dea,
    0x3c8b898c3f1353bf, 0x3fef635beb6fcb75, 0xbc96d99c7611eb26, 0x3fef5be084045cd4,
    0x3c9aecf73e3a2f60, 0x3fef54873168b9aa, 0xbc8fe782cb86389d, 0x3fef4d5022fcd91d,
    0x3c8a6f4144a6c38d, 0x3fef463b88628cd6, 0x3c807a05b0e4047d, 0x3fef3f49917ddc96,
    0x3c968efde3a8a894, 0x3fef387a6e756238, 0x3c875e18f274487d, 0x3fef31ce4fb2a63f,
    0x3c80472b981fe7f2, 0x3fef2b4565e27cdd, 0xbc96b87b3f71085e, 0x3fef24dfe1f56381,
    0x3c82f7e16d09ab31, 0x3fef1e9df51fdee1, 0xbc3d219b1a6fbffa, 0x3fef187fd0dad990,
    0x3c8b3782720c0ab4, 0x3fef1285a6e4030b, 0x3c6e149289cecb8f, 0x3fef0cafa93e2f56,
    0x3c834d754db0abb6, 0x3fef06fe0a31b715, 0x3c864201e2ac744c, 0x3fef0170fc4cd831,
    0x3c8fdd395dd3f84a, 0x3feefc08b26416ff, 0xbc86a3803b8e5b04, 0x3feef6c55f929ff1,
    0xbc924aedcc4b5068, 0x3feef1a7373aa9cb, 0xbc9907f81b512d8e, 0x3feeecae6d05d866,
    0xbc71d1e83e9436d2, 0x3feee7db34e59ff7, 0xbc991919b3ce1b15, 0x3feee32dc313a8e5,
    0x3c859f48a72a4c6d, 0x3feedea64c123422, 0xbc9312607a28698a, 0x3feeda4504ac801c,
    0xbc58a78f4817895b, 0x3feed60a21f72e2a, 0xbc7c2c9b67499a1b, 0x3feed1f5d950a897,
    0x3c4363ed60c2ac11, 0x3feece086061892d, 0x3c9666093b0664ef, 0x3feeca41ed1d0057,
    0x3c6ecce1daa10379, 0x3feec6a2b5c13cd0, 0x3c93ff8e3f0f1230, 0x3feec32af0d7d3de,
    0x3c7690cebb7aafb0, 0x3feebfdad5362a27, 0x3c931dbdeb54e077, 0x3feebcb299fddd0d,
    0xbc8f94340071a38e, 0x3feeb9b2769d2ca7, 0xbc87deccdc93a349, 0x3feeb6daa2cf6642,
    0xbc78dec6bd0f385f, 0x3feeb42b569d4f82, 0xbc861246ec7b5cf6, 0x3feeb1a4ca5d920f,
    0x3c93350518fdd78e, 0x3feeaf4736b527da, 0x3c7b98b72f8a9b05, 0x3feead12d497c7fd,
    0x3c9063e1e21c5409, 0x3feeab07dd485429, 0x3c34c7855019c6ea, 0x3feea9268a5946b7,
    0x3c9432e62b64c035, 0x3feea76f15ad2148, 0xbc8ce44a6199769f, 0x3feea5e1b976dc09,
    0xbc8c33c53bef4da8, 0x3feea47eb03a5585, 0xbc845378892be9ae, 0x3feea34634ccc320,
    0xbc93cedd78565858, 0x3feea23882552225, 0x3c5710aa807e1964, 0x3feea155d44ca973,
    0xbc93b3efbf5e2228, 0x3feea09e667f3bcd, 0xbc6a12ad8734b982, 0x3feea012750bdabf,
    0xbc6367efb86da9ee, 0x3fee9fb23c651a2f, 0xbc80dc3d54e08851, 0x3fee9f7df9519484,
    0xbc781f647e5a3ecf, 0x3fee9f75e8ec5f74, 0xbc86ee4ac08b7db0, 0x3fee9f9a48a58174,
    0xbc8619321e55e68a, 0x3fee9feb564267c9, 0x3c909ccb5e09d4d3, 0x3feea0694fde5d3f,
    0xbc7b32dcb94da51d, 0x3feea11473eb0187, 0x3c94ecfd5467c06b, 0x3feea1ed0130c132,
    0x3c65ebe1abd66c55, 0x3feea2f336cf4e62, 0xbc88a1c52fb3cf42, 0x3feea427543e1a12,
    0xbc9369b6f13b3734, 0x3feea589994cce13, 0xbc805e843a19ff1e, 0x3feea71a4623c7ad,
    0xbc94d450d872576e, 0x3feea8d99b4492ed, 0x3c90ad675b0e8a00, 0x3feeaac7d98a6699,
    0x3c8db72fc1f0eab4, 0x3feeace5422aa0db, 0xbc65b6609cc5e7ff, 0x3feeaf3216b5448c,
    0x3c7bf68359f35f44, 0x3feeb1ae99157736, 0xbc93091fa71e3d83, 0x3feeb45b0b91ffc6,
    0xbc5da9b88b6c1e29, 0x3feeb737b0cdc5e5, 0xbc6c23f97c90b959, 0x3feeba44cbc8520f,
    0xbc92434322f4f9aa, 0x3feebd829fde4e50, 0xbc85ca6cd7668e4b, 0x3feec0f170ca07ba,
    0x3c71affc2b91ce27, 0x3feec49182a3f090, 0x3c6dd235e10a73bb, 0x3feec86319e32323,
    0xbc87c50422622263, 0x3feecc667b5de565, 0x3c8b1c86e3e231d5, 0x3feed09bec4a2d33,
    0xbc91bbd1d3bcbb15, 0x3feed503b23e255d, 0x3c90cc319cee31d2, 0x3feed99e1330b358,
    0x3c8469846e735ab3, 0x3feede6b5579fdbf, 0xbc82dfcd978e9db4, 0x3feee36bbfd3f37a,
    0x3c8c1a7792cb3387, 0x3feee89f995ad3ad, 0xbc907b8f4ad1d9fa, 0x3feeee07298db666,
    0xbc55c3d956dcaeba, 0x3feef3a2b84f15fb, 0xbc90a40e3da6f640, 0x3feef9728de5593a,
    0xbc68d6f438ad9334, 0x3feeff76f2fb5e47, 0xbc91eee26b588a35, 0x3fef05b030a1064a,
    0x3c74ffd70a5fddcd, 0x3fef0c1e904bc1d2, 0xbc91bdfbfa9298ac, 0x3fef12c25bd71e09,
    0x3c736eae30af0cb3, 0x3fef199bdd85529c, 0x3c8ee3325c9ffd94, 0x3fef20ab5fffd07a,
    0x3c84e08fd10959ac, 0x3fef27f12e57d14b, 0x3c63cdaf384e1a67, 0x3fef2f6d9406e7b5,
    0x3c676b2c6c921968, 0x3fef3720dcef9069, 0xbc808a1883ccb5d2, 0x3fef3f0b555dc3fa,
    0xbc8fad5d3ffffa6f, 0x3fef472d4a07897c, 0xbc900dae3875a949, 0x3fef4f87080d89f2,
    0x3c74a385a63d07a7, 0x3fef5818dcfba487, 0xbc82919e2040220f, 0x3fef60e316c98398,
    0x3c8e5a50d5c192ac, 0x3fef69e603db3285, 0x3c843a59ac016b4b, 0x3fef7321f301b460,
    0xbc82d52107b43e1f, 0x3fef7c97337b9b5f, 0xbc892ab93b470dc9, 0x3fef864614f5a129,
    0x3c74b604603a88d3, 0x3fef902ee78b3ff6, 0x3c83c5ec519d7271, 0x3fef9a51fbc74c83,
    0xbc8ff7128fd391f0, 0x3fefa4afa2a490da, 0xbc8dae98e223747d, 0x3fefaf482d8e67f1,
    0x3c8ec3bc41aa2008, 0x3fefba1bee615a27, 0x3c842b94c3a9eb32, 0x3fefc52b376bba97,
    0x3c8a64a931d185ee, 0x3fefd0765b6e4540, 0xbc8e37bae43be3ed, 0x3fefdbfdad9cbe14,
    0x3c77893b4d91cd9d, 0x3fefe7c1819e90d8, 0x3c5305c14160cc89, 0x3feff3c22b8f71f1,
];

/// `[exp v0, exp v1, exp v2, exp v3]` with the bits of glibc's `exp`, or
/// `None` where this code does not answer (see the module's docs).
#[inline]
pub(crate) fn exp4(v: [f64; 4]) -> Option<[f64; 4]> {
    if usable() {
        // SAFETY: the CPU supports AVX2 and FMA (`usable` detected them).
        unsafe { exp4_fma(v) }
    } else {
        None
    }
}

/// Whether the CPU has AVX2 and FMA and the C library is glibc ≥ 2.28:
/// found once, then one load (0 not yet known, 1 yes, 2 no).
static USABLE: AtomicU8 = AtomicU8::new(0);

#[inline(always)]
fn usable() -> bool {
    match USABLE.load(Ordering::Relaxed) {
        1 => true,
        2 => false,
        _ => {
            let u = detect();
            USABLE.store(if u { 1 } else { 2 }, Ordering::Relaxed);
            u
        }
    }
}

/// Arguments on which glibc's FMA copy of `exp` and its AVX/SSE2 copies
/// differ (the first four: the last product fused or not) or on which
/// leaving `r²·(C2 + r·C3)` unfused shows (the last four).
const PROBES: [[f64; 4]; 2] = [
    [
        1.437_901_316_286_260_8,
        -1.003_879_618_602_461_2,
        -0.399_847_581_603_305_36,
        -6.843_189_268_120_682,
    ],
    [
        5.181_155_512_099_799,
        -108.425_077_571_400_08,
        11.617_584_122_461_107,
        -28.160_114_852_352_61,
    ],
];

#[cold]
fn detect() -> bool {
    extern "C" {
        fn gnu_get_libc_version() -> *const core::ffi::c_char;
    }
    if !(std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma")) {
        return false;
    }
    // SAFETY: glibc returns a pointer to its static, NUL-terminated
    // version string ("2.36").
    let version = unsafe { core::ffi::CStr::from_ptr(gnu_get_libc_version()) };
    if !version.to_str().is_ok_and(|v| at_least(v, (2, 28))) {
        return false;
    }
    PROBES.iter().all(|&p| {
        // SAFETY: the CPU supports AVX2 and FMA (detected above).
        let e = unsafe { exp4_fma(p) };
        e.is_some_and(|e| {
            e.iter()
                .zip(p)
                .all(|(e, x)| e.to_bits() == x.exp().to_bits())
        })
    })
}

/// Whether the version `v` ("major.minor[.patch]") is at least `min`.
fn at_least(v: &str, min: (u32, u32)) -> bool {
    let mut parts = v.split('.').map(|p| p.parse::<u32>().ok());
    match (parts.next().flatten(), parts.next().flatten()) {
        (Some(major), Some(minor)) => (major, minor) >= min,
        _ => false,
    }
}

/// [`exp4`]'s four lanes: glibc's `__exp_fma` fast path, operation by
/// operation.
///
/// # Safety
/// The CPU must support AVX2 and FMA.
#[inline]
#[target_feature(enable = "avx2,fma")]
unsafe fn exp4_fma(v: [f64; 4]) -> Option<[f64; 4]> {
    let one = |b: u64| _mm256_set1_pd(f64::from_bits(b));
    let int = |i: i64| _mm256_set1_epi64x(i);
    let x = _mm256_loadu_pd(v.as_ptr());
    // abstop − 0x3c9 ≤ 0x3e in every lane: 2^−54 ≤ |x| < 512 (glibc's
    // `abstop - top12(0x1p-54) >= top12(512.0) - top12(0x1p-54)` test).
    let top = _mm256_and_si256(_mm256_srli_epi64::<52>(_mm256_castpd_si256(x)), int(0x7ff));
    let d = _mm256_sub_epi64(top, int(0x3c9));
    let out_of_range: __m256i = _mm256_or_si256(
        _mm256_cmpgt_epi64(d, int(0x3e)),
        _mm256_cmpgt_epi64(_mm256_setzero_si256(), d),
    );
    if _mm256_testz_si256(out_of_range, out_of_range) == 0 {
        return None;
    }
    // kd = x·N/ln2 + shift (fused), ki its bits, kd − shift = k.
    let kd = _mm256_fmadd_pd(x, one(INV_LN2_N), one(SHIFT));
    let ki = _mm256_castpd_si256(kd);
    let kd = _mm256_sub_pd(kd, one(SHIFT));
    // r = x + k·(−ln2/N)_hi + k·(−ln2/N)_lo, each product fused.
    let r = _mm256_fmadd_pd(kd, one(NEG_LN2_HI_N), x);
    let r = _mm256_fmadd_pd(kd, one(NEG_LN2_LO_N), r);
    // idx = 2·(k mod N); sbits = tab[idx + 1] + (k << 45).
    // (Eight scalar loads, not AVX2's gathers: on Intel CPUs with the
    // Gather Data Sampling microcode mitigation a gather costs tens of
    // cycles.)
    let mut k = [0u64; 4];
    _mm256_storeu_si256(k.as_mut_ptr().cast::<__m256i>(), ki);
    let i = k.map(|k| 2 * (k & 0x7f) as usize);
    let tail = _mm256_set_pd(
        f64::from_bits(TAB[i[3]]),
        f64::from_bits(TAB[i[2]]),
        f64::from_bits(TAB[i[1]]),
        f64::from_bits(TAB[i[0]]),
    );
    let hi = _mm256_set_epi64x(
        TAB[i[3] + 1] as i64,
        TAB[i[2] + 1] as i64,
        TAB[i[1] + 1] as i64,
        TAB[i[0] + 1] as i64,
    );
    let sbits = _mm256_add_epi64(hi, _mm256_slli_epi64::<45>(ki));
    // tmp = tail + r + r²(C2 + r·C3) + r⁴(C4 + r·C5), as __exp_fma
    // evaluates it: ((r·C3 + C2)·r² + (r + tail)) then r⁴·(r·C5 + C4) + that.
    let p1 = _mm256_fmadd_pd(r, one(C[1]), one(C[0]));
    let t0 = _mm256_add_pd(r, tail);
    let r2 = _mm256_mul_pd(r, r);
    let p2 = _mm256_fmadd_pd(r, one(C[3]), one(C[2]));
    let tmp = _mm256_fmadd_pd(p1, r2, t0);
    let r4 = _mm256_mul_pd(r2, r2);
    let tmp = _mm256_fmadd_pd(r4, p2, tmp);
    // scale + scale·tmp, fused.
    let scale = _mm256_castsi256_pd(sbits);
    let e = _mm256_fmadd_pd(scale, tmp, scale);
    let mut out = [0.0; 4];
    _mm256_storeu_pd(out.as_mut_ptr(), e);
    Some(out)
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point
mod tests {
    use super::*;

    /// Whether `exp4` runs here. If not, the test says so, and fails when
    /// `EHSERVO_REQUIRE_EXP4` is set (`.ci/run` sets it on a CPU with
    /// AVX2 and FMA), so that a skip cannot pass for a check.
    fn runs_here() -> bool {
        if usable() {
            return true;
        }
        assert!(
            std::env::var_os("EHSERVO_REQUIRE_EXP4").is_none(),
            "EHSERVO_REQUIRE_EXP4 is set but exp4 does not run here \
             (CPU features, glibc version or its self-test)"
        );
        eprintln!("exp4 does not run here (no AVX2/FMA, glibc < 2.28 or another exp): skipped");
        false
    }

    /// A printed hex float ("0x1.71547652b82fep7", "-0x1.62e42fefa0000p-8")
    /// to its bits: the sign, 52 bits of mantissa after "1.", the exponent.
    fn hex_float(t: &str) -> u64 {
        let (sign, t) = t.strip_prefix('-').map_or((0, t), |t| (1u64 << 63, t));
        let t = t.strip_prefix("0x1.").expect("normal hex float");
        let (frac, exp) = t.split_once('p').expect("exponent");
        let frac = format!("{frac:0<13}");
        let mantissa = u64::from_str_radix(&frac, 16).expect("hex digits");
        let exp: i64 = exp.parse().expect("exponent digits");
        sign | (((exp + 1023) as u64) << 52) | mantissa
    }

    /// The constants are exp_data.c's as printed there (N = 128,
    /// EXP_POLY_ORDER = 5, !EXP_POLY_WIDE), bit for bit; the table's
    /// scales are 2^(i/128) to an ulp, its tails below half an ulp, and the
    /// whole table has the FNV-1a checksum of exp_data.c's N = 128 `tab`
    /// (computed from that file, not from this one).
    #[test]
    fn constants_are_exp_datas() {
        assert_eq!(INV_LN2_N, hex_float("0x1.71547652b82fep7"));
        assert_eq!(NEG_LN2_HI_N, hex_float("-0x1.62e42fefa0000p-8"));
        assert_eq!(NEG_LN2_LO_N, hex_float("-0x1.cf79abc9e3b3ap-47"));
        assert_eq!(SHIFT, hex_float("0x1.8p52"));
        let printed = [
            "0x1.ffffffffffdbdp-2",
            "0x1.555555555543cp-3",
            "0x1.55555cf172b91p-5",
            "0x1.1111167a4d017p-7",
        ];
        for (c, t) in C.iter().zip(printed) {
            assert_eq!(*c, hex_float(t), "{t}");
        }
        for i in 0..128u64 {
            let scale = f64::from_bits(TAB[2 * i as usize + 1] + (i << 45));
            let exact = (i as f64 / 128.0).exp2();
            assert!((scale - exact).abs() <= f64::EPSILON * exact, "scale {i}");
            assert!(
                f64::from_bits(TAB[2 * i as usize]).abs() < f64::EPSILON / 2.0,
                "tail {i}"
            );
        }
        let fnv = TAB
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
                (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)
            });
        assert_eq!(fnv, 0x3025_0b75_e556_caa5);
    }

    /// Values known independently: e, 1/e, e^0.5, e^10 rounded to f64
    /// (their correctly rounded bits, from 60-digit decimal arithmetic,
    /// which a 0.51-ulp exp gives for these arguments).
    #[test]
    fn known_values() {
        if !runs_here() {
            return;
        }
        let e = exp4([1.0, -1.0, 0.5, 10.0]).expect("in range");
        assert_eq!(e[0], core::f64::consts::E);
        assert_eq!(e[1], 0.367_879_441_171_442_33);
        assert_eq!(e[2], 1.648_721_270_700_128_1);
        assert_eq!(e[3], 22_026.465_794_806_718);
    }

    /// The probes give the bits of glibc 2.36's FMA copy (Debian 12,
    /// `math.exp` in Python on an AVX2 + FMA CPU): a result of the
    /// non-FMA copies, or of this code with a product unfused, differs.
    #[test]
    fn probes_give_the_fma_copys_bits() {
        if !runs_here() {
            return;
        }
        let fma_copy = [
            [
                0x4010_d8ee_78ed_398f,
                0x3fd7_73ff_9071_43a3,
                0x3fe5_7419_4e3f_ba0b,
                0x3f51_7a0c_18ec_5f97,
            ],
            [
                0x4066_3c6c_7f4e_d044,
                0x3627_d896_9905_fc7b,
                0x40fb_1b92_77ba_cb7c,
                0x3d64_ba7d_3883_3519,
            ],
        ];
        for (p, bits) in PROBES.iter().zip(fma_copy) {
            assert_eq!(exp4(*p).expect("in range").map(f64::to_bits), bits);
        }
    }

    /// glibc's version string, compared as numbers (2.9 < 2.28).
    #[test]
    fn version_compare() {
        assert!(at_least("2.28", (2, 28)));
        assert!(at_least("2.36", (2, 28)));
        assert!(at_least("3.0", (2, 28)));
        assert!(!at_least("2.17", (2, 28)));
        assert!(!at_least("2.9", (2, 28)));
        assert!(!at_least("2", (2, 28)));
        assert!(!at_least("x.y", (2, 28)));
    }

    /// Outside 2^−54 ≤ |x| < 512 in any lane, no answer (the scalar exp's
    /// special cases are not copied).
    #[test]
    fn declines_outside_the_fast_path() {
        if !runs_here() {
            return;
        }
        for bad in [
            0.0,
            -0.0,
            1e-17,
            512.0,
            -600.0,
            1e3,
            f64::INFINITY,
            f64::NAN,
        ] {
            assert_eq!(exp4([1.0, bad, 2.0, 3.0]), None, "{bad}");
        }
        assert!(exp4([2f64.powi(-54), -511.9, 1e-16, 5.0]).is_some());
    }

    /// The point of the module: the platform's `exp`, to the bit, over
    /// 2·10⁵ arguments: random ones (a fixed xorshift) on the whole fast
    /// path and dense ones where the law's exponentials fall (|x| ≤ 30).
    #[test]
    fn exp4_is_the_platform_exp_to_the_bit() {
        if !runs_here() {
            return;
        }
        let mut s = 0x9e37_79b9_7f4a_7c15_u64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut checked = 0;
        for i in 0..50_000 {
            let span = if i % 2 == 0 { 60.0 } else { 1022.0 };
            let v = [0; 4].map(|_| (2.0 * next() - 1.0) * span * 0.5 + 1e-9);
            let Some(e) = exp4(v) else { continue };
            for (ei, vi) in e.iter().zip(v) {
                assert_eq!(ei.to_bits(), vi.exp().to_bits(), "exp({vi:e})");
                checked += 1;
            }
        }
        assert!(checked > 190_000, "{checked}");
    }
}
