#!/usr/bin/env python3
"""SymPy's KanesMethod on the scaling benchmark's two models, for the side-by-side ratios in
docs/scaling.md. Outside CI (it needs SymPy: `pip install sympy`).

    python3 docs/scaling/sympy_kane.py --model pendulum --sizes 5,10,20 --json out.json

For each size it prints and records: the time to build the model and run `kanes_equations`
(derive), the time of `cse([M, F])`, and `count_ops` of that CSE (the operations to assemble
the mass matrix and forcing), the count the generator's "assembly" column compares with.

The models are the generator's `n_link_pendulum_on_cart` and `floating_chain`
(generator/src/model/examples.rs): the same bodies, joints and generalized speeds.
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


def floating_chain(n):
    """A rigid base (ZYX angles, position X, Y, Z) and n links on revolute joints alternating
    about the parent's z and y axes, no gravity; speeds: the base's body-frame angular velocity,
    the joint rates, the translation rates (scene 2's choice)."""
    psi, theta, phi = me.dynamicsymbols("psi theta phi")
    a = me.dynamicsymbols("a1:%d" % (n + 1))
    X, Y, Z = me.dynamicsymbols("X Y Z")
    w = me.dynamicsymbols("w1:4")
    da = me.dynamicsymbols("da1:%d" % (n + 1))
    vx, vy, vz = me.dynamicsymbols("vx vy vz")
    mb, Ibx, Iby, Ibz, h, m, L, J1, J2 = sm.symbols("mb Ibx Iby Ibz h m L J1 J2")
    t = me.dynamicsymbols._t

    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    B = N.orientnew("B", "Body", (psi, theta, phi), "ZYX")
    B.set_ang_vel(N, w[0] * B.x + w[1] * B.y + w[2] * B.z)
    G = O.locatenew("G", X * N.x + Y * N.y + Z * N.z)
    G.set_vel(N, vx * N.x + vy * N.y + vz * N.z)
    bodies = [me.RigidBody("base", G, B, mb, (me.inertia(B, Ibx, Iby, Ibz), G))]
    kd = [X.diff(t) - vx, Y.diff(t) - vy, Z.diff(t) - vz]
    # w = the body-frame angular velocity of the ZYX rotation, in psi', theta', phi'.
    frame_tmp = N.orientnew("Bt", "Body", (psi, theta, phi), "ZYX")
    rates = frame_tmp.ang_vel_in(N)
    kd += [rates.dot(frame_tmp.x) - w[0], rates.dot(frame_tmp.y) - w[1], rates.dot(frame_tmp.z) - w[2]]
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
    q = [psi, theta, phi] + list(a) + [X, Y, Z]
    u = list(w) + list(da) + [vx, vy, vz]
    kane = me.KanesMethod(N, q_ind=q, u_ind=u, kd_eqs=kd)
    kane.kanes_equations(bodies, [])
    return kane


def measure(model, n):
    start = time.process_time()
    kane = pendulum_on_cart(n) if model == "pendulum" else floating_chain(n)
    mass, forcing = kane.mass_matrix, kane.forcing
    derive = time.process_time() - start
    start = time.process_time()
    replacements, reduced = sm.cse([mass, forcing])
    cse = time.process_time() - start
    ops = sum(sm.count_ops(e) for _, e in replacements) + sum(sm.count_ops(r) for r in reduced)
    return {"model": model, "n": n, "derive_seconds": derive, "cse_seconds": cse, "assembly_ops": int(ops)}


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--model", choices=["pendulum", "floating"], required=True)
    p.add_argument("--sizes", default="2,4,8", help="comma-separated sizes n")
    p.add_argument("--json", help="write the records to this file")
    args = p.parse_args()
    records = []
    for n in [int(x) for x in args.sizes.split(",")]:
        r = measure(args.model, n)
        records.append(r)
        print(f"{r['model']} n={n}: derive {r['derive_seconds']:.2f} s, cse {r['cse_seconds']:.2f} s, {r['assembly_ops']} ops", flush=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"sympy": sm.__version__, "records": records}, f, indent=1)


if __name__ == "__main__":
    sys.exit(main())
