"""Richardson's error estimate (continuum.richardson): exact on an error of one power of h, and the one every
continuum estimate calls."""
import inspect
import re

import numpy as np
import pytest
from granstokes.continuum import ngf, oscillation, scene_models, solver
from granstokes.continuum.paper import stability
from granstokes.continuum.richardson import REFINEMENT, richardson, richardson_on_nodes


@pytest.mark.parametrize("order", [1, 2, 4])
def test_the_estimate_is_the_fine_value_s_true_error_when_the_error_is_c_h_to_the_order(order):
    """f(h) = f0 + c h^p on h and REFINEMENT h: |f(h) - f(2h)|/(2^p - 1) = |f(h) - f0|, safety times it."""
    f0, c, h = 1.25, np.array([-3.0, 0.5, 7.0]), 0.01
    fine, coarse = f0 + c * h**order, f0 + c * (REFINEMENT * h) ** order
    assert richardson(fine, coarse, order) == pytest.approx(np.abs(fine - f0), rel=1e-9)
    assert richardson(fine, coarse, order, 3.0) == pytest.approx(3 * np.abs(fine - f0), rel=1e-9)
    assert richardson(fine[0], coarse[0], order) == pytest.approx(abs(fine[0] - f0), rel=1e-9)


def test_the_second_order_default_divides_by_three():
    assert richardson(1.0, 0.25) == 0.25
    assert np.array_equal(richardson(np.array([1.0, -2.0]), np.array([4.0, 1.0])), [1.0, 1.0])


def test_a_nodal_field_from_a_companion_on_every_other_node():
    """An error c h^2 (1 + y), linear in y, is recovered at every fine node (the coarse nodes a subset)."""
    y = np.linspace(0.0, 1.0, 17)
    yc, h, c = y[::2], 1.0 / 16, 0.3
    fine = np.sin(y) + c * h**2 * (1 + y)
    coarse = np.sin(yc) + c * (2 * h) ** 2 * (1 + yc)
    assert richardson_on_nodes(y, fine, yc, coarse) == pytest.approx(c * h**2 * (1 + y), rel=1e-9)


@pytest.mark.parametrize("function", [solver._estimate, scene_models.SceneModel.estimated, ngf.solve_transient,
                                      oscillation._estimate, stability._estimated])
def test_every_estimate_calls_richardson_and_writes_no_formula_of_its_own(function):
    source = inspect.getsource(function)
    assert "richardson" in source
    assert not re.search(r"\)\s*/\s*(3\b|\(g(ain)? - 1\)|RICHARDSON)", source), source
