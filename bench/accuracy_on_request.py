"""Accuracy on request against the independent reference: for each imposed-stress case of
tests/continuum/reference.STRESS_CASES, ``solve_stress(..., accuracy=TOL)`` at TOL = 1e-4 and 1e-6; prints a
markdown row per run: cells reached, CPU of the whole refinement, the worst relative error against the
cached reference, the range over the times of estimate / true error (>= 1: the estimate bounds it) and the
largest estimate over the largest error (what tests/continuum/test_accuracy.py bounds by 10).

    .venv/bin/python bench/accuracy_on_request.py
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.continuum.reference

from granstokes.continuum.solver import solve_stress  # noqa: E402

from tests.continuum import reference  # noqa: E402

ACCURACIES = (1e-4, 1e-6)


def main() -> None:
    print("| case | accuracy | cells reached | CPU [s] | worst relative error; estimate / true per time (min-max), "
          "largest estimate / largest error |")
    print("|---|---|---|---|---|")
    for name, (fr, mu_w_tilde) in reference.STRESS_CASES.items():
        exact = reference.cached(name)
        for accuracy in ACCURACIES:
            start = time.process_time()
            sol = solve_stress(fr, fr.mu_w_from_tilde(mu_w_tilde), reference.TIMES, accuracy=accuracy)
            cpu = time.process_time() - start
            parts = []
            for q in ("u_w", "delta"):
                true = np.abs(getattr(sol, q) - exact[q])
                ratio = sol.errors[q] / np.maximum(true, np.finfo(float).tiny)
                parts.append(f"{q} {np.max(true / np.abs(exact[q])):.1e} ({ratio.min():.1f}-{ratio.max():.1f}, "
                             f"{sol.errors[q].max() / true.max():.1f})")
            print(f"| {name} | {accuracy:g} | {sol.numerics.n_cells} | {cpu:.2f} | {'; '.join(parts)} |", flush=True)


if __name__ == "__main__":
    main()
