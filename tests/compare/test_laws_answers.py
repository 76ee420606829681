"""Independent answers for the growth law's window and fit (compare.laws ``growth_window`` and ``growth``, which
reads the layer depths in the window and fits their log-log slope), for the laws fitted as a line across drives, and
for the drives the layer's laws read, on made-up drives: a drive is a
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
  and one fewer is not measurable, with the count in the reason; readings all at one time have no exponent;
* a line across drives (the creep length against p_w, the steady layer against delta_s) is weighted by each drive's
  seed-spread error: each made-up drive's bootstrap is two resamples at y -+ h, whose standard deviation (ddof 1) is
  h sqrt(2), so h = sd/sqrt(2) gives it the error sd (BOOTSTRAP_FEW_SEEDS seeds: no few-seed correction); the answers
  are numpy.polyfit's weighted by 1/sd with its unscaled covariance, the chi-square written out, the lack-of-fit
  probability scipy's chi-square survival function;
* every law leaves out a drive whose bed is short of the depth rule (compare.scorecard.depth_needed).
"""
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
from granstokes.compare.drive import TRANSITS_BEFORE_COMPARISON
from granstokes.compare.laws import (
    BOOTSTRAP_FEW_SEEDS,
    GROWTH_END,
    LAWS,
    MIN_DECADES,
    MIN_POINTS,
    Window,
    _drives,
    _law_row,
    _Sources,
    growth,
    growth_window,
)
from granstokes.compare.plate import SLIP_MAX
from granstokes.compare.rows import LACK_OF_FIT_P, critical
from granstokes.compare.scorecard import CREEP_ZONES, depth_needed
from scipy import stats

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


P_W = np.array([5.0, 7.0, 10.0, 14.0, 20.0, 28.0])
LOG_SD = np.array([0.05, 0.08, 0.04, 0.10, 0.06, 0.05])   # each drive's error of ln(creep length)
Z = np.array([0.9, -1.4, 0.3, 1.6, -1.2, 0.4])            # each drive's deviation from the line, in its errors


def _law(name, quantity=""):
    return next(law for law in LAWS if law.name == name and law.quantity.startswith(quantity))


def _row_of(law, drives, full, lo, hi, predicted):
    """compare.laws' row of ``law`` for the model "local" from the DEM's tracks ``full``, its two resamples ``lo``
    and ``hi`` and the model's tracks ``predicted`` (each a list over ``drives``)."""
    labels = [dc.label for dc in drives]
    src = _Sources(dict(zip(labels, full)), [dict(zip(labels, lo)), dict(zip(labels, hi))],
                   {(k, "local"): tr for k, tr in zip(labels, predicted)}, {},
                   dict.fromkeys(labels, BOOTSTRAP_FEW_SEEDS), (np.nan, np.nan))
    return _law_row(law, "local", drives, src, True)


def _hand_line(x, y, sd):
    """(slope, offset), their unscaled errors and chi2 of the weighted line, by numpy."""
    coef, cov = np.polyfit(x, y, 1, w=1 / sd, cov="unscaled")
    return coef, np.sqrt(np.diag(cov)), float(np.sum(((y - np.polyval(coef, x)) / sd) ** 2))


def _creep_drives(creep):
    drives = [SimpleNamespace(label=f"p{p:g}", dem=SimpleNamespace(spec=SimpleNamespace(p_w=p))) for p in P_W]
    h = LOG_SD / np.sqrt(2)
    tracks = lambda c: [SimpleNamespace(creep=dict.fromkeys(CREEP_ZONES, float(v))) for v in c]  # noqa: E731
    return drives, tracks(creep), tracks(creep * np.exp(-h)), tracks(creep * np.exp(h))


def test_creep_lengths_on_a_power_law_give_the_weighted_slope_its_scaled_error_and_chi2_per_dof():
    """ln creep = ln(2 p_w^0.3) + Z sd over six drives: the DEM's slope and error are the weighted fit's, the error
    scaled by sqrt(chi2/dof) (here 1.7 > 1), dof 6 - 2 = 4; the model's exact power law gives 0.3 on the same
    weights; sigma and the verdict at Student-t's quantile with 4 dof."""
    drives, full, lo, hi = _creep_drives(2 * P_W**0.3 * np.exp(Z * LOG_SD))
    row = _row_of(_law("creep_length_scaling"), drives, full, lo, hi, _creep_drives(2 * P_W**0.3)[1])
    (slope, _), (slope_err, _), chi2 = _hand_line(np.log(P_W), np.log(2 * P_W**0.3) + Z * LOG_SD, LOG_SD)
    assert chi2 / 4 == pytest.approx(1.713, abs=1e-3)
    err = slope_err * np.sqrt(chi2 / 4)
    assert row["chi2_dof"] == pytest.approx(chi2 / 4, rel=1e-9) and row["dof"] == pytest.approx(4)
    assert row["dem"] == pytest.approx(slope, rel=1e-9) and row["dem_err"] == pytest.approx(err, rel=1e-9)
    assert row["predicted"] == pytest.approx(0.3, rel=1e-9) and row["predicted_err"] == 0
    assert row["sigma"] == pytest.approx((slope - 0.3) / err, rel=1e-9)
    assert row["verdict"] == ("consistent" if abs(slope - 0.3) / err <= critical(4) else "disagrees") == "consistent"
    assert row["choices"][0]["chi2_dof"] == row["chi2_dof"] and row["n_drives"] == 6


