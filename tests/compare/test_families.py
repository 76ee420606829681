"""Estimator families and laws in their regime (compare.families, compare.laws) on synthetic drives whose answers are
known: a layer whose exponent depends on the threshold, windows too short or outside the model's regime, the stress
and speed drives apart, a plateau in one series only."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from granstokes.compare.analysis import DriveAnalysis
from granstokes.compare.comparison import DriveComparison
from granstokes.compare.drive import DriveSpec
from granstokes.compare.families import FROM_TRANSITS, LAYER_ESTIMATORS, Choice, entry, family_note, systematic
from granstokes.compare.laws import (
    GROWTH_END,
    MIN_DECADES,
    PLATEAU_SPAN,
    PLATEAU_TOLERANCE,
    REGIME_PIECES,
    REGIME_TOLERANCE,
    laws,
)
from granstokes.compare.plate import PlateRecord
from granstokes.compare.rows import ESTIMATOR_DEPENDENT, critical
from granstokes.continuum.crossing import layer_measures
from granstokes.continuum.load import Load
from granstokes.continuum.scales import Material, Scales
from granstokes.continuum.scene_models import Prediction, Steady
from scipy.special import erfc

MATERIAL = Material(mu_s=0.3, mu_d=0.7, I0=0.3, phi=0.8)
DEPTH = 40.0
Y = np.linspace(0.0, DEPTH, 2001)
P_W, MU_W, TRANSIT = 10.0, 0.45, 0.01


def erfc_layer(k: float, power: float = 0.5):
    """u/u_w = erfc(y / (k t^power)): every threshold's depth grows as t^power."""
    return lambda t: erfc(Y / (k * t ** power))


def synthetic(dem_profile, model_profile, *, kind: str = "stress", transit: float = TRANSIT, noise: float = 0.1,
              seeds: int = 4, dem_mu=None, model_mu=None, rng=None) -> DriveComparison:
    """A drive of ``kind`` whose DEM seeds' layer measures are those of ``dem_profile(t)`` (u/u_w on Y) times an
    independent factor 1 + noise N(0, 1) per seed, frame and estimator, and a model whose profiles are
    ``model_profile(t)``; the plate at u_w = sqrt(t/t_s) saturating at t_s, mu_w ``dem_mu(t)`` and ``model_mu(t)``
    (MU_W when not given)."""
    rng = rng or np.random.default_rng(0)
    scales = Scales(MATERIAL, P_W, MU_W)
    t_end = 10 * scales.t_s
    t = np.linspace(0.0, t_end, 2001)
    u = np.sqrt(np.minimum(t / scales.t_s, 1.0))
    mu = dem_mu(t) if dem_mu else MU_W * np.ones_like(t)
    frames = np.geomspace(t_end / 3000, t_end, 120)
    exact = pd.DataFrame([layer_measures(Y, dem_profile(tf), 1.0) for tf in frames])
    plates, layers = [], []
    for s in range(seeds):
        plates.append(PlateRecord(t, u, mu * P_W, P_W * np.ones_like(t), np.zeros_like(t), u, np.ones_like(t)))
        noisy = {k: exact[k].to_numpy() * (1 + noise * rng.standard_normal(len(frames))) for k in LAYER_ESTIMATORS}
        layers.append(pd.DataFrame({"t": frames, "u_w": 1.0, **noisy, "seed": s}))
    sample = pd.DataFrame({"depth": Y, "y": DEPTH - Y, "u_x": model_profile(scales.t_s)})
    load = Load("stress", P_W, mu_w=MU_W) if kind == "stress" else Load("speed", P_W, u_w=1.0)
    spec = DriveSpec(Path("run"), f"{kind}-drive", load, DEPTH, 1.0, 0.0, 1000, transit, seeds, 1000, 2)
    a = DriveAnalysis(spec, tuple(plates), (), pd.DataFrame({"t": t, "u_w": u, "mu_w": mu}), {}, 0.7 * t_end, t_end,
                      {"value": 0.0}, {}, sample, sample, pd.DataFrame(), pd.DataFrame(), np.array([]),
                      tuple(sample for _ in range(seeds)), "seeds", len(frames), 0,
                      pd.concat(layers, ignore_index=True))
    model_t = np.geomspace(t_end / 3000, t_end, 80)
    prof = pd.DataFrame({"t": np.repeat(model_t, len(Y)), "depth": np.tile(Y, len(model_t)),
                         "u": np.concatenate([model_profile(ti) for ti in model_t]), "mu": MU_W})
    model_u = np.sqrt(np.minimum(model_t / scales.t_s, 1.0))
    series = pd.DataFrame({"t": model_t, "u_w": model_u, "mu_w": model_mu(model_t) if model_mu else MU_W,
                           "delta_u": 0.0})
    pred = Prediction("local", "synthetic", series, prof, Steady(Y, model_profile(scales.t_s), 1.0, MU_W,
                                                                 scales.delta_s))
    return DriveComparison(a, scales, (pred,), "")


