//! The emitted modules (committed in `generated/`) against Lagrange's equations, against each
//! other, and against the invariants they must keep, at random states consistent with the
//! constraints.

use generated::{Failure, Model};
use generator::formulation::{ignorable, mechanics, volterra};
use generator::model::Model as ModelDef;
use generator::symbolic::Expr;
use generator::symbolic::SplitMix;

const MODELS: [&str; 8] =
    ["cart_pendulum", "three_body", "satellite_boom", "cartesian_pendulum", "rolling_disk", "spring_cart", "pendulum_on_cart_5", "stiff_pendulum"];

use crate::common;
use common::{accelerations_from as accelerations, load};

fn emitted(module: &str) -> Model {
    generated::find(module).unwrap_or_else(|| panic!("no emitted module {module}"))
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * (1.0 + a.abs().max(b.abs()))
}

/// One random consistent state: `(t, q, q')`, `q` moved onto the holonomic constraints by
/// Newton steps, `q'` from random Kane quasi-velocities.
fn random_state(model: &ModelDef, holonomic: &[Expr], kane: &volterra::Volterra, rng: &mut SplitMix) -> (f64, Vec<f64>, Vec<f64>) {
    let mut env = model.parameter_env();
    let t = rng.uniform(0.0, 20.0);
    env.set(model.t, t);
    let mut q: Vec<f64> = model.coordinates.iter().map(|_| rng.uniform(-1.0, 1.0)).collect();
    for _ in 0..60 {
        for h in holonomic {
            for (s, x) in model.coordinates.iter().zip(&q) {
                env.set(*s, *x);
            }
            let value = h.eval(&env).unwrap();
            let grad: Vec<f64> = model.coordinates.iter().map(|c| h.diff(*c).eval(&env).unwrap()).collect();
            let norm2: f64 = grad.iter().map(|g| g * g).sum();
            for (x, g) in q.iter_mut().zip(&grad) {
                *x -= value * g / norm2;
            }
        }
    }
    for (s, x) in model.coordinates.iter().zip(&q) {
        env.set(*s, *x);
    }
    for h in holonomic {
        assert!(h.eval(&env).unwrap().abs() < 1e-13, "could not place q on {h}");
    }
    for u in &kane.u {
        env.set(*u, rng.uniform(-1.5, 1.5));
    }
    let qd = kane.qdot.iter().map(|e| e.eval(&env).unwrap()).collect();
    (t, q, qd)
}

