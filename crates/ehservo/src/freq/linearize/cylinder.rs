//! The valve-controlled cylinder's analytic Jacobians (`[plant] model =
//! "cylinder"`, `ehservo_sim::cylinder`) and its trim: a rod position with
//! its load, at rest or in steady motion, in either direction.
//!
//! State `(y, ẏ, p̃_A, p̃_B)` with a fixed supply, `(y, ẏ, p̃_A, p̃_B, p̃_s,
//! x_r)` with a pump (the simulator's slots, without the two a fixed
//! supply holds constant); input the valve command the plant receives (V);
//! output the axis position: y (m), or θ = (y − stroke/2)/r (rad) with a
//! rack and pinion. With `V_A = V_0A + A_A·y`, `V_B = V_0B + A_B·(stroke − y)`,
//! `p = max(p̃, 0)`, `x_v = clamp(Kv·u, ±x_max)` and `N_A = Q_A − A_A·ẏ −
//! C_l·(p_A − p_B)`, `N_B = Q_B + A_B·ẏ + C_l·(p_A − p_B)`:
//!
//! ```text
//! ∂ÿ/∂y   = (−K + ∂F_stop/∂y)/M         ∂ÿ/∂ẏ  = (−B − F_f'(ẏ) + ∂F_stop/∂ẏ)/M
//! ∂ÿ/∂p_A = A_A/M                       ∂ÿ/∂p_B = −A_B/M
//! ∂ṗ_A/∂y = −(βe·A_A/V_A²)·N_A          ∂ṗ_B/∂y = +(βe·A_B/V_B²)·N_B
//! ∂ṗ_A/∂ẏ = −βe·A_A/V_A                 ∂ṗ_B/∂ẏ = +βe·A_B/V_B
//! ∂ṗ_A/∂p_A = (βe/V_A)·(∂Q_A/∂p_A − C_l)   ∂ṗ_A/∂p_B = (βe/V_A)·C_l      (and B alike)
//! ∂ṗ_A/∂u = (βe/V_A)·∂Q_A/∂x_v·Kv        ∂ṗ_A/∂p_s = (βe/V_A)·∂Q_A/∂p_s
//! ```
//!
//! Each edge `q_i = q(Cd·w_i·o_i, Δp_i)` of `ehservo_sim::valve` gives
//! `∂q/∂Δp` (`orifice_slope`) and `∂q/∂(Cd·A)` (`orifice_area_slope`);
//! `∂o_i/∂x_v = ±1` on an open edge. The pump's rows are
//! `(V_s/βe)·ṗ_s = Q_pump − x_r·√(p_s − P_t) − Q_P`, `ẋ_r = (x_s(p_s) − x_r)/τ`
//! differentiated the same way. Every factor of `[uncertainty.physical]` is
//! applied as the simulator applies it.
//!
//! **What is linearised at the trim (a stated choice).** The load is taken
//! at its value there: the spring's stiffness, the force signal F(t) at the
//! trim's time (t = 0, constant in the linear model), the Coulomb–Stribeck
//! friction by its slope at the trim's speed, or, where it holds the rod
//! (at rest below the break-away force: ehservo_sim::cylinder's stick
//! model), ÿ = −ẏ/τ with the rod deaf to the pressures,
//! an end stop by its spring and damper when it is in contact and not at
//! all otherwise. **A metering edge at its opening point** (a closed-centre
//! valve at rest, x_v at the lap) is taken at its turbulent limit: the
//! orifice law's laminar region makes q ∝ A^{3/2} within a few nanometres
//! of spool travel (ehservo_sim::valve), whose exact slope at A = 0 is 0,
//! but any signal larger than that sees the turbulent flow gain
//! `Cd·w·√(2|Δp|/ρ)` (Merritt's K_q at null). The edge opens on one side
//! only, so this is a kink ([`Side`]): from above (`--side plus`) the edges
//! P→A and B→T open (the rod extends), from below (`--side minus`) P→B and
//! A→T (it retracts); where both sides' gains agree (a symmetric cylinder
//! at centre) there is no kink.

