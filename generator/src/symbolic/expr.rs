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
use rustc_hash::FxHashMap;
use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::sync::atomic::{AtomicU32, AtomicUsize, Ordering as AtomicOrdering};

/// The most distinct expression nodes one context may hold unless raised ([`set_max_nodes`]):
/// a bound on the memory a derivation takes, well above what the largest documented models need
/// (a 50-link chain holds about 0.4 million in its deriving context, 0.5 GB in all), and
/// reached within seconds by a model far larger (a 200-link chain), long before the machine's
/// memory is gone.
pub const DEFAULT_MAX_NODES: usize = 1_000_000;

static MAX_NODES: AtomicUsize = AtomicUsize::new(DEFAULT_MAX_NODES);

/// Sets the node budget of every context (the command lines' `--max-nodes`).
pub fn set_max_nodes(limit: usize) {
    MAX_NODES.store(limit.max(1), AtomicOrdering::Relaxed);
}

/// The node budget in force.
pub fn max_nodes() -> usize {
    MAX_NODES.load(AtomicOrdering::Relaxed)
}

/// A context's node budget, spent: the library's entry points ([`catch_budget`]) return a
/// located error naming it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodeBudgetSpent {
    pub limit: usize,
}

thread_local! {
    /// The budget a context on this thread spent, since [`catch_budget`] last looked.
    static SPENT: Cell<Option<usize>> = const { Cell::new(None) };
}

/// True (and cleared) when a context on this thread spent its node budget since the last
/// look: for a thread of a derivation's own, which reports it as its caller's
/// [`catch_budget`] would.
pub fn take_spent() -> Option<NodeBudgetSpent> {
    SPENT.with(|s| s.take()).map(|limit| NodeBudgetSpent { limit })
}

/// Runs `f`; a node budget spent inside it (on this thread) comes back as `Err`. A spent
/// budget does not unwind: every new node is one placeholder from then on, so `f` runs to its
/// end cheaply and its result is dropped. A panic inside `f` after the budget was spent (a
/// stage that met the placeholder where it expected a number) is reported as the budget too.
pub fn catch_budget<R>(f: impl FnOnce() -> R) -> Result<R, NodeBudgetSpent> {
    let before = take_spent();
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    let spent = take_spent();
    if let Some(b) = before {
        SPENT.with(|s| s.set(Some(b.limit)));
    }
    match (result, spent) {
        (_, Some(spent)) => Err(spent),
        (Ok(r), None) => Ok(r),
        (Err(payload), None) => std::panic::resume_unwind(payload),
    }
}

/// A command line's budget: `--max-nodes` when given.
pub fn budget_for_command_line(max_nodes: Option<u64>) {
    if let Some(n) = max_nodes {
        set_max_nodes(usize::try_from(n).unwrap_or(usize::MAX));
    }
}

/// An interned symbol name (coordinate, velocity, parameter, time, ...), meaningful in the
/// [`Context`] that made it, as an [`Expr`] is: reading one in another context panics with a
/// clear message instead of reading another symbol's name.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, PartialOrd, Ord)]
pub struct Symbol {
    pub(crate) id: u32,
    pub(crate) cx: u32,
}

/// An expression: an id into the current [`Context`].
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
pub struct Expr {
    pub(crate) id: u32,
    pub(crate) cx: u32,
}

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

impl Node {
    /// The `i`-th child (a sum's term, a product's base, a function's argument), if any.
    fn child(&self, i: usize) -> Option<Expr> {
        match self {
            Node::Num(_) | Node::Sym(_) => None,
            Node::Add { terms: items, .. } | Node::Mul { factors: items, .. } => items.get(i).map(|(e, _)| *e),
            Node::Fun(_, a) | Node::Apply(_, a) => (i == 0).then_some(*a),
        }
    }
}

struct Pool {
    /// Distinguishes this pool's expressions from another context's.
    id: u32,
    nodes: Vec<Rc<Node>>,
    keys: Vec<u64>,
    masks: Vec<u128>,
    sizes: Vec<u32>,
    depths: Vec<u32>,
    /// Every node's id, found by the node's structural key (`keys`, computed once per node): a
    /// lookup hashes a new node by its children's keys, and growing the table rehashes nothing
    /// (a map keyed by the node itself hashed every node again at each growth, 8 % of the
    /// 100-link pendulum's derivation, `perf`).
    map: hashbrown::HashTable<u32>,
    names: Vec<String>,
    name_map: FxHashMap<String, Symbol>,
    diff_memo: FxHashMap<(Expr, Symbol), Expr>,
    /// The node every request for a new node returns once the budget is spent.
    spent: Option<u32>,
}

