"""A model whose wall inertial number leaves the calibrated range extrapolates the fitted law, and its rows are not
scored: worked out by hand for mu_s = 0.3, mu_d = 0.7, I0 = 0.3 (DEM convention), where I = 0.3 (mu - 0.3)/(0.7 - mu):
mu = 0.5 is at I = 0.3, mu = 0.6 at I = 0.9, mu = 0.7 (the asymptote) at no finite I.

* compare.scorecard.wall_I: the largest I of a series of wall frictions (NaNs left out; none: NaN);
* the oscillating plate (compare.oscillation._beyond): a loop whose |tau_w|/p_w peaks at 0.6 against a calibration
  measured to I = 0.55 makes every row of that model unscored, "extrapolated" with both numbers; a peak of 0.5 does
  not; an unknown calibrated range is not checked;
* the Stokes laws (compare.laws._extrapolating): a model's friction series reaching 0.6 inside a transient law's
  window extrapolates, the same series outside the window does not; a steady law reads the steady friction.
"""
from types import SimpleNamespace as NS

import numpy as np
import pandas as pd
import pytest
from granstokes.compare import oscillation as osc
from granstokes.compare.laws import LAWS, Window, _extrapolating
from granstokes.compare.scorecard import wall_I
from granstokes.continuum.scales import Material

MATERIAL = Material(mu_s=0.3, mu_d=0.7, I0=0.3, I_convention="dem", phi=0.8)
CALIBRATED = (0.001, 0.55)
NOTE_09 = ("not scored: extrapolated: the model's wall inertial number I = 0.9 (DEM convention) lies beyond "
           "the calibration's largest, 0.55")


def test_the_wall_inertial_number_of_a_friction_series_is_its_largest():
    f = MATERIAL.friction
    assert wall_I(f, [0.4, 0.5], 0.3) == pytest.approx(0.3)
    assert wall_I(f, [0.6, np.nan, 0.35], 0.3) == pytest.approx(0.9)
    assert wall_I(f, [0.5, 0.7], 0.3) == np.inf and wall_I(f, [0.75], 0.3) == np.inf
    assert np.isnan(wall_I(f, [np.nan], 0.3))


def test_an_oscillating_model_whose_wall_friction_peaks_beyond_the_calibration_is_not_scored():
    dem = NS(drive=NS(load=NS(p_w=20.0)))
    phases = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    setup = NS(material=MATERIAL, calibrated_I=CALIBRATED)
    loop = lambda peak: NS(loop=pd.DataFrame({"tau_w": 20.0 * peak * np.sin(phases + 0.1)}))  # noqa: E731
    peak = np.max(np.abs(np.sin(phases + 0.1)))
    assert osc._beyond(dem, loop(0.6 / peak), setup) == NOTE_09
    assert osc._beyond(dem, loop(0.5 / peak), setup) == ""
    assert osc._beyond(dem, loop(0.6 / peak), NS(material=MATERIAL, calibrated_I=(np.nan, np.nan))) == ""


def test_a_stokes_law_extrapolates_where_the_model_s_friction_inside_its_window_does():
    growth = next(law for law in LAWS if law.name == "delta_growth_exponent")
    steady = next(law for law in LAWS if law.name == "steady_speed_law")
    t = np.linspace(0.0, 10.0, 101)
    mu = np.where(t < 2.0, 0.6, 0.45)  # the impulsive start: the friction peaks early, then settles
    dc = NS(label="runs/p20/speed", scales=NS(material=MATERIAL),
            predictions=[NS(model="local", steady=NS(mu_w=0.45))])
    src = NS(predicted={(dc.label, "local"): NS(t=t, mu_w=mu)})
    early, late = {dc.label: Window(1.0, 5.0)}, {dc.label: Window(3.0, 9.0)}
    assert _extrapolating(growth, [dc], "local", early, src, CALIBRATED) == NOTE_09 + " (runs/p20/speed)"
    assert _extrapolating(growth, [dc], "local", late, src, CALIBRATED) == ""
    assert _extrapolating(steady, [dc], "local", {}, src, CALIBRATED) == ""
    dc.predictions[0].steady.mu_w = 0.6
    assert _extrapolating(steady, [dc], "local", {}, src, CALIBRATED) == NOTE_09 + " (runs/p20/speed)"
    assert _extrapolating(growth, [dc], "local", early, src, (np.nan, np.nan)) == ""
