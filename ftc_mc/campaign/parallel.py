"""Where chunks run: worker threads here, local worker processes (loky) or a Dask
cluster; and a parent that stays responsive while they run.

:func:`run_chunks` is the parent side of ``ftc-mc run`` and ``ftc-mc sweep``:
it sends every chunk not yet finished to :func:`ftc_mc.campaign.chunk.run_chunk`
and stores each as it completes (or keeps it, without a chunk store).  The same
chunk function runs everywhere, and results do not depend on where they ran.

* ``threads`` (the default) runs chunks on worker threads of this process: the
  kernels release the GIL (``nogil``), so the threads share one core each, with
  no worker start-up, no second load of the kernels and no results pickled
  back (``docs/findings/performance.md``, lesson 5).  Even ``jobs=1`` runs its chunks on
  one worker thread, so that the main thread is free to react to Ctrl-C.
* ``loky`` runs worker processes (``joblib.externals.loky``); the chunk spec is
  sent to each worker once, when it starts.  With one worker it runs on one
  thread here instead (same results, no process start).
* ``dask`` sends the chunks to a ``distributed`` cluster: the one at
  ``scheduler`` (e.g. ``tcp://10.0.0.5:8786``), or a local cluster of
  single-threaded worker processes when no address is given; the chunk spec
  is scattered to every worker once.

Kernels are compiled (and cached on disk) in the parent before fanning out;
Dask workers on other machines compile their own copy once.

The main thread only submits chunks and waits for the next one with a short
timeout; one writer thread stores the finished ones in the chunk store (one at
a time, in whatever order they finish: each chunk has its own files, and the
results are assembled in chunk order later), so not even a slow disk (a
``fsync``) delays the main thread.  At most two chunks per worker are in flight,
and at most as many wait to be written, so the parent holds at most that many
chunk results.  An interrupt (:mod:`ftc_mc.interrupt`) is therefore handled at
once: chunks already stored stay, chunks in flight are dropped (a chunk's files
are written atomically and its trials file last, so a chunk is whole or not
counted, even when the process ends during its write), the workers are told
to stop (worker processes are killed), and the interrupt goes up to the
command.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import gc
import os
import queue
import signal
import threading

from tqdm.auto import tqdm

from ..errors import UserError
from .chunk import ChunkSpec, run_chunk, warm_up

BACKENDS = ("threads", "loky", "dask")

WAIT_S = 0.2
"""Longest wait of the main thread between two looks at its workers [s]."""


class _Threads:
    """Daemon worker threads taking chunks from a queue.

    Daemon threads, because a worker inside a Numba kernel cannot be stopped:
    after an interrupt the process ends without waiting for them.
    """

    def __init__(self, spec: ChunkSpec, n: int):
        self.spec = spec
        self.queue = queue.SimpleQueue()
        self.stopping = False
        for i in range(n):
            threading.Thread(target=self._work, name=f"ftc-mc-chunk-{i}", daemon=True).start()
        self.n = n

    def _work(self):
        while True:
            item = self.queue.get()
            if item is None or self.stopping:
                return
            fut, name, ids = item
            if not fut.set_running_or_notify_cancel():
                continue
            try:
                fut.set_result(run_chunk(self.spec, name, ids))
            except BaseException as exc:  # noqa: BLE001 -- handed to the main thread
                fut.set_exception(exc)

    def submit(self, name, ids) -> cf.Future:
        fut = cf.Future()
        self.queue.put((fut, name, ids))
        return fut

    def close(self, abort: bool):
        self.stopping = abort
        for _ in range(self.n):
            self.queue.put(None)


_WORKER_SPEC = None


def _set_spec(spec):
    """Loky worker initializer: keep the run's chunk spec."""
    global _WORKER_SPEC
    _WORKER_SPEC = spec


def _run_in_worker(name, ids):
    """A chunk in a loky worker, with the spec it received when it started."""
    return run_chunk(_WORKER_SPEC, name, ids)


