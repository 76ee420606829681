"""Independent answers for the oscillating plate's rows and laws (compare.oscillation ``scorecard``, ``choice_rows``,
``_row``, ``_unmeasurable``, ``_difference``, ``laws``, ``_weighted_slope``, ``_beds``, ``unsettled``; the report's
words), on synthetic DEM sides and model sides: no record is read and no solver runs (the real DriveSpec,
DemOscillation, OscPrediction and ModelSetup, carrying made-up numbers).

What is checked, and how the answers are found without the module:

* a row's DEM value and error are the beds' mean and std(ddof=1)/sqrt(n), computed here from per-bed values, with
  n - 1 degrees of freedom; sigma is (DEM - model)/sqrt(dem_err^2 + numerical_err^2 + calibration_sd^2), the row's
  dof the Welch-Satterthwaite (sum e^2)^2 / (dem_err^4/(n - 1)) (the model's errors exact), written out here, and the
  band predicted -+ z sd with z the normal 97.5 % quantile (scipy, not the module's constant); the verdict words are
  written out per row (consistent when |sigma| <= scipy's t.ppf(0.975, dof)).  The bands are normal (compare.rows);
* phase differences are wrapped into (-pi, pi]: a DEM lag of +3.0 against a model's -3.0 differs by 6 - 2 pi (not 6),
  and pi stays pi; other observables are never wrapped (a dissipation difference of 4.5 > pi is 4.5);
  phase_lag > 0 means the response peaks after the imposed sine (the DEM reader's side of that convention is pinned
  by test_independent_answers.py's Newtonian Stokes second problem, not repeated here);
* unscored rows: the note's head is the verdict ("not predicted" when a model has no prediction, with the reason
  appended once; "not measurable" when the DEM has no value or no error, or when the yielded edge reaches the deepest
  plane for the two depth observables), sigma is NaN whatever the model's errors;
* laws: n in yielded_depth ~ (omega t_s)^n and s in phase_lag = a + s ln(omega t_s) on data made from a known power
  law / line plus known offsets, against numpy.polyfit with weights 1/sd (its unscaled covariance gives the DEM
  slope's error) and the weighted least-squares hat matrix built here (the model's slope on the DEM's weights, its
  error from the model's per-drive sds); a three-point line whose slope and error are closed forms; the drives left
  out (no yielded layer on either side), n_drives, the window and the "need 3" rows.  Lack of fit: chi2 = the
  weighted squared residuals about the polyfit line, by hand; chi2/dof above 1 scales the DEM slope's error by its
  square root, a step in the lag (chi2's p-value, scipy's chi2.sf, below 0.01) is "not a line" with no slope; a
  slope has n - 2 degrees of freedom;
* estimator families: a law row carries each choice's fit (polyfit by hand), ``systematic`` = half the range of
  DEM - model over the measured choices, the primary's numbers, and "depends on the estimator" when the choices
  split; a primary that is not a line leaves the row to the first measured choice; a slipping plate leaves only the
  choices read against the plate's speed unscored;
* the periodic state: beds built cycle by cycle (a jam 1.6 -> 0.12, a bed creeping at 0.03 beside two at 2.0) give
  every row of their drive the note written out here; the report's sentences (the lag frequency by frequency, the
  count of such drives) and its scene check, written out.
"""
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from granstokes.compare import oscillation as osc
from granstokes.compare.drive import DriveSpec
from granstokes.continuum.load import Load
from scipy import stats

P_W, DEPTH, T_S = 20.0, 12.0, 2.0
PLANES = np.arange(1.0, DEPTH + 0.5)  # the profile planes' depths: the deepest is DEPTH
Z = stats.norm.ppf(0.975)
NGF_NOTE = "no NGF amplitude: give a Stokes report's metrics.json (--ngf-from)"
BEDS4 = "spread over 4 beds (std/sqrt(n))"
UNITS_SPEED = {"response_amplitude": "1", "phase_lag": "rad", "yielded_depth": "d",
               "dissipation": "rho_p g d^2 per plate area", "remobilization_strain": "1"}


def _drive(name: str, omega_ts: float, kind: str = "speed", amplitude: float = 2.0,
           transit_time: float = np.nan) -> DriveSpec:
    """A drive at omega t_s (t_s = T_S: the division and product by 2 are exact); its transit time unknown unless
    given."""
    imposed = {"mu_w": amplitude} if kind == "stress" else {"u_w": amplitude}
    load = Load(kind, P_W, omega=omega_ts / T_S, **imposed)
    return DriveSpec(Path("runs/p20"), name, load, DEPTH, plate_mass=1.0, surface_offset=0.0, steps=0,
                     transit_time=transit_time, seeds=4, grains=0, dimension=2, t_s=T_S)


def _over_beds(per_bed) -> tuple[float, float, str, int]:
    """The beds' mean, its error std(ddof=1)/sqrt(n) and its n - 1 degrees of freedom, by hand."""
    b = np.asarray(per_bed, dtype=float)
    n = len(b)
    mean = b.sum() / n
    return mean, np.sqrt(((b - mean) ** 2).sum() / (n - 1)) / np.sqrt(n), f"spread over {n} beds (std/sqrt(n))", n - 1


def _welch(dem_err, dem_dof, *exact):
    """Welch-Satterthwaite degrees of freedom of sqrt(dem_err^2 + sum exact^2), the exact errors' dof infinite."""
    total = dem_err ** 2 + sum(e ** 2 for e in exact)
    return total ** 2 / (dem_err ** 4 / dem_dof)


def _family(values: dict, chosen: dict | None) -> dict:
    """Every law choice (osc.LAW_FAMILIES) with its observable's ``values`` unless ``chosen`` gives its own."""
    return {(o, c): (chosen or {}).get((o, c), values[o]) for o, family in osc.LAW_FAMILIES.items() for c in family}


def _dem(drive: DriveSpec, values: dict, deepest_edge: float = 6.0, slip: float = 0.0, chosen: dict | None = None,
         beds: tuple = ()) -> osc.DemOscillation:
    """A DEM side with ``values`` (observable -> (value, err, how, dof); the others 1 +- 0.1 over 4 beds), each law
    choice the same as its observable unless ``chosen`` says otherwise ((observable, choice) -> (value, err, how,
    dof)), a yielded edge over the phase reaching ``deepest_edge`` (one phase bin without data: NaN) and ``beds``'
    periodic states."""
    values = {o: values.get(o, (1.0, 0.1, BEDS4, 3)) for o in osc.OBSERVABLES}
    zones = pd.DataFrame(np.zeros((4, len(PLANES))), columns=pd.Index(PLANES, name="depth"))
    yielded = pd.Series([0.5 * deepest_edge, deepest_edge, np.nan, 0.0])
    empty = pd.DataFrame()
    return osc.DemOscillation(drive, (), values, _family(values, chosen), zones, yielded, empty, empty, empty, slip,
                              beds, 3)


