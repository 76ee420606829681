"""Independent answers for the growth law's window and fit (compare.laws ``growth_window`` and ``growth``, which
reads the layer depths in the window and fits their log-log slope), on made-up drives: a drive is a
SimpleNamespace carrying only what these functions read (the DEM's shear-wave transit time, whose
TRANSITS_BEFORE_COMPARISON transits are the elastic start, and record length ``t_end``, the calibrated ``t_s`` and
``nu_g``), a track only its layer times and depths; no record is read and no solver runs.

What is checked, and how the answers are found without the module:

* the window is [elastic start, min(GROWTH_END t_s, half the record)] (GROWTH_END imported) when it spans
  MIN_DECADES; a drive without calibrated scales or transit time, whose elastic start reaches the window's end, or
  whose window spans less, is not measurable and says why (with the numbers in the reason);
* delta = c t^n exactly over the window (another law outside it): the exponent is n and the prefactor the mean of
  delta/sqrt(nu_g t) over the window's readings, both written out here (the exponent also by numpy.polyfit on the
  logs, for float32 input);
* the window includes both its ends; only positive, finite depths count; MIN_POINTS (imported) readings are enough
  and one fewer is not measurable, with the count in the reason; readings all at one time have no exponent.
"""
from types import SimpleNamespace

import numpy as np
import pytest
from granstokes.compare.drive import TRANSITS_BEFORE_COMPARISON
from granstokes.compare.laws import GROWTH_END, MIN_DECADES, MIN_POINTS, Window, growth, growth_window

NU_G = 0.3
#: the fits' window, given explicitly (the window's own rules are tested apart)
FIT = Window(0.25, 1.0)


def drive(t_s=2.0, t_end=40.0, start=0.25, scales=True):
    """A drive whose elastic start (TRANSITS_BEFORE_COMPARISON transits) is at ``start``."""
    spec = SimpleNamespace(transit_time=start / TRANSITS_BEFORE_COMPARISON)
    return SimpleNamespace(dem=SimpleNamespace(spec=spec, t_end=t_end),
                           scales=SimpleNamespace(t_s=t_s, nu_g=NU_G) if scales else None)


def track(t, delta):
    return SimpleNamespace(t_layer=np.asarray(t), depth=lambda estimator: np.asarray(delta))


def test_growth_window_ends_at_growth_end_t_s_or_at_half_the_record():
    t_end = 40.0
    short_t_s, long_t_s = 0.1 * t_end / GROWTH_END, 10 * t_end / GROWTH_END
    assert growth_window(drive(short_t_s, t_end)) == Window(0.25, GROWTH_END * short_t_s)
    assert growth_window(drive(long_t_s, t_end)) == Window(0.25, 0.5 * t_end)
    unknown = growth_window(drive(short_t_s, t_end, start=np.nan))
    assert unknown.why == "the drive's shear-wave transit time is unknown, and so is its elastic start"


def test_a_drive_without_calibrated_scales_has_no_growth_window():
    w = growth_window(drive(scales=False))
    assert np.isnan(w.t0) and np.isnan(w.t1) and w.why.startswith("no calibrated scales")
    assert growth(track([1.0, 2.0, 3.0, 4.0], [1.0, 2.0, 3.0, 4.0]), drive(scales=False)) == {"why": w.why}


def test_an_elastic_start_at_the_window_s_end_leaves_no_window_and_a_short_one_is_refused():
    end = GROWTH_END * 40.0
    covered = growth_window(drive(t_s=40.0, start=end))
    assert (covered.t0, covered.t1) == (end, end)
    assert f"{end:.3g}" in covered.why and "covers the growth window" in covered.why
    assert growth(track(np.linspace(0.1, 1.0, 10), np.ones(10)), drive(t_s=40.0, start=end)) == {"why": covered.why}
    decade = end / 10 ** MIN_DECADES
    assert growth_window(drive(t_s=40.0, start=decade)) == Window(decade, end)
    short = growth_window(drive(t_s=40.0, start=1.01 * decade))
    assert short.why == (f"the window [{1.01 * decade:.3g}, {end:.3g}] spans {np.log10(end / (1.01 * decade)):.2g} "
                         f"decade(s) of time (fewer than {MIN_DECADES:g})")