use super::{Jacobian, Kink, Linearize, PlantState, Point, Side, AT_KINK, SAME_SLOPE};
use crate::freq::ss::Quantity;
use crate::plant::Plant;
use crate::simulation::Sample;
use crate::uncertainty::Factors;
use ehservo_sim::cylinder::{Cylinder, CylinderPlant, CylinderVariation, VOLUME_FLOOR};
use ehservo_sim::error::KeyError;
use ehservo_sim::supply::{Pump, Supply};
use nalgebra::{DMatrix, DVector};

/// The edges: P→A, P→B, A→T, B→T (`ehservo_sim::valve`'s order).
const PA: usize = 0;
const PB: usize = 1;
const AT: usize = 2;
const BT: usize = 3;

/// How an edge's opening moves with x_v: `o_i = max(σ_i·x_v − lap_i, 0)`.
const SIGMA: [f64; 4] = [1.0, -1.0, -1.0, 1.0];

/// Newton iterations of a cylinder trim.
const TRIM_ITERATIONS: usize = 100;

/// Step halvings per iteration.
const TRIM_HALVINGS: usize = 60;

/// The cylinder as a linearisable stage: the plant, the physical factors
/// of the operating point and the time at which the force signal is taken.
#[derive(Debug, Clone)]
pub struct CylinderLin {
    plant: CylinderPlant,
    f: Factors,
    t: f64,
}

/// The full 6 × 6 Jacobian and the input column.
struct Full {
    a: [[f64; 6]; 6],
    b: [f64; 6],
}

impl CylinderLin {
    /// The plant with the physical factors `f`, its force signal at `t`.
    pub fn new(plant: CylinderPlant, f: Factors, t: f64) -> Self {
        Self { plant, f, t }
    }

    /// The same at another time (the force signal's).
    pub fn at_time(&self, t: f64) -> Self {
        Self { t, ..self.clone() }
    }

    fn c(&self) -> &Cylinder {
        self.plant.cylinder()
    }

    fn pump(&self) -> Option<Pump> {
        match &self.c().supply {
            Supply::Pump(p) => Some(*p),
            // A pressure-compensated pump is refused before a CylinderLin
            // is built (crate::freq::oppoint).
            Supply::Fixed { .. } | Supply::PcPump(_) => None,
        }
    }

    /// The model's states: 4 with a fixed supply, 6 with a pump.
    pub fn n(&self) -> usize {
        if self.pump().is_some() {
            6
        } else {
            4
        }
    }

    /// The supply's steady pressure with the valve closed (Pa).
    fn holding(&self) -> f64 {
        let c = self.c();
        c.supply.holding_pressure_at(c.pt, self.f.supply_pressure)
    }

    /// The simulator's 6-slot state for the model's state `x` (a fixed
    /// supply's two slots are not read by its derivative).
    fn full(&self, x: &[f64]) -> [f64; 6] {
        if self.pump().is_some() {
            [x[0], x[1], x[2], x[3], x[4], x[5]]
        } else {
            [x[0], x[1], x[2], x[3], self.holding(), 0.0]
        }
    }

    /// The rod's position and speed for the axis's position and speed.
    pub fn rod(&self, x: f64, v: f64) -> (f64, f64) {
        match self.c().radius {
            None => (x, v),
            Some(r) => (0.5 * self.c().stroke + r * x, r * v),
        }
    }

    /// The axis's position for the rod's.
    fn axis_of(&self, y: f64) -> f64 {
        match self.c().radius {
            None => y,
            Some(r) => (y - 0.5 * self.c().stroke) / r,
        }
    }

    fn variation(&self) -> CylinderVariation {
        CylinderVariation { f: self.f }
    }

    /// The pre-openings `σ_i·x_v − lap_i` of the four edges.
    fn pre_openings(&self, xv: f64) -> [f64; 4] {
        let l = self.c().valve.lap;
        [0, 1, 2, 3].map(|i| SIGMA[i] * xv - l[i])
    }

