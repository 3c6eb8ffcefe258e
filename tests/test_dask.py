"""The Dask backend (a LocalCluster of 2 single-threaded workers, started by ftc-mc or
beforehand and named by ``--scheduler``) gives the same bytes."""

import pandas as pd
import pytest

import ftc_mc
from ftc_mc.campaign.sweep import run_sweep, threshold_points
from ftc_mc.config import Config
from ftc_mc.errors import UserError

pytest.importorskip("dask.distributed")

CFG = Config.model_validate({
    "campaign": {"transitions": ["elevon_lock", "engine_loss"], "trials": 8,
                 "chunk_size": 4},
    "controller": {"kind": "nominal"},
    "timing": {"fault_time_s": 5, "window_s": 5, "duration_s": 15}})


def test_campaign_on_dask_equals_loky():
    a = ftc_mc.run_campaign(CFG, jobs=1, progress=False)
    b = ftc_mc.run_campaign(CFG, jobs=2, progress=False, backend="dask")
    pd.testing.assert_frame_equal(a.trials, b.trials, check_exact=True)
    pd.testing.assert_frame_equal(a.resets, b.resets, check_exact=True)


def test_sweep_on_a_running_scheduler_equals_loky():
    """``--scheduler``: the sweep runs on a cluster started beforehand (the
    campaign test above covers the local cluster ftc-mc starts itself)."""
    from dask.distributed import LocalCluster

    pts = threshold_points("8,25")
    a = run_sweep(CFG, pts, flights=4, jobs=1, progress=False)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=":0") as cluster:
        b = run_sweep(CFG, pts, flights=4, jobs=2, progress=False, backend="dask",
                      scheduler=cluster.scheduler_address)
        assert len(cluster.scheduler_info["workers"]) == 2  # still up: not closed by the run
    pd.testing.assert_frame_equal(a.table, b.table, check_exact=True)


def test_bad_backend_and_scheduler():
    with pytest.raises(UserError, match="--backend"):
        ftc_mc.run_campaign(CFG, progress=False, backend="spark")
    with pytest.raises(UserError, match="--scheduler"):
        ftc_mc.run_campaign(CFG, progress=False, scheduler="tcp://127.0.0.1:1")
