"""The threshold crossing that reads delta off a profile (continuum.crossing): ``crossing_depth``,
``depth_at_fraction`` and ``layer_measures`` against answers found without the module.

How the answers are independent:

* a linear f crosses exactly where its line does, (a - level)/b; an exponential A exp(-y/L) crosses, in log form,
  exactly at L ln(A/level); the default (linear) crossing of a curved profile is numpy.interp between the two
  bracketing nodes, written here;
* the cubic form is the cubic through nodes j-2..j+1 (0..3 in the first cell, n-4..n-1 in the last), built here by
  numpy.polyfit on those four nodes and solved by numpy.roots in the bracketing cell: exact to rounding on a cubic
  polynomial (in log form, on exp of one), fourth order on a smooth profile (the crossing kept at a cell's centre,
  one halving of h cuts the error ~16x);
* edge cases as the module states them: first=True gives y[0] where f[0] is already below the level, nan where f
  never falls below it (touching the level is not falling below it); first=False gives the last downward crossing,
  y[0] where no node is at or above the level, y[-1] where the last node is;
* the cubic's answer stays in the bracketing cell where the cubic meets the level again just outside it, and a nan
  node in its stencil falls back to the chord; with log=True a non-positive node in the stencil makes it the cubic
  in f (exact on a cubic vanishing at its last node);
* end_zero: a cubic polynomial vanishing at y[-1] (its end node at round-off) crosses in the last cell exactly;
* no numpy warning on the edge cases (a flat profile, a level of 0 in log form, end_zero's log(0/0));
* layer_measures: u = u_w (1 - depth/D) crosses fraction f of u_w at D (1 - f) (each LAYER_FRACTIONS, imported)
  and its first moment is D/2 (the trapezoid is exact on a piecewise-linear profile); nodes at depth < 0 or with
  non-finite u are dropped, unsorted nodes sorted, a plate speed u_w <= 0, infinite or nan gives nan;
* float32 input gives its float64 copy's answer: the arithmetic is done in double precision.
"""
import warnings
from contextlib import contextmanager

import numpy as np
import pytest
from granstokes.continuum.crossing import LAYER_FRACTIONS, U_FRACTION, crossing_depth, depth_at_fraction, layer_measures
from scipy.optimize import brentq
from scipy.special import erfc

LEVEL = 1e-3


def test_cubic_log_crossing_is_fourth_order_on_an_erfc_tail():
    """delta of the short-time profile erfc(y/w) on uniform nodes: the cubic in log f converges at fourth
    order over two halvings (measured 4.3; one halving alone scatters, 5.4 then 3.2, as the crossing moves
    within its cell)."""
    w = 0.1
    exact = brentq(lambda y: erfc(y / w) - LEVEL, 0.0, 1.0, xtol=1e-15)
    errors = [abs(crossing_depth(y, erfc(y / w), LEVEL, log=True, cubic=True) - exact)
              for y in (np.linspace(0.0, 1.0, n + 1) for n in (32, 64, 128))]
    assert 3.5 < np.log(errors[0] / errors[2]) / np.log(4) < 5, errors


@pytest.mark.parametrize("n", [128, 160, 192])
def test_end_zero_crossing_near_a_vanishing_end(n):
    """A profile that vanishes linearly at the last node, f = (1 - y) exp(-y/L) (the continuum's mu - mu_s
    at y~ = 1), crossing the level two to four cells from it (the cubic's nodes short of the end): with
    end_zero, log(f/(1 - y)) is linear, so the crossing is exact to rounding; without it, log f's singularity
    at the end costs > 1e-6 (the control)."""
    L = 0.33
    f = lambda y: (1 - y) * np.exp(-y / L)
    exact = brentq(lambda y: f(y) - LEVEL, 0.5, 1.0, xtol=1e-15)
    y = np.linspace(0.0, 1.0, n + 1)
    assert 2 < (1 - exact) * n < 4
    with_end = crossing_depth(y, f(y), LEVEL, log=True, cubic=True, end_zero=True)
    without = crossing_depth(y, f(y), LEVEL, log=True, cubic=True)
    assert abs(with_end - exact) < 1e-12
    assert abs(without - exact) > 1e-6


