"""The plate's geometry by number: the design whose slip docs/dem.md ("Why this plate", "Slip against p_w")
measured.  A change of PLATE_DIAMETER, PLATE_GAP_FRACTION, PLATE_RIDGE_PITCH, PLATE_FRICTION or of the layout fails
here first, and the measurements must then be redone."""
import math
import re

import pytest
from granstokes.dem import config, scene
from granstokes.dem.layout import BED, PLATE
from granstokes.dem.sizing import plan


def _plan(name):
    return plan(config.preset(name)[0])


def _nest(d_plate: float, d_bed: float, half_opening: float) -> float:
    """Depth below the plate grains' centres of a bed grain touching the plate grains around a gap."""
    return math.sqrt(((d_plate + d_bed) / 2) ** 2 - half_opening ** 2)


def test_the_2d_plate_is_the_measured_row():
    """quick: 19 unit grains 32/19 = 1.684 d apart, friction 1; the smallest bed grain (0.8 d) cannot pass a gap
    (0.684 d wide), the unit grain nests 0.539 d below the row's centres, the largest (1.2 d) 0.708 d, the
    smallest 0.318 d; the contact plane is 0.039 d below the plate's centre of mass."""
    p = _plan("quick")
    assert (scene.PLATE_DIAMETER, scene.PLATE_GAP_FRACTION, scene.PLATE_FRICTION) == (1.0, 0.9, 1.0)
    nx, nz, ax, az = scene.plate_layout(p)
    assert (nx, nz) == (19, 1) and ax == pytest.approx(1.684211, abs=1e-6)
    assert scene.plate_pitch(2, 0.8) == pytest.approx(1.72)
    gap = ax - scene.PLATE_DIAMETER
    assert gap == pytest.approx(0.684211, abs=1e-6) and gap < 1 - p.config.grains.polydispersity == 0.8
    assert scene.nesting_depth(p) == pytest.approx(0.539313, abs=1e-6)
    assert [_nest(1.0, d, ax / 2) for d in (0.8, 1.0, 1.2)] == pytest.approx([0.3176, 0.5393, 0.7077], abs=1e-4)
    geometry = scene.plate_geometry(p)
    assert geometry["surface_offset"] == pytest.approx(0.039313, abs=1e-6)
    assert geometry["mass_per_area"] == pytest.approx(19 * math.pi / 4 / 32)
    # the generated script places exactly that row, and the bed-plate contacts get the plate's friction
    text = scene.prepare_script(p, 1)
    xs = [float(x) for x in re.findall(rf"create_atoms {PLATE} single (\S+) \$\{{y_plate\}} 0 units box", text)]
    assert len(xs) == 19 and xs[0] == pytest.approx(ax / 2) and xs[-1] == pytest.approx(32 - ax / 2)
    assert "set group plate diameter 1\n" in text
    style = re.search(r"pair_style hybrid (.*)\n", text).group(1).split("gran/")
    assert [float(s.split()[5]) for s in style[1:]] == [p.config.contact.mu_p, 1.0]
    assert f"pair_coeff {BED} {PLATE} gran/hooke/history 2" in text


def test_the_3d_plate_is_the_measured_ridges():
    """spheres (diameters 0.85-1.15 d): ridges along z of unit spheres 0.5 d apart, 5 across the 8 d box 1.6 d apart
    (pitch 1.693 from the gap criterion); a unit sphere in a hole touches the four grains around it 0.545 d below
    their centres."""
    p = _plan("spheres")
    assert scene.PLATE_RIDGE_PITCH == 0.5
    nx, nz, ax, az = scene.plate_layout(p)
    assert (nx, nz, ax, az) == (5, 16, pytest.approx(1.6), pytest.approx(0.5))
    assert p.config.grains.polydispersity == 0.15
    assert scene.plate_pitch(3, 0.85) == pytest.approx(1.692698, abs=1e-6)
    assert scene.nesting_depth(p) == pytest.approx(0.545436, abs=1e-6)
    assert scene.plate_grains(p) == 80
