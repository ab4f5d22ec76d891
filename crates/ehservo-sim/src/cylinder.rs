//! A valve-controlled linear cylinder as a plant: single-rod or double-rod,
//! the 4/3 valve of [`crate::valve`], the supply of [`crate::supply`], a
//! load (mass, spring, viscous and Stribeck friction, gravity on an
//! inclined axis, an external force signal), end stops, and cavitation.
//! `[plant] model = "cylinder"`; docs/cylinder.md has the derivations.
//!
//! State `[y, ẏ, p̃_A, p̃_B, p̃_s, x_r]` in SI (m, m/s, Pa, Pa, Pa,
//! m³/(s·√Pa)): the rod's extension y ∈ [0, stroke], its speed, the
//! pressure states of chamber A (the piston side, which grows with y),
//! chamber B (the rod side) and the supply line, and the relief valve's
//! opening (the last two constant with a fixed supply). Pressures are
//! absolute; the spool is the actuator stage's (`[actuator]`), the valve
//! reads its output.
//!
//! ```text
//! V_A = V_0A + A_A·y,   V_B = V_0B + A_B·(stroke − y)              (floored at 1 % of V_0)
//! p = max(p̃, 0)                                                    cavitation: a state below 0 is a cavity
//! (V_A/βe)·dp̃_A/dt = Q_A − A_A·ẏ − C_l·(p_A − p_B)
//! (V_B/βe)·dp̃_B/dt = Q_B + A_B·ẏ + C_l·(p_A − p_B)
//! M·ÿ = F_d − F_f,   F_d = A_A·p_A − A_B·p_B − (B + B_v)·ẏ − K·(y − y_K) − M·g·sin α − F(t) + F_stop(y, ẏ) − F_env
//! F_stop = max(k_s·(−y) − c_s·ẏ, 0)             for y < 0
//!        = min(k_s·(stroke − y) − c_s·ẏ, 0)      for y > stroke
//! ```
//!
//! **Friction** (`[plant.load.friction]`) is Karnopp's stick–slip model
//! (D. Karnopp, "Computer simulation of stick-slip friction in mechanical
//! dynamic systems", ASME J. Dyn. Sys., Meas., Control 107(1):100–103,
//! 1985; the Stribeck curve as in Armstrong-Hélouvry, Dupont, Canudas de
//! Wit, Automatica 30(7):1083–1138, 1994), with its force bounded
//! so that explicit RK4 cannot overshoot at any friction level. With
//! F_stop* = F_d + M·ẏ/τ, the force that leaves ÿ = −ẏ/τ:
//!
//! ```text
//! |ẏ| ≤ D_v = 10⁻³·v_s (stick window):  F_f = clamp(F_stop*, −F_s, F_s)       held while |F_stop*| ≤ F_s
//! |ẏ| > D_v (slip):  F_f = sgn(ẏ)·min(g(ẏ), max(sgn(ẏ)·F_stop*, 0)),   g = F_c + (F_s − F_c)·e^{−(ẏ/v_s)²}
//! ```
//!
//! So a rod at rest stays exactly at rest (ÿ = 0, ẏ = 0) while the other
//! forces are within ±F_s, whatever F_s is, and breaks away with
//! ÿ = (F_d ∓ F_s)/M beyond it; sliding friction opposes the motion and
//! never exceeds what stops the rod within τ, so it cannot reverse the
//! speed in a step, and a residual speed decays as e^{−t/τ}. τ = 1/ω_h
//! with ω_h = √(βe·(A_A²/V_A + A_B²/V_B)/M) at mid-stroke, a rate the
//! integrator already resolves (Plant::stiffness), so holding costs no
//! extra steps. The core's `smoothing` (tanh(ẏ/v₀)) is the nominal
//! model's only: the plant's sign is exact, its window D_v.
//!
//! The cavitation rule is Hopsan's (`HydraulicCylinderC` and
//! `Hydraulic43Valve`: a port whose pressure would fall below 0 is held at
//! 0 while its chamber keeps integrating the net flow, docs/hopsan/
//! position-servo.md, "The model as ODEs"): the pressure that acts on the
//! orifices and the piston is max(p̃, 0), and a cavity must be refilled
//! before the pressure rises again. End stops are a stiff spring-damper
//! contact that only pushes (no sticking), so a run goes on at the stop as
//! a real cylinder does; by default k_s is 100 times the oil column's
//! stiffness βe·(A_A²/V_A + A_B²/V_B) at mid-stroke and c_s = 2·√(k_s·M)
//! (critically damped): a modelling choice, stated, not a measured stop.
//! The stops' stated penetration δ ([`Cylinder::stated_penetration`]) is
//! where the stop has held the largest force that can press on it and
//! absorbed that force's work over the whole stroke; a rod beyond it is a
//! divergence ([`crate::simulation::DivergenceReason::BeyondEndStop`]).
//!
//! F_env is `[plant.environment]`'s force, when there is one: a specimen
//! with contact and lift-off or a preloaded spring, on a fixed or moving
//! mount ([`crate::environment`], docs/environments.md).
//!
//! With `[plant.transmission] radius = r` (a rack and pinion) the axis is
//! rotary: θ = (y − stroke/2)/r, the pinion at 0 with the piston at
//! mid-stroke.
//!
//! **Nominal model.** The controller is told the paper's third-order model
//! (8)–(9) of the axis, linearised at `[plant.nominal] position` (default
//! mid-stroke): the volumes there, Ā = (A_A + A_B)/2 as Dm, M as Jt, the
//! valve's land as the flow gain, and the single rod's direction-dependent
//! gain and the constant load as the valve's load-pressure offset
//! ([`NominalModel::with_offset`]); see [`CylinderPlant::nominal_model`].
//!
//! **Variation.** `[uncertainty.physical]` only: the mass, the bulk
//! modulus (chambers and supply line), the cross-piston leakage, the supply
//! pressure (a fixed supply's Ps, a pump's relief setting), every friction
//! force (viscous, Coulomb, stiction) and the load (spring, gravity,
//! external force), each scaled by `1 + bias + random·r`.

