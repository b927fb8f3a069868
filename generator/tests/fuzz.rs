//! A seeded mutation fuzzer over the model loader, the expression parser and the whole
//! generator, run in-process on stable Rust: every file of `models/` is mutated (bytes deleted,
//! duplicated or replaced, tokens of the format inserted, numbers and names swapped, lines
//! shuffled, the file cut short, expressions nested thousands deep, extreme run settings), under
//! file names with control characters and a node budget small enough to be reached, and every
//! mutant must give either a located error (file, line and column, a fix; the node budget's
//! error names the budget instead) with no control character in it, or a module that parses as
//! Rust with only finite numbers and no control character in it (the first few distinct ones
//! are compiled by rustc, warnings denied), whose in-process evaluation computes every
//! formulation's first right-hand side as finite numbers or a typed failure. A panic fails the
//! test with the mutant that caused it, written to a file to replay.
//!
//! `cargo test --release -p generator --test fuzz` runs the short pass CI runs;
//! `FUZZ_MUTANTS=20000 FUZZ_SEED=7 cargo test --release -p generator --test fuzz -- --nocapture`
//! runs a longer one. The count of mutants is the budget: no wall-clock limit.

use generator::emit::Options;

use generator::generate;

mod support {
    pub mod rustc;
}
use generator::model::from_source;
use std::panic::{AssertUnwindSafe, catch_unwind};

/// SplitMix64: a small seeded generator, the same sequence on every machine.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Pieces of the format and of expressions, and values at the edges.
const TOKENS: &[&str] = &[
    "(",
    ")",
    "[",
    "]",
    "{",
    "}",
    ",",
    ":",
    "\"",
    "'",
    "''",
    "^",
    "*",
    "/",
    "-",
    "+",
    "0",
    "1e999",
    "1e-400",
    "-0",
    "1e308",
    "NaN",
    "inf",
    "9999999999999999999999",
    "sin(",
    "cos(",
    "sqrt(",
    "ln(",
    "abs(",
    "t",
    "pi",
    "theta1",
    "x",
    "l",
    "_",
    "u1",
    "G_x",
    "world",
    "Frame(name: \"f\", parent: \"world\")",
    "Z(\"x\")",
    "Body(",
    "PointMass",
    "Declared([\"x\"])",
    "Auto",
    "Velocity(name: \"c\", expr: \"x'\")",
    "Position(name: \"p\", expr: \"x\")",
    "^1000",
    "/0",
    "\u{feff}",
    "\u{e9}",
    "\n",
    " ",
];

fn mutate(src: &str, rng: &mut Rng) -> String {
    let mut s: Vec<char> = src.chars().collect();
    for _ in 0..1 + rng.below(3) {
        let n = s.len().max(1);
        let at = rng.below(n);
        match rng.below(10) {
            // Delete a short range.
            0 => {
                let end = (at + 1 + rng.below(12)).min(s.len());
                s.drain(at.min(s.len())..end);
            }
            // Duplicate a range.
            1 => {
                let end = (at + 1 + rng.below(40)).min(s.len());
                let piece: Vec<char> = s[at.min(s.len())..end].to_vec();
                let to = rng.below(s.len() + 1);
                s.splice(to..to, piece);
            }
            // Insert a token.
            2 | 3 => {
                let t: Vec<char> = TOKENS[rng.below(TOKENS.len())].chars().collect();
                let to = rng.below(s.len() + 1);
                s.splice(to..to, t);
            }
            // Replace a character with a token.
            4 => {
                if at < s.len() {
                    let t: Vec<char> = TOKENS[rng.below(TOKENS.len())].chars().collect();
                    s.splice(at..at + 1, t);
                }
            }
            // Replace a digit run with an extreme number.
            5 => {
                if let Some(p) = (at..s.len()).find(|&i| s[i].is_ascii_digit()) {
                    let end = (p..s.len()).find(|&i| !s[i].is_ascii_digit() && s[i] != '.').unwrap_or(s.len());
                    let v: Vec<char> = ["0", "1e300", "-5", "0.000000001", "1e-320", "123456789012345678901234567890"][rng.below(6)].chars().collect();
                    s.splice(p..end, v);
                }
            }
            // Swap two lines.
            6 => {
                let text: String = s.iter().collect();
                let mut lines: Vec<&str> = text.lines().collect();
                if lines.len() > 2 {
                    let (a, b) = (rng.below(lines.len()), rng.below(lines.len()));
                    lines.swap(a, b);
                }
                s = lines.join("\n").chars().collect();
            }
            // Nest an expression deep (beyond the parser's depth limit at times).
            7 => {
                let depth = [20, 200, 1500, 2500][rng.below(4)];
                let f = ["sin(", "sqrt(", "(1+", "abs("][rng.below(4)];
                let nested: Vec<char> = format!("{}x{}", f.repeat(depth), ")".repeat(depth)).chars().collect();
                if let Some(p) = (at..s.len()).find(|&i| s[i] == '"') {
                    s.splice(p + 1..p + 1, nested);
                }
            }
            // Extreme run settings.
            8 => {
                let text: String = s.iter().collect();
                if let Some(p) = text.find("simulation:") {
                    let values = ["1e300", "1e-300", "0", "-1", "1e7", "0.01", "1e-9", "5e-324", "1e308"];
                    let (a, b) = (values[rng.below(values.len())], values[rng.below(values.len())]);
                    let end = text[p..].find(")").map_or(text.len(), |e| p + e + 1);
                    let replaced = format!("{}simulation: Simulation(t_end: {a}, dt_out: {b}){}", &text[..p], &text[end..]);
                    s = replaced.chars().collect();
                }
            }
            // Cut the file short.
            _ => s.truncate(at),
        }
    }
    s.into_iter().collect()
}

