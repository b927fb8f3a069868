//! `multibody._multibody`, the extension module of the Python package `multibody`: a model
//! loaded from RON text, derived and evaluated in-process (the `load` crate, the JIT), its
//! right-hand sides and Jacobians on numpy arrays, runs and ensembles by the `runtime` crate with
//! the GIL released. The Python package (`python/multibody/__init__.py`) adds what is Python's
//! own: DataFrames, Dask, the notebook's LaTeX.
//!
//! Every error of the user's reaches Python as an exception carrying the command line's message:
//! [`ModelError`] (a `ValueError`) with the file, the line and column and the fix for a model,
//! `ValueError` for arguments, [`SimulationError`] (a `RuntimeError`) for a run that fails.

use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use runtime::integrate::{Method, Reason, Settings};
use runtime::system::System;
use runtime::trajectory::TrajectoryError;
use seam::FormulationKind;
use std::ops::ControlFlow;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::RecvTimeoutError;
use std::time::Duration;

/// How often an ensemble's caller runs Python's signal handlers while the members run (a Ctrl-C
/// answers within it).
const INTERRUPT_POLL: Duration = Duration::from_millis(50);

pyo3::create_exception!(
    _multibody,
    ModelError,
    PyValueError,
    "A model that cannot be loaded: the message names the file, the line and column, the place in the model and the fix."
);
pyo3::create_exception!(
    _multibody,
    InternalError,
    PyRuntimeError,
    "A fault of multibody's own (a panic inside it), not of the model or the call: please report it with the model."
);
pyo3::create_exception!(
    _multibody,
    SimulationError,
    PyRuntimeError,
    "A run, a right-hand side or a linearization that failed (a singular matrix, a step size underflow...)."
);

fn model_error(e: impl Into<::load::LoadError>) -> PyErr {
    match e.into() {
        ::load::LoadError::Model(e) => ModelError::new_err(e.render(false)),
        other => ModelError::new_err(other.to_string()),
    }
}

/// The result of `work`, a panic in it (a fault of multibody's, never the user's) turned into an
/// [`InternalError`], which `except Exception` catches, instead of pyo3's `PanicException`,
/// which it does not.
fn guarded<T>(work: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(work)).unwrap_or_else(|panic| {
        let what = panic.downcast_ref::<&str>().map(|s| s.to_string()).or_else(|| panic.downcast_ref::<String>().cloned()).unwrap_or_default();
        Err(InternalError::new_err(format!("a fault of multibody's, not of the model or the call (please report it with the model): {what}")))
    })
}

fn run_error(e: impl std::fmt::Display) -> PyErr {
    SimulationError::new_err(e.to_string())
}

/// A trajectory's rows as a numpy table (rows x columns).
fn table_of<'py>(py: Python<'py>, run: &runtime::trajectory::Trajectory) -> Bound<'py, PyArray2<f64>> {
    let (rows, width) = (run.rows.len(), run.columns.len());
    Array2::from_shape_vec((rows, width), run.rows.concat()).expect("rows x columns").into_pyarray(py)
}

/// A trajectory's events as (name, t, q).
fn events_of(events: Vec<runtime::trajectory::Crossing>) -> Vec<(String, f64, Vec<f64>)> {
    events.into_iter().map(|e| (e.name, e.t, e.q)).collect()
}

/// Ctrl-C during a run: the interpreter's signal handlers, run every
/// [`runtime::events::INTERRUPT_CHECK_CALLS`] right-hand sides from the thread that holds the
/// run with the GIL released (the caller's: Python runs its handlers on the main thread). The
/// exception a handler raises (`KeyboardInterrupt`) stops the run and reaches the caller.
#[derive(Default)]
struct Interrupt {
    calls: u32,
    raised: Option<PyErr>,
}

impl Interrupt {
    /// Called before each right-hand side, the GIL released: breaks once a handler raised.
    fn check(&mut self) -> ControlFlow<()> {
        self.calls = self.calls.wrapping_add(1);
        if !self.calls.is_multiple_of(runtime::events::INTERRUPT_CHECK_CALLS) {
            return ControlFlow::Continue(());
        }
        self.poll()
    }

    /// Runs the pending signal handlers now.
    fn poll(&mut self) -> ControlFlow<()> {
        if self.raised.is_none()
            && let Err(e) = Python::attach(|py| py.check_signals())
        {
            self.raised = Some(e);
        }
        if self.raised.is_some() { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
    }

    /// The exception the handler raised, with a note saying where the run stopped (Python 3.11
    /// and later show it under the traceback).
    fn into_error(self, py: Python<'_>, note: String) -> PyErr {
        let e = self.raised.unwrap_or_else(|| SimulationError::new_err(note.clone()));
        // `add_note` is missing before Python 3.11; the exception is the same without it.
        let _ = e.value(py).call_method1("add_note", (format!("multibody: {note}"),));
        e
    }
}

/// A model, derived and ready to run: `multibody.load(path)` or `multibody.loads(text)`.
#[pyclass(frozen, module = "multibody._multibody")]
struct Model {
    source: ::load::Source,
    evaluated: seam::Model,
    /// The same model with its exact Jacobians, derived at the first `jacobian` or `linearize`.
    exact: OnceLock<seam::Model>,
    warnings: Vec<String>,
    /// The model file's `units`, by coordinate or parameter.
    units: Vec<(String, String)>,
}

impl Model {
    fn open(source: ::load::Source) -> PyResult<Model> {
        let model = source.model().map_err(model_error)?;
        let loaded = ::load::evaluate(&model, ::load::Jacobians::Differenced, ::load::Route::Jit, &mut |_| {}).map_err(model_error)?;
        let units = model.def.units.iter().map(|(k, v)| (k.clone(), v.clone())).collect();
        Ok(Model { source, evaluated: loaded.model, exact: OnceLock::new(), warnings: loaded.warnings, units })
    }

