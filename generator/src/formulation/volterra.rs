//! The paper's reduced Volterra equations (section 2.3) and, with no ignorable coordinates,
//! the standard Volterra / Kane form.
//!
//! - Dynamical constraints `M' q' + N' = 0`, `N' = N2 - G_I` (Eq. 25); `G_I` are symbols,
//!   runtime inputs computed from the initial state (Eq. 26).
//! - `q' = W_NI u_NI + X_NI` from `[Y_NI; M'; a]` (Eqs. 43-44), by the symbolic solver.
//! - `M_NI = W^T M W` (Eq. 47).
//! - `L_NI = U_NI + K_NI - A_NI` (Eq. 65) with `U_NI = W^T (Q - dV/dq)` (Eq. 33). The inertia
//!   part `K_NI - A_NI` is evaluated through the identity the paper derives it from (Eqs.
//!   38-39): `A_NI - K_NI = sum_i m_i a_i . dV_i/du` at `u' = 0`, which with `q'' = W u' + c`,
//!   `c = d/dt(W u + X)` at `u' = 0`, is `W^T (h + M c)`, `h` the generalized inertia forces
//!   of [`super::mechanics`]. So `L_NI = W^T (Q - dV/dq - h - M c)`: one product per body and
//!   quasi-velocity, where differentiating `dT/du` (Eq. 52) costs a derivative of every entry of
//!   `M_NI` by every coordinate.
//! - `M_NI u' = L_NI` (Eq. 64).
//!
//! ```
//! use generator::formulation::{mechanics, volterra};
//! let model = generator::model::load("../models/cart_pendulum.ron").unwrap();
//! let mech = mechanics::derive(&model);
//! let v = volterra::derive(&model, &mech, &[2], &model.quasi_reduced).unwrap();
//! assert_eq!((v.w.rows, v.w.cols), (3, 1));
//! ```

use super::mechanics::Mechanics;
use crate::kinematics::{TimeChain, add3, cross, dot, mat_vec};
use crate::model::{ErrorKind, Model, ModelError};
use crate::symbolic::limits::Limits;
use crate::symbolic::matrix::{SolveError, SolveOptions, solve};
use crate::symbolic::zero::zero_test;
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
    /// `det [Y_NI; M'; a]` (`None` when the matrix is too large to expand).
    pub determinant: Option<Expr>,
    /// `q'` as a function of `(q, u, G, t)`: `W u + X`.
    pub qdot: Vec<Expr>,
    /// `c = d/dt(W u + X)` at `u' = 0`, so that `q'' = W u' + c`.
    pub drift: Vec<Expr>,
    /// `M_NI` (Eq. 47).
    pub mass_ni: Matrix,
    /// `U_NI = W^T (Q - dV/dq)` (Eq. 33).
    pub u_ni: Vec<Expr>,
    /// `K_NI - A_NI = -W^T (h + M c)` (Eqs. 51-63 through Eq. 39).
    pub inertia_ni: Vec<Expr>,
    /// `L_NI = U_NI + K_NI - A_NI` (Eq. 65).
    pub l_ni: Vec<Expr>,
}

/// `e` with each symbol in `symbols` it does not depend on set to zero (exact: `L_NI` is
/// polynomial in `G_I`, and the derivative is decided by the exact zero test). It removes terms
/// that cancel only across bodies, such as the total momentum in the relative motion of
/// scene 2.
fn drop_absent(e: Expr, symbols: &[Symbol]) -> Expr {
    let mut out = e;
    for s in symbols {
        if out.contains(*s) && zero_test(out.diff(*s)).is_zero() {
            out = out.subs(&HashMap::from([(*s, Expr::zero())]));
        }
    }
    out
}

/// Largest model (coordinates) for which the body route of `inertia_by_bodies` is tried beside
/// the coordinate route. Measured: it wins on the paper's scenes (scene 2's reduced right-hand
/// side 1186 operations against 2149), loses from a 6-link floating chain on, and costs more
/// than the rest of the derivation there.
const MAX_BODY_ROUTE_COORDINATES: usize = 10;

