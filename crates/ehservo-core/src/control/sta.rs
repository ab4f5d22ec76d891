//! Super-twisting sliding-mode control on the paper's switching surface.
//!
//! Reference: A. Levant, "Sliding order and sliding accuracy in sliding
//! mode control", *International Journal of Control* 58(6), 1993 (the
//! super-twisting algorithm); gains by the standard rule of the later
//! literature on it (k1 = 1.5√C, k2 = 1.1C).
//!
//! **On this plant.** σ is the paper's (10), `σ = ë + p1ė + p2e + p3∫e`
//! with `e = θd − θ` ([`crate::surface`]), the σ of the VSC and NNBVSC.
//! With the plant (8), `σ̇ = N + Δa·x + d − b̄u − Δb·u`, N the numerator of
//! (12) from the nominal model (the VSC's equivalent control,
//! [`crate::surface::SwitchingSurface::equivalent_numerator`]). The STA is
//! written for `σ̇ = w_sta + ρ`, `w_sta = −k1|σ|^{1/2}sgn σ + v`,
//! `v̇ = −k2·sgn σ`; here the input enters σ̇ with a minus sign (e is
//! reference minus plant), so the law sets `b̄u = N − w_sta`:
//!
//! ```text
//! u    = [N + k1·|σ|^{1/2}·sgn(σ) − v]/b̄
//! v̇    = −k2·sgn(σ)
//! ```
//!
//! so that `σ̇ = −(1 + Δb/b̄)·(k1|σ|^{1/2}sgn σ − v) + ρ`,
//! `ρ = Σ Δa_i x_i + d − (Δb/b̄)·N`. b̄ = b(x, sgn(b̄u)) is the nominal gain
//! at the measured state with the valve direction of the command, exactly
//! as the VSC finds it (the module doc of [`crate::control`]; floored at
//! 10⁻³·b̄0 when the valve root clamps). The state is (∫e, v), v(0) = 0.
//!
//! **Default gains: k1 = 1.5·√C, k2 = 1.1·C, with C(t) a bound on |ρ̇|**
//! evaluated at each instant from the bounds the controller knows, as the
//! VSC's gain (14) is (α_i = bound_a·|ā_i|, β = bound_b·b̄), along the
//! reference (ẋ ≈ ż: on the surface the state follows the reference):
//!
//! ```text
//! C(t) = [Σ (α_i + bound_b·|ā_i|)·|ż_{i+1}| + D(z)]/(1 − bound_b),   ż = (θ̇d, θ̈d, θ⃛d)
//! D(z) = |A·k|·(c_T·|θ̇d| + (|k|·θ̇d² + |θ̈d|)/Jt)
//! ```
//!
//! `Σ α_i|ẋ_i|` bounds `d(Δa·x)/dt`; `bound_b·Σ|ā_i||ẋ_i|` bounds the
//! `(Δb/b̄)·Ṅ` term by Ṅ's plant part (Ṅ's error terms vanish on σ = 0 and
//! θ⁗d is not available: both are left out); D bounds ḋ for the sine load
//! `Tl = A sin(kθ)`
//! (`d = c_T·Tl + Ṫl/Jt`, c_T = 4βe·Kce/(Vt·Jt); friction is left out);
//! the division by 1 − bound_b accounts for the input gain `1 + Δb/b̄ ≥
//! 1 − bound_b` as (14) does. The gains are thus time-varying, but depend
//! on the reference only: evaluated at the measured state instead (ẋ ≈
//! (x2, x3, θ⃛d)), they grow with the oscillation they should damp, and the
//! Fig. 2 loop sampled at 0.01 s diverged within 0.3 s that way. `k1` and
//! `k2` given as keys are constants instead (each independently).

use super::{Config, Controller, Design, Measurement, Output, Signal, Signals, Tunable};
use crate::control::flags;
use crate::error::{non_negative, positive, ParamError};
use crate::math::{sgn, sqrt, Real};
use crate::servo::NominalModel;
use crate::surface::SwitchingSurface;

