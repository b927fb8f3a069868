//! The bodies a module has built, so that a function whose outputs are another's (in any order,
//! beside constants, up to the names of the speeds) takes that body instead of building it
//! again. On a model without constraints, Maggi's `rhs` is Lagrange's with the speeds
//! reordered and `W`, `c` constant, and their `initial_state` and `velocities` coincide too;
//! where Kane's quasi-velocities are the rates in another order (`q' = u` permuted, the
//! default on the chains), Kane's `rhs` is Lagrange's with each rate renamed to its
//! quasi-velocity and read from that one's place in Kane's state. Building a body (pair
//! sharing, sum factoring, Horner forms, lowering) is the emission's main cost: on the planar
//! chain of 20 rods in absolute angles, Maggi's and Kane's `rhs` are each a fifth of the CPU.
//!
//! The speeds are compared as the rates they stand for ([`speeds_as_rates`]); a body built
//! under other names is renamed (its bindings rebound to the new places) unless a new name is
//! already something else in it. A formulation's bodies are kept while a formulation follows in
//! the same emitter. Measured on the 50-link pendulum on a cart (command line, peak memory):
//! about 555 MB, as before Kane reused (560 MB without any reuse; 790 MB when Kane's were kept
//! for a reduced form emitted on the other thread).

use super::function::{Arg, Body, Input};
use super::lower::{LowerError, lower};
use crate::symbolic::{Expr, Symbol};
use proc_macro2::Ident;
use rustc_hash::{FxHashMap as HashMap, FxHashSet as HashSet};
use seam::FormulationKind;
use std::collections::HashMap as StdHashMap;
use syn::visit_mut::VisitMut;

/// What a body is built from besides its outputs: two requests with the same signature and the
/// same non-constant outputs get the same statements.
#[derive(PartialEq, Eq, Debug)]
pub struct Signature {
    name: String,
    definitions: Vec<(Symbol, Expr)>,
    inputs: Vec<(Symbol, String, usize, String)>,
    args: Vec<(String, String)>,
    max_lets: usize,
}

impl Signature {
    /// The signature of a body named `name` (helpers of a split body are named after it).
    pub fn new(name: &str, definitions: &[(Symbol, Expr)], inputs: &[Input], args: &[Arg], max_lets: usize) -> Signature {
        Signature {
            name: name.to_string(),
            definitions: definitions.to_vec(),
            inputs: inputs.iter().map(|i| (i.symbol, i.ident.clone(), i.arg, i.source.to_string())).collect(),
            args: args.iter().map(|a| (a.name.clone(), a.ty.to_string())).collect(),
            max_lets,
        }
    }
}

/// A signature with the speeds named as the coordinates' rates: what two bodies must share to
/// be one up to the names of their inputs.
#[derive(PartialEq, Eq)]
struct Key {
    name: String,
    definitions: Vec<(Symbol, Expr)>,
    /// Each input as (symbol, argument), sorted.
    inputs: Vec<(Symbol, usize)>,
    args: Vec<(String, String)>,
    max_lets: usize,
}

/// Bodies built so far, with the outputs they were built for.
#[derive(Default)]
pub struct Bodies {
    built: Vec<Built>,
    /// The formulations the emitter emits, in order.
    emits: Vec<FormulationKind>,
    /// The speeds of the formulation being emitted, named as the coordinates' rates where its
    /// speeds are those rates in another order (empty otherwise).
    relabel: StdHashMap<Symbol, Expr>,
    /// Whether the bodies built now are kept: a formulation follows in this emitter.
    keep: bool,
}

struct Built {
    key: Key,
    /// Each non-constant output (in the key's names): where it first appears, and how often.
    outputs: HashMap<Expr, (usize, usize)>,
    /// The identifier each input (in the key's names) is bound to, and its source.
    bindings: HashMap<Symbol, (String, String)>,
    body: Body,
}

/// Each non-constant output of `outputs`: its first position and its number of occurrences.
fn occurrences(outputs: &[Expr]) -> HashMap<Expr, (usize, usize)> {
    let mut seen: HashMap<Expr, (usize, usize)> = HashMap::default();
    for (k, e) in outputs.iter().enumerate().filter(|(_, e)| e.as_num().is_none()) {
        seen.entry(*e).or_insert((k, 0)).1 += 1;
    }
    seen
}

