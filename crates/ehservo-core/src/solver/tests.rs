//! The pairs' tableaux against the order conditions, their orders measured
//! on ẏ = y, and the controller's global error on linear ODEs with closed
//! forms, held to the tolerance asked.

use super::bs32::BS32;
use super::dopri5::DOPRI5;
use super::rosenbrock23::{Analytic, FiniteDifference, Matrix, Rosenbrock23, D};
use super::*;

/// Σⱼ aᵢⱼ·vⱼ for row i.
fn a_dot(tab: &Tableau, i: usize, v: &[f64]) -> f64 {
    tab.a[i].iter().zip(v).map(|(a, x)| a * x).sum()
}

/// The Butcher order conditions up to order 4 for the weights `w`
/// (Hairer, Nørsett & Wanner, Solving ODEs I, §II.2, Table 2.2): the
/// elementary differentials' values 1, 1/2, 1/3, 1/6, 1/4, 1/8, 1/12, 1/24.
fn conditions(tab: &Tableau, w: &[f64], order: u32) -> Vec<(f64, f64)> {
    let s = tab.stages();
    let c = tab.c;
    let ac: Vec<f64> = (0..s).map(|i| a_dot(tab, i, c)).collect();
    let c2: Vec<f64> = c.iter().map(|x| x * x).collect();
    let ac2: Vec<f64> = (0..s).map(|i| a_dot(tab, i, &c2)).collect();
    let aac: Vec<f64> = (0..s).map(|i| a_dot(tab, i, &ac)).collect();
    let sum = |g: &dyn Fn(usize) -> f64| (0..s).map(|i| w[i] * g(i)).sum::<f64>();
    let mut out = vec![(sum(&|_| 1.0), 1.0)];
    if order >= 2 {
        out.push((sum(&|i| c[i]), 0.5));
    }
    if order >= 3 {
        out.push((sum(&|i| c2[i]), 1.0 / 3.0));
        out.push((sum(&|i| ac[i]), 1.0 / 6.0));
    }
    if order >= 4 {
        out.push((sum(&|i| c2[i] * c[i]), 0.25));
        out.push((sum(&|i| c[i] * ac[i]), 0.125));
        out.push((sum(&|i| ac2[i]), 1.0 / 12.0));
        out.push((sum(&|i| aac[i]), 1.0 / 24.0));
    }
    out
}

/// Each row of A sums to its node (cᵢ = Σⱼ aᵢⱼ), b and b̂ = b − e meet the
/// order conditions of their orders (up to 4), and e sums to 0.
#[test]
fn tableaux_meet_the_order_conditions() {
    for tab in [&DOPRI5, &BS32] {
        let s = tab.stages();
        assert_eq!((tab.a.len(), tab.c.len(), tab.e.len()), (s, s, s));
        for i in 0..s {
            assert_eq!(tab.a[i].len(), i, "{} row {i}", tab.name);
            let row: f64 = tab.a[i].iter().sum();
            assert!((row - tab.c[i]).abs() < 1e-14, "{} row {i}", tab.name);
        }
        let b_hat: Vec<f64> = tab.b.iter().zip(tab.e).map(|(b, e)| b - e).collect();
        for (w, p) in [(tab.b, tab.order), (&b_hat[..], tab.error_order)] {
            for (got, want) in conditions(tab, w, p.min(4)) {
                assert!((got - want).abs() < 1e-14, "{}: {got} vs {want}", tab.name);
            }
        }
        assert!(tab.e.iter().sum::<f64>().abs() < 1e-15);
    }
}

/// On ẏ = y one step's local error is O(h^(p+1)) for y₁ and the estimate
/// ê is O(h^(p̂+1)): halving h divides them by 2^(p+1) and 2^(p̂+1)
/// (64 and 32 for DOPRI5, 16 and 8 for BS32), within 15%.
#[test]
fn local_errors_have_the_stated_orders() {
    for tab in [&DOPRI5, &BS32] {
        let one = |h: f64| {
            let mut k = [[0.0]; MAX_STAGES];
            let mut f = |_t: f64, y: &[f64; 1], d: &mut [f64; 1]| d[0] = y[0];
            k[0] = [1.0];
            let (y1, e) = trial(tab, &mut f, 0.0, &[1.0], &mut k, h);
            ((y1[0] - h.exp()).abs(), e[0].abs())
        };
        let (a, b) = (one(0.1), one(0.05));
        let p = f64::from(2u32.pow(tab.order + 1));
        let q = f64::from(2u32.pow(tab.error_order + 1));
        assert!(
            (a.0 / b.0 / p - 1.0).abs() < 0.15,
            "{}: {}",
            tab.name,
            a.0 / b.0
        );
        assert!(
            (a.1 / b.1 / q - 1.0).abs() < 0.15,
            "{}: {}",
            tab.name,
            a.1 / b.1
        );
    }
}