    fn kind(&self, formulation: Option<&str>) -> PyResult<FormulationKind> {
        let available = || self.evaluated.kinds().iter().map(|k| k.name()).collect::<Vec<_>>().join(", ");
        let Some(name) = formulation else { return Ok(self.evaluated.default_kind()) };
        match FormulationKind::from_name(name) {
            Some(k) if self.evaluated.formulation(k).is_some() => Ok(k),
            _ => Err(PyValueError::new_err(format!("model `{}` has no formulation `{name}` (it has: {})", self.evaluated.module, available()))),
        }
    }

    /// The parameters: the model's defaults with `given` applied (a dict by name, or a sequence
    /// of every parameter in order).
    fn param_values(&self, given: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<f64>> {
        named_values(given, &self.evaluated.parameter_names, &self.evaluated.default_params, "parameter")
    }

    /// The exact-Jacobian model (derived once; differences where the node budget refuses).
    fn exact(&self, py: Python<'_>) -> PyResult<&seam::Model> {
        if let Some(m) = self.exact.get() {
            return Ok(m);
        }
        let model = self.source.model().map_err(model_error)?;
        let loaded = py
            .detach(|| {
                ::load::evaluate(&model, ::load::Jacobians::Exact { only: None, by_parameters: !model.inputs.is_empty() }, ::load::Route::Jit, &mut |_| {})
            })
            .map_err(model_error)?;
        // What the second derivation warns of (exact Jacobians over the budget replaced by
        // differences, for one) is news: the first load's warnings were told already.
        let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
        for line in loaded.warnings.iter().filter(|w| !self.warnings.contains(w)) {
            let message = std::ffi::CString::new(format!("{}: {line}", self.evaluated.name)).unwrap_or_default();
            PyErr::warn(py, category.as_any(), &message, 1)?;
        }
        Ok(self.exact.get_or_init(|| loaded.model))
    }

    /// What a call at a state evaluates: `formulation` of `model` (the plain one, or the
    /// exact-Jacobian one), the parameters, the momenta, and the state `x` checked against it.
    fn at<'m>(
        &self,
        model: &'m seam::Model,
        formulation: Option<&str>,
        x: &Bound<'_, PyAny>,
        params: Option<&Bound<'_, PyAny>>,
        momenta: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Call<'m>> {
        let kind = self.kind(formulation)?;
        let form = model.formulation(kind).expect("the kind is the model's");
        let g_i = self.momenta(model, kind, momenta.map(|m| vector(m, "momenta")).transpose()?)?;
        let x = vector(x, "x")?;
        check_len(&x, form.states(), "x")?;
        Ok(Call { model, form, params: self.param_values(params)?, g_i, x })
    }

    /// The coordinates and rates given (by name or in order) over the file's initial values.
    fn coordinates_and_rates(&self, q: Option<&Bound<'_, PyAny>>, qdot: Option<&Bound<'_, PyAny>>) -> PyResult<(Vec<f64>, Vec<f64>)> {
        let (q0, qd0) = self.initial();
        let names = &self.evaluated.coordinates;
        Ok((named_values(q, names, &q0, "coordinate")?, named_values(qdot, names, &qd0, "coordinate rate")?))
    }

    /// The conserved momenta a call is given, checked (only the reduced formulation needs them).
    fn momenta(&self, model: &seam::Model, kind: FormulationKind, momenta: Option<Vec<f64>>) -> PyResult<Vec<f64>> {
        let ignorable = model.ignorable.len();
        match momenta {
            Some(g) if g.len() == ignorable => Ok(g),
            Some(g) => Err(PyValueError::new_err(format!("momenta has {} values, the model has {ignorable} ignorable coordinates", g.len()))),
            None if kind == FormulationKind::ReducedVolterra && ignorable > 0 => Err(PyValueError::new_err(
                "the reduced formulation needs the conserved momenta of the ignorable coordinates: pass momenta=, the second value initial_state returns",
            )),
            None => Ok(vec![0.0; ignorable]),
        }
    }
}

/// A call's formulation, parameters, momenta and state (see `Model::at`).
struct Call<'m> {
    model: &'m seam::Model,
    form: &'m seam::Formulation,
    params: Vec<f64>,
    g_i: Vec<f64>,
    x: Vec<f64>,
}

