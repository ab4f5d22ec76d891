//! The loop's unit tests: resuming, the finiteness of a sample, the shared
//! first stage and the static valve changing no bit, the actuator stage,
//! a plant's own state dimension, and the delays.

use super::*;
use crate::actuator::ActuatorConfig;
use crate::plant::{Draw, ThirdOrderPlant, Variation};
use ehservo_core::control::nnvsc::{NnVsc, NnVscParams};
use ehservo_core::prelude::{Load, NominalModel, Rbf, ServoParams, Sine, SwitchingSurface};
use ehservo_core::rk4::rk4_step;

pub(super) fn nn() -> NnVsc {
    NnVsc::try_new(
        NominalModel::new(ServoParams::paper(), Load::paper()),
        SwitchingSurface::paper(),
        NnVscParams::paper(),
        Rbf::paper(),
    )
    .unwrap()
}

pub(super) fn stages(actuator: Actuator) -> Stages {
    Stages {
        uncertainty: UncertaintySpec {
            a_bias: 0.5,
            a_random: 0.5,
            b_bias: 0.25,
            b_random: 0.25,
            seed: 3,
            ..UncertaintySpec::NONE
        },
        actuator,
        sensor: Sensor::identity(),
        policy: FaultPolicy::default(),
        estimator: None,
    }
}

pub(super) fn cfg(mode: Mode) -> SimConfig {
    SimConfig {
        steps: 300,
        step: if mode == Mode::Sampled { 0.01 } else { 0.001 },
        mode,
        substeps: 3,
        theta_limit: 1.0,
        x0: [0.0; 3],
        computation_delay: false,
    }
}

fn sim(mode: Mode, a: Actuator) -> Simulation<ThirdOrderPlant, NnVsc, Sine> {
    let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
    Simulation::new(plant, nn(), Sine::paper(), stages(a), cfg(mode)).unwrap()
}

/// Stopping at any time and resuming gives the run in one go, bit for bit.
#[test]
fn run_until_resumes_exactly() {
    for mode in [Mode::Sampled, Mode::Continuous] {
        let mut whole = Vec::new();
        let out = sim(mode, Actuator::IDENTITY).run(&mut |s| whole.push(*s));
        let mut parts = Vec::new();
        let mut s = sim(mode, Actuator::IDENTITY);
        let h = cfg(mode).step;
        assert_eq!(s.run_until(0.5 * h * 300.0, &mut |x| parts.push(*x)), None);
        assert_eq!(parts.len(), 151, "samples 0..=150");
        assert!((s.time() - 151.0 * h).abs() < 1e-12);
        let one = s.step().unwrap();
        parts.push(one);
        assert_eq!(
            s.run_until(f64::INFINITY, &mut |x| parts.push(*x)),
            Some(Stop::Horizon)
        );
        assert_eq!(s.step(), None, "a stopped simulation stays stopped");
        assert_eq!(whole, parts, "{mode:?}");
        assert_eq!(s.outcome(), out);
        assert_eq!(out.samples, 301);
    }
}

/// The finiteness check of a sample looks at every logged number and
/// nothing else: one ±∞ or NaN anywhere among them fails it.
#[test]
fn a_sample_is_finite_exactly_when_every_logged_number_is() {
    use ehservo_core::control::sliding::SlidingParts;
    let mut s = Sample {
        x: [1.0, -2.0, 3e300],
        z: [0.1, 0.2, -0.3, 0.4],
        u: -0.0,
        u_plant: 5e-324,
        e: f64::MAX,
        signals: SlidingParts::<f64>::SIGNALS,
        ..Default::default()
    };
    for (i, v) in s.values.iter_mut().enumerate() {
        *v = i as f64 - 7.5;
    }
    assert!(s.is_finite());
    // A count that is not a multiple of the four lanes.
    let mut short = s;
    short.signals = &SlidingParts::<f64>::SIGNALS[..13];
    short.values[12] = f64::INFINITY;
    assert!(!short.is_finite());
    short.values[12] = 0.0;
    short.values[13] = f64::INFINITY;
    assert!(short.is_finite());
    let n = SlidingParts::<f64>::SIGNALS.len();
    let mut past = s;
    past.values[n] = f64::NAN; // not one of this controller's signals
    assert!(past.is_finite());
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut cases = Vec::new();
        for i in 0..n {
            let mut c = s;
            c.values[i] = bad;
            cases.push(c);
        }
        for i in 0..3 {
            let mut c = s;
            c.x[i] = bad;
            cases.push(c);
        }
        for i in 0..4 {
            let mut c = s;
            c.z[i] = bad;
            cases.push(c);
        }
        for f in [
            |c: &mut Sample, b| c.u = b,
            |c: &mut Sample, b| c.u_plant = b,
            |c: &mut Sample, b| c.e = b,
        ] {
            let mut c = s;
            f(&mut c, bad);
            cases.push(c);
        }
        assert_eq!(cases.len(), n + 10);
        assert!(cases.iter().all(|c| !c.is_finite()), "{bad}");
    }
}

