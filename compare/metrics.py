"""metrics.json: the comparison's numbers, each defined once (DEFINITIONS, with its unit), rendered
from a compare.comparison.Comparison.  DEM units; I0 in the named convention."""
from __future__ import annotations

import numpy as np
from granstokes.continuum.scales import UNITS
from scipy import stats

from .analysis import BLOCKS
from .calibrate import WALL_EXCLUSION
from .comparison import Comparison, DriveComparison, early_exponents
from .drive import TRANSITS_BEFORE_COMPARISON
from .laws import BOOTSTRAP_FEW_SEEDS, SEED_RESAMPLES
from .plate import BLOCK_TAUS, MIN_SEEDS_SPREAD, SLIP_FROM, STEADY_WINDOW, TREND_SIGMA
from .rows import Z95, critical
from .scorecard import CREEP_WINDOW, OBSERVABLES, T90_WINDOW, bulk, creep_length

#: name -> (unit, definition)
DEFINITIONS = {
    "steady": ("-", f"the final quarter has no trend (slope through block means, blocks longer than the "
                    "correlation time, within the t quantile (blocks - 2 degrees of freedom) of a "
                    f"{TREND_SIGMA:g} sigma normal deviation), and the record is steady from the "
                    f"earliest start (in steps of {STEADY_WINDOW:.0%} of the record) after which it has no trend "
                    f"and the mean of the first quarter of the rest is within {TREND_SIGMA:g} errors of the final "
                    "value; the prepared state at t = 0 is in no window"),
    "u_w_inf": (OBSERVABLES["u_w_inf"][0], "steady plate speed: mean over the final quarter of the record"),
    "mu_w_inf": (OBSERVABLES["mu_w_inf"][0], "steady plate friction: final-quarter mean of tau_w/p"),
    "delta_u": ("d", "depth below the plate's contact plane where the steady-window coarse-grained u falls to 5 % "
                     "of u_w (DEM and continuum alike). The paper's definition ((mu - mu_s) at 1e-3 of the "
                     "wall excess) is not measured: single-frame noise in mu exceeds its threshold"),
    "t90": ("sqrt(d/g)", f"time for the running mean ({T90_WINDOW:.0%} of the record) of the free response (u_w under "
                         "an imposed stress, mu_w under an imposed speed) to cover 90 % of its change; the continuum "
                         "series are interpolated onto the DEM's output times and treated alike"),
    "creep_length": ("d", "e-folding length of u below the calibrated delta_s, from a least-squares fit of ln u "
                          f"over the first {CREEP_WINDOW:g} d below it (never within {WALL_EXCLUSION:g} d of the "
                          "base); local mu(I) is rigid there (0)"),
    "sigma": ("1", "(DEM - predicted) / sqrt(dem_err^2 + calibration_sd^2 + numerical_err^2), calibration_sd = "
                   "band width / 3.92; 'consistent' when |sigma| <= t_0.975(dof), Student-t's 97.5 % quantile at the "
                   f"row's dof ({Z95:.3g} at infinite dof, {critical(3):.3g} at 3, {critical(2):.3g} at 2)"),
    "dof": ("1", "degrees of freedom of a row's combined error (Welch-Satterthwaite): the DEM error's (seeds - 1, "
                 "blocks - 1, or infinite for a resolution) with the band's and the numerical error's infinite; "
                 "the threshold of the row's verdict is t_0.975(dof); in metrics.json an infinite dof is null (JSON "
                 "has no infinity; a scored row's dof is never undefined)"),
    "scored": ("-", "False where the scene cannot support the row (the flow reaches the base: the layer rows, and "
                    "every row of the half-space model; a model not steady within the record: its steady rows); "
                    "'note' says why. Only scored rows with blind = true count for a model"),
    "tally": ("-", "per model, over the scored blind rows every model has (same drive and observable): rows, "
                   "consistent rows, share, median |sigma|; the verdict ranks models by share, then median |sigma|"),
    "predicted": ("unit of the row", "the model's value compared with the DEM's: for the steady plate value "
                                     "(u_w_inf under a stress, mu_w_inf under a speed) the model's response averaged "
                                     "over the DEM's window (the record's final quarter: like with like), else its "
                                     "steady value"),
    "asymptote": ("unit of the row", "the model's steady plate value (t -> infinity), beside 'predicted' on the "
                                     "plate rows: equal when the model is steady within the record"),
    "band": ("unit of the row", "95 % band of the prediction from the calibration's uncertainty (compare.scorecard)"),
    "dem_err": ("unit of the row", f"standard error of the DEM value: spread over seeds (>= 2 seeds), else over "
                                   f"{BLOCKS} blocks of the steady window, or the estimator's resolution; dem_how "
                                   "says"),
    "errors": ("-", f"the steady plate values' errors: the spread over the seeds (>= {MIN_SEEDS_SPREAD} seeds), else "
                    f"blocks of >= {BLOCK_TAUS:g} integrated autocorrelation times within each run (Sokal's window), "
                    "combined over the seeds; every *_err says how (*_how, *_method)"),
    "mu_w": ("1", "friction of a window = <tau_w>/<p> (ratio of means; plate.csv rows average their interval, "
                  "sampled every half contact time)"),
    "slip": ("1", f"1 - <u_x of the bed grains touching a plate grain>/<plate u_x> over the final {1 - SLIP_FROM:.0%} "
                  "of the drive (grain-weighted over the samples)"),
    "tau_bulk": ("rho_p g d", "coarse-grained tau = -sigma_xy (contact + kinetic) averaged over the bulk in each frame "
                              "of the final 30 % of the drive, against the plate's <tau_w> over the same window"),
    "elastic_start": ("sqrt(d/g)", "transit_time = depth/c_s of the shear wave through the bed, c_s measured in the "
                                   "calibration's packing (its elasticity; without one the contacts' d sqrt(k_t/m), "
                                   "run.json); "
                                   f"transients (the early exponents alpha) are compared from "
                                   f"{TRANSITS_BEFORE_COMPARISON:g} transits on"),
    "duration": ("sqrt(d/g)", "the DEM record's length (its last whole frame)"),
    "delta_s": ("d", "the paper's steady layer depth beta_w p_w/(phi rho_p g) with the calibrated material"),
    "t_s": ("sqrt(d/g)", "the paper's time scale delta_s^2/nu_g with the calibrated material"),
    "pressure_slope": ("rho_p g", "dp/d(depth) over the bulk, from the whole run's mean profile"),
    "creep_at_delta_s": ("1", "u/u_w of the DEM's steady profile at the calibrated delta_s"),
    "phi_bulk": ("1", f"mean solid fraction of the steady windows, {WALL_EXCLUSION:g} d away from plate and base "
                      "(area fraction in 2D)"),
    "mass_error": ("1", "relative error of the integral of the coarse-grained phi against the grains' volume per area"),
    "alpha": ("1", "exponents of u_w ~ t^alpha and delta_u ~ t^alpha by least squares on log-log from the first "
                   "output to half the final value, with their 95 % interval and number of points"),
    "wall_exclusion": ("d", f"calibration and bulk averages exclude {WALL_EXCLUSION:g} d next to plate and base"),
    "laws": ("-", "the paper's predictions, one row per law x model (compare/laws.py): the same estimator on the DEM's "
                  "seed-mean series and on the model's output over the same window; dem_err the spread over "
                  f"{SEED_RESAMPLES} bootstrap resamples of each drive's seeds (times sqrt(n/(n - 1)) below "
                  f"{BOOTSTRAP_FEW_SEEDS} seeds; dof n - 1, a fit across drives n_drives - 2); band predicted "
                  "-+ 1.96 s_cal, s_cal "
                  "the calibration's replicates propagated linearly (the law re-estimated on predictions re-solved "
                  "with each parameter shifted); sigma = (dem - predicted) / sqrt(dem_err^2 + s_cal^2); "
                  "'not measurable' or 'not predicted' with the reason where the data cannot decide; choices: the law "
                  "over its estimator family (compare/families.py), systematic: half their range of dem - predicted, "
                  "verdict 'depends on the estimator' where consistent and disagreeing choices meet"),
    "units": ("-", UNITS["dem_units"]),
    "inertial_number": ("-", UNITS["inertial_number"]),
}


