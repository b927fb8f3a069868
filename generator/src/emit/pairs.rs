//! Common sub-products and sub-sums: `m2*l1` inside `m2*l1*cos(q2)` and `m2*l1*l0*s`, or
//! `m1 + m2` inside `m0 + m1 + m2`, computed once.
//!
//! Hash-consing already shares whole nodes; this pass shares parts of them. Every product is a
//! bag of factors (a factor `x^2` counts twice) and every sum a bag of terms (a term with its
//! coefficient); [`merge_pairs`] then repeatedly takes the pair of atoms found together in the
//! most bags and gives it a name of its own (greedy pair merging, as Re-Pair does for text), while
//! some pair is shared by two bags or more. Each merge saves one operation per bag beyond the
//! first. A merged pair becomes a node `()(a*b)` (or `()(a + b)`), the grouping function that
//! lowers to its argument: without it the canonical form would flatten the product back.
//!
//! Ties are broken first by the atoms' order of first appearance in a post-order walk of the
//! outputs, then by the order in which pairs reached their count, so the result depends only
//! on the expressions; a merge updates only the pairs of the atoms it moved, and the work is
//! bounded by [`PAIR_BUDGET`] updates (a count, never a time).

use super::cse::post_order;
use crate::symbolic::number::Rat;
use crate::symbolic::{Expr, Node, Symbol};
use rustc_hash::{FxHashMap, FxHashSet};
use std::collections::VecDeque;

/// The named function that groups a shared pair; emission lowers `()(x)` as `x`.
pub fn group_symbol() -> Symbol {
    Symbol::new("()")
}

/// Most pair-count updates one call of [`merge_pairs`] performs. The 60-link pendulum on a cart's
/// Lagrange body, the largest in the scaling benchmark, merges all its shared pairs in 8.7
/// million; at the earlier budget of 4 million (and a cost per merge of the bag's whole pair
/// list) the 40-link one stopped after 375 merges and its assembly took 22569 operations
/// instead of 12043.
pub const PAIR_BUDGET: usize = 32_000_000;

/// Most distinct atoms of one bag whose pairs are counted (the rest stay as they are).
const MAX_BAG_ATOMS: usize = 32;

/// An unordered pair of atoms, smaller first.
type Pair = (usize, usize);

/// The distinct atoms of a bag that `shared` accepts (an atom found in one bag only can be in no
/// shared pair), sorted, each with its multiplicity: the first [`MAX_BAG_ATOMS`] of them.
fn view(bag: &[usize], shared: &impl Fn(usize) -> bool) -> Vec<(usize, usize)> {
    let mut sorted: Vec<usize> = bag.iter().copied().filter(|&a| shared(a)).collect();
    sorted.sort_unstable();
    let mut distinct: Vec<(usize, usize)> = Vec::new();
    for a in sorted {
        match distinct.last_mut() {
            Some((x, n)) if *x == a => *n += 1,
            _ => distinct.push((a, 1)),
        }
    }
    distinct.truncate(MAX_BAG_ATOMS);
    distinct
}

/// The distinct pairs a bag's [`view`] holds (an atom twice makes the pair `(a, a)`), sorted.
fn pairs_of(view: &[(usize, usize)]) -> Vec<Pair> {
    let mut out = Vec::new();
    for (i, &(a, n)) in view.iter().enumerate() {
        if n >= 2 {
            out.push((a, a));
        }
        for &(b, _) in &view[i + 1..] {
            out.push((a, b));
        }
    }
    out
}

/// The multiplicity of `atom` in a view (0 when absent).
fn multiplicity(view: &[(usize, usize)], atom: usize) -> usize {
    view.binary_search_by_key(&atom, |&(a, _)| a).map_or(0, |i| view[i].1)
}

/// Whether a view holds `pair`.
fn holds(view: &[(usize, usize)], pair: Pair) -> bool {
    if pair.0 == pair.1 { multiplicity(view, pair.0) >= 2 } else { multiplicity(view, pair.0) > 0 && multiplicity(view, pair.1) > 0 }
}

/// The pairs `from` holds and `to` does not: those with an atom `to` lacks, and the doubled
/// atoms `to` holds once. Costs the atoms that left times the view, not the view's square.
fn pairs_lost(from: &[(usize, usize)], to: &[(usize, usize)]) -> Vec<Pair> {
    let left: Vec<usize> = from.iter().map(|&(a, _)| a).filter(|&a| multiplicity(to, a) == 0).collect();
    let mut out = Vec::new();
    for &(a, n) in from {
        let gone = left.binary_search(&a).is_ok();
        if n >= 2 && multiplicity(to, a) < 2 {
            out.push((a, a));
        }
        if gone {
            // Every pair with a surviving atom, and with the atoms that left after it.
            out.extend(from.iter().filter(|&&(b, _)| b != a && (b > a || left.binary_search(&b).is_err())).map(|&(b, _)| (a.min(b), a.max(b))));
        }
    }
    out
}