/// The third-order plant through the trait's defaults only: no shared
/// evaluation of k1 and the lumped uncertainty, nothing prepared ahead
/// of the law (`Plant::prepare`), so every step is `rk4_step`'s.
#[derive(Debug, Clone, Copy)]
struct Plain(ThirdOrderPlant);

impl Plant for Plain {
    type State = [f64; 3];
    type Variation = Variation;
    type Prepared = ();
    fn initial_state(&self, x0: [f64; 3], v: &Variation) -> [f64; 3] {
        self.0.initial_state(x0, v)
    }
    fn measure(&self, t: f64, s: &[f64; 3], v: &Variation) -> [f64; 3] {
        self.0.measure(t, s, v)
    }
    fn deriv(&self, t: f64, s: &[f64; 3], u: f64, v: &Variation, ds: &mut [f64; 3]) {
        self.0.deriv(t, s, u, v, ds)
    }
    fn nominal(&self) -> &NominalModel {
        self.0.nominal()
    }
    fn variation(&self, spec: &UncertaintySpec, r: &Draw) -> Variation {
        self.0.variation(spec, r)
    }
    fn lumped_uncertainty(
        &self,
        s: &[f64; 3],
        x: &[f64; 3],
        u: f64,
        ue: f64,
        bb: f64,
        v: &Variation,
    ) -> f64 {
        self.0.lumped_uncertainty(s, x, u, ue, bb, v)
    }
}

/// Every number of a sample, as bits.
fn bits(s: &Sample) -> Vec<u64> {
    let mut b = vec![s.k, s.t.to_bits(), s.u.to_bits(), s.u_plant.to_bits()];
    b.extend(s.x.iter().chain(&s.z).chain(&s.values).map(|v| v.to_bits()));
    b.extend([s.e.to_bits(), s.flags as u64, s.signals.len() as u64]);
    b
}

