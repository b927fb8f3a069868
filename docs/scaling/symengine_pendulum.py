#!/usr/bin/env python3
"""SymEngine (the C++ algebra system, through its Python package) beside our generator on the
n-link pendulum on a cart, measured side by side and interleaved in one run; outside CI.

    python3 -m venv target/peers/symengine && target/peers/symengine/bin/pip install symengine
    cargo build --release -p generator
    target/peers/symengine/bin/python docs/scaling/symengine_pendulum.py --sizes 5,10,20,30,40,50,60

writes docs/scaling/symengine.json. For each n, alternately, `--repeats` times each, in fresh
processes, CPU time (user + system) of:

- ours: `generator MODEL.ron -o OUT.rs`, the whole generation (load, derive all four
  formulations, Definition 1, the reduced form, emission), on the model the generator's
  `n_link_pendulum_on_cart(n)` writes (`cargo run --release -p generator --example write_model`);
  its Kane right-hand side's count (the whole call: where the articulated-body recursion is
  chosen it has no solve) and the nodes its simplifier kept "as built" read from its summary;
- ours, the same work as SymEngine's: `generator MODEL.ron --formulations lagrange -o OUT.rs`
  (load, the mechanics, Lagrange's M and N, CSE, and the emission of that one module), with its
  assembly count (M and N after CSE: the quantity SymEngine's count measures);
- SymEngine's: a direct derivation of the same system, positions -> Jacobians J ->
  M = sum m J^T J, F = -sum m J^T (dJ/dt) q' - dV/dq, then `cse([M, F])`, counted by
  `count_ops` over the replacements and the reduced expressions (as docs/scaling/sympy_kane.py
  counts SymPy's).

First SymEngine's M and F are checked against the generator's model at the two smallest sizes:
q'' from M q'' = F at a random state (the scaling benchmark's `--point pendulum N`) against
ours, recorded as `checked` (the largest difference over the largest |q''|); the run stops where
they differ. The minimum over the repeats of each is recorded, with the ratios ours / SymEngine's. Both
sides are timed without starting their process: SymEngine's inside its process, after Python
has started and imported it; ours from outside, less the CPU of starting the generator (the
least of `--repeats` runs of `generator --version`, timed in the same rounds and recorded as
`ours_process_start_seconds`; each whole process's CPU is kept too, `*_process_seconds`).
"""

import argparse
import json
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
GENERATOR = ROOT / "target" / "release" / "generator"


def symengine_derivation(n):
    """SymEngine's M and F of the n-link pendulum on a cart and their CSE: (seconds, ops)."""
    import symengine as se

    start = time.process_time()
    mass, forcing, _ = mass_and_forcing(n)
    size = n + 1
    entries = [mass[r, c] for r in range(size) for c in range(r, size)] + [forcing[r, 0] for r in range(size)]
    replacements, reduced = se.cse(entries)
    seconds = time.process_time() - start
    ops = sum(se.count_ops(e) for _, e in replacements) + sum(se.count_ops(e) for e in reduced)
    return seconds, int(ops)


def mass_and_forcing(n):
    """SymEngine's M and F of the n-link pendulum on a cart (M q'' = F), and the symbols
    (q, qd, m, lengths, g)."""
    import symengine as se

    q = se.symbols(" ".join(f"q{i}" for i in range(n + 1)))
    qd = se.symbols(" ".join(f"qd{i}" for i in range(n + 1)))
    m = se.symbols(" ".join(f"m{i}" for i in range(n + 1)))
    lengths = se.symbols(" ".join(f"l{i}" for i in range(n)))
    g = se.Symbol("g")
    if n == 1:
        lengths = [lengths]
    # The cart at (q0, 0); mass i at the end of link i-1, at the absolute angle q_i from +y.
    positions = [(q[0], se.Integer(0))]
    x, y = q[0], se.Integer(0)
    for i in range(1, n + 1):
        x = x - lengths[i - 1] * se.sin(q[i])
        y = y + lengths[i - 1] * se.cos(q[i])
        positions.append((x, y))
    size = n + 1
    mass = se.zeros(size, size)
    forcing = se.zeros(size, 1)
    for i, (px, py) in enumerate(positions):
        jac = se.Matrix([[se.diff(px, qj) for qj in q], [se.diff(py, qj) for qj in q]])
        djac = se.zeros(2, size)
        for j in range(size):
            djac = djac + jac.diff(q[j]) * qd[j]
        qd_vec = se.Matrix(list(qd))
        mass = mass + m[i] * (jac.T * jac)
        forcing = forcing - m[i] * (jac.T * (djac * qd_vec))
        potential = m[i] * g * py
        forcing = forcing - se.Matrix([se.diff(potential, qj) for qj in q])
    return mass, forcing, (q, qd, m, lengths, g)


