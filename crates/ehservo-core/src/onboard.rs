//! A closed loop that fits on a board: the plant (8) with the paper's
//! constant uncertainty, integrated by RK4 in the core's float type, around
//! a [`SampledController`] at a fixed rate.
//!
//! This is what the Cortex-M4F firmware (`examples/firmware-m4f`) runs, and
//! what a host runs to check it: both compute in the same `T` with the same
//! `libm`, so an f32 host build and the board print the same bits. It is
//! also the f32-versus-f64 yardstick of the core (`tests/float_types.rs`).
//!
//! The true plant is the sampled-mode plant of SPEC for a constant
//! uncertainty (the C yardstick's `plant_rhs`):
//!
//! ```text
//! ẋ1 = x2,  ẋ2 = x3,
//! ẋ3 = −Σ a_i x_i + b·u − d,   a_i = ā_i + a_bias·bound_a·|ā_i|,
//!                              b = b̄(x, sgn u)·(1 + b_bias·bound_b)
//! ```
//!
//! with `b̄` and `d` of the nominal model (load known, SPEC §2), `u` held
//! over each period and the plant advanced by `substeps` RK4 steps. Time is
//! `t = k·dt` (never accumulated); the reference (period 1 s) is evaluated
//! at `(k mod rate)·dt`, the same instant with its phase reduced exactly.

use core::fmt;

use crate::control::nnvsc::{NnVsc, NnVscParams};
use crate::control::vsc::{Vsc, VscParams};
use crate::control::Controller;
use crate::error::{non_negative, ParamError};
use crate::math::{sgn, Real, DR};
use crate::rbf::Rbf;
use crate::reference::{Reference, Sine};
use crate::rk4::rk4_step;
use crate::sampled::SampledController;
use crate::servo::{Load, NominalModel, ServoParams};
use crate::surface::SwitchingSurface;

/// A constant parametric uncertainty of the plant (SPEC §7 without the
/// random part): `a_i = ā_i + a_bias·bound_a·|ā_i|`,
/// `b = b̄·(1 + b_bias·bound_b)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bias<T = f64> {
    /// Fraction of the bound on Δa_i (Fig. 2: 1).
    pub a_bias: T,
    /// Fraction of the bound on Δb (Fig. 2: 0.5).
    pub b_bias: T,
    /// Bound on |Δa_i|/|ā_i| (the paper's 1).
    pub bound_a: T,
    /// Bound on |Δb|/b̄ (the paper's 0.5).
    pub bound_b: T,
}

impl<T: Real> Bias<T> {
    /// Fig. 2's: 100 % of the a_i bound, 50 % of the b bound.
    pub fn fig2() -> Self {
        Self {
            a_bias: T::ONE,
            b_bias: T::of(0.5),
            bound_a: T::ONE,
            bound_b: T::of(0.5),
        }
    }
}

/// The true plant of the loop: the nominal model plus a [`Bias`].
///
/// ```
/// use ehservo_core::onboard::{Bias, BiasedPlant};
/// use ehservo_core::servo::{Load, NominalModel, ServoParams};
///
/// let model = NominalModel::new(ServoParams::paper(), Load::paper());
/// let plant = BiasedPlant::new(model, Bias::fig2())?;
/// // Fig. 2: a_i = ā_i + 1·1·|ā_i| = 2ā_i, b = b̄·(1 + 0.5·0.5) = 1.25·b̄.
/// let abar = model.coeffs.as_array();
/// assert_eq!(plant.a(), abar.map(|a| 2.0 * a));
/// // At rest under u = 1 V only the valve acts: ẋ3 = b·u, with b̄ at Pl = 0.
/// let mut dx = [0.0; 3];
/// plant.rhs(&[0.0; 3], 1.0, &mut dx);
/// assert_eq!(dx[..2], [0.0, 0.0]);
/// assert!((dx[2] - 1.25 * model.b_at_rest()).abs() <= 1e-12 * dx[2]);
/// # Ok::<(), ehservo_core::error::ParamError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasedPlant<T: Real = f64> {
    model: NominalModel<T>,
    a: [T; 3],
    b_factor: T,
}

