"""Compile the continuum solver's numba kernels into their disk cache (continuum/__pycache__ beside the sources, or
NUMBA_CACHE_DIR) by solving a small case of each drive through the solver's entry points, so that the first
``granstokes continuum`` after set-up starts at once.  The Makefile's install step runs it:

    .venv/bin/python -m granstokes.continuum.warmup
"""
from __future__ import annotations

import multiprocessing as mp
import os
import time
from concurrent.futures import ProcessPoolExecutor

#: the cases: the command's example friction, one output time; few cells, and an error estimate as the command makes
FRICTION = (0.3839, 0.6494)
MU_W_TILDE, U_W, TIMES = 0.5, 1.334, [1.0]


def _solve(drive: str) -> float:
    """Solve the small case of ``drive`` (compiling its kernels, or loading them from the cache): wall seconds."""
    from .rheology import Friction
    from .solver import Numerics, solve_speed, solve_stress

    fr = Friction(*FRICTION)
    solve, value = (solve_stress, fr.mu_w_from_tilde(MU_W_TILDE)) if drive == "stress" else (solve_speed, U_W)
    start = time.perf_counter()
    solve(fr, value, TIMES, Numerics(n_cells=16), estimate=True)
    return time.perf_counter() - start


def warm_up() -> dict:
    """Solve one imposed stress and one imposed speed, each in its own forked process when the machine has two cores
    (their kernels compile side by side): {drive: wall seconds}."""
    drives = ("stress", "speed")
    if (os.cpu_count() or 1) < 2 or "fork" not in mp.get_all_start_methods():
        return {d: _solve(d) for d in drives}
    with ProcessPoolExecutor(len(drives), mp_context=mp.get_context("fork")) as pool:
        return dict(zip(drives, pool.map(_solve, drives)))


def main() -> None:
    seconds = warm_up()
    print("granstokes: solver kernels ready (" + ", ".join(f"{d} {s:.1f} s" for d, s in seconds.items()) + ")")


if __name__ == "__main__":
    main()
