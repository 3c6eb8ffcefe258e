"""Numba kernels on float64 arrays: no I/O, no configuration objects.

Settings enter as the namedtuples of :mod:`ftc_mc.core.longitudinal.settings`.
"""
