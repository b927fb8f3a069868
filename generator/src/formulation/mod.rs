//! From mechanics to equations of motion: the shared derivation ([`mechanics`]), the
//! ignorable-coordinate analysis ([`ignorable`]), the Volterra forms ([`volterra`]) and the
//! four formulations, each a [`Method`] giving [`Equations`]: [`lagrange`], [`maggi`],
//! [`kane`], [`reduced`]. [`derive`] runs them once for `inspect`; emission runs the same
//! stages in the same order, spread over two threads ([`crate::emit::generate`]).
//!
//! ```
//! use generator::formulation::{derive, Request};
//! let model = generator::model::load("../models/cart_pendulum.ron").unwrap();
//! let d = derive(&model, &Request::all()).unwrap();
//! let names: Vec<&str> = d.equations.iter().map(|e| e.name).collect();
//! assert_eq!(names, ["lagrange", "maggi", "kane", "reduced_volterra"]);
//! assert_eq!(d.ignorable, vec![2]);
//! ```

pub mod classical;
pub mod equations;
pub mod ignorable;
pub mod kane;
pub mod lagrange;
pub mod maggi;
pub mod mechanics;
pub mod reduced;
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
    /// The ignorable coordinates the reduced method uses.
    pub ignorable: &'a [usize],
    /// Kane's form (the full quasi-velocities), when a formulation needs it.
    pub kane: Option<&'a Volterra>,
    /// The reduced form, when requested.
    pub reduced: Option<&'a Volterra>,
    pub integrate_ignorable: bool,
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
}

impl Derivation {
    /// The equations of the formulation called `name`.
    pub fn equations(&self, name: &str) -> Option<&Equations> {
        self.equations.iter().find(|e| e.name == name)
    }
}

/// Derives what `request` asks for, each formulation right after what it needs (Lagrange's
/// equations need only the mechanics, Maggi's and Kane's Kane's form, the reduced method's the
/// reduced form): the order generation's two threads follow too ([`crate::emit::generate`]).
pub fn derive(model: &Model, request: &Request) -> Result<Derivation, ModelError> {
    let mut stages = Vec::new();
    let mut clock = Instant::now();
    // Time in the formulations' own work, summed over the places it runs.
    let mut formulations = Duration::ZERO;
    let mut stage = |name: &'static str, stages: &mut Vec<(&'static str, Duration)>| {
        stages.push((name, clock.elapsed()));
        clock = Instant::now();
    };
    let mech = mechanics::derive(model);
    stage("mechanics", &mut stages);
    let reports = ignorable::analyze(model, &mech);
    let chosen = ignorable::choose(model, &reports)?;
    stage("ignorable", &mut stages);
    let wants = |f: FormulationDef| request.formulations.contains(&f);
    let mut equations = Vec::new();
    let mut formulate = |def: FormulationDef, method: &dyn Method, kane: Option<&Volterra>, reduced: Option<&Volterra>| -> Result<(), ModelError> {
        if wants(def) {
            let start = Instant::now();
            let shared = Shared { model, mech: &mech, ignorable: &chosen, kane, reduced, integrate_ignorable: request.integrate_ignorable };
            let eqs = method.equations(&shared)?;
            formulations += start.elapsed();
            equations.push(eqs);
        }
        Ok(())
    };
    formulate(FormulationDef::Lagrange, &lagrange::Lagrange, None, None)?;
    let clock_start = Instant::now();
    // Kane's form serves Kane, Maggi, and the reduced method's Schur route.
    let kane = if wants(FormulationDef::Kane) || wants(FormulationDef::Maggi) || wants(FormulationDef::ReducedVolterra) {
        Some(volterra::derive(model, &mech, &[], &model.quasi_full)?)
    } else {
        None
    };
    stages.push(("kane", clock_start.elapsed()));
    formulate(FormulationDef::Maggi, &maggi::Maggi, kane.as_ref(), None)?;
    formulate(FormulationDef::Kane, &kane::Kane, kane.as_ref(), None)?;
    let clock_start = Instant::now();
    let reduced = match &kane {
        Some(k) if wants(FormulationDef::ReducedVolterra) => Some(volterra::derive_reduced(model, &mech, &chosen, &model.quasi_reduced, k)?),
        _ => None,
    };
    stages.push(("reduced", clock_start.elapsed()));
    formulate(FormulationDef::ReducedVolterra, &reduced::ReducedVolterra, kane.as_ref(), reduced.as_ref())?;
    stages.push(("formulations", formulations));
    Ok(Derivation { mechanics: mech, reports, ignorable: chosen, kane, reduced, equations, stages })
}
