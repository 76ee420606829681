"""Baseline: the same spatial discretisation integrated by scipy's solve_ivp (method of lines).

Imposed stress only (the imposed-speed problem is a DAE, which solve_ivp does not take).  The
Jacobian is the exact banded one, passed as a sparse matrix so BDF/Radau factorise it as sparse.
"""
from __future__ import annotations

import time

import numpy as np
from scipy.integrate import solve_ivp

from .problems import ImposedStress
from .rheology import Friction
from .solver import Numerics, Solution, check_times, map_for
from .stepper import StepStats


def solve_stress_mol(friction: Friction, mu_w: float, times, numerics: Numerics = Numerics(),
                     method: str = "BDF") -> Solution:
    """Imposed wall stress by solve_ivp(method) on the interior nodes, tau~(0) = 1 for t~ > 0."""
    t = check_times(times)
    numerics = numerics.for_drive("stress")
    problem = ImposedStress(friction, mu_w, numerics.mesh(*map_for(friction, mu_w, "stress", t[0])), numerics.order)
    x0 = problem.initial()
    x0[0] = 1.0

    def rhs(_, z):
        return problem.rate(np.concatenate(([1.0], z)))[1:]

    def jac(_, z):
        return problem.jacobian(np.concatenate(([1.0], z))).interior()

    start = time.process_time()
    sol = solve_ivp(rhs, (0.0, t[-1]), x0[1:], method=method, t_eval=t, jac=jac,
                    rtol=numerics.rtol, atol=numerics.atol)
    if not sol.success:
        raise RuntimeError(f"solve_ivp({method}) failed: {sol.message}")
    stats = StepStats(steps=int(sol.t.size), newton_iterations=int(sol.nfev), cpu_seconds=time.process_time() - start)
    tau = np.column_stack([np.ones(len(t)), sol.y.T, np.ones(len(t))])
    return Solution("stress", friction, problem.mu_w, None, problem.mesh, t, tau, np.empty((0, 4)), stats, numerics)
