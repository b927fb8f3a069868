//! Linearization about an equilibrium or a steady motion: `x' = A x` in a formulation's state
//! (without the work integral, which is bookkeeping), from the emitted exact Jacobian (finite
//! differences when the module has none), and its eigenvalues; and sweeps of one parameter or
//! one initial velocity, the way the bicycle benchmark plots its eigenvalues against speed.
//!
//! ```
//! use runtime::linearize::{Operating, linearize};
//! // The spring cart at rest: every eigenvalue has a negative real part (its damper) or none.
//! let model = generated::find("spring_cart").unwrap();
//! let m = model.coordinates.len();
//! let at = Operating { q: vec![0.0; m], qdot: vec![0.0; m], params: model.default_params.to_vec(), held: vec![] };
//! let lin = linearize(&model, seam::FormulationKind::Kane, &at).unwrap();
//! assert_eq!(lin.eigenvalues.len(), 4);
//! assert!(lin.eigenvalues.iter().all(|l| l.re < 1e-9));
//! ```

use crate::system::{SetupError, System};
use nalgebra::{Complex, DMatrix};
use seam::{Failure, FormulationKind, Model};

/// Where to linearize: coordinates, their rates and the parameters. When `held` names some
/// rates (indices into `qdot`) and the model has velocity constraints, the other rates are
/// solved from the constraints (`a q' + b = 0`, least squares), so that giving the forward
/// speed of a bicycle sets its wheels' rates.
#[derive(Clone, Debug, PartialEq)]
pub struct Operating {
    pub q: Vec<f64>,
    pub qdot: Vec<f64>,
    pub params: Vec<f64>,
    pub held: Vec<usize>,
}

impl Operating {
    /// The rates with the free ones solved from the constraints (see [`Operating`]).
    pub fn consistent_rates(&self, model: &Model) -> Result<Vec<f64>, LinearizeError> {
        let (m, r) = (model.coordinates.len(), model.constraints.len());
        if self.held.is_empty() || r == 0 {
            return Ok(self.qdot.clone());
        }
        let (a_all, b) = crate::system::constraint_matrix(model, 0.0, &self.q, &self.params).map_err(LinearizeError::Rhs)?;
        let free: Vec<usize> = (0..m).filter(|j| !self.held.contains(j)).collect();
        if free.is_empty() {
            // Every rate given: nothing to solve (the constraints check them where they are used).
            return Ok(self.qdot.clone());
        }
        let a = DMatrix::from_fn(r, free.len(), |i, k| a_all[(i, free[k])]);
        let rhs = nalgebra::DVector::from_iterator(r, (0..r).map(|i| -b[i] - self.held.iter().map(|&j| a_all[(i, j)] * self.qdot[j]).sum::<f64>()));
        let x = a.svd(true, true).solve(&rhs, 1e-12).map_err(|e| LinearizeError::Rates(e.to_string()))?;
        // Round-off of the solve (below 1e-13 of the rates given) is no motion: at rest the
        // rates come out exactly zero, as the constraints' own check expects.
        let scale = self.held.iter().fold(0.0f64, |m, &j| m.max(self.qdot[j].abs())).max(x.amax());
        let mut qd = self.qdot.clone();
        for (k, &j) in free.iter().enumerate() {
            qd[j] = if x[k].abs() <= 1e-13 * scale { 0.0 } else { x[k] };
        }
        Ok(qd)
    }
}

/// The linear model about an operating point.
#[derive(Clone, Debug)]
pub struct Linear {
    /// The state it is taken about (the formulation's, without `W`).
    pub state: Vec<f64>,
    /// The rates there: zero at an equilibrium, the steady motion's otherwise.
    pub rates: Vec<f64>,
    /// `A = d f / d state`.
    pub a: DMatrix<f64>,
    /// State entries nothing depends on (their column of `A` vanishes: positions, headings,
    /// wheel angles), each a zero eigenvalue, left out of `eigenvalues`.
    pub cyclic: Vec<usize>,
    /// Cyclic entries that move and on which `A` depends near the point: the linear model
    /// changes along the motion ([`Motion::Transient`]).
    pub drifting: Vec<usize>,
    /// The eigenvalues of `A` without the cyclic entries, sorted by real part, then imaginary
    /// part, descending.
    pub eigenvalues: Vec<Complex<f64>>,
    /// True when `A` came from the emitted Jacobian, false for finite differences.
    pub exact: bool,
}

