//! The paper's comparison of the four formulations on a scene, run on its committed module
//! compiled by rustc (the fastest route), at the paper's settings: prints the table and writes
//! `docs/comparisons/<scene>.json`, the file the README's tables are quoted from (a test checks
//! that they are, and that the file's numbers other than times are what a run gives now).
//!
//! `cargo run --release -p generated --example compare -- three_body --repeats 11`

use runtime::compare::{Options, compare, table};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: compare SCENE [--repeats N]   (SCENE: cart_pendulum, three_body, satellite_boom)";
    let scene = args.first().ok_or(usage)?;
    let repeats = match args.get(1).map(String::as_str) {
        Some("--repeats") => args.get(2).ok_or(usage)?.parse::<usize>()?,
        Some(_) => return Err(usage.into()),
        None => 11,
    };
    let model = generated::find(scene).ok_or_else(|| format!("no committed module `{scene}`"))?;
    let runs = compare(&model, &Options { repeats, ..Options::paper(&model) })?;
    print!("{}", table(&runs));
    let records: Vec<_> = runs.into_iter().map(|r| r.record).collect();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../docs/comparisons/{scene}.json"));
    files::write_creating_folder(&path, (serde_json::to_string_pretty(&records)? + "\n").as_bytes())?;
    eprintln!("wrote {}", path.display());
    Ok(())
}
