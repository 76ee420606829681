"""Fits of the mu(I) and phi(I) laws with bootstrap intervals: the one ``Calibration`` object, used for
the independent plane-shear calibration (``granstokes dem calibrate``, ``fit_blocks``) and for the fit
on the Stokes drives' own steady windows (compare.calibrate); its ``contract`` is calibration.json.

Laws, I in the DEM convention (I = |du/dy| d/sqrt(p/rho_p); I0_dem = 2 I0_paper):

* Jop form mu = mu_s + (mu_d - mu_s)/(1 + I0/I) (continuum.rheology.jop_law, what the continuum uses);
* linear form mu = mu_1 + b I and phi = phi_max - a I, both on I <= LINEAR_I_MAX (the range where
  da Cruz et al. 2005 and GDR MiDi 2004 find them linear).

Intervals: 95 % percentile intervals of N_BOOTSTRAP replicates.  Plane shear: each replicate
resamples, for every point, the seeds with replacement and then each drawn seed's blocks (blocks
longer than the autocorrelation time, dem.calibrate) with replacement, and refits with the weights of
the original fit.  The replicates (joint samples of mu_s, mu_d, I0, phi_max, a) carry the joint
uncertainty into predictions.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy.optimize import curve_fit

from granstokes.lib.validate import require

from .rheology import convert_I, jop_law
from .scales import Material

LINEAR_I_MAX = 0.3
N_BOOTSTRAP = 500
BOOTSTRAP_SEED = 10
#: the kinds of calibration: an independent measurement (a prediction follows) or a fit on the drives
PLANE_SHEAR, IN_DRIVE = "plane shear (independent)", "fit on the drives' steady windows (not a prediction)"
JOP_BOUNDS = ([0.0, 0.0, 1e-6], [2.0, 3.0, 50.0])
#: a Jop parameter is not determined by the data when its best fit or an end of its 95 % interval comes within
#: BOUND_TOLERANCE of a bound of JOP_BOUNDS, or its interval covers more than SPAN_MAX of that range (both as
#: fractions of the range; of its logarithm for I0)
BOUND_TOLERANCE, SPAN_MAX = 1e-3, 0.5
#: replicate keys of calibration.json (its contract with compare) and the parameter each one samples
REPLICATE_KEYS = {"mu_s": "mu_s", "mu_d": "mu_d", "I0": "I0_dem", "phi_max": "phi_max", "a": "phi_slope"}




def mu_law(I, mu_s, mu_d, I0):
    """The Jop law's value (continuum.rheology.jop_law) as curve_fit's model function."""
    return jop_law(I, mu_s, mu_d, I0)[0]


def fit_laws(I, mu, phi, sigma, p0=None) -> np.ndarray:
    """(mu_s, mu_d, I0, mu_1, b, phi_max, a) by weighted least squares (sigma: mu's errors or None)."""
    if p0 is None:
        p0 = (max(mu.min() - 0.02, 0.01), mu.max() + 0.1, float(np.median(I)))
    jop, _ = curve_fit(mu_law, I, mu, p0=p0, sigma=sigma, bounds=JOP_BOUNDS, maxfev=20000)
    low = I <= LINEAR_I_MAX
    w = None if sigma is None else 1.0 / sigma[low]
    b, mu_1 = np.polyfit(I[low], mu[low], 1, w=w)
    slope, phi_max = np.polyfit(I[low], phi[low], 1)
    return np.array([*jop, mu_1, b, phi_max, -slope])


PARAMS = ("mu_s", "mu_d", "I0_dem", "mu_1", "b", "phi_max", "phi_slope")


@dataclass(frozen=True, eq=False)
class Calibration:
    """A mu(I), phi(I) calibration: best fit, 95 % intervals and bootstrap replicates of every
    parameter (``replicates``: PARAMS -> array, joint), the points it was fitted to (``points``: I,
    mu, phi and their errors where known), its ``kind`` (PLANE_SHEAR or IN_DRIVE) and ``source``."""

    mu_s: float
    mu_d: float
    I0_dem: float
    mu_1: float
    b: float
    phi_max: float
    phi_slope: float
    ci95: dict
    replicates: dict
    points: pd.DataFrame
    kind: str
    source: str
    rms_mu: float
    grains: dict | None = None
    wall_exclusion: float | None = None
    I_min: float | None = None
    info: dict = field(default_factory=dict)
    elasticity: dict | None = None  # calibration.json's "elasticity" (dem.modulus), None when it has none

    @property
    def is_prediction(self) -> bool:
        """True when mu(I) comes from an independent measurement, so the drives are a blind test."""
        return self.kind == PLANE_SHEAR

    @property
    def failure(self) -> str:
        """Why this fit cannot be used, in one line, or "" when it can: a Jop parameter at a bound of its
        admissible range (JOP_BOUNDS) or with a 95 % interval reaching one or spanning most of it, or a value
        or interval end that is not finite."""
        for k, name in enumerate(("mu_s", "mu_d", "I0_dem")):
            scale = np.log10 if name == "I0_dem" else float
            lo, hi = scale(JOP_BOUNDS[0][k]), scale(JOP_BOUNDS[1][k])
            value, (c_lo, c_hi) = getattr(self, name), self.ci95[name]
            where = [scale(max(x, JOP_BOUNDS[0][k])) for x in (value, c_lo, c_hi)]
            stated = f"{name} = {value:.3g} (95 % interval [{c_lo:.3g}, {c_hi:.3g}])"
            if not np.all(np.isfinite([value, c_lo, c_hi])):
                return f"{stated} is not a finite number: the fit did not determine it"
            if any(min(x - lo, hi - x) <= BOUND_TOLERANCE * (hi - lo) for x in where):
                return (f"{stated} reaches a bound of its admissible range [{JOP_BOUNDS[0][k]:g}, "
                        f"{JOP_BOUNDS[1][k]:g}]: the data do not determine it")
            if where[2] - where[1] > SPAN_MAX * (hi - lo):
                return f"{stated} spans most of its admissible range: the data do not determine it"
        if self.mu_d <= self.mu_s:
            return f"mu_d = {self.mu_d:.3g} <= mu_s = {self.mu_s:.3g}: no mu(I) law"
        return ""

    @property
    def I0_paper(self) -> float:
        return convert_I(self.I0_dem, "dem", "paper")

    def material(self, phi: float | None = None) -> Material:
        """The calibrated material (DEM units), phi = the bulk solid fraction given or phi_max."""
        return Material(mu_s=self.mu_s, mu_d=self.mu_d, I0=self.I0_dem, I_convention="dem",
                        phi=self.phi_max if phi is None else phi)

    def as_dict(self) -> dict:
        """Summary for metrics.json (no replicates, no points)."""
        return {**{k: getattr(self, k) for k in PARAMS}, "ci95": self.ci95, "I0_paper": self.I0_paper,
                "I0_convention": "dem", "kind": self.kind, "source": self.source, "n_points": len(self.points),
                "rms_mu": self.rms_mu, "wall_exclusion": self.wall_exclusion, "I_min": self.I_min,
                "law": "mu = mu_s + (mu_d - mu_s)/(1 + I0/I); mu = mu_1 + b I and phi = phi_max - phi_slope I "
                       f"on I <= {LINEAR_I_MAX:g} (I_dem)"}

    def contract(self) -> dict:
        """calibration.json's keys, its contract with compare (the caller adds grains and provenance)."""
        ci = {k: list(v) for k, v in self.ci95.items()}
        return {"mu_s": self.mu_s, "mu_d": self.mu_d, "I0": self.I0_dem, "I_convention": "dem",
                "ci95": {"mu_s": ci["mu_s"], "mu_d": ci["mu_d"], "I0": ci["I0_dem"]},
                "linear": {"mu_1": self.mu_1, "b": self.b, "ci95": {"mu_1": ci["mu_1"], "b": ci["b"]},
                           "I_max": LINEAR_I_MAX},
                "phi": {"phi_max": self.phi_max, "a": self.phi_slope,
                        "ci95": {"phi_max": ci["phi_max"], "a": ci["phi_slope"]}, "I_max": LINEAR_I_MAX},
                "replicates": {k: [float(x) for x in self.replicates[p]] for k, p in REPLICATE_KEYS.items()}}


def from_replicates(best, reps, points, kind, source, rms, **extra) -> Calibration:
    reps = np.asarray(reps)
    ci = {p: (float(np.percentile(reps[:, i], 2.5)), float(np.percentile(reps[:, i], 97.5)))
          for i, p in enumerate(PARAMS)}
    return Calibration(*map(float, best), ci, {p: reps[:, i] for i, p in enumerate(PARAMS)}, points, kind, source,
                       float(rms), **extra)


def _point_means(groups, rng=None):
    """Per point: I = <rate>/sqrt(<p>), mu = <tau>/<p>, phi = <phi> over its blocks (columns tau, p, phi,
    rate of each seed's block array); with ``rng`` one bootstrap draw: the seeds with replacement, then
    each drawn seed's blocks with replacement."""
    out = np.empty((3, len(groups)))
    for k, seeds in enumerate(groups):
        if rng is not None:
            seeds = [seeds[i] for i in rng.integers(0, len(seeds), len(seeds))]
            seeds = [b[rng.integers(0, len(b), len(b))] for b in seeds]
        tau, p, phi, rate = np.concatenate(seeds).mean(axis=0)
        out[:, k] = rate / np.sqrt(p), tau / p, phi
    return out


def fit_blocks(blocks: pd.DataFrame, source: str, n_boot: int = N_BOOTSTRAP) -> Calibration:
    """The plane-shear fit on block means (columns point, seed, block, tau, p, phi, rate; DEM units,
    d = rho_p = 1) of every steady point and seed."""
    require(blocks.point.nunique() >= 3, "steady calibration points", ">= 3 distinct inertial numbers",
            blocks.point.nunique())
    groups = [[b[["tau", "p", "phi", "rate"]].to_numpy() for _, b in pt.groupby("seed")]
              for _, pt in blocks.groupby("point")]
    I, mu, phi = _point_means(groups)
    require((I <= LINEAR_I_MAX).sum() >= 2, "steady calibration points", f">= 2 with I <= {LINEAR_I_MAX:g} "
            "(the linear fits)", int((I <= LINEAR_I_MAX).sum()))
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    draws = [_point_means(groups, rng) for _ in range(n_boot)]
    err = {k: np.std([d[i] for d in draws], axis=0, ddof=1) for i, k in enumerate(("I", "mu", "phi"))}
    sigma = np.maximum(err["mu"], 1e-12)
    best = fit_laws(I, mu, phi, sigma)
    reps = [fit_laws(*d, sigma, p0=best[:3]) for d in draws]
    points = pd.DataFrame({"I": I, "I_err": err["I"], "mu": mu, "mu_err": err["mu"], "phi": phi,
                           "phi_err": err["phi"]})
    rms = np.sqrt(np.mean((mu_law(I, *best[:3]) - mu) ** 2))
    return from_replicates(best, reps, points, PLANE_SHEAR, source, rms)
