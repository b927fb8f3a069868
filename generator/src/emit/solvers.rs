//! The solvers an emitted module carries and what they cost: `solve_dense` (Gaussian elimination
//! with partial pivoting, for Lagrange's equations with constraints), the generic `solve_spd`
//! (`L D L^T` without pivoting, where a matrix has no structural zero to skip; elsewhere a
//! formulation's own plan, [`super::ldl`]), and `lu_factor` / `lu_solve` for the Jacobians;
//! the relative pivot tolerance they share.
//!
//! ```
//! use generator::emit::solvers::{solve_cost, spd_cost};
//! // L D L^T takes fewer multiplications than Gaussian elimination, and one division per pivot
//! // where elimination divides once per entry below the diagonal and once per unknown.
//! assert!(spd_cost(20).mul < solve_cost(20).mul);
//! assert_eq!((spd_cost(20).div, solve_cost(20).div), (20, 20 * 19 / 2 + 20));
//! ```

use super::ops::OpCount;
use proc_macro2::TokenStream;
use quote::quote;

/// Relative size below which a pivot of the mass matrix counts as zero.
pub(crate) const PIVOT_TOLERANCE: f64 = 1e-13;

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

/// `solve_dense`: Gaussian elimination with partial pivoting, for Lagrange's equations with
/// constraints (an indefinite matrix).
pub(super) fn solve_dense() -> TokenStream {
    quote! {
        #[doc = "Solves `a x = b` in place by Gaussian elimination with partial pivoting; `Err(column)` when a pivot is below `PIVOT_TOLERANCE` times the largest entry."]
        fn solve_dense<const N: usize>(a: &mut [[f64; N]; N], b: &mut [f64; N]) -> Result<(), usize> {
            let mut scale = 0.0f64;
            for row in a.iter() {
                for x in row.iter() {
                    scale = scale.max(x.abs());
                }
            }
            for c in 0..N {
                let mut p = c;
                for r in c + 1..N {
                    if a[r][c].abs() > a[p][c].abs() {
                        p = r;
                    }
                }
                if !(a[p][c].abs() > PIVOT_TOLERANCE * scale) {
                    return Err(c);
                }
                a.swap(c, p);
                b.swap(c, p);
                for r in c + 1..N {
                    let f = a[r][c] / a[c][c];
                    for k in c + 1..N {
                        a[r][k] -= f * a[c][k];
                    }
                    b[r] -= f * b[c];
                }
            }
            for r in (0..N).rev() {
                let mut s = b[r];
                for k in r + 1..N {
                    s -= a[r][k] * b[k];
                }
                b[r] = s / a[r][r];
            }
            Ok(())
        }
    }
}

/// `solve_spd`: the generic `L D L^T` without pivoting, for a symmetric positive definite
/// matrix with no structural zero to skip.
/// The largest dense symmetric positive definite matrix whose solve is emitted unrolled
/// (`solve_ldl`); larger ones call the looped `solve_spd`.
pub const MAX_UNROLLED_DENSE: usize = 16;

pub(super) fn solve_spd() -> TokenStream {
    quote! {
        #[doc = "Solves `a x = b` in place for a symmetric positive definite `a` (both triangles given) by `a = L D L^T` without pivoting, one reciprocal per pivot; `Err(column)` when a pivot is not above `PIVOT_TOLERANCE` times the largest diagonal entry (singular, or not positive definite). Used where the matrix has no structural zero to skip; elsewhere the formulation's own `solve_ldl` skips them."]
        #[allow(dead_code)]
        fn solve_spd<const N: usize>(a: &mut [[f64; N]; N], b: &mut [f64; N]) -> Result<(), usize> {
            let mut scale = 0.0f64;
            for i in 0..N {
                scale = scale.max(a[i][i].abs());
            }
            let mut inv = [0.0f64; N];
            // `L` in `a` below the diagonal; `L D` in `u` (each entry before its division by the pivot).
            let mut u = [[0.0f64; N]; N];
            for j in 0..N {
                let mut d = a[j][j];
                for k in 0..j {
                    d -= a[j][k] * u[j][k];
                }
                if !(d > PIVOT_TOLERANCE * scale) {
                    return Err(j);
                }
                inv[j] = 1.0 / d;
                for i in j + 1..N {
                    let mut s = a[i][j];
                    for k in 0..j {
                        s -= a[i][k] * u[j][k];
                    }
                    u[i][j] = s;
                    a[i][j] = s * inv[j];
                }
            }
            for i in 0..N {
                for k in 0..i {
                    b[i] -= a[i][k] * b[k];
                }
            }
            for i in 0..N {
                b[i] *= inv[i];
            }
            for i in (0..N).rev() {
                for k in i + 1..N {
                    b[i] -= a[k][i] * b[k];
                }
            }
            Ok(())
        }
    }
}

/// `lu_factor` and `lu_solve`: the factorization `solve_dense` performs, kept for many
/// right-hand sides.
pub(super) fn lu_items() -> TokenStream {
    quote! {
        #[doc = "Factors `a` in place (`P a = L U`, partial pivoting, `L` unit lower below the diagonal); the row taken at each step, or `Err(column)` when a pivot is below `PIVOT_TOLERANCE` times the largest entry."]
        fn lu_factor<const N: usize>(a: &mut [[f64; N]; N]) -> Result<[usize; N], usize> {
            let mut scale = 0.0f64;
            for row in a.iter() {
                for x in row.iter() {
                    scale = scale.max(x.abs());
                }
            }
            let mut pivots = [0usize; N];
            for c in 0..N {
                let mut p = c;
                for r in c + 1..N {
                    if a[r][c].abs() > a[p][c].abs() {
                        p = r;
                    }
                }
                if !(a[p][c].abs() > PIVOT_TOLERANCE * scale) {
                    return Err(c);
                }
                pivots[c] = p;
                a.swap(c, p);
                for r in c + 1..N {
                    let f = a[r][c] / a[c][c];
                    a[r][c] = f;
                    for k in c + 1..N {
                        a[r][k] -= f * a[c][k];
                    }
                }
            }
            Ok(pivots)
        }
        #[doc = "Solves `a x = b` in place with the factors of `lu_factor`."]
        fn lu_solve<const N: usize>(a: &[[f64; N]; N], pivots: &[usize; N], b: &mut [f64; N]) {
            for c in 0..N {
                b.swap(c, pivots[c]);
            }
            for c in 0..N {
                for r in c + 1..N {
                    b[r] -= a[r][c] * b[c];
                }
            }
            for r in (0..N).rev() {
                let mut s = b[r];
                for k in r + 1..N {
                    s -= a[r][k] * b[k];
                }
                b[r] = s / a[r][r];
            }
        }
    }
}