class _Loky:
    """A fresh loky process pool; its workers get the spec once, when they start."""

    def __init__(self, spec: ChunkSpec, n: int):
        from joblib.externals.loky import ProcessPoolExecutor

        self.pool = ProcessPoolExecutor(max_workers=n, initializer=_set_spec,
                                        initargs=(spec,))

    def submit(self, name, ids) -> cf.Future:
        return self.pool.submit(_run_in_worker, name, ids)

    def close(self, abort: bool):
        if not abort:
            self.pool.shutdown(wait=True)
            return
        # loky would kill its workers from its manager thread, after the chunks
        # they run: they are killed here, then the pool is shut down, and the
        # finalizers that release its semaphores run now (the process ends with
        # os._exit, which skips them: loky's resource tracker would warn)
        import multiprocessing

        from joblib.externals.loky.backend.process import LokyProcess
        workers = {p.pid: p for p in multiprocessing.active_children()
                   if isinstance(p, LokyProcess)}  # also those starting
        workers.update({p.pid: p for p in getattr(self.pool, "_processes", {}).values()})
        for w in workers.values():
            with contextlib.suppress(OSError, TypeError):
                os.kill(w.pid, signal.SIGKILL)
        for w in workers.values():
            with contextlib.suppress(Exception):
                w.join(timeout=1.0)
        manager = getattr(self.pool, "_executor_manager_thread", None)
        self.pool.shutdown(wait=False, kill_workers=True)
        if manager is not None:
            manager.join(timeout=1.0)  # bounded: an interrupt never hangs here
        self.pool = None
        _release_semaphores()


class _Dask:
    """A ``distributed`` client (a local cluster when no scheduler is given)."""

    def __init__(self, spec: ChunkSpec, n: int, scheduler: str | None):
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:
            raise UserError("--backend dask: install the optional extra, "
                            "pip install 'ftc-mc[dask]'") from None
        self.cluster = None
        try:
            if scheduler is None:
                self.cluster = LocalCluster(n_workers=max(1, n), threads_per_worker=1,
                                            processes=True, dashboard_address=":0")
                self.client = Client(self.cluster)
            else:
                self.client = Client(scheduler, timeout=30)
        except OSError as exc:
            if self.cluster is not None:
                self.cluster.close()
            raise UserError(f"--scheduler: cannot reach {scheduler!r} ({exc})") from None
        self.spec = self.client.scatter(spec, broadcast=True)
        self.futures = []

    def submit(self, name, ids) -> cf.Future:
        out = cf.Future()
        out.set_running_or_notify_cancel()
        fut = self.client.submit(run_chunk, self.spec, name, ids, pure=False)
        self.futures.append(fut)

        def relay(f):
            try:
                out.set_result(f.result())
            except BaseException as exc:  # noqa: BLE001 -- handed to the main thread
                if not out.done():
                    out.set_exception(exc)
        fut.add_done_callback(relay)
        return out

    def close(self, abort: bool):
        if not abort:
            self.client.close()
            if self.cluster is not None:
                self.cluster.close()
            return
        # an interrupt: the chunks in flight are dropped, not waited for
        import logging
        logging.getLogger("distributed").setLevel(logging.CRITICAL)  # lost workers
        with contextlib.suppress(Exception):
            self.client.cancel(self.futures, force=True)
        if self.cluster is not None:
            # the local cluster's worker processes are killed (a graceful close
            # waits for the chunks they run), their nannies told not to restart them
            from distributed.core import Status
            pids = []
            for nanny in self.cluster.workers.values():
                nanny.status = Status.closing
                with contextlib.suppress(AttributeError):
                    pids.append(nanny.process.process.pid)
            for pid in pids:
                with contextlib.suppress(OSError, TypeError):
                    os.kill(pid, signal.SIGKILL)
        _release_semaphores()

        def close_quietly():  # may take seconds; the process does not wait for it
            with contextlib.suppress(Exception):
                self.client.close(timeout=5)
                if self.cluster is not None:
                    self.cluster.close(timeout=5)
        threading.Thread(target=close_quietly, daemon=True).start()


def _release_semaphores():
    """Run the multiprocessing finalizers that release semaphores now: after an
    interrupt the process ends with ``os._exit``, which skips them, and the
    resource tracker would warn about them."""
    from multiprocessing import util
    gc.collect()
    with contextlib.suppress(Exception):
        util._run_finalizers(0)


def check_backend(name: str, scheduler: str | None) -> None:
    """Refuse an unknown backend, or a scheduler address without ``dask``.

    Raises
    ------
    UserError
    """
    if name not in BACKENDS:
        raise UserError(f"--backend: must be one of {', '.join(BACKENDS)}, got {name!r}")
    if name != "dask" and scheduler is not None:
        raise UserError("--scheduler: only with --backend dask")