    /// The full Jacobian at the simulator's state `s` under `u`, one-sided
    /// (`side`) at the spool limit and at an edge's opening point.
    fn full_jacobian(&self, s: &[f64; 6], u: f64, side: Side) -> Full {
        let c = self.c();
        let f = &self.f;
        let valve = &c.valve;
        let [y, v, pa_s, pb_s, ps_s, xr] = *s;
        let on = |p: f64| if p > 0.0 { 1.0 } else { 0.0 };
        let (hpa, hpb) = (on(pa_s), on(pb_s));
        let (pa, pb) = (pa_s.max(0.0), pb_s.max(0.0));
        let pump = self.pump();
        let ps = c.supply.pressure(ps_s, f.supply_pressure);
        let hps = if pump.is_some() { on(ps_s) } else { 0.0 };
        let pt = c.pt;
        // The spool: Kv inside its travel, 0 beyond, one-sided at the limit.
        let raw = valve.kv * u;
        let xv = valve.spool(u);
        let over = raw.abs() - valve.x_max;
        let dxv = if over < -AT_KINK * valve.x_max {
            valve.kv
        } else if over > AT_KINK * valve.x_max {
            0.0
        } else if side.sign() * raw.signum() < 0.0 {
            // Approached from inside the travel.
            valve.kv
        } else {
            0.0
        };
        // The edges: ∂q/∂Δp and ∂q/∂x_v.
        let o = valve.openings(xv);
        let pre = self.pre_openings(xv);
        let drops = [ps - pa, ps - pb, pa - pt, pb - pt];
        let mut g = [0.0; 4];
        let mut k = [0.0; 4];
        for (i, (gi, ki)) in g.iter_mut().zip(k.iter_mut()).enumerate() {
            let cda = valve.cdw[i] * o[i];
            *gi = valve.orifice_slope(cda, drops[i]);
            *ki = if pre[i].abs() <= AT_KINK * valve.x_max {
                // At its opening point: open on the side where σ_i·x_v grows,
                // at its turbulent limit (module doc).
                if SIGMA[i] * side.sign() > 0.0 {
                    SIGMA[i] * valve.cdw[i] * valve.turbulent_area_slope(drops[i])
                } else {
                    0.0
                }
            } else if o[i] > 0.0 {
                SIGMA[i] * valve.cdw[i] * valve.orifice_area_slope(cda, drops[i])
            } else {
                0.0
            };
        }
        let q = valve.flows(xv, ps, pt, pa, pb);
        let (kqa, kqb, kqp) = (k[PA] - k[AT], k[PB] - k[BT], k[PA] + k[PB]);
        let [va, vb] = c.volumes(y);
        let dva = if c.v0[0] + c.area[0] * y > VOLUME_FLOOR * c.v0[0] {
            c.area[0]
        } else {
            0.0
        };
        let dvb = if c.v0[1] + c.area[1] * (c.stroke - y) > VOLUME_FLOOR * c.v0[1] {
            -c.area[1]
        } else {
            0.0
        };
        let beta = c.beta * f.bulk_modulus;
        let cl = c.leakage * f.leakage;
        let leak = cl * (pa - pb);
        let na = q.a - c.area[0] * v - leak;
        let nb = q.b + c.area[1] * v + leak;
        let m = c.mass * f.mass;
        // Friction: held (stuck, or bounded by the force that stops the
        // rod within τ), ÿ = −ẏ/τ and nothing else moves the rod; else the
        // viscous terms and the sliding law's slope.
        let dry = c.friction_at(0.0, s, f);
        let friction_slope = c.viscous_coeff(f) + dry.slope;
        let [ks, cs] = c.stop;
        let pressing = (y < 0.0 && -ks * y - cs * v > 0.0)
            || (y > c.stroke && ks * (c.stroke - y) - cs * v < 0.0);
        let (mut stop_y, mut stop_v) = if pressing { (-ks, -cs) } else { (0.0, 0.0) };
        if let Some(e) = &c.environment {
            // The environment's spring and damper while it pushes, beside
            // the stop's (docs/environments.md).
            let (ky, kv) = e.slopes(self.t, y, v);
            stop_y -= ky;
            stop_v -= kv;
        }
        let mut a = [[0.0; 6]; 6];
        let mut b = [0.0; 6];
        a[0][1] = 1.0;
        if dry.held {
            a[1][1] = -c.stick_rate;
        } else {
            a[1][0] = (-f.load * c.spring + stop_y) / m;
            a[1][1] = (-friction_slope + stop_v) / m;
            a[1][2] = c.area[0] * hpa / m;
            a[1][3] = -c.area[1] * hpb / m;
        }
        let (ka, kb) = (beta / va, beta / vb);
        a[2][0] = -ka * dva / va * na;
        a[2][1] = -ka * c.area[0];
        a[2][2] = ka * (-g[PA] - g[AT] - cl) * hpa;
        a[2][3] = ka * cl * hpb;
        a[2][4] = ka * g[PA] * hps;
        b[2] = ka * kqa * dxv;
        a[3][0] = -kb * dvb / vb * nb;
        a[3][1] = kb * c.area[1];
        a[3][2] = kb * cl * hpa;
        a[3][3] = kb * (-g[PB] - g[BT] - cl) * hpb;
        a[3][4] = kb * g[PB] * hps;
        b[3] = kb * kqb * dxv;
        if let Some(p) = pump {
            // With an accumulator the line's stiffness depends on p_s; its
            // derivative multiplies the flow balance, 0 at a trim.
            let kp = p.line_stiffness(ps, f.bulk_modulus);
            let p_max = p.p_max * f.supply_pressure;
            let dp = ps - pt;
            let sq = dp.max(0.0).sqrt();
            let dqr_dps = if dp > 0.0 {
                xr.max(0.0) / (2.0 * sq)
            } else {
                0.0
            };
            let dqr_dxr = if xr > 0.0 { sq } else { 0.0 };
            a[4][2] = kp * g[PA] * hpa;
            a[4][3] = kp * g[PB] * hpb;
            a[4][4] = kp * (-p.leakage - dqr_dps - g[PA] - g[PB]) * hps;
            a[4][5] = -kp * dqr_dxr;
            b[4] = -kp * kqp * dxv;
            // x_s(p_s) = clamp((p_s − p_max)/b1, 0, x_max), b1 = C_s + C_f·(p_s − P_t).
            let (b1, db1) = if dp * p.cf < 0.0 {
                (p.cs, 0.0)
            } else {
                (p.cs + dp * p.cf, p.cf)
            };
            let xs = (ps - p_max) / b1;
            let dxs = if xs > 0.0 && xs < p.x_max {
                (b1 - (ps - p_max) * db1) / (b1 * b1)
            } else {
                0.0
            };
            a[5][4] = p.rate * dxs * hps;
            a[5][5] = -p.rate;
        }
        Full { a, b }
    }

