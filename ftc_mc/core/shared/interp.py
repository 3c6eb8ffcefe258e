"""Bilinear interpolation of the engine-fault gain tables (paper section 4.1.5).

The engine-fault controller of Theorem 4.1 (eqs. 26-44) depends on the thrust
fault parameters ``(b0, b1)``.  Its gain ``K`` and affine term ``k`` are computed
offline on a grid (:mod:`ftc_mc.design.theorem41`) and interpolated online from
the estimates ``(b0_hat, b1_hat)`` (last paragraph of section 4.1.5):

    u = -K(b0, b1) x - k(b0, b1)

Conventions
-----------
* A table has shape ``(nx, ny, m)``: the two grid axes first, the interpolated
  values flattened into the last axis (``K_tab`` of shape ``(nb0, nb1, 3, 9)`` is
  passed as ``K_tab.reshape(nb0, nb1, 27)``, a free view of a C-contiguous array).
* Grids are strictly increasing, length >= 1, not necessarily uniform.
* Outside the grid the coordinate is **clamped** to the nearest edge (the
  estimates of ``b0``, ``b1`` are projected onto their bounds by the filter, so
  clamping only absorbs round-off; extrapolating gains would be unsafe).
* A NaN coordinate gives NaN outputs (it is not silently clamped).
* At a grid node the result equals the stored value bit for bit: the weights are
  exactly 0 and 1 there.

Because interpolation is linear in the table values, ``engine_controller`` never
forms the interpolated ``K``: it accumulates ``-(K_c x + k_c)`` of the four cell
corners with the bilinear weights.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..jit import kernel

EngineTables = namedtuple("EngineTables", [
    "K",        # (nb0, nb1, 3, 9) gain of u = -K x - k at each grid node (eq. 42)
    "k",        # (nb0, nb1, 3) affine term of u = -K x - k (eq. 42)
    "b0_grid",  # (nb0,) strictly increasing thrust b0 nodes (absolute lock position) [-]
    "b1_grid",  # (nb1,) strictly increasing thrust b1 nodes in [0, 1] [-]
])
"""Offline Theorem 4.1 tables of the engine-fault controller c1 (section 4.1.5).

Built by :func:`ftc_mc.design.theorem41.engine_fault_tables`; read by
:func:`engine_controller`.  ``k`` is the *negative* of the term the paper adds in
eq. (44): ``u = -K x - k``.
"""


@kernel(internal=True)
def locate(grid, x):
    """Cell index and fractional position of ``x`` in a sorted grid, clamped.

    Parameters
    ----------
    grid : ndarray, shape (n,)
        Strictly increasing nodes, ``n >= 1``.
    x : float
        Query coordinate.

    Returns
    -------
    i : int
        Left node of the cell, ``0 <= i <= max(n - 2, 0)``.
    t : float
        Position in the cell in [0, 1] (``x = grid[i] + t (grid[i+1] - grid[i])``);
        0 below the grid, 1 above it, NaN when ``x`` is NaN.  For ``n == 1``,
        ``i = 0`` and ``t = 0`` (constant table).
    """
    n = grid.shape[0]
    if n == 1:
        if x != x:
            return 0, np.nan
        return 0, 0.0
    if x != x:
        return 0, np.nan
    if x <= grid[0]:
        return 0, 0.0
    if x >= grid[n - 1]:
        return n - 2, 1.0
    # grid[i] <= x < grid[i + 1]
    i = np.searchsorted(grid, x, side="right") - 1
    if i > n - 2:
        i = n - 2
    return i, (x - grid[i]) / (grid[i + 1] - grid[i])


@kernel(internal=True)
def bilinear(table, x_grid, y_grid, x, y, out):
    """Bilinear interpolation of a table over its first two axes, clamped.

    Parameters
    ----------
    table : ndarray, shape (nx, ny, m)
        Values at the nodes ``(x_grid[i], y_grid[j])``; the last axis holds the
        ``m`` interpolated quantities (flatten trailing axes before the call).
    x_grid : ndarray, shape (nx,)
        Strictly increasing nodes of the first axis.
    y_grid : ndarray, shape (ny,)
        Strictly increasing nodes of the second axis.
    x, y : float
        Query point; clamped to the grid box.
    out : ndarray, shape (m,)
        Written in place with the interpolated values.
    """
    i, tx = locate(x_grid, x)
    j, ty = locate(y_grid, y)
    i1 = min(i + 1, x_grid.shape[0] - 1)
    j1 = min(j + 1, y_grid.shape[0] - 1)
    w00 = (1.0 - tx) * (1.0 - ty)
    w01 = (1.0 - tx) * ty
    w10 = tx * (1.0 - ty)
    w11 = tx * ty
    for c in range(table.shape[2]):
        out[c] = (w00 * table[i, j, c] + w01 * table[i, j1, c]
                  + w10 * table[i1, j, c] + w11 * table[i1, j1, c])


@kernel
def engine_controller(tables, b0, b1, x, u):
    """Engine-fault command ``u = -K(b0, b1) x - k(b0, b1)`` (eqs. 42, 44).

    The gain and affine term are interpolated bilinearly in ``(b0, b1)`` from the
    offline Theorem 4.1 tables (section 4.1.5); the saturation and excitation of
    eq. (44) are applied by the caller.

    Parameters
    ----------
    tables : EngineTables
        ``K`` (nb0, nb1, 3, 9), ``k`` (nb0, nb1, 3), ``b0_grid`` (nb0,),
        ``b1_grid`` (nb1,).
    b0 : float
        Thrust bias estimate (absolute lock position when locked) [-]; clamped.
    b1 : float
        Thrust effectiveness-loss estimate [-]; clamped to the grid.
    x : ndarray, shape (9,)
        State estimate (deviation from trim).
    u : ndarray, shape (3,)
        Written in place: command deviation from trim [throttle, rad, rad].
    """
    K = tables.K
    k = tables.k
    i, tx = locate(tables.b0_grid, b0)
    j, ty = locate(tables.b1_grid, b1)
    i1 = min(i + 1, tables.b0_grid.shape[0] - 1)
    j1 = min(j + 1, tables.b1_grid.shape[0] - 1)
    w00 = (1.0 - tx) * (1.0 - ty)
    w01 = (1.0 - tx) * ty
    w10 = tx * (1.0 - ty)
    w11 = tx * ty
    m = K.shape[2]
    n = K.shape[3]
    for r in range(m):
        a00 = k[i, j, r]
        a01 = k[i, j1, r]
        a10 = k[i1, j, r]
        a11 = k[i1, j1, r]
        for c in range(n):
            xc = x[c]
            a00 += K[i, j, r, c] * xc
            a01 += K[i, j1, r, c] * xc
            a10 += K[i1, j, r, c] * xc
            a11 += K[i1, j1, r, c] * xc
        u[r] = -(w00 * a00 + w01 * a01 + w10 * a10 + w11 * a11)
