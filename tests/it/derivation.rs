//! Workspace-level checks of the derivation up to M, N, T0, Q, a, b and Definition 1.

use generator::formulation::{ignorable, mechanics};
use generator::model::Model;
use generator::symbolic::{Expr, Symbol};
use generator::symbolic::{Resolver, lower, parse};
use generator::symbolic::{SplitMix, zero_test};

const SCENES: [&str; 3] = ["cart_pendulum", "three_body", "satellite_boom"];
const OWN: [&str; 3] = ["cartesian_pendulum", "rolling_disk", "spring_cart"];

use crate::common;
use common::load;

struct Names;
impl Resolver for Names {
    fn name(&self, name: &str, primes: usize) -> Result<Expr, String> {
        Ok(Symbol::new(&format!("{name}{}", "'".repeat(primes))).expr())
    }
}

fn expr(s: &str) -> Expr {
    lower(&parse(s).unwrap(), &Names).unwrap()
}

#[test]
fn scene1_mass_matrix_is_the_papers() {
    let m = load("cart_pendulum");
    let mech = mechanics::derive(&m);
    let expected = [
        ((0, 0), "(m1/3 + m2)*l^2"),
        ((0, 1), "m2*l^2/2*cos(theta1 - theta2)"),
        ((0, 2), "(m1/2 + m2)*l*cos(theta1)"),
        ((1, 1), "m2*l^2/3"),
        ((1, 2), "m2*l/2*cos(theta2)"),
        ((2, 2), "M + m1 + m2"),
    ];
    for ((i, j), e) in expected {
        let d = mech.mass.get(i, j) - expr(e);
        assert!(zero_test(d).is_zero(), "M[{i}][{j}] = {}", mech.mass.get(i, j));
        // Symmetric by construction.
        assert_eq!(mech.mass.get(i, j), mech.mass.get(j, i));
    }
    // The printed forms are the simplified ones, not expanded products.
    assert_eq!(mech.mass.get(0, 1).to_string(), "l^2*m2*cos(theta1 - theta2)/2");
    assert_eq!(mech.mass.get(1, 1).to_string(), "l^2*m2/3");
}

#[test]
fn ignorable_counts_match_the_scenes() {
    for (name, s, ign) in [("cart_pendulum", 1, vec!["x"]), ("three_body", 3, vec!["X", "Y", "Z"]), ("satellite_boom", 3, vec!["X", "Y", "Z"])] {
        let m = load(name);
        let mech = mechanics::derive(&m);
        let reports = ignorable::analyze(&m, &mech);
        let chosen = ignorable::choose(&m, &reports).unwrap();
        assert_eq!(chosen.len(), s, "{name}");
        let names: Vec<String> = chosen.iter().map(|&j| m.coordinates[j].name()).collect();
        assert_eq!(names, ign, "{name}");
        // Automatic detection finds the same set on the scenes.
        let auto: Vec<usize> = reports.iter().filter(|r| r.is_ignorable()).map(|r| r.index).collect();
        assert_eq!(auto, chosen, "{name}");
        // The ignorable coordinates can leave the state: a, b, Q are free of them.
        for &j in &chosen {
            assert!(reports[j].appears_in.is_empty(), "{name}: {:?}", reports[j].appears_in);
        }
    }
}

#[test]
fn own_models_exercise_what_the_scenes_do_not() {
    let m = load("rolling_disk");
    let mech = mechanics::derive(&m);
    let reports = ignorable::analyze(&m, &mech);
    // psi is ignorable by Definition 1 but must stay in the state (a depends on it).
    assert!(reports[2].is_ignorable());
    assert!(!reports[2].appears_in.is_empty());
    assert!(matches!(reports[0].failure, Some(ignorable::Failure::InConstraint { .. })));
    // The holonomic constraint is differentiated: a = [2x, 2y].
    let m = load("cartesian_pendulum");
    let mech = mechanics::derive(&m);
    assert_eq!(mech.a.get(0, 0), expr("2*x"));
    assert_eq!(mech.holonomic.len(), 1);
    assert_eq!(mech.q_forces[0], expr("w"));
    // The spring makes x non-ignorable through V; the damper gives Q = -c x'.
    let m = load("spring_cart");
    let mech = mechanics::derive(&m);
    let reports = ignorable::analyze(&m, &mech);
    assert!(matches!(&reports[0].failure, Some(ignorable::Failure::InLagrangian { place, .. }) if place == "V"));
    let mut rng = SplitMix(11);
    let mut env = m.parameter_env();
    for (q, v) in m.coordinates.iter().zip(&m.velocities) {
        env.set(*q, rng.uniform(-0.5, 0.5));
        env.set(*v, rng.uniform(-1.0, 1.0));
    }
    let qx = mech.q_forces[0].eval(&env).unwrap();
    let expected = -env.get(Symbol::new("c")).unwrap() * env.get(m.velocities[0]).unwrap();
    assert!((qx - expected).abs() < 1e-12, "{qx} vs {expected}");
}

