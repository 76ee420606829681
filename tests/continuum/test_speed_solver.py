"""Imposed wall speed (eq. (3.14) with eq. (3.15))."""
import functools
from dataclasses import replace

import numpy as np
import pytest
from granstokes.continuum.bdf import HANDOVER
from granstokes.continuum.closed_forms import speed_short_time_mu
from granstokes.continuum.integrators import integrate
from granstokes.continuum.mesh import Mesh
from granstokes.continuum.problems import ImposedSpeed
from granstokes.continuum.rheology import Friction
from granstokes.continuum.solver import (
    INITIAL_STEP,
    MIN_ESTIMATED_CELLS,
    TIME_ERROR_PER_RTOL,
    WALL_STRETCH,
    Numerics,
    map_for,
    solve_speed,
    solve_stress,
)
from granstokes.continuum.steady import mu_w_for_speed

from tests.continuum.reference import PAPER as FR
from tests.continuum.reference import SPEED_CASES

SPEEDS = (0.198, 1.334, 4.629)


@pytest.mark.slow
@pytest.mark.parametrize("u_w", SPEEDS)
def test_constraint_and_bounds_hold_at_every_step(paper_friction, u_w):
    """At every accepted step the integral condition holds to 1e-8 and mu_s <= mu <= mu_d (mu_w = mu_d
    to round-off before t~_mud, as in the continuum): the comparison principle of the second-order
    scheme (an M-matrix; the fourth-order stencils are not monotone and undershoot at an unresolved front)."""
    fr = paper_friction
    pb = ImposedSpeed(fr, u_w, Mesh.graded(200), order=2)
    rows = []

    def check(t, x):
        mu = pb.mu(x)
        rows.append((abs(pb.wall_residual(x)) if t > 0 else 0.0, np.min(mu - fr.mu_s), np.max(mu - fr.mu_d)))

    integrate(pb, [1e-4, 1.0, 100.0], observer=check)
    residual, lo, hi = np.array(rows).T
    assert residual.max() < 1e-8
    assert lo.min() > -1e-12 and hi.max() <= 0


@pytest.mark.parametrize("u_w", SPEEDS[:2])
def test_steady_wall_friction_matches_the_imposed_stress_case(paper_friction, u_w):
    """mu_w(t~ -> inf) equals mu_w^inf of the matching imposed-stress case, to the mesh's O(h_0^3) (the
    first cell's weight sqrt(p~) taken at its midpoint) plus O(h^4) elsewhere: the gap shrinks at least
    8-fold per mesh halving (measured 47x and 3.7e-10 on 200 cells for u~_w = 0.198: the wall cluster's
    first cell, ~1e-6, leaves the O(h^4) alone); and that stress case's steady speed is u~_w."""
    fr = paper_friction
    gaps = []
    for n in (100, 200):
        sol = solve_speed(fr, u_w, [1e3], Numerics(n_cells=n))
        gaps.append(sol.mu_w[-1] - sol.mu_w_inf)
    assert gaps[0] / gaps[1] >= 8.0 * 0.9
    assert abs(gaps[1]) < 1e-8
    stress = solve_stress(fr, sol.mu_w_inf, [1e3])
    assert stress.u_w[-1] == pytest.approx(u_w, rel=1e-4)
    assert sol.delta[-1] == pytest.approx(stress.delta[-1], abs=1e-6)


def test_wall_friction_is_mu_d_before_t_mud_on_any_mesh(paper_friction):
    """For t~ << t_mud = u~_w^2 the continuum has mu_w -> mu_d exponentially: the first cell, exact for
    a linear mu~, shows it on every mesh (a trapezoidal first cell would give mu~_w = h_0/(2 Dmu u~_w),
    1e-5 here), and mu_w has left mu_d by t~ = t_mud."""
    fr, u_w = paper_friction, 1.334
    for n in (64, 128):
        sol = solve_speed(fr, u_w, [1e-4, u_w**2], Numerics(n_cells=n))
        assert fr.tilde(sol.mu_w[0]) < 1e-12 < 1e-2 < fr.tilde(sol.mu_w[1])


