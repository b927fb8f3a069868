//! Small symbolic matrices: products, transposes, and solving `A X = B`.
//!
//! The solver is fraction-free Gauss-Jordan elimination with complete pivoting that prefers
//! structurally simple pivots (numbers, then expressions free of the state, then the
//! smallest), skips structural zeros, decides zero entries with the trigonometric zero test,
//! and divides common monomial factors (`cos(theta)`, `l`, ...) out of rows, so that no
//! spurious singularity (a pivot that vanishes where the matrix does not) is left behind in the
//! common cases. Numbers pivot by exact rational division.

use super::expr::{Expr, Node, Symbol};
use super::limits::{Limits, StopReason};
use super::number::Rat;
use super::zero::{ZeroVerdict, zero_test};
use std::collections::{BTreeMap, HashSet};

/// A dense matrix of expressions, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Matrix {
    pub rows: usize,
    pub cols: usize,
    pub data: Vec<Expr>,
}

impl Matrix {
    /// A matrix of zeros.
    pub fn zeros(rows: usize, cols: usize) -> Matrix {
        Matrix { rows, cols, data: vec![Expr::zero(); rows * cols] }
    }

    /// The identity.
    pub fn identity(n: usize) -> Matrix {
        let mut m = Matrix::zeros(n, n);
        for i in 0..n {
            m.set(i, i, Expr::one());
        }
        m
    }

    /// From rows of equal length.
    pub fn from_rows(rows: Vec<Vec<Expr>>) -> Matrix {
        let r = rows.len();
        let c = rows.first().map_or(0, |x| x.len());
        assert!(rows.iter().all(|x| x.len() == c), "rows of a matrix must have equal length");
        Matrix { rows: r, cols: c, data: rows.into_iter().flatten().collect() }
    }

    /// A column vector.
    pub fn column(items: Vec<Expr>) -> Matrix {
        Matrix { rows: items.len(), cols: 1, data: items }
    }

    /// Entry `(i, j)`.
    pub fn get(&self, i: usize, j: usize) -> Expr {
        self.data[i * self.cols + j]
    }

    /// Sets entry `(i, j)`.
    pub fn set(&mut self, i: usize, j: usize, e: Expr) {
        self.data[i * self.cols + j] = e;
    }

    /// Row `i` as a vector.
    pub fn row(&self, i: usize) -> Vec<Expr> {
        self.data[i * self.cols..(i + 1) * self.cols].to_vec()
    }

    /// Column `j` as a vector.
    pub fn col(&self, j: usize) -> Vec<Expr> {
        (0..self.rows).map(|i| self.get(i, j)).collect()
    }

    /// The transpose.
    pub fn transpose(&self) -> Matrix {
        let mut t = Matrix::zeros(self.cols, self.rows);
        for i in 0..self.rows {
            for j in 0..self.cols {
                t.set(j, i, self.get(i, j));
            }
        }
        t
    }

    /// The product `self * other`, skipping zero entries.
    pub fn mul(&self, other: &Matrix) -> Matrix {
        assert_eq!(self.cols, other.rows, "matrix product dimensions");
        let mut out = Matrix::zeros(self.rows, other.cols);
        for i in 0..self.rows {
            for j in 0..other.cols {
                let terms: Vec<Expr> = (0..self.cols)
                    .filter_map(|k| {
                        let (a, b) = (self.get(i, k), other.get(k, j));
                        (!a.is_zero() && !b.is_zero()).then(|| a * b)
                    })
                    .collect();
                out.set(i, j, Expr::sum(terms));
            }
        }
        out
    }

    /// Entry-wise sum.
    pub fn add(&self, other: &Matrix) -> Matrix {
        assert_eq!((self.rows, self.cols), (other.rows, other.cols), "matrix sum dimensions");
        Matrix { rows: self.rows, cols: self.cols, data: self.data.iter().zip(&other.data).map(|(a, b)| *a + *b).collect() }
    }

    /// Applies `f` to every entry.
    pub fn map(&self, f: impl FnMut(&Expr) -> Expr) -> Matrix {
        Matrix { rows: self.rows, cols: self.cols, data: self.data.iter().map(f).collect() }
    }

