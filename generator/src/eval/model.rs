//! A [`Program`] behind the seam: the emitted module's hand-written parts (the checks, the dense
//! solve, the state's assembly, the errors) over its tapes, step for step as the module does
//! them, so that the numbers are the compiled module's.

use super::kernel::{Backend, Interpreter, Kernel};
use super::{FormShape, Program};
use crate::emit::tape::Tape;
use crate::emit::{LdlPlan, Solve};
use seam::rates::Block;
use seam::solve::Rows;
use seam::{Failure, Formulation, FormulationFunctions, Model, ModelFunctions, StateLayout};
use std::sync::Arc;

/// The tolerances of emitted modules (`generator::emit::module`), read from one place.
use crate::emit::{CONSTRAINT_TOLERANCE, SINGULAR_TOLERANCE};

/// The shared functions of a program (energy, work rate, momenta, residuals).
pub struct Evaluated {
    event_values: Option<Box<dyn Kernel>>,
    event_resets: Option<Box<dyn Kernel>>,
    energy: Option<Box<dyn Kernel>>,
    work_rate: Option<Box<dyn Kernel>>,
    momenta: Option<Arc<dyn Kernel>>,
    constraint_residuals: Option<Box<dyn Kernel>>,
    position_residuals: Option<Box<dyn Kernel>>,
    m: usize,
    params: usize,
}

/// One formulation of a program.
pub struct EvaluatedForm {
    shape: FormShape,
    m: usize,
    params: usize,
    ignorable: usize,
    constraint_names: Arc<[String]>,
    holonomic_names: Arc<[String]>,
    rhs: Box<dyn Kernel>,
    initial_state: Box<dyn Kernel>,
    /// The model's `momenta`, where `initial_state` reads `G_I` from it
    /// ([`FormShape::momenta_by_function`]).
    momenta: Option<Arc<dyn Kernel>>,
    velocities: Box<dyn Kernel>,
    singular_margin: Box<dyn Kernel>,
    /// `matrix`'s own tape where `rhs` assembles none (the articulated-body recursion).
    matrix: Option<Box<dyn Kernel>>,
    /// The unrolled solve (`solve_ldl`, [`Solve::sparse`]) as a kernel of its own, for `rhs_baumgarte`, whose stabilization changes
    /// the forcing between the assembly and the solve.
    ldl: Option<Box<dyn Kernel>>,
    /// The exact Jacobians' tapes, when the module has them.
    jacobian: Option<Box<dyn Kernel>>,
    parameter_jacobian: Option<Box<dyn Kernel>>,
}

fn check(argument: &'static str, slice: &[f64], expected: usize) -> Result<(), Failure> {
    if slice.len() == expected { Ok(()) } else { Err(Failure::Dimension { argument, expected, got: slice.len() }) }
}

/// `[t | params | a | b]`: the input registers of a tape, as `eval::tape::Slots` laid them out.
fn pack(buf: &mut Vec<f64>, t: f64, params: &[f64], a: &[f64], b: &[f64]) {
    buf.clear();
    buf.push(t);
    buf.extend_from_slice(params);
    buf.extend_from_slice(a);
    buf.extend_from_slice(b);
}

thread_local! {
    static INPUTS: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
    static OUTPUTS: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
    /// The matrix and forcing a right-hand side solves, reused from call to call.
    static SOLVE: std::cell::RefCell<(Vec<f64>, Vec<f64>, Vec<usize>)> = const { std::cell::RefCell::new((Vec::new(), Vec::new(), Vec::new())) };
    /// The inputs and outputs of an `L D L^T` solve's kernel, reused from call to call.
    static LDL: std::cell::RefCell<(Vec<f64>, Vec<f64>)> = const { std::cell::RefCell::new((Vec::new(), Vec::new())) };
    /// A Jacobian's column of solved rates, reused from call to call.
    static COLUMN: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// One block of a Jacobian tape's outputs (the values, or one variable's derivatives) as the
/// parts `seam::rates` reads: kept rates, matrix, forcing, `W`, `c`, power, its weights.
fn block_parts<'o>(s: &FormShape, b: &'o [f64]) -> Block<'o> {
    let (nq, n) = (s.kept.len(), s.matrix_size);
    let (rw, cw) = s.post.unwrap_or((0, 0));
    let (m_at, f_at) = (nq, nq + n * n);
    let (w_at, c_at) = (f_at + n, f_at + n + rw * cw);
    let p_at = c_at + rw;
    let weights = if s.power_weights { n } else { 0 };
    Block {
        qdot: &b[..nq],
        matrix: &b[m_at..f_at],
        force: &b[f_at..f_at + n],
        w: &b[w_at..c_at],
        c: &b[c_at..p_at],
        power: if s.work { b[p_at] } else { 0.0 },
        power_weights: &b[p_at + usize::from(s.work)..p_at + usize::from(s.work) + weights],
    }
}

