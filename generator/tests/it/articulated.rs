//! Kane's and the reduced right-hand sides by the articulated-body recursion (no matrix, no
//! solve), where the generator chooses it: the 20-link pendulum on a cart, evaluated in-process.
//! Kane's rates equal Lagrange's, the reduced form's equal Kane's, `matrix` is still the mass
//! matrix, and a joint with nothing beyond it (a massless last bob) stops it with
//! `Failure::Singular` naming the pivot instead of NaN.

use generator::emit::{Options, Summary};
use generator::model::Model;
use generator::model::examples::n_link_pendulum_on_cart;
use seam::{Failure, Formulation};

fn state(n: usize, k: usize) -> Vec<f64> {
    (0..n).map(|i| 0.3 * ((i as f64) * 1.7 + k as f64).sin()).collect()
}

/// Kane's state and rates from `q, q'`, and Lagrange's.
fn both(f: &Formulation, q: &[f64], qdot: &[f64], p: &[f64], ignorable: usize) -> (Vec<f64>, Vec<f64>, Result<Vec<f64>, Failure>) {
    let (mut y, mut g) = (vec![0.0; f.states()], vec![0.0; ignorable]);
    f.initial_state(0.0, q, qdot, p, &mut y, &mut g).unwrap();
    let mut d = vec![0.0; y.len()];
    let r = f.rhs(0.0, &y, p, &g, &mut d).map(|()| d);
    (y, g, r)
}

/// The 20-link pendulum evaluated in-process, with the generator's summary of the same emission.
fn pendulum() -> (Model, seam::Model, Summary) {
    let model = n_link_pendulum_on_cart(20).build().unwrap();
    let (evaluated, summary) = generator::evaluate_reporting(&model, &Options::from_model(&model)).unwrap();
    (model, evaluated, summary)
}

/// The formulation `name` gives its rates by the articulated-body recursion.
fn assert_articulated(summary: &Summary, name: &str) {
    let how = &summary.solves.iter().find(|(n, _)| n == name).unwrap().1;
    assert!(how.starts_with("no solve: the articulated-body recursion"), "{name}: {how}");
}

#[test]
fn kanes_articulated_body_rates_are_lagranges_and_its_matrix_is_the_mass_matrix() {
    let (model, evaluated, summary) = pendulum();
    assert_articulated(&summary, "kane");
    let (kane_ops, lagrange_ops) = (summary.ops("kane::rhs").unwrap(), summary.ops("lagrange::rhs").unwrap());
    assert_eq!(kane_ops.solve.total(), 0);
    // Its body is already smaller than the solve alone: the matrix's bodies were not built, and
    // the summary compares with the solve it saves.
    let how = &summary.solves.iter().find(|(n, _)| n == "kane").unwrap().1;
    let solve_alone: usize = how.split("(the matrix's solve alone: ").nth(1).and_then(|r| r.strip_suffix(')')).expect(how).parse().unwrap();
    assert_eq!(solve_alone, generator::emit::spd_cost(model.m()).total(), "{how}");
    assert!(kane_ops.total() < solve_alone, "{how}");
    assert!(kane_ops.total() < lagrange_ops.total(), "{} against {}", kane_ops.total(), lagrange_ops.total());
    let form = |name: &str| evaluated.formulations.iter().find(|f| f.name() == name).unwrap();
    let (lagrange, kane) = (form("lagrange"), form("kane"));
    let (m, p, s) = (model.m(), &evaluated.default_params, evaluated.ignorable.len());
    let mut compared = 0;
    for k in 0..4 {
        let (q, qdot) = (state(m, k), state(m, k + 5));
        let (_, _, dl) = both(lagrange, &q, &qdot, p, s);
        let (mut y, g, dk) = both(kane, &q, &qdot, p, s);
        let (dl, dk) = (dl.unwrap(), dk.unwrap());
        // Kane's speeds are the rates in another order: u[i] = q'[order[i]].
        let order: Vec<usize> = y[m..].iter().map(|u| qdot.iter().position(|v| v == u).unwrap()).collect();
        y[m..].copy_from_slice(&dk[m..]);
        let (mut q_back, mut qddot) = (vec![0.0; m], vec![0.0; m]);
        kane.velocities(0.0, &y, p, &g, &mut q_back, &mut qddot).unwrap();
        for (i, (l, c)) in dl[m..].iter().zip(&qddot).enumerate() {
            assert!((l - c).abs() <= 1e-10 * l.abs().max(1.0), "state #{k} q''[{i}]: Lagrange {l:e}, Kane {c:e}");
            compared += usize::from(*l != 0.0);
        }
        // `matrix` is Kane's mass matrix: Lagrange's with rows and columns in the speeds' order.
        let (mut yl, mut gl) = (vec![0.0; lagrange.states()], vec![0.0; s]);
        lagrange.initial_state(0.0, &q, &qdot, p, &mut yl, &mut gl).unwrap();
        let (mut ml, mut mk) = (vec![0.0; m * m], vec![0.0; m * m]);
        lagrange.matrix(0.0, &yl, p, &gl, &mut ml).unwrap();
        kane.matrix(0.0, &y, p, &g, &mut mk).unwrap();
        for i in 0..m {
            for j in 0..m {
                let (want, got) = (ml[order[i] * m + order[j]], mk[i * m + j]);
                assert!((want - got).abs() <= 1e-12 * want.abs().max(1.0), "state #{k} M[{i}][{j}]: {got:e} against {want:e}");
            }
        }
    }
    assert!(compared > 60, "{compared} nonzero accelerations");
}

