"""mu(I) and phi(I) fits with bootstrap intervals: the independent plane-shear calibration
(``granstokes dem calibrate``, read back from its calibration.json) and, labelled as a fit and not a
prediction, the Stokes drives' own steady windows.

Laws, I in the DEM convention (I = |du/dy| d/sqrt(p/rho_p); I0_dem = 2 I0_paper):

* Jop form mu = mu_s + (mu_d - mu_s)/(1 + I0/I) (continuum.rheology.jop_law, what the continuum uses);
* linear form mu = mu_1 + b I and phi = phi_max - a I, both on I <= LINEAR_I_MAX (the range where
  da Cruz et al. 2005 and GDR MiDi 2004 find them linear).

Intervals: 95 % percentile intervals of N_BOOTSTRAP replicates.  Plane shear: each replicate
resamples, for every point, the seeds with replacement and then each drawn seed's blocks (blocks
longer than the autocorrelation time, dem.calibrate) with replacement, and refits with the weights of
the original fit.  In-drive fit: the steady (mu, I) pairs are resampled with replacement (one pair per
PAIR_SPACING of depth, themselves correlated in time: its intervals are optimistic).
The replicates (joint samples of mu_s, mu_d, I0, phi_max, a) carry the joint uncertainty.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.optimize import curve_fit

from continuum.rheology import convert_I, jop_law
from continuum.scales import Material
from dem.layout import POINTS_CSV
from granstokes.validate import require

WALL_EXCLUSION = 2.0  # d
I_MIN = 1e-3
PAIR_SPACING = 1.0  # d: one (mu, I) pair per d of depth, about the coarse-graining's correlation length
LINEAR_I_MAX = 0.3
N_BOOTSTRAP = 500
BOOTSTRAP_SEED = 10
#: the kinds of calibration: an independent measurement (a prediction follows) or a fit on the drives
PLANE_SHEAR, IN_DRIVE = "plane shear (independent)", "fit on the drives' steady windows (not a prediction)"
JOP_BOUNDS = ([0.0, 0.0, 1e-6], [2.0, 3.0, 50.0])
#: replicate keys of calibration.json (the issue-10 contract) and the parameter each one samples
REPLICATE_KEYS = {"mu_s": "mu_s", "mu_d": "mu_d", "I0": "I0_dem", "phi_max": "phi_max", "a": "phi_slope"}


#: published plane-shear (or rheometry) values shown beside the fit; I in the DEM convention.  Only what
#: ``verified`` says was checked against the source; the constants are the literature values as quoted
#: in the project's notes.
PUBLISHED = (
    {"source": "da Cruz et al., Phys. Rev. E 72, 021309 (2005)", "dimension": 2,
     "system": "2D polydisperse disks, mu_p = 0.4, plane shear at controlled pressure (DEM)",
     "mu_1": 0.26, "b": 1.0, "phi_max": 0.81, "a": 0.3,
     "verified": "the linear forms mu = mu_min + b I, phi = phi_max - a I (abstract); constants not checked "
                 "against the paper's tables"},
    {"source": "Kamrin & Koval, Phys. Rev. Lett. 108, 178301 (2012)", "dimension": 2,
     "system": "2D disks (the da Cruz/Koval DEM family), local part of the nonlocal law",
     "mu_1": 0.28, "b": 1.1, "verified": "not checked"},
    {"source": "Jop, Forterre & Pouliquen, Nature 441, 727 (2006)", "dimension": 3,
     "system": "3D glass beads (experiments; |gamma_dot| = du/dy in simple shear, so I is the DEM convention)",
     "mu_s": 0.382, "mu_d": 0.643, "I0": 0.279, "verified": "the values the paper preset uses"},
)


def mu_law(I, mu_s, mu_d, I0):
    """The Jop law's value (continuum.rheology.jop_law) as curve_fit's model function."""
    return jop_law(I, mu_s, mu_d, I0)[0]


def _fit_once(I, mu, phi, sigma, p0=None) -> np.ndarray:
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

    @property
    def is_prediction(self) -> bool:
        """True when mu(I) comes from an independent measurement, so the drives are a blind test."""
        return self.kind == PLANE_SHEAR

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
        """calibration.json's keys as issue 10 specifies them (the caller adds grains and provenance)."""
        ci = {k: list(v) for k, v in self.ci95.items()}
        return {"mu_s": self.mu_s, "mu_d": self.mu_d, "I0": self.I0_dem, "I_convention": "dem",
                "ci95": {"mu_s": ci["mu_s"], "mu_d": ci["mu_d"], "I0": ci["I0_dem"]},
                "linear": {"mu_1": self.mu_1, "b": self.b, "ci95": {"mu_1": ci["mu_1"], "b": ci["b"]},
                           "I_max": LINEAR_I_MAX},
                "phi": {"phi_max": self.phi_max, "a": self.phi_slope,
                        "ci95": {"phi_max": ci["phi_max"], "a": ci["phi_slope"]}, "I_max": LINEAR_I_MAX},
                "replicates": {k: [float(x) for x in self.replicates[p]] for k, p in REPLICATE_KEYS.items()}}


