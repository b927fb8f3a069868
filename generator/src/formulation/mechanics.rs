//! The mechanics of a model, to the stage every formulation shares: body velocities
//! `V_Gi = B_i q' + C_i`, `omega_i = D_i q' + E_i` (paper Eq. 54), the kinetic energy
//! `T = 1/2 q'^T M q' + q'^T N + T0` (Eq. 13), the potential V, the generalized forces Q by
//! virtual power, the kinematic constraints `a q' + b = 0` (Eq. 1), and the generalized
//! inertia forces `h(q, q', t)` with `d/dt dT/dq' - dT/dq = M q'' + h`.
//!
//! `h` comes from Kane's form of the same identity, `sum_i m_i a_i . dV_i/dq' + (I alpha_i +
//! omega_i x I omega_i) . d omega_i/dq'` with the accelerations at `q'' = 0`, one forward time
//! derivative of each body's velocity: linear in the size of the velocities, where
//! differentiating T (or M) by every coordinate is cubic in the number of bodies.
//!
//! Velocities are taken in each body's own components (the relative angles of a chain) or in
//! world components (translations of a floating base), whichever is smaller; every expression
//! goes through one shared [`Simplifier`].
//!
//! ```
//! let model = generator::model::load("../models/cart_pendulum.ron").unwrap();
//! let mech = generator::formulation::mechanics::derive(&model);
//! assert_eq!((mech.m, mech.r, mech.p), (3, 1, 2));
//! ```

use crate::kinematics::{TimeChain, add3, cross, dot, mat_vec};
use crate::model::{Constraint, Force, Model};
use crate::symbolic::fourier::{FourierLimits, Simplifier, SimplifyReport};
use crate::symbolic::transfer::{Transfer, Visitor};
use crate::symbolic::{Expr, Matrix, Symbol};
use std::cell::RefCell;
use std::collections::HashMap;
use std::rc::Rc;

/// Velocities of one body, split as in Eq. (54).
#[derive(Clone, Debug)]
pub struct BodyVelocity {
    /// Centre-of-mass velocity, in world components or (`in_body`) the body frame's.
    pub v: [Expr; 3],
    /// True when `v`, `b`, `c` and `accel` are in the body frame's components.
    pub in_body: bool,
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
    /// Inertial acceleration of the centre of mass at `q'' = 0`, in `v`'s components.
    pub accel: [Expr; 3],
    /// Angular acceleration at `q'' = 0`, body components.
    pub alpha: [Expr; 3],
    /// The centre of mass's velocity in the body's components and in the world's, as the
    /// kinematics built them (for formulations that choose their own components).
    pub v_both: ([Expr; 3], [Expr; 3]),
}

/// The simplifier a derivation shares, with interior mutability: every stage adds to its memo.
#[derive(Clone)]
pub struct Tidy(Rc<RefCell<Simplifier>>);

impl std::fmt::Debug for Tidy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Tidy({:?})", self.0.borrow().report())
    }
}

