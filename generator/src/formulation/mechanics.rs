//! The mechanics of a model, to the stage every formulation shares: body velocities
//! `V_Gi = B_i q' + C_i`, `omega_i = D_i q' + E_i` (paper Eq. 54), the kinetic energy as
//! `T = 1/2 q'^T M q' + q'^T N + T0` (Eq. 13), the potential V, the generalized forces Q by
//! virtual power, and the kinematic constraints `a q' + b = 0` (Eq. 1).
//!
//! ```
//! let model = generator::model::load("../models/cart_pendulum.ron").unwrap();
//! let mech = generator::formulation::mechanics::derive(&model);
//! assert_eq!((mech.m, mech.r, mech.p), (3, 1, 2));
//! ```

use crate::model::{Constraint, Force, Model};
use crate::symbolic::limits::Limits;
use crate::symbolic::{Expr, Matrix, Symbol};
use std::collections::HashMap;

/// Velocities of one body, split as in Eq. (54).
#[derive(Clone, Debug)]
pub struct BodyVelocity {
    /// Centre-of-mass velocity, world components.
    pub v: [Expr; 3],
    /// Angular velocity, body-frame components.
    pub omega: [Expr; 3],
    /// `B_i = dV/dq'` (3 x m).
    pub b: Matrix,
    /// `C_i = V(q' = 0)`.
    pub c: [Expr; 3],
    /// `D_i = d omega/dq'` (3 x m).
    pub d: Matrix,
    /// `E_i = omega(q' = 0)`.
    pub e: [Expr; 3],
}

/// Everything derived before a formulation is chosen.
#[derive(Clone, Debug)]
pub struct Mechanics {
    /// Coordinates m, constraints r, degrees of freedom p = m - r.
    pub m: usize,
    pub r: usize,
    pub p: usize,
    pub bodies: Vec<BodyVelocity>,
    /// Kinetic energy T.
    pub kinetic: Expr,
    /// Potential energy V.
    pub potential: Expr,
    /// Mass matrix M (Eq. 13).
    pub mass: Matrix,
    /// N (Eq. 13), one entry per coordinate.
    pub n: Vec<Expr>,
    /// T0 (Eq. 13).
    pub t0: Expr,
    /// Generalized forces of the non-potential forces, Q (may depend on q, q', t).
    pub q_forces: Vec<Expr>,
    /// Constraint Jacobian a (r x m).
    pub a: Matrix,
    /// Constraint bias b (r).
    pub b: Vec<Expr>,
    /// Position-level constraints `phi(q, t) = 0`, by constraint index.
    pub holonomic: Vec<(usize, Expr)>,
    /// Constraint names, in order.
    pub constraint_names: Vec<String>,
}

/// Limits for the simplifications made while deriving.
pub fn derivation_limits() -> Limits {
    Limits { max_terms: 4000, max_time: std::time::Duration::from_secs(5) }
}

/// Splits a velocity-linear expression into `(d/dq', value at q' = 0)`.
fn split_linear(e: Expr, velocities: &[Symbol], zero: &HashMap<Symbol, Expr>) -> (Vec<Expr>, Expr) {
    (velocities.iter().map(|v| e.diff(*v)).collect(), e.subs(zero))
}

fn zero_velocities(model: &Model) -> HashMap<Symbol, Expr> {
    model.velocities.iter().map(|v| (*v, Expr::zero())).collect()
}

