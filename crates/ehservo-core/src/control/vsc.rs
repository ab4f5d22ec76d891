//! The traditional variable structure controller of Theorem 1.
//!
//! ```text
//! u    = u_eq + u_sw                                                    (11)
//! u_eq = {θ⃛d + ā1x1 + ā2x2 + ā3x3 + p1(θ̈d − x3) + p2(θ̇d − x2) + p3(θd − x1)}/b̄   (12)
//! u_sw = k·sgn(σ)                                                       (13)
//! k    = [α1|x1| + α2|x2| + α3|x3| + γ + β|u_eq|]/(b̄ − β)               (14)
//! ```
//!
//! with the bounds the controller knows: α_i = bound_a·|ā_i|,
//! β = bound_b·b̄(t), γ = |d(t)| (the nominal load term at the measured
//! state). The paper's Fig. 2 bounds are bound_a = 1, bound_b = 0.5.
//! Remark 2's boundary-layer variant replaces sgn(σ) by sat(σ/μ).
//! The state is ∫e alone (it enters σ through p3).

use super::sliding::SlidingParts;
use super::{flags, Controller, Measurement, Output, Truth};
use crate::error::{non_negative, positive, ParamError};
use crate::math::{sat, sgn, Real};
use crate::servo::NominalModel;
use crate::surface::SwitchingSurface;

/// How the switching term switches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Switching<T = f64> {
    /// sgn(σ), eq. (13).
    Sign,
    /// sat(σ/μ) with a constant boundary-layer width μ (Remark 2).
    Saturation {
        /// Width μ of the boundary layer (rad/s²).
        mu: T,
    },
}

/// Gains of the traditional VSC.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VscParams<T = f64> {
    /// α_i = bound_a·|ā_i|.
    pub bound_a: T,
    /// β = bound_b·b̄, 0 ≤ bound_b < 1 (A1: β < b̄).
    pub bound_b: T,
    /// sgn or sat.
    pub switching: Switching<T>,
}

impl VscParams<f64> {
    /// The paper's Theorem 1 controller with the Fig. 2 bounds.
    pub const fn paper() -> Self {
        Self {
            bound_a: 1.0,
            bound_b: 0.5,
            switching: Switching::Sign,
        }
    }
}

impl<T: Real> VscParams<T> {
    /// The same parameters in another float type.
    pub fn cast<U: Real>(&self) -> VscParams<U> {
        let c = |v: T| U::of(v.to_f64());
        VscParams {
            bound_a: c(self.bound_a),
            bound_b: c(self.bound_b),
            switching: match self.switching {
                Switching::Sign => Switching::Sign,
                Switching::Saturation { mu } => Switching::Saturation { mu: c(mu) },
            },
        }
    }
}

/// The traditional VSC (Theorem 1), or its boundary-layer variant.
/// In a scenario: `kind = "vsc"` or `"vsc-sat"`
/// ([`VscConfig`](super::sliding::VscConfig),
/// [`VscSatConfig`](super::sliding::VscSatConfig)).
///
/// ```
/// use ehservo_core::prelude::*;
///
/// let model = NominalModel::new(ServoParams::paper(), Load::paper());
/// let vsc = Vsc::try_new(model, SwitchingSurface::paper(), VscParams::paper())?;
/// // At rest, z = (0, −0.5, 0, 0): σ = p1·ė = 90·(−0.5) = −45 and
/// // N = p2·θ̇d = −1300, so k·b̄ = 0.5·1300/(1 − 0.5) = 1300 (14) and
/// // b̄·u = N + k·b̄·sgn σ = −2600: the sign of σ picks the direction.
/// let m = Measurement { t: 0.0, x: [0.0; 3], z: [0.0, -0.5, 0.0, 0.0] };
/// let mut ds = [0.0];
/// let out = vsc.law(&m, &[0.0], &mut ds);
/// assert!((out.sigma + 45.0).abs() < 1e-12);
/// assert!((out.u * out.b_bar + 2600.0).abs() < 1e-9);
/// // The state is ∫e, and ė of it is e = 0.
/// assert_eq!(ds[0], 0.0);
/// // Assumption A1 needs β < b̄: bound_b = 1 is refused.
/// let bad = VscParams { bound_b: 1.0, ..VscParams::paper() };
/// assert_eq!(Vsc::try_new(model, SwitchingSurface::paper(), bad).unwrap_err().name, "bound_b");
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vsc<T: Real = f64> {
    model: NominalModel<T>,
    surface: SwitchingSurface<T>,
    params: VscParams<T>,
    alpha: [T; 3],
    b_floor: T,
}

