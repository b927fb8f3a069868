//! The generated module: sizes, `Params`, the seam's `Failure`, the shared functions (energy, work
//! rate, momenta, constraint residuals) and one submodule per formulation ([`super::form`]).
//! It only emits: everything it writes comes from one [`Derivation`].

use super::from_mechanics::FromMechanics;
use super::function::{Arg, Body, Input, arg_list, body_with_definitions, ident};
use super::lower::literal;
use super::names::Names;
use super::prepare::Preparer;
use super::reuse::{Bodies, Signature};
use super::solvers::PIVOT_TOLERANCE;
use super::splice::Splices;
use super::syntax::{doc, usize_lit};
use super::{Function, FunctionCost, Generated, Options, Parameters, Summary};
use crate::formulation::mechanics::Quantities;
use crate::formulation::{self, Equations};
use crate::model::{ErrorKind, Model, ModelError};
use crate::symbolic::number::rat_from_f64;
use crate::symbolic::{Expr, Symbol};
use proc_macro2::{Literal, TokenStream};
use quote::quote;
use std::collections::HashMap;

/// Absolute size below which a singular factor of `[Y; M'; a]` counts as zero.
pub(crate) const SINGULAR_TOLERANCE: f64 = 1e-12;
/// Relative size of a constraint residual, against its triangle-inequality magnitude, above
/// which initial velocities are rejected.
pub(crate) const CONSTRAINT_TOLERANCE: f64 = 1e-9;

/// The symbols of a model, with their identifiers in emitted code.
pub(super) struct SymbolNames {
    pub coordinates: Vec<String>,
    pub velocities: Vec<String>,
    pub parameters: Vec<String>,
    /// Every state or input symbol (coordinates, rates, quasi-velocities, momenta) to its
    /// identifier.
    pub of: HashMap<Symbol, String>,
}

/// Writes a module's items, in three parts by role: what the module is written for
/// ([`Scope`]), what builds and shares the function bodies ([`Workshop`]), and what has been
/// written ([`Record`]). Its methods are in this file (the module's own functions), `form.rs`
/// (a formulation's submodule) and `jacobian.rs` (its exact Jacobians).
pub(super) struct Emitter<'a> {
    pub scope: Scope<'a>,
    pub workshop: Workshop,
    pub record: Record,
}

/// What every function of a module is written for; fixed once the emitter is made.
pub(super) struct Scope<'a> {
    pub model: &'a Model,
    pub options: &'a Options,
    pub names: SymbolNames,
    /// The seam crate's path in emitted code.
    pub seam: syn::Path,
    /// The states end with the work integral `W`.
    pub work: bool,
    /// Number of ignorable coordinates (the length of `g_i`).
    pub num_ignorable: usize,
}

/// What builds the function bodies, with what it shares between them.
pub(super) struct Workshop {
    pub prep: Preparer,
    /// Horner forms, shared by every function of the module.
    pub horner: rustc_hash::FxHashMap<Expr, Expr>,
    /// The bodies built so far, for functions with the same outputs.
    pub bodies: Bodies,
    /// The bodies' syntax trees, placed into the parsed module at the end.
    pub splices: Splices,
}

/// What has been written: for the summary and for in-process evaluation.
#[derive(Default)]
pub(super) struct Record {
    pub functions: Vec<FunctionCost>,
    /// Per emitted formulation: name, states, equations, and how its `rhs` solves (the plan it
    /// was emitted with, described once).
    pub forms: Vec<(String, usize, usize, String)>,
    /// Each function's tape, by name, when [`Options::tapes`] asks for them.
    pub tapes: Option<HashMap<String, super::tape::Tape>>,
    /// Each formulation's shape around its tapes (in-process evaluation).
    pub shapes: Vec<super::program::FormShape>,
}

/// A [`Body`] whose trees wait in the module's [`Splices`]: each field holds placeholders to
/// write into `quote!` where the trees go.
pub(super) struct Placed {
    pub stmts: TokenStream,
    pub outputs: Vec<TokenStream>,
    pub helpers: TokenStream,
    pub used_args: std::collections::BTreeSet<usize>,
}

/// Part of the module, printed, with what its functions cost: what one [`Emission`] wrote.
pub(crate) struct Part {
    text: String,
    /// What the budgets cut on the thread that wrote it.
    cuts: crate::symbolic::report::Cuts,
    functions: Vec<FunctionCost>,
    forms: Vec<(String, usize, usize, String)>,
    /// In-process evaluation: the part's tapes and formulation shapes, and (the head's part)
    /// the module's description.
    program: super::program::Program,
}

