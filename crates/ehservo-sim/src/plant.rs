//! The "true" plants the controllers are tried on, with the parameter
//! variations they do not know.
//!
//! Two models of the same servo (SPEC §2):
//! - [`ThirdOrderPlant`], eq. (8)–(9) in x = (θ, θ̇, θ̈):
//!   `ẋ3 = −Σ(ā_i + Δa_i)·x_i + b·u − d`, `b = (1 + δb)·b(x, sgn u)`;
//! - [`PhysicalPlant`], eqs. (1)–(6) in (θ, θ̇, Pl), with the same variations
//!   carried exactly: the valve flow scaled by `1 + δb`, and the `Δa_i` as an
//!   unmodelled flow term `−(Jt/Dm)·Σ Δa_i·x_i` in `Ṗl`. Differentiating (4)
//!   once shows that this term adds exactly `−Σ Δa_i·x_i` to `θ⃛`, so the two
//!   models are the same system under any variation (a test checks it).
//!
//! **Variations** ([`UncertaintySignal`]): `Δa_i = |ā_i|·(a_bias + a_random·r_i(t))`
//! and `Δb = b_ref·b(t)·(b_bias + b_random·r_b(t))`, i.e. fractions of the
//! paper's reference sizes α_i = |ā_i| and β = b_ref·|b̄| with b_ref = 0.5
//! (SPEC §2: β = 0.5|b̄|), whatever bounds the controller is told. `b_ref = 1`
//! reads "x % bias of b" as a fraction of b̄ itself (the Fig. 2 caption's
//! reading; docs/paper-notes.md N11). `r(t)` is uniform on [−1, 1], drawn once
//! per `hold` seconds (0.01 s) from a seeded ChaCha8 stream and held: the
//! same signal whatever the integration step. The paper's Fig. 2 is
//! `a_bias = 1, b_bias = 0.5` (true a = 2ā, true b = 1.25·b̄); Fig. 8 is
//! `a_bias = a_random = 0.5` and `b_bias = b_random = 0.25`.

use ehservo_core::control::Signal;
use ehservo_core::math::sgn;
use ehservo_core::rk4::OdeState;
use ehservo_core::servo::{BothDirections, Load, NominalModel, ServoParams};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// The plant's parameters at one instant, as they differ from the nominal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Variation {
    /// Δa1, Δa2, Δa3.
    pub da: [f64; 3],
    /// δb, with true `b = (1 + δb)·b_nominal` (so `Δb = δb·b_nominal`).
    pub db_rel: f64,
}

impl Variation {
    /// No variation.
    pub const NONE: Variation = Variation {
        da: [0.0; 3],
        db_rel: 0.0,
    };
}

/// Sizes of the variation, as fractions of the paper's bounds: a scenario's
/// `[uncertainty]` table, the Fig. 2 case by default.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct UncertaintySpec {
    /// Bias fraction of α_i = |ā_i|.
    pub a_bias: f64,
    /// Random fraction of α_i.
    pub a_random: f64,
    /// Bias fraction of β = 0.5·|b̄|.
    pub b_bias: f64,
    /// Random fraction of β.
    pub b_random: f64,
    /// The size the b fractions refer to, as a multiple of b̄ (0.5: β).
    pub b_reference: f64,
    /// Seed of the random signal.
    pub seed: u64,
    /// Hold period of the random signal (s).
    pub hold: f64,
}

/// The paper's Fig. 2 case: Δa_i = α_i, Δb = 0.5β (SPEC §2), seed 0, held
/// 0.01 s.
impl Default for UncertaintySpec {
    fn default() -> Self {
        Self {
            a_bias: 1.0,
            b_bias: 0.5,
            ..Self::NONE
        }
    }
}

impl UncertaintySpec {
    /// No variation at all.
    pub const NONE: UncertaintySpec = UncertaintySpec {
        a_bias: 0.0,
        a_random: 0.0,
        b_bias: 0.0,
        b_random: 0.0,
        b_reference: 0.5,
        seed: 0,
        hold: 0.01,
    };
}

