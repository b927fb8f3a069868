"""An ensemble spread over a local Dask cluster of two worker processes equals the same
ensemble run on this machine, member by member, and names its stiff members as it does."""

import numpy as np
import pytest

import multibody

distributed = pytest.importorskip("dask.distributed")


def test_an_ensemble_over_a_local_cluster_equals_the_local_one():
    import multibody.distributed

    m = multibody.load("three_body")
    rng = np.random.default_rng(3)
    n = 24
    q0, qd0 = m.initial
    q = np.tile(q0, (n, 1)) + 0.05 * rng.standard_normal((n, len(q0)))
    t_eval = np.linspace(0.0, 1.0, 11)
    local = multibody.ensemble(m, t_eval, q0=q, formulation="reduced")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            with distributed.get_task_stream(client) as stream:
                spread = multibody.distributed.ensemble(client, m, t_eval, q0=q, formulation="reduced", chunk_size=5)
            # Five chunks of at most five members, run as tasks by both worker processes.
            chunks = [t for t in stream.data if t["key"].startswith("_chunk")]
            assert len(chunks) == 5
            assert len({t["worker"] for t in chunks}) == 2
            # A member that looked stiff on a worker is named to the caller, as locally.
            stiff = multibody.load("stiff_pendulum")
            params = np.tile(list(stiff.params.values()), (2, 1))
            params[:, list(stiff.params).index("k")] = [100.0, 1e8]
            with pytest.warns(UserWarning, match=r'member 1 looks stiff from t = .*method="ros23": members \[1\]'):
                multibody.distributed.ensemble(client, stiff, [0.0, 0.1, 0.2], params=params, formulation="kane", rtol=1e-4, atol=1e-4, chunk_size=1)
            # An unknown option is refused, as by multibody.ensemble.
            with pytest.raises(TypeError, match="rtoll"):
                multibody.distributed.ensemble(client, stiff, [0.0, 0.1], params=params, rtoll=1e-4)
    assert spread.shape == local.shape == (n, 11, len(m.state_names("reduced")))
    assert np.array_equal(spread, local)
