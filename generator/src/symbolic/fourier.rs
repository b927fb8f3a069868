//! The product-to-sum (Fourier) normal form, and the simplifier built on it.
//!
//! A trigonometric polynomial is held as a sum of `c * m * e^{i k.q}`: `m` a monomial in the
//! non-trigonometric atoms (symbols, and opaque subexpressions such as `1/cos(theta)` or
//! `sqrt(..)`), `k.q` an integer (or rational) combination of angle atoms, `c` a complex
//! rational. Real expressions are conjugate-symmetric, so only the half with the leading `k`
//! positive is stored. A product of two terms is one term (`e^{iA} e^{iB} = e^{i(A+B)}`), so
//! angle sums are never multiplied out into products of single-angle sines and cosines: the
//! mass matrix of a planar chain stays `l_i l_j cos(q_i - q_j) (m_j + ...)` at any length,
//! where expanding is exponential in the length. For polynomials in independent atoms and
//! their sines and cosines the form is canonical.
//!
//! [`Simplifier`] walks a DAG bottom-up, computes each node's form from its children's (under
//! a term budget per node and a work budget per simplifier: past them a node becomes an
//! opaque atom, correct and only less compact), and keeps for each node whichever is smaller:
//! the rebuilt normal form or the node over its children's choices. Memoized across calls, so
//! a whole derivation shares one.
//!
//! ```
//! use generator::symbolic::{Expr, Simplifier};
//! let (a, b, l) = (Expr::sym("a"), Expr::sym("b"), Expr::sym("l"));
//! let mut s = Simplifier::default();
//! let e = l * a.cos() * b.cos() + l * a.sin() * b.sin();
//! assert_eq!(s.simplify(e), l * (a - b).cos());
//! assert_eq!(s.simplify(a.sin().powi(2) + a.cos().powi(2)), Expr::one());
//! ```

use super::expr::{Expr, Func, Node};
use super::number::Rat;
use rustc_hash::FxHashMap;
use std::rc::Rc;

/// A complex rational.
#[derive(Clone, Debug, PartialEq, Default)]
struct C {
    re: Rat,
    im: Rat,
}

impl C {
    fn real(re: Rat) -> C {
        C { re, im: Rat::zero() }
    }
    fn is_zero(&self) -> bool {
        self.re.is_zero() && self.im.is_zero()
    }
    fn mul(&self, o: &C) -> C {
        match (self.im.is_zero(), o.im.is_zero()) {
            (true, true) => C::real(&self.re * &o.re),
            (true, false) => C { re: &self.re * &o.re, im: &self.re * &o.im },
            (false, true) => C { re: &self.re * &o.re, im: &self.im * &o.re },
            (false, false) => C { re: &self.re * &o.re - &self.im * &o.im, im: &self.re * &o.im + &self.im * &o.re },
        }
    }
    fn conj(&self) -> C {
        C { re: self.re.clone(), im: -&self.im }
    }
    fn scale(&self, r: &Rat) -> C {
        C { re: &self.re * r, im: &self.im * r }
    }
    fn add_assign(&mut self, o: &C) {
        if !o.re.is_zero() {
            self.re += &o.re;
        }
        if !o.im.is_zero() {
            self.im += &o.im;
        }
    }
}

/// Sorted `(atom, rational)` pairs with nonzero rationals: a monomial (exponents) or an angle
/// combination (coefficients).
type Pairs = Vec<(Expr, Rat)>;

fn order_key(e: &Expr) -> (u64, u32) {
    (e.key(), e.id())
}

/// `a + sign * b`, merged.
fn merge(a: &Pairs, b: &Pairs, sign: &Rat) -> Pairs {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() || j < b.len() {
        let take_a = j >= b.len() || (i < a.len() && order_key(&a[i].0) < order_key(&b[j].0));
        let take_b = i >= a.len() || (j < b.len() && order_key(&b[j].0) < order_key(&a[i].0));
        if take_a {
            out.push(a[i].clone());
            i += 1;
        } else if take_b {
            out.push((b[j].0, &b[j].1 * sign));
            j += 1;
        } else {
            let c = &a[i].1 + &(&b[j].1 * sign);
            if !c.is_zero() {
                out.push((a[i].0, c));
            }
            i += 1;
            j += 1;
        }
    }
    out
}

