//! Robots at their real size (the issue "Robots", item 3): each robot of example-robot-data read
//! from its URDF, derived and made ready to evaluate in-process (the JIT), in all four
//! formulations as `multibody compare robot.urdf` does, and in the one `multibody simulate
//! robot.urdf` runs (the reduced method, derived alone); and its emitted modules built by rustc
//! (the four formulations, and the one `simulate --compiled` builds). Each robot runs in a child process
//! of its own (this program, re-invoked), so its CPU time and peak memory are its own. Writes
//! `docs/robots/derive.json`; `docs/robots.md` quotes it.
//!
//! ```sh
//! pip install example-robot-data                 # the robots (outside CI)
//! cargo bench --bench robots                     # every robot, rustc included
//! cargo bench --bench robots -- --robots ur5,talos_reduced --no-rustc
//! ```

#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

#[path = "support/robots.rs"]
mod robots;
use robots::ROBOTS;

/// Fresh processes per robot; the median CPU and the largest peak are reported.
const RUNS: usize = 3;

#[derive(serde::Serialize, serde::Deserialize, Clone, Debug, Default)]
struct Record {
    robot: String,
    base: String,
    coordinates: usize,
    /// Load, derive, emit the tapes, compile them by the JIT: ready to evaluate.
    cpu_s: f64,
    peak_mb: f64,
    /// The emitted module's build by rustc (a library, as `--compiled` builds it).
    rustc_s: Option<f64>,
    code_bytes: usize,
    /// The same for the one formulation `simulate` derives (the default one).
    #[serde(default)]
    simulate_cpu_s: f64,
    #[serde(default)]
    simulate_peak_mb: f64,
    /// The module `simulate --compiled` builds (that formulation alone) by rustc.
    #[serde(default)]
    simulate_rustc_s: Option<f64>,
    #[serde(default)]
    simulate_code_bytes: usize,
}

/// example-robot-data's robots folder: `--robots-dir`, else found in a Python environment.
fn robots_folder(given: Option<PathBuf>) -> PathBuf {
    if let Some(dir) = given {
        return dir;
    }
    let out = Command::new("python3")
        .args(["-c", "import sys, pathlib; print(next(str(p) for p in (pathlib.Path(s) / 'cmeel.prefix/share/example-robot-data/robots' for s in sys.path) if p.is_dir()))"])
        .output();
    match out {
        Ok(o) if o.status.success() => PathBuf::from(String::from_utf8_lossy(&o.stdout).trim()),
        _ => panic!("example-robot-data not found: pip install example-robot-data, or give --robots-dir DIR"),
    }
}

/// CPU (user + system) and peak resident memory of this process so far.
fn usage() -> (f64, f64) {
    // SAFETY: getrusage writes the struct it is given.
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut u) };
    let cpu = u.ru_utime.tv_sec as f64 + u.ru_utime.tv_usec as f64 * 1e-6 + u.ru_stime.tv_sec as f64 + u.ru_stime.tv_usec as f64 * 1e-6;
    (cpu, u.ru_maxrss as f64 / 1024.0)
}

