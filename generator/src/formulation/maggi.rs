//! Maggi's equations, state `[q; q']`: `q'' = W u' + c` with `W^T M W u' = W^T (f - M c)`,
//! `W` the null-space basis of `a` from the full quasi-velocities (Kane's `W`), no multipliers
//! (the paper's Table 1: m equations).

use super::Shared;
use super::classical;
use super::equations::{Equations, Method};
use crate::model::ModelError;
use crate::symbolic::{Expr, Matrix};

/// Maggi's equations.
pub struct Maggi;

impl Method for Maggi {
    fn kind(&self) -> seam::FormulationKind {
        seam::FormulationKind::Maggi
    }

    fn equations(&self, shared: &Shared) -> Result<Equations, ModelError> {
        let (model, mech) = (shared.model, shared.mech);
        let kane = shared.kane.expect("Maggi is derived with Kane's form");
        let m = mech.m;
        let c = classical::derive(model, mech);
        let w = kane.w.clone();
        let drift = classical::maggi_drift(model, mech, kane);
        let wt = w.transpose();
        let mass = mech.tidy.matrix(&wt.mul(&mech.mass).mul(&w));
        let mc = mech.mass.mul(&Matrix::column(drift.clone()));
        let rest = Matrix::column((0..m).map(|j| c.force[j] - mc.get(j, 0)).collect());
        // Lagrange's `f` is a combination of simplified parts past 8 coordinates, and so is this.
        let forcing = wt.mul(&rest).col(0).into_iter().map(|e| mech.tidy.combination(e, m)).collect();
        let qd: Vec<Expr> = model.velocities.iter().map(|s| s.expr()).collect();
        Ok(Equations {
            kind: self.kind(),
            label: "Maggi's equations",
            kept: (0..m).collect(),
            speeds: model.velocities.clone(),
            momenta: vec![],
            qdot: qd.clone(),
            speeds_from_qdot: qd,
            mass,
            forcing,
            post: Some((w, drift)),
            singular: kane.singular_factors.clone(),
            equations: m,
            matrix_name: "Maggi matrix W^T M W",
            stabilization: None,
            elimination: kane.route,
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
        assert_eq!(d.equations("maggi").unwrap().mass.rows, 2); // p
    }
}
