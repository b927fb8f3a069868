//! Ignorable coordinates (paper Definition 1): `q_j` is ignorable when the Lagrangian
//! `L = T - V` does not depend on it, its column of the constraint Jacobian `a` is zero, and
//! its generalized force `Q_j` is zero. Then `G_j = dT/dq_j'` is conserved (Eqs. 20-26).
//! Separately: whether `a`, `b` and `Q` are free of it too, which is what dropping it from the
//! integrated state needs.
//!
//! ```
//! let model = generator::model::load("../models/cart_pendulum.ron").unwrap();
//! let mech = generator::formulation::mechanics::derive(&model);
//! let report = generator::formulation::ignorable::analyze(&model, &mech);
//! assert!(report[2].is_ignorable() && !report[0].is_ignorable());
//! ```

use super::mechanics::Quantities;
use crate::model::{ErrorKind, Model, ModelError};
use crate::symbolic::zero::{ZeroVerdict, zero_test};
use crate::symbolic::{Expr, Symbol};

/// Which condition of Definition 1 fails, and on what.
#[derive(Clone, Debug)]
pub enum Failure {
    /// The Lagrangian depends on the coordinate, through `place` (`M[1][2]`, `N[0]`, `T0`,
    /// `V`), whose derivative is `derivative`.
    InLagrangian { place: String, derivative: Expr, undecided: bool },
    /// Column of `a` is not zero in constraint `constraint`.
    InConstraint { constraint: String, entry: Expr },
    /// The generalized force `Q_j` is not zero.
    Forced { force: Expr },
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Failure::InLagrangian { place, derivative, undecided: false } => write!(f, "L = T - V depends on it through {place} (derivative {derivative})"),
            Failure::InLagrangian { place, derivative, undecided: true } => {
                write!(f, "L = T - V may depend on it through {place} (the exact test could not decide whether {derivative} vanishes)")
            }
            Failure::InConstraint { constraint, entry } => write!(f, "its column of a is not zero in constraint `{constraint}` (entry {entry})"),
            Failure::Forced { force } => write!(f, "its generalized force is not zero (Q = {force})"),
        }
    }
}

/// The verdict for one coordinate.
#[derive(Clone, Debug)]
pub struct CoordinateReport {
    pub index: usize,
    pub name: String,
    /// `None` when Definition 1 holds.
    pub failure: Option<Failure>,
    /// Where `a`, `b` or `Q` depend on the coordinate (empty when it could leave the state).
    pub appears_in: Vec<String>,
}

impl CoordinateReport {
    /// Definition 1 holds.
    pub fn is_ignorable(&self) -> bool {
        self.failure.is_none()
    }
}

/// `Some(de/dq)` when `e` depends on `q` (decided by the exact zero test). A dependence the test
/// cannot decide counts as one (the safe side: the coordinate is not taken as ignorable), and
/// is reported.
pub fn depends(e: Expr, q: Symbol) -> Option<Expr> {
    dependence(e, q).map(|(d, _)| d)
}

/// [`depends`], and whether the dependence is only undecided.
fn dependence(e: Expr, q: Symbol) -> Option<(Expr, bool)> {
    if !e.contains(q) {
        return None;
    }
    let d = e.diff(q);
    match zero_test(d) {
        ZeroVerdict::Zero { .. } => None,
        ZeroVerdict::NonZero { .. } => Some((d, false)),
        ZeroVerdict::Undecided { reason } => {
            crate::symbolic::report::record(|c| c.note(undecided_note(q, reason)));
            Some((d, true))
        }
    }
}

/// What is said of a dependence on `q` the exact test could not decide.
fn undecided_note(q: Symbol, reason: &str) -> String {
    format!("whether the equations depend on `{}` could not be decided exactly ({reason}): taken as depending on it", q.name())
}

/// Where `L = T - V` can depend on a coordinate, with the place each is reported as: the mass
/// matrix's upper triangle by rows (`M[r][c]`, the first `m (m + 1) / 2`), then `N`, `T0`, `V`.
fn lagrangian_parts(mech: &Quantities) -> Vec<(String, Expr)> {
    let m = mech.m;
    let mass = (0..m).flat_map(|r| (r..m).map(move |c| (r, c))).map(|(r, c)| (format!("M[{}][{}]", r + 1, c + 1), mech.mass.get(r, c)));
    let rest = (0..m).map(|k| (format!("N[{}]", k + 1), mech.n[k])).chain([("T0".to_string(), mech.t0), ("V".to_string(), mech.potential)]);
    mass.chain(rest).collect()
}

