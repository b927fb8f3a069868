//! Building a model in Rust code instead of a RON file.
//!
//! A [`ModelBuilder`] assembles the same [`ModelFile`] a RON file deserializes to; [`build`]
//! writes it out as RON and loads that text through [`from_source`], so a built model gets
//! exactly the validation, and the located errors, of a file (the "file" named in an error is
//! `<builder NAME>`, and [`ModelBuilder::to_ron`] gives the text the line and column refer to).
//! [`ModelBuilder::to_ron`] is also how a built model is saved to `models/`.
//!
//! [`build`]: ModelBuilder::build
//!
//! ```
//! use generator::model::builder::{Body, Frame, ModelBuilder};
//! // A pendulum: a point mass on a massless rod of length l, swinging about z.
//! let model = ModelBuilder::new("pendulum")
//!     .parameter("m", 1.0)
//!     .parameter("l", 0.5)
//!     .parameter("g", 9.81)
//!     .coordinate("theta")
//!     .frame(Frame::new("rod", "world").rotate_z("theta"))
//!     .body(Body::new("bob", "rod", "m").com(["0", "-l", "0"]))
//!     .gravity(["0", "-g", "0"])
//!     .quasi_velocities(["theta'"], ["theta'"])
//!     .initial([("theta", "0.1")], [("theta", "0")])
//!     .simulation(10.0, 0.01)
//!     .build()
//!     .unwrap();
//! assert_eq!(model.m(), 1);
//! // The same validation as a file: a mass of zero is refused, located in the RON text.
//! let err = ModelBuilder::new("bad")
//!     .coordinate("x")
//!     .frame(Frame::new("f", "world").translation(["x", "0", "0"]))
//!     .body(Body::new("b", "f", "0"))
//!     .quasi_velocities(["x'"], ["x'"])
//!     .build()
//!     .unwrap_err();
//! assert!(err.message.contains("not positive"), "{err}");
//! ```

use super::schema::*;
use super::{Model, ModelError, from_source};
use indexmap::IndexMap;

/// A frame under construction: its parent moved by a translation and turned by rotations.
#[derive(Clone, Debug)]
pub struct Frame(FrameDef);

impl Frame {
    /// A frame `name` whose parent is `parent` (`"world"` for the root).
    pub fn new(name: impl Into<String>, parent: impl Into<String>) -> Frame {
        Frame(FrameDef { name: name.into(), parent: parent.into(), translation: None, rotation: Vec::new() })
    }

    /// The translation from the parent's origin, in the parent's components.
    pub fn translation(mut self, t: [&str; 3]) -> Frame {
        self.0.translation = Some(t.iter().map(|s| s.to_string()).collect());
        self
    }

    /// Appends an elementary rotation (applied after the ones before it, about the current axes).
    pub fn rotate(mut self, r: RotationDef) -> Frame {
        self.0.rotation.push(r);
        self
    }

    /// Appends a rotation about the current x axis.
    pub fn rotate_x(self, angle: impl Into<String>) -> Frame {
        self.rotate(RotationDef::X(angle.into()))
    }

    /// Appends a rotation about the current y axis.
    pub fn rotate_y(self, angle: impl Into<String>) -> Frame {
        self.rotate(RotationDef::Y(angle.into()))
    }

    /// Appends a rotation about the current z axis.
    pub fn rotate_z(self, angle: impl Into<String>) -> Frame {
        self.rotate(RotationDef::Z(angle.into()))
    }

    /// The definition, as a RON file would give it.
    pub fn into_def(self) -> FrameDef {
        self.0
    }
}

/// A body under construction: a point mass at the frame's origin until told otherwise.
#[derive(Clone, Debug)]
pub struct Body(BodyDef);

impl Body {
    /// A point mass `mass` (an expression in the parameters) at the origin of `frame`.
    pub fn new(name: impl Into<String>, frame: impl Into<String>, mass: impl Into<String>) -> Body {
        Body(BodyDef { name: name.into(), frame: frame.into(), mass: mass.into(), com: None, inertia: InertiaDef::PointMass, shape: None })
    }

    /// The centre of mass in the frame's components.
    pub fn com(mut self, c: [&str; 3]) -> Body {
        self.0.com = Some(c.iter().map(|s| s.to_string()).collect());
        self
    }

    /// A diagonal inertia about the centre of mass, in the frame's axes.
    pub fn diagonal(self, d: [&str; 3]) -> Body {
        self.inertia(InertiaDef::Diagonal(d.iter().map(|s| s.to_string()).collect()))
    }

