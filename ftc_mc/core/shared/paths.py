"""Compile paths: which kernels a run reaches, told to Numba by types.

Numba types and compiles every branch a kernel can reach, whatever the values
of run-time flags.  A run of the paper's design on the linear plant would
therefore compile the dense and extended filters, the GLR test, the nonlinear
plant and the controller selection it never calls (``docs/findings/performance.md``,
lesson 11).  Instead, the choices that select large kernels travel as
*types*: a :class:`Path` of empty marker namedtuples, one per choice, passed
as the first argument of :func:`ftc_mc.core.longitudinal.trial.advance` and of the stages.
At each point where the paths part, a dispatcher (a stub with a typing
template and a lowering of its own, :func:`on_path`) looks at the marker's
type while the caller is being typed and calls one implementation, directly
(no wrapper function between) and by address (:mod:`ftc_mc.core.linking`: the
implementation is compiled once, on its own, and no caller keeps a copy of its
code); the others are never typed, lowered or optimised.  Each path is one signature of
``advance``, compiled on its first use and cached on disk like any other.

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
* ``control``: :data:`NOMINAL_CONTROL` (c0 throughout),
  :data:`RECONFIGURING` (the selection of eqs. 45-47 every period) or
  :data:`SELECT_FOUR` (6-DOF plant: the selection among the four 6-DOF
  controllers, :mod:`ftc_mc.core.sixdof.selection`, which the 6-DOF truth and
  monitor stages run: the paper's selection is not compiled).

Everything else (turbulence, sensor faults, the settling rule, sensor-bias
states) stays a run-time value: their code is small.  The path is computed
from the settings in one place, :func:`ftc_mc.sim.paths.path_of`.
"""

from __future__ import annotations

import importlib
from collections import namedtuple

from numba import types
from numba.core.imputils import lower_builtin
from numba.core.typing.templates import AbstractTemplate, infer_global, signature

from .. import linking

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
SelectFour = _marker("SelectFour")

LINEAR_PLANT, NONLINEAR_PLANT, SIXDOF_PLANT = LinearPlant(), NonlinearPlant(), SixdofPlant()
SIXDOF_EXTENDED_PLANT = SixdofExtendedPlant()
PAPER_FILTER, DENSE_FILTER, EXTENDED_FILTER = PaperFilter(), DenseFilter(), ExtendedFilter()
ONE_STEP_TEST, GLR_TEST = OneStepTest(), GlrTest()
NOMINAL_CONTROL, RECONFIGURING, SELECT_FOUR = NominalControl(), Reconfiguring(), SelectFour()

NAMES = {LinearPlant: "linear plant", NonlinearPlant: "nonlinear plant",
         SixdofPlant: "6-DOF plant",
         SixdofExtendedPlant: "6-DOF plant with the extended side monitor",
         PaperFilter: "paper filter", DenseFilter: "dense filter",
         ExtendedFilter: "extended filter", OneStepTest: "one-step test",
         GlrTest: "GLR test", NominalControl: "nominal controller",
         Reconfiguring: "reconfiguring controller",
         SelectFour: "selection among four controllers"}
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

    The choice is made while the caller is typed (a typing template and a
    lowering of the stub's own, :func:`_register_dispatch`), so the kernels
    of the other markers are never compiled.  The chosen kernels are
    ``@kernel`` functions of their own (cached on disk) that take no
    :class:`Path`: compiled once, whatever the path that calls them, and
    loaded from the cache by every later path.  The caller calls the chosen
    kernel by address (:mod:`ftc_mc.core.linking`: its code is not linked into
    the caller's); nothing is IR-inlined (Numba's typed inlining of overloads
    gave wrong results inside the trial loop: lanes read as out of the
    envelope at the first step; ``docs/findings/performance.md`` lesson 11).

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
        _register_dispatch(stub, field, table, passes)
        return stub
    return decorate


def _register_dispatch(stub, field: str, table: "_LazyTable", passes):
    """Type and lower ``stub(first, *rest)`` as a direct call of the chosen
    kernel (``on_path``), by address when it is a kernel
    (:func:`ftc_mc.core.linking.call`).

    The call is lowered in the caller itself: no function of its own sits
    between the caller and the kernel.  (A ``numba.extending.overload``
    returning ``lambda ...: impl(...)`` compiled that lambda as a library of
    its own, which linked, re-optimised and re-emitted a whole copy of the
    kernel it called: 20 of the default path's 120 s of cold compile,
    ``docs/findings/performance.md`` lesson 11.)
    """

    at = Path._fields.index(field)

    def lead_types(first) -> tuple:
        """The types of what the kernel gets before the stub's other
        arguments: the marker, the path, or nothing (``passes``)."""
        if passes is None:
            return ()
        if passes == "marker" and _is_path(first):
            return (first.types[at],)
        return (first,)

    def inner_signature(typing_context, args):
        """The chosen kernel's Numba type and its signature for ``args``
        (``None, None`` when the path has no kernel here)."""
        impl = table.get(_marker_class(args[0], field))
        if impl is None:
            return None, None
        inner = tuple(types.unliteral(a) for a in lead_types(args[0]) + tuple(args[1:]))
        # a kernel, or another dispatcher stub (``passes="path"``)
        fnty = typing_context.resolve_value_type(impl)
        return fnty, fnty.get_call_type(typing_context, inner, {})

    class _Typer(AbstractTemplate):
        key = stub

        def generic(self, args, kws):
            if kws:
                raise TypeError(f"{stub.__name__}: keyword arguments are not supported")
            impl, sig = inner_signature(self.context, args)
            return signature(types.none if impl is None else sig.return_type, *args)

    infer_global(stub, types.Function(_Typer))

    @lower_builtin(stub, types.VarArg(types.Any))
    def _lower(context, builder, sig, args):
        impl, inner = inner_signature(context.typing_context, sig.args)
        if impl is None:
            return context.get_dummy_value()
        first = sig.args[0]
        lead = lead_types(first)
        if passes == "marker" and _is_path(first):  # the marker, read from the path
            lead_values = [builder.extract_value(args[0], at)]
        else:
            lead_values = list(args[:len(lead)])
        values = [context.cast(builder, v, t, want) for v, t, want
                  in zip(lead_values + list(args[1:]), lead + sig.args[1:], inner.args)]
        if isinstance(impl, types.Dispatcher):  # a kernel: by address, not linked
            return linking.call(context, builder, impl.dispatcher, inner, values)
        return context.get_function(impl, inner)(builder, values)  # another stub


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
