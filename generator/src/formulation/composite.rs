//! Kane's equations of a tree of frames by recursion over the tree, as straight-line
//! definitions instead of one symbolic expression per matrix entry.
//!
//! The dense form writes each entry of `M_K = sum_k Phi_k^T I_k Phi_k` (`Phi_k` the partial
//! spatial velocities of frame `k` by the quasi-velocities) as its own sum over the bodies beyond
//! both joints: `O(n^3)` operations on a chain of `n` links. Here the same matrix comes from
//! the composite-rigid-body algorithm (Featherstone, *Rigid Body Dynamics Algorithms*, 6.2) and
//! the inertia forces from the recursive Newton-Euler algorithm (5.3), generalized to any
//! quasi-velocities `u` with `q' = W u + X`:
//!
//! - each frame's velocity relative to its parent, in its own components, is
//!   `v_rel = S_k u + s_k` (`S_k` a 6 x p matrix with few nonzero columns on a tree of joints);
//! - forward: `V_k = X_k V_parent + v_rel`, `a_k = X_k a_parent + V_k x v_rel + d/dt v_rel` at
//!   `u' = 0` (spatial velocity and acceleration in own components);
//! - backward: the composite inertia `I^c_k = I_k + sum_children X^T I^c X` and the composite
//!   force `f^c_k = I_k a_k + V_k x* I_k V_k + sum_children X^T f^c`;
//! - `M_K = sum_a [S_a^T I^c_a S_a + sum_{b ancestor of a} (S_b^T X_{a->b}^* I^c_a S_a + transpose)]`
//!   and `L_K = U_K - sum_k S_k^T f^c_k` (`U_K = W^T (Q - dV/dq)` as the dense form has it).
//!
//! `O(n^2)` operations for the matrix of a chain and `O(n)` for the forcing. Each vector the
//! recursion forms becomes a named intermediate ([`Recursion::definitions`]): the symbolic core
//! flattens sums, and a flattened composite inertia would be the dense form again. Emission
//! keeps whichever assembly takes fewer operations ([`crate::emit`]).

use super::mechanics::Mechanics;
use super::spatial::{Force, Inertia, Motion, Program, zero3};
use super::volterra::Volterra;
use crate::kinematics::{Joint, TimeChain, cross, mat_vec};
use crate::model::Model;
use crate::symbolic::transfer::{Transfer, Visitor};
use crate::symbolic::{Expr, Matrix, Symbol};
use std::collections::HashMap;

/// The mass matrix and forcing of Kane's equations as a program: `definitions` evaluated in
/// order, then `mass` and `forcing` in terms of them, the state, the parameters and `t`.
#[derive(Clone, Debug)]
pub struct Recursion {
    /// Intermediate values, each defined from the inputs and earlier ones.
    pub definitions: Vec<(Symbol, Expr)>,
    /// `M_K` (symmetric), in the definitions.
    pub mass: Matrix,
    /// `L_K`, in the definitions.
    pub forcing: Vec<Expr>,
    /// Every coordinate's rate `q' = W u + X`, in the definitions (the reduced form's reads
    /// the ignorable rates the definitions solve for).
    pub qdot: Vec<Expr>,
}

impl Transfer for Recursion {
    fn visit(&mut self, v: &mut dyn Visitor) {
        self.definitions.visit(v);
        self.mass.visit(v);
        self.forcing.visit(v);
        self.qdot.visit(v);
    }
}

impl Recursion {
    /// `mass` and `forcing` with the definitions substituted back: the dense form's values.
    pub fn expanded(&self) -> (Matrix, Vec<Expr>) {
        let mut map: HashMap<Symbol, Expr> = HashMap::new();
        for (s, e) in &self.definitions {
            let value = e.subs(&map);
            map.insert(*s, value);
        }
        (self.mass.map(|e| e.subs(&map)), Expr::subs_all(&self.forcing, &map))
    }
}

/// One frame's joint in the quasi-velocities: `v_rel = S u + s` with its columns.
#[derive(Debug)]
pub(super) struct JointRates {
    /// `v_rel` in `(q, u, t)`.
    pub(super) relative: Motion,
    /// `(column, S[:, column])` for the columns not identically zero.
    pub(super) columns: Vec<(usize, Motion)>,
    /// `d/dt v_rel` at `u' = 0`.
    pub(super) drift: Motion,
}

