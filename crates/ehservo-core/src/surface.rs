//! The switching surface (10) and the error dynamics (15)–(16).
//!
//! ```text
//! σ(t) = ë + p1·ė + p2·e + p3·∫e,   e = θd − x1                  (10)
//! E = [∫e, e, ė]ᵀ,  Ė = P·E + Q·σ,
//! P = [[0, 1, 0], [0, 0, 1], [−p3, −p2, −p1]],  Q = [0, 0, 1]ᵀ   (15)–(16)
//! ```
//!
//! On σ = 0 the error obeys `s³ + p1·s² + p2·s + p3 = 0`; the paper's
//! p = (90, 2600, 24000) places its roots at −20, −30, −40.

use crate::error::ParamError;
use crate::math::Real;

/// The coefficients p1, p2, p3 of (10), checked to give a stable surface.
///
/// ```
/// use ehservo_core::surface::SwitchingSurface;
///
/// let s = SwitchingSurface::paper();
/// // σ by hand for x = (0.01, 0.2, 3), z = (0.02, 0.1, 1, 0), ∫e = 0.001:
/// // e = 0.01, ė = −0.1, ë = −2, so
/// // σ = −2 + 90·(−0.1) + 2600·0.01 + 24000·0.001 = −2 − 9 + 26 + 24 = 39.
/// let st = s.evaluate(&[0.01, 0.2, 3.0], &[0.02, 0.1, 1.0, 0.0], 0.001);
/// assert!((st.sigma - 39.0).abs() < 1e-12);
/// // ‖E‖ = ‖(∫e, e, ė)‖ = √(1e-6 + 1e-4 + 1e-2).
/// assert!((st.norm_e - (1e-6f64 + 1e-4 + 1e-2).sqrt()).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SwitchingSurface<T = f64> {
    p: [T; 3],
}

/// The surface and error quantities at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SurfaceState<T = f64> {
    /// e = θd − x1 (rad).
    pub e: T,
    /// ė = θ̇d − x2 (rad/s).
    pub e_dot: T,
    /// ë = θ̈d − x3 (rad/s²).
    pub e_ddot: T,
    /// ∫e (rad·s).
    pub int_e: T,
    /// σ of (10) (rad/s²).
    pub sigma: T,
    /// ‖E‖ = ‖[∫e, e, ė]‖.
    pub norm_e: T,
}

impl<T: Real> SurfaceState<T> {
    /// E = [∫e, e, ė] of (16).
    pub fn e_vec(&self) -> [T; 3] {
        [self.int_e, self.e, self.e_dot]
    }

    /// Ė = [e, ė, ë].
    pub fn e_vec_dot(&self) -> [T; 3] {
        [self.e, self.e_dot, self.e_ddot]
    }
}

impl<T: Real> SwitchingSurface<T> {
    /// From coefficients; rejects a surface whose error dynamics
    /// `s³ + p1 s² + p2 s + p3` are not Hurwitz (Routh: p1, p2, p3 > 0 and
    /// p1·p2 > p3).
    ///
    /// ```
    /// use ehservo_core::surface::SwitchingSurface;
    ///
    /// assert!(SwitchingSurface::try_new([90.0, 2600.0, 24000.0]).is_ok());
    /// // s³ + s² + s + 2: p1·p2 = 1 < p3 = 2, a root in the right half-plane.
    /// assert_eq!(SwitchingSurface::try_new([1.0, 1.0, 2.0]).unwrap_err().name, "p");
    /// ```
    pub fn try_new(p: [T; 3]) -> Result<Self, ParamError> {
        for (i, name) in ["p1", "p2", "p3"].iter().enumerate() {
            if !p[i].is_finite() || p[i] <= T::ZERO {
                return Err(ParamError::new(
                    name,
                    "must be finite and > 0 for a stable switching surface",
                    p[i].to_f64(),
                ));
            }
        }
        if p[0] * p[1] <= p[2] {
            return Err(ParamError::new(
                "p",
                "unstable switching surface: Routh–Hurwitz needs p1·p2 > p3",
                f64::NAN,
            ));
        }
        Ok(Self { p })
    }

    /// From three real poles, all strictly in the left half-plane:
    /// (s − r1)(s − r2)(s − r3) = s³ + p1 s² + p2 s + p3 with
    /// p1 = −(r1 + r2 + r3), p2 = r1r2 + r1r3 + r2r3, p3 = −r1r2r3.
    ///
    /// ```
    /// use ehservo_core::surface::SwitchingSurface;
    ///
    /// let s = SwitchingSurface::from_poles([-20.0, -30.0, -40.0])?;
    /// // (s + 20)(s + 30)(s + 40) expanded: 20 + 30 + 40 = 90,
    /// // 20·30 + 20·40 + 30·40 = 600 + 800 + 1200 = 2600, 20·30·40 = 24000.
    /// assert_eq!(s.p(), [90.0, 2600.0, 24000.0]);
    /// assert_eq!(s, SwitchingSurface::paper());
    /// // A pole in the right half-plane is refused, and named.
    /// let err = SwitchingSurface::from_poles([-20.0, 30.0, -40.0]).unwrap_err();
    /// assert_eq!((err.name, err.value), ("poles", 30.0));
    /// # Ok::<(), ehservo_core::error::ParamError>(())
    /// ```
    pub fn from_poles(poles: [T; 3]) -> Result<Self, ParamError> {
        for &r in &poles {
            if !r.is_finite() || r >= T::ZERO {
                return Err(ParamError::new(
                    "poles",
                    "every pole must be finite and < 0 (left half-plane)",
                    r.to_f64(),
                ));
            }
        }
        let [r1, r2, r3] = poles;
        Self::try_new([
            -(r1 + r2 + r3),
            r1 * r2 + r1 * r3 + r2 * r3,
            -(r1 * r2 * r3),
        ])
    }

