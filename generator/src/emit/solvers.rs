//! What the dense solves an emitted module calls cost: `seam::solve`'s `solve_dense` (Gaussian
//! elimination with partial pivoting, for Lagrange's equations with constraints) and the generic
//! `solve_spd` (`L D L^T` without pivoting, where a matrix has no structural zero to skip;
//! elsewhere a formulation's own plan, [`super::ldl`]); the relative pivot tolerance they share
//! is the seam's.

use super::ops::OpCount;

/// Relative size below which a pivot of the mass matrix counts as zero: the seam's, which its
/// solves use.
pub(crate) const PIVOT_TOLERANCE: f64 = seam::solve::PIVOT_TOLERANCE;

/// The cost of `solve_spd` (`LDL^T`, no pivoting) for `n` unknowns: the factorization's
/// `n^3 / 6` multiply-adds, one reciprocal per pivot, two triangular solves and the scaling.
pub fn spd_cost(n: usize) -> OpCount {
    let factor_mul: usize = (0..n).map(|j| j + (n - 1 - j) * (j + 1)).sum();
    let factor_add: usize = (0..n).map(|j| j + (n - 1 - j) * j).sum();
    let triangles = n * n.saturating_sub(1);
    OpCount { add: factor_add + triangles, mul: factor_mul + triangles + n, div: n, neg: 0, calls: Default::default() }
}

/// The worst-case cost of `solve_dense` for `n` unknowns.
pub fn solve_cost(n: usize) -> OpCount {
    let elim_div = n * n.saturating_sub(1) / 2;
    let elim_mul: usize = (0..n).map(|c| (n - 1 - c) * (n - c)).sum();
    let back = n * n.saturating_sub(1) / 2;
    OpCount { add: elim_mul + back, mul: elim_mul + back, div: elim_div + n, neg: 0, calls: Default::default() }
}

/// The largest dense symmetric positive definite matrix whose solve is emitted unrolled
/// (`solve_ldl`); larger ones call the looped `solve_spd`.
pub const MAX_UNROLLED_DENSE: usize = 16;

/// The examples that were this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::emit::solvers::{solve_cost, spd_cost};
        // L D L^T takes fewer multiplications than Gaussian elimination, and one division per pivot
        // where elimination divides once per entry below the diagonal and once per unknown.
        assert!(spd_cost(20).mul < solve_cost(20).mul);
        assert_eq!((spd_cost(20).div, solve_cost(20).div), (20, 20 * 19 / 2 + 20));
    }
}
