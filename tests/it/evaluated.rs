//! Every committed module, evaluated in-process (`generator::eval`), gives the compiled module's
//! numbers to 1e-13 relative: every shared function (the event functions and reset maps among
//! them) at random coordinates and rates, and every
//! formulation's `rhs`, `rhs_baumgarte`, `matrix`, `velocities`, `singular_margin`,
//! `initial_state` and exact `jacobian` and `parameter_jacobian` at random states around the
//! reference run's.

use generator::emit::Options;
use seam::{Failure, Model};

#[path = "../../generated/tests/common/variants.rs"]
mod variants;
use variants::variants;

/// A small deterministic generator (xorshift), so failures reproduce.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

fn evaluated(module: &str, file: &str, edit: fn(&mut Options)) -> Model {
    evaluated_by(module, file, edit, &generator::eval::kernel::Interpreter)
}

/// The module evaluated in-process, its tapes run by `backend`.
fn evaluated_by(module: &str, file: &str, edit: fn(&mut Options), backend: &dyn generator::eval::kernel::Backend) -> Model {
    let m = generator::model::load(format!("{}/models/{file}.ron", env!("CARGO_MANIFEST_DIR"))).unwrap();
    // The committed modules carry their Jacobians, as the regeneration test makes them.
    let mut options = Options { module_name: Some(module.to_string()), jacobian: true, ..Options::from_model(&m) };
    edit(&mut options);
    generator::evaluate_with_backend(&m, &options, backend).unwrap().0
}

/// Both succeeded with outputs equal to 1e-13 relative, or both failed the same way.
fn same(what: &str, a: Result<Vec<f64>, Failure>, b: Result<Vec<f64>, Failure>) -> usize {
    match (a, b) {
        (Ok(a), Ok(b)) => {
            assert_eq!(a.len(), b.len(), "{what}");
            for (k, (x, y)) in a.iter().zip(&b).enumerate() {
                let scale = x.abs().max(y.abs());
                assert!((x - y).abs() <= 1e-13 * scale || x == y, "{what}[{k}]: compiled {x:e}, evaluated {y:e}");
            }
            a.len()
        }
        (Err(a), Err(b)) => {
            assert_eq!(std::mem::discriminant(&a), std::mem::discriminant(&b), "{what}: {a} against {b}");
            0
        }
        (a, b) => panic!("{what}: compiled {a:?}, evaluated {b:?}"),
    }
}

#[test]
fn every_committed_module_evaluated_in_process_equals_the_compiled_one() {
    compare_every_module(&generator::eval::kernel::Interpreter);
}

/// The same with the tapes compiled to machine code by cranelift (`jit`): the same operations in
/// the same order, so the same numbers.
#[test]
fn every_committed_module_compiled_by_the_jit_equals_the_compiled_one() {
    let jit = jit::Jit::default();
    compare_every_module(&jit);
    assert_eq!(jit.interpreted(), 0, "every tape compiles");
}

