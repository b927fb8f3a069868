//! The `L D L^T` solve of a symmetric positive definite matrix (Maggi's, Kane's and the reduced
//! method's), planned per formulation from the matrix's structural zeros: an elimination order
//! with the least work (no fill-in where the sparsity allows, as Featherstone's `LTDL` orders a
//! tree's mass matrix), then straight-line code that skips every product with a structural zero.
//! A dense matrix keeps the module's generic `solve_spd` (every order costs the same).
//!
//! One plan drives both the emitted code ([`LdlPlan::emit`]) and in-process evaluation
//! ([`LdlPlan::solve`]): the same operations in the same order, so the same numbers.

use super::ops::OpCount;
use super::splice::Splices;
use super::tape::{Instr, Tape, Writer};
use crate::formulation::Equations;
use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::quote;

/// Largest matrix whose elimination order is the exact optimum, by dynamic programming over
/// the subsets already eliminated (`2^n` states); larger ones take the minimum-degree order.
const MAX_EXACT_ORDER: usize = 14;

/// How a symmetric positive definite `n x n` matrix is factored as `L D L^T`: the order the
/// rows are eliminated in, and where `L` has structural nonzeros in that order.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LdlPlan {
    /// `order[k]`: the matrix row (and column) eliminated `k`-th.
    order: Vec<usize>,
    /// `rows[i]`: the positions `k < i` where `L[i][k]` may be nonzero, ascending.
    rows: Vec<Vec<usize>>,
    /// `cols[k]`: the positions `i > k` where `L[i][k]` may be nonzero, ascending.
    cols: Vec<Vec<usize>>,
    /// Entries of `L` below the diagonal that are nonzero where the matrix has a zero.
    fill_in: usize,
    /// Per entry `(i, j)` of `L`, column by column: the positions `k < j` whose products
    /// `L[i][k] (L D)[j][k]` it subtracts, as a range of `shared`.
    entries: Vec<(usize, usize, std::ops::Range<usize>)>,
    shared: Vec<usize>,
    /// The same, as indices for [`Self::solve`]: the entries of `L` numbered in that order.
    steps: Steps,
}

/// [`LdlPlan::solve`]'s operands, resolved once: every entry of `L` by its number `e`, its
/// matrix element by its row-major index.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
struct Steps {
    /// Per pivot `j`: the row-major index of its diagonal element, the entries `(j, k)` of its
    /// row (a range of `row_entries`), and its column's entries (a range of entry numbers).
    pivots: Vec<(usize, std::ops::Range<usize>, std::ops::Range<usize>)>,
    row_entries: Vec<usize>,
    /// Per entry: the row-major index of its matrix element, and its products `(i, k)` times
    /// `(j, k)` (a range of `products`).
    elements: Vec<(usize, std::ops::Range<usize>)>,
    products: Vec<(usize, usize)>,
    /// Forward substitution, row by row: `(entry (i, k), k)` (a range of `forward`); back
    /// substitution, column by column: `(entry (k, i), k)` (a range of `back`).
    forward_rows: Vec<std::ops::Range<usize>>,
    forward: Vec<(usize, usize)>,
    back_columns: Vec<std::ops::Range<usize>>,
    back: Vec<(usize, usize)>,
}

impl LdlPlan {
    /// The plan of a dense `n x n` matrix in its own order: the module's generic `solve_spd`.
    pub fn dense(n: usize) -> LdlPlan {
        LdlPlan::with_order(n, |_, _| true, (0..n).collect())
    }

    /// The plan with the least work for a matrix whose entry `(i, j)` may be nonzero where
    /// `nonzero(i, j)` (read for `i > j`; the diagonal is always nonzero). The matrix's own
    /// order wins every tie, so a dense matrix keeps it.
    pub fn new(n: usize, nonzero: impl Fn(usize, usize) -> bool) -> LdlPlan {
        let adjacency: Vec<u64> = (0..n).map(|i| (0..n).filter(|&j| j != i && nonzero(i.max(j), i.min(j))).fold(0u64, |m, j| m | 1 << j)).collect();
        let natural = LdlPlan::with_order(n, &nonzero, (0..n).collect());
        let order = if n > 64 {
            return natural;
        } else if n <= MAX_EXACT_ORDER {
            least_work_order(&adjacency)
        } else {
            minimum_degree_order(&adjacency)
        };
        let planned = LdlPlan::with_order(n, &nonzero, order);
        if planned.cost().total() < natural.cost().total() { planned } else { natural }
    }