/// `kind = "sta"`: the `[controller]` keys.
///
/// ```
/// use ehservo_core::control::sta::StaConfig;
/// # use ehservo_core::prelude::*;
/// # let design = Design {
/// #     model: NominalModel::new(ServoParams::paper(), Load::paper()),
/// #     surface: SwitchingSurface::paper(),
/// #     dt: 0.01,
/// # };
/// let sta = StaConfig { k1: Some(2.0), k2: Some(3.0), ..StaConfig::default() }.build(&design)?;
/// // At rest, z = (0, 0.5, 0, 0), state (∫e, v) = (0, 0.2): σ = 90·0.5 = 45,
/// // N = 2600·0.5 = 1300, so b̄·u = N + k1·√45·sgn σ − v = 1300 + 2√45 − 0.2,
/// // and v̇ = −k2·sgn σ = −3.
/// let m = Measurement { t: 0.0, x: [0.0; 3], z: [0.0, 0.5, 0.0, 0.0] };
/// let mut ds = [0.0; 2];
/// let out = sta.law(&m, &[0.0, 0.2], &mut ds);
/// assert!((out.u * out.b_bar - (1300.0 + 2.0 * 45f64.sqrt() - 0.2)).abs() < 1e-9);
/// assert_eq!(ds, [0.0, -3.0]);
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct StaConfig {
    /// k1, the gain of |σ|^{1/2}sgn σ (rad^{1/2}/s²); default 1.5·√C(t).
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub k1: Option<f64>,
    /// k2, the gain of v̇ = −k2·sgn σ (rad/s⁴); default 1.1·C(t).
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub k2: Option<f64>,
    /// Bound the controller knows on Δa_i: α_i = bound_a·|ā_i|. Default 1
    /// (the paper's Fig. 2 bound).
    pub bound_a: f64,
    /// Bound the controller knows on Δb: β = bound_b·b̄, < 1. Default 0.5.
    pub bound_b: f64,
}

impl Default for StaConfig {
    fn default() -> Self {
        Self {
            k1: None,
            k2: None,
            bound_a: 1.0,
            bound_b: 0.5,
        }
    }
}

/// The super-twisting law's parts.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StaParts<T = f64> {
    /// σ of (10) (rad/s²).
    pub sigma: T,
    /// Equivalent part N/b̄ (V).
    pub u_eq: T,
    /// The continuous STA term k1|σ|^{1/2}sgn(σ)/b̄ (V).
    pub u_sta: T,
    /// The integral term −v/b̄ (V).
    pub u_v: T,
    /// The STA's integral state v (rad/s³).
    pub v: T,
    /// C(t), the bound on |ρ̇| behind the default gains (rad/s⁴).
    pub c: T,
    /// Nominal gain b̄ used by the law (1/(V·s³)).
    pub b_bar: T,
    /// Tracking error θd − x1 (rad).
    pub e: T,
}

impl<T: Real> Signals for StaParts<T> {
    const SIGNALS: &'static [Signal] = &[
        Signal::new(
            "sigma",
            "sigma_rad_s2",
            "rad/s²",
            "switching function σ (10)",
        ),
        Signal::new("u_eq", "u_eq_V", "V", "equivalent part N/b̄"),
        Signal::new(
            "u_sta",
            "u_sta_V",
            "V",
            "continuous STA term k1|σ|^½sgn σ/b̄",
        ),
        Signal::new("u_v", "u_v_V", "V", "integral STA term −v/b̄"),
        Signal::new("v", "v_rad_s3", "rad/s³", "STA integral state v"),
        Signal::new(
            "c",
            "C_rad_s4",
            "rad/s⁴",
            "bound C(t) on the perturbation's rate",
        ),
        Signal::new(
            "b_bar",
            "b_bar_V_s3",
            "1/(V·s³)",
            "nominal gain b̄(t) of (9)",
        ),
        Signal::new("e", "", "rad", "tracking error θd − x1"),
    ];
    fn write(&self, out: &mut [f64]) {
        let v = [
            self.sigma, self.u_eq, self.u_sta, self.u_v, self.v, self.c, self.b_bar, self.e,
        ];
        for (o, v) in out.iter_mut().zip(v) {
            *o = v.to_f64();
        }
    }
}

