//! The README's and the docs' figures cannot drift: every table and number they quote from a
//! measurement is checked here against the file the measurement writes, and the files'
//! reproducible numbers against what a run gives now.
//!
//! - the first build: `docs/benchmarks/first_build.json` (`docs/benchmarks/first_build.sh`);
//! - the scene tables: `docs/comparisons/<scene>.json`, written by
//!   `cargo run --release -p generated --example compare -- <scene> --repeats 11` (scenes 2
//!   and 3 in quaternions: the tables and ratios of `docs/attitude.md`);
//! - the in-process figures: `docs/benchmarks/eval.json` (`cargo bench -p generated --bench eval`);
//! - the scaling figures: `docs/scaling/ours.json`, `docs/scaling/sympy.json` and the tables of
//!   `docs/scaling.md` (`cargo bench --bench scaling -- --sympy`);
//! - every other table of `docs/benchmarks.md`: `docs/benchmarks/<table>.json`, each holding the
//!   command that writes it, its columns and its rows (Pinocchio's beside ours:
//!   `cargo bench -p generator --bench pinocchio`, outside CI);
//! - the goals of `docs/goals.md`: `docs/benchmarks/pinocchio.json`, each verdict from its figures.

use runtime::compare::{Options, Record, compare, table_of};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const SCENES: [&str; 3] = ["cart_pendulum", "three_body", "satellite_boom"];

fn read(path: &str) -> String {
    std::fs::read_to_string(format!("{ROOT}/{path}")).unwrap_or_else(|e| panic!("{path}: {e}"))
}

fn json(path: &str) -> serde_json::Value {
    serde_json::from_str(&read(path)).unwrap()
}

fn records(scene: &str) -> Vec<Record> {
    serde_json::from_str(&read(&format!("docs/comparisons/{scene}.json"))).unwrap()
}

fn assert_quoted(text: &str, figure: &str, source: &str) {
    assert!(text.contains(figure), "the page does not quote `{figure}` from {source}");
}

/// Seconds as the README writes a wait: "2 min 58 s", or "45 s".
fn minutes(seconds: f64) -> String {
    let s = seconds.round() as u64;
    if s < 60 { format!("{s} s") } else { format!("{} min {} s", s / 60, s % 60) }
}

/// The README's first-build times are the file the script writes from a fresh clone.
#[test]
fn the_first_build_figures_are_the_script_file() {
    let file = json("docs/benchmarks/first_build.json");
    let readme = read("README.md");
    for command in ["main_job", "tests"] {
        let written = file[command].as_str().unwrap();
        assert!(readme.contains(&format!("\n{written}\n")), "the README's commands are not the timed `{written}`");
    }
    let (main, tests) = (file["main_job_seconds"].as_f64().unwrap(), file["tests_seconds"].as_f64().unwrap());
    let said = format!("the first command takes {}, the first build included, then the tests {}", minutes(main), minutes(tests));
    assert_quoted(&readme, &said, "docs/benchmarks/first_build.json");
    assert_quoted(&readme, &format!("{} cores", file["cores"]), "docs/benchmarks/first_build.json");
}

/// `watch`'s figures in docs/tool.md are those `cargo bench --bench watch` wrote, with the
/// verdict of the goal (under a second from a save, on the paper's scenes).
#[test]
fn the_watch_figures_are_the_benchmark_file() {
    let file = json("docs/benchmarks/watch.json");
    let docs = read("docs/tool.md");
    let records = file["records"].as_array().unwrap();
    assert_eq!(records.len(), 3, "the paper's three scenes");
    let said: Vec<String> = records
        .iter()
        .map(|r| format!("`{}` {:.2} s ({:.2} s at most)", r["scene"].as_str().unwrap(), r["median_s"].as_f64().unwrap(), r["max_s"].as_f64().unwrap()))
        .collect();
    assert_quoted(&docs, &said.join(", "), "docs/benchmarks/watch.json");
    let met = records.iter().all(|r| r["max_s"].as_f64().unwrap() < 1.0);
    assert_quoted(&docs, &format!("under one second from a save: {}", if met { "met" } else { "missed" }), "docs/benchmarks/watch.json");
}

/// The page's frame rates in docs/tool.md are the page benchmark's file, and the goal's verdict
/// follows from it.
#[test]
fn the_page_figures_are_the_benchmark_file() {
    let file = json("docs/benchmarks/page.json");
    // Lines wrap where they will: the figures are read as words.
    let docs = read("docs/tool.md").split_whitespace().collect::<Vec<_>>().join(" ");
    let fps = |name: &str| file["results"][name]["frames_per_second"].as_f64().unwrap();
    let script = |name: &str| file["results"][name]["script_median_ms"].as_f64().unwrap();
    let cases = ["carousel_40_capsules", "carousel_40_meshes", "pendulum_on_cart_39"];
    for (said, name) in ["40 capsules", "40 STL meshes", "the 39-link pendulum on a cart's 40 inertia cubes"].iter().zip(cases) {
        assert_quoted(&docs, &format!("{said} {:.1} frames per second", fps(name)), "docs/benchmarks/page.json");
    }
    assert_quoted(&docs, &format!("antialiasing asked for, {:.1} frames per second", fps("carousel_40_capsules_antialiased")), "docs/benchmarks/page.json");
    let scripts = format!("{:.1} ms (capsules), {:.1} ms (meshes) and {:.1} ms (cubes)", script(cases[0]), script(cases[1]), script(cases[2]));
    assert_quoted(&docs, &scripts, "docs/benchmarks/page.json");
    let display = file["display_frames_per_second"].as_f64().unwrap();
    assert_quoted(&docs, &format!("an empty page plays at {display:.1} frames per second"), "docs/benchmarks/page.json");
    let empty = file["empty_layers_frames_per_second"].as_f64().unwrap();
    assert_quoted(&docs, &format!("nothing drawn, at {empty:.1}."), "docs/benchmarks/page.json");
    // The goal is met by the page as it draws by default: every model at 95 % of the display's
    // rate (57 of 60), measured in the same run.
    let met = cases.iter().all(|name| fps(name) >= 0.95 * display);
    assert_quoted(
        &docs,
        &format!("60 frames per second for 40 bodies (95 % of the display's rate, each model): {}", if met { "met" } else { "missed" }),
        "docs/benchmarks/page.json",
    );
}

