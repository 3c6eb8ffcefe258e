"""Offline synthesis, pure: gains and tables from models, no files.

* :mod:`~ftc_mc.design.lqr`: the discounted LQR of the paper's controllers;
* :mod:`~ftc_mc.design.theorem41`: Theorem 4.1, the engine-fault controller's
  tables over ``(b0, b1)``;
* :mod:`~ftc_mc.design.terminal`: the terminal costs J^N of the controller
  selection;
* :mod:`~ftc_mc.design.lateral`: the 6-DOF lateral loop (wings level and
  heading hold), and c0 and c1 on the whole 6-DOF model (6-DOF path only);
* :mod:`~ftc_mc.design.lock_turn`: the steady-turn LQR of one locked elevon
  (throttle and healthy elevon) and its table over lock positions, which the
  ``lock_turn`` controller flies; on the linear plant the table is designed on
  the linear model's own steady flights
  (:class:`ftc_mc.model.trimmable.LinearSteady`).

Designs that take long are cached on disk by :mod:`ftc_mc.cache`, which the
callers use; nothing here imports :mod:`ftc_mc.io` or :mod:`ftc_mc.cache`
(``tests/test_structure.py``).
"""
