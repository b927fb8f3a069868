"""Ensembles spread over a Dask cluster (``dask.distributed``): the members split into chunks,
each chunk a task that runs ``multibody.ensemble`` on a worker (on every core of that worker),
the results gathered into one array, equal to the ensemble run on one machine.

>>> from dask.distributed import Client                       # doctest: +SKIP
>>> client = Client("tcp://scheduler:8786")                   # doctest: +SKIP
>>> states = multibody.distributed.ensemble(client, model, t_eval, q0=q0)  # doctest: +SKIP

A model travels to the workers as its text and is derived there once per worker process.
"""

from __future__ import annotations

import numpy as np

import multibody


def _rows(value, start, stop):
    """Rows ``start:stop`` of a 2-D argument; one row for all members and None pass as they are."""
    if value is None:
        return None
    array = np.asarray(value, dtype=float)
    return array[start:stop] if array.ndim == 2 else array


def _members(params, q0, qdot0):
    counts = {np.asarray(v).shape[0] for v in (params, q0, qdot0) if v is not None and np.ndim(v) == 2}
    if len(counts) != 1:
        raise ValueError("give params, q0 or qdot0 as 2-D arrays (N, ...) that agree on N: one row per member")
    return counts.pop()


def _chunk(model, t_eval, params, q0, qdot0, options):
    """One task: a chunk of the ensemble, run on the worker: its states, the times each member
    reached and when each looked stiff (the caller warns, as ``multibody.ensemble`` does)."""
    return multibody._ensemble_arrays(model, t_eval, params, q0, qdot0, **options)


def ensemble(client, model, t_eval, params=None, q0=None, qdot0=None, chunk_size=None, **options):
    """``multibody.ensemble`` over the workers of ``client`` (a ``dask.distributed.Client``):
    the N members in chunks of ``chunk_size`` (default: N split evenly over the workers' threads,
    at least 4 chunks per worker thread for balance), one task per chunk. ``options`` are
    ``multibody.ensemble``'s (``formulation``, ``method``, ``rtol``, ``atol``, ``h``,
    ``threads`` per task, ``return_reached``). Returns what ``multibody.ensemble`` returns, in
    member order."""
    n = _members(params, q0, qdot0)
    return_reached = options.pop("return_reached", False)
    # The gathered output is whole on the caller's machine: the same limit as one ensemble's.
    limit = options.get("max_values") or 10**8
    values = n * len(np.atleast_1d(t_eval)) * len(model.state_names(options.get("formulation")))
    if values > limit:
        raise ValueError(
            f"the ensemble's output would hold {values} numbers ({values * 8e-9:.1f} GB), more than the limit of {limit}: "
            "give fewer members or output times, or raise the limit (max_values)"
        )
    if chunk_size is None:
        threads = max(1, sum(client.nthreads().values()))
        chunk_size = max(1, -(-n // (4 * threads)))
    t_eval = np.asarray(t_eval, dtype=float)
    [remote_model] = client.scatter([model], broadcast=True)
    starts = range(0, n, chunk_size)
    futures = [
        client.submit(
            _chunk,
            remote_model,
            t_eval,
            _rows(params, s, s + chunk_size),
            _rows(q0, s, s + chunk_size),
            _rows(qdot0, s, s + chunk_size),
            options,
            pure=False,
        )
        for s in starts
    ]
    parts = client.gather(futures)
    states, reached, stiff_at = (np.concatenate([p[k] for p in parts]) for k in range(3))
    return multibody._ensemble_result(states, reached, stiff_at, return_reached)