#[test]
fn durations_read_as_minutes() {
    assert_eq!(minutes(178.4), "2 min 58 s");
    assert_eq!(minutes(45.0), "45 s");
    assert_eq!(minutes(909.6), "15 min 10 s");
}

/// Scenes 2 and 3 in quaternions: their tables are in docs/attitude.md.
const QUATERNION_SCENES: [&str; 2] = ["three_body_quaternion", "satellite_boom_quaternion"];

/// docs/attitude.md's tables are the quaternion scenes' comparison files, and the ratios it
/// quotes are those of the right-hand-side benchmark's file.
#[test]
fn the_attitude_figures_are_the_files() {
    let docs = read("docs/attitude.md");
    for scene in QUATERNION_SCENES {
        let table = table_of(&records(scene));
        assert!(docs.contains(&table), "docs/attitude.md's table of {scene} is not docs/comparisons/{scene}.json:\n{table}");
    }
    let rhs = json("docs/benchmarks/rhs.json");
    let rows: Vec<Vec<String>> =
        rhs["rows"].as_array().unwrap().iter().map(|r| r.as_array().unwrap().iter().map(|c| c.as_str().unwrap().to_string()).collect()).collect();
    let range = |forms: [&str; 2]| {
        let ratios: Vec<f64> = rows.iter().filter(|r| r[0].ends_with("quaternions") && forms.contains(&r[1].as_str())).map(|r| r[7].parse().unwrap()).collect();
        assert_eq!(ratios.len(), 4, "{forms:?}");
        format!("{:.2} to {:.2}", ratios.iter().copied().fold(f64::INFINITY, f64::min), ratios.iter().copied().fold(0.0, f64::max))
    };
    let fast = format!("Kane's form and the reduced method take {} of the Euler\nmodules' time", range(["Kane", "reduced Volterra"]));
    assert!(docs.contains(&fast), "docs/attitude.md does not quote `{fast}` from docs/benchmarks/rhs.json");
    let slow = format!("Lagrange and Maggi\n{}", range(["Lagrange", "Maggi"]));
    assert!(docs.contains(&slow), "docs/attitude.md does not quote `{slow}` from docs/benchmarks/rhs.json");
}

#[test]
fn the_scene_tables_are_the_comparison_files() {
    let page = read("docs/formulations.md");
    for scene in SCENES {
        let table = table_of(&records(scene));
        assert!(page.contains(&table), "docs/formulations.md's table of {scene} is not docs/comparisons/{scene}.json:\n{table}");
    }
    // The README shows scene 2's.
    let table = table_of(&records("three_body"));
    assert!(read("README.md").contains(&table), "the README's table of three_body is not docs/comparisons/three_body.json:\n{table}");
}

/// Everything in a comparison file but the times is what the committed module gives now: the
/// same states, equations, steps and calls, and the same errors (to the round-off of the
/// machine's libm where an error is round-off itself).
#[test]
fn the_comparison_files_hold_what_a_run_gives_now() {
    for scene in SCENES.into_iter().chain(QUATERNION_SCENES) {
        let model = generated::find(scene).unwrap();
        let now = compare(&model, &Options { repeats: 1, ..Options::paper(&model) }).unwrap();
        let filed = records(scene);
        assert_eq!(now.len(), filed.len(), "{scene}");
        for (run, old) in now.iter().zip(&filed) {
            let new = &run.record;
            let what = format!("{scene} {}", new.method);
            assert_eq!(
                (&new.method, new.states, new.equations, new.steps, new.rejected, new.rhs_calls),
                (&old.method, old.states, old.equations, old.steps, old.rejected, old.rhs_calls),
                "{what}"
            );
            let pairs = [
                ("energy", new.energy_error_norm, old.energy_error_norm, new.energy_error_rel),
                ("constraint", new.constraint_error_norm, old.constraint_error_norm, new.constraint_error_norm),
            ];
            let momenta = new.momenta.iter().zip(&old.momenta).map(|(n, o)| ("momentum", n.norm, o.norm, n.rel));
            for (name, a, b, relative) in pairs.into_iter().chain(momenta) {
                // Round-off (relative to the invariant's size, or absolute for a constraint):
                // both must be round-off; anything larger is a truncation error, reproducible.
                if relative.abs() < 1e-12 {
                    assert!(b.abs() <= 1e-12 * (a.abs() / relative.abs().max(1e-300)).max(1.0), "{what} {name}: {a:e} now, {b:e} filed");
                } else {
                    assert!((a - b).abs() <= 1e-9 * a.abs(), "{what} {name}: {a:e} now, {b:e} filed");
                }
            }
            assert!((new.max_condition - old.max_condition).abs() <= 1e-9 * new.max_condition, "{what} condition");
        }
    }
}