/// Largest matrix whose determinant is expanded symbolically (for `inspect`).
const MAX_DETERMINANT_SIZE: usize = 10;

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
    let tidy = &mech.tidy;
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
            y.set(k, j, tidy.of(e.diff(*v)));
        }
        z.push(tidy.of(e.subs(&zero)));
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
    let opts = SolveOptions {
        constants: model.constant_symbols().into_iter().chain(g.iter().copied()).collect(),
        limits: Limits { max_terms: 2_000, max_work: 400_000 },
        determinant: m <= MAX_DETERMINANT_SIZE,
    };
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
            w.set(i, k, tidy.of(sol.x.get(i, k)));
        }
        x.push(tidy.of(sol.x.get(i, n_u)));
    }
    let u: Vec<Symbol> = (0..n_u).map(quasi_symbol).collect();
    let qdot: Vec<Expr> = (0..m)
        .map(|i| tidy.of(Expr::sum((0..n_u).filter(|&k| !w.get(i, k).is_zero()).map(|k| w.get(i, k) * u[k].expr())) + x[i]))
        .collect();
    // c = d/dt(W u + X) along the motion, u and G constant.
    let chain = TimeChain::new(model.t, model.coordinates.iter().copied().zip(qdot.iter().copied()).collect());
    let drift: Vec<Expr> = qdot.iter().map(|e| tidy.of(chain.dt(*e))).collect();
    // U_NI = W^T (Q - dV/dq), the rates replaced by W u + X (Eq. 33).
    let to_u: HashMap<Symbol, Expr> = model.velocities.iter().copied().zip(qdot.iter().copied()).collect();
    let wt = w.transpose();
    let project = |v: Vec<Expr>| -> Vec<Expr> { wt.mul(&Matrix::column(v)).col(0) };
    let applied: Vec<Expr> = (0..m).map(|j| mech.q_forces[j] - mech.potential_gradient[j]).collect();
    let u_ni: Vec<Expr> = project(Expr::subs_all(&applied, &to_u)).into_iter().map(|e| tidy.of(e)).collect();
    // M_NI and K_NI - A_NI from the coordinates' M and h; where the quasi-velocities are not
    // plain rates (a body's angular velocity), also from the bodies' velocities in u, which
    // cancels the rate transformation body by body; the smaller is kept (both are exact).
    let by_coordinates = inertia_by_coordinates(mech, &w, &drift, &to_u);
    let rates_only = y.data.iter().all(|e| e.as_num().is_some());
    let (mass_ni, inertia_ni) = if rates_only || m > MAX_BODY_ROUTE_COORDINATES {
        by_coordinates
    } else {
        let by_bodies = inertia_by_bodies(model, mech, &u, &qdot, &chain);
        let size = |(mass, inertia): &(Matrix, Vec<Expr>)| {
            crate::symbolic::expr::post_order(&mass.data.iter().chain(inertia).copied().collect::<Vec<_>>()).len()
        };
        if size(&by_bodies) <= size(&by_coordinates) { by_bodies } else { by_coordinates }
    };
    let l_ni: Vec<Expr> = (0..n_u).map(|k| drop_absent(tidy.of(u_ni[k] + inertia_ni[k]), &g)).collect();
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
        drift,
        mass_ni,
        u_ni,
        inertia_ni,
        l_ni,
    })
}