@pytest.mark.parametrize("compiled", [False, True], ids=["python", "compiled"])
@pytest.mark.parametrize("q, b", [(3.0, 0.5), (0.7, 0.5), (np.log(2.0) + 1e-7, 0.5), (np.log(2.0) + 1e-3, 0.5),
                                  (0.1, 0.9), (40.0, 0.2), (-2.0, 0.3)])
def test_first_cell_integral_and_derivatives(q, b, compiled):
    """The first cell's int_0^1 ds/(a + (b - a) s), a = exp(-q), against adaptive quadrature (to 1e-13) in
    each of its three forms (series, atanh, logarithms), and its derivatives against central differences; as
    ImposedSpeed runs it and as numba compiles it (continuum.kernels)."""
    from granstokes.continuum.problems import first_cell
    from scipy.integrate import quad

    if compiled:
        from numba import njit

        first_cell = njit(error_model="numpy")(first_cell)
    a = np.exp(-q)
    ref = quad(lambda s: 1 / (a + (b - a) * s), 0, 1, epsabs=0, epsrel=1e-13, limit=200)[0]
    lam, dq, db = first_cell(q, b)
    assert lam == pytest.approx(ref, rel=2e-13)
    e = 1e-6
    assert dq == pytest.approx((first_cell(q + e, b)[0] - first_cell(q - e, b)[0]) / (2 * e), rel=1e-7)
    assert db == pytest.approx((first_cell(q, b + e)[0] - first_cell(q, b - e)[0]) / (2 * e), rel=1e-7)


@pytest.mark.parametrize("u_w", SPEEDS)
def test_layer_grows_as_sqrt_t(paper_friction, u_w):
    sol = solve_speed(paper_friction, u_w, [1e-4, 1e-3])
    assert np.log10(sol.delta[1] / sol.delta[0]) == pytest.approx(0.5, abs=0.02)


@pytest.mark.parametrize("u_w", SPEEDS[1:])
def test_short_time_self_similarity(paper_friction, u_w):
    """For t~ << t_mud the excess (mu - mu_s)/(mu_w(t) - mu_s) is a function of
    eta = y~/(2 Dmu sqrt(t~)) alone (the paper's figure 9: collapse within 1 %), and the erfc form
    eq. (3.20) is the 'reasonable fit' the paper reports: within 25 %."""
    fr = paper_friction
    times = [1e-4, 1e-3, 1e-2]
    sol = solve_speed(fr, u_w, times)
    eta = np.linspace(0.0, 2.5, 60)
    curves = []
    for k, t in enumerate(times):
        excess = (sol.mu[k] - fr.mu_s) / (sol.mu_w[k] - fr.mu_s)
        curves.append(np.interp(eta, sol.mesh.y / (2 * fr.dmu * np.sqrt(t)), excess))
        fit = speed_short_time_mu(fr, sol.mu_w[k], sol.mesh.y, t)
        assert np.max(np.abs(fit - sol.mu[k])) < 0.25 * (sol.mu_w[k] - fr.mu_s)
    assert np.max(np.abs(np.array(curves) - curves[-1])) < 0.01


@pytest.mark.parametrize("u_w", SPEEDS)
def test_wall_friction_starts_near_mu_d_and_relaxes(paper_friction, u_w):
    """mu_w(t~) decreases monotonically from ~mu_d to mu_w^inf: step by step, it rises by less than the time
    error (TIME_ERROR_PER_RTOL rtol) in all (measured: ~1e-8 near the steady state, the steps' noise)."""
    fr = paper_friction
    sol = solve_speed(fr, u_w, [1e-4, 30.0])
    series = sol.steps[1:, 2]
    assert fr.tilde(series[0]) < 1e-2
    assert np.clip(np.diff(series), 0, None).sum() < TIME_ERROR_PER_RTOL["bdf"] * sol.numerics.rtol
    assert sol.mu_w[-1] == pytest.approx(sol.mu_w_inf, abs=2e-2 * (sol.mu_w_inf - fr.mu_s))