/// What happened to one mutant.
enum Outcome {
    Refused,
    Generated(String),
}

/// Compiles an emitted module on its own (against the seam crate), warnings denied.
fn compiles(code: &str, tag: usize) -> Result<(), String> {
    let dir = std::env::temp_dir().join(format!("fuzz-compile-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("module.rs");
    std::fs::write(&file, format!("#![deny(warnings)]\n#![allow(clippy::all)]\n{code}")).unwrap();
    let out = support::rustc::rustc().args(["--crate-type", "lib", "-C", "opt-level=0", "--out-dir"]).arg(&dir).arg(&file).output().unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    if out.status.success() { Ok(()) } else { Err(format!("emitted code does not compile:\n{}", String::from_utf8_lossy(&out.stderr))) }
}

/// File names a mutant is loaded under: control characters must reach no error and no module.
const FILES: &[&str] = &["models/mutant.ron", "models/mu\ntant.ron", "models/\u{1b}[31mred\u{1b}[0m.ron", "models/tab\there\r.ron", "models/ünïcode.ron"];

/// True when `text` holds a control character other than a line break.
fn has_control(text: &str) -> bool {
    text.chars().any(|c| c.is_control() && c != '\n')
}

/// The in-process evaluation of a generated mutant: every formulation's first right-hand side
/// is finite or a typed failure (any panic is caught by the caller).
fn evaluate_first_step(model: &generator::model::Model) -> Result<(), String> {
    let Ok(evaluated) = generator::evaluate(model) else { return Err("generated, but the in-process evaluation failed".into()) };
    let Some((q0, qd0)) = evaluated.initial.clone() else { return Ok(()) };
    for form in &evaluated.formulations {
        let mut state = vec![0.0; form.states()];
        let mut g_i = vec![0.0; evaluated.ignorable.len()];
        if form.initial_state(0.0, &q0, &qd0, &evaluated.default_params, &mut state, &mut g_i).is_err() {
            continue;
        }
        let mut rate = vec![0.0; state.len()];
        if form.rhs(0.0, &state, &evaluated.default_params, &g_i, &mut rate).is_ok() && rate.iter().any(|x| !x.is_finite()) {
            return Err(format!("{}: the in-process right-hand side returned a non-finite number without a failure", form.kind.name()));
        }
    }
    Ok(())
}

/// Loads and generates `text` under the name `file`, checking the contract; `Err` describes a
/// violation.
fn run_one(text: &str, file: &str, evaluate: bool) -> Result<Outcome, String> {
    let result = catch_unwind(AssertUnwindSafe(|| match from_source(file, text) {
        Err(e) => Err(e),
        Ok(model) => generate(&model, &Options::from_model(&model)).map(|g| (g.code, evaluate.then(|| evaluate_first_step(&model)))),
    }));
    match result {
        Err(panic) => {
            let msg = panic.downcast_ref::<String>().cloned().or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()));
            Err(format!("panicked: {}", msg.unwrap_or_default()))
        }
        Ok(Err(e)) => {
            let shown = e.to_string();
            if !shown.starts_with(&format!("error: {}", files::printable(file))) || !shown.contains("help: ") {
                return Err(format!("an error without the file or a fix: {shown}"));
            }
            if has_control(&shown) || has_control(&e.render(false)) {
                return Err(format!("an error with a control character in it: {shown:?}"));
            }
            if e.kind == generator::model::ErrorKind::Budget {
                return if shown.contains("--max-nodes") { Ok(Outcome::Refused) } else { Err(format!("a budget error that names no budget: {shown}")) };
            }
            if std::env::var_os("FUZZ_SHOW_UNLOCATED").is_some() && e.location.is_none() {
                eprintln!("unlocated: {shown}");
            }
            if e.location.is_none() {
                return Err(format!("an error without line and column: {shown}"));
            }
            if shown.len() > 2000 {
                return Err(format!("an error of {} bytes", shown.len()));
            }
            Ok(Outcome::Refused)
        }
        Ok(Ok((code, evaluated))) => {
            syn::parse_file(&code).map_err(|e| format!("emitted code does not parse: {e}"))?;
            if code.contains("NAN") || code.contains("INFINITY") && !code.contains("f64::INFINITY") {
                return Err("emitted code holds a non-finite number".into());
            }
            if has_control(&code) {
                return Err("emitted code holds a control character".into());
            }
            evaluated.unwrap_or(Ok(()))?;
            Ok(Outcome::Generated(code))
        }
    }
}

