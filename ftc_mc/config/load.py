"""Read and validate configuration files: YAML in, a validated model or one error line out.

YAML is read with ``yaml.safe_load`` only, so no tag can construct a Python
object.  Every problem becomes a :class:`~ftc_mc.errors.UserError` whose one
line names the file (or ``options``) and the field: ``path: section.field:
problem``.
"""

from __future__ import annotations

import re
import reprlib

from pydantic import BaseModel, ValidationError

from ..errors import UserError
from ..io.yamlfile import read_yaml  # noqa: F401  (part of this module's API)
from .schema import Config, ScenarioConfig


_REPR = reprlib.Repr()
_REPR.maxstring = _REPR.maxother = 80
_REPR.maxlevel = 2
"""Bounded repr of rejected values: error lines stay short whatever the input."""


def _format_error(exc: ValidationError, source: str) -> str:
    err = exc.errors()[0]
    loc = ".".join(str(p) for p in err["loc"]) or "(top level)"
    msg = err["msg"]
    if msg.startswith("Value error, "):
        msg = msg[len("Value error, "):]
    prefix = re.match(r"^([A-Za-z_][\w.]*): (.*)$", msg)
    if prefix and err["type"] == "value_error":
        # a model validator names the field itself: "field: problem"
        loc = prefix.group(1) if loc == "(top level)" else f"{loc}.{prefix.group(1)}"
        return f"{source}: {loc}: {prefix.group(2)}"
    got = err.get("input")
    extra = ""
    if err["type"] not in ("missing",) and not isinstance(got, (dict, list, tuple)):
        extra = f" (got {_REPR.repr(got)})"
    more = len(exc.errors()) - 1
    tail = f" [and {more} more problem{'s' if more > 1 else ''}]" if more else ""
    return f"{source}: {loc}: {msg}{extra}{tail}"


def parse_config(data, source: str = "config") -> Config:
    """Validate a mapping as a :class:`Config`.

    Parameters
    ----------
    data : dict
        Parsed YAML.
    source : str
        Name used in error messages.

    Raises
    ------
    UserError
        Naming the field and the problem.
    """
    return validate_model(Config, data, source)


def validate_model(model: type[BaseModel], data, source: str):
    """``model`` validated from the parsed YAML ``data``, or :class:`UserError`."""
    if data is None:
        raise UserError(f"{source}: the file is empty; expected a mapping of sections")
    if not isinstance(data, dict):
        raise UserError(f"{source}: expected a mapping of sections at the top level, "
                        f"got {type(data).__name__}")
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        raise UserError(_format_error(exc, source)) from None


def as_current(model: type[BaseModel], data):
    """``data`` recorded from a ``model`` (a result folder's config, a section of
    it) as the current schema resolves it, as JSON types: fields added since it
    was recorded take their defaults, so comparing two records compares
    meanings, not the schema's age.  Returned as it is when it does not
    validate (a comparison then fails)."""
    try:
        return model.model_validate(data).model_dump(mode="json")
    except Exception:  # noqa: BLE001 -- not ours to judge: compared as recorded
        return data


def load_config(path) -> Config:
    """Read and validate a YAML campaign configuration file.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    Config

    Raises
    ------
    UserError
        Missing or unreadable file, malformed YAML, or an invalid field.
    """
    return parse_config(read_yaml(path), str(path))


def with_overrides(cfg, **sections):
    """Return ``cfg`` with fields replaced, re-validated.

    Parameters
    ----------
    cfg : Config or ScenarioConfig
    **sections : dict
        ``section={field: value}`` pairs, e.g. ``campaign={"trials": 10}``;
        ``None`` values are left as they are.

    Raises
    ------
    UserError
        Naming the field and the problem (source ``options``).
    """
    data = cfg.model_dump()
    for section, fields in sections.items():
        data[section].update({k: v for k, v in fields.items() if v is not None})
    return validate_model(type(cfg), data, "options")


def load_scenario(path) -> ScenarioConfig:
    """Read and validate a scenario YAML file (see :func:`load_config`)."""
    return validate_model(ScenarioConfig, read_yaml(path), str(path))


def load_any(path):
    """Read and validate a campaign or a scenario file: a :class:`ScenarioConfig`
    when its top level has a ``scenario`` section, else a :class:`Config`."""
    data = read_yaml(path)
    model = ScenarioConfig if isinstance(data, dict) and "scenario" in data else Config
    return validate_model(model, data, str(path))
