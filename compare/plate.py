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

#: steady-state criterion (stated in every report): the running mean over 5 % of the record stays
#: within max(3 standard errors of the final-quarter mean, 5 % of the total change) of that mean
STEADY_WINDOW, STEADY_CHANGE = 0.05, 0.05


@dataclass(frozen=True, eq=False)
class PlateRecord:
    kind: str          # "stress" or "speed"
    t: np.ndarray
    u_w: np.ndarray
    tau_w: np.ndarray
    p: np.ndarray
    y: np.ndarray      # height of the plate grains' centres

    @classmethod
    def read(cls, drive_dir: Path, kind: str) -> "PlateRecord":
        df = pd.read_csv(Path(drive_dir) / "plate.csv")
        return cls(kind, df.t.to_numpy(), df.u_x.to_numpy(), -df.f_x.to_numpy(), df.f_y.to_numpy(), df.y.to_numpy())

    def surface(self, t, radius: float):
        """Height of the plate's contact plane (grain centres minus their radius) at times t."""
        return np.interp(t, self.t, self.y) - radius

    @property
    def mu_w(self) -> np.ndarray:
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.p > 0, self.tau_w / self.p, np.nan)

    @property
    def response(self) -> np.ndarray:
        """What the drive leaves free: u_w under an imposed stress, mu_w under an imposed speed."""
        return self.u_w if self.kind == "stress" else self.mu_w


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
