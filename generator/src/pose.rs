//! Where the model's frames and bodies are: the symbolic kinematics evaluated at given times
//! and coordinates (the origin and rotation of every frame in the world), and each body's
//! mass, centre of mass and inertia as numbers, for drawing the motion.
//!
//! ```
//! use generator::pose::Poser;
//! let model = generator::model::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/cart_pendulum.ron")).unwrap();
//! let params: Vec<f64> = model.parameters.iter().map(|(_, v)| *v).collect();
//! let poser = Poser::new(&model, &params).unwrap();
//! // The cart's frame follows x.
//! let poses = poser.frames_at(0.0, &[0.0, 0.0, 1.5]).unwrap();
//! let cart = poser.frame_names.iter().position(|n| n == "cart").unwrap();
//! assert_eq!(poses[cart].origin, [1.5, 0.0, 0.0]);
//! ```

use crate::model::Model;
use crate::symbolic::Expr;
use crate::symbolic::eval::{Env, EvalError};

/// A frame's place in the world: its origin, and its rotation (row-major, columns the frame's
/// axes in world components).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub origin: [f64; 3],
    pub rotation: [f64; 9],
}

/// A body's mass properties, as numbers.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyValues {
    pub name: String,
    /// Index into [`Poser::frame_names`].
    pub frame: usize,
    pub mass: f64,
    /// Centre of mass, in the frame (where it moves with the coordinates or time, a boom's
    /// tip on a sliding joint, its place at the model's initial state; [`Poser::centers_at`]
    /// gives it at any state).
    pub com: [f64; 3],
    /// The centre of mass depends on the coordinates or on time.
    pub moving: bool,
    /// Inertia about the centre of mass in frame components, row-major (`None`: a point mass).
    pub inertia: Option<[f64; 9]>,
    /// How it is drawn (empty: as its equivalent-inertia box).
    pub shapes: Vec<ShapeValues>,
}

/// One solid of a body's drawn geometry, as numbers, in the body's frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeValues {
    /// `box`, `cylinder`, `sphere`, `capsule` or `mesh` ([`crate::model::shape::Solid::sizes`]).
    pub solid: &'static str,
    /// Its sizes: a box's three sides; a radius, then a length; a mesh's scale along x, y, z.
    pub sizes: Vec<f64>,
    /// A mesh's triangles (in its own units, before the scale).
    pub mesh: Option<std::sync::Arc<crate::model::mesh::TriangleMesh>>,
    pub origin: [f64; 3],
    /// Its axes in the frame's, row-major (columns the solid's axes).
    pub rotation: [f64; 9],
}

/// A shape's sizes and placement at the parameters in `env`.
fn shape_values(shape: &crate::model::shape::Shape, env: &Env) -> Result<ShapeValues, EvalError> {
    let (solid, sizes) = shape.solid.sizes();
    let origin = Expr::eval_all(&shape.origin, env)?;
    let [r, p, y] = Expr::eval_all(&shape.rpy, env)?[..] else { unreachable!("three angles") };
    Ok(ShapeValues {
        solid,
        sizes: Expr::eval_all(&sizes, env)?,
        mesh: match &shape.solid {
            crate::model::shape::Solid::Mesh { mesh, .. } => mesh.as_ref().ok().cloned(),
            _ => None,
        },
        origin: [origin[0], origin[1], origin[2]],
        rotation: crate::model::shape::rpy_rotation(r, p, y),
    })
}

/// The model's frame poses as functions of `t` and `q`, with its parameters set.
pub struct Poser {
    /// The frames' names; the world is first.
    pub frame_names: Vec<String>,
    pub bodies: Vec<BodyValues>,
    /// The gravity vector of the model's `Gravity` force, if it has one.
    pub gravity: Option<[f64; 3]>,
    /// The shapes drawn fixed to the world, placed in its frame ([`Model::scenery`]).
    pub scenery: Vec<ShapeValues>,
    model: Model,
    env: Env,
    /// Per frame, its 12 expressions: origin, then rotation row-major.
    expressions: Vec<Expr>,
    /// Per body, its centre of mass's 3 expressions.
    centers: Vec<Expr>,
}