/// The sampled step that starts from the k1 the diagnostics evaluated
/// (`Plant::deriv_and_lumped`), or from the one made of what
/// the plant prepared (`FirstStage::k1`), gives the run the plain RK4
/// step gives, bit for bit: with the valve passing the command,
/// lagging it (the plant's input then differs from the command, and
/// its sign may too), saturating it, with sub-steps, with a computation
/// delay (the plant gets the previous command), with a law's safe
/// output after a measurement fault, and for a law without
/// diagnostics.
#[test]
fn the_shared_first_stage_changes_nothing() {
    let lag = Actuator::try_new(&ActuatorConfig {
        time_constant: Some(0.02),
        ..Default::default()
    })
    .unwrap();
    let sat = Actuator::try_new(&ActuatorConfig {
        limit: Some(0.2),
        ..Default::default()
    })
    .unwrap();
    let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
    // (With a computation delay the plant gets the previous command, not
    // the one the diagnostics' k1 was for: k1 comes from what was
    // prepared.)
    for (a, substeps, delay) in [
        (Actuator::IDENTITY, 1, false),
        (lag, 1, false),
        (sat, 1, false),
        (Actuator::IDENTITY, 3, false),
        (Actuator::IDENTITY, 1, true),
        (lag, 2, true),
    ] {
        let mut c = cfg(Mode::Sampled);
        c.substeps = substeps;
        c.computation_delay = delay;
        let mut shared = Vec::new();
        let o1 = Simulation::new(plant, nn(), Sine::paper(), stages(a), c)
            .unwrap()
            .run(&mut |s| shared.push(bits(s)));
        let mut plain = Vec::new();
        let o2 = Simulation::new(Plain(plant), nn(), Sine::paper(), stages(a), c)
            .unwrap()
            .run(&mut |s| plain.push(bits(s)));
        assert_eq!(o1, o2);
        assert_eq!(shared, plain, "{a:?}, {substeps} sub-steps, delay {delay}");
        assert_eq!(shared.len(), 301);
    }
    // The prepared path is the one taken (the plant prepares).
    assert!(plant.prepare(&[0.01, -0.2, 3.0]).is_some());
    // Measurement faults: the law does not run (no diagnostics, no
    // shared k1) and the plant gets the safe output, zero: the step's
    // k1 is made of what was prepared, for a command of sign 0.
    let mut faulty = stages(Actuator::IDENTITY);
    faulty.policy = FaultPolicy {
        safe: ehservo_core::sampled::SafeCommand::Zero,
        limits: ehservo_core::sampled::Limits {
            x: [0.04, f64::INFINITY, f64::INFINITY],
            u: f64::INFINITY,
        },
    };
    let c = cfg(Mode::Sampled);
    let mut f1 = Vec::new();
    let o1 = Simulation::new(plant, nn(), Sine::paper(), faulty.clone(), c)
        .unwrap()
        .run(&mut |s| f1.push(bits(s)));
    let mut f2 = Vec::new();
    let o2 = Simulation::new(Plain(plant), nn(), Sine::paper(), faulty, c)
        .unwrap()
        .run(&mut |s| f2.push(bits(s)));
    assert!(o1.measurement_faults > 10, "{o1:?}");
    assert_eq!(o1, o2);
    assert_eq!(f1, f2);
    // A PID has no diagnostics: no k1 is shared with them; the step's
    // k1 comes from what was prepared, and is rk4_step's all the same.
    let pid = ehservo_core::control::Config::build(
        &ehservo_core::control::pid::PidConfig::default(),
        &ehservo_core::control::Design {
            model: *plant.nominal(),
            surface: SwitchingSurface::paper(),
            dt: 0.01,
        },
    )
    .unwrap();
    let c = cfg(Mode::Sampled);
    let mut a1 = Vec::new();
    Simulation::new(plant, pid, Sine::paper(), stages(lag), c)
        .unwrap()
        .run(&mut |s| a1.push(bits(s)));
    let mut a2 = Vec::new();
    Simulation::new(Plain(plant), pid, Sine::paper(), stages(lag), c)
        .unwrap()
        .run(&mut |s| a2.push(bits(s)));
    assert_eq!(a1, a2);
}

/// A valve without spool dynamics gives every RK4 stage the input that
/// the sampled step computes once for all of them (`advance`): the same
/// step, bit for bit, as evaluating the valve at each stage, here with
/// saturation, a dead band and a null bias, with and without sub-steps.
#[test]
fn a_static_valve_is_evaluated_once_per_step() {
    let valve = Actuator::try_new(&ActuatorConfig {
        limit: Some(0.3),
        dead_band: Some(0.01),
        null_bias: Some(0.004),
        ..Default::default()
    })
    .unwrap();
    assert!(!valve.has_lag() && !valve.is_identity());
    let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
    for substeps in [1u32, 2] {
        let mut c = cfg(Mode::Sampled);
        c.substeps = substeps;
        let (m, hs) = (u64::from(substeps), c.step / f64::from(substeps));
        let mut sim = Simulation::new(plant, nn(), Sine::paper(), stages(valve), c).unwrap();
        let (mut steps, mut saturated) = (0, 0);
        loop {
            let (k, mut y) = (sim.k, sim.y.pa);
            let smp = sim.step().expect("the paper's loop does not stop early");
            if sim.stopped().is_some() {
                break;
            }
            let u = smp.u;
            for j in 0..m {
                let v = sim.unc.at_step(&plant, k * m + j, hs, sim.per_hold);
                let f = |tt: f64, s: &PlantAct<[f64; 3]>, ds: &mut PlantAct<[f64; 3]>| {
                    plant.deriv(tt, &s.x, valve.output(&s.a, u), &v, &mut ds.x);
                    valve.deriv(&s.a, u, &mut ds.a);
                };
                rk4_step(f, k as f64 * c.step + j as f64 * hs, &mut y, hs);
            }
            let b = |p: &PlantAct<[f64; 3]>| {
                p.x.iter()
                    .chain(&p.a)
                    .map(|v| v.to_bits())
                    .collect::<Vec<_>>()
            };
            assert_eq!(b(&sim.y.pa), b(&y), "step {k}, {substeps} sub-step(s)");
            steps += 1;
            saturated += usize::from(u.abs() > 0.3);
        }
        assert_eq!(steps, 300);
        assert!(saturated > 0, "the limit was reached");
    }
}

