"""The registry of time integrators: every method by name, its integrate function and what it takes.

A problem is M x' = F(x, t): a diagonal mass ``mass`` (0 on algebraic rows), ``initial()``, the rate
``rate(x, t)``, its Jacobian ``jacobian(x, t)`` (continuum.jacobian; or, for a problem without an analytic one, its
pattern ``sparsity()``), ``project(x)`` onto the algebraic rows and, for the DIRKs' Newton, ``step_fraction``,
``carries_contraction``, ``dense_wall``; a time-dependent wall enters F through t (continuum.load.Load.wall), never
by changing the problem.  ``integrate(problem, t_out, method=..., ...)`` looks the method up in METHODS and runs it:
the DIRKs (continuum.stepper; their loop compiled with the problem's kernels where the problem has its own), BDF
(continuum.bdf), explicit Euler (fixed steps only) and the solve_ivp baselines (scipy's BDF and Radau on the
differential rows; the only place the package calls solve_ivp).  ``register`` adds one.
"""
from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import stepper
from .stepper import FIRST_STEP, MAX_STEPS, NEWTON_TOL, TABLEAUX, StepStats


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
    def run(problem, t_out, *, h0=None, **options):
        return stepper.integrate(problem, t_out, method=name, h0=FIRST_STEP if h0 is None else h0, **options)
    return run


for _name, _tab in TABLEAUX.items():
    register(_name, adaptive=_tab.err is not None)(_dirk(_name))


@register("bdf")
def _bdf(problem, t_out, *, fixed_times=None, newton_tol=None, resume=None, h0=None, **options):
    """continuum.bdf; its Newton tolerance is scipy's rule from rtol (``newton_tol`` is the DIRKs'); from t = 0."""
    from .bdf import integrate as integrate_bdf

    if fixed_times is not None:
        raise ValueError("method 'bdf' chooses its own steps: fixed_times needs a DIRK method")
    if resume is not None:
        raise ValueError("method 'bdf' starts from the problem's initial state: resume needs a DIRK or a baseline")
    return integrate_bdf(problem, t_out, h0=FIRST_STEP if h0 is None else h0, **options)


@register("explicit-euler", adaptive=False)
def _euler(problem, t_out, *, fixed_times=None, observer=None, compiled=None, rtol=None, atol=None, h0=None,
           newton_tol=None, max_steps=None, repeat_cap=None, resume=None):
    """continuum.stepper.explicit_euler on ``fixed_times`` (no error control, no Newton: the tolerances and the
    step cap do not apply)."""
    if fixed_times is None:
        raise ValueError("method 'explicit-euler' has no error estimate: give fixed_times")
    if resume is not None:
        raise ValueError("method 'explicit-euler' starts from the problem's initial state")
    return stepper.explicit_euler(problem, t_out, fixed_times, observer)


def _ivp_jacobian(problem, state, first: int, inverse_mass: np.ndarray, unit_mass: bool) -> dict:
    """solve_ivp's Jacobian option: the problem's band at (x, t) over the mass on the differential rows (a sparse
    matrix: BDF and Radau factorise it as sparse), or its pattern ``sparsity()`` for scipy's finite differences."""
    if not hasattr(problem, "jacobian"):
        return {"jac_sparsity": problem.sparsity()}
    import scipy.sparse as sp

    if unit_mass:
        return {"jac": lambda t, z: problem.jacobian(state(z), t).sparse(first).tocsc()}
    over_mass = sp.diags(inverse_mass)
    return {"jac": lambda t, z: (over_mass @ problem.jacobian(state(z), t).sparse(first)).tocsc()}


def _solve_ivp(method):
    def run(problem, t_out, *, rtol=1e-6, atol=1e-8, h0=None, resume=None, observer=None, fixed_times=None,
            compiled=None, newton_tol=None, max_steps=None):
        """scipy's solve_ivp(``method``) on the differential rows z, dz/dt = F(x, t)/M, from the problem's initial
        state at t = 0 or from ``resume`` = (t0, x0); the algebraic rows (leading rows only) from ``problem.project``
        (which must not depend on z: an imposed stress; without algebraic rows x is z).  ``atol``: a number or one
        per differential row; ``h0``: the first step (None: scipy's choice); scipy's own step count (``max_steps``
        does not apply).  ``steps`` reports the output times, ``newton_iterations`` scipy's evaluations of the rate
        (its finite differences' included)."""
        from scipy.integrate import solve_ivp

        if observer is not None or fixed_times is not None:
            raise ValueError(f"solve_ivp-{method} takes neither an observer nor fixed_times")

        t_out = np.asarray(t_out, dtype=float)
        mass = np.asarray(problem.mass, dtype=float)
        first = int(np.argmax(mass > 0))
        if not np.all(mass[first:] > 0):
            raise ValueError(f"solve_ivp-{method} takes algebraic rows before the differential ones only")
        inverse_mass = 1 / mass[first:]
        unit_mass = bool(np.all(inverse_mass == 1.0))
        t0, x0 = resume if resume is not None else (0.0, problem.initial())
        x = problem.project(np.array(x0, dtype=float))

        def state(z):
            if not first:
                return z
            full = x.copy()
            full[first:] = z
            return problem.project(full)

        def rhs(t, z):
            f = problem.rate(state(z), t)[first:]
            return f if unit_mass else f * inverse_mass

        start = time.process_time()
        sol = solve_ivp(rhs, (t0, t_out[-1]), x[first:], method=method, t_eval=t_out, rtol=rtol, atol=atol,
                        first_step=h0, **_ivp_jacobian(problem, state, first, inverse_mass, unit_mass))
        if not sol.success:
            raise stepper.StepperFailure(f"solve_ivp({method}) failed: {sol.message}")
        states = np.array([state(z) for z in sol.y.T])
        return states, StepStats(steps=int(sol.t.size), rejected=None, newton_iterations=int(sol.nfev),
                                 cpu_seconds=time.process_time() - start)
    return run


for _name in ("BDF", "Radau"):
    register(f"solve_ivp-{_name}", kind="baseline")(_solve_ivp(_name))


def integrate(problem, t_out, *, method: str = "sdirk4", compiled: bool = True, rtol=1e-6, atol=1e-8, h0=None,
              newton_tol=NEWTON_TOL, observer=None, max_steps=MAX_STEPS, resume=None, **options):
    """The registered ``method`` on ``problem`` (M x' = F(x, t)): (states at ``t_out``, StepStats).  ``compiled``: the
    loop and the problem's kernels compiled by numba (numba is imported then, ~0.4 s once a process); ``h0``: the
    first step (None: the method's own, FIRST_STEP for the package's); ``resume`` = (t0, x0): start there instead of
    the problem's initial state at t = 0.  ``options``: the method's own (fixed_times, repeat_cap for the DIRKs;
    stall, handover for bdf)."""
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}: one of {list(METHODS)}")
    resumed = {} if resume is None else {"resume": resume}
    return METHODS[method].run(problem, t_out, compiled=compiled, rtol=rtol, atol=atol, h0=h0, newton_tol=newton_tol,
                               observer=observer, max_steps=max_steps, **resumed, **options)
