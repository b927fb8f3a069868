//! Hash-consed expression DAG with canonical sums and products.
//!
//! Every expression is an [`Expr`]: a cheap, copyable id into a thread-local pool of
//! interned [`Node`]s. Structurally equal expressions get the same id, so equality is an
//! integer comparison and shared subexpressions are stored once.
//!
//! Canonical forms (applied by the constructors, never by a separate `simplify`):
//! - `Add { constant, terms }`: a rational constant plus `coefficient * term` pairs; terms are
//!   never numbers, sums, or products with a coefficient other than 1.
//! - `Mul { coefficient, factors }`: a rational coefficient times `base ^ exponent` pairs with
//!   rational exponents; bases are never products with rational exponents that could merge.
//! - Terms and factors are sorted by a structural key that does not depend on the order in
//!   which expressions were created, so output is deterministic.
//!
//! ```
//! use generator::symbolic::Expr;
//! let x = Expr::sym("x");
//! let e = x * 2 + x - x * 3;
//! assert!(e.is_zero());
//! assert_eq!((x * x).to_string(), "x^2");
//! ```

use super::number::{Rat, rat_from_i64};
use num_traits::{One, Signed, ToPrimitive, Zero};
use std::cell::RefCell;
use std::collections::HashMap;
use std::rc::Rc;

/// An interned symbol name (coordinate, velocity, parameter, time, ...).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, PartialOrd, Ord)]
pub struct Symbol(pub(crate) u32);

/// An expression: an id into the thread-local pool.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct Expr(pub(crate) u32);

/// Elementary functions of one argument.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, PartialOrd, Ord)]
pub enum Func {
    Sin,
    Cos,
    Tan,
    Exp,
    Ln,
    Abs,
}

impl Func {
    /// The name used in model files and printed output; also the name of the `f64` method
    /// that emitted code calls.
    pub fn name(self) -> &'static str {
        match self {
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Exp => "exp",
            Func::Ln => "ln",
            Func::Abs => "abs",
        }
    }

    /// Looks a function up by its name in model files.
    pub fn from_name(name: &str) -> Option<Func> {
        Some(match name {
            "sin" => Func::Sin,
            "cos" => Func::Cos,
            "tan" => Func::Tan,
            "exp" => Func::Exp,
            "ln" | "log" => Func::Ln,
            "abs" => Func::Abs,
            _ => return None,
        })
    }

    /// Evaluates the function on a float.
    pub fn apply(self, x: f64) -> f64 {
        match self {
            Func::Sin => x.sin(),
            Func::Cos => x.cos(),
            Func::Tan => x.tan(),
            Func::Exp => x.exp(),
            Func::Ln => x.ln(),
            Func::Abs => x.abs(),
        }
    }
}

/// One interned node of the DAG.
#[derive(Clone, PartialEq, Eq, Hash, Debug)]
pub enum Node {
    /// An exact rational number.
    Num(Rat),
    /// A named symbol.
    Sym(Symbol),
    /// `constant + sum(coefficient * term)`.
    Add { constant: Rat, terms: Vec<(Expr, Rat)> },
    /// `coefficient * prod(base ^ exponent)`.
    Mul { coefficient: Rat, factors: Vec<(Expr, Rat)> },
    /// An elementary function applied to an argument.
    Fun(Func, Expr),
    /// A named function of one argument, such as a prescribed force `F(t)`.
    Apply(Symbol, Expr),
}

struct Pool {
    nodes: Vec<Rc<Node>>,
    keys: Vec<u64>,
    masks: Vec<u128>,
    sizes: Vec<u32>,
    map: HashMap<Rc<Node>, Expr>,
    names: Vec<String>,
    name_map: HashMap<String, Symbol>,
    diff_memo: HashMap<(Expr, Symbol), Expr>,
}