    /// The chamber pressures that hold the rod at `y0` moving at `v0` in
    /// the direction `s` when the valve's flows are in the limit of a
    /// vanishing opening of the metering edges (turbulent): the pair
    /// (p_A, p_B), the spool position where the edges open, or an error.
    fn limit_pressures(&self, force: f64, ps: f64, s: f64) -> Result<([f64; 2], f64), KeyError> {
        let c = self.c();
        let v = &c.valve;
        let [aa, ab] = c.area;
        let pt = c.pt;
        // In-edge feeds the chamber that grows, out-edge drains the other.
        let (i_in, i_out) = if s > 0.0 { (PA, BT) } else { (PB, AT) };
        let (l_in, l_out) = (v.lap[i_in], v.lap[i_out]);
        let tol = AT_KINK * v.x_max;
        let p = if (l_in - l_out).abs() <= tol {
            // Both at their opening point: Cd·w·x·√(2Δp/ρ) = A·|ẏ| on each,
            // the same x, so the drops are in the ratio (A/(Cd·w))².
            if s > 0.0 {
                // (Ps − p_A) = r·(p_B − Pt), r = (A_A·cdw_BT/(A_B·cdw_PA))².
                let r = (aa * v.cdw[BT] / (ab * v.cdw[PA])).powi(2);
                let pb = (aa * ps + aa * r * pt - force) / (aa * r + ab);
                [ps - r * (pb - pt), pb]
            } else {
                // (Ps − p_B) = r·(p_A − Pt), r = (A_B·cdw_AT/(A_A·cdw_PB))².
                let r = (ab * v.cdw[AT] / (aa * v.cdw[PB])).powi(2);
                let pa = (force + ab * ps + ab * r * pt) / (aa + ab * r);
                [pa, ps - r * (pa - pt)]
            }
        } else if l_in > l_out {
            // The out-edge is open wider: its drop vanishes with the flow.
            if s > 0.0 {
                [(force + ab * pt) / aa, pt]
            } else {
                [pt, (aa * pt - force) / ab]
            }
        } else if s > 0.0 {
            [ps, (aa * ps - force) / ab]
        } else {
            [(force + ab * ps) / aa, ps]
        };
        let lap = l_in.max(l_out);
        for (name, pv) in [("p_A", p[0]), ("p_B", p[1])] {
            if !(pv.is_finite() && (pt - 1e-9 * ps..=ps * (1.0 + 1e-9)).contains(&pv)) {
                return Err(KeyError::new(
                    "--trim",
                    format!(
                        "no trim point {}: holding the load {force:.6e} N needs {name} = {pv:.6e} Pa, outside the tank to supply range {pt:.6e} to {ps:.6e} Pa",
                        if s > 0.0 { "extending" } else { "retracting" }
                    ),
                ));
            }
        }
        Ok((p, s * lap))
    }

