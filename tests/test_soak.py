"""Long-run soundness: 10^6 filter steps with random fault switching and resets."""

import numpy as np
import pytest
from ftc_mc.core.jit import kernel
from ftc_mc.core.shared.belief import belief_update
from single_trajectory import filter_step
from ftc_mc.sim.estimator import (EstimatorSettings, belief_settings, detection, filter_model)


@kernel(error_model="python")  # cached by content (core/jit.py CloneFolderLocator)
def soak(fm, det, bs, K, n, switch_every, seed, checks):
    """Closed loop on the linear plant; the truth fault changes every
    ``switch_every`` steps (nominal, engine lock/loss, left/right elevon
    lock/loss, drawn at random); checks every 100 steps.  Returns the resets."""
    np.random.seed(seed)
    x = np.zeros(9)
    xa = np.zeros(14)
    P = np.eye(14) * 1e-4
    u = np.zeros(3)
    z = np.zeros(12)
    e = np.zeros(3)
    b0 = np.zeros(3)
    b1 = np.zeros(3)
    phi = np.zeros((9, 5))
    T = np.zeros((9, 14))
    h = np.zeros(14)
    res = np.zeros(3)
    xp = np.zeros(14)
    Pp = np.zeros((14, 14))
    belief = np.array([1.0, 0.0, 0.0, 0.0])
    bw = np.zeros(8)
    qs = np.sqrt(fm.q_diag[:9])
    rs = np.sqrt(fm.r_diag)
    resets = 0
    c = 0
    for k in range(n):
        if k % switch_every == 0:
            b0[:] = 0.0
            b1[:] = 0.0
            a = np.random.randint(0, 3)
            kind = np.random.randint(0, 3)
            if kind == 1:  # lock anywhere in the command range
                b1[a] = 1.0
                b0[a] = fm.u0[a] + np.random.uniform(-0.3, 0.3)
            elif kind == 2:
                b1[a] = np.random.uniform(0.0, 1.0)
        for i in range(3):
            acc = 0.0
            for j in range(9):
                acc -= K[i, j] * xa[j]
            u[i] = min(0.3, max(-0.3, acc + 0.05 * np.random.standard_normal()))
            e[i] = b0[i] + (1.0 - b1[i]) * u[i] - b1[i] * fm.u0[i]
        xn = fm.A @ x + fm.B @ e
        for i in range(9):
            x[i] = xn[i] + qs[i] * np.random.standard_normal()
        for r in range(12):
            acc = 0.0
            for j in range(9):
                acc += fm.C[r, j] * x[j]
            z[r] = acc + rs[r] * np.random.standard_normal()
        if filter_step(xa, P, u, z, fm, det, phi, T, h, res, xp, Pp) != 0:
            resets += 1
        if (k + 1) % 10 == 0:
            belief_update(belief, bs, xa[9:], np.diag(P)[9:].copy(), bw)
        if (k + 1) % 100 == 0 or k == n - 1:
            ev = np.linalg.eigvalsh(P)
            asym = 0.0
            for i in range(14):
                for j in range(14):
                    asym = max(asym, abs(P[i, j] - P[j, i]))
            finite = np.all(np.isfinite(P)) and np.all(np.isfinite(xa))
            s = belief.sum()
            checks[c, 0] = asym
            checks[c, 1] = ev[0] / ev[-1]
            checks[c, 2] = 1.0 if finite else 0.0
            checks[c, 3] = abs(s - 1.0)
            checks[c, 4] = belief.min()
            checks[c, 5] = belief.max()
            c += 1
    return resets


@pytest.mark.slow
def test_million_steps_stay_sound(plant):
    from ftc_mc.design.lqr import discounted_lqr, paper_q_lqr

    s = EstimatorSettings(t_q=10.0, t_nx=10.0)  # low thresholds: many resets
    fm, det, bs = filter_model(plant, s), detection(plant, s), belief_settings(plant, s)
    K, _ = discounted_lqr(plant.A, plant.B, paper_q_lqr(plant.trim.gamma0),
                          0.1 * np.eye(3), 0.999)
    n = 1_000_000
    checks = np.zeros((n // 100, 6))
    resets = soak(fm, det, bs, K, n, 2000, 11, checks)
    assert resets > 1000  # the resets really happen
    assert checks[:, 0].max() == 0.0  # exactly symmetric
    assert checks[:, 1].min() > -1e-12  # positive semi-definite (relative)
    assert checks[:, 2].all()  # finite
    assert checks[:, 3].max() < 1e-12  # belief sums to one
    assert checks[:, 4].min() >= 0.0 and checks[:, 5].max() <= 1.0
