"""From DEM run folders to continuum-comparable observables, a mu(I) calibration and predictions.

For every drive (pooled over its seeds): the plate record (u_w, mu_w), coarse-grained profiles
(compare.profiles) in the depth below the plate, zeta = y_plate - d/2 - y (the plate's grains have
unit diameter), the steady window (compare.plate.steady_state on the free response), delta_u(t)
from the instantaneous velocity profiles (compare.predict.depth_at_fraction), then a mu(I)/phi(I)
calibration pooled over all drives' steady windows (compare.calibrate) and, from it alone, the
continuum predictions (compare.predict).  DEM units throughout.
"""
from __future__ import annotations

import json
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from continuum.scales import Scales
from continuum.steady import DELTA_THRESHOLD

from . import calibrate
from .plate import PlateRecord, power_law, steady_state
from .predict import Prediction, depth_at_fraction, predict
from .profiles import CGSettings, DepthProfiles, ensemble
from .reader import BED, DriveFolder

PLATE_RADIUS = 0.5  # d: the plate's glued grains have unit diameter (dem/scene.py)


@dataclass
class DriveGroup:
    """One drive of one run, over its seeds."""

    run: Path
    name: str
    kind: str
    value: float                 # tau_w (stress) or u_w (speed)
    p_w: float
    depth: float                 # bed depth below the plate
    plate_mass: float            # per unit plate area
    folders: list[DriveFolder]
    plates: list[PlateRecord] = field(default_factory=list)
    profiles: list[DepthProfiles] = field(default_factory=list)
    series: pd.DataFrame | None = None
    steady: dict | None = None
    steady_profile: pd.DataFrame | None = None
    mean_profile: pd.DataFrame | None = None  # the whole run: hydrostatics need no steady state
    instant: pd.DataFrame | None = None       # seed-averaged profiles of every snapshot, with depth
    delta: pd.DataFrame | None = None
    predictions: list[Prediction] = field(default_factory=list)
    scales: Scales | None = None  # the paper's scales with the calibrated material
    prediction_note: str = ""     # why there is no prediction, when there is none

    @property
    def label(self) -> str:
        return f"{self.run.name}/{self.name}"

    @property
    def cost(self) -> float:
        """grains x steps of the drive summed over seeds (the DEM's work)."""
        meta = self.folders[0].meta
        steps = next(d["steps"] for d in meta["sizing"]["drives"] if d["name"] == self.name)
        return float(len(self.folders) * len(self.folders[0].grains) * steps)


def drive_groups(run_dir: Path) -> list[DriveGroup]:
    meta = json.loads((Path(run_dir) / "run.json").read_text())
    require_complete = [k for k, s in meta.get("stages", {}).items() if s.get("status") != "complete"]
    if require_complete:
        raise ValueError(f"{run_dir}: run not complete ({', '.join(require_complete)}); resume it first")
    groups = []
    for d in meta["sizing"]["drives"]:
        folders = [DriveFolder(Path(run_dir) / f"seed-{s}" / d["name"]) for s in meta["seeds"]]
        value = d["tau_w"] if d["kind"] == "stress" else d["u_w"]
        groups.append(DriveGroup(Path(run_dir), d["name"], d["kind"], float(value), float(meta["config"]["p_w"]),
                                 float(meta["sizing"]["depth"]), float(meta["plate"]["mass_per_area"]), folders))
    return groups


def _ensemble_series(plates: list[PlateRecord]) -> pd.DataFrame:
    t = plates[0].t
    cols = {}
    for name in ("u_w", "mu_w"):
        values = np.array([np.interp(t, p.t, getattr(p, name)) for p in plates])
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # mu_w is nan while the plate is out of contact
            mean = np.nanmean(values, axis=0)
        half = 1.96 * np.nanstd(values, axis=0, ddof=1) / np.sqrt(len(plates)) if len(plates) > 1 else np.nan * mean
        cols.update({name: mean, f"{name}_lo": mean - half, f"{name}_hi": mean + half})
    return pd.DataFrame({"t": t, **cols})


