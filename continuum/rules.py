"""Yield rules for the velocity-form solver: the shear stress as a function of the shear rate.

Shear-rate convention: the paper's |gamma_dot| = 1/2 |du/dy| (continuum.rheology), so here
g = 1/2 du/dy and I = |g| d / sqrt(p/rho_p) with I0 in the paper's convention.  The signed shear
stress is s = sigma_xy; where the bed is sheared by a plate moving in +x above it, g < 0 and s < 0.

* ``regularised``: eta = mu(I) p / sqrt(g^2 + eps^2), s = eta g.  Below yield the material is a
  very viscous fluid (viscosity mu_s p/eps) that creeps at |g| ~ eps |s|/(mu_s p); as eps -> 0 the
  paper's local mu(I) model with rigid zones is recovered (measured rate in the tests).  The default:
  it is the paper's model up to a controlled, vanishing creep.
* ``barker-gray``: the partially regularised law of Barker & Gray (2017, JFM 828): for I < I_N,
  mu(I) = sqrt(alpha / ln(A/I)), C^1-matched to mu(I) at I_N, the lower edge of the range where the
  2D incompressible mu(I) equations are well posed (Barker et al. 2015, JFM 779, eq. 3.9:
  4 nu^2 - 4 nu + mu^2 (1 - nu/2)^2 < 0 with nu = I mu'(I)/mu(I)).  It has no yield stress
  (mu -> 0 as I -> 0): it creeps below mu_s, a different model, kept for the comparison with the
  creep the DEM shows; a tiny numerical eps only smooths sign(g) at g = 0.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.optimize import brentq

from granstokes.lib.validate import finite, require

from .rheology import Friction


def wellposedness(fr: Friction, I0: float, I):
    """Barker et al. (2015) eq. 3.9 function: 4 nu^2 - 4 nu + mu^2 (1 - nu/2)^2 (< 0: well posed),
    nu = I mu'(I)/mu(I).  Convention-free (nu is invariant under I -> 2I with I0 -> 2 I0)."""
    I = np.asarray(I, dtype=float)
    mu, slope = fr.mu_and_slope(I, I0)
    nu = I * slope / mu
    return 4 * nu**2 - 4 * nu + mu**2 * (1 - nu / 2) ** 2


def well_posed_range(fr: Friction, I0: float):
    """(I_low, I_high) where the 2D mu(I) equations are well posed, or None if nowhere."""
    grid = np.logspace(-12, 6, 4000) * I0
    ok = wellposedness(fr, I0, grid) < 0
    if not ok.any():
        return None
    i, j = np.argmax(ok), len(ok) - 1 - np.argmax(ok[::-1])
    f = lambda I: float(wellposedness(fr, I0, I))
    lo = brentq(f, grid[i - 1], grid[i]) if i > 0 else grid[0]
    hi = brentq(f, grid[j], grid[j + 1]) if j < len(grid) - 1 else grid[-1]
    return lo, hi


#: regularisation of the DEM-scene predictions, eps = EPS_FRACTION U/delta_s: the creep it adds below
#: yield scales as eps^(2/3) (tests/continuum/test_velocity_form.py); 1e-3 of the layer's shear rate
EPS_FRACTION = 1e-3


@dataclass(frozen=True)
class YieldRule:
    """``kind`` "regularised" (eps in 1/time, the material's units) or "barker-gray"."""

    kind: str = "regularised"
    eps: float = 1e-3

    def __post_init__(self):
        require(self.kind in ("regularised", "barker-gray"), "rule", "'regularised' or 'barker-gray'", self.kind)
        require(finite(self.eps) and self.eps > 0, "eps", "a finite number > 0 (a shear rate)", self.eps)

    @classmethod
    def for_layer(cls, scales) -> YieldRule:
        """The regularised rule of the DEM-scene predictions: eps = EPS_FRACTION U/delta_s."""
        return cls(eps=EPS_FRACTION * scales.U / scales.delta_s)


class ShearLaw:
    """mu(I) and dmu/dI for a yield rule, a friction law and I0 (paper convention); the stress s(g) and
    ds/dg on faces of fixed pressure are a ``FaceLaw`` (``on_faces``)."""

    def __init__(self, rule: YieldRule, fr: Friction, I0: float, d: float, rho_p: float):
        self.rule, self.fr, self.I0 = rule, fr, I0
        self.d, self.rho = d, rho_p

    @cached_property
    def barker_gray(self) -> tuple[float, float, float]:
        """(I_N, alpha, A): mu = sqrt(alpha/ln(A/I)) below I_N, C^1 with mu(I) at I_N."""
        span = well_posed_range(self.fr, self.I0)
        require(span is not None, "mu(I) parameters", "a law that is well posed somewhere (Barker et al. 2015)",
                (self.fr.mu_s, self.fr.mu_d, self.I0))
        i_n = span[0]
        mu_n, slope_n = map(float, self.fr.mu_and_slope(i_n, self.I0))
        nu_n = i_n * slope_n / mu_n
        alpha = mu_n**2 / (2 * nu_n)
        return i_n, alpha, i_n * np.exp(alpha / mu_n**2)

    def mu_and_slope(self, I):
        """mu(I) and dmu/dI for the rule's friction law."""
        mu, slope = self.fr.mu_and_slope(I, self.I0)
        if self.rule.kind == "barker-gray":
            i_n, alpha, A = self.barker_gray
            low = I < i_n
            Il = np.maximum(I[low], 1e-300)
            mu_low = np.sqrt(alpha / np.log(A / Il))
            mu[low] = mu_low
            slope[low] = mu_low**3 / (2 * alpha * Il)
        return mu, slope

    def mu(self, I):
        """mu(I) alone (the rate needs no slope)."""
        if self.rule.kind == "barker-gray":
            return self.mu_and_slope(I)[0]
        return self.fr.mu_of_I(I, self.I0)

    def on_faces(self, p) -> FaceLaw:
        """This law on faces of fixed pressures p."""
        return FaceLaw(self, np.asarray(p, dtype=float))


class FaceLaw:
    """s(g) = mu(I) p g / sqrt(g^2 + eps^2) with I = |g| d sqrt(rho_p/p), and ds/dg, on faces of fixed
    pressure p (the factor d sqrt(rho_p/p) computed once)."""

    def __init__(self, law: ShearLaw, p: np.ndarray):
        self.law, self.p = law, p
        self.inertial = law.d * np.sqrt(law.rho / p)  # I/|g|
        self.eps2 = law.rule.eps**2

    def stress(self, g):
        """s at the faces (g: the faces on the last axis)."""
        root = g * g
        root += self.eps2
        np.sqrt(root, out=root)
        s = self.law.mu(np.abs(g) * self.inertial)
        s *= self.p
        s *= g
        s /= root
        return s

    def slope(self, g):
        """ds/dg at the faces."""
        ag = np.abs(g)
        root = np.sqrt(g * g + self.eps2)
        mu, slope = self.law.mu_and_slope(ag * self.inertial)
        return self.p * (slope * self.inertial * ag / root + mu * self.eps2 / root**3)
