use generator::emit::{Options, generate};
use generator::model::builder::{Body, Frame, ModelBuilder};
fn main() {
    let n: usize = std::env::args().nth(1).unwrap().parse().unwrap();
    let mut b = ModelBuilder::new("rel").coordinate("x").parameter("g", 9.81).parameter("l", 1.0).parameter("m", 1.0);
    for i in 1..=n {
        b = b.coordinate(format!("q{i}"));
    }
    b = b.frame(Frame::new("cart", "world").translation(["x", "0", "0"])).body(Body::new("cart", "cart", "m"));
    for i in 1..=n {
        let parent = if i == 1 { "cart".to_string() } else { format!("L{}", i - 1) };
        let f = if i == 1 { Frame::new(format!("L{i}"), parent) } else { Frame::new(format!("L{i}"), parent).translation(["0", "-l", "0"]) };
        b = b.frame(f.rotate_z(format!("q{i}"))).body(Body::new(format!("P{i}"), format!("L{i}"), "m").com(["0", "-l", "0"]));
    }
    let rates: Vec<String> = std::iter::once("x'".to_string()).chain((1..=n).map(|i| format!("q{i}'"))).collect();
    let model = b.gravity(["0", "-g", "0"]).quasi_velocities(rates.clone(), rates[1..].to_vec()).ignorable(["x"]).build().unwrap();
    let t = std::time::Instant::now();
    let out = generate(&model, &Options::from_model(&model)).unwrap();
    for f in &out.summary.functions {
        if f.name.ends_with("::rhs") {
            eprintln!("{} assembly {} solve {}", f.name, f.ops.total(), f.solve.total());
        }
    }
    eprintln!("total {:.3} s", t.elapsed().as_secs_f64());
}
