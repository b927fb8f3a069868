//! The generator's command line: `inspect` a model, or generate its Rust module.

use std::process::ExitCode;

const USAGE: &str = "usage:
  generator inspect MODEL.ron [--latex]    show what is derived from a model
  generator MODEL.ron [-o PATH]            generate the Rust module (stdout or PATH)";

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
        Some(_) => Err(format!("generation is not available yet\n{USAGE}")),
    }
}