    /// The plan of the matrix eliminated in `order` (a permutation of `0..n`).
    fn with_order(n: usize, nonzero: impl Fn(usize, usize) -> bool, order: Vec<usize>) -> LdlPlan {
        // Symbolic factorization: column k's nonzeros below the diagonal join, as fill-in, every
        // later column they meet.
        let mut pattern = vec![vec![false; n]; n];
        let mut fill_in = 0;
        for i in 0..n {
            for k in 0..i {
                let (a, b) = (order[i], order[k]);
                pattern[i][k] = nonzero(a.max(b), a.min(b));
            }
        }
        for k in 0..n {
            let below: Vec<usize> = (k + 1..n).filter(|&i| pattern[i][k]).collect();
            for (x, &j) in below.iter().enumerate() {
                for &i in &below[x + 1..] {
                    if !pattern[i][j] {
                        pattern[i][j] = true;
                        fill_in += 1;
                    }
                }
            }
        }
        let rows: Vec<Vec<usize>> = (0..n).map(|i| (0..i).filter(|&k| pattern[i][k]).collect()).collect();
        let cols: Vec<Vec<usize>> = (0..n).map(|k| (k + 1..n).filter(|&i| pattern[i][k]).collect()).collect();
        let (mut entries, mut shared) = (Vec::new(), Vec::new());
        for j in 0..n {
            for i in j + 1..n {
                if pattern[i][j] {
                    let start = shared.len();
                    shared.extend((0..j).filter(|&k| pattern[i][k] && pattern[j][k]));
                    entries.push((i, j, start..shared.len()));
                }
            }
        }
        let number: std::collections::HashMap<(usize, usize), usize> = entries.iter().enumerate().map(|(e, (i, j, _))| ((*i, *j), e)).collect();
        let mut steps = Steps::default();
        let mut next = 0;
        for j in 0..n {
            let start = steps.row_entries.len();
            steps.row_entries.extend(rows[j].iter().map(|&k: &usize| number[&(j, k)]));
            let column = next..next + cols[j].len();
            next = column.end;
            steps.pivots.push((order[j] * n + order[j], start..steps.row_entries.len(), column));
        }
        for (i, j, ks) in &entries {
            let start = steps.products.len();
            steps.products.extend(shared[ks.clone()].iter().map(|&k| (number[&(*i, k)], number[&(*j, k)])));
            steps.elements.push((order[*i] * n + order[*j], start..steps.products.len()));
        }
        for i in 0..n {
            let start = steps.forward.len();
            steps.forward.extend(rows[i].iter().map(|&k: &usize| (number[&(i, k)], k)));
            steps.forward_rows.push(start..steps.forward.len());
            let start = steps.back.len();
            steps.back.extend(cols[i].iter().map(|&k: &usize| (number[&(k, i)], k)));
            steps.back_columns.push(start..steps.back.len());
        }
        LdlPlan { order, rows, cols, fill_in, entries, shared, steps }
    }

    /// Size of the matrix.
    pub fn size(&self) -> usize {
        self.order.len()
    }

    /// The order the rows are eliminated in.
    pub fn order(&self) -> &[usize] {
        &self.order
    }

    /// Entries of `L` that are nonzero where the matrix has a structural zero.
    pub fn fill_in(&self) -> usize {
        self.fill_in
    }

    /// True when nothing is skipped and the order is the matrix's own: the generic solve.
    pub fn is_dense(&self) -> bool {
        self.order.iter().enumerate().all(|(k, &i)| k == i) && self.rows.iter().enumerate().all(|(i, r)| r.len() == i)
    }

    /// Operations of the solve: per pivot one reciprocal and one scaling, per entry of `L`
    /// its share of the pivot, its division by the pivot (a product with the reciprocal) and
    /// both triangular solves, and per pair of entries in one column one multiply-add. The
    /// entry before its division is `L D`'s, so `L D` costs nothing more.
    pub fn cost(&self) -> OpCount {
        let n = self.size();
        let mut c = OpCount { div: n, mul: n, ..OpCount::default() };
        for (_, _, shared) in &self.entries {
            // The pivot's share, l = s / d, forward and back substitution, and the entry's own
            // multiply-adds.
            c.mul += 4 + shared.len();
            c.add += 3 + shared.len();
        }
        c
    }

