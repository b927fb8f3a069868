//! An emitted module compiled on its own with a program that times each formulation's `rhs`
//! at the model's initial state: the best, over 7 rounds, of the mean time of 200 calls. Shared
//! by the scaling and the Pinocchio benchmarks (`#[path]`), so both time the same way.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

#[path = "../../tests/support/rustc.rs"]
mod rustc_support;

/// The formulations, in the order the timing program prints them.
pub const FORMS: [&str; 4] = ["lagrange", "maggi", "kane", "reduced_volterra"];

/// The timing program's clock: cycles per nanosecond from a chain of dependent register
/// additions (one cycle each on every x86-64), 4 x 2,000,000 of them, the best of 7 rounds;
/// 0 elsewhere. Read in the same process as the calls it converts to cycles.
const CLOCK: &str = r#"fn clock_ghz() -> f64 {
    #[cfg(target_arch = "x86_64")]
    {
        let mut best = 0.0f64;
        for _ in 0..7 {
            let n: u64 = 2_000_000;
            let (mut x, mut i, one) = (0u64, n, std::hint::black_box(1u64));
            let t = Instant::now();
            unsafe {
                std::arch::asm!("2:", "add {x}, {one}", "add {x}, {one}", "add {x}, {one}", "add {x}, {one}", "dec {i}", "jnz 2b",
                    x = inout(reg) x, i = inout(reg) i, one = in(reg) one, options(nomem, nostack));
            }
            std::hint::black_box((x, i));
            best = best.max(4.0 * n as f64 / (t.elapsed().as_secs_f64() * 1e9));
        }
        best
    }
    #[cfg(not(target_arch = "x86_64"))]
    0.0
}
"#;

/// A program that times each formulation's `rhs` at the model's initial state.
fn timing_program() -> String {
    let mut s = String::from(
        "#[allow(dead_code, non_snake_case, clippy::all)]\n#[path = \"model.rs\"]\nmod model;\nuse std::time::Instant;\n\
         fn time<F: FnMut()>(mut f: F) -> f64 {\n    let mut best = f64::INFINITY;\n    for _ in 0..7 {\n        let n = 200;\n        let t = Instant::now();\n        for _ in 0..n { f(); }\n        best = best.min(t.elapsed().as_secs_f64() * 1e9 / n as f64);\n    }\n    best\n}\n",
    );
    s += CLOCK;
    s += "fn main() {\n    println!(\"clock_ghz {}\", clock_ghz());\n    let p = model::Params::default();\n";
    for f in FORMS {
        s += &format!(
            "    {{\n        let (state, g) = model::{f}::initial_state(0.0, &model::INITIAL_Q, &model::INITIAL_QDOT, &p).unwrap();\n        let mut d = [0.0; model::{f}::STATES];\n        let ns = time(|| {{ model::{f}::rhs(0.0, std::hint::black_box(&state), &p, &g, &mut d).unwrap(); std::hint::black_box(&d); }});\n        println!(\"{f} {{ns}}\");\n    }}\n"
        );
    }
    s + "}\n"
}

/// Writes `code` (an emitted module) and the timing program into `dir` and compiles them
/// (`rustc -C opt-level=3`, plain x86-64); the program's path and rustc's seconds.
pub fn compile(dir: &Path, code: &str) -> (PathBuf, f64) {
    compile_with(dir, code, &[])
}

/// [`compile`] with more rustc flags (`-C target-cpu=native`).
pub fn compile_with(dir: &Path, code: &str, flags: &[&str]) -> (PathBuf, f64) {
    std::fs::create_dir_all(dir).expect("a scratch directory");
    std::fs::write(dir.join("model.rs"), code).expect("the module is written");
    std::fs::write(dir.join("main.rs"), timing_program()).expect("the timing program is written");
    rustc_support::seam_rlib(); // built once, outside the timing
    let exe = dir.join("timing");
    let start = Instant::now();
    let status = rustc_support::rustc().args(["-C", "opt-level=3"]).args(flags).arg("-o").arg(&exe).arg(dir.join("main.rs")).status().expect("rustc runs");
    let seconds = start.elapsed().as_secs_f64();
    assert!(status.success(), "the emitted module compiles");
    (exe, seconds)
}

/// One run of a compiled timing program: the clock it read (cycles per nanosecond, 0 where it
/// cannot) and ns per call, per formulation.
pub fn run(exe: &Path) -> (f64, Vec<(String, f64)>) {
    let run = Command::new(exe).output().expect("the timing program runs");
    let mut clock = 0.0;
    let mut calls = Vec::new();
    for (name, value) in String::from_utf8_lossy(&run.stdout).lines().filter_map(|line| line.split_once(' ')) {
        let value = value.parse().unwrap_or(f64::NAN);
        match name {
            "clock_ghz" => clock = value,
            f => calls.push((f.to_string(), value)),
        }
    }
    (clock, calls)
}
