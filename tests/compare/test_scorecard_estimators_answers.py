"""The scorecard's estimators on their own (compare.scorecard.t90, creep_length, _final_quarter,
_final_quarter_band) against answers worked out by hand.

* t90: a unit step at output index s, on 230 output times (a running mean of int(T90_WINDOW x 230) = 11 points,
  centred): the centred mean rises linearly over the 11 points around the step, (j - s + 6)/11 at index j, so it
  reaches 90 % at j = s + 3.9; short records (no smoothing) where the final value is the mean of the last tenth
  (at least one point) and where leading gaps (NaN or None) are filled from the first value; with two seeds the
  DEM's t90 is the seeds' mean and standard error (1 dof), with one the running mean's half-width (infinite dof);
* creep_length: ln u a straight line of slope -1/l on exactly three points that fill [delta_s, bed -
  WALL_EXCLUSION] (one fewer gives no length), points beyond that zone off the line; u growing or flat gives none;
  a layer (delta_s) reaching exactly WALL_EXCLUSION above the base reaches the base (the sentence written out);
* the final quarter: the mean over the output times at or after t[0] + STEADY_LAST (t[-1] - t[0]) of a response
  equal to t, on an uneven grid that does not start at 0 (the listed times are written out here).

Constants (T90_WINDOW, T90_LEVEL, WALL_EXCLUSION, STEADY_LAST) are imported from their modules.
"""
from types import SimpleNamespace as NS

import numpy as np
import pandas as pd
import pytest
from granstokes.compare.calibrate import WALL_EXCLUSION
from granstokes.compare.plate import STEADY_LAST
from granstokes.compare.scorecard import (
    T90_LEVEL,
    T90_WINDOW,
    _final_quarter,
    _final_quarter_band,
    base_reach,
    creep_length,
    dem_observables,
    t90,
)


def test_t90_of_a_step_is_where_the_centred_running_mean_reaches_ninety_percent():
    n, s, dt = 230, 100, 0.5
    window = int(T90_WINDOW * n)
    assert window == 11  # the closed form below is for a centred window of 11 points
    t = 2.0 + dt * np.arange(n)
    y = np.where(np.arange(n) >= s, 1.0, 0.0)
    # centred mean at index j (window j-5..j+5): (j - s + 6)/11 while the window straddles the step
    j = s - 6 + T90_LEVEL * 11
    assert t90(t, y) == pytest.approx(t[0] + dt * j, rel=1e-12)


def test_t90_takes_the_final_value_as_the_mean_of_the_last_tenth_of_at_least_one_point():
    # 10 points: the last tenth is the last point (2); too few for any smoothing
    t = np.arange(10.0)
    y = np.array([0, 0, 0, 0, 1, 1, 1, 1, 1, 2.0])
    level = T90_LEVEL * 2.0  # y = 1.8 between t = 8 (y = 1) and t = 9 (y = 2)
    assert t90(t, y) == pytest.approx(8 + (level - 1) / (2 - 1), rel=1e-12)
    # 20 points: the last tenth is the last two (1, 2): final 1.5
    t = np.arange(20.0)
    y = np.array([0.0] * 10 + [1.0] * 9 + [2.0])
    level = T90_LEVEL * 1.5
    assert t90(t, y) == pytest.approx(18 + (level - 1) / (2 - 1), rel=1e-12)


def test_t90_fills_leading_gaps_from_the_first_value():
    t = np.arange(10.0)
    y = np.array([np.nan, np.nan, 0, 0, 1, 1, 1, 1, 1, 2.0])  # as if the first two were 0
    assert t90(t, y) == pytest.approx(8 + (T90_LEVEL * 2 - 1), rel=1e-12)
    assert t90(t, [None, None, 0, 0, 1, 1, 1, 1, 1, 2]) == pytest.approx(8 + (T90_LEVEL * 2 - 1), rel=1e-12)


def _zone(bed=10.0):
    last = bed - WALL_EXCLUSION
    delta_s = last - 1.0
    return bed, delta_s, np.array([delta_s, delta_s + 0.5, last])


