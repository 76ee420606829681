"""The imposed speed's BDF loop compiled (continuum.bdf) against scipy's own BDF on the same system
(tests/continuum/bdf_oracle.py), in one process, alternating.  Prints the table for bench/RESULTS.md
"The speed compiled".

    PYTHONPATH=. .venv/bin/python bench/speed_compiled.py

Cases: the paper's three wall speeds and the disks' u~_w = 1 (tests/continuum/reference.py), t~ = 1e-4 ... 10
(bench/speed_solver.py TIMES), one solve on CELLS cells on the solve's map at the solver's default tolerances.
CPU time (time.process_time), best of ROUNDS; the first compiled solve of the process (numba's import and its
cache's load, ~0.4-0.6 s) is run and reported apart.
"""
from __future__ import annotations

import time

from granstokes.continuum.integrators import integrate
from granstokes.continuum.problems import ImposedSpeed
from granstokes.continuum.solver import Numerics, map_for
from granstokes.continuum.steady import mu_w_for_speed

from bench.speed_solver import TIMES
from tests.continuum import bdf_oracle
from tests.continuum.reference import DISKS, PAPER

CASES = [("paper", PAPER, 0.198), ("paper", PAPER, 1.334), ("paper", PAPER, 4.629), ("disks", DISKS, 1.0)]
CELLS = (64, 256, 512)
ROUNDS = 2


def timed(fr, u_w, n, ours):
    numerics = Numerics(n_cells=n).for_drive("speed")
    pb = ImposedSpeed(fr, u_w, numerics.mesh(*map_for(fr, mu_w_for_speed(fr, u_w), "speed", TIMES[0])))
    options = dict(rtol=numerics.rtol, atol=numerics.atol, h0=numerics.initial_step * TIMES[0])
    start = time.process_time()
    states, stats = (integrate(pb, TIMES, method="bdf", **options) if ours
                     else bdf_oracle.integrate(pb, TIMES, **options))
    return time.process_time() - start, [pb.mu(x)[0] for x in states], stats.steps


def main():
    first = timed(PAPER, 1.334, 64, True)[0]
    print(f"first compiled solve of the process (numba import, cache load, 64 cells): {first:.2f} s CPU\n")
    print("| case | u~_w | cells | scipy's BDF [s] | compiled [s] | ratio | steps scipy / compiled | "
          "max rel. difference mu_w |")
    print("|---|---|---|---|---|---|---|---|")
    for name, fr, u_w in CASES:
        for n in CELLS:
            best = {True: (float("inf"),), False: (float("inf"),)}
            for _ in range(ROUNDS):
                for ours in (False, True):
                    best[ours] = min(best[ours], timed(fr, u_w, n, ours), key=lambda row: row[0])
            (slow, ref, ref_steps), (fast, mu_w, steps) = best[False], best[True]
            diff = max(abs(a / b - 1) for a, b in zip(mu_w, ref))
            print(f"| {name} | {u_w:g} | {n} | {slow:.3f} | {fast:.3f} | {slow / fast:.1f} | {ref_steps} / {steps} | "
                  f"{diff:.1e} |", flush=True)


if __name__ == "__main__":
    main()
