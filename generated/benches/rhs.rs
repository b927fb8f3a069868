//! Nanoseconds per right-hand-side call, per scene and formulation, through the typed
//! functions of each emitted module (no slices, no conversions), beside each function's exact
//! operation counts (assembly + worst-case solve, from the generation summary): every call
//! timed interleaved with the others, best of 30 rounds of 2,000 calls. Scenes 2 and 3 with
//! their attitudes in quaternions are timed beside their Euler-angle modules.
//!
//! `cargo bench -p generated --bench rhs` writes `docs/benchmarks/rhs.json` (the table of
//! `docs/benchmarks.md`, checked by `tests/it/figures.rs`) and prints it.

use std::hint::black_box;
use std::time::Instant;

#[path = "../tests/common/variants.rs"]
mod variants;

/// The command that writes the file (quoted in the docs).
const COMMAND: &str = "cargo bench -p generated --bench rhs";

/// One timed function: (row label, module, formulation, states, equations, the call).
type Entry = (&'static str, &'static str, &'static str, usize, usize, Box<dyn FnMut()>);

macro_rules! entries {
    ($out:expr, $m:ident, $label:expr, [$($f:ident),*]) => {{
        use generated::$m as model;
        $(
            let params = model::Params::default();
            let (state, g_i) = model::$f::initial_state(0.0, &model::INITIAL_Q, &model::INITIAL_QDOT, &params).unwrap();
            let mut dstate = [0.0; model::$f::STATES];
            let equations = generated::find(stringify!($m)).unwrap().formulations.iter().find(|f| f.name() == stringify!($f)).unwrap().equations;
            $out.push((
                $label,
                stringify!($m),
                stringify!($f),
                model::$f::STATES,
                equations,
                Box::new(move || {
                    model::$f::rhs(black_box(0.0), black_box(&state), black_box(&params), black_box(&g_i), &mut dstate).unwrap();
                }) as Box<dyn FnMut()>,
            ));
        )*
    }};
}

fn ns_per_call(call: &mut dyn FnMut()) -> f64 {
    let calls = 2000;
    let start = Instant::now();
    for _ in 0..calls {
        call();
    }
    start.elapsed().as_secs_f64() * 1e9 / calls as f64
}

/// The table's name of a formulation.
fn title(f: &str) -> &'static str {
    match f {
        "lagrange" => "Lagrange",
        "maggi" => "Maggi",
        "kane" => "Kane",
        _ => "reduced Volterra",
    }
}

fn main() {
    let root = concat!(env!("CARGO_MANIFEST_DIR"), "/..");
    let mut entries: Vec<Entry> = Vec::new();
    entries!(entries, cart_pendulum, "1 cart_pendulum", [lagrange, maggi, kane, reduced_volterra]);
    entries!(entries, cart_pendulum_baked, "1 cart_pendulum, baked", [kane, reduced_volterra]);
    entries!(entries, three_body, "2 three_body", [lagrange, maggi, kane, reduced_volterra]);
    entries!(entries, three_body_drop, "2 three_body, ignorable not integrated", [reduced_volterra]);
    entries!(entries, three_body_split, "2 three_body, split every 40 lets", [kane, reduced_volterra]);
    entries!(entries, satellite_boom, "3 satellite_boom", [lagrange, maggi, kane, reduced_volterra]);
    entries!(entries, three_body_quaternion, "2 three_body, quaternions", [lagrange, maggi, kane, reduced_volterra]);
    entries!(entries, satellite_boom_quaternion, "3 satellite_boom, quaternions", [lagrange, maggi, kane, reduced_volterra]);
    // Operation counts: each module's generation summary, with the options it was committed with.
    let mut ops = std::collections::HashMap::new();
    for (module, model, edit) in variants::variants() {
        if !entries.iter().any(|e| e.1 == module) {
            continue;
        }
        let m = generator::model::load(format!("{root}/models/{model}.ron")).unwrap();
        let mut options = generator::emit::Options { module_name: Some(module.to_string()), jacobian: true, ..generator::emit::Options::from_model(&m) };
        edit(&mut options);
        for f in generator::generate(&m, &options).unwrap().summary.functions {
            ops.insert((module, f.name.clone()), (f.ops.total(), f.solve.total()));
        }
    }
    let mut best = vec![f64::INFINITY; entries.len()];
    for _ in 0..30 {
        for (k, e) in entries.iter_mut().enumerate() {
            best[k] = best[k].min(ns_per_call(&mut e.5));
        }
    }
    let mut rows = Vec::new();
    for (k, (label, module, form, states, equations, _)) in entries.iter().enumerate() {
        let (assembly, solve) = ops[&(*module, format!("{form}::rhs"))];
        // Against Kane's call of the same module, in the scenes' own rows.
        let kane = entries.iter().position(|e| e.1 == *module && e.2 == "kane");
        let against_kane = match kane {
            Some(j) if label.chars().all(|c| c != ',') => format!("{:.2}", best[k] / best[j]),
            _ => String::new(),
        };
        // The attitude in quaternions against the same formulation in Euler angles.
        let euler = module.strip_suffix("_quaternion").and_then(|m| entries.iter().position(|e| e.1 == m && e.2 == *form));
        let against_euler = euler.map_or(String::new(), |j| format!("{:.2}", best[k] / best[j]));
        rows.push(vec![
            label.to_string(),
            title(form).to_string(),
            states.to_string(),
            equations.to_string(),
            format!("{assembly} + {solve}"),
            format!("{:.0}", best[k]),
            against_kane,
            against_euler,
        ]);
    }
    let columns = ["scene", "formulation", "states", "equations", "assembly + solve ops", "ns/call", "/ Kane (ns)", "/ Euler angles (ns)"];
    let json = serde_json::json!({ "command": COMMAND, "columns": columns, "rows": rows });
    let table = std::iter::once(columns.join(" | ")).chain(rows.iter().map(|r| r.join(" | "))).collect::<Vec<_>>().join("\n");
    println!("{table}");
    std::fs::write(format!("{root}/docs/benchmarks/rhs.json"), serde_json::to_string_pretty(&json).unwrap() + "\n").unwrap();
}
