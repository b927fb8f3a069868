fn main() {
    print!("{}", generator::model::examples::n_link_pendulum_on_cart(5).to_ron());
}
