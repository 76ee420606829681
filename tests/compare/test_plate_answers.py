"""Independent answers for compare/plate.py: the plate record's observables and their errors on synthetic records
whose answers are known in closed form or recomputed here by hand with numpy from the documented formulas.

* The record is written as the DEM leaves it in a drive folder (``plate.csv``: the columns of LAMMPS's fix print,
  dem.layout.PLATE_COLUMNS, plus mu_w = -f_x/f_y, empty while f_y <= 0, as dem.outputs.merge_drive writes it) and
  read back with ``PlateRecord.read``.
* Block errors: series of alternating sign, level + a w_i (-1)^i with w_i > 0 smooth, have a lag-1 correlation near
  -1, so their integrated autocorrelation time is its floor, 1/2 sample, and a block is BLOCK_TAUS/2 samples: the
  expected error is the std (ddof = 1) of those blocks' means (of f of them: the friction is <tau>/<p> of each block)
  over sqrt(blocks), computed here with reshape.  AR(1) noise has tau = (1 + a)/(2 (1 - a)) samples and standard
  error of the mean sigma_y sqrt(2 tau / N).
* Steady state: noise-free records (a constant, a single spike, a step) make the final error 0, so a start is steady
  exactly when the head (the first quarter of the rest, [s, s + (1 - STEADY_LAST)(t_end - s))) equals the final
  value: the answer is read off the start grid (steps of STEADY_WINDOW of the record after the prepared state).  A
  nine-sample record pins the head's tolerance TREND_SIGMA stderr sqrt(m/h + 1) with a one-sample head just inside
  and just outside it.  An exponential transient whose head excess at the first start (closed form: 0.048) exceeds
  the tolerance (0.033) and is below 1e-3 of it one step later is steady from the second start.
* Trend and power law: least squares by hand (slope = Sxy/Sxx, stderr = sqrt(SSR/(n - 2)/Sxx)); the trend's limit is
  the Student-t quantile at blocks - 2 degrees of freedom exceeded as often as a normal variable exceeds TREND_SIGMA,
  the power law's interval t.ppf(0.975, n - 2) stderr.
* Slip: 1 - (sum u_c n_c / sum n_c) / <u_w> over the second half (SLIP_FROM) of the record, grain-weighted.
* Degrees of freedom: blocks - 1 for a block error, n - 1 for the spread over n seeds, the Welch-Satterthwaite
  (sum e_i^2)^2 / sum(e_i^4/dof_i) written out for block errors combined over beds, blocks - 2 for a trend.

Constants (STEADY_*, BLOCK_TAUS, MIN_BLOCKS, MIN_SEEDS_SPREAD, TREND_SIGMA, SLIP_FROM) are imported from the module.
"""
import warnings

import numpy as np
import pandas as pd
import pytest
from granstokes.compare import plate
from granstokes.dem import layout
from scipy import stats
from scipy.signal import lfilter

#: a block of an alternating series: BLOCK_TAUS autocorrelation times of 1/2 sample
BLOCK = int(np.ceil(plate.BLOCK_TAUS * 0.5))


def _alternating(n, level, amplitude, phase=0.0):
    """level + amplitude w_i (-1)^i, w_i = 1 + sin(i + phase)/2: integrated autocorrelation time 1/2 sample."""
    i = np.arange(n)
    return level + amplitude * (1 + 0.5 * np.sin(i + phase)) * (-1.0) ** i


def _write_plate(folder, t, u_x, f_x, f_y, u_c, n_c, y):
    """plate.csv as a drive folder holds it: LAMMPS's columns (step, t, x, y, u_x, u_y, f_x, f_y, u_c, n_c) and
    mu_w = -f_x/f_y, empty while the plate is out of contact (f_y <= 0)."""
    folder.mkdir(parents=True)
    dt = t[1] - t[0]
    df = pd.DataFrame({"step": np.arange(len(t)) * 100, "t": t, "x": np.cumsum(u_x) * dt, "y": y, "u_x": u_x,
                       "u_y": 0.0, "f_x": f_x, "f_y": f_y, "u_c": u_c, "n_c": n_c})
    assert tuple(df.columns) == layout.PLATE_COLUMNS
    df["mu_w"] = (-df["f_x"] / df["f_y"]).where(df["f_y"] > 0)
    df.to_csv(folder / layout.PLATE_CSV, index=False)


