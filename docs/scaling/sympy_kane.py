#!/usr/bin/env python3
"""SymPy's KanesMethod on the scaling benchmark's two models and the paper's three scenes, for the
side-by-side ratios in docs/scaling.md. Outside CI (it needs SymPy: `pip install sympy`).

    python3 docs/scaling/sympy_kane.py --model pendulum --sizes 5,10,20 --json out.json
    python3 docs/scaling/sympy_kane.py --model three_body --json out.json
    python3 docs/scaling/sympy_kane.py --model three_body --check POINT.json

`--check` validates a model instead of timing it: SymPy's accelerations q'' at the state, time
and parameters of POINT.json (the scaling benchmark writes it: `--scene NAME point`, `--point
KIND N`) against the generator's there; exit 1 beyond CHECK_TOLERANCE. The benchmark runs it
with `--sympy`, so the ratios it reports compare derivations of the same equations.

For each size it prints and records: the time to build the model and run `kanes_equations`
(derive), the time of `cse([M, F])`, and `count_ops` of that CSE (the operations to assemble
the mass matrix and forcing), the count the generator's "assembly" column compares with.

The models are the generator's `n_link_pendulum_on_cart` and `floating_chain`
(generator/src/model/examples.rs) and the scenes `models/cart_pendulum.ron`,
`models/three_body.ron` and `models/satellite_boom.ron`: the same bodies, joints, forces,
constraints and generalized speeds (the full set of each scene's quasi-velocities; products
of inertia as the paper's Eq. 75 writes them, negated in the tensor). A scene
has no size: `--sizes` is ignored and its record says n = 0.
"""

import argparse
import json
import sys
import time

import sympy as sm
import sympy.physics.mechanics as me


def pendulum_on_cart(n):
    """SymPy's own n_link_pendulum_on_cart(n, cart_force=False, joint_torques=False)."""
    from sympy.physics.mechanics.models import n_link_pendulum_on_cart

    return n_link_pendulum_on_cart(n, cart_force=False, joint_torques=False)


def zyx_base(N, names):
    """A frame turned by ZYX angles from N, with its body-frame angular velocity as speeds w1..w3
    and the kinematic equations that define them."""
    psi, theta, phi = me.dynamicsymbols(names)
    w = me.dynamicsymbols("w1:4")
    B = N.orientnew("B", "Body", (psi, theta, phi), "ZYX")
    rates = B.ang_vel_in(N)
    kd = [rates.dot(B.x) - w[0], rates.dot(B.y) - w[1], rates.dot(B.z) - w[2]]
    B.set_ang_vel(N, w[0] * B.x + w[1] * B.y + w[2] * B.z)
    return B, [psi, theta, phi], list(w), kd


def translating_point(O, N, names, speeds):
    """A point at (X, Y, Z) from O in N, moving with the speeds vx, vy, vz."""
    X, Y, Z = me.dynamicsymbols(names)
    vx, vy, vz = me.dynamicsymbols(speeds)
    t = me.dynamicsymbols._t
    G = O.locatenew("G", X * N.x + Y * N.y + Z * N.z)
    G.set_vel(N, vx * N.x + vy * N.y + vz * N.z)
    return G, [X, Y, Z], [vx, vy, vz], [X.diff(t) - vx, Y.diff(t) - vy, Z.diff(t) - vz]


def floating_base():
    """The world frame N and a base frame B turned by ZYX angles (zyx_base) whose point G moves by
    (X, Y, Z) from a fixed origin (translating_point): the floating chain's base and the scenes'
    free bodies. The two kinematic-equation lists come back apart, for each model to order."""
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    B, angles, w, kd_w = zyx_base(N, "psi theta phi")
    G, position, v, kd_t = translating_point(O, N, "X Y Z", "vx vy vz")
    return N, B, angles, w, kd_w, G, position, v, kd_t


