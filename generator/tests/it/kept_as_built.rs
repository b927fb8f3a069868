//! Past 8 coordinates the derivation leaves each combination of simplified per-body parts as
//! built (the inertia forces `h`, Lagrange's `f = Q - dV/dq - h`, the potential, the reduced
//! form's momentum equation) instead of expanding it: on the n-link pendulum on a cart, whose
//! links each have a mass symbol of their own, the expanded forms sum a term per link and mass
//! and passed the simplifier's term limit from n = 50 (73 nodes kept as built at 50 links, 127 at
//! 60). Now nothing is cut, and the work stays far below the limit.

use generator::formulation::{ignorable, mechanics, volterra};
use generator::model::examples::n_link_pendulum_on_cart;

#[test]
fn the_50_link_pendulum_derives_with_no_node_kept_as_built() {
    let model = n_link_pendulum_on_cart(50).build().unwrap();
    let mech = mechanics::derive(&model);
    let chosen = ignorable::choose(&model, &ignorable::analyze(&model, &mech)).unwrap();
    let kane = volterra::derive(&model, &mech, &[], &model.quasi_full).unwrap();
    let reduced = volterra::derive_reduced(&model, &mech, &chosen, &model.quasi_reduced, &kane).unwrap();
    assert_eq!((kane.l_ni.len(), reduced.l_ni.len()), (51, 50));
    let report = mech.tidy.report();
    assert_eq!(report.over_term_limit, 0, "{report:?}");
    assert!(!report.work_limit_reached, "{report:?}");
    // Lagrange's f, which Kane's L_NI renames, is left as built: simplifying the combination
    // again finds it a fixpoint or leaves it, never expands it past the limit.
    let f = mech.lagrange_force();
    assert_eq!(f.len(), 51);
    assert_eq!(mech.tidy.report().over_term_limit, 0);
}