/// A normal form: `(monomial id, angle id) -> coefficient`, the angle's leading coefficient
/// positive (or the angle empty).
#[derive(Clone, Debug, Default)]
pub struct Form {
    terms: FxHashMap<(u32, u32), C>,
}

impl Form {
    /// Number of terms (each a monomial times `cos`/`sin` of one angle combination).
    pub fn len(&self) -> usize {
        self.terms.len()
    }

    /// True for the zero form.
    pub fn is_empty(&self) -> bool {
        self.terms.is_empty()
    }

    fn add_term(&mut self, key: (u32, u32), c: C) {
        if c.is_zero() {
            return;
        }
        match self.terms.entry(key) {
            std::collections::hash_map::Entry::Occupied(mut acc) => {
                acc.get_mut().add_assign(&c);
                if acc.get().is_zero() {
                    acc.remove();
                }
            }
            std::collections::hash_map::Entry::Vacant(slot) => {
                slot.insert(c);
            }
        }
    }
}

/// Limits of one [`Simplifier`]. They count terms and term products, never time, so the
/// same input gives the same output on any machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FourierLimits {
    /// Most terms a node's normal form may have; past it the node is kept as an atom.
    pub max_terms: usize,
    /// Most term products the simplifier may compute in all; past it every new node is kept
    /// as it is.
    pub max_work: u64,
    /// Most angle atoms one harmonic may combine: a product that needs more is kept as built.
    /// The sine of a sum of many angles costs more than the products it would replace, and
    /// spatial chains combine every joint angle. Measured on a 20-link chain in relative
    /// coordinates (Kane's assembly): 13320 operations with 3, 17523 with 6, 71404 unlimited;
    /// the absolute-angle chain and the paper's scenes are the same with any of them.
    pub max_angle_atoms: usize,
}

impl Default for FourierLimits {
    fn default() -> Self {
        FourierLimits { max_terms: 1000, max_work: 4_000_000, max_angle_atoms: 3 }
    }
}

/// What a simplifier did, for the summary: how many nodes were kept as they are because a
/// limit was reached.
///
/// ```
/// use generator::symbolic::SimplifyReport;
/// assert_eq!(SimplifyReport::default().summary(), None);
/// let cut = SimplifyReport { over_term_limit: 2, over_angle_limit: 5, ..SimplifyReport::default() };
/// assert_eq!(
///     cut.summary().unwrap(),
///     "2 nodes over the term limit, 5 products combining more angles than one harmonic may (kept as built)"
/// );
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SimplifyReport {
    /// Nodes whose normal form exceeded `max_terms`.
    pub over_term_limit: usize,
    /// Products kept as built because a harmonic of theirs would combine more than
    /// `max_angle_atoms` angles (by design: the sine of such a sum costs more than the product).
    pub over_angle_limit: usize,
    /// True when `max_work` was reached (everything after it was kept as built).
    pub work_limit_reached: bool,
    /// Term products computed.
    pub work: u64,
}

impl SimplifyReport {
    /// One line saying what the limits cut, or `None` when nothing was.
    pub fn summary(&self) -> Option<String> {
        let mut parts = Vec::new();
        if self.over_term_limit > 0 {
            parts.push(format!("{} nodes over the term limit", self.over_term_limit));
        }
        if self.over_angle_limit > 0 {
            parts.push(format!("{} products combining more angles than one harmonic may", self.over_angle_limit));
        }
        if self.work_limit_reached {
            parts.push("work limit reached".to_string());
        }
        (!parts.is_empty()).then(|| format!("{} (kept as built)", parts.join(", ")))
    }
}

/// Why a product of normal forms was not formed.
enum Cut {
    /// The work budget is spent.
    Work,
    /// A harmonic would combine more than `max_angle_atoms` angles.
    Angles,
    /// The product grew past the term limit.
    Terms,
}

/// A node's normal form and the expression chosen for it.
#[derive(Clone)]
struct Entry {
    form: Rc<Form>,
    /// The smaller of the rebuilt normal form and the node over its children's choices.
    chosen: Expr,
}

