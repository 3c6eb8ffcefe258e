"""Numba kernels of the 6-DOF plant family.

* :mod:`~ftc_mc.core.sixdof.layout`: the family's names and indices (its
  ``Layout``);
* :mod:`~ftc_mc.core.sixdof.plant`: the nonlinear plant, and the linear
  plant's step and output map, shared by the truth and the lock-turn rollouts;
* :mod:`~ftc_mc.core.sixdof.truth`: the trial's truth stage on the 6-DOF path
  (lateral autopilot, faults, gusts, plant, measurements), reached through
  ``longitudinal/plant.truth``'s dispatcher by import path;
* :mod:`~ftc_mc.core.sixdof.loop`: the command the paper's loop sends on the
  flying wing (its controllers' command plus the lateral autopilot's aileron,
  or the coupled laws), which the truth stage sends and the selection predicts
  with;
* :mod:`~ftc_mc.core.sixdof.monitor`: the side monitor flown beside the
  scheme: an augmented 6-DOF filter (its prediction linear, the airframe's
  equations, or the extended filter in the gust states' wind) and a windowed
  GLR per actuator, reached through ``longitudinal/trial.side_monitor``'s
  dispatcher;
* :mod:`~ftc_mc.core.sixdof.lockturn`: the lock-turn law a ``lock_turn``
  design flies once the monitor names an elevon (with the opt-in rocking law
  where no steady flight exists and the opt-in rollout guard), its opt-in
  probe and hand-back of a partial loss, and the block such a design's resets
  open, chosen by the monitor;
* :mod:`~ftc_mc.core.sixdof.selection`: a ``lock_turn_selected`` design's
  belief and eqs. 45-47 among c0, c1 and the lock-turn controllers of either
  elevon, each predicted on the plant's model (``action_cost``, also the
  terminal costs' offline flights), reached through
  ``longitudinal/trial.six_dof_selection``'s dispatcher on that design's path
  only;
* :mod:`~ftc_mc.core.sixdof.kinds`: the 6-DOF designs' ``Reconfig.kind`` codes.

Imported only by the 6-DOF path (``ftc_mc.model.sixdof``, ``ftc-mc model --dof
6``); the longitudinal path never imports it, so its kernels are never compiled
or loaded by a longitudinal run.
"""
