//! The reduced Volterra equations against Lagrange's equations and the Kane form, at random
//! states consistent with the constraints.

use generator::formulation::{ignorable, mechanics, volterra};
use generator::model::Model;
use generator::symbolic::Env;
use generator::symbolic::Expr;
use generator::symbolic::SplitMix;

const MODELS: [&str; 8] =
    ["cart_pendulum", "three_body", "satellite_boom", "cartesian_pendulum", "rolling_disk", "spring_cart", "pendulum_on_cart_5", "stiff_pendulum"];

use crate::common;
use common::{accelerations_from, lin_solve, load};

/// q'' implied by a Volterra form at the state in `env` (q, u, G, t set): returns (q', q'').
fn accelerations(v: &volterra::Volterra, env: &Env, model: &Model) -> (Vec<f64>, Vec<f64>) {
    let n = v.u.len();
    let mass: Vec<Vec<f64>> = (0..n).map(|i| (0..n).map(|j| v.mass_ni.get(i, j).eval(env).unwrap()).collect()).collect();
    let l: Vec<f64> = v.l_ni.iter().map(|e| e.eval(env).unwrap()).collect();
    let ud = lin_solve(mass, l);
    let qd: Vec<f64> = v.qdot.iter().map(|e| e.eval(env).unwrap()).collect();
    (qd, accelerations_from(v, env, model, &ud))
}

#[test]
fn reduced_volterra_satisfies_lagrange_and_agrees_with_kane() {
    for name in MODELS {
        let model = load(name);
        let mech = mechanics::derive(&model);
        let reports = ignorable::analyze(&model, &mech);
        let chosen = ignorable::choose(&model, &reports).unwrap();
        let kane = volterra::derive(&model, &mech, &[], &model.quasi_full).unwrap();
        let reduced = volterra::derive(&model, &mech, &chosen, &model.quasi_reduced).unwrap();
        assert_eq!(reduced.u.len(), mech.p - chosen.len());
        // Lagrange's equations, symbolically: d/dt(dT/dq') - dT/dq + dV/dq - Q.
        let vchain = model.velocity_chain();
        let lagrange: Vec<Expr> = (0..mech.m)
            .map(|j| {
                let p = mech.kinetic.diff(model.velocities[j]);
                vchain.dt(p) - mech.kinetic.diff(model.coordinates[j]) + mech.potential.diff(model.coordinates[j]) - mech.q_forces[j]
            })
            .collect();
        let mut rng = SplitMix(42);
        for trial in 0..5 {
            let mut env = model.parameter_env();
            for q in &model.coordinates {
                env.set(*q, rng.uniform(-1.0, 1.0));
            }
            env.set(model.t, rng.uniform(0.0, 20.0));
            // A consistent velocity from random full quasi-velocities (Kane has no G).
            for u in &kane.u {
                env.set(*u, rng.uniform(-1.5, 1.5));
            }
            let (qd, qdd_kane) = accelerations(&kane, &env, &model);
            let mut renv = env.clone();
            for (v, x) in model.velocities.iter().zip(&qd) {
                renv.set(*v, *x);
            }
            // G_I and u_NI at this state.
            for (k, &i) in chosen.iter().enumerate() {
                let g = mech.kinetic.diff(model.velocities[i]).eval(&renv).unwrap();
                renv.set(reduced.g[k], g);
            }
            let quasi: Vec<f64> = model.quasi_reduced.iter().map(|e| e.eval(&renv).unwrap()).collect();
            for (u, x) in reduced.u.iter().zip(&quasi) {
                renv.set(*u, *x);
            }
            let (qd_r, qdd_r) = accelerations(&reduced, &renv, &model);
            for j in 0..mech.m {
                assert!((qd_r[j] - qd[j]).abs() < 1e-10 * (1.0 + qd[j].abs()), "{name} #{trial}: q'[{j}] {} vs {}", qd_r[j], qd[j]);
                assert!(
                    (qdd_r[j] - qdd_kane[j]).abs() < 1e-8 * (1.0 + qdd_kane[j].abs()),
                    "{name} #{trial}: q''[{j}] reduced {} vs Kane {}",
                    qdd_r[j],
                    qdd_kane[j]
                );
            }
            // Lagrange residual projected on the admissible motions (columns of Kane's W).
            let mut lenv = renv.clone();
            for (a, x) in model.accelerations.iter().zip(&qdd_r) {
                lenv.set(*a, *x);
            }
            let res: Vec<f64> = lagrange.iter().map(|e| e.eval(&lenv).unwrap()).collect();
            let scale: f64 = 1.0 + res.iter().map(|x| x.abs()).sum::<f64>() + qdd_r.iter().map(|x| x.abs()).sum::<f64>();
            for k in 0..kane.u.len() {
                let proj: f64 = (0..mech.m).map(|j| kane.w.get(j, k).eval(&renv).unwrap() * res[j]).sum();
                assert!(proj.abs() < 1e-9 * scale, "{name} #{trial}: projected Lagrange residual {proj:e} (scale {scale})");
            }
        }
    }
}

