//! Rolling contact: a thin disk rolling without slip on the ground plane `z = 0`.
//!
//! For a wheel of radius `R` with centre `c` and unit axle `a` (world components), the vector
//! in the wheel's plane towards the ground's normal is `n = z - (a . z) a`, of length
//! `|n| = sqrt(1 - a_z^2)`; the contact point is `p = c - R n / |n|`, at height
//! `h = c_z - R |n|`. The material point of the wheel at `p` moves with
//! `v_p = v_c + omega x (p - c) = v_c - (R / |n|) omega x n`. The no-slip constraints are its
//! horizontal components, multiplied by `|n|` (non-zero unless the wheel lies flat):
//! `|n| v_c,x - R (omega x n)_x = 0` and the same for `y`, linear in the rates with
//! coefficients free of them. The height constraint `h = 0` is holonomic; its derivative is
//! the vertical component of `v_p`.

use super::{FrameKinematics, TimeChain, cross};
use crate::symbolic::eval::Env;
use crate::symbolic::limits::Limits;
use crate::symbolic::zero::SplitMix;
use crate::symbolic::{Expr, Symbol};

/// What a rolling wheel contributes.
#[derive(Clone, Debug)]
pub struct Contact {
    /// `|n| v_p,x` and `|n| v_p,y`: the no-slip constraints (zero when rolling).
    pub slip: [Expr; 2],
    /// `h = c_z - R |n|`: the contact point's height above the ground.
    pub height: Expr,
}

/// The contact of the wheel turning with `frame`: centre `center` and unit `axle` in the
/// frame's components, radius `radius`.
pub fn contact(frame: &FrameKinematics, center: &[Expr; 3], axle: &[Expr; 3], radius: Expr, chain: &TimeChain) -> Contact {
    let c = frame.point(center);
    let a = frame.to_world(axle);
    let omega = frame.to_world(&frame.omega);
    let v_c = chain.dt3(&c);
    let az = a[2];
    let n = [-(az * a[0]), -(az * a[1]), Expr::one() - az * a[2]];
    let norm = (Expr::one() - az * az).simplify_trig(Limits::default()).sqrt();
    let w = cross(&omega, &n);
    let slip = [norm * v_c[0] - radius * w[0], norm * v_c[1] - radius * w[1]];
    let height = c[2] - radius * norm;
    Contact { slip: slip.map(|e| e.simplify_trig(Limits::default())), height: height.simplify_trig(Limits::default()) }
}

/// True when the frames keep the wheel on the ground by construction: `height` vanishes at
/// sixteen seeded random configurations with every coordinate in `[-1, 1]` (angles within a
/// radian of upright; a wheel that lies flat is outside the element's domain).
pub fn on_the_ground(height: Expr, coordinates: &[Symbol], params: &Env) -> bool {
    if height.is_zero() {
        return true;
    }
    let mut rng = SplitMix(0x005e_ed0f_6a11);
    (0..16).all(|_| {
        let mut env = params.clone();
        for q in coordinates {
            env.set(*q, rng.uniform(-1.0, 1.0));
        }
        height.eval(&env).is_ok_and(|h| h.abs() < 1e-12)
    })
}

/// The example that was this module's documentation when it was public.
#[cfg(test)]
mod examples {
    #[test]
    fn module_example() {
        use crate::kinematics::{Axis, FrameKinematics, TimeChain, rolling::contact};
        use crate::symbolic::{Expr, Symbol};
        // An upright disk of radius 1 on a heading frame at (x, y, 1), spinning about its y axis.
        let (t, x, y, psi, phi) = (Symbol::new("t"), Symbol::new("x"), Symbol::new("y"), Symbol::new("psi"), Symbol::new("phi"));
        let rates: Vec<_> = [x, y, psi, phi].iter().map(|s| (*s, Symbol::new(&format!("{}'", s.name())).expr())).collect();
        let chain = TimeChain::new(t, rates);
        let heading = FrameKinematics::world().child(0, "h", &[x.expr(), y.expr(), Expr::one()], &[(Axis::Z, psi.expr())], &chain);
        let disk = heading.child(1, "d", &[Expr::zero(), Expr::zero(), Expr::zero()], &[(Axis::Y, phi.expr())], &chain);
        let z = Expr::zero();
        let c = contact(&disk, &[z, z, z], &[z, Expr::one(), z], Expr::one(), &chain);
        assert!(c.height.is_zero());
    }
}
