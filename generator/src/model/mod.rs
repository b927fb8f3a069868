//! Loading and validating a model: from RON text to a [`Model`] whose every expression is
//! resolved, every frame has its kinematics, and every check that can be made on the input
//! alone has been made (names, sizes, frame tree, masses, inertias, quasi-velocity counts).
//!
//! ```
//! let model = generator::model::load("../models/cart_pendulum.ron").unwrap();
//! assert_eq!(model.coordinates.len(), 3);
//! ```

pub mod builder;
mod built_in;
pub(crate) mod error;
pub mod examples;
pub(crate) mod mesh;
mod resolve;
pub(crate) mod schema;
pub(crate) mod shape;
pub(crate) mod spans;
pub(crate) mod urdf;

pub use built_in::{Source, built_in, source, source_with};
pub use error::{ErrorKind, ModelError};
pub use mesh::{MeshFormat, TriangleMesh};
pub use schema::*;
pub use shape::{Shape, Solid, rpy_rotation};
pub use urdf::{OptionsNotRead, UrdfOptions, ident as urdf_ident, model_file as urdf_model_file, refuse_options_unless_urdf, world_rotation};

use crate::kinematics::{Axis, FrameKinematics, TimeChain, Turn};
use crate::symbolic::eval::Env;
use crate::symbolic::number::rat_from_f64;
use crate::symbolic::parse::{self, Ast, AstKind, LowerError, Resolver};
use crate::symbolic::transfer::{Transfer, Visitor};
use crate::symbolic::{Expr, Matrix, Symbol};
use std::collections::{HashMap, HashSet};

/// A resolved body.
#[derive(Clone, Debug)]
pub struct Body {
    pub name: String,
    /// Index into [`Model::frames`].
    pub frame: usize,
    pub mass: Expr,
    /// Centre of mass in the frame.
    pub com: [Expr; 3],
    /// Inertia about the centre of mass, frame components (`None` for a point mass).
    pub inertia: Option<Matrix>,
    /// How it is drawn (empty: as its equivalent-inertia box).
    pub shapes: Vec<shape::Shape>,
}

/// A resolved constraint.
#[derive(Clone, Debug)]
pub enum Constraint {
    /// `expr(q, q', t) = 0`, linear in `q'`.
    Velocity { name: String, expr: Expr },
    /// `expr(q, t) = 0`.
    Position { name: String, expr: Expr },
}

/// A resolved force.
#[derive(Clone, Debug)]
pub enum Force {
    Gravity { vector: [Expr; 3] },
    PointForce { name: String, frame: usize, point: [Expr; 3], force_world: [Expr; 3] },
    Torque { name: String, body: usize, torque: [Expr; 3] },
    Spring { name: String, a: (usize, [Expr; 3]), b: (usize, [Expr; 3]), stiffness: Expr, rest_length: Expr },
    Damper { name: String, a: (usize, [Expr; 3]), b: (usize, [Expr; 3]), damping: Expr },
    Generalized { name: String, components: Vec<Expr> },
    Potential { name: String, expr: Expr },
}

