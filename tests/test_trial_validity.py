"""Numerical and envelope faults stop a trial, flag it, and keep it out of the rates."""

import dataclasses

import numpy as np
import pandas as pd
import pytest

from ftc_mc.campaign.chunk import chunk_spec, classify, run_chunk, trial_inputs
from ftc_mc.campaign.summary import summarize
from ftc_mc.config import Config
from ftc_mc.sim.lanes import new_record, run_trials

CFG = Config.model_validate({"campaign": {"transitions": ["elevon_lock"], "trials": 4},
                             "timing": {"fault_time_s": 2.0, "window_s": 2.0,
                                        "duration_s": 6.0}})


@pytest.fixture(scope="module")
def spec():
    # seed 1, the first variant only, 256 resets stored; window 2 s = 20 steps
    return dataclasses.replace(chunk_spec(CFG), seed=1, variants=("paper",), max_resets=256)


def _with_setup(spec, **changes):
    return dataclasses.replace(spec, setup=dataclasses.replace(spec.setup, **changes))


def _run(spec, inp=None, ids=np.arange(4)):
    if inp is None:
        inp, draws = trial_inputs(spec, "elevon_lock", ids)
    else:
        draws = np.zeros(len(ids))
    setup = spec.setup
    rec = new_record(setup, len(ids), spec.max_resets)
    run_trials(setup.scheme("paper"), setup.flight, inp, rec)
    trials, _ = classify(spec, "elevon_lock", "paper", ids, draws, inp, rec)
    return rec, trials


def test_healthy_trials_run_to_the_end(spec):
    rec, t = _run(spec)
    assert list(t["status"]) == ["ok"] * 4 and t["judged"].all()
    assert np.all(rec.stop_k == -1)


def test_nonfinite_measurement_stops_the_lane(spec):
    inp, _ = trial_inputs(spec, "elevon_lock", np.arange(4))
    inp.v[15, 2, 1] = np.nan  # lane 1 gets a NaN pitch-rate measurement at step 16
    rec, t = _run(spec, inp)
    assert t["status"][1] == "nonfinite" and rec.stop_k[1] == 16
    assert list(t["status"][[0, 2, 3]]) == ["ok"] * 3
    assert not t["judged"][1] and t["judged"][[0, 2, 3]].all()


def test_lost_positive_definiteness_is_caught(spec):
    setup = spec.setup
    bad = setup.P0.copy()
    # indefinite in the direction dl - dr of the elevon states, which no output
    # sees, so no measurement update can repair it: eigenvalue 1 - 2 = -1
    bad[7, 7] = bad[8, 8] = 1.0
    bad[7, 8] = bad[8, 7] = 2.0
    s = _with_setup(spec, P0=bad, val=setup.val._replace(psd_every=1))
    rec, t = _run(s)
    assert set(t["status"]) == {"covariance_not_psd"}
    assert not t["judged"].any()
    assert np.all(rec.stop_k == 1)


def test_airspeed_and_alpha_bounds(spec):
    setup = spec.setup
    va0 = setup.val.va_trim
    tight_va = _with_setup(spec, val=setup.val._replace(va_min=va0 - 1e-4,
                                                        va_max=va0 + 1e-4))
    _, t = _run(tight_va)
    assert set(t["status"]) == {"airspeed_out_of_bounds"}
    a0 = setup.val.alpha_trim
    tight_alpha = _with_setup(spec, val=setup.val._replace(
        alpha_min=a0 - 1e-6, alpha_max=a0 + 1e-6))
    _, t = _run(tight_alpha)
    assert set(t["status"]) == {"alpha_out_of_bounds"}


def test_flagged_trials_are_counted_not_averaged(spec):
    inp, _ = trial_inputs(spec, "elevon_lock", np.arange(4))
    inp.w[3, 0, 0] = np.inf
    healthy = run_chunk(spec, "elevon_lock", np.arange(4))["trials"]
    rec, t = _run(spec, inp)
    df = pd.DataFrame(t)
    s = summarize(df).iloc[0]
    assert s["trials"] == 3 and s["excluded"] == 1 and s["stopped_nonfinite"] == 1
    assert s["correct"] == int(healthy["correct"][1:].sum())