    /// The determinant by Laplace expansion along the sparsest row or column (for the small,
    /// sparse matrices of multibody systems), simplified under `limits`.
    pub fn determinant(&self, limits: Limits) -> Expr {
        assert_eq!(self.rows, self.cols, "determinant of a non-square matrix");
        let rows: Vec<usize> = (0..self.rows).collect();
        let cols: Vec<usize> = (0..self.cols).collect();
        let mut memo = std::collections::HashMap::new();
        self.minor(&rows, &cols, &mut memo).simplify_trig(limits)
    }

    fn minor(&self, rows: &[usize], cols: &[usize], memo: &mut std::collections::HashMap<(Vec<usize>, Vec<usize>), Expr>) -> Expr {
        if rows.is_empty() {
            return Expr::one();
        }
        if rows.len() == 1 {
            return self.get(rows[0], cols[0]);
        }
        let key = (rows.to_vec(), cols.to_vec());
        if let Some(e) = memo.get(&key) {
            return *e;
        }
        // Expand along the row or column with the most zeros.
        let zeros_row = |r: usize| cols.iter().filter(|&&c| self.get(r, c).is_zero()).count();
        let zeros_col = |c: usize| rows.iter().filter(|&&r| self.get(r, c).is_zero()).count();
        let (best_r, zr) = rows.iter().enumerate().map(|(i, &r)| (i, zeros_row(r))).max_by_key(|x| x.1).unwrap_or((0, 0));
        let (best_c, zc) = cols.iter().enumerate().map(|(i, &c)| (i, zeros_col(c))).max_by_key(|x| x.1).unwrap_or((0, 0));
        let mut terms = Vec::new();
        if zr >= zc {
            let sub_rows: Vec<usize> = rows.iter().enumerate().filter(|(i, _)| *i != best_r).map(|(_, r)| *r).collect();
            for (j, &c) in cols.iter().enumerate() {
                let e = self.get(rows[best_r], c);
                if e.is_zero() {
                    continue;
                }
                let sub_cols: Vec<usize> = cols.iter().enumerate().filter(|(k, _)| *k != j).map(|(_, c)| *c).collect();
                let sign = if (best_r + j) % 2 == 0 { 1 } else { -1 };
                terms.push(e * self.minor(&sub_rows, &sub_cols, memo) * sign);
            }
        } else {
            let sub_cols: Vec<usize> = cols.iter().enumerate().filter(|(k, _)| *k != best_c).map(|(_, c)| *c).collect();
            for (i, &r) in rows.iter().enumerate() {
                let e = self.get(r, cols[best_c]);
                if e.is_zero() {
                    continue;
                }
                let sub_rows: Vec<usize> = rows.iter().enumerate().filter(|(k, _)| *k != i).map(|(_, r)| *r).collect();
                let sign = if (i + best_c) % 2 == 0 { 1 } else { -1 };
                terms.push(e * self.minor(&sub_rows, &sub_cols, memo) * sign);
            }
        }
        let d = Expr::sum(terms);
        memo.insert(key, d);
        d
    }

    /// Stacks matrices with equal column counts on top of each other.
    pub fn vstack(parts: &[&Matrix]) -> Matrix {
        let cols = parts.iter().find(|m| m.rows > 0).map_or(0, |m| m.cols);
        let mut data = Vec::new();
        let mut rows = 0;
        for p in parts {
            if p.rows == 0 {
                continue;
            }
            assert_eq!(p.cols, cols, "vstack column counts");
            data.extend_from_slice(&p.data);
            rows += p.rows;
        }
        Matrix { rows, cols, data }
    }
}

