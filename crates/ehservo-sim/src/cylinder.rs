//! A valve-controlled double-rod cylinder on a rack and pinion as a
//! [`Plant`]: state `[y, ẏ, P1, P2]` in SI (m, m/s, Pa, Pa), output
//! θ = y/r (docs/cylinder.md, [`CylinderParams`] for the equations).
//!
//! The controller is told the paper's model with the parameters the
//! cylinder linearises to ([`CylinderParams::nominal_servo_params`]) and the
//! scenario's load; what the linearisation drops (chamber volumes varying
//! with y, the common-mode pressure, the seal friction) is what the
//! controller does not know. The scenario's `[load]` is a torque on the
//! pinion shaft: a force `Tl/r` on the rod.
//!
//! **Variations** are carried as on [`PhysicalPlant`](crate::plant::PhysicalPlant):
//! both valve flows scaled by `1 + δb`, and the `Δa_i` as a load-pressure
//! rate `−(M·r/A)·Σ Δa_i·x_i` split evenly between the chambers, which adds
//! exactly `−Σ Δa_i·x_i` to θ⃛. [`Plant::lumped_uncertainty`] is the
//! default one: the variation's part only, not the cylinder's own mismatch.
//!
//! **Stroke.** End stops are not modelled. The scenario's `theta_limit` is
//! lowered to the stroke's angle, so a run whose |θ| reaches the end of the
//! stroke stops as diverged; the chamber volumes are floored at their
//! end-of-stroke values so that a last RK4 stage past it stays finite.

use crate::plant::{Plant, Variation, MAX_STATES};
use ehservo_core::control::Signal;
use ehservo_core::cylinder::CylinderParams;
use ehservo_core::servo::{Load, NominalModel};

/// The cylinder plant.
#[derive(Debug, Clone, Copy)]
pub struct CylinderPlant {
    params: CylinderParams,
    model: NominalModel,
}

impl CylinderPlant {
    /// From validated parameters and the load torque on the pinion.
    pub fn new(params: CylinderParams, load: Load) -> Self {
        Self {
            params,
            model: NominalModel::new(params.nominal_servo_params(), load),
        }
    }

    /// The cylinder's parameters.
    pub fn params(&self) -> &CylinderParams {
        &self.params
    }

    /// The external force on the rod from the load torque, `Tl(θ, θ̇)/r`.
    #[inline]
    fn load_force(&self, y: f64, v: f64) -> f64 {
        let r = self.params.r;
        self.model.load.torque(y / r, v / r) / r
    }

    /// Rod acceleration ÿ from the force balance.
    #[inline]
    pub fn acceleration(&self, s: &[f64; 4]) -> f64 {
        let c = &self.params;
        let [y, v, p1, p2] = *s;
        (c.area * (p1 - p2)
            - c.damping * v
            - c.spring * y
            - c.friction_force(v)
            - self.load_force(y, v))
            / c.mass
    }

    /// The derivative and whether a valve root was clamped.
    #[inline]
    pub fn deriv_clamped(&self, s: &[f64; 4], u: f64, v: &Variation, ds: &mut [f64; 4]) -> bool {
        let c = &self.params;
        let [y, yd, p1, p2] = *s;
        let (q1, q2, clamped) = c.valve_flows(c.kv * u, p1, p2);
        let scale = 1.0 + v.db_rel;
        let (v1, v2) = c.volumes(y);
        let leak = c.leakage * (p1 - p2);
        let ydd = self.acceleration(s);
        // The Δa_i as a load-pressure rate (module doc).
        let r = c.r;
        let x = [y / r, yd / r, ydd / r];
        let extra = -0.5 * c.mass * r / c.area * (v.da[0] * x[0] + v.da[1] * x[1] + v.da[2] * x[2]);
        ds[0] = yd;
        ds[1] = ydd;
        ds[2] = c.beta_e / v1 * (scale * q1 - c.area * yd - leak) + extra;
        ds[3] = c.beta_e / v2 * (-scale * q2 + c.area * yd + leak) - extra;
        clamped
    }

