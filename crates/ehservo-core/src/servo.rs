//! The electrohydraulic servo: physical parameters and the quantities the
//! paper derives from them.
//!
//! Servovalve and motor, eqs. (1)–(6), in SI units:
//!
//! ```text
//! Kg = Cd·Ag·sqrt((Ps − sgn(xv)·Pl)/ρ)                 (2)
//! (Vt/4βe)·Ṗl = Kg·xv − Dm·θ̇ − Kce·Pl                  (5)
//! Jt·θ̈ = Pl·Dm − Bm·θ̇ − G·θ − Tl(θ, θ̇)                 (4)
//! xv = Kv·u                                             (6)
//! ```
//!
//! Differentiating (4) once and substituting (5) gives the third-order model
//! (8) in x = (θ, θ̇, θ̈): `ẋ3 = −a1·x1 − a2·x2 − a3·x3 + b·u − d` with (9):
//!
//! ```text
//! a1 = 4βe·Kce·G/(Vt·Jt)
//! a2 = G/Jt + 4βe·Dm²/(Vt·Jt) + 4βe·Kce·Bm/(Vt·Jt)
//! a3 = Bm/Jt + 4βe·Kce/Vt
//! b  = 4βe·Dm·Kg·Kv/(Vt·Jt)
//! d  = 4βe·Kce·Tl/(Vt·Jt) + Ṫl/Jt
//! ```
//!
//! With the paper's Section IV numbers these are ā1 = 0.39982 s⁻³,
//! ā2 = 13000.2711 s⁻², ā3 = 169.98043 s⁻¹ and b ≈ 17 912 s⁻³V⁻¹ at Pl = 0.
//! `Pl`, needed by `Kg`, follows from (4): `Pl = (Jt·x3 + Bm·x2 + G·x1 + Tl)/Dm`.
//!
//! **Valve root.** When `Ps − sgn(xv)·Pl < 0` the valve cannot deliver flow
//! in that direction: the argument of the root is clamped at 0 (so `Kg = 0`,
//! never NaN) and the clamp is reported to the caller.

use crate::error::{non_negative, positive, ParamError};
use crate::math::{cos, exp, sgn, sin, sqrt, tanh, Real};

/// Physical parameters of the servo (eqs. 1–6), SI units throughout.
///
/// ```
/// use ehservo_core::servo::ServoParams;
///
/// let p = ServoParams::paper();
/// assert!(p.validate().is_ok());
/// // Section IV's supply pressure, 13.795 MPa, in Pa.
/// assert!((p.ps - 13.795e6).abs() < 1e-6);
/// // A volume of zero is no servo: the error names the parameter.
/// let bad = ServoParams { vt: 0.0, ..p };
/// assert_eq!(bad.validate().unwrap_err().name, "Vt");
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct ServoParams<T: Real = f64> {
    /// Supply pressure Ps (Pa).
    #[cfg_attr(feature = "serde", serde(rename = "Ps"))]
    pub ps: T,
    /// Effective bulk modulus βe (Pa).
    pub beta_e: T,
    /// Total compressed volume Vt (m³).
    #[cfg_attr(feature = "serde", serde(rename = "Vt"))]
    pub vt: T,
    /// Total flow-pressure coefficient Kce = Kc + Ctm (m³/(s·Pa)).
    #[cfg_attr(feature = "serde", serde(rename = "Kce"))]
    pub kce: T,
    /// Motor volumetric displacement Dm (m³/rad).
    #[cfg_attr(feature = "serde", serde(rename = "Dm"))]
    pub dm: T,
    /// Total inertia of motor and load Jt (N·m·s²).
    #[cfg_attr(feature = "serde", serde(rename = "Jt"))]
    pub jt: T,
    /// Viscous damping of the load Bm (N·m·s).
    #[cfg_attr(feature = "serde", serde(rename = "Bm"))]
    pub bm: T,
    /// Servovalve gain Kv (m/V).
    #[cfg_attr(feature = "serde", serde(rename = "Kv"))]
    pub kv: T,
    /// Torsional spring gradient of the load G (N·m/rad).
    #[cfg_attr(feature = "serde", serde(rename = "G"))]
    pub g: T,
    /// Fluid mass density ρ (kg/m³).
    pub rho: T,
    /// Discharge coefficient Cd (–).
    #[cfg_attr(feature = "serde", serde(rename = "Cd"))]
    pub cd: T,
    /// Area gradient Ag (m).
    #[cfg_attr(feature = "serde", serde(rename = "Ag"))]
    pub ag: T,
}

/// The paper's parameters.
impl<T: Real> Default for ServoParams<T> {
    fn default() -> Self {
        ServoParams::paper().cast()
    }
}