static NEXT_CONTEXT: AtomicU32 = AtomicU32::new(1);

impl Pool {
    fn new() -> Pool {
        Pool {
            id: NEXT_CONTEXT.fetch_add(1, AtomicOrdering::Relaxed),
            nodes: Vec::new(),
            keys: Vec::new(),
            masks: Vec::new(),
            sizes: Vec::new(),
            depths: Vec::new(),
            map: hashbrown::HashTable::new(),
            names: Vec::new(),
            name_map: FxHashMap::default(),
            diff_memo: FxHashMap::default(),
            spent: None,
        }
    }
}

thread_local! {
    /// The context expressions are built in: the thread's default one, or the one a caller
    /// entered with [`Context::enter`].
    static CURRENT: RefCell<Rc<RefCell<Pool>>> = RefCell::new(Rc::new(RefCell::new(Pool::new())));
}

fn with_pool<R>(f: impl FnOnce(&mut Pool) -> R) -> R {
    CURRENT.with(|c| f(&mut c.borrow().borrow_mut()))
}

/// An expression context: the arena that owns every expression built while it is entered,
/// with its memo tables. Dropping it frees them all, so a library user can derive a model,
/// emit it, and drop the memory. Expressions are only meaningful in the context that built
/// them; using one in another context panics with a clear message instead of reading the
/// wrong node.
///
/// Each thread has a default context, used when none is entered (tests and small tools).
///
/// ```
/// use generator::symbolic::{Context, Expr};
/// let cx = Context::new();
/// let size = cx.enter(|| (Expr::sym("x").sin() + 1).dag_size());
/// assert_eq!(size, 3); // the sum, sin(x), x
/// assert!(cx.nodes() >= 3);
/// drop(cx); // frees every node built above
/// ```
pub struct Context {
    pool: Rc<RefCell<Pool>>,
}

impl Default for Context {
    fn default() -> Self {
        Context::new()
    }
}

impl Context {
    /// A new, empty context.
    pub fn new() -> Context {
        Context { pool: Rc::new(RefCell::new(Pool::new())) }
    }

    /// Runs `f` with this context as the current one (restored afterwards, also on panic).
    pub fn enter<R>(&self, f: impl FnOnce() -> R) -> R {
        struct Restore(Option<Rc<RefCell<Pool>>>);
        impl Drop for Restore {
            fn drop(&mut self) {
                if let Some(p) = self.0.take() {
                    CURRENT.with(|c| *c.borrow_mut() = p);
                }
            }
        }
        let previous = CURRENT.with(|c| std::mem::replace(&mut *c.borrow_mut(), self.pool.clone()));
        let _restore = Restore(Some(previous));
        f()
    }

    /// Number of distinct nodes interned so far.
    pub fn nodes(&self) -> usize {
        self.pool.borrow().nodes.len()
    }

    /// Number of distinct nodes in the current context (the thread's default one, or the one
    /// entered).
    pub fn current_nodes() -> usize {
        with_pool(|p| p.nodes.len())
    }

    /// Frees the current context's memo of derivatives (a cache: a derivative taken again is
    /// computed again, to the same node), keeping every node.
    pub fn forget_derivatives() {
        with_pool(|p| p.diff_memo = FxHashMap::default());
    }
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
    let (a, b) = r.stable_words();
    mix(mix(0x7A7, a), b)
}

impl Pool {
    fn check(&self, e: Expr) -> usize {
        assert!(e.cx == self.id, "an expression was used outside the context that built it");
        e.id as usize
    }

    fn check_symbol(&self, s: Symbol) -> usize {
        assert!(s.cx == self.id, "a symbol was used outside the context that made it");
        s.id as usize
    }

    fn intern(&mut self, node: Node) -> Expr {
        let summary = self.summarize(&node);
        // The key first: it is beside the others, where the node is behind a pointer.
        if let Some(&id) = self.map.find(summary.0, |&id| self.keys[id as usize] == summary.0 && *self.nodes[id as usize] == node) {
            return Expr { id, cx: self.id };
        }
        if self.nodes.len() >= max_nodes() {
            // Spent: no new node. Every request from now on gets one placeholder symbol, so the
            // work goes on cheaply to its end, where the caller's [`catch_budget`] reports the
            // budget (no unwinding: a library under `panic = "abort"` gets the error too).
            SPENT.with(|s| s.set(Some(max_nodes())));
            if let Some(id) = self.spent {
                return Expr { id, cx: self.id };
            }
            let placeholder = Node::Sym(self.symbol(&format!("{INTERNAL}node budget spent")));
            let summary = self.summarize(&placeholder);
            let id = self.push(placeholder, summary);
            self.spent = Some(id);
            return Expr { id, cx: self.id };
        }
        let id = self.push(node, summary);
        Expr { id, cx: self.id }
    }