fn compare_every_module(backend: &dyn generator::eval::kernel::Backend) {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut jacobians = 0;
    for (module, file, edit) in variants() {
        let compiled = generated::find(module).unwrap();
        let eval = evaluated_by(module, file, edit, backend);
        assert_eq!(
            (&eval.module, &eval.coordinates, &eval.constraints, &eval.ignorable),
            (&compiled.module, &compiled.coordinates, &compiled.constraints, &compiled.ignorable)
        );
        assert_eq!((&eval.parameter_names, &eval.default_params, eval.holonomic), (&compiled.parameter_names, &compiled.default_params, compiled.holonomic));
        assert_eq!((&eval.initial, eval.run), (&compiled.initial, compiled.run));
        assert_eq!(eval.kinds(), compiled.kinds(), "{module}");
        let m = compiled.coordinates.len();
        let params = compiled.default_params.clone();
        let (q0, qd0) = compiled.initial.clone().unwrap_or((vec![0.1; m], vec![0.0; m]));
        let mut compared = 0;
        for trial in 0..20 {
            let q: Vec<f64> = q0.iter().map(|x| x + 0.3 * rng.next()).collect();
            let qd: Vec<f64> = qd0.iter().map(|x| x + 0.3 * rng.next()).collect();
            let t = 0.7 * trial as f64;
            type Point = fn(&Model, f64, &[f64], &[f64], &[f64], &mut [f64]) -> Result<(), Failure>;
            let (events, m) = (compiled.events.len(), compiled.coordinates.len());
            let shared: [(&str, usize, Point); 7] = [
                ("event_values", events, Model::event_values),
                ("event_resets", 2 * m * events, Model::event_resets),
                ("energy", 1, Model::energy),
                ("work_rate", 1, Model::work_rate),
                ("momenta", compiled.ignorable.len(), Model::momenta),
                ("constraint_residuals", compiled.constraints.len(), Model::constraint_residuals),
                ("position_residuals", compiled.holonomic, Model::position_residuals),
            ];
            for (name, n, f) in shared {
                let call = |model: &Model| {
                    let mut out = vec![0.0; n];
                    f(model, t, &q, &qd, &params, &mut out).map(|()| out)
                };
                compared += same(&format!("{module} {name}"), call(&compiled), call(&eval));
            }
            assert_eq!((&compiled.events, &compiled.inputs), (&eval.events, &eval.inputs), "{module}");
            for (fc, fe) in compiled.formulations.iter().zip(&eval.formulations) {
                assert_eq!((fc.kind, &fc.layout, fc.equations, &fc.state_names), (fe.kind, &fe.layout, fe.equations, &fe.state_names));
                assert_eq!((fc.matrix_size, fc.has_baumgarte, fc.depends_on_time), (fe.matrix_size, fe.has_baumgarte, fe.depends_on_time));
                assert_eq!((fc.has_jacobian, fc.has_parameter_jacobian), (fe.has_jacobian, fe.has_parameter_jacobian), "{module} {}", fc.kind);
                let what = format!("{module} {}", fc.kind);
                let (n, s) = (fc.states(), compiled.ignorable.len());
                // The state of the reference run's initial values, perturbed.
                let start = |f: &seam::Formulation| {
                    let (mut y, mut g) = (vec![0.0; n], vec![0.0; s]);
                    f.initial_state(0.0, &q0, &qd0, &params, &mut y, &mut g).map(|()| (y, g))
                };
                let (y0, g) = match (start(fc), start(fe)) {
                    (Ok(a), Ok(b)) => {
                        same(&format!("{what} initial_state"), Ok(a.0.iter().chain(&a.1).copied().collect()), Ok(b.0.iter().chain(&b.1).copied().collect()));
                        a
                    }
                    (a, b) => panic!("{what}: initial states {a:?} against {b:?}"),
                };
                let y: Vec<f64> = y0.iter().map(|x| x + 0.2 * rng.next()).collect();
                let rhs = |f: &seam::Formulation| {
                    let mut d = vec![0.0; n];
                    f.rhs(t, &y, &params, &g, &mut d).map(|()| d)
                };
                compared += same(&format!("{what} rhs"), rhs(fc), rhs(fe));
                if fc.has_jacobian {
                    let jac = |f: &seam::Formulation| {
                        let (mut d, mut j) = (vec![0.0; n], vec![0.0; n * n]);
                        f.jacobian(t, &y, &params, &g, &mut d, &mut j).map(|()| [d, j].concat())
                    };
                    compared += same(&format!("{what} jacobian"), jac(fc), jac(fe));
                    jacobians += 1;
                }
                if fc.has_parameter_jacobian {
                    let jac = |f: &seam::Formulation| {
                        let (mut d, mut j) = (vec![0.0; n], vec![0.0; n * params.len()]);
                        f.parameter_jacobian(t, &y, &params, &g, &mut d, &mut j).map(|()| [d, j].concat())
                    };
                    compared += same(&format!("{what} parameter_jacobian"), jac(fc), jac(fe));
                }
                if fc.has_baumgarte {
                    let stab = |f: &seam::Formulation| {
                        let mut d = vec![0.0; n];
                        f.rhs_baumgarte(t, &y, &params, &g, &mut d, 3.0, 5.0).map(|()| d)
                    };
                    compared += same(&format!("{what} rhs_baumgarte"), stab(fc), stab(fe));
                }
                let matrix = |f: &seam::Formulation| {
                    let mut a = vec![0.0; f.matrix_size * f.matrix_size];
                    f.matrix(t, &y, &params, &g, &mut a).map(|()| a)
                };
                compared += same(&format!("{what} matrix"), matrix(fc), matrix(fe));
                let vel = |f: &seam::Formulation| {
                    let (mut a, mut b) = (vec![0.0; m], vec![0.0; m]);
                    f.velocities(t, &y, &params, &g, &mut a, &mut b).map(|()| [a, b].concat())
                };
                compared += same(&format!("{what} velocities"), vel(fc), vel(fe));
                let margin = |f: &seam::Formulation| f.singular_margin(t, &y, &params, &g).map(|x| vec![x]);
                compared += same(&format!("{what} singular_margin"), margin(fc), margin(fe));
                // Off the constraints, both refuse the same way.
                if !compiled.constraints.is_empty() {
                    let off: Vec<f64> = qd0.iter().map(|x| x + 1.0).collect();
                    let start = |f: &seam::Formulation| f.initial_state(0.0, &q0, &off, &params, &mut vec![0.0; n], &mut vec![0.0; s]).map(|()| vec![]);
                    same(&format!("{what} initial_state off the constraints"), start(fc), start(fe));
                }
            }
        }
        assert!(compared > 100, "{module}: only {compared} values compared");
    }
    assert!(jacobians > 100, "only {jacobians} Jacobians compared");
}