impl ServoParams<f64> {
    /// The paper's Section IV parameters, converted to SI (MPa → Pa; the
    /// printed Kce = 2.376e-6 m³/(s·MPa) is 2.376e-12 m³/(s·Pa)).
    pub const fn paper() -> Self {
        Self {
            ps: 13.795e6,
            beta_e: 344.875e6,
            vt: 1.639e-4,
            kce: 2.376e-12,
            dm: 8.195e-6,
            jt: 5.652e-2,
            bm: 8.477,
            kv: 0.508,
            g: 1.13e-3,
            rho: 850.0,
            cd: 0.67,
            ag: 3.385e-7,
        }
    }
}

impl<T: Real> ServoParams<T> {
    /// The same parameters in another float type.
    pub fn cast<U: Real>(&self) -> ServoParams<U> {
        let c = |v: T| U::of(v.to_f64());
        ServoParams {
            ps: c(self.ps),
            beta_e: c(self.beta_e),
            vt: c(self.vt),
            kce: c(self.kce),
            dm: c(self.dm),
            jt: c(self.jt),
            bm: c(self.bm),
            kv: c(self.kv),
            g: c(self.g),
            rho: c(self.rho),
            cd: c(self.cd),
            ag: c(self.ag),
        }
    }

    /// Checks that every parameter is physical: finite, and positive (the
    /// leakage `Kce`, damping `Bm` and spring `G` may be zero).
    pub fn validate(&self) -> Result<(), ParamError> {
        positive("Ps", self.ps)?;
        positive("beta_e", self.beta_e)?;
        positive("Vt", self.vt)?;
        non_negative("Kce", self.kce)?;
        positive("Dm", self.dm)?;
        positive("Jt", self.jt)?;
        non_negative("Bm", self.bm)?;
        positive("Kv", self.kv)?;
        non_negative("G", self.g)?;
        positive("rho", self.rho)?;
        positive("Cd", self.cd)?;
        positive("Ag", self.ag)?;
        // Each parameter finite is not enough: the model's constants are
        // products and quotients of them (Bm = 1e308 or Jt = 5e-324 made
        // a2 = ∞ and the open-loop poles NaN). The most extreme parameter
        // (farthest from 1 by ratio) is named.
        let c = self.coefficients();
        let (kg, _) = self.flow_gain(T::ZERO, T::ONE);
        let derived = [
            c.a1,
            c.a2,
            c.a3,
            self.b_per_kg() * kg,
            self.d_per_torque(),
            T::ONE / self.jt,
        ];
        if derived.iter().any(|v| !v.is_finite()) {
            let params = [
                ("Ps", self.ps),
                ("beta_e", self.beta_e),
                ("Vt", self.vt),
                ("Kce", self.kce),
                ("Dm", self.dm),
                ("Jt", self.jt),
                ("Bm", self.bm),
                ("Kv", self.kv),
                ("G", self.g),
                ("rho", self.rho),
                ("Cd", self.cd),
                ("Ag", self.ag),
            ];
            let far = |v: f64| if v >= 1.0 { v } else { 1.0 / v };
            let (name, v) = params
                .iter()
                .map(|(n, v)| (*n, v.to_f64()))
                .filter(|(_, v)| *v > 0.0)
                .max_by(|a, b| far(a.1).total_cmp(&far(b.1)))
                .unwrap_or(("Jt", self.jt.to_f64()));
            return Err(ParamError::new(
                name,
                "is so far from a physical servo that the model's constants (a1, a2, a3, b̄, d) overflow",
                v,
            ));
        }
        Ok(())
    }

    /// The coefficients a1, a2, a3 of (9).
    ///
    /// ```
    /// use ehservo_core::servo::ServoParams;
    ///
    /// let p = ServoParams::paper();
    /// let c = p.coefficients();
    /// // (9) written out, with k = 4βe/(Vt·Jt).
    /// let k = 4.0 * p.beta_e / (p.vt * p.jt);
    /// let a1 = k * p.kce * p.g;
    /// let a2 = p.g / p.jt + k * p.dm * p.dm + k * p.kce * p.bm;
    /// let a3 = p.bm / p.jt + 4.0 * p.beta_e * p.kce / p.vt;
    /// for (got, want) in c.as_array().into_iter().zip([a1, a2, a3]) {
    ///     assert!((got - want).abs() <= 1e-12 * want);
    /// }
    /// // And the values the paper prints in Section IV.
    /// assert!((c.a1 - 0.39982).abs() < 1e-5);
    /// assert!((c.a2 - 13000.2711).abs() < 1e-3);
    /// assert!((c.a3 - 169.98043).abs() < 1e-4);
    /// ```
    pub fn coefficients(&self) -> Coefficients<T> {
        let four = T::of(4.0);
        let k = four * self.beta_e / (self.vt * self.jt);
        Coefficients {
            a1: k * self.kce * self.g,
            a2: self.g / self.jt + k * self.dm * self.dm + k * self.kce * self.bm,
            a3: self.bm / self.jt + four * self.beta_e * self.kce / self.vt,
        }
    }

