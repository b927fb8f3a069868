//! Kane's accelerations of a tree of frames by the articulated-body algorithm (Featherstone,
//! *Rigid Body Dynamics Algorithms*, 7.3): `u'` directly, in `O(n)` operations on a chain of `n`
//! links, with no mass matrix and no dense solve.
//!
//! The composite-body recursion ([`super::composite`]) still forms the `n x n` matrix that a
//! dense `L D L^T` then factors (`n^3 / 3` operations); here each joint's axes are eliminated
//! where they hang, from the leaves in:
//!
//! - the joints' own rates `w = J u`: each frame's relative velocity `v_rel = S u + s` has
//!   columns that are numeric multiples of a few axes `S'` (one for a hinge written in
//!   relative angles `q(i+1) - q(i)` of absolute coordinates, whose two columns are `+-` the
//!   same axis), so `v_rel = S' w + s` with `J` a numeric matrix, triangular in some order of
//!   the joints (else: no recursion);
//! - the applied forces `tau = J^-T U_K` by substitution;
//! - forward: velocities `v_k = X v_parent + v_rel` and bias accelerations
//!   `c_k = v_k x v_rel + d/dt v_rel` at `u' = 0`;
//! - backward: articulated inertias and bias forces
//!   `I^A_k = I_k + sum_children X^T (I^A - U D^-1 U^T) X`,
//!   `p^A_k = v_k x* I_k v_k + sum_children X^T (p^A + I^a c + U D^-1 (tau - S'^T p^A))`
//!   with `U = I^A S'` and `D = S'^T U`;
//! - forward: `a' = X a_parent + c`, `w' = D^-1 (tau - S'^T p^A - U^T a')`, `a = a' + S' w'`;
//! - `u' = J^-1 w'` by substitution.
//!
//! The pivots `D` (each joint's articulated inertia along its axes; an `L D L^T` of `D` for a
//! joint of several axes) vanish exactly where the mass matrix is singular: they are the checks
//! a right-hand side makes before it divides. Joints of several axes are taken on the world
//! alone (a floating base).

use super::composite::Tree;
use super::mechanics::Mechanics;
use super::spatial::{Force, Motion, Program, SpatialInertia, zero3};
use super::volterra::Volterra;
use crate::model::Model;
use crate::symbolic::transfer::{Transfer, Visitor};
use crate::symbolic::{Expr, Symbol};

/// Kane's accelerations as a program: `definitions` evaluated in order, then `accelerations`
/// (`u'`, in Kane's order of the quasi-velocities) in terms of them, the state, the parameters
/// and `t`.
#[derive(Clone, Debug)]
pub struct Articulated {
    /// Intermediate values, each defined from the inputs and earlier ones.
    pub definitions: Vec<(Symbol, Expr)>,
    /// `u'`.
    pub accelerations: Vec<Expr>,
    /// The joints' pivots `D`, each to be checked nonzero before the accelerations are read.
    pub pivots: Vec<Expr>,
    /// Every coordinate's rate `q' = W u + X`.
    pub qdot: Vec<Expr>,
}

impl Transfer for Articulated {
    fn visit(&mut self, v: &mut dyn Visitor) {
        self.definitions.visit(v);
        self.accelerations.visit(v);
        self.pivots.visit(v);
        self.qdot.visit(v);
    }
}

/// One axis of a joint: its motion `S'` and its rate `w = sum_c J[c] u_c` (numeric `J[c]`).
struct Axis {
    node: usize,
    motion: Motion,
    row: Vec<(usize, Expr)>,
}

/// The joints' axes: each column of a joint's `S` a numeric multiple of one of its axes found
/// before it, or a new axis.
fn axes(t: &Tree, mech: &Mechanics) -> Vec<Axis> {
    let mut out: Vec<Axis> = Vec::new();
    for (node, rates) in t.rates.iter().enumerate() {
        let Some(rates) = rates else { continue };
        let first = out.len();
        for (c, s) in &rates.columns {
            match out[first..].iter_mut().find_map(|axis| multiple(&axis.motion, s, mech).map(|k| (axis, k))) {
                Some((axis, k)) => axis.row.push((*c, k)),
                None => out.push(Axis { node, motion: *s, row: vec![(*c, Expr::one())] }),
            }
        }
    }
    out
}

