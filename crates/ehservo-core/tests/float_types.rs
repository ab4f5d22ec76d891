//! The core in f32 against the core in f64, on the paper's cases closed
//! around the on-board plant ([`ehservo_core::onboard`]).
//!
//! The requirement: closed-loop e_max (t ≥ 2 s) of f32 within 2 %
//! of f64. Measured (`cargo test -p ehservo-core --test float_types --
//! --nocapture` prints every pair): the largest relative difference over
//! these cases is far below that (see BENCHMARKS.md); the 2 % band is the
//! requirement, not a fit to the measurement.

use ehservo_core::control::nnvsc::NnVscParams;
use ehservo_core::control::vsc::{Vsc, VscParams};
use ehservo_core::control::Controller;
use ehservo_core::math::{Real, DR};
use ehservo_core::onboard::{Bias, BiasedPlant, ClosedLoop, Fig2Loop};
use ehservo_core::prelude::*;

fn nn_case<T: Real>(rate: u32, params: NnVscParams, bias: Bias<T>, seconds: u32) -> f64 {
    let mut lp = Fig2Loop::<T>::paper_with(rate, params, bias).unwrap();
    lp.run_for(seconds).expect("bounded");
    lp.e_max_deg().to_f64()
}

fn vsc_case<T: Real>(rate: u32, bias: Bias<T>, seconds: u32) -> f64 {
    let mut lp = ClosedLoop::paper_vsc(rate, bias).unwrap();
    if let Err(k) = lp.run_for(seconds) {
        panic!("unbounded at k = {k} ({rate} Hz, {})", T::NAME);
    }
    lp.e_max_deg().to_f64()
}

/// A controller computing in `T` around the f64 plant: what a board does
/// (its plant is physics, not arithmetic). x is rounded to `T` at the
/// measurement, u widened back; the reference phase is reduced as in
/// [`ClosedLoop::control`].
fn mixed_case<T: Real, C: Controller<T>>(ctl: C, rate: u32, bias: Bias<f64>, seconds: u32) -> f64 {
    let dt = 1.0 / f64::from(rate);
    let mut sc = SampledController::new(ctl, T::of(dt)).unwrap();
    let model = NominalModel::new(ServoParams::paper(), Load::paper());
    let plant = BiasedPlant::new(model, bias).unwrap();
    let r = Sine::paper().cast::<T>();
    let (mut x, mut e_max) = ([0.0f64; 3], 0.0f64);
    for k in 0..seconds * rate {
        let t_ref = T::of(f64::from(k % rate)) * T::of(dt);
        let z = r.z(t_ref);
        let e = z[0].to_f64() - x[0];
        if k >= 2 * rate {
            e_max = e_max.max(e.abs());
        }
        let u = sc
            .step(T::of(f64::from(k) * dt), x.map(T::of), z)
            .u
            .to_f64();
        rk4_step(
            |_, x: &[f64; 3], dx: &mut [f64; 3]| plant.rhs(x, u, dx),
            0.0,
            &mut x,
            dt,
        );
        assert!(x.iter().all(|v| v.is_finite()), "unbounded at k = {k}");
    }
    e_max / DR
}

fn bias<T: Real>(a: f64, b: f64) -> Bias<T> {
    Bias {
        a_bias: T::of(a),
        b_bias: T::of(b),
        ..Bias::fig2()
    }
}

fn check(name: &str, e32: f64, e64: f64) -> f64 {
    let rel = (e32 - e64).abs() / e64;
    println!("{name:<28} f64 {e64:.9}°  f32 {e32:.9}°  rel {rel:.2e}");
    assert!(e64.is_finite() && e64 > 0.0, "{name}: e_max {e64}");
    assert!(
        rel < 0.02,
        "{name}: f32 e_max {e32}° vs f64 {e64}° ({rel:.3e})"
    );
    rel
}

