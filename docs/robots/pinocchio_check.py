"""Robots of example-robot-data against Pinocchio (outside CI): each robot's URDF is loaded by
both, and at random states the accelerations are compared in every formulation, to 1e-10
relative. Run before anything is timed; writes docs/robots/pinocchio_check.json.

    pip install ./python pin example-robot-data     # the wheel, Pinocchio, the robots
    python docs/robots/pinocchio_check.py            # [--robots ur5,panda] [--states 5]

Conventions, ours against Pinocchio's:
- a fixed base: our coordinates are the joints (named after them), Pinocchio's the same (a
  continuous joint's cos and sin made its angle); a mimic joint is its master's (Pinocchio with
  `mimic=True`);
- a floating base: ours are the base's position in the world, its unit quaternion (w, x, y, z)
  and the joints; the quasi-velocities (Kane, the reduced method) the base's angular velocity in
  its own frame, then the world rates of its position, then the joints' rates. Pinocchio's free
  flyer has the position, the quaternion (x, y, z, w), and in v the base's linear and angular
  velocity in its own frame. So `p' = R v_lin`, `e' = e (0, w) / 2`, and from Pinocchio's
  `a = d/dt v`: `w' = a_ang`, `p'' = R (a_lin + w x v_lin)`;
- the joints' damping is applied in both (Pinocchio: `tau = -damping v`), gravity `(0, 0, -9.81)`.
"""

import argparse
import json
import re
import sys
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

import multibody

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "robots" / "pinocchio_check.json"

ROBOTS = {
    "ur5": ("ur_description/urdf/ur5_robot.urdf", "fixed"),
    "panda": ("panda_description/urdf/panda.urdf", "fixed"),
    "solo12": ("solo_description/robots/solo12.urdf", "floating"),
    "anymal": ("anymal_b_simple_description/robots/anymal.urdf", "floating"),
    "talos_reduced": ("talos_data/robots/talos_reduced.urdf", "floating"),
}


def robots_folder() -> Path:
    """example-robot-data's robots, installed by pip (a cmeel package)."""
    for base in map(Path, sys.path):
        folder = base / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
        if folder.is_dir():
            return folder
    raise SystemExit("example-robot-data is not installed: pip install example-robot-data")


def ident(name: str) -> str:
    """Our coordinate name of a URDF joint (generator::model::urdf::ident)."""
    out = re.sub(r"[^A-Za-z0-9_]", "_", name)
    if not re.match(r"[A-Za-z_]", out):
        out = "j_" + out
    return out + "_" if out in ("t", "pi", "world", "e") else out


def quat_mul(a, b):
    """(w, x, y, z) products."""
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2, w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def expected(model, data, ours, q, v, floating):
    """Pinocchio's accelerations at (q, v) in our coordinates: (ours q, q', q'') and the
    quasi-velocities' rates (u, u') by name."""
    tau = -model.damping * v
    if any(model.joints[j].shortname() == "JointModelMimic" for j in range(1, model.njoints)):
        # ABA has no mimic joints: M^-1 (tau - b) from CRBA and the nonlinear effects.
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        a = np.linalg.solve(M, tau - pin.nonLinearEffects(model, data, q, v))
    else:
        a = pin.aba(model, data, q, v, tau)
    coords, rates, accs = {}, {}, {}
    speeds, speed_rates = {}, {}
    for j in range(1, model.njoints):
        joint, name = model.joints[j], model.names[j]
        if joint.nv == 0 or name == "root_joint":
            continue  # a mimic joint: its master's coordinate
        iq, iv = joint.idx_q, joint.idx_v
        c = ident(name)
        coords[c] = float(np.arctan2(q[iq + 1], q[iq])) if joint.nq == 2 else float(q[iq])
        rates[c], accs[c] = float(v[iv]), float(a[iv])
        speeds[c + "'"], speed_rates[c + "'"] = rates[c], accs[c]
    if floating:
        p, (qx, qy, qz, qw) = q[:3], q[3:7]
        e = np.array([qw, qx, qy, qz])
        R = pin.Quaternion(qw, qx, qy, qz).toRotationMatrix()
        v_lin, w = v[:3], v[3:6]
        a_lin, w_dot = a[:3], a[3:6]
        p_dot = R @ v_lin
        p_ddot = R @ (a_lin + np.cross(w, v_lin))
        e_dot = 0.5 * quat_mul(e, [0.0, *w])
        e_ddot = 0.5 * quat_mul(e_dot, [0.0, *w]) + 0.5 * quat_mul(e, [0.0, *w_dot])
        root = [n for n in ours.coordinates if n.startswith("base_")]
        for k, c in enumerate(["base_x", "base_y", "base_z"]):
            coords[c], rates[c], accs[c] = float(p[k]), float(p_dot[k]), float(p_ddot[k])
            speeds[c + "'"], speed_rates[c + "'"] = rates[c], accs[c]
        for k, c in enumerate(["base_qw", "base_qx", "base_qy", "base_qz"]):
            coords[c], rates[c], accs[c] = float(e[k]), float(e_dot[k]), float(e_ddot[k])
        for k, axis in enumerate("xyz"):
            speeds[f"omega_{axis}"], speed_rates[f"omega_{axis}"] = float(w[k]), float(w_dot[k])
        assert root, "a floating base"
    return coords, rates, accs, speeds, speed_rates