    /// Stores a new node with its [`Pool::summarize`] summary.
    fn push(&mut self, node: Node, (key, mask, size, depth): (u64, u128, u32, u32)) -> u32 {
        let id = self.nodes.len() as u32;
        self.nodes.push(Rc::new(node));
        self.keys.push(key);
        self.masks.push(mask);
        self.sizes.push(size);
        self.depths.push(depth);
        let keys = &self.keys;
        self.map.insert_unique(key, id, |&other| keys[other as usize]);
        id
    }

    /// Structural key (independent of creation order), free-symbol mask, tree size, depth.
    fn summarize(&self, node: &Node) -> (u64, u128, u32, u32) {
        let k = |e: &Expr| self.keys[self.check(*e)];
        let m = |e: &Expr| self.masks[self.check(*e)];
        let s = |e: &Expr| self.sizes[self.check(*e)];
        let d = |e: &Expr| self.depths[self.check(*e)];
        match node {
            Node::Num(r) => (mix(1, hash_rat(r)), 0, 1, 1),
            Node::Sym(sym) => (mix(2, hash_str(&self.names[self.check_symbol(*sym)])), 1u128 << (sym.id % 128), 1, 1),
            Node::Add { constant, terms } | Node::Mul { coefficient: constant, factors: terms } => {
                let tag = if matches!(node, Node::Add { .. }) { 3 } else { 4 };
                let mut h = mix(tag, hash_rat(constant));
                let mut mask = 0;
                let mut size = 1u32;
                let mut depth = 0;
                for (e, c) in terms {
                    h = mix(mix(h, k(e)), hash_rat(c));
                    mask |= m(e);
                    size = size.saturating_add(s(e));
                    depth = depth.max(d(e));
                }
                (h, mask, size, depth + 1)
            }
            Node::Fun(f, a) => (mix(mix(5, *f as u64), k(a)), m(a), s(a).saturating_add(1), d(a) + 1),
            Node::Apply(name, a) => {
                (mix(mix(6, hash_str(&self.names[self.check_symbol(*name)])), k(a)), m(a) | (1u128 << (name.id % 128)), s(a).saturating_add(1), d(a) + 1)
            }
        }
    }

    fn symbol(&mut self, name: &str) -> Symbol {
        if let Some(&s) = self.name_map.get(name) {
            return s;
        }
        let s = Symbol { id: self.names.len() as u32, cx: self.id };
        self.names.push(name.to_string());
        self.name_map.insert(name.to_string(), s);
        s
    }
}

/// The mark that keeps internal symbols apart from a model's: a character no identifier has.
const INTERNAL: char = '\u{1}';

impl Symbol {
    /// Interns a symbol name.
    pub fn new(name: &str) -> Symbol {
        with_pool(|p| p.symbol(name))
    }
    /// Interns a symbol of the generator's own (a quasi-velocity `u1`, a momentum `G_x`): it
    /// prints as `name` but is never the symbol a model file's `name` parses to, so a
    /// parameter called `u1` cannot alias a quasi-velocity.
    ///
    /// ```
    /// use generator::symbolic::Symbol;
    /// let internal = Symbol::internal("u1");
    /// assert_ne!(internal, Symbol::new("u1"));
    /// assert_eq!(internal.name(), "u1");
    /// assert_eq!(internal, Symbol::internal("u1"));
    /// ```
    pub fn internal(name: &str) -> Symbol {
        with_pool(|p| p.symbol(&format!("{INTERNAL}{name}")))
    }
    /// The symbol's name (without the mark of an internal symbol).
    pub fn name(self) -> String {
        with_pool(|p| {
            let n = &p.names[p.check_symbol(self)];
            n.strip_prefix(INTERNAL).unwrap_or(n).to_string()
        })
    }
    /// The name as interned (an internal symbol's with its mark): what
    /// [`Symbol::from_interned_name`] takes back, in any context.
    pub(crate) fn interned_name(self) -> String {
        with_pool(|p| p.names[p.check_symbol(self)].clone())
    }
    /// The symbol whose [`Symbol::interned_name`] is `name`, in the current context.
    pub(crate) fn from_interned_name(name: &str) -> Symbol {
        with_pool(|p| p.symbol(name))
    }
    /// True for a symbol made by [`Symbol::internal`].
    pub fn is_internal(self) -> bool {
        with_pool(|p| p.names[p.check_symbol(self)].starts_with(INTERNAL))
    }
    /// The symbol as an expression.
    pub fn expr(self) -> Expr {
        with_pool(|p| p.intern(Node::Sym(self)))
    }
}

