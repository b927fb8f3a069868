//! Kinematics of a tree of frames: world position and orientation of every frame, its
//! angular velocity in its own components, and the velocities of points fixed in it.
//!
//! Rotations are sequences of elementary rotations about the current axes; the angular
//! velocity of a frame in its own components is the parent's, rotated into the frame, plus
//! `sum_k (R_{k+1} ... R_n)^T e_k alpha_k'` over the sequence (so ZYX Euler angles give the
//! paper's `omega_m`).
//!
//! ```
//! use generator::kinematics::{rotation, Axis};
//! use generator::symbolic::Expr;
//! let r = rotation(Axis::Z, Expr::sym("a"));
//! assert_eq!(r.get(0, 1), -Expr::sym("a").sin());
//! ```

use crate::symbolic::{Expr, Matrix, Symbol};

/// A coordinate axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

/// The rotation matrix (child components to parent components) about `axis` by `angle`.
pub fn rotation(axis: Axis, angle: Expr) -> Matrix {
    let (c, s) = (angle.cos(), angle.sin());
    let (z, o) = (Expr::zero(), Expr::one());
    let rows = match axis {
        Axis::X => vec![vec![o, z, z], vec![z, c, -s], vec![z, s, c]],
        Axis::Y => vec![vec![c, z, s], vec![z, o, z], vec![-s, z, c]],
        Axis::Z => vec![vec![c, -s, z], vec![s, c, z], vec![z, z, o]],
    };
    Matrix::from_rows(rows)
}

/// What the time derivative needs to know: the time symbol and each coordinate with its
/// velocity symbol.
#[derive(Clone, Debug)]
pub struct TimeChain {
    pub t: Symbol,
    pub pairs: Vec<(Symbol, Expr)>,
}

impl TimeChain {
    /// `d/dt e`.
    pub fn dt(&self, e: Expr) -> Expr {
        e.time_derivative(self.t, &self.pairs)
    }
}

/// The kinematic state of one frame.
#[derive(Clone, Debug)]
pub struct FrameKinematics {
    pub name: String,
    /// World position of the origin.
    pub origin: [Expr; 3],
    /// Orientation: frame components to world components.
    pub rotation: Matrix,
    /// Angular velocity in the frame's own components.
    pub omega: [Expr; 3],
}

impl FrameKinematics {
    /// The world frame.
    pub fn world() -> FrameKinematics {
        FrameKinematics {
            name: "world".into(),
            origin: [Expr::zero(), Expr::zero(), Expr::zero()],
            rotation: Matrix::identity(3),
            omega: [Expr::zero(), Expr::zero(), Expr::zero()],
        }
    }

    /// A child frame: this frame moved by `translation` (in this frame's components) and
    /// turned by the elementary rotations `turns`, applied in order about the current axes.
    pub fn child(&self, name: &str, translation: &[Expr; 3], turns: &[(Axis, Expr)], chain: &TimeChain) -> FrameKinematics {
        let offset = self.rotation.mul(&Matrix::column(translation.to_vec()));
        let origin = [self.origin[0] + offset.get(0, 0), self.origin[1] + offset.get(1, 0), self.origin[2] + offset.get(2, 0)];
        let mut r_pc = Matrix::identity(3);
        for (axis, angle) in turns {
            r_pc = r_pc.mul(&rotation(*axis, *angle));
        }
        // omega_child = R_pc^T omega_parent + sum_k (R_{k+1}..R_n)^T e_k alpha_k'.
        let mut omega = r_pc.transpose().mul(&Matrix::column(self.omega.to_vec()));
        let mut tail = Matrix::identity(3);
        for (axis, angle) in turns.iter().rev() {
            let rate = chain.dt(*angle);
            let e_k = tail.transpose().col(axis.index());
            omega = omega.add(&Matrix::column(e_k.into_iter().map(|x| x * rate).collect()));
            tail = rotation(*axis, *angle).mul(&tail);
        }
        FrameKinematics {
            name: name.to_string(),
            origin,
            rotation: self.rotation.mul(&r_pc),
            omega: [omega.get(0, 0), omega.get(1, 0), omega.get(2, 0)],
        }
    }

    /// World position of a point with coordinates `p` in this frame.
    pub fn point(&self, p: &[Expr; 3]) -> [Expr; 3] {
        let w = self.rotation.mul(&Matrix::column(p.to_vec()));
        [self.origin[0] + w.get(0, 0), self.origin[1] + w.get(1, 0), self.origin[2] + w.get(2, 0)]
    }

    /// World components of a vector given in this frame's components.
    pub fn to_world(&self, v: &[Expr; 3]) -> [Expr; 3] {
        let w = self.rotation.mul(&Matrix::column(v.to_vec()));
        [w.get(0, 0), w.get(1, 0), w.get(2, 0)]
    }
}

/// World velocity of a world position vector.
pub fn velocity(position: &[Expr; 3], chain: &TimeChain) -> [Expr; 3] {
    [chain.dt(position[0]), chain.dt(position[1]), chain.dt(position[2])]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::symbolic::limits::Limits;

    #[test]
    fn zyx_euler_rates_give_the_papers_omega() {
        let names = ["psi", "theta", "phi"];
        let q: Vec<Symbol> = names.iter().map(|n| Symbol::new(n)).collect();
        let qd: Vec<Expr> = names.iter().map(|n| Expr::sym(&format!("{n}'"))).collect();
        let chain = TimeChain { t: Symbol::new("t"), pairs: q.iter().copied().zip(qd.iter().copied()).collect() };
        let z = [Expr::zero(), Expr::zero(), Expr::zero()];
        let f = FrameKinematics::world().child(
            "m",
            &z,
            &[(Axis::Z, q[0].expr()), (Axis::Y, q[1].expr()), (Axis::X, q[2].expr())],
            &chain,
        );
        let (th, ph) = (q[1].expr(), q[2].expr());
        let expected = [
            qd[2] - th.sin() * qd[0],
            ph.cos() * qd[1] + ph.sin() * th.cos() * qd[0],
            -ph.sin() * qd[1] + ph.cos() * th.cos() * qd[0],
        ];
        for k in 0..3 {
            let diff = (f.omega[k] - expected[k]).trig_normal(Limits::default()).unwrap();
            assert!(diff.is_zero(), "omega[{k}] = {}", f.omega[k]);
        }
    }
}
