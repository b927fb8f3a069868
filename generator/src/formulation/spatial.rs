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