    /// Servovalve flow gain Kg of (2) for load pressure `pl` and valve
    /// direction `s = sgn(xv)`. Returns `(Kg, clamped)`, `clamped` when the
    /// root's argument was negative and set to 0.
    ///
    /// ```
    /// use ehservo_core::servo::ServoParams;
    ///
    /// let p = ServoParams::paper();
    /// // At Pl = 0, (2) is Cd·Ag·√(Ps/ρ).
    /// let (kg, clamped) = p.flow_gain(0.0, 1.0);
    /// assert!(!clamped);
    /// assert!((kg - p.cd * p.ag * (p.ps / p.rho).sqrt()).abs() <= 1e-15 * kg);
    /// // A load pressure above Ps: no flow in that direction, flagged.
    /// assert_eq!(p.flow_gain(2.0 * p.ps, 1.0), (0.0, true));
    /// ```
    #[inline]
    pub fn flow_gain(&self, pl: T, s: T) -> (T, bool) {
        let arg = self.ps - s * pl;
        if arg >= T::ZERO {
            (self.cd * self.ag * sqrt(arg / self.rho), false)
        } else {
            (T::ZERO, true)
        }
    }

    /// The factor `4βe·Dm·Kv/(Vt·Jt)` with `b = factor · Kg`.
    #[inline]
    pub fn b_per_kg(&self) -> T {
        T::of(4.0) * self.beta_e * self.dm * self.kv / (self.vt * self.jt)
    }

    /// The factor `4βe·Kce/(Vt·Jt)` of `Tl` in `d`.
    #[inline]
    pub fn d_per_torque(&self) -> T {
        T::of(4.0) * self.beta_e * self.kce / (self.vt * self.jt)
    }
}

/// The coefficients of the third-order model (8).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coefficients<T: Real = f64> {
    /// a1 (s⁻³).
    pub a1: T,
    /// a2 (s⁻²).
    pub a2: T,
    /// a3 (s⁻¹).
    pub a3: T,
}

impl<T: Real> Coefficients<T> {
    /// As an array `[a1, a2, a3]`.
    pub fn as_array(&self) -> [T; 3] {
        [self.a1, self.a2, self.a3]
    }
}

/// Coulomb, Stribeck and viscous friction on the motor shaft, one of the
/// load components the paper names (refs. \[6\], \[7\]):
///
/// ```text
/// Tf(v) = tanh(v/v0)·[Tc + (Ts − Tc)·exp(−(v/vs)²)] + Bv·v
/// ```
///
/// `sgn(v)` is regularised as `tanh(v/v0)` with a small velocity `v0`
/// (`smoothing`), because the third-order model needs `Ṫl` and a true sign
/// has an impulse for a derivative.
///
/// ```
/// use ehservo_core::servo::Friction;
///
/// // The defaults: Tc = 0.2, Ts = 0.3 N·m, vs = 0.05, v0 = 0.005 rad/s.
/// let f: Friction = Friction::default();
/// assert!(f.validate().is_ok());
/// // At rest: no torque (tanh 0 = 0).
/// assert_eq!(f.torque(0.0), 0.0);
/// // At 1 rad/s ≫ vs, v0: tanh(200) = 1 and exp(−400) = 0, so Tf = Tc.
/// assert!((f.torque(1.0) - 0.2).abs() < 1e-12);
/// // Odd in v.
/// assert_eq!(f.torque(-1.0), -f.torque(1.0));
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct Friction<T: Real = f64> {
    /// Coulomb level Tc (N·m).
    pub coulomb: T,
    /// Break-away (static) level Ts ≥ Tc (N·m).
    pub stiction: T,
    /// Stribeck velocity vs (rad/s).
    pub stribeck_velocity: T,
    /// Extra viscous coefficient Bv (N·m·s), on top of the plant's Bm.
    pub viscous: T,
    /// Regularisation velocity v0 of the sign (rad/s).
    pub smoothing: T,
}

/// Illustrative values, not the paper's (it has no friction): Tc = 0.2,
/// Ts = 0.3 N·m, vs = 0.05 rad/s, no extra viscous term, v0 = 0.005 rad/s.
impl<T: Real> Default for Friction<T> {
    fn default() -> Self {
        Self {
            coulomb: T::of(0.2),
            stiction: T::of(0.3),
            stribeck_velocity: T::of(0.05),
            viscous: T::ZERO,
            smoothing: T::of(0.005),
        }
    }
}

impl<T: Real> Friction<T> {
    /// The same parameters in another float type.
    pub fn cast<U: Real>(&self) -> Friction<U> {
        let c = |v: T| U::of(v.to_f64());
        Friction {
            coulomb: c(self.coulomb),
            stiction: c(self.stiction),
            stribeck_velocity: c(self.stribeck_velocity),
            viscous: c(self.viscous),
            smoothing: c(self.smoothing),
        }
    }

    /// Checks the friction parameters.
    pub fn validate(&self) -> Result<(), ParamError> {
        non_negative("coulomb", self.coulomb)?;
        non_negative("stiction", self.stiction)?;
        positive("stribeck_velocity", self.stribeck_velocity)?;
        non_negative("viscous", self.viscous)?;
        positive("smoothing", self.smoothing)?;
        Ok(())
    }

