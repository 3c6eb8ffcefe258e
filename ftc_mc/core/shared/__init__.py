"""Kernels shared by the plant families, shape-generic over states, outputs and
lanes, and the compile paths.

* :mod:`~ftc_mc.core.shared.belief`: the mode likelihood and the Bayes belief
  update (eqs. 12-14);
* :mod:`~ftc_mc.core.shared.glr`: the windowed GLR test of the residuals;
* :mod:`~ftc_mc.core.shared.excitation`: the excitation signals (doublet,
  3-2-1-1) and the saturation with excitation headroom (eqs. 15-16);
* :mod:`~ftc_mc.core.shared.interp`: interpolation of Theorem 4.1's tables
  and the engine-fault controller c1;
* :mod:`~ftc_mc.core.shared.dryden`: Dryden gusts;
* :mod:`~ftc_mc.core.shared.paths`: the compile paths, and the dispatchers
  that compile only the implementation a path names.
"""