def _prediction(values: dict, model: str = "local", chosen: dict | None = None) -> osc.OscPrediction:
    """A model side with ``values`` (observable -> (predicted, numerical error, calibration sd); the others 1) and its
    law choices (as ``_dem``'s)."""
    values = {o: values.get(o, (1.0, 0.01, 0.01)) for o in osc.OBSERVABLES}
    empty = pd.DataFrame()
    return osc.OscPrediction(model, values, _family(values, chosen), empty, pd.Series(dtype=float), empty, empty)


def _rows(dems, predictions, setup=None, ngf_note=NGF_NOTE) -> pd.DataFrame:
    return osc.scorecard(dems, predictions, setup or osc.ModelSetup(None, None), ngf_note)


def _choices(dems, predictions, setup=None, ngf_note=NGF_NOTE) -> pd.DataFrame:
    return osc.choice_rows(dems, predictions, setup or osc.ModelSetup(None, None), ngf_note)


# --- the scorecard's rows --------------------------------------------------------------------------------------

BEDS = {"response_amplitude": [0.52, 0.55, 0.49, 0.54], "phase_lag": [-0.62, -0.55, -0.66, -0.57],
        "yielded_depth": [3.1, 3.3, 2.9, 3.2], "dissipation": [50.0, 53.0, 47.0, 52.0],
        "remobilization_strain": [0.8, 0.9, 0.85, 0.75]}
MODEL = {"response_amplitude": (0.45, 0.004, 0.006), "phase_lag": (-0.5, 0.01, 0.02), "yielded_depth": (3.0, 0.05, 0.1),
         "dissipation": (46.0, 0.5, 1.5), "remobilization_strain": (0.6, 0.02, 0.03)}
# |sigma| by hand: 4.98, 2.99, 0.89, 2.18 (wrapped as a phase it would be -0.86), 4.65; the rows' dof 5.1, 9.8, 22.1,
# 17.7, 15.2 (4 beds: the DEM's 3, the model's exact errors adding to the sum), thresholds t_0.975(dof) 2.56, 2.23,
# 2.07, 2.10, 2.13: the dissipation's 2.18 still disagrees
VERDICTS = {"response_amplitude": "disagrees", "phase_lag": "disagrees", "yielded_depth": "consistent",
            "dissipation": "disagrees", "remobilization_strain": "disagrees"}
DOF = {"response_amplitude": 5.05, "phase_lag": 9.84, "yielded_depth": 22.1, "dissipation": 17.69,
       "remobilization_strain": 15.16}


def test_each_row_is_the_beds_mean_and_error_against_the_prediction_and_its_band():
    drive = _drive("speed-1", 1.5)
    dem = _dem(drive, {o: _over_beds(b) for o, b in BEDS.items()})
    rows = _rows([dem], {(drive.label, "local"): _prediction(MODEL)})
    local = rows[rows.model == "local"].set_index("observable")
    assert list(local.index) == list(osc.OBSERVABLES)
    assert local.blind.dtype == bool and local.blind.all()  # every row is predicted blind
    lag = np.mean(BEDS["phase_lag"])
    for o, per_bed in BEDS.items():
        r = local.loc[o]
        b = np.array(per_bed)
        mean, err = b.mean(), np.std(b, ddof=1) / np.sqrt(len(b))
        p, num, cal = MODEL[o]
        assert r.dem == pytest.approx(mean, rel=1e-12) and r.dem_err == pytest.approx(err, rel=1e-12)
        assert r.dem_how == "spread over 4 beds (std/sqrt(n))"
        assert r.predicted == p and r.numerical_err == num and r.calibration_sd == cal
        sd = np.sqrt(num ** 2 + cal ** 2)
        np.testing.assert_allclose(r.band, [p - Z * sd, p + Z * sd], rtol=1e-12)
        assert r.sigma == pytest.approx((mean - p) / np.sqrt(err ** 2 + num ** 2 + cal ** 2), rel=1e-12), o
        assert r.dof == pytest.approx(_welch(err, len(b) - 1, num, cal), rel=1e-12), o
        assert r.dof == pytest.approx(DOF[o], abs=0.05), o
        threshold = stats.t.ppf(0.975, r.dof)
        assert (abs(r.sigma) <= threshold) == (VERDICTS[o] == "consistent"), o
        assert r.verdict == VERDICTS[o] and r.scored and r.note == "", o
        assert r.unit == UNITS_SPEED[o] and r.drive == "runs/p20/speed-1" and r.model_label == osc.LABELS["local"]
        assert r.kind == "speed" and r.amplitude == 2.0 and r.omega == 0.75 and r.omega_ts == 1.5
        assert r.phase_lag == pytest.approx(lag, rel=1e-12) and r.phase_lag_predicted == -0.5
    # the difference 50.5 - 46 = 4.5 > pi of a dissipation is not wrapped like a phase
    assert local.loc["dissipation", "sigma"] > 2


def test_phase_difference_is_wrapped_into_minus_pi_pi():
    cases = {"ahead": (3.0, -3.0, 6.0 - 2 * np.pi),  # 6 is one turn from 6 - 2 pi: the DEM lags 0.28 less
             "behind": (-3.0, 3.0, 2 * np.pi - 6.0),
             "half-turn": (np.pi / 2, -np.pi / 2, np.pi),  # pi itself is kept
             "minus-half-turn": (-np.pi / 2, np.pi / 2, np.pi)}  # -pi is brought to +pi
    dem_err, num, cal = 0.13, 0.1, 0.12
    combined = np.sqrt(dem_err ** 2 + num ** 2 + cal ** 2)
    dems, predictions = [], {}
    for name, (v, p, _) in cases.items():
        drive = _drive(name, 1.0)
        dems.append(_dem(drive, {"phase_lag": (v, dem_err, BEDS4, 3)}))
        predictions[drive.label, "local"] = _prediction({"phase_lag": (p, num, cal)})
    rows = _rows(dems, predictions)
    lag = rows[(rows.model == "local") & (rows.observable == "phase_lag")].set_index("drive")
    for name, (v, p, difference) in cases.items():
        r = lag.loc[f"runs/p20/{name}"]
        assert r.sigma == pytest.approx(difference / combined, rel=1e-9), name
        assert r.dem == v and r.predicted == p and r.phase_lag == v and r.phase_lag_predicted == p
    # +3.0 against -3.0: |6 - 2 pi| / 0.2 = 1.4 sd, consistent at any dof (6 / 0.2 = 30 sd would disagree)
    assert lag.loc["runs/p20/ahead", "sigma"] < 0 and lag.loc["runs/p20/ahead", "verdict"] == "consistent"
    assert lag.loc["runs/p20/behind", "sigma"] > 0 and lag.loc["runs/p20/behind", "verdict"] == "consistent"
    assert lag.loc["runs/p20/half-turn", "verdict"] == "disagrees"  # pi / 0.2 = 15.7 sd