/// The speeds of a formulation whose rates `q'` are its speeds in another order
/// (`qdot[j]` is a speed for each coordinate `j`, each speed once), each named as the rate
/// `rates[j]` it stands for; empty where the speeds are anything else.
pub fn speeds_as_rates(speeds: &[Symbol], qdot: &[Expr], rates: &[Symbol]) -> StdHashMap<Symbol, Expr> {
    let mut relabel = StdHashMap::new();
    for (e, rate) in qdot.iter().zip(rates) {
        match e.as_sym() {
            Some(u) if speeds.contains(&u) && !relabel.contains_key(&u) => {
                relabel.insert(u, rate.expr());
            }
            _ => return StdHashMap::new(),
        }
    }
    if relabel.len() != speeds.len() || relabel.iter().all(|(u, r)| r.as_sym() == Some(*u)) {
        return StdHashMap::new();
    }
    relabel
}

impl Bodies {
    /// For an emitter that emits the formulations `emits`, in that order.
    pub fn new(emits: Vec<FormulationKind>) -> Bodies {
        Bodies { emits, ..Bodies::default() }
    }

    /// The formulation `kind` starts, its speeds named as rates by `relabel`
    /// ([`speeds_as_rates`]): its bodies are kept when a formulation follows it in this emitter.
    pub fn start(&mut self, kind: FormulationKind, relabel: StdHashMap<Symbol, Expr>) {
        self.relabel = relabel;
        self.keep = self.emits.iter().skip_while(|k| **k != kind).nth(1).is_some();
    }

    /// `signature` and `outputs` in the key's names: `None` where renaming would merge two inputs.
    fn key(&self, signature: &Signature, outputs: &[Expr]) -> Option<(Key, Vec<Expr>, HashMap<Symbol, usize>)> {
        let renamed = signature.inputs.iter().any(|(s, ..)| self.relabel.contains_key(s));
        let name = |s: Symbol| if renamed { self.relabel.get(&s).and_then(|e| e.as_sym()).unwrap_or(s) } else { s };
        let mut position: HashMap<Symbol, usize> = HashMap::default();
        for (k, (s, ..)) in signature.inputs.iter().enumerate() {
            if position.insert(name(*s), k).is_some() {
                return None;
            }
        }
        let mut inputs: Vec<(Symbol, usize)> = signature.inputs.iter().map(|(s, _, arg, _)| (name(*s), *arg)).collect();
        inputs.sort_by_key(|(s, arg)| (s.id, *arg));
        let (definitions, outputs) = if renamed {
            let all: Vec<Expr> = signature.definitions.iter().map(|(_, e)| *e).chain(outputs.iter().copied()).collect();
            let all = Expr::subs_all(&all, &self.relabel);
            let (d, o) = all.split_at(signature.definitions.len());
            (signature.definitions.iter().zip(d).map(|((s, _), e)| (*s, *e)).collect(), o.to_vec())
        } else {
            (signature.definitions.clone(), outputs.to_vec())
        };
        let key = Key { name: signature.name.clone(), definitions, inputs, args: signature.args.clone(), max_lets: signature.max_lets };
        Some((key, outputs, position))
    }

    /// A body built before with this signature and the same non-constant outputs, each as
    /// often, up to the names of the speeds (Kane's `rhs` is Lagrange's where the
    /// quasi-velocities are the rates): its statements, with the inputs bound as `signature`
    /// binds them, the outputs in `outputs`' order and the constants lowered here (they cost no
    /// operation, so the counts carry over).
    pub fn find(&self, signature: &Signature, outputs: &[Expr]) -> Option<Result<Body, LowerError>> {
        // Naming the outputs as rates costs a pass over them: only where a body of this name was built.
        let same_name = |b: &Built| b.key.name == signature.name && b.key.args == signature.args && b.key.max_lets == signature.max_lets;
        if !self.built.iter().any(same_name) {
            return None;
        }
        let (key, named, position) = self.key(signature, outputs)?;
        let wanted = occurrences(&named);
        let built = self
            .built
            .iter()
            .find(|b| b.key == key && b.outputs.len() == wanted.len() && wanted.iter().all(|(e, (_, n))| b.outputs.get(e).is_some_and(|(_, m)| m == n)))?;
        let mut rename: StdHashMap<String, (Ident, syn::Expr)> = StdHashMap::new();
        for (s, (old, old_source)) in &built.bindings {
            let (_, ident, _, source) = &signature.inputs[position[s]];
            if ident != old || source != old_source {
                // An input that is an argument itself (no source) keeps the argument's name.
                let source = syn::parse_str::<syn::Expr>(source).ok()?;
                rename.insert(old.clone(), (super::function::ident(ident), source));
            }
        }
        let mut body = built.body.clone();
        if !rename.is_empty() && !rename_inputs(&mut body, &rename) {
            return None;
        }
        let lowered = named
            .iter()
            .zip(outputs)
            .map(|(e, original)| match built.outputs.get(e) {
                Some(&(k, _)) => Ok(body.outputs[k].clone()),
                None => lower(*original, &|_| None, &|_| None).map(|(t, _)| t),
            })
            .collect::<Result<Vec<_>, _>>();
        Some(lowered.map(|outputs| Body { outputs, ..body }))
    }

