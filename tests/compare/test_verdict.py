"""Verdicts a referee accepts: a fit that does not determine its law predicts nothing, models are ranked
over the rows they share, only blind scored rows count, and a drive whose flow reaches the base has its
layer rows (and every row of the half-space model) left unscored."""
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from granstokes.compare.scorecard import Measured, _not_scored, _unmeasurable, base_reach, headline, tally
from granstokes.continuum.calibration import IN_DRIVE, JOP_BOUNDS, from_replicates
from granstokes.continuum.scene_models import LOCAL, PAPER
from scipy import stats


def _row(drive, observable, model, sigma, scored=True, blind=True):
    return {"drive": drive, "observable": observable, "model": model, "model_label": f"{model} model",
            "sigma": sigma, "scored": scored, "blind": blind, "note": "" if scored else "not scored: why",
            "verdict": "not scored" if not scored else "consistent" if abs(sigma) <= stats.norm.ppf(0.975)
            else "disagrees"}


def test_models_are_ranked_over_the_rows_they_share_only():
    # the paper's model has no creep row; local mu(I) fails exactly there: over all rows local would look worse
    rows = pd.DataFrame([
        _row("a", "u_w_inf", "local", 0.5), _row("a", "delta_u", "local", 1.0), _row("a", "creep_length", "local", 9.0),
        _row("a", "u_w_inf", "paper", 2.5), _row("a", "delta_u", "paper", 3.0),
    ])
    t = tally(rows)
    assert list(t.model) == ["local", "paper"] and list(t.n) == [2, 2] and list(t.consistent) == [2, 0]
    assert t.median_abs_sigma.tolist() == pytest.approx([0.75, 2.75])
    text = headline(rows, blind=True, failure="", n_drives=1)
    assert "on the 2 row(s) the models share" in text and text.endswith("the DEM supports local model best.")


def test_rows_not_scored_or_not_blind_never_count():
    rows = pd.DataFrame([
        _row("a", "u_w_inf", "local", 0.5), _row("a", "delta_u", "local", 0.2, scored=False),
        _row("a", "u_w_inf", "ngf", 0.1, blind=False), _row("b", "u_w_inf", "local", 5.0),
    ])
    t = tally(rows)
    assert list(t.model) == ["local"] and int(t.n.iloc[0]) == 2 and int(t.consistent.iloc[0]) == 1
    text = headline(rows, blind=True, failure="", n_drives=2)
    assert "no ranking" in text and "1 row(s) not scored" in text
    fitted = headline(rows, blind=False, failure="", n_drives=2)
    assert fitted.startswith("No verdict") and "fitted on the drives" in fitted


def test_a_fit_at_a_bound_or_spanning_its_range_is_a_failed_fit():
    def calibration(mu_s, mu_d, I0, spread):
        rng = np.random.default_rng(1)
        reps = np.column_stack([np.clip(rng.normal(v, s, 400), lo, hi) for v, s, lo, hi in
                                zip((mu_s, mu_d, I0), spread, *JOP_BOUNDS)]
                               + [np.full(400, x) for x in (0.3, 1.0, 0.8, 0.3)])
        return from_replicates([mu_s, mu_d, I0, 0.3, 1.0, 0.8, 0.3], reps, pd.DataFrame(), IN_DRIVE, "test", 0.01)

    assert calibration(0.28, 0.62, 0.3, (0.005, 0.01, 0.02)).failure == ""
    degenerate = calibration(1.2e-14, 0.42, 0.007, (0.1, 0.01, 0.001)).failure  # the smoke's in-drive fit
    assert degenerate.startswith("mu_s = 1.2e-14") and "bound" in degenerate
    assert "mu_d" in calibration(0.28, 0.62, 0.3, (0.005, 0.8, 0.02)).failure  # mu_d's interval spans [0, 3]
    assert "I0_dem" in calibration(0.28, 0.62, 0.3, (0.005, 0.01, 20.0)).failure
    assert "no mu(I) law" in calibration(0.5, 0.45, 0.3, (0.005, 0.01, 0.02)).failure


def _drive(depth_of_layer, bed=12.0):
    """A steady profile decaying linearly to zero at ``depth_of_layer`` below the plate (u_w = 1)."""
    depth = np.linspace(-0.5, bed, 126)
    u = np.clip(1 - depth / depth_of_layer, 0, 1)
    return SimpleNamespace(steady_profile=pd.DataFrame({"depth": depth, "u_x": u}), spec=SimpleNamespace(depth=bed))


