//! Emission: derived equations as a flat, specialized Rust module.
//!
//! It derives nothing: the pipeline ([`crate::generate`]) hands it the mechanics, the ignorable
//! coordinates and each formulation's equations, and its private `module` writes the module as
//! a syntax tree (quote), printed by prettyplease, one part per reuse group of formulations.
//! Inside each function, `cse` picks one `let` per common subexpression, `lower` turns nodes
//! into Rust expressions and `ops` counts what they cost ([`OpCount`]). The public face:
//! [`Options`], the [`Summary`] and [`Generated`], the solve plans ([`Solve`], [`LdlPlan`]) and
//! the register tapes' compiler ([`tape`]).
//!
//! ```no_run
//! let model = generator::model::load("models/cart_pendulum.ron").unwrap();
//! let out = generator::generate(&model, &generator::emit::Options::from_model(&model)).unwrap();
//! std::fs::write("cart_pendulum.rs", &out.code).unwrap();
//! eprintln!("{}", out.summary);
//! ```

mod assembly;
mod cse;
mod fma;
mod form;
mod from_mechanics;
mod function;
mod jacobian;
mod ldl;
mod lower;
mod module;
mod names;
mod ops;
mod optimize;
mod pairs;
pub(crate) mod program;
mod prepare;
mod reuse;
mod seam;
mod solvers;
mod splice;
mod syntax;
pub mod tape;

use crate::model::Model;
pub use crate::model::schema::{FormulationDef as Formulation, FunctionDef as Function, ParameterDef as Parameters};
pub use ldl::{LdlPlan, Solve};
pub(crate) use module::{CONSTRAINT_TOLERANCE, Emission, Part, SINGULAR_TOLERANCE, assemblies, module, reuse_groups};
pub use ops::OpCount;
pub use solvers::spd_cost;
use std::fmt;
use std::time::Duration;

/// What to emit. [`Options::from_model`] reads the model's `emit` section.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    pub formulations: Vec<Formulation>,
    pub functions: Vec<Function>,
    pub parameters: Parameters,
    pub integrate_ignorable: bool,
    pub max_lets_per_function: usize,
    /// Emit each formulation's exact `jacobian` (the right-hand side's derivative by the state).
    pub jacobian: bool,
    /// Emit each formulation's `parameter_jacobian` (runtime parameters only).
    pub parameter_jacobian: bool,
    /// The name the module is emitted under, written into `model().module` (the model's name
    /// when `None`; a variant such as `cart_pendulum_baked` otherwise).
    pub module_name: Option<String>,
    /// The path of the seam crate in emitted code: `::seam` when the crate depends on `seam`
    /// itself, or a re-export such as `runtime::seam`.
    pub seam_path: String,
    /// Also compile every emitted function into a tape for in-process evaluation
    /// ([`crate::eval`]), returned as [`Generated::program`].
    pub tapes: bool,
    /// Emit fused multiply-adds (`f64::mul_add`) in the function bodies and the unrolled solves, for targets that
    /// have the instruction. The tapes are the plain code's.
    pub fma: bool,
    /// Write the Rust source ([`Generated::code`]). In-process evaluation wants the tapes only
    /// ([`crate::evaluate_with_backend`] turns it off, and `code` is then empty): parsing,
    /// splicing and formatting a module nobody reads took an eighth of the matrix test of the
    /// pendulum on a cart at 1 to 24 links (`perf record`).
    pub source: bool,
}

/// The seam crate's path when nothing else is asked for.
pub const DEFAULT_SEAM_PATH: &str = "::seam";

/// What to give as the seam crate's path when one is not a Rust path.
pub(crate) const SEAM_PATH_HELP: &str = "give the seam crate's path, such as `::seam` or `runtime::seam`";

/// `path` parsed as the seam crate's path in emitted code, or what is wrong with it. The
/// callers check it where the option comes from (`--seam-path`, `Builder::seam_path`), before
/// any derivation, and name that place.
pub(crate) fn parse_seam_path(path: &str) -> Result<syn::Path, String> {
    syn::parse_str(path).map_err(|e| format!("`{}` is not a Rust path: {e}", files::printable(path)))
}

impl Options {
    /// The options the model file asks for.
    pub fn from_model(model: &Model) -> Options {
        let e = &model.def.emit;
        let mut formulations = e.formulations.clone();
        formulations.sort();
        formulations.dedup();
        let mut functions = e.functions.clone();
        functions.sort();
        functions.dedup();
        Options {
            formulations,
            functions,
            parameters: e.parameters,
            integrate_ignorable: e.integrate_ignorable,
            max_lets_per_function: e.max_lets_per_function,
            jacobian: e.jacobian,
            parameter_jacobian: e.parameter_jacobian,
            module_name: None,
            seam_path: DEFAULT_SEAM_PATH.to_string(),
            tapes: false,
            fma: false,
            source: true,
        }
    }
}

