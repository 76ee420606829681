"""The whole comparison, built once before anything is rendered: every drive's DEM analysis, the mu(I)
calibration, the continuum predictions from it, and the checks of the coarse-graining.

``build(run_dirs, settings)`` -> ``Comparison`` (frozen).  compare.metrics and compare.report only
render it.  DEM units throughout; I in the DEM convention.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from tqdm import tqdm

from continuum.crossing import crossing_depth
from continuum.scales import Material, Scales
from continuum.steady import DELTA_THRESHOLD
from granstokes.validate import require

from . import calibrate
from .analysis import DriveAnalysis, analyse_drive, drive_specs, mass_error, snapshot_times
from .checks import CROSSCHECK_MARGIN, lammps_crosscheck, width_check
from .models import LOCAL, PAPER, Prediction, ngf_model
from .nonlocal_fit import A_RANGE, FluidityFit, fit_amplitude
from .plate import STEADY_WINDOW_LATEST, power_law
from .profiles import CGSettings
from .scorecard import Z95, Scorecard, scene_checks, score

#: smoothing of mu_w(t) before the paper's threshold is applied (delta_mu), in time units: single
#: plate samples scatter by about their mean, the threshold is 1e-3 of the wall excess
MU_W_SMOOTHING = 0.5
#: continuum output times per drive (log-spaced from t_end/PREDICTION_SPAN to t_end, plus the snapshots)
PREDICTION_TIMES, PREDICTION_SPAN = 60, 300
#: calibration samples pushed through every steady prediction (bootstrap replicates of the fit)
REPLICATES = 200


@dataclass(frozen=True, eq=False)
class DriveComparison:
    """One drive: the DEM analysis, the paper's scales with the calibrated material, the continuum
    predictions (empty with ``note`` saying why when the calibrated law cannot sustain the drive) and
    delta_mu(t) (the paper's threshold on mu, aligned with ``dem.delta.t``)."""

    dem: DriveAnalysis
    scales: Scales | None
    predictions: tuple[Prediction, ...]
    note: str
    delta_mu: np.ndarray

    @property
    def label(self) -> str:
        return self.dem.label


@dataclass(frozen=True)
class Checks:
    """Coarse-graining checks on the first drive: kernel-width plateau and LAMMPS's own chunk
    averages (``crosscheck_bulk``: mean |CG - LAMMPS| / mean |LAMMPS| per quantity in the bulk)."""

    drive: str
    width: pd.DataFrame
    crosscheck: pd.DataFrame
    crosscheck_bulk: dict

    @property
    def plateau(self) -> pd.DataFrame:
        """Fraction of heights where each field plateaus going from each width to the next."""
        w = self.width[self.width.width > self.width.width.min()]
        return w.groupby(["field", "width"]).plateau.mean().unstack()


@dataclass(frozen=True, eq=False)
class Comparison:
    runs: tuple[Path, ...]
    drives: tuple[DriveComparison, ...]
    pairs: pd.DataFrame
    calibration: calibrate.Calibration
    calibration_source: str
    replicates: pd.DataFrame     # joint samples mu_s, mu_d, I0 (DEM convention), phi
    material: Material
    phi_bulk: float
    mass_error: float
    checks: Checks
    scorecard: Scorecard
    fluidity: FluidityFit | None  # the NGF amplitude and the drive it was fitted on
    settings: CGSettings


def steady_pairs(drives: list[DriveAnalysis], wall_exclusion: float = calibrate.WALL_EXCLUSION,
                 spacing: float = calibrate.PAIR_SPACING) -> pd.DataFrame:
    """(mu, I_dem, phi) of every steady window, away from plate and base, one point per ``spacing``
    in depth (the kernel correlates neighbouring grid points: the fit's intervals need independent ones),
    with the standard errors of mu and phi from the window's band."""
    rows = []
    for a in drives:
        p = a.steady_profile
        inside = p[(p.depth > wall_exclusion) & (p.depth < a.spec.depth - wall_exclusion)]
        step = max(1, int(round(spacing / abs(np.diff(inside.y.to_numpy()[:2])[0]))))
        pick = inside.iloc[::step]
        rows.append(pick[["depth", "mu", "I_dem", "phi", "p", "tau"]].assign(
            drive=a.label, mu_err=(pick.mu_hi - pick.mu_lo) / (2 * Z95), phi_err=(pick.phi_hi - pick.phi_lo) / (2 * Z95)))
    return pd.concat(rows, ignore_index=True)


def delta_mu(a: DriveAnalysis, mu_s: float) -> np.ndarray:
    """The paper's definition on the DEM (continuum.steady.DELTA_THRESHOLD): the first depth below
    the wall layer where (mu - mu_s)/(mu_w(t) - mu_s) falls under 1e-3, mu_s the calibrated one.
    Reported beside delta_u; single-frame mu fluctuates by more than the threshold, so it is noise-bound."""
    dt = float(np.median(np.diff(a.series.t)))
    window = max(1, int(round(MU_W_SMOOTHING / dt)))
    mu_w_smooth = a.series.mu_w.rolling(window, center=True, min_periods=1).mean()
    out = []
    for t in a.delta.t:
        frame = a.instant[np.isclose(a.instant.t, t)].sort_values("depth")
        keep = (frame.depth >= calibrate.WALL_EXCLUSION) & np.isfinite(frame.mu)
        mu_w = float(np.interp(t, a.series.t, mu_w_smooth))
        excess = (frame.mu[keep].to_numpy() - mu_s) / (mu_w - mu_s)
        out.append(crossing_depth(frame.depth[keep].to_numpy(), excess, DELTA_THRESHOLD, order=1))
    return np.array(out, dtype=float)


def early_exponents(a: DriveAnalysis) -> dict:
    """alpha of u_w ~ t^alpha (imposed stress) and delta_u ~ t^alpha over the early window: from the
    first output after the elastic start (spec.compared_from) to the time u_w (delta_u) reaches half its
    steady value."""
    out = {}
    t, u = a.series.t.to_numpy(), a.series.u_w.to_numpy()
    start = np.nan_to_num(a.spec.compared_from)
    if a.spec.kind == "stress":
        half = t[np.argmax(u >= 0.5 * a.steady["u_w"]["value"])]
        out["alpha_u"] = power_law(t, u, max(t[1], start), half)
    d = a.delta.dropna()
    d = d[d.t >= start]
    if len(d) >= 4:
        final = d.delta_u.iloc[-len(d) // 4:].mean()
        half = d.t.iloc[np.argmax(d.delta_u.to_numpy() >= 0.5 * final)]
        out["alpha_delta"] = power_law(d.t.to_numpy(), d.delta_u.to_numpy(), d.t.iloc[0], max(half, d.t.iloc[3]))
    return out


def _checks(a: DriveAnalysis) -> Checks:
    widths = width_check(a.spec.folders[0], STEADY_WINDOW_LATEST * a.t_end, a.t_end)
    cross = lammps_crosscheck(a.profiles[0])
    y = a.steady_profile.y
    bulk = cross[(cross.y > y.min() + CROSSCHECK_MARGIN) & (cross.y < y.max() - CROSSCHECK_MARGIN)]
    summary = {q: float(np.nanmean(np.abs(bulk[f"{q}_diff"])) / np.nanmean(np.abs(bulk[f"{q}_lammps"])))
               for q in ("phi", "u_x", "p", "tau_yx", "p_mop", "tau_mop")}
    return Checks(a.label, widths, cross, summary)


def _predict(a: DriveAnalysis, material: Material, models) -> DriveComparison:
    s = a.spec
    dm = delta_mu(a, material.mu_s)
    try:
        scales = (Scales(material, s.p_w, s.value / s.p_w) if s.kind == "stress"
                  else Scales.for_speed(material, s.p_w, s.value))
    except ValueError as err:  # e.g. tau_w >= mu_d p_w: local mu(I) has no steady state at all
        return DriveComparison(a, None, (), f"no continuum prediction: {err} (the calibrated mu(I) cannot sustain "
                                            "this drive: the plate would accelerate forever)", dm)
    t_end = float(a.series.t.iloc[-1])
    times = np.union1d(np.geomspace(t_end / PREDICTION_SPAN, t_end, PREDICTION_TIMES), snapshot_times(a))
    preds = tuple(model.predict(material, s.drive, times) for model in models)
    return DriveComparison(a, scales, preds, "", dm)


def fit_replicates(pairs: pd.DataFrame, phi: float, n: int = REPLICATES, seed: int = 0) -> pd.DataFrame:
    """Joint samples of the in-drive fit: refits on pairs resampled with replacement (bootstrap);
    phi is the bulk mean of each resample."""
    rng = np.random.default_rng(seed)
    rows = []
    while len(rows) < n:
        sample = pairs.iloc[rng.integers(0, len(pairs), len(pairs))]
        try:
            c = calibrate.fit(sample)
        except (ValueError, RuntimeError):  # too few usable points, or no convergence
            continue
        rows.append({"mu_s": c.mu_s, "mu_d": c.mu_d, "I0": c.I0_dem, "phi": float(sample.phi.mean())})
    return pd.DataFrame(rows)


def build(run_dirs, settings: CGSettings = CGSettings(), progress: bool = True) -> Comparison:
    """Analyse every drive of ``run_dirs``, calibrate on their steady windows, predict each drive."""
    runs = tuple(Path(r) for r in run_dirs)
    resolved = [r.resolve() for r in runs]
    require(len(set(resolved)) == len(resolved), "RUN_DIR", "distinct run folders (one was given twice)",
            [str(r) for r in runs])
    specs = [spec for run in runs for spec in drive_specs(run)]
    drives = [analyse_drive(spec, settings) for spec in tqdm(specs, desc="coarse-graining", disable=not progress)]
    pairs = steady_pairs(drives)
    cal = calibrate.fit(pairs)
    phi = float(pairs.phi.mean())
    material = cal.material(phi=phi)
    replicates = fit_replicates(pairs, phi)
    fluidity = _fit_fluidity(drives, material)
    models = [LOCAL, PAPER] + ([ngf_model(fluidity.A)] if fluidity else [])
    if fluidity:
        replicates = replicates.assign(A=_amplitude_samples(fluidity, len(replicates)))
    compared = tuple(_predict(a, material, models)
                     for a in tqdm(drives, desc="continuum predictions", disable=not progress))
    predictions = {(dc.label, p.model): p for dc in compared for p in dc.predictions}
    delta_s = {dc.label: dc.predictions[0].steady.delta_s for dc in compared if dc.predictions}
    t0 = {a.label: a.t_window for a in drives}
    rows, edges, bands = score([dc.dem for dc in compared if dc.predictions], models, predictions, material, replicates,
                        delta_s, t0, {"ngf": fluidity.drive} if fluidity else {}, progress)
    card = Scorecard.of(rows, [r for a in drives for r in scene_checks(a, phi)], len(replicates), edges, bands)
    return Comparison(runs, compared, pairs, cal, "in-drive fit (not a blind test)", replicates, material, phi,
                      mass_error(drives[0]), _checks(drives[0]), card, fluidity, settings)


def _fit_fluidity(drives: list[DriveAnalysis], material: Material) -> FluidityFit | None:
    """A of the NGF model, fitted on the creep of the first imposed-stress drive that local mu(I) can
    sustain (compare.nonlocal_fit); None when there is none."""
    for a in drives:
        if a.spec.kind == "stress" and a.spec.value / a.spec.p_w < material.mu_d:
            return fit_amplitude(a, material)
    return None


def _amplitude_samples(fit: FluidityFit, n: int, seed: int = 1) -> np.ndarray:
    """Samples of A for the propagation: normal with the fit's standard error (independent of the
    material's replicates: A is fitted given the central calibration), kept inside the search range."""
    err = fit.err if np.isfinite(fit.err) else 0.0
    return np.clip(np.random.default_rng(seed).normal(fit.A, err, n), *A_RANGE)
