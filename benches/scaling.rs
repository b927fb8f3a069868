//! The scaling benchmark: the n-link pendulum on a cart, the spatial chain on a floating base
//! and the planar free chain written in absolute angles (`generator::model::examples`), derived
//! and emitted at growing n. Writes
//! `docs/scaling.md` (a table per model: derive time per stage, emit time, peak memory,
//! operations per formulation split into assembly and solve, rustc time, ns per call) and
//! `docs/plots/scaling.svg` (log-log: derive + emit time and assembly operations against n).
//!
//! ```sh
//! cargo bench --bench scaling                      # default sizes
//! cargo bench --bench scaling -- --sympy           # SymPy's KanesMethod beside it
//! cargo bench --bench scaling -- --pendulum 5,10,20,50 --floating 2,4,8,20 --planar 5,20 --compile-up-to 20 --out /tmp/x
//! cargo bench --bench scaling -- --at-scale        # pendulum n = 100, 200, planar n = 50: docs/scaling/at_scale.json
//! ```
//!
//! Each size runs in a child process (this program, re-invoked), so peak memory is its own and
//! no memo carries over. `--sympy` runs `docs/scaling/sympy_kane.py` in the same run (needs
//! python3 with SymPy), so the ratios are side by side.

/// As the generator's command line (`generator/src/main.rs`).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

use generator::emit::{Formulation, Options};

use generator::generate;
use generator::model::examples::{floating_chain, n_link_pendulum_on_cart, planar_chain_absolute};
use plotters::prelude::*;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

#[path = "../generator/benches/support/timing.rs"]
mod timing;
#[path = "../generator/benches/support/point.rs"]
mod point;
use timing::FORMS;

/// Fresh processes per scene; the best is reported.
const SCENE_RUNS: usize = 25;

/// Fresh processes (no compilation) for the planar chain's goal row: its CPU time is their
/// median, its memory their largest peak (one run's CPU varied from 0.62 s to 0.83 s from one
/// hour to the next).
const PLANAR_GOAL_RUNS: usize = 9;

/// Fresh SymPy processes per scene (each takes up to about a second); the best is reported.
const SYMPY_SCENE_RUNS: usize = 3;

/// The paper's scenes, by their file in `models/`.
const SCENES: [&str; 3] = ["cart_pendulum", "three_body", "satellite_boom"];

#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
struct Record {
    model: String,
    n: usize,
    derive_ms: f64,
    stages_ms: Vec<(String, f64)>,
    emit_ms: f64,
    /// CPU time of the whole child (user + system, both threads), seconds.
    #[serde(default)]
    cpu_s: f64,
    peak_mb: f64,
    /// Per formulation: (name, assembly ops, solve ops).
    ops: Vec<(String, usize, usize)>,
    code_bytes: usize,
    rustc_s: Option<f64>,
    /// Per formulation: ns per right-hand-side call.
    ns_per_call: Vec<(String, f64)>,
    /// Per formulation: ns per call evaluated in-process, compiled by the JIT (as `multibody`
    /// runs it), timed the same way in the same child.
    #[serde(default)]
    jit_ns_per_call: Vec<(String, f64)>,
    /// The Fourier simplifier's term products, its nodes over the term limit, and whether it
    /// reached its work limit (`Summary::simplifier`).
    #[serde(default)]
    simplifier: (u64, usize, bool),
}

#[derive(Clone, Debug, Default, serde::Deserialize)]
struct SympyRecord {
    n: usize,
    derive_seconds: f64,
    cse_seconds: f64,
    assembly_ops: usize,
}

fn peak_mb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find(|l| l.starts_with("VmHWM:"))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|kb| kb.parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

/// CPU seconds this process has used so far (user + system, every thread), from
/// `/proc/self/stat` (clock ticks of 1/100 s, the kernel's fixed `USER_HZ`).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // The fields after the command name (which is in parentheses and may hold spaces).
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let fields: Vec<f64> = rest.split_whitespace().map(|x| x.parse().unwrap_or(f64::NAN)).collect();
    // utime and stime are fields 14 and 15 of the line, 12 and 13 after the name.
    fields.get(11).zip(fields.get(12)).map_or(f64::NAN, |(u, s)| (u + s) / 100.0)
}

/// CPU microseconds this process has used so far (user + system, every thread, those that
/// ended too), from `getrusage`: fine enough for a scene's 20 ms, where `/proc/self/stat`
/// counts in 10 ms ticks.
fn cpu_microseconds() -> f64 {
    // SAFETY: getrusage writes one `rusage` into the zeroed value it is given and reads nothing.
    let usage = unsafe {
        let mut usage: libc::rusage = std::mem::zeroed();
        if libc::getrusage(libc::RUSAGE_SELF, &mut usage) != 0 {
            return f64::NAN;
        }
        usage
    };
    let micros = |t: libc::timeval| t.tv_sec as f64 * 1e6 + t.tv_usec as f64;
    micros(usage.ru_utime) + micros(usage.ru_stime)
}

/// `docs/scaling/sympy_kane.py --model MODEL EXTRA...` in a fresh python3 process: its records,
/// or None when it could not run (no python3, no SymPy).
fn run_sympy(root: &Path, model: &str, extra: &[&str]) -> Option<Vec<SympyRecord>> {
    #[derive(serde::Deserialize)]
    struct File {
        records: Vec<SympyRecord>,
    }
    let json = std::env::temp_dir().join(format!("sympy-{model}-{}.json", std::process::id()));
    let status = Command::new("python3").arg(root.join("docs/scaling/sympy_kane.py")).args(["--model", model]).args(extra).arg("--json").arg(&json).status();
    let records = match status {
        Ok(s) if s.success() => std::fs::read_to_string(&json).ok().and_then(|t| serde_json::from_str::<File>(&t).ok()).map(|f| f.records),
        _ => None,
    };
    let _ = std::fs::remove_file(&json);
    records
}

