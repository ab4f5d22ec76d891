//! Dormand–Prince 5(4): seven stages, the fifth-order solution propagated
//! (local extrapolation), the embedded fourth-order one for the error.
//!
//! Coefficients from J. R. Dormand and P. J. Prince, "A family of embedded
//! Runge–Kutta formulae", J. Comput. Appl. Math. 6(1):19–26, 1980, as
//! tabulated in Hairer, Nørsett & Wanner, *Solving Ordinary Differential
//! Equations I*, 2nd ed., Springer 1993, §II.5, Table 5.2 (p. 178). The
//! error weights `e` are `b − b̂` of that table (b̂ the 4th-order row).
//! The last stage is evaluated at the new solution (first same as last);
//! the integrator here evaluates it afresh each step (see
//! [`super::Tableau`]).

use super::Tableau;

/// The Dormand–Prince 5(4) pair.
pub const DOPRI5: Tableau = Tableau {
    name: "dopri5",
    c: &[0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0],
    a: &[
        &[],
        &[1.0 / 5.0],
        &[3.0 / 40.0, 9.0 / 40.0],
        &[44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0],
        &[
            19372.0 / 6561.0,
            -25360.0 / 2187.0,
            64448.0 / 6561.0,
            -212.0 / 729.0,
        ],
        &[
            9017.0 / 3168.0,
            -355.0 / 33.0,
            46732.0 / 5247.0,
            49.0 / 176.0,
            -5103.0 / 18656.0,
        ],
        &[
            35.0 / 384.0,
            0.0,
            500.0 / 1113.0,
            125.0 / 192.0,
            -2187.0 / 6784.0,
            11.0 / 84.0,
        ],
    ],
    b: &[
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
        0.0,
    ],
    // b − b̂, b̂ = (5179/57600, 0, 7571/16695, 393/640, −92097/339200,
    // 187/2100, 1/40).
    e: &[
        71.0 / 57600.0,
        0.0,
        -71.0 / 16695.0,
        71.0 / 1920.0,
        -17253.0 / 339200.0,
        22.0 / 525.0,
        -1.0 / 40.0,
    ],
    order: 5,
    error_order: 4,
    // Hairer & Wanner's DOPRI5 code: β = 0.04 (Solving ODEs I, §II.4,
    // "Automatic step size control", and the code's default BETA).
    beta: 0.04,
};
