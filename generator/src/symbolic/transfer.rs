//! Moving derived values to another [`super::Context`], such as a worker thread's.
//!
//! An [`Expr`] is an id into the context that built it, so a value holding expressions means
//! nothing in another one. A [`Parcel`] packs a value with the part of the DAG its expressions
//! reach (plain nodes over indices, symbols by name): it is `Send` when the value is, and
//! [`Parcel::unpack`] rebuilds the same nodes, already canonical, in the current context. What
//! a value holds is said by its [`Transfer`] impl, which visits every expression and symbol in
//! a fixed order.

use super::expr::post_order_pruned;
use super::number::Rat;
use super::{Expr, Func, Matrix, Node, Symbol};
use rustc_hash::FxHashMap;

/// Visits the expressions and symbols a value holds (see [`Transfer`]).
pub trait Visitor {
    fn expr(&mut self, e: &mut Expr);
    fn symbol(&mut self, s: &mut Symbol);
}

/// A value whose expressions and symbols can move to another context: `visit` calls the
/// visitor on each of them, in the same order every time.
pub trait Transfer {
    fn visit(&mut self, v: &mut dyn Visitor);
}

/// One node of a packed DAG: children are indices of earlier nodes, symbols indices into the
/// parcel's names.
#[derive(Clone, Debug)]
enum Packed {
    Num(Rat),
    Sym(u32),
    Add { constant: Rat, terms: Vec<(u32, Rat)> },
    Mul { coefficient: Rat, factors: Vec<(u32, Rat)> },
    Fun(Func, u32),
    Apply(u32, u32),
}

/// A value packed with its expressions, ready for another context.
#[derive(Clone, Debug)]
pub struct Parcel<T> {
    value: T,
    /// How many nodes the parcels before this one on its channel carried ([`Packer`]): node
    /// numbers below it are theirs.
    base: u32,
    /// The DAG the parcels before did not carry, children before parents, numbered on from
    /// `base`.
    nodes: Vec<Packed>,
    /// The node of each expression the value holds, in visiting order.
    roots: Vec<u32>,
    /// Symbol names (as interned) the nodes and the value refer to.
    names: Vec<String>,
    /// The name index of each symbol the value holds, in visiting order.
    symbols: Vec<u32>,
}

/// Collects what a value holds, in visiting order.
#[derive(Default)]
struct Collect {
    exprs: Vec<Expr>,
    symbols: Vec<Symbol>,
}

impl Visitor for Collect {
    fn expr(&mut self, e: &mut Expr) {
        self.exprs.push(*e);
    }
    fn symbol(&mut self, s: &mut Symbol) {
        self.symbols.push(*s);
    }
}

/// Puts the rebuilt expressions and symbols back, in visiting order.
struct Replace<'a> {
    exprs: std::slice::Iter<'a, Expr>,
    symbols: std::slice::Iter<'a, Symbol>,
}

impl Visitor for Replace<'_> {
    fn expr(&mut self, e: &mut Expr) {
        *e = *self.exprs.next().expect("a value visits what it visited when packed");
    }
    fn symbol(&mut self, s: &mut Symbol) {
        *s = *self.symbols.next().expect("a value visits what it visited when packed");
    }
}

impl<T: Transfer + Clone> Parcel<T> {
    /// Packs `value` (expressions of the current context) alone: [`Parcel::unpack`] rebuilds it.
    pub fn pack(value: &T) -> Parcel<T> {
        Packer::default().pack(value)
    }

    /// The value, its expressions rebuilt in the current context (a parcel packed alone).
    pub fn unpack(self) -> T {
        Unpacker::default().unpack(self)
    }
}

/// The sending end of a channel of parcels between two contexts: a node one parcel carried is
/// referred to by the next ones, not packed again (Lagrange's matrix is the mechanics' `M`:
/// on the pendulum on a cart at n = 100, handing the formulations to the emitting thread
/// packed most of the DAG again for each). The parcels are unpacked in the order packed, by
/// one [`Unpacker`].
#[derive(Default)]
pub struct Packer {
    /// The stream's number of every node sent.
    sent: FxHashMap<Expr, u32>,
}

