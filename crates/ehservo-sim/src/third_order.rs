//! The paper's third-order model (8)–(9) as a plant, in x = (θ, θ̇, θ̈):
//! `ẋ3 = −Σ(a_i + Δa_i)·x_i + (1 + δb)·b(x, sgn u)·u − d(x)`.
//!
//! **Variation.** The paper's form (`[uncertainty]`'s a/b keys,
//! [`Variation`]) as in SPEC §2. The physical form (`[uncertainty.physical]`)
//! as a bias only: the true plant is then (8)–(9) of the varied physical
//! parameters (Jt·mass, βe·bulk_modulus, Kce·leakage, Ps·supply_pressure,
//! the load's amplitude·load and its friction·friction), which the
//! controller does not know; its coefficients, b(x, u) and d(x) are that
//! model's. A random physical part changes the model every hold interval,
//! which this plant does not do: it is refused, with `model = "physical"`
//! (the same servo in (θ, θ̇, Pl), which carries it exactly) as the way.

use crate::axis::Axis;
use crate::error::KeyError;
use crate::plant::MAX_STATES;
use crate::plant::{lumped, Draw, Plant, PlantConfig, PlantContext, UncertaintySpec, Variation};
use crate::uncertainty::Factors;
use ehservo_core::control::Signal;
use ehservo_core::math::sgn;
use ehservo_core::servo::{BothDirections, Load, NominalModel, ServoParams};
use serde::{Deserialize, Serialize};

/// The load pressure Pl of the paper's servo.
pub(crate) const LOAD_PRESSURE: [Signal; 1] = [Signal::new(
    "p_load",
    "p_load_Pa",
    "Pa",
    "load pressure Pl (the third-order plant: from the torque balance (4))",
)];

/// The paper's parameters varied by the physical factors `f`: Jt by mass,
/// βe by bulk modulus, Kce by leakage, Ps by supply pressure; the load's
/// amplitude by load and its friction forces by friction.
///
/// ```
/// use ehservo_sim::core::servo::{Load, ServoParams};
/// use ehservo_sim::plant::Factors;
/// use ehservo_sim::third_order::varied;
///
/// // `mass = { bias = 1.0 }`: twice the inertia, so a3 = Bm/Jt + 4βe·Kce/Vt
/// // loses half its first term.
/// let p = ServoParams::paper();
/// let (q, _) = varied(&p, &Load::paper(), &Factors { mass: 2.0, ..Factors::ONE });
/// assert_eq!(q.jt, 2.0 * p.jt);
/// let (a3p, a3q) = (p.coefficients().a3, q.coefficients().a3);
/// assert!((a3p - a3q - p.bm / (2.0 * p.jt)).abs() < 1e-9);
/// ```
pub fn varied(p: &ServoParams, load: &Load, f: &Factors) -> (ServoParams, Load) {
    let p = ServoParams {
        jt: p.jt * f.mass,
        beta_e: p.beta_e * f.bulk_modulus,
        kce: p.kce * f.leakage,
        ps: p.ps * f.supply_pressure,
        ..*p
    };
    let mut l = *load;
    l.amplitude *= f.load;
    if let Some(fr) = &mut l.friction {
        fr.coulomb *= f.friction;
        fr.stiction *= f.friction;
        fr.viscous *= f.friction;
    }
    (p, l)
}

/// The third-order model (8)–(9).
///
/// ```
/// use ehservo_sim::core::servo::{Load, ServoParams};
/// use ehservo_sim::plant::{Draw, Plant, ThirdOrderPlant, UncertaintySpec};
///
/// let p = ServoParams::paper();
/// let plant = ThirdOrderPlant::new(p, Load::none());
/// // b of (9) at Pl = 0: 4βe·Dm·Kv·Cd·Ag·√(Ps/ρ)/(Vt·Jt).
/// let b0 = 4.0 * p.beta_e * p.dm * p.kv * p.cd * p.ag * (p.ps / p.rho).sqrt() / (p.vt * p.jt);
/// // Fig. 2's variation (the default [uncertainty]): true b = 1.25·b̄.
/// let v = plant.variation(&UncertaintySpec::default(), &Draw::default());
/// assert_eq!(v.db_rel, 0.25);
/// // At rest under u = 1 V: ẋ = (x2, x3, b·u) = (0, 0, 1.25·b̄).
/// let mut dx = [0.0; 3];
/// plant.deriv(0.0, &[0.0; 3], 1.0, &v, &mut dx);
/// assert_eq!(dx[..2], [0.0, 0.0]);
/// assert!((dx[2] - 1.25 * b0).abs() <= 1e-12 * b0);
/// ```
#[derive(Debug, Clone, Copy)]
pub struct ThirdOrderPlant {
    model: NominalModel,
    /// The true model: the nominal one, unless a physical bias makes it
    /// differ (`biased`). Held whole rather than as an `Option` beside the
    /// nominal model, so that the derivative reads its coefficients at
    /// fixed places instead of picking one of two models at every stage.
    truth: NominalModel,
    /// Whether `truth` differs from `model` (a physical bias).
    biased: bool,
}