def analyse_drive(group: DriveGroup, settings: CGSettings) -> DriveGroup:
    group.plates = [PlateRecord.read(f.path, group.kind) for f in group.folders]
    group.series = _ensemble_series(group.plates)
    response = group.series.u_w if group.kind == "stress" else group.series.mu_w
    group.steady = steady_state(group.series.t.to_numpy(), response.to_numpy())
    for name in ("u_w", "mu_w"):
        group.steady[name] = steady_state(group.series.t.to_numpy(), group.series[name].to_numpy())
        group.steady[name]["stderr_over"] = "blocks of the final quarter"
        if len(group.plates) > 1:  # an ensemble: the error of the mean is the spread over seeds
            finals = [steady_state(p.t, getattr(p, name))["value"] for p in group.plates]
            group.steady[name]["stderr"] = float(np.std(finals, ddof=1) / np.sqrt(len(finals)))
            group.steady[name]["stderr_over"] = "seeds"
    first = group.folders[0]
    grid = settings.grid_for(next(first.frames([0])))
    group.profiles = [DepthProfiles(f, settings, grid).run() for f in group.folders]
    surface = lambda t: group.plates[0].surface(t, PLATE_RADIUS * first.d)  # noqa: E731
    t_end = group.series.t.iloc[-1]
    t0 = group.steady["t_steady"] if np.isfinite(group.steady["t_steady"]) else 0.7 * t_end
    t0 = min(t0, 0.7 * t_end)
    win = ensemble(group.profiles, t0, t_end)
    win.insert(1, "depth", float(np.mean(surface([t0, t_end]))) - win.y)
    group.steady_profile = win
    whole = ensemble(group.profiles, float(group.profiles[0].results.t[0]), t_end)
    whole.insert(1, "depth", float(np.mean(surface(group.profiles[0].results.t))) - whole.y)
    group.mean_profile = whole
    inst = ensemble(group.profiles)
    inst.insert(3, "depth", surface(inst.t.to_numpy()) - inst.y.to_numpy())
    group.instant = inst
    rows = []
    for t, g in inst.groupby("t"):
        g = g[g.depth >= 0].sort_values("depth")
        u_w = float(np.interp(t, group.series.t, group.series.u_w))
        if t > 0 and u_w > 1e-2 * group.steady["u_w"]["value"]:
            rows.append((t, depth_at_fraction(g.depth.to_numpy(), g.u_x.to_numpy(), u_w)))
    group.delta = pd.DataFrame(rows, columns=["t", "delta_u"])
    return group


def delta_mu(g: DriveGroup, mu_s: float) -> np.ndarray:
    """The paper's definition on the DEM (continuum.steady.DELTA_THRESHOLD): the first depth below
    the wall layer where (mu - mu_s)/(mu_w(t) - mu_s) falls under 1e-3, mu_s the calibrated one.
    Reported beside delta_u; single-frame mu fluctuates by more than the threshold, so it is noise-bound."""
    mu_w_smooth = g.series.mu_w.rolling(25, center=True, min_periods=1).mean()
    out = []
    for t in g.delta.t:
        frame = g.instant[np.isclose(g.instant.t, t)].sort_values("depth")
        keep = (frame.depth >= calibrate.WALL_EXCLUSION) & np.isfinite(frame.mu)
        mu_w = float(np.interp(t, g.series.t, mu_w_smooth))
        excess = (frame.mu[keep].to_numpy() - mu_s) / (mu_w - mu_s)
        below = np.nonzero(excess < DELTA_THRESHOLD)[0]
        out.append(float(frame.depth[keep].iloc[below[0]]) if len(below) else np.nan)
    return np.array(out)


def snapshot_times(g: DriveGroup, n: int = 5) -> np.ndarray:
    """About ``n`` log-spaced times of the drive's atom snapshots (t > 0): the transient profiles."""
    t = g.folders[0].times()
    t = t[t > 0]
    picks = np.unique(np.searchsorted(t, np.geomspace(t[0], t[-1], n)).clip(0, len(t) - 1))
    return t[picks]