impl Tidy {
    /// A fresh simplifier under `limits`.
    pub fn new(limits: FourierLimits) -> Tidy {
        Tidy(Rc::new(RefCell::new(Simplifier::new(limits))))
    }
    /// The simplified form of `e`.
    pub fn of(&self, e: Expr) -> Expr {
        self.0.borrow_mut().simplify(e)
    }
    /// Each component simplified.
    pub fn of3(&self, v: [Expr; 3]) -> [Expr; 3] {
        v.map(|e| self.of(e))
    }
    /// Every entry simplified.
    pub fn matrix(&self, m: &Matrix) -> Matrix {
        m.map(|e| self.of(*e))
    }
    /// [`Tidy::of`], then, for a small expression with a sine or cosine in a denominator
    /// (`1/cos(theta)` from the ZYX rates), the polynomial normal form too, where such a
    /// factor cancels against the numerator's (the Fourier form keeps it as an atom). The
    /// smaller wins.
    pub fn rational(&self, e: Expr) -> Expr {
        let f = self.of(e);
        if f.dag_size() > MAX_RATIONAL_NORMAL || !has_trig_denominator(f) {
            return f;
        }
        let p = self.of(f.simplify_trig(crate::symbolic::limits::Limits { max_terms: 2_000, max_work: 200_000 }));
        if p.tree_size() < f.tree_size() { p } else { f }
    }
    /// A combination of parts already simplified (a sum of results, a transformation applied
    /// to them) in a model with `m` coordinates: simplified on a small model ([`is_small`]),
    /// left as built on a larger one, where simplifying such combinations spent most of the
    /// spatial chains' work limit and changed no emitted operation (`docs/goals.md`).
    ///
    /// ```
    /// use generator::formulation::mechanics::Tidy;
    /// use generator::symbolic::{Expr, FourierLimits};
    /// let tidy = Tidy::new(FourierLimits::default());
    /// let (a, b) = (Expr::sym("a"), Expr::sym("b"));
    /// let e = a.sin() * b.cos() + a.cos() * b.sin();
    /// assert_eq!(tidy.combination(e, 3), (a + b).sin());
    /// assert_eq!(tidy.combination(e, 20), e);
    /// ```
    pub fn combination(&self, e: Expr, m: usize) -> Expr {
        if is_small(m) { self.of(e) } else { e }
    }
    /// What the limits cut so far.
    pub fn report(&self) -> SimplifyReport {
        self.0.borrow().report()
    }
    /// Frees the memo of the forms simplified so far ([`Simplifier::forget`]): for a stage that
    /// simplifies nothing more (emission), which would hold it to its end.
    pub fn forget(&self) {
        self.0.borrow_mut().forget();
    }
    /// The limits it runs under.
    pub fn limits(&self) -> FourierLimits {
        self.0.borrow().limits()
    }
}

/// A point's velocity in the components where it is cheapest, with what the formulations
/// need of it: the partial velocities by each rate and the acceleration with the rates'
/// derivatives zero.
#[derive(Clone, Debug)]
pub struct Translation {
    pub v: [Expr; 3],
    /// True for the body frame's components (the acceleration then has the transport term).
    pub in_body: bool,
    /// `dv/d rate_j`, one per rate.
    pub partials: Vec<[Expr; 3]>,
    pub accel: [Expr; 3],
}

impl Translation {
    /// The velocity, given in the frame's components and in the world's, with partials by
    /// `rates` and the acceleration along `chain` (`omega` the frame's angular velocity in its
    /// own components); the one with fewer operations
    /// (`dag_ops`: the operations with shared nodes counted once) wins. A body moved by translation rates (a floating
    /// base) is cheapest in world components, where their derivatives vanish at once; a link of
    /// a chain in its own, where only its joints' relative angles appear.
    pub fn cheaper(tidy: &Tidy, v_body: &[Expr; 3], v_world: &[Expr; 3], omega: &[Expr; 3], rates: &[Symbol], chain: &TimeChain) -> Translation {
        let vw = v_world.map(|e| tidy.rational(e));
        let world_accel = tidy.of3(chain.dt3(&vw));
        let world = Translation { partials: partials(tidy, &vw, rates), v: vw, in_body: false, accel: world_accel };
        let world_ops = ops(&world.partials, &world.accel);
        let vb = v_body.map(|e| tidy.rational(e));
        let body_partials = partials(tidy, &vb, rates);
        // The body form's partials alone cost at least the world form in all (operations over
        // distinct nodes only grow with more outputs): it loses without its acceleration, the
        // transport term that costs most to simplify. On the planar chain of 20 rods in
        // absolute angles, every link from the third on.
        if crate::symbolic::expr::dag_ops(&body_partials.concat()) >= world_ops {
            return world;
        }
        // A rate absent from the world acceleration (as simplified: no occurrence left).
        let absent = |r: Symbol| !world.accel.iter().any(|e| e.contains(r));
        let body = Translation::body_form_of(tidy, vb, body_partials, omega, rates, chain, absent);
        if body_ops(&body) < world_ops { body } else { world }
    }