def test_rows_without_a_prediction_say_why_and_are_not_scored():
    failed, missing = _drive("failed", 1.0, "stress", 0.45), _drive("missing", 2.0, "stress", 0.45)
    dems = [_dem(failed, {"phase_lag": (0.7, 0.05, "how", 3)}), _dem(missing, {"phase_lag": (0.4, 0.05, "how", 3)})]
    reason = "the local solver failed on this drive: step size too small"
    rows = _rows(dems, {(failed.label, "local"): reason})
    assert len(rows) == 2 * 2 * len(osc.OBSERVABLES)  # drives x models (every label) x observables
    notes = {("failed", "local"): f"not predicted: {reason}", ("missing", "local"): "not predicted: ",
             ("failed", "ngf"): f"not predicted: {NGF_NOTE}", ("missing", "ngf"): f"not predicted: {NGF_NOTE}"}
    for (drive, model), note in notes.items():
        g = rows[(rows.drive == f"runs/p20/{drive}") & (rows.model == model)]
        assert list(g.observable) == list(osc.OBSERVABLES)
        assert (g.note == note).all() and (g.verdict == "not predicted").all() and not g.scored.any()
        assert g.sigma.isna().all() and g.predicted.isna().all() and g.phase_lag_predicted.isna().all()
        assert g.numerical_err.isna().all() and g.calibration_sd.isna().all()
        assert np.isnan(np.stack(g.band.to_numpy())).all()
        assert (g.dem == 1.0).sum() == 4 and (g.phase_lag == (0.7 if drive == "failed" else 0.4)).all()
        assert (g.model_label == osc.LABELS[model]).all()
    units = rows[rows.observable == "response_amplitude"].unit
    assert (units == "sqrt(g d)").all()  # under an imposed stress the response is the plate's speed
    # a reason that already says "not predicted" is kept as it is
    again = _rows(dems[:1], {(failed.label, "local"): "not predicted: the bed is too shallow"},
                  ngf_note="not predicted: NGF is off")
    assert set(again.note) == {"not predicted: the bed is too shallow", "not predicted: NGF is off"}


def test_a_dem_value_without_a_finite_error_is_not_measurable():
    drive = _drive("speed-1", 1.0)
    dem = _dem(drive, {"response_amplitude": (0.5, 0.0, "one bed: its cycles as blocks", 4),  # zero error
                       "phase_lag": (-0.6, np.nan, "one bed: its cycles as blocks", 0),  # no error
                       "dissipation": (np.nan, 0.5, BEDS4, 3)})  # no value
    rows = _rows([dem], {(drive.label, "local"): _prediction({"response_amplitude": (0.3, 0.01, 0.02)})})
    local = rows[rows.model == "local"].set_index("observable")
    for o in ("response_amplitude", "phase_lag", "dissipation"):
        r = local.loc[o]
        assert r.verdict == "not measurable" and not r.scored, o
        assert r.note.startswith("not measurable: no error (fewer than two beds"), o
        assert np.isnan(r.sigma), o  # even where the model's errors would make (0.5 - 0.3)/0.022 finite
        assert r.predicted == (0.3 if o == "response_amplitude" else 1.0)
    for o in ("yielded_depth", "remobilization_strain"):  # 1 +- 0.1 against 1: sigma 0
        assert local.loc[o, "verdict"] == "consistent" and local.loc[o, "note"] == ""
        assert local.loc[o, "sigma"] == pytest.approx(0.0, abs=1e-15)


def test_a_prediction_without_a_value_or_an_error_is_not_scored():
    """A model value of NaN, or a NaN calibration sd, would make sigma NaN: the row says why and is not scored."""
    drive = _drive("speed-1", 1.0)
    pred = _prediction({"dissipation": (np.nan, 0.5, 1.0), "phase_lag": (-0.5, 0.01, np.nan)})
    local = _rows([_dem(drive, {})], {(drive.label, "local"): pred}).query("model == 'local'").set_index("observable")
    assert local.loc["dissipation", "note"] == "not predicted: the model's solution gives no value of this observable"
    assert local.loc["phase_lag", "note"] == ("not predicted: the model's numerical error or calibration band is "
                                              "undefined")
    assert not local.loc[["dissipation", "phase_lag"], "scored"].any()
    assert (local.loc[["dissipation", "phase_lag"], "verdict"] == "not predicted").all()
    assert local.loc["response_amplitude", "verdict"] == "consistent"  # 1 +- 0.1 against 1


def test_an_edge_at_the_deepest_plane_makes_only_the_depth_observables_unmeasurable():
    censored, inside = _drive("censored", 1.0), _drive("inside", 1.0)
    dems = [_dem(censored, {}, deepest_edge=PLANES.max()), _dem(inside, {}, deepest_edge=PLANES.max() - 0.1)]
    predictions = {(d.drive.label, "local"): _prediction({}) for d in dems}
    rows = _rows(dems, predictions)
    local = rows[rows.model == "local"].set_index(["drive", "observable"])
    for o in osc.OBSERVABLES:
        r = local.loc[("runs/p20/censored", o)]
        if o in ("yielded_depth", "remobilization_strain"):
            assert r.verdict == "not measurable" and not r.scored and np.isnan(r.sigma), o
            assert r.note.startswith("not measurable: at some phase the bed yields down to its deepest plane")
            assert r.note.endswith("(the edge is censored by the base)")
        else:
            assert r.verdict == "consistent" and r.scored and r.note == "", o
        assert local.loc[("runs/p20/inside", o), "verdict"] == "consistent", o


# --- the laws ---------------------------------------------------------------------------------------------------

