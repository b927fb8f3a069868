"""A tour of the wheel, notebook-style (each block a cell): scene 2 loaded, its four formulations
compared, an ensemble of 1,000 initial conditions on every core, the same ensemble on a local Dask
cluster, and the motion written as an HTML page. Run by the tests (python/tests/test_example.py).

    python python/examples/tour.py [OUT_DIR]

The cells run inside `main()`: Dask starts its workers as fresh processes that import this file,
and only the guard at the end keeps them from running the tour themselves.
"""

import sys
import time
from pathlib import Path

import numpy as np
from dask.distributed import Client, LocalCluster

import multibody
import multibody.distributed


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    out.mkdir(parents=True, exist_ok=True)

    # %% Scene 2 of the paper: a satellite with two rotors (three bodies, eight coordinates, three of
    # them ignorable). Built into the wheel; `multibody.load("path/to/model.ron")` reads a file.
    model = multibody.load("three_body")
    print(model)
    print("parameters:", model.params)

    # %% The four formulations integrated at the same settings: the same motion, in 16 states
    # (Lagrange and Maggi: q and q'; Kane: q and the 8 quasi-velocities) or 13 (the reduced
    # method: the 3 momenta of the ignorable coordinates are constants, not states).
    finals = {}
    for kind in model.formulations:
        run = model.simulate(kind, t_end=10.0, dt_out=0.1, method="dop853", rtol=1e-10, atol=1e-10, frame=False)
        finals[kind] = np.array([run[c][-1] for c in model.coordinates])
        print(f"{kind:18} {len(model.state_names(kind)):2} states, max |energy error| {np.max(np.abs(run['energy_error'])):.1e}")
    spread = max(np.max(np.abs(finals[k] - finals["lagrange"])) for k in finals)
    print(f"largest difference between the formulations at t = 10: {spread:.1e}")

    # %% An ensemble: 1,000 initial attitudes around the file's, run on every core (the GIL released).
    rng = np.random.default_rng(0)
    q0, qdot0 = model.initial
    q = np.tile(q0, (1000, 1))
    q[:, :3] += 0.1 * rng.standard_normal((1000, 3))
    t_eval = np.linspace(0.0, 5.0, 51)
    start = time.perf_counter()
    states = multibody.ensemble(model, t_eval, q0=q, formulation="reduced")
    print(f"ensemble of {states.shape[0]} runs: states {states.shape} in {time.perf_counter() - start:.2f} s")

    # %% The same ensemble on a Dask cluster: here two local worker processes; on a real cluster,
    # `Client("tcp://scheduler:8786")` instead of the LocalCluster.
    with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster, Client(cluster) as client:
        spread_states = multibody.distributed.ensemble(client, model, t_eval, q0=q, formulation="reduced")
    print("the cluster's ensemble equals the local one:", bool(np.array_equal(spread_states, states)))

    # %% The motion: a self-contained page (open it in any browser; no network needed).
    run = model.simulate("reduced", t_end=20.0, dt_out=0.05)
    page = out / "three_body.html"
    model.animate(run, page)
    print("wrote", page)


if __name__ == "__main__":
    main()