/// SymPy's model of `model` (a scene, or a scaled model at size `n`) checked against ours:
/// this program writes the point (`--scene NAME point`, `--point KIND N`), `sympy_kane.py
/// --check` derives SymPy's accelerations there. The largest difference of `q''` over the
/// largest `|q''|`, or None when SymPy could not run. Panics where the models differ: a ratio
/// against a different system would say nothing.
fn check_sympy(root: &Path, exe: &Path, model: &str, n: usize) -> Option<f64> {
    let args: Vec<String> =
        if SCENES.contains(&model) { vec!["--scene".into(), model.into(), "point".into()] } else { vec!["--point".into(), model.into(), n.to_string()] };
    let child = Command::new(exe).args(&args).output().expect("the child runs");
    assert!(child.status.success(), "the point of {model} failed: {}", String::from_utf8_lossy(&child.stderr));
    let point = std::env::temp_dir().join(format!("sympy-point-{model}-{}.json", std::process::id()));
    std::fs::write(&point, &child.stdout).expect("the point is written");
    let json = std::env::temp_dir().join(format!("sympy-check-{model}-{}.json", std::process::id()));
    let script = root.join("docs/scaling/sympy_kane.py");
    let out = Command::new("python3").arg(&script).args(["--model", model, "--sizes", &n.to_string(), "--check"]).arg(&point).arg("--json").arg(&json).output();
    let _ = std::fs::remove_file(&point);
    let out = out.ok()?;
    let error = std::fs::read_to_string(&json)
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|v| v["records"][0]["relative_difference"].as_f64());
    let _ = std::fs::remove_file(&json);
    let error = error?;
    assert!(out.status.success(), "SymPy's model of {model} (n = {n}) is not the generator's: {}", String::from_utf8_lossy(&out.stdout));
    Some(error)
}

/// This program re-invoked as the child `--one`: one model at one size (`compile`: "compile" or
/// "no"), its record.
fn one(exe: &Path, kind: &str, n: usize, compile: &str, work: &Path) -> Record {
    let child = Command::new(exe).args(["--one", kind, &n.to_string(), compile]).arg(work).output().expect("the child runs");
    assert!(child.status.success(), "{kind} n = {n} failed: {}", String::from_utf8_lossy(&child.stderr));
    serde_json::from_slice(&child.stdout).expect("the child's record")
}

/// A table's simplifier cell: the term products in millions and the nodes over the term limit,
/// and the work limit where it was reached (everything after it kept as built).
fn simplifier_cell((work, over, reached): (u64, usize, bool)) -> String {
    format!("{:.2}, {over}{}", work as f64 / 1e6, if reached { " (work limit reached)" } else { "" })
}

/// The issue "Robots"' goals for chains at robot scale: `(model, n, fresh runs, CPU s, MB, node
/// budget)`. The goals are for the default settings (budget 0: the default); the pendulum at
/// n = 200 is measured again with the budget raised to what it builds, to say by how much it
/// misses them past the budget.
const AT_SCALE: [(&str, usize, usize, f64, f64, usize); 4] = [
    ("pendulum", 100, 3, 10.0, 1000.0, 0),
    ("pendulum", 200, 1, 60.0, 4000.0, 0),
    ("pendulum", 200, 1, 60.0, 4000.0, 12_000_000),
    ("planar", 50, 3, 3.0, f64::INFINITY, 0),
];

/// `--at-scale`: each model of [`AT_SCALE`] generated (derive and emit, the default settings)
/// in fresh processes, its CPU (both threads) and peak memory, or the error that stopped it;
/// the median CPU, the spread of the runs (largest over smallest) and the largest peak, against
/// the goals. Writes `path` (`docs/robots.md` quotes it).
fn at_scale(path: &Path) {
    let exe = std::env::current_exe().expect("this program's path");
    let mut rows = Vec::new();
    for (kind, n, runs, goal_cpu, goal_mb, budget) in AT_SCALE {
        let mut done: Vec<serde_json::Value> = (0..runs)
            .map(|k| {
                eprintln!("at scale: {kind} n = {n}, run {} of {runs} ...", k + 1);
                let child = Command::new(&exe).args(["--at-scale-one", kind, &n.to_string(), &budget.to_string()]).output().expect("the child runs");
                assert!(child.status.success(), "{kind} n = {n}: {}", String::from_utf8_lossy(&child.stderr));
                let r: serde_json::Value = serde_json::from_slice(&child.stdout).expect("the child's record");
                eprintln!("at scale: {kind} n = {n}: {r}");
                r
            })
            .collect();
        let cpu = |r: &serde_json::Value| r["cpu_s"].as_f64().unwrap_or(f64::NAN);
        done.sort_by(|a, b| cpu(a).total_cmp(&cpu(b)));
        let median = cpu(&done[done.len() / 2]);
        let peak = done.iter().map(|r| r["peak_mb"].as_f64().unwrap_or(f64::NAN)).fold(0.0, f64::max);
        rows.push(serde_json::json!({
            "model": kind,
            "n": n,
            "max_nodes": if budget == 0 { serde_json::Value::Null } else { serde_json::json!(budget) },
            "nodes": done[done.len() / 2]["nodes"],
            "runs": done.len(),
            "cpu_s": median,
            "spread": cpu(&done[done.len() - 1]) / cpu(&done[0]),
            "peak_mb": peak,
            "error": done.iter().find_map(|r| r["error"].as_str().map(str::to_string)),
            "goal_cpu_s": goal_cpu,
            "goal_mb": if goal_mb.is_finite() { serde_json::json!(goal_mb) } else { serde_json::Value::Null },
        }));
    }
    let json = serde_json::json!({
        "command": "cargo bench --bench scaling -- --at-scale",
        "about": "chains at robot scale (the issue Robots, item 3): derive and emit all four formulations with the default settings (max_nodes null; a raised node budget otherwise, to say by how much a model stopped at the default one misses its goals), in fresh processes; the median CPU (both threads), the spread of the runs (largest over smallest CPU), the largest peak memory and the expression nodes built, or the error that stopped the generation",
        "cores": std::thread::available_parallelism().map_or(1, |n| n.get()),
        "records": rows,
    });
    std::fs::write(path, serde_json::to_string_pretty(&json).expect("plain data") + "\n").expect("the file is written");
    eprintln!("wrote {}", path.display());
}

/// The models the benchmark scales, by their key.
const KINDS: [&str; 3] = ["pendulum", "floating", "planar"];

/// The scaled model `kind` at size `n`.
fn scaled_model(kind: &str, n: usize) -> generator::model::Model {
    let builder = match kind {
        "pendulum" => n_link_pendulum_on_cart(n),
        "floating" => floating_chain(n),
        _ => planar_chain_absolute(n),
    };
    builder.build().expect("the benchmark models are valid")
}

