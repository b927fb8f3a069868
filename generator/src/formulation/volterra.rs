//! The paper's reduced Volterra equations (section 2.3) and, with no ignorable coordinates,
//! the standard Volterra / Kane form.
//!
//! - Dynamical constraints `M' q' + N' = 0`, `N' = N2 - G_I` (Eq. 25); `G_I` are symbols,
//!   runtime inputs computed from the initial state (Eq. 26).
//! - `q' = W_NI u_NI + X_NI` from `[Y_NI; M'; a]` (Eqs. 43-44), by the symbolic solver.
//! - `M_NI = W^T M W`, `N_NI = W^T (M X + N)` (Eqs. 47-48).
//! - `A_NI = d/dt(dT/du)` without the `u'` term (Eq. 52).
//! - `K_NI = sum_i B_NI_i^T P_i + C_NI_i^T H_Gi` (Eqs. 57-63), where the time derivative of the
//!   partial angular velocity is inertial: with body-frame components it gets the transport
//!   term `omega x (.)` (the trap in design.md).
//! - `U_NI = W^T (Q - dV/dq)`, `L_NI = U_NI + K_NI - A_NI` (Eq. 65), `M_NI u' = L_NI` (Eq. 64).
//!
//! ```
//! use generator::formulation::{mechanics, volterra};
//! let model = generator::model::load("../models/cart_pendulum.ron").unwrap();
//! let mech = mechanics::derive(&model);
//! let v = volterra::derive(&model, &mech, &[2], &model.quasi_reduced).unwrap();
//! assert_eq!((v.w.rows, v.w.cols), (3, 1));
//! ```

use super::mechanics::{Mechanics, derivation_limits};
use crate::kinematics::TimeChain;
use crate::model::{ErrorKind, Model, ModelError};
use crate::symbolic::matrix::{SolveError, SolveOptions, solve};
use crate::symbolic::eval::magnitude;
use crate::symbolic::trig::SplitMix;
use crate::symbolic::{Expr, Matrix, Symbol};
use std::collections::HashMap;

/// The derived reduced (or, with s = 0, standard) Volterra equations.
#[derive(Clone, Debug)]
pub struct Volterra {
    /// Indices of the ignorable coordinates used (s of them).
    pub ignorable: Vec<usize>,
    /// `G_I` symbols, one per ignorable coordinate.
    pub g: Vec<Symbol>,
    /// Quasi-velocity symbols `u_1..`.
    pub u: Vec<Symbol>,
    /// `Y_NI`, `Z_NI` (Eq. 42).
    pub y: Matrix,
    pub z: Vec<Expr>,
    /// `W_NI` (m x (p-s)) and `X_NI` (m) of Eq. 43.
    pub w: Matrix,
    pub x: Vec<Expr>,
    /// Factors of the pivots of `[Y_NI; M'; a]`: singular only where one vanishes.
    pub singular_factors: Vec<Expr>,
    /// `det [Y_NI; M'; a]`.
    pub determinant: Expr,
    /// `q'` as a function of `(q, u, G, t)`: `W u + X`.
    pub qdot: Vec<Expr>,
    pub mass_ni: Matrix,
    pub n_ni: Vec<Expr>,
    pub a_ni: Vec<Expr>,
    pub k_ni: Vec<Expr>,
    pub u_ni: Vec<Expr>,
    pub l_ni: Vec<Expr>,
}

/// `e` with each symbol in `symbols` it does not depend on (its derivative is identically
/// zero) set to zero. `L_NI` is polynomial in `G_I`, so this is exact; it removes terms that
/// cancel only across bodies, such as the total momentum in the relative motion of scene 2.
///
/// The test is numeric: the derivative must vanish, against the size of its terms, at three
/// seeded random points (a symbolic proof on expressions this size costs more than the
/// whole derivation; an analytic function that vanishes at random points is zero).
fn drop_absent(model: &Model, e: Expr, symbols: &[Symbol]) -> Expr {
    let mut out = e;
    for s in symbols {
        if out.contains(*s) && vanishes_at_random_points(model, out.diff(*s)) {
            out = out.subs(&HashMap::from([(*s, Expr::zero())]));
        }
    }
    out
}

fn vanishes_at_random_points(model: &Model, d: Expr) -> bool {
    let bound = magnitude(d);
    let mut rng = SplitMix(0x5EED);
    (0..3).all(|_| {
        let mut env = model.parameter_env();
        for s in d.free_symbols() {
            if env.get(s).is_none() {
                env.set(s, rng.uniform(-1.0, 1.0));
            }
        }
        match (d.eval(&env), bound.eval(&env)) {
            (Ok(v), Ok(b)) => v.is_finite() && b.is_finite() && v.abs() <= 1e-12 * b,
            _ => false,
        }
    })
}