/// The memoized bottom-up simplifier (see the module docs).
pub struct Simplifier {
    limits: FourierLimits,
    monos: Vec<Pairs>,
    mono_ids: FxHashMap<Pairs, u32>,
    angles: Vec<Pairs>,
    angle_ids: FxHashMap<Pairs, u32>,
    memo: FxHashMap<Expr, Entry>,
    mono_products: FxHashMap<(u32, u32), u32>,
    angle_products: FxHashMap<(u32, u32), ((u32, bool), (u32, bool))>,
    costs: FxHashMap<Expr, u32>,
    report: SimplifyReport,
}

impl Default for Simplifier {
    fn default() -> Self {
        Simplifier::new(FourierLimits::default())
    }
}

/// The cost [`Simplifier`] counts for the sine or cosine of an angle that is not a sum of
/// symbols with integer coefficients (a call).
pub const HARMONIC_COST: u32 = 8;

/// The cost of the sine or cosine of `k1 x1 + k2 x2 + ...` with integer `k` and symbols `x`, as
/// emission computes it from the single angles' sines and cosines: three operations per unit
/// of `|k1| + |k2| + ...` beyond the first.
fn harmonic_cost(arg: Expr) -> Option<u32> {
    let terms: Vec<(Expr, Rat)> = match &*arg.node() {
        Node::Add { constant, terms } if constant.is_zero() => terms.clone(),
        _ => {
            let (k, atom) = arg.split_coefficient();
            vec![(atom, k)]
        }
    };
    let mut units = 0u32;
    for (x, k) in &terms {
        let k = k.to_i64().filter(|_| x.as_sym().is_some())?;
        units = units.saturating_add(k.unsigned_abs().min(64) as u32);
    }
    Some(1 + 3 * units.saturating_sub(1))
}

/// Largest positive integer power expanded by repeated multiplication.
const MAX_EXPANDED_POWER: i64 = 12;

impl Simplifier {
    /// A simplifier with these limits.
    pub fn new(limits: FourierLimits) -> Simplifier {
        let mut s = Simplifier {
            limits,
            monos: Vec::new(),
            mono_ids: FxHashMap::default(),
            angles: Vec::new(),
            angle_ids: FxHashMap::default(),
            memo: FxHashMap::default(),
            mono_products: FxHashMap::default(),
            angle_products: FxHashMap::default(),
            costs: FxHashMap::default(),
            report: SimplifyReport::default(),
        };
        s.mono_id(Vec::new());
        s.angle_id(Vec::new());
        s
    }

    /// What the limits cut so far.
    pub fn report(&self) -> SimplifyReport {
        self.report
    }

    /// Frees the memo of every form computed so far (a cache: later calls compute again what
    /// they need, to the same results), keeping the limits and what they cut.
    pub fn forget(&mut self) {
        let report = self.report;
        *self = Simplifier::new(self.limits);
        self.report = report;
    }

    /// The limits it runs under.
    pub fn limits(&self) -> FourierLimits {
        self.limits
    }

    fn mono_id(&mut self, m: Pairs) -> u32 {
        if let Some(&id) = self.mono_ids.get(&m) {
            return id;
        }
        let id = self.monos.len() as u32;
        self.monos.push(m.clone());
        self.mono_ids.insert(m, id);
        id
    }

    fn angle_id(&mut self, a: Pairs) -> u32 {
        if let Some(&id) = self.angle_ids.get(&a) {
            return id;
        }
        let id = self.angles.len() as u32;
        self.angles.push(a.clone());
        self.angle_ids.insert(a, id);
        id
    }

    fn mono_mul(&mut self, a: u32, b: u32) -> u32 {
        if a == 0 {
            return b;
        }
        if b == 0 {
            return a;
        }
        let key = if a <= b { (a, b) } else { (b, a) };
        if let Some(&m) = self.mono_products.get(&key) {
            return m;
        }
        let m = merge(&self.monos[a as usize], &self.monos[b as usize], &Rat::one());
        let id = self.mono_id(m);
        self.mono_products.insert(key, id);
        id
    }

