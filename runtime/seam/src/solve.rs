//! The dense linear solves every model uses, written once: emitted modules call them on their
//! fixed-size arrays (the `*_array` forms, no allocation), the in-process evaluator on row-major
//! slices ([`Rows`]): one generic routine each, over [`Square`]. Both run the same operations
//! in the same order, so a module and its evaluation give the same numbers.
//!
//! - [`solve_dense`]: Gaussian elimination with partial pivoting (Lagrange's equations with
//!   constraints: an indefinite matrix), as [`lu_factor`] then [`lu_solve`];
//! - [`solve_spd`]: `L D L^T` without pivoting, one reciprocal per pivot, for a symmetric
//!   positive definite matrix with no structural zero to skip (a formulation whose matrix has
//!   some gets its own unrolled plan from the generator);
//! - [`lu_factor`] and [`lu_solve`]: the factors kept for many right-hand sides (the exact
//!   Jacobians);
//! - [`baumgarte`]: the stabilized constraints' forcing, before Lagrange's solve.
//!
//! Each returns `Err(column)` where a pivot is not above [`PIVOT_TOLERANCE`] times the matrix's
//! scale (for `L D L^T`, not positive: the matrix is singular or not positive definite).
//!
//! ```
//! // 4 x + y = 1, x + 3 y = 2
//! let mut a = [[4.0, 1.0], [1.0, 3.0]];
//! let mut b = [1.0, 2.0];
//! seam::solve::solve_spd_array(&mut a, &mut b).unwrap();
//! assert!((b[0] - 1.0 / 11.0).abs() < 1e-15 && (b[1] - 7.0 / 11.0).abs() < 1e-15);
//! let mut singular = [[1.0, 2.0], [2.0, 4.0]];
//! assert_eq!(seam::solve::solve_dense_array(&mut singular, &mut [1.0, 1.0]), Err(1));
//! ```

use crate::Failure;
use std::borrow::Cow;

/// Relative size below which a pivot counts as zero.
pub const PIVOT_TOLERANCE: f64 = 1e-13;

/// A square matrix the solves work on in place: an emitted module's `[[f64; N]; N]` (its size
/// known to the compiler, so the loops are as the module's own were) or [`Rows`], a row-major
/// slice of any size (the evaluator's).
pub trait Square {
    /// The number of rows (and columns).
    fn size(&self) -> usize;
    /// Entry `(r, c)`.
    fn at(&self, r: usize, c: usize) -> f64;
    /// Entry `(r, c)`, to write.
    fn at_mut(&mut self, r: usize, c: usize) -> &mut f64;
    /// Exchanges rows `r` and `s`.
    fn swap_rows(&mut self, r: usize, s: usize);
    /// Row `r`, its entries in order (dot products walk them without index checks).
    fn row(&self, r: usize) -> &[f64];
}

impl<const N: usize> Square for [[f64; N]; N] {
    #[inline(always)]
    fn size(&self) -> usize {
        N
    }
    #[inline(always)]
    fn at(&self, r: usize, c: usize) -> f64 {
        self[r][c]
    }
    #[inline(always)]
    fn at_mut(&mut self, r: usize, c: usize) -> &mut f64 {
        &mut self[r][c]
    }
    #[inline(always)]
    fn swap_rows(&mut self, r: usize, s: usize) {
        self.swap(r, s)
    }
    #[inline(always)]
    fn row(&self, r: usize) -> &[f64] {
        &self[r]
    }
}

/// A row-major `n x n` matrix in a slice.
///
/// ```
/// use seam::solve::{Rows, Square};
/// let mut data = [1.0, 2.0, 3.0, 4.0];
/// let mut m = Rows::new(2, &mut data);
/// m.swap_rows(0, 1);
/// assert_eq!((m.at(0, 0), m.at(1, 1)), (3.0, 2.0));
/// ```
pub struct Rows<'a> {
    n: usize,
    data: &'a mut [f64],
}