/// Rates below this fraction of the largest rate (or of 1) are round-off: an entry whose rate is
/// this small does not move.
pub const STILL: f64 = 1e-9;

/// How the operating point moves, in the linearized state.
#[derive(Clone, Debug, PartialEq)]
pub enum Motion {
    /// Nothing moves: `x' = 0`.
    Equilibrium,
    /// A steady motion: only cyclic entries move (a spin about a symmetry axis, a rolling
    /// wheel's angle), which nothing depends on near the point either, so the linear model of
    /// the rest is that of the motion.
    Steady { moving: Vec<usize> },
    /// An entry the others depend on moves: `A` is the Jacobian of the flow at this instant
    /// only. Its eigenvalues are the rates at which neighbouring motions separate from this one
    /// now, not the stability of the motion (the largest such rate is `rate`, of entry `entry`).
    Transient { entry: usize, rate: f64 },
}

impl Linear {
    /// Whether the point is an equilibrium, a steady motion, or neither ([`Motion`]): rates
    /// below [`STILL`] of the largest (or of 1) count as none.
    ///
    /// ```
    /// use runtime::linearize::{Motion, Operating, linearize};
    /// let model = generated::cart_pendulum::model();
    /// let (q0, qd0) = model.initial.clone().unwrap();
    /// let at = Operating { q: q0, qdot: qd0, params: model.default_params.clone(), held: vec![] };
    /// // Scene 1's initial state swings: its linear model holds for an instant only.
    /// assert!(matches!(linearize(&model, seam::FormulationKind::Kane, &at).unwrap().motion(), Motion::Transient { .. }));
    /// ```
    pub fn motion(&self) -> Motion {
        let largest = self.rates.iter().fold(0.0f64, |m, r| m.max(r.abs()));
        let still = STILL * largest.max(1.0);
        let moving = |i: &usize| self.rates[*i].abs() > still;
        let kept: Vec<usize> = (0..self.rates.len()).filter(|i| !self.cyclic.contains(i)).collect();
        let changing = kept.iter().chain(&self.drifting).filter(|i| moving(i));
        if let Some(&entry) = changing.max_by(|a, b| self.rates[**a].abs().total_cmp(&self.rates[**b].abs())) {
            return Motion::Transient { entry, rate: self.rates[entry] };
        }
        let moving: Vec<usize> = self.cyclic.iter().copied().filter(|i| moving(i)).collect();
        if moving.is_empty() { Motion::Equilibrium } else { Motion::Steady { moving } }
    }
}

/// Why a linearization failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LinearizeError {
    #[error(transparent)]
    Setup(#[from] SetupError),
    #[error("the right-hand side failed at the operating point: {0}")]
    Rhs(Failure),
    #[error("the rates cannot be made consistent with the constraints: {0}")]
    Rates(String),
    #[error(
        "the eigenvalues of the {size} x {size} matrix A did not converge: the Schur decomposition took more than {sweeps} QR sweeps on each of {tries} shifted copies"
    )]
    Eigenvalues { size: usize, sweeps: usize, tries: usize },
    #[error("A has a non-finite entry at row {row}, column {column}: no eigenvalues")]
    NotFinite { row: usize, column: usize },
    #[error("`{name}` is neither a parameter nor a coordinate's rate `q'` of model `{model}` (parameters: {parameters}; coordinates: {coordinates})")]
    UnknownSweep { name: String, model: String, parameters: String, coordinates: String },
}