def test_the_creep_length_fits_exactly_the_three_points_from_delta_s_to_the_wall_exclusion():
    bed, delta_s, zone = _zone()
    ell = 0.75
    above, below = np.array([delta_s - 1.0, delta_s - 0.5]), np.array([bed - 1.5, bed - 1.0, bed])
    depth = np.concatenate([above, zone, below])
    u = np.concatenate([[5.0, 4.0], 0.3 * np.exp(-(zone - delta_s) / ell), [1.0, 2.0, 3.0]])
    assert creep_length(depth, u, delta_s, bed) == pytest.approx(ell, rel=1e-9)
    # a missing speed or depth (None, as read from a table with gaps) is left out of the fit
    gappy_u, gappy_depth = [*u[:3], None, 9.0, *u[3:]], [*depth[:3], delta_s + 0.25, None, *depth[3:]]
    assert creep_length(gappy_depth, gappy_u, delta_s, bed) == pytest.approx(ell, rel=1e-9)


def test_the_creep_length_needs_three_points_in_the_zone_and_three_moving():
    bed, delta_s, zone = _zone()
    u = 0.3 * np.exp(-(zone - delta_s))
    assert np.isnan(creep_length(zone[:2], u[:2], delta_s, bed))  # two points in the zone: no length
    assert creep_length(zone, np.array([u[0], u[1], 0.0]), delta_s, bed) == 0.0  # two moving: rigid


def test_the_creep_length_of_a_speed_growing_or_flat_with_depth_is_undefined():
    bed, delta_s, zone = _zone()
    assert np.isnan(creep_length(zone, np.exp(0.5 * (zone - delta_s)), delta_s, bed))  # e-folds upward, slope 0.5
    assert np.isnan(creep_length(zone, np.exp(3.0 * (zone - delta_s)), delta_s, bed))  # slope 3
    assert np.isnan(creep_length(zone, np.full(3, 0.25), delta_s, bed))  # flat: slope 0


# an uneven grid from t = 4 to 12: the final quarter starts at 4 + STEADY_LAST x 8
T = np.array([4.0, 5.0, 6.0, 7.0, 8.0, 9.5, 10.0, 10.5, 12.0])


def test_the_final_quarter_is_the_mean_over_the_output_times_from_three_quarters_of_the_record():
    start = T[0] + STEADY_LAST * (T[-1] - T[0])
    assert start == 10.0  # the listed times below are those at or after 10
    a = NS(series=pd.DataFrame({"t": T}), response="u_w")
    model = pd.DataFrame({"t": T, "u_w": T})
    assert _final_quarter(model, a) == pytest.approx((10.0 + 10.5 + 12.0) / 3, rel=1e-12)


def test_the_final_quarter_band_averages_both_edges_over_the_same_times():
    band = pd.DataFrame({"t": T, "lo": T, "hi": 2 * T + 1})
    lo, hi = _final_quarter_band(band)
    assert lo == pytest.approx((10.0 + 10.5 + 12.0) / 3, rel=1e-12)
    assert hi == pytest.approx((21.0 + 22.0 + 25.0) / 3, rel=1e-12)


def test_a_layer_reaching_exactly_the_wall_exclusion_above_the_base_reaches_the_base():
    depth = np.arange(0.0, 10.5, 0.5)
    profile = pd.DataFrame({"depth": depth, "u_x": np.clip(1 - depth / 4, 0, None)})  # 5 % of u_w at 3.8 d
    a = NS(steady_profile=profile, spec=NS(depth=10.0))
    delta_s = 10.0 - WALL_EXCLUSION
    assert base_reach(a, delta_s) == (
        f"the flow reaches the base: the layer (DEM delta_u 3.8 d, calibrated delta_s {delta_s:.3g} d) "
        f"comes within {WALL_EXCLUSION:g} d of the base of the 10 d bed")
    assert base_reach(a, delta_s - 0.5) == ""


def _step(t, at):
    return NS(t=t, u_w=np.where(np.arange(len(t)) >= at, 1.0, 0.0))


def _drive(plates):
    t = 2.0 + np.arange(10.0)  # one seed's record from t = 2 to 11: its step at index 2 (t90 = 2 + 1.9)
    return NS(response="u_w", steady={"u_w": {"value": 1.0, "stderr": 0.1, "method": "blocks", "dof": 3}},
              samples=[], samples_how="blocks", spec=NS(depth=10.0), plates=plates,
              series=pd.DataFrame({"t": t, "u_w": _step(t, 2).u_w}))