/// The child: one model at one size.
fn measure(kind: &str, n: usize, compile: bool, work: &Path) -> Record {
    let model = scaled_model(kind, n);
    let out = generate(&model, &Options::from_model(&model)).expect("the benchmark models generate");
    let cpu_s = cpu_seconds();
    let s = &out.summary;
    let mut record = Record {
        model: kind.to_string(),
        n,
        derive_ms: s.derive_time.as_secs_f64() * 1e3,
        stages_ms: s.stages.iter().map(|(k, d)| (k.to_string(), d.as_secs_f64() * 1e3)).collect(),
        emit_ms: s.emit_time.as_secs_f64() * 1e3,
        cpu_s,
        peak_mb: peak_mb(),
        ops: FORMS.iter().filter_map(|f| s.ops(&format!("{f}::rhs")).map(|c| (f.to_string(), c.ops.total(), c.solve.total()))).collect(),
        code_bytes: out.code.len(),
        simplifier: (s.simplifier.work, s.simplifier.over_term_limit, s.simplifier.work_limit_reached),
        ..Record::default()
    };
    if compile {
        let (exe, rustc_s) = timing::compile(&work.join(format!("{kind}_{n}")), &out.code);
        record.rustc_s = Some(rustc_s);
        // The compiled module and the JIT's code timed in turn, each its best over the rounds:
        // one timing of each drifted by up to a third apart on this machine.
        let jit = jit::Jit::default();
        let evaluated = generator::evaluate_with_backend(&model, &Options::from_model(&model), &jit).expect("the benchmark models evaluate").0;
        // The long tapes' best code (compiled in the background) before anything is timed.
        jit::settle();
        for _ in 0..CALL_ROUNDS {
            keep_best(&mut record.ns_per_call, timing::run(&exe).1);
            keep_best(&mut record.jit_ns_per_call, jit_ns_per_call(&evaluated));
        }
    }
    record
}

/// Rounds in which the compiled module and the JIT's code are timed in turn.
const CALL_ROUNDS: usize = 3;

/// `best` (empty at first) lowered to `round`'s time wherever that is smaller, by name.
fn keep_best(best: &mut Vec<(String, f64)>, round: Vec<(String, f64)>) {
    if best.is_empty() {
        *best = round;
        return;
    }
    for (name, ns) in round {
        if let Some((_, b)) = best.iter_mut().find(|(n, _)| *n == name) {
            *b = b.min(ns);
        }
    }
}

/// Each formulation's `rhs` evaluated in-process by the JIT, timed as the timing program times
/// the compiled module (`generator/benches/support/timing.rs`): best of 7 rounds of 200 calls at the model's initial state.
fn jit_ns_per_call(evaluated: &seam::Model) -> Vec<(String, f64)> {
    let (q0, qd0) = evaluated.initial.clone().expect("the benchmark models have an initial state");
    let params = evaluated.default_params.clone();
    evaluated
        .formulations
        .iter()
        .map(|f| {
            let (mut state, mut g) = (vec![0.0; f.states()], vec![0.0; evaluated.ignorable.len()]);
            f.initial_state(0.0, &q0, &qd0, &params, &mut state, &mut g).expect("a consistent initial state");
            let mut d = vec![0.0; state.len()];
            let mut best = f64::INFINITY;
            for _ in 0..7 {
                let t = Instant::now();
                for _ in 0..200 {
                    f.rhs(0.0, std::hint::black_box(&state), &params, &g, &mut d).expect("the right-hand side");
                    std::hint::black_box(&d);
                }
                best = best.min(t.elapsed().as_secs_f64() * 1e9 / 200.0);
            }
            (f.name().to_string(), best)
        })
        .collect()
}

