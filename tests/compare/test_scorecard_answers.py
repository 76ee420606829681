"""The Stokes drives' scorecard rows (compare.scorecard.score) and the headline sentence, against answers worked out by
hand on a small synthetic drive.

The drive and the models are plain objects carrying only what ``score`` reads (no DEM run, no solve):

* DEM profiles u_x = 1 - depth/d0 down to d0, then 0.01 exp(-(depth - d0)/l): on the 0.5 d grid the 5 % crossing
  lies between two nodes of the straight part, so delta_u = 0.95 d0 exactly, and ln u is a straight line below
  delta_s, so the creep length is l exactly; the plates' response rises linearly to its plateau at t_r on 21 output
  times (too few for the running mean to smooth: T90_WINDOW x 21 < 2), so t90 = 0.9 t_r exactly;
* a model's series rises linearly to a plateau short of its steady value (its asymptote), so the windowed steady
  response is that plateau; its t90 interpolated from every other output time moves by a known amount (the ramp's
  kink falls between the coarse nodes);
* the calibration's replicates are given steady states with known delta_u and creep lengths (the band: the 2.5 and
  97.5 % percentiles, linear between order statistics, written out here), and the Sensitivity's shifted predictions
  are ramps whose plateaus and rise times are known, so the linearised sd is sqrt(g C g) with g the hand-made
  differences over the steps.

Every expected number is computed here from those closed forms with plain arithmetic (std with ddof = 1 written
out, the percentile's interpolation written out, a row's Welch-Satterthwaite degrees of freedom written out and its
threshold Student-t's 97.5 % quantile from scipy); the constants (Z95, MODEL_UNSTEADY, STEADY_LAST, T90_WINDOW,
WALL_EXCLUSION) are imported from their modules.  The notes and the headline are compared as
whole sentences: they are what the report prints.
"""
import warnings
from pathlib import Path
from types import SimpleNamespace as NS

import numpy as np
import pandas as pd
import pytest
from granstokes.compare.band import Sensitivity
from granstokes.compare.calibrate import WALL_EXCLUSION
from granstokes.compare.plate import STEADY_LAST
from granstokes.compare.rows import Z95
from granstokes.compare.scorecard import (
    MODEL_UNSTEADY,
    T90_WINDOW,
    Measured,
    _mean_err,
    _unmeasurable,
    headline,
    score,
)
from scipy import stats

T = np.arange(21.0)               # the DEM's output times
BED = 36.0                        # the bed's depth [d]: deep enough for every row (compare.scorecard.short_bed)
DEPTH = np.arange(0.0, BED + 0.25, 0.5)
DELTA_S = 7.0                     # the calibrated delta_s: the creep zone is [7, 7 + CREEP_WINDOW]
LABEL = "stress-1"
# the calibration's spread: two parameters, their steps and covariance
NAMES, STEPS = ("mu_s", "I0"), (0.005, 0.003)
COV = np.array([[0.002**2, 0.3 * 0.002 * 0.004], [0.3 * 0.002 * 0.004, 0.004**2]])
# the shifted predictions: (rise time, plateau) per parameter, around the central (9, plateau)
SHIFT_RISE, SHIFT_PLATEAU = (0.5, -0.2), (0.01, -0.005)


def _ramp(t, rise, plateau):
    return plateau * np.minimum(np.asarray(t, dtype=float) / rise, 1.0)


def _profile(d0, ell):
    """delta_u = 0.95 d0, creep length ell (module docstring)."""
    u = np.where(DEPTH <= d0, 1 - DEPTH / d0, 0.01 * np.exp(-(DEPTH - d0) / ell))
    return pd.DataFrame({"depth": DEPTH, "u_x": u})


def _drive(d0s=(5.0, 6.0, 4.0), ells=(2.4, 3.0, 2.7), rises=(8.0, 10.0, 12.0), response="u_w", steady=(0.95, 0.01),
           samples=None, steady_profile=None, label=LABEL, steady_dof=None, slip=0.01):
    assert int(T90_WINDOW * len(T)) <= 1  # the running mean of t90 is the series itself
    assert max(d0s) < DELTA_S and DELTA_S < BED - WALL_EXCLUSION  # the creep zone lies in the exponential tail
    samples = samples if samples is not None else tuple(_profile(d, e) for d, e in zip(d0s, ells))
    plates = tuple(NS(t=T, **{response: _ramp(T, r, 1.0)}) for r in rises)
    return NS(label=label, response=response, spec=NS(depth=BED),
              steady={response: {"value": steady[0], "stderr": steady[1], "dof": steady_dof or len(rises) - 1,
                                 "method": "pooled over 3 seeds"}},
              steady_profile=steady_profile if steady_profile is not None else samples[0], samples=samples,
              samples_how="spread over 3 seeds", plates=plates, slip={"value": slip},
              series=pd.DataFrame({"t": T, response: np.mean([getattr(p, response) for p in plates], axis=0)}))


def _steady(value, delta_u, ell, response="u_w"):
    """A model's steady state: u = value exp(-y/ell) (creep length ell; ell None: at rest, u = 0)."""
    u = np.zeros_like(DEPTH) if ell is None else value * np.exp(-DEPTH / ell)
    return NS(y=DEPTH, u=u, delta_s=DELTA_S, delta_u=delta_u, **{response: value})


def _model(key, half_space=False, transient_calibrated=True):
    return NS(key=key, label=f"{key} model", half_space=half_space, transient_calibrated=transient_calibrated)


REPLICATES = {"value": (0.98, 1.02, 1.0, 0.99, 1.01),   # its first two span the same 2.5-97.5 % edges: no change
              "delta_u": (6.2, 6.4, 6.1, 6.5, 6.3),     # all deeper than the central 6.0: the band widens down to it
              "ell": (2.5, 3.0, 2.7, 2.6, 2.8)}         # below the central 3.0 but for one: the band widens up to it


