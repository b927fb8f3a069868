"""Runs from Python: scipy's solve_ivp on the wheel's rhs and jacobian against the independent
reference trajectory of scene 2, the built-in integrators, and ensembles."""

import _thread
import csv
import math
import pathlib
import threading
import warnings

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import multibody


def reference(root, scene):
    with open(root / "tests" / "reference" / f"ref_{scene}.csv") as f:
        rows = list(csv.reader(f))
    return rows[0], np.array(rows[1:], dtype=float)


def test_solve_ivp_with_the_exact_jacobian_follows_scene_2s_reference(root):
    m = multibody.load("three_body")
    header, ref = reference(root, "three_body")
    assert header[1 : 1 + len(m.coordinates)] == m.coordinates
    kind = "kane"
    x0, _ = m.initial_state(kind)
    n = len(m.coordinates)
    # The whole 50 s reference; Radau, an implicit method, calls the Jacobian.
    t_eval = ref[:, 0]
    jacobians = []

    def jac(t, x):
        jacobians.append(t)
        return m.jacobian(t, x, kind)

    sol = solve_ivp(lambda t, x: m.rhs(t, x, kind), (0.0, t_eval[-1]), x0, method="Radau", t_eval=t_eval, jac=jac, rtol=1e-12, atol=1e-12)
    assert sol.success, sol.message
    assert len(jacobians) > 0
    q = sol.y[:n].T
    assert np.max(np.abs(q - ref[:, 1 : 1 + n])) < 1e-8


def test_the_jacobian_is_the_derivative_of_the_rhs():
    m = multibody.load("three_body")
    for kind in m.formulations:
        x, momenta = m.initial_state(kind)
        g = momenta if kind == "reduced_volterra" else None
        jac = m.jacobian(0.2, x, kind, momenta=g)
        h = 1e-6
        for c in range(len(x)):
            up, down = x.copy(), x.copy()
            up[c] += h
            down[c] -= h
            column = (m.rhs(0.2, up, kind, momenta=g) - m.rhs(0.2, down, kind, momenta=g)) / (2 * h)
            assert np.max(np.abs(jac[:, c] - column)) < 1e-7 * max(1.0, np.max(np.abs(column))), (kind, c)


def test_simulate_follows_the_reference_and_keeps_the_invariants(root):
    m = multibody.load("three_body")
    header, ref = reference(root, "three_body")
    for kind in m.formulations:
        # The file asks for the paper's loose settings; the reference needs tight ones.
        run = m.simulate(kind, t_end=5.0, dt_out=0.1, method="dop853", rtol=1e-12, atol=1e-12, frame=False)
        assert run.formulation == kind
        t = run["t"]
        assert len(t) == 51 and t[0] == 0.0
        q = np.column_stack([run[c] for c in m.coordinates])
        assert np.max(np.abs(q - ref[:51, 1 : 1 + len(m.coordinates)])) < 1e-8, kind
        assert np.max(np.abs(run["energy_error"])) < 1e-10
        for c in m.ignorable:
            p = run[f"momentum:{c}"]
            assert np.max(np.abs(p - p[0])) < 1e-8


def test_simulate_gives_a_dataframe_with_pandas():
    pd = pytest.importorskip("pandas")
    m = multibody.load("cart_pendulum")
    frame = m.simulate("kane", t_end=1.0, dt_out=0.5)
    assert isinstance(frame, pd.DataFrame)
    assert list(frame.columns[:4]) == ["t", "theta1", "theta2", "x"]
    assert frame.attrs["formulation"] == "kane" and frame.attrs["model"] == "cart_pendulum"
    plain = m.simulate("kane", t_end=1.0, dt_out=0.5, frame=False)
    assert np.array_equal(frame["theta1"].to_numpy(), plain["theta1"])


def test_simulate_reports_events():
    m = multibody.load("bouncing_ball")
    run = m.simulate("kane", t_end=10.0, dt_out=0.01, frame=False)
    names = [e[0] for e in run.events]
    assert names[-1] == "wall" and "floor" in names and "apex" in names
    # The wall at x = 5 is reached at t = 5 (x' = 1): the run stops there.
    assert abs(run.events[-1][1] - 5.0) < 1e-9
    assert run["t"][-1] <= 5.0


def test_a_stiff_run_warns_and_names_the_stiff_method():
    m = multibody.load("stiff_pendulum")
    # At k = 1e8 the spring's mode holds DOP853 (the default) and DOPRI5 to steps set by
    # stability: Hairer's test says so, and the stiff method is named.
    for method in [None, "dopri5"]:
        with pytest.warns(UserWarning, match=r'stiff_pendulum kane: looks stiff from t = 0\.0.*method="ros23"'):
            m.simulate("kane", t_end=0.5, dt_out=0.1, method=method, rtol=1e-4, atol=1e-4, params={"k": 1e8}, frame=False)
    # At its own stiffness the run is accuracy-bound: no warning (an error if one is raised).
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m.simulate("kane", t_end=0.5, dt_out=0.1, frame=False)
        stiff = m.simulate("kane", t_end=0.5, dt_out=0.1, method="ros23", rtol=1e-4, atol=1e-4, params={"k": 1e8}, frame=False)
    assert stiff["t"][-1] == 0.5


