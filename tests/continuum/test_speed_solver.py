"""Imposed wall speed (eq. GranularStokesEqn_muBIS with eq. GranularStokesEqn_muBIS_BCs)."""
import numpy as np
import pytest

from continuum.closed_forms import speed_short_time_mu
from continuum.mesh import Mesh
from continuum.problems import ImposedSpeed
from continuum.solver import Numerics, solve_speed, solve_stress
from continuum.stepper import integrate

SPEEDS = (0.198, 1.334, 4.629)


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
    """mu_w(t~ -> inf) equals mu_w^inf of the matching imposed-stress case, to the mesh's O(h^3)
    (the first cell's weight sqrt(p~) taken at its midpoint; fourth order elsewhere): the gap shrinks
    eight-fold per mesh halving; and that stress case's steady speed is u~_w."""
    fr = paper_friction
    gaps = []
    for n in (100, 200):
        sol = solve_speed(fr, u_w, [1e3], Numerics(n_cells=n))
        gaps.append(sol.mu_w[-1] - sol.mu_w_inf)
    assert gaps[0] / gaps[1] == pytest.approx(8.0, rel=0.1)
    assert abs(gaps[1]) < 1e-5
    stress = solve_stress(fr, sol.mu_w_inf, [1e3])
    assert stress.u_w[-1] == pytest.approx(u_w, rel=1e-4)
    assert sol.delta[-1] == pytest.approx(stress.delta[-1], abs=1e-6)


def test_wall_friction_is_mu_d_before_t_mud_on_any_mesh(paper_friction):
    """For t~ << t_mud = u~_w^2 the continuum has mu_w -> mu_d exponentially: the first cell, exact for
    a linear mu~, shows it on every mesh (the former trapezoidal cell gave mu~_w = h_0/(2 Dmu u~_w),
    1e-5 here), and mu_w has left mu_d by t~ = t_mud."""
    fr, u_w = paper_friction, 1.334
    for n in (64, 128):
        sol = solve_speed(fr, u_w, [1e-4, u_w**2], Numerics(n_cells=n))
        assert fr.tilde(sol.mu_w[0]) < 1e-12 < 1e-2 < fr.tilde(sol.mu_w[1])


@pytest.mark.parametrize("q, b", [(3.0, 0.5), (0.7, 0.5), (np.log(2.0) + 1e-7, 0.5), (np.log(2.0) + 1e-3, 0.5),
                                  (0.1, 0.9), (40.0, 0.2), (-2.0, 0.3)])
def test_first_cell_integral_and_derivatives(paper_friction, q, b):
    """The first cell's int_0^1 ds/(a + (b - a) s), a = exp(-q), against adaptive quadrature (to 1e-13) in
    each of its three forms (series, atanh, logarithms), and its derivatives against central differences."""
    from scipy.integrate import quad

    pb = ImposedSpeed(paper_friction, 1.0, Mesh.graded(16))
    a = np.exp(-q)
    ref = quad(lambda s: 1 / (a + (b - a) * s), 0, 1, epsabs=0, epsrel=1e-13, limit=200)[0]
    lam, dq, db = pb._first_cell(q, b)
    assert lam == pytest.approx(ref, rel=2e-13)
    e = 1e-6
    assert dq == pytest.approx((pb._first_cell(q + e, b)[0] - pb._first_cell(q - e, b)[0]) / (2 * e), rel=1e-7)
    assert db == pytest.approx((pb._first_cell(q, b + e)[0] - pb._first_cell(q, b - e)[0]) / (2 * e), rel=1e-7)


@pytest.mark.parametrize("u_w", SPEEDS)
def test_layer_grows_as_sqrt_t(paper_friction, u_w):
    sol = solve_speed(paper_friction, u_w, [1e-4, 1e-3])
    assert np.log10(sol.delta[1] / sol.delta[0]) == pytest.approx(0.5, abs=0.02)


