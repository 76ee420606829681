"""One DEM drive, pooled over its seeds, as continuum-comparable observables (DEM units throughout).

``analyse_drive(spec, settings)`` -> ``DriveAnalysis`` (frozen): the plate record (u_w, mu_w), the
coarse-grained profiles (compare.profiles) in the depth below the plate's contact plane
(dem.layout.plate_surface), the steady window (compare.plate.steady_state on the free response),
delta_u(t) from the instantaneous velocity profiles (continuum.crossing), the slip of the grains
touching the plate, and the bulk shear-stress check (the coarse-grained tau of the steady window against
the plate's <tau_w> over the same window).  Every steady value carries an error (compare.plate: spread
over >= 3 seeds, else blocks longer than the autocorrelation time).  Nothing here depends on a
calibration: compare.comparison adds that.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd
from granstokes.continuum.crossing import LAYER_FRACTIONS, depth_at_fraction, layer_measures
from granstokes.dem import layout

from .calibrate import WALL_EXCLUSION
from .drive import DriveSpec
from .plate import (
    STEADY_LAST,
    STEADY_WINDOW_LATEST,
    PlateRecord,
    block_estimate,
    pooled,
    slip,
    steady_state,
    steady_window_start,
    tail,
    window_values,
)
from .profiles import CGSettings, DepthProfiles, derive, ensemble


@dataclass(frozen=True, eq=False)
class DriveAnalysis:
    """The DEM side of one drive: plate records, ensemble series (mean and 95 % band over seeds),
    steady values, coarse-grained profiles (steady window, whole run, every snapshot) and delta_u(t)."""

    spec: DriveSpec
    plates: tuple[PlateRecord, ...]
    profiles: tuple[DepthProfiles, ...]
    series: pd.DataFrame         # t, u_w, mu_w (+ _lo, _hi)
    steady: dict                 # u_w, mu_w: steady_state dicts with pooled errors; t_steady of the free response
    t_window: float              # start of the steady window (compare.plate.steady_window_start)
    t_end: float                 # its end: the record's, or the last whole frame of a truncated dump
    slip: dict                   # pooled slip of the grains touching the plate (compare.plate.slip)
    bulk_tau: dict               # coarse-grained bulk tau of the steady window vs the plate's <tau_w>
    steady_profile: pd.DataFrame  # window average over the steady window, with depth
    mean_profile: pd.DataFrame   # the whole run: hydrostatics need no steady state
    instant: pd.DataFrame        # seed-averaged profiles at the snapshot times, with depth
    delta: pd.DataFrame          # t, delta_u
    snapshots: np.ndarray        # times of the transient profiles shown and predicted (snapshot_times)
    samples: tuple[pd.DataFrame, ...]  # independent steady-window profiles (steady_samples)
    samples_how: str             # what they are: seeds or blocks of one seed
    frames: int                  # snapshots of a bed
    dropped_frames: int          # snapshots lost to truncated dumps, over the seeds
    layers: pd.DataFrame         # every seed's layer over time (layer_series): seed, t, u_w, depths, moment

    @property
    def response(self) -> str:
        """What the drive leaves free: u_w under an imposed stress, mu_w under an imposed speed."""
        return "u_w" if self.spec.kind == "stress" else "mu_w"

    @property
    def label(self) -> str:
        return self.spec.label

    def surface(self, t):
        """Height of the plate's contact plane at times ``t`` (first seed's plate record)."""
        p = self.plates[0]
        return layout.plate_surface(np.interp(t, p.t, p.y), self.spec.surface_offset)


def _ensemble_series(plates: tuple[PlateRecord, ...]) -> pd.DataFrame:
    t = plates[0].t
    cols = {}
    for name in ("u_w", "mu_w"):
        values = np.array([np.interp(t, p.t, getattr(p, name)) for p in plates])
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # mu_w is nan while the plate is out of contact
            mean = np.nanmean(values, axis=0)
            if name == "mu_w":  # ratio of the seed-mean stresses
                tau, p_ = ([np.interp(t, p.t, getattr(p, k)) for p in plates] for k in ("tau_w", "p"))
                mean = np.where(np.mean(p_, axis=0) > 0, np.mean(tau, axis=0) / np.mean(p_, axis=0), np.nan)
            half = (1.96 * np.nanstd(values, axis=0, ddof=1) / np.sqrt(len(plates)) if len(plates) > 1
                    else np.nan * mean)
        cols.update({name: mean, f"{name}_lo": mean - half, f"{name}_hi": mean + half})
    return pd.DataFrame({"t": t, **cols})


def _steady(series: pd.DataFrame, plates, response: str) -> dict:
    """t_steady of the free response; u_w and mu_w (= <tau_w>/<p>) over the last quarter, pooled over
    the seeds with their errors (``stderr``, ``method``)."""
    t = series.t.to_numpy()
    steady = {"t_steady": steady_state(t, series[response].to_numpy())["t_steady"]}
    t_last = t[0] + STEADY_LAST * (t[-1] - t[0])
    per = [window_values(p, t_last) for p in plates]
    for name in ("u_w", "mu_w"):
        steady[name] = {**steady_state(t, series[name].to_numpy()), **pooled([w[name] for w in per])}
        steady[name]["window"] = [float(t_last), float(t[-1])]
    return steady


def bulk_tau(plates, profiles, surface, depth: float, t0: float, t1: float) -> dict:
    """The coarse-grained shear stress tau = -sigma_xy (contact + kinetic) averaged over the bulk
    (WALL_EXCLUSION from plate and base) in each frame of [t0, t1] with contacts, against the plate's
    <tau_w> over the same window; both with block errors pooled over the seeds.  ``agree``: the
    difference is within 2 standard errors of the difference (95 %)."""
    cg, plate, frames = [], [], 0
    for rec, prof in zip(plates, profiles):
        r = prof.results
        sel = (r.t >= t0 - 1e-9) & (r.t <= t1 + 1e-9) & r.has_contacts
        add = {k: v[sel] for k, v in r.additive.items()}
        tau = derive(add, r.y, prof.drive.dimension, prof.drive.d, prof.drive.rho_p)["tau"]
        d = surface(r.t[sel])[:, None] - r.y[None, :]
        inside = (d > WALL_EXCLUSION) & (d < depth - WALL_EXCLUSION)
        per_frame = np.nanmean(np.where(inside, tau, np.nan), axis=1)
        frames += len(per_frame)
        cg.append(block_estimate({"tau": per_frame}))
        plate.append(block_estimate({"tau": tail(rec, t0)["tau_w"]}))
    a, b = pooled(cg), pooled(plate)
    diff, err = a["value"] - b["value"], float(np.hypot(a["stderr"], b["stderr"]))
    return {"cg": a, "plate": b, "difference": diff, "difference_stderr": err, "agree": bool(abs(diff) <= 2 * err),
            "window": [t0, t1], "frames": frames,
            "definition": "bulk = depths within (wall exclusion, depth - wall exclusion); agree = |cg - plate| <= "
                          "2 stderr of the difference"}


def _with_depth(table: pd.DataFrame, depth_of_y) -> pd.DataFrame:
    table = table.copy()
    table.insert(1, "depth", depth_of_y)
    return table


def plate_estimates(plates: tuple[PlateRecord, ...], kind: str) -> tuple[pd.DataFrame, dict, dict]:
    """What the plate records alone give: the ensemble series, the steady values and the slip, pooled over seeds."""
    series = _ensemble_series(plates)
    steady = _steady(series, plates, "u_w" if kind == "stress" else "mu_w")
    return series, steady, pooled([slip(p) for p in plates])


def analyse_drive(spec: DriveSpec, settings: CGSettings = CGSettings()) -> DriveAnalysis:
    plates = tuple(PlateRecord.read(f.path) for f in spec.beds)
    series, steady, slips = plate_estimates(plates, spec.kind)
    rise = max(float(np.max(p.y) - p.y[0]) for p in plates)
    grid = settings.grid_for([next(bed.frames([0])) for bed in spec.beds], rise=rise)
    profiles = tuple(DepthProfiles(f, settings, grid).run() for f in spec.beds)
    surface = lambda t: layout.plate_surface(np.interp(t, plates[0].t, plates[0].y), spec.surface_offset)  # noqa: E731
    # the record ends with the plate's, or earlier where a truncated dump lost its last frames
    t_end = min(float(series.t.iloc[-1]), *(float(p.results.t[-1]) for p in profiles))
    t0 = steady_window_start(steady["t_steady"], t_end)
    win = ensemble(list(profiles), t0, t_end)
    steady_profile = _with_depth(win, float(np.mean(surface([t0, t_end]))) - win.y)
    whole = ensemble(list(profiles), float(profiles[0].results.t[0]), t_end)
    mean_profile = _with_depth(whole, float(np.mean(surface(profiles[0].results.t))) - whole.y)
    inst = ensemble(list(profiles))
    inst.insert(3, "depth", surface(inst.t.to_numpy()) - inst.y.to_numpy())
    snapshots = snapshot_times(spec.beds[0].times())
    rows = []
    u_scale = steady["u_w"]["value"]
    for t, g in inst.groupby("t"):
        g = g[g.depth >= 0].sort_values("depth")
        u_w = float(np.interp(t, series.t, series.u_w))
        if t > 0 and u_w > DELTA_MIN_SPEED * u_scale:
            rows.append((t, depth_at_fraction(g.depth.to_numpy(), g.u_x.to_numpy(), u_w)))
    delta = pd.DataFrame(rows, columns=["t", "delta_u"])
    # the final 30 %: a steady plate record can begin while the creep below still deepens (the bed's
    # momentum still grows and the bulk tau lags the plate's)
    check = bulk_tau(plates, profiles, surface, spec.depth, STEADY_WINDOW_LATEST * t_end, t_end)
    samples, how = steady_samples(profiles, surface, t0, t_end)
    shown = inst[np.isin(inst.t, snapshots)].reset_index(drop=True)
    dropped = sum(f.atoms.dropped + f.contacts.dropped for f in spec.beds)
    layers = pd.concat([layer_series(prof, plate, spec.surface_offset, u_scale).assign(seed=i)
                        for i, (prof, plate) in enumerate(zip(profiles, plates))], ignore_index=True)
    return DriveAnalysis(spec, plates, profiles, series, steady, t0, t_end, slips, check, steady_profile,
                         mean_profile, shown, delta, snapshots, samples, how, len(profiles[0].results.steps), dropped,
                         layers)


def layer_series(prof: DepthProfiles, plate: PlateRecord, surface_offset: float, u_scale: float) -> pd.DataFrame:
    """One seed's layer in every frame (t > 0, its plate at DELTA_MIN_SPEED of ``u_scale`` or faster): the plate's
    u_w and continuum.crossing.layer_measures of the coarse-grained u_x below its own plate."""
    r, drive = prof.results, prof.drive
    u = derive(r.additive, r.y, drive.dimension, drive.d, drive.rho_p)["u_x"]
    rows = []
    for k, t in enumerate(r.t):
        u_w = float(np.interp(t, plate.t, plate.u_w))
        if t > 0 and u_w > DELTA_MIN_SPEED * u_scale:
            surface = layout.plate_surface(float(np.interp(t, plate.t, plate.y)), surface_offset)
            rows.append({"t": float(t), "u_w": u_w, **layer_measures(surface - r.y, u[k], u_w)})
    return pd.DataFrame(rows, columns=["t", "u_w", *LAYER_FRACTIONS, "moment"])


#: blocks of a single seed's steady window that stand for independent samples (steady_samples)
BLOCKS = 4


def steady_samples(profiles, surface, t0: float, t_end: float) -> tuple[tuple[pd.DataFrame, ...], str]:
    """Independent steady-window profiles (every field, with depth below the plate's contact plane
    ``surface(t)``, sorted by depth): one per seed, or BLOCKS consecutive blocks of a single seed's window."""
    if len(profiles) >= 2:
        windows = [(p, t0, t_end) for p in profiles]
        how = f"spread over {len(profiles)} seeds"
    else:
        edges = np.linspace(t0, t_end, BLOCKS + 1)
        windows = [(profiles[0], lo, hi) for lo, hi in zip(edges[:-1], edges[1:])]
        how = f"spread over {BLOCKS} blocks of the steady window (1 seed)"
    out = []
    for prof, lo, hi in windows:
        w = prof.window(lo, hi)
        w.insert(1, "depth", float(np.mean(surface([lo, hi]))) - w.y)
        out.append(w[w.depth >= 0].sort_values("depth"))
    return tuple(out), how


