//! The RON model format, as written by users. Every struct denies unknown fields so a typo is
//! an error, not a silently ignored line. Expressions are strings in the language of
//! [`crate::symbolic::parse`].

use indexmap::IndexMap;
use serde::{Deserialize, Deserializer, Serialize};

/// A map whose keys must be distinct: a key written twice is an error, not a silent
/// overwrite of the first value.
fn unique_keys<'de, D, V>(d: D) -> Result<IndexMap<String, V>, D::Error>
where
    D: Deserializer<'de>,
    V: Deserialize<'de>,
{
    struct Visitor<V>(std::marker::PhantomData<V>);
    impl<'de, V: Deserialize<'de>> serde::de::Visitor<'de> for Visitor<V> {
        type Value = IndexMap<String, V>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a map with distinct keys")
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
            let mut out = IndexMap::new();
            while let Some((k, v)) = map.next_entry::<String, V>()? {
                if out.contains_key(&k) {
                    return Err(serde::de::Error::custom(format!("the key `{k}` is given twice")));
                }
                out.insert(k, v);
            }
            Ok(out)
        }
    }
    d.deserialize_map(Visitor(std::marker::PhantomData))
}

/// A model file.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename = "Model")]
pub struct ModelFile {
    /// Identifier of the model (used for generated module names).
    pub name: String,
    /// Free text.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub description: String,
    /// Parameter names and values. Every symbol must be bound here or be a coordinate.
    #[serde(deserialize_with = "unique_keys")]
    pub parameters: IndexMap<String, f64>,
    /// Inputs and their nominal values: parameters that the runtime may set at every call of
    /// the model's functions (a controller, a time series). Expressions use them as parameters.
    #[serde(default, skip_serializing_if = "IndexMap::is_empty", deserialize_with = "unique_keys")]
    pub inputs: IndexMap<String, f64>,
    /// Generalized coordinates, in order.
    pub coordinates: Vec<String>,
    /// Named functions of time: name -> expression in `t` (e.g. a prescribed force `F(t)`).
    #[serde(default, skip_serializing_if = "IndexMap::is_empty", deserialize_with = "unique_keys")]
    pub time_functions: IndexMap<String, String>,
    /// The kinematic tree; `world` is the implicit root.
    pub frames: Vec<FrameDef>,
    /// Rigid bodies and point masses.
    pub bodies: Vec<BodyDef>,
    /// Kinematic constraints.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub constraints: Vec<ConstraintDef>,
    /// Applied forces and potentials.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub forces: Vec<ForceDef>,
    /// A URDF robot this model starts from (its path relative to this file, and how it is
    /// read): its coordinates, frames, bodies, forces and quasi-velocities come first, and
    /// this file's items are added to them (as [`urdf_model_file`](crate::model::urdf_model_file) reads it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub urdf: Option<UrdfInclude>,
    /// The choice of quasi-velocities (with `urdf` and none given: the robot's, followed by the
    /// rates of this file's own coordinates).
    #[serde(default, skip_serializing_if = "QuasiVelocityDef::is_empty")]
    pub quasi_velocities: QuasiVelocityDef,
    /// Which coordinates are ignorable.
    #[serde(default)]
    pub ignorable: IgnorableDef,
    /// The initial state of the reference run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub initial: Option<InitialDef>,
    /// The reference run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub simulation: Option<SimulationDef>,
    /// Events: functions of `t`, `q` and `q'` whose zero crossings a run locates, and what
    /// happens there.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub events: Vec<EventDef>,
    /// What is drawn fixed to the world (a table, a pedestal, a fixed-base robot's base link's
    /// visuals): shapes placed in the world's frame, drawn by the animation only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scenery: Option<ShapeDef>,
    /// The unit of a coordinate or a parameter, for plots and tables: `{"x": "m", "theta":
    /// "rad", "M": "kg"}` (text shown as given; the equations do not read it).
    #[serde(default, skip_serializing_if = "IndexMap::is_empty", deserialize_with = "unique_keys")]
    pub units: IndexMap<String, String>,
    /// What the generated module contains (default: everything, runtime parameters).
    #[serde(default)]
    pub emit: EmitDef,
}

