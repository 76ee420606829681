"""The cost of an error bar: the DEM's standard error of each scored observable against a drive's size,

    err = C_D  X^r  (seeds x area)^(-1/2)  duration^(-a)  p_w^(-b)

with ``area`` the plate's area (2D: its length) in d^(D-1), ``duration`` the drive's in sqrt(d/g), and X the
drive's expected scale of the observable (``SCALES``: what the calibrated local law gives before the run).
Independent beds average at the central limit's rate (the exponent of seeds x area); a wider plate at least as
fast (its beds' offsets shrink faster: the law is then conservative, bench/RESULTS.md).  One law per scored
observable and drive kind; its coefficients (``noise.csv``) are fitted by bench/dem_cost_noise.py on the
committed studies (C_2 on the 2D disks, C_3 on the 3D spheres with the 2D exponents).  ``drive_errors``
predicts a planned drive's errors (``granstokes study --dry-run``).

An error target (``Target``, a study's ``[target]`` table) turns the law around: the beds a drive needs so that
a stated difference of each observable is decided at a stated confidence, the mean of n beds tested at Student-t's
quantile of n - 1 degrees of freedom (few beds pay twice: a larger error and a larger quantile).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd
from granstokes.continuum.steady import steady_wall_speed
from scipy import special, stats

NOISE_CSV = Path(__file__).with_name("noise.csv")
#: the observable each drive kind scores (compare.scorecard), in the order printed
SCORED = {"stress": ("u_w_inf", "delta_u", "creep_length", "t90"),
          "speed": ("mu_w_inf", "delta_u", "creep_length", "t90")}
#: the expected scale X of each observable: the local law's steady wall speed and friction, the layer
#: thickness delta_s, the time scale t_s; "one" for an observable whose error does not follow a scale
SCALES = {"u_w_inf": "u_w", "mu_w_inf": "mu_w", "delta_u": "one", "creep_length": "one", "t90": "t_s"}
#: the plate's steady responses, whose scale is their expected value
RESPONSES = ("u_w_inf", "mu_w_inf")
UNITS = {"u_w_inf": "sqrt(g d)", "mu_w_inf": "", "delta_u": "d", "creep_length": "d", "t90": "sqrt(d/g)"}
#: the exponent of seeds x area
AVERAGING = 0.5
#: a decision's confidence unless the target states one (two-sided)
CONFIDENCE = 0.95
#: the fewest beds a decision rests on (one degree of freedom), and the most a target may take unless it says
MIN_BEDS, BEDS_MAX = 2, 12
#: a value this fraction beyond a fitted range still counts as inside it (planned and measured scales differ)
RANGE_SLACK = 0.05
#: noise.csv's fitted ranges (NoiseLaw.p_range, x_range)
RANGE_COLUMNS = ("p_min", "p_max", "x_min", "x_max")


@dataclass(frozen=True)
class DriveSize:
    """What a drive's error depends on: its kind, the scene's dimension, beds, plate area (d^(D-1)), duration,
    pressure and the expected scales (``SCALES`` name -> value)."""

    kind: str
    dimension: int
    seeds: int
    area: float
    duration: float
    p_w: float
    scales: dict

    def x(self, observable: str) -> float:
        name = SCALES[observable]
        return 1.0 if name == "one" else float(self.scales[name])


def log_spread_bias(beds) -> np.ndarray:
    """E ln(s / sigma) of the spread s of ``beds`` Gaussian beds (s^2 (n-1) / sigma^2 ~ chi2(n-1)):
    (psi((n-1)/2) + ln(2/(n-1))) / 2, -0.18 at 4 beds, -0.09 at 7.  A law fitted to ln s is low by it."""
    k = np.asarray(beds, float) - 1
    return 0.5 * (special.digamma(k / 2) + np.log(2 / k))


@dataclass(frozen=True)
class NoiseLaw:
    """One observable's law for one drive kind; ``p_range`` and ``x_range`` the pressures and scales of the 2D
    drives its exponents were fitted to (NaN: not recorded, or no scale)."""

    observable: str
    kind: str
    c2: float
    c3: float
    r: float
    a: float
    b: float
    p_range: tuple[float, float] = (np.nan, np.nan)
    x_range: tuple[float, float] = (np.nan, np.nan)

    def error(self, size: DriveSize) -> float:
        c = self.c2 if size.dimension == 2 else self.c3
        return float(c * size.x(self.observable) ** self.r * (size.seeds * size.area) ** -AVERAGING
                     * size.duration ** -self.a * size.p_w ** -self.b)

    def extrapolated(self, size: DriveSize) -> list[str]:
        """What of the drive lies beyond the fitted ranges, where an exponent other than 0 is applied:
        e.g. ["p_w 40 beyond 10-20"]."""
        out = []
        for name, value, (lo, hi), exponent in (("p_w", size.p_w, self.p_range, self.b),
                                                 (SCALES[self.observable], size.x(self.observable), self.x_range,
                                                  self.r)):
            if exponent != 0 and np.isfinite(lo) and not lo * (1 - RANGE_SLACK) <= value <= hi * (1 + RANGE_SLACK):
                out.append(f"{name} {value:.3g} beyond {lo:.3g}-{hi:.3g}")
        return out


def fit(err, x, seeds, area, duration, p_w, r: float | None = None, a: float | None = None,
        b: float | None = None) -> dict:
    """Least squares of ln err on ln X, ln duration and ln p_w (seeds x area at the fixed AVERAGING exponent): c, r,
    a, b; an exponent given is held (one the rows do not vary independently, or that the physics sets)."""
    y = np.log(np.asarray(err, float)) + AVERAGING * np.log(np.asarray(seeds, float) * np.asarray(area, float))
    held = {"r": r, "a": a, "b": b}
    terms = {"r": np.log(np.asarray(x, float)), "a": -np.log(np.asarray(duration, float)),
             "b": -np.log(np.asarray(p_w, float))}
    free = [k for k in terms if held[k] is None]
    for k in terms:
        if held[k] is not None:
            y = y - held[k] * terms[k]
    design = np.column_stack([np.ones_like(y), *(terms[k] for k in free)])
    coef = np.linalg.lstsq(design, y, rcond=None)[0]
    return {"c": float(np.exp(coef[0])), **{k: float(held[k]) for k in terms if held[k] is not None},
            **dict(zip(free, map(float, coef[1:])))}


def laws(path: Path = NOISE_CSV) -> dict[tuple[str, str], NoiseLaw]:
    """The fitted laws by (observable, kind)."""
    table = pd.read_csv(path)
    for column in RANGE_COLUMNS:  # a table fitted without its ranges: none recorded
        if column not in table:
            table[column] = np.nan
    return {(row.observable, row.kind): NoiseLaw(row.observable, row.kind, row.c2, row.c3, row.r, row.a, row.b,
                                                 (row.p_min, row.p_max), (row.x_min, row.x_max))
            for row in table.itertuples()}


def drive_size(plan, drive_plan, p_w: float) -> DriveSize:
    """A planned drive (dem.sizing.Plan and one of its DriveSizings) as a DriveSize, its scales those of the
    plan's material."""
    s = drive_plan.scales
    u_w = (drive_plan.load.u_w if drive_plan.load.kind == "speed"
           else s.U * steady_wall_speed(plan.config.material.friction, s.mu_w))
    return DriveSize(drive_plan.load.kind, plan.dimension, len(plan.config.seeds), plan.area, drive_plan.duration,
                     p_w, {"u_w": u_w, "mu_w": s.mu_w, "delta_s": s.delta_s, "t_s": s.t_s})


