"""The DIRK loop on an imposed stress (continuum.stepper with ImposedStress's kernels) against what it is built from:
the kernels against ImposedStress's rate and LAPACK's LU of its Newton matrix, and the compiled loop against the same
loop run as Python, step for step."""
import granstokes.continuum.problems as problems
import granstokes.continuum.stepper as stepper
import numpy as np
import pytest
from granstokes.continuum.integrators import integrate
from granstokes.continuum.problems import ImposedStress
from granstokes.continuum.solver import Numerics, map_for, solve_stress

from tests.continuum.reference import DISKS, PAPER, cached

TIMES = [1e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0]


@pytest.fixture(scope="module")
def stress_state():
    """mu~_w = 0.5 on 96 cells of its solve's map, and its state at t~ = 1e-2."""
    mu_w = PAPER.mu_w_from_tilde(0.5)
    numerics = Numerics(n_cells=96).for_drive("stress")
    pb = ImposedStress(PAPER, mu_w, numerics.mesh(*map_for(PAPER, mu_w, "stress", 1e-4)))
    x = integrate(pb, [1e-2], rtol=numerics.rtol, atol=numerics.atol)[0][0]
    return pb, x, numerics


def test_rate_and_newton_matrix_are_imposed_stresses(stress_state):
    """The kernels' rate equals ImposedStress.rate to the round-off of the Laplacian's sums (weights up to ~1/h_0^2
    on values O(1)), and their LU of M - dh J solves as stepper.NewtonMatrix does (LAPACK on ImposedStress.jacobian's
    band), to 1e-12 relative, at a step's dh (1e-4) and a large one (1)."""
    from granstokes.continuum.stepper import NewtonMatrix

    pb, x, _ = stress_state
    n = len(x)
    _, data, factors = pb.dirk_kernels()
    f = np.empty(n)
    problems.stress_rate(x, 0.0, f, data)
    ref = pb.rate(x, 0.0)
    cancel = 8 * np.finfo(float).eps * np.sum(np.abs(pb.lap.weights * pb.full(x)[pb.lap.cols]), axis=1)
    _, _, mud_p, p32, _ = pb.stencil()
    s = mud_p - pb.mu_w * x[1:]
    assert f[0] == ref[0] and np.all(np.abs(f[1:] - ref[1:]) <= s * s / p32 * cancel + 1e-13 * np.abs(ref[1:]))
    rhs = np.random.default_rng(3).uniform(-1, 1, n)
    for dh in (1e-4, 1.0):
        lu = factors()
        assert problems.stress_factor(x, 0.0, dh, lu, data) and lu[2][0] >= pb.ku
        ours = rhs.copy()
        problems.band_factors_solve(lu, ours, data)
        lapack = NewtonMatrix(pb, pb.jacobian(x, 0.0), dh).solve(rhs.copy())
        assert np.max(np.abs(ours - lapack)) <= 1e-12 * np.max(np.abs(lapack)), dh


def _steps(compiled, pb, numerics, method):
    rows = []
    _, stats = integrate(pb, [1e-3], method=method, compiled=compiled, rtol=numerics.rtol, atol=numerics.atol,
                         h0=1e-9, observer=lambda t, x: rows.append((t, x[1])))
    return np.array(rows), stats


@pytest.mark.slow
@pytest.mark.parametrize("method", ["sdirk4", "tr-bdf2"])
def test_compiled_dirk_takes_the_python_steps(stress_state, method):
    """The loop compiled takes the steps of the loop run as Python (the implicit-first SDIRK4 and the explicit-first
    TR-BDF2): the first 20 steps land on the same times to 1e-9 relative (the two sum in another order: round-off; a
    wrong stage weight, Newton rule or step control moves them by O(1))."""
    pb, _, numerics = stress_state
    (ours, _), (python, _) = (_steps(compiled, pb, numerics, method) for compiled in (True, False))
    assert len(ours) > 20 and len(python) > 20
    assert np.max(np.abs(ours[1:21, 0] / python[1:21, 0] - 1)) < 1e-9


@pytest.mark.parametrize("friction, mu_w_tilde, cells", [(PAPER, 0.5, 96), (PAPER, 0.1, 256), (DISKS, 0.3, 128)])
def test_compiled_solve_is_within_its_estimate_of_the_reference(friction, mu_w_tilde, cells):
    """solve_stress compiled agrees with the independent reference (tests/continuum/reference.py) in u~_w and delta
    at t~ = 1e-4 ... 10 within its estimated error, on meshes other than the default (measured: at most 0.73 of the
    estimate)."""
    ref = cached(f"{'paper' if friction is PAPER else 'disks'}-{mu_w_tilde}")
    sol = solve_stress(friction, friction.mu_w_from_tilde(mu_w_tilde), TIMES, Numerics(n_cells=cells), estimate=True)
    for q in ("u_w", "delta"):
        assert np.all(np.abs(getattr(sol, q) - np.asarray(ref[q])) <= sol.errors[q]), q


def test_a_step_limit_is_a_stepper_failure(stress_state):
    """The DIRK loop stops at max_steps (accepted plus rejected) with stepper.StepperFailure, naming the limit and
    the time reached."""
    pb, _, numerics = stress_state
    with pytest.raises(stepper.StepperFailure, match=r"max_steps = 20 reached at t = "):
        integrate(pb, [1.0], rtol=numerics.rtol, atol=numerics.atol, h0=1e-9, max_steps=20)
