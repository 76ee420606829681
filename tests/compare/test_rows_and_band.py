"""The row makers and the calibration band (compare/rows.py, compare/band.py) against answers built by hand.

Rows: a row's keys come in ROW_KEYS / LAW_KEYS order with the experiment's own after them, its verdict and scored
flag follow its note, a row that lacks a key is refused naming it.  Small samples: the verdict's threshold is
Student-t's 97.5 % quantile at the row's degrees of freedom (scipy's t.ppf, called here), the normal one at infinitely
many; a sigma between 1.96 and t_0.975(2) = 4.30 is consistent on 3 samples and disagrees at infinite dof; the
Welch-Satterthwaite degrees of freedom of a sum of errors are written out on a hand example.  Band: for a prediction
linear in the parameters, F(t) = a(t) . p, the standard deviation at each t is sqrt(a(t) C a(t)) whatever the step
(written out with loops here, not with the einsum of the code); a zero-valued parameter is shifted by STEP itself; a
derivative that is not finite makes the sd NaN; a phase's difference is taken wrapped when the caller asks for it.
"""
import numpy as np
import pandas as pd
import pytest
from granstokes.compare import band, rows
from scipy import stats

SCORE_FIELDS = {"drive": "D1", "observable": "u_w_inf", "unit": "sqrt(g d)", "dem": 1.0, "dem_err": 0.1,
                "dem_how": "seeds", "model": "local", "model_label": "local mu(I)", "predicted": 0.8,
                "band": [0.7, 0.9], "numerical_err": 0.0, "calibration_sd": 0.05, "dof": np.inf}


def test_a_score_row_takes_its_verdict_and_scored_flag_from_sigma_and_note():
    row = rows.score_row(**SCORE_FIELDS, sigma=2.5, blind=True, note="", asymptote=0.81)
    assert list(row) == [*rows.ROW_KEYS, "asymptote"]
    assert (row["verdict"], row["scored"], row["asymptote"]) == ("disagrees", True, 0.81)
    kept = rows.score_row(**SCORE_FIELDS, sigma=2.5, blind=True, note="not scored: the flow reaches the base")
    assert (kept["verdict"], kept["scored"]) == ("not scored", False)
    assert rows.score_row(**SCORE_FIELDS, sigma=-1.9, blind=True, note="")["verdict"] == "consistent"


def test_a_row_without_one_of_its_keys_is_refused_naming_it():
    fields = {k: v for k, v in SCORE_FIELDS.items() if k not in ("unit", "dem_how", "dof")}
    with pytest.raises(KeyError, match=r"a row needs \['unit', 'dem_how', 'dof', 'blind'\]"):
        rows.score_row(**fields, sigma=0.0, note="")


def test_a_law_row_without_a_note_is_judged_by_sigma_and_gets_its_band():
    law = rows.law_row(law="t90 ~ t_s", quantity="slope", unit="1", kind="stress", model="local", dem=1.0,
                       dem_err=0.1, predicted=1.2, predicted_err=0.05, sigma=-2.1, dof=np.inf, chi2_dof=0.8,
                       n_drives=4, window="all", note="", choices=[], systematic=np.nan, extra="kept")
    assert list(law) == [*rows.LAW_KEYS, "extra"]
    assert law["verdict"] == "disagrees" and (law["kind"], law["chi2_dof"]) == ("stress", 0.8)
    assert law["band"] == pytest.approx([1.2 - rows.Z95 * 0.05, 1.2 + rows.Z95 * 0.05], rel=1e-15)
    assert rows.law_row(**{**law, "sigma": 0.3})["verdict"] == "consistent"
    assert rows.law_row(**{**law, "dof": 2})["verdict"] == "consistent"  # -2.1 within t_0.975(2) = 4.30
    assert rows.law_row(**{**law, "note": "not measurable: one drive"})["verdict"] == "not measurable"
    split = rows.law_row(**{**law, "note": f"{rows.ESTIMATOR_DEPENDENT}: 1 of 2 measured choices consistent"})
    assert split["verdict"] == "depends on the estimator"
    with pytest.raises(ValueError, match="must start with one of"):
        rows.law_row(**{**law, "note": "depends on the weather"})
    z = stats.norm.ppf(0.975)
    assert rows.verdict(-z) == "consistent" and rows.verdict(z + 1e-12) == "disagrees"
    assert rows.verdict(-2.0) == "disagrees"  # beyond 1.96 at infinite dof


def test_the_threshold_is_student_t_at_the_rows_dof_and_normal_at_infinite_dof():
    for dof in (1, 2, 3, 4.6, 30):
        assert rows.critical(dof) == pytest.approx(stats.t.ppf(0.975, dof), rel=1e-12), dof
    assert rows.critical(np.inf) == pytest.approx(stats.norm.ppf(0.975), rel=1e-12)
    assert rows.critical(2) == pytest.approx(4.303, abs=1e-3) and rows.critical(3) == pytest.approx(3.182, abs=1e-3)
    for bad in (0, -1, np.nan):
        with pytest.raises(ValueError, match="positive degrees of freedom"):
            rows.critical(bad)