/// Options for [`solve`].
#[derive(Clone, Debug)]
pub struct SolveOptions {
    /// Symbols that are constants (parameters): pivots free of other symbols are preferred.
    pub constants: HashSet<Symbol>,
    /// Limits for the normal forms computed on the way.
    pub limits: Limits,
    /// Expand the determinant too (Laplace expansion: for small matrices only).
    pub determinant: bool,
    /// Put eliminated entries in the polynomial normal form, so that common factors show and
    /// cancel (off for systems built from already simplified pieces).
    pub normalize: bool,
    /// A state the equations will be used at (the model's initial one): a pivot that vanishes
    /// there is taken only when no other is left, so that the solution does not divide by zero
    /// where a run starts (an off-diagonal entry of a floating base's mass block, zero at the
    /// identity attitude, chosen for being short).
    pub reference: Option<crate::symbolic::eval::Env>,
}

impl Default for SolveOptions {
    fn default() -> Self {
        SolveOptions { constants: HashSet::new(), limits: Limits::default(), determinant: true, normalize: true, reference: None }
    }
}

/// The solution of `A X = B`.
#[derive(Clone, Debug)]
pub struct Solution {
    /// `X`.
    pub x: Matrix,
    /// The distinct factors of the final pivots (after cancellation): `A` is singular only
    /// where one of them vanishes. Numbers are left out.
    pub pivots: Vec<Expr>,
    /// `det(A)` as far as it could be simplified, when asked for.
    pub determinant: Option<Expr>,
}

/// Why [`solve`] failed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// The matrix is singular for every value of its symbols: these rows (0-based, of `A`)
    /// became zero, and these unknowns (columns) stayed undetermined.
    #[error("the matrix is singular at every state: rows {rows:?} are linear combinations of the others; unknowns {columns:?} stay undetermined")]
    Singular { rows: Vec<usize>, columns: Vec<usize> },
    /// `A` is not square or `B` has the wrong number of rows.
    #[error("cannot solve a {a_rows}x{a_cols} system with a right-hand side of {b_rows} rows")]
    Dimensions { a_rows: usize, a_cols: usize, b_rows: usize },
}

