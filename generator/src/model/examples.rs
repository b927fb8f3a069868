//! Parametric models of any size, built with [`ModelBuilder`], in the spirit of
//! `sympy.physics.mechanics.models`: the scaling benchmark's chains, and tests at sizes no
//! one writes by hand.
//!
//! ```
//! use generator::model::examples::n_link_pendulum_on_cart;
//! let model = n_link_pendulum_on_cart(3).build().unwrap();
//! assert_eq!(model.m(), 4); // the cart and three links
//! ```

use super::builder::{Body, Frame, ModelBuilder};

/// The n-link pendulum on a cart of SymPy's `n_link_pendulum_on_cart(n, cart_force=False,
/// joint_torques=False)`: a cart on the x axis (`q0`, point mass `m0`), and n point masses
/// `m1..mn` on massless links of lengths `l0..l(n-1)`, link i at the absolute angle `q(i+1)`
/// from the y axis; gravity `g` along -y. Each link frame is turned relative to the previous
/// one by `q(i+1) - q(i)`, as a frame tree of a chain is written. The cart position `q0` is
/// ignorable (s = 1).
pub fn n_link_pendulum_on_cart(n: usize) -> ModelBuilder {
    let mut b = ModelBuilder::new(format!("pendulum_on_cart_{n}"))
        .description(format!("{n}-link pendulum on a cart (SymPy's n_link_pendulum_on_cart)"))
        .coordinate("q0");
    for i in 0..=n {
        b = b.parameter(format!("m{i}"), 1.0);
    }
    for i in 0..n {
        b = b.parameter(format!("l{i}"), 1.0);
    }
    b = b.parameter("g", 9.81);
    for i in 1..=n {
        b = b.coordinate(format!("q{i}"));
    }
    b = b.frame(Frame::new("cart", "world").translation(["q0", "0", "0"]));
    b = b.body(Body::new("cart", "cart", "m0"));
    for i in 0..n {
        let (name, parent) = (format!("B{i}"), if i == 0 { "cart".to_string() } else { format!("B{}", i - 1) });
        let frame = if i == 0 {
            Frame::new(&name, &parent).rotate_z("q1")
        } else {
            let offset = format!("l{}", i - 1);
            Frame::new(&name, &parent).translation(["0", &offset, "0"]).rotate_z(format!("q{} - q{}", i + 1, i))
        };
        let com = format!("l{i}");
        b = b.frame(frame).body(Body::new(format!("P{}", i + 1), &name, format!("m{}", i + 1)).com(["0", &com, "0"]));
    }
    let rates: Vec<String> = (0..=n).map(|i| format!("q{i}'")).collect();
    let q0: Vec<(String, String)> = (0..=n).map(|i| (format!("q{i}"), if i == 0 { "0".into() } else { format!("{}", 0.1 * i as f64) })).collect();
    let qd0: Vec<(String, String)> = (0..=n).map(|i| (format!("q{i}"), if i == 0 { "0.2".into() } else { "0".into() })).collect();
    b.gravity(["0", "-g", "0"]).quasi_velocities(rates.clone(), rates[1..].to_vec()).ignorable(["q0"]).initial(q0, qd0).simulation(10.0, 0.01)
}

/// A spatial chain on a floating base: a rigid base (ZYX angles `psi, theta, phi`, centre of
/// mass at `X, Y, Z`, mass `mb`, inertia `diag(Ibx, Iby, Ibz)`) and n rigid links on revolute
/// joints whose axes alternate between the parent's z and y axes (`a1..an`). The first joint
/// sits at `(h, 0, 0)` on the base, each next one at the previous link's end `(L, 0, 0)`; a
/// link has mass `m`, centre of mass `(L/2, 0, 0)` and inertia `diag(J1, J2, J2)`. No gravity.
/// `X, Y, Z` are ignorable (s = 3). The quasi-velocities are scene 2's: the base's body-frame
/// angular velocity, the joint rates, and the translation rates.
pub fn floating_chain(n: usize) -> ModelBuilder {
    let mut b = ModelBuilder::new(format!("floating_chain_{n}")).description(format!("spatial {n}-link chain on a floating base (z and y joints alternating)"));
    for (name, value) in [("mb", 10.0), ("Ibx", 1.2), ("Iby", 1.5), ("Ibz", 1.8), ("h", 0.5), ("m", 1.0), ("L", 0.8), ("J1", 0.01), ("J2", 0.06)] {
        b = b.parameter(name, value);
    }
    for c in ["psi", "theta", "phi"] {
        b = b.coordinate(c);
    }
    for i in 1..=n {
        b = b.coordinate(format!("a{i}"));
    }
    for c in ["X", "Y", "Z"] {
        b = b.coordinate(c);
    }
    b = b
        .frame(Frame::new("base", "world").translation(["X", "Y", "Z"]).rotate(super::schema::RotationDef::EulerZYX(
            "psi".into(),
            "theta".into(),
            "phi".into(),
        )))
        .body(Body::new("base", "base", "mb").diagonal(["Ibx", "Iby", "Ibz"]));
    for i in 1..=n {
        let (name, parent) = (format!("link{i}"), if i == 1 { "base".to_string() } else { format!("link{}", i - 1) });
        let at = if i == 1 { "h" } else { "L" };
        let frame = Frame::new(&name, &parent).translation([at, "0", "0"]);
        let angle = format!("a{i}");
        let frame = if i % 2 == 1 { frame.rotate_z(angle) } else { frame.rotate_y(angle) };
        b = b.frame(frame).body(Body::new(&name, &name, "m").com(["L/2", "0", "0"]).diagonal(["J1", "J2", "J2"]));
    }
    let mut reduced: Vec<String> = ["omega_x(base)", "omega_y(base)", "omega_z(base)"].iter().map(|s| s.to_string()).collect();
    reduced.extend((1..=n).map(|i| format!("a{i}'")));
    let mut full = reduced.clone();
    full.extend(["X'", "Y'", "Z'"].iter().map(|s| s.to_string()));
    let mut q0: Vec<(String, String)> = vec![("psi".into(), "0.1".into()), ("theta".into(), "0.2".into()), ("phi".into(), "0.3".into())];
    q0.extend((1..=n).map(|i| (format!("a{i}"), format!("{}", 0.3 / i as f64))));
    q0.extend(["X", "Y", "Z"].iter().map(|c| (c.to_string(), "0".to_string())));
    let mut qd0: Vec<(String, String)> = vec![("psi".into(), "0.2".into()), ("theta".into(), "-0.1".into()), ("phi".into(), "0.3".into())];
    qd0.extend((1..=n).map(|i| (format!("a{i}"), if i % 2 == 0 { "-0.2".to_string() } else { "0.4".to_string() })));
    qd0.extend([("X", "0.1"), ("Y", "-0.2"), ("Z", "0.05")].iter().map(|(c, v)| (c.to_string(), v.to_string())));
    b.quasi_velocities(full, reduced).ignorable(["X", "Y", "Z"]).initial(q0, qd0).simulation(10.0, 0.01)
}