def _block_means(x):
    return x.reshape(-1, BLOCK).mean(axis=1)


def _stderr(values):
    values = np.asarray(values)
    return np.sqrt(np.sum((values - values.mean()) ** 2) / (len(values) - 1)) / np.sqrt(len(values))


def _line(x, y):
    """Least squares by hand: slope, its standard error."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    sxx = np.sum((x - x.mean()) ** 2)
    slope = np.sum((x - x.mean()) * (y - y.mean())) / sxx
    resid = y - y.mean() - slope * (x - x.mean())
    return slope, np.sqrt(np.sum(resid ** 2) / (len(x) - 2) / sxx)


# --- the record: plate.csv, tail, window values, slip ------------------------------------------------------------

#: the drive: 81 rows every 0.25 (t = 0 ... 20): a transient over the first half, then the plate at U_W = 2.0, the
#: grains touching it alternating between 1.0 (2 of them) and 1.6 (4 of them), tau ~ 4, p ~ 10; the last row's force
#: is missing (nan): the second half is 40 finite rows = 8 blocks
DT, ROWS, HALF, U_W = 0.25, 81, 40, 2.0


def _drive(tmp_path):
    t = np.arange(ROWS) * DT
    first = np.arange(HALF)
    u = np.r_[U_W * (1 - np.exp(-first / 10.0)), _alternating(ROWS - HALF, U_W, 0.1)]
    tau = np.r_[8.0 - 0.1 * first, _alternating(ROWS - HALF, 4.0, 0.3, phase=1.0)]
    p = np.r_[np.full(HALF, 10.0), _alternating(ROWS - HALF, 10.0, 0.5, phase=2.0)]
    p[0] = 0.0  # the prepared state: the plate not yet loaded
    n_c = np.r_[np.full(HALF, 1.0), np.where(np.arange(ROWS - HALF) % 2, 4.0, 2.0)]
    u_c = np.r_[0.1 * u[:HALF], np.where(np.arange(ROWS - HALF) % 2, 1.6, 1.0)]
    tau[-1] = np.nan
    y = 30.0 + 0.01 * np.cos(t)
    _write_plate(tmp_path / "bed", t, u, -tau, p, u_c, n_c, y)
    return plate.PlateRecord.read(tmp_path / "bed"), dict(t=t, u=u, tau=tau, p=p, u_c=u_c, n_c=n_c, y=y)


def test_plate_csv_columns_become_the_record_fields(tmp_path):
    """u_w = u_x, tau_w = -f_x, p = f_y, y, u_c, n_c as written; mu_w = tau_w/p, nan where p <= 0 (row 0)."""
    rec, c = _drive(tmp_path)
    for field, column in (("t", "t"), ("u_w", "u"), ("tau_w", "tau"), ("p", "p"), ("y", "y"), ("u_c", "u_c"),
                          ("n_c", "n_c")):
        np.testing.assert_array_equal(getattr(rec, field), c[column], err_msg=field)
    assert np.isnan(rec.mu_w[0]) and np.isnan(rec.mu_w[-1])
    np.testing.assert_allclose(rec.mu_w[1:-1], c["tau"][1:-1] / c["p"][1:-1], rtol=1e-15)


def test_tail_keeps_the_rows_from_t0_on_with_finite_forces():
    """t >= t0 (t0 itself included), dropping the rows whose tau_w or p is not finite, in every series."""
    t = np.arange(8.0)
    cols = {k: t * s for k, s in (("u_w", 2.0), ("tau_w", 3.0), ("p", 5.0), ("y", 7.0), ("u_c", 11.0),
                                   ("n_c", 13.0))}
    cols["tau_w"][4] = np.nan
    cols["p"][6] = np.inf
    cols["tau_w"][1] = np.nan  # before t0 anyway
    rec = plate.PlateRecord(t=t, **cols)
    out = plate.tail(rec, 3.0)
    keep = np.array([3, 5, 7])
    assert sorted(out) == ["n_c", "p", "t", "tau_w", "u_c", "u_w"]
    np.testing.assert_array_equal(out["t"], t[keep])
    for k, s in (("u_w", 2.0), ("tau_w", 3.0), ("p", 5.0), ("u_c", 11.0), ("n_c", 13.0)):
        np.testing.assert_array_equal(out[k], t[keep] * s, err_msg=k)


def test_window_values_are_ratio_of_means_with_block_errors(tmp_path):
    """u_w and mu_w = <tau_w>/<p> over t >= t0 = 10 (the 40 finite rows): values and std(ddof=1)/sqrt(8) of the
    8 blocks' u_w means and <tau>/<p> ratios."""
    rec, c = _drive(tmp_path)
    out = plate.window_values(rec, HALF * DT)
    u, tau, p = c["u"][HALF:-1], c["tau"][HALF:-1], c["p"][HALF:-1]
    assert out["u_w"]["value"] == pytest.approx(u.mean(), rel=1e-14)
    assert out["u_w"]["blocks"] == 8 and out["mu_w"]["blocks"] == 8 and out["u_w"]["enough_blocks"]
    assert out["u_w"]["stderr"] == pytest.approx(_stderr(_block_means(u)), rel=1e-12)
    assert out["mu_w"]["value"] == pytest.approx(tau.mean() / p.mean(), rel=1e-14)
    assert out["mu_w"]["stderr"] == pytest.approx(_stderr(_block_means(tau) / _block_means(p)), rel=1e-12)