def _model_side(asymptote=1.0, plateau=0.98, rise=9.0, delta_u=6.0, ell=3.0, replicates=REPLICATES,
                response="u_w", series=None, shift_rise=SHIFT_RISE):
    """A model's central Prediction and its spread (replicates' steady states, Sensitivity)."""
    if series is None:
        series = pd.DataFrame({"t": T, response: _ramp(T, rise, plateau)})
    pred = NS(steady=_steady(asymptote, delta_u, ell, response), series=series, initial="rest")
    steadies = [_steady(v, d, e, response) for v, d, e in
                zip(replicates["value"], replicates["delta_u"], replicates["ell"])]
    shifted = tuple(NS(series=pd.DataFrame({"t": [0.0, rise + dr, T[-1]], response: [0.0, plateau + dp, plateau + dp]}))
                    for dr, dp in zip(shift_rise, SHIFT_PLATEAU))
    return pred, (steadies, Sensitivity(NAMES, STEPS, COV, shifted))


def _score(a, sides, n_replicates=5, models=None, **kwargs):
    """score() of drive ``a`` for ``sides`` (key -> (prediction, spread)); the models plain ones of those keys unless
    given."""
    models = models or [_model(k) for k in sides]
    preds = {k: s[0] for k, s in sides.items()}
    spreads = {k: s[1] for k, s in sides.items()}
    return score(a, models, preds, spreads, n_replicates, **kwargs)


def _by(rows, model="local"):
    return rows[rows.model == model].set_index("observable")


def _mean_and_error(values):
    """The mean and its standard error std(ddof = 1)/sqrt(n), written out."""
    v = np.asarray(values, dtype=float)
    m = v.sum() / len(v)
    return m, np.sqrt(((v - m) ** 2).sum() / (len(v) - 1)) / np.sqrt(len(v))


def _percentile(values, p):
    """numpy's default percentile written out: linear between the order statistics at p/100 (n - 1)."""
    x = sorted(values)
    pos = p / 100 * (len(x) - 1)
    i = int(pos)
    return x[i] + (pos - i) * (x[min(i + 1, len(x) - 1)] - x[i])


def _replicate_band(values, central):
    """The 2.5-97.5 % range of the replicates, widened to include the central value."""
    return min(_percentile(values, 2.5), central), max(_percentile(values, 97.5), central)


def _edge(values, central, half):
    lo, hi = _replicate_band(values, central)
    first = values[:half]
    return max(abs(_percentile(first, 2.5) - lo), abs(_percentile(first, 97.5) - hi)) / (hi - lo)


def _linearised_sd(derivatives):
    g = np.asarray(derivatives, dtype=float)
    return float(np.sqrt(g @ COV @ g))


# the central model's numbers, by hand
PLATEAU_SD = _linearised_sd([dp / h for dp, h in zip(SHIFT_PLATEAU, STEPS)])   # the plateau's sd
T90_SD = _linearised_sd([0.9 * dr / h for dr, h in zip(SHIFT_RISE, STEPS)])    # t90 = 0.9 x rise time
# t90 from every other output time: the ramp's kink at t = 9 is cut, the coarse interpolant runs from 8/9 (t = 8) to
# (8/9 + 1)/2 = 17/18 (t = 9) of the plateau, and crosses 0.9 at t = 8 + (0.9 - 8/9) / (17/18 - 8/9)
T90_NUMERICAL = abs(8 + (0.9 - 8 / 9) / (17 / 18 - 8 / 9) - 0.9 * 9)


@pytest.fixture
def central():
    """The drive's three seeds against the central model (asymptote 1.0, plateau 0.98, t90 8.1, delta_u 6.0, creep
    length 3.0) with five replicates, all five run: (rows, edge stability, bands).  Scored afresh for each test (not
    shared: the mutation runner picks a mutant's tests by which of them call ``score``)."""
    return _score(_drive(), {"local": _model_side()}, n_replicates=5)


def test_each_row_carries_the_dem_mean_and_its_standard_error_over_the_seeds(central):
    rows = _by(central[0])
    delta = _mean_and_error([0.95 * d for d in (5.0, 6.0, 4.0)])
    creep = _mean_and_error([2.4, 3.0, 2.7])
    t90 = _mean_and_error([0.9 * r for r in (8.0, 10.0, 12.0)])
    assert list(rows.index) == ["u_w_inf", "delta_u", "creep_length", "t90"]
    assert list(rows.unit) == ["sqrt(g d)", "d", "d", "sqrt(d/g)"]
    assert rows.loc["u_w_inf", ["dem", "dem_err"]].tolist() == [0.95, 0.01]
    assert rows.loc["delta_u", ["dem", "dem_err"]].tolist() == pytest.approx(delta, rel=1e-12)
    assert rows.loc["creep_length", ["dem", "dem_err"]].tolist() == pytest.approx(creep, rel=1e-9)
    assert rows.loc["t90", ["dem", "dem_err"]].tolist() == pytest.approx(t90, rel=1e-12)
    assert list(rows.dem_how) == ["pooled over 3 seeds"] + ["spread over 3 seeds"] * 3
    assert set(rows.drive) == {LABEL} and set(rows.model_label) == {"local model"}


