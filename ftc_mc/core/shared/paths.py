"""Compile paths: which kernels a run reaches, told to Numba by types.

Numba types and compiles every branch a kernel can reach, whatever the values
of run-time flags.  A run of the paper's design on the linear plant would
therefore compile the dense and extended filters, the GLR test, the nonlinear
plant and the controller selection it never calls (``docs/performance.md``,
lesson 11).  Instead, the choices that select large kernels travel as
*types*: a :class:`Path` of empty marker namedtuples, one per choice, passed
as the first argument of :func:`ftc_mc.core.longitudinal.trial.advance` and of the stages.
At each point where the paths part, a dispatcher (a stub with a
``numba.extending.overload``) looks at the marker's type while the caller is
being typed and hands over one implementation; the others are never typed,
lowered or optimised.  Each path is one signature of ``advance``, compiled on
its first use and cached on disk like any other.

The choices:

* ``plant``: :data:`LINEAR_PLANT` (eq. 1), :data:`NONLINEAR_PLANT` (the
  airframe's equations, RK4) or :data:`SIXDOF_PLANT` (the 6-DOF family's
  truth, :mod:`ftc_mc.core.sixdof.truth`, named by its import path so that a
  longitudinal path never imports it), or :data:`SIXDOF_EXTENDED_PLANT` (the
  same, its side monitor the extended filter,
  :func:`ftc_mc.core.sixdof.monitor.sixdof_monitor_extended`, which the other
  6-DOF path never compiles);
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

import importlib
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
SixdofPlant = _marker("SixdofPlant")
SixdofExtendedPlant = _marker("SixdofExtendedPlant")
PaperFilter = _marker("PaperFilter")
DenseFilter = _marker("DenseFilter")
ExtendedFilter = _marker("ExtendedFilter")
OneStepTest = _marker("OneStepTest")
GlrTest = _marker("GlrTest")
NominalControl = _marker("NominalControl")
Reconfiguring = _marker("Reconfiguring")

LINEAR_PLANT, NONLINEAR_PLANT, SIXDOF_PLANT = LinearPlant(), NonlinearPlant(), SixdofPlant()
SIXDOF_EXTENDED_PLANT = SixdofExtendedPlant()
PAPER_FILTER, DENSE_FILTER, EXTENDED_FILTER = PaperFilter(), DenseFilter(), ExtendedFilter()
ONE_STEP_TEST, GLR_TEST = OneStepTest(), GlrTest()
NOMINAL_CONTROL, RECONFIGURING = NominalControl(), Reconfiguring()

NAMES = {LinearPlant: "linear plant", NonlinearPlant: "nonlinear plant",
         SixdofPlant: "6-DOF plant",
         SixdofExtendedPlant: "6-DOF plant with the extended side monitor",
         PaperFilter: "paper filter", DenseFilter: "dense filter",
         ExtendedFilter: "extended filter", OneStepTest: "one-step test",
         GlrTest: "GLR test", NominalControl: "nominal controller",
         Reconfiguring: "reconfiguring controller"}
"""What the compile notice calls each marker."""


def describe(path: Path) -> str:
    """The path in words, e.g. ``linear plant, paper filter, one-step test,
    reconfiguring controller``."""
    return ", ".join(NAMES[type(m)] for m in path)


def _marker_class(arg_type, field: str):
    """The marker class a dispatcher's first argument names for ``field``: read
    from a :class:`Path`, or the argument is that marker itself."""
    if isinstance(arg_type, types.BaseNamedTuple) and arg_type.instance_class is Path:
        arg_type = arg_type.types[Path._fields.index(field)]
    if not (isinstance(arg_type, types.BaseNamedTuple) and not arg_type.types
            and arg_type.instance_class in NAMES):
        raise TypeError(f"expected a core.shared.paths.Path or marker, got {arg_type}")
    return arg_type.instance_class


def takes(path_type, field: str, marker) -> bool:
    """Whether the Numba type of a :class:`Path` (or of a marker) holds
    ``marker``'s class in ``field`` (read while a dispatcher's caller is typed).

    Parameters
    ----------
    path_type : numba.types.NamedTuple
        The type Numba gives a :class:`Path` or a marker.
    field : str
        ``"plant"``, ``"filter"``, ``"test"`` or ``"control"``.
    marker : namedtuple instance
        One of the module's markers (e.g. :data:`PAPER_FILTER`).
    """
    return _marker_class(path_type, field) is type(marker)


def on_path(field: str, impls: dict, passes: str | None = None):
    """Make a stub a dispatcher on the ``field`` marker of its first argument.

    The decorated function is a stub whose first parameter is a :class:`Path`
    or a marker; a call ``stub(path, a, b)`` in a kernel compiles as
    ``impls[marker](a, b)`` for the marker ``path.<field>`` (or ``path``)
    holds, or as nothing (``None``) when ``impls`` has no entry for it.  With
    ``passes="marker"`` the kernel gets that marker first
    (``impls[marker](path.<field>, a, b)``: a kernel that dispatches further on
    the same choice); with ``passes="path"``, the first argument as it is
    (another dispatcher).

    The choice is made while the caller is typed (a
    ``numba.extending.overload``), so the kernels of the other markers are
    never compiled.  The chosen kernels are ``@kernel`` functions of their own
    (cached on disk) that take no :class:`Path`: compiled once, whatever the
    path that calls them, and loaded from the cache by every later path.  The
    call between is a small function of its own, not inlined into the
    caller's IR: Numba's typed inlining of overloads gave wrong results inside
    the trial loop (lanes read as out of the envelope at the first step;
    ``docs/performance.md`` lesson 11).

    Parameters
    ----------
    field : str
        ``"plant"``, ``"filter"``, ``"test"`` or ``"control"``.
    impls : dict
        Marker (e.g. :data:`PAPER_FILTER`) -> kernel taking the stub's
        parameters after the first, or its import path ``"module:name"``
        (imported only when a path takes it: another family's kernel).
    passes : {None, "marker", "path"}
        What the kernel gets first, if anything.
    """
    assert passes in (None, "marker", "path"), passes
    table = _LazyTable({type(m): f for m, f in impls.items()})

    def decorate(stub):
        params = list(inspect.signature(stub).parameters)
        first, rest = params[0], ", ".join(params[1:])
        arglist = ", ".join(params)
        lead = {None: "", "path": f"{first}, ",
                "marker": f"{first}.{field}, "}[passes]
        # the overload must take the stub's own parameter names: written out
        src = (f"def overload_of({arglist}):\n"
               f"    impl = table.get(_marker_class({first}, field))\n"
               f"    if impl is None:\n"
               f"        return lambda {arglist}: None\n"
               f"    if passes == 'marker' and not _is_path({first}):\n"
               f"        return lambda {arglist}: impl({first}, {rest})\n"
               f"    return lambda {arglist}: impl({lead}{rest})\n")
        scope = {"table": table, "_marker_class": _marker_class, "field": field,
                 "passes": passes, "_is_path": _is_path}
        exec(src, scope)  # noqa: S102 -- source built above from the stub's names
        overload(stub, jit_options=_JIT_OPTIONS)(scope["overload_of"])
        return stub
    return decorate


class _LazyTable(dict):
    """Marker class -> kernel, importing a kernel given as ``"module:name"``
    the first time it is asked for."""

    def get(self, key, default=None):
        impl = super().get(key, default)
        if isinstance(impl, str):
            module, _, name = impl.partition(":")
            impl = getattr(importlib.import_module(module), name)
            self[key] = impl
        return impl


def _is_path(arg_type) -> bool:
    return isinstance(arg_type, types.BaseNamedTuple) and arg_type.instance_class is Path