def test_growth_reads_the_exponent_and_prefactor_of_an_exact_power_law_over_the_window():
    """delta = 1.7 sqrt(nu_g) t^0.37 in the window [0.25, 1], 5 t outside it: exponent 0.37, prefactor
    the window's mean of delta/sqrt(nu_g t) = 1.7 t^(-0.13)."""
    dc = drive(t_s=2.0)
    t1 = FIT.t1
    t = np.geomspace(0.05, 5 * t1, 40)
    inside = (t >= FIT.t0) & (t <= t1)
    delta = np.where(inside, 1.7 * np.sqrt(NU_G) * t**0.37, 5 * t)
    out = growth(track(t, delta), dc, window=FIT)
    assert out["exponent"] == pytest.approx(0.37, abs=1e-12)
    assert out["prefactor"] == pytest.approx(np.mean(1.7 * t[inside] ** -0.13), rel=1e-12)
    np.testing.assert_array_equal(out["t"], t[inside])


def test_the_window_includes_both_ends_and_min_points_readings_are_enough():
    """MIN_POINTS readings, two of them exactly at the window's ends: measurable, all of them read; without the
    last one: not measurable, the count in the reason."""
    dc = drive(t_s=2.0)
    t0, t1 = FIT.t0, FIT.t1
    t = np.concatenate([[0.1, t0], np.linspace(t0, t1, MIN_POINTS)[1:-1], [t1, 3.0]])
    delta = 2.0 * t**0.5
    out = growth(track(t, delta), dc, window=FIT)
    np.testing.assert_array_equal(out["t"], t[1:-1])
    assert out["exponent"] == pytest.approx(0.5, abs=1e-12)
    fewer = growth(track(t[:-2], delta[:-2]), dc, window=FIT)
    assert "exponent" not in fewer and f"{MIN_POINTS - 1} layer depths" in fewer["why"]


def test_only_positive_finite_depths_are_read():
    """Readings of 0, a negative, nan and inf depth in the window are left out: MIN_POINTS good ones give the exact
    exponent and prefactor; one fewer good one is not measurable, however many bad ones."""
    dc = drive(t_s=2.0)
    good_t = np.linspace(0.3, 0.9, MIN_POINTS)
    bad_t = np.array([0.4, 0.5, 0.6, 0.7])
    t = np.concatenate([good_t, bad_t])
    delta = np.concatenate([3.0 * np.sqrt(NU_G) * good_t**0.25, [0.0, -1.0, np.nan, np.inf]])
    out = growth(track(t, delta), dc, window=FIT)
    assert out["exponent"] == pytest.approx(0.25, abs=1e-12)
    assert out["prefactor"] == pytest.approx(np.mean(3.0 * good_t**-0.25), rel=1e-12)
    fewer = growth(track(t[1:], delta[1:]), dc, window=FIT)
    assert "exponent" not in fewer and f"{MIN_POINTS - 1} layer depths" in fewer["why"]


def test_a_reading_at_t_0_is_left_out_of_the_power_law():
    """A window from 0 and a layer depth read at t = 0 (an imposed speed's first frame): a power law has no value
    there, so the exponent and the prefactor are the power law's over the positive times."""
    t = np.concatenate([[0.0], np.linspace(0.2, 0.9, MIN_POINTS)])
    delta = np.concatenate([[0.05], 2.0 * np.sqrt(NU_G) * t[1:] ** 0.6])
    out = growth(track(t, delta), drive(t_s=2.0), window=Window(0.0, 1.0))
    assert out["exponent"] == pytest.approx(0.6, abs=1e-12)
    assert out["prefactor"] == pytest.approx(np.mean(2.0 * t[1:] ** 0.1), rel=1e-12)


def test_single_precision_readings_give_the_double_precision_exponent():
    """float32 times and depths: the exponent is numpy.polyfit's slope of their float64 copies' logs, to 1e-12
    (logs taken in float32 would be off by ~1e-7)."""
    t32 = np.geomspace(0.3, 0.95, 9).astype(np.float32)
    d32 = (1.3 * t32.astype(float) ** 0.41 * (1 + 0.05 * np.sin(7 * np.arange(9)))).astype(np.float32)
    expected = np.polyfit(np.log(t32.astype(float)), np.log(d32.astype(float)), 1)[0]
    assert growth(track(t32, d32), drive(t_s=2.0), window=FIT)["exponent"] == pytest.approx(expected, abs=1e-12)


def test_readings_all_at_one_time_have_no_exponent():
    out = growth(track(np.full(MIN_POINTS + 1, 0.5), np.linspace(1.0, 2.0, MIN_POINTS + 1)), drive(t_s=2.0),
                 window=FIT)
    assert np.isnan(out["exponent"])