impl<'a> Rows<'a> {
    /// The first `n * n` entries of `data`, row by row.
    ///
    /// # Panics
    ///
    /// Where `data` is shorter than `n * n`.
    pub fn new(n: usize, data: &'a mut [f64]) -> Rows<'a> {
        Rows { n, data: &mut data[..n * n] }
    }
}

impl Square for Rows<'_> {
    #[inline(always)]
    fn size(&self) -> usize {
        self.n
    }
    #[inline(always)]
    fn at(&self, r: usize, c: usize) -> f64 {
        self.data[r * self.n + c]
    }
    #[inline(always)]
    fn at_mut(&mut self, r: usize, c: usize) -> &mut f64 {
        &mut self.data[r * self.n + c]
    }
    #[inline(always)]
    fn swap_rows(&mut self, r: usize, s: usize) {
        if r != s {
            for k in 0..self.n {
                self.data.swap(r * self.n + k, s * self.n + k);
            }
        }
    }
    #[inline(always)]
    fn row(&self, r: usize) -> &[f64] {
        &self.data[r * self.n..(r + 1) * self.n]
    }
}

/// `a x = b` in place (`a` overwritten by its factors) by Gaussian elimination with partial
/// pivoting: [`lu_factor`] then [`lu_solve`], the same operations in the same order as one pass
/// that eliminates `b` with `a`. `pivots` (at least the size) receives the row taken at each step.
#[inline]
pub fn solve_dense<M: Square>(a: &mut M, b: &mut [f64], pivots: &mut [usize]) -> Result<(), usize> {
    lu_factor(a, pivots)?;
    lu_solve(a, pivots, b);
    Ok(())
}

/// `P a = L U` in place (partial pivoting, `L` unit lower below the diagonal), the row taken at
/// each step into `pivots`.
#[inline]
pub fn lu_factor<M: Square>(a: &mut M, pivots: &mut [usize]) -> Result<(), usize> {
    let n = a.size();
    let mut scale = 0.0f64;
    for r in 0..n {
        for c in 0..n {
            scale = scale.max(a.at(r, c).abs());
        }
    }
    for c in 0..n {
        let mut p = c;
        for r in c + 1..n {
            if a.at(r, c).abs() > a.at(p, c).abs() {
                p = r;
            }
        }
        if !(a.at(p, c).abs() > PIVOT_TOLERANCE * scale) {
            return Err(c);
        }
        pivots[c] = p;
        a.swap_rows(c, p);
        for r in c + 1..n {
            let f = a.at(r, c) / a.at(c, c);
            *a.at_mut(r, c) = f;
            for k in c + 1..n {
                let x = a.at(c, k);
                *a.at_mut(r, k) -= f * x;
            }
        }
    }
    Ok(())
}

/// `a x = b` in place with the factors of [`lu_factor`].
#[inline]
pub fn lu_solve<M: Square>(a: &M, pivots: &[usize], b: &mut [f64]) {
    let n = a.size();
    let b = &mut b[..n];
    for c in 0..n {
        b.swap(c, pivots[c]);
    }
    for c in 0..n {
        for r in c + 1..n {
            b[r] -= a.at(r, c) * b[c];
        }
    }
    for r in (0..n).rev() {
        let mut s = b[r];
        for k in r + 1..n {
            s -= a.at(r, k) * b[k];
        }
        b[r] = s / a.at(r, r);
    }
}

