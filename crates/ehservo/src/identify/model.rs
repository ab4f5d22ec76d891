//! What the two fits share: a model simulated on each experiment's logged
//! command, and the output-error residuals that compare it with the
//! measured channels.
//!
//! The command u_k is held over [t_k, t_k + h) (a rig's zero-order hold,
//! and ehservo's sampled loop), the model's state integrated over each
//! period by `substeps` classical RK4 steps, and its outputs taken at the
//! sample instants: y_k = θ(t_k) (and θ̇(t_k), P_l(t_k) for the channels
//! the file has). Every experiment has its own initial position θ0 (a
//! nuisance parameter, starting at rest: θ̇ = θ̈ = 0); the valve's null
//! offset u_offset (V, added to every command) is shared.

use super::data::Experiment;
use super::fit::Problem;

/// A model's outputs over one experiment.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SimOut {
    /// Position at each sample.
    pub y: Vec<f64>,
    /// Velocity at each sample.
    pub v: Vec<f64>,
    /// Load pressure at each sample (the physical model only).
    pub p: Vec<f64>,
}

/// A model that can be simulated on an experiment.
pub trait Model: Sync {
    /// Simulates experiment `e` (the `i`-th of the fit) under the
    /// parameters `p` (every parameter, natural units); `false` on
    /// divergence (a non-finite state, or a position beyond `limit`).
    fn simulate(&self, p: &[f64], i: usize, e: &Experiment, out: &mut SimOut) -> bool;
    /// Whether the model has a load pressure output.
    fn has_pressure(&self) -> bool;
}

/// RK4 steps per sample that keep h·|λ|max/substeps ≤ 0.25 with a
/// margin of two for the parameters moving during the fit (at most 256):
/// `rho` is the largest |λ| of the model's linearisation (1/s).
pub fn substeps(h: f64, rho: f64) -> usize {
    let m = (2.0 * h * rho / 0.25).ceil();
    if m.is_finite() {
        m.clamp(1.0, 256.0) as usize
    } else {
        256
    }
}

/// The largest |root| of s³ + a3·s² + a2·s + a1, from the companion
/// matrix's eigenvalues; the Cauchy bound 1 + max|a_i| if they fail.
pub fn spectral_radius(a: [f64; 3]) -> f64 {
    let m = nalgebra::Matrix3::new(0.0, 1.0, 0.0, 0.0, 0.0, 1.0, -a[0], -a[1], -a[2]);
    let ev = m.complex_eigenvalues();
    let r = ev.iter().map(|z| z.norm()).fold(0.0f64, f64::max);
    if r.is_finite() {
        r
    } else {
        1.0 + a.iter().fold(0.0f64, |x, v| x.max(v.abs()))
    }
}

/// The channels fitted and their weights.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Weights {
    /// 1/σ of the position (1/rad or 1/m).
    pub y: f64,
    /// 1/σ of the velocity, 0 when not fitted.
    pub v: f64,
    /// 1/σ of the load pressure (1/Pa), 0 when not fitted.
    pub p: f64,
}

/// The output-error problem: every experiment simulated, each measured
/// channel's residual weighted by its 1/σ, stacked.
pub struct OutputError<'a, M: Model> {
    /// The model.
    pub model: &'a M,
    /// The experiments.
    pub experiments: &'a [Experiment],
    /// The weights.
    pub weights: Weights,
}

