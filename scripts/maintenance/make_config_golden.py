"""Record what every shipped config resolves to: ``tests/golden/configs/<name>.json``.

Each file holds the validated config of ``configs/<name>.yaml`` as
``model_dump(mode="json")`` (every field, defaults included), and whether it is a
campaign (``ftc-mc run``/``sweep``) or a scenario (``ftc-mc scenario``) config.
``tests/test_config_equivalence.py`` checks that each shipped config still
resolves to an equal ``Config``/``ScenarioConfig``: editing a config's text
(comments, order, dropping a field at its default) must not change what it runs.
Run this only after a deliberate change of what a shipped config or a default
means, in its own commit::

    .venv/bin/python scripts/maintenance/make_config_golden.py
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from ftc_mc.config import ScenarioConfig, load_any  # noqa: E402

GOLDEN = ROOT / "tests" / "golden" / "configs"


def resolved(path) -> dict:
    """``{"kind": "campaign"|"scenario", "config": model_dump(mode="json")}``."""
    cfg = load_any(path)
    kind = "scenario" if isinstance(cfg, ScenarioConfig) else "campaign"
    return {"kind": kind, "config": cfg.model_dump(mode="json")}


def main() -> None:
    GOLDEN.mkdir(parents=True, exist_ok=True)
    for path in sorted((ROOT / "configs").glob("*.yaml")):
        out = GOLDEN / f"{path.stem}.json"
        out.write_text(json.dumps(resolved(path), indent=1) + "\n", encoding="utf-8")
        print(f"wrote {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