    /// The velocity in the frame's own components only: for a body whose velocity the
    /// mechanics already found cheaper there (a link of a chain, where only its joints'
    /// relative angles appear), the world form is not derived again. The rates absent from
    /// the world acceleration are found by the exact zero test on its unsimplified form.
    ///
    /// Measured on every model in `models/`: where the mechanics chose the body's components,
    /// Kane's derivation in the quasi-velocities chose them too (scene 2's links: 123 operations
    /// against 796); where it chose the world's, the choice can turn (scene 3's boom), so
    /// there both are compared ([`Translation::cheaper`]).
    pub fn in_body(tidy: &Tidy, v_body: &[Expr; 3], v_world: &[Expr; 3], omega: &[Expr; 3], rates: &[Symbol], chain: &TimeChain) -> Translation {
        let world_accel = chain.dt3(v_world);
        let absent = |r: Symbol| world_accel.iter().all(|e| !e.contains(r) || crate::symbolic::zero::is_identically_zero(e.diff(r)));
        let vb = v_body.map(|e| tidy.rational(e));
        let body_partials = partials(tidy, &vb, rates);
        Translation::body_form_of(tidy, vb, body_partials, omega, rates, chain, absent)
    }

    /// The body-components form of the simplified velocity `vb` with its partials: the
    /// transport acceleration `dv/dt + omega x v`, the rates for which `absent` holds set to
    /// zero in it.
    fn body_form_of(
        tidy: &Tidy,
        vb: [Expr; 3],
        partials: Vec<[Expr; 3]>,
        omega: &[Expr; 3],
        rates: &[Symbol],
        chain: &TimeChain,
        absent: impl Fn(Symbol) -> bool,
    ) -> Translation {
        let transport = tidy.of3(add3(&chain.dt3(&vb), &cross(omega, &vb)));
        // The transport form `dv/dt + omega x v` holds translation rates (a floating base's)
        // formally, where only the rotation's identities cancel them; but the acceleration is
        // R^T times the world's, so a rate absent from the world acceleration is absent from it
        // too, and is set to zero (exact, no test needed).
        let zeros: HashMap<Symbol, Expr> = rates.iter().filter(|r| absent(**r)).map(|r| (*r, Expr::zero())).collect();
        let transport = if zeros.is_empty() { transport } else { transport.map(|e| tidy.of(e.subs(&zeros))) };
        Translation { partials, v: vb, in_body: true, accel: transport }
    }
}

/// `dv/d rate_j`, one per rate, simplified.
fn partials(tidy: &Tidy, v: &[Expr; 3], rates: &[Symbol]) -> Vec<[Expr; 3]> {
    rates.iter().map(|r| v.map(|e| tidy.rational(e.diff(*r)))).collect()
}

/// Operations of the partials and the acceleration together ([`crate::symbolic::expr::dag_ops`]).
fn ops(p: &[[Expr; 3]], a: &[Expr; 3]) -> usize {
    let all: Vec<Expr> = p.iter().flatten().chain(a).copied().collect();
    crate::symbolic::expr::dag_ops(&all)
}

fn body_ops(t: &Translation) -> usize {
    ops(&t.partials, &t.accel)
}

/// Largest expression (distinct nodes) [`Tidy::rational`] puts in the polynomial normal form.
const MAX_RATIONAL_NORMAL: usize = 300;

/// True when `e` divides by an expression holding a sine or cosine.
fn has_trig_denominator(e: Expr) -> bool {
    use crate::symbolic::{Func, Node};
    let trig = |b: Expr| b.post_order_nodes().iter().any(|n| matches!(&*n.node(), Node::Fun(Func::Sin | Func::Cos | Func::Tan, _)));
    e.post_order_nodes().iter().any(|n| match &*n.node() {
        Node::Mul { factors, .. } => factors.iter().any(|(b, x)| x.is_negative() && trig(*b)),
        _ => false,
    })
}

/// What the mechanics derives before a formulation is chosen (a [`Mechanics`] without its
/// simplifier: this part can move to another context, as a `Parcel`).
#[derive(Clone, Debug)]
pub struct Quantities {
    /// Coordinates m, constraints r, degrees of freedom p = m - r.
    pub m: usize,
    pub r: usize,
    pub p: usize,
    pub bodies: Vec<BodyVelocity>,
    /// Kinetic energy T: on small models (at most [`MAX_FOUR_ANGLE_COORDINATES`] coordinates)
    /// simplified, elsewhere the sum of the bodies' `m v.v / 2 + omega.I omega / 2` over their
    /// simplified velocities as built (the energy's emission, the power's `dT/dt` and
    /// Definition 1's zero tests take either).
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
    /// `dV/dq`.
    pub potential_gradient: Vec<Expr>,
    /// Constraint Jacobian a (r x m).
    pub a: Matrix,
    /// Constraint bias b (r).
    pub b: Vec<Expr>,
    /// Position-level constraints `phi(q, t) = 0`, by constraint index.
    pub holonomic: Vec<(usize, Expr)>,
    /// Constraint names, in order.
    pub constraint_names: Vec<String>,
}