    /// The same surface in another float type.
    pub fn cast<U: Real>(&self) -> SwitchingSurface<U> {
        SwitchingSurface {
            p: self.p.map(|v| U::of(v.to_f64())),
        }
    }

    /// [p1, p2, p3].
    pub fn p(&self) -> [T; 3] {
        self.p
    }

    /// The matrix P of (16), row-major.
    pub fn p_matrix(&self) -> [[T; 3]; 3] {
        let [p1, p2, p3] = self.p;
        let (o, l) = (T::ZERO, T::ONE);
        [[o, l, o], [o, o, l], [-p3, -p2, -p1]]
    }

    /// Errors, σ and ‖E‖ for state `x = (θ, θ̇, θ̈)`, reference `z` and the
    /// integral of the error `int_e`.
    #[inline]
    pub fn evaluate(&self, x: &[T; 3], z: &[T; 4], int_e: T) -> SurfaceState<T> {
        let e = z[0] - x[0];
        let e_dot = z[1] - x[1];
        let e_ddot = z[2] - x[2];
        let [p1, p2, p3] = self.p;
        SurfaceState {
            e,
            e_dot,
            e_ddot,
            int_e,
            sigma: e_ddot + p1 * e_dot + p2 * e + p3 * int_e,
            norm_e: crate::math::sqrt(int_e * int_e + e * e + e_dot * e_dot),
        }
    }

    /// The part of σ̇ the equivalent control must cancel, with the plant's
    /// nominal coefficients `a`:
    /// `N = θ⃛d + ā1x1 + ā2x2 + ā3x3 + p1(θ̈d − x3) + p2(θ̇d − x2) + p3(θd − x1)`,
    /// the numerator of (12) (with the printed p1[θ̇d − x3] read as
    /// p1[θ̈d − x3], SPEC §4).
    #[inline]
    pub fn equivalent_numerator(&self, a: &[T; 3], x: &[T; 3], z: &[T; 4]) -> T {
        let [p1, p2, p3] = self.p;
        z[3] + a[0] * x[0]
            + a[1] * x[1]
            + a[2] * x[2]
            + p1 * (z[2] - x[2])
            + p2 * (z[1] - x[1])
            + p3 * (z[0] - x[0])
    }
}

impl SwitchingSurface<f64> {
    /// The paper's surface, poles −20, −30, −40.
    pub fn paper() -> Self {
        Self {
            p: [90.0, 2600.0, 24000.0],
        }
    }
}

#[cfg(test)]
#[allow(clippy::float_cmp)] // exact values are the point of several checks
mod tests {
    use super::*;

    /// (s+20)(s+30)(s+40) = s³ + 90 s² + 2600 s + 24000:
    /// 20+30+40 = 90; 600+800+1200 = 2600; 20·30·40 = 24000.
    #[test]
    fn paper_poles_give_paper_coefficients() {
        let s = SwitchingSurface::from_poles([-20.0, -30.0, -40.0]).unwrap();
        assert_eq!(s.p(), [90.0, 2600.0, 24000.0]);
    }

    #[test]
    fn unstable_surfaces_are_rejected() {
        assert_eq!(
            SwitchingSurface::from_poles([-20.0, 30.0, -40.0])
                .unwrap_err()
                .name,
            "poles"
        );
        assert_eq!(
            SwitchingSurface::try_new([-1.0, 2.0, 3.0])
                .unwrap_err()
                .name,
            "p1"
        );
        // s³ + s² + s + 2: p1·p2 = 1 < 2, roots with positive real part.
        assert_eq!(
            SwitchingSurface::try_new([1.0, 1.0, 2.0]).unwrap_err().name,
            "p"
        );
    }

    /// σ by hand for x = (0.01, 0.2, 3), z = (0.02, 0.1, 1, 0), ∫e = 0.001:
    /// e = 0.01, ė = −0.1, ë = −2; σ = −2 + 90·(−0.1) + 2600·0.01 + 24000·0.001
    /// = −2 − 9 + 26 + 24 = 39; ‖E‖ = sqrt(1e-6 + 1e-4 + 1e-2) = 0.1005037.
    #[test]
    fn sigma_by_hand() {
        let s = SwitchingSurface::paper();
        let st = s.evaluate(&[0.01, 0.2, 3.0], &[0.02, 0.1, 1.0, 0.0], 0.001);
        assert!((st.sigma - 39.0).abs() < 1e-12);
        assert!((st.norm_e - 0.1005037).abs() < 1e-7);
    }
}
