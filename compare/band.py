"""The calibration band: how the calibration's uncertainty reaches a prediction, one propagation for every
experiment.

A prediction F depends on the calibrated parameters p (mu_s, mu_d, I0, phi; a model's own, such as NGF's A).  Each
parameter is shifted by STEP of its value and the prediction solved again; J_j = (F(p + h_j e_j) - F(p)) / h_j and
the standard deviation is sqrt(J C J^T), C the covariance of the parameters over the calibration's replicates.

STEP = 1e-2: a one-sided difference errs by about h/2 |F''/F'| (truncation) plus eps/h (the solver's relative error
eps amplified).  The comparison's solvers run at rtol ~ 1e-4 (the oscillating plate's numerics; the Stokes models'
steady and transient solves are at least as tight), so 1e-2 keeps both terms near 1 % of the derivative, where a
step of 1e-3 would let the solver's error reach ~ 10 % of it (the sd would then change with the solver's path).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd

#: relative shift of each calibrated parameter (see the module's docstring)
STEP = 1e-2


@dataclass(frozen=True)
class Sensitivity:
    """A prediction's linear response to the calibration: each parameter ``names[j]`` shifted by ``steps[j]`` gives
    ``shifted[j]`` (whatever the solve returns: a whole prediction, or its observables); ``cov`` is the
    parameters' covariance over the calibration's replicates."""

    names: tuple[str, ...]
    steps: tuple[float, ...]
    cov: np.ndarray
    shifted: tuple

    @classmethod
    def of(cls, solve: Callable[[dict], object], central: dict, cov: pd.DataFrame) -> Sensitivity:
        """``solve(parameters)`` at each of ``central``'s parameters shifted by STEP of its value (zero-valued ones by
        STEP); ``cov`` the replicates' covariance, indexed by the parameters' names (a name it lacks: no variance)."""
        names = tuple(central)
        steps = tuple(STEP * (abs(central[n]) or 1.0) for n in names)
        shifted = tuple(solve({**central, n: central[n] + h}) for n, h in zip(names, steps))
        c = cov.reindex(index=list(names), columns=list(names)).fillna(0.0).to_numpy(dtype=float, copy=True)
        return cls(names, steps, c, shifted)

    def derivatives(self, estimate: Callable[[int], float], central: float,
                    difference: Callable[[float, float], float] = lambda a, b: a - b) -> np.ndarray:
        """One-sided differences of ``estimate(j)`` (the estimate on ``shifted[j]``) from ``central``; ``difference``
        for quantities that are not on a line (a phase: wrapped)."""
        return np.array([difference(estimate(j), central) / h for j, h in enumerate(self.steps)], dtype=float)

    def sd(self, derivatives) -> float:
        """sqrt(J C J^T) of the derivatives (one per name, in order); NaN when one is not finite."""
        j = np.asarray(derivatives, dtype=float)
        return float(np.sqrt(max(j @ self.cov @ j, 0.0))) if np.all(np.isfinite(j)) else np.nan

    def sd_of(self, estimate: Callable[[int], float], central: float, **kwargs) -> float:
        """The standard deviation of a scalar estimate (``derivatives`` then ``sd``)."""
        return self.sd(self.derivatives(estimate, central, **kwargs))

    def series_sd(self, series: Callable[[int], np.ndarray], central: np.ndarray) -> np.ndarray:
        """The standard deviation at each point of a series (``series(j)`` on the same points as ``central``)."""
        js = np.array([(series(j) - central) / h for j, h in enumerate(self.steps)])
        return np.sqrt(np.maximum(np.einsum("it,ij,jt->t", js, self.cov, js), 0.0))