impl<M: Model> OutputError<'_, M> {
    /// The channels a fit uses: the position always; velocity and pressure
    /// when every experiment has them (and the model has a pressure).
    pub fn initial_weights(model: &M, experiments: &[Experiment]) -> Weights {
        // A first scale: a hundredth of each channel's spread (the weights
        // only set the channels' balance, which the second pass corrects
        // from the residuals).
        let spread = |f: &dyn Fn(&Experiment) -> Option<&[f64]>| -> f64 {
            let mut s = 0.0f64;
            for e in experiments {
                let Some(v) = f(e) else { return 0.0 };
                let m = v.iter().sum::<f64>() / v.len() as f64;
                s = s.max((v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64).sqrt());
            }
            if s > 0.0 {
                100.0 / s
            } else {
                0.0
            }
        };
        Weights {
            y: spread(&|e| Some(&e.y.values)),
            v: spread(&|e| e.velocity.as_ref().map(|c| c.values.as_slice())),
            p: if model.has_pressure() {
                spread(&|e| e.pressure.as_ref().map(|c| c.values.as_slice()))
            } else {
                0.0
            },
        }
    }

    /// The unweighted residual RMS of each channel at `p`: the weights of
    /// the second pass (1/RMS), the first pass's where a channel is not used.
    pub fn reweighted(&self, p: &[f64]) -> Weights {
        let mut acc = [(0.0, 0usize); 3];
        let mut out = SimOut::default();
        for (i, e) in self.experiments.iter().enumerate() {
            if !self.model.simulate(p, i, e, &mut out) {
                return self.weights;
            }
            let mut add = |c: usize, meas: &[f64], sim: &[f64]| {
                for (a, b) in meas.iter().zip(sim) {
                    acc[c].0 += (a - b).powi(2);
                    acc[c].1 += 1;
                }
            };
            add(0, &e.y.values, &out.y);
            if self.weights.v > 0.0 {
                if let Some(v) = &e.velocity {
                    add(1, &v.values, &out.v);
                }
            }
            if self.weights.p > 0.0 {
                if let Some(pp) = &e.pressure {
                    add(2, &pp.values, &out.p);
                }
            }
        }
        let w = |c: usize, old: f64| {
            let (s, n) = acc[c];
            let rms = (s / n.max(1) as f64).sqrt();
            if old > 0.0 && rms > 0.0 && rms.is_finite() {
                1.0 / rms
            } else {
                old
            }
        };
        Weights {
            y: w(0, self.weights.y),
            v: w(1, self.weights.v),
            p: w(2, self.weights.p),
        }
    }

    /// Simulates every experiment at `p`.
    pub fn simulate_all(&self, p: &[f64]) -> Option<Vec<SimOut>> {
        self.experiments
            .iter()
            .enumerate()
            .map(|(i, e)| {
                let mut out = SimOut::default();
                self.model.simulate(p, i, e, &mut out).then_some(out)
            })
            .collect()
    }
}

impl<M: Model> Problem for OutputError<'_, M> {
    fn residuals(&self, p: &[f64], out: &mut Vec<f64>) -> bool {
        out.clear();
        let mut sim = SimOut::default();
        for (i, e) in self.experiments.iter().enumerate() {
            if !self.model.simulate(p, i, e, &mut sim) {
                return false;
            }
            let w = self.weights;
            out.extend(e.y.values.iter().zip(&sim.y).map(|(a, b)| w.y * (a - b)));
            if w.v > 0.0 {
                if let Some(v) = &e.velocity {
                    out.extend(v.values.iter().zip(&sim.v).map(|(a, b)| w.v * (a - b)));
                }
            }
            if w.p > 0.0 {
                if let Some(pp) = &e.pressure {
                    out.extend(pp.values.iter().zip(&sim.p).map(|(a, b)| w.p * (a - b)));
                }
            }
        }
        true
    }
}

/// The largest |position| a simulation may reach before it counts as
/// diverged: a thousand times the experiments' largest |y|, and at least 10.
pub fn divergence_limit(experiments: &[Experiment]) -> f64 {
    let m = experiments
        .iter()
        .flat_map(|e| e.y.values.iter())
        .fold(0.0f64, |a, v| a.max(v.abs()));
    (1000.0 * m).max(10.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paper's ā: s³ + 169.98s² + 13000.27s + 0.39982 has a root
    /// near −a1/a2 ≈ −3.1e-5 and a pair with |λ|² = a2 (to within the tiny
    /// real root), so the largest |λ| is √13000.27 = 114.02.
    #[test]
    fn spectral_radius_of_the_paper_servo() {
        let r = spectral_radius([0.39982, 13000.2711, 169.98043]);
        assert!((r - 13000.2711f64.sqrt()).abs() < 0.01, "{r}");
        // h = 1 ms: 2·0.001·114/0.25 = 0.91 → one RK4 step per sample.
        assert_eq!(substeps(1e-3, r), 1);
        assert_eq!(substeps(1e-2, r), 10);
    }
}
