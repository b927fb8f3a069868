"""Python's cells of the matrix (the issue "Every path works"): `rhs`, `jacobian`, `simulate`,
`linearize` and `animate` on every built-in model and on the families the benchmarks use, in
every formulation; and the README's recipe (`solve_ivp` with the exact Jacobian) on the
pendulum on a cart up to 24 links, whose exact Jacobian failed from 8 links."""

import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import multibody

FAMILIES = [("pendulum_on_cart", n) for n in (1, 8, 9, 16)] + [("floating_chain", n) for n in (1, 4)]


def _models():
    for name in multibody.built_in():
        yield name, lambda name=name: multibody.load(name)
    for family, n in FAMILIES:
        yield f"{family}({n})", lambda family=family, n=n: getattr(multibody, family)(n)


def _central(m, kind, x, momenta):
    """d f / d x by central differences of `rhs`."""
    n = len(x)
    out = np.zeros((n, n))
    for k in range(n):
        h = 1e-6 * (1.0 + abs(x[k]))
        up, down = x.copy(), x.copy()
        up[k] += h
        down[k] -= h
        out[:, k] = (m.rhs(0.0, up, kind, momenta=momenta) - m.rhs(0.0, down, kind, momenta=momenta)) / (2 * h)
    return out


@pytest.mark.parametrize("name,make", list(_models()), ids=[n for n, _ in _models()])
def test_every_call_on_every_model(name, make, tmp_path):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = make()
    assert not caught, f"{name}: a built-in model or family warns: {[str(w.message) for w in caught]}"
    run_span = 0.2
    for kind in m.formulations:
        x0, momenta = m.initial_state(kind)
        g = momenta if len(momenta) else None
        f = m.rhs(0.0, x0, kind, momenta=g)
        assert f.shape == x0.shape and np.all(np.isfinite(f)), (name, kind)
        # (The bicycle's exact Jacobians exceed the node budget: differenced, tested in Rust.)
        if name != "bicycle":
            jac = m.jacobian(0.0, x0, kind, momenta=g)
            scale = max(1.0, np.max(np.abs(jac)))
            assert np.max(np.abs(jac - _central(m, kind, x0, g))) <= 1e-6 * scale, (name, kind)
        run = m.simulate(kind, t_end=run_span, dt_out=run_span / 10)
        energy = [c for c in run.columns if c.endswith("_error") and not c.startswith("momentum")]
        assert energy and np.max(np.abs(np.asarray(run[energy[0]]))) < 1e-6 * (1 + np.max(np.abs(np.asarray(run[energy[0][: -len("_error")]])))), (name, kind)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # a point that is not an equilibrium is said so
            lin = m.linearize(kind)
        assert lin.A.shape[0] == lin.A.shape[1] and np.all(np.isfinite(lin.eigenvalues)), (name, kind)
    page = tmp_path / "page.html"
    m.animate(run, page)
    assert page.read_text().startswith("<!DOCTYPE html>")


@pytest.mark.parametrize("n", [8, 16, 24])
def test_the_readme_recipe_on_the_pendulum_on_a_cart(n):
    # solve_ivp with the exact Jacobian: it raised "singular configuration" from 8 links.
    m = multibody.pendulum_on_cart(n)
    for kind in ("kane", "reduced_volterra"):
        x0, momenta = m.initial_state(kind)
        g = momenta if len(momenta) else None
        sol = solve_ivp(
            lambda t, x: m.rhs(t, x, kind, momenta=g),
            (0, 0.5),
            x0,
            method="Radau",
            jac=lambda t, x: m.jacobian(t, x, kind, momenta=g),
            rtol=1e-8,
            atol=1e-8,
        )
        assert sol.success, (n, kind, sol.message)
        # The same motion as the tool's own run.
        run = m.simulate(kind, t_end=0.5, dt_out=0.5)
        states = [c for c in run.columns if c.startswith("state:")]
        last = np.array([np.asarray(run[c])[-1] for c in states])
        assert len(states) == len(x0) and np.max(np.abs(sol.y[:, -1] - last)) < 1e-5, (n, kind)
