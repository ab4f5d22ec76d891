//! Tests of `ss.rs` (state-space models), apart from the code they test.

use super::*;

fn q(n: &str) -> Quantity {
    Quantity::new(n, "")
}

/// `1/(s + a)` as a model.
fn first_order(a: f64) -> StateSpace {
    StateSpace::new(
        DMatrix::from_element(1, 1, -a),
        DMatrix::from_element(1, 1, 1.0),
        DMatrix::from_element(1, 1, 1.0),
        DMatrix::zeros(1, 1),
        None,
        (vec![q("x")], vec![q("u")], vec![q("y")]),
    )
}

/// ZOH of 1/(s + a) with period h, by hand: Φ = e^{−a·h},
/// Γ = (1 − e^{−a·h})/a. a = 3, h = 0.1: Φ = e^{−0.3} = 0.7408182,
/// Γ = 0.2591818/3 = 0.0863939.
#[test]
fn zoh_of_a_first_order_lag_by_hand() {
    let d = first_order(3.0).zoh(0.1).unwrap();
    assert!((d.a[(0, 0)] - (-0.3f64).exp()).abs() < 1e-15);
    assert!((d.b[(0, 0)] - (1.0 - (-0.3f64).exp()) / 3.0).abs() < 1e-15);
    // DC gains agree: continuous 1/3, discrete Γ/(1 − Φ) = 1/3.
    assert!((d.dc_gain().unwrap() - 1.0 / 3.0).abs() < 1e-14);
    assert!((first_order(3.0).dc_gain().unwrap() - 1.0 / 3.0).abs() < 1e-15);
}

/// The RK4 map of ẋ = −a·x over one step τ is the Taylor polynomial of
/// e^{−aτ} to fourth order (R), and Γ = τ·(1 − z/2 + z²/6 − z³/24) with
/// z = aτ; two sub-steps give R² and (1 + R)·Q.
#[test]
fn rk4_map_of_a_lag_by_hand() {
    let (a, h) = (3.0, 0.1);
    let s = first_order(a).rk4_map(h, 2).unwrap();
    let z = a * h / 2.0;
    let r = 1.0 - z + z * z / 2.0 - z * z * z / 6.0 + z.powi(4) / 24.0;
    let qq = h / 2.0 * (1.0 - z / 2.0 + z * z / 6.0 - z * z * z / 24.0);
    assert!((s.a[(0, 0)] - r * r).abs() < 1e-15);
    assert!((s.b[(0, 0)] - (1.0 + r) * qq).abs() < 1e-15);
    // And it is what ehservo_core's RK4 does to the same ODE, in two
    // steps of h/2 with u = 1 held.
    let mut x = [0.25f64];
    for k in 0..2 {
        ehservo_core::rk4::rk4_step(
            |_t, y: &[f64; 1], dy: &mut [f64; 1]| dy[0] = -a * y[0] + 1.0,
            k as f64 * h / 2.0,
            &mut x,
            h / 2.0,
        );
    }
    assert!((x[0] - (s.a[(0, 0)] * 0.25 + s.b[(0, 0)])).abs() < 1e-15);
}

/// (s + 2)/((s + 1)(s + 3)) in companion form: poles −1, −3, zero −2,
/// DC gain 2/3; at s = j: (2 + j)/((1 + j)(3 + j)) = (2 + j)/(2 + 4j)
/// = (2 + j)(2 − 4j)/20 = (8 − 6j)/20 = 0.4 − 0.3j.
#[test]
fn poles_zeros_gain_and_response_by_hand() {
    let s = StateSpace::new(
        DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -3.0, -4.0]),
        DMatrix::from_row_slice(2, 1, &[0.0, 1.0]),
        DMatrix::from_row_slice(1, 2, &[2.0, 1.0]),
        DMatrix::zeros(1, 1),
        None,
        (vec![q("x1"), q("x2")], vec![q("u")], vec![q("y")]),
    );
    let p = s.poles().unwrap();
    assert!((p[0].re + 3.0).abs() < 1e-12 && (p[1].re + 1.0).abs() < 1e-12);
    let z = s.zeros().unwrap();
    assert_eq!(z.len(), 1);
    assert!((z[0].re + 2.0).abs() < 1e-12 && z[0].im.abs() < 1e-12);
    assert!((s.dc_gain().unwrap() - 2.0 / 3.0).abs() < 1e-14);
    let g = s.response(1.0).unwrap();
    assert!(
        (g.re - 0.4).abs() < 1e-14 && (g.im + 0.3).abs() < 1e-14,
        "{g}"
    );
    // With D = 1: (s² + 5s + 5)/(s² + 4s + 3), zeros (−5 ± √5)/2.
    let mut s1 = s.clone();
    s1.d[(0, 0)] = 1.0;
    let z = s1.zeros().unwrap();
    let r5 = 5f64.sqrt();
    assert!((z[0].re - (-5.0 - r5) / 2.0).abs() < 1e-12);
    assert!((z[1].re - (-5.0 + r5) / 2.0).abs() < 1e-12);
    // Damping of the poles: real, ζ = 1, ωn = 3 and 1.
    let m = s.damping().unwrap();
    assert!((m[0].wn_rad_s.unwrap() - 3.0).abs() < 1e-12);
    assert!((m[0].zeta.unwrap() - 1.0).abs() < 1e-12);
}

