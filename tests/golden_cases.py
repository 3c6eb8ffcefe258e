"""The fixed small campaigns and scenarios pinned by ``tests/test_golden.py``.

``python scripts/maintenance/make_golden.py`` writes what they produce today to
``tests/golden/``; the test reruns them and asks for the same data bit for bit.
A refactor or speed-up must leave these files alone.  A change of behaviour
regenerates them in its own commit, and its issue note says what moved and why.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

GOLDEN = Path(__file__).resolve().parent / "golden"

TRANSITIONS = ["elevon_lock", "elevon_unlock", "elevon_loss", "elevon_loss_recover",
               "engine_lock", "engine_unlock", "engine_loss", "engine_loss_recover"]

SHORT = {"fault_time_s": 5.0, "window_s": 5.0, "duration_s": 15.0}

PINNED = {"airframe": "x8-gryte2018"}
"""The airframe every golden case flies, named so a change of default leaves them."""

CAMPAIGNS = {
    # all eight transitions, both Table 1 variants, reconfiguring controller,
    # linear plant in still air
    "linear": {"campaign": {"transitions": TRANSITIONS, "trials": 6, "chunk_size": 4,
                            "seed": 2026, "signature": "both"},
               "controller": {"kind": "reconfiguring"},
               "model": PINNED, "timing": SHORT},
    # a nonlinear, moderate-turbulence slice
    "nonlinear_moderate": {"campaign": {"transitions": ["elevon_lock", "engine_loss"],
                                        "trials": 4, "chunk_size": 4, "seed": 2026,
                                        "signature": "both"},
                           "controller": {"kind": "reconfiguring"},
                           "plant": {"kind": "nonlinear", "turbulence": "moderate"},
                           "model": PINNED, "timing": SHORT},
    # the 6-DOF flying wing: left and right elevon and an engine row,
    # nonlinear equations in moderate turbulence, with the lateral autopilot
    "sixdof_moderate": {"campaign": {"transitions": ["elevon_lock", "right_elevon_loss",
                                                     "engine_loss"],
                                     "trials": 4, "chunk_size": 4, "seed": 2026,
                                     "signature": "both"},
                        "controller": {"kind": "reconfiguring"},
                        "plant": {"kind": "nonlinear", "turbulence": "moderate", "dof": 6},
                        "model": PINNED, "timing": SHORT},
}

SCENARIOS = {
    "linear": {"model": PINNED},
    "nonlinear_moderate": {"model": PINNED,
                           "plant": {"kind": "nonlinear", "turbulence": "moderate"}},
    "sixdof": {"model": PINNED, "plant": {"kind": "nonlinear", "dof": 6}},
}


def campaign_frames(name: str) -> dict:
    """``{"trials": DataFrame, "resets": DataFrame}`` of campaign ``name``."""
    from ftc_mc import run_campaign

    res = run_campaign(CAMPAIGNS[name], jobs=1, progress=False)
    return {"trials": res.trials, "resets": res.resets}


def scenario_frames(name: str) -> dict:
    """``{"timeseries": DataFrame}`` of the paper's scenario under ``name``."""
    from ftc_mc.config import load_scenario, with_overrides
    from ftc_mc.scenario import run_scenario

    root = Path(__file__).resolve().parents[1]
    sc = load_scenario(root / "configs" / "paper_scenario.yaml")
    sc = with_overrides(sc, **SCENARIOS[name])
    return {"timeseries": run_scenario(sc).timeseries}


def golden_path(kind: str, name: str, table: str) -> Path:
    return GOLDEN / f"{kind}-{name}-{table}.parquet"


def all_frames():
    """Yield ``(path, DataFrame)`` of every golden table."""
    for name in CAMPAIGNS:
        for table, df in campaign_frames(name).items():
            yield golden_path("campaign", name, table), df
    for name in SCENARIOS:
        for table, df in scenario_frames(name).items():
            yield golden_path("scenario", name, table), df


def read(path: Path) -> pd.DataFrame:
    return pd.read_parquet(path)