/// The child: one robot, ready to evaluate, its figures as JSON on stdout.
fn child(path: &Path, base: &str, rustc: bool, one: bool) {
    use generator::model::{Base, UrdfOptions};
    let options = UrdfOptions { base: if base == "floating" { Base::Floating } else { Base::Fixed }, ..UrdfOptions::default() };
    let model = load::model_with(path, &options).unwrap();
    let only = one.then(|| load::default_formulation(&model));
    let loaded = load::evaluate_only(&model, only, load::Jacobians::Differenced, load::Route::Jit, &mut |_| {}).unwrap();
    // Ready: one right-hand side evaluated.
    let m = &loaded.model;
    let (q, qd) = m.initial.clone().unwrap();
    let (sys, y) = runtime::system::System::start(m, m.default_kind(), m.default_params.clone(), &q, &qd).unwrap();
    let mut dy = vec![0.0; y.len()];
    sys.rhs(0.0, &y, &mut dy).unwrap();
    let (cpu, peak) = usage();
    let mut record = Record { robot: String::new(), base: base.into(), coordinates: m.coordinates.len(), cpu_s: cpu, peak_mb: peak, ..Record::default() };
    // The module `--compiled` builds: the formulation `simulate` runs alone, or all four.
    let mut options = generator::emit::Options::from_model(&model);
    if let Some(kind) = only {
        options.formulations = vec![generator::emit::Formulation::of(kind)];
    }
    let generated = generator::generate(&model, &options).unwrap();
    let built = rustc.then(|| {
        let cache = tempfile::tempdir().unwrap();
        let start = Instant::now();
        native::build(&generated.code, cache.path(), &mut |_| {}).unwrap();
        start.elapsed().as_secs_f64()
    });
    if one {
        (record.simulate_code_bytes, record.simulate_rustc_s) = (generated.code.len(), built);
    } else {
        (record.code_bytes, record.rustc_s) = (generated.code.len(), built);
    }
    println!("{}", serde_json::to_string(&record).unwrap());
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let value = |flag: &str| args.iter().position(|a| a == flag).and_then(|i| args.get(i + 1)).cloned();
    if let Some(path) = value("--child") {
        child(Path::new(&path), &value("--base").unwrap(), !args.iter().any(|a| a == "--no-rustc"), args.iter().any(|a| a == "--one"));
        return;
    }
    let folder = robots_folder(value("--robots-dir").map(PathBuf::from));
    let only: Option<Vec<String>> = value("--robots").map(|s| s.split(',').map(str::to_string).collect());
    let out = value("--out").map(PathBuf::from).unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/robots/derive.json"));
    let no_rustc = args.iter().any(|a| a == "--no-rustc");
    let mut records = Vec::new();
    for (name, file, base) in ROBOTS {
        if only.as_ref().is_some_and(|o| !o.iter().any(|n| n == name)) {
            continue;
        }
        // All four formulations, then (`--one`) the one `simulate` derives.
        let mut runs: Vec<Record> = (0..2 * RUNS)
            .map(|k| {
                let mut cmd = Command::new(std::env::current_exe().unwrap());
                cmd.args(["--child", folder.join(file).to_str().unwrap(), "--base", base]);
                // rustc once per robot and module: its time does not depend on the run.
                if no_rustc || (k != 0 && k != RUNS) {
                    cmd.arg("--no-rustc");
                }
                if k >= RUNS {
                    cmd.arg("--one");
                }
                let o = cmd.output().unwrap();
                assert!(o.status.success(), "{name}: {}", String::from_utf8_lossy(&o.stderr));
                let mut r: Record = serde_json::from_slice(&o.stdout).unwrap();
                r.robot = name.into();
                eprintln!(
                    "  {name} run {}: {:.2} s CPU, {:.0} MB{}",
                    k + 1,
                    r.cpu_s,
                    r.peak_mb,
                    r.rustc_s.or(r.simulate_rustc_s).map_or(String::new(), |s| format!(", rustc {s:.1} s"))
                );
                r
            })
            .collect();
        let mut one = runs.split_off(RUNS);
        runs.sort_by(|a, b| a.cpu_s.total_cmp(&b.cpu_s));
        one.sort_by(|a, b| a.cpu_s.total_cmp(&b.cpu_s));
        let mut record = runs[RUNS / 2].clone();
        record.peak_mb = runs.iter().map(|r| r.peak_mb).fold(0.0, f64::max);
        record.rustc_s = runs.iter().find_map(|r| r.rustc_s);
        record.simulate_cpu_s = one[RUNS / 2].cpu_s;
        record.simulate_peak_mb = one.iter().map(|r| r.peak_mb).fold(0.0, f64::max);
        record.simulate_rustc_s = one.iter().find_map(|r| r.simulate_rustc_s);
        record.simulate_code_bytes = one.iter().map(|r| r.simulate_code_bytes).max().unwrap_or(0);
        records.push(record);
    }
    let json = serde_json::json!({
        "command": "cargo bench --bench robots",
        "cores": std::thread::available_parallelism().map_or(1, |n| n.get()),
        "about": "each robot of example-robot-data from its URDF, loaded, derived and ready to evaluate in-process (JIT): CPU time (median of 3 fresh processes) and peak memory (the largest), in all four formulations (cpu_s, peak_mb) and in the one simulate derives (simulate_cpu_s, simulate_peak_mb); the emitted module's build by rustc, with the four formulations (rustc_s, code_bytes) and with the one simulate --compiled builds (simulate_rustc_s, simulate_code_bytes)",
        "records": records,
    });
    std::fs::create_dir_all(out.parent().unwrap()).unwrap();
    std::fs::write(&out, serde_json::to_string_pretty(&json).unwrap() + "\n").unwrap();
    eprintln!("wrote {}", out.display());
}
