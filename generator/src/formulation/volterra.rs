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

use super::mechanics::{Mechanics, Translation, is_small};
use crate::kinematics::{TimeChain, add3, cross, dot, mat_vec};
use crate::model::{ErrorKind, Model, ModelError};
use crate::symbolic::limits::Limits;
use crate::symbolic::matrix::{SolveError, SolveOptions, solve};
use crate::symbolic::zero::settle_absent;
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
    /// `M_NI` (Eq. 47).
    pub mass_ni: Matrix,
    /// `U_NI = W^T (Q - dV/dq)` (Eq. 33).
    pub u_ni: Vec<Expr>,
    /// `L_NI = U_NI + K_NI - A_NI` (Eq. 65).
    pub l_ni: Vec<Expr>,
    /// How `q' = W u + X` was eliminated and the inertia terms formed.
    pub route: &'static str,
}

impl crate::symbolic::transfer::Transfer for Volterra {
    fn visit(&mut self, v: &mut dyn crate::symbolic::transfer::Visitor) {
        self.g.visit(v);
        self.u.visit(v);
        self.y.visit(v);
        self.z.visit(v);
        self.w.visit(v);
        self.x.visit(v);
        self.singular_factors.visit(v);
        self.determinant.visit(v);
        self.qdot.visit(v);
        self.mass_ni.visit(v);
        self.u_ni.visit(v);
        self.l_ni.visit(v);
    }
}

/// Largest model (coordinates) for which the body route of `inertia_by_bodies` is taken, when the
/// quasi-velocities are not plain rates. Measured (distinct nodes of `M_NI` and `L_NI`): the
/// body route is smaller on scenes 2 and 3 (scene 2's Kane form 844 against 2008) and on the
/// floating chain with 2 links (2620 against 2983), the coordinate route from 3 links on.
const MAX_BODY_ROUTE_COORDINATES: usize = 8;

/// Largest model for which both routes are derived and the smaller kept (beyond
/// [`MAX_BODY_ROUTE_COORDINATES`]): scene 2 in quaternions has 9 coordinates, and its body route
/// gives Kane's right-hand side in 454 operations against 2175 by the coordinates. Not beyond:
/// deriving both for the floating chain of 6 links (12 coordinates) took 6.9 s against 0.85 s.
const MAX_COMPARED_ROUTE_COORDINATES: usize = 9;

/// Largest matrix whose determinant is expanded symbolically (for `inspect`).
const MAX_DETERMINANT_SIZE: usize = 10;

/// Name of the `G` symbol of an ignorable coordinate.
pub fn momentum_symbol(model: &Model, j: usize) -> Symbol {
    Symbol::internal(&format!("G_{}", model.coordinates[j].name()))
}

/// Name of the j-th quasi-velocity symbol.
pub fn quasi_symbol(k: usize) -> Symbol {
    Symbol::internal(&format!("u{}", k + 1))
}

/// `Y` and `Z` of `u = Y q' + Z` (Eq. 42).
fn quasi_matrices(model: &Model, mech: &Mechanics, quasi: &[Expr]) -> (Matrix, Vec<Expr>) {
    let zero: HashMap<Symbol, Expr> = model.velocities.iter().map(|v| (*v, Expr::zero())).collect();
    let mut y = Matrix::zeros(quasi.len(), mech.m);
    let mut z = Vec::new();
    for (k, e) in quasi.iter().enumerate() {
        for (j, v) in model.velocities.iter().enumerate() {
            y.set(k, j, mech.tidy.of(e.diff(*v)));
        }
        z.push(mech.tidy.of(e.subs(&zero)));
    }
    (y, z)
}

/// The reduced Volterra equations for `quasi` with the ignorable set `ignorable`, given the
/// Kane form of the same model. Where the reduced quasi-velocities are Kane's without the
/// ignorable rates (the scenes' choice), they come from Kane's equations by eliminating the
/// ignorable rates with the conserved momenta ([`by_schur_complement`]); otherwise directly
/// from Eqs. 43-65 ([`derive()`]). Measured: the Schur route gives scene 2's reduced right-hand
/// side in 978 operations against 3100 by the direct route, and scene 3's in 255 against 641.
pub fn derive_reduced(model: &Model, mech: &Mechanics, ignorable: &[usize], quasi: &[Expr], kane: &Volterra) -> Result<Volterra, ModelError> {
    if ignorable.is_empty() {
        return derive(model, mech, ignorable, quasi);
    }
    match by_schur_complement(model, mech, ignorable, quasi, kane) {
        Some(schur) => Ok(schur),
        None => derive(model, mech, ignorable, quasi),
    }
}

