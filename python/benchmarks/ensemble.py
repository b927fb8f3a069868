"""The wheel measured, outside CI: writes docs/benchmarks/python.json (the README quotes it).

    python python/benchmarks/ensemble.py          # with the wheel, scipy installed

1. From ``import multibody`` to the first right-hand side of the 10-link pendulum on a cart
   (derivation and in-process compilation included), in fresh processes, best of 5; and the
   same with today's SymPy (``sympy.physics.mechanics.models.n_link_pendulum_on_cart(10)``, its
   ``KanesMethod``'s full mass matrix and forcing made a function by ``lambdify(cse=True)``, the
   first call solving ``M x' = F``), when SymPy is installed (``pip install sympy``), best of 3.
   The two right-hand sides are compared at the same state.
2. Runs per second of scene 2 (three_body, the reduced formulation): ``multibody.ensemble`` on
   every core and on one thread, against a Python loop of ``scipy.integrate.solve_ivp`` over the
   same ``rhs`` at the same method and tolerances (DOP853, rtol = atol = 1e-10), alternated in
   rounds, the best round of each. The largest difference between the two at the end is
   recorded, so that the runs are seen to be the same runs.
"""

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

import multibody

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "benchmarks" / "python.json"


def first_rhs(repeats=5):
    code = (
        "import time; t0 = time.perf_counter(); import multibody; t1 = time.perf_counter();"
        "m = multibody.pendulum_on_cart(10); t2 = time.perf_counter();"
        "x, g = m.initial_state('kane'); m.rhs(0.0, x, 'kane'); t3 = time.perf_counter();"
        "print(t1 - t0, t2 - t1, t3 - t2, t3 - t0)"
    )
    runs = []
    for k in range(repeats):
        out = subprocess.run([sys.executable, "-W", "ignore", "-c", code], capture_output=True, text=True, check=True)
        runs.append([float(v) for v in out.stdout.split()])
        print(f"  import to first rhs, run {k + 1}: {runs[-1][3]:.3f} s", file=sys.stderr)
    best = min(runs, key=lambda r: r[3])
    return {"import_s": best[0], "load_s": best[1], "first_rhs_s": best[2], "total_s": best[3], "repeats": repeats}


SYMPY_FIRST_RHS = """
import time
t0 = time.perf_counter()
import numpy as np
import sympy as sm
from sympy.physics.mechanics.models import n_link_pendulum_on_cart
kane = n_link_pendulum_on_cart(10, cart_force=False, joint_torques=False)
q, u = kane.q, kane.u
constants = sorted(kane.forcing_full.free_symbols | kane.mass_matrix_full.free_symbols - set(q) - set(u) - {sm.Symbol("t")}, key=str)
f = sm.lambdify((list(q) + list(u), constants), [kane.mass_matrix_full, kane.forcing_full], cse=True)
x = np.array([0.0] + [0.1 * (i + 1) for i in range(10)] + [0.2] + [0.0] * 10)
values = [9.81 if str(c) == "g" else 1.0 for c in constants]
M, F = f(x, values)
xdot = np.linalg.solve(np.array(M, dtype=float), np.array(F, dtype=float).ravel())
t1 = time.perf_counter()
print(t1 - t0, " ".join(repr(float(v)) for v in xdot))
"""