/// What to emit: the model "models only what a scene requires".
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename = "Emit")]
pub struct EmitDef {
    /// Formulations to emit, each as a module with its own right-hand side.
    #[serde(default = "all_formulations")]
    pub formulations: Vec<FormulationDef>,
    /// Extra functions beside the right-hand sides.
    #[serde(default = "all_functions")]
    pub functions: Vec<FunctionDef>,
    /// `Runtime`: parameters are fields of `Params`; `Baked`: folded in as constants.
    #[serde(default)]
    pub parameters: ParameterDef,
    /// Integrate the ignorable coordinates in the reduced method (`false`: state `[q_NI; u_NI]`,
    /// allowed when nothing in it depends on them).
    #[serde(default = "yes")]
    pub integrate_ignorable: bool,
    /// Above this many common subexpressions, a function's work is split into helpers.
    #[serde(default = "default_max_lets")]
    pub max_lets_per_function: usize,
    /// Emit each formulation's exact `jacobian` (the right-hand side and its derivative by
    /// the state), which the stiff integrator and linearization use (default: off; they fall
    /// back to finite differences without it).
    #[serde(default)]
    pub jacobian: bool,
    /// Emit each formulation's `parameter_jacobian` (the right-hand side's derivative by the
    /// runtime parameters, for sensitivities and input matrices).
    #[serde(default)]
    pub parameter_jacobian: bool,
}

impl Default for EmitDef {
    fn default() -> Self {
        EmitDef {
            formulations: all_formulations(),
            functions: all_functions(),
            parameters: ParameterDef::Runtime,
            integrate_ignorable: true,
            max_lets_per_function: default_max_lets(),
            jacobian: false,
            parameter_jacobian: false,
        }
    }
}

fn all_formulations() -> Vec<FormulationDef> {
    vec![FormulationDef::Lagrange, FormulationDef::Maggi, FormulationDef::Kane, FormulationDef::ReducedVolterra]
}

fn all_functions() -> Vec<FunctionDef> {
    vec![FunctionDef::Energy, FunctionDef::WorkRate, FunctionDef::Momenta, FunctionDef::Constraints]
}

fn yes() -> bool {
    true
}

fn default_max_lets() -> usize {
    2000
}

/// A formulation of the equations of motion.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Deserialize, Serialize)]
pub enum FormulationDef {
    /// Lagrange's equations with multipliers: state `[q; q']`, m equations (+ r multipliers).
    Lagrange,
    /// Maggi's equations: state `[q; q']`, m equations, no multipliers.
    Maggi,
    /// Kane / Gibbs-Appell (standard Volterra): state `[q; u]`, p equations.
    Kane,
    /// The paper's reduced Volterra equations: state `[q; u_NI]`, p - s equations.
    ReducedVolterra,
}

impl FormulationDef {
    /// The seam's kind of this formulation.
    pub fn kind(self) -> seam::FormulationKind {
        match self {
            FormulationDef::Lagrange => seam::FormulationKind::Lagrange,
            FormulationDef::Maggi => seam::FormulationKind::Maggi,
            FormulationDef::Kane => seam::FormulationKind::Kane,
            FormulationDef::ReducedVolterra => seam::FormulationKind::ReducedVolterra,
        }
    }

    /// The formulation of the seam's `kind`.
    pub fn of(kind: seam::FormulationKind) -> FormulationDef {
        match kind {
            seam::FormulationKind::Lagrange => FormulationDef::Lagrange,
            seam::FormulationKind::Maggi => FormulationDef::Maggi,
            seam::FormulationKind::Kane => FormulationDef::Kane,
            seam::FormulationKind::ReducedVolterra => FormulationDef::ReducedVolterra,
        }
    }
}