def law_row(table: pd.DataFrame, law: str, kind: str = "stress") -> pd.Series:
    sel = table[(table.law == law) & (table.kind == kind)]
    assert len(sel) == 1, sel
    return sel.iloc[0]


def by_choice(r: pd.Series) -> dict:
    return {(c["estimator"], c["from_transits"]): c for c in r.choices}


def test_a_creep_tail_makes_the_growth_exponent_depend_on_the_threshold():
    """u/u_w = 0.9 erfc(y / 2 sqrt(t)) + 0.1 exp(-y/20) against a model without the tail, u/u_w = erfc(y / 2 sqrt(t)):
    the half-speed depth is the erfc's (the tail adds at most 0.1 there) and grows as t^(1/2) like the model's; the
    5 % depth is the tail's alone, 20 ln(0.1/0.05) = 13.9 at every time (the erfc term is below 1e-4 there), so its
    exponent is 0 against the model's 1/2.  The family splits: the law depends on the estimator, the DEM - model
    difference spans 0 to -1/2 (systematic 1/4), and no verdict is 'disagrees' while a choice is consistent."""
    e, creep = 0.1, 20.0
    dc = synthetic(lambda t: (1 - e) * erfc(Y / (2 * np.sqrt(t))) + e * np.exp(-Y / creep), erfc_layer(2.0))
    row = law_row(laws([dc], resamples=30), "delta_growth_exponent")
    choices = by_choice(row)
    assert len(row.choices) == len(LAYER_ESTIMATORS) * len(FROM_TRANSITS)
    half, five = choices[("delta_50", 3.0)], choices[("delta_05", 3.0)]
    assert half["dem"] == pytest.approx(0.5, abs=0.03) and abs(half["sigma"]) <= critical(half["dof"])
    assert five["dem"] == pytest.approx(0.0, abs=0.03) and five["predicted"] == pytest.approx(0.5, abs=0.01)
    assert five["sigma"] < -critical(five["dof"])
    assert row.verdict == ESTIMATOR_DEPENDENT and row.note.startswith(ESTIMATOR_DEPENDENT)
    assert "delta_50 of the plate's speed from 3 transits" in row.note.split("disagree")[0]
    assert row.systematic == pytest.approx((0.0 - (0.0 - 0.5)) / 2, abs=0.03)
    # the headline numbers stay the primary choice's (delta_05 from 3 transits)
    assert row.dem == five["dem"] and row.predicted == five["predicted"]


def test_a_window_under_a_decade_is_not_measurable_with_its_numbers():
    """Transit 0.05: from 3 transits the growth window is [0.15, GROWTH_END t_s = 0.593] (log10(0.593/0.15) = 0.6 of a
    decade), from 5 and 10 transits less than that or nothing: no choice is measurable."""
    dc = synthetic(erfc_layer(1.0), erfc_layer(1.0), transit=0.05)
    row = law_row(laws([dc], resamples=10), "delta_growth_exponent")
    end = GROWTH_END * Scales(MATERIAL, P_W, MU_W).t_s
    assert row.verdict == "not measurable" and np.isnan(row.sigma) and np.isnan(row.systematic)
    span = (f"the window [0.15, {end:.3g}] spans {np.log10(end / 0.15):.2g} decade(s) of time "
            f"(fewer than {MIN_DECADES:g})")
    assert span in by_choice(row)[("delta_05", 3.0)]["note"]
    assert all(c["note"].startswith("not measurable") for c in row.choices)


