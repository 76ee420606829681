"""The verdict: one row per drive x observable x model, DEM value with its error against the model's
prediction with a 95 % band propagated from the calibration's uncertainty.

Observables (DEM units; estimators applied alike to the DEM and to every model):

* ``u_w_inf`` (imposed stress) or ``mu_w_inf`` (imposed speed): the steady value of the free response, the
  model's averaged over the DEM's window (the record's final quarter: like with like; its ``asymptote`` beside);
* ``delta_u``: steady layer thickness, the depth where the steady-window u falls to 5 % of u_w;
* ``t90``: time for the running mean of the free response to cover 90 % of its change (the model's
  series is interpolated onto the DEM's output times first, so that both are smoothed alike);
* ``creep_length``: e-folding length of u below the calibrated delta_s (least squares of ln u over
  depth, over CREEP_WINDOW below delta_s); local mu(I) is rigid there: 0.

Errors.  DEM: spread over seeds (standard error of the mean; n_seeds - 1 degrees of freedom) when a drive has
>= 2 seeds; with one seed, for the profile observables the spread over BLOCKS consecutive blocks of the steady
window (BLOCKS - 1 degrees of freedom), for t90 the running mean's half-width (a resolution, not a statistical
error: infinitely many degrees of freedom); for the steady response the block or seed error of
compare.plate.pooled with its degrees of freedom.  Model: the band is the 2.5-97.5 % range over
the calibration's replicates (joint samples of mu_s, mu_d, I0, phi) for the steady profile observables; for
t90 and the windowed plate value (a transient solve per sample is too costly) the linearised propagation
J C J^T of the replicates' covariance C, J by one-sided differences, band +-1.96 sd (the plate value's: the
band's mean over the window); the numerical error of t90 is its change when every other output time is dropped
(interpolation), none for the others (the solvers' errors are far below the bands).  sigma =
(dem - predicted) / sqrt(dem_err^2 + band_sd^2 + numerical^2), band_sd = band width / (2 x 1.96); the row's dof
the Welch-Satterthwaite degrees of freedom of that combined error (the band's and the numerical error's infinite);
verdict "consistent" when |sigma| <= t_0.975(dof) (compare.rows.verdict).

Rows that the scene cannot support are kept but not scored (``scored`` False, ``note`` says why): where the plate
slips by more than SLIP_MAX against the grains touching it (``slipping``), every row of the drive (the plate's speed
and friction are not the bed's, and every model's plate grips); where the bed leaves less than the depth study's
clearance between delta_s and the base (``short_bed``, dem.sizing.clearance), every row of the drive; where a model's
steady wall inertial number lies beyond the calibration's largest I (``extrapolated``), its steady rows; where the
drive's flow reaches the base (``base_reach``), its layer observables, and every row of a model whose bed is a
half-space; where a model is not yet steady over the DEM's final quarter (the record is shorter than the model's time
scale), that model's steady profile rows (delta_u, creep_length).  A row is ``blind`` only when mu(I) comes from an
independent calibration and the model's own parameter was not fitted on that drive; only scored blind rows count for
a model (``tally``), and models are ranked over the rows they share.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from granstokes.continuum.crossing import crossing_depth, depth_at_fraction
from granstokes.continuum.rheology import convert_I
from granstokes.continuum.scene_models import Prediction, SceneModel, Steady
from granstokes.dem.sizing import BASE_CLEARANCE, DEPTH_STUDY_DELTA_S, clearance
from scipy import stats

from .analysis import DriveAnalysis
from .band import Sensitivity
from .calibrate import WALL_EXCLUSION
from .plate import SLIP_MAX, STEADY_LAST
from .rows import Z95, critical, effective_dof, score_row, sigma, tally

OBSERVABLES = {
    "u_w_inf": ("sqrt(g d)", "steady plate speed"),
    "mu_w_inf": ("1", "steady plate friction <tau_w>/<p>"),
    "delta_u": ("d", "steady layer thickness (u = 5 % of u_w)"),
    "t90": ("sqrt(d/g)", "time to 90 % of the change of the free response"),
    "creep_length": ("d", "e-folding length of u below delta_s"),
}
#: t90: the running mean over this fraction of the record reaches this fraction of the change
T90_WINDOW, T90_LEVEL = 0.05, 0.9
#: a model whose free response over the DEM's final quarter is this far from its steady value is not steady
#: within the record: the record is shorter than the model's time scale
MODEL_UNSTEADY = 0.05
#: the observables of the steady state, and those of the layer (meaningless where the flow reaches the base)
STEADY_OBSERVABLES = ("u_w_inf", "mu_w_inf", "delta_u", "creep_length")
LAYER_OBSERVABLES = ("delta_u", "creep_length")
TRANSIENT_OBSERVABLES = ("t90",)


def t90(t, y, level: float = T90_LEVEL) -> float:
    """First time the running mean (T90_WINDOW of the record) has covered ``level`` (90 %) of the change from the
    first to the final-tenth value, interpolated linearly between output times (continuum.crossing);
    the running mean keeps DEM noise from triggering it."""
    y = pd.Series(np.asarray(y, dtype=float)).interpolate(limit_direction="both")
    t = np.asarray(t, dtype=float)
    smooth = y.rolling(max(1, int(T90_WINDOW * len(y))), center=True, min_periods=1).mean().to_numpy()
    start, final = smooth[0], np.mean(smooth[-max(1, len(smooth) // 10):])
    if final == start:
        return np.nan
    remaining = 1 - (smooth - start) / (final - start)  # 1 at the start, 0 at the final value
    return crossing_depth(t, remaining, 1 - level)


#: the creep's fit zones (the creep law's estimator family, compare.families), each of fixed width and never below the
#: base's WALL_EXCLUSION: the tail's first CREEP_WINDOW below delta_s ("creep", the scorecard's), as wide from
#: CREEP_ZONE_OFFSET below delta_s (clear of the yield surface's rounding) and twice as wide.  Fixed, because the DEM's
#: tail is not exponential: the length fitted from delta_s to the base grows with the bed (3.0 to 13.1 d from 26 to 78
#: d, bench/creep_depth.py), over the first 3 d it does not (2.5-2.8 d), over 6 d it grows less (2.5-3.5 d)
CREEP_WINDOW, CREEP_ZONE_OFFSET = 3.0, 2.0
CREEP_ZONES = {
    "creep": lambda delta_s, bottom: (delta_s, min(delta_s + CREEP_WINDOW, bottom)),
    "creep_deep": lambda delta_s, bottom: (delta_s + CREEP_ZONE_OFFSET,
                                           min(delta_s + CREEP_ZONE_OFFSET + CREEP_WINDOW, bottom)),
    "creep_wide": lambda delta_s, bottom: (delta_s, min(delta_s + 2 * CREEP_WINDOW, bottom)),
}


def creep_length(depth, u, delta_s: float, bed_depth: float, zone: str = "creep") -> float:
    """e-folding length of u below delta_s (least squares of ln u over the CREEP_ZONES ``zone``, by default
    [delta_s, delta_s + CREEP_WINDOW] above bed_depth - WALL_EXCLUSION); 0 when u vanishes there (rigid), nan when
    fewer than 3 points lie in it."""
    depth, u = np.asarray(depth, dtype=float), np.asarray(u, dtype=float)
    top, bottom = CREEP_ZONES[zone](delta_s, bed_depth - WALL_EXCLUSION)
    zone = (depth >= top) & (depth <= bottom)
    if zone.sum() < 3:
        return np.nan
    moving = zone & (u > 0)
    if moving.sum() < 3:
        return 0.0
    slope = stats.linregress(depth[moving], np.log(u[moving])).slope
    return float(-1 / slope) if slope < 0 else np.nan


@dataclass(frozen=True)
class Measured:
    """A DEM value, its standard error, how it was estimated and the error's degrees of freedom."""

    value: float
    err: float
    how: str
    dof: float