/// `k` with `s = k axis`, where `k` is a number.
fn multiple(axis: &Motion, s: &Motion, mech: &Mechanics) -> Option<Expr> {
    let (a, b) = (components(axis), components(s));
    let i = a.iter().position(|e| !e.is_zero())?;
    let k = mech.tidy.of(b[i] / a[i]);
    (k.as_num().is_some() && a.iter().zip(&b).all(|(x, y)| mech.tidy.of(*y - k * *x).is_zero())).then_some(k)
}

fn components(m: &Motion) -> [Expr; 6] {
    [m.w[0], m.w[1], m.w[2], m.v[0], m.v[1], m.v[2]]
}

/// An order of the axes in which `J` is lower triangular: each axis's row holds one column
/// not held by the rows before it (its pivot, returned beside it). `None` where there is none.
fn triangular(axes: &[Axis], p: usize) -> Option<Vec<(usize, usize)>> {
    let mut solved = vec![false; p];
    let mut placed = vec![false; axes.len()];
    let mut order = Vec::with_capacity(axes.len());
    while order.len() < axes.len() {
        let next = (0..axes.len()).find_map(|d| {
            if placed[d] {
                return None;
            }
            let mut open = axes[d].row.iter().filter(|(c, _)| !solved[*c]);
            match (open.next(), open.next()) {
                (Some((c, _)), None) => Some((d, *c)),
                _ => None,
            }
        })?;
        placed[next.0] = true;
        solved[next.1] = true;
        order.push(next);
    }
    Some(order)
}

/// The coefficient of column `c` in `row`.
fn coefficient(row: &[(usize, Expr)], c: usize) -> Option<Expr> {
    row.iter().find(|(k, _)| *k == c).map(|(_, e)| *e)
}

/// `x = D^-1 b` for the symmetric `D` of a joint of several axes, by an unrolled `L D L^T`
/// whose pivots are pushed to `pivots`.
fn solve_small(prog: &mut Program, d: &[Vec<Expr>], b: &[Expr], pivots: &mut Vec<Expr>) -> Vec<Expr> {
    let r = b.len();
    let mut l = vec![vec![Expr::zero(); r]; r];
    let mut diag = vec![Expr::zero(); r];
    let mut inv = vec![Expr::zero(); r];
    for j in 0..r {
        let dj = prog.bind(d[j][j] - Expr::sum((0..j).map(|k| l[j][k] * l[j][k] * diag[k])));
        pivots.push(dj);
        diag[j] = dj;
        inv[j] = prog.bind(dj.recip());
        for i in j + 1..r {
            l[i][j] = prog.bind((d[i][j] - Expr::sum((0..j).map(|k| l[i][k] * l[j][k] * diag[k]))) * inv[j]);
        }
    }
    let mut y = vec![Expr::zero(); r];
    for i in 0..r {
        y[i] = prog.bind(b[i] - Expr::sum((0..i).map(|k| l[i][k] * y[k])));
    }
    let mut x = vec![Expr::zero(); r];
    for i in (0..r).rev() {
        x[i] = prog.bind(y[i] * inv[i] - Expr::sum((i + 1..r).map(|k| l[k][i] * x[k])));
    }
    x
}

/// Kane's accelerations of `model` by the articulated-body algorithm, from its Kane form
/// `kane` (for `q' = W u + X` and the applied forces `U_K`). `None` where the tree's joints do
/// not split the quasi-velocities into one rate per axis by a triangular `J`, or a joint of
/// several axes hangs below another frame.
#[cfg(test)]
pub fn derive(model: &Model, mech: &Mechanics, kane: &Volterra) -> Option<Articulated> {
    on_tree(&super::composite::tree(model, mech, kane)?, mech, kane)
}