/// Values by name (a dict) or in order (a sequence), over `defaults`.
fn named_values(given: Option<&Bound<'_, PyAny>>, names: &[String], defaults: &[f64], what: &str) -> PyResult<Vec<f64>> {
    let mut values = defaults.to_vec();
    let Some(given) = given.filter(|g| !g.is_none()) else { return Ok(values) };
    if let Ok(dict) = given.cast::<PyDict>() {
        for (key, value) in dict.iter() {
            let name: String = key.extract()?;
            let k = names.iter().position(|n| *n == name).ok_or_else(|| PyValueError::new_err(format!("no {what} `{name}` (known: {})", names.join(", "))))?;
            values[k] = finite(value.extract()?, &name)?;
        }
        return Ok(values);
    }
    let list = vector(given, what)?;
    if list.len() != names.len() {
        return Err(PyValueError::new_err(format!("{} {what} values given, the model has {} ({})", list.len(), names.len(), names.join(", "))));
    }
    Ok(list)
}

fn finite(x: f64, name: &str) -> PyResult<f64> {
    if x.is_finite() { Ok(x) } else { Err(PyValueError::new_err(format!("`{name}` = {x} is not finite"))) }
}

/// A float vector from a numpy array (without a copy of the Python objects) or any sequence.
fn vector(x: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<f64>> {
    if let Ok(a) = x.extract::<PyReadonlyArray1<'_, f64>>() {
        return Ok(a.as_array().to_vec());
    }
    x.extract::<Vec<f64>>().map_err(|_| PyValueError::new_err(format!("{what}: needs a sequence of numbers or a 1-D float array")))
}

fn check_len(x: &[f64], n: usize, what: &str) -> PyResult<()> {
    if x.len() == n { Ok(()) } else { Err(PyValueError::new_err(format!("{what} has {} values, the formulation has {n}", x.len()))) }
}

/// The integrator settings of a run of `span` seconds (the command line's defaults: DOP853 at
/// 1e-10, or the paper's DOPRI5 where the model asks for it).
fn settings(model: &seam::Model, span: f64, method: Option<&str>, rtol: Option<f64>, atol: Option<f64>, h: Option<f64>) -> PyResult<Settings> {
    let mut s = if model.paper_settings { Settings::paper(span) } else { Settings::tight(span) };
    if let Some(x) = h.filter(|x| !(*x > 0.0 && x.is_finite())) {
        return Err(PyValueError::new_err(format!("h needs a positive number, not {x}")));
    }
    if let Some(name) = method {
        s.method = Method::from_name(name, h.or(Some(0.01 * span)))
            .ok_or_else(|| PyValueError::new_err(format!("no method `{name}` (known: {}; rk4 takes h=)", Method::NAMES.join(", "))))?;
    }
    s.rtol = rtol.unwrap_or(s.rtol);
    s.atol = atol.unwrap_or(s.atol);
    Settings::check_tolerances(s.rtol, s.atol).map_err(PyValueError::new_err)?;
    Ok(s)
}

#[pymethods]
impl Model {
    /// The model's name.
    #[getter]
    fn name(&self) -> &str {
        &self.evaluated.name
    }

    /// The file the model came from (`models/<name>.ron` for a built-in one, `<string>` for
    /// `loads`).
    #[getter]
    fn file(&self) -> &str {
        &self.source.file
    }

    /// The model's text (RON).
    #[getter]
    fn text(&self) -> &str {
        &self.source.text
    }

    /// The generalized coordinates, in the order of every `q` and `qdot`.
    #[getter]
    fn coordinates(&self) -> Vec<String> {
        self.evaluated.coordinates.clone()
    }

    /// The units the model file gives its coordinates and parameters (`units`), in file order.
    #[getter]
    fn units(&self) -> Vec<(String, String)> {
        self.units.clone()
    }

