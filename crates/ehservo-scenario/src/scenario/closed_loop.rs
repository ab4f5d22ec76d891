//! [`Loop`]: a scenario built, once. It owns the plant and the controller
//! (built), the reference, the stages around the plant, the loop's
//! settings and the axis; it exists only if every key of its scenario
//! checked out, and nothing downstream derives any of them from the
//! scenario again. [`Loop::simulate`] is the one way into the typed loop:
//! a [`LoopVisit`] receives the plant and the controller as their own
//! types, so that the simulation around them is monomorphised.
//!
//! ```
//! use ehservo_scenario::scenario::Loop;
//! use ehservo_scenario::run::{run, Keep};
//!
//! // The paper's Fig. 2 case over 3 s, from a TOML string.
//! let lp = Loop::parse("name = \"fig2\"\n[simulation]\nhorizon = 3.0\n").unwrap();
//! assert_eq!(lp.controller().kind(), "nnvsc");
//! assert_eq!(lp.sim().steps, 300); // 3 s at the paper's 0.01 s
//! let r = run(&lp, Keep::Nothing);
//! assert!(r.outcome.diverged.is_none());
//! // e_max after the 2 s transient, in the axis's unit (degrees here).
//! let e_max = r.metrics.e_max.unwrap();
//! assert!(e_max > 0.0 && e_max < 1.0, "{e_max}");
//! ```

use super::registry::{Built, BuiltVisit};
use super::{
    AnyPlant, AnyReference, ControllerCfg, ControllerConfig, PlantVisit, Scenario, ScenarioError,
};
use ehservo_core::control::Design;
use ehservo_core::servo::{NominalModel, ServoParams};
use ehservo_sim::axis::Axis;
use ehservo_sim::plant::Plant;
use ehservo_sim::simulation::{Settings, SimConfig, Simulation, Stages};
use std::fmt::Debug;
use std::path::Path;

/// What [`super::build::build`] makes of a scenario.
pub(super) struct Parts {
    pub(super) plant: AnyPlant,
    pub(super) axis: Axis,
    pub(super) model: NominalModel,
    pub(super) design: Design,
    pub(super) controller: Built,
    pub(super) settings: Settings,
    pub(super) reference: AnyReference,
    pub(super) settle: f64,
    pub(super) horizon: f64,
    pub(super) period: f64,
}

/// A scenario, checked and built: see the [module](self).
#[derive(Debug, Clone)]
pub struct Loop {
    scenario: Scenario,
    plant: AnyPlant,
    axis: Axis,
    model: NominalModel,
    design: Design,
    controller: Built,
    settings: Settings,
    reference: AnyReference,
    settle: f64,
    horizon: f64,
    period: f64,
}

/// The bounds a plant of the registry meets.
pub trait LoopPlant: Plant + Clone + Debug + Send + Sync + 'static {}

impl<P: Plant + Clone + Debug + Send + Sync + 'static> LoopPlant for P {}

/// Code that runs a loop with its plant and controller typed: the one
/// way in ([`Loop::simulate`]).
pub trait LoopVisit {
    /// What the visit returns.
    type Out;
    /// Called with the loop's plant and controller, typed, and the loop.
    fn visit<P: LoopPlant, K: ControllerConfig>(self, typed: Typed<'_, P, K>) -> Self::Out;
}

/// A loop's plant and controller as their own types ([`LoopVisit`]).
pub struct Typed<'a, P, K: ControllerConfig> {
    /// The plant, a copy of the loop's.
    pub plant: P,
    /// The controller, a copy of the loop's (built once, with the loop).
    pub controller: K::Controller,
    /// The parameters it was built from.
    pub config: &'a K,
    /// The loop.
    pub lp: &'a Loop,
}

impl<P: LoopPlant, K: ControllerConfig> Typed<'_, P, K> {
    /// The scenario's simulation of this plant and controller, at t = 0.
    pub fn simulation(self) -> Simulation<P, K::Controller, AnyReference> {
        Simulation::from_settings(
            self.plant,
            self.controller,
            self.lp.reference.clone(),
            self.lp.settings.clone(),
        )
    }
}

impl Loop {
    pub(super) fn from_parts(scenario: Scenario, p: Parts) -> Loop {
        Loop {
            scenario,
            plant: p.plant,
            axis: p.axis,
            model: p.model,
            design: p.design,
            controller: p.controller,
            settings: p.settings,
            reference: p.reference,
            settle: p.settle,
            horizon: p.horizon,
            period: p.period,
        }
    }