impl JointRates {
    /// `V x v_rel` for the frame's velocity `v` below a parent moving with `parent` (its own
    /// components): the velocity product of the frame's acceleration. It is `(X V_parent) x
    /// v_rel` (a motion crossed with itself is zero), so zero below a still parent (a floating
    /// base on the world), where `v`'s names would hide the cancelling of `v_rel x v_rel` from
    /// the symbolic core and the emitted code would compute `u3 u2 - u3 u2`.
    pub(super) fn transport(&self, parent: &Motion, v: &Motion) -> Motion {
        if parent.is_zero() { Motion { w: zero3(), v: zero3() } } else { v.cross_motion(&self.relative) }
    }
}

/// A model's frames as a tree of rigid bodies in Kane's quasi-velocities, built once and shared
/// by the recursions ([`derive`], [`super::articulated`]).
#[derive(Debug)]
pub struct Tree {
    /// Each node's joint to its parent (`None` for the world); the model's frames first, then
    /// a node per body whose centre of mass moves in its frame.
    pub(super) joints: Vec<Option<Joint>>,
    /// The rigid-body inertia each node carries itself.
    pub(super) own: Vec<Inertia>,
    /// The joints' rates, for the nodes with mass in their subtree (`None` elsewhere).
    pub(super) rates: Vec<Option<JointRates>>,
    /// The world's acceleration, `-g` (Featherstone's way with gravity: each body's inertia
    /// force then carries its weight, at the cost of the accelerations the recursion forms
    /// anyway).
    pub(super) world: Motion,
    /// `U_K` without gravity: `W^T (Q - dV/dq)` of the other forces and potentials.
    pub(super) applied: Vec<Expr>,
}

/// The tree of `model`'s frames in the quasi-velocities of `kane`. `None` when no body hangs
/// below a frame below the world (every frame on the world: the dense form is the recursion
/// already).
pub(super) fn tree(model: &Model, mech: &Mechanics, kane: &Volterra) -> Option<Tree> {
    let tidy = &mech.tidy;
    let frames = &model.frames;
    let p = kane.u.len();
    let to_u: HashMap<Symbol, Expr> = model.velocities.iter().copied().zip(kane.qdot.iter().copied()).collect();
    let chain = TimeChain::new(model.t, model.coordinates.iter().copied().zip(kane.qdot.iter().copied()).collect());
    // The tree: the model's frames, then one node per body whose centre of mass moves in its
    // frame (a point on a boom), joined to the frame by that motion.
    let by_rates = TimeChain::new(model.t, model.coordinates.iter().zip(&model.velocities).map(|(q, v)| (*q, v.expr())).collect());
    let mut joints: Vec<Option<Joint>> = frames.iter().map(|f| f.joint.clone()).collect();
    let mut own: Vec<Inertia> = vec![Inertia::zero(); frames.len()];
    for b in &model.bodies {
        let moves = b.com.iter().any(|e| e.contains(model.t) || model.coordinates.iter().any(|q| e.contains(*q)));
        if moves {
            joints.push(Some(Joint { parent: b.frame, rotation: Matrix::identity(3), translation: b.com, omega: zero3(), velocity: by_rates.dt3(&b.com) }));
            own.push(Inertia::body(b.mass, &zero3(), b.inertia.as_ref()));
        } else {
            own[b.frame] = own[b.frame].add(&Inertia::body(b.mass, &b.com, b.inertia.as_ref()));
        }
    }
    let nodes = joints.len();
    // Nodes carrying mass in their subtree (the others need no recursion).
    let mut massive: Vec<bool> = own.iter().map(|i| !i.is_zero()).collect();
    for k in (1..nodes).rev() {
        if massive[k] {
            let parent = joints[k].as_ref()?.parent;
            massive[parent] = true;
        }
    }
    // Without a massive node below another frame the recursion is the dense sum itself
    // (`M_K = sum_k S_k^T I_k S_k`, every frame hung from the world): nothing to gain.
    if !(1..nodes).any(|k| massive[k] && joints[k].as_ref().is_some_and(|j| j.parent != 0)) {
        return None;
    }
    let rates: Vec<Option<JointRates>> = joints
        .iter()
        .enumerate()
        .map(|(k, joint)| {
            let joint = joint.as_ref()?;
            if !massive[k] {
                return None;
            }
            let in_u = |v: &[Expr; 3]| -> [Expr; 3] { v.map(|e| tidy.rational(e.subs(&to_u))) };
            let relative = Motion { w: in_u(&joint.omega), v: in_u(&joint.velocity) };
            let columns: Vec<(usize, Motion)> = (0..p)
                .filter_map(|c| {
                    let u = kane.u[c];
                    let d = |v: &[Expr; 3]| v.map(|e| tidy.rational(e.diff(u)));
                    let col = Motion { w: d(&relative.w), v: d(&relative.v) };
                    (!col.is_zero()).then_some((c, col))
                })
                .collect();
            let mut drift = Motion { w: relative.w.map(|e| tidy.of(chain.dt(e))), v: relative.v.map(|e| tidy.of(chain.dt(e))) };
            // `v_rel = R^T t'` moves with the joint's turning too: `d/dt v_rel = -omega_rel x
            // v_rel + R^T t''`. Differentiated as an expression, the turning's rate comes
            // through the attitude's own rates: on a floating base's quaternion, a term over
            // its norm for each entry of `R` (about 40 operations a component where the
            // identity takes 5); the smaller form is kept.
            if !relative.v.iter().all(|e| e.is_zero()) && !relative.w.iter().all(|e| e.is_zero()) {
                let t_rate = by_rates.dt3(&joint.translation).map(|e| e.subs(&to_u));
                let turned = mat_vec(&joint.rotation.transpose(), &t_rate.map(|e| chain.dt(e)));
                let spun = cross(&relative.w, &relative.v);
                let by_identity = [0, 1, 2].map(|i| tidy.of(turned[i] - spun[i]));
                if crate::symbolic::expr::dag_ops(&by_identity) < crate::symbolic::expr::dag_ops(&drift.v) {
                    drift.v = by_identity;
                }
            }
            Some(JointRates { relative, columns, drift })
        })
        .collect();
    let world = Motion { w: zero3(), v: mech.gravity.map(|g| -g) };
    let applied =
        if world.is_zero() { kane.u_ni.clone() } else { super::volterra::applied_forces(mech, &kane.w, &to_u, &mech.potential_gradient_without_gravity) };
    Some(Tree { joints, own, rates, world, applied })
}