/// The length of one block of a Jacobian tape's outputs ([`block_parts`]).
fn block_len(s: &FormShape) -> usize {
    let n = s.matrix_size;
    let (rw, cw) = s.post.unwrap_or((0, 0));
    s.kept.len() + n * n + n + rw * cw + rw + usize::from(s.work) + if s.power_weights { n } else { 0 }
}

/// Runs `tape` on `[t | params | a | b]` and hands its outputs to `then`.
fn run<R>(tape: &dyn Kernel, t: f64, params: &[f64], a: &[f64], b: &[f64], then: impl FnOnce(&[f64]) -> R) -> R {
    INPUTS.with(|inputs| {
        OUTPUTS.with(|outputs| {
            let (mut inputs, mut outputs) = (inputs.borrow_mut(), outputs.borrow_mut());
            pack(&mut inputs, t, params, a, b);
            // A kernel reads exactly its input registers: those the arguments do not fill are 0.
            if inputs.len() < tape.inputs() {
                inputs.resize(tape.inputs(), 0.0);
            }
            // The kernel writes every output: the buffer is only sized, not cleared.
            outputs.resize(tape.outputs(), 0.0);
            tape.run(&inputs, &mut outputs[..tape.outputs()]);
            then(&outputs[..tape.outputs()])
        })
    })
}

impl Evaluated {
    /// The program as a [`seam::Model`], its tapes interpreted.
    pub fn model(program: Program) -> Model {
        Evaluated::model_with(program, &Interpreter)
    }