def drive_metrics(dc: DriveComparison) -> dict:
    """One drive's own numbers (each with its error where it has one) and the central predictions."""
    g, spec = dc.dem, dc.dem.spec
    whole = g.mean_profile[bulk(g.mean_profile, spec.depth)]
    slope = stats.linregress(whole.depth, whole.p)
    expo = early_exponents(g)
    out = {
        "kind": spec.kind, "imposed": spec.load.value, "imposed_unit": "tau_w [rho_p g d]" if spec.kind == "stress"
        else "u_w [sqrt(g d)]", "p_w": spec.p_w, "depth": spec.depth, "seeds": spec.seeds,
        "duration": g.t_end, "delta_s": dc.scales.delta_s if dc.scales is not None else None,
        "t_s": dc.scales.t_s if dc.scales is not None else None,
        "grains_x_steps": spec.cost, "t_steady": g.steady["t_steady"], "t_window": g.t_window,
        "pressure_slope": slope.slope, "pressure_slope_err": slope.stderr,
        "u_w_inf": {"dem": g.steady["u_w"]["value"], "dem_err": g.steady["u_w"]["stderr"],
                    "dem_dof": g.steady["u_w"]["dof"], "dem_how": g.steady["u_w"]["method"]},
        "mu_w_inf": {"dem": g.steady["mu_w"]["value"], "dem_err": g.steady["mu_w"]["stderr"],
                     "dem_dof": g.steady["mu_w"]["dof"], "dem_how": g.steady["mu_w"]["method"]},
        "slip": g.slip["value"], "slip_err": g.slip["stderr"], "slip_how": g.slip["method"],
        "slip_per_seed": g.slip["per_seed"],
        "tau_bulk": {"cg": g.bulk_tau["cg"]["value"], "cg_err": g.bulk_tau["cg"]["stderr"],
                     "plate": g.bulk_tau["plate"]["value"], "plate_err": g.bulk_tau["plate"]["stderr"],
                     "difference": g.bulk_tau["difference"], "difference_err": g.bulk_tau["difference_stderr"],
                     "agree": g.bulk_tau["agree"], "window": g.bulk_tau["window"], "frames": g.bulk_tau["frames"],
                     "how": g.bulk_tau["cg"]["method"]},
        "elastic_start": {"transit_time": spec.transit_time, "compared_from": spec.compared_from},
        "alpha": {k: {"value": v["alpha"], "ci95": v["ci95"], "n": v["n"]} for k, v in expo.items()},
        "frames": g.frames, "dropped_frames": g.dropped_frames,
        "prediction": dc.note or "predicted from the calibration",
        "base_confined": bool(dc.base), "base_note": dc.base,
    }
    for p in dc.predictions:
        out[f"steady_{p.model}"] = {"u_w": p.steady.u_w, "mu_w": p.steady.mu_w, "delta_s": p.steady.delta_s,
                                    "delta_u": p.steady.delta_u}
    if dc.predictions:
        delta_s = dc.predictions[0].steady.delta_s
        p = g.steady_profile
        out["creep_at_delta_s"] = (float(np.interp(delta_s, p.depth[::-1], p.u_x[::-1]) / g.steady["u_w"]["value"])
                                   if delta_s < spec.depth else np.nan)
        out["creep_length_window_mean"] = creep_length(p.depth, p.u_x, delta_s, spec.depth)
    return out