#[test]
fn emitted_reduced_volterra_satisfies_lagrange_agrees_with_kane_and_keeps_momenta() {
    for name in MODELS {
        let def = load(name);
        let mech = mechanics::derive(&def);
        let chosen = ignorable::choose(&def, &ignorable::analyze(&def, &mech)).unwrap();
        let kane = volterra::derive(&def, &mech, &[], &def.quasi_full).unwrap();
        let reduced = volterra::derive(&def, &mech, &chosen, &def.quasi_reduced).unwrap();
        let lagrange: Vec<(Expr, Expr)> = (0..mech.m)
            .map(|j| {
                let p = mech.kinetic.diff(def.velocities[j]);
                let full = def.velocity_chain().dt(p) - mech.kinetic.diff(def.coordinates[j]) + mech.potential.diff(def.coordinates[j]) - mech.q_forces[j];
                let inertia = Expr::sum((0..mech.m).map(|k| mech.mass.get(j, k) * def.accelerations[k].expr()));
                (full, inertia)
            })
            .collect();
        let e = emitted(name);
        let params = e.default_params.to_vec();
        let (red, kf) = (e.formulation(seam::FormulationKind::ReducedVolterra).unwrap(), e.formulation(seam::FormulationKind::Kane).unwrap());
        let (m, s) = (mech.m, chosen.len());
        let w = usize::from(red.has_work_state());
        // The paper's Table 1: states 2m, 2m, m + p, m + p - s (+1 for the work integral);
        // equations m, m, p, p - s.
        let counts: Vec<(usize, usize)> = seam::FormulationKind::ALL.iter().map(|f| e.formulation(*f).map(|f| (f.states(), f.equations)).unwrap()).collect();
        assert_eq!(counts, vec![(2 * m + w, m), (2 * m + w, m), (m + mech.p + w, mech.p), (m + mech.p - s + w, mech.p - s)], "{name}");
        let mut rng = SplitMix(7);
        for trial in 0..5 {
            let holonomic: Vec<Expr> = mech.holonomic.iter().map(|(_, h)| *h).collect();
            let (t, q, qd) = random_state(&def, &holonomic, &kane, &mut rng);
            // Reduced: initial state, right-hand side, q''.
            let mut state = vec![0.0; red.states()];
            let mut g = vec![0.0; s];
            red.initial_state(t, &q, &qd, &params, &mut state, &mut g).unwrap();
            let mut ds = vec![0.0; red.states()];
            red.rhs(t, &state, &params, &g, &mut ds).unwrap();
            for j in 0..m {
                assert!(close(ds[j], qd[j], 1e-11), "{name} #{trial}: q'[{j}] {} vs {}", ds[j], qd[j]);
            }
            let mut env = def.parameter_env();
            env.set(def.t, t);
            for (sym, x) in def.coordinates.iter().zip(&q).chain(def.velocities.iter().zip(&qd)) {
                env.set(*sym, *x);
            }
            for (sym, x) in reduced.u.iter().zip(&state[m..]).chain(reduced.g.iter().zip(&g)) {
                env.set(*sym, *x);
            }
            let qdd = accelerations(&reduced, &env, &def, &ds[m..]);
            // Lagrange's equations with multipliers, projected on the admissible motions.
            for (a, x) in def.accelerations.iter().zip(&qdd) {
                env.set(*a, *x);
            }
            let mut res = vec![0.0; m];
            let mut scale = 1.0;
            for j in 0..m {
                res[j] = lagrange[j].0.eval(&env).unwrap();
                let inertia = lagrange[j].1.eval(&env).unwrap();
                scale += inertia.abs() + (res[j] - inertia).abs();
            }
            for k in 0..kane.u.len() {
                let proj: f64 = (0..m).map(|j| kane.w.get(j, k).eval(&env).unwrap() * res[j]).sum();
                assert!(proj.abs() < 1e-9 * scale, "{name} #{trial}: projected Lagrange residual {proj:e} (scale {scale:e})");
            }
            // Kane: same q''.
            let mut kstate = vec![0.0; kf.states()];
            let mut kg = vec![0.0; s];
            kf.initial_state(t, &q, &qd, &params, &mut kstate, &mut kg).unwrap();
            let mut kds = vec![0.0; kf.states()];
            kf.rhs(t, &kstate, &params, &kg, &mut kds).unwrap();
            for (sym, x) in kane.u.iter().zip(&kstate[m..]) {
                env.set(*sym, *x);
            }
            let kqdd = accelerations(&kane, &env, &def, &kds[m..]);
            for j in 0..m {
                assert!(close(qdd[j], kqdd[j], 1e-8), "{name} #{trial}: q''[{j}] reduced {} vs Kane {}", qdd[j], kqdd[j]);
            }
            // Lagrange and Maggi give q'' directly: state [q; q'].
            for form in ["lagrange", "maggi"] {
                let ds = rhs_at(&e, form, t, &q, &qd).unwrap();
                for j in 0..m {
                    assert!(close(ds[j], qd[j], 1e-14), "{name} {form}: q'[{j}]");
                    assert!(close(ds[m + j], qdd[j], 1e-8), "{name} #{trial}: q''[{j}] {form} {} vs reduced {}", ds[m + j], qdd[j]);
                }
            }
            // The work integral's rate is Q . q' in every formulation.
            if red.has_work_state() {
                let mut power = [0.0];
                e.work_rate(t, &q, &qd, &params, &mut power).unwrap();
                let last = red.states() - 1;
                assert!(close(ds[last], power[0], 1e-12), "{name}: W' {} vs Q.q' {}", ds[last], power[0]);
            }
            // The momenta of the reduced state are G_I; the constraints hold; energy matches.
            let (mut qq, mut qqd) = (vec![0.0; m], vec![0.0; m]);
            red.velocities(t, &state, &params, &g, &mut qq, &mut qqd).unwrap();
            let mut mom = vec![0.0; s];
            e.momenta(t, &qq, &qqd, &params, &mut mom).unwrap();
            for k in 0..s {
                assert!(close(mom[k], g[k], 1e-12), "{name} #{trial}: momentum {k} {} vs G {}", mom[k], g[k]);
            }
            let mut cres = vec![0.0; e.constraints.len()];
            e.constraint_residuals(t, &qq, &qqd, &params, &mut cres).unwrap();
            assert!(cres.iter().all(|r| r.abs() < 1e-12), "{name} #{trial}: constraint residuals {cres:?}");
            let mut energy = [0.0];
            e.energy(t, &q, &qd, &params, &mut energy).unwrap();
            let want = (mech.kinetic + mech.potential).eval(&env).unwrap();
            assert!(close(energy[0], want, 1e-12), "{name}: energy {} vs {want}", energy[0]);
        }
    }
}