use crate::axis::{Axis, Quantity};
use crate::environment::Environment;
use crate::force::{Force, ForceCfg};
use crate::plant::{Draw, Plant, PlantConfig, PlantContext, UncertaintySpec, MAX_STATES};
use crate::supply::{Supply, SupplyCfg};
use crate::uncertainty::Factors;
use crate::valve::{SpoolValve, ValveCfg};
use ehservo_core::control::Signal;
use ehservo_core::math::sgn;
use ehservo_core::servo::{Friction, Load, NominalModel, ServoParams};
use serde::{Deserialize, Serialize};

#[path = "cylinder_cfg.rs"]
mod cfg;
pub use cfg::*;

/// Standard gravity g_n = 9.80665 m/s², exact by definition (3rd CGPM,
/// 1901; BIPM SI Brochure, 9th ed., 2019).
pub const STANDARD_GRAVITY: f64 = 9.806_65;

/// The kinematic viscosity of an ISO VG 46 hydraulic oil at 40 °C
/// (46 mm²/s: ISO 3448 names a viscosity grade by its mid-point kinematic
/// viscosity at 40 °C in mm²/s), the default of `[plant.fluid] viscosity`.
pub const ISO_VG46_VISCOSITY: f64 = 46e-6;

/// The validated cylinder's constants.
#[derive(Debug, Clone, PartialEq)]
pub struct Cylinder {
    /// A_A, A_B (m²).
    pub area: [f64; 2],
    /// Stroke (m).
    pub stroke: f64,
    /// Dead volumes (m³), with the hoses' equivalent volumes.
    pub v0: [f64; 2],
    /// C_l (m³/(s·Pa)).
    pub leakage: f64,
    /// B_p + external damping (N·s/m).
    pub viscous: f64,
    /// βe (Pa).
    pub beta: f64,
    /// ρ (kg/m³).
    pub rho: f64,
    /// M (kg).
    pub mass: f64,
    /// K (N/m).
    pub spring: f64,
    /// y_K (m).
    pub spring_origin: f64,
    /// M·g·sin α (N).
    pub gravity_force: f64,
    /// Friction of the rod.
    pub friction: Option<Friction>,
    /// The external force.
    pub force: Force,
    /// A further external force on the rod, held (N, opposing extension;
    /// 0 unless a plant FMU's importer sets it: [`Plant::set_external_load`]).
    /// Not scaled by the load factor: it is the importer's, not the
    /// scenario's.
    pub external: f64,
    /// k_s, c_s of the end stops.
    pub stop: [f64; 2],
    /// The stops' stated penetration δ at factors 1 (m):
    /// [`Cylinder::stated_penetration`].
    pub penetration: f64,
    /// 1/τ, the rate at which held friction stops the rod (1/s): the oil
    /// column's ω_h = √(βe·(A_A²/V_A + A_B²/V_B)/M) at mid-stroke.
    pub stick_rate: f64,
    /// The valve.
    pub valve: SpoolValve,
    /// The supply.
    pub supply: Supply,
    /// Tank pressure (Pa).
    pub pt: f64,
    /// Pinion radius, when the axis is rotary.
    pub radius: Option<f64>,
    /// p_A(0), p_B(0) when given.
    pub initial: [Option<f64>; 2],
    /// The longer hose's pressure drop at the valve's full flow (Pa; 0
    /// without `[plant.hose]`): [`crate::hose::HoseCfg::drop`].
    pub hose_drop: f64,
    /// What the rod works against beyond its load (`[plant.environment]`).
    pub environment: Option<Environment>,
}

/// The cylinder plant.
///
/// Built from `[plant] model = "cylinder"`'s tables by
/// [`CylinderCfg`]'s [`build`](crate::plant::PlantConfig::build), whose
/// example evaluates its derivative.
#[derive(Debug, Clone)]
pub struct CylinderPlant {
    c: Cylinder,
    model: NominalModel,
    /// What x₀ is: the rod's position (the default), the environment's
    /// force or the load pressure (`[reference] quantity`).
    output: Quantity,
}

/// One hold interval's variation of a cylinder.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CylinderVariation {
    /// The physical factors.
    pub f: Factors,
}

/// The cylinder's physical states in a trace.
const CYLINDER_STATES: [Signal; 6] = [
    Signal::new(
        "p_a",
        "p_a_Pa",
        "Pa",
        "pressure of chamber A (piston side), max(p̃_A, 0)",
    ),
    Signal::new(
        "p_b",
        "p_b_Pa",
        "Pa",
        "pressure of chamber B (rod side), max(p̃_B, 0)",
    ),
    Signal::new("p_supply", "p_supply_Pa", "Pa", "supply pressure"),
    Signal::new(
        "relief",
        "relief_m3_s_sqrtPa",
        "m³/(s·√Pa)",
        "relief valve opening (flow coefficient)",
    ),
    Signal::new(
        "f_load",
        "f_load_N",
        "N",
        "load force on the rod: spring, gravity and F(t)",
    ),
    Signal::new("f_stop", "f_stop_N", "N", "end-stop contact force"),
];