    /// Friction torque at shaft speed `v`.
    #[inline]
    pub fn torque(&self, v: T) -> T {
        let r = v / self.stribeck_velocity;
        tanh(v / self.smoothing) * (self.coulomb + (self.stiction - self.coulomb) * exp(-r * r))
            + self.viscous * v
    }

    /// dTf/dv at shaft speed `v` (so that `Ṫf = dTf/dv · θ̈`).
    #[inline]
    pub fn slope(&self, v: T) -> T {
        let th = tanh(v / self.smoothing);
        let r = v / self.stribeck_velocity;
        let g = self.coulomb + (self.stiction - self.coulomb) * exp(-r * r);
        let dg = (self.stiction - self.coulomb)
            * exp(-r * r)
            * (T::of(-2.0) * r / self.stribeck_velocity);
        (T::ONE - th * th) / self.smoothing * g + th * dg + self.viscous
    }
}

/// The load torque `Tl(θ, θ̇) = A·sin(k·θ) [+ friction(θ̇)]` (N·m).
/// The paper's load is `2·sin(4θ)`.
///
/// ```
/// use ehservo_core::servo::Load;
///
/// let load = Load::paper();
/// // 2·sin(4·π/8) = 2·sin(π/2) = 2 N·m.
/// let th = std::f64::consts::PI / 8.0;
/// assert!((load.torque(th, 0.0) - 2.0).abs() < 1e-12);
/// // dTl/dt = A·k·cos(kθ)·θ̇ = 2·4·1·0.5 = 4 N·m/s at θ = 0, θ̇ = 0.5 rad/s.
/// assert!((load.torque_rate(0.0, 0.5, 0.0) - 4.0).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields, default)
)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct Load<T: Real = f64> {
    /// Amplitude A (N·m).
    pub amplitude: T,
    /// Angular wavenumber k (1/rad).
    pub wavenumber: T,
    /// Optional friction torque (`[load.friction]`).
    #[cfg_attr(feature = "serde", serde(skip_serializing_if = "Option::is_none"))]
    pub friction: Option<Friction<T>>,
}

/// The paper's load.
impl<T: Real> Default for Load<T> {
    fn default() -> Self {
        Load::paper().cast()
    }
}

impl Load<f64> {
    /// The paper's `Tl = 2·sin(4θm)` N·m, no friction.
    pub const fn paper() -> Self {
        Self {
            amplitude: 2.0,
            wavenumber: 4.0,
            friction: None,
        }
    }

    /// No load at all.
    pub const fn none() -> Self {
        Self {
            amplitude: 0.0,
            wavenumber: 0.0,
            friction: None,
        }
    }
}

impl<T: Real> Load<T> {
    /// The same load in another float type.
    pub fn cast<U: Real>(&self) -> Load<U> {
        Load {
            amplitude: U::of(self.amplitude.to_f64()),
            wavenumber: U::of(self.wavenumber.to_f64()),
            friction: self.friction.map(|f| f.cast()),
        }
    }

    /// Checks the load parameters.
    pub fn validate(&self) -> Result<(), ParamError> {
        crate::error::finite("amplitude", self.amplitude)?;
        crate::error::finite("wavenumber", self.wavenumber)?;
        if let Some(f) = &self.friction {
            f.validate()?;
        }
        Ok(())
    }

    /// `Tl(θ, θ̇)`.
    #[inline]
    pub fn torque(&self, theta: T, theta_dot: T) -> T {
        let mut t = self.amplitude * sin(self.wavenumber * theta);
        if let Some(f) = &self.friction {
            t += f.torque(theta_dot);
        }
        t
    }

    /// `Ṫl = A·k·cos(kθ)·θ̇ + dTf/dθ̇·θ̈`.
    #[inline]
    pub fn torque_rate(&self, theta: T, theta_dot: T, theta_ddot: T) -> T {
        let mut r = self.amplitude * self.wavenumber * cos(self.wavenumber * theta) * theta_dot;
        if let Some(f) = &self.friction {
            r += f.slope(theta_dot) * theta_ddot;
        }
        r
    }
}