    /// The trim: the rod at the axis position `x0` moving at `v0` (the
    /// axis's SI units), the chamber pressures that hold its load, the
    /// supply's states and the command, at time `self.t`. At rest on a
    /// closed-centre valve without leakage the pressures are the limit of
    /// the steady motion in the direction of `side` (module doc). Returns
    /// the model's state, the plant's input (V) and the iterations.
    pub fn trim(&self, x0: f64, v0: f64, side: Side) -> Result<(Vec<f64>, f64, usize), KeyError> {
        let c = self.c();
        let (y0, yd0) = self.rod(x0, v0);
        if !y0.is_finite() {
            return Err(KeyError::new("--trim", "the position must be finite"));
        }
        if !yd0.is_finite() {
            return Err(KeyError::new("--velocity", "the speed must be finite"));
        }
        if !(0.0..=c.stroke).contains(&y0) {
            return Err(KeyError::new(
                "--trim",
                format!(
                    "the rod at y = {:.6} mm is outside its stroke, 0 to {} mm (plant.cylinder.stroke): a trim on an end stop is not linearised",
                    y0 * 1e3,
                    c.stroke * 1e3
                ),
            ));
        }
        let vv = self.variation();
        let ps0 = self.holding();
        // The load the pressures hold: the net force with both chambers at 0.
        let mut ds = [0.0; 6];
        let mut s = [y0, yd0, 0.0, 0.0, ps0, 0.0];
        if let Some(p) = self.pump() {
            let relief = Pump {
                p_max: p.p_max * self.f.supply_pressure,
                ..p
            };
            s[5] = relief.steady_opening(ps0, c.pt);
        }
        self.plant.deriv(self.t, &s, 0.0, &vv, &mut ds);
        let force = -ds[1] * c.mass * self.f.mass;
        let dir = if yd0 > 0.0 {
            1.0
        } else if yd0 < 0.0 {
            -1.0
        } else {
            side.sign()
        };
        let leaks = c.leakage * self.f.leakage > 0.0;
        let r = match self.trim_in(s, force, dir, side) {
            // At rest with leakage the valve's direction follows the load,
            // not the side: the other direction's start when the side's fails.
            Err(e) if yd0 == 0.0 && leaks => self.trim_in(s, force, -dir, side).map_err(|_| e),
            r => r,
        };
        // In motion the speed asked for is what cannot be held.
        r.map_err(|mut e| {
            if yd0 != 0.0 {
                e.key = "--velocity".into();
            }
            e
        })
    }

