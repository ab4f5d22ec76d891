//! Bogacki–Shampine 3(2): four stages, the third-order solution propagated,
//! the embedded second-order one for the error; cheap at loose tolerances.
//!
//! Coefficients from P. Bogacki and L. F. Shampine, "A 3(2) pair of
//! Runge–Kutta formulas", Appl. Math. Lett. 2(4):321–325, 1989 (the
//! pair of MATLAB's `ode23`). The error weights `e` are `b − b̂` with
//! b̂ = (7/24, 1/4, 1/3, 1/8).

use super::Tableau;

/// The Bogacki–Shampine 3(2) pair.
pub const BS32: Tableau = Tableau {
    name: "bs32",
    c: &[0.0, 1.0 / 2.0, 3.0 / 4.0, 1.0],
    a: &[
        &[],
        &[1.0 / 2.0],
        &[0.0, 3.0 / 4.0],
        &[2.0 / 9.0, 1.0 / 3.0, 4.0 / 9.0],
    ],
    b: &[2.0 / 9.0, 1.0 / 3.0, 4.0 / 9.0, 0.0],
    // 2/9 − 7/24 = −5/72, 1/3 − 1/4 = 1/12, 4/9 − 1/3 = 1/9, 0 − 1/8.
    e: &[-5.0 / 72.0, 1.0 / 12.0, 1.0 / 9.0, -1.0 / 8.0],
    order: 3,
    error_order: 2,
    // DOPRI5's β (Hairer's code: β ≤ 0.1 steadies the step size; 0.04 by
    // default), kept for this pair too.
    beta: 0.04,
};
