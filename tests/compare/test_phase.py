"""compare.phase: the oscillating plate's estimators recover known harmonics (with honest errors), lags, loop
areas, yielded depths, remobilisation strains and periodic states of synthetic records."""
from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from granstokes.compare import phase

OMEGA = 2.0
PERIOD = 2 * np.pi / OMEGA
MEAN, AMPLITUDE, PHASE, NOISE = 0.3, 1.2, 3.1, 0.3  # a phase near pi: the per-cycle phases straddle +-pi
TRUE = {"amplitude": AMPLITUDE, "phase": PHASE, "mean": MEAN}


def _times(cycles: int, per_cycle: int = 50, rng=None) -> np.ndarray:
    """Samples over [0, ``cycles`` periods], the inner ones jittered by up to half a step when ``rng`` is given."""
    step = PERIOD / per_cycle
    t = np.arange(cycles * per_cycle + 1) * step
    if rng is not None:
        t[1:-1] += rng.uniform(-0.5, 0.5, len(t) - 2) * step
    return t


def _signal(t, rng) -> np.ndarray:
    """The fundamental, two harmonics and white noise."""
    return (MEAN + AMPLITUDE * np.sin(OMEGA * t + PHASE) + 0.4 * np.sin(2 * OMEGA * t + 1.0)
            + 0.2 * np.sin(3 * OMEGA * t) + NOISE * rng.standard_normal(len(t)))


def test_cycles_are_whole_and_after_the_start_up():
    ends_on = phase.cycles(_times(6), OMEGA)  # a sample at 6 T: cycle 6 is not whole
    ends_short = phase.cycles(_times(6)[:-1], OMEGA)  # the last sample one step before 6 T
    for c in (ends_short, ends_on):
        assert list(c) == [1, 2, 3, 4, 5] and all(len(i) == 50 for i in c.values())
    assert list(phase.cycles(_times(6)[:-10], OMEGA, skip=2)) == [2, 3, 4]  # the cut last cycle is dropped
    assert list(phase.cycles(_times(6)[3:], OMEGA, skip=0)) == [1, 2, 3, 4, 5]  # the cut first one too


def test_harmonic_errors_cover_and_scale_with_cycles():
    rng = np.random.default_rng(7)
    dev, err, covered = {}, {}, {}
    for cycles in (6, 21):  # 5 and 20 whole cycles after the start-up
        fits = []
        for _ in range(200):
            t = _times(cycles, rng=rng)
            fits.append(phase.harmonic(t, _signal(t, rng), OMEGA))
        assert all(h.n_cycles == cycles - 1 and h.note == "" for h in fits)
        for name, true in TRUE.items():
            off = np.array([getattr(h, name) for h in fits]) - true
            dev[cycles, name] = phase.wrap(off) if name == "phase" else off
            half = np.array([np.diff(h.interval(name))[0] / 2 for h in fits])
            covered[cycles, name] = np.mean(np.abs(dev[cycles, name]) <= half)
            err[cycles, name] = np.sqrt(np.mean([getattr(h, f"{name}_err") ** 2 for h in fits]))
    for name in TRUE:
        for cycles in (6, 21):
            assert 0.88 <= covered[cycles, name] <= 0.99
            # the error is the estimates' real scatter, and they are unbiased
            assert err[cycles, name] == pytest.approx(np.std(dev[cycles, name]), rel=0.15)
            assert abs(np.mean(dev[cycles, name])) < 4 * err[cycles, name] / np.sqrt(200)
        assert err[6, name] / err[21, name] == pytest.approx(2.0, rel=0.12)  # 1/sqrt(cycles): sqrt(20/5)
    assert err[6, "amplitude"] == pytest.approx(NOISE * np.sqrt(2 / 50 / 5), rel=0.15)


def test_harmonic_needs_two_cycles_for_an_error():
    rng = np.random.default_rng(1)
    t = _times(2)
    h = phase.harmonic(t, _signal(t, rng), OMEGA)
    assert h.n_cycles == 1 and np.isnan(h.amplitude_err) and "needs 2" in h.note
    assert h.amplitude == pytest.approx(AMPLITUDE, abs=0.15)
    assert phase.harmonic(t[:60], _signal(t[:60], rng), OMEGA).n_cycles == 0


