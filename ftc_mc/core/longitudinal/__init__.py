"""The longitudinal family's kernels: the paper's plant, its filters, Table 1,
the controllers and their selection, and the trial loop.

* :mod:`~ftc_mc.core.longitudinal.settings`: the settings namedtuples
  (``Scheme``, ``Flight``, ``TrialInputs``, ``TrialRecord``, ...);
* :mod:`~ftc_mc.core.longitudinal.batch`: the paper's 14-state filter,
  lane-interleaved, with its block structure;
* :mod:`~ftc_mc.core.longitudinal.gustfilter`: the general filter, dense, with
  gust or sensor-bias states and the airframe's prediction (extended filter);
* :mod:`~ftc_mc.core.longitudinal.signature`: Table 1 as data, and the
  covariance reset;
* :mod:`~ftc_mc.core.longitudinal.nonlinear`: the X8's longitudinal equations
  (RK4);
* :mod:`~ftc_mc.core.longitudinal.plant`: the truth step (eq. 2, gusts,
  linear or nonlinear plant, measurements, sensor faults);
* :mod:`~ftc_mc.core.longitudinal.control`: the controllers and their
  selection (eqs. 45-47);
* :mod:`~ftc_mc.core.longitudinal.stages`: the stages of a trial step;
* :mod:`~ftc_mc.core.longitudinal.trial`: the loop over them
  (:func:`~ftc_mc.core.longitudinal.trial.advance`);
* :mod:`~ftc_mc.core.longitudinal.workspace`: work arrays.

Each 0.1 s step of :func:`~ftc_mc.core.longitudinal.trial.advance` runs
``commands`` (controller, saturation, excitation), ``truth_step`` (eq. 2,
gusts, plant, measurement), ``record_cost``, ``filter_update`` (the path's
filter: predict, residuals, Table 1, reset, update, projection),
``check_validity``, ``handle_resets`` (excitation requests and the design's
excitation policy), ``record_step``, and every second ``reconfigure`` (belief,
eqs. 12-14; the controller selection, eqs. 45-47); the results land in a
``TrialRecord``.
"""