OMEGA_TS = np.array([0.1, 0.3, 1.0, 3.0, 10.0, 30.0])
# yielded depth: DEM 1.6 (omega t_s)^-1/2, model 1.5 (omega t_s)^-0.4, each times exp(known offsets); the fifth
# drive's model does not yield and the sixth's DEM does not: both are left out of the exponent
Y_DEM = 1.6 * OMEGA_TS ** -0.5 * np.exp([0.03, -0.05, 0.02, 0.04, -0.03, 0.0]) * [1, 1, 1, 1, 1, 0]
Y_DEM_ERR = np.array([0.02, 0.05, 0.03, 0.08, 0.04, 0.05]) * np.where(Y_DEM > 0, Y_DEM, 1.0)
Y_MODEL = 1.5 * OMEGA_TS ** -0.4 * np.exp([-0.02, 0.01, 0.03, -0.01, 0.0, 0.02]) * [1, 1, 1, 1, 0, 1]
Y_NUM = np.array([0.01, 0.02, 0.01, 0.03, 0.01, 0.02]) * Y_MODEL
Y_CAL = np.array([0.03, 0.02, 0.04, 0.02, 0.03, 0.05]) * Y_MODEL
# phase lag: DEM 0.05 + 0.1 ln(omega t_s), model 0.105 ln(omega t_s), plus known offsets (lags of both signs)
L_DEM = 0.05 + 0.1 * np.log(OMEGA_TS) + [0.01, -0.02, 0.015, -0.01, 0.02, -0.015]
L_DEM_ERR = np.array([0.02, 0.03, 0.015, 0.04, 0.025, 0.03])
L_MODEL = 0.105 * np.log(OMEGA_TS) + [0.0, 0.01, -0.01, 0.02, 0.0, -0.01]
L_NUM = np.array([0.005, 0.01, 0.008, 0.012, 0.006, 0.01])
L_CAL = np.array([0.02, 0.015, 0.02, 0.01, 0.03, 0.02])


def _wls(x, y, sd, model_y, model_sd):
    """The DEM's slope and error by numpy.polyfit (weights 1/sd, unscaled covariance), the model's slope on the same
    weights by the hat matrix (A^T W A)^-1 A^T W and its error from the model's sds, and the DEM's chi2 about its
    line."""
    (slope, intercept), cov = np.polyfit(x, y, 1, w=1 / sd, cov="unscaled")
    a, w = np.column_stack([x, np.ones_like(x)]), np.diag(1 / sd ** 2)
    hat = np.linalg.solve(a.T @ w @ a, a.T @ w)[0]
    chi2 = np.sum(((y - slope * x - intercept) / sd) ** 2)
    return slope, np.sqrt(cov[0, 0]), hat @ model_y, np.sqrt(np.sum((hat * model_sd) ** 2)), chi2


def _law_rows() -> pd.DataFrame:
    """The scorecard of six speed drives at OMEGA_TS (local predicted; NGF not: its rows are not scored)."""
    dems, predictions = [], {}
    for i, w in enumerate(OMEGA_TS):
        drive = _drive(f"speed-{i}", w)
        dems.append(_dem(drive, {"yielded_depth": (Y_DEM[i], Y_DEM_ERR[i], "how", 2),
                                 "phase_lag": (L_DEM[i], L_DEM_ERR[i], "how", 2)}))
        predictions[drive.label, "local"] = _prediction({"yielded_depth": (Y_MODEL[i], Y_NUM[i], Y_CAL[i]),
                                                         "phase_lag": (L_MODEL[i], L_NUM[i], L_CAL[i])})
    return _choices(dems, predictions)


def test_laws_are_weighted_least_squares_slopes_against_an_independent_fit():
    """The yielded depth's four points scatter about their line a little more than their errors (chi2/dof 1.10):
    its slope's error is scaled by sqrt(1.10); the lag's six points scatter less (0.52): its error is not scaled.
    Both slopes have n - 2 degrees of freedom (2 and 4)."""
    laws = osc.laws(_law_rows())
    assert len(laws) == 2 and set(laws.model) == {"local"}  # NGF's rows are not scored: no law
    # a law in omega has no window start in transits: its choices say so (None), not the Stokes default
    assert all(c["from_transits"] is None for choices in laws.choices for c in choices)
    laws = laws.set_index("law")
    x = np.log(OMEGA_TS)
    k = slice(0, 4)  # the yielded layers of both sides
    expected = {
        "yielded_depth_exponent": _wls(x[k], np.log(Y_DEM[k]), Y_DEM_ERR[k] / Y_DEM[k], np.log(Y_MODEL[k]),
                                       np.hypot(Y_NUM[k], Y_CAL[k]) / Y_MODEL[k]),
        "phase_lag_slope": _wls(x, L_DEM, L_DEM_ERR, L_MODEL, np.hypot(L_NUM, L_CAL))}
    points = {"yielded_depth_exponent": 4, "phase_lag_slope": 6}
    for law, (dem, dem_err, pred, pred_err, chi2) in expected.items():
        r = laws.loc[law]
        reduced = chi2 / (points[law] - 2)
        dem_err *= np.sqrt(max(reduced, 1.0))
        assert r.chi2_dof == pytest.approx(reduced, rel=1e-9), law
        assert r.dem == pytest.approx(dem, rel=1e-10) and r.dem_err == pytest.approx(dem_err, rel=1e-10), law
        assert r.predicted == pytest.approx(pred, rel=1e-10), law
        assert r.predicted_err == pytest.approx(pred_err, rel=1e-10), law
        s = (dem - pred) / np.sqrt(dem_err ** 2 + pred_err ** 2)
        assert r.sigma == pytest.approx(s, rel=1e-10), law
        assert r.dof == pytest.approx((dem_err ** 2 + pred_err ** 2) ** 2 / (dem_err ** 4 / (points[law] - 2)),
                                      rel=1e-10), law
        np.testing.assert_allclose(r.band, [pred - Z * pred_err, pred + Z * pred_err], rtol=1e-10)
        assert r.kind == "speed" and r.amplitude == 2.0 and r.model == "local" and r.unit == "1" and r.note == ""
    y, p = laws.loc["yielded_depth_exponent"], laws.loc["phase_lag_slope"]
    assert y.chi2_dof == pytest.approx(1.097, abs=1e-3) and p.chi2_dof == pytest.approx(0.521, abs=1e-3)
    # the offsets move the fits off the laws they were built on by less than 0.01 and 0.002
    assert y.dem == pytest.approx(-0.5, abs=0.01) and y.predicted == pytest.approx(-0.4, abs=0.02)
    assert p.dem == pytest.approx(0.1, abs=0.002) and p.predicted == pytest.approx(0.105, abs=0.005)
    # -0.50 against -0.38, errors 0.015 and 0.018: -5.2 sigma beyond t_0.975 at its dof (above 2: the model's error
    # is exact and the larger)
    assert y.sigma < -stats.t.ppf(0.975, y.dof) and y.verdict == "disagrees"
    assert abs(p.sigma) < stats.norm.ppf(0.975) and p.verdict == "consistent"
    assert (y.n_drives, y.window) == (4, "omega t_s in [0.1, 3]")
    assert (p.n_drives, p.window) == (6, "omega t_s in [0.1, 30]")
    assert y.quantity == "n in yielded_depth ~ (omega t_s)^n"
    assert p.quantity == "s in phase_lag = a + s ln(omega t_s) [rad]"


OFFSETS = np.array([0.01, -0.01, 0.0, 0.01, -0.01, 0.005])  # a known scatter about a line: an error each


