//! Kinematics of a tree of frames, recursively from the root: each frame's world position and
//! orientation, and its angular velocity and origin velocity in its own components, each from
//! its parent's. In own components the relative angles of a chain appear as the mechanism has
//! them (a link's velocity is its parent's turned by the joint), where world components would
//! compose the rotations of every joint above it.
//!
//! Rotations are sequences of elementary rotations about the current axes; the angular
//! velocity of a frame in its own components is the parent's, rotated into the frame, plus
//! `sum_k (R_{k+1} ... R_n)^T e_k alpha_k'` over the sequence (so ZYX Euler angles give the
//! paper's `omega_m`). The origin velocity is `R^T (v_parent + omega_parent x t + t')`, `t` the
//! translation in the parent's components.
//!
//! ```
//! use generator::kinematics::{rotation, Axis};
//! use generator::symbolic::Expr;
//! let r = rotation(Axis::Z, Expr::sym("a"));
//! assert_eq!(r.get(0, 1), -Expr::sym("a").sin());
//! ```

pub(crate) mod rolling;

use crate::symbolic::diff::TimeDerivative;
use crate::symbolic::{Expr, Matrix, Symbol};
use std::cell::RefCell;

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

/// The rotation about the unit axis `a` (constant components) by `angle` (Rodrigues):
/// `R = cos I + sin [a]x + (1 - cos) a a^T`.
pub fn rotation_about(a: &[Expr; 3], angle: Expr) -> Matrix {
    let (c, s) = (angle.cos(), angle.sin());
    let v = Expr::one() - c;
    let rows = (0..3)
        .map(|i| {
            (0..3)
                .map(|j| {
                    let outer = a[i] * a[j] * v;
                    let diagonal = if i == j { c } else { Expr::zero() };
                    // [a]x: row i, column j.
                    let cross = match (i, j) {
                        (0, 1) => -a[2] * s,
                        (0, 2) => a[1] * s,
                        (1, 0) => a[2] * s,
                        (1, 2) => -a[0] * s,
                        (2, 0) => -a[1] * s,
                        (2, 1) => a[0] * s,
                        _ => Expr::zero(),
                    };
                    diagonal + cross + outer
                })
                .collect()
        })
        .collect();
    Matrix::from_rows(rows)
}

/// One step of a frame's rotation relative to its parent, applied about the current axes.
#[derive(Clone, Debug)]
pub enum Turn {
    /// About a coordinate axis by an angle.
    About(Axis, Expr),
    /// About a constant unit axis (its components in the current axes) by an angle: a joint of
    /// any direction.
    Along([Expr; 3], Expr),
    /// A constant rotation (the current axes' components of the new ones, columns): a
    /// joint's fixed orientation in its parent.
    Fixed(Matrix),
}

impl Turn {
    /// The rotation matrix of the step.
    fn matrix(&self) -> Matrix {
        match self {
            Turn::About(axis, angle) => rotation(*axis, *angle),
            Turn::Along(a, angle) => rotation_about(a, *angle),
            Turn::Fixed(m) => m.clone(),
        }
    }

    /// The angular velocity of a step about a unit axis, in the current axes.
    fn rate(&self, chain: &TimeChain) -> [Expr; 3] {
        match self {
            Turn::Along(a, angle) => {
                let rate = chain.dt(*angle);
                [a[0] * rate, a[1] * rate, a[2] * rate]
            }
            Turn::About(..) | Turn::Fixed(_) => [Expr::zero(), Expr::zero(), Expr::zero()],
        }
    }
}

/// The total time derivative along the motion: the time symbol and each coordinate with its
/// rate (velocities with accelerations for velocity-level expressions). Memoized: one
/// forward pass over the DAG however many expressions share it.
#[derive(Clone, Debug)]
pub struct TimeChain {
    pub t: Symbol,
    pub pairs: Vec<(Symbol, Expr)>,
    memo: RefCell<TimeDerivative>,
}

impl TimeChain {
    /// The chain `d/dt t = 1`, `d/dt x_i = rate_i`.
    pub fn new(t: Symbol, pairs: Vec<(Symbol, Expr)>) -> TimeChain {
        let memo = RefCell::new(TimeDerivative::new(t, &pairs));
        TimeChain { t, pairs, memo }
    }

    /// `d/dt e`.
    pub fn dt(&self, e: Expr) -> Expr {
        self.memo.borrow_mut().dt(e)
    }

    /// `d/dt` of each component.
    pub fn dt3(&self, v: &[Expr; 3]) -> [Expr; 3] {
        [self.dt(v[0]), self.dt(v[1]), self.dt(v[2])]
    }
}

