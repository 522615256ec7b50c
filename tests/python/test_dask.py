"""The Dask sweep of examples/python/dask_sweep.py: 100 parameter sets on a
LocalCluster of two worker processes equal the serial loop bit for bit."""

import importlib.util

import numpy as np

import paper
from conftest import ROOT


def load_example():
    spec = importlib.util.spec_from_file_location(
        "dask_sweep", ROOT / "examples/python/dask_sweep.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_dask_sweep_equals_the_serial_loop_bit_for_bit():
    from dask.distributed import Client, LocalCluster

    example = load_example()
    t = np.linspace(0.0, 5.0, 51)
    sets = [{"alpha": a, "M0": 1.0 + a} for a in np.linspace(0.0, 1.0, 100)]
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster:
        with Client(cluster) as client:
            swept = example.sweep(client, sets, t)
            # The work ran in the worker processes.
            workers = client.run(lambda: __import__("os").getpid())
            assert len(workers) == 2
    serial = [paper.Model(**p).solve(t=t) for p in sets]
    assert len(swept) == 100
    for a, b in zip(swept, serial):
        assert np.array_equal(a.t, b.t) and np.array_equal(a.y, b.y)
        assert a.stats["steps"] == b.stats["steps"]