/// Largest integer power of a number folded into a coefficient: beyond it the exact value would
/// cost more than it is worth (`2^1000000` has 300,000 digits), so the power stays symbolic.
pub const MAX_FOLDED_POWER: u32 = 64;

/// The exponent as a small integer power that may be folded into a number.
fn small_power(e: &Rat) -> Option<i32> {
    e.to_i32().filter(|p| p.unsigned_abs() <= MAX_FOLDED_POWER)
}

/// Sorts `(expr, rational)` pairs by structural key and merges equal exprs by adding the
/// rationals; drops pairs whose rational becomes zero.
fn merge_pairs(pairs: Vec<(Expr, Rat)>) -> Vec<(Expr, Rat)> {
    // Each pair with its sort key, in one vector (sorted in place, merged in one pass).
    let mut keyed: Vec<((u64, u32), (Expr, Rat))> = with_pool(|p| pairs.into_iter().map(|(e, c)| ((p.keys[p.check(e)], e.id), (e, c))).collect());
    keyed.sort_unstable_by_key(|(k, _)| *k);
    let mut out: Vec<(Expr, Rat)> = Vec::with_capacity(keyed.len());
    for (_, (e, c)) in keyed {
        match out.last_mut() {
            Some((last, acc)) if *last == e => *acc += c,
            _ => out.push((e, c)),
        }
    }
    out.retain(|(_, c)| !c.is_zero());
    out
}

impl Expr {
    /// Interns a node as it is (no canonicalization): for the constructors below, and for
    /// nodes already canonical in another context ([`super::transfer`]).
    pub(crate) fn intern(node: Node) -> Expr {
        with_pool(|p| p.intern(node))
    }

    /// The node behind this expression.
    pub fn node(self) -> Rc<Node> {
        with_pool(|p| p.nodes[p.check(self)].clone())
    }

    /// Structural key: equal for equal expressions in any pool, used for canonical order.
    pub fn key(self) -> u64 {
        with_pool(|p| p.keys[p.check(self)])
    }

    /// Tree size (number of nodes counted with repetition, saturating).
    pub fn tree_size(self) -> u32 {
        with_pool(|p| p.sizes[p.check(self)])
    }

    /// Length of the longest chain of nested operations below (and including) this node.
    pub fn depth(self) -> u32 {
        with_pool(|p| p.depths[p.check(self)])
    }

    /// A stable id within this context (creation order): a tie-break for sorting.
    pub fn id(self) -> u32 {
        self.id
    }

    /// A bloom mask of the free symbols: if `sym` may occur, its bit is set.
    pub fn mask(self) -> u128 {
        with_pool(|p| p.masks[p.check(self)])
    }