/// Where `L` depends on `q`, or None. A mass-matrix entry proven by the exact zero test to
/// depend on `q` decides it at once, when every entry before it is proven independent: `L`
/// depends on `q` then (an entry is the coefficient of its own product of rates in `T`), and
/// the test on the whole of `L`, many times larger, is not needed. Otherwise one test on `L`,
/// and only when it fails, the place it fails at (the mass entries proven independent are not
/// tested again; after an undecided one, every place is, as [`depends`] reports).
fn in_lagrangian(mech: &Quantities, parts: &[(String, Expr)], q: Symbol) -> Option<Failure> {
    let mass_entries = mech.m * (mech.m + 1) / 2;
    let mut from = mass_entries;
    for (place, e) in &parts[..mass_entries] {
        if !e.contains(q) {
            continue;
        }
        let d = e.diff(q);
        match zero_test(d) {
            ZeroVerdict::Zero { .. } => {}
            ZeroVerdict::NonZero { .. } => return Some(Failure::InLagrangian { place: place.clone(), derivative: d, undecided: false }),
            ZeroVerdict::Undecided { .. } => {
                from = 0;
                break;
            }
        }
    }
    dependence(mech.kinetic - mech.potential, q)?;
    parts[from..].iter().find_map(|(place, e)| dependence(*e, q).map(|(d, undecided)| Failure::InLagrangian { place: place.clone(), derivative: d, undecided }))
}

/// Checks Definition 1 for every coordinate.
pub fn analyze(model: &Model, mech: &Quantities) -> Vec<CoordinateReport> {
    let m = mech.m;
    let parts = lagrangian_parts(mech);
    model
        .coordinates
        .iter()
        .enumerate()
        .map(|(j, q)| {
            let mut failure = in_lagrangian(mech, &parts, *q);
            if failure.is_none() {
                for i in 0..mech.r {
                    let entry = mech.a.get(i, j);
                    if !zero_test(entry).is_zero() {
                        failure = Some(Failure::InConstraint { constraint: mech.constraint_names[i].clone(), entry });
                        break;
                    }
                }
            }
            if failure.is_none() && !zero_test(mech.q_forces[j]).is_zero() {
                failure = Some(Failure::Forced { force: mech.q_forces[j] });
            }
            let mut appears_in = Vec::new();
            for i in 0..mech.r {
                for k in 0..m {
                    if depends(mech.a.get(i, k), *q).is_some() {
                        appears_in.push(format!("a[{}][{}]", i + 1, k + 1));
                    }
                }
                if depends(mech.b[i], *q).is_some() {
                    appears_in.push(format!("b[{}]", i + 1));
                }
            }
            for k in 0..m {
                if depends(mech.q_forces[k], *q).is_some() {
                    appears_in.push(format!("Q[{}]", k + 1));
                }
            }
            CoordinateReport { index: j, name: q.name(), failure, appears_in }
        })
        .collect()
}

/// The ignorable set the reduced method uses: the declared one (each verified), or all
/// coordinates that qualify.
pub fn choose(model: &Model, reports: &[CoordinateReport]) -> Result<Vec<usize>, ModelError> {
    match &model.declared_ignorable {
        None => {
            // Where only an undecided question kept a coordinate out, the user should hear it:
            // the reduced method then has fewer equations eliminated than it might.
            for r in reports {
                if let Some(Failure::InLagrangian { undecided: true, .. }) = &r.failure {
                    let name = &r.name;
                    crate::symbolic::report::record(|c| {
                        c.warn(format!(
                            "`{name}` is not taken as ignorable: whether the equations depend on it could not be decided exactly (declare it under `ignorable` if you know it is)"
                        ))
                    });
                }
            }
            Ok(reports.iter().filter(|r| r.is_ignorable()).map(|r| r.index).collect())
        }
        Some(list) => {
            for &j in list {
                if let Some(f) = &reports[j].failure {
                    return Err(model.error(
                        ErrorKind::NotIgnorable,
                        "ignorable",
                        &format!("\"{}\"", reports[j].name),
                        format!("`{}` is declared ignorable but is not (Definition 1): {f}", reports[j].name),
                        "remove it from `ignorable`, or use `ignorable: Auto` to see which coordinates qualify".into(),
                    ));
                }
            }
            let mut l = list.clone();
            l.sort();
            Ok(l)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The expression the reduced `L_NI` of a free body held: it contains `a` but is `G u3`.
    #[test]
    fn formal_dependence_is_not_dependence() {
        let (a, g, u1, u3) = (Expr::sym("ia"), Expr::sym("iG"), Expr::sym("iu1"), Expr::sym("iu3"));
        let e = g * (a.cos() * (u1 * a.sin() + u3 * a.cos()) - a.sin() * (u1 * a.cos() - u3 * a.sin()));
        let q = a.as_sym().unwrap();
        assert!(e.contains(q));
        assert!(depends(e, q).is_none());
        assert!(depends(e + u1 * a.sin(), q).is_some());
    }
}
