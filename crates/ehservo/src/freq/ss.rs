//! Linear time-invariant models in state-space form, `ẋ = A·x + B·u`,
//! `y = C·x + D·u` (continuous) or `x⁺ = A·x + B·u` (discrete, period
//! `dt`), with named states, inputs and outputs and their units; their
//! frequency responses, poles, zeros, DC gain and damping, the exact
//! zero-order-hold discretisation and the maps of the simulator's own
//! integrators.
//!
//! All the linear algebra is nalgebra's: the matrix exponential (Padé
//! scaling and squaring), LU solves (real and complex), the Schur form
//! for eigenvalues and the symmetric eigen-decomposition for a kernel. Every
//! matrix is checked finite first (nalgebra's iterations do not end on a
//! non-finite matrix) and every iteration is bounded.

use nalgebra::{Complex, DMatrix, DVector, Schur, SymmetricEigen};
use serde::Serialize;

/// A complex number.
pub type C64 = Complex<f64>;

/// Iterations allowed to the Schur and symmetric eigen iterations (they
/// need tens).
const MAX_ITER: usize = 10_000;

/// Sweeps allowed to the balancing (it needs a handful).
const MAX_BALANCE_SWEEPS: usize = 100;

/// A named quantity with its unit: a state, an input or an output.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Quantity {
    /// The name (`theta`, `p_load`, `u`).
    pub name: String,
    /// The unit (`rad`, `Pa`, `V`; empty when dimensionless).
    pub unit: String,
}

impl Quantity {
    /// A quantity `name` in `unit`.
    pub fn new(name: &str, unit: &str) -> Self {
        Self {
            name: name.into(),
            unit: unit.into(),
        }
    }
}

/// Why a model could not be formed or evaluated.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LinearError(pub String);

impl std::fmt::Display for LinearError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for LinearError {}

/// A state-space model.
#[derive(Debug, Clone, PartialEq)]
pub struct StateSpace {
    /// A (n × n).
    pub a: DMatrix<f64>,
    /// B (n × m).
    pub b: DMatrix<f64>,
    /// C (p × n).
    pub c: DMatrix<f64>,
    /// D (p × m).
    pub d: DMatrix<f64>,
    /// The sample period (s) of a discrete-time model; None: continuous.
    pub dt: Option<f64>,
    /// The n states.
    pub states: Vec<Quantity>,
    /// The m inputs.
    pub inputs: Vec<Quantity>,
    /// The p outputs.
    pub outputs: Vec<Quantity>,
}

/// Whether every entry is finite.
fn finite(m: &DMatrix<f64>) -> bool {
    m.iter().all(|v| v.is_finite())
}

/// Row-major rows of a matrix, for JSON.
fn rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect())
        .collect()
}

/// The eigenvalues of a square matrix (balanced first), or None when it is
/// not finite or the Schur iteration does not converge.
pub fn eigenvalues(m: &DMatrix<f64>) -> Option<Vec<C64>> {
    if m.nrows() == 0 {
        return Some(Vec::new());
    }
    if !finite(m) {
        return None;
    }
    let (mut ev, rest) = isolate(m);
    if rest.nrows() > 0 {
        let (bal, _) = balance(&rest);
        ev.extend(
            Schur::try_new(bal, f64::EPSILON, MAX_ITER)?
                .complex_eigenvalues()
                .iter()
                .copied(),
        );
    }
    let mut ev: Vec<C64> = ev
        .iter()
        .all(|z| z.re.is_finite() && z.im.is_finite())
        .then_some(ev)?;
    sort_roots(&mut ev);
    Some(ev)
}