/// A planar free-floating chain of n uniform rods written in absolute angles: rod 0 (the base)
/// has its end at `(x, y)` and turns by `a0`; rod k is joined to the end of rod k-1 by the
/// joint angle `ak`. Every rod's frame hangs from the world, turned by its absolute angle
/// `a0 + a1 + ... + ak` and placed at its joint, `(x + sum_j L cos(a0 + ... + aj), y + ...)`
/// over the rods before it: the way the chain is written when each rod's orientation is
/// thought of on its own, not as a tree of relative joints. Rods of mass `m`, length `L`,
/// inertia `m L^2 / 12` about their centre; no gravity. `x`, `y` are ignorable (s = 2).
///
/// ```
/// let model = generator::model::examples::planar_chain_absolute(4).build().unwrap();
/// assert_eq!(model.m(), 6); // x, y and the four angles
/// ```
pub fn planar_chain_absolute(n: usize) -> ModelBuilder {
    let mut b = ModelBuilder::new(format!("planar_chain_absolute_{n}"))
        .description(format!("planar free chain of {n} rods, frames turned by absolute angles"))
        .parameter("m", 1.0)
        .parameter("L", 1.0)
        .coordinate("x")
        .coordinate("y");
    for k in 0..n {
        b = b.coordinate(format!("a{k}"));
    }
    let absolute = |k: usize| (0..=k).map(|j| format!("a{j}")).collect::<Vec<_>>().join(" + ");
    for k in 0..n {
        let (mut px, mut py) = ("x".to_string(), "y".to_string());
        for j in 0..k {
            px += &format!(" + L*cos({})", absolute(j));
            py += &format!(" + L*sin({})", absolute(j));
        }
        let name = format!("rod{k}");
        b = b
            .frame(Frame::new(&name, "world").translation([&px, &py, "0"]).rotate_z(absolute(k)))
            .body(Body::new(&name, &name, "m").com(["L/2", "0", "0"]).diagonal(["0", "m*L^2/12", "m*L^2/12"]));
    }
    let angles: Vec<String> = (0..n).map(|k| format!("a{k}'")).collect();
    let mut full = angles.clone();
    full.extend(["x'".to_string(), "y'".to_string()]);
    let mut q0: Vec<(String, String)> = vec![("x".into(), "0".into()), ("y".into(), "0".into())];
    q0.extend((0..n).map(|k| (format!("a{k}"), format!("{}", 0.2 / (k + 1) as f64))));
    let mut qd0: Vec<(String, String)> = vec![("x".into(), "0.1".into()), ("y".into(), "-0.1".into())];
    qd0.extend((0..n).map(|k| (format!("a{k}"), if k % 2 == 0 { "0.3".to_string() } else { "-0.2".to_string() })));
    b.quasi_velocities(full, angles).ignorable(["x", "y"]).initial(q0, qd0).simulation(10.0, 0.01)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn built_models_round_trip_through_ron() {
        for b in [n_link_pendulum_on_cart(2), floating_chain(2)] {
            let text = b.to_ron();
            let from_text = crate::model::from_source("x.ron", &text).unwrap();
            let built = b.build().unwrap();
            assert_eq!(from_text.coordinates.len(), built.coordinates.len());
            assert_eq!(from_text.bodies.len(), built.bodies.len());
            assert_eq!(from_text.frames.len(), built.frames.len());
        }
        let m = floating_chain(3).build().unwrap();
        assert_eq!((m.m(), m.bodies.len(), m.quasi_reduced.len()), (9, 4, 6));
    }
}
