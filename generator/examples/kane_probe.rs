use generator::formulation::{Request, derive};
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let model = generator::model::load(&path).unwrap();
    let d = derive(&model, &Request::all()).unwrap();
    let r = d.reduced.as_ref().unwrap();
    for (k, e) in r.mass_ni.data.iter().enumerate() {
        let fs: Vec<String> = e.free_symbols().iter().map(|s| s.name()).collect();
        eprintln!("M[{k}] ops {} syms {:?}", generator::symbolic::expr::dag_ops(&[*e]), fs);
    }
    for (k, e) in r.l_ni.iter().enumerate() {
        let fs: Vec<String> = e.free_symbols().iter().map(|s| s.name()).collect();
        eprintln!("L[{k}] ops {} syms {:?}", generator::symbolic::expr::dag_ops(&[*e]), fs);
    }
}