/// The super-twisting controller, built.
/// Built by [`StaConfig`] (`kind = "sta"`), whose example evaluates one
/// step of the law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sta<T: Real = f64> {
    model: NominalModel<T>,
    surface: SwitchingSurface<T>,
    k1: Option<T>,
    k2: Option<T>,
    /// (α_i + bound_b·|ā_i|)/(1 − bound_b).
    c_x: [T; 3],
    /// |A·k|, |k|, c_T, 1/Jt for D(x), already over (1 − bound_b) in `ak`.
    load: [T; 4],
    b_floor: T,
}

impl<T: Real> Sta<T> {
    /// C(t) of the module doc for the reference `z = (θd, θ̇d, θ̈d, θ⃛d)`.
    ///
    /// ```
    /// use ehservo_core::control::sta::StaConfig;
    /// use ehservo_core::prelude::*;
    ///
    /// // No load, so D(z) = 0 and C = Σ (bound_a + bound_b)·|ā_i|·|ż_{i+1}|/(1 − bound_b).
    /// let model = NominalModel::new(ServoParams::paper(), Load::none());
    /// let design = Design { model, surface: SwitchingSurface::paper(), dt: 0.01 };
    /// let sta = StaConfig::default().build(&design)?; // bound_a = 1, bound_b = 0.5
    /// let [a1, a2, a3] = model.coeffs.as_array();
    /// let want = (1.0 + 0.5) * (a1 * 0.5 + a2 * 2.0 + a3 * 10.0) / (1.0 - 0.5);
    /// assert!((sta.c_bound(&[0.0, 0.5, 2.0, 10.0]) - want).abs() <= 1e-12 * want);
    /// # Ok::<(), ParamError>(())
    /// ```
    #[inline]
    pub fn c_bound(&self, z: &[T; 4]) -> T {
        let [ak, k, ct, inv_jt] = self.load;
        self.c_x[0] * z[1].abs()
            + self.c_x[1] * z[2].abs()
            + self.c_x[2] * z[3].abs()
            + ak * (ct * z[1].abs() + (k * z[1] * z[1] + z[2].abs()) * inv_jt)
    }

    /// The same controller in another float type.
    pub fn cast<U: Real>(&self) -> Sta<U> {
        let c = |v: T| U::of(v.to_f64());
        Sta {
            model: self.model.cast(),
            surface: self.surface.cast(),
            k1: self.k1.map(c),
            k2: self.k2.map(c),
            c_x: self.c_x.map(c),
            load: self.load.map(c),
            b_floor: c(self.b_floor),
        }
    }
}

impl Config for StaConfig {
    const KIND: &'static str = "sta";
    const USES_SURFACE: bool = true;
    /// Constant gains in place of the C(t) rule, over decades.
    const TUNABLE: &'static [Tunable] =
        &[Tunable::log("k1", 1.0, 1e4), Tunable::log("k2", 1.0, 1e7)];
    type Controller = Sta;
    type Law<F: Real> = Sta<F>;
    fn build_in<F: Real>(&self, d: &Design) -> Result<Sta<F>, ParamError> {
        Ok(self.build(d)?.cast())
    }