thread_local! {
    static POOL: RefCell<Pool> = RefCell::new(Pool {
        nodes: Vec::new(),
        keys: Vec::new(),
        masks: Vec::new(),
        sizes: Vec::new(),
        map: HashMap::new(),
        names: Vec::new(),
        name_map: HashMap::new(),
        diff_memo: HashMap::new(),
    });
}

fn with_pool<R>(f: impl FnOnce(&mut Pool) -> R) -> R {
    POOL.with(|p| f(&mut p.borrow_mut()))
}

/// A 64-bit mixing step (splitmix64's finalizer): stable across runs and toolchains.
fn mix(h: u64, v: u64) -> u64 {
    let mut z = h ^ v.wrapping_add(0x9E37_79B9_7F4A_7C15).wrapping_add(h << 6).wrapping_add(h >> 2);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn hash_str(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| mix(h, b as u64))
}

fn hash_rat(r: &Rat) -> u64 {
    let n = r.numer().to_string();
    let d = r.denom().to_string();
    mix(hash_str(&n), hash_str(&d))
}

impl Pool {
    fn intern(&mut self, node: Node) -> Expr {
        if let Some(&e) = self.map.get(&node) {
            return e;
        }
        let (key, mask, size) = self.summarize(&node);
        let id = Expr(self.nodes.len() as u32);
        let rc = Rc::new(node);
        self.nodes.push(rc.clone());
        self.keys.push(key);
        self.masks.push(mask);
        self.sizes.push(size);
        self.map.insert(rc, id);
        id
    }

    /// Structural key (independent of creation order), free-symbol mask and tree size.
    fn summarize(&self, node: &Node) -> (u64, u128, u32) {
        let k = |e: &Expr| self.keys[e.0 as usize];
        let m = |e: &Expr| self.masks[e.0 as usize];
        let s = |e: &Expr| self.sizes[e.0 as usize];
        match node {
            Node::Num(r) => (mix(1, hash_rat(r)), 0, 1),
            Node::Sym(sym) => (
                mix(2, hash_str(&self.names[sym.0 as usize])),
                1u128 << (sym.0 % 128),
                1,
            ),
            Node::Add { constant, terms } | Node::Mul { coefficient: constant, factors: terms } => {
                let tag = if matches!(node, Node::Add { .. }) { 3 } else { 4 };
                let mut h = mix(tag, hash_rat(constant));
                let mut mask = 0;
                let mut size = 1u32;
                for (e, c) in terms {
                    h = mix(mix(h, k(e)), hash_rat(c));
                    mask |= m(e);
                    size = size.saturating_add(s(e));
                }
                (h, mask, size)
            }
            Node::Fun(f, a) => (mix(mix(5, *f as u64), k(a)), m(a), s(a) + 1),
            Node::Apply(name, a) => (
                mix(mix(6, hash_str(&self.names[name.0 as usize])), k(a)),
                m(a) | (1u128 << (name.0 % 128)),
                s(a) + 1,
            ),
        }
    }

    fn symbol(&mut self, name: &str) -> Symbol {
        if let Some(&s) = self.name_map.get(name) {
            return s;
        }
        let s = Symbol(self.names.len() as u32);
        self.names.push(name.to_string());
        self.name_map.insert(name.to_string(), s);
        s
    }
}

impl Symbol {
    /// Interns a symbol name.
    pub fn new(name: &str) -> Symbol {
        with_pool(|p| p.symbol(name))
    }
    /// The symbol's name.
    pub fn name(self) -> String {
        with_pool(|p| p.names[self.0 as usize].clone())
    }
    /// The symbol as an expression.
    pub fn expr(self) -> Expr {
        with_pool(|p| p.intern(Node::Sym(self)))
    }
}