/// [`derive`] on the tree `t` of Kane's form `kane`.
pub(super) fn on_tree(t: &Tree, mech: &Mechanics, kane: &Volterra) -> Option<Articulated> {
    let p = kane.u.len();
    let axes = axes(t, mech);
    if axes.len() != p {
        return None;
    }
    let order = triangular(&axes, p)?;
    let nodes = t.joints.len();
    let mut by_node: Vec<Vec<usize>> = vec![Vec::new(); nodes];
    for (d, axis) in axes.iter().enumerate() {
        by_node[axis.node].push(d);
    }
    if (1..nodes).any(|k| by_node[k].len() > 1 && t.joints[k].as_ref().is_some_and(|j| j.parent != 0)) {
        return None;
    }
    let mut prog = Program { definitions: Vec::new(), prefix: "aba" };
    // tau = J^-T U_K: J^T is upper triangular in the order, so from the last axis back.
    let mut tau = vec![Expr::zero(); p];
    for (at, &(d, c)) in order.iter().enumerate().rev() {
        let later = order[at + 1..].iter().filter_map(|&(e, _)| coefficient(&axes[e].row, c).map(|k| k * tau[e]));
        let pivot = coefficient(&axes[d].row, c).expect("the pivot is in its row");
        tau[d] = prog.bind((t.applied[c] - Expr::sum(later)) / pivot);
    }
    // Forward: velocities and bias accelerations.
    let still = Motion { w: zero3(), v: zero3() };
    let mut velocity = vec![still; nodes];
    let mut bias = vec![still; nodes];
    for k in 1..nodes {
        let (Some(joint), Some(r)) = (t.joints[k].as_ref(), t.rates[k].as_ref()) else { continue };
        let vp = velocity[joint.parent];
        let v = prog.motion(vp.in_child(joint).add(&r.relative));
        bias[k] = prog.motion(r.transport(&vp, &v).add(&r.drift));
        velocity[k] = v;
    }
    // Backward: articulated inertias and bias forces.
    let mut inertia: Vec<SpatialInertia> = t.own.iter().map(SpatialInertia::rigid).collect();
    let mut force: Vec<Force> =
        (0..nodes).map(|k| if t.own[k].is_zero() { Force::zero() } else { velocity[k].cross_force(&t.own[k].apply(&velocity[k])) }).collect();
    let mut pivots = Vec::new();
    // Per axis: U = I^A S', and D^-1 with its joint's other entries (one axis: 1 / D).
    let mut u_of = vec![Force::zero(); p];
    let mut reciprocal = vec![Expr::zero(); p];
    let mut free = vec![Expr::zero(); p];
    let mut joint_d: Vec<Vec<Vec<Expr>>> = vec![Vec::new(); nodes];
    for k in (1..nodes).rev() {
        let (Some(joint), Some(_)) = (t.joints[k].as_ref(), t.rates[k].as_ref()) else { continue };
        let ia = prog.spatial_inertia(inertia[k].clone());
        let pa = prog.force(force[k]);
        for &d in &by_node[k] {
            u_of[d] = prog.force(ia.apply(&axes[d].motion));
            free[d] = prog.bind(tau[d] - axes[d].motion.power(&pa));
        }
        let dm: Vec<Vec<Expr>> = by_node[k].iter().map(|&i| by_node[k].iter().map(|&j| prog.bind(axes[i].motion.power(&u_of[j]))).collect()).collect();
        if let [d] = by_node[k][..] {
            pivots.push(dm[0][0]);
            reciprocal[d] = prog.bind(dm[0][0].recip());
        }
        joint_d[k] = dm;
        if joint.parent == 0 {
            continue;
        }
        let (ia_passed, pa_passed) = match by_node[k][..] {
            [] => (ia.clone(), pa.add(&ia.apply(&bias[k]))),
            [d] => {
                let passed = ia.minus_outer(&u_of[d], reciprocal[d]);
                let pa = pa.add(&passed.apply(&bias[k])).add(&u_of[d].scale(reciprocal[d] * free[d]));
                (passed, pa)
            }
            _ => unreachable!("joints of several axes hang from the world"),
        };
        inertia[joint.parent] = inertia[joint.parent].add(&ia_passed.to_parent(joint));
        force[joint.parent] = force[joint.parent].add(&pa_passed.in_parent(joint));
    }
    // Forward: accelerations, from the world's (`-g`: gravity).
    let mut accel = vec![still; nodes];
    accel[0] = t.world;
    let mut w_dot = vec![Expr::zero(); p];
    for k in 1..nodes {
        let (Some(joint), Some(_)) = (t.joints[k].as_ref(), t.rates[k].as_ref()) else { continue };
        let a_prime = accel[joint.parent].in_child(joint).add(&bias[k]);
        let axes_k = &by_node[k];
        let rhs: Vec<Expr> = axes_k.iter().map(|&d| free[d] - a_prime.power(&u_of[d])).collect();
        let solved = match axes_k[..] {
            [] => Vec::new(),
            [d] => vec![prog.bind(reciprocal[d] * rhs[0])],
            _ => solve_small(&mut prog, &joint_d[k], &rhs, &mut pivots),
        };
        let mut a = a_prime;
        for (&d, w) in axes_k.iter().zip(&solved) {
            w_dot[d] = *w;
            a = a.add(&axes[d].motion.scale(*w));
        }
        accel[k] = if axes_k.is_empty() { a } else { prog.motion(a) };
    }
    // u' = J^-1 w': J is lower triangular in the order.
    let mut u_dot = vec![Expr::zero(); p];
    for &(d, c) in &order {
        let known = axes[d].row.iter().filter(|(k, _)| *k != c).map(|(k, e)| *e * u_dot[*k]);
        let pivot = coefficient(&axes[d].row, c).expect("the pivot is in its row");
        u_dot[c] = prog.bind((w_dot[d] - Expr::sum(known)) / pivot);
    }
    Some(Articulated { definitions: prog.definitions, accelerations: u_dot, pivots, qdot: kane.qdot.clone() })
}