/// A validated model.
#[derive(Clone, Debug)]
pub struct Model {
    /// The file it came from (as given).
    pub file: String,
    /// The file's text (for locating later errors).
    pub source: String,
    pub name: String,
    pub description: String,
    /// Parameters and their values, in file order, then the inputs with their nominal values.
    pub parameters: Vec<(Symbol, f64)>,
    /// The inputs: indices into `parameters` (the last ones), set by the runtime at every call.
    pub inputs: Vec<usize>,
    /// `q`.
    pub coordinates: Vec<Symbol>,
    /// `q'`, one per coordinate.
    pub velocities: Vec<Symbol>,
    /// `q''`, one per coordinate.
    pub accelerations: Vec<Symbol>,
    /// Time.
    pub t: Symbol,
    /// Named time functions with their definitions in `t`.
    pub time_functions: Vec<(Symbol, Expr)>,
    /// Frames with kinematics; index 0 is the world.
    pub frames: Vec<FrameKinematics>,
    pub bodies: Vec<Body>,
    pub constraints: Vec<Constraint>,
    pub forces: Vec<Force>,
    /// The p quasi-velocities for Maggi and Kane.
    pub quasi_full: Vec<Expr>,
    /// The p - s quasi-velocities of the reduced Volterra method.
    pub quasi_reduced: Vec<Expr>,
    /// Declared ignorable coordinates (indices), or `None` for automatic detection.
    pub declared_ignorable: Option<Vec<usize>>,
    /// Initial coordinates and velocities (values), when the model gives them.
    pub initial: Option<(Vec<f64>, Vec<f64>)>,
    pub simulation: Option<SimulationDef>,
    /// The events a run watches, in file order.
    pub events: Vec<Event>,
    /// The shapes drawn fixed to the world ([`schema::ModelFile::scenery`]).
    pub scenery: Vec<shape::Shape>,
    /// The raw definition.
    pub def: ModelFile,
}

/// A model's event ([`schema::EventDef`]): `g(t, q, q')` crossing zero in `direction`, and
/// what happens there.
#[derive(Clone, Debug)]
pub struct Event {
    pub name: String,
    pub direction: seam::Direction,
    pub action: seam::EventAction,
    /// `g(t, q, q')`.
    pub when: Expr,
    /// A reset's new coordinates, one per coordinate (`None`: unchanged), in the values before it.
    pub reset_q: Vec<Option<Expr>>,
    /// A reset's new rates, likewise.
    pub reset_qdot: Vec<Option<Expr>>,
}

impl Transfer for Event {
    fn visit(&mut self, v: &mut dyn Visitor) {
        self.when.visit(v);
        self.reset_q.visit(v);
        self.reset_qdot.visit(v);
    }
}

impl Transfer for Body {
    fn visit(&mut self, v: &mut dyn Visitor) {
        self.mass.visit(v);
        self.com.visit(v);
        self.inertia.visit(v);
        for s in &mut self.shapes {
            s.visit(v);
        }
    }
}

impl Transfer for Constraint {
    fn visit(&mut self, v: &mut dyn Visitor) {
        match self {
            Constraint::Velocity { expr, .. } | Constraint::Position { expr, .. } => expr.visit(v),
        }
    }
}

impl Transfer for Force {
    fn visit(&mut self, v: &mut dyn Visitor) {
        match self {
            Force::Gravity { vector } => vector.visit(v),
            Force::PointForce { point, force_world, .. } => {
                point.visit(v);
                force_world.visit(v);
            }
            Force::Torque { torque, .. } => torque.visit(v),
            Force::Spring { a, b, stiffness, rest_length, .. } => {
                a.1.visit(v);
                b.1.visit(v);
                stiffness.visit(v);
                rest_length.visit(v);
            }
            Force::Damper { a, b, damping, .. } => {
                a.1.visit(v);
                b.1.visit(v);
                damping.visit(v);
            }
            Force::Generalized { components, .. } => components.visit(v),
            Force::Potential { expr, .. } => expr.visit(v),
        }
    }
}

/// Every expression and symbol of the model, so that it can be emitted in another context.
impl Transfer for Model {
    fn visit(&mut self, v: &mut dyn Visitor) {
        self.parameters.iter_mut().for_each(|(s, _)| s.visit(v));
        self.coordinates.visit(v);
        self.velocities.visit(v);
        self.accelerations.visit(v);
        self.t.visit(v);
        self.time_functions.visit(v);
        self.frames.visit(v);
        self.bodies.visit(v);
        self.constraints.visit(v);
        self.forces.visit(v);
        self.quasi_full.visit(v);
        self.quasi_reduced.visit(v);
        self.events.visit(v);
        self.scenery.visit(v);
    }
}