/// The linear model of formulation `formulation` of `model` at `at`.
pub fn linearize(model: &Model, formulation: FormulationKind, at: &Operating) -> Result<Linear, LinearizeError> {
    let qdot = at.consistent_rates(model)?;
    let (sys, y0) = System::start(model, formulation, at.params.clone(), &at.q, &qdot)?;
    let n = sys.form.states();
    // The work integral (last in the layout) is left out: nothing depends on it.
    let k = sys.form.layout.work_index().unwrap_or(n);
    let mut dy = vec![0.0; n];
    let mut flat = vec![0.0; n * n];
    let exact = sys.has_exact_jacobian();
    if exact {
        sys.jacobian(0.0, &y0, &mut dy, &mut flat).map_err(LinearizeError::Rhs)?;
    } else {
        sys.rhs(0.0, &y0, &mut dy).map_err(LinearizeError::Rhs)?;
        let columns = central_differences(&y0, k, n, |y, out| sys.rhs(0.0, y, out))?;
        for (c, col) in columns.iter().enumerate() {
            for r in 0..n {
                flat[r * n + c] = col[r];
            }
        }
    }
    let a = DMatrix::from_fn(k, k, |r, c| flat[r * n + c]);
    let tol = if exact { 1e-12 } else { 1e-8 };
    let (kept, cyclic) = cyclic_entries(&a, tol);
    let drifting = drifting_entries(&sys, &y0, &dy[..k], &a, &cyclic, tol)?;
    let reduced = DMatrix::from_fn(kept.len(), kept.len(), |r, c| a[(kept[r], kept[c])]);
    let mut eigenvalues = eigenvalues(&reduced)?;
    eigenvalues.sort_by(|x, y| y.re.total_cmp(&x.re).then(y.im.total_cmp(&x.im)));
    Ok(Linear { state: y0[..k].to_vec(), rates: dy[..k].to_vec(), a, cyclic, drifting, eigenvalues, exact })
}

/// The cyclic entries at `y0` that move there (their rate in `dy` above [`STILL`]) and whose
/// column of `A` is not zero at a state near `y0`: they are cyclic at the point only (a body's
/// rates in its own frame turn with a spin angle: `psi' = (sin phi u1 + cos phi u2) / cos
/// theta` has no `phi` column while `u1 = u2 = 0`), so along the motion `A` changes.
fn drifting_entries(sys: &System, y0: &[f64], dy: &[f64], a: &DMatrix<f64>, cyclic: &[usize], tol: f64) -> Result<Vec<usize>, LinearizeError> {
    let largest = dy.iter().fold(0.0f64, |m, r| m.max(r.abs()));
    let moving: Vec<usize> = cyclic.iter().copied().filter(|&i| dy[i].abs() > STILL * largest.max(1.0)).collect();
    if moving.is_empty() {
        return Ok(moving);
    }
    // A fixed, irregular move of every entry by a thousandth (of the entry, or of 1).
    let near: Vec<f64> = y0.iter().enumerate().map(|(i, y)| y + 1e-3 * (1.0 + y.abs()) * (0.3 + 0.7 * ((i as f64 * 0.618_034) % 1.0))).collect();
    let (_, flat, _) = state_jacobian(sys, 0.0, &near)?;
    let (n, k) = (near.len(), a.nrows());
    let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(f64::MIN_POSITIVE);
    Ok(moving.into_iter().filter(|&c| (0..k).any(|r| flat[r * n + c].abs() > tol.max(1e-9) * scale)).collect())
}

/// The QR sweeps the Schur decomposition may take before it is given up, per row of the
/// matrix (LAPACK's `dlahqr` allows 30 per eigenvalue, at least 10 eigenvalues' worth).
const SWEEPS_PER_ROW: usize = 30;

/// The shifts `c` (times the largest entry) tried in turn: the eigenvalues of `A + c I` are
/// those of `A` moved by `c`. nalgebra's Francis iteration has no exceptional shifts
/// (nalgebra issues #611 and #1528) and stalls on matrices whose eigenvalues share a modulus,
/// such as a spinning top's (`+-w` and `+-a +- w i`); moving them off a common modulus lets it
/// converge, at a cost of round-off relative to the largest entry, the backward error any
/// eigenvalue solver has anyway.
const SHIFTS: [f64; 4] = [0.0, 0.3, -0.55, 0.8];

