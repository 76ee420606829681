"""The imposed speed's BDF compiled (continuum.speed_bdf) against scipy's BDF on the same system
(Numerics.compiled = False), in one process, alternating.  Prints the table for bench/RESULTS.md
"The speed compiled".

    PYTHONPATH=. .venv/bin/python bench/speed_compiled.py

Cases: the paper's three wall speeds and the disks' u~_w = 1 (tests/continuum/reference.py), t~ = 1e-4 ... 10
(bench/speed_solver.py TIMES), at the default accuracy 1e-6 (the solve on 512 cells and its companion on 256) and
one solve on 64 cells at the solver's defaults.  CPU time (time.process_time), best of ROUNDS; the first compiled
solve of the process (numba's import and its cache's load, ~0.4-0.6 s) is run and reported apart.
"""
from __future__ import annotations

import time

from granstokes.continuum.solver import Numerics, solve_speed

from bench.speed_solver import TIMES
from tests.continuum.reference import DISKS, PAPER

CASES = [("paper", PAPER, 0.198), ("paper", PAPER, 1.334), ("paper", PAPER, 4.629), ("disks", DISKS, 1.0)]
SETTINGS = {"accuracy 1e-6": dict(accuracy=1e-6), "64 cells": dict(n_cells=64)}
ROUNDS = 2


def timed(fr, u_w, compiled, kwargs):
    cells = {k: v for k, v in kwargs.items() if k == "n_cells"}
    start = time.process_time()
    sol = solve_speed(fr, u_w, TIMES, Numerics(compiled=compiled, **cells), accuracy=kwargs.get("accuracy"))
    return time.process_time() - start, sol


def main():
    first, _ = timed(PAPER, 1.334, True, SETTINGS["64 cells"])
    print(f"first compiled solve of the process (numba import, cache load, 64 cells): {first:.2f} s CPU\n")
    print("| case | u~_w | setting | scipy's BDF [s] | compiled [s] | ratio | steps scipy / compiled | "
          "max rel. difference mu_w, delta |")
    print("|---|---|---|---|---|---|---|---|")
    for name, fr, u_w in CASES:
        for label, kwargs in SETTINGS.items():
            best = {True: (float("inf"), None), False: (float("inf"), None)}
            for _ in range(ROUNDS):
                for compiled in (False, True):
                    cpu, sol = timed(fr, u_w, compiled, kwargs)
                    best[compiled] = min(best[compiled], (cpu, sol), key=lambda pair: pair[0])
            (slow, ref), (fast, ours) = best[False], best[True]
            diff = max(float(abs(getattr(ours, q) / getattr(ref, q) - 1).max()) for q in ("mu_w", "delta"))
            print(f"| {name} | {u_w:g} | {label} | {slow:.3f} | {fast:.3f} | {slow / fast:.1f} | "
                  f"{ref.stats.steps} / {ours.stats.steps} | {diff:.1e} |", flush=True)


if __name__ == "__main__":
    main()