/// The states of a cylinder with an environment: [`CYLINDER_STATES`] and
/// the environment's force (a column only then, so that a cylinder
/// without one keeps its trace).
const ENVIRONMENT_STATES: [Signal; 7] = [
    CYLINDER_STATES[0],
    CYLINDER_STATES[1],
    CYLINDER_STATES[2],
    CYLINDER_STATES[3],
    CYLINDER_STATES[4],
    CYLINDER_STATES[5],
    Signal::new(
        "f_env",
        "f_env_N",
        "N",
        "force of the environment on the rod, opposing extension (specimen or spring)",
    ),
];

/// Karnopp's velocity window as a share of the Stribeck velocity v_s:
/// the friction may hold the rod at |ẏ| ≤ 10⁻³·v_s. Small beside the
/// friction curve's own velocity scale, so that a rod sliding at the
/// Coulomb level is not caught (Karnopp 1985 asks for a window small
/// against the velocities of interest); the held rod's residual speed
/// decays at 1/τ, so the window need not be crossed in one step.
pub const STICK_WINDOW: f64 = 1e-3;

/// The rod's dry friction at a state ([`Cylinder::dry_friction`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DryFriction {
    /// The force, opposing extension (N).
    pub force: f64,
    /// Whether it holds the rod (stuck in the window, or sliding friction
    /// bounded by the force that stops the rod within τ): ÿ = −ẏ/τ.
    pub held: bool,
    /// d(force)/dẏ of the sliding law when not held (N·s/m).
    pub slope: f64,
}

impl DryFriction {
    /// No dry friction.
    pub const NONE: Self = Self {
        force: 0.0,
        held: false,
        slope: 0.0,
    };
}

/// The volumes' floor as a share of the dead volume: a stop's
/// penetration can otherwise shrink a chamber to nothing.
pub const VOLUME_FLOOR: f64 = 0.01;

impl Cylinder {
    /// The chamber volumes at y (floored at 1 % of the dead volume).
    #[inline]
    pub fn volumes(&self, y: f64) -> [f64; 2] {
        [
            (self.v0[0] + self.area[0] * y).max(VOLUME_FLOOR * self.v0[0]),
            (self.v0[1] + self.area[1] * (self.stroke - y)).max(VOLUME_FLOOR * self.v0[1]),
        ]
    }

    /// The stop's force at y, ẏ (only pushing).
    #[inline]
    pub fn stop_force(&self, y: f64, v: f64) -> f64 {
        let [k, c] = self.stop;
        if y < 0.0 {
            (-k * y - c * v).max(0.0)
        } else if y > self.stroke {
            (k * (self.stroke - y) - c * v).min(0.0)
        } else {
            0.0
        }
    }

    /// The supply pressure acting at the valve for the state `ps_state`
    /// (a fixed supply's Ps scaled by the variation).
    #[inline]
    fn supply_pressure(&self, ps_state: f64, f: &Factors) -> f64 {
        self.supply.pressure(ps_state, f.supply_pressure)
    }

    /// The load force on the rod (N, opposing extension): the spring and
    /// F(t) scaled by the load factor, and the weight M·g·sin α scaled by
    /// the mass factor (a heavier load weighs more as it is harder to
    /// accelerate: one mass, one factor); and its rate.
    #[inline]
    fn load_force(&self, t: f64, y: f64, v: f64, f: &Factors) -> (f64, f64) {
        let (fe, fe_rate) = self.force.at(t);
        let spring = self.spring * (y - self.spring_origin);
        (
            f.load * (spring + fe) + f.mass * self.gravity_force + self.external,
            f.load * (self.spring * v + fe_rate),
        )
    }

    /// The viscous coefficient on the rod, B_p + damping + the friction's
    /// B_v, scaled (N·s/m).
    #[inline]
    pub fn viscous_coeff(&self, f: &Factors) -> f64 {
        f.friction * (self.viscous + self.friction.map_or(0.0, |fr| fr.viscous))
    }

    /// The sliding law's dry part, sgn(ẏ)·g(ẏ) with g = F_c + (F_s − F_c)·
    /// e^{−(ẏ/v_s)²}, scaled, and its slope d/dẏ (0 at rest and without
    /// friction).
    #[inline]
    fn slip(&self, v: f64, f: &Factors) -> (f64, f64) {
        let Some(fr) = &self.friction else {
            return (0.0, 0.0);
        };
        let s = sgn(v);
        let r = v / fr.stribeck_velocity;
        let e = (-r * r).exp();
        let g = f.friction * (fr.coulomb + (fr.stiction - fr.coulomb) * e);
        let dg = f.friction * (fr.stiction - fr.coulomb) * e * (-2.0 * r / fr.stribeck_velocity);
        (s * g, s * dg)
    }

