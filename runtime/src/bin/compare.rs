//! `compare MODEL [options]`: every formulation of an emitted model under the same integrator
//! settings, as a table shaped like the paper's Tables 2, 3 and 6.

use runtime::compare::{Options, compare, table};
use runtime::integrate::Method;
use std::process::ExitCode;

const USAGE: &str = "usage: compare MODEL [options]
  MODEL                a module of `generated/` (cart_pendulum, three_body, satellite_boom, ...)
options (default: the paper's settings, Dormand-Prince 5(4), rtol 1e-3, atol 1e-6, h_max = span/10):
  --method M           dopri5 | dop853 | rk4
  --rtol X  --atol X   tolerances (adaptive methods)
  --h X                step (rk4)
  --h-max X            largest step
  --repeats N          CPU time is the median of N runs (default 5)
  --formulations LIST  comma-separated subset of lagrange, maggi, kane, reduced_volterra
  --baumgarte A,B      Baumgarte stabilization of Lagrange (alpha, beta)
  --projection         project Lagrange and Maggi onto the constraints after every step
  --json FILE          also write the records as JSON (`-` for stdout)
  --plots DIR          also write SVG plots of coordinates and errors";

fn main() -> ExitCode {
    match run(std::env::args().skip(1).collect()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn number(name: &str, v: Option<String>) -> Result<f64, String> {
    let v = v.ok_or_else(|| format!("`{name}` needs a value\n{USAGE}"))?;
    v.parse::<f64>().ok().filter(|x| x.is_finite() && *x > 0.0).ok_or_else(|| format!("`{name}` needs a positive number, not `{v}`"))
}

fn run(args: Vec<String>) -> Result<(), String> {
    let mut it = args.into_iter();
    let mut model_name = None;
    let (mut json, mut plots) = (None, None);
    let mut edits: Vec<Box<dyn Fn(&mut Options)>> = Vec::new();
    let mut h = None;
    let mut method = None;
    while let Some(a) = it.next() {
        match a.as_str() {
            "-h" | "--help" => return Err(USAGE.into()),
            "--method" => {
                method = Some(match it.next().as_deref() {
                    Some("dopri5") => "dopri5",
                    Some("dop853") => "dop853",
                    Some("rk4") => "rk4",
                    other => return Err(format!("unknown method {other:?}: use dopri5, dop853 or rk4")),
                })
            }
            "--rtol" => {
                let x = number("--rtol", it.next())?;
                edits.push(Box::new(move |o| o.settings.rtol = x));
            }
            "--atol" => {
                let x = number("--atol", it.next())?;
                edits.push(Box::new(move |o| o.settings.atol = x));
            }
            "--h-max" => {
                let x = number("--h-max", it.next())?;
                edits.push(Box::new(move |o| o.settings.h_max = x));
            }
            "--h" => h = Some(number("--h", it.next())?),
            "--repeats" => {
                let n = number("--repeats", it.next())? as usize;
                edits.push(Box::new(move |o| o.repeats = n.max(1)));
            }
            "--formulations" => {
                let list: Vec<String> = it.next().unwrap_or_default().split(',').map(|s| s.trim().to_string()).collect();
                edits.push(Box::new(move |o| o.formulations = list.clone()));
            }
            "--baumgarte" => {
                let v = it.next().unwrap_or_default();
                let parts: Vec<f64> = v.split(',').filter_map(|x| x.trim().parse().ok()).collect();
                let [alpha, beta] = parts[..] else { return Err(format!("`--baumgarte` needs `alpha,beta`, not `{v}`")) };
                edits.push(Box::new(move |o| o.drift = runtime::system::Drift::Baumgarte { alpha, beta }));
            }
            "--projection" => edits.push(Box::new(|o| o.drift = runtime::system::Drift::Projection)),
            "--json" => json = Some(it.next().ok_or("`--json` needs a file (or -)")?),
            "--plots" => plots = Some(it.next().ok_or("`--plots` needs a directory")?),
            s if s.starts_with('-') => return Err(format!("unknown option `{s}`\n{USAGE}")),
            s if model_name.is_none() => model_name = Some(s.to_string()),
            s => return Err(format!("unexpected argument `{s}`\n{USAGE}")),
        }
    }
    let name = model_name.ok_or(USAGE)?;
    let model = generated::find(&name).ok_or_else(|| {
        let known: Vec<&str> = generated::models().iter().map(|m| m.module).collect();
        format!("no emitted model `{name}` (known: {})", known.join(", "))
    })?;
    let mut options = Options::paper(&model);
    match method {
        Some("dop853") => options.settings.method = Method::Dop853,
        Some("rk4") => options.settings.method = Method::Rk4 { h: h.ok_or("`--method rk4` needs `--h`")? },
        _ => {}
    }
    for e in &edits {
        e(&mut options);
    }
    let runs = compare(&model, &options).map_err(|e| e.to_string())?;
    let s = &options.settings;
    println!(
        "{}: {}, rtol {:e}, atol {:e}, h_max {}, {} outputs, CPU time median of {}\n",
        model.module,
        s.method,
        s.rtol,
        s.atol,
        s.h_max,
        runs.first().map_or(0, |r| r.solution.times.len()),
        options.repeats
    );
    print!("{}", table(&runs));
    if let Some(path) = json {
        let records: Vec<_> = runs.iter().map(|r| &r.record).collect();
        let text = serde_json::to_string_pretty(&records).map_err(|e| e.to_string())?;
        if path == "-" {
            println!("{text}");
        } else {
            std::fs::write(&path, text).map_err(|e| format!("cannot write `{path}`: {e}"))?;
        }
    }
    if let Some(dir) = plots {
        for p in runtime::plot::write_plots(&runs, std::path::Path::new(&dir)).map_err(|e| e.to_string())? {
            eprintln!("wrote {}", p.display());
        }
    }
    Ok(())
}