def _mean_err(values, how: str) -> Measured:
    """The mean of the finite ``values`` (independent samples: seeds or blocks) and its standard error, with
    samples - 1 degrees of freedom."""
    v = np.asarray([x for x in values if np.isfinite(x)], dtype=float)
    if len(v) < 2:
        return Measured(float(v.mean()) if len(v) else np.nan, np.nan, how, np.nan)
    return Measured(float(v.mean()), float(v.std(ddof=1) / np.sqrt(len(v))), how, len(v) - 1)


def base_reach(a: DriveAnalysis, delta_s: float) -> str:
    """Why drive ``a``'s flow reaches the base, or "": its steady DEM layer (delta_u) or the calibrated
    delta_s comes within WALL_EXCLUSION of the base, or u never falls to 5 % of u_w in the bed."""
    p = a.steady_profile
    p = p[p.depth >= 0].sort_values("depth")
    dem = depth_at_fraction(p.depth.to_numpy(), p.u_x.to_numpy(), p.u_x.iloc[0])
    limit = a.spec.depth - WALL_EXCLUSION
    if not np.isfinite(dem):
        return f"the flow reaches the base: u stays above 5 % of u_w down to the base of the {a.spec.depth:.3g} d bed"
    if max(dem, delta_s) >= limit:
        return (f"the flow reaches the base: the layer (DEM delta_u {dem:.3g} d, calibrated delta_s {delta_s:.3g} d) "
                f"comes within {WALL_EXCLUSION:g} d of the base of the {a.spec.depth:.3g} d bed")
    return ""