/// A piecewise-constant random variation, held over `hold` seconds.
#[derive(Debug, Clone)]
pub struct UncertaintySignal {
    spec: UncertaintySpec,
    abar: [f64; 3],
    rng: ChaCha8Rng,
    drawn: u64,
    r: [f64; 4],
    random: bool,
    /// The variation while no random part is drawn (r = 0): the bias alone,
    /// the same every step, so computed once.
    bias: Variation,
}

impl UncertaintySignal {
    /// A signal for the plant with nominal coefficients `abar`.
    pub fn new(spec: UncertaintySpec, abar: [f64; 3]) -> Self {
        let mut s = Self {
            spec,
            abar,
            rng: ChaCha8Rng::seed_from_u64(spec.seed),
            drawn: 0,
            r: [0.0; 4],
            random: spec.a_random != 0.0 || spec.b_random != 0.0,
            bias: Variation::NONE,
        };
        s.bias = s.variation();
        s
    }

    /// One uniform draw on [−1, 1): 53 random bits, portable across
    /// platforms and `rand` versions.
    fn uniform(&mut self) -> f64 {
        let bits = self.rng.next_u64() >> 11;
        (bits as f64) * (2.0 / (1u64 << 53) as f64) - 1.0
    }

    /// The variation at time `t ≥ 0`. Times must not go backwards across
    /// hold intervals (the simulator only moves forward).
    pub fn at(&mut self, t: f64) -> Variation {
        // Interval index; the tiny offset keeps t = k·hold in interval k
        // despite rounding of k·h.
        let j = (t / self.spec.hold + 1e-9).floor().max(0.0) as u64;
        self.at_interval(j)
    }

    /// How many (sub)steps of `hs` seconds make one hold interval, when the
    /// hold is a whole number of them (to 1e-9): the simulator then finds a
    /// (sub)step's interval by integer division, exact however long the run.
    pub fn steps_per_hold(&self, hs: f64) -> Option<u64> {
        let r = self.spec.hold / hs;
        let n = r.round();
        ((1.0..9.0e15).contains(&n) && (r - n).abs() <= 1e-9 * n).then_some(n as u64)
    }

    /// The variation over the `j`-th (sub)step of `hs` seconds (it starts
    /// at `j·hs`), with `per_hold = steps_per_hold(hs)`.
    #[inline]
    pub fn at_step(&mut self, j: u64, hs: f64, per_hold: Option<u64>) -> Variation {
        if !self.random {
            return self.bias;
        }
        let i = self.interval(j, hs, per_hold);
        self.at_interval(i)
    }

    /// The hold interval of the `j`-th (sub)step of `hs` seconds: `j / n`
    /// in integers when a hold is `n` (sub)steps, else from the time.
    pub fn interval(&self, j: u64, hs: f64, per_hold: Option<u64>) -> u64 {
        match per_hold {
            Some(n) => j / n,
            None => ((j as f64 * hs) / self.spec.hold + 1e-9).floor().max(0.0) as u64,
        }
    }

    /// The variation over hold interval `j` (intervals never go backwards).
    pub fn at_interval(&mut self, j: u64) -> Variation {
        if !self.random {
            return self.bias;
        }
        while self.drawn <= j {
            for i in 0..4 {
                self.r[i] = self.uniform();
            }
            self.drawn += 1;
        }
        self.variation()
    }

    /// The variation for the current draw `r`.
    #[inline]
    fn variation(&self) -> Variation {
        let s = &self.spec;
        let da = core::array::from_fn(|i| self.abar[i].abs() * (s.a_bias + s.a_random * self.r[i]));
        Variation {
            da,
            db_rel: s.b_reference * (s.b_bias + s.b_random * self.r[3]),
        }
    }
}

/// Most physical states a plant may log per sample ([`Plant::STATES`]).
pub const MAX_STATES: usize = 4;

/// The load pressure Pl of the paper's servo.
const LOAD_PRESSURE: [Signal; 1] = [Signal::new(
    "p_load",
    "p_load_Pa",
    "Pa",
    "load pressure Pl (the third-order plant: from the torque balance (4))",
)];