/// Sorts `(expr, rational)` pairs by structural key and merges equal exprs by adding the
/// rationals; drops pairs whose rational becomes zero.
fn merge_pairs(mut pairs: Vec<(Expr, Rat)>) -> Vec<(Expr, Rat)> {
    let keys: Vec<u64> = with_pool(|p| pairs.iter().map(|(e, _)| p.keys[e.0 as usize]).collect());
    let mut idx: Vec<usize> = (0..pairs.len()).collect();
    idx.sort_by_key(|&i| (keys[i], pairs[i].0.0));
    let mut out: Vec<(Expr, Rat)> = Vec::with_capacity(pairs.len());
    let mut taken: Vec<Option<(Expr, Rat)>> = pairs.drain(..).map(Some).collect();
    for i in idx {
        let (e, c) = taken[i].take().expect("each pair is taken once");
        match out.last_mut() {
            Some((last, acc)) if *last == e => *acc += c,
            _ => out.push((e, c)),
        }
    }
    out.retain(|(_, c)| !c.is_zero());
    out
}

impl Expr {
    /// Interns a node as it is (no canonicalization): for the constructors below.
    fn intern(node: Node) -> Expr {
        with_pool(|p| p.intern(node))
    }

    /// The node behind this expression.
    pub fn node(self) -> Rc<Node> {
        with_pool(|p| p.nodes[self.0 as usize].clone())
    }

    /// Structural key: equal for equal expressions in any pool, used for canonical order.
    pub fn key(self) -> u64 {
        with_pool(|p| p.keys[self.0 as usize])
    }

    /// Tree size (number of nodes counted with repetition, saturating).
    pub fn tree_size(self) -> u32 {
        with_pool(|p| p.sizes[self.0 as usize])
    }

    /// A bloom mask of the free symbols: if `sym` may occur, its bit is set.
    pub(crate) fn mask(self) -> u128 {
        with_pool(|p| p.masks[self.0 as usize])
    }

    /// True when `sym` might occur in the expression (never false when it does).
    pub fn may_contain(self, sym: Symbol) -> bool {
        self.mask() & (1u128 << (sym.0 % 128)) != 0
    }

    /// A symbol by name.
    pub fn sym(name: &str) -> Expr {
        Symbol::new(name).expr()
    }

    /// An exact rational number.
    pub fn num(r: Rat) -> Expr {
        Expr::intern(Node::Num(r))
    }

    /// An integer.
    pub fn int(i: i64) -> Expr {
        Expr::num(rat_from_i64(i))
    }

    /// The number zero.
    pub fn zero() -> Expr {
        Expr::int(0)
    }

    /// The number one.
    pub fn one() -> Expr {
        Expr::int(1)
    }

    /// The rational value, if this is a number.
    pub fn as_num(self) -> Option<Rat> {
        match &*self.node() {
            Node::Num(r) => Some(r.clone()),
            _ => None,
        }
    }

    /// The symbol, if this is one.
    pub fn as_sym(self) -> Option<Symbol> {
        match &*self.node() {
            Node::Sym(s) => Some(*s),
            _ => None,
        }
    }

    /// True for the number zero.
    pub fn is_zero(self) -> bool {
        self.as_num().is_some_and(|r| r.is_zero())
    }

    /// True for the number one.
    pub fn is_one(self) -> bool {
        self.as_num().is_some_and(|r| r.is_one())
    }

    /// Splits into `(coefficient, rest)` with `self == coefficient * rest`.
    pub fn split_coefficient(self) -> (Rat, Expr) {
        match &*self.node() {
            Node::Num(r) => (r.clone(), Expr::one()),
            Node::Mul { coefficient, factors } if !coefficient.is_one() => {
                (coefficient.clone(), Expr::make_mul(Rat::one(), factors.clone()))
            }
            _ => (Rat::one(), self),
        }
    }