/// A linear test problem with its closed form.
struct Case {
    name: &'static str,
    f: fn(f64, &[f64; 2], &mut [f64; 2]),
    exact: fn(f64) -> f64,
}

const W: f64 = 2.0 * core::f64::consts::PI * 5.0; // 5 Hz
const ZETA: f64 = 0.2;

fn cases() -> [Case; 3] {
    [
        // ẋ = −x + 1, x(0) = 0: x = 1 − e^{−t}.
        Case {
            name: "first-order step",
            f: |_t, y, d| *d = [-y[0] + 1.0, 0.0],
            exact: |t| 1.0 - (-t).exp(),
        },
        // ẋ = −x + sin 2t, x(0) = 0: x = (sin 2t − 2 cos 2t + 2e^{−t})/5
        // (particular solution A sin + B cos with A − 2B = 1, 2A + B = 0).
        Case {
            name: "first-order sine",
            f: |t, y, d| *d = [-y[0] + (2.0 * t).sin(), 0.0],
            exact: |t| ((2.0 * t).sin() - 2.0 * (2.0 * t).cos() + 2.0 * (-t).exp()) / 5.0,
        },
        // ẍ + 2ζωẋ + ω²x = ω² (a unit step), at rest: x = 1 − e^{−ζωt}
        // (cos ω_d t + ζ/√(1−ζ²) sin ω_d t), ω_d = ω√(1−ζ²).
        Case {
            name: "damped oscillator step",
            f: |_t, y, d| *d = [y[1], W * W * (1.0 - y[0]) - 2.0 * ZETA * W * y[1]],
            exact: |t| {
                let r = (1.0 - ZETA * ZETA).sqrt();
                let wd = W * r;
                1.0 - (-ZETA * W * t).exp() * ((wd * t).cos() + ZETA / r * (wd * t).sin())
            },
        },
    ]
}

/// The largest |x − x_exact| at the samples of a 1 s loop over 0–10 s,
/// integrated sample to sample as the simulator does (restarting at each),
/// with rtol = atol = `tol`; and the counts.
fn run<M: Method<[f64; 2]>>(tab: &M, case: &Case, tol: f64) -> (f64, StepCounts) {
    let period = 1.0;
    let ctl = StepControl {
        max_step: period,
        max_steps: 10_000_000,
    };
    let w = tab.error_weight(tol);
    let norm =
        |y0: &[f64; 2], y1: &[f64; 2], e: &[f64; 2]| w * scaled_rms(&[(y0, y1, e)], tol, &[tol]);
    let mut a = Adaptive::new();
    let mut y = [0.0; 2];
    let mut worst: f64 = 0.0;
    for k in 0..10u32 {
        let (t0, t1) = (f64::from(k) * period, f64::from(k + 1) * period);
        a.integrate(tab, &ctl, case.f, norm, |_| {}, t0, t1, &mut y)
            .expect("within the budget");
        worst = worst.max((y[0] - (case.exact)(t1)).abs());
    }
    (worst, a.counts)
}

/// The global error stays within C·tol, C = 10, for tol = rtol = atol
/// from 1e-3 to 1e-8 (the solutions are of size 1, so tol is the scale),
/// and falls as tol falls (by at least 10× over the five decades, with
/// more steps taken at each tighter tolerance).
#[test]
fn global_error_is_held_to_the_tolerance() {
    const C: f64 = 10.0;
    for tab in [&DOPRI5, &BS32] {
        for case in cases() {
            let mut prev: Option<(f64, u64)> = None;
            let mut first = None;
            for tol in [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8] {
                let (err, n) = run(tab, &case, tol);
                std::println!(
                    "{} {}: tol {tol:e} error {err:.3e} steps {n:?}",
                    tab.name,
                    case.name
                );
                assert!(
                    err <= C * tol,
                    "{} {}: error {err:e} at tol {tol:e}",
                    tab.name,
                    case.name
                );
                if let Some((_, steps)) = prev {
                    assert!(
                        n.accepted >= steps,
                        "{} {}: fewer steps at {tol:e}",
                        tab.name,
                        case.name
                    );
                }
                first.get_or_insert(err);
                prev = Some((err, n.accepted));
            }
            let (last, _) = prev.expect("ran");
            let first = first.expect("ran");
            assert!(
                last * 10.0 < first.max(1e-16),
                "{} {}: {first:e} → {last:e}",
                tab.name,
                case.name
            );
        }
    }
}

