//! What emission hands to in-process evaluation ([`crate::eval`]): every emitted function as a
//! [`Tape`], and what the module's hand-written parts do around them (sizes, names, each
//! formulation's state layout, checks and solve).

use super::tape::Tape;
use seam::FormulationKind;
use std::collections::HashMap;

/// What the module describes of itself: `model()`'s sizes, names and values.
#[derive(Clone, Debug, Default)]
pub struct Description {
    pub module: String,
    pub name: String,
    pub coordinates: Vec<String>,
    pub constraints: Vec<String>,
    pub ignorable: Vec<usize>,
    /// The holonomic constraints' names (the first `holonomic` of `constraints`).
    pub holonomic_names: Vec<String>,
    pub parameter_names: Vec<String>,
    pub inputs: Vec<usize>,
    pub default_params: Vec<f64>,
    pub initial: Option<(Vec<f64>, Vec<f64>)>,
    pub run: Option<(f64, f64, f64)>,
    pub paper_settings: bool,
    pub energy_balance: seam::EnergyBalance,
    pub events: Vec<seam::Event>,
    pub gimbals: Vec<seam::Gimbal>,
}

/// What a formulation's hand-written functions do around its tapes: the layout of `assemble`'s
/// outputs and of the state, and the names its errors carry.
#[derive(Clone, Debug)]
pub struct FormShape {
    pub kind: FormulationKind,
    /// Coordinates in the state (indices into the model's coordinates).
    pub kept: Vec<usize>,
    pub speeds: usize,
    pub work: bool,
    pub equations: usize,
    pub state_names: Vec<String>,
    /// Size `n` of the matrix solved.
    pub matrix_size: usize,
    /// Maggi: the speeds' rates are `W x + c` with `W` of `(rows, cols)`.
    pub post: Option<(usize, usize)>,
    /// What each checked singular factor's vanishing means.
    pub conditions: Vec<String>,
    pub matrix_name: String,
    /// Lagrange: the number of constraints stabilized by `rhs_baumgarte`.
    pub stabilization: Option<usize>,
    /// The power ends with `matrix_size` weights on the solution (moving constraints).
    pub power_weights: bool,
    pub depends_on_time: bool,
    /// How `rhs` solves its matrix (the plan the module's code follows).
    pub solve: super::ldl::Solve,
    /// `initial_state` reads `G_I` from the module's `momenta` (its tape's outputs leave them out).
    pub momenta_by_function: bool,
}

impl FormShape {
    /// The formulation's own checked factors: `conditions` without the articulated-body
    /// recursion's pivots, which only `rhs` computes (the Jacobian differentiates the dense
    /// assembly and checks these alone).
    pub fn formulation_conditions(&self) -> &[String] {
        let pivots = match &self.solve {
            super::ldl::Solve::Articulated { pivots } => *pivots,
            _ => 0,
        };
        &self.conditions[..self.conditions.len() - pivots]
    }

    /// How the solution becomes the state's rates, for `seam::rates`.
    pub fn layout(&self) -> seam::rates::Layout {
        seam::rates::Layout { speeds: self.speeds, post: self.post, work: self.work }
    }
}

/// Every function of a module as tapes, with the shapes around them.
#[derive(Clone, Debug, Default)]
pub struct Program {
    pub description: Description,
    /// Tapes by function: `energy`, `kane::rhs`, `kane::initial_state`, ...
    pub tapes: HashMap<String, Tape>,
    pub forms: Vec<FormShape>,
}