#[test]
fn the_in_process_figures_are_the_benchmark_file() {
    let readme = read("README.md");
    let tool = read("docs/tool.md");
    let eval = json("docs/benchmarks/eval.json");
    let ms = eval["scene2_file_to_table_seconds"].as_f64().unwrap() * 1e3;
    assert_quoted(&readme, &format!("comparison table takes {ms:.0} ms"), "docs/benchmarks/eval.json");
    assert_quoted(&tool, &format!("comparison table takes {ms:.0} ms"), "docs/benchmarks/eval.json");
    let range = |field: &str| {
        let ratios: Vec<f64> = eval["rhs"].as_array().unwrap().iter().map(|r| r[field].as_f64().unwrap()).collect();
        ratios.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), r| (lo.min(*r), hi.max(*r)))
    };
    let ((jl, jh), (il, ih), (nl, nh)) = (range("jit_ratio"), range("ratio"), range("native_ratio"));
    assert_quoted(&tool, &format!("call costs {jl:.1} to {jh:.1} times the compiled module's"), "docs/benchmarks/eval.json");
    assert_quoted(&tool, &format!("without the JIT: {il:.1} to {ih:.1} times"), "docs/benchmarks/eval.json");
    assert_quoted(&tool, &format!("with `--compiled`, a call costs {nl:.2} to {nh:.2} times the compiled module's"), "docs/benchmarks/eval.json");
    // docs/benchmarks.md's table is the file's, row for row.
    let docs = read("docs/benchmarks.md");
    for r in eval["rhs"].as_array().unwrap() {
        let row = eval_row(r);
        assert!(docs.contains(&row), "docs/benchmarks.md lacks the row `{row}` of docs/benchmarks/eval.json");
    }
    assert!(docs.contains(&format!("the four runs at the paper's settings): {ms:.0} ms")), "docs/benchmarks.md quotes another time to the first table");
    assert!(docs.contains(&format!("dispatch costs {il:.1} to {ih:.1} times")), "docs/benchmarks.md quotes another interpreter range");
    assert!(docs.contains(&format!("`--compiled` is rustc's code, {nl:.2} to {nh:.2} times")), "docs/benchmarks.md quotes another --compiled range");
}

#[test]
fn the_scaling_figures_are_the_benchmark_files() {
    let readme = read("docs/benchmarks.md");
    let ours = json("docs/scaling/ours.json");
    let sympy = json("docs/scaling/sympy.json");
    let row =
        |model: &str, n: u64| ours.as_array().unwrap().iter().find(|r| r["model"] == model && r["n"] == n).unwrap_or_else(|| panic!("{model} {n}")).clone();
    let seconds = |r: &serde_json::Value| (r["derive_ms"].as_f64().unwrap() + r["emit_ms"].as_f64().unwrap()) / 1e3;
    let kane_assembly = |r: &serde_json::Value| r["ops"].as_array().unwrap().iter().find(|o| o[0] == "kane").unwrap()[1].as_f64().unwrap();
    let sympy_ops = |model: &str, n: u64| sympy[model].as_array().unwrap().iter().find(|r| r["n"] == n).unwrap()["assembly_ops"].as_f64().unwrap();
    let (p20, p50, f8) = (row("pendulum", 20), row("pendulum", 50), row("floating", 8));
    let source = "docs/scaling/ours.json";
    assert_quoted(&readme, &format!("four formulations in {:.2} s", seconds(&p20)), source);
    assert_quoted(&readme, &format!("50 links take {:.1} s and {:.0} MB", seconds(&p50), p50["peak_mb"].as_f64().unwrap()), source);
    assert_quoted(&readme, &format!("with {:.2} of SymPy's assembly", kane_assembly(&p20) / sympy_ops("pendulum", 20)), "docs/scaling/sympy.json");
    assert_quoted(&readme, &format!("8 links\ntakes {:.2} s", seconds(&f8)), source);
    assert_quoted(&readme, &format!("at {:.2} of its operations", kane_assembly(&f8) / sympy_ops("floating", 8)), "docs/scaling/sympy.json");
    let worst = ours
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|r| {
            let (model, n) = (r["model"].as_str()?, r["n"].as_u64()?);
            let theirs = sympy[model].as_array()?.iter().find(|s| s["n"] == n)?["assembly_ops"].as_f64()?;
            Some(kane_assembly(r) / theirs)
        })
        .fold(0.0f64, f64::max);
    assert_quoted(&readme, &format!("at most {worst:.2} of SymPy's cse'd count at every size measured"), "docs/scaling/*.json");
    // The in-process call of the 20-link pendulum against its compiled module, in the same child.
    let per_call = |field: &str, form: &serde_json::Value| p20[field].as_array().unwrap().iter().find(|x| x[0] == *form).map(|x| x[1].as_f64().unwrap());
    let ratios: Vec<f64> =
        p20["ns_per_call"].as_array().unwrap().iter().filter_map(|x| Some(per_call("jit_ns_per_call", &x[0])? / per_call("ns_per_call", &x[0])?)).collect();
    assert_eq!(ratios.len(), 4, "ours.json lacks the 20-link pendulum's per-call times");
    let (lo, hi) = ratios.iter().fold((f64::INFINITY, 0.0f64), |(a, b), r| (a.min(*r), b.max(*r)));
    assert_quoted(&readme, &format!("call of the 20-link pendulum costs {lo:.2} to {hi:.2} times its compiled module's"), source);
    // SymPy's own times are in the tables the benchmark writes into docs/scaling.md.
    let scaling = read("docs/scaling.md");
    let sympy_seconds = |table: &str, n: u64| -> f64 {
        let section = scaling.split(table).nth(1).unwrap_or_else(|| panic!("docs/scaling.md has no `{table}`"));
        let line = section.lines().find(|l| l.starts_with(&format!("| {n} |"))).unwrap();
        line.split('|').nth(2).unwrap().trim().parse().unwrap()
    };
    let pendulum = sympy_seconds("SymPy's `KanesMethod` on the same model", 20);
    assert_quoted(&readme, &format!("SymPy's Kane with cse: {pendulum:.1} s"), "docs/scaling.md");
    // The README's headline: the same two figures.
    let door = read("README.md");
    assert_quoted(
        &door,
        &format!("derives and emits all four formulations\n  in {:.2} s, where SymPy's `KanesMethod` with cse takes {pendulum:.1} s", seconds(&p20)),
        "docs/scaling",
    );
    let floating = scaling.rsplit("SymPy's `KanesMethod` on the same model").next().unwrap();
    let line = floating.lines().find(|l| l.starts_with("| 8 |")).unwrap();
    let seconds: f64 = line.split('|').nth(2).unwrap().trim().parse().unwrap();
    assert_quoted(&readme, &format!("against SymPy's {seconds:.0} s"), "docs/scaling.md");
}

