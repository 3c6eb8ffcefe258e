"""The sensor-aware design: biases of the q, n_x and n_z sensors in the
augmented filter.

* the filter stage with bias states, linear (with gust states) and extended
  (nonlinear prediction, re-linearised), against the dense twin of
  ``tests/naive.py``, with Table 1 resets that open the biases;
* the design builder (``ftc_mc/sim/designs.py``) against the construction
  written out here;
* a small campaign: the design names a q bias and an n_x bias, where the
  paper's design resets an actuator block.

The bias columns are built here from their definition (a random walk that only
adds to its output), independently of the builder.
"""

from __future__ import annotations

import numpy as np
import pytest

from test_design_kernels import (NG, compare_steps, extended, gust_filter, gust_scheme,
                                 linear_gusts, nonlinear_gusts, with_gust_states,  # noqa: F401
                                 with_trim_jacobians)
from test_stages import random_cov, random_lanes
from ftc_mc.config.schema import Config, DesignConfig
from ftc_mc.conventions import N_AUG, OUTPUT_NAMES, RESET_ELEVONS, RESET_THRUST
from ftc_mc.sim.designs import build_design

OUTS = ("q", "n_x", "n_z")
NS = len(OUTS)
SD = {"q": 0.0873, "n_x": 0.08, "n_z": 0.08}
WALK = {"q": 0.3, "n_x": 0.05, "n_z": 0.1}


def with_biases(fm, P0, dt):
    """``fm``, ``P0`` with the three output biases after the gust states: ``G``
    and ``C_d`` columns 0, ``A_d`` identity, random walk ``(WALK sigma_R)^2 dt``,
    unit entry of ``D_g`` and ``D_z`` on the output (``WALK`` per output); the thrust reset opens the
    n_x bias, the elevon reset the q and n_z biases."""
    ng = fm.Ad.shape[0]
    rows = [OUTPUT_NAMES.index(o) for o in OUTS]
    sig = np.sqrt(fm.r_diag[rows])
    E = np.zeros((12, NS))
    for j, r in enumerate(rows):
        E[r, j] = 1.0
    Ad = np.eye(ng + NS)
    Ad[:ng, :ng] = fm.Ad
    Qg = np.zeros((ng + NS, ng + NS))
    Qg[:ng, :ng] = fm.Qg
    Qg[ng:, ng:] = np.diag((np.array([WALK[o] for o in OUTS]) * sig) ** 2 * dt)
    reset = np.zeros((3, ng + NS))
    reset[RESET_THRUST, ng + 1] = SD["n_x"] ** 2
    reset[RESET_ELEVONS, ng] = SD["q"] ** 2
    reset[RESET_ELEVONS, ng + 2] = SD["n_z"] ** 2
    c = np.ascontiguousarray
    fm = fm._replace(G=c(np.hstack([fm.G, np.zeros((9, NS))])), Ad=c(Ad),
                     Dg=c(np.hstack([fm.Dg, E])), Qg=c(Qg),
                     Cg=c(np.hstack([fm.Cg, np.zeros((3, NS))])),
                     Dz=c(np.hstack([np.zeros((12, ng)), E])), reset_g=c(reset))
    n = P0.shape[0] + NS
    P = np.zeros((n, n))
    P[:-NS, :-NS] = P0
    P[-NS:, -NS:] = np.diag(sig ** 2)
    return fm, P


def test_bias_filter_update(linear_gusts):
    """Gust and bias states, linear prediction: the stage against the twin, over
    steps where both blocks are reset (so ``reset_g`` opens every bias)."""
    fm, P0, d = gust_filter(linear_gusts)
    fm, P0 = with_biases(fm, P0, linear_gusts.plant.dt)
    n = P0.shape[0]
    scheme = gust_scheme(linear_gusts, fm, t_q=3.0, t_nx=3.0)
    rng = np.random.default_rng(71)
    st = with_gust_states(random_lanes(linear_gusts, rng, 10), rng, d, P0)
    scale = np.array([0.3, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0])
    fired = compare_steps(scheme, st, rng, [scale[::-1], scale] * 3, 10, n)
    assert fired == {0, RESET_THRUST, RESET_ELEVONS}


def test_bias_reset_opens_the_bias(linear_gusts):
    """After a thrust reset the n_x bias has exactly its opening variance before
    the update shrinks it: the lane's ``P_{k|k}`` bias row is zero off the
    diagonal (checked on the twin's reset, which the stage matches above)."""
    import naive
    fm, P0, _ = gust_filter(linear_gusts)
    fm, P0 = with_biases(fm, P0, linear_gusts.plant.dt)
    P = random_cov(np.random.default_rng(3), P0)
    out = naive.reset_extra_ref(P, RESET_THRUST, fm.reset_g)
    i = N_AUG + NG + 1
    assert out[i, i] == SD["n_x"] ** 2
    assert np.count_nonzero(out[i]) == 1 and np.count_nonzero(out[:, i]) == 1
    keep = [j for j in range(P.shape[0]) if j != i]
    assert np.array_equal(out[np.ix_(keep, keep)], P[np.ix_(keep, keep)])


