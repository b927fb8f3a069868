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
    /// The eigenvalues of `A` without the cyclic entries, sorted by real part, then imaginary
    /// part, descending.
    pub eigenvalues: Vec<Complex<f64>>,
    /// True when `A` came from the emitted Jacobian, false for finite differences.
    pub exact: bool,
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
    let (kept, cyclic) = cyclic_entries(&a, if exact { 1e-12 } else { 1e-8 });
    let reduced = DMatrix::from_fn(kept.len(), kept.len(), |r, c| a[(kept[r], kept[c])]);
    let mut eigenvalues: Vec<Complex<f64>> = reduced.complex_eigenvalues().iter().copied().collect();
    eigenvalues.sort_by(|x, y| y.re.total_cmp(&x.re).then(y.im.total_cmp(&x.im)));
    Ok(Linear { state: y0[..k].to_vec(), rates: dy[..k].to_vec(), a, cyclic, eigenvalues, exact })
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
}

/// Linearizes at `at` with the swept value at each of `values`.
pub fn sweep(model: &Model, formulation: FormulationKind, at: &Operating, swept: Swept, values: &[f64]) -> Result<Vec<SweepRow>, LinearizeError> {
    values
        .iter()
        .map(|&v| {
            let lin = linearize(model, formulation, &swept.apply(at, v))?;
            Ok(SweepRow { value: v, eigenvalues: lin.eigenvalues.iter().map(|l| (l.re, l.im)).collect() })
        })
        .collect()
}

/// The largest real part among the eigenvalues that are not zero (`|lambda|` above `1e-6`
/// times the largest): zero eigenvalues belong to conserved quantities (a constraint's value,
/// the speed of a steady motion), not to the stability of the motion.
pub fn growth(eigenvalues: &[(f64, f64)]) -> f64 {
    growth_without(eigenvalues, trivial_zeros(eigenvalues))
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

/// The values between neighbouring rows where [`growth`] changes sign, each refined by
/// bisection (re-linearizing) to a relative width of `1e-13`. Near a crossing the crossing
/// eigenvalue itself is small, so the zeros set aside are counted at the bracket's ends.
pub fn crossings(model: &Model, formulation: FormulationKind, at: &Operating, swept: Swept, rows: &[SweepRow]) -> Result<Vec<f64>, LinearizeError> {
    let mut out = Vec::new();
    for w in rows.windows(2) {
        let (s0, s1) = (growth(&w[0].eigenvalues) > 0.0, growth(&w[1].eigenvalues) > 0.0);
        if s0 == s1 {
            continue;
        }
        let zeros = trivial_zeros(&w[0].eigenvalues).min(trivial_zeros(&w[1].eigenvalues));
        let sign = |v: f64| -> Result<bool, LinearizeError> {
            let lin = linearize(model, formulation, &swept.apply(at, v))?;
            let e: Vec<(f64, f64)> = lin.eigenvalues.iter().map(|l| (l.re, l.im)).collect();
            Ok(growth_without(&e, zeros) > 0.0)
        };
        let (mut lo, mut hi) = (w[0].value, w[1].value);
        while (hi - lo).abs() > 1e-13 * lo.abs().max(hi.abs()).max(1e-300) {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if sign(mid)? == s0 {
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