/// Solves `A X = B` (see the module docs).
pub fn solve(a: &Matrix, b: &Matrix, opts: &SolveOptions) -> Result<Solution, SolveError> {
    let n = a.rows;
    if a.cols != n || b.rows != n {
        return Err(SolveError::Dimensions { a_rows: a.rows, a_cols: a.cols, b_rows: b.rows });
    }
    let k = b.cols;
    let mut stops = Vec::new();
    // Augmented rows [A | B].
    let mut rows: Vec<Vec<Expr>> = (0..n).map(|i| a.row(i).into_iter().chain(b.row(i)).collect()).collect();
    let mut row_used = vec![false; n];
    let mut col_used = vec![false; n];
    let mut pivot_of_col = vec![usize::MAX; n];

    for _ in 0..n {
        // Candidates, simplest first.
        let mut cands: Vec<((u8, u8, u32, usize, usize), usize, usize)> = Vec::new();
        for (i, row) in rows.iter().enumerate() {
            if row_used[i] {
                continue;
            }
            for (j, e) in row.iter().enumerate().take(n) {
                if col_used[j] || e.is_zero() {
                    continue;
                }
                let is_num = e.as_num().is_some();
                let state_free = e.free_symbols().iter().all(|s| opts.constants.contains(s));
                cands.push(((u8::from(!is_num), u8::from(!state_free), e.tree_size(), j, i), i, j));
            }
        }
        cands.sort_by_key(|c| c.0);
        // A pivot must be known to be nonzero; one the zero test could not decide is taken
        // only when no other is left (and said so), never one known to be zero.
        let mut chosen = None;
        let mut undecided = None;
        let mut vanishing = None;
        // Zero at the reference state (to round-off of its terms' size).
        let vanishes_there = |e: Expr| {
            opts.reference.as_ref().is_some_and(|env| {
                let scale = crate::symbolic::eval::magnitude(e).eval(env).unwrap_or(f64::NAN);
                e.eval(env).is_ok_and(|v| v.abs() <= 1e-12 * scale)
            })
        };
        for (_, i, j) in cands {
            let e = rows[i][j];
            if e.as_num().is_some() {
                chosen = Some((i, j));
                break;
            }
            match zero_test(e) {
                ZeroVerdict::NonZero { .. } if vanishes_there(e) => {
                    vanishing.get_or_insert((i, j));
                }
                ZeroVerdict::NonZero { .. } => {
                    chosen = Some((i, j));
                    break;
                }
                ZeroVerdict::Undecided { .. } => {
                    undecided.get_or_insert((i, j));
                }
                ZeroVerdict::Zero { .. } => rows[i][j] = Expr::zero(),
            }
        }
        if chosen.is_none() {
            chosen = vanishing;
        }
        if chosen.is_none() && undecided.is_some() {
            super::report::record(|c| {
                c.warn("a symbolic solve took a pivot the zero test could not decide: the equations divide by it, and a run stops where it vanishes".into())
            });
            chosen = undecided;
        }
        let Some((pi, pj)) = chosen else {
            let rows_left: Vec<usize> = (0..n).filter(|i| !row_used[*i]).collect();
            let cols_left: Vec<usize> = (0..n).filter(|j| !col_used[*j]).collect();
            return Err(SolveError::Singular { rows: rows_left, columns: cols_left });
        };
        row_used[pi] = true;
        col_used[pj] = true;
        pivot_of_col[pj] = pi;
        let p = rows[pi][pj];
        let prow = rows[pi].clone();
        for i in 0..n {
            if i == pi || rows[i][pj].is_zero() {
                continue;
            }
            let f = rows[i][pj];
            let updated: Vec<Expr> = if let Some(pn) = p.as_num() {
                let factor = f.scale(&pn.recip());
                rows[i].iter().zip(&prow).map(|(x, y)| if y.is_zero() { *x } else { *x - factor * *y }).collect()
            } else {
                rows[i].iter().zip(&prow).map(|(x, y)| if y.is_zero() { p * *x } else { p * *x - f * *y }).collect()
            };
            let mut updated: Vec<Expr> =
                if opts.normalize { updated.into_iter().map(|e| simplify_entry(e, opts.limits, &mut stops)).collect() } else { updated };
            updated[pj] = Expr::zero();
            if p.as_num().is_none() {
                let content = common_content(&updated);
                if !content.is_one() {
                    updated = updated.into_iter().map(|e| divide_content(e, content)).collect();
                }
            }
            rows[i] = updated;
        }
    }
    // Now row pivot_of_col[j] reads d * x_j = rhs.
    let mut x = Matrix::zeros(n, k);
    let mut pivots = Vec::new();
    for j in 0..n {
        let i = pivot_of_col[j];
        let d = rows[i][j];
        for f in factors_of(d) {
            if !pivots.contains(&f) {
                pivots.push(f);
            }
        }
        for c in 0..k {
            let r = rows[i][n + c];
            x.set(j, c, cancel_divide(r, d));
        }
    }
    let determinant = opts.determinant.then(|| a.determinant(opts.limits));
    if !stops.is_empty() {
        super::report::record(|c| c.solver_stops += stops.len());
    }
    Ok(Solution { x, pivots, determinant })
}

/// Solves `A X = B` without elimination where the rows of `A` are mutually orthogonal: `A A^T =
/// D` diagonal (every off-diagonal entry decided zero exactly, none left to a guess) gives
/// `A^-1 = A^T D^-1`, exact at every state, singular only where some `D_k` vanishes. A body's
/// angular velocity in unit quaternions, `omega = 2 G(e) e'`, with the unit norm's row `2 e^T`
/// and plain rates beside them, is such a matrix (`G G^T = |e|^2 I`, `G e = 0`): elimination
/// would bury `|e|^2` in fractions of high powers. `None` where the rows are not orthogonal.
pub fn solve_orthogonal(a: &Matrix, b: &Matrix) -> Option<Solution> {
    let n = a.rows;
    if a.cols != n || b.rows != n {
        return None;
    }
    let rows: Vec<Vec<Expr>> = (0..n).map(|i| a.row(i)).collect();
    for i in 0..n {
        for j in i + 1..n {
            let terms: Vec<Expr> = (0..n).filter(|&k| !rows[i][k].is_zero() && !rows[j][k].is_zero()).map(|k| rows[i][k] * rows[j][k]).collect();
            if !terms.is_empty() && !matches!(zero_test(Expr::sum(terms)), ZeroVerdict::Zero { .. }) {
                return None;
            }
        }
    }
    let d: Vec<Expr> = rows.iter().map(|r| Expr::sum(r.iter().filter(|e| !e.is_zero()).map(|e| *e * *e))).collect();
    if d.iter().any(|e| e.is_zero()) {
        return None;
    }
    let mut x = Matrix::zeros(n, b.cols);
    for i in 0..n {
        for c in 0..b.cols {
            x.set(i, c, Expr::sum((0..n).filter(|&k| !rows[k][i].is_zero() && !b.get(k, c).is_zero()).map(|k| rows[k][i] * b.get(k, c) / d[k])));
        }
    }
    let mut pivots = Vec::new();
    for e in d.into_iter().filter(|e| e.as_num().is_none()) {
        if !pivots.contains(&e) {
            pivots.push(e);
        }
    }
    Some(Solution { x, pivots, determinant: None })
}