def _lag_law(lags, errors, model_lags):
    """The phase-lag law of speed drives at OMEGA_TS with the DEM's ``lags`` and ``errors`` (3 beds: 2 dof)."""
    dems, predictions = [], {}
    for i, w in enumerate(OMEGA_TS):
        drive = _drive(f"speed-{i}", w)
        dems.append(_dem(drive, {"phase_lag": (lags[i], errors[i], "spread over 3 beds (std/sqrt(n))", 2)}))
        predictions[drive.label, "local"] = _prediction({"phase_lag": (model_lags[i], 0.005, 0.01)})
    return osc.laws(_choices(dems, predictions)).set_index("law").loc["phase_lag_slope"]


def test_a_lag_on_a_step_is_not_a_line_and_quotes_no_slope():
    """The DEM's lag steps from -0.1 to -0.6 between omega t_s = 1 and 3 (flat on either side, errors 0.01): a line
    through it leaves chi2/dof in the hundreds (by hand: polyfit's weighted residuals), p far below 0.01; the row is
    "not measurable: not a line" with chi2/dof and p, no slope and no sigma.  The same six drives on a line with
    residuals of about their errors give a slope, chi2/dof near 1 (0.668 by hand) and the unscaled error."""
    x = np.log(OMEGA_TS)
    err = np.full(6, 0.01)
    model = -0.1 * x
    step = np.where(OMEGA_TS < 2, -0.1, -0.6)
    r = _lag_law(step, err, model)
    (slope, intercept) = np.polyfit(x, step, 1, w=1 / err)
    chi2 = np.sum(((step - slope * x - intercept) / err) ** 2)
    p = stats.chi2.sf(chi2, 4)
    assert chi2 / 4 > 100 and p < 1e-50
    assert r.verdict == "not measurable"
    assert r.note == f"not measurable: not a line (chi2/dof = {chi2 / 4:.3g}, p = {p:.2g})"  # chi2/dof = 216
    assert r.chi2_dof == pytest.approx(chi2 / 4, rel=1e-9) and r.dof == 4 and r.n_drives == 6
    assert np.isnan([r.dem, r.dem_err, r.predicted, r.predicted_err, r.sigma]).all()
    line = 0.05 - 0.2 * x + 0.8 * OFFSETS
    r = _lag_law(line, err, model)
    (slope, intercept), cov = np.polyfit(x, line, 1, w=1 / err, cov="unscaled")
    chi2 = np.sum(((line - slope * x - intercept) / err) ** 2)
    assert chi2 / 4 == pytest.approx(0.668, abs=1e-3)
    assert r.note == "" and r.chi2_dof == pytest.approx(chi2 / 4, rel=1e-9) and r.dof > 4
    assert r.dem == pytest.approx(slope, rel=1e-10) and r.dem_err == pytest.approx(np.sqrt(cov[0, 0]), rel=1e-10)
    assert r.verdict == "disagrees"  # -0.2 against -0.1, errors 0.0021 and 0.0023


def test_a_scatter_beyond_the_errors_but_not_a_step_scales_the_slopes_error():
    """Residuals of about 1.7 errors each: chi2/dof = 3.02 by hand, p = chi2.sf(12.1, 4) = 0.017 (not below 0.01):
    a slope is quoted, its error the weighted one times sqrt(3.02)."""
    x = np.log(OMEGA_TS)
    err = np.full(6, 0.01)
    line = 0.05 - 0.2 * x + 1.7 * OFFSETS
    r = _lag_law(line, err, -0.1 * x)
    (slope, intercept), cov = np.polyfit(x, line, 1, w=1 / err, cov="unscaled")
    chi2 = np.sum(((line - slope * x - intercept) / err) ** 2)
    assert 0.01 < stats.chi2.sf(chi2, 4) < 0.05 and chi2 / 4 == pytest.approx(3.016, abs=1e-3)
    assert r.note == "" and r.chi2_dof == pytest.approx(chi2 / 4, rel=1e-9)
    assert r.dem == pytest.approx(slope, rel=1e-10)
    assert r.dem_err == pytest.approx(np.sqrt(cov[0, 0]) * np.sqrt(chi2 / 4), rel=1e-10)


def test_a_law_needs_three_measurable_drives():
    """Three stress drives at omega t_s = 1/2, 2, 8 (ln: -ln 2, ln 2, 3 ln 2): none yields, and the lag is a line
    of slope -0.05 (the model's -0.08) with constant errors, so the slope's error is sd / sqrt(Sxx), Sxx = 8 ln2^2."""
    omega_ts = np.array([0.5, 2.0, 8.0])
    dems, predictions = [], {}
    for w in omega_ts:
        drive = _drive(f"stress-{w:g}", w, "stress", 0.45)
        dems.append(_dem(drive, {"yielded_depth": (0.0, 0.05, "how", 2),
                                 "phase_lag": (0.2 - 0.05 * np.log(w), 0.02, "how", 2)}))
        predictions[drive.label, "local"] = _prediction({"yielded_depth": (0.0, 0.01, 0.01),
                                                         "phase_lag": (0.1 - 0.08 * np.log(w), 0.006, 0.008)})
    laws = osc.laws(_choices(dems, predictions)).set_index("law")
    y, p = laws.loc["yielded_depth_exponent"], laws.loc["phase_lag_slope"]
    assert y.n_drives == 0 and y.window == "" and y.verdict == "not measurable"
    assert y.note == "not measurable: 0 measurable drive(s), a slope and its error need 3"
    assert np.isnan([y.dem, y.dem_err, y.predicted, y.predicted_err, y.sigma]).all() and np.isnan(y.band).all()
    assert y.kind == "stress" and y.amplitude == 0.45 and y.quantity == "n in yielded_depth ~ (omega t_s)^n"
    root_sxx = 2 * np.sqrt(2) * np.log(2)
    assert p.n_drives == 3 and p.window == "omega t_s in [0.5, 8]" and p.note == ""
    assert p.dem == pytest.approx(-0.05, abs=1e-12) and p.dem_err == pytest.approx(0.02 / root_sxx, rel=1e-12)
    assert p.predicted == pytest.approx(-0.08, abs=1e-12)
    assert p.predicted_err == pytest.approx(0.01 / root_sxx, rel=1e-12)  # hypot(0.006, 0.008) = 0.01
    assert p.sigma == pytest.approx(0.03 / np.hypot(0.02, 0.01) * root_sxx, rel=1e-12)
    # an exact line: chi2 = 0; one degree of freedom (3 points - 2), the model's error exact: dof (4 + 1)^2/16 = 1.56,
    # so 2.63 sigma is within t_0.975(1.56) (beyond the normal 1.96)
    assert p.chi2_dof == pytest.approx(0.0, abs=1e-20) and p.dof == pytest.approx(25 / 16, rel=1e-12)
    assert stats.norm.ppf(0.975) < p.sigma < stats.t.ppf(0.975, 25 / 16)
    assert p.verdict == "consistent"
    # two drives: the lag's law is not measurable either
    two = osc.laws(_choices(dems[:2], {k: v for k, v in predictions.items() if k[0] != dems[2].drive.label}))
    two = two.set_index("law").loc["phase_lag_slope"]
    assert two.n_drives == 2 and two.verdict == "not measurable"
    # floats, also in a table where no law is measured (no None a report's number formats would choke on)
    assert np.isnan([two.dem, two.dem_err, two.predicted, two.predicted_err, two.sigma]).all()
    assert two.note == "not measurable: 2 measurable drive(s), a slope and its error need 3"
    assert two.window == "omega t_s in [0.5, 2]"