/// The eigenvalues of a square matrix, by nalgebra's Schur decomposition with its iteration
/// bounded ([`SWEEPS_PER_ROW`]) and retried on shifted matrices ([`SHIFTS`]) where it does not
/// converge: a matrix whose iteration converges on none is reported
/// ([`LinearizeError::Eigenvalues`]), never waited on.
///
/// ```
/// use nalgebra::DMatrix;
/// let a = DMatrix::from_row_slice(3, 3, &[0.0, 1.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 2.0]);
/// let mut e = runtime::linearize::eigenvalues(&a).unwrap();
/// e.sort_by(|x, y| x.im.total_cmp(&y.im));
/// assert!((e[0].im + 1.0).abs() < 1e-14 && (e[1].re - 2.0).abs() < 1e-14 && (e[2].im - 1.0).abs() < 1e-14);
/// assert!(runtime::linearize::eigenvalues(&DMatrix::zeros(0, 0)).unwrap().is_empty());
/// ```
pub fn eigenvalues(a: &DMatrix<f64>) -> Result<Vec<Complex<f64>>, LinearizeError> {
    let n = a.nrows();
    assert_eq!(n, a.ncols(), "eigenvalues of a square matrix");
    if let Some(k) = a.iter().position(|x| !x.is_finite()) {
        return Err(LinearizeError::NotFinite { row: k % n.max(1), column: k / n.max(1) });
    }
    match n {
        0 => return Ok(Vec::new()),
        1 => return Ok(vec![Complex::new(a[(0, 0)], 0.0)]),
        _ => {}
    }
    eigenvalues_within(a, SWEEPS_PER_ROW * n.max(10))
}

/// [`eigenvalues`] with at most `sweeps` QR sweeps per try.
fn eigenvalues_within(a: &DMatrix<f64>, sweeps: usize) -> Result<Vec<Complex<f64>>, LinearizeError> {
    let n = a.nrows();
    let scale = a.amax();
    for shift in SHIFTS {
        let c = shift * scale;
        let moved = a + DMatrix::identity(n, n) * c;
        if let Some(schur) = nalgebra::Schur::try_new(moved, f64::EPSILON, sweeps) {
            return Ok(schur.complex_eigenvalues().iter().map(|z| Complex::new(z.re - c, z.im)).collect());
        }
    }
    Err(LinearizeError::Eigenvalues { size: n, sweeps, tries: SHIFTS.len() })
}

/// The input matrix `B = d f / d p` of the parameters `inputs` (indices into the parameters)
/// at `at`, in the state of [`linearize`] (without `W`): `x' = A x + B u` with `u` the inputs'
/// deviations. From the emitted `parameter_jacobian` when the module has one
/// (`generator --parameter-jacobian`), else central differences; the flag says which.
///
/// ```
/// use runtime::linearize::{Operating, input_matrix};
/// // Scene 1's motor torque tau drives the two bars' rates, nothing else.
/// let model = generated::find("cart_pendulum").unwrap();
/// let (q0, qd0) = model.initial.clone().unwrap();
/// let at = Operating { q: q0, qdot: qd0, params: model.default_params.clone(), held: vec![] };
/// let tau = model.parameter_index("tau").unwrap();
/// let (b, exact) = input_matrix(&model, seam::FormulationKind::Kane, &at, &[tau]).unwrap();
/// assert!(exact && b.column(0).iter().any(|x| x.abs() > 1e-3));
/// ```
pub fn input_matrix(model: &Model, formulation: FormulationKind, at: &Operating, inputs: &[usize]) -> Result<(DMatrix<f64>, bool), LinearizeError> {
    let qdot = at.consistent_rates(model)?;
    let (sys, y0) = System::start(model, formulation, at.params.clone(), &at.q, &qdot)?;
    let n = sys.form.states();
    let k = sys.form.layout.work_index().unwrap_or(n);
    let np = at.params.len();
    let mut b = DMatrix::zeros(k, inputs.len());
    let mut dy = vec![0.0; n];
    match sys.form.has_parameter_jacobian {
        true => {
            let mut flat = vec![0.0; n * np];
            sys.form.parameter_jacobian(0.0, &y0, &at.params, &sys.g_i, &mut dy, &mut flat).map_err(LinearizeError::Rhs)?;
            for (c, &p) in inputs.iter().enumerate() {
                for r in 0..k {
                    b[(r, c)] = flat[r * np + p];
                }
            }
            Ok((b, true))
        }
        false => {
            let chosen: Vec<f64> = inputs.iter().map(|&p| at.params[p]).collect();
            let columns = central_differences(&chosen, inputs.len(), n, |values, out| {
                let mut params = at.params.clone();
                for (&p, v) in inputs.iter().zip(values) {
                    params[p] = *v;
                }
                sys.form.rhs(0.0, &y0, &params, &sys.g_i, out)
            })?;
            for (c, col) in columns.iter().enumerate() {
                for r in 0..k {
                    b[(r, c)] = col[r];
                }
            }
            Ok((b, false))
        }
    }
}