def test_a_model_outside_its_power_law_regime_over_the_window_is_not_measurable():
    """The model's layer L = sqrt(t / (1 + t/t_c)) bends from t^(1/2) to a constant around t_c = 0.1: over a piece
    [a, b] of the window its mean exponent is 1/2 - ln((1 + b/t_c)/(1 + a/t_c)) / (2 ln(b/a)), and these spread by more
    than REGIME_TOLERANCE over the windows from 3 and 5 transits; the DEM's layer, a clean t^(1/2), is not fitted."""
    t_c = 0.1
    model = lambda t: erfc(Y / np.sqrt(t / (1 + t / t_c)))  # noqa: E731
    table = laws([synthetic(erfc_layer(1.0), model)], resamples=10)
    row = law_row(table, "delta_growth_exponent")
    end = GROWTH_END * Scales(MATERIAL, P_W, MU_W).t_s
    edges = np.geomspace(3 * TRANSIT, end, REGIME_PIECES + 1)
    a, b = edges[:-1], edges[1:]
    exponents = 0.5 - np.log((1 + b / t_c) / (1 + a / t_c)) / (2 * np.log(b / a))
    assert np.ptp(exponents) > REGIME_TOLERANCE
    assert row.verdict == "not measurable" and "outside the model's power-law regime" in row.note
    assert f"local exponents {', '.join(f'{x:.2f}' for x in exponents)}" in row.note
    assert law_row(table, "delta_growth_prefactor").verdict == "not measurable"


def test_stress_and_speed_drives_give_their_own_growth_rows():
    """A stress drive growing as t^(1/2) and a speed drive growing as t^(1/3), each predicted exactly: each kind's
    row reads its own drive (dem 1/2 and 1/3, one drive each)."""
    stress = synthetic(erfc_layer(1.0), erfc_layer(1.0), noise=0.05)
    speed = synthetic(erfc_layer(1.5, 1 / 3), erfc_layer(1.5, 1 / 3), kind="speed", noise=0.05)
    table = laws([stress, speed], resamples=20)
    for kind, power in (("stress", 0.5), ("speed", 1 / 3)):
        row = law_row(table, "delta_growth_exponent", kind)
        assert row.n_drives == 1 and row.verdict != "not measurable"
        assert row.dem == pytest.approx(power, abs=0.02) and row.predicted == pytest.approx(power, abs=0.005)
    assert set(table[table.law == "delta_s_scaling"].kind) == {"all"}


def test_a_plateau_only_in_the_dem_is_not_measured():
    """Speed drive, the DEM's friction held at mu_w (a plateau), the model's falling linearly from mu_d by Dmu over
    t_f = 2: over the plateau window [t0, t1] its (mu - mu_s)/Dmu = 1 - t/t_f rises by (t1 - t0)/t_f in magnitude,
    relative to its value 1 - (t0 + t1)/(2 t_f) at the window's middle: 35 %, above PLATEAU_TOLERANCE."""
    m, t_f = MATERIAL, 2.0
    dc = synthetic(erfc_layer(1.0), erfc_layer(1.0), kind="speed",
                   model_mu=lambda t: m.mu_d - (m.mu_d - m.mu_s) * t / t_f)
    row = law_row(laws([dc], resamples=10), "mu_w_plateau", "speed")
    t_end = 10 * Scales(MATERIAL, P_W, MU_W).t_s
    t0 = 3 * TRANSIT
    t1 = t0 + PLATEAU_SPAN * (t_end - t0)
    change = (t1 - t0) / t_f / (1 - (t0 + t1) / 2 / t_f)
    assert change > PLATEAU_TOLERANCE
    assert row.verdict == "not measurable" and "no plateau in both series" in row.note
    assert f"changes by 0% in the DEM, {change:.0%} in the model" in row.note