def test_t90_of_two_seeds_is_their_mean_with_its_standard_error_and_one_dof():
    t = np.arange(10.0)  # ten points: no smoothing, the final value is the last; steps at 4 and 6: t90 3.9 and 5.9
    m = dem_observables(_drive([_step(t, 4), _step(t, 6)]), 1.0)["t90"]
    assert m.value == pytest.approx(4.9, rel=1e-12)
    assert m.err == pytest.approx(np.std([3.9, 5.9], ddof=1) / np.sqrt(2), rel=1e-12)
    assert (m.how, m.dof) == ("spread over 2 seeds", 1)


def test_t90_of_one_seed_carries_the_running_mean_s_half_width_with_infinite_dof():
    m = dem_observables(_drive([_step(np.arange(10.0), 4)]), 1.0)["t90"]
    assert m.value == pytest.approx(2.0 + 1.9, rel=1e-12)
    assert m.err == pytest.approx(0.5 * T90_WINDOW * (11.0 - 2.0), rel=1e-12)
    assert m.dof == np.inf


def test_the_creep_zones_read_each_part_of_a_two_slope_tail_over_fixed_widths():
    """A tail that e-folds over 2 d from delta_s = 4 to 8 and over 4 d below, in a bed of 30: "creep" fits [4, 7]
    (CREEP_WINDOW = 3 d, all in the 2 d part: exactly 2), "creep_deep" [6, 9], "creep_wide" [4, 10], whatever the bed
    below; each is the least-squares slope of ln u over its own points, by numpy; a bed of 10 cuts every zone at
    10 - WALL_EXCLUSION; on one exponential every zone gives its length."""
    from granstokes.compare.scorecard import CREEP_WINDOW, CREEP_ZONE_OFFSET, CREEP_ZONES
    delta_s = 4.0
    depth = np.arange(0.0, 30.25, 0.25)
    ln_u = np.where(depth <= 8.0, -(depth - delta_s) / 2.0, -2.0 - (depth - 8.0) / 4.0)
    assert (CREEP_WINDOW, CREEP_ZONE_OFFSET) == (3.0, 2.0)
    for bed in (30.0, 10.0):
        bottom = bed - WALL_EXCLUSION
        zones = {"creep": (4.0, min(7.0, bottom)), "creep_deep": (6.0, min(9.0, bottom)),
                 "creep_wide": (4.0, min(10.0, bottom))}
        assert set(CREEP_ZONES) == set(zones)
        for zone, (top, low) in zones.items():
            inside = (depth >= top) & (depth <= low)
            hand = -1 / np.polyfit(depth[inside], ln_u[inside], 1)[0]
            assert creep_length(depth, np.exp(ln_u), delta_s, bed, zone) == pytest.approx(hand, rel=1e-9)
    lengths = {z: creep_length(depth, np.exp(ln_u), delta_s, 30.0, z) for z in CREEP_ZONES}
    assert lengths["creep"] == pytest.approx(2.0, rel=1e-9)
    assert 2.0 < lengths["creep_wide"] < 4.0 and 2.0 < lengths["creep_deep"] < 4.0  # they reach the 4 d tail
    single = np.exp(-(depth - delta_s) / 3.0)
    for zone in CREEP_ZONES:
        assert creep_length(depth, single, delta_s, 30.0, zone) == pytest.approx(3.0, rel=1e-9)


def test_a_response_time_at_any_level_on_a_ramp_is_that_fraction_of_the_ramp():
    """A speed at 0 to t = 20, rising linearly to 1 at t = 300, flat to t = 400 (4001 output times): the running mean
    over T90_WINDOW of the record (+-10) is exact on the ramp more than 10 from its kinks and 0 or 1 on the flats, so
    the time to 90 % is 20 + 0.9 x 280 = 272 and to 75 % 20 + 0.75 x 280 = 230, to half an output step (a running
    window of an even 200 points is centred half a step early)."""
    t = np.linspace(0.0, 400.0, 4001)
    y = np.clip((t - 20.0) / 280.0, 0.0, 1.0)
    assert T90_WINDOW * 400.0 / 2 == pytest.approx(10.0)
    assert t90(t, y) == pytest.approx(20.0 + T90_LEVEL * 280.0, abs=0.05 + 1e-9)
    assert t90(t, y, 0.75) == pytest.approx(230.0, abs=0.05 + 1e-9)