/// `M_NI` and `K_NI - A_NI` from the bodies' velocities in the quasi-velocities (Kane's
/// form of Eqs. 35-39): `M_NI = sum m P^T P + O^T I O`, `K_NI - A_NI = -sum m P^T a + O^T (I
/// alpha + omega x I omega)`, with `P = dV/du`, `O = d omega/du` and the accelerations at
/// `u' = 0`. Compact where the quasi-velocities are the bodies' own rates (a base whose
/// angular velocity is a quasi-velocity has `O = [I 0]`).
fn inertia_by_bodies(model: &Model, mech: &Mechanics, u: &[Symbol], qdot: &[Expr], chain: &TimeChain) -> (Matrix, Vec<Expr>) {
    let tidy = &mech.tidy;
    let n_u = u.len();
    let to_u: HashMap<Symbol, Expr> = model.velocities.iter().copied().zip(qdot.iter().copied()).collect();
    let mut mass_terms: Vec<Vec<Expr>> = vec![Vec::new(); n_u * n_u];
    let mut inertia_terms: Vec<Vec<Expr>> = vec![Vec::new(); n_u];
    for (bv, body) in mech.bodies.iter().zip(&model.bodies) {
        // The velocity in the quasi-velocities, in world or body components, whichever is
        // smaller here (the momentum rows of W are simplest in world components).
        let v = Expr::subs_all(&bv.v, &to_u);
        let v = [v[0], v[1], v[2]];
        let rot = tidy.matrix(&model.frames[body.frame].rotation);
        let (v_body, v_world) = if bv.in_body { (v, mat_vec(&rot, &v)) } else { (mat_vec(&rot.transpose(), &v), v) };
        let v_body = v_body.map(|e| tidy.rational(e));
        let v_world = v_world.map(|e| tidy.rational(e));
        let in_body = crate::symbolic::expr::post_order(&v_body).len() < crate::symbolic::expr::post_order(&v_world).len();
        let v = if in_body { v_body } else { v_world };
        let om = Expr::subs_all(&bv.omega, &to_u).into_iter().map(|e| tidy.rational(e)).collect::<Vec<_>>();
        let om = [om[0], om[1], om[2]];
        let partial = |x: &[Expr; 3], k: usize| x.map(|e| tidy.rational(e.diff(u[k])));
        let p: Vec<[Expr; 3]> = (0..n_u).map(|k| partial(&v, k)).collect();
        let o: Vec<[Expr; 3]> = (0..n_u).map(|k| partial(&om, k)).collect();
        let dv = chain.dt3(&v);
        let accel = tidy.of3(if in_body { add3(&dv, &cross(&om, &v)) } else { dv });
        let torque = body.inertia.as_ref().map(|inertia| {
            let alpha = chain.dt3(&om);
            tidy.of3(add3(&mat_vec(inertia, &alpha), &cross(&om, &mat_vec(inertia, &om))))
        });
        let io: Vec<Option<[Expr; 3]>> = o.iter().map(|ok| body.inertia.as_ref().map(|i| mat_vec(i, ok))).collect();
        for k in 0..n_u {
            for l in k..n_u {
                let mut e = dot(&p[k], &p[l]) * body.mass;
                if let Some(iol) = &io[l] {
                    e = e + dot(&o[k], iol);
                }
                if !e.is_zero() {
                    mass_terms[k * n_u + l].push(e);
                }
            }
            inertia_terms[k].push(-(dot(&p[k], &accel) * body.mass));
            if let Some(t) = &torque {
                inertia_terms[k].push(-dot(&o[k], t));
            }
        }
    }
    let mut mass = Matrix::zeros(n_u, n_u);
    for k in 0..n_u {
        for l in k..n_u {
            let e = tidy.of(Expr::sum(std::mem::take(&mut mass_terms[k * n_u + l])));
            mass.set(k, l, e);
            mass.set(l, k, e);
        }
    }
    (mass, inertia_terms.into_iter().map(|t| tidy.of(Expr::sum(t))).collect())
}

/// `M_NI = W^T M W` and `K_NI - A_NI = -W^T (h + M c)` from the coordinates' mass matrix and
/// inertia forces: compact where `W` is simple (quasi-velocities that are rates).
fn inertia_by_coordinates(mech: &Mechanics, w: &Matrix, drift: &[Expr], to_u: &HashMap<Symbol, Expr>) -> (Matrix, Vec<Expr>) {
    let tidy = &mech.tidy;
    let wt = w.transpose();
    let mass = tidy.matrix(&wt.mul(&mech.mass.mul(w)));
    let inertial = Expr::subs_all(&mech.inertial, to_u);
    let mc = mech.mass.mul(&Matrix::column(drift.to_vec()));
    let rest: Vec<Expr> = (0..mech.m).map(|j| -(inertial[j] + mc.get(j, 0))).collect();
    (mass, wt.mul(&Matrix::column(rest)).col(0).into_iter().map(|e| tidy.of(e)).collect())
}
