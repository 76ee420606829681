"""numba kernels shared by the compiled steppers (continuum.speed_bdf, continuum.stress_dirk): the banded LU of
their Newton matrices, the Laplacian's stencil sums, the weighted RMS norm, and the compiling of a plain function
of continuum.problems (one definition, run by Python and compiled); and the one line on stderr that a kernel must
compile."""
from __future__ import annotations

import math
import sys
import types

from numba import njit
from numba.core import event

#: every kernel's numba options: cached on disk (continuum/__pycache__; see BUILT_FROM in the modules that build
#: these kernels in), and numpy's floating-point semantics (a division by zero gives inf or NaN, as in the Python
#: code, which the steppers then treat as an inadmissible iterate, instead of raising ZeroDivisionError)
JIT = dict(cache=True, error_model="numpy")


def jit(fn):
    """``fn`` compiled with JIT's options."""
    return njit(**JIT)(fn)


#: the modules whose kernels a drive calls from Python, their drive and about how long a first solve compiles them
#: (wall on 2 cores: 10-13 s and 11-18 s measured, bench/RESULTS.md "First solve after set-up"; the set-up compiles
#: them ahead, continuum.warmup)
DRIVES = {f"{__package__}.stress_dirk": ("imposed-stress", 15), f"{__package__}.speed_bdf": ("imposed-speed", 20)}


class _CompileNotice(event.Listener):
    """Says on stderr, once a drive and process, that its kernels compile: numba sends "numba:compile" only when a
    kernel is not in memory nor in its disk cache for these argument types, just before compiling it."""

    def __init__(self):
        self.told = set()

    def on_start(self, ev):
        module = ev.data["dispatcher"].py_func.__module__
        if module in DRIVES and module not in self.told:
            self.told.add(module)
            drive, seconds = DRIVES[module]
            print(f"granstokes: compiling the {drive} solver's kernels once (about {seconds} s); later runs start at "
                  "once", file=sys.stderr, flush=True)

    def on_end(self, ev):
        pass


event.register("numba:compile", _CompileNotice())


def compile_function(fn, **replaced):
    """``fn`` compiled, its globals' functions replaced by compiled ones (the same source, one definition)."""
    return jit(types.FunctionType(fn.__code__, {**fn.__globals__, **replaced}, fn.__name__))


def digest(*modules) -> str:
    """A short hash of these modules' source files: numba's cache of a kernel checks only its own file, so a module
    whose kernels build in code from others records their digest (BUILT_FROM) and changes with it
    (tests/continuum/test_compiled_cache.py)."""
    import hashlib
    import inspect

    h = hashlib.sha256()
    for module in modules:
        h.update(inspect.getsource(module).encode())
    return h.hexdigest()[:16]


@jit
def laplacians(x, tau0, tau, lap, cols, weights):
    """d2 tau~/dy~2 at nodes 1..N-1 into ``lap`` (continuum.mesh.Stencil: cols, weights); ``tau`` (N + 1 values)
    gets tau~ at every node: tau0 at the wall, x[1:] inside, 1 at the bottom (eq. BCStokesEqn)."""
    n = len(x)
    tau[0] = tau0
    tau[1:n] = x[1:]
    tau[n] = 1.0
    for i in range(len(lap)):
        total = 0.0
        for k in range(cols.shape[1]):
            total += weights[i, k] * tau[cols[i, k]]
        lap[i] = total


@jit
def rms(v, scale):
    """sqrt(mean((v/scale)^2)), the steppers' error and Newton norm."""
    total = 0.0
    for i in range(len(v)):
        total += (v[i] / scale[i]) ** 2
    return math.sqrt(total / len(v))


@jit
def band_lu(ab, piv, kl, ku):
    """Factorise A in place, A[i, j] = ab[kl + ku + i - j, j] (rows 0..kl-1 of ab: room for the fill-in), by partial
    pivoting (LAPACK dgbtf2), the pivots stored as their reciprocals.  Returns U's upper bandwidth for band_solve: ku
    if no rows were swapped, kl + ku if some were; -1 if A is singular."""
    n = ab.shape[1]
    kv = kl + ku
    ju = 0
    upper = ku
    for j in range(n):
        km = min(kl, n - 1 - j)
        jp, big = 0, abs(ab[kv, j])
        for r in range(1, km + 1):
            if abs(ab[kv + r, j]) > big:
                jp, big = r, abs(ab[kv + r, j])
        piv[j] = j + jp
        if big == 0.0:
            return -1
        ju = max(ju, min(j + ku + jp, n - 1))
        if jp != 0:
            upper = kv
            for c in range(j, ju + 1):
                a, b = kv + j - c, kv + j + jp - c
                ab[a, c], ab[b, c] = ab[b, c], ab[a, c]
        pivot = ab[kv, j]
        for r in range(1, km + 1):
            ab[kv + r, j] /= pivot
        for c in range(j + 1, ju + 1):
            u = ab[kv + j - c, c]
            if u != 0.0:
                for r in range(1, km + 1):
                    ab[kv + j + r - c, c] -= ab[kv + r, j] * u
        ab[kv, j] = 1.0 / pivot
    return upper


@jit
def band_solve(ab, piv, kl, ku, upper, b):
    """b = A^-1 b from ``band_lu``'s factors and its upper bandwidth (LAPACK dgbtrs)."""
    n = ab.shape[1]
    kv = kl + ku
    for j in range(n - 1):
        lm = min(kl, n - 1 - j)
        m = piv[j]
        if m != j:
            b[m], b[j] = b[j], b[m]
        bj = b[j]
        for r in range(1, lm + 1):
            b[j + r] -= ab[kv + r, j] * bj
    for j in range(n - 1, -1, -1):
        bj = b[j] * ab[kv, j]
        b[j] = bj
        for r in range(max(0, j - upper), j):
            b[r] -= ab[kv + r - j, j] * bj