    /// The formulations the model has, by name (`lagrange`, `maggi`, `kane`, `reduced_volterra`).
    #[getter]
    fn formulations(&self) -> Vec<&'static str> {
        self.evaluated.kinds().iter().map(|k| k.name()).collect()
    }

    /// The parameters and their defaults, in the model's order.
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for (name, value) in self.evaluated.parameter_names.iter().zip(&self.evaluated.default_params) {
            dict.set_item(name, value)?;
        }
        Ok(dict)
    }

    /// The ignorable coordinates whose momenta the reduced formulation holds constant.
    #[getter]
    fn ignorable(&self) -> Vec<String> {
        self.evaluated.ignorable.iter().map(|&j| self.evaluated.coordinates[j].clone()).collect()
    }

    /// What the derivation warned of.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// The initial coordinates and rates of the model's file (zeros without an `initial`
    /// section).
    #[getter]
    fn initial(&self) -> (Vec<f64>, Vec<f64>) {
        let m = self.evaluated.coordinates.len();
        self.evaluated.initial.clone().unwrap_or((vec![0.0; m], vec![0.0; m]))
    }

    /// The run of the model's file: `(t_start, t_end, dt_out)`, or None.
    #[getter]
    fn run(&self) -> Option<(f64, f64, f64)> {
        self.evaluated.run
    }

    /// The state of a formulation, by name, in order.
    #[pyo3(signature = (formulation=None))]
    fn state_names(&self, formulation: Option<&str>) -> PyResult<Vec<String>> {
        let kind = self.kind(formulation)?;
        Ok(self.evaluated.formulation(kind).expect("checked").state_names.clone())
    }

    /// What is derived: T, M, N, the constraints, Definition 1 per coordinate, the reduced
    /// method's matrices; as text, or LaTeX with `latex=True`.
    #[pyo3(signature = (latex=false))]
    fn inspect(&self, py: Python<'_>, latex: bool) -> PyResult<String> {
        guarded(|| {
            let model = self.source.model().map_err(model_error)?;
            py.detach(|| generator::inspect(&model, latex)).map_err(model_error)
        })
    }

    /// The state `x` of `formulation` at the coordinates `q` and rates `qdot` (the file's initial
    /// values where not given; a dict by name or a sequence in order), and the conserved momenta
    /// of the ignorable coordinates there (pass them to `rhs` of the reduced formulation).
    #[pyo3(signature = (formulation=None, q=None, qdot=None, params=None))]
    fn initial_state<'py>(
        &self,
        py: Python<'py>,
        formulation: Option<&str>,
        q: Option<&Bound<'py, PyAny>>,
        qdot: Option<&Bound<'py, PyAny>>,
        params: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<(Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<f64>>)> {
        guarded(|| {
            let kind = self.kind(formulation)?;
            let (q, qdot) = self.coordinates_and_rates(q, qdot)?;
            let params = self.param_values(params)?;
            let (sys, y0) = System::start(&self.evaluated, kind, params, &q, &qdot).map_err(run_error)?;
            Ok((y0.into_pyarray(py), sys.g_i.into_pyarray(py)))
        })
    }

    /// The right-hand side `x' = f(t, x)` of `formulation` (a 1-D array): what
    /// `scipy.integrate.solve_ivp` asks for. The reduced formulation needs `momenta`.
    #[pyo3(signature = (t, x, formulation=None, params=None, momenta=None))]
    fn rhs<'py>(
        &self,
        py: Python<'py>,
        t: f64,
        x: &Bound<'py, PyAny>,
        formulation: Option<&str>,
        params: Option<&Bound<'py, PyAny>>,
        momenta: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        guarded(|| {
            // The formulation's own function: no system (and none of its copies) per call.
            let call = self.at(&self.evaluated, formulation, x, params, momenta)?;
            let mut dx = vec![0.0; call.x.len()];
            call.form.rhs(t, &call.x, &call.params, &call.g_i, &mut dx).map_err(run_error)?;
            Ok(dx.into_pyarray(py))
        })
    }

    /// The Jacobian `d f / d x` (a 2-D array, row i the derivatives of `x'[i]`): exact from the
    /// derivation (derived at the first call), central differences where the node budget
    /// refuses it. `solve_ivp(..., jac=...)` takes it.
    #[pyo3(signature = (t, x, formulation=None, params=None, momenta=None))]
    fn jacobian<'py>(
        &self,
        py: Python<'py>,
        t: f64,
        x: &Bound<'py, PyAny>,
        formulation: Option<&str>,
        params: Option<&Bound<'py, PyAny>>,
        momenta: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        guarded(|| {
            let call = self.at(self.exact(py)?, formulation, x, params, momenta)?;
            let sys = System::new(call.model, call.form.kind, call.params, call.g_i).map_err(run_error)?;
            let (_, jac, _) = runtime::linearize::state_jacobian(&sys, t, &call.x).map_err(run_error)?;
            let n = call.x.len();
            Ok(Array2::from_shape_vec((n, n), jac).expect("n x n").into_pyarray(py))
        })
    }

    /// One formulation integrated from `q`, `qdot` (the file's initial values by default) with
    /// the model's events: a dict of columns (`t`, each coordinate, `q'`, `state:...`, the
    /// energy and its error, `momentum:...`, the constraint residuals), each a 1-D array, and
    /// the events, after the formulation's name and before the parameters used. The Python
    /// package turns it into a DataFrame.
    #[pyo3(signature = (formulation=None, t_end=None, dt_out=None, method=None, rtol=None, atol=None, h=None, params=None, q=None, qdot=None, t_start=None))]
    fn simulate_columns<'py>(
        &self,
        py: Python<'py>,
        formulation: Option<&str>,
        t_end: Option<f64>,
        dt_out: Option<f64>,
        method: Option<&str>,
        rtol: Option<f64>,
        atol: Option<f64>,
        h: Option<f64>,
        params: Option<&Bound<'py, PyAny>>,
        q: Option<&Bound<'py, PyAny>>,
        qdot: Option<&Bound<'py, PyAny>>,
        t_start: Option<f64>,
    ) -> PyResult<(&'static str, Vec<String>, Bound<'py, PyArray2<f64>>, Vec<(String, f64, Vec<f64>)>, Vec<f64>, Option<f64>)> {
        guarded(|| {
            let kind = self.kind(formulation)?;
            let (q, qdot) = self.coordinates_and_rates(q, qdot)?;
            let params = self.param_values(params)?;
            let file_run = self.evaluated.run;
            let (t_start, t_end, dt_out) = match (file_run, t_end, dt_out) {
                (Some((a, b, c)), t_end, dt_out) => (t_start.unwrap_or(a), t_end.unwrap_or(b), dt_out.unwrap_or(c)),
                (None, Some(b), Some(c)) => (t_start.unwrap_or(0.0), b, c),
                (None, _, _) => {
                    return Err(PyValueError::new_err(format!("model `{}` has no `simulation` section: give t_end= and dt_out=", self.evaluated.module)));
                }
            };
            let times = seam::output_times(t_start, t_end, dt_out).map_err(|e| PyValueError::new_err(format!("run settings: {e}")))?;
            let settings = settings(&self.evaluated, t_end - t_start, method, rtol, atol, h)?;
            let (sys, y0) = System::start(&self.evaluated, kind, params.clone(), &q, &qdot).map_err(run_error)?;
            let mut interrupt = Interrupt::default();
            let run = match py.detach(|| runtime::trajectory::simulate_interruptible(&sys, &y0, &times, &settings, &mut |_| interrupt.check())) {
                Err(TrajectoryError::Run(e)) if e.reason == Reason::Interrupted => {
                    return Err(interrupt.into_error(py, format!("the run stopped at t = {} (its last accepted step)", e.t)));
                }
                // A run that stops early (gimbal lock, a singular matrix) keeps its outputs up
                // to the stop, as `multibody simulate` writes them: carried by the error as
                // `partial` (the wrapper makes it the exception's `trajectory`).
                Err(TrajectoryError::Run(e)) => {
                    let err = run_error(&e);
                    if let Some(kept) = py.detach(|| runtime::trajectory::up_to(&sys, &y0, &times, &settings, &e)) {
                        err.value(py).setattr("partial", (kind.name(), kept.columns.clone(), table_of(py, &kept), events_of(kept.events), params.clone()))?;
                    }
                    return Err(err);
                }
                run => run.map_err(run_error)?,
            };
            let table = table_of(py, &run);
            // DOPRI5's or DOP853's stiffness test: the wrapper warns, naming the stiff method.
            Ok((kind.name(), run.columns, table, events_of(run.events), params, run.solution.stats.stiff_at))
        })
    }

    /// The linear model `x' = A x + B u` of `formulation` about `q`, `qdot` (the file's
    /// initial values by default): `(A, B, eigenvalues)`, B by the model's inputs (no columns
    /// without any), the eigenvalues without the zeros of cyclic coordinates.
    #[pyo3(signature = (formulation=None, q=None, qdot=None, params=None))]
    fn linearize<'py>(
        &self,
        py: Python<'py>,
        formulation: Option<&str>,
        q: Option<&Bound<'py, PyAny>>,
        qdot: Option<&Bound<'py, PyAny>>,
        params: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<f64>>, Bound<'py, PyArray1<numpy::Complex64>>)> {
        guarded(|| {
            let kind = self.kind(formulation)?;
            let (q, qdot) = self.coordinates_and_rates(q, qdot)?;
            let at = runtime::linearize::Operating { q, qdot, params: self.param_values(params)?, held: vec![] };
            let exact = self.exact(py)?;
            // A Ctrl-C during the derivation of the exact Jacobians answers here.
            py.check_signals()?;
            // The eigenvalue iteration is bounded (`runtime::linearize::eigenvalues`): it returns.
            let (linear, b) = py
                .detach(|| -> Result<_, runtime::linearize::LinearizeError> {
                    let linear = runtime::linearize::linearize(exact, kind, &at)?;
                    let (b, _) = runtime::linearize::input_matrix(exact, kind, &at, &exact.inputs)?;
                    Ok((linear, b))
                })
                .map_err(run_error)?;
            if let runtime::linearize::Motion::Transient { entry, rate } = linear.motion() {
                let state = &exact.formulation(kind).expect("the kind is the model's").state_names;
                let message = format!(
                    "{}: not an equilibrium nor a steady motion: {}' = {rate:e} there, so A is the Jacobian of the flow at this instant and its eigenvalues are how fast neighbouring motions separate now, not the stability of the motion (linearize at an equilibrium, or in a formulation whose state holds the motion steady)",
                    self.evaluated.name, state[entry]
                );
                let message = std::ffi::CString::new(message).unwrap_or_default();
                PyErr::warn(py, py.get_type::<pyo3::exceptions::PyUserWarning>().as_any(), &message, 1)?;
            }
            let k = linear.a.nrows();
            let a = Array2::from_shape_fn((k, k), |(r, c)| linear.a[(r, c)]).into_pyarray(py);
            let b = Array2::from_shape_fn((k, b.ncols()), |(r, c)| b[(r, c)]).into_pyarray(py);
            let eigenvalues: Vec<numpy::Complex64> = linear.eigenvalues.iter().map(|z| numpy::Complex64::new(z.re, z.im)).collect();
            Ok((a, b, eigenvalues.into_pyarray(py)))
        })
    }

    /// Writes the model's Rust module (what `generator MODEL -o PATH` writes) to `path`,
    /// atomically; a file already holding the same bytes is left alone. Refuses the model file
    /// itself (by any path: any file this process read), and any `.ron` file unless `force`.
    #[pyo3(signature = (path, force=false))]
    fn generate_rust(&self, py: Python<'_>, path: std::path::PathBuf, force: bool) -> PyResult<()> {
        guarded(|| {
            use generator::overwrite::{Overwrite, overwrites_a_model};
            let shown = files::printable_path(&path);
            match overwrites_a_model(std::path::Path::new(&self.source.file), &path).filter(|o| !force || *o == Overwrite::ModelItself) {
                None => {}
                Some(Overwrite::ModelItself) => {
                    return Err(PyValueError::new_err(format!(
                        "`{shown}` is the model file itself: writing Rust there would destroy the model (give another path)"
                    )));
                }
                Some(Overwrite::RonFile) => {
                    return Err(PyValueError::new_err(format!(
                        "`{shown}` is a `.ron` file: this writes Rust, and would replace a model (write to a `.rs` path, or force=True if you mean it)"
                    )));
                }
            }
            let model = self.source.model().map_err(model_error)?;
            let generated = py.detach(|| generator::generate(&model, &generator::emit::Options::from_model(&model))).map_err(model_error)?;
            files::write_if_changed(&path, generated.code.as_bytes()).map_err(|e| pyo3::exceptions::PyOSError::new_err(e.to_string()))?;
            Ok(())
        })
    }

    /// Writes the self-contained HTML page that plays motions in 3-D (the `animate` crate):
    /// each run a `(times (T,), q (T, m), formulation)`, the first drawn as the bodies and the
    /// others over it, with the parameters `params`.
    #[pyo3(signature = (path, runs, params=None))]
    fn animate(
        &self,
        path: std::path::PathBuf,
        runs: Vec<(PyReadonlyArray1<'_, f64>, PyReadonlyArray2<'_, f64>, String)>,
        params: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<()> {
        guarded(|| {
            let model = self.source.model().map_err(model_error)?;
            let params = self.param_values(params)?;
            let data: Vec<(Vec<f64>, Vec<f64>)> = runs.iter().map(|(t, q, _)| (t.as_array().to_vec(), q.as_array().iter().copied().collect())).collect();
            let motions: Vec<animate::Motion> =
                runs.iter().zip(&data).map(|((_, _, formulation), (times, q))| animate::Motion { formulation, times, q }).collect();
            animate::write_overlaid(&path, &model, &params, &motions).map_err(|e| match e {
                animate::AnimateError::File(e) => pyo3::exceptions::PyOSError::new_err(e.to_string()),
                animate::AnimateError::Mesh(e) => model_error(*e),
                other => PyValueError::new_err(other.to_string()),
            })
        })
    }

    /// Pickled as its file name and text: a Dask worker derives it again on arrival.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let from_source = py.import("multibody._multibody")?.getattr("_from_source")?;
        Ok((from_source, PyTuple::new(py, [self.source.file.clone(), self.source.text.clone()])?))
    }

    fn __repr__(&self) -> String {
        format!(
            "<multibody.Model {} ({}): {} coordinates, formulations {}>",
            self.evaluated.module,
            self.source.file,
            self.evaluated.coordinates.len(),
            self.formulations().join(", ")
        )
    }
}