/// The permutation step of LAPACK's balancing (`dgebal`, job 'P'): an
/// index whose row (or column) has no nonzero entry off the diagonal
/// within the indices left is an eigenvalue on its own, its diagonal
/// entry; taking it out may free others. Returns those eigenvalues and the
/// matrix of the indices left. A delay line (a nilpotent shift, on which
/// an unshifted QR iteration stalls) is taken out whole this way.
fn isolate(m: &DMatrix<f64>) -> (Vec<C64>, DMatrix<f64>) {
    let n = m.nrows();
    let mut left: Vec<usize> = (0..n).collect();
    let mut out = Vec::new();
    loop {
        let alone = left.iter().position(|&i| {
            left.iter().all(|&j| j == i || m[(i, j)] == 0.0)
                || left.iter().all(|&j| j == i || m[(j, i)] == 0.0)
        });
        match alone {
            Some(p) => {
                let i = left.remove(p);
                out.push(C64::new(m[(i, i)], 0.0));
            }
            None => break,
        }
    }
    let rest = DMatrix::from_fn(left.len(), left.len(), |a, b| m[(left[a], left[b])]);
    (out, rest)
}

/// Roots in a fixed order: by real part, then imaginary part (a conjugate
/// pair negative imaginary part first), so outputs do not depend on the
/// order the iteration found them in.
pub fn sort_roots(v: &mut [C64]) {
    v.sort_by(|a, b| a.re.total_cmp(&b.re).then(a.im.total_cmp(&b.im)));
}

/// Parlett–Reinsch balancing by powers of two (exact in floating point):
/// `B = D⁻¹·M·D` with row and column norms of each index made alike.
/// Returns `(B, diag D)`. Eigenvalues are unchanged; the exponential and
/// the eigenvalues of a badly scaled matrix (a state in Pa beside one in
/// rad) are computed far more accurately from `B`.
pub fn balance(m: &DMatrix<f64>) -> (DMatrix<f64>, DVector<f64>) {
    let n = m.nrows();
    let mut b = m.clone();
    let mut d = DVector::from_element(n, 1.0);
    if !finite(m) {
        return (b, d);
    }
    for _ in 0..MAX_BALANCE_SWEEPS {
        let mut done = true;
        for i in 0..n {
            let (mut c, mut r) = (0.0, 0.0);
            for j in 0..n {
                if j != i {
                    c += b[(j, i)].abs();
                    r += b[(i, j)].abs();
                }
            }
            if c == 0.0 || r == 0.0 {
                continue;
            }
            let s = c + r;
            let mut f = 1.0;
            let mut g = r / 2.0;
            while c < g && f < 1e150 {
                f *= 2.0;
                c *= 4.0;
            }
            g = r * 2.0;
            while c > g && f > 1e-150 {
                f /= 2.0;
                c /= 4.0;
            }
            if (c + r) / f < 0.95 * s {
                done = false;
                d[i] *= f;
                for j in 0..n {
                    b[(i, j)] /= f;
                    b[(j, i)] *= f;
                }
            }
        }
        if done {
            break;
        }
    }
    (b, d)
}

/// `exp(m)` through the balanced matrix; None when `m` is not finite or the
/// result overflows.
pub fn expm(m: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    if !finite(m) {
        return None;
    }
    let (b, d) = balance(m);
    let e = b.exp();
    let n = m.nrows();
    let out = DMatrix::from_fn(n, n, |i, j| d[i] * e[(i, j)] / d[j]);
    finite(&out).then_some(out)
}

/// One pole with its natural frequency and damping (for a discrete pole,
/// those of `s = ln(z)/dt`, as MATLAB's and python-control's `damp`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Mode {
    /// Real part.
    pub re: f64,
    /// Imaginary part.
    pub im: f64,
    /// |s| (rad/s); None for a discrete pole at z = 0.
    pub wn_rad_s: Option<f64>,
    /// −Re s/|s|; None at s = 0 or z = 0.
    pub zeta: Option<f64>,
}

/// The model as JSON: the matrices row by row, the names with units.
#[derive(Debug, Clone, Serialize)]
pub struct StateSpaceJson {
    /// The sample period (s); null for a continuous-time model.
    pub dt_s: Option<f64>,
    /// The states, in order.
    pub states: Vec<Quantity>,
    /// The inputs, in order.
    pub inputs: Vec<Quantity>,
    /// The outputs, in order.
    pub outputs: Vec<Quantity>,
    /// A, row by row.
    #[serde(rename = "A")]
    pub a: Vec<Vec<f64>>,
    /// B, row by row.
    #[serde(rename = "B")]
    pub b: Vec<Vec<f64>>,
    /// C, row by row.
    #[serde(rename = "C")]
    pub c: Vec<Vec<f64>>,
    /// D, row by row.
    #[serde(rename = "D")]
    pub d: Vec<Vec<f64>>,
}

