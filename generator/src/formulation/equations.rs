//! The contract every formulation implements, as SymPy's mechanics `_Methods` does: a state
//! layout, the mass matrix and forcing of the linear system the right-hand side solves, and how
//! the state's rates follow from its solution. [`crate::emit`] emits any [`Equations`] the same
//! way; [`crate::inspect`] prints them.
//!
//! ```
//! use generator::formulation::{derive, Request};
//! let model = generator::model::load("../models/cart_pendulum.ron").unwrap();
//! let d = derive(&model, &Request::all()).unwrap();
//! let reduced = d.equations("reduced_volterra").unwrap();
//! assert_eq!((reduced.mass.rows, reduced.speeds.len(), reduced.kept.len()), (1, 1, 3));
//! ```

use crate::model::ModelError;
use crate::symbolic::transfer::{Transfer, Visitor};
use crate::symbolic::{Expr, Matrix, Symbol};

/// The equations of motion of one formulation, ready to emit.
#[derive(Clone, Debug)]
pub struct Equations {
    /// Which formulation these are (its module name in emitted code is the kind's name).
    pub kind: seam::FormulationKind,
    /// A readable name, for documentation.
    pub label: &'static str,
    /// Indices of the coordinates in the state, in order (all of them unless the ignorable
    /// ones are left out).
    pub kept: Vec<usize>,
    /// The second half of the state: quasi-velocities, or the rates `q'`.
    pub speeds: Vec<Symbol>,
    /// Runtime inputs beside the state: the conserved momenta `G_I`.
    pub momenta: Vec<Symbol>,
    /// `q'` of every coordinate in terms of the state.
    pub qdot: Vec<Expr>,
    /// The speeds in terms of `q, q'` (for the initial state).
    pub speeds_from_qdot: Vec<Expr>,
    /// `mass x = forcing`, solved numerically by the right-hand side (symmetric).
    pub mass: Matrix,
    pub forcing: Vec<Expr>,
    /// Maggi: the speeds' rates are `W x + c` (`None`: they are the first entries of `x`).
    pub post: Option<(Matrix, Vec<Expr>)>,
    /// Factors whose vanishing makes the symbolic elimination singular.
    pub singular: Vec<Expr>,
    /// Number of dynamical equations, as the paper's Table 1 counts them.
    pub equations: usize,
    /// What `mass` is, for error messages.
    pub matrix_name: &'static str,
    /// Lagrange: per constraint, its velocity residual `a q' + b` and its position residual
    /// (zero for a velocity constraint), for Baumgarte stabilization.
    pub stabilization: Option<Vec<(Expr, Expr)>>,
    /// How the velocity transformation was eliminated, for the summary and `inspect`.
    pub elimination: &'static str,
    /// Where a constraint moves: the power of the constraint forces as `(weights, offset)`,
    /// `R . q' = weights . x + offset` for the solution `x` (`power`); filled in by
    /// [`super::derive_with`].
    pub constraint_power: Option<(Vec<Expr>, Expr)>,
    /// The same `mass` and `forcing` as a recursion over the tree of frames (Kane's form):
    /// emission keeps it where it takes fewer operations (`composite`).
    pub recursion: Option<super::composite::Recursion>,
    /// The speeds' rates `u'` of the same equations by the articulated-body recursion, with no
    /// matrix and no solve (Kane's form on a tree): emission keeps it where its right-hand
    /// side takes fewer operations than an assembly and its solve (`articulated`).
    pub articulated: Option<super::articulated::Articulated>,
}

impl Transfer for Equations {
    fn visit(&mut self, v: &mut dyn Visitor) {
        self.speeds.visit(v);
        self.momenta.visit(v);
        self.qdot.visit(v);
        self.speeds_from_qdot.visit(v);
        self.mass.visit(v);
        self.forcing.visit(v);
        self.post.visit(v);
        self.singular.visit(v);
        self.stabilization.visit(v);
        self.constraint_power.visit(v);
        self.recursion.visit(v);
        self.articulated.visit(v);
    }
}

impl Equations {
    /// The module name in emitted code: `lagrange`, `maggi`, `kane`, `reduced_volterra`.
    pub fn name(&self) -> &'static str {
        self.kind.name()
    }

    /// Length of the state: kept coordinates, speeds, and `W` when forces do work.
    pub fn states(&self, work: bool) -> usize {
        self.kept.len() + self.speeds.len() + usize::from(work)
    }
}

/// A formulation of the equations of motion: derives its [`Equations`] from what every
/// formulation shares.
pub trait Method {
    /// Which formulation it is.
    fn kind(&self) -> seam::FormulationKind;
    /// The module name in emitted code.
    fn name(&self) -> &'static str {
        self.kind().name()
    }
    /// The equations, from the shared derivation.
    fn equations(&self, shared: &super::Shared) -> Result<Equations, ModelError>;
}
