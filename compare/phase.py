"""Phase-resolved estimators for a plate oscillating over a granular bed (Stokes' second problem), applied
alike to DEM records and continuum solutions.

The wall value is imposed as A sin(omega t) from t = 0 (A the amplitude of the stress ratio mu_w or of the
plate speed u_w); the response is the plate speed u_w under an imposed stress, the wall friction tau_w (or
mu_w) under an imposed speed, with the sign of ``plate``: tau_w > 0 when it resists a plate moving in +x.
Times, displacements and stresses are in the units of the record (DEM: d, rho_p, g); phases in radians.

Cycles.  Cycle k is t in [k T, (k + 1) T), T = 2 pi/omega; it is whole when the samples reach within one
(median) sampling step of both its ends.  The first ``skip`` cycles (the start-up) are discarded.

Errors.  The whole cycles are independent blocks: a quantity is estimated on all kept cycles, and its
standard error is the spread of its per-cycle values / sqrt(n_cycles) (a Student-t with n_cycles - 1 degrees
of freedom; at least MIN_CYCLES cycles, else the error is nan).

Harmonic.  y ~ mean + amplitude sin(omega t + phase), phase in (-pi, pi], by least squares on
[1, sin omega t, cos omega t].  A record whose samples are averages over the ``interval`` ending at each
sample sees a harmonic attenuated by sinc(omega interval/2) and delayed by interval/2; the fit undoes both.

Lag.  The response's lag behind the imposed sine is imposed phase - response phase, in (-pi, pi]: > 0 when
the response peaks after the imposed value (a Newtonian Stokes layer: the speed lags an imposed stress by
pi/4, the friction leads an imposed speed by pi/4, lag -pi/4).  ``lag`` measures it against another record
(the grains' speed instead of the imposed one), ``peak_lag`` from the phase-averaged response's peak.

Periodic state.  A record is periodic when the fundamental of its last kept cycle is that of its first within
PERIODIC_TOLERANCE (``periodicity``): a test on the change over the kept cycles, which a bed that jams fails
whatever the number of cycles (a trend test over three cycle means has one degree of freedom and passes anything).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import integrate, stats

#: fewest whole cycles that give an error (their spread)
MIN_CYCLES = 2
#: phase bins per cycle of the phase averages
PHASE_BINS = 24
#: relative slack for times that fall on a cycle's boundary up to rounding
ROUNDING = 1e-9
#: a record is periodic when the fundamental of its last kept cycle is within this fraction of the larger amplitude
#: of its first's (``change``): its amplitude neither halves nor doubles, its phase turns by less than 2 arcsin(1/4)
#: = 29 degrees.  A bed's mean over its cycles describes none of them beyond that.  Against the DEM's noise: the
#: committed oscillating study's flowing beds change by up to 0.44 over their three kept cycles (imposed stress,
#: omega t_s >= 1; 0.28 under an imposed speed); the bed that jams, its amplitude falling from 1.59 to 0.12, by 0.98
PERIODIC_TOLERANCE = 0.5


def wrap(phase):
    """Phase(s) brought into (-pi, pi]."""
    return np.pi - np.mod(np.pi - np.asarray(phase, dtype=float), 2 * np.pi)


def cycles(t, omega: float, skip: int = 1) -> dict[int, np.ndarray]:
    """The sample indices of each whole cycle k >= ``skip``, by cycle number (``t`` may repeat, as in a
    long table of profiles)."""
    t = np.asarray(t, dtype=float)
    period = 2 * np.pi / omega
    times = np.unique(t)
    slack = (np.median(np.diff(times)) if len(times) > 1 else 0.0) * (1 + ROUNDING)
    first = max(skip, int(np.ceil((times[0] - slack) / period - ROUNDING)))
    last = int(np.floor((times[-1] + slack) / period + ROUNDING)) - 1
    k = np.floor(t / period + ROUNDING).astype(int)
    return {c: idx for c in range(first, last + 1) if len(idx := np.flatnonzero(k == c))}


def _finite(*arrays) -> list[np.ndarray]:
    """The arrays as floats, at the samples where all are finite."""
    arrays = [np.asarray(a, dtype=float) for a in arrays]
    ok = np.logical_and.reduce([np.isfinite(a) for a in arrays])
    return [a[ok] for a in arrays]


def _over_blocks(values) -> dict:
    """The mean of per-block values (value), its standard error (nan below MIN_CYCLES blocks) and the values."""
    values = np.asarray(values, dtype=float)
    n = len(values)
    return {"value": float(values.mean()) if n else np.nan,
            "stderr": float(values.std(ddof=1) / np.sqrt(n)) if n >= MIN_CYCLES else np.nan, "values": values}


def _fit(t, y, omega: float) -> np.ndarray:
    """Least-squares (mean, amplitude, phase) of y ~ mean + amplitude sin(omega t + phase)."""
    m, s, c = np.linalg.lstsq(np.column_stack([np.ones_like(t), np.sin(omega * t), np.cos(omega * t)]), y,
                              rcond=None)[0]
    return np.array([m, np.hypot(s, c), np.arctan2(c, s)])


@dataclass(frozen=True)
class Harmonic:
    """The fundamental of a periodic record: y ~ mean + amplitude sin(omega t + phase), with standard errors."""
    amplitude: float
    phase: float
    mean: float
    amplitude_err: float
    phase_err: float
    mean_err: float
    n_cycles: int
    note: str = ""

    def interval(self, name: str, level: float = 0.95) -> tuple[float, float]:
        """The ``level`` confidence interval of ``name`` (amplitude, phase or mean): value -+ a Student-t
        quantile with n_cycles - 1 degrees of freedom times its error."""
        value, err = getattr(self, name), getattr(self, f"{name}_err")
        half = err * stats.t.ppf((1 + level) / 2, self.n_cycles - 1)
        return value - half, value + half


def _cycle_fits(t, y, omega: float, blocks, interval: float) -> np.ndarray:
    """(mean, amplitude, phase) of each block's fit, the ``interval`` average undone (amplitude / sinc(omega
    interval/2), phase + omega interval/2); phases not wrapped."""
    scale, shift = np.array([1.0, 1 / np.sinc(omega * interval / (2 * np.pi)), 1.0]), [0, 0, omega * interval / 2]
    return np.array([_fit(t[b], y[b], omega) for b in blocks]).reshape(-1, 3) * scale + shift


def harmonic(t, y, omega: float, skip: int = 1, interval: float = 0.0) -> Harmonic:
    """The fundamental of y(t) on the whole cycles after ``skip``, errors from the per-cycle fits; ``interval``:
    the samples are averages over the interval ending at each (the attenuation and delay are undone)."""
    if omega * interval >= 2 * np.pi:
        raise ValueError(f"an average over {interval:g} >= one period erases the harmonic")
    t, y = _finite(t, y)
    blocks = list(cycles(t, omega, skip).values())
    n = len(blocks)
    if n == 0:
        return Harmonic(*[np.nan] * 6, n_cycles=0, note=f"no whole cycle after the first {skip}")
    mean, amplitude, phase = _cycle_fits(t, y, omega, [np.concatenate(blocks)], interval)[0]
    amplitude, phase, mean = float(amplitude), float(wrap(phase)), float(mean)
    if n < MIN_CYCLES:
        return Harmonic(amplitude, phase, mean, np.nan, np.nan, np.nan, n,
                        f"{n} whole cycle after the first {skip}: an error needs {MIN_CYCLES}")
    per = _cycle_fits(t, y, omega, blocks, interval)
    per[:, 2] = wrap(per[:, 2] - phase)  # about the estimate: a phase near +-pi does not split
    m_err, a_err, p_err = (per.std(axis=0, ddof=1) / np.sqrt(n)).tolist()
    return Harmonic(amplitude, phase, mean, a_err, p_err, m_err, n)


def cycle_harmonics(t, y, omega: float, skip: int = 1, interval: float = 0.0) -> pd.DataFrame:
    """The fundamental of each whole cycle after ``skip`` (``harmonic``'s per-cycle fits): cycle, amplitude, phase
    in (-pi, pi] and mean."""
    t, y = _finite(t, y)
    blocks = cycles(t, omega, skip)
    per = _cycle_fits(t, y, omega, list(blocks.values()), interval)
    return pd.DataFrame({"cycle": list(blocks), "amplitude": per[:, 1], "phase": wrap(per[:, 2]), "mean": per[:, 0]})


def phase_lag(response: Harmonic, imposed_phase: float = 0.0) -> float:
    """The response's lag behind the imposed sine in (-pi, pi] (> 0: it peaks later); its error is the
    response's phase_err."""
    return float(wrap(imposed_phase - response.phase))


def lag(t, response, omega: float, skip: int = 1, interval: float = 0.0, reference=None) -> tuple[float, float, int]:
    """The lag of the response's fundamental behind the ``reference``'s (a second record on the same samples; None:
    the imposed sine, phase 0), in (-pi, pi], on the whole cycles after ``skip``: (value, standard error, whole
    cycles).  The error is the spread of the per-cycle lags about the value over sqrt(n) (against the imposed sine:
    the response's phase_err)."""
    if reference is None:
        h = harmonic(t, response, omega, skip, interval)
        return phase_lag(h), h.phase_err, h.n_cycles
    t, y, r = _finite(t, response, reference)
    hy, hr = harmonic(t, y, omega, skip, interval), harmonic(t, r, omega, skip, interval)
    value = phase_lag(hy, hr.phase)
    if hy.n_cycles < MIN_CYCLES:
        return value, np.nan, hy.n_cycles
    per = wrap(cycle_harmonics(t, r, omega, skip, interval).phase - cycle_harmonics(t, y, omega, skip, interval).phase
               - value)
    return value, float(np.std(per, ddof=1) / np.sqrt(len(per))), hy.n_cycles


def peak_lag(t, y, omega: float, skip: int = 1, interval: float = 0.0, bins: int = PHASE_BINS) -> float:
    """The lag of the response's peak behind the imposed sine's (omega t = pi/2), in (-pi, pi]: the vertex of the
    parabola through the phase average's (``phase_average``, ``bins``) largest bin and the two beside it, each at
    the mean phase of its samples (not the bin's centre: samples on a grid aligned with the bins sit off it), less
    the delay omega interval/2 of samples averaged over the ``interval`` ending at each.  Not the fundamental's: a
    response that rises fast after a reversal and then saturates peaks elsewhere than its first harmonic."""
    t = np.asarray(t, dtype=float)
    m = phase_average(t, y, omega, bins, skip)["mean"].to_numpy()
    at = phase_average(t, np.mod(omega * t, 2 * np.pi), omega, bins, skip)["mean"].to_numpy()
    j = int(np.nanargmax(m))
    near = [(j - 1) % bins, j, (j + 1) % bins]
    dx, dy = wrap(at[near] - at[j]), m[near]
    vertex = 0.0
    if np.all(np.isfinite(dx) & np.isfinite(dy)):
        a, b, _ = np.polyfit(dx, dy, 2)
        vertex = float(np.clip(-b / (2 * a), dx[0], dx[2])) if a < 0 else 0.0
    return float(wrap(at[j] + vertex - omega * interval / 2 - np.pi / 2))


def amplitude_profile(df: pd.DataFrame, omega: float, value: str, skip: int = 1) -> pd.Series:
    """The fundamental's amplitude of ``value`` at each depth of a long table (columns t, depth, ``value``), fitted
    on the whole cycles after ``skip``, by increasing depth."""
    kept = np.concatenate([np.zeros(0, int), *cycles(df.t, omega, skip).values()])
    rows = df.iloc[kept]
    return pd.Series({d: _fit(g.t.to_numpy(float), g[value].to_numpy(float), omega)[1]
                      for d, g in rows.groupby("depth")}, dtype=float).sort_index()


def _binned(t, y, omega: float, bins: int, skip: int, by=None) -> pd.DataFrame:
    """Per phase bin (and ``by`` group): the mean over the whole cycles of the per-cycle bin means, their
    sd / sqrt(n_cycles) and n_cycles (the cycles with a sample in the bin)."""
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    blocks = cycles(t, omega, skip)
    rows = np.concatenate([np.zeros(0, int), *blocks.values()])
    keys = {"bin": np.mod(np.floor(omega * t[rows] / (2 * np.pi) * bins + ROUNDING).astype(int), bins)}
    if by is not None:
        keys["by"] = np.asarray(by)[rows]
    frame = pd.DataFrame({**keys, "cycle": np.repeat(list(blocks), [len(b) for b in blocks.values()]),
                          "y": y[rows]})
    per = frame.groupby([*keys, "cycle"]).y.mean().groupby(list(keys))
    count = per.count()
    return pd.DataFrame({"mean": per.mean(), "err": per.std(ddof=1) / np.sqrt(count), "n_cycles": count})


def _centres(bins: int) -> np.ndarray:
    """The phase bins' centres."""
    return (np.arange(bins) + 0.5) * 2 * np.pi / bins


def phase_average(t, y, omega: float, bins: int = PHASE_BINS, skip: int = 1) -> pd.DataFrame:
    """The cycle-averaged signal at fixed phase: per bin of omega t mod 2 pi, its centre (phase), the mean over
    the whole cycles of the per-cycle bin means (mean), their sd / sqrt(n_cycles) (err) and n_cycles."""
    out = _binned(t, y, omega, bins, skip).reindex(range(bins))
    out.insert(0, "phase", _centres(bins))
    out["n_cycles"] = out.n_cycles.fillna(0).astype(int)
    return out.reset_index(drop=True)


def phase_profile(df: pd.DataFrame, omega: float, value: str, bins: int = PHASE_BINS,
                  skip: int = 1) -> dict[str, pd.DataFrame]:
    """``phase_average`` of ``value`` at each depth of a long table (columns t, depth, ``value``): "mean", "err"
    and "n_cycles", each a (phase bin centre x depth) table."""
    grid = _binned(df.t, df[value], omega, bins, skip, by=df.depth)
    out = {}
    for name in ("mean", "err", "n_cycles"):
        table = grid[name].unstack("by").reindex(range(bins))
        table.index, table.columns.name = pd.Index(_centres(bins), name="phase"), "depth"
        out[name] = table
    out["n_cycles"] = out["n_cycles"].fillna(0).astype(int)
    return out


def dissipation(t, u_w, tau_w, omega: float, skip: int = 1) -> dict:
    """Energy the bed dissipates per cycle and plate area, W = the integral of tau_w u_w dt over a cycle (the
    area of the loop in the (x_w, tau_w) plane; trapezoid over the cycle's samples, its last joined to its first
    one period later): mean over the whole cycles after ``skip`` (value), its standard error and the per-cycle
    values."""
    t, u_w, tau_w = _finite(t, u_w, tau_w)
    power, period = tau_w * u_w, 2 * np.pi / omega
    return _over_blocks([integrate.trapezoid(np.r_[power[i], power[i[0]]], np.r_[t[i], t[i[0]] + period])
                         for i in cycles(t, omega, skip).values()])


def yielded_depth(depth, mu, mu_s: float) -> np.ndarray:
    """The deepest depth where |mu| >= mu_s along each profile (the last axis of ``mu``, at increasing
    ``depth``), the crossing interpolated linearly; 0 where no depth is yielded, depth[-1] where the last is."""
    depth = np.asarray(depth, dtype=float)
    excess = np.abs(np.asarray(mu, dtype=float)) - mu_s
    yielded = excess >= 0  # nan: not yielded
    n = depth.size
    last = n - 1 - np.argmax(yielded[..., ::-1], axis=-1)
    below = np.minimum(last + 1, n - 1)
    e0 = np.take_along_axis(excess, last[..., None], -1)[..., 0]
    e1 = np.take_along_axis(excess, below[..., None], -1)[..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        crossing = depth[last] + e0 / (e0 - e1) * (depth[below] - depth[last])
    return np.where(~yielded.any(axis=-1), 0.0, np.where(last == n - 1, depth[-1], crossing))


def remobilization_strain(t, x_w, u_w, response, omega: float, depth: float, fraction: float = 0.9,
                          skip: int = 1, bins: int = PHASE_BINS) -> dict:
    """Strain to remobilise the bed after a reversal of the plate.

    The reversals are at the phases where the phase-averaged u_w (``phase_average``, ``bins``) first reaches
    zero after its maximum and after its minimum (linear interpolation between bin centres), in each whole cycle
    after ``skip``.  In each half-cycle between consecutive reversals, with s = the sign of the new motion, the
    bed is remobilised when s response first reaches ``fraction`` of its maximum over the half-cycle (linear
    interpolation between samples); the strain is |x_w(then) - x_w(reversal)| / ``depth`` (displacement over
    depth, as du/dy).  Mean over the half-cycles (value), its standard error and the per-half-cycle values."""
    t, x_w, u_w, response = _finite(t, x_w, u_w, response)
    avg = phase_average(t, u_w, omega, bins, skip)
    phase, u = avg.phase.to_numpy(), avg["mean"].to_numpy()

    def reversal(start: int) -> float:
        """Phase of the first zero of the averaged u_w after bin ``start``."""
        j = next(j for j in range(start + 1, start + bins) if np.sign(u[j % bins]) != np.sign(u[start]))
        p0, p1, u0, u1 = phase[(j - 1) % bins], phase[j % bins], u[(j - 1) % bins], u[j % bins]
        return np.mod(p0 + u0 / (u0 - u1) * np.mod(p1 - p0, 2 * np.pi), 2 * np.pi)

    down, up = reversal(int(np.nanargmax(u))), reversal(int(np.nanargmin(u)))
    period = 2 * np.pi / omega
    ks = np.array(list(cycles(t, omega, skip)))
    starts = np.concatenate([(ks + down / (2 * np.pi)) * period, (ks + up / (2 * np.pi)) * period])
    signs = np.repeat([-1.0, 1.0], len(ks))
    order = np.argsort(starts)
    starts, signs = starts[order], signs[order]
    strains = []
    for t0, t1, sign in zip(starts[:-1], starts[1:], signs):
        inside = (t > t0) & (t < t1)
        ts = np.r_[t0, t[inside]]
        r = sign * np.r_[np.interp(t0, t, response), response[inside]]
        i = int(np.argmax(r >= fraction * r.max()))
        t_mob = ts[0] if i == 0 else np.interp(fraction * r.max(), r[i - 1:i + 1], ts[i - 1:i + 1])
        strains.append(abs(np.interp(t_mob, t, x_w) - np.interp(t0, t, x_w)) / depth)
    return _over_blocks(strains)


def change(first: complex, last: complex) -> float:
    """How far a fundamental moved, as complex amplitudes a e^(i phase): |last - first| / the larger of |first|,
    |last|; 0 for the same, 2 for opposite phases (0 when both are zero)."""
    larger = max(abs(first), abs(last))
    return float(abs(last - first) / larger) if larger > 0 else 0.0


def periodicity(t, y, omega: float, skip: int = 1, interval: float = 0.0) -> dict:
    """The periodic-state check of a record: its per-cycle fundamentals (``cycle_harmonics``: cycle, amplitude,
    phase), the ``change`` from the first kept cycle's to the last's and ``periodic``: change <=
    PERIODIC_TOLERANCE (None, untested, with fewer than 2 whole cycles after ``skip``)."""
    per = cycle_harmonics(t, y, omega, skip, interval)
    out = {"cycles": per, "change": np.nan, "periodic": None}
    if len(per) >= 2:
        z = per.amplitude.to_numpy() * np.exp(1j * per.phase.to_numpy())
        out["change"] = change(z[0], z[-1])
        out["periodic"] = bool(out["change"] <= PERIODIC_TOLERANCE)
    return out