    /// The dry friction at ẏ = `v` under the drive `drive` (every other
    /// force on the rod, N) for the moving mass `m`: Karnopp's stick–slip
    /// model with its force bounded by the one that stops the rod within
    /// τ = 1/[`Cylinder::stick_rate`] (the module doc).
    #[inline]
    pub fn dry_friction(&self, v: f64, drive: f64, m: f64, f: &Factors) -> DryFriction {
        let Some(fr) = &self.friction else {
            return DryFriction::NONE;
        };
        // The force that leaves ÿ = −ẏ/τ: the rod held, its residual speed
        // decaying.
        let stop = drive + m * v * self.stick_rate;
        if v.abs() <= STICK_WINDOW * fr.stribeck_velocity {
            let fs = f.friction * fr.stiction;
            return DryFriction {
                force: stop.clamp(-fs, fs),
                held: stop.abs() <= fs,
                slope: 0.0,
            };
        }
        let (force, slope) = self.slip(v, f);
        // Sliding friction opposes the motion and never more than stops
        // it: it cannot reverse the speed, whatever its size.
        // (When the other forces alone stop it faster than τ, none.)
        let cap = sgn(v) * stop;
        if force.abs() <= cap {
            DryFriction {
                force,
                held: false,
                slope,
            }
        } else if cap > 0.0 {
            DryFriction {
                force: sgn(v) * cap,
                held: true,
                slope: 0.0,
            }
        } else {
            DryFriction::NONE
        }
    }

    /// The stated penetration δ of the end stops under the factors `f`
    /// (m): the depth at which a stop of stiffness k_s holds the largest
    /// force F that can press the rod into it and has absorbed that
    /// force's work over the whole stroke L, ½·k_s·δ² = F·(L + δ):
    /// δ = (F + √(F² + 2·k_s·F·L))/k_s, with F = A_A·p_max + |M·g·sin α| +
    /// max|F(t)| + K·max(|y_K|, |L − y_K|), p_max the supply's holding
    /// pressure (docs/cylinder.md, "End stops"). The factors scale F by at
    /// most their largest, and δ(c·F) ≤ c·δ(F) for c ≥ 1.
    pub fn stated_penetration(&self, f: &Factors) -> f64 {
        let scale = [f.supply_pressure, f.mass, f.load]
            .into_iter()
            .fold(1.0f64, f64::max);
        scale * self.penetration
    }

    /// Whether y lies outside the stroke by more than the stops' stated
    /// penetration ([`Cylinder::stated_penetration`]): the model no longer
    /// holds, a divergence.
    #[inline]
    pub fn beyond_stops(&self, y: f64, f: &Factors) -> bool {
        let d = self.stated_penetration(f);
        !(-d..=self.stroke + d).contains(&y)
    }

    /// The dry friction at the state `s` at time `t` ([`Cylinder::dry_friction`]
    /// under the state's other forces).
    pub fn friction_at(&self, t: f64, s: &[f64; 6], f: &Factors) -> DryFriction {
        self.forces(t, s, f).3
    }

    /// The net force on the rod and the parts a trace shows (load, stop),
    /// with the dry friction's state.
    #[inline]
    fn forces(&self, t: f64, s: &[f64; 6], f: &Factors) -> (f64, f64, f64, DryFriction) {
        let [y, v, pa, pb, _, _] = *s;
        let (pa, pb) = (pa.max(0.0), pb.max(0.0));
        let (fl, _) = self.load_force(t, y, v, f);
        let fs = self.stop_force(y, v);
        let mut drive = self.area[0] * pa - self.area[1] * pb - self.viscous_coeff(f) * v - fl + fs;
        if let Some(e) = &self.environment {
            drive -= e.force(t, y, v);
        }
        let dry = self.dry_friction(v, drive, self.mass * f.mass, f);
        (drive - dry.force, fl, fs, dry)
    }

    /// The state derivative under the spool command `u` (V).
    #[inline]
    pub fn deriv(&self, t: f64, s: &[f64; 6], u: f64, f: &Factors, ds: &mut [f64; 6]) {
        let [y, v, pa_s, pb_s, ps_s, xr] = *s;
        let (pa, pb) = (pa_s.max(0.0), pb_s.max(0.0));
        let ps = self.supply_pressure(ps_s, f);
        let xv = self.valve.spool(u);
        let q = self.valve.flows(xv, ps, self.pt, pa, pb);
        let [va, vb] = self.volumes(y);
        let beta = self.beta * f.bulk_modulus;
        let leak = self.leakage * f.leakage * (pa - pb);
        let (force, _, _, _) = self.forces(t, s, f);
        ds[0] = v;
        ds[1] = force / (self.mass * f.mass);
        ds[2] = beta / va * (q.a - self.area[0] * v - leak);
        ds[3] = beta / vb * (q.b + self.area[1] * v + leak);
        [ds[4], ds[5]] = self
            .supply
            .deriv(ps, xr, self.pt, q.p, f.supply_pressure, f.bulk_modulus);
    }