    /// Keeps `body`, built under `signature` for `outputs`, if a later formulation may reuse it.
    pub fn remember(&mut self, signature: Signature, outputs: &[Expr], body: &Body) {
        if !self.keep {
            return;
        }
        let Some((key, named, position)) = self.key(&signature, outputs) else { return };
        let bindings = position.iter().map(|(s, &k)| (*s, (signature.inputs[k].1.clone(), signature.inputs[k].3.clone()))).collect();
        self.built.push(Built { key, outputs: occurrences(&named), bindings, body: body.clone() });
    }
}

/// Renames the inputs of `body` (`old identifier -> (new identifier, new source)`), in its
/// bindings and wherever they are read; false (and `body` unusable) where a new name is already
/// taken by something else in the body.
fn rename_inputs(body: &mut Body, rename: &StdHashMap<String, (Ident, syn::Expr)>) -> bool {
    let mut names = Names::default();
    visit_body(body, &mut names);
    let new: HashSet<String> = rename.values().map(|(i, _)| i.to_string()).collect();
    if names.0.iter().any(|n| new.contains(n) && !rename.contains_key(n)) {
        return false;
    }
    visit_body(body, &mut Renamer(rename));
    true
}

/// `visitor` over a body's statements, outputs and helpers.
fn visit_body(body: &mut Body, visitor: &mut impl VisitMut) {
    for s in &mut body.stmts {
        visitor.visit_stmt_mut(s);
    }
    for e in &mut body.outputs {
        visitor.visit_expr_mut(e);
    }
    for h in &mut body.helpers {
        visitor.visit_item_mut(h);
    }
}

/// Every identifier of a syntax tree (collected, not changed).
#[derive(Default)]
struct Names(HashSet<String>);

impl VisitMut for Names {
    fn visit_ident_mut(&mut self, i: &mut Ident) {
        self.0.insert(i.to_string());
    }
}

/// Renames variables (bindings and single-segment paths), and rebinds renamed inputs to their
/// new sources.
struct Renamer<'a>(&'a StdHashMap<String, (Ident, syn::Expr)>);