def test_slip_is_grain_weighted_over_the_second_half(tmp_path):
    """1 - (sum u_c n_c / sum n_c)/<u_w> from t = SLIP_FROM t_end: grains at 1.0 (2) and 1.6 (4) move at 1.4 on
    average (1.3 unweighted); the plate at ~2.0: slip ~0.3; its error from the 8 blocks.  Shifting the clock
    changes nothing, nor does ending the record one row earlier (its half-way point then falls between rows)."""
    rec, c = _drive(tmp_path)
    start = plate.SLIP_FROM * (c["t"][-1] - c["t"][0])
    sel = (c["t"] >= start) & np.isfinite(c["tau"])
    assert sel.sum() == 8 * BLOCK and c["t"][sel][0] == HALF * DT
    u, u_c, n_c = c["u"][sel], c["u_c"][sel], c["n_c"][sel]
    expected = 1 - np.sum(u_c * n_c) / np.sum(n_c) / u.mean()
    assert np.sum(u_c * n_c) / np.sum(n_c) == pytest.approx(1.4)
    out = plate.slip(rec)
    assert out["value"] == pytest.approx(expected, rel=1e-13) and out["value"] == pytest.approx(0.3, abs=0.01)
    per_block = 1 - _block_means(u_c * n_c) / _block_means(n_c) / _block_means(u)
    assert out["stderr"] == pytest.approx(_stderr(per_block), rel=1e-12) and out["blocks"] == 8
    shifted = plate.PlateRecord(rec.t + 100.0, rec.u_w, rec.tau_w, rec.p, rec.y, rec.u_c, rec.n_c)
    assert plate.slip(shifted)["value"] == pytest.approx(expected, rel=1e-13)
    # without the last (force-less) row the record ends at 19.75: its second half starts at 9.875, the same 40 rows
    shorter = plate.PlateRecord(*(getattr(rec, k)[:-1] for k in ("t", "u_w", "tau_w", "p", "y", "u_c", "n_c")))
    assert plate.slip(shorter)["value"] == pytest.approx(expected, rel=1e-13)