    /// Reads a scenario file, applies the `key.path=value` overrides and
    /// builds it. The error names the file (or `--set`), the key with its
    /// line and column, and the reason.
    pub fn load(path: &Path, overrides: &[String]) -> Result<Loop, ScenarioError> {
        let (s, text) = Scenario::read(path, overrides)?;
        Self::checked(s, &text, &path.display().to_string(), overrides)
    }

    /// Builds TOML text (no overrides; the file is `<string>`).
    pub fn parse(text: &str) -> Result<Loop, ScenarioError> {
        Self::parse_with(text, "<string>", &[])
    }

    /// Builds TOML text under the name `file`, with overrides. A relative
    /// `reference.file` is read from the working directory.
    pub fn parse_with(text: &str, file: &str, overrides: &[String]) -> Result<Loop, ScenarioError> {
        Self::parse_in(text, file, overrides, None)
    }

    /// As [`Loop::parse_with`], for a file in `base_dir`.
    pub fn parse_in(
        text: &str,
        file: &str,
        overrides: &[String],
        base_dir: Option<std::path::PathBuf>,
    ) -> Result<Loop, ScenarioError> {
        let s = Scenario::parse_in(text, file, overrides, base_dir)?;
        Self::checked(s, text, file, overrides)
    }

    /// Builds `s`, read from `text` of `file` with `overrides`: an error
    /// is placed in the file, or blamed on the flag that set its key.
    fn checked(
        s: Scenario,
        text: &str,
        file: &str,
        overrides: &[String],
    ) -> Result<Loop, ScenarioError> {
        match super::build::build(&s) {
            Ok(parts) => Ok(Loop::from_parts(s, parts)),
            Err(e) => Err(super::placed(e, text, file, overrides)),
        }
    }

    /// The same loop under the name `name` (what a loop read from text
    /// without a `name` key is called; the name builds nothing).
    pub fn named(mut self, name: impl Into<String>) -> Loop {
        self.scenario.name = name.into();
        self
    }

    /// The scenario it was built from.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// The scenario's name.
    pub fn name(&self) -> &str {
        &self.scenario.name
    }

    /// The controller's kind and parameters.
    pub fn controller(&self) -> &ControllerCfg {
        &self.scenario.controller
    }

    /// The true plant, built.
    pub fn plant(&self) -> &AnyPlant {
        &self.plant
    }

    /// The plant's axis: what the position is and the unit it is shown in.
    pub fn axis(&self) -> Axis {
        self.axis
    }

    /// The nominal model (what the controller is designed on).
    pub fn model(&self) -> &NominalModel {
        &self.model
    }

    /// The nominal model's numbers in one phrase, as a design's refusal
    /// quotes them: ā1, ā2, ā3, b̄0 and, when ā2 > 0, the hydraulic
    /// resonance `s² + ā3·s + ā2` as ω_h = √ā2 and ζ_h = ā3/(2ω_h).
    ///
    /// ```
    /// # fn main() -> anyhow::Result<()> {
    /// let lp = ehservo_scenario::Loop::parse("")?;
    /// // The paper's servo: ā2 = 13000.27 1/s², so ω_h = 114.0 rad/s.
    /// assert!(lp.model_summary().contains("ω_h = 114.0 rad/s"));
    /// # Ok(())
    /// # }
    /// ```
    pub fn model_summary(&self) -> String {
        super::build::model_numbers(&self.model, self.axis.si_unit())
    }

    /// The controller's parameters that its design derived on this loop's
    /// nominal model and were not written (the PID's `kp`, `ki`, `kd`, the
    /// ADRC's `omega_c`, `omega_o`, `b0`, state feedback's `frequency` and
    /// `pole`, …), as `(key, value)` sorted by key; empty for a kind
    /// that derives nothing it reports (`Config::designed`).
    ///
    /// ```
    /// # fn main() -> anyhow::Result<()> {
    /// let lp = ehservo_scenario::Loop::parse("[controller]\nkind = \"pid\"")?;
    /// let d = lp.designed();
    /// // The PID's gains come from its pole placement on the paper's servo.
    /// let keys: Vec<&str> = d.iter().map(|(k, _)| k.as_str()).collect();
    /// assert!(["kp", "ki", "kd"].iter().all(|k| keys.contains(k)));
    /// assert!(d.iter().all(|(_, v)| v.is_finite() && *v > 0.0));
    /// # Ok(())
    /// # }
    /// ```
    pub fn designed(&self) -> Vec<(String, f64)> {
        self.controller.visit(Designed(&self.design))
    }

