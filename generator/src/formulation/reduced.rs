//! The paper's reduced Volterra equations, state `[q; u_NI]` (or `[q_NI; u_NI]` with the
//! ignorable coordinates left out): `M_NI u_NI' = L_NI` (Eqs. 64-67; Table 1: p - s equations).

use super::Shared;
use super::equations::{Equations, Method};
use super::ignorable::depends;
use super::kane::speeds_from_qdot;
use super::volterra::Volterra;
use crate::model::{ErrorKind, Model, ModelError};
use crate::symbolic::{Expr, Matrix, Symbol};
use std::collections::HashMap;

/// The reduced Volterra equations.
pub struct ReducedVolterra;

/// For each ignorable coordinate of the reduced form, the first place its state's rates need
/// it (`None`: it can leave the integrated state): `q' = W u + X`, `L_NI`, `M_NI`, each decided
/// by the exact zero test. `inspect` reports the same verdicts the generator acts on.
pub fn needed(model: &Model, v: &Volterra) -> Vec<(usize, Option<String>)> {
    let m = model.m();
    let places: Vec<(String, Expr)> = (0..m)
        .map(|j| (format!("q'_{} = W u + X", model.coordinates[j].name()), v.qdot[j]))
        .chain(v.l_ni.iter().enumerate().map(|(k, e)| (format!("L_NI[{}]", k + 1), *e)))
        .chain(v.mass_ni.data.iter().map(|e| ("M_NI".to_string(), *e)))
        .collect();
    v.ignorable
        .iter()
        .map(|&j| {
            let q = model.coordinates[j];
            (j, places.iter().find(|(_, e)| depends(*e, q).is_some()).map(|(p, _)| p.clone()))
        })
        .collect()
}

impl Method for ReducedVolterra {
    fn kind(&self) -> seam::FormulationKind {
        seam::FormulationKind::ReducedVolterra
    }

    fn equations(&self, shared: &Shared) -> Result<Equations, ModelError> {
        let (model, v) = (shared.model, shared.reduced.expect("the reduced form is derived"));
        let m = model.m();
        let mut qdot = v.qdot.clone();
        let mut mass = v.mass_ni.clone();
        let mut forcing = v.l_ni.clone();
        let mut singular = v.singular_factors.clone();
        let mut recursion = shared.kane.zip(shared.trees.composite).and_then(|(kane, rec)| super::composite::reduce(model, shared.mech, kane, rec, v));
        let mut articulated = shared
            .kane
            .zip(shared.trees.frames)
            .zip(shared.trees.articulated)
            .and_then(|((kane, frames), aba)| super::articulated::reduce_on(frames, model, shared.mech, kane, aba, v));
        let kept: Vec<usize> = if shared.integrate_ignorable { (0..m).collect() } else { (0..m).filter(|j| !v.ignorable.contains(j)).collect() };
        if !shared.integrate_ignorable {
            if let Some((j, place)) = needed(model, v).into_iter().find_map(|(j, p)| p.map(|p| (j, p))) {
                let q = model.coordinates[j];
                return Err(model.error(
                    ErrorKind::IgnorableNeeded,
                    "emit.integrate_ignorable",
                    "integrate_ignorable",
                    format!("`{}` cannot leave the state: {place} depends on it", q.name()),
                    "set `integrate_ignorable: true` in `emit`".into(),
                ));
            }
            // Free of them (decided exactly): set to zero where they only appear formally.
            let zero: HashMap<Symbol, Expr> = v.ignorable.iter().map(|&j| (model.coordinates[j], Expr::zero())).collect();
            qdot = Expr::subs_all(&qdot, &zero);
            forcing = Expr::subs_all(&forcing, &zero);
            mass = Matrix { rows: mass.rows, cols: mass.cols, data: Expr::subs_all(&mass.data, &zero) };
            singular = Expr::subs_all(&singular, &zero);
            if let Some(r) = &mut recursion {
                for (_, e) in &mut r.definitions {
                    *e = e.subs(&zero);
                }
                r.mass = r.mass.map(|e| e.subs(&zero));
                r.forcing = Expr::subs_all(&r.forcing, &zero);
                r.qdot = Expr::subs_all(&r.qdot, &zero);
            }
            if let Some(a) = &mut articulated {
                for (_, e) in &mut a.definitions {
                    *e = e.subs(&zero);
                }
                a.accelerations = Expr::subs_all(&a.accelerations, &zero);
                a.pivots = Expr::subs_all(&a.pivots, &zero);
                a.qdot = Expr::subs_all(&a.qdot, &zero);
            }
        }
        Ok(Equations {
            kind: self.kind(),
            label: "the reduced Volterra equations (paper Eqs. 64-67)",
            kept,
            speeds: v.u.clone(),
            momenta: v.g.clone(),
            qdot,
            speeds_from_qdot: speeds_from_qdot(model, v),
            mass,
            forcing,
            post: None,
            singular,
            equations: v.u.len(),
            matrix_name: "mass matrix M_NI",
            stabilization: None,
            elimination: v.route,
            constraint_power: None,
            recursion,
            articulated,
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
        assert_eq!(d.equations("reduced_volterra").unwrap().equations, 5);
    }
}