/// A plant as a pure derivative over its own state (of any dimension: a
/// spool, a cylinder's two pressures), with an output map to the
/// x = (θ, θ̇, θ̈) that the sensors see.
pub trait Plant {
    /// The plant's state.
    type State: OdeState;
    /// The physical states beyond x = (θ, θ̇, θ̈) that a trace carries
    /// (a load pressure, chamber pressures), at most [`MAX_STATES`].
    const STATES: &'static [Signal] = &[];
    /// Their values at the state `s`, whose output is `x`.
    fn states(&self, _s: &Self::State, _x: &[f64; 3], _out: &mut [f64; MAX_STATES]) {}
    /// The plant state that corresponds to x(0).
    fn initial_state(&self, x0: [f64; 3]) -> Self::State;
    /// x = (θ, θ̇, θ̈) from the plant state.
    fn measure(&self, s: &Self::State) -> [f64; 3];
    /// The state derivative under input `u` (the valve command, V) and
    /// variation `v`.
    fn deriv(&self, t: f64, s: &Self::State, u: f64, v: &Variation, ds: &mut Self::State);
    /// The nominal model (what a controller is told).
    fn nominal(&self) -> &NominalModel;
    /// The lumped uncertainty of (19) without ξ: `Σ Δa_i x_i − Δb·u_eq + d`,
    /// with `Δb = b_true − b̄` (b_true at the sign of the applied `u`).
    fn lumped_uncertainty(
        &self,
        x: &[f64; 3],
        u: f64,
        u_eq: f64,
        b_bar: f64,
        v: &Variation,
    ) -> f64 {
        let m = self.nominal();
        let (b, d) = m.b_and_d(x, sgn(u));
        lumped(x, u_eq, b_bar, v, b, d)
    }

    /// [`Plant::deriv`] at `s` under the input `u_plant`, and
    /// [`Plant::lumped_uncertainty`] at `x = measure(s)` for the command
    /// `u`: the simulator asks for both at once for the first RK4 stage of
    /// a sample (whose state is the sample's), so that a plant can evaluate
    /// what the two share only once, with what [`Plant::prepare`] made at
    /// `s` if anything. Must return exactly what the two calls return; the
    /// default makes them.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    fn deriv_and_lumped(
        &self,
        prepared: Option<&BothDirections>,
        t: f64,
        s: &Self::State,
        u_plant: f64,
        v: &Variation,
        ds: &mut Self::State,
        u: f64,
        u_eq: f64,
        b_bar: f64,
    ) -> f64 {
        self.deriv_prepared(prepared, t, s, u_plant, v, ds);
        self.lumped_uncertainty(&self.measure(s), u, u_eq, b_bar, v)
    }

    /// What the derivative at state `s` needs of `s` alone, before the
    /// command is known: the simulator asks for it as a sample begins, so
    /// that its latency (for the third-order plant: the load's sine, and
    /// the division and root of both valve directions) runs beside the
    /// law's instead of after the command, and hands it to
    /// [`Plant::deriv_prepared`] and [`Plant::deriv_and_lumped`] for the
    /// sample's first RK4 stage, at that same state `s` only (the
    /// caller's contract: nothing checks it). `None` (the default):
    /// nothing. The values are the third-order model's
    /// ([`BothDirections`]: b for both valve directions, d), which the
    /// plants of this crate that prepare anything share.
    #[inline]
    fn prepare(&self, _s: &Self::State) -> Option<BothDirections> {
        None
    }

    /// [`Plant::deriv`] at the state `prepared` was made from, by
    /// [`Plant::prepare`]: must give exactly what `deriv` gives; the
    /// default calls it.
    #[inline]
    fn deriv_prepared(
        &self,
        _prepared: Option<&BothDirections>,
        t: f64,
        s: &Self::State,
        u: f64,
        v: &Variation,
        ds: &mut Self::State,
    ) {
        self.deriv(t, s, u, v, ds);
    }
}

/// `Σ Δa_i x_i − Δb·u_eq + d` with `Δb = b_true − b̄`, from the nominal
/// `b(x, sgn u)` and `d(x)`: the expression of (19) both plants share.
#[inline]
fn lumped(x: &[f64; 3], u_eq: f64, b_bar: f64, v: &Variation, b: f64, d: f64) -> f64 {
    let b_true = (1.0 + v.db_rel) * b;
    v.da[0] * x[0] + v.da[1] * x[1] + v.da[2] * x[2] - (b_true - b_bar) * u_eq + d
}