def check(n):
    """SymEngine's M and F against the generator's model of the same size: q'' from
    M q'' = F at the state and parameters of the scaling benchmark's point (`--point pendulum
    N`: a random state, every parameter moved off its value) against the generator's q''
    there. Returns the largest difference over the largest |q''|; exits where they differ by
    more than CHECK_TOLERANCE (a ratio against another system would say nothing)."""
    import symengine as se

    point = json.loads(cargo_output("bench", "-q", "-p", "generator", "--bench", "scaling", "--", "--point", "pendulum", str(n)))
    mass, forcing, (q, qd, _, _, _) = mass_and_forcing(n)
    values = {se.Symbol(name): value for name, value in point["params"].items()}
    values.update({x: point["q"][str(x)] for x in q})
    values.update({v: point["qdot"][f"q{i}"] for i, v in enumerate(qd)})
    size = n + 1
    a = [[float(mass[r, c].subs(values)) for c in range(size)] for r in range(size)]
    b = [float(forcing[r, 0].subs(values)) for r in range(size)]
    # Gaussian elimination with partial pivoting (M is symmetric positive definite).
    for k in range(size):
        p = max(range(k, size), key=lambda r: abs(a[r][k]))
        a[k], a[p], b[k], b[p] = a[p], a[k], b[p], b[k]
        for r in range(k + 1, size):
            f = a[r][k] / a[k][k]
            a[r] = [x - f * y for x, y in zip(a[r], a[k])]
            b[r] -= f * b[k]
    qdd = [0.0] * size
    for k in reversed(range(size)):
        qdd[k] = (b[k] - sum(a[k][j] * qdd[j] for j in range(k + 1, size))) / a[k][k]
    ours = [point["qddot"][f"q{i}"] for i in range(size)]
    error = max(abs(x - y) for x, y in zip(qdd, ours)) / max(abs(y) for y in ours)
    print(f"n = {n}: SymEngine's q'' differs from ours by {error:.1e} of the largest |q''|", file=sys.stderr, flush=True)
    if error > CHECK_TOLERANCE:
        raise SystemExit(f"SymEngine's pendulum on a cart (n = {n}) is not the generator's: q'' {qdd} against ours {ours}")
    return error


# `check` fails beyond this difference of q'' (relative to the largest |q''|): both sides in
# double precision, so a different model differs in the leading digits, round-off in the last.
CHECK_TOLERANCE = 1e-9


def cargo_output(*args):
    """What `cargo ARGS...` prints, run in the repository."""
    return subprocess.run(["cargo", *args], cwd=ROOT, capture_output=True, text=True, check=True).stdout