/// The f64 loop at the paper's 0.01 s is the Fig. 2 run of the C yardstick
/// (`shared/peers/c/nnvsc.c`, an independent implementation): its printed
/// e_max is 0.20909499579719379°. The band (1e-12 relative) allows the last
/// bits of `exp` (libm's here, glibc's in the C).
#[test]
fn f64_fig2_is_the_c_yardstick() {
    let e = nn_case::<f64>(100, NnVscParams::paper(), Bias::fig2(), 10);
    assert!((e - 0.209_094_995_797_193_8).abs() < 1e-12 * e, "{e}");
}

/// The paper's NNBVSC cases of 10 s (Figs. 2, 4, 5 and the ε variations;
/// the 60 s ones share the gains of `abar50`, taken here over 10 s) at the
/// paper's sample rate, and Fig. 2 at 1 and 10 kHz.
#[test]
fn f32_nnbvsc_within_two_percent_of_f64() {
    let p = NnVscParams::paper();
    let cases: [(&str, u32, NnVscParams); 7] = [
        ("fig2 100 Hz", 100, p),
        ("fig2 1 kHz", 1_000, p),
        ("fig2 10 kHz", 10_000, p),
        ("eta0", 100, NnVscParams { eta: 0.0, ..p }),
        ("gamma1-200", 100, NnVscParams { gamma1: 200.0, ..p }),
        (
            "eps-5-2",
            100,
            NnVscParams {
                eps0: 5.0,
                eps1: 2.0,
                ..p
            },
        ),
        (
            "abar50",
            100,
            NnVscParams {
                alpha_bar: 50.0,
                ..p
            },
        ),
    ];
    let mut worst = 0.0f64;
    for (name, rate, params) in cases {
        let e64 = nn_case::<f64>(rate, params, Bias::fig2(), 10);
        let e32 = nn_case::<f32>(rate, params, Bias::fig2(), 10);
        worst = worst.max(check(name, e32, e64));
    }
    println!("worst relative difference: {worst:.2e}");
}

/// The traditional VSC (Fig. 3: 40 % biases; and on the Fig. 2 case).
/// Sign switching chatters, so this is the least forgiving comparison.
/// Sampled at the paper's 0.01 s it is unbounded (as `ehservo run
/// scenarios/paper/fig3.toml` reports: θ leaves its limit at t = 1.77 s) in
/// both types; at 1 kHz it tracks, and f32 stays within 2 % of f64.
///
/// At 10 kHz the VSC chatters at |e| ≈ 6e-5 rad (0.0033°) and e_max *is*
/// the chattering amplitude: with the plant, too, integrated in f32 (whose
/// x1 += h·ẋ1 rounds by ulp(0.09 rad) ≈ 7e-9 rad every step, a random walk
/// of about 1e-6 rad over 10⁵ steps that the loop must reject) e_max moved
/// by 3 %. That is the f32 *plant*, not the f32 controller: the same f32
/// controller around an f64 plant (as on a board, whose plant is physics)
/// stays within 2 %, and that is what is asserted at 10 kHz.
#[test]
fn f32_vsc_within_two_percent_of_f64() {
    for (name, a, b) in [("fig3 vsc", 0.4, 0.4), ("vsc on fig2", 1.0, 0.5)] {
        let e64 = vsc_case::<f64>(1_000, bias(a, b), 10);
        let e32 = vsc_case::<f32>(1_000, bias(a, b), 10);
        check(&format!("{name} 1 kHz"), e32, e64);
        let vsc = || {
            let m = NominalModel::new(ServoParams::paper(), Load::paper());
            Vsc::try_new(m, SwitchingSurface::paper(), VscParams::paper()).unwrap()
        };
        let e64 = mixed_case::<f64, _>(vsc(), 10_000, bias(a, b), 10);
        let e32 = mixed_case::<f32, _>(vsc().cast().unwrap(), 10_000, bias(a, b), 10);
        check(&format!("{name} 10 kHz, f64 plant"), e32, e64);
        let all32 = vsc_case::<f32>(10_000, bias(a, b), 10);
        println!(
            "  (f32 plant too: {all32:.9}°, rel {:.2e})",
            (all32 - e64).abs() / e64
        );
    }
    let mut l64 = ClosedLoop::paper_vsc(100, bias::<f64>(0.4, 0.4)).unwrap();
    let mut l32 = ClosedLoop::paper_vsc(100, bias::<f32>(0.4, 0.4)).unwrap();
    let (r64, r32) = (l64.run_for(10), l32.run_for(10));
    // The simulator (an independent loop over the same core) reports the
    // f64 run "unbounded at t = 1.7700 s" (tests/golden/fig3.json of the
    // ehservo crate): k = 177 at 100 Hz. f32 leaves at the same sample.
    assert_eq!((r64, r32), (Err(177), Err(177)));
}