/// The formulations whose bodies one emitter shares ([`Bodies`]), from the requested kinds
/// alone (in the order they are derived): the classical three together (Maggi's and Kane's
/// `rhs` are Lagrange's up to the speeds' names on many models), the reduced form apart (keeping
/// Kane's bodies for it costs memory: [`super::reuse`]). Whatever emits the groups, on
/// whichever thread, each group's bytes are the same.
///
/// ```text
/// [Lagrange, Maggi, Kane, ReducedVolterra] -> [[Lagrange, Maggi, Kane], [ReducedVolterra]]
/// ```
pub(crate) fn reuse_groups(kinds: &[seam::FormulationKind]) -> Vec<Vec<seam::FormulationKind>> {
    let (reduced, classical): (Vec<_>, Vec<_>) = kinds.iter().partition(|k| **k == seam::FormulationKind::ReducedVolterra);
    [classical, reduced].into_iter().filter(|g| !g.is_empty()).collect()
}

/// Writes one part of a module: the head (sizes, `Params`, the shared functions, the events),
/// the formulations of one reuse group ([`reuse_groups`]) as their equations come, `model()`;
/// each item printed as it is emitted (the items of one file, printed in order, are the items
/// printed one by one). It derives nothing: what it writes comes from the mechanics, the
/// ignorable coordinates and each formulation's [`Equations`].
pub(crate) struct Emission<'a> {
    em: Emitter<'a>,
    shared: FromMechanics,
    text: String,
    /// The head is in this part (the program's description goes with it).
    head: bool,
}

impl<'a> Emission<'a> {
    /// An emission of the formulations `group` (in order) of `model`, whose mechanics are `mech`
    /// and ignorable coordinates `ignorable`.
    pub(crate) fn new(
        model: &'a Model,
        options: &'a Options,
        mech: &Quantities,
        ignorable: &[usize],
        group: Vec<seam::FormulationKind>,
    ) -> Result<Emission<'a>, ModelError> {
        let shared = FromMechanics::new(mech, ignorable, &model.velocities, model.t);
        let mut em = Emitter::new(model, options, seam_path(model, options)?, &shared);
        em.workshop.bodies = Bodies::new(group);
        Ok(Emission { em, shared, text: String::new(), head: false })
    }

    /// The module's head: sizes, `Params`, the seam's `Failure`, the shared functions and the
    /// events. The dense solves are `seam::solve`'s, called by the formulations: written once,
    /// not carried by every module.
    pub(crate) fn head(&mut self) -> Result<(), ModelError> {
        let (em, shared) = (&mut self.em, &self.shared);
        let mut items = vec![em.header(shared), em.params(), super::seam::failure_import(&em.scope.seam)];
        for f in &em.scope.options.functions {
            items.extend(em.shared_function(*f, shared)?);
        }
        if !em.scope.model.events.is_empty() {
            items.extend(em.event_functions()?);
        }
        self.text += &em.print(items)?;
        self.head = true;
        Ok(())
    }

    /// One formulation's submodule.
    pub(crate) fn form(&mut self, eqs: &Equations) -> Result<(), ModelError> {
        let item = self.em.form(eqs, &self.shared)?;
        self.text += &self.em.print(vec![item])?;
        Ok(())
    }

    /// `model()`, listing the formulations `names`.
    pub(crate) fn model_fn(&mut self, names: Vec<String>) -> Result<(), ModelError> {
        let em = &mut self.em;
        let module_name = em.scope.options.module_name.clone().unwrap_or_else(|| em.scope.model.name.clone());
        let item = super::seam::model_fn(&super::seam::SeamParts {
            seam: &em.scope.seam,
            module: &module_name,
            formulations: names,
            functions: &em.scope.options.functions,
            has_initial: em.scope.model.initial.is_some(),
            has_run: em.scope.model.simulation.is_some(),
            has_events: !em.scope.model.events.is_empty(),
            has_gimbals: !em.scope.model.gimbals().is_empty(),
            has_inputs: !em.scope.model.inputs.is_empty(),
        });
        self.text += &em.print(vec![item])?;
        Ok(())
    }

    /// What this emission wrote, with what the budgets cut on this thread.
    pub(crate) fn finish(mut self) -> Part {
        let em = &mut self.em;
        let mut program = super::program::Program {
            description: Default::default(),
            tapes: em.record.tapes.take().unwrap_or_default(),
            forms: std::mem::take(&mut em.record.shapes),
        };
        if self.head && em.scope.options.tapes {
            program.description = em.description(&self.shared);
        }
        Part {
            text: self.text,
            cuts: crate::symbolic::report::take(),
            functions: std::mem::take(&mut em.record.functions),
            forms: std::mem::take(&mut em.record.forms),
            program,
        }
    }
}

