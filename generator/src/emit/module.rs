//! The generated module: sizes, `Params`, `EvalError`, the shared functions (energy, work
//! rate, momenta, constraint residuals) and one submodule per formulation with its
//! right-hand side, initial-state builder and velocity recovery.

use super::function::{Arg, Body, Input, arg_list, body, ident};
use super::lower::literal;
use super::ops::OpCount;
use super::prepare::Preparer;
use crate::symbolic::eval::magnitude;
use super::{Formulation, Function, Generated, Options, Parameters, Summary};
use crate::formulation::mechanics::{self, Mechanics};
use crate::formulation::volterra::{self, Volterra};
use crate::formulation::{classical, ignorable};
use crate::model::{ErrorKind, Model, ModelError};
use crate::symbolic::number::rat_from_f64;
use crate::symbolic::{Expr, Matrix, Symbol};
use proc_macro2::{Literal, TokenStream};
use quote::quote;
use std::collections::{BTreeSet, HashSet};
use std::time::Instant;

/// Relative size below which a pivot of the mass matrix counts as zero.
const PIVOT_TOLERANCE: f64 = 1e-13;
/// Absolute size below which a singular factor of `[Y; M'; a]` counts as zero.
const SINGULAR_TOLERANCE: f64 = 1e-12;
/// Relative size of a constraint residual, against its triangle-inequality magnitude, above
/// which initial velocities are rejected.
const CONSTRAINT_TOLERANCE: f64 = 1e-9;

const RUST_WORDS: &[&str] = &[
    "as", "async", "await", "break", "const", "continue", "crate", "dyn", "else", "enum", "extern", "false", "fn", "for",
    "gen", "if", "impl", "in", "let", "loop", "match", "mod", "move", "mut", "pub", "ref", "return", "self", "Self",
    "static", "struct", "super", "trait", "true", "type", "unsafe", "use", "where", "while", "abstract", "become", "box",
    "do", "final", "macro", "override", "priv", "typeof", "unsized", "virtual", "yield", "try", "union", "Ok", "Err",
    "Some", "None", "f64", "usize", "core", "std",
];

/// Names of the module's own items and of function arguments; model names that collide get a
/// trailing `_`.
const ITEM_NAMES: &[&str] = &[
    "MODEL", "NUM_COORDINATES", "NUM_CONSTRAINTS", "NUM_QUASI", "NUM_IGNORABLE", "NUM_HOLONOMIC", "COORDINATES",
    "CONSTRAINTS", "IGNORABLE", "INITIAL_Q", "INITIAL_QDOT", "T_START", "T_END", "DT_OUT", "PARAMETERS_BAKED",
    "SINGULAR_TOLERANCE", "PIVOT_TOLERANCE", "CONSTRAINT_TOLERANCE", "Params", "EvalError", "solve_dense", "energy",
    "work_rate", "momenta", "constraint_residuals", "position_residuals", "reduced_volterra", "kane", "STATES",
    "EQUATIONS", "STATE_NAMES", "INTEGRATES_IGNORABLE", "rhs", "initial_state", "velocities", "t", "state", "params",
    "g_i", "dstate", "q", "qdot", "v", "mass", "force", "value", "residual", "tolerance", "column", "index",
    "constraint", "bound", "residuals", "positions", "alpha", "beta", "rhs_baumgarte", "lagrange", "maggi", "matrix", "singular_margin", "MATRIX_SIZE",
];

/// Identifiers for model symbols, unique and never a keyword or item name.
struct Names {
    taken: HashSet<String>,
}

impl Names {
    fn new() -> Names {
        Names { taken: RUST_WORDS.iter().chain(ITEM_NAMES).map(|s| s.to_string()).collect() }
    }

    fn fresh(&mut self, base: &str) -> String {
        let mut name: String = base.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
        if name.is_empty() || name.starts_with(|c: char| c.is_ascii_digit()) {
            name.insert(0, '_');
        }
        while self.taken.contains(&name) {
            name.push('_');
        }
        self.taken.insert(name.clone());
        name
    }
}

/// Everything derived for one model, before emission.
struct Derived {
    mech: Mechanics,
    ignorable: Vec<usize>,
    reduced: Option<Volterra>,
    kane: Option<Volterra>,
}

fn derive(model: &Model, options: &Options) -> Result<Derived, ModelError> {
    let mech = mechanics::derive(model);
    let reports = ignorable::analyze(model, &mech);
    let chosen = ignorable::choose(model, &reports)?;
    let reduced = if options.formulations.contains(&Formulation::ReducedVolterra) {
        Some(volterra::derive(model, &mech, &chosen, &model.quasi_reduced)?)
    } else {
        None
    };
    let kane = if options.formulations.iter().any(|f| matches!(f, Formulation::Kane | Formulation::Maggi)) {
        Some(volterra::derive(model, &mech, &[], &model.quasi_full)?)
    } else {
        None
    };
    Ok(Derived { mech, ignorable: chosen, reduced, kane })
}

/// The symbols of a model, with their identifiers in emitted code.
struct SymbolNames {
    coordinates: Vec<String>,
    velocities: Vec<String>,
    parameters: Vec<String>,
    momenta: Vec<String>,
    quasi: Vec<String>,
}

struct Emitter<'a> {
    model: &'a Model,
    options: &'a Options,
    prep: Preparer,
    names: SymbolNames,
    functions: Vec<(String, usize, OpCount)>,
    /// Per emitted formulation: name, states, equations.
    forms: Vec<(String, usize, usize)>,
    /// The states end with the work integral `W`.
    work: bool,
}

