"""The paper's laws confronted with the DEM: one row per law x model, the same estimators on the DEM's seed-mean
series and on every model's output over the same windows and drives (DEM units; tilde variables as in
continuum.scales).

Per drive (a ``Track``: times, the layer's depths over time, u_w(t), the contact layer's u_c(t), mu_w(t), and the
steady u_w, layer depths and creep length), from the DEM's seeds or from a model's prediction:

* ``delta_growth_exponent``, ``delta_growth_prefactor``: delta ~ t^n and delta/sqrt(nu_g t) over the growth window
  [the window's start, min(GROWTH_END t_s, half the record)]; the paper: 1/2, the self-similar solution of the stress
  form, eq. (3.3) (delta/delta_s ~ 4.66 Dmu sqrt(t~)), and of the speed form, eq. (3.20) (3.66 Dmu sqrt(t~));
* ``u_w_sqrt_t``: the exponent of u_w(t) over the same window (imposed stress; the paper: 1/2);
* ``mu_w_plateau``: (mu_w - mu_s)/Dmu over the plateau window, the first PLATEAU_SPAN of the record after the
  window's start (imposed speed; the paper: close to 1, mu_w near mu_d);
* ``mu_w_decay_exponent``: the exponent of mu_w - mu_s from the plateau's end to where it is DECAY_END times its
  steady value in the DEM (imposed speed; the paper: -1/2, eq. (3.16));
and across drives:
* ``delta_s_scaling``: the steady layer depth against the calibrated delta_s = beta_w p_w/(phi rho_p g) (slope,
  offset);
* ``t_s_collapse``: the slope of log t90 against log t_s over the imposed stresses (the paper: 1);
* ``t_mud_scaling``: the slope of log t~_mud against log u~_w over the imposed speeds (the paper: 2, eq. (3.17)),
  t_mud the first time after the plateau window's start that (mu_w - mu_s)/Dmu falls below MUD_LEVEL;
* ``steady_speed_law``: u~_w^inf over the exact steady integral f(beta_w) (eq. (3.11) with the exact profile)
  and over its asymptote, eq. (3.12), averaged over the imposed stresses (the paper: 1);
* ``creep_length_scaling``: the slope of log creep length against log p_w (local mu(I): no creep at all).
The growth laws are scored for the imposed stresses and the imposed speeds apart (the row's ``kind``): the two forms'
layers grow with different prefactors and saturate differently; a law over every drive has kind "all".

Estimator families (compare.families): every law is measured over its family of choices (the layer's depth at each
threshold and its moment, the window's start at 1, 3 and 10 shear-wave transits, the plate's or the contact layer's
speed), the same for the DEM and each model; the row carries every choice (``choices``), the family's spread
(``systematic``), its headline numbers from the primary choice, and the family's verdict (disagrees only when every
measured choice disagrees; "depends on the estimator" when they split).

Laws in their regime: a power law (the layer's and u_w's growth, the friction's decay) is fitted only on a window
that spans MIN_DECADES of time after its start and lies inside the model's own power-law regime (the model's local
exponents over the window, ``local_exponents``, spread by at most REGIME_TOLERANCE); the plateau only where both the
DEM's and the model's friction hold one over the window (PLATEAU_TOLERANCE).  A drive whose window fails is left out
of that choice for that model, for the DEM and the model alike; a choice no drive passes is ``not measurable`` with
each drive's numbers (window, span, the model's local exponents).

Errors: dem_err is the standard deviation of the DEM's estimate over SEED_RESAMPLES bootstrap resamples of each
drive's seeds (independent samples), times sqrt(n/(n - 1)) where the smallest drive has n < BOOTSTRAP_FEW_SEEDS
seeds (the bootstrap's spread of a mean over n samples is the sample's standard error times sqrt((n - 1)/n)), with
n - 1 degrees of freedom.  A law fitted as a line across drives (``Across``) weights each drive by its own error:
the standard deviation of that drive's y (ln y for a power law) over the same resamples of its seeds, corrected
alike for its number of seeds; the DEM's slope or offset and its error are the weighted least-squares line's
(``Line``), the error scaled by sqrt(chi2_dof) where the drives scatter about the line beyond their errors
(chi2_dof = chi2/(n - 2) > 1), with n - 2 degrees of freedom over the n drives fitted; where chi2.sf(chi2, n - 2) <
LACK_OF_FIT_P the drives are no line (a step, a bend) and the choice is "not measurable: not a line" with chi2/dof
and p (compare.rows.not_a_line); every choice carries its chi2_dof (NaN for a law that is a mean over drives), and
each model's line is fitted with the DEM's weights.  The model's standard deviation s_cal propagates the
calibration's replicates linearly (compare.band.Sensitivity: the same estimate on the predictions re-solved with
each parameter shifted), band = predicted -+ 1.96 s_cal, sigma = (dem - predicted)/sqrt(dem_err^2 + s_cal^2) and
each choice's verdict is at Student-t's quantile of its Welch-Satterthwaite dof (compare.rows).

Scenes: a drive whose plate slips (compare.scorecard.slipping) or whose bed leaves less than the depth study's
clearance below delta_s (compare.scorecard.short_bed) is left out of every law, as its scorecard rows are not scored,
and so is a drive whose steady wall inertial number by the calibrated mu(I) lies beyond the calibration's measured I
(``within_calibration``: outside the range calibrated, its steady rows unscored).
A law
the data cannot decide (a window the elastic start covers, too short or outside the model's regime, too few points or
drives, a model without the quantity) is ``not measurable`` with the reason, never a number fitted on noise.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace
from functools import partial

import numpy as np
import pandas as pd
from granstokes.continuum.closed_forms import uwall_asymp
from granstokes.continuum.crossing import layer_measures
from granstokes.continuum.paper.equations import eq
from granstokes.continuum.steady import steady_wall_speed

from .band import STEP
from .drive import TRANSITS_BEFORE_COMPARISON
from .families import (
    FAMILIES,
    LAYER_ESTIMATORS,
    PRIMARY_ESTIMATOR,
    RESPONSE_LEVELS,
    STEADY_WINDOWS,
    Choice,
    entry,
    family_note,
    headline,
    systematic,
)
from .plate import STEADY_LAST
from .rows import LAW_KEYS, effective_dof, law_row, not_a_line
from .scorecard import (
    CREEP_ZONES,
    beyond_calibration,
    creep_length,
    initial_state,
    short_bed,
    slipping,
    t90,
)

#: the growth window ends at this many t_s (the paper's self-similar regime holds to t~ of order 1)
GROWTH_END = 0.5
#: the plateau window: this fraction of the record after the window's start
PLATEAU_SPAN = 0.05
#: the decay window ends where mu_w - mu_s is this many times its steady value
DECAY_END = 2.0
#: t_mud: (mu_w - mu_s)/Dmu falls below this level
MUD_LEVEL = 0.5
#: fewest points of a fit, fewest drives of a law across drives
MIN_POINTS, MIN_DRIVES = 4, 3
SEED_RESAMPLES = 200
#: below this many seeds in a drive the bootstrap's sqrt((n - 1)/n) understatement (13 % at 4) is corrected
BOOTSTRAP_FEW_SEEDS = 8
#: a power law is fitted over at least this many decades of time: over less, an exponent cannot be told from a bend
MIN_DECADES = 1.0
#: a window lies inside a model's power-law regime when the model's mean exponents over REGIME_PIECES equal log-time
#: pieces of it spread by at most REGIME_TOLERANCE: a fifth of the paper's exponent 1/2, so that a window reaching
#: into the layer's saturation (where the exponent falls towards 0) is not read as a power law
REGIME_TOLERANCE, REGIME_PIECES = 0.1, 3
#: a plateau: the series' least-squares line rises or falls over the window by at most this fraction of its mean
PLATEAU_TOLERANCE = 0.1


@dataclass(frozen=True)
class Track:
    """One drive seen by one source: the primary layer depth ``delta`` (families.PRIMARY_ESTIMATOR) and the other
    LAYER_ESTIMATORS the source has (``layers``) at times ``t_layer``, the plate's u_w and mu_w and the contact
    layer's ``u_c`` (None: a source that does not slip, whose contact layer moves with the plate) at times ``t``, and
    the steady layer (the record's final quarter for the DEM, the steady state for a model): the primary depth
    ``delta_inf``, the others (``steady_layers``) and the creep lengths (a steady speed: ``steady_speed``)."""

    t_layer: np.ndarray
    delta: np.ndarray
    t: np.ndarray
    u_w: np.ndarray
    mu_w: np.ndarray
    delta_inf: float
    creep: dict          # compare.scorecard.CREEP_ZONES -> the steady profile's creep length over that zone
    layers: dict = field(default_factory=dict)
    steady_layers: dict = field(default_factory=dict)
    u_c: np.ndarray | None = None

    def depth(self, estimator: str) -> np.ndarray | None:
        """The layer's depth by ``estimator`` at ``t_layer`` (None when the source does not hold it)."""
        return self.delta if estimator == PRIMARY_ESTIMATOR else self.layers.get(estimator)

    def steady_depth(self, estimator: str) -> float:
        return self.delta_inf if estimator == PRIMARY_ESTIMATOR else float(self.steady_layers.get(estimator, np.nan))

    def speed(self, reference: str) -> np.ndarray:
        """u_w ("plate") or u_c ("contact"; u_w for a source that does not slip)."""
        return self.u_c if reference == "contact" and self.u_c is not None else self.u_w


@dataclass(frozen=True)
class Seeds:
    """A drive's DEM seed by seed on common times, computed once; ``track`` averages any resample of the seeds."""

    t: np.ndarray
    u_w: np.ndarray      # (seeds, times), and tau_w, p, u_c alike
    tau_w: np.ndarray
    p: np.ndarray
    u_c: np.ndarray
    t_layer: np.ndarray
    layers: dict         # estimator -> (seeds, layer times): the LAYER_ESTIMATORS the layer table holds
    steady: dict         # estimator -> per seed (every LAYER_ESTIMATORS, from the steady-window profiles)
    creep: dict          # CREEP_ZONES -> per seed

    @classmethod
    def of(cls, dc) -> Seeds:
        a = dc.dem
        t = a.plates[0].t
        plate = {k: np.array([np.interp(t, r.t, getattr(r, k)) for r in a.plates])
                 for k in ("u_w", "tau_w", "p", "u_c")}
        held = [k for k in LAYER_ESTIMATORS if k in a.layers.columns]
        table = a.layers.pivot_table(index="t", columns="seed", values=held, dropna=False)
        layers = {k: table[k].reindex(columns=range(len(a.plates))).to_numpy(dtype=float).T for k in held}
        delta_s = dc.scales.delta_s if dc.scales is not None else np.nan
        measures = [layer_measures(s.depth, s.u_x, s.u_x.iloc[0]) for s in a.samples]
        steady = {k: np.array([m[k] for m in measures]) for k in LAYER_ESTIMATORS}
        creep = {z: np.array([creep_length(s.depth, s.u_x, delta_s, a.spec.depth, z) for s in a.samples])
                 for z in CREEP_ZONES}
        if len(a.samples) != len(a.plates):  # blocks of one seed's window: one value for the seed
            steady = {k: np.array([np.nanmean(v)]) for k, v in steady.items()}
            creep = {z: np.array([np.nanmean(v)]) for z, v in creep.items()}
        return cls(t, plate["u_w"], plate["tau_w"], plate["p"], plate["u_c"], table.index.to_numpy(dtype=float),
                   layers, steady, creep)

    def track(self, pick) -> Track:
        """The seed-mean track over the seeds ``pick`` (indices, repeats allowed)."""
        pick = np.asarray(pick)
        u, tau, p = self.u_w[pick].mean(axis=0), self.tau_w[pick].mean(axis=0), self.p[pick].mean(axis=0)
        with np.errstate(invalid="ignore", divide="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # a layer time no picked seed resolved
            mu = np.where(p > 0, tau / p, np.nan)
            layers = {k: np.nanmean(v[pick], axis=0) for k, v in self.layers.items()}
            steady = {k: float(np.nanmean(v[pick])) for k, v in self.steady.items()}
            creep = {z: float(np.nanmean(v[pick])) for z, v in self.creep.items()}
        primary = layers.pop(PRIMARY_ESTIMATOR, np.full(len(self.t_layer), np.nan))
        return Track(self.t_layer, primary, self.t, u, mu, steady.pop(PRIMARY_ESTIMATOR),
                     creep, layers, steady, self.u_c[pick].mean(axis=0))


def model_track(pred, dc) -> Track:
    """A model's track of drive ``dc``: continuum.crossing.layer_measures of its profiles (the DEM's estimators), its
    series, and its steady profile's layer and creep lengths."""
    prof = pred.profiles.sort_values(["t", "depth"])
    t_all, depth, u = (prof[k].to_numpy(dtype=float) for k in ("t", "depth", "u"))
    times, first = np.unique(t_all, return_index=True)
    measures = [layer_measures(d, v, v[0]) for d, v in zip(np.split(depth, first[1:]), np.split(u, first[1:]))]
    layers = {k: np.array([m[k] for m in measures]) for k in LAYER_ESTIMATORS}
    st = pred.steady
    steady = layer_measures(st.y, st.u, st.u_w)
    delta_s = dc.scales.delta_s if dc.scales is not None else np.nan
    return Track(times, layers.pop(PRIMARY_ESTIMATOR), pred.series.t.to_numpy(),
                 pred.series.u_w.to_numpy(), pred.series.mu_w.to_numpy(), st.delta_u,
                 {z: creep_length(st.y, st.u, delta_s, dc.dem.spec.depth, z) for z in CREEP_ZONES}, layers,
                 {k: v for k, v in steady.items() if k != PRIMARY_ESTIMATOR})


def _slope(x, y) -> float:
    """The least-squares slope of log y against log x over the positive, finite pairs (NaN with fewer than two x)."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    ok = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
    if ok.sum() < 2 or np.ptp(np.log(x[ok])) == 0:
        return np.nan
    lx, ly = np.log(x[ok]), np.log(y[ok])
    dx = lx - lx.mean()
    return float(dx @ (ly - ly.mean()) / (dx @ dx))


# --- windows (from the DEM's scene and the calibrated scales; a model's regime picks among them) -----------

@dataclass(frozen=True)
class Window:
    """[t0, t1] of one drive for one choice, or why it cannot be used (``why``)."""

    t0: float
    t1: float
    why: str = ""

    def text(self) -> str:
        return f"[{self.t0:.3g}, {self.t1:.3g}]"


def _start(dc, from_transits: float) -> float:
    """The window's start: ``from_transits`` shear-wave transits over the bed (NaN when the transit is unknown)."""
    return from_transits * float(dc.dem.spec.transit_time)


def _spanning(w: Window) -> Window:
    """``w``, or why it spans fewer than MIN_DECADES of time."""
    if w.why or np.log10(w.t1 / w.t0) >= MIN_DECADES:
        return w
    return replace(w, why=f"the window {w.text()} spans {np.log10(w.t1 / w.t0):.2g} decade(s) of time (fewer than "
                          f"{MIN_DECADES:g})")


def growth_bounds(transit_time: float, t_s: float, t_end: float,
                  from_transits: float = TRANSITS_BEFORE_COMPARISON) -> tuple[float, float]:
    """A growth window's [start, end]: ``from_transits`` shear-wave transits to min(GROWTH_END t_s, half the record
    of length ``t_end``): what a study plans (granstokes.study.plan) and a drive's window is (``growth_window``)."""
    return from_transits * transit_time, min(GROWTH_END * t_s, 0.5 * t_end)


def growth_window(dc, from_transits: float = TRANSITS_BEFORE_COMPARISON) -> Window:
    """Drive ``dc``'s growth window from ``from_transits`` transits to min(GROWTH_END t_s, half the record)."""
    if dc.scales is None:
        return Window(np.nan, np.nan, "no calibrated scales for this drive")
    start, end = growth_bounds(float(dc.dem.spec.transit_time), dc.scales.t_s, dc.dem.t_end, from_transits)
    if not start > 0:
        return Window(start, end, "the drive's shear-wave transit time is unknown, and so is its elastic start")
    if start >= end:
        return Window(start, end, f"the elastic start ({from_transits:g} shear-wave transits, {start:.3g}) covers the "
                                  f"growth window (until {end:.3g} = min({GROWTH_END:g} t_s, half the record))")
    return _spanning(Window(start, end))


def plateau_window(dc, from_transits: float = TRANSITS_BEFORE_COMPARISON) -> Window:
    start = _start(dc, from_transits)
    if not start > 0:
        return Window(start, np.nan, "the drive's shear-wave transit time is unknown, and so is its elastic start")
    return Window(start, start + PLATEAU_SPAN * (dc.dem.t_end - start))


def local_exponents(t, y, t0: float, t1: float, pieces: int = REGIME_PIECES) -> np.ndarray:
    """The mean exponent d ln y / d ln t over each of ``pieces`` equal log-time pieces of [t0, t1], from y
    interpolated linearly in log-log between its positive samples; NaN for a piece beyond them."""
    t, y = np.asarray(t, dtype=float), np.asarray(y, dtype=float)
    ok = np.isfinite(t) & np.isfinite(y) & (t > 0) & (y > 0)
    edges = np.log(np.geomspace(t0, t1, pieces + 1))
    if ok.sum() < 2:
        return np.full(pieces, np.nan)
    lt, ly = np.log(t[ok]), np.log(y[ok])
    order = np.argsort(lt)
    at = np.where((edges >= lt.min()) & (edges <= lt.max()), np.interp(edges, lt[order], ly[order]), np.nan)
    return np.diff(at) / np.diff(edges)


def in_regime(w: Window, t, y, what: str) -> Window:
    """``w``, or why it is not inside the power-law regime of the model's ``what`` (t, y)."""
    if w.why or y is None:
        return w if w.why else replace(w, why=f"the model has no {what}")
    k = local_exponents(t, y, w.t0, w.t1)
    span = f"{w.text()} ({np.log10(w.t1 / w.t0):.2g} decades)"
    if not np.all(np.isfinite(k)):
        return replace(w, why=f"the model's {what} is not resolved over the window {span}")
    if np.ptp(k) > REGIME_TOLERANCE:
        return replace(w, why=f"the window {span} is outside the model's power-law regime: its {what}'s local "
                              f"exponents {', '.join(f'{x:.2f}' for x in k)} spread by {np.ptp(k):.2f} (more than "
                              f"{REGIME_TOLERANCE:g})")
    return w


def _in(t: np.ndarray, values: np.ndarray, w: Window) -> tuple[np.ndarray, np.ndarray]:
    """The positive, finite values at positive times in the window (a power law has no value at t = 0)."""
    sel = (t >= w.t0) & (t <= w.t1) & (t > 0) & np.isfinite(values) & (values > 0)
    return t[sel], values[sel]


# --- per-drive estimators: (track, dc, choice, window) -> {value...} or {"why"} --------------------------------

def _early(t, y, w: Window, what: str) -> dict:
    """The power law of y(t) over window ``w``: {"t", "y", "exponent", "window"} or {"why"}."""
    if w.why:
        return {"why": w.why}
    if y is None:
        return {"why": f"no {what} in the DEM's layer table (written before it was measured)"}
    t, y = _in(t, y, w)
    if len(t) < MIN_POINTS:
        return {"why": f"{len(t)} {what} in the window {w.text()} (fewer than {MIN_POINTS})"}
    return {"t": t, "y": y, "exponent": _slope(t, y), "window": [w.t0, w.t1]}


def growth(track: Track, dc, choice: Choice = FAMILIES["layer"][0], window: Window | None = None) -> dict:
    """delta ~ t^n over the growth window (``window``, else growth_window's): exponent and mean delta/sqrt(nu_g t)."""
    w = window or growth_window(dc, choice.from_transits)
    what = "layer depths" if choice.estimator == PRIMARY_ESTIMATOR else f"layer depths {choice.estimator}"
    out = _early(track.t_layer, track.depth(choice.estimator), w, what)
    if "t" in out:
        out["prefactor"] = float(np.mean(out["y"] / np.sqrt(dc.scales.nu_g * out["t"])))
    return out


def sqrt_t(track: Track, dc, choice: Choice = FAMILIES["speed"][0], window: Window | None = None) -> dict:
    """u_w ~ t^n over the growth window (an imposed stress); u_c for the contact layer's reference."""
    return _early(track.t, track.speed(choice.reference), window or growth_window(dc, choice.from_transits),
                  "plate speeds")


def _mu_hat(track: Track, dc) -> np.ndarray:
    m = dc.scales.material
    return (track.mu_w - m.mu_s) / (m.mu_d - m.mu_s)


def plateau(track: Track, dc, choice: Choice = FAMILIES["friction"][0], window: Window | None = None) -> dict:
    w = window or plateau_window(dc, choice.from_transits)
    if w.why:
        return {"why": w.why}
    sel = (track.t >= w.t0) & (track.t <= w.t1) & np.isfinite(track.mu_w)
    if sel.sum() < MIN_POINTS:
        return {"why": f"{int(sel.sum())} friction samples in the plateau window (fewer than {MIN_POINTS})"}
    return {"level": float(np.mean(_mu_hat(track, dc)[sel])), "window": [w.t0, w.t1]}


def plateau_change(track: Track, dc, w: Window) -> float:
    """The relative change of (mu_w - mu_s)/Dmu over ``w``: its least-squares line's rise over the window, over the
    line's value at the window's middle (whatever the sampling); NaN with too few samples."""
    sel = (track.t >= w.t0) & (track.t <= w.t1) & np.isfinite(track.mu_w)
    if w.why or sel.sum() < MIN_POINTS:
        return np.nan
    slope, intercept = np.polyfit(track.t[sel], _mu_hat(track, dc)[sel], 1)
    return float(abs(slope) * (w.t1 - w.t0) / abs(intercept + slope * (w.t0 + w.t1) / 2))


def t_mud(track: Track, dc, from_transits: float = TRANSITS_BEFORE_COMPARISON) -> float:
    """First time after the plateau window's start that (mu_w - mu_s)/Dmu falls below MUD_LEVEL (nan if never)."""
    w = plateau_window(dc, from_transits)
    after = (track.t >= w.t0) & (_mu_hat(track, dc) < MUD_LEVEL)
    return float(track.t[np.argmax(after)]) if after.any() and not w.why else np.nan


def decay_window(track: Track, dc, from_transits: float = TRANSITS_BEFORE_COMPARISON) -> Window:
    """[the plateau window's end, where mu_w - mu_s first comes within DECAY_END times its steady value]."""
    plate = plateau_window(dc, from_transits)
    if plate.why:
        return plate
    m = dc.scales.material
    last = track.t >= track.t[0] + STEADY_LAST * (track.t[-1] - track.t[0])
    target = DECAY_END * (float(np.nanmean(track.mu_w[last])) - m.mu_s)
    below = (track.t > plate.t1) & (track.mu_w - m.mu_s <= target)
    if not below.any() or not target > 0:
        return Window(plate.t1, np.nan, "the friction never comes within twice its steady excess over mu_s in the "
                                        "record")
    return _spanning(Window(plate.t1, float(track.t[np.argmax(below)])))


def decay(track: Track, dc, choice: Choice = FAMILIES["friction"][0], window: Window | None = None) -> dict:
    """The exponent of mu_w - mu_s over the decay window (``window``: the DEM's, applied to the models)."""
    w = window or decay_window(track, dc, choice.from_transits)
    out = _early(track.t, track.mu_w - dc.scales.material.mu_s, w, "friction samples")
    return {k: v for k, v in out.items() if k not in ("t", "y")}


# --- a drive's window for one choice and one model -----------------------------------------------------------

def _regime_window(base, series, what: str):
    """The window ``base(dc, choice, dem)`` if inside the model's power-law regime of ``series(model, dc, choice)``."""
    def window(dc, choice, dem, model) -> Window:
        return in_regime(base(dc, choice, dem), *series(model, dc, choice), what)
    return window


def _plateau_both(dc, choice, dem, model) -> Window:
    """The plateau window when both the DEM's and the model's friction hold a plateau over it."""
    w = plateau_window(dc, choice.from_transits)
    change = {who: plateau_change(tr, dc, w) for who, tr in (("DEM", dem), ("model", model))}
    if w.why or all(c <= PLATEAU_TOLERANCE for c in change.values()):
        return w
    return replace(w, why=f"no plateau in both series over {w.text()}: (mu_w - mu_s)/Dmu changes by "
                          f"{change['DEM']:.0%} in the DEM, {change['model']:.0%} in the model (a plateau: at most "
                          f"{PLATEAU_TOLERANCE:.0%})")


_GROWTH_WINDOW = _regime_window(lambda dc, choice, dem: growth_window(dc, choice.from_transits),
                                lambda tr, dc, choice: (tr.t_layer, tr.depth(choice.estimator)), "layer depth")
_SPEED_WINDOW = _regime_window(lambda dc, choice, dem: growth_window(dc, choice.from_transits),
                               lambda tr, dc, choice: (tr.t, tr.speed(choice.reference)), "plate speed")
_DECAY_WINDOW = _regime_window(lambda dc, choice, dem: decay_window(dem, dc, choice.from_transits),
                               lambda tr, dc, choice: (tr.t, tr.mu_w - dc.scales.material.mu_s), "friction excess")


# --- the laws --------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Law:
    name: str
    quantity: str
    unit: str
    kind: str | None                    # the drives it reads: "stress", "speed" or None (all)
    estimate: object                    # (tracks, drives, choice, windows) -> (value, window text) or (nan, why)
    family: tuple[Choice, ...]          # compare.families: the primary choice first
    window: object = None               # (dc, choice, DEM track, model track) -> Window; None: no window to choose
    transient: bool = True              # it reads the response over time (a model needs a calibrated time scale)

    @property
    def across(self) -> bool:
        """A line fitted across drives (its dof: drives - 2), else a mean over drives."""
        return isinstance(self.estimate, Across)


#: why a law has no drive to read
NO_DRIVE = ("no drive of this kind holds the scene rules (a plate that grips, a bed deep enough below delta_s, the "
            "flow clear of the base)")


def _mean_of(per_drive, key):
    def estimate(tracks, drives, choice, windows):
        out = [per_drive(tr, dc, choice, windows.get(dc.label)) for tr, dc in zip(tracks, drives)]
        kept = [o for o in out if key in o and np.isfinite(o[key])]
        if not kept:
            reasons = {}
            for o, dc in zip(out, drives):
                reasons.setdefault(o.get("why", ""), []).append(dc.label)
            why = "; ".join(f"{', '.join(names)}: {why}" for why, names in reasons.items() if why)
            return np.nan, "not measurable: " + (why or NO_DRIVE)
        used = [o["window"] for o in kept if "window" in o]
        text = f"{len(kept)} of {len(out)} drive(s)"
        if used:
            text += f"; windows from [{min(w[0] for w in used):.3g}, ...] to [..., {max(w[1] for w in used):.3g}]"
        return float(np.mean([o[key] for o in kept])), text
    return estimate


@dataclass(frozen=True)
class Line:
    """The least-squares line y = offset + slope x through n points weighted by 1/sd^2, each point's ``sd`` its own
    error: the slope and offset with their errors propagated from the sd (1/S_xx and 1/S_w + x_m^2/S_xx, S_w = sum w,
    x_m the weighted mean of x, S_xx = sum w (x - x_m)^2), and chi2 = sum ((y - offset - slope x)/sd)^2, the
    weighted squared residuals, with n - 2 degrees of freedom."""

    slope: float
    offset: float
    slope_err: float
    offset_err: float
    chi2: float
    n: int

    @classmethod
    def fit(cls, x, y, sd) -> Line:
        x, y, w = (np.asarray(v, dtype=float) for v in (x, y, np.asarray(sd, dtype=float) ** -2.0))
        s_w = w.sum()
        x_m, y_m = (w @ x) / s_w, (w @ y) / s_w
        s_xx = w @ (x - x_m) ** 2
        slope = (w @ ((x - x_m) * (y - y_m))) / s_xx
        offset = y_m - slope * x_m
        return cls(float(slope), float(offset), float(np.sqrt(1 / s_xx)), float(np.sqrt(1 / s_w + x_m**2 / s_xx)),
                   float(w @ (y - offset - slope * x) ** 2), len(x))

    @property
    def dof(self) -> int:
        return self.n - 2

    @property
    def chi2_dof(self) -> float:
        return self.chi2 / self.dof


@dataclass(frozen=True)
class Across:
    """A law fitted as a line across drives: ``y_of`` against ``x_of`` per drive (``fit`` "slope": the slope of
    ln y against ln x, a power law's exponent; "linear_slope" and "offset": the line's in y against x), weighted by
    each drive's error of its (transformed) y, the DEM's (``_Sources.dem_line``): the same weights for the DEM and every
    model, so that both lines are the same estimator; a drive without a value or an error is left out."""

    x_of: object                        # (track, dc, choice) -> the drive's x
    y_of: object                        # (track, dc, choice) -> the drive's y
    what: str
    fit: str = "slope"

    def points(self, tracks, drives, choice) -> tuple[np.ndarray, np.ndarray]:
        """Each drive's (x, y), logs for a power law (NaN where not positive), NaN where the drive has none."""
        x = np.array([self.x_of(tr, dc, choice) for tr, dc in zip(tracks, drives)], dtype=float)
        y = np.array([self.y_of(tr, dc, choice) for tr, dc in zip(tracks, drives)], dtype=float)
        if self.fit == "slope":
            x, y = (np.log(np.where(v > 0, v, np.nan)) for v in (x, y))
        return x, y

    def line(self, x, y, sd) -> tuple[Line | None, str]:
        """The weighted line through the drives with a value and an error, and its text (or None and why not)."""
        valued = np.isfinite(x) & np.isfinite(y)
        ok = valued & np.isfinite(sd) & (sd > 0)
        unweighted = f" ({int(valued.sum() - ok.sum())} more without a seed spread)" if valued.sum() > ok.sum() else ""
        if ok.sum() < MIN_DRIVES or len(np.unique(np.round(x[ok], 12))) < 2:
            return None, (f"not measurable: {int(ok.sum())} drive(s) with {self.what}{unweighted} (at least "
                          f"{MIN_DRIVES}, 2 values)")
        scale = "log-log " if self.fit == "slope" else ""
        return Line.fit(x[ok], y[ok], sd[ok]), (f"{int(ok.sum())} drives{unweighted}, {scale}least squares weighted by "
                                                "each drive's seed-spread error")

    def value(self, line: Line) -> tuple[float, float]:
        """The law's number and its error from the line."""
        return (line.offset, line.offset_err) if self.fit == "offset" else (line.slope, line.slope_err)

    def __call__(self, tracks, drives, choice, windows, sd) -> tuple[float, str]:
        """The law on ``tracks`` weighted by the DEM's errors ``sd`` (one per drive): (value, text) or (NaN, why)."""
        line, text = self.line(*self.points(tracks, drives, choice), np.asarray(sd, dtype=float))
        return (self.value(line)[0], text) if line is not None else (np.nan, text)


def _scale(dc, name):
    return getattr(dc.scales, name) if dc.scales is not None else np.nan


def steady_speed(tr: Track, dc, choice: Choice) -> float:
    """``tr``'s speed (the choice's reference) averaged over the DEM's output times in the record's final part
    (families.STEADY_WINDOWS): a model over the DEM's window, like with like."""
    t = dc.dem.series.t.to_numpy()
    last = t[t >= t[0] + STEADY_WINDOWS[choice.estimator] * (t[-1] - t[0])]
    return float(np.mean(np.interp(last, tr.t, tr.speed(choice.reference))))


def _ratio_exact(u, sc):
    return (u / sc.U) / steady_wall_speed(sc.material.friction, sc.mu_w)


def _ratio_asymp(u, sc):
    return (u / sc.U) / float(uwall_asymp(sc.material.friction, sc.mu_w_tilde))


def _steady_window(ratio):
    """A per-drive ratio of the steady speed (``steady_speed``) to the paper's law over its window."""
    def estimate(tr, dc, choice, window):
        t0, t1 = float(dc.dem.series.t.iloc[0]), float(dc.dem.series.t.iloc[-1])
        r = ratio(steady_speed(tr, dc, choice), dc.scales) if dc.scales is not None else np.nan
        return {"r": r, "window": [t0 + STEADY_WINDOWS[choice.estimator] * (t1 - t0), t1]}
    return estimate


def _growth_laws(kind: str) -> tuple[Law, ...]:
    return (Law("delta_growth_exponent", "n in delta_u ~ t^n", "1", kind, _mean_of(growth, "exponent"),
                FAMILIES["layer"], _GROWTH_WINDOW),
            Law("delta_growth_prefactor", "delta_u / sqrt(nu_g t)", "1", kind, _mean_of(growth, "prefactor"),
                FAMILIES["layer"], _GROWTH_WINDOW))


_DELTA_S = (lambda tr, dc, choice: _scale(dc, "delta_s"), lambda tr, dc, choice: tr.steady_depth(choice.estimator),
            "a steady layer")
LAWS = (
    *_growth_laws("stress"),
    *_growth_laws("speed"),
    Law("u_w_sqrt_t", "n in u_w ~ t^n", "1", "stress", _mean_of(sqrt_t, "exponent"), FAMILIES["speed"],
        _SPEED_WINDOW),
    Law("mu_w_plateau", "(mu_w - mu_s)/Dmu early", "1", "speed", _mean_of(plateau, "level"), FAMILIES["friction"],
        _plateau_both),
    Law("mu_w_decay_exponent", "n in mu_w - mu_s ~ t^n", "1", "speed", _mean_of(decay, "exponent"),
        FAMILIES["friction"], _DECAY_WINDOW),
    Law("delta_s_scaling", "slope of delta_u against delta_s", "1", None, Across(*_DELTA_S, "linear_slope"),
        FAMILIES["steady layer"], transient=False),
    Law("delta_s_scaling", "offset of delta_u against delta_s", "d", None, Across(*_DELTA_S, "offset"),
        FAMILIES["steady layer"], transient=False),
    Law("t_s_collapse", "slope of log t90 against log t_s", "1", "stress",
        Across(lambda tr, dc, choice: _scale(dc, "t_s"),
               lambda tr, dc, choice: t90(tr.t, tr.speed(choice.reference), RESPONSE_LEVELS[choice.estimator]),
               "a t90 and a t_s"), FAMILIES["response time"]),
    Law("t_mud_scaling", "slope of log t~_mud against log u~_w", "1", "speed",
        Across(lambda tr, dc, choice: dc.dem.spec.load.u_w / _scale(dc, "U"),
               lambda tr, dc, choice: t_mud(tr, dc, choice.from_transits) / _scale(dc, "t_s"), "a t_mud"),
        FAMILIES["friction"]),
    Law("steady_speed_law", "u~_w^inf / f(beta_w), exact steady integral", "1", "stress",
        _mean_of(_steady_window(_ratio_exact), "r"), FAMILIES["steady speed"], transient=False),
    Law("steady_speed_law", f"u~_w^inf / {eq('Uwall_asymp', named=True)}", "1", "stress",
        _mean_of(_steady_window(_ratio_asymp), "r"), FAMILIES["steady speed"], transient=False),
    Law("creep_length_scaling", "slope of log creep length against log p_w", "1", None,
        Across(lambda tr, dc, choice: dc.dem.spec.p_w, lambda tr, dc, choice: tr.creep[choice.estimator],
               "a creep length"),
        FAMILIES["creep"], transient=False),
)


def _drives(compared, kind, calibrated_I=(np.nan, np.nan)):
    """The drives a law reads: predicted, their flow clear of the base, of the law's kind, their plate gripping
    (compare.scorecard.slipping), their bed deep enough (compare.scorecard.short_bed): the scene rules of the
    scorecard's rows; and their load within the calibration (``within_calibration``)."""
    return [dc for dc in compared if dc.predictions and not dc.base and (kind is None or dc.dem.spec.kind == kind)
            and not slipping(dc.dem) and not short_bed(dc.dem, dc.scales.delta_s)
            and within_calibration(dc, calibrated_I)]


def within_calibration(dc, calibrated_I) -> bool:
    """Whether drive ``dc``'s steady wall inertial number by the calibrated mu(I) (DEM convention, at its steady
    wall friction) lies within the calibration's measured I: a drive beyond it is outside the range calibrated, and
    every law leaves it out (its steady scorecard rows are unscored, compare.scorecard.extrapolated); an unknown
    range is not checked."""
    if dc.scales is None or not np.isfinite(calibrated_I[1]):
        return True
    return not beyond_calibration(dc.scales.material, [dc.scales.mu_w], calibrated_I)


def _few_seeds(n: int) -> float:
    """The bootstrap's correction over ``n`` seeds: sqrt(n/(n - 1)) below BOOTSTRAP_FEW_SEEDS (module docstring)."""
    return float(np.sqrt(n / (n - 1))) if 1 < n < BOOTSTRAP_FEW_SEEDS else 1.0


@dataclass(frozen=True)
class _DemLaw:
    """The DEM's estimate of a law for one choice: its value (NaN: ``text`` says why), the window text, its standard
    error and that error's degrees of freedom; for a line across drives, the fit's reduced chi-square, the lack-of-fit
    note (compare.rows.not_a_line) and each drive's error ``sd``, which weights the models' lines alike."""

    value: float
    text: str
    err: float
    dof: float
    chi2_dof: float = np.nan
    lack: str = ""
    sd: np.ndarray | None = None


@dataclass(frozen=True)
class _Sources:
    """Every track the laws read: the DEM's over all seeds (``full``) and over each bootstrap resample of them
    (``replicas``), each model's (``predicted``, by (drive, model)) and its calibration-shifted ones (``shifted``, by
    (drive, model)); ``dem`` caches the DEM's estimates by law, choice and windows."""

    full: dict
    replicas: list
    predicted: dict
    shifted: dict
    seeds: dict                         # each drive's number of seeds
    calibrated_I: tuple                 # the calibration's range of I (DEM convention): a model beyond extrapolates
    dem: dict = field(default_factory=dict)

    @classmethod
    def of(cls, usable, resamples: int, seed: int, calibrated_I=(np.nan, np.nan)) -> _Sources:
        rng = np.random.default_rng(seed)
        seeds = {dc.label: Seeds.of(dc) for dc in usable}
        full = {label: s.track(np.arange(len(s.u_w))) for label, s in seeds.items()}
        bootable = bool(usable) and all(len(s.u_w) >= 2 for s in seeds.values())
        replicas = [{label: s.track(rng.integers(0, len(s.u_w), len(s.u_w))) for label, s in seeds.items()}
                    for _ in range(resamples if bootable else 0)]
        predicted = {(dc.label, p.model): model_track(p, dc) for dc in usable for p in dc.predictions}
        shifted = {(dc.label, key): [model_track(p, dc) for p in sens.shifted]
                   for dc in usable for key, sens in dc.sensitivity.items()}
        return cls(full, replicas, predicted, shifted, {label: len(s.u_w) for label, s in seeds.items()},
                   tuple(calibrated_I))

    def dem_estimate(self, law: Law, choice: Choice, drives, windows: dict) -> _DemLaw:
        """The DEM's estimate of a law that is a mean over drives: its error the bootstrap's standard deviation,
        corrected for few seeds (see the module's docstring), with n - 1 degrees of freedom."""
        key = (law.name, law.quantity, law.kind, choice, tuple(sorted(windows.items(), key=lambda kv: kv[0])))
        if key not in self.dem:
            dem, text = law.estimate([self.full[dc.label] for dc in drives], drives, choice, windows)
            boot = np.array([law.estimate([r[dc.label] for dc in drives], drives, choice, windows)[0]
                             for r in self.replicas] if np.isfinite(dem) else [])
            boot = boot[np.isfinite(boot)]
            n = min((self.seeds[dc.label] for dc in drives), default=0)
            self.dem[key] = _DemLaw(dem, text, float(boot.std(ddof=1)) * _few_seeds(n) if len(boot) >= 2 else np.nan,
                                    float(n - 1) if n > 1 else np.nan)
        return self.dem[key]

    def spread(self, law: Law, choice: Choice, drives) -> np.ndarray:
        """Each drive's seed-spread error of a line's y (its log for a power law): the standard deviation of that
        drive's y over the bootstrap resamples of its seeds, corrected for few seeds; NaN with fewer than 2 finite
        resamples."""
        ys = np.array([law.estimate.points([r[dc.label] for dc in drives], drives, choice)[1]
                       for r in self.replicas]).reshape(len(self.replicas), len(drives))
        return np.array([np.std(y[np.isfinite(y)], ddof=1) * _few_seeds(self.seeds[dc.label])
                         if np.isfinite(y).sum() >= 2 else np.nan for y, dc in zip(ys.T, drives)])

    def dem_line(self, law: Law, choice: Choice, drives) -> _DemLaw:
        """The DEM's line across drives (an Across law), each drive weighted by its seed-spread error (``spread``):
        the slope or offset, its error scaled by sqrt(chi2/dof) where that is above 1 (the points scatter about the
        line beyond their errors), n - 2 degrees of freedom, and the lack-of-fit note where the points are no line."""
        key = (law.name, law.quantity, law.kind, choice)
        if key not in self.dem:
            x, y = law.estimate.points([self.full[dc.label] for dc in drives], drives, choice)
            sd = self.spread(law, choice, drives)
            line, text = law.estimate.line(x, y, sd)
            if line is None:
                self.dem[key] = _DemLaw(np.nan, text, np.nan, np.nan, sd=sd)
            else:
                value, err = law.estimate.value(line)
                self.dem[key] = _DemLaw(value, text, err * np.sqrt(max(line.chi2_dof, 1.0)), float(line.dof),
                                        line.chi2_dof, not_a_line(line.chi2, line.dof), sd)
        return self.dem[key]


def _calibration_sd(estimate, drives, key: str, predicted: float, shifted_tracks: dict) -> float:
    """The standard deviation of a model's law from the calibration (Sensitivity.sd of the law re-estimated on
    every drive's prediction with one parameter shifted); 0 when the drives carry none (a prediction given
    without its calibration's spread)."""
    if not all((dc.label, key) in shifted_tracks for dc in drives):
        return 0.0
    sens = drives[0].sensitivity[key]
    return sens.sd_of(lambda j: estimate([shifted_tracks[(dc.label, key)][j] for dc in drives]), predicted)


def _choice(law: Law, choice: Choice, drives, model: str, src: _Sources) -> tuple[dict, str]:
    """One choice of ``law`` for ``model``: its entry (compare.families.entry, with the DEM line's ``chi2_dof``) and
    the DEM's window text.  A line that is no line (compare.rows.not_a_line) quotes no DEM value."""
    windows = ({dc.label: law.window(dc, choice, src.full[dc.label], src.predicted[(dc.label, model)])
                for dc in drives} if law.window is not None else {})
    if law.across:
        dem = src.dem_line(law, choice, drives)
        estimate = partial(law.estimate, drives=drives, choice=choice, windows=windows, sd=dem.sd)
    else:
        dem = src.dem_estimate(law, choice, drives, windows)
        estimate = partial(law.estimate, drives=drives, choice=choice, windows=windows)
    predicted, model_text = estimate([src.predicted[(dc.label, model)] for dc in drives])
    note = ""
    if beyond := _extrapolating(law, drives, model, windows, src, src.calibrated_I):
        note = beyond
    elif not np.isfinite(dem.value):
        note = dem.text
    elif dem.lack:
        note = dem.lack
    elif not np.isfinite(predicted):
        note = f"not predicted: {model_text.removeprefix('not measurable: ')}"
    elif not (np.isfinite(dem.err) and dem.err > 0):
        note = "not measurable: no spread over resampled seeds (fewer than 2 seeds per drive)"
    s_cal = 0.0 if note else _calibration_sd(lambda tracks: estimate(tracks)[0], drives, model, predicted,
                                             src.shifted)
    if not np.isfinite(s_cal):
        note, s_cal = ("not predicted: the law is undefined for a calibration parameter shifted by "
                       f"{STEP:g} of its value, so its calibration band is unknown"), 0.0
    if not note and not dem.dof > 0:
        note = f"not measurable: no degree of freedom left for the DEM's error ({len(drives)} drive(s))"
    dof = effective_dof((dem.err, s_cal), (dem.dof, np.inf)) if not note else np.nan
    value, err = (np.nan, np.nan) if dem.lack else (dem.value, dem.err)
    return ({**entry(choice, value, err, predicted, s_cal, note, dof), "chi2_dof": dem.chi2_dof},
            dem.text if np.isfinite(value) else "")


def _extrapolating(law: Law, drives, model: str, windows: dict, src: _Sources, calibrated_I) -> str:
    """Why ``model``'s side of ``law`` rests on mu(I) beyond the calibration, or "": on some drive its wall inertial
    number (DEM convention) exceeds the calibration's largest measured I (compare.scorecard.extrapolated): over the
    law's window on that drive for a law of the transient (its whole record where the law has no window), in its
    steady state for a law of the steady state (an unknown calibrated range is not checked)."""
    if not np.isfinite(calibrated_I[1]):
        return ""
    for dc in drives:
        if law.transient:
            tr, w = src.predicted[(dc.label, model)], windows.get(dc.label)
            usable = w is not None and not w.why and np.isfinite(w.t0)
            mu_w = tr.mu_w[(tr.t >= w.t0) & (tr.t <= w.t1) if usable else tr.t > 0]
        else:
            mu_w = [p.steady.mu_w for p in dc.predictions if p.model == model]
        if why := beyond_calibration(dc.scales.material, mu_w, calibrated_I):
            return f"{why} ({dc.label})"
    return ""


def _law_row(law: Law, model: str, drives, src: _Sources, calibrated: bool, start: str = "") -> dict:
    """The row of ``law`` for ``model``: its family's entries, the headline numbers and the family's verdict;
    ``start`` what the model's transient starts from (Prediction.initial)."""
    measured = [_choice(law, c, drives, model, src) for c in law.family]
    entries = [e for e, _ in measured]
    h = headline(entries)
    e, window = measured[h]
    if h:
        window = f"the primary choice ({law.family[0].describe()}) is not measurable; shown: " \
                 f"{law.family[h].describe()}: {window}"
    split = family_note(entries)
    note = e["note"] or split
    if law.transient and not calibrated:
        note = (f"not predicted: {model}'s time scale is assumed (t0 one local inertial time), not calibrated, "
                "so its transient is no prediction")
    return law_row(law=law.name, quantity=law.quantity, unit=law.unit, model=model, dem=e["dem"],
                   dem_err=e["dem_err"], predicted=e["predicted"], predicted_err=e["predicted_err"],
                   sigma=e["sigma"] if note in ("", split) else np.nan, dof=e["dof"], chi2_dof=e["chi2_dof"],
                   n_drives=len(drives), window=window, note=note, choices=entries, systematic=systematic(entries),
                   kind=law.kind or "all",
                   initial_state=initial_state(start) if law.transient else "")



def laws(compared, calibrated_I=(np.nan, np.nan), resamples: int = SEED_RESAMPLES, seed: int = 1) -> pd.DataFrame:
    """Every law x model row (compare.rows.LAW_KEYS) over the drives ``compared`` (comparison.DriveComparison);
    ``calibrated_I`` the calibration's range of I (DEM convention; unknown: not checked)."""
    usable = _drives(compared, None, calibrated_I)
    src = _Sources.of(usable, resamples, seed, calibrated_I)
    predicted = [p for dc in compared for p in dc.predictions]  # every model, though no drive hold the rules
    calibrated = {p.model: p.transient_calibrated for p in predicted}
    starts = {p.model: p.initial for p in predicted}
    rows = [_law_row(law, model, _drives(compared, law.kind, calibrated_I), src, calibrated[model],
                     starts[model])
            for law in LAWS for model in calibrated]
    return pd.DataFrame(rows, columns=list(dict.fromkeys([*LAW_KEYS, *(k for r in rows for k in r)])))
