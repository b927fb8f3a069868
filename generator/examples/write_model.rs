//! Writes a benchmark model as RON: `write_model [pendulum|floating|planar] [n]`.
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(2).map_or(5, |s| s.parse().unwrap());
    let b = match args.get(1).map(String::as_str) {
        Some("floating") => generator::model::examples::floating_chain(n),
        Some("planar") => generator::model::examples::planar_chain_absolute(n),
        _ => generator::model::examples::n_link_pendulum_on_cart(n),
    };
    print!("{}", b.to_ron());
}
