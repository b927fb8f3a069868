//! What the emitted functions read from the shared derivation (the mechanics and the
//! ignorable coordinates): the same expressions for the module's own functions and for every
//! formulation's `rhs` and `initial_state`, computed once, and movable to the context a
//! formulation is emitted in ([`crate::symbolic::transfer`]).

use crate::formulation::mechanics::Quantities;
use crate::symbolic::eval::magnitude;
use crate::symbolic::transfer::{Transfer, Visitor};
use crate::symbolic::{Expr, Symbol};

/// See the module docs.
#[derive(Clone, Debug)]
pub struct FromMechanics {
    /// The energy function (Jacobi's integral) `h = q' . dL/dq' - L = T2 - T0 + V`, with `T =
    /// T2 + T1 + T0` split by degree in `q'` (Eq. 13: `T1 = N . q'`): `T + V` where the kinematics
    /// do not move with time; conserved (less the work below) where the model does not depend
    /// on `t` explicitly, as in a frame turning at a constant rate.
    pub energy: Expr,
    /// The rate of the work `W` that the energy function balances: `Q . q' - dL/dt` (the applied
    /// non-potential forces' power and the explicit time dependence, from a prescribed motion or
    /// time-varying forces), so `h - W` is constant along a motion whose constraints do not move
    /// (`b = 0`). Moving constraints do work this does not count: each formulation adds it after
    /// its solve (`formulation::power`).
    pub power: Expr,
    /// What `energy` is and what its balance with `W` means.
    pub energy_balance: seam::EnergyBalance,
    /// The generalized applied non-potential forces `Q`, one per coordinate.
    pub q_forces: Vec<Expr>,
    /// `M' q' + N2` of the ignorable coordinates (Eq. 26).
    pub momenta: Vec<Expr>,
    /// `a q' + b`, one per constraint.
    pub velocity_residuals: Vec<Expr>,
    /// Triangle-inequality bounds of the velocity residuals' terms.
    pub residual_bounds: Vec<Expr>,
    /// The holonomic constraints' position residuals, and their bounds.
    pub positions: Vec<Expr>,
    pub position_bounds: Vec<Expr>,
    /// Every constraint's name, and the holonomic ones'.
    pub constraint_names: Vec<String>,
    pub holonomic_names: Vec<String>,
    /// The ignorable coordinates the reduced method uses, and the number of quasi-velocities p.
    pub ignorable: Vec<usize>,
    pub p: usize,
}

impl FromMechanics {
    /// From the mechanics and the ignorable coordinates the reduced method uses.
    pub fn new(mech: &Quantities, ignorable: &[usize], velocities: &[Symbol], t: Symbol) -> FromMechanics {
        let residual_bounds =
            (0..mech.r).map(|i| Expr::sum((0..mech.m).map(|j| magnitude(mech.a.get(i, j) * velocities[j].expr()))) + magnitude(mech.b[i])).collect();
        let positions: Vec<Expr> = mech.holonomic.iter().map(|(_, e)| *e).collect();
        FromMechanics {
            energy: mech.kinetic - Expr::sum(mech.n.iter().zip(velocities).map(|(n, v)| *n * v.expr())) - mech.t0 * 2 + mech.potential,
            power: Expr::sum(mech.q_forces.iter().zip(velocities).map(|(q, v)| *q * v.expr())) - (mech.kinetic - mech.potential).diff(t),
            energy_balance: if crate::formulation::power::constraints_move(mech) {
                seam::EnergyBalance::MovingConstraints
            } else if mech.n.iter().chain([&mech.t0]).any(|e| !crate::symbolic::zero::zero_test(*e).is_zero()) {
                seam::EnergyBalance::Jacobi
            } else {
                seam::EnergyBalance::Energy
            },
            q_forces: mech.q_forces.clone(),
            momenta: ignorable.iter().map(|&i| mech.momentum(i, velocities)).collect(),
            velocity_residuals: mech.velocity_residuals(velocities),
            residual_bounds,
            position_bounds: positions.iter().map(|e| magnitude(*e)).collect(),
            positions,
            constraint_names: mech.constraint_names.clone(),
            holonomic_names: mech.holonomic.iter().map(|(i, _)| mech.constraint_names[*i].clone()).collect(),
            ignorable: ignorable.to_vec(),
            p: mech.p,
        }
    }
}

impl Transfer for FromMechanics {
    fn visit(&mut self, v: &mut dyn Visitor) {
        self.energy.visit(v);
        self.power.visit(v);
        self.q_forces.visit(v);
        self.momenta.visit(v);
        self.velocity_residuals.visit(v);
        self.residual_bounds.visit(v);
        self.positions.visit(v);
        self.position_bounds.visit(v);
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn from_mechanics_example() {
        use crate::formulation::{Request, derive};
        let model = crate::model::load("../models/cart_pendulum.ron").unwrap();
        let d = derive(&model, &Request::all()).unwrap();
        let shared = crate::emit::from_mechanics::FromMechanics::new(&d.mechanics, &d.ignorable, &model.velocities, model.t);
        assert_eq!((shared.momenta.len(), shared.velocity_residuals.len()), (1, 1));
    }
}
