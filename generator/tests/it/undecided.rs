//! What the derivation cannot decide exactly reaches the user: a coordinate whose place in the
//! equations only a floating-point guess could settle is kept on the safe side (not taken as
//! ignorable), and the generation summary, `inspect` and the in-process route say so.

use generator::model::from_source;

/// `tests/fixtures/kink.ron`: a potential `k (sqrt(x^2) - x)` whose dependence on x only a
/// floating-point guess could settle.
const KINK: &str = include_str!("../../../tests/fixtures/kink.ron");

const NOTE: &str = "whether the equations depend on `x` could not be decided exactly";

#[test]
fn an_undecided_dependence_keeps_the_coordinate_and_is_reported() {
    let model = from_source("kink.ron", KINK).unwrap();
    let derivation = generator::formulation::derive(&model, &generator::formulation::Request::all()).unwrap();
    // y is ignorable; x, which a float test would have called absent, is not.
    assert_eq!(derivation.ignorable, [1]);
    assert!(derivation.cuts.notes.iter().any(|n| n.starts_with(NOTE)), "{:?}", derivation.cuts);
    assert!(derivation.cuts.undecided.values().sum::<usize>() >= 1, "{:?}", derivation.cuts);

    let inspected = generator::inspect(&model, false).unwrap();
    let section = inspected.split("Budgets and undecided questions:").nth(1).expect("inspect lists the undecided questions");
    assert!(section.contains(NOTE), "{section}");

    let generated = generator::generate(&model, &generator::emit::Options::from_model(&model)).unwrap();
    // The automatic choice left x out for want of an answer: a warning the user can act on.
    let warned = "`x` is not taken as ignorable: whether the equations depend on it could not be decided exactly";
    assert!(generated.summary.warnings().iter().any(|w| w.starts_with(warned)), "{:?}", generated.summary.warnings());
    assert!(generated.summary.notes().iter().any(|w| w.starts_with(NOTE)), "{:?}", generated.summary.notes());
    assert!(generated.summary.to_string().contains(NOTE));
    let (_, summary) = generator::evaluate_reporting(&model, &generator::emit::Options::from_model(&model)).unwrap();
    assert_eq!(summary.warnings(), generated.summary.warnings());
}

/// A model everything of which is decided says nothing.
#[test]
fn a_decided_model_reports_no_cuts() {
    let model = generator::model::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/cart_pendulum.ron")).unwrap();
    let generated = generator::generate(&model, &generator::emit::Options::from_model(&model)).unwrap();
    assert_eq!(generated.summary.warnings(), Vec::<String>::new());
    assert!(!generator::inspect(&model, false).unwrap().contains("Budgets and undecided questions"));
}

/// The bicycle's Kane form: the simplifier's cuts are in the summary (the nodes over the term
/// limit apart from the products it keeps because they combine more than three angles), and the
/// solver's stopped normal forms too.
#[test]
fn the_bicycle_reports_what_its_budgets_cut() {
    let model = generator::model::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/bicycle.ron")).unwrap();
    let generated = generator::generate(&model, &generator::emit::Options::from_model(&model)).unwrap();
    let warnings = generated.summary.notes();
    assert!(generated.summary.warnings().is_empty(), "a built-in model loads without warnings: {:?}", generated.summary.warnings());
    assert!(
        warnings
            .iter()
            .any(|w| w.starts_with("simplifier: 573 nodes over the term limit, 1506 products combining more angles than one harmonic may, work limit reached")),
        "{warnings:?}"
    );
    assert!(warnings.iter().any(|w| w.contains("symbolic solve hit the solver's term or work limit")), "{warnings:?}");
}
