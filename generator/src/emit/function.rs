//! One emitted function body: input bindings, one `let` per common subexpression, and the
//! outputs; split into helper functions that fill a scratch array when it would be too long
//! to compile quickly (measured when the crates were chosen: rustc time grows about quadratically above a
//! few thousand statements in one function).

use super::cse::plan_with;
use super::lower::{LowerError, lower};
use super::ops::OpCount;
use super::optimize::{expand_angle_sums, factor_sums_with, share_reciprocals};
use super::pairs::share_pairs;
use super::syntax;
use crate::symbolic::{Expr, Symbol};
use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::quote;
use rustc_hash::{FxHashMap as HashMap, FxHashSet as HashSet};
use std::cell::RefCell;
use std::collections::BTreeSet;

/// A function argument.
#[derive(Clone, Debug)]
pub struct Arg {
    pub name: String,
    pub ty: TokenStream,
}

impl Arg {
    /// An argument `name: ty`.
    pub fn new(name: &str, ty: TokenStream) -> Arg {
        Arg { name: name.to_string(), ty }
    }
}

/// A symbol's value inside the function: `let ident = source;`, where `source` reads
/// argument number `arg`.
#[derive(Clone, Debug)]
pub struct Input {
    pub symbol: Symbol,
    pub ident: String,
    pub arg: usize,
    pub source: TokenStream,
}

impl Input {
    /// A binding of `symbol` to `ident`, read from argument `arg` by `source`.
    pub fn new(symbol: Symbol, ident: &str, arg: usize, source: TokenStream) -> Input {
        Input { symbol, ident: ident.to_string(), arg, source }
    }
}

/// The pieces of a function body, as syntax trees.
#[derive(Clone)]
pub struct Body {
    /// Statements: input bindings, then the `let`s (or the calls of the helper parts).
    pub stmts: Vec<syn::Stmt>,
    /// One expression per output, in terms of the `let`s and inputs.
    pub outputs: Vec<syn::Expr>,
    /// Helper functions (the parts of a split body), to place beside the function.
    pub helpers: Vec<syn::Item>,
    /// Arguments the statements and outputs read.
    pub used_args: BTreeSet<usize>,
    /// Operations of the whole body.
    pub ops: OpCount,
    /// Number of common subexpressions bound.
    pub lets: usize,
}

pub(crate) fn ident(name: &str) -> Ident {
    Ident::new(name, Span::call_site())
}