def stiff_members(m):
    """The stiff pendulum on a soft spring (k = 100) and on a stiff one (k = 1e8)."""
    params = np.tile(list(m.params.values()), (2, 1))
    params[:, list(m.params).index("k")] = [100.0, 1e8]
    return params


def test_an_ensemble_names_the_members_that_looked_stiff():
    m = multibody.load("stiff_pendulum")
    t_eval = np.linspace(0.0, 0.2, 3)
    with pytest.warns(UserWarning, match=r'1 member looked stiff: member 1 looks stiff from t = 0\.0.*method="ros23": members \[1\]'):
        states = multibody.ensemble(m, t_eval, params=stiff_members(m), formulation="kane", rtol=1e-4, atol=1e-4)
    assert states.shape[0] == 2 and not np.isnan(states).any()
    # The soft spring alone: no warning (an error if one is raised).
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        multibody.ensemble(m, t_eval, params=stiff_members(m)[:1], formulation="kane", rtol=1e-4, atol=1e-4)


def members(m, n):
    rng = np.random.default_rng(7)
    q0, qd0 = m.initial
    q = np.tile(q0, (n, 1)) + 0.05 * rng.standard_normal((n, len(q0)))
    qd = np.tile(qd0, (n, 1)) + 0.05 * rng.standard_normal((n, len(q0)))
    params = np.tile(list(m.params.values()), (n, 1))
    params[:, 0] *= 1.0 + 0.1 * rng.random(n)
    return params, q, qd


def test_an_ensemble_is_its_runs_one_by_one():
    m = multibody.load("three_body")
    params, q, qd = members(m, 16)
    t_eval = np.linspace(0.0, 2.0, 21)
    for kind in ["kane", "reduced_volterra"]:
        states = multibody.ensemble(m, t_eval, params=params, q0=q, qdot0=qd, formulation=kind)
        names = m.state_names(kind)
        assert states.shape == (16, 21, len(names))
        for k in range(16):
            alone = m.simulate(kind, t_end=2.0, dt_out=0.1, params=params[k], q=q[k], qdot=qd[k], frame=False)
            expected = np.column_stack([alone[f"state:{s}"] for s in names])
            assert np.array_equal(states[k], expected), (kind, k)
        assert not np.array_equal(states[0], states[1])
    one = multibody.ensemble(m, t_eval, params=params, q0=q, qdot0=qd, formulation="kane", threads=1)
    two = multibody.ensemble(m, t_eval, params=params, q0=q, qdot0=qd, formulation="kane", threads=2)
    assert np.array_equal(one, two)


def test_an_ensemble_says_which_members_stopped():
    m = multibody.load("bouncing_ball")
    qd = np.array([[2.2, 0.0], [1.0, 0.0]])
    t_eval = np.arange(0.0, 4.01, 0.5)
    with pytest.warns(UserWarning, match=r"members \[0\]"):
        states = multibody.ensemble(m, t_eval, qdot0=qd, formulation="kane")
    assert np.all(np.isnan(states[0, 5:])) and np.all(np.isfinite(states[0, :5]))
    states, reached = multibody.ensemble(m, t_eval, qdot0=qd, formulation="kane", return_reached=True)
    assert reached.tolist() == [5, 9]


def test_an_ensemble_refuses_shapes_that_disagree():
    m = multibody.load("three_body")
    params, q, qd = members(m, 4)
    with pytest.raises(ValueError, match="disagree"):
        multibody.ensemble(m, [0.0, 1.0], params=params, q0=q[:3])
    with pytest.raises(ValueError, match="one row per member"):
        multibody.ensemble(m, [0.0, 1.0])
    with pytest.raises(ValueError, match="output times"):
        multibody.ensemble(m, [1.0, 0.0], q0=q)


def _interrupt_main_after(seconds):
    """Ctrl-C, as the interpreter sees it, `seconds` from now (`_thread.interrupt_main` runs
    the SIGINT handler on the main thread, where the run is)."""
    timer = threading.Timer(seconds, _thread.interrupt_main)
    timer.start()
    return timer


def _stopped_at(notes):
    """The time in the note `simulate` adds to the KeyboardInterrupt it lets through."""
    (note,) = [n for n in notes if n.startswith("multibody: the run stopped at t = ")]
    return float(note.split("t = ")[1].split(" ")[0])