/// Φ in f32 (the factorised form: 4 exponentials, then products of up to
/// q⁴·C_j) against Φ in f64 (125 direct exponentials), over 2·10⁵ states
/// spread to three times the network's scale on every axis. Each f32
/// rounding is 6e-8 relative; the spaced form chains about ten of them
/// (G·C_j·q^j with q^j formed by repeated squaring), so entries ≤ 1 should
/// agree within about 1e-6. Measured: 3.3e-7.
#[test]
fn f32_rbf_agrees_with_f64_direct() {
    let r64 = Rbf::paper();
    let r32 = r64.cast::<f32>().unwrap();
    let (mut p64, mut p32) = ([0.0f64; N_PHI], [0.0f32; N_PHI]);
    let z = [0.01, -0.2, 3.0, -40.0];
    let mut seed = 1u64;
    let mut worst = 0.0f64;
    for _ in 0..200_000 {
        let mut x = [0.0f64; 3];
        for (i, xi) in x.iter_mut().enumerate() {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            let u = (seed >> 11) as f64 / (1u64 << 53) as f64;
            *xi = (2.0 * u - 1.0) * 3.0 * r64.scale()[i];
        }
        r64.phi_direct(&x, &z, &mut p64);
        let n32 = r32.phi(&x.map(|v| v as f32), &z.map(|v| v as f32), &mut p32);
        for (a, b) in p64[1..=N_KERNELS].iter().zip(&p32[1..=N_KERNELS]) {
            worst = worst.max((a - f64::from(*b)).abs());
        }
        let n64: f64 = p64.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!(
            (f64::from(n32) - n64).abs() < 1e-6 * n64,
            "‖Φ‖ {n32} vs {n64}"
        );
    }
    println!("max |φ32 − φ64| = {worst:e}");
    assert!(worst < 1e-6, "{worst:e}");
}

/// f32's fallback for one axis out of the factorised range
/// (`Real::RBF_AXIS_FALLBACK`): states with one or two axes far off the
/// grid (normalised 4.5 to 40, where only the in-range axes keep the
/// factorised form) agree with f64's direct Φ as closely as the grid's,
/// ‖Φ‖ too; infinite coordinates give no NaN, a NaN coordinate NaN kernels.
#[test]
fn f32_rbf_axis_fallback_agrees_with_f64_direct() {
    let r64 = Rbf::paper();
    let r32 = r64.cast::<f32>().unwrap();
    let s = r64.scale();
    let (mut p64, mut p32) = ([0.0f64; N_PHI], [0.0f32; N_PHI]);
    let z = [0.01, -0.2, 3.0, -40.0];
    let mut worst = 0.0f64;
    let mut n = 0;
    for far in [4.5, 5.0, 5.6, 7.0, 12.0, 40.0, -4.6, -6.3, -25.0] {
        for near in [-1.3, -0.37, 0.0, 0.21, 0.9, 2.2] {
            for axes in [[0, 1], [1, 2], [2, 0], [0, 0], [2, 2]] {
                let mut xt = [near, 0.5 * near + 0.1, -near];
                xt[axes[0]] = far;
                if axes[0] != axes[1] && far > 5.5 {
                    xt[axes[1]] = -far; // two axes out
                }
                let x = [xt[0] * s[0], xt[1] * s[1], xt[2] * s[2]];
                r64.phi_direct(&x, &z, &mut p64);
                let n32 = r32.phi(&x.map(|v| v as f32), &z.map(|v| v as f32), &mut p32);
                for (a, b) in p64[1..=N_KERNELS].iter().zip(&p32[1..=N_KERNELS]) {
                    worst = worst.max((a - f64::from(*b)).abs());
                }
                let n64: f64 = p64.iter().map(|v| v * v).sum::<f64>().sqrt();
                assert!(
                    (f64::from(n32) - n64).abs() < 1e-6 * n64,
                    "{xt:?}: ‖Φ‖ {n32} vs {n64}"
                );
                n += 1;
            }
        }
    }
    assert_eq!(n, 9 * 6 * 5);
    assert!(worst < 1e-6, "{worst:e}");
    for v in [f32::INFINITY, f32::NEG_INFINITY, f32::MAX] {
        let norm = r32.phi(&[0.0, v, 0.01], &z.map(|v| v as f32), &mut p32);
        assert!(norm.is_finite(), "{v}");
        assert!(p32.iter().all(|p| !p.is_nan()), "{v}");
    }
    r32.phi(&[0.0, f32::NAN, 0.0], &z.map(|v| v as f32), &mut p32);
    assert!(p32[1..=N_KERNELS].iter().all(|p| p.is_nan()));
}