def test_the_windowed_steady_response_is_the_models_final_quarter_mean_with_the_asymptote_beside_it(central):
    rows, _, bands = central
    rows = _by(rows)
    assert T[0] + STEADY_LAST * (T[-1] - T[0]) > 9.0  # the final quarter lies on the plateau
    row = rows.loc["u_w_inf"]
    assert row.predicted == pytest.approx(0.98, rel=1e-14) and row.asymptote == 1.0
    assert row.band == pytest.approx([0.98 - Z95 * PLATEAU_SD, 0.98 + Z95 * PLATEAU_SD], rel=1e-9)
    assert row.calibration_sd == pytest.approx(PLATEAU_SD, rel=1e-9) and row.numerical_err == 0.0
    assert rows.loc[["delta_u", "creep_length", "t90"], "asymptote"].isna().all()
    band = bands[(LABEL, "local")].set_index("t")
    assert band.loc[20.0, ["lo", "hi"]].tolist() == pytest.approx([0.98 - Z95 * PLATEAU_SD, 0.98 + Z95 * PLATEAU_SD])
    assert band.loc[0.0, ["lo", "hi"]].tolist() == [0.0, 0.0]  # every ramp starts at rest


def test_the_profile_bands_are_the_replicates_percentiles_widened_to_the_central_value(central):
    rows = _by(central[0])
    delta_band = _replicate_band(REPLICATES["delta_u"], 6.0)
    creep_band = _replicate_band(REPLICATES["ell"], 3.0)
    assert delta_band == pytest.approx((6.0, 6.49)) and creep_band == pytest.approx((2.51, 3.0))  # both widened
    assert rows.loc["delta_u", "predicted"] == 6.0
    assert rows.loc["delta_u", "band"] == pytest.approx(delta_band, rel=1e-12)
    assert rows.loc["creep_length", "predicted"] == pytest.approx(3.0, rel=1e-9)
    assert rows.loc["creep_length", "band"] == pytest.approx(creep_band, rel=1e-9)
    for obs, (lo, hi) in (("delta_u", delta_band), ("creep_length", creep_band)):
        assert rows.loc[obs, "calibration_sd"] == pytest.approx((hi - lo) / (2 * Z95), rel=1e-9)
        assert rows.loc[obs, "numerical_err"] == 0.0


def test_t90_has_the_linearised_band_and_its_numerical_error_from_every_other_output_time(central):
    row = _by(central[0]).loc["t90"]
    assert T90_NUMERICAL == pytest.approx(0.1)
    assert row.predicted == pytest.approx(0.9 * 9, rel=1e-12)
    assert row.band == pytest.approx([8.1 - Z95 * T90_SD, 8.1 + Z95 * T90_SD], rel=1e-9)
    assert row.calibration_sd == pytest.approx(T90_SD, rel=1e-9)
    assert row.numerical_err == pytest.approx(T90_NUMERICAL, rel=1e-9)


def _welch(dem_err, dem_dof, *exact):
    """Welch-Satterthwaite degrees of freedom of sqrt(dem_err^2 + sum exact^2), the exact errors' dof infinite."""
    total = dem_err**2 + sum(e**2 for e in exact)
    return total**2 / (dem_err**4 / dem_dof)


def test_sigma_is_dem_minus_model_over_every_error_in_quadrature_and_gives_the_verdict(central):
    """Three seeds: the DEM's errors have 2 degrees of freedom, the rows' combined errors 2.2 to 4.6, and the verdict
    is Student-t's at those: u_w_inf at -2.50 sigma and delta_u at -2.22 are consistent (thresholds 2.73 and 3.93),
    though both lie beyond the normal 1.96."""
    rows = _by(central[0])
    delta, delta_err = _mean_and_error([0.95 * d for d in (5.0, 6.0, 4.0)])
    creep, creep_err = _mean_and_error([2.4, 3.0, 2.7])
    t90, t90_err = _mean_and_error([0.9 * r for r in (8.0, 10.0, 12.0)])
    delta_sd = (6.49 - 6.0) / (2 * Z95)
    creep_sd = (3.0 - 2.51) / (2 * Z95)
    expected = {"u_w_inf": (0.95 - 0.98) / np.sqrt(0.01**2 + PLATEAU_SD**2),
                "delta_u": (delta - 6.0) / np.sqrt(delta_err**2 + delta_sd**2),
                "creep_length": (creep - 3.0) / np.sqrt(creep_err**2 + creep_sd**2),
                "t90": (t90 - 8.1) / np.sqrt(t90_err**2 + T90_SD**2 + T90_NUMERICAL**2)}
    dof = {"u_w_inf": _welch(0.01, 2, PLATEAU_SD), "delta_u": _welch(delta_err, 2, delta_sd),
           "creep_length": _welch(creep_err, 2, creep_sd), "t90": _welch(t90_err, 2, T90_SD, T90_NUMERICAL)}
    assert rows.sigma.to_dict() == pytest.approx(expected, rel=1e-8)
    assert rows.dof.to_dict() == pytest.approx(dof, rel=1e-9)
    threshold = {k: stats.t.ppf(0.975, v) for k, v in dof.items()}
    assert threshold == pytest.approx({"u_w_inf": 2.7317, "delta_u": 3.9289, "creep_length": 2.6344,
                                       "t90": 3.8288}, abs=1e-4)
    normal = stats.norm.ppf(0.975)
    assert expected["u_w_inf"] < -normal and expected["delta_u"] < -normal  # beyond 1.96 ...
    assert all(abs(expected[k]) <= threshold[k] for k in expected)  # ... within their own t quantile
    assert rows.verdict.to_dict() == {"u_w_inf": "consistent", "delta_u": "consistent", "creep_length": "consistent",
                                      "t90": "consistent"}
    assert rows.scored.all() and (rows.note == "").all()


