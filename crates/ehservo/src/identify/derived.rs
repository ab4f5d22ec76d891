//! Quantities derived from a fit's estimates (the linear model's pair, the
//! grey-box's coefficients, ω_h and effective pair), each with its
//! delta-method standard error and 95 % interval.

use super::fit::FitReport;
use super::{greybox, oe, stats, Derived};
use ehservo_core::servo::Load;

/// The delta-method standard errors of `f(values)` from the fit's covariance.
pub(super) fn delta(
    rep: &FitReport,
    keys: &[(&str, &str)],
    f: &dyn Fn(&[f64]) -> Vec<f64>,
) -> Vec<Derived> {
    let v = rep.values();
    let base = f(&v);
    let free: Vec<usize> = rep
        .free_keys
        .iter()
        .filter_map(|k| rep.estimates.iter().position(|e| &e.key == k))
        .collect();
    let grads: Vec<Vec<f64>> = free
        .iter()
        .map(|&j| {
            let h = 1e-6 * v[j].abs().max(1e-300);
            let (mut a, mut b) = (v.clone(), v.clone());
            a[j] += h;
            b[j] -= h;
            f(&a)
                .iter()
                .zip(f(&b))
                .map(|(x, y)| (x - y) / (2.0 * h))
                .collect()
        })
        .collect();
    let ok = !rep.covariance.is_empty() && rep.covariance.iter().flatten().all(|c| c.is_finite());
    keys.iter()
        .enumerate()
        .map(|(q, &(key, unit))| {
            let se = ok.then(|| {
                let mut s = 0.0;
                for a in 0..free.len() {
                    for b in 0..free.len() {
                        s += grads[a][q] * rep.covariance[a][b] * grads[b][q];
                    }
                }
                s.max(0.0).sqrt()
            });
            let value = base[q];
            Derived {
                key: key.into(),
                unit: unit.into(),
                value,
                se: se.filter(|s| s.is_finite()),
                ci95: se
                    .filter(|s| s.is_finite())
                    .map(|s| [value - stats::Z95 * s, value + stats::Z95 * s]),
            }
        })
        .collect()
}

/// ω_n, ζ of the complex pair of s³ + a3·s² + a2·s + a1 (NaN without one).
fn pair_of(a: [f64; 3]) -> [f64; 2] {
    oe::pair(a).map_or([f64::NAN; 2], |(w, z, _)| [w, z])
}

/// The linear model's derived quantities.
pub(super) fn linear_derived(rep: &FitReport, load_terms: bool, k: f64) -> Vec<Derived> {
    delta(
        rep,
        &[("omega_n_rad_s", "rad/s"), ("zeta", ""), ("f_n_Hz", "Hz")],
        &|v| {
            let mut a = [v[0], v[1], v[2]];
            if load_terms {
                a[0] += v[4] * k;
                a[1] += v[5];
            }
            let [w, z] = pair_of(a);
            vec![w, z, w / (2.0 * std::f64::consts::PI)]
        },
    )
}

/// The grey-box's derived quantities: (9)'s coefficients at P_l = 0, the
/// load terms, ω_h = √(4βe·Dm²/(Vt·Jt)) and the effective pair.
pub(super) fn greybox_derived(rep: &FitReport, load: &Load) -> Vec<Derived> {
    let nk = greybox::KEYS.len();
    delta(
        rep,
        &[
            ("a1", "1/s^3"),
            ("a2", "1/s^2"),
            ("a3", "1/s"),
            ("b", "rad/(V*s^3)"),
            ("d1", "rad/s^3"),
            ("d2", "1/s^2"),
            ("omega_h_rad_s", "rad/s"),
            ("f_h_Hz", "Hz"),
            ("omega_n_rad_s", "rad/s"),
            ("zeta", ""),
        ],
        &|v| {
            let (p, l) = greybox::from_vec(&v[..nk], load);
            let c = p.coefficients();
            let b = ehservo_core::servo::NominalModel::new(p, l).b_at_rest();
            let wh = (4.0 * p.beta_e * p.dm * p.dm / (p.vt * p.jt)).sqrt();
            let [w, z] = pair_of(greybox::effective(&p, &l));
            vec![
                c.a1,
                c.a2,
                c.a3,
                b,
                p.d_per_torque() * l.amplitude,
                l.amplitude * l.wavenumber / p.jt,
                wh,
                wh / (2.0 * std::f64::consts::PI),
                w,
                z,
            ]
        },
    )
}