/// `a x = b` in place for a symmetric positive definite `a` (both triangles given; `L` written
/// below its diagonal), by `L D L^T` in the natural order. `u` (the same size) holds `L D`, each
/// entry before its division by the pivot; `inv` (at least the size) the reciprocals of `D`.
#[inline]
pub fn solve_spd<M: Square>(a: &mut M, b: &mut [f64], u: &mut M, inv: &mut [f64]) -> Result<(), usize> {
    let n = a.size();
    let (b, inv) = (&mut b[..n], &mut inv[..n]);
    let mut scale = 0.0f64;
    for i in 0..n {
        scale = scale.max(a.at(i, i).abs());
    }
    // The dot products walk the rows as slices (in the order of `k`, as indexed loops would).
    for j in 0..n {
        let mut d = a.at(j, j);
        for (x, y) in a.row(j)[..j].iter().zip(&u.row(j)[..j]) {
            d -= x * y;
        }
        if !(d > PIVOT_TOLERANCE * scale) {
            return Err(j);
        }
        inv[j] = 1.0 / d;
        for i in j + 1..n {
            let mut s = a.at(i, j);
            for (x, y) in a.row(i)[..j].iter().zip(&u.row(j)[..j]) {
                s -= x * y;
            }
            *u.at_mut(i, j) = s;
            *a.at_mut(i, j) = s * inv[j];
        }
    }
    for i in 0..n {
        let (done, rest) = b.split_at_mut(i);
        for (x, y) in a.row(i)[..i].iter().zip(done.iter()) {
            rest[0] -= x * y;
        }
    }
    for i in 0..n {
        b[i] *= inv[i];
    }
    for i in (0..n).rev() {
        for k in i + 1..n {
            b[i] -= a.at(k, i) * b[k];
        }
    }
    Ok(())
}

/// [`solve_dense`] on an emitted module's array.
#[inline]
pub fn solve_dense_array<const N: usize>(a: &mut [[f64; N]; N], b: &mut [f64; N]) -> Result<(), usize> {
    let mut pivots = [0usize; N];
    solve_dense(a, b, &mut pivots)
}

/// [`solve_spd`] on an emitted module's array (its scratch on the stack).
#[inline]
pub fn solve_spd_array<const N: usize>(a: &mut [[f64; N]; N], b: &mut [f64; N]) -> Result<(), usize> {
    let mut u = [[0.0f64; N]; N];
    let mut inv = [0.0f64; N];
    solve_spd(a, b, &mut u, &mut inv)
}

/// [`lu_factor`] on an emitted module's array: the row taken at each step.
#[inline]
pub fn lu_factor_array<const N: usize>(a: &mut [[f64; N]; N]) -> Result<[usize; N], usize> {
    let mut pivots = [0usize; N];
    lu_factor(a, &mut pivots)?;
    Ok(pivots)
}

/// [`lu_solve`] on an emitted module's array.
#[inline]
pub fn lu_solve_array<const N: usize>(a: &[[f64; N]; N], pivots: &[usize; N], b: &mut [f64; N]) {
    lu_solve(a, pivots, b)
}

/// The failure of a numerical solve of the matrix named `matrix` at time `t`, which found no
/// usable pivot in `column`: [`Failure::SingularMatrix`].
///
/// ```
/// let failed = seam::solve::solve_dense_array(&mut [[1.0, 2.0], [2.0, 4.0]], &mut [1.0, 1.0]);
/// let err = failed.map_err(|column| seam::solve::singular(0.5, "mass matrix", column)).unwrap_err();
/// assert_eq!(err.to_string(), "singular configuration at t = 0.5: mass matrix has no usable pivot in column 1");
/// ```
#[cold]
pub fn singular(t: f64, matrix: impl Into<Cow<'static, str>>, column: usize) -> Failure {
    Failure::SingularMatrix { t, matrix: matrix.into(), column }
}

