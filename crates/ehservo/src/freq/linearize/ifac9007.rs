//! IFAC benchmark 9007's Jacobian (`[plant] model = "ifac9007"`): the
//! plant is linear, so its Jacobian is the source's matrices themselves
//! (JuDO-dev/ControlBenchmarks.jl f11f4a98,
//! `src/benchmarks/ifac/prob9007-hydraulicPositioningSystem.jl` lines
//! 79–92), with the input column's sign turned (the plant's command is
//! u = −u_b, `ehservo_sim::ifac9007`) and 0 beyond the input bound ±866
//! (saturated; the bound itself is a kink).
//!
//! ```text
//! A = [0  1                 0            ]     B = [0      ]
//!     [0  −(R + 4Rc/π)/m    A/m          ]         [0      ]
//!     [0  −(4B/V)·A         −(4B/V)(σ+KL)]         [4B/V   ]   (|u| < 866)
//! C = [1 0 0]
//! ```

use super::{Jacobian, Kink, Linearize, PlantState, Point, Side, AT_KINK};
use crate::freq::ss::Quantity;
use crate::plant::Plant;
use crate::simulation::Sample;
use ehservo_sim::ifac9007::{Ifac9007Plant, Ifac9007Variation, INPUT_LIMIT};
use ehservo_sim::uncertainty::Factors;

/// The plant as linearised: its parameters already varied (the operating
/// point's bias folded in by [`Ifac9007Plant::with_factors`]).
const ONE: Ifac9007Variation = Ifac9007Variation { f: Factors::ONE };

/// Whether `u` is beyond the bound on `side` (at the bound, the side
/// decides: from below it still acts, from above it is saturated).
fn saturated(u: f64, side: Side) -> bool {
    let over = u.abs() - INPUT_LIMIT;
    if over.abs() <= AT_KINK * INPUT_LIMIT {
        // At +866 the side above is saturated; at −866 the side below.
        (u > 0.0) == (side == Side::Plus)
    } else {
        over > 0.0
    }
}

impl Linearize for Ifac9007Plant {
    fn states(&self) -> Vec<Quantity> {
        vec![
            Quantity::new("y", "L"),
            Quantity::new("y_dot", "L/s"),
            Quantity::new("p", "benchmark pressure unit"),
        ]
    }
    fn input(&self) -> Quantity {
        Quantity::new("u_plant", "−u of the benchmark")
    }
    fn output(&self) -> Quantity {
        Quantity::new("y", "L")
    }
    fn scales(&self) -> Vec<f64> {
        vec![0.1, 1.0, 10.0]
    }
    fn eval(&self, p: &Point, dx: &mut [f64]) -> f64 {
        let s = [p.x[0], p.x[1], p.x[2]];
        let mut d = [0.0; 3];
        self.deriv(0.0, &s, p.u, &ONE, &mut d);
        dx.copy_from_slice(&d);
        s[0]
    }
    fn jacobian(&self, p: &Point, side: Side) -> Jacobian {
        let q = &self.params;
        let k = 4.0 * q.b / q.v;
        let mut j = Jacobian::zeros(3);
        j.a[(0, 1)] = 1.0;
        j.a[(1, 1)] = -q.damping() / q.m;
        j.a[(1, 2)] = q.a / q.m;
        j.a[(2, 1)] = -k * q.a;
        j.a[(2, 2)] = -k * (q.sigma + q.kl);
        j.b[(2, 0)] = if saturated(p.u, side) { 0.0 } else { k };
        j.c[(0, 0)] = 1.0;
        j
    }
    fn kinks(&self, p: &Point) -> Vec<Kink> {
        if (p.u.abs() - INPUT_LIMIT).abs() <= AT_KINK * INPUT_LIMIT {
            vec![Kink {
                what: format!(
                    "the input bound |u| = {INPUT_LIMIT} (u_plant = {:.6}): the plant's input gain is 4B/V inside and 0 beyond",
                    p.u
                ),
                quantity: "u_plant".into(),
            }]
        } else {
            Vec::new()
        }
    }
    fn notes(&self, p: &Point) -> Vec<String> {
        if p.u.abs() > INPUT_LIMIT * (1.0 + AT_KINK) {
            vec![format!(
                "the input is saturated (|u_plant| = {:.4} > {INPUT_LIMIT}): the plant's input gain is 0",
                p.u.abs()
            )]
        } else {
            Vec::new()
        }
    }
}

