//! The power of the constraint forces where a constraint moves (`b` not zero): the forces
//! `R = M q'' - f` that keep `a q' + b = 0` do work `R . q' = -lambda . b` on the system (a motor
//! holding a rate, a guide that moves). Jacobi's integral `h = T2 - T0 + V` then changes by that
//! work besides the applied forces' (`dh/dt = (Q + R) . q' - dL/dt`), so the work integral `W`
//! takes it in and `h - W` stays constant.
//!
//! `R . q'` needs the accelerations, which every formulation has only after its solve
//! `mass x = forcing`; but `q''` is affine in `x`, so the power is too: `P = weights . x +
//! offset`, with `weights` and `offset` in the state, emitted before the solve and combined after
//! it. With the state's coordinates `q_K`, speeds `s` and rates `q' = qdot(q_K, s, t)`:
//!
//! `q'' = dqdot/dq_K qdot_K + dqdot/dt + dqdot/ds s'`, `s' = x` (or Maggi's `W x + c`), so
//! `weights = (qdot^T M dqdot/ds) [I 0]` (or `... W`) and
//! `offset = qdot^T (M (dqdot/dq_K qdot_K + dqdot/dt (+ dqdot/ds c)) - f)`.

use super::equations::Equations;
use super::mechanics::{Mechanics, Quantities};
use crate::model::Model;
use crate::symbolic::diff::TimeDerivative;
use crate::symbolic::{Expr, Symbol};
use std::collections::HashMap;

/// True when some constraint moves: its bias `b` is not identically zero.
pub fn constraints_move(mech: &Quantities) -> bool {
    mech.b.iter().any(|b| !crate::symbolic::zero::zero_test(*b).is_zero())
}

/// `(weights, offset)` with `R . q' = weights . x + offset` for the solution `x` of `eqs`'
/// `mass x = forcing`; `force` is Lagrange's `f` ([`Mechanics::lagrange_force`]).
pub fn constraint_power(model: &Model, mech: &Mechanics, force: &[Expr], eqs: &Equations) -> (Vec<Expr>, Expr) {
    let m = model.m();
    let n = eqs.mass.rows;
    let qdot = &eqs.qdot;
    // q' in the state's terms, for M and f (which read q' as the model's velocity symbols).
    let to_state: HashMap<Symbol, Expr> = model.velocities.iter().copied().zip(qdot.iter().copied()).collect();
    // The part of q'' not proportional to x: the kept coordinates move at their rates, time
    // passes, and Maggi's speeds add c.
    let mut pairs: Vec<(Symbol, Expr)> = eqs.kept.iter().map(|&j| (model.coordinates[j], qdot[j])).collect();
    if let Some((_, c)) = &eqs.post {
        pairs.extend(eqs.speeds.iter().copied().zip(c.iter().copied()));
    }
    let mut chain = TimeDerivative::new(model.t, &pairs);
    let drift: Vec<Expr> = qdot.iter().map(|e| chain.dt(*e)).collect();
    // dq''/dx: the speeds' rates are x itself, or W x.
    let by_speed: Vec<Vec<Expr>> = qdot.iter().map(|e| eqs.speeds.iter().map(|s| e.diff(*s)).collect()).collect();
    let by_x = |j: usize, k: usize| -> Expr {
        match &eqs.post {
            None if k < eqs.speeds.len() => by_speed[j][k],
            None => Expr::zero(),
            Some((w, _)) => Expr::sum((0..eqs.speeds.len()).map(|i| by_speed[j][i] * w.get(i, k))),
        }
    };
    // qdot^T M, in the state.
    let row: Vec<Expr> = (0..m).map(|k| mech.tidy.of(Expr::sum((0..m).map(|j| qdot[j] * mech.mass.get(j, k).subs(&to_state))))).collect();
    let weights = (0..n).map(|k| mech.tidy.of(Expr::sum((0..m).map(|j| row[j] * by_x(j, k))))).collect();
    let offset = mech.tidy.of(Expr::sum((0..m).map(|j| row[j] * drift[j] - qdot[j] * force[j].subs(&to_state))));
    (weights, offset)
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::formulation::{Request, derive};
        let model = crate::model::from_source(
            "rod.ron",
            r#"Model(
            name: "rod",
            parameters: { "m": 1.0, "I": 0.1, "Omega": 2.0 },
            coordinates: ["phi", "r"],
            frames: [Frame(name: "rod", parent: "world", rotation: [Z("phi")])],
            bodies: [
                Body(name: "hub", frame: "rod", mass: "1", com: ["0", "0", "0"], inertia: Diagonal(["I", "I", "I"])),
                Body(name: "bead", frame: "rod", mass: "m", com: ["r", "0", "0"], inertia: PointMass),
            ],
            constraints: [Velocity(name: "motor", expr: "phi' - Omega")],
            quasi_velocities: QuasiVelocities(full: ["r'"], reduced: ["r'"]),
            ignorable: Auto,
        )"#,
        )
        .unwrap();
        let d = derive(&model, &Request::all()).unwrap();
        // Lagrange's x is [q''; -lambda]: the power reads the accelerations (phi'' and r'').
        let (weights, _) = d.equations("lagrange").unwrap().constraint_power.clone().unwrap();
        assert_eq!(weights.len(), 3);
    }
}