def test_interval_average_is_undone():
    """Samples that are exact averages over the step ending at each (8 a period): the fit with the interval
    returns the underlying harmonic, the plain fit the attenuated and delayed one."""
    interval = PERIOD / 8
    t = np.arange(1, 6 * 8 + 1) * interval

    def averaged(k, a, p):  # the mean of a sin(k omega s + p) over [t - interval, t]
        return a * (np.cos(k * OMEGA * (t - interval) + p) - np.cos(k * OMEGA * t + p)) / (k * OMEGA * interval)

    y = MEAN + averaged(1, AMPLITUDE, PHASE) + averaged(2, 0.4, 1.0)
    h = phase.harmonic(t, y, OMEGA, interval=interval)
    assert (h.amplitude, h.phase, h.mean) == pytest.approx((AMPLITUDE, PHASE, MEAN), abs=1e-12)
    assert h.amplitude_err < 1e-12
    raw = phase.harmonic(t, y, OMEGA)
    assert raw.amplitude == pytest.approx(AMPLITUDE * np.sin(np.pi / 8) / (np.pi / 8), abs=1e-12)
    assert raw.phase == pytest.approx(PHASE - np.pi / 8, abs=1e-12)


def test_phase_lag_sign_and_range():
    t = _times(6)
    y = np.sin(OMEGA * (t - 0.3))  # peaks 0.3 after the imposed sine
    y[[10, 70]] = np.nan  # missing samples are left out
    lagging = phase.harmonic(t, y, OMEGA)
    assert phase.phase_lag(lagging) == pytest.approx(0.3 * OMEGA)
    assert phase.phase_lag(phase.harmonic(t, np.sin(OMEGA * t + 0.5), OMEGA)) == pytest.approx(-0.5)
    late = phase.harmonic(t, np.sin(OMEGA * t - 3.5), OMEGA)  # 3.5 late is 2 pi - 3.5 early
    assert phase.phase_lag(late) == pytest.approx(3.5 - 2 * np.pi)
    assert phase.phase_lag(late, imposed_phase=-1.0) == pytest.approx(2.5)


def test_phase_average_and_profile():
    rng = np.random.default_rng(3)
    t = _times(6, per_cycle=96)
    avg = phase.phase_average(t, np.sin(OMEGA * t) + NOISE * rng.standard_normal(len(t)), OMEGA, bins=24)
    centre = (np.arange(24) + 0.5) * 2 * np.pi / 24
    start, h = centre - np.pi / 24, 2 * np.pi / 96  # the bins' 4 samples: start + (0, 1, 2, 3) h
    bin_mean = np.mean([np.sin(start + m * h) for m in range(4)], axis=0)
    assert avg.phase.to_numpy() == pytest.approx(centre) and (avg.n_cycles == 5).all()
    assert np.mean(avg.err ** 2) == pytest.approx(NOISE ** 2 / (4 * 5), rel=0.3)  # 4 samples a bin, 5 cycles
    assert np.mean((avg["mean"] - bin_mean) ** 2) == pytest.approx(NOISE ** 2 / 20, rel=0.75)  # chi2, 24 dof
    depth = np.arange(6) * 0.5
    tt, dd = np.meshgrid(t, depth, indexing="ij")
    df = pd.DataFrame({"t": tt.ravel(), "depth": dd.ravel(), "u": (np.exp(-dd) * np.sin(OMEGA * tt - dd)).ravel()})
    grid = phase.phase_profile(df, OMEGA, "u", bins=24)
    assert grid["mean"].shape == (24, 6) and list(grid["mean"].columns) == list(depth)
    expected = np.exp(-depth) * np.mean([np.sin(start[:, None] + m * h - depth) for m in range(4)], axis=0)
    assert grid["mean"].to_numpy() == pytest.approx(expected, abs=1e-12)
    assert (grid["n_cycles"] == 5).all().all() and (grid["err"].to_numpy() < 1e-12).all()


