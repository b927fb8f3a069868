//! Robots described in URDF, read as models: each moving joint a coordinate named after it, each
//! link a body (links fixed to one another merged into one, exactly), the base fixed to the world
//! or free (six degrees of freedom, its attitude in a unit quaternion, its angular velocity a
//! quasi-velocity), gravity along `-z` unless set. The result is a [`ModelFile`], as a RON file
//! would give; every error of the robot's file is located in it (line and column, the element).
//!
//! The XML is parsed by `roxmltree`, which keeps every element's place in the text: `urdf-rs`
//! (serde) gives the values without their places, and a wrong joint type, a loop or a missing
//! link could then not be shown where it is.
//!
//! What is read, and how (`docs/robots.md`):
//! - joints `revolute`, `continuous`, `prismatic` (one coordinate each, named after the joint;
//!   its `origin` xyz/rpy and an `axis` of any direction), `fixed` (the child merged into its
//!   parent: mass, centre of mass and inertia combined); a `mimic` joint follows its master
//!   (no coordinate of its own); `floating` and `planar` joints, closed loops and several roots
//!   are refused, located;
//! - links' `inertial` (mass, the centre of mass `origin` with its own rotation, the inertia
//!   tensor); `visual` boxes, cylinders, spheres and meshes (STL, COLLADA or OBJ files, where
//!   found) become the body's drawn shapes, `collision` is not read;
//! - `limit` (lower, upper) becomes events on request ([`LimitAction`]); `dynamics` `damping`
//!   a generalized force `-damping q'` (its friction is not modelled, and said so);
//! - the parameters are each moving body's mass (`mass_<link>`) and each damped joint's
//!   damping (`damping_<joint>`); names that are not identifiers have their other characters
//!   replaced by `_`.
//!
//! ```
//! use generator::model::{UrdfOptions, urdf_model_file as model_file};
//! let xml = r#"<robot name="arm">
//!   <link name="base"/>
//!   <link name="upper"><inertial><mass value="2"/><origin xyz="0 0 0.5"/>
//!     <inertia ixx="0.1" iyy="0.1" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
//!   <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
//!     <origin xyz="0 0 0.1"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
//! </robot>"#;
//! let def = model_file("arm.urdf", xml, &UrdfOptions::default()).unwrap();
//! assert_eq!(def.coordinates, ["shoulder"]);
//! assert!(def.parameters.contains_key("mass_upper"));
//! let model = generator::model::from_source("arm.urdf", &generator::model::to_ron(&def)).unwrap();
//! assert_eq!(model.m(), 1);
//! ```

use super::error::{ErrorKind, ModelError};
use super::schema::*;
use indexmap::IndexMap;
use std::collections::{BTreeMap, HashMap, HashSet, VecDeque};

/// A floating base's coordinates: the root link's position in the world.
pub const BASE_POSITION: [&str; 3] = ["base_x", "base_y", "base_z"];
/// A floating base's coordinates: the root link's attitude, a unit quaternion `(w, x, y, z)`
/// turning the link's axes into the world's.
pub const BASE_ATTITUDE: [&str; 4] = ["base_qw", "base_qx", "base_qy", "base_qz"];

/// The rates the coordinates of a robot on a floating base take when the whole robot turns
/// about the world axis `axis` at unit rate, at `q`: the base's position turns (`axis x r`), its
/// attitude turns on the left (`(0, axis) q / 2`), the joints stay. The momentum conjugate to
/// it is the angular momentum about that axis (`runtime::monitor::momentum_along`). `None`
/// when the coordinates have no floating base.
///
/// ```
/// use generator::model::world_rotation;
/// let names: Vec<String> = ["base_x", "base_y", "base_z", "base_qw", "base_qx", "base_qy", "base_qz", "elbow"].map(String::from).into();
/// let q = [1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.3];
/// let xi = world_rotation(&names, &q, [0.0, 0.0, 1.0]).unwrap();
/// assert_eq!(xi, [0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0]);
/// ```
pub fn world_rotation(coordinates: &[String], q: &[f64], axis: [f64; 3]) -> Option<Vec<f64>> {
    let at = |name: &str| coordinates.iter().position(|c| c == name);
    let r: Vec<usize> = BASE_POSITION.iter().map(|n| at(n)).collect::<Option<_>>()?;
    let e: Vec<usize> = BASE_ATTITUDE.iter().map(|n| at(n)).collect::<Option<_>>()?;
    let (p, [w, x, y, z]) = ([q[r[0]], q[r[1]], q[r[2]]], [q[e[0]], q[e[1]], q[e[2]], q[e[3]]]);
    let [a, b, c] = axis;
    let mut xi = vec![0.0; q.len()];
    for (&i, v) in r.iter().zip([b * p[2] - c * p[1], c * p[0] - a * p[2], a * p[1] - b * p[0]]) {
        xi[i] = v;
    }
    for (&i, v) in e.iter().zip([-(a * x + b * y + c * z), a * w + b * z - c * y, b * w + c * x - a * z, c * w + a * y - b * x]) {
        xi[i] = v / 2.0;
    }
    Some(xi)
}

// The base and the limits are words of the model format (a RON model that includes a URDF
// names them too): they live with its schema.
pub use super::schema::{Base, LimitAction};

/// URDF options given for a model that is not a URDF file, which would not read them (a RON
/// model that includes a robot sets them in its `urdf` section).
#[derive(Debug, thiserror::Error)]
#[error(
    "{} {} read for a URDF robot only, and `{model}` is not a URDF file: {} would be ignored\n  help: leave {} out; a RON model that includes a robot sets its base, gravity and limits in its `urdf: Urdf(file: ..., base: Floating, gravity: (0.0, 0.0, 0.0), limits: Stop)` section",
    given.join(", "), if given.len() == 1 { "is" } else { "are" }, if given.len() == 1 { "it" } else { "they" }, if given.len() == 1 { "it" } else { "them" }
)]
pub struct OptionsNotRead {
    /// The options given, as the caller names them (`--base`, `base=`).
    pub given: Vec<&'static str>,
    /// The model as given.
    pub model: String,
}