def test_steady_window_starts_at_t_steady_but_no_later_than_the_latest_fraction():
    t_end = 10.0
    latest = plate.STEADY_WINDOW_LATEST * t_end
    assert plate.steady_window_start(3.0, t_end) == 3.0
    assert plate.steady_window_start(9.5, t_end) == pytest.approx(latest, rel=1e-15)
    assert plate.steady_window_start(np.nan, t_end) == pytest.approx(latest, rel=1e-15)
    assert plate.steady_window_start(np.inf, t_end) == pytest.approx(latest, rel=1e-15)


# --- block errors and pooling ------------------------------------------------------------------------------------

def test_block_error_of_ar1_noise_is_the_spread_of_blocks_of_ten_correlation_times():
    """AR(1), a = 0.8: tau = (1 + a)/(2 (1 - a)) = 4.5 samples; blocks of ceil(BLOCK_TAUS tau) samples; the error is
    std(ddof=1) of their means / sqrt(blocks) exactly, and sigma_y sqrt(2 tau/N) within 15 %."""
    rng = np.random.default_rng(8)
    a, n = 0.8, 20_000
    y = lfilter([1.0], [1.0, -a], rng.standard_normal(n))
    tau = (1 + a) / (2 * (1 - a))
    est = plate.block_estimate({"y": y})
    assert est["tau_samples"] == pytest.approx(tau, rel=0.15)
    assert est["blocks"] == n // int(np.ceil(plate.BLOCK_TAUS * est["tau_samples"])) and est["enough_blocks"]
    means = [b.mean() for b in np.array_split(y, est["blocks"])]
    assert est["stderr"] == pytest.approx(_stderr(means), rel=1e-12)
    assert est["stderr"] == pytest.approx(np.sqrt(1 / (1 - a ** 2)) * np.sqrt(2 * tau / n), rel=0.15)
    assert est["value"] == pytest.approx(y.mean(), rel=1e-12)
    assert est["dof"] == est["blocks"] - 1


def test_exactly_min_blocks_blocks_of_ten_correlation_times_are_enough():
    """An alternating series (tau = 1/2): MIN_BLOCKS blocks of BLOCK samples are enough; one sample fewer still
    makes MIN_BLOCKS (shorter) blocks, and says the error is underestimated."""
    n = plate.MIN_BLOCKS * BLOCK
    y = _alternating(n, 1.0, 0.2)
    est = plate.block_estimate({"y": y})
    assert est["tau_samples"] == 0.5 and est["blocks"] == plate.MIN_BLOCKS and est["enough_blocks"]
    assert est["method"] == f"{plate.MIN_BLOCKS} blocks of 10 autocorrelation times (0.5 samples) within the run"
    assert est["stderr"] == pytest.approx(_stderr(_block_means(y)), rel=1e-12)
    short = plate.block_estimate({"y": y[:-1]})
    assert short["blocks"] == plate.MIN_BLOCKS and not short["enough_blocks"]
    per = (n - 1) / plate.MIN_BLOCKS / 0.5
    assert short["method"] == (f"{plate.MIN_BLOCKS} blocks of {per:.3g} autocorrelation times (0.5 samples) within "
                               f"the run (too short for {plate.MIN_BLOCKS} blocks of {plate.BLOCK_TAUS:g}: error "
                               "underestimated)")
    means = [b.mean() for b in np.array_split(y[:-1], plate.MIN_BLOCKS)]
    assert short["stderr"] == pytest.approx(_stderr(means), rel=1e-12)