/// Everything derived before a formulation is chosen: the [`Quantities`] (read through
/// `Deref`: `mech.mass`) and the simplifier every later stage shares.
#[derive(Clone, Debug)]
pub struct Mechanics {
    pub quantities: Quantities,
    pub tidy: Tidy,
    /// Generalized inertia forces `h` (`d/dt dT/dq' - dT/dq = M q'' + h`) as built: each entry
    /// the sum over the bodies of their simplified partial velocities and accelerations.
    /// [`Mechanics::inertial`] gives them simplified where the model is small; only the routes
    /// through the coordinates' `h` ask for it (Lagrange's and Maggi's forms, Kane's through
    /// `W^T h`), so Kane's form from the bodies' velocities (scenes 2 and 3) never simplifies
    /// it. Not among the [`Quantities`]: the emitting thread, which gets those, never reads it.
    pub inertial_built: Vec<Expr>,
    /// Uniform gravity, world components (the sum of the model's gravity forces; zero for none).
    pub gravity: [Expr; 3],
    /// `dV/dq` without gravity's potential: the recursions over a tree take gravity as the
    /// world's acceleration `-g` instead (Featherstone's way), where its potential's gradient
    /// sums, for every coordinate, a term for every body beyond it (a floating humanoid's
    /// gravity was 28 % of its Kane's operations this way).
    pub potential_gradient_without_gravity: Vec<Expr>,
}

impl std::ops::Deref for Mechanics {
    type Target = Quantities;
    fn deref(&self) -> &Quantities {
        &self.quantities
    }
}

impl Transfer for BodyVelocity {
    fn visit(&mut self, v: &mut dyn Visitor) {
        self.v.visit(v);
        self.omega.visit(v);
        self.b.visit(v);
        self.c.visit(v);
        self.e.visit(v);
        self.d.visit(v);
        self.accel.visit(v);
        self.alpha.visit(v);
        self.v_both.visit(v);
    }
}

impl Transfer for Quantities {
    fn visit(&mut self, v: &mut dyn Visitor) {
        self.bodies.visit(v);
        self.kinetic.visit(v);
        self.potential.visit(v);
        self.mass.visit(v);
        self.n.visit(v);
        self.t0.visit(v);
        self.q_forces.visit(v);
        self.potential_gradient.visit(v);
        self.a.visit(v);
        self.b.visit(v);
        self.holonomic.iter_mut().for_each(|(_, e)| e.visit(v));
    }
}

/// Largest model (coordinates) whose simplifier combines four angles in one harmonic instead of
/// three: enough to find that a free system's locked inertia does not depend on its absolute
/// orientation (three ZYX angles and a joint), too costly on long chains (see
/// [`FourierLimits::max_angle_atoms`]).
pub const MAX_FOUR_ANGLE_COORDINATES: usize = 8;

/// Whether a model with `m` coordinates is small (at most [`MAX_FOUR_ANGLE_COORDINATES`]): its
/// simplifier combines four angles ([`derivation_limits`]) and simplifies combinations of parts
/// already simplified ([`Tidy::combination`]).
pub fn is_small(m: usize) -> bool {
    m <= MAX_FOUR_ANGLE_COORDINATES
}

/// Limits for the simplifications made while deriving a model with `m` coordinates.
pub fn derivation_limits(m: usize) -> FourierLimits {
    let limits = FourierLimits::default();
    if is_small(m) { FourierLimits { max_angle_atoms: 4, ..limits } } else { limits }
}

/// Splits a velocity-linear expression into `(d/dq', value at q' = 0)`.
pub fn split_linear(e: Expr, velocities: &[Symbol], zero: &HashMap<Symbol, Expr>) -> (Vec<Expr>, Expr) {
    (velocities.iter().map(|v| e.diff(*v)).collect(), e.subs(zero))
}

fn zero_velocities(model: &Model) -> HashMap<Symbol, Expr> {
    model.velocities.iter().map(|v| (*v, Expr::zero())).collect()
}

/// The time derivative with `q'' = 0`: coordinates move with their rates, rates are constant.
fn drift_chain(model: &Model) -> TimeChain {
    model.position_chain()
}