/// Refuses the options `given` (as the caller names them; empty: none given) for the model
/// `argument` unless it is a URDF file: given for another, they were silently ignored. The
/// command line and Python's `load` both ask here.
///
/// ```
/// use generator::model::refuse_options_unless_urdf;
/// use std::path::Path;
/// assert!(refuse_options_unless_urdf(Path::new("arm.urdf"), vec!["--base"]).is_ok());
/// assert!(refuse_options_unless_urdf(Path::new("cart_pendulum"), vec![]).is_ok());
/// let e = refuse_options_unless_urdf(Path::new("cart_pendulum"), vec!["--base"]).unwrap_err();
/// assert!(e.to_string().starts_with("--base is read for a URDF robot only"));
/// ```
pub fn refuse_options_unless_urdf(argument: &std::path::Path, given: Vec<&'static str>) -> Result<(), OptionsNotRead> {
    if given.is_empty() || super::is_urdf(argument) {
        return Ok(());
    }
    Err(OptionsNotRead { given, model: files::printable_path(argument) })
}

/// How a URDF becomes a model.
#[derive(Clone, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, rename = "Urdf")]
pub struct UrdfOptions {
    #[serde(default)]
    pub base: Base,
    /// Gravity in world components (default `(0, 0, -9.81)`; all zero for none).
    #[serde(default = "default_gravity")]
    pub gravity: [f64; 3],
    #[serde(default)]
    pub limits: LimitAction,
}

fn default_gravity() -> [f64; 3] {
    [0.0, 0.0, -9.81]
}

impl Default for UrdfOptions {
    fn default() -> Self {
        UrdfOptions { base: Base::Fixed, gravity: default_gravity(), limits: LimitAction::Report }
    }
}

/// A 3 x 3 matrix of numbers, row-major.
type M3 = [[f64; 3]; 3];
const IDENTITY: M3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

fn mul(a: &M3, b: &M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

fn transpose(a: &M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| a[j][i]))
}

fn apply(a: &M3, v: &[f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| (0..3).map(|k| a[i][k] * v[k]).sum())
}

fn add(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| a[i] + b[i])
}

/// URDF's `rpy`: fixed-axis roll about x, pitch about y, yaw about z, `R = Rz Ry Rx`.
fn rpy(r: f64, p: f64, y: f64) -> M3 {
    let m = super::shape::rpy_rotation_of([r, p, y].map(quarter_sin_cos));
    std::array::from_fn(|i| std::array::from_fn(|j| m[3 * i + j]))
}

/// Angles this close to a multiple of a quarter turn are read as it (radians): pi/2 written to
/// 11 digits or more (anymal C's 1.57079632679, 4.9e-12 short). Ten times that changes a robot's
/// accelerations by about 1e-11 of themselves (ur5 against Pinocchio, which reads the angle as
/// written), under the 1e-10 `docs/robots/pinocchio_check.py` holds them to.
const QUARTER_TURN_SNAP: f64 = 1e-11;

/// `(sin, cos)` of `angle`, exact where it is within [`QUARTER_TURN_SNAP`] of a multiple of a
/// quarter turn.
fn quarter_sin_cos(angle: f64) -> (f64, f64) {
    let quarters = (angle / std::f64::consts::FRAC_PI_2).round();
    if (angle - quarters * std::f64::consts::FRAC_PI_2).abs() <= QUARTER_TURN_SNAP {
        match (quarters as i64).rem_euclid(4) {
            0 => (0.0, 1.0),
            1 => (1.0, 0.0),
            2 => (0.0, -1.0),
            _ => (-1.0, 0.0),
        }
    } else {
        angle.sin_cos()
    }
}

/// A pose: the rotation (components of the child's axes in the parent's, columns) and the
/// origin's offset, in the parent's components.
#[derive(Clone, Copy, Debug)]
struct Pose {
    r: M3,
    p: [f64; 3],
}

impl Pose {
    const IDENTITY: Pose = Pose { r: IDENTITY, p: [0.0; 3] };

    /// This pose followed by `then` (given in this pose's frame).
    fn then(&self, then: &Pose) -> Pose {
        Pose { r: mul(&self.r, &then.r), p: add(&self.p, &apply(&self.r, &then.p)) }
    }
}

/// A number as a model file writes it: exact where the float is an integer or a short decimal,
/// else its shortest round trip; float noise of an exact `0` or `1` (a rotation by `pi/2`
/// written to 16 digits gives `6e-17`) made exact.
fn num(x: f64) -> String {
    let snapped = [-1.0, 0.0, 1.0].into_iter().find(|k| (x - k).abs() <= 1e-15).unwrap_or(x);
    if snapped == 0.0 {
        return "0".to_string();
    }
    // Fifteen significant digits: a product of the file's numbers in floats carries noise in
    // the sixteenth and seventeenth (`1.0000000000000002`), which as an exact rational would
    // grow every coefficient it meets.
    let rounded: f64 = format!("{snapped:.14e}").parse().expect("a float prints as one");
    format!("{rounded:?}")
}

/// An identifier from a URDF name: other characters made `_`, a leading digit prefixed, a
/// name the expressions reserve suffixed. A joint's coordinate is named so (and suffixed by
/// `_` again while the name is taken).
///
/// ```
/// assert_eq!(generator::model::urdf_ident("arm/elbow-1"), "arm_elbow_1");
/// assert_eq!(generator::model::urdf_ident("2nd"), "j_2nd");
/// assert_eq!(generator::model::urdf_ident("world"), "world_");
/// ```
pub fn ident(name: &str) -> String {
    let mut out: String = name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
    if !out.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_') {
        out.insert(0, 'j');
        out.insert(1, '_');
    }
    if ["t", "pi", "world", "e"].contains(&out.as_str()) {
        out.push('_');
    }
    out
}

/// A link's inertial: mass, centre of mass and inertia about it, in the link's frame.
#[derive(Clone, Copy, Debug)]
struct Inertial {
    mass: f64,
    com: [f64; 3],
    inertia: M3,
}

impl Inertial {
    /// The same mass seen from a frame in which the link's frame is at `pose`.
    fn moved(&self, pose: &Pose) -> Inertial {
        Inertial { mass: self.mass, com: add(&pose.p, &apply(&pose.r, &self.com)), inertia: mul(&mul(&pose.r, &self.inertia), &transpose(&pose.r)) }
    }

    /// Two masses combined: the total mass, the centre of mass, and the inertia about it
    /// (each shifted by the parallel-axis theorem).
    fn combined(&self, other: &Inertial) -> Inertial {
        let mass = self.mass + other.mass;
        let com: [f64; 3] = std::array::from_fn(|i| (self.mass * self.com[i] + other.mass * other.com[i]) / mass);
        let shifted = |part: &Inertial| -> M3 {
            let d: [f64; 3] = std::array::from_fn(|i| part.com[i] - com[i]);
            let d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            std::array::from_fn(|i| std::array::from_fn(|j| part.inertia[i][j] + part.mass * (if i == j { d2 } else { 0.0 } - d[i] * d[j])))
        };
        let (a, b) = (shifted(self), shifted(other));
        Inertial { mass, com, inertia: std::array::from_fn(|i| std::array::from_fn(|j| a[i][j] + b[i][j])) }
    }
}

