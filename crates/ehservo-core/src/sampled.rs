//! A fixed-rate control loop for hardware.
//!
//! Every `dt` seconds the board reads x (and knows z), calls
//! [`SampledController::step`], applies `u` to the servovalve and holds it
//! (zero-order hold) until the next tick. The controller state ξ (∫e, W)
//! advances once per tick by forward Euler with the derivative at the tick:
//! `ξ(k+1) = ξ(k) + dt·ξ̇(k)`. This is the `sampled` reading of the paper's
//! simulation (SPEC §7), and exactly what the simulator does in that mode.
//!
//! **Faults.** A sensor can return NaN, ±∞ or a value no servo can reach.
//! Before the law runs, every measurement is checked (finite, and
//! |x_i| ≤ `limits.x[i]`, z finite); a bad one raises
//! [`flags::MEASUREMENT_FAULT`] and the step returns the safe command of
//! the [`FaultPolicy`] (hold the last good command, or zero) **without
//! touching ∫e or W**, so one bad sample cannot poison the weights. The same
//! happens if the law itself produces a non-finite u or ξ̇
//! ([`flags::NON_FINITE_CONTROL`], [`flags::NON_FINITE_STATE`]). A good command is clamped to
//! `±limits.u` (the valve's range) and the clamp raises [`flags::SATURATED`].
//!
//! No allocation: the state lives inside the struct, twice (the current
//! one and the next one being formed; about 1 kB each for the
//! NNBVSC).

use crate::control::{flags, Controller, Measurement, Output};
use crate::error::{positive, ParamError};
use crate::math::Real;
use crate::rk4::OdeState;
use core::fmt;

/// What to command when a step cannot be trusted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SafeCommand {
    /// Hold the last command that came from a good step (0 before any).
    HoldLast,
    /// Command zero (valve centred).
    Zero,
}

/// Plausibility limits and the valve's range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits<T = f64> {
    /// |θ|, |θ̇|, |θ̈| beyond these are sensor faults (rad, rad/s, rad/s²).
    pub x: [T; 3],
    /// The valve's command range ±u (V).
    pub u: T,
}

impl<T: Real> Limits<T> {
    /// No limits at all (the simulator's default).
    pub const NONE: Self = Limits {
        x: [T::INFINITY; 3],
        u: T::INFINITY,
    };

    /// The same limits in another float type.
    pub fn cast<U: Real>(&self) -> Limits<U> {
        Limits {
            x: self.x.map(|v| U::of(v.to_f64())),
            u: U::of(self.u.to_f64()),
        }
    }
}

/// How [`SampledController::step`] treats faults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaultPolicy<T = f64> {
    /// The command on a bad step.
    pub safe: SafeCommand,
    /// Plausibility limits and valve range.
    pub limits: Limits<T>,
}

impl<T: Real> Default for FaultPolicy<T> {
    fn default() -> Self {
        Self {
            safe: SafeCommand::HoldLast,
            limits: Limits::NONE,
        }
    }
}

impl<T: Real> FaultPolicy<T> {
    /// Checks the limits (positive; infinity allowed).
    ///
    /// ```
    /// use ehservo_core::sampled::{FaultPolicy, Limits};
    ///
    /// assert!(FaultPolicy::<f64>::default().validate().is_ok());
    /// // A valve range of zero is no valve.
    /// let limits = Limits { u: 0.0, ..Limits::NONE };
    /// let policy = FaultPolicy { limits, ..FaultPolicy::default() };
    /// assert_eq!(policy.validate().unwrap_err().name, "limits.u");
    /// ```
    pub fn validate(&self) -> Result<(), ParamError> {
        for &l in &self.limits.x {
            if l.is_nan() || l <= T::ZERO {
                return Err(ParamError::new(
                    "limits.x",
                    "must be > 0 (or infinite)",
                    l.to_f64(),
                ));
            }
        }
        if self.limits.u.is_nan() || self.limits.u <= T::ZERO {
            return Err(ParamError::new(
                "limits.u",
                "must be > 0 (or infinite)",
                self.limits.u.to_f64(),
            ));
        }
        Ok(())
    }
}

/// A sample period and a fault policy, checked together: what a
/// [`SampledController`] is made of besides its controller. A value of
/// this type is valid, so [`SampledController::sampled`] cannot fail.
///
/// ```
/// use ehservo_core::sampled::{FaultPolicy, Sampling};
/// let s = Sampling::try_new(0.01, FaultPolicy::default()).unwrap();
/// assert_eq!(s.dt(), 0.01);
/// // A period must be finite and > 0.
/// assert_eq!(Sampling::try_new(0.0, FaultPolicy::default()).unwrap_err().name, "dt");
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sampling<T = f64> {
    dt: T,
    policy: FaultPolicy<T>,
}