    /// The largest rate the state's dynamics have here (1/s): chamber and
    /// supply pressure time constants through the open edges, the oil
    /// column, a stop in contact, friction, the relief spool.
    pub fn stiffness(&self, t: f64, s: &[f64; 6], u: f64, f: &Factors) -> f64 {
        let [y, _, pa_s, pb_s, ps_s, _] = *s;
        let (pa, pb) = (pa_s.max(0.0), pb_s.max(0.0));
        let ps = self.supply_pressure(ps_s, f);
        let pt = self.pt;
        let xv = self.valve.spool(u);
        let o = self.valve.openings(xv);
        let slope = |i: usize, dp: f64| self.valve.orifice_slope(self.valve.cdw[i] * o[i], dp);
        let (s_pa, s_pb, s_at, s_bt) = (
            slope(0, ps - pa),
            slope(1, ps - pb),
            slope(2, pa - pt),
            slope(3, pb - pt),
        );
        let [va, vb] = self.volumes(y);
        let beta = self.beta * f.bulk_modulus;
        let cl = self.leakage * f.leakage;
        let m = self.mass * f.mass;
        let mut lam = beta / va * (s_pa + s_at + cl);
        lam = lam.max(beta / vb * (s_pb + s_bt + cl));
        let kh = beta * (self.area[0] * self.area[0] / va + self.area[1] * self.area[1] / vb);
        lam = lam.max((kh / m).sqrt());
        if y < 0.0 || y > self.stroke {
            lam = lam.max((self.stop[0] / m).sqrt() + self.stop[1] / m);
        }
        if let Some(e) = &self.environment {
            // The environment's spring beside the oil column's, and its
            // damper: a bound whether or not it touches.
            lam = lam.max(((kh + e.stiffness) / m).sqrt() + e.damping / m);
        }
        // Friction: the viscous terms, and the dry force's slope when it
        // slides or the rate 1/τ at which it holds the rod.
        lam = lam.max(self.viscous_coeff(f) / m);
        let (_, _, _, dry) = self.forces(t, s, f);
        lam = lam.max(if dry.held {
            self.stick_rate
        } else {
            dry.slope.abs() / m
        });
        match &self.supply {
            Supply::Pump(p) => {
                let relief = p.x_max.max(s[5]) * 0.5 / (ps - pt).max(1.0).sqrt();
                lam = lam.max(p.stiffness * f.bulk_modulus * (p.leakage + relief + s_pa + s_pb));
                lam = lam.max(p.rate);
            }
            Supply::PcPump(p) => {
                // The line through the leakage and the valve's edges, and the
                // regulator's rates: g2 and the lead's feedthrough of ṗ,
                // (βe/V_s)/(ω_p1·d).
                let k = p.beta * f.bulk_modulus / p.volume;
                let d = p.denom(ps);
                lam = lam.max(k * (p.leakage + s_pa + s_pb));
                lam = lam.max(p.r_p / d + k / (p.lead * d));
            }
            Supply::Fixed { .. } => {}
        }
        lam
    }

    /// The state at t = 0 with the rod at y0 moving at v0 and accelerating
    /// at a0 (the pressures then hold that force), or the given pressures.
    pub fn initial_state(&self, y0: f64, v0: f64, a0: f64, f: &Factors) -> [f64; 6] {
        let (ps0, x0) = match &self.supply {
            Supply::Fixed { ps } => (ps * f.supply_pressure, 0.0),
            Supply::Pump(p) => (p.p0, 0.0),
            // Hopsan's regulator starts at full stroke (y0 = q_max·d,
            // HydraulicPressureControlledPump.hpp lines 128–133).
            Supply::PcPump(p) => (p.p0, p.y_max(p.p0)),
        };
        let [pa, pb] = match self.initial {
            [Some(a), Some(b)] => [a, b],
            _ => {
                // Hold m·a0 + the load at y0 about the mid pressure of the
                // supply it will have: A_A·p_A − A_B·p_B = F with
                // p_A + p_B = 2·p_m, p_A = (F + 2·A_B·p_m)/(A_A + A_B).
                let ps = self.supply.holding_pressure(self.pt) * f.supply_pressure;
                let pm = 0.5 * (ps + self.pt);
                let (mut fl, _) = self.load_force(0.0, y0, v0, f);
                if let Some(e) = &self.environment {
                    fl += e.force(0.0, y0, v0);
                }
                // Moving: the sliding friction; at rest none is needed.
                let ff = self.viscous_coeff(f) * v0 + self.slip(v0, f).0;
                let force = self.mass * f.mass * a0 + fl + ff - self.stop_force(y0, v0);
                let [a, b] = self.area;
                let pa = (force + 2.0 * b * pm) / (a + b);
                [pa, 2.0 * pm - pa]
            }
        };
        [y0, v0, pa, pb, ps0, x0]
    }
}

impl CylinderPlant {
    /// From a validated cylinder.
    pub fn new(c: Cylinder, y_nominal: f64) -> Self {
        let model = Self::nominal_model(&c, y_nominal);
        Self {
            c,
            model,
            output: Quantity::Position,
        }
    }

    /// The same plant measuring `q` as x₀, with the rod's velocity and
    /// acceleration as x₁ and x₂ when `q` is not the position
    /// (docs/force-control.md). The loader checks that `q` can be
    /// measured (an environment for a force, a rod without a pinion).
    pub fn with_output(mut self, q: Quantity) -> Self {
        self.output = q;
        self
    }

    /// The load pressure p_L = p_A − α·p_B, α = A_B/A_A, of the chamber
    /// pressures as the trace gives them (max(p̃, 0)).
    #[inline]
    pub fn load_pressure(&self, s: &[f64; 6]) -> f64 {
        let a = &self.c.area;
        s[2].max(0.0) - a[1] / a[0] * s[3].max(0.0)
    }

    /// The cylinder.
    pub fn cylinder(&self) -> &Cylinder {
        &self.c
    }

