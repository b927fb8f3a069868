//! Development probe: derive + emit a chain of size n in a context of its own, print the
//! summary and the nodes the deriving thread's context holds.
use generator::emit::{Options, generate};
use generator::model::examples::{floating_chain, n_link_pendulum_on_cart};
use generator::symbolic::Context;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let kind = args[1].as_str();
    let n: usize = args[2].parse().unwrap();
    let b = if kind == "pendulum" { n_link_pendulum_on_cart(n) } else { floating_chain(n) };
    let t = std::time::Instant::now();
    let cx = Context::new();
    let out = cx.enter(|| {
        let model = b.build().unwrap();
        generate(&model, &Options::from_model(&model)).unwrap()
    });
    eprintln!("{}", out.summary);
    eprintln!("total {:.3} s, {} bytes, {} nodes", t.elapsed().as_secs_f64(), out.code.len(), cx.nodes());
    if args.len() > 3 {
        std::fs::write(&args[3], &out.code).unwrap();
    }
}
