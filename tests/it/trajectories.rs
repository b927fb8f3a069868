//! The emitted formulations integrated by the runtime: they follow the independent reference
//! trajectories, agree with each other, and keep the invariants the paper claims.

use runtime::compare::{Options, Reference, compare, run, run_with};
use runtime::integrate::{Method, Settings};
use runtime::system::Drift;
use seam::FormulationKind;

const SCENES: [&str; 3] = ["cart_pendulum", "three_body", "satellite_boom"];
const METHODS: [&str; 4] = ["lagrange", "maggi", "kane", "reduced_volterra"];

/// `(times, rows)` of `tests/reference/ref_<scene>.csv`: t, q..., q'...
fn reference(scene: &str) -> (Vec<f64>, Vec<Vec<f64>>) {
    let path = format!("{}/tests/reference/ref_{scene}.csv", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut times = Vec::new();
    let mut rows = Vec::new();
    for line in text.lines().skip(1) {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        times.push(v[0]);
        rows.push(v[1..].to_vec());
    }
    (times, rows)
}

#[test]
fn every_formulation_follows_the_reference_trajectories_at_tight_tolerance() {
    for scene in SCENES {
        let model = generated::find(scene).unwrap();
        let (times, rows) = reference(scene);
        assert_eq!(times.len(), Reference::of(&model).unwrap().times().unwrap().len(), "{scene}: sample count");
        let m = model.coordinates.len();
        let (t0, t1, _) = model.run.unwrap();
        let settings = Settings { method: Method::Dop853, rtol: 1e-10, atol: 1e-10, h_max: 0.1 * (t1 - t0), ..Settings::default() };
        for method in METHODS {
            let r = run(&model, FormulationKind::from_name(method).unwrap(), &settings, 1).unwrap();
            let mut worst = (0.0f64, 0.0, 0);
            for (i, q) in r.invariants.coordinates.iter().enumerate() {
                for j in 0..m {
                    let d = (q[j] - rows[i][j]).abs();
                    if d > worst.0 {
                        worst = (d, times[i], j);
                    }
                }
            }
            assert!(worst.0 < 1e-6, "{scene} {method}: |q - q_ref| = {:e} at t = {} in {}", worst.0, worst.1, model.coordinates[worst.2]);
        }
    }
}

#[test]
fn the_four_formulations_agree_to_their_tolerance() {
    for scene in SCENES {
        let model = generated::find(scene).unwrap();
        let (t0, t1, _) = model.run.unwrap();
        let options = Options {
            settings: Settings { rtol: 1e-8, atol: 1e-8, ..Settings::paper(t1 - t0) },
            repeats: 1,
            formulations: vec![],
            drift: Drift::None,
            reference: None,
        };
        let runs = compare(&model, &options).unwrap();
        assert_eq!(runs.len(), 4);
        let base = &runs[3].invariants.coordinates;
        for r in &runs[..3] {
            let d = r.invariants.coordinates.iter().zip(base).flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs())).fold(0.0, f64::max);
            // Local tolerance 1e-8; over 50 s the global error grows by up to about 1e4 (scene 1 is
            // a lively double pendulum): 1e-3 is what the tolerance allows, and a wrong
            // formulation misses it by orders of magnitude.
            assert!(d < 1e-3, "{scene}: {} and reduced_volterra differ by {d:e}", r.record.method);
        }
    }
}