def test_creep_lengths_on_a_step_are_not_a_line():
    """Creep lengths 2 below p_w = 12 and 4 above, each to 4-10 %: the weighted line leaves chi2/dof = 12.6 (p = 3e-10),
    improbable below LACK_OF_FIT_P: 'not measurable: not a line' with chi2/dof and p, no DEM slope quoted."""
    step = np.where(P_W < 12, 2.0, 4.0)
    drives, full, lo, hi = _creep_drives(step)
    row = _row_of(_law("creep_length_scaling"), drives, full, lo, hi, _creep_drives(2 * P_W**0.3)[1])
    *_, chi2 = _hand_line(np.log(P_W), np.log(step), LOG_SD)
    p = stats.chi2.sf(chi2, 4)
    assert p < LACK_OF_FIT_P and chi2 / 4 == pytest.approx(12.57, abs=0.01)
    assert row["verdict"] == "not measurable"
    assert row["note"] == f"not measurable: not a line (chi2/dof = {chi2 / 4:.3g}, p = {p:.2g})"
    assert row["chi2_dof"] == pytest.approx(chi2 / 4, rel=1e-9) and np.isnan(row["dem"]) and np.isnan(row["sigma"])


def test_the_steady_layer_s_slope_and_offset_carry_each_choice_s_chi2_per_dof():
    """delta_05 = 0.7 delta_s + 4.5 and delta_50 = 0.7 delta_s + 1, each with its own deviations, the other depths
    unmeasured: the slope and offset rows read delta_05 (the primary), the offset's error sqrt(1/S_w + x_m^2/S_xx)
    scaled by sqrt(chi2/dof) = sqrt(1.72); delta_50's entry has its own chi2/dof (0.38: no scaling), the unmeasured
    choices none."""
    delta_s = np.array([4.0, 6.0, 9.0, 12.0, 16.0, 20.0])
    sd = np.array([0.3, 0.4, 0.3, 0.5, 0.4, 0.6])
    depth = {"delta_05": 0.7 * delta_s + 4.5 + sd * Z,
             "delta_50": 0.7 * delta_s + 1.0 + sd * np.array([-0.5, 0.2, 0.6, -0.9, 0.1, 0.4])}
    drives = [SimpleNamespace(label=f"d{k}", scales=SimpleNamespace(delta_s=x)) for k, x in enumerate(delta_s)]

    def tracks(shift):
        return [SimpleNamespace(steady_depth=lambda e, k=k: depth[e][k] + shift[k] if e in depth else np.nan)
                for k in range(len(delta_s))]

    model = [SimpleNamespace(steady_depth=lambda e, x=x: 0.7 * x + 3.0) for x in delta_s]
    hand = {e: _hand_line(delta_s, y, sd) for e, y in depth.items()}
    for quantity, k in (("slope", 0), ("offset", 1)):
        row = _row_of(_law("delta_s_scaling", quantity), drives, tracks(0 * sd), tracks(-sd / np.sqrt(2)),
                      tracks(sd / np.sqrt(2)), model)
        coef, errors, chi2 = hand["delta_05"]
        assert row["dem"] == pytest.approx(coef[k], rel=1e-9)
        assert row["dem_err"] == pytest.approx(errors[k] * np.sqrt(chi2 / 4), rel=1e-9)
        assert row["predicted"] == pytest.approx((0.7, 3.0)[k], rel=1e-9)
        chi2_dof = {c["estimator"]: c["chi2_dof"] for c in row["choices"]}
        assert chi2_dof["delta_05"] == pytest.approx(hand["delta_05"][2] / 4, abs=1e-9) == row["chi2_dof"]
        assert chi2_dof["delta_50"] == pytest.approx(hand["delta_50"][2] / 4, abs=1e-9)
        assert all(np.isnan(chi2_dof[e]) for e in ("delta_10", "delta_20", "moment"))
        delta_50 = next(c for c in row["choices"] if c["estimator"] == "delta_50")
        assert hand["delta_50"][2] / 4 < 1 and delta_50["dem_err"] == pytest.approx(hand["delta_50"][1][k], rel=1e-9)