/// Where the reduced quasi-velocities and the ignorable rates sit among Kane's.
pub struct SchurMap {
    /// Kane's index of each reduced quasi-velocity.
    pub map: Vec<usize>,
    /// Kane's index of each ignorable coordinate's rate `q_I'`.
    pub rates: Vec<usize>,
    /// `Y`, `Z` of the reduced quasi-velocities.
    pub y: Matrix,
    pub z: Vec<Expr>,
}

/// The [`SchurMap`], `None` unless Kane's quasi-velocities are the reduced ones (in any order)
/// plus the ignorable rates `q_I'` and no reduced one involves a `q_I'`.
pub fn schur_map(model: &Model, mech: &Mechanics, ignorable: &[usize], quasi: &[Expr], kane: &Volterra) -> Option<SchurMap> {
    let (m, s) = (mech.m, ignorable.len());
    let n_u = quasi.len();
    if n_u + s != kane.u.len() {
        return None;
    }
    let (y, z) = quasi_matrices(model, mech, quasi);
    let row = |mat: &Matrix, r: usize| mat.row(r);
    // Each reduced quasi-velocity is one of Kane's; each ignorable rate is one of Kane's.
    let mut used = vec![false; kane.u.len()];
    let mut map = Vec::with_capacity(n_u);
    for k in 0..n_u {
        let r = (0..kane.u.len()).find(|&r| !used[r] && row(&kane.y, r) == row(&y, k) && kane.z[r] == z[k])?;
        used[r] = true;
        map.push(r);
    }
    let mut rates = Vec::with_capacity(s);
    for &j in ignorable {
        if (0..n_u).any(|k| !y.get(k, j).is_zero()) {
            return None;
        }
        let unit: Vec<Expr> = (0..m).map(|c| if c == j { Expr::one() } else { Expr::zero() }).collect();
        let r = (0..kane.u.len()).find(|&r| !used[r] && row(&kane.y, r) == unit && kane.z[r].is_zero())?;
        used[r] = true;
        rates.push(r);
    }
    Some(SchurMap { map, rates, y, z })
}

/// The reduced equations as the Schur complement of Kane's, `None` unless Kane's
/// quasi-velocities are the reduced ones (in any order) plus the ignorable rates `q_I'`.
///
/// With `u = [u_N; v_I]`, `v_I = q_I'`, Kane's equations are `M_K u' = L_K`. The momenta
/// `G_I = dT/dq_I'` are linear in `u`, `G = K_N u_N + K_I v_I + n`, which gives `v_I` from
/// `(u_N, G)`; eliminating `v_I'` between the two blocks of Kane's equations leaves
/// `(M_NN - M_NI M_II^-1 M_IN) u_N' = L_N - M_NI M_II^-1 L_I`: p - s equations, exactly the
/// reduced Volterra equations for `u_N` (the same `M_NI`, since `K_I = M_II` when `u_N` does
/// not involve `q_I'`), at the cost of Kane's assembly and an s x s elimination.
/// The options of the `s x s` solve for the ignorable rates from their momenta
/// (`M_II v_I = G - ...`), the same in the Schur route, the composite recursion's and the
/// articulated-body recursion's: a small system, checked at the model's initial state.
pub(super) fn momenta_solve_options(model: &Model) -> SolveOptions {
    SolveOptions {
        constants: model.constant_symbols(),
        limits: Limits { max_terms: 2_000, max_work: 400_000 },
        determinant: false,
        normalize: false,
        reference: Some(model.initial_env()),
    }
}