impl<T: Real> Sampling<T> {
    /// The period `dt` (s, finite and > 0) with `policy` (its limits > 0).
    pub fn try_new(dt: T, policy: FaultPolicy<T>) -> Result<Self, ParamError> {
        positive("dt", dt)?;
        policy.validate()?;
        Ok(Self { dt, policy })
    }

    /// The sample period (s).
    pub fn dt(&self) -> T {
        self.dt
    }

    /// The fault policy.
    pub fn policy(&self) -> &FaultPolicy<T> {
        &self.policy
    }
}

/// A controller with its state, a fixed sample period and a fault policy.
///
/// ```
/// # use ehservo_core::control::pid::PidConfig;
/// # use ehservo_core::prelude::*;
/// # let design = Design {
/// #     model: NominalModel::new(ServoParams::paper(), Load::paper()),
/// #     surface: SwitchingSurface::paper(),
/// #     dt: 0.01,
/// # };
/// // A PI law: kp = 2 V/rad, ki = 3 V/(rad·s), no derivative, no feedforward.
/// let pi = PidConfig {
///     kp: Some(2.0),
///     ki: Some(3.0),
///     kd: Some(0.0),
///     feedforward: false,
///     ..PidConfig::default()
/// }
/// .build(&design)?;
/// let mut ctl = SampledController::new(pi, 0.01)?;
/// // θd = 0.05, θ = 0.03: e = 0.02 at every tick.
/// let (x, z) = ([0.03, 0.0, 0.0], [0.05, 0.0, 0.0, 0.0]);
/// // Tick 0: I = 0, u = kp·e = 0.04; then I ← I + dt·ki·e = 0.0006.
/// assert!((ctl.step(0.0, x, z).u - 0.04).abs() < 1e-12);
/// assert!((ctl.state()[0] - 0.0006).abs() < 1e-15);
/// // Tick 1: u = 0.04 + 0.0006.
/// assert!((ctl.step(0.01, x, z).u - 0.0406).abs() < 1e-12);
/// # Ok::<(), ParamError>(())
/// ```
///
/// The state is double-buffered: the law writes ξ + dt·ξ̇ into the spare
/// buffer, checking that every component is finite
/// ([`Controller::law_euler`]), and a good step makes it the current state
/// (no copy of the state, no second pass).
#[derive(Clone)]
pub struct SampledController<C: Controller<T>, T: Real = f64> {
    ctrl: C,
    /// The current state is `states[cur]`; the other one is scratch.
    states: [C::State; 2],
    cur: usize,
    dt: T,
    policy: FaultPolicy<T>,
    last_u: T,
    faults: u64,
    saturations: u64,
}

impl<C, T> fmt::Debug for SampledController<C, T>
where
    C: Controller<T> + fmt::Debug,
    C::State: fmt::Debug,
    T: Real,
{
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SampledController")
            .field("ctrl", &self.ctrl)
            .field("state", self.state())
            .field("dt", &self.dt)
            .field("policy", &self.policy)
            .field("last_u", &self.last_u)
            .field("faults", &self.faults)
            .field("saturations", &self.saturations)
            .finish()
    }
}

impl<T: Real, C: Controller<T>> SampledController<C, T> {
    /// Wraps `ctrl` with its initial state, sample period `dt` (s) and the
    /// default policy (hold the last command, no limits).
    pub fn new(ctrl: C, dt: T) -> Result<Self, ParamError> {
        Self::with_policy(ctrl, dt, FaultPolicy::default())
    }