/// `f(t, y)` and its Jacobian `d f / d y` (row-major, every state, the work integral's too),
/// exact when the system has the model's own (`has_exact_jacobian`), else by central
/// differences; the flag says which.
///
/// ```
/// use runtime::{linearize::state_jacobian, system::System};
/// let model = generated::cart_pendulum::model();
/// let (sys, y0) = System::start(&model, seam::FormulationKind::Kane, model.default_params.clone(), &[0.2, 0.1, 0.0], &[0.0; 3]).unwrap();
/// let (f, jac, exact) = state_jacobian(&sys, 0.0, &y0).unwrap();
/// let n = f.len();
/// assert_eq!((jac.len(), exact), (n * n, sys.has_exact_jacobian()));
/// ```
pub fn state_jacobian(sys: &System, t: f64, y: &[f64]) -> Result<(Vec<f64>, Vec<f64>, bool), LinearizeError> {
    let n = y.len();
    let (mut dy, mut flat) = (vec![0.0; n], vec![0.0; n * n]);
    let exact = sys.has_exact_jacobian();
    if exact {
        sys.jacobian(t, y, &mut dy, &mut flat).map_err(LinearizeError::Rhs)?;
    } else {
        sys.rhs(t, y, &mut dy).map_err(LinearizeError::Rhs)?;
        let columns = central_differences(y, n, n, |y, out| sys.rhs(t, y, out))?;
        for (c, col) in columns.iter().enumerate() {
            for r in 0..n {
                flat[r * n + c] = col[r];
            }
        }
    }
    Ok((dy, flat, exact))
}

/// `d f / d x_c` for the first `columns` entries of `x`, by central differences at the step
/// that balances truncation (`h^2`) against round-off (`eps / h`); `f` writes `n` values.
fn central_differences(
    x: &[f64],
    columns: usize,
    n: usize,
    mut f: impl FnMut(&[f64], &mut [f64]) -> Result<(), Failure>,
) -> Result<Vec<Vec<f64>>, LinearizeError> {
    let (mut up, mut down) = (vec![0.0; n], vec![0.0; n]);
    (0..columns)
        .map(|c| {
            let h = f64::EPSILON.cbrt() * (1.0 + x[c].abs());
            let mut moved = x.to_vec();
            moved[c] += h;
            f(&moved, &mut up).map_err(LinearizeError::Rhs)?;
            moved[c] -= 2.0 * h;
            f(&moved, &mut down).map_err(LinearizeError::Rhs)?;
            Ok(up.iter().zip(&down).map(|(a, b)| (a - b) / (2.0 * h)).collect())
        })
        .collect()
}

/// The entries whose column of `a` (among the rows still kept) is below `tol` times the
/// largest entry, removed until none is left: `(kept, cyclic)`. Removing such an entry leaves
/// the other eigenvalues as they are (the matrix is block triangular) and takes out one zero.
fn cyclic_entries(a: &DMatrix<f64>, tol: f64) -> (Vec<usize>, Vec<usize>) {
    let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(f64::MIN_POSITIVE);
    let mut kept: Vec<usize> = (0..a.nrows()).collect();
    while let Some(pos) = kept.iter().position(|&c| kept.iter().all(|&r| a[(r, c)].abs() <= tol * scale)) {
        kept.remove(pos);
    }
    let cyclic = (0..a.nrows()).filter(|i| !kept.contains(i)).collect();
    (kept, cyclic)
}

