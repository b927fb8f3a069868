//! Expressions made ready for emission: time functions inlined, `pi` and (when baked) the
//! parameters replaced by numbers.

use crate::model::Model;
use crate::symbolic::number::rat_from_f64;
use crate::symbolic::{Expr, Node, Symbol};
use std::collections::HashMap;

/// Rewrites expressions for emission, memoized over the DAG.
pub struct Preparer {
    numbers: HashMap<Symbol, Expr>,
    functions: HashMap<String, (Symbol, Expr)>,
    /// The symbol mask ([`Expr::mask`]) an expression must meet to hold anything replaced:
    /// every bit when there are time functions to inline.
    replaced: u128,
    memo: rustc_hash::FxHashMap<Expr, Expr>,
}

impl Preparer {
    /// For `model`; with `bake`, parameters become constants.
    pub fn new(model: &Model, bake: bool) -> Preparer {
        let mut numbers = HashMap::new();
        numbers.insert(Symbol::new("pi"), Expr::num(rat_from_f64(std::f64::consts::PI).expect("finite")));
        if bake {
            for (s, v) in &model.parameters {
                // Values were checked finite when the model was loaded.
                numbers.insert(*s, Expr::num(rat_from_f64(*v).expect("finite parameter")));
            }
        }
        let functions: HashMap<String, (Symbol, Expr)> = model.time_functions.iter().map(|(f, body)| (f.name(), (model.t, *body))).collect();
        let replaced = if functions.is_empty() { numbers.keys().fold(0u128, |m, s| m | s.expr().mask()) } else { u128::MAX };
        Preparer { numbers, functions, replaced, memo: Default::default() }
    }

    /// The expression with functions inlined and numbers substituted.
    pub fn prepare(&mut self, e: Expr) -> Expr {
        if e.mask() & self.replaced == 0 {
            return e;
        }
        if let Some(&r) = self.memo.get(&e) {
            return r;
        }
        let r = match &*e.node() {
            Node::Num(_) => e,
            Node::Sym(s) => self.numbers.get(s).copied().unwrap_or(e),
            Node::Apply(name, arg) => {
                let arg = self.prepare(*arg);
                let full = name.name();
                let base = full.trim_end_matches('\'');
                let order = full.len() - base.len();
                match self.functions.get(base).copied() {
                    Some((param, body)) => {
                        let mut d = body;
                        for _ in 0..order {
                            d = d.diff(param);
                        }
                        let d = self.prepare(d);
                        d.subs(&HashMap::from([(param, arg)]))
                    }
                    None => Expr::apply_named(*name, arg),
                }
            }
            _ => e.map_children(|c| self.prepare(c)),
        };
        self.memo.insert(e, r);
        r
    }

    /// [`Preparer::prepare`] on each.
    pub fn prepare_all(&mut self, items: &[Expr]) -> Vec<Expr> {
        items.iter().map(|e| self.prepare(*e)).collect()
    }
}