/// Random states: coordinates in [-1.2, 1.2] (away from the ZYX singularity), rates in [-2, 2].
fn random_env(m: &Model, rng: &mut SplitMix) -> generator::symbolic::Env {
    let mut env = m.parameter_env();
    for (q, v) in m.coordinates.iter().zip(&m.velocities) {
        env.set(*q, rng.uniform(-1.2, 1.2));
        env.set(*v, rng.uniform(-2.0, 2.0));
    }
    env.set(m.t, rng.uniform(0.0, 50.0));
    env
}

#[test]
fn mass_matrices_are_symmetric_positive_definite_and_rebuild_t() {
    for name in SCENES.iter().chain(OWN.iter()) {
        let m = load(name);
        let mech = mechanics::derive(&m);
        let t_rebuilt = mech.kinetic_from_matrices(&m.velocities);
        let mut rng = SplitMix(7);
        for _ in 0..20 {
            let env = random_env(&m, &mut rng);
            let n = mech.m;
            let mut a = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    a[i * n + j] = mech.mass.get(i, j).eval(&env).unwrap();
                }
            }
            for i in 0..n {
                for j in 0..n {
                    assert!((a[i * n + j] - a[j * n + i]).abs() < 1e-12 * (1.0 + a[i * n + j].abs()), "{name}: M not symmetric");
                }
            }
            // Cholesky succeeds iff positive definite.
            let mut l = vec![0.0; n * n];
            for j in 0..n {
                let mut d = a[j * n + j];
                for k in 0..j {
                    d -= l[j * n + k] * l[j * n + k];
                }
                assert!(d > 0.0, "{name}: M not positive definite (pivot {j}: {d})");
                l[j * n + j] = d.sqrt();
                for i in j + 1..n {
                    let mut s = a[i * n + j];
                    for k in 0..j {
                        s -= l[i * n + k] * l[j * n + k];
                    }
                    l[i * n + j] = s / l[j * n + j];
                }
            }
            // T from M, N, T0 equals T from the bodies.
            let t1 = mech.kinetic.eval(&env).unwrap();
            let t2 = t_rebuilt.eval(&env).unwrap();
            assert!((t1 - t2).abs() <= 1e-10 * (1.0 + t1.abs()), "{name}: T {t1} vs {t2}");
        }
    }
}

#[test]
fn scene1_energy_matches_the_reference_initial_value() {
    let m = load("cart_pendulum");
    let mech = mechanics::derive(&m);
    let (q0, qd0) = m.initial.clone().unwrap();
    let mut env = m.parameter_env();
    for i in 0..3 {
        env.set(m.coordinates[i], q0[i]);
        env.set(m.velocities[i], qd0[i]);
    }
    let e = mech.kinetic.eval(&env).unwrap() + mech.potential.eval(&env).unwrap();
    // tests/reference/README.md: E(0) = -14.86241191799228, G_x(0) = 2.0634351215568323.
    assert!((e - -14.86241191799228).abs() < 1e-12, "E(0) = {e}");
    let g = mech.kinetic.diff(m.velocities[2]).eval(&env).unwrap();
    assert!((g - 2.0634351215568323).abs() < 1e-12, "G_x(0) = {g}");
}

#[test]
fn every_model_inspects_in_text_and_latex() {
    for name in SCENES.iter().chain(OWN.iter()) {
        let m = load(name);
        let text = generator::inspect(&m, false).unwrap();
        assert!(text.contains("mass matrix M"), "{name}");
        let tex = generator::inspect(&m, true).unwrap();
        assert!(tex.contains("\\begin{aligned}") && tex.contains("M_{11}"), "{name}");
    }
}

#[test]
fn inspect_and_the_drop_option_agree_on_every_model() {
    use generator::emit::{Formulation, Options};
    use generator::generate;
    for name in SCENES.iter().chain(OWN.iter()).chain(["pendulum_on_cart_5"].iter()) {
        let m = load(name);
        let text = generator::inspect(&m, false).unwrap();
        let says_can = text.contains("it can leave the integrated state");
        let says_cannot = text.contains("it must stay in the integrated state");
        let options = Options { integrate_ignorable: false, formulations: vec![Formulation::ReducedVolterra], ..Options::from_model(&m) };
        let dropped = generate(&m, &options);
        let s = generator::formulation::derive(&m, &generator::formulation::Request::all()).unwrap().ignorable.len();
        if s == 0 {
            // Nothing to leave out: no verdict, and dropping is a no-op.
            assert!(!says_can && !says_cannot && dropped.is_ok(), "{name}");
            continue;
        }
        assert!(says_can || says_cannot, "{name}: no verdict in\n{text}");
        assert_eq!(dropped.is_ok(), says_can && !says_cannot, "{name}: inspect says can {says_can}, cannot {says_cannot}; generation {:?}", dropped.err());
    }
}