impl<T: Real> Vsc<T> {
    /// Validates the gains and builds the controller.
    pub fn try_new(
        model: NominalModel<T>,
        surface: SwitchingSurface<T>,
        params: VscParams<T>,
    ) -> Result<Self, ParamError> {
        non_negative("bound_a", params.bound_a)?;
        non_negative("bound_b", params.bound_b)?;
        if params.bound_b >= T::ONE {
            return Err(ParamError::new(
                "bound_b",
                "must be < 1 (Assumption A1: β < b̄)",
                params.bound_b.to_f64(),
            ));
        }
        if let Switching::Saturation { mu } = params.switching {
            positive("mu", mu)?;
        }
        let a = model.coeffs.as_array();
        Ok(Self {
            alpha: [
                params.bound_a * a[0].abs(),
                params.bound_a * a[1].abs(),
                params.bound_a * a[2].abs(),
            ],
            b_floor: T::of(1e-3) * model.b_at_rest(),
            model,
            surface,
            params,
        })
    }

    /// The same controller in another float type.
    pub fn cast<U: Real>(&self) -> Result<Vsc<U>, ParamError> {
        Vsc::try_new(self.model.cast(), self.surface.cast(), self.params.cast())
    }

    /// The gains.
    pub fn params(&self) -> &VscParams<T> {
        &self.params
    }

    /// The switching surface.
    pub fn surface(&self) -> &SwitchingSurface<T> {
        &self.surface
    }

    /// The nominal model.
    pub fn model(&self) -> &NominalModel<T> {
        &self.model
    }
}

impl<T: Real> Controller<T> for Vsc<T> {
    type State = [T; 1];
    type Parts = SlidingParts<T>;

    fn initial_state(&self) -> [T; 1] {
        [T::ZERO]
    }

    #[inline]
    fn law(&self, m: &Measurement<T>, s: &[T; 1], ds: &mut [T; 1]) -> Output<SlidingParts<T>, T> {
        let x = &m.x;
        let st = self.surface.evaluate(x, &m.z, s[0]);
        let a = self.model.coeffs.as_array();
        let n = self.surface.equivalent_numerator(&a, x, &m.z);
        let gamma = self.model.d(x).abs();
        let bb = self.params.bound_b;
        let (switch, mu) = match self.params.switching {
            Switching::Sign => (sgn(st.sigma), T::ZERO),
            Switching::Saturation { mu } => (sat(st.sigma / mu), mu),
        };
        // k·b̄ = [Σα|x| + γ + bb·|N|]/(1 − bb): independent of b̄ (module doc).
        let kb = (self.alpha[0] * x[0].abs()
            + self.alpha[1] * x[1].abs()
            + self.alpha[2] * x[2].abs()
            + gamma
            + bb * n.abs())
            / (T::ONE - bb);
        let v = n + switch * kb;
        let mut fl = 0;
        let (b_bar, clamped) = self.model.gain_for(x, v, self.b_floor);
        if clamped {
            fl |= flags::VALVE_ROOT_CLAMPED;
        }
        let u_eq = n / b_bar;
        let k = kb / b_bar;
        let u_sw = k * switch;
        ds[0] = st.e;
        Output {
            u: u_eq + u_sw,
            flags: fl,
            parts: SlidingParts {
                u_eq,
                u_sw,
                e: st.e,
                sigma: st.sigma,
                sigma_delta: st.sigma,
                b_bar,
                gain: k,
                mu,
                norm_e: st.norm_e,
                ..SlidingParts::default()
            },
        }
    }

