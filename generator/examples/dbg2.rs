use generator::formulation::{mechanics, volterra};
use generator::symbolic::Symbol;
fn main() {
    let model = generator::model::load("models/three_body.ron").unwrap();
    let mech = mechanics::derive(&model);
    for (i, b) in mech.bodies.iter().enumerate() {
        let syms: Vec<String> = b.accel.iter().flat_map(|e| e.free_symbols()).map(|s| s.name()).collect::<std::collections::BTreeSet<_>>().into_iter().collect();
        println!("body {i} in_body {} accel syms {:?}", b.in_body, syms);
    }
    let h: Vec<String> = mech.inertial.iter().map(|e| format!("{:?}", e.free_symbols().iter().map(|s| s.name()).filter(|n| n.ends_with('\'')).collect::<Vec<_>>())).collect();
    println!("h rates: {:?}", h);
    let _ = volterra::quasi_symbol(0);
    let _ = Symbol::new("x");
}