/// What a sweep varies: a parameter, or the initial rate of a coordinate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Swept {
    Parameter(usize),
    Rate(usize),
}

impl Swept {
    /// `name` as a parameter (`k`) or a coordinate's rate (`x'`).
    pub fn find(model: &Model, name: &str) -> Result<Swept, LinearizeError> {
        if let Some(i) = model.parameter_names.iter().position(|p| *p == name) {
            return Ok(Swept::Parameter(i));
        }
        if let Some(i) = name.strip_suffix('\'').and_then(|q| model.coordinates.iter().position(|c| *c == q)) {
            return Ok(Swept::Rate(i));
        }
        Err(LinearizeError::UnknownSweep {
            name: name.to_string(),
            model: model.module.to_string(),
            parameters: model.parameter_names.join(", "),
            coordinates: model.coordinates.join(", "),
        })
    }

    /// `at` with the swept value set to `v` (a swept rate is held).
    pub fn apply(self, at: &Operating, v: f64) -> Operating {
        let mut out = at.clone();
        match self {
            Swept::Parameter(i) => out.params[i] = v,
            Swept::Rate(i) => {
                out.qdot[i] = v;
                if !out.held.contains(&i) {
                    out.held.push(i);
                }
            }
        }
        out
    }
}

/// The eigenvalues at each value of a sweep.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SweepRow {
    pub value: f64,
    /// `(re, im)` pairs, as [`Linear::eigenvalues`].
    pub eigenvalues: Vec<(f64, f64)>,
    /// Neither an equilibrium nor a steady motion there ([`Motion::Transient`]): the
    /// eigenvalues hold for an instant only.
    pub transient: bool,
}

/// Linearizes at `at` with the swept value at each of `values`.
pub fn sweep(model: &Model, formulation: FormulationKind, at: &Operating, swept: Swept, values: &[f64]) -> Result<Vec<SweepRow>, LinearizeError> {
    values
        .iter()
        .map(|&v| {
            let lin = linearize(model, formulation, &swept.apply(at, v))?;
            let transient = matches!(lin.motion(), Motion::Transient { .. });
            Ok(SweepRow { value: v, eigenvalues: lin.eigenvalues.iter().map(|l| (l.re, l.im)).collect(), transient })
        })
        .collect()
}

/// The largest real part among the eigenvalues that are not zero (`|lambda|` above `1e-6`
/// times the largest): zero eigenvalues belong to conserved quantities (a constraint's value,
/// the speed of a steady motion), not to the stability of the motion.
pub fn growth(eigenvalues: &[(f64, f64)]) -> f64 {
    growth_without(eigenvalues, trivial_zeros(eigenvalues))
}

/// Real parts below this fraction of the eigenvalue's modulus are round-off: a conservative
/// system's eigenvalues lie on the imaginary axis, and the solver leaves them `+-1e-15` off it.
pub const ROUND_OFF: f64 = 1e-9;

/// Whether some eigenvalue that is not zero grows: its real part above [`ROUND_OFF`] of its
/// modulus. (The sign of [`growth`] alone would count the round-off of a conservative system's
/// imaginary eigenvalues.)
///
/// ```
/// use runtime::linearize::grows;
/// assert!(!grows(&[(1e-15, 2.0), (1e-15, -2.0), (-3e-16, 1.0)]));
/// assert!(grows(&[(1e-3, 2.0), (1e-3, -2.0)]) && grows(&[(0.5, 0.0)]));
/// ```
pub fn grows(eigenvalues: &[(f64, f64)]) -> bool {
    grows_without(eigenvalues, trivial_zeros(eigenvalues))
}

