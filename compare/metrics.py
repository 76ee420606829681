"""The comparison's numbers (metrics.json), defined once.  DEM units; I0 in the named convention."""
from __future__ import annotations

import numpy as np
import pandas as pd
from scipy import stats

from continuum.scales import UNITS

from .calibrate import WALL_EXCLUSION
from .analysis import TRANSITS_BEFORE_COMPARISON
from .comparison import Comparison, DriveComparison, early_exponents
from .plate import (BLOCK_TAUS, MIN_SEEDS_SPREAD, SLIP_FROM, STEADY_CHANGE, STEADY_WINDOW, STEADY_WINDOW_LATEST,
                    block_estimate)

DEFINITIONS = {
    "steady": f"running mean over {STEADY_WINDOW:.0%} of the record within max(3 stderr, "
              f"{STEADY_CHANGE:.0%} of the total change) of the final-quarter mean",
    "delta_u": "depth below the plate where the coarse-grained u falls to 5 % of u_w (DEM and continuum alike): "
               "the layer thickness used in the metrics.  delta_mu, the paper's definition ((mu - mu_s) at 1e-3 of "
               "the wall excess, calibrated mu_s), is reported beside it but is bound by single-frame noise in mu",
    "t90": "time for the running mean (5 % of the record) of u_w (imposed stress) or mu_w (imposed speed) "
           "to cover 90 % of its change; the continuum series are treated alike",
    "wall_exclusion": f"calibration and bulk averages exclude {WALL_EXCLUSION:g} d next to plate and base",
    "pressure_slope": "dp/d(depth) in rho_p g over the bulk, from the whole run's mean profile (the y momentum "
                      "balance needs no steady state; a long average beats the force-chain noise)",
    "creep": "u/u_w of the DEM's steady profile at the continuum's delta_s, and the e-folding length of u below it",
    "alpha": "exponents of u_w ~ t^alpha and delta_u ~ t^alpha by least squares on log-log from the first output to "
             "half the final value; alpha_fits gives the 95 % interval and the number of points (few points: "
             "the DEM layer is established within a few frames, and the exponent is then undetermined)",
    "errors": f"every DEM value's *_stderr is one standard error; *_method says how: the spread over the seeds "
              f"(>= {MIN_SEEDS_SPREAD} seeds), else blocks of >= {BLOCK_TAUS:g} integrated autocorrelation times "
              "within each run (Sokal's window), combined over the seeds",
    "mu_w": "friction of a window = <tau_w>/<p> (ratio of means; plate.csv samples average every step of their "
            "interval)",
    "slip": f"1 - <u_x of the bed grains touching a plate grain>/<plate u_x> over the final {1 - SLIP_FROM:.0%} of "
            "the drive (grain-weighted over every step)",
    "tau_bulk": "coarse-grained tau = -sigma_xy (contact + kinetic) averaged over the bulk in each frame of the "
                f"final {1 - STEADY_WINDOW_LATEST:.0%} of the drive, against the plate's <tau_w> over the same window",
    "elastic_start": f"transit_time = depth/c_s of the shear wave through the deposited bed (run.json); "
                     f"the early exponents (alpha) are fitted from {TRANSITS_BEFORE_COMPARISON:g} transits on",
    "units": UNITS["dem_units"],
    "inertial_number": UNITS["inertial_number"],
}