/// Evaluates a formulation's right-hand side from `q, q'`.
fn rhs_at(e: &Model, form: &str, t: f64, q: &[f64], qd: &[f64]) -> Result<Vec<f64>, Failure> {
    let f = e.formulation(seam::FormulationKind::from_name(form).unwrap()).unwrap();
    let params = e.default_params.to_vec();
    let mut state = vec![0.0; f.states()];
    let mut g = vec![0.0; e.ignorable.len()];
    f.initial_state(t, q, qd, &params, &mut state, &mut g)?;
    let mut ds = vec![0.0; f.states()];
    f.rhs(t, &state, &params, &g, &mut ds)?;
    Ok(ds)
}

#[test]
fn variants_compute_the_same_right_hand_sides() {
    let full = emitted("three_body");
    let (q, qd) = full.initial.clone().unwrap();
    let (q, qd) = (&q[..], &qd[..]);
    for form in ["lagrange", "maggi", "kane", "reduced_volterra"] {
        let a = rhs_at(&full, form, 0.0, q, qd).unwrap();
        let b = rhs_at(&emitted("three_body_split"), form, 0.0, q, qd).unwrap();
        for (x, y) in a.iter().zip(&b) {
            assert!(close(*x, *y, 1e-13), "split {form}: {x} vs {y}");
        }
    }
    // Without the ignorable coordinates X, Y, Z (indices 5..8): the other entries agree.
    let drop = emitted("three_body_drop");
    assert_eq!(drop.formulation(seam::FormulationKind::ReducedVolterra).unwrap().layout.coordinates, [0, 1, 2, 3, 4]);
    let a = rhs_at(&full, "reduced_volterra", 0.0, q, qd).unwrap();
    let b = rhs_at(&drop, "reduced_volterra", 0.0, q, qd).unwrap();
    let kept: Vec<f64> = a[..5].iter().chain(&a[8..]).copied().collect();
    assert_eq!(kept.len(), b.len());
    for (x, y) in kept.iter().zip(&b) {
        assert!(close(*x, *y, 1e-13), "drop: {x} vs {y}");
    }
    // Baked parameters: the same numbers, and no runtime parameters.
    let (runtime, baked) = (emitted("cart_pendulum"), emitted("cart_pendulum_baked"));
    assert!(baked.parameter_names.is_empty() && !runtime.parameter_names.is_empty());
    let (q, qd) = runtime.initial.clone().unwrap();
    let (q, qd) = (&q[..], &qd[..]);
    for form in ["lagrange", "maggi", "kane", "reduced_volterra"] {
        let a = rhs_at(&runtime, form, 0.0, q, qd).unwrap();
        let b = rhs_at(&baked, form, 0.0, q, qd).unwrap();
        // With tau baked to 0 the motor does no work: no work state in the baked module.
        for (x, y) in a.iter().zip(&b) {
            assert!(close(*x, *y, 1e-12), "baked {form}: {x} vs {y}");
        }
    }
}

#[test]
fn runtime_parameters_change_the_motion() {
    let e = emitted("cart_pendulum");
    let f = e.formulation(seam::FormulationKind::ReducedVolterra).unwrap();
    let (q, qd) = e.initial.clone().unwrap();
    let (q, qd) = (&q[..], &qd[..]);
    let mut params = e.default_params.to_vec();
    let g_index = e.parameter_index("g").unwrap();
    let mut state = vec![0.0; f.states()];
    let mut g = vec![0.0; 1];
    let mut out = [vec![0.0; f.states()], vec![0.0; f.states()]];
    for (i, gravity) in [9.81, 1.62].into_iter().enumerate() {
        params[g_index] = gravity;
        f.initial_state(0.0, q, qd, &params, &mut state, &mut g).unwrap();
        f.rhs(0.0, &state, &params, &g, &mut out[i]).unwrap();
    }
    assert!((out[0][3] - out[1][3]).abs() > 1e-3, "u' must depend on g: {:?}", out);
}