/// A joint as the file gives it.
struct Joint<'a> {
    name: String,
    kind: &'a str,
    parent: String,
    child: String,
    origin: Pose,
    axis: [f64; 3],
    limit: Option<(f64, f64)>,
    damping: f64,
    friction: f64,
    /// `q = multiplier q_master + offset`: no coordinate of its own.
    mimic: Option<(String, f64, f64, roxmltree::Node<'a, 'a>)>,
    node: roxmltree::Node<'a, 'a>,
}

/// The file's reader: its text and name for errors.
struct Reader<'a> {
    file: &'a str,
    xml: &'a str,
}

impl<'a> Reader<'a> {
    /// An error at `node` of the file.
    fn err(&self, kind: ErrorKind, node: roxmltree::Node, place: &str, message: String, help: &str) -> ModelError {
        let range = node.range();
        // The start tag only: an element's whole text may span the file.
        let end = self.xml[range.start..range.end].find('>').map_or(range.end, |i| range.start + i + 1);
        ModelError::at(kind, self.file, self.xml, Some(range.start..end), place, message, help.to_string())
    }

    /// The attribute `name` of `node` as numbers (`xyz="0 0 1"`), `default` where absent.
    fn numbers<const N: usize>(&self, node: roxmltree::Node, name: &str, default: [f64; N], place: &str) -> Result<[f64; N], ModelError> {
        let Some(text) = node.attribute(name) else { return Ok(default) };
        let values: Vec<f64> = text.split_whitespace().map(|s| s.parse::<f64>()).collect::<Result<_, _>>().map_err(|_| {
            self.err(ErrorKind::BadValue, node, place, format!("`{name}=\"{text}\"` is not {N} numbers"), &format!("give {N} numbers separated by spaces"))
        })?;
        if values.len() != N || values.iter().any(|v| !v.is_finite()) {
            return Err(self.err(
                ErrorKind::BadValue,
                node,
                place,
                format!("`{name}=\"{text}\"` is not {N} finite numbers"),
                &format!("give {N} finite numbers separated by spaces"),
            ));
        }
        Ok(std::array::from_fn(|i| values[i]))
    }

    /// The attribute `name` of `node` as one number.
    fn number(&self, node: roxmltree::Node, name: &str, place: &str) -> Result<Option<f64>, ModelError> {
        match node.attribute(name) {
            None => Ok(None),
            Some(_) => Ok(Some(self.numbers::<1>(node, name, [0.0], place)?[0])),
        }
    }

    /// The pose of an `<origin xyz rpy>` child of `node` (identity without one).
    fn origin(&self, node: roxmltree::Node, place: &str) -> Result<Pose, ModelError> {
        let Some(o) = child(node, "origin") else { return Ok(Pose::IDENTITY) };
        let p = self.numbers(o, "xyz", [0.0; 3], &format!("{place}.origin"))?;
        let [r, pi, y] = self.numbers(o, "rpy", [0.0; 3], &format!("{place}.origin"))?;
        Ok(Pose { r: rpy(r, pi, y), p })
    }

    /// A `<visual>` of link `link`, whose frame is at `at` in its model frame, as a shape in that
    /// frame: a box, cylinder or sphere as given; a mesh where its file (STL, COLLADA or OBJ,
    /// [`super::mesh::MeshFormat`]) is found beside
    /// the URDF (`package://NAME/...` is looked for in the folders above it), named relative to
    /// the URDF's folder; `None` for a mesh not found or of another format, and for geometry of
    /// another kind.
    fn visual(&self, visual: roxmltree::Node, link: &str, at: &Pose, folder: &std::path::Path) -> Result<Option<ShapeDef>, ModelError> {
        let place = format!("link `{link}`.visual");
        let Some(geometry) = child(visual, "geometry") else { return Ok(None) };
        let Some(g) = geometry.children().find(|c| c.is_element()) else { return Ok(None) };
        let pose = at.then(&self.origin(visual, &place)?);
        let positive = |name: &str| -> Result<f64, ModelError> {
            match self.number(g, name, &place)? {
                Some(v) if v > 0.0 && v.is_finite() => Ok(v),
                v => Err(self.err(
                    ErrorKind::BadValue,
                    g,
                    &place,
                    format!("link `{link}`'s visual {} has {name} {}", g.tag_name().name(), v.map_or("missing".to_string(), |v| v.to_string())),
                    &format!("give the {} a positive {name}", g.tag_name().name()),
                )),
            }
        };
        let placed = |p: &Pose| (Some(p.p.iter().map(|x| num(*x)).collect()), Some(rpy_of(&p.r).iter().map(|x| num(*x)).collect()));
        let shape = match g.tag_name().name() {
            "box" => {
                let size = self.numbers(g, "size", [0.0; 3], &place)?;
                if let Some(bad) = size.iter().find(|x| !(**x > 0.0 && x.is_finite())) {
                    return Err(self.err(
                        ErrorKind::BadValue,
                        g,
                        &place,
                        format!("link `{link}`'s visual box has a side {bad}"),
                        "give the box three positive sides",
                    ));
                }
                let (origin, rpy) = placed(&pose);
                ShapeDef::Box { size: size.iter().map(|x| num(*x)).collect(), origin, rpy }
            }
            "cylinder" => {
                let (origin, rpy) = placed(&pose);
                ShapeDef::Cylinder { radius: num(positive("radius")?), length: num(positive("length")?), origin, rpy }
            }
            "sphere" => ShapeDef::Sphere { radius: num(positive("radius")?), origin: placed(&pose).0 },
            "mesh" => {
                let scale = self.numbers(g, "scale", [1.0; 3], &place)?;
                if scale.iter().any(|x| !(*x != 0.0 && x.is_finite())) {
                    return Err(self.err(
                        ErrorKind::BadValue,
                        g,
                        &place,
                        format!("link `{link}`'s visual mesh has scale {} {} {}", scale[0], scale[1], scale[2]),
                        "give the mesh three scale factors other than zero",
                    ));
                }
                // Drawn only where the file is found and reads as a mesh of its format.
                let Some(file) = g.attribute("filename").and_then(|name| mesh_file(name, folder)) else { return Ok(None) };
                let (origin, rpy) = placed(&pose);
                ShapeDef::Mesh { file, scale: Some(scale.iter().map(|x| num(*x)).collect()), origin, rpy }
            }
            _ => return Ok(None),
        };
        Ok(Some(shape))
    }