def test_a_series_shorter_than_min_blocks_has_a_block_per_sample():
    """3 samples: 3 blocks of one (error sqrt(21)/3/sqrt(3)); 2 samples: 2 (error 1); 1 sample: no error (nan),
    without a warning."""
    three = plate.block_estimate({"y": [1.0, 4.0, 2.0]})
    assert three["blocks"] == 3 and three["value"] == pytest.approx(7 / 3) and not three["enough_blocks"]
    assert three["stderr"] == pytest.approx(np.sqrt(21) / 3 / np.sqrt(3), rel=1e-14) and three["dof"] == 2
    assert three["tau_samples"] == 0.5
    assert three["method"] == ("3 blocks of 2 autocorrelation times (0.5 samples) within the run (too short for "
                               f"{plate.MIN_BLOCKS} blocks of {plate.BLOCK_TAUS:g}: error underestimated)")
    two = plate.block_estimate({"y": [1.0, 3.0]})
    assert two["blocks"] == 2 and two["stderr"] == pytest.approx(1.0, rel=1e-14)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        one = plate.block_estimate({"y": [5.0]})
    assert one["blocks"] == 1 and one["value"] == 5.0 and np.isnan(one["stderr"])


def test_pooled_error_is_the_spread_over_enough_seeds_else_the_combined_block_errors():
    """One bed: its own value, error and method.  Fewer than MIN_SEEDS_SPREAD: sqrt(sum stderr^2)/n and the first
    bed's method.  MIN_SEEDS_SPREAD or more: std(ddof=1)/sqrt(n) of the values, whatever their block errors."""
    one = plate.pooled([{"value": 0.3, "stderr": 0.02, "dof": 3, "method": "blocks of bed 1"}])
    assert one == {"value": 0.3, "stderr": 0.02, "dof": 3, "method": "blocks of bed 1", "per_seed": [0.3]}
    two = plate.pooled([{"value": 0.3, "stderr": 0.03, "dof": 3, "method": "blocks of bed 1"},
                        {"value": 0.5, "stderr": 0.04, "dof": 5, "method": "blocks of bed 2"}])
    assert two["value"] == pytest.approx(0.4) and two["stderr"] == pytest.approx(0.025, rel=1e-14)
    # Welch-Satterthwaite: (0.03^2 + 0.04^2)^2 / (0.03^4/3 + 0.04^4/5) = 6.25e-6 / 7.82e-7 = 7.99
    assert two["dof"] == pytest.approx(6.25e-6 / (8.1e-7 / 3 + 2.56e-6 / 5), rel=1e-12)
    assert two["method"] == "blocks of bed 1, combined over 2 seeds" and two["per_seed"] == [0.3, 0.5]
    values = 0.3 + 0.1 * np.arange(plate.MIN_SEEDS_SPREAD) ** 2
    many = plate.pooled([{"value": v, "stderr": 1e-6, "method": "blocks"} for v in values])
    assert many["value"] == pytest.approx(values.mean(), rel=1e-14)
    assert many["stderr"] == pytest.approx(_stderr(values), rel=1e-14)
    assert many["method"] == f"spread over {plate.MIN_SEEDS_SPREAD} seeds (std/sqrt(n))"
    assert many["dof"] == plate.MIN_SEEDS_SPREAD - 1  # the block errors' dof do not enter
    assert many["per_seed"] == pytest.approx(values.tolist(), rel=1e-15)


# --- trend ------------------------------------------------------------------------------------------------------

def test_trend_of_three_blocks_is_the_line_through_them():
    """Three samples are three blocks: slope 0.5, stderr sqrt(0.75) by hand, limit at 1 degree of freedom."""
    tr = plate.trend(np.array([0.0, 1.0, 2.0]), np.array([1.0, 3.0, 2.0]))
    assert tr["blocks"] == 3
    assert tr["slope"] == pytest.approx(0.5, rel=1e-14) and tr["stderr"] == pytest.approx(np.sqrt(0.75), rel=1e-14)
    assert tr["z"] == pytest.approx(0.5 / np.sqrt(0.75), rel=1e-14)
    assert tr["limit"] == pytest.approx(stats.t.isf(stats.norm.sf(plate.TREND_SIGMA), 1), rel=1e-12)
    assert tr["dof"] == 1  # three blocks, a line through them
    assert plate.no_trend(tr)