def dem_creep(a: DriveAnalysis, delta_s: float) -> Measured:
    """The DEM's creep length of drive ``a`` (``creep_length`` of each of its steady-window samples below the
    calibrated ``delta_s``): the mean and its standard error."""
    return _mean_err([creep_length(s.depth, s.u_x, delta_s, a.spec.depth) for s in a.samples], a.samples_how)


def depth_needed(delta_s: float) -> float:
    """The depth a bed needs below the calibrated ``delta_s``: delta_s and the depth study's clearance
    (dem.sizing.clearance)."""
    return delta_s + clearance(delta_s)


def short_bed(a: DriveAnalysis, delta_s: float) -> str:
    """Why drive ``a``'s bed is too shallow for its rows, or "": it is shorter than ``depth_needed``."""
    need = depth_needed(delta_s)
    if a.spec.depth >= need:
        return ""
    return (f"the bed ({a.spec.depth:.3g} d) leaves {a.spec.depth - delta_s:.3g} d below delta_s ({delta_s:.3g} d), "
            f"less than the {need - delta_s:.3g} d ({BASE_CLEARANCE:g} x max(delta_s, {DEPTH_STUDY_DELTA_S:g} d)) at "
            "which the depth study found the observables independent of the depth")


def bulk(table: pd.DataFrame, bed_depth: float) -> pd.Series:
    """Rows of a depth profile away from plate and base (WALL_EXCLUSION)."""
    return (table.depth > WALL_EXCLUSION) & (table.depth < bed_depth - WALL_EXCLUSION)


#: the pressure slope's least-squares error counts correlated depths as independent (a lower bound): the
#: check passes within this relative tolerance as well (the smoke CG test's 10 %)
PRESSURE_TOLERANCE = 0.1


def slipping(a: DriveAnalysis) -> str:
    """Why drive ``a``'s rows are not scored, or "": the grains touching the plate lag it by more than SLIP_MAX of its
    speed, so the plate's speed is not the bed's, its friction is a wall's, not the material's, and the bed is driven
    by a boundary no model has (every model's plate grips)."""
    value = a.slip["value"]
    if not value > SLIP_MAX:
        return ""
    return (f"not scored: the plate slips {value:.0%} against the grains touching it (more than {SLIP_MAX:.0%}), "
            "so its speed and friction are not the bed's")