impl Packer {
    /// `value` packed with the nodes its expressions reach that no earlier parcel carried.
    pub fn pack<T: Transfer + Clone>(&mut self, value: &T) -> Parcel<T> {
        let mut value = value.clone();
        let mut held = Collect::default();
        value.visit(&mut held);
        let base = self.sent.len() as u32;
        let order = post_order_pruned(&held.exprs, |e| self.sent.contains_key(&e));
        for (i, e) in order.iter().enumerate() {
            self.sent.insert(*e, base + i as u32);
        }
        let index = &self.sent;
        let mut names = Vec::new();
        let mut name_index: FxHashMap<Symbol, u32> = FxHashMap::default();
        let mut name_of = |s: Symbol| {
            *name_index.entry(s).or_insert_with(|| {
                names.push(s.interned_name());
                names.len() as u32 - 1
            })
        };
        let pairs = |v: &[(Expr, Rat)]| v.iter().map(|(e, r)| (index[e], r.clone())).collect();
        let nodes = order
            .iter()
            .map(|e| match &*e.node() {
                Node::Num(r) => Packed::Num(r.clone()),
                Node::Sym(s) => Packed::Sym(name_of(*s)),
                Node::Add { constant, terms } => Packed::Add { constant: constant.clone(), terms: pairs(terms) },
                Node::Mul { coefficient, factors } => Packed::Mul { coefficient: coefficient.clone(), factors: pairs(factors) },
                Node::Fun(f, a) => Packed::Fun(*f, index[a]),
                Node::Apply(s, a) => Packed::Apply(name_of(*s), index[a]),
            })
            .collect();
        let roots = held.exprs.iter().map(|e| index[e]).collect();
        let symbols = held.symbols.iter().map(|s| name_of(*s)).collect();
        Parcel { value, base, nodes, roots, names, symbols }
    }
}

/// The receiving end of a [`Packer`]'s channel: the nodes rebuilt so far, by the stream's
/// numbers.
#[derive(Default)]
pub struct Unpacker {
    received: Vec<Expr>,
}

impl Unpacker {
    /// The value of the next parcel of the channel, its expressions rebuilt in the current
    /// context.
    pub fn unpack<T: Transfer>(&mut self, parcel: Parcel<T>) -> T {
        let Parcel { mut value, base, nodes, roots, names, symbols } = parcel;
        assert_eq!(base as usize, self.received.len(), "parcels are unpacked in the order they were packed");
        let syms: Vec<Symbol> = names.iter().map(|n| Symbol::from_interned_name(n)).collect();
        let built = &mut self.received;
        built.reserve(nodes.len());
        for node in nodes {
            let pairs = |v: Vec<(u32, Rat)>, built: &[Expr]| v.into_iter().map(|(i, r)| (built[i as usize], r)).collect();
            // Each node was canonical where it was built, and canonical order depends only on
            // structure: interned as it is.
            let e = match node {
                Packed::Num(r) => Expr::num(r),
                Packed::Sym(s) => syms[s as usize].expr(),
                Packed::Add { constant, terms } => Expr::intern(Node::Add { constant, terms: pairs(terms, built) }),
                Packed::Mul { coefficient, factors } => Expr::intern(Node::Mul { coefficient, factors: pairs(factors, built) }),
                Packed::Fun(f, a) => Expr::intern(Node::Fun(f, built[a as usize])),
                Packed::Apply(s, a) => Expr::intern(Node::Apply(syms[s as usize], built[a as usize])),
            };
            built.push(e);
        }
        let exprs: Vec<Expr> = roots.iter().map(|&i| built[i as usize]).collect();
        let symbols: Vec<Symbol> = symbols.iter().map(|&i| syms[i as usize]).collect();
        value.visit(&mut Replace { exprs: exprs.iter(), symbols: symbols.iter() });
        value
    }
}

impl Transfer for Expr {
    fn visit(&mut self, v: &mut dyn Visitor) {
        v.expr(self);
    }
}

impl Transfer for Symbol {
    fn visit(&mut self, v: &mut dyn Visitor) {
        v.symbol(self);
    }
}

impl<T: Transfer> Transfer for Vec<T> {
    fn visit(&mut self, v: &mut dyn Visitor) {
        self.iter_mut().for_each(|x| x.visit(v));
    }
}

impl<T: Transfer, const N: usize> Transfer for [T; N] {
    fn visit(&mut self, v: &mut dyn Visitor) {
        self.iter_mut().for_each(|x| x.visit(v));
    }
}

impl<T: Transfer> Transfer for Option<T> {
    fn visit(&mut self, v: &mut dyn Visitor) {
        if let Some(x) = self {
            x.visit(v);
        }
    }
}

impl<A: Transfer, B: Transfer> Transfer for (A, B) {
    fn visit(&mut self, v: &mut dyn Visitor) {
        self.0.visit(v);
        self.1.visit(v);
    }
}