impl StateSpace {
    /// A model from its matrices and names (the dimensions must agree).
    pub fn new(
        a: DMatrix<f64>,
        b: DMatrix<f64>,
        c: DMatrix<f64>,
        d: DMatrix<f64>,
        dt: Option<f64>,
        names: (Vec<Quantity>, Vec<Quantity>, Vec<Quantity>),
    ) -> Self {
        let (states, inputs, outputs) = names;
        let (n, m, p) = (states.len(), inputs.len(), outputs.len());
        assert_eq!(a.shape(), (n, n), "A is n × n");
        assert_eq!(b.shape(), (n, m), "B is n × m");
        assert_eq!(c.shape(), (p, n), "C is p × n");
        assert_eq!(d.shape(), (p, m), "D is p × m");
        Self {
            a,
            b,
            c,
            d,
            dt,
            states,
            inputs,
            outputs,
        }
    }

    /// A static gain `y = D·u` (no state).
    pub fn gain(
        d: DMatrix<f64>,
        dt: Option<f64>,
        inputs: Vec<Quantity>,
        outputs: Vec<Quantity>,
    ) -> Self {
        let (p, m) = d.shape();
        Self::new(
            DMatrix::zeros(0, 0),
            DMatrix::zeros(0, m),
            DMatrix::zeros(p, 0),
            d,
            dt,
            (Vec::new(), inputs, outputs),
        )
    }

    /// The number of states.
    pub fn n(&self) -> usize {
        self.a.nrows()
    }

    /// Whether every entry is finite.
    pub fn is_finite(&self) -> bool {
        finite(&self.a) && finite(&self.b) && finite(&self.c) && finite(&self.d)
    }

    /// The model as JSON.
    pub fn to_json(&self) -> StateSpaceJson {
        StateSpaceJson {
            dt_s: self.dt,
            states: self.states.clone(),
            inputs: self.inputs.clone(),
            outputs: self.outputs.clone(),
            a: rows(&self.a),
            b: rows(&self.b),
            c: rows(&self.c),
            d: rows(&self.d),
        }
    }

    /// The sub-model from input `i` to output `o`.
    pub fn siso(&self, o: usize, i: usize) -> StateSpace {
        StateSpace::new(
            self.a.clone(),
            self.b.columns(i, 1).into_owned(),
            self.c.rows(o, 1).into_owned(),
            self.d.view((o, i), (1, 1)).into_owned(),
            self.dt,
            (
                self.states.clone(),
                vec![self.inputs[i].clone()],
                vec![self.outputs[o].clone()],
            ),
        )
    }

    /// The sub-model of inputs `first..first + count`, every output.
    pub fn inputs_from(&self, first: usize, count: usize) -> StateSpace {
        StateSpace::new(
            self.a.clone(),
            self.b.columns(first, count).into_owned(),
            self.c.clone(),
            self.d.columns(first, count).into_owned(),
            self.dt,
            (
                self.states.clone(),
                self.inputs[first..first + count].to_vec(),
                self.outputs.clone(),
            ),
        )
    }

    /// A continuous SISO model with its output's first two derivatives as
    /// outputs too, `(y, ẏ, ÿ) = (C, C·A, C·A²)·x`: what a sensor of the
    /// velocity and the acceleration reads. None unless the input reaches
    /// y no sooner than its third integral (`D = C·B = C·A·B = 0`), so
    /// that a held input has no part in the derivatives.
    pub fn with_derivatives(&self, names: Vec<Quantity>) -> Option<StateSpace> {
        let ca = &self.c * &self.a;
        let ca2 = &ca * &self.a;
        let zero = |m: &DMatrix<f64>| m.iter().all(|v| *v == 0.0);
        if self.dt.is_some()
            || self.outputs.len() != 1
            || self.inputs.len() != 1
            || !(zero(&self.d) && zero(&(&self.c * &self.b)) && zero(&(&ca * &self.b)))
        {
            return None;
        }
        let n = self.n();
        let mut c = DMatrix::zeros(3, n);
        c.row_mut(0).copy_from(&self.c.row(0));
        c.row_mut(1).copy_from(&ca.row(0));
        c.row_mut(2).copy_from(&ca2.row(0));
        Some(StateSpace::new(
            self.a.clone(),
            self.b.clone(),
            c,
            DMatrix::zeros(3, 1),
            None,
            (self.states.clone(), self.inputs.clone(), names),
        ))
    }