    /// The paper's third-order model of this axis at the rod position `y`
    /// (docs/cylinder.md, "The nominal model"):
    ///
    /// | paper | cylinder (r = 1 m without a transmission) |
    /// |---|---|
    /// | Dm | Ā·r, Ā = (A_A + A_B)/2 |
    /// | Jt, Bm, G | M·r², B·r², K·r² |
    /// | Vt | 4Ā²/(A_A²/V_A + A_B²/V_B) at y |
    /// | Kce | C_l·Ā·(A_A/V_A + A_B/V_B)/(A_A²/V_A + A_B²/V_B), plus the valve's Kc at null |
    /// | Ag | w·Ā·√(2Ā/(A_A³ + A_B³)), w the P→A land's area gradient |
    /// | Ps | holding supply pressure − Pt |
    /// | offset | (ΔA·(Ps + Pt) − F₀)/Ā, ΔA = (A_A − A_B)/2, F₀ the static load |
    ///
    /// so that b(x, sgn u) is the single rod's gain in each direction,
    /// b₊ ∝ √(A_A·Ps' − F) and b₋ ∝ √(A_B·Ps' + F), and a double-rod
    /// cylinder at mid-stroke is exactly the paper's servo.
    ///
    /// ```
    /// use ehservo_sim::cylinder::{CylinderCfg, CylinderPlant};
    /// use ehservo_sim::plant::PlantConfig;
    /// # use ehservo_sim::plant::{PlantContext, UncertaintySpec};
    /// # let ctx = PlantContext {
    /// #     load: None,
    /// #     load_given: false,
    /// #     uncertainty: UncertaintySpec::NONE,
    /// #     x0: [0.0; 3],
    /// #     base_dir: None,
    /// #     reference_range: None,
    /// #     quantity: Default::default(),
    /// # };
    /// // A double-rod cylinder: A = π(D² − d²)/4 on both sides.
    /// let cfg: CylinderCfg = toml::from_str(r#"
    /// [cylinder]
    /// bore = 0.063
    /// rod_diameter = 0.036
    /// rods = 2
    /// stroke = 0.5
    /// dead_volume_a = 2e-4
    /// dead_volume_b = 2e-4
    /// [fluid]
    /// density = 870.0
    /// bulk_modulus = 1.4e9
    /// [valve]
    /// spool_limit = 5e-4
    /// gain = 5e-5
    /// discharge_coefficient = 0.65
    /// area_gradient = 0.02
    /// [supply]
    /// kind = "fixed"
    /// pressure = 2e7
    /// [load]
    /// mass = 250.0
    /// "#).unwrap();
    /// let plant = cfg.build(&ctx).unwrap();
    /// let m = CylinderPlant::nominal_model(plant.cylinder(), 0.25).params;
    /// let a = std::f64::consts::PI / 4.0 * (0.063 * 0.063 - 0.036 * 0.036);
    /// // Dm = Ā = A, Jt = M; at mid-stroke both chambers hold V = V0 + A·0.25,
    /// // so Vt = 4A²/(A²/V + A²/V) = 2V.
    /// assert!((m.dm - a).abs() < 1e-15 && m.jt == 250.0);
    /// let vol = 2e-4 + a * 0.25;
    /// assert!((m.vt - 2.0 * vol).abs() < 1e-15);
    /// ```
    pub fn nominal_model(c: &Cylinder, y: f64) -> NominalModel {
        let [aa, ab] = c.area;
        let abar = 0.5 * (aa + ab);
        let da = 0.5 * (aa - ab);
        let [va, vb] = c.volumes(y);
        let s2 = aa * aa / va + ab * ab / vb;
        let vt = 4.0 * abar * abar / s2;
        let ps_abs = c.supply.holding_pressure(c.pt);
        let ps = ps_abs - c.pt;
        let w = c.valve.cdw[0] / c.valve.cd;
        let ag = w * abar * (2.0 * abar / (aa * aa * aa + ab * ab * ab)).sqrt();
        // The valve's flow-pressure coefficient at null, Kc = (Kc_A + Kc_B)/4
        // of the load flow, from the edges' slopes at the mid pressure (0
        // for a critically centred or overlapped valve).
        let pm = 0.5 * (ps_abs + c.pt);
        let o = c.valve.openings(0.0);
        let sl = |i: usize, dp: f64| c.valve.orifice_slope(c.valve.cdw[i] * o[i], dp);
        let kc_a = sl(0, ps_abs - pm) + sl(2, pm - c.pt);
        let kc_b = sl(1, ps_abs - pm) + sl(3, pm - c.pt);
        let kc = 0.25 * (kc_a + kc_b);
        let kce = c.leakage * abar * (aa / va + ab / vb) / s2 + kc;
        let r = c.radius.unwrap_or(1.0);
        let f0 = c.gravity_force + c.force.static_part() - c.spring * c.spring_origin;
        let offset = (da * (ps_abs + c.pt) - f0) / abar;
        let params = ServoParams {
            ps,
            beta_e: c.beta,
            vt,
            kce,
            dm: abar * r,
            jt: c.mass * r * r,
            bm: c.viscous * r * r,
            kv: c.valve.kv,
            g: c.spring * r * r,
            rho: c.rho,
            cd: c.valve.cd,
            ag,
        };
        // The rod's friction, as a torque on the pinion with a transmission.
        let friction = c.friction.map(|f| Friction {
            coulomb: f.coulomb * r,
            stiction: f.stiction * r,
            stribeck_velocity: f.stribeck_velocity / r,
            viscous: f.viscous * r * r,
            smoothing: f.smoothing / r,
        });
        let load = Load {
            amplitude: 0.0,
            wavenumber: 0.0,
            friction,
        };
        NominalModel::with_offset(params, load, offset)
    }