@pytest.mark.parametrize("u_w", SPEEDS[1:])
def test_short_time_self_similarity(paper_friction, u_w):
    """For t~ << t_mud the excess (mu - mu_s)/(mu_w(t) - mu_s) is a function of
    eta = y~/(2 Dmu sqrt(t~)) alone (the paper's figure 9: collapse within 1 %), and the erfc form
    eq. muShortTime_VelocityImposed is the 'reasonable fit' the paper reports: within 25 %."""
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
    """mu_w(t~) decreases monotonically (to the step tolerance) from ~mu_d to mu_w^inf."""
    fr = paper_friction
    sol = solve_speed(fr, u_w, [1e-4, 30.0])
    series = sol.series["mu_w"].to_numpy()[1:]
    assert fr.tilde(series[0]) < 1e-2
    assert np.all(np.diff(series) < 1e-6)
    assert sol.mu_w[-1] == pytest.approx(sol.mu_w_inf, abs=2e-2 * (sol.mu_w_inf - fr.mu_s))


#: the speed drive's estimate (SAFETY |fine - companion| at order 1) is pessimistic where mu_w or delta
#: converge faster than order 1 (measured: up to ~200x for mu_w, ~1000x for delta; bench/RESULTS.md)
SPEED_PESSIMISM = 500


@pytest.mark.parametrize("u_w", SPEEDS[:2])
def test_speed_error_estimates_bound_the_true_error(paper_friction, u_w):
    """At the default 64 cells the estimates of mu_w and delta bound the error against 512 cells (whose
    own error, first order, is 1/8 of it), t~ = 1e-4 to 10, within SPEED_PESSIMISM."""
    times = [1e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0]
    ref = solve_speed(paper_friction, u_w, times, Numerics(n_cells=512))
    sol = solve_speed(paper_friction, u_w, times, Numerics(n_cells=64), estimate=True)
    for q in ("mu_w", "delta"):
        true = np.abs(getattr(sol, q) - getattr(ref, q))
        assert np.all(true <= sol.errors[q]), q
        resolved = true > 1e-12
        assert np.all(sol.errors[q][resolved] <= SPEED_PESSIMISM * true[resolved]), q


@pytest.mark.xfail(strict=True, reason="issue 11 open: the lift-off peak of the mu_w error (t~ ~ t_mud/13) is "
                                       "underestimated at 64 cells (measured 1.1e-3 true against 2.3e-4 estimated)")
def test_speed_estimate_bounds_the_lift_off_peak(paper_friction):
    """Between the decades, at t~ = 3e-3 on the mesh for t~ >= 1e-3 (u~_w = 0.198, t_mud = 0.039), the wall cell is thicker than the
    lifting sub-layer; against a strongly graded reference (256 cells, stretch 12, good to ~1e-7 there)
    the 64-cell estimate should bound the error of mu_w."""
    times = [1e-3, 2e-3, 3e-3]  # the mesh follows the first: as in bench/RESULTS.md
    ref = solve_speed(paper_friction, 0.198, times, Numerics(n_cells=256, stretch=12.0, rtol=1e-10, atol=1e-12))
    sol = solve_speed(paper_friction, 0.198, times, Numerics(n_cells=64), estimate=True)
    assert np.all(np.abs(sol.mu_w - ref.mu_w) <= sol.errors["mu_w"])


def test_reduced_jacobian_dense_equals_sparse(paper_friction, monkeypatch):
    """The BDF path's reduced Jacobian (wall eliminated) is the same matrix whether built dense (up to
    DENSE_BDF_MAX unknowns) or sparse: entry by entry, to rounding."""
    import continuum.stepper as stepper

    pb = ImposedSpeed(paper_friction, 1.334, Mesh.graded(64, 8.0), order=4)
    x = integrate(pb, [1e-2], method="bdf", rtol=1e-6, atol=1e-8)[0][0]
    dense = stepper._reduced_jacobian(pb, x)
    monkeypatch.setattr(stepper, "DENSE_BDF_MAX", 0)
    sparse = stepper._reduced_jacobian(pb, x).toarray()
    assert isinstance(dense, np.ndarray) and dense.shape == sparse.shape == (63, 63)  # nodes 1..63 (tau~_64 = 1 fixed)
    assert np.max(np.abs(dense - sparse)) <= 1e-15 * np.max(np.abs(sparse))