/// A lag of τ between command and plant: the plant sees the valve
/// state, which follows the command with the lag's first-order response,
/// integrated with the plant in both modes.
#[test]
fn actuator_lag_is_integrated_with_the_plant() {
    let tau = 0.02;
    let a = Actuator::try_new(&ActuatorConfig {
        time_constant: Some(tau),
        ..Default::default()
    })
    .unwrap();
    for mode in [Mode::Sampled, Mode::Continuous] {
        let mut trace = Vec::new();
        sim(mode, a).run(&mut |s| trace.push(*s));
        assert_eq!(trace[0].u_plant, 0.0, "the valve starts at rest");
        // Over one sample the valve moves toward the command by at most
        // |u − v|·(1 − e^(−h/τ)) plus what the command itself moved.
        let h = cfg(mode).step;
        for w in trace.windows(2) {
            let dv = (w[1].u_plant - w[0].u_plant).abs();
            let bound = (w[0].u - w[0].u_plant)
                .abs()
                .max((w[1].u - w[0].u_plant).abs())
                * (1.0 - (-h / tau).exp())
                * 1.01
                + 1e-12;
            assert!(dv <= bound, "{mode:?} at t = {}: {dv} > {bound}", w[1].t);
        }
        // With a lag the plant sees something other than the command.
        assert!(trace.iter().any(|s| (s.u - s.u_plant).abs() > 1e-3));
    }
    // Without one it sees the command exactly.
    let mut trace = Vec::new();
    sim(Mode::Sampled, Actuator::IDENTITY).run(&mut |s| trace.push(*s));
    assert!(trace.iter().all(|s| s.u.to_bits() == s.u_plant.to_bits()));
}

/// In sampled mode the valve range is the sampled loop's: the command is
/// clamped and the clamps are counted.
#[test]
fn valve_range_clamps_the_sampled_command() {
    let a = Actuator::try_new(&ActuatorConfig {
        limit: Some(0.2),
        ..Default::default()
    })
    .unwrap();
    let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
    let mut st = stages(a);
    st.policy.limits.u = 0.2;
    let mut s = Simulation::new(plant, nn(), Sine::paper(), st, cfg(Mode::Sampled)).unwrap();
    let mut max_u: f64 = 0.0;
    let out = s.run(&mut |x| max_u = max_u.max(x.u.abs()));
    assert!(max_u <= 0.2);
    assert!(out.saturated > 0);
}

/// A plant whose state is not x: θ, θ̇ and a spool position v with
/// v̇ = (u − v)/τ driving θ̈ = k·v − c·θ̇. Any dimension fits.
#[derive(Debug, Clone, Copy)]
struct Spool {
    model: NominalModel,
}

impl Plant for Spool {
    type State = [f64; 4];
    type Variation = Variation;
    type Prepared = ();
    fn initial_state(&self, x0: [f64; 3], _v: &Variation) -> [f64; 4] {
        [x0[0], x0[1], 0.0, 0.0]
    }
    fn measure(&self, _t: f64, s: &[f64; 4], _v: &Variation) -> [f64; 3] {
        [s[0], s[1], 50.0 * s[2] - 10.0 * s[1]]
    }
    fn deriv(&self, _t: f64, s: &[f64; 4], u: f64, _v: &Variation, ds: &mut [f64; 4]) {
        ds[0] = s[1];
        ds[1] = 50.0 * s[2] - 10.0 * s[1];
        ds[2] = (u - s[2]) / 0.01;
        ds[3] = 1.0; // a clock, to show every component is integrated
    }
    fn nominal(&self) -> &NominalModel {
        &self.model
    }
    fn variation(&self, spec: &UncertaintySpec, r: &Draw) -> Variation {
        Variation::of(spec, &self.model.coeffs.as_array(), r)
    }
    fn lumped_uncertainty(
        &self,
        _s: &[f64; 4],
        x: &[f64; 3],
        u: f64,
        u_eq: f64,
        b_bar: f64,
        v: &Variation,
    ) -> f64 {
        let (b, d) = self.model.b_and_d(x, ehservo_core::math::sgn(u));
        crate::plant::lumped(x, u_eq, b_bar, v, b, d)
    }
}

