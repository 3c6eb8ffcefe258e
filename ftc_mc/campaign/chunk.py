"""Run one chunk of trials of one transition and classify them (worker side).

A chunk is a fixed range of trial ids; its results depend only on those ids and
the root seed, never on which worker runs it or how many chunks there are.
"""

from __future__ import annotations

import numpy as np

from ..core.settings import TrialInputs, TrialRecord
from ..core.trial import STATUS_NAMES, STATUS_NONFINITE, STATUS_NOT_PSD, run_trials
from .setup import CampaignSetup
from .transitions import (BLOCK_NAMES, TRANSITION_TABLE, draw_trial, estimator_params,
                          faulty_params, gust_lanes, mode_of)

from ..conventions import MODE_NAMES


def draw_lanes(setup: CampaignSetup, tr, trial_ids, seed: int, lock_range=(0.0, 1.0)):
    """Every trial's draws (:func:`~ftc_mc.campaign.transitions.draw_trial`) in lanes.

    Returns
    -------
    draws : ndarray, shape (L,)
        The fault draw of each trial (lock position or b1).
    w, v : ndarray, shapes (n_steps, 9, L) and (n_steps, 12, L)
    eta, g0 : ndarray
        Gust draws and initial gust states (see
        :func:`~ftc_mc.campaign.transitions.gust_lanes`).
    """
    n, L = setup.tim.n_steps, len(trial_ids)
    w = np.empty((n, 9, L))
    v = np.empty((n, 12, L))
    draws = np.empty(L)
    eta, g0 = gust_lanes(n, L, setup.gust_chol is not None)
    for l, tid in enumerate(trial_ids):
        draws[l], w[:, :, l], v[:, :, l], gust = draw_trial(
            int(tid), seed, tr, lock_range, setup.loss_range, n, setup.q_std,
            setup.r_std, setup.gust_chol)
        if gust is not None:
            eta[:, :, l], g0[:, l] = gust
    return draws, w, v, eta, g0


def build_inputs(setup: CampaignSetup, tr_name: str, trial_ids, seed: int):
    """Draw every trial of a chunk and lay the inputs out in lanes.

    Returns
    -------
    inp : TrialInputs
    draws : ndarray, shape (L,)
        The fault draw of each trial (lock position or b1).
    """
    tr = TRANSITION_TABLE[tr_name]
    tim = setup.tim
    L = len(trial_ids)
    b0 = {True: np.zeros((3, L)), False: np.zeros((3, L))}   # keyed by 'faulty'
    b1 = {True: np.zeros((3, L)), False: np.zeros((3, L))}
    mode_f = np.zeros(L, dtype=np.int64)
    xa0 = np.zeros((14, L))
    draws, w, v, eta, g0 = draw_lanes(setup, tr, trial_ids, seed,
                                      setup.lock_range[tr.actuator])
    for l, value in enumerate(draws):
        fb0, fb1 = faulty_params(tr, value)
        b0[True][:, l] = fb0
        b1[True][:, l] = fb1
        mode_f[l] = mode_of(fb1, *setup.beta)
    mode_nominal = np.zeros(L, dtype=np.int64)
    pre_faulty = not tr.onset
    b0_sched = np.stack([b0[pre_faulty], b0[not pre_faulty]])
    b1_sched = np.stack([b1[pre_faulty], b1[not pre_faulty]])
    mode_pre = mode_f if pre_faulty else mode_nominal
    mode_post = mode_nominal if pre_faulty else mode_f
    for l in range(L):
        # the trial starts with the initial mode already identified
        xa0[9:, l] = estimator_params(b0_sched[0, :, l], b1_sched[0, :, l])
    inp = TrialInputs(k_switch=np.array([0, tim.k_fault], dtype=np.int64), b0=b0_sched,
                      b1=b1_sched, mode_pre=mode_pre, mode_post=mode_post, xa0=xa0,
                      P0=setup.P0, w=w, v=v, eta=eta, g0=g0)
    return inp, draws


