//! The sampled mode: at `t_k` the core's sampled loop computes `u` once and
//! holds it over the period while the plant and the actuator are integrated
//! by `substeps` RK4 steps, the first of which may start from the stage the
//! law's diagnostics already evaluated ([`FirstStage`]).

use super::{PlantAct, Sample, Simulation, Stop, TruthAt};
use crate::actuator::Actuator;
use crate::plant::{refinement, resolvable, Plant, MAX_REFINE};
use crate::uncertainty::Varying;
use ehservo_core::control::Controller;
use ehservo_core::reference::Reference;
use ehservo_core::rk4::{rk4_step, rk4_step_with_k1, OdeState};
use std::cell::Cell;
use std::ops::ControlFlow;

/// The first RK4 stage of a sampled step: at the sample's time and state,
/// under the command the law returns. [`Plant::deriv_and_lumped`]
/// gives it with the lumped uncertainty (the third-order plant computes
/// the b and d both need once, from what [`Plant::prepare`] made as the
/// sample began); the step starts from it ([`rk4_step_with_k1`]) if it
/// was for the command the plant gets, else from [`FirstStage::k1`] when
/// the plant prepared something, else it is `rk4_step`'s.
pub(super) struct FirstStage<'a, P: Plant> {
    pub(super) t: f64,
    pub(super) y: &'a PlantAct<P::State>,
    pub(super) act: &'a Actuator,
    /// What the plant's derivative needs of the state alone
    /// ([`Plant::prepare`]), made as the sample began.
    pub(super) prepared: Option<P::Prepared>,
    /// The command's bits and k1.
    pub(super) k1: Cell<Option<(u64, PlantAct<P::State>)>>,
}

impl<P: Plant> FirstStage<'_, P> {
    /// k1 for the command `u`, under the variation `var`: the plant's
    /// derivative from [`FirstStage::prepared`] and the valve's.
    fn k1(&self, plant: &P, var: &P::Variation, u: f64) -> PlantAct<P::State> {
        let mut k1 = PlantAct::<P::State>::zero();
        plant.deriv_prepared(
            self.prepared.as_ref(),
            self.t,
            &self.y.x,
            self.act.output(&self.y.a, u),
            var,
            &mut k1.x,
        );
        self.act.deriv(&self.y.a, u, &mut k1.a);
        k1
    }
}

/// One RK4 step of `f` from `t`, from the first stage `k1` when it is known.
#[inline]
fn stage_step<S: OdeState, F: FnMut(f64, &S, &mut S)>(
    f: F,
    t: f64,
    y: &mut S,
    k1: Option<&S>,
    h: f64,
) {
    match k1 {
        Some(k1) => rk4_step_with_k1(f, t, y, k1, h),
        None => rk4_step(f, t, y, h),
    }
}

impl<P: Plant, C: Controller, R: Reference> Simulation<P, C, R> {
    /// [`Simulation::advance`] in sampled mode, from the measurement `x`
    /// and the reference `z` at `t_k`: `Break` with what `advance` returns
    /// when the sample ends the run, else `Continue` once the plant has been
    /// integrated to `t_{k+1}`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn advance_sampled(
        &mut self,
        sample: &mut Sample,
        k: u64,
        t: f64,
        x: [f64; 3],
        z: [f64; 4],
        var: P::Variation,
        j0: u64,
        hs: f64,
        m: u64,
    ) -> ControlFlow<bool> {
        // First: what the step's first RK4 stage needs of the state
        // alone (a sine, divisions, roots), so that it runs beside
        // the law rather than after the command it waits for.
        let prepared = self.plant.prepare(&self.y.pa.x);
        let xs = self.sensor.sample(x);
        // A new array rather than element writes into the sensor's:
        // the measurement can then stay in registers up to the
        // sampled loop's range check (written in place, it is
        // stored and reloaded, across the stores, which stalls).
        let xm = match &mut self.estimator {
            None => xs,
            Some(est) => {
                if k == 0 {
                    est.reset(xs[0]);
                }
                let xe = est.update(xs[0], self.u_applied);
                sample.x_est = xe;
                let measured = self.sensor.measured();
                let pick = |i: usize| if measured.has(i) { xs[i] } else { xe[i] };
                [xs[0], pick(1), pick(2)]
            }
        };
        let truth = TruthAt {
            plant: &self.plant,
            s: &self.y.pa.x,
            x,
            var,
            stage: Some(FirstStage {
                t,
                y: &self.y.pa,
                act: &self.actuator,
                prepared,
                k1: Cell::new(None),
            }),
        };
        let out = self
            .ctrl
            .step_with(t, xm, z, |c, s, o| c.annotate_stepped(s, o, &truth));
        let u = if self.cfg.computation_delay {
            self.u_applied
        } else {
            out.u
        };
        // The step's k1: the one the law's diagnostics evaluated, if
        // for the command the plant now gets; else from what was
        // prepared (as rk4_step would compute it, the same bits).
        let k1 = truth.stage.and_then(|st| match st.k1.get() {
            Some((bits, k1)) if bits == u.to_bits() => Some(k1),
            _ if st.prepared.is_some() => Some(st.k1(&self.plant, &var, u)),
            _ => None,
        });
        if !self.log(sample, t, z, x, xm, u, &out) {
            return ControlFlow::Break(false);
        }
        self.u_applied = out.u;
        if k == self.cfg.steps {
            self.stop = Some(Stop::Horizon);
            return ControlFlow::Break(true);
        }
        if self.adaptive.is_some() {
            // To the next sample instant exactly, under the held command
            // and this sample's variation (solver.rs).
            let t_next = (k + 1) as f64 * self.cfg.step;
            return match self.advance_adaptive(t, t_next, u, &var) {
                true => ControlFlow::Continue(()),
                false => ControlFlow::Break(true),
            };
        }
        let held = Held {
            t,
            h: self.cfg.step,
            j0,
            hs,
            m,
            per_hold: self.per_hold,
        };
        self.unresolved = !held.integrate(
            &self.plant,
            &self.actuator,
            &mut self.unc,
            &mut self.y.pa,
            u,
            var,
            k1,
        );
        ControlFlow::Continue(())
    }
}

