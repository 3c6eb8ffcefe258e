"""Numba kernels on float64 arrays: no I/O, no configuration objects, no pandas.

Settings enter as the namedtuples of :mod:`ftc_mc.core.longitudinal.settings`;
:mod:`ftc_mc.sim` builds them from a config.  The kernels are grouped by plant
family:

* :mod:`~ftc_mc.core.jit`: the one decorator, :func:`~ftc_mc.core.jit.kernel`,
  and the disk cache keyed on the content of the kernel sources (also of the
  kernels a clone's ``tests/`` and ``scripts/`` define,
  :class:`~ftc_mc.core.jit.CloneFolderLocator`).  A kernel that only other
  kernels call is ``kernel(internal=True)``, compiled without Numba's Python
  wrappers (a call from Python goes to a twin that has them;
  ``docs/findings/performance.md``, lesson 14);
* :mod:`~ftc_mc.core.linking`: how a kernel calls a stage, by address instead
  of linking the stage's code into the caller's (a stage is
  ``kernel(by_address=True)``, and so is every kernel a compile path's
  dispatcher chooses); a kernel's cache entry names the stages it calls, and
  loading it registers them first (lesson 17);
* :mod:`~ftc_mc.core.shared`: kernels of any family, shape-generic over
  states, outputs and lanes, and the compile paths
  (:mod:`~ftc_mc.core.shared.paths`: which kernels a run reaches, told to
  Numba by types);
* :mod:`~ftc_mc.core.longitudinal`: the paper's plant family, its filters,
  Table 1, controllers and the trial loop;
* :mod:`~ftc_mc.core.sixdof`: the 6-DOF family, imported only on the 6-DOF
  path.

A new kernel goes in its family's folder (``shared/`` if it is shape-generic),
decorated with :func:`~ftc_mc.core.jit.kernel` (``by_address=True`` for a stage
called once per step over all lanes; a helper called per lane stays linked, so
that LLVM can inline it), with a plain-NumPy twin in ``tests/naive.py`` (or
``tests/naive_sixdof.py``) and a test comparing them.  Nothing is registered by
hand: an edit of any kernel source starts a new cache folder, so a stale kernel
is never loaded, and another clone of the same sources loads instead of
compiling.
"""
