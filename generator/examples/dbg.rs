use generator::formulation::{derive, Request};
use generator::symbolic::expr::dag_ops;
fn main() {
    let model = generator::model::load(std::env::args().nth(1).unwrap()).unwrap();
    let d = derive(&model, &Request::all()).unwrap();
    let k = d.kane.as_ref().unwrap();
    let r = d.reduced.as_ref().unwrap();
    for (i, l) in k.l_ni.iter().enumerate() {
        let syms: Vec<String> = l.free_symbols().iter().map(|s| s.name()).collect();
        println!("L_K[{i}] ops {} syms {:?}", dag_ops(&[*l]), syms);
    }
    println!("kane M {} L {} qdot {}", dag_ops(&k.mass_ni.data), dag_ops(&k.l_ni), dag_ops(&k.qdot));
    println!("red  M {} L {} qdot {} route {}", dag_ops(&r.mass_ni.data), dag_ops(&r.l_ni), dag_ops(&r.qdot), r.route);
}
