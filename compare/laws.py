"""The paper's laws confronted with the DEM: one row per law x model, the same estimator on the DEM's
seed-mean series and on every model's output over the same window (DEM units; tilde variables as in
continuum.scales).

Per drive (a ``Track``: times, the layer depth delta_u(t) at U_FRACTION of u_w, u_w(t), mu_w(t), and the
steady u_w, delta_u, creep length), from the DEM's seeds or from a model's prediction:

* ``delta_growth_exponent``, ``delta_growth_prefactor``: delta_u ~ t^n and delta_u/sqrt(nu_g t) over the
  growth window [3 shear-wave transits (the elastic start), GROWTH_END t_s];
* ``u_w_sqrt_t``: the exponent of u_w(t) over the same window (imposed stress; the paper: 1/2);
* ``mu_w_plateau``: (mu_w - mu_s)/Dmu over the plateau window, the first PLATEAU_SPAN of the record after the
  elastic start (imposed speed; the paper: close to 1, mu_w near mu_d);
* ``mu_w_decay_exponent``: the exponent of mu_w - mu_s from the plateau's end to where it is DECAY_END times
  its steady value (imposed speed; the paper: -1/2);
and across drives:
* ``delta_s_scaling``: steady delta_u against the calibrated delta_s = beta_w p_w/(phi rho_p g) (slope, offset);
* ``t_s_collapse``: the slope of log t90 against log t_s over the imposed stresses (the paper: 1);
* ``t_mud_scaling``: the slope of log t~_mud against log u~_w over the imposed speeds (the paper: 2), t_mud the
  first time after the elastic start that (mu_w - mu_s)/Dmu falls below MUD_LEVEL;
* ``steady_speed_law``: u~_w^inf over the exact steady integral f(beta_w) (eq. (3.11) with the exact profile)
  and over its asymptote, eq. (3.12), averaged over the imposed stresses (the paper: 1);
* ``creep_length_scaling``: the slope of log creep length against log p_w (local mu(I): no creep at all).

Errors: dem_err is the standard deviation of the DEM's estimate over SEED_RESAMPLES bootstrap resamples of each
drive's seeds (independent samples), times sqrt(n/(n - 1)) where the smallest drive has n < BOOTSTRAP_FEW_SEEDS
seeds (the bootstrap's spread of a mean over n samples is the sample's standard error times sqrt((n - 1)/n)), with
n - 1 degrees of freedom (a law fitted across drives: n_drives - 2); the model's standard deviation s_cal propagates
the calibration's replicates linearly (compare.band.Sensitivity: the same estimate on the predictions re-solved with
each parameter shifted), band = predicted -+ 1.96 s_cal, and sigma = (dem - predicted)/sqrt(dem_err^2 + s_cal^2).
A law the data cannot decide (a window the elastic start covers, too few points or drives, a model without the
quantity) is ``not measurable`` with the reason, never a number fitted on noise.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd
from granstokes.continuum.closed_forms import uwall_asymp
from granstokes.continuum.crossing import depth_at_fraction, layer_measures
from granstokes.continuum.paper.equations import eq
from granstokes.continuum.steady import steady_wall_speed
from scipy import stats

from .band import STEP
from .plate import STEADY_LAST
from .rows import LAW_KEYS, effective_dof, law_row, sigma
from .scorecard import creep_length, t90

#: the growth window ends at this many t_s (the paper's self-similar regime holds to t~ of order 1)
GROWTH_END = 0.5
#: the plateau window: this fraction of the record after the elastic start
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


@dataclass(frozen=True)
class Track:
    """One drive seen by one source: the layer depth delta_u at times ``t_layer``, the plate's u_w and mu_w at times
    ``t``, and the steady values (the record's final quarter for the DEM, the steady state for a model)."""

    t_layer: np.ndarray
    delta: np.ndarray
    t: np.ndarray
    u_w: np.ndarray
    mu_w: np.ndarray
    u_w_inf: float
    delta_inf: float
    creep: float


@dataclass(frozen=True)
class Seeds:
    """A drive's DEM seed by seed on common times, computed once; ``track`` averages any resample of the seeds."""

    t: np.ndarray
    u_w: np.ndarray      # (seeds, times), and tau_w, p alike
    tau_w: np.ndarray
    p: np.ndarray
    t_layer: np.ndarray
    delta: np.ndarray    # (seeds, layer times)
    delta_inf: np.ndarray  # per seed
    creep: np.ndarray      # per seed

    @classmethod
    def of(cls, dc) -> Seeds:
        a = dc.dem
        t = a.plates[0].t
        plate = {k: np.array([np.interp(t, r.t, getattr(r, k)) for r in a.plates]) for k in ("u_w", "tau_w", "p")}
        lay = a.layers.pivot_table(index="t", columns="seed", values="delta_05").reindex(columns=range(len(a.plates)))
        delta_s = dc.scales.delta_s if dc.scales is not None else np.nan
        depth = np.array([depth_at_fraction(s.depth.to_numpy(), s.u_x.to_numpy(), s.u_x.iloc[0]) for s in a.samples])
        creep = np.array([creep_length(s.depth, s.u_x, delta_s, a.spec.depth) for s in a.samples])
        if len(a.samples) != len(a.plates):  # blocks of one seed's window: one value for the seed
            depth, creep = np.array([np.nanmean(depth)]), np.array([np.nanmean(creep)])
        return cls(t, plate["u_w"], plate["tau_w"], plate["p"], lay.index.to_numpy(dtype=float), lay.to_numpy().T,
                   depth, creep)

    def track(self, pick) -> Track:
        """The seed-mean track over the seeds ``pick`` (indices, repeats allowed)."""
        pick = np.asarray(pick)
        u, tau, p = self.u_w[pick].mean(axis=0), self.tau_w[pick].mean(axis=0), self.p[pick].mean(axis=0)
        last = self.t >= self.t[0] + STEADY_LAST * (self.t[-1] - self.t[0])
        with np.errstate(invalid="ignore", divide="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # a layer time no picked seed resolved
            mu = np.where(p > 0, tau / p, np.nan)
            delta = np.nanmean(self.delta[pick], axis=0)
        return Track(self.t_layer, delta, self.t, u, mu, float(u[last].mean()),
                     float(np.nanmean(self.delta_inf[pick])), float(np.nanmean(self.creep[pick])))


def model_track(pred, dc) -> Track:
    """A model's track of drive ``dc``: its profiles' delta_u (continuum.crossing.layer_measures, the DEM's
    estimator), its series, its u_w averaged over the DEM's steady window and its steady profile."""
    times, delta = [], []
    for t, g in pred.profiles.groupby("t"):
        g = g.sort_values("depth")
        times.append(t)
        delta.append(layer_measures(g.depth, g.u, float(g.u.iloc[0]))["delta_05"])
    st = pred.steady
    delta_s = dc.scales.delta_s if dc.scales is not None else np.nan
    t = dc.dem.series.t.to_numpy()
    last = t[t >= t[0] + STEADY_LAST * (t[-1] - t[0])]  # the DEM's steady window: the plate value like with like
    u_w = float(np.mean(np.interp(last, pred.series.t, pred.series.u_w)))
    return Track(np.array(times), np.array(delta), pred.series.t.to_numpy(), pred.series.u_w.to_numpy(),
                 pred.series.mu_w.to_numpy(), u_w, st.delta_u, creep_length(st.y, st.u, delta_s, dc.dem.spec.depth))


def _slope(x, y) -> float:
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    ok = np.isfinite(x) & np.isfinite(y) & (x > 0) & (y > 0)
    if ok.sum() < 2 or np.ptp(np.log(x[ok])) == 0:
        return np.nan
    return float(stats.linregress(np.log(x[ok]), np.log(y[ok])).slope)


# --- windows (from the DEM's scene and the calibrated scales: the same for every source) -------------------

def growth_window(dc) -> tuple[float, float, str]:
    """(t0, t1, why not measurable or "") of drive ``dc``'s growth."""
    start = float(np.nan_to_num(dc.dem.spec.compared_from))
    if dc.scales is None:
        return np.nan, np.nan, "no calibrated scales for this drive"
    end = min(GROWTH_END * dc.scales.t_s, 0.5 * dc.dem.t_end)
    if start >= end:
        return start, end, (f"the elastic start (3 shear-wave transits, {start:.3g}) covers the growth window "
                            f"(until {end:.3g} = min({GROWTH_END:g} t_s, half the record))")
    return start, end, ""


def plateau_window(dc) -> tuple[float, float]:
    start = float(np.nan_to_num(dc.dem.spec.compared_from))
    return start, start + PLATEAU_SPAN * (dc.dem.t_end - start)


def _in(t: np.ndarray, values: np.ndarray, t0: float, t1: float) -> tuple[np.ndarray, np.ndarray]:
    """The positive, finite values at times in [t0, t1]."""
    sel = (t >= t0) & (t <= t1) & np.isfinite(values) & (values > 0)
    return t[sel], values[sel]


# --- per-drive estimators ---------------------------------------------------------------------------------

def _early(t, y, dc, what: str) -> dict:
    """The early power law of y(t) over the growth window: {"t", "y", "window"} or {"why"}."""
    t0, t1, why = growth_window(dc)
    if why:
        return {"why": why}
    t, y = _in(t, y, t0, t1)
    if len(t) < MIN_POINTS:
        return {"why": f"{len(t)} {what} in the growth window [{t0:.3g}, {t1:.3g}] (fewer than {MIN_POINTS})"}
    return {"t": t, "y": y, "exponent": _slope(t, y), "window": [t0, t1]}


def growth(track: Track, dc) -> dict:
    """delta_u ~ t^n over the growth window: exponent and mean delta_u/sqrt(nu_g t)."""
    out = _early(track.t_layer, track.delta, dc, "layer depths")
    if "t" in out:
        out["prefactor"] = float(np.mean(out["y"] / np.sqrt(dc.scales.nu_g * out["t"])))
    return out


def sqrt_t(track: Track, dc) -> dict:
    """u_w ~ t^n over the growth window (an imposed stress)."""
    return _early(track.t, track.u_w, dc, "plate speeds")


def _mu_hat(track: Track, dc) -> np.ndarray:
    m = dc.scales.material
    return (track.mu_w - m.mu_s) / (m.mu_d - m.mu_s)


def plateau(track: Track, dc) -> dict:
    t0, t1 = plateau_window(dc)
    sel = (track.t >= t0) & (track.t <= t1) & np.isfinite(track.mu_w)
    if sel.sum() < MIN_POINTS:
        return {"why": f"{int(sel.sum())} friction samples in the plateau window (fewer than {MIN_POINTS})"}
    return {"level": float(np.mean(_mu_hat(track, dc)[sel])), "window": [t0, t1]}


def t_mud(track: Track, dc) -> float:
    """First time after the plateau window's start that (mu_w - mu_s)/Dmu falls below MUD_LEVEL (nan if never)."""
    t0, _ = plateau_window(dc)
    after = (track.t >= t0) & (_mu_hat(track, dc) < MUD_LEVEL)
    return float(track.t[np.argmax(after)]) if after.any() else np.nan


def decay(track: Track, dc, window=None) -> dict:
    """The exponent of mu_w - mu_s over [end of the plateau, where it reaches DECAY_END times its steady value]
    (``window``: the DEM's, applied to the models)."""
    m = dc.scales.material
    excess = track.mu_w - m.mu_s
    if window is None:
        _, t0 = plateau_window(dc)
        last = track.t >= track.t[0] + STEADY_LAST * (track.t[-1] - track.t[0])
        target = DECAY_END * (float(np.nanmean(track.mu_w[last])) - m.mu_s)
        below = (track.t > t0) & (excess <= target)
        if not below.any() or not target > 0:
            return {"why": "the friction never comes within twice its steady excess over mu_s in the record"}
        window = (t0, float(track.t[np.argmax(below)]))
    t, e = _in(track.t, excess, *window)
    if len(t) < MIN_POINTS:
        return {"why": f"{len(t)} friction samples in the decay window [{window[0]:.3g}, {window[1]:.3g}]"}
    return {"exponent": _slope(t, e), "window": list(window)}


# --- the laws --------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Law:
    name: str
    quantity: str
    unit: str
    kind: str | None                    # the drives it reads: "stress", "speed" or None (all)
    estimate: object                    # (tracks, drives) -> (value, window text) or (nan, why)
    transient: bool = True              # it reads the response over time (a model needs a calibrated time scale)


def _mean_of(per_drive, key):
    def estimate(tracks, drives):
        out = [per_drive(tr, dc) for tr, dc in zip(tracks, drives)]
        values = [o[key] for o in out if key in o and np.isfinite(o[key])]
        if not values:
            reasons = sorted({o.get("why", "") for o in out} - {""})
            return np.nan, "not measurable: " + ("; ".join(reasons) or "no drive of this kind")
        windows = [o["window"] for o in out if "window" in o]
        text = f"{len(values)} drive(s); windows from [{min(w[0] for w in windows):.3g}, ...] to " \
               f"[..., {max(w[1] for w in windows):.3g}]"
        return float(np.mean(values)), text
    return estimate


def _across(x_of, y_of, what: str, fit: str = "slope"):
    def estimate(tracks, drives):
        x = np.array([x_of(tr, dc) for tr, dc in zip(tracks, drives)], dtype=float)
        y = np.array([y_of(tr, dc) for tr, dc in zip(tracks, drives)], dtype=float)
        ok = np.isfinite(x) & np.isfinite(y)
        if fit == "slope":
            ok &= (x > 0) & (y > 0)
        if ok.sum() < MIN_DRIVES or len(np.unique(np.round(x[ok], 12))) < 2:
            return np.nan, f"not measurable: {int(ok.sum())} drive(s) with {what} (at least {MIN_DRIVES}, 2 values)"
        if fit == "slope":
            return _slope(x[ok], y[ok]), f"{int(ok.sum())} drives, log-log least squares"
        lin = stats.linregress(x[ok], y[ok])
        return float(lin.slope if fit == "linear_slope" else lin.intercept), f"{int(ok.sum())} drives, least squares"
    return estimate


def _scale(dc, name):
    return getattr(dc.scales, name) if dc.scales is not None else np.nan


def _ratio_exact(tr, dc):
    sc = dc.scales
    return (tr.u_w_inf / sc.U) / steady_wall_speed(sc.material.friction, sc.mu_w) if sc is not None else np.nan


def _ratio_asymp(tr, dc):
    sc = dc.scales
    return (tr.u_w_inf / sc.U) / float(uwall_asymp(sc.material.friction, sc.mu_w_tilde)) if sc is not None else np.nan


def _steady_window(ratio):
    """A per-drive steady ratio over the record's final quarter (the DEM's steady window)."""
    return lambda tr, dc: {"r": ratio(tr, dc), "window": [STEADY_LAST * dc.dem.t_end, dc.dem.t_end]}


_DELTA_S = (lambda tr, dc: _scale(dc, "delta_s"), lambda tr, dc: tr.delta_inf, "a steady layer")
LAWS = (
    Law("delta_growth_exponent", "n in delta_u ~ t^n", "1", None, _mean_of(growth, "exponent")),
    Law("delta_growth_prefactor", "delta_u / sqrt(nu_g t)", "1", None, _mean_of(growth, "prefactor")),
    Law("u_w_sqrt_t", "n in u_w ~ t^n", "1", "stress", _mean_of(sqrt_t, "exponent")),
    Law("mu_w_plateau", "(mu_w - mu_s)/Dmu early", "1", "speed", _mean_of(plateau, "level")),
    Law("mu_w_decay_exponent", "n in mu_w - mu_s ~ t^n", "1", "speed", _mean_of(decay, "exponent")),
    Law("delta_s_scaling", "slope of delta_u against delta_s", "1", None, _across(*_DELTA_S, "linear_slope"),
        transient=False),
    Law("delta_s_scaling", "offset of delta_u against delta_s", "d", None, _across(*_DELTA_S, "offset"),
        transient=False),
    Law("t_s_collapse", "slope of log t90 against log t_s", "1", "stress",
        _across(lambda tr, dc: _scale(dc, "t_s"), lambda tr, dc: t90(tr.t, tr.u_w), "a t90 and a t_s")),
    Law("t_mud_scaling", "slope of log t~_mud against log u~_w", "1", "speed",
        _across(lambda tr, dc: dc.dem.spec.load.u_w / _scale(dc, "U"),
                lambda tr, dc: t_mud(tr, dc) / _scale(dc, "t_s"), "a t_mud")),
    Law("steady_speed_law", "u~_w^inf / f(beta_w), exact steady integral", "1", "stress",
        _mean_of(_steady_window(_ratio_exact), "r"), transient=False),
    Law("steady_speed_law", f"u~_w^inf / {eq('Uwall_asymp', named=True)}", "1", "stress",
        _mean_of(_steady_window(_ratio_asymp), "r"), transient=False),
    Law("creep_length_scaling", "slope of log creep length against log p_w", "1", None,
        _across(lambda tr, dc: dc.dem.spec.p_w, lambda tr, dc: tr.creep, "a creep length"), transient=False),
)


def _drives(compared, kind):
    """The drives a law reads: predicted, their flow clear of the base, of the law's kind."""
    return [dc for dc in compared if dc.predictions and not dc.base and (kind is None or dc.dem.spec.kind == kind)]


def _decay_windows(drives, full: dict):
    """The DEM's decay windows (applied unchanged to the models)."""
    out = {}
    for dc in drives:
        d = decay(full[dc.label], dc)
        out[dc.label] = tuple(d["window"]) if "window" in d else None
    return out


def _calibration_sd(estimate, drives, key: str, predicted: float, shifted_tracks: dict) -> float:
    """The standard deviation of a model's law from the calibration (Sensitivity.sd of the law re-estimated on
    every drive's prediction with one parameter shifted); 0 when the drives carry none (a prediction given
    without its calibration's spread)."""
    if not all((dc.label, key) in shifted_tracks for dc in drives):
        return 0.0
    sens = drives[0].sensitivity[key]
    return sens.sd_of(lambda j: estimate([shifted_tracks[(dc.label, key)][j] for dc in drives], drives)[0], predicted)


def laws(compared, resamples: int = SEED_RESAMPLES, seed: int = 1) -> pd.DataFrame:
    """Every law x model row (compare.rows.LAW_KEYS) over the drives ``compared`` (comparison.DriveComparison)."""
    rng = np.random.default_rng(seed)
    usable = _drives(compared, None)
    seeds = {dc.label: Seeds.of(dc) for dc in usable}
    full = {label: s.track(np.arange(len(s.u_w))) for label, s in seeds.items()}
    bootable = bool(usable) and all(len(s.u_w) >= 2 for s in seeds.values())
    replicas = [{label: s.track(rng.integers(0, len(s.u_w), len(s.u_w))) for label, s in seeds.items()}
                for _ in range(resamples if bootable else 0)]
    models = dict.fromkeys(p.model for dc in usable for p in dc.predictions)
    calibrated = {p.model: p.transient_calibrated for dc in usable for p in dc.predictions}
    predicted_tracks = {(dc.label, p.model): model_track(p, dc) for dc in usable for p in dc.predictions}
    shifted_tracks = {(dc.label, key): [model_track(p, dc) for p in sens.shifted]
                      for dc in usable for key, sens in dc.sensitivity.items()}
    rows = []
    for law in LAWS:
        drives = _drives(compared, law.kind)
        estimate = law.estimate
        if law.name == "mu_w_decay_exponent":
            windows = _decay_windows(drives, full)
            estimate = _mean_of(lambda tr, dc, w=windows: decay(tr, dc, w[dc.label]) if w[dc.label] else
                                {"why": "the DEM's friction has no decay window"}, "exponent")
        dem, window = estimate([full[dc.label] for dc in drives], drives)
        boot = np.array([estimate([r[dc.label] for dc in drives], drives)[0] for r in replicas] if np.isfinite(dem)
                        else [])
        boot = boot[np.isfinite(boot)]
        n_seeds = min((len(seeds[dc.label].u_w) for dc in drives), default=0)
        few = np.sqrt(n_seeds / (n_seeds - 1)) if 1 < n_seeds < BOOTSTRAP_FEW_SEEDS else 1.0
        dem_err = float(boot.std(ddof=1)) * few if len(boot) >= 2 else np.nan
        dem_dof = len(drives) - 2 if law.estimate.__qualname__.startswith("_across") else n_seeds - 1
        for key in models:
            predicted, model_window = estimate([predicted_tracks[(dc.label, key)] for dc in drives], drives)
            note = ""
            if law.transient and not calibrated[key]:
                note = (f"not predicted: {key}'s time scale is assumed (t0 one local inertial time), not calibrated, "
                        "so its transient is no prediction")
            elif not np.isfinite(dem):
                note = window
            elif not np.isfinite(predicted):
                note = f"not predicted: {model_window.removeprefix('not measurable: ')}"
            elif not (np.isfinite(dem_err) and dem_err > 0):
                note = "not measurable: no spread over resampled seeds (fewer than 2 seeds per drive)"
            s_cal = 0.0 if note else _calibration_sd(estimate, drives, key, predicted, shifted_tracks)
            if not np.isfinite(s_cal):
                note, s_cal = ("not predicted: the law is undefined for a calibration parameter shifted by "
                               f"{STEP:g} of its value, so its calibration band is unknown"), 0.0
            rows.append(law_row(law=law.name, quantity=law.quantity, unit=law.unit, kind=law.kind or "both",
                                model=key, dem=dem, dem_err=dem_err, predicted=predicted, predicted_err=s_cal,
                                sigma=np.nan if note else sigma(dem - predicted, dem_err, s_cal),
                                dof=effective_dof((dem_err, s_cal), (dem_dof, np.inf)),
                                chi2_dof=np.nan, n_drives=len(drives), window=window if np.isfinite(dem) else "",
                                note=note))
    return pd.DataFrame(rows, columns=list(LAW_KEYS))
