//! `sweep MODEL [--out DIR] [--repeats N] [--quick]`: the work-precision sweep of a model,
//! written as CSV, JSON and an SVG diagram; progress on stderr.

use runtime::sweep::{SweepOptions, csv, sweep};
use std::io::Write;
use std::process::ExitCode;

const USAGE: &str = "usage: sweep MODEL [--out DIR] [--repeats N] [--quick] [--formulations LIST]
  writes DIR/<model>_work_precision.{csv,json,svg} (default DIR: .)
  --quick   three tolerances and three RK4 steps instead of ten and seven";

fn main() -> ExitCode {
    match run(std::env::args().skip(1).collect()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: Vec<String>) -> Result<(), String> {
    let mut it = args.into_iter();
    let (mut name, mut out) = (None, String::from("."));
    let mut options = SweepOptions::default();
    while let Some(a) = it.next() {
        match a.as_str() {
            "-h" | "--help" => return Err(USAGE.into()),
            "--out" => out = it.next().ok_or("`--out` needs a directory")?,
            "--repeats" => {
                let v = it.next().unwrap_or_default();
                options.repeats = v.parse().ok().filter(|n| *n > 0).ok_or_else(|| format!("`--repeats` needs a positive integer, not `{v}`"))?;
            }
            "--quick" => {
                options.tolerances = vec![1e-3, 1e-6, 1e-9];
                options.rk4_steps = vec![1.0, 0.1, 0.01];
            }
            "--formulations" => options.formulations = it.next().unwrap_or_default().split(',').map(|s| s.trim().to_string()).collect(),
            s if s.starts_with('-') => return Err(format!("unknown option `{s}`\n{USAGE}")),
            s if name.is_none() => name = Some(s.to_string()),
            s => return Err(format!("unexpected argument `{s}`\n{USAGE}")),
        }
    }
    let name = name.ok_or(USAGE)?;
    let model = generated::find(&name).ok_or_else(|| format!("no emitted model `{name}`"))?;
    let mut stderr = std::io::stderr();
    let points = sweep(&model, &options, &mut |done, total, label| {
        let _ = write!(stderr, "\r[{done:>3}/{total}] {label:<48}");
        let _ = stderr.flush();
    })
    .map_err(|e| e.to_string())?;
    eprintln!();
    let dir = std::path::Path::new(&out);
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create `{out}`: {e}"))?;
    let base = dir.join(format!("{name}_work_precision"));
    let write = |ext: &str, text: String| {
        let p = base.with_extension(ext);
        std::fs::write(&p, text).map_err(|e| format!("cannot write `{}`: {e}", p.display()))
    };
    write("csv", csv(&points))?;
    write("json", serde_json::to_string_pretty(&points).map_err(|e| e.to_string())?)?;
    runtime::plot::write_work_precision(&points, &base.with_extension("svg")).map_err(|e| e.to_string())?;
    let failed = points.iter().filter(|p| p.failure.is_some()).count();
    println!("{} runs ({failed} stopped early), written to {}.{{csv,json,svg}}", points.len(), base.display());
    Ok(())
}