/// Replaces every occurrence of `pair` in `bag` by `group`.
fn replace_pair(bag: &mut Vec<usize>, pair: Pair, group: usize) {
    loop {
        let Some(i) = bag.iter().position(|&x| x == pair.0) else { return };
        let j = bag.iter().enumerate().position(|(k, &x)| k != i && x == pair.1);
        let Some(j) = j else { return };
        let (lo, hi) = (i.min(j), i.max(j));
        bag.remove(hi);
        bag.remove(lo);
        bag.push(group);
    }
}

/// Greedy pair merging over `bags` of atom numbers. Atoms `0..first_group` exist; merged pairs
/// get the numbers `first_group, first_group + 1, ...` in the order returned, and replace their
/// pair in the bags. Stops when no pair is held by two bags, or after [`PAIR_BUDGET`] updates.
pub fn merge_pairs(bags: &mut [Vec<usize>], first_group: usize) -> Vec<Pair> {
    let mut count: FxHashMap<Pair, usize> = FxHashMap::default();
    let mut holders: FxHashMap<Pair, Vec<usize>> = FxHashMap::default();
    let mut candidates = Candidates::default();
    let mut work = 0usize;
    // Atoms held by two bags or more (merged pairs always are).
    let mut holding = vec![0u8; first_group];
    for bag in bags.iter() {
        let mut distinct: Vec<usize> = bag.clone();
        distinct.sort_unstable();
        distinct.dedup();
        for a in distinct {
            holding[a] = holding[a].saturating_add(1);
        }
    }
    let shared = |a: usize| a >= first_group || holding[a] >= 2;
    // Each bag's view, kept as its last replacement left it (whether an atom is shared does
    // not change while merging: a group is, and so is an atom held twice from the start).
    let mut views: Vec<_> = bags.iter().map(|bag| view(bag, &shared)).collect();
    for (k, v) in views.iter().enumerate() {
        for p in pairs_of(v) {
            *count.entry(p).or_default() += 1;
            holders.entry(p).or_default().push(k);
            work += 1;
        }
    }
    candidates.fill(&count);
    let mut groups = Vec::new();
    let change = |count: &mut FxHashMap<Pair, usize>, candidates: &mut Candidates, p: Pair, up: bool| {
        let n = count.entry(p).or_default();
        if up {
            *n += 1;
        } else {
            *n -= 1;
        }
        candidates.moved(p, *n);
    };
    while let Some(pair) = candidates.next(&count) {
        if work > PAIR_BUDGET {
            break;
        }
        let group = first_group + groups.len();
        groups.push(pair);
        let mut seen = FxHashSet::default();
        let bag_ids: Vec<usize> = holders.remove(&pair).unwrap_or_default().into_iter().filter(|k| seen.insert(*k)).collect();
        for k in bag_ids {
            if !holds(&views[k], pair) {
                continue;
            }
            replace_pair(&mut bags[k], pair, group);
            let old = std::mem::replace(&mut views[k], view(&bags[k], &shared));
            let new = &views[k];
            let (lost, gained) = (pairs_lost(&old, new), pairs_lost(new, &old));
            work += old.len() + new.len() + lost.len() + gained.len();
            for p in lost.into_iter().filter(|&p| p != pair) {
                change(&mut count, &mut candidates, p, false);
            }
            for p in gained {
                change(&mut count, &mut candidates, p, true);
                holders.entry(p).or_default().push(k);
            }
        }
        // Whatever still counts this pair (a bag holding it twice) is done with it.
        count.remove(&pair);
    }
    groups
}

/// The pairs held by two bags or more, by count: the most shared first, and among equals the
/// first to reach that count (the initial ones smallest first). A bucket per count, each a
/// queue; an entry whose pair's count has moved on since is stale and skipped when it comes up.
#[derive(Default)]
struct Candidates {
    buckets: Vec<VecDeque<Pair>>,
    /// No bucket above it holds a live entry.
    top: usize,
}

