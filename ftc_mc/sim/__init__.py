"""From a validated config to the kernels' settings and inputs.

* :mod:`~ftc_mc.sim.setup`: a campaign, sweep or scenario config -> one
  :class:`~ftc_mc.sim.setup.SimSetup` (plant, filter model, detection per
  variant, belief, controllers and engine tables, truth plant, timing,
  validity, noise, initial covariance, gust model);
* :mod:`~ftc_mc.sim.estimator`: the filter, detection and belief settings of
  the linear plant;
* :mod:`~ftc_mc.sim.truth`: the truth plant (linear or nonlinear, gusts);
* :mod:`~ftc_mc.sim.inputs`: per-lane schedules and random streams -> trial
  inputs, for campaign trials, fault-free flights and scenarios;
* :mod:`~ftc_mc.sim.lanes`: records, and the runs of one set of inputs under
  several detections, alone or sharing their start.

Nothing here validates user values: the config schema (:mod:`ftc_mc.config`)
has done so, and the builders assert what they rely on.
"""