    fn build(&self, d: &Design) -> Result<Sta, ParamError> {
        let k1 = self.k1.map(|k| positive("k1", k)).transpose()?;
        let k2 = self.k2.map(|k| positive("k2", k)).transpose()?;
        non_negative("bound_a", self.bound_a)?;
        non_negative("bound_b", self.bound_b)?;
        if self.bound_b >= 1.0 {
            return Err(ParamError::new(
                "bound_b",
                "must be < 1 (Assumption A1: β < b̄)",
                self.bound_b,
            ));
        }
        let a = d.model.coeffs.as_array();
        let den = 1.0 - self.bound_b;
        let l = &d.model.load;
        let p = &d.model.params;
        Ok(Sta {
            model: d.model,
            surface: d.surface,
            k1,
            k2,
            c_x: a.map(|ai| (self.bound_a + self.bound_b) * ai.abs() / den),
            load: [
                (l.amplitude * l.wavenumber).abs() / den,
                l.wavenumber.abs(),
                p.d_per_torque(),
                1.0 / p.jt,
            ],
            b_floor: 1e-3 * d.model.b_at_rest(),
        })
    }
}

impl<T: Real> Controller<T> for Sta<T> {
    /// (∫e, v): the error integral of σ (rad·s) and the STA's v (rad/s³).
    type State = [T; 2];
    type Parts = StaParts<T>;

    fn initial_state(&self) -> [T; 2] {
        [T::ZERO; 2]
    }

