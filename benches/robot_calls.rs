//! Robots per call (the issue "Robots", item 4): each robot of example-robot-data, read from its
//! URDF, its forward dynamics by our Kane's and reduced right-hand sides (the emitted module
//! compiled by rustc, and the same model compiled in-process by the JIT) against Pinocchio's
//! ABA and its CRBA with Cholesky, on the same URDF read by Pinocchio's own parser. Writes
//! `docs/robots/per_call.json`; `docs/robots.md` quotes it.
//!
//! ```sh
//! cargo bench --bench robot_calls                          # every robot, 7 rounds
//! cargo bench --bench robot_calls -- --robots ur5,solo12 --rounds 3 --out /tmp/calls.json
//! ```
//!
//! Outside CI: Pinocchio as the generator's Pinocchio benchmark has it
//! (`generator/benches/support/pinocchio.rs`: the `pin` wheel, `aba.cpp` built with
//! `g++ -O3 -march=native`), example-robot-data in the same environment. Pinocchio's model of
//! each robot is its parser's (`pin.buildModelFromUrdf`, saved as its text archive for the C++
//! program). Our modules are compiled for plain x86-64 (`-C opt-level=3`), which gives Pinocchio
//! the newer instructions and us none, and, emitted with `--fma`, with `-C target-cpu=native`: the
//! same instructions as Pinocchio's build. Every side times a call the same way (the best,
//! over 7 rounds, of the mean of 200 calls at one state); the rounds alternate the sides, and
//! each figure is the best over the rounds.
//!
//! Before a robot is timed, Pinocchio's model is checked to be ours: at a state drawn in
//! Pinocchio's coordinates, ABA's accelerations against our Kane's and reduced rates (the
//! mapping of `docs/robots/pinocchio_check.py`), to 1e-9 of the largest. A robot with mimic
//! joints (panda's second finger) has more degrees of freedom in Pinocchio's ABA, which takes
//! no mimic joint: it is timed, not checked here; `pinocchio_check.py` checks it with CRBA.

#[path = "../generator/benches/support/pinocchio.rs"]
mod pinocchio;
// Only its draws serve here.
#[allow(dead_code)]
#[path = "../generator/benches/support/point.rs"]
mod point;
#[path = "support/robots.rs"]
mod robots;
#[path = "../generator/benches/support/timing.rs"]
mod timing;

use generator::model::{Base, UrdfOptions, urdf_ident as ident};
use seam::FormulationKind;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// The best, over 7 rounds, of the mean time of 200 calls of `call` (as the timing program).
fn best_ns(mut call: impl FnMut()) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..7 {
        let start = Instant::now();
        for _ in 0..200 {
            call();
        }
        best = best.min(start.elapsed().as_secs_f64() * 1e9 / 200.0);
    }
    best
}

/// One joint of Pinocchio's model: its name, its place in q and v, its kind.
struct Joint {
    name: String,
    idx_q: usize,
    nq: usize,
    idx_v: usize,
    nv: usize,
    kind: String,
}

/// Pinocchio's model's layout: nq, nv, the joints (`aba saved FILE layout`).
fn layout(aba: &Path, saved: &Path) -> (usize, usize, Vec<Joint>) {
    let text = pinocchio::run(Command::new(aba).arg("saved").arg(saved).arg("layout"), "aba layout");
    let (mut nq, mut nv, mut joints) = (0, 0, Vec::new());
    for line in text.lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        match f.as_slice() {
            ["nq", n] => nq = n.parse().expect("nq"),
            ["nv", n] => nv = n.parse().expect("nv"),
            ["joint", name, iq, q, iv, v, kind] => joints.push(Joint {
                name: name.to_string(),
                idx_q: iq.parse().expect("idx_q"),
                nq: q.parse().expect("nq"),
                idx_v: iv.parse().expect("idx_v"),
                nv: v.parse().expect("nv"),
                kind: kind.to_string(),
            }),
            _ => panic!("aba layout: `{line}`"),
        }
    }
    (nq, nv, joints)
}

/// `(w, x, y, z)` products.
fn quat_mul(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    let ([w1, x1, y1, z1], [w2, x2, y2, z2]) = (a, b);
    [w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2, w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2]
}