def _calibration(best, reps, points, kind, source, rms, **extra) -> Calibration:
    reps = np.asarray(reps)
    ci = {p: (float(np.percentile(reps[:, i], 2.5)), float(np.percentile(reps[:, i], 97.5)))
          for i, p in enumerate(PARAMS)}
    return Calibration(*map(float, best), ci, {p: reps[:, i] for i, p in enumerate(PARAMS)}, points, kind, source,
                       float(rms), **extra)


def fit(pairs: pd.DataFrame, wall_exclusion: float = WALL_EXCLUSION, I_min: float = I_MIN,
        n_boot: int = N_BOOTSTRAP) -> Calibration:
    """The in-drive fit on a table with columns I_dem, mu, phi (steady windows away from the walls,
    chosen by the caller, who states ``wall_exclusion``); creep below ``I_min`` excluded."""
    sel = pairs[(pairs.I_dem > I_min) & np.isfinite(pairs.mu) & np.isfinite(pairs.I_dem)]
    require(len(sel) >= 6, "calibration points", ">= 6 steady (mu, I) pairs with I > I_min", len(sel))
    I, mu, phi = sel.I_dem.to_numpy(), sel.mu.to_numpy(), sel.phi.to_numpy()
    best = _fit_once(I, mu, phi, None)
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    reps = []
    for _ in range(n_boot):
        k = rng.integers(0, len(I), len(I))
        if (I[k] <= LINEAR_I_MAX).sum() >= 2:
            reps.append(_fit_once(I[k], mu[k], phi[k], None, p0=best[:3]))
    points = pd.DataFrame({"I": I, "mu": mu, "phi": phi, "drive": sel.get("drive", pd.Series([""] * len(I))).to_numpy()})
    rms = np.sqrt(np.mean((mu_law(I, *best[:3]) - mu) ** 2))
    return _calibration(best, reps, points, IN_DRIVE, "fit on the steady windows of the runs compared", rms,
                        wall_exclusion=wall_exclusion, I_min=I_min)


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
    best = _fit_once(I, mu, phi, sigma)
    reps = [_fit_once(*d, sigma, p0=best[:3]) for d in draws]
    points = pd.DataFrame({"I": I, "I_err": err["I"], "mu": mu, "mu_err": err["mu"], "phi": phi,
                           "phi_err": err["phi"]})
    rms = np.sqrt(np.mean((mu_law(I, *best[:3]) - mu) ** 2))
    return _calibration(best, reps, points, PLANE_SHEAR, source, rms)


def load(path: str | Path) -> Calibration:
    """A calibration.json written by ``granstokes dem calibrate`` (its points.csv beside it)."""
    path = Path(path)
    require(path.is_file(), "--calibration", "a calibration.json written by granstokes dem calibrate", str(path))
    try:
        doc = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise ValueError(f"--calibration {path} is not valid JSON: {exc}") from None
    missing = sorted({"mu_s", "mu_d", "I0", "I_convention", "ci95", "linear", "phi", "replicates", "grains"} - set(doc))
    require(not missing, f"--calibration {path}", "a calibration.json with the issue-10 keys", f"missing {missing}")
    require(doc["I_convention"] == "dem", f"--calibration {path}: I_convention", "'dem'", doc["I_convention"])
    lin, ph, ci = doc["linear"], doc["phi"], doc["ci95"]
    rep = doc["replicates"]
    n = len(rep["mu_s"])
    replicates = {"mu_s": rep["mu_s"], "mu_d": rep["mu_d"], "I0_dem": rep["I0"], "phi_max": rep["phi_max"],
                  "phi_slope": rep["a"], "mu_1": [np.nan] * n, "b": [np.nan] * n}
    points_path = path.parent / POINTS_CSV
    points = pd.read_csv(points_path) if points_path.exists() else pd.DataFrame(columns=["I", "mu", "phi"])
    return Calibration(doc["mu_s"], doc["mu_d"], doc["I0"], lin["mu_1"], lin["b"], ph["phi_max"], ph["a"],
                       {"mu_s": tuple(ci["mu_s"]), "mu_d": tuple(ci["mu_d"]), "I0_dem": tuple(ci["I0"]),
                        "mu_1": tuple(lin["ci95"]["mu_1"]), "b": tuple(lin["ci95"]["b"]),
                        "phi_max": tuple(ph["ci95"]["phi_max"]), "phi_slope": tuple(ph["ci95"]["a"])},
                       {k: np.asarray(v, dtype=float) for k, v in replicates.items()}, points, PLANE_SHEAR,
                       str(path), float(doc.get("rms_mu", np.nan)), grains=doc["grains"],
                       info={k: doc[k] for k in ("provenance", "protocol", "published") if k in doc})
