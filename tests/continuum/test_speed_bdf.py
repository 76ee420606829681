"""The BDF loop of an imposed speed (continuum.bdf) against what it is built from: the speed's kernels against
ImposedSpeed's rate, Jacobian, wall row and projection, the band LU against LAPACK's (through scipy), and the loop
against scipy's own BDF step for step (tests/continuum/bdf_oracle.py)."""
import granstokes.continuum.kernels as kernels
import granstokes.continuum.problems as problems
import granstokes.continuum.stepper as stepper
import numpy as np
import pytest
from granstokes.continuum.integrators import integrate
from granstokes.continuum.problems import ImposedSpeed
from granstokes.continuum.solver import TIME_ERROR_PER_RTOL, Numerics, map_for, solve_speed
from granstokes.continuum.steady import mu_w_for_speed
from scipy.linalg import solve_banded

from tests.continuum import bdf_oracle

#: the compiled arithmetic differs from numpy's in the order of additions only: relative round-off of a few
#: operations, besides the cancellations bounded in each test
ROUND_OFF = 1e-13


@pytest.fixture(scope="module")
def speed_state(request):
    """An imposed speed (u~_w = 1.334, 64 cells on its solve's map) and its state in the lift-off, t~ = 0.3
    (q = 2.5: mu~_w = 0.08)."""
    import math

    from granstokes.continuum.rheology import Friction

    fr = Friction(math.tan(math.radians(21.0)), math.tan(math.radians(33.0)))
    numerics = Numerics(n_cells=64).for_drive("speed")
    pb = ImposedSpeed(fr, 1.334, numerics.mesh(*map_for(fr, mu_w_for_speed(fr, 1.334), "speed", 1e-4)))
    x = integrate(pb, [0.3], method="bdf", rtol=numerics.rtol, atol=numerics.atol)[0][0]
    return pb, x


def test_projection_rate_and_jacobian_are_imposed_speeds(speed_state):
    """The kernels' projection, rate and Jacobian band equal ImposedSpeed's at a state in the lift-off, to the
    round-off of the sums they make in another order: q to that of its constraint (the interior's share over the
    first cell's weight w_0 ~ 8e-6 and dL/dq: N eps share/(w_0 dL/dq) ~ 4e-10), the rate and the band's diagonal
    to that of the Laplacian (weights up to ~1/h_0^2 on values O(1): measured 5e-9 of the largest rate), every
    entry to ROUND_OFF relative besides."""
    from granstokes.continuum.problems import first_cell

    pb, x = speed_state
    n = len(x)
    _, _, mud_p, p32, _ = pb.stencil()
    _, _, _, _, w_first = pb.wall_terms()
    _, data, _ = pb.bdf_kernels()
    projected = np.empty(n)
    problems.speed_project(x[1:].copy(), projected, data)
    _, b, share = pb._interior(x)
    q = pb.project(x.copy())[0]
    bound = n * np.finfo(float).eps * share / (w_first * first_cell(q, b)[1])
    assert abs(projected[0] - q) <= bound and 2 < q < 3
    # the Laplacian's sums cancel (weights up to ~1/h_0^2 on values O(1)): their round-off, row by row
    tau = pb.full(x)
    cancel = 8 * np.finfo(float).eps * np.sum(np.abs(pb.lap.weights * tau[pb.lap.cols]), axis=1)
    s = mud_p - pb.mu_w * x[1:]
    f = np.empty(n - 1)
    problems.speed_rate(x, 0.0, f, data)
    ref = pb.interior_rate(x, 0.0)
    assert np.all(np.abs(f - ref) <= s * s / p32 * cancel + ROUND_OFF * np.abs(ref))
    band = np.zeros((pb.kl + pb.ku + 1, n - 1))
    problems.speed_jacobian(x, 0.0, band, data)
    full = pb.jacobian(x, 0.0).bands[:, 1:]  # columns 1..N-1; its entries of row 0 (the dense wall row) are masked
    rows = np.arange(band.shape[0])[:, None] - pb.ku + np.arange(1, n)[None, :]  # the row i of each band entry
    interior = (rows >= 1) & (rows <= n - 1)
    allowed = ROUND_OFF * np.abs(full)
    allowed[pb.ku] += 2 * pb.mu_w * np.abs(s) / p32 * cancel  # the diagonal's d D/d tau~ times the Laplacian
    assert np.all(np.where(interior, np.abs(band - full) <= allowed, True))
    assert np.all(band[~interior] == 0.0)


def test_wall_row_and_column_are_imposed_speeds(speed_state):
    """The kernels' wall row (the constraint's gradient) and column (dF_i/dq, rows 1..kl) equal
    ImposedSpeed.wall_jacobian's to ROUND_OFF relative."""
    pb, x = speed_state
    _, data, n_wall = pb.bdf_kernels()
    row0, column = np.empty(len(x)), np.empty(n_wall)
    problems.speed_wall(x, 0.0, row0, column, data)
    ref_row, ref_column = pb.wall_jacobian(x, 0.0)
    assert np.max(np.abs(row0 - ref_row)) <= ROUND_OFF * np.max(np.abs(ref_row))
    assert np.max(np.abs(column - ref_column)) <= ROUND_OFF * np.max(np.abs(ref_column))


