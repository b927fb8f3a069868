use generator::formulation::{ignorable, mechanics, volterra};
use generator::model::examples::{floating_chain, n_link_pendulum_on_cart};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args[2].parse().unwrap();
    let model = if args[1] == "pendulum" { n_link_pendulum_on_cart(n) } else { floating_chain(n) }.build().unwrap();
    let t = std::time::Instant::now();
    let mech = mechanics::derive(&model);
    eprintln!("mechanics {:.3} s {:?}", t.elapsed().as_secs_f64(), mech.tidy.report());
    let chosen = ignorable::choose(&model, &ignorable::analyze(&model, &mech)).unwrap();
    eprintln!("ignorable {:.3} s", t.elapsed().as_secs_f64());
    let kane = volterra::derive(&model, &mech, &[], &model.quasi_full).unwrap();
    eprintln!("kane {:.3} s {:?}", t.elapsed().as_secs_f64(), mech.tidy.report());
    let _r = volterra::derive_reduced(&model, &mech, &chosen, &model.quasi_reduced, &kane).unwrap();
    eprintln!("reduced {:.3} s {:?}", t.elapsed().as_secs_f64(), mech.tidy.report());
}