/// The reduced Volterra equations' rates `u_N'` of `model` by the articulated-body recursion,
/// from Kane's (`kane_aba`, of the Kane form `kane`) and the reduced form `reduced`: the
/// ignorable rates from the momenta first, `u_I = M_II^-1 (G_I - G_I|u_I=0)`, where
/// `G_I|u_I=0 = S_I^T h` is the momentum of the subtree the ignorable axes move (`h` summed from
/// the leaves at `u_I = 0`) and `M_II` the dense form's (small and simplified: the total mass on
/// a floating base), then Kane's recursion at that `u`. `None` unless each ignorable rate is
/// the rate of one axis of a joint on the world, alone in its row of `J`.
#[cfg(test)]
pub fn reduce(model: &Model, mech: &Mechanics, kane: &Volterra, kane_aba: &Articulated, reduced: &Volterra) -> Option<Articulated> {
    reduce_on(&super::composite::tree(model, mech, kane)?, model, mech, kane, kane_aba, reduced)
}

/// [`reduce`] on the tree `t` of Kane's form `kane`.
pub(super) fn reduce_on(t: &Tree, model: &Model, mech: &Mechanics, kane: &Volterra, kane_aba: &Articulated, reduced: &Volterra) -> Option<Articulated> {
    use crate::symbolic::matrix::solve;
    use std::collections::{HashMap, HashSet};
    let super::volterra::SchurMap { map, rates, .. } = super::volterra::schur_map(model, mech, &reduced.ignorable, &model.quasi_reduced, kane)?;
    let axes = axes(t, mech);
    // Each ignorable rate: its axis, the coefficient of the rate in its row.
    let mut ignorable_axes = Vec::with_capacity(rates.len());
    for &c in &rates {
        let mut holding = axes.iter().filter(|a| a.row.iter().any(|(k, _)| *k == c));
        let (Some(axis), None) = (holding.next(), holding.next()) else { return None };
        let on_world = t.joints[axis.node].as_ref().is_some_and(|j| j.parent == 0);
        let [(_, k)] = axis.row[..] else { return None };
        if !on_world {
            return None;
        }
        ignorable_axes.push((axis, k));
    }
    let (s, n_u) = (rates.len(), map.len());
    let mut prog = Program { definitions: Vec::new(), prefix: "abr" };
    // The momentum at u_I = 0: velocities from the leaves' parents out, momenta back in.
    let mut at_rest: HashMap<Symbol, Expr> = map.iter().zip(&reduced.u).map(|(&r, u)| (kane.u[r], u.expr())).collect();
    for &r in &rates {
        at_rest.insert(kane.u[r], Expr::zero());
    }
    let nodes = t.joints.len();
    let still = Motion { w: zero3(), v: zero3() };
    let mut velocity = vec![still; nodes];
    for k in 1..nodes {
        let (Some(joint), Some(r)) = (t.joints[k].as_ref(), t.rates[k].as_ref()) else { continue };
        let relative = Motion { w: r.relative.w.map(|e| e.subs(&at_rest)), v: r.relative.v.map(|e| e.subs(&at_rest)) };
        velocity[k] = prog.motion(velocity[joint.parent].in_child(joint).add(&relative));
    }
    let mut momentum: Vec<Force> = (0..nodes).map(|k| if t.own[k].is_zero() { Force::zero() } else { t.own[k].apply(&velocity[k]) }).collect();
    for k in (1..nodes).rev() {
        let (Some(joint), Some(_)) = (t.joints[k].as_ref(), t.rates[k].as_ref()) else { continue };
        momentum[k] = prog.force(momentum[k]);
        if joint.parent != 0 {
            momentum[joint.parent] = momentum[joint.parent].add(&momentum[k].in_parent(joint));
        }
    }
    // u_I = M_II^-1 (G - G|u_I=0).
    let mut m_ii = crate::symbolic::Matrix::zeros(s, s);
    let mut rhs = crate::symbolic::Matrix::zeros(s, 1);
    for (a, &ra) in rates.iter().enumerate() {
        for (b, &rb) in rates.iter().enumerate() {
            m_ii.set(a, b, kane.mass_ni.get(ra, rb));
        }
        let (axis, k) = &ignorable_axes[a];
        rhs.set(a, 0, reduced.g[a].expr() - *k * axis.motion.power(&momentum[axis.node]));
    }
    let opts = super::volterra::momenta_solve_options(model);
    let u_i = solve(&m_ii, &rhs, &opts).ok()?;
    let mut sigma: HashMap<Symbol, Expr> = map.iter().zip(&reduced.u).map(|(&r, u)| (kane.u[r], u.expr())).collect();
    for (b, &r) in rates.iter().enumerate() {
        let v = prog.bind(u_i.x.get(b, 0));
        sigma.insert(kane.u[r], v);
    }
    // Kane's recursion at that u: the definitions that read a quasi-velocity, renamed.
    let speeds: HashSet<Symbol> = kane.u.iter().copied().collect();
    let mut moving: HashSet<Symbol> = HashSet::new();
    for (sym, e) in &kane_aba.definitions {
        if e.free_symbols().iter().any(|x| speeds.contains(x) || moving.contains(x)) {
            moving.insert(*sym);
            let v = prog.bind(e.subs(&sigma));
            sigma.insert(*sym, v);
        } else {
            prog.definitions.push((*sym, *e));
        }
    }
    let accelerations = (0..n_u).map(|k| kane_aba.accelerations[map[k]].subs(&sigma)).collect();
    let pivots = Expr::subs_all(&kane_aba.pivots, &sigma);
    let qdot = Expr::subs_all(&kane_aba.qdot, &sigma);
    Some(Articulated { definitions: prog.definitions, accelerations, pivots, qdot })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formulation::test_states::random_state;
    use crate::formulation::{mechanics, volterra};

    /// `x` with `a x = b` by the evaluator's LU with partial pivoting (a test's reference).
    fn solve(a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
        let n = b.len();
        let mut flat: Vec<f64> = a.into_iter().flatten().collect();
        crate::eval::model::solve_dense(n, &mut flat, &mut b, &mut Vec::new()).unwrap();
        b
    }

    /// The articulated-body accelerations solve Kane's dense `M_K u' = L_K` at random states,
    /// and the pivots' product is `det M_K / det J^2` up to sign (none vanish at random).
    fn agrees(model: &Model) -> usize {
        let mech = mechanics::derive(model);
        let kane = volterra::derive(model, &mech, &[], &model.quasi_full).unwrap();
        let aba = derive(model, &mech, &kane).unwrap_or_else(|| panic!("{}: no articulated-body form", model.name));
        let p = kane.u.len();
        let mut seed = 3u64;
        for _ in 0..3 {
            let mut env = random_state(model, &kane.u, &mut seed);
            let m: Vec<Vec<f64>> = (0..p).map(|i| (0..p).map(|j| kane.mass_ni.get(i, j).eval(&env).unwrap()).collect()).collect();
            let l: Vec<f64> = kane.l_ni.iter().map(|e| e.eval(&env).unwrap()).collect();
            let want = solve(m, l);
            for (s, e) in &aba.definitions {
                let v = e.eval(&env).unwrap();
                env.set(*s, v);
            }
            for (i, w) in want.iter().enumerate() {
                let got = aba.accelerations[i].eval(&env).unwrap();
                assert!((got - w).abs() <= 1e-9 * (1.0 + w.abs()), "{}: u'[{i}] {got} against {w}", model.name);
            }
            for d in &aba.pivots {
                assert!(d.eval(&env).unwrap() > 0.0, "{}: a pivot not positive", model.name);
            }
        }
        aba.pivots.len()
    }

    /// The reduced recursion's `u_N'` solve the dense reduced `M_NI u_N' = L_NI` at random
    /// states and momenta.
    fn reduced_agrees(model: &Model) {
        let mech = mechanics::derive(model);
        let kane = volterra::derive(model, &mech, &[], &model.quasi_full).unwrap();
        let chosen = crate::formulation::ignorable::choose(model, &crate::formulation::ignorable::analyze(model, &mech)).unwrap();
        let reduced = volterra::derive_reduced(model, &mech, &chosen, &model.quasi_reduced, &kane).unwrap();
        let aba = derive(model, &mech, &kane).unwrap();
        let r = reduce(model, &mech, &kane, &aba, &reduced).unwrap_or_else(|| panic!("{}: no reduced recursion", model.name));
        let n = reduced.u.len();
        let mut seed = 5u64;
        for _ in 0..3 {
            let speeds: Vec<Symbol> = reduced.u.iter().chain(&reduced.g).copied().collect();
            let mut env = random_state(model, &speeds, &mut seed);
            let m: Vec<Vec<f64>> = (0..n).map(|i| (0..n).map(|j| reduced.mass_ni.get(i, j).eval(&env).unwrap()).collect()).collect();
            let l: Vec<f64> = reduced.l_ni.iter().map(|e| e.eval(&env).unwrap()).collect();
            let want = solve(m, l);
            for (s, e) in &r.definitions {
                let v = e.eval(&env).unwrap();
                env.set(*s, v);
            }
            for (i, w) in want.iter().enumerate() {
                let got = r.accelerations[i].eval(&env).unwrap();
                assert!((got - w).abs() <= 1e-9 * (1.0 + w.abs()), "{}: u_N'[{i}] {got} against {w}", model.name);
            }
            for (j, e) in reduced.qdot.iter().enumerate() {
                let (want, got) = (e.eval(&env).unwrap(), r.qdot[j].eval(&env).unwrap());
                assert!((got - want).abs() <= 1e-9 * (1.0 + want.abs()), "{}: q'[{j}] {got} against {want}", model.name);
            }
        }
    }

    #[test]
    fn the_reduced_articulated_body_rates_solve_the_reduced_equations() {
        reduced_agrees(&crate::model::load("../models/pendulum_on_cart_5.ron").unwrap());
        reduced_agrees(&crate::model::examples::floating_chain(3).build().unwrap());
        for name in ["satellite_boom", "three_body"] {
            reduced_agrees(&crate::model::load(format!("../models/{name}.ron")).unwrap());
        }
    }

    #[test]
    fn the_articulated_body_accelerations_solve_kanes_equations() {
        // The pendulum's hinges are written in relative angles of absolute coordinates: two
        // columns per hinge, one axis.
        assert_eq!(agrees(&crate::model::load("../models/pendulum_on_cart_5.ron").unwrap()), 6);
        assert_eq!(agrees(&crate::model::examples::n_link_pendulum_on_cart(3).build().unwrap()), 4);
        // A floating base (six axes on the world, one L D L^T) and hinges below it.
        assert_eq!(agrees(&crate::model::examples::floating_chain(3).build().unwrap()), 9);
        for name in ["three_body", "satellite_boom"] {
            let model = crate::model::load(format!("../models/{name}.ron")).unwrap();
            let p = volterra::derive(&model, &mechanics::derive(&model), &[], &model.quasi_full).unwrap().u.len();
            assert_eq!(agrees(&model), p, "{name}");
        }
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::formulation::{articulated, mechanics, volterra};
        let model = crate::model::load("../models/pendulum_on_cart_5.ron").unwrap();
        let mech = mechanics::derive(&model);
        let kane = volterra::derive(&model, &mech, &[], &model.quasi_full).unwrap();
        let aba = articulated::derive(&model, &mech, &kane).unwrap();
        assert_eq!((aba.accelerations.len(), aba.pivots.len()), (6, 6));
    }
}