    /// Any inertia about the centre of mass.
    pub fn inertia(mut self, inertia: InertiaDef) -> Body {
        self.0.inertia = inertia;
        self
    }

    /// How the body is drawn (the animation only).
    ///
    /// ```
    /// use generator::model::{builder::Body, ShapeDef};
    /// let rod = Body::new("rod", "rod", "m").shape(ShapeDef::Cylinder { radius: "0.02".into(), length: "l".into(), origin: None, rpy: None });
    /// assert!(rod.into_def().shape.is_some());
    /// ```
    pub fn shape(mut self, shape: ShapeDef) -> Body {
        self.0.shape = Some(shape);
        self
    }

    /// The definition, as a RON file would give it.
    pub fn into_def(self) -> BodyDef {
        self.0
    }
}

/// Builds a [`Model`] in code (see the module docs).
#[derive(Clone, Debug)]
pub struct ModelBuilder {
    def: ModelFile,
}

fn strings<I: IntoIterator<Item = S>, S: Into<String>>(items: I) -> Vec<String> {
    items.into_iter().map(Into::into).collect()
}

fn map<I: IntoIterator<Item = (K, V)>, K: Into<String>, V: Into<String>>(items: I) -> IndexMap<String, String> {
    items.into_iter().map(|(k, v)| (k.into(), v.into())).collect()
}

impl ModelBuilder {
    /// An empty model called `name` (the generated module's name).
    pub fn new(name: impl Into<String>) -> ModelBuilder {
        ModelBuilder {
            def: ModelFile {
                name: name.into(),
                description: String::new(),
                parameters: IndexMap::new(),
                inputs: IndexMap::new(),
                coordinates: Vec::new(),
                time_functions: IndexMap::new(),
                frames: Vec::new(),
                bodies: Vec::new(),
                constraints: Vec::new(),
                forces: Vec::new(),
                urdf: None,
                quasi_velocities: QuasiVelocityDef { full: Vec::new(), reduced: Vec::new() },
                ignorable: IgnorableDef::Auto,
                initial: None,
                simulation: None,
                events: Vec::new(),
                scenery: None,
                units: IndexMap::new(),
                emit: EmitDef::default(),
            },
        }
    }

    /// Includes a robot read from a URDF file (`path` as given: relative to the working
    /// directory, or absolute), as a RON model's `urdf: Urdf(...)` does: the robot's
    /// parameters, coordinates, frames, bodies and forces come first, this builder's after them;
    /// its quasi-velocities, unless this builder gives some, are the robot's followed by the
    /// rates of this builder's coordinates (`docs/robots.md`).
    ///
    /// ```no_run
    /// use generator::model::builder::{Body, Frame, ModelBuilder};
    /// use generator::model::{Base, UrdfOptions};
    /// // A panda with a 0.5 kg payload between its fingers.
    /// let model = ModelBuilder::new("panda_with_payload")
    ///     .urdf("panda.urdf", &UrdfOptions { base: Base::Fixed, ..UrdfOptions::default() })
    ///     .parameter("m_payload", 0.5)
    ///     .frame(Frame::new("payload", "panda_hand").translation(["0", "0", "0.1"]))
    ///     .body(Body::new("payload", "payload", "m_payload"))
    ///     .build()
    ///     .unwrap();
    /// assert_eq!(model.m(), 8);
    /// ```
    pub fn urdf(mut self, path: impl Into<String>, options: &super::urdf::UrdfOptions) -> ModelBuilder {
        self.def.urdf = Some(UrdfInclude { file: path.into(), base: options.base, gravity: Some(options.gravity), limits: options.limits });
        self
    }

    /// Free text describing the model.
    pub fn description(mut self, text: impl Into<String>) -> ModelBuilder {
        self.def.description = text.into();
        self
    }

    /// A parameter with its value.
    pub fn parameter(mut self, name: impl Into<String>, value: f64) -> ModelBuilder {
        self.def.parameters.insert(name.into(), value);
        self
    }

    /// Shapes drawn fixed to the world (`scenery` in RON; the animation only): a second call
    /// adds to the first.
    ///
    /// ```
    /// use generator::model::{builder::ModelBuilder, ShapeDef};
    /// let table = ShapeDef::Box { size: vec!["1".into(), "1".into(), "0.05".into()], origin: None, rpy: None };
    /// let b = ModelBuilder::new("m").scenery(table);
    /// assert!(b.to_ron().contains("scenery: Box("));
    /// ```
    pub fn scenery(mut self, shape: ShapeDef) -> ModelBuilder {
        self.def.scenery = Some(match self.def.scenery.take() {
            None => shape,
            Some(ShapeDef::Compound(mut parts)) => {
                parts.push(shape);
                ShapeDef::Compound(parts)
            }
            Some(first) => ShapeDef::Compound(vec![first, shape]),
        });
        self
    }

