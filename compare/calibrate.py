"""mu(I) for the comparison: the independent plane-shear calibration read back from its calibration.json
(``load``), or, labelled as a fit and not a prediction, a fit on the Stokes drives' own steady windows
(``fit``: the steady (mu, I) pairs resampled with replacement for the bootstrap, one pair per
PAIR_SPACING of depth, themselves correlated in time, so its intervals are optimistic); and the
published plane-shear values the report shows beside them.  The fitting itself is continuum.calibration's.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
from granstokes.continuum.calibration import (
    BOOTSTRAP_SEED,
    IN_DRIVE,
    LINEAR_I_MAX,
    N_BOOTSTRAP,
    PLANE_SHEAR,
    Calibration,
    fit_laws,
    from_replicates,
    mu_law,
)
from granstokes.dem.layout import POINTS_CSV

from granstokes.lib.validate import require

WALL_EXCLUSION = 2.0  # d
I_MIN = 1e-3
PAIR_SPACING = 1.0  # d: one (mu, I) pair per d of depth, about the coarse-graining's correlation length

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


def fit(pairs: pd.DataFrame, wall_exclusion: float = WALL_EXCLUSION, I_min: float = I_MIN,
        n_boot: int = N_BOOTSTRAP) -> Calibration:
    """The in-drive fit on a table with columns I_dem, mu, phi (steady windows away from the walls,
    chosen by the caller, who states ``wall_exclusion``); creep below ``I_min`` excluded from the fit.
    Bootstrap: the pairs resampled with replacement; ``replicates["phi_bulk"]`` is each resample's mean phi."""
    def usable(t):
        return t[(t.I_dem > I_min) & np.isfinite(t.mu) & np.isfinite(t.I_dem)]

    sel = usable(pairs)
    require(len(sel) >= 6, "calibration points", ">= 6 steady (mu, I) pairs with I > I_min", len(sel))
    I, mu, phi = sel.I_dem.to_numpy(), sel.mu.to_numpy(), sel.phi.to_numpy()
    best = fit_laws(I, mu, phi, None)
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    reps, phi_bulk = [], []
    while len(reps) < n_boot:
        sample = pairs.iloc[rng.integers(0, len(pairs), len(pairs))]
        s = usable(sample)
        if len(s) < 6 or (s.I_dem <= LINEAR_I_MAX).sum() < 2:
            continue
        try:
            reps.append(fit_laws(s.I_dem.to_numpy(), s.mu.to_numpy(), s.phi.to_numpy(), None, p0=best[:3]))
        except RuntimeError:  # no convergence on this resample
            continue
        phi_bulk.append(float(sample.phi.mean()))
    points = pd.DataFrame({"I": I, "mu": mu, "phi": phi,
                           "drive": sel.get("drive", pd.Series([""] * len(I))).to_numpy()})
    rms = np.sqrt(np.mean((mu_law(I, *best[:3]) - mu) ** 2))
    cal = from_replicates(best, reps, points, IN_DRIVE, "fit on the steady windows of the runs compared", rms,
                          wall_exclusion=wall_exclusion, I_min=I_min)
    cal.replicates["phi_bulk"] = np.asarray(phi_bulk)
    return cal


def load(path: str | Path) -> Calibration:
    """A calibration.json written by ``granstokes dem calibrate`` (its points.csv beside it); its ``elasticity``
    (G, c_s of the static packing, dem.modulus) when it has one, else None."""
    path = Path(path)
    require(path.is_file(), "--calibration", "a calibration.json written by granstokes dem calibrate", str(path))
    try:
        doc = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise ValueError(f"--calibration {path} is not valid JSON: {exc}") from None
    missing = sorted({"mu_s", "mu_d", "I0", "I_convention", "ci95", "linear", "phi", "replicates", "grains"} - set(doc))
    require(not missing, f"--calibration {path}", "a complete calibration.json", f"missing {missing}")
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
                       info={k: doc[k] for k in ("provenance", "protocol", "published") if k in doc},
                       elasticity=doc.get("elasticity"))


def calibrated_range(cal: Calibration) -> tuple[float, float]:
    """The range of I (DEM convention) the calibration measured (its points): a model beyond it extrapolates the
    fitted law (compare.scorecard.extrapolated); NaNs when the calibration holds no points."""
    measured = cal.points["I"].to_numpy(dtype=float)
    return (float(measured.min()), float(measured.max())) if len(measured) else (np.nan, np.nan)