def initial_state(start: str) -> str:
    """What a transient row says of its model's start (``start``: Prediction.initial): no model starts from the DEM
    bed's measured stresses tau(y, 0), which the plate's loading leaves anywhere between rest and yield."""
    return f"the model starts from {start or 'its own initial state'}, not from the DEM bed's measured tau(y, 0)"


def wall_I(friction, mu_w, I0: float) -> float:
    """The largest wall inertial number (I0's convention) of the wall frictions ``mu_w``: eq. (2.1) inverted, infinite
    at or above mu_d (the law's asymptote: no finite I reaches it)."""
    mu = np.asarray(mu_w, dtype=float)
    mu = mu[np.isfinite(mu)]
    if not len(mu):
        return np.nan
    below = mu < friction.mu_d
    return float(np.max(friction.I_of_mu(mu[below], I0))) if below.all() else np.inf


def extrapolated(I_wall: float, calibrated: tuple[float, float]) -> str:
    """Why a model's steady rows are not scored, or "": its steady wall inertial number ``I_wall`` (DEM convention,
    the profile's largest) lies beyond the largest I the calibration measured, so the prediction rests on the fitted
    law outside its data (an unknown ``calibrated`` range is not checked)."""
    if not I_wall > calibrated[1]:
        return ""
    return (f"not scored: extrapolated: the model's wall inertial number I = {I_wall:.3g} (DEM convention) lies "
            f"beyond the calibration's largest, {calibrated[1]:.3g}")


def beyond_calibration(material, mu_w, calibrated: tuple[float, float]) -> str:
    """``extrapolated``'s note for the wall frictions ``mu_w`` under ``material``'s calibrated mu(I) (its I0 in the
    DEM convention), or ""."""
    return extrapolated(wall_I(material.friction, mu_w, convert_I(material.I0, material.I_convention, "dem")),
                        calibrated)


def scene_checks(a: DriveAnalysis) -> list[dict]:
    """The scene's own quality figures, each with its error, target and verdict: the slip of the grains
    touching the plate, the bulk coarse-grained shear stress against the plate's <tau_w>
    (compare.analysis.bulk_tau), the pressure slope against phi rho_p g."""
    whole = a.mean_profile[bulk(a.mean_profile, a.spec.depth)]
    fit = stats.linregress(whole.depth, whole.p)
    bt, sl = a.bulk_tau, a.slip
    phi = float(whole.phi.mean())  # hydrostatics: the weight of the grains over the same depths
    pressure = fit.slope / phi
    within = critical(len(whole) - 2) * fit.stderr / phi  # the slope's 95 % half-width (least squares: n - 2 dof)
    return [
        {"drive": a.label, "check": "slip at the plate", "unit": "1", "value": sl["value"], "err": sl["stderr"],
         "how": sl["method"], "target": f"<= {SLIP_MAX:.0%}",
         "verdict": "grips" if sl["value"] <= SLIP_MAX else "slips"},
        {"drive": a.label, "check": "bulk CG tau - plate <tau_w>", "unit": "rho_p g d", "value": bt["difference"],
         "err": bt["difference_stderr"], "how": bt["cg"]["method"], "target": "0",
         "verdict": "within error" if bt["agree"] else "off"},
        {"drive": a.label, "check": "pressure slope / (mean phi rho_p g)", "unit": "1", "value": pressure,
         "err": fit.stderr / phi, "how": "least squares over the bulk of the whole run's mean profile (depths "
         "correlated: a lower bound; passes within 10 %)", "target": "1",
         "verdict": "within error" if abs(pressure - 1) <= max(within, PRESSURE_TOLERANCE) else "off"},
    ]