impl<T: Real> BiasedPlant<T> {
    /// From the nominal model and the uncertainty.
    pub fn new(model: NominalModel<T>, bias: Bias<T>) -> Result<Self, ParamError> {
        non_negative("bound_a", bias.bound_a)?;
        non_negative("bound_b", bias.bound_b)?;
        crate::error::finite("a_bias", bias.a_bias)?;
        crate::error::finite("b_bias", bias.b_bias)?;
        let abar = model.coeffs.as_array();
        let a = abar.map(|ai| ai + bias.a_bias * (bias.bound_a * ai.abs()));
        Ok(Self {
            model,
            a,
            b_factor: T::ONE + bias.b_bias * bias.bound_b,
        })
    }

    /// The true a_i.
    pub fn a(&self) -> [T; 3] {
        self.a
    }

    /// ẋ under the held command `u` (valve direction `sgn u`).
    #[inline]
    pub fn rhs(&self, x: &[T; 3], u: T, dx: &mut [T; 3]) {
        let (bb, d) = self.model.b_and_d(x, sgn(u));
        let b = bb * self.b_factor;
        dx[0] = x[1];
        dx[1] = x[2];
        dx[2] = -self.a[0] * x[0] - self.a[1] * x[1] - self.a[2] * x[2] + b * u - d;
    }
}

/// |θ| beyond this (rad) is divergence ([`ClosedLoop::run_for`]).
pub const THETA_LIMIT: f64 = 1.0;

/// A sampled controller around a [`BiasedPlant`], at `dt` per period.
///
/// ```
/// use ehservo_core::onboard::ClosedLoop;
///
/// // The traditional VSC on the Fig. 2 plant, sampled at 1 kHz.
/// let mut lp = ClosedLoop::<_, f64>::paper_vsc(1000, ehservo_core::onboard::Bias::fig2())?;
/// // A board's interrupt: the controller's half, then the plant's.
/// let u = lp.control();
/// lp.advance(u);
/// // At t = 0 the reference 5°·sin(2πt) is at 0 and rising: e = 0, u > 0.
/// assert_eq!(lp.e(), 0.0);
/// assert!(u > 0.0);
/// assert_eq!((lp.k(), lp.t()), (1, 0.001));
/// // Whole periods up to t = 1 s: 1000 of them, time kept as k·dt.
/// lp.run_for(1).expect("no divergence");
/// assert_eq!((lp.k(), lp.t()), (1000, 1.0));
/// assert!(lp.checkpoint().to_string().starts_with("checkpoint k=1000 t=1.0 "));
/// # Ok::<(), ehservo_core::error::ParamError>(())
/// ```
#[derive(Clone)]
pub struct ClosedLoop<C: Controller<T>, T: Real = f64> {
    ctl: SampledController<C, T>,
    plant: BiasedPlant<T>,
    reference: Sine<T>,
    dt: T,
    substeps: u32,
    rate_hz: u32,
    k: u32,
    x: [T; 3],
    e: T,
    e_max: T,
    u: T,
}

/// The Fig. 2 case on a board: the NNBVSC of Theorem 3.
///
/// ```
/// use ehservo_core::onboard::Fig2Loop;
///
/// // The paper's sample rate, 100 Hz, over the paper's 10 s.
/// let mut lp = Fig2Loop::<f64>::paper(100)?;
/// assert_eq!(lp.run_for(10), Ok(()));
/// assert_eq!(lp.k(), 1000);
/// // max |e| over t ≥ 2 s against the C yardstick (shared/peers/c/nnvsc.c,
/// // an independent implementation of the same loop), which prints
/// // 0.20909499579719379°; the band allows the last bits of `exp`.
/// let e = lp.e_max_deg();
/// assert!((e - 0.209_094_995_797_193_8).abs() < 1e-9 * e, "{e}");
/// # Ok::<(), ehservo_core::error::ParamError>(())
/// ```
pub type Fig2Loop<T> = ClosedLoop<NnVsc<T>, T>;

impl<T: Real> ClosedLoop<NnVsc<T>, T> {
    /// The Fig. 2 case (NNBVSC with the paper's gains, surface, network,
    /// load and reference; 100 % a_i bias, 50 % b bias) with the controller
    /// sampled at `rate_hz` and one RK4 step of the plant per period. The
    /// controller is built in f64 from the paper's values and cast to `T`.
    pub fn paper(rate_hz: u32) -> Result<Self, ParamError> {
        Self::paper_with(rate_hz, NnVscParams::paper(), Bias::fig2())
    }