fn list(s: &str) -> Vec<usize> {
    s.split(',').filter_map(|x| x.trim().parse().ok()).collect()
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| a != "--bench").collect();
    if args.first().map(String::as_str) == Some("--scene") {
        let path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/models")).join(format!("{}.ron", args[1]));
        // Timed inside the process from before the model is read, as SymPy's side is timed from
        // before its model is built: neither counts starting the process or loading the library.
        if args.get(2).map(String::as_str) == Some("point") {
            println!("{}", model_point(&generator::model::load(&path).expect("the scene loads")));
            return;
        }
        let (start, cpu_start) = (Instant::now(), cpu_microseconds());
        let model = generator::model::load(&path).expect("the scene loads");
        match args.get(2).map(String::as_str) {
            Some("inspect") => {
                generator::inspect(&model, false).expect("the scene inspects");
            }
            Some("kane") => {
                // Kane's form alone, derived and emitted.
                let options = Options { formulations: vec![Formulation::Kane], ..Options::from_model(&model) };
                generate(&model, &options).expect("the scene generates");
            }
            Some("derive") => {
                // The work SymPy's figure covers: Kane's equations derived, neither CSE'd nor
                // emitted (the simplifier's work and the mechanics every formulation shares
                // are in it; SymPy's side leaves its equations unsimplified).
                let request = generator::formulation::Request { formulations: vec![Formulation::Kane], integrate_ignorable: true };
                generator::model::in_own_context(&model, |m| generator::formulation::derive(m, &request).map(|d| d.equations.len()))
                    .expect("the scene derives");
            }
            _ => {
                generate(&model, &Options::from_model(&model)).expect("the scene generates");
            }
        }
        println!("{} {}", start.elapsed().as_secs_f64() * 1e3, (cpu_microseconds() - cpu_start) / 1e3);
        return;
    }
    if args.first().map(String::as_str) == Some("--point") {
        // `--point KIND N`: as `--scene NAME point`, on a scaled model.
        println!("{}", model_point(&scaled_model(&args[1], args[2].parse().expect("--point KIND N"))));
        return;
    }
    if args.first().map(String::as_str) == Some("--at-scale-one") {
        // `--at-scale-one KIND N [MAX_NODES]` (0 or none: the default budget).
        let (kind, n) = (&args[1], args[2].parse().expect("--at-scale-one KIND N"));
        let budget: usize = args.get(3).map_or(0, |b| b.parse().expect("--at-scale-one KIND N MAX_NODES"));
        if budget > 0 {
            generator::symbolic::set_max_nodes(budget);
        }
        let model = scaled_model(kind, n);
        let out = generate(&model, &Options::from_model(&model));
        let (cpu_s, peak_mb) = (cpu_seconds(), peak_mb());
        let nodes = out.as_ref().ok().map(|g| g.summary.nodes);
        let error = out.err().map(|e| e.to_string().lines().next().unwrap_or_default().to_string());
        println!("{}", serde_json::json!({ "cpu_s": cpu_s, "peak_mb": peak_mb, "error": error, "nodes": nodes }));
        return;
    }
    if args.first().map(String::as_str) == Some("--at-scale") {
        at_scale(&PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/scaling/at_scale.json")));
        return;
    }
    if args.first().map(String::as_str) == Some("--one") {
        let (kind, n, compile, work) = (&args[1], args[2].parse().unwrap(), args[3] == "compile", PathBuf::from(&args[4]));
        println!("{}", serde_json::to_string(&measure(kind, n, compile, &work)).unwrap());
        return;
    }
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut pendulum = vec![2, 5, 10, 20, 30, 50];
    let mut floating = vec![2, 4, 6, 8, 12, 16, 20];
    let mut planar = vec![5, 10, 20];
    let mut compile_up_to = 20;
    let mut out = root.join("docs");
    let mut sympy = false;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--pendulum" => pendulum = list(it.next().expect("--pendulum needs sizes")),
            "--floating" => floating = list(it.next().expect("--floating needs sizes")),
            "--planar" => planar = list(it.next().expect("--planar needs sizes")),
            "--compile-up-to" => compile_up_to = it.next().and_then(|s| s.parse().ok()).expect("--compile-up-to needs a size"),
            "--out" => out = PathBuf::from(it.next().expect("--out needs a directory")),
            "--sympy" => sympy = true,
            other => panic!("unknown option `{other}`"),
        }
    }
    let work = std::env::temp_dir().join(format!("multibody-scaling-{}", std::process::id()));
    std::fs::create_dir_all(&work).expect("a scratch directory");
    let exe = std::env::current_exe().expect("this program's path");
    let mut records = Vec::new();
    for (kind, sizes) in KINDS.into_iter().zip([&pendulum, &floating, &planar]) {
        for &n in sizes {
            eprintln!("scaling: {kind} n = {n} ...");
            let compile = if n <= compile_up_to { "compile" } else { "no" };
            let r = one(&exe, kind, n, compile, &work);
            eprintln!("scaling: {kind} n = {n}: derive {:.0} ms, emit {:.0} ms, CPU {:.2} s, {:.0} MB", r.derive_ms, r.emit_ms, r.cpu_s, r.peak_mb);
            records.push(r);
        }
    }
    // The planar chain's goal row: the median CPU of fresh runs without compilation.
    let planar_goal = planar.contains(&20).then(|| {
        let mut runs: Vec<Record> = (0..PLANAR_GOAL_RUNS).map(|_| one(&exe, "planar", 20, "no", &work)).collect();
        runs.sort_by(|a, b| a.cpu_s.total_cmp(&b.cpu_s));
        let peak = runs.iter().map(|r| r.peak_mb).fold(0.0, f64::max);
        eprintln!(
            "scaling: planar n = 20, {PLANAR_GOAL_RUNS} runs: CPU {:.2} s to {:.2} s, median {:.2} s",
            runs[0].cpu_s,
            runs[runs.len() - 1].cpu_s,
            runs[runs.len() / 2].cpu_s
        );
        (runs[runs.len() / 2].cpu_s, peak)
    });
    let _ = std::fs::remove_dir_all(&work);
    // The paper's scenes: load, derive and emit, from a fresh process, best of SCENE_RUNS (on
    // the 2-core machine the same run varies by up to a factor of two from minute to minute).
    let mut scenes = Vec::new();
    let mut scene_cpu = Vec::new();
    let mut inspects = Vec::new();
    for scene in SCENES {
        // The best wall time and the best CPU time (milliseconds) of the runs.
        let best = |extra: &[&str]| {
            (0..SCENE_RUNS)
                .map(|_| {
                    let out = Command::new(&exe).args(["--scene", scene]).args(extra).output().expect("the child runs");
                    let text = String::from_utf8_lossy(&out.stdout);
                    let mut fields = text.split_whitespace().map(|x| x.parse::<f64>().unwrap_or(f64::NAN));
                    (fields.next().unwrap_or(f64::NAN), fields.next().unwrap_or(f64::NAN))
                })
                .fold((f64::INFINITY, f64::INFINITY), |(w, c), (a, b)| (w.min(a), c.min(b)))
        };
        let ((generate_ms, cpu_ms), (inspect_ms, inspect_cpu_ms)) = (best(&[]), best(&["inspect"]));
        let (kane_cpu_ms, derive_cpu_ms) = (best(&["kane"]).1, best(&["derive"]).1);
        eprintln!(
            "scaling: {scene}: generate {generate_ms:.1} ms ({cpu_ms:.1} ms of CPU), Kane's alone {kane_cpu_ms:.1} ms of CPU ({derive_cpu_ms:.1} ms derived only), inspect {inspect_ms:.1} ms ({inspect_cpu_ms:.1} ms of CPU)"
        );
        scenes.push((scene, generate_ms));
        scene_cpu.push(SceneCpu { scene, generate_ms: cpu_ms, kane_ms: kane_cpu_ms, derive_ms: derive_cpu_ms });
        inspects.push((scene, inspect_ms, inspect_cpu_ms));
    }
    let mut peers: Vec<(String, Vec<SympyRecord>)> = Vec::new();
    if sympy {
        for (kind, sizes) in [("pendulum", &pendulum), ("floating", &floating)] {
            // SymPy takes minutes beyond these sizes (8 links of the spatial chain: about 45 s).
            let limit = if kind == "pendulum" { 30 } else { 8 };
            let sizes: Vec<String> = sizes.iter().filter(|&&n| n <= limit).map(|n| n.to_string()).collect();
            eprintln!("scaling: SymPy {kind} {} ...", sizes.join(","));
            match run_sympy(&root, kind, &["--sizes", &sizes.join(",")]) {
                Some(records) => peers.push((kind.to_string(), records)),
                None => eprintln!("scaling: SymPy not measured (python3 with sympy needed)"),
            }
        }
    }
    // SymPy on the scenes: KanesMethod and kanes_equations, CPU, best of SYMPY_SCENE_RUNS fresh
    // processes each.
    let mut sympy_scenes: Vec<(&str, f64)> = Vec::new();
    if sympy {
        for scene in SCENES {
            let runs: Option<Vec<f64>> = (0..SYMPY_SCENE_RUNS).map(|_| Some(run_sympy(&root, scene, &[])?.first()?.derive_seconds)).collect();
            let best = runs.map_or(f64::NAN, |r| r.into_iter().fold(f64::INFINITY, f64::min));
            if best.is_finite() {
                sympy_scenes.push((scene, best));
            }
        }
    }
    // SymPy's models checked against ours before their times are compared: each scene, and
    // each scaled model at its smallest size SymPy ran.
    let mut sympy_checks: Vec<(String, f64)> = Vec::new();
    if sympy {
        let smallest = |kind: &str| peers.iter().find(|(k, _)| k == kind).and_then(|(_, r)| r.iter().map(|r| r.n).min());
        let models = SCENES.iter().map(|s| (s.to_string(), 0)).chain(["pendulum", "floating"].into_iter().filter_map(|k| Some((k.to_string(), smallest(k)?))));
        for (model, n) in models {
            if let Some(error) = check_sympy(&root, &exe, &model, n) {
                eprintln!("scaling: SymPy's {model} checked: q'' within {error:.1e}");
                sympy_checks.push((if n == 0 { model } else { format!("{model} n = {n}") }, error));
            }
        }
    }
    std::fs::create_dir_all(out.join("plots")).expect("the output directory");
    // Per scene: SymPy's derivation CPU seconds and ours in milliseconds.
    let against_sympy: Vec<(f64, SceneCpu)> =
        sympy_scenes.iter().filter_map(|(s, sympy_s)| scene_cpu.iter().find(|c| c.scene == *s).map(|c| (*sympy_s, *c))).collect();
    let measured = Measured {
        records: &records,
        peers: &peers,
        scenes: &scenes,
        scene_cpu: &scene_cpu,
        inspects: &inspects,
        against_sympy: &against_sympy,
        sympy_checks: &sympy_checks,
        planar_goal,
    };
    write_atomic(&out.join("scaling.md"), &report(&measured, [&pendulum, &floating, &planar], compile_up_to, sympy));
    plot(&out.join("plots/scaling.svg"), &records, &peers);
    std::fs::create_dir_all(out.join("scaling")).expect("the output directory");
    std::fs::write(out.join("scaling/ours.json"), serde_json::to_string_pretty(&records).unwrap()).expect("the records are written");
    if !peers.is_empty() {
        // SymPy's operation counts (deterministic), for tests/it/ops_against_sympy.rs.
        let version = Command::new("python3")
            .args(["-c", "import sympy; print(sympy.__version__)"])
            .output()
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
            .unwrap_or_default();
        let mut json = serde_json::json!({
            "about": "SymPy's KanesMethod on the scaling benchmark's models: count_ops(cse([M, F])), written by `cargo bench --bench scaling -- --sympy` (docs/scaling/sympy_kane.py); tests/it/ops_against_sympy.rs holds our Kane assembly to it",
            "sympy": version,
        });
        for (kind, p) in &peers {
            json[kind.as_str()] = p.iter().map(|x| serde_json::json!({ "n": x.n, "assembly_ops": x.assembly_ops })).collect();
        }
        std::fs::write(out.join("scaling/sympy.json"), serde_json::to_string_pretty(&json).unwrap() + "\n").expect("the SymPy records are written");
    }
    eprintln!("scaling: wrote {} and {}", out.join("scaling.md").display(), out.join("plots/scaling.svg").display());
}