    /// True when `sym` might occur in the expression (never false when it does).
    pub fn may_contain(self, sym: Symbol) -> bool {
        self.mask() & (1u128 << (sym.id % 128)) != 0
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
            Node::Mul { coefficient, factors } if !coefficient.is_one() => (coefficient.clone(), Expr::make_mul(Rat::one(), factors.clone())),
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
                    } else if let Some(p) = small_power(&e) {
                        coefficient *= r.pow(p);
                    } else {
                        flat.push((b, e));
                    }
                }
                Node::Mul { coefficient: k, factors: fs } if small_power(&e).is_some() => {
                    let p = small_power(&e).expect("checked");
                    coefficient *= k.pow(p);
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
        let keep = || Expr::make_mul(Rat::one(), vec![(self, exponent.clone())]);
        match &*self.node() {
            Node::Num(r) if !exponent.is_integer() && !r.is_negative() => {
                // Exact roots of perfect powers: sqrt(4) = 2, (8/27)^(2/3) = 4/9.
                let q = exponent.denom().to_string().parse::<u32>().unwrap_or(0);
                let p = exponent.numer().to_string().parse::<i32>().ok();
                match (r.exact_root(q), p) {
                    (Some(root), Some(p)) if !(root.is_zero() && p < 0) && p.unsigned_abs() <= MAX_FOLDED_POWER => Expr::num(root.pow(p)),
                    _ => keep(),
                }
            }
            Node::Num(r) if exponent.is_integer() => match small_power(exponent) {
                Some(p) if !(r.is_zero() && p < 0) => Expr::num(r.pow(p)),
                _ => keep(),
            },
            Node::Mul { coefficient, factors } if factors.len() == 1 && coefficient.is_one() && !exponent.is_integer() => {
                // (b^e1)^e2 = b^(e1 e2) is safe when e1 is an odd integer (the sign of b^e1 is
                // the sign of b); otherwise keep the nested power.
                let (b, e1) = &factors[0];
                if e1.to_i64().is_some_and(|n| n % 2 != 0) { Expr::make_mul(Rat::one(), vec![(*b, e1 * exponent)]) } else { keep() }
            }
            _ => keep(),
        }
    }

    /// `self ^ n` for an integer exponent.
    pub fn powi(self, n: i64) -> Expr {
        self.pow_rat(&rat_from_i64(n))
    }

    /// Square root.
    pub fn sqrt(self) -> Expr {
        self.pow_rat(&Rat::frac(1, 2))
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
            Node::Add { constant, terms } => Expr::make_add(constant.clone(), terms.iter().map(|(t, c)| (f(*t), c.clone())).collect()),
            Node::Mul { coefficient, factors } => Expr::make_mul(coefficient.clone(), factors.iter().map(|(b, e)| (f(*b), e.clone())).collect()),
            Node::Fun(func, a) => Expr::apply(*func, f(*a)),
            Node::Apply(name, a) => Expr::apply_named(*name, f(*a)),
        }
    }

    /// [`Expr::map_children`], but the node itself when `f` changes no child: no rebuild, so
    /// no sorting and interning (and no re-canonicalization of a node built another way).
    ///
    /// ```
    /// use generator::symbolic::Expr;
    /// let (x, y) = (Expr::sym("x"), Expr::sym("y"));
    /// let e = x.sin() + y;
    /// assert_eq!(e.map_children_or_self(|c| c), e);
    /// assert_eq!(e.map_children_or_self(|c| if c == y { x } else { c }), x.sin() + x);
    /// ```
    pub fn map_children_or_self(self, mut f: impl FnMut(Expr) -> Expr) -> Expr {
        let children = self.children();
        let mapped: Vec<Expr> = children.iter().map(|c| f(*c)).collect();
        if mapped == children {
            return self;
        }
        let mut each = mapped.into_iter();
        self.map_children(|_| each.next().expect("one mapped child per child"))
    }

    /// Every node below (and including) this expression, children before parents, each once.
    pub fn post_order_nodes(self) -> Vec<Expr> {
        post_order(&[self])
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
        self.symbols_and_applied().0
    }

    /// [`Expr::free_symbols`], and those of them the expression applies as named functions
    /// (`F` in `F(t)`): one walk for both.
    ///
    /// ```
    /// use generator::symbolic::{Expr, Symbol};
    /// let (f, t, a) = (Symbol::new("F"), Expr::sym("t"), Expr::sym("a"));
    /// let e = Expr::apply_named(f, t * 2) * a + t.sin();
    /// let (symbols, applied) = e.symbols_and_applied();
    /// assert_eq!(symbols, e.free_symbols());
    /// assert_eq!(symbols.iter().map(|s| s.name()).collect::<Vec<_>>(), ["F", "a", "t"]);
    /// assert_eq!(applied.into_iter().collect::<Vec<_>>(), [f]);
    /// ```
    pub fn symbols_and_applied(self) -> (Vec<Symbol>, rustc_hash::FxHashSet<Symbol>) {
        let mut seen = std::collections::HashSet::new();
        let mut syms = std::collections::BTreeSet::new();
        let mut applied = rustc_hash::FxHashSet::default();
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
                    applied.insert(*name);
                    stack.extend(e.children());
                }
                _ => stack.extend(e.children()),
            }
        }
        (syms.into_iter().map(|(_, s)| s).collect(), applied)
    }

    /// True when `sym` occurs in the expression (exact, not the bloom mask).
    pub fn contains(self, sym: Symbol) -> bool {
        any_contains(&[self], sym)
    }
}