    /// The program as a [`seam::Model`], its tapes made kernels by `backend` (a JIT).
    pub fn model_with(mut program: Program, backend: &dyn Backend) -> Model {
        let d = program.description;
        let m = d.coordinates.len();
        let params = d.parameter_names.len();
        // A right-hand side whose module unrolls its solve runs it in the same call: the plan's
        // tape reads the matrix and the forcing from the rhs tape's outputs, `[q'; matrix;
        // forcing; ...]`. Where the state is stabilized (Baumgarte), the plan keeps a tape of its
        // own too, named `FORMULATION::ldl`.
        let mut solves_alone = Vec::new();
        for shape in &program.forms {
            let name = shape.kind.name();
            if let (Some(plan), Some(tape)) = (shape.solve.sparse(), program.tapes.get(&format!("{name}::rhs"))) {
                let (nq, n) = (shape.kept.len(), shape.matrix_size);
                let joined = tape.followed_by(&plan.tape(), &(nq..nq + n * n + n).collect::<Vec<_>>());
                program.tapes.insert(format!("{name}::rhs"), joined);
                if shape.stabilization.is_some() {
                    solves_alone.push((format!("{name}::ldl"), plan.tape()));
                }
            }
        }
        // Every tape compiled at once, side by side on the machine's threads.
        let mut named: Vec<(String, Tape)> = program.tapes.drain().collect();
        named.extend(solves_alone);
        named.sort_by(|a, b| a.0.cmp(&b.0));
        let (names, tapes): (Vec<String>, Vec<Tape>) = named.into_iter().unzip();
        let threads = std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get);
        let mut kernels: std::collections::HashMap<String, Box<dyn Kernel>> = names.into_iter().zip(super::kernel::kernels(tapes, backend, threads)).collect();
        let take = |name: &str, kernels: &mut std::collections::HashMap<String, Box<dyn Kernel>>| kernels.remove(name);
        let tapes = &mut kernels;
        let holonomic = d.holonomic_names.len();
        let momenta: Option<Arc<dyn Kernel>> = take("momenta", tapes).map(Arc::from);
        let constraint_names: Arc<[String]> = d.constraints.clone().into();
        let holonomic_names: Arc<[String]> = d.holonomic_names.clone().into();
        let baked_params = if d.default_params.is_empty() { 0 } else { params };
        let formulations = program
            .forms
            .into_iter()
            .filter_map(|shape| {
                let name = shape.kind.name();
                let f = EvaluatedForm {
                    m,
                    params: baked_params,
                    ignorable: d.ignorable.len(),
                    constraint_names: constraint_names.clone(),
                    holonomic_names: holonomic_names.clone(),
                    rhs: take(&format!("{name}::rhs"), tapes)?,
                    initial_state: take(&format!("{name}::initial_state"), tapes)?,
                    momenta: if shape.momenta_by_function { Some(momenta.clone()?) } else { None },
                    velocities: take(&format!("{name}::velocities"), tapes)?,
                    singular_margin: take(&format!("{name}::singular_margin"), tapes)?,
                    matrix: take(&format!("{name}::matrix"), tapes),
                    ldl: take(&format!("{name}::ldl"), tapes),
                    jacobian: take(&format!("{name}::jacobian"), tapes),
                    parameter_jacobian: take(&format!("{name}::parameter_jacobian"), tapes),
                    shape: shape.clone(),
                };
                let (has_jacobian, has_parameter_jacobian) = (f.jacobian.is_some(), f.parameter_jacobian.is_some());
                Some(Formulation {
                    kind: shape.kind,
                    layout: StateLayout { coordinates: shape.kept.clone(), speeds: shape.speeds, speeds_are: shape.kind.speeds(), work: shape.work },
                    equations: shape.equations,
                    state_names: shape.state_names.clone(),
                    matrix_size: shape.matrix_size,
                    has_baumgarte: shape.stabilization.is_some(),
                    has_jacobian,
                    has_parameter_jacobian,
                    depends_on_time: shape.depends_on_time,
                    functions: Arc::new(f),
                })
            })
            .collect();
        let functions = Evaluated {
            event_values: take("event_values", tapes),
            event_resets: take("event_resets", tapes),
            energy: take("energy", tapes),
            work_rate: take("work_rate", tapes),
            momenta,
            constraint_residuals: take("constraint_residuals", tapes),
            position_residuals: take("position_residuals", tapes),
            m,
            params: baked_params,
        };
        Model {
            module: d.module,
            name: d.name,
            coordinates: d.coordinates,
            constraints: d.constraints,
            ignorable: d.ignorable,
            holonomic,
            parameter_names: if baked_params == 0 { vec![] } else { d.parameter_names },
            inputs: d.inputs,
            default_params: d.default_params,
            initial: d.initial,
            run: d.run,
            paper_settings: d.paper_settings,
            energy_balance: d.energy_balance,
            events: d.events,
            gimbals: d.gimbals,
            formulations,
            functions: Arc::new(functions),
        }
    }

    fn point(
        &self,
        tape: Option<&dyn Kernel>,
        function: &'static str,
        t: f64,
        q: &[f64],
        qdot: &[f64],
        params: &[f64],
        out: &mut [f64],
        rates: bool,
    ) -> Result<(), Failure> {
        let tape = tape.ok_or(Failure::Missing { function })?;
        check("q", q, self.m)?;
        if rates {
            check("qdot", qdot, self.m)?;
        }
        check("params", params, self.params)?;
        check("out", out, tape.outputs())?;
        let qdot = if rates { qdot } else { &[] };
        run(tape, t, params, q, qdot, |o| out.copy_from_slice(o));
        Ok(())
    }
}

impl ModelFunctions for Evaluated {
    fn energy(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.point(self.energy.as_deref(), "energy", t, q, qdot, params, out, true)
    }
    fn work_rate(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.point(self.work_rate.as_deref(), "work_rate", t, q, qdot, params, out, true)
    }
    fn momenta(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.point(self.momenta.as_deref(), "momenta", t, q, qdot, params, out, true)
    }
    fn constraint_residuals(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.point(self.constraint_residuals.as_deref(), "constraint_residuals", t, q, qdot, params, out, true)
    }
    fn position_residuals(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.point(self.position_residuals.as_deref(), "position_residuals", t, q, qdot, params, out, false)
    }
    fn event_values(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.point(self.event_values.as_deref(), "event_values", t, q, qdot, params, out, true)
    }
    fn event_resets(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.point(self.event_resets.as_deref(), "event_resets", t, q, qdot, params, out, true)
    }
}