def test_the_dem_errors_dof_is_seeds_minus_one_or_blocks_of_one_seed_minus_one():
    """Four seeds: every DEM error has 3 degrees of freedom.  One seed whose steady window is cut into four blocks:
    the profile rows' errors have 3, and t90's error, the running mean's half-width, is a resolution (infinite dof,
    said in dem_how), so its row's dof is infinite."""
    d0s, ells, rises = (5.0, 6.0, 4.0, 5.5), (2.4, 3.0, 2.7, 2.6), (8.0, 10.0, 12.0, 9.0)
    rows = _by(_score(_drive(d0s=d0s, ells=ells, rises=rises), {"local": _model_side()})[0])
    delta, delta_err = _mean_and_error([0.95 * d for d in d0s])
    assert rows.loc["delta_u", ["dem", "dem_err"]].tolist() == pytest.approx([delta, delta_err], rel=1e-12)
    assert rows.loc["delta_u", "dof"] == pytest.approx(_welch(delta_err, 3, (6.49 - 6.0) / (2 * Z95)), rel=1e-9)
    assert rows.loc["u_w_inf", "dof"] == pytest.approx(_welch(0.01, 3, PLATEAU_SD), rel=1e-9)
    assert _mean_err([0.95 * d for d in d0s], "four seeds").dof == 3
    one = _drive(rises=(10.0,), samples=tuple(_profile(d, e) for d, e in zip(d0s, ells)), steady_dof=3)
    one.samples_how = "spread over 4 blocks of the steady window (1 seed)"
    rows = _by(_score(one, {"local": _model_side()})[0])
    creep, creep_err = _mean_and_error(ells)
    assert rows.loc["creep_length", "dem_err"] == pytest.approx(creep_err, rel=1e-9)
    assert rows.loc["creep_length", "dof"] == pytest.approx(_welch(creep_err, 3, (3.0 - 2.51) / (2 * Z95)),
                                                            rel=1e-9)
    t90 = rows.loc["t90"]
    assert t90.dem_err == pytest.approx(0.5 * T90_WINDOW * (T[-1] - T[0])) and np.isinf(t90.dof)
    assert t90.dem_how == ("half-width of the running mean (1 seed: a resolution, not a statistical error; infinite "
                           "dof)")
    # 9.0 against 8.1 over sqrt(0.5^2 + T90_SD^2 + 0.1^2): 1.58, within the normal 1.96
    assert t90.sigma == pytest.approx(0.9 / np.sqrt(0.25 + T90_SD**2 + T90_NUMERICAL**2), rel=1e-9)
    assert t90.verdict == "consistent"


def test_a_t90_row_whose_only_error_is_the_interpolations_is_scored_on_it():
    # identical seeds (no DEM spread) and a rise time no parameter moves (no band): the interpolation error is all
    rows, _, _ = _score(_drive(rises=(10.0, 10.0, 10.0)), {"local": _model_side(shift_rise=(0.0, 0.0))})
    row = _by(rows).loc["t90"]
    assert (row.dem, row.dem_err, row.calibration_sd) == (pytest.approx(9.0), 0.0, pytest.approx(0.0, abs=1e-12))
    assert row.band == pytest.approx([8.1, 8.1], abs=1e-12) and row.numerical_err == pytest.approx(T90_NUMERICAL)
    assert row.scored and row.sigma == pytest.approx((9.0 - 8.1) / T90_NUMERICAL, rel=1e-9)
    assert row.verdict == "disagrees"


def test_a_row_is_blind_only_under_an_independent_calibration_and_off_the_models_own_drive():
    a, local = _drive(), {"local": _model_side()}
    rows, _, _ = _score(a, local)  # the defaults: nothing fitted, an independent calibration
    assert len(rows) == 4 and rows.blind.all()
    rows, _, _ = _score(a, {**local, "ngf": _model_side()}, fitted_on={"ngf": LABEL, "local": "another drive"},
                        independent=True)
    assert rows.groupby("model").blind.agg(["all", "any"]).to_dict("index") == {
        "local": {"all": True, "any": True}, "ngf": {"all": False, "any": False}}
    rows, _, _ = _score(a, local, independent=False)
    assert len(rows) == 4 and not rows.blind.any()


def test_edge_stability_is_the_largest_change_of_a_band_edge_from_half_to_all_replicates(central):
    # five replicates, half = 2: delta_u's lower edge moves from 6.205 (first two) to the central 6.0 over a band of
    # 0.49; the other observables' first two replicates already span their edges
    edge = central[1]
    for key, value in (("value", 1.0), ("ell", 3.0)):
        assert _edge(REPLICATES[key], value, 2) < 0.5 * _edge(REPLICATES["delta_u"], 6.0, 2)
    assert _edge(REPLICATES["delta_u"], 6.0, 2) == pytest.approx(0.205 / 0.49)
    assert edge == pytest.approx(_edge(REPLICATES["delta_u"], 6.0, 2), rel=1e-9)
    # an upper edge that moves: the replicates shallower than the central delta_u; two models, the larger counts
    shallow = {**REPLICATES, "delta_u": (5.6, 5.8, 5.9, 5.7, 5.5)}
    _, edge, _ = _score(_drive(), {"local": _model_side(), "ngf": _model_side(replicates=shallow, delta_u=6.1)})
    assert _edge(shallow["delta_u"], 6.1, 2) == pytest.approx(0.305 / 0.59)
    assert edge == pytest.approx(_edge(shallow["delta_u"], 6.1, 2), rel=1e-9)
    # eight replicates ran, half = 4: the first four against all five
    _, edge, _ = _score(_drive(), {"local": _model_side()}, n_replicates=8)
    expected = max(_edge(REPLICATES[k], c, 4) for k, c in (("value", 1.0), ("delta_u", 6.0), ("ell", 3.0)))
    assert edge == pytest.approx(expected, rel=1e-9)


