"""A drive record without its transit time (tables written before run.json held it) gets the one its scene had:
the bed's depth over d sqrt(k_t/m), worked out here for the committed disks (Hooke, kappa = 1e4 at p = 20, k_t/k_n =
2/7, a disk of mass pi/4): c_s = sqrt(2e5 x 2/7 / (pi/4)) = 269.7, a 28 d bed crossed in 0.1038; at p_w = 40 with
kappa stated at 20 the stiffness k_n is the same (dem.contact.rigidity), so is the time; a Hertz contact's k_n
scales as kappa^1.5; a known transit time is kept; a measured shear-wave speed replaces both."""
import math
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from granstokes.compare.comparison import DemSide, timed
from granstokes.compare.drive import DriveSpec, with_transit_time
from granstokes.continuum.load import Load

GRAINS = {"dimension": 2, "polydispersity": 0.2, "mu_p": 0.5, "restitution": 0.5, "contact": "hooke",
          "kappa": 1.0e4, "kt_over_kn": 2 / 7, "pair_style": "classic"}


def _drive(p_w: float, transit_time: float = np.nan) -> DriveSpec:
    return DriveSpec(Path("runs/p"), "speed", Load("speed", p_w, u_w=4.0), 28.0, 0.47, 0.05, 0, transit_time, 3, 0, 2,
                     4.3, 1000.0)


def test_a_missing_transit_time_is_the_depth_over_the_contact_shear_wave_speed():
    c_s = math.sqrt(2.0e5 * (2 / 7) / (math.pi / 4))
    assert c_s == pytest.approx(269.73, abs=0.01)
    assert with_transit_time(_drive(20.0), GRAINS, 20.0).transit_time == pytest.approx(28.0 / c_s, rel=1e-12)
    assert with_transit_time(_drive(40.0), GRAINS, 20.0).transit_time == pytest.approx(28.0 / c_s, rel=1e-12)
    # a calibration that does not state its pressure: kappa is read at the drive's p_w (k_n = 1e4 x 40)
    assert with_transit_time(_drive(40.0), GRAINS, np.nan).transit_time == pytest.approx(28.0 / c_s / math.sqrt(2))
    hertz = {**GRAINS, "contact": "hertz", "pair_style": "granular"}
    k_n = 2 * 1.0e4**1.5 * 20.0
    assert with_transit_time(_drive(20.0), hertz, 20.0).transit_time == pytest.approx(
        28.0 / math.sqrt(k_n * (2 / 7) / (math.pi / 4)), rel=1e-12)
    known = _drive(20.0, 0.5)
    assert with_transit_time(known, GRAINS, 20.0) is known


def test_a_measured_shear_wave_speed_times_the_transit_whatever_the_record_says():
    """A calibration that measured c_s = 118 (dem.modulus): the 28 d bed is crossed in 28/118, for a record with or
    without its own (contact-speed) transit time."""
    measured = {"G": 11277.0, "c_s": 118.0}
    for transit in (np.nan, 0.1038):
        assert with_transit_time(_drive(20.0, transit), GRAINS, 20.0, measured).transit_time == pytest.approx(
            28.0 / 118.0, rel=1e-12)


@dataclass(frozen=True)
class _Analysis:
    spec: DriveSpec


def test_the_stokes_comparison_starts_its_transients_after_transits_at_the_measured_speed():
    """The Stokes drives' elastic start (compare.comparison.timed, the StokesDrives experiment's first step): a
    calibration with c_s = 118 moves every drive's transit from the run's contact-speed 0.1038 to 28/118 = 0.2373
    and the comparison's start to three of them; a calibration without a modulus (or none) leaves the run's."""
    dem = DemSide((), {}, (_Analysis(_drive(20.0, 0.1038)), _Analysis(_drive(5.0, 0.1038))), None, 0.0)
    cal = SimpleNamespace(elasticity={"G": 11277.0, "c_s": 118.0}, grains=GRAINS, info={"protocol": {"p": 20.0}})
    out = timed(dem, cal)
    assert [a.spec.transit_time for a in out.drives] == pytest.approx([28.0 / 118.0] * 2, rel=1e-12)
    assert [a.spec.compared_from for a in out.drives] == pytest.approx([3 * 28.0 / 118.0] * 2, rel=1e-12)
    assert timed(dem, SimpleNamespace(elasticity=None, grains=GRAINS, info={})) is dem
    assert timed(dem, None) is dem