/// `plan`'s solve by its kernel ([`LdlPlan::tape`]): `force` overwritten by the solution, the
/// numbers of [`LdlPlan::solve`] (the same operations), `Err(column)` where it refuses.
fn solve_ldl(plan: &LdlPlan, kernel: &dyn Kernel, matrix: &[f64], force: &mut [f64]) -> Result<(), usize> {
    LDL.with(|cell| {
        let (inputs, outputs) = &mut *cell.borrow_mut();
        inputs.clear();
        inputs.extend_from_slice(matrix);
        inputs.extend_from_slice(force);
        // The kernel writes every output: the buffer is only sized, not cleared.
        outputs.resize(kernel.outputs(), 0.0);
        kernel.run(inputs, &mut outputs[..kernel.outputs()]);
        let (x, pivots) = outputs[..kernel.outputs()].split_at(force.len());
        plan.checked(matrix, pivots)?;
        force.copy_from_slice(x);
        Ok(())
    })
}

/// `seam::solve::solve_spd` with its scratch in `scratch`: `L D` and the reciprocals of `D`.
/// (Looped over the rows as slices, it is faster than the plan's straight-line code compiled by
/// the JIT on the 20-link pendulum's in-process Lagrange call, a 21 x 21 matrix, in `cargo bench
/// -p generator --bench scaling`: the figures are in docs/benchmarks.md.)
fn solve_spd(n: usize, a: &mut [f64], b: &mut [f64], scratch: &mut Vec<f64>) -> Result<(), usize> {
    scratch.clear();
    scratch.resize(n * n + n, 0.0);
    let (u, inv) = scratch.split_at_mut(n * n);
    seam::solve::solve_spd(&mut Rows::new(n, a), b, &mut Rows::new(n, u), inv)
}

/// `seam::solve::solve_dense`, its pivots in `pivots`.
pub(crate) fn solve_dense(n: usize, a: &mut [f64], b: &mut [f64], pivots: &mut Vec<usize>) -> Result<(), usize> {
    pivots.resize(n, 0);
    seam::solve::solve_dense(&mut Rows::new(n, a), b, pivots)
}

impl EvaluatedForm {
    /// `rhs` ends with the `L D L^T` solve of its matrix ([`LdlPlan::tape`], joined by
    /// [`Tape::followed_by`] in [`Evaluated::model_with`]: one call) where the module unrolls it
    /// ([`Solve::sparse`]): its last outputs are the solution and the pivots. A dense large
    /// solve is [`solve_spd`].
    fn solves_in_rhs(&self) -> bool {
        self.shape.solve.sparse().is_some()
    }

    fn states(&self) -> usize {
        self.shape.kept.len() + self.shape.speeds + usize::from(self.shape.work)
    }

    fn check_state(&self, state: &[f64], params: &[f64], g_i: &[f64]) -> Result<(), Failure> {
        check("state", state, self.states())?;
        check("params", params, self.params)?;
        check("g_i", g_i, self.ignorable)
    }

