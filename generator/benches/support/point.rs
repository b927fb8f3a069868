//! A random state of a model where a peer's model is checked against ours (the scaling
//! benchmark's SymPy checks, the Pinocchio benchmark's ABA checks): the same draws on every
//! machine.

use generator::symbolic::SplitMix;
use seam::{FormulationKind, Model};

/// Numbers in `[-1, 1)` from SplitMix64 with a fixed seed.
pub struct Draws(SplitMix);

impl Draws {
    pub fn new() -> Draws {
        Draws(SplitMix(0x9e37_79b9_7f4a_7c15))
    }

    pub fn next(&mut self) -> f64 {
        self.0.uniform(-1.0, 1.0)
    }
}

/// Kane's state with its coordinates and quasi-velocities drawn (the work integral 0), and the
/// `(q, q')` it stands for (Kane's `velocities`: a velocity constraint holds).
pub fn kane_state(model: &Model, t: f64, params: &[f64], draws: &mut Draws) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let kane = model.formulation(FormulationKind::Kane).expect("the model has Kane's form");
    let mut state: Vec<f64> = (0..kane.states()).map(|_| draws.next()).collect();
    if let Some(w) = kane.layout.work_index() {
        state[w] = 0.0;
    }
    let n = model.coordinates.len();
    let (mut q, mut qdot) = (vec![0.0; n], vec![0.0; n]);
    kane.velocities(t, &state, params, &vec![0.0; model.ignorable.len()], &mut q, &mut qdot).expect("Kane's velocities at the point");
    (state, q, qdot)
}

/// Lagrange's accelerations `q''` at `(q, q')`.
pub fn lagrange_accelerations(model: &Model, t: f64, params: &[f64], q: &[f64], qdot: &[f64]) -> Vec<f64> {
    let n = model.coordinates.len();
    let lagrange = model.formulation(FormulationKind::Lagrange).expect("the model has Lagrange's form");
    assert!(lagrange.layout.holds_every_rate(n), "Lagrange's state is [q; q'; W?]");
    let (mut x, mut g) = (vec![0.0; lagrange.states()], vec![0.0; model.ignorable.len()]);
    lagrange.initial_state(t, q, qdot, params, &mut x, &mut g).expect("Lagrange's state at the point");
    let mut dx = vec![0.0; x.len()];
    lagrange.rhs(t, &x, params, &g, &mut dx).expect("Lagrange's right-hand side at the point");
    dx[n..2 * n].to_vec()
}
