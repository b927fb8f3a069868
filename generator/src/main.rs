//! The generator's command line: generate a model's Rust module, or `inspect` what is derived.

use generator::emit::{self, Formulation, Options, Parameters};
use std::process::ExitCode;

const USAGE: &str = "usage:
  generator MODEL.ron [-o PATH] [OPTIONS]  generate the Rust module (to stdout, or to PATH)
  generator inspect MODEL.ron [--latex]    show what is derived from a model

options (each overrides the model's `emit` section):
  --formulations LIST   comma-separated: lagrange, maggi, kane, reduced_volterra
  --baked               fold the parameters into the code as constants
  --runtime-params      keep the parameters as fields of `Params`
  --drop-ignorable      leave the ignorable coordinates out of the reduced state
  --max-lets N          split functions with more than N common subexpressions";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("{msg}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: &[String]) -> Result<(), String> {
    match args.first().map(String::as_str) {
        Some("inspect") => {
            let latex = args.iter().any(|a| a == "--latex");
            let files: Vec<&String> = args[1..].iter().filter(|a| !a.starts_with("--")).collect();
            let [file] = files.as_slice() else { return Err(USAGE.into()) };
            if let Some(bad) = args[1..].iter().find(|a| a.starts_with("--") && *a != "--latex") {
                return Err(format!("unknown option `{bad}`\n{USAGE}"));
            }
            let model = generator::model::load(file).map_err(|e| e.to_string())?;
            let text = generator::inspect::inspect(&model, latex).map_err(|e| e.to_string())?;
            print!("{text}");
            Ok(())
        }
        Some("-h") | Some("--help") | None => Err(USAGE.into()),
        Some(_) => generate(args),
    }
}

fn generate(args: &[String]) -> Result<(), String> {
    let mut file = None;
    let mut output = None;
    let mut edits: Vec<Box<dyn Fn(&mut Options)>> = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = |name: &str| it.next().cloned().ok_or_else(|| format!("`{name}` needs a value\n{USAGE}"));
        match a.as_str() {
            "-o" | "--output" => output = Some(value(a)?),
            "--baked" => edits.push(Box::new(|o| o.parameters = Parameters::Baked)),
            "--runtime-params" => edits.push(Box::new(|o| o.parameters = Parameters::Runtime)),
            "--drop-ignorable" => edits.push(Box::new(|o| o.integrate_ignorable = false)),
            "--max-lets" => {
                let v = value(a)?;
                let n: usize = v.parse().map_err(|_| format!("`--max-lets` needs a positive integer, not `{v}`"))?;
                edits.push(Box::new(move |o| o.max_lets_per_function = n.max(1)));
            }
            "--formulations" => {
                let v = value(a)?;
                let mut list = Vec::new();
                for name in v.split(',') {
                    list.push(match name.trim() {
                        "reduced_volterra" | "reduced" => Formulation::ReducedVolterra,
                        "kane" => Formulation::Kane,
                        "lagrange" => Formulation::Lagrange,
                        "maggi" => Formulation::Maggi,
                        other => {
                            return Err(format!("unknown formulation `{other}`: use lagrange, maggi, kane or reduced_volterra"));
                        }
                    });
                }
                list.sort();
                list.dedup();
                edits.push(Box::new(move |o| o.formulations = list.clone()));
            }
            s if s.starts_with('-') => return Err(format!("unknown option `{s}`\n{USAGE}")),
            s if file.is_none() => file = Some(s.to_string()),
            s => return Err(format!("unexpected argument `{s}`\n{USAGE}")),
        }
    }
    let file = file.ok_or_else(|| USAGE.to_string())?;
    let model = generator::model::load(&file).map_err(|e| e.to_string())?;
    let mut options = Options::from_model(&model);
    for edit in &edits {
        edit(&mut options);
    }
    let out = emit::generate(&model, &options).map_err(|e| e.to_string())?;
    match output {
        Some(path) => std::fs::write(&path, &out.code).map_err(|e| format!("error: cannot write `{path}`: {e}"))?,
        None => print!("{}", out.code),
    }
    eprintln!("{}", out.summary);
    Ok(())
}
