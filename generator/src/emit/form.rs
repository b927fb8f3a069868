//! One formulation's submodule, from its [`Equations`]: a private `assemble` that evaluates
//! everything the right-hand side needs (the rates of the kept coordinates, the matrix and
//! forcing to solve, the singular factors), and the public functions built on it: `rhs`
//! (assemble, check, solve, write), `rhs_baumgarte` for Lagrange (assemble, stabilize, solve),
//! `matrix` (for conditioning monitors), plus `initial_state`, `velocities` and
//! `singular_margin`. Each big expression is emitted once per formulation.

use super::from_mechanics::FromMechanics;
use super::function::{Input, arg_list, state_args};
use super::jacobian::Wrt;
use super::ldl::Solve;
use super::module::Emitter;
use super::ops::OpCount;
use super::syntax::{doc, usize_lit};
use super::{Function, FunctionCost};
use crate::formulation::Equations;
use crate::model::{Model, ModelError};
use crate::symbolic::expr::any_contains;
use crate::symbolic::{Expr, Symbol};
use proc_macro2::{Literal, TokenStream};
use quote::quote;
use std::collections::{BTreeSet, HashMap};

/// A right-hand side's chosen assembly: its body, what it reads (to decide whether it reads
/// `t`) and the summary's description of the choice.
pub(super) struct Assembled {
    pub body: super::function::Body,
    pub reads: Vec<Expr>,
    pub description: String,
    /// How the right-hand side solves: its matrix's plan, or no solve.
    pub solve: Solve,
}

/// A right-hand side's items and what the module's summary says of them.
struct RhsItems {
    items: TokenStream,
    /// Whether it reads `t`.
    depends_on_time: bool,
    solve: Solve,
    /// How it assembles.
    assembly: String,
    /// What each of its checks' vanishing means.
    conditions: Vec<String>,
}

/// The body that assembles a matrix and forcing to solve, and what it reads.
struct ByMatrix {
    body: super::function::Body,
    reads: Vec<Expr>,
    description: String,
}

/// Largest singular factor (tree nodes) named by its formula in `Failure::Singular`.
const MAX_CONDITION_TREE: u32 = 200;

fn ident(name: &str) -> proc_macro2::Ident {
    super::function::ident(name)
}