/// The module of `model` from its parts (in module order, the head's first) and what its
/// derivation `d` found; `derive_time` and `emit_time` go to the summary.
pub(crate) fn module(model: &Model, options: &Options, d: &formulation::Derivation, parts: Vec<Part>, work: super::Work) -> Generated {
    let mut cuts = d.cuts.clone();
    let mut functions = Vec::new();
    let mut forms: Vec<(String, usize, usize, String)> = Vec::new();
    let mut text = String::new();
    let mut program = super::program::Program::default();
    for (k, part) in parts.into_iter().enumerate() {
        cuts.merge(part.cuts);
        functions.extend(part.functions);
        forms.extend(part.forms);
        text += &part.text;
        if k == 0 {
            program.description = part.program.description;
        }
        program.tapes.extend(part.program.tapes);
        program.forms.extend(part.program.forms);
    }
    program.description.module = options.module_name.clone().unwrap_or_else(|| model.name.clone());
    let formulations = forms.iter().map(|(name, states, eqs, _)| (name.clone(), *states, *eqs)).collect();
    let solves = forms.into_iter().map(|(name, _, _, how)| (name, how)).collect();
    let code = if options.source {
        format!("// Generated by `generator` from {} ({}). Do not edit: regenerate.\n\n{text}", one_line(&model_file_name(model)), one_line(&model.name))
    } else {
        String::new()
    };
    let summary = Summary {
        model: model.name.clone(),
        m: d.mechanics.m,
        r: d.mechanics.r,
        p: d.mechanics.p,
        s: d.ignorable.len(),
        formulations,
        eliminations: d.equations.iter().map(|e| (e.name().to_string(), e.elimination.to_string())).collect(),
        solves,
        functions,
        simplifier: d.mechanics.tidy.report(),
        cuts,
        stages: d.stages.clone(),
        derive_time: work.derive_time,
        emit_time: work.emit_time,
        nodes: work.nodes,
    };
    Generated { code, summary, program: options.tapes.then_some(program) }
}

/// Each formulation's solve and assembly of its right-hand side, `(name, description)`, as the
/// summary describes them ([`super::assembly`]): the same bodies a module compares, built by
/// one emitter per reuse group ([`reuse_groups`]), so that a body reused there is reused here.
pub(crate) fn assemblies(model: &Model, d: &formulation::Derivation, options: &Options) -> Result<Vec<(String, String)>, ModelError> {
    let shared = FromMechanics::new(&d.mechanics, &d.ignorable, &model.velocities, model.t);
    let kinds: Vec<_> = d.equations.iter().map(|e| e.kind).collect();
    let mut out = Vec::new();
    for group in reuse_groups(&kinds) {
        let mut em = Emitter::new(model, options, seam_path(model, options)?, &shared);
        em.workshop.bodies = Bodies::new(group.clone());
        let forms: Vec<&Equations> = d.equations.iter().filter(|e| group.contains(&e.kind)).collect();
        for (k, f) in forms.iter().enumerate() {
            let later = &forms[k + 1..];
            em.start(f);
            // Without a recursion there is nothing to compare; the dense body is built only
            // where a later formulation of the same group takes it under its speeds' names.
            let tree = |g: &formulation::Equations| g.recursion.is_some() || g.articulated.is_some();
            let feeds = || f.kind.speeds() == seam::Speeds::Rates && later.iter().any(|g| tree(g) && !em.speeds_as_rates(g).is_empty());
            let description = if !tree(f) && !feeds() {
                super::assembly::summary_line(&super::ldl::Solve::for_equations(f), "assembly: dense entries")
            } else {
                let checks = em.runtime_factors(f);
                let chosen = em.assembly(f, &shared, &checks)?;
                super::assembly::summary_line(&chosen.solve, &chosen.description)
            };
            out.push((f.name().to_string(), description));
        }
    }
    Ok(out)
}

/// The seam crate's path in emitted code, from the options (set by a library caller: the
/// command line and the builder check theirs first, and name the option).
fn seam_path(model: &Model, options: &Options) -> Result<syn::Path, ModelError> {
    super::parse_seam_path(&options.seam_path)
        .map_err(|message| ModelError::in_place(ErrorKind::Emission, &model.file, "options.seam_path", message, super::SEAM_PATH_HELP.into()))
}

/// The symbols' identifiers in emitted code (a model's names, made unique and valid).
fn symbol_names(model: &Model, shared: &FromMechanics) -> SymbolNames {
    let mut names = Names::new();
    let parameters = model.parameters.iter().map(|(s, _)| names.fresh(&s.name())).collect();
    let coordinates: Vec<String> = model.coordinates.iter().map(|s| names.fresh(&s.name())).collect();
    let velocities: Vec<String> = model.coordinates.iter().map(|s| names.fresh(&format!("{}_dot", s.name()))).collect();
    let mut of: HashMap<Symbol, String> = HashMap::new();
    for (j, q) in model.coordinates.iter().enumerate() {
        of.insert(*q, coordinates[j].clone());
        of.insert(model.velocities[j], velocities[j].clone());
    }
    for &j in &shared.ignorable {
        let g = formulation::volterra::momentum_symbol(model, j);
        of.insert(g, names.fresh(&g.name()));
    }
    for k in 0..shared.p {
        let u = formulation::volterra::quasi_symbol(k);
        of.insert(u, names.fresh(&u.name()));
    }
    SymbolNames { coordinates, velocities, parameters, of }
}

