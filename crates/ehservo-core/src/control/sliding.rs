//! What the paper's two sliding-mode laws share: their parts as signals,
//! and their `[controller]` table.
//!
//! The traditional VSC of Theorem 1 ([`super::vsc`]) and the NNBVSC of
//! Theorem 3 ([`super::nnvsc`]) both split `u = u_eq + u_sw` on the
//! switching surface σ of (10), so they log the same parts
//! ([`SlidingParts`]; the VSC's network terms are 0). Their parameters are
//! one table ([`SlidingConfig`]): a scenario or a study can switch
//! `controller.kind` among `vsc`, `vsc-sat` and `nnvsc` and keep its keys,
//! and every key is validated whichever law reads it.

use super::{Config, Design, Output, Signal, Signals, Truth, Tunable};
use crate::control::nnvsc::{MuRule, NnVsc, NnVscParams};
use crate::control::vsc::{Switching, Vsc, VscParams};
use crate::error::{non_negative, positive, ParamError};
use crate::math::Real;
use crate::rbf::Rbf;

/// The parts of a sliding-mode law at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SlidingParts<T = f64> {
    /// Equivalent control (12) or (24) (V).
    pub u_eq: T,
    /// Switching control (13) or (25) (V).
    pub u_sw: T,
    /// Tracking error e = θd − x1 (rad).
    pub e: T,
    /// Switching function σ of (10) (rad/s²).
    pub sigma: T,
    /// Dead-zone switching function σΔ of (27) (σ itself for the VSC).
    pub sigma_delta: T,
    /// The network's estimate WᵀΦ (rad/s³); 0 for the VSC.
    pub wphi: T,
    /// The lumped uncertainty of (19), Σ Δa_i x_i − Δb·u_eq + d − ξ
    /// (rad/s³): a diagnostic filled by [`super::Controller::annotate`].
    pub uncertainty: T,
    /// ‖W‖ (0 without a network; filled by [`super::Controller::annotate`]).
    pub w_norm: T,
    /// The paper's w_1, the first Gaussian's weight `W[1]`.
    pub w_1: T,
    /// The paper's w_128, θ̈d's weight `W[128]`.
    pub w_128: T,
    /// Boundary layer: μ(t) (NNBVSC, SPEC §5) or the constant μ (VSC-sat).
    pub mu: T,
    /// ‖E‖.
    pub norm_e: T,
    /// Nominal gain b̄(t) used by the law (s⁻³V⁻¹).
    pub b_bar: T,
    /// ‖Φ‖ (0 for the VSC).
    pub phi_norm: T,
    /// ξ = ᾱ·EᵀĖ·sgn(σ)/‖E‖ of (19) (rad/s³); 0 for the VSC.
    pub xi: T,
    /// Switching gain: k of (14) for the VSC, γ2 of (34) for the NNBVSC.
    pub gain: T,
}

