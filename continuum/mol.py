"""Baseline: the same spatial discretisation integrated by scipy's solve_ivp (method of lines).

Imposed stress only (the imposed-speed problem is a DAE, which solve_ivp does not take).  The
Jacobian is the exact banded one, passed as a sparse matrix so BDF/Radau factorise it as sparse.
"""
from __future__ import annotations

import numpy as np

from .integrators import integrate
from .problems import ImposedStress
from .rheology import Friction
from .solver import Numerics, Solution, check_times, map_for


def solve_stress_mol(friction: Friction, mu_w: float, times, numerics: Numerics = Numerics(),
                     method: str = "BDF") -> Solution:
    """Imposed wall stress by solve_ivp(method) on the interior nodes, tau~(0) = 1 for t~ > 0."""
    t = check_times(times)
    numerics = numerics.for_drive("stress")
    problem = ImposedStress(friction, mu_w, numerics.mesh(*map_for(friction, mu_w, "stress", t[0])), numerics.order)
    states, stats = integrate(problem, t, method=f"solve_ivp-{method}", rtol=numerics.rtol, atol=numerics.atol)
    tau = np.array([problem.full(x) for x in states])
    return Solution("stress", friction, problem.mu_w, None, problem.mesh, t, tau, np.empty((0, 4)), stats, numerics)