/// Where SymPy's model of a scene or a scaled model is checked against ours (`sympy_kane.py
/// --check`): a state of the model at a time away from 0, consistent with its constraints, and
/// our accelerations `q''` there, as JSON with every value by its name in the model (the names
/// SymPy's models use).
/// The state is Kane's with its coordinates and quasi-velocities drawn from a fixed sequence in
/// `[-1, 1)`, mapped to `(q, q')` by Kane's `velocities` (so a velocity constraint holds); `q''`
/// is Lagrange's right-hand side at that `(q, q')`.
fn model_point(model: &generator::model::Model) -> serde_json::Value {
    let evaluated = generator::evaluate(model).expect("the model evaluates");
    let t = 1.3;
    let mut draws = point::Draws::new();
    // Each parameter moved off the file's value by up to a quarter (a zero one, such as scene
    // 1's motor torque, drawn in [0.1, 0.5)), so that no term hides behind a round value.
    let params: Vec<f64> =
        evaluated.default_params.iter().map(|&p| if p == 0.0 { 0.3 + 0.2 * draws.next() } else { p * (1.0 + 0.25 * draws.next()) }).collect();
    let (_, q, qdot) = point::kane_state(&evaluated, t, &params, &mut draws);
    let qddot = point::lagrange_accelerations(&evaluated, t, &params, &q, &qdot);
    let named = |values: &[f64]| -> serde_json::Map<String, serde_json::Value> {
        evaluated.coordinates.iter().zip(values).map(|(name, v)| (name.clone(), serde_json::json!(v))).collect()
    };
    serde_json::json!({
        "model": model.name,
        "t": t,
        "params": evaluated.parameter_names.iter().zip(params).map(|(name, v)| (name.clone(), serde_json::json!(v))).collect::<serde_json::Map<_, _>>(),
        "q": named(&q),
        "qdot": named(&qdot),
        "qddot": named(&qddot),
    })
}

/// Writes through a temporary file in the same directory, renamed over the target.
fn write_atomic(path: &Path, text: &str) {
    let tmp = path.with_extension("md.tmp");
    std::fs::write(&tmp, text).expect("the report is written");
    std::fs::rename(&tmp, path).expect("the report replaces the old one");
}

fn ops_of(r: &Record, f: &str) -> Option<(usize, usize)> {
    r.ops.iter().find(|(n, _, _)| n == f).map(|(_, a, s)| (*a, *s))
}

/// The slope of log(time) against log(n) between the two largest sizes measured.
fn growth(records: &[Record], kind: &str) -> Option<f64> {
    let rs: Vec<&Record> = records.iter().filter(|r| r.model == kind).collect();
    let (a, b) = (rs.get(rs.len().checked_sub(2)?)?, rs.last()?);
    let t = |r: &Record| r.derive_ms + r.emit_ms;
    Some((t(b) / t(a)).ln() / (b.n as f64 / a.n as f64).ln())
}

