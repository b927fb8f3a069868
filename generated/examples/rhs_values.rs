//! The right-hand sides of every committed module (built by rustc) at states near each model's
//! initial one, as JSON on stdout: what the Python wheel's tests compare its in-process
//! evaluation against (`python/tests/test_models.py` runs this).
//!
//! `cargo run --release -p generated --example rhs_values`
//!
//! Per model and formulation: the time, the parameters (the model's defaults), the conserved
//! momenta of the initial state, and `STATES` states `x` (the initial state with every entry
//! moved by up to 0.1, from a fixed seed) with `f(t, x)`. Floats are printed to round trip.

const STATES: usize = 4;

/// SplitMix64: a fixed, portable sequence of uniform numbers in [-1, 1).
struct Uniform(u64);

impl Uniform {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut uniform = Uniform(2026);
    let mut out = Vec::new();
    for model in generated::models() {
        let m = model.coordinates.len();
        let (q0, qd0) = model.initial.clone().unwrap_or((vec![0.0; m], vec![0.0; m]));
        for form in &model.formulations {
            let (mut y0, mut g_i) = (vec![0.0; form.states()], vec![0.0; model.ignorable.len()]);
            form.initial_state(0.0, &q0, &qd0, &model.default_params, &mut y0, &mut g_i)?;
            let t = 0.3;
            let mut states = Vec::new();
            for _ in 0..STATES {
                let x: Vec<f64> = y0.iter().map(|v| v + 0.1 * uniform.next()).collect();
                let mut dx = vec![0.0; x.len()];
                form.rhs(t, &x, &model.default_params, &g_i, &mut dx)?;
                states.push(serde_json::json!({ "x": x, "rhs": dx }));
            }
            out.push(serde_json::json!({
                "model": model.module,
                "formulation": form.kind.name(),
                "t": t,
                "params": model.default_params,
                "momenta": g_i,
                "states": states,
            }));
        }
    }
    println!("{}", serde_json::to_string(&out)?);
    Ok(())
}