impl<'a> Emitter<'a> {
    fn new(model: &'a Model, options: &'a Options, seam: syn::Path, shared: &FromMechanics) -> Emitter<'a> {
        let mut prep = Preparer::new(model, options.parameters == Parameters::Baked);
        // Applied non-potential forces can do work (Q not identically zero once prepared): every
        // formulation then carries the work integral W as its last state.
        // So can moving constraints (their power joins W after each solve).
        let work = !prep.prepare(shared.power).is_zero() || shared.energy_balance == seam::EnergyBalance::MovingConstraints;
        Emitter {
            scope: Scope { model, options, names: symbol_names(model, shared), seam, work, num_ignorable: shared.ignorable.len() },
            workshop: Workshop { prep, horner: Default::default(), bodies: Bodies::default(), splices: Splices::default() },
            record: Record { tapes: options.tapes.then(HashMap::new), ..Record::default() },
        }
    }

    /// `items` as a formatted file, the bodies' trees in their places (nothing where the options
    /// want no source).
    fn print(&mut self, items: Vec<TokenStream>) -> Result<String, ModelError> {
        let model = self.scope.model;
        if !self.scope.options.source {
            self.workshop.splices = Splices::default();
            return Ok(String::new());
        }
        let tokens = quote!(#(#items)*);
        let mut file: syn::File = syn::parse2(tokens)
            .map_err(|e| model.error(ErrorKind::Emission, "emit", "emit", format!("internal: emitted tokens do not parse: {e}"), String::new()))?;
        std::mem::take(&mut self.workshop.splices)
            .apply(&mut file)
            .map_err(|e| model.error(ErrorKind::Emission, "emit", "emit", e.to_string(), String::new()))?;
        Ok(prettyplease::unparse(&file))
    }
}

/// The first number in `source` whose magnitude is beyond `1e150` or below `1e-150` (but not
/// zero): products of two such numbers leave the range of `f64`.
///
/// ```ignore
/// assert_eq!(extreme_literal("m: \"2*1e200\""), Some(6..11));
/// ```
fn extreme_literal(source: &str) -> Option<std::ops::Range<usize>> {
    let bytes = source.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        let starts = bytes[i].is_ascii_digit() && (i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_' || bytes[i - 1] == b'.'));
        if !starts {
            i += 1;
            continue;
        }
        let start = i;
        while i < bytes.len() && (bytes[i].is_ascii_digit() || bytes[i] == b'.') {
            i += 1;
        }
        if i < bytes.len() && (bytes[i] == b'e' || bytes[i] == b'E') {
            let mut j = i + 1;
            if j < bytes.len() && (bytes[j] == b'-' || bytes[j] == b'+') {
                j += 1;
            }
            if j < bytes.len() && bytes[j].is_ascii_digit() {
                i = j;
                while i < bytes.len() && bytes[i].is_ascii_digit() {
                    i += 1;
                }
            }
        }
        let text = &source[start..i];
        let digits = text.split(['e', 'E']).next().unwrap_or("").trim_start_matches('0').trim_start_matches('.').len();
        let exponent: i64 = text.split(['e', 'E']).nth(1).and_then(|x| x.parse().ok()).unwrap_or(0);
        let magnitude = exponent + digits as i64;
        let nonzero = text.split(['e', 'E']).next().is_some_and(|m| m.chars().any(|c| ('1'..='9').contains(&c)));
        if nonzero && !(-150..=150).contains(&magnitude) {
            return Some(start..i);
        }
    }
    None
}

/// The model file's name without directories, so output does not depend on where it was run.
fn model_file_name(model: &Model) -> String {
    std::path::Path::new(&model.file).file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default()
}

/// `text` fit for a `//` comment: each control character (a line break in a file name would
/// end the comment and let the rest through as code) written as its escape, `\n`, `\u{1b}`.
pub(super) fn one_line(text: &str) -> String {
    files::printable(text)
}

pub(super) fn f64_lit(x: f64) -> TokenStream {
    match rat_from_f64(x) {
        Some(r) => literal(&r).unwrap_or_else(|_| quote!(f64::NAN)),
        None => quote!(f64::NAN),
    }
}

