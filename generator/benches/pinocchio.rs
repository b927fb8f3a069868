//! Our emitted right-hand sides against Pinocchio's articulated-body algorithm (ABA), the
//! fastest general-purpose forward dynamics we know of, on the same models: the paper's scenes
//! 2 and 3, the 20-link pendulum on a cart and the spatial chain on a floating base at 8 and 20
//! links (`generator::model::examples`). Writes `docs/benchmarks/pinocchio.json` (the table of
//! `docs/benchmarks.md`, "Against Pinocchio").
//!
//! ```sh
//! cargo bench -p generator --bench pinocchio                 # every model, 15 rounds
//! cargo bench -p generator --bench pinocchio -- --rounds 5 --out /tmp/pin.json
//! cargo bench -p generator --bench pinocchio -- --check      # only that the models agree
//! ```
//!
//! Before a model is timed, its Pinocchio twin is checked to be the same system: ABA's
//! accelerations at a random state against ours ([`check_against_aba`]), the last column.
//!
//! Outside CI: it installs the `pin` wheel (Pinocchio's headers and library) and Eigen's
//! headers (`cmeel-eigen`) into a virtual environment under `target/peers/`, and builds
//! `benches/pinocchio/aba.cpp` with `g++ -O3 -march=native` against them, header-only (every
//! template instantiated for this machine; `benches/support/pinocchio.rs`). Our modules are compiled by `rustc -C opt-level=3`
//! for plain x86-64 (`benches/support/timing.rs`): the comparison gives Pinocchio the newer
//! instructions (FMA, AVX2) and us none. Both sides time one call the same way (the best, over
//! 7 rounds, of the mean of 200 calls at one state), in separate processes run alternately,
//! round after round; each figure is the best over the rounds, so both met the same machine.
//! A third side is ours with the newer instructions too: the module emitted with fused
//! multiply-adds (`Options::fma`) and compiled with `-C target-cpu=native`, timed in the same
//! rounds.
//!
//! Cycles per operation: each timing program first reads the clock it runs at (a chain of
//! dependent register additions, one cycle each; `benches/support/timing.rs`), so a call's
//! cycles are its ns times that clock, in the same process; divided by the reduced right-hand
//! side's operations (assembly + solve, the plain module's count for both builds).

#[path = "support/timing.rs"]
mod timing;
#[path = "support/point.rs"]
mod point;
// Its robots' functions serve the workspace's robots benchmark.
#[allow(dead_code)]
#[path = "support/pinocchio.rs"]
mod pinocchio;

use generator::emit::Options;

use generator::generate;
use generator::model::examples::{floating_chain, n_link_pendulum_on_cart};
use std::path::{Path, PathBuf};
use std::process::Command;

struct Case {
    /// The row's name, and the model's name in `aba.cpp` with its size.
    label: String,
    aba: (&'static str, usize),
    model: generator::model::Model,
}

fn cases() -> Vec<Case> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models");
    let scene = |file: &str| generator::model::load(root.join(format!("{file}.ron"))).expect("the scene loads");
    let built = |b: generator::model::builder::ModelBuilder| b.build().expect("the benchmark models are valid");
    vec![
        Case { label: "scene 2 three_body".into(), aba: ("three_body", 0), model: scene("three_body") },
        Case { label: "scene 3 satellite_boom".into(), aba: ("satellite_boom", 0), model: scene("satellite_boom") },
        Case { label: "pendulum on a cart, 20 links".into(), aba: ("pendulum_on_cart", 20), model: built(n_link_pendulum_on_cart(20)) },
        Case { label: "spatial chain, 8 links on a floating base".into(), aba: ("floating_chain", 8), model: built(floating_chain(8)) },
        Case { label: "spatial chain, 20 links on a floating base".into(), aba: ("floating_chain", 20), model: built(floating_chain(20)) },
    ]
}

fn aba_ns(exe: &Path, (model, n): (&str, usize)) -> (f64, usize) {
    let out = Command::new(exe).args([model, &n.to_string()]).output().expect("aba runs");
    let text = String::from_utf8_lossy(&out.stdout);
    let field = |name: &str| {
        text.lines().find_map(|l| l.strip_prefix(name).map(|v| v.trim().to_string())).unwrap_or_else(|| panic!("aba {model} {n}: no `{name}` in {text}"))
    };
    (field("aba ").parse().expect("ns"), field("dof ").parse().expect("dof"))
}

