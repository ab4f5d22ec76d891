//! The paper's law, eqs. (23)–(34) of Theorem 3, as [`Controller::law`]
//! computes it: [`NnVsc::prelude`] (Φ's per-axis factors, N, the surface,
//! σΔ (27), μ (SPEC §5), ξ, γ2 (34) and the switching term of (25)), then
//! [`NnVsc::law_body`] (WᵀΦ, b̄, u_eq (24), u_sw (25), u (23) and Ẇ (26)).
//! The fused, dispatched and vector forms that give the same bits faster are
//! in [`super::fast`].

use super::{MuRule, NnState, NnVsc};
use crate::control::sliding::SlidingParts;
#[cfg(doc)]
use crate::control::Controller;
use crate::control::{flags, Measurement, Output};
use crate::math::{sgn, Real};
use crate::rbf::{Rbf, N_KERNELS, N_LEVELS};

impl<T: Real> NnVsc<T> {
    /// [`Controller::law`]'s body, inlined into [`NnVsc::law_baseline`]
    /// (itself inlined into `law` where there is no AVX2 dispatch) and
    /// into the AVX2 copies of `law` and of [`Controller::law_euler`].
    #[inline(always)]
    pub(super) fn law_body(
        &self,
        m: &Measurement<T>,
        s: &NnState<T>,
        ds: &mut NnState<T>,
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
        // WᵀΦ first, in a pass of its own: v, b̄ and u wait for it. Nothing
        // waits for Ẇ, so its pass comes last (in one fused pass its
        // products delayed WᵀΦ's chain). Each result is computed by the
        // same operations in the same order as in the fused pass.
        let w = &s.w;
        let g3 = &g[2];
        let t = |i1: usize, i2: usize| {
            let j = 1 + N_LEVELS * (N_LEVELS * i1 + i2);
            let wr = &w[j..j + N_LEVELS];
            ((wr[0] * g3[0] + wr[2] * g3[2]) + (wr[1] * g3[1] + wr[3] * g3[3])) + wr[4] * g3[4]
        };
        // u[i1] = Σ_i2 g2·t(i1, i2) from its first term rather than from
        // 0 + first term: they differ only when every term is −0 (u = −0
        // against +0), and u only enters wphi_k += g1·u, where wphi_k (from
        // 0 + …) is never −0, so wphi_k + g1·(±0) is the same. Built i2 by
        // i2 for the five i1 side by side (each u[i1] by the same
        // operations in the same order as one i1 at a time).
        let mut u: [T; N_LEVELS] = core::array::from_fn(|i1| g[1][0] * t(i1, 0));
        for (i2, &g2) in g[1].iter().enumerate().skip(1) {
            for (i1, ui) in u.iter_mut().enumerate() {
                *ui += g2 * t(i1, i2);
            }
        }
        let mut wphi_k = T::ZERO;
        for (&g1, &ui) in g[0].iter().zip(&u) {
            wphi_k += g1 * ui;
        }
        let mut wphi = w[0] + wphi_k;
        for (i, &zi) in m.z.iter().enumerate() {
            wphi += w[1 + N_KERNELS + i] * zi;
        }

        let v = n + wphi + sw_v;
        let (b_bar, clamped) = gains.pick(&self.model, v);
        if clamped {
            fl |= flags::VALVE_ROOT_CLAMPED;
        }
        let u_eq = (n + wphi) / b_bar;
        let u_sw = sw_num / (b_bar * self.one_minus_bb);

        let a = sd * self.inv_h;
        let bw = p.eta * sd.abs() * self.inv_h;
        let dw = &mut ds.w;
        for (i1, &g1) in g[0].iter().enumerate() {
            for (i2, &g2) in g[1].iter().enumerate() {
                let j = 1 + N_LEVELS * (N_LEVELS * i1 + i2);
                let (wr, dr) = (&w[j..j + N_LEVELS], &mut dw[j..j + N_LEVELS]);
                let ag = a * (g1 * g2);
                for ((d, &wi), &gi) in dr.iter_mut().zip(wr).zip(g3) {
                    *d = ag * gi - bw * wi;
                }
            }
        }
        dw[0] = a - bw * w[0]; // Φ_0 = 1
        for (i, &zi) in m.z.iter().enumerate() {
            let k = 1 + N_KERNELS + i;
            dw[k] = a * zi - bw * w[k];
        }
        ds.int_e = st.e; // ∫e' = e

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

    /// What [`Controller::law`] and [`NnVsc::law_euler`] compute before the
    /// passes over W, in the same operations and order in both: Φ's
    /// per-axis factors, b̄ both ways, N, the surface, σΔ, μ, ξ and the
    /// switching term.
    #[inline(always)]
    pub(super) fn prelude(&self, m: &Measurement<T>, s: &NnState<T>) -> Prelude<T> {
        let p = &self.params;
        let x = &m.x;
        // The load pressure (a sine) and Φ (four exponentials) first: the
        // longest chains, needing only x. Then, while they run out, what
        // else needs only the measurement: b̄ for both valve directions (a
        // division and a root each; the end of the law only picks one by
        // sgn v), N and the surface. Φ is never stored: its 125 kernels are
        // the products of 15 per-axis factors (see the passes over W below).
        let pl = self.model.load_pressure(x);
        let g = self.rbf.gaussians(x);
        let gains = self.model.directional_gains(pl, self.b_floor);
        let n = self
            .surface
            .equivalent_numerator(&self.model.coeffs.as_array(), x, &m.z);
        let st = self.surface.evaluate(x, &m.z, s.int_e);
        let phi_norm = Rbf::norm_from(&g, &m.z);

        // c = ηW²max/4 + ε0‖Φ‖ + ε1; γ2 = c + ε2 (34).
        let c = self.c_fixed + p.eps0 * phi_norm;
        let gamma2 = c + p.eps2;

        let mut fl = 0;
        let (sd, mu, xi) = if st.norm_e > T::ZERO {
            let delta = p.alpha_bar * st.norm_e;
            let sd = if st.sigma.abs() > delta {
                st.sigma - delta * sgn(st.sigma)
            } else {
                T::ZERO
            };
            let mu = match p.mu_rule {
                MuRule::Remark7 => self.alpha_gap * st.norm_e * p.eps2 / c,
                MuRule::Literal33 => self.alpha_gap * st.norm_e * ((gamma2 - c) / c - T::ONE),
                MuRule::Zero => T::ZERO,
            };
            let e = st.e_vec();
            let ed = st.e_vec_dot();
            let ete = e[0] * ed[0] + e[1] * ed[1] + e[2] * ed[2];
            let xi = p.alpha_bar * ete * sgn(st.sigma) / st.norm_e;
            (sd, mu, xi)
        } else {
            fl |= flags::ZERO_ERROR_NORM;
            (T::ZERO, T::ZERO, T::ZERO)
        };

        let denom = sd.abs() + mu;
        // |σΔ| + μ ≥ 0 under the default rule, and 0 only when σΔ = 0.
        // (Under the literal (33) it can be negative: computed as printed.)
        let frac = if denom != T::ZERO && sd != T::ZERO {
            sd / denom
        } else {
            T::ZERO
        };
        // (b̄ − β)·u_sw = γ1σΔ + γ2σΔ/(|σΔ| + μ), and b̄ − β = b̄(1 − bound_b).
        let sw_num = p.gamma1 * sd + gamma2 * frac;
        let sw_v = sw_num / self.one_minus_bb;
        Prelude {
            g,
            gains,
            n,
            st,
            phi_norm,
            gamma2,
            fl,
            sd,
            mu,
            xi,
            sw_num,
            sw_v,
        }
    }
}

/// The part of the NNBVSC law before the passes over W ([`NnVsc::prelude`]).
pub(super) struct Prelude<T: Real> {
    pub(super) g: [[T; N_LEVELS]; 3],
    pub(super) gains: crate::servo::DirectionalGains<T>,
    pub(super) n: T,
    pub(super) st: crate::surface::SurfaceState<T>,
    pub(super) phi_norm: T,
    pub(super) gamma2: T,
    pub(super) fl: u8,
    pub(super) sd: T,
    pub(super) mu: T,
    pub(super) xi: T,
    pub(super) sw_num: T,
    pub(super) sw_v: T,
}