/// An extra emitted function.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Deserialize, Serialize)]
pub enum FunctionDef {
    /// `energy(t, q, qdot, params)`: T + V.
    Energy,
    /// `work_rate(t, q, qdot, params)`: `Q . q'`, the power of the non-potential forces.
    WorkRate,
    /// `momenta(t, q, qdot, params)`: the generalized momenta of the ignorable coordinates.
    Momenta,
    /// `constraint_residuals` (velocity level) and `position_residuals` (holonomic).
    Constraints,
}

/// How parameters reach the emitted code.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
pub enum ParameterDef {
    /// Fields of `Params`, set at runtime (sweepable).
    #[default]
    Runtime,
    /// Folded into the code as constants (fewer operations).
    Baked,
}

/// A frame: its parent frame moved by `translation` (in parent components) and turned by the
/// `rotation` sequence (applied left to right, each about the current axes).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename = "Frame")]
pub struct FrameDef {
    pub name: String,
    pub parent: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub translation: Option<Vec<String>>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub rotation: Vec<RotationDef>,
}

/// An elementary rotation by an angle expression, or the ZYX Euler shorthand
/// `EulerZYX(psi, theta, phi)` = `[Z(psi), Y(theta), X(phi)]`, `R = Rz Ry Rx`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub enum RotationDef {
    X(String),
    Y(String),
    Z(String),
    EulerZYX(String, String, String),
    /// Euler parameters `(e0, e1, e2, e3)`, the scalar first: the attitude without a singular
    /// configuration. The frame's only rotation; the model keeps `e0^2 + e1^2 + e2^2 + e3^2 = 1`
    /// as a `Position` constraint of its own.
    Quaternion(String, String, String, String),
    /// About a constant unit axis `[x, y, z]` (in the current axes) by an angle: a joint of any
    /// direction (a URDF joint's `axis`).
    Axis(Vec<String>, String),
    /// A constant rotation, its rows in the current axes' components (the columns are the new
    /// axes): a URDF joint's `rpy`. Orthonormal with determinant 1.
    Matrix(Vec<Vec<String>>),
}

/// A body attached to a frame.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename = "Body")]
pub struct BodyDef {
    pub name: String,
    pub frame: String,
    pub mass: String,
    /// Centre of mass in the frame's components (default: the frame's origin).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub com: Option<Vec<String>>,
    pub inertia: InertiaDef,
    /// How the body is drawn (the animation only: the dynamics take the mass and inertia);
    /// without one it is drawn as its equivalent-inertia box.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape: Option<ShapeDef>,
}

/// A body's drawn geometry, in its frame: each solid placed at `origin` (default the frame's
/// origin) and turned by `rpy` (roll, pitch, yaw about the fixed x, y, z axes, URDF's
/// convention; default none). Sizes are expressions in the parameters, positive.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub enum ShapeDef {
    /// A box of full sides `size` along the placed x, y and z axes.
    Box {
        size: Vec<String>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        origin: Option<Vec<String>>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        rpy: Option<Vec<String>>,
    },
    /// A cylinder along the placed z axis, centred on the origin.
    Cylinder {
        radius: String,
        length: String,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        origin: Option<Vec<String>>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        rpy: Option<Vec<String>>,
    },
    /// A sphere centred on the origin.
    Sphere {
        radius: String,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        origin: Option<Vec<String>>,
    },
    /// A cylinder along the placed z axis with a hemisphere on each end: `length` between the
    /// hemispheres' centres.
    Capsule {
        radius: String,
        length: String,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        origin: Option<Vec<String>>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        rpy: Option<Vec<String>>,
    },
    /// A triangle mesh read from a file, STL (binary or text), COLLADA (`.dae`) or Wavefront
    /// OBJ by its extension, `file` relative to the model
    /// file's folder (or absolute), its vertices multiplied by `scale` (default 1, 1, 1: a mesh
    /// drawn in millimetres takes `["0.001", "0.001", "0.001"]`). Drawn simplified to at most
    /// 4,000 triangles (`mesh::MAX_DRAWN_TRIANGLES`).
    Mesh {
        file: String,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        scale: Option<Vec<String>>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        origin: Option<Vec<String>>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        rpy: Option<Vec<String>>,
    },
    /// Several solids (a URDF link's visuals, and those of the links merged into it).
    Compound(Vec<ShapeDef>),
}

