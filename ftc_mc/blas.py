"""One BLAS kernel family on every x86-64 machine, so results match to the bit.

The setup of a run (trim, the LQR gains, Theorem 4.1's tables, the terminal
costs, the initial covariance) calls LAPACK and BLAS through numpy and scipy.
Their OpenBLAS picks its kernels by the CPU it runs on, and the kernels of two
CPUs differ in the last bits of a product: measured here, the golden files of
``tests/golden`` written on an Intel AVX-512 machine (OpenBLAS ``SkylakeX``)
did not match to the bit on an AMD EPYC one (``Zen``), and every trial that
fed on those gains drifted from them.  Trials are simulated by the Numba
kernels, whose arithmetic does not depend on the CPU (no fast-math).

:func:`pin_openblas` asks OpenBLAS for its ``Haswell`` kernels (AVX2, on every
x86-64 CPU of the last decade) through ``OPENBLAS_CORETYPE``, which OpenBLAS
reads once, when numpy or scipy first loads it; so ``ftc_mc`` calls it before
it imports numpy.  A user's own ``OPENBLAS_CORETYPE`` is kept, as is any
machine that is not x86-64 with AVX2 (its results are its own).  Importing
numpy before ``ftc_mc`` leaves OpenBLAS on its own choice.
"""

from __future__ import annotations

import os
import platform

CORETYPE = "Haswell"
"""The OpenBLAS kernels every x86-64 run uses (AVX2)."""


def has_avx2() -> bool:
    """Whether this CPU has AVX2, read from ``/proc/cpuinfo`` (False where
    there is none to read)."""
    try:
        with open("/proc/cpuinfo", encoding="ascii", errors="replace") as f:
            for line in f:
                if line.startswith("flags"):
                    return " avx2" in line
    except OSError:
        return False
    return False


def pin_openblas() -> str | None:
    """Set ``OPENBLAS_CORETYPE`` to :data:`CORETYPE` unless it is set already,
    on x86-64 with AVX2; return the value in force (``None``: OpenBLAS chooses)."""
    if "OPENBLAS_CORETYPE" not in os.environ and (
            platform.machine().lower() in ("x86_64", "amd64") and has_avx2()):
        os.environ["OPENBLAS_CORETYPE"] = CORETYPE
    return os.environ.get("OPENBLAS_CORETYPE")