def test_end_zero_crossing_in_the_last_cell_ignores_the_ends_round_off():
    """Crossing in the last cell, the end node at round-off (5.6e-17, as mu_w/p~(1) - mu_s gives) rather than
    0: the end is taken as 0 and the cubic through it is in f, exact for this linear end (f = 1 - y);
    keeping the end's round-off would put log(f/0) into the cubic (delta of u~_w = 0.02 at t~ = 10: 0.979 for
    0.999)."""
    y = np.linspace(0.0, 1.0, 257)
    exact = 1 - LEVEL
    f = 1 - y
    f[-1] = 5.6e-17
    assert y[-2] < exact
    assert abs(crossing_depth(y, f, LEVEL, log=True, cubic=True, end_zero=True) - exact) < 1e-12


# --- helpers: the answers, computed without the module -------------------------------------------------------------

def cubic_root(ys, fs, level, lo, hi):
    """The root in [lo, hi] of the cubic through the four points (ys, fs) minus ``level`` (numpy.polyfit, roots)."""
    c = np.polyfit(ys - lo, fs, 3)
    c[-1] -= level
    roots = [r.real + lo for r in np.roots(c) if abs(r.imag) < 1e-9 and -1e-12 <= r.real <= hi - lo + 1e-12]
    assert len(roots) == 1, roots
    return roots[0]


def linear_crossing(y0, y1, f0, f1, level):
    """Where the chord from (y0, f0) to (y1, f1) meets ``level`` (numpy.interp on the falling chord)."""
    return float(np.interp(level, [f1, f0], [y1, y0]))


@contextmanager
def silent():
    """Any warning (numpy's divide or invalid among them) raises inside this block."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


# uneven nodes, not starting at 0
Y = np.array([0.3, 0.7, 1.6, 2.0, 2.9, 3.1, 4.4])


# --- the linear and log-linear forms -------------------------------------------------------------------------------

def test_a_linear_profile_crosses_exactly_where_its_line_does():
    """f = 2 - 0.4 y on uneven nodes, level 0.5: the crossing is (2 - 0.5)/0.4 = 3.75, read as a Python float."""
    out = crossing_depth(Y, 2.0 - 0.4 * Y, 0.5)
    assert isinstance(out, float)
    assert out == pytest.approx(3.75, abs=1e-13)


def test_by_default_the_crossing_is_the_chord_between_the_bracketing_nodes():
    """A curved profile, exp(-y): the default (neither log nor cubic) is the chord between nodes 3 and 4 (f falls
    below 0.1 between y = 2.0 and 2.9), not the exponential's own crossing ln 10."""
    f = np.exp(-Y)
    expected = linear_crossing(Y[3], Y[4], f[3], f[4], 0.1)
    assert crossing_depth(Y, f, 0.1) == pytest.approx(expected, abs=1e-13)
    assert abs(expected - np.log(10.0)) > 1e-2


def test_log_crossing_of_an_exponential_is_exact():
    """f = 0.9 exp(-y/0.5) (every node below 1) crosses 1e-3 at 0.5 ln(900), exactly in log form, on uneven nodes,
    also in the first cell (level 0.3: 0.5 ln 3, between 0.3 and 0.7), where the chord is not exact."""
    f = 0.9 * np.exp(-Y / 0.5)
    assert crossing_depth(Y, f, LEVEL, log=True) == pytest.approx(0.5 * np.log(900.0), abs=1e-13)
    assert crossing_depth(Y, f, 0.3, log=True) == pytest.approx(0.5 * np.log(3.0), abs=1e-13)
    assert crossing_depth(Y, f, 0.3) != pytest.approx(0.5 * np.log(3.0), abs=1e-3)