pub(super) fn generate(model: &Model, options: &Options) -> Result<Generated, ModelError> {
    let start = Instant::now();
    let derived = derive(model, options)?;
    let derive_time = start.elapsed();
    let start = Instant::now();
    let mut names = Names::new();
    let parameters = model.parameters.iter().map(|(s, _)| names.fresh(&s.name())).collect();
    let coordinates: Vec<String> = model.coordinates.iter().map(|s| names.fresh(&s.name())).collect();
    let velocities = model.coordinates.iter().map(|s| names.fresh(&format!("{}_dot", s.name()))).collect();
    let momenta = derived.ignorable.iter().map(|&j| names.fresh(&volterra::momentum_symbol(model, j).name())).collect();
    let n_quasi = derived.mech.p;
    let quasi = (0..n_quasi).map(|k| names.fresh(&volterra::quasi_symbol(k).name())).collect();
    let mut em = Emitter {
        model,
        options,
        prep: Preparer::new(model, options.parameters == Parameters::Baked),
        names: SymbolNames { coordinates, velocities, parameters, momenta, quasi },
        functions: Vec::new(),
        forms: Vec::new(),
        work: false,
    };
    // Applied non-potential forces can do work (Q not identically zero once prepared): every
    // formulation then carries the work integral W as its last state.
    em.work = derived.mech.q_forces.iter().any(|q| !em.prep.prepare(*q).is_zero());
    let mut items = vec![em.header(&derived)];
    items.push(em.params());
    items.push(error_type());
    if !options.formulations.is_empty() {
        items.push(solve_dense());
    }
    let mut fns = Vec::new();
    for f in &options.functions {
        fns.extend(em.shared_function(*f, &derived)?);
    }
    items.extend(fns);
    if options.formulations.contains(&Formulation::Lagrange) {
        items.push(em.classical_form("lagrange", &derived)?);
    }
    if options.formulations.contains(&Formulation::Maggi) {
        items.push(em.classical_form("maggi", &derived)?);
    }
    if let Some(v) = &derived.kane
        && options.formulations.contains(&Formulation::Kane)
    {
        items.push(em.volterra_form("kane", v, &derived, true)?);
    }
    if let Some(v) = &derived.reduced {
        items.push(em.volterra_form("reduced_volterra", v, &derived, options.integrate_ignorable)?);
    }
    let tokens = quote!(#(#items)*);
    let file: syn::File = syn::parse2(tokens).map_err(|e| {
        model.error(ErrorKind::Emission, "emit", "emit", format!("internal: emitted tokens do not parse: {e}"), String::new())
    })?;
    let code = format!(
        "// Generated by `generator` from {} ({}). Do not edit: regenerate.\n\n{}",
        model_file_name(model),
        model.name,
        prettyplease::unparse(&file)
    );
    let s = derived.ignorable.len();
    let formulations = std::mem::take(&mut em.forms);
    let summary = Summary {
        model: model.name.clone(),
        m: derived.mech.m,
        r: derived.mech.r,
        p: derived.mech.p,
        s,
        formulations,
        functions: em.functions,
        derive_time,
        emit_time: start.elapsed(),
    };
    Ok(Generated { code, summary })
}

/// The model file's name without directories, so output does not depend on where it was run.
fn model_file_name(model: &Model) -> String {
    std::path::Path::new(&model.file).file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default()
}

fn usize_lit(n: usize) -> Literal {
    Literal::usize_unsuffixed(n)
}

fn f64_lit(x: f64) -> TokenStream {
    match rat_from_f64(x) {
        Some(r) => literal(&r).unwrap_or_else(|_| quote!(f64::NAN)),
        None => quote!(f64::NAN),
    }
}

fn doc(text: &str) -> TokenStream {
    quote!(#[doc = #text])
}

impl Emitter<'_> {
    fn emission_error(&self, what: &str, e: impl std::fmt::Display) -> ModelError {
        self.model.error(
            ErrorKind::Emission,
            "emit",
            "emit",
            format!("cannot emit {what}: {e}"),
            "check the model's expressions for numbers too large for f64 and functions without a definition".into(),
        )
    }

    fn header(&self, d: &Derived) -> TokenStream {
        let model = self.model;
        let m = &d.mech;
        let name = &model.name;
        let description = doc(&format!("Model `{}`: {}", model.name, model.description));
        let (nm, nr, np, ns, nh) = (usize_lit(m.m), usize_lit(m.r), usize_lit(m.p), usize_lit(d.ignorable.len()), usize_lit(m.holonomic.len()));
        let coords: Vec<String> = model.coordinates.iter().map(|s| s.name()).collect();
        let cons = &m.constraint_names;
        let ign: Vec<Literal> = d.ignorable.iter().map(|&i| usize_lit(i)).collect();
        let (pivot, singular, constraint) = (f64_lit(PIVOT_TOLERANCE), f64_lit(SINGULAR_TOLERANCE), f64_lit(CONSTRAINT_TOLERANCE));
        let mut out = quote! {
            #description
            pub const MODEL: &str = #name;
            #[doc = "Number of generalized coordinates, m."]
            pub const NUM_COORDINATES: usize = #nm;
            #[doc = "Number of kinematic constraints, r (holonomic ones counted at velocity level)."]
            pub const NUM_CONSTRAINTS: usize = #nr;
            #[doc = "Degrees of freedom in velocity, p = m - r."]
            pub const NUM_QUASI: usize = #np;
            #[doc = "Number of ignorable coordinates used by the reduced method, s."]
            pub const NUM_IGNORABLE: usize = #ns;
            #[doc = "Number of holonomic (position-level) constraints."]
            pub const NUM_HOLONOMIC: usize = #nh;
            #[doc = "Names of the generalized coordinates, in state order."]
            pub const COORDINATES: [&str; NUM_COORDINATES] = [#(#coords),*];
            #[doc = "Names of the constraints."]
            pub const CONSTRAINTS: [&str; NUM_CONSTRAINTS] = [#(#cons),*];
            #[doc = "Indices of the ignorable coordinates in `COORDINATES`."]
            pub const IGNORABLE: [usize; NUM_IGNORABLE] = [#(#ign),*];
            #[doc = "A singular factor of `[Y; M'; a]` smaller than this in magnitude stops the right-hand side."]
            pub const SINGULAR_TOLERANCE: f64 = #singular;
            #[doc = "A mass-matrix pivot smaller than this, relative to the largest entry, stops the right-hand side."]
            pub const PIVOT_TOLERANCE: f64 = #pivot;
            #[doc = "Initial velocities are rejected when a constraint residual exceeds this, relative to the residual's magnitude bound."]
            pub const CONSTRAINT_TOLERANCE: f64 = #constraint;
        };
        if let Some((q0, qd0)) = &model.initial {
            let q0: Vec<TokenStream> = q0.iter().map(|x| f64_lit(*x)).collect();
            let qd0: Vec<TokenStream> = qd0.iter().map(|x| f64_lit(*x)).collect();
            out.extend(quote! {
                #[doc = "Initial coordinates of the model's reference run."]
                pub const INITIAL_Q: [f64; NUM_COORDINATES] = [#(#q0),*];
                #[doc = "Initial velocities of the model's reference run."]
                pub const INITIAL_QDOT: [f64; NUM_COORDINATES] = [#(#qd0),*];
            });
        }
        if let Some(sim) = &model.simulation {
            let (a, b, c) = (f64_lit(sim.t_start), f64_lit(sim.t_end), f64_lit(sim.dt_out));
            out.extend(quote! {
                #[doc = "Start of the reference run."]
                pub const T_START: f64 = #a;
                #[doc = "End of the reference run."]
                pub const T_END: f64 = #b;
                #[doc = "Output interval of the reference run."]
                pub const DT_OUT: f64 = #c;
            });
        }
        out
    }

    fn params(&self) -> TokenStream {
        let baked = self.options.parameters == Parameters::Baked;
        let model = self.model;
        let k = if baked { 0 } else { model.parameters.len() };
        let kl = usize_lit(k);
        let fields: Vec<proc_macro2::Ident> =
            if baked { vec![] } else { self.names.parameters.iter().map(|n| ident(n)).collect() };
        let names: Vec<String> = if baked { vec![] } else { model.parameters.iter().map(|(s, _)| s.name()).collect() };
        let values: Vec<TokenStream> = if baked { vec![] } else { model.parameters.iter().map(|(_, v)| f64_lit(*v)).collect() };
        let docs: Vec<TokenStream> =
            names.iter().zip(&values).map(|(n, v)| doc(&format!("`{n}` (model value {v})"))).collect();
        let idx: Vec<Literal> = (0..k).map(usize_lit).collect();
        let struct_doc = if baked {
            "Parameters: none at runtime; the model's values are baked into the code as constants."
        } else {
            "The model's parameters; `Default` holds the values from the model file."
        };
        let values_arg = if k == 0 { quote!(_values) } else { quote!(values) };
        quote! {
            #[doc = "True when the parameters were folded into the code as constants."]
            pub const PARAMETERS_BAKED: bool = #baked;
            #[doc = #struct_doc]
            #[allow(non_snake_case)]
            #[derive(Clone, Copy, Debug, PartialEq)]
            pub struct Params {
                #(#docs pub #fields: f64,)*
            }
            impl Default for Params {
                fn default() -> Self {
                    Params { #(#fields: #values,)* }
                }
            }
            impl Params {
                #[doc = "Parameter names, in the order of `values` and `from_values`."]
                pub const NAMES: [&'static str; #kl] = [#(#names),*];
                #[doc = "The parameters as an array, in the order of `NAMES`."]
                pub fn values(&self) -> [f64; #kl] {
                    [#(self.#fields),*]
                }
                #[doc = "Parameters from an array in the order of `NAMES`."]
                pub fn from_values(#values_arg: &[f64; #kl]) -> Self {
                    Params { #(#fields: values[#idx],)* }
                }
            }
        }
    }

    /// Inputs for the parameters (runtime mode only), read from argument `arg`.
    fn parameter_inputs(&self, arg: usize) -> Vec<Input> {
        if self.options.parameters == Parameters::Baked {
            return vec![];
        }
        self.model
            .parameters
            .iter()
            .zip(&self.names.parameters)
            .map(|((s, _), n)| {
                let f = ident(n);
                Input::new(*s, n, arg, quote!(params.#f))
            })
            .collect()
    }

    fn time_input(&self) -> Input {
        Input::new(self.model.t, "t", 0, TokenStream::new())
    }

    /// Inputs `t`, `q[j]`, `qdot[j]`, `params`: the signature of the shared functions.
    fn q_qdot_inputs(&self, with_velocities: bool) -> (Vec<Arg>, Vec<Input>) {
        let mut args = vec![Arg::new("t", quote!(f64)), Arg::new("q", quote!(&[f64; NUM_COORDINATES]))];
        let mut inputs = vec![self.time_input()];
        for (j, (s, n)) in self.model.coordinates.iter().zip(&self.names.coordinates).enumerate() {
            let l = usize_lit(j);
            inputs.push(Input::new(*s, n, 1, quote!(q[#l])));
        }
        if with_velocities {
            args.push(Arg::new("qdot", quote!(&[f64; NUM_COORDINATES])));
            for (j, (s, n)) in self.model.velocities.iter().zip(&self.names.velocities).enumerate() {
                let l = usize_lit(j);
                inputs.push(Input::new(*s, n, 2, quote!(qdot[#l])));
            }
        }
        args.push(Arg::new("params", quote!(&Params)));
        let p = args.len() - 1;
        inputs.extend(self.parameter_inputs(p));
        (args, inputs)
    }

    /// Emits the body for `outputs` and records its cost under `name`.
    fn body(&mut self, name: &str, outputs: &[Expr], inputs: &[Input], args: &[Arg]) -> Result<Body, ModelError> {
        let prepared = self.prep.prepare_all(outputs);
        let short = name.rsplit("::").next().unwrap_or(name);
        let b = body(short, &prepared, inputs, args, self.options.max_lets_per_function)
            .map_err(|e| self.emission_error(name, e))?;
        self.functions.push((name.to_string(), b.lets, b.ops.clone()));
        Ok(b)
    }

    fn shared_function(&mut self, f: Function, d: &Derived) -> Result<Vec<TokenStream>, ModelError> {
        let m = &d.mech;
        let mut out = Vec::new();
        match f {
            Function::Energy => {
                let (args, inputs) = self.q_qdot_inputs(true);
                let b = self.body("energy", &[m.kinetic + m.potential], &inputs, &args)?;
                out.push(simple_fn("energy", "Total energy T + V.", &args, &b, quote!(f64), |o| quote!(#(#o)*)));
            }
            Function::WorkRate => {
                let (args, inputs) = self.q_qdot_inputs(true);
                let rate = Expr::sum(m.q_forces.iter().zip(&self.model.velocities).map(|(q, v)| *q * v.expr()));
                let b = self.body("work_rate", &[rate], &inputs, &args)?;
                out.push(simple_fn(
                    "work_rate",
                    "Power of the applied non-potential forces, `Q . q'`: the rate of the work integral (Eq. 80).",
                    &args,
                    &b,
                    quote!(f64),
                    |o| quote!(#(#o)*),
                ));
            }
            Function::Momenta => {
                let (args, inputs) = self.q_qdot_inputs(true);
                let g = momenta(m, &d.ignorable, &self.model.velocities);
                let b = self.body("momenta", &g, &inputs, &args)?;
                out.push(simple_fn(
                    "momenta",
                    "Generalized momenta `M' q' + N2` of the ignorable coordinates (Eq. 26): conserved, equal to `G_I`.",
                    &args,
                    &b,
                    quote!([f64; NUM_IGNORABLE]),
                    |o| quote!([#(#o),*]),
                ));
            }
            Function::Constraints => {
                let (args, inputs) = self.q_qdot_inputs(true);
                let res = m.velocity_residuals(&self.model.velocities);
                let b = self.body("constraint_residuals", &res, &inputs, &args)?;
                out.push(simple_fn(
                    "constraint_residuals",
                    "Velocity-level constraint residuals `a q' + b` (zero on admissible motions).",
                    &args,
                    &b,
                    quote!([f64; NUM_CONSTRAINTS]),
                    |o| quote!([#(#o),*]),
                ));
                let (args, inputs) = self.q_qdot_inputs(false);
                let pos: Vec<Expr> = m.holonomic.iter().map(|(_, e)| *e).collect();
                let b = self.body("position_residuals", &pos, &inputs, &args)?;
                out.push(simple_fn(
                    "position_residuals",
                    "Position-level residuals of the holonomic constraints.",
                    &args,
                    &b,
                    quote!([f64; NUM_HOLONOMIC]),
                    |o| quote!([#(#o),*]),
                ));
            }
        }
        Ok(out)
    }

    /// The reduced Volterra or Kane submodule.
    fn volterra_form(&mut self, name: &str, v: &Volterra, d: &Derived, integrate_ignorable: bool) -> Result<TokenStream, ModelError> {
        let model = self.model;
        let m = model.m();
        let dropped: Vec<usize> = if integrate_ignorable { vec![] } else { v.ignorable.clone() };
        if !dropped.is_empty() {
            self.check_droppable(v, &dropped)?;
        }
        let n_u = v.u.len();
        let speeds: Vec<(Symbol, String)> = v.u.iter().zip(&self.names.quasi).map(|(u, n)| (*u, n.clone())).collect();
        // u = Y q' + Z, for the initial state.
        let from_qdot: Vec<Expr> = (0..n_u)
            .map(|k| Expr::sum((0..m).map(|j| v.y.get(k, j) * model.velocities[j].expr())) + v.z[k])
            .collect();
        let kane = name == "kane";
        let form = Form {
            name: name.to_string(),
            label: if kane { "Kane / Gibbs-Appell (standard Volterra)" } else { "the reduced Volterra equations (paper Eqs. 64-67)" }.into(),
            kept: (0..m).filter(|j| !dropped.contains(j)).collect(),
            speeds,
            momenta: v.g.clone(),
            qdot: v.qdot.clone(),
            from_qdot,
            mass: v.mass_ni.clone(),
            force: v.l_ni.clone(),
            post: None,
            checks: self.runtime_factors(v),
            equations: n_u,
            matrix_name: "mass matrix M_NI",
        };
        self.form(&form, d)
    }

    /// The Lagrange (with multipliers) or Maggi submodule, state `[q; q']`.
    fn classical_form(&mut self, name: &str, d: &Derived) -> Result<TokenStream, ModelError> {
        let model = self.model;
        let mech = &d.mech;
        let (m, r) = (mech.m, mech.r);
        let c = classical::derive(model, mech);
        let speeds: Vec<(Symbol, String)> = model.velocities.iter().zip(&self.names.velocities).map(|(v, n)| (*v, n.clone())).collect();
        let qd: Vec<Expr> = model.velocities.iter().map(|s| s.expr()).collect();
        let (mass, force, post, matrix_name, label) = if name == "lagrange" {
            // [M a^T; a 0] [q''; -lambda] = [f; gamma]: symmetric.
            let mut kkt = Matrix::zeros(m + r, m + r);
            for i in 0..m {
                for j in 0..m {
                    kkt.set(i, j, mech.mass.get(i, j));
                }
            }
            for i in 0..r {
                for j in 0..m {
                    kkt.set(m + i, j, mech.a.get(i, j));
                    kkt.set(j, m + i, mech.a.get(i, j));
                }
            }
            let rhs: Vec<Expr> = c.force.iter().chain(&c.gamma).copied().collect();
            (kkt, rhs, None, "constraint matrix [M a^T; a 0]", "Lagrange's equations with multipliers")
        } else {
            let kane = d.kane.as_ref().expect("Maggi needs the Kane derivation");
            let w = kane.w.clone();
            let drift = classical::maggi_drift(model, mech, kane);
            let wt = w.transpose();
            let mass = wt.mul(&mech.mass).mul(&w);
            let mc = mech.mass.mul(&Matrix::column(drift.clone()));
            let rest = Matrix::column((0..m).map(|j| c.force[j] - mc.get(j, 0)).collect());
            let force = wt.mul(&rest).col(0);
            (mass, force, Some((w, drift)), "Maggi matrix W^T M W", "Maggi's equations")
        };
        let checks = d.kane.as_ref().map(|k| self.runtime_factors(k)).filter(|_| name == "maggi").unwrap_or_default();
        let form = Form {
            name: name.to_string(),
            label: label.into(),
            kept: (0..m).collect(),
            speeds,
            momenta: vec![],
            qdot: qd.clone(),
            from_qdot: qd,
            mass,
            force,
            post,
            checks,
            equations: m,
            matrix_name,
        };
        self.form(&form, d)
    }

    /// A formulation's submodule: `rhs`, `initial_state`, `velocities`.
    fn form(&mut self, f: &Form, d: &Derived) -> Result<TokenStream, ModelError> {
        let model = self.model;
        let m = model.m();
        let name = f.name.as_str();
        let work = self.work;
        let n_states = f.states(work);
        let mut state_names: Vec<String> = f.kept.iter().map(|&j| model.coordinates[j].name()).collect();
        state_names.extend(f.speeds.iter().map(|(s, _)| s.name()));
        if work {
            state_names.push("W".into());
        }
        let states_l = usize_lit(n_states);

        let rhs = self.rhs_item(f, d, "rhs", &f.force, &[])?;
        let stabilized = if name == "lagrange" {
            // Baumgarte: a q'' = gamma - 2 alpha (a q' + b) - beta^2 h.
            let (alpha, beta) = (Symbol::new("alpha__"), Symbol::new("beta__"));
            let mech = &d.mech;
            let mut force = f.force.clone();
            let m = mech.m;
            for (i, residual) in mech.velocity_residuals(&model.velocities).into_iter().enumerate() {
                let position = mech.holonomic.iter().find(|(k, _)| *k == i).map_or(Expr::zero(), |(_, h)| *h);
                force[m + i] = force[m + i] - alpha.expr() * residual * 2 - beta.expr().powi(2) * position;
            }
            self.rhs_item(f, d, "rhs_baumgarte", &force, &[(alpha, "alpha"), (beta, "beta")])?
        } else {
            TokenStream::new()
        };
        let init = self.initial_state(f, d)?;
        let vel = self.velocities_fn(f)?;
        let conditioning = self.conditioning_fns(f)?;
        let module = ident(name);
        let eqs = usize_lit(f.equations);
        let integrates = f.kept.len() == m;
        let mod_doc = doc(&format!("{}: {n_states} states, {} equations.", f.label, f.equations));
        self.forms.push((name.to_string(), n_states, f.equations));
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
                #rhs
                #stabilized
                #init
                #vel
                #conditioning
            }
        })
    }

    /// The `rhs` function (or a variant with `extra` scalar arguments after `dstate`).
    fn rhs_item(&mut self, f: &Form, d: &Derived, fn_name: &str, force: &[Expr], extra: &[(Symbol, &str)]) -> Result<TokenStream, ModelError> {
        let work = self.work;
        let n_states = f.states(work);
        let model = self.model;
        let name = f.name.as_str();
        let nq = f.kept.len();
        let n_speeds = f.speeds.len();
        let n = f.mass.rows;
        let n_l = usize_lit(n);
        // The right-hand side.
        let mut args = vec![
            Arg::new("t", quote!(f64)),
            Arg::new("state", quote!(&[f64; STATES])),
            Arg::new("params", quote!(&Params)),
            Arg::new("g_i", quote!(&[f64; NUM_IGNORABLE])),
            Arg::new("dstate", quote!(&mut [f64; STATES])),
        ];
        let mut inputs = self.state_inputs(f);
        for (k, (sym, arg)) in extra.iter().enumerate() {
            args.push(Arg::new(arg, quote!(f64)));
            inputs.push(Input::new(*sym, arg, 5 + k, TokenStream::new()));
        }
        let mut outputs: Vec<Expr> = f.kept.iter().map(|&j| f.qdot[j]).collect();
        // Symmetric: both triangles read the upper entry, so CSE binds it once.
        for i in 0..n {
            for j in 0..n {
                outputs.push(f.mass.get(i.min(j), i.max(j)));
            }
        }
        outputs.extend(force.iter().copied());
        let post_len = f.post.as_ref().map_or(0, |(w, _)| w.rows * w.cols + w.rows);
        if let Some((w, c)) = &f.post {
            outputs.extend(w.data.iter().copied());
            outputs.extend(c.iter().copied());
        }
        if work {
            let to_qdot: std::collections::HashMap<Symbol, Expr> =
                model.velocities.iter().copied().zip(f.qdot.iter().copied()).collect();
            let power = Expr::sum(d.mech.q_forces.iter().zip(&f.qdot).map(|(q, v)| q.subs(&to_qdot) * *v));
            outputs.push(power);
        }
        outputs.extend(f.checks.iter().copied());
        let b = self.body(&format!("{name}::{fn_name}"), &outputs, &inputs, &args)?;
        add_solve_cost(self.functions.last_mut().expect("just pushed"), n);
        let o = &b.outputs;
        let qd_out = &o[..nq];
        let rows: Vec<TokenStream> = o[nq..nq + n * n].chunks(n).map(|r| quote!([#(#r),*])).collect();
        let mut at = nq + n * n;
        let l_out = &o[at..at + n];
        at += n;
        let speed_values: Vec<TokenStream> = match &f.post {
            None => (0..n_speeds).map(|k| {
                let l = usize_lit(k);
                quote!(force[#l])
            }).collect(),
            Some((w, _)) => {
                let (rows_w, cols_w) = (w.rows, w.cols);
                let w_out = &o[at..at + rows_w * cols_w];
                let c_out = &o[at + rows_w * cols_w..at + post_len];
                (0..rows_w)
                    .map(|j| {
                        let terms: Vec<TokenStream> = (0..cols_w)
                            .map(|k| {
                                let wk = &w_out[j * cols_w + k];
                                let l = usize_lit(k);
                                quote!(#wk * force[#l])
                            })
                            .collect();
                        let cj = &c_out[j];
                        quote!(#(#terms +)* #cj)
                    })
                    .collect()
            }
        };
        at += post_len;
        let power_stmt = if work {
            let p = &o[at];
            at += 1;
            let l = usize_lit(n_states - 1);
            quote!(dstate[#l] = #p;)
        } else {
            TokenStream::new()
        };
        let check_stmts = singular_checks(&f.checks, &o[at..]);
        let qd_idx: Vec<Literal> = (0..nq).map(usize_lit).collect();
        let s_idx: Vec<Literal> = (0..n_speeds).map(|k| usize_lit(nq + k)).collect();
        let stmts = &b.stmts;
        let helpers = &b.helpers;
        let matrix_name = f.matrix_name;
        let rhs_args = arg_list(&args, &b.used_args.iter().copied().chain([0, 1, 4]).collect());
        let fn_ident = ident(fn_name);
        let stabilized_note = if extra.is_empty() {
            ""
        } else {
            " Baumgarte-stabilized: the constraints at acceleration level become `a q'' = gamma - 2 alpha (a q' + b) - beta^2 h` (h: holonomic residuals); `alpha = beta = 0` is `rhs`."
        };
        let rhs_doc = doc(&format!(
            "Right-hand side of {}: `dstate = [q'; {}']`{} for `state = [q; {}]`. Stops with `EvalError::Singular` where the equations are singular and `EvalError::NonFinite` instead of writing NaN.{}",
            f.label,
            if f.post.is_some() || name == "lagrange" { "q'" } else { "u" },
            if work { " and the power `W' = Q . q'` last" } else { "" },
            if f.post.is_some() || name == "lagrange" { "q'" } else { "u" },
            stabilized_note,
        ));
        Ok(quote! {
            #rhs_doc
            #[allow(non_snake_case, clippy::all)]
            pub fn #fn_ident(#(#rhs_args),*) -> Result<(), EvalError> {
                #(#stmts)*
                #(#check_stmts)*
                let mut matrix: [[f64; #n_l]; #n_l] = [#(#rows),*];
                let mut force: [f64; #n_l] = [#(#l_out),*];
                if let Err(column) = solve_dense(&mut matrix, &mut force) {
                    return Err(EvalError::Singular { t, condition: #matrix_name, value: column as f64 });
                }
                #(dstate[#qd_idx] = #qd_out;)*
                #(dstate[#s_idx] = #speed_values;)*
                #power_stmt
                for (index, value) in dstate.iter().enumerate() {
                    if !value.is_finite() {
                        return Err(EvalError::NonFinite { t, index });
                    }
                }
                Ok(())
            }
            #(#helpers)*
        })
    }

    /// `matrix` (what `rhs` solves numerically, for its condition number) and
    /// `singular_margin` (the smallest singular factor of what was solved symbolically).
    fn conditioning_fns(&mut self, f: &Form) -> Result<TokenStream, ModelError> {
        let name = f.name.as_str();
        let n = f.mass.rows;
        let n_l = usize_lit(n);
        let args = vec![
            Arg::new("t", quote!(f64)),
            Arg::new("state", quote!(&[f64; STATES])),
            Arg::new("params", quote!(&Params)),
            Arg::new("g_i", quote!(&[f64; NUM_IGNORABLE])),
        ];
        let inputs = self.state_inputs(f);
        let mut outputs = Vec::new();
        for i in 0..n {
            for j in 0..n {
                outputs.push(f.mass.get(i.min(j), i.max(j)));
            }
        }
        let b = self.body(&format!("{name}::matrix"), &outputs, &inputs, &args)?;
        let rows: Vec<TokenStream> = b.outputs.chunks(n).map(|r| quote!([#(#r),*])).collect();
        let stmts = &b.stmts;
        let helpers = &b.helpers;
        let fn_args = arg_list(&args, &b.used_args);
        let matrix_name = f.matrix_name;
        let matrix_doc = doc(&format!("The matrix `rhs` solves numerically ({matrix_name}), for monitoring its conditioning."));
        let mut out = quote! {
            #[doc = "Size of the matrix `rhs` solves numerically."]
            pub const MATRIX_SIZE: usize = #n_l;
            #matrix_doc
            #[allow(non_snake_case, clippy::all)]
            pub fn matrix(#(#fn_args),*) -> [[f64; MATRIX_SIZE]; MATRIX_SIZE] {
                #(#stmts)*
                [#(#rows),*]
            }
            #(#helpers)*
        };
        let b = self.body(&format!("{name}::singular_margin"), &f.checks, &inputs, &args)?;
        let stmts = &b.stmts;
        let values = &b.outputs;
        let fn_args = arg_list(&args, &b.used_args);
        let body = if values.is_empty() {
            quote!(f64::INFINITY)
        } else {
            quote!(f64::INFINITY #(.min(f64::abs(#values)))*)
        };
        out.extend(quote! {
            #[doc = "The smallest magnitude of the factors whose vanishing makes the symbolically solved `[Y; M'; a]` singular (infinite when there are none): the distance to the singular set that `rhs` checks against `SINGULAR_TOLERANCE`."]
            #[allow(non_snake_case, clippy::all)]
            pub fn singular_margin(#(#fn_args),*) -> f64 {
                #(#stmts)*
                #body
            }
        });
        Ok(out)
    }

    /// Inputs of the functions of a state: `t`, kept coordinates and speeds from `state`
    /// (argument 1), parameters (argument 2), `G_I` (argument 3).
    fn state_inputs(&self, f: &Form) -> Vec<Input> {
        let model = self.model;
        let mut inputs = vec![self.time_input()];
        for (pos, &j) in f.kept.iter().enumerate() {
            let l = usize_lit(pos);
            inputs.push(Input::new(model.coordinates[j], &self.names.coordinates[j], 1, quote!(state[#l])));
        }
        for (k, (s, n)) in f.speeds.iter().enumerate() {
            let l = usize_lit(f.kept.len() + k);
            inputs.push(Input::new(*s, n, 1, quote!(state[#l])));
        }
        inputs.extend(self.parameter_inputs(2));
        for (k, g) in f.momenta.iter().enumerate() {
            let l = usize_lit(k);
            inputs.push(Input::new(*g, &self.names.momenta[k], 3, quote!(g_i[#l])));
        }
        inputs
    }

    /// The factors of `[Y; M'; a]`'s pivots that vary with the state: checked at runtime.
    fn runtime_factors(&mut self, v: &Volterra) -> Vec<Expr> {
        let varying: BTreeSet<Symbol> = self
            .model
            .coordinates
            .iter()
            .chain(&v.u)
            .chain(&v.g)
            .chain([&self.model.t])
            .copied()
            .collect();
        let mut out: Vec<Expr> = Vec::new();
        for f in &v.singular_factors {
            let p = self.prep.prepare(*f);
            if p.free_symbols().iter().any(|s| varying.contains(s)) && !out.contains(f) {
                out.push(*f);
            }
        }
        out
    }

    fn check_droppable(&self, v: &Volterra, dropped: &[usize]) -> Result<(), ModelError> {
        let mut exprs: Vec<(String, Expr)> = Vec::new();
        for (j, e) in v.qdot.iter().enumerate() {
            exprs.push((format!("q'_{} = W u + X", self.model.coordinates[j].name()), *e));
        }
        for (k, e) in v.l_ni.iter().enumerate() {
            exprs.push((format!("L_NI[{k}]"), *e));
        }
        for e in v.mass_ni.data.iter() {
            exprs.push(("M_NI".into(), *e));
        }
        for &j in dropped {
            let q = self.model.coordinates[j];
            if let Some((place, _)) = exprs.iter().find(|(_, e)| e.contains(q)) {
                return Err(self.model.error(
                    ErrorKind::IgnorableNeeded,
                    "emit.integrate_ignorable",
                    "integrate_ignorable",
                    format!("`{}` cannot leave the state: {place} depends on it", q.name()),
                    "set `integrate_ignorable: true` in `emit`".into(),
                ));
            }
        }
        Ok(())
    }

    fn initial_state(&mut self, f: &Form, d: &Derived) -> Result<TokenStream, ModelError> {
        let work = self.work;
        let model = self.model;
        let mech = &d.mech;
        let name = f.name.as_str();
        let (args, inputs) = self.q_qdot_inputs(true);
        let u = &f.from_qdot;
        let g = momenta(mech, &d.ignorable, &model.velocities);
        let residuals = mech.velocity_residuals(&model.velocities);
        let bounds: Vec<Expr> = (0..mech.r)
            .map(|i| {
                Expr::sum((0..mech.m).map(|j| magnitude(mech.a.get(i, j) * model.velocities[j].expr()))) + magnitude(mech.b[i])
            })
            .collect();
        let positions: Vec<Expr> = mech.holonomic.iter().map(|(_, e)| *e).collect();
        let pos_bounds: Vec<Expr> = positions.iter().map(|e| magnitude(*e)).collect();
        let mut outputs = u.clone();
        outputs.extend(g.iter().copied());
        outputs.extend(residuals.iter().copied());
        outputs.extend(bounds.iter().copied());
        outputs.extend(positions.iter().copied());
        outputs.extend(pos_bounds.iter().copied());
        let b = self.body(&format!("{name}::initial_state"), &outputs, &inputs, &args)?;
        let o = &b.outputs;
        let (nu, ng, nr, nh) = (u.len(), g.len(), mech.r, positions.len());
        let u_out = &o[..nu];
        let g_out = &o[nu..nu + ng];
        let r_out = &o[nu + ng..nu + ng + nr];
        let rb_out = &o[nu + ng + nr..nu + ng + 2 * nr];
        let h_out = &o[nu + ng + 2 * nr..nu + ng + 2 * nr + nh];
        let hb_out = &o[nu + ng + 2 * nr + nh..];
        let names: Vec<&String> = mech.constraint_names.iter().collect();
        let h_names: Vec<&String> = mech.holonomic.iter().map(|(i, _)| &mech.constraint_names[*i]).collect();
        let q_idx: Vec<Literal> = f.kept.iter().map(|&j| usize_lit(j)).collect();
        let w0 = if work { quote!(, 0.0) } else { TokenStream::new() };
        let stmts = &b.stmts;
        let used: BTreeSet<usize> = b.used_args.iter().copied().chain([0, 1, 2]).collect();
        let fn_args = arg_list(&args, &used);
        Ok(quote! {
            #[doc = "The initial state and the conserved momenta `G_I` (Eq. 26) from `q(0), q'(0)`. Rejects velocities (or positions) that violate a constraint, with the residual."]
            #[allow(non_snake_case, clippy::all)]
            pub fn initial_state(#(#fn_args),*) -> Result<([f64; STATES], [f64; NUM_IGNORABLE]), EvalError> {
                #(#stmts)*
                let residuals: [(&'static str, f64, f64); NUM_CONSTRAINTS] = [#((#names, #r_out, #rb_out)),*];
                let positions: [(&'static str, f64, f64); NUM_HOLONOMIC] = [#((#h_names, #h_out, #hb_out)),*];
                for (constraint, residual, bound) in residuals.into_iter().chain(positions) {
                    let tolerance = CONSTRAINT_TOLERANCE * bound;
                    if !(residual.abs() <= tolerance) {
                        return Err(EvalError::ConstraintViolated { constraint, residual, tolerance });
                    }
                }
                let state: [f64; STATES] = [#(q[#q_idx],)* #(#u_out),* #w0];
                let g_i: [f64; NUM_IGNORABLE] = [#(#g_out),*];
                for (index, value) in state.iter().chain(g_i.iter()).enumerate() {
                    if !value.is_finite() {
                        return Err(EvalError::NonFinite { t, index });
                    }
                }
                Ok((state, g_i))
            }
        })
    }

    fn velocities_fn(&mut self, f: &Form) -> Result<TokenStream, ModelError> {
        let model = self.model;
        let m = model.m();
        let name = f.name.as_str();
        let args = vec![
            Arg::new("t", quote!(f64)),
            Arg::new("state", quote!(&[f64; STATES])),
            Arg::new("params", quote!(&Params)),
            Arg::new("g_i", quote!(&[f64; NUM_IGNORABLE])),
        ];
        let inputs = self.state_inputs(f);
        let mut outputs = f.qdot.clone();
        outputs.extend(f.checks.iter().copied());
        let b = self.body(&format!("{name}::velocities"), &outputs, &inputs, &args)?;
        let qd = &b.outputs[..m];
        let check_stmts = singular_checks(&f.checks, &b.outputs[m..]);
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
        let fn_args = arg_list(&args, &b.used_args.iter().copied().chain([0, 1]).collect());
        Ok(quote! {
            #[doc = "Coordinates and velocities `(q, q')` at a state (`q' = W u + X`, Eq. 43, for the Volterra forms). Coordinates left out of the state read as 0."]
            #[allow(non_snake_case, clippy::all)]
            pub fn velocities(#(#fn_args),*) -> Result<([f64; NUM_COORDINATES], [f64; NUM_COORDINATES]), EvalError> {
                #(#stmts)*
                #(#check_stmts)*
                let q: [f64; NUM_COORDINATES] = [#(#q_items),*];
                let qdot: [f64; NUM_COORDINATES] = [#(#qd),*];
                for (index, value) in qdot.iter().enumerate() {
                    if !value.is_finite() {
                        return Err(EvalError::NonFinite { t, index });
                    }
                }
                Ok((q, qdot))
            }
        })
    }
}

/// What a formulation's submodule is built from.
struct Form {
    name: String,
    label: String,
    /// Coordinates in the state, in order.
    kept: Vec<usize>,
    /// The second half of the state: quasi-velocities or `q'` symbols, with identifiers.
    speeds: Vec<(Symbol, String)>,
    /// `G_I` symbols the expressions use.
    momenta: Vec<Symbol>,
    /// `q'` of every coordinate in terms of the state.
    qdot: Vec<Expr>,
    /// The speeds in terms of `q, q'` (for the initial state).
    from_qdot: Vec<Expr>,
    /// `matrix x = force`, solved numerically (symmetric: the upper triangle is read).
    mass: Matrix,
    force: Vec<Expr>,
    /// Maggi: the speeds' rates are `W x + c`.
    post: Option<(Matrix, Vec<Expr>)>,
    /// Factors whose vanishing makes the equations singular.
    checks: Vec<Expr>,
    equations: usize,
    matrix_name: &'static str,
}

impl Form {
    /// Length of the state: kept coordinates, speeds, and `W` when forces can do work.
    fn states(&self, work: bool) -> usize {
        self.kept.len() + self.speeds.len() + usize::from(work)
    }
}

/// `if !(f.abs() > SINGULAR_TOLERANCE) { return Err(..) }` per factor.
/// Largest singular factor (tree nodes) named by its formula in `EvalError::Singular`.
const MAX_CONDITION_TREE: u32 = 200;

fn singular_checks(factors: &[Expr], values: &[TokenStream]) -> Vec<TokenStream> {
    factors
        .iter()
        .zip(values)
        .enumerate()
        .map(|(k, (f, v))| {
            let cond = if f.tree_size() <= MAX_CONDITION_TREE { format!("{f} = 0") } else { format!("pivot factor {} of the velocity transformation vanishes", k + 1) };
            quote! {
                let value = #v;
                if !(value.abs() > SINGULAR_TOLERANCE) {
                    return Err(EvalError::Singular { t, condition: #cond, value });
                }
            }
        })
        .collect()
}

/// `M' q' + N2` for the ignorable coordinates.
fn momenta(m: &Mechanics, ignorable: &[usize], velocities: &[Symbol]) -> Vec<Expr> {
    ignorable.iter().map(|&i| m.momentum(i, velocities)).collect()
}

/// The worst-case cost of `solve_dense` for `n` unknowns, added to a function's count.
fn add_solve_cost(entry: &mut (String, usize, OpCount), n: usize) {
    let elim_div = n * (n - 1) / 2;
    let elim_mul: usize = (0..n).map(|c| (n - 1 - c) * (n - c)).sum();
    let back = n * (n - 1) / 2;
    entry.2.div += elim_div + n;
    entry.2.mul += elim_mul + back;
    entry.2.add += elim_mul + back;
}

fn simple_fn(
    name: &str,
    text: &str,
    args: &[Arg],
    b: &Body,
    ret: TokenStream,
    result: impl FnOnce(&[TokenStream]) -> TokenStream,
) -> TokenStream {
    let f = ident(name);
    let d = doc(text);
    let fn_args = arg_list(args, &b.used_args);
    let stmts = &b.stmts;
    let helpers = &b.helpers;
    let value = result(&b.outputs);
    quote! {
        #d
        #[allow(non_snake_case, clippy::all)]
        pub fn #f(#(#fn_args),*) -> #ret {
            #(#stmts)*
            #value
        }
        #(#helpers)*
    }
}

fn error_type() -> TokenStream {
    quote! {
        #[doc = "Why an emitted function could not produce a value."]
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum EvalError {
            #[doc = "The equations are singular at time `t`: `condition` vanishes (its value, or the pivot column for the mass matrix)."]
            Singular { t: f64, condition: &'static str, value: f64 },
            #[doc = "Output `index` is not a finite number at time `t`."]
            NonFinite { t: f64, index: usize },
            #[doc = "A state violates `constraint`: its residual exceeds the tolerance."]
            ConstraintViolated { constraint: &'static str, residual: f64, tolerance: f64 },
        }
        impl core::fmt::Display for EvalError {
            fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
                match self {
                    EvalError::Singular { t, condition, value } => write!(f, "singular configuration at t = {t}: {condition} (value {value:e})"),
                    EvalError::NonFinite { t, index } => write!(f, "non-finite value in output {index} at t = {t}"),
                    EvalError::ConstraintViolated { constraint, residual, tolerance } => write!(f, "constraint `{constraint}` is violated: residual {residual:e} exceeds {tolerance:e}"),
                }
            }
        }
        impl std::error::Error for EvalError {}
    }
}

fn solve_dense() -> TokenStream {
    quote! {
        #[doc = "Solves `a x = b` in place by Gaussian elimination with partial pivoting; `Err(column)` when a pivot is below `PIVOT_TOLERANCE` times the largest entry."]
        fn solve_dense<const N: usize>(a: &mut [[f64; N]; N], b: &mut [f64; N]) -> Result<(), usize> {
            let mut scale = 0.0f64;
            for row in a.iter() {
                for x in row.iter() {
                    scale = scale.max(x.abs());
                }
            }
            for c in 0..N {
                let mut p = c;
                for r in c + 1..N {
                    if a[r][c].abs() > a[p][c].abs() {
                        p = r;
                    }
                }
                if !(a[p][c].abs() > PIVOT_TOLERANCE * scale) {
                    return Err(c);
                }
                a.swap(c, p);
                b.swap(c, p);
                for r in c + 1..N {
                    let f = a[r][c] / a[c][c];
                    for k in c + 1..N {
                        a[r][k] -= f * a[c][k];
                    }
                    b[r] -= f * b[c];
                }
            }
            for r in (0..N).rev() {
                let mut s = b[r];
                for k in r + 1..N {
                    s -= a[r][k] * b[k];
                }
                b[r] = s / a[r][r];
            }
            Ok(())
        }
    }
}