def test_edge_stability_is_undefined_without_more_replicates_than_half_of_those_run():
    two = {k: v[:2] for k, v in REPLICATES.items()}
    _, edge, _ = _score(_drive(), {"local": _model_side(replicates=two)}, n_replicates=4)  # half = 2: not more
    assert np.isnan(edge)
    _, edge, _ = _score(_drive(), {"local": _model_side()}, n_replicates=3)  # half = 1: too few to compare
    assert np.isnan(edge)


def test_a_drive_reaching_the_base_leaves_its_layer_rows_and_every_half_space_row_unscored():
    still = pd.DataFrame({"depth": DEPTH, "u_x": np.ones_like(DEPTH)})  # u never falls to 5 % of u_w
    rows, _, _ = _score(_drive(steady_profile=still), {"local": _model_side(), "paper": _model_side()},
                        models=[_model("local"), _model("paper", half_space=True)])
    base = f"the flow reaches the base: u stays above 5 % of u_w down to the base of the {BED:g} d bed"
    local, paper = _by(rows, "local"), _by(rows, "paper")
    assert local.note.to_dict() == {"u_w_inf": "", "delta_u": "not scored: " + base,
                                    "creep_length": "not scored: " + base, "t90": ""}
    assert local.scored.to_dict() == {"u_w_inf": True, "delta_u": False, "creep_length": False, "t90": True}
    assert set(paper.note) == {"not scored: " + base + " (the model's bed is a half-space)"}
    assert set(paper.verdict) == {"not scored"} and not paper.scored.any()
    # the unscored rows keep their numbers
    assert local.loc["delta_u", "predicted"] == 6.0 and paper.loc["t90", "predicted"] == pytest.approx(8.1)


def test_a_model_whose_time_scale_is_assumed_predicts_no_t90():
    rows, _, _ = _score(_drive(), {"ngf": _model_side()}, models=[_model("ngf", transient_calibrated=False)])
    ngf = _by(rows, "ngf")
    assert ngf.note.to_dict() == {
        "u_w_inf": "", "delta_u": "", "creep_length": "",
        "t90": "not predicted: ngf's time scale is assumed (t0 one local inertial time), not calibrated, so its "
               "transient is no prediction"}
    assert ngf.verdict["t90"] == "not predicted" and ngf.scored.sum() == 3


def test_a_model_not_yet_steady_over_the_final_quarter_has_its_steady_profile_rows_unscored():
    # the plateau is 10 % short of the asymptote 2.0: the windowed value (like with like) and t90 are still scored
    assert 0.02 < MODEL_UNSTEADY < 0.1
    rows, _, _ = _score(_drive(), {"local": _model_side(asymptote=2.0, plateau=1.8)})
    local = _by(rows)
    short = ("not scored: over the DEM's final quarter the model is still -10% from its steady value (the record is "
             "shorter than the model's time scale)")
    assert local.note.to_dict() == {"u_w_inf": "", "delta_u": short, "creep_length": short, "t90": ""}
    assert local.loc["u_w_inf", "predicted"] == pytest.approx(1.8) and local.loc["u_w_inf", "asymptote"] == 2.0
    # 2 % short: steady enough
    rows, _, _ = _score(_drive(), {"local": _model_side(asymptote=2.0, plateau=1.96)})
    assert rows.scored.all()


def test_a_model_at_rest_is_unscored_only_while_its_response_still_moves():
    at_rest = {"value": (0.0,) * 5, "delta_u": (np.nan,) * 5, "ell": (None,) * 5}
    moving = _model_side(asymptote=0.0, plateau=0.1, delta_u=np.nan, ell=None, replicates=at_rest)
    rows, _, _ = _score(_drive(), {"local": moving})
    local = _by(rows)
    # no delta_u row (the model's is undefined) but the rows after it are kept
    assert list(local.index) == ["u_w_inf", "creep_length", "t90"]
    assert local.loc["creep_length", "predicted"] == 0.0  # rigid below delta_s
    assert local.note.to_dict() == {
        "u_w_inf": "", "t90": "",
        "creep_length": "not scored: over the DEM's final quarter the model still moves while its steady state is at "
                        "rest (the record is shorter than the model's time scale)"}
    still = pd.DataFrame({"t": T, "u_w": np.zeros_like(T)})
    rows, _, _ = _score(_drive(), {"local": _model_side(asymptote=0.0, delta_u=np.nan, ell=None, replicates=at_rest,
                                                        series=still)})
    local = _by(rows)  # no t90 (the model never moves): rest is steady
    assert list(local.index) == ["u_w_inf", "creep_length"] and local.scored.all()
    assert local.predicted.tolist() == [0.0, 0.0]


def test_rows_a_side_cannot_measure_are_left_out():
    # the DEM's u never falls to 5 % (no delta_u: u >= 0.9 exp(-1.475) = 0.21 at the base; creep length 20 d); the
    # model's creep zone holds fewer than 3 points (no creep length)
    assert 0.9 * np.exp(-(BED - 6.5) / 20) > 0.05
    slow = pd.DataFrame({"depth": DEPTH, "u_x": np.where(DEPTH <= 6.5, 1.0, 0.9 * np.exp(-(DEPTH - 6.5) / 20))})
    flat = (slow, slow.copy(), slow.copy())
    rows, _, _ = _score(_drive(samples=flat, steady_profile=_profile(5.0, 2.4)), {"local": _model_side()})
    assert list(rows.observable) == ["u_w_inf", "creep_length", "t90"]
    thin = _model_side()
    thin[0].steady.y, thin[0].steady.u = DEPTH[:15], thin[0].steady.u[:15]  # down to 7 d: one point in the zone
    rows, _, _ = _score(_drive(), {"local": thin})
    assert list(rows.observable) == ["u_w_inf", "delta_u", "t90"]