    /// The unit of a coordinate or a parameter, for plots and tables (`units` in RON).
    pub fn unit(mut self, name: impl Into<String>, unit: impl Into<String>) -> ModelBuilder {
        self.def.units.insert(name.into(), unit.into());
        self
    }

    /// The next generalized coordinate.
    pub fn coordinate(mut self, name: impl Into<String>) -> ModelBuilder {
        self.def.coordinates.push(name.into());
        self
    }

    /// A named function of time, used as `name(t)`.
    pub fn time_function(mut self, name: impl Into<String>, expr: impl Into<String>) -> ModelBuilder {
        self.def.time_functions.insert(name.into(), expr.into());
        self
    }

    /// A frame of the kinematic tree.
    pub fn frame(mut self, frame: Frame) -> ModelBuilder {
        self.def.frames.push(frame.0);
        self
    }

    /// A body.
    pub fn body(mut self, body: Body) -> ModelBuilder {
        self.def.bodies.push(body.0);
        self
    }

    /// A velocity constraint `expr = 0`, linear in the rates.
    pub fn velocity_constraint(mut self, name: impl Into<String>, expr: impl Into<String>) -> ModelBuilder {
        self.def.constraints.push(ConstraintDef::Velocity { name: name.into(), expr: expr.into() });
        self
    }

    /// A holonomic constraint `expr(q, t) = 0`.
    pub fn position_constraint(mut self, name: impl Into<String>, expr: impl Into<String>) -> ModelBuilder {
        self.def.constraints.push(ConstraintDef::Position { name: name.into(), expr: expr.into() });
        self
    }

    /// Any force or potential.
    pub fn force(mut self, force: ForceDef) -> ModelBuilder {
        self.def.forces.push(force);
        self
    }

    /// Uniform gravity: the acceleration vector in world components.
    pub fn gravity(self, vector: [&str; 3]) -> ModelBuilder {
        self.force(ForceDef::Gravity { vector: strings(vector) })
    }

    /// The quasi-velocities: `full` (p of them) for Maggi and Kane, `reduced` (p - s) for the
    /// reduced Volterra method.
    pub fn quasi_velocities<F, R, S, T>(mut self, full: F, reduced: R) -> ModelBuilder
    where
        F: IntoIterator<Item = S>,
        R: IntoIterator<Item = T>,
        S: Into<String>,
        T: Into<String>,
    {
        self.def.quasi_velocities = QuasiVelocityDef { full: strings(full), reduced: strings(reduced) };
        self
    }

    /// Declares the ignorable coordinates the reduced method uses (each is verified).
    pub fn ignorable<I: IntoIterator<Item = S>, S: Into<String>>(mut self, names: I) -> ModelBuilder {
        self.def.ignorable = IgnorableDef::Declared(strings(names));
        self
    }

    /// The initial coordinates and rates of the reference run, as expressions.
    pub fn initial<Q, D, K1, V1, K2, V2>(mut self, q: Q, qdot: D) -> ModelBuilder
    where
        Q: IntoIterator<Item = (K1, V1)>,
        D: IntoIterator<Item = (K2, V2)>,
        K1: Into<String>,
        V1: Into<String>,
        K2: Into<String>,
        V2: Into<String>,
    {
        self.def.initial = Some(InitialDef { q: map(q), qdot: map(qdot) });
        self
    }

    /// The reference run: from 0 to `t_end`, output every `dt_out`.
    pub fn simulation(mut self, t_end: f64, dt_out: f64) -> ModelBuilder {
        self.def.simulation = Some(SimulationDef { t_start: 0.0, t_end, dt_out, paper: false });
        self
    }

    /// What the generated module contains.
    pub fn emit(mut self, emit: EmitDef) -> ModelBuilder {
        self.def.emit = emit;
        self
    }

    /// The definition built so far.
    pub fn definition(&self) -> &ModelFile {
        &self.def
    }

    /// The model as RON text, in the format of `models/`.
    pub fn to_ron(&self) -> String {
        super::to_ron(&self.def)
    }

    /// Validates the model exactly as a file would be (see the module docs).
    pub fn build(&self) -> Result<Model, ModelError> {
        from_source(&format!("<builder {}>", self.def.name), &self.to_ron())
    }
}
