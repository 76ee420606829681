"""The registry of time integrators: every method by name, its integrate function and what it takes.

``integrate(problem, t_out, method=..., compiled=True, ...)`` looks the method up in METHODS and runs it: the DIRKs
(continuum.stepper; their loop compiled with the problem's kernels where the problem has its own), BDF
(continuum.bdf), explicit Euler (fixed steps only) and the solve_ivp baselines (scipy's BDF and Radau on the
differential rows of a problem whose algebraic rows its ``project`` fixes).  ``register`` adds one.
"""
from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import stepper
from .stepper import MAX_STEPS, NEWTON_TOL, TABLEAUX, StepStats


@dataclass(frozen=True)
class Method:
    """A registered method: ``run(problem, t_out, **options)`` -> (states at t_out, StepStats); ``adaptive``: chooses
    its steps (else fixed_times are required); ``kind``: "project" (the package's), "baseline" (scipy's solve_ivp)."""

    name: str
    run: Callable
    adaptive: bool = True
    kind: str = "project"


METHODS: dict[str, Method] = {}


def register(name: str, *, adaptive: bool = True, kind: str = "project"):
    """Decorator: register ``fn`` as the method ``name``."""
    def add(fn):
        METHODS[name] = Method(name, fn, adaptive, kind)
        return fn
    return add


def _dirk(name):
    def run(problem, t_out, **options):
        return stepper.integrate(problem, t_out, method=name, **options)
    return run


for _name, _tab in TABLEAUX.items():
    register(_name, adaptive=_tab.err is not None)(_dirk(_name))


@register("bdf")
def _bdf(problem, t_out, *, fixed_times=None, newton_tol=None, **options):
    """continuum.bdf; its Newton tolerance is scipy's rule from rtol (``newton_tol`` is the DIRKs')."""
    from .bdf import integrate as integrate_bdf

    if fixed_times is not None:
        raise ValueError("method 'bdf' chooses its own steps: fixed_times needs a DIRK method")
    return integrate_bdf(problem, t_out, **options)


@register("explicit-euler", adaptive=False)
def _euler(problem, t_out, *, fixed_times=None, observer=None, compiled=None, rtol=None, atol=None, h0=None,
           newton_tol=None, max_steps=None):
    """continuum.stepper.explicit_euler on ``fixed_times`` (no error control: the tolerances do not apply)."""
    if fixed_times is None:
        raise ValueError("method 'explicit-euler' has no error estimate: give fixed_times")
    return stepper.explicit_euler(problem, t_out, fixed_times, observer)


def _solve_ivp(method):
    def run(problem, t_out, *, rtol=1e-6, atol=1e-8, observer=None, fixed_times=None, compiled=None, h0=None,
            newton_tol=None, max_steps=None):
        """scipy's solve_ivp(``method``) on the differential rows z, the algebraic rows from ``problem.project``
        (which must not depend on z: an imposed stress), with the problem's banded Jacobian as a sparse matrix; its
        own first step and step count (``h0``, ``max_steps`` do not apply); ``steps`` reports the output times."""
        from scipy.integrate import solve_ivp

        if observer is not None or fixed_times is not None:
            raise ValueError(f"solve_ivp-{method} takes neither an observer nor fixed_times")

        t_out = np.asarray(t_out, dtype=float)
        differential = np.flatnonzero(problem.mass > 0)
        x = problem.project(problem.initial().astype(float))

        def state(z):
            full = x.copy()
            full[differential] = z
            return problem.project(full)

        def rhs(_, z):
            return problem.rate(state(z))[differential]

        def jac(_, z):
            return problem.jacobian(state(z)).interior()

        start = time.process_time()
        sol = solve_ivp(rhs, (0.0, t_out[-1]), x[differential], method=method, t_eval=t_out, jac=jac, rtol=rtol,
                        atol=atol)
        if not sol.success:
            raise stepper.StepperFailure(f"solve_ivp({method}) failed: {sol.message}")
        states = np.array([state(z) for z in sol.y.T])
        return states, StepStats(steps=int(sol.t.size), rejected=None, newton_iterations=int(sol.nfev),
                                 cpu_seconds=time.process_time() - start)
    return run


for _name in ("BDF", "Radau"):
    register(f"solve_ivp-{_name}", kind="baseline")(_solve_ivp(_name))


def integrate(problem, t_out, *, method: str = "sdirk4", compiled: bool = True, rtol=1e-6, atol=1e-8, h0=1e-9,
              newton_tol=NEWTON_TOL, observer=None, max_steps=MAX_STEPS, **options):
    """The registered ``method`` on ``problem``: (states at ``t_out``, StepStats).  ``compiled``: the loop and the
    problem's kernels compiled by numba (numba is imported then, ~0.4 s once a process).  ``options``: the method's
    own (fixed_times, resume, repeat_cap for the DIRKs; stall, handover for bdf)."""
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}: one of {list(METHODS)}")
    return METHODS[method].run(problem, t_out, compiled=compiled, rtol=rtol, atol=atol, h0=h0, newton_tol=newton_tol,
                               observer=observer, max_steps=max_steps, **options)