def t90(t, y) -> float:
    """First time the running mean (5 % of the record) has covered 90 % of the change from the
    first to the final-tenth value (the running mean keeps DEM noise from triggering it)."""
    y = pd.Series(np.asarray(y, dtype=float)).interpolate(limit_direction="both")
    t = np.asarray(t, dtype=float)
    smooth = y.rolling(max(1, len(y) // 20), center=True, min_periods=1).mean().to_numpy()
    start, final = smooth[0], np.mean(smooth[-max(1, len(smooth) // 10):])
    reached = np.abs(smooth - start) >= 0.9 * abs(final - start)
    return float(t[np.argmax(reached)]) if reached.any() else np.nan


def drive_metrics(dc: DriveComparison) -> dict:
    """One drive's numbers: the DEM's own (always) and the comparison with the continuum (when the
    calibrated mu(I) admits a prediction; otherwise ``prediction`` says why not)."""
    g, spec = dc.dem, dc.dem.spec
    whole = g.mean_profile
    bulk = (whole.depth > WALL_EXCLUSION) & (whole.depth < spec.depth - WALL_EXCLUSION)
    slope = stats.linregress(whole.depth[bulk], whole.p[bulk])
    p = g.steady_profile
    inside = (p.depth > WALL_EXCLUSION) & (p.depth < spec.depth - WALL_EXCLUSION)
    tau_plate = g.steady["mu_w"]["value"] * spec.p_w if spec.kind == "speed" else spec.value
    steady_delta = g.delta.delta_u[g.delta.t >= STEADY_WINDOW_LATEST * g.delta.t.max()].dropna()
    delta_est = block_estimate({"d": steady_delta.to_numpy()}) if len(steady_delta) > 1 else {}
    response = g.response
    expo = early_exponents(g)
    out = {
        "kind": spec.kind, "imposed": spec.value, "p_w": spec.p_w, "seeds": len(spec.folders),
        "grains_x_steps": spec.cost,
        "pressure_slope": slope.slope, "pressure_slope_stderr": slope.stderr,
        "pressure_slope_method": "least squares over the depths of the whole run's mean profile (neighbouring "
                                 "depths are correlated by the kernel: indicative)",
        "u_w_inf": {"dem": g.steady["u_w"]["value"], "dem_stderr": g.steady["u_w"]["stderr"],
                    "dem_method": g.steady["u_w"]["method"]},
        "mu_w_inf": {"dem": g.steady["mu_w"]["value"], "dem_stderr": g.steady["mu_w"]["stderr"],
                     "dem_method": g.steady["mu_w"]["method"]},
        "delta_s": {"dem": delta_est.get("value", np.nan), "dem_stderr": delta_est.get("stderr", np.nan),
                    "dem_method": delta_est.get("method", "") + " (seed-averaged frames)"},
        "slip": g.slip["value"], "slip_err": g.slip["stderr"], "slip_method": g.slip["method"],
        "slip_per_seed": g.slip["per_seed"],
        "tau_bulk": {"cg": g.bulk_tau["cg"]["value"], "cg_stderr": g.bulk_tau["cg"]["stderr"],
                     "plate": g.bulk_tau["plate"]["value"], "plate_stderr": g.bulk_tau["plate"]["stderr"],
                     "difference": g.bulk_tau["difference"], "difference_stderr": g.bulk_tau["difference_stderr"],
                     "agree": g.bulk_tau["agree"], "window": g.bulk_tau["window"], "frames": g.bulk_tau["frames"],
                     "method": g.bulk_tau["cg"]["method"]},
        "elastic_start": {"transit_time": spec.transit_time, "compared_from": spec.compared_from},
        "t90": {"dem": t90(g.series.t, g.series[response])},
        "alpha_u": expo.get("alpha_u", {}).get("alpha", np.nan),
        "alpha_delta": expo.get("alpha_delta", {}).get("alpha", np.nan),
        "alpha_fits": {k: {"ci95": v["ci95"], "n": v["n"]} for k, v in expo.items()},
        "prediction": dc.note or "velocity form and paper's model from the calibration",
    }
    if not dc.predictions:
        return out
    vel, paper = dc.predictions
    delta_s = vel.steady["delta_s"]
    layer = inside & (p.depth < min(delta_s, spec.depth - WALL_EXCLUSION))
    below = inside & (p.depth >= delta_s) & (p.u_x > 0)
    u_w = g.steady["u_w"]["value"]
    for name, key in (("u_w_inf", "u_w"), ("mu_w_inf", "mu_w")):
        out[name].update({"velocity_form": vel.series[key].iloc[-1], "paper": paper.steady[key]})
    out["delta_s"].update({"velocity_form": vel.series.delta_u.iloc[-1], "paper": paper.series.delta_u.iloc[-1],
                           "paper_delta_s": delta_s})
    out["t90"].update({"velocity_form": t90(vel.series.t, vel.series[response]),
                       "paper": t90(paper.series.t, paper.series[response])})
    out["t90"]["ratio_dem_to_velocity_form"] = out["t90"]["dem"] / out["t90"]["velocity_form"]
    out["rel_error_response"] = float(vel.series[response].iloc[-1] / g.steady[response]["value"] - 1)
    out["tau_uniformity"] = float(np.nanmax(np.abs(p.tau[layer] - tau_plate)) / tau_plate) if layer.any() else np.nan
    out["creep_at_delta_s"] = (float(np.interp(delta_s, p.depth[::-1], p.u_x[::-1]) / u_w)
                               if delta_s < spec.depth else np.nan)
    out["creep_length"] = (float(-1 / stats.linregress(p.depth[below], np.log(p.u_x[below])).slope)
                           if below.sum() >= 3 else np.nan)
    return out


def _clean(v):
    """JSON-ready: numpy scalars to float, non-finite numbers to None (valid JSON, pandas-readable)."""
    if isinstance(v, dict):
        return {k: _clean(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_clean(x) for x in v]
    if isinstance(v, (float, np.floating, int, np.integer)) and not isinstance(v, bool):
        return float(v) if np.isfinite(v) else None
    return v


def metrics(c: Comparison) -> dict:
    """metrics.json: the issue's keys at the top level (taken from the first imposed-stress drive
    where a key is per drive) and every drive's numbers under ``drives``."""
    cal = c.calibration
    per = {dc.label: drive_metrics(dc) for dc in c.drives}
    predicted = [dc for dc in c.drives if dc.predictions]
    main = next((per[dc.label] for dc in predicted if dc.dem.spec.kind == "stress"),
                per[(predicted or list(c.drives))[0].label])
    return _clean({
        "phi_bulk": c.phi_bulk,
        "pressure_slope": main.get("pressure_slope"),
        "tau_uniformity": main.get("tau_uniformity"),
        "mass_error": c.mass_error,
        "mu_s": cal.mu_s, "mu_d": cal.mu_d, "I0": cal.I0_dem, "I0_convention": "dem", "I0_paper": cal.I0_paper,
        "calibration": cal.as_dict(),
        "u_w_inf": main["u_w_inf"], "delta_s": main.get("delta_s"),
        "alpha_delta": main.get("alpha_delta"), "alpha_u": main.get("alpha_u"),
        "alpha_fits": main.get("alpha_fits"),
        "drives": per, "definitions": DEFINITIONS, "runs": [str(r) for r in c.runs],
        "frames_analysed": int(sum(len(dc.dem.profiles[0].results.steps) for dc in c.drives)),
    })