/// Values that hold no expression: nothing to visit.
macro_rules! plain {
    ($($t:ty),*) => {
        $(impl Transfer for $t {
            fn visit(&mut self, _: &mut dyn Visitor) {}
        })*
    };
}
plain!(usize, f64, bool, String, &'static str);

impl Transfer for Matrix {
    fn visit(&mut self, v: &mut dyn Visitor) {
        self.data.visit(v);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::symbolic::Context;
    use proptest::prelude::*;

    fn parse(text: &str) -> Expr {
        crate::symbolic::parse::lower_default(&crate::symbolic::parse::parse(text).unwrap()).unwrap()
    }

    /// What `build` makes in a context of its own, packed and unpacked in another: printed the
    /// same, with the same structural keys and sizes, and equal to what `build` makes there.
    fn round_trip(build: impl Fn() -> Vec<Expr>) {
        let from = Context::new();
        let (parcel, printed, keys) = from.enter(|| {
            let es = build();
            (Parcel::pack(&es), es.iter().map(|e| e.to_string()).collect::<Vec<_>>(), es.iter().map(|e| (e.key(), e.dag_size())).collect::<Vec<_>>())
        });
        let to = Context::new();
        to.enter(|| {
            // Something built first, so ids differ between the contexts.
            let _ = Expr::sym("unrelated").cos() + Expr::sym("y");
            let es = parcel.unpack();
            assert_eq!(es.iter().map(|e| e.to_string()).collect::<Vec<_>>(), printed);
            assert_eq!(es.iter().map(|e| (e.key(), e.dag_size())).collect::<Vec<_>>(), keys);
            assert_eq!(es, build());
        });
    }

    #[test]
    fn expressions_arrive_equal_to_the_same_built_there() {
        round_trip(|| {
            let f = Expr::apply_named(Symbol::new("F"), Expr::sym("t"));
            vec![parse("x"), parse("2*sin(x + y)^2 - cos(x)/3 + 7/2"), f * parse("exp(-t) + abs(x)*y^(1/2)"), parse("x*y + (x*y)^2 - x")]
        });
    }

    #[test]
    fn symbols_and_internal_symbols_keep_their_names() {
        let parcel = Context::new().enter(|| Parcel::pack(&vec![(Symbol::internal("u1"), Symbol::new("u1").expr())]));
        Context::new().enter(|| {
            let v = parcel.unpack();
            assert_eq!(v[0].0, Symbol::internal("u1"));
            assert_ne!(v[0].1, Symbol::internal("u1").expr());
            assert_eq!(v[0].1, Expr::sym("u1"));
        });
    }

    /// Parcels on one channel: a node the first carried is referred to by the second, not
    /// packed again, and both arrive equal to what is built there.
    #[test]
    fn a_channel_packs_each_node_once() {
        let shared = || parse("2*sin(x + y)^2 - cos(x)/3 + x*y");
        let (first, second, alone) = Context::new().enter(|| {
            let mut packer = Packer::default();
            let first = packer.pack(&vec![shared()]);
            let second = packer.pack(&vec![shared() * Expr::sym("z"), shared()]);
            (first, second, Parcel::pack(&vec![shared() * Expr::sym("z"), shared()]))
        });
        // The second parcel carries only the product and `z`.
        assert_eq!((second.base as usize, second.nodes.len()), (first.nodes.len(), 2));
        assert!(alone.nodes.len() > first.nodes.len());
        Context::new().enter(|| {
            let _ = Expr::sym("unrelated").cos();
            let mut unpacker = Unpacker::default();
            assert_eq!(unpacker.unpack(first), vec![shared()]);
            assert_eq!(unpacker.unpack(second), vec![shared() * Expr::sym("z"), shared()]);
        });
    }

    #[test]
    fn a_parcel_crosses_threads() {
        let parcel = Context::new().enter(|| Parcel::pack(&Matrix::from_rows(vec![vec![Expr::sym("a"), Expr::sym("a").sin()]])));
        let printed =
            std::thread::spawn(move || Context::new().enter(|| parcel.unpack().data.iter().map(|e| e.to_string()).collect::<Vec<_>>())).join().unwrap();
        assert_eq!(printed, ["a", "sin(a)"]);
    }

    proptest! {
        #[test]
        fn random_sums_of_products_round_trip(terms in proptest::collection::vec((0usize..4, 0usize..4, -5i64..6, 1u32..3), 1..8)) {
            let names = ["x", "y", "sin(x)", "cos(x - y)"];
            let text: Vec<String> = terms.iter().map(|(a, b, c, p)| format!("{c}*{}*({})^{p}", names[*a], names[*b])).collect();
            round_trip(|| vec![parse(&text.join(" + "))]);
        }
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::symbolic::{Context, Expr, transfer::Parcel};
        let parcel = Context::new().enter(|| Parcel::pack(&vec![Expr::sym("x").sin() * 2]));
        let text = std::thread::spawn(move || Context::new().enter(|| parcel.unpack()[0].to_string())).join().unwrap();
        assert_eq!(text, "2*sin(x)");
    }
}