/// A scene's best CPU milliseconds (of [`SCENE_RUNS`] fresh processes each, timed inside the
/// process from before the model is read): the whole generation (four formulations, derived and
/// emitted), Kane's form alone derived and emitted, and Kane's form derived only.
#[derive(Clone, Copy)]
struct SceneCpu {
    scene: &'static str,
    generate_ms: f64,
    kane_ms: f64,
    derive_ms: f64,
}

/// What one run of the benchmark measured, for the report.
struct Measured<'a> {
    records: &'a [Record],
    /// SymPy's records per model.
    peers: &'a [(String, Vec<SympyRecord>)],
    /// Per scene: the best wall milliseconds of a generation.
    scenes: &'a [(&'a str, f64)],
    /// Per scene: the best CPU milliseconds of each kind of run.
    scene_cpu: &'a [SceneCpu],
    /// Per scene: the best wall and the best CPU milliseconds of `inspect`.
    inspects: &'a [(&'a str, f64, f64)],
    /// Per scene: SymPy's derivation CPU seconds and our generation's CPU milliseconds.
    against_sympy: &'a [(f64, SceneCpu)],
    /// Per model SymPy derived: the largest difference of its `q''` from ours at a random state,
    /// over the largest `|q''|` ([`check_sympy`]).
    sympy_checks: &'a [(String, f64)],
    /// The planar chain of 20 rods: median CPU seconds and largest peak megabytes of
    /// [`PLANAR_GOAL_RUNS`] fresh runs.
    planar_goal: Option<(f64, f64)>,
}

fn goals(m: &Measured) -> String {
    let Measured { records, peers, scenes, scene_cpu, inspects, against_sympy, planar_goal, .. } = *m;
    let find = |kind: &str, n: usize| records.iter().find(|r| r.model == kind && r.n == n);
    let total = |r: &Record| (r.derive_ms + r.emit_ms) / 1e3;
    let verdict = |ok: bool, reason: &str| if ok { "met".to_string() } else { format!("missed: {reason}") };
    let mut md = String::from("## Goals\n\n| goal | target | measured | |\n|---|---|---|---|\n");
    if let Some(r) = find("pendulum", 20) {
        let ok = total(r) < 1.0;
        md += &format!("| n-link pendulum on a cart, n = 20, derive + emit all four formulations | < 1 s | {:.2} s | {} |\n", total(r), verdict(ok, ""));
    }
    if let Some(r) = find("pendulum", 50) {
        let ok = total(r) < 30.0 && r.peak_mb < 1024.0;
        md += &format!(
            "| n = 50 | < 30 s, < 1 GB | {:.1} s, {:.0} MB | {} |\n",
            total(r),
            r.peak_mb,
            verdict(ok, "the expression pool and the emitted module's tokens")
        );
    }
    if let Some(r) = find("floating", 20) {
        md += &format!("| spatial chain on a floating base, n = 20 (beyond the issue's table) | - | {:.1} s, {:.0} MB | |\n", total(r), r.peak_mb);
    }
    if let Some((cpu_s, peak_mb)) = planar_goal {
        let ok = cpu_s < 0.5 && peak_mb < 200.0;
        md += &format!(
            "| planar free chain of 20 rods in absolute angles, derive + emit, CPU (both threads; median of {PLANAR_GOAL_RUNS} fresh runs) and peak memory (largest) | < 0.5 s, < 200 MB | {:.2} s, {:.0} MB | {} |\n",
            cpu_s,
            peak_mb,
            verdict(
                ok,
                "its frames all hang from the world, so every rod's position is a sum of cosines of sums of angles that the mechanics expands and simplifies term by term (see the table below)"
            )
        );
    }
    let g: Vec<String> = KINDS.iter().filter_map(|k| growth(records, k).map(|e| format!("{k} n^{e:.1}"))).collect();
    let sympy_growth: Vec<String> = peers
        .iter()
        .filter_map(|(k, p)| {
            let (a, b) = (p.get(p.len().checked_sub(2)?)?, p.last()?);
            let t = |x: &SympyRecord| x.derive_seconds + x.cse_seconds;
            Some(format!("{k} n^{:.1}", (t(b) / t(a)).ln() / (b.n as f64 / a.n as f64).ln()))
        })
        .collect();
    md += &format!(
        "| growth of derive + emit time in n (slope between the two largest sizes) | polynomial, no worse than SymPy's (~n^3) | ours {}; SymPy {} | polynomial; see the tables |\n",
        g.join(", "),
        if sympy_growth.is_empty() { "not measured".to_string() } else { sympy_growth.join(", ") }
    );
    let sc: Vec<String> = scenes.iter().map(|(s, ms)| format!("{s} {ms:.0} ms")).collect();
    let scenes_ok = scenes.iter().all(|(_, ms)| *ms < 50.0);
    md += &format!(
        "| each paper scene, load + derive + emit | < 50 ms each | {} | {} |\n",
        sc.join(", "),
        verdict(
            scenes_ok,
            "scene 2 (three bodies free in space, eight coordinates, four formulations) simplifies with four-angle harmonics so that its reduced mass matrix comes out free of the absolute orientation; emission overlaps the derivation on a second thread, so the time is the deriving thread's (the mechanics, Kane's form, the reduced form, then the last formulation's emission), and on this 2-core machine the best of the runs itself varies by up to a factor of 1.4 from hour to hour"
        )
    );
    if !against_sympy.is_empty() {
        // SymPy's seconds against ours in milliseconds, per scene, for one kind of our runs.
        let cells = |ours: fn(&SceneCpu) -> f64| -> (String, bool) {
            let cells: Vec<String> =
                against_sympy.iter().map(|(sympy_s, c)| format!("{} {:.1} ({sympy_s:.2} s / {:.1} ms)", c.scene, sympy_s * 1e3 / ours(c), ours(c))).collect();
            (cells.join(", "), against_sympy.iter().all(|(sympy_s, c)| sympy_s * 1e3 / ours(c) >= 30.0))
        };
        let ((same, same_ok), (kane, _), (whole, whole_ok)) = (cells(|c| c.derive_ms), cells(|c| c.kane_ms), cells(|c| c.generate_ms));
        md += &format!(
            "| derivation CPU, SymPy's `KanesMethod` / ours, each paper scene, the same work (SymPy: the model and `kanes_equations`, best of {SYMPY_SCENE_RUNS} fresh processes, `docs/scaling/sympy_kane.py`; ours: the model loaded and Kane's equations derived, neither CSE'd nor emitted, best of {SCENE_RUNS}; both timed inside the process) | at least 30 | {same} | {} |\n",
            verdict(same_ok, "ours also simplifies its equations (SymPy's are left unsimplified) and derives the mechanics every formulation shares")
        );
        md += &format!(
            "| SymPy's `KanesMethod` / our whole generation, each paper scene (ours: load, derive and emit all four formulations, Definition 1 for every coordinate; timed as above) | at least 30 | {whole} | {} |\n",
            verdict(
                whole_ok,
                &format!(
                    "the issue's first measure; emission is about half of each scene's time (the generator's summary, `emitted in`), and Kane's form alone, derived and emitted (`--formulations kane`), gives {kane}"
                )
            )
        );
    }
    // Cost is CPU: generation overlaps its emission with the derivation on a second thread,
    // inspect derives on one, so their wall times say how the work is spread, not how much.
    let generate_cpu = |scene: &str| scene_cpu.iter().find(|c| c.scene == scene).map(|c| c.generate_ms);
    let ins: Vec<(String, bool)> = inspects
        .iter()
        .zip(scenes)
        .map(|((s, wall, cpu), (_, g_wall))| {
            let g_cpu = generate_cpu(s).unwrap_or(f64::NAN);
            (format!("{s} {cpu:.0} against {g_cpu:.0} ms of CPU ({wall:.0} against {g_wall:.0} ms wall)"), *cpu <= g_cpu)
        })
        .collect();
    md += &format!(
        "| `inspect` costs no more than generation (one shared derivation), CPU of the best run each | inspect <= generate | {} | {} |\n",
        ins.iter().map(|(t, _)| t.as_str()).collect::<Vec<_>>().join(", "),
        verdict(ins.iter().all(|(_, ok)| *ok), "inspect builds the trial bodies of the recursive formulations, as generation does")
    );
    let mut worst: Option<(String, usize, f64)> = None;
    for (kind, p) in peers {
        for x in p {
            if let Some(r) = find(kind, x.n) {
                let ratio = ops_of(r, "kane").map_or(f64::NAN, |(a, _)| a as f64 / x.assembly_ops as f64);
                if worst.as_ref().is_none_or(|w| ratio > w.2) {
                    worst = Some((kind.clone(), x.n, ratio));
                }
            }
        }
    }
    if let Some((kind, n, ratio)) = worst {
        md += &format!(
            "| assembly operations (Kane) against SymPy's cse'd Kane count, at every n | <= 1 | worst {ratio:.2} ({kind}, n = {n}) | {} |\n",
            verdict(ratio <= 1.0, "at the smallest size; from 4 links on ours is smaller and the ratio falls with n")
        );
    }
    if let Some(r) = find("pendulum", 20) {
        let ok = r.rustc_s.is_some_and(|s| s < 30.0);
        md += &format!(
            "| rustc time of the n = 20 module | < 30 s | {} | {} |\n",
            r.rustc_s.map_or("-".into(), |s| format!("{s:.1} s (pendulum)")),
            verdict(ok, "not compiled")
        );
    }
    if let Some(r) = find("pendulum", 20) {
        let ratios = jit_ratios(r);
        if let Some(worst) = ratios.iter().copied().reduce(f64::max) {
            let shown: Vec<String> = ratios.iter().map(|x| format!("{x:.2}")).collect();
            md += &format!(
                "| a right-hand-side call of the n = 20 pendulum in-process (JIT) against its compiled module | within 2x | {} (lagrange / maggi / kane / reduced) | {} |\n",
                shown.join(" / "),
                verdict(worst <= 2.0, "the JIT's code against rustc's")
            );
        }
    }
    md += "| output bytes | depend only on the model and the options | budgets count terms and term products, never time; `generated/tests/regenerate.rs` checks the committed modules byte for byte and across threads | met |\n\n";
    md
}