    /// The canonical angles `A + B` and `A - B` (ids, and whether each was negated), memoized.
    fn angle_sum_difference(&mut self, a: u32, b: u32) -> ((u32, bool), (u32, bool)) {
        if let Some(&r) = self.angle_products.get(&(a, b)) {
            return r;
        }
        let (aa, bb) = (self.angles[a as usize].clone(), self.angles[b as usize].clone());
        let sum = self.canonical_angle(merge(&aa, &bb, &Rat::one()));
        let diff = self.canonical_angle(merge(&aa, &bb, &-Rat::one()));
        self.angle_products.insert((a, b), (sum, diff));
        (sum, diff)
    }

    /// `sign * angle` canonical: the angle id and whether it was negated.
    fn canonical_angle(&mut self, a: Pairs) -> (u32, bool) {
        let negate = a.first().is_some_and(|(_, k)| k.is_negative());
        let a = if negate { a.into_iter().map(|(e, k)| (e, -k)).collect() } else { a };
        (self.angle_id(a), negate)
    }

    /// The form of a single term `c * m * e^{i angle}` (real part taken by symmetry).
    fn single(&mut self, mono: Pairs, angle: Pairs, c: C) -> Form {
        let m = self.mono_id(mono);
        let (a, neg) = self.canonical_angle(angle);
        let mut f = Form::default();
        f.add_term((m, a), if neg { c.conj() } else { c });
        f
    }

    fn constant(&mut self, r: &Rat) -> Form {
        let mut f = Form::default();
        f.add_term((0, 0), C::real(r.clone()));
        f
    }

    fn atom(&mut self, e: Expr, exponent: Rat) -> Form {
        self.single(vec![(e, exponent)], vec![], C::real(Rat::one()))
    }

    fn add_scaled(&self, acc: &mut Form, f: &Form, c: &Rat) {
        for (k, v) in &f.terms {
            acc.add_term(*k, v.scale(c));
        }
    }

    /// The product of two forms (real functions stored by their canonical half).
    fn mul(&mut self, a: &Form, b: &Form) -> Result<Form, Cut> {
        let work = (a.len() * b.len()) as u64;
        self.report.work += work;
        if self.report.work > self.limits.max_work {
            self.report.work_limit_reached = true;
            return Err(Cut::Work);
        }
        let mut out = Form { terms: FxHashMap::with_capacity_and_hasher((a.len() * b.len()).min(64), Default::default()) };
        for (&(ma, ka), ca) in &a.terms {
            for (&(mb, kb), cb) in &b.terms {
                let m = self.mono_mul(ma, mb);
                if ka == 0 || kb == 0 {
                    // e^{i0} is real: one product, still canonical.
                    let k = if ka == 0 { kb } else { ka };
                    let c = if ka == 0 && kb == 0 {
                        C::real(&ca.re * &cb.re)
                    } else if ka == 0 {
                        cb.scale(&ca.re)
                    } else {
                        ca.scale(&cb.re)
                    };
                    out.add_term((m, k), c);
                    continue;
                }
                // (c_a e^{iA} + conj) (c_b e^{iB} + conj) = c_a c_b e^{i(A+B)} + c_a conj(c_b) e^{i(A-B)} + conj.
                let ((sum, neg_s), (diff, neg_d)) = self.angle_sum_difference(ka, kb);
                if self.angles[sum as usize].len() > self.limits.max_angle_atoms || self.angles[diff as usize].len() > self.limits.max_angle_atoms {
                    return Err(Cut::Angles);
                }
                let p = ca.mul(cb);
                out.add_term((m, sum), if neg_s { p.conj() } else { p });
                let q = ca.mul(&cb.conj());
                let q = if diff == 0 {
                    // e^{i0}: the two conjugate halves meet, their sum is 2 Re.
                    C::real(&q.re * Rat::int(2))
                } else if neg_d {
                    q.conj()
                } else {
                    q
                };
                out.add_term((m, diff), q);
            }
            if out.len() > self.limits.max_terms * 4 {
                return Err(Cut::Terms);
            }
        }
        // Terms of e^{i(A+B)} with A + B = 0 cannot occur (both leading positive), so the
        // form is complete; the constant (angle 0) carries its full real value.
        Ok(out)
    }

