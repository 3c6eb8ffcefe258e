"""The on-disk cache of offline computations, kept apart so that synthesis stays pure.

``design/`` and ``model/`` compute; this package keys their results by every
input (SHA-256, :func:`~ftc_mc.cache.store.design_key`), reads them back and
writes them atomically under ``~/.cache/ftc-mc/design`` (or
``$FTC_MC_CACHE_DIR/design``):

* :mod:`~ftc_mc.cache.store`: the folder, the key, the atomic write;
* :mod:`~ftc_mc.cache.engine_tables`: the Theorem 4.1 engine-fault tables
  (``engine_tables/``);
* :mod:`~ftc_mc.cache.lock_turn`: the lock-turn controllers' table over lock
  offsets (``lock_turn/``);
* :mod:`~ftc_mc.cache.trimmable`: the trimmable set of an airframe's
  equations (``trimmable/``).

A file of another key, or unreadable, is recomputed and replaced; a cache that
cannot be written costs only time.  The compiled numba kernels have their own
cache (:mod:`ftc_mc.core.jit`).
"""
