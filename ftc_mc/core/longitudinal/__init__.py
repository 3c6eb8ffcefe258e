"""The longitudinal family's kernels: the paper's plant (linear and
nonlinear), its 14-state filter and the general filter, Table 1, the
controllers and their selection, and the trial loop."""