impl ThirdOrderPlant {
    /// From validated physical parameters and load: the plant is its
    /// nominal model (the variation, if any, is the paper's form).
    pub fn new(params: ServoParams, load: Load) -> Self {
        let model = NominalModel::new(params, load);
        Self {
            model,
            truth: model,
            biased: false,
        }
    }

    /// The plant whose true parameters are the nominal ones varied by `f`.
    pub fn with_bias(params: ServoParams, load: Load, f: &Factors) -> Self {
        let mut p = Self::new(params, load);
        if *f != Factors::ONE {
            let (tp, tl) = varied(&params, &load, f);
            p.truth = NominalModel::new(tp, tl);
            p.biased = true;
        }
        p
    }

    /// The model the plant's derivative is: the true one.
    #[inline(always)]
    fn truth(&self) -> &NominalModel {
        &self.truth
    }

    /// b(x, s) and d(x) of the true model: picked from what was prepared
    /// at x, if anything, else evaluated (the same bits either way).
    /// Always inlined: the pick is a few instructions, and left to LLVM
    /// it had become a call of its own at every sample's lumped
    /// uncertainty.
    #[inline(always)]
    fn b_and_d(&self, prepared: Option<&BothDirections>, x: &[f64; 3], s: f64) -> (f64, f64) {
        let m = self.truth();
        match prepared {
            Some(both) => m.b_and_d_from(both, s),
            None => m.b_and_d(x, s),
        }
    }

    /// ẋ from the true `b(x, sgn u)` and `d(x)`.
    #[inline]
    fn deriv_with(&self, x: &[f64; 3], u: f64, v: &Variation, b: f64, d: f64, dx: &mut [f64; 3]) {
        let a = &self.truth().coeffs;
        let b = (1.0 + v.db_rel) * b;
        dx[0] = x[1];
        dx[1] = x[2];
        dx[2] = -(a.a1 + v.da[0]) * x[0] - (a.a2 + v.da[1]) * x[1] - (a.a3 + v.da[2]) * x[2]
            + b * u
            - d;
    }

    /// (19) from the true b and d at x: the paper's form alone when the
    /// plant is its nominal model, else with the true coefficients'
    /// difference from the nominal ones added to the Δa_i.
    #[inline]
    fn lumped_with(
        &self,
        x: &[f64; 3],
        u_eq: f64,
        b_bar: f64,
        v: &Variation,
        b: f64,
        d: f64,
    ) -> f64 {
        if self.biased {
            let (at, an) = (self.truth.coeffs.as_array(), self.model.coeffs.as_array());
            let da = core::array::from_fn(|i| at[i] + v.da[i] - an[i]);
            lumped(x, u_eq, b_bar, &Variation { da, ..*v }, b, d)
        } else {
            lumped(x, u_eq, b_bar, v, b, d)
        }
    }
}

impl Plant for ThirdOrderPlant {
    type State = [f64; 3];
    type Variation = Variation;
    type Prepared = BothDirections;
    const STATES: &'static [Signal] = &LOAD_PRESSURE;

    fn states(&self, _t: f64, _s: &[f64; 3], x: &[f64; 3], out: &mut [f64; MAX_STATES]) {
        out[0] = self.truth().load_pressure(x);
    }

    fn initial_state(&self, x0: [f64; 3], _v: &Variation) -> [f64; 3] {
        x0
    }

    #[inline]
    fn measure(&self, _t: f64, s: &[f64; 3], _v: &Variation) -> [f64; 3] {
        *s
    }