/// Derives the shared mechanics of a model.
pub fn derive(model: &Model) -> Mechanics {
    derive_for(model, true)
}

/// [`derive()`], for formulations of which `classical` says whether Lagrange's or Maggi's form
/// is among them (they solve with `M` and `N` themselves; Kane's and the reduced forms on a
/// tree take their rates from the recursions).
pub fn derive_for(model: &Model, classical: bool) -> Mechanics {
    let tidy = Tidy::new(derivation_limits(model.m()));
    let chain = model.position_chain();
    let drift = drift_chain(model);
    let zero = zero_velocities(model);
    let m = model.m();

    let mut bodies = Vec::new();
    // Terms per entry, summed once at the end (adding to a sum one term at a time copies it).
    let mut mass_terms: Vec<Vec<Expr>> = vec![Vec::new(); m * m];
    let mut n_terms: Vec<Vec<Expr>> = vec![Vec::new(); m];
    let mut inertial_terms: Vec<Vec<Expr>> = vec![Vec::new(); m];
    let mut t0_terms = Vec::new();
    let mut kinetic_terms = Vec::new();
    // The most rates moving one body: a chain's last link is moved by all of them, a robot's
    // hand by its own branch's joints and the base's.
    let mut deepest = 0;
    for body in &model.bodies {
        let frame = &model.frames[body.frame];
        // The centre of mass's velocity in the body's components and in the world's.
        // The centre of mass's velocity, partial velocities and acceleration, in the body's
        // components or the world's, whichever is cheaper.
        let v_body = frame.point_velocity(&body.com, &chain);
        let v_world = chain.dt3(&frame.point(&body.com));
        let translation = Translation::cheaper(&tidy, &v_body, &v_world, &frame.omega, &model.velocities, &drift);
        let (v, in_body, accel) = (translation.v, translation.in_body, translation.accel);
        let omega = tidy.of3(frame.omega);
        let mut bm = Matrix::zeros(3, m);
        let mut dm = Matrix::zeros(3, m);
        let mut c = [Expr::zero(); 3];
        let mut e = [Expr::zero(); 3];
        for k in 0..3 {
            let (dk, ek) = split_linear(omega[k], &model.velocities, &zero);
            for j in 0..m {
                bm.set(k, j, translation.partials[j][k]);
                dm.set(k, j, tidy.of(dk[j]));
            }
            c[k] = tidy.of(v[k].subs(&zero));
            e[k] = tidy.of(ek);
        }
        let alpha = tidy.of3(drift.dt3(&omega));
        let mass_expr = body.mass;
        let (iw, ie, torque) = match &body.inertia {
            Some(inertia) => {
                let iw = mat_vec(inertia, &omega);
                let euler = add3(&mat_vec(inertia, &alpha), &cross(&omega, &iw));
                (Some(iw), Some(mat_vec(inertia, &e)), Some(tidy.of3(euler)))
            }
            None => (None, None, None),
        };
        let col = |mat: &Matrix, j: usize| [mat.get(0, j), mat.get(1, j), mat.get(2, j)];
        let moving: Vec<usize> = (0..m).filter(|&j| (0..3).any(|k| !bm.get(k, j).is_zero() || !dm.get(k, j).is_zero())).collect();
        deepest = deepest.max(moving.len());
        let i_d: Vec<Option<[Expr; 3]>> = (0..m).map(|j| body.inertia.as_ref().map(|inertia| mat_vec(inertia, &col(&dm, j)))).collect();
        for (x, &i) in moving.iter().enumerate() {
            let (bi, di) = (col(&bm, i), col(&dm, i));
            for &j in &moving[x..] {
                let mut entry = dot(&bi, &col(&bm, j)) * mass_expr;
                if let Some(idj) = &i_d[j] {
                    entry += dot(&di, idj);
                }
                if !entry.is_zero() {
                    mass_terms[i * m + j].push(entry);
                }
            }
            n_terms[i].push(dot(&bi, &c) * mass_expr);
            inertial_terms[i].push(dot(&bi, &accel) * mass_expr);
            if let (Some(ie), Some(torque)) = (&ie, &torque) {
                n_terms[i].push(dot(&di, ie));
                inertial_terms[i].push(dot(&di, torque));
            }
        }
        t0_terms.push(dot(&c, &c) * mass_expr / 2);
        kinetic_terms.push(dot(&v, &v) * mass_expr / 2);
        if let Some(iw) = &iw {
            kinetic_terms.push(dot(&omega, iw) / 2);
            t0_terms.push(dot(&e, ie.as_ref().expect("with iw")) / 2);
        }
        bodies.push(BodyVelocity { v, in_body, omega, b: bm, c, d: dm, e, accel, alpha, v_both: (v_body, v_world) });
    }
    // Where neither Lagrange's nor Maggi's form is derived, on a tree of short branches (a
    // humanoid: no body moved by more than half the rates), the entries of `M` and `N` are left
    // as built: simplifying them took two thirds of the humanoid's mechanics stage and 40 % of
    // its memory when only the reduced form was asked for, and changed its operations by under
    // 2 %. Lagrange's and Maggi's forms, which solve with them, took longer with them as built
    // (the humanoid's formulations after the mechanics: 4.4 s against 0.7 s); so did a
    // chain, where each entry sums products of the angles of every link beyond both joints
    // (the 20-link floating chain: 13 times as long).
    let as_built = !classical && 2 * deepest <= m;
    let settle = |e: Expr| if as_built { e } else { tidy.of(e) };
    let mut mass = Matrix::zeros(m, m);
    for i in 0..m {
        for j in i..m {
            let s = settle(Expr::sum(std::mem::take(&mut mass_terms[i * m + j])));
            mass.set(i, j, s);
            mass.set(j, i, s);
        }
    }
    let n: Vec<Expr> = n_terms.into_iter().map(|t| settle(Expr::sum(t))).collect();
    let inertial_built: Vec<Expr> = inertial_terms.into_iter().map(Expr::sum).collect();
    let t0 = tidy.of(Expr::sum(t0_terms));
    // Expanded, T is the larger form on long chains (`n^3 / 6` terms on the n-link pendulum):
    // simplifying it cost the 40-link pendulum 20 nodes over the term limit and a tenth of its
    // memory and changed no emitted operation; on small models it is the smaller (the cart
    // pendulum's energy 50 operations against 56 as built).
    let kinetic = tidy.combination(Expr::sum(kinetic_terms), m);

    // Forces: potentials into V, the rest into Q by virtual power.
    let mut potential_terms = Vec::new();
    // Gravity's terms of V, and the other potentials' (`potential_gradient_without_gravity`).
    let mut other_potentials = Vec::new();
    let mut gravity = [Expr::zero(); 3];
    let mut q_forces = vec![Expr::zero(); m];
    let add_power = |q: &mut Vec<Expr>, force: &[Expr; 3], vel: &[Expr; 3]| {
        for (j, v) in model.velocities.iter().enumerate() {
            let partial = [vel[0].diff(*v), vel[1].diff(*v), vel[2].diff(*v)];
            q[j] += dot(force, &partial);
        }
    };
    for f in &model.forces {
        match f {
            Force::Gravity { vector } => {
                gravity = add3(&gravity, vector);
                for body in &model.bodies {
                    let pos = model.frames[body.frame].point(&body.com);
                    potential_terms.push(-dot(vector, &pos) * body.mass);
                }
            }
            Force::PointForce { frame, point, force_world, .. } => {
                let vel = chain.dt3(&model.frames[*frame].point(point));
                add_power(&mut q_forces, force_world, &vel);
            }
            Force::Torque { body, torque, .. } => {
                let omega = model.frames[model.bodies[*body].frame].omega;
                add_power(&mut q_forces, torque, &omega);
            }
            Force::Spring { a, b, stiffness, rest_length, .. } => {
                let len = spring_length(model, &tidy, a, b);
                let energy = (len - *rest_length).powi(2) * *stiffness / 2;
                potential_terms.push(energy);
                other_potentials.push(energy);
            }
            Force::Damper { a, b, damping, .. } => {
                // Force -c L' along the line: Q_j = -c L' dL/dq_j.
                let len = spring_length(model, &tidy, a, b);
                let rate = chain.dt(len);
                for (j, q) in model.coordinates.iter().enumerate() {
                    q_forces[j] = q_forces[j] - *damping * rate * len.diff(*q);
                }
            }
            Force::Generalized { components, .. } => {
                for j in 0..m {
                    q_forces[j] += components[j];
                }
            }
            Force::Potential { expr, .. } => {
                potential_terms.push(*expr);
                other_potentials.push(*expr);
            }
        }
    }
    let q_forces: Vec<Expr> = q_forces.into_iter().map(|e| tidy.of(e)).collect();
    // Expanded, a chain's V sums a term per body and link (past the term limit from 60 links on
    // the pendulum on a cart, each link's mass its own symbol): past 8 coordinates it is the sum
    // of each body's simplified term, as built.
    let potential = if is_small(m) { tidy.of(Expr::sum(potential_terms)) } else { Expr::sum(potential_terms.into_iter().map(|t| tidy.of(t))) };
    let gradient = |v: Expr| -> Vec<Expr> { model.coordinates.iter().map(|q| tidy.of(v.diff(*q))).collect() };
    let potential_gradient = gradient(potential);
    let potential_gradient_without_gravity =
        if gravity.iter().all(|g| g.is_zero()) { potential_gradient.clone() } else { gradient(Expr::sum(other_potentials.into_iter().map(|t| tidy.of(t)))) };

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
            a.set(i, j, tidy.of(row[j]));
        }
        b.push(tidy.of(bias));
    }
    Mechanics {
        quantities: Quantities { m, r, p: m - r, bodies, kinetic, potential, mass, n, t0, q_forces, potential_gradient, a, b, holonomic, constraint_names },
        tidy,
        inertial_built,
        gravity,
        potential_gradient_without_gravity,
    }
}