/// The reduced form's speeds are coordinates' rates (all but the cart's, which its momentum
/// replaces): at the same `q, q'` their rates are Lagrange's accelerations of those coordinates.
#[test]
fn the_reduced_articulated_body_rates_are_lagranges_accelerations() {
    let (model, evaluated, summary) = pendulum();
    assert_articulated(&summary, "reduced_volterra");
    let form = |name: &str| evaluated.formulations.iter().find(|f| f.name() == name).unwrap();
    let (lagrange, reduced) = (form("lagrange"), form("reduced_volterra"));
    let (m, p, s) = (model.m(), &evaluated.default_params, evaluated.ignorable.len());
    let mut compared = 0;
    for k in 0..4 {
        let (q, qdot) = (state(m, k), state(m, k + 3));
        let dl = both(lagrange, &q, &qdot, p, s).2.unwrap();
        let (y, _, dr) = both(reduced, &q, &qdot, p, s);
        let dr = dr.unwrap();
        let kept = reduced.states() - reduced.layout.speeds - usize::from(reduced.layout.work);
        for (i, u) in y[kept..kept + reduced.layout.speeds].iter().enumerate() {
            let j = qdot.iter().position(|v| v == u).expect("a speed is a coordinate's rate");
            let (want, got) = (dl[m + j], dr[kept + i]);
            assert!((want - got).abs() <= 1e-10 * want.abs().max(1.0), "state #{k} speed {i} (q{j}''): reduced {got:e}, Lagrange {want:e}");
            compared += usize::from(want != 0.0);
        }
    }
    assert!(compared > 60, "{compared} nonzero rates");
}

#[test]
fn a_massless_last_bob_stops_the_articulated_body_recursion_at_its_pivot() {
    let (model, evaluated, summary) = pendulum();
    assert_articulated(&summary, "kane");
    assert_articulated(&summary, "reduced_volterra");
    let last = evaluated.parameter_names.iter().position(|n| n == "m20").expect("the last bob's mass");
    let (m, s) = (model.m(), evaluated.ignorable.len());
    let (q, qdot) = (state(m, 1), state(m, 2));
    for name in ["kane", "reduced_volterra"] {
        let form = evaluated.formulations.iter().find(|f| f.name() == name).unwrap();
        let mut p = evaluated.default_params.clone();
        let (y, g, _) = both(form, &q, &qdot, &p, s);
        p[last] = 0.0;
        let mut d = vec![0.0; y.len()];
        match form.rhs(0.0, &y, &p, &g, &mut d) {
            Err(Failure::Singular { condition, value, .. }) => {
                assert!(condition.contains("pivot") && condition.contains("articulated-body"), "{name}: {condition}");
                assert!(value.abs() <= 1e-12, "{name}: {value}");
            }
            other => panic!("{name}: expected the pivot's singularity, got {other:?}"),
        }
    }
}
