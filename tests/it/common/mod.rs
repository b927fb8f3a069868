//! Helpers shared by the workspace tests.

#![allow(dead_code)] // each test file uses its own subset

pub mod http;

use generator::formulation::Derivation;
use generator::formulation::volterra::Volterra;
use generator::model::{self, Model};
use generator::symbolic::Env;
use generator::symbolic::SplitMix;
use generator::symbolic::{Expr, Symbol};

/// A model of `models/`.
pub fn load(name: &str) -> Model {
    model::load(format!("{}/models/{name}.ron", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

/// `q''` implied by a Volterra form with `q' = W u + X` and the rates `u'`, at the state in `env`
/// (`q`, `u`, `G`, `t` set): `d/dt(W u + X)` along the motion plus `W u'`.
pub fn accelerations_from(v: &Volterra, env: &Env, model: &Model, udot: &[f64]) -> Vec<f64> {
    let chain: Vec<(Symbol, Expr)> = model.coordinates.iter().copied().zip(v.qdot.iter().copied()).collect();
    v.qdot
        .iter()
        .map(|e| {
            let explicit = e.time_derivative(model.t, &chain).eval(env).unwrap();
            explicit + v.u.iter().zip(udot).map(|(u, ud)| e.diff(*u).eval(env).unwrap() * ud).sum::<f64>()
        })
        .collect()
}

/// Solves a small dense system by Gaussian elimination with partial pivoting.
pub fn lin_solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for c in 0..n {
        let p = (c..n).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs())).unwrap();
        a.swap(c, p);
        b.swap(c, p);
        for r in c + 1..n {
            let f = a[r][c] / a[c][c];
            for k in c..n {
                a[r][k] -= f * a[c][k];
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = vec![0.0; n];
    for r in (0..n).rev() {
        let s: f64 = (r + 1..n).map(|k| a[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    x
}

/// `q''` of every formulation of `d` at the state in `env` (parameters, `t`, `q` and `q'` set,
/// `q'` admissible), each evaluated through its own [`Equations`]: the speeds and momenta from
/// `(q, q')`, the matrix and forcing, the solve, and the formulation's way back to `q''`.
pub fn all_accelerations(d: &Derivation, model: &Model, env: &Env) -> Vec<(&'static str, Vec<f64>)> {
    let m = model.m();
    let mut out = Vec::new();
    for e in &d.equations {
        let mut fenv = env.clone();
        let speeds = Expr::eval_all(&e.speeds_from_qdot, env).unwrap();
        for (s, x) in e.speeds.iter().zip(&speeds) {
            fenv.set(*s, *x);
        }
        for (g, &j) in e.momenta.iter().zip(&d.ignorable) {
            fenv.set(*g, d.mechanics.momentum(j, &model.velocities).eval(env).unwrap());
        }
        let n = e.mass.rows;
        let flat = Expr::eval_all(&e.mass.data, &fenv).unwrap();
        let mass: Vec<Vec<f64>> = flat.chunks(n).map(|r| r.to_vec()).collect();
        let x = lin_solve(mass, Expr::eval_all(&e.forcing, &fenv).unwrap());
        let qdd = match (e.name(), &e.post) {
            ("lagrange", _) => x[..m].to_vec(),
            (_, Some((w, c))) => {
                let (w, c) = (Expr::eval_all(&w.data, &fenv).unwrap(), Expr::eval_all(c, &fenv).unwrap());
                (0..m).map(|j| (0..x.len()).map(|k| w[j * x.len() + k] * x[k]).sum::<f64>() + c[j]).collect()
            }
            ("kane", None) => accelerations_from(d.kane.as_ref().unwrap(), &fenv, model, &x),
            (_, None) => accelerations_from(d.reduced.as_ref().unwrap(), &fenv, model, &x),
        };
        out.push((e.name(), qdd));
    }
    out
}

/// Lagrange's equations from T by differentiation, `d/dt(dT/dq') - dT/dq + dV/dq - Q`, one
/// expression per coordinate in `q, q', q''`: independent of how the formulations got `h`.
pub fn lagrange_residuals(d: &Derivation, model: &Model) -> Vec<Expr> {
    let mech = &d.mechanics;
    let chain = model.velocity_chain();
    (0..mech.m)
        .map(|j| {
            chain.dt(mech.kinetic.diff(model.velocities[j])) - mech.kinetic.diff(model.coordinates[j]) + mech.potential.diff(model.coordinates[j])
                - mech.q_forces[j]
        })
        .collect()
}

/// Checks, at `trials` random admissible states, that all formulations of `d` give the same
/// `q''` and that it satisfies Lagrange's equations projected on the admissible motions.
pub fn check_formulations_agree(name: &str, d: &Derivation, model: &Model, trials: usize, seed: u64) {
    let residuals = lagrange_residuals(d, model);
    let kane = d.kane.as_ref().expect("Kane's form");
    let mut rng = SplitMix(seed);
    for trial in 0..trials {
        let mut env = model.parameter_env();
        for q in &model.coordinates {
            env.set(*q, rng.uniform(-1.0, 1.0));
        }
        env.set(model.t, rng.uniform(0.0, 20.0));
        // An admissible q' from random full quasi-velocities.
        let mut kenv = env.clone();
        for u in &kane.u {
            kenv.set(*u, rng.uniform(-1.5, 1.5));
        }
        let qd = Expr::eval_all(&kane.qdot, &kenv).unwrap();
        for (v, x) in model.velocities.iter().zip(&qd) {
            env.set(*v, *x);
        }
        let all = all_accelerations(d, model, &env);
        let (first, reference) = &all[0];
        let scale = 1.0 + reference.iter().map(|x| x.abs()).fold(0.0, f64::max);
        for (form, qdd) in &all[1..] {
            for j in 0..model.m() {
                assert!((qdd[j] - reference[j]).abs() < 1e-8 * scale, "{name} #{trial}: q''[{j}] {form} {} vs {first} {}", qdd[j], reference[j]);
            }
        }
        let mut lenv = env.clone();
        for (a, x) in model.accelerations.iter().zip(reference) {
            lenv.set(*a, *x);
        }
        let res = Expr::eval_all(&residuals, &lenv).unwrap();
        let w = Expr::eval_all(&kane.w.data, &kenv).unwrap();
        let p = kane.u.len();
        let size = 1.0 + res.iter().map(|x| x.abs()).sum::<f64>() + reference.iter().map(|x| x.abs()).sum::<f64>();
        for k in 0..p {
            let proj: f64 = (0..model.m()).map(|j| w[j * p + k] * res[j]).sum();
            assert!(proj.abs() < 1e-9 * size, "{name} #{trial}: projected Lagrange residual {proj:e} (scale {size:e})");
        }
    }
}

/// The complete elliptic integral of the first kind `K(m)`, by the arithmetic-geometric mean
/// (which converges quadratically: a fixed number of rounds reaches the last bit).
#[allow(dead_code)]
pub fn elliptic_k(m: f64) -> f64 {
    let (mut a, mut b) = (1.0f64, (1.0 - m).sqrt());
    for _ in 0..40 {
        (a, b) = (0.5 * (a + b), (a * b).sqrt());
    }
    std::f64::consts::PI / (2.0 * a)
}

/// `multibody ARGS` in `dir`, with `PATH` holding only the system's folders (no cargo, no
/// rustc), killed if it runs for more than ten minutes (no command may hang).
pub fn multibody(dir: &std::path::Path, args: &[&str]) -> std::process::Output {
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_multibody"))
        .args(args)
        .current_dir(dir)
        .env_clear()
        .env("PATH", "/usr/bin:/bin")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let id = child.id();
    let (done, finished) = std::sync::mpsc::channel::<()>();
    let guard = std::thread::spawn(move || {
        if let Err(std::sync::mpsc::RecvTimeoutError::Timeout) = finished.recv_timeout(std::time::Duration::from_secs(600)) {
            let _ = std::process::Command::new("kill").args(["-9", &id.to_string()]).status();
        }
    });
    let out = child.wait_with_output().unwrap();
    drop(done);
    guard.join().unwrap();
    assert!(out.status.code().is_some(), "`multibody {}` was killed: it hung or crashed", args.join(" "));
    out
}

/// The standard output of a command that succeeded (its exit and both streams otherwise).
pub fn ok(out: &std::process::Output) -> String {
    assert!(out.status.success(), "exit {:?}\n{}\n{}", out.status.code(), String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}
