"""Kernels shared by the plant families: shape-generic over states,
outputs and lanes (belief, GLR, excitation signals, interpolation, Dryden gusts)
and the compile paths."""
