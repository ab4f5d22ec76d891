//! The forms of the law that exist for speed, each held to the plain law
//! ([`super::law`]) to the bit: the one pass that fuses the law with the
//! Euler step ([`Euler`], a Cortex-M's), the law's passes then a vectorised
//! Euler pass (a host's), and their copies compiled for AVX2 and FMA that
//! [`Controller::law`] and [`Controller::law_euler`] dispatch to.

use super::law::Prelude;
use super::{NnState, NnVsc};
use crate::control::sliding::SlidingParts;
#[cfg(doc)]
use crate::control::Controller;
use crate::control::{flags, Measurement, Output};
use crate::math::Real;
use crate::rbf::{N_KERNELS, N_LEVELS, N_PHI};
use crate::rk4::OdeState;

impl<T: Real> NnVsc<T> {
    /// [`Controller::law_euler`] in one pass over the weights.
    #[inline(always)]
    pub(super) fn law_euler_one_pass(
        &self,
        m: &Measurement<T>,
        s: &NnState<T>,
        next: &mut NnState<T>,
        dt: T,
    ) -> (Output<SlidingParts<T>, T>, bool) {
        let mut sink = Euler {
            next,
            dt,
            lane: [T::ZERO; N_LEVELS],
        };
        let out = self.law_and_euler(m, s, &mut sink);
        (out, sink.finite())
    }

    /// The law's passes, then the vectorised Euler pass (an out-of-order
    /// host; see [`Controller::law_euler`]).
    #[inline(always)]
    pub(super) fn law_then_euler(
        &self,
        m: &Measurement<T>,
        s: &NnState<T>,
        next: &mut NnState<T>,
        dt: T,
    ) -> (Output<SlidingParts<T>, T>, bool) {
        // The law writes every component of ξ̇: no zeroing first. ‖W‖ of
        // the state the law saw (a logged diagnostic, see
        // `annotate_stepped`) here, beside the Euler pass it does not
        // depend on (its chain of additions overlaps that pass), and in
        // AVX2 when the step is.
        let mut out = self.law_body(m, s, next);
        out.parts.w_norm = crate::math::norm(&s.w);
        let finite = next.euler_from(s, dt);
        (out, finite)
    }

    /// [`NnVsc::law_then_euler`] for the target's baseline (SSE2 on an
    /// x86-64), as a function of its own: [`Controller::law_euler`], then
    /// only a dispatch to this or to [`NnVsc::law_then_euler_avx2`], is
    /// small enough to inline into the simulator's loop, and the law's
    /// output is written straight into the caller's frame.
    #[inline(never)]
    pub(super) fn law_then_euler_baseline(
        &self,
        m: &Measurement<T>,
        s: &NnState<T>,
        next: &mut NnState<T>,
        dt: T,
    ) -> (Output<SlidingParts<T>, T>, bool) {
        self.law_then_euler(m, s, next, dt)
    }

    /// [`NnVsc::law_then_euler`] compiled for AVX2 and FMA: the rows, WᵀΦ's
    /// sums and the Euler pass in 4-wide vectors instead of SSE2's 2-wide,
    /// and Φ's four exponentials in one vector ([`Real::exp4`], inlined
    /// here because this function has the FMA it needs). The same
    /// operations in the same order (Rust never fuses a·b + c of its own,
    /// so enabling FMA fuses nothing in the law; no sum is reassociated),
    /// so the same bits.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(all(any(test, feature = "std"), target_arch = "x86_64"))]
    #[allow(unsafe_code)]
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn law_then_euler_avx2(
        &self,
        m: &Measurement<T>,
        s: &NnState<T>,
        next: &mut NnState<T>,
        dt: T,
    ) -> (Output<SlidingParts<T>, T>, bool) {
        self.law_then_euler(m, s, next, dt)
    }