def test_two_samples_have_no_trend_to_test():
    """Fewer than 3 blocks: slope, stderr and z are nan, no limit, and no_trend says False."""
    tr = plate.trend(np.array([0.0, 1.0]), np.array([1.0, 5.0]))
    assert tr["blocks"] == 2 and "limit" not in tr
    assert np.isnan(tr["slope"]) and np.isnan(tr["stderr"]) and np.isnan(tr["z"])
    assert plate.no_trend(tr) is False


def test_a_constant_series_has_zero_trend():
    """Zero slope with zero scatter: z = 0 (not 0/0), within the limit."""
    tr = plate.trend(np.arange(40.0), np.full(40, 2.0))
    assert tr["slope"] == 0.0 and tr["z"] == 0.0 and plate.no_trend(tr)


def test_an_exact_line_is_an_infinite_trend_of_its_own_sign():
    """Zero scatter about a falling line: z = -inf (a falling record drifts down), beyond any limit."""
    for sign in (1.0, -1.0):
        tr = plate.trend(np.arange(40.0), sign * np.arange(40.0))
        assert tr["z"] == sign * np.inf and not plate.no_trend(tr)


def test_a_linear_drift_is_flagged_and_the_same_noise_without_it_is_not():
    """y = 0.01 t + white noise (sigma 1) over 400 samples: the slope of the blocks' means (by hand) is ~0.01 and
    beyond the limit; the noise alone is within it."""
    rng = np.random.default_rng(12)
    t = np.arange(400.0)
    noise = rng.standard_normal(t.size)
    tr = plate.trend(t, 0.01 * t + noise)
    tb, yb = (np.array([b.mean() for b in np.array_split(x, tr["blocks"])]) for x in (t, 0.01 * t + noise))
    slope, se = _line(tb, yb)
    assert tr["slope"] == pytest.approx(slope, rel=1e-12) and tr["stderr"] == pytest.approx(se, rel=1e-10)
    assert tr["z"] == pytest.approx(slope / se, rel=1e-10) and tr["slope"] == pytest.approx(0.01, abs=3 * se)
    assert tr["z"] > tr["limit"] and not plate.no_trend(tr)
    flat = plate.trend(t, noise)
    assert abs(flat["z"]) <= flat["limit"] and plate.no_trend(flat)


def test_no_trend_includes_its_limit_and_is_two_sided():
    assert plate.no_trend({"z": 2.5, "limit": 2.5}) and plate.no_trend({"z": -2.5, "limit": 2.5})
    assert not plate.no_trend({"z": -2.5000001, "limit": 2.5})
    assert plate.no_trend({"z": np.nan, "slope": np.nan, "stderr": np.nan, "blocks": 2}) is False


# --- steady state -------------------------------------------------------------------------------------------------

def _grid(t):
    """The starts tried: from the first sample after the prepared state, in steps of STEADY_WINDOW of the rest."""
    return t[1] + np.arange(0.0, plate.STEADY_LAST, plate.STEADY_WINDOW) * (t[-1] - t[1])


def test_a_constant_record_is_steady_from_its_first_sample_after_the_prepared_state():
    t = np.arange(101.0)
    y = np.full(t.size, 2.0)
    y[0] = 5.26  # the prepared state
    st = plate.steady_state(t, y)
    assert st["value"] == 2.0 and st["stderr"] == 0.0 and st["t_steady"] == t[1]
    assert st["drift"] == 0.0 and st["drift_z"] == 0.0


@pytest.mark.parametrize("n, spike", [(401, 1.0), (401, 101.0), (402, 101.0)])
def test_a_spike_delays_t_steady_only_inside_the_head(n, spike):
    """A constant record (error 0) with one spike: steady from t[1] unless the spike is in the head
    [s, s + (1 - STEADY_LAST)(t_end - s)) of t[1] (the first sample; the head's open end 101 when t_end = 401;
    just inside it, 101 < 101.25, when t_end = 402), else from the first start after the spike."""
    t = np.arange(n + 1.0)
    y = np.full(t.size, 2.0)
    y[0], y[t == spike] = 0.0, 3.0
    head_end = t[1] + (1 - plate.STEADY_LAST) * (t[-1] - t[1])
    starts = _grid(t)
    expected = starts[starts > spike][0] if t[1] <= spike < head_end else t[1]
    assert plate.steady_state(t, y)["t_steady"] == pytest.approx(expected, rel=1e-14)
    assert (n, spike, expected) in ((401, 1.0, starts[1]), (401, 101.0, 1.0), (402, 101.0, starts[5]))