/// The third-order model (8)–(9).
#[derive(Debug, Clone, Copy)]
pub struct ThirdOrderPlant {
    model: NominalModel,
}

impl ThirdOrderPlant {
    /// From validated physical parameters and load.
    pub fn new(params: ServoParams, load: Load) -> Self {
        Self {
            model: NominalModel::new(params, load),
        }
    }
}

impl Plant for ThirdOrderPlant {
    type State = [f64; 3];
    const STATES: &'static [Signal] = &LOAD_PRESSURE;

    fn states(&self, _s: &[f64; 3], x: &[f64; 3], out: &mut [f64; MAX_STATES]) {
        out[0] = self.model.load_pressure(x);
    }

    fn initial_state(&self, x0: [f64; 3]) -> [f64; 3] {
        x0
    }

    #[inline]
    fn measure(&self, s: &[f64; 3]) -> [f64; 3] {
        *s
    }

    /// `b` and `d` at x in one evaluation ([`NominalModel::b_and_d`]): one
    /// `sincos` per stage instead of two sines and a cosine.
    #[inline]
    fn deriv(&self, _t: f64, x: &[f64; 3], u: f64, v: &Variation, dx: &mut [f64; 3]) {
        let (b, d) = self.model.b_and_d(x, sgn(u));
        self.deriv_with(x, u, v, b, d, dx);
    }

    fn nominal(&self) -> &NominalModel {
        &self.model
    }

    /// b and d once for both when the input and the command have the same
    /// sign (the valve root of both is then the same); x is the state.
    #[inline]
    fn deriv_and_lumped(
        &self,
        prepared: Option<&BothDirections>,
        _t: f64,
        x: &[f64; 3],
        u_plant: f64,
        v: &Variation,
        dx: &mut [f64; 3],
        u: f64,
        u_eq: f64,
        b_bar: f64,
    ) -> f64 {
        let s = sgn(u);
        let (b, d) = self.b_and_d(prepared, x, s);
        // Signs are exactly −1, 0 or +1 (never −0): compare their bits.
        if sgn(u_plant).to_bits() == s.to_bits() {
            self.deriv_with(x, u_plant, v, b, d, dx);
        } else {
            let (bp, dp) = self.b_and_d(prepared, x, sgn(u_plant));
            self.deriv_with(x, u_plant, v, bp, dp, dx);
        }
        lumped(x, u_eq, b_bar, v, b, d)
    }

    /// b(x, ±1) and d(x) ([`NominalModel::b_and_d_both`]).
    #[inline]
    fn prepare(&self, x: &[f64; 3]) -> Option<BothDirections> {
        Some(self.model.b_and_d_both(x))
    }

    #[inline]
    fn deriv_prepared(
        &self,
        prepared: Option<&BothDirections>,
        _t: f64,
        x: &[f64; 3],
        u: f64,
        v: &Variation,
        dx: &mut [f64; 3],
    ) {
        let (b, d) = self.b_and_d(prepared, x, sgn(u));
        self.deriv_with(x, u, v, b, d, dx);
    }
}

impl ThirdOrderPlant {
    /// b(x, s) and d(x): picked from what was prepared at x, if anything,
    /// else evaluated (the same bits either way).
    #[inline]
    fn b_and_d(&self, prepared: Option<&BothDirections>, x: &[f64; 3], s: f64) -> (f64, f64) {
        match prepared {
            Some(both) => self.model.b_and_d_from(both, s),
            None => self.model.b_and_d(x, s),
        }
    }

    /// ẋ from the nominal `b(x, sgn u)` and `d(x)`.
    #[inline]
    fn deriv_with(&self, x: &[f64; 3], u: f64, v: &Variation, b: f64, d: f64, dx: &mut [f64; 3]) {
        let a = &self.model.coeffs;
        let b = (1.0 + v.db_rel) * b;
        dx[0] = x[1];
        dx[1] = x[2];
        dx[2] = -(a.a1 + v.da[0]) * x[0] - (a.a2 + v.da[1]) * x[1] - (a.a3 + v.da[2]) * x[2]
            + b * u
            - d;
    }
}

