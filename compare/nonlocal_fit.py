"""The nonlocal amplitude A of the granular fluidity model (continuum.ngf), calibrated on the steady
creep profile of one drive; mu_s, mu_d, I0 and phi come from the calibration, so A is the only number
fitted, and the other drives are then predicted with no fitted parameter.

The fit: least squares of ln(u/u_w) between the DEM's steady window and the NGF steady state of the
same drive, at one point per d of depth from WALL_EXCLUSION below the plate to WALL_EXCLUSION above
the base, where the DEM's u exceeds U_FLOOR u_w.  Fitting the logarithm of the normalised profile
weighs every d of depth alike, tail and layer, and fits the profile's shape only: u_w itself stays a
prediction.  Its 95 % interval: A is fitted on each independent sample of the steady window (seeds,
or blocks of one seed: compare.analysis.steady_samples) and the interval is the t interval of
their mean.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from granstokes.continuum.ngf import NonlocalFluidity, solve_steady
from granstokes.continuum.scales import Material
from scipy import stats
from scipy.optimize import minimize_scalar

from .analysis import DriveAnalysis
from .calibrate import PAIR_SPACING, WALL_EXCLUSION

#: DEM velocities below this fraction of u_w are noise (a grain's thermal jiggle), not creep
U_FLOOR = 1e-4
#: the search range of A (log-uniform); Henann & Kamrin 2013 found 0.48 for glass beads
A_RANGE = (0.02, 5.0)


@dataclass(frozen=True)
class FluidityFit:
    A: float
    ci95: tuple[float, float]
    drive: str
    samples: tuple[float, ...]
    how: str
    points: int

    @property
    def at_bound(self) -> bool:
        """The fit ran into the search range: the profile does not determine A (no creep tail to fit)."""
        return bool(np.isclose(self.A, A_RANGE[0], rtol=1e-3) or np.isclose(self.A, A_RANGE[1], rtol=1e-3))

    @property
    def err(self) -> float:
        return float(np.std(self.samples, ddof=1) / np.sqrt(len(self.samples))) if len(self.samples) > 1 else np.nan


def _misfit(A: float, material: Material, a: DriveAnalysis, depth, log_u) -> float:
    st = solve_steady(material, a.spec.scene, a.spec.load, fluidity=NonlocalFluidity(A=A))
    model = np.interp(depth, st.y, st.u)
    return float(np.sum((np.log(np.maximum(model, 1e-300) / st.u_w) - log_u) ** 2))


def _fit_one(material: Material, a: DriveAnalysis, depth, u) -> float:
    keep = (u > U_FLOOR * u[0]) & (depth >= WALL_EXCLUSION) & (depth <= a.spec.depth - WALL_EXCLUSION)
    d, log_u = depth[keep], np.log(u[keep] / u[0])
    res = minimize_scalar(lambda x: _misfit(np.exp(x), material, a, d, log_u), method="bounded",
                          bounds=tuple(np.log(A_RANGE)), options={"xatol": 1e-4})
    return float(np.exp(res.x))


def fit_amplitude(a: DriveAnalysis, material: Material) -> FluidityFit:
    """A of drive ``a`` (its steady window), with the interval from the spread over independent samples."""
    samples, how = a.samples, a.samples_how
    grid = np.arange(0.0, a.spec.depth + PAIR_SPACING / 2, PAIR_SPACING)
    fits = []
    for s in samples:
        u = np.interp(grid, s.depth, s.u_x)
        fits.append(_fit_one(material, a, grid, u))
    p = a.steady_profile.sort_values("depth")
    A = _fit_one(material, a, grid, np.interp(grid, p.depth, p.u_x))
    if len(fits) > 1:
        half = stats.t.ppf(0.975, len(fits) - 1) * np.std(fits, ddof=1) / np.sqrt(len(fits))
        ci = (max(A - half, A_RANGE[0]), A + half)
    else:
        ci = (np.nan, np.nan)
    points = int(np.sum((grid >= WALL_EXCLUSION) & (grid <= a.spec.depth - WALL_EXCLUSION)))
    return FluidityFit(A, (float(ci[0]), float(ci[1])), a.label, tuple(fits), how, points)