def test_ctrl_c_stops_a_long_run():
    # 1e5 s of the cart pendulum at rtol 1e-13 take about 25 s of integration here. The
    # KeyboardInterrupt must come from inside the run: its note says where the run stopped (an
    # interrupt handled only after the run returned would carry no note).
    m = multibody.load("cart_pendulum")
    timer = _interrupt_main_after(0.3)
    with pytest.raises(KeyboardInterrupt) as caught:
        m.simulate(t_end=1e5, dt_out=1e5, rtol=1e-13, atol=1e-13, frame=False)
    timer.join()
    t = _stopped_at(caught.value.__notes__)
    assert 0.0 < t < 1e5
    # The model still runs afterwards.
    assert len(m.simulate(t_end=1.0, dt_out=0.5, frame=False)["t"]) == 3


def test_ctrl_c_stops_an_ensemble():
    m = multibody.load("cart_pendulum")
    q0 = np.tile(np.array(m.initial[0]), (16, 1))
    q0[:, 0] += np.linspace(0.0, 0.1, 16)
    timer = _interrupt_main_after(0.3)
    with pytest.raises(KeyboardInterrupt) as caught:
        # About 20 s on two threads, uninterrupted.
        multibody.ensemble(m, [0.0, 1e4], q0=q0, rtol=1e-13, atol=1e-13, threads=2)
    timer.join()
    assert "multibody: the ensemble stopped" in caught.value.__notes__


def test_oversized_ensembles_are_refused_before_they_run():
    # 10**6 members x 1000 times grew until killed; a t_eval of 1.25e8 points aborted the
    # interpreter; threads=10**4 hung. Each is refused at once, naming the limit.
    m = multibody.load("cart_pendulum")
    q0 = np.tile(m.initial[0], (10**6, 1))
    with pytest.raises(ValueError, match="max_values"):
        multibody.ensemble(m, np.linspace(0, 1, 1000), q0=q0)
    with pytest.raises(ValueError, match="more than the 1000001 a run may hold"):
        multibody.ensemble(m, np.zeros(1_100_000), q0=q0[:2])
    for threads in (10**4, 10**6):
        with pytest.raises(ValueError, match="per core"):
            multibody.ensemble(m, [0.0, 0.1], q0=q0[:2], threads=threads)
    # Raised, the limit lets it through.
    states = multibody.ensemble(m, [0.0, 0.1], q0=q0[:3], max_values=3 * 2 * len(m.state_names()))
    assert states.shape == (3, 2, len(m.state_names()))
    with pytest.raises(ValueError, match="max_values"):
        multibody.ensemble(m, [0.0, 0.1], q0=q0[:3], max_values=3 * 2 * len(m.state_names()) - 1)


def test_loads_of_a_huge_text_is_refused_at_once():
    with pytest.raises(multibody.ModelError, match="more than the 16777216 a model may hold"):
        multibody.loads("Model(" + " " * (17 << 20) + ")")


def test_bad_arguments_say_what_is_wrong():
    m = multibody.load("cart_pendulum")
    with pytest.raises(ValueError, match="h needs a positive number, not 0"):
        m.simulate("kane", t_end=0.1, dt_out=0.05, method="rk4", h=0.0)
    with pytest.raises(ValueError, match="rtol = 1e300"):
        m.simulate("kane", t_end=0.1, dt_out=0.05, rtol=1e300)
    q0 = list(m.initial[0])
    q0[0] = float("nan")
    with pytest.raises(multibody.SimulationError, match="theta1` is NaN, not a finite number"):
        m.simulate("kane", t_end=0.1, dt_out=0.05, q=q0)
    # Another model's run is named as such, not a bare KeyError.
    run = multibody.load("spring_cart").simulate("kane", t_end=0.1, dt_out=0.05)
    with pytest.raises(ValueError, match="the run is of model `spring_cart`, not of `cart_pendulum`"):
        m.animate(run, "never.html")


def test_a_run_stopped_early_keeps_its_trajectory_up_to_the_stop():
    # Euler angles pitched up to their singular attitude (cos(theta) = 0 at t = 0.1414): the run
    # stops there, as `multibody simulate` does, and the error carries the outputs before it.
    m = multibody.load(str(pathlib.Path(__file__).parents[2] / "tests" / "fixtures" / "tumbling_euler.ron"))
    ask = dict(t_end=1.0, dt_out=0.01, q={"psi": 0.1, "theta": 1.5, "phi": 0.3}, qdot={"psi": 0.0, "theta": 0.5, "phi": 0.0})
    for frame in [False, True]:
        with pytest.raises(multibody.SimulationError, match=r"cos\(theta\) = 0") as info:
            m.simulate("lagrange", frame=frame, **ask)
        kept = info.value.trajectory
        t = np.asarray(kept["t"])
        assert len(t) == 15 and math.isclose(t[-1], 0.14, abs_tol=1e-12), t
        # The same outputs as a run asked to end there.
        ended = m.simulate("lagrange", frame=False, **{**ask, "t_end": 0.14})
        for name in ["psi", "theta", "phi", "energy"]:
            assert np.allclose(np.asarray(kept[name]), ended[name], rtol=0, atol=1e-8), name
        assert np.asarray(kept["theta"])[-1] > 1.5
