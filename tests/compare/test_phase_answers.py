"""compare.phase against answers known in closed form or counted by hand: the wrap's boundaries; which samples
make a whole cycle (a non-integer number of samples per period, the one-step slack and ROUNDING); the harmonic's
per-cycle errors and Student-t interval; phase averages and a Stokes-layer profile on sparse samples (empty bins);
yielded depths on curved profiles; remobilisation strains of plates whose reversals, friction and displacement are
known; the periodic-state check at its amplitude and phase edges, on one and two cycles; the lag against a second
record, the peak's lag and the amplitude profile; the dissipation's per-cycle loop areas.

How the answers are independent: every record is a sum of sinusoids (or a plate snapping at a reversal) whose
per-cycle amplitude, phase and mean are chosen by the test, sampled uniformly over whole periods, where least
squares and the trapezoid rule are exact; the expected values are those closed forms (loop area
pi u tau cos(lag)/omega; strain U (1 - cos chi)/omega/depth with chi = lag + arcsin(level)), counts of samples by
integer arithmetic, and the documented statistics done here in plain numpy (error = std(ddof=1)/sqrt(n),
Student-t quantiles from scipy.stats, the change of complex amplitudes written out).  Nothing expected is
computed by compare.phase; its constants (ROUNDING, PHASE_BINS, PERIODIC_TOLERANCE) are imported.
"""
from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest
from granstokes.compare import phase
from granstokes.compare.phase import PERIODIC_TOLERANCE, PHASE_BINS, ROUNDING
from scipy import stats

OMEGA = 2.0
PERIOD = 2 * np.pi / OMEGA


def _uniform(cycles: int, per_cycle: int) -> tuple[np.ndarray, np.ndarray]:
    """Samples at i T/per_cycle over [0, cycles T] and each one's cycle (i // per_cycle, by integers)."""
    i = np.arange(cycles * per_cycle + 1)
    return i * PERIOD / per_cycle, i // per_cycle


def test_wrap_keeps_pi_and_sends_minus_pi_and_three_half_pi_into_the_half_open_range():
    got = phase.wrap([np.pi, -np.pi, 1.5 * np.pi, -1.5 * np.pi, 0.3 + 4 * np.pi, -0.3 - 6 * np.pi, 0.0])
    assert got == pytest.approx([np.pi, np.pi, -0.5 * np.pi, 0.5 * np.pi, 0.3, -0.3, 0.0], abs=1e-12)