    fn annotate(&self, _s: &[T; 1], out: &mut Output<SlidingParts<T>, T>, truth: &dyn Truth) {
        SlidingParts::annotate(out, &[], truth);
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;
    use crate::servo::{Load, ServoParams};

    fn vsc(switching: Switching) -> Vsc {
        Vsc::try_new(
            NominalModel::new(ServoParams::paper(), Load::none()),
            SwitchingSurface::paper(),
            VscParams {
                switching,
                ..VscParams::paper()
            },
        )
        .unwrap()
    }

    /// At rest (x = 0, no load) with z = (0, 0.5, 0, 0) and ∫e = 0:
    /// e = 0, ė = 0.5, ë = 0 → σ = 90·0.5 = 45 > 0.
    /// N = p2·θ̇d = 2600·0.5 = 1300; γ = 0 (no load); Σα|x| = 0.
    /// b̄ = b(0, +) = 17911.75 (Pl = 0). u_eq = 1300/17911.75 = 0.0725780.
    /// k = [0 + 0 + 0.5·b̄·|u_eq|]/(0.5·b̄) = |u_eq| → u = 2·u_eq = 0.1451561.
    #[test]
    fn law_by_hand_at_rest() {
        let c = vsc(Switching::Sign);
        let m = Measurement {
            t: 0.0,
            x: [0.0; 3],
            z: [0.0, 0.5, 0.0, 0.0],
        };
        let mut ds = [0.0];
        let o = c.law(&m, &[0.0], &mut ds);
        assert!((o.sigma - 45.0).abs() < 1e-12);
        assert!((o.u_eq - 0.0725780).abs() < 1e-7, "u_eq {}", o.u_eq);
        assert!((o.u_sw - 0.0725780).abs() < 1e-7);
        assert!((o.u - 0.1451561).abs() < 1e-7);
        assert_eq!(ds[0], 0.0); // ∫e' = e = 0
                                // Reverse the error: σ < 0 flips only the switching term.
        let m2 = Measurement {
            z: [0.0, -0.5, 0.0, 0.0],
            ..m
        };
        let o2 = c.law(&m2, &[0.0], &mut ds);
        assert!((o2.u_eq + 0.0725780).abs() < 1e-7);
        assert!((o2.u + 0.1451561).abs() < 1e-7);
    }

    /// With a boundary layer of width μ = 90 and σ = 45: sat(0.5) = 0.5, so
    /// u_sw is half the k above: u = 1.5·u_eq = 0.1088671.
    #[test]
    fn boundary_layer_scales_switching() {
        let c = vsc(Switching::Saturation { mu: 90.0 });
        let m = Measurement {
            t: 0.0,
            x: [0.0; 3],
            z: [0.0, 0.5, 0.0, 0.0],
        };
        let o = c.law(&m, &[0.0], &mut [0.0]);
        assert!((o.u - 0.1088671).abs() < 1e-7, "{}", o.u);
    }

    #[test]
    fn rejects_bad_gains() {
        let m = NominalModel::new(ServoParams::paper(), Load::paper());
        let s = SwitchingSurface::paper();
        let bad = |p: VscParams| Vsc::try_new(m, s, p).unwrap_err().name;
        assert_eq!(
            bad(VscParams {
                bound_b: 1.0,
                ..VscParams::paper()
            }),
            "bound_b"
        );
        assert_eq!(
            bad(VscParams {
                bound_a: -1.0,
                ..VscParams::paper()
            }),
            "bound_a"
        );
        assert_eq!(
            bad(VscParams {
                switching: Switching::Saturation { mu: 0.0 },
                ..VscParams::paper()
            }),
            "mu"
        );
    }
}
