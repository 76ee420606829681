"""The laws' small estimators (compare.laws ``_slope``, ``local_exponents``, ``in_regime``, ``plateau_change``, the
growth window's start and the growth law's reasons) against answers worked out by hand, on made-up samples and
drives (SimpleNamespace objects carrying only what the functions read; no record, no solver).

* y = c t^n exactly: the log-log slope and every local exponent is n (log-log interpolation of a power law is exact);
  samples that are not positive and finite (t <= 0, y <= 0, NaN, inf, None) are set in the window, next to its
  edges, and must change nothing (a sample at t = 0 does not make the window's first piece resolved); two samples
  are enough, one gives a NaN per piece; a piece beyond the samples is NaN, a window
  whose ends are the first and last samples is resolved to its ends; ln x spanning exactly 1 (x = 1, e) is a span;
* in_regime's reasons are compared as whole sentences, written out here ("[10, 1e+03]" and "2 decades" by hand);
* plateau_change: (mu_w - mu_s)/Dmu = a + b t on exactly MIN_POINTS samples of the window, both ends included, other
  values outside it: |b| (t1 - t0) / |a + b (t0 + t1)/2|.

Constants (MIN_POINTS, REGIME_PIECES, TRANSITS_BEFORE_COMPARISON, GROWTH_END) are imported from their modules.
"""
from types import SimpleNamespace as NS

import numpy as np
import pytest
from granstokes.compare.drive import TRANSITS_BEFORE_COMPARISON
from granstokes.compare.families import LAYER_ESTIMATORS, PRIMARY_ESTIMATOR, Choice
from granstokes.compare.laws import (
    GROWTH_END,
    MIN_POINTS,
    REGIME_PIECES,
    Window,
    _slope,
    growth,
    growth_window,
    in_regime,
    local_exponents,
    plateau_change,
)

#: samples no power law has: x <= 0, y <= 0, not finite (t, y)
BAD = [(-1.0, 2.0), (3.0, np.inf), (30.0, np.nan), (0.0, 2.0), (105.0, 0.0), (np.inf, 2.0), (np.nan, 2.0)]


def _with_bad(t, y):
    bt, by = zip(*BAD, strict=True)
    return np.concatenate([t, bt]), np.concatenate([y, by])


def test_the_log_log_slope_reads_only_positive_finite_pairs():
    x, y = _with_bad(np.array([1.0, 2.0, 4.0, 8.0, 50.0]), 3.0 * np.array([1.0, 2.0, 4.0, 8.0, 50.0]) ** 0.7)
    assert _slope(x, y) == pytest.approx(0.7, abs=1e-12)


def test_the_log_log_slope_of_two_points_or_a_unit_log_span_is_defined_and_of_none_is_not():
    assert _slope([1.0, 4.0], [2.0, 8.0]) == pytest.approx(1.0, abs=1e-12)
    assert _slope([1.0, np.e], [1.0, np.exp(0.5)]) == pytest.approx(0.5, abs=1e-12)  # ln x spans exactly 1
    assert np.isnan(_slope([0.0, -1.0], [1.0, 1.0]))


def test_local_exponents_of_a_power_law_ignore_samples_that_are_not_positive_and_finite():
    t = np.geomspace(0.5, 2000.0, 30)
    t, y = _with_bad(t, 2.0 * t**0.5)
    np.testing.assert_allclose(local_exponents(t, y, 1.0, 1000.0), np.full(REGIME_PIECES, 0.5), atol=1e-12)
    # gaps given as None (a table read with missing values) are not samples either
    gappy_t, gappy_y = [*t, None, 7.0], [*y, 1.0, None]
    np.testing.assert_allclose(local_exponents(gappy_t, gappy_y, 1.0, 1000.0), [0.5] * REGIME_PIECES, atol=1e-12)


def test_a_sample_at_t_zero_does_not_extend_the_samples_to_the_window_s_start():
    t = np.geomspace(2.0, 1000.0, 12)  # edges 1, 10, 100, 1000: the first piece starts before the samples
    k = local_exponents(np.r_[0.0, t], np.r_[5.0, t**0.5], 1.0, 1000.0, pieces=3)
    assert np.isnan(k[0])
    np.testing.assert_allclose(k[1:], [0.5, 0.5], atol=1e-12)


def test_local_exponents_are_nan_beyond_the_samples_and_resolved_up_to_their_ends():
    t = np.geomspace(1.0, 100.0, 9)
    k = local_exponents(t, t**0.5, 1.0, 1000.0, pieces=3)  # edges 1, 10, 100, 1000: the last piece has no samples
    np.testing.assert_allclose(k[:2], [0.5, 0.5], atol=1e-12)
    assert np.isnan(k[2])
    t = np.geomspace(1.0, 1000.0, 7)  # the first and last samples are the window's ends
    np.testing.assert_allclose(local_exponents(t, t**0.25, 1.0, 1000.0, pieces=3), [0.25] * 3, atol=1e-12)