def sympy_first_rhs(repeats=3):
    """Today's SymPy from import to the first right-hand side of the same chain, and that
    right-hand side against ours at the same state (None without SymPy)."""
    try:
        import sympy
    except ImportError:
        return None
    runs = []
    for k in range(repeats):
        out = subprocess.run([sys.executable, "-W", "ignore", "-c", SYMPY_FIRST_RHS], capture_output=True, text=True, check=True)
        seconds, *xdot = out.stdout.split()
        runs.append((float(seconds), np.array([float(v) for v in xdot])))
        print(f"  SymPy import to first rhs, run {k + 1}: {runs[-1][0]:.2f} s", file=sys.stderr)
    best = min(runs, key=lambda r: r[0])
    # Ours at the same state: SymPy's state is q0..q10, u0..u10 (rates), Lagrange's here too.
    m = multibody.pendulum_on_cart(10)
    q = [0.0] + [0.1 * (i + 1) for i in range(10)]
    qd = [0.2] + [0.0] * 10
    x, g = m.initial_state("lagrange", q=q, qdot=qd)
    ours = m.rhs(0.0, x, "lagrange")[: 2 * len(q)]
    difference = float(np.max(np.abs(ours - best[1])) / max(1.0, float(np.max(np.abs(best[1])))))
    return {"sympy": sympy.__version__, "total_s": best[0], "repeats": repeats, "relative_difference_of_the_rhs": difference}


def ensemble_against_solve_ivp(members=2000, loop_members=30, rounds=5):
    m = multibody.load("three_body")
    kind = "reduced_volterra"
    rng = np.random.default_rng(1)
    q0, qd0 = m.initial
    q = np.tile(q0, (members, 1)) + 0.02 * rng.standard_normal((members, len(q0)))
    t_eval = np.linspace(0.0, 10.0, 101)
    options = dict(formulation=kind, method="dop853", rtol=1e-10, atol=1e-10)
    best = {"all_cores": np.inf, "one_thread": np.inf, "solve_ivp": np.inf}
    difference = 0.0
    for r in range(rounds):
        start = time.perf_counter()
        states = multibody.ensemble(m, t_eval, q0=q, **options)
        best["all_cores"] = min(best["all_cores"], (time.perf_counter() - start) / members)
        start = time.perf_counter()
        multibody.ensemble(m, t_eval, q0=q[: members // 4], threads=1, **options)
        best["one_thread"] = min(best["one_thread"], (time.perf_counter() - start) / (members // 4))
        start = time.perf_counter()
        for k in range(loop_members):
            x0, g = m.initial_state(kind, q=q[k])
            sol = solve_ivp(lambda t, x: m.rhs(t, x, kind, momenta=g), (0.0, 10.0), x0, method="DOP853", t_eval=t_eval, rtol=1e-10, atol=1e-10)
            difference = max(difference, float(np.max(np.abs(sol.y[:, -1] - states[k, -1]))))
        best["solve_ivp"] = min(best["solve_ivp"], (time.perf_counter() - start) / loop_members)
        print(f"  round {r + 1}: " + ", ".join(f"{k} {1 / v:.0f} runs/s" for k, v in best.items()), file=sys.stderr)
    return {
        "model": "three_body",
        "formulation": kind,
        "settings": "DOP853, rtol 1e-10, atol 1e-10, 101 outputs over 10 s",
        "members": members,
        "loop_members": loop_members,
        "rounds": rounds,
        "runs_per_second": {k: 1.0 / v for k, v in best.items()},
        "speedup_all_cores": best["solve_ivp"] / best["all_cores"],
        "speedup_one_thread": best["solve_ivp"] / best["one_thread"],
        "largest_difference_at_the_end": difference,
    }


def main():
    print("from import to the first rhs (10-link pendulum on a cart)...", file=sys.stderr)
    first = first_rhs()
    print("the same with SymPy...", file=sys.stderr)
    sympy_first = sympy_first_rhs()
    print("ensemble against a loop of solve_ivp (scene 2)...", file=sys.stderr)
    runs = ensemble_against_solve_ivp()
    record = {
        "command": "python python/benchmarks/ensemble.py",
        "cores": os.cpu_count(),
        "python": sys.version.split()[0],
        "import_to_first_rhs": first,
        "sympy_import_to_first_rhs": sympy_first,
        "ensemble": runs,
    }
    OUT.write_text(json.dumps(record, indent=2) + "\n")
    print(f"wrote {OUT}", file=sys.stderr)


if __name__ == "__main__":
    main()
