use generator::formulation::{ignorable, mechanics, volterra};
use generator::model::examples::floating_chain;
use generator::symbolic::expr::post_order;
fn main() {
    let n: usize = std::env::args().nth(1).unwrap().parse().unwrap();
    let model = floating_chain(n).build().unwrap();
    let mech = mechanics::derive(&model);
    let chosen = ignorable::choose(&model, &ignorable::analyze(&model, &mech)).unwrap();
    let kane = volterra::derive(&model, &mech, &[], &model.quasi_full).unwrap();
    let schur = volterra::by_schur_complement(&model, &mech, &chosen, &model.quasi_reduced, &kane).unwrap();
    let sz = |v: &[generator::symbolic::Expr]| post_order(v).len();
    for (name, v) in [("kane", &kane), ("schur", &schur)] {
        let all: Vec<_> = v.mass_ni.data.iter().chain(&v.l_ni).chain(&v.qdot).copied().collect();
        println!("{name}: M {} L {} qdot {} all {}", sz(&v.mass_ni.data), sz(&v.l_ni), sz(&v.qdot), sz(&all));
    }
}