#: the estimates may be this many times the true error where that is above the time-error floor
#: (measured: 2-4x at 128 cells, the decades from t~ = 1e-4 to 10)
SPEED_PESSIMISM = 10
DECADES = [1e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0]


@functools.cache
def speed_run(u_w: float, n_cells: int, estimate: bool = False):
    """The paper's speed cases at the decades on the solver's default map."""
    return solve_speed(FR, u_w, DECADES, Numerics(n_cells=n_cells), estimate=estimate)


#: the orders of delta measured from successive differences on 64, 128, 256 cells
FOURTH = (3.0, 5.0)


@pytest.mark.parametrize("u_w", SPEEDS)
def test_speed_converges_at_fourth_order(u_w):
    """On the speed's wall-clustered map (solver.map_for) delta converges at fourth order wherever its
    differences are above the time error (TIME_ERROR_PER_RTOL rtol = 3e-7): measured 4.0-4.5 at t~ <= 0.1,
    3.4-3.6 at t~ = 1.  mu_w, its lift-off included, changes by less than that time error from 128 to 256
    cells at every decade (measured <= 1.9e-7; on an exponential map that does not grade the wall it is
    first order, 4.3e-6 at u~_w = 0.198)."""
    runs = [speed_run(u_w, n) for n in (64, 128, 256)]
    floor = TIME_ERROR_PER_RTOL["bdf"] * runs[-1].numerics.rtol
    delta = np.array([r.delta for r in runs])
    coarse, fine = np.abs(delta[0] - delta[1]), np.abs(delta[1] - delta[2])
    resolved = fine > floor * delta[2]
    orders = np.log2(coarse[resolved] / fine[resolved])
    assert resolved[:4].all(), fine / delta[2]  # t~ = 1e-4 ... 0.1: the layer inside the domain
    assert np.all((orders >= FOURTH[0]) & (orders <= FOURTH[1])), orders
    mu_w = np.array([r.mu_w for r in runs])
    assert np.all(np.abs(mu_w[1] - mu_w[2]) <= floor * mu_w[2])


def test_bdf_lands_on_every_output_time():
    """An output time between others is stepped onto, not read from BDF's dense output: mu_w at t~ = 1
    (u~_w = 1.334, in its lift-off, on the same map) is the same whether t~ = 1e-4 ... 10 are asked or
    t~ = 1 alone, to the time error (30 rtol; the dense output is 2.5e-5 off, 1e4 rtol)."""
    numerics = Numerics(n_cells=256, stretch=WALL_STRETCH)
    many, alone = (solve_speed(FR, 1.334, times, numerics) for times in (DECADES, [1.0]))
    rtol = many.numerics.rtol
    assert abs(many.mu_w[DECADES.index(1.0)] / alone.mu_w[0] - 1) < TIME_ERROR_PER_RTOL["bdf"] * rtol


def test_a_stall_after_the_lift_off_hands_over_to_sdirk4(paper_friction, monkeypatch):
    """Where BDF's steps stay small (here every step counts as small: Numerics.stall = (1, 5)) after the
    lift-off (u~_w = 0.198: 0.39), the rest goes to SDIRK4 from BDF's state, and the result is BDF's own to the
    time error, TIME_ERROR_PER_RTOL rtol (measured 7.4e-9 in mu_w, 1.4e-9 in delta, at rtol 1e-8)."""
    import granstokes.continuum.stepper as stepper

    times, numerics = [0.1, 1.0, 10.0], Numerics(n_cells=64)
    alone = solve_speed(paper_friction, 0.198, times, numerics)
    methods, original = [], stepper.integrate

    def spy(*args, **kwargs):
        methods.append(kwargs.get("method"))
        return original(*args, **kwargs)

    monkeypatch.setattr(stepper, "integrate", spy)  # observes the handover
    handed = solve_speed(paper_friction, 0.198, times, replace(numerics, stall=(1.0, 5)))
    assert methods == [HANDOVER]
    tolerance = TIME_ERROR_PER_RTOL["bdf"] * alone.numerics.rtol
    for q in ("mu_w", "delta"):
        assert np.all(np.abs(getattr(handed, q) / getattr(alone, q) - 1) <= tolerance), q