fn dot(a: &[Expr; 3], b: &[Expr; 3]) -> Expr {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Derives the shared mechanics of a model.
pub fn derive(model: &Model) -> Mechanics {
    let lim = derivation_limits();
    let chain = model.position_chain();
    let zero = zero_velocities(model);
    let m = model.m();
    let tidy = |e: Expr| e.simplify_trig(lim);

    let mut bodies = Vec::new();
    let mut mass = Matrix::zeros(m, m);
    let mut n = vec![Expr::zero(); m];
    let mut t0 = Expr::zero();
    let mut kinetic = Expr::zero();
    let mut potential = Expr::zero();
    for body in &model.bodies {
        let frame = &model.frames[body.frame];
        let pos = frame.point(&body.com);
        let v = crate::kinematics::velocity(&pos, &chain).map(tidy);
        let omega = frame.omega.map(tidy);
        let mut bm = Matrix::zeros(3, m);
        let mut dm = Matrix::zeros(3, m);
        let mut c = [Expr::zero(); 3];
        let mut e = [Expr::zero(); 3];
        for k in 0..3 {
            let (bk, ck) = split_linear(v[k], &model.velocities, &zero);
            let (dk, ek) = split_linear(omega[k], &model.velocities, &zero);
            for j in 0..m {
                bm.set(k, j, bk[j]);
                dm.set(k, j, dk[j]);
            }
            c[k] = ck;
            e[k] = ek;
        }
        // M += m B^T B + D^T I D; N += m B^T C + D^T I E; T0 += m/2 C.C + 1/2 E.I E.
        let bt = bm.transpose();
        mass = mass.add(&bt.mul(&bm).map(|x| *x * body.mass));
        let cb = bt.mul(&Matrix::column(c.to_vec()));
        for j in 0..m {
            n[j] = n[j] + cb.get(j, 0) * body.mass;
        }
        t0 = t0 + dot(&c, &c) * body.mass / 2;
        kinetic = kinetic + dot(&v, &v) * body.mass / 2;
        if let Some(inertia) = &body.inertia {
            let dt = dm.transpose();
            mass = mass.add(&dt.mul(inertia).mul(&dm));
            let ie = inertia.mul(&Matrix::column(e.to_vec()));
            let die = dt.mul(&ie);
            for j in 0..m {
                n[j] = n[j] + die.get(j, 0);
            }
            t0 = t0 + dot(&e, &[ie.get(0, 0), ie.get(1, 0), ie.get(2, 0)]) / 2;
            let iw = inertia.mul(&Matrix::column(omega.to_vec()));
            kinetic = kinetic + dot(&omega, &[iw.get(0, 0), iw.get(1, 0), iw.get(2, 0)]) / 2;
        }
        bodies.push(BodyVelocity { v, omega, b: bm, c, d: dm, e });
    }
    let mass = mass.map(|x| tidy(*x));
    let n: Vec<Expr> = n.into_iter().map(tidy).collect();
    let t0 = tidy(t0);

    // Forces: potentials into V, the rest into Q by virtual power.
    let mut q_forces = vec![Expr::zero(); m];
    let add_power = |q: &mut Vec<Expr>, force: &[Expr; 3], vel: &[Expr; 3]| {
        for (j, v) in model.velocities.iter().enumerate() {
            let partial = [vel[0].diff(*v), vel[1].diff(*v), vel[2].diff(*v)];
            q[j] = q[j] + dot(force, &partial);
        }
    };
    for f in &model.forces {
        match f {
            Force::Gravity { vector } => {
                for body in &model.bodies {
                    let pos = model.frames[body.frame].point(&body.com);
                    potential = potential - dot(vector, &pos) * body.mass;
                }
            }
            Force::PointForce { frame, point, force_world, .. } => {
                let vel = crate::kinematics::velocity(&model.frames[*frame].point(point), &chain);
                add_power(&mut q_forces, force_world, &vel);
            }
            Force::Torque { body, torque, .. } => {
                let omega = model.frames[model.bodies[*body].frame].omega.clone();
                add_power(&mut q_forces, torque, &omega);
            }
            Force::Spring { a, b, stiffness, rest_length, .. } => {
                let len = spring_length(model, a, b);
                potential = potential + (len - *rest_length).powi(2) * *stiffness / 2;
            }
            Force::Damper { a, b, damping, .. } => {
                // Force -c L' along the line: Q_j = -c L' dL/dq_j.
                let len = spring_length(model, a, b);
                let rate = chain.dt(len);
                for (j, q) in model.coordinates.iter().enumerate() {
                    q_forces[j] = q_forces[j] - *damping * rate * len.diff(*q);
                }
            }
            Force::Generalized { components, .. } => {
                for j in 0..m {
                    q_forces[j] = q_forces[j] + components[j];
                }
            }
            Force::Potential { expr, .. } => potential = potential + *expr,
        }
    }
    let q_forces: Vec<Expr> = q_forces.into_iter().map(tidy).collect();
    let potential = tidy(potential);
    let kinetic = tidy(kinetic);

    // Constraints a q' + b = 0.
    let r = model.constraints.len();
    let mut a = Matrix::zeros(r, m);
    let mut b = Vec::new();
    let mut holonomic = Vec::new();
    let mut constraint_names = Vec::new();
    for (i, c) in model.constraints.iter().enumerate() {
        let (name, rate) = match c {
            Constraint::Velocity { name, expr } => (name, *expr),
            Constraint::Position { name, expr } => {
                holonomic.push((i, *expr));
                (name, chain.dt(*expr))
            }
        };
        constraint_names.push(name.clone());
        let (row, bias) = split_linear(rate, &model.velocities, &zero);
        for j in 0..m {
            a.set(i, j, tidy(row[j]));
        }
        b.push(tidy(bias));
    }
    Mechanics { m, r, p: m - r, bodies, kinetic, potential, mass, n, t0, q_forces, a, b, holonomic, constraint_names }
}

fn spring_length(model: &Model, a: &(usize, [Expr; 3]), b: &(usize, [Expr; 3])) -> Expr {
    let pa = model.frames[a.0].point(&a.1);
    let pb = model.frames[b.0].point(&b.1);
    let d = [pa[0] - pb[0], pa[1] - pb[1], pa[2] - pb[2]];
    dot(&d, &d).simplify_trig(derivation_limits()).sqrt()
}

impl Mechanics {
    /// Kinetic energy rebuilt from M, N, T0 and the velocities (Eq. 13).
    pub fn kinetic_from_matrices(&self, velocities: &[Symbol]) -> Expr {
        let qd: Vec<Expr> = velocities.iter().map(|v| v.expr()).collect();
        let mut t = self.t0;
        for i in 0..self.m {
            t = t + self.n[i] * qd[i];
            for j in 0..self.m {
                t = t + self.mass.get(i, j) * qd[i] * qd[j] / 2;
            }
        }
        t
    }

    /// The generalized momentum of coordinate `j`, `dT/dq'_j = M_j q' + N_j` (Eq. 26 for an
    /// ignorable one).
    pub fn momentum(&self, j: usize, velocities: &[Symbol]) -> Expr {
        Expr::sum((0..self.m).map(|k| self.mass.get(j, k) * velocities[k].expr())) + self.n[j]
    }

    /// The residuals `a q' + b` of the kinematic constraints, one per constraint.
    pub fn velocity_residuals(&self, velocities: &[Symbol]) -> Vec<Expr> {
        (0..self.r)
            .map(|i| Expr::sum((0..self.m).map(|j| self.a.get(i, j) * velocities[j].expr())) + self.b[i])
            .collect()
    }
}