/// A stiff-ish problem (ẏ = −2000·(y − cos t), stiffness far beyond the
/// accuracy's step at a loose tolerance) makes the controller reject
/// steps; the counts record them, and the step budget stops the
/// integration as a result, not a hang.
#[test]
fn rejections_are_counted_and_the_budget_holds() {
    let f = |t: f64, y: &[f64; 1], d: &mut [f64; 1]| d[0] = -2000.0 * (y[0] - t.cos());
    let norm =
        |y0: &[f64; 1], y1: &[f64; 1], e: &[f64; 1]| scaled_rms(&[(y0, y1, e)], 1e-3, &[1e-6]);
    let ctl = StepControl {
        max_step: 1.0,
        max_steps: 1_000_000,
    };
    let mut a = Adaptive::new();
    let mut y = [0.0];
    a.integrate(&DOPRI5, &ctl, f, norm, |_| {}, 0.0, 1.0, &mut y)
        .expect("within the budget");
    assert!(a.counts.rejected > 0, "{:?}", a.counts);
    // The slow solution y ≈ cos t (error O(1/2000) from the lag sin t/2000).
    assert!((y[0] - 1f64.cos()).abs() < 1e-3);
    let small = StepControl {
        max_step: 1.0,
        max_steps: 10,
    };
    let mut b = Adaptive::new();
    let mut y = [0.0];
    let r = b.integrate(&DOPRI5, &small, f, norm, |_| {}, 0.0, 1.0, &mut y);
    assert!(matches!(r, Err(Failure::StepBudget { .. })), "{r:?}");
    assert_eq!(b.counts.total(), 10);
}

/// A right-hand side that is NaN beyond t = 0.5 cannot be integrated past
/// it: every trial there is rejected until the step is under ten ulps,
/// and the integration says so at t ≤ 0.5.
#[test]
fn a_non_finite_right_hand_side_stops_as_a_result() {
    let f = |t: f64, _y: &[f64; 1], d: &mut [f64; 1]| d[0] = if t > 0.5 { f64::NAN } else { 1.0 };
    let norm =
        |y0: &[f64; 1], y1: &[f64; 1], e: &[f64; 1]| scaled_rms(&[(y0, y1, e)], 1e-6, &[1e-9]);
    let ctl = StepControl {
        max_step: 0.1,
        max_steps: 100_000,
    };
    let mut a = Adaptive::new();
    let mut y = [0.0];
    match a.integrate(&DOPRI5, &ctl, f, norm, |_| {}, 0.0, 1.0, &mut y) {
        Err(Failure::StepTooSmall { t, .. }) => assert!(t <= 0.5, "{t}"),
        r => panic!("{r:?}"),
    }
    assert!(y[0].is_finite());
}

/// The scaled norm by hand: ê = (1e-6, 2e-6), y = (1, −3), rtol 1e-3,
/// atol (1e-4, 1e-3): scales 1e-4 + 1e-3 = 1.1e-3 and 1e-3 + 3e-3 = 4e-3;
/// ratios 9.0909e-4 and 5e-4; rms = √((8.2645e-7 + 2.5e-7)/2) = 7.3363e-4.
#[test]
fn scaled_rms_by_hand() {
    let r = scaled_rms(
        &[(&[1.0, -3.0], &[1.0, -3.0], &[1e-6, 2e-6])],
        1e-3,
        &[1e-4, 1e-3],
    );
    let want = ((1e-6f64 / 1.1e-3).powi(2) / 2.0 + (2e-6f64 / 4e-3).powi(2) / 2.0).sqrt();
    assert!(
        (r - want).abs() < 1e-15 && (r - 7.3363e-4).abs() < 1e-8,
        "{r}"
    );
}