    /// What a cylinder scenario is warned of, one line each (the CLI
    /// prints them on stderr): no `[actuator]` stage (the spool follows
    /// the command at once and without limit), and a sample step h with
    /// ω_h·h > 1, ω_h = √ā2 the hydraulic natural frequency of the nominal
    /// model (a sampled law then acts slower than the oil column rings),
    /// and a hose whose drop at the valve's full flow is more than 5 % of
    /// the supply (folded into its chamber as a volume without resistance).
    /// Empty for the other plants: the paper's own servo is sampled at
    /// ω_h·h ≈ 1.14 (ā2 = 13000 s⁻², h = 10 ms) by the paper's choice.
    pub fn warnings(&self) -> Vec<String> {
        let mut v = Vec::new();
        if self.scenario.plant.model() != "cylinder" {
            return v;
        }
        if self.stages().actuator.is_identity() {
            v.push(
                "a cylinder without an [actuator] stage: the valve's spool follows the command at once and without limit (no saturation, no spool lag)"
                    .to_string(),
            );
        }
        if let Some(c) = self.plant().get::<ehservo_sim::cylinder::CylinderPlant>() {
            let c = c.cylinder();
            let dp = c.supply.holding_pressure(c.pt) - c.pt;
            if c.hose_drop > 0.05 * dp {
                // In %, with an exponent once it is long (a 1e300 m hose).
                let pct = 100.0 * c.hose_drop / dp;
                let pct = if pct < 1e6 {
                    format!("{pct:.1}")
                } else {
                    format!("{pct:.3e}")
                };
                v.push(format!(
                    "[plant.hose]: the longer hose drops {:.4e} Pa at the valve's full flow, {pct} % of the supply's {dp:.4e} Pa: the hose is folded into the chamber as a volume without resistance (docs/cylinder.md, \"Hoses\"), which a drop this large makes unfair",
                    c.hose_drop
                ));
            }
        }
        let a2 = self.model.coeffs.a2;
        let h = self.sim().step;
        if a2 > 0.0 && a2.is_finite() {
            let wh = a2.sqrt();
            if wh * h > 1.0 {
                v.push(format!(
                    "the hydraulic natural frequency ω_h = √ā2 = {wh:.4} rad/s and the step h = {h} s give ω_h·h = {:.4} > 1: the sampled loop is slower than the oil column rings",
                    wh * h
                ));
            }
        }
        v
    }

    /// The paper's physical parameters of a third-order-family plant
    /// (`[plant.params]`); `None` for another plant.
    pub fn paper_params(&self) -> Option<ServoParams> {
        self.scenario.paper_params()
    }

    /// What the controller is designed from: the nominal model, the
    /// surface and the sample period.
    pub fn design(&self) -> &Design {
        &self.design
    }

    /// The stages around the plant: variation, valve, sensors, estimator,
    /// fault policy.
    pub fn stages(&self) -> &Stages {
        self.settings.stages()
    }

    /// The loop's settings (steps, step, mode, sub-steps, x0).
    pub fn sim(&self) -> &SimConfig {
        self.settings.config()
    }

    /// The stages and the settings together, checked: what a
    /// [`Simulation`] is made from ([`Simulation::from_settings`]).
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The same loop with the fault policy's limits replaced by `limits`
    /// (an off-board controller applies its own; the simulator keeps its
    /// finiteness check and the same safe command).
    pub fn with_limits(
        &self,
        limits: ehservo_core::sampled::Limits,
    ) -> Result<Loop, ehservo_core::error::ParamError> {
        let mut lp = self.clone();
        lp.settings = self.settings.clone().with_limits(limits)?;
        Ok(lp)
    }

    /// The desired trajectory.
    pub fn reference(&self) -> &AnyReference {
        &self.reference
    }

    /// The span (s) along which the analyses sample the reference: one
    /// period of a sine, the horizon otherwise.
    pub fn reference_span(&self) -> f64 {
        match self.scenario.reference.kind {
            super::ReferenceKind::Sine => 1.0 / self.scenario.reference.frequency(),
            _ => self.horizon,
        }
    }

    /// End of the transient for the metrics (s).
    pub fn settle(&self) -> f64 {
        self.settle
    }

    /// The horizon (s).
    pub fn horizon(&self) -> f64 {
        self.horizon
    }

