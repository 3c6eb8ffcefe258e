"""A complete, commented YAML file of a configuration (`ftc-mc config show`)."""

from __future__ import annotations

import typing

import yaml
from pydantic import BaseModel


def render_yaml(cfg: BaseModel, title: str, omit=()) -> str:
    """A complete, commented YAML file for ``cfg``: every field with its doc.

    Parameters
    ----------
    cfg : Config or ScenarioConfig
    title : str
        First comment line.
    omit : sequence of str
        Sections left out (they keep their defaults), e.g. ``sensor_draws`` of a
        config without sensor transitions.

    Returns
    -------
    str
        YAML that :func:`load_config` reads back to ``cfg``.
    """
    lines = [f"# {title}", "# Every field is listed with its default; delete a field to "
             "use the default.", ""]
    for section, sinfo in type(cfg).model_fields.items():
        if section in omit:
            continue
        sub = getattr(cfg, section)
        if isinstance(sub, dict):
            lines += _named_models(section, sub, sinfo)
            continue
        doc = (type(sub).__doc__ or "").strip().splitlines()[0]
        lines.append(f"{section}:  # {doc}")
        for name, info in type(sub).model_fields.items():
            value = getattr(sub, name)
            if isinstance(value, tuple):
                value = list(value)
            if isinstance(value, dict):
                value = {k: list(v) if isinstance(v, tuple) else v for k, v in value.items()}
            if isinstance(value, list) and value and isinstance(value[0], BaseModel):
                lines.append(f"  {name}:  # {' '.join((info.description or '').split())}")
                for item in value:
                    d = {k: v for k, v in item.model_dump().items() if v is not None}
                    flow = yaml.safe_dump(d, default_flow_style=True, sort_keys=False).strip()
                    lines.append(f"    - {flow}")
                continue
            text = yaml.safe_dump(value, default_flow_style=True, sort_keys=False,
                                  width=10_000).strip()
            if text.endswith("\n..."):
                text = text[:-4].strip()
            text = text.removesuffix("...").strip()
            doc = " ".join((info.description or "").split())
            lines.append(f"  {name}: {text}  # {doc}".rstrip())
        lines.append("")
    return "\n".join(lines)


def _fields(model: BaseModel, indent: str) -> list:
    """``name: value  # doc`` lines of a model's fields."""
    out = []
    for name, info in type(model).model_fields.items():
        text = yaml.safe_dump(getattr(model, name), default_flow_style=True,
                              width=10_000).strip().removesuffix("...").strip()
        out.append(f"{indent}{name}: {text}  # {' '.join((info.description or '').split())}")
    return out


def _named_models(section: str, models: dict, info) -> list:
    """A top-level mapping of names to models (``designs``); when empty, the fields
    of one entry with their defaults, commented out, as an example."""
    doc = " ".join((info.description or "").split())
    if models:
        lines = [f"{section}:  # {doc}"]
        for key, model in models.items():
            lines.append(f"  {key}:")
            lines += _fields(model, "    ")
        return lines + [""]
    model_type = typing.get_args(info.annotation)[1]
    return [f"{section}: {{}}  # {doc}",
            "# for example (replace {} by these lines uncommented, rename NAME, list NAME "
            "to run it):", "#  NAME:", *_fields(model_type(), "#    "), ""]