def test_a_model_without_a_prediction_is_skipped():
    a = _drive()
    local, spread = _model_side()
    rows, _, bands = score(a, [_model("paper"), _model("local")], {"local": local}, {"local": spread}, 5)
    assert set(rows.model) == {"local"} and len(rows) == 4 and list(bands) == [(LABEL, "local")]


def test_one_seed_profile_gives_no_dem_error_and_its_profile_rows_are_not_measurable():
    a = _drive(samples=(_profile(5.0, 2.4),))
    a.samples_how = "one steady-window profile"
    rows = _by(_score(a, {"local": _model_side()})[0])
    note = "not measurable: no DEM error (one steady-window profile gives none)"
    assert rows.loc["delta_u", "dem"] == pytest.approx(4.75) and np.isnan(rows.loc["delta_u", "dem_err"])
    assert rows.note.to_dict() == {"u_w_inf": "", "delta_u": note, "creep_length": note, "t90": ""}
    assert rows.verdict["creep_length"] == "not measurable" and np.isnan(rows.sigma["delta_u"])


def test_profile_rows_without_a_sustaining_replicate_have_no_band_and_are_not_scored():
    none = {k: () for k in REPLICATES}
    rows, edge, _ = _score(_drive(), {"local": _model_side(replicates=none)})
    rows = _by(rows)
    note = "not scored: no calibration replicate sustains this drive, so the prediction has no band"
    assert rows.note.to_dict() == {"u_w_inf": "", "delta_u": note, "creep_length": note, "t90": ""}
    assert np.isnan(rows.loc["delta_u", "band"]).all() and np.isnan(edge)
    assert rows.loc["t90", "band"] == pytest.approx([8.1 - Z95 * T90_SD, 8.1 + Z95 * T90_SD], rel=1e-9)


def test_a_row_whose_every_error_is_zero_has_no_sigma():
    # identical seeds (no DEM spread) and replicates at the central delta_u (no band): delta_u has no error at all
    same = tuple(_profile(5.0, 2.4) for _ in range(3))
    flat = {**REPLICATES, "delta_u": (6.0,) * 5}
    rows, edge, _ = _score(_drive(samples=same), {"local": _model_side(replicates=flat)})
    row = _by(rows).loc["delta_u"]
    assert row.dem_err == 0.0 and row.band == [6.0, 6.0] and row.calibration_sd == 0.0 and np.isnan(row.sigma)
    assert row.note == ("not scored: the DEM's error, the band and the numerical error are all zero, so sigma is "
                        "undefined")
    # a band of zero width has no edge to compare; the others still do
    assert edge == pytest.approx(max(_edge(REPLICATES[k], c, 2) for k, c in (("value", 1.0), ("ell", 3.0))), rel=1e-9)


def test_a_speed_drive_is_scored_on_its_free_friction():
    a = _drive(response="mu_w", steady=(0.41, 0.004))
    rows = _by(_score(a, {"local": _model_side(asymptote=0.4, plateau=0.39, response="mu_w")})[0])
    assert list(rows.index) == ["mu_w_inf", "delta_u", "creep_length", "t90"]
    row = rows.loc["mu_w_inf"]
    assert row.unit == "1" and row.predicted == pytest.approx(0.39) and row.asymptote == 0.4
    assert row.band == pytest.approx([0.39 - Z95 * PLATEAU_SD, 0.39 + Z95 * PLATEAU_SD], rel=1e-9)
    assert row.sigma == pytest.approx(0.02 / np.sqrt(0.004**2 + PLATEAU_SD**2), rel=1e-9)


def test_a_band_with_an_undefined_edge_is_no_band():
    assert _unmeasurable(Measured(1.0, 0.1, "seeds", 2), 0.9, np.nan, 0.1).startswith("not scored: no calibration")
    assert _unmeasurable(Measured(1.0, 0.1, "seeds", 2), np.nan, 1.1, 0.1).startswith("not scored: no calibration")


def test_the_mean_of_one_value_has_no_error_and_of_two_has_one():
    one = _mean_err([np.nan, 0.7], "one block")
    assert (one.value, one.how) == (0.7, "one block") and np.isnan(one.err) and np.isnan(one.dof)
    two = _mean_err([0.4, np.nan, 0.6], "two seeds")
    assert (two.value, two.how, two.dof) == (pytest.approx(0.5), "two seeds", 1)
    assert two.err == pytest.approx(np.sqrt(0.1**2 + 0.1**2) / np.sqrt(2), rel=1e-12)  # std(ddof=1)/sqrt(2) = 0.1
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no mean of an empty slice
        none = _mean_err([np.nan, np.nan], "nothing")
    assert np.isnan(none.value) and np.isnan(none.err) and none.how == "nothing"


# --- the headline ---------------------------------------------------------------------------------------------

def _row(drive, model, sigma, observable="u_w_inf", scored=True, blind=True):
    return {"drive": drive, "observable": observable, "model": model, "model_label": f"{model} model",
            "sigma": sigma, "scored": scored, "blind": blind, "note": "" if scored else "not scored: why",
            "verdict": "not scored" if not scored else "consistent" if abs(sigma) <= stats.norm.ppf(0.975)
            else "disagrees"}


