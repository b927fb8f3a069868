//! Lagrange's equations with multipliers, state `[q; q']`: `[M a^T; a 0] [q''; -lambda] =
//! [f; gamma]` (the paper's Table 1: m equations).

use super::Shared;
use super::classical;
use super::equations::{Equations, Method};
use crate::model::ModelError;
use crate::symbolic::{Expr, Matrix};

/// Lagrange's equations with multipliers.
pub struct Lagrange;

impl Method for Lagrange {
    fn kind(&self) -> seam::FormulationKind {
        seam::FormulationKind::Lagrange
    }

    fn equations(&self, shared: &Shared) -> Result<Equations, ModelError> {
        let (model, mech) = (shared.model, shared.mech);
        let (m, r) = (mech.m, mech.r);
        let c = classical::derive(model, mech);
        let mut kkt = Matrix::zeros(m + r, m + r);
        for i in 0..m {
            for j in 0..m {
                kkt.set(i, j, mech.mass.get(i, j));
            }
        }
        for i in 0..r {
            for j in 0..m {
                kkt.set(m + i, j, mech.a.get(i, j));
                kkt.set(j, m + i, mech.a.get(i, j));
            }
        }
        let qd: Vec<Expr> = model.velocities.iter().map(|s| s.expr()).collect();
        let stabilization = mech
            .velocity_residuals(&model.velocities)
            .into_iter()
            .enumerate()
            .map(|(i, residual)| (residual, mech.holonomic.iter().find(|(k, _)| *k == i).map_or(Expr::zero(), |(_, h)| *h)))
            .collect();
        Ok(Equations {
            kind: self.kind(),
            label: "Lagrange's equations with multipliers",
            kept: (0..m).collect(),
            speeds: model.velocities.clone(),
            momenta: vec![],
            qdot: qd.clone(),
            speeds_from_qdot: qd,
            mass: kkt,
            forcing: c.force.iter().chain(&c.gamma).copied().collect(),
            post: None,
            singular: vec![],
            equations: m,
            matrix_name: if r == 0 { "mass matrix M" } else { "constraint matrix [M a^T; a 0]" },
            stabilization: Some(stabilization),
            elimination: "none (multipliers solved with the accelerations)",
            constraint_power: None,
            recursion: None,
            articulated: None,
        })
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::formulation::{Request, derive};
        let model = crate::model::load("../models/cart_pendulum.ron").unwrap();
        let d = derive(&model, &Request::all()).unwrap();
        assert_eq!(d.equations("lagrange").unwrap().mass.rows, 4); // m + r
    }
}
