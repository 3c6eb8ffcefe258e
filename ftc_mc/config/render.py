"""A resolved configuration as commented YAML (``ftc-mc config show``), and the
field tables of ``docs/reference/config.md``.

:func:`render_yaml` lists every section and field of a :class:`Config` or
:class:`ScenarioConfig` with its value and its one-line description; a value
that differs from the field's default says the default.  The output reads back
to the same configuration.  :func:`type_text` and :func:`value_text` give a
field's type and a value as a reader sees them (the reference tables).
"""

from __future__ import annotations

import types
import typing

import yaml
from annotated_types import Ge, Gt, Le, Lt, MinLen
from pydantic import BaseModel

DEFAULT_TEXT_MAX = 60
"""Longest default written beside a changed value; a longer one is named only."""


def value_text(value) -> str:
    """A JSON-compatible value as one line of YAML flow text."""
    text = yaml.safe_dump(value, default_flow_style=True, sort_keys=False, width=10_000)
    text = text.strip()
    if text.endswith("\n..."):
        text = text[:-4].strip()
    return text.removesuffix("...").strip()


def description(info) -> str:
    """A field's one-line description (its docstring, whitespace collapsed)."""
    return " ".join((info.description or "").split())


def section_doc(model_type) -> str:
    """The first line of a section model's docstring."""
    doc = (model_type.__doc__ or "").strip().splitlines()
    return doc[0] if doc else ""


def _field_line(indent: str, name: str, value, default, info, mark: bool) -> str:
    doc = description(info)
    if mark and value != default:
        d = value_text(default)
        doc += f" [default: {d}]" if len(d) <= DEFAULT_TEXT_MAX else " [not the default]"
    if isinstance(value, list) and value and isinstance(value[0], dict):
        items = [f"{indent}  - {value_text({k: v for k, v in item.items() if v is not None})}"
                 for item in value]
        return "\n".join([f"{indent}{name}:  # {doc}".rstrip(), *items])
    return f"{indent}{name}: {value_text(value)}  # {doc}".rstrip()


def _model_lines(model: BaseModel, indent: str) -> list:
    """``name: value  # doc`` lines of every field of ``model``; a changed value
    says its default."""
    values = model.model_dump(mode="json")
    defaults = type(model)().model_dump(mode="json")
    return [_field_line(indent, name, values[name], defaults[name], info, True)
            for name, info in type(model).model_fields.items()]


def render_yaml(cfg: BaseModel, title: str) -> str:
    """Commented YAML of ``cfg``: every section and field, its value and its doc.

    Parameters
    ----------
    cfg : Config or ScenarioConfig
    title : str
        First comment line.

    Returns
    -------
    str
        YAML that reads back to ``cfg``.
    """
    lines = [f"# {title}",
             "# Every field with its value and what it means; [default: ...] marks a "
             "value that is not the default.",
             "# Reference: docs/reference/config.md", ""]
    for section, sinfo in type(cfg).model_fields.items():
        sub = getattr(cfg, section)
        if isinstance(sub, dict):
            lines += _named_models(section, sub, sinfo)
            continue
        lines.append(f"{section}:  # {section_doc(type(sub))}")
        lines += _model_lines(sub, "  ")
        lines.append("")
    return "\n".join(lines)


def _named_models(section: str, models: dict, info) -> list:
    """A top-level mapping of names to models (``designs``); when empty, the fields
    of one entry with their defaults, commented out, as an example."""
    doc = description(info)
    if models:
        lines = [f"{section}:  # {doc}"]
        for key, model in models.items():
            lines.append(f"  {key}:  # {section_doc(type(model))}")
            lines += _model_lines(model, "    ")
        return lines + [""]
    model_type = typing.get_args(info.annotation)[1]
    example = _model_lines(model_type(), "#    ")
    return [f"{section}: {{}}  # {doc}",
            "# for example (replace {} by these lines uncommented, rename NAME, list NAME "
            "to run it):", "#  NAME:", *example, ""]


# -- types as a reader sees them (docs/reference/config.md) --------------------------

def _num(v) -> str:
    if isinstance(v, int) and v == 2 ** 63:
        return "2^63"
    return str(v) if isinstance(v, int) else f"{v:g}".replace("e+0", "e").replace("e+", "e")


def _bounds(metadata) -> str:
    """``> 0``, ``in [0, 1]``... from a field's annotated-types metadata."""
    lo = hi = None
    for m in metadata:
        if isinstance(m, Gt):
            lo = ("(", m.gt)
        elif isinstance(m, Ge):
            lo = ("[", m.ge)
        elif isinstance(m, Lt):
            hi = (")", m.lt)
        elif isinstance(m, Le):
            hi = ("]", m.le)
        elif hasattr(m, "metadata"):  # a FieldInfo nested in Annotated
            inner = _bounds(m.metadata)
            if inner:
                return inner
    if lo and hi:
        return f"in {lo[0]}{_num(lo[1])}, {_num(hi[1])}{hi[0]}"
    if lo:
        return f"{'>' if lo[0] == '(' else '>='} {_num(lo[1])}"
    if hi:
        return f"{'<' if hi[0] == ')' else '<='} {_num(hi[1])}"
    return ""


def type_text(annotation, metadata=(), top=True) -> str:
    """A field's type in words: ``float > 0``, ``one of: a, b``, ``[float, float]``..."""
    origin = typing.get_origin(annotation)
    args = typing.get_args(annotation)
    if origin is typing.Annotated:
        return type_text(args[0], (*args[1:], *metadata), top)
    if origin in (typing.Union, types.UnionType):
        parts = [type_text(a, top=False) for a in args if a is not type(None)]
        text = " or ".join(parts)
        return f"{text} or null" if type(None) in args else text
    if origin is typing.Literal:
        names = [str(a) for a in args]
        return "one of: " + ", ".join(names) if top else "|".join(names)
    if origin is tuple:
        if len(args) == 2 and args[1] is Ellipsis:
            return f"list of {type_text(args[0], top=False)}"
        return "[" + ", ".join(type_text(a, top=False) for a in args) + "]"
    if origin is list:
        text = f"list of {type_text(args[0], top=False)}"
        return text + (" (not empty)" if any(isinstance(m, MinLen) and m.min_length
                                            for m in metadata) else "")
    if origin is dict:
        return f"mapping {type_text(args[0], top=False)} -> {type_text(args[1], top=False)}"
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation.__name__
    name = getattr(annotation, "__name__", str(annotation))
    return f"{name} {_bounds(metadata)}".strip()


def field_type(info) -> str:
    """:func:`type_text` of a pydantic ``FieldInfo``."""
    return type_text(info.annotation, tuple(info.metadata))