    /// The same model with its outputs scaled by `k` (and renamed).
    pub fn scaled_output(&self, k: f64, outputs: Vec<Quantity>) -> StateSpace {
        let mut s = self.clone();
        s.c *= k;
        s.d *= k;
        s.outputs = outputs;
        s
    }

    /// `then ∘ self`: the outputs of `self` feed the inputs of `then`
    /// (`x = (x_self, x_then)`).
    pub fn series(&self, then: &StateSpace) -> Result<StateSpace, LinearError> {
        if self.outputs.len() != then.inputs.len() {
            return Err(LinearError(format!(
                "series: {} outputs into {} inputs",
                self.outputs.len(),
                then.inputs.len()
            )));
        }
        if self.dt != then.dt {
            return Err(LinearError("series: different time bases".into()));
        }
        let (n1, n2) = (self.n(), then.n());
        let m = self.inputs.len();
        let p = then.outputs.len();
        let mut a = DMatrix::zeros(n1 + n2, n1 + n2);
        a.view_mut((0, 0), (n1, n1)).copy_from(&self.a);
        a.view_mut((n1, n1), (n2, n2)).copy_from(&then.a);
        a.view_mut((n1, 0), (n2, n1))
            .copy_from(&(&then.b * &self.c));
        let mut b = DMatrix::zeros(n1 + n2, m);
        b.view_mut((0, 0), (n1, m)).copy_from(&self.b);
        b.view_mut((n1, 0), (n2, m)).copy_from(&(&then.b * &self.d));
        let mut c = DMatrix::zeros(p, n1 + n2);
        c.view_mut((0, 0), (p, n1)).copy_from(&(&then.d * &self.c));
        c.view_mut((0, n1), (p, n2)).copy_from(&then.c);
        let d = &then.d * &self.d;
        let mut states = self.states.clone();
        states.extend(then.states.iter().cloned());
        Ok(StateSpace::new(
            a,
            b,
            c,
            d,
            self.dt,
            (states, self.inputs.clone(), then.outputs.clone()),
        ))
    }

    /// A delay of `n` samples of period `dt` on one signal: `y_k = u_{k−n}`,
    /// a shift register of `n` states (none: `y = u`).
    pub fn delay(n: usize, dt: f64, signal: &Quantity) -> StateSpace {
        let mut a = DMatrix::zeros(n, n);
        for i in 1..n {
            a[(i, i - 1)] = 1.0;
        }
        let mut b = DMatrix::zeros(n, 1);
        let mut c = DMatrix::zeros(1, n);
        let mut d = DMatrix::zeros(1, 1);
        if n == 0 {
            d[(0, 0)] = 1.0;
        } else {
            b[(0, 0)] = 1.0;
            c[(0, n - 1)] = 1.0;
        }
        let states = (1..=n)
            .map(|k| Quantity::new(&format!("{}_delayed_{k}", signal.name), &signal.unit))
            .collect();
        StateSpace::new(
            a,
            b,
            c,
            d,
            Some(dt),
            (states, vec![signal.clone()], vec![signal.clone()]),
        )
    }

    /// The exact discretisation under a zero-order hold of period `h`:
    /// `Φ = e^{A·h}`, `Γ = ∫₀ʰ e^{A·s} ds·B`, both read off the exponential
    /// of `[[A, B], [0, 0]]·h` (C. Van Loan, *Computing integrals involving
    /// the matrix exponential*, IEEE TAC 23(3), 1978).
    pub fn zoh(&self, h: f64) -> Result<StateSpace, LinearError> {
        self.check_continuous(h)?;
        let (n, m) = (self.n(), self.inputs.len());
        let mut big = DMatrix::zeros(n + m, n + m);
        big.view_mut((0, 0), (n, n)).copy_from(&(&self.a * h));
        big.view_mut((0, n), (n, m)).copy_from(&(&self.b * h));
        let e = expm(&big).ok_or_else(|| {
            LinearError("the matrix exponential of the plant is not finite".into())
        })?;
        let mut s = self.clone();
        s.a = e.view((0, 0), (n, n)).into_owned();
        s.b = e.view((0, n), (n, m)).into_owned();
        s.dt = Some(h);
        Ok(s)
    }