def new_record(setup: CampaignSetup, L: int, max_resets: int, history: bool = False
               ) -> TrialRecord:
    """Preallocated outputs of :func:`ftc_mc.core.trial.run_trials`.

    ``history=True`` keeps every step's state, estimate, commands, residuals
    and excitation (for scenarios); campaigns keep only the per-period arrays.
    """
    n_per = setup.tim.n_steps // setup.tim.reconf_every
    n_hist = setup.tim.n_steps if history else 0
    return TrialRecord(
        reset_k=np.zeros((max_resets, L), dtype=np.int64),
        reset_block=np.zeros((max_resets, L), dtype=np.int64),
        reset_res=np.zeros((max_resets, 3, L)),
        n_resets=np.zeros(L, dtype=np.int64),
        belief=np.zeros((n_per, 4, L)), bhat=np.zeros((n_per, 5, L)),
        detect_k=np.zeros(L, dtype=np.int64), status=np.zeros(L, dtype=np.int64),
        stop_k=np.zeros(L, dtype=np.int64),
        controller=np.zeros((n_per, L), dtype=np.int64),
        hist_x=np.zeros((n_hist, 9, L)), hist_xa=np.zeros((n_hist, 14, L)),
        hist_pdiag=np.zeros((n_hist, 5, L)), hist_u=np.zeros((n_hist, 3, L)),
        hist_res=np.zeros((n_hist, 3, L)), hist_exc=np.zeros((n_hist, 4, L)),
        hist_block=np.zeros((n_hist, L), dtype=np.int64),
        hist_wind=np.zeros((n_hist, 3, L)),
        xa_end=np.zeros((14, L)))