impl Candidates {
    /// Queues the initial pairs with their counts, smallest pair first within a count.
    fn fill(&mut self, count: &FxHashMap<Pair, usize>) {
        let mut initial: Vec<(Pair, usize)> = count.iter().filter(|&(_, &n)| n >= 2).map(|(&p, &n)| (p, n)).collect();
        initial.sort_unstable();
        for (p, n) in initial {
            self.moved(p, n);
        }
    }

    /// A pair's count is now `after`.
    fn moved(&mut self, p: Pair, after: usize) {
        if after >= 2 {
            if self.buckets.len() <= after {
                self.buckets.resize_with(after + 1, VecDeque::new);
            }
            self.buckets[after].push_back(p);
            self.top = self.top.max(after);
        }
    }

    /// The next pair to merge, taken off its queue.
    fn next(&mut self, count: &FxHashMap<Pair, usize>) -> Option<Pair> {
        while self.top >= 2 {
            match self.buckets[self.top].pop_front() {
                Some(p) if count.get(&p) == Some(&self.top) => return Some(p),
                Some(_) => {}
                None => self.top -= 1,
            }
        }
        None
    }
}

/// What an atom of a bag stands for: a factor's base, or a sum's term with its coefficient.
#[derive(Clone, PartialEq, Eq, Hash)]
enum Atom {
    Factor(Expr),
    Term(Expr, Rat),
}

/// Where a node's bag sits and what stays outside it.
enum Shape {
    /// A product: its coefficient, and the factors that are not small positive powers.
    Product(Rat, Vec<(Expr, Rat)>),
    /// A sum: its constant, and the sign it was taken with (a sum of negative terms is shared
    /// as its negation, so `-m1 - m2` finds `m1 + m2`; it costs a negation either way).
    Sum(Rat, Rat),
}

/// Shares the pairs of factors and of terms that two or more products or sums hold, across all
/// `outputs` (values unchanged up to rounding).
pub fn share_pairs(outputs: &[Expr]) -> Vec<Expr> {
    let order = post_order(outputs);
    let mut atoms: Vec<Atom> = Vec::new();
    let mut number: FxHashMap<Atom, usize> = FxHashMap::default();
    let mut intern = |a: Atom, atoms: &mut Vec<Atom>| -> usize {
        *number.entry(a.clone()).or_insert_with(|| {
            atoms.push(a);
            atoms.len() - 1
        })
    };
    // Products and sums get bags in separate passes so that their atoms never pair.
    let mut product_bags: Vec<Vec<usize>> = Vec::new();
    let mut sum_bags: Vec<Vec<usize>> = Vec::new();
    let mut shapes: FxHashMap<Expr, (Shape, usize)> = FxHashMap::default();
    for &e in &order {
        match &*e.node() {
            Node::Mul { coefficient, factors } => {
                let mut bag = Vec::new();
                let mut rest = Vec::new();
                for (b, ex) in factors {
                    match ex.to_i64() {
                        Some(n @ 1..=3) => bag.extend(std::iter::repeat_n(intern(Atom::Factor(*b), &mut atoms), n as usize)),
                        _ => rest.push((*b, ex.clone())),
                    }
                }
                if bag.len() >= 2 {
                    shapes.insert(e, (Shape::Product(coefficient.clone(), rest), product_bags.len()));
                    product_bags.push(bag);
                }
            }
            Node::Add { constant, terms } if terms.len() >= 2 => {
                let sign = if terms.iter().all(|(_, c)| c.is_negative()) { -Rat::one() } else { Rat::one() };
                let bag = terms.iter().map(|(t, c)| intern(Atom::Term(*t, c * &sign), &mut atoms)).collect();
                shapes.insert(e, (Shape::Sum(constant * &sign, sign), sum_bags.len()));
                sum_bags.push(bag);
            }
            _ => {}
        }
    }
    let product_groups = merge_pairs(&mut product_bags, atoms.len());
    let sum_groups = merge_pairs(&mut sum_bags, atoms.len() + product_groups.len());
    let groups: Vec<Pair> = product_groups.iter().chain(&sum_groups).copied().collect();
    let mut rebuild = Rebuild { atoms: &atoms, groups: &groups, first_group: atoms.len(), built: FxHashMap::default(), memo: FxHashMap::default() };
    // A bag that holds a merged pair (atom numbers from `atoms.len()` on are merged pairs).
    let merged = |k: usize, bags: &[Vec<usize>]| bags[k].iter().any(|&a| a >= atoms.len());
    for &e in &order {
        let r = match shapes.get(&e) {
            Some((Shape::Product(_, _), k)) if !merged(*k, &product_bags) => rebuild.over_children(e),
            // A sum of negative terms is rebuilt as the negation of a positive one even where
            // nothing merged: the sign then goes into a product's coefficient for free.
            Some((Shape::Sum(_, sign), k)) if sign.is_one() && !merged(*k, &sum_bags) => rebuild.over_children(e),
            Some((Shape::Product(coefficient, rest), k)) => {
                let mut factors: Vec<(Expr, Rat)> = product_bags[*k].iter().map(|&a| (rebuild.factor(a), Rat::one())).collect();
                factors.extend(rest.iter().map(|(b, ex)| (rebuild.memo[b], ex.clone())));
                Expr::make_mul(coefficient.clone(), factors)
            }
            Some((Shape::Sum(constant, sign), k)) => {
                let terms: Vec<(Expr, Rat)> = sum_bags[*k].iter().map(|&a| rebuild.term(a)).collect();
                Expr::make_mul(sign.clone(), vec![(Expr::make_add(constant.clone(), terms), Rat::one())])
            }
            None => rebuild.over_children(e),
        };
        rebuild.memo.insert(e, r);
    }
    outputs.iter().map(|e| rebuild.memo[e]).collect()
}