@pytest.mark.parametrize("f_lower", [0.0, -0.2])
def test_log_crossing_is_linear_where_the_lower_node_is_not_positive(f_lower):
    """log=True with the node below the level at 0 or negative: the chord in f (log f does not exist there)."""
    f = np.array([1.0, 0.6, f_lower, -0.5])
    y = np.array([0.0, 1.0, 2.5, 3.0])
    assert crossing_depth(y, f, 0.3, log=True) == pytest.approx(linear_crossing(1.0, 2.5, 0.6, f_lower, 0.3),
                                                                abs=1e-13)


# --- which crossing, and the edge cases ----------------------------------------------------------------------------

# falls below 0.5 between 1 and 2, rises above between 3 and 4, falls below again between 5 and 6
RECROSS = np.array([1.0, 0.8, 0.2, 0.4, 0.9, 0.7, 0.1])
RY = np.arange(7.0)


def test_first_gives_the_first_downward_crossing_and_not_first_the_last():
    assert crossing_depth(RY, RECROSS, 0.5) == pytest.approx(1.0 + 0.3 / 0.6, abs=1e-13)
    assert crossing_depth(RY, RECROSS, 0.5, first=False) == pytest.approx(5.0 + 0.2 / 0.6, abs=1e-13)


def test_first_crossing_edges_a_profile_already_below_never_below_or_only_touching():
    """first=True: y[0] where f[0] is already below; nan where f never falls below the level, including a profile
    that only touches it; a touch before the real fall is not the crossing."""
    assert crossing_depth(RY, RECROSS, 1.5) == 0.0
    assert crossing_depth(RY + 2.0, RECROSS - 0.9, 0.5) == 2.0
    assert np.isnan(crossing_depth(RY, RECROSS, 0.05))
    assert np.isnan(crossing_depth([0.0, 1.0, 2.0], [1.0, 0.5, 0.7], 0.5))
    assert crossing_depth([0.0, 1.0, 2.0, 3.0], [1.0, 0.5, 1.0, 0.2], 0.5) == pytest.approx(2.0 + 0.5 / 0.8,
                                                                                            abs=1e-13)


def test_last_crossing_edges_none_at_or_above_and_the_last_node_at_or_above():
    """first=False: y[0] where no node is at or above the level; y[-1] where the last node is (above it, or exactly
    at it), whatever the profile did before; the last node at or above it two nodes from the end."""
    assert crossing_depth(RY + 1.0, RECROSS, 1.5, first=False) == 1.0
    assert crossing_depth(RY, RECROSS, 0.05, first=False) == 6.0
    assert crossing_depth([0.0, 1.0, 2.0], [1.0, 0.2, 0.8], 0.5, first=False) == 2.0
    assert crossing_depth([0.0, 1.0, 2.0], [1.0, 0.2, 0.5], 0.5, first=False) == 2.0
    assert crossing_depth([0.0, 1.0, 2.0], [1.0, 0.5, 0.2], 0.5, first=False) == 1.0
    assert crossing_depth(RY[:5], [1.0, 0.8, 0.7, 0.2, 0.1], 0.5, first=False) == pytest.approx(2.4, abs=1e-13)


def test_rows_of_a_2d_profile_are_answered_one_by_one():
    """(times x depth): one answer per row, each the 1-D answer worked out above (a crossing, a recrossing, a row
    already below, a row never below)."""
    f = np.array([2.0 - 0.4 * (RY + 0.3), RECROSS, RECROSS - 0.9, RECROSS + 0.5])
    first = crossing_depth(RY, f, 0.5)
    last = crossing_depth(RY, f, 0.5, first=False)
    assert first.shape == last.shape == (4,)
    np.testing.assert_allclose(first[:3], [3.45, 1.5, 0.0], atol=1e-13)
    assert np.isnan(first[3])
    np.testing.assert_allclose(last, [3.45, 5.0 + 0.2 / 0.6, 0.0, 6.0], atol=1e-13)


