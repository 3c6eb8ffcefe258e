"""Where chunks run: worker threads here, local worker processes (joblib/loky) or a
Dask cluster.

:func:`run_chunks` is the parent side of ``ftc-mc run`` and ``ftc-mc sweep``:
it sends every chunk not yet finished to :func:`ftc_mc.campaign.chunk.run_chunk`,
stores each as it completes, and returns them all.  The same chunk function
runs either way, and results do not depend on where they ran.  ``threads`` (the
default) runs chunks on joblib's threading backend in this process: the kernels
release the GIL (``nogil``), so the threads share one core each, with no worker
start-up, no second load of the kernels and no results pickled back
(``docs/performance.md``, lesson 5).  ``loky`` runs worker processes.  With
``backend="dask"`` the chunks go through joblib's Dask backend to a
``distributed`` cluster: the one at ``scheduler`` (e.g.
``tcp://10.0.0.5:8786``), or a local cluster of single-threaded worker
processes when no address is given.  Kernels are compiled (and cached on disk)
in the parent before fanning out; Dask workers on other machines compile their
own copy once.
"""

from __future__ import annotations

import contextlib

from joblib import Parallel, delayed, parallel_config
from tqdm.auto import tqdm

from ..errors import UserError
from .chunk import ChunkSpec, run_chunk, warm_up

BACKENDS = ("threads", "loky", "dask")


@contextlib.contextmanager
def backend(name: str = "threads", scheduler: str | None = None, n_workers: int = 2):
    """Route joblib's ``Parallel`` to the chosen backend inside the block.

    Parameters
    ----------
    name : {"threads", "loky", "dask"}
    scheduler : str, optional
        Address of a running Dask scheduler (dask only).
    n_workers : int
        Workers of the local Dask cluster started when ``scheduler`` is None.

    Raises
    ------
    UserError
        Unknown backend, Dask not installed, or the scheduler unreachable.
    """
    if name not in BACKENDS:
        raise UserError(f"--backend: must be one of {', '.join(BACKENDS)}, got {name!r}")
    if name in ("threads", "loky"):
        if scheduler is not None:
            raise UserError("--scheduler: only with --backend dask")
        with parallel_config(backend="threading" if name == "threads" else "loky"):
            yield
        return
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise UserError("--backend dask: install the optional extra, "
                        "pip install 'ftc-mc[dask]'") from None
    cluster = None
    try:
        if scheduler is None:
            cluster = LocalCluster(n_workers=max(1, n_workers), threads_per_worker=1,
                                   processes=True, dashboard_address=":0")
            client = Client(cluster)
        else:
            client = Client(scheduler, timeout=30)
    except OSError as exc:
        raise UserError(f"--scheduler: cannot reach {scheduler!r} ({exc})") from None
    try:
        with parallel_config(backend="dask"):
            yield
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def run_chunks(spec: ChunkSpec, units, *, n_jobs: int = 1, backend_name: str = "threads",
               scheduler: str | None = None, progress: bool = True, chunks=None,
               desc: str = "trials") -> list:
    """Run every chunk of a run or sweep; return their tables in the order of ``units``.

    Parameters
    ----------
    spec : ChunkSpec
    units : list of (str, ndarray)
        ``(name, trial_ids)`` of every chunk (a transition or ``FLIGHT``).
    n_jobs : int
        Workers (1: in this process).
    backend_name, scheduler
        Where chunks run (:func:`backend`).
    progress : bool
        Show a tqdm bar counting finished trials.
    chunks : ChunkStore, optional
        Where finished chunks are stored as they complete; chunks already in it
        are not run again (resume).  The tables are then read back from the
        store, so they are the same whether or not the run was resumed.
    desc : str
        Label of the progress bar.

    Returns
    -------
    list of dict of str to DataFrame
        :func:`~ftc_mc.campaign.chunk.run_chunk`'s tables of each unit.
    """
    tables = spec.tables
    todo = [(n, ids) for n, ids in units if chunks is None or not chunks.done(n, int(ids[0]))]
    if todo:
        warm_up(spec, units[0][0])
    done = {}
    total = sum(len(ids) for _, ids in units)
    with tqdm(total=total, unit="trial", disable=not progress, desc=desc,
              dynamic_ncols=True) as bar:
        bar.update(total - sum(len(ids) for _, ids in todo))
        with backend(backend_name, scheduler, n_jobs):
            gen = Parallel(n_jobs=n_jobs, return_as="generator")(
                delayed(run_chunk)(spec, name, ids) for name, ids in todo)
            for (name, ids), out in zip(todo, gen):
                if chunks is not None:
                    chunks.write(name, int(ids[0]), out[tables[0]],
                                 **{t: out[t] for t in tables[1:]})
                else:
                    done[name, int(ids[0])] = out
                bar.update(len(ids))
    if chunks is not None:
        done = {(n, int(ids[0])): dict(zip(tables, chunks.read(n, int(ids[0]), tables)))
                for n, ids in units}
    return [done[n, int(ids[0])] for n, ids in units]