impl<T: Real> Signals for SlidingParts<T> {
    const SIGNALS: &'static [Signal] = &[
        Signal::new("u_eq", "u_eq_V", "V", "equivalent control (12)/(24)"),
        Signal::new("u_sw", "u_sw_V", "V", "switching control (13)/(25)"),
        Signal::new(
            "sigma",
            "sigma_rad_s2",
            "rad/s²",
            "switching function σ (10)",
        ),
        Signal::new(
            "sigma_delta",
            "sigma_delta_rad_s2",
            "rad/s²",
            "dead-zone switching function σΔ (27)",
        ),
        Signal::new("wphi", "wphi_rad_s3", "rad/s³", "network estimate WᵀΦ"),
        Signal::new(
            "uncertainty",
            "uncertainty_rad_s3",
            "rad/s³",
            "lumped uncertainty of (19): Σ Δa_i x_i − Δb·u_eq + d − ξ",
        ),
        Signal::new("w_norm", "w_norm", "", "‖W‖"),
        Signal::new(
            "w_1",
            "w_1",
            "",
            "the paper's w_1 (first Gaussian's weight)",
        ),
        Signal::new("w_128", "w_128", "", "the paper's w_128 (θ̈d's weight)"),
        Signal::new("mu", "mu_rad_s2", "rad/s²", "boundary layer μ"),
        Signal::new("norm_e", "norm_E", "rad", "‖E‖ of (16)"),
        Signal::new(
            "b_bar",
            "b_bar_V_s3",
            "1/(V·s³)",
            "nominal gain b̄(t) of (9)",
        ),
        Signal::new("e", "", "rad", "tracking error θd − x1"),
        Signal::new("phi_norm", "", "", "‖Φ‖ of (20)"),
        Signal::new("xi", "", "rad/s³", "ξ of (19)"),
        Signal::new("gain", "", "", "switching gain: k (14) or γ2 (34)"),
    ];

    fn write(&self, out: &mut [f64]) {
        let v = [
            self.u_eq,
            self.u_sw,
            self.sigma,
            self.sigma_delta,
            self.wphi,
            self.uncertainty,
            self.w_norm,
            self.w_1,
            self.w_128,
            self.mu,
            self.norm_e,
            self.b_bar,
            self.e,
            self.phi_norm,
            self.xi,
            self.gain,
        ];
        for (o, v) in out.iter_mut().zip(v) {
            *o = v.to_f64();
        }
    }

    /// The inverse of [`SlidingParts::write`] (the lumped uncertainty
    /// needs the true plant: a PIL host fills it from a board's parts).
    fn rebuild<F: Real>(v: &[F]) -> Option<Self> {
        if v.len() < Self::SIGNALS.len() {
            return None;
        }
        let g = |i: usize| T::of(v[i].to_f64());
        // The order of `write` (held by ehservo-wire's rebuild_inverts_write).
        Some(SlidingParts {
            u_eq: g(0),
            u_sw: g(1),
            sigma: g(2),
            sigma_delta: g(3),
            wphi: g(4),
            uncertainty: g(5),
            w_norm: g(6),
            w_1: g(7),
            w_128: g(8),
            mu: g(9),
            norm_e: g(10),
            b_bar: g(11),
            e: g(12),
            phi_norm: g(13),
            xi: g(14),
            gain: g(15),
        })
    }
}

impl<T: Real> SlidingParts<T> {
    /// The diagnostics of [`super::Controller::annotate`]: the lumped uncertainty
    /// of (19) (less ξ) and the weight statistics of `w` (empty for the VSC).
    #[inline]
    pub fn annotate(out: &mut Output<SlidingParts<T>, T>, w: &[T], truth: &dyn Truth) {
        Self::annotate_but_norm(out, w, truth);
        out.parts.w_norm = crate::math::norm(w);
    }

    /// [`SlidingParts::annotate`] without ‖W‖ (`w_norm` is left as it is).
    #[inline]
    pub fn annotate_but_norm(out: &mut Output<SlidingParts<T>, T>, w: &[T], truth: &dyn Truth) {
        let p = &mut out.parts;
        let lumped = truth.lumped_uncertainty(out.u.to_f64(), p.u_eq.to_f64(), p.b_bar.to_f64());
        p.uncertainty = T::of(lumped) - p.xi;
        p.w_1 = w.get(1).copied().unwrap_or(T::ZERO);
        p.w_128 = w.get(128).copied().unwrap_or(T::ZERO);
    }
}

// `controller.mu_rule`'s spellings.
#[cfg(feature = "serde")]
serde_by_name!(
    MuRule,
    "one of `remark7`, `literal-33`, `zero`",
    ["remark7", "literal-33", "zero"]
);

/// `[controller.rbf]`: the network's grid, width and normalising scales.
///
/// ```
/// use ehservo_core::control::sliding::RbfConfig;
/// use ehservo_core::rbf::Rbf;
///
/// // The defaults are the paper's network.
/// assert_eq!(RbfConfig::default().build()?, Rbf::paper());
/// let err = RbfConfig { width: 0.0, ..RbfConfig::default() }.build().unwrap_err();
/// assert_eq!(err.name, "rbf.width");
/// # Ok::<(), ehservo_core::error::ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct RbfConfig {
    /// δ. Default 0.5.
    pub width: f64,
    /// Grid levels per axis. Default [−1, −0.5, 0, 0.5, 1].
    pub levels: [f64; 5],
    /// Normalising scales of x1, x2, x3 (rad, rad/s, rad/s²).
    /// Default (6.25°, 12.5π °/s, 25π² °/s²) in radians.
    pub scale: [f64; 3],
}