/// Kane's equations of `model` by the recursion over its frames, from its Kane form `kane`
/// (for `q' = W u + X` and the applied forces `U_K`). `None` when no body hangs below a frame
/// below the world (every frame on the world: the dense form is the recursion already).
#[cfg(test)]
pub fn derive(model: &Model, mech: &Mechanics, kane: &Volterra) -> Option<Recursion> {
    on_tree(&tree(model, mech, kane)?, kane)
}

/// [`derive`] on the tree `t` of Kane's form `kane`.
pub(super) fn on_tree(t: &Tree, kane: &Volterra) -> Option<Recursion> {
    let (joints, own, rates) = (&t.joints, &t.own, &t.rates);
    let nodes = joints.len();
    let p = kane.u.len();
    let massive: Vec<bool> = rates.iter().map(Option::is_some).collect();
    let mut prog = Program { definitions: Vec::new(), prefix: "rec" };
    // Forward: velocities and accelerations at u' = 0.
    let still = Motion { w: zero3(), v: zero3() };
    let mut velocity = vec![still; nodes];
    let mut accel = vec![still; nodes];
    accel[0] = t.world;
    for k in 1..nodes {
        let (Some(joint), Some(r)) = (joints[k].as_ref(), rates[k].as_ref()) else { continue };
        let (vp, ap) = (velocity[joint.parent], accel[joint.parent]);
        let v = prog.motion(vp.in_child(joint).add(&r.relative));
        let a = ap.in_child(joint).add(&r.transport(&vp, &v)).add(&r.drift);
        velocity[k] = v;
        accel[k] = prog.motion(a);
    }
    // Backward: composite inertias and forces.
    let mut composite: Vec<Inertia> = own.clone();
    let mut forces: Vec<Force> = vec![Force::zero(); nodes];
    for k in 1..nodes {
        if !own[k].is_zero() {
            let i = &own[k];
            let v = velocity[k];
            forces[k] = i.apply(&accel[k]).add(&v.cross_force(&i.apply(&v)));
        }
    }
    for k in (1..nodes).rev() {
        let Some(joint) = joints[k].as_ref() else { continue };
        if !massive[k] {
            continue;
        }
        composite[k] = prog.inertia(composite[k].clone());
        forces[k] = prog.force(forces[k]);
        if joint.parent != 0 {
            composite[joint.parent] = composite[joint.parent].add(&composite[k].to_parent(joint));
            forces[joint.parent] = forces[joint.parent].add(&forces[k].in_parent(joint));
        }
    }
    // L_K = U_K - sum_k S_k^T f^c_k.
    let mut forcing: Vec<Vec<Expr>> = t.applied.iter().map(|e| vec![*e]).collect();
    // M_K from the composite inertias, walking each joint's columns up to the root.
    let mut mass: Vec<Vec<Vec<Expr>>> = vec![vec![Vec::new(); p]; p];
    for a in 1..nodes {
        let Some(r) = rates[a].as_ref() else { continue };
        for (c, s) in &r.columns {
            forcing[*c].push(-s.power(&forces[a]));
        }
        let mut carried: Vec<(usize, Force)> = r.columns.iter().map(|(c, s)| (*c, prog.force(composite[a].apply(s)))).collect();
        for (c, f) in &carried {
            for (d, s) in &r.columns {
                mass[*d][*c].push(s.power(f));
            }
        }
        let mut j = a;
        loop {
            let joint = joints[j].as_ref().expect("a frame below the world has a joint");
            let parent = joint.parent;
            if parent == 0 {
                break;
            }
            carried = carried.into_iter().map(|(c, f)| (c, if f.is_zero() { f } else { prog.force(f.in_parent(joint)) })).collect();
            if let Some(rp) = rates[parent].as_ref() {
                for (c, f) in &carried {
                    for (d, s) in &rp.columns {
                        let e = s.power(f);
                        mass[*d][*c].push(e);
                        mass[*c][*d].push(e);
                    }
                }
            }
            j = parent;
        }
    }
    let mut m = Matrix::zeros(p, p);
    for (d, row) in mass.into_iter().enumerate() {
        for (c, terms) in row.into_iter().enumerate() {
            m.set(d, c, Expr::sum(terms));
        }
    }
    Some(Recursion { definitions: prog.definitions, mass: m, forcing: forcing.into_iter().map(Expr::sum).collect(), qdot: kane.qdot.clone() })
}