fn spring_length(model: &Model, tidy: &Tidy, a: &(usize, [Expr; 3]), b: &(usize, [Expr; 3])) -> Expr {
    let pa = model.frames[a.0].point(&a.1);
    let pb = model.frames[b.0].point(&b.1);
    let d = [pa[0] - pb[0], pa[1] - pb[1], pa[2] - pb[2]];
    tidy.of(dot(&d, &d)).sqrt()
}

impl Quantities {
    /// Kinetic energy rebuilt from M, N, T0 and the velocities (Eq. 13).
    pub fn kinetic_from_matrices(&self, velocities: &[Symbol]) -> Expr {
        let qd: Vec<Expr> = velocities.iter().map(|v| v.expr()).collect();
        let mut terms = vec![self.t0];
        for i in 0..self.m {
            terms.push(self.n[i] * qd[i]);
            for j in 0..self.m {
                terms.push(self.mass.get(i, j) * qd[i] * qd[j] / 2);
            }
        }
        Expr::sum(terms)
    }

    /// The generalized momentum of coordinate `j`, `dT/dq'_j = M_j q' + N_j` (Eq. 26 for an
    /// ignorable one).
    pub fn momentum(&self, j: usize, velocities: &[Symbol]) -> Expr {
        Expr::sum((0..self.m).map(|k| self.mass.get(j, k) * velocities[k].expr())) + self.n[j]
    }