/// Baumgarte's stabilization of the constraints' rows of a forcing: each constraint at
/// acceleration level becomes `a q'' = gamma - 2 alpha (a q' + b) - beta^2 h`, so row `i` of
/// `force` (the constraints' rows) loses `2 alpha residuals[i] + beta^2 positions[i]` (the
/// velocity residual `a q' + b` and the holonomic residual `h`, zero for a velocity constraint).
/// `alpha = beta = 0` leaves the forcing as it was.
///
/// ```
/// let mut force = [1.0, 0.5];
/// seam::solve::baumgarte(&mut force, &[0.1, 0.2], &[0.01, 0.0], 2.0, 3.0);
/// assert_eq!(force, [1.0 - (2.0 * 2.0 * 0.1 + 9.0 * 0.01), 0.5 - 2.0 * 2.0 * 0.2]);
/// ```
#[inline]
pub fn baumgarte(force: &mut [f64], residuals: &[f64], positions: &[f64], alpha: f64, beta: f64) {
    for ((f, r), h) in force.iter_mut().zip(residuals).zip(positions) {
        *f -= 2.0 * alpha * r + beta * beta * h;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A symmetric positive definite matrix of size `n` (diagonally dominant), and a right-hand
    /// side.
    fn system(n: usize) -> (Vec<f64>, Vec<f64>) {
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] = if i == j { 2.0 * n as f64 } else { 1.0 / (1.0 + (i + j) as f64) };
            }
        }
        (a, (0..n).map(|i| 1.0 + i as f64 * 0.25).collect())
    }

    fn residual(n: usize, a: &[f64], x: &[f64], b: &[f64]) -> f64 {
        (0..n).map(|i| ((0..n).map(|j| a[i * n + j] * x[j]).sum::<f64>() - b[i]).abs()).fold(0.0, f64::max)
    }

    /// Every solve solves, and the array forms give the slice forms' numbers to the bit.
    #[test]
    fn the_solves_solve_and_the_array_forms_are_the_slice_forms() {
        const N: usize = 7;
        let (a, b) = system(N);
        let array = |flat: &[f64]| -> [[f64; N]; N] { std::array::from_fn(|i| std::array::from_fn(|j| flat[i * N + j])) };
        let rhs: [f64; N] = std::array::from_fn(|i| b[i]);
        // L D L^T.
        let (mut a1, mut x1, mut u, mut inv) = (a.clone(), b.clone(), vec![0.0; N * N], vec![0.0; N]);
        solve_spd(&mut Rows::new(N, &mut a1), &mut x1, &mut Rows::new(N, &mut u), &mut inv).unwrap();
        assert!(residual(N, &a, &x1, &b) < 1e-14);
        let (mut a2, mut x2) = (array(&a), rhs);
        solve_spd_array(&mut a2, &mut x2).unwrap();
        assert_eq!(x1.iter().map(|x| x.to_bits()).collect::<Vec<_>>(), x2.iter().map(|x| x.to_bits()).collect::<Vec<_>>());
        // Elimination, and the factors reused.
        let (mut a3, mut x3, mut pivots) = (a.clone(), b.clone(), vec![0; N]);
        solve_dense(&mut Rows::new(N, &mut a3), &mut x3, &mut pivots).unwrap();
        assert!(residual(N, &a, &x3, &b) < 1e-14);
        let (mut a4, mut x4) = (array(&a), rhs);
        solve_dense_array(&mut a4, &mut x4).unwrap();
        assert_eq!(x3, x4.to_vec());
        let mut a5 = array(&a);
        let p = lu_factor_array(&mut a5).unwrap();
        let mut x5 = rhs;
        lu_solve_array(&a5, &p, &mut x5);
        assert_eq!(x5, x4);
    }

    /// A pivot at the tolerance stops the solve at its column; `L D L^T` also refuses a matrix
    /// that is not positive definite; elimination pivots past a zero.
    #[test]
    fn singular_and_indefinite_matrices_name_their_column() {
        let mut singular = [[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [1.0, 0.0, 1.0]];
        assert_eq!(solve_dense_array(&mut singular, &mut [1.0, 1.0, 1.0]), Err(2));
        let mut indefinite = [[1.0, 2.0], [2.0, 1.0]];
        assert_eq!(solve_spd_array(&mut indefinite, &mut [1.0, 1.0]), Err(1));
        // A zero on the diagonal: elimination swaps rows, L D L^T cannot.
        let mut swap = [[0.0, 1.0], [1.0, 0.0]];
        let mut b = [2.0, 3.0];
        solve_dense_array(&mut swap, &mut b).unwrap();
        assert_eq!(b, [3.0, 2.0]);
        assert_eq!(solve_spd_array(&mut [[0.0, 1.0], [1.0, 0.0]], &mut [2.0, 3.0]), Err(0));
    }
}