def _sample_row(values, predicted):
    """A row whose only error is the DEM's: the mean of ``values`` and its standard error, n - 1 dof."""
    v = np.asarray(values, dtype=float)
    n = len(v)
    mean = v.sum() / n
    err = np.sqrt(((v - mean) ** 2).sum() / (n - 1) / n)
    dof = rows.effective_dof((err, 0.0, 0.0), (n - 1, np.inf, np.inf))
    fields = {**SCORE_FIELDS, "dem": mean, "dem_err": err, "predicted": predicted, "calibration_sd": 0.0, "dof": dof}
    return rows.score_row(**fields, sigma=rows.sigma(mean - predicted, err, 0.0, 0.0), blind=True,
                          note=""), (mean - predicted) / err


def test_a_verdict_on_three_and_on_four_samples_uses_their_t_quantile():
    """Three samples 1.0, 1.2, 1.4 (mean 1.2, error 0.2/sqrt(3)) against 0.8: sigma 2 sqrt(3) = 3.46, beyond the
    normal 1.96 but within t_0.975(2) = 4.30: consistent.  Four samples 1.0, 1.2, 1.4, 1.2 against 0.95: sigma
    0.25/(0.1633/2) = 3.06, within t_0.975(3) = 3.18: consistent; against 0.93 (3.31): disagrees."""
    three, s3 = _sample_row([1.0, 1.2, 1.4], 0.8)
    assert s3 == pytest.approx(2 * np.sqrt(3), rel=1e-12) and three["sigma"] == pytest.approx(s3, rel=1e-12)
    assert three["dof"] == 2 and stats.norm.ppf(0.975) < s3 < stats.t.ppf(0.975, 2)
    assert three["verdict"] == "consistent"
    assert rows.score_row(**{**three, "dof": np.inf})["verdict"] == "disagrees"
    four, s4 = _sample_row([1.0, 1.2, 1.4, 1.2], 0.95)
    assert four["dof"] == 3 and s4 == pytest.approx(0.25 / (np.sqrt(0.08 / 3) / 2), rel=1e-12)
    assert stats.norm.ppf(0.975) < s4 < stats.t.ppf(0.975, 3) and four["verdict"] == "consistent"
    far, s_far = _sample_row([1.0, 1.2, 1.4, 1.2], 0.93)
    assert stats.t.ppf(0.975, 3) < s_far < stats.t.ppf(0.975, 2) and far["verdict"] == "disagrees"


def test_welch_satterthwaite_on_a_hand_example():
    """Errors 0.3 (2 dof), 0.4 (3 dof) and 0.12 (exact): (0.09 + 0.16 + 0.0144)^2 / (0.0081/2 + 0.0256/3) = 5.556."""
    nu = rows.effective_dof((0.3, 0.4, 0.12), (2, 3, np.inf))
    assert nu == pytest.approx(0.2644 ** 2 / (0.0081 / 2 + 0.0256 / 3), rel=1e-12)
    assert nu == pytest.approx(5.5555, abs=1e-3)
    assert rows.effective_dof((0.3,), (2,)) == pytest.approx(2.0, rel=1e-12)  # one error: its own dof
    assert rows.effective_dof((0.3, 0.3), (2, 2)) == pytest.approx(4.0, rel=1e-12)  # two equal: the sum
    assert rows.effective_dof((0.3, 0.0), (2, 1)) == pytest.approx(2.0, rel=1e-12)  # a zero error adds nothing
    assert np.isinf(rows.effective_dof((0.3, 0.1), (np.inf, np.inf)))  # exact errors: the normal limit
    assert np.isinf(rows.effective_dof((0.0, 0.1), (3, np.inf)))
    assert np.isnan(rows.effective_dof((np.nan, 0.1), (3, np.inf)))


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
    correlated = band.Sensitivity(("x", "y"), (0.01, 0.01), np.array([[1.0, 0.5], [0.5, 1.0]]), (1.0, np.inf))
    assert np.isnan(correlated.sd_of(lambda j: correlated.shifted[j], 1.0))  # an infinite one too, not inf


def test_a_phase_s_derivative_is_taken_wrapped_when_asked():
    """A phase at pi - 0.005 shifted across the cut to -pi + 0.005: a change of 0.01, not 2 pi - 0.01."""
    sens = band.Sensitivity(("x",), (0.1,), np.array([[0.04]]), (-np.pi + 0.005,))
    wrapped = sens.sd_of(lambda j: sens.shifted[j], np.pi - 0.005,
                         difference=lambda a, b: (a - b + np.pi) % (2 * np.pi) - np.pi)
    assert wrapped == pytest.approx(0.01 / 0.1 * 0.2, rel=1e-9)
    assert sens.sd_of(lambda j: sens.shifted[j], np.pi - 0.005) == pytest.approx((2 * np.pi - 0.01) / 0.1 * 0.2,
                                                                                 rel=1e-9)