impl Model {
    /// Why the model cannot be drawn, if it cannot: the first mesh (of its bodies, then of its
    /// scenery) whose file could not be read as a mesh, as a located error.
    ///
    /// ```
    /// let model = generator::model::from_source("m.ron", &std::fs::read_to_string("../models/cart_pendulum.ron").unwrap()).unwrap();
    /// assert!(model.undrawable().is_none());
    /// ```
    pub fn undrawable(&self) -> Option<&ModelError> {
        self.bodies.iter().flat_map(|b| b.shapes.iter()).chain(&self.scenery).find_map(|s| match &s.solid {
            shape::Solid::Mesh { mesh: Err(e), .. } => Some(&**e),
            _ => None,
        })
    }

    /// The frames turned by ZYX Euler angles whose three angles are coordinates: each frame's
    /// name and the index of its pitch, singular where `cos(pitch)` vanishes (gimbal lock).
    ///
    /// ```
    /// let model = generator::model::load("../models/three_body.ron").unwrap();
    /// assert_eq!(model.gimbals(), vec![("middle".to_string(), 1)]);
    /// ```
    pub fn gimbals(&self) -> Vec<(String, usize)> {
        let index = |name: &str| self.coordinates.iter().position(|q| q.name() == name.trim());
        self.def
            .frames
            .iter()
            .flat_map(|f| f.rotation.iter().map(move |r| (f, r)))
            .filter_map(|(f, r)| match r {
                RotationDef::EulerZYX(psi, theta, phi) => {
                    let (a, b, c) = (index(psi)?, index(theta)?, index(phi)?);
                    (a != b && b != c && a != c).then(|| (f.name.clone(), b))
                }
                _ => None,
            })
            .collect()
    }

    /// The time chain `q -> q'` for total time derivatives of position-level expressions.
    pub fn position_chain(&self) -> TimeChain {
        TimeChain::new(self.t, self.coordinates.iter().zip(&self.velocities).map(|(q, v)| (*q, v.expr())).collect())
    }

    /// The time chain `q -> q'`, `q' -> q''` for velocity-level expressions.
    pub fn velocity_chain(&self) -> TimeChain {
        let mut pairs = self.position_chain().pairs;
        pairs.extend(self.velocities.iter().zip(&self.accelerations).map(|(v, a)| (*v, a.expr())));
        TimeChain::new(self.t, pairs)
    }

    /// [`Model::parameter_env`] with the initial coordinates and rates bound too (zeros without
    /// an `initial` section), at the run's start: the state a model's equations are first used
    /// at.
    pub fn initial_env(&self) -> Env {
        let mut env = self.parameter_env();
        env.set(self.t, self.simulation.as_ref().map_or(0.0, |s| s.t_start));
        let m = self.coordinates.len();
        let (q, qd) = self.initial.clone().unwrap_or((vec![0.0; m], vec![0.0; m]));
        for ((c, v), (x, xd)) in self.coordinates.iter().zip(&self.velocities).zip(q.iter().zip(&qd)) {
            env.set(*c, *x);
            env.set(*v, *xd);
        }
        env
    }

    /// An evaluation environment with the parameters, `pi` and the time functions bound.
    pub fn parameter_env(&self) -> Env {
        let mut env = Env::default();
        for (s, v) in &self.parameters {
            env.set(*s, *v);
        }
        env.set(Symbol::new("pi"), std::f64::consts::PI);
        for (f, body) in &self.time_functions {
            env.define(*f, self.t, *body);
        }
        env
    }

    /// The parameter symbols (and `pi`): constants for the solver.
    pub fn constant_symbols(&self) -> HashSet<Symbol> {
        let mut s: HashSet<Symbol> = self.parameters.iter().map(|(p, _)| *p).collect();
        s.insert(Symbol::new("pi"));
        s
    }

    /// The unit the model file gives a coordinate or a parameter (`units`), if any.
    pub fn unit(&self, name: &str) -> Option<&str> {
        self.def.units.get(name).map(String::as_str)
    }

