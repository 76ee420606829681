"""Calibrate mu(I) and phi(I) on DEM steady states (pooled local pairs), with confidence intervals.

mu(I) = mu_s + (mu_d - mu_s)/(1 + I0/I) (paper eq. MuI) and phi(I) = phi_max - b I, fitted with
scipy.optimize.curve_fit on (I, mu, phi) pooled over depth and runs from steady-state windows,
excluding the layers within ``wall_exclusion`` of the plate and of the base (their stress and
shear rate carry the wall's layering) and the creeping points I < ``I_min`` (local mu(I) has no
creep), one point per PAIR_SPACING of depth (neighbouring kernel-smoothed points are not
independent).  I in the DEM convention (I_dem = |du/dy| d/sqrt(p/rho_p)); I0 is reported in both.
Intervals: 95 % from the covariance (Student t on n - 3 degrees of freedom).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import pandas as pd
from scipy import stats
from scipy.optimize import curve_fit

from continuum.rheology import convert_I, jop_law
from granstokes.validate import require
from continuum.scales import Material

WALL_EXCLUSION = 2.0  # d
I_MIN = 1e-3
PAIR_SPACING = 1.0  # d: one (mu, I) pair per d of depth, about the coarse-graining's correlation length


def mu_law(I, mu_s, mu_d, I0):
    """The Jop law's value (continuum.rheology.jop_law) as curve_fit's model function."""
    return jop_law(I, mu_s, mu_d, I0)[0]


@dataclass(frozen=True)
class Calibration:
    mu_s: float
    mu_d: float
    I0_dem: float
    phi_max: float
    phi_slope: float
    ci95: dict          # name -> (lo, hi)
    n_points: int
    rms_mu: float
    wall_exclusion: float
    I_min: float

    @property
    def I0_paper(self) -> float:
        return convert_I(self.I0_dem, "dem", "paper")

    def material(self, phi: float | None = None) -> Material:
        """The calibrated material (DEM units), phi = the bulk solid fraction given or phi_max."""
        return Material(mu_s=self.mu_s, mu_d=self.mu_d, I0=self.I0_dem, I_convention="dem",
                        phi=self.phi_max if phi is None else phi)

    def as_dict(self) -> dict:
        return {**asdict(self), "I0_paper": self.I0_paper, "I0_convention": "dem",
                "law": "mu = mu_s + (mu_d - mu_s)/(1 + I0/I); phi = phi_max - phi_slope I (I_dem)"}


def fit(pairs: pd.DataFrame, wall_exclusion: float = WALL_EXCLUSION, I_min: float = I_MIN) -> Calibration:
    """Fit on a table with columns I_dem, mu, phi (already restricted to steady windows and away
    from the walls by the caller, who states ``wall_exclusion``)."""
    sel = pairs[(pairs.I_dem > I_min) & np.isfinite(pairs.mu) & np.isfinite(pairs.I_dem)]
    require(len(sel) >= 6, "calibration points", ">= 6 steady (mu, I) pairs with I > I_min", len(sel))
    I, mu, phi = sel.I_dem.to_numpy(), sel.mu.to_numpy(), sel.phi.to_numpy()
    p0 = (max(mu.min() - 0.02, 0.01), mu.max() + 0.1, np.median(I))
    popt, pcov = curve_fit(mu_law, I, mu, p0=p0, bounds=([0.0, 0.0, 1e-6], [2.0, 3.0, 50.0]), maxfev=20000)
    q = stats.t.ppf(0.975, max(len(I) - 3, 1))
    err = q * np.sqrt(np.diag(pcov))
    lin = stats.linregress(I, phi)
    q2 = stats.t.ppf(0.975, max(len(I) - 2, 1))
    ci = {"mu_s": (popt[0] - err[0], popt[0] + err[0]), "mu_d": (popt[1] - err[1], popt[1] + err[1]),
          "I0_dem": (popt[2] - err[2], popt[2] + err[2]),
          "phi_max": (lin.intercept - q2 * lin.intercept_stderr, lin.intercept + q2 * lin.intercept_stderr),
          "phi_slope": (-lin.slope - q2 * lin.stderr, -lin.slope + q2 * lin.stderr)}
    rms = float(np.sqrt(np.mean((mu_law(I, *popt) - mu) ** 2)))
    return Calibration(float(popt[0]), float(popt[1]), float(popt[2]), float(lin.intercept), float(-lin.slope),
                       {k: tuple(map(float, v)) for k, v in ci.items()}, len(I), rms, wall_exclusion, I_min)