    /// Canonical sum from a constant and (possibly unmerged, possibly nested) terms.
    pub fn make_add(constant: Rat, terms: Vec<(Expr, Rat)>) -> Expr {
        let mut constant = constant;
        let mut flat: Vec<(Expr, Rat)> = Vec::with_capacity(terms.len());
        for (e, c) in terms {
            if c.is_zero() {
                continue;
            }
            match &*e.node() {
                Node::Num(r) => constant += r * &c,
                Node::Add { constant: k, terms: ts } => {
                    constant += k * &c;
                    flat.extend(ts.iter().map(|(t, tc)| (*t, tc * &c)));
                }
                _ => {
                    let (k, rest) = e.split_coefficient();
                    flat.push((rest, k * c));
                }
            }
        }
        let terms = merge_pairs(flat);
        if terms.is_empty() {
            return Expr::num(constant);
        }
        if constant.is_zero() && terms.len() == 1 {
            let (t, c) = terms.into_iter().next().expect("one term");
            return t.scale(&c);
        }
        Expr::intern(Node::Add { constant, terms })
    }

    /// Multiplies by a rational.
    pub fn scale(self, c: &Rat) -> Expr {
        if c.is_zero() {
            return Expr::zero();
        }
        if c.is_one() {
            return self;
        }
        match &*self.node() {
            Node::Num(r) => Expr::num(r * c),
            Node::Mul { coefficient, factors } => Expr::make_mul(coefficient * c, factors.clone()),
            Node::Add { constant, terms } => {
                // Distribute a number over a sum, as CAS do: keeps sums canonical.
                Expr::make_add(constant * c, terms.iter().map(|(t, k)| (*t, k * c)).collect())
            }
            _ => Expr::make_mul(c.clone(), vec![(self, Rat::one())]),
        }
    }

    /// Canonical product from a coefficient and (possibly nested) factors.
    pub fn make_mul(coefficient: Rat, factors: Vec<(Expr, Rat)>) -> Expr {
        let mut coefficient = coefficient;
        if coefficient.is_zero() {
            return Expr::zero();
        }
        let mut flat: Vec<(Expr, Rat)> = Vec::with_capacity(factors.len());
        for (b, e) in factors {
            if e.is_zero() {
                continue;
            }
            match &*b.node() {
                Node::Num(r) => {
                    if r.is_zero() {
                        if e.is_positive() {
                            return Expr::zero();
                        }
                        // 0^negative: keep symbolic so evaluation reports the division by zero.
                        flat.push((b, e));
                    } else if e.is_integer() {
                        let p = e.to_integer().to_i32().unwrap_or(i32::MAX);
                        coefficient *= num_traits::pow::Pow::pow(r.clone(), p);
                    } else {
                        flat.push((b, e));
                    }
                }
                Node::Mul { coefficient: k, factors: fs } if e.is_integer() => {
                    let p = e.to_integer().to_i32().unwrap_or(i32::MAX);
                    coefficient *= num_traits::pow::Pow::pow(k.clone(), p);
                    flat.extend(fs.iter().map(|(fb, fe)| (*fb, fe * &e)));
                }
                _ => flat.push((b, e)),
            }
        }
        let factors = merge_pairs(flat);
        // Merge numeric bases with rational exponents that became integers.
        if factors.is_empty() {
            return Expr::num(coefficient);
        }
        if coefficient.is_one() && factors.len() == 1 && factors[0].1.is_one() {
            return factors[0].0;
        }
        Expr::intern(Node::Mul { coefficient, factors })
    }