def children_cpu():
    """CPU seconds of the waited-for children so far, to the microsecond (`os.times` counts
    clock ticks of 10 ms)."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def generate(model_file, out_file, *options):
    """CPU seconds of one generation in a fresh process and its summary."""
    before = children_cpu()
    done = subprocess.run([str(GENERATOR), str(model_file), *options, "-o", str(out_file)], capture_output=True, text=True)
    seconds = children_cpu() - before
    if done.returncode != 0:
        raise SystemExit(f"the generator failed on {model_file}:\n{done.stderr}")
    return seconds, done.stderr


def process_start():
    """CPU seconds of starting and ending the generator: `generator --version` in a fresh
    process."""
    before = children_cpu()
    subprocess.run([str(GENERATOR), "--version"], capture_output=True, check=True)
    return children_cpu() - before


def rhs_ops(summary, formulation, assembly_only):
    """A right-hand side's operation count from the summary: its assembly (before the solve),
    or the whole call (assembly and solve, or the recursion's body where there is no solve)."""
    found = re.search(formulation + r"::rhs\s+\d+ lets, (assembly )?(\d+) ops[^\n]*?(\+ solve (\d+) ops)?\n", summary)
    if found is None:
        raise SystemExit(f"no {formulation}::rhs in the summary:\n{summary}")
    assembly, solve = int(found.group(2)), int(found.group(4) or 0)
    return assembly if assembly_only else assembly + solve


def ours(model_file, out_file):
    """CPU seconds of the generator's whole generation, its Kane right-hand side's count, and
    the nodes its simplifier kept as built."""
    seconds, summary = generate(model_file, out_file)
    line = re.search(r"simplifier: ([^\n]*)\(kept as built\)", summary)
    kept = 0
    if line:
        # The nodes over the term limit and the products kept for combining too many angles.
        kept = sum(int(n) for n in re.findall(r"(\d+) (?:nodes over the term limit|products combining)", line.group(1)))
    return seconds, rhs_ops(summary, "kane", False), kept


def ours_lagrange(model_file, out_file):
    """CPU seconds of the generator on Lagrange's form alone, and that form's assembly count
    (M and N after CSE)."""
    seconds, summary = generate(model_file, out_file, "--formulations", "lagrange")
    return seconds, rhs_ops(summary, "lagrange", True)


def theirs(n):
    """SymEngine's derivation in a fresh process: (CPU seconds measured inside, ops)."""
    done = subprocess.run([sys.executable, __file__, "--one", str(n)], capture_output=True, text=True, check=True)
    seconds, ops = done.stdout.split()
    return float(seconds), int(ops)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sizes", default="5,10,20,30")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--one", type=int, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.one is not None:
        seconds, ops = symengine_derivation(args.one)
        print(seconds, ops)
        return
    import symengine

    if not GENERATOR.is_file():
        raise SystemExit(f"no {GENERATOR}: run `cargo build --release -p generator` first")
    sizes = [int(s) for s in args.sizes.split(",")]
    checked = {n: check(n) for n in sorted(set(sizes))[:2]}
    records = []
    with tempfile.TemporaryDirectory() as folder:
        for n in sizes:
            model = Path(folder) / f"pendulum_on_cart_{n}.ron"
            text = cargo_output("run", "--release", "-q", "-p", "generator", "--example", "write_model", "--", "pendulum", str(n))
            model.write_text(text)
            mine, same_work, other, starts = [], [], [], []
            for _ in range(args.repeats):
                starts.append(process_start())
                mine.append(ours(model, Path(folder) / "out.rs"))
                same_work.append(ours_lagrange(model, Path(folder) / "out.rs"))
                other.append(theirs(n))
            best_ours = min(mine, key=lambda r: r[0])
            best_lagrange = min(same_work, key=lambda r: r[0])
            best_theirs = min(other, key=lambda r: r[0])
            start = min(starts)
            inside, lagrange_inside = best_ours[0] - start, best_lagrange[0] - start
            record = {
                "n": n,
                "ours_seconds": inside,
                "ours_process_seconds": best_ours[0],
                "ours_process_start_seconds": start,
                "ours_kane_rhs_ops": best_ours[1],
                "ours_kept_as_built": best_ours[2],
                "ours_lagrange_seconds": lagrange_inside,
                "ours_lagrange_process_seconds": best_lagrange[0],
                "ours_lagrange_assembly_ops": best_lagrange[1],
                "symengine_seconds": best_theirs[0],
                "symengine_cse_ops": best_theirs[1],
                "time_ratio": inside / best_theirs[0],
                "lagrange_time_ratio": lagrange_inside / best_theirs[0],
                "ops_ratio": best_lagrange[1] / best_theirs[1],
                "kane_ops_ratio": best_ours[1] / best_theirs[1],
            }
            records.append(record)
            print(
                f"n = {n}: ours {record['ours_seconds']:.3f} s (Lagrange alone {record['ours_lagrange_seconds']:.3f} s), "
                f"SymEngine {record['symengine_seconds']:.3f} s (ratios {record['time_ratio']:.2f}, {record['lagrange_time_ratio']:.2f}); "
                f"Lagrange assembly {record['ours_lagrange_assembly_ops']} ops, Kane rhs {record['ours_kane_rhs_ops']}, "
                f"SymEngine's cse {record['symengine_cse_ops']} (ratios {record['ops_ratio']:.2f}, {record['kane_ops_ratio']:.2f}); "
                f"kept as built {record['ours_kept_as_built']}",
                file=sys.stderr,
                flush=True,
            )
    out = ROOT / "docs" / "scaling" / "symengine.json"
    document = {
        "command": "target/peers/symengine/bin/python docs/scaling/symengine_pendulum.py --sizes " + args.sizes,
        "symengine": symengine.__version__,
        "repeats": args.repeats,
        "checked": {str(n): e for n, e in checked.items()},
        "records": records,
    }
    out.write_text(json.dumps(document, indent=1) + "\n")
    print(f"wrote {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