    /// As [`SampledController::new`] with a fault policy.
    ///
    /// ```
    /// use ehservo_core::control::flags;
    /// # use ehservo_core::control::pid::PidConfig;
    /// # use ehservo_core::prelude::*;
    /// # let design = Design {
    /// #     model: NominalModel::new(ServoParams::paper(), Load::paper()),
    /// #     surface: SwitchingSurface::paper(),
    /// #     dt: 0.01,
    /// # };
    /// // A PI law: kp = 2 V/rad, ki = 3 V/(rad·s), no derivative, no feedforward.
    /// let pi = PidConfig {
    ///     kp: Some(2.0),
    ///     ki: Some(3.0),
    ///     kd: Some(0.0),
    ///     feedforward: false,
    ///     ..PidConfig::default()
    /// }
    /// .build(&design)?;
    /// // A valve range of ±0.03 V, and θ beyond 1 rad is a sensor fault.
    /// let policy = FaultPolicy {
    ///     safe: SafeCommand::HoldLast,
    ///     limits: Limits { x: [1.0, 100.0, 1e4], u: 0.03 },
    /// };
    /// let mut ctl = SampledController::with_policy(pi, 0.01, policy)?;
    /// let z = [0.05, 0.0, 0.0, 0.0];
    /// // kp·e = 0.04 V is beyond the range: clamped, and said so.
    /// let out = ctl.step(0.0, [0.03, 0.0, 0.0], z);
    /// assert_eq!(out.u, 0.03);
    /// assert_ne!(out.flags & flags::SATURATED, 0);
    /// // A NaN from the sensor: the last good command, the state untouched.
    /// let before = *ctl.state();
    /// let out = ctl.step(0.01, [f64::NAN, 0.0, 0.0], z);
    /// assert_eq!((out.u, out.flags), (0.03, flags::MEASUREMENT_FAULT));
    /// assert_eq!(*ctl.state(), before);
    /// assert_eq!((ctl.fault_count(), ctl.saturation_count()), (1, 1));
    /// # Ok::<(), ParamError>(())
    /// ```
    pub fn with_policy(ctrl: C, dt: T, policy: FaultPolicy<T>) -> Result<Self, ParamError> {
        Sampling::try_new(dt, policy).map(|s| Self::sampled(ctrl, s))
    }

    /// Wraps `ctrl` with its initial state and a checked period and
    /// policy: infallible.
    pub fn sampled(ctrl: C, sampling: Sampling<T>) -> Self {
        Self {
            states: [ctrl.initial_state(), C::State::zero()],
            cur: 0,
            ctrl,
            dt: sampling.dt,
            policy: sampling.policy,
            last_u: T::ZERO,
            faults: 0,
            saturations: 0,
        }
    }

    fn safe_output(&mut self, fault: u8) -> Output<C::Parts, T> {
        self.faults += 1;
        let u = match self.policy.safe {
            SafeCommand::HoldLast => self.last_u,
            SafeCommand::Zero => T::ZERO,
        };
        Output {
            u,
            flags: fault,
            parts: C::Parts::default(),
        }
    }

    /// One tick at time `t` with measurement `x` and reference `z`: returns
    /// the law's parts (or the safe command, flagged) and advances the state
    /// only after a good step. Always returns a finite `u` within the valve
    /// range.
    #[inline]
    pub fn step(&mut self, t: T, x: [T; 3], z: [T; 4]) -> Output<C::Parts, T> {
        self.step_with(t, x, z, |_, _, _| {})
    }

    /// As [`SampledController::step`], calling `inspect` with the state the
    /// law saw and the (clamped) output before the state advances, on good
    /// steps only: the simulator fills its logged diagnostics there
    /// ([`Controller::annotate`]) without copying the state.
    #[inline]
    pub fn step_with(
        &mut self,
        t: T,
        x: [T; 3],
        z: [T; 4],
        inspect: impl FnOnce(&C, &C::State, &mut Output<C::Parts, T>),
    ) -> Output<C::Parts, T> {
        let lim = &self.policy.limits;
        // Branch-free: 0·v is ±0 for a finite v and NaN for ±∞ or NaN, so
        // the sum is 0 exactly when t, x and z are all finite; then each
        // |x_i| ≤ limit (a NaN fails it as well).
        let o = T::ZERO;
        let finite = ((o * t + o * x[0]) + (o * x[1] + o * x[2]))
            + ((o * z[0] + o * z[1]) + (o * z[2] + o * z[3]));
        let in_range =
            (x[0].abs() <= lim.x[0]) & (x[1].abs() <= lim.x[1]) & (x[2].abs() <= lim.x[2]);
        if !(finite == o && in_range) {
            return self.safe_output(flags::MEASUREMENT_FAULT);
        }
        // The spare buffer receives ξ + dt·ξ̇ ([`Controller::law_euler`]);
        // it becomes the state only after a good step.
        let (state, next) = match &mut self.states {
            [a, b] if self.cur == 0 => (&*a, b),
            [a, b] => (&*b, a),
        };
        let (mut out, next_finite) =
            self.ctrl
                .law_euler(&Measurement { t, x, z }, state, next, self.dt);
        let fault = if !out.u.is_finite() {
            flags::NON_FINITE_CONTROL
        } else {
            if out.u.abs() > lim.u {
                out.u = out.u.clamp(-lim.u, lim.u);
                out.flags |= flags::SATURATED;
            }
            inspect(&self.ctrl, state, &mut out);
            // A non-finite ξ̇ makes ξ + dt·ξ̇ non-finite: one check covers
            // both, and refuses an overflow too.
            if next_finite {
                0
            } else {
                flags::NON_FINITE_STATE
            }
        };
        if fault != 0 {
            out = self.safe_output(fault);
        } else {
            self.cur = 1 - self.cur;
            if out.flags & flags::SATURATED != 0 {
                self.saturations += 1;
            }
            self.last_u = out.u;
        }
        out
    }

