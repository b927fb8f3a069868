//! A formulation's exact Jacobian: `jacobian` returns the right-hand side and its derivative
//! by the state, from one body that evaluates the assembly (rates, matrix, forcing) and the
//! assembly's partial derivatives by every state entry, differentiated on the expression graph
//! and bound with one CSE over both.
//!
//! The solved rates `x = A^-1 F` are differentiated numerically-exactly after the solve:
//! `dx/ds_k = A^-1 (dF/ds_k - dA/ds_k x)`, with the LU factors of `A` computed once and reused
//! for every column. Maggi's speeds `W x + c` add `dW/ds_k x + W dx/ds_k + dc/ds_k`.

use super::from_mechanics::FromMechanics;
use super::function::state_args;
use super::module::Emitter;
use super::ops::OpCount;
use super::solvers::solve_cost;
use super::syntax::usize_lit;
use crate::formulation::Equations;
use crate::model::ModelError;
use crate::symbolic::Expr;
use proc_macro2::TokenStream;
use quote::quote;

/// The worst-case cost of the Jacobian's numeric part for an `n` by `n` matrix and `v` state
/// variables: one factorization, `v + 1` solves, and the products `dA/ds_k x`.
pub fn jacobian_solve_cost(n: usize, v: usize) -> OpCount {
    let mut c = solve_cost(n);
    let per_solve = n * n; // forward and back substitution: about n^2 multiply-adds
    c.add += v * (per_solve + n * n);
    c.mul += v * (per_solve + n * n);
    c.div += v * n;
    c
}

/// What a Jacobian differentiates by.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Wrt {
    /// The state's variables (kept coordinates, then speeds): `jacobian`.
    State,
    /// The runtime parameters, in `Params` order: `parameter_jacobian`.
    Parameters,
}