    /// One line for the summary and `inspect`: the order, what it skips and what it costs.
    pub fn describe(&self) -> String {
        let n = self.size();
        let dense = LdlPlan::dense(n).cost().total();
        if self.is_dense() {
            return format!("LDL^T, dense {n} x {n}, {dense} operations");
        }
        let entries: usize = self.rows.iter().map(Vec::len).sum();
        let zeros = n * n.saturating_sub(1) / 2 - entries;
        let order: Vec<String> = self.order.iter().map(|i| (i + 1).to_string()).collect();
        format!(
            "LDL^T, rows eliminated in the order [{}], {zeros} of {} entries of L structurally zero ({} fill-in), {} operations ({dense} dense)",
            order.join(", "),
            n * n.saturating_sub(1) / 2,
            self.fill_in,
            self.cost().total()
        )
    }

    /// Solves `a x = b` in place for the row-major `n x n` matrix `a` (both triangles given),
    /// as the emitted code does: the reference its twins are held to bit for bit (the tape the
    /// evaluator compiles, [`Self::tape`], and its looped dense solve, `eval::model::solve_spd`),
    /// which run in its place; `Err(column)` when the pivot of `column` (of the matrix) is not
    /// above `PIVOT_TOLERANCE` times the largest diagonal entry. `scratch` holds `L`, `L D`
    /// (each entry before its division by the pivot), the reciprocals of `D` and the permuted
    /// right-hand side.
    pub fn solve(&self, a: &[f64], b: &mut [f64], scratch: &mut Vec<f64>) -> Result<(), usize> {
        let n = self.size();
        let (o, st, m) = (&self.order, &self.steps, self.entries.len());
        // Every slot is written before it is read: no clearing from call to call.
        if scratch.len() < 2 * m + 2 * n {
            scratch.resize(2 * m + 2 * n, 0.0);
        }
        let (l, rest) = scratch.split_at_mut(m);
        let (u, rest) = rest.split_at_mut(m);
        let (inv, y) = rest.split_at_mut(n);
        let mut scale = 0.0f64;
        for i in 0..n {
            scale = scale.max(a[i * n + i].abs());
        }
        for (j, (diagonal, row, column)) in st.pivots.iter().enumerate() {
            let mut dj = a[*diagonal];
            for &e in &st.row_entries[row.clone()] {
                dj -= l[e] * u[e];
            }
            if !(dj > super::solvers::PIVOT_TOLERANCE * scale) {
                return Err(o[j]);
            }
            inv[j] = 1.0 / dj;
            for e in column.clone() {
                let (element, products) = &st.elements[e];
                let mut s = a[*element];
                for &(ik, jk) in &st.products[products.clone()] {
                    s -= l[ik] * u[jk];
                }
                u[e] = s;
                l[e] = s * inv[j];
            }
        }
        // The permuted right-hand side, then forward substitution, scaling, back substitution.
        for (i, &oi) in o.iter().enumerate() {
            y[i] = b[oi];
        }
        for i in 0..n {
            for &(e, k) in &st.forward[st.forward_rows[i].clone()] {
                y[i] -= l[e] * y[k];
            }
        }
        for i in 0..n {
            y[i] *= inv[i];
        }
        for i in (0..n).rev() {
            for &(e, k) in &st.back[st.back_columns[i].clone()] {
                y[i] -= l[e] * y[k];
            }
        }
        for (i, &oi) in o.iter().enumerate() {
            b[oi] = y[i];
        }
        Ok(())
    }