/// Argument list with unused arguments prefixed by `_`.
pub fn arg_list(args: &[Arg], used: &BTreeSet<usize>) -> Vec<TokenStream> {
    args.iter()
        .enumerate()
        .map(|(i, a)| {
            let name = if used.contains(&i) { ident(&a.name) } else { ident(&format!("_{}", a.name)) };
            let ty = &a.ty;
            quote!(#name: #ty)
        })
        .collect()
}

/// Builds the body computing `outputs`. Above `max_lets` bound subexpressions the work goes to
/// helper functions `<name>_part<k>` that fill a scratch array.
#[cfg(test)]
pub fn body(name: &str, outputs: &[Expr], inputs: &[Input], args: &[Arg], max_lets: usize) -> Result<Body, LowerError> {
    body_with(name, outputs, inputs, args, max_lets, &mut HashMap::default())
}

/// [`body`] with the Horner memo of [`factor_sums_with`] kept by the caller (one per module).
#[cfg(test)]
pub fn body_with(name: &str, outputs: &[Expr], inputs: &[Input], args: &[Arg], max_lets: usize, horner: &mut HashMap<Expr, Expr>) -> Result<Body, LowerError> {
    body_with_definitions(name, &[], outputs, inputs, args, max_lets, horner)
}

/// [`body_with`] where the outputs may read named intermediates: `definitions` in order, each
/// in terms of the inputs and the ones before it (a recursion's vectors, which the symbolic
/// core would otherwise flatten into the outputs). Each gets its own `let` (or scratch slot),
/// computed before anything that reads it, and shares subexpressions with everything else.
pub fn body_with_definitions(
    name: &str,
    definitions: &[(Symbol, Expr)],
    outputs: &[Expr],
    inputs: &[Input],
    args: &[Arg],
    max_lets: usize,
    horner: &mut HashMap<Expr, Expr>,
) -> Result<Body, LowerError> {
    let definitions = &needed(definitions, outputs);
    let all: Vec<Expr> = definitions.iter().map(|(_, e)| *e).chain(outputs.iter().copied()).collect();
    let all = share_pairs(&share_reciprocals(&factor_sums_with(&expand_angle_sums(&all), horner)));
    let (defined, outputs) = all.split_at(definitions.len());
    // Each name's value: a bound node, or the leaf it stands for (resolved through other names).
    let mut value: HashMap<Symbol, Expr> = HashMap::default();
    for ((s, _), d) in definitions.iter().zip(defined) {
        let resolved = d.as_sym().and_then(|x| value.get(&x).copied()).unwrap_or(*d);
        value.insert(*s, resolved);
    }
    let forced: HashSet<Expr> = defined.iter().copied().filter(|d| d.as_num().is_none() && d.as_sym().is_none()).collect();
    let bound = plan_with(&all, &forced);
    let by_symbol: HashMap<Symbol, &Input> = inputs.iter().map(|i| (i.symbol, i)).collect();
    let taken: HashSet<String> = inputs.iter().map(|i| i.ident.clone()).chain(args.iter().map(|a| a.name.clone())).collect();
    let mut ops = OpCount::default();
    if bound.len() <= max_lets {
        let names = let_names(bound.len(), &taken);
        let index: HashMap<Expr, usize> = bound.iter().enumerate().map(|(k, e)| (*e, k)).collect();
        let symbols = SymbolUse::new(&by_symbol);
        let reference = |e: Expr| index.get(&e).map(|&k| syntax::ident(&names[k]));
        let lookup = |s: Symbol| named(s, &value, &symbols, &reference);
        let mut lets = Vec::new();
        for (k, e) in bound.iter().enumerate() {
            let (t, o) = lower(*e, &lookup, &reference)?;
            ops.merge(&o);
            lets.push(syntax::let_stmt(&names[k], t));
        }
        let outs = lower_outputs(outputs, &lookup, &reference, &mut ops)?;
        let used = symbols.used.into_inner();
        let (mut stmts, used_args) = input_lets(inputs, &used);
        stmts.extend(lets);
        return Ok(Body { stmts, outputs: outs, helpers: vec![], used_args, ops, lets: bound.len() });
    }
    // Split: v[k] holds bound subexpression k; part j computes a contiguous range of them.
    let n = bound.len();
    let index: HashMap<Expr, usize> = bound.iter().enumerate().map(|(k, e)| (*e, k)).collect();
    let reference = |e: Expr| index.get(&e).map(|&k| syntax::index("v", k));
    let size = Literal::usize_unsuffixed(n);
    let mut helpers = Vec::new();
    let mut calls = Vec::new();
    let mut all_used_args = BTreeSet::new();
    for (j, chunk) in bound.chunks(max_lets.max(1)).enumerate() {
        let symbols = SymbolUse::new(&by_symbol);
        let lookup = |s: Symbol| named(s, &value, &symbols, &reference);
        let mut lines = Vec::new();
        for e in chunk {
            let (t, o) = lower(*e, &lookup, &reference)?;
            ops.merge(&o);
            let target = reference(*e).expect("bound");
            lines.push(syntax::assign_stmt(target, t));
        }
        let (ins, used_args) = input_lets(inputs, &symbols.used.into_inner());
        all_used_args.extend(used_args.iter().copied());
        let part = ident(&format!("{name}_part{j}"));
        let param_types = arg_list(args, &used_args);
        let mut helper: syn::ItemFn = syn::parse_quote! {
            #[allow(non_snake_case)]
            #[inline(never)]
            fn #part(#(#param_types,)* v: &mut [f64; #size]) {}
        };
        helper.block.stmts = ins.into_iter().chain(lines).collect();
        helpers.push(syn::Item::Fn(helper));
        // Pass every argument (the part's signature has them all, unused ones prefixed).
        let all: Vec<Ident> = args.iter().map(|a| ident(&a.name)).collect();
        calls.push(syn::parse_quote!(#part(#(#all,)* &mut v);));
        all_used_args.extend(0..args.len());
    }
    let symbols = SymbolUse::new(&by_symbol);
    let lookup = |s: Symbol| named(s, &value, &symbols, &reference);
    let outs = lower_outputs(outputs, &lookup, &reference, &mut ops)?;
    let (mut stmts, used_args) = input_lets(inputs, &symbols.used.into_inner());
    all_used_args.extend(used_args);
    stmts.push(syn::parse_quote!(let mut v = [0.0f64; #size];));
    stmts.extend(calls);
    Ok(Body { stmts, outputs: outs, helpers, used_args: all_used_args, ops, lets: n })
}

/// Resolves symbols to their input identifiers, remembering which were used.
struct SymbolUse<'a> {
    by_symbol: &'a HashMap<Symbol, &'a Input>,
    used: RefCell<BTreeSet<Symbol>>,
}

impl<'a> SymbolUse<'a> {
    fn new(by_symbol: &'a HashMap<Symbol, &'a Input>) -> Self {
        SymbolUse { by_symbol, used: RefCell::new(BTreeSet::new()) }
    }

    fn lookup(&self, s: Symbol) -> Option<syn::Expr> {
        let inp = self.by_symbol.get(&s)?;
        self.used.borrow_mut().insert(s);
        Some(syntax::ident(&inp.ident))
    }
}

/// Operations of `outputs` and the `definitions` they read, before emission's sharing
/// ([`crate::symbolic::expr::dag_ops`]): a cheap estimate of a program's size.
pub fn program_ops(definitions: &[(Symbol, Expr)], outputs: &[Expr]) -> usize {
    let read: Vec<Expr> = needed(definitions, outputs).into_iter().map(|(_, e)| e).chain(outputs.iter().copied()).collect();
    crate::symbolic::expr::dag_ops(&read)
}

/// The definitions the outputs read, directly or through later definitions (a recursion forms
/// vectors some of whose components nothing reads).
fn needed(definitions: &[(Symbol, Expr)], outputs: &[Expr]) -> Vec<(Symbol, Expr)> {
    if definitions.is_empty() {
        return Vec::new();
    }
    let names: HashSet<Symbol> = definitions.iter().map(|(s, _)| *s).collect();
    let mut wanted: HashSet<Symbol> = HashSet::default();
    let read = |e: Expr, wanted: &mut HashSet<Symbol>| {
        for s in e.free_symbols() {
            if names.contains(&s) {
                wanted.insert(s);
            }
        }
    };
    for e in outputs {
        read(*e, &mut wanted);
    }
    for (s, e) in definitions.iter().rev() {
        if wanted.contains(s) {
            read(*e, &mut wanted);
        }
    }
    definitions.iter().filter(|(s, _)| wanted.contains(s)).cloned().collect()
}

/// A symbol's value: a named intermediate's bound node (or the leaf it stands for), else the
/// input.
fn named(s: Symbol, value: &HashMap<Symbol, Expr>, symbols: &SymbolUse, reference: &dyn Fn(Expr) -> Option<syn::Expr>) -> Option<syn::Expr> {
    match value.get(&s) {
        None => symbols.lookup(s),
        Some(v) => match (v.as_sym(), v.as_num()) {
            (Some(x), _) => symbols.lookup(x),
            (_, Some(_)) => lower(*v, &|_| None, &|_| None).ok().map(|(t, _)| t),
            _ => reference(*v),
        },
    }
}

/// Each output as tokens: a bound name, or the lowered expression.
fn lower_outputs(
    outputs: &[Expr],
    symbol: &dyn Fn(Symbol) -> Option<syn::Expr>,
    reference: &dyn Fn(Expr) -> Option<syn::Expr>,
    ops: &mut OpCount,
) -> Result<Vec<syn::Expr>, LowerError> {
    let mut outs = Vec::with_capacity(outputs.len());
    for e in outputs {
        let (t, o) = match reference(*e) {
            Some(t) => (t, OpCount::default()),
            None => lower(*e, symbol, reference)?,
        };
        ops.merge(&o);
        outs.push(t);
    }
    Ok(outs)
}

/// `let x = source;` for each used input, in the inputs' order; and the arguments they read.
fn input_lets(inputs: &[Input], used: &BTreeSet<Symbol>) -> (Vec<syn::Stmt>, BTreeSet<usize>) {
    let mut stmts = Vec::new();
    let mut args = BTreeSet::new();
    for inp in inputs.iter().filter(|i| used.contains(&i.symbol)) {
        args.insert(inp.arg);
        // An empty source: the argument itself (such as `t`).
        if !inp.source.is_empty() {
            let i = ident(&inp.ident);
            let src = &inp.source;
            stmts.push(syn::parse_quote!(let #i = #src;));
        }
    }
    (stmts, args)
}

/// `x0, x1, ...`, skipping names already taken.
fn let_names(n: usize, taken: &HashSet<String>) -> Vec<String> {
    let mut out = Vec::with_capacity(n);
    let mut k = 0;
    while out.len() < n {
        let name = format!("x{k}");
        if !taken.contains(&name) {
            out.push(name);
        }
        k += 1;
    }
    out
}

/// The arguments of a function of the state: `t`, `state`, `params` and `g_i`.
pub(super) fn state_args() -> Vec<Arg> {
    vec![
        Arg::new("t", quote!(f64)),
        Arg::new("state", quote!(&[f64; STATES])),
        Arg::new("params", quote!(&Params)),
        Arg::new("g_i", quote!(&[f64; NUM_IGNORABLE])),
    ]
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::emit::function::{Arg, Input, body};
        use crate::symbolic::Expr;
        use quote::quote;
        let x = Expr::sym("x");
        let args = [Arg::new("state", quote!(&[f64; 1]))];
        let inputs = [Input::new(x.as_sym().unwrap(), "x", 0, quote!(state[0]))];
        let b = body("f", &[x.sin() * x, x.sin() + x], &inputs, &args, usize::MAX).unwrap();
        assert_eq!(b.lets, 1); // sin(x), shared by both outputs
        assert_eq!(b.stmts.len(), 2); // let x = state[0]; let x0 = f64::sin(x);
    }
    #[test]
    fn body_with_definitions_example() {
        use crate::emit::function::{Arg, Input, body_with_definitions};
        use crate::symbolic::{Expr, Symbol};
        use quote::quote;
        let x = Expr::sym("x");
        let s = Symbol::internal("s");
        let args = [Arg::new("state", quote!(&[f64; 1]))];
        let inputs = [Input::new(x.as_sym().unwrap(), "x", 0, quote!(state[0]))];
        let b = body_with_definitions("f", &[(s, x.sin() + x)], &[s.expr() * s.expr() + 1, s.expr() * x], &inputs, &args, usize::MAX, &mut Default::default())
            .unwrap();
        assert_eq!(b.lets, 1); // s = sin(x) + x, once, read by both outputs
        assert_eq!(b.stmts.len(), 2); // let x = state[0]; let x0 = f64::sin(x) + x;
    }
    /// A root that several products read (the bicycle's Kane form reads its contact
    /// geometry's roots in most of its products) is computed once, in its own `let`.
    #[test]
    fn a_root_read_by_several_products_is_computed_once() {
        use crate::emit::function::{Arg, Input, body_with_definitions};
        use crate::symbolic::Expr;
        use quote::quote;
        let (x, a) = (Expr::sym("x"), Expr::sym("a"));
        let args = [Arg::new("state", quote!(&[f64; 2]))];
        let inputs = [Input::new(x.as_sym().unwrap(), "x", 0, quote!(state[0])), Input::new(a.as_sym().unwrap(), "a", 1, quote!(state[1]))];
        let root = (x.sin() + 2).sqrt();
        let outputs = [a * root, x / root, (a + x) * root];
        let b = body_with_definitions("f", &[], &outputs, &inputs, &args, usize::MAX, &mut Default::default()).unwrap();
        assert_eq!(b.ops.calls.get("sqrt"), Some(&1), "{:?}", b.ops);
    }

    #[test]
    fn program_ops_example() {
        use crate::emit::function::program_ops;
        use crate::symbolic::{Expr, Symbol};
        let (x, d, unread) = (Symbol::new("x"), Symbol::internal("d0"), Symbol::internal("d1"));
        let definitions = [(d, x.expr() * x.expr() + Expr::int(1)), (unread, x.expr().sin())];
        assert_eq!(program_ops(&definitions, &[d.expr() * Expr::int(3)]), 3); // pow, add, mul
    }
}