/// f32's far axis: an axis more than √80·δ = 4.472·0.5 from its nearest
/// level (here x̃₃ − 1 = 4.6: 4.6²/0.25 = 84.6 > 80) makes every kernel
/// smaller than e^−80 (the largest is e^−84.8 ≈ 1.5e-37), and every kernel
/// is taken as exactly 0, so Φ is the bias and z only and ‖Φ‖ = √(1 +
/// ‖z‖²); with a NaN coordinate too, the kernels are NaN. Just inside
/// (x̃₃ − 1 = 4.4: 77.4, still in the factorised range) the kernel nearest
/// x is e^−(0.1² + 0.2² + 4.4²)/0.25 = e^−77.64 ≈ 1.9e-34, nonzero, and
/// f64's to 1e-4: x̃₃ in f32 carries ≈ 3e-7 of rounding, which the
/// exponent's slope 2·4.4/0.25 = 35 turns into ≈ 1e-5 of the kernel.
#[test]
fn f32_rbf_far_axis_is_flushed() {
    let r64 = Rbf::paper();
    let r32 = r64.cast::<f32>().unwrap();
    let s = r64.scale();
    let z = [0.01, -0.2, 3.0, -40.0];
    let z32 = z.map(|v| v as f32);
    let mut p32 = [0.0f32; N_PHI];
    let mut p64 = [0.0f64; N_PHI];
    let at = |xt: [f64; 3]| [xt[0] * s[0], xt[1] * s[1], xt[2] * s[2]];
    // Flushed.
    let far = at([0.1, -0.2, 5.6]).map(|v| v as f32);
    let norm = r32.phi(&far, &z32, &mut p32);
    assert!(p32[1..=N_KERNELS].iter().all(|&p| p == 0.0));
    let expect = (1.0 + z.iter().map(|v| v * v).sum::<f64>()).sqrt();
    assert!((f64::from(norm) - expect).abs() <= 1e-6 * expect);
    r32.phi(&[far[0], f32::NAN, far[2]], &z32, &mut p32);
    assert!(p32[1..=N_KERNELS].iter().all(|p| p.is_nan()));
    // Kept: the kernel at the centre nearest x (levels 0, 0, 1: index
    // 25·2 + 5·2 + 4 = 64, the first Φ entry being the bias).
    let x = at([0.1, -0.2, 5.4]);
    r32.phi(&x.map(|v| v as f32), &z32, &mut p32);
    r64.phi_direct(&x, &z, &mut p64);
    let by_hand = (-(0.01 + 0.04 + 4.4f64 * 4.4) / 0.25).exp();
    assert!(
        (p64[1 + 64] / by_hand - 1.0).abs() < 1e-9,
        "{}",
        p64[1 + 64]
    );
    assert!(p32[1 + 64] > 0.0);
    let rel = (f64::from(p32[1 + 64]) / p64[1 + 64] - 1.0).abs();
    assert!(rel < 1e-4, "{rel:e}");
}