def test_a_small_speed_steps_on_past_an_output_time(paper_friction):
    """BDF keeps the steps it cut to land on an output time for order + 1 steps: no stall, no handover to
    SDIRK4 (which crawls on the speed's DAE). u~_w = 0.02 on 256 cells, as solve_speed runs it, reaches
    t~ = 10 within 3000 steps (measured 961; with a single small step setting off the handover, STALL_STEPS = 1,
    SDIRK4 reaches 3000 at t~ = 1.001), where mu_w is the steady mu_w^inf to BDF's time error
    (TIME_ERROR_PER_RTOL rtol): the approach's remainder (its slowest mode decays as e^(-2.7 t~)) and the mesh's
    O(h^4) are below 1e-10."""
    fr, u_w = paper_friction, 0.02
    numerics = Numerics(n_cells=256).for_drive("speed")
    mu_w = mu_w_for_speed(fr, u_w)
    pb = ImposedSpeed(fr, u_w, numerics.mesh(*map_for(fr, mu_w, "speed", DECADES[0])))
    states, _ = integrate(pb, DECADES, method="bdf", rtol=numerics.rtol, atol=numerics.atol,
                          h0=INITIAL_STEP * DECADES[0], max_steps=3000)
    assert pb.mu(states[-1])[0] == pytest.approx(mu_w, rel=TIME_ERROR_PER_RTOL["bdf"] * numerics.rtol)


@pytest.mark.parametrize("u_w", SPEEDS)
def test_speed_error_estimates_bound_the_true_error(u_w):
    """The estimates (128 cells against their 64-cell companion: MIN_ESTIMATED_CELLS) of mu_w and delta
    bound the error against 512 cells (1/16 of it) at the decades t~ = 1e-4 to 10, within SPEED_PESSIMISM
    where the error is above the time-error floor (TIME_ERROR_PER_RTOL rtol)."""
    ref, sol = speed_run(u_w, 512), speed_run(u_w, 64, estimate=True)
    assert sol.numerics.n_cells == MIN_ESTIMATED_CELLS["speed"]
    floor = TIME_ERROR_PER_RTOL["bdf"] * sol.numerics.rtol
    for q in ("mu_w", "delta"):
        true = np.abs(getattr(sol, q) - getattr(ref, q))
        assert np.all(true <= sol.errors[q]), q
        resolved = true > floor * np.abs(getattr(ref, q))
        assert np.all(sol.errors[q][resolved] <= SPEED_PESSIMISM * true[resolved]), q


#: u~_w = 0.198 at t~ = 1e-3 (0.026 t~_mud) is in its early lift-off: mu~_w ~ 1e-5, a sub-layer mu~_w/b ~ 3e-7
#: thinner than the wall cluster's first cell (1.5e-7 on 512 cells) resolves; mu_w is off by 1.35e-6 relative
#: whatever the cells (0.6494059 on 256 and 512), and 0.64940507 with 18 e-folds, as the reference (whose map
#: has 20), but 18 e-folds stall BDF near the steady state (bench/RESULTS.md "One map with a wall cluster")
@pytest.fixture(scope="module")
def default_speeds():
    """The CLI's default accuracy for each speed at the reference's times, t~ = 1e-4 ... 10, and the reference
    converged to 1e-9 (tests/continuum/test_reference.py) at each: before and through the lift-off on its
    wall-clustered maps, after it on its exponential map (reference.pieces).  The paper's three speeds and the
    disks' u~_w = 1 (a second parameter set)."""
    from granstokes.continuum.cli import ACCURACY

    from tests.continuum.reference import assembled

    return ACCURACY, {label: (solve_speed(case.friction, case.u_w, case.times, accuracy=ACCURACY), assembled(label))
                      for label, case in SPEED_CASES.items()}