impl Default for RbfConfig {
    fn default() -> Self {
        let r = Rbf::paper();
        Self {
            width: r.width(),
            levels: r.levels(),
            scale: r.scale(),
        }
    }
}

impl RbfConfig {
    /// The network (errors name `rbf.width`, `rbf.levels`, `rbf.scale`).
    pub fn build(&self) -> Result<Rbf, ParamError> {
        Rbf::try_new(self.levels, self.width, self.scale)
    }
}

/// The `[controller]` table of the paper's laws (`vsc`, `vsc-sat`,
/// `nnvsc`), every key at the paper's Fig. 2 value by default.
///
/// One table for the three kinds: a study switches `controller.kind`
/// among `"vsc"`, `"vsc-sat"` and `"nnvsc"` and keeps its keys.
///
/// ```
/// # use ehservo_core::prelude::*;
/// # let design = Design {
/// #     model: NominalModel::new(ServoParams::paper(), Load::paper()),
/// #     surface: SwitchingSurface::paper(),
/// #     dt: 0.01,
/// # };
/// let table = SlidingConfig { gamma1: 200.0, ..SlidingConfig::default() };
/// assert_eq!(NnVscConfig(table).build(&design)?.params().gamma1, 200.0);
/// assert_eq!(VscConfig(table).build(&design)?.params().bound_b, 0.5);
/// // Every key is checked, whichever law reads it: `mu` is `vsc-sat`'s.
/// let bad = SlidingConfig { mu: 0.0, ..SlidingConfig::default() };
/// assert_eq!(NnVscConfig(bad).build(&design).unwrap_err().name, "mu");
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct SlidingConfig {
    /// Bound the controller knows on Δa_i: α_i = bound_a·|ā_i| (VSC). Default 1.
    pub bound_a: f64,
    /// Bound the controller knows on Δb: β = bound_b·|b̄|. Default 0.5.
    pub bound_b: f64,
    /// γ1. Default 100.
    pub gamma1: f64,
    /// η. Default 0.25.
    pub eta: f64,
    /// α. Default 250.
    pub alpha: f64,
    /// ᾱ. Default 5.
    pub alpha_bar: f64,
    /// Wmax. Default 4.
    pub w_max: f64,
    /// ε0. Default 0.1.
    pub eps0: f64,
    /// ε1. Default 0.1.
    pub eps1: f64,
    /// ε2. Default 0.01.
    pub eps2: f64,
    /// h (H = h·I). Default 1.
    pub h: f64,
    /// Boundary-layer width of `vsc-sat` (rad/s²). Default 1.
    pub mu: f64,
    /// NNBVSC boundary-layer rule: `"remark7"` (default, SPEC §5),
    /// `"literal-33"` (the printed, negative (33)) or `"zero"`.
    pub mu_rule: MuRule,
    /// `[controller.rbf]`.
    pub rbf: RbfConfig,
}

impl Default for SlidingConfig {
    fn default() -> Self {
        let p = NnVscParams::paper();
        Self {
            bound_a: 1.0,
            bound_b: p.bound_b,
            gamma1: p.gamma1,
            eta: p.eta,
            alpha: p.alpha,
            alpha_bar: p.alpha_bar,
            w_max: p.w_max,
            eps0: p.eps0,
            eps1: p.eps1,
            eps2: p.eps2,
            h: p.h,
            mu: 1.0,
            mu_rule: MuRule::Remark7,
            rbf: RbfConfig::default(),
        }
    }
}