pub fn by_schur_complement(model: &Model, mech: &Mechanics, ignorable: &[usize], quasi: &[Expr], kane: &Volterra) -> Option<Volterra> {
    let tidy = &mech.tidy;
    let (m, s) = (mech.m, ignorable.len());
    let n_u = quasi.len();
    let SchurMap { map, rates, y, z } = schur_map(model, mech, ignorable, quasi, kane)?;
    let g: Vec<Symbol> = ignorable.iter().map(|&j| momentum_symbol(model, j)).collect();
    let u: Vec<Symbol> = (0..n_u).map(quasi_symbol).collect();
    // The momenta in Kane's quasi-velocities: T = u^T M_K u / 2 + u^T N_K + T0 and u_N free of
    // q_I', so G = dT/dv_I = M_II v_I + M_IN u_N + n with n = M_I X_K + N_I (the momenta at
    // u = 0). Solved for v_I; M_K's own entries keep the DAG shared with the Schur complement.
    let mk = &kane.mass_ni;
    let mut m_ii = Matrix::zeros(s, s);
    let mut rhs = Matrix::zeros(s, 1);
    for (a, &j) in ignorable.iter().enumerate() {
        for (b, &rb) in rates.iter().enumerate() {
            m_ii.set(a, b, mk.get(rates[a], rb));
        }
        // Combinations of simplified entries ([`Tidy::combination`]): the n-link pendulum's
        // momentum of the cart sums a term per link and mass (past the term limit at 60 links).
        let n = tidy.combination(Expr::sum((0..m).map(|c| mech.mass.get(j, c) * kane.x[c])) + mech.n[j], m);
        let coupled = Expr::sum(map.iter().zip(&u).map(|(&r, uk)| mk.get(rates[a], r) * uk.expr()));
        rhs.set(a, 0, tidy.combination(g[a].expr() - n - coupled, m));
    }
    let opts = momenta_solve_options(model);
    let v_i = solve(&m_ii, &rhs, &opts).ok()?;
    // Kane's quasi-velocities in the reduced ones: u_N renamed, v_I from the momenta.
    let mut sigma: HashMap<Symbol, Expr> = HashMap::new();
    for (k, &r) in map.iter().enumerate() {
        sigma.insert(kane.u[r], u[k].expr());
    }
    // Built from M_K's entries, which the right-hand side computes anyway: simplifying the
    // combination would only copy them.
    for (b, &r) in rates.iter().enumerate() {
        sigma.insert(kane.u[r], v_i.x.get(b, 0));
    }
    let sub = |items: &[Expr]| -> Vec<Expr> { Expr::subs_all(items, &sigma) };
    let qdot = sub(&kane.qdot);
    let (l_k, u_k) = (sub(&kane.l_ni), sub(&kane.u_ni));
    // Schur complement: M_II Z = [M_IN | L_I | U_I].
    let mut right = Matrix::zeros(s, n_u + 2);
    for (a, &ra) in rates.iter().enumerate() {
        for (k, &rk) in map.iter().enumerate() {
            right.set(a, k, mk.get(ra, rk));
        }
        right.set(a, n_u, l_k[ra]);
        right.set(a, n_u + 1, u_k[ra]);
    }
    let zs = solve(&m_ii, &right, &opts).ok()?;
    let mut mass_ni = Matrix::zeros(n_u, n_u);
    let coupling = |k: usize, col: usize| Expr::sum((0..s).map(|a| mk.get(map[k], rates[a]) * zs.x.get(a, col)));
    // The Schur complement combines the ignorable rows' entries, which carry the absolute
    // orientation, into entries that do not (the locked inertia of a free system depends on its
    // shape only): on small models simplified, and kept where that is smaller; on large ones the
    // combination of already simplified entries is left as it is (simplifying it costs more
    // than the rest of the reduction and finds little: 1.1 s of 2.4 s on the 50-link chain).
    let small = is_small(m);
    // A free system's shape equations do not depend on where it is or how it is turned: the
    // coordinates an entry does not depend on (decided exactly) are set to zero before it is
    // simplified, which takes the absolute orientation's sines and cosines out of it (scene 2).
    let simplify = |e: Expr| {
        if !small {
            return e;
        }
        let e = settle_absent(e, &model.coordinates);
        let s = tidy.of(e);
        if crate::symbolic::expr::dag_ops(&[s]) < crate::symbolic::expr::dag_ops(&[e]) { s } else { e }
    };
    for k in 0..n_u {
        for l in k..n_u {
            let e = simplify(mk.get(map[k], map[l]) - coupling(k, l));
            mass_ni.set(k, l, e);
            mass_ni.set(l, k, e);
        }
    }
    let l_ni: Vec<Expr> = (0..n_u).map(|k| settle_absent(simplify(l_k[map[k]] - coupling(k, n_u)), &g)).collect();
    let u_ni: Vec<Expr> = (0..n_u).map(|k| u_k[map[k]] - coupling(k, n_u + 1)).collect();
    let mut w = Matrix::zeros(m, n_u);
    let zero_n: HashMap<Symbol, Expr> = u.iter().map(|s| (*s, Expr::zero())).collect();
    for i in 0..m {
        for k in 0..n_u {
            w.set(i, k, qdot[i].diff(u[k]));
        }
    }
    let x: Vec<Expr> = Expr::subs_all(&qdot, &zero_n);
    let mut singular_factors = kane.singular_factors.clone();
    for f in v_i.pivots.iter().chain(&zs.pivots) {
        if !singular_factors.contains(f) {
            singular_factors.push(*f);
        }
    }
    Some(Volterra {
        ignorable: ignorable.to_vec(),
        g,
        u,
        y,
        z,
        w,
        x,
        singular_factors,
        determinant: None,
        qdot,
        mass_ni,
        u_ni,
        l_ni,
        route: "Schur complement of Kane's equations: the momenta eliminate the ignorable rates",
    })
}