impl Poser {
    /// The poser of `model` with the parameters `params` (the model's order: `parameters`).
    pub fn new(model: &Model, params: &[f64]) -> Result<Poser, EvalError> {
        let mut env = Env::default();
        for ((symbol, _), value) in model.parameters.iter().zip(params) {
            env.set(*symbol, *value);
        }
        // `pi` as the model's expressions read it (a frame turned by `pi/2`, a shape's `rpy`).
        env.set(crate::symbolic::Symbol::new("pi"), std::f64::consts::PI);
        for (name, body) in &model.time_functions {
            env.define(*name, model.t, *body);
        }
        let mut expressions = Vec::with_capacity(12 * model.frames.len());
        for frame in &model.frames {
            expressions.extend(frame.origin);
            expressions.extend(frame.rotation.data.iter().copied());
        }
        let number = |e: Expr| e.eval(&env);
        // A centre that moves is placed at the initial state (or zero) until asked at a state.
        let mut start = env.clone();
        start.set(model.t, 0.0);
        let (q0, _) = model.initial.clone().unwrap_or((vec![0.0; model.coordinates.len()], Vec::new()));
        for (symbol, value) in model.coordinates.iter().zip(&q0) {
            start.set(*symbol, *value);
        }
        let bodies = model
            .bodies
            .iter()
            .map(|b| {
                let inertia = match &b.inertia {
                    Some(m) => {
                        let values = Expr::eval_all(&m.data, &env)?;
                        Some(std::array::from_fn(|k| values[k]))
                    }
                    None => None,
                };
                let moving = b.com.iter().any(|c| c.eval(&env).is_err());
                let com = Expr::eval_all(&b.com, if moving { &start } else { &env })?;
                let shapes = b.shapes.iter().map(|shape| shape_values(shape, &env)).collect::<Result<_, EvalError>>()?;
                Ok(BodyValues { name: b.name.clone(), frame: b.frame, mass: number(b.mass)?, com: [com[0], com[1], com[2]], moving, inertia, shapes })
            })
            .collect::<Result<_, EvalError>>()?;
        let gravity = model
            .forces
            .iter()
            .find_map(|f| match f {
                crate::model::Force::Gravity { vector } => Some(vector),
                _ => None,
            })
            .map(|v| Ok::<_, EvalError>([number(v[0])?, number(v[1])?, number(v[2])?]))
            .transpose()?;
        let centers = model.bodies.iter().flat_map(|b| b.com).collect();
        let scenery = model.scenery.iter().map(|shape| shape_values(shape, &env)).collect::<Result<_, EvalError>>()?;
        Ok(Poser {
            frame_names: model.frames.iter().map(|f| f.name.clone()).collect(),
            bodies,
            gravity,
            scenery,
            model: model.clone(),
            env,
            expressions,
            centers,
        })
    }

    /// The bodies' centres of mass (each in its frame) at time `t` and coordinates `q`.
    ///
    /// ```
    /// use generator::pose::Poser;
    /// // Scene 3's tip mass slides along the boom: its centre is l/2 + rho along x.
    /// let model = generator::model::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/satellite_boom.ron")).unwrap();
    /// let params: Vec<f64> = model.parameters.iter().map(|(_, v)| *v).collect();
    /// let poser = Poser::new(&model, &params).unwrap();
    /// let tip = poser.bodies.iter().position(|b| b.name == "tip").unwrap();
    /// assert!(poser.bodies[tip].moving);
    /// let q = [0.0, 0.0, 0.0, 0.25, 0.0, 0.0, 0.0];
    /// let l = params[model.parameters.iter().position(|(p, _)| p.name() == "l").unwrap()];
    /// assert_eq!(poser.centers_at(0.0, &q).unwrap()[tip], [l / 2.0 + 0.25, 0.0, 0.0]);
    /// ```
    pub fn centers_at(&self, t: f64, q: &[f64]) -> Result<Vec<[f64; 3]>, EvalError> {
        let mut env = self.env.clone();
        env.set(self.model.t, t);
        for (symbol, value) in self.model.coordinates.iter().zip(q) {
            env.set(*symbol, *value);
        }
        let values = Expr::eval_all(&self.centers, &env)?;
        Ok(values.chunks_exact(3).map(|v| [v[0], v[1], v[2]]).collect())
    }

    /// Every frame's pose at time `t` and coordinates `q`.
    pub fn frames_at(&self, t: f64, q: &[f64]) -> Result<Vec<Pose>, EvalError> {
        let mut env = self.env.clone();
        env.set(self.model.t, t);
        for (symbol, value) in self.model.coordinates.iter().zip(q) {
            env.set(*symbol, *value);
        }
        let values = Expr::eval_all(&self.expressions, &env)?;
        Ok(values.chunks_exact(12).map(|v| Pose { origin: [v[0], v[1], v[2]], rotation: std::array::from_fn(|k| v[3 + k]) }).collect())
    }
}