def test_cycle_members_follow_the_boundaries_with_seven_and_a_half_samples_per_period():
    """Sample i at i T/7.5 is in cycle k when 7.5 k <= i < 7.5 (k + 1); samples 15, 30 and 45 fall on a boundary
    (up to rounding) and open their cycle; cycle 6 (one sample, at 6 T) is not whole."""
    t = np.arange(46) * PERIOD / 7.5
    got = phase.cycles(t, OMEGA)
    first = [(15 * k + 1) // 2 for k in range(7)]  # ceil(7.5 k) by integers
    assert list(got) == [1, 2, 3, 4, 5]
    for k in got:
        assert got[k].tolist() == list(range(first[k], first[k + 1]))


def test_a_cycle_is_whole_when_the_samples_reach_its_ends_within_one_step_up_to_rounding():
    """7.5 samples a period.  A record starting one step (plus half a ROUNDING period) after 1 T has cycle 1 whole,
    one starting one step and 3 ROUNDING periods after it has not; likewise at the end, a record stopping one step
    and ROUNDING periods short of 4 T has cycle 3 whole, one stopping 3 ROUNDING periods further short has not."""
    step = PERIOD / 7.5
    n = np.arange(22)
    assert list(phase.cycles(PERIOD + step + 0.5 * ROUNDING * PERIOD + n * step, OMEGA, skip=0)) == [1, 2, 3]
    assert list(phase.cycles(PERIOD + step + 3 * ROUNDING * PERIOD + n * step, OMEGA, skip=0)) == [2, 3]
    for gap, whole in ((1.0, [1, 2, 3]), (3.0, [1, 2])):
        end = 4 * PERIOD - step - gap * ROUNDING * PERIOD
        t = end - np.arange(29)[::-1] * step  # from just after 0 (within one step) up to ``end``
        assert 0 < t[0] < step and list(phase.cycles(t, OMEGA)) == whole


def test_cycle_slack_is_one_step_between_distinct_times_and_none_for_a_single_time():
    """A long table (each time repeated per depth): two times 0.6 T apart reach both ends of cycle 0 within one
    step, so it is whole; a table of one time (omega = 2 pi, so T = 1) has no whole cycle."""
    two = np.repeat([0.0, 0.6 * PERIOD], 3)
    got = phase.cycles(two, OMEGA, skip=0)
    assert list(got) == [0] and got[0].tolist() == [0, 1, 2, 3, 4, 5]
    assert phase.cycles(np.full(3, 0.5), 2 * np.pi, skip=0) == {}


def test_harmonic_refuses_an_average_over_a_whole_period():
    t, _ = _uniform(4, 32)
    with pytest.raises(ValueError, match="one period"):
        phase.harmonic(t, np.sin(OMEGA * t), OMEGA, interval=PERIOD)  # omega interval = 2 pi exactly


def test_harmonic_without_a_whole_cycle_is_nan_and_says_why():
    t, _ = _uniform(2, 32)
    h = phase.harmonic(t[:40], np.sin(OMEGA * t[:40]), OMEGA, skip=1)
    assert h.n_cycles == 0 and np.isnan([h.amplitude, h.phase, h.mean, h.amplitude_err]).all()
    assert "no whole cycle" in h.note


def test_harmonic_of_one_whole_cycle_has_its_values_but_no_errors():
    t, _ = _uniform(2, 32)  # cycle 1 only, after the start-up
    h = phase.harmonic(t, 0.4 + 1.5 * np.sin(OMEGA * t + 2.0), OMEGA)
    assert h.n_cycles == 1 and "needs 2" in h.note
    assert (h.amplitude, h.phase, h.mean) == pytest.approx((1.5, 2.0, 0.4), abs=1e-12)
    assert np.isnan([h.amplitude_err, h.phase_err, h.mean_err]).all()


def test_harmonic_errors_are_the_spread_of_two_cycles_fits_over_root_two():
    """Cycles 0 and 1 (skip=0) with mean, amplitude and phase (0.3, 1.0, 0.1) and (0.2, 1.2, -0.1), read as
    averages over half a period: each cycle's fit is exact, amplitude / sinc(1/2) = A pi/2 and phase + pi/2; the
    whole fit is the mean of the cycles' [1, sin, cos] coefficients; each error is std(ddof=1)/sqrt(2) of the two
    cycles' values.  The phases pi/2 +- 0.1 would split at +-pi if they were centred on anything but the estimate."""
    t, k = _uniform(2, 40)
    m, a, q = np.array([0.3, 0.2, 0.2]), np.array([1.0, 1.2, 1.2]), np.array([0.1, -0.1, -0.1])
    y = m[k] + a[k] * np.sin(OMEGA * t + q[k])
    h = phase.harmonic(t, y, OMEGA, skip=0, interval=PERIOD / 2)
    s, c = np.mean(a[:2] * np.cos(q[:2])), np.mean(a[:2] * np.sin(q[:2]))
    assert h.n_cycles == 2 and h.note == ""
    assert (h.mean, h.amplitude, h.phase) == pytest.approx(
        (0.25, np.hypot(s, c) * np.pi / 2, np.arctan2(c, s) + np.pi / 2), abs=1e-12)
    spread = lambda v: np.std(v, ddof=1) / np.sqrt(2)  # noqa: E731
    assert (h.mean_err, h.amplitude_err, h.phase_err) == pytest.approx(
        (spread(m[:2]), spread(a[:2] * np.pi / 2), spread(q[:2])), abs=1e-12)
    assert h.phase_err == pytest.approx(0.1, abs=1e-12)


def test_harmonic_interval_is_student_t_with_n_cycles_minus_one_dof():
    h = phase.Harmonic(amplitude=2.0, phase=0.5, mean=0.1, amplitude_err=0.3, phase_err=0.05, mean_err=0.02,
                       n_cycles=4)
    q95, q90 = stats.t.ppf(0.975, 3), stats.t.ppf(0.95, 3)
    assert h.interval("amplitude") == pytest.approx((2.0 - 0.3 * q95, 2.0 + 0.3 * q95), abs=1e-12)
    assert h.interval("phase", level=0.9) == pytest.approx((0.5 - 0.05 * q90, 0.5 + 0.05 * q90), abs=1e-12)
    assert h.interval("mean") == pytest.approx((0.1 - 0.02 * q95, 0.1 + 0.02 * q95), abs=1e-12)


def _sparse(cycles: int) -> tuple[np.ndarray, np.ndarray]:
    """Times at the centres of the even phase bins (PHASE_BINS a period, so the odd bins stay empty) over
    ``cycles`` cycles, and each one's cycle."""
    k, m = np.meshgrid(np.arange(cycles), np.arange(0, PHASE_BINS, 2) + 0.5, indexing="ij")
    return (k + m / PHASE_BINS).ravel() * PERIOD, k.ravel()


def test_phase_average_of_sparse_samples_leaves_the_empty_bins_with_no_cycles():
    """y = A_k sin(omega t) with A_k per cycle, one sample per even bin at its centre; skip=2 keeps cycles 2-5:
    an even bin's mean is mean(A_2..A_5) sin(centre), its error std(A, ddof=1)/2 |sin(centre)|, n_cycles 4; an odd
    bin has no sample: nan and 0 cycles."""
    amp = np.array([3.0, 2.0, 1.0, 1.2, 0.9, 1.3])
    t, k = _sparse(len(amp))
    y = amp[k] * np.sin(OMEGA * t)
    avg = phase.phase_average(t, y, OMEGA, skip=2)
    centre = (np.arange(PHASE_BINS) + 0.5) * 2 * np.pi / PHASE_BINS
    even = np.arange(PHASE_BINS) % 2 == 0
    kept = amp[2:]
    assert list(avg.columns) == ["phase", "mean", "err", "n_cycles"] and list(avg.index) == list(range(PHASE_BINS))
    assert avg.phase.to_numpy() == pytest.approx(centre, abs=1e-12)
    assert avg["mean"][even].to_numpy() == pytest.approx(kept.mean() * np.sin(centre[even]), abs=1e-12)
    assert avg.err[even].to_numpy() == pytest.approx(
        np.std(kept, ddof=1) / 2 * np.abs(np.sin(centre[even])), abs=1e-12)
    assert avg["mean"][~even].isna().all() and avg.err[~even].isna().all()
    assert avg.n_cycles.dtype.kind == "i" and avg.n_cycles.tolist() == [4, 0] * (PHASE_BINS // 2)


def test_phase_profile_of_a_stokes_layer_on_sparse_samples():
    """A long table of u = A_k e^{-y/delta} sin(omega t - y/delta) (amplitude decaying, phase lagging with depth y)
    at the even bins' centres, rows shuffled; skip=2: mean(A) e^{-y/delta} sin(centre - y/delta) and its error,
    (phase x depth) tables named as such, empty bins nan with 0 cycles."""
    amp, delta, depth = np.array([3.0, 2.0, 1.0, 1.2, 0.9, 1.3]), 1.3, np.array([0.0, 0.5, 1.0, 2.0])
    t, k = _sparse(len(amp))
    tt, yy = np.meshgrid(t, depth, indexing="ij")
    a = amp[k][:, None]
    df = pd.DataFrame({"t": tt.ravel(), "depth": yy.ravel(),
                       "u": (a * np.exp(-yy / delta) * np.sin(OMEGA * tt - yy / delta)).ravel()})
    grid = phase.phase_profile(df.sample(frac=1.0, random_state=4), OMEGA, "u", skip=2)
    centre = (np.arange(PHASE_BINS) + 0.5) * 2 * np.pi / PHASE_BINS
    even = np.arange(PHASE_BINS) % 2 == 0
    shape = np.exp(-depth / delta) * np.sin(centre[even, None] - depth / delta)
    for name in ("mean", "err", "n_cycles"):
        table = grid[name]
        assert table.index.name == "phase" and table.columns.name == "depth"
        assert table.index.to_numpy() == pytest.approx(centre, abs=1e-12) and list(table.columns) == list(depth)
    assert grid["mean"].to_numpy()[even] == pytest.approx(amp[2:].mean() * shape, abs=1e-12)
    assert grid["err"].to_numpy()[even] == pytest.approx(np.std(amp[2:], ddof=1) / 2 * np.abs(shape), abs=1e-12)
    assert grid["mean"].to_numpy()[~even].size and np.isnan(grid["mean"].to_numpy()[~even]).all()
    counts = grid["n_cycles"].to_numpy()
    assert counts.dtype.kind == "i" and (counts[even] == 4).all() and (counts[~even] == 0).all()


def test_dissipation_is_each_cycles_loop_area_with_the_spread_over_root_n():
    """u = U sin(omega t), tau = a_k sin(omega t + lag) with a_k per cycle: cycle k dissipates pi U a_k cos(lag) /
    omega (the trapezoid is exact over a period's uniform samples); the error is std(ddof=1)/sqrt(n), from n = 2."""
    u, lag, a = 0.7, 0.6, np.array([2.0, 0.5, 0.4, 0.5, 0.7, 0.55, 0.55])
    t, k = _uniform(6, 32)
    w = np.pi * u * a * np.cos(lag) / OMEGA
    for skip in (2, 4):  # cycles 2-5, and cycles 4-5
        got = phase.dissipation(t, u * np.sin(OMEGA * t), a[k] * np.sin(OMEGA * t + lag), OMEGA, skip=skip)
        assert got["values"] == pytest.approx(w[skip:6], rel=1e-12)
        assert got["value"] == pytest.approx(w[skip:6].mean(), rel=1e-12)
        assert got["stderr"] == pytest.approx(np.std(w[skip:6], ddof=1) / np.sqrt(6 - skip), rel=1e-9)


def test_dissipation_of_one_or_no_whole_cycle_is_quiet():
    """One whole cycle: its area and a nan error; none: nan; no numpy warning either way."""
    u, tau, lag = 0.7, 0.4, 0.6
    t, _ = _uniform(6, 32)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        one = phase.dissipation(t, u * np.sin(OMEGA * t), tau * np.sin(OMEGA * t + lag), OMEGA, skip=5)
        none = phase.dissipation(t[:40], u * np.sin(OMEGA * t[:40]), tau * np.sin(OMEGA * t[:40] + lag), OMEGA)
    assert one["value"] == pytest.approx(np.pi * u * tau * np.cos(lag) / OMEGA, rel=1e-12)
    assert len(one["values"]) == 1 and np.isnan(one["stderr"])
    assert len(none["values"]) == 0 and np.isnan(none["value"]) and np.isnan(none["stderr"])


def test_dissipation_leaves_out_samples_missing_in_any_column():
    """None (an object column) or nan in the start-up cycle: those samples are dropped, cycles 1-5 unchanged."""
    u, tau, lag = 0.7, 0.4, 0.6
    t, _ = _uniform(6, 32)
    speed, friction = list(u * np.sin(OMEGA * t)), tau * np.sin(OMEGA * t + lag)
    speed[3], friction[7] = None, np.nan
    got = phase.dissipation(list(t), speed, friction, OMEGA)
    assert got["values"] == pytest.approx([np.pi * u * tau * np.cos(lag) / OMEGA] * 5, rel=1e-12)


def test_yielded_depth_interpolates_the_crossing_between_the_bracketing_depths():
    """Curved profiles on an uneven grid (a straight line would hide a wrong bracket): 0.8 e^{-y/1.2} crosses 0.3
    between y = 1.0 and 1.5; -0.9 e^{-y/3} between 3.0 and 4.0, the last two depths."""
    depth = np.array([0.2, 0.5, 1.0, 1.5, 2.5, 3.0, 4.0])
    mu = np.array([0.8 * np.exp(-depth / 1.2), -0.9 * np.exp(-depth / 3.0)])

    def crossing(f, y0, y1):  # linear between the two depths
        e0, e1 = f(y0) - 0.3, f(y1) - 0.3
        return y0 + e0 / (e0 - e1) * (y1 - y0)

    expected = [crossing(lambda y: 0.8 * np.exp(-y / 1.2), 1.0, 1.5),
                crossing(lambda y: 0.9 * np.exp(-y / 3.0), 3.0, 4.0)]
    assert 1.0 < expected[0] < 1.5 and 3.0 < expected[1] < 4.0
    assert phase.yielded_depth(depth, mu, 0.3) == pytest.approx(expected, abs=1e-12)


def test_a_depth_exactly_at_the_threshold_is_yielded():
    depth = np.array([0.5, 1.0, 1.5, 2.0])
    mu = np.array([[0.5, 0.25, 0.25, 0.125],  # down to 1.5 (at mu_s), then below
                   [0.25, 0.125, 0.0, 0.0]])  # only the first depth, at mu_s
    assert phase.yielded_depth(depth, mu, 0.25) == pytest.approx([1.5, 0.5], abs=1e-12)


def test_yielded_depth_is_quiet_where_nothing_or_everything_yields():
    """Never yielded: 0; yielded to the last depth (above mu_s, or exactly at it): the last depth; no floating-point
    error raised (numpy set to raise)."""
    depth = np.array([0.5, 1.0, 1.5, 2.0])
    mu = np.array([[0.2, 0.1, 0.1, 0.05], [0.5, 0.4, 0.35, 0.3], [0.5, 0.4, 0.3, 0.25]])
    with np.errstate(all="raise"):
        got = phase.yielded_depth(depth, mu, 0.25)
    assert got == pytest.approx([0.0, 2.0, 2.0], abs=0)


U, TAU, DEPTH, LEVEL = 0.8, 0.5, 4.0, 0.9
PER_CYCLE = 16 * PHASE_BINS  # 16 samples a phase bin, symmetric about its centre


def _times(cycles: int = 6) -> np.ndarray:
    """Samples at the middles of PER_CYCLE equal steps: each bin's mean of a straight line is its centre value."""
    return (np.arange(cycles * PER_CYCLE) + 0.5) * PERIOD / PER_CYCLE


@pytest.mark.parametrize("shift", [np.pi / 48, np.pi / 2])
def test_remobilization_strain_alternates_with_a_biased_friction_after_a_creeping_start(shift):
    """Plate speed U sin(psi), psi = omega t - shift (its reversals at omega t = shift and pi + shift: pi/48, just
    after each cycle's start, or pi/2), plus U/2 during the start-up cycles 0-1 (skip=2; the displacement creeps
    accordingly); friction TAU (sin(psi - lag) + b).  After an up reversal s tau reaches LEVEL of its peak
    TAU (1 + b) at chi = lag + arcsin(LEVEL - (1 - LEVEL) b), after a down one TAU (1 - b) at lag + arcsin(LEVEL +
    (1 - LEVEL) b); the strain is U (1 - cos chi)/omega/DEPTH.  Cycles 2-5 give up, down, ..., up: 7 half-cycles."""
    lag, b = np.pi / 6, 0.5
    t = _times()
    psi = OMEGA * t - shift
    creep = 0.5 * U * (t < 2 * PERIOD)
    x = U / OMEGA * (1 - np.cos(psi)) + 0.5 * U * np.minimum(t, 2 * PERIOD)
    got = phase.remobilization_strain(t, x, U * np.sin(psi) + creep, TAU * (np.sin(psi - lag) + b), OMEGA, DEPTH,
                                      LEVEL, skip=2)
    up, down = (U * (1 - np.cos(lag + np.arcsin(LEVEL + s * (1 - LEVEL) * b))) / OMEGA / DEPTH for s in (-1, 1))
    expected = np.array([up, down] * 3 + [up])
    assert got["values"] == pytest.approx(expected, rel=2e-4)
    assert got["value"] == pytest.approx(expected.mean(), rel=2e-4)
    assert got["stderr"] == pytest.approx(np.std(expected, ddof=1) / np.sqrt(7), rel=2e-3)


def test_remobilization_strain_of_a_snapping_plate_reversing_next_to_its_extremes():
    """Plate speed U sin(psi_w/2), psi_w = psi wrapped into (-pi, pi], psi = omega t - pi/2: it rises through zero at
    psi = 0 and snaps from +U to -U at psi = pi, so its largest and smallest phase bins sit on either side of that
    reversal (and, curved, the bins before an extreme do not point at a zero).  Displacement (its integral)
    2 U (1 - cos(psi_w/2))/omega; friction TAU sin(psi - lag) reaches LEVEL of its peak at chi = lag +
    arcsin(LEVEL) after either reversal: the strain is x(chi) - x(0) after an up reversal, x(pi) - x(pi - chi) after
    the snap, over DEPTH, with x at a reversal read by linear interpolation between the samples half a step either
    side (at the snap's cusp that is x(pi - half a step)).  Cycles 1-5: up, down, ..., up (9 half-cycles)."""
    lag = np.pi / 6
    t = _times()
    psi = OMEGA * t - np.pi / 2
    psi_w = np.where(np.mod(psi, 2 * np.pi) > np.pi, np.mod(psi, 2 * np.pi) - 2 * np.pi, np.mod(psi, 2 * np.pi))
    x = 2 * U * (1 - np.cos(psi_w / 2)) / OMEGA
    got = phase.remobilization_strain(t, x, U * np.sin(psi_w / 2), TAU * np.sin(psi - lag), OMEGA, DEPTH, LEVEL)
    chi, half = lag + np.arcsin(LEVEL), np.pi / PER_CYCLE  # half a step in phase
    at = lambda p: 2 * U * (1 - np.cos(p / 2)) / OMEGA  # noqa: E731  x at psi_w = p
    up, down = (at(chi) - at(half)) / DEPTH, (at(np.pi - half) - at(np.pi - chi)) / DEPTH
    assert got["values"] == pytest.approx(np.array([up, down] * 4 + [up]), rel=2e-4)


def test_a_friction_leading_the_plate_is_remobilised_at_the_reversal():
    """Friction TAU sin(psi + 1.2), plate U sin(psi), psi = omega t - 0.05 (reversals off the sampling grid): right
    after each reversal s tau = sin(1.2) TAU = 0.93 TAU, already above LEVEL of its peak TAU: the strain is 0 in
    every half-cycle."""
    t = _times()
    psi = OMEGA * t - 0.05
    got = phase.remobilization_strain(t, U / OMEGA * (1 - np.cos(psi)), U * np.sin(psi), TAU * np.sin(psi + 1.2),
                                      OMEGA, DEPTH, LEVEL)
    assert len(got["values"]) == 9 and (got["values"] == 0).all() and got["value"] == 0 and got["stderr"] == 0


def test_remobilization_to_the_full_peak_stops_at_the_peak_sample():
    """fraction 1: the strain up to the friction's peak, chi = lag + pi/2, put on a sample (chi = 170.5 steps)."""
    step = 2 * np.pi / PER_CYCLE
    lag = 170.5 * step - np.pi / 2
    t = _times()
    got = phase.remobilization_strain(t, U / OMEGA * (1 - np.cos(OMEGA * t)), U * np.sin(OMEGA * t),
                                      TAU * np.sin(OMEGA * t - lag), OMEGA, DEPTH, fraction=1.0)
    assert got["values"] == pytest.approx([U * (1 - np.cos(170.5 * step)) / OMEGA / DEPTH] * 9, rel=1e-4)


def _per_cycle(amplitudes, phases, per_cycle: int = 32, mean: float = 0.1):
    """Whole cycles 0..n-1 sampled uniformly, cycle k a sine of amplitude ``amplitudes[k]`` and phase
    ``phases[k]``: each cycle's fit is exactly its own (least squares on a whole cycle's uniform samples)."""
    t, k = _uniform(len(amplitudes), per_cycle)
    k = np.minimum(k, len(amplitudes) - 1)
    return t, mean + np.asarray(amplitudes)[k] * np.sin(OMEGA * t + np.asarray(phases)[k])


def _hand_change(a0, q0, a1, q1) -> float:
    """|a1 e^(i q1) - a0 e^(i q0)| / max(a0, a1), written out."""
    return np.hypot(a1 * np.cos(q1) - a0 * np.cos(q0), a1 * np.sin(q1) - a0 * np.sin(q0)) / max(a0, a1)


@pytest.mark.parametrize(("last", "periodic"), [(1 - PERIODIC_TOLERANCE + 1e-6, True),
                                                (1 - PERIODIC_TOLERANCE - 1e-6, False)])
def test_the_periodic_state_s_amplitude_edge_is_the_tolerance(last, periodic):
    """Amplitudes 3 (the start-up, skipped), 1.0, 0.2, ``last`` at one phase: the change from the first kept cycle
    to the last is 1 - last (the middle cycle does not count), just inside or just outside PERIODIC_TOLERANCE."""
    t, y = _per_cycle([3.0, 1.0, 0.2, last], [0.4] * 4)
    got = phase.periodicity(t, y, OMEGA)
    assert list(got["cycles"].cycle) == [1, 2, 3]
    assert got["cycles"].amplitude.to_numpy() == pytest.approx([1.0, 0.2, last], abs=1e-12)
    assert got["cycles"].phase.to_numpy() == pytest.approx([0.4] * 3, abs=1e-12)
    assert got["change"] == pytest.approx(_hand_change(1.0, 0.4, last, 0.4), abs=1e-12)
    assert got["change"] == pytest.approx(1 - last, abs=1e-12) and got["periodic"] is periodic


@pytest.mark.parametrize(("turn", "periodic"), [(2 * np.arcsin(PERIODIC_TOLERANCE / 2) - 1e-6, True),
                                                (2 * np.arcsin(PERIODIC_TOLERANCE / 2) + 1e-6, False)])
def test_the_periodic_state_s_phase_edge_is_a_turn_of_two_arcsin_half_the_tolerance(turn, periodic):
    """One amplitude, the phase turning by ``turn`` from the first kept cycle (2) to the last (4; skip 2): the
    change is 2 sin(turn/2), the tolerance's edge at turn = 2 arcsin(tolerance/2) (29 degrees at 0.5)."""
    t, y = _per_cycle([0.5, 0.5, 0.8, 0.8, 0.8], [0.0, 0.0, -1.0, -1.0 + turn / 3, -1.0 + turn])
    got = phase.periodicity(t, y, OMEGA, skip=2)
    assert list(got["cycles"].cycle) == [2, 3, 4]
    assert got["change"] == pytest.approx(_hand_change(0.8, -1.0, 0.8, -1.0 + turn), abs=1e-12)
    assert got["change"] == pytest.approx(2 * np.sin(turn / 2), abs=1e-12) and got["periodic"] is periodic


def test_the_periodic_state_of_one_kept_cycle_is_untested_and_of_two_is_tested():
    t, y = _per_cycle([1.0, 1.0], [0.0, 0.0])
    one = phase.periodicity(t, y, OMEGA)
    assert len(one["cycles"]) == 1 and one["periodic"] is None and np.isnan(one["change"])
    t, y = _per_cycle([1.0, 1.0, 2.0], [0.0, 0.0, 0.0])
    two = phase.periodicity(t, y, OMEGA)
    assert two["change"] == pytest.approx(0.5, abs=1e-12) and two["periodic"] is True  # 1 -> 2: half of 2


def test_change_is_the_distance_of_two_complex_amplitudes_over_the_larger():
    assert phase.change(1.0, -1.0) == pytest.approx(2.0)  # opposite phases
    assert phase.change(2.0, 1.0) == pytest.approx(0.5) and phase.change(1.0, 2.0) == pytest.approx(0.5)
    assert phase.change(3j, 4.0) == pytest.approx(5.0 / 4.0)  # |4 - 3i| = 5 over the larger 4
    assert phase.change(0.0, 0.0) == 0.0


def test_the_lag_against_a_reference_is_the_difference_of_the_two_fits_phases_with_the_per_cycle_spread():
    """Response and reference with per-cycle phases (cycles 1-3 kept): whole-record fits are the means of the
    per-cycle complex amplitudes (uniform whole cycles), the lag is wrap(reference's phase - response's), and its
    error the spread of the per-cycle lags wrap(q_r - q_y) about it over sqrt(3)."""
    a_y, q_y = np.array([1.0, 1.0, 1.2, 0.9]), np.array([0.0, 0.3, 0.2, 0.4])
    a_r, q_r = np.array([2.0, 2.0, 2.0, 2.1]), np.array([0.0, 1.1, 1.3, 1.0])
    t, y = _per_cycle(a_y, q_y)
    _, r = _per_cycle(a_r, q_r, mean=-0.2)
    z_y, z_r = np.mean(a_y[1:] * np.exp(1j * q_y[1:])), np.mean(a_r[1:] * np.exp(1j * q_r[1:]))
    expected = np.angle(z_r) - np.angle(z_y)
    per = (q_r[1:] - q_y[1:]) - expected
    value, err, n = phase.lag(t, y, OMEGA, reference=r)
    assert n == 3 and value == pytest.approx(expected, abs=1e-12)
    assert err == pytest.approx(np.std(per, ddof=1) / np.sqrt(3), rel=1e-9)
    # against the imposed sine: minus the response's phase, the harmonic's error
    value, err, n = phase.lag(t, y, OMEGA)
    h = phase.harmonic(t, y, OMEGA)
    assert value == pytest.approx(-np.angle(z_y), abs=1e-12) and err == h.phase_err and n == 3


def test_the_peak_s_lag_on_a_bin_centre_is_exact_and_undoes_the_averaging_delay():
    """A response whose phase-averaged peak falls on the centre of bin 8 (17 pi/24), sampled symmetrically about
    the bins' centres (20 samples a bin, half a step off its edges): sin(omega t - lag) with lag = 17 pi/24 - pi/2
    = 5 pi/24, read exactly (the bins beside it are equal: the parabola's vertex is the centre).  The same response
    averaged over the interval ending at each sample peaks omega interval/2 later: with the interval given, the lag
    is the same."""
    t, _ = _uniform(5, 24 * 20)
    t = t[:-1] + PERIOD / (24 * 20) / 2
    lag = 5 * np.pi / 24
    assert phase.peak_lag(t, np.sin(OMEGA * t - lag), OMEGA) == pytest.approx(lag, abs=1e-12)
    interval = PERIOD / 24  # the delay omega interval/2 = pi/24: the peak moves half a bin
    late = lag - np.pi / 24  # whose delayed peak is again on bin 8's centre
    delayed = np.sin(OMEGA * (t - interval / 2) - late)
    assert phase.peak_lag(t, delayed, OMEGA, interval=interval) == pytest.approx(late, abs=1e-12)


def test_the_peak_s_lag_reads_the_bins_where_their_samples_are():
    """Four samples a bin on the bins' edges (the plate record's grid of 96 a period): a bin's samples sit 1.5/4 of
    a bin from its start, an eighth of a bin (0.033 rad) before its centre; the peak of sin(omega t - 0.4) is read
    within 1e-3 rad (a parabola through three points of a cosine 0.26 rad apart), not 0.033 early."""
    t, _ = _uniform(5, 96)
    assert phase.peak_lag(t, np.sin(OMEGA * t - 0.4), OMEGA) == pytest.approx(0.4, abs=1e-3)


def test_the_peak_s_lag_differs_from_the_fundamental_s_for_a_response_with_a_second_harmonic():
    """sin(psi) + 0.3 sin(2 psi), psi = omega t - 0.3: the first harmonic lags by 0.3 exactly; the peak is where
    cos psi + 0.6 cos 2 psi = 0, i.e. 1.2 c^2 + c - 0.6 = 0 with c = cos psi: psi* = arccos((-1 + sqrt(3.88))/2.4)
    = 1.155, the lag psi* + 0.3 - pi/2 = -0.116 (to 0.01: a parabola through three bins of a non-sinusoidal
    peak)."""
    t, _ = _uniform(5, 96)
    psi = OMEGA * t - 0.3
    y = np.sin(psi) + 0.3 * np.sin(2 * psi)
    peak = np.arccos((-1 + np.sqrt(1 + 4 * 1.2 * 0.6)) / 2.4)
    assert phase.peak_lag(t, y, OMEGA) == pytest.approx(peak + 0.3 - np.pi / 2, abs=0.01)
    assert phase.lag(t, y, OMEGA)[0] == pytest.approx(0.3, abs=1e-12)


def test_the_amplitude_profile_is_each_depth_s_first_harmonic_over_the_kept_cycles():
    """Two depths whose amplitudes change after the start-up cycle: the profile reads the kept cycles' (1.5 at
    depth 1, 0.25 at depth 3), sorted by depth."""
    t, k = _uniform(4, 24)
    rows = []
    for depth, start, kept in ((3.0, 9.0, 0.25), (1.0, 0.1, 1.5)):
        amplitude = np.where(k == 0, start, kept)
        rows.append(pd.DataFrame({"t": t, "depth": depth, "u": 0.2 + amplitude * np.sin(OMEGA * t - depth)}))
    got = phase.amplitude_profile(pd.concat(rows, ignore_index=True), OMEGA, "u")
    assert list(got.index) == [1.0, 3.0] and got.to_numpy() == pytest.approx([1.5, 0.25], abs=1e-12)


def test_cycle_harmonics_by_default_keeps_cycles_after_the_first_with_no_average_undone():
    """Cycles of amplitudes 3, 1, 0.5, 0.8 and phases 0.1-0.4 about a mean 0.7: the defaults (skip 1, no interval)
    give cycles 1-3 with their own amplitude, phase and mean (the mean column, not the amplitude)."""
    t, y = _per_cycle([3.0, 1.0, 0.5, 0.8], [0.1, 0.2, 0.3, 0.4], mean=0.7)
    got = phase.cycle_harmonics(t, y, OMEGA)
    assert list(got.cycle) == [1, 2, 3]
    assert got.amplitude.to_numpy() == pytest.approx([1.0, 0.5, 0.8], abs=1e-12)
    assert got.phase.to_numpy() == pytest.approx([0.2, 0.3, 0.4], abs=1e-12)
    assert got["mean"].to_numpy() == pytest.approx([0.7] * 3, abs=1e-12)


def test_the_periodic_state_s_cycles_undo_the_averaging_interval():
    """Samples averaged over an interval of 0.4 period ending at each: a sin(omega t + q) reads a sinc(0.4) sin(omega
    t + q - 0.4 pi); the per-cycle fundamentals are the unaveraged a and q again."""
    width = 0.4
    t, y = _per_cycle([2.0, 1.0, 1.0], [0.5 - width * np.pi] * 3)
    y = y * np.sin(width * np.pi) / (width * np.pi)
    got = phase.periodicity(t, y, OMEGA, interval=width * PERIOD)
    assert got["cycles"].amplitude.to_numpy() == pytest.approx([1.0, 1.0], abs=1e-12)
    assert got["cycles"].phase.to_numpy() == pytest.approx([0.5, 0.5], abs=1e-12)
    assert got["change"] == pytest.approx(0.0, abs=1e-12) and got["periodic"] is True


def _lag_records(interval: float):
    """Response and reference sampled as averages over ``interval`` (phases delayed by omega interval/2) with
    per-cycle lags q_r - q_y near pi/2 (cycles 0-3): the unaveraged phases, the two records and t."""
    delay = OMEGA * interval / 2
    q_y = np.array([0.0, 0.2, -0.1, 0.1])
    q_r = q_y + np.array([0.0, 1.45, 1.70, 1.55])
    t, y = _per_cycle([1.0] * 4, q_y - delay)
    _, r = _per_cycle([1.5] * 4, q_r - delay, mean=0.3)
    return q_y, q_r, t, y, r


def test_the_lag_against_a_reference_undoes_both_records_averaging_and_spreads_the_cycles_about_it():
    """Lags near pi/2 (1.45, 1.70, 1.55) and a delay omega interval/2 = pi - 0.05: value and error are those of the
    unaveraged records, wrap(angle(mean z_r) - angle(mean z_y)) and std(ddof=1)/sqrt(3) of the per-cycle lags about
    it (a delay left on one record, or the value added instead of removed, would wrap some cycles' lags by 2 pi)."""
    interval = 2 * (np.pi - 0.05) / OMEGA
    q_y, q_r, t, y, r = _lag_records(interval)
    expected = np.angle(np.mean(np.exp(1j * q_r[1:]))) - np.angle(np.mean(np.exp(1j * q_y[1:])))
    per = (q_r[1:] - q_y[1:]) - expected
    value, err, n = phase.lag(t, y, OMEGA, interval=interval, reference=r)
    assert n == 3 and value == pytest.approx(expected, abs=1e-12)
    assert err == pytest.approx(np.std(per, ddof=1) / np.sqrt(3), rel=1e-9)


def test_the_lag_against_a_reference_on_two_kept_cycles_has_an_error():
    """skip 2 leaves cycles 2 and 3 (MIN_CYCLES): the error is the two lags' spread about the value over root 2."""
    q_y, q_r, t, y, r = _lag_records(0.0)
    expected = np.angle(np.mean(np.exp(1j * q_r[2:]))) - np.angle(np.mean(np.exp(1j * q_y[2:])))
    value, err, n = phase.lag(t, y, OMEGA, skip=2, reference=r)
    assert n == 2 and value == pytest.approx(expected, abs=1e-12)
    assert err == pytest.approx(np.std((q_r[2:] - q_y[2:]) - expected, ddof=1) / np.sqrt(2), rel=1e-9)


def _centred_cycles(z) -> tuple[np.ndarray, np.ndarray]:
    """Cycle k of 5 a sine of complex amplitude z[k] (|z| sin(omega t + angle z)), 20 samples a bin at the bins'
    centres +- half steps (no sample on a cycle's edge)."""
    t, _ = _uniform(5, 24 * 20)
    t = t[:-1] + PERIOD / (24 * 20) / 2
    k = np.floor(t / PERIOD).astype(int)
    z = np.asarray(z)[k]
    return t, np.abs(z) * np.sin(OMEGA * t + np.angle(z))


def test_the_peak_s_lag_averages_the_cycles_after_skip():
    """Cycles 2-4 lag by 6 pi/24 (a bin centre's lag), cycle 1 such that the mean complex amplitude of cycles 1-4 is
    4/4 e^(-i 5 pi/24): by default (skip 1) the peak lags 5 pi/24, with skip 2 by 6 pi/24, both exactly."""
    l1, l2 = 5 * np.pi / 24, 6 * np.pi / 24
    z1 = 4 * np.exp(-1j * l1) - 3 * np.exp(-1j * l2)
    t, y = _centred_cycles([5.0, z1, np.exp(-1j * l2), np.exp(-1j * l2), np.exp(-1j * l2)])
    assert phase.peak_lag(t, y, OMEGA) == pytest.approx(l1, abs=1e-12)
    assert phase.peak_lag(t, y, OMEGA, skip=2) == pytest.approx(l2, abs=1e-12)


def test_the_peak_s_lag_before_a_bin_centre_is_read_before_it():
    """sin(omega t - lag) with the peak 0.05 rad before bin 8's centre: the parabola's vertex lies left of the
    centre, the lag read within 1e-3 (not clipped to the centre, 0.05 off)."""
    lag = 5 * np.pi / 24 - 0.05
    t, y = _centred_cycles([np.exp(-1j * lag)] * 5)
    assert phase.peak_lag(t, y, OMEGA) == pytest.approx(lag, abs=1e-3)


def test_the_peak_s_lag_beside_an_empty_bin_is_the_largest_bin_s_phase():
    """Samples at the centres of every bin but bin 9: the largest bin (8) has no neighbour on its right, so no
    parabola: the lag is bin 8's centre less pi/2 (5 pi/24), though the sine peaks 0.05 later."""
    bins = np.array([b for b in range(PHASE_BINS) if b != 9])
    t = ((np.arange(5)[:, None] * PHASE_BINS + bins[None, :] + 0.5) * PERIOD / PHASE_BINS).ravel()
    lag = 5 * np.pi / 24 + 0.05
    assert phase.peak_lag(t, np.sin(OMEGA * t - lag), OMEGA) == pytest.approx(5 * np.pi / 24, abs=1e-12)


def test_the_peak_s_lag_reads_the_bins_phases_on_the_cycles_after_skip():
    """One sample a bin; cycles 0-1 sampled a quarter bin after the bins' centres, cycles 2-4 on them: with skip 2
    the bins' phases are the centres, and sin(omega t - 5 pi/24) peaks on bin 8's centre: the lag is 5 pi/24 (the
    early cycles' phases, a sixteenth of a bin off over cycles 1-4, are not read)."""
    b = np.arange(5 * PHASE_BINS)
    t = (b + 0.5 + np.where(b < 2 * PHASE_BINS, 0.25, 0.0)) * PERIOD / PHASE_BINS
    lag = 5 * np.pi / 24
    assert phase.peak_lag(t, np.sin(OMEGA * t - lag), OMEGA, skip=2) == pytest.approx(lag, abs=1e-12)


def test_the_amplitude_profile_fits_the_cycles_after_skip():
    """One depth, same phase, amplitudes 5, 1.5, 0.9, 0.9 over cycles 0-3: over cycles 1-3 (the default) the fit's
    amplitude is their mean 1.1 (uniform whole cycles), over cycles 2-3 (skip 2) 0.9."""
    t, k = _uniform(4, 24)
    amplitude = np.array([5.0, 1.5, 0.9, 0.9])[np.minimum(k, 3)]
    df = pd.DataFrame({"t": t, "depth": 2.0, "u": amplitude * np.sin(OMEGA * t + 0.3)})
    assert phase.amplitude_profile(df, OMEGA, "u").to_numpy() == pytest.approx([1.1], abs=1e-12)
    assert phase.amplitude_profile(df, OMEGA, "u", skip=2).to_numpy() == pytest.approx([0.9], abs=1e-12)