impl ShapeDef {
    /// The same shapes with each mesh's relative `file` put under `dir` (a model included from
    /// another folder).
    ///
    /// ```
    /// use generator::model::ShapeDef;
    /// let mut s = ShapeDef::Mesh { file: "hand.stl".into(), scale: None, origin: None, rpy: None };
    /// s.rebase_meshes(std::path::Path::new("robots/arm"));
    /// assert!(matches!(&s, ShapeDef::Mesh { file, .. } if file == "robots/arm/hand.stl"));
    /// ```
    pub fn rebase_meshes(&mut self, dir: &std::path::Path) {
        match self {
            ShapeDef::Compound(parts) => parts.iter_mut().for_each(|p| p.rebase_meshes(dir)),
            ShapeDef::Mesh { file, .. } if std::path::Path::new(file.as_str()).is_relative() => *file = dir.join(file.as_str()).to_string_lossy().into_owned(),
            _ => {}
        }
    }
}

/// Inertia about the centre of mass, in the body frame.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub enum InertiaDef {
    /// No rotational inertia.
    PointMass,
    /// `diag(Ixx, Iyy, Izz)`.
    Diagonal(Vec<String>),
    /// The paper's Eq. (75): `[[Ixx, -Ixy, -Ixz], [-Ixy, Iyy, -Iyz], [-Ixz, -Iyz, Izz]]`.
    Products { ixx: String, iyy: String, izz: String, ixy: String, ixz: String, iyz: String },
    /// The full symmetric matrix, as written.
    Matrix(Vec<Vec<String>>),
}

/// A kinematic constraint.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub enum ConstraintDef {
    /// Velocity level, `expr = 0`, linear in the velocities `q'` (nonholonomic or not).
    Velocity { name: String, expr: String },
    /// Position level, `expr(q, t) = 0` (holonomic); differentiated by the generator.
    Position { name: String, expr: String },
    /// A wheel (a thin disk of `radius` about `center`, turning about `axle`, both in
    /// `frame`'s components; `frame` turns with the wheel) rolling without slip on the ground
    /// plane `z = 0` of the world: the generator finds the contact point and emits the two
    /// no-slip constraints `{name}_x`, `{name}_y`, and the height constraint `{name}_height`
    /// where the frames do not already keep the wheel on the ground.
    Rolling {
        name: String,
        frame: String,
        radius: String,
        axle: Vec<String>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        center: Option<Vec<String>>,
    },
}

/// An applied force or a potential.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub enum ForceDef {
    /// Uniform gravity on every body: the acceleration vector in world components.
    Gravity { vector: Vec<String> },
    /// A force at a point fixed in a frame, with components in `expressed_in` (default world).
    PointForce {
        name: String,
        frame: String,
        point: Vec<String>,
        force: Vec<String>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        expressed_in: Option<String>,
    },
    /// A torque on a body, in body-frame components.
    Torque { name: String, body: String, torque: Vec<String> },
    /// A linear spring between two points fixed in frames.
    Spring { name: String, frame_a: String, point_a: Vec<String>, frame_b: String, point_b: Vec<String>, stiffness: String, rest_length: String },
    /// A linear damper between two points fixed in frames.
    Damper { name: String, frame_a: String, point_a: Vec<String>, frame_b: String, point_b: Vec<String>, damping: String },
    /// Generalized forces given directly: coordinate -> expression.
    Generalized {
        name: String,
        #[serde(deserialize_with = "unique_keys")]
        components: IndexMap<String, String>,
    },
    /// A potential energy given directly.
    Potential { name: String, expr: String },
}