    /// `self ^ exponent` for a rational exponent.
    pub fn pow_rat(self, exponent: &Rat) -> Expr {
        if exponent.is_zero() {
            return Expr::one();
        }
        if exponent.is_one() {
            return self;
        }
        match &*self.node() {
            Node::Num(r) if !exponent.is_integer() && !r.is_negative() => {
                // Exact roots of perfect powers: sqrt(4) = 2, (8/27)^(2/3) = 4/9.
                let q = exponent.denom().to_u32().unwrap_or(0);
                let (n, d) = (r.numer().nth_root(q.max(1)), r.denom().nth_root(q.max(1)));
                if q > 0 && num_traits::pow::Pow::pow(&n, q) == *r.numer() && num_traits::pow::Pow::pow(&d, q) == *r.denom() {
                    let root = Rat::new(n, d);
                    let p = exponent.numer().to_i32().unwrap_or(1);
                    if root.is_zero() && p < 0 {
                        return Expr::make_mul(Rat::one(), vec![(self, exponent.clone())]);
                    }
                    return Expr::num(num_traits::pow::Pow::pow(root, p));
                }
                Expr::make_mul(Rat::one(), vec![(self, exponent.clone())])
            }
            Node::Num(r) if exponent.is_integer() => {
                if r.is_zero() && exponent.is_negative() {
                    return Expr::make_mul(Rat::one(), vec![(self, exponent.clone())]);
                }
                let p = exponent.to_integer().to_i32().unwrap_or(i32::MAX);
                Expr::num(num_traits::pow::Pow::pow(r.clone(), p))
            }
            Node::Mul { coefficient, factors }
                if factors.len() == 1 && coefficient.is_one() && !exponent.is_integer() =>
            {
                // (b^e1)^e2 = b^(e1 e2) when e1 is odd-free: only safe when e1*e2 keeps sign;
                // we merge when e1 is an integer power of an odd exponent or e2 is an integer.
                let (b, e1) = &factors[0];
                if e1.is_integer() && (e1.to_integer() % 2u8) != num_bigint::BigInt::zero() {
                    Expr::make_mul(Rat::one(), vec![(*b, e1 * exponent)])
                } else {
                    Expr::make_mul(Rat::one(), vec![(self, exponent.clone())])
                }
            }
            _ => Expr::make_mul(Rat::one(), vec![(self, exponent.clone())]),
        }
    }

    /// `self ^ n` for an integer exponent.
    pub fn powi(self, n: i64) -> Expr {
        self.pow_rat(&rat_from_i64(n))
    }

    /// Square root.
    pub fn sqrt(self) -> Expr {
        self.pow_rat(&Rat::new(1.into(), 2.into()))
    }

    /// Reciprocal.
    pub fn recip(self) -> Expr {
        self.powi(-1)
    }

    /// Applies an elementary function, folding the obvious identities.
    pub fn apply(f: Func, a: Expr) -> Expr {
        if let Some(r) = a.as_num() {
            if r.is_zero() {
                match f {
                    Func::Sin | Func::Tan | Func::Abs => return Expr::zero(),
                    Func::Cos | Func::Exp => return Expr::one(),
                    Func::Ln => {}
                }
            }
            if f == Func::Abs {
                return Expr::num(r.abs());
            }
            if f == Func::Ln && r.is_one() {
                return Expr::zero();
            }
        }
        // Odd/even symmetry: f(-x) for a "negative-looking" argument.
        if a.has_negative_lead() {
            let neg = -a;
            match f {
                Func::Sin | Func::Tan => return -Expr::intern(Node::Fun(f, neg)),
                Func::Cos | Func::Abs => return Expr::intern(Node::Fun(f, neg)),
                _ => {}
            }
        }
        Expr::intern(Node::Fun(f, a))
    }

    /// True when the canonical form starts with a negative coefficient; used to put odd and
    /// even functions into a canonical sign.
    fn has_negative_lead(self) -> bool {
        match &*self.node() {
            Node::Num(r) => r.is_negative(),
            Node::Mul { coefficient, .. } => coefficient.is_negative(),
            Node::Add { constant, terms } => {
                // Sign of the term with the smallest key, then the constant.
                terms.first().map(|(_, c)| c.is_negative()).unwrap_or(constant.is_negative())
            }
            _ => false,
        }
    }

    /// A named function of one argument, such as `F(t)`.
    pub fn apply_named(name: Symbol, a: Expr) -> Expr {
        Expr::intern(Node::Apply(name, a))
    }