    /// [`NnVsc::law_body`] for the target's baseline, as a function of its
    /// own: [`Controller::law`] is then only the dispatch and a tail call
    /// (with the body inlined there, every call, AVX2 or not, paid the
    /// body's prologue: six registers saved and a 700-byte frame). Where
    /// there is no dispatch, inlined as before.
    #[cfg_attr(all(any(test, feature = "std"), target_arch = "x86_64"), inline(never))]
    #[cfg_attr(
        not(all(any(test, feature = "std"), target_arch = "x86_64")),
        inline(always)
    )]
    pub(super) fn law_baseline(
        &self,
        m: &Measurement<T>,
        s: &NnState<T>,
        ds: &mut NnState<T>,
    ) -> Output<SlidingParts<T>, T> {
        self.law_body(m, s, ds)
    }

    /// [`NnVsc::law_body`] compiled for AVX2 and FMA, as
    /// [`NnVsc::law_then_euler_avx2`] is: the same bits.
    ///
    /// # Safety
    /// The CPU must support AVX2 and FMA.
    #[cfg(all(any(test, feature = "std"), target_arch = "x86_64"))]
    #[allow(unsafe_code)]
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn law_avx2(
        &self,
        m: &Measurement<T>,
        s: &NnState<T>,
        ds: &mut NnState<T>,
    ) -> Output<SlidingParts<T>, T> {
        self.law_body(m, s, ds)
    }

    /// The law of [`Controller::law`], the same
    /// operations in the same order, with ξ + dt·ξ̇ written by `sink` as
    /// each row of Ẇ is formed. (A copy of the law rather than one generic
    /// body for both: sharing it cost the host's `law` about 290
    /// instructions, its inlining decisions changed.
    /// `law_euler_is_law_then_euler_to_the_bit` holds the two together.)
    #[inline(always)]
    fn law_and_euler(
        &self,
        m: &Measurement<T>,
        s: &NnState<T>,
        sink: &mut Euler<'_, T>,
    ) -> Output<SlidingParts<T>, T> {
        let p = &self.params;
        let Prelude {
            g,
            gains,
            n,
            st,
            phi_norm,
            gamma2,
            mut fl,
            sd,
            mu,
            xi,
            sw_num,
            sw_v,
        } = self.prelude(m, s);
        // WᵀΦ and Ẇ = H⁻¹(σΔΦ − η|σΔ|W) (26) without forming Φ: kernel
        // (i1, i2, i3) is g1·g2·g3, so by rows of five (fixed i1, i2)
        // WᵀΦ = Σ_i1 g1 Σ_i2 g2 (w_row · g3) and Ẇ_row = (σΔ·g1g2/h)·g3 − η|σΔ|/h·w_row.
        // Each row of W is loaded once, for its term of WᵀΦ and its Ẇ (on
        // an in-order core the loads are the cost; the law's separate
        // passes suit an out-of-order host).
        let w = &s.w;
        let g3 = &g[2];
        let a = sd * self.inv_h;
        let bw = p.eta * sd.abs() * self.inv_h;
        // The sink's factors: with `Real::FOLDED_EULER`, dt folded in.
        let (ka, kbw) = sink.factors(a, bw);
        let mut wphi_k = T::ZERO;
        for (i1, &g1) in g[0].iter().enumerate() {
            // u from its first term, as in the law.
            let mut u = T::ZERO;
            for (i2, &g2) in g[1].iter().enumerate() {
                let j = 1 + N_LEVELS * (N_LEVELS * i1 + i2);
                let wr = row_of(w, j);
                let t = ((wr[0] * g3[0] + wr[2] * g3[2]) + (wr[1] * g3[1] + wr[3] * g3[3]))
                    + wr[4] * g3[4];
                // σΔ does not depend on W: the row's Ẇ right away, while
                // its weights are in registers.
                sink.row(j, wr, ka * (g1 * g2), g3, kbw);
                u = if i2 == 0 { g2 * t } else { u + g2 * t };
            }
            wphi_k += g1 * u;
        }
        let mut wphi = w[0] + wphi_k;
        for (i, &zi) in m.z.iter().enumerate() {
            wphi += w[1 + N_KERNELS + i] * zi;
        }
        sink.tail(w, ka, &m.z, kbw);

        let v = n + wphi + sw_v;
        let (b_bar, clamped) = gains.pick(&self.model, v);
        if clamped {
            fl |= flags::VALVE_ROOT_CLAMPED;
        }
        let u_eq = (n + wphi) / b_bar;
        let u_sw = sw_num / (b_bar * self.one_minus_bb);

        sink.int_e(s.int_e, st.e); // ∫e' = e

        Output {
            u: u_eq + u_sw,
            flags: fl,
            parts: SlidingParts {
                u_eq,
                u_sw,
                e: st.e,
                sigma: st.sigma,
                sigma_delta: sd,
                wphi,
                phi_norm,
                xi,
                b_bar,
                gain: gamma2,
                mu,
                norm_e: st.norm_e,
                ..SlidingParts::default()
            },
        }
    }
}