def floating_chain(n):
    """A rigid base (ZYX angles, position X, Y, Z) and n links on revolute joints alternating
    about the parent's z and y axes, no gravity; speeds: the base's body-frame angular velocity,
    the joint rates, the translation rates (scene 2's choice)."""
    a = me.dynamicsymbols("a1:%d" % (n + 1))
    da = me.dynamicsymbols("da1:%d" % (n + 1))
    mb, Ibx, Iby, Ibz, h, m, L, J1, J2 = sm.symbols("mb Ibx Iby Ibz h m L J1 J2")
    t = me.dynamicsymbols._t

    N, B, angles, w, kd_w, G, position, v, kd = floating_base()
    bodies = [me.RigidBody("base", G, B, mb, (me.inertia(B, Ibx, Iby, Ibz), G))]
    kd += kd_w
    parent, joint = B, G.locatenew("J1", h * B.x)
    joint.v2pt_theory(G, N, B)
    for i in range(n):
        axis = parent.z if i % 2 == 0 else parent.y
        Li = parent.orientnew("L%d" % (i + 1), "Axis", (a[i], axis))
        Li.set_ang_vel(parent, da[i] * axis)
        Ci = joint.locatenew("C%d" % (i + 1), L / 2 * Li.x)
        Ci.v2pt_theory(joint, N, Li)
        bodies.append(me.RigidBody("link%d" % (i + 1), Ci, Li, m, (me.inertia(Li, J1, J2, J2), Ci)))
        kd.append(a[i].diff(t) - da[i])
        nxt = joint.locatenew("J%d" % (i + 2), L * Li.x)
        nxt.v2pt_theory(joint, N, Li)
        parent, joint = Li, nxt
    q = angles + list(a) + position
    u = w + list(da) + v
    kane = me.KanesMethod(N, q_ind=q, u_ind=u, kd_eqs=kd)
    kane.kanes_equations(bodies, [])
    return kane


def cart_pendulum():
    """Scene 1 (models/cart_pendulum.ron): a cart on x, bar AB turned by theta1 about z, bar BC
    by theta2 (absolute), gravity along -y, the motor's torque pair tau, and the wheel's
    velocity constraint l cos(theta1 - theta2) theta1' + l theta2' = 0. Speeds: u1 = theta1' -
    theta2' and x' independent, theta2' dependent."""
    th1, th2, x = me.dynamicsymbols("theta1 theta2 x")
    u1, u2, u3 = me.dynamicsymbols("u1:4")
    M, m1, m2, l, g, tau = sm.symbols("M m1 m2 l g tau")
    t = me.dynamicsymbols._t
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    A = N.orientnew("A", "Axis", (th1, N.z))
    Bf = N.orientnew("Bf", "Axis", (th2, N.z))
    A.set_ang_vel(N, (u1 + u3) * N.z)
    Bf.set_ang_vel(N, u3 * N.z)
    cart = O.locatenew("cart", x * N.x)
    cart.set_vel(N, u2 * N.x)
    g1 = cart.locatenew("G1", -l / 2 * A.y)
    g1.v2pt_theory(cart, N, A)
    b = cart.locatenew("B", -l * A.y)
    b.v2pt_theory(cart, N, A)
    g2 = b.locatenew("G2", -l / 2 * Bf.y)
    g2.v2pt_theory(b, N, Bf)
    bodies = [
        me.Particle("cart", cart, M),
        me.RigidBody("bar1", g1, A, m1, (me.inertia(A, m1 * l**2 / 12, 0, m1 * l**2 / 12), g1)),
        me.RigidBody("bar2", g2, Bf, m2, (me.inertia(Bf, m2 * l**2 / 12, 0, m2 * l**2 / 12), g2)),
    ]
    loads = [(cart, -M * g * N.y), (g1, -m1 * g * N.y), (g2, -m2 * g * N.y), (A, tau * N.z), (Bf, -tau * N.z)]
    kd = [th1.diff(t) - (u1 + u3), th2.diff(t) - u3, x.diff(t) - u2]
    constraint = [l * sm.cos(th1 - th2) * (u1 + u3) + l * u3]
    kane = me.KanesMethod(N, q_ind=[th1, th2, x], u_ind=[u1, u2], u_dependent=[u3], kd_eqs=kd, velocity_constraints=constraint)
    kane.kanes_equations(bodies, loads)
    return kane


