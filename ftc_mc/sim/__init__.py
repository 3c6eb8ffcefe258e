"""From a validated config to the kernels' settings and inputs.

* :mod:`~ftc_mc.sim.setup`: a campaign, sweep or scenario config -> one
  :class:`~ftc_mc.sim.setup.SimSetup` (plant, filter model, detection per
  variant, belief, controllers and engine tables, truth plant, timing,
  validity, noise, initial covariance, gust model);
* :mod:`~ftc_mc.sim.designs`: each detection design's filter model, detection
  (Table 1 at its thresholds, residual test, window) and initial covariance;
* :mod:`~ftc_mc.sim.estimator`: the filter, detection and belief settings of
  the linear plant (Q, R, Table 1, mode boxes);
* :mod:`~ftc_mc.sim.truth`: the truth plant (linear, nonlinear or 6-DOF,
  gusts); :mod:`~ftc_mc.sim.noise`: the 6-DOF lateral loop's measurement noise;
* :mod:`~ftc_mc.sim.monitor`: the 6-DOF side monitor's settings and its
  lock-turn table (6-DOF path only);
* :mod:`~ftc_mc.sim.selection`: a ``lock_turn_selected`` design's belief
  boxes on the side monitor's six parameters, its 6-DOF weights and its
  (4, 4) terminal costs (6-DOF path only);
* :mod:`~ftc_mc.sim.inputs`: per-lane schedules and random streams -> trial
  inputs, for campaign trials, fault-free flights and scenarios;
* :mod:`~ftc_mc.sim.lanes`: records, and the runs of one set of inputs under
  several detections, alone or sharing their start;
* :mod:`~ftc_mc.sim.paths`: the compile path of a design on a truth plant
  (:func:`~ftc_mc.sim.paths.path_of`, the one place that maps settings to a
  path);
* :mod:`~ftc_mc.sim.compiling`: one compile of each path at a time per kernel
  cache (the compile lock and notice);
* :mod:`~ftc_mc.sim.compile_helper`: the second process that compiles part of
  a path's stages meanwhile, from the compile plan ``compile_plan.pkl``
  (written by ``scripts/maintenance/make_compile_plan.py``).

Nothing here validates user values: the config schema (:mod:`ftc_mc.config`)
has done so, and the builders assert what they rely on.
"""