def metrics(c: Comparison) -> dict:
    """The Stokes drives' entries of metrics.json beyond the shared ones (compare.experiment): scene checks,
    uncertainty, calibration and its test, the NGF fit, per-drive numbers."""
    cal = c.calibration
    rows = c.scorecard.rows
    short = {label: sorted(g.model.unique()) for label, g in rows[rows.note.str.contains("record is shorter")]
             .groupby("drive")} if len(rows) else {}
    drives = {dc.label: {**drive_metrics(dc), "record_short_for": short.get(dc.label, [])} for dc in c.drives}
    return {
        "calibration_failure": c.failure,
        "scene_checks": c.scorecard.scene.to_dict("records"),
        "uncertainty": {"replicates": c.scorecard.replicates, "band_edge_stability": c.scorecard.edge_stability},
        "calibration": {**cal.as_dict(), "source": c.calibration_source},
        "blind": c.blind, "calibration_test": c.law_test,
        "mu_s": cal.mu_s, "mu_d": cal.mu_d, "I0": cal.I0_dem, "I0_convention": "dem", "I0_paper": cal.I0_paper,
        "phi_bulk": c.phi_bulk, "mass_error": c.mass_error,
        "ngf": None if c.fluidity is None else {"A": c.fluidity.A, "A_err": c.fluidity.err, "ci95": c.fluidity.ci95,
                                                "fitted_on": c.fluidity.drive, "how": c.fluidity.how,
                                                "points": c.fluidity.points, "at_search_bound": c.fluidity.at_bound},
        "drives": drives,
    }