/// The generated module and what it took.
#[derive(Clone, Debug)]
pub struct Generated {
    /// The Rust source, formatted; identical bytes for identical input (empty where
    /// [`Options::source`] is off).
    pub code: String,
    pub summary: Summary,
    /// The functions as tapes, when [`Options::tapes`] asked for them.
    pub program: Option<program::Program>,
}

/// What one emitted function costs: the operations of its straight-line body and, for a
/// right-hand side, of its dense solve (worst case), counted apart so they compare with
/// SymPy's `count_ops` of `cse([M, F])` (assembly only).
#[derive(Clone, Debug, PartialEq)]
pub struct FunctionCost {
    /// `energy`, `kane::rhs`, ...
    pub name: String,
    /// Common subexpressions bound.
    pub lets: usize,
    /// Operations of the body: assembling the matrix and forcing, for a right-hand side.
    pub ops: OpCount,
    /// Operations of the dense solve (zero for functions that solve nothing).
    pub solve: OpCount,
}

/// Sizes and costs, printed by the command line to stderr.
#[derive(Clone, Debug)]
pub struct Summary {
    pub model: String,
    pub m: usize,
    pub r: usize,
    pub p: usize,
    pub s: usize,
    /// Per formulation: name, states, equations.
    pub formulations: Vec<(String, usize, usize)>,
    /// Per formulation: how its velocity transformation was eliminated.
    pub eliminations: Vec<(String, String)>,
    /// Per formulation: how its right-hand side solves its matrix ([`ldl::Solve`]).
    pub solves: Vec<(String, String)>,
    /// Per emitted function: its cost.
    pub functions: Vec<FunctionCost>,
    /// What the simplifier's limits cut (nodes kept as built: correct, only less compact).
    pub simplifier: crate::symbolic::fourier::SimplifyReport,
    /// What the other budgets cut and which questions stayed undecided (both threads').
    pub cuts: crate::symbolic::report::Cuts,
    /// Time per derivation stage.
    pub stages: Vec<(&'static str, Duration)>,
    /// Time spent deriving (mechanics and formulations), and emitting after the derivation
    /// ended (every formulation but the last is emitted meanwhile, on a second thread: the
    /// two add up to the whole).
    pub derive_time: Duration,
    pub emit_time: Duration,
    /// The expression nodes the generation built (both threads' contexts): its work and its
    /// memory (about 1 KB a node), counted, and the same in every run.
    pub nodes: usize,
}

/// What a generation spent, as the pipeline measured it: the times, and the nodes counted.
pub(crate) struct Work {
    pub(crate) derive_time: Duration,
    pub(crate) emit_time: Duration,
    pub(crate) nodes: usize,
}

impl Summary {
    /// The cost of the function called `name` (e.g. `"kane::rhs"`).
    pub fn ops(&self, name: &str) -> Option<&FunctionCost> {
        self.functions.iter().find(|f| f.name == name)
    }
}

impl Summary {
    /// Sizes, eliminations and operation counts without the timings: deterministic, for golden
    /// files.
    pub fn work_counters(&self) -> String {
        let mut out = format!("model {}: m = {}, r = {}, p = {}, s = {}\n", self.model, self.m, self.r, self.p, self.s);
        for (name, states, eqs) in &self.formulations {
            out += &format!("  {name:<18} {states:>3} states, {eqs:>3} equations\n");
        }
        for (name, how) in &self.eliminations {
            out += &format!("  {name:<18} {how}\n");
        }
        for (name, how) in &self.solves {
            out += &format!("  {name:<18} solve: {how}\n");
        }
        for f in &self.functions {
            if f.solve.total() == 0 {
                out += &format!("  {:<32} {:>5} lets, {}\n", f.name, f.lets, f.ops);
            } else {
                out += &format!("  {:<32} {:>5} lets, assembly {} + solve {} ops\n", f.name, f.lets, f.ops, f.solve.total());
            }
        }
        for line in self.notes().into_iter().chain(self.warnings()) {
            out += &format!("  {line}\n");
        }
        out += &format!("  expression nodes built: {}\n", self.nodes);
        out
    }

    /// What the simplifier's limits kept as built (empty when nothing): exact, only larger, so
    /// a note for the summary and `inspect`, not a warning at every load.
    pub fn notes(&self) -> Vec<String> {
        let simplifier = self.simplifier.summary().map(|cut| format!("simplifier: {cut}"));
        simplifier.into_iter().chain(self.cuts.quiet_lines()).collect()
    }

    /// What the user should act on (empty when nothing): a decision the derivation took for
    /// want of an answer that changes what the model does (the report of cuts' warnings).
    pub fn warnings(&self) -> Vec<String> {
        self.cuts.warnings.clone()
    }
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.work_counters())?;
        let stages: Vec<String> = self.stages.iter().map(|(n, d)| format!("{n} {:.1}", d.as_secs_f64() * 1e3)).collect();
        write!(
            f,
            "  derived in {:.1} ms ({} ms), emitted in {:.1} ms",
            self.derive_time.as_secs_f64() * 1e3,
            stages.join(", "),
            self.emit_time.as_secs_f64() * 1e3
        )
    }
}
