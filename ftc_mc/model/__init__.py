"""The aircraft: airframes, equations, trim, linear models, turbulence, faults.

* airframes: :mod:`~ftc_mc.model.airframe` (the parameters),
  :mod:`~ftc_mc.model.presets` (each a copy of one cited parameter file),
  :mod:`~ftc_mc.model.airframe_files` (a user's own airframe YAML or linear
  model), :mod:`~ftc_mc.model.source` (where a run's plant comes from);
* the longitudinal model: :mod:`~ftc_mc.model.dynamics` (the X8's equations,
  evaluated through :mod:`ftc_mc.core.longitudinal.nonlinear`),
  :mod:`~ftc_mc.model.linear` (trim, linearisation, zero-order hold: eq. 1),
  :mod:`~ftc_mc.model.wind` (gust input matrices),
  :mod:`~ftc_mc.model.faults` (the fault model, eqs. 2-5);
* :mod:`~ftc_mc.model.turbulence`: Dryden turbulence, longitudinal and
  lateral;
* the 6-DOF model (6-DOF path only): :mod:`~ftc_mc.model.sixdof` (packing,
  trim, linearisation, named modes, its model file) and
  :mod:`~ftc_mc.model.trimmable` (the steady flights left with one elevon
  locked, straight or turning: the trimmable set);
* :mod:`~ftc_mc.model.summary`: what ``ftc-mc model`` prints.
"""