/// Rows of a 2-D array (N, n), or one 1-D row for every member, or the default for every member.
fn rows(given: Option<&Bound<'_, PyAny>>, members: usize, default: &[f64], what: &str) -> PyResult<Vec<Vec<f64>>> {
    let Some(given) = given.filter(|g| !g.is_none()) else { return Ok(vec![default.to_vec(); members]) };
    if let Ok(a) = given.extract::<PyReadonlyArray2<'_, f64>>() {
        let a = a.as_array();
        if a.nrows() != members || a.ncols() != default.len() {
            return Err(PyValueError::new_err(format!("{what} has shape ({}, {}), the ensemble needs ({members}, {})", a.nrows(), a.ncols(), default.len())));
        }
        return Ok(a.rows().into_iter().map(|r| r.to_vec()).collect());
    }
    let row = vector(given, what)?;
    if row.len() != default.len() {
        return Err(PyValueError::new_err(format!("{what} has {} values, the model has {}", row.len(), default.len())));
    }
    Ok(vec![row; members])
}

/// The number of members a 2-D argument gives.
fn members_of(given: Option<&Bound<'_, PyAny>>) -> Option<usize> {
    let a = given?.extract::<PyReadonlyArray2<'_, f64>>().ok()?;
    Some(a.as_array().nrows())
}

