"""The LAPACK routines of the time steppers (banded LU gbtrf/gbtrs, symmetric tridiagonal L D L^T
pttrf/pttrs) from scipy's f2py wrapper module, without ``import scipy.linalg``.

scipy.linalg's package init imports scipy._lib._array_api, which clones numpy's namespace and so imports
numpy.f2py, .testing, .ma, .random and .polynomial: 0.11 s of the package's 0.18 s, most of a CLI
solve's start-up (bench/RESULTS.md, "Start-up").  The wrapper module ``scipy.linalg._flapack`` is the one
``scipy.linalg.lapack`` re-exports; it is loaded from its file and registered under its own name, so a
later ``import scipy.linalg`` reuses it (tests/granstokes/test_lazy_imports.py checks that the routines
are scipy.linalg.lapack's).
"""
from __future__ import annotations

import importlib.machinery
import importlib.util
import sys
from pathlib import Path

import scipy

WRAPPERS = "scipy.linalg._flapack"
ROUTINES = ("dgbtrf", "dgbtrs", "dpttrf", "dpttrs")


def _wrappers():
    """The wrapper module, loaded from its file; scipy.linalg.lapack itself (the slow, public way) if this
    scipy lays its files out otherwise."""
    if WRAPPERS in sys.modules:
        return sys.modules[WRAPPERS]
    folder = Path(scipy.__file__).parent / "linalg"
    paths = [p for suffix in importlib.machinery.EXTENSION_SUFFIXES if (p := folder / f"_flapack{suffix}").exists()]
    try:
        spec = importlib.util.spec_from_file_location(WRAPPERS, paths[0])
        module = importlib.util.module_from_spec(spec)
        sys.modules[WRAPPERS] = module
        spec.loader.exec_module(module)
        return module
    except (IndexError, ImportError, OSError):
        sys.modules.pop(WRAPPERS, None)
        import scipy.linalg.lapack as public

        return public


_flapack = _wrappers()
if not all(hasattr(_flapack, name) for name in ROUTINES):  # a wrapper module without them: the public way
    import scipy.linalg.lapack as _flapack
dgbtrf, dgbtrs, dpttrf, dpttrs = (getattr(_flapack, name) for name in ROUTINES)
