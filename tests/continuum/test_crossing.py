"""The threshold crossing that reads delta off a profile (continuum.crossing)."""
import numpy as np
import pytest
from granstokes.continuum.crossing import crossing_depth
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