/// Runs `N` simulations of `model` on every core with the GIL released, each exactly as it
/// would run alone: parameters `params` (N, k), initial coordinates `q0` (N, m) and rates
/// `qdot0` (N, m) (any may be one row for all, or None for the model's own), output times
/// `t_eval` (the first is the start). Returns the formulation's states, (N, len(t_eval),
/// states), and the number of output times each member reached (fewer only where a terminal
/// event stopped it; its later rows are NaN).
#[pyfunction]
#[pyo3(signature = (model, t_eval, params=None, q0=None, qdot0=None, formulation=None, method=None, rtol=None, atol=None, h=None, threads=None, max_values=None))]
fn ensemble<'py>(
    py: Python<'py>,
    model: &Model,
    t_eval: &Bound<'py, PyAny>,
    params: Option<&Bound<'py, PyAny>>,
    q0: Option<&Bound<'py, PyAny>>,
    qdot0: Option<&Bound<'py, PyAny>>,
    formulation: Option<&str>,
    method: Option<&str>,
    rtol: Option<f64>,
    atol: Option<f64>,
    h: Option<f64>,
    threads: Option<usize>,
    max_values: Option<usize>,
) -> PyResult<(Bound<'py, PyArray3<f64>>, Bound<'py, PyArray1<u64>>, Bound<'py, PyArray1<f64>>)> {
    guarded(|| {
        let kind = model.kind(formulation)?;
        let m = &model.evaluated;
        let counts: Vec<usize> = [params, q0, qdot0].into_iter().filter_map(members_of).collect();
        let n = counts.first().copied().ok_or_else(|| PyValueError::new_err("give params, q0 or qdot0 as a 2-D array (N, ...): one row per member"))?;
        if counts.iter().any(|&c| c != n) {
            return Err(PyValueError::new_err(format!("the 2-D arguments disagree on the number of members: {counts:?}")));
        }
        let limit = max_values.unwrap_or(runtime::ensemble::DEFAULT_MAX_VALUES);
        let states = m.formulation(kind).expect("the kind is the model's").states();
        let values = n as u128 * t_eval.len().unwrap_or(0) as u128 * states as u128;
        if values > limit as u128 {
            return Err(PyValueError::new_err(
                runtime::ensemble::EnsembleError::TooLarge { members: n, times: t_eval.len().unwrap_or(0), states, values, limit }.to_string(),
            ));
        }
        let (iq, iqd) = model.initial();
        let (params, q0, qdot0) = (rows(params, n, &m.default_params, "params")?, rows(q0, n, &iq, "q0")?, rows(qdot0, n, &iqd, "qdot0")?);
        let members: Vec<runtime::ensemble::Member> =
            params.into_iter().zip(q0).zip(qdot0).map(|((params, q0), qd0)| runtime::ensemble::Member { params, q0, qd0 }).collect();
        // Sizes first, before anything is copied or allocated.
        let count = t_eval.len().unwrap_or(0);
        if count > seam::MAX_OUTPUTS + 1 {
            return Err(PyValueError::new_err(format!(
                "t_eval has {count} times, more than the {} a run may hold: sample the run more coarsely",
                seam::MAX_OUTPUTS + 1
            )));
        }
        if let Some(n) = threads {
            runtime::ensemble::check_threads(n).map_err(|e| PyValueError::new_err(e.to_string()))?;
        }
        let times = vector(t_eval, "t_eval")?;
        let span = times.last().copied().unwrap_or(0.0) - times.first().copied().unwrap_or(0.0);
        let settings = settings(m, span.max(f64::MIN_POSITIVE), method, rtol, atol, h)?;
        // The members run on a worker thread while this one, the caller's, runs Python's signal
        // handlers every `INTERRUPT_POLL` and sets `stop` once one raised (Ctrl-C).
        let (stop, mut interrupt) = (AtomicBool::new(false), Interrupt::default());
        let runs = py.detach(|| {
            std::thread::scope(|scope| {
                let (finished, done) = std::sync::mpsc::channel::<()>();
                let worker = scope.spawn(|| {
                    let runs = runtime::ensemble::ensemble(m, kind, &members, &times, &settings, threads, limit, &|| {}, &stop);
                    drop(finished);
                    runs
                });
                while let Err(RecvTimeoutError::Timeout) = done.recv_timeout(INTERRUPT_POLL) {
                    if interrupt.poll().is_break() {
                        stop.store(true, Ordering::Relaxed);
                    }
                }
                worker.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic))
            })
        });
        let runs = runs.map_err(|e| match e {
            runtime::ensemble::EnsembleError::Times
            | runtime::ensemble::EnsembleError::Shape { .. }
            | runtime::ensemble::EnsembleError::TooLarge { .. }
            | runtime::ensemble::EnsembleError::Threads { .. } => PyValueError::new_err(e.to_string()),
            runtime::ensemble::EnsembleError::Interrupted => interrupt.into_error(py, "the ensemble stopped".into()),
            other => run_error(other),
        })?;
        let shape = (runs.members, runs.times, runs.states);
        let reached: Vec<u64> = runs.reached.iter().map(|&r| r as u64).collect();
        // Each member's time from which it looked stiff (NaN: it did not); the wrapper warns.
        let stiff_at: Vec<f64> = runs.stiff_at.iter().map(|t| t.unwrap_or(f64::NAN)).collect();
        Ok((Array3::from_shape_vec(shape, runs.data).expect("members x times x states").into_pyarray(py), reached.into_pyarray(py), stiff_at.into_pyarray(py)))
    })
}