/// Per formulation (in `FORMS` order), the JIT's ns per call over the compiled module's, where
/// both were measured.
fn jit_ratios(r: &Record) -> Vec<f64> {
    FORMS
        .iter()
        .filter_map(|f| {
            let compiled = r.ns_per_call.iter().find(|(n, _)| n == f)?.1;
            let jit = r.jit_ns_per_call.iter().find(|(n, _)| n == f)?.1;
            Some(jit / compiled)
        })
        .collect()
}

fn report(measured: &Measured, [pendulum, floating, planar]: [&Vec<usize>; 3], compile_up_to: usize, sympy: bool) -> String {
    let (records, peers) = (measured.records, measured.peers);
    let mut md = String::from("# Scaling\n\n");
    md += "Measured by `cargo bench --bench scaling";
    if sympy {
        md += " -- --sympy";
    }
    md += &format!(
        "` (sizes: pendulum {:?}, floating {:?}, planar {:?}; modules compiled up to n = {compile_up_to}), every size in a fresh process. \
         Times are wall-clock on the machine that ran it, one run (the scenes: best of {SCENE_RUNS} fresh processes); operation counts are deterministic. \
         Generation runs on two threads: every formulation but the last is emitted while the next is derived, so \"emit\" is what is left after the derivation. \
         \"Assembly\" is what a right-hand side computes before its dense solve (comparable with SymPy's \
         `count_ops(cse([M, F]))`), \"solve\" that of the emitted solve (LDL^T for Maggi, Kane and the reduced method; the worst case of LU with partial pivoting for Lagrange).\n\n",
        pendulum, floating, planar
    );
    md += &goals(measured);
    if !measured.sympy_checks.is_empty() {
        let checks: Vec<String> = measured.sympy_checks.iter().map(|(model, error)| format!("{model} {error:.1e}")).collect();
        md += &format!(
            "SymPy's models (`docs/scaling/sympy_kane.py`) derive the same equations as ours, checked in this run before their times are compared: \
             the accelerations `q''` at a random state consistent with the constraints, every parameter moved off its value, differ from ours by at most \
             (relative to the largest `|q''|`): {}.\n\n",
            checks.join(", ")
        );
    }
    let title = |k: &str| match k {
        "pendulum" => "The n-link pendulum on a cart (s = 1)",
        "floating" => "The spatial chain on a floating base (s = 3)",
        _ => "The planar free chain of n rods in absolute angles (s = 2)",
    };
    for kind in KINDS {
        md += &format!("## {}\n\n", title(kind));
        md += "| n | derive ms (mechanics / ignorable / kane / reduced / formulations / trees / hand-off) | emit ms after the derivation | CPU s | peak MB | assembly ops: lagrange / maggi / kane / reduced | solve ops: kane / reduced | module KB | rustc s | ns per call: lagrange / maggi / kane / reduced | in-process (JIT) / compiled, per call | simplifier: million term products, nodes over the term limit |\n";
        md += "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
        for r in records.iter().filter(|r| r.model == kind) {
            let stages: Vec<String> = r.stages_ms.iter().map(|(_, v)| format!("{v:.0}")).collect();
            let asm: Vec<String> = FORMS.iter().map(|f| ops_of(r, f).map_or("-".into(), |(a, _)| a.to_string())).collect();
            let solve: Vec<String> = ["kane", "reduced_volterra"].iter().map(|f| ops_of(r, f).map_or("-".into(), |(_, s)| s.to_string())).collect();
            let ns: Vec<String> = FORMS.iter().map(|f| r.ns_per_call.iter().find(|(n, _)| n == f).map_or("-".into(), |(_, v)| format!("{v:.0}"))).collect();
            let jit: Vec<String> = jit_ratios(r).iter().map(|x| format!("{x:.2}")).collect();
            md += &format!(
                "| {} | {:.0} ({}) | {:.0} | {:.2} | {:.0} | {} | {} | {:.0} | {} | {} | {} | {} |\n",
                r.n,
                r.derive_ms,
                stages.join(" / "),
                r.emit_ms,
                r.cpu_s,
                r.peak_mb,
                asm.join(" / "),
                solve.join(" / "),
                r.code_bytes as f64 / 1024.0,
                r.rustc_s.map_or("-".into(), |s| format!("{s:.1}")),
                ns.join(" / "),
                if jit.is_empty() { "-".to_string() } else { jit.join(" / ") },
                simplifier_cell(r.simplifier),
            );
        }
        if let Some((_, peer)) = peers.iter().find(|(k, _)| k == kind) {
            md += "\nSymPy's `KanesMethod` on the same model, in the same run (`docs/scaling/sympy_kane.py`):\n\n";
            md += "| n | SymPy derive + cse s | ours derive + emit s | ratio (SymPy / ours) | SymPy assembly ops | our Kane assembly ops | ratio (ours / SymPy) |\n|---|---|---|---|---|---|---|\n";
            for p in peer {
                if let Some(r) = records.iter().find(|r| r.model == kind && r.n == p.n) {
                    let ours = (r.derive_ms + r.emit_ms) / 1e3;
                    let theirs = p.derive_seconds + p.cse_seconds;
                    let kane = ops_of(r, "kane").map_or(0, |(a, _)| a);
                    md += &format!(
                        "| {} | {:.2} | {:.3} | {:.1} | {} | {} | {:.2} |\n",
                        p.n,
                        theirs,
                        ours,
                        theirs / ours,
                        p.assembly_ops,
                        kane,
                        kane as f64 / p.assembly_ops as f64
                    );
                }
            }
        }
        md += "\n";
    }
    md += "![scaling](plots/scaling.svg)\n";
    md
}