def dem_observables(a: DriveAnalysis, delta_s: float) -> dict[str, Measured]:
    """The DEM's value and error of every observable of drive ``a`` (its steady window: ``a.samples``)."""
    resp = a.response
    st = a.steady[resp]
    out = {f"{resp}_inf": Measured(st["value"], st["stderr"], st["method"], st["dof"])}
    samples, how = a.samples, a.samples_how
    out["delta_u"] = _mean_err([depth_at_fraction(s.depth.to_numpy(), s.u_x.to_numpy(), s.u_x.iloc[0])
                                for s in samples], how)
    out["creep_length"] = dem_creep(a, delta_s)
    if len(a.plates) >= 2:
        out["t90"] = _mean_err([t90(p.t, getattr(p, resp)) for p in a.plates], f"spread over {len(a.plates)} seeds")
    else:
        t = a.series.t.to_numpy()
        out["t90"] = Measured(t90(t, a.series[resp]), 0.5 * T90_WINDOW * (t[-1] - t[0]),
                              "half-width of the running mean (1 seed: a resolution, not a statistical error; "
                              "infinite dof)", np.inf)
    return out


def model_observables(pred_steady: Steady, series: pd.DataFrame | None, a: DriveAnalysis,
                      delta_s: float) -> dict[str, float]:
    """The same estimators on a model's steady state and (if given) its series on the DEM's times."""
    resp = a.response
    out = {f"{resp}_inf": getattr(pred_steady, resp), "delta_u": pred_steady.delta_u,
           "creep_length": creep_length(pred_steady.y, pred_steady.u, delta_s, a.spec.depth)}
    if series is not None:
        t = a.series.t.to_numpy()
        out["t90"] = t90(t, np.interp(t, series.t, series[resp]))
    return out


def _linearised(sens: Sensitivity, a: DriveAnalysis, central_series: pd.DataFrame) -> tuple[float, pd.DataFrame]:
    """Linearised propagation J C J^T of the calibration through the free response (the drive's response on the
    DEM's output times) and its t90: the standard deviation of t90 and the 95 % band (t, lo, hi)."""
    t = a.series.t.to_numpy()

    def response(pred):
        return np.interp(t, pred.series.t, pred.series[a.response])

    central = np.interp(t, central_series.t, central_series[a.response])
    sd = sens.series_sd(lambda j: response(sens.shifted[j]), central)
    band = pd.DataFrame({"t": t, "lo": central - Z95 * sd, "hi": central + Z95 * sd})
    t90_sd = sens.sd_of(lambda j: t90(t, response(sens.shifted[j])), t90(t, central))
    return t90_sd, band


@dataclass(frozen=True, eq=False)
class Scorecard:
    rows: pd.DataFrame      # drive, observable, unit, dem, dem_err, dem_how, model, predicted, band, sigma, verdict
    scene: pd.DataFrame     # drive, check, unit, value, err, how, target, verdict
    replicates: int         # calibration samples pushed through each steady prediction
    edge_stability: float   # largest relative change of a band edge from half to all replicates
    bands: dict             # (drive, model) -> DataFrame t, lo, hi: 95 % band of the free response

    @classmethod
    def of(cls, rows: pd.DataFrame, scene: list[dict], replicates: int, edge_stability: float,
           bands: dict) -> Scorecard:
        return cls(rows, pd.DataFrame(scene), replicates, edge_stability, bands)


def _final_quarter(series: pd.DataFrame, a: DriveAnalysis) -> float:
    """The model's free response averaged like the DEM's steady value: over the record's final quarter
    (compare.plate.STEADY_LAST), on the DEM's output times: is the model itself steady by then?"""
    t = a.series.t.to_numpy()
    last = t >= t[0] + STEADY_LAST * (t[-1] - t[0])
    return float(np.mean(np.interp(t[last], series.t, series[a.response])))


def _final_quarter_band(band: pd.DataFrame) -> tuple[float, float]:
    """The linearised 95 % band of the free response (t, lo, hi on the DEM's output times) averaged over the
    record's final quarter, as ``_final_quarter`` averages the response."""
    t = band.t.to_numpy()
    last = t >= t[0] + STEADY_LAST * (t[-1] - t[0])
    return float(band.lo[last].mean()), float(band.hi[last].mean())


def _t90_numerical(series: pd.DataFrame, a: DriveAnalysis) -> float:
    """Interpolation error of a model's t90: the change when every other output time is dropped."""
    t = a.series.t.to_numpy()
    coarse = series.iloc[::2]
    return abs(t90(t, np.interp(t, series.t, series[a.response])) - t90(t, np.interp(t, coarse.t, coarse[a.response])))


