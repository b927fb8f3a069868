//! The classical formulations the paper compares with (Tables 1-3, 6), state `[q; q']`:
//!
//! - Lagrange with multipliers: `[M a^T; a 0] [q''; -lambda] = [f; gamma]`;
//! - Maggi: `q'' = W u' + c` with `W^T M W u' = W^T (f - M c)`, `W` the null-space basis of
//!   `a` from the full quasi-velocities (the Kane `W`), no multipliers.
//!
//! Here `f = Q - dV/dq - h` (`h` the generalized inertia forces, [`Mechanics::inertial`]) and
//! `a q'' = gamma`, `gamma = -(a' q' + b')` (the constraints differentiated once more).

use super::mechanics::Mechanics;
use super::volterra::Volterra;
use crate::model::Model;
use crate::symbolic::{Expr, Symbol};
use std::collections::HashMap;

/// The pieces of Lagrange's equations with multipliers, in `q`, `q'` and `t`.
#[derive(Clone, Debug)]
pub struct Classical {
    /// `f`: everything in Lagrange's equations but `M q''` and the constraint forces.
    pub force: Vec<Expr>,
    /// `gamma = -(a' q' + b')`, so that `a q'' = gamma`.
    pub gamma: Vec<Expr>,
}

/// Derives `f` and `gamma`.
pub fn derive(model: &Model, mech: &Mechanics) -> Classical {
    let chain = model.position_chain();
    let force = mech.lagrange_force();
    let gamma = mech.velocity_residuals(&model.velocities).into_iter().map(|r| mech.tidy.of(-chain.dt(r))).collect();
    Classical { force, gamma }
}

/// Maggi's `c = W' u + X'` (the part of `q''` not proportional to `u'`), in `q`, `q'`, `t`:
/// the time derivative of `W u + X` at fixed `u`, with `u = Y q' + Z` substituted.
pub fn maggi_drift(model: &Model, mech: &Mechanics, kane: &Volterra) -> Vec<Expr> {
    let chain = model.position_chain();
    let u_of_qdot: HashMap<Symbol, Expr> = kane
        .u
        .iter()
        .enumerate()
        .map(|(k, u)| {
            let e = Expr::sum((0..model.m()).map(|j| kane.y.get(k, j) * model.velocities[j].expr())) + kane.z[k];
            (*u, e)
        })
        .collect();
    kane.qdot.iter().map(|e| mech.tidy.of(chain.dt(*e).subs(&u_of_qdot))).collect()
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::formulation::{classical, mechanics};
        let model = crate::model::load("../models/cart_pendulum.ron").unwrap();
        let mech = mechanics::derive(&model);
        let c = classical::derive(&model, &mech);
        assert_eq!((c.force.len(), c.gamma.len()), (3, 1));
    }
}