def test_a_record_steady_only_in_its_final_quarter_is_steady_from_its_first_sample():
    """2.5 until the final quarter (t >= t[1] + STEADY_LAST (t_end - t[1]) = 301 exactly), 2.0 from there: every
    start's head holds 2.5s, the final quarter has no trend, so t_steady is the final quarter's first sample."""
    t = np.arange(402.0)
    boundary = t[1] + plate.STEADY_LAST * (t[-1] - t[1])
    assert boundary == 301.0
    y = np.where(t < boundary, 2.5, 2.0)
    y[0] = 0.0
    st = plate.steady_state(t, y)
    assert st["t_steady"] == 301.0 and st["value"] == 2.0 and st["stderr"] == 0.0


@pytest.mark.parametrize("k, start", [(5.2, 3), (6.5, 4)])
def test_the_head_agrees_within_trend_sigma_combined_errors(k, start):
    """Nine samples after the prepared state (t = 1..9): final quarter t = 7, 8, 9 (1.0, 1.2, 0.8: value 1, stderr
    0.2/sqrt(3) over 3 one-sample blocks, drift -0.1 +- sqrt(0.03) by hand).  Starts 1, 1.4, 1.8 have heads holding
    y(2) = 5; the start 2.2 has the one-sample head t = 3: its tolerance is TREND_SIGMA stderr sqrt(3/1 + 1) =
    6 stderr.  y(3) = 1 + 5.2 stderr: steady from 2.2; 1 + 6.5 stderr: from 2.6 (head t = 3, 4: 3.25 < 3 sqrt(2.5))."""
    se = np.sqrt(((1.0 - 1) ** 2 + (1.2 - 1) ** 2 + (0.8 - 1) ** 2) / 2) / np.sqrt(3)
    t = np.arange(10.0)
    y = np.array([50.0, 3.0, 5.0, 1 + k * se, 1.0, 1.0, 1.0, 1.0, 1.2, 0.8])
    st = plate.steady_state(t, y)
    assert st["value"] == pytest.approx(1.0, rel=1e-14) and st["stderr"] == pytest.approx(se, rel=1e-12)
    slope, drift_err = _line([7.0, 8.0, 9.0], [1.0, 1.2, 0.8])
    assert st["drift"] == pytest.approx(slope, rel=1e-12) and slope == pytest.approx(-0.1)
    assert st["drift_err"] == pytest.approx(drift_err, rel=1e-12) and drift_err == pytest.approx(np.sqrt(0.03))
    assert st["drift_z"] == pytest.approx(slope / drift_err, rel=1e-12)
    assert st["t_steady"] == pytest.approx(_grid(t)[start], rel=1e-14)
    assert _grid(t)[start] == pytest.approx(1 + 0.4 * start)


def test_an_exponential_transient_is_steady_one_window_after_it():
    """y = 2 + exp(-t/1.24) + N(0, 0.1) every 0.1 to t = 100: value the last quarter's mean (2 within 3 stderr);
    the head excess at t = 0.1, sum exp(-t/1.24)/250 = 0.048, is beyond 3 combined errors (~0.033); one window
    later (t = 5.095) it is 1e-4 of them: t_steady = t[1] + STEADY_WINDOW (t_end - t[1])."""
    rng = np.random.default_rng(11)
    t = np.arange(1001) * 0.1
    y = 2.0 + np.exp(-t / 1.24) + 0.1 * rng.standard_normal(t.size)
    y[0] = 0.0
    st = plate.steady_state(t, y)
    last = y[t >= t[1] + plate.STEADY_LAST * (t[-1] - t[1])]
    assert len(last) == 250 and st["value"] == pytest.approx(last.mean(), rel=1e-14)
    assert abs(st["value"] - 2.0) < 3 * st["stderr"]
    head = (t >= t[1]) & (t < t[1] + (1 - plate.STEADY_LAST) * (t[-1] - t[1]))
    assert np.exp(-t[head] / 1.24).mean() == pytest.approx(0.048, abs=0.001)
    assert st["t_steady"] == pytest.approx(t[1] + plate.STEADY_WINDOW * (t[-1] - t[1]), rel=1e-14)


