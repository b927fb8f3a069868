//! A body's drawn geometry, resolved: each solid's sizes and placement in the body's frame, as
//! expressions in the parameters. Only the animation reads it; the dynamics take the mass and
//! the inertia.

use crate::symbolic::Expr;
use crate::symbolic::transfer::{Transfer, Visitor};

/// One solid of a body's geometry, placed in the body's frame: at `origin`, turned by `rpy`
/// (roll, pitch, yaw about the fixed x, y, z axes: `R = Rz(yaw) Ry(pitch) Rx(roll)`).
#[derive(Clone, Debug)]
pub struct Shape {
    pub solid: Solid,
    pub origin: [Expr; 3],
    pub rpy: [Expr; 3],
}

/// What a [`Shape`] is, in its own axes.
#[derive(Clone, Debug)]
pub enum Solid {
    /// Full sides along x, y, z.
    Box {
        size: [Expr; 3],
    },
    /// Along z, centred.
    Cylinder {
        radius: Expr,
        length: Expr,
    },
    Sphere {
        radius: Expr,
    },
    /// Along z, centred: `length` between the hemispheres' centres.
    Capsule {
        radius: Expr,
        length: Expr,
    },
    /// A triangle mesh (from a mesh file), its vertices multiplied by `scale` along x, y, z; or
    /// why its file could not be drawn (a model whose picture is missing still derives and runs:
    /// a Dask worker has no mesh files; drawing it is refused with this located error).
    Mesh {
        mesh: Result<std::sync::Arc<super::mesh::TriangleMesh>, Box<super::ModelError>>,
        scale: [Expr; 3],
    },
}

impl Solid {
    /// The solid's name and its sizes, in the order the page reads them (a mesh's: its scale).
    ///
    /// ```
    /// # use generator::model::Solid;
    /// # use generator::symbolic::Expr;
    /// let s = Solid::Cylinder { radius: Expr::int(1), length: Expr::int(2) };
    /// assert_eq!(s.sizes(), ("cylinder", vec![Expr::int(1), Expr::int(2)]));
    /// ```
    pub fn sizes(&self) -> (&'static str, Vec<Expr>) {
        match self {
            Solid::Box { size } => ("box", size.to_vec()),
            Solid::Cylinder { radius, length } => ("cylinder", vec![*radius, *length]),
            Solid::Sphere { radius } => ("sphere", vec![*radius]),
            Solid::Capsule { radius, length } => ("capsule", vec![*radius, *length]),
            Solid::Mesh { scale, .. } => ("mesh", scale.to_vec()),
        }
    }
}

impl Transfer for Shape {
    fn visit(&mut self, v: &mut dyn Visitor) {
        match &mut self.solid {
            Solid::Box { size } => size.visit(v),
            Solid::Cylinder { radius, length } | Solid::Capsule { radius, length } => {
                radius.visit(v);
                length.visit(v);
            }
            Solid::Sphere { radius } => radius.visit(v),
            Solid::Mesh { scale, .. } => scale.visit(v),
        }
        self.origin.visit(v);
        self.rpy.visit(v);
    }
}

/// The rotation of URDF's `rpy`: roll, pitch, yaw about the fixed x, y, z axes,
/// `Rz(yaw) Ry(pitch) Rx(roll)`, row-major (columns the turned axes).
///
/// ```
/// let r = generator::model::rpy_rotation(0.0, 0.0, std::f64::consts::FRAC_PI_2);
/// // Yaw a quarter turn: x goes to y.
/// assert!((r[3] - 1.0).abs() < 1e-15 && r[0].abs() < 1e-15);
/// ```
pub fn rpy_rotation(roll: f64, pitch: f64, yaw: f64) -> [f64; 9] {
    rpy_rotation_of([roll, pitch, yaw].map(f64::sin_cos))
}

/// [`rpy_rotation`] from the angles' `(sin, cos)` pairs (a URDF reader gives quarter turns
/// exactly).
pub fn rpy_rotation_of([(sr, cr), (sp, cp), (sy, cy)]: [(f64, f64); 3]) -> [f64; 9] {
    [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr, sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr, -sp, cp * sr, cp * cr]
}