/// The physical model (1)–(6) in (θ, θ̇, Pl).
#[derive(Debug, Clone, Copy)]
pub struct PhysicalPlant {
    model: NominalModel,
}

impl PhysicalPlant {
    /// From validated physical parameters and load.
    pub fn new(params: ServoParams, load: Load) -> Self {
        Self {
            model: NominalModel::new(params, load),
        }
    }
}

impl Plant for PhysicalPlant {
    type State = [f64; 3];
    const STATES: &'static [Signal] = &LOAD_PRESSURE;

    fn states(&self, s: &[f64; 3], _x: &[f64; 3], out: &mut [f64; MAX_STATES]) {
        out[0] = s[2];
    }

    /// Pl(0) from the torque balance (4) with θ̈(0) = x0[2].
    fn initial_state(&self, x0: [f64; 3]) -> [f64; 3] {
        [x0[0], x0[1], self.model.load_pressure(&x0)]
    }

    /// θ̈ from (4): `(Pl·Dm − Bm·θ̇ − G·θ − Tl)/Jt`.
    #[inline]
    fn measure(&self, s: &[f64; 3]) -> [f64; 3] {
        let p = &self.model.params;
        let tl = self.model.load.torque(s[0], s[1]);
        [
            s[0],
            s[1],
            (s[2] * p.dm - p.bm * s[1] - p.g * s[0] - tl) / p.jt,
        ]
    }

    #[inline]
    fn deriv(&self, _t: f64, s: &[f64; 3], u: f64, v: &Variation, ds: &mut [f64; 3]) {
        let p = &self.model.params;
        let x = self.measure(s);
        let (kg, _) = p.flow_gain(s[2], sgn(u));
        let flow = (1.0 + v.db_rel) * kg * p.kv * u;
        ds[0] = s[1];
        ds[1] = x[2];
        ds[2] = 4.0 * p.beta_e / p.vt * (flow - p.dm * s[1] - p.kce * s[2])
            - p.jt / p.dm * (v.da[0] * x[0] + v.da[1] * x[1] + v.da[2] * x[2]);
    }

