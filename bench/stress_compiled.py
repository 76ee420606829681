"""An imposed stress's adaptive DIRK loop compiled against the same loop run as Python (Numerics.compiled = False;
continuum.stepper), in one process, alternating.  Prints the table for bench/RESULTS.md "The stress compiled".

    PYTHONPATH=. .venv/bin/python bench/stress_compiled.py

Cases: the paper's three stresses and the disks' mu~_w = 0.3 (tests/continuum/reference.py), t~ = 1e-4 ... 10
(bench/speed_solver.py TIMES), one solve on CELLS cells at the drive's default tolerances (the Python loop runs the
same element kernels uncompiled: at the 512-1024 cells of a 1e-6 request it would take minutes).  CPU time
(time.process_time), best of ROUNDS, after one solve that pays numba's import and cache load.
"""
from __future__ import annotations

import time

import numpy as np
from granstokes.continuum.solver import Numerics, solve_stress

from bench.speed_solver import TIMES
from tests.continuum.reference import DISKS, PAPER

CASES = [("paper", PAPER, 0.9), ("paper", PAPER, 0.5), ("paper", PAPER, 0.1), ("disks", DISKS, 0.3)]
ROUNDS = 2
CELLS = 64


def timed(fr, mu_w_tilde, compiled):
    start = time.process_time()
    sol = solve_stress(fr, fr.mu_w_from_tilde(mu_w_tilde), TIMES, Numerics(n_cells=CELLS, compiled=compiled))
    return time.process_time() - start, sol


def main():
    first, _ = timed(PAPER, 0.5, True)
    print(f"first compiled solve of the process (numba's import and cache load included): {first:.2f} s CPU\n")
    print("| friction | mu~_w | cells | Python [s] | compiled [s] | ratio | max rel. difference u~_w, delta |")
    print("|---|---|---|---|---|---|---|")
    for name, fr, mu_w_tilde in CASES:
        best = {True: (float("inf"), None), False: (float("inf"), None)}
        for _ in range(ROUNDS):
            for compiled in (False, True):
                cpu, sol = timed(fr, mu_w_tilde, compiled)
                best[compiled] = min(best[compiled], (cpu, sol), key=lambda pair: pair[0])
        (slow, ref), (fast, ours) = best[False], best[True]
        diff = max(float(np.max(np.abs(getattr(ours, q) / getattr(ref, q) - 1))) for q in ("u_w", "delta"))
        print(f"| {name} | {mu_w_tilde:g} | {ours.numerics.n_cells} | {slow:.3f} | {fast:.3f} | {slow / fast:.1f} | "
              f"{diff:.1e} |", flush=True)


if __name__ == "__main__":
    main()
