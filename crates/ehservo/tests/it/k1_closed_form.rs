//! The closed form of exp((P + K2·I)t) (`SpectralExp`) and the K1 built on
//! it, against the reference path that `analyze` used before: nalgebra's
//! Padé `exp` and the SVD on the same grids (`k1_expm`, which is also the
//! fallback for poles too close for the closed form). Pole sets: distinct
//! real (slow, the paper's, far apart), complex pairs (dominant or not),
//! an exactly repeated pole (dominant or not) and near-repeated ones on
//! either side of `SEPARATION`.
//!
//! The tolerances are the reference's own accuracy: its Padé approximant
//! with scaling and squaring loses digits on the large, non-normal
//! (P + K2 I)t of close poles (≈ 1e-8 at poles 0.5 s⁻¹ apart against the
//! mpmath values of tests/it/analysis.rs), while the closed form is within
//! ≈ 1e-12 there.
#![allow(clippy::float_cmp)] // repeated poles are equal on purpose

use ehservo::analysis::{
    cubic_roots, k1, k1_expm, k1_profile, p_matrix, Pole, SpectralExp, K1, SEPARATION,
};
use nalgebra::{Complex, Matrix3};

/// A pole set: its name, p, the poles, the agreement asked of g with the
/// reference and the agreement asked of K1.
type Case = (&'static str, [f64; 3], [Pole; 3], f64, f64);

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// p and the exact poles for real poles r (p = elementary symmetric
/// functions of −r; exact for these integers and halves).
fn real(r: [f64; 3]) -> ([f64; 3], [Pole; 3]) {
    let (a, b, c) = (-r[0], -r[1], -r[2]);
    let p = [a + b + c, a * b + a * c + b * c, a * b * c];
    let mut q = r.map(|x| Pole::from(Complex::new(x, 0.0)));
    q.sort_by(|x, y| y.re.total_cmp(&x.re));
    (p, q)
}

/// K2 as `analyze` takes it: −Re of the dominant pole (the mean of a
/// repeated dominant pair).
fn k2_of(q: &[Pole; 3]) -> f64 {
    if q[0].re == q[1].re && q[0].im == q[1].im {
        -(q[0].re + q[1].re) / 2.0
    } else {
        -q[0].re
    }
}

/// Times from the fast transients to well past the slowest mode.
fn times(q: &[Pole; 3]) -> Vec<f64> {
    let fast = q.iter().map(|x| x.wn).fold(0.0, f64::max);
    let slow = q.iter().map(|x| x.wn).fold(f64::INFINITY, f64::min);
    let mut t: Vec<f64> = (0..60)
        .map(|i| 1e-3 / fast * (1e4 * fast / slow).powf(i as f64 / 59.0))
        .collect();
    t.push(0.0);
    t
}

fn same_k1(name: &str, a: &K1, b: &K1, tol: f64) {
    match (a.value, b.value) {
        (Some(x), Some(y)) => assert!(rel(x, y) <= tol, "{name}: K1 {x} vs {y}"),
        (None, None) => {}
        _ => panic!("{name}: {a:?} vs {b:?}"),
    }
    match (a.at_t, b.at_t) {
        (Some(x), Some(y)) => assert!((x - y).abs() <= 1e-6 * x.max(1e-3), "{name}: at {x} vs {y}"),
        (None, None) => {}
        _ => panic!("{name}: at_t {a:?} vs {b:?}"),
    }
    if let (Some(x), Some(y)) = (a.limit, b.limit) {
        assert!(rel(x, y) <= 1e-13, "{name}: limit {x} vs {y}");
    }
    assert_eq!(a.verified, b.verified, "{name}: {a:?} vs {b:?}");
    assert_eq!(
        (a.grid_points, a.check_points, a.span),
        (b.grid_points, b.check_points, b.span),
        "{name}"
    );
}

/// g(t) = ‖exp((P + K2 I)t)‖₂ in closed form against nalgebra's exp and the
/// SVD, and K1 by both paths, on every structure. `exp_tol` is the
/// reference's accuracy on g, `k1_tol` the agreement of K1.
#[test]
fn closed_form_against_the_expm_path() {
    let cases: Vec<Case> = vec![
        {
            let (p, q) = real([-20.0, -30.0, -40.0]);
            ("paper −20, −30, −40", p, q, 1e-11, 1e-14)
        },
        {
            let p = [90.0, 2600.0, 24000.0];
            (
                "paper p (computed roots)",
                p,
                cubic_roots(p[0], p[1], p[2]),
                1e-11,
                1e-14,
            )
        },
        {
            let (p, q) = real([-1.0, -5.0, -10.0]);
            ("slow −1, −5, −10 (peaked)", p, q, 1e-12, 1e-12)
        },
        {
            let (p, q) = real([-1.0, -1000.0, -2000.0]);
            ("far −1, −1000, −2000", p, q, 1e-9, 1e-12)
        },
        {
            let (p, q) = real([-3.0, -50.0, -51.0]);
            ("close fast pair −50, −51", p, q, 1e-9, 1e-9)
        },
        {
            let p = [30.0, 425.0, 3750.0];
            (
                "complex, dominant pair",
                p,
                cubic_roots(p[0], p[1], p[2]),
                1e-11,
                1e-12,
            )
        },
        {
            let p = [22.0, 137.0, 350.0]; // −4 ± 3j, −14
            (
                "complex −4 ± 3j, −14",
                p,
                cubic_roots(p[0], p[1], p[2]),
                1e-12,
                1e-12,
            )
        },
        {
            let p = [42.0, 580.0, 1000.0]; // −2, −20 ± 10j
            (
                "complex −2, −20 ± 10j",
                p,
                cubic_roots(p[0], p[1], p[2]),
                1e-12,
                1e-12,
            )
        },
        {
            let (p, q) = real([-20.0, -40.0, -40.0]);
            ("repeated, not dominant", p, q, 1e-11, 1e-12)
        },
        {
            let (p, q) = real([-20.0, -20.5, -40.0]);
            ("near-repeated dominant, 0.5 apart", p, q, 1e-7, 1e-8)
        },
    ];
    for (name, p, q, exp_tol, k1_tol) in cases {
        let pm = p_matrix(p);
        let k2 = k2_of(&q);
        let f = SpectralExp::new(&pm, &q, k2).unwrap_or_else(|| panic!("{name}: no closed form"));
        for t in times(&q) {
            let (a, b) = (f.norm(t), k1_profile(&pm, k2, t));
            assert!(rel(a, b) <= exp_tol, "{name}, t = {t}: {a} vs {b}");
        }
        same_k1(name, &k1(&pm, &q, k2), &k1_expm(&pm, &q, k2), k1_tol);
    }
}

/// Below SEPARATION the closed form declines and K1 is the reference path's,
/// bit for bit; a repeated dominant pole gives an infinite K1 either way.
#[test]
fn near_repeated_poles_fall_back_to_the_expm_path() {
    for gap in [1e-3, 1e-2, 3e-2, 0.1] {
        let (p, q) = real([-20.0, -20.0 - gap, -40.0]);
        assert!(gap < SEPARATION * 40.0);
        let pm = p_matrix(p);
        let k2 = k2_of(&q);
        assert!(SpectralExp::new(&pm, &q, k2).is_none(), "gap {gap}");
        assert_eq!(k1(&pm, &q, k2), k1_expm(&pm, &q, k2), "gap {gap}");
    }
    // Computed roots of a double pole split by ~sqrt(ε): not equal, so no
    // confluent form either.
    let p = [100.0, 3200.0, 32000.0]; // (s + 20)(s + 40)²
    let q = cubic_roots(p[0], p[1], p[2]);
    let pm = p_matrix(p);
    if q[1].re != q[2].re || q[1].im != q[2].im {
        assert!(SpectralExp::new(&pm, &q, 20.0).is_none());
    }
    assert_eq!(k1(&pm, &q, 20.0), k1_expm(&pm, &q, 20.0));
    let (p, q) = real([-20.0, -20.0, -40.0]);
    let (a, b) = (k1(&p_matrix(p), &q, 20.0), k1_expm(&p_matrix(p), &q, 20.0));
    assert!(a.value.is_none() && b.value.is_none());
}

/// A double pole against its own closed form, independent of the module's
/// Hermite formula: for (s + 20)(s + 40)², the first entry of exp(Pt) is
/// the solution of the characteristic ODE with y(0) = 1, y'(0) = y''(0) = 0:
/// y = A e^(−20t) + (B + Ct) e^(−40t) with A + B = 1, −20A − 40B + C = 0,
/// 400A + 1600B − 80C = 0, i.e. A = 4, B = −3, C = −40; its derivatives
/// give the rest of the first column (x = (y, y', y'') solves x' = Px from
/// e1): y' = −80e^(−20t) + [−40 − 40(−3 − 40t)]e^(−40t)
/// = −80e^(−20t) + (80 + 1600t)e^(−40t) and
/// y'' = 1600e^(−20t) + [1600 − 40(80 + 1600t)]e^(−40t)
/// = 1600e^(−20t) − (1600 + 64000t)e^(−40t).
#[test]
fn double_pole_against_the_ode_solution() {
    let (p, q) = real([-20.0, -40.0, -40.0]);
    assert_eq!(p, [100.0, 3200.0, 32000.0]);
    let f = SpectralExp::new(&p_matrix(p), &q, 0.0).unwrap();
    for t in [0.0, 0.001, 0.02, 0.1, 0.5, 2.0] {
        let e = f.exp(t);
        let (a, b) = ((-20.0 * t).exp(), (-40.0 * t).exp());
        let want = [
            4.0 * a - (3.0 + 40.0 * t) * b,
            -80.0 * a + (80.0 + 1600.0 * t) * b,
            1600.0 * a - (1600.0 + 64000.0 * t) * b,
        ];
        for (i, w) in want.iter().enumerate() {
            let scale = [1.0, 80.0, 1600.0][i];
            assert!(
                (e[(i, 0)] - w).abs() <= 1e-14 * scale,
                "t = {t}, row {i}: {} vs {w}",
                e[(i, 0)]
            );
        }
    }
    // At t = 0 the closed form is I.
    assert!((f.exp(0.0) - Matrix3::identity()).abs().max() < 1e-15);
}

/// Not a test: prints g(t) by both paths (the closed form down to a gap of
/// 1e-4 of the scale) for the pole sets of the SEPARATION study, compared
/// with mpmath at 50 digits in its doc.
/// `cargo test --release -p ehservo --test it k1_closed_form -- --ignored --nocapture`
#[test]
#[ignore]
fn dump_for_mpmath() {
    for gap in [10.0, 0.5, 0.1, 0.04, 0.02, 0.01] {
        for (name, r) in [
            ("dom", [-20.0, -20.0 - gap, -40.0]),
            ("fast", [-20.0, -40.0, -40.0 - gap]),
        ] {
            let (p, q) = real(r);
            let pm = p_matrix(p);
            let k2 = -q[0].re;
            let f = SpectralExp::with_separation(&pm, &q, k2, 1e-4);
            for t in [1e-4, 1e-3, 1e-2, 0.05, 0.1, 0.3, 1.0, 3.0, 10.0] {
                println!(
                    "{name} {gap} {t} {:.17e} {:.17e}",
                    f.as_ref().map_or(f64::NAN, |f| f.norm(t)),
                    k1_profile(&pm, k2, t)
                );
            }
        }
    }
}