    /// The rod position and speed for the axis's x.
    #[inline]
    fn to_rod(&self, p: f64, v: f64) -> (f64, f64) {
        match self.c.radius {
            None => (p, v),
            Some(r) => (0.5 * self.c.stroke + r * p, r * v),
        }
    }

    /// The storage of docs/cylinder.md §"Energy": kinetic, spring, gravity,
    /// stop and the chambers' compression energy `V·g(p)`,
    /// g(p) = βe·(e^{p/βe} − 1) − p (J). Without F(t), whose work is
    /// counted as a port; with the environment's E(δ) at time `t`
    /// ([`Environment::stored`]).
    pub fn storage(&self, t: f64, s: &[f64; 6]) -> f64 {
        let c = &self.c;
        let [y, v, pa, pb, _, _] = *s;
        let [va, vb] = c.volumes(y);
        let g = |p: f64| c.beta * (p / c.beta).exp_m1() - p;
        let pen = if y < 0.0 {
            -y
        } else if y > c.stroke {
            y - c.stroke
        } else {
            0.0
        };
        0.5 * c.mass * v * v
            + 0.5 * c.spring * (y - c.spring_origin).powi(2)
            + c.gravity_force * y
            + 0.5 * c.stop[0] * pen * pen
            + va * g(pa)
            + vb * g(pb)
            + c.environment.as_ref().map_or(0.0, |e| e.stored(t, y))
    }

    /// The hydraulic potential π(p) = βe·(e^{p/βe} − 1) of fluid at p in
    /// this constant-βe model (docs/cylinder.md §"Energy").
    pub fn potential(&self, p: f64) -> f64 {
        self.c.beta * (p / self.c.beta).exp_m1()
    }

    /// The power balance's terms at a state (no cavitation, fixed supply):
    /// `(port power π_s·Q_P − π_t·Q_T − F(t)·ẏ, dissipation)` (W), with the
    /// valve's, the leakage's, the viscous, the friction's and the stop's
    /// losses; with an environment, its mount's power in the port and its
    /// damping in the losses ([`Environment::power`]).
    pub fn power(&self, t: f64, s: &[f64; 6], u: f64) -> (f64, f64) {
        let c = &self.c;
        let f = Factors::ONE;
        let [y, v, pa, pb, ps_s, _] = *s;
        let ps = c.supply_pressure(ps_s, &f);
        let xv = c.valve.spool(u);
        let q = c.valve.flows(xv, ps, c.pt, pa, pb);
        let pi = |p: f64| self.potential(p);
        let o = c.valve.openings(xv);
        let edges = [(0, ps, pa), (1, ps, pb), (2, pa, c.pt), (3, pb, c.pt)];
        let valve_loss: f64 = edges
            .iter()
            .map(|&(i, hi, lo)| c.valve.orifice(c.valve.cdw[i] * o[i], hi - lo) * (pi(hi) - pi(lo)))
            .sum();
        let leak = c.leakage * (pa - pb) * (pi(pa) - pi(pb));
        let (_, _, _, dry) = c.forces(t, s, &f);
        let ff = c.viscous_coeff(&f) * v + dry.force;
        let stop = if y < 0.0 || y > c.stroke {
            // Only the damper dissipates; the spring is stored.
            let fs = c.stop_force(y, v);
            let spring = if y < 0.0 {
                -c.stop[0] * y
            } else {
                c.stop[0] * (c.stroke - y)
            };
            -(fs - spring) * v
        } else {
            0.0
        };
        let (fe, _) = c.force.at(t);
        let (env_port, env_loss) = c
            .environment
            .as_ref()
            .map_or((0.0, 0.0), |e| e.power(t, y, v));
        let port = pi(ps) * q.p - pi(c.pt) * q.t - fe * v + env_port;
        (port, valve_loss + leak + ff * v + stop + env_loss)
    }
}

impl Plant for CylinderPlant {
    type State = [f64; 6];
    type Variation = CylinderVariation;
    type Prepared = ();
    const STATES: &'static [Signal] = &CYLINDER_STATES;
    const EXTERNAL_LOAD: bool = true;

    /// A force on the rod, or through a pinion of radius r a torque T on
    /// it, the rod's force T/r (the pinion turns positive as the rod
    /// extends, so a positive torque opposes it as a positive force does).
    fn set_external_load(&mut self, load: f64) {
        self.c.external = match self.c.radius {
            None => load,
            Some(r) => load / r,
        };
    }

    fn axis(&self) -> Axis {
        if self.c.radius.is_some() {
            Axis::Rotary
        } else {
            self.output.axis_on(Axis::Linear)
        }
    }

    /// The rod at y < 0 or y > stroke ([`Cylinder::stop_force`] acts
    /// there), as the axis's x₀: the rod's y, or (y − stroke/2)/r through
    /// a pinion of radius r.
    fn end_stops(&self) -> Option<[f64; 2]> {
        if !self.output.is_position() {
            // x₀ is a force or a pressure: the stops' contacts are not
            // seen in it (the trace's f_stop_N shows them).
            return None;
        }
        let half = 0.5 * self.c.stroke;
        Some(match self.c.radius {
            None => [0.0, self.c.stroke],
            Some(r) => [-half / r, half / r],
        })
    }

    /// The rod outside [−δ, stroke + δ], δ the stops' stated penetration
    /// ([`Cylinder::stated_penetration`]).
    #[inline]
    fn beyond_stops(&self, s: &[f64; 6], v: &CylinderVariation) -> bool {
        self.c.beyond_stops(s[0], &v.f)
    }

