"""How a kernel calls a trial stage: by address, not by linking its code.

Numba compiles every kernel as a code library of its own, and a kernel that
calls another links the callee's library into its own: the callee's code is
optimised and emitted again inside every caller, up the chain to
:func:`ftc_mc.core.longitudinal.trial.advance`.  For the default path that was
about 10 s of ``advance``'s 25 s of cold compile (``docs/findings/performance.md``,
lessons 14 and 15).

A call of a kernel declared ``kernel(by_address=True)`` (the trial's stage
kernels, :func:`route_calls`), or of one that
:func:`ftc_mc.core.shared.paths.on_path` dispatches to, is lowered instead as
a call of an external function with a stable symbol name
(:func:`symbol_name`: the kernel's module, name and a digest of its argument
types).  The stage is compiled (or loaded from the cache) once,
on its own, and its native entry point is registered under that name with
LLVM's symbol table (:func:`register`) before any caller is finalised, so the
caller keeps no copy of its code.  The calling convention is Numba's own, so
the stage's exceptions and return values pass as through a linked call, and
the machine code of the stage is the same: no result changes.

A caller loaded from the disk cache names symbols that this process may not
have registered yet; calling an unresolved one would jump to address 0.  So
the cached form of every kernel (:class:`ByAddressCacheImpl`) carries the
stages its code calls by address, and loading it registers them first,
compiling or loading each one, before its machine code is loaded.
"""

from __future__ import annotations

import copy
import hashlib
import importlib

import llvmlite.binding as ll
from numba.core import caching, cgutils, imputils

PREFIX = "ftcmc_stage."
"""The start of every symbol name a kernel calls by address."""

_STAGES: dict[str, tuple[str, str, tuple]] = {}
"""Symbol name -> (module, function name, argument types) of every stage
registered in this process."""

_ADDRESSES: dict[str, int] = {}
"""Symbol name -> the address registered for it in this process."""


def symbol_name(dispatcher, args) -> str:
    """The stable symbol of ``dispatcher``'s overload for the argument types
    ``args``: the same in every process and clone for the same kernel and
    types."""
    f = dispatcher.py_func
    digest = hashlib.sha256(str(tuple(args)).encode()).hexdigest()[:20]
    return f"{PREFIX}{f.__module__}.{f.__qualname__}.{digest}"


def register(dispatcher, args) -> str:
    """Compile (or load) ``dispatcher`` for ``args`` and register its native
    entry point under :func:`symbol_name`; return that name."""
    args = tuple(args)
    cres = dispatcher.overloads.get(args)
    if cres is None:
        dispatcher.compile(args)
        cres = dispatcher.overloads[args]
    name = symbol_name(dispatcher, args)
    address = cres.library.get_pointer_to_function(cres.fndesc.llvm_func_name)
    if not address:
        raise RuntimeError(f"no entry point for {name}")
    if _ADDRESSES.get(name) != address:
        ll.add_symbol(name, address)
        _ADDRESSES[name] = address
    f = dispatcher.py_func
    _STAGES[name] = (f.__module__, f.__qualname__, args)
    return name


def call(context, builder, dispatcher, sig, values):
    """Lower a call of ``dispatcher``'s overload for ``sig.args`` as a call by
    address (module docstring), as Numba lowers a call of a kernel it links
    (``numba.core.imputils.user_function``), but for the symbol."""
    name = register(dispatcher, sig.args)
    fndesc = copy.copy(dispatcher.overloads[tuple(sig.args)].fndesc)
    fndesc.mangled_name = name
    fn = context.declare_function(builder.module, fndesc)
    status, res = context.call_conv.call_function(builder, fn, fndesc.restype,
                                                  fndesc.argtypes, values)
    with cgutils.if_unlikely(builder, status.is_error):
        context.call_conv.return_status_propagate(builder, status)
    return imputils.fix_returning_optional(context, builder, sig, status, res)


def route_calls(dispatcher, cres) -> None:
    """Make every kernel that calls ``dispatcher``'s overload ``cres`` from
    now on call it by address instead of linking it: replace the lowering
    Numba registered for it (a call of its symbol with its library linked).
    For a kernel decorated ``kernel(internal=True, by_address=True)``."""
    def lower(context, builder, sig, args):
        return call(context, builder, dispatcher, cres.signature, args)
    lower.signature = cres.fndesc.argtypes
    lower.libs = ()
    context = dispatcher.targetctx
    context.remove_user_function(cres.entry_point)
    context._defns[cres.entry_point].append(lower, lower.signature)


def stages_called(library) -> tuple:
    """The stages a compiled library's code calls by address, as
    ``(module, name, argument types)`` (the callees it linked included)."""
    called = []
    for fn in library._final_module.functions:
        if fn.is_declaration and fn.name.startswith(PREFIX):
            called.append(_STAGES[fn.name])
    return tuple(sorted(called, key=str))


def register_all(stages) -> None:
    """Register every ``(module, name, argument types)`` of ``stages``."""
    for module, qualname, args in stages:
        register(getattr(importlib.import_module(module), qualname), args)


_TAG = "ftc-mc stages called by address"


class ByAddressCacheImpl(caching.FunctionCache._impl_class):
    """Numba's cache of compile results, whose saved form carries the stages
    the kernel calls by address (:func:`stages_called`); loading registers
    them before the kernel's machine code (module docstring)."""

    def reduce(self, cres):
        return (_TAG, stages_called(cres.library), super().reduce(cres))

    def rebuild(self, target_context, payload):
        tag, stages, inner = payload
        if tag != _TAG:
            raise ValueError("a kernel cache entry not written by this version")
        register_all(stages)
        return super().rebuild(target_context, inner)