    /// `name`, with its unit where the model gives one: `x [m]`, for axes and legends.
    ///
    /// ```
    /// let model = generator::model::load("../models/cart_pendulum.ron").unwrap();
    /// assert_eq!(model.labelled("x"), "x [m]");
    /// assert_eq!(model.labelled("nothing"), "nothing");
    /// ```
    pub fn labelled(&self, name: &str) -> String {
        match self.unit(name) {
            Some(unit) => format!("{name} [{unit}]"),
            None => name.to_string(),
        }
    }

    /// Number of coordinates, m.
    pub fn m(&self) -> usize {
        self.coordinates.len()
    }

    /// An error at `place` in the file (a path such as `quasi_velocities.full`), narrowed to
    /// `needle` inside it (the narrowing of `place_span` in `model/error.rs`).
    pub fn error(&self, kind: ErrorKind, place: &str, needle: &str, message: String, help: String) -> ModelError {
        let span = error::place_span(&self.source, &spans::Spans::new(&self.source), place, needle);
        located(kind, &self.file, &self.source, span, place, message, help)
    }
}

/// True for a URDF robot's path (`.urdf`, in any case): read as XML, its model made from it.
pub fn is_urdf(path: &std::path::Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("urdf"))
}

/// An error in the model text `source` of `file`, at `span`: located there, unless `file` is a
/// URDF robot's, whose model is RON text made from the XML (a line of that text is in no file
/// the user has, and the same line of the URDF is another thing): then the file and the place
/// are named, with no line.
fn located(kind: ErrorKind, file: &str, source: &str, span: Option<std::ops::Range<usize>>, place: &str, message: String, help: String) -> ModelError {
    if is_urdf(std::path::Path::new(file)) {
        return ModelError::in_place(kind, file, place, message, help);
    }
    ModelError::at(kind, file, source, span, place, message, help)
}

/// Runs `f` on a copy of `model` in a new expression context, dropped when `f` returns: the
/// library's entry points ([`crate::generate`], [`crate::inspect()`]) derive there,
/// so what a derivation builds never stays in the caller's context. `f`'s result must not hold
/// expressions (it cannot: they would belong to a context that is gone).
///
/// ```
/// use generator::symbolic::Context;
/// let model = generator::model::load("../models/cart_pendulum.ron").unwrap();
/// let before = Context::current_nodes();
/// let name = generator::model::in_own_context(&model, |m| m.coordinates[0].name());
/// assert_eq!(name, model.coordinates[0].name());
/// assert_eq!(Context::current_nodes(), before);
/// ```
pub fn in_own_context<R>(model: &Model, f: impl FnOnce(&Model) -> R) -> R {
    let parcel = crate::symbolic::transfer::Parcel::pack(model);
    crate::symbolic::Context::new().enter(|| f(&parcel.unpack()))
}

/// The most bytes a model file may hold (16 MiB): far above any model written by hand or by
/// the builder (a 200-link chain is about 100 KB), and a bound on what `inspect /dev/zero`
/// reads.
pub const MAX_MODEL_BYTES: u64 = 16 << 20;

/// Reads and validates a model file.
pub fn load(path: impl AsRef<std::path::Path>) -> Result<Model, ModelError> {
    let (file, source) = read_source(path.as_ref())?;
    from_source(&file, &source)
}

/// The text of the model file at `path`, and the file's name as errors print it: read with the
/// checks [`load`] makes (a size limit, UTF-8, no byte-order mark), not yet parsed.
pub fn read_source(path: &std::path::Path) -> Result<(String, String), ModelError> {
    let file = path.display().to_string();
    let bytes = files::read_bounded(path, MAX_MODEL_BYTES).map_err(|e| match e {
        files::FileError::TooLarge { limit, .. } => ModelError::unlocated(
            ErrorKind::Io,
            &file,
            format!("the file holds more than {limit} bytes, the most a model file may hold"),
            "is it the right file? A model of hundreds of bodies takes well under a megabyte; build larger ones in Rust with `ModelBuilder`".into(),
        ),
        e => ModelError::unlocated(
            ErrorKind::Io,
            &file,
            format!("cannot read the file: {}", e.source_message()),
            format!("check the path, or name a built-in model: {}", built_in().collect::<Vec<_>>().join(", ")),
        ),
    })?;
    let source = text_of(&file, &bytes)?.to_string();
    Ok((file, source))
}