impl PlantState for Ifac9007Plant {
    /// `(y, ẏ, p)`, p from the logged acceleration:
    /// p = (m·ÿ + (R + 4Rc/π)·ẏ + FL)/A.
    fn state_of(&self, s: &Sample) -> Vec<f64> {
        self.initial_state(s.x, &ONE).to_vec()
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact zeros and ones of the matrices are the point
mod tests {
    use super::super::finite_difference;
    use super::*;
    use crate::plant::Variation;
    use ehservo_sim::ifac9007::Ifac9007Params;

    /// The source's matrices at the nominal point by hand (jl:30–38,
    /// jl:80–88): 4B/V = 4·14000/874 = 64.073227;
    /// A[2,2] = −(0.15 + 4·0.01/π)/0.1287 = −0.1627324/0.1287 = −1.264432;
    /// A[2,3] = 10.75/0.1287 = 83.527584;
    /// A[3,2] = −64.073227·10.75 = −688.787185;
    /// A[3,3] = −64.073227·(0.24 + 0.002) = −15.505721;
    /// B[3] = −4B/V = −64.073227 for the source's u_b, so +64.073227 for
    /// the plant's command u = −u_b.
    #[test]
    fn linearisation_is_the_source_matrices() {
        let p = Ifac9007Plant::new(Ifac9007Params::NOMINAL, 0.0);
        let x = [0.0; 3];
        let at = Point {
            x: &x,
            u: 0.0,
            v: Variation::NONE,
        };
        let j = p.jacobian(&at, Side::Plus);
        let want_a = [
            [0.0, 1.0, 0.0],
            [0.0, -1.264432, 83.527584],
            [0.0, -688.787185, -15.505721],
        ];
        for (r, row) in want_a.iter().enumerate() {
            for (c, w) in row.iter().enumerate() {
                let got = j.a[(r, c)];
                assert!((got - w).abs() < 1e-6, "A[{r},{c}] = {got}, want {w}");
            }
        }
        let source_b3 = -64.073227;
        assert!((j.b[(2, 0)] + source_b3).abs() < 1e-6, "{}", j.b[(2, 0)]);
        assert_eq!((j.b[(0, 0)], j.b[(1, 0)]), (0.0, 0.0));
        assert_eq!(j.c[(0, 0)], 1.0);
        // The simulator's own derivative agrees (central differences).
        let fd = finite_difference(&p, &at);
        for r in 0..3 {
            for c in 0..3 {
                let (a, f) = (j.a[(r, c)], fd.a[(r, c)]);
                assert!(
                    (a - f).abs() <= 1e-6 * (1.0 + a.abs()),
                    "[{r},{c}] {a} vs {f}"
                );
            }
        }
        assert!((fd.b[(2, 0)] - j.b[(2, 0)]).abs() < 1e-6);
    }

    /// Eigenvalues at the nominal point against the closed form: the
    /// characteristic polynomial is s·(s² + a3·s + a2) with
    /// a3 = 1.264432 + 15.505721 = 16.770153 and
    /// a2 = 64.073227·10.75²/0.1287 + 15.505721·1.264432 = 57552.335, so
    /// λ = 0 and −a3/2 ± j·√(a2 − a3²/4) = −8.385076 ± j·√(57552.335 −
    /// 70.3094) = −8.385076 ± j·239.754094.
    #[test]
    fn eigenvalues_are_the_closed_form() {
        let p = Ifac9007Plant::new(Ifac9007Params::NOMINAL, 0.0);
        let x = [0.0; 3];
        let at = Point {
            x: &x,
            u: 0.0,
            v: Variation::NONE,
        };
        let a = p.jacobian(&at, Side::Plus).a;
        let mut ev: Vec<(f64, f64)> = a
            .complex_eigenvalues()
            .iter()
            .map(|z| (z.re, z.im))
            .collect();
        ev.sort_by(|x, y| x.1.total_cmp(&y.1));
        let want = [
            (-8.385076, -239.754094),
            (0.0, 0.0),
            (-8.385076, 239.754094),
        ];
        for (g, w) in ev.iter().zip(want) {
            assert!(
                (g.0 - w.0).abs() < 1e-5 && (g.1 - w.1).abs() < 1e-5,
                "{g:?} vs {w:?}"
            );
        }
    }

    /// Beyond ±866 the input acts no more: a note, and B = 0; at the
    /// bound, a kink with the two sides.
    #[test]
    fn the_input_bound_is_a_kink_and_beyond_it_a_note() {
        let p = Ifac9007Plant::new(Ifac9007Params::NOMINAL, 0.0);
        let x = [0.0; 3];
        let v = Variation::NONE;
        let beyond = Point { x: &x, u: 900.0, v };
        assert_eq!(p.jacobian(&beyond, Side::Plus).b[(2, 0)], 0.0);
        assert_eq!(p.notes(&beyond).len(), 1);
        let at = Point {
            x: &x,
            u: INPUT_LIMIT,
            v,
        };
        assert_eq!(p.kinks(&at).len(), 1);
        assert_eq!(p.jacobian(&at, Side::Plus).b[(2, 0)], 0.0);
        assert!(p.jacobian(&at, Side::Minus).b[(2, 0)] > 0.0);
        let low = Point {
            x: &x,
            u: -INPUT_LIMIT,
            v,
        };
        assert_eq!(p.jacobian(&low, Side::Minus).b[(2, 0)], 0.0);
        assert!(p.jacobian(&low, Side::Plus).b[(2, 0)] > 0.0);
    }
}