def drive_errors(size: DriveSize, table: dict | None = None) -> dict[str, float]:
    """The predicted standard error of each observable the drive scores."""
    table = laws() if table is None else table
    return {obs: table[(obs, size.kind)].error(size) for obs in SCORED[size.kind]}


def error_line(label: str, size: DriveSize, table: dict | None = None) -> str:
    """One drive's predicted errors, as ``granstokes study --dry-run`` prints them (relative to the expected value
    for the plate's response)."""
    table = laws() if table is None else table
    parts = []
    for obs, err in drive_errors(size, table).items():
        unit = f" {UNITS[obs]}" if UNITS[obs] else ""
        x = size.x(obs)
        rel = f" ({err / x:.1%} of {x:.3g})" if obs in RESPONSES else ""
        beyond = table[(obs, size.kind)].extrapolated(size)
        parts.append(f"{obs} +- {err:.3g}{unit}{rel}" + (f" (extrapolated: {', '.join(beyond)})" if beyond else ""))
    area = f"{size.area:g} d" + ("" if size.dimension == 2 else f"^{size.dimension - 1}")
    return (f"  {label}: expected errors at {size.seeds} bed(s) x {area}, duration {size.duration:.4g}: "
            + ", ".join(parts))


def relative(observable: str) -> bool:
    """Whether a target states the observable's difference as a fraction of its expected scale (``SCALES``)."""
    return SCALES[observable] != "one"


