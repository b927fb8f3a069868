//! The scaling benchmark's models at n = 3 and n = 8 (the n-link pendulum on a cart and the
//! spatial chain on a floating base): the four formulations give the same accelerations, and
//! they satisfy Lagrange's equations derived from T by differentiation, at random admissible
//! states. The models of `models/` get the same check.

use generator::formulation::{Request, derive};
use generator::model::examples::{floating_chain, n_link_pendulum_on_cart};

use crate::common;
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

#[test]
fn parameters_named_like_the_generator_s_own_symbols_do_not_alias_them() {
    // Scene 1 with its cart mass called `u1` (the name of the first quasi-velocity) and its motor
    // torque called `G_x` (the name of the momentum of x): the same system, so the same
    // equations, and the emitted module compiles with both.
    let text = std::fs::read_to_string(format!("{}/models/cart_pendulum.ron", env!("CARGO_MANIFEST_DIR"))).unwrap();
    let renamed = text
        .replace("\"M\": 2.0", "\"u1\": 2.0")
        .replace("mass: \"M\"", "mass: \"u1\"")
        .replace("\"M\": \"kg\"", "\"u1\": \"kg\"")
        .replace("\"tau\": 0.0", "\"G_x\": 0.3")
        .replace("\"tau\": \"N m\"", "\"G_x\": \"N m\"")
        .replace("{\"theta1\": \"tau\", \"theta2\": \"-tau\"}", "{\"theta1\": \"G_x\", \"theta2\": \"-G_x\"}");
    assert_eq!(renamed.matches("u1").count(), 3, "the three places renamed (parameter, mass, unit)");
    let dir = std::env::temp_dir().join(format!("aliases-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("cart_pendulum.ron");
    std::fs::write(&file, &renamed).unwrap();
    let model = generator::model::load(&file).unwrap();
    let d = derive(&model, &Request::all()).unwrap();
    assert_eq!(d.ignorable, vec![2], "x stays ignorable");
    check_formulations_agree("cart_pendulum with u1 and G_x", &d, &model, 4, 23);
    let code = generator::generate(&model, &generator::emit::Options::from_model(&model)).unwrap().code;
    assert!(code.contains("pub u1: f64") && code.contains("pub G_x: f64"), "the parameters keep their names");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The spatial chains on a floating base take each route over their tree: at 4 links Kane's
/// and the reduced right-hand sides assemble their matrices by the composite-body recursion
/// and solve them (fewer operations than the dense entries, and than the articulated-body
/// recursion); at 8 links both give their rates by the articulated-body recursion (no matrix,
/// no solve); Lagrange's and Maggi's assemble the dense entries. Integrated in-process over the
/// reference run, the four follow the same trajectory, keep the energy (no forces), and the
/// reduced one keeps the momenta.
#[test]
fn the_recursive_assembly_integrates_like_the_dense_one_on_the_floating_chain() {
    for (links, route) in [(4, "assembly: recursion over the tree of frames"), (8, "assembly: articulated-body recursion")] {
        integrates_like_the_dense_one(links, route);
    }
}

fn integrates_like_the_dense_one(links: usize, route: &str) {
    use runtime::compare::{Options, compare};
    use runtime::integrate::{Method, Settings};
    let model = floating_chain(links).build().unwrap();
    let (evaluated, summary) = generator::evaluate_reporting(&model, &generator::emit::Options::from_model(&model)).unwrap();
    for (name, how) in &summary.solves {
        let over_the_tree = name == "kane" || name == "reduced_volterra";
        assert_eq!(how.contains(route), over_the_tree, "{links} links, {name}: {how}");
    }
    let (t0, t1, _) = evaluated.run.unwrap();
    let settings = Settings { method: Method::Dop853, rtol: 1e-11, atol: 1e-11, h_max: 0.1 * (t1 - t0), ..Settings::default() };
    let options = Options { settings, repeats: 1, formulations: vec![], drift: runtime::system::Drift::None, reference: None };
    let runs = compare(&evaluated, &options).unwrap();
    assert_eq!(runs.len(), 4);
    let lagrange = &runs.iter().find(|r| r.record.method == "lagrange").unwrap().invariants.coordinates;
    for r in &runs {
        let d = r.invariants.coordinates.iter().zip(lagrange).flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs())).fold(0.0, f64::max);
        assert!(d < 1e-7, "{}: {d:e} from Lagrange's trajectory", r.record.method);
        assert!(r.record.energy_error_rel < 1e-8, "{}: energy error {:e} (rel)", r.record.method, r.record.energy_error_rel);
    }
    let reduced = &runs.iter().find(|r| r.record.method == "reduced_volterra").unwrap().record;
    assert!(reduced.momentum_error_rel < 1e-12, "reduced momentum error {:e} (rel)", reduced.momentum_error_rel);
}