/// The model text in `bytes`: UTF-8, without a leading byte-order mark (editors that write one
/// are common, and it carries no meaning). Binary data and invalid UTF-8 get a short message
/// with the place of the first bad byte, never the bytes themselves.
///
/// ```
/// use generator::model::text_of;
/// assert_eq!(text_of("m.ron", b"\xEF\xBB\xBFModel(").unwrap(), "Model(");
/// let e = text_of("m.ron", b"Model(\n  name: \"x\xFF\"").unwrap_err();
/// assert!(e.to_string().contains("m.ron:2:11") && e.to_string().contains("0xFF"), "{e}");
/// assert!(text_of("m.ron", b"\x7FELF\x02\x01\x00\x00").unwrap_err().to_string().contains("binary"));
/// ```
pub fn text_of<'a>(file: &str, bytes: &'a [u8]) -> Result<&'a str, ModelError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let place = |at: usize| {
        let before = &bytes[..at];
        let line = before.iter().filter(|b| **b == b'\n').count() + 1;
        let col = at - before.iter().rposition(|b| *b == b'\n').map_or(0, |p| p + 1) + 1;
        (line, col)
    };
    let error = |at: usize, message: String, help: &str| ModelError {
        location: Some(place(at)),
        span: Some(at..at + 1),
        ..ModelError::unlocated(ErrorKind::Syntax, file, message, help.into())
    };
    if let Some(at) = bytes.iter().position(|b| *b == 0) {
        return Err(error(at, "the file is binary data (a NUL byte), not a model".into(), "give a model file: RON text, as in `models/`"));
    }
    std::str::from_utf8(bytes).map_err(|e| {
        let at = e.valid_up_to();
        error(at, format!("the file is not UTF-8 text: byte 0x{:02X} here", bytes[at]), "save the model as UTF-8")
    })
}

/// The byte offset of 1-based `line` and `col` (characters) in `source`.
fn offset_of(source: &str, line: usize, col: usize) -> usize {
    let start: usize = source.split_inclusive('\n').take(line.saturating_sub(1)).map(str::len).sum();
    let rest = &source[start.min(source.len())..];
    start + rest.chars().take(col.saturating_sub(1)).map(char::len_utf8).sum::<usize>()
}

impl Model {
    /// The error for a derivation of this model that spent its node budget.
    pub fn budget_error(&self, spent: crate::symbolic::expr::NodeBudgetSpent) -> ModelError {
        ModelError::unlocated(
            ErrorKind::Budget,
            &self.file,
            format!(
                "deriving `{}` needs more than {} expression nodes, the node budget: the model is too large to derive within it ({} coordinates, {} bodies)",
                self.name,
                spent.limit,
                self.coordinates.len(),
                self.def.bodies.len()
            ),
            "raise the budget with `--max-nodes N` (about 1 KB of memory per node), or model fewer bodies".into(),
        )
    }