/// Wrong lengths are refused as the compiled module refuses them.
#[test]
fn evaluated_functions_refuse_slices_of_the_wrong_length() {
    let eval = evaluated("cart_pendulum", "cart_pendulum", |_| {});
    let kane = eval.formulation(seam::FormulationKind::Kane).unwrap();
    let e = kane.rhs(0.0, &[0.0; 3], &eval.default_params, &[0.0], &mut [0.0; 6]).unwrap_err();
    assert_eq!(e, Failure::Dimension { argument: "state", expected: 6, got: 3 });
    let e = eval.energy(0.0, &[0.0; 3], &[0.0; 3], &[1.0], &mut [0.0]).unwrap_err();
    assert!(matches!(e, Failure::Dimension { argument: "params", .. }), "{e}");
}

/// Where Kane's mass matrix has structural zeros, its solve follows a sparse `L D L^T` plan in
/// an order of its own; a matrix that is singular there (every mass and inertia zero) is still
/// reported as `Singular`, naming the matrix and the column of the first pivot in that order,
/// by the compiled module and by the evaluator alike, never as NaN.
#[test]
fn a_singular_matrix_is_reported_at_the_first_pivot_of_the_sparse_plan() {
    use generator::emit::Solve;
    for (module, kind) in
        [("satellite_boom", seam::FormulationKind::Kane), ("three_body", seam::FormulationKind::Kane), ("three_body", seam::FormulationKind::Lagrange)]
    {
        let model = generator::model::load(format!("{}/models/{module}.ron", env!("CARGO_MANIFEST_DIR"))).unwrap();
        let d = generator::formulation::derive(&model, &generator::formulation::Request::all()).unwrap();
        let eqs = d.equations.iter().find(|e| e.kind == kind).unwrap();
        let Solve::Ldl(plan) = Solve::for_equations(eqs) else { panic!("{module} {kind}: not LDL^T") };
        assert!(!plan.is_dense(), "{module} {kind}: no structural zero to skip");
        let compiled = generated::find(module).unwrap();
        let eval = evaluated(module, module, |_| {});
        for m in [&compiled, &eval] {
            let f = m.formulation(kind).unwrap();
            let params = vec![0.0; m.parameter_names.len()];
            let (state, g) = (vec![0.1; f.states()], vec![0.0; m.ignorable.len()]);
            let mut ds = vec![0.0; f.states()];
            match f.rhs(0.5, &state, &params, &g, &mut ds) {
                Err(Failure::SingularMatrix { matrix, column, .. }) => {
                    assert_eq!((matrix.as_ref(), column), (eqs.matrix_name, plan.order()[0]), "{module} {kind}");
                }
                other => panic!("{module} {kind}: expected a singular matrix, got {other:?}"),
            }
        }
    }
}