    /// [`Self::solve`] as a tape, for a backend to compile: inputs the row-major matrix then the
    /// right-hand side, outputs the solution (in the right-hand side's order) then the pivots
    /// `D` in elimination order. The same operations in the same order as `solve`, so where
    /// every pivot is above `PIVOT_TOLERANCE` times the largest diagonal entry (checked by the
    /// caller on the pivots, [`Self::checked`]) the same numbers.
    pub fn tape(&self) -> Tape {
        let n = self.size();
        let (o, st, m) = (&self.order, &self.steps, self.entries.len());
        Tape::write(|w| {
            let (mut l, mut u) = (vec![0u32; m], vec![0u32; m]);
            let (mut inv, mut pivots) = (Vec::with_capacity(n), Vec::with_capacity(n));
            let one = w.constant(1.0);
            let minus_product = |w: &mut Writer, acc: u32, x: u32, y: u32| {
                let p = w.instr(Instr::Mul(x, y));
                w.instr(Instr::Sub(acc, p))
            };
            for (j, (diagonal, row, column)) in st.pivots.iter().enumerate() {
                let mut dj = w.input(*diagonal);
                for &e in &st.row_entries[row.clone()] {
                    dj = minus_product(w, dj, l[e], u[e]);
                }
                pivots.push(dj);
                inv.push(w.instr(Instr::Div(one, dj)));
                for e in column.clone() {
                    let (element, products) = &st.elements[e];
                    let mut s = w.input(*element);
                    for &(ik, jk) in &st.products[products.clone()] {
                        s = minus_product(w, s, l[ik], u[jk]);
                    }
                    u[e] = s;
                    l[e] = w.instr(Instr::Mul(s, inv[j]));
                }
            }
            let mut y: Vec<u32> = o.iter().map(|&oi| w.input(n * n + oi)).collect();
            for i in 0..n {
                for &(e, k) in &st.forward[st.forward_rows[i].clone()] {
                    y[i] = minus_product(w, y[i], l[e], y[k]);
                }
            }
            for i in 0..n {
                y[i] = w.instr(Instr::Mul(y[i], inv[i]));
            }
            for i in (0..n).rev() {
                for &(e, k) in &st.back[st.back_columns[i].clone()] {
                    y[i] = minus_product(w, y[i], l[e], y[k]);
                }
            }
            let mut x = vec![0u32; n];
            for (i, &oi) in o.iter().enumerate() {
                x[oi] = y[i];
            }
            x.extend(pivots);
            x
        })
    }

    /// `Err(column)` of the first pivot of `pivots` (in elimination order, as [`Self::tape`]
    /// gives them) that is not above `PIVOT_TOLERANCE` times the largest diagonal entry of the
    /// row-major matrix `a`: [`Self::solve`]'s check.
    pub fn checked(&self, a: &[f64], pivots: &[f64]) -> Result<(), usize> {
        let n = self.size();
        let scale = (0..n).fold(0.0f64, |s, i| s.max(a[i * n + i].abs()));
        match pivots.iter().position(|&d| !(d > super::solvers::PIVOT_TOLERANCE * scale)) {
            Some(j) => Err(self.order[j]),
            None => Ok(()),
        }
    }