impl VisitMut for Renamer<'_> {
    fn visit_local_mut(&mut self, local: &mut syn::Local) {
        if let syn::Pat::Ident(p) = &mut local.pat
            && let Some((new, source)) = self.0.get(&p.ident.to_string())
        {
            p.ident = new.clone();
            if let Some(init) = &mut local.init {
                *init.expr = source.clone();
            }
            return;
        }
        syn::visit_mut::visit_local_mut(self, local);
    }

    fn visit_expr_path_mut(&mut self, e: &mut syn::ExprPath) {
        if e.qself.is_none()
            && e.path.leading_colon.is_none()
            && e.path.segments.len() == 1
            && let Some((new, _)) = self.0.get(&e.path.segments[0].ident.to_string())
        {
            e.path.segments[0].ident = new.clone();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::function::body_with_definitions;
    use super::*;
    use quote::{ToTokens, quote};

    fn args() -> Vec<Arg> {
        vec![Arg::new("x", quote!(&[f64; 3]))]
    }

    fn inputs() -> Vec<Input> {
        ["a", "b", "c"].iter().enumerate().map(|(k, s)| Input::new(Symbol::new(s), s, 0, quote!(x[#k]))).collect()
    }

    fn built(outputs: &[Expr]) -> (Bodies, Body) {
        let body = body_with_definitions("f", &[], outputs, &inputs(), &args(), 100, &mut Default::default()).unwrap();
        let mut bodies = Bodies::new(vec![FormulationKind::Lagrange, FormulationKind::Maggi]);
        bodies.start(FormulationKind::Lagrange, Default::default());
        bodies.remember(Signature::new("f", &[], &inputs(), &args(), 100), outputs, &body);
        (bodies, body)
    }

    fn text(e: &syn::Expr) -> String {
        e.to_token_stream().to_string()
    }

    #[test]
    fn the_same_outputs_reordered_beside_constants_take_the_built_body() {
        let (a, b, c) = (Symbol::new("a").expr(), Symbol::new("b").expr(), Symbol::new("c").expr());
        let (first, second) = (a.sin() * b + c, a.sin() * b * c);
        let (bodies, body) = built(&[first, second, Expr::int(2)]);
        let wanted = [Expr::zero(), second, Expr::int(-3), first];
        let reused = bodies.find(&Signature::new("f", &[], &inputs(), &args(), 100), &wanted).expect("the same outputs").unwrap();
        let texts: Vec<String> = reused.outputs.iter().map(text).collect();
        assert_eq!(texts, ["0.0", text(&body.outputs[1]).as_str(), "- 3.0", text(&body.outputs[0]).as_str()]);
        assert_eq!(reused.stmts.len(), body.stmts.len());
        assert_eq!((reused.ops, reused.lets, reused.used_args), (body.ops, body.lets, body.used_args));
    }

    #[test]
    fn other_outputs_or_another_signature_build_anew() {
        let (a, b, c) = (Symbol::new("a").expr(), Symbol::new("b").expr(), Symbol::new("c").expr());
        let (first, second) = (a.sin() * b + c, a.sin() * b * c);
        let (bodies, _) = built(&[first, second]);
        let signature = Signature::new("f", &[], &inputs(), &args(), 100);
        assert!(bodies.find(&signature, &[first]).is_none(), "an output left out");
        assert!(bodies.find(&signature, &[first, second, a]).is_none(), "an output added");
        assert!(bodies.find(&signature, &[first, second, second]).is_none(), "an output twice");
        assert!(bodies.find(&Signature::new("g", &[], &inputs(), &args(), 100), &[first, second]).is_none(), "another name");
        assert!(bodies.find(&Signature::new("f", &[], &inputs(), &args(), 1), &[first, second]).is_none(), "another split");
        assert!(bodies.find(&signature, &[second, first]).is_some());
    }

    #[test]
    fn bodies_are_kept_while_a_formulation_follows_in_the_emitter() {
        use FormulationKind::{Kane, Lagrange, Maggi, ReducedVolterra};
        let (a, b) = (Symbol::new("a").expr(), Symbol::new("b").expr());
        let outputs = [a.sin() * b];
        let signature = || Signature::new("f", &[], &inputs(), &args(), 100);
        let body = body_with_definitions("f", &[], &outputs, &inputs(), &args(), 100, &mut Default::default()).unwrap();
        let mut bodies = Bodies::new(vec![Lagrange, Maggi, Kane]);
        bodies.remember(signature(), &outputs, &body);
        assert!(bodies.find(&signature(), &outputs).is_none(), "before the first formulation: nothing follows");
        bodies.start(Lagrange, Default::default());
        bodies.remember(signature(), &outputs, &body);
        bodies.start(Maggi, Default::default());
        assert!(bodies.find(&signature(), &outputs).is_some(), "kept for Maggi after Lagrange");
        bodies.start(Kane, Default::default());
        assert!(bodies.find(&signature(), &outputs).is_some(), "kept for Kane");
        let mut last = Bodies::new(vec![Kane]);
        last.start(Kane, Default::default());
        last.remember(signature(), &outputs, &body);
        assert!(last.find(&signature(), &outputs).is_none(), "nothing follows the last formulation: not kept");
        let mut alone = Bodies::new(vec![Kane, ReducedVolterra]);
        alone.start(Kane, Default::default());
        alone.remember(signature(), &outputs, &body);
        alone.start(ReducedVolterra, Default::default());
        assert!(alone.find(&signature(), &outputs).is_some(), "kept for the reduced form after Kane");
    }

    /// Speeds `u, v` that are the rates `c, b` (`state[2]`, `state[1]` in the first body; `u`
    /// is `state[1]` and `v` is `state[2]` in the second).
    fn speeds() -> Vec<Input> {
        vec![
            Input::new(Symbol::new("a"), "a", 0, quote!(x[0])),
            Input::new(Symbol::new("u"), "u", 0, quote!(x[1])),
            Input::new(Symbol::new("v"), "v", 0, quote!(x[2])),
        ]
    }

    fn relabel() -> StdHashMap<Symbol, Expr> {
        speeds_as_rates(&[Symbol::new("u"), Symbol::new("v")], &[Symbol::new("v").expr(), Symbol::new("u").expr()], &[Symbol::new("b"), Symbol::new("c")])
    }

    #[test]
    fn speeds_that_are_the_rates_reordered_name_them() {
        let (b, c, u, v) = (Symbol::new("b"), Symbol::new("c"), Symbol::new("u"), Symbol::new("v"));
        let relabel = relabel();
        assert_eq!((relabel.len(), relabel[&u], relabel[&v]), (2, c.expr(), b.expr()));
        assert!(speeds_as_rates(&[u, v], &[v.expr(), u.expr() + v.expr()], &[b, c]).is_empty(), "a rate not a speed");
        assert!(speeds_as_rates(&[u, v], &[v.expr(), v.expr()], &[b, c]).is_empty(), "a speed twice");
        assert!(speeds_as_rates(&[u, v], &[u.expr(), v.expr()], &[u, v]).is_empty(), "the rates themselves: nothing to rename");
    }

    #[test]
    fn a_body_is_reused_under_the_speeds_names_and_places() {
        use FormulationKind::{Kane, Lagrange};
        let (a, b, c, u, v) = (Symbol::new("a").expr(), Symbol::new("b").expr(), Symbol::new("c").expr(), Symbol::new("u").expr(), Symbol::new("v").expr());
        let first = [a.sin() * b + c * c, b * c];
        let body = body_with_definitions("f", &[], &first, &inputs(), &args(), 100, &mut Default::default()).unwrap();
        let mut bodies = Bodies::new(vec![Lagrange, Kane]);
        bodies.start(Lagrange, Default::default());
        bodies.remember(Signature::new("f", &[], &inputs(), &args(), 100), &first, &body);
        bodies.start(Kane, relabel());
        let second = [u * v, a.sin() * v + u * u];
        let reused = bodies.find(&Signature::new("f", &[], &speeds(), &args(), 100), &second).expect("the same outputs in the rates").unwrap();
        let built = body_with_definitions("f", &[], &second, &speeds(), &args(), 100, &mut Default::default()).unwrap();
        let code = |b: &Body| {
            let stmts = &b.stmts;
            let outputs = &b.outputs;
            quote!(#(#stmts)* [#(#outputs),*]).to_string()
        };
        assert!(code(&reused).contains("let u = x [1] ;") && code(&reused).contains("let v = x [2] ;"), "{}", code(&reused));
        assert!(!code(&reused).contains(" b ") && !code(&reused).contains(" c "), "{}", code(&reused));
        assert_eq!((reused.ops, reused.lets), (built.ops, built.lets));
        assert!(bodies.find(&Signature::new("f", &[], &speeds(), &args(), 100), &[u * v, a.sin() * u + v * v]).is_none(), "other outputs in the rates");
    }

    #[test]
    fn a_speed_named_as_something_in_the_body_is_not_renamed_into_it() {
        use FormulationKind::{Kane, Lagrange};
        let (a, b, c) = (Symbol::new("a").expr(), Symbol::new("b").expr(), Symbol::new("c").expr());
        let first = [a.sin() * b * c, a.sin() * b + c];
        let body = body_with_definitions("f", &[], &first, &inputs(), &args(), 100, &mut Default::default()).unwrap();
        let stmts = &body.stmts;
        let taken = quote!(#(#stmts)*).to_string();
        let let_name = body.stmts.iter().find_map(|s| match s {
            syn::Stmt::Local(l) => match &l.pat {
                syn::Pat::Ident(p) if !["a", "b", "c"].contains(&p.ident.to_string().as_str()) => Some(p.ident.to_string()),
                _ => None,
            },
            _ => None,
        });
        let let_name = let_name.unwrap_or_else(|| panic!("a let in {taken}"));
        let mut bodies = Bodies::new(vec![Lagrange, Kane]);
        bodies.start(Lagrange, Default::default());
        bodies.remember(Signature::new("f", &[], &inputs(), &args(), 100), &first, &body);
        let (u, v) = (Symbol::new(&let_name), Symbol::new("v"));
        bodies.start(Kane, speeds_as_rates(&[u, v], &[v.expr(), u.expr()], &[Symbol::new("b"), Symbol::new("c")]));
        let named = vec![Input::new(Symbol::new("a"), "a", 0, quote!(x[0])), Input::new(u, &let_name, 0, quote!(x[1])), Input::new(v, "v", 0, quote!(x[2]))];
        let second = [a.sin() * v.expr() * u.expr(), a.sin() * v.expr() + u.expr()];
        assert!(bodies.find(&Signature::new("f", &[], &named, &args(), 100), &second).is_none(), "{let_name} is a let of the body");
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn speeds_as_rates_example() {
        use crate::emit::reuse::speeds_as_rates;
        use crate::symbolic::Symbol;
        let (u1, u2, x_dot, y_dot) = (Symbol::new("u1"), Symbol::new("u2"), Symbol::new("x_dot"), Symbol::new("y_dot"));
        let relabel = speeds_as_rates(&[u1, u2], &[u2.expr(), u1.expr()], &[x_dot, y_dot]);
        assert_eq!(relabel[&u2], x_dot.expr());
        assert!(speeds_as_rates(&[u1, u2], &[u2.expr(), u1.expr() + u2.expr()], &[x_dot, y_dot]).is_empty());
    }
}