#[test]
fn mutated_models_give_a_located_error_or_a_module() {
    let mutants: usize = std::env::var("FUZZ_MUTANTS").ok().and_then(|v| v.parse().ok()).unwrap_or(300);
    let seed: u64 = std::env::var("FUZZ_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(2026);
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../models");
    let mut sources: Vec<(String, String)> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().extension().is_some_and(|x| x == "ron"))
        .map(|e| (e.file_name().to_string_lossy().into_owned(), std::fs::read_to_string(e.path()).unwrap()))
        .collect();
    sources.sort();
    // The big scenes cost the most per mutant; the small ones find most of the parser's cases.
    sources.retain(|(name, _)| name != "pendulum_on_cart_5.ron" && name != "bicycle.ron");
    // An 8 MB stack, as the command line's main thread has.
    let report = std::thread::Builder::new()
        .stack_size(8 << 20)
        .spawn(move || {
            let mut rng = Rng(seed);
            let (mut refused, mut generated) = (0, 0);
            // The first few distinct modules are compiled too (rustc costs about a second each).
            let compile_budget: usize = std::env::var("FUZZ_COMPILE").ok().and_then(|v| v.parse().ok()).unwrap_or(3);
            let mut compiled: Vec<String> = Vec::new();
            // A panic inside is caught and reported; keep the default hook quiet meanwhile.
            std::panic::set_hook(Box::new(|_| {}));
            // A budget the nested expressions reach (this test binary runs nothing else).
            generator::symbolic::set_max_nodes(200_000);
            for i in 0..mutants {
                let (name, src) = &sources[i % sources.len()];
                let text = mutate(src, &mut rng);
                let file = FILES[rng.below(FILES.len())];
                // One in four generated mutants is evaluated in-process too.
                let evaluate = rng.below(4) == 0;
                match run_one(&text, file, evaluate) {
                    Ok(Outcome::Refused) => refused += 1,
                    Ok(Outcome::Generated(code)) => {
                        generated += 1;
                        let result = if compiled.len() < compile_budget && !compiled.contains(&code) {
                            compiled.push(code.clone());
                            compiles(&code, i)
                        } else {
                            Ok(())
                        };
                        if let Err(why) = result {
                            let _ = std::panic::take_hook();
                            let replay = std::env::temp_dir().join(format!("fuzz-mutant-{seed}-{i}.ron"));
                            std::fs::write(&replay, &text).unwrap();
                            panic!("mutant {i} of {name} (seed {seed}): {why}\nreplay: {}", replay.display());
                        }
                    }
                    Err(why) => {
                        let _ = std::panic::take_hook();
                        let replay = std::env::temp_dir().join(format!("fuzz-mutant-{seed}-{i}.ron"));
                        std::fs::write(&replay, &text).unwrap();
                        panic!("mutant {i} of {name} (seed {seed}): {why}\nreplay: {}", replay.display());
                    }
                }
            }
            let _ = std::panic::take_hook();
            (refused, generated, compiled.len())
        })
        .unwrap()
        .join();
    let (refused, generated, compiled) = report.unwrap_or_else(|e| std::panic::resume_unwind(e));
    eprintln!("fuzz: {mutants} mutants (seed {seed}): {refused} refused with a located error, {generated} generated ({compiled} compiled)");
    assert_eq!(refused + generated, mutants);
    // The mutations must reach both sides, or they test nothing.
    assert!(refused > mutants / 4 && generated > 0, "refused {refused}, generated {generated}");
    assert!(compiled > 0, "no generated mutant was compiled");
}