    /// The law's state set to its start at the plant state `x`
    /// ([`Controller::initial_state_at`]); for a loop that does not start
    /// at rest at the origin.
    pub fn start_at(&mut self, x: &[T; 3]) {
        self.states[self.cur] = self.ctrl.initial_state_at(x);
    }

    /// Back to the initial state (∫e = 0, W = 0), last command 0, counters 0.
    pub fn reset(&mut self) {
        self.states[self.cur] = self.ctrl.initial_state();
        self.last_u = T::ZERO;
        self.faults = 0;
        self.saturations = 0;
    }

    /// The controller state.
    pub fn state(&self) -> &C::State {
        &self.states[self.cur]
    }

    /// The controller.
    pub fn controller(&self) -> &C {
        &self.ctrl
    }

    /// The sample period (s).
    pub fn dt(&self) -> T {
        self.dt
    }

    /// The fault policy.
    pub fn policy(&self) -> &FaultPolicy<T> {
        &self.policy
    }

    /// Steps that returned the safe command.
    pub fn fault_count(&self) -> u64 {
        self.faults
    }

    /// Steps whose command was clamped to the valve range.
    pub fn saturation_count(&self) -> u64 {
        self.saturations
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;
    use crate::control::nnvsc::{NnState, NnVsc, NnVscParams};
    use crate::rbf::Rbf;
    use crate::reference::{Reference, Sine};
    use crate::servo::{Load, NominalModel, ServoParams};
    use crate::surface::SwitchingSurface;

    fn nn() -> NnVsc {
        NnVsc::try_new(
            NominalModel::new(ServoParams::paper(), Load::paper()),
            SwitchingSurface::paper(),
            NnVscParams::paper(),
            Rbf::paper(),
        )
        .unwrap()
    }

    #[test]
    fn bad_measurements_hold_the_last_command_and_spare_the_weights() {
        let mut c = SampledController::new(nn(), 0.01).unwrap();
        let r = Sine::paper();
        let good = c.step(0.0, [0.0; 3], r.z(0.0));
        assert_eq!(good.flags & flags::MEASUREMENT_FAULT, 0);
        let state: NnState = *c.state();
        for bad in [
            [f64::NAN, 0.0, 0.0],
            [0.0, f64::INFINITY, 0.0],
            [0.0, 0.0, f64::NEG_INFINITY],
        ] {
            let o = c.step(0.01, bad, r.z(0.01));
            assert_eq!(o.u, good.u, "held");
            assert_ne!(o.flags & flags::MEASUREMENT_FAULT, 0);
            assert_eq!(*c.state(), state, "weights untouched");
        }
        assert_eq!(c.fault_count(), 3);
        // Zero policy.
        let mut z = SampledController::with_policy(
            nn(),
            0.01,
            FaultPolicy {
                safe: SafeCommand::Zero,
                limits: Limits::NONE,
            },
        )
        .unwrap();
        z.step(0.0, [0.0; 3], r.z(0.0));
        assert_eq!(z.step(0.01, [f64::NAN; 3], r.z(0.01)).u, 0.0);
    }

    #[test]
    fn out_of_range_measurements_are_faults_and_commands_are_clamped() {
        let policy = FaultPolicy {
            safe: SafeCommand::HoldLast,
            limits: Limits {
                x: [1.0, 10.0, 1000.0],
                u: 0.25,
            },
        };
        let mut c = SampledController::with_policy(nn(), 0.01, policy).unwrap();
        let r = Sine::paper();
        // The first Fig. 2 command is 0.599 V (see nnvsc tests): clamped to 0.25.
        let o = c.step(0.0, [0.0; 3], r.z(0.0));
        assert_eq!(o.u, 0.25);
        assert_ne!(o.flags & flags::SATURATED, 0);
        assert_eq!(c.saturation_count(), 1);
        // |θ| = 2 rad > 1 rad: a sensor fault, the held (clamped) command.
        let f = c.step(0.01, [2.0, 0.0, 0.0], r.z(0.01));
        assert_ne!(f.flags & flags::MEASUREMENT_FAULT, 0);
        assert_eq!(f.u, 0.25);
    }

    /// Every input is checked: a non-finite t or reference component and
    /// each |x_i| beyond its own limit are faults; |x_i| exactly at the
    /// limit, and a huge but finite value without limits, are not.
    #[test]
    fn every_input_is_checked_and_the_limits_are_inclusive() {
        let r = Sine::paper();
        let lim = [1.0, 10.0, 1000.0];
        let policy = FaultPolicy {
            safe: SafeCommand::Zero,
            limits: Limits { x: lim, u: 1e3 },
        };
        let fault = |t: f64, x: [f64; 3], z: [f64; 4], p: FaultPolicy| {
            let mut c = SampledController::with_policy(nn(), 0.01, p).unwrap();
            c.step(t, x, z).flags & flags::MEASUREMENT_FAULT != 0
        };
        let z = r.z(0.0);
        assert!(!fault(0.0, [0.0; 3], z, policy));
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert!(fault(bad, [0.0; 3], z, policy), "t = {bad}");
            for i in 0..4 {
                let mut zb = z;
                zb[i] = bad;
                assert!(fault(0.0, [0.0; 3], zb, policy), "z[{i}] = {bad}");
            }
        }
        for i in 0..3 {
            let mut x = [0.0; 3];
            x[i] = -lim[i];
            assert!(!fault(0.0, x, z, policy), "x[{i}] at -limit");
            x[i] = lim[i];
            assert!(!fault(0.0, x, z, policy), "x[{i}] at +limit");
            x[i] = lim[i] * (1.0 + f64::EPSILON);
            assert!(fault(0.0, x, z, policy), "x[{i}] just over");
            x[i] = -x[i];
            assert!(fault(0.0, x, z, policy), "x[{i}] just under -limit");
        }
        let none = FaultPolicy {
            limits: Limits::NONE,
            ..policy
        };
        assert!(!fault(0.0, [f64::MAX, -f64::MAX, 1e300], z, none));
        // Without limits, finiteness is the only guard: every component.
        for i in 0..3 {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                let mut x = [0.0; 3];
                x[i] = bad;
                assert!(fault(0.0, x, z, none), "x[{i}] = {bad} without limits");
            }
        }
    }

    /// A step whose ξ + dt·ξ̇ overflows is refused: the state is the one
    /// before (the spare buffer is not taken), the last command is held,
    /// and the controller keeps stepping from the old state.
    #[test]
    fn overflowing_state_is_refused_and_the_state_kept() {
        let r = Sine::paper();
        // dt = 1e306: the first Ẇ (|Ẇ[129]| ≈ 1009) overflows W.
        let mut c = SampledController::new(nn(), 1e306).unwrap();
        let before: NnState = *c.state();
        let o = c.step(0.0, [0.0; 3], r.z(0.0));
        assert_ne!(o.flags & flags::NON_FINITE_STATE, 0);
        assert_eq!(o.u, 0.0, "the last good command (none yet)");
        assert_eq!(*c.state(), before);
        assert_eq!(c.fault_count(), 1);
        // The same step with a usable dt from the same state: the double
        // buffer gives what a single buffer gives.
        let mut d = SampledController::new(nn(), 0.01).unwrap();
        let mut e = SampledController::new(nn(), 0.01).unwrap();
        for k in 0..5 {
            let t = 0.01 * f64::from(k);
            let (od, oe) = (
                d.step(t, [1e-3 * t; 3], r.z(t)),
                e.step(t, [1e-3 * t; 3], r.z(t)),
            );
            assert_eq!(od, oe);
        }
        let mut manual = NnState::zero();
        let ctl = nn();
        for k in 0..5 {
            let t = 0.01 * f64::from(k);
            let mut ds = NnState::zero();
            let _ = ctl.law(
                &Measurement {
                    t,
                    x: [1e-3 * t; 3],
                    z: r.z(t),
                },
                &manual,
                &mut ds,
            );
            manual.axpy(0.01, &ds);
        }
        assert_eq!(*d.state(), manual, "ξ ← ξ + dt·ξ̇, to the bit");
    }

    #[test]
    fn invalid_policies_are_rejected() {
        let bad = FaultPolicy {
            safe: SafeCommand::Zero,
            limits: Limits {
                x: [1.0, -1.0, 1.0],
                u: 1.0,
            },
        };
        assert_eq!(
            SampledController::with_policy(nn(), 0.01, bad)
                .unwrap_err()
                .name,
            "limits.x"
        );
        assert_eq!(SampledController::new(nn(), 0.0).unwrap_err().name, "dt");
    }
}