    /// sin(self).
    pub fn sin(self) -> Expr {
        Expr::apply(Func::Sin, self)
    }
    /// cos(self).
    pub fn cos(self) -> Expr {
        Expr::apply(Func::Cos, self)
    }
    /// tan(self).
    pub fn tan(self) -> Expr {
        Expr::apply(Func::Tan, self)
    }
    /// exp(self).
    pub fn exp(self) -> Expr {
        Expr::apply(Func::Exp, self)
    }
    /// ln(self).
    pub fn ln(self) -> Expr {
        Expr::apply(Func::Ln, self)
    }
    /// abs(self).
    pub fn abs(self) -> Expr {
        Expr::apply(Func::Abs, self)
    }

    /// Sum of many expressions.
    pub fn sum<I: IntoIterator<Item = Expr>>(items: I) -> Expr {
        Expr::make_add(Rat::zero(), items.into_iter().map(|e| (e, Rat::one())).collect())
    }

    /// Product of many expressions.
    pub fn product<I: IntoIterator<Item = Expr>>(items: I) -> Expr {
        Expr::make_mul(Rat::one(), items.into_iter().map(|e| (e, Rat::one())).collect())
    }

    /// Children of this node (arguments, terms, factor bases).
    pub fn children(self) -> Vec<Expr> {
        match &*self.node() {
            Node::Num(_) | Node::Sym(_) => vec![],
            Node::Add { terms, .. } => terms.iter().map(|(t, _)| *t).collect(),
            Node::Mul { factors, .. } => factors.iter().map(|(b, _)| *b).collect(),
            Node::Fun(_, a) | Node::Apply(_, a) => vec![*a],
        }
    }

    /// Rebuilds this node with each child mapped by `f` (canonicalizing again).
    pub fn map_children(self, mut f: impl FnMut(Expr) -> Expr) -> Expr {
        match &*self.node() {
            Node::Num(_) | Node::Sym(_) => self,
            Node::Add { constant, terms } => {
                Expr::make_add(constant.clone(), terms.iter().map(|(t, c)| (f(*t), c.clone())).collect())
            }
            Node::Mul { coefficient, factors } => Expr::make_mul(
                coefficient.clone(),
                factors.iter().map(|(b, e)| (f(*b), e.clone())).collect(),
            ),
            Node::Fun(func, a) => Expr::apply(*func, f(*a)),
            Node::Apply(name, a) => Expr::apply_named(*name, f(*a)),
        }
    }

    /// Number of distinct nodes in the DAG below (and including) this expression.
    pub fn dag_size(self) -> usize {
        let mut seen = std::collections::HashSet::new();
        let mut stack = vec![self];
        while let Some(e) = stack.pop() {
            if seen.insert(e) {
                stack.extend(e.children());
            }
        }
        seen.len()
    }

    /// All symbols occurring in the expression, sorted by name.
    pub fn free_symbols(self) -> Vec<Symbol> {
        let mut seen = std::collections::HashSet::new();
        let mut syms = std::collections::BTreeSet::new();
        let mut stack = vec![self];
        while let Some(e) = stack.pop() {
            if !seen.insert(e) {
                continue;
            }
            match &*e.node() {
                Node::Sym(s) => {
                    syms.insert((s.name(), *s));
                }
                Node::Apply(name, _) => {
                    syms.insert((name.name(), *name));
                    stack.extend(e.children());
                }
                _ => stack.extend(e.children()),
            }
        }
        syms.into_iter().map(|(_, s)| s).collect()
    }

    /// True when `sym` occurs in the expression (exact, not the bloom mask).
    pub fn contains(self, sym: Symbol) -> bool {
        self.may_contain(sym) && self.free_symbols().contains(&sym)
    }
}

pub(crate) fn memo_diff_get(e: Expr, s: Symbol) -> Option<Expr> {
    with_pool(|p| p.diff_memo.get(&(e, s)).copied())
}