impl SlidingConfig {
    /// The NNBVSC gains.
    pub fn nnvsc(&self) -> NnVscParams {
        NnVscParams {
            gamma1: self.gamma1,
            eta: self.eta,
            alpha: self.alpha,
            alpha_bar: self.alpha_bar,
            w_max: self.w_max,
            eps0: self.eps0,
            eps1: self.eps1,
            eps2: self.eps2,
            h: self.h,
            bound_b: self.bound_b,
            mu_rule: self.mu_rule,
        }
    }

    /// The VSC gains, with sgn(σ) or sat(σ/μ).
    pub fn vsc(&self, saturation: bool) -> VscParams {
        VscParams {
            bound_a: self.bound_a,
            bound_b: self.bound_b,
            switching: if saturation {
                Switching::Saturation { mu: self.mu }
            } else {
                Switching::Sign
            },
        }
    }

    /// Checks every key, whichever law reads it.
    pub fn validate(&self) -> Result<Rbf, ParamError> {
        non_negative("bound_a", self.bound_a)?;
        self.nnvsc().validate()?;
        positive("mu", self.mu)?;
        self.rbf.build()
    }
}

/// `kind = "nnvsc"`: the NNBVSC of Theorem 3.
///
/// ```
/// # use ehservo_core::prelude::*;
/// # let design = Design {
/// #     model: NominalModel::new(ServoParams::paper(), Load::paper()),
/// #     surface: SwitchingSurface::paper(),
/// #     dt: 0.01,
/// # };
/// let nn = NnVscConfig::default().build(&design)?;
/// // At rest (x = 0, so Pl = 0 and d = 0), z = (θd, θ̇d, θ̈d, θ⃛d) = (0, 0.5, 0, 0):
/// // e = ë = 0, ė = 0.5, so σ = p1·ė = 90·0.5 = 45 and
/// // N = p2·θ̇d = 2600·0.5 = 1300 (the numerator of (12)).
/// let m = Measurement { t: 0.0, x: [0.0; 3], z: [0.0, 0.5, 0.0, 0.0] };
/// let (s, mut ds) = (nn.initial_state(), nn.initial_state());
/// let out = nn.law(&m, &s, &mut ds);
/// assert!((out.sigma - 45.0).abs() < 1e-12);
/// // W = 0: u_eq = N/b̄ (24), no network term.
/// assert!((out.u_eq * out.b_bar - 1300.0).abs() < 1e-9);
/// // Dead zone (27): Δ = ᾱ·‖E‖ = 5·0.5, so σΔ = 45 − 2.5 = 42.5.
/// assert!((out.sigma_delta - 42.5).abs() < 1e-12);
/// // (26) with W = 0, h = 1: Ẇ = σΔ·Φ, and Φ's first entry is the bias 1.
/// assert!((ds.w[0] - 42.5).abs() < 1e-12);
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(transparent)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct NnVscConfig(pub SlidingConfig);

/// `kind = "vsc"`: the traditional VSC of Theorem 1, sgn(σ).
///
/// ```
/// # use ehservo_core::prelude::*;
/// # let design = Design {
/// #     model: NominalModel::new(ServoParams::paper(), Load::paper()),
/// #     surface: SwitchingSurface::paper(),
/// #     dt: 0.01,
/// # };
/// let vsc = VscConfig::default().build(&design)?;
/// // At rest (x = 0, so Pl = 0 and d = 0), z = (θd, θ̇d, θ̈d, θ⃛d) = (0, 0.5, 0, 0):
/// // e = ë = 0, ė = 0.5, so σ = p1·ė = 90·0.5 = 45 and
/// // N = p2·θ̇d = 2600·0.5 = 1300 (the numerator of (12)).
/// let m = Measurement { t: 0.0, x: [0.0; 3], z: [0.0, 0.5, 0.0, 0.0] };
/// let out = vsc.law(&m, &[0.0], &mut [0.0]);
/// // (14) with x = 0 and γ = |d| = 0: k·b̄ = bound_b·|N|/(1 − bound_b)
/// // = 0.5·1300/0.5 = 1300, so b̄·u = N + k·b̄·sgn σ = 2600.
/// assert!((out.u * out.b_bar - 2600.0).abs() < 1e-9);
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(transparent)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct VscConfig(pub SlidingConfig);