#[test]
fn bad_states_are_reported_not_computed() {
    let e = emitted("cart_pendulum");
    let (q, qd) = e.initial.clone().unwrap();
    let (q, qd) = (&q[..], &qd[..]);
    // Velocities that violate the wheel constraint: rejected with the residual.
    let mut bad = qd.to_vec();
    bad[1] += 0.1;
    for form in ["lagrange", "maggi", "kane", "reduced_volterra"] {
        match rhs_at(&e, form, 0.0, q, &bad) {
            Err(Failure::ConstraintViolated { constraint, residual, .. }) => {
                assert_eq!(constraint, "wheel");
                assert!((residual.abs() - 0.1).abs() < 1e-9, "residual {residual}");
            }
            other => panic!("{form}: expected a constraint violation, got {other:?}"),
        }
    }
    // Positions that violate a holonomic constraint.
    let p = emitted("cartesian_pendulum");
    let (q, qd) = p.initial.clone().unwrap();
    let (q, qd) = (&q[..], &qd[..]);
    let mut moved = q.to_vec();
    moved[0] += 0.01;
    assert!(matches!(rhs_at(&p, "reduced_volterra", 0.0, &moved, qd), Err(Failure::ConstraintViolated { .. })));
    // Scene 1 at cos(theta1 - theta2) = -1: singular, reported with the condition.
    let f = e.formulation(seam::FormulationKind::ReducedVolterra).unwrap();
    let params = e.default_params.to_vec();
    let state = [0.3, 0.3 + std::f64::consts::PI, 0.0, 0.5, 0.0];
    let mut ds = [0.0; 5];
    match f.rhs(1.5, &state, &params, &[0.2], &mut ds) {
        Err(Failure::Singular { t, condition, .. }) => {
            assert_eq!(t, 1.5);
            assert!(condition.contains("theta1") && condition.contains("theta2"), "{condition}");
        }
        other => panic!("expected a singular configuration, got {other:?}"),
    }
    // A NaN in the state never comes back as a number.
    let state = [0.3, f64::NAN, 0.0, 0.5, 0.0];
    assert!(f.rhs(0.0, &state, &params, &[0.2], &mut ds).is_err());
    // Slices of the wrong length.
    assert!(matches!(f.rhs(0.0, &[0.0; 4], &params, &[0.2], &mut ds), Err(Failure::Dimension { argument: "state", .. })));
}

/// The reduced method solves fewer equations than Kane's on both spatial scenes. Kane's solve
/// skips its matrix's structural zeros (scene 2: 8 x 8 with 16 zeros), so on scene 2 the whole
/// right-hand side of each does about the same work (the Schur complement that the reduced form
/// does symbolically, Kane's sparse LDL^T does numerically); on scene 3 the reduced one does less.
#[test]
fn reduced_right_hand_side_solves_less_than_kane_and_does_less_work_on_scene_3() {
    for (scene, whole_less) in [("three_body", false), ("satellite_boom", true)] {
        let def = load(scene);
        let out = generator::generate(&def, &generator::emit::Options::from_model(&def)).unwrap();
        let (reduced, kane) = (out.summary.ops("reduced_volterra::rhs").unwrap(), out.summary.ops("kane::rhs").unwrap());
        assert!(reduced.solve.total() < kane.solve.total(), "{scene}: solve {} against Kane's {}", reduced.solve.total(), kane.solve.total());
        if whole_less {
            let (r, k) = (reduced.ops.total() + reduced.solve.total(), kane.ops.total() + kane.solve.total());
            assert!(r < k, "{scene}: reduced {r} ops, Kane {k} ops");
        }
    }
}

#[test]
fn inspect_and_the_generator_count_the_same_states_and_equations_and_solve_alike() {
    for name in MODELS {
        let def = load(name);
        let text = generator::inspect(&def, false).unwrap();
        let out = generator::generate(&def, &generator::emit::Options::from_model(&def)).unwrap();
        for (form, states, eqs) in &out.summary.formulations {
            let line = format!("  {form:<17} {states:>3} states, {eqs:>3} equations");
            assert!(text.contains(&line), "{name}: `{line}` missing from inspect");
        }
        // The same solve plan in both, a sparse one where the matrix has structural zeros.
        assert_eq!(out.summary.solves.len(), out.summary.formulations.len(), "{name}");
        for (form, how) in &out.summary.solves {
            assert!(
                text.lines().any(|l| l.starts_with(&format!("  {form:<17} ")) && l.ends_with(&format!(": {how}"))),
                "{name}: `{form}: {how}` missing from inspect"
            );
        }
        if name == "satellite_boom" {
            assert!(out.summary.solves.iter().all(|(_, how)| how.contains("rows eliminated in the order")), "{:?}", out.summary.solves);
        }
    }
}