    /// The storage of docs/cylinder.md: kinetic, spring, load-potential and
    /// compression energy, `½Mẏ² + ½Ky² + U_load(θ) + Σ V_i·g(P_i)` (J).
    /// The load potential is that of the load's sine,
    /// `(amplitude/k)·(1 − cos kθ)`; friction has none.
    pub fn storage(&self, s: &[f64; 4]) -> f64 {
        let c = &self.params;
        let [y, yd, p1, p2] = *s;
        let (v1, v2) = c.volumes(y);
        let l = &self.model.load;
        let theta = y / c.r;
        let u_load = if l.wavenumber == 0.0 {
            0.0
        } else {
            l.amplitude / l.wavenumber * (1.0 - (l.wavenumber * theta).cos())
        };
        0.5 * c.mass * yd * yd
            + 0.5 * c.spring * y * y
            + u_load
            + v1 * c.compression_energy_density(p1)
            + v2 * c.compression_energy_density(p2)
    }
}

/// The cylinder's physical states in a trace.
const CYLINDER_STATES: [Signal; 4] = [
    Signal::new("y", "y_mm", "mm", "rod position y = r·θ"),
    Signal::new(
        "p1",
        "p1_Pa",
        "Pa",
        "pressure of chamber 1 (extends the rod)",
    ),
    Signal::new("p2", "p2_Pa", "Pa", "pressure of chamber 2"),
    Signal::new("p_load", "p_load_Pa", "Pa", "load pressure P1 − P2"),
];

impl Plant for CylinderPlant {
    type State = [f64; 4];
    const STATES: &'static [Signal] = &CYLINDER_STATES;

    fn states(&self, s: &[f64; 4], _x: &[f64; 3], out: &mut [f64; MAX_STATES]) {
        *out = [1e3 * s[0], s[2], s[3], s[2] - s[3]];
    }

    /// y = r·θ, ẏ = r·θ̇, and the chamber pressures split symmetrically
    /// about Ps/2 with the load pressure the force balance asks for θ̈(0).
    fn initial_state(&self, x0: [f64; 3]) -> [f64; 4] {
        let c = &self.params;
        let (y, v) = (c.r * x0[0], c.r * x0[1]);
        let force = c.mass * c.r * x0[2]
            + c.damping * v
            + c.spring * y
            + c.friction_force(v)
            + self.load_force(y, v);
        let pl = force / c.area;
        [y, v, 0.5 * (c.ps + pl), 0.5 * (c.ps - pl)]
    }

    #[inline]
    fn measure(&self, s: &[f64; 4]) -> [f64; 3] {
        let r = self.params.r;
        [s[0] / r, s[1] / r, self.acceleration(s) / r]
    }

    #[inline]
    fn deriv(&self, _t: f64, s: &[f64; 4], u: f64, v: &Variation, ds: &mut [f64; 4]) {
        self.deriv_clamped(s, u, v, ds);
    }