/// Derives the Volterra equations for the quasi-velocities `quasi` with the ignorable set
/// `ignorable` (empty for the standard form), directly from Eqs. 43-65.
pub fn derive(model: &Model, mech: &Mechanics, ignorable: &[usize], quasi: &[Expr]) -> Result<Volterra, ModelError> {
    let m = mech.m;
    let s = ignorable.len();
    let n_u = mech.p - s;
    let tidy = &mech.tidy;
    // The list the quasi-velocities came from, for the errors' place (the reduced list with no
    // ignorable coordinate is still the reduced list).
    let which = if s > 0 || (quasi == &model.quasi_reduced[..] && quasi != &model.quasi_full[..]) { "reduced" } else { "full" };
    if quasi.len() != n_u {
        return Err(model.error(
            ErrorKind::QuasiVelocityCount,
            &format!("quasi_velocities.{which}"),
            which,
            format!("{} quasi-velocities given, but p - s = {} - {s} = {n_u} are needed", quasi.len(), mech.p),
            format!("list exactly {n_u} quasi-velocities under `{which}`"),
        ));
    }
    let (y, z) = quasi_matrices(model, mech, quasi);
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
        normalize: true,
        reference: Some(model.initial_env()),
    };
    // A body's angular velocity in quaternions gives orthogonal rows: inverted as A^T D^-1.
    let rates_only = y.data.iter().all(|e| e.as_num().is_some());
    let orthogonal = if rates_only { None } else { crate::symbolic::matrix::solve_orthogonal(&a_full, &rhs) };
    let by_rows = orthogonal.is_some();
    let sol = match orthogonal {
        Some(sol) => Ok(sol),
        None => solve(&a_full, &rhs, &opts),
    }
    .map_err(|e| match e {
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
    let qdot: Vec<Expr> = (0..m).map(|i| tidy.of(Expr::sum((0..n_u).filter(|&k| !w.get(i, k).is_zero()).map(|k| w.get(i, k) * u[k].expr())) + x[i])).collect();
    // c = d/dt(W u + X) along the motion, u and G constant.
    let chain = TimeChain::new(model.t, model.coordinates.iter().copied().zip(qdot.iter().copied()).collect());
    let drift: Vec<Expr> = qdot.iter().map(|e| tidy.of(chain.dt(*e))).collect();
    // U_NI = W^T (Q - dV/dq), the rates replaced by W u + X (Eq. 33).
    let to_u: HashMap<Symbol, Expr> = model.velocities.iter().copied().zip(qdot.iter().copied()).collect();
    let u_ni = applied_forces(mech, &w, &to_u, &mech.potential_gradient);
    // M_NI and K_NI - A_NI from the coordinates' M and h; where the quasi-velocities are not
    // plain rates (a body's angular velocity), also from the bodies' velocities in u, which
    // cancels the rate transformation body by body; the smaller is kept (both are exact).
    let renamed = renamed_force(mech, &w, &x, &to_u);
    let (mass_ni, inertia_ni, by_bodies) = if renamed.is_some() {
        (mass_by_coordinates(mech, &w), Vec::new(), false)
    } else if rates_only || m > MAX_COMPARED_ROUTE_COORDINATES {
        let (mass, inertia) = inertia_by_coordinates(mech, &w, &drift, &to_u);
        (mass, inertia, false)
    } else if m <= MAX_BODY_ROUTE_COORDINATES {
        let (mass, inertia) = inertia_by_bodies(model, mech, &u, &qdot, &chain);
        (mass, inertia, true)
    } else {
        let bodies = inertia_by_bodies(model, mech, &u, &qdot, &chain);
        let coordinates = inertia_by_coordinates(mech, &w, &drift, &to_u);
        let size =
            |(mass, inertia): &(Matrix, Vec<Expr>)| crate::symbolic::expr::post_order(&mass.data.iter().chain(inertia).copied().collect::<Vec<_>>()).len();
        if size(&bodies) <= size(&coordinates) { (bodies.0, bodies.1, true) } else { (coordinates.0, coordinates.1, false) }
    };
    let route = match (by_rows, by_bodies) {
        (false, true) => "symbolic elimination of [Y; M'; a]; M_NI and L_NI from the bodies' velocities in u",
        (false, false) => "symbolic elimination of [Y; M'; a]; M_NI = W^T M W, L_NI = W^T (Q - dV/dq - h - M c)",
        (true, true) => {
            "[Y; M'; a] with orthogonal rows, inverted as its transpose over the rows' squared norms; M_NI and L_NI from the bodies' velocities in u"
        }
        (true, false) => {
            "[Y; M'; a] with orthogonal rows, inverted as its transpose over the rows' squared norms; M_NI = W^T M W, L_NI = W^T (Q - dV/dq - h - M c)"
        }
    };
    // Where the quasi-velocities are not rates and the inertia forces came from the coordinates,
    // they are a combination (`inertia_by_coordinates`): so is their sum with U_NI. Where they
    // only rename the rates, L_NI is Lagrange's f renamed (`renamed_force`).
    let l_ni: Vec<Expr> = match renamed {
        Some(f) => f.into_iter().map(|e| settle_absent(e, &g)).collect(),
        None => (0..n_u)
            .map(|k| {
                let l = u_ni[k] + inertia_ni[k];
                settle_absent(if rates_only || by_bodies { tidy.of(l) } else { tidy.combination(l, m) }, &g)
            })
            .collect(),
    };
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
        u_ni,
        l_ni,
        route,
    })
}