@dataclass(frozen=True)
class Target:
    """The smallest difference of each observable a study must decide (``differences``: observable -> difference;
    ``relative`` ones as a fraction of their expected scale, the others in their ``UNITS``) at ``confidence``
    (two-sided), with at most ``beds_max`` beds a drive."""

    differences: tuple  # (observable, difference) pairs
    confidence: float = CONFIDENCE
    beds_max: int = BEDS_MAX

    def beds(self, size: DriveSize, table: dict | None = None, measured: dict | None = None) -> dict[str, int | None]:
        """The beds each targeted observable the drive scores needs (None: more than ``beds_max``), from its
        one-bed error as ``measured`` (observable -> error, a first round's: ``measured_errors``) or else as the
        law predicts."""
        table, measured = laws() if table is None else table, measured or {}
        needs = {}
        for obs, diff in self.differences:
            if obs in SCORED[size.kind]:
                one = measured.get(obs, table[(obs, size.kind)].error(replace(size, seeds=1)))
                needs[obs] = beds_for(one / (size.x(obs) if relative(obs) else 1.0), diff, self.confidence,
                                      self.beds_max)
        return needs


def beds_for(one_bed: float, difference: float, confidence: float = CONFIDENCE, beds_max: int = BEDS_MAX) -> int | None:
    """The fewest beds n (at least MIN_BEDS) whose mean decides ``difference`` at ``confidence`` when one bed's
    error is ``one_bed``: t(n - 1) one_bed n^-1/2 <= difference; None when ``beds_max`` beds do not."""
    for n in range(MIN_BEDS, beds_max + 1):
        if stats.t.isf((1 - confidence) / 2, n - 1) * one_bed * n ** -AVERAGING <= difference:
            return n
    return None


def measured_errors(metrics: dict) -> dict[str, dict[str, float]]:
    """A first round's one-bed errors (a report's metrics.json): per drive label, each scored observable's DEM
    standard error over its beds times sqrt(beds) (the spread of one bed), where finite; what a resume that adds
    beds plans from instead of the law."""
    beds = {label: int(d["seeds"]) for label, d in metrics.get("drives", {}).items()}
    out: dict[str, dict[str, float]] = {}
    for row in metrics.get("scorecard", []):
        err, label = row.get("dem_err"), row.get("drive")
        if row.get("observable") in RESPONSES + ("delta_u", "creep_length", "t90") and label in beds \
                and err is not None and np.isfinite(err):
            out.setdefault(label, {})[row["observable"]] = float(err) * beds[label] ** AVERAGING
    return out


def target_line(label: str, size: DriveSize, target: Target, run_beds: int, table: dict | None = None,
                measured: dict | None = None) -> str:
    """What the target asks of one drive, as ``granstokes study`` prints it before running: the beds each targeted
    observable needs (from a first round's ``measured`` one-bed error where given: marked "measured"), the drive's
    (the most of them) and its run's; an observable ``beds_max`` beds cannot decide is named as such."""
    needs, diffs, measured = target.beds(size, table, measured), dict(target.differences), measured or {}
    parts = [(f"{obs} {100 * diffs[obs]:g} % of {SCALES[obs]}" if relative(obs) else
              f"{obs} {diffs[obs]:g} {UNITS[obs]}")
             + (f": {n}" if n is not None else f": undecided within {target.beds_max}")
             + (" (measured)" if obs in measured else "") for obs, n in needs.items()]
    if not needs:
        return f"  {label}: no targeted observable; {run_beds} bed(s) with its run"
    undecided = [obs for obs, n in needs.items() if n is None]
    own = (f"cannot decide {', '.join(undecided)} within {target.beds_max} beds" if undecided
           else f"needs {max(needs.values())} bed(s)")
    return f"  {label}: {own} ({'; '.join(parts)}); its run takes {run_beds}"