    fn inertial(&self, link: roxmltree::Node, name: &str) -> Result<Option<Inertial>, ModelError> {
        let Some(node) = child(link, "inertial") else { return Ok(None) };
        let place = format!("link `{name}`.inertial");
        let frame = self.origin(node, &place)?;
        let mass_node = child(node, "mass")
            .ok_or_else(|| self.err(ErrorKind::Syntax, node, &place, format!("link `{name}`'s inertial has no mass"), "add <mass value=\"...\"/>"))?;
        let mass = self.number(mass_node, "value", &place)?.unwrap_or(0.0);
        if mass < 0.0 {
            return Err(self.err(ErrorKind::NonPositiveMass, mass_node, &place, format!("link `{name}` has mass {mass}"), "give a mass of zero or more"));
        }
        let tensor = match child(node, "inertia") {
            None => [[0.0; 3]; 3],
            Some(i) => {
                let v = |k: &str| self.number(i, k, &place).map(|x| x.unwrap_or(0.0));
                let (xx, yy, zz, xy, xz, yz) = (v("ixx")?, v("iyy")?, v("izz")?, v("ixy")?, v("ixz")?, v("iyz")?);
                [[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]]
            }
        };
        // The tensor is given in the inertial frame, turned by its rpy in the link's. Whether
        // it is a rigid body's is checked on the body it becomes part of (a placeholder link of
        // 1e-6 kg fixed to the real one is common, and harmless once merged).
        let inertia = mul(&mul(&frame.r, &tensor), &transpose(&frame.r));
        Ok((mass > 0.0).then_some(Inertial { mass, com: frame.p, inertia }))
    }
}

/// Why an inertia tensor belongs to no rigid body (not symmetric positive semi-definite, or
/// its principal moments break the triangle inequality), if it does not.
///
/// Within `1e-9` of the larger of the tensor's largest entry and `mass` times a millimetre
/// squared: CAD exporters write a point mass's tensor as float noise (iCub's head: all zero but
/// `ixz = 2.4e-35`, a negative principal moment of that size; its ankle: entries of 1e-20
/// breaking the triangle inequality by 1e-20), a billionth of the inertia of that mass spread over
/// a millimetre, which no motion can tell apart from a rigid body's.
fn not_a_body(i: &M3, mass: f64) -> Option<String> {
    let scale = i.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs())).max(mass * 1e-6);
    let tol = 1e-9 * scale.max(f64::MIN_POSITIVE);
    let m = nalgebra_free_eigen(i);
    if m[0] < -tol {
        return Some(format!("it has a negative principal moment ({:e})", m[0]));
    }
    if m[2] > m[0] + m[1] + tol {
        return Some(format!("its largest principal moment ({:e}) exceeds the sum of the other two ({:e})", m[2], m[0] + m[1]));
    }
    None
}

/// The eigenvalues of a symmetric 3 x 3 matrix, ascending (the trigonometric closed form).
fn nalgebra_free_eigen(a: &M3) -> [f64; 3] {
    let p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    let q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
    if p1 == 0.0 {
        let mut d = [a[0][0], a[1][1], a[2][2]];
        d.sort_by(f64::total_cmp);
        return d;
    }
    let p2 = (a[0][0] - q).powi(2) + (a[1][1] - q).powi(2) + (a[2][2] - q).powi(2) + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    let b: M3 = std::array::from_fn(|i| std::array::from_fn(|j| (a[i][j] - if i == j { q } else { 0.0 }) / p));
    let det = b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1]) - b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0])
        + b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]);
    let phi = (det / 2.0).clamp(-1.0, 1.0).acos() / 3.0;
    let largest = q + 2.0 * p * phi.cos();
    let smallest = q + 2.0 * p * (phi + 2.0 * std::f64::consts::PI / 3.0).cos();
    [smallest, 3.0 * q - largest - smallest, largest]
}

fn child<'a>(node: roxmltree::Node<'a, 'a>, tag: &str) -> Option<roxmltree::Node<'a, 'a>> {
    node.children().find(|c| c.has_tag_name(tag))
}

