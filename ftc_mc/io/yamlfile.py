"""Reading a YAML file safely: parsed data, or one :class:`~ftc_mc.errors.UserError` line.

PyYAML's safe loader only, so no tag can construct a Python object.  Shared by
configs (:mod:`ftc_mc.config.load`) and airframe files
(:mod:`ftc_mc.model.airframe_files`); the line names the file and the problem.

The loader is :data:`SAFE_LOADER`: PyYAML's libyaml-backed ``CSafeLoader``
where PyYAML was built with libyaml (its wheels are), else the pure-Python
``SafeLoader``.  Both construct with ``SafeConstructor``, so they return the
same data; the C scanner and parser read the shipped configs 15 times faster
(329 ms -> 22 ms for the 19 of them; the test suite spent 27 s of 380 in the
pure-Python scanner, measured), and
refuse nesting deeper than libyaml's limit (1000 levels) with a scanner error
where the Python parser recursed until ``RecursionError``.
"""

from __future__ import annotations

import reprlib
from pathlib import Path

import yaml

from ..errors import UserError

SAFE_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
"""The safe loader :func:`read_yaml` parses with (module docstring)."""

_REPR = reprlib.Repr()
_REPR.maxstring = _REPR.maxother = 80
_REPR.maxlevel = 2


def read_yaml(path):
    """Parsed YAML of a file (safe loader), or :class:`UserError`."""
    path = Path(path)
    try:
        exists, is_file = path.exists(), path.is_file()
    except OSError as exc:
        raise UserError(f"{path}: cannot read ({exc.strerror})") from None
    if not exists:
        raise UserError(f"{path}: no such file")
    if not is_file:
        raise UserError(f"{path}: not a regular file")
    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as exc:
        raise UserError(f"{path}: not UTF-8 text (byte {exc.start})") from None
    except OSError as exc:
        raise UserError(f"{path}: cannot read ({exc.strerror})") from None
    try:
        return yaml.load(text, Loader=SAFE_LOADER)  # noqa: S506 (a safe loader)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise UserError(f"{path}: malformed YAML{where}: {problem}") from None
    except RecursionError:
        raise UserError(f"{path}: malformed YAML: nested too deeply") from None
    except Exception as exc:  # PyYAML's constructors raise plain errors on bad tags
        first = (str(exc).splitlines() or [type(exc).__name__])[0]
        raise UserError(f"{path}: malformed YAML: {_REPR.repr(first)[1:-1]}") from None