/// The model in the RON or URDF file at `path`, or the built-in model of that name; a URDF
/// robot's base (`"fixed"` or `"floating"`), gravity (three numbers) and limits (`"report"`,
/// `"record"`, `"stop"`).
#[pyfunction]
#[pyo3(name = "load", signature = (path, base=None, gravity=None, limits=None))]
fn load_model(path: &Bound<'_, PyAny>, base: Option<&str>, gravity: Option<[f64; 3]>, limits: Option<&str>) -> PyResult<Model> {
    guarded(|| {
        use generator::model::{Base, LimitAction, UrdfOptions};
        let argument: std::path::PathBuf = path.extract()?;
        let given = [(base.is_some(), "base="), (gravity.is_some(), "gravity="), (limits.is_some(), "limits=")];
        generator::model::refuse_options_unless_urdf(&argument, given.into_iter().filter(|g| g.0).map(|g| g.1).collect())
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let base = match base {
            None | Some("fixed") => Base::Fixed,
            Some("floating") => Base::Floating,
            Some(other) => return Err(PyValueError::new_err(format!("base=`{other}`: give \"fixed\" or \"floating\""))),
        };
        let mut robot = UrdfOptions { base, ..UrdfOptions::default() };
        if let Some(g) = gravity {
            if !g.iter().all(|x| x.is_finite()) {
                return Err(PyValueError::new_err(format!("gravity={g:?}: give three finite numbers")));
            }
            robot.gravity = g;
        }
        robot.limits = match limits {
            None | Some("report") => LimitAction::Report,
            Some("record") => LimitAction::Record,
            Some("stop") => LimitAction::Stop,
            Some(other) => return Err(PyValueError::new_err(format!("limits=`{other}`: give \"report\", \"record\" or \"stop\""))),
        };
        Model::open(::load::source_with(&argument, &robot).map_err(model_error)?)
    })
}