    #[inline]
    fn law(&self, m: &Measurement<T>, s: &[T; 2], ds: &mut [T; 2]) -> Output<StaParts<T>, T> {
        let x = &m.x;
        let st = self.surface.evaluate(x, &m.z, s[0]);
        let a = self.model.coeffs.as_array();
        let n = self.surface.equivalent_numerator(&a, x, &m.z);
        let c = self.c_bound(&m.z);
        let k1 = self.k1.unwrap_or(T::of(1.5) * sqrt(c));
        let k2 = self.k2.unwrap_or(T::of(1.1) * c);
        let sg = sgn(st.sigma);
        let cont = k1 * sqrt(st.sigma.abs()) * sg;
        let bu = n + cont - s[1];
        let (b_bar, clamped) = self.model.gain_for(x, bu, self.b_floor);
        ds[0] = st.e;
        ds[1] = -k2 * sg;
        Output {
            u: bu / b_bar,
            flags: if clamped {
                flags::VALVE_ROOT_CLAMPED
            } else {
                0
            },
            parts: StaParts {
                sigma: st.sigma,
                u_eq: n / b_bar,
                u_sta: cont / b_bar,
                u_v: -s[1] / b_bar,
                v: s[1],
                c,
                b_bar,
                e: st.e,
            },
        }
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;
    use crate::servo::{Load, ServoParams};

    fn design(load: Load) -> Design {
        Design {
            model: NominalModel::new(ServoParams::paper(), load),
            surface: SwitchingSurface::paper(),
            dt: 0.01,
        }
    }

    fn close(a: f64, b: f64, tol: f64) {
        assert!((a - b).abs() <= tol, "{a} vs {b}");
    }

    /// One evaluation by hand, gains given (k1 = 2, k2 = 3), no load, at
    /// rest with z = (0, 0.5, 0, 0), ∫e = 0, v = 0.2:
    /// σ = 90·0.5 = 45; N = p2·θ̇d = 2600·0.5 = 1300 (the VSC's hand case);
    /// k1·√45·sgn σ = 2·6.7082039 = 13.4164079;
    /// b̄u = 1300 + 13.4164079 − 0.2 = 1313.2164079; b̄ = b(0, +) =
    /// 17911.75 → u = 0.0733159; ∫e' = e = 0, v̇ = −3.
    #[test]
    fn law_by_hand() {
        let c = StaConfig {
            k1: Some(2.0),
            k2: Some(3.0),
            ..StaConfig::default()
        }
        .build(&design(Load::none()))
        .unwrap();
        let m = Measurement {
            t: 0.0,
            x: [0.0; 3],
            z: [0.0, 0.5, 0.0, 0.0],
        };
        let mut ds = [0.0; 2];
        let o = c.law(&m, &[0.0, 0.2], &mut ds);
        close(o.sigma, 45.0, 1e-12);
        close(o.u, 0.0733159, 1e-7);
        close(o.u_eq, 0.0725780, 1e-7);
        close(o.u_sta, 13.4164079 / 17911.75, 1e-8);
        close(o.u_v, -0.2 / 17911.75, 1e-9);
        close(o.u_eq + o.u_sta + o.u_v, o.u, 1e-15);
        assert_eq!(ds, [0.0, -3.0]);
        // σ < 0 flips the continuous term and v̇.
        let m2 = Measurement {
            z: [0.0, -0.5, 0.0, 0.0],
            ..m
        };
        let o2 = c.law(&m2, &[0.0, 0.0], &mut ds);
        close(o2.u, -1313.4164079 / 17911.75, 2e-6);
        assert_eq!(ds[1], 3.0);
    }

    /// The default gains by hand, no load, bound_a = 1, bound_b = 0.5, with
    /// ż = (θ̇d, θ̈d, θ⃛d) = (0.5, 2, 10) at rest: Σ ā_i|ż_{i+1}| =
    /// 0.19991 + 26000.5422 + 1699.8043 = 27700.5464;
    /// C = (1 + 0.5)·27700.5464/0.5 = 83101.639; k2 = 1.1·C = 91411.80;
    /// k1 = 1.5·√C = 1.5·288.2736 = 432.410.
    /// σ = ë + p1ė = 2 + 90·0.5 = 47 > 0 → v̇ = −k2.
    #[test]
    fn default_gains_by_hand() {
        let c = StaConfig::default().build(&design(Load::none())).unwrap();
        let m = Measurement {
            t: 0.0,
            x: [0.0; 3],
            z: [0.0, 0.5, 2.0, 10.0],
        };
        let mut ds = [0.0; 2];
        let o = c.law(&m, &[0.0, 0.0], &mut ds);
        close(o.c, 83101.639, 1e-3);
        close(ds[1], -91411.80, 0.01);
        close(o.sigma, 47.0, 1e-12);
        close(o.u_sta * o.b_bar, 432.410 * 47f64.sqrt(), 0.01);
    }

    /// The load's share D(z) by hand for Tl = 2 sin 4θ at (θ̇d, θ̈d) = (0.5, 2):
    /// |A·k| = 8; c_T = 4βe·Kce/(Vt·Jt) = 4·344.875e6·2.376e-12/(1.639e-4·
    /// 5.652e-2) = 3.27776e-3/9.26363e-6 = 353.8238;
    /// D = 8·(353.8238·0.5 + (4·0.25 + 2)/0.05652) = 8·(176.9119 + 53.0786)
    /// = 1839.924, over 1 − 0.5: 3679.847 more than the unloaded C.
    #[test]
    fn load_share_of_c_by_hand() {
        let z = [0.0, 0.5, 2.0, 10.0];
        let loaded = StaConfig::default().build(&design(Load::paper())).unwrap();
        let bare = StaConfig::default().build(&design(Load::none())).unwrap();
        close(loaded.c_bound(&z) - bare.c_bound(&z), 3679.847, 2e-3);
    }

    #[test]
    fn bad_parameters_are_named() {
        let d = design(Load::paper());
        let bad = |c: StaConfig| c.build(&d).unwrap_err().name;
        for (cfg, name) in [
            (
                StaConfig {
                    k1: Some(0.0),
                    ..StaConfig::default()
                },
                "k1",
            ),
            (
                StaConfig {
                    k2: Some(f64::INFINITY),
                    ..StaConfig::default()
                },
                "k2",
            ),
            (
                StaConfig {
                    bound_b: 1.0,
                    ..StaConfig::default()
                },
                "bound_b",
            ),
            (
                StaConfig {
                    bound_a: -1.0,
                    ..StaConfig::default()
                },
                "bound_a",
            ),
        ] {
            assert_eq!(bad(cfg), name);
        }
    }
}