def three_body():
    """Scene 2 (models/three_body.ron): a middle body (products of inertia) free in space, two
    outer bodies on revolute joints at (+a, 0, 0) about its z axis and (-a, 0, 0) about its y
    axis, centres of mass at (+-d, 0, 0) in their frames, no gravity. Speeds: the middle body's
    angular velocity in its own components, the joint rates, the translation rates (Eq. 74)."""
    m0, Ixx, Iyy, Izz, Ixy, Ixz, Iyz, m1, m2, d, a, J1, J2 = sm.symbols("m0 Ixx Iyy Izz Ixy Ixz Iyz m1 m2 d a J1 J2")
    g1, g2 = me.dynamicsymbols("gamma1 gamma2")
    dg1, dg2 = me.dynamicsymbols("dgamma1 dgamma2")
    t = me.dynamicsymbols._t
    N, B, angles, w, kd, G, position, v, kd_t = floating_base()
    L1 = B.orientnew("L1", "Axis", (g1, B.z))
    L1.set_ang_vel(B, dg1 * B.z)
    L2 = B.orientnew("L2", "Axis", (g2, B.y))
    L2.set_ang_vel(B, dg2 * B.y)
    ja = G.locatenew("JA", a * B.x)
    ja.v2pt_theory(G, N, B)
    jb = G.locatenew("JB", -a * B.x)
    jb.v2pt_theory(G, N, B)
    c1 = ja.locatenew("C1", d * L1.x)
    c1.v2pt_theory(ja, N, L1)
    c2 = jb.locatenew("C2", -d * L2.x)
    c2.v2pt_theory(jb, N, L2)
    bodies = [
        me.RigidBody("middle", G, B, m0, (me.inertia(B, Ixx, Iyy, Izz, -Ixy, -Iyz, -Ixz), G)),
        me.RigidBody("body1", c1, L1, m1, (me.inertia(L1, J1, J2, J2), c1)),
        me.RigidBody("body2", c2, L2, m2, (me.inertia(L2, J1, J2, J2), c2)),
    ]
    kd += [g1.diff(t) - dg1, g2.diff(t) - dg2] + kd_t
    kane = me.KanesMethod(N, q_ind=angles + [g1, g2] + position, u_ind=w + [dg1, dg2] + v, kd_eqs=kd)
    kane.kanes_equations(bodies, [])
    return kane


def satellite_boom():
    """Scene 3 (models/satellite_boom.ron): a satellite (products of inertia) free in space and a
    tip mass at (l/2 + rho, 0, 0) in its frame, pushed along the boom by the prescribed force
    F(t) of Eq. (79), the reaction on the satellite's centre of mass. Speeds: the satellite's
    angular velocity in its own components, rho', the translation rates (Eq. 78)."""
    mg, Ixx, Iyy, Izz, Ixy, Ixz, Iyz, m, l = sm.symbols("mg Ixx Iyy Izz Ixy Ixz Iyz m l")
    rho, drho = me.dynamicsymbols("rho drho")
    t = me.dynamicsymbols._t
    F = -sm.Rational(18, 1000) * sm.sin(sm.Rational(89, 1000) * t) + sm.Rational(12, 1000) * sm.cos(sm.Rational(485, 10000) * t)
    N, B, angles, w, kd, G, position, v, kd_t = floating_base()
    tip = G.locatenew("tip", (l / 2 + rho) * B.x)
    tip.set_vel(B, drho * B.x)
    tip.v1pt_theory(G, N, B)
    bodies = [
        me.RigidBody("satellite", G, B, mg, (me.inertia(B, Ixx, Iyy, Izz, -Ixy, -Iyz, -Ixz), G)),
        me.Particle("tip", tip, m),
    ]
    loads = [(tip, F * B.x), (G, -F * B.x)]
    kd += [rho.diff(t) - drho] + kd_t
    kane = me.KanesMethod(N, q_ind=angles + [rho] + position, u_ind=w + [drho] + v, kd_eqs=kd)
    kane.kanes_equations(bodies, loads)
    return kane


SCENES = {"cart_pendulum": cart_pendulum, "three_body": three_body, "satellite_boom": satellite_boom}

# `--check` fails beyond this difference of q'' (relative to the largest |q''|): both sides
# evaluate the same equations in double precision (ours) and 30 digits (SymPy's), so a
# different model differs in the leading digits, round-off in the last few.
CHECK_TOLERANCE = 1e-9


def measure(model, n):
    start = time.process_time()
    kane = build(model, n)
    n = 0 if model in SCENES else n
    mass, forcing = kane.mass_matrix, kane.forcing
    derive = time.process_time() - start
    start = time.process_time()
    replacements, reduced = sm.cse([mass, forcing])
    cse = time.process_time() - start
    ops = sum(sm.count_ops(e) for _, e in replacements) + sum(sm.count_ops(r) for r in reduced)
    return {"model": model, "n": n, "derive_seconds": derive, "cse_seconds": cse, "assembly_ops": int(ops)}