    /// The angle `form` describes, when it is a linear combination of atoms: `(atom, k)`.
    fn as_angle(&self, f: &Form) -> Option<Pairs> {
        let mut pairs: Pairs = Vec::with_capacity(f.len());
        for (&(m, k), c) in &f.terms {
            if k != 0 || !c.im.is_zero() {
                return None;
            }
            let mono = &self.monos[m as usize];
            let atom = match mono.as_slice() {
                [] => Expr::one(),
                [(a, e)] if e.is_one() => *a,
                _ => return None,
            };
            pairs.push((atom, c.re.clone()));
        }
        pairs.sort_by_key(|(a, _)| order_key(a));
        Some(pairs)
    }

    /// The expression of a form.
    fn rebuild(&self, f: &Form) -> Expr {
        let mut keys: Vec<&(u32, u32)> = f.terms.keys().collect();
        keys.sort();
        let mut terms = Vec::with_capacity(keys.len() * 2);
        for key in keys {
            let c = &f.terms[key];
            let mono = Expr::make_mul(Rat::one(), self.monos[key.0 as usize].clone());
            if key.1 == 0 {
                terms.push((mono, c.re.clone()));
                continue;
            }
            let angle = Expr::make_add(Rat::zero(), self.angles[key.1 as usize].clone());
            // 2 Re(c e^{iA}) = 2 re cos A - 2 im sin A.
            if !c.re.is_zero() {
                terms.push((mono * angle.cos(), &c.re * Rat::int(2)));
            }
            if !c.im.is_zero() {
                terms.push((mono * angle.sin(), &c.im * Rat::int(-2)));
            }
        }
        Expr::make_add(Rat::zero(), terms)
    }

    /// The form of `base ^ x` for an exponent that is not a small positive integer: a number
    /// folded, a single monomial distributed (`(x y)^-1 = x^-1 y^-1`), anything else an atom.
    fn power(&mut self, base: Expr, x: &Rat) -> Form {
        let chosen = self.memo[&base].chosen;
        if let (Some(r), Some(p)) = (chosen.as_num(), x.to_i32())
            && !r.is_zero()
            && p.unsigned_abs() <= crate::symbolic::expr::MAX_FOLDED_POWER
        {
            return self.constant(&r.pow(p));
        }
        let form = self.memo[&base].form.clone();
        if let (Some(p), true) = (x.to_i32(), form.len() == 1) {
            let (&(m, k), c) = form.terms.iter().next().expect("one term");
            if k == 0 && !c.re.is_zero() && p.unsigned_abs() <= crate::symbolic::expr::MAX_FOLDED_POWER {
                let mono: Pairs = self.monos[m as usize].iter().map(|(e, n)| (*e, n * x)).collect();
                return self.single(mono, vec![], C::real(c.re.pow(p)));
            }
        }
        self.atom(chosen, x.clone())
    }

    /// The normal form of `e` (its nodes' forms memoized; see the module docs).
    fn form_of(&mut self, e: Expr) -> Rc<Form> {
        self.simplify(e);
        self.memo[&e].form.clone()
    }

    /// The smaller of `e`'s normal form and `e` over its children's simplified forms.
    pub fn simplify(&mut self, e: Expr) -> Expr {
        if let Some(entry) = self.memo.get(&e) {
            return entry.chosen;
        }
        let memo = &self.memo;
        for node in super::expr::post_order_pruned(&[e], |n| memo.contains_key(&n)) {
            let entry = self.node_entry(node);
            // The result is its own simplified form: the formulations simplify sums of results
            // again (Lagrange's f = Q - dV/dq - h of simplified parts), which otherwise walked
            // every rebuilt node anew (the 50-link pendulum's Lagrange form 426 -> 79 ms).
            if entry.chosen != node {
                let fixpoint = Entry { form: entry.form.clone(), chosen: entry.chosen };
                self.memo.entry(entry.chosen).or_insert(fixpoint);
            }
            self.memo.insert(node, entry);
        }
        self.memo[&e].chosen
    }