/// The model file of the robot in `xml` (the URDF at `file`), built as `options` say.
pub fn model_file(file: &str, xml: &str, options: &UrdfOptions) -> Result<ModelFile, ModelError> {
    let doc = roxmltree::Document::parse(xml).map_err(|e| {
        let pos = e.pos();
        let at = super::offset_of(xml, pos.row as usize, pos.col as usize);
        ModelError::at(
            ErrorKind::Syntax,
            file,
            xml,
            Some(at..(at + 1).min(xml.len()).max(at)),
            "",
            format!("malformed URDF: {e}"),
            "fix the XML at this place".into(),
        )
    })?;
    let reader = Reader { file, xml };
    let robot = doc.root_element();
    if !robot.has_tag_name("robot") {
        return Err(reader.err(
            ErrorKind::Syntax,
            robot,
            "",
            format!("the root element is <{}>, not <robot>", robot.tag_name().name()),
            "a URDF file holds one <robot>",
        ));
    }
    let robot_name = ident(robot.attribute("name").unwrap_or("robot"));

    // Links, in file order, with their inertials.
    let mut links: IndexMap<String, (roxmltree::Node, Option<Inertial>)> = IndexMap::new();
    for node in robot.children().filter(|n| n.has_tag_name("link")) {
        let name = node.attribute("name").unwrap_or_default().to_string();
        if links.contains_key(&name) {
            return Err(reader.err(
                ErrorKind::Duplicate,
                node,
                &format!("link `{name}`"),
                format!("link `{name}` is defined twice"),
                "give every link its own name",
            ));
        }
        let inertial = reader.inertial(node, &name)?;
        links.insert(name, (node, inertial));
    }

    // Joints.
    let mut joints: Vec<Joint> = Vec::new();
    let mut child_of: HashMap<String, usize> = HashMap::new();
    for node in robot.children().filter(|n| n.has_tag_name("joint")) {
        let name = node.attribute("name").unwrap_or_default().to_string();
        let place = format!("joint `{name}`");
        let kind = node.attribute("type").unwrap_or("");
        match kind {
            "revolute" | "continuous" | "prismatic" | "fixed" => {}
            "floating" | "planar" => {
                return Err(reader.err(
                    ErrorKind::BadValue,
                    node,
                    &place,
                    format!("joint `{name}` is {kind}: a {kind} joint inside a robot is not read"),
                    "give the robot a floating base instead (`--base floating`, `base: Floating`), or split the joint into revolute and prismatic ones",
                ));
            }
            other => {
                return Err(reader.err(
                    ErrorKind::BadValue,
                    node,
                    &place,
                    format!("joint `{name}` has type `{other}`"),
                    "use revolute, continuous, prismatic or fixed",
                ));
            }
        }
        let mimic = match child(node, "mimic") {
            None => None,
            Some(m) => {
                let master = m.attribute("joint").unwrap_or_default().to_string();
                let multiplier = reader.number(m, "multiplier", &place)?.unwrap_or(1.0);
                let offset = reader.number(m, "offset", &place)?.unwrap_or(0.0);
                Some((master, multiplier, offset, m))
            }
        };
        let link_of = |tag: &str| -> Result<String, ModelError> {
            let l = child(node, tag).and_then(|c| c.attribute("link")).ok_or_else(|| {
                reader.err(ErrorKind::Syntax, node, &place, format!("joint `{name}` has no <{tag} link=\"...\"/>"), &format!("name the joint's {tag} link"))
            })?;
            if !links.contains_key(l) {
                return Err(reader.err(
                    ErrorKind::UnknownFrame,
                    node,
                    &place,
                    format!("joint `{name}`'s {tag} `{l}` is not a link of the robot"),
                    "name a link defined by a <link>",
                ));
            }
            Ok(l.to_string())
        };
        let (parent, childl) = (link_of("parent")?, link_of("child")?);
        if let Some(&other) = child_of.get(&childl) {
            return Err(reader.err(
                ErrorKind::FrameCycle,
                node,
                &place,
                format!("link `{childl}` is the child of joints `{}` and `{name}`: the robot closes a loop", joints[other].name),
                "a URDF is a tree: cut the loop at one joint, and close it with a constraint in a RON model that includes this URDF",
            ));
        }
        let origin = reader.origin(node, &place)?;
        let mut axis = child(node, "axis").map_or(Ok([1.0, 0.0, 0.0]), |a| reader.numbers(a, "xyz", [1.0, 0.0, 0.0], &place))?;
        let norm = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
        if kind != "fixed" && !(norm > 0.0) {
            return Err(reader.err(
                ErrorKind::BadValue,
                child(node, "axis").unwrap_or(node),
                &place,
                format!("joint `{name}` has a zero axis"),
                "give the axis a direction",
            ));
        }
        if norm > 0.0 {
            axis = axis.map(|a| a / norm);
        }
        let limit = match (kind, child(node, "limit")) {
            ("revolute" | "prismatic", Some(l)) => match (reader.number(l, "lower", &place)?, reader.number(l, "upper", &place)?) {
                (Some(lo), Some(hi)) if lo < hi => Some((lo, hi)),
                _ => None,
            },
            _ => None,
        };
        let dynamics = child(node, "dynamics");
        let damping = dynamics.map_or(Ok(None), |d| reader.number(d, "damping", &place))?.unwrap_or(0.0);
        let friction = dynamics.map_or(Ok(None), |d| reader.number(d, "friction", &place))?.unwrap_or(0.0);
        if damping < 0.0 {
            return Err(reader.err(
                ErrorKind::BadValue,
                dynamics.unwrap_or(node),
                &place,
                format!("joint `{name}` has damping {damping}"),
                "give a damping of zero or more",
            ));
        }
        child_of.insert(childl.clone(), joints.len());
        joints.push(Joint { name, kind, parent, child: childl, origin, axis, limit, damping, friction, mimic, node });
    }

    // One root: the links that are no joint's child.
    let roots: Vec<&String> = links.keys().filter(|l| !child_of.contains_key(*l)).collect();
    if roots.len() != 1 {
        let node = roots.get(1).map_or(robot, |l| links[*l].0);
        return Err(reader.err(
            ErrorKind::FrameCycle,
            node,
            "robot",
            if roots.is_empty() {
                "every link is a joint's child: the links form a loop, and the robot has no root".to_string()
            } else {
                format!(
                    "the robot has {} roots ({}): its links are not one tree",
                    roots.len(),
                    roots.iter().map(|r| format!("`{r}`")).collect::<Vec<_>>().join(", ")
                )
            },
            "join the trees with a joint, or remove the links that belong to no tree",
        ));
    }
    let root = roots[0].clone();
    let children: HashMap<&str, Vec<usize>> = joints.iter().enumerate().fold(HashMap::new(), |mut m, (k, j)| {
        m.entry(j.parent.as_str()).or_default().push(k);
        m
    });

    // Each link's frame in the model (the nearest ancestor-or-self reached by a moving joint, or
    // the root), and the link's pose in it; joints in breadth-first order from the root.
    let mut frame_of: HashMap<String, (String, Pose)> = HashMap::new();
    // Each link's frame name: its identifier, suffixed by `_` while another link's has it
    // (`arm-1` and `arm_1` both read `arm_1`).
    let mut named: HashSet<String> = HashSet::new();
    let frame_name: HashMap<&str, String> = links
        .keys()
        .map(|l| {
            let mut name = ident(l);
            while !named.insert(name.clone()) {
                name.push('_');
            }
            (l.as_str(), name)
        })
        .collect();
    let root_frame = if options.base == Base::Floating { frame_name[root.as_str()].clone() } else { "world".to_string() };
    frame_of.insert(root.clone(), (root_frame.clone(), Pose::IDENTITY));
    let mut order: Vec<usize> = Vec::new();
    let mut queue: VecDeque<String> = VecDeque::from([root.clone()]);
    let mut reached: HashSet<String> = HashSet::from([root.clone()]);
    while let Some(link) = queue.pop_front() {
        for &k in children.get(link.as_str()).map(Vec::as_slice).unwrap_or(&[]) {
            let j = &joints[k];
            if !reached.insert(j.child.clone()) {
                continue;
            }
            let (frame, pose) = frame_of[&link].clone();
            let joint_pose = pose.then(&j.origin);
            if j.kind == "fixed" {
                frame_of.insert(j.child.clone(), (frame, joint_pose));
            } else {
                frame_of.insert(j.child.clone(), (frame_name[j.child.as_str()].clone(), Pose::IDENTITY));
            }
            order.push(k);
            queue.push_back(j.child.clone());
        }
    }
    // Links no joint reaches from the root sit in a loop of their own.
    if let Some((l, (node, _))) = links.iter().find(|(l, _)| !reached.contains(*l)) {
        return Err(reader.err(
            ErrorKind::FrameCycle,
            *node,
            &format!("link `{l}`"),
            format!("link `{l}` is not reached from the root `{root}`: its joints form a loop"),
            "a URDF is a tree: cut the loop",
        ));
    }

    // The bodies: every link's mass in its model frame, combined per frame.
    let mut bodies: BTreeMap<String, (usize, Inertial)> = BTreeMap::new();
    for (k, (link, (_, inertial))) in links.iter().enumerate() {
        let Some(inertial) = inertial else { continue };
        let (frame, pose) = &frame_of[link];
        let moved = inertial.moved(pose);
        bodies.entry(frame.clone()).and_modify(|(_, b)| *b = b.combined(&moved)).or_insert((k, moved));
    }

    // What each body looks like: its links' visuals, placed in its model frame.
    let mut looks: BTreeMap<String, Vec<ShapeDef>> = BTreeMap::new();
    let folder = std::path::Path::new(file).parent().unwrap_or(std::path::Path::new(""));
    for (link, (node, _)) in &links {
        let (frame, pose) = &frame_of[link];
        for visual in node.children().filter(|c| c.has_tag_name("visual")) {
            if let Some(shape) = reader.visual(visual, link, pose, folder)? {
                looks.entry(frame.clone()).or_default().push(shape);
            }
        }
    }

    // Each body (the links merged into it) is a rigid body's.
    for (frame, (first, b)) in &bodies {
        if let Some(why) = not_a_body(&b.inertia, b.mass) {
            let (link, (node, _)) = links.get_index(*first).expect("a body starts at a link");
            let merged: Vec<&String> = links.keys().filter(|l| frame_of[*l].0 == *frame && links[*l].1.is_some()).collect();
            let at = child(*node, "inertial").and_then(|i| child(i, "inertia")).unwrap_or(*node);
            return Err(reader.err(
                ErrorKind::InertiaNotPsd,
                at,
                &format!("link `{link}`.inertial"),
                format!(
                    "the inertia of {} is no rigid body's: {why}",
                    if merged.len() > 1 { format!("links {} (fixed to one another)", merged.iter().map(|l| format!("`{l}`")).collect::<Vec<_>>().join(", ")) } else { format!("link `{link}`") }
                ),
                "check the values: ixy, ixz, iyz are the tensor's off-diagonal entries (-sum m x y), and each principal moment is at most the sum of the other two",
            ));
        }
    }

    // Moving joints need mass beyond them.
    let mut subtree_mass: HashMap<&str, f64> = HashMap::new();
    for &k in order.iter().rev() {
        let j = &joints[k];
        let own = links[&j.child].1.map_or(0.0, |i| i.mass);
        let below: f64 =
            children.get(j.child.as_str()).map_or(0.0, |ks| ks.iter().map(|c| subtree_mass.get(joints[*c].child.as_str()).copied().unwrap_or(0.0)).sum());
        subtree_mass.insert(j.child.as_str(), own + below);
        if j.kind != "fixed" && !(own + below > 0.0) {
            return Err(reader.err(
                ErrorKind::NonPositiveMass,
                j.node,
                &format!("joint `{}`", j.name),
                format!("joint `{}` moves link `{}` and the links beyond it, which carry no mass: its equation of motion is singular", j.name, j.child),
                &format!("give link `{}` (or a link beyond it) an <inertial>, or make joint `{}` fixed", j.child, j.name),
            ));
        }
    }
    if options.base == Base::Floating && !bodies.contains_key(&root_frame) {
        return Err(reader.err(
            ErrorKind::NonPositiveMass,
            links[&root].0,
            &format!("link `{root}`"),
            format!("the root link `{root}` carries no inertia (nor do links fixed to it), yet as a floating base it must move the robot"),
            &format!("give link `{root}` an <inertial>, or fix the base"),
        ));
    }

    // The model.
    let mut parameters: IndexMap<String, f64> = IndexMap::new();
    let mut coordinates: Vec<String> = Vec::new();
    // URDF is in SI units: a revolute joint's angle in radians, a prismatic one's travel and the
    // base's position in metres, the masses in kilograms.
    let mut units: IndexMap<String, String> = IndexMap::new();
    let mut frames: Vec<FrameDef> = Vec::new();
    let mut full: Vec<String> = Vec::new();
    let mut ignorable: Vec<String> = Vec::new();
    let mut q0: IndexMap<String, String> = IndexMap::new();
    let mut constraints = Vec::new();
    let moving_gravity = options.gravity.iter().any(|g| *g != 0.0);
    if options.base == Base::Floating {
        let (b, e) = (BASE_POSITION, BASE_ATTITUDE);
        coordinates.extend(b.iter().chain(&e).map(|s| s.to_string()));
        units.extend(b.iter().map(|s| (s.to_string(), "m".to_string())));
        frames.push(FrameDef {
            name: root_frame.clone(),
            parent: "world".into(),
            translation: Some(b.iter().map(|s| s.to_string()).collect()),
            rotation: vec![RotationDef::Quaternion(e[0].into(), e[1].into(), e[2].into(), e[3].into())],
        });
        constraints.push(ConstraintDef::Position { name: "unit".into(), expr: e.iter().map(|c| format!("{c}^2")).collect::<Vec<_>>().join(" + ") + " - 1" });
        full.extend(["x", "y", "z"].iter().map(|a| format!("omega_{a}({root_frame})")));
        full.extend(b.iter().map(|c| format!("{c}'")));
        // A translation gravity has no component along is ignorable.
        for (k, c) in b.iter().enumerate() {
            if options.gravity[k] == 0.0 {
                ignorable.push(c.to_string());
            }
        }
        for c in b {
            q0.insert(c.into(), "0".into());
        }
        for (c, v) in e.iter().zip(["1", "0", "0", "0"]) {
            q0.insert(c.to_string(), v.into());
        }
    }
    // A coordinate takes its joint's name unless a frame (a link's) has it: a joint and the
    // link it moves often share one (so100's `gripper`).
    let mut taken: HashSet<String> = coordinates.iter().cloned().chain(frame_of.values().map(|(f, _)| f.clone())).collect();
    let mut forces: Vec<ForceDef> = Vec::new();
    let mut damping: IndexMap<String, String> = IndexMap::new();
    let mut events: Vec<EventDef> = Vec::new();
    let mut limits_text: Vec<String> = Vec::new();
    let mut unmodelled: Vec<String> = Vec::new();
    // Each moving joint's coordinate (a mimic joint's master's, resolved along chains).
    let mut coordinate_of: HashMap<&str, String> = HashMap::new();
    for &k in &order {
        let j = &joints[k];
        if j.kind != "fixed" && j.mimic.is_none() {
            let mut q = ident(&j.name);
            while !taken.insert(q.clone()) {
                q.push('_');
            }
            coordinate_of.insert(j.name.as_str(), q);
        }
    }
    let angle_of = |k: usize| -> Result<String, ModelError> {
        let (mut j, mut multiplier, mut offset) = (&joints[k], 1.0, 0.0);
        for _ in 0..=joints.len() {
            let Some((master, m, o, node)) = &j.mimic else {
                let q = &coordinate_of[j.name.as_str()];
                return Ok(match (multiplier == 1.0, offset == 0.0) {
                    (true, true) => q.clone(),
                    (false, true) => format!("{}*{q}", num(multiplier)),
                    (true, false) => format!("{q} + {}", num(offset)),
                    (false, false) => format!("{}*{q} + {}", num(multiplier), num(offset)),
                });
            };
            let Some(next) = joints.iter().find(|x| x.name == *master && x.kind != "fixed") else {
                return Err(reader.err(
                    ErrorKind::UnknownName,
                    *node,
                    &format!("joint `{}`", j.name),
                    format!("joint `{}` mimics `{master}`, which is not a moving joint of the robot", j.name),
                    "name a revolute, continuous or prismatic joint",
                ));
            };
            // q = m (m' q'' + o') + o.
            offset += multiplier * o;
            multiplier *= m;
            j = next;
        }
        Err(reader.err(
            ErrorKind::Cycle,
            joints[k].node,
            &format!("joint `{}`", joints[k].name),
            format!("joint `{}`'s mimics form a loop", joints[k].name),
            "let one of them be a joint of its own",
        ))
    };
    for &k in &order {
        let j = &joints[k];
        if j.kind == "fixed" {
            continue;
        }
        let own = coordinate_of.get(j.name.as_str()).cloned();
        let q = angle_of(k)?;
        let (frame, pose) = frame_of[&j.parent].clone();
        let joint = pose.then(&j.origin);
        let mut rotation = Vec::new();
        if joint.r != IDENTITY {
            rotation.push(RotationDef::Matrix(joint.r.iter().map(|row| row.iter().map(|x| num(*x)).collect()).collect()));
        }
        let along = |sign: f64| if sign > 0.0 { q.clone() } else { format!("-({q})") };
        let unit = j.axis.iter().position(|a| a.abs() == 1.0);
        let mut translation: Vec<String> = joint.p.iter().map(|x| num(*x)).collect();
        match j.kind {
            "prismatic" => {
                // Along the axis turned into the frame's components.
                let a = apply(&joint.r, &j.axis);
                for (t, ak) in translation.iter_mut().zip(a) {
                    let ak = num(ak);
                    if ak != "0" {
                        *t = format!("{t} + {ak}*({q})");
                    }
                }
            }
            _ => rotation.push(match unit {
                Some(0) => RotationDef::X(along(j.axis[0])),
                Some(1) => RotationDef::Y(along(j.axis[1])),
                Some(2) => RotationDef::Z(along(j.axis[2])),
                _ => RotationDef::Axis(j.axis.iter().map(|x| num(*x)).collect(), q.clone()),
            }),
        }
        frames.push(FrameDef { name: frame_name[j.child.as_str()].clone(), parent: frame, translation: Some(translation), rotation });
        // A mimic joint adds no coordinate: its angle is its master's.
        let Some(q) = own else { continue };
        coordinates.push(q.clone());
        units.insert(q.clone(), if j.kind == "prismatic" { "m" } else { "rad" }.to_string());
        full.push(format!("{q}'"));
        let start = match j.limit {
            Some((lo, hi)) if !(lo..=hi).contains(&0.0) => 0.5 * (lo + hi),
            _ => 0.0,
        };
        q0.insert(q.clone(), num(start));
        if j.damping > 0.0 {
            let p = format!("damping_{q}");
            parameters.insert(p.clone(), j.damping);
            damping.insert(q.clone(), format!("-{p}*{q}'"));
        }
        if j.friction > 0.0 {
            unmodelled.push(format!("joint `{}`'s friction {}", j.name, j.friction));
        }
        if let Some((lo, hi)) = j.limit {
            limits_text.push(format!("{q} in [{}, {}]", num(lo), num(hi)));
            let action = match options.limits {
                LimitAction::Report => None,
                LimitAction::Record => Some(ActionDef::Record),
                LimitAction::Stop => Some(ActionDef::Stop),
            };
            if let Some(action) = action {
                events.push(EventDef {
                    name: format!("{q}_upper"),
                    when: format!("{q} - {}", num(hi)),
                    direction: DirectionDef::Rising,
                    action: action.clone(),
                });
                events.push(EventDef { name: format!("{q}_lower"), when: format!("{} - {q}", num(lo)), direction: DirectionDef::Rising, action });
            }
        }
    }
    if !damping.is_empty() {
        forces.push(ForceDef::Generalized { name: "joint damping".into(), components: damping });
    }
    if moving_gravity {
        forces.insert(0, ForceDef::Gravity { vector: options.gravity.iter().map(|g| num(*g)).collect() });
    }
    // Bodies: the root's only where it moves; each a mass parameter, its inertia as numbers.
    let mut body_defs = Vec::new();
    let mut mass_parameters = IndexMap::new();
    for (frame, (_, b)) in &bodies {
        if frame == "world" {
            continue;
        }
        let p = format!("mass_{frame}");
        mass_parameters.insert(p.clone(), b.mass);
        units.insert(p.clone(), "kg".to_string());
        body_defs.push(BodyDef {
            name: frame.clone(),
            frame: frame.clone(),
            mass: p,
            com: Some(b.com.iter().map(|x| num(*x)).collect()),
            inertia: InertiaDef::Matrix(b.inertia.iter().map(|row| row.iter().map(|x| num(*x)).collect()).collect()),
            shape: looks.remove(frame).map(|mut v| if v.len() == 1 { v.remove(0) } else { ShapeDef::Compound(v) }),
        });
    }
    // The bodies in the frames' order (a parent before its children).
    body_defs.sort_by_key(|b| frames.iter().position(|f| f.name == b.frame).unwrap_or(usize::MAX));
    mass_parameters.extend(parameters);
    let reduced: Vec<String> = full.iter().filter(|u| !ignorable.iter().any(|c| **u == format!("{c}'"))).cloned().collect();
    let qdot0: IndexMap<String, String> = coordinates.iter().map(|c| (c.clone(), "0".to_string())).collect();
    let mut description =
        format!("{} (from {}, {} base)", robot.attribute("name").unwrap_or("robot"), file, if options.base == Base::Floating { "floating" } else { "fixed" });
    if !limits_text.is_empty() {
        description += &format!(
            "; joint limits ({}): {}",
            match options.limits {
                LimitAction::Report => "not enforced",
                LimitAction::Record => "recorded",
                LimitAction::Stop => "stop the run",
            },
            limits_text.join(", ")
        );
    }
    if !unmodelled.is_empty() {
        description += &format!("; not modelled: {}", unmodelled.join(", "));
    }
    Ok(ModelFile {
        name: robot_name,
        description,
        parameters: mass_parameters,
        inputs: IndexMap::new(),
        coordinates,
        time_functions: IndexMap::new(),
        frames,
        bodies: body_defs,
        constraints,
        forces,
        urdf: None,
        quasi_velocities: QuasiVelocityDef { full, reduced },
        ignorable: IgnorableDef::Declared(ignorable),
        initial: Some(InitialDef { q: q0, qdot: qdot0 }),
        simulation: Some(SimulationDef { t_start: 0.0, t_end: 1.0, dt_out: 0.01, paper: false }),
        events,
        // On a fixed base, the visuals of the links fixed to the world.
        scenery: looks.remove("world").map(|mut v| if v.len() == 1 { v.remove(0) } else { ShapeDef::Compound(v) }),
        units,
        emit: EmitDef::default(),
    })
}