    /// [`CylinderLin::trim`] from the start `s` (y, ẏ and the supply set)
    /// with the valve opening in the direction `dir`.
    fn trim_in(
        &self,
        mut s: [f64; 6],
        force: f64,
        dir: f64,
        side: Side,
    ) -> Result<(Vec<f64>, f64, usize), KeyError> {
        let c = self.c();
        let n = self.n();
        let ps0 = self.holding();
        let yd0 = s[1];
        let ([pa, pb], x_open) = self.limit_pressures(force, ps0, dir)?;
        let closed_centre = c.valve.lap.iter().all(|&l| l >= -AT_KINK * c.valve.x_max);
        let cl = c.leakage * self.f.leakage;
        s[2] = pa;
        s[3] = pb;
        if yd0 == 0.0 && cl == 0.0 && closed_centre {
            // Nothing flows: the spool where the metering edges open.
            let u = x_open / c.valve.kv;
            return Ok((s[..n].to_vec(), u, 0));
        }
        // Otherwise the flows fix the pressures: Newton from the limit's
        // pressures with the opening that passes the flow into the growing
        // chamber.
        let (i_in, a_in) = if dir > 0.0 {
            (PA, c.area[0])
        } else {
            (PB, c.area[1])
        };
        let q_in = a_in * yd0.abs() + cl * (pa - pb).abs();
        let dp_in = if dir > 0.0 { ps0 - pa } else { ps0 - pb };
        let k = c.valve.cdw[i_in] * c.valve.turbulent_area_slope(dp_in.max(1.0));
        let xv = x_open + dir * q_in / k;
        self.newton(s, xv / c.valve.kv, side)
    }

    /// Newton's method on ÿ = 0, ṗ_A = ṗ_B = 0 (and the supply's two) in
    /// the unknowns (p_A, p_B[, p_s, x_r], u), y and ẏ held.
    fn newton(
        &self,
        s0: [f64; 6],
        u0: f64,
        side: Side,
    ) -> Result<(Vec<f64>, f64, usize), KeyError> {
        let c = self.c();
        let n = self.n();
        let m = n - 1; // unknowns: states 2..n and u
        let vv = self.variation();
        let ps0 = self.holding();
        let mut scale = vec![ps0; m];
        if let Some(p) = self.pump() {
            scale[3] = p.x_max.max(1e-12);
        }
        scale[m - 1] = c.valve.x_max / c.valve.kv;
        let unpack = |z: &[f64]| {
            let mut s = s0;
            s[2..n].copy_from_slice(&z[..n - 2]);
            (s, z[m - 1])
        };
        let residual = |z: &[f64]| -> Vec<f64> {
            let (s, u) = unpack(z);
            let mut ds = [0.0; 6];
            self.plant.deriv(self.t, &s, u, &vv, &mut ds);
            ds[1..n].to_vec()
        };
        let jac = |z: &[f64]| -> DMatrix<f64> {
            let (s, u) = unpack(z);
            let j = self.full_jacobian(&s, u, side);
            DMatrix::from_fn(m, m, |i, k| {
                if k < m - 1 {
                    j.a[i + 1][k + 2]
                } else {
                    j.b[i + 1]
                }
            })
        };
        let mut z: Vec<f64> = s0[2..n].iter().copied().chain([u0]).collect();
        let mut f = residual(&z);
        for it in 0..=TRIM_ITERATIONS {
            let jm = jac(&z);
            let tol: Vec<f64> = (0..m)
                .map(|i| 1e-10 * (0..m).map(|k| jm[(i, k)].abs() * scale[k]).sum::<f64>() + 1e-300)
                .collect();
            let worst = f
                .iter()
                .zip(&tol)
                .map(|(a, t)| a.abs() / t)
                .fold(0.0f64, f64::max);
            if !worst.is_finite() {
                break;
            }
            if worst <= 1.0 {
                let (s, u) = unpack(&z);
                return Ok((s[..n].to_vec(), u, it));
            }
            let ms = DMatrix::from_fn(m, m, |i, k| jm[(i, k)] * scale[k] / tol[i]);
            let rhs = DVector::from_fn(m, |i, _| -f[i] / tol[i]);
            let Some(step) = ms
                .lu()
                .solve(&rhs)
                .filter(|s| s.iter().all(|v| v.is_finite()))
            else {
                break;
            };
            let norm = |f: &[f64]| {
                f.iter()
                    .zip(&tol)
                    .map(|(a, t)| (a / t).powi(2))
                    .sum::<f64>()
            };
            let f0 = norm(&f);
            let mut lambda = 1.0;
            let mut moved = false;
            for _ in 0..TRIM_HALVINGS {
                let next: Vec<f64> = (0..m).map(|k| z[k] + lambda * step[k] * scale[k]).collect();
                let fnext = residual(&next);
                if norm(&fnext) < f0 {
                    z = next;
                    f = fnext;
                    moved = true;
                    break;
                }
                lambda /= 2.0;
            }
            if !moved {
                break;
            }
        }
        let (s, u) = unpack(&z);
        let names = self.states();
        let (i, r) = f.iter().enumerate().fold((0, 0.0f64), |acc, (i, r)| {
            if r.abs() > acc.1.abs() {
                (i, *r)
            } else {
                acc
            }
        });
        Err(KeyError::new(
            "--trim",
            format!(
                "no trim point at y = {:.6} mm, ẏ = {:.6} mm/s: the residual d({})/dt = {r:.6e} {}/s does not vanish (Newton's method from the pressures that hold the load; there p_A = {:.6e} Pa, p_B = {:.6e} Pa, x_v = {:.6e} m of spool_limit {} m)",
                s[0] * 1e3,
                s[1] * 1e3,
                names[i + 1].name,
                names[i + 1].unit,
                s[2],
                s[3],
                c.valve.spool(u),
                c.valve.x_max
            ),
        ))
    }
}

