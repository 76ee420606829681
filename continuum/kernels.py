"""The plain functions on arrays that the time-stepping loops are built from: a problem's rate, Newton matrix and
projection (continuum.problems), and the shared band LU, stencil sums and weighted norm below.

Each is written once.  Python runs it as it is; a loop built with ``compiled=True`` (continuum.stepper,
continuum.bdf) compiles it into itself (numba, continuum.compiled).  ``jitable`` only marks a function: numba is
imported when a loop is compiled, not when a problem is built.
"""
from __future__ import annotations

import hashlib
import inspect
import math
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

#: every function marked ``jitable`` (continuum.compiled registers them with numba before it compiles a loop)
JITABLE: list = []
#: the source text of each module whose functions a loop compiles in, as it was when the module was imported (so that
#: a file edited under a running process does not key that process's compiled code), and of continuum.compiled (its
#: numba options)
_TEXTS: dict[str, str] = {"compiled": (Path(__file__).with_name("compiled.py")).read_text()}


def _text(module) -> str:
    return _TEXTS.setdefault(module.__name__, inspect.getsource(module))


def jitable(fn):
    """Mark ``fn`` as callable from a compiled loop; returns ``fn`` itself."""
    JITABLE.append(fn)
    _text(inspect.getmodule(fn))
    return fn


def source_key(*functions) -> str:
    """A short hash of the source of the modules that define ``functions``, of this module and of the numba options:
    a compiled loop holds it in its closure, and numba's cache keys a closure by its cells, so the loop recompiles
    when any code it compiles in changes (numba checks only the loop's own file)."""
    h = hashlib.sha256(_TEXTS["compiled"].encode())
    modules = {inspect.getmodule(fn).__name__: inspect.getmodule(fn) for fn in (*functions, source_key)}
    for name in sorted(modules):
        h.update(_text(modules[name]).encode())
    return h.hexdigest()[:16]


class DirkKernels(NamedTuple):
    """A problem's side of the DIRK loop: plain functions on arrays (continuum.kernels), ``data`` their problem's
    arrays and constants (a problem's ``dirk_kernels``; continuum.stepper).

    rate(x, t, f, data): f = F(x, t).  factor(x, t, dh, lu, data) -> bool: ``lu`` (from ``factors``) holds the
    factors of M - dh J(x, t); False if singular.  refresh(lu, x, t, data): the factors' parts that change fastest, at
    the Newton iterate x (an imposed speed's dense wall row).  solve(lu, r, data): r = (M - dh J)^-1 r in place.
    project(x, data): x onto the algebraic constraints (which do not depend on t), in place.  fraction(x, dx, data)
    -> float: the largest share of a Newton update to take (1: no limit).  t is the stage's time (a time-dependent
    wall: continuum.load.Load); a problem whose rate does not depend on it ignores it."""

    rate: Callable
    factor: Callable
    refresh: Callable
    solve: Callable
    project: Callable
    fraction: Callable


class BdfKernels(NamedTuple):
    """A problem's side of the BDF loop: plain functions on arrays (continuum.kernels), ``data`` their problem's arrays
    and constants (a problem's ``bdf_kernels``; continuum.bdf).

    project(z, x, data) -> float: x = (x_0, z) with x_0 from the constraint (NaN where inadmissible); returns the
    constraint's magnitude (the scale of x_0's round-off).  rate(x, t, f, data): f = F(x, t) at the interior.
    jacobian(x, t, band, data): band[ku + i - j, j] = dF_i/dz_j.  wall(x, t, row0, column, data): the constraint's
    gradient (row0) and dF_i/dx_0 at the first rows (column)."""

    project: Callable
    rate: Callable
    jacobian: Callable
    wall: Callable


@jitable
def laplacians(x, tau0, tau, lap, cols, weights):
    """d2 tau~/dy~2 at nodes 1..N-1 into ``lap`` (continuum.mesh.Stencil: cols, weights); ``tau`` (N + 1 values)
    gets tau~ at every node: tau0 at the wall, x[1:] inside, 1 at the bottom (eqs. (2.8)-(2.9))."""
    n = len(x)
    tau[0] = tau0
    tau[1:n] = x[1:]
    tau[n] = 1.0
    for i in range(len(lap)):
        total = 0.0
        for k in range(cols.shape[1]):
            total += weights[i, k] * tau[cols[i, k]]
        lap[i] = total


@jitable
def rms(v, scale):
    """sqrt(mean((v/scale)^2)), summed in index order."""
    total = 0.0
    for i in range(len(v)):
        total += (v[i] / scale[i]) ** 2
    return math.sqrt(total / len(v))


@jitable
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


@jitable
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