def test_a_drive_whose_bed_is_short_or_whose_plate_slips_is_left_out_of_every_law():
    """delta_s = 7, below the depth study's 10.58 d, so the clearance is 1.45 x 10.58 d: a bed of 7 + 15.341 d.  One
    0.5 d shorter is left out of every law (of every kind), as is a deep bed whose plate slips 2 SLIP_MAX."""
    depth = np.arange(0.0, 40.0, 0.5)
    sample = pd.DataFrame({"depth": depth, "u_x": np.exp(-depth / 3.0)})
    need = depth_needed(7.0)
    assert need == pytest.approx(7.0 + 1.45 * 10.58)
    assert depth_needed(20.0) == pytest.approx(20.0 * 2.45)  # above 10.58 d the clearance is 1.45 delta_s

    def dc(bed):
        dem = SimpleNamespace(spec=SimpleNamespace(depth=bed, kind="stress"), samples=(sample, sample),
                              samples_how="spread over 2 seeds", slip={"value": 0.0})
        return SimpleNamespace(predictions=(None,), base="", dem=dem, scales=SimpleNamespace(delta_s=7.0))

    deep, short = dc(need + 0.5), dc(need - 0.5)
    assert _drives([deep, short], None) == [deep] and _drives([deep, short], "stress") == [deep]
    assert _drives([deep, short], "speed") == []
    slipping = dc(need + 0.5)
    slipping.dem.slip = {"value": 2 * SLIP_MAX}
    assert _drives([deep, slipping], None) == [deep]


def test_a_steady_speed_is_the_mean_over_the_dem_s_final_quarter_or_half_of_the_chosen_speed():
    """The DEM's output times 0, 1, ..., 100; a track whose plate speed is t and whose contact layer moves at t/2:
    the plate over the final quarter (t >= 75) averages 87.5, over the final half 75, the contact layer over the
    final quarter 43.75; a model's track (no contact speed: it does not slip) reads its plate speed for both,
    interpolated onto the DEM's times from its own (every 0.5)."""
    from granstokes.compare.families import FAMILIES
    from granstokes.compare.laws import steady_speed
    dc = SimpleNamespace(dem=SimpleNamespace(series=pd.DataFrame({"t": np.arange(101.0)})))
    t = np.arange(101.0)
    dem = SimpleNamespace(t=t, speed=lambda ref: t / 2 if ref == "contact" else t)
    quarter, half, contact = FAMILIES["steady speed"]
    assert (quarter.estimator, quarter.reference, half.estimator, contact.reference) == (
        "final quarter", "plate", "final half", "contact")
    assert steady_speed(dem, dc, quarter) == pytest.approx(87.5)
    assert steady_speed(dem, dc, half) == pytest.approx(75.0)
    assert steady_speed(dem, dc, contact) == pytest.approx(43.75)
    fine = np.arange(0.0, 100.5, 0.5)
    model = SimpleNamespace(t=fine, speed=lambda ref: fine)
    assert steady_speed(model, dc, contact) == steady_speed(model, dc, quarter) == pytest.approx(87.5)


def test_a_drive_whose_load_lies_beyond_the_calibrated_I_is_left_out_of_every_law():
    """mu_s = 0.3, mu_d = 0.7, I0 = 0.3 (DEM convention): a wall friction of 0.5 is the steady wall I = 0.3 x 0.2/0.2 =
    0.3 (eq. (2.1) inverted). A calibration that measured I up to 0.31 keeps the drive, one up to 0.29 leaves it out of
    every law; an unknown range (NaN) keeps it."""
    from granstokes.compare.laws import within_calibration
    from granstokes.continuum.rheology import Friction
    material = SimpleNamespace(friction=Friction(mu_s=0.3, mu_d=0.7), I0=0.3, I_convention="dem")
    dem = SimpleNamespace(spec=SimpleNamespace(depth=60.0, kind="stress"), slip={"value": 0.0})
    dc = SimpleNamespace(predictions=(None,), base="", dem=dem,
                         scales=SimpleNamespace(delta_s=7.0, mu_w=0.5, material=material))
    assert within_calibration(dc, (1e-3, 0.31)) and within_calibration(dc, (np.nan, np.nan))
    assert not within_calibration(dc, (1e-3, 0.29))
    assert _drives([dc], None, (1e-3, 0.31)) == [dc] and _drives([dc], "stress", (1e-3, 0.29)) == []