/// Pinocchio's model of `case` checked against ours: a state of our model at a time away from 0
/// (Kane's quasi-velocities drawn from a fixed sequence in `[-1, 1)`, mapped to the rates by
/// Kane's `velocities`), the joints' applied forces read from `work_rate` (the generalized force
/// of a coordinate is the power at its unit rate), ABA's accelerations there (`aba MODEL N
/// accel`) against ours. Returns the largest difference over the largest acceleration; panics
/// beyond 1e-9, since a ratio against another system would say nothing. Pinocchio's models hold
/// the model files' parameter values, so ours are used as they are.
///
/// A free-flyer base (ZYX angles, then the joints, then `X, Y, Z`; Kane's speeds the base's
/// body-frame angular velocity, the joint rates, the translation rates) is compared on Kane's
/// `u'`; the pendulum on a cart (absolute angles, revolute joints relative) on Lagrange's `q''`
/// turned into the joints' relative accelerations.
fn check_against_aba(aba: &Path, case: &Case) -> f64 {
    let evaluated = generator::evaluate(&case.model).expect("the model evaluates");
    let (t, params) = (1.3, &evaluated.default_params);
    let n = evaluated.coordinates.len();
    let kane = evaluated.formulation(seam::FormulationKind::Kane).expect("Kane's form");
    let (state, q, qdot) = point::kane_state(&evaluated, t, params, &mut point::Draws::new());
    let g_i = vec![0.0; evaluated.ignorable.len()];
    // The generalized force of each coordinate: the power at its unit rate.
    let force = |k: usize| {
        let mut unit = vec![0.0; n];
        unit[k] = 1.0;
        let mut power = [0.0];
        evaluated.work_rate(t, &q, &unit, params, &mut power).expect("the work rate");
        power[0]
    };
    let floating = evaluated.coordinates[..3] == ["psi", "theta", "phi"];
    let (input, ours): (Vec<f64>, Vec<f64>) = if floating {
        let joints = n - 6;
        let mut dstate = vec![0.0; state.len()];
        kane.rhs(t, &state, params, &g_i, &mut dstate).expect("Kane's right-hand side");
        let u = &state[n..2 * n];
        let du = &dstate[n..2 * n];
        assert!((0..3).chain(n - 3..n).all(|k| force(k) == 0.0), "{}: forces on the base", case.label);
        let input = [&q[n - 3..], &q[..3], &q[3..3 + joints], &u[n - 3..], &u[..3], &u[3..3 + joints]].concat();
        let tau: Vec<f64> = (3..3 + joints).map(force).collect();
        ([input, tau].concat(), [&du[n - 3..], &du[..3], &du[3..3 + joints]].concat())
    } else {
        // Pinocchio's joints turn relative to the previous link: q1, q2 - q1, ...
        let relative = |x: &[f64]| -> Vec<f64> { (0..n).map(|k| if k < 2 { x[k] } else { x[k] - x[k - 1] }).collect() };
        let qddot = point::lagrange_accelerations(&evaluated, t, params, &q, &qdot);
        assert!((0..n).all(|k| force(k) == 0.0), "{}: no applied forces", case.label);
        ([relative(&q), relative(&qdot), vec![0.0; n]].concat(), relative(&qddot))
    };
    let mut child = Command::new(aba)
        .args([case.aba.0, &case.aba.1.to_string(), "accel"])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("aba runs");
    let text: String = input.iter().map(|v| format!("{v:e}\n")).collect();
    std::io::Write::write_all(&mut child.stdin.take().expect("stdin"), text.as_bytes()).expect("the state is written");
    let out = child.wait_with_output().expect("aba runs");
    assert!(out.status.success(), "aba {} accel failed", case.label);
    let theirs: Vec<f64> = String::from_utf8_lossy(&out.stdout).split_whitespace().map(|v| v.parse().expect("a number")).collect();
    assert_eq!(theirs.len(), ours.len(), "{}: ABA's accelerations", case.label);
    let scale = ours.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let error = ours.iter().zip(&theirs).fold(0.0f64, |m, (a, b)| m.max((a - b).abs())) / scale;
    assert!(error <= 1e-9, "{}: Pinocchio's model is not ours: accelerations {theirs:?} against {ours:?}", case.label);
    error
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| a != "--bench").collect();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut rounds = 15;
    let mut out = root.join("docs/benchmarks/pinocchio.json");
    let mut check_only = false;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--check" => check_only = true,
            "--rounds" => rounds = it.next().and_then(|s| s.parse().ok()).expect("--rounds needs a number"),
            "--out" => out = PathBuf::from(it.next().expect("--out needs a file")),
            other => panic!("unknown option `{other}`"),
        }
    }
    let aba = pinocchio::Peers::new(&root).aba();
    if check_only {
        for case in cases() {
            println!("{}: ABA's accelerations are ours within {:.1e}", case.label, check_against_aba(&aba, &case));
        }
        return;
    }
    let work = std::env::temp_dir().join(format!("multibody-pinocchio-{}", std::process::id()));
    let mut rows = Vec::new();
    for case in cases() {
        eprintln!("pinocchio: {} ...", case.label);
        let checked = check_against_aba(&aba, &case);
        eprintln!("pinocchio: {}: ABA's accelerations are ours within {checked:.1e}", case.label);
        let generated = generate(&case.model, &Options::from_model(&case.model)).expect("the benchmark models generate");
        let ops = |f: &str| generated.summary.ops(&format!("{f}::rhs")).map(|c| (c.ops.total(), c.solve.total())).expect("the formulation is emitted");
        let dir = work.join(case.aba.0).join(case.aba.1.to_string());
        let (exe, _) = timing::compile(&dir, &generated.code);
        let fused = generate(&case.model, &Options { fma: true, ..Options::from_model(&case.model) }).expect("the benchmark models generate");
        let (native, _) = timing::compile_with(&dir.join("native"), &fused.code, &["-C", "target-cpu=native"]);
        let (mut pin_best, mut dof) = (f64::INFINITY, 0);
        let mut ours_best = [f64::INFINITY; 4];
        let mut native_best = [f64::INFINITY; 4];
        // Cycles per call: each run's ns times the clock that run read, the best over the rounds.
        let mut ours_cycles = [f64::INFINITY; 4];
        let mut native_cycles = [f64::INFINITY; 4];
        let mut clock = 0.0f64;
        for _ in 0..rounds {
            let (ns, n) = aba_ns(&aba, case.aba);
            (pin_best, dof) = (pin_best.min(ns), n);
            for (best, cycles, exe) in [(&mut ours_best, &mut ours_cycles, &exe), (&mut native_best, &mut native_cycles, &native)] {
                let (ghz, calls) = timing::run(exe);
                clock = clock.max(ghz);
                for (f, ns) in calls {
                    let k = timing::FORMS.iter().position(|x| *x == f).expect("a formulation");
                    best[k] = best[k].min(ns);
                    cycles[k] = cycles[k].min(ns * ghz);
                }
            }
        }
        let (kane, reduced) = (ours_best[2], ours_best[3]);
        let (kane_native, reduced_native) = (native_best[2], native_best[3]);
        let ((ka, ks), (ra, rs)) = (ops("kane"), ops("reduced_volterra"));
        eprintln!(
            "pinocchio: {}: ABA {pin_best:.0} ns, Kane {kane:.0} ns, reduced {reduced:.0} ns (FMA + native: {kane_native:.0}, {reduced_native:.0})",
            case.label
        );
        rows.push(vec![
            case.label.clone(),
            dof.to_string(),
            format!("{pin_best:.0}"),
            format!("{kane:.0}"),
            format!("{reduced:.0}"),
            format!("{:.2}", kane / pin_best),
            format!("{:.2}", reduced / pin_best),
            format!("{ka} + {ks}"),
            format!("{ra} + {rs}"),
            format!("{kane_native:.0}"),
            format!("{reduced_native:.0}"),
            format!("{:.2}", kane_native / pin_best),
            format!("{:.2}", reduced_native / pin_best),
            format!("{clock:.2}"),
            format!("{:.2}", ours_cycles[3] / (ra + rs) as f64),
            format!("{:.2}", native_cycles[3] / (ra + rs) as f64),
            format!("{checked:.0e}"),
        ]);
    }
    let _ = std::fs::remove_dir_all(&work);
    let columns = [
        "model",
        "dof",
        "Pinocchio ABA ns",
        "Kane ns",
        "reduced ns",
        "Kane / ABA",
        "reduced / ABA",
        "Kane ops (assembly + solve)",
        "reduced ops",
        "Kane ns, FMA + native",
        "reduced ns, FMA + native",
        "Kane / ABA, FMA + native",
        "reduced / ABA, FMA + native",
        "clock GHz",
        "reduced cycles / op",
        "reduced cycles / op, FMA + native",
        "accelerations against ours",
    ];
    let file = serde_json::json!({ "command": "cargo bench -p generator --bench pinocchio", "columns": columns, "rows": rows });
    let text = serde_json::to_string_pretty(&file).expect("json") + "\n";
    let tmp = out.with_extension("json.tmp");
    std::fs::write(&tmp, &text).expect("the table is written");
    std::fs::rename(&tmp, &out).expect("the table is moved into place");
    println!("| {} |", columns.join(" | "));
    for r in &rows {
        println!("| {} |", r.join(" | "));
    }
    eprintln!("pinocchio: wrote {}", out.display());
}
