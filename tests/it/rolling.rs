//! The rolling-contact element against hand-written constraints: the upright disk of
//! `models/rolling_disk.ron` (written with `Rolling`) and the same disk with its no-slip
//! constraints by hand (`tests/fixtures/rolling_disk_hand.ron`) have the same constraints and
//! the same accelerations in every formulation; a disk placed by free coordinates gets the
//! height constraint, and one whose frames keep it on the ground does not.

use crate::common;
use common::{all_accelerations, load};
use generator::formulation::{Request, derive};
use generator::model::{Constraint, Model, from_source};
use generator::symbolic::Env;
use generator::symbolic::SplitMix;

fn hand() -> Model {
    from_source("rolling_disk_hand.ron", include_str!("../fixtures/rolling_disk_hand.ron")).unwrap()
}

/// A random state with admissible rates: the disk rolls along its heading.
fn state(model: &Model, rng: &mut SplitMix) -> Env {
    let mut env = Env::default();
    for (s, v) in &model.parameters {
        env.set(*s, *v);
    }
    env.set(model.t, 0.0);
    env.set(generator::symbolic::Symbol::new("pi"), std::f64::consts::PI);
    let r = model.parameters.iter().find(|(s, _)| s.name() == "R").unwrap().1;
    let (psi, dpsi, dphi) = (rng.uniform(-3.0, 3.0), rng.uniform(-2.0, 2.0), rng.uniform(-5.0, 5.0));
    let q = [rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0), psi, rng.uniform(-3.0, 3.0)];
    let qd = [r * psi.cos() * dphi, r * psi.sin() * dphi, dpsi, dphi];
    for j in 0..4 {
        env.set(model.coordinates[j], q[j]);
        env.set(model.velocities[j], qd[j]);
    }
    env
}

fn exprs(model: &Model) -> Vec<generator::symbolic::Expr> {
    model
        .constraints
        .iter()
        .map(|c| match c {
            Constraint::Velocity { expr, .. } | Constraint::Position { expr, .. } => *expr,
        })
        .collect()
}

#[test]
fn the_element_gives_the_hand_written_constraints_and_equations() {
    let (element, hand) = (load("rolling_disk"), hand());
    assert_eq!(element.constraints.len(), 2, "no height constraint: the frames keep the disk on the ground");
    let (de, dh) = (derive(&element, &Request::all()).unwrap(), derive(&hand, &Request::all()).unwrap());
    let mut rng = SplitMix(7);
    for _ in 0..20 {
        let env = state(&element, &mut rng);
        // Any rates, admissible or not: the constraint expressions agree term by term.
        let mut any = env.clone();
        for v in &element.velocities {
            any.set(*v, rng.uniform(-2.0, 2.0));
        }
        for (a, b) in exprs(&element).iter().zip(exprs(&hand)) {
            let (x, y) = (a.eval(&any).unwrap(), b.eval(&any).unwrap());
            assert!((x - y).abs() < 1e-12 * (1.0 + y.abs()), "constraint {x} against {y}");
        }
        for ((name, qa), (_, qb)) in all_accelerations(&de, &element, &env).iter().zip(all_accelerations(&dh, &hand, &env)) {
            for (a, b) in qa.iter().zip(&qb) {
                assert!((a - b).abs() < 1e-10 * (1.0 + b.abs()), "{name}: q'' {qa:?} against {qb:?}");
            }
        }
    }
}

/// A disk placed by free coordinates `(x, y, z)` and turned by heading, lean and spin: the
/// element adds `contact_height = z - R cos(lean)` (for a lean within a right angle).
#[test]
fn a_free_disk_gets_its_height_constraint() {
    let src = r#"Model(
        name: "free_disk",
        parameters: { "m": 1.0, "R": 0.4 },
        coordinates: ["x", "y", "z", "psi", "th", "phi"],
        frames: [
            Frame(name: "centre", parent: "world", translation: ["x", "y", "z"], rotation: [Z("psi"), X("th")]),
            Frame(name: "disk", parent: "centre", rotation: [Y("phi")]),
        ],
        bodies: [Body(name: "disk", frame: "disk", mass: "m", inertia: Diagonal(["m*R^2/4", "m*R^2/2", "m*R^2/4"]))],
        constraints: [Rolling(name: "contact", frame: "disk", radius: "R", axle: ["0", "1", "0"])],
        forces: [Gravity(vector: ["0", "0", "-9.81"])],
        quasi_velocities: QuasiVelocities(full: ["psi'", "th'", "phi'"], reduced: ["psi'", "th'", "phi'"]),
    )"#;
    let model = from_source("free_disk.ron", src).unwrap();
    let names: Vec<String> = model
        .constraints
        .iter()
        .map(|c| match c {
            Constraint::Velocity { name, .. } | Constraint::Position { name, .. } => name.clone(),
        })
        .collect();
    assert_eq!(names, ["contact_x", "contact_y", "contact_height"]);
    let Constraint::Position { expr, .. } = &model.constraints[2] else { panic!("height is holonomic") };
    let mut rng = SplitMix(11);
    for _ in 0..10 {
        let mut env = Env::default();
        env.set(model.parameters[1].0, 0.4);
        let q: Vec<f64> = (0..6).map(|_| rng.uniform(-1.2, 1.2)).collect();
        for (s, v) in model.coordinates.iter().zip(&q) {
            env.set(*s, *v);
        }
        let want = q[2] - 0.4 * q[4].cos();
        assert!((expr.eval(&env).unwrap() - want).abs() < 1e-12, "height at {q:?}");
    }
    // A bad wheel says where and what to do.
    let bad = src.replace(r#"axle: ["0", "1", "0"]"#, r#"axle: ["0", "2", "0"]"#);
    let e = from_source("free_disk.ron", &bad).unwrap_err();
    assert!(e.to_string().contains("axle has length 2"), "{e}");
}