def test_leading_axes_are_kept():
    """(2 x 3 x depth): a (2, 3) answer, element by element the line 2 - b (y + 0.3) crossing 0.5 at 1.5/b - 0.3."""
    b = np.array([[0.4, 0.5, 0.6], [0.7, 0.8, 0.9]])
    out = crossing_depth(RY, 2.0 - b[..., None] * (RY + 0.3), 0.5)
    assert out.shape == (2, 3)
    np.testing.assert_allclose(out, 1.5 / b - 0.3, atol=1e-13)


def test_single_precision_input_gives_its_double_precision_answer():
    """float32 nodes and profile (as a DEM file's columns may be): the answer of their float64 copies, to double
    precision (a float32 subtraction would be off by ~1e-8)."""
    y32 = np.array([0.1, 0.7, 2.3, 5.9], dtype=np.float32)
    f32 = np.array([1.3, 0.7, 0.01, 0.0], dtype=np.float32)
    y64, f64 = y32.astype(float), f32.astype(float)
    expected = linear_crossing(y64[1], y64[2], f64[1], f64[2], 0.05)
    assert crossing_depth(y32, f32, 0.05) == pytest.approx(expected, rel=1e-15)


def test_edge_cases_are_silent():
    """No numpy warning where the chord or its logarithm divide by zero or 0/0 on the discarded cells: a flat
    profile above or at the level, a level of 0 in log form (the cubic in f, the chord in f)."""
    with silent():
        assert np.isnan(crossing_depth(RY, np.ones(7), 0.5))
        assert np.isnan(crossing_depth(RY, np.full(7, 0.5), 0.5, log=True))
        assert crossing_depth(RY, 3.0 - RY, 0.0, log=True, cubic=True) == pytest.approx(3.0, abs=1e-13)
        assert crossing_depth(RY, 3.0 - RY, 0.0, log=True) == pytest.approx(3.0, abs=1e-13)


# --- the cubic form -----------------------------------------------------------------------------------------------

CY = -2.0 + 0.25 * np.arange(7)  # the cubic's nodes: uniform, negative (depths need not start at 0)


@pytest.mark.parametrize(("level", "cell"), [(0.99, 0), (0.6, 3), (0.17, 5)], ids=["first", "inner", "last"])
@pytest.mark.parametrize("log", [False, True])
def test_cubic_crossing_is_the_cubic_through_the_cells_four_nearest_nodes(level, cell, log):
    """g = cos(y + 2) (log=False) or f = exp(g) (log=True) on 7 nodes of h = 0.25: the crossing of the cubic through
    nodes cell-1..cell+2 (0..3 in the first cell, 3..6 in the last), in g, solved in the cell."""
    g = np.cos(CY + 2.0)
    first = min(max(cell - 1, 0), len(CY) - 4)
    nodes = slice(first, first + 4)
    expected = cubic_root(CY[nodes], g[nodes], level, CY[cell], CY[cell + 1])
    f, at = (np.exp(g), np.exp(level)) if log else (g, level)
    assert crossing_depth(CY, f, at, log=log, cubic=True) == pytest.approx(expected, abs=1e-12)
    assert abs(crossing_depth(CY, f, at, log=log) - expected) > 1e-5  # the (log-)linear form differs


def test_cubic_crossing_of_a_cubic_polynomial_is_exact():
    """p(y) = 1 - 3 (y + 2) + 4 (y + 2)^2 - 2.5 (y + 2)^3, strongly curved, on 7 nodes and on 4 (the fewest the cubic
    takes); in log form, exp(p): exact to rounding."""
    p = np.poly1d([-2.5, 4.0, -3.0, 1.0])
    for y in (CY, CY[2:6]):
        z = y + 2.0
        level = p(0.5 * (z[1] + z[2]))
        exact = cubic_root(z, p(z), level, z[1], z[2]) - 2.0
        assert crossing_depth(y, p(z), level, cubic=True) == pytest.approx(exact, abs=1e-13)
        assert crossing_depth(y, np.exp(p(z)), np.exp(level), log=True, cubic=True) == pytest.approx(exact, abs=1e-13)


