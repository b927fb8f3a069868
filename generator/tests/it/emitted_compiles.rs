//! Exit 0 means code that compiles: modules emitted under option combinations that the
//! committed ones do not cover (splitting every few statements, subsets of formulations,
//! baked parameters) are compiled by rustc with warnings denied.

use generator::emit::{Formulation, Options, Parameters};

use generator::generate;

use crate::support;

fn compile(name: &str, code: &str) {
    let dir = std::env::temp_dir().join(format!("emitted-compiles-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("module.rs");
    std::fs::write(&file, format!("#![deny(warnings)]\n#![allow(clippy::all)]\n{code}")).unwrap();
    let out = support::rustc::rustc().args(["--crate-type", "lib", "-C", "opt-level=0", "--out-dir"]).arg(&dir).arg(&file).output().expect("rustc runs");
    let _ = std::fs::remove_dir_all(&dir);
    assert!(out.status.success(), "{name} does not compile:\n{}", String::from_utf8_lossy(&out.stderr));
}

fn model(name: &str) -> generator::model::Model {
    generator::model::load(format!("{}/../models/{name}.ron", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

#[test]
fn split_modules_compile_at_any_split_size() {
    for (name, lets) in [("cart_pendulum", 5), ("three_body", 30), ("cartesian_pendulum", 1)] {
        let m = model(name);
        let options = Options { max_lets_per_function: lets, ..Options::from_model(&m) };
        let out = generate(&m, &options).unwrap();
        assert!(out.code.contains("_part0"), "{name} at {lets} lets was not split");
        compile(&format!("{name}_{lets}"), &out.code);
    }
}

#[test]
fn subsets_and_baked_modules_compile() {
    let m = model("satellite_boom");
    for formulations in [vec![Formulation::Lagrange], vec![Formulation::Maggi], vec![Formulation::Kane, Formulation::ReducedVolterra], vec![]] {
        let options = Options { formulations: formulations.clone(), parameters: Parameters::Baked, ..Options::from_model(&m) };
        let out = generate(&m, &options).unwrap();
        compile(&format!("satellite_{}", formulations.len()), &out.code);
    }
}

#[test]
fn odd_names_become_valid_identifiers() {
    // A parameter called `_`, names that are Rust keywords or the module's own items.
    let src = std::fs::read_to_string(format!("{}/../models/cart_pendulum.ron", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let src =
        src.replace("\"tau\": 0.0", "\"tau\": 0.0, \"_\": 1.0, \"fn\": 2.0, \"rhs\": 3.0, \"state\": 4.0").replace("\"M\": 2.0", "\"M\": 2.0, \"Params\": 1.0");
    let src = src.replace("mass: \"M\",", "mass: \"M*_*fn/2*rhs/3*state/4*Params\",");
    assert!(src.contains("M*_*fn"), "test edit not applied");
    let m = generator::model::from_source("odd.ron", &src).unwrap();
    let out = generate(&m, &Options::from_model(&m)).unwrap();
    compile("odd_names", &out.code);
}