/// Whether [`Controller::law_euler`] takes the one-pass form (Arm: in
/// order, no SIMD), which leaves ‖W‖ to `annotate`; elsewhere the law's
/// passes, a vectorised Euler pass and ‖W‖ beside it.
const ONE_PASS: bool = cfg!(target_arch = "arm");

/// [`ONE_PASS`], and on every target for a float type with
/// [`Real::FOLDED_EULER`] (f32): its folded Euler update exists only in
/// the one pass, so that a host's f32 build computes a board's bits.
#[inline(always)]
pub(super) const fn one_pass<T: Real>() -> bool {
    ONE_PASS || T::FOLDED_EULER
}

/// The five weights `j..j + 5`.
#[inline(always)]
fn row_of<T>(w: &[T; N_PHI], j: usize) -> &[T; N_LEVELS] {
    w[j..j + N_LEVELS].try_into().expect("five")
}

/// Writes ξ + dt·ξ̇, each component as [`OdeState::euler_from`] computes
/// it (`w + dt·ẇ`; with [`Real::FOLDED_EULER`], f32, the weights as
/// `(w − (dt·bw)·w) + (dt·a)·Φᵢ`), and sums the results v per lane (one lane per column
/// of a row, so the sums do not wait on each other). A sum is finite only
/// if every v in it is (±∞ and NaN propagate through finite additions,
/// ∞ − ∞ is NaN); a non-finite sum (an overflowing sum of finite v, or a
/// non-finite v) is settled by a scan of `next` (rare: faults only). One
/// addition per weight instead of the 0·v test's multiplication and
/// addition.
struct Euler<'a, T> {
    next: &'a mut NnState<T>,
    dt: T,
    lane: [T; N_LEVELS],
}

impl<T: Real> Euler<'_, T> {
    /// The factors `row` and `tail` take for Ẇ = a·Φ − bw·W: `(a, bw)`,
    /// or with [`Real::FOLDED_EULER`] `(dt·a, dt·bw)`.
    #[inline(always)]
    fn factors(&self, a: T, bw: T) -> (T, T) {
        if T::FOLDED_EULER {
            (self.dt * a, self.dt * bw)
        } else {
            (a, bw)
        }
    }
    /// w + dt·ẇ for ẇ = ag·g − bw·w, with `ag` and `bw` from
    /// [`Euler::factors`]: `w + dt·(ag·g − bw·w)` as
    /// [`OdeState::euler_from`] computes it, or, folded,
    /// `(w − bw·w) + ag·g`.
    #[inline(always)]
    fn update(dt: T, w: T, ag: T, g: T, bw: T) -> T {
        if T::FOLDED_EULER {
            (w - bw * w) + ag * g
        } else {
            w + dt * (ag * g - bw * w)
        }
    }
    /// The five weights `j..j + 5` (`wr`), whose Ẇ is `ag·g3[i] − bw·wr[i]`.
    #[inline(always)]
    fn row(&mut self, j: usize, wr: &[T; N_LEVELS], ag: T, g3: &[T; N_LEVELS], bw: T) {
        let dt = self.dt;
        let dr = &mut self.next.w[j..j + N_LEVELS];
        for (((n, &wi), &gi), l) in dr.iter_mut().zip(wr).zip(g3).zip(&mut self.lane) {
            let v = Self::update(dt, wi, ag, gi, bw);
            *n = v;
            *l += v;
        }
    }
    /// The bias weight (Ẇ = a − bw·w[0], Φ_0 = 1) and the z weights
    /// (Ẇ = a·z_i − bw·w[k]).
    #[inline(always)]
    fn tail(&mut self, w: &[T; N_PHI], a: T, z: &[T; 4], bw: T) {
        let v = Self::update(self.dt, w[0], a, T::ONE, bw);
        self.next.w[0] = v;
        self.lane[0] += v;
        for (i, &zi) in z.iter().enumerate() {
            let k = 1 + N_KERNELS + i;
            let v = Self::update(self.dt, w[k], a, zi, bw);
            self.next.w[k] = v;
            self.lane[1 + i] += v;
        }
    }
    /// ∫e' = e (`int_e` is the state's ∫e).
    #[inline(always)]
    fn int_e(&mut self, int_e: T, e: T) {
        self.next.int_e = int_e + self.dt * e;
    }

    /// Whether every component written is finite.
    #[inline(always)]
    fn finite(&self) -> bool {
        let l = &self.lane;
        let sum = ((l[0] + l[1]) + (l[2] + l[3])) + l[4];
        self.next.int_e.is_finite() && (sum.is_finite() || self.next.all_finite())
    }
}