    /// The solve as straight-line code: `fn solve_ldl(a: &[[f64; MATRIX_SIZE]; MATRIX_SIZE],
    /// b: &mut [f64; MATRIX_SIZE]) -> Result<(), usize>`, the same operations as [`Self::solve`];
    /// with `fma`, each product subtracted is fused.
    pub fn emit(&self, splices: &mut Splices, fma: bool) -> TokenStream {
        use super::syntax::{assign_stmt, binary, ident, index, let_stmt, literal};
        let n = self.size();
        let o = &self.order;
        let (l, u) = (|i: usize, k: usize| format!("l{i}_{k}"), |i: usize, k: usize| format!("u{i}_{k}"));
        let (d, inv) = (|j: usize| format!("d{j}"), |j: usize| format!("inv{j}"));
        let (y, x) = (|i: usize| format!("y{i}"), |i: usize| format!("x{i}"));
        let mul = |a: String, b: String| binary(ident(&a), syn::BinOp::Mul(Default::default()), ident(&b));
        // `first - a0 * b0 - a1 * b1 ...`, the products in the order given.
        let minus_products = |first: syn::Expr, products: Vec<(String, String)>| {
            products.into_iter().fold(first, |acc, (a, b)| binary(acc, syn::BinOp::Sub(Default::default()), mul(a, b)))
        };
        // `a[i][j]`.
        let entry = |i: usize, j: usize| {
            syn::Expr::Index(syn::ExprIndex {
                attrs: vec![],
                expr: Box::new(index("a", i)),
                bracket_token: Default::default(),
                index: Box::new(literal(Literal::usize_unsuffixed(j))),
            })
        };
        // The straight-line code is built as trees (a 20 x 20 solve is thousands of products,
        // which syn would otherwise parse back from tokens); the few fixed statements are parsed.
        let mut stmts: Vec<syn::Stmt> = Vec::new();
        let diagonal = (0..n).map(|i| {
            let i = Literal::usize_unsuffixed(i);
            quote!(.max(a[#i][#i].abs()))
        });
        stmts.push(syn::parse_quote!(let scale = 0.0f64 #(#diagonal)*;));
        for j in 0..n {
            let oj = o[j];
            let products = self.rows[j].iter().map(|&k| (l(j, k), u(j, k))).collect();
            stmts.push(let_stmt(&d(j), minus_products(entry(oj, oj), products)));
            let (dj, oj_lit) = (Ident::new(&d(j), Span::call_site()), Literal::usize_unsuffixed(oj));
            stmts.push(syn::parse_quote! {
                if !(#dj > PIVOT_TOLERANCE * scale) {
                    return Err(#oj_lit);
                }
            });
            stmts.push(let_stmt(&inv(j), binary(literal(Literal::f64_unsuffixed(1.0)), syn::BinOp::Div(Default::default()), ident(&d(j)))));
            for (i, _, ks) in self.entries.iter().filter(|e| e.1 == j) {
                let i = *i;
                let products = self.shared[ks.clone()].iter().map(|&k| (l(i, k), u(j, k))).collect();
                stmts.push(let_stmt(&u(i, j), minus_products(entry(o[i], oj), products)));
                stmts.push(let_stmt(&l(i, j), mul(u(i, j), inv(j))));
            }
        }
        for i in 0..n {
            let products = self.rows[i].iter().map(|&k| (l(i, k), y(k))).collect();
            stmts.push(let_stmt(&y(i), minus_products(index("b", o[i]), products)));
        }
        for i in (0..n).rev() {
            let products = self.cols[i].iter().map(|&k| (l(k, i), x(k))).collect();
            stmts.push(let_stmt(&x(i), minus_products(mul(y(i), inv(i)), products)));
            stmts.push(assign_stmt(index("b", o[i]), ident(&x(i))));
        }
        if fma {
            super::fma::fuse_stmts(&mut stmts);
        }
        let stmts = splices.stmts(stmts);
        let order: Vec<String> = self.order.iter().map(|i| i.to_string()).collect();
        let doc = format!(
            "Solves `a x = b` in place for the symmetric positive definite `a` by `L D L^T`, rows eliminated in the order [{}] (counted from 0), skipping the structural zeros ({} fill-in); `Err(column)` when a pivot is not above `PIVOT_TOLERANCE` times the largest diagonal entry.",
            order.join(", "),
            self.fill_in
        );
        quote! {
            #[doc = #doc]
            #[allow(clippy::all)]
            #[inline(never)]
            fn solve_ldl(a: &[[f64; MATRIX_SIZE]; MATRIX_SIZE], b: &mut [f64; MATRIX_SIZE]) -> Result<(), usize> {
                #stmts
                Ok(())
            }
        }
    }
}

/// How a formulation's right-hand side solves its matrix, decided from its equations alone.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Solve {
    /// Lagrange's (indefinite with multipliers): the generic LU with partial pivoting of size `n`.
    Lu(usize),
    /// The symmetric positive definite matrices of the other formulations.
    Ldl(Box<LdlPlan>),
    /// No solve: the right-hand side's body gives the speeds' rates by the articulated-body
    /// recursion (`formulation::articulated`), having checked its `pivots`.
    Articulated { pivots: usize },
}

impl Solve {
    /// The solve of `f`'s matrix: `L D L^T` planned on its structural zeros where the matrix is
    /// symmetric positive definite (every formulation's but Lagrange's with constraints, whose
    /// multipliers make it indefinite), LU otherwise.
    pub fn for_equations(f: &Equations) -> Solve {
        let n = f.mass.rows;
        // Lagrange's matrix is `M` alone when there are no multipliers.
        if !f.kind.solves_positive_definite() && n > f.kept.len() {
            return Solve::Lu(n);
        }
        let nonzero = |i: usize, j: usize| !f.mass.get(i.min(j), i.max(j)).is_zero();
        let dense = (0..n).all(|i| (0..i).all(|j| nonzero(i, j)));
        Solve::Ldl(Box::new(if dense { LdlPlan::dense(n) } else { LdlPlan::new(n, nonzero) }))
    }

    /// Operations of the solve (LU: its worst case).
    pub fn cost(&self) -> OpCount {
        match self {
            Solve::Lu(n) => super::solvers::solve_cost(*n),
            Solve::Ldl(plan) => plan.cost(),
            Solve::Articulated { .. } => OpCount::default(),
        }
    }

    /// One line for the summary and `inspect`.
    pub fn describe(&self) -> String {
        match self {
            Solve::Lu(n) => format!("LU with partial pivoting, {n} x {n}, at most {} operations", self.cost().total()),
            Solve::Ldl(plan) => plan.describe(),
            Solve::Articulated { pivots } => format!("no solve: the articulated-body recursion gives the rates, {pivots} pivots checked"),
        }
    }

    /// True where the right-hand side assembles a matrix to solve (not by the articulated-body
    /// recursion).
    pub fn reads_matrix(&self) -> bool {
        !matches!(self, Solve::Articulated { .. })
    }

    /// The plan, where it is `L D L^T` skipping structural zeros (emitted as `solve_ldl`).
    pub fn sparse(&self) -> Option<&LdlPlan> {
        match self {
            Solve::Ldl(plan) if !plan.is_dense() || plan.size() <= super::solvers::MAX_UNROLLED_DENSE => Some(plan),
            _ => None,
        }
    }
}

/// Operations of eliminating a row whose remaining neighbours number `degree`: the terms of
/// [`LdlPlan::cost`] that the row's column of `L` brings.
fn elimination_cost(degree: u32) -> u64 {
    let d = u64::from(degree);
    d * d + 6 * d + 2
}

/// The rows still to eliminate that row `v` reaches through eliminated ones (`done`): its
/// column of `L` once the rows in `done` are eliminated.
fn reach(adjacency: &[u64], v: usize, done: u64) -> u64 {
    let (mut seen, mut frontier) = (1u64 << v, adjacency[v]);
    let mut out = 0u64;
    while frontier & !seen != 0 {
        let new = frontier & !seen;
        seen |= new;
        out |= new & !done;
        let mut through = new & done;
        frontier = 0;
        while through != 0 {
            let u = through.trailing_zeros() as usize;
            through &= through - 1;
            frontier |= adjacency[u];
        }
    }
    out
}

/// The order with the least work, exactly: the cost still to come from every set of rows
/// already eliminated, then the lowest-numbered row that keeps to it at each step.
fn least_work_order(adjacency: &[u64]) -> Vec<usize> {
    let n = adjacency.len();
    let full = (1u64 << n) - 1;
    let mut to_come = vec![0u64; 1 << n];
    for done in (0..full).rev() {
        to_come[done as usize] = (0..n)
            .filter(|&v| done & 1 << v == 0)
            .map(|v| elimination_cost(reach(adjacency, v, done).count_ones()) + to_come[(done | 1 << v) as usize])
            .min()
            .expect("a row is left");
    }
    let mut done = 0u64;
    let mut order = Vec::with_capacity(n);
    while done != full {
        let v = (0..n)
            .find(|&v| {
                done & 1 << v == 0 && elimination_cost(reach(adjacency, v, done).count_ones()) + to_come[(done | 1 << v) as usize] == to_come[done as usize]
            })
            .expect("some row keeps to the least work");
        order.push(v);
        done |= 1 << v;
    }
    order
}

/// The minimum-degree order: at each step the row with the fewest remaining neighbours (the
/// lowest-numbered among equals).
fn minimum_degree_order(adjacency: &[u64]) -> Vec<usize> {
    let n = adjacency.len();
    let mut done = 0u64;
    let mut order = Vec::with_capacity(n);
    for _ in 0..n {
        let v = (0..n).filter(|&v| done & 1 << v == 0).min_by_key(|&v| reach(adjacency, v, done).count_ones()).expect("a row is left");
        order.push(v);
        done |= 1 << v;
    }
    order
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
    }

    /// A random symmetric positive definite matrix with the zeros of `pattern`: a dominant
    /// diagonal.
    fn matrix(n: usize, pattern: &dyn Fn(usize, usize) -> bool, rng: &mut Rng) -> Vec<f64> {
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..i {
                if pattern(i, j) {
                    let x = rng.next();
                    a[i * n + j] = x;
                    a[j * n + i] = x;
                }
            }
        }
        for i in 0..n {
            a[i * n + i] = 1.0 + (0..n).map(|j| a[i * n + j].abs()).sum::<f64>();
        }
        a
    }

    #[test]
    fn the_dense_plan_costs_what_the_generic_solve_does() {
        for n in 1..10 {
            assert_eq!(LdlPlan::dense(n).cost(), super::super::solvers::spd_cost(n), "n = {n}");
            assert!(LdlPlan::new(n, |_, _| true).is_dense());
        }
    }

    #[test]
    fn every_plan_solves_its_matrix_and_costs_no_more_than_dense() {
        let mut rng = Rng(0x2545_f491_4f6c_dd1d);
        for n in [1, 2, 3, 5, 7, 9, 16, 20] {
            for trial in 0..20 {
                // Structural zeros at random, at densities from sparse to nearly full.
                let density = 0.1 + 0.04 * trial as f64;
                let mask: Vec<bool> = (0..n * n).map(|_| rng.next() + 0.5 < density).collect();
                let pattern = |i: usize, j: usize| mask[i.max(j) * n + i.min(j)];
                let a = matrix(n, &pattern, &mut rng);
                let plan = LdlPlan::new(n, pattern);
                assert!(plan.cost().total() <= LdlPlan::dense(n).cost().total());
                let x: Vec<f64> = (0..n).map(|_| rng.next()).collect();
                let mut b: Vec<f64> = (0..n).map(|i| (0..n).map(|j| a[i * n + j] * x[j]).sum()).collect();
                plan.solve(&a, &mut b, &mut Vec::new()).unwrap();
                for (got, want) in b.iter().zip(&x) {
                    assert!((got - want).abs() < 1e-13, "n = {n}, trial {trial}: {got} against {want}");
                }
            }
        }
    }

    /// The plan's tape (what the JIT compiles) gives `solve`'s numbers to the bit, and its
    /// pivots the same refusal, on random patterns and on singular and indefinite matrices.
    #[test]
    fn the_tape_of_a_plan_is_its_solve() {
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
        let by_tape = |plan: &LdlPlan, a: &[f64], b: &[f64]| {
            let n = plan.size();
            let mut out = vec![0.0; 2 * n];
            plan.tape().eval(&[a, b].concat(), &mut out);
            plan.checked(a, &out[n..]).map(|()| out[..n].to_vec())
        };
        for n in [1, 2, 4, 7, 12, 21] {
            for trial in 0..6 {
                let density = 0.15 * trial as f64 + 0.1;
                let mask: Vec<bool> = (0..n * n).map(|_| rng.next() + 0.5 < density).collect();
                let pattern = |i: usize, j: usize| mask[i.max(j) * n + i.min(j)];
                let a = matrix(n, &pattern, &mut rng);
                let b: Vec<f64> = (0..n).map(|_| rng.next()).collect();
                for plan in [LdlPlan::new(n, pattern), LdlPlan::dense(n)] {
                    let mut solved = b.clone();
                    plan.solve(&a, &mut solved, &mut Vec::new()).unwrap();
                    let taped = by_tape(&plan, &a, &b).unwrap();
                    assert_eq!(
                        taped.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                        solved.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                        "n = {n}, trial {trial}"
                    );
                }
            }
        }
        let plan = LdlPlan::new(3, |i, j| i == j || (i, j) == (2, 0));
        for a in [[1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0], [1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0]] {
            let refused = plan.solve(&a, &mut [1.0, 1.0, 1.0], &mut Vec::new()).unwrap_err();
            assert_eq!(by_tape(&plan, &a, &[1.0, 1.0, 1.0]), Err(refused));
        }
    }

    #[test]
    fn the_least_work_order_is_no_worse_than_any_other() {
        // Every permutation of a 6 x 6 pattern, against the plan's.
        let mut rng = Rng(7);
        for _ in 0..10 {
            let n = 6;
            let mask: Vec<bool> = (0..n * n).map(|_| rng.next() > 0.1).collect();
            let pattern = |i: usize, j: usize| mask[i.max(j) * n + i.min(j)];
            let best = LdlPlan::new(n, pattern).cost().total();
            let mut order: Vec<usize> = (0..n).collect();
            let mut c = vec![0; n];
            let mut i = 0;
            // Heap's algorithm.
            while i < n {
                if c[i] < i {
                    order.swap(if i % 2 == 0 { 0 } else { c[i] }, i);
                    assert!(best <= LdlPlan::with_order(n, pattern, order.clone()).cost().total(), "{order:?}");
                    c[i] += 1;
                    i = 0;
                } else {
                    c[i] = 0;
                    i += 1;
                }
            }
        }
    }

    #[test]
    fn a_tree_is_factored_without_fill_in() {
        // A branched tree's mass matrix: a joint couples to its ancestors only. Leaves first.
        let parent = [usize::MAX, 0, 1, 1, 0, 4, 4];
        let ancestor = |mut i: usize, j: usize| {
            while i != usize::MAX {
                if i == j {
                    return true;
                }
                i = parent[i];
            }
            false
        };
        let plan = LdlPlan::new(7, |i, j| ancestor(i, j) || ancestor(j, i));
        assert_eq!(plan.fill_in(), 0);
        assert!(plan.describe().contains("(0 fill-in)"), "{}", plan.describe());
    }

    #[test]
    fn a_pivot_that_is_not_positive_names_its_column() {
        let plan = LdlPlan::new(3, |i, j| i == j || (i, j) == (2, 0));
        // Columns 0 and 2 coupled: [[1, 0, 1], [0, 1, 0], [1, 0, 1]] is singular in column 2 or 0.
        let a = [1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0];
        let failed = plan.solve(&a, &mut [1.0, 1.0, 1.0], &mut Vec::new()).unwrap_err();
        assert!(failed == 0 || failed == 2, "{failed}");
        let negative = [1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0];
        assert_eq!(plan.solve(&negative, &mut [1.0, 1.0, 1.0], &mut Vec::new()), Err(1));
    }
}

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::emit::ldl::LdlPlan;
        // An arrow matrix: the dense row and column first would fill everything in; once at most
        // one other row is left, nothing.
        let arrow = |i: usize, j: usize| i == j || i == 0 || j == 0;
        let plan = LdlPlan::new(4, arrow);
        assert_eq!(plan.order(), &[1, 2, 0, 3]);
        assert_eq!(plan.fill_in(), 0);
        assert!(plan.cost().total() < LdlPlan::dense(4).cost().total());
        let mut b = [4.0, 1.0, 1.0, 1.0];
        let a = [4.0, 1.0, 1.0, 1.0, 1.0, 2.0, 0.0, 0.0, 1.0, 0.0, 2.0, 0.0, 1.0, 0.0, 0.0, 2.0];
        plan.solve(&a, &mut b, &mut Vec::new()).unwrap();
        // x = (1, 0, 0, 0) solves it: a's first column is b.
        assert!(b.iter().zip([1.0, 0.0, 0.0, 0.0]).all(|(x, e)| (x - e).abs() < 1e-15));
    }
    #[test]
    fn dense_example() {
        let plan = crate::emit::ldl::LdlPlan::dense(3);
        assert!(plan.is_dense());
        assert_eq!(plan.cost().div, 3);
    }
    #[test]
    fn new_example() {
        use crate::emit::ldl::LdlPlan;
        let diagonal = LdlPlan::new(3, |i, j| i == j);
        assert_eq!((diagonal.order(), diagonal.cost().total()), (&[0, 1, 2][..], 6));
    }
    #[test]
    fn tape_example() {
        use crate::emit::ldl::LdlPlan;
        let plan = LdlPlan::dense(2);
        let tape = plan.tape();
        let (a, mut b) = ([4.0, 2.0, 2.0, 3.0], [2.0, 1.0]);
        let mut out = [0.0; 4];
        tape.eval(&[a[0], a[1], a[2], a[3], b[0], b[1]], &mut out);
        plan.solve(&a, &mut b, &mut Vec::new()).unwrap();
        assert_eq!(out[..2], b);
        assert_eq!(plan.checked(&a, &out[2..]), Ok(()));
    }
    #[test]
    fn for_equations_example() {
        use crate::emit::ldl::Solve;
        let model = crate::model::load("../models/satellite_boom.ron").unwrap();
        let d = crate::formulation::derive(&model, &crate::formulation::Request::all()).unwrap();
        let kane = Solve::for_equations(d.equations("kane").unwrap());
        assert!(matches!(&kane, Solve::Ldl(plan) if !plan.is_dense()));
        // No constraints: Lagrange's matrix is the mass matrix itself.
        assert!(matches!(Solve::for_equations(d.equations("lagrange").unwrap()), Solve::Ldl(_)));
        // One constraint: its multiplier makes the matrix indefinite.
        let model = crate::model::load("../models/cart_pendulum.ron").unwrap();
        let d = crate::formulation::derive(&model, &crate::formulation::Request::all()).unwrap();
        assert!(matches!(Solve::for_equations(d.equations("lagrange").unwrap()), Solve::Lu(4)));
    }
}