    /// Simplifies each.
    pub fn simplify_all(&mut self, items: &[Expr]) -> Vec<Expr> {
        items.iter().map(|e| self.simplify(*e)).collect()
    }

    /// True when the normal form of `e` is zero (exact for trigonometric polynomials; a
    /// nonzero form can still be zero where opaque atoms hide an identity).
    pub fn form_is_zero(&mut self, e: Expr) -> bool {
        self.form_of(e).is_empty()
    }

    /// An estimate of what `e` costs in emitted code, counting shared children each time (a
    /// tree cost, saturating): one per operation, and `HARMONIC_COST` for the sine or cosine of
    /// a combination of angles (a call, or a chain of angle-sum products), where the sine and
    /// cosine of a single angle are computed once per function and cost one.
    pub fn cost(&mut self, e: Expr) -> u32 {
        if let Some(&c) = self.costs.get(&e) {
            return c;
        }
        let costs = &self.costs;
        for node in super::expr::post_order_pruned(&[e], |n| costs.contains_key(&n)) {
            let c = match &*node.node() {
                Node::Num(_) | Node::Sym(_) => 0u32,
                Node::Add { constant, terms } => {
                    let own = terms.len() as u32 - 1 + u32::from(!constant.is_zero()) + terms.iter().filter(|(_, c)| !c.abs().is_one()).count() as u32;
                    terms.iter().fold(own, |acc, (t, _)| acc.saturating_add(self.costs[t]))
                }
                Node::Mul { coefficient, factors } => {
                    let own = factors.len() as u32 - 1 + u32::from(!coefficient.abs().is_one());
                    factors.iter().fold(own, |acc, (b, x)| {
                        let power = if x.is_one() { 0 } else { 1 };
                        acc.saturating_add(self.costs[b]).saturating_add(power)
                    })
                }
                Node::Fun(Func::Sin | Func::Cos, a) if a.as_sym().is_some() => 1,
                Node::Fun(Func::Sin | Func::Cos, a) => harmonic_cost(*a).unwrap_or_else(|| HARMONIC_COST.saturating_add(self.costs[a])),
                Node::Fun(_, a) | Node::Apply(_, a) => self.costs[a].saturating_add(2),
            };
            self.costs.insert(node, c);
        }
        self.costs[&e]
    }

    /// A lower bound of [`Simplifier::cost`] of the rebuilt form, from the form alone.
    fn form_cost(&self, f: &Form) -> u32 {
        let mut c = (f.len() as u32).saturating_sub(1);
        for (&(m, k), coef) in &f.terms {
            let factors = self.monos[m as usize].len() as u32 + u32::from(k != 0);
            c = c.saturating_add(factors.saturating_sub(1));
            if k != 0 {
                let units: i64 = self.angles[k as usize].iter().map(|(_, x)| x.to_i64().map_or(2, |n| n.abs())).sum();
                c = c.saturating_add(1 + 3 * (units.max(1) as u32 - 1));
                if !coef.re.is_zero() && !coef.im.is_zero() {
                    c = c.saturating_add(2);
                }
            }
        }
        c
    }

