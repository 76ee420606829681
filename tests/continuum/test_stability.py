"""Stability map: the explicit scheme's derived bound, and the classification of runs."""
import math
from dataclasses import replace

import numpy as np
import pytest
from granstokes.continuum.mesh import Mesh
from granstokes.continuum.paper.stability import METHODS, explicit_bound, plot_maps, stability_table
from granstokes.continuum.problems import ImposedStress
from granstokes.continuum.scales import Material
from granstokes.continuum.stepper import explicit_euler

FR = Material().friction


def test_bound_is_the_largest_eigenvalue_of_the_max_diffusivity_operator():
    mu_w = FR.mu_w_from_tilde(0.5)
    mesh = Mesh.graded(30, 3.0)
    p = 1 + FR.beta(mu_w) * mesh.y[1:-1]
    cl, cd, cu = mesh.d2
    L = np.diag(cd) + np.diag(cl[1:], -1) + np.diag(cu[:-1], 1)
    lam = np.linalg.eigvals(FR.dmu**2 * np.sqrt(p)[:, None] * L)
    assert explicit_bound(FR, mu_w, mesh) == pytest.approx(2 / np.abs(lam.real).max(), rel=1e-10)


def grid_mode(mt, factor, n=40):
    """Amplitude of the grid-scale (checkerboard) mode of tau~ per explicit Euler step."""
    mu_w = FR.mu_w_from_tilde(mt)
    mesh = Mesh.graded(n, 0.0)
    pb = ImposedStress(FR, mu_w, mesh, order=2)  # the three-point scheme of explicit_bound
    dt = factor * explicit_bound(FR, mu_w, mesh)
    steps = int(math.ceil(1.0 / dt))
    sign = (-1.0) ** np.arange(n - 1)
    amp = []
    explicit_euler(pb, [steps * dt], np.arange(1, steps + 1) * dt,
                   observer=lambda t, x: amp.append(abs(sign @ np.diff(pb.full(x), 2)) / (n - 1)))
    return np.array(amp)


def test_explicit_euler_is_stable_just_below_and_unstable_just_above_the_bound():
    """mu~_w = 0.99 keeps D at its bound's value: below (0.95 dt*) the grid mode decays at about
    |1 - 2 x 0.95| = 0.9 per step; above (1.05 dt*) it grows at about 1.1 per step.  The growth
    saturates into a bounded checkerboard rather than overflowing (D falls where tau~ rises), so the
    failure is a persistent grid-scale oscillation, 1e4 times the stable run's residue."""
    below, above = grid_mode(0.99, 0.95), grid_mode(0.99, 1.05)
    assert (below[40] / below[10]) ** (1 / 30) == pytest.approx(0.9, abs=0.07)
    assert (above[40] / above[10]) ** (1 / 30) == pytest.approx(1.1, abs=0.05)
    assert above[-1] > 1e4 * below[-1] and above[-1] > 1e-4


def test_explicit_euler_blows_up_far_above_the_bound():
    with pytest.raises(FloatingPointError), np.errstate(all="ignore"):
        grid_mode(0.5, 2.0)


def test_classification_and_maps(tmp_path):
    """A small map: SDIRK4 on the fourth-order scheme converges at order ~4 already from 25 cells, and
    at 200 cells its refined run (400 cells) is at the reference's own accuracy: no order, "ref"; the
    second-order BDF baseline converges at order ~2; explicit Euler blows up at 2 dt* and is stable
    at dt*/2, with the first-order error of ~1e-3 that its time step (dt* ~ h^2/(2 Dmu^2)) leaves
    after the singular start."""
    sdirk4, bdf, euler = (replace(m, params=(0.5,), values=v, refine=r) for m, v, r in
                          ((METHODS[0], (25, 100, 200), (50, 200, 400)), (METHODS[3], (50,), (100,)),
                           (METHODS[2], (2.0, 0.5), (1.0, 0.25))))
    table = stability_table(FR, (sdirk4, bdf, euler))
    sdirk = table[table.method == sdirk4.name].set_index("axis_value")
    assert (sdirk["class"] == "converged").all()
    assert sdirk.loc[100, "order"] == pytest.approx(4.0, abs=0.5) and not sdirk.loc[100, "at_reference"]
    assert sdirk.loc[25, "rel_error"] > 4**3 * sdirk.loc[100, "rel_error"]
    assert sdirk.loc[200, "at_reference"] and math.isnan(sdirk.loc[200, "order"])
    assert table[table.method == bdf.name].order.item() == pytest.approx(2.0, abs=0.3)
    euler = table[table.method == euler.name].set_index("axis_value")
    assert euler.loc[2.0, "class"] == "blown up" and euler.loc[0.5, "class"] in ("converged", "inaccurate")
    assert euler.loc[0.5, "rel_error"] < 2e-3 and euler.loc[0.5, "order"] > 0.5
    paths = plot_maps(table, tmp_path)
    assert len(paths) == 3 and all(p.stat().st_size > 5000 for p in paths)


def test_speed_map_holds_the_constraint():
    """The imposed-speed map's cell: the integral condition holds at the end (it is re-evaluated from the
    returned wall friction in the wall unknown q = ln(1/mu~_w)), and mu_w converges towards the reference
    (this map's classes: "constraint-violating" when the condition is off by more than 1e-8)."""
    speed = next(m for m in METHODS if m.name.startswith("speed"))
    row = stability_table(FR, (replace(speed, params=(1.334,), values=(50,), refine=(100,)),)).iloc[0]
    assert row["class"] == "converged" and row["rel_error"] < 1e-3