/// [`grows`] once the `zeros` eigenvalues of smallest magnitude are set aside.
fn grows_without(eigenvalues: &[(f64, f64)], zeros: usize) -> bool {
    let mut by_size: Vec<&(f64, f64)> = eigenvalues.iter().collect();
    by_size.sort_by(|a, b| a.0.hypot(a.1).total_cmp(&b.0.hypot(b.1)));
    by_size.iter().skip(zeros).any(|(re, im)| *re > ROUND_OFF * re.hypot(*im))
}

/// How many eigenvalues are zero (`|lambda|` below `1e-6` times the largest).
pub fn trivial_zeros(eigenvalues: &[(f64, f64)]) -> usize {
    let scale = eigenvalues.iter().fold(0.0f64, |m, (re, im)| m.max(re.hypot(*im)));
    eigenvalues.iter().filter(|(re, im)| re.hypot(*im) <= 1e-6 * scale).count()
}

/// The largest real part once the `zeros` eigenvalues of smallest magnitude are set aside.
fn growth_without(eigenvalues: &[(f64, f64)], zeros: usize) -> f64 {
    let mut by_size: Vec<&(f64, f64)> = eigenvalues.iter().collect();
    by_size.sort_by(|a, b| a.0.hypot(a.1).total_cmp(&b.0.hypot(b.1)));
    by_size.iter().skip(zeros).map(|e| e.0).fold(f64::NEG_INFINITY, f64::max)
}