#[test]
fn scene1_singular_set_is_reported() {
    let model = load("cart_pendulum");
    let mech = mechanics::derive(&model);
    let v = volterra::derive(&model, &mech, &[2], &model.quasi_reduced).unwrap();
    let mut env = model.parameter_env();
    env.set(model.coordinates[0], 0.3);
    env.set(model.coordinates[1], 0.3 + std::f64::consts::PI);
    let det = v.determinant.expect("a 3 x 3 determinant is expanded");
    assert!(det.eval(&env).unwrap().abs() < 1e-12, "det = {det}");
    env.set(model.coordinates[1], 0.9);
    assert!(det.eval(&env).unwrap().abs() > 1e-3);
}

/// Scene 2's reduced equations by the Schur route do not depend on the absolute orientation
/// of the free system (its shape's inertia and forces are the same however it is turned): the
/// coordinates `psi, theta, phi` are taken out of `M_NI` and `L_NI` exactly, and what is left
/// equals the direct route's `M_NI` and `L_NI` (Eqs. 43-65) at random states.
#[test]
fn scene_2_reduced_equations_leave_out_the_absolute_orientation_and_equal_the_direct_route() {
    let model = load("three_body");
    let mech = mechanics::derive(&model);
    let chosen = ignorable::choose(&model, &ignorable::analyze(&model, &mech)).unwrap();
    let kane = volterra::derive(&model, &mech, &[], &model.quasi_full).unwrap();
    let schur = volterra::derive_reduced(&model, &mech, &chosen, &model.quasi_reduced, &kane).unwrap();
    let direct = volterra::derive(&model, &mech, &chosen, &model.quasi_reduced).unwrap();
    let orientation: Vec<_> = model.coordinates.iter().filter(|q| ["psi", "theta", "phi"].contains(&q.name().as_str())).copied().collect();
    assert_eq!(orientation.len(), 3);
    for e in schur.mass_ni.data.iter().chain(&schur.l_ni) {
        assert!(orientation.iter().all(|q| !e.contains(*q)), "{e} depends on the orientation");
    }
    let mut rng = SplitMix(7);
    for trial in 0..5 {
        let mut env = model.parameter_env();
        for q in &model.coordinates {
            env.set(*q, rng.uniform(-1.0, 1.0));
        }
        for (a, b) in schur.u.iter().zip(&direct.u) {
            let x = rng.uniform(-1.5, 1.5);
            env.set(*a, x);
            env.set(*b, x);
        }
        for (a, b) in schur.g.iter().zip(&direct.g) {
            let x = rng.uniform(-1.0, 1.0);
            env.set(*a, x);
            env.set(*b, x);
        }
        let pairs = schur.mass_ni.data.iter().zip(&direct.mass_ni.data).chain(schur.l_ni.iter().zip(&direct.l_ni));
        for (k, (s, d)) in pairs.enumerate() {
            let (s, d) = (s.eval(&env).unwrap(), d.eval(&env).unwrap());
            assert!((s - d).abs() <= 1e-10 * (1.0 + d.abs()), "#{trial} entry {k}: Schur {s}, direct {d}");
        }
    }
}