/// `a x b`.
pub fn cross(a: &[Expr; 3], b: &[Expr; 3]) -> [Expr; 3] {
    let term = |x: Expr, y: Expr| if x.is_zero() || y.is_zero() { Expr::zero() } else { x * y };
    [term(a[1], b[2]) - term(a[2], b[1]), term(a[2], b[0]) - term(a[0], b[2]), term(a[0], b[1]) - term(a[1], b[0])]
}

/// `a . b`.
pub fn dot(a: &[Expr; 3], b: &[Expr; 3]) -> Expr {
    let term = |x: Expr, y: Expr| if x.is_zero() || y.is_zero() { Expr::zero() } else { x * y };
    Expr::sum([term(a[0], b[0]), term(a[1], b[1]), term(a[2], b[2])])
}

/// `a + b`.
pub fn add3(a: &[Expr; 3], b: &[Expr; 3]) -> [Expr; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `m v` for a 3x3 matrix.
pub fn mat_vec(m: &Matrix, v: &[Expr; 3]) -> [Expr; 3] {
    let c = m.mul(&Matrix::column(v.to_vec()));
    [c.get(0, 0), c.get(1, 0), c.get(2, 0)]
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
    /// Velocity of the origin in the frame's own components.
    pub velocity: [Expr; 3],
    /// The joint to the parent frame (`None` for the world).
    pub joint: Option<Joint>,
}

/// How a frame moves relative to its parent: the transform and the relative velocity, in the
/// frame's own components. `omega = R^T omega_parent + joint.omega` and
/// `velocity = R^T (v_parent + omega_parent x t) + joint.velocity`: what a recursion over the
/// tree (Featherstone's spatial transforms) needs.
#[derive(Clone, Debug)]
pub struct Joint {
    /// Index of the parent in the model's frames (the world is 0).
    pub parent: usize,
    /// `R`: the frame's components to the parent's.
    pub rotation: Matrix,
    /// `t`: the origin's offset in the parent's components.
    pub translation: [Expr; 3],
    /// The angular velocity relative to the parent, own components.
    pub omega: [Expr; 3],
    /// `R^T t'`: the origin's velocity relative to the parent, own components.
    pub velocity: [Expr; 3],
}

impl crate::symbolic::transfer::Transfer for Joint {
    fn visit(&mut self, v: &mut dyn crate::symbolic::transfer::Visitor) {
        self.rotation.visit(v);
        self.translation.visit(v);
        self.omega.visit(v);
        self.velocity.visit(v);
    }
}

impl crate::symbolic::transfer::Transfer for FrameKinematics {
    fn visit(&mut self, v: &mut dyn crate::symbolic::transfer::Visitor) {
        self.origin.visit(v);
        self.rotation.visit(v);
        self.omega.visit(v);
        self.velocity.visit(v);
        if let Some(j) = &mut self.joint {
            j.visit(v);
        }
    }
}

impl FrameKinematics {
    /// The world frame.
    pub fn world() -> FrameKinematics {
        let z = [Expr::zero(), Expr::zero(), Expr::zero()];
        FrameKinematics { name: "world".into(), origin: z, rotation: Matrix::identity(3), omega: z, velocity: z, joint: None }
    }

    /// A child frame: this frame (number `parent` in the model) moved by `translation` (in this
    /// frame's components) and turned by the elementary rotations `turns`, applied in order
    /// about the current axes.
    pub fn child(&self, parent: usize, name: &str, translation: &[Expr; 3], turns: &[(Axis, Expr)], chain: &TimeChain) -> FrameKinematics {
        let turns: Vec<Turn> = turns.iter().map(|(axis, angle)| Turn::About(*axis, *angle)).collect();
        self.child_turned(parent, name, translation, &turns, chain)
    }

    /// [`FrameKinematics::child`] with any [`Turn`]s: about coordinate axes, about a unit axis
    /// of any direction, or by a constant rotation.
    pub fn child_turned(&self, parent: usize, name: &str, translation: &[Expr; 3], turns: &[Turn], chain: &TimeChain) -> FrameKinematics {
        let offset = mat_vec(&self.rotation, translation);
        let origin = add3(&self.origin, &offset);
        let matrices: Vec<Matrix> = turns.iter().map(Turn::matrix).collect();
        let mut r_pc = Matrix::identity(3);
        for m in &matrices {
            r_pc = r_pc.mul(m);
        }
        let r_cp = r_pc.transpose();
        // omega_child = R_pc^T omega_parent + sum_k (R_{k+1}..R_n)^T w_k, w_k step k's rate.
        let mut relative = [Expr::zero(), Expr::zero(), Expr::zero()];
        let mut tail = Matrix::identity(3);
        for (turn, m) in turns.iter().zip(&matrices).rev() {
            match turn {
                // A column of the tail, as the elementary rotations always had it.
                Turn::About(axis, angle) => {
                    let rate = chain.dt(*angle);
                    let e_k = tail.transpose().col(axis.index());
                    relative = add3(&relative, &[e_k[0] * rate, e_k[1] * rate, e_k[2] * rate]);
                }
                Turn::Along(..) => relative = add3(&relative, &mat_vec(&tail.transpose(), &turn.rate(chain))),
                Turn::Fixed(_) => {}
            }
            tail = m.mul(&tail);
        }
        let omega = add3(&mat_vec(&r_cp, &self.omega), &relative);
        // v_child = R_pc^T (v_parent + omega_parent x t + t').
        let moving = add3(&add3(&self.velocity, &cross(&self.omega, translation)), &chain.dt3(translation));
        let joint = Joint { parent, rotation: r_pc.clone(), translation: *translation, omega: relative, velocity: mat_vec(&r_cp, &chain.dt3(translation)) };
        FrameKinematics { name: name.to_string(), origin, rotation: self.rotation.mul(&r_pc), omega, velocity: mat_vec(&r_cp, &moving), joint: Some(joint) }
    }

    /// A child frame: this frame moved by `translation` and turned by the unit quaternion
    /// (Euler parameters) `e = (e0, e1, e2, e3)`: `R = (e0^2 - |e_v|^2) I + 2 e_v e_v^T + 2 e0 [e_v]x`
    /// (written in squares, orthogonal where `|e| = 1`), its own angular velocity `2 G(e) e'` with
    /// `G = [-e_v, e0 I - [e_v]x]`, the relation that holds on the unit sphere.
    pub fn child_quaternion(&self, parent: usize, name: &str, translation: &[Expr; 3], e: &[Expr; 4], chain: &TimeChain) -> FrameKinematics {
        let [e0, e1, e2, e3] = *e;
        let two = Expr::int(2);
        let r_pc = Matrix::from_rows(vec![
            vec![e0 * e0 + e1 * e1 - e2 * e2 - e3 * e3, two * (e1 * e2 - e0 * e3), two * (e1 * e3 + e0 * e2)],
            vec![two * (e1 * e2 + e0 * e3), e0 * e0 - e1 * e1 + e2 * e2 - e3 * e3, two * (e2 * e3 - e0 * e1)],
            vec![two * (e1 * e3 - e0 * e2), two * (e2 * e3 + e0 * e1), e0 * e0 - e1 * e1 - e2 * e2 + e3 * e3],
        ]);
        let d = e.map(|x| chain.dt(x));
        let g = [[-e1, e0, e3, -e2], [-e2, -e3, e0, e1], [-e3, e2, -e1, e0]];
        let own: [Expr; 3] = g.map(|row| two * (row[0] * d[0] + row[1] * d[1] + row[2] * d[2] + row[3] * d[3]));
        let offset = mat_vec(&self.rotation, translation);
        let r_cp = r_pc.transpose();
        let omega = add3(&mat_vec(&r_cp, &self.omega), &own);
        let moving = add3(&add3(&self.velocity, &cross(&self.omega, translation)), &chain.dt3(translation));
        let joint = Joint { parent, rotation: r_pc.clone(), translation: *translation, omega: own, velocity: mat_vec(&r_cp, &chain.dt3(translation)) };
        FrameKinematics {
            name: name.to_string(),
            origin: add3(&self.origin, &offset),
            rotation: self.rotation.mul(&r_pc),
            omega,
            velocity: mat_vec(&r_cp, &moving),
            joint: Some(joint),
        }
    }

    /// World position of a point with coordinates `p` in this frame.
    pub fn point(&self, p: &[Expr; 3]) -> [Expr; 3] {
        add3(&self.origin, &mat_vec(&self.rotation, p))
    }

    /// Velocity of a point with coordinates `p(q, t)` in this frame, in this frame's
    /// components: `v + omega x p + p'`.
    pub fn point_velocity(&self, p: &[Expr; 3], chain: &TimeChain) -> [Expr; 3] {
        add3(&add3(&self.velocity, &cross(&self.omega, p)), &chain.dt3(p))
    }

    /// World components of a vector given in this frame's components.
    pub fn to_world(&self, v: &[Expr; 3]) -> [Expr; 3] {
        mat_vec(&self.rotation, v)
    }

    /// This frame's components of a vector given in world components.
    pub fn from_world(&self, v: &[Expr; 3]) -> [Expr; 3] {
        mat_vec(&self.rotation.transpose(), v)
    }
}

/// World velocity of a world position vector.
pub fn velocity(position: &[Expr; 3], chain: &TimeChain) -> [Expr; 3] {
    chain.dt3(position)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::symbolic::zero::zero_test;

    /// The quaternion of ZYX Euler angles `(2a, 2b, 2c)` (half angles `a, b, c`) turns the frame
    /// as the three elementary rotations do, and `2 G(e) e'` is their angular velocity.
    #[test]
    fn a_quaternion_turns_as_its_euler_angles() {
        let names = ["a", "b", "c"];
        let q: Vec<Symbol> = names.iter().map(|n| Symbol::new(n)).collect();
        let chain = TimeChain::new(Symbol::new("t"), q.iter().map(|s| (*s, Expr::sym(&format!("{}'", s.name())))).collect());
        let [a, b, c] = [q[0].expr(), q[1].expr(), q[2].expr()];
        let (c1, s1, c2, s2, c3, s3) = (a.cos(), a.sin(), b.cos(), b.sin(), c.cos(), c.sin());
        let e = [c1 * c2 * c3 + s1 * s2 * s3, c1 * c2 * s3 - s1 * s2 * c3, c1 * s2 * c3 + s1 * c2 * s3, s1 * c2 * c3 - c1 * s2 * s3];
        let z = [Expr::zero(), Expr::zero(), Expr::zero()];
        let two = Expr::int(2);
        let quaternion = FrameKinematics::world().child_quaternion(0, "q", &z, &e, &chain);
        let euler = FrameKinematics::world().child(0, "e", &z, &[(Axis::Z, two * a), (Axis::Y, two * b), (Axis::X, two * c)], &chain);
        for i in 0..3 {
            for j in 0..3 {
                let d = quaternion.rotation.get(i, j) - euler.rotation.get(i, j);
                assert!(zero_test(d).is_zero(), "R[{i}][{j}]: {d}");
            }
            assert!(zero_test(quaternion.omega[i] - euler.omega[i]).is_zero(), "omega[{i}]: {} against {}", quaternion.omega[i], euler.omega[i]);
        }
    }

    #[test]
    fn zyx_euler_rates_give_the_papers_omega() {
        let names = ["psi", "theta", "phi"];
        let q: Vec<Symbol> = names.iter().map(|n| Symbol::new(n)).collect();
        let qd: Vec<Expr> = names.iter().map(|n| Expr::sym(&format!("{n}'"))).collect();
        let chain = TimeChain::new(Symbol::new("t"), q.iter().copied().zip(qd.iter().copied()).collect());
        let z = [Expr::zero(), Expr::zero(), Expr::zero()];
        let f = FrameKinematics::world().child(0, "m", &z, &[(Axis::Z, q[0].expr()), (Axis::Y, q[1].expr()), (Axis::X, q[2].expr())], &chain);
        let (th, ph) = (q[1].expr(), q[2].expr());
        let expected = [qd[2] - th.sin() * qd[0], ph.cos() * qd[1] + ph.sin() * th.cos() * qd[0], -ph.sin() * qd[1] + ph.cos() * th.cos() * qd[0]];
        for k in 0..3 {
            assert!(zero_test(f.omega[k] - expected[k]).is_zero(), "omega[{k}] = {}", f.omega[k]);
        }
    }

    #[test]
    fn own_component_velocity_is_the_world_velocity_turned() {
        // A two-link spatial chain on a moving base: R^T d/dt(world origin) = recursive velocity.
        let names = ["x", "a", "b"];
        let q: Vec<Symbol> = names.iter().map(|n| Symbol::new(n)).collect();
        let chain = TimeChain::new(Symbol::new("t"), q.iter().map(|s| (*s, Expr::sym(&format!("{}'", s.name())))).collect());
        let (l, z) = (Expr::sym("l"), Expr::zero());
        let base = FrameKinematics::world().child(0, "base", &[q[0].expr(), z, z], &[(Axis::Z, q[1].expr())], &chain);
        let link = base.child(1, "link", &[l, z, l * q[0].expr()], &[(Axis::Y, q[2].expr() - q[1].expr())], &chain);
        let world = velocity(&link.origin, &chain);
        let own = link.from_world(&world);
        for k in 0..3 {
            assert!(zero_test(own[k] - link.velocity[k]).is_zero(), "component {k}");
        }
    }
}
