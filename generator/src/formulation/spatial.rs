//! Spatial vector algebra over symbolic expressions (Featherstone, *Rigid Body Dynamics
//! Algorithms*, ch. 2): motions, forces, rigid-body inertias in a frame's own components, and
//! the straight-line programs the recursions over a tree of frames write them into.

use crate::kinematics::{Joint, add3, cross, dot, mat_vec};
use crate::symbolic::{Expr, Matrix, Symbol};

/// A spatial motion vector `(omega, v)` at a frame's origin, in its components.
#[derive(Clone, Copy, Debug)]
pub(super) struct Motion {
    pub(super) w: [Expr; 3],
    pub(super) v: [Expr; 3],
}

/// A spatial force `(n, f)`: the moment about a frame's origin and the force.
#[derive(Clone, Copy, Debug)]
pub(super) struct Force {
    pub(super) n: [Expr; 3],
    pub(super) f: [Expr; 3],
}

/// A spatial inertia about a frame's origin: mass, first moment `h = m c`, and the inertia
/// matrix about the origin (symmetric).
#[derive(Clone, Debug)]
pub(super) struct Inertia {
    pub(super) m: Expr,
    pub(super) h: [Expr; 3],
    pub(super) i: Matrix,
}

pub(super) fn zero3() -> [Expr; 3] {
    [Expr::zero(), Expr::zero(), Expr::zero()]
}

pub(super) fn scale3(k: Expr, a: &[Expr; 3]) -> [Expr; 3] {
    a.map(|x| if x.is_zero() || k.is_zero() { Expr::zero() } else { k * x })
}