#[test]
fn at_the_papers_settings_the_reduced_method_keeps_constraint_and_momenta_to_round_off() {
    for scene in SCENES {
        let model = generated::find(scene).unwrap();
        let runs = compare(&model, &Options { repeats: 1, ..Options::paper(&model) }).unwrap();
        let get = |name: &str| &runs.iter().find(|r| r.record.method == name).unwrap().record;
        let (reduced, lagrange) = (get("reduced_volterra"), get("lagrange"));
        // Fewest states and equations.
        for r in &runs {
            assert!(reduced.states <= r.record.states && reduced.equations <= r.record.equations);
        }
        // Round-off: relative to the size of the momenta (scene 3's are about 4.5e3).
        assert!(reduced.momentum_error_rel < 1e-12, "{scene}: reduced momentum error {:e} (rel)", reduced.momentum_error_rel);
        assert_eq!(reduced.momenta.len(), model.ignorable.len());
        for g in &reduced.momenta {
            assert!(g.rel < 1e-12, "{scene}: momentum of {} drifts by {:e} (rel)", g.coordinate, g.rel);
        }
        assert!(reduced.constraint_error_norm < 1e-12, "{scene}: reduced constraint error {:e}", reduced.constraint_error_norm);
        assert!(
            reduced.energy_error_norm <= lagrange.energy_error_norm,
            "{scene}: reduced energy error {:e} above Lagrange's {:e}",
            reduced.energy_error_norm,
            lagrange.energy_error_norm
        );
        // The classical methods drift where the paper says they do.
        if scene == "cart_pendulum" {
            assert!(lagrange.constraint_error_norm > 1e-6, "Lagrange drifts off the wheel constraint");
        }
        assert!(lagrange.momentum_error_rel > 1e-9, "{scene}: Lagrange's momentum drifts");
    }
}

#[test]
fn the_work_integral_balances_the_energy_of_a_driven_system() {
    // Scene 3's boom is driven by F(t): mechanical energy changes, E = T + V - W does not.
    let model = generated::find("satellite_boom").unwrap();
    let (t0, t1, _) = model.run.unwrap();
    let settings = Settings { method: Method::Dop853, rtol: 1e-11, atol: 1e-11, h_max: 0.1 * (t1 - t0), ..Settings::default() };
    let r = run(&model, FormulationKind::ReducedVolterra, &settings, 1).unwrap();
    let form = model.formulation(seam::FormulationKind::ReducedVolterra).unwrap();
    assert!(form.has_work_state());
    let work = r.solution.states.iter().map(|y| y[form.states() - 1].abs()).fold(0.0, f64::max);
    let drift = r.invariants.energy_error.iter().map(|e| e.abs()).fold(0.0, f64::max);
    assert!(work > 1e3 * drift.max(1e-9), "work {work:e} must dwarf the balance error {drift:e}");
    assert!(drift < 1e-6 * r.invariants.energy0.abs(), "energy balance error {drift:e}");
}

#[test]
fn drift_control_keeps_the_classical_methods_nearer_the_constraint() {
    let model = generated::find("cart_pendulum").unwrap();
    let base = Options { repeats: 1, formulations: vec![FormulationKind::Lagrange, FormulationKind::Maggi], ..Options::paper(&model) };
    let plain = compare(&model, &base).unwrap();
    for drift in [Drift::Baumgarte { alpha: 10.0, beta: 10.0 }, Drift::Projection] {
        let runs = compare(&model, &Options { drift, ..base.clone() }).unwrap();
        for (with, without) in runs.iter().zip(&plain) {
            if with.record.method == without.record.method {
                continue; // Baumgarte does not apply to Maggi
            }
            assert!(
                with.record.constraint_error_norm < 0.2 * without.record.constraint_error_norm,
                "{}: {:e} against {:e} without",
                with.record.method,
                with.record.constraint_error_norm,
                without.record.constraint_error_norm
            );
        }
    }
    // At the end of every step the projected state is on the constraint: with outputs only at
    // step ends (RK4 stepping by the output interval) the residual is round-off.
    let holonomic = generated::find("cartesian_pendulum").unwrap();
    let (_, _, dt) = holonomic.run.unwrap();
    let settings = Settings { method: Method::Rk4 { h: dt }, ..Settings::default() };
    let reference = Reference::of(&holonomic).unwrap();
    let r = run_with(&holonomic, &reference, FormulationKind::Lagrange, &settings, 1, Drift::Projection).unwrap();
    assert!(r.record.position_constraint_error_norm < 1e-10, "position residual {:e}", r.record.position_constraint_error_norm);
    assert!(r.record.constraint_error_norm < 1e-10, "velocity residual {:e}", r.record.constraint_error_norm);
    // Kane's state holds every coordinate: its positions are projected (its quasi-velocities
    // describe admissible motions only).
    let kane = run_with(&holonomic, &reference, FormulationKind::Kane, &settings, 1, Drift::Projection).unwrap();
    assert!(kane.record.position_constraint_error_norm < 1e-10, "Kane's position residual {:e}", kane.record.position_constraint_error_norm);
    // Drift control is refused where it does not apply: a state without the ignorable
    // coordinates cannot be projected onto constraints in every coordinate.
    let dropped = generated::find("three_body_drop").unwrap();
    let e = run_with(&dropped, &Reference::of(&dropped).unwrap(), FormulationKind::ReducedVolterra, &settings, 1, Drift::Projection).unwrap_err();
    assert!(e.to_string().contains("states that hold every coordinate"), "{e}");
}