def _executor(name: str, spec: ChunkSpec, n_jobs: int, scheduler: str | None):
    """The worker pool of backend ``name``.

    Raises
    ------
    UserError
        Unknown backend, a scheduler without Dask, Dask not installed, or the
        scheduler unreachable.
    """
    check_backend(name, scheduler)
    if name == "threads" or (name == "loky" and n_jobs == 1):  # one worker: no process
        return _Threads(spec, n_jobs)
    if name == "loky":
        return _Loky(spec, n_jobs)
    return _Dask(spec, n_jobs, scheduler)


def run_chunks(spec: ChunkSpec, units, *, n_jobs: int = 1, backend_name: str = "threads",
               scheduler: str | None = None, progress: bool = True, chunks=None,
               desc: str = "trials"):
    """Run every chunk of a run or sweep not yet in ``chunks``.

    Parameters
    ----------
    spec : ChunkSpec
    units : list of (str, ndarray)
        ``(name, trial_ids)`` of every chunk (a transition or ``FLIGHT``).
    n_jobs : int
        Workers.
    backend_name, scheduler
        Where chunks run (``threads``, ``loky`` or ``dask``; a Dask scheduler
        address or None for a local cluster).
    progress : bool
        Show a tqdm bar counting finished trials.
    chunks : ChunkStore, optional
        Where each chunk is stored as it completes; chunks already in it are not
        run again (resume).  The caller then reads them back from the store one
        at a time (:mod:`ftc_mc.campaign.assemble`).
    desc : str
        Label of the progress bar.

    Returns
    -------
    list of dict of str to DataFrame, or None
        Without ``chunks``: :func:`~ftc_mc.campaign.chunk.run_chunk`'s tables of
        each unit, in the order of ``units``.  With ``chunks``: None.

    Raises
    ------
    KeyboardInterrupt
        (:class:`ftc_mc.interrupt.Interrupted` for SIGINT/SIGTERM under
        :func:`ftc_mc.interrupt.stop_on_signals`): the chunks stored so far stay;
        the workers are stopped without waiting for the chunks in flight.
    """
    tables = spec.tables
    finished = chunks.finished() if chunks is not None else set()
    todo = [(n, ids) for n, ids in units if (n, int(ids[0])) not in finished]
    check_backend(backend_name, scheduler)
    if todo:
        warm_up(spec, units[0][0])
    done = {}
    total = sum(len(ids) for _, ids in units)
    with tqdm(total=total, unit="trial", disable=not progress, desc=desc,
              dynamic_ncols=True) as bar:
        bar.update(total - sum(len(ids) for _, ids in todo))
        if todo:
            pool = _executor(backend_name, spec, max(1, n_jobs), scheduler)
            writer = cf.ThreadPoolExecutor(1, thread_name_prefix="ftc-mc-write")
            aborted = True
            pending, writing = {}, {}
            try:
                queued = iter(todo)
                depth = 2 * max(1, n_jobs)

                def refill():
                    while len(pending) < depth and len(writing) < depth:
                        nxt = next(queued, None)
                        if nxt is None:
                            return
                        pending[pool.submit(*nxt)] = nxt

                refill()
                while pending or writing:
                    ready, _ = cf.wait([*pending, *writing], timeout=WAIT_S,
                                       return_when=cf.FIRST_COMPLETED)
                    for fut in ready:
                        if fut in writing:
                            fut.result()  # a write that failed stops the run
                            bar.update(len(writing.pop(fut)[1]))
                            continue
                        name, ids = pending.pop(fut)
                        out = fut.result()
                        if chunks is not None:
                            writing[writer.submit(chunks.write, name, int(ids[0]),
                                                  out[tables[0]],
                                                  **{t: out[t] for t in tables[1:]})] = (
                                name, ids)
                        else:
                            done[name, int(ids[0])] = out
                            bar.update(len(ids))
                        del out
                    refill()
                aborted = False
            finally:
                # the write under way is finished (a chunk's tables, tens of
                # ms), the queued ones are dropped: the interrupt's message then
                # counts the chunks that stay (it counted one too few when a
                # write ended between its count and the exit); an error
                # waits too, so that the caller finds the store as it stays
                writer.shutdown(wait=True, cancel_futures=aborted)
                if aborted:
                    for fut in pending:
                        fut.cancel()
                    with contextlib.suppress(Exception):  # the interrupt goes on up
                        pool.close(abort=True)
                else:
                    pool.close(abort=False)
    if chunks is not None:
        return None
    return [done[n, int(ids[0])] for n, ids in units]