    fn nominal(&self) -> &NominalModel {
        &self.model
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;

    #[test]
    fn bias_only_is_constant_and_matches_fig2() {
        let abar = ServoParams::paper().coefficients().as_array();
        let mut s = UncertaintySignal::new(
            UncertaintySpec {
                a_bias: 1.0,
                b_bias: 0.5,
                ..UncertaintySpec::NONE
            },
            abar,
        );
        let v = s.at(3.7);
        // Fig. 2: Δa_i = α_i = |ā_i|, Δb = 0.5β = 0.25·b̄ → true b = 1.25·b̄.
        assert_eq!(v.da, abar);
        assert!((v.db_rel - 0.25).abs() < 1e-15);
    }

    /// The random part is held over each 0.01 s and independent of how
    /// often it is asked for.
    #[test]
    fn random_signal_is_held_and_step_independent() {
        let abar = [1.0, 1.0, 1.0];
        let spec = UncertaintySpec {
            a_random: 1.0,
            b_random: 1.0,
            seed: 7,
            ..UncertaintySpec::NONE
        };
        let mut coarse = UncertaintySignal::new(spec, abar);
        let mut fine = UncertaintySignal::new(spec, abar);
        for k in 0..100 {
            let t = k as f64 * 0.01;
            let vc = coarse.at(t);
            for j in 0..10 {
                let vf = fine.at(t + j as f64 * 0.001);
                assert_eq!(vc, vf, "t = {t}, j = {j}");
            }
        }
        // Within [−1, 1] and not constant.
        let mut s = UncertaintySignal::new(spec, abar);
        let vals: Vec<f64> = (0..200).map(|k| s.at(k as f64 * 0.01).da[0]).collect();
        assert!(vals.iter().all(|v| (-1.0..=1.0).contains(v)));
        let mean = vals.iter().sum::<f64>() / 200.0;
        assert!(mean.abs() < 0.15, "mean {mean}");
        assert!(vals.windows(2).any(|w| w[0] != w[1]));
    }

    /// The hold interval of a (sub)step is exact however long the run: with
    /// h = 0.01/7 s, sub-step 699 999 958 = 7·99 999 994 starts interval
    /// 99 999 994, which the time-based formula misses by one
    /// (699 999 958·h/0.01 rounds just below the integer, by more than the
    /// 1e-9 guard).
    #[test]
    fn hold_intervals_by_integer_index() {
        let s = UncertaintySignal::new(UncertaintySpec::NONE, [1.0; 3]);
        let hs = 0.01 / 7.0;
        let n = s.steps_per_hold(hs);
        assert_eq!(n, Some(7));
        let j = 699_999_958;
        assert_eq!(s.interval(j, hs, n), 99_999_994);
        assert_eq!(s.interval(j - 1, hs, n), 99_999_993);
        assert_eq!(s.interval(j, hs, None), 99_999_993, "the float path drifts");
        assert_eq!(
            s.steps_per_hold(0.003),
            None,
            "0.01 s is not a whole number of 3 ms"
        );
    }

    /// Arguments over every magnitude a run can meet and then some: a
    /// deterministic spread of sign, exponent and mantissa, the edges of
    /// libm's small-argument branches, and the special values.
    fn spread() -> Vec<f64> {
        let mut v = vec![
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            5e-324,
            1.0536712127723509e-8, // 2^-27·√2: sincos's and cos's tiny branch
            1.4901161193847656e-8, // 2^-26: sin's tiny branch
            std::f64::consts::FRAC_PI_4,
            f64::MAX,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        let mut z = 0x9E37_79B9_7F4A_7C15_u64;
        for i in 0..200_000u64 {
            z = z
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            // Exponents from 2^-40 to 2^40, denser near the run's range.
            let e = (z >> 58) as i32 - 40 + (i % 17) as i32;
            let m = 1.0 + (z >> 11) as f64 / (1u64 << 53) as f64;
            let x = m * 2f64.powi(e.clamp(-40, 40));
            v.push(if i % 2 == 0 { x } else { -x });
        }
        // Around the tiny-branch edges, ulp by ulp.
        for edge in [1.0536712127723509e-8, 1.4901161193847656e-8] {
            let b = f64::to_bits(edge);
            for d in 0..2000u64 {
                v.push(f64::from_bits(b - 1000 + d));
            }
        }
        v
    }

    /// `libm::sincos` is `libm::sin` and `libm::cos` to the bit.
    #[test]
    fn sincos_is_sin_and_cos() {
        for x in spread() {
            let (s, c) = libm::sincos(x);
            assert_eq!(s.to_bits(), libm::sin(x).to_bits(), "sin {x:e}");
            assert_eq!(c.to_bits(), libm::cos(x).to_bits(), "cos {x:e}");
        }
    }

    /// The plant's shared evaluation of b and d is the nominal model's
    /// `b` and `d`, bit for bit, with and without friction, at every sign
    /// and in the clamped valve root; so are the derivative and the lumped
    /// uncertainty built on it.
    #[test]
    fn b_and_d_are_the_nominal_models_bit_for_bit() {
        let p = ServoParams::paper();
        let friction = Load {
            friction: Some(ehservo_core::servo::Friction::default()),
            ..Load::paper()
        };
        let odd = Load {
            amplitude: -3.5,
            wavenumber: 1e3,
            friction: None,
        };
        let xs = spread();
        for load in [Load::paper(), Load::none(), friction, odd] {
            let plant = ThirdOrderPlant::new(p, load);
            let m = NominalModel::new(p, load);
            let v = Variation {
                da: [0.4, -13000.0, 170.0],
                db_rel: 0.25,
            };
            for (i, w) in xs.windows(3).enumerate().step_by(7) {
                let x = [w[0] * 1e-2, w[1], w[2] * 1e2];
                let both = plant.prepare(&x).expect("the third-order plant prepares");
                for s in [-1.0, 0.0, 1.0] {
                    let (b, d) = plant.model.b_and_d(&x, s);
                    assert_eq!(b.to_bits(), m.b(&x, s).0.to_bits(), "b at {x:?}, {s}");
                    assert_eq!(d.to_bits(), m.d(&x).to_bits(), "d at {x:?}");
                    // Both directions made before the sign is known.
                    let (bp, dp) = plant.model.b_and_d_from(&both, s);
                    assert_eq!(bp.to_bits(), b.to_bits(), "prepared b at {x:?}, {s}");
                    assert_eq!(dp.to_bits(), d.to_bits(), "prepared d at {x:?}");
                }
                let u = w[(i % 3).min(2)] * 1e-3;
                let mut dx = [0.0; 3];
                plant.deriv(0.0, &x, u, &v, &mut dx);
                // The prepared derivative, and the first stage with the
                // lumped uncertainty with and without what was prepared, are
                // `deriv` and `lumped_uncertainty` (held to the formulas
                // below), for commands of every sign pair (0 included).
                for (uc, up) in [(u, u), (u, -u), (0.0, u), (u, 0.0), (-u, u)] {
                    let (ueq, bb) = (w[0] * 0.3, 16000.0);
                    let mut want = [0.0; 3];
                    plant.deriv(0.0, &x, up, &v, &mut want);
                    let lumped = plant.lumped_uncertainty(&x, uc, ueq, bb, &v);
                    let mut got = [0.0; 3];
                    plant.deriv_prepared(Some(&both), 0.0, &x, up, &v, &mut got);
                    assert_eq!(
                        got.map(f64::to_bits),
                        want.map(f64::to_bits),
                        "at {x:?}, {up}"
                    );
                    for prep in [Some(&both), None] {
                        let mut got = [0.0; 3];
                        let l =
                            plant.deriv_and_lumped(prep, 0.0, &x, up, &v, &mut got, uc, ueq, bb);
                        let at = format!("{x:?}, {uc}, {up}, prepared {}", prep.is_some());
                        assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits), "at {at}");
                        assert_eq!(l.to_bits(), lumped.to_bits(), "lumped at {at}");
                    }
                }
                let a = &m.coeffs;
                let bt = (1.0 + v.db_rel) * m.b(&x, sgn(u)).0;
                let dx2 =
                    -(a.a1 + v.da[0]) * x[0] - (a.a2 + v.da[1]) * x[1] - (a.a3 + v.da[2]) * x[2]
                        + bt * u
                        - m.d(&x);
                assert_eq!(dx[2].to_bits(), dx2.to_bits(), "deriv at {x:?}, u = {u}");
                let (u_eq, b_bar) = (w[1] * 0.5, 17000.0);
                let old = v.da[0] * x[0] + v.da[1] * x[1] + v.da[2] * x[2] - (bt - b_bar) * u_eq
                    + m.d(&x);
                let new = plant.lumped_uncertainty(&x, u, u_eq, b_bar, &v);
                assert_eq!(new.to_bits(), old.to_bits(), "lumped at {x:?}");
                let phys = PhysicalPlant::new(p, load).lumped_uncertainty(&x, u, u_eq, b_bar, &v);
                assert_eq!(phys.to_bits(), old.to_bits(), "default lumped at {x:?}");
            }
        }
    }