/// What the controller knows of the plant: the nominal parameters, the
/// coefficients ā_i, and the load model. It evaluates the nominal gain
/// `b̄(t)` and load term `d(t)` at a measured state (SPEC §2).
///
/// ```
/// use ehservo_core::servo::{Load, NominalModel, ServoParams};
///
/// let p = ServoParams::paper();
/// let m = NominalModel::try_new(p, Load::paper())?;
/// // b of (9) at Pl = 0, 4βe·Dm·Kv·Cd·Ag·√(Ps/ρ)/(Vt·Jt): the paper's ≈ 17 912.
/// let b0 = 4.0 * p.beta_e * p.dm * p.kv * p.cd * p.ag * (p.ps / p.rho).sqrt() / (p.vt * p.jt);
/// assert!((m.b_at_rest() - b0).abs() <= 1e-12 * b0);
/// assert!((b0 - 17_912.0).abs() < 1.0);
/// // At rest the load term d of (9) vanishes (Tl = 0 and dTl/dt = 0).
/// assert_eq!(m.d(&[0.0; 3]), 0.0);
/// // θ̈ = 100 rad/s² takes Pl = Jt·θ̈/Dm (4): the valve passes less flow
/// // with the load than against it, b₊/b₋ = √((Ps − Pl)/(Ps + Pl)) by (2).
/// let pl = p.jt * 100.0 / p.dm;
/// let (up, _) = m.b(&[0.0, 0.0, 100.0], 1.0);
/// let (down, _) = m.b(&[0.0, 0.0, 100.0], -1.0);
/// assert!((up / down - ((p.ps - pl) / (p.ps + pl)).sqrt()).abs() < 1e-12);
/// # Ok::<(), ehservo_core::error::ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NominalModel<T: Real = f64> {
    /// Physical parameters.
    pub params: ServoParams<T>,
    /// ā1, ā2, ā3.
    pub coeffs: Coefficients<T>,
    /// The load model.
    pub load: Load<T>,
    b_per_kg: T,
    d_per_torque: T,
    /// The valve's load-pressure offset p_off (Pa): `Kg = Cd·Ag·√((Ps −
    /// sgn(xv)·(Pl − p_off))/ρ)`; 0 for the paper's servo (see
    /// [`NominalModel::with_offset`]).
    offset: T,
}

impl<T: Real> NominalModel<T> {
    /// Builds the model (parameters are assumed validated; see
    /// [`NominalModel::try_new`]).
    pub fn new(params: ServoParams<T>, load: Load<T>) -> Self {
        Self {
            params,
            coeffs: params.coefficients(),
            load,
            b_per_kg: params.b_per_kg(),
            d_per_torque: params.d_per_torque(),
            offset: T::ZERO,
        }
    }

    /// The model whose valve sees the load pressure shifted by `offset`
    /// (Pa): `Kg(Pl, s) = Cd·Ag·√((Ps − s·(Pl − offset))/ρ)`, i.e. the
    /// root's constant part is `Ps + offset` for s = +1 and `Ps − offset`
    /// for s = −1. A single-rod cylinder's direction-dependent gain and a
    /// constant load are exactly this (docs/cylinder.md); `offset = 0` is
    /// [`NominalModel::new`].
    pub fn with_offset(params: ServoParams<T>, load: Load<T>, offset: T) -> Self {
        let mut m = Self::new(params, load);
        m.offset = offset;
        m
    }

    /// The valve's load-pressure offset (Pa; 0 for the paper's servo).
    pub fn offset(&self) -> T {
        self.offset
    }

    /// The same model in another float type (its derived factors
    /// recomputed in `U` from the cast parameters).
    pub fn cast<U: Real>(&self) -> NominalModel<U> {
        NominalModel::with_offset(
            self.params.cast(),
            self.load.cast(),
            U::of(self.offset.to_f64()),
        )
    }

    /// Kg of (2) with this model's offset: [`ServoParams::flow_gain`] with
    /// the direction's `Ps + s·p_off`, which for a sign s is exactly
    /// `Ps + p_off`, `Ps − p_off` or `Ps` (a product by ±1 or 0 is exact;
    /// without an offset the same operations on the same values, so the
    /// same bits). Found by arithmetic, not by comparing s twice and
    /// picking one of three stored values at every evaluation.
    #[inline(always)]
    fn flow_gain(&self, pl: T, s: T) -> (T, bool) {
        let p = &self.params;
        let arg = (p.ps + s * self.offset) - s * pl;
        if arg >= T::ZERO {
            (p.cd * p.ag * sqrt(arg / p.rho), false)
        } else {
            (T::ZERO, true)
        }
    }

    /// Builds the model after validating parameters and load.
    pub fn try_new(params: ServoParams<T>, load: Load<T>) -> Result<Self, ParamError> {
        params.validate()?;
        load.validate()?;
        Ok(Self::new(params, load))
    }

    /// Load pressure from the torque balance (4):
    /// `Pl = (Jt·x3 + Bm·x2 + G·x1 + Tl)/Dm`.
    #[inline]
    pub fn load_pressure(&self, x: &[T; 3]) -> T {
        let p = &self.params;
        (p.jt * x[2] + p.bm * x[1] + p.g * x[0] + self.load.torque(x[0], x[1])) / p.dm
    }

    /// `b(t)` of (9) at state `x` with valve direction `s = sgn(u)`.
    /// Returns `(b, clamped)` (see the module doc on the valve root).
    #[inline]
    pub fn b(&self, x: &[T; 3], s: T) -> (T, bool) {
        let (kg, clamped) = self.flow_gain(self.load_pressure(x), sgn(s));
        (self.b_per_kg * kg, clamped)
    }