fn plot(path: &Path, records: &[Record], peers: &[(String, Vec<SympyRecord>)]) {
    let root = SVGBackend::new(path, (1000, 420)).into_drawing_area();
    root.fill(&WHITE).expect("a white background");
    let (left, right) = root.split_horizontally(500);
    let colors = [RGBColor(31, 119, 180), RGBColor(255, 127, 14), RGBColor(44, 160, 44), RGBColor(214, 39, 40), RGBColor(148, 103, 189)];
    let mut series_time: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    let mut series_ops: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for kind in KINDS {
        let rs: Vec<&Record> = records.iter().filter(|r| r.model == kind).collect();
        series_time.push((format!("ours, {kind}"), rs.iter().map(|r| (r.n as f64, (r.derive_ms + r.emit_ms) / 1e3)).collect()));
        series_ops.push((format!("ours (Kane), {kind}"), rs.iter().filter_map(|r| ops_of(r, "kane").map(|(a, _)| (r.n as f64, a as f64))).collect()));
        if let Some((_, p)) = peers.iter().find(|(k, _)| k == kind) {
            series_time.push((format!("SymPy, {kind}"), p.iter().map(|x| (x.n as f64, x.derive_seconds + x.cse_seconds)).collect()));
            series_ops.push((format!("SymPy, {kind}"), p.iter().map(|x| (x.n as f64, x.assembly_ops as f64)).collect()));
        }
    }
    for (area, title, ylabel, series) in [(&left, "derive + emit time", "s", &series_time), (&right, "assembly operations", "ops", &series_ops)] {
        let pts: Vec<(f64, f64)> = series.iter().flat_map(|(_, s)| s.iter().copied()).filter(|(_, y)| *y > 0.0).collect();
        if pts.is_empty() {
            continue;
        }
        let (x0, x1) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), (x, _)| (a.min(*x), b.max(*x)));
        let (y0, y1) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), (_, y)| (a.min(*y), b.max(*y)));
        let mut chart = ChartBuilder::on(area)
            .caption(title, ("sans-serif", 16))
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(60)
            .build_cartesian_2d((x0 / 1.2..x1 * 1.2).log_scale(), (y0 / 2.0..y1 * 2.0).log_scale())
            .expect("a chart");
        chart
            .configure_mesh()
            .x_desc("n")
            .y_desc(ylabel)
            .x_label_formatter(&|x| format!("{x:.0}"))
            .y_label_formatter(&|y| if *y >= 1.0 { format!("{y:.0}") } else { format!("{y}") })
            .draw()
            .expect("the mesh");
        for (k, (name, s)) in series.iter().enumerate() {
            let color = colors[k % colors.len()];
            let points: Vec<(f64, f64)> = s.iter().copied().filter(|(_, y)| *y > 0.0).collect();
            chart
                .draw_series(LineSeries::new(points.clone(), color.stroke_width(2)))
                .expect("a series")
                .label(name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color));
            chart.draw_series(points.into_iter().map(|p| Circle::new(p, 3, color.filled()))).expect("the points");
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperLeft)
            .draw()
            .expect("the legend");
    }
    root.present().expect("the plot is written");
}