/// One row of eval.json as docs/benchmarks.md's in-process table shows it.
fn eval_row(r: &serde_json::Value) -> String {
    let f = |k: &str| r[k].as_f64().unwrap();
    format!(
        "| {} | {} | {:.0} | {:.0} | {:.2} | {:.0} | {:.2} | {:.0} | {:.2} |",
        r["model"].as_str().unwrap(),
        r["formulation"].as_str().unwrap(),
        f("compiled_ns"),
        f("evaluated_ns"),
        f("ratio"),
        f("jit_ns"),
        f("jit_ratio"),
        f("native_ns"),
        f("native_ratio")
    )
}

/// The tables the benchmarks write as `{command, columns, rows}`.
const TABLES: [&str; 7] = ["rhs", "pinocchio", "runs", "drift", "derive", "rustc", "integrators"];

/// A table file as the markdown lines it stands for.
fn markdown(file: &serde_json::Value) -> Vec<String> {
    let cells = |v: &serde_json::Value| v.as_array().unwrap().iter().map(|c| c.as_str().unwrap().to_string()).collect::<Vec<_>>();
    let columns = cells(&file["columns"]);
    let mut lines = vec![format!("| {} |", columns.join(" | ")), format!("|{}", "---|".repeat(columns.len()))];
    lines.extend(file["rows"].as_array().unwrap().iter().map(|r| format!("| {} |", cells(r).join(" | "))));
    lines
}

/// Every table of docs/benchmarks.md is a file a benchmark wrote, whole and in order, with the
/// command that writes it quoted; no table line is typed by hand.
#[test]
fn the_benchmark_tables_are_the_files_the_benchmarks_write() {
    let docs = read("docs/benchmarks.md");
    let mut from_files: Vec<String> = Vec::new();
    for name in TABLES {
        let file = json(&format!("docs/benchmarks/{name}.json"));
        let lines = markdown(&file);
        let table = lines.join("\n") + "\n";
        assert!(docs.contains(&table), "docs/benchmarks.md lacks the table of docs/benchmarks/{name}.json:\n{table}");
        let command = file["command"].as_str().unwrap();
        assert!(docs.contains(&format!("`{command}`")), "docs/benchmarks.md does not say how {name}.json is written (`{command}`)");
        from_files.extend(lines);
    }
    // The in-process table is eval.json's (checked row by row above, in its own test).
    let eval = json("docs/benchmarks/eval.json");
    from_files.extend(eval["rhs"].as_array().unwrap().iter().map(eval_row));
    from_files.push("| model | formulation | compiled ns | interpreted ns | ratio | JIT ns | ratio | --compiled ns | ratio |".into());
    from_files.push(format!("|{}", "---|".repeat(9)));
    let typed: Vec<&str> = docs.lines().filter(|l| l.starts_with('|') && !from_files.iter().any(|f| f == l)).collect();
    assert!(typed.is_empty(), "docs/benchmarks.md has table lines no benchmark wrote: {typed:#?}");
}