pub(super) fn sub3(a: &[Expr; 3], b: &[Expr; 3]) -> [Expr; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

impl Motion {
    pub(super) fn is_zero(&self) -> bool {
        self.w.iter().chain(&self.v).all(|e| e.is_zero())
    }
    /// This motion (the parent's) seen in the child's components at its origin.
    pub(super) fn in_child(&self, joint: &Joint) -> Motion {
        let rt = joint.rotation.transpose();
        Motion { w: mat_vec(&rt, &self.w), v: mat_vec(&rt, &add3(&self.v, &cross(&self.w, &joint.translation))) }
    }
    pub(super) fn add(&self, o: &Motion) -> Motion {
        Motion { w: add3(&self.w, &o.w), v: add3(&self.v, &o.v) }
    }
    /// The spatial cross product `self x m` of two motions.
    pub(super) fn cross_motion(&self, m: &Motion) -> Motion {
        Motion { w: cross(&self.w, &m.w), v: add3(&cross(&self.w, &m.v), &cross(&self.v, &m.w)) }
    }
    /// The spatial cross product `self x* f` of a motion and a force.
    pub(super) fn cross_force(&self, f: &Force) -> Force {
        Force { n: add3(&cross(&self.w, &f.n), &cross(&self.v, &f.f)), f: cross(&self.w, &f.f) }
    }
    /// `k self`.
    pub(super) fn scale(&self, k: Expr) -> Motion {
        Motion { w: scale3(k, &self.w), v: scale3(k, &self.v) }
    }
    /// The power `self . f`.
    pub(super) fn power(&self, f: &Force) -> Expr {
        dot(&self.w, &f.n) + dot(&self.v, &f.f)
    }
}

impl Force {
    pub(super) fn zero() -> Force {
        Force { n: zero3(), f: zero3() }
    }
    pub(super) fn is_zero(&self) -> bool {
        self.n.iter().chain(&self.f).all(|e| e.is_zero())
    }
    pub(super) fn add(&self, o: &Force) -> Force {
        Force { n: add3(&self.n, &o.n), f: add3(&self.f, &o.f) }
    }
    /// `k self`.
    pub(super) fn scale(&self, k: Expr) -> Force {
        Force { n: scale3(k, &self.n), f: scale3(k, &self.f) }
    }
    /// This force (the child's) in the parent's components, about its origin.
    pub(super) fn in_parent(&self, joint: &Joint) -> Force {
        let f = mat_vec(&joint.rotation, &self.f);
        Force { n: add3(&mat_vec(&joint.rotation, &self.n), &cross(&joint.translation, &f)), f }
    }
}

impl Inertia {
    pub(super) fn zero() -> Inertia {
        Inertia { m: Expr::zero(), h: zero3(), i: Matrix::zeros(3, 3) }
    }
    pub(super) fn is_zero(&self) -> bool {
        self.m.is_zero() && self.h.iter().all(|e| e.is_zero()) && self.i.data.iter().all(|e| e.is_zero())
    }
    /// A body of mass `m` with its centre of mass at `c` and inertia `ic` about it.
    pub(super) fn body(m: Expr, c: &[Expr; 3], ic: Option<&Matrix>) -> Inertia {
        let h = scale3(m, c);
        let mut i = ic.cloned().unwrap_or_else(|| Matrix::zeros(3, 3));
        // Parallel axes: + m (|c|^2 1 - c c^T).
        for r in 0..3 {
            for s in 0..3 {
                let mut e = -(c[r] * c[s]);
                if r == s {
                    e += dot(c, c);
                }
                i.set(r, s, i.get(r, s) + m * e);
            }
        }
        Inertia { m, h, i }
    }
    pub(super) fn add(&self, o: &Inertia) -> Inertia {
        Inertia { m: self.m + o.m, h: add3(&self.h, &o.h), i: self.i.add(&o.i) }
    }
    /// `I v`: the momentum `(I_o w + h x v, m v - h x w)` of the motion `v`.
    pub(super) fn apply(&self, v: &Motion) -> Force {
        Force { n: add3(&mat_vec(&self.i, &v.w), &cross(&self.h, &v.v)), f: sub3(&scale3(self.m, &v.v), &cross(&self.h, &v.w)) }
    }
    /// This inertia (the child's) about the parent's origin, in its components:
    /// `X^T I X` = `h' = R h + m t`, `I' = R I R^T + m (|t|^2 1 - t t^T) + 2 (t . Rh) 1 - Rh t^T - t Rh^T`.
    pub(super) fn to_parent(&self, joint: &Joint) -> Inertia {
        let r = &joint.rotation;
        let t = &joint.translation;
        let rh = mat_vec(r, &self.h);
        let h = add3(&rh, &scale3(self.m, t));
        let mut i = r.mul(&self.i).mul(&r.transpose());
        let tt = dot(t, t);
        let th = dot(t, &rh);
        for a in 0..3 {
            for b in 0..3 {
                let mut e = -(self.m * t[a] * t[b]) - rh[a] * t[b] - t[a] * rh[b];
                if a == b {
                    e += self.m * tt + Expr::int(2) * th;
                }
                i.set(a, b, i.get(a, b) + e);
            }
        }
        Inertia { m: self.m, h, i }
    }
}

/// The definitions under construction.
pub(super) struct Program {
    pub(super) definitions: Vec<(Symbol, Expr)>,
    /// The names' prefix, distinct per program so that one can extend another's definitions.
    pub(super) prefix: &'static str,
}

impl Program {
    /// `e` as a named intermediate (numbers and symbols as they are).
    pub(super) fn bind(&mut self, e: Expr) -> Expr {
        if e.as_num().is_some() || e.as_sym().is_some() {
            return e;
        }
        let s = Symbol::internal(&format!("{}{}", self.prefix, self.definitions.len()));
        self.definitions.push((s, e));
        s.expr()
    }
    pub(super) fn bind3(&mut self, v: [Expr; 3]) -> [Expr; 3] {
        v.map(|e| self.bind(e))
    }
    pub(super) fn motion(&mut self, m: Motion) -> Motion {
        Motion { w: self.bind3(m.w), v: self.bind3(m.v) }
    }
    pub(super) fn force(&mut self, f: Force) -> Force {
        Force { n: self.bind3(f.n), f: self.bind3(f.f) }
    }
    pub(super) fn inertia(&mut self, i: Inertia) -> Inertia {
        let m = self.bind(i.m);
        let h = self.bind3(i.h);
        let mut out = Matrix::zeros(3, 3);
        for a in 0..3 {
            for b in a..3 {
                let e = self.bind(i.i.get(a, b));
                out.set(a, b, e);
                out.set(b, a, e);
            }
        }
        Inertia { m, h, i: out }
    }
}

/// `[a]x`: the matrix of the cross product `a x .`.
pub(super) fn skew(a: &[Expr; 3]) -> Matrix {
    let z = Expr::zero();
    Matrix::from_rows(vec![vec![z, -a[2], a[1]], vec![a[2], z, -a[0]], vec![-a[1], a[0], z]])
}

/// A symmetric spatial inertia in blocks, `[A B; B^T C]` (`n = A w + B v`, `f = B^T w + C v`):
/// a rigid body's, or an articulated body's (Featherstone 7.1), which is no rigid body's.
#[derive(Clone, Debug)]
pub(super) struct SpatialInertia {
    pub(super) a: Matrix,
    pub(super) b: Matrix,
    pub(super) c: Matrix,
}

impl SpatialInertia {
    /// The rigid body `i`: `A = I_o`, `B = [h]x`, `C = m 1`.
    pub(super) fn rigid(i: &Inertia) -> SpatialInertia {
        SpatialInertia { a: i.i.clone(), b: skew(&i.h), c: Matrix::identity(3).map(|e| if e.is_zero() { *e } else { i.m }) }
    }
    pub(super) fn add(&self, o: &SpatialInertia) -> SpatialInertia {
        SpatialInertia { a: self.a.add(&o.a), b: self.b.add(&o.b), c: self.c.add(&o.c) }
    }
    /// `I v`.
    pub(super) fn apply(&self, v: &Motion) -> Force {
        Force { n: add3(&mat_vec(&self.a, &v.w), &mat_vec(&self.b, &v.v)), f: add3(&mat_vec(&self.b.transpose(), &v.w), &mat_vec(&self.c, &v.v)) }
    }
    /// `I - k U U^T` for the force `U = (n, f)`.
    pub(super) fn minus_outer(&self, u: &Force, k: Expr) -> SpatialInertia {
        let outer = |x: &[Expr; 3], y: &[Expr; 3], m: &Matrix| {
            let mut out = m.clone();
            for r in 0..3 {
                for s in 0..3 {
                    if !x[r].is_zero() && !y[s].is_zero() {
                        out.set(r, s, m.get(r, s) - k * x[r] * y[s]);
                    }
                }
            }
            out
        };
        SpatialInertia { a: outer(&u.n, &u.n, &self.a), b: outer(&u.n, &u.f, &self.b), c: outer(&u.f, &u.f, &self.c) }
    }
    /// This inertia (the child's) about the parent's origin, in its components, `X^T I X`:
    /// with `A1 = R A R^T` (likewise `B1`, `C1`) and `T = [t]x`,
    /// `A' = A1 - B1 T - (B1 T)^T - T C1 T`, `B' = B1 + T C1`, `C' = C1`.
    pub(super) fn to_parent(&self, joint: &Joint) -> SpatialInertia {
        let r = &joint.rotation;
        let rt = r.transpose();
        let turn = |m: &Matrix| r.mul(m).mul(&rt);
        let (a1, b1, c1) = (turn(&self.a), turn(&self.b), turn(&self.c));
        let t = skew(&joint.translation);
        let b1t = b1.mul(&t);
        let tc1 = t.mul(&c1);
        let tc1t = tc1.mul(&t);
        let mut a = Matrix::zeros(3, 3);
        for i in 0..3 {
            for j in 0..3 {
                a.set(i, j, a1.get(i, j) - b1t.get(i, j) - b1t.get(j, i) - tc1t.get(i, j));
            }
        }
        SpatialInertia { a, b: b1.add(&tc1), c: c1 }
    }
}

impl Program {
    /// Each entry of `i` as a named intermediate (the symmetric blocks' upper triangles).
    pub(super) fn spatial_inertia(&mut self, i: SpatialInertia) -> SpatialInertia {
        let symmetric = |m: &Matrix, prog: &mut Program| {
            let mut out = Matrix::zeros(3, 3);
            for r in 0..3 {
                for s in r..3 {
                    let e = prog.bind(m.get(r, s));
                    out.set(r, s, e);
                    out.set(s, r, e);
                }
            }
            out
        };
        let a = symmetric(&i.a, self);
        let c = symmetric(&i.c, self);
        let b = i.b.map(|e| self.bind(*e));
        SpatialInertia { a, b, c }
    }
}