def test_the_headline_without_a_verdict_says_why():
    rows = pd.DataFrame([_row("a", "local", 0.5)])
    assert headline(rows, True, "mu_s at its bound", 2) == (
        "No verdict: the mu(I) calibration failed (mu_s at its bound), so no prediction was made or scored.")
    assert headline(rows, False, "", 2) == (
        "No verdict: mu(I) was fitted on the drives themselves, so the rows restate the fit and none counts as "
        "support for a model; pass an independent calibration (--calibration) for a test.")
    assert headline(pd.DataFrame(), True, "", 3) == "No verdict: no blind row is shared by the models over 3 drive(s)."
    unscored = pd.DataFrame([_row("a", "local", 0.5, scored=False), _row("b", "ngf", 0.5, scored=False),
                             _row("a", "ngf", 0.5, blind=False)])
    assert headline(unscored, True, "", 2) == (
        "No verdict: no blind row is shared by the models over 2 drive(s); 2 row(s) not scored (the scene cannot "
        "support them: see each row's note).")


def test_the_headline_with_one_model_scored_gives_its_numbers_and_no_ranking():
    rows = pd.DataFrame([_row("a", "local", 0.5), _row("b", "local", -3.04), _row("c", "local", 1.0)])
    assert headline(rows, True, "", 3) == (
        "Blind test over 3 drive(s), one model scored: local model consistent on 2 of 3 (median |sigma| 1.0); no "
        "ranking, since no other model has a scored row.")


def test_the_headline_ranks_the_models_on_their_shared_rows_and_names_the_unranked():
    rows = pd.DataFrame([_row("a", "local", 0.5), _row("b", "local", 3.1),
                         _row("a", "ngf", 2.5), _row("b", "ngf", -4.1),
                         _row("a", "paper", 0.1, scored=False), _row("a", "kin", 0.1, blind=False)])
    # local: 1 of 2 consistent (share 0.5: most is not needed for "best"), ngf 0 of 2
    assert headline(rows, True, "", 2) == (
        "Blind test on the 2 row(s) the models share over 2 drive(s): local model consistent on 1 of 2 (median "
        "|sigma| 1.8), ngf model consistent on 0 of 2 (median |sigma| 3.3); the DEM supports local model best; "
        "1 row(s) not scored (the scene cannot support them: see each row's note); not ranked (no scored blind "
        "row shared with the others): kin model, paper model.")


def test_the_headline_says_when_no_model_is_consistent_on_most_rows():
    rows = pd.DataFrame([_row(d, "local", s) for d, s in zip("abc", (0.5, 3.0, 2.5))]
                        + [_row(d, "ngf", s) for d, s in zip("abc", (2.1, 3.0, -4.0))])
    assert headline(rows, True, "", 3) == (
        "Blind test on the 3 row(s) the models share over 3 drive(s): local model consistent on 1 of 3 (median "
        "|sigma| 2.5), ngf model consistent on 0 of 3 (median |sigma| 3.0); no model is consistent on most of them.")


def test_the_headline_separates_no_models_consistent_on_as_many_rows():
    """Three models each consistent on the one shared row, their median |sigma| 0.5, 0.9, 1.2: no ranking."""
    rows = pd.DataFrame([_row("a", "local", 0.5), _row("a", "ngf", -0.9), _row("a", "paper", 1.2)])
    assert headline(rows, True, "", 1) == (
        "Blind test on the 1 row(s) the models share over 1 drive(s): local model consistent on 1 of 1 (median "
        "|sigma| 0.5), ngf model consistent on 1 of 1 (median |sigma| 0.9), paper model consistent on 1 of 1 "
        "(median |sigma| 1.2); the DEM does not separate local model, ngf model, paper model (each consistent on 1 "
        "of 1).")


def test_a_slipping_plate_leaves_every_row_of_its_drive_unscored():
    """The grains touching the plate lag it by 12 % (> SLIP_MAX): every row of the drive (the plate's steady speed
    and t90, the layer's depth and creep) is kept, not scored, its note naming the slip. At SLIP_MAX exactly the
    plate grips and every row is scored."""
    from granstokes.compare.scorecard import SLIP_MAX
    models = [_model("local")]
    predictions, spreads = _model_side()
    for slip, slipped in ((0.12, True), (SLIP_MAX, False)):
        rows, _, _ = score(_drive(slip=slip), models, {"local": predictions}, {"local": spreads}, 5)
        assert len(rows) == 4 and rows.scored.all() != slipped
        assert set(rows.observable) == {"u_w_inf", "t90", "delta_u", "creep_length"}
        if slipped:
            assert (rows.note == "not scored: the plate slips 12% against the grains touching it (more than "
                                 "5%), so its speed and friction are not the bed's").all()


def test_a_model_beyond_the_calibrated_inertial_number_extrapolates_its_steady_rows():
    """A steady wall I of 0.8 against a calibration measured up to 0.55: the model's steady rows (the plate's steady
    value, the layer) are kept, not scored, their note saying so with both numbers; t90 (transient) is scored. At the
    calibration's largest I exactly, and with no calibrated range, nothing is extrapolated."""
    from granstokes.compare.scorecard import STEADY_OBSERVABLES, extrapolated
    note = extrapolated(0.8, (0.005, 0.55))
    assert note == ("not scored: extrapolated: the model's wall inertial number I = 0.8 (DEM convention) lies "
                    "beyond the calibration's largest, 0.55")
    assert extrapolated(0.55, (0.005, 0.55)) == "" and extrapolated(0.8, (np.nan, np.nan)) == ""
    predictions, spreads = _model_side()
    rows, _, _ = score(_drive(), [_model("local")], {"local": predictions}, {"local": spreads}, 5,
                       beyond={"local": note})
    steady = rows.observable.isin(STEADY_OBSERVABLES)
    assert (rows[steady].note == note).all() and (~rows[steady].scored).all()
    assert rows[~steady].scored.all() and set(rows[~steady].observable) == {"t90"}