def _not_scored(obs: str, model: SceneModel, base: str, end_value: float, steady_value: float) -> str:
    """Why a row is not scored, or "" (see the module's docstring)."""
    if base and (obs in LAYER_OBSERVABLES or model.half_space):
        return "not scored: " + base + (" (the model's bed is a half-space)" if model.half_space else "")
    if obs in TRANSIENT_OBSERVABLES and not model.transient_calibrated:
        return (f"not predicted: {model.key}'s time scale is assumed (t0 one local inertial time), not calibrated, "
                "so its transient is no prediction")
    if obs not in STEADY_OBSERVABLES:
        return ""
    if steady_value == 0:  # the model's steady state is at rest (no flow): steady once its response is at rest too
        if end_value != 0:
            return ("not scored: over the DEM's final quarter the model still moves while its steady state is at "
                    "rest (the record is shorter than the model's time scale)")
        return ""
    change = end_value / steady_value - 1
    if not abs(change) <= MODEL_UNSTEADY:
        return (f"not scored: over the DEM's final quarter the model is still {change:+.0%} from its steady value "
                "(the record is shorter than the model's time scale)")
    return ""


def _unmeasurable(measured: Measured, lo: float, hi: float, combined: float) -> str:
    """Why a row's sigma cannot be formed, or "": no DEM error, no band, or no error at all."""
    if not np.isfinite(measured.err):
        return f"not measurable: no DEM error ({measured.how} gives none)"
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return "not scored: no calibration replicate sustains this drive, so the prediction has no band"
    if not (np.isfinite(combined) and combined > 0):
        return "not scored: the DEM's error, the band and the numerical error are all zero, so sigma is undefined"
    return ""


def score(a: DriveAnalysis, models, predictions: dict, spreads: dict, n_replicates: int, fitted_on: dict | None = None,
          independent: bool = True, beyond: dict | None = None):
    """Drive ``a``'s scorecard rows, the band edges' stability (largest relative change from half to all
    replicates) and the free responses' 95 % bands per model (linearised).  Estimation only, no solve:
    ``predictions[key]`` is a model's central Prediction, ``spreads[key]`` its steady states at the calibration's
    replicates that sustain the drive and its Sensitivity (compare.comparison's model side); ``n_replicates`` the
    replicates there were; ``fitted_on[key]``: the drive a model's own parameter was fitted on (its rows there are
    not blind); ``independent``: mu(I) comes from an independent calibration (else no row is blind); ``beyond[key]``:
    why a model's steady rows extrapolate the calibration (``extrapolated``), or ""."""
    fitted_on, beyond = fitted_on or {}, beyond or {}
    rows, edges, bands = [], [], {}
    half = n_replicates // 2
    delta_s = next(iter(predictions.values())).steady.delta_s
    dem = dem_observables(a, delta_s)
    base, shallow = base_reach(a, delta_s), short_bed(a, delta_s)
    scene = slipping(a) or (f"not scored: {shallow}" if shallow else "")
    for model in models:
        pred: Prediction | None = predictions.get(model.key)
        if pred is None:
            continue
        steadies, sens = spreads[model.key]
        central = model_observables(pred.steady, pred.series, a, delta_s)
        samples = [model_observables(st, None, a, delta_s) for st in steadies]
        end_value = _final_quarter(pred.series, a)
        t90_sd, bands[(a.label, model.key)] = _linearised(sens, a, pred.series)
        for obs, measured in dem.items():
            value = central.get(obs)
            if value is None or not np.isfinite(value) or not np.isfinite(measured.value):
                continue
            asymptote = value
            windowed = obs == f"{a.response}_inf"  # like with like: the model over the DEM's steady window
            numerical = 0.0
            if windowed:
                value = end_value
                lo, hi = _final_quarter_band(bands[(a.label, model.key)])
                lo, hi = min(lo, value), max(hi, value)
            elif obs == "t90":
                lo, hi, numerical = value - Z95 * t90_sd, value + Z95 * t90_sd, _t90_numerical(pred.series, a)
            else:
                sampled = np.array([x[obs] for x in samples], dtype=float)
                sampled = sampled[np.isfinite(sampled)]
                lo = hi = np.nan
                if len(sampled):
                    lo, hi = np.percentile(sampled, [2.5, 97.5])
                    lo, hi = min(lo, value), max(hi, value)
                if half >= 2 and len(sampled) > half and abs(hi - lo) > 0:
                    lo2, hi2 = np.percentile(sampled[:half], [2.5, 97.5])
                    edges.append(max(abs(lo2 - lo), abs(hi2 - hi)) / abs(hi - lo))
            band_sd = (hi - lo) / (2 * Z95)
            combined = np.sqrt(measured.err**2 + band_sd**2 + numerical**2)
            note = (scene
                    or (beyond.get(model.key, "") if obs in STEADY_OBSERVABLES else "")
                    or (_not_scored(obs, model, base, end_value, central[f"{a.response}_inf"])
                        if not windowed else _not_scored("", model, base, end_value, asymptote))
                    or _unmeasurable(measured, lo, hi, combined))
            rows.append(score_row(
                drive=a.label, observable=obs, unit=OBSERVABLES[obs][0], dem=measured.value, dem_err=measured.err,
                dem_how=measured.how, model=model.key, model_label=model.label, predicted=value,
                band=[float(lo), float(hi)], numerical_err=numerical, calibration_sd=float(band_sd),
                sigma=sigma(measured.value - value, measured.err, band_sd, numerical),
                dof=effective_dof((measured.err, band_sd, numerical), (measured.dof, np.inf, np.inf)), note=note,
                blind=independent and fitted_on.get(model.key) != a.label,
                asymptote=asymptote if windowed else np.nan,
                initial_state=initial_state(pred.initial) if obs in TRANSIENT_OBSERVABLES else ""))
    return pd.DataFrame(rows), float(np.max(edges)) if edges else np.nan, bands


