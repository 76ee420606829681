"""One-dimensional coarse-graining kernels K(s) of width w (Goldhirsch 2010, eq. 3; Weinhart et al. 2012).

Every kernel is even, has compact support |s| < c, and is normalised, int K ds = 1, so that
sum_i m_i K(y - y_i) / A integrates over y to the total mass per area (A = L_x L_z, or L_x in 2D).
The width w is the kernel's standard deviation, sqrt(int s^2 K ds) = w, for every kernel, so that
widths mean the same smoothing whichever kernel is used.

* ``gaussian``: K(s) = exp(-s^2 / 2w^2) / Z for |s| < c = 3w, Z = sqrt(2 pi) w erf(3/sqrt 2) (cut at
  3 w and renormalised; the standard deviation of the cut kernel is 0.986 w, the 1.4 % is stated, not
  corrected); CDF F(s) = 1/2 + erf(s / (sqrt 2 w)) sqrt(2 pi) w / (2 Z), clipped to [0, 1] at |s| = c.
* ``lucy``: K(s) = 5/(4c) (1 + 3q)(1 - q)^3, q = |s|/c < 1 (Lucy 1977, the 1D normalisation),
  variance 2 c^2 / 21, hence c = sqrt(21/2) w = 3.24 w; CDF from the polynomial antiderivative
  G(q) = int_0^q (1 + 3r)(1 - r)^3 dr = q - 2 q^3 + 2 q^4 - (3/5) q^5, F(s) = 1/2 + sign(s) 5 G(q) / 4.

The stress line (Goldhirsch 2010, eq. 30): a force f carried along a branch from y_2 to y_1 = y_2 + r_y
spreads as int_0^1 K(y - y_2 - l r_y) dl = (F(y - y_2) - F(y - y_1)) / r_y, exact for both kernels
(``line``); its r_y-weighted form ``line_ry`` = F(y - y_2) - F(y - y_1) needs no division.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import erf

from granstokes.lib.validate import finite, require

KERNELS = ("gaussian", "lucy")
GAUSS_CUT = 3.0  # Gaussian cutoff in widths
LUCY_CUT = math.sqrt(21.0 / 2.0)  # Lucy cutoff in widths (standard deviation = w)
_GAUSS_Z = math.sqrt(2.0 * math.pi) * math.erf(GAUSS_CUT / math.sqrt(2.0))  # times w


@dataclass(frozen=True)
class Kernel:
    """A normalised, even 1D kernel with standard deviation ``width`` (in d) and support |s| < cutoff."""

    name: str = "lucy"
    width: float = 0.5

    def __post_init__(self):
        require(self.name in KERNELS, "kernel", f"one of {KERNELS}", self.name)
        require(finite(self.width) and self.width > 0, "width", "a finite number > 0 (in d)", self.width)

    @property
    def cutoff(self) -> float:
        """Support half-width c: K(s) = 0 for |s| >= c."""
        return (GAUSS_CUT if self.name == "gaussian" else LUCY_CUT) * self.width

    def __call__(self, s) -> np.ndarray:
        """K(s), integral 1 over its support."""
        s = np.asarray(s, dtype=float)
        w, c = self.width, self.cutoff
        if self.name == "gaussian":
            return np.where(np.abs(s) < c, np.exp(-0.5 * (s / w) ** 2) / (_GAUSS_Z * w), 0.0)
        q = np.minimum(np.abs(s) / c, 1.0)  # the polynomial vanishes at q = 1
        return 5.0 / (4.0 * c) * (1.0 + 3.0 * q) * (1.0 - q) ** 3

    def cdf(self, s) -> np.ndarray:
        """F(s) = int_{-inf}^s K: 0 below -c, 1 above c, exact (erf or the Lucy polynomial)."""
        s = np.asarray(s, dtype=float)
        c = self.cutoff
        if self.name == "gaussian":
            w = self.width
            f = 0.5 + 0.5 * erf(np.clip(s, -c, c) / (math.sqrt(2.0) * w)) / math.erf(GAUSS_CUT / math.sqrt(2.0))
        else:
            q = np.minimum(np.abs(s) / c, 1.0)
            g = q * (1.0 + q * q * (-2.0 + q * (2.0 - 0.6 * q)))  # G(q), G(1) = 2/5
            f = np.where(q < 1.0, 0.5 + np.sign(s) * 1.25 * g, np.where(s > 0, 1.0, 0.0))  # exact tails
        return np.clip(f, 0.0, 1.0)

    def line_ry(self, y, y2, y1) -> np.ndarray:
        """r_y int_0^1 K(y - y2 - l r_y) dl = F(y - y2) - F(y - y1), r_y = y1 - y2 (the stress line
        weighted by the branch's y component; broadcasts)."""
        return self.cdf(np.asarray(y) - y2) - self.cdf(np.asarray(y) - y1)

    def line(self, y, y2, y1, line_ry=None) -> np.ndarray:
        """int_0^1 K(y - y2 - l (y1 - y2)) dl: the kernel averaged along the branch from y2 to y1; for
        |y1 - y2| < 1e-6 w the branch is horizontal and the average is K at its height (error O(r_y^2)).
        ``line_ry``: the already computed ``line_ry(y, y2, y1)``, if at hand."""
        y, y2, y1 = np.broadcast_arrays(np.asarray(y, dtype=float), y2, y1)
        ry = y1 - y2
        flat = np.abs(ry) < 1e-6 * self.width
        lr = self.line_ry(y, y2, y1) if line_ry is None else line_ry
        if not flat.any():
            return lr / ry
        out = np.array(self(y - 0.5 * (y1 + y2)), dtype=float)
        np.divide(lr, ry, out=out, where=~flat)
        return out

    def describe(self) -> dict:
        """Kernel metadata for the JSON outputs."""
        return {"kernel": self.name, "width": self.width, "cutoff": self.cutoff,
                "width_meaning": "standard deviation of the kernel, in d",
                "definition": ("Gaussian exp(-s^2/2w^2) cut at |s| = 3w and renormalised" if self.name == "gaussian"
                               else "Lucy 5/(4c)(1+3q)(1-q)^3, q = |s|/c, c = sqrt(21/2) w")}