/// `W^T (Q - dV/dq)` with the rates `q'` replaced by `to_u` (Eq. 33's `U_NI`), `dV/dq` given:
/// the whole potential's, or all but gravity's where a recursion takes gravity as the world's
/// acceleration (`composite::tree`).
pub(super) fn applied_forces(mech: &Mechanics, w: &Matrix, to_u: &HashMap<Symbol, Expr>, potential_gradient: &[Expr]) -> Vec<Expr> {
    let applied: Vec<Expr> = (0..mech.m).map(|j| mech.q_forces[j] - potential_gradient[j]).collect();
    w.transpose().mul(&Matrix::column(Expr::subs_all(&applied, to_u))).col(0).into_iter().map(|e| mech.tidy.of(e)).collect()
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
        // cheaper here (the momentum rows of W are simplest in world components).
        let both = Expr::subs_all(&[bv.v_both.0, bv.v_both.1].concat(), &to_u);
        let om = Expr::subs_all(&bv.omega, &to_u).into_iter().map(|e| tidy.rational(e)).collect::<Vec<_>>();
        let om = [om[0], om[1], om[2]];
        let (v_body, v_world) = ([both[0], both[1], both[2]], [both[3], both[4], both[5]]);
        let translation = if bv.in_body {
            Translation::in_body(tidy, &v_body, &v_world, &om, u, chain)
        } else {
            Translation::cheaper(tidy, &v_body, &v_world, &om, u, chain)
        };
        let (p, accel) = (translation.partials, translation.accel);
        let partial = |x: &[Expr; 3], k: usize| x.map(|e| tidy.rational(e.diff(u[k])));
        let o: Vec<[Expr; 3]> = (0..n_u).map(|k| partial(&om, k)).collect();
        let torque = body.inertia.as_ref().map(|inertia| {
            let alpha = chain.dt3(&om);
            tidy.of3(add3(&mat_vec(inertia, &alpha), &cross(&om, &mat_vec(inertia, &om))))
        });
        let io: Vec<Option<[Expr; 3]>> = o.iter().map(|ok| body.inertia.as_ref().map(|i| mat_vec(i, ok))).collect();
        for k in 0..n_u {
            for l in k..n_u {
                let mut e = dot(&p[k], &p[l]) * body.mass;
                if let Some(iol) = &io[l] {
                    e += dot(&o[k], iol);
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
/// True when `q' = W u + X` only renames each rate to one quasi-velocity: `W` a permutation
/// matrix and `X = 0` (Kane's default on chains, `u` the rates in another order).
fn renames_rates(w: &Matrix, x: &[Expr]) -> bool {
    // Exactly one nonzero entry, and that one is 1.
    let single_unit = |entries: &mut dyn Iterator<Item = Expr>| {
        let mut nonzero = entries.filter(|e| !e.is_zero());
        nonzero.next().is_some_and(|e| e.as_num().is_some_and(|v| v.is_one())) && nonzero.next().is_none()
    };
    x.iter().all(|e| e.is_zero())
        && (0..w.rows).all(|i| single_unit(&mut (0..w.cols).map(|k| w.get(i, k))))
        && (0..w.cols).all(|k| single_unit(&mut (0..w.rows).map(|i| w.get(i, k))))
}

/// `L_NI` where `q' = W u` only renames the rates ([`renames_rates`]): then `c = 0`, and
/// `W^T (Q - dV/dq - h)` in the quasi-velocities is Lagrange's `f` ([`Mechanics::lagrange_force`])
/// with each rate renamed, each entry simplified once in the rates (the node Lagrange's form
/// takes too, one memo entry) rather than again under the new names, where the inertia forces
/// over the term limit were tried anew (the 60-link pendulum's Kane stage). `None` elsewhere.
fn renamed_force(mech: &Mechanics, w: &Matrix, x: &[Expr], to_u: &HashMap<Symbol, Expr>) -> Option<Vec<Expr>> {
    if !renames_rates(w, x) {
        return None;
    }
    let f = Expr::subs_all(&mech.lagrange_force(), to_u);
    Some((0..w.cols).map(|k| (0..w.rows).find(|&i| !w.get(i, k).is_zero()).map(|i| f[i]).expect("a permutation")).collect())
}

/// `M_NI = W^T M W`, each entry a combination of simplified entries of `M`
/// ([`super::mechanics::Tidy::combination`]).
fn mass_by_coordinates(mech: &Mechanics, w: &Matrix) -> Matrix {
    w.transpose().mul(&mech.mass.mul(w)).map(|e| mech.tidy.combination(*e, mech.m))
}

fn inertia_by_coordinates(mech: &Mechanics, w: &Matrix, drift: &[Expr], to_u: &HashMap<Symbol, Expr>) -> (Matrix, Vec<Expr>) {
    let tidy = &mech.tidy;
    // Where `W` is not numeric (a base's angular velocity), an entry combines simplified
    // entries of M and h with W's sines and cosines ([`Tidy::combination`]: simplifying them
    // found nothing on the spatial chains, where the recursions give the right-hand sides, and
    // spent 1.1 of the 8-link chain's 4 million term products).
    let simplify = |e: Expr| tidy.combination(e, mech.m);
    let wt = w.transpose();
    let mass = mass_by_coordinates(mech, w);
    let inertial = Expr::subs_all(&mech.inertial(), to_u);
    let mc = mech.mass.mul(&Matrix::column(drift.to_vec()));
    let rest: Vec<Expr> = (0..mech.m).map(|j| -(inertial[j] + mc.get(j, 0))).collect();
    (mass, wt.mul(&Matrix::column(rest)).col(0).into_iter().map(simplify).collect())
}

#[cfg(test)]
mod tests {
    use super::renames_rates;
    use crate::symbolic::{Expr, Matrix, Symbol};

    fn matrix(rows: &[&[i64]]) -> Matrix {
        Matrix::from_rows(rows.iter().map(|r| r.iter().map(|&v| Expr::int(v)).collect()).collect())
    }

    #[test]
    fn a_permutation_without_drift_renames_the_rates() {
        let zero = [Expr::zero(), Expr::zero()];
        assert!(renames_rates(&matrix(&[&[0, 1], &[1, 0]]), &zero));
        assert!(renames_rates(&matrix(&[&[1, 0], &[0, 1]]), &zero));
    }

    #[test]
    fn scaled_mixed_or_drifting_rates_are_not_a_renaming() {
        let zero = [Expr::zero(), Expr::zero()];
        // A rate scaled, two rates in one quasi-velocity, a rate in none.
        assert!(!renames_rates(&matrix(&[&[0, 2], &[1, 0]]), &zero));
        assert!(!renames_rates(&matrix(&[&[1, 1], &[0, 1]]), &zero));
        assert!(!renames_rates(&matrix(&[&[1, 0], &[1, 0]]), &zero));
        // A symbolic entry, and a drift X.
        let c = Symbol::new("c_renames").expr();
        assert!(!renames_rates(&Matrix::from_rows(vec![vec![c, Expr::zero()], vec![Expr::zero(), Expr::one()]]), &zero));
        assert!(!renames_rates(&matrix(&[&[0, 1], &[1, 0]]), &[Expr::zero(), c]));
    }
}