/// Name of the `G` symbol of an ignorable coordinate.
pub fn momentum_symbol(model: &Model, j: usize) -> Symbol {
    Symbol::new(&format!("G_{}", model.coordinates[j].name()))
}

/// Name of the j-th quasi-velocity symbol.
pub fn quasi_symbol(k: usize) -> Symbol {
    Symbol::new(&format!("u{}", k + 1))
}

/// Derives the Volterra equations for the quasi-velocities `quasi` with the ignorable set
/// `ignorable` (empty for the standard form).
pub fn derive(model: &Model, mech: &Mechanics, ignorable: &[usize], quasi: &[Expr]) -> Result<Volterra, ModelError> {
    let m = mech.m;
    let s = ignorable.len();
    let n_u = mech.p - s;
    let lim = derivation_limits();
    let tidy = |e: Expr| e.simplify_trig(lim);
    let which = if s == 0 { "full" } else { "reduced" };
    if quasi.len() != n_u {
        return Err(model.error(
            ErrorKind::QuasiVelocityCount,
            &format!("quasi_velocities.{which}"),
            which,
            format!("{} quasi-velocities given, but p - s = {} - {s} = {n_u} are needed", quasi.len(), mech.p),
            format!("list exactly {n_u} quasi-velocities under `{which}`"),
        ));
    }
    let zero: HashMap<Symbol, Expr> = model.velocities.iter().map(|v| (*v, Expr::zero())).collect();
    // Y_NI, Z_NI.
    let mut y = Matrix::zeros(n_u, m);
    let mut z = Vec::new();
    for (k, e) in quasi.iter().enumerate() {
        for (j, v) in model.velocities.iter().enumerate() {
            y.set(k, j, tidy(e.diff(*v)));
        }
        z.push(tidy(e.subs(&zero)));
    }
    let g: Vec<Symbol> = ignorable.iter().map(|&j| momentum_symbol(model, j)).collect();
    // [Y; M'; a] and the right-hand sides [I | -[Z; N'; b]].
    let mut mp = Matrix::zeros(s, m);
    let mut np = Vec::new();
    for (k, &i) in ignorable.iter().enumerate() {
        for j in 0..m {
            mp.set(k, j, mech.mass.get(i, j));
        }
        np.push(mech.n[i] - g[k].expr());
    }
    let a_full = Matrix::vstack(&[&y, &mp, &mech.a]);
    let mut rhs = Matrix::zeros(m, n_u + 1);
    for k in 0..n_u {
        rhs.set(k, k, Expr::one());
    }
    let bias: Vec<Expr> = z.iter().chain(&np).chain(&mech.b).copied().collect();
    for (i, e) in bias.iter().enumerate() {
        rhs.set(i, n_u, -*e);
    }
    let opts = SolveOptions { constants: model.constant_symbols().into_iter().chain(g.iter().copied()).collect(), limits: lim };
    let sol = solve(&a_full, &rhs, &opts).map_err(|e| match e {
        SolveError::Singular { rows, .. } => {
            let names: Vec<String> = rows
                .iter()
                .map(|&r| {
                    if r < n_u {
                        format!("quasi-velocity {} (`{}`)", r + 1, quasi[r])
                    } else if r < n_u + s {
                        format!("the momentum of `{}`", model.coordinates[ignorable[r - n_u]].name())
                    } else {
                        format!("constraint `{}`", mech.constraint_names[r - n_u - s])
                    }
                })
                .collect();
            model.error(
                ErrorKind::SingularQuasiVelocities,
                &format!("quasi_velocities.{which}"),
                which,
                format!(
                    "the quasi-velocities with the constraints do not determine q' at any state: {} {} on the other rows",
                    names.join(", "),
                    if names.len() == 1 { "depends" } else { "depend" }
                ),
                "choose quasi-velocities independent of each other, of the constraints and of the ignorable momenta".into(),
            )
        }
        other => model.error(ErrorKind::Dimension, "quasi_velocities", which, other.to_string(), String::new()),
    })?;
    let mut w = Matrix::zeros(m, n_u);
    let mut x = Vec::new();
    for i in 0..m {
        for k in 0..n_u {
            w.set(i, k, tidy(sol.x.get(i, k)));
        }
        x.push(tidy(sol.x.get(i, n_u)));
    }
    let u: Vec<Symbol> = (0..n_u).map(quasi_symbol).collect();
    let u_col = Matrix::column(u.iter().map(|s| s.expr()).collect());
    let wu = w.mul(&u_col);
    let qdot: Vec<Expr> = (0..m).map(|i| wu.get(i, 0) + x[i]).collect();
    // Time derivative along the motion: d/dt = d/dt|explicit + sum_k d/dq_k q'_k (q' = W u + X).
    let chain = TimeChain { t: model.t, pairs: model.coordinates.iter().copied().zip(qdot.iter().copied()).collect() };

    // M_NI, N_NI (Eqs. 47-48).
    let wt = w.transpose();
    let mass_ni = wt.mul(&mech.mass).mul(&w).map(|e| tidy(*e));
    let mx_n = mech.mass.mul(&Matrix::column(x.clone())).add(&Matrix::column(mech.n.clone()));
    let n_ni: Vec<Expr> = wt.mul(&mx_n).col(0).into_iter().map(tidy).collect();
    // A_NI (Eq. 52).
    let dtdu = mass_ni.mul(&u_col).add(&Matrix::column(n_ni.clone()));
    let a_ni: Vec<Expr> = dtdu.col(0).into_iter().map(|e| chain.dt(e)).collect();
    // K_NI (Eqs. 57-63).
    let mut k_ni = vec![Expr::zero(); n_u];
    let qdot_col = Matrix::column(qdot.clone());
    for (bi, body) in mech.bodies.iter().zip(&model.bodies) {
        // Partial velocities and velocities in u, simplified first: the round trip
        // u -> q' -> omega cancels here (omega of a body whose rates are quasi-velocities
        // becomes u itself), which keeps everything derived from them small.
        // Translation in the body's own components (R^T of world components): the dot
        // products are the same, but the rotation of the body drops out of them. Their
        // inertial derivative gets the transport term omega x (.), as for the rotation.
        // Whichever of world and body components is smaller is used (the transport term
        // vanishes in world components).
        // (decided on the velocity, the partial velocities follow it).
        let pv_world = bi.b.mul(&w);
        let v_world = Matrix::column(bi.b.mul(&qdot_col).col(0).iter().zip(&bi.c).map(|(a, b)| *a + *b).collect());
        let rt = model.frames[body.frame].rotation.transpose();
        let v_in_world = v_world.map(|e| tidy(*e));
        let v_in_body = rt.mul(&v_world).map(|e| tidy(*e));
        let size = |a: &Matrix| a.data.iter().map(|e| e.dag_size()).sum::<usize>();
        let body_frame = size(&v_in_body) < size(&v_in_world);
        let (pv, v) = if body_frame {
            (rt.mul(&pv_world).map(|e| tidy(*e)), v_in_body)
        } else {
            (pv_world.map(|e| tidy(*e)), v_in_world)
        };
        let v = v.col(0);
        let pw = bi.d.mul(&w).map(|e| tidy(*e)); // d omega/du, body components
        let om = bi.d.mul(&qdot_col).col(0).iter().zip(&bi.e).map(|(a, b)| tidy(*a + *b)).collect::<Vec<_>>();
        let cross = |a: [Expr; 3], b: [Expr; 3]| [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
        for k in 0..n_u {
            // F_NI: m (d/dt dV/du_k, inertial) . V
            let c = [pv.get(0, k), pv.get(1, k), pv.get(2, k)];
            let transport = if body_frame { cross([om[0], om[1], om[2]], c) } else { [Expr::zero(); 3] };
            let dpv: Vec<Expr> = (0..3).map(|r| chain.dt(c[r]) + transport[r]).collect();
            k_ni[k] = k_ni[k] + (dpv[0] * v[0] + dpv[1] * v[1] + dpv[2] * v[2]) * body.mass;
            // J_NI: (d/dt dω/du_k, inertial) . H, with H = I ω in body components.
            if let Some(inertia) = &body.inertia {
                let c = [pw.get(0, k), pw.get(1, k), pw.get(2, k)];
                let transport = cross([om[0], om[1], om[2]], c);
                let dpw: Vec<Expr> = (0..3).map(|r| chain.dt(c[r]) + transport[r]).collect();
                let h = inertia.mul(&Matrix::column(om.clone()));
                k_ni[k] = k_ni[k] + dpw[0] * h.get(0, 0) + dpw[1] * h.get(1, 0) + dpw[2] * h.get(2, 0);
            }
        }
    }
    // U_NI = W^T (Q - dV/dq), with the forces' rates replaced by W u + X.
    let to_u: HashMap<Symbol, Expr> = model.velocities.iter().copied().zip(qdot.iter().copied()).collect();
    let gen_force: Vec<Expr> = model
        .coordinates
        .iter()
        .enumerate()
        .map(|(j, q)| mech.q_forces[j].subs(&to_u) - mech.potential.diff(*q))
        .collect();
    let u_ni: Vec<Expr> = wt.mul(&Matrix::column(gen_force)).col(0);
    let l_ni: Vec<Expr> = (0..n_u).map(|k| drop_absent(model, u_ni[k] + k_ni[k] - a_ni[k], &g)).collect();
    Ok(Volterra {
        ignorable: ignorable.to_vec(),
        g,
        u,
        y,
        z,
        w,
        x,
        singular_factors: sol.pivots,
        determinant: sol.determinant,
        qdot,
        mass_ni,
        n_ni,
        a_ni,
        k_ni,
        u_ni,
        l_ni,
    })
}