def test_cubic_crossing_is_fourth_order_on_a_smooth_profile():
    """cos(y) crossing 0.3 (at arccos 0.3) kept at the centre of its cell: halving h cuts the error 16x (13 to 19)."""
    exact = np.arccos(0.3)
    errors = []
    for h in (0.2, 0.1, 0.05):
        y = exact + h * (np.arange(-5, 6) + 0.5)
        errors.append(abs(crossing_depth(y, np.cos(y), 0.3, cubic=True) - exact))
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    assert np.all((13 < ratios) & (ratios < 19)), (errors, ratios)


@pytest.mark.parametrize("nodes", [(1.7, 0.3, -0.1, 1.8), (2.1, 0.1, -0.1, -2.8)], ids=["left", "right"])
def test_cubic_crossing_stays_in_the_bracketing_cell(nodes):
    """Four nodes whose cubic meets the level again outside the cell [y_1, y_2], where an unguarded Newton from the
    linear crossing would go (left, right): the answer is the cubic's one root inside the cell."""
    y = 3.0 + 0.5 * np.arange(-1, 3)
    f = np.array(nodes) + 0.2
    assert crossing_depth(y, f, 0.2, cubic=True) == pytest.approx(cubic_root(y, f, 0.2, y[1], y[2]), abs=1e-12)


def test_cubic_log_crossing_with_a_zero_node_in_its_stencil_is_the_cubic_in_f():
    """log=True, the profile a cubic vanishing at its last node (no end_zero): log f does not exist at that node,
    so the cubic is in f, exact; rows with and without the zero node answered one by one."""
    p = np.poly1d([2.0, -1.0, 3.0, 0.0])  # p(x) = x (3 - x + 2 x^2), x = 1 - y: zero at y = 1
    y = np.linspace(0.0, 1.0, 9)
    x = 1.0 - y
    level = p(0.07)
    exact = 1.0 - cubic_root(x[-4:][::-1], p(x[-4:][::-1]), level, x[-1], x[-2])
    f = np.array([p(x), np.exp(-3.0 * y), p(x) + 0.5])
    out = crossing_depth(y, f, level, log=True, cubic=True)
    assert out.shape == (3,)
    assert out[0] == pytest.approx(exact, abs=1e-13)
    assert out[1] == pytest.approx(np.log(1.0 / level) / 3.0, abs=1e-13)
    assert np.isnan(out[2])


def test_cubic_crossing_falls_back_to_the_chord_where_its_stencil_has_a_gap():
    """A nan node just past the crossing (a gap in the data): no cubic through it; the chord of the bracketing
    nodes."""
    f = np.array([1.0, 0.9, 0.6, 0.2, np.nan, 0.01])
    y = np.arange(6.0)
    assert crossing_depth(y, f, 0.5, cubic=True) == pytest.approx(2.25, abs=1e-13)


def test_end_zero_crossing_in_the_last_cell_of_a_curved_profile_is_the_cubic_in_f_and_silent():
    """f = x (1 + 4 x + 30 x^2), x = 1 - y, its end node at round-off, crossing 0.05 in the last cell: the end is
    taken as 0 and the cubic through it is in f, exact for this cubic; no warning from log(f/0)."""
    y = np.linspace(0.0, 1.0, 11)
    x = 1.0 - y
    p = np.poly1d([30.0, 4.0, 1.0, 0.0])
    f = p(x)
    f[-1] = 5.6e-17
    exact = 1.0 - cubic_root(x[-4:][::-1], p(x[-4:][::-1]), 0.05, 0.0, 0.1)
    assert y[-2] < exact
    with silent():
        out = crossing_depth(y, f, 0.05, log=True, cubic=True, end_zero=True)
        out_f = crossing_depth(y, f, 0.05, cubic=True, end_zero=True)
    assert out == pytest.approx(exact, abs=1e-13)
    assert out_f == pytest.approx(exact, abs=1e-13)