impl Linearize for CylinderLin {
    fn states(&self) -> Vec<Quantity> {
        let mut v = vec![
            Quantity::new("y", "m"),
            Quantity::new("y_dot", "m/s"),
            Quantity::new("p_a", "Pa"),
            Quantity::new("p_b", "Pa"),
        ];
        if self.pump().is_some() {
            v.push(Quantity::new("p_supply", "Pa"));
            v.push(Quantity::new("relief", "m³/(s·√Pa)"));
        }
        v
    }
    fn input(&self) -> Quantity {
        Quantity::new("u_plant", "V")
    }
    fn output(&self) -> Quantity {
        match self.c().radius {
            None => Quantity::new("y", "m"),
            Some(_) => Quantity::new("theta", "rad"),
        }
    }
    fn scales(&self) -> Vec<f64> {
        let c = self.c();
        let p = self.holding();
        let mut v = vec![c.stroke, 0.1, p, p];
        if let Some(pump) = self.pump() {
            v.push(p);
            v.push(pump.x_max.max(1e-12));
        }
        v
    }
    fn eval(&self, p: &Point, dx: &mut [f64]) -> f64 {
        let s = self.full(p.x);
        let mut ds = [0.0; 6];
        self.plant
            .deriv(self.t, &s, p.u, &self.variation(), &mut ds);
        let n = self.n();
        dx[..n].copy_from_slice(&ds[..n]);
        self.axis_of(s[0])
    }
    fn jacobian(&self, p: &Point, side: Side) -> Jacobian {
        let n = self.n();
        let s = self.full(p.x);
        let full = self.full_jacobian(&s, p.u, side);
        let mut j = Jacobian::zeros(n);
        for (i, row) in full.a.iter().take(n).enumerate() {
            for (k, v) in row.iter().take(n).enumerate() {
                j.a[(i, k)] = *v;
            }
            j.b[(i, 0)] = full.b[i];
        }
        j.c[(0, 0)] = match self.c().radius {
            None => 1.0,
            Some(r) => 1.0 / r,
        };
        j
    }
    fn kinks(&self, p: &Point) -> Vec<Kink> {
        let c = self.c();
        let v = &c.valve;
        let s = self.full(p.x);
        let mut out = Vec::new();
        let raw = v.kv * p.u;
        if (raw.abs() - v.x_max).abs() <= AT_KINK * v.x_max {
            out.push(Kink {
                what: format!(
                    "the spool at its travel limit plant.valve.spool_limit = {} m (u_plant = {:.6e} V): the flow gain is there from inside and 0 beyond",
                    v.x_max, p.u
                ),
                quantity: "u_plant".into(),
            });
        }
        let xv = v.spool(p.u);
        let opening: Vec<usize> = (0..4)
            .filter(|&i| self.pre_openings(xv)[i].abs() <= AT_KINK * v.x_max)
            .collect();
        if !opening.is_empty() {
            let jm = self.full_jacobian(&s, p.u, Side::Minus);
            let jp = self.full_jacobian(&s, p.u, Side::Plus);
            let differ = |a: f64, b: f64| (a - b).abs() > SAME_SLOPE * a.abs().max(b.abs());
            if (2..4).any(|i| differ(jm.b[i], jp.b[i])) {
                out.push(Kink {
                    what: format!(
                        "the valve's metering edges at their opening point (x_v = {xv:.3e} m, p_A = {:.6e} Pa, p_B = {:.6e} Pa): ∂ṗ_A/∂u is {:.6e} Pa/(s·V) from above (P→A and B→T open: extending) and {:.6e} Pa/(s·V) from below (P→B and A→T open: retracting)",
                        s[2].max(0.0),
                        s[3].max(0.0),
                        jp.b[2],
                        jm.b[2]
                    ),
                    quantity: "u_plant".into(),
                });
            }
        }
        out
    }
    fn notes(&self, p: &Point) -> Vec<String> {
        let c = self.c();
        let v = &c.valve;
        let s = self.full(p.x);
        let mut out = Vec::new();
        if (v.kv * p.u).abs() > v.x_max * (1.0 + AT_KINK) {
            out.push(format!(
                "the spool is at its travel limit (|Kv·u_plant| = {:.6e} m > spool_limit {} m): the plant's input gain is 0",
                (v.kv * p.u).abs(),
                v.x_max
            ));
        }
        let xv = v.spool(p.u);
        if self
            .pre_openings(xv)
            .iter()
            .any(|pre| pre.abs() <= AT_KINK * v.x_max)
        {
            out.push(
                "metering edges at their opening point are taken at their turbulent flow gain Cd·w·√(2|Δp|/ρ): the orifice's laminar region (a few nm of spool travel) is not linearised".into(),
            );
        }
        if s[1] == 0.0
            && c.leakage * self.f.leakage == 0.0
            && v.openings(xv).iter().all(|&o| o == 0.0)
        {
            out.push(
                "at rest with every edge closed and no leakage, any pair of chamber pressures that holds the load is an equilibrium: their common mode is a pole at s = 0 (z = 1) that the command does not move, and the closed loop's `stable` verdict leaves it out as a hidden mode (the position's own response is not affected)".into(),
            );
        }
        for (i, name) in [(2, "A"), (3, "B")] {
            if s[i] <= 0.0 {
                out.push(format!(
                    "chamber {name} cavitates (p̃ = {:.6e} Pa ≤ 0): its pressure is held at 0 and does not act",
                    s[i]
                ));
            }
        }
        if !(0.0..=c.stroke).contains(&s[0]) {
            out.push(format!(
                "the rod is on an end stop (y = {:.6} mm): the stop's spring and damper are in the model",
                s[0] * 1e3
            ));
        }
        out
    }
}

impl PlantState for CylinderLin {
    /// `(y, ẏ, p_A, p_B[, p_s, x_r])` from the sample's axis position and
    /// its logged physical states (the pressures are logged as max(p̃, 0)).
    fn state_of(&self, smp: &Sample) -> Vec<f64> {
        let (y, v) = self.rod(smp.x[0], smp.x[1]);
        let mut x = vec![y, v, smp.states[0], smp.states[1]];
        if self.pump().is_some() {
            x.push(smp.states[2]);
            x.push(smp.states[3]);
        }
        x
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact zeros and the speed asked for are the point of some checks
#[path = "cylinder_tests.rs"]
mod tests;
