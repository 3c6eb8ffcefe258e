"""ftc_mc pins OpenBLAS's kernels before numpy loads it (ftc_mc/blas.py), so a
run's setup matches to the bit on every x86-64 machine with AVX2."""

import os
import platform
import subprocess
import sys

import pytest

from ftc_mc.blas import CORETYPE, has_avx2

PROBE = """
import ctypes, glob, os, sys
import ftc_mc, numpy, scipy.linalg
names = []
for lib in sorted(glob.glob(os.path.join(os.path.dirname(numpy.__file__), '..', '*.libs',
                                         '*openblas*'))):
    dll = ctypes.CDLL(lib)
    for fn in ('scipy_openblas_get_corename64_', 'scipy_openblas_get_corename',
               'openblas_get_corename'):
        if hasattr(dll, fn):
            f = getattr(dll, fn)
            f.restype = ctypes.c_char_p
            names.append(f().decode())
print(' '.join(names))
"""


def corenames(env):
    done = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True,
                          text=True, check=True)
    return done.stdout.split()


needs_x86 = pytest.mark.skipif(
    platform.machine().lower() not in ("x86_64", "amd64") or not has_avx2(),
    reason="the pin applies to x86-64 with AVX2 only")


@needs_x86
def test_numpy_and_scipy_run_the_pinned_kernels():
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"}
    names = corenames(env)
    assert names and all(n == CORETYPE for n in names), names


@needs_x86
def test_a_users_own_choice_is_kept():
    env = {**os.environ, "OPENBLAS_CORETYPE": "Sandybridge"}
    names = corenames(env)
    assert names and all(n == "Sandybridge" for n in names), names
