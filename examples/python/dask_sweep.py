"""A parameter sweep of a lagc model on Dask.

Build and install the model's module first (README, "From Python"):

    lagc build examples/paper.lag --python -o build/paper
    pip install build/paper "dask[distributed]"

then `python examples/python/dask_sweep.py`. The sweep runs on a
`LocalCluster` of two worker processes here; on a real cluster, pass the
scheduler's address to `Client` instead: the code is the same. Each task
builds `paper.Model(**params)` and solves it in a worker; the Solutions come
back pickled. A sweep on one machine is faster with `Model.solve_batch`
(threads, no pickling); Dask is for sweeps beyond one machine.
"""

import numpy as np

import paper


def solve(params, t):
    """One member of the sweep: the model with `params`, solved at `t`."""
    return paper.Model(**params).solve(t=t)


def sweep(client, sets, t):
    """Every set of `sets` solved on the cluster of `client`, in order."""
    futures = client.map(solve, sets, t=t, pure=False)
    return client.gather(futures)


def main():
    from dask.distributed import Client, LocalCluster

    t = np.linspace(0.0, 5.0, 51)
    sets = [{"alpha": a} for a in np.linspace(0.0, 1.0, 100)]
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True) as cluster:
        with Client(cluster) as client:
            solutions = sweep(client, sets, t)
    final = [s["q1'"][-1] for s in solutions]
    print(f"{len(solutions)} solutions; q1'(5) from {min(final):.6g} to {max(final):.6g}")


if __name__ == "__main__":
    main()
