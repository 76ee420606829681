"""The registry of time integrators: which implementation integrates a problem with a method.

``integrate(problem, t_out, method=..., compiled=True, ...)`` runs the problem's compiled kernel where it has one
and the options allow it (an adaptive DIRK for a problem with ``compiled_dirk``: continuum.stress_dirk; bdf with
its bordered wall Newton for a problem with ``compiled_bdf``: continuum.speed_bdf), else continuum.stepper's
Python integrators.  ``compiled=False`` always runs the Python, the compiled kernels' reference.
"""
from __future__ import annotations

from . import stepper
from .stepper import MAX_STEPS, NEWTON_TOL, TABLEAUX


def _compiled_dirk(problem, method, options) -> bool:
    tab = TABLEAUX.get(method)
    return (tab is not None and tab.err is not None and getattr(problem, "compiled_dirk", False)
            and options.get("fixed_times") is None and options.get("resume") is None)


def _compiled_bdf(problem, method, options) -> bool:
    return (method == "bdf" and getattr(problem, "compiled_bdf", False) and options.get("resume") is None
            and options.get("bordered", True) and options.get("wall_newton", True))


def integrate(problem, t_out, *, method: str = "sdirk4", compiled: bool = True, rtol=1e-6, atol=1e-8, h0=1e-9,
              newton_tol=NEWTON_TOL, observer=None, max_steps=MAX_STEPS, **options):
    """``stepper.integrate``'s contract (states at ``t_out``, StepStats), by the compiled kernel when ``compiled``
    and the problem and options have one (numba is imported then, ~0.4 s once a process)."""
    common = {"rtol": rtol, "atol": atol, "h0": h0, "observer": observer, "max_steps": max_steps}
    if compiled and _compiled_dirk(problem, method, options):
        from .stress_dirk import integrate_stress

        return integrate_stress(problem, t_out, TABLEAUX[method], newton_tol=newton_tol,
                                repeat_cap=options.get("repeat_cap", True), **common)
    if compiled and _compiled_bdf(problem, method, options):
        from .speed_bdf import integrate_speed

        return integrate_speed(problem, t_out, **common)
    return stepper.integrate(problem, t_out, method=method, newton_tol=newton_tol, **common, **options)