@pytest.mark.parametrize("dominant", [False, True], ids=["rows swapped", "no swaps"])
def test_band_lu_solves_as_lapack_does(dominant):
    """kernels.band_lu/band_solve solve a random band system (kl = 3, ku = 2) as LAPACK's gbsv through scipy's
    solve_banded, to 1e-12: with its first sub-diagonal the largest (rows are swapped; U's upper bandwidth kl + ku)
    and with a dominant diagonal (none; ku, and the solve skips the fill's bands)."""
    rng = np.random.default_rng(7)
    n, kl, ku = 40, 3, 2
    band = rng.uniform(-1, 1, (kl + ku + 1, n))
    if dominant:
        band[ku] += 10.0 * np.sign(band[ku])  # |diagonal| > 10 > the column's other |entries| (< 5)
    else:
        band[ku + 1] *= 8.0
    rhs = rng.uniform(-1, 1, n)
    ab = np.zeros((2 * kl + ku + 1, n), order="F")
    ab[kl:] = band
    piv = np.zeros(n, dtype=np.int64)
    upper = kernels.band_lu(ab, piv, kl, ku)
    assert upper == (ku if dominant else kl + ku)
    assert np.any(piv != np.arange(n)) != dominant
    x = rhs.copy()
    kernels.band_solve(ab, piv, kl, ku, upper, x)
    ref = solve_banded((kl, ku), band, rhs)
    assert np.max(np.abs(x - ref)) <= 1e-12 * np.max(np.abs(ref))


def _steps(ours: bool, pb, times, numerics):
    rows = []
    run = integrate if ours else bdf_oracle.integrate
    run(pb, times, **({"method": "bdf"} if ours else {}), rtol=numerics.rtol, atol=numerics.atol, h0=1e-9,
        observer=lambda t, x: rows.append((t, x[0])))
    return np.array(rows)


def test_bdf_takes_scipys_steps(speed_state):
    """Step for step scipy's BDF: the first 50 steps land on the times of scipy's to 1e-9 relative (measured 8e-11:
    round-off of the sums, growing by the step control's feedback; a wrong coefficient or control rule moves
    them by O(1)), and their wall unknowns q agree as well."""
    pb, _ = speed_state
    numerics = Numerics(n_cells=64).for_drive("speed")
    times = [1e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0]
    ours, scipys = (_steps(ours, pb, times, numerics) for ours in (True, False))
    assert np.max(np.abs(ours[1:51] / scipys[1:51] - 1)) < 1e-9


def test_bdf_is_scipys_to_the_time_error():
    """The BDF loop and scipy's BDF on the same system agree in mu_w at t~ = 1e-4 ... 10 to the time error,
    TIME_ERROR_PER_RTOL rtol (their step sequences part by round-off after a few hundred steps: measured 6e-9
    relative at rtol 1e-8)."""
    from tests.continuum.reference import DISKS

    times = [1e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0]
    numerics = Numerics(n_cells=128).for_drive("speed")
    pb = ImposedSpeed(DISKS, 1.0, numerics.mesh(*map_for(DISKS, mu_w_for_speed(DISKS, 1.0), "speed", times[0])))
    options = dict(rtol=numerics.rtol, atol=numerics.atol, h0=numerics.initial_step * times[0])
    ours = integrate(pb, times, method="bdf", **options)[0]
    scipys = bdf_oracle.integrate(pb, times, **options)[0]
    bound = TIME_ERROR_PER_RTOL["bdf"] * numerics.rtol
    assert np.max(np.abs([pb.mu(a)[0] / pb.mu(b)[0] - 1 for a, b in zip(ours, scipys)])) < bound


def test_newton_floor_carries_a_steady_state_past_its_round_off():
    """After the lift-off, where scipy's Newton would give up, an update within the wall unknown's round-off is
    accepted (bdf.ROUND_OFF_UPDATES):
    the disks' u~_w = 0.05 on 512 cells at the matched rtol (6.25e-10) reaches t~ = 10 (without the floor its step
    collapses at t~ = 9.244, measured on this machine; the collapse is chaotic in the round-off, so it is not
    replayed here), at its steady state mu_w^inf to the time error TIME_ERROR_PER_RTOL rtol (1.9e-8; measured
    1.3e-10 off, bench/speed_range.py)."""
    from granstokes.continuum.steady import mu_w_for_speed

    from tests.continuum.reference import DISKS

    sol = solve_speed(DISKS, 0.05, [1e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0], Numerics(n_cells=512))
    assert abs(sol.mu_w[-1] / mu_w_for_speed(DISKS, 0.05) - 1) < TIME_ERROR_PER_RTOL["bdf"] * sol.numerics.rtol


def test_a_step_limit_is_a_stepper_failure(speed_state):
    """The BDF loop stops at max_steps with stepper.StepperFailure (the CLI's exit 1, one line), naming the limit
    and the time reached."""
    pb, _ = speed_state
    with pytest.raises(stepper.StepperFailure, match=r"max_steps = 20 reached at t = "):
        integrate(pb, [1.0], method="bdf", rtol=1e-8, atol=1e-10, h0=1e-9, max_steps=20)


def test_a_repeated_output_time_is_landed_on_once(speed_state):
    """integrate's output times may repeat (solve_speed refuses that, direct callers may not): the BDF loop returns
    the same state twice, as scipy's BDF does (its solver is already there), instead of taking a zero step (and
    dividing by it)."""
    pb, _ = speed_state
    times = [1e-3, 1e-2, 1e-2, 0.1]
    ours = integrate(pb, times, method="bdf", rtol=1e-8, atol=1e-10, h0=1e-9)[0]
    scipys = bdf_oracle.integrate(pb, times, rtol=1e-8, atol=1e-10, h0=1e-9)[0]
    assert np.array_equal(ours[1], ours[2])
    assert np.max(np.abs(ours[:, 1:] - scipys[:, 1:])) < TIME_ERROR_PER_RTOL["bdf"] * 1e-8
