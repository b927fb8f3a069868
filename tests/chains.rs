//! The scaling benchmark's models at n = 3 and n = 8 (the n-link pendulum on a cart and the
//! spatial chain on a floating base): the four formulations give the same accelerations, and
//! they satisfy Lagrange's equations derived from T by differentiation, at random admissible
//! states. The models of `models/` get the same check.

use generator::formulation::{Request, derive};
use generator::model::examples::{floating_chain, n_link_pendulum_on_cart};

mod common;
use common::{check_formulations_agree, load};

#[test]
fn pendulum_on_cart_formulations_agree_at_3_and_8_links() {
    for n in [3, 8] {
        let model = n_link_pendulum_on_cart(n).build().unwrap();
        let d = derive(&model, &Request::all()).unwrap();
        assert_eq!(d.equations.len(), 4);
        assert_eq!(d.equations("reduced_volterra").unwrap().equations, n, "p - s");
        check_formulations_agree(&model.name, &d, &model, 4, 3 + n as u64);
    }
}

#[test]
fn floating_chain_formulations_agree_at_3_and_8_links() {
    for n in [3, 8] {
        let model = floating_chain(n).build().unwrap();
        let d = derive(&model, &Request::all()).unwrap();
        assert_eq!(d.ignorable.len(), 3);
        assert_eq!(d.equations("reduced_volterra").unwrap().equations, n + 3, "p - s");
        check_formulations_agree(&model.name, &d, &model, 3, 5 + n as u64);
    }
}

#[test]
fn model_files_formulations_agree() {
    for name in ["cart_pendulum", "three_body", "satellite_boom", "cartesian_pendulum", "rolling_disk", "spring_cart", "pendulum_on_cart_5"] {
        let model = load(name);
        let d = derive(&model, &Request::all()).unwrap();
        check_formulations_agree(name, &d, &model, 4, 17);
    }
}

#[test]
fn the_pendulum_model_file_is_the_builders() {
    // models/pendulum_on_cart_5.ron is `n_link_pendulum_on_cart(5).to_ron()`.
    let text = std::fs::read_to_string(format!("{}/models/pendulum_on_cart_5.ron", env!("CARGO_MANIFEST_DIR"))).unwrap();
    assert_eq!(text, n_link_pendulum_on_cart(5).to_ron());
}