@pytest.mark.parametrize("relin", [0, 2])
def test_extended_bias_filter_update(nonlinear_gusts, relin):
    """Extended filter with biases: the predicted outputs are ``h(x, C_d g) - y0
    + D_z s`` and the re-linearised rows carry ``D_z``; against the twin
    (tolerances as ``test_relinearised_filter_update`` with re-linearisation)."""
    fm, P0, d = extended(nonlinear_gusts, relin)
    fm, P0 = with_biases(fm, P0, nonlinear_gusts.plant.dt)
    n = P0.shape[0]
    scheme = gust_scheme(nonlinear_gusts, fm, t_q=3.0, t_nx=3.0)
    rng = np.random.default_rng(72)
    st = with_trim_jacobians(with_gust_states(random_lanes(nonlinear_gusts, rng, 10), rng,
                                              d, P0), fm)
    scale = np.array([0.3, 0.5, 1.0, 2.0, 3.0, 5.0, 10.0])
    tol = 1e-7 if relin else 1e-9
    fired = compare_steps(scheme, st, rng, [scale] * 4, 10, n, tol_res=tol, tol=tol,
                          tol_jac=tol if relin else None)
    assert len(fired) > 1


@pytest.mark.parametrize("estimator", ["paper", "gust_aware"])
def test_builder_matches_definition(linear_gusts, estimator):
    """``build_design`` with ``sensor_biases`` gives the model written out in
    :func:`with_biases` (on the gust-aware or the paper's filter)."""
    cfg = Config()
    dc = DesignConfig(estimator=estimator, sensor_biases=list(OUTS), sensor_bias_sd=SD,
                      sensor_bias_walk=WALK)
    plain = DesignConfig(estimator=estimator)
    p = linear_gusts.plant
    d = build_design("s", dc, p, cfg.estimator, 100.0)
    base = build_design("b", plain, p, cfg.estimator, 100.0)
    fm, P0 = with_biases(base.fm, base.P0, p.dt)
    for f in ("G", "Ad", "Dg", "Qg", "Cg", "Dz", "reset_g"):
        assert np.array_equal(getattr(d.fm, f), getattr(fm, f)), f
    assert np.array_equal(d.P0, P0)
    assert d.biases == OUTS and d.bias_row("n_z") == d.n_aug - 1
    assert d.key != base.key


@pytest.mark.usefixtures("trial_kernel")
def test_sensor_aware_names_biases():
    """16 trials each of a q bias and an n_x bias (linear plant, still air): the
    sensor-aware design estimates the bias within 25 % with a nominal belief at
    the end in most trials, the paper's design in none (it has no bias to
    estimate); the tables of a run mixing actuator and sensor rows."""
    from ftc_mc.api import run_campaign
    from ftc_mc.report.sensors import misattribution_table
    cfg = Config.model_validate({
        "campaign": {"transitions": ["elevon_lock", "sensor_bias:q", "sensor_bias:n_x"],
                     "trials": 16, "signature": "swapped", "designs": ["aware"]},
        "designs": {"aware": {"sensor_biases": list(OUTS), "settle_s": 3.0}},
        "timing": {"fault_time_s": 10.0, "window_s": 10.0, "duration_s": 30.0}})
    out = run_campaign(cfg, progress=False)
    s = out.summary.set_index(["transition", "variant"])
    for tr in ("sensor_bias:q", "sensor_bias:n_x"):
        assert s.loc[(tr, "aware"), "isolated_rate"] >= 0.75, s.loc[(tr, "aware")]
        assert np.isnan(s.loc[(tr, "swapped")].get("isolated_rate", np.nan))
        assert s.loc[(tr, "aware"), "wrong_mode_rate"] == 0.0
    hat = out.trials.query("transition == 'sensor_bias:n_x' and variant == 'aware'")
    assert np.corrcoef(hat["sensor_bias_hat_end"], hat["sensor_size"])[0, 1] > 0.9
    text = out.markdown()  # the elevon row has no no-reset at all: its share is NaN
    assert "inappropriate" in text and "isolated %" in text
    lines = "\n".join(misattribution_table(out.summary, out.trials))
    assert "Sensor-bias isolation" in lines and "bin 4" in lines