    /// `rhs` (and `rhs_baumgarte` with `stabilize`): `finish(assemble(..))` of the module.
    fn rates(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64], stabilize: Option<(f64, f64)>) -> Result<(), Failure> {
        self.check_state(state, params, g_i)?;
        check("dstate", dstate, self.states())?;
        let s = &self.shape;
        let (nq, n) = (s.kept.len(), s.matrix_size);
        run(&*self.rhs, t, params, g_i, state, |o| {
            // The solution and the pivots of the solve the rhs tape ends with.
            let (o, solved_in_rhs) = o.split_at(o.len() - if self.solves_in_rhs() { 2 * n } else { 0 });
            let mut at = 0;
            let mut take = |k: usize| {
                let out = &o[at..at + k];
                at += k;
                out
            };
            let qdot = take(nq);
            let (matrix_out, force_out) = (take(if s.solve.reads_matrix() { n * n } else { 0 }), take(n));
            let post = s.post.map(|(rw, cw)| (take(rw * cw), take(rw)));
            let power = if s.work { Some(take(1)[0]) } else { None };
            let power_weights = if s.power_weights { take(n) } else { &[] };
            let checks = take(s.conditions.len());
            SOLVE.with(|cell| {
                let (matrix, force, pivots) = &mut *cell.borrow_mut();
                // The solves that overwrite the matrix get a copy of it.
                let copy = || {
                    matrix.clear();
                    matrix.extend_from_slice(matrix_out);
                    matrix
                };
                force.clear();
                force.extend_from_slice(force_out);
                let stabilized = s.stabilization.is_some() && stabilize.is_some();
                if let (Some(r), Some((alpha, beta))) = (s.stabilization, stabilize) {
                    let (residuals, positions) = (take(r), take(r));
                    seam::solve::baumgarte(&mut force[self.m..self.m + r], residuals, positions, alpha, beta);
                }
                seam::check::nonsingular(t, &s.conditions, checks, SINGULAR_TOLERANCE)?;
                // The module's own solve: `solve_spd` or its `solve_ldl`, both a plan's twin.
                let solved = match &s.solve {
                    // As the module: its unrolled `solve_ldl` (`Solve::sparse`), else the looped
                    // `solve_spd`.
                    Solve::Ldl(plan) if self.solves_in_rhs() && !stabilized => {
                        let (x, pivots) = solved_in_rhs.split_at(n);
                        plan.checked(matrix_out, pivots).map(|()| force.copy_from_slice(x))
                    }
                    Solve::Ldl(plan) => match &self.ldl {
                        Some(kernel) => solve_ldl(plan, &**kernel, matrix_out, force),
                        None => COLUMN.with(|scratch| solve_spd(n, copy(), force, &mut scratch.borrow_mut())),
                    },
                    Solve::Lu(_) => solve_dense(n, copy(), force, pivots),
                    // The body's forcing slots hold the rates already.
                    Solve::Articulated { .. } => Ok(()),
                };
                solved.map_err(|column| seam::solve::singular(t, s.matrix_name.clone(), column))?;
                let (w, c) = post.unwrap_or_default();
                let block = Block { qdot, w, c, power: power.unwrap_or(0.0), power_weights, ..Block::EMPTY };
                seam::rates::write(t, s.layout(), &block, force, dstate)
            })
        })
    }
}

impl EvaluatedForm {
    /// `jacobian` or `parameter_jacobian` of the module (`jacobian.rs` emits them): the
    /// assembly and its derivatives by `columns` variables from the tape, then the solve and
    /// `dx/ds_k = A^-1 (dF/ds_k - dA/ds_k x)` with the LU factors computed once.
    #[allow(clippy::too_many_arguments)]
    fn derivatives(
        &self,
        tape: &dyn Kernel,
        variables: usize,
        columns: usize,
        t: f64,
        state: &[f64],
        params: &[f64],
        g_i: &[f64],
        dstate: &mut [f64],
        jac: &mut [f64],
    ) -> Result<(), Failure> {
        self.check_state(state, params, g_i)?;
        check("dstate", dstate, self.states())?;
        check("jac", jac, self.states() * columns)?;
        let s = &self.shape;
        let n = s.matrix_size;
        // One block (`block_parts`): kept rates, matrix, forcing, W, c, power, its weights.
        let block = block_len(s);
        run(tape, t, params, g_i, state, |o| {
            let at = |b: usize| &o[b..b + block];
            let value = at(0);
            let conditions = s.formulation_conditions();
            let checks = &o[block..block + conditions.len()];
            let derivative = |k: usize| at(block + conditions.len() + k * block);
            seam::check::nonsingular(t, conditions, checks, SINGULAR_TOLERANCE)?;
            SOLVE.with(|solve| {
                COLUMN.with(|column| {
                    let (matrix, x, pivots) = &mut *solve.borrow_mut();
                    let dx = &mut *column.borrow_mut();
                    let values = block_parts(s, value);
                    matrix.clear();
                    matrix.extend_from_slice(values.matrix);
                    x.clear();
                    x.extend_from_slice(values.force);
                    pivots.resize(n, 0);
                    dx.resize(n, 0.0);
                    seam::solve::lu_factor(&mut Rows::new(n, matrix), pivots).map_err(|column| seam::solve::singular(t, s.matrix_name.clone(), column))?;
                    seam::solve::lu_solve(&Rows::new(n, matrix), pivots, x);
                    seam::rates::write_jacobian(
                        t,
                        s.layout(),
                        &values,
                        x,
                        (&Rows::new(n, matrix), pivots),
                        (variables, |k| block_parts(s, derivative(k))),
                        dx,
                        dstate,
                        (jac, columns),
                    )
                })
            })
        })
    }
}

