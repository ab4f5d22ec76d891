//! Controllers as dynamic systems.
//!
//! A controller has a configuration (gains, surface, network) and a state ξ
//! (∫e, and for the NNBVSC the weights W). It is evaluated as
//! `u = h(t, ξ, x, z)` with `ξ̇ = f(t, ξ, x, z)` by [`Controller::law`], which
//! returns the parts of its law as plain fields ([`ControlOutput`]) and
//! writes ξ̇. It never integrates itself: the simulator (continuous or
//! sampled) or [`crate::sampled::SampledController`] (hardware) decides how ξ
//! advances.
//!
//! **The sign of the valve.** Both laws divide by the nominal gain
//! `b̄(t) = b(x, sgn u)`, which itself depends on `sgn(u)` through the valve
//! root (2). The circle is exact to break: with `β = bound_b·b̄`, the product
//! `v = b̄·u` does not depend on `b̄` (for (11)–(14):
//! `v = N + sgn(σ)·[Σα_i|x_i| + γ + bound_b·|N|]/(1 − bound_b)`; for
//! (23)–(25): `v = N + WᵀΦ + [γ1σΔ + γ2σΔ/(|σΔ| + μ)]/(1 − bound_b)`), and
//! `b̄ > 0`, so `sgn(u) = sgn(v)`; then `b̄ = b(x, sgn v)` and `u = v/b̄`.

pub mod nnvsc;
pub mod vsc;

use crate::rk4::OdeState;

/// What the controller measures at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Measurement {
    /// Time (s).
    pub t: f64,
    /// x = (θm, θ̇m, θ̈m) (rad, rad/s, rad/s²); Assumption A4.
    pub x: [f64; 3],
    /// z = (θd, θ̇d, θ̈d, θ⃛d); Assumption A3.
    pub z: [f64; 4],
}

/// Flags a law may raise (bit set in [`ControlOutput::flags`]).
pub mod flags {
    /// The valve root of (2) had a negative argument and was clamped at 0;
    /// the nominal gain b̄ was floored to keep u finite.
    pub const VALVE_ROOT_CLAMPED: u8 = 1;
    /// ‖E‖ = 0: σΔ, μ and ξ were set to 0 (no division by ‖E‖).
    pub const ZERO_ERROR_NORM: u8 = 2;
    /// A measurement was non-finite or out of its plausible range: the safe
    /// command was returned and the state left alone
    /// ([`crate::sampled::SampledController`]).
    pub const MEASUREMENT_FAULT: u8 = 4;
    /// The law produced a non-finite u or state derivative: the safe command
    /// was returned and the state left alone.
    pub const NON_FINITE_CONTROL: u8 = 8;
    /// u was clamped to the valve range.
    pub const SATURATED: u8 = 16;
}

/// The parts of a control law at one instant (like a PID's p, i, d terms).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ControlOutput {
    /// Control voltage u = u_eq + u_sw (V).
    pub u: f64,
    /// Equivalent control (12) or (24) (V).
    pub u_eq: f64,
    /// Switching control (13) or (25) (V).
    pub u_sw: f64,
    /// Tracking error e = θd − x1 (rad).
    pub e: f64,
    /// Switching function σ of (10) (rad/s²).
    pub sigma: f64,
    /// Dead-zone switching function σΔ of (27) (σ itself for the VSC).
    pub sigma_delta: f64,
    /// The network's estimate WᵀΦ (rad/s³); 0 for the VSC.
    pub wphi: f64,
    /// ‖Φ‖ (0 for the VSC).
    pub phi_norm: f64,
    /// ξ = ᾱ·EᵀĖ·sgn(σ)/‖E‖ of (19) (rad/s³); 0 for the VSC.
    pub xi: f64,
    /// Nominal gain b̄(t) used by the law (s⁻³V⁻¹).
    pub b_bar: f64,
    /// Switching gain: k of (14) for the VSC, γ2 of (34) for the NNBVSC.
    pub gain: f64,
    /// Boundary layer: μ(t) (NNBVSC, SPEC §5) or the constant μ (VSC-sat).
    pub mu: f64,
    /// ‖E‖.
    pub norm_e: f64,
    /// Bit set of [`flags`].
    pub flags: u8,
}

/// A control law with state.
pub trait Controller {
    /// The controller state ξ.
    type State: OdeState;

    /// Short name (`"vsc"`, `"vsc-sat"`, `"nnvsc"`).
    fn name(&self) -> &'static str;

    /// ξ(0): ∫e = 0 and W(0) = 0.
    fn initial_state(&self) -> Self::State;

    /// Evaluates the law at measurement `m` and state `s`; writes ξ̇ into
    /// `ds`. Infallible and allocation-free.
    fn law(&self, m: &Measurement, s: &Self::State, ds: &mut Self::State) -> ControlOutput;

    /// The network weights in `s` (empty for controllers without any).
    fn weights<'a>(&self, _s: &'a Self::State) -> &'a [f64] {
        &[]
    }
}