/// Largest entry (distinct nodes) put in the polynomial normal form: larger ones are kept as
/// they are (correct, only without cancelled factors).
const MAX_NORMALIZED_ENTRY: usize = 400;

/// The polynomial normal form (single-angle factors stay visible, so common factors show), or
/// the expression when it is large or a limit stopped the normal form.
fn simplify_entry(e: Expr, limits: Limits, stops: &mut Vec<StopReason>) -> Expr {
    if e.is_zero() || e.as_num().is_some() || e.as_sym().is_some() {
        return e;
    }
    if e.dag_size() > MAX_NORMALIZED_ENTRY {
        return e;
    }
    match e.trig_normal(limits) {
        Ok(nf) => nf,
        Err(stop) => {
            if !stops.contains(&stop) {
                stops.push(stop);
            }
            e
        }
    }
}

/// The monomial factors `(base -> exponent)` common to every term of `e` (positive
/// exponents of atoms only).
fn monomial_content(e: Expr) -> Option<BTreeMap<(u64, u32), (Expr, Rat)>> {
    let terms: Vec<Expr> = match &*e.node() {
        Node::Add { constant, terms } => {
            if !constant.is_zero() {
                return Some(BTreeMap::new());
            }
            terms.iter().map(|(t, _)| *t).collect()
        }
        Node::Num(r) if r.is_zero() => return None,
        _ => vec![e],
    };
    let mut common: Option<BTreeMap<(u64, u32), (Expr, Rat)>> = None;
    for t in terms {
        let (_, mono) = t.split_coefficient();
        let factors: Vec<(Expr, Rat)> = match &*mono.node() {
            Node::Mul { factors, .. } => factors.clone(),
            Node::Num(_) => vec![],
            _ => vec![(mono, Rat::one())],
        };
        let here: BTreeMap<(u64, u32), (Expr, Rat)> = factors
            .into_iter()
            .filter(|(b, x)| x.is_positive() && !matches!(&*b.node(), Node::Add { .. } | Node::Num(_)))
            .map(|(b, x)| ((b.key(), b.id()), (b, x)))
            .collect();
        common = Some(match common {
            None => here,
            Some(c) => c.into_iter().filter_map(|(key, (b, x))| here.get(&key).map(|(_, y)| (key, (b, if *y < x { y.clone() } else { x })))).collect(),
        });
    }
    common
}

fn content_of(map: &BTreeMap<(u64, u32), (Expr, Rat)>) -> Expr {
    Expr::make_mul(Rat::one(), map.values().cloned().collect())
}

/// The monomial common to every entry (ignoring zeros), `1` if none.
fn common_content(items: &[Expr]) -> Expr {
    let mut common: Option<BTreeMap<(u64, u32), (Expr, Rat)>> = None;
    for e in items {
        let Some(c) = monomial_content(*e) else { continue };
        common = Some(match common {
            None => c,
            Some(acc) => acc.into_iter().filter_map(|(key, (b, x))| c.get(&key).map(|(_, y)| (key, (b, if *y < x { y.clone() } else { x })))).collect(),
        });
    }
    common.map_or(Expr::one(), |c| content_of(&c))
}

