"""Where chunks run: local worker processes (joblib/loky) or a Dask cluster.

The same chunk functions run either way, and results do not depend on where
they ran.  With ``backend="dask"`` the chunks go through joblib's Dask backend
to a ``distributed`` cluster: the one at ``scheduler`` (e.g.
``tcp://10.0.0.5:8786``), or a local cluster of single-threaded worker
processes when no address is given.  Kernels are compiled (and cached on disk)
in the parent before fanning out; Dask workers on other machines compile their
own copy once.
"""

from __future__ import annotations

import contextlib

from joblib import parallel_config

from ..errors import UserError

BACKENDS = ("loky", "dask")


@contextlib.contextmanager
def backend(name: str = "loky", scheduler: str | None = None, n_workers: int = 2):
    """Route joblib's ``Parallel`` to the chosen backend inside the block.

    Parameters
    ----------
    name : {"loky", "dask"}
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
    if name == "loky":
        if scheduler is not None:
            raise UserError("--scheduler: only with --backend dask")
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