/// atol 0 on a state that stays at 0 (issue #46, round four: every step
/// of a cylinder at rest was rejected, ê/(0 + rtol·0) = 0/0 = NaN): a
/// zero estimate adds 0, so ê = (1e-6, 0), y = (1, 0), rtol 1e-3, atol 0
/// gives √((1e-6/1e-3)²/2) = 7.0711e-4; a nonzero ê against a zero scale
/// is infinite (the step is rejected).
#[test]
fn a_zero_error_at_zero_tolerance_is_no_error() {
    let r = scaled_rms(&[(&[1.0, 0.0], &[1.0, 0.0], &[1e-6, 0.0])], 1e-3, &[0.0]);
    assert!((r - 7.0711e-4).abs() < 1e-8, "{r}");
    let inf = scaled_rms(&[(&[1.0, 0.0], &[1.0, 0.0], &[1e-6, 1e-300])], 1e-3, &[0.0]);
    assert!(inf.is_infinite(), "{inf}");
    // And an integration of ẏ = (−y₀, 0) from (1, 0) at atol 0 reaches t = 1.
    let ctl = StepControl {
        max_step: 1.0,
        max_steps: 100_000,
    };
    let norm =
        |y0: &[f64; 2], y1: &[f64; 2], e: &[f64; 2]| scaled_rms(&[(y0, y1, e)], 1e-8, &[0.0]);
    let mut y = [1.0, 0.0];
    let mut a = Adaptive::new();
    a.integrate(
        &DOPRI5,
        &ctl,
        |_, y: &[f64; 2], d: &mut [f64; 2]| *d = [-y[0], 0.0],
        norm,
        |_| {},
        0.0,
        1.0,
        &mut y,
    )
    .expect("a state at rest does not stop the solver");
    // e⁻¹ = 0.36788 within 10·rtol of its size.
    assert!(
        (y[0] - (-1.0f64).exp()).abs() < 1e-7 && y[1] == 0.0,
        "{y:?}"
    );
}

/// The stiff method with a finite-difference Jacobian.
const ROS_FD: Rosenbrock23<FiniteDifference> = Rosenbrock23 {
    jacobian: FiniteDifference {
        floor: [0.0; rosenbrock23::MAX_DIM],
    },
};

/// Rosenbrock23 holds the same closed-form cases to C·tol, C = 10, from
/// 1e-3 to 1e-7 (order 2: 1e-8 would take ~10⁵ steps a case), with the
/// Jacobian by forward differences, and its error falls in proportion to
/// tol (its error weight 1/√rtol; without it the error grew as tol^(2/3),
/// 55·tol at 1e-7). Seen: error/tol 0.22–0.26, 0.34–0.37, 0.016.
#[test]
fn rosenbrock23_holds_the_closed_forms_to_the_tolerance() {
    const C: f64 = 10.0;
    for case in cases() {
        let mut errs = Vec::new();
        for tol in [1e-3, 1e-4, 1e-5, 1e-6, 1e-7] {
            let (err, n) = run(&ROS_FD, &case, tol);
            std::println!(
                "rosenbrock23 {}: tol {tol:e} error {err:.3e} steps {n:?}",
                case.name
            );
            assert!(
                err <= C * tol,
                "{}: error {err:e} at tol {tol:e}",
                case.name
            );
            errs.push(err);
        }
        // Proportional: 10⁴ less tolerance buys more than 10³ less error.
        assert!(errs[4] * 1e3 < errs[0], "{}: {errs:?}", case.name);
    }
}

/// y' = A·y with A = P·diag(−1, −10⁶)·P⁻¹, P = [[1, 1], [1, −1]]:
/// A = ½[[λ₁+λ₂, λ₁−λ₂], [λ₁−λ₂, λ₁+λ₂]]. From y(0) = (1, 0), P⁻¹y(0) =
/// (½, ½), so y(t) = ½e^{λ₁t}(1, 1) + ½e^{λ₂t}(1, −1).
const L1: f64 = -1.0;
const L2: f64 = -1e6;

fn stiff(_t: f64, y: &[f64; 2], d: &mut [f64; 2]) {
    let (s, m) = (0.5 * (L1 + L2), 0.5 * (L1 - L2));
    *d = [s * y[0] + m * y[1], m * y[0] + s * y[1]];
}

fn stiff_exact(t: f64) -> [f64; 2] {
    let (a, b) = (0.5 * (L1 * t).exp(), 0.5 * (L2 * t).exp());
    [a + b, a - b]
}