    /// `b` and `d` at x in one evaluation ([`NominalModel::b_and_d`]): one
    /// `sincos` per stage instead of two sines and a cosine. Whole in the
    /// caller's stage, where what depends on `u` alone (its sign, the
    /// valve direction's supply term) is shared by a step's stages.
    #[inline(always)]
    fn deriv(&self, _t: f64, x: &[f64; 3], u: f64, v: &Variation, dx: &mut [f64; 3]) {
        let (b, d) = self.truth().b_and_d(x, sgn(u));
        self.deriv_with(x, u, v, b, d, dx);
    }

    fn nominal(&self) -> &NominalModel {
        &self.model
    }

    #[inline]
    fn variation(&self, spec: &UncertaintySpec, r: &Draw) -> Variation {
        Variation::of(spec, &self.model.coeffs.as_array(), r)
    }

    fn lumped_uncertainty(
        &self,
        _s: &[f64; 3],
        x: &[f64; 3],
        u: f64,
        u_eq: f64,
        b_bar: f64,
        v: &Variation,
    ) -> f64 {
        let (b, d) = self.truth().b_and_d(x, sgn(u));
        self.lumped_with(x, u_eq, b_bar, v, b, d)
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
        self.lumped_with(x, u_eq, b_bar, v, b, d)
    }

    /// b(x, ±1) and d(x) of the true model ([`NominalModel::b_and_d_both`]).
    #[inline]
    fn prepare(&self, x: &[f64; 3]) -> Option<BothDirections> {
        Some(self.truth().b_and_d_both(x))
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

/// `[plant] model = "third-order"` (the default): `[plant.params]`, the
/// paper's physical parameters (SI, by the paper's symbol: `Ps`, `beta_e`,
/// `Vt`, `Kce`, `Dm`, `Jt`, `Bm`, `Kv`, `G`, `rho`, `Cd`, `Ag`); the load is
/// the scenario's `[load]`.
///
/// ```
/// use ehservo_sim::plant::{Plant, PlantConfig};
/// use ehservo_sim::third_order::ThirdOrderCfg;
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
/// // Twice the paper's inertia, every other key the paper's.
/// let cfg: ThirdOrderCfg = toml::from_str("[params]\nJt = 0.11304").unwrap();
/// let heavy = cfg.build(&ctx).unwrap();
/// let paper = ThirdOrderCfg::default().build(&ctx).unwrap();
/// // a2 = (G + 4βe·Dm²/Vt + 4βe·Kce·Bm/Vt)/Jt of (9): halved.
/// let (a2h, a2p) = (heavy.nominal().coeffs.a2, paper.nominal().coeffs.a2);
/// assert!((a2h - a2p / 2.0).abs() <= 1e-12 * a2p);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct ThirdOrderCfg {
    /// `[plant.params]`.
    pub params: ServoParams,
}

/// The checks the paper's family shares: the parameters, the load, and
/// the variation's physical form (as a bias, unless `random` is allowed).
pub(crate) fn paper_family(
    params: &ServoParams,
    ctx: &PlantContext,
    random: bool,
) -> Result<Load, KeyError> {
    params
        .validate()
        .map_err(|e| KeyError::param("plant.params", e))?;
    let load = ctx.load.unwrap_or_else(Load::paper);
    load.validate().map_err(|e| {
        let prefix = if matches!(e.name, "amplitude" | "wavenumber") {
            "load"
        } else {
            "load.friction"
        };
        KeyError::param(prefix, e)
    })?;
    let phys = &ctx.uncertainty.physical;
    phys.validate()
        .map_err(|e| e.under("uncertainty.physical"))?;
    if !random && phys.is_random() {
        return Err(KeyError::new(
            "uncertainty.physical",
            "the third-order plant takes a physical variation as a bias only (random parts change the model every hold interval): use plant.model = \"physical\", the same servo in (θ, θ̇, Pl), which carries them exactly",
        ));
    }
    Ok(load)
}

impl PlantConfig for ThirdOrderCfg {
    const MODEL: &'static str = "third-order";
    const DOC: &'static str = "the paper's third-order model (8)–(9) in (θ, θ̇, θ̈)";
    const PAPER_UNCERTAINTY: bool = true;
    const USES_LOAD: bool = true;
    type Plant = ThirdOrderPlant;

    fn axis(&self) -> Axis {
        Axis::Rotary
    }