def steady_pairs(groups: list[DriveGroup], wall_exclusion: float = calibrate.WALL_EXCLUSION,
                 spacing: float = calibrate.PAIR_SPACING) -> pd.DataFrame:
    """(mu, I_dem, phi) of every steady window, away from plate and base, one point per ``spacing``
    in depth (the kernel correlates neighbouring grid points: the fit's intervals need independent ones)."""
    rows = []
    for g in groups:
        p = g.steady_profile
        inside = p[(p.depth > wall_exclusion) & (p.depth < g.depth - wall_exclusion)]
        step = max(1, int(round(spacing / abs(np.diff(inside.y.to_numpy()[:2])[0]))))
        rows.append(inside.iloc[::step][["depth", "mu", "I_dem", "phi", "p", "tau"]].assign(drive=g.label))
    return pd.concat(rows, ignore_index=True)


def bulk_phi(groups: list[DriveGroup], wall_exclusion: float = calibrate.WALL_EXCLUSION) -> float:
    pairs = steady_pairs(groups, wall_exclusion)
    return float(pairs.phi.mean())


def mass_error(group: DriveGroup) -> float:
    """Relative error of the integral of the coarse-grained phi over y against the bed grains'
    volume per unit area (first frame of the first seed; 2D: disk areas per unit length)."""
    drive, res = group.folders[0], group.profiles[0].results
    frame = next(drive.frames([0]))
    bed = frame.types == BED
    r = frame.radius[bed]
    volume = np.pi * r**2 if drive.dimension == 2 else 4 / 3 * np.pi * r**3
    widths = frame.box[:, 1] - frame.box[:, 0]
    area = widths[0] if drive.dimension == 2 else widths[0] * widths[2]
    integral = np.trapezoid(res.additive["phi"][0], res.y)
    return float(integral / (volume.sum() / area) - 1)


def analyse(run_dirs, settings: CGSettings = CGSettings(), n_times: int = 60) -> dict:
    """Everything the report needs: drive groups with predictions, the calibration, the pairs."""
    groups = [analyse_drive(g, settings) for run in run_dirs for g in drive_groups(Path(run))]
    pairs = steady_pairs(groups)
    cal = calibrate.fit(pairs)
    phi = bulk_phi(groups)
    material = cal.material(phi=phi)
    for g in groups:
        t_end = float(g.series.t.iloc[-1])
        times = np.union1d(np.geomspace(t_end / 300, t_end, n_times), snapshot_times(g))
        g.delta["delta_mu"] = delta_mu(g, material.mu_s)
        try:
            g.scales = (Scales(material, g.p_w, g.value / g.p_w) if g.kind == "stress"
                        else Scales.for_speed(material, g.p_w, g.value))
        except ValueError as err:  # e.g. tau_w >= mu_d p_w: local mu(I) has no steady state at all
            g.prediction_note = (f"no continuum prediction: {err} (the calibrated mu(I) cannot sustain this drive: "
                                 "the plate would accelerate forever)")
            continue
        g.predictions = predict(material, g.p_w, g.depth, g.plate_mass, g.kind, g.value, times)
    return {"groups": groups, "pairs": pairs, "calibration": cal, "material": material, "phi_bulk": phi,
            "mass_error": mass_error(groups[0]), "settings": settings}


def early_exponents(g: DriveGroup) -> dict:
    """alpha of u_w ~ t^alpha (imposed stress) and delta_u ~ t^alpha over the early window:
    from the first output to the time u_w (delta_u) reaches half its steady value."""
    out = {}
    t, u = g.series.t.to_numpy(), g.series.u_w.to_numpy()
    if g.kind == "stress":
        half = t[np.argmax(u >= 0.5 * g.steady["u_w"]["value"])]
        out["alpha_u"] = power_law(t, u, t[1], half)
    d = g.delta.dropna()
    if len(d) >= 4:
        final = d.delta_u.iloc[-len(d) // 4:].mean()
        half = d.t.iloc[np.argmax(d.delta_u.to_numpy() >= 0.5 * final)]
        out["alpha_delta"] = power_law(d.t.to_numpy(), d.delta_u.to_numpy(), d.t.iloc[0], max(half, d.t.iloc[3]))
    return out