@pytest.mark.parametrize("case", SPEED_CASES)
def test_speed_default_accuracy_against_the_independent_reference(default_speeds, case):
    """At the default accuracy mu_w and delta are within it of the independent reference, t~ = 1e-4 ... 10."""
    accuracy, runs = default_speeds
    sol, ref = runs[case]
    for q in ("mu_w", "delta"):
        true = np.abs(getattr(sol, q) - ref[q])
        assert np.all(true <= accuracy * np.abs(ref[q])), (q, true / np.abs(ref[q]))


@pytest.mark.parametrize("case", SPEED_CASES)
def test_speed_default_estimates_bound_the_independent_reference(default_speeds, case):
    """At the default accuracy the estimates of mu_w and delta bound their errors against the reference at
    every time, the lift-off's included (the early times on the deeper cluster, solver.EARLY_SPAN: on the solve's
    own map the cluster's depth leaves errors that mesh halving cannot see, delta at t~ = 1e-4 3.2e-7 true against
    2.6e-7 estimated, 0.198's mu_w at t~ = 1e-3 1.35e-6)."""
    _, runs = default_speeds
    sol, ref = runs[case]
    for q in ("mu_w", "delta"):
        assert np.all(np.abs(getattr(sol, q) - ref[q]) <= sol.errors[q]), q


def test_speed_estimate_bounds_the_lift_off_peak(paper_friction):
    """Between the decades, at t~ = 2-3e-3 (u~_w = 0.198, t_mud = 0.039) the sub-layer lifts off the wall:
    against a strongly graded reference (256 cells, stretch 12, rtol 1e-10) the estimate bounds the difference
    in mu_w (on the layer's map alone it is first order, 1.1e-3 true against 2.3e-4 estimated).  Before
    solver.early_until (1.6e-3 here) the sub-layer is thinner than the reference's first cell."""
    times = [2e-3, 3e-3]
    ref = solve_speed(paper_friction, 0.198, times, Numerics(n_cells=256, stretch=12.0, rtol=1e-10, atol=1e-12))
    sol = solve_speed(paper_friction, 0.198, times, estimate=True)
    assert np.all(np.abs(sol.mu_w - ref.mu_w) <= sol.errors["mu_w"])


#: a smoke run's in-drive calibration (mu_s ~ 1e-14): its DEM times are t~ ~ 1e-20 ... 1e-17, where BDF's c
#: ~ 1e-25 vanishes from 1 - c J_nn (c read off that diagonal would divide by zero there: lu is handed c itself)
DEGENERATE = (Friction(1.1829808188478833e-14, 0.4233339402935836), 3.157465774452083e-09,
              np.geomspace(4.074607634010895e-20, 1.2223822902032684e-17, 8))


@pytest.mark.parametrize("case", ["64 cells", "160 cells", "degenerate calibration"])  # scipy's dense and
def test_bordered_newton_solves_match_scipys_lu(case):                     # sparse paths, t ~ 1e-20
    """bdf's Newton systems by the bordered band give the solution of scipy's own LU of the reduced Jacobian
    (tests/continuum/bdf_oracle.py) to the time error (measured: 7e-8 relative at rtol 1e-8; held to
    TIME_ERROR_PER_RTOL rtol) with as many Newton iterations (a c read off 2x wrong: BDF fails at t~ = 1e-3).  The
    times are after solver.early_until: on the early times' deeper cluster scipy's LU fails on 64 cells."""
    from tests.continuum import bdf_oracle

    fr, u_w, times = DEGENERATE if case.startswith("degenerate") else (FR, 1.334, [0.06, 0.3, 1.0])
    numerics = (Numerics() if case.startswith("degenerate") else Numerics(n_cells=int(case.split()[0])))
    numerics = numerics.for_drive("speed")
    pb = ImposedSpeed(fr, u_w, numerics.mesh(*map_for(fr, mu_w_for_speed(fr, u_w), "speed", times[0])))
    options = dict(rtol=numerics.rtol, atol=numerics.atol, h0=numerics.initial_step * times[0])
    ours, our_stats = integrate(pb, times, method="bdf", **options)
    scipys, scipy_stats = bdf_oracle.integrate(pb, times, bordered=False, **options)
    bound = TIME_ERROR_PER_RTOL["bdf"] * numerics.rtol
    assert np.max(np.abs([pb.mu(a)[0] / pb.mu(b)[0] - 1 for a, b in zip(ours, scipys)])) < bound
    assert our_stats.newton_iterations <= 1.2 * scipy_stats.newton_iterations  # measured 2514 vs 2531, 2600 vs 2593