    fn build(&self, ctx: &PlantContext) -> Result<ThirdOrderPlant, KeyError> {
        let load = paper_family(&self.params, ctx, false)?;
        let f = ctx.uncertainty.physical.factors(&[0.0; 6]);
        Ok(ThirdOrderPlant::with_bias(self.params, load, &f))
    }

    fn paper_params(&self) -> Option<ServoParams> {
        Some(self.params)
    }

    fn with_paper_params(&self, params: ServoParams) -> Option<Self> {
        Some(Self { params })
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;
    use crate::physical::PhysicalPlant;
    use crate::uncertainty::{PhysicalSpec, Spread, Varying};

    #[test]
    fn bias_only_is_constant_and_matches_fig2() {
        let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
        let abar = plant.nominal().coeffs.as_array();
        let spec = UncertaintySpec {
            a_bias: 1.0,
            b_bias: 0.5,
            ..UncertaintySpec::NONE
        };
        let mut s = Varying::new(&plant, spec);
        let v = s.at(&plant, 3.7);
        // Fig. 2: Δa_i = α_i = |ā_i|, Δb = 0.5β = 0.25·b̄ → true b = 1.25·b̄.
        assert_eq!(v.da, abar);
        assert!((v.db_rel - 0.25).abs() < 1e-15);
    }

    /// The random part is held over each 0.01 s and independent of how
    /// often it is asked for.
    #[test]
    fn random_signal_is_held_and_step_independent() {
        let p = ServoParams {
            g: 1.0,
            ..ServoParams::paper()
        };
        let plant = ThirdOrderPlant::new(p, Load::none());
        let abar = plant.nominal().coeffs.as_array();
        let spec = UncertaintySpec {
            a_random: 1.0,
            b_random: 1.0,
            seed: 7,
            ..UncertaintySpec::NONE
        };
        let mut coarse = Varying::new(&plant, spec);
        let mut fine = Varying::new(&plant, spec);
        for k in 0..100 {
            let t = k as f64 * 0.01;
            let vc = coarse.at(&plant, t);
            for j in 0..10 {
                let vf = fine.at(&plant, t + j as f64 * 0.001);
                assert_eq!(vc, vf, "t = {t}, j = {j}");
            }
        }
        // Within ±|ā_1| and not constant.
        let mut s = Varying::new(&plant, spec);
        let vals: Vec<f64> = (0..200)
            .map(|k| s.at(&plant, k as f64 * 0.01).da[0] / abar[0].abs())
            .collect();
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
        let s = crate::uncertainty::UncertaintySignal::new(UncertaintySpec::NONE);
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
                    let lumped = plant.lumped_uncertainty(&x, &x, uc, ueq, bb, &v);
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
                let new = plant.lumped_uncertainty(&x, &x, u, u_eq, b_bar, &v);
                assert_eq!(new.to_bits(), old.to_bits(), "lumped at {x:?}");
                let phys = PhysicalPlant::new(p, load);
                let pv0 = crate::physical::PhysicalVariation {
                    paper: v,
                    factors: Factors::ONE,
                };
                let ps = phys.initial_state(x, &pv0);
                let pv = crate::physical::PhysicalVariation {
                    paper: v,
                    factors: Factors::ONE,
                };
                let l = phys.lumped_uncertainty(&ps, &x, u, u_eq, b_bar, &pv);
                assert_eq!(l.to_bits(), old.to_bits(), "physical's lumped at {x:?}");
            }
        }
    }