def test_dissipation_is_the_loop_area():
    u, tau, d = 0.7, 0.4, 0.6  # the friction leads the plate speed by d
    expected = np.pi * u * tau * np.cos(d) / OMEGA
    t = _times(6, per_cycle=64)
    w = phase.dissipation(t, u * np.sin(OMEGA * t), tau * np.sin(OMEGA * t + d), OMEGA)
    assert w["value"] == pytest.approx(expected, rel=1e-9) and len(w["values"]) == 5 and w["stderr"] < 1e-9
    jittered = _times(6, per_cycle=200, rng=np.random.default_rng(0))
    w = phase.dissipation(jittered, u * np.sin(OMEGA * jittered), tau * np.sin(OMEGA * jittered + d), OMEGA)
    assert w["value"] == pytest.approx(expected, rel=1e-3)
    elastic = phase.dissipation(t, u * np.sin(OMEGA * t), tau * np.cos(OMEGA * t), OMEGA)
    assert abs(elastic["value"]) < 1e-12


def test_yielded_depth():
    depth = np.arange(11) * 0.5
    mu = np.array([0.6 - 0.1 * depth,  # |mu| >= 0.33 down to 2.7
                   -(0.6 - 0.1 * depth),  # the same in the other direction
                   np.full_like(depth, 0.2),  # never yielded
                   np.full_like(depth, 0.5),  # yielded throughout
                   np.where(depth < 1, 0.2, 0.5 - 0.05 * depth)])  # below at the plate, yielded deeper to 3.4
    assert phase.yielded_depth(depth, mu, 0.33) == pytest.approx([2.7, 2.7, 0.0, 5.0, 3.4])
    assert phase.yielded_depth(depth, mu[0], 0.33) == pytest.approx(2.7)


@pytest.mark.parametrize("delay", [np.pi / 6, 1.2])  # 1.2: |friction| > 0.9 T at the reversal
def test_remobilization_strain_after_a_known_delay(delay):
    """Imposed speed U sin(omega t); the friction T sin(omega t - delay) reaches 0.9 of its peak at omega t =
    delay + arcsin 0.9 after each reversal, the plate having moved U (1 - cos(that)) / omega."""
    u, tau, depth = 0.8, 0.5, 4.0
    t = _times(6, per_cycle=400)
    x = u / OMEGA * (1 - np.cos(OMEGA * t))
    s = phase.remobilization_strain(t, x, u * np.sin(OMEGA * t), tau * np.sin(OMEGA * t - delay), OMEGA, depth)
    expected = u * (1 - np.cos(delay + np.arcsin(0.9))) / OMEGA / depth
    assert s["value"] == pytest.approx(expected, rel=1e-4) and len(s["values"]) == 9  # 10 reversals in cycles 1-5
    assert s["values"] == pytest.approx(expected, rel=1e-4) and s["stderr"] < 1e-4 * expected


def test_a_bed_that_jams_fails_the_periodic_state_and_noisy_periodic_beds_pass():
    """A response of amplitude 1.60 in its first kept cycle, 0.14 and 0.12 after it (a bed that jams, as in the
    committed oscillating study), with noise NOISE/3 (per-cycle coefficient error 0.1 sqrt(2/50) = 0.02): its
    first harmonic moves by 1 -+ 0.12/1.6 of its amplitude (the last cycle's at any phase), beyond
    PERIODIC_TOLERANCE.  A periodic response with noise NOISE (coefficient error 0.06) passes in 100 of 100
    records: its change stays below 0.6 of the tolerance."""
    rng = np.random.default_rng(5)
    t = _times(4)
    k = np.minimum((t / PERIOD).astype(int), 3)
    jam = (np.array([2.0, 1.60, 0.14, 0.12])[k] * np.sin(OMEGA * t + 0.3)
           + NOISE / 3 * rng.standard_normal(len(t)))
    got = phase.periodicity(t, jam, OMEGA)
    assert list(got["cycles"].cycle) == [1, 2, 3] and got["periodic"] is False
    assert got["cycles"].amplitude.to_numpy() == pytest.approx([1.60, 0.14, 0.12], abs=0.07)
    assert 1 - 0.2 / 1.60 < got["change"] < 1 + 0.2 / 1.60
    changes = [phase.periodicity(t, np.sin(OMEGA * t + 0.3) + NOISE * rng.standard_normal(len(t)), OMEGA)["change"]
               for _ in range(100)]
    assert max(changes) < 0.6 * phase.PERIODIC_TOLERANCE