/// The reduced Volterra equations of `model` from Kane's recursion `kane_rec`, as the Schur
/// complement ([`super::volterra::by_schur_complement`], the same algebra on the recursion's
/// values): `u_I` from the momenta `G_I`, then
/// `M_NI = M_NN - M_NI M_II^-1 M_IN`, `L_NI = L_N - M_NI M_II^-1 L_I`. `M_II` and the momenta's
/// offsets are the dense form's (small and simplified: the total mass on a floating base);
/// everything else is read from the recursion. `None` where the reduced form is not Kane's
/// Schur complement.
pub fn reduce(model: &Model, mech: &Mechanics, kane: &Volterra, kane_rec: &Recursion, reduced: &Volterra) -> Option<Recursion> {
    use crate::symbolic::matrix::solve;
    let super::volterra::SchurMap { map, rates, .. } = super::volterra::schur_map(model, mech, &reduced.ignorable, &model.quasi_reduced, kane)?;
    let (m, s, n_u) = (mech.m, rates.len(), map.len());
    let mut prog = Program { definitions: Vec::new(), prefix: "red" };
    // The definitions that read no quasi-velocity (the composite inertias and everything the
    // matrix is built from) stay as they are, first.
    let speeds: std::collections::HashSet<Symbol> = kane.u.iter().copied().collect();
    let mut moving: std::collections::HashSet<Symbol> = std::collections::HashSet::new();
    for (sym, e) in &kane_rec.definitions {
        if e.free_symbols().iter().any(|x| speeds.contains(x) || moving.contains(x)) {
            moving.insert(*sym);
        } else {
            prog.definitions.push((*sym, *e));
        }
    }
    let mk = kane_rec.mass.map(|e| prog.bind(*e));
    let dense = &kane.mass_ni;
    let mut m_ii = Matrix::zeros(s, s);
    for a in 0..s {
        for b in 0..s {
            m_ii.set(a, b, dense.get(rates[a], rates[b]));
        }
    }
    let opts = super::volterra::momenta_solve_options(model);
    // u_I = M_II^-1 (G - n - M_IN u_N), n the momenta at u = 0.
    let mut rhs = Matrix::zeros(s, 1);
    for (a, &j) in reduced.ignorable.iter().enumerate() {
        let n = mech.tidy.of(Expr::sum((0..m).map(|c| mech.mass.get(j, c) * kane.x[c])) + mech.n[j]);
        let coupled = Expr::sum(map.iter().zip(&reduced.u).map(|(&r, u)| mk.get(rates[a], r) * u.expr()));
        rhs.set(a, 0, reduced.g[a].expr() - n - coupled);
    }
    let v_i = solve(&m_ii, &rhs, &opts).ok()?;
    let mut sigma: HashMap<Symbol, Expr> = HashMap::new();
    for (k, &r) in map.iter().enumerate() {
        sigma.insert(kane.u[r], reduced.u[k].expr());
    }
    for (b, &r) in rates.iter().enumerate() {
        let v = prog.bind(v_i.x.get(b, 0));
        sigma.insert(kane.u[r], v);
    }
    // The definitions that read the quasi-velocities, renamed, in the reduced ones.
    for (sym, e) in &kane_rec.definitions {
        if moving.contains(sym) {
            let v = prog.bind(e.subs(&sigma));
            sigma.insert(*sym, v);
        }
    }
    let l_k: Vec<Expr> = kane_rec.forcing.iter().map(|e| e.subs(&sigma)).collect();
    let qdot = Expr::subs_all(&kane_rec.qdot, &sigma);
    // M_II Z = [M_IN | L_I].
    let mut right = Matrix::zeros(s, n_u + 1);
    for (a, &ra) in rates.iter().enumerate() {
        for (k, &rk) in map.iter().enumerate() {
            right.set(a, k, mk.get(ra, rk));
        }
        right.set(a, n_u, prog.bind(l_k[ra]));
    }
    let zs = solve(&m_ii, &right, &opts).ok()?;
    let zs = zs.x.map(|e| prog.bind(*e));
    let coupling = |k: usize, col: usize| Expr::sum((0..s).map(|a| mk.get(map[k], rates[a]) * zs.get(a, col)));
    let mut mass = Matrix::zeros(n_u, n_u);
    for k in 0..n_u {
        for l in k..n_u {
            let e = mk.get(map[k], map[l]) - coupling(k, l);
            mass.set(k, l, e);
            mass.set(l, k, e);
        }
    }
    let forcing = (0..n_u).map(|k| l_k[map[k]] - coupling(k, n_u)).collect();
    Some(Recursion { definitions: prog.definitions, mass, forcing, qdot })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formulation::mechanics;
    use crate::formulation::test_states::random_state;
    use crate::formulation::volterra;

    /// The recursion gives the dense form's `M_K` and `L_K` at random states of every model
    /// with frames (values of the coordinates, quasi-velocities, parameters and `t`).
    fn agrees(path: &str) {
        let model = crate::model::load(path).unwrap();
        let mech = mechanics::derive(&model);
        let kane = volterra::derive(&model, &mech, &[], &model.quasi_full).unwrap();
        let r = derive(&model, &mech, &kane).expect("a tree of frames with bodies");
        let mut seed = 7u64;
        for _ in 0..3 {
            let mut env = random_state(&model, &kane.u, &mut seed);
            for (s, e) in &r.definitions {
                let v = e.eval(&env).unwrap();
                env.set(*s, v);
            }
            let p = kane.u.len();
            for i in 0..p {
                let want = kane.l_ni[i].eval(&env).unwrap();
                let got = r.forcing[i].eval(&env).unwrap();
                assert!((want - got).abs() <= 1e-10 * (1.0 + want.abs()), "{path}: L[{i}] {got} against {want}");
                for j in 0..p {
                    let want = kane.mass_ni.get(i, j).eval(&env).unwrap();
                    let got = r.mass.get(i, j).eval(&env).unwrap();
                    assert!((want - got).abs() <= 1e-10 * (1.0 + want.abs()), "{path}: M[{i}][{j}] {got} against {want}");
                }
            }
        }
    }

    /// The reduced recursion gives the dense reduced form's `M_NI`, `L_NI` at random states
    /// and momenta.
    fn reduced_agrees(model: &Model) {
        let path = &model.name;
        let model = model.clone();
        let mech = mechanics::derive(&model);
        let kane = volterra::derive(&model, &mech, &[], &model.quasi_full).unwrap();
        let chosen = crate::formulation::ignorable::choose(&model, &crate::formulation::ignorable::analyze(&model, &mech)).unwrap();
        assert!(!chosen.is_empty(), "{path}: no ignorable coordinate");
        let reduced = volterra::derive_reduced(&model, &mech, &chosen, &model.quasi_reduced, &kane).unwrap();
        let rec = derive(&model, &mech, &kane).unwrap();
        let r = reduce(&model, &mech, &kane, &rec, &reduced).unwrap_or_else(|| panic!("{path}: the Schur route"));
        let mut seed = 11u64;
        for _ in 0..3 {
            let speeds: Vec<Symbol> = reduced.u.iter().chain(&reduced.g).copied().collect();
            let mut env = random_state(&model, &speeds, &mut seed);
            for (s, e) in &r.definitions {
                let v = e.eval(&env).unwrap();
                env.set(*s, v);
            }
            let n = reduced.u.len();
            for i in 0..n {
                let want = reduced.l_ni[i].eval(&env).unwrap();
                let got = r.forcing[i].eval(&env).unwrap();
                assert!((want - got).abs() <= 1e-10 * (1.0 + want.abs()), "{path}: L_NI[{i}] {got} against {want}");
                for j in 0..n {
                    let want = reduced.mass_ni.get(i, j).eval(&env).unwrap();
                    let got = r.mass.get(i, j).eval(&env).unwrap();
                    assert!((want - got).abs() <= 1e-10 * (1.0 + want.abs()), "{path}: M_NI[{i}][{j}] {got} against {want}");
                }
            }
        }
    }

    #[test]
    fn the_reduced_recursion_gives_the_dense_reduced_form() {
        for name in ["three_body", "satellite_boom", "pendulum_on_cart_5", "three_body_quaternion"] {
            reduced_agrees(&crate::model::load(format!("../models/{name}.ron")).unwrap());
        }
        reduced_agrees(&crate::model::examples::floating_chain(3).build().unwrap());
    }

    #[test]
    fn the_recursion_gives_the_dense_mass_matrix_and_forcing() {
        for name in [
            "three_body",
            "satellite_boom",
            "cart_pendulum",
            "pendulum_on_cart_5",
            "three_body_quaternion",
            "satellite_boom_quaternion",
            "rolling_disk",
            "inverted_pendulum",
            "spring_cart",
            "bicycle",
        ] {
            agrees(&format!("../models/{name}.ron"));
        }
    }

    /// Every body on a frame hung from the world: no recursion (it would be the dense sum).
    #[test]
    fn frames_on_the_world_alone_have_no_recursion() {
        let mut models: Vec<Model> = ["tumbling_body", "winch", "bouncing_ball", "cartesian_pendulum", "stiff_pendulum"]
            .iter()
            .map(|n| crate::model::load(format!("../models/{n}.ron")).unwrap())
            .collect();
        models.push(crate::model::examples::planar_chain_absolute(4).build().unwrap());
        for model in models {
            let mech = mechanics::derive(&model);
            let kane = volterra::derive(&model, &mech, &[], &model.quasi_full).unwrap();
            assert!(derive(&model, &mech, &kane).is_none(), "{}", model.name);
        }
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::formulation::{composite, mechanics, volterra};
        let model = crate::model::load("../models/three_body.ron").unwrap();
        let mech = mechanics::derive(&model);
        let kane = volterra::derive(&model, &mech, &[], &model.quasi_full).unwrap();
        let r = composite::derive(&model, &mech, &kane).unwrap();
        assert_eq!((r.mass.rows, r.forcing.len()), (8, 8));
        assert!(!r.definitions.is_empty());
    }
}