/// `e / content` for a monomial that divides every term of `e`.
fn divide_content(e: Expr, content: Expr) -> Expr {
    if e.is_zero() {
        return e;
    }
    let inv = content.recip();
    match &*e.node() {
        Node::Add { constant, terms } => Expr::make_add(constant.clone(), terms.iter().map(|(t, c)| (*t * inv, c.clone())).collect()),
        _ => e * inv,
    }
}

/// The non-numeric factors of a product (the expression itself if it is not a product).
fn factors_of(d: Expr) -> Vec<Expr> {
    match &*d.node() {
        Node::Num(_) => vec![],
        Node::Mul { factors, .. } => factors.iter().map(|(b, _)| *b).filter(|b| b.as_num().is_none()).collect(),
        _ => vec![d],
    }
}

/// `r / d`, cancelling the monomial factors they share.
fn cancel_divide(r: Expr, d: Expr) -> Expr {
    if r.is_zero() {
        return r;
    }
    let common = common_content(&[r, d]);
    if common.is_one() {
        return r / d;
    }
    divide_content(r, common) / divide_content(d, common)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::symbolic::eval::Env;
    use crate::symbolic::zero::SplitMix;

    fn check_solution(a: &Matrix, b: &Matrix, x: &Matrix, seed: u64) {
        let ax = a.mul(x);
        let mut syms: Vec<Symbol> = a.data.iter().chain(&b.data).flat_map(|e| e.free_symbols()).collect();
        syms.sort();
        syms.dedup();
        let mut rng = SplitMix(seed);
        for _ in 0..5 {
            let mut env = Env::default();
            for s in &syms {
                env.set(*s, rng.uniform(0.1, 1.4));
            }
            for (l, r) in ax.data.iter().zip(&b.data) {
                let (lv, rv) = (l.eval(&env).unwrap(), r.eval(&env).unwrap());
                assert!((lv - rv).abs() <= 1e-9 * (1.0 + rv.abs()), "{lv} vs {rv}");
            }
        }
    }

    /// The ZYX kinematic matrix: its inverse must not divide by cos(phi).
    #[test]
    fn zyx_inverse_has_no_spurious_pivot() {
        let (th, ph) = (Expr::sym("th"), Expr::sym("ph"));
        let a = Matrix::from_rows(vec![
            vec![-th.sin(), Expr::zero(), Expr::one()],
            vec![ph.sin() * th.cos(), ph.cos(), Expr::zero()],
            vec![ph.cos() * th.cos(), -ph.sin(), Expr::zero()],
        ]);
        let s = solve(&a, &Matrix::identity(3), &SolveOptions::default()).unwrap();
        check_solution(&a, &Matrix::identity(3), &s.x, 1);
        assert_eq!(s.pivots, vec![th.cos()], "{:?}", s.pivots.iter().map(|p| p.to_string()).collect::<Vec<_>>());
        for e in &s.x.data {
            for f in e.free_symbols() {
                assert!(f.name() == "th" || f.name() == "ph");
            }
            assert!(!e.to_string().contains("/cos(ph)"), "{e}");
        }
    }

    /// A structured 8x8 system: block-sparse with numeric, parametric and trigonometric
    /// entries, like [Y; M'; a] of a spatial multibody system.
    #[test]
    fn structured_8x8() {
        let q: Vec<Expr> = (0..4).map(|i| Expr::sym(&format!("q{i}"))).collect();
        let m = Expr::sym("mass");
        let z = Expr::zero;
        let o = Expr::one;
        let a = Matrix::from_rows(vec![
            vec![-q[1].sin(), z(), o(), z(), z(), z(), z(), z()],
            vec![q[2].sin() * q[1].cos(), q[2].cos(), z(), z(), z(), z(), z(), z()],
            vec![q[2].cos() * q[1].cos(), -q[2].sin(), z(), z(), z(), z(), z(), z()],
            vec![z(), z(), z(), o(), z(), z(), z(), z()],
            vec![z(), z(), z(), q[3].cos(), o(), z(), z(), z()],
            vec![q[0].cos() * m, q[1].sin(), z(), q[3].sin(), z(), m, z(), z()],
            vec![q[0].sin(), z(), q[2].cos() * m, z(), q[3].cos(), z(), m, z()],
            vec![z(), q[1].cos(), z(), z(), z(), z(), z(), m * 2],
        ]);
        let mut opts = SolveOptions::default();
        opts.constants.insert(Symbol::new("mass"));
        let mut b = Matrix::zeros(8, 2);
        for i in 0..8 {
            b.set(i, 0, if i < 5 { Expr::one() } else { Expr::zero() });
            b.set(i, 1, if i >= 5 { Expr::sym(&format!("g{i}")) } else { Expr::zero() });
        }
        let s = solve(&a, &b, &opts).unwrap();
        check_solution(&a, &b, &s.x, 2);
        // Singular only where cos(q1) = 0 (and mass = 0).
        let names: Vec<String> = s.pivots.iter().map(|p| p.to_string()).collect();
        assert_eq!(names, vec!["cos(q1)".to_string(), "mass".to_string()]);
        // The determinant is -cos(q1) * 2 mass^3 up to sign.
        let det = s.determinant.unwrap().to_string();
        assert!(det.contains("cos(q1)") && det.contains("mass^3"), "{det}");
    }

    #[test]
    fn singular_matrices_name_rows() {
        let x = Expr::sym("x");
        let a = Matrix::from_rows(vec![vec![x.cos(), x.sin()], vec![x.cos() * 2, x.sin() * 2]]);
        let err = solve(&a, &Matrix::identity(2), &SolveOptions::default()).unwrap_err();
        assert!(matches!(err, SolveError::Singular { ref rows, .. } if rows.len() == 1), "{err}");
    }

    #[test]
    fn singular_set_is_reported_through_pivots() {
        let (a1, a2, l) = (Expr::sym("a1"), Expr::sym("a2"), Expr::sym("l"));
        let a = Matrix::from_rows(vec![vec![-Expr::one(), Expr::one()], vec![l * (a1 - a2).cos(), l]]);
        let s = solve(&a, &Matrix::identity(2), &SolveOptions::default()).unwrap();
        check_solution(&a, &Matrix::identity(2), &s.x, 3);
        assert_eq!(s.pivots.len(), 2, "{:?}", s.pivots.iter().map(|p| p.to_string()).collect::<Vec<_>>());
        let mut env = Env::default();
        env.set(Symbol::new("a1"), 1.0);
        env.set(Symbol::new("a2"), 1.0 + std::f64::consts::PI);
        env.set(Symbol::new("l"), 1.0);
        assert!(s.pivots.iter().any(|p| p.eval(&env).unwrap().abs() < 1e-12));
        assert!(s.determinant.unwrap().eval(&env).unwrap().abs() < 1e-12);
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::symbolic::{
            Expr,
            matrix::{Matrix, SolveOptions, solve},
        };
        let (a, b) = (Expr::sym("a"), Expr::sym("b"));
        let m = Matrix::from_rows(vec![vec![Expr::one(), b], vec![Expr::zero(), a]]);
        let rhs = Matrix::from_rows(vec![vec![Expr::int(1)], vec![Expr::int(2)]]);
        let s = solve(&m, &rhs, &SolveOptions::default()).unwrap();
        assert_eq!(s.x.get(1, 0), Expr::int(2) / a);
    }

    #[test]
    fn solve_orthogonal_example() {
        use crate::symbolic::{
            Expr,
            matrix::{Matrix, solve_orthogonal},
        };
        let (c, s) = (Expr::sym("c"), Expr::sym("s"));
        let a = Matrix::from_rows(vec![vec![c, s], vec![-s, c]]);
        let x = solve_orthogonal(&a, &Matrix::from_rows(vec![vec![Expr::one()], vec![Expr::zero()]])).unwrap().x;
        assert_eq!(x.get(0, 0), c / (c * c + s * s));
        assert!(solve_orthogonal(&Matrix::from_rows(vec![vec![c, s], vec![s, c]]), &Matrix::zeros(2, 1)).is_none());
    }
}
