"""The mu(I) law (paper eq. (2.1)) and the inertial-number conventions.

Convention (stated once, used everywhere):

* ``"paper"``: I = |gamma_dot| d / sqrt(p/rho_p) with |gamma_dot| = 1/2 |du/dy|
  (the second invariant of the strain-rate tensor, paper eq. (2.4)).
* ``"dem"``:   I = |du/dy| d / sqrt(p/rho_p), the usual choice in DEM papers.

The same material has I_dem = 2 I_paper, hence I0_dem = 2 I0_paper; mu_s, mu_d are unchanged.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from granstokes.lib.validate import finite, require

#: |gamma_dot| = SHEAR_RATE_FACTOR[convention] * |du/dy|
SHEAR_RATE_FACTOR = {"paper": 0.5, "dem": 1.0}


def convert_I(value, source: str, target: str):
    """Convert an inertial number (or I0) between the ``"paper"`` and ``"dem"`` conventions."""
    for name, conv in (("source", source), ("target", target)):
        if conv not in SHEAR_RATE_FACTOR:
            raise ValueError(f"{name} convention must be one of {sorted(SHEAR_RATE_FACTOR)}, got {conv!r}")
    return value * SHEAR_RATE_FACTOR[target] / SHEAR_RATE_FACTOR[source]


def jop_law(I, mu_s, mu_d, I0):
    """mu(I) = mu_s + (mu_d - mu_s)/(1 + I0/I) (eq. (2.1), Jop et al. 2006) and its slope dmu/dI;
    I and I0 in the same convention.  The package's one implementation of the law."""
    I = np.asarray(I, dtype=float)
    return jop_mu(I, mu_s, mu_d, I0), (mu_d - mu_s) * I0 / (I + I0) ** 2


def jop_mu(I, mu_s, mu_d, I0):
    """The value of ``jop_law`` alone."""
    return mu_s + (mu_d - mu_s) * I / (I + I0)


@dataclass(frozen=True)
class Friction:
    """Static and dynamic friction coefficients of the mu(I) law; everything dimensionless
    in the paper depends on (mu_s, mu_d) and the wall friction mu_w only."""

    mu_s: float
    mu_d: float

    def __post_init__(self):
        require(finite(self.mu_s) and self.mu_s > 0, "mu_s", "a finite number > 0", self.mu_s)
        require(finite(self.mu_d) and self.mu_d > self.mu_s, "mu_d", f"a finite number > mu_s = {self.mu_s}", self.mu_d)

    @property
    def dmu(self) -> float:
        """Delta mu = mu_d - mu_s (paper, below eq. (2.13))."""
        return self.mu_d - self.mu_s

    def check_mu_w(self, mu_w: float) -> float:
        require(finite(mu_w) and self.mu_s < mu_w < self.mu_d, "mu_w",
                f"in the open interval (mu_s, mu_d) = ({self.mu_s:.6g}, {self.mu_d:.6g})", mu_w)
        return float(mu_w)

    def mu_w_from_tilde(self, mu_w_tilde: float) -> float:
        """Wall friction from the paper's normalised value mu~_w = (mu_d - mu_w)/Delta mu (eq. (3.9))."""
        require(finite(mu_w_tilde) and 0 < mu_w_tilde < 1, "mu_w_tilde", "in the open interval (0, 1)", mu_w_tilde)
        return self.mu_d - mu_w_tilde * self.dmu

    def tilde(self, mu):
        """mu~ = (mu_d - mu)/Delta mu (eq. (3.9)): 1 at yield, 0 at mu_d."""
        return (self.mu_d - mu) / self.dmu

    def beta(self, mu_w: float) -> float:
        """beta_w = mu_w/mu_s - 1, the relative wall-stress surplus (eq. (2.11))."""
        return mu_w / self.mu_s - 1.0

    def mu_and_slope(self, I, I0: float):
        """mu(I) (eq. (2.1)) and dmu/dI; I and I0 in the same convention."""
        return jop_law(I, self.mu_s, self.mu_d, I0)

    def mu_of_I(self, I, I0: float):
        return jop_mu(I, self.mu_s, self.mu_d, I0)

    def I_of_mu(self, mu, I0: float):
        """Inverse of eq. (2.1): I = I0 (mu - mu_s)/(mu_d - mu) for mu_s <= mu < mu_d."""
        mu = np.asarray(mu, dtype=float)
        return I0 * (mu - self.mu_s) / (self.mu_d - mu)