    /// The Fig. 2 loop with other gains and another uncertainty (the
    /// paper's other NNBVSC cases: η, ᾱ, γ1, ε0, ε1, biases).
    pub fn paper_with(
        rate_hz: u32,
        params: NnVscParams,
        bias: Bias<T>,
    ) -> Result<Self, ParamError> {
        let model = NominalModel::new(ServoParams::paper(), Load::paper());
        let nn = NnVsc::try_new(model, SwitchingSurface::paper(), params, Rbf::paper())?;
        ClosedLoop::new(nn.cast()?, model.cast(), bias, rate_hz, 1)
    }
}

impl<T: Real> ClosedLoop<Vsc<T>, T> {
    /// The traditional VSC of Theorem 1 (sign switching) on the paper's
    /// plant with uncertainty `bias` (Fig. 3: 40 % biases).
    pub fn paper_vsc(rate_hz: u32, bias: Bias<T>) -> Result<Self, ParamError> {
        let model = NominalModel::new(ServoParams::paper(), Load::paper());
        let vsc = Vsc::try_new(model, SwitchingSurface::paper(), VscParams::paper())?;
        ClosedLoop::new(vsc.cast()?, model.cast(), bias, rate_hz, 1)
    }
}

impl<C: Controller<T>, T: Real> ClosedLoop<C, T> {
    /// `ctl` sampled at `rate_hz` around the plant `model` + `bias`, the
    /// plant advanced by `substeps` RK4 steps per period, from rest, with
    /// the paper's reference.
    pub fn new(
        ctl: C,
        model: NominalModel<T>,
        bias: Bias<T>,
        rate_hz: u32,
        substeps: u32,
    ) -> Result<Self, ParamError> {
        if rate_hz == 0 {
            return Err(ParamError::new("rate_hz", "must be > 0", 0.0));
        }
        if substeps == 0 {
            return Err(ParamError::new("substeps", "must be > 0", 0.0));
        }
        let dt = T::ONE / T::of_u32(rate_hz);
        Ok(Self {
            ctl: SampledController::new(ctl, dt)?,
            plant: BiasedPlant::new(model, bias)?,
            reference: Sine::paper().cast(),
            dt,
            substeps,
            rate_hz,
            k: 0,
            x: [T::ZERO; 3],
            e: T::ZERO,
            e_max: T::ZERO,
            u: T::ZERO,
        })
    }

    /// The controller's half of a period: [`Self::sense`] then
    /// [`Self::law_step`]; returns u (V).
    #[inline]
    pub fn control(&mut self) -> T {
        let z = self.sense();
        self.law_step(z)
    }

    /// The reference at `t = k·dt` (what the controller is asked to track);
    /// tracks e and its maximum over t ≥ 2 s.
    #[inline]
    pub fn sense(&mut self) -> [T; 4] {
        // The reference's phase from k mod rate (its period is 1 s): exact
        // to ulp(1 s) at any time. In f32, t = k·dt itself carries
        // ulp(10 s) ≈ 1e-6 s at 10 s, i.e. 3e-7 rad in θd and 8e-4 rad/s²
        // in σ (through p2·e) — at the sign-switching VSC's chattering level
        // (|e| ≈ 6e-5 rad at 10 kHz) a 3 % effect on e_max.
        let t_ref = T::of_u32(self.k % self.rate_hz) * self.dt;
        let z = self.reference.z(t_ref);
        self.e = z[0] - self.x[0];
        if self.k >= 2 * self.rate_hz {
            let ae = self.e.abs();
            if ae > self.e_max {
                self.e_max = ae;
            }
        }
        z
    }

    /// The controller step proper: [`SampledController::step`] (checks,
    /// the law, forward Euler on the controller state) on the measured
    /// state and the reference `z`; returns u (V). This is what a board's
    /// control interrupt runs.
    #[inline]
    pub fn law_step(&mut self, z: [T; 4]) -> T {
        self.u = self.ctl.step(self.t(), self.x, z).u;
        self.u
    }

    /// The plant's half: integrates the plant over one period holding `u`,
    /// then `k += 1`.
    #[inline]
    pub fn advance(&mut self, u: T) {
        let h = self.dt / T::of_u32(self.substeps);
        let plant = &self.plant;
        for _ in 0..self.substeps {
            rk4_step(
                |_, x: &[T; 3], dx: &mut [T; 3]| plant.rhs(x, u, dx),
                T::ZERO,
                &mut self.x,
                h,
            );
        }
        self.k += 1;
    }

    /// One whole period: [`Self::control`] then [`Self::advance`].
    #[inline]
    pub fn step(&mut self) -> T {
        let u = self.control();
        self.advance(u);
        u
    }