def test_a_period_under_three_transits_is_elastic_and_a_slipping_plate_s_rows_are_not_scored():
    """Period 2 pi/omega over the transit time: 2.5 transits (< TRANSITS_BEFORE_COMPARISON) leaves every row of the
    drive unscored; 4 transits scores them. A plate slipping 20 % (> SLIP_MAX) leaves every row unscored, the
    plate's observables (amplitude, lag, dissipation) and the profile's (yielded depth, remobilization strain)."""
    from granstokes.compare.drive import TRANSITS_BEFORE_COMPARISON
    from granstokes.compare.plate import SLIP_MAX
    omega_ts = 1.0
    period = 2 * np.pi / (omega_ts / T_S)
    predictions = {("runs/p20/fast", "local"): _prediction(MODEL)}
    fast = _rows([_dem(_drive("fast", omega_ts, transit_time=period / 2.5), {})], predictions)
    assert (~fast.scored[fast.model == "local"]).all()
    assert (fast[fast.model == "local"].note == "not scored: the plate's period spans 2.5 shear-wave transits of the "
            f"bed (fewer than {TRANSITS_BEFORE_COMPARISON:g}): an elastic response, which rigid-plastic models do not "
            "have").all()
    held = _rows([_dem(_drive("fast", omega_ts, transit_time=period / 4), {})], predictions)
    assert held[held.model == "local"].scored.all()
    # the elasto-plastic model has the elastic regime: its rows of the fast drive are scored, local mu(I)'s are not
    both = {**predictions, ("runs/p20/fast", "elastic"): _prediction(MODEL, "elastic")}
    elastic_setup = osc.ModelSetup(None, None, elastic_G=1e4)
    fast = _rows([_dem(_drive("fast", omega_ts, transit_time=period / 2.5), {})], both, elastic_setup)
    assert set(fast.model) == {"local", "ngf", "elastic"} and elastic_setup.models == ("local", "elastic")
    assert fast[fast.model == "elastic"].scored.all() and not fast[fast.model == "local"].scored.any()
    slipping = _rows([_dem(_drive("fast", omega_ts, transit_time=period / 4), {}, slip=4 * SLIP_MAX)], predictions)
    local = slipping[slipping.model == "local"].set_index("observable")
    assert len(local) == 5 and (~local.scored).all()
    assert local.note["phase_lag"] == ("not scored: the plate slips 20% against the grains touching it (more than 5%), "
                                      "so its speed and force are not the bed's")


# --- the estimator families -------------------------------------------------------------------------------------

def _lag_choices(primary, peak, model, errors):
    """Six speed drives at OMEGA_TS whose lag is ``primary`` for every choice but the peak's (``peak``), the model's
    ``model`` for every choice (its errors 0.005 and 0.01); 3 beds each (2 dof)."""
    lag = osc.LAW_FAMILIES["phase_lag"]
    dems, predictions = [], {}
    for i, w in enumerate(OMEGA_TS):
        drive = _drive(f"speed-{i}", w)
        dems.append(_dem(drive, {"phase_lag": (primary[i], errors[i], "how", 2)},
                         chosen={("phase_lag", c): (peak[i], errors[i], "how", 2) for c in lag
                                 if c.estimator == "peak"}))
        predictions[drive.label, "local"] = _prediction({"phase_lag": (model[i], 0.005, 0.01)})
    return dems, predictions


def test_a_law_row_carries_its_family_and_depends_on_the_estimator_when_the_choices_split():
    """The lag of six speed drives: every choice on the model's line but the peak's, whose slope is -0.3 against the
    model's -0.2.  The row's numbers are the primary's (the first harmonic against the plate's speed, after 1 cycle,
    consistent), its four choices each carry their fit (polyfit by hand), ``systematic`` is half the range of DEM -
    model over them, and the verdict "depends on the estimator" names both sides."""
    x = np.log(OMEGA_TS)
    err = np.full(6, 0.01)
    primary, peak, model = 0.05 - 0.2 * x + 0.8 * OFFSETS, 0.05 - 0.3 * x + 0.8 * OFFSETS, 0.05 - 0.2 * x
    r = osc.laws(_choices(*_lag_choices(primary, peak, model, err))).set_index("law").loc["phase_lag_slope"]
    slopes = {}
    for name, y in (("primary", primary), ("peak", peak)):
        (slope, _), cov = np.polyfit(x, y, 1, w=1 / err, cov="unscaled")
        slopes[name] = (slope, np.sqrt(cov[0, 0]))
    model_slope = np.polyfit(x, model, 1)[0]  # equal weights: the model's slope on the DEM's
    model_err = np.hypot(0.005, 0.01) / np.sqrt(np.sum((x - x.mean()) ** 2))
    assert [(c["estimator"], c["reference"], c["skip"]) for c in r.choices] == [
        ("fundamental", "plate", 1), ("fundamental", "plate", 2), ("fundamental", "contact", 1), ("peak", "plate", 1)]
    for c in r.choices:
        dem, dem_err = slopes["peak" if c["estimator"] == "peak" else "primary"]
        assert c["dem"] == pytest.approx(dem, rel=1e-10) and c["dem_err"] == pytest.approx(dem_err, rel=1e-10)
        assert c["predicted"] == pytest.approx(model_slope, rel=1e-10)
        assert c["predicted_err"] == pytest.approx(model_err, rel=1e-10)
        assert c["sigma"] == pytest.approx((dem - model_slope) / np.hypot(dem_err, model_err), rel=1e-9)
        assert c["dof"] > 4 and c["n_drives"] == 6 and c["chi2_dof"] < 1 and c["note"] == ""
    assert abs(r.choices[0]["sigma"]) < stats.t.ppf(0.975, r.choices[0]["dof"])  # the model's line
    assert r.choices[3]["sigma"] < -stats.t.ppf(0.975, r.choices[3]["dof"])  # -0.3 against -0.2
    assert r.systematic == pytest.approx(abs(slopes["primary"][0] - slopes["peak"][0]) / 2, rel=1e-10)
    assert r.dem == pytest.approx(slopes["primary"][0], rel=1e-10) and r.sigma == r.choices[0]["sigma"]
    assert r.verdict == "depends on the estimator"
    assert r.note.startswith("depends on the estimator: 3 of 4 measured choices consistent (the first harmonic's lag "
                             "against the plate's speed, after 1 cycle ")
    assert "1 disagree (the peak's lag against the plate's speed, after 1 cycle -" in r.note
    assert "the first harmonic's lag against the plate's speed, after 2 cycles" in r.note