/// Quasi-velocities: `full` has p of them (Maggi, Kane/Gibbs-Appell); `reduced` has p - s
/// (the reduced Volterra method). Expressions in `q`, `q'`, `t` and `omega_x(body)`,
/// `omega_y(body)`, `omega_z(body)` (body-frame angular velocity components).
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename = "QuasiVelocities")]
pub struct QuasiVelocityDef {
    pub full: Vec<String>,
    pub reduced: Vec<String>,
}

impl QuasiVelocityDef {
    /// No quasi-velocity given.
    pub fn is_empty(&self) -> bool {
        self.full.is_empty() && self.reduced.is_empty()
    }
}

/// How the robot's root link is held.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
pub enum Base {
    /// Fixed to the world (an arm on a table).
    #[default]
    Fixed,
    /// Free: three translations and a unit quaternion (a humanoid, a quadruped, a satellite).
    Floating,
}

/// What the joints' `limit`s become.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
pub enum LimitAction {
    /// Nothing in the equations: `inspect` lists them.
    #[default]
    Report,
    /// Events that record each crossing of a limit.
    Record,
    /// Events that stop the run at the first limit reached.
    Stop,
}

/// A URDF a model starts from: `urdf: Urdf(file: "robot.urdf", base: Floating)`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename = "Urdf")]
pub struct UrdfInclude {
    /// The URDF's path, relative to the model file.
    pub file: String,
    #[serde(default)]
    pub base: Base,
    /// Gravity in world components (default `["0", "0", "-9.81"]`; zeros for none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gravity: Option<[f64; 3]>,
    #[serde(default)]
    pub limits: LimitAction,
}

/// Ignorable coordinates: found automatically, or declared (and verified).
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub enum IgnorableDef {
    #[default]
    Auto,
    Declared(Vec<String>),
}

/// Initial coordinates and velocities: expressions in the parameters; velocity expressions may
/// also use the initial coordinates and other initial velocities (`theta1'`).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename = "Initial")]
pub struct InitialDef {
    #[serde(deserialize_with = "unique_keys")]
    pub q: IndexMap<String, String>,
    #[serde(deserialize_with = "unique_keys")]
    pub qdot: IndexMap<String, String>,
}

/// An event: `Event(name: "floor", when: "y", direction: Falling, action: Reset(qdot: {"y":
/// "-e*y'"}))`. `when` is an expression in `t`, the coordinates, their rates and the parameters;
/// the event happens where it crosses zero in `direction`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename = "Event")]
pub struct EventDef {
    pub name: String,
    pub when: String,
    #[serde(default)]
    pub direction: DirectionDef,
    pub action: ActionDef,
}

/// Which way `when` must cross zero.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub enum DirectionDef {
    Rising,
    Falling,
    #[default]
    Either,
}

/// What happens at an event: the run stops, the crossing is recorded, or the coordinates and
/// rates named in `Reset` take new values (expressions in the values just before), the others
/// keeping theirs.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub enum ActionDef {
    Stop,
    Record,
    Reset {
        #[serde(default, deserialize_with = "unique_keys", skip_serializing_if = "IndexMap::is_empty")]
        q: IndexMap<String, String>,
        #[serde(default, deserialize_with = "unique_keys", skip_serializing_if = "IndexMap::is_empty")]
        qdot: IndexMap<String, String>,
    },
}

/// The reference run.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields, rename = "Simulation")]
pub struct SimulationDef {
    #[serde(default)]
    pub t_start: f64,
    pub t_end: f64,
    pub dt_out: f64,
    /// Run with the paper's integrator settings by default (DOPRI5, rtol 1e-3, atol 1e-6):
    /// the paper's scenes say so; other models get tight settings.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub paper: bool,
}
