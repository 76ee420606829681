"""The map's inverse and the resampling between maps (continuum.mesh), which carry an imposed speed's early
output times from their deeper wall cluster onto the solve's mesh (continuum.solver.EARLY_SPAN)."""
import numpy as np
import pytest
from granstokes.continuum.mesh import RESAMPLE_DEGREE, Mesh


@pytest.mark.parametrize("stretch, folds", [(0.0, 0.0), (6.0, 0.0), (6.0, 12.0)])
def test_xi_at_inverts_the_map(stretch, folds):
    """xi_at(y) returns the uniform xi-grid at the nodes, to round-off (the uniform mesh: the identity)."""
    mesh = Mesh.graded(128, stretch, folds)
    assert np.max(np.abs(mesh.xi_at(mesh.y) - np.linspace(0, 1, 129))) < 1e-14


def test_resampling_a_wall_layer_converges_at_the_splines_order():
    """A layer of width 1e-2 over a log sub-layer of 1e-7 (an early speed profile's shape), from the deep
    cluster onto the solve's map: the error falls at least as N^-(degree + 1) (measured: order 8, 6.9e-9 on 128
    cells), so the resampling adds nothing to the solver's fourth-order error."""
    def profile(y):
        return np.exp(-y / 1e-2) + 1e-3 * np.log1p(y / 1e-7)

    onto = Mesh.graded(128, 6.0, 8.0)
    errors = []
    for n in (64, 128, 256):
        deep = Mesh.graded(n, 6.0, 12.0)
        errors.append(np.max(np.abs(deep.resample(profile(deep.y), onto) - profile(onto.y))))
    orders = np.log2(np.array(errors[:-1]) / errors[1:])
    assert np.all(orders > RESAMPLE_DEGREE + 1) and errors[1] < 1e-7, (errors, orders)
    assert deep.resample(profile(deep.y), onto)[0] == pytest.approx(profile(0.0), abs=1e-15)  # the wall node