def test_two_samples_give_local_exponents_and_one_gives_a_nan_per_piece():
    np.testing.assert_allclose(local_exponents([1.0, 1000.0], [1.0, 1000.0**0.5], 1.0, 1000.0, pieces=3),
                               [0.5] * 3, atol=1e-12)
    k = local_exponents([5.0], [1.0], 1.0, 1000.0, pieces=3)
    assert k.shape == (3,) and np.isnan(k).all()


def test_in_regime_says_the_model_has_no_curve_and_keeps_an_earlier_reason():
    t = np.geomspace(1.0, 1000.0, 20)
    assert in_regime(Window(1.0, 100.0), t, None, "speeds") == Window(1.0, 100.0, "the model has no speeds")
    assert in_regime(Window(1.0, 100.0, "earlier"), t, None, "speeds") == Window(1.0, 100.0, "earlier")


def test_in_regime_says_when_the_model_s_curve_does_not_cover_the_window():
    t = np.geomspace(10.0, 100.0, 20)  # covers a third of [10, 1000]
    w = in_regime(Window(10.0, 1000.0), t, t**0.5, "speeds")
    assert w == Window(10.0, 1000.0, "the model's speeds is not resolved over the window [10, 1e+03] (2 decades)")


def test_in_regime_keeps_a_window_over_a_single_power_law():
    t = np.geomspace(1.0, 1000.0, 20)
    assert in_regime(Window(10.0, 1000.0), t, 3 * t**0.4, "speeds") == Window(10.0, 1000.0)


MATERIAL = NS(mu_s=0.25, mu_d=0.75)


def _plateau_track(t, mu_hat):
    return NS(t=np.asarray(t), mu_w=MATERIAL.mu_s + (MATERIAL.mu_d - MATERIAL.mu_s) * np.asarray(mu_hat))


def test_plateau_change_is_the_line_s_rise_over_its_middle_on_exactly_the_window_s_samples():
    assert MIN_POINTS == 4  # the window [2, 5] below holds exactly MIN_POINTS samples, its ends included
    t = np.arange(8.0)
    a, b = 1.0, 0.1
    mu_hat = np.where((t >= 2) & (t <= 5), a + b * t, 5.0 + t**2)  # off the line outside the window
    dc = NS(scales=NS(material=MATERIAL))
    expected = abs(b) * (5 - 2) / abs(a + b * (2 + 5) / 2)
    assert plateau_change(_plateau_track(t, mu_hat), dc, Window(2.0, 5.0)) == pytest.approx(expected, rel=1e-9)
    assert np.isnan(plateau_change(_plateau_track(t, mu_hat), dc, Window(2.0, 5.0, "no window")))
    assert np.isnan(plateau_change(_plateau_track(t, mu_hat), dc, Window(2.0, 4.0)))  # three samples


def _drive(transit, t_s=1000.0, t_end=40.0):
    return NS(dem=NS(spec=NS(transit_time=transit), t_end=t_end), scales=NS(t_s=t_s, nu_g=0.3))


def test_a_drive_whose_transit_time_is_zero_or_unknown_has_no_growth_window():
    why = "the drive's shear-wave transit time is unknown, and so is its elastic start"
    end = min(GROWTH_END * 1000.0, 0.5 * 40.0)
    assert growth_window(_drive(0.0)) == Window(0.0, end, why)
    w = growth_window(_drive(np.nan))
    assert np.isnan(w.t0) and w.t1 == end and w.why == why


def _layers(t, delta, estimator):
    return NS(t_layer=np.asarray(t), depth=lambda e: np.asarray(delta) if e == estimator else None)


def test_growth_starts_its_window_at_the_choice_s_number_of_transits():
    transit = 0.01
    t = np.geomspace(0.01, 20.0, 40)
    out = growth(_layers(t, t**0.5, PRIMARY_ESTIMATOR), _drive(transit), Choice(PRIMARY_ESTIMATOR, "plate", 10.0))
    assert 10.0 != TRANSITS_BEFORE_COMPARISON
    assert out["window"] == [pytest.approx(10.0 * transit, rel=1e-12), 20.0]
    assert out["exponent"] == pytest.approx(0.5, abs=1e-12)


def test_growth_names_the_estimator_and_says_when_the_layer_table_lacks_it():
    other = next(e for e in LAYER_ESTIMATORS if e != PRIMARY_ESTIMATOR)
    w = Window(1.0, 10.0)
    out = growth(_layers([1.0, 2.0, 30.0], [1.0, 2.0, 3.0], other), _drive(0.1), Choice(other), window=w)
    assert out == {"why": f"2 layer depths {other} in the window [1, 10] (fewer than {MIN_POINTS})"}
    out = growth(_layers([1.0, 2.0], [1.0, 2.0], other), _drive(0.1), Choice(PRIMARY_ESTIMATOR), window=w)
    assert out == {"why": "no layer depths in the DEM's layer table (written before it was measured)"}