/// `def` with the URDF it includes (`urdf: Urdf(file, ...)`, the path relative to `file`, the
/// model file's own path) put first: its parameters, coordinates, frames, bodies, constraints,
/// forces and events, then this file's; this file's quasi-velocities, or the robot's followed by
/// the rates of this file's coordinates; the robot's ignorable coordinates unless this file
/// declares its own; the initial values merged (this file's win).
pub fn include(file: &str, def: ModelFile) -> Result<ModelFile, ModelError> {
    let Some(urdf) = def.urdf.clone() else { return Ok(def) };
    let dir = std::path::Path::new(file).parent().unwrap_or(std::path::Path::new(""));
    let path = dir.join(&urdf.file);
    let (robot_file, xml) = super::read_source(&path)?;
    let options = UrdfOptions { base: urdf.base, gravity: urdf.gravity.unwrap_or_else(default_gravity), limits: urdf.limits };
    let mut robot = model_file(&robot_file, &xml, &options)?;
    // The robot's meshes are named relative to its folder; the merged model reads them relative
    // to this file's.
    let urdf_dir = std::path::Path::new(&urdf.file).parent().unwrap_or(std::path::Path::new(""));
    for shape in robot.bodies.iter_mut().filter_map(|b| b.shape.as_mut()).chain(robot.scenery.as_mut()) {
        shape.rebase_meshes(urdf_dir);
    }
    let mut out = robot.clone();
    out.name = def.name.clone();
    out.description = if def.description.is_empty() { robot.description.clone() } else { def.description.clone() };
    out.parameters.extend(def.parameters.clone());
    out.inputs.extend(def.inputs.clone());
    out.coordinates.extend(def.coordinates.iter().cloned());
    out.time_functions.extend(def.time_functions.clone());
    out.frames.extend(def.frames.iter().cloned());
    out.bodies.extend(def.bodies.iter().cloned());
    out.constraints.extend(def.constraints.iter().cloned());
    out.forces.extend(def.forces.iter().cloned());
    out.units.extend(def.units.clone());
    out.scenery = match (robot.scenery.clone(), def.scenery.clone()) {
        (Some(a), Some(b)) => Some(ShapeDef::Compound(vec![a, b])),
        (a, b) => a.or(b),
    };
    out.events.extend(def.events.iter().cloned());
    out.quasi_velocities = if def.quasi_velocities.is_empty() {
        let own: Vec<String> = def.coordinates.iter().map(|c| format!("{c}'")).collect();
        QuasiVelocityDef {
            full: robot.quasi_velocities.full.iter().cloned().chain(own.iter().cloned()).collect(),
            reduced: robot.quasi_velocities.reduced.iter().cloned().chain(own).collect(),
        }
    } else {
        def.quasi_velocities.clone()
    };
    // The robot's ignorable coordinates, unless this file declares some.
    if matches!(&def.ignorable, IgnorableDef::Declared(list) if !list.is_empty()) {
        out.ignorable = def.ignorable.clone();
    }
    let mut initial = robot.initial.clone().unwrap_or(InitialDef { q: IndexMap::new(), qdot: IndexMap::new() });
    for c in &def.coordinates {
        initial.q.entry(c.clone()).or_insert_with(|| "0".into());
        initial.qdot.entry(c.clone()).or_insert_with(|| "0".into());
    }
    if let Some(own) = &def.initial {
        initial.q.extend(own.q.clone());
        initial.qdot.extend(own.qdot.clone());
    }
    out.initial = Some(initial);
    out.simulation = def.simulation.clone().or(robot.simulation);
    out.emit = def.emit.clone();
    out.urdf = None;
    Ok(out)
}