impl Emitter<'_> {
    /// `jacobian` (`jac[i][k] = d dstate_i / d state_k`) or `parameter_jacobian`
    /// (`jac[i][k] = d dstate_i / d params_k`), each with the right-hand side `dstate`.
    pub(super) fn jacobian_fn(&mut self, f: &Equations, shared: &FromMechanics, checks: &[Expr], wrt: Wrt) -> Result<TokenStream, ModelError> {
        let seam = self.scope.seam.clone();
        let name = f.name();
        let work = self.scope.work;
        let nq = f.kept.len();
        let n = f.mass.rows;
        let (rw, cw) = f.post.as_ref().map(|(w, _)| (w.rows, w.cols)).unwrap_or((0, 0));
        let rates = self.rate_outputs(f, shared);
        let variables: Vec<_> = match wrt {
            Wrt::State => f.kept.iter().map(|&j| self.scope.model.coordinates[j]).chain(f.speeds.iter().copied()).collect(),
            Wrt::Parameters => self.scope.model.parameters.iter().map(|(s, _)| *s).collect(),
        };
        let (function, structure, assemble) = match wrt {
            Wrt::State => ("jacobian", "Derivatives", "assemble_derivatives"),
            Wrt::Parameters => ("parameter_jacobian", "ParameterDerivatives", "assemble_parameter_derivatives"),
        };
        let (function_i, structure_i, assemble_i) = (super::function::ident(function), super::function::ident(structure), super::function::ident(assemble));
        let nv = variables.len();
        let mut outputs = rates.clone();
        outputs.extend(checks.iter().copied());
        for v in &variables {
            outputs.extend(rates.iter().map(|e| e.diff(*v)));
        }
        let args = state_args();
        let inputs = self.state_inputs(f);
        let b = self.body(&format!("{name}::{function}"), &outputs, &inputs, &args)?;
        // Moving constraints always carry the work state (`Emitter::new`): their power joins it.
        let weighted = f.constraint_power.is_some();
        let mut solve = jacobian_solve_cost(n, nv);
        if weighted {
            // `power_weights . x` and, per column, `d_power_weights . x + power_weights . dx`.
            solve.add += n * (2 * nv + 1);
            solve.mul += n * (2 * nv + 1);
        }
        self.record.functions.last_mut().expect("just pushed").solve = solve;
        let mut it = b.outputs.iter().cloned();
        let dims = Dims { nq, n, rw, cw, work, weighted };
        let (qd0, m0, f0, w0, c0, (p0, pw0)) = dims.block(&mut it);
        let check_out: Vec<TokenStream> = it.by_ref().take(checks.len()).collect();
        let mut d_qd = Vec::new();
        let mut d_m = Vec::new();
        let mut d_f = Vec::new();
        let mut d_w = Vec::new();
        let mut d_c = Vec::new();
        let mut d_p = Vec::new();
        let mut d_pw = Vec::new();
        for _ in 0..nv {
            let (a, b_, c_, w_, cc, (p, pw)) = dims.block(&mut it);
            d_qd.push(a);
            d_m.push(b_);
            d_f.push(c_);
            d_w.push(w_);
            d_c.push(cc);
            d_p.push(p);
            d_pw.push(pw);
        }
        let (n_l, nq_l, nv_l, rw_l, cw_l, nc_l) = (usize_lit(n), usize_lit(nq), usize_lit(nv), usize_lit(rw), usize_lit(cw), usize_lit(checks.len()));
        let stmts = &b.stmts;
        let helpers = &b.helpers;
        let fn_args = super::function::arg_list(&args, &b.used_args);
        // The parts `seam::rates::write_jacobian` reads besides the kept rates, the matrix and
        // the forcing, in the values' block and in variable `k`'s.
        let (mut parts, mut d_parts) = (Vec::new(), Vec::new());
        if f.post.is_some() {
            parts.push(quote!(w: w.as_flattened(), c: &c,));
            d_parts.push(quote!(w: d_w[k].as_flattened(), c: &d_c[k],));
        }
        if work {
            parts.push(quote!(power,));
            d_parts.push(quote!(power: d_power[k],));
        }
        if weighted {
            parts.push(quote!(power_weights: &power_weights,));
            d_parts.push(quote!(power_weights: &d_power_weights[k],));
        }
        let mut fields: Vec<(&str, TokenStream, TokenStream)> = vec![
            ("qdot", quote!([f64; #nq_l]), qd0),
            ("matrix", quote!([[f64; #n_l]; #n_l]), m0),
            ("force", quote!([f64; #n_l]), f0),
            ("checks", quote!([f64; #nc_l]), quote!([#(#check_out),*])),
            ("d_qdot", quote!([[f64; #nq_l]; #nv_l]), quote!([#(#d_qd),*])),
            ("d_matrix", quote!([[[f64; #n_l]; #n_l]; #nv_l]), quote!([#(#d_m),*])),
            ("d_force", quote!([[f64; #n_l]; #nv_l]), quote!([#(#d_f),*])),
        ];
        if f.post.is_some() {
            fields.push(("w", quote!([[f64; #cw_l]; #rw_l]), w0));
            fields.push(("c", quote!([f64; #rw_l]), c0));
            fields.push(("d_w", quote!([[[f64; #cw_l]; #rw_l]; #nv_l]), quote!([#(#d_w),*])));
            fields.push(("d_c", quote!([[f64; #rw_l]; #nv_l]), quote!([#(#d_c),*])));
        }
        if work {
            fields.push(("power", quote!(f64), p0));
            fields.push(("d_power", quote!([f64; #nv_l]), quote!([#(#d_p),*])));
        }
        if weighted {
            fields.push(("power_weights", quote!([f64; #n_l]), pw0));
            fields.push(("d_power_weights", quote!([[f64; #n_l]; #nv_l]), quote!([#(#d_pw),*])));
        }
        let field_types: Vec<TokenStream> = fields
            .iter()
            .map(|(n, ty, _)| {
                let i = super::function::ident(n);
                quote!(#i: #ty)
            })
            .collect();
        let field_values: Vec<TokenStream> = fields
            .iter()
            .map(|(n, _, v)| {
                let i = super::function::ident(n);
                quote!(#i: #v)
            })
            .collect();
        let field_names: Vec<TokenStream> = fields
            .iter()
            .map(|(n, _, _)| {
                let i = super::function::ident(n);
                if *n == "matrix" { quote!(mut #i) } else { quote!(#i) }
            })
            .collect();
        let (columns, what, zero_column) = match wrt {
            Wrt::State => (quote!(STATES), "state[k]", " The work integral's column is zero: nothing depends on it."),
            Wrt::Parameters => (quote!(#nv_l), "params.values()[k]", ""),
        };
        let struct_doc = format!(
            "Everything `{function}` evaluates before its solves: the assembly and its derivatives by each {}.",
            match wrt {
                Wrt::State => "state variable (kept coordinates, then speeds)",
                Wrt::Parameters => "parameter, in `Params::NAMES` order",
            }
        );
        let fn_doc = format!(
            "The right-hand side (as `rhs` writes it) and its exact derivative `jac[i][k] = d dstate[i] / d {what}`, from the assembly's symbolic derivatives and the LU factors of the solved matrix.{zero_column}"
        );
        Ok(quote! {
            #[doc = #struct_doc]
            struct #structure_i {
                #(#field_types,)*
            }
            #[doc = "Evaluates the assembly and its partial derivatives, with one set of common subexpressions."]
            #[allow(non_snake_case, clippy::all)]
            fn #assemble_i(#(#fn_args),*) -> #structure_i {
                #stmts
                #structure_i {
                    #(#field_values,)*
                }
            }
            #helpers
            #[doc = #fn_doc]
            #[allow(clippy::all)]
            pub fn #function_i(t: f64, state: &[f64; STATES], params: &Params, g_i: &[f64; NUM_IGNORABLE], dstate: &mut [f64; STATES], jac: &mut [[f64; #columns]; STATES]) -> Result<(), Failure> {
                let #structure_i { #(#field_names),* } = #assemble_i(t, state, params, g_i);
                let mut x = force;
                #seam::check::nonsingular(t, &CONDITIONS, &checks, SINGULAR_TOLERANCE)?;
                let pivots = #seam::solve::lu_factor_array(&mut matrix).map_err(|column| #seam::solve::singular(t, MATRIX_NAME, column))?;
                #seam::solve::lu_solve_array(&matrix, &pivots, &mut x);
                let block = #seam::rates::Block { qdot: &qdot, #(#parts)* ..#seam::rates::Block::EMPTY };
                let derivative = |k: usize| #seam::rates::Block { qdot: &d_qdot[k], matrix: d_matrix[k].as_flattened(), force: &d_force[k], #(#d_parts)* ..#seam::rates::Block::EMPTY };
                #seam::rates::write_jacobian(t, LAYOUT, &block, &x, (&matrix, &pivots), (#nv_l, derivative), &mut [0.0; #n_l], dstate, (jac.as_flattened_mut(), #columns))
            }
        })
    }
}

/// The sizes of one block of rates.
struct Dims {
    nq: usize,
    n: usize,
    rw: usize,
    cw: usize,
    work: bool,
    /// The power ends with weights on the solution (moving constraints).
    weighted: bool,
}

/// Kept rates, matrix, forcing, `W`, `c`, and the power with its weights.
type Block = (TokenStream, TokenStream, TokenStream, TokenStream, TokenStream, (TokenStream, TokenStream));

impl Dims {
    /// One block of rates (the values, or one variable's derivatives) as array literals:
    /// kept rates, matrix, forcing, `W`, `c`, power (and its weights on the solution).
    fn block(&self, it: &mut impl Iterator<Item = TokenStream>) -> Block {
        let mut take = |k: usize| -> Vec<TokenStream> { it.by_ref().take(k).collect() };
        let qd = take(self.nq);
        let rows = super::syntax::matrix_rows(&take(self.n * self.n), self.n, self.n);
        let force = take(self.n);
        let w_rows = super::syntax::matrix_rows(&take(self.rw * self.cw), self.rw, self.cw);
        let c = take(self.rw);
        let power = if self.work { take(1).remove(0) } else { quote!(0.0) };
        let weights = if self.weighted { take(self.n) } else { Vec::new() };
        (quote!([#(#qd),*]), quote!([#(#rows),*]), quote!([#(#force),*]), quote!([#(#w_rows),*]), quote!([#(#c),*]), (power, quote!([#(#weights),*])))
    }
}