    /// The physical model's measured θ̈ and the third-order model's x3 have
    /// the same derivative at a state (the two models are one system).
    #[test]
    fn models_have_the_same_jerk() {
        let p = ServoParams::paper();
        let third = ThirdOrderPlant::new(p, Load::paper());
        let phys = PhysicalPlant::new(p, Load::paper());
        let x = [0.03, -0.2, 1.5];
        let v = Variation {
            da: [0.4, 13000.0, 170.0],
            db_rel: 0.25,
        };
        for &u in &[0.3, -0.2] {
            let mut d3 = [0.0; 3];
            third.deriv(0.0, &x, u, &v, &mut d3);
            // d/dt of the physical θ̈ = (Ṗl·Dm − Bm·θ̈ − G·θ̇ − Ṫl)/Jt.
            let s = phys.initial_state(x);
            assert!((phys.measure(&s)[2] - x[2]).abs() < 1e-9);
            let mut ds = [0.0; 3];
            phys.deriv(0.0, &s, u, &v, &mut ds);
            let l = Load::paper();
            let jerk =
                (ds[2] * p.dm - p.bm * x[2] - p.g * x[1] - l.torque_rate(x[0], x[1], x[2])) / p.jt;
            assert!(
                (jerk - d3[2]).abs() < 1e-6 * d3[2].abs().max(1.0),
                "{jerk} vs {}",
                d3[2]
            );
        }
    }
}