/// True when `sym` occurs in any of `exprs`: one walk over their shared DAG, which skips every
/// node whose bloom mask rules the symbol out (so a symbol that occurs nowhere costs one mask
/// test per root, whatever the expressions' size).
pub fn any_contains(exprs: &[Expr], sym: Symbol) -> bool {
    let mut seen = rustc_hash::FxHashSet::default();
    let mut stack: Vec<Expr> = exprs.iter().copied().filter(|e| e.may_contain(sym)).collect();
    while let Some(e) = stack.pop() {
        if !seen.insert(e) {
            continue;
        }
        match &*e.node() {
            Node::Sym(s) if *s == sym => return true,
            Node::Apply(name, _) if *name == sym => return true,
            _ => stack.extend(e.children().into_iter().filter(|c| c.may_contain(sym))),
        }
    }
    false
}

/// Every node reachable from `outputs`, children before parents, each once, in a depth-first
/// order that follows the outputs' order and the canonical child order (so it never depends on
/// how the expressions were built). Iterative: deep expressions do not exhaust the stack.
pub fn post_order(outputs: &[Expr]) -> Vec<Expr> {
    post_order_pruned(outputs, |_| false)
}

/// [`post_order`] without the nodes `known` accepts, nor anything below them: for memo tables
/// that hold a node only once they hold everything it is built from, this lists exactly what
/// they lack, in the order [`post_order`] would visit it, without walking what they have.
pub fn post_order_pruned(outputs: &[Expr], mut known: impl FnMut(Expr) -> bool) -> Vec<Expr> {
    let mut seen = rustc_hash::FxHashSet::default();
    let mut order = Vec::new();
    for &root in outputs {
        if known(root) || !seen.insert(root) {
            continue;
        }
        // (node, its node, next child index): the children read in place, not collected.
        let mut stack: Vec<(Expr, Rc<Node>, usize)> = vec![(root, root.node(), 0)];
        while let Some((node, held, next)) = stack.last_mut() {
            if let Some(c) = held.child(*next) {
                *next += 1;
                if !known(c) && seen.insert(c) {
                    stack.push((c, c.node(), 0));
                }
            } else {
                order.push(*node);
                stack.pop();
            }
        }
    }
    order
}

/// The operations it takes to evaluate `outputs` with every shared node computed once: per
/// distinct node, one addition per term beyond the first, one multiplication per factor beyond
/// the first and per coefficient other than +-1, one per integer power, one per call. An
/// estimate of emitted cost that, unlike a node count, sees the size of sums and products.
pub fn dag_ops(outputs: &[Expr]) -> usize {
    post_order(outputs)
        .into_iter()
        .map(|e| match &*e.node() {
            Node::Num(_) | Node::Sym(_) => 0,
            Node::Add { constant, terms } => terms.len() - 1 + usize::from(!constant.is_zero()) + terms.iter().filter(|(_, c)| !c.abs().is_one()).count(),
            Node::Mul { coefficient, factors } => {
                factors.len() - 1 + usize::from(!coefficient.abs().is_one()) + factors.iter().filter(|(_, x)| !x.is_one()).count()
            }
            Node::Fun(..) | Node::Apply(..) => 1,
        })
        .sum()
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

    /// Forgetting the derivatives' memo frees it and changes no answer: a derivative taken
    /// again is the same node, and builds none.
    #[test]
    fn forgetting_the_derivatives_keeps_the_answers_and_builds_no_node() {
        Context::new().enter(|| {
            let (x, y) = (Symbol::new("dx"), Symbol::new("dy"));
            let e = (x.expr() * y.expr()).sin() * x.expr().powi(3);
            let d = e.diff(x);
            assert!(with_pool(|p| !p.diff_memo.is_empty()));
            Context::forget_derivatives();
            assert!(with_pool(|p| p.diff_memo.is_empty()));
            let nodes = Context::current_nodes();
            assert_eq!(e.diff(x), d);
            assert_eq!(Context::current_nodes(), nodes);
        });
    }

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
        assert_eq!(Expr::int(2).powi(-2), Expr::num(Rat::frac(1, 4)));
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

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn any_contains_finds_a_symbol() {
        use crate::symbolic::{Expr, Symbol, expr::any_contains};
        let (x, y) = (Expr::sym("x"), Expr::sym("y"));
        assert!(any_contains(&[x.sin(), y * y], Symbol::new("y")));
        assert!(!any_contains(&[x.sin() * x], Symbol::new("y")));
    }

    #[test]
    fn post_order_pruned_skips_known_nodes() {
        use crate::symbolic::{Expr, expr::post_order_pruned};
        let (x, y) = (Expr::sym("x"), Expr::sym("y"));
        let s = x.sin();
        assert_eq!(post_order_pruned(&[s * y], |e| e == s), vec![y, s * y]);
    }
}