/// A delay of 3 samples: z⁻³ on the unit circle is e^{−3jωh}; its poles
/// are three at 0 and it has no zeros.
#[test]
fn delay_is_z_to_the_minus_n() {
    let d = StateSpace::delay(3, 0.01, &q("u"));
    for w in [0.5, 10.0, 200.0] {
        let g = d.response(w).unwrap();
        let want = C64::from_polar(1.0, -3.0 * w * 0.01);
        assert!((g - want).norm() < 1e-14, "{w}: {g} vs {want}");
    }
    assert_eq!(d.poles().unwrap().len(), 3);
    assert!(d.poles().unwrap().iter().all(|p| p.norm() == 0.0));
    let g0 = StateSpace::delay(0, 0.01, &q("u"));
    assert_eq!(g0.response(3.0).unwrap(), C64::new(1.0, 0.0));
}

/// Series connection: 1/(s + 1) then 1/(s + 2) is 1/((s + 1)(s + 2)):
/// at s = j, 1/((1 + j)(2 + j)) = 1/(1 + 3j) = (1 − 3j)/10.
#[test]
fn series_multiplies_responses() {
    let s = first_order(1.0).series(&first_order(2.0)).unwrap();
    let g = s.response(1.0).unwrap();
    assert!((g - C64::new(0.1, -0.3)).norm() < 1e-15, "{g}");
}

/// Balancing keeps the eigenvalues and the exponential of a badly
/// scaled matrix: [[0, 1e6], [−1e-6, 0]] is a rotation at 1 rad/s in
/// disguise, e^{M·t} = [[cos t, 1e6 sin t], [−1e-6 sin t, cos t]].
#[test]
fn balanced_exponential_of_a_badly_scaled_matrix() {
    let m = DMatrix::from_row_slice(2, 2, &[0.0, 1e6, -1e-6, 0.0]);
    let e = expm(&(&m * 0.3)).unwrap();
    let (c, s) = (0.3f64.cos(), 0.3f64.sin());
    assert!((e[(0, 0)] - c).abs() < 1e-14);
    assert!((e[(0, 1)] - 1e6 * s).abs() < 1e-8);
    assert!((e[(1, 0)] + 1e-6 * s).abs() < 1e-20);
    let ev = eigenvalues(&m).unwrap();
    assert!(ev[0].re.abs() < 1e-12 && (ev[0].im + 1.0).abs() < 1e-12);
}

/// The stack solve of `response` is the heap LU of `at`: on a badly
/// scaled discrete loop (the slide's, m and Pa, spool and delays) and a
/// continuous one, at frequencies around their resonances and poles, to
/// 1e-9 of the value's size: both are partially pivoted eliminations, and
/// near a resonance (pI − A is ill-conditioned there) the order of the
/// operations moves the last digits (measured: 3e-12 at the slide's
/// 234 rad/s).
#[test]
fn response_on_the_stack_is_the_lu_of_at() {
    use crate::freq::{linearise, At, Discretisation, Side};
    use crate::scenario::Loop;
    let slide = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/cylinders/slide.toml");
    let s = crate::formats::load(&slide, &[]).unwrap();
    let l = linearise(
        &s,
        "slide",
        Some(At::Trim(0.18)),
        Some(Side::Plus),
        Discretisation::Zoh,
    )
    .unwrap();
    let c =
        Loop::parse("[simulation]\nmode = \"continuous\"\n[controller]\nkind = \"pid\"\n").unwrap();
    let lc = linearise(&c, "c", None, None, Discretisation::Zoh).unwrap();
    for m in [
        l.lp.loop_l.as_ref().unwrap(),
        l.lp.g_d.as_ref().unwrap(),
        &l.lp.g,
        lc.lp.loop_l.as_ref().unwrap(),
    ] {
        assert!(m.n() <= super::STACK_STATES);
        for k in 0..200 {
            let w = 10f64.powf(-1.0 + 4.5 * f64::from(k) / 199.0);
            let heap = m.at(m.point(w)).map(|v| v[(0, 0)]);
            let stack = m.response(w);
            match (heap, stack) {
                (Some(h), Some(s)) => {
                    assert!((h - s).norm() <= 1e-9 * h.norm(), "w = {w}: {h} vs {s}")
                }
                (h, s) => assert_eq!(h.is_some(), s.is_some(), "w = {w}"),
            }
        }
    }
}