    /// A physical bias: the plant is (8)–(9) of the varied parameters,
    /// written out here from the paper's formulas (9), and (19) is the
    /// difference of that model from the nominal one.
    #[test]
    fn a_physical_bias_is_the_model_of_the_varied_parameters() {
        let p = ServoParams {
            g: 2.0,
            ..ServoParams::paper()
        };
        let load = Load::paper();
        let spec = PhysicalSpec {
            mass: Spread {
                bias: 0.3,
                random: 0.0,
            },
            bulk_modulus: Spread {
                bias: -0.2,
                random: 0.0,
            },
            leakage: Spread {
                bias: 1.0,
                random: 0.0,
            },
            supply_pressure: Spread {
                bias: -0.1,
                random: 0.0,
            },
            load: Spread {
                bias: 0.5,
                random: 0.0,
            },
            ..Default::default()
        };
        let f = spec.factors(&[0.0; 6]);
        let plant = ThirdOrderPlant::with_bias(p, load, &f);
        // (9) by hand for the true parameters.
        let (jt, be, kce, ps) = (p.jt * 1.3, p.beta_e * 0.8, p.kce * 2.0, p.ps * 0.9);
        let a1 = 4.0 * be * kce * p.g / (p.vt * jt);
        let a2 =
            p.g / jt + 4.0 * be * p.dm * p.dm / (p.vt * jt) + 4.0 * be * kce * p.bm / (p.vt * jt);
        let a3 = p.bm / jt + 4.0 * be * kce / p.vt;
        let x = [0.02, -0.1, 3.0];
        let amp = 1.5 * load.amplitude;
        let tl = amp * (load.wavenumber * x[0]).sin();
        let tl_rate = amp * load.wavenumber * (load.wavenumber * x[0]).cos() * x[1];
        let pl = (jt * x[2] + p.bm * x[1] + p.g * x[0] + tl) / p.dm;
        let u = 0.4;
        let kg = p.cd * p.ag * ((ps - pl) / p.rho).sqrt();
        let b = 4.0 * be * p.dm * kg * p.kv / (p.vt * jt);
        let d = 4.0 * be * kce * tl / (p.vt * jt) + tl_rate / jt;
        let want = -a1 * x[0] - a2 * x[1] - a3 * x[2] + b * u - d;
        let mut dx = [0.0; 3];
        plant.deriv(0.0, &x, u, &Variation::NONE, &mut dx);
        assert!(
            (dx[2] - want).abs() <= 1e-10 * want.abs(),
            "{} vs {want}",
            dx[2]
        );
        // (19): Σ (a_true − ā) x − (b_true − b̄) u_eq + d_true.
        let m = plant.nominal();
        let an = m.coeffs.as_array();
        let (u_eq, bb) = (0.3, m.b(&x, 1.0).0);
        let want_l =
            (a1 - an[0]) * x[0] + (a2 - an[1]) * x[1] + (a3 - an[2]) * x[2] - (b - bb) * u_eq + d;
        let l = plant.lumped_uncertainty(&x, &x, u, u_eq, bb, &Variation::NONE);
        assert!((l - want_l).abs() <= 1e-9 * want_l.abs(), "{l} vs {want_l}");
    }

    /// The family's errors name their keys from the scenario's root, with
    /// the core's reason; both models give their `[plant.params]`.
    #[test]
    fn build_errors_name_their_keys() {
        use crate::cylinder::CylinderCfg;
        use crate::error::Reason;
        use crate::physical::PhysicalCfg;
        let ctx = |uncertainty: UncertaintySpec| PlantContext {
            load: None,
            load_given: false,
            uncertainty,
            x0: [0.0; 3],
            base_dir: None,
            reference_range: None,
            quantity: Default::default(),
        };
        let bad = ThirdOrderCfg {
            params: ServoParams {
                vt: -1.0,
                ..ServoParams::paper()
            },
        };
        let e = bad.build(&ctx(UncertaintySpec::NONE)).unwrap_err();
        assert_eq!(e.key, "plant.params.Vt");
        assert!(matches!(e.reason, Reason::Param(_)));
        assert_eq!(
            e.to_string(),
            "`plant.params.Vt`: must be finite and > 0 (got -1.0)"
        );
        let mut spec = UncertaintySpec::NONE;
        spec.physical = PhysicalSpec {
            mass: Spread {
                bias: 0.0,
                random: 0.1,
            },
            ..PhysicalSpec::default()
        };
        let paper = ThirdOrderCfg {
            params: ServoParams::paper(),
        };
        assert_eq!(
            paper.build(&ctx(spec)).unwrap_err().key,
            "uncertainty.physical"
        );
        assert!(PhysicalCfg {
            params: paper.params
        }
        .build(&ctx(spec))
        .is_ok());
        spec.physical.load.bias = f64::INFINITY;
        assert_eq!(
            paper.build(&ctx(spec)).unwrap_err().to_string(),
            "`uncertainty.physical.load.bias`: must be finite (got inf)"
        );
        assert_eq!(paper.paper_params(), Some(ServoParams::paper()));
        assert_eq!(
            PhysicalCfg {
                params: paper.params
            }
            .paper_params(),
            Some(ServoParams::paper())
        );
        assert_eq!(CylinderCfg::default().paper_params(), None);
    }
}