def test_a_primary_choice_that_is_not_a_line_leaves_the_row_to_the_first_measured_choice():
    """The primary lag steps (not a line, as the scorecard's step test); the peak's is a line: the row's numbers
    are the peak's and its window says the primary is not measurable; the primary's entry keeps its "not a line"."""
    x = np.log(OMEGA_TS)
    err = np.full(6, 0.01)
    step, line = np.where(OMEGA_TS < 2, -0.1, -0.6), 0.05 - 0.2 * x + 0.8 * OFFSETS
    dems, predictions = _lag_choices(step, line, -0.2 * x, err)
    r = osc.laws(_choices(dems, predictions)).set_index("law").loc["phase_lag_slope"]
    assert [c["note"].startswith("not measurable: not a line") for c in r.choices] == [True, True, True, False]
    assert r.dem == pytest.approx(np.polyfit(x, line, 1, w=1 / err)[0], rel=1e-10)
    assert r.window == ("the primary choice (the first harmonic's lag against the plate's speed, after 1 cycle) is "
                        "not measurable; shown: the peak's lag against the plate's speed, after 1 cycle: "
                        "omega t_s in [0.1, 30]")
    assert r.verdict == "consistent" and np.isnan(r.systematic)  # one measured choice: no spread


def test_a_slipping_plate_leaves_its_choices_kept_and_unscored():
    """A plate slipping 4 SLIP_MAX: every choice of every law is kept with its numbers, those read against the
    contact layer's speed and the stress edge too, and none is scored (every model's plate grips)."""
    from granstokes.compare.plate import SLIP_MAX
    rows = _choices([_dem(_drive("slips", 1.0), {}, slip=4 * SLIP_MAX)],
                    {("runs/p20/slips", "local"): _prediction({})})
    local = rows[rows.model == "local"]
    assert len(local) == sum(len(f) for f in osc.LAW_FAMILIES.values())
    assert {"plate", "contact"} <= set(local.reference) and np.isfinite(local.dem).all()
    assert not local.scored.any()
    assert local.note.str.startswith("not scored: the plate slips 20% against the grains touching it").all()


