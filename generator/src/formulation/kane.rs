//! Kane's equations (Gibbs-Appell, the standard Volterra form), state `[q; u]` with the p full
//! quasi-velocities: `M_K u' = L_K` (the paper's Table 1: p equations).

use super::Shared;
use super::equations::{Equations, Method};
use super::volterra::Volterra;
use crate::model::{Model, ModelError};
use crate::symbolic::Expr;

/// Kane's equations.
pub struct Kane;

/// `u = Y q' + Z` of a Volterra form, in `q, q'` (for the initial state).
pub fn speeds_from_qdot(model: &Model, v: &Volterra) -> Vec<Expr> {
    (0..v.u.len()).map(|k| Expr::sum((0..model.m()).map(|j| v.y.get(k, j) * model.velocities[j].expr())) + v.z[k]).collect()
}

impl Method for Kane {
    fn kind(&self) -> seam::FormulationKind {
        seam::FormulationKind::Kane
    }

    fn equations(&self, shared: &Shared) -> Result<Equations, ModelError> {
        let v = shared.kane.expect("Kane's form is derived");
        Ok(Equations {
            kind: self.kind(),
            label: "Kane / Gibbs-Appell (standard Volterra)",
            kept: (0..shared.mech.m).collect(),
            speeds: v.u.clone(),
            momenta: vec![],
            qdot: v.qdot.clone(),
            speeds_from_qdot: speeds_from_qdot(shared.model, v),
            mass: v.mass_ni.clone(),
            forcing: v.l_ni.clone(),
            post: None,
            singular: v.singular_factors.clone(),
            equations: v.u.len(),
            matrix_name: "mass matrix M_NI",
            stabilization: None,
            elimination: v.route,
            constraint_power: None,
            recursion: shared.trees.composite.cloned(),
            articulated: shared.trees.articulated.cloned(),
        })
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::formulation::{Request, derive};
        let model = crate::model::load("../models/three_body.ron").unwrap();
        let d = derive(&model, &Request::all()).unwrap();
        assert_eq!(d.equations("kane").unwrap().equations, 8);
    }
}