/// Integrates the stiff system over 0–`horizon` in samples of 0.1 s with
/// rtol = atol = tol: the largest error over both components at the
/// samples, and the counts (None when the budget ran out).
fn run_stiff<M: Method<[f64; 2]>>(
    m: &M,
    tol: f64,
    horizon: u32,
    budget: u64,
) -> Option<(f64, StepCounts)> {
    let ctl = StepControl {
        max_step: 0.1,
        max_steps: budget,
    };
    let w = m.error_weight(tol);
    let norm =
        |y0: &[f64; 2], y1: &[f64; 2], e: &[f64; 2]| w * scaled_rms(&[(y0, y1, e)], tol, &[tol]);
    let mut a = Adaptive::new();
    let mut y = [1.0, 0.0];
    let mut worst: f64 = 0.0;
    for k in 0..horizon * 10 {
        let (t0, t1) = (f64::from(k) * 0.1, f64::from(k + 1) * 0.1);
        a.integrate(m, &ctl, stiff, norm, |_| {}, t0, t1, &mut y)
            .ok()?;
        let want = stiff_exact(t1);
        worst = worst
            .max((y[0] - want[0]).abs())
            .max((y[1] - want[1]).abs());
    }
    Some((worst, a.counts))
}

/// On the stiff system the stiff method meets the tolerance with either
/// Jacobian in a few hundred steps, while dopri5, held to its stability
/// limit h·|λ₂| ≲ 3.3 (h ≈ 3.3 µs), needs about 3·10⁵ steps for 1 s.
#[test]
fn a_stiff_linear_system_is_held_to_the_tolerance_in_few_steps() {
    let jac = |_t: f64, _y: &[f64; 2], j: &mut Matrix| {
        let (s, m) = (0.5 * (L1 + L2), 0.5 * (L1 - L2));
        j[0][0] = s;
        j[0][1] = m;
        j[1][0] = m;
        j[1][1] = s;
    };
    let analytic = Rosenbrock23 {
        jacobian: Analytic(jac),
    };
    for tol in [1e-4, 1e-6] {
        let (e_fd, n_fd) = run_stiff(&ROS_FD, tol, 10, 1_000_000).expect("within the budget");
        let (e_an, n_an) = run_stiff(&analytic, tol, 10, 1_000_000).expect("within the budget");
        std::println!("stiff tol {tol:e}: fd {e_fd:.3e} {n_fd:?}, analytic {e_an:.3e} {n_an:?}");

        assert!(
            n_fd.total() < 5_000 && n_an.total() < 5_000,
            "{n_fd:?} {n_an:?}"
        );
    }
    let (_, n_dp) = run_stiff(&DOPRI5, 1e-6, 1, 10_000_000).expect("within the budget");
    let (_, n_ros) = run_stiff(&ROS_FD, 1e-6, 1, 10_000_000).expect("within the budget");
    std::println!("1 s: dopri5 {n_dp:?}, rosenbrock23 {n_ros:?}");
    assert!(n_dp.accepted > 200_000, "{n_dp:?}");
    assert!(n_ros.total() * 100 < n_dp.total(), "{n_ros:?} vs {n_dp:?}");
}

/// The global error of fixed steps falls as h²: over 0–1 with N and 2N
/// steps the error ratio is 4 within 10 %, on ẏ = −y² (y = 1/(1+t), the
/// analytic J = −2y) and on ẋ = −x + sin 2t (non-autonomous: the h·d·T
/// term carries the order; J by differences).
/// One fixed step (t, y, h) → y₁.
type OneStep = dyn Fn(f64, &[f64; 1], f64) -> [f64; 1];