def test_a_drive_whose_layer_reaches_the_base_is_flagged_and_its_layer_rows_unscored():
    assert base_reach(_drive(5.0), delta_s=4.0) == ""
    deep = base_reach(_drive(11.0), delta_s=9.3)  # delta_u = 0.95 x 11 d = 10.45 d in a 12 d bed: the smoke drive
    assert "reaches the base" in deep and "10.4 d" in deep
    assert "reaches the base" in base_reach(_drive(5.0), delta_s=10.5)  # the calibrated layer reaches it
    assert "stays above 5 %" in base_reach(_drive(40.0), delta_s=9.0)
    assert _not_scored("delta_u", LOCAL, deep, 1.0, 1.0).startswith("not scored: the flow reaches the base")
    assert _not_scored("u_w_inf", LOCAL, deep, 1.0, 1.0) == ""
    assert "half-space" in _not_scored("t90", PAPER, deep, 1.0, 1.0)
    short = _not_scored("u_w_inf", LOCAL, "", 0.9, 1.0)
    assert "-10%" in short and "shorter than the model's time scale" in short
    assert _not_scored("t90", LOCAL, "", 0.9, 1.0) == ""


def test_models_consistent_on_as_many_rows_are_not_separated_and_a_model_without_shared_rows_is_named():
    """local and NGF each consistent on their one shared row: a tie, whatever their median |sigma| (0.5 against 0.6
    separates nothing); NGF disagreeing there makes local the best."""
    rows = pd.DataFrame([_row("a", "u_w_inf", "local", 0.5), _row("a", "u_w_inf", "ngf", -0.6),
                         _row("a", "u_w_inf", "paper", 0.4, scored=False)])
    text = headline(rows, blind=True, failure="", n_drives=1)
    assert "the DEM does not separate local model, ngf model (each consistent on 1 of 1)" in text
    assert "supports" not in text
    assert "not ranked (no scored blind row shared with the others): paper model" in text
    rows.loc[1, ["sigma", "verdict"]] = [-4.0, "disagrees"]
    assert "the DEM supports local model best;" in headline(rows, blind=True, failure="", n_drives=1)


def test_a_fit_with_a_non_finite_value_or_interval_is_a_failed_fit():
    reps = np.column_stack([np.full(50, x) for x in (0.28, 0.62, 0.3, 0.3, 1.0, 0.8, 0.3)])
    reps[:, 1] = np.nan  # every replicate of mu_d undefined: its interval is nan
    cal = from_replicates([0.28, 0.62, 0.3, 0.3, 1.0, 0.8, 0.3], reps, pd.DataFrame(), IN_DRIVE, "test", 0.01)
    assert cal.failure.startswith("mu_d = 0.62") and "not a finite number" in cal.failure


def test_a_model_at_rest_in_its_steady_state_is_judged_without_dividing_by_zero():
    assert _not_scored("u_w_inf", LOCAL, "", 0.0, 0.0) == ""
    moving = _not_scored("u_w_inf", LOCAL, "", 0.2, 0.0)
    assert "still moves" in moving and "nan" not in moving


def test_a_row_without_a_dem_error_or_a_band_is_not_scored():
    assert _unmeasurable(Measured(1.0, 0.1, "seeds", 2), 0.9, 1.1, 0.1) == ""
    assert _unmeasurable(Measured(1.0, np.nan, "one seed", np.nan), 0.9, 1.1, np.nan).startswith(
        "not measurable: no DEM error")
    assert "no calibration replicate" in _unmeasurable(Measured(1.0, 0.1, "seeds", 2), np.nan, np.nan, np.nan)
    assert "sigma is undefined" in _unmeasurable(Measured(1.0, 0.0, "seeds", 2), 1.0, 1.0, 0.0)


def test_the_paper_s_predictions_in_words_come_from_its_model_s_law_rows():
    """Supported and refuted laws with their sigma (the paper's model's rows only), then what the scene cannot
    decide with its reason; the other models' rows do not enter the sentence."""
    from granstokes.compare.report import laws_verdict

    def law(name, model, verdict, dem=1.0, err=0.1, predicted=1.0, sigma=0.0, note=""):
        return {"law": name, "quantity": "q", "model": model, "verdict": verdict, "dem": dem, "dem_err": err,
                "predicted": predicted, "sigma": sigma, "note": note}

    rows = pd.DataFrame([law("a", "paper", "consistent", 0.52, 0.04, 0.5, 0.5),
                         law("b", "paper", "disagrees", 1.75, 0.03, 0.72, 12.9),
                         law("c", "paper", "not measurable", np.nan, np.nan, np.nan, np.nan,
                             "not measurable: 2 drives"),
                         law("d", "local", "disagrees", 9.0, 0.1, 1.0, 80.0)])
    assert laws_verdict(SimpleNamespace(laws=rows)) == {
        "supports": ["a (q): DEM 0.520 ± 0.040 against 0.5, +0.5 sigma"],
        "refutes": ["b (q): DEM 1.750 ± 0.030 against 0.72, +12.9 sigma"], "cannot decide": ["c (q): 2 drives"]}
    rows.loc[1, "predicted"] = -2.7e-15  # round-off of an exact zero prints as zero
    assert laws_verdict(SimpleNamespace(laws=rows))["refutes"] == ["b (q): DEM 1.750 ± 0.030 against 0, +12.9 sigma"]
