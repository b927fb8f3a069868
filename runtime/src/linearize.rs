//! Linearization about an equilibrium or a steady motion: `x' = A x` in a formulation's state
//! (without the work integral, which is bookkeeping), from the emitted exact Jacobian (finite
//! differences when the module has none), and its eigenvalues; and sweeps of one parameter or
//! one initial velocity, the way the bicycle benchmark plots its eigenvalues against speed.
//!
//! ```
//! use runtime::linearize::{Operating, linearize};
//! // The spring cart at rest: every eigenvalue has a negative real part (its damper) or none.
//! let model = generated::find("spring_cart").unwrap();
//! let (q0, _) = model.initial.unwrap();
//! let at = Operating { q: vec![0.0; q0.len()], qdot: vec![0.0; q0.len()], params: model.default_params.to_vec() };
//! let lin = linearize(&model, "kane", &at).unwrap();
//! assert_eq!(lin.eigenvalues.len(), 4);
//! assert!(lin.eigenvalues.iter().all(|l| l.re < 1e-9));
//! ```

use crate::system::{SetupError, System};
use nalgebra::{Complex, DMatrix};
use seam::{Failure, Model};

/// Where to linearize: coordinates, their rates and the parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Operating {
    pub q: Vec<f64>,
    pub qdot: Vec<f64>,
    pub params: Vec<f64>,
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
    /// The eigenvalues of `A`, sorted by real part, then imaginary part, descending.
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
    #[error("`{name}` is neither a parameter nor a coordinate's rate `q'` of model `{model}` (parameters: {parameters}; coordinates: {coordinates})")]
    UnknownSweep { name: String, model: String, parameters: String, coordinates: String },
}

/// The linear model of formulation `formulation` of `model` at `at`.
pub fn linearize(model: &Model, formulation: &str, at: &Operating) -> Result<Linear, LinearizeError> {
    let (sys, y0) = System::start(*model, formulation, at.params.clone(), &at.q, &at.qdot)?;
    let n = sys.form.states;
    let k = if sys.form.has_work_state { n - 1 } else { n };
    let mut dy = vec![0.0; n];
    let mut flat = vec![0.0; n * n];
    let exact = sys.has_exact_jacobian();
    if exact {
        sys.jacobian(0.0, &y0, &mut dy, &mut flat).map_err(LinearizeError::Rhs)?;
    } else {
        sys.rhs(0.0, &y0, &mut dy).map_err(LinearizeError::Rhs)?;
        // Central differences, one column per state entry.
        let (mut up, mut down) = (vec![0.0; n], vec![0.0; n]);
        for c in 0..k {
            let h = 1e-6 * (1.0 + y0[c].abs());
            let mut y = y0.clone();
            y[c] += h;
            sys.rhs(0.0, &y, &mut up).map_err(LinearizeError::Rhs)?;
            y[c] -= 2.0 * h;
            sys.rhs(0.0, &y, &mut down).map_err(LinearizeError::Rhs)?;
            for r in 0..n {
                flat[r * n + c] = (up[r] - down[r]) / (2.0 * h);
            }
        }
    }
    let a = DMatrix::from_fn(k, k, |r, c| flat[r * n + c]);
    let mut eigenvalues: Vec<Complex<f64>> = a.complex_eigenvalues().iter().copied().collect();
    eigenvalues.sort_by(|x, y| y.re.total_cmp(&x.re).then(y.im.total_cmp(&x.im)));
    Ok(Linear { state: y0[..k].to_vec(), rates: dy[..k].to_vec(), a, eigenvalues, exact })
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

    /// `at` with the swept value set to `v`.
    pub fn apply(self, at: &Operating, v: f64) -> Operating {
        let mut out = at.clone();
        match self {
            Swept::Parameter(i) => out.params[i] = v,
            Swept::Rate(i) => out.qdot[i] = v,
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
pub fn sweep(model: &Model, formulation: &str, at: &Operating, swept: Swept, values: &[f64]) -> Result<Vec<SweepRow>, LinearizeError> {
    values
        .iter()
        .map(|&v| {
            let lin = linearize(model, formulation, &swept.apply(at, v))?;
            Ok(SweepRow { value: v, eigenvalues: lin.eigenvalues.iter().map(|l| (l.re, l.im)).collect() })
        })
        .collect()
}

/// The largest real part among the eigenvalues that are not zero (`|lambda| > 1e-8`): zero
/// eigenvalues belong to the coordinates nothing depends on (positions, headings), not to
/// the stability of the motion.
pub fn growth(eigenvalues: &[(f64, f64)]) -> f64 {
    eigenvalues.iter().filter(|(re, im)| re.hypot(*im) > 1e-8).map(|e| e.0).fold(f64::NEG_INFINITY, f64::max)
}

/// The values between neighbouring rows where [`growth`] changes sign, each refined by
/// bisection (re-linearizing) to a relative width of `1e-12`.
pub fn crossings(model: &Model, formulation: &str, at: &Operating, swept: Swept, rows: &[SweepRow]) -> Result<Vec<f64>, LinearizeError> {
    let sign = |v: f64| -> Result<bool, LinearizeError> {
        let lin = linearize(model, formulation, &swept.apply(at, v))?;
        let e: Vec<(f64, f64)> = lin.eigenvalues.iter().map(|l| (l.re, l.im)).collect();
        Ok(growth(&e) > 0.0)
    };
    let mut out = Vec::new();
    for w in rows.windows(2) {
        let (s0, s1) = (growth(&w[0].eigenvalues) > 0.0, growth(&w[1].eigenvalues) > 0.0);
        if s0 == s1 {
            continue;
        }
        let (mut lo, mut hi) = (w[0].value, w[1].value);
        while (hi - lo).abs() > 1e-12 * lo.abs().max(hi.abs()).max(1e-300) {
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