#: the fields that name a row of each section of metrics.json (the rest are its numbers and words)
ROW_IDENTITY = {"scorecard": ("drive", "observable", "model"), "laws": ("law", "quantity", "kind", "amplitude",
                                                                       "model")}


#: a number that names a row (a drive's amplitude) is matched to this many significant digits (JSON writers differ)
IDENTITY_DIGITS = 9


def _identity(v):
    return float(f"{v:.{IDENTITY_DIGITS}g}") if isinstance(v, float) else v


def row_differences(committed: dict, regenerated: dict) -> dict:
    """The scorecard and law rows of two metrics.json documents, matched by ROW_IDENTITY: per section, the rows
    only one side has, the largest relative difference of a number (|a - b| / max(|a|, |b|), lists element-wise),
    and the fields whose words differ."""
    def numbers(v):
        """A field's numbers (None as NaN), or [] for words (a law's choices, dicts with words, among them)."""
        items = v if isinstance(v, list) else [v]
        if not items or any(isinstance(x, bool | str | dict) for x in items) or all(x is None for x in items):
            return []
        return [np.nan if x is None else float(x) for x in items]

    out = {}
    for section, keys in ROW_IDENTITY.items():
        index = [{tuple(_identity(r.get(k)) for k in keys): r for r in doc.get(section, [])}
                 for doc in (committed, regenerated)]
        common = index[0].keys() & index[1].keys()
        worst, words = 0.0, set()
        for key in common:
            a, b = index[0][key], index[1][key]
            for field in a.keys() | b.keys():
                x, y = a.get(field), b.get(field)
                xs, ys = numbers(x), numbers(y)
                if xs and ys and len(xs) == len(ys):
                    for p, q in zip(xs, ys):
                        if p != q and np.isfinite(p) and np.isfinite(q):
                            worst = max(worst, abs(p - q) / max(abs(p), abs(q)))
                        elif p != q and not (np.isnan(p) and np.isnan(q)):
                            worst = np.inf
                elif x != y:
                    words.add(field)
        out[section] = {"rows": len(common), "only_committed": len(index[0].keys() - common),
                        "only_regenerated": len(index[1].keys() - common), "max_relative": worst,
                        "words_differ": sorted(words)}
    return out