    /// The nominal gain b̄ a law divides by when its `b̄·u` is `v` (the
    /// module doc of [`crate::control`]): `b(x, sgn v)`, floored at `floor`
    /// when the valve root was clamped or b fell below the floor. Returns
    /// `(b̄, floored)`.
    #[inline]
    pub fn gain_for(&self, x: &[T; 3], v: T, floor: T) -> (T, bool) {
        let (b, clamped) = self.b(x, sgn(v));
        if clamped || b < floor {
            (b.max(floor), true)
        } else {
            (b, false)
        }
    }

    /// The nominal gains b̄ of [`NominalModel::gain_for`] for both valve
    /// directions at a state `x` whose load pressure is
    /// `pl = load_pressure(x)`, before `v` is known: the load pressure (a
    /// sine), the division and root of each direction need only `x`, so a
    /// law can start them first and let them run while it computes `v`;
    /// [`DirectionalGains::pick`] then returns what `gain_for(x, v, floor)`
    /// returns, to the bit. On an in-order core (Arm), where nothing runs
    /// ahead, only the picked direction is computed, in `pick`.
    #[inline]
    pub fn directional_gains(&self, pl: T, floor: T) -> DirectionalGains<T> {
        let (up, down) = if EAGER_GAINS {
            (
                self.floored_gain(pl, T::ONE, floor),
                self.floored_gain(pl, -T::ONE, floor),
            )
        } else {
            ((T::ZERO, false), (T::ZERO, false))
        };
        DirectionalGains {
            pl,
            floor,
            up,
            down,
        }
    }

    /// `b(x, s)` from the load pressure `pl` of `x` and `s = sgn v`,
    /// floored as [`NominalModel::gain_for`] describes.
    #[inline]
    fn floored_gain(&self, pl: T, s: T, floor: T) -> (T, bool) {
        let (kg, clamped) = self.flow_gain(pl, sgn(s));
        let b = self.b_per_kg * kg;
        if clamped || b < floor {
            (b.max(floor), true)
        } else {
            (b, false)
        }
    }

    /// `b` at zero load pressure: `4βe·Dm·Kv·Cd·Ag·sqrt(Ps/ρ)/(Vt·Jt)`.
    pub fn b_at_rest(&self) -> T {
        self.b_per_kg * self.flow_gain(T::ZERO, T::ZERO).0
    }

    /// `(b(x, s), d(x))` in one evaluation: the load's sine and cosine
    /// from one `sin_cos`, Tl once. The same bits as [`Self::b`] and
    /// [`Self::d`] (the same operations in the same order; `sin_cos` gives
    /// `sin`'s and `cos`'s bits); `s` is a sign (−1, 0, 1).
    #[inline]
    pub fn b_and_d(&self, x: &[T; 3], s: T) -> (T, T) {
        let (pl, d) = self.pl_and_d(x);
        (self.b_per_kg * self.flow_gain(pl, s).0, d)
    }

    /// [`Self::b_and_d`] before the sign is known: `b(x, +1)`, `b(x, −1)`
    /// and `d(x)` from the state alone, the same bits. A simulator computes
    /// them as a sample begins, ahead of the law, so that the load's sine,
    /// the divisions and the roots run beside the law's own chains instead
    /// of after the command they would otherwise wait for
    /// ([`Self::b_and_d_from`] then picks by the command's sign).
    #[inline]
    pub fn b_and_d_both(&self, x: &[T; 3]) -> BothDirections<T> {
        let (pl, d) = self.pl_and_d(x);
        BothDirections {
            pl,
            d,
            up: self.b_per_kg * self.flow_gain(pl, T::ONE).0,
            down: self.b_per_kg * self.flow_gain(pl, -T::ONE).0,
        }
    }

    /// [`Self::b_and_d`]`(x, s)` from [`Self::b_and_d_both`]`(x)`: the same
    /// bits for every `s` (for s = 0, a command or valve output of exactly
    /// zero, or anything but ±1, b is computed here from the kept P_L).
    #[inline]
    pub fn b_and_d_from(&self, both: &BothDirections<T>, s: T) -> (T, T) {
        let b = if s == T::ONE {
            both.up
        } else if s == -T::ONE {
            both.down
        } else {
            self.b_per_kg * self.flow_gain(both.pl, s).0
        };
        (b, both.d)
    }

    /// The load pressure and `d(x)`, the load's sine and cosine from one
    /// `sin_cos`, Tl once: what [`Self::b_and_d`] shares between b and d.
    #[inline(always)]
    fn pl_and_d(&self, x: &[T; 3]) -> (T, T) {
        let (p, l) = (&self.params, &self.load);
        let (sin_kt, cos_kt) = (l.wavenumber * x[0]).sin_cos();
        // Load::torque and Load::torque_rate.
        let mut tl = l.amplitude * sin_kt;
        let mut tl_rate = l.amplitude * l.wavenumber * cos_kt * x[1];
        if let Some(f) = &l.friction {
            let (torque, rate) = friction_terms(f, x);
            tl += torque;
            tl_rate += rate;
        }
        // Self::load_pressure and ::d.
        let pl = (p.jt * x[2] + p.bm * x[1] + p.g * x[0] + tl) / p.dm;
        let d = self.d_per_torque * tl + tl_rate / p.jt;
        (pl, d)
    }