def test_systematic_is_half_the_range_of_the_difference_over_measured_choices():
    """Differences 0.1, -0.3 and one unmeasured choice: systematic (0.1 - (-0.3))/2 = 0.2; one measured: NaN; the
    family of one consistent (|sigma| 1) and one disagreeing (sigma -3) choice depends on the estimator, of two
    disagreeing ones does not."""
    ok = entry(Choice("delta_50"), 1.1, 0.1, 1.0, 0.0, "", np.inf)
    bad = entry(Choice("delta_05"), 0.7, 0.1, 1.0, 0.0, "", np.inf)
    off = entry(Choice("moment"), np.nan, np.nan, 1.0, 0.0, "not measurable: no window", np.inf)
    assert systematic([ok, bad, off]) == pytest.approx(0.2)
    assert np.isnan(systematic([ok, off]))
    assert family_note([ok, bad, off]).startswith(f"{ESTIMATOR_DEPENDENT}: 1 of 2 measured choices consistent")
    assert family_note([bad, bad]) == ""


def test_the_family_panel_draws_each_measured_choice_and_the_systematic_beside_the_primary():
    """Two choices measured (DEM 0.2 and 0.5 against 0.5), one not: the panel has a tick per choice and one for the
    primary, DEM points at the measured choices only, and a grey bar of half-height systematic = (0.3 - 0)/2 around
    the primary's DEM value."""
    from granstokes.compare.law_figures import family_panel
    from granstokes.compare.rows import Z95
    from matplotlib.figure import Figure

    choices = [entry(Choice("delta_05"), 0.2, 0.01, 0.5, 0.0, "", np.inf),
               entry(Choice("delta_50"), 0.5, 0.02, 0.5, 0.0, "", np.inf),
               entry(Choice("moment"), np.nan, np.nan, np.nan, 0.0, "not measurable: no window", np.inf)]
    rows = pd.DataFrame([{"law": "delta_growth_exponent", "kind": "stress", "model": "local", "dem": 0.2,
                          "dem_err": 0.01, "choices": choices, "systematic": systematic(choices)}])
    ax = Figure().subplots()
    family_panel(ax, rows, "n")
    assert len(ax.get_xticks()) == len(choices) + 1
    dem_points, primary, syst = ax.containers
    assert list(dem_points.lines[0].get_ydata()) == [0.2, 0.5]
    assert primary.lines[0].get_ydata()[0] == 0.2
    lo_hi = syst.lines[2][0].get_segments()[0][:, 1]
    assert lo_hi == pytest.approx([0.2 - 0.15, 0.2 + 0.15])
    bars = dem_points.lines[2][0].get_segments()
    assert [s[1, 1] - s[0, 1] for s in bars] == pytest.approx([2 * Z95 * 0.01, 2 * Z95 * 0.02])


def test_a_family_with_no_measured_choice_says_why_instead_of_an_empty_axis():
    """Every choice not measurable: the panel draws no axis and says so with the primary's note."""
    from granstokes.compare.law_figures import family_panel
    from matplotlib.figure import Figure

    why = "not measurable: the window [0.67, 3.19] spans 0.68 decade(s) of time (fewer than 1)"
    choices = [entry(Choice(e), np.nan, np.nan, np.nan, 0.0, why, np.inf) for e in ("delta_05", "delta_50")]
    rows = pd.DataFrame([{"law": "delta_growth_exponent", "kind": "stress", "model": "local", "dem": np.nan,
                          "dem_err": np.nan, "choices": choices, "systematic": np.nan}])
    ax = Figure().subplots()
    family_panel(ax, rows, "growth exponent n")
    assert not ax.axison and not ax.containers
    (text,) = ax.texts
    assert text.get_text().replace("\n", " ").startswith("growth exponent n: no choice measured on these drives.")
    assert "spans 0.68 decade(s)" in text.get_text().replace("\n", " ")
