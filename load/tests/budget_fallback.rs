//! Exact Jacobians that need more expression nodes than the budget allows fall back to the
//! runtime's differences, with the warning that says so. Alone in its file: the node budget is
//! the whole process's.

use generator::symbolic::{DEFAULT_MAX_NODES, set_max_nodes};
use load::{Jacobians, Route};

/// Enough for the cart pendulum's four right-hand sides (they evaluate within 2000 nodes), not
/// for their exact Jacobians too (which need between 5000 and 10000).
const BUDGET: usize = 3000;

const WARNING: &str = "the exact Jacobians need more expression nodes than the budget allows";

#[test]
fn exact_jacobians_over_the_budget_fall_back_to_differences() {
    let model = load::model("cart_pendulum").unwrap();
    let exact = Jacobians::Exact { only: None, by_parameters: true };
    set_max_nodes(BUDGET);
    let plain = load::evaluate(&model, Jacobians::Differenced, Route::Jit, &mut |_| {}).unwrap();
    assert!(plain.warnings.is_empty(), "{:?}", plain.warnings);
    let fallen_back = load::evaluate(&model, exact, Route::Jit, &mut |_| {}).unwrap();
    assert!(fallen_back.warnings.iter().any(|w| w.contains(WARNING)), "{:?}", fallen_back.warnings);
    assert_eq!(fallen_back.model.formulations.len(), 4);
    assert!(fallen_back.model.formulations.iter().all(|f| !f.has_jacobian && !f.has_parameter_jacobian));
    // Under the default budget the same request gets every exact Jacobian, and no warning;
    // without `by_parameters`, those by the state only.
    set_max_nodes(DEFAULT_MAX_NODES);
    let full = load::evaluate(&model, exact, Route::Jit, &mut |_| {}).unwrap();
    assert!(full.warnings.is_empty(), "{:?}", full.warnings);
    assert!(full.model.formulations.iter().all(|f| f.has_jacobian && f.has_parameter_jacobian));
    let by_state = load::evaluate(&model, Jacobians::Exact { only: None, by_parameters: false }, Route::Jit, &mut |_| {}).unwrap();
    assert!(by_state.model.formulations.iter().all(|f| f.has_jacobian && !f.has_parameter_jacobian));
}