def check(name, path, base, states, rng):
    floating = base == "floating"
    model = pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer(), mimic=True) if floating else pin.buildModelFromUrdf(str(path), mimic=True)
    data = model.createData()
    start = time.perf_counter()
    ours = multibody.load(path, base=base)
    load_s = time.perf_counter() - start
    worst = {kind: 0.0 for kind in ours.formulations}
    for _ in range(states):
        q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq)) if floating else pin.randomConfiguration(model)
        if floating:
            q[:3] = rng.uniform(-1, 1, 3)
        v = rng.uniform(-1, 1, model.nv)
        coords, rates, accs, speeds, speed_rates = expected(model, data, ours, q, v, floating)
        qs = {c: coords[c] for c in ours.coordinates}
        qds = {c: rates[c] for c in ours.coordinates}
        # The quasi-velocities, in order (generator::model::urdf): the base's, then the joints'.
        joints = [c + "'" for c in ours.coordinates if not c.startswith("base_")]
        full = (["omega_x", "omega_y", "omega_z", "base_x'", "base_y'", "base_z'"] if floating else []) + joints
        reduced = [u for u in full if u[:-1] not in ours.ignorable]
        for kind in ours.formulations:
            quasi = {"kane": full, "reduced_volterra": reduced}.get(kind, [])
            x, momenta = ours.initial_state(kind, q=qs, qdot=qds)
            f = ours.rhs(0.0, x, kind, momenta=momenta if len(momenta) else None)
            names = ours.state_names(kind)
            got, want = [], []
            for i, s in enumerate(names):
                if kind in ("lagrange", "maggi") and s.endswith("'") and s[:-1] in accs:
                    got.append(f[i]), want.append(accs[s[:-1]])
                elif quasi and re.fullmatch(r"u\d+", s) and quasi[int(s[1:]) - 1] in speed_rates:
                    got.append(f[i]), want.append(speed_rates[quasi[int(s[1:]) - 1]])
            assert len(got) >= model.nv - (6 if floating else 0), (name, kind, names)
            got, want = np.array(got), np.array(want)
            worst[kind] = max(worst[kind], float(np.max(np.abs(got - want)) / max(1.0, float(np.max(np.abs(want))))))
    print(f"{name:14} {base:8} nq {model.nq:2} nv {model.nv:2}: loaded in {load_s:.2f} s; " + ", ".join(f"{k} {v:.1e}" for k, v in worst.items()), file=sys.stderr)
    return {"robot": name, "urdf": str(path.relative_to(path.parents[2])), "base": base, "nv": model.nv, "states": states, "worst_relative_difference": worst, "load_seconds": load_s}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--robots", default=",".join(ROBOTS))
    parser.add_argument("--states", type=int, default=5)
    args = parser.parse_args()
    folder = robots_folder()
    rng = np.random.default_rng(1)
    pin.seed(1)
    records = [check(n, folder / ROBOTS[n][0], ROBOTS[n][1], args.states, rng) for n in args.robots.split(",")]
    failed = [r for r in records if max(r["worst_relative_difference"].values()) > 1e-10]
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps({"command": "python docs/robots/pinocchio_check.py", "pinocchio": pin.__version__, "tolerance": 1e-10, "records": records}, indent=2) + "\n")
    print(f"wrote {OUT}", file=sys.stderr)
    if failed:
        raise SystemExit(f"differences above 1e-10: {[r['robot'] for r in failed]}")


if __name__ == "__main__":
    main()