def _plate(amplitudes, phase_, per_cycle: int = 48) -> pd.DataFrame:
    """A stress drive's plate record at omega = 1: cycle k's speed u_w = amplitudes[k] sin(t + phase_)."""
    t = np.arange(len(amplitudes) * per_cycle + 1) * 2 * np.pi / per_cycle
    k = np.minimum(np.arange(len(t)) // per_cycle, len(amplitudes) - 1)
    return pd.DataFrame({"t": t, "u_w": np.asarray(amplitudes)[k] * np.sin(t + phase_)})


def test_a_drive_whose_bed_jams_or_sits_in_another_state_keeps_its_rows_unscored():
    """Three beds of a stress drive at omega = 1 (4 cycles, the first the start-up): bed 1 jams (1.60, 0.14, 0.12
    over the kept cycles), beds 2 and 3 flow at 2.0.  Every row of the drive, scorecard and law choices, says "not
    scored: bed 1 of 3 jams (...)" with the first and last kept cycles' amplitude and phase; a second drive whose
    bed 2 creeps at 0.03 throughout, its others at 2.0, is "in another state"; a drive of periodic beds is scored."""
    drive = _drive("stress-1", 2.0, "stress", 0.45)  # omega = omega_ts / T_S = 1
    jam = [_plate([2.0, 1.6, 0.14, 0.12], 0.3), _plate([2.0] * 4, 0.3), _plate([2.0] * 4, 0.3)]
    creep = [_plate([2.0] * 4, 0.3), _plate([0.03] * 4, 0.3), _plate([2.0] * 4, 0.3)]
    mean_jam = np.mean([1.6, 0.14, 0.12]) * np.exp(0.3j)  # a bed's fundamental over its kept cycles
    beds = {}
    for name, plates, fundamentals in (("jam", jam, [mean_jam, 2 * np.exp(0.3j), 2 * np.exp(0.3j)]),
                                       ("creep", creep, [2 * np.exp(0.3j), 0.03 * np.exp(0.3j), 2 * np.exp(0.3j)]),
                                       ("flow", creep[:1] * 3, [2 * np.exp(0.3j)] * 3)):
        records = [osc.Record(p, pd.DataFrame(), pd.DataFrame()) for p in plates]
        beds[name] = osc._beds(drive, records, fundamentals)
    assert [b["periodic"] for b in beds["jam"]] == [False, True, True]
    assert beds["jam"][0]["change"] == pytest.approx(1 - 0.12 / 1.6, abs=1e-12)
    assert [b["same_state"] for b in beds["creep"]] == [True, False, True]
    # the jammed bed's mean 0.62 is also 0.69 of 2 away from the others': its note says it jams (the first reason)
    assert [b["same_state"] for b in beds["jam"]] == [False, True, True]
    said = {"jam": "not scored: bed 1 of 3 jams (response amplitude 1.6 -> 0.12 sqrt(g d), phase +0.30 -> +0.30 "
                   "rad over the kept cycles 1 to 3)",
            "creep": "not scored: bed 2 of 3 is in another state than the others (response amplitude 0.03 sqrt(g d) "
                     "against 2, 2)",
            "flow": ""}
    for name, note in said.items():
        dem = _dem(drive, {}, beds=beds[name])
        prediction = {(drive.label, "local"): _prediction({})}
        for rows in (_rows([dem], prediction), _choices([dem], prediction)):
            local = rows[rows.model == "local"]
            assert (local.note == note).all(), name
            assert (local.scored == (note == "")).all(), name


# --- the report's words -----------------------------------------------------------------------------------------

def _comparison(dems, predictions) -> osc.OscillationComparison:
    setup = osc.ModelSetup(None, None)
    rows, choices = _rows(dems, predictions, setup), _choices(dems, predictions, setup)
    return osc.OscillationComparison(("runs/p20",), setup, "", "", tuple(dems), predictions, rows, osc.laws(choices),
                                     choices)


def test_the_report_says_frequency_by_frequency_which_drives_lag_agrees_and_counts_the_unsettled_drives():
    """Four speed drives at omega t_s = 1 (two: one agrees, one 0.5 rad off its model), 3 (one agrees) and 10 (its
    bed 2 in another state: not scored).  The lag's sentence names them per frequency with their sigma; the
    periodic-state sentence counts 1 of 4 drives and quotes its note; the scene's periodic check fails for it
    alone, with that note as its detail."""
    from granstokes.compare import oscillation_report as report
    drives = [_drive("a", 1.0), _drive("b", 1.0), _drive("c", 3.0), _drive("d", 10.0)]
    odd = ({"periodic": True, "change": 0.1, "fundamental": 2.0 + 0j, "same_state": True},
           {"periodic": True, "change": 0.1, "fundamental": 0.03 + 0j, "same_state": False})
    dems = [_dem(d, {"phase_lag": (0.6 if d.name == "b" else 0.1, 0.05, BEDS4, 3)}, beds=odd if d.name == "d" else ())
            for d in drives]
    c = _comparison(dems, {(d.label, "local"): _prediction({"phase_lag": (0.1, 0.01, 0.01)}) for d in drives})
    b_sigma = 0.5 / np.sqrt(0.05 ** 2 + 2 * 0.01 ** 2)
    assert report.lag_sentences(c) == [
        f"The lag frequency by frequency, local mu(I): at omega t_s = 1, agrees for 1 of 2 scored drives (p20: a), "
        f"disagrees for p20: b (+{b_sigma:.1f} sigma); at omega t_s = 3, agrees for 1 of 1 scored drives (p20: c); "
        f"at omega t_s = 10, none of its 1 drive(s) scored."]
    said = ("bed 2 of 2 is in another state than the others (response amplitude 0.03 against 2)")
    assert report.states_sentences(c) == [
        "Periodic state: in 1 of 4 drives a bed jams, drifts or sits in another state than the others (its first "
        "harmonic moves by more than 0.5 of its amplitude over the kept cycles, or lies that far from every other "
        "bed's): p20: d (1 of 2 beds); their rows are kept, not scored."]
    assert report.states_sentences(c)[0] in report.verdict_parts(c)
    periodic = {s["drive"]: s for s in report.scene(c) if s["check"] == "periodic"}
    assert periodic["runs/p20/d"]["holds"] is False and periodic["runs/p20/d"]["detail"] == said
    assert periodic["runs/p20/a"]["holds"] is None  # no bed's state known (the synthetic drive has none)


def test_the_law_sentences_give_the_family_s_spread_and_say_when_a_law_is_not_a_line():
    """The six speed drives' lag on a line (choices split as above) reads with its chi2/dof, its systematic and
    its 4 choices; a lag that steps for every choice reads "not a line" with its chi2/dof."""
    from granstokes.compare import oscillation_report as report
    x = np.log(OMEGA_TS)
    err = np.full(6, 0.01)
    line, peak = 0.05 - 0.2 * x + 0.8 * OFFSETS, 0.05 - 0.3 * x + 0.8 * OFFSETS
    c = _comparison(*_lag_choices(line, peak, 0.05 - 0.2 * x, err))
    r = c.laws.set_index("law").loc["phase_lag_slope"]
    lag = next(p for p in report.law_sentences(c) if p.startswith("lag of the response"))
    assert lag.startswith("lag of the response against the frequency (slope in ln omega t_s), s in phase_lag = a + "
                          "s ln(omega t_s) [rad] (imposed speed, amplitude 2, 6 drives): DEM ")
    assert f"(chi2/dof {r.chi2_dof:.2g}; systematic {r.systematic:.4g} over 4 estimator choices)" in lag
    assert "local mu(I)" in lag and "(depends on the estimator, " in lag
    step = np.where(OMEGA_TS < 2, -0.1, -0.6)
    c = _comparison(*_lag_choices(step, step, -0.2 * x, err))
    r = c.laws.set_index("law").loc["phase_lag_slope"]
    lag = next(p for p in report.law_sentences(c) if p.startswith("lag of the response"))
    assert lag.endswith(f"(imposed speed, amplitude 2, 6 drives): not a line (chi2/dof = {r.chi2_dof:.3g}, "
                        f"p = {stats.chi2.sf(r.chi2_dof * 4, 4):.2g}).")


def test_a_choice_row_reads_the_model_s_estimate_for_that_choice():
    """The model predicts the peak's lag 0.3 (+- 0.01, 0.02) and 1.0 for its scorecard lag: the peak choice's row
    carries 0.3 and sigma (1 - 0.3)/sqrt(0.1^2 + 0.01^2 + 0.02^2) against the DEM's 1 +- 0.1."""
    peak = next(c for c in osc.LAW_FAMILIES["phase_lag"] if c.estimator == "peak")
    pred = _prediction({}, chosen={("phase_lag", peak): (0.3, 0.01, 0.02)})
    rows = _choices([_dem(_drive("peak", 1.0), {})], {("runs/p20/peak", "local"): pred})
    r = rows[(rows.model == "local") & (rows.observable == "phase_lag") & (rows.estimator == "peak")].iloc[0]
    assert r.predicted == 0.3 and r.scored
    assert r.sigma == pytest.approx(0.7 / np.sqrt(0.1 ** 2 + 0.01 ** 2 + 0.02 ** 2), rel=1e-12)


def test_an_edge_at_the_deepest_plane_censors_only_the_edge_s_choices():
    """The yielded edge reaches the deepest plane: the yielded depth's choices read off the edge are not measurable,
    those read at a speed fraction (delta_50, delta_20) are scored."""
    rows = _choices([_dem(_drive("deep", 1.0), {}, deepest_edge=PLANES.max())],
                    {("runs/p20/deep", "local"): _prediction({})})
    depth = rows[(rows.model == "local") & (rows.observable == "yielded_depth")]
    assert len(depth) == len(osc.LAW_FAMILIES["yielded_depth"])
    for r in depth.itertuples():
        assert r.scored == (r.estimator != "edge"), r.estimator
        if r.estimator == "edge":
            assert r.note.startswith("not measurable: at some phase the bed yields down to its deepest plane")


def test_a_period_of_exactly_three_transits_and_a_slip_of_exactly_slip_max_are_scored():
    """The edges belong to the scored side: transits = TRANSITS_BEFORE_COMPARISON and slip = SLIP_MAX."""
    from granstokes.compare.drive import TRANSITS_BEFORE_COMPARISON
    from granstokes.compare.plate import SLIP_MAX
    period = 2 * np.pi / (1.0 / T_S)
    transit = period / TRANSITS_BEFORE_COMPARISON
    assert period / transit == TRANSITS_BEFORE_COMPARISON  # exact in floating point, checked here
    rows = _rows([_dem(_drive("edge", 1.0, transit_time=transit), {}, slip=SLIP_MAX)],
                 {("runs/p20/edge", "local"): _prediction(MODEL)})
    local = rows[rows.model == "local"]
    assert local.scored.all() and (local.note == "").all()