#[test]
fn a_singular_configuration_stops_the_run_with_time_and_reason() {
    // Scene 1 started on cos(theta1 - theta2) = -1, where [Y_NI; M'; a] is singular.
    let model = generated::find("cart_pendulum").unwrap();
    let q0 = [0.3, 0.3 + std::f64::consts::PI, 0.0];
    let qd0 = [0.2, 0.2, 0.1]; // l cos(pi) theta1' + l theta2' = 0
    let (sys, y0) = runtime::system::System::start(&model, FormulationKind::ReducedVolterra, model.default_params.clone(), &q0, &qd0).unwrap();
    let err = runtime::integrate::integrate(&mut |t, y, dy| sys.rhs(t, y, dy), &y0, &[0.0, 1.0], &Settings::default()).unwrap_err();
    assert_eq!(err.t, 0.0);
    assert!(
        matches!(&err.reason, runtime::integrate::Reason::Rhs(runtime::seam::Failure::Singular { t, condition, .. }) if *t == 0.0 && condition.contains("theta1")),
        "{err}"
    );
    assert_eq!(err.state, y0);
}

#[test]
fn the_same_typed_errors_come_through_every_path() {
    use runtime::seam::Failure;
    use runtime::system::{SetupError, System};
    let model = generated::find("cart_pendulum").unwrap();
    let (q0, qd0) = model.initial.clone().unwrap();
    let params = model.default_params.clone();
    let (q0, qd0) = (&q0[..], &qd0[..]);
    // An initial state off the wheel constraint.
    let off = [qd0[0], qd0[1] + 0.1, qd0[2]];
    for form in FormulationKind::ALL {
        match System::start(&model, form, params.clone(), q0, &off) {
            // At velocity level (the coordinates are on every constraint), and said so.
            Err(e @ SetupError::Violated { position: false, .. }) => {
                let SetupError::Violated { ref constraint, residual, .. } = e else { unreachable!() };
                assert!(constraint == "wheel" && (residual.abs() - 0.1).abs() < 1e-9, "{form}: {e}");
                assert!(e.to_string().contains("the initial rates violate the velocity constraint `wheel`"), "{e}");
            }
            other => panic!("{form}: {other:?}"),
        }
    }
    // Slices of the wrong length, named.
    assert!(matches!(
        System::start(&model, FormulationKind::Kane, vec![1.0; 2], q0, qd0),
        Err(SetupError::Initial(Failure::Dimension { argument: "params", expected: 6, got: 2 }))
    ));
    assert!(matches!(
        System::start(&model, FormulationKind::Kane, params.clone(), &q0[..2], qd0),
        Err(SetupError::Initial(Failure::Dimension { argument: "q", expected: 3, got: 2 }))
    ));
    let (sys, y0) = System::start(&model, FormulationKind::Kane, params.clone(), q0, qd0).unwrap();
    let mut dy = vec![0.0; y0.len()];
    assert_eq!(sys.rhs(0.0, &y0[1..], &mut dy), Err(Failure::Dimension { argument: "state", expected: y0.len(), got: y0.len() - 1 }));
    assert!(matches!(sys.rhs(0.0, &y0, &mut dy[1..]), Err(Failure::Dimension { argument: "dstate", .. })));
    // A singular configuration during a run, through the comparison: the run error keeps the
    // model's failure typed.
    let singular = runtime::seam::Model { initial: Some((vec![0.3, 3.441592653589793, 0.0], vec![0.2, 0.2, 0.1])), ..model };
    let settings = Settings::paper(1.0);
    match run(&singular, FormulationKind::ReducedVolterra, &settings, 1) {
        Err(runtime::compare::CompareError::Run { source, .. }) => {
            assert!(matches!(source.reason, runtime::integrate::Reason::Rhs(Failure::Singular { .. })), "{source}")
        }
        other => panic!("{:?}", other.map(|r| r.record)),
    }
}
