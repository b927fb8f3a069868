//! Fused multiply-adds (`Options::fma`): the emitted bodies and unrolled solves call
//! `f64::mul_add` where the plain code multiplies and adds, and the compiled module gives the plain module's right-hand sides
//! to round-off, on the paper's scenes 2 and 3 and the spatial chain of 8 links (whose Kane
//! and reduced forms take the recursive assembly).

use crate::support;

use generator::emit::Options;

use generator::generate;

#[test]
fn fused_modules_give_the_plain_modules_rates_to_round_off() {
    let dir = tempfile::tempdir().unwrap();
    let root = env!("CARGO_MANIFEST_DIR");
    let models = [
        generator::model::load(format!("{root}/../models/three_body.ron")).unwrap(),
        generator::model::load(format!("{root}/../models/satellite_boom.ron")).unwrap(),
        generator::model::examples::floating_chain(8).build().unwrap(),
    ];
    let mut fused_solves = 0;
    for model in models {
        let plain = generate(&model, &Options::from_model(&model)).unwrap();
        let fused = generate(&model, &Options { fma: true, ..Options::from_model(&model) }).unwrap();
        assert!(!plain.code.contains("mul_add"), "{}: the plain module fuses", model.name);
        let calls = fused.code.matches("f64::mul_add(").count();
        assert!(calls > 50, "{}: {calls} fused multiply-adds", model.name);
        // The unrolled solves fuse their eliminations too (`d1 = a[1][1] - l1_0 * u1_0`), where
        // a formulation solves its matrix by one (the chain's recursions solve none).
        let solves: Vec<&str> = fused.code.split("fn solve_ldl(").skip(1).map(|rest| rest.split("Ok(())").next().unwrap()).collect();
        let plain_solves = plain.code.matches("fn solve_ldl(").count();
        assert_eq!(solves.len(), plain_solves, "{}", model.name);
        for solve in &solves {
            assert!(solve.contains("f64::mul_add("), "{}: a solve left unfused:\n{solve}", model.name);
        }
        fused_solves += solves.len();
        // The same operation counts: fusing changes how they round, not what they compute; both
        // compile without a parenthesis too many (`-D unused_parens`).
        assert_eq!(plain.summary.work_counters(), fused.summary.work_counters(), "{}", model.name);
        let a = support::rustc::printed_rates(dir.path(), &format!("{}_plain", model.name), &plain.code, &["-C", "opt-level=1", "-D", "unused_parens"]);
        let b = support::rustc::printed_rates(dir.path(), &format!("{}_fma", model.name), &fused.code, &["-C", "opt-level=1", "-D", "unused_parens"]);
        assert_eq!(a.len(), b.len());
        let (mut compared, mut differing) = (0, 0);
        for ((name, k, x), (name_b, k_b, y)) in a.iter().zip(&b) {
            assert_eq!((name, k), (name_b, k_b));
            let (Some(x), Some(y)) = (x, y) else {
                assert_eq!(x.is_none(), y.is_none(), "{} {name} #{k}: one refused, the other did not", model.name);
                continue;
            };
            // Round-off of the assembly and the solve, relative to the largest rate of the call.
            let scale = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (i, (u, v)) in x.iter().zip(y).enumerate() {
                assert!((u - v).abs() <= 1e-12 * scale, "{} {name} #{k} [{i}]: plain {u:e}, fused {v:e}", model.name);
                compared += 1;
                differing += usize::from(u != v);
            }
        }
        assert!(compared > 50, "{}: {compared} values", model.name);
        // The fused code rounds differently: some rates differ in their last bits.
        assert!(differing > 0, "{}: every rate bit for bit the plain code's", model.name);
    }
    // Scenes 2 and 3 solve their matrices: the solves were looked at.
    assert!(fused_solves >= 2, "{fused_solves} unrolled solves");
}