impl FormulationFunctions for EvaluatedForm {
    fn jacobian(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64], jac: &mut [f64]) -> Result<(), Failure> {
        let tape = self.jacobian.as_ref().ok_or(Failure::Missing { function: "jacobian" })?;
        let variables = self.shape.kept.len() + self.shape.speeds;
        self.derivatives(&**tape, variables, self.states(), t, state, params, g_i, dstate, jac)
    }

    fn parameter_jacobian(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64], jac: &mut [f64]) -> Result<(), Failure> {
        let tape = self.parameter_jacobian.as_ref().ok_or(Failure::Missing { function: "parameter_jacobian" })?;
        self.derivatives(&**tape, self.params, self.params, t, state, params, g_i, dstate, jac)
    }

    fn rhs(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64]) -> Result<(), Failure> {
        self.rates(t, state, params, g_i, dstate, None)
    }

    fn rhs_baumgarte(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], dstate: &mut [f64], alpha: f64, beta: f64) -> Result<(), Failure> {
        if self.shape.stabilization.is_none() {
            return Err(Failure::Missing { function: "rhs_baumgarte" });
        }
        self.rates(t, state, params, g_i, dstate, Some((alpha, beta)))
    }

    fn initial_state(&self, t: f64, q: &[f64], qdot: &[f64], params: &[f64], state: &mut [f64], g_i: &mut [f64]) -> Result<(), Failure> {
        check("q", q, self.m)?;
        check("qdot", qdot, self.m)?;
        check("params", params, self.params)?;
        check("state", state, self.states())?;
        check("g_i", g_i, self.ignorable)?;
        let s = &self.shape;
        let (nr, nh) = (self.constraint_names.len(), self.holonomic_names.len());
        if let Some(momenta) = &self.momenta {
            run(&**momenta, t, params, q, qdot, |o| g_i.copy_from_slice(o));
        }
        let own = if self.momenta.is_some() { 0 } else { self.ignorable };
        run(&*self.initial_state, t, params, q, qdot, |o| {
            let (u, rest) = o.split_at(s.speeds);
            let (g, rest) = rest.split_at(own);
            let (r, rest) = rest.split_at(nr);
            let (rb, rest) = rest.split_at(nr);
            let (h, hb) = rest.split_at(nh);
            let residuals = self.constraint_names.iter().zip(r.iter().zip(rb));
            let positions = self.holonomic_names.iter().zip(h.iter().zip(hb));
            let entries = residuals.chain(positions).map(|(constraint, (&residual, &bound))| (constraint.clone(), residual, bound));
            seam::check::satisfied(entries, CONSTRAINT_TOLERANCE)?;
            for (k, &j) in s.kept.iter().enumerate() {
                state[k] = q[j];
            }
            state[s.kept.len()..s.kept.len() + s.speeds].copy_from_slice(u);
            if s.work {
                state[s.kept.len() + s.speeds] = 0.0;
            }
            if own > 0 {
                g_i.copy_from_slice(g);
            }
            seam::check::finite(t, state)?;
            seam::check::finite_after(t, state.len(), g_i)
        })
    }

    fn velocities(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], q: &mut [f64], qdot: &mut [f64]) -> Result<(), Failure> {
        self.check_state(state, params, g_i)?;
        check("q", q, self.m)?;
        check("qdot", qdot, self.m)?;
        let s = &self.shape;
        run(&*self.velocities, t, params, g_i, state, |o| {
            let (qd, checks) = o.split_at(self.m);
            seam::check::nonsingular(t, &s.conditions, checks, SINGULAR_TOLERANCE)?;
            q.fill(0.0);
            for (k, &j) in s.kept.iter().enumerate() {
                q[j] = state[k];
            }
            qdot.copy_from_slice(qd);
            seam::check::finite(t, qdot)
        })
    }

    fn matrix(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64], out: &mut [f64]) -> Result<(), Failure> {
        self.check_state(state, params, g_i)?;
        let (nq, n) = (self.shape.kept.len(), self.shape.matrix_size);
        check("out", out, n * n)?;
        match &self.matrix {
            Some(own) => run(&**own, t, params, g_i, state, |o| out.copy_from_slice(&o[..n * n])),
            None => run(&*self.rhs, t, params, g_i, state, |o| out.copy_from_slice(&o[nq..nq + n * n])),
        }
        Ok(())
    }

    fn singular_margin(&self, t: f64, state: &[f64], params: &[f64], g_i: &[f64]) -> Result<f64, Failure> {
        self.check_state(state, params, g_i)?;
        Ok(run(&*self.singular_margin, t, params, g_i, state, |o| o.iter().fold(f64::INFINITY, |m, v| m.min(v.abs()))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emit::LdlPlan;
    use crate::symbolic::zero::SplitMix;

    /// A random symmetric positive definite matrix `B B^T + n I`, row-major.
    fn spd(n: usize, rng: &mut SplitMix) -> Vec<f64> {
        let b: Vec<f64> = (0..n * n).map(|_| rng.uniform(-1.0, 1.0)).collect();
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] = (0..n).map(|k| b[i * n + k] * b[j * n + k]).sum::<f64>() + if i == j { n as f64 } else { 0.0 };
            }
        }
        a
    }

    /// `LDL^T` solves what partial-pivoting LU solves, to round-off, at every size up to 12.
    #[test]
    fn ldlt_solves_symmetric_positive_definite_systems() {
        let mut rng = SplitMix(3);
        let mut scratch = Vec::new();
        for n in 1..=12 {
            let a = spd(n, &mut rng);
            let b: Vec<f64> = (0..n).map(|_| rng.uniform(-1.0, 1.0)).collect();
            let (a1, mut x1) = (a.clone(), b.clone());
            LdlPlan::dense(n).solve(&a1, &mut x1, &mut scratch).unwrap();
            let (mut a2, mut x2, mut pivots) = (a.clone(), b.clone(), Vec::new());
            solve_dense(n, &mut a2, &mut x2, &mut pivots).unwrap();
            for i in 0..n {
                let residual: f64 = (0..n).map(|k| a[i * n + k] * x1[k]).sum::<f64>() - b[i];
                assert!(residual.abs() < 1e-13 * n as f64, "n = {n}: residual {residual:e}");
                assert!((x1[i] - x2[i]).abs() < 1e-13, "n = {n}: {} against LU's {}", x1[i], x2[i]);
            }
        }
    }

    /// The looped `solve_spd` is the dense plan's solve to the bit, and refuses where it
    /// refuses: singular, indefinite, a negative first pivot. (Against the compiled module's
    /// `solve_spd`: `generator/tests/it/evaluated_chains.rs`, the 20-link pendulum.)
    #[test]
    fn the_looped_solve_is_the_dense_plan_s() {
        let mut rng = SplitMix(11);
        for n in [1, 2, 5, 17, 21, 30] {
            let a = spd(n, &mut rng);
            let b: Vec<f64> = (0..n).map(|_| rng.uniform(-1.0, 1.0)).collect();
            let mut planned = b.clone();
            LdlPlan::dense(n).solve(&a, &mut planned, &mut Vec::new()).unwrap();
            let (mut looped, mut factors) = (b.clone(), a.clone());
            solve_spd(n, &mut factors, &mut looped, &mut Vec::new()).unwrap();
            assert_eq!(looped.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), planned.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), "n = {n}");
        }
        for (n, a) in [(2, vec![1.0, 2.0, 2.0, 4.0]), (2, vec![1.0, 2.0, 2.0, 1.0]), (1, vec![-1.0])] {
            let refused = LdlPlan::dense(n).solve(&a, &mut vec![1.0; n], &mut Vec::new());
            assert!(refused.is_err());
            assert_eq!(solve_spd(n, &mut a.clone(), &mut vec![1.0; n], &mut Vec::new()), refused);
        }
    }

    /// A singular matrix, and a symmetric one that is not positive definite, are refused at the
    /// pivot where it shows, never solved into NaN.
    #[test]
    fn ldlt_refuses_singular_and_indefinite_matrices() {
        let mut scratch = Vec::new();
        // Rank one: the second pivot is zero.
        let singular = [1.0, 2.0, 2.0, 4.0];
        assert_eq!(LdlPlan::dense(2).solve(&singular, &mut [1.0, 1.0], &mut scratch), Err(1));
        // Eigenvalues 3 and -1: the second pivot is 1 - 4 = -3.
        let indefinite = [1.0, 2.0, 2.0, 1.0];
        assert_eq!(LdlPlan::dense(2).solve(&indefinite, &mut [1.0, 1.0], &mut scratch), Err(1));
        // A negative first pivot.
        assert_eq!(LdlPlan::dense(1).solve(&[-1.0], &mut [1.0], &mut scratch), Err(0));
    }
}