    fn node_entry(&mut self, e: Expr) -> Entry {
        let direct = e.map_children_or_self(|c| self.memo[&c].chosen);
        let opaque = |s: &mut Simplifier, direct: Expr| {
            let form = Rc::new(match direct.as_num() {
                Some(r) => s.constant(&r),
                None => s.atom(direct, Rat::one()),
            });
            Entry { form, chosen: direct }
        };
        if self.report.work_limit_reached {
            return opaque(self, direct);
        }
        let form = match &*e.node() {
            Node::Num(r) => self.constant(r),
            Node::Sym(_) => self.atom(e, Rat::one()),
            Node::Add { constant, terms } => {
                let mut acc = self.constant(constant);
                for (t, c) in terms {
                    let f = self.memo[t].form.clone();
                    self.add_scaled(&mut acc, &f, c);
                }
                acc
            }
            Node::Mul { coefficient, factors } => {
                let mut acc = self.constant(coefficient);
                let mut cut = None;
                for (b, x) in factors {
                    let power = x.to_i64().filter(|n| (1..=MAX_EXPANDED_POWER).contains(n));
                    let fb = match power {
                        Some(_) => self.memo[b].form.clone(),
                        None => Rc::new(self.power(*b, x)),
                    };
                    for _ in 0..power.unwrap_or(1) {
                        match self.mul(&acc, &fb) {
                            Ok(f) => acc = f,
                            Err(why) => {
                                cut = Some(why);
                                break;
                            }
                        }
                    }
                    if cut.is_none() && acc.len() > self.limits.max_terms {
                        cut = Some(Cut::Terms);
                    }
                    if cut.is_some() {
                        break;
                    }
                }
                if let Some(why) = cut {
                    match why {
                        Cut::Terms => self.report.over_term_limit += 1,
                        Cut::Angles => self.report.over_angle_limit += 1,
                        // Reported once, by `work_limit_reached`.
                        Cut::Work => {}
                    }
                    return opaque(self, direct);
                }
                acc
            }
            Node::Fun(f @ (Func::Sin | Func::Cos), a) => {
                let fa = self.memo[a].form.clone();
                match self.as_angle(&fa) {
                    Some(angle) if angle.is_empty() => self.constant(&Rat::int(i64::from(*f == Func::Cos))),
                    Some(angle) if angle.iter().any(|(x, _)| !x.is_one()) => {
                        let c = if *f == Func::Cos {
                            C::real(Rat::frac(1, 2))
                        } else {
                            // sin A = Re(-i e^{iA}) * 2 / 2: coefficient -i/2.
                            C { re: Rat::zero(), im: Rat::frac(-1, 2) }
                        };
                        self.single(vec![], angle, c)
                    }
                    _ => self.atom(direct, Rat::one()),
                }
            }
            _ => self.atom(direct, Rat::one()),
        };
        if form.len() > self.limits.max_terms {
            self.report.over_term_limit += 1;
            return opaque(self, direct);
        }
        // Rebuilding costs as much as the form is large: only when it can win.
        let direct_cost = self.cost(direct);
        let chosen = if self.form_cost(&form) <= direct_cost {
            let rebuilt = self.rebuild(&form);
            if self.cost(rebuilt) <= direct_cost { rebuilt } else { direct }
        } else {
            direct
        };
        Entry { form: Rc::new(form), chosen }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::symbolic::eval::Env;
    use crate::symbolic::zero::zero_test;

    #[test]
    fn angle_sums_stay_sums() {
        let mut s = Simplifier::default();
        let qs: Vec<Expr> = (0..3).map(|i| Expr::sym(&format!("fq{i}"))).collect();
        // cos and sin of q0 + q1 + q2 built by the angle-sum formulas: 4 products each; the
        // normal form is one term.
        let (mut sn, mut cs) = (qs[0].sin(), qs[0].cos());
        for q in &qs[1..] {
            let ns = sn * q.cos() + cs * q.sin();
            cs = cs * q.cos() - sn * q.sin();
            sn = ns;
        }
        let total = Expr::sum(qs.iter().copied());
        assert_eq!(s.simplify(cs), total.cos());
        assert_eq!(s.simplify(sn), total.sin());
        assert!(s.report().work < 100, "{:?}", s.report());
        // Past max_angle_atoms the products are kept: a fourth angle is not combined.
        let q3 = Expr::sym("fq3");
        let four = cs * q3.cos() - sn * q3.sin();
        assert!(s.simplify(four).tree_size() > (total + q3).cos().tree_size());
        assert!(crate::symbolic::zero::zero_test(s.simplify(four) - (total + q3).cos()).is_zero());
    }

    #[test]
    fn a_result_simplifies_to_itself_without_work() {
        let mut s = Simplifier::default();
        let (a, b, c) = (Expr::sym("fa"), Expr::sym("fb"), Expr::sym("fc"));
        let built = (a.sin() * b.cos() + a.cos() * b.sin()) * c + c * c;
        let result = s.simplify(built);
        assert_ne!(result, built);
        let work = s.report().work;
        assert!(work > 0);
        // Simplifying the result again (as a formulation does with a sum of results) finds it
        // in the memo: no product is formed again.
        assert_eq!(s.simplify(result), result);
        assert_eq!(s.report().work, work);
        // And a new sum over it forms only its own terms.
        let again = s.simplify(result - c * c);
        assert!(zero_test(again - c * (a + b).sin()).is_zero());
    }

    #[test]
    fn products_and_powers_reduce() {
        let mut s = Simplifier::default();
        let (a, b, k) = (Expr::sym("a"), Expr::sym("b"), Expr::sym("k"));
        assert_eq!(s.simplify(k * a.cos() * b.cos() - k * a.sin() * b.sin()), k * (a + b).cos());
        assert_eq!(s.simplify((a * 2).sin() - a.sin() * a.cos() * 2), Expr::zero());
        assert_eq!(s.simplify(a.sin().powi(2) * 2 - 1 + (a * 2).cos()), Expr::zero());
        assert!(s.form_is_zero(((a + b) / 2).cos().powi(2) * 2 - 1 - (a + b).cos()));
        // Values are kept when nothing cancels.
        let e = (a.sin() * b.cos() * 2 + a.cos() * b.sin() * 3 + k) / (a + k);
        let r = s.simplify(e);
        let mut env = Env::default();
        for (n, v) in [("a", 0.3), ("b", 1.1), ("k", -0.7)] {
            env.set(crate::symbolic::Symbol::new(n), v);
        }
        assert!((r.eval(&env).unwrap() - e.eval(&env).unwrap()).abs() < 1e-14);
        assert!(zero_test(r - e).is_zero());
    }

    /// Forgetting the memo frees it and changes no answer: the same simplified forms after it,
    /// the limits' report kept.
    #[test]
    fn forgetting_the_memo_keeps_the_answers_and_the_report() {
        let (a, b) = (Expr::sym("fa"), Expr::sym("fb"));
        let e = a.sin() * b.cos() + a.cos() * b.sin() + (a.sin().powi(2) + a.cos().powi(2)) * b;
        let mut s = Simplifier::new(FourierLimits::default());
        let first = s.simplify(e);
        assert_eq!(first, (a + b).sin() + b);
        assert!(!s.memo.is_empty());
        let report = s.report();
        s.forget();
        assert!(s.memo.is_empty() && s.costs.is_empty());
        assert_eq!(s.report(), report);
        assert_eq!(s.simplify(e), first);
    }

    #[test]
    fn limits_keep_expressions_as_they_are() {
        let qs: Vec<Expr> = (0..8).map(|i| Expr::sym(&format!("lq{i}"))).collect();
        // (sum of cos q_i)^6 has thousands of harmonics: over the term limit, kept as built.
        let e = Expr::sum(qs.iter().map(|q| q.cos())).powi(6);
        let mut s = Simplifier::new(FourierLimits { max_terms: 50, max_work: 1_000_000, max_angle_atoms: 3 });
        let r = s.simplify(e);
        assert_eq!(r, e);
        assert_eq!(s.report().over_term_limit, 1);
        let mut tiny = Simplifier::new(FourierLimits { max_terms: 50, max_work: 10, max_angle_atoms: 3 });
        assert_eq!(tiny.simplify(e), e);
        assert!(tiny.report().work_limit_reached);
    }

    #[test]
    fn products_of_more_angles_than_a_harmonic_may_combine_are_counted_apart() {
        let qs: Vec<Expr> = (0..4).map(|i| Expr::sym(&format!("aq{i}"))).collect();
        let product = Expr::product(qs.iter().map(|q| q.cos()));
        let limits = FourierLimits { max_terms: 1000, max_work: 1_000_000, max_angle_atoms: 3 };
        let mut s = Simplifier::new(limits);
        assert_eq!(s.simplify(product), product);
        assert_eq!((s.report().over_angle_limit, s.report().over_term_limit), (1, 0));
        assert!(s.report().summary().unwrap().contains("1 products combining more angles"));
        // Three angles combine (the product is kept for its cost, not cut): nothing to report.
        let mut three = Simplifier::new(limits);
        three.simplify(Expr::product(qs[..3].iter().map(|q| q.cos())));
        assert_eq!(three.report(), SimplifyReport { work: three.report().work, ..SimplifyReport::default() });
        assert_eq!(three.report().summary(), None);
    }
}