    fn states(&self, t: f64, s: &[f64; 6], _x: &[f64; 3], out: &mut [f64; MAX_STATES]) {
        let f = Factors::ONE;
        let (_, fl, fs, _) = self.c.forces(t, s, &f);
        out[..6].copy_from_slice(&[
            s[2].max(0.0),
            s[3].max(0.0),
            self.c.supply_pressure(s[4], &f),
            // A pressure-compensated pump has no relief: its slot holds
            // the regulator's state, not an opening.
            if matches!(self.c.supply, Supply::PcPump(_)) {
                0.0
            } else {
                s[5]
            },
            fl,
            fs,
        ]);
        if let Some(e) = &self.c.environment {
            out[6] = e.force(t, s[0], s[1]);
        }
    }

    /// [`CYLINDER_STATES`], and the environment's force when there is one.
    fn signals(&self) -> &'static [Signal] {
        match self.c.environment {
            None => &CYLINDER_STATES,
            Some(_) => &ENVIRONMENT_STATES,
        }
    }

    fn initial_state(&self, x0: [f64; 3], v: &CylinderVariation) -> [f64; 6] {
        let (y, yd) = self.to_rod(x0[0], x0[1]);
        let r = self.c.radius.unwrap_or(1.0);
        self.c.initial_state(y, yd, r * x0[2], &v.f)
    }

    #[inline]
    fn measure(&self, t: f64, s: &[f64; 6], v: &CylinderVariation) -> [f64; 3] {
        let (force, _, _, _) = self.c.forces(t, s, &v.f);
        let a = force / (self.c.mass * v.f.mass);
        match self.c.radius {
            None => match self.output {
                Quantity::Position => [s[0], s[1], a],
                Quantity::Force => [
                    self.c
                        .environment
                        .as_ref()
                        .map_or(0.0, |e| e.force(t, s[0], s[1])),
                    s[1],
                    a,
                ],
                Quantity::LoadPressure => [self.load_pressure(s), s[1], a],
            },
            Some(r) => [(s[0] - 0.5 * self.c.stroke) / r, s[1] / r, a / r],
        }
    }

    #[inline]
    fn deriv(&self, t: f64, s: &[f64; 6], u: f64, v: &CylinderVariation, ds: &mut [f64; 6]) {
        self.c.deriv(t, s, u, &v.f, ds);
    }

    /// The supply's second state (the relief valve's opening, or the
    /// compensator's regulator) back inside its limits
    /// ([`Supply::limit_opening`]).
    #[inline]
    fn limit_state(&self, s: &mut [f64; 6]) {
        s[5] = self.c.supply.limit_opening(s[4], s[5]);
    }

    #[inline]
    fn stiffness(&self, t: f64, s: &[f64; 6], u: f64, v: &CylinderVariation) -> f64 {
        self.c.stiffness(t, s, u, &v.f)
    }

    fn nominal(&self) -> &NominalModel {
        &self.model
    }

    fn variation(&self, spec: &UncertaintySpec, r: &Draw) -> CylinderVariation {
        CylinderVariation {
            f: spec.physical.factors(&r.physical),
        }
    }

    /// (19) at the applied command: `x⃛_model(u) − x⃛_true + d̄(x)`, the
    /// nominal model's jerk under u against the cylinder's, plus the
    /// nominal load term; equal to `Σ Δa_i x_i − Δb·u + d` where the
    /// paper's form has u_eq in place of u (docs/cylinder.md).
    fn lumped_uncertainty(
        &self,
        s: &[f64; 6],
        x: &[f64; 3],
        u: f64,
        _u_eq: f64,
        _b_bar: f64,
        v: &CylinderVariation,
    ) -> f64 {
        let c = &self.c;
        let f = &v.f;
        let mut ds = [0.0; 6];
        c.deriv(0.0, s, u, f, &mut ds);
        // (F(t)'s rate at t = 0: the diagnostic of a time-varying force is
        // approximate; the dynamics are not.)
        let [y, yd, pa, pb, _, _] = *s;
        let dpa = if pa > 0.0 { ds[2] } else { 0.0 };
        let dpb = if pb > 0.0 { ds[3] } else { 0.0 };
        let (_, mut fl_rate) = c.load_force(0.0, y, yd, f);
        let (_, _, _, dry) = c.forces(0.0, s, f);
        let ydd = ds[1];
        if let Some(e) = &c.environment {
            fl_rate += e.rate(0.0, y, yd, ydd);
        }
        let stop_rate = if y < 0.0 || y > c.stroke {
            -c.stop[0] * yd - c.stop[1] * ydd
        } else {
            0.0
        };
        // Held by friction, ÿ = −ẏ/τ whatever the other forces do.
        let jerk = if dry.held {
            -c.stick_rate * ydd
        } else {
            let dfdv = c.viscous_coeff(f) + dry.slope;
            (c.area[0] * dpa - c.area[1] * dpb - dfdv * ydd - fl_rate + stop_rate)
                / (c.mass * f.mass)
        } / c.radius.unwrap_or(1.0);
        let m = &self.model;
        let a = m.coeffs.as_array();
        let (b, d) = m.b_and_d(x, sgn(u));
        let model = -a[0] * x[0] - a[1] * x[1] - a[2] * x[2] + b * u - d;
        model - jerk + d
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of some checks
#[path = "cylinder_tests.rs"]
mod tests;
