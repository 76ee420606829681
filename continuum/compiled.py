"""The numba backend of the time-stepping loops: ``compile_loop`` compiles a loop built by continuum.stepper or
continuum.bdf, with the ``jitable`` functions it calls (continuum.kernels), into numba's disk cache; and the one line
on stderr that a loop must compile.  Imported only when a loop is compiled (numba costs ~0.4 s to import)."""
from __future__ import annotations

import sys

from numba import njit
from numba.core import event
from numba.extending import register_jitable

from .kernels import JITABLE

#: every loop's numba options: cached on disk (continuum/__pycache__; the loop's closure holds kernels.source_key,
#: so the cache follows every file compiled in), and numpy's floating-point semantics (a division by zero gives inf
#: or NaN, as in Python, which the loops then treat as an inadmissible iterate, instead of raising ZeroDivisionError)
JIT = dict(cache=True, error_model="numpy")
_REGISTERED: set = set()


def compile_loop(loop, *inner):
    """``loop`` compiled with JIT's options; ``inner``: the plain functions of its closure that it calls."""
    for fn in (*JITABLE, *inner):
        if fn not in _REGISTERED:
            register_jitable(error_model=JIT["error_model"])(fn)
            _REGISTERED.add(fn)
    return njit(**JIT)(loop)


#: the loops' modules, the drive each compiles for and about how long a first solve compiles it (wall on 2 cores,
#: bench/RESULTS.md "First solve after set-up"; the set-up compiles them ahead, continuum.warmup)
DRIVES = {f"{__package__}.stepper": ("imposed-stress", 15), f"{__package__}.bdf": ("imposed-speed", 20)}


class _CompileNotice(event.Listener):
    """Says on stderr, once a drive and process, that its loop compiles: numba sends "numba:compile" only when a
    function is not in memory nor in its disk cache for these argument types, just before compiling it."""

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