def test_reduced_jacobian_dense_equals_sparse(paper_friction):
    """The scipy BDF oracle's reduced Jacobian (wall eliminated) is the same matrix whether built dense (up to
    DENSE_BDF_MAX unknowns) or sparse: entry by entry, to rounding."""
    from tests.continuum import bdf_oracle

    pb = ImposedSpeed(paper_friction, 1.334, Mesh.graded(64, 8.0), order=4)
    x = integrate(pb, [1e-2], method="bdf", rtol=1e-6, atol=1e-8)[0][0]
    dense = bdf_oracle.reduced_jacobian(pb, x, 1e-2)
    sparse = bdf_oracle.reduced_jacobian(pb, x, 1e-2, dense_max=0).toarray()
    assert isinstance(dense, np.ndarray) and dense.shape == sparse.shape == (63, 63)  # nodes 1..63 (tau~_64 = 1 fixed)
    assert np.max(np.abs(dense - sparse)) <= 1e-15 * np.max(np.abs(sparse))


#: the relative spread of mu_w(1) over first steps that the wall's Newton keeps (its measured 1.4e-9, x3.5; the
#: trapped solves' 1.3e-8 is above it)
WALL_NEWTON_SPREAD = 5e-9


def test_bdf_wall_newton_keeps_bdf_out_of_the_order_one_trap():
    """u~_w = 1.334 on 256 cells from five first steps 1e-3 apart (the trap is chaotic in the step sequence):
    each solve within 2300 steps (measured 1867-1934; with the wall's row and column frozen, scipy's BDF with
    wall_newton=False in tests/continuum/bdf_oracle.py, 1910-3516, three of the five trapped at order 1 through the
    lift-off), and mu_w at t~ = 1 the same within WALL_NEWTON_SPREAD across them (measured 1.4e-9; frozen 1.3e-8)."""
    mu_w = []
    for k in range(5):
        sol = solve_speed(FR, 1.334, DECADES, Numerics(n_cells=256, initial_step=INITIAL_STEP * (1 + 1e-3 * k)))
        assert sol.stats.steps <= 2300, k
        mu_w.append(sol.mu_w[list(DECADES).index(1.0)])
    assert np.ptp(mu_w) <= WALL_NEWTON_SPREAD * np.median(mu_w)


def test_an_accuracy_request_starts_where_the_error_model_points():
    """A speed's accuracy request starts on the cells ERROR_MODEL predicts (1e-6: 512, its companion on 256, not
    the 64- and 128-cell rungs), within [MIN_ESTIMATED_CELLS, MAX_CELLS]; the stress has no model."""
    from granstokes.continuum.solver import ERROR_MODEL, MAX_CELLS, first_cells

    cells, error = ERROR_MODEL["speed"]
    assert first_cells("speed", error) == cells
    assert first_cells("speed", error * 16) == cells // 2 and first_cells("speed", error * 17) == cells // 2
    assert first_cells("speed", 1e-2) == MIN_ESTIMATED_CELLS["speed"]
    assert first_cells("speed", 1e-10) == MAX_CELLS["speed"]
    assert first_cells("stress", 1e-10) == MIN_ESTIMATED_CELLS["stress"]