impl Emitter<'_> {
    /// The identifier of a state or input symbol.
    fn symbol_ident(&self, s: Symbol) -> String {
        self.scope.names.of.get(&s).cloned().unwrap_or_else(|| s.name())
    }

    /// Inputs of the functions of a state: `t`, kept coordinates and speeds from `state`
    /// (argument 1), parameters (argument 2), `G_I` (argument 3).
    pub(super) fn state_inputs(&self, f: &Equations) -> Vec<Input> {
        let model = self.scope.model;
        let mut inputs = vec![self.time_input()];
        for (pos, &j) in f.kept.iter().enumerate() {
            let l = usize_lit(pos);
            inputs.push(Input::new(model.coordinates[j], &self.scope.names.coordinates[j], 1, quote!(state[#l])));
        }
        for (k, s) in f.speeds.iter().enumerate() {
            let l = usize_lit(f.kept.len() + k);
            inputs.push(Input::new(*s, &self.symbol_ident(*s), 1, quote!(state[#l])));
        }
        inputs.extend(self.parameter_inputs(2));
        for (k, g) in f.momenta.iter().enumerate() {
            let l = usize_lit(k);
            inputs.push(Input::new(*g, &self.symbol_ident(*g), 3, quote!(g_i[#l])));
        }
        inputs
    }

    /// The factors of the elimination's pivots that vary with the state: checked at runtime.
    pub(super) fn runtime_factors(&mut self, f: &Equations) -> Vec<Expr> {
        let model = self.scope.model;
        let varying: BTreeSet<Symbol> = model.coordinates.iter().chain(&f.speeds).chain(&f.momenta).chain([&model.t]).copied().collect();
        let mut out: Vec<Expr> = Vec::new();
        for s in &f.singular {
            let p = self.workshop.prep.prepare(*s);
            if p.free_symbols().iter().any(|x| varying.contains(x)) && !out.contains(s) {
                out.push(*s);
            }
        }
        out
    }

    /// The formulation `f` starts: the bodies kept for it, its speeds named as the rates they are
    /// (where they are).
    pub(super) fn start(&mut self, f: &Equations) {
        let relabel = self.speeds_as_rates(f);
        self.workshop.bodies.start(f.kind, relabel);
    }

    /// `f`'s speeds named as the coordinates' rates, where they are those rates in another
    /// order ([`super::reuse::speeds_as_rates`]).
    pub(super) fn speeds_as_rates(&self, f: &Equations) -> std::collections::HashMap<Symbol, Expr> {
        let rates: Vec<Symbol> = f.kept.iter().map(|&j| self.scope.model.velocities[j]).collect();
        let qdot: Vec<Expr> = f.kept.iter().map(|&j| f.qdot[j]).collect();
        super::reuse::speeds_as_rates(&f.speeds, &qdot, &rates)
    }

    /// A formulation's submodule (see the module docs).
    pub(super) fn form(&mut self, f: &Equations, shared: &FromMechanics) -> Result<TokenStream, ModelError> {
        self.start(f);
        let model = self.scope.model;
        let m = model.m();
        let name = f.name();
        let work = self.scope.work;
        let n_states = f.states(work);
        let mut state_names: Vec<String> = f.kept.iter().map(|&j| model.coordinates[j].name()).collect();
        state_names.extend(speed_names(model, f));
        if work {
            state_names.push("W".into());
        }
        let checks = self.runtime_factors(f);
        let RhsItems { items: assemble, depends_on_time, solve, assembly, conditions } = self.assemble(f, shared, &checks)?;
        let init = self.initial_state(f, shared)?;
        let vel = self.velocities_fn(f, &checks)?;
        let margin = self.singular_margin(f, &checks)?;
        let jacobian = if self.scope.options.jacobian { self.jacobian_fn(f, shared, &checks, Wrt::State)? } else { TokenStream::new() };
        let parameter_jacobian = if self.emits_parameter_jacobian() { self.jacobian_fn(f, shared, &checks, Wrt::Parameters)? } else { TokenStream::new() };
        let module = ident(name);
        let states_l = usize_lit(n_states);
        let eqs = usize_lit(f.equations);
        let integrates = f.kept.len() == m;
        let mod_doc = doc(&format!("{}: {n_states} states, {} equations.", f.label, f.equations));
        self.record.forms.push((name.to_string(), n_states, f.equations, super::assembly::summary_line(&solve, &assembly)));
        let seam_const =
            super::seam::formulation_const(&self.scope.seam, f.kind, f.stabilization.is_some(), self.scope.options.jacobian, self.emits_parameter_jacobian());
        let kept: Vec<Literal> = f.kept.iter().map(|&j| usize_lit(j)).collect();
        let (n_kept, n_speeds) = (usize_lit(f.kept.len()), usize_lit(f.speeds.len()));
        if self.record.tapes.is_some() {
            self.record.shapes.push(super::program::FormShape {
                kind: f.kind,
                kept: f.kept.clone(),
                speeds: f.speeds.len(),
                work,
                equations: f.equations,
                state_names: state_names.clone(),
                matrix_size: f.mass.rows,
                post: f.post.as_ref().map(|(w, _)| (w.rows, w.cols)),
                conditions,
                matrix_name: f.matrix_name.to_string(),
                stabilization: f.stabilization.as_ref().map(|s| s.len()),
                power_weights: f.constraint_power.is_some(),
                depends_on_time,
                solve,
                momenta_by_function: self.momenta_by_function(),
            });
        }
        Ok(quote! {
            #mod_doc
            pub mod #module {
                use super::*;
                #[doc = "Length of the state: kept coordinates, speeds, and the work integral when forces do work."]
                pub const STATES: usize = #states_l;
                #[doc = "Number of dynamical equations, counted as the paper's Table 1 does."]
                pub const EQUATIONS: usize = #eqs;
                #[doc = "Names of the state entries."]
                pub const STATE_NAMES: [&str; STATES] = [#(#state_names),*];
                #[doc = "False when the ignorable coordinates are left out of the state."]
                pub const INTEGRATES_IGNORABLE: bool = #integrates;
                #[doc = "True when the last state entry is the work integral `W` of Eq. 80."]
                pub const HAS_WORK_STATE: bool = #work;
                #[doc = "The coordinates the state holds, as indices into `COORDINATES`."]
                pub const STATE_COORDINATES: [usize; #n_kept] = [#(#kept),*];
                #[doc = "How many speeds follow them in the state."]
                pub const SPEEDS: usize = #n_speeds;
                #[doc = "True when the right-hand side reads `t`."]
                pub const DEPENDS_ON_TIME: bool = #depends_on_time;
                #assemble
                #init
                #vel
                #margin
                #jacobian
                #parameter_jacobian
                #seam_const
            }
        })
    }

    /// What the state's rates are computed from, in order: the kept coordinates' rates, the
    /// matrix (both triangles read the upper entry, so CSE binds it once), the forcing, Maggi's
    /// `W` and `c`, and the power `Q . q'` when forces do work (with the moving constraints'
    /// power's offset, then its weights on the solution, `formulation::power`).
    pub(super) fn rate_outputs(&self, f: &Equations, shared: &FromMechanics) -> Vec<Expr> {
        self.rate_outputs_of(f, shared, (&f.qdot, &f.mass, &f.forcing))
    }

    /// [`Emitter::rate_outputs`] with the rates, matrix and forcing given (the dense form's or
    /// the recursion's).
    fn rate_outputs_of(&self, f: &Equations, shared: &FromMechanics, (qdot, mass, forcing): (&[Expr], &crate::symbolic::Matrix, &[Expr])) -> Vec<Expr> {
        let n = mass.rows;
        let mut outputs: Vec<Expr> = f.kept.iter().map(|&j| qdot[j]).collect();
        for i in 0..n {
            for j in 0..n {
                outputs.push(mass.get(i.min(j), i.max(j)));
            }
        }
        outputs.extend(forcing.iter().copied());
        if let Some((w, c)) = &f.post {
            outputs.extend(w.data.iter().copied());
            outputs.extend(c.iter().copied());
        }
        if self.scope.work {
            let offset = f.constraint_power.as_ref().map_or(Expr::zero(), |(_, offset)| *offset);
            outputs.push(self.power_output(shared, qdot) + offset);
            if let Some((weights, _)) = &f.constraint_power {
                outputs.extend(weights.iter().copied());
            }
        }
        outputs
    }

    /// The power `Q . q'` of the applied forces with the rates `qdot`.
    fn power_output(&self, shared: &FromMechanics, qdot: &[Expr]) -> Expr {
        let to_qdot: HashMap<Symbol, Expr> = self.scope.model.velocities.iter().copied().zip(qdot.iter().copied()).collect();
        shared.power.subs(&to_qdot)
    }

    /// The outputs of a right-hand side's body from its rates, matrix and forcing: then the
    /// singular factors, then the constraint residuals for Baumgarte.
    fn rhs_outputs(f: &Equations, rates: Vec<Expr>, checks: &[Expr]) -> Vec<Expr> {
        let mut outputs = rates;
        outputs.extend(checks.iter().copied());
        if let Some(stab) = &f.stabilization {
            outputs.extend(stab.iter().map(|(r, _)| *r));
            outputs.extend(stab.iter().map(|(_, p)| *p));
        }
        outputs
    }

    /// The right-hand side's body: the dense form's entries, or the recursion over the tree of
    /// frames where its body takes fewer operations ([`super::assembly::prefers_recursion`]:
    /// both bodies are built, and the counts compared are the emitted code's); then, where the
    /// articulated-body recursion gives the rates with fewer operations than that body and its
    /// solve ([`super::assembly::prefers_articulated`]), that one, with no matrix. Where the
    /// articulated body already takes fewer operations than the solve alone
    /// ([`super::assembly::beats_solve_alone`]), the matrix's bodies are not built: they could
    /// only add to the solve.
    pub(super) fn assembly(&mut self, f: &Equations, shared: &FromMechanics, checks: &[Expr]) -> Result<Assembled, ModelError> {
        let plan = Solve::for_equations(f);
        let solve_total = plan.cost().total();
        let Some(a) = f.articulated.as_ref().filter(|_| f.post.is_none() && f.stabilization.is_none() && f.constraint_power.is_none()) else {
            let ByMatrix { body, reads, description } = self.matrix_assembly(f, shared, checks)?;
            return Ok(Assembled { body, reads, description, solve: plan });
        };
        let estimate = super::function::program_ops(&a.definitions, &a.accelerations.iter().chain(&a.pivots).copied().collect::<Vec<_>>());
        let composite = f.recursion.as_ref().map(|r| {
            let outputs: Vec<Expr> = r.mass.data.iter().chain(&r.forcing).copied().collect();
            super::function::program_ops(&r.definitions, &outputs)
        });
        if !super::assembly::worth_building_articulated(estimate, composite, solve_total) {
            let c = composite.expect("built without a composite recursion");
            let ByMatrix { body, reads, description } = self.matrix_assembly(f, shared, checks)?;
            return Ok(Assembled {
                body,
                reads,
                description: format!(
                    "{description} (articulated-body recursion not built: {estimate} operations before sharing against the composite recursion's {c} and the solve's {solve_total})"
                ),
                solve: plan,
            });
        }
        let rhs_name = format!("{}::rhs", f.name());
        let args = state_args();
        let inputs = self.state_inputs(f);
        let mut rates: Vec<Expr> = f.kept.iter().map(|&j| a.qdot[j]).collect();
        rates.extend(a.accelerations.iter().copied());
        if self.scope.work {
            rates.push(self.power_output(shared, &a.qdot));
        }
        let all_checks: Vec<Expr> = checks.iter().chain(&a.pivots).copied().collect();
        let reads = rates.iter().copied().chain(all_checks.iter().copied()).chain(a.definitions.iter().map(|(_, e)| *e)).collect();
        let direct = self.trial_body(&rhs_name, &a.definitions, &Self::rhs_outputs(f, rates, &all_checks), &inputs, &args)?;
        let by_recursion = direct.ops.total();
        let articulated = |direct, reads, matrix: String| Assembled {
            body: direct,
            reads,
            description: format!("assembly: articulated-body recursion, {by_recursion} operations and no solve ({matrix})"),
            solve: Solve::Articulated { pivots: a.pivots.len() },
        };
        if super::assembly::beats_solve_alone(by_recursion, solve_total) {
            return Ok(articulated(direct, reads, format!("the matrix's solve alone: {solve_total}")));
        }
        let ByMatrix { body, reads: matrix_reads, description } = self.matrix_assembly(f, shared, checks)?;
        let assembly_total = body.ops.total();
        Ok(if super::assembly::prefers_articulated(by_recursion, assembly_total + solve_total) {
            articulated(direct, reads, format!("the matrix's: {assembly_total} + solve {solve_total}"))
        } else {
            Assembled {
                body,
                reads: matrix_reads,
                description: format!("{description} (articulated-body recursion: {by_recursion} operations, no solve)"),
                solve: plan,
            }
        })
    }

    /// The body that assembles the matrix and forcing to solve: the dense form's entries or the
    /// recursion over the tree of frames, the one with fewer operations.
    fn matrix_assembly(&mut self, f: &Equations, shared: &FromMechanics, checks: &[Expr]) -> Result<ByMatrix, ModelError> {
        let rhs_name = format!("{}::rhs", f.name());
        let args = state_args();
        let inputs = self.state_inputs(f);
        // What decides whether the right-hand side reads `t`: the rates, matrix, forcing and
        // checks it assembles (not the stabilization's residuals).
        let rates = self.rate_outputs(f, shared);
        let reads: Vec<Expr> = rates.iter().copied().chain(checks.iter().copied()).collect();
        let body = self.trial_body(&rhs_name, &[], &Self::rhs_outputs(f, rates, checks), &inputs, &args)?;
        let Some(r) = &f.recursion else {
            return Ok(ByMatrix { body, reads, description: "assembly: dense entries".to_string() });
        };
        let rates = self.rate_outputs_of(f, shared, (&r.qdot, &r.mass, &r.forcing));
        let tree_reads = rates.iter().copied().chain(checks.iter().copied()).chain(r.definitions.iter().map(|(_, e)| *e)).collect();
        let recursive = self.trial_body(&rhs_name, &r.definitions, &Self::rhs_outputs(f, rates, checks), &inputs, &args)?;
        let (by_tree, by_entries) = (recursive.ops.total(), body.ops.total());
        Ok(if super::assembly::prefers_recursion(by_tree, by_entries) {
            let description = format!("assembly: recursion over the tree of frames, {by_tree} operations (dense entries: {by_entries})");
            ByMatrix { body: recursive, reads: tree_reads, description }
        } else {
            let description = format!("assembly: dense entries, {by_entries} operations (recursion over the tree of frames: {by_tree})");
            ByMatrix { body, reads, description }
        })
    }

    /// The matrix alone, for `matrix` where the right-hand side assembles none: the recursion
    /// over the tree of frames where there is one, else the dense entries.
    fn matrix_body(&mut self, f: &Equations) -> Result<super::module::Placed, ModelError> {
        let name = format!("{}::matrix", f.name());
        let args = state_args();
        let inputs = self.state_inputs(f);
        let n = f.mass.rows;
        let (definitions, mass) = f.recursion.as_ref().map_or((&[][..], &f.mass), |r| (&r.definitions[..], &r.mass));
        let outputs: Vec<Expr> = (0..n).flat_map(|i| (0..n).map(move |j| mass.get(i.min(j), i.max(j)))).collect();
        let b = self.trial_body(&name, definitions, &outputs, &inputs, &args)?;
        self.record_body(&name, b, &args)
    }

    /// `Assembly`, `assemble`, `finish`, `rhs`, `rhs_baumgarte` (Lagrange) and `matrix`,
    /// whether the right-hand side reads `t` (decided on the same outputs), and how it solves.
    fn assemble(&mut self, f: &Equations, shared: &FromMechanics, checks: &[Expr]) -> Result<RhsItems, ModelError> {
        let model = self.scope.model;
        let name = f.name();
        let work = self.scope.work;
        let nq = f.kept.len();
        let n_speeds = f.speeds.len();
        let n = f.mass.rows;
        let args = state_args();
        let rhs_name = format!("{name}::rhs");
        let Assembled { body: b, reads, description: assembly, solve: plan } = self.assembly(f, shared, checks)?;
        let t = model.t;
        let prepared = self.workshop.prep.prepare_all(&reads);
        let depends_on_time = any_contains(&prepared, t);
        let b = self.record_body(&rhs_name, b, &args)?;
        let mut solve = plan.cost();
        if f.constraint_power.is_some() {
            // The moving constraints' power after the solve: `power_weights . x`.
            solve.add += n;
            solve.mul += n;
        }
        self.record.functions.last_mut().expect("just pushed").solve = solve;
        let o = &b.outputs;
        let mut at = 0;
        let mut take = |k: usize| {
            let s = &o[at..at + k];
            at += k;
            s
        };
        let qd_out = take(nq);
        let rows = if plan.reads_matrix() { super::syntax::matrix_rows(take(n * n), n, n) } else { Vec::new() };
        let force_out = take(n);
        let mut conditions = conditions(checks);
        if let Solve::Articulated { pivots } = &plan {
            // The articulated-body recursion's pivots follow the formulation's own checks.
            conditions.extend((1..=*pivots).map(|k| format!("pivot {k} of the articulated-body recursion vanishes ({} singular)", f.matrix_name)));
        }
        let (n_l, nq_l, nc_l) = (usize_lit(n), usize_lit(nq), usize_lit(conditions.len()));
        let mut fields = vec![quote!(qdot: [f64; #nq_l]), quote!(force: [f64; #n_l])];
        let mut values = vec![quote!(qdot: [#(#qd_out),*]), quote!(force: [#(#force_out),*])];
        if plan.reads_matrix() {
            fields.insert(1, quote!(matrix: [[f64; #n_l]; #n_l]));
            values.insert(1, quote!(matrix: [#(#rows),*]));
        }
        // The parts `seam::rates::write` reads besides the kept rates and the solution.
        let mut parts = Vec::new();
        if let Some((w, _)) = &f.post {
            let (rw, cw) = (w.rows, w.cols);
            let w_out = take(rw * cw);
            let c_out = take(rw);
            let (rw_l, cw_l) = (usize_lit(rw), usize_lit(cw));
            let w_rows = super::syntax::matrix_rows(w_out, rw, cw);
            fields.push(quote!(w: [[f64; #cw_l]; #rw_l]));
            fields.push(quote!(c: [f64; #rw_l]));
            values.push(quote!(w: [#(#w_rows),*]));
            values.push(quote!(c: [#(#c_out),*]));
            parts.push(quote!(w: a.w.as_flattened(), c: &a.c,));
        }
        if work {
            let p = &take(1)[0];
            fields.push(quote!(power: f64));
            values.push(quote!(power: #p));
            parts.push(quote!(power: a.power,));
            if f.constraint_power.is_some() {
                // The moving constraints' power: its weights on the solution x (in `force`).
                let weights = take(n);
                fields.push(quote!(power_weights: [f64; #n_l]));
                values.push(quote!(power_weights: [#(#weights),*]));
                parts.push(quote!(power_weights: &a.power_weights,));
            }
        }
        let check_out = take(conditions.len());
        fields.push(quote!(checks: [f64; #nc_l]));
        values.push(quote!(checks: [#(#check_out),*]));
        let stabilized = match &f.stabilization {
            None => TokenStream::new(),
            Some(stab) => {
                let r = stab.len();
                let (res, pos) = (take(r).to_vec(), take(r).to_vec());
                let r_l = usize_lit(r);
                fields.push(quote!(residuals: [f64; #r_l]));
                fields.push(quote!(positions: [f64; #r_l]));
                values.push(quote!(residuals: [#(#res),*]));
                values.push(quote!(positions: [#(#pos),*]));
                let m_l = usize_lit(model.m());
                let seam = &self.scope.seam;
                let extra = OpCount { add: 2 * r, mul: 4 * r + 1, ..OpCount::default() };
                let mut cost = self.record.functions.last().expect("rhs").clone();
                cost.name = format!("{name}::rhs_baumgarte");
                cost.ops.merge(&extra);
                self.record.functions.push(cost);
                quote! {
                    #[doc = "Right-hand side with Baumgarte stabilization: the constraints at acceleration level become `a q'' = gamma - 2 alpha (a q' + b) - beta^2 h` (h: holonomic residuals); `alpha = beta = 0` is `rhs`."]
                    pub fn rhs_baumgarte(t: f64, state: &[f64; STATES], params: &Params, g_i: &[f64; NUM_IGNORABLE], dstate: &mut [f64; STATES], alpha: f64, beta: f64) -> Result<(), Failure> {
                        let mut a = assemble(t, state, params, g_i);
                        #seam::solve::baumgarte(&mut a.force[#m_l..], &a.residuals, &a.positions, alpha, beta);
                        finish(t, a, dstate)
                    }
                }
            }
        };
        let stmts = &b.stmts;
        let helpers = &b.helpers;
        let fn_args = arg_list(&args, &b.used_args);
        let matrix_name = f.matrix_name;
        let rhs_doc = doc(&format!(
            "Right-hand side of {}: `dstate = [q'; {}']`{} for `state = [q; {}]`. Stops with `Failure::Singular` where the equations are singular and `Failure::NonFinite` instead of writing NaN.",
            f.label,
            if f.post.is_some() || name == "lagrange" { "q'" } else { "u" },
            match (work, f.constraint_power.is_some()) {
                (true, true) => " and the power `W' = (Q + R) . q' - dL/dt` last (`R` the moving constraints' forces)",
                (true, false) => " and the power `W' = Q . q'` last",
                _ => "",
            },
            if f.post.is_some() || name == "lagrange" { "q'" } else { "u" },
        ));
        let matrix_doc = doc(&format!("The matrix `rhs` solves numerically ({matrix_name}), for monitoring its conditioning."));
        let seam = self.scope.seam.clone();
        let solve_with = |call: TokenStream, matrix_mut: TokenStream| {
            quote! {
                let (#matrix_mut matrix, mut force) = (a.matrix, a.force);
                #call.map_err(|column| #seam::solve::singular(t, MATRIX_NAME, column))?;
            }
        };
        let (solve_stmts, solve_item) = match (plan.sparse(), &plan) {
            (Some(sparse), _) => {
                (solve_with(quote!(solve_ldl(&matrix, &mut force)), TokenStream::new()), sparse.emit(&mut self.workshop.splices, self.scope.options.fma))
            }
            (None, Solve::Ldl(_)) => (solve_with(quote!(#seam::solve::solve_spd_array(&mut matrix, &mut force)), quote!(mut)), TokenStream::new()),
            (None, Solve::Lu(_)) => (solve_with(quote!(#seam::solve::solve_dense_array(&mut matrix, &mut force)), quote!(mut)), TokenStream::new()),
            (None, Solve::Articulated { .. }) => (quote!(let force = a.force;), TokenStream::new()),
        };
        let layout = {
            let speeds = usize_lit(n_speeds);
            let post = match &f.post {
                Some((w, _)) => {
                    let (rw, cw) = (usize_lit(w.rows), usize_lit(w.cols));
                    quote!(Some((#rw, #cw)))
                }
                None => quote!(None),
            };
            quote!(#seam::rates::Layout { speeds: #speeds, post: #post, work: #work })
        };
        let matrix_fn = if plan.reads_matrix() {
            quote! {
                #matrix_doc
                pub fn matrix(t: f64, state: &[f64; STATES], params: &Params, g_i: &[f64; NUM_IGNORABLE]) -> [[f64; MATRIX_SIZE]; MATRIX_SIZE] {
                    assemble(t, state, params, g_i).matrix
                }
            }
        } else {
            let m = self.matrix_body(f)?;
            let (stmts, helpers) = (&m.stmts, &m.helpers);
            let fn_args = arg_list(&args, &m.used_args);
            let rows = super::syntax::matrix_rows(&m.outputs, n, n);
            quote! {
                #matrix_doc
                #[allow(non_snake_case, clippy::all)]
                pub fn matrix(#(#fn_args),*) -> [[f64; MATRIX_SIZE]; MATRIX_SIZE] {
                    #stmts
                    [#(#rows),*]
                }
                #helpers
            }
        };
        let items = quote! {
            #[doc = "Size of the matrix `rhs` solves numerically."]
            pub const MATRIX_SIZE: usize = #n_l;
            #[doc = "The matrix `rhs` solves, as its singular failures name it."]
            const MATRIX_NAME: &str = #matrix_name;
            #[doc = "How the solution becomes the state's rates."]
            const LAYOUT: #seam::rates::Layout = #layout;
            #[doc = "What each checked singular factor's vanishing means, in the order of `Assembly::checks`."]
            const CONDITIONS: [&str; #nc_l] = [#(#conditions),*];
            #[doc = "Everything the right-hand side evaluates before its solve."]
            struct Assembly {
                #(#fields,)*
            }
            #[doc = "Evaluates the rates of the kept coordinates, the matrix and forcing, and the singular factors."]
            #[allow(non_snake_case, clippy::all)]
            fn assemble(#(#fn_args),*) -> Assembly {
                #stmts
                Assembly { #(#values,)* }
            }
            #helpers
            #solve_item
            #[doc = "Checks the singular factors, solves, and writes the state's rates."]
            #[allow(clippy::all)]
            fn finish(t: f64, a: Assembly, dstate: &mut [f64; STATES]) -> Result<(), Failure> {
                #seam::check::nonsingular(t, &CONDITIONS, &a.checks, SINGULAR_TOLERANCE)?;
                #solve_stmts
                let block = #seam::rates::Block { qdot: &a.qdot, #(#parts)* ..#seam::rates::Block::EMPTY };
                #seam::rates::write(t, LAYOUT, &block, &force, dstate)
            }
            #rhs_doc
            pub fn rhs(t: f64, state: &[f64; STATES], params: &Params, g_i: &[f64; NUM_IGNORABLE], dstate: &mut [f64; STATES]) -> Result<(), Failure> {
                finish(t, assemble(t, state, params, g_i), dstate)
            }
            #stabilized
            #matrix_fn
        };
        Ok(RhsItems { items, depends_on_time, solve: plan, assembly, conditions })
    }

    /// Whether `initial_state` takes `G_I` from the module's `momenta` (emitted, and not empty).
    fn momenta_by_function(&self) -> bool {
        self.scope.num_ignorable > 0 && self.scope.options.functions.contains(&Function::Momenta)
    }

    fn initial_state(&mut self, f: &Equations, shared: &FromMechanics) -> Result<TokenStream, ModelError> {
        let work = self.scope.work;
        let name = f.name();
        let (args, inputs) = self.q_qdot_inputs(true);
        let u = &f.speeds_from_qdot;
        // The module's own `momenta` gives `G_I` where it is emitted: its body, stamped into
        // every formulation's `initial_state` as well, was a fifth of the humanoid's module
        // (rustc's time grows with the code it checks).
        let by_function = self.momenta_by_function();
        let g: &[Expr] = if by_function { &[] } else { &shared.momenta };
        let mut outputs = u.clone();
        outputs.extend(g.iter().copied());
        outputs.extend(shared.velocity_residuals.iter().copied());
        outputs.extend(shared.residual_bounds.iter().copied());
        outputs.extend(shared.positions.iter().copied());
        outputs.extend(shared.position_bounds.iter().copied());
        let b = self.body(&format!("{name}::initial_state"), &outputs, &inputs, &args)?;
        let o = &b.outputs;
        let (nu, ng, nr, nh) = (u.len(), g.len(), shared.velocity_residuals.len(), shared.positions.len());
        let u_out = &o[..nu];
        let g_out = &o[nu..nu + ng];
        let r_out = &o[nu + ng..nu + ng + nr];
        let rb_out = &o[nu + ng + nr..nu + ng + 2 * nr];
        let h_out = &o[nu + ng + 2 * nr..nu + ng + 2 * nr + nh];
        let hb_out = &o[nu + ng + 2 * nr + nh..];
        let names = &shared.constraint_names;
        let h_names = &shared.holonomic_names;
        let q_idx: Vec<Literal> = f.kept.iter().map(|&j| usize_lit(j)).collect();
        let w0 = if work { quote!(, 0.0) } else { TokenStream::new() };
        let stmts = &b.stmts;
        let helpers = &b.helpers;
        let calls: &[usize] = if by_function { &[0, 1, 2, 3] } else { &[0, 1, 2] };
        let used: BTreeSet<usize> = b.used_args.iter().copied().chain(calls.iter().copied()).collect();
        let fn_args = arg_list(&args, &used);
        let seam = &self.scope.seam;
        let g_i = if by_function { quote!(momenta(t, q, qdot, params)) } else { quote!([#(#g_out),*]) };
        Ok(quote! {
            #[doc = "The initial state and the conserved momenta `G_I` (Eq. 26) from `q(0), q'(0)`. Rejects velocities (or positions) that violate a constraint, with the residual."]
            #[allow(non_snake_case, clippy::all)]
            pub fn initial_state(#(#fn_args),*) -> Result<([f64; STATES], [f64; NUM_IGNORABLE]), Failure> {
                #stmts
                let residuals: [(&'static str, f64, f64); NUM_CONSTRAINTS] = [#((#names, #r_out, #rb_out)),*];
                let positions: [(&'static str, f64, f64); NUM_HOLONOMIC] = [#((#h_names, #h_out, #hb_out)),*];
                #seam::check::satisfied(residuals.into_iter().chain(positions), CONSTRAINT_TOLERANCE)?;
                let state: [f64; STATES] = [#(q[#q_idx],)* #(#u_out),* #w0];
                let g_i: [f64; NUM_IGNORABLE] = #g_i;
                #seam::check::finite(t, &state)?;
                #seam::check::finite_after(t, STATES, &g_i)?;
                Ok((state, g_i))
            }
            #helpers
        })
    }

    fn velocities_fn(&mut self, f: &Equations, checks: &[Expr]) -> Result<TokenStream, ModelError> {
        let model = self.scope.model;
        let m = model.m();
        let name = f.name();
        let args = state_args();
        let inputs = self.state_inputs(f);
        let mut outputs = f.qdot.clone();
        outputs.extend(checks.iter().copied());
        let b = self.body(&format!("{name}::velocities"), &outputs, &inputs, &args)?;
        let qd = &b.outputs[..m];
        let check_stmts: Vec<TokenStream> = b.outputs[m..]
            .iter()
            .enumerate()
            .map(|(k, v)| {
                let l = usize_lit(k);
                quote! {
                    let value = #v;
                    if !(value.abs() > SINGULAR_TOLERANCE) {
                        return Err(Failure::Singular { t, condition: CONDITIONS[#l].into(), value });
                    }
                }
            })
            .collect();
        let q_items: Vec<TokenStream> = (0..m)
            .map(|j| match f.kept.iter().position(|&k| k == j) {
                Some(pos) => {
                    let l = usize_lit(pos);
                    quote!(state[#l])
                }
                None => quote!(0.0),
            })
            .collect();
        let stmts = &b.stmts;
        let helpers = &b.helpers;
        let fn_args = arg_list(&args, &b.used_args.iter().copied().chain([0, 1]).collect());
        let seam = &self.scope.seam;
        Ok(quote! {
            #[doc = "Coordinates and velocities `(q, q')` at a state (`q' = W u + X`, Eq. 43, for the Volterra forms). Coordinates left out of the state read as 0."]
            #[allow(non_snake_case, clippy::all)]
            pub fn velocities(#(#fn_args),*) -> Result<([f64; NUM_COORDINATES], [f64; NUM_COORDINATES]), Failure> {
                #stmts
                #(#check_stmts)*
                let q: [f64; NUM_COORDINATES] = [#(#q_items),*];
                let qdot: [f64; NUM_COORDINATES] = [#(#qd),*];
                #seam::check::finite(t, &qdot)?;
                Ok((q, qdot))
            }
            #helpers
        })
    }

    /// `singular_margin`: the smallest singular factor of what was solved symbolically.
    fn singular_margin(&mut self, f: &Equations, checks: &[Expr]) -> Result<TokenStream, ModelError> {
        let args = state_args();
        let inputs = self.state_inputs(f);
        let b = self.body(&format!("{}::singular_margin", f.name()), checks, &inputs, &args)?;
        let stmts = &b.stmts;
        let values = &b.outputs;
        let helpers = &b.helpers;
        let fn_args = arg_list(&args, &b.used_args);
        let body = if values.is_empty() { quote!(f64::INFINITY) } else { quote!(f64::INFINITY #(.min(f64::abs(#values)))*) };
        Ok(quote! {
            #[doc = "The smallest magnitude of the factors whose vanishing makes the symbolically solved `[Y; M'; a]` singular (infinite when there are none): the distance to the singular set that `rhs` checks against `SINGULAR_TOLERANCE`."]
            #[allow(non_snake_case, clippy::all)]
            pub fn singular_margin(#(#fn_args),*) -> f64 {
                #stmts
                #body
            }
            #helpers
        })
    }
}

/// What each checked singular factor's vanishing means, in the order of the checks.
fn conditions(checks: &[Expr]) -> Vec<String> {
    checks
        .iter()
        .enumerate()
        .map(
            |(k, c)| {
                if c.tree_size() <= MAX_CONDITION_TREE { format!("{c} = 0") } else { format!("pivot factor {} of the velocity transformation vanishes", k + 1) }
            },
        )
        .collect()
}

impl FunctionCost {
    /// Assembly and solve together.
    pub fn total(&self) -> usize {
        self.ops.total() + self.solve.total()
    }
}

/// The speeds' names in a formulation's state: the rates' (`x'`) in Lagrange's and Maggi's
/// forms; in Kane's and the reduced form the quasi-velocities as the model writes them
/// (`omega_x(middle)`, `gamma1'`), which the derivation calls `u1, u2, ...`: a state column,
/// or `linearize`'s note on the fastest-moving entry, names what the user chose.
fn speed_names(model: &Model, f: &Equations) -> Vec<String> {
    let written = match f.kind {
        seam::FormulationKind::Kane => &model.def.quasi_velocities.full,
        seam::FormulationKind::ReducedVolterra => &model.def.quasi_velocities.reduced,
        _ => return f.speeds.iter().map(|s| s.name()).collect(),
    };
    let tidy = |w: &String| w.split_whitespace().collect::<Vec<_>>().join(" ");
    f.speeds.iter().enumerate().map(|(k, s)| written.get(k).map_or_else(|| s.name(), tidy)).collect()
}