def test_a_bed_short_of_the_depth_study_s_clearance_leaves_every_row_unscored():
    """DELTA_S = 7, below the depth study's 10.58 d: a bed must hold 7 + 1.45 x 10.58 = 22.34 d. 0.1 d short of that:
    every row (the layer's and the plate's) kept, not scored, the note giving the clearance; 0.1 d deeper: every row
    scored."""
    from granstokes.compare.scorecard import short_bed
    predictions, spreads = _model_side()
    need = DELTA_S + 1.45 * 10.58
    for depth in (need - 0.1, need + 0.1):
        a = _drive()
        a.spec = NS(depth=depth)
        rows, _, _ = score(a, [_model("local")], {"local": predictions}, {"local": spreads}, 5)
        assert set(rows.observable) == {"u_w_inf", "t90", "delta_u", "creep_length"}
        if depth < need:
            why = ("the bed (22.2 d) leaves 15.2 d below delta_s (7 d), less than the 15.3 d (1.45 x max(delta_s, "
                   "10.58 d)) at which the depth study found the observables independent of the depth")
            assert short_bed(a, DELTA_S) == why
            assert (rows.note == "not scored: " + why).all() and set(rows.verdict) == {"not scored"}
            # the unscored rows keep the DEM's numbers: the creep length is the seeds' mean
            assert rows[rows.observable == "creep_length"].dem.iloc[0] == pytest.approx((2.4 + 3.0 + 2.7) / 3)
        else:
            assert short_bed(a, DELTA_S) == "" and rows.scored.all()


def test_the_creep_length_is_fitted_over_a_fixed_window_below_delta_s_whatever_the_bed():
    """A tail whose local e-folding length grows with depth (ln u = -(z - 7)/3 - (z - 7)^2/60 below delta_s = 7): over
    the first CREEP_WINDOW = 3 d the least-squares length is the same in a 36 d and an 80 d bed, and equals numpy's fit
    over [7, 10]."""
    from granstokes.compare.scorecard import CREEP_WINDOW, creep_length
    assert CREEP_WINDOW == 3.0
    z = np.arange(0.0, 80.25, 0.25)
    u = np.exp(-(z - 7) / 3 - (z - 7) ** 2 / 60)
    zone = (z >= 7) & (z <= 10)
    expected = -1 / np.polyfit(z[zone], np.log(u[zone]), 1)[0]
    assert creep_length(z, u, 7.0, 36.0) == pytest.approx(expected, rel=1e-12) == creep_length(z, u, 7.0, 80.0)


def test_the_depth_study_finds_every_scored_observable_flat_from_the_clearance_and_the_creep_to_the_base_growing():
    """bench/creep_depth.csv (one drive, delta_s = 10.58 d, beds 26-78 d deep, each value with its error over two
    beds): every bed's plate speed, t90, delta_u and creep length (the scorecard's fixed zone) agree with the deepest
    bed's (|difference| within Student-t's 95 % at the Welch dof of the two beds' errors), and BASE_CLEARANCE is the
    shallowest bed's clearance (at most it, within 0.05); the creep length fitted from delta_s to the base grows with
    the depth (a weighted line's slope beyond Student-t's 95 % at n - 2 dof, its error scaled by sqrt(chi2/dof))."""
    from granstokes.compare.rows import effective_dof
    from granstokes.dem.sizing import BASE_CLEARANCE, DEPTH_STUDY_DELTA_S
    table = pd.read_csv(Path(__file__).resolve().parents[2] / "bench" / "creep_depth.csv").sort_values("depth")
    assert (table.delta_s == DEPTH_STUDY_DELTA_S).all()
    deepest = table.iloc[-1]

    def agrees(row, key):
        errors = (row[f"{key}_err"], deepest[f"{key}_err"])
        dof = effective_dof(errors, (row.beds - 1, deepest.beds - 1))
        return abs(row[key] - deepest[key]) <= stats.t.ppf(0.975, dof) * np.hypot(*errors)

    assert all(agrees(r, k) for _, r in table.iterrows() for k in ("u_w_inf", "t90", "delta_u", "creep_length"))
    clear = (table.depth - table.delta_s) / table.delta_s
    assert 0 <= clear.iloc[0] - BASE_CLEARANCE < 0.05
    coef, cov = np.polyfit(table.depth, table.creep_to_base, 1, w=1 / table.creep_to_base_err, cov="unscaled")
    chi2 = np.sum(((table.creep_to_base - np.polyval(coef, table.depth)) / table.creep_to_base_err) ** 2)
    dof = len(table) - 2
    assert coef[0] / np.sqrt(cov[0, 0] * max(1.0, chi2 / dof)) > stats.t.ppf(0.975, dof)


def test_a_wall_friction_beyond_the_calibration_is_judged_in_the_dem_convention():
    """mu_s = 0.3, mu_d = 0.7, I0 = 0.15 in the paper's convention (|gamma_dot| = |du/dy|/2) is I0 = 0.3 in the DEM's:
    a wall friction of 0.5 is then the wall I = 0.3 (DEM), beyond a calibration measured up to 0.29 and within one up
    to 0.31; read without the conversion it would be 0.15, within both."""
    from granstokes.compare.scorecard import beyond_calibration
    from granstokes.continuum.rheology import Friction
    material = NS(friction=Friction(mu_s=0.3, mu_d=0.7), I0=0.15, I_convention="paper")
    assert "I = 0.3 (DEM convention)" in beyond_calibration(material, [0.5], (1e-3, 0.29))
    assert beyond_calibration(material, [0.5, 0.4], (1e-3, 0.31)) == ""
    assert "I = inf" in beyond_calibration(material, [0.7], (1e-3, 0.31))  # at mu_d no finite I reaches it
