"""DEM observables from the plate record (plate.csv), defined as on the continuum side.

u_w(t) = plate x-velocity; tau_w(t) = -f_x (x force of the bed on the plate per area, sign flipped so
that it is > 0 when it resists a plate moving in +x); mu_w(t) = tau_w/p, p = f_y (the normal load the
bed carries, ~p_w); every row of plate.csv is an average over its output interval, sampled every half contact time.
DEM units (d, rho_p, g).

Errors.  A window's value is a function of the window means of one or more series (the friction is
the ratio of means <tau_w>/<p>, never the mean of the ratios, which is biased when p fluctuates).  Its
standard error comes from blocks longer than the series' integrated autocorrelation time
(``block_estimate``); over independent beds (``pooled``) it is the spread of the per-bed values when
there are at least MIN_SEEDS_SPREAD of them, else the per-bed block errors combined.  Every error carries its
degrees of freedom (``dof``, for compare.rows' Student-t verdict): blocks - 1 for a block error, n_seeds - 1 for a
spread over seeds, the Welch-Satterthwaite combination (compare.rows.effective_dof) of the per-bed block errors',
blocks - 2 for a trend's slope and points - 2 for a power law's exponent.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from granstokes.dem.layout import PLATE_CSV
from scipy import stats

from granstokes.lib.statistics import autocorrelation_time

from .rows import effective_dof

#: steady-state criterion (stated in every report): the final quarter has no trend (its slope, fitted to the
#: means of blocks longer than the correlation time, within the Student-t quantile of the blocks' degrees of
#: freedom that a normal variable exceeds at TREND_SIGMA: a steady record is flagged 0.27 % of the time), and
#: the record is steady from the earliest start (in steps of STEADY_WINDOW of the record) after which it has no
#: trend; the prepared state (t = 0) is in no window
STEADY_WINDOW, TREND_SIGMA = 0.05, 3.0
#: the steady window starts at t_steady, but no later than this fraction of the record (and there
#: when no steady state was detected): the profiles always average the final 30 % at least
STEADY_WINDOW_LATEST = 0.7
#: the steady value is the mean from this fraction of the record on (its last quarter)
STEADY_LAST = 0.75


def steady_window_start(t_steady: float, t_end: float) -> float:
    """Start of the window whose profiles stand for the steady state."""
    latest = STEADY_WINDOW_LATEST * t_end
    return min(t_steady, latest) if np.isfinite(t_steady) else latest


#: blocks span at least BLOCK_TAUS integrated autocorrelation times: the neighbouring blocks' correlation
#: then biases the error low by ~1/BLOCK_TAUS in variance (AR(1): -5 % in the error, tested); when the
#: series holds fewer than MIN_BLOCKS such blocks, MIN_BLOCKS shorter ones are used and the method says so
BLOCK_TAUS, MIN_BLOCKS = 10.0, 4
#: with this many beds or more, the error of a drive's value is their spread (fewer: pooled blocks)
MIN_SEEDS_SPREAD = 3
#: the slip of the bed grains touching the plate is measured over the second half of each drive
SLIP_FROM = 0.5


@dataclass(frozen=True, eq=False)
class PlateRecord:
    t: np.ndarray
    u_w: np.ndarray
    tau_w: np.ndarray
    p: np.ndarray
    y: np.ndarray      # height of the plate's centre of mass
    u_c: np.ndarray    # mean x velocity of the bed grains touching a plate grain
    n_c: np.ndarray    # mean number of them

    @classmethod
    def read(cls, drive_dir: Path) -> PlateRecord:
        df = pd.read_csv(Path(drive_dir) / PLATE_CSV)
        return cls(df.t.to_numpy(), df.u_x.to_numpy(), -df.f_x.to_numpy(), df.f_y.to_numpy(), df.y.to_numpy(),
                   df.u_c.to_numpy(), df.n_c.to_numpy())

    @property
    def mu_w(self) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.p > 0, self.tau_w / self.p, np.nan)


def block_estimate(series: dict, f=None) -> dict:
    """``f`` (default: the identity of the single series) of the series' means, with its standard error
    from blocks of at least BLOCK_TAUS autocorrelation times (the longest of the series'): the spread of
    f over the blocks' means / sqrt(blocks), with blocks - 1 degrees of freedom.  Series: equal-length arrays
    sampled at equal steps."""
    f = f or (lambda m: next(iter(m.values())))
    arrays = {k: np.asarray(v, dtype=float) for k, v in series.items()}
    n = len(next(iter(arrays.values())))
    tau = max(autocorrelation_time(a) for a in arrays.values())
    length = max(1, int(np.ceil(BLOCK_TAUS * tau)))
    blocks = max(MIN_BLOCKS, n // length) if n >= MIN_BLOCKS else n
    parts = {k: np.array_split(a, blocks) for k, a in arrays.items()}
    values = [f({k: p[b].mean() for k, p in parts.items()}) for b in range(blocks)]
    value = f({k: a.mean() for k, a in arrays.items()})
    stderr = float(np.std(values, ddof=1) / np.sqrt(blocks)) if blocks > 1 else np.nan
    enough = n // length >= MIN_BLOCKS
    method = (f"{blocks} blocks of {n / blocks / tau:.3g} autocorrelation times ({tau:.3g} samples) within the run"
              + ("" if enough else f" (too short for {MIN_BLOCKS} blocks of {BLOCK_TAUS:g}: error underestimated)"))
    return {"value": float(value), "stderr": stderr, "dof": int(blocks) - 1, "tau_samples": tau, "blocks": int(blocks),
            "enough_blocks": bool(enough), "method": method}


def pooled(estimates: list[dict]) -> dict:
    """One drive's value over its beds: the mean of the per-bed values; its error the spread over
    the beds (>= MIN_SEEDS_SPREAD; n - 1 degrees of freedom) or the per-bed block errors combined (their
    Welch-Satterthwaite degrees of freedom: blocks - 1 for one bed)."""
    values = np.array([e["value"] for e in estimates])
    n = len(values)
    if n >= MIN_SEEDS_SPREAD:
        stderr, method = float(np.std(values, ddof=1) / np.sqrt(n)), f"spread over {n} seeds (std/sqrt(n))"
        dof = n - 1
    else:
        errors = [e["stderr"] for e in estimates]
        stderr = float(np.sqrt(np.sum(np.square(errors))) / n)
        dof = effective_dof(errors, [e["dof"] for e in estimates])
        method = estimates[0]["method"] + ("" if n == 1 else f", combined over {n} seeds")
    return {"value": float(values.mean()), "stderr": stderr, "dof": dof, "method": method,
            "per_seed": values.tolist()}


def friction(tau: np.ndarray, p: np.ndarray) -> float:
    """The friction of a window: the ratio of means <tau>/<p> (the mean of tau/p is biased)."""
    return float(np.mean(tau) / np.mean(p))


def tail(record: PlateRecord, t0: float) -> dict:
    """The record's series from t0 on (finite samples)."""
    sel = (record.t >= t0) & np.isfinite(record.tau_w) & np.isfinite(record.p)
    return {k: getattr(record, k)[sel] for k in ("t", "u_w", "tau_w", "p", "u_c", "n_c")}


def window_values(record: PlateRecord, t0: float) -> dict:
    """u_w and mu_w = <tau_w>/<p> over t >= t0, with block errors."""
    s = tail(record, t0)
    return {"u_w": block_estimate({"u_w": s["u_w"]}),
            "mu_w": block_estimate({"tau": s["tau_w"], "p": s["p"]}, lambda m: friction(m["tau"], m["p"]))}


#: the plate grips when at most this fraction of its speed is lost to slip against the grains touching it
SLIP_MAX = 0.05


def slip(record: PlateRecord) -> dict:
    """1 - <u_x of the bed grains touching a plate grain>/<plate u_x> over the second half of the
    drive (grain-weighted over the samples), with its block error."""
    s = tail(record, record.t[0] + SLIP_FROM * (record.t[-1] - record.t[0]))
    return block_estimate({"sum": s["u_c"] * s["n_c"], "n": s["n_c"], "u": s["u_w"]},
                          lambda m: 1 - m["sum"] / m["n"] / m["u"])


def trend(t: np.ndarray, y: np.ndarray) -> dict:
    """Slope of y(t) and its standard error from a straight line through the means of the blocks of
    ``block_estimate`` (longer than the correlation time: independent), with blocks - 2 degrees of freedom
    (``dof``), their ratio ``z`` and the ``limit`` |z| may reach for a record without trend (a t quantile at dof)."""
    est = block_estimate({"y": y})
    blocks = est["blocks"]
    if blocks < 3:
        return {"slope": np.nan, "stderr": np.nan, "dof": np.nan, "z": np.nan, "blocks": blocks}
    tb = np.array([b.mean() for b in np.array_split(t, blocks)])
    yb = np.array([b.mean() for b in np.array_split(y, blocks)])
    fit = stats.linregress(tb, yb)
    tail = 2 * stats.norm.sf(TREND_SIGMA)  # two-sided: the same false-alarm rate at any number of blocks
    exact = float(np.copysign(np.inf, fit.slope)) if fit.slope else 0.0  # no scatter about the line
    return {"slope": float(fit.slope), "stderr": float(fit.stderr), "dof": blocks - 2, "blocks": blocks,
            "z": float(fit.slope / fit.stderr) if fit.stderr > 0 else exact,
            "limit": float(stats.t.isf(tail / 2, blocks - 2))}


def no_trend(tr: dict) -> bool:
    """Whether a ``trend`` is within its limit (False when it could not be formed)."""
    return bool(abs(tr["z"]) <= tr.get("limit", np.nan))


def steady_state(t: np.ndarray, y: np.ndarray) -> dict:
    """Final value (mean over the last quarter), its standard error and dof (``block_estimate``), the final quarter's
    ``trend``, and t_steady: the earliest start, in steps of STEADY_WINDOW of the record, from which the rest
    of the record has no trend (``no_trend``) and the mean of its first quarter agrees with the final value
    within TREND_SIGMA combined errors; nan when the final quarter itself drifts.  The record's
    first sample, the prepared state at t = 0, is left out."""
    ok = np.isfinite(y) & (t > t[0])
    t, y = t[ok], y[ok]
    last_t = t >= t[0] + STEADY_LAST * (t[-1] - t[0])
    last = y[last_t]
    est = block_estimate({"y": last})
    value, stderr = float(last.mean()), est["stderr"]
    tr = trend(t[last_t], last)
    def settled(s: float) -> bool:
        """From s on: no trend, and the first quarter of the rest agrees with the final value."""
        rest = t >= s
        head = rest & (t < s + (1 - STEADY_LAST) * (t[-1] - s))
        err = stderr * np.sqrt(len(last) / max(1, head.sum()) + 1)  # a head mean against the final value
        return abs(y[head].mean() - value) <= TREND_SIGMA * err and no_trend(trend(t[rest], y[rest]))

    t_steady = np.nan
    if no_trend(tr):  # a drifting (or too short to test) final quarter is not steady
        starts = t[0] + np.arange(0.0, STEADY_LAST, STEADY_WINDOW) * (t[-1] - t[0])
        t_steady = next((float(s) for s in starts if settled(s)), float(t[last_t][0]))
    return {"value": value, "stderr": stderr, "dof": est["dof"], "t_steady": t_steady, "drift": tr["slope"],
            "drift_err": tr["stderr"], "drift_z": tr["z"]}


def power_law(t: np.ndarray, y: np.ndarray, t_min: float, t_max: float) -> dict:
    """Exponent alpha of y ~ t^alpha by least squares on log-log over [t_min, t_max], with its
    standard error, its n - 2 degrees of freedom and 95 % interval (scipy.stats.linregress)."""
    sel = (t >= t_min) & (t <= t_max) & (y > 0) & np.isfinite(y)
    if sel.sum() < 4:
        return {"alpha": np.nan, "stderr": np.nan, "dof": np.nan, "ci95": (np.nan, np.nan), "n": int(sel.sum())}
    fit = stats.linregress(np.log(t[sel]), np.log(y[sel]))
    dof = int(sel.sum()) - 2
    q = stats.t.ppf(0.975, dof) * fit.stderr
    return {"alpha": fit.slope, "stderr": fit.stderr, "dof": dof, "ci95": (fit.slope - q, fit.slope + q),
            "n": int(sel.sum())}