/// `kind = "vsc-sat"`: Theorem 1 with sat(σ/μ) (Remark 2).
///
/// ```
/// # use ehservo_core::prelude::*;
/// # let design = Design {
/// #     model: NominalModel::new(ServoParams::paper(), Load::paper()),
/// #     surface: SwitchingSurface::paper(),
/// #     dt: 0.01,
/// # };
/// let table = SlidingConfig { mu: 90.0, ..SlidingConfig::default() };
/// let vsc = VscSatConfig(table).build(&design)?;
/// // At rest (x = 0, so Pl = 0 and d = 0), z = (θd, θ̇d, θ̈d, θ⃛d) = (0, 0.5, 0, 0):
/// // e = ë = 0, ė = 0.5, so σ = p1·ė = 90·0.5 = 45 and
/// // N = p2·θ̇d = 2600·0.5 = 1300 (the numerator of (12)).
/// let m = Measurement { t: 0.0, x: [0.0; 3], z: [0.0, 0.5, 0.0, 0.0] };
/// let out = vsc.law(&m, &[0.0], &mut [0.0]);
/// // As `"vsc"` (k·b̄ = 1300) but with sat(σ/μ) = sat(45/90) = 0.5:
/// // b̄·u = 1300 + 0.5·1300 = 1950.
/// assert!((out.u * out.b_bar - 1950.0).abs() < 1e-9);
/// # Ok::<(), ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(transparent)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct VscSatConfig(pub SlidingConfig);

impl Config for NnVscConfig {
    const KIND: &'static str = "nnvsc";
    const USES_SURFACE: bool = true;
    /// The paper's three main gains: the linear switching gain γ1, the
    /// leakage η and the learning rate α (ᾱ = 5 stays below it).
    const TUNABLE: &'static [Tunable] = &[
        Tunable::log("gamma1", 1.0, 1e4),
        Tunable::linear("eta", 0.0, 2.0),
        Tunable::log("alpha", 10.0, 1e4),
    ];
    type Controller = NnVsc;
    type Law<F: Real> = NnVsc<F>;
    fn build_in<F: Real>(&self, d: &Design) -> Result<NnVsc<F>, ParamError> {
        self.build(d)?.cast()
    }
    fn build(&self, d: &Design) -> Result<NnVsc, ParamError> {
        let rbf = self.0.validate()?;
        NnVsc::try_new(d.model, d.surface, self.0.nnvsc(), rbf)
    }
}

impl Config for VscConfig {
    const KIND: &'static str = "vsc";
    const USES_SURFACE: bool = true;
    /// The switching gain's bounds (what the law is told).
    const TUNABLE: &'static [Tunable] = &[
        Tunable::linear("bound_a", 0.0, 3.0),
        Tunable::linear("bound_b", 0.0, 0.9),
    ];
    type Controller = Vsc;
    type Law<F: Real> = Vsc<F>;
    fn build_in<F: Real>(&self, d: &Design) -> Result<Vsc<F>, ParamError> {
        self.build(d)?.cast()
    }
    fn build(&self, d: &Design) -> Result<Vsc, ParamError> {
        self.0.validate()?;
        Vsc::try_new(d.model, d.surface, self.0.vsc(false))
    }
}

impl Config for VscSatConfig {
    const KIND: &'static str = "vsc-sat";
    const USES_SURFACE: bool = true;
    /// The switching gain's bounds (what the law is told) and the
    /// boundary layer.
    const TUNABLE: &'static [Tunable] = &[
        Tunable::linear("bound_a", 0.0, 3.0),
        Tunable::linear("bound_b", 0.0, 0.9),
        Tunable::log("mu", 1e-2, 1e3),
    ];
    type Controller = Vsc;
    type Law<F: Real> = Vsc<F>;
    fn build_in<F: Real>(&self, d: &Design) -> Result<Vsc<F>, ParamError> {
        self.build(d)?.cast()
    }
    fn build(&self, d: &Design) -> Result<Vsc, ParamError> {
        self.0.validate()?;
        Vsc::try_new(d.model, d.surface, self.0.vsc(true))
    }
}
