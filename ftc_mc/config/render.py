"""A complete, commented YAML file of a configuration (``scripts/make_configs.py``)."""

from __future__ import annotations

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
    for section in type(cfg).model_fields:
        if section in omit:
            continue
        sub = getattr(cfg, section)
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