#[test]
fn a_plant_with_its_own_state_dimension() {
    let plant = Spool {
        model: NominalModel::new(ServoParams::paper(), Load::none()),
    };
    let pid = ehservo_core::control::pid::PidConfig {
        kp: Some(20.0),
        ki: Some(0.0),
        kd: Some(0.0),
        feedforward: false,
        ..Default::default()
    };
    let ctrl = ehservo_core::control::Config::build(
        &pid,
        &ehservo_core::control::Design {
            model: plant.model,
            surface: SwitchingSurface::paper(),
            dt: 0.001,
        },
    )
    .unwrap();
    let mut s = Simulation::new(
        plant,
        ctrl,
        Sine::paper(),
        stages(Actuator::IDENTITY),
        cfg(Mode::Continuous),
    )
    .unwrap();
    let out = s.run(&mut |_| {});
    assert!(out.diverged.is_none());
    assert_eq!(out.samples, 301);
    // The clock component: 300 steps of 1 ms.
    assert!((s.y.pa.x[3] - 0.3).abs() < 1e-12);
}

/// With a computation delay the plant gets each command one sample
/// late; with a measurement delay of 2 the controller sees x of two
/// samples back (the first x until then).
#[test]
fn computation_and_measurement_delays() {
    let plant = ThirdOrderPlant::new(ServoParams::paper(), Load::paper());
    let mut c = cfg(Mode::Sampled);
    c.computation_delay = true;
    let mut st = stages(Actuator::IDENTITY);
    st.sensor = Sensor::try_new(&crate::sensor::SensorConfig {
        delay: 2,
        ..Default::default()
    })
    .unwrap();
    let mut trace = Vec::new();
    Simulation::new(plant, nn(), Sine::paper(), st, c)
        .unwrap()
        .run(&mut |s| trace.push(*s));
    assert_eq!(trace[0].u_plant, 0.0);
    for k in 1..trace.len() {
        assert_eq!(
            trace[k].u_plant.to_bits(),
            trace[k - 1].u.to_bits(),
            "k = {k}"
        );
    }
    for k in 0..trace.len() {
        let src = k.saturating_sub(2);
        assert_eq!(trace[k].x_ctrl, trace[src].x, "k = {k}");
    }
    // A continuous loop refuses both.
    let mut cc = cfg(Mode::Continuous);
    cc.computation_delay = true;
    let e =
        Simulation::new(plant, nn(), Sine::paper(), stages(Actuator::IDENTITY), cc).unwrap_err();
    assert_eq!(e.name, "computation_delay");
}

/// A rod past an end stop by more than the stop's stated penetration is a
/// divergence, reported as such: the doc example's 63/36 mm cylinder
/// (δ ≈ 5.3 mm, cylinder.rs's tests) started 100 mm below its lower stop
/// diverges at the first step's end; started 1 mm into it, it does not.
#[test]
fn a_rod_beyond_its_stop_is_a_divergence() {
    use crate::cylinder::CylinderCfg;
    use crate::plant::{PlantConfig, PlantContext};
    let cfg: CylinderCfg = toml::from_str(
        "[cylinder]\nbore = 0.063\nrod_diameter = 0.036\nstroke = 0.5\ndead_volume_a = 2e-4\ndead_volume_b = 2e-4\n\
         [fluid]\ndensity = 870.0\nbulk_modulus = 1.4e9\n\
         [valve]\nspool_limit = 5e-4\ngain = 5e-5\ndischarge_coefficient = 0.65\narea_gradient = 0.02\n\
         [supply]\nkind = \"fixed\"\npressure = 2e7\n[load]\nmass = 250.0\n",
    )
    .unwrap();
    let ctx = PlantContext {
        load: None,
        load_given: false,
        uncertainty: UncertaintySpec::NONE,
        x0: [0.0; 3],
        base_dir: None,
        reference_range: None,
        quantity: Default::default(),
    };
    let plant = cfg.build(&ctx).unwrap();
    let mut st = stages(Actuator::IDENTITY);
    st.uncertainty = UncertaintySpec::NONE;
    for (y0, diverges) in [(-0.1, true), (-1e-3, false)] {
        let c = SimConfig {
            steps: 10,
            step: 1e-3,
            mode: Mode::Sampled,
            substeps: 1,
            theta_limit: 1e3,
            x0: [y0, 0.0, 0.0],
            computation_delay: false,
        };
        let mut s = Simulation::new(plant.clone(), nn(), Sine::paper(), st.clone(), c).unwrap();
        let out = s.run(&mut |_| {});
        let want = diverges.then_some(Divergence {
            t: 1e-3,
            reason: DivergenceReason::BeyondEndStop,
        });
        assert_eq!(out.diverged, want, "y0 = {y0}");
    }
}