/// The model in the RON text `text` (`name` is what its errors call the file).
#[pyfunction]
#[pyo3(signature = (text, name="<string>"))]
fn loads(text: &str, name: &str) -> PyResult<Model> {
    guarded(|| {
        // The limit of a model file, for a model given as text.
        if text.len() as u64 > generator::model::MAX_MODEL_BYTES {
            return Err(ModelError::new_err(format!(
                "{}: the text holds {} bytes, more than the {} a model may hold (a model of hundreds of bodies takes well under a megabyte; build larger ones in Rust with `ModelBuilder`)",
                files::printable(name),
                text.len(),
                generator::model::MAX_MODEL_BYTES
            )));
        }
        Model::open(::load::Source { file: name.to_string(), text: text.to_string() })
    })
}

/// The inverse of `Model.__reduce__`.
#[pyfunction]
fn _from_source(file: String, text: String) -> PyResult<Model> {
    guarded(|| Model::open(::load::Source { file, text }))
}

/// The RON text of one of the generator's model families: `pendulum_on_cart` (SymPy's
/// `n_link_pendulum_on_cart`: n point masses on massless links, the cart ignorable) or
/// `floating_chain` (n rigid links on alternating revolute joints on a free-floating base).
#[pyfunction]
fn _example_text(family: &str, n: usize) -> PyResult<String> {
    if !(1..=500).contains(&n) {
        return Err(PyValueError::new_err(format!("n = {n}: a chain of 1 to 500 links")));
    }
    let builder = match family {
        "pendulum_on_cart" => generator::model::examples::n_link_pendulum_on_cart(n),
        "floating_chain" => generator::model::examples::floating_chain(n),
        other => return Err(PyValueError::new_err(format!("no model family `{other}` (known: pendulum_on_cart, floating_chain)"))),
    };
    Ok(builder.to_ron())
}

/// What a run that looked stiff from `t` tells the user (the command line's words; the
/// wrapper names `method="ros23"`).
#[pyfunction]
fn stiffness_note(t: f64) -> String {
    runtime::integrate::stiffness_note(t)
}

/// The names of the models built into the wheel (`multibody.load(name)` takes them).
#[pyfunction]
fn built_in() -> Vec<&'static str> {
    ::load::built_in().collect()
}

#[pymodule]
fn _multibody(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Model>()?;
    m.add_function(wrap_pyfunction!(load_model, m)?)?;
    m.add_function(wrap_pyfunction!(loads, m)?)?;
    m.add_function(wrap_pyfunction!(_from_source, m)?)?;
    m.add_function(wrap_pyfunction!(built_in, m)?)?;
    m.add_function(wrap_pyfunction!(_example_text, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble, m)?)?;
    m.add_function(wrap_pyfunction!(stiffness_note, m)?)?;
    m.add("ModelError", m.py().get_type::<ModelError>())?;
    m.add("SimulationError", m.py().get_type::<SimulationError>())?;
    m.add("InternalError", m.py().get_type::<InternalError>())?;
    m.add("METHODS", Method::NAMES.to_vec())?;
    Ok(())
}