#: delta_u(t) is measured only once the plate moves at 1 % of its steady speed (before, u/u_w is noise)
DELTA_MIN_SPEED = 1e-2


def snapshot_times(times, n: int = 5) -> np.ndarray:
    """About ``n`` log-spaced times among a drive's atom snapshots ``times`` (t > 0): the transient profiles."""
    t = np.asarray(times, dtype=float)
    t = t[t > 0]
    picks = np.unique(np.searchsorted(t, np.geomspace(t[0], t[-1], n)).clip(0, len(t) - 1))
    return t[picks]


def mass_error(a: DriveAnalysis) -> float:
    """Relative error of the integral of the coarse-grained phi over y against the bed grains'
    volume per unit area (first frame of the first seed; 2D: disk areas per unit length)."""
    drive, res = a.spec.beds[0], a.profiles[0].results
    frame = next(drive.frames([0]))
    r = frame.radius[frame.types == layout.BED]
    volume = np.pi * r**2 if drive.dimension == 2 else 4 / 3 * np.pi * r**3
    widths = frame.box[:, 1] - frame.box[:, 0]
    area = widths[0] if drive.dimension == 2 else widths[0] * widths[2]
    integral = np.trapezoid(res.additive["phi"][0], res.y)
    return float(integral / (volume.sum() / area) - 1)


def nearest_frame(df: pd.DataFrame, t: float) -> pd.DataFrame:
    """The rows of a table of profiles (column t) at its one time nearest ``t``: one profile, never two."""
    times = df.t.unique()
    return df[df.t == times[np.argmin(np.abs(times - t))]]