    /// `d(t) = 4βe·Kce·Tl/(Vt·Jt) + Ṫl/Jt` of (9) at state `x`.
    #[inline]
    pub fn d(&self, x: &[T; 3]) -> T {
        self.d_per_torque * self.load.torque(x[0], x[1])
            + self.load.torque_rate(x[0], x[1], x[2]) / self.params.jt
    }
}

/// The friction's terms of [`Load::torque`] and [`Load::torque_rate`] at
/// `x`, out of line (the same operations): the paper's load has none, and
/// inlined into [`NominalModel::b_and_d`] their exponentials made every
/// plant derivative carry their spills and callee-saved registers, and
/// too large to inline into the RK4 stages.
#[cold]
#[inline(never)]
fn friction_terms<T: Real>(f: &Friction<T>, x: &[T; 3]) -> (T, T) {
    (f.torque(x[1]), f.slope(x[1]) * x[2])
}

/// `b(x, ±1)` and `d(x)` at one state ([`NominalModel::b_and_d_both`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BothDirections<T: Real = f64> {
    pl: T,
    d: T,
    up: T,
    down: T,
}

/// Whether [`NominalModel::directional_gains`] computes both directions
/// ahead of `v` (an out-of-order host overlaps their divisions and roots
/// with the rest of the law) or leaves the one picked to
/// [`DirectionalGains::pick`] (32-bit Arm, the Cortex-M this core is
/// built for: in order, it would spend a division and a root, about 35
/// cycles, on the other direction). The same bits either way: `pick`
/// computes what the eager form stores.
const EAGER_GAINS: bool = !cfg!(target_arch = "arm");

/// The floored nominal gain for each valve direction at one state
/// ([`NominalModel::directional_gains`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectionalGains<T: Real = f64> {
    pl: T,
    floor: T,
    up: (T, bool),
    down: (T, bool),
}