    /// Runs until `t = seconds` (`seconds·rate` periods); stops early and
    /// returns `Err(k)` at the first period after which the state or the
    /// command is not finite or |θ| exceeds [`THETA_LIMIT`] (the
    /// simulator's default divergence limit).
    pub fn run_for(&mut self, seconds: u32) -> Result<(), u32> {
        let n = seconds * self.rate_hz;
        while self.k < n {
            let u = self.step();
            let bounded = self.x[0].abs() <= T::of(THETA_LIMIT);
            if !(bounded && u.is_finite() && self.x.iter().all(|v| v.is_finite())) {
                return Err(self.k);
            }
        }
        Ok(())
    }

    /// Periods done.
    pub fn k(&self) -> u32 {
        self.k
    }
    /// The rate (Hz).
    pub fn rate_hz(&self) -> u32 {
        self.rate_hz
    }
    /// `t = k·dt` (s).
    pub fn t(&self) -> T {
        T::of_u32(self.k) * self.dt
    }
    /// The plant state (θ, θ̇, θ̈).
    pub fn x(&self) -> [T; 3] {
        self.x
    }
    /// The tracking error θd − θ at the last [`Self::control`] (rad).
    pub fn e(&self) -> T {
        self.e
    }
    /// The last command (V).
    pub fn u(&self) -> T {
        self.u
    }
    /// max |e| over t ≥ 2 s so far, in degrees.
    pub fn e_max_deg(&self) -> T {
        self.e_max / T::of(DR)
    }
    /// The sampled controller (its state, fault and saturation counts).
    pub fn controller(&self) -> &SampledController<C, T> {
        &self.ctl
    }
    /// A checkpoint line of the current period (for host/board comparison).
    pub fn checkpoint(&self) -> Checkpoint<T> {
        Checkpoint {
            k: self.k,
            t: self.t(),
            x1: self.x[0],
            e: self.e,
            u: self.u,
        }
    }
}

impl<C: Controller<T>, T: Real> fmt::Debug for ClosedLoop<C, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ClosedLoop")
            .field("rate_hz", &self.rate_hz)
            .field("k", &self.k)
            .field("x", &self.x)
            .field("e_max_deg", &self.e_max_deg())
            .finish_non_exhaustive()
    }
}

/// What the firmware and the host print at a checkpoint; `Display` gives
/// the one line both print (`{:?}` of each float: the shortest text that
/// reads back to the same bits).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Checkpoint<T> {
    /// Period index.
    pub k: u32,
    /// Time (s).
    pub t: T,
    /// θ (rad).
    pub x1: T,
    /// θd − θ (rad) at the last control step.
    pub e: T,
    /// The last command (V).
    pub u: T,
}

impl<T: Real> fmt::Display for Checkpoint<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "checkpoint k={} t={:?} x1={:?} e={:?} u={:?}",
            self.k, self.t, self.x1, self.e, self.u
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The true a_i of Fig. 2 are 2ā_i and b is 1.25·b̄: at rest (x = 0,
    /// Tl = 0, d = 0) with u = 1 V, ẋ3 = 1.25·b̄(0) = 1.25·17 911.8.
    #[test]
    fn fig2_plant_by_hand() {
        let model = NominalModel::new(ServoParams::paper(), Load::paper());
        let p = BiasedPlant::new(model, Bias::fig2()).unwrap();
        let a = p.a();
        assert!((a[1] - 2.0 * 13000.2711).abs() < 1e-3);
        let mut dx = [0.0; 3];
        p.rhs(&[0.0, 0.0, 0.0], 1.0, &mut dx);
        assert!((dx[2] - 1.25 * 17911.8).abs() < 0.2, "{}", dx[2]);
        // ẋ1 = x2, ẋ2 = x3, and −a3·x3 enters ẋ3.
        p.rhs(&[0.0, 0.5, 2.0], 0.0, &mut dx);
        assert_eq!(dx[..2], [0.5, 2.0]);
        let d = model.d(&[0.0, 0.5, 2.0]);
        let want = -a[1] * 0.5 - a[2] * 2.0 - d;
        assert!((dx[2] - want).abs() < 1e-9 * want.abs());
    }

    #[test]
    fn bad_rates_are_rejected() {
        assert_eq!(Fig2Loop::<f32>::paper(0).unwrap_err().name, "rate_hz");
    }
}