/// One sample period's integration with the command held: `m` RK4
/// sub-steps of `hs` from `t` (the variation's clock at sub-step `j0`),
/// each split further for a stiff plant. What the closed loop
/// ([`Simulation`]) and the plant alone ([`super::PlantAlone`]) both run,
/// so the two give the same bits.
#[derive(Debug, Clone, Copy)]
pub(super) struct Held {
    /// The sample's time t_k (s).
    pub(super) t: f64,
    /// The sample period h (s): what a plant that steps itself
    /// ([`Plant::STEPS_ITSELF`]) is advanced over, in one call.
    pub(super) h: f64,
    /// The index of its first sub-step on the variation's clock.
    pub(super) j0: u64,
    /// The sub-step (s).
    pub(super) hs: f64,
    /// The sub-steps per sample.
    pub(super) m: u64,
    /// Sub-steps per hold of the variation, when whole.
    pub(super) per_hold: Option<u64>,
}

impl Held {
    /// Integrates `y` over the period under the command `u`, with the
    /// variation `var` over the first sub-step and the first RK4 stage
    /// `k1` when it is already known. False, with the sub-steps before
    /// it integrated, where the plant is stiffer than [`MAX_REFINE`] RK4
    /// steps a sub-step can follow ([`resolvable`]).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn integrate<P: Plant>(
        self,
        plant: &P,
        act: &Actuator,
        unc: &mut Varying<P::Variation>,
        y: &mut PlantAct<P::State>,
        u: f64,
        var: P::Variation,
        k1: Option<PlantAct<P::State>>,
    ) -> bool {
        let Held { t, j0, hs, m, .. } = self;
        if P::STEPS_ITSELF {
            // A co-simulation FMU: one call over the period under the
            // actuator's output as the period begins; the actuator's own
            // state, if it has one, by its RK4 sub-steps beside it.
            plant.step_held(t, self.h, act.output(&y.a, u), &mut y.x);
            if act.held_output(u).is_none() {
                for j in 0..m {
                    let ts = t + j as f64 * hs;
                    rk4_step(|_, a, da| act.deriv(a, u, da), ts, &mut y.a, hs);
                }
            }
            return true;
        }
        // A valve without spool dynamics gives the plant the same
        // input at every stage, and its state derivative is zero:
        // computed once here instead of at each stage (the same bits).
        let held = act.held_output(u);
        for j in 0..m {
            let ts = t + j as f64 * hs;
            let v = if j == 0 {
                var
            } else {
                unc.at_step(plant, j0 + j, hs, self.per_hold)
            };
            // The same k1 = f(t, y) that rk4_step would compute.
            let k1 = k1.as_ref().filter(|_| j == 0);
            // A stiff plant (Plant::stiffness) splits this step so
            // that RK4 stays stable; never for the paper's plants,
            // whose step is then the one below, untouched.
            let lambda = plant.stiffness(ts, &y.x, act.output(&y.a, u), &v);
            let n = refinement(lambda, hs);
            if n > 1 {
                if n == MAX_REFINE && !resolvable(lambda, hs) {
                    return false;
                }
                let hr = hs / f64::from(n);
                for i in 0..n {
                    rk4_step(
                        |tt: f64, s: &PlantAct<P::State>, ds: &mut PlantAct<P::State>| {
                            plant.deriv(tt, &s.x, act.output(&s.a, u), &v, &mut ds.x);
                            act.deriv(&s.a, u, &mut ds.a);
                        },
                        ts + f64::from(i) * hr,
                        y,
                        hr,
                    );
                    plant.limit_state(&mut y.x);
                }
                continue;
            }
            match held {
                // The valve's state has a zero derivative at every
                // stage, so RK4 would leave it as it is (+0, its
                // initial state, plus h/6·0): the step integrates
                // the plant's state alone. The same bits, and no
                // plant+valve state whose copies the stages would
                // reload across store boundaries. The derivative is
                // inlined into the stages, which then share what depends
                // on the held input alone (the third-order plant's sign
                // and supply term): left to LLVM, it was a call at every
                // stage that made them again.
                Some(u_plant) => stage_step(
                    #[inline(always)]
                    |tt: f64, s: &P::State, ds: &mut P::State| {
                        plant.deriv(tt, s, u_plant, &v, ds);
                    },
                    ts,
                    &mut y.x,
                    k1.map(|k1| &k1.x),
                    hs,
                ),
                None => stage_step(
                    |tt: f64, s: &PlantAct<P::State>, ds: &mut PlantAct<P::State>| {
                        plant.deriv(tt, &s.x, act.output(&s.a, u), &v, &mut ds.x);
                        act.deriv(&s.a, u, &mut ds.a);
                    },
                    ts,
                    y,
                    k1,
                    hs,
                ),
            }
            plant.limit_state(&mut y.x);
        }
        true
    }
}