    /// The residuals `a q' + b` of the kinematic constraints, one per constraint.
    pub fn velocity_residuals(&self, velocities: &[Symbol]) -> Vec<Expr> {
        (0..self.r).map(|i| Expr::sum((0..self.m).map(|j| self.a.get(i, j) * velocities[j].expr())) + self.b[i]).collect()
    }
}

impl Mechanics {
    /// Generalized inertia forces `h`: `d/dt dT/dq' - dT/dq = M q'' + h`. On small models (at
    /// most [`MAX_FOUR_ANGLE_COORDINATES`] coordinates) simplified, elsewhere each entry the sum
    /// over the bodies of their simplified partial velocities and accelerations as built
    /// ([`Tidy::combination`]): expanded, a chain's entries sum a term per body and link (past
    /// the term limit from 50 links on the pendulum on a cart), and the emitted code shares the
    /// built form's per-body parts (the 60-link pendulum's Lagrange assembly 19499 operations
    /// against 28026 expanded). Simplified when first asked for (the simplifier's memo makes
    /// later calls lookups): 5 of scene 2's 13 ms of mechanics, which Kane's form alone skips.
    ///
    /// ```
    /// use generator::formulation::mechanics;
    /// let model = generator::model::examples::n_link_pendulum_on_cart(1).build().unwrap();
    /// let mech = mechanics::derive(&model);
    /// assert_eq!(mech.inertial().len(), model.m());
    /// ```
    pub fn inertial(&self) -> Vec<Expr> {
        self.inertial_built.iter().map(|e| self.tidy.combination(*e, self.m)).collect()
    }