    /// The same model with some parameters set to other values (the command line's `--param`),
    /// validated as the file's own values are: a negative mass or an inertia that is not
    /// positive semi-definite is refused, located in the file, the message naming the values
    /// given.
    ///
    /// ```
    /// let model = generator::model::load("../models/cart_pendulum.ron").unwrap();
    /// let heavy = model.with_parameters(&[("M".into(), 20.0)]).unwrap();
    /// assert_eq!(heavy.def.parameters["M"], 20.0);
    /// let e = model.with_parameters(&[("M".into(), -1.0)]).unwrap_err().to_string();
    /// assert!(e.contains("M = -1.0") && e.contains("mass"), "{e}");
    /// assert!(model.with_parameters(&[("mass".into(), 1.0)]).unwrap_err().to_string().contains("no parameter `mass`"));
    /// ```
    pub fn with_parameters(&self, values: &[(String, f64)]) -> Result<Model, ModelError> {
        if values.is_empty() {
            return Ok(self.clone());
        }
        let mut def = self.def.clone();
        for (name, v) in values {
            match def.parameters.get_mut(name).or_else(|| def.inputs.get_mut(name)) {
                Some(x) => *x = *v,
                None => {
                    let known: Vec<&str> = def.parameters.keys().chain(def.inputs.keys()).map(String::as_str).collect();
                    return Err(ModelError::unlocated(
                        ErrorKind::UnknownName,
                        &self.file,
                        format!("no parameter `{name}` (known: {})", known.join(", ")),
                        "give a parameter the model file declares under `parameters`".into(),
                    ));
                }
            }
        }
        let given: Vec<String> = values.iter().map(|(n, v)| format!("{n} = {v:?}")).collect();
        build_within_budget(&self.file, &self.source, def).map_err(|mut e| {
            e.message = format!("with {} (given on the command line): {}", given.join(", "), e.message);
            e
        })
    }
}

/// A model definition as the RON text of a model file.
pub fn to_ron(def: &ModelFile) -> String {
    let config = ron::ser::PrettyConfig::new()
        .struct_names(true)
        .extensions(ron::extensions::Extensions::IMPLICIT_SOME)
        .indentor("    ".to_string())
        .escape_strings(false);
    // Serializing plain data with string keys cannot fail.
    ron::ser::to_string_pretty(def, config).expect("a model definition serializes to RON")
}

/// Parses and validates model text; `file` names it in errors.
pub fn from_source(file: &str, source: &str) -> Result<Model, ModelError> {
    let options = ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
    let def: ModelFile = options.from_str(source).map_err(|e| {
        let (line, col) = (e.span.start.line, e.span.start.col);
        let code = e.code.to_string();
        let help = if code.contains("Unexpected field") || code.contains("unknown field") {
            "remove the field or fix its spelling; the fields each item takes are documented in docs/model-format.md".to_string()
        } else if code.contains("missing field") || code.contains("Missing") {
            "add the missing field (see docs/model-format.md)".to_string()
        } else {
            "fix the RON syntax at this place (strings in double quotes, items separated by commas, balanced brackets)".to_string()
        };
        let at = offset_of(source, line, col);
        located(ErrorKind::Syntax, file, source, Some(at..(at + 1).min(source.len()).max(at)), "", format!("malformed model: {code}"), help)
    })?;
    if def.urdf.is_some() {
        // The robot first, then this file's items: validated as one model file would be.
        let merged = urdf::include(file, def)?;
        return from_source(file, &to_ron(&merged));
    }
    if def.quasi_velocities.is_empty() {
        return Err(ModelError::unlocated(
            ErrorKind::QuasiVelocityCount,
            file,
            "the model gives no quasi-velocities".into(),
            "add `quasi_velocities: QuasiVelocities(full: [...], reduced: [...])` (the rates `q'` are a choice that always works)".into(),
        ));
    }
    build_within_budget(file, source, def)
}

/// Validates `def`, reporting a spent node budget as an error (validation builds expressions).
fn build_within_budget(file: &str, source: &str, def: ModelFile) -> Result<Model, ModelError> {
    crate::symbolic::expr::catch_budget(|| resolve::Builder::new(file, source, def).build()).unwrap_or_else(|spent| {
        Err(ModelError::unlocated(
            ErrorKind::Budget,
            file,
            format!("reading the model needs more than {} expression nodes, the node budget", spent.limit),
            "raise the budget with `--max-nodes N` (about 1 KB of memory per node), or model fewer bodies".into(),
        ))
    })
}
