"""The controller a design flies (its own ``controller``, else the controller
section's kind) in the report: run and scenario headers, and the endurance runs
an operating characteristic matches to a sweep's designs."""

from __future__ import annotations

from types import SimpleNamespace

import pandas as pd

from ftc_mc.report.endurance import matching_endurance
from ftc_mc.report.markdown import controller_of
from ftc_mc.report.runs import _run_header

DESIGN = {"estimator": "paper", "test": "one_step", "t_q": 25.0, "t_nx": 25.0}


def _cfg(kind="reconfiguring", own=None):
    return {"campaign": {"transitions": ["elevon_lock"], "trials": 10, "seed": 1,
                         "signature": "paper", "designs": ["d"]},
            "controller": {"kind": kind}, "estimator": {"sigma_qx": 1.0},
            "designs": {"d": dict(DESIGN, controller=own)},
            "plant": {"kind": "nonlinear", "turbulence": "none"},
            "model": {"airframe": "x8-pyfly"}}


def test_controller_of_a_stored_config():
    assert controller_of(_cfg(own="nominal"), "d") == "nominal"
    assert controller_of(_cfg(own=None), "d") == "reconfiguring"
    assert controller_of(_cfg(own="nominal"), "paper") == "reconfiguring"  # built-in
    assert controller_of(_cfg(own="nominal"), None) == "reconfiguring"


def test_run_header_names_a_designs_own_controller():
    head = _run_header(_cfg(own="nominal"))
    assert "t_nx 25.0, controller `nominal`)" in head
    assert "controller `reconfiguring` where a design names none" in head
    plain = _run_header(_cfg(own=None))
    assert "controller `reconfiguring`," in plain and "names none" not in plain


def test_endurance_rows_match_the_controller_a_design_flies():
    """An endurance run whose design flew another controller (its own, or the
    config's kind) is not the sweep's design."""
    table = pd.DataFrame({"variant": ["d", "paper"]})

    def run(cfg):
        return SimpleNamespace(meta={"config": cfg}, tables={"endurance": table})

    sweep = _cfg(kind="reconfiguring")
    same = matching_endurance([run(_cfg(kind="reconfiguring"))], sweep)
    assert list(same["variant"]) == ["d", "paper"]
    assert matching_endurance([run(_cfg(kind="nominal"))], sweep) is None
    # the design's own controller wins over the kind, on either side
    own = matching_endurance([run(_cfg(kind="nominal", own="reconfiguring"))], sweep)
    assert list(own["variant"]) == ["d"]


def test_endurance_rows_match_the_weights_a_design_flies_and_results_of_before():
    """A design recorded before fields were added (here every design field the
    current schema fills in) is the same design; one that flies other LQR
    weights (its own, or the controller section's, or other scales) is not."""
    from ftc_mc.config.schema import DesignConfig

    table = pd.DataFrame({"variant": ["d"]})

    def run(cfg):
        return SimpleNamespace(meta={"config": cfg}, tables={"endurance": table})

    def with_(cfg, design=None, controller=None):
        cfg["designs"]["d"].update(design or {})
        cfg["controller"].update(controller or {})
        return cfg

    sweep = _cfg()  # a design recorded with only the fields it set
    full = _cfg()
    full["designs"]["d"] = DesignConfig.model_validate(DESIGN).model_dump(mode="json")
    assert "weights" in full["designs"]["d"] and "weights" not in sweep["designs"]["d"]
    assert list(matching_endurance([run(full)], sweep)["variant"]) == ["d"]
    assert matching_endurance([run(with_(_cfg(), {"weights": "airspeed"}))], sweep) is None
    assert matching_endurance([run(with_(_cfg(), None, {"weights": "airspeed"}))],
                              sweep) is None
    own = with_(_cfg(), {"weights": "airspeed"})
    section = with_(_cfg(), None, {"weights": "airspeed"})
    assert list(matching_endurance([run(section)], own)["variant"]) == ["d"]
    other_scale = with_(_cfg(), None, {"weights": "airspeed", "height_scale_m": 3.0})
    assert matching_endurance([run(other_scale)], own) is None