    /// The map the simulator's sampled mode applies to a linear plant over
    /// one sample of period `h` under a held input: `substeps` classical RK4
    /// steps of `h/substeps` (`ehservo_core::rk4`). For `ẋ = A·x + B·u` one
    /// step of `τ` is `x⁺ = R·x + Q·B·u` with `Z = A·τ`,
    /// `R = I + Z + Z²/2 + Z³/6 + Z⁴/24`, `Q = τ·(I + Z/2 + Z²/6 + Z³/24)`;
    /// `m` steps give `Φ = Rᵐ`, `Γ = (I + R + … + R^{m−1})·Q·B`.
    pub fn rk4_map(&self, h: f64, substeps: u32) -> Result<StateSpace, LinearError> {
        self.check_continuous(h)?;
        let m = substeps.max(1);
        let tau = h / f64::from(m);
        let n = self.n();
        let i = DMatrix::<f64>::identity(n, n);
        let z = &self.a * tau;
        let z2 = &z * &z;
        let z3 = &z2 * &z;
        let z4 = &z3 * &z;
        let r = &i + &z + &z2 / 2.0 + &z3 / 6.0 + &z4 / 24.0;
        let q = (&i + &z / 2.0 + &z2 / 6.0 + &z3 / 24.0) * tau;
        let mut phi = i.clone();
        let mut sum = DMatrix::zeros(n, n);
        for _ in 0..m {
            sum += &phi;
            phi = &r * &phi;
        }
        let mut s = self.clone();
        s.a = phi;
        s.b = sum * q * &self.b;
        s.dt = Some(h);
        if !s.is_finite() {
            return Err(LinearError("the RK4 map of the plant is not finite".into()));
        }
        Ok(s)
    }

    /// The forward-Euler map of period `h`: `(I + h·A, h·B, C, D)`, what
    /// the sampled loop does to a controller's state
    /// (`ehservo_core::sampled`).
    pub fn euler(&self, h: f64) -> Result<StateSpace, LinearError> {
        self.check_continuous(h)?;
        let n = self.n();
        let mut s = self.clone();
        s.a = DMatrix::identity(n, n) + &self.a * h;
        s.b = &self.b * h;
        s.dt = Some(h);
        Ok(s)
    }

    fn check_continuous(&self, h: f64) -> Result<(), LinearError> {
        if self.dt.is_some() {
            return Err(LinearError("already a discrete-time model".into()));
        }
        if !(h.is_finite() && h > 0.0) {
            return Err(LinearError(format!("the period must be > 0 (got {h:?})")));
        }
        if !self.is_finite() {
            return Err(LinearError("the model is not finite".into()));
        }
        Ok(())
    }

    /// The point of the complex plane frequency `w` (rad/s) maps to:
    /// `j·w`, or `e^{j·w·dt}` in discrete time.
    pub fn point(&self, w: f64) -> C64 {
        match self.dt {
            None => C64::new(0.0, w),
            Some(h) => C64::from_polar(1.0, w * h),
        }
    }

    /// `C·(p·I − A)⁻¹·B + D` at the complex point `p`; None when `p` is a
    /// pole (the LU solve fails).
    pub fn at(&self, p: C64) -> Option<DMatrix<C64>> {
        let n = self.n();
        let dc = self.d.map(|v| C64::new(v, 0.0));
        if n == 0 {
            return Some(dc);
        }
        let m = DMatrix::from_fn(n, n, |i, j| {
            let diag = if i == j { p } else { C64::new(0.0, 0.0) };
            diag - self.a[(i, j)]
        });
        let b = self.b.map(|v| C64::new(v, 0.0));
        let x = m.lu().solve(&b)?;
        let y = self.c.map(|v| C64::new(v, 0.0)) * x + dc;
        y.iter()
            .all(|z| z.re.is_finite() && z.im.is_finite())
            .then_some(y)
    }