    fn nominal(&self) -> &NominalModel {
        &self.model
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant::ThirdOrderPlant;
    use ehservo_core::rk4::rk4_step;
    use ehservo_core::servo::Friction;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Uniform on [lo, hi) from 53 random bits.
    fn uni(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }

    fn with_friction() -> CylinderParams {
        CylinderParams {
            spring: 2.0e4,
            friction: Some(Friction {
                coulomb: 40.0,
                stiction: 60.0,
                stribeck_velocity: 0.01,
                viscous: 50.0,
                smoothing: 1e-3,
            }),
            ..CylinderParams::typical()
        }
    }

    /// Steady flow balance: at constant velocity with steady pressures,
    /// Q1 = Q2 = A·ẏ + Cl·(P1 − P2). The state is built by hand: choose
    /// ẏ, y and the load; the force balance gives P_L; P1 + P2 = Ps; the
    /// orifice law solved for x_v. The derivative must then vanish.
    #[test]
    fn steady_state_flow_balance() {
        let c = with_friction();
        let load = Load::paper();
        let plant = CylinderPlant::new(c, load);
        for &(y, v) in &[(0.01, 0.02), (-0.03, 0.05), (0.02, -0.04), (0.0, -0.001)] {
            let f_ext = load.torque(y / c.r, v / c.r) / c.r;
            let pl = (c.damping * v + c.spring * y + c.friction_force(v) + f_ext) / c.area;
            let (p1, p2) = (0.5 * (c.ps + pl), 0.5 * (c.ps - pl));
            let q = c.area * v + c.leakage * pl;
            let drop = if v >= 0.0 { c.ps - pl } else { c.ps + pl };
            let xv = q / (c.cd * c.w * (drop / c.rho).sqrt());
            let (q1, q2, clamped) = c.valve_flows(xv, p1, p2);
            assert!(!clamped);
            assert!((q1 - q).abs() <= 1e-12 * q.abs(), "Q1 {q1} vs {q}");
            assert!((q2 - q).abs() <= 1e-12 * q.abs(), "Q2 {q2} vs {q}");
            let s = [y, v, p1, p2];
            let mut ds = [0.0; 4];
            plant.deriv(0.0, &s, xv / c.kv, &Variation::NONE, &mut ds);
            assert_eq!(ds[0].to_bits(), v.to_bits());
            // Scales: the pressure force per mass, and β/V·A·ẏ.
            let acc_scale = c.area * c.ps / c.mass;
            let p_scale = c.beta_e / c.v0 * c.area * v.abs();
            assert!(ds[1].abs() <= 1e-13 * acc_scale, "ÿ = {}", ds[1]);
            assert!(ds[2].abs() <= 1e-11 * p_scale, "Ṗ1 = {}", ds[2]);
            assert!(ds[3].abs() <= 1e-11 * p_scale, "Ṗ2 = {}", ds[3]);
        }
    }

    /// dH/dt along the vector field at a state, by the chain rule.
    fn storage_rate(plant: &CylinderPlant, s: &[f64; 4], ds: &[f64; 4]) -> f64 {
        let c = plant.params();
        let [y, v, p1, p2] = *s;
        let (v1, v2) = c.volumes(y);
        let l = &plant.nominal().load;
        let dg = |p: f64| (p / c.beta_e).exp() - 1.0;
        c.mass * v * ds[1]
            + c.spring * y * v
            + l.amplitude * (l.wavenumber * y / c.r).sin() * v / c.r
            + c.area * v * c.compression_energy_density(p1)
            - c.area * v * c.compression_energy_density(p2)
            + v1 * dg(p1) * ds[2]
            + v2 * dg(p2) * ds[3]
    }

    /// Passivity, pointwise: the storage's rate is exactly port power
    /// minus dissipation,
    /// dH/dt = π(P1)·Q1 − π(P2)·Q2 − B·ẏ² − ẏ·Ff(ẏ) − Cl·(P1 − P2)·(π(P1) − π(P2)),
    /// so dH/dt ≤ 0 with the valve closed and dH/dt ≤ π(Ps)·Q_supply with
    /// it open (π(Ps) = Ps·(1 + Ps/2βe + …), the constant-βe model's
    /// supply potential).
    #[test]
    fn storage_balance_and_passivity_at_random_states() {
        let c = with_friction();
        let plant = CylinderPlant::new(c, Load::paper());
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        for _ in 0..20_000 {
            let s = [
                uni(&mut rng, -0.049, 0.049),
                uni(&mut rng, -0.5, 0.5),
                uni(&mut rng, -0.1 * c.ps, 1.1 * c.ps),
                uni(&mut rng, -0.1 * c.ps, 1.1 * c.ps),
            ];
            let u = if uni(&mut rng, 0.0, 1.0) < 0.3 {
                0.0
            } else {
                uni(&mut rng, -10.0, 10.0)
            };
            let mut ds = [0.0; 4];
            plant.deriv(0.0, &s, u, &Variation::NONE, &mut ds);
            let rate = storage_rate(&plant, &s, &ds);
            let [_, v, p1, p2] = s;
            let (q1, q2, _) = c.valve_flows(c.kv * u, p1, p2);
            let pi = |p: f64| c.port_potential(p);
            let dissipation = c.damping * v * v
                + v * c.friction_force(v)
                + c.leakage * (p1 - p2) * (pi(p1) - pi(p2));
            assert!(dissipation >= 0.0);
            let port = pi(p1) * q1 - pi(p2) * q2;
            let expected = port - dissipation;
            // Round-off scale: the largest term of the sum.
            let scale = (c.area * v * c.ps).abs() + (pi(p1) * q1).abs() + (pi(p2) * q2).abs() + 1.0;
            assert!(
                (rate - expected).abs() <= 1e-9 * scale,
                "dH/dt {rate} vs {expected} at {s:?}, u = {u}"
            );
            let supply = if u >= 0.0 { q1 } else { -q2 };
            let bound = if u == 0.0 { 0.0 } else { pi(c.ps) * supply };
            assert!(
                rate <= bound + 1e-9 * scale,
                "{rate} > {bound} at {s:?}, u = {u}"
            );
        }
    }

    /// Passivity along trajectories: valve closed, random initial states
    /// inside the stroke, RK4 at 10 µs: the storage never increases.
    #[test]
    fn storage_decreases_along_closed_valve_trajectories() {
        let c = with_friction();
        let plant = CylinderPlant::new(c, Load::paper());
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..4 {
            let mut s = [
                uni(&mut rng, -0.02, 0.02),
                uni(&mut rng, -0.2, 0.2),
                uni(&mut rng, 0.0, c.ps),
                uni(&mut rng, 0.0, c.ps),
            ];
            let mut h_prev = plant.storage(&s);
            let h0 = h_prev;
            for k in 0..20_000 {
                let f = |t: f64, x: &[f64; 4], d: &mut [f64; 4]| {
                    plant.deriv(t, x, 0.0, &Variation::NONE, d)
                };
                rk4_step(f, k as f64 * 1e-5, &mut s, 1e-5);
                let h = plant.storage(&s);
                assert!(
                    h <= h_prev + 1e-12 * h0,
                    "H rose {h_prev} → {h} at step {k}"
                );
                h_prev = h;
            }
            assert!(h_prev < h0, "a damped plant loses energy");
        }
    }

    /// The linearised model written down by hand from A, M, B, K, Vt = 2V0,
    /// βe, Cl and Kq.
    fn by_hand(c: &CylinderParams) -> ([f64; 3], f64) {
        let (a, m, b, k, vt, be, cl) = (
            c.area,
            c.mass,
            c.damping,
            c.spring,
            2.0 * c.v0,
            c.beta_e,
            c.leakage,
        );
        let kq = c.cd * c.w * (c.ps / c.rho).sqrt();
        let a1 = 4.0 * be * cl * k / (vt * m);
        let a2 = k / m + 4.0 * be * a * a / (vt * m) + 4.0 * be * cl * b / (vt * m);
        let a3 = b / m + 4.0 * be * cl / vt;
        // θ⃛ per volt: y⃛ per volt over r.
        let bu = 4.0 * be * a * kq * c.kv / (vt * m) / c.r;
        ([a1, a2, a3], bu)
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * a.abs().max(b.abs())
    }

    #[test]
    fn nominal_params_are_the_hand_linearisation() {
        for c in [CylinderParams::typical(), with_friction()] {
            let (a, b) = by_hand(&c);
            let m = NominalModel::new(c.nominal_servo_params(), Load::none());
            let got = m.coeffs.as_array();
            for i in 0..3 {
                assert!(
                    close(got[i], a[i], 1e-12),
                    "a{} {} vs {}",
                    i + 1,
                    got[i],
                    a[i]
                );
            }
            assert!(close(m.b_at_rest(), b, 1e-12), "b {} vs {b}", m.b_at_rest());
        }
    }

    /// The plant's own Jacobian at the centre (central differences, exact
    /// here: the vector field is affine in each direction there), its
    /// characteristic polynomial by Faddeev–LeVerrier: s·(s³ + a3·s² +
    /// a2·s + a1), the extra s being the common-mode pressure, which
    /// nothing observes. Its first Markov parameter C·J²·g is b·r.
    #[test]
    fn jacobian_at_centre_is_the_third_order_model() {
        let c = CylinderParams {
            spring: 2.0e4,
            ..CylinderParams::typical()
        };
        let plant = CylinderPlant::new(c, Load::none());
        let s0 = [0.0, 0.0, 0.5 * c.ps, 0.5 * c.ps];
        let steps = [1e-6, 1e-6, 1.0, 1.0];
        let f = |s: &[f64; 4], u: f64| {
            let mut d = [0.0; 4];
            plant.deriv(0.0, s, u, &Variation::NONE, &mut d);
            d
        };
        let mut j = [[0.0; 4]; 4];
        for (col, &h) in steps.iter().enumerate() {
            let (mut sp, mut sm) = (s0, s0);
            sp[col] += h;
            sm[col] -= h;
            let (dp, dm) = (f(&sp, 0.0), f(&sm, 0.0));
            for row in 0..4 {
                j[row][col] = (dp[row] - dm[row]) / (2.0 * h);
            }
        }
        let (dp, dm) = (f(&s0, 1e-3), f(&s0, -1e-3));
        let g: [f64; 4] = core::array::from_fn(|i| (dp[i] - dm[i]) / 2e-3);
        // Faddeev–LeVerrier: det(sI − J) = s⁴ + c1·s³ + c2·s² + c3·s + c4.
        let mul = |a: &[[f64; 4]; 4], b: &[[f64; 4]; 4]| {
            let mut r = [[0.0; 4]; 4];
            for i in 0..4 {
                for k in 0..4 {
                    for l in 0..4 {
                        r[i][k] += a[i][l] * b[l][k];
                    }
                }
            }
            r
        };
        let mut mk = [[0.0; 4]; 4];
        let mut coeff = [1.0, 0.0, 0.0, 0.0, 0.0];
        for k in 1..=4 {
            let mut next = mul(&j, &mk);
            for (i, row) in next.iter_mut().enumerate() {
                row[i] += coeff[k - 1];
            }
            mk = next;
            let amk = mul(&j, &mk);
            let tr: f64 = (0..4).map(|i| amk[i][i]).sum();
            coeff[k] = -tr / k as f64;
        }
        let (a, b) = by_hand(&c);
        assert!(
            close(coeff[1], a[2], 1e-9),
            "c1 {} vs a3 {}",
            coeff[1],
            a[2]
        );
        assert!(
            close(coeff[2], a[1], 1e-9),
            "c2 {} vs a2 {}",
            coeff[2],
            a[1]
        );
        assert!(
            close(coeff[3], a[0], 1e-6),
            "c3 {} vs a1 {}",
            coeff[3],
            a[0]
        );
        assert!(
            coeff[4].abs() <= 1e-9 * coeff[3].abs() * coeff[1].abs(),
            "c4 {}",
            coeff[4]
        );
        let jg = mul(&j, &{
            let mut m = [[0.0; 4]; 4];
            for i in 0..4 {
                m[i][0] = g[i];
            }
            m
        });
        let j2g = mul(&j, &jg);
        assert!(
            close(j2g[0][0], b * c.r, 1e-9),
            "CJ²g {} vs b·r {}",
            j2g[0][0],
            b * c.r
        );
    }

    /// Open loop, small signal: the cylinder and the third-order plant with
    /// the equivalent parameters give the same θ(t) to first order in the
    /// amplitude (the relative difference shrinks with it).
    #[test]
    fn small_signal_matches_the_third_order_plant() {
        let c = CylinderParams::typical();
        let cyl = CylinderPlant::new(c, Load::none());
        let third = ThirdOrderPlant::new(c.nominal_servo_params(), Load::none());
        let rel = |eps: f64| {
            let u = |t: f64| eps * (2.0 * core::f64::consts::PI * 3.0 * t).sin();
            let mut sc = cyl.initial_state([0.0; 3]);
            let mut s3 = third.initial_state([0.0; 3]);
            let (mut diff, mut size) = (0.0_f64, 0.0_f64);
            let h = 1e-5;
            for k in 0..30_000 {
                let t = k as f64 * h;
                let uk = u(t);
                rk4_step(
                    |t, x, d| cyl.deriv(t, x, uk, &Variation::NONE, d),
                    t,
                    &mut sc,
                    h,
                );
                rk4_step(
                    |t, x, d| third.deriv(t, x, uk, &Variation::NONE, d),
                    t,
                    &mut s3,
                    h,
                );
                let (a, b) = (cyl.measure(&sc)[0], third.measure(&s3)[0]);
                diff = diff.max((a - b).abs());
                size = size.max(b.abs());
            }
            diff / size
        };
        let (small, large) = (rel(0.01), rel(0.1));
        assert!(small < 1e-3, "relative difference {small} at 0.01 V");
        // At least first order: the relative difference falls with the
        // amplitude. (It falls as its square, ratio ≈ 100: by the double-rod
        // symmetry the chamber volumes enter Ṗ_L only through
        // 1/(V0 + A·y) + 1/(V0 − A·y), even in y, and the common-mode
        // pressure, odd, reaches θ only through the valve roots.)
        let ratio = large / small;
        assert!(ratio > 5.0, "difference not first order: {small}, {large}");
    }

    /// Open-loop step of the valve: the rod settles at the velocity the
    /// orifice law gives at the load, A·ẏ + Cl·P_L = Cd·w·x_v·√((Ps − P_L)/ρ)
    /// with P_L = B·ẏ/A, a quadratic solved by hand.
    #[test]
    fn valve_step_settles_at_the_orifice_velocity() {
        let c = CylinderParams::typical();
        let plant = CylinderPlant::new(c, Load::none());
        for &u in &[1.0, -2.0] {
            let xv: f64 = c.kv * u;
            let k = c.cd * c.w * xv.abs();
            // a²v² + (k²B/(Aρ))v − k²Ps/ρ = 0 for the speed v = |ẏ|.
            let a = c.area + c.leakage * c.damping / c.area;
            let bq = k * k * c.damping / (c.area * c.rho);
            let cq = -k * k * c.ps / c.rho;
            let speed = (-bq + (bq * bq - 4.0 * a * a * cq).sqrt()) / (2.0 * a * a);
            let expected = speed * xv.signum();
            let mut s = plant.initial_state([0.0; 3]);
            let h = 1e-5;
            for i in 0..60_000 {
                rk4_step(
                    |t, x, d| plant.deriv(t, x, u, &Variation::NONE, d),
                    i as f64 * h,
                    &mut s,
                    h,
                );
            }
            assert!(s[0].abs() < c.half_stroke(), "inside the stroke");
            assert!(
                close(s[1], expected, 1e-6),
                "ẏ {} vs {expected} (Q/A by hand)",
                s[1]
            );
            // And the steady chamber pressures sum to Ps.
            assert!(close(s[2] + s[3], c.ps, 1e-6));
        }
    }

    /// The variation is carried exactly: Δa_i adds −Σ Δa_i·x_i to θ⃛,
    /// δb scales the flows.
    #[test]
    fn variation_adds_the_papers_terms_to_the_jerk() {
        let c = with_friction();
        let plant = CylinderPlant::new(c, Load::paper());
        let s = [0.01, 0.03, 0.6 * c.ps, 0.45 * c.ps];
        let v = Variation {
            da: [0.4, 13000.0, 170.0],
            db_rel: 0.25,
        };
        let jerk = |var: &Variation| {
            let mut d = [0.0; 4];
            plant.deriv(0.0, &s, 0.7, var, &mut d);
            // θ⃛ from d/dt of the force balance, only its pressure part
            // differs between the two calls.
            c.area * (d[2] - d[3]) / (c.mass * c.r)
        };
        let x = plant.measure(&s);
        let flow_only = Variation {
            da: [0.0; 3],
            db_rel: 0.25,
        };
        let want = -(v.da[0] * x[0] + v.da[1] * x[1] + v.da[2] * x[2]);
        let got = jerk(&v) - jerk(&flow_only);
        assert!(close(got, want, 1e-9), "{got} vs {want}");
    }
}