#[test]
fn rosenbrock23_is_second_order_by_halving() {
    let fixed = |m: &OneStep, n: u32| {
        let h = 1.0 / f64::from(n);
        let mut y = [1.0];
        for i in 0..n {
            y = m(f64::from(i) * h, &y, h);
        }
        y[0]
    };
    let quad = |t: f64, y: &[f64; 1], h: f64| {
        let m = Rosenbrock23 {
            jacobian: Analytic(|_t: f64, y: &[f64; 1], j: &mut Matrix| j[0][0] = -2.0 * y[0]),
        };
        let mut f = |_t: f64, y: &[f64; 1], d: &mut [f64; 1]| d[0] = -y[0] * y[0];
        let f0 = [-y[0] * y[0]];
        m.trial(&mut f, t, y, &f0, h).expect("W regular").0
    };
    let sine = |t: f64, y: &[f64; 1], h: f64| {
        let mut f = |t: f64, y: &[f64; 1], d: &mut [f64; 1]| d[0] = -y[0] + (2.0 * t).sin();
        let mut f0 = [0.0];
        f(t, y, &mut f0);
        ROS_FD.trial(&mut f, t, y, &f0, h).expect("W regular").0
    };
    // ẋ = −x + sin 2t from x(0) = 1: (sin 2t − 2cos 2t)/5 + (7/5)e^{−t}.
    let sine_exact = ((2f64).sin() - 2.0 * (2f64).cos()) / 5.0 + 1.4 * (-1f64).exp();
    for (name, m, exact) in [
        ("-y^2", &quad as &OneStep, 0.5),
        ("sine", &sine, sine_exact),
    ] {
        let e1 = (fixed(m, 20) - exact).abs();
        let e2 = (fixed(m, 40) - exact).abs();
        let e3 = (fixed(m, 80) - exact).abs();
        std::println!("{name}: {e1:e} {e2:e} {e3:e}");
        assert!((e1 / e2 / 4.0 - 1.0).abs() < 0.1, "{name}: {}", e1 / e2);
        assert!((e2 / e3 / 4.0 - 1.0).abs() < 0.1, "{name}: {}", e2 / e3);
    }
}

/// ẏ = λy with h·d·λ = 1 makes W = 1 − h·d·λ = 0: the step is refused (not
/// a NaN), and the integration shrinks past it to y(0.2) = e^{0.2λ}
/// (λ ≈ 34/s: the growing mode amplifies the local errors, so 1e-3
/// relative at rtol 1e-6).
#[test]
fn a_singular_w_is_refused_and_stepped_around() {
    let h = 0.1;
    let lambda = 1.0 / (h * D);
    let mut f = |_t: f64, y: &[f64; 1], d: &mut [f64; 1]| d[0] = lambda * y[0];
    let y = [1.0];
    let f0 = [lambda];
    let an = Rosenbrock23 {
        jacobian: Analytic(|_t: f64, _y: &[f64; 1], j: &mut Matrix| j[0][0] = lambda),
    };
    assert!(an.trial(&mut f, 0.0, &y, &f0, h).is_none());
    assert!(an.trial(&mut f, 0.0, &y, &f0, h / 2.0).is_some());
    let ctl = StepControl {
        max_step: h,
        max_steps: 100_000,
    };
    let norm =
        |y0: &[f64; 1], y1: &[f64; 1], e: &[f64; 1]| scaled_rms(&[(y0, y1, e)], 1e-6, &[1e-9]);
    let mut a = Adaptive::new();
    let mut y = [1.0];
    a.integrate(&an, &ctl, f, norm, |_| {}, 0.0, 0.2, &mut y)
        .expect("within the budget");
    let want = (0.2 * lambda).exp();
    assert!((y[0] / want - 1.0).abs() < 1e-3, "{} vs {want}", y[0]);
}

/// The forward-difference Jacobian of f(y) = (y₀·y₁, sin y₀ + y₁³) at
/// (0.5, 2): [[y₁, y₀], [cos y₀, 3y₁²]] = [[2, 0.5], [0.8776, 12]], to
/// about √ε relative.
#[test]
fn the_finite_difference_jacobian_matches_the_analytic_one() {
    let mut f =
        |_t: f64, y: &[f64; 2], d: &mut [f64; 2]| *d = [y[0] * y[1], y[0].sin() + y[1].powi(3)];
    let y = [0.5, 2.0];
    let mut f0 = [0.0; 2];
    f(0.0, &y, &mut f0);
    let mut j = [[0.0; rosenbrock23::MAX_DIM]; rosenbrock23::MAX_DIM];
    rosenbrock23::JacobianSource::jacobian(
        &FiniteDifference::default(),
        &mut f,
        0.0,
        &y,
        &f0,
        0.01,
        &mut j,
    );
    let want = [[2.0, 0.5], [0.5f64.cos(), 12.0]];
    for r in 0..2 {
        for c in 0..2 {
            assert!(
                (j[r][c] - want[r][c]).abs() < 1e-6 * want[r][c].abs().max(1.0),
                "{r}{c}: {}",
                j[r][c]
            );
        }
    }
}
