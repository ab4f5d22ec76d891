//! TEMPORARY stand-in for `ehservo_core::onboard::Fig2Loop<T>` (the core is
//! being made generic over f32/f64; `onboard` lands with it). Same API, so
//! the swap is one line in main.rs. Scaffolding only:
//!
//! - the controller is today's f64 `SampledController<NnVsc>`: in the `f32`
//!   build only the plant and the loop's bookkeeping are f32, the law itself
//!   still runs in (software-emulated) f64;
//! - the plant is the nominal third-order model (8) with constant
//!   b = b(Pl = 0) ≈ 17 912 and the nominal load term d, not the paper's
//!   Fig. 2 uncertainty.
//!
//! Its numbers (trajectory, e_max, instructions per step) are therefore
//! provisional. Delete this file when `ehservo_core::onboard` exists.

use core::fmt::Debug;
use core::ops::{Add, Div, Mul, Neg, Sub};

use ehservo_core::prelude::*;

mod sealed {
    pub trait Sealed {}
    impl Sealed for f32 {}
    impl Sealed for f64 {}
}

/// The float types the loop runs in (f32, f64), as the core's `Real` will be.
pub trait Real:
    sealed::Sealed
    + Copy
    + PartialOrd
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// Rounds an f64 to this type.
    fn from_f64(v: f64) -> Self;
    /// Widens to f64.
    fn to_f64(self) -> f64;
    /// |v|.
    fn abs(self) -> Self;
}

impl Real for f32 {
    #[inline]
    fn from_f64(v: f64) -> Self {
        v as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self as f64
    }
    #[inline]
    fn abs(self) -> Self {
        if self < 0.0 {
            -self
        } else {
            self
        }
    }
}

impl Real for f64 {
    #[inline]
    fn from_f64(v: f64) -> Self {
        v
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline]
    fn abs(self) -> Self {
        if self < 0.0 {
            -self
        } else {
            self
        }
    }
}

/// The Fig. 2 loop closed on a board (stand-in; see the module doc).
pub struct Fig2Loop<T> {
    ctl: SampledController<NnVsc>,
    model: NominalModel,
    reference: Sine,
    rate_hz: u32,
    dt: T,
    a: [T; 3],
    b: T,
    k: u32,
    x: [T; 3],
    e: T,
    e_max: T,
}

impl<T: Real> Fig2Loop<T> {
    /// The loop at `rate_hz`, from rest (x = 0).
    pub fn paper(rate_hz: u32) -> Result<Self, ParamError> {
        if rate_hz == 0 {
            return Err(ParamError::new("rate_hz", "must be > 0", 0.0));
        }
        let model = NominalModel::try_new(ServoParams::paper(), Load::paper())?;
        let nn = NnVsc::try_new(
            model,
            SwitchingSurface::paper(),
            NnVscParams::paper(),
            Rbf::paper(),
        )?;
        let dt = 1.0 / rate_hz as f64;
        let ctl = SampledController::new(nn, dt)?;
        let c = model.coeffs;
        let reference = Sine::paper();
        let x = [T::from_f64(0.0); 3];
        let e = T::from_f64(reference.z(0.0)[0]) - x[0];
        Ok(Self {
            ctl,
            model,
            reference,
            rate_hz,
            dt: T::from_f64(dt),
            a: [c.a1, c.a2, c.a3].map(T::from_f64),
            b: T::from_f64(model.b_at_rest()),
            k: 0,
            x,
            e,
            e_max: T::from_f64(0.0),
        })
    }

    /// One controller step at the current sample; returns u (V).
    #[inline]
    pub fn control(&mut self) -> T {
        let t = self.t64();
        let x = self.x.map(T::to_f64);
        let out = self.ctl.step(t, x, self.reference.z(t));
        T::from_f64(out.u)
    }

    /// Integrates the plant over one period holding `u` (RK4 in T); k += 1.
    pub fn advance(&mut self, u: T) {
        let h = self.dt;
        let half = T::from_f64(0.5);
        let x = self.x;
        let k1 = self.f(&x, u);
        let k2 = self.f(&add(&x, half * h, &k1), u);
        let k3 = self.f(&add(&x, half * h, &k2), u);
        let k4 = self.f(&add(&x, h, &k3), u);
        let two = T::from_f64(2.0);
        let sixth = h / T::from_f64(6.0);
        for i in 0..3 {
            self.x[i] = x[i] + sixth * (k1[i] + two * k2[i] + two * k3[i] + k4[i]);
        }
        self.k += 1;
        self.e = T::from_f64(self.reference.z(self.t64())[0]) - self.x[0];
        if self.k >= 2 * self.rate_hz {
            let e_deg = T::from_f64(self.e.abs().to_f64().to_degrees());
            if e_deg > self.e_max {
                self.e_max = e_deg;
            }
        }
    }

    fn f(&self, x: &[T; 3], u: T) -> [T; 3] {
        let d = T::from_f64(self.model.d(&x.map(T::to_f64)));
        let [a1, a2, a3] = self.a;
        [
            x[1],
            x[2],
            -a1 * x[0] - a2 * x[1] - a3 * x[2] + self.b * u - d,
        ]
    }

    fn t64(&self) -> f64 {
        self.k as f64 / self.rate_hz as f64
    }

    /// Samples taken so far.
    pub fn k(&self) -> u32 {
        self.k
    }
    /// Time of the current sample (s).
    pub fn t(&self) -> T {
        T::from_f64(self.t64())
    }
    /// The plant state (θ, θ̇, θ̈).
    pub fn x(&self) -> [T; 3] {
        self.x
    }
    /// e = θd − θ at the current sample (rad).
    pub fn e(&self) -> T {
        self.e
    }
    /// max |e| in degrees over t ≥ 2 s so far.
    pub fn e_max_deg(&self) -> T {
        self.e_max
    }
}

fn add<T: Real>(x: &[T; 3], a: T, d: &[T; 3]) -> [T; 3] {
    [x[0] + a * d[0], x[1] + a * d[1], x[2] + a * d[2]]
}