pub(crate) fn memo_diff_put(e: Expr, s: Symbol, d: Expr) {
    with_pool(|p| {
        p.diff_memo.insert((e, s), d);
    })
}

impl std::ops::Add for Expr {
    type Output = Expr;
    fn add(self, o: Expr) -> Expr {
        Expr::make_add(Rat::zero(), vec![(self, Rat::one()), (o, Rat::one())])
    }
}
impl std::ops::Sub for Expr {
    type Output = Expr;
    fn sub(self, o: Expr) -> Expr {
        Expr::make_add(Rat::zero(), vec![(self, Rat::one()), (o, -Rat::one())])
    }
}
impl std::ops::Mul for Expr {
    type Output = Expr;
    fn mul(self, o: Expr) -> Expr {
        if let Some(r) = self.as_num() {
            return o.scale(&r);
        }
        if let Some(r) = o.as_num() {
            return self.scale(&r);
        }
        Expr::make_mul(Rat::one(), vec![(self, Rat::one()), (o, Rat::one())])
    }
}
impl std::ops::Div for Expr {
    type Output = Expr;
    fn div(self, o: Expr) -> Expr {
        if let Some(r) = o.as_num()
            && !r.is_zero()
        {
            return self.scale(&r.recip());
        }
        self * o.recip()
    }
}
impl std::ops::Neg for Expr {
    type Output = Expr;
    fn neg(self) -> Expr {
        self.scale(&-Rat::one())
    }
}
impl std::ops::Add<i64> for Expr {
    type Output = Expr;
    fn add(self, o: i64) -> Expr {
        self + Expr::int(o)
    }
}
impl std::ops::Sub<i64> for Expr {
    type Output = Expr;
    fn sub(self, o: i64) -> Expr {
        self - Expr::int(o)
    }
}
impl std::ops::Mul<i64> for Expr {
    type Output = Expr;
    fn mul(self, o: i64) -> Expr {
        self.scale(&rat_from_i64(o))
    }
}
impl std::ops::Div<i64> for Expr {
    type Output = Expr;
    fn div(self, o: i64) -> Expr {
        self / Expr::int(o)
    }
}
impl std::ops::AddAssign for Expr {
    fn add_assign(&mut self, o: Expr) {
        *self = *self + o;
    }
}
impl std::iter::Sum for Expr {
    fn sum<I: Iterator<Item = Expr>>(iter: I) -> Expr {
        Expr::sum(iter)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn like_terms_collect_and_cancel() {
        let x = Expr::sym("x");
        let y = Expr::sym("y");
        assert_eq!(x + y, y + x);
        assert!((x + y - x - y).is_zero());
        assert_eq!(x * y * x, x.powi(2) * y);
        assert_eq!((x * y) / (y * x), Expr::one());
        assert_eq!(x * 2 + x * 3, x * 5);
    }

    #[test]
    fn numbers_fold() {
        assert_eq!(Expr::int(2) * Expr::int(3) + Expr::int(1), Expr::int(7));
        assert_eq!(Expr::int(4).sqrt(), Expr::int(2));
        assert_eq!(Expr::int(2).sqrt().tree_size(), 2);
        assert_eq!(Expr::int(2).powi(-2), Expr::num(Rat::new(1.into(), 4.into())));
    }

    #[test]
    fn odd_and_even_functions_take_canonical_sign() {
        let x = Expr::sym("x");
        assert_eq!((-x).sin(), -(x.sin()));
        assert_eq!((-x).cos(), x.cos());
        assert!(Expr::zero().sin().is_zero());
    }

    #[test]
    fn key_is_independent_of_creation_order() {
        let a = Expr::sym("key_a_zz") + Expr::sym("key_b_zz");
        let k = a.key();
        let b = Expr::sym("key_b_zz") + Expr::sym("key_a_zz");
        assert_eq!(k, b.key());
    }
}
