"""Numba kernels of the 6-DOF plant family: layout and nonlinear plant.

Imported only by the 6-DOF path (``ftc_mc.model.sixdof``, ``ftc-mc model --dof
6``); the longitudinal path never imports it, so its kernels are never compiled
or loaded by a longitudinal run.
"""