def accelerations(kane, point):
    """SymPy's accelerations q'' of a derived model at `point` (a state of the scene with its
    parameters and time, every value by its name in the model file, as the scaling benchmark's
    `--scene NAME point` writes it): the speeds solved from the kinematic equations at (q, q'),
    u' from the full mass matrix and forcing, then q'' = d/dt q'(q, u). Returns {name: q''}."""
    t = me.dynamicsymbols._t
    name = lambda f: f.func.__name__
    q, u = list(kane.q), list(kane.u)
    params = {sm.Symbol(k): sm.Float(v, 30) for k, v in point["params"].items()}
    at = {t: sm.Float(point["t"], 30), **params, **{x: sm.Float(point["q"][name(x)], 30) for x in q}}
    qdot_of_u = kane.kindiffdict()
    rates = [qdot_of_u[x.diff(t)] for x in q]
    # The kinematic equations q' = f(q, u), linear in u: solved for u at the point.
    unknowns = sm.symbols("s0:%d" % len(u))
    plain = dict(zip(u, unknowns))
    equations = [sm.N(r.xreplace(plain).subs(at), 30) - sm.Float(point["qdot"][name(x)], 30) for r, x in zip(rates, q)]
    (speeds,) = sm.linsolve(equations, unknowns)
    at.update(dict(zip(u, speeds)))
    # [q'; u'] = M_full^-1 F_full at the point; the derivatives stand in for symbols first.
    mass, forcing = kane.mass_matrix_full, kane.forcing_full
    derivatives = {x.diff(t): sm.Symbol("d_" + name(x)) for x in q + u}
    value = lambda m: m.xreplace(derivatives).subs(at).evalf(30)
    solution = value(mass).LUsolve(value(forcing))
    udot = dict(zip(u, solution[len(q):]))
    # q'' = sum_j df/dq_j q'_j + sum_k df/du_k u'_k.
    result = {}
    for r, x in zip(rates, q):
        total = sum(value(sm.Matrix([r.diff(y)]))[0] * sm.Float(point["qdot"][name(y)], 30) for y in q)
        total += sum(value(sm.Matrix([r.diff(v)]))[0] * udot[v] for v in u)
        result[name(x)] = float(total)
    return result


def build(model, n):
    """SymPy's KanesMethod of `model` (a scene, or a scaled model at size n), derived."""
    if model in SCENES:
        return SCENES[model]()
    return pendulum_on_cart(n) if model == "pendulum" else floating_chain(n)


def check(model, n, point_file):
    """Derives `model` (at size n) and compares its q'' with the generator's at the point in
    `point_file`: prints the largest difference over the largest |q''| and returns it."""
    with open(point_file) as f:
        point = json.load(f)
    ours = point["qddot"]
    theirs = accelerations(build(model, n), point)
    if set(ours) != set(theirs):
        raise SystemExit(f"{model}: SymPy's coordinates {sorted(theirs)} are not the model's {sorted(ours)}")
    scale = max(abs(v) for v in ours.values())
    error = max(abs(theirs[k] - ours[k]) for k in ours) / scale
    for k in sorted(ours):
        print(f"{model}: {k}'' ours {ours[k]:+.15e} SymPy {theirs[k]:+.15e}")
    print(f"{model}: largest difference {error:.2e} of the largest |q''|", flush=True)
    return error


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--model", choices=["pendulum", "floating", *SCENES], required=True)
    p.add_argument("--sizes", default="2,4,8", help="comma-separated sizes n")
    p.add_argument("--json", help="write the records to this file")
    p.add_argument("--check", metavar="POINT", help="compare q'' with the generator's at this point (JSON, for a scaled model at the first of --sizes) instead of timing")
    args = p.parse_args()
    if args.check:
        n = 0 if args.model in SCENES else int(args.sizes.split(",")[0])
        error = check(args.model, n, args.check)
        if args.json:
            with open(args.json, "w") as f:
                json.dump({"sympy": sm.__version__, "records": [{"model": args.model, "n": n, "relative_difference": error}]}, f, indent=1)
        return 0 if error <= CHECK_TOLERANCE else 1
    records = []
    sizes = [0] if args.model in SCENES else [int(x) for x in args.sizes.split(",")]
    for n in sizes:
        r = measure(args.model, n)
        records.append(r)
        print(f"{r['model']} n={n}: derive {r['derive_seconds']:.2f} s, cse {r['cse_seconds']:.2f} s, {r['assembly_ops']} ops", flush=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"sympy": sm.__version__, "records": records}, f, indent=1)


if __name__ == "__main__":
    sys.exit(main())