/// URDF's `rpy` of a rotation (`R = Rz(yaw) Ry(pitch) Rx(roll)`), roll taken as zero where the
/// pitch is a right angle.
fn rpy_of(r: &M3) -> [f64; 3] {
    let pitch = (-r[2][0]).clamp(-1.0, 1.0).asin();
    if r[2][0].abs() > 1.0 - 1e-12 {
        return [0.0, pitch, (-r[0][1]).atan2(r[1][1])];
    }
    [r[2][1].atan2(r[2][2]), pitch, r[1][0].atan2(r[0][0])]
}

/// The path, relative to `folder` where it was found there or above (so that the model reads
/// the same on any machine), of a mesh file named `name` in a URDF in `folder`:
/// `file://` absolute, `package://NAME/PATH` looked for as `NAME/PATH` and as `PATH` in `folder`
/// and the folders above it, or relative to `folder`; `None` where it is not a file of a mesh
/// format read ([`super::mesh::MeshFormat`]) that is found and reads as a mesh.
fn mesh_file(name: &str, folder: &std::path::Path) -> Option<String> {
    super::mesh::MeshFormat::of(std::path::Path::new(name))?;
    let candidates: Vec<(std::path::PathBuf, String)> = if let Some(path) = name.strip_prefix("file://") {
        vec![(path.into(), path.to_string())]
    } else if let Some(rest) = name.strip_prefix("package://") {
        let inside = rest.split_once('/').map_or("", |(_, path)| path);
        folder.ancestors().enumerate().flat_map(|(up, dir)| [rest, inside].map(|p| (dir.join(p), format!("{}{p}", "../".repeat(up))))).collect()
    } else {
        vec![(folder.join(name), name.to_string())]
    };
    candidates.into_iter().filter(|(p, _)| p.is_file()).find_map(|(path, relative)| super::mesh::drawn_mesh(&path).ok().map(|_| relative))
}
