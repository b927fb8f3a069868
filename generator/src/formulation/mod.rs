//! From mechanics to equations of motion: the shared derivation ([`mechanics`]), the
//! ignorable-coordinate analysis ([`ignorable`]), the Volterra forms ([`volterra`]) and the
//! four formulations, each a [`Method`] giving [`Equations`] (private modules: `lagrange`,
//! `maggi`, `kane`, `reduced`; over a tree of frames, `composite` and `articulated`).
//! [`derive()`] runs them once for `inspect`; emission runs the same stages in the same order,
//! spread over two threads ([`crate::generate`]).
//!
//! ```
//! use generator::formulation::{derive, Request};
//! let model = generator::model::load("../models/cart_pendulum.ron").unwrap();
//! let d = derive(&model, &Request::all()).unwrap();
//! let names: Vec<&str> = d.equations.iter().map(|e| e.name()).collect();
//! assert_eq!(names, ["lagrange", "maggi", "kane", "reduced_volterra"]);
//! assert_eq!(d.ignorable, vec![2]);
//! ```

mod articulated;
mod classical;
mod composite;
mod equations;
pub mod ignorable;
mod kane;
mod lagrange;
mod maggi;
pub mod mechanics;
pub(crate) mod power;
pub(crate) mod reduced;
mod spatial;
#[cfg(test)]
mod test_states;
pub mod volterra;

pub use equations::{Equations, Method};

use crate::model::schema::FormulationDef;
use crate::model::{Model, ModelError};
use mechanics::Mechanics;
use std::time::{Duration, Instant};
use volterra::Volterra;

/// What to derive.
#[derive(Clone, Debug, PartialEq)]
pub struct Request {
    /// The formulations, in any order (they are derived in the canonical one).
    pub formulations: Vec<FormulationDef>,
    /// Keep the ignorable coordinates in the reduced method's state.
    pub integrate_ignorable: bool,
}

impl Request {
    /// All four formulations, ignorable coordinates integrated.
    pub fn all() -> Request {
        Request {
            formulations: vec![FormulationDef::Lagrange, FormulationDef::Maggi, FormulationDef::Kane, FormulationDef::ReducedVolterra],
            integrate_ignorable: true,
        }
    }
}

/// What the formulations share, handed to each [`Method`].
pub struct Shared<'a> {
    pub model: &'a Model,
    pub mech: &'a Mechanics,
    /// Kane's form (the full quasi-velocities), when a formulation needs it.
    pub kane: Option<&'a Volterra>,
    /// The reduced form, when requested.
    pub reduced: Option<&'a Volterra>,
    /// Kane's equations by the recursions over the tree of frames, derived once for Kane's and
    /// the reduced form.
    pub trees: Trees<'a>,
    pub integrate_ignorable: bool,
}

/// Kane's equations by the recursions over a tree of frames, where the model is one.
#[derive(Clone, Copy, Debug, Default)]
pub struct Trees<'a> {
    /// The model's frames as a tree in Kane's quasi-velocities (`composite::Tree`).
    pub frames: Option<&'a composite::Tree>,
    /// `M_K` and `L_K` by the composite-body and Newton-Euler recursions (`composite::derive` in the tests; `on_tree` here).
    pub composite: Option<&'a composite::Recursion>,
    /// `u'` by the articulated-body recursion (`articulated::derive` in the tests).
    pub articulated: Option<&'a articulated::Articulated>,
}