def test_the_smallest_speed_tried_reaches_the_default_accuracy():
    """u~_w = 0.001 (beads, t~_mud = 1e-6): its delta is ill-conditioned (mu_w^inf - mu_s tiny) and BDF's time error
    there ~500 rtol; with the companion's rtol capped (COMPANION_MAX_RTOL, 4e-9 on 256 cells) the default accuracy is
    reached (measured worst estimate 5.7e-7; at the uncapped 1e-8 the request is refused, 1.0-1.1e-6)."""
    from granstokes.continuum.cli import ACCURACY
    from granstokes.continuum.solver import COMPANION_MAX_RTOL

    fine = Numerics(n_cells=512, method="bdf", rtol=6.25e-10, atol=6.25e-12)
    assert fine.coarser(16).rtol == COMPANION_MAX_RTOL["bdf"]
    sol = solve_speed(FR, 0.001, DECADES, accuracy=ACCURACY)
    assert max(np.max(sol.errors[q] / np.abs(getattr(sol, q))) for q in ("mu_w", "delta")) <= ACCURACY


def test_the_reachable_accuracy_is_printed_rounded_up():
    """The refusal's bound, printed at two digits, is rounded up: 1.018e-6 must not read as a request of 1e-6."""
    from granstokes.continuum.solver import round_up

    assert f"{round_up(1.018e-6):.1e}" == "1.1e-06" and f"{round_up(1e-6):.1e}" == "1.0e-06"
    assert f"{round_up(3.81e-7):.1e}" == "3.9e-07" and round_up(2.5e-12) == pytest.approx(2.5e-12, rel=1e-12)


def test_unreachable_speed_accuracy_is_refused_with_what_can_be_reached():
    """1e-8 for a speed would need more than MAX_CELLS: refused after the estimate on them (ERROR_MODEL starts
    it there), naming the accuracy that 512 cells reach (measured 3.8e-7 at u~_w = 1.334)."""
    from granstokes.continuum.solver import MAX_CELLS

    with pytest.raises(ValueError, match=rf"accuracy must be >= \d\.\de-07 .*at most {MAX_CELLS['speed']} cells"):
        solve_speed(FR, 1.334, DECADES, accuracy=1e-8)


def test_speed_early_times_on_the_deeper_cluster():
    """0.198's mu_w at t~ = 1e-3 (0.026 t~_mud, mu~_w ~ 1e-5) on 128 cells: within 1e-7 of the early reference
    with its early times apart (Numerics.early_span, measured 8e-9); on the solve's own map (early_span = 0, the
    control) 1.2e-6 off, an error that N does not change.  The joined series runs on in time."""
    from granstokes.continuum.solver import EARLY_SPAN

    from tests.continuum.reference import cached

    times = [1e-4, 1e-3, 1e-2, 0.1]
    ref = cached("speed-early-0.198", times=np.array(times[:2]))["mu_w"]
    errors = []
    for span in (EARLY_SPAN, 0.0):
        sol = solve_speed(FR, 0.198, times, Numerics(n_cells=128, early_span=span))
        errors.append(np.abs(sol.mu_w[:2] - ref) / ref)
        assert (sol.early_mesh is not None) == (span > 0)
    assert np.all(errors[0] < 1e-7) and errors[1][1] > 1e-6, errors
    assert np.all(np.diff(sol.series.t) > 0)


@pytest.mark.parametrize("u_w", [0.198, 1.334, 4.629])
def test_speed_from_a_late_first_time_meets_the_default_accuracy(u_w):
    """From t~_min = 0.1 the layer's stretch alone would be 0 and the map's cells would crowd the bottom (0.198
    cannot reach 1e-6 on 512 cells there); with the least stretch solver.CLUSTER_MIN_STRETCH every speed reaches
    the CLI's default accuracy, and is within it of the independent reference at t~ = 0.1, 1 and 10, within its
    estimates."""
    from granstokes.continuum.cli import ACCURACY

    from tests.continuum.reference import assembled

    label = f"{u_w:g}"
    times = np.array(SPEED_CASES[label].times)
    late = times >= 0.1
    sol = solve_speed(FR, u_w, times[late], accuracy=ACCURACY)
    ref = {q: v[late] for q, v in assembled(label).items()}
    for q in ("mu_w", "delta"):
        assert np.all(np.abs(getattr(sol, q) - ref[q]) <= ACCURACY * np.abs(ref[q])), q
        assert np.all(np.abs(getattr(sol, q) - ref[q]) <= sol.errors[q]), q
