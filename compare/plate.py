"""DEM observables from the plate record (plate.csv), defined as on the continuum side.

u_w(t) = plate x-velocity; tau_w(t) = -f_x (x force of the bed on the plate per area, sign flipped so
that it is > 0 when it resists a plate moving in +x); mu_w(t) = tau_w/p, p = f_y (the normal load the
bed carries, ~p_w).  DEM units (d, rho_p, g).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from dem.layout import PLATE_CSV

#: steady-state criterion (stated in every report): the running mean over 5 % of the record stays
#: within max(3 standard errors of the final-quarter mean, 5 % of the total change) of that mean
STEADY_WINDOW, STEADY_CHANGE = 0.05, 0.05
#: the steady window starts at t_steady, but no later than this fraction of the record (and there
#: when no steady state was detected): the profiles always average the final 30 % at least
STEADY_WINDOW_LATEST = 0.7


def steady_window_start(t_steady: float, t_end: float) -> float:
    """Start of the window whose profiles stand for the steady state."""
    latest = STEADY_WINDOW_LATEST * t_end
    return min(t_steady, latest) if np.isfinite(t_steady) else latest


@dataclass(frozen=True, eq=False)
class PlateRecord:
    t: np.ndarray
    u_w: np.ndarray
    tau_w: np.ndarray
    p: np.ndarray
    y: np.ndarray      # height of the plate's centre of mass

    @classmethod
    def read(cls, drive_dir: Path) -> "PlateRecord":
        df = pd.read_csv(Path(drive_dir) / PLATE_CSV)
        return cls(df.t.to_numpy(), df.u_x.to_numpy(), -df.f_x.to_numpy(), df.f_y.to_numpy(), df.y.to_numpy())

    @property
    def mu_w(self) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.p > 0, self.tau_w / self.p, np.nan)


def steady_state(t: np.ndarray, y: np.ndarray) -> dict:
    """Final value (mean over the last quarter), its standard error (block means, 5 blocks) and the
    time from which the running mean stays in the band (STEADY_WINDOW, STEADY_CHANGE); t_steady is
    nan when the record has not settled: the last quarter's linear trend still moves it by more
    than the band (``drift``: that slope)."""
    ok = np.isfinite(y)
    t, y = t[ok], y[ok]
    last = y[t >= t[0] + 0.75 * (t[-1] - t[0])]
    blocks = np.array_split(last, 5)
    value = float(last.mean())
    stderr = float(np.std([b.mean() for b in blocks], ddof=1) / np.sqrt(len(blocks)))
    n = max(1, int(STEADY_WINDOW * len(y)))
    running = pd.Series(y).rolling(n, center=True, min_periods=1).mean().to_numpy()
    band = max(3 * stderr, STEADY_CHANGE * abs(value - y[0]))
    outside = np.nonzero(np.abs(running - value) > band)[0]
    t_steady = float(t[outside[-1] + 1]) if len(outside) and outside[-1] + 1 < len(t) else float(t[0])
    tail = t >= t[0] + 0.75 * (t[-1] - t[0])
    slope = stats.linregress(t[tail], y[tail]).slope
    drift = abs(slope) * (t[-1] - t[tail][0]) > band  # still moving by more than the band: not steady
    return {"value": value, "stderr": stderr, "t_steady": np.nan if drift else t_steady, "band": band,
            "drift": float(slope)}


def power_law(t: np.ndarray, y: np.ndarray, t_min: float, t_max: float) -> dict:
    """Exponent alpha of y ~ t^alpha by least squares on log-log over [t_min, t_max], with its
    standard error and 95 % interval (scipy.stats.linregress)."""
    sel = (t >= t_min) & (t <= t_max) & (y > 0) & np.isfinite(y)
    if sel.sum() < 4:
        return {"alpha": np.nan, "stderr": np.nan, "ci95": (np.nan, np.nan), "n": int(sel.sum())}
    fit = stats.linregress(np.log(t[sel]), np.log(y[sel]))
    q = stats.t.ppf(0.975, sel.sum() - 2) * fit.stderr
    return {"alpha": fit.slope, "stderr": fit.stderr, "ci95": (fit.slope - q, fit.slope + q), "n": int(sel.sum())}