/// The weights over the Fig. 2 run at 10 kHz (10⁵ steps, 130 weights):
/// how many forward-Euler updates left a weight unchanged (an increment
/// below half an ulp of w, or the dead zone's exact zero), and ‖W(10 s)‖
/// in f32 against f64. Printed for docs/float-types.md. Asserted, as a
/// guard against a loss of accuracy in f32's update (both runs are
/// deterministic; measured: 9e-7 and 2 % more): ‖W‖ within 1e-5
/// relative, and f32 losing at most 5 % more updates than f64.
#[test]
fn f32_weights_track_f64() {
    fn run<T: Real>() -> (u64, f64) {
        let mut lp = Fig2Loop::<T>::paper(10_000).unwrap();
        let mut unchanged = 0;
        for _ in 0..100_000 {
            let before = lp.controller().state().w;
            lp.step();
            let after = &lp.controller().state().w;
            unchanged += before.iter().zip(after).filter(|(a, b)| a == b).count() as u64;
        }
        let w = &lp.controller().state().w;
        (
            unchanged,
            w.iter()
                .map(|v| v.to_f64() * v.to_f64())
                .sum::<f64>()
                .sqrt(),
        )
    }
    let (u32_, n32) = run::<f32>();
    let (u64_, n64) = run::<f64>();
    println!(
        "Fig. 2, 10 kHz: unchanged weight updates f32 {u32_}, f64 {u64_} of {}; ‖W(10 s)‖ f32 {n32:.5}, f64 {n64:.5}",
        100_000u64 * N_PHI as u64
    );
    assert!((n32 / n64 - 1.0).abs() < 1e-5, "{n32} vs {n64}");
    assert!((u32_ as f64) < 1.05 * u64_ as f64, "{u32_} vs {u64_}");
}

/// f32's direct exponentials for one axis (`Real::RBF_AXIS_FALLBACK`), on
/// a grid spaced wider than δ (levels 0.5 apart, δ = 0.4), where q =
/// exp(2Δd/δ²) leaves the factorised range (|6.25·d| > 20, d > 3.2) before
/// the kernels become negligible (d²/δ² > 80, d > 3.58): with x̃₃ − 1 =
/// 3.4 that axis takes its five direct exponentials and the others their
/// factorised ones. Every kernel then agrees with f64's direct Φ to 1e-4
/// relative (x̃₃'s f32 rounding times the exponent's slope 2·3.4/0.16 =
/// 42.5: ≈ 1.3e-5), and the largest is the hand value
/// e^−(0.1² + 0.2² + 3.4²)/0.16 = e^−72.56.
#[test]
fn f32_rbf_direct_axis_on_a_wide_grid() {
    let r64 = Rbf::try_new([-1.0, -0.5, 0.0, 0.5, 1.0], 0.4, Rbf::paper_scale()).unwrap();
    let r32 = r64.cast::<f32>().unwrap();
    let s = r64.scale();
    let z = [0.01, -0.2, 3.0, -40.0];
    let (mut p32, mut p64) = ([0.0f32; N_PHI], [0.0f64; N_PHI]);
    let x = [0.1 * s[0], -0.2 * s[1], 4.4 * s[2]];
    r32.phi(&x.map(|v| v as f32), &z.map(|v| v as f32), &mut p32);
    r64.phi_direct(&x, &z, &mut p64);
    let by_hand = (-(0.01 + 0.04 + 3.4f64 * 3.4) / 0.16).exp();
    assert!((p64[1 + 64] / by_hand - 1.0).abs() < 1e-9);
    let mut n = 0;
    for (a, b) in p64[1..=N_KERNELS].iter().zip(&p32[1..=N_KERNELS]) {
        // (kernels below f32's normal range are not compared)
        if a.abs() > 1e-36 {
            let rel = (f64::from(*b) / a - 1.0).abs();
            assert!(rel < 1e-4, "{a:e} vs {b:e}: {rel:e}");
            n += 1;
        }
    }
    assert!(n >= 5, "{n} kernels compared");
}
