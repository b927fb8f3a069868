use generator::formulation::{Request, derive};
use generator::symbolic::Expr;
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let model = generator::model::load(&path).unwrap();
    let d = derive(&model, &Request::all()).unwrap();
    let l = &d.equations[0];
    let k = &d.equations[2];
    eprintln!("{} {} speeds {:?} {:?}", l.kind, k.kind, l.speeds.len(), k.speeds.len());
    let map: std::collections::HashMap<_, Expr> = l.speeds.iter().zip(&k.qdot).map(|(a, b)| (*a, *b)).collect();
    let mut same = 0;
    let mut diff = 0;
    let kset: std::collections::HashSet<Expr> = k.mass.data.iter().chain(&k.forcing).copied().collect();
    for a in l.mass.data.iter() {
        if kset.contains(&a.subs(&map)) { same += 1 } else { diff += 1 }
    }
    eprintln!("mass same {same} diff {diff}");
    let (mut same, mut diff) = (0, 0);
    for (i, (a, b)) in l.forcing.iter().zip(&k.forcing).enumerate() {
        if kset.contains(&a.subs(&map)) {
            same += 1
        } else {
            diff += 1;
            if diff < 2 {
                eprintln!("{i}: L {}\n K {}", a.subs(&map), b)
            }
        }
    }
    eprintln!("forcing same {same} diff {diff}; kane qdot {:?}", k.qdot.iter().take(3).map(|e| e.to_string()).collect::<Vec<_>>());
}