    /// What the reference does after the transient, whose forced response
    /// the oscillation check leaves alone: a sine's or a square wave's
    /// frequency, a multisine's components, a chirp's sweep; nothing for a
    /// step or a ramp (at rest after the transient) or a CSV table (not
    /// analysed: a cycle the table itself has is reported).
    pub fn forcing(&self) -> ehservo_sim::behaviour::Forcing {
        use super::ReferenceKind as K;
        use ehservo_sim::behaviour::Forcing;
        match self.scenario.reference.kind {
            K::Sine | K::Square if self.period > 0.0 => Forcing::Tones(vec![1.0 / self.period]),
            K::Multisine | K::Chirp => self.reference.forcing().unwrap_or_default(),
            _ => Forcing::None,
        }
    }

    /// Whether the loop is open (kind `open-loop`): its reference is a
    /// command, not a position, so it has no tracking error.
    pub fn is_open(&self) -> bool {
        matches!(self.scenario.controller, ControllerCfg::OpenLoop(_))
    }

    /// The period of the reference (s): the window of `e_final`.
    pub fn period(&self) -> f64 {
        self.period
    }

    /// Runs `v` with the loop's plant and controller, typed.
    pub fn simulate<V: LoopVisit>(&self, v: V) -> V::Out {
        self.controller.visit(WithController { lp: self, v })
    }

    /// This loop's scenario with some keys set to new values (each a
    /// dotted path and a TOML value), built. Cheaper than parsing text:
    /// a sweep makes each run this way.
    pub fn with_values(&self, values: &[(String, toml::Value)]) -> Result<Loop, ScenarioError> {
        self.with_values_on(self.table()?, values)
    }

    /// As [`Loop::with_values`], from `table`, which must be this loop's
    /// own [`Loop::table`]: a sweep makes it once, not once per run.
    pub fn with_values_on(
        &self,
        table: toml::Table,
        values: &[(String, toml::Value)],
    ) -> Result<Loop, ScenarioError> {
        Loop::new(self.scenario.with_values_on(table, values)?)
    }

    /// This loop with `uncertainty.seed = seed`: what
    /// [`Loop::with_values`] gives for that one value when the scenario
    /// survives its TOML round trip (a study checks that once), without
    /// the round trip (a Monte Carlo run over the seed alone).
    pub fn with_seed(&self, seed: u64) -> Result<Loop, ScenarioError> {
        let mut s = self.scenario.clone();
        s.uncertainty.seed = seed;
        Loop::new(s)
    }

    /// The scenario as a TOML table: what [`Loop::with_values_on`]
    /// starts from.
    pub fn table(&self) -> Result<toml::Table, ScenarioError> {
        self.scenario.table()
    }
}

/// [`Loop::designed`]: the keys the design filled in, with their values.
struct Designed<'a>(&'a Design);

impl BuiltVisit for Designed<'_> {
    type Out = Vec<(String, f64)>;
    fn visit<K: ControllerConfig>(self, cfg: &K, _: &K::Controller) -> Self::Out {
        let Some(Ok(full)) = cfg.designed(self.0) else {
            return Vec::new();
        };
        let (Ok(given), Ok(full)) = (toml::Table::try_from(cfg), toml::Table::try_from(&full))
        else {
            return Vec::new();
        };
        full.into_iter()
            .filter(|(k, _)| !given.contains_key(k))
            .filter_map(|(k, v)| match v {
                toml::Value::Float(x) => Some((k, x)),
                _ => None,
            })
            .collect()
    }
}

/// [`Loop::simulate`]'s first half: the controller typed.
struct WithController<'a, V> {
    lp: &'a Loop,
    v: V,
}

impl<V: LoopVisit> BuiltVisit for WithController<'_, V> {
    type Out = V::Out;
    fn visit<K: ControllerConfig>(self, cfg: &K, ctrl: &K::Controller) -> V::Out {
        self.lp.plant.visit(WithPlant {
            lp: self.lp,
            v: self.v,
            cfg,
            ctrl,
        })
    }
}

/// [`Loop::simulate`]'s second half: the plant typed.
struct WithPlant<'a, V, K: ControllerConfig> {
    lp: &'a Loop,
    v: V,
    cfg: &'a K,
    ctrl: &'a K::Controller,
}

impl<V: LoopVisit, K: ControllerConfig> PlantVisit for WithPlant<'_, V, K> {
    type Out = V::Out;
    fn visit<P: Plant + Clone + Debug + Send + Sync + 'static>(self, plant: &P) -> V::Out {
        self.v.visit(Typed {
            plant: plant.clone(),
            controller: self.ctrl.clone(),
            config: self.cfg,
            lp: self.lp,
        })
    }
}