impl Emitter<'_> {
    pub(super) fn emission_error(&self, what: &str, e: impl std::fmt::Display) -> ModelError {
        let message = format!("cannot emit {what}: {e}");
        let source = &self.scope.model.source;
        // A constant beyond f64 comes from the model's own extreme numbers: point at the first.
        if message.contains("is not a finite f64")
            && let Some(span) = extreme_literal(source)
        {
            let place = crate::model::spans::Spans::new(source).path_at(span.start).unwrap_or_default();
            return ModelError::at(
                ErrorKind::Emission,
                &self.scope.model.file,
                source,
                Some(span),
                &place,
                message,
                "scale the model (other units) so that its numbers and their products stay within about 1e-150 to 1e150".into(),
            );
        }
        self.scope.model.error(
            ErrorKind::Emission,
            "emit",
            "emit",
            message,
            "check the model's expressions for numbers too large for f64 and functions without a definition".into(),
        )
    }

    fn header(&self, m: &FromMechanics) -> TokenStream {
        let model = self.scope.model;
        let name = &model.name;
        let description = doc(&format!("Model `{}`: {}", model.name, model.description));
        let (nm, nr, np, ns, nh) =
            (usize_lit(model.m()), usize_lit(m.constraint_names.len()), usize_lit(m.p), usize_lit(m.ignorable.len()), usize_lit(m.positions.len()));
        let coords: Vec<String> = model.coordinates.iter().map(|s| s.name()).collect();
        let cons = &m.constraint_names;
        let ign: Vec<Literal> = m.ignorable.iter().map(|&i| usize_lit(i)).collect();
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
        let paper = model.simulation.as_ref().is_some_and(|s| s.paper);
        let balance = match m.energy_balance {
            seam::EnergyBalance::Energy => quote!(Energy),
            seam::EnergyBalance::Jacobi => quote!(Jacobi),
            seam::EnergyBalance::MovingConstraints => quote!(MovingConstraints),
        };
        let seam = &self.scope.seam;
        let balance_doc = m.energy_balance.describe();
        out.extend(quote! {
            #[doc = "What `energy` computes, and what its balance with the work state means:"]
            #[doc = #balance_doc]
            pub const ENERGY_BALANCE: #seam::EnergyBalance = #seam::EnergyBalance::#balance;
            #[doc = "True when the model file asks for the paper's integrator settings (DOPRI5, rtol 1e-3, atol 1e-6) by default."]
            pub const PAPER_SETTINGS: bool = #paper;
        });
        if !model.inputs.is_empty() {
            let ni = usize_lit(model.inputs.len());
            let idx = model.inputs.iter().map(|&i| usize_lit(i));
            out.extend(quote! {
                #[doc = "Number of inputs."]
                pub const NUM_INPUTS: usize = #ni;
                #[doc = "The inputs: indices into `Params::NAMES` of the parameters a run sets at every call (a controller's output, a time series)."]
                pub const INPUTS: [usize; NUM_INPUTS] = [#(#idx),*];
            });
        }
        let gimbals = model.gimbals();
        if !gimbals.is_empty() {
            let ng = usize_lit(gimbals.len());
            let frames = gimbals.iter().map(|(f, _)| f.as_str());
            let pitches = gimbals.iter().map(|(_, p)| usize_lit(*p));
            out.extend(quote! {
                #[doc = "Number of frames turned by ZYX Euler angles."]
                pub const NUM_GIMBALS: usize = #ng;
                #[doc = "The frames turned by ZYX Euler angles: the frame and the index of its pitch in `COORDINATES`, singular where the pitch's cosine vanishes (a run stops before it)."]
                pub const GIMBALS: [(&str, usize); NUM_GIMBALS] = [#((#frames, #pitches)),*];
            });
        }
        if !model.events.is_empty() {
            let ne = usize_lit(model.events.len());
            let names = model.events.iter().map(|e| e.name.as_str());
            let directions = model.events.iter().map(|e| ident(&variant_name(e.direction.name())));
            let actions = model.events.iter().map(|e| ident(&variant_name(e.action.name())));
            out.extend(quote! {
                #[doc = "Number of events."]
                pub const NUM_EVENTS: usize = #ne;
                #[doc = "The events: name, the direction of the crossing that counts, and the action (see `event_values` and `event_resets`)."]
                pub const EVENTS: [(&str, #seam::Direction, #seam::EventAction); NUM_EVENTS] = [#((#names, #seam::Direction::#directions, #seam::EventAction::#actions)),*];
            });
        }
        out
    }

    /// `event_values` (each event's `g(t, q, q')`) and `event_resets` (each event's new `q` and
    /// `q'`, the values before it where its reset leaves them).
    fn event_functions(&mut self) -> Result<Vec<TokenStream>, ModelError> {
        let model = self.scope.model;
        let (args, inputs) = self.q_qdot_inputs(true);
        let values: Vec<Expr> = model.events.iter().map(|e| e.when).collect();
        let b = self.body("event_values", &values, &inputs, &args)?;
        let mut out = vec![simple_fn(
            "event_values",
            "The event functions `g(t, q, q')`, in the order of `EVENTS`: an event happens where its function crosses zero in its direction.",
            &args,
            &b,
            quote!([f64; NUM_EVENTS]),
            |o| quote!([#(#o),*]),
        )];
        let mut resets = Vec::new();
        for e in &model.events {
            resets.extend(e.reset_q.iter().zip(&model.coordinates).map(|(r, q)| r.unwrap_or_else(|| q.expr())));
            resets.extend(e.reset_qdot.iter().zip(&model.velocities).map(|(r, v)| r.unwrap_or_else(|| v.expr())));
        }
        let b = self.body("event_resets", &resets, &inputs, &args)?;
        let n = usize_lit(resets.len());
        out.push(simple_fn(
            "event_resets",
            "Each event's reset map, in the order of `EVENTS`: the new `q` then the new `q'` (the values before it where the event does not set them), `2 NUM_COORDINATES` entries per event.",
            &args,
            &b,
            quote!([f64; #n]),
            |o| quote!([#(#o),*]),
        ));
        Ok(out)
    }

    /// What `model()` says of the module, for in-process evaluation (its `module` name is set
    /// by [`generate`]).
    fn description(&self, m: &FromMechanics) -> super::program::Description {
        let model = self.scope.model;
        let baked = self.scope.options.parameters == Parameters::Baked;
        super::program::Description {
            module: String::new(),
            name: model.name.clone(),
            coordinates: model.coordinates.iter().map(|s| s.name()).collect(),
            constraints: m.constraint_names.clone(),
            ignorable: m.ignorable.clone(),
            holonomic_names: m.holonomic_names.clone(),
            parameter_names: if baked { vec![] } else { model.parameters.iter().map(|(s, _)| s.name()).collect() },
            inputs: model.inputs.clone(),
            default_params: if baked { vec![] } else { model.parameters.iter().map(|(_, v)| *v).collect() },
            initial: model.initial.clone(),
            run: model.simulation.as_ref().map(|s| (s.t_start, s.t_end, s.dt_out)),
            paper_settings: model.simulation.as_ref().is_some_and(|s| s.paper),
            energy_balance: m.energy_balance,
            events: model.events.iter().map(|e| seam::Event { name: e.name.clone(), direction: e.direction, action: e.action }).collect(),
            gimbals: model.gimbals().into_iter().map(|(frame, pitch)| seam::Gimbal { frame, pitch }).collect(),
        }
    }

    fn params(&self) -> TokenStream {
        let baked = self.scope.options.parameters == Parameters::Baked;
        let model = self.scope.model;
        let k = if baked { 0 } else { model.parameters.len() };
        let kl = usize_lit(k);
        let fields: Vec<proc_macro2::Ident> = if baked { vec![] } else { self.scope.names.parameters.iter().map(|n| ident(n)).collect() };
        let names: Vec<String> = if baked { vec![] } else { model.parameters.iter().map(|(s, _)| s.name()).collect() };
        let values: Vec<TokenStream> = if baked { vec![] } else { model.parameters.iter().map(|(_, v)| f64_lit(*v)).collect() };
        let docs: Vec<TokenStream> = names.iter().zip(&values).map(|(n, v)| doc(&format!("`{n}` (model value {v})"))).collect();
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
                    Params::DEFAULT
                }
            }
            #[doc = "The model file's parameter values, in the order of `Params::NAMES`."]
            pub const DEFAULT_PARAMS: [f64; #kl] = Params::DEFAULT.values();
            impl Params {
                #[doc = "The values from the model file."]
                pub const DEFAULT: Params = Params { #(#fields: #values,)* };
                #[doc = "Parameter names, in the order of `values` and `from_values`."]
                pub const NAMES: [&'static str; #kl] = [#(#names),*];
                #[doc = "The parameters as an array, in the order of `NAMES`."]
                pub const fn values(&self) -> [f64; #kl] {
                    [#(self.#fields),*]
                }
                #[doc = "Parameters from an array in the order of `NAMES`."]
                pub const fn from_values(#values_arg: &[f64; #kl]) -> Self {
                    Params { #(#fields: values[#idx],)* }
                }
            }
        }
    }

    /// Inputs for the parameters (runtime mode only), read from argument `arg`.
    pub(super) fn parameter_inputs(&self, arg: usize) -> Vec<Input> {
        if self.scope.options.parameters == Parameters::Baked {
            return vec![];
        }
        self.scope
            .model
            .parameters
            .iter()
            .zip(&self.scope.names.parameters)
            .map(|((s, _), n)| {
                let f = ident(n);
                Input::new(*s, n, arg, quote!(params.#f))
            })
            .collect()
    }

    pub(super) fn time_input(&self) -> Input {
        Input::new(self.scope.model.t, "t", 0, TokenStream::new())
    }

    /// Inputs `t`, `q[j]`, `qdot[j]`, `params`: the signature of the shared functions.
    pub(super) fn q_qdot_inputs(&self, with_velocities: bool) -> (Vec<Arg>, Vec<Input>) {
        let mut args = vec![Arg::new("t", quote!(f64)), Arg::new("q", quote!(&[f64; NUM_COORDINATES]))];
        let mut inputs = vec![self.time_input()];
        for (j, (s, n)) in self.scope.model.coordinates.iter().zip(&self.scope.names.coordinates).enumerate() {
            let l = usize_lit(j);
            inputs.push(Input::new(*s, n, 1, quote!(q[#l])));
        }
        if with_velocities {
            args.push(Arg::new("qdot", quote!(&[f64; NUM_COORDINATES])));
            for (j, (s, n)) in self.scope.model.velocities.iter().zip(&self.scope.names.velocities).enumerate() {
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
    pub(super) fn body(&mut self, name: &str, outputs: &[Expr], inputs: &[Input], args: &[Arg]) -> Result<Placed, ModelError> {
        let b = self.trial_body(name, &[], outputs, inputs, args)?;
        self.record_body(name, b, args)
    }

    /// The body for `outputs` reading the named intermediates `definitions`, built but not
    /// recorded (to compare assemblies).
    pub(super) fn trial_body(
        &mut self,
        name: &str,
        definitions: &[(Symbol, Expr)],
        outputs: &[Expr],
        inputs: &[Input],
        args: &[Arg],
    ) -> Result<Body, ModelError> {
        let prepared = self.workshop.prep.prepare_all(outputs);
        let defined: Vec<(Symbol, Expr)> = definitions.iter().map(|(s, e)| (*s, self.workshop.prep.prepare(*e))).collect();
        let short = name.rsplit("::").next().unwrap_or(name);
        let signature = Signature::new(short, &defined, inputs, args, self.scope.options.max_lets_per_function);
        if let Some(reused) = self.workshop.bodies.find(&signature, &prepared) {
            return reused.map_err(|e| self.emission_error(name, e));
        }
        let body = body_with_definitions(short, &defined, &prepared, inputs, args, self.scope.options.max_lets_per_function, &mut self.workshop.horner)
            .map_err(|e| self.emission_error(name, e))?;
        self.workshop.bodies.remember(signature, &prepared, &body);
        Ok(body)
    }

    /// Records `b`'s cost under `name` (and its tape), and places it.
    pub(super) fn record_body(&mut self, name: &str, b: Body, args: &[Arg]) -> Result<Placed, ModelError> {
        self.record.functions.push(FunctionCost { name: name.to_string(), lets: b.lets, ops: b.ops.clone(), solve: Default::default() });
        if self.record.tapes.is_some() {
            let tape = self.tape(&b, args).map_err(|e| self.emission_error(name, e))?;
            if let Some(tapes) = &mut self.record.tapes {
                tapes.insert(name.to_string(), tape);
            }
        }
        Ok(self.place(b))
    }

    /// `b` as a tape over `[t | params | g_i | state]` (functions of a state) or
    /// `[t | params | q | qdot]` (functions of the coordinates and rates), as
    /// [`crate::eval::model`] packs them. A split body's helpers are read in call order.
    fn tape(&self, b: &Body, args: &[Arg]) -> Result<super::tape::Tape, super::tape::TapeError> {
        use super::tape::{Slots, compile};
        let m = self.scope.model.m();
        let np = if self.scope.options.parameters == Parameters::Baked { 0 } else { self.scope.model.parameters.len() };
        let layout: Vec<(&str, usize)> = if args.iter().any(|a| a.name == "state") {
            vec![("t", 1), ("params", np), ("g_i", self.scope.num_ignorable), ("state", usize::MAX >> 8)]
        } else {
            vec![("t", 1), ("params", np), ("q", m), ("qdot", m)]
        };
        let slots = Slots::new(&layout).with_fields(&self.scope.names.parameters);
        // The statements read where they are: cloning them (a Jacobian's trees run to
        // hundreds of thousands of nodes) took 6 % of `multibody linearize bicycle
        // --formulation kane` and 95 of its 570 MB.
        let own = b.stmts.iter().filter(|s| match s {
            // The split form's scratch array and its helpers' calls: the helpers' own
            // statements stand in for them.
            syn::Stmt::Local(l) => !matches!(&l.pat, syn::Pat::Ident(p) if p.mutability.is_some()),
            syn::Stmt::Expr(syn::Expr::Call(_), _) => false,
            _ => true,
        });
        let helpers = b.helpers.iter().flat_map(|h| match h {
            syn::Item::Fn(f) => f.block.stmts.as_slice(),
            _ => &[],
        });
        compile(own.chain(helpers), &b.outputs, &slots)
    }

    /// True when the formulations get `parameter_jacobian`: asked for, and the parameters
    /// are `Params` fields (not baked) and there are some.
    pub(super) fn emits_parameter_jacobian(&self) -> bool {
        self.scope.options.parameter_jacobian && self.scope.options.parameters == Parameters::Runtime && !self.scope.model.parameters.is_empty()
    }

    /// Leaves `b`'s trees in the splices, returning their placeholders.
    fn place(&mut self, b: Body) -> Placed {
        let Body { mut stmts, mut outputs, mut helpers, used_args, .. } = b;
        if self.scope.options.fma {
            super::fma::fuse_stmts(&mut stmts);
            outputs.iter_mut().for_each(super::fma::fuse);
            helpers.iter_mut().for_each(super::fma::fuse_item);
        }
        Placed {
            stmts: self.workshop.splices.stmts(stmts),
            outputs: outputs.into_iter().map(|e| self.workshop.splices.expr(e)).collect(),
            helpers: self.workshop.splices.items(helpers),
            used_args,
        }
    }

    fn shared_function(&mut self, f: Function, m: &FromMechanics) -> Result<Vec<TokenStream>, ModelError> {
        let mut out = Vec::new();
        match f {
            Function::Energy => {
                let (args, inputs) = self.q_qdot_inputs(true);
                let b = self.body("energy", &[m.energy], &inputs, &args)?;
                out.push(simple_fn("energy", "Total energy T + V.", &args, &b, quote!(f64), |o| quote!(#(#o)*)));
            }
            Function::WorkRate => {
                let (args, inputs) = self.q_qdot_inputs(true);
                let b = self.body("work_rate", &[m.power], &inputs, &args)?;
                let doc = if m.energy_balance == seam::EnergyBalance::MovingConstraints {
                    "The part of the work integral's rate (Eq. 80) that `q` and `q'` give: `Q . q' - dL/dt`, the applied non-potential forces' power and the explicit time dependence. The moving constraints' power `R . q'` needs the accelerations: each formulation's `rhs` adds it after its solve."
                } else {
                    "The rate of the work integral (Eq. 80) the energy function balances: `Q . q' - dL/dt`, the applied non-potential forces' power and the explicit time dependence."
                };
                out.push(simple_fn("work_rate", doc, &args, &b, quote!(f64), |o| quote!(#(#o)*)));
            }
            Function::Momenta => {
                let (args, inputs) = self.q_qdot_inputs(true);
                let b = self.body("momenta", &m.momenta, &inputs, &args)?;
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
                let b = self.body("constraint_residuals", &m.velocity_residuals, &inputs, &args)?;
                out.push(simple_fn(
                    "constraint_residuals",
                    "Velocity-level constraint residuals `a q' + b` (zero on admissible motions).",
                    &args,
                    &b,
                    quote!([f64; NUM_CONSTRAINTS]),
                    |o| quote!([#(#o),*]),
                ));
                let (args, inputs) = self.q_qdot_inputs(false);
                let b = self.body("position_residuals", &m.positions, &inputs, &args)?;
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
}

/// `rising` as `Rising`: a seam enum's variant from its name.
fn variant_name(name: &str) -> String {
    let mut c = name.chars();
    c.next().map(|f| f.to_ascii_uppercase().to_string() + c.as_str()).unwrap_or_default()
}

fn simple_fn(name: &str, text: &str, args: &[Arg], b: &Placed, ret: TokenStream, result: impl FnOnce(&[TokenStream]) -> TokenStream) -> TokenStream {
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
            #stmts
            #value
        }
        #helpers
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn comments_hold_one_line_whatever_the_text() {
        assert_eq!(super::one_line("a\nfn evil() {}\r\u{1b}"), "a\\nfn evil() {}\\r\\u{1b}");
        assert_eq!(super::one_line("cart_pendulum.ron"), "cart_pendulum.ron");
    }

    #[test]
    fn the_classical_formulations_share_bodies_and_the_reduced_form_keeps_its_own() {
        use seam::FormulationKind::{Kane, Lagrange, Maggi, ReducedVolterra};
        assert_eq!(super::reuse_groups(&[Lagrange, Maggi, Kane, ReducedVolterra]), vec![vec![Lagrange, Maggi, Kane], vec![ReducedVolterra]]);
        assert_eq!(super::reuse_groups(&[Lagrange, Kane]), vec![vec![Lagrange, Kane]]);
        assert_eq!(super::reuse_groups(&[ReducedVolterra]), vec![vec![ReducedVolterra]]);
        assert_eq!(super::reuse_groups(&[]), Vec::<Vec<seam::FormulationKind>>::new());
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn assemblies_example() {
        use crate::{emit, formulation};
        let model = crate::model::load("../models/three_body.ron").unwrap();
        let d = formulation::derive(&model, &formulation::Request::all()).unwrap();
        let chosen = emit::assemblies(&model, &d, &emit::Options::from_model(&model)).unwrap();
        assert_eq!(chosen.len(), 4);
        assert!(chosen.iter().all(|(_, how)| how.contains("; assembly: ")));
    }
}