/// The values between neighbouring rows where the motion turns stable or unstable ([`grows`]
/// changes: round-off is no crossing), each refined by bisection (re-linearizing) to a
/// relative width of `1e-13`. Near a crossing the crossing eigenvalue itself is small, so the
/// zeros set aside are counted at the bracket's ends. Where both ends are off the imaginary
/// axis (a damped mode turning unstable: its real part passes through zero) the bisection
/// follows the real part's sign itself, so the crossing is found to round-off; where one end
/// lies on it (a conservative system: its eigenvalues leave the axis in pairs) it follows
/// [`grows`].
pub fn crossings(model: &Model, formulation: FormulationKind, at: &Operating, swept: Swept, rows: &[SweepRow]) -> Result<Vec<f64>, LinearizeError> {
    let mut out = Vec::new();
    for w in rows.windows(2) {
        let (s0, s1) = (grows(&w[0].eigenvalues), grows(&w[1].eigenvalues));
        if s0 == s1 {
            continue;
        }
        let zeros = trivial_zeros(&w[0].eigenvalues).min(trivial_zeros(&w[1].eigenvalues));
        let off_axis = |e: &[(f64, f64)]| {
            let g = growth_without(e, zeros);
            g.abs() > ROUND_OFF * e.iter().fold(0.0f64, |m, (re, im)| m.max(re.hypot(*im)))
        };
        let by_sign = off_axis(&w[0].eigenvalues) && off_axis(&w[1].eigenvalues);
        let side = |v: f64| -> Result<bool, LinearizeError> {
            let lin = linearize(model, formulation, &swept.apply(at, v))?;
            let e: Vec<(f64, f64)> = lin.eigenvalues.iter().map(|l| (l.re, l.im)).collect();
            Ok(if by_sign { growth_without(&e, zeros) > 0.0 } else { grows_without(&e, zeros) })
        };
        let (mut lo, mut hi) = (w[0].value, w[1].value);
        while (hi - lo).abs() > 1e-13 * lo.abs().max(hi.abs()).max(1e-300) {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if side(mid)? == s0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        out.push(0.5 * (lo + hi));
    }
    Ok(out)
}

/// The sweep as CSV: `value,re_1,im_1,re_2,im_2,...`.
pub fn csv(name: &str, rows: &[SweepRow]) -> String {
    let k = rows.iter().map(|r| r.eigenvalues.len()).max().unwrap_or(0);
    let mut out = name.to_string();
    for i in 1..=k {
        out += &format!(",re_{i},im_{i}");
    }
    out.push('\n');
    for r in rows {
        out += &format!("{:e}", r.value);
        for (re, im) in &r.eigenvalues {
            out += &format!(",{re:e},{im:e}");
        }
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The smallest singular value of `A - lambda I` over the largest entry of `A`: zero at an
    /// eigenvalue.
    fn residual(a: &DMatrix<f64>, lambda: Complex<f64>) -> f64 {
        let n = a.nrows();
        let shifted = DMatrix::from_fn(n, n, |r, c| Complex::new(a[(r, c)], 0.0) - if r == c { lambda } else { Complex::new(0.0, 0.0) });
        shifted.singular_values().min() / a.amax()
    }

    /// The frozen Jacobian of a heavy symmetric top spinning upright in quaternions (Kane's
    /// state `e0..e3, omega`): nalgebra's unshifted iteration does not converge on it in ten
    /// times the sweeps allowed (its `complex_eigenvalues` loops for ever), the shifted one does.
    #[test]
    fn a_spinning_top_s_jacobian_has_its_eigenvalues() {
        #[rustfmt::skip]
        let a = DMatrix::from_row_slice(7, 7, &[
            0.0, 0.0, 0.0, -10.0, 0.0, 0.0, 0.0,
            0.0, 0.0, 10.0, 0.0, 0.5, 0.0, 0.0,
            0.0, -10.0, 0.0, 0.0, 0.0, 0.5, 0.0,
            -10.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.5,
            0.0, 9.81, 0.0, 0.0, 0.0, 10.0, 0.0,
            0.0, 0.0, 9.81, 0.0, -10.0, 0.0, 0.0,
            0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
        ]);
        assert!(nalgebra::Schur::try_new(a.clone(), f64::EPSILON, 10 * SWEEPS_PER_ROW * 10).is_none());
        let e = eigenvalues(&a).unwrap();
        assert_eq!(e.len(), 7);
        for &l in &e {
            assert!(residual(&a, l) < 1e-13, "{l} is not an eigenvalue: residual {}", residual(&a, l));
        }
        // +-10 and a zero, and two pairs +-2.2147 +- 10i (each with its conjugate).
        let real: Vec<f64> = e.iter().filter(|l| l.im.abs() < 1e-9).map(|l| l.re).collect();
        assert_eq!(real.len(), 3);
        assert!(real.iter().any(|r| (r - 10.0).abs() < 1e-12) && real.iter().any(|r| (r + 10.0).abs() < 1e-12) && real.iter().any(|r| r.abs() < 1e-12));
        let trace: f64 = e.iter().map(|l| l.re).sum();
        assert!(trace.abs() < 1e-12 && e.iter().map(|l| l.im).sum::<f64>().abs() < 1e-12);
    }

    /// Random matrices of every size up to 12: every eigenvalue found is one, and they sum to
    /// the trace.
    #[test]
    fn random_matrices_have_their_eigenvalues() {
        let mut seed = 7u64;
        let mut next = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for n in 1..=12 {
            for _ in 0..5 {
                let a = DMatrix::from_fn(n, n, |_, _| next());
                let e = eigenvalues(&a).unwrap();
                assert_eq!(e.len(), n);
                for &l in &e {
                    assert!(residual(&a, l) < 1e-12, "n = {n}: {l}: residual {}", residual(&a, l));
                }
                assert!((e.iter().map(|l| l.re).sum::<f64>() - a.trace()).abs() < 1e-11 * n as f64);
            }
        }
        assert!(eigenvalues(&DMatrix::zeros(0, 0)).unwrap().is_empty());
        assert_eq!(eigenvalues(&DMatrix::from_element(1, 1, -3.0)).unwrap(), vec![Complex::new(-3.0, 0.0)]);
    }

    /// An iteration that does not converge is reported, with its bound.
    #[test]
    fn an_iteration_that_does_not_converge_is_reported() {
        let a = DMatrix::from_fn(6, 6, |r, c| ((r * 7 + c * 3) % 5) as f64 - 2.0 + if r == c { 0.5 } else { 0.0 });
        assert_eq!(eigenvalues_within(&a, 1), Err(LinearizeError::Eigenvalues { size: 6, sweeps: 1, tries: SHIFTS.len() }));
        let mut b = a.clone();
        b[(2, 3)] = f64::NAN;
        assert_eq!(eigenvalues(&b), Err(LinearizeError::NotFinite { row: 2, column: 3 }));
    }
}