    /// `f = Q - dV/dq - h`: everything in Lagrange's equations but `M q''` and the constraint
    /// forces, in `q`, `q'`, `t`; a combination of its simplified parts past
    /// [`MAX_FOUR_ANGLE_COORDINATES`] coordinates, as `h` is ([`Tidy::combination`]).
    pub fn lagrange_force(&self) -> Vec<Expr> {
        let inertial = self.inertial();
        (0..self.m).map(|j| self.tidy.combination(self.q_forces[j] - self.potential_gradient[j] - inertial[j], self.m)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::symbolic::zero::zero_test;

    /// `h` is simplified only when asked for: Kane's form from the bodies' velocities (scene 2)
    /// never asks, and asking afterwards still finds work to do; asked again, the memo answers.
    #[test]
    fn the_inertia_forces_are_simplified_only_when_asked_for() {
        let model = crate::model::load("../models/three_body.ron").unwrap();
        let mech = derive(&model);
        let kane = crate::formulation::volterra::derive(&model, &mech, &[], &model.quasi_full).unwrap();
        assert!(kane.route.contains("from the bodies' velocities"), "{}", kane.route);
        let before = mech.tidy.report().work;
        let h = mech.inertial();
        let after = mech.tidy.report().work;
        assert!(after > before, "h was already simplified: {before} term products before asking, {after} after");
        assert_eq!(mech.inertial(), h);
        assert_eq!(mech.tidy.report().work, after, "asked again, h is simplified anew");
        // Simplified, each entry is the sum it was built as (a zero difference at a state).
        for (built, simple) in mech.inertial_built.iter().zip(&h) {
            assert!(zero_test(*built - *simple).is_zero(), "{built} against {simple}");
        }
    }

    /// Where the body's components win, deriving them alone (the absent rates by the zero test
    /// on the raw world acceleration) gives exactly what comparing both forms gave.
    #[test]
    fn the_body_form_alone_is_the_compared_one_where_it_wins() {
        let mut checked = 0;
        for name in ["three_body", "cart_pendulum", "satellite_boom", "pendulum_on_cart_5"] {
            let model = crate::model::load(format!("../models/{name}.ron")).unwrap();
            let (tidy, chain) = (Tidy::new(derivation_limits(model.m())), model.position_chain());
            for body in &model.bodies {
                let frame = &model.frames[body.frame];
                let (vb, vw) = (frame.point_velocity(&body.com, &chain), chain.dt3(&frame.point(&body.com)));
                let compared = Translation::cheaper(&tidy, &vb, &vw, &frame.omega, &model.velocities, &chain);
                if compared.in_body {
                    let alone = Translation::in_body(&tidy, &vb, &vw, &frame.omega, &model.velocities, &chain);
                    assert_eq!((alone.v, alone.partials, alone.accel), (compared.v, compared.partials, compared.accel), "{name}: {}", body.name);
                    checked += 1;
                }
            }
        }
        assert!(checked >= 8, "{checked} bodies where the body's components win");
    }

    /// `M q'' + h` equals `d/dt dT/dq' - dT/dq` with T from the body velocities, and M, N, T0
    /// rebuild T, on every reference model.
    #[test]
    fn inertia_forces_are_lagranges() {
        for name in ["cart_pendulum", "three_body", "satellite_boom", "cartesian_pendulum", "rolling_disk", "spring_cart"] {
            let model = crate::model::load(format!("../models/{name}.ron")).unwrap();
            let mech = derive(&model);
            assert!(zero_test(mech.kinetic - mech.kinetic_from_matrices(&model.velocities)).is_zero(), "{name}: T");
            let chain = model.velocity_chain();
            for j in 0..mech.m {
                let lagrange = chain.dt(mech.kinetic.diff(model.velocities[j])) - mech.kinetic.diff(model.coordinates[j]);
                let ours = Expr::sum((0..mech.m).map(|k| mech.mass.get(j, k) * model.accelerations[k].expr())) + mech.inertial()[j];
                assert!(zero_test(lagrange - ours).is_zero(), "{name}: equation {j}");
            }
        }
    }
}