/// `R v` for the unit quaternion `e = (w, x, y, z)`: `e (0, v) e*`.
fn rotate(e: [f64; 4], v: [f64; 3]) -> [f64; 3] {
    let r = quat_mul(quat_mul(e, [0.0, v[0], v[1], v[2]]), [e[0], -e[1], -e[2], -e[3]]);
    [r[1], r[2], r[3]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// Pinocchio's ABA against our Kane's and reduced rates at a state drawn in Pinocchio's
/// coordinates: the largest difference over the largest acceleration, or `None` where the
/// models' degrees of freedom differ (mimic joints). Panics beyond 1e-9.
fn check(aba: &Path, saved: &Path, ours: &seam::Model, floating: bool, name: &str) -> Option<f64> {
    let (nq, nv, joints) = layout(aba, saved);
    let dof = ours.coordinates.len() - usize::from(floating);
    if dof != nv {
        return None;
    }
    let mut draws = point::Draws::new();
    let (mut pq, pv): (Vec<f64>, Vec<f64>) = (vec![0.0; nq], (0..nv).map(|_| draws.next()).collect());
    for j in &joints {
        match (j.kind.as_str(), j.nq) {
            ("JointModelFreeFlyer", 7) => {
                let e: Vec<f64> = (0..4).map(|_| draws.next()).collect();
                let norm = e.iter().map(|x| x * x).sum::<f64>().sqrt();
                for k in 0..3 {
                    pq[j.idx_q + k] = draws.next();
                }
                for k in 0..4 {
                    pq[j.idx_q + 3 + k] = e[k] / norm;
                }
            }
            (_, 1) => pq[j.idx_q] = draws.next(),
            (_, 2) => {
                let angle = std::f64::consts::PI * draws.next();
                (pq[j.idx_q], pq[j.idx_q + 1]) = (angle.cos(), angle.sin());
            }
            (kind, n) => panic!("{name}: a joint {kind} with {n} coordinates"),
        }
    }
    let input: String = pq.iter().chain(&pv).map(|x| format!("{x:e}\n")).collect();
    let mut child = Command::new(aba)
        .arg("saved")
        .arg(saved)
        .arg("accel")
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("aba runs");
    std::io::Write::write_all(&mut child.stdin.take().expect("stdin"), input.as_bytes()).expect("the state is written");
    let out = child.wait_with_output().expect("aba runs");
    assert!(out.status.success(), "{name}: aba accel failed");
    let a: Vec<f64> = String::from_utf8_lossy(&out.stdout).split_whitespace().map(|v| v.parse().expect("a number")).collect();
    assert_eq!(a.len(), nv, "{name}: ABA's accelerations");

    // Ours: (q, q') and the quasi-velocities' expected rates, by name.
    let n = ours.coordinates.len();
    let (mut q, mut qdot) = (vec![0.0; n], vec![0.0; n]);
    let mut speed_rates: Vec<(String, f64)> = Vec::new();
    let at = |c: &str| ours.coordinate_index(c).unwrap_or_else(|| panic!("{name}: no coordinate `{c}`"));
    if floating {
        let root = joints.iter().find(|j| j.kind == "JointModelFreeFlyer").expect("a free flyer");
        let (p, e) = (&pq[root.idx_q..root.idx_q + 3], [pq[root.idx_q + 6], pq[root.idx_q + 3], pq[root.idx_q + 4], pq[root.idx_q + 5]]);
        let v_lin = [pv[root.idx_v], pv[root.idx_v + 1], pv[root.idx_v + 2]];
        let w = [pv[root.idx_v + 3], pv[root.idx_v + 4], pv[root.idx_v + 5]];
        let a_lin = [a[root.idx_v], a[root.idx_v + 1], a[root.idx_v + 2]];
        let p_dot = rotate(e, v_lin);
        let c = cross(w, v_lin);
        let p_ddot = rotate(e, [a_lin[0] + c[0], a_lin[1] + c[1], a_lin[2] + c[2]]);
        let e_dot = quat_mul(e, [0.0, w[0], w[1], w[2]]).map(|x| x / 2.0);
        for (k, c) in ["base_x", "base_y", "base_z"].iter().enumerate() {
            (q[at(c)], qdot[at(c)]) = (p[k], p_dot[k]);
        }
        for (k, c) in ["base_qw", "base_qx", "base_qy", "base_qz"].iter().enumerate() {
            (q[at(c)], qdot[at(c)]) = (e[k], e_dot[k]);
        }
        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
            speed_rates.push((format!("omega_{axis}"), a[root.idx_v + 3 + k]));
        }
        for (k, c) in ["base_x", "base_y", "base_z"].iter().enumerate() {
            speed_rates.push((format!("{c}'"), p_ddot[k]));
        }
    }
    let mut joint_rates: Vec<(usize, f64)> = Vec::new();
    for j in joints.iter().filter(|j| j.kind != "JointModelFreeFlyer" && j.nv > 0) {
        let k = at(&ident(&j.name));
        q[k] = if j.nq == 2 { pq[j.idx_q + 1].atan2(pq[j.idx_q]) } else { pq[j.idx_q] };
        qdot[k] = pv[j.idx_v];
        joint_rates.push((k, a[j.idx_v]));
    }
    // The joints' quasi-velocities follow the base's, in the coordinates' order.
    joint_rates.sort_by_key(|(k, _)| *k);
    speed_rates.extend(joint_rates.into_iter().map(|(k, r)| (format!("{}'", ours.coordinates[k]), r)));

    let params = &ours.default_params;
    let mut worst = 0.0f64;
    let scale = a.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    for kind in [FormulationKind::Kane, FormulationKind::ReducedVolterra] {
        let f = ours.formulation(kind).expect("the formulation");
        let (mut state, mut g) = (vec![0.0; f.states()], vec![0.0; ours.ignorable.len()]);
        f.initial_state(0.0, &q, &qdot, params, &mut state, &mut g).expect("the state");
        let mut dstate = vec![0.0; state.len()];
        f.rhs(0.0, &state, params, &g, &mut dstate).expect("the right-hand side");
        let ignorable: Vec<String> = ours.ignorable.iter().map(|&j| format!("{}'", ours.coordinates[j])).collect();
        let expected: Vec<f64> = speed_rates.iter().filter(|(s, _)| kind == FormulationKind::Kane || !ignorable.contains(s)).map(|(_, r)| *r).collect();
        let got = &dstate[f.layout.speed_range()];
        assert_eq!(got.len(), expected.len(), "{name} {kind}: quasi-velocities");
        let error = got.iter().zip(&expected).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale;
        assert!(error <= 1e-9, "{name} {kind}: Pinocchio's model is not ours: rates {got:?} against {expected:?}");
        worst = worst.max(error);
    }
    Some(worst)
}

/// One robot's figures.
#[derive(serde::Serialize)]
struct Row {
    robot: String,
    base: String,
    /// Degrees of freedom: ours, and Pinocchio's (more where mimic joints are free in it).
    dof: usize,
    pinocchio_dof: usize,
    aba_ns: f64,
    crba_cholesky_ns: f64,
    kane_ns: f64,
    reduced_ns: f64,
    kane_jit_ns: f64,
    reduced_jit_ns: f64,
    kane_over_aba: f64,
    reduced_over_aba: f64,
    reduced_jit_over_compiled: f64,
    kane_jit_over_compiled: f64,
    /// The module emitted with fused multiply-adds (`--fma`) and built with `-C
    /// target-cpu=native`: this machine's instructions, as Pinocchio's `-march=native` build.
    kane_native_ns: f64,
    reduced_native_ns: f64,
    kane_native_over_aba: f64,
    reduced_native_over_aba: f64,
    reduced_ops: String,
    /// The check against Pinocchio: the largest relative difference, or why none.
    check: String,
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| a != "--bench").collect();
    let value = |flag: &str| args.iter().position(|a| a == flag).and_then(|i| args.get(i + 1)).cloned();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let rounds: usize = value("--rounds").map_or(7, |r| r.parse().expect("--rounds needs a number"));
    let out = value("--out").map(PathBuf::from).unwrap_or_else(|| root.join("docs/robots/per_call.json"));
    let only: Option<Vec<String>> = value("--robots").map(|s| s.split(',').map(str::to_string).collect());
    let peers = pinocchio::Peers::new(root);
    let aba = peers.aba();
    let folder = peers.robots_folder();
    let work = std::env::temp_dir().join(format!("multibody-robot-calls-{}", std::process::id()));
    let mut rows = Vec::new();
    for (name, file, base) in robots::ROBOTS {
        if only.as_ref().is_some_and(|o| !o.iter().any(|n| n == name)) {
            continue;
        }
        let urdf = folder.join(file);
        let floating = base == "floating";
        let saved = peers.save_robot(&urdf, base, name);
        eprintln!("robot calls: {name}: deriving ...");
        let options = UrdfOptions { base: if floating { Base::Floating } else { Base::Fixed }, ..UrdfOptions::default() };
        let model = load::model_with(&urdf, &options).expect("the robot loads");
        let jit = load::evaluate(&model, load::Jacobians::Differenced, load::Route::Jit, &mut |_| {}).expect("the robot derives").model;
        // The long tapes' best code (compiled in the background) before anything is timed.
        jit::settle();
        let checked = check(&aba, &saved, &jit, floating, name);
        let check_text = checked.map_or("not here: mimic joints (docs/robots/pinocchio_check.py)".to_string(), |e| format!("{e:.0e}"));
        eprintln!("robot calls: {name}: Pinocchio's model against ours: {check_text}");
        let generated = generator::generate(&model, &generator::emit::Options::from_model(&model)).expect("the robot emits");
        let ops = generated.summary.ops("reduced_volterra::rhs").map(|c| format!("{} + {}", c.ops.total(), c.solve.total())).unwrap_or_default();
        eprintln!("robot calls: {name}: rustc ...");
        let (exe, _) = timing::compile(&work.join(name), &generated.code);
        let fused =
            generator::generate(&model, &generator::emit::Options { fma: true, ..generator::emit::Options::from_model(&model) }).expect("the robot emits");
        let (native_exe, _) = timing::compile_with(&work.join(format!("{name}_native")), &fused.code, &["-C", "target-cpu=native"]);
        // The JIT's right-hand sides at the model's initial state, as the timing program's.
        let (q0, qd0) = jit.initial.clone().expect("an initial state");
        let jit_call = |kind: FormulationKind| {
            let f = jit.formulation(kind).expect("the formulation");
            let (mut state, mut g) = (vec![0.0; f.states()], vec![0.0; jit.ignorable.len()]);
            f.initial_state(0.0, &q0, &qd0, &jit.default_params, &mut state, &mut g).expect("the state");
            let mut d = vec![0.0; state.len()];
            best_ns(|| {
                f.rhs(0.0, std::hint::black_box(&state), &jit.default_params, &g, &mut d).expect("the right-hand side");
                std::hint::black_box(&d);
            })
        };
        let (mut aba_ns, mut crba_ns, mut pin_dof) = (f64::INFINITY, f64::INFINITY, 0);
        let mut compiled = [f64::INFINITY; 4];
        let mut native = [f64::INFINITY; 4];
        let (mut kane_jit, mut reduced_jit) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..rounds {
            let text = pinocchio::run(Command::new(&aba).arg("saved").arg(&saved), "aba saved");
            let field = |f: &str| -> f64 {
                text.lines().find_map(|l| l.strip_prefix(f).map(|v| v.trim().parse().expect("a number"))).unwrap_or_else(|| panic!("aba: no `{f}`"))
            };
            aba_ns = aba_ns.min(field("aba "));
            crba_ns = crba_ns.min(field("crba "));
            pin_dof = field("dof ") as usize;
            for (times, exe) in [(&mut compiled, &exe), (&mut native, &native_exe)] {
                for (f, ns) in timing::run(exe).1 {
                    let k = timing::FORMS.iter().position(|x| *x == f).expect("a formulation");
                    times[k] = times[k].min(ns);
                }
            }
            kane_jit = kane_jit.min(jit_call(FormulationKind::Kane));
            reduced_jit = reduced_jit.min(jit_call(FormulationKind::ReducedVolterra));
        }
        let (kane, reduced) = (compiled[2], compiled[3]);
        let (kane_native, reduced_native) = (native[2], native[3]);
        eprintln!(
            "robot calls: {name}: ABA {aba_ns:.0} ns, CRBA + Cholesky {crba_ns:.0} ns; Kane {kane:.0} ns, reduced {reduced:.0} ns; native {kane_native:.0}, {reduced_native:.0} ns; JIT {kane_jit:.0}, {reduced_jit:.0} ns"
        );
        rows.push(Row {
            robot: name.into(),
            base: base.into(),
            dof: jit.coordinates.len() - usize::from(floating),
            pinocchio_dof: pin_dof,
            aba_ns,
            crba_cholesky_ns: crba_ns,
            kane_ns: kane,
            reduced_ns: reduced,
            kane_jit_ns: kane_jit,
            reduced_jit_ns: reduced_jit,
            kane_over_aba: kane / aba_ns,
            reduced_over_aba: reduced / aba_ns,
            reduced_jit_over_compiled: reduced_jit / reduced,
            kane_jit_over_compiled: kane_jit / kane,
            kane_native_ns: kane_native,
            reduced_native_ns: reduced_native,
            kane_native_over_aba: kane_native / aba_ns,
            reduced_native_over_aba: reduced_native / aba_ns,
            reduced_ops: ops,
            check: check_text,
        });
    }
    let _ = std::fs::remove_dir_all(&work);
    let json = serde_json::json!({
        "command": "cargo bench --bench robot_calls",
        "rounds": rounds,
        "about": "ns per call, the best over the rounds of the best of 7 means of 200 calls; ours compiled by rustc -C opt-level=3 for plain x86-64 (kane_ns, reduced_ns) and, emitted with --fma, with -C target-cpu=native (kane_native_ns, reduced_native_ns), Pinocchio 4.1 by g++ -O3 -march=native; the JIT in-process",
        "rows": rows,
    });
    let text = serde_json::to_string_pretty(&json).expect("json") + "\n";
    let tmp = out.with_extension("json.tmp");
    std::fs::write(&tmp, text).expect("the table is written");
    std::fs::rename(&tmp, &out).expect("the table is moved into place");
    eprintln!("robot calls: wrote {}", out.display());
}