    /// The SISO response (output 0, input 0) at frequency `w` (rad/s).
    ///
    /// Up to [`STACK_STATES`] states it is solved on the stack
    /// ([`siso_at`]): the margins evaluate L at thousands of points per
    /// candidate of a tune, where the heap's matrices cost more than the
    /// solve.
    pub fn response(&self, w: f64) -> Option<C64> {
        let n = self.n();
        if n > STACK_STATES || self.inputs.is_empty() || self.outputs.is_empty() {
            return self.at(self.point(w)).map(|m| m[(0, 0)]);
        }
        let p = self.point(w);
        // The smallest stack array that holds the model: zeroing a larger
        // one would cost more than the solve.
        match n {
            0..=6 => siso_at::<6, 7>(self, p),
            7..=12 => siso_at::<12, 13>(self, p),
            _ => siso_at::<STACK_STATES, { STACK_STATES + 1 }>(self, p),
        }
    }

    /// The poles (eigenvalues of A), sorted.
    pub fn poles(&self) -> Option<Vec<C64>> {
        eigenvalues(&self.a)
    }

    /// The poles with their natural frequencies and damping.
    pub fn damping(&self) -> Option<Vec<Mode>> {
        let poles = self.poles()?;
        Some(
            poles
                .iter()
                .map(|&p| {
                    let s = match self.dt {
                        None => Some(p),
                        Some(h) if p.norm() > 0.0 => Some(p.ln() / h),
                        Some(_) => None,
                    };
                    let (wn, zeta) = match s {
                        Some(s) if s.norm() > 0.0 => (Some(s.norm()), Some(-s.re / s.norm())),
                        Some(_) => (Some(0.0), None),
                        None => (None, None),
                    };
                    Mode {
                        re: p.re,
                        im: p.im,
                        wn_rad_s: wn,
                        zeta,
                    }
                })
                .collect(),
        )
    }

    /// The SISO DC gain (output 0, input 0): `D − C·A⁻¹·B`, or in discrete
    /// time `D + C·(I − A)⁻¹·B`; None with a pole at s = 0 (z = 1), an
    /// integrator.
    pub fn dc_gain(&self) -> Option<f64> {
        let p = match self.dt {
            None => C64::new(0.0, 0.0),
            Some(_) => C64::new(1.0, 0.0),
        };
        let g = self.at(p)?[(0, 0)];
        // A pole exactly there makes the LU fail; one within round-off of
        // it gives a gain beyond any the model's scales allow.
        (g.re.abs() < 1e300).then_some(g.re)
    }