impl<T: Real> DirectionalGains<T> {
    /// `gain_for(x, v, floor)`: the gain of direction `sgn v` and whether
    /// it was floored. `v = 0` (or NaN), rare, is computed here.
    #[inline]
    pub fn pick(&self, model: &NominalModel<T>, v: T) -> (T, bool) {
        if EAGER_GAINS && v > T::ZERO {
            self.up
        } else if EAGER_GAINS && v < T::ZERO {
            self.down
        } else {
            model.floored_gain(self.pl, sgn(v), self.floor)
        }
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;

    /// ā_i from (9) with the Section IV parameters, computed by hand:
    /// k = 4βe/(Vt·Jt) = 4·344.875e6/(1.639e-4·5.652e-2) = 1.489157e14;
    /// a1 = k·Kce·G = 1.489157e14·2.376e-12·1.13e-3 = 0.399821;
    /// a2 = G/Jt + k·Dm² + k·Kce·Bm = 0.0199929 + 10000.884 + 2999.364 = 13000.268
    /// (hand rounding of k; the paper's 13000.2711 needs k to 7 digits);
    /// a3 = Bm/Jt + 4βe·Kce/Vt = 149.98231 + 19.99812 = 169.98043.
    /// The paper prints 0.39982, 13000.2711, 169.98043.
    #[test]
    fn coefficients_match_the_paper_printed_digits() {
        let c = ServoParams::paper().coefficients();
        assert!((c.a1 - 0.39982).abs() < 0.5e-5, "a1 = {}", c.a1);
        assert!((c.a2 - 13000.2711).abs() < 0.5e-4, "a2 = {}", c.a2);
        assert!((c.a3 - 169.98043).abs() < 0.5e-5, "a3 = {}", c.a3);
    }

    /// Every parameter finite and positive, yet the model overflows: Bm =
    /// 1e308 gives a3 = Bm/Jt = 1e308/0.05652 = ∞, Jt = 5e-324 gives
    /// 1/Jt = ∞; each is refused, naming that parameter. The paper's set,
    /// and one a thousand times lighter, pass.
    #[test]
    fn parameters_whose_model_overflows_are_refused() {
        let mut p = ServoParams::paper();
        p.bm = 1e308;
        assert_eq!(p.validate().unwrap_err().name, "Bm");
        let mut p = ServoParams::paper();
        p.jt = f64::from_bits(1);
        assert_eq!(p.validate().unwrap_err().name, "Jt");
        assert!(ServoParams::paper().validate().is_ok());
        let mut p = ServoParams::paper();
        p.jt *= 1e-3;
        assert!(p.validate().is_ok());
    }

    /// b at Pl = 0: Kg = 0.67·3.385e-7·sqrt(13.795e6/850) = 2.26795e-7·127.394
    /// = 2.88925e-5; b = 4·344.875e6·8.195e-6·2.88925e-5·0.508/(1.639e-4·5.652e-2)
    /// = 17 911.8 (SPEC: ≈ 17 912).
    #[test]
    fn b_at_rest_by_hand() {
        let m = NominalModel::new(ServoParams::paper(), Load::paper());
        assert!((m.b_at_rest() - 17911.8).abs() < 0.1, "{}", m.b_at_rest());
        // At rest, x = 0 and Tl(0) = 0, so Pl = 0 and the sign is irrelevant.
        let (b, clamped) = m.b(&[0.0; 3], 1.0);
        assert!(!clamped);
        assert!((b - m.b_at_rest()).abs() < 1e-9);
    }

    /// A positive load pressure reduces the flow gain for positive xv and
    /// raises it for negative xv: Ps − Pl < Ps < Ps + Pl.
    #[test]
    fn flow_gain_direction_and_clamp() {
        let p = ServoParams::paper();
        let (k0, _) = p.flow_gain(0.0, 1.0);
        let (kp, _) = p.flow_gain(1e6, 1.0);
        let (kn, _) = p.flow_gain(1e6, -1.0);
        assert!(kp < k0 && k0 < kn);
        // sqrt((Ps − Pl)/Ps) scaling: Pl = Ps/4 → factor sqrt(3/4).
        let (kq, _) = p.flow_gain(p.ps / 4.0, 1.0);
        assert!((kq / k0 - (0.75f64).sqrt()).abs() < 1e-12);
        // Pl beyond the supply: the root is clamped, never NaN.
        let (kc, clamped) = p.flow_gain(2.0 * p.ps, 1.0);
        assert!(clamped);
        assert_eq!(kc, 0.0);
    }

    /// d = 4βe·Kce·Tl/(Vt·Jt) + Ṫl/Jt for Tl = 2 sin 4θ at θ = 0.1, θ̇ = 0.5:
    /// Tl = 2·sin(0.4) = 0.778837; Ṫl = 8·cos(0.4)·0.5 = 3.684244;
    /// 4βe·Kce/(Vt·Jt) = 3.277692e-3/9.263628e-6 = 353.8238;
    /// d = 353.8238·0.778837 + 3.684244/0.05652 = 275.5710 + 65.1848 = 340.7558.
    #[test]
    fn load_term_by_hand() {
        let m = NominalModel::new(ServoParams::paper(), Load::paper());
        let d = m.d(&[0.1, 0.5, 0.0]);
        assert!((d - 340.7558).abs() < 1e-3, "d = {d}");
    }

    /// The gains computed ahead of v are `gain_for`'s to the bit: both
    /// directions, v = ±0 and NaN (direction 0), a load pressure beyond the
    /// supply (the root clamped, b̄ floored) and a floor above b; and so is
    /// what the lazy `pick` (Arm, `EAGER_GAINS` false) computes for every v.
    #[test]
    fn directional_gains_pick_what_gain_for_computes() {
        let m = NominalModel::new(ServoParams::paper(), Load::paper());
        let floor = 1e-3 * m.b_at_rest();
        let states = [
            [0.0, 0.0, 0.0],
            [0.1, 0.5, -3.0],
            [-0.3, 2.0, 40.0],
            [0.0, 0.0, 5e4],  // Pl beyond Ps: one direction clamped
            [0.0, 0.0, -5e4], // and the other one
        ];
        for x in states {
            for floor in [floor, 1e9] {
                let d = m.directional_gains(m.load_pressure(&x), floor);
                for v in [1.0, -2.5, 0.0, -0.0, f64::NAN, 1e-300, -f64::INFINITY] {
                    let (a, fa) = m.gain_for(&x, v, floor);
                    let (b, fb) = d.pick(&m, v);
                    assert_eq!((a.to_bits(), fa), (b.to_bits(), fb), "{x:?} {v}");
                    let (c, fc) = m.floored_gain(m.load_pressure(&x), sgn(v), floor);
                    assert_eq!((a.to_bits(), fa), (c.to_bits(), fc), "lazy: {x:?} {v}");
                }
            }
        }
    }

    /// Friction slope against a central finite difference.
    #[test]
    fn friction_slope_matches_finite_difference() {
        let f = Friction {
            coulomb: 0.3,
            stiction: 0.5,
            stribeck_velocity: 0.1,
            viscous: 0.05,
            smoothing: 0.01,
        };
        for &v in &[-0.3, -0.05, -0.002, 0.0, 0.003, 0.07, 0.4] {
            let h = 1e-7;
            let fd = (f.torque(v + h) - f.torque(v - h)) / (2.0 * h);
            let an = f.slope(v);
            assert!(
                (fd - an).abs() < 1e-5 * (1.0 + an.abs()),
                "v={v}: {fd} vs {an}"
            );
        }
        // Far from zero speed the friction is Tc·sgn(v) + Bv·v (Stribeck term gone).
        assert!((f.torque(2.0) - (0.3 + 0.05 * 2.0)).abs() < 1e-9);
    }
}