def classify(setup: CampaignSetup, tr_name: str, variant: str, trial_ids, draws,
             inp: TrialInputs, rec: TrialRecord, window_steps: int):
    """Per-trial and per-reset columns of one kernel call.

    Definitions (DESIGN.md section 6), with ``k_f`` the switch step and the
    window the steps ``k_f < k <= k_f + window_steps``:

    * ``correct``: the transition's block was reset in the window;
    * ``inappropriate``: the other block was reset in the window (whether or
      not the correct one was too);
    * ``no_reset``: nothing was reset in the window;
    * ``false_resets``: resets at or before ``k_f``;
    * ``first_reset_s``: delay from the switch to the first reset in the window;
    * ``detection_s``: delay from the switch to the first belief update where
      the final mode is the most probable with at least ``detect_prob``; NaN when
      the final mode equals the initial one (nothing to detect);
    * ``status``/``stop_s``: why and when a trial stopped (``ok`` if it ran to
      the end); ``judged``: the trial counts in the rates, i.e. it never failed
      numerically, left the validity envelope (if at all) only after the window,
      and stored all its resets.

    Returns
    -------
    trials : dict of str to ndarray
    resets : dict of str to ndarray
    """
    tr = TRANSITION_TABLE[tr_name]
    dt = setup.plant.dt
    kf = setup.tim.k_fault
    L = len(trial_ids)
    R = rec.reset_k.shape[0]
    stored = np.minimum(rec.n_resets, R)
    idx = np.arange(R)[:, None]
    valid = idx < stored[None, :]
    k = rec.reset_k
    blk = rec.reset_block
    in_win = valid & (k > kf) & (k <= kf + window_steps)
    before = valid & (k <= kf)
    correct = np.any(in_win & (blk == tr.correct_block), axis=0)
    inappropriate = np.any(in_win & (blk == tr.other_block), axis=0)
    n_win = in_win.sum(axis=0)
    first = np.where(n_win > 0, np.argmax(in_win, axis=0), 0)
    first_k = k[first, np.arange(L)]
    first_block = blk[first, np.arange(L)]
    changed = inp.mode_pre != inp.mode_post
    detected = changed & (rec.detect_k >= 0)
    a = tr.actuator
    u0 = setup.plant.u0[a]
    beta = setup.beta[0 if a == 0 else 1]
    near = setup.near_trim[0 if a == 0 else 1]
    is_lock = tr.kind == "lock"
    small_b1 = np.zeros(L, dtype=bool) if is_lock else draws < beta
    near_trim = np.abs(draws - u0) < near if is_lock else np.zeros(L, dtype=bool)
    truncated = rec.n_resets > R
    # A trial is judged when it stayed valid through the whole window: numerical
    # failures never count; an envelope exit after the window does not matter.
    numeric_fail = (rec.status == STATUS_NONFINITE) | (rec.status == STATUS_NOT_PSD)
    judged = (rec.status == 0) | (~numeric_fail & (rec.stop_k > kf + window_steps))
    xa = rec.xa_end
    b1_idx = 11 if a == 0 else 12
    b0_idx = 9 if a == 0 else 10
    trials = {
        "transition": np.full(L, tr_name, dtype=object),
        "variant": np.full(L, variant, dtype=object),
        "trial_id": np.asarray(trial_ids, dtype=np.int64),
        "lock_position": draws if is_lock else np.full(L, np.nan),
        "loss_b1": np.full(L, np.nan) if is_lock else draws,
        "mode_pre": np.array([MODE_NAMES[m] for m in inp.mode_pre], dtype=object),
        "mode_post": np.array([MODE_NAMES[m] for m in inp.mode_post], dtype=object),
        "correct": correct,
        "inappropriate": inappropriate,
        "no_reset": n_win == 0,
        "first_reset_s": np.where(n_win > 0, (first_k - kf) * dt, np.nan),
        "first_reset_block": np.array([BLOCK_NAMES[b] if n else "none"
                                       for b, n in zip(first_block, n_win)], dtype=object),
        "resets_in_window": n_win.astype(np.int64),
        "false_resets": before.sum(axis=0).astype(np.int64),
        "resets_total": rec.n_resets.copy(),
        "detection_s": np.where(detected, (rec.detect_k - kf) * dt, np.nan),
        "mode_changed": changed,
        "detected": detected,
        "small_b1": small_b1,
        "lock_near_trim": near_trim,
        "b0_hat_end": xa[b0_idx].copy(),
        "b1_hat_end": xa[b1_idx].copy(),
        "resets_truncated": truncated,
        "judged": judged & ~truncated,
        "status": np.array([STATUS_NAMES[s] for s in rec.status], dtype=object),
        "stop_s": np.where(rec.stop_k >= 0, rec.stop_k * dt, np.nan),
    }
    lane, slot = np.nonzero(valid.T)
    kk = k[slot, lane]
    resets = {
        "transition": np.full(len(lane), tr_name, dtype=object),
        "variant": np.full(len(lane), variant, dtype=object),
        "trial_id": np.asarray(trial_ids, dtype=np.int64)[lane],
        "time_s": kk * dt,
        "time_from_fault_s": (kk - kf) * dt,
        "block": np.array([BLOCK_NAMES[b] for b in blk[slot, lane]], dtype=object),
        "r_q": rec.reset_res[slot, 0, lane],
        "r_nx": rec.reset_res[slot, 1, lane],
        "r_nz": rec.reset_res[slot, 2, lane],
        "in_window": in_win[slot, lane],
        "before_fault": before[slot, lane],
    }
    return trials, resets


def run_chunk(setup: CampaignSetup, tr_name: str, trial_ids, seed: int, variants,
              max_resets: int, window_steps: int):
    """Draw, simulate both variants on the same draws, and classify.

    Returns
    -------
    list of (trials, resets)
        One pair of column dicts per variant.
    """
    inp, draws = build_inputs(setup, tr_name, trial_ids, seed)
    out = []
    for variant in variants:
        rec = new_record(setup, len(trial_ids), max_resets)
        run_trials(setup.scheme(variant), setup.flight, inp, rec)
        out.append(classify(setup, tr_name, variant, trial_ids, draws, inp, rec,
                            window_steps))
    return out
