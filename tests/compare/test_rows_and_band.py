"""The row makers and the calibration band (compare/rows.py, compare/band.py) against answers built by hand.

Rows: a row's keys come in ROW_KEYS / LAW_KEYS order with the experiment's own after them, its verdict and scored
flag follow its note, a row that lacks a key is refused naming it. Band: for a prediction linear in the parameters,
F(t) = a(t) . p, the standard deviation at each t is sqrt(a(t) C a(t)) whatever the step (written out with loops
here, not with the einsum of the code); a zero-valued parameter is shifted by STEP itself; a derivative that is not
finite makes the sd NaN; a phase's difference is taken wrapped when the caller asks for it.
"""
import numpy as np
import pandas as pd
import pytest
from granstokes.compare import band, rows

SCORE_FIELDS = {"drive": "D1", "observable": "u_w_inf", "unit": "sqrt(g d)", "dem": 1.0, "dem_err": 0.1,
                "dem_how": "seeds", "model": "local", "model_label": "local mu(I)", "predicted": 0.8,
                "band": [0.7, 0.9], "numerical_err": 0.0, "calibration_sd": 0.05}


def test_a_score_row_takes_its_verdict_and_scored_flag_from_sigma_and_note():
    row = rows.score_row(**SCORE_FIELDS, sigma=2.5, blind=True, note="", asymptote=0.81)
    assert list(row) == [*rows.ROW_KEYS, "asymptote"]
    assert (row["verdict"], row["scored"], row["asymptote"]) == ("disagrees", True, 0.81)
    kept = rows.score_row(**SCORE_FIELDS, sigma=2.5, blind=True, note="not scored: the flow reaches the base")
    assert (kept["verdict"], kept["scored"]) == ("not scored", False)
    assert rows.score_row(**SCORE_FIELDS, sigma=-1.9, blind=True, note="")["verdict"] == "consistent"


def test_a_row_without_one_of_its_keys_is_refused_naming_it():
    fields = {k: v for k, v in SCORE_FIELDS.items() if k not in ("unit", "dem_how")}
    with pytest.raises(KeyError, match=r"a row needs \['unit', 'dem_how', 'blind'\]"):
        rows.score_row(**fields, sigma=0.0, note="")


def test_a_law_row_without_a_note_is_judged_by_sigma_and_gets_its_band():
    law = rows.law_row(law="t90 ~ t_s", quantity="slope", unit="1", model="local", dem=1.0, dem_err=0.1,
                       predicted=1.2, predicted_err=0.05, sigma=-2.1, n_drives=4, window="all", note="",
                       choices=[], systematic=np.nan, extra="kept")
    assert list(law) == [*rows.LAW_KEYS, "extra"]
    assert law["verdict"] == "disagrees"
    assert law["band"] == pytest.approx([1.2 - rows.Z95 * 0.05, 1.2 + rows.Z95 * 0.05], rel=1e-15)
    assert rows.law_row(**{**law, "sigma": 0.3})["verdict"] == "consistent"
    assert rows.law_row(**{**law, "note": "not measurable: one drive"})["verdict"] == "not measurable"
    split = rows.law_row(**{**law, "note": f"{rows.ESTIMATOR_DEPENDENT}: 1 of 2 measured choices consistent"})
    assert split["verdict"] == "depends on the estimator"
    with pytest.raises(ValueError, match="must start with one of"):
        rows.law_row(**{**law, "note": "depends on the weather"})
    assert rows.verdict(-2.0) == "consistent" and rows.verdict(2.0 + 1e-12) == "disagrees"


def _linear(cov):
    """F(t; x, y) = x sin t + y t at x = 1.5, y = 0.7 (a linear prediction: its sd is exact)."""
    t = np.linspace(0.0, 3.0, 7)
    sens = band.Sensitivity.of(lambda q: q["x"] * np.sin(t) + q["y"] * t, {"x": 1.5, "y": 0.7}, cov)
    return t, sens, 1.5 * np.sin(t) + 0.7 * t


def test_the_band_of_a_linear_series_is_sqrt_a_c_a_at_every_point():
    cov = pd.DataFrame([[0.04, 0.01], [0.01, 0.09]], index=["x", "y"], columns=["x", "y"])
    t, sens, central = _linear(cov)
    assert sens.names == ("x", "y") and sens.steps == pytest.approx((band.STEP * 1.5, band.STEP * 0.7))
    sd = sens.series_sd(lambda j: sens.shifted[j], central)
    c = cov.to_numpy()
    for k, tk in enumerate(t):
        a = np.array([np.sin(tk), tk])
        assert sd[k] == pytest.approx(np.sqrt(a[0] * a[0] * c[0, 0] + 2 * a[0] * a[1] * c[0, 1]
                                              + a[1] * a[1] * c[1, 1]), rel=1e-8, abs=1e-12)
    assert sd[0] == pytest.approx(0.0, abs=1e-12)  # F(0) = 0 whatever the parameters


def test_a_parameter_the_covariance_lacks_has_no_variance():
    cov = pd.DataFrame([[0.04]], index=["x"], columns=["x"])
    t, sens, central = _linear(cov)
    assert sens.cov.tolist() == [[0.04, 0.0], [0.0, 0.0]]
    assert sens.series_sd(lambda j: sens.shifted[j], central) == pytest.approx(0.2 * np.abs(np.sin(t)), rel=1e-8,
                                                                               abs=1e-12)


def test_a_zero_valued_parameter_is_shifted_by_the_step_itself():
    """F = q^2 at q = 0: the one-sided difference is (STEP^2 - 0)/STEP = STEP, so sd = STEP sqrt(C)."""
    cov = pd.DataFrame([[0.25]], index=["q"], columns=["q"])
    sens = band.Sensitivity.of(lambda p: p["q"] ** 2, {"q": 0.0}, cov)
    assert sens.steps == (band.STEP,)
    assert sens.sd_of(lambda j: sens.shifted[j], 0.0) == pytest.approx(band.STEP * 0.5, rel=1e-12)


def test_a_derivative_that_is_not_finite_makes_the_sd_nan():
    sens = band.Sensitivity(("x", "y"), (0.01, 0.01), np.eye(2), (1.0, np.nan))
    assert np.isnan(sens.sd_of(lambda j: sens.shifted[j], 1.0))
    assert sens.sd([3.0, 4.0]) == pytest.approx(5.0)


def test_a_phase_s_derivative_is_taken_wrapped_when_asked():
    """A phase at pi - 0.005 shifted across the cut to -pi + 0.005: a change of 0.01, not 2 pi - 0.01."""
    sens = band.Sensitivity(("x",), (0.1,), np.array([[0.04]]), (-np.pi + 0.005,))
    wrapped = sens.sd_of(lambda j: sens.shifted[j], np.pi - 0.005,
                         difference=lambda a, b: (a - b + np.pi) % (2 * np.pi) - np.pi)
    assert wrapped == pytest.approx(0.01 / 0.1 * 0.2, rel=1e-9)
    assert sens.sd_of(lambda j: sens.shifted[j], np.pi - 0.005) == pytest.approx((2 * np.pi - 0.01) / 0.1 * 0.2,
                                                                                 rel=1e-9)
