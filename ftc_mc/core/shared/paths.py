"""Compile paths: which kernels a run reaches, told to Numba by types.

Numba types and compiles every branch a kernel can reach, whatever the values
of run-time flags.  A run of the paper's design on the linear plant would
therefore compile the dense and extended filters, the GLR test, the nonlinear
plant and the controller selection it never calls (``docs/performance.md``,
lesson 10).  Instead, the choices that select large kernels travel as
*types*: a :class:`Path` of empty marker namedtuples, one per choice, passed
as the first argument of :func:`ftc_mc.core.longitudinal.trial.advance` and of the stages.
At each point where the paths part, a dispatcher (a stub with a
``numba.extending.overload``) looks at the marker's type while the caller is
being typed and hands over one implementation; the others are never typed,
lowered or optimised.  Each path is one signature of ``advance``, compiled on
its first use and cached on disk like any other.

The choices:

* ``plant``: :data:`LINEAR_PLANT` (eq. 1) or :data:`NONLINEAR_PLANT` (the
  airframe's equations, RK4);
* ``filter``: :data:`PAPER_FILTER` (the 14-state filter of eqs. 4-11, with
  the block structure of :mod:`ftc_mc.core.longitudinal.batch`), :data:`DENSE_FILTER`
  (the general filter with extra states, :mod:`ftc_mc.core.longitudinal.gustfilter`) or
  :data:`EXTENDED_FILTER` (the general filter whose prediction runs the
  airframe's equations);
* ``test``: :data:`ONE_STEP_TEST` (eqs. 9-11) or :data:`GLR_TEST`
  (:mod:`ftc_mc.core.shared.glr`);
* ``control``: :data:`NOMINAL_CONTROL` (c0 throughout) or
  :data:`RECONFIGURING` (the selection of eqs. 45-47 every period).

Everything else (turbulence, sensor faults, the settling rule, sensor-bias
states) stays a run-time value: their code is small.  The path is computed
from the settings in one place, :func:`ftc_mc.sim.paths.path_of`.
"""

from __future__ import annotations

import inspect
from collections import namedtuple

from numba import types
from numba.extending import overload

from ..jit import OPTIONS

_JIT_OPTIONS = {k: v for k, v in OPTIONS.items() if k != "cache"}
"""The kernels' options for the dispatchers' chosen calls (compiled into their
caller, which is cached)."""

Path = namedtuple("Path", ["plant", "filter", "test", "control"])
"""The compile path of a trial kernel call: one marker per choice (module
docstring)."""



def _marker(name: str):
    """An empty namedtuple class: a distinct Numba type.  Its instances are
    equal only to instances of the same class (empty tuples would all be
    equal, and a dict or set keyed on markers would merge them)."""
    cls = namedtuple(name, [], module=__name__)
    cls.__eq__ = lambda a, b: type(a) is type(b)
    cls.__ne__ = lambda a, b: type(a) is not type(b)
    cls.__hash__ = lambda a: hash(type(a).__name__)
    return cls


LinearPlant = _marker("LinearPlant")
NonlinearPlant = _marker("NonlinearPlant")
PaperFilter = _marker("PaperFilter")
DenseFilter = _marker("DenseFilter")
ExtendedFilter = _marker("ExtendedFilter")
OneStepTest = _marker("OneStepTest")
GlrTest = _marker("GlrTest")
NominalControl = _marker("NominalControl")
Reconfiguring = _marker("Reconfiguring")

LINEAR_PLANT, NONLINEAR_PLANT = LinearPlant(), NonlinearPlant()
PAPER_FILTER, DENSE_FILTER, EXTENDED_FILTER = PaperFilter(), DenseFilter(), ExtendedFilter()
ONE_STEP_TEST, GLR_TEST = OneStepTest(), GlrTest()
NOMINAL_CONTROL, RECONFIGURING = NominalControl(), Reconfiguring()

NAMES = {LinearPlant: "linear plant", NonlinearPlant: "nonlinear plant",
         PaperFilter: "paper filter", DenseFilter: "dense filter",
         ExtendedFilter: "extended filter", OneStepTest: "one-step test",
         GlrTest: "GLR test", NominalControl: "nominal controller",
         Reconfiguring: "reconfiguring controller"}
"""What the compile notice calls each marker."""


def describe(path: Path) -> str:
    """The path in words, e.g. ``linear plant, paper filter, one-step test,
    reconfiguring controller``."""
    return ", ".join(NAMES[type(m)] for m in path)


def _marker_class(path_type, field: str):
    if not (isinstance(path_type, types.BaseNamedTuple)
            and path_type.instance_class is Path):
        raise TypeError(f"expected a core.shared.paths.Path, got {path_type}")
    t = path_type.types[Path._fields.index(field)]
    return t.instance_class if isinstance(t, types.BaseNamedTuple) else None


def takes(path_type, field: str, marker) -> bool:
    """Whether the Numba type of a :class:`Path` holds ``marker``'s class in
    ``field`` (read while a dispatcher's caller is typed).

    Parameters
    ----------
    path_type : numba.types.NamedTuple
        The type Numba gives a :class:`Path`.
    field : str
        ``"plant"``, ``"filter"``, ``"test"`` or ``"control"``.
    marker : namedtuple instance
        One of the module's markers (e.g. :data:`PAPER_FILTER`).
    """
    return _marker_class(path_type, field) is type(marker)


def on_path(field: str, impls: dict, with_path: bool = False):
    """Make a stub a dispatcher on ``path.<field>``.

    The decorated function is a stub whose first parameter is the
    :class:`Path`; a call ``stub(path, a, b)`` in a kernel compiles as
    ``impls[marker](a, b)`` (``impls[marker](path, a, b)`` with ``with_path``)
    for the marker ``path.<field>`` holds, or as nothing (``None``) when
    ``impls`` has no entry for it.  The choice is made while
    the caller is typed (a ``numba.extending.overload``, IR-inlined), so the
    kernels of the other markers are never compiled.

    Parameters
    ----------
    field : str
        ``"plant"``, ``"filter"``, ``"test"`` or ``"control"``.
    impls : dict
        Marker (e.g. :data:`PAPER_FILTER`) -> kernel taking the stub's
        parameters after ``path`` (or another dispatcher).
    with_path : bool
        Pass ``path`` on as the first argument (to kernels that dispatch
        further).
    """
    table = {type(m): f for m, f in impls.items()}

    def decorate(stub):
        params = list(inspect.signature(stub).parameters)
        arglist = ", ".join(params)
        inner = ", ".join(params if with_path else params[1:])
        # the overload must take the stub's own parameter names: written out
        src = (f"def overload_of({arglist}):\n"
               f"    impl = table.get(_marker_class({params[0]}, field))\n"
               f"    if impl is None:\n"
               f"        return lambda {arglist}: None\n"
               f"    return lambda {arglist}: impl({inner})\n")
        scope = {"table": table, "_marker_class": _marker_class, "field": field}
        exec(src, scope)  # noqa: S102 -- source built above from the stub's names
        overload(stub, jit_options=_JIT_OPTIONS)(scope["overload_of"])
        return stub
    return decorate