/// Everything derived from a model, once.
#[derive(Clone, Debug)]
pub struct Derivation {
    pub mechanics: Mechanics,
    /// Definition 1, coordinate by coordinate.
    pub reports: Vec<ignorable::CoordinateReport>,
    /// The ignorable coordinates the reduced method uses.
    pub ignorable: Vec<usize>,
    /// Kane's form, derived for Kane, Maggi and the reduced method.
    pub kane: Option<Volterra>,
    pub reduced: Option<Volterra>,
    /// The requested formulations' equations, in the order Lagrange, Maggi, Kane, reduced.
    pub equations: Vec<Equations>,
    /// Time per stage (for the summary and the scaling benchmark; never in output).
    pub stages: Vec<(&'static str, Duration)>,
    /// What this thread's budgets cut and which questions stayed undecided on the way.
    pub cuts: crate::symbolic::report::Cuts,
}

impl Derivation {
    /// The equations of the formulation called `name`.
    pub fn equations(&self, name: &str) -> Option<&Equations> {
        self.equations.iter().find(|e| e.name() == name)
    }
}

/// Where [`derive_with`] hands its results as soon as they are ready, and where it has the
/// ignorable coordinates decided: here by default ([`derive()`]); generation hands the mechanics
/// to a second thread that decides them meanwhile, and emits each formulation as it arrives
/// ([`crate::generate`]).
pub trait Stages {
    /// The mechanics are derived (first, once).
    fn mechanics(&mut self, _mech: &Mechanics) {}
    /// Definition 1 for every coordinate, and the set the reduced method uses. Asked for after
    /// Maggi's and Kane's forms (which do not need it) and before the reduced form; its error
    /// is reported before theirs.
    fn ignorable(&mut self, model: &Model, mech: &Mechanics) -> Result<Ignorable, ModelError> {
        let clock = Instant::now();
        let reports = ignorable::analyze(model, mech);
        let chosen = ignorable::choose(model, &reports)?;
        Ok(Ignorable { reports, chosen, time: clock.elapsed() })
    }
    /// One formulation's equations, as soon as derived.
    fn equations(&mut self, _eqs: &Equations) {}
}

/// What [`Stages::ignorable`] decides.
pub struct Ignorable {
    /// Definition 1, coordinate by coordinate (empty where they were decided elsewhere).
    pub reports: Vec<ignorable::CoordinateReport>,
    /// The ignorable coordinates the reduced method uses.
    pub chosen: Vec<usize>,
    /// Time it took, where it ran.
    pub time: Duration,
}

/// Everything done where it is asked for.
struct Here;
impl Stages for Here {}

/// Derives what `request` asks for ([`derive_with`], everything on this thread).
pub fn derive(model: &Model, request: &Request) -> Result<Derivation, ModelError> {
    crate::symbolic::expr::catch_budget(|| derive_with(model, request, &mut Here)).unwrap_or_else(|spent| Err(model.budget_error(spent)))
}

/// Refuses a coordinate that moves no mass (its diagonal entry of `M` is identically zero)
/// and that no constraint involves: the mass matrix, and every formulation's matrix, would be
/// singular at every state.
fn every_coordinate_has_inertia(model: &Model, mech: &mechanics::Mechanics) -> Result<(), ModelError> {
    use crate::symbolic::zero::is_identically_zero;
    for (j, q) in model.coordinates.iter().enumerate() {
        let massless = is_identically_zero(mech.mass.get(j, j));
        if massless && (0..mech.r).all(|i| is_identically_zero(mech.a.get(i, j))) {
            let name = q.name();
            return Err(model.error(
                crate::model::ErrorKind::SingularQuasiVelocities,
                &format!("coordinates[{j}]"),
                &format!("\"{name}\""),
                format!("coordinate `{name}` moves no body and no constraint involves it: the mass matrix is singular at every state"),
                "give the coordinate a body to move (a frame that depends on it, carrying a body with mass or inertia), or remove it".into(),
            ));
        }
    }
    Ok(())
}

/// Derives what `request` asks for, each formulation right after what it needs: Lagrange's
/// equations after the mechanics, Maggi's and Kane's after Kane's form, the reduced method's
/// after the reduced form. `stages` hears of each result as soon as it is ready and decides the
/// ignorable coordinates. Errors come in the order mechanics, ignorable coordinates, Kane's
/// form, reduced form, formulations.
///
/// ```
/// use generator::formulation::{derive_with, Equations, Request, Stages};
/// struct Names(Vec<&'static str>);
/// impl Stages for Names {
///     fn equations(&mut self, e: &Equations) { self.0.push(e.name()) }
/// }
/// let model = generator::model::load("../models/cart_pendulum.ron").unwrap();
/// let mut names = Names(Vec::new());
/// derive_with(&model, &Request::all(), &mut names).unwrap();
/// assert_eq!(names.0, ["lagrange", "maggi", "kane", "reduced_volterra"]);
/// ```
pub fn derive_with(model: &Model, request: &Request, stages: &mut dyn Stages) -> Result<Derivation, ModelError> {
    crate::symbolic::report::take();
    let mut times = Vec::new();
    let mut clock = Instant::now();
    // Time in the formulations' own work, summed over the places it runs.
    let mut formulations = Duration::ZERO;
    let classical = request.formulations.iter().any(|f| matches!(f, FormulationDef::Lagrange | FormulationDef::Maggi));
    let mech = mechanics::derive_for(model, classical);
    every_coordinate_has_inertia(model, &mech)?;
    times.push(("mechanics", clock.elapsed()));
    // Time in the stages' hands (where they hand the results to another thread, packing them,
    // and wait for Definition 1 beyond its own time).
    let mut handoff = Duration::ZERO;
    clock = Instant::now();
    stages.mechanics(&mech);
    handoff += clock.elapsed();
    let wants = |f: FormulationDef| request.formulations.contains(&f);
    // Where a constraint moves, each formulation also gives the power of its forces.
    let moving_force = power::constraints_move(&mech).then(|| mech.lagrange_force());
    let mut equations = Vec::new();
    let mut formulate = |stages: &mut dyn Stages,
                         handoff: &mut Duration,
                         def: FormulationDef,
                         method: &dyn Method,
                         kane: Option<&Volterra>,
                         reduced: Option<&Volterra>,
                         trees: Trees|
     -> Result<(), ModelError> {
        if wants(def) {
            let start = Instant::now();
            let shared = Shared { model, mech: &mech, kane, reduced, trees, integrate_ignorable: request.integrate_ignorable };
            let mut eqs = method.equations(&shared)?;
            if let Some(force) = &moving_force {
                eqs.constraint_power = Some(power::constraint_power(model, &mech, force, &eqs));
            }
            formulations += start.elapsed();
            let start = Instant::now();
            stages.equations(&eqs);
            *handoff += start.elapsed();
            equations.push(eqs);
        }
        Ok(())
    };
    formulate(stages, &mut handoff, FormulationDef::Lagrange, &lagrange::Lagrange, None, None, Trees::default())?;
    clock = Instant::now();
    // Kane's form serves Kane, Maggi, and the reduced method's Schur route.
    let kane = if wants(FormulationDef::Kane) || wants(FormulationDef::Maggi) || wants(FormulationDef::ReducedVolterra) {
        volterra::derive(model, &mech, &[], &model.quasi_full).map(Some)
    } else {
        Ok(None)
    };
    let kane_time = clock.elapsed();
    // Definition 1 may be decided on another thread (generation's emitting one) while Maggi's
    // and Kane's forms are formulated here: its answer is read before the reduced form, the one
    // that needs it, and its error still comes before theirs (the order the stages run alone).
    let mut pending: Result<(), ModelError> = Ok(());
    let kane = kane.unwrap_or_else(|e| {
        pending = Err(e);
        None
    });
    if pending.is_ok() {
        pending = formulate(stages, &mut handoff, FormulationDef::Maggi, &maggi::Maggi, kane.as_ref(), None, Trees::default());
    }
    // The tree of frames, once, for both recursions of Kane's and the reduced form.
    clock = Instant::now();
    let frames = match &kane {
        Some(k) if pending.is_ok() && (wants(FormulationDef::Kane) || wants(FormulationDef::ReducedVolterra)) => composite::tree(model, &mech, k).zip(Some(k)),
        _ => None,
    };
    let recursion = frames.as_ref().and_then(|(t, k)| composite::on_tree(t, k));
    let articulated = frames.as_ref().and_then(|(t, k)| articulated::on_tree(t, &mech, k));
    let trees = Trees { frames: frames.as_ref().map(|(t, _)| t), composite: recursion.as_ref(), articulated: articulated.as_ref() };
    let trees_time = clock.elapsed();
    if pending.is_ok() {
        pending = formulate(stages, &mut handoff, FormulationDef::Kane, &kane::Kane, kane.as_ref(), None, trees);
    }
    clock = Instant::now();
    let decided = stages.ignorable(model, &mech)?;
    handoff += clock.elapsed().saturating_sub(decided.time);
    pending?;
    times.push(("ignorable", decided.time));
    times.push(("kane", kane_time));
    clock = Instant::now();
    let reduced = match &kane {
        Some(k) if wants(FormulationDef::ReducedVolterra) => Some(volterra::derive_reduced(model, &mech, &decided.chosen, &model.quasi_reduced, k)?),
        _ => None,
    };
    times.push(("reduced", clock.elapsed()));
    formulate(stages, &mut handoff, FormulationDef::ReducedVolterra, &reduced::ReducedVolterra, kane.as_ref(), reduced.as_ref(), trees)?;
    times.push(("formulations", formulations));
    times.push(("trees", trees_time));
    times.push(("handoff", handoff));
    let cuts = crate::symbolic::report::take();
    Ok(Derivation { mechanics: mech, reports: decided.reports, ignorable: decided.chosen, kane, reduced, equations, stages: times, cuts })
}