# --- depth_at_fraction and layer_measures -------------------------------------------------------------------------

D = 8.0
DEPTH = np.linspace(0.0, 10.0, 41)  # beyond D: u is 0 there


def linear_layer(u_w):
    return u_w * np.maximum(0.0, 1.0 - DEPTH / D)


def test_depth_at_fraction_reads_the_first_depth_below_the_fraction_of_u_w():
    """u = 2.5 (1 - depth/8): U_FRACTION (the default) of u_w at 8 (1 - U_FRACTION), a fraction 0.3 at 8 x 0.7."""
    assert depth_at_fraction(DEPTH, linear_layer(2.5), 2.5) == pytest.approx(D * (1 - U_FRACTION), abs=1e-12)
    assert depth_at_fraction(DEPTH, linear_layer(2.5), 2.5, 0.3) == pytest.approx(D * 0.7, abs=1e-12)


@pytest.mark.parametrize("u_w", [0.0, -1.0, np.inf, np.nan])
def test_depth_at_fraction_is_nan_for_a_plate_speed_not_a_positive_number(u_w):
    with silent():
        assert np.isnan(depth_at_fraction(DEPTH, linear_layer(1.0) - 0.5, u_w))


def test_layer_measures_of_a_linear_layer():
    """u = u_w (1 - depth/D), 0 beyond D: depth D (1 - f) at each LAYER_FRACTIONS f, first moment D/2 (trapezoid
    exact on a piecewise-linear profile); u_w = 0.5 (below 1) as well as 2."""
    for u_w in (0.5, 2.0):
        m = layer_measures(DEPTH, linear_layer(u_w), u_w)
        for key, frac in LAYER_FRACTIONS.items():
            assert m[key] == pytest.approx(D * (1 - frac), abs=1e-12), key
        assert m["moment"] == pytest.approx(D / 2, abs=1e-12)


def test_layer_measures_drop_negative_depths_and_non_finite_speeds_and_sort():
    """Nodes above the plate (depth < 0, large u) and with u nan or inf are left out, shuffled nodes sorted: the
    linear layer's answers stay D (1 - f) and D/2."""
    depth = np.concatenate([DEPTH, [-1.0, -0.5, 2.1, 5.3, 3.3]])
    u = np.concatenate([linear_layer(2.0), [50.0, 40.0, np.nan, np.inf, -np.inf]])
    order = np.random.default_rng(3).permutation(len(depth))
    m = layer_measures(depth[order], u[order], 2.0)
    for key, frac in LAYER_FRACTIONS.items():
        assert m[key] == pytest.approx(D * (1 - frac), abs=1e-12), key
    assert m["moment"] == pytest.approx(D / 2, abs=1e-12)


@pytest.mark.parametrize("u_w", [0.0, -2.0, np.inf, np.nan])
def test_layer_measures_are_nan_for_a_plate_speed_not_a_positive_number(u_w):
    with silent():
        m = layer_measures(DEPTH, linear_layer(2.0), u_w)
    assert all(np.isnan(m[key]) for key in [*LAYER_FRACTIONS, "moment"]), m


def test_layer_measures_of_single_precision_input_are_their_double_precision_answers():
    """float32 depths and speeds: the float64 copies' crossing and trapezoid sum (written out here), to double
    precision."""
    depth32 = np.array([0.0, 0.3, 1.7, 2.9, 4.1], dtype=np.float32)
    u32 = np.array([1.3, 1.1, 0.7, 0.3, 0.01], dtype=np.float32)
    d, u = depth32.astype(float), u32.astype(float)
    m = layer_measures(depth32, u32, 1.3)
    moment = np.sum(np.diff(d) * (u[1:] + u[:-1]) / 2) / 1.3
    assert m["moment"] == pytest.approx(moment, rel=1e-15)
    assert m["delta_05"] == pytest.approx(linear_crossing(d[3], d[4], u[3] / 1.3, u[4] / 1.3, U_FRACTION), rel=1e-15)