    /// The transmission zeros of the SISO model (output 0, input 0), sorted:
    /// with `D ≠ 0` the eigenvalues of `A − B·C/D`; with `D = 0` and relative
    /// degree r (the first k with `C·A^{k−1}·B ≠ 0`), the eigenvalues of
    /// `F = A − B·(C·A^{r−1}·B)⁻¹·C·A^r` restricted to the kernel of
    /// `[C; C·A; …; C·A^{r−1}]`, which F leaves invariant (the zero
    /// dynamics of input–output linearisation). Computed on the balanced
    /// model. None when the eigenvalue iteration fails.
    pub fn zeros(&self) -> Option<Vec<C64>> {
        let n = self.n();
        if n == 0 {
            return Some(Vec::new());
        }
        let (a, dg) = balance(&self.a);
        let b = DMatrix::from_fn(n, 1, |i, _| self.b[(i, 0)] / dg[i]);
        let c = DMatrix::from_fn(1, n, |_, j| self.c[(0, j)] * dg[j]);
        let d = self.d[(0, 0)];
        let scale = a.norm().max(f64::MIN_POSITIVE);
        if d.abs() > 1e-14 * (c.norm() * b.norm() / scale) && d != 0.0 {
            let f = &a - &b * &c / d;
            return eigenvalues(&f);
        }
        // Relative degree: the first Markov parameter C·A^{k−1}·B that is
        // not round-off of the products' sizes.
        let mut row = c.clone();
        let mut obs: Vec<DMatrix<f64>> = Vec::new();
        let mut r = None;
        for k in 0..n {
            let markov = (&row * &b)[(0, 0)];
            obs.push(row.clone());
            if markov.abs() > 1e-10 * row.norm() * b.norm() {
                r = Some((k + 1, markov));
                break;
            }
            row = &row * &a;
        }
        let Some((r, markov)) = r else {
            return Some(Vec::new()); // the transfer function is zero
        };
        if r == n {
            return Some(Vec::new());
        }
        let car = &obs[r - 1] * &a; // C·A^r
        let f = &a - &b * &car / markov;
        // The kernel of O (rows normalised): eigenvectors of OᵀO for its
        // n − r smallest eigenvalues.
        let mut o = DMatrix::zeros(r, n);
        for (i, rw) in obs.iter().enumerate() {
            let nr = rw.norm().max(f64::MIN_POSITIVE);
            o.row_mut(i).copy_from(&(rw / nr));
        }
        let g = o.transpose() * &o;
        if !finite(&g) {
            return None;
        }
        let eig = SymmetricEigen::try_new(g, f64::EPSILON, MAX_ITER)?;
        let mut idx: Vec<usize> = (0..n).collect();
        idx.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
        let basis = DMatrix::from_fn(n, n - r, |i, j| eig.eigenvectors[(i, idx[j])]);
        let restricted = basis.transpose() * f * &basis;
        eigenvalues(&restricted)
    }
}

/// A complex number as `[re, im]`, for JSON.
pub fn pair(z: C64) -> [f64; 2] {
    [z.re, z.im]
}

#[cfg(test)]
#[path = "ss_tests.rs"]
mod tests;

/// The most states [`StateSpace::response`] solves on the stack.
pub const STACK_STATES: usize = 24;

/// `c·(p·I − A)⁻¹·b + d` of output 0 and input 0 at the complex point `p`,
/// by Gaussian elimination with partial pivoting (the pivot of largest
/// |re| + |im|, as nalgebra's LU picks it) on the augmented `[pI − A | b]`
/// in a stack array; None when a pivot vanishes (p is a pole) or the value
/// is not finite. Needs `n ≤ N` and `W = N + 1`.
fn siso_at<const N: usize, const W: usize>(m: &StateSpace, p: C64) -> Option<C64> {
    let n = m.n();
    let d = m.d[(0, 0)];
    if n == 0 {
        return Some(C64::new(d, 0.0));
    }
    let zero = C64::new(0.0, 0.0);
    let mut g = [[zero; W]; N];
    for (i, row) in g.iter_mut().enumerate().take(n) {
        for (j, v) in row.iter_mut().enumerate().take(n) {
            *v = C64::new(-m.a[(i, j)], 0.0);
        }
        row[i] += p;
        row[n] = C64::new(m.b[(i, 0)], 0.0);
    }
    let norm1 = |z: C64| z.re.abs() + z.im.abs();
    for k in 0..n {
        let piv = (k..n).fold(k, |best, i| {
            if norm1(g[i][k]) > norm1(g[best][k]) {
                i
            } else {
                best
            }
        });
        if norm1(g[piv][k]) == 0.0 {
            return None;
        }
        g.swap(k, piv);
        let (top, below) = g.split_at_mut(k + 1);
        let row_k = &top[k];
        for row in below.iter_mut().take(n - k - 1) {
            let f = row[k] / row_k[k];
            if f != zero {
                for (v, &vk) in row[k + 1..=n].iter_mut().zip(&row_k[k + 1..=n]) {
                    *v -= f * vk;
                }
            }
        }
    }
    let mut x = [zero; N];
    for i in (0..n).rev() {
        let mut acc = g[i][n];
        for j in i + 1..n {
            acc -= g[i][j] * x[j];
        }
        x[i] = acc / g[i][i];
    }
    let y = (0..n).fold(C64::new(d, 0.0), |acc, j| acc + x[j] * m.c[(0, j)]);
    (y.re.is_finite() && y.im.is_finite()).then_some(y)
}