/// docs/goals.md quotes each model's ratios to Pinocchio's ABA, and the operation counts of the
/// spatial 8-link chain and the 20-link pendulum, as docs/benchmarks/pinocchio.json has them.
#[test]
fn the_goals_quote_the_pinocchio_file() {
    let goals = read("docs/goals.md");
    let file = json("docs/benchmarks/pinocchio.json");
    let rows = file["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 5);
    for row in rows {
        let cell = |k: usize| row[k].as_str().unwrap().to_string();
        let ratios = format!("{} (Kane), {} (reduced)", cell(5), cell(6));
        assert!(goals.contains(&ratios), "docs/goals.md does not quote `{ratios}` ({}) from docs/benchmarks/pinocchio.json", cell(0));
        if cell(0).starts_with("pendulum on a cart, 20") {
            let quoted = format!("{} / {}", cell(5), cell(6));
            assert!(read("README.md").contains(&quoted), "README.md does not quote `{quoted}` ({})", cell(0));
        }
        if cell(0).starts_with("spatial chain, 8 links") || cell(0).starts_with("pendulum on a cart, 20") {
            let ops = format!("{} (Kane), {} (reduced)", cell(7), cell(8));
            assert!(goals.contains(&ops), "docs/goals.md does not quote `{ops}` ({})", cell(0));
        }
    }
    assert!(read("docs/benchmarks.md").contains("[`goals.md`](goals.md)"), "docs/benchmarks.md links the goals");
    // Each row's verdict follows from its figures: met when every figure it names is within the
    // target (the reduced method's alone where the goal names only it).
    let mut verdicts = 0;
    for line in goals.lines().filter(|l| l.starts_with("| ") && l.contains("<= ")) {
        let cells: Vec<&str> = line.split(" | ").collect();
        let (goal, target, measured, verdict) = (cells[0], cells[1], cells[2], cells[3]);
        let limit: f64 = target.trim_start_matches("<= ").trim_end_matches(" each").parse().unwrap();
        let value = |who: &str| -> f64 {
            let text = measured.split(", ").find(|p| p.ends_with(&format!("({who})"))).unwrap().trim_end_matches(&format!(" ({who})"));
            text.split(" + ").map(|x| x.parse::<f64>().unwrap()).sum()
        };
        let within =
            if goal.trim_start_matches("| ").ends_with(", reduced") { value("reduced") <= limit } else { value("Kane") <= limit && value("reduced") <= limit };
        assert_eq!(verdict.starts_with("met"), within, "docs/goals.md: `{line}`");
        verdicts += 1;
    }
    assert_eq!(verdicts, 6);
}

/// The Python figures of the README and docs/python.md are docs/benchmarks/python.json's
/// (`python python/benchmarks/ensemble.py` writes it, outside CI).
#[test]
fn the_python_figures_are_the_benchmark_file() {
    let file = json("docs/benchmarks/python.json");
    let first = &file["import_to_first_rhs"];
    let runs = &file["ensemble"];
    let number = |v: &serde_json::Value| v.as_f64().unwrap();
    let total = format!("{:.2} s", number(&first["total_s"]));
    let per_second = |k: &str| format!("{:.0}", number(&runs["runs_per_second"][k]));
    let speedup = format!("{:.0} times", number(&runs["speedup_all_cores"]));
    let readme = read("README.md");
    let page = read("docs/python.md");
    assert_quoted(&readme, &format!("takes {total}"), "README.md");
    assert_quoted(&page, &format!("takes {total}"), "docs/python.md");
    assert_quoted(&page, &format!("{} runs/s", per_second("solve_ivp")), "docs/python.md");
    assert_quoted(&page, &format!("runs {} runs/s on every core and {} on one thread", per_second("all_cores"), per_second("one_thread")), "docs/python.md");
    assert_quoted(&page, &format!("{speedup} fewer than the ensemble"), "docs/python.md");
    // The loop and the ensemble ran the same runs.
    assert!(number(&runs["largest_difference_at_the_end"]) < 1e-8);
    // Today's SymPy to the same first right-hand side, measured in the same run, on the same
    // system (the right-hand sides agree).
    let sympy = &file["sympy_import_to_first_rhs"];
    assert!(number(&sympy["relative_difference_of_the_rhs"]) < 1e-12);
    let sympy_total = format!("takes {:.2} s", number(&sympy["total_s"]));
    assert_quoted(&readme, &sympy_total, "README.md");
    assert_quoted(&page, &sympy_total, "docs/python.md");
    assert!(!readme.contains("3906") && !page.contains("3906"), "the 2019 PyDy figure is gone: today's SymPy is measured");
}

/// docs/goals.md's SymEngine table is docs/scaling/symengine.json (written by
/// `docs/scaling/symengine_pendulum.py`, outside CI), and its two verdicts follow from it.
#[test]
fn the_symengine_figures_are_the_script_file() {
    let goals = read("docs/goals.md");
    let file = json("docs/scaling/symengine.json");
    let records = file["records"].as_array().unwrap();
    assert!(records.len() >= 5);
    let f = |r: &serde_json::Value, k: &str| r[k].as_f64().unwrap();
    for r in records {
        let row = format!(
            "| {} | {:.3} | {:.3} | {:.3} | {:.2} | {:.2} | {} | {} | {} | {:.2} | {:.2} | {} |",
            r["n"],
            f(r, "ours_seconds"),
            f(r, "ours_lagrange_seconds"),
            f(r, "symengine_seconds"),
            f(r, "time_ratio"),
            f(r, "lagrange_time_ratio"),
            r["ours_lagrange_assembly_ops"],
            r["ours_kane_rhs_ops"],
            r["symengine_cse_ops"],
            f(r, "ops_ratio"),
            f(r, "kane_ops_ratio"),
            r["ours_kept_as_built"]
        );
        assert_quoted(&goals, &row, "docs/scaling/symengine.json");
        assert!((f(r, "time_ratio") - f(r, "ours_seconds") / f(r, "symengine_seconds")).abs() < 1e-9);
        // Ours are timed without starting the process, as SymEngine's are: the whole process
        // less its start, which is a small part of even the smallest generation.
        let start = f(r, "ours_process_start_seconds");
        assert!((f(r, "ours_seconds") - (f(r, "ours_process_seconds") - start)).abs() < 1e-9);
        assert!((f(r, "ours_lagrange_seconds") - (f(r, "ours_lagrange_process_seconds") - start)).abs() < 1e-9);
        assert!(start > 0.0 && start < 0.2 * f(r, "ours_lagrange_process_seconds"), "n = {}: process start {start} s", r["n"]);
        assert!((f(r, "lagrange_time_ratio") - f(r, "ours_lagrange_seconds") / f(r, "symengine_seconds")).abs() < 1e-9);
        assert!((f(r, "ops_ratio") - f(r, "ours_lagrange_assembly_ops") / f(r, "symengine_cse_ops")).abs() < 1e-9);
    }
    let range = |k: &str| {
        let values: Vec<f64> = records.iter().map(|r| f(r, k)).collect();
        (values.iter().copied().fold(f64::INFINITY, f64::min), values.iter().copied().fold(0.0, f64::max))
    };
    let ((t_lo, t_hi), (l_lo, l_hi)) = (range("time_ratio"), range("lagrange_time_ratio"));
    let (o_lo, o_hi) = range("ops_ratio");
    let time_met = t_hi <= 1.0;
    let ops_met = o_hi <= 0.4 && records.iter().all(|r| r["ours_kept_as_built"] == 0);
    let verdict = |met: bool| if met { "met" } else { "missed" };
    // The smallest n from which every larger one meets `ok`.
    let from = |ok: &dyn Fn(&serde_json::Value) -> bool| {
        let last_miss = records.iter().rposition(|r| !ok(r));
        last_miss.map_or(&records[0], |i| &records[(i + 1).min(records.len() - 1)])["n"].clone()
    };
    let (whole_from, lagrange_from) = (from(&|r| f(r, "time_ratio") <= 1.0), from(&|r| f(r, "lagrange_time_ratio") <= 1.0));
    assert_quoted(
        &goals,
        &format!(
            "at most 1 at every n: {} ({t_lo:.2} to {t_hi:.2}; at most 1 from n = {whole_from}; Lagrange's form alone, the same work as SymEngine's, {l_lo:.2} to {l_hi:.2}, at most 1 from n = {lagrange_from})",
            verdict(time_met)
        ),
        "docs/scaling/symengine.json",
    );
    let ops_from = from(&|r| f(r, "ops_ratio") <= 0.4);
    assert_quoted(
        &goals,
        &format!("no node kept as built:\n  {} ({o_lo:.2} to {o_hi:.2}; at most 0.4 from n = {ops_from};", verdict(ops_met)),
        "docs/scaling/symengine.json",
    );
    let kept_from = records.iter().find(|r| r["ours_kept_as_built"] != 0).map(|r| r["n"].clone());
    let kept = kept_from.map_or("no node kept as built at any n".to_string(), |n| format!("nodes kept as built from n = {n}"));
    assert_quoted(&goals, &kept, "docs/scaling/symengine.json");
}

/// docs/goals.md quotes the scaling benchmark's measured cells for the goals it measures: SymPy's
/// derivation time on the paper's scenes against ours (the same work, and our whole generation),
/// the planar chain in absolute angles, and the simplifier's work on the spatial chains.
#[test]
fn the_goals_quote_the_scaling_rows() {
    let goals = read("docs/goals.md");
    let scaling = read("docs/scaling.md");
    for row in [
        "| derivation CPU, SymPy's `KanesMethod` / ours, each paper scene, the same work",
        "| SymPy's `KanesMethod` / our whole generation, each paper scene",
        "| planar free chain of 20 rods in absolute angles",
    ] {
        let line = scaling.lines().find(|l| l.starts_with(row)).unwrap_or_else(|| panic!("docs/scaling.md has no row `{row}`"));
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        let (measured, verdict) = (cells[3], cells[4]);
        assert!(goals.contains(measured), "docs/goals.md does not quote `{measured}` from docs/scaling.md");
        let word = if verdict.starts_with("met") { "met" } else { "missed" };
        assert!(goals.contains(&format!("{measured}: {word}")), "docs/goals.md does not say `{measured}: {word}` as docs/scaling.md does");
    }
    // The status page quotes the range of the two SymPy rows' ratios.
    let readme = read("docs/status.md");
    for (row, what) in [
        ("| derivation CPU, SymPy's `KanesMethod` / ours, each paper scene, the same work", "on the same work"),
        ("| SymPy's `KanesMethod` / our whole generation, each paper scene", "against our whole generation"),
    ] {
        let line = scaling.lines().find(|l| l.starts_with(row)).unwrap();
        let measured = line.split('|').map(str::trim).nth(3).unwrap();
        // "scene R (a s / b ms), ...": the ratio follows each scene's name.
        let ratios: Vec<f64> = measured.split(", ").map(|cell| cell.split_whitespace().nth(1).unwrap().parse().unwrap()).collect();
        let (low, high) = ratios.iter().fold((f64::INFINITY, 0.0f64), |(l, h), r| (l.min(*r), h.max(*r)));
        assert_quoted(&readme, &format!("{low:.1} to {high:.1}"), &format!("docs/scaling.md ({what})"));
    }
    // The simplifier's work on the spatial chain, per size (the last column of its table).
    let spatial = scaling.split("## The spatial chain on a floating base").nth(1).unwrap().split("\n## ").next().unwrap();
    let sizes = ["8 links", "12", "16", "20"];
    for (n, said) in [8, 12, 16, 20].into_iter().zip(sizes) {
        let line = spatial.lines().find(|l| l.starts_with(&format!("| {n} |"))).unwrap_or_else(|| panic!("docs/scaling.md has no spatial chain of {n} links"));
        let cell = line.split('|').map(str::trim).nth(12).unwrap();
        assert!(goals.contains(&format!("`{cell}` at {said}")), "docs/goals.md does not quote the spatial chain's `{cell}` at {n} links from docs/scaling.md");
    }
}

/// The operation counts of the right-hand-side table are the committed modules' own
/// (`generated/op-counts.txt`): a module regenerated with fewer operations makes the file stale
/// (scene 2's reduced call was quoted at 632 + 100 operations when the module had 576 + 100).
#[test]
fn the_right_hand_side_table_counts_the_committed_modules_operations() {
    let file = json("docs/benchmarks/rhs.json");
    let counts = read("generated/op-counts.txt");
    let mut checked = 0;
    for row in file["rows"].as_array().unwrap() {
        let cell = |k: usize| row[k].as_str().unwrap().to_string();
        let (scene, formulation, ops) = (cell(0), cell(1), cell(4));
        // Rows of a plain module: "<n> <module>".
        let Some((_, module)) = scene.split_once(' ').filter(|(_, m)| !m.contains(',')) else { continue };
        let function = match formulation.as_str() {
            "Lagrange" => "lagrange::rhs",
            "Maggi" => "maggi::rhs",
            "Kane" => "kane::rhs",
            _ => "reduced_volterra::rhs",
        };
        let section = counts.split(&format!("[{module}]\n")).nth(1).unwrap_or_else(|| panic!("no [{module}] in op-counts.txt")).split("\n[").next().unwrap();
        let line = section.lines().find(|l| l.trim_start().starts_with(&format!("{function} "))).unwrap_or_else(|| panic!("{module}: no {function}"));
        let (assembly, solve) = ops.split_once(" + ").unwrap();
        assert!(
            line.contains(&format!("assembly {assembly} ops")) && line.ends_with(&format!("solve {solve} ops")),
            "{module} {function}: the table says {ops}, op-counts.txt `{}`",
            line.trim()
        );
        checked += 1;
    }
    assert!(checked >= 12, "{checked} rows checked");
}

/// docs/robots.md's tables are the files its benchmarks and scripts write: the check against
/// Pinocchio (`docs/robots/pinocchio_check.py`), the derivation at robot scale (`cargo bench
/// --bench robots`), the calls against Pinocchio (`cargo bench --bench robot_calls`), the space
/// manipulator (`cargo run --release --example space_manipulator`); and its verdicts on the
/// issue's goals follow from them.
#[test]
fn the_robot_figures_are_the_files() {
    let page = read("docs/robots.md");
    let f = |v: &serde_json::Value| v.as_f64().unwrap_or_else(|| panic!("a number: {v}"));
    let s = |v: &serde_json::Value| v.as_str().unwrap_or_else(|| panic!("a string: {v}")).to_string();
    let table = |head: &[&str], rows: Vec<Vec<String>>| -> String {
        let mut t = format!("| {} |\n|{}\n", head.join(" | "), "---|".repeat(head.len()));
        for r in rows {
            t += &format!("| {} |\n", r.join(" | "));
        }
        t
    };
    let quoted = |t: &str, what: &str| assert!(page.contains(t), "docs/robots.md does not hold the {what} table of its file; it is:\n{t}");

    let check = json("docs/robots/pinocchio_check.json");
    let tolerance = f(&check["tolerance"]);
    let forms = ["lagrange", "maggi", "kane", "reduced_volterra"];
    let rows = check["records"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            let worst = &r["worst_relative_difference"];
            forms.iter().for_each(|k| assert!(f(&worst[*k]) <= tolerance, "{}: {k} is off Pinocchio", s(&r["robot"])));
            let mut row = vec![s(&r["robot"]), s(&r["base"]), r["nv"].to_string(), r["states"].to_string()];
            row.extend(forms.iter().map(|k| format!("{:.0e}", f(&worst[*k]))));
            row
        })
        .collect();
    quoted(&table(&["robot", "base", "dof", "states", "lagrange", "maggi", "kane", "reduced"], rows), "Pinocchio check");

    let derive = json("docs/robots/derive.json");
    let records = derive["records"].as_array().unwrap();
    let rows = records
        .iter()
        .map(|r| {
            vec![
                s(&r["robot"]),
                s(&r["base"]),
                r["coordinates"].to_string(),
                format!("{:.2}", f(&r["cpu_s"])),
                format!("{:.0}", f(&r["peak_mb"])),
                format!("{:.2}", f(&r["simulate_cpu_s"])),
                format!("{:.0}", f(&r["simulate_peak_mb"])),
                format!("{:.1}", f(&r["rustc_s"])),
                format!("{:.0}", f(&r["code_bytes"]) / 1024.0),
                format!("{:.1}", f(&r["simulate_rustc_s"])),
                format!("{:.0}", f(&r["simulate_code_bytes"]) / 1024.0),
            ]
        })
        .collect();
    let header = [
        "robot",
        "base",
        "coordinates",
        "CPU s (four)",
        "peak MB (four)",
        "CPU s (simulate)",
        "peak MB (simulate)",
        "rustc s (four)",
        "module KB (four)",
        "rustc s (simulate)",
        "module KB (simulate)",
    ];
    quoted(&table(&header, rows), "derivation");
    // The humanoid's verdicts: 3 s of CPU, 500 MB, 30 s of rustc.
    let talos = records.iter().find(|r| r["robot"] == "talos_reduced").expect("the humanoid");
    let verdict = |value: f64, goal: f64, unit: &str| {
        let v = format!("{value:.1} {unit} against < {goal} {unit}: {}", if value < goal { "met" } else { "missed" });
        assert!(page.contains(&v), "docs/robots.md does not say `{v}`");
    };
    verdict(f(&talos["cpu_s"]), 3.0, "s");
    verdict(f(&talos["peak_mb"]), 500.0, "MB");
    verdict(f(&talos["simulate_cpu_s"]), 3.0, "s");
    verdict(f(&talos["simulate_peak_mb"]), 500.0, "MB");
    verdict(f(&talos["rustc_s"]), 30.0, "s of rustc");
    verdict(f(&talos["simulate_rustc_s"]), 30.0, "s of rustc");

    // Chains at robot scale: the scaling benchmark's `--at-scale`.
    let chains = json("docs/scaling/at_scale.json");
    let rows = chains["records"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            let mb = |v: &serde_json::Value| v.as_f64().map_or("-".to_string(), |x| format!("< {x:.0}"));
            vec![
                s(&r["model"]),
                r["n"].to_string(),
                r["max_nodes"].as_u64().map_or("default".to_string(), |b| b.to_string()),
                r["runs"].to_string(),
                format!("{:.1}", f(&r["cpu_s"])),
                format!("{:.2}", f(&r["spread"])),
                format!("{:.0}", f(&r["peak_mb"])),
                r["nodes"].as_u64().map_or("-".to_string(), |n| n.to_string()),
                format!("< {:.0}, {}", f(&r["goal_cpu_s"]), mb(&r["goal_mb"])),
                r["error"].as_str().map_or("generated".to_string(), |e| e.replace('|', "/")),
            ]
        })
        .collect();
    quoted(
        &table(&["chain", "n", "node budget", "fresh runs", "CPU s (median)", "spread", "peak MB", "nodes built", "goal (s, MB)", "outcome"], rows),
        "chains at scale",
    );
    // The goals are for the default settings: a raised budget's row says by how much.
    for r in chains["records"].as_array().unwrap().iter().filter(|r| r["max_nodes"].is_null()) {
        let met = r["error"].is_null() && f(&r["cpu_s"]) < f(&r["goal_cpu_s"]) && r["goal_mb"].as_f64().is_none_or(|g| f(&r["peak_mb"]) < g);
        let v = format!("{} n = {}: {}", s(&r["model"]), r["n"], if met { "met" } else { "missed" });
        assert!(page.contains(&v), "docs/robots.md does not say `{v}`");
    }

    let calls = json("docs/robots/per_call.json");
    let rows: Vec<Vec<String>> = calls["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            vec![
                s(&r["robot"]),
                s(&r["base"]),
                format!("{} / {}", r["dof"], r["pinocchio_dof"]),
                format!("{:.0}", f(&r["aba_ns"])),
                format!("{:.0}", f(&r["crba_cholesky_ns"])),
                format!("{:.0}", f(&r["kane_ns"])),
                format!("{:.0}", f(&r["reduced_ns"])),
                format!("{:.2}", f(&r["kane_over_aba"])),
                format!("{:.2}", f(&r["reduced_over_aba"])),
                format!("{:.0}", f(&r["kane_jit_ns"])),
                format!("{:.0}", f(&r["reduced_jit_ns"])),
                format!("{:.2} / {:.2}", f(&r["kane_jit_over_compiled"]), f(&r["reduced_jit_over_compiled"])),
                s(&r["check"]),
            ]
        })
        .collect();
    for r in calls["rows"].as_array().unwrap() {
        let ratio = f(&r["kane_ns"]) / f(&r["aba_ns"]);
        assert!((ratio - f(&r["kane_over_aba"])).abs() < 1e-9, "the ratios are the times'");
    }
    let head = [
        "robot",
        "base",
        "dof (ours / Pinocchio)",
        "ABA ns",
        "CRBA + Cholesky ns",
        "Kane ns",
        "reduced ns",
        "Kane / ABA",
        "reduced / ABA",
        "Kane JIT ns",
        "reduced JIT ns",
        "JIT / compiled (Kane / reduced)",
        "accelerations against ABA",
    ];
    quoted(&table(&head, rows), "calls");
    // The verdicts: the better of Kane's and the reduced form within half of ABA's time, the
    // JIT within twice the compiled module.
    let list = |names: Vec<String>| if names.is_empty() { "none".to_string() } else { names.join(", ") };
    let (met, missed): (Vec<_>, Vec<_>) = calls["rows"].as_array().unwrap().iter().partition(|r| f(&r["kane_over_aba"]).min(f(&r["reduced_over_aba"])) <= 0.5);
    let names = |rows: Vec<&serde_json::Value>| list(rows.iter().map(|r| s(&r["robot"])).collect());
    let v = format!("At most 0.5 of ABA's time (the better of Kane's and the reduced form): met on {}; missed on {}.", names(met), names(missed));
    assert!(page.contains(&v), "docs/robots.md does not say `{v}`");
    // The same instructions as Pinocchio's build: the module with `--fma`, `-C target-cpu=native`.
    let native: Vec<Vec<String>> = calls["rows"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            vec![
                s(&r["robot"]),
                s(&r["base"]),
                format!("{:.0}", f(&r["aba_ns"])),
                format!("{:.0}", f(&r["kane_native_ns"])),
                format!("{:.0}", f(&r["reduced_native_ns"])),
                format!("{:.2}", f(&r["kane_native_over_aba"])),
                format!("{:.2}", f(&r["reduced_native_over_aba"])),
            ]
        })
        .collect();
    quoted(&table(&["robot", "base", "ABA ns", "Kane native ns", "reduced native ns", "Kane native / ABA", "reduced native / ABA"], native), "native calls");
    let (met, missed): (Vec<_>, Vec<_>) =
        calls["rows"].as_array().unwrap().iter().partition(|r| f(&r["kane_native_over_aba"]).min(f(&r["reduced_native_over_aba"])) <= 0.5);
    let v = format!("With Pinocchio's instructions, at most 0.5 of ABA's time: met on {}; missed on {}.", names(met), names(missed));
    assert!(page.contains(&v), "docs/robots.md does not say `{v}`");
    let (within, beyond): (Vec<_>, Vec<_>) =
        calls["rows"].as_array().unwrap().iter().partition(|r| f(&r["kane_jit_over_compiled"]).max(f(&r["reduced_jit_over_compiled"])) <= 2.0);
    let v = format!("The JIT within twice the compiled module: met on {}; missed on {}.", names(within), names(beyond));
    assert!(page.contains(&v), "docs/robots.md does not say `{v}`");
    // The README's headline: the range of the better of the two over the robots.
    let best = |r: &serde_json::Value| f(&r["kane_over_aba"]).min(f(&r["reduced_over_aba"]));
    let by_best = |a: &&serde_json::Value, b: &&serde_json::Value| best(a).total_cmp(&best(b));
    let rows = calls["rows"].as_array().unwrap();
    let (low, high) = (rows.iter().min_by(by_best).unwrap(), rows.iter().max_by(by_best).unwrap());
    let range = format!("from {:.2} ({}) to {:.2} ({}) of it", best(low), s(&low["robot"]), best(high), s(&high["robot"]));
    assert_quoted(&read("README.md"), &range, "docs/robots/per_call.json");

    let arm = json("docs/robots/space_manipulator.json");
    let rows = arm["records"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            vec![
                s(&r["settings"]),
                s(&r["formulation"]),
                r["equations"].to_string(),
                format!("{:.0}", f(&r["ns_per_call"])),
                r["rhs_calls"].to_string(),
                format!("{:.1e}", f(&r["error_at_the_end"])),
                format!("{:.1e}", f(&r["momentum_drift"])),
                format!("{:.1e}", f(&r["angular_momentum_drift"])),
                format!("{:.1e}", f(&r["energy_balance_drift"])),
            ]
        })
        .collect();
    let head = [
        "settings",
        "formulation",
        "equations",
        "ns per call",
        "calls",
        "error at 10 s",
        "linear momentum drift",
        "angular momentum drift",
        "energy balance drift",
    ];
    quoted(&table(&head, rows), "space manipulator");
}