# --- power law --------------------------------------------------------------------------------------------------

#: u = 0.05 t^0.75 up to t = 10 (all below 1; u(0) = 0), then 0.05 10^0.75 (t/10)^2: a broken power law
T_PL = np.arange(0.0, 21.0)
U_PL = np.where(T_PL <= 10, 0.05 * T_PL ** 0.75, 0.05 * 10 ** 0.75 * (T_PL / 10) ** 2)


def test_a_pure_power_law_has_its_exponent_and_no_error():
    """Over [0, 10]: the 10 positive samples (u(0) = 0 left out), exponent 0.75 exactly, error 0; over [10, 20]
    the second branch, exponent 2."""
    fit = plate.power_law(T_PL, U_PL, 0.0, 10.0)
    assert fit["n"] == 10 and fit["alpha"] == pytest.approx(0.75, rel=1e-12) and fit["stderr"] < 1e-12
    assert fit["ci95"][0] == pytest.approx(0.75, rel=1e-10) and fit["ci95"][1] == pytest.approx(0.75, rel=1e-10)
    late = plate.power_law(T_PL, U_PL, 10.0, 20.0)
    assert late["n"] == 11 and late["alpha"] == pytest.approx(2.0, rel=1e-9)


def test_a_fit_across_the_break_shows_its_lack_of_fit():
    """Over [1, 20] across the break: the least-squares slope and stderr by hand (1.04 +- 0.063), an interval
    t.ppf(0.975, 18) stderr wide each side that holds neither branch's exponent."""
    fit = plate.power_law(T_PL, U_PL, 1.0, 20.0)
    slope, se = _line(np.log(T_PL[1:]), np.log(U_PL[1:]))
    assert fit["n"] == 20 and fit["alpha"] == pytest.approx(slope, rel=1e-12)
    assert fit["stderr"] == pytest.approx(se, rel=1e-10) and se == pytest.approx(0.0628, abs=1e-4)
    half = stats.t.ppf(0.975, 18) * se
    assert fit["ci95"][0] == pytest.approx(slope - half, rel=1e-10)
    assert fit["ci95"][1] == pytest.approx(slope + half, rel=1e-10)
    assert 0.75 < fit["ci95"][0] and fit["ci95"][1] < 2.0


def test_a_power_law_needs_four_samples():
    """Four samples fit (interval t.ppf(0.975, 2) stderr); three give nan and say n = 3."""
    t = np.array([1.0, 2.0, 3.0, 4.0, 5.0])
    u = 3.0 * np.sqrt(t) * np.exp(0.05 * (-1.0) ** np.arange(5))
    four = plate.power_law(t, u, 1.0, 4.0)
    slope, se = _line(np.log(t[:4]), np.log(u[:4]))
    assert four["n"] == 4 and four["alpha"] == pytest.approx(slope, rel=1e-12)
    assert four["stderr"] == pytest.approx(se, rel=1e-10)
    assert four["ci95"][1] - four["alpha"] == pytest.approx(stats.t.ppf(0.975, 2) * se, rel=1e-10)
    three = plate.power_law(t, u, 2.0, 4.0)
    assert three["n"] == 3 and np.isnan(three["alpha"]) and np.isnan(three["stderr"])
    assert np.isnan(three["ci95"][0]) and np.isnan(three["ci95"][1])