/// Rebuilds atoms and merged pairs as expressions over the rewritten children.
struct Rebuild<'a> {
    atoms: &'a [Atom],
    groups: &'a [Pair],
    first_group: usize,
    built: FxHashMap<usize, Expr>,
    memo: FxHashMap<Expr, Expr>,
}

impl Rebuild<'_> {
    /// `e` over its rewritten children (itself when none changed).
    fn over_children(&self, e: Expr) -> Expr {
        e.map_children_or_self(|c| self.memo[&c])
    }

    /// Atom `a` of a product as a factor.
    fn factor(&mut self, a: usize) -> Expr {
        if a < self.first_group {
            let Atom::Factor(b) = &self.atoms[a] else { unreachable!("a product's atom is a factor") };
            return self.memo[b];
        }
        if let Some(&e) = self.built.get(&a) {
            return e;
        }
        let (x, y) = self.groups[a - self.first_group];
        let inner = Expr::make_mul(Rat::one(), vec![(self.factor(x), Rat::one()), (self.factor(y), Rat::one())]);
        let e = Expr::apply_named(group_symbol(), inner);
        self.built.insert(a, e);
        e
    }

    /// Atom `a` of a sum as a term with its coefficient.
    fn term(&mut self, a: usize) -> (Expr, Rat) {
        if a < self.first_group {
            let Atom::Term(t, c) = &self.atoms[a] else { unreachable!("a sum's atom is a term") };
            return (self.memo[t], c.clone());
        }
        if let Some(&e) = self.built.get(&a) {
            return (e, Rat::one());
        }
        let (x, y) = self.groups[a - self.first_group];
        let inner = Expr::make_add(Rat::zero(), vec![self.term(x), self.term(y)]);
        let e = Expr::apply_named(group_symbol(), inner);
        self.built.insert(a, e);
        (e, Rat::one())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::symbolic::eval::Env;
    use proptest::prelude::*;

    fn env() -> Env {
        let mut env = Env::default();
        for (s, v) in [("a", 0.3), ("b", -1.7), ("c", 2.5), ("d", 0.9), ("e", 1.3)] {
            env.set(Symbol::new(s), v);
        }
        env.define(group_symbol(), Symbol::internal("arg"), Symbol::internal("arg").expr());
        env
    }

    #[test]
    fn most_shared_pair_first_and_repeated_atoms_pair_with_themselves() {
        // (0, 1) is in three bags, (0, 0) in two; once (0, 1) is merged, (0, 0) is left in one.
        let mut bags = vec![vec![0, 0, 1], vec![0, 0, 2], vec![0, 1, 3], vec![0, 1]];
        assert_eq!(merge_pairs(&mut bags, 4), vec![(0, 1)]);
        assert_eq!(bags, vec![vec![0, 4], vec![0, 0, 2], vec![3, 4], vec![4]]);
        let mut squares = vec![vec![0, 0, 1], vec![0, 0, 2], vec![0, 0]];
        assert_eq!(merge_pairs(&mut squares, 3), vec![(0, 0)]);
        assert_eq!(squares, vec![vec![1, 3], vec![2, 3], vec![3]]);
    }

    #[test]
    fn a_pair_in_one_bag_only_is_left_alone() {
        let mut bags = vec![vec![0, 1, 2], vec![3, 4]];
        assert!(merge_pairs(&mut bags, 5).is_empty());
        assert_eq!(bags, vec![vec![0, 1, 2], vec![3, 4]]);
    }

    #[test]
    fn sums_share_their_common_terms() {
        let (a, b, c) = (Expr::sym("a"), Expr::sym("b"), Expr::sym("c"));
        let out = share_pairs(&[a + b * 2 + c, (a + b * 2) * c]);
        let env = env();
        let want = [(a + b * 2 + c).eval(&env).unwrap(), ((a + b * 2) * c).eval(&env).unwrap()];
        for (o, w) in out.iter().zip(want) {
            assert!((o.eval(&env).unwrap() - w).abs() < 1e-14);
        }
        assert!(out[0].children().iter().any(|x| x.to_string().starts_with("()(")), "{}", out[0]);
    }

    fn arb_product() -> impl Strategy<Value = Vec<(usize, i64)>> {
        prop::collection::vec((0usize..5, 1i64..4), 1..6)
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, rng_seed: proptest::test_runner::RngSeed::Fixed(11), ..ProptestConfig::default() })]
        /// The pairs a merge takes from a bag and gives it, found from the atoms that moved,
        /// are the two set differences of the bag's whole pair lists, also where the merge
        /// brings atoms past the view's first [`MAX_BAG_ATOMS`] into it.
        #[test]
        fn pair_changes_are_the_differences_of_the_pair_lists(
            bag in prop::collection::vec(0usize..48, 2..80),
            pick in (0usize..80, 0usize..80),
            lonely in 0usize..48,
        ) {
            let shared = |a: usize| a != lonely;
            let old = view(&bag, &shared);
            let (i, j) = (pick.0 % old.len().max(1), pick.1 % old.len().max(1));
            prop_assume!(!old.is_empty());
            let pair = (old[i].0.min(old[j].0), old[i].0.max(old[j].0));
            prop_assume!(holds(&old, pair));
            let mut merged = bag.clone();
            replace_pair(&mut merged, pair, 1000);
            let new = view(&merged, &shared);
            let (before, after) = (pairs_of(&old), pairs_of(&new));
            let mut lost = pairs_lost(&old, &new);
            let mut gained = pairs_lost(&new, &old);
            lost.sort_unstable();
            gained.sort_unstable();
            let want_lost: Vec<Pair> = before.iter().copied().filter(|p| after.binary_search(p).is_err()).collect();
            let want_gained: Vec<Pair> = after.iter().copied().filter(|p| before.binary_search(p).is_err()).collect();
            prop_assert_eq!(lost, want_lost);
            prop_assert_eq!(gained, want_gained);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, rng_seed: proptest::test_runner::RngSeed::Fixed(7), ..ProptestConfig::default() })]
        /// Sharing keeps every value and never adds an operation to what the products cost.
        #[test]
        fn sharing_keeps_the_values(products in prop::collection::vec(arb_product(), 1..8), k in -3i64..4) {
            let names = ["a", "b", "c", "d", "e"];
            let outputs: Vec<Expr> = products
                .iter()
                .map(|p| p.iter().fold(Expr::num(Rat::from(k)), |acc, (s, n)| acc * Expr::sym(names[*s]).powi(*n)) + Expr::sym("e"))
                .collect();
            let shared = share_pairs(&outputs);
            let env = env();
            for (o, s) in outputs.iter().zip(&shared) {
                let (want, got) = (o.eval(&env).unwrap(), s.eval(&env).unwrap());
                prop_assert!((want - got).abs() <= 1e-12 * want.abs().max(1.0), "{o} = {want}, {s} = {got}");
            }
        }
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::emit::pairs::share_pairs;
        use crate::symbolic::Expr;
        let (a, b, c, d) = (Expr::sym("a"), Expr::sym("b"), Expr::sym("c"), Expr::sym("d"));
        let out = share_pairs(&[a * b * c, a * b * d]);
        // Both products now hold the same grouped node for `a*b`.
        let shared: Vec<_> = out[0].children().into_iter().filter(|x| out[1].children().contains(x)).collect();
        assert_eq!(shared.len(), 1);
    }
    #[test]
    fn merge_pairs_example() {
        use crate::emit::pairs::merge_pairs;
        let mut bags = vec![vec![0, 1, 2], vec![0, 1, 3], vec![0, 1]];
        let groups = merge_pairs(&mut bags, 4);
        assert_eq!(groups, vec![(0, 1)]);
        assert_eq!(bags, vec![vec![2, 4], vec![3, 4], vec![4]]);
    }
}