def headline(rows: pd.DataFrame, blind: bool, failure: str, n_drives: int) -> str:
    """The comparison's verdict in one sentence, written from the numbers."""
    if failure:
        return f"No verdict: the mu(I) calibration failed ({failure}), so no prediction was made or scored."
    if not blind:
        return ("No verdict: mu(I) was fitted on the drives themselves, so the rows restate the fit and none counts "
                "as support for a model; pass an independent calibration (--calibration) for a test.")
    t = tally(rows)
    skipped = int((~rows.scored).sum()) if len(rows) else 0
    aside = f"; {skipped} row(s) not scored (the scene cannot support them: see each row's note)" if skipped else ""
    if t.empty:
        return f"No verdict: no blind row is shared by the models over {n_drives} drive(s){aside}."
    unranked = sorted(set(rows.model_label) - set(t.label))
    if unranked:
        aside += f"; not ranked (no scored blind row shared with the others): {', '.join(unranked)}"
    parts = ", ".join(f"{r.label} consistent on {r.consistent} of {r.n} (median |sigma| {r.median_abs_sigma:.1f})"
                      for r in t.itertuples())
    best = t.iloc[0]
    if len(t) == 1:
        return (f"Blind test over {n_drives} drive(s), one model scored: {parts}; no ranking, since no other model "
                f"has a scored row{aside}.")
    # the ranking is the count of consistent rows; the median |sigma| describes, it does not separate
    tied = t[t.share == best.share]
    ranking = ("no model is consistent on most of them" if best.share < 0.5 else
               f"the DEM does not separate {', '.join(tied.label)} (each consistent on {best.consistent} of "
               f"{int(best.n)})" if len(tied) > 1 else
               f"the DEM supports {best.label} best")
    return (f"Blind test on the {int(best.n)} row(s) the models share over {n_drives} drive(s): {parts}; "
            f"{ranking}{aside}.")
