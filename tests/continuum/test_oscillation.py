"""Stokes' second problem, the oscillating plate (continuum/oscillation.py): the Newtonian closed form, the
periodic-state criterion, mu(I) and NGF drives.  Grains of the quick preset (mu_s = 0.28, mu_d = 0.58, I0 = 0.3
DEM convention, phi = 0.8), p_w = 20, DEM units."""
from __future__ import annotations

import math

import numpy as np
import pytest
from granstokes.continuum.load import Load
from granstokes.continuum.mesh import Mesh
from granstokes.continuum.ngf import NonlocalFluidity
from granstokes.continuum.oscillation import Newtonian, periodic_state, solve_oscillating
from granstokes.continuum.rules import YieldRule
from granstokes.continuum.scales import Material
from granstokes.continuum.scene import BedScene, SceneNumerics
from granstokes.continuum.solver import SAFETY
from granstokes.continuum.velocity import VelocityProblem

MAT = Material(mu_s=0.28, mu_d=0.58, I0=0.3, I_convention="dem", phi=0.8)
P_W = 20.0
# Newtonian: nu = eta/(phi rho_p) = 2.5, k = sqrt(omega/(2 nu)) = 1/sqrt(5) at omega = 1
ETA, OMEGA, U = 2.0, 1.0, 1.0
K = math.sqrt(OMEGA / (2 * ETA / (MAT.phi * MAT.rho_p)))
SPEED = Load("speed", P_W, u_w=U, omega=OMEGA)
FINE = SceneNumerics(n_cells=100, rtol=1e-8, atol=1e-11)


def newtonian(kH, **options):
    return periodic_state(MAT, BedScene(kH / K), SPEED, law=Newtonian(ETA), numerics=FINE, **options)


def finite_bed(t, y, H):
    """u = U Im[e^{i omega t} sinh(kappa (H - y))/sinh(kappa H)], kappa = (1 + i) k: u(0) = U sin(omega t), u(H) = 0
    (Im, not Re: the plate moves as sin); and the plate's friction -eta du/dy(0)/p_w."""
    kappa = (1 + 1j) * K
    phase = np.exp(1j * OMEGA * np.asarray(t))[:, None]
    u = U * np.imag(phase * np.sinh(kappa * (H - y)) / np.sinh(kappa * H))
    return u, ETA * U * np.imag(phase[:, 0] * kappa / np.tanh(kappa * H)) / P_W


def test_newtonian_finite_bed_matches_the_closed_form_within_the_estimate():
    """kH = 3 (the finite bed differs from the semi-infinite one by ~e^-3): the periodic state (tol 1e-6) matches
    the closed form, and the Richardson estimate is the error to within its safety factor both ways (measured:
    err/estimate = 1.03 for u, 1.00 for mu_w on 100 cells; second order)."""
    H = 3 / K
    ps = newtonian(3, tol=1e-6)
    u, mu_w = finite_bed(ps.t, ps.y, H)
    err_u, err_mu = np.max(np.abs(ps.u - u)), np.max(np.abs(ps.mu_w - mu_w))
    est_u, est_mu = np.max(ps.u_err), np.max(ps.mu_w_err)
    assert est_u < 1e-3 * U and est_mu < 1e-3 * np.max(np.abs(mu_w))
    assert est_u / SAFETY < err_u < SAFETY * est_u, (err_u, est_u)
    assert est_mu / SAFETY < err_mu < SAFETY * est_mu, (err_mu, est_mu)
    assert np.all(ps.u_w_err == 0)  # an imposed speed: the plate's u_w is exact
    semi = U * np.exp(-K * ps.y) * np.sin(OMEGA * ps.t[:, None] - K * ps.y)
    assert np.max(np.abs(ps.u - semi)) > 30 * SAFETY * est_u  # the finite bed is not the semi-infinite one


@pytest.mark.slow
def test_newtonian_deep_bed_is_the_semi_infinite_stokes_layer():
    """kH = 8: the semi-infinite Stokes layer u = U e^{-ky} sin(omega t - ky) within the estimate plus e^{-kH} U
    (measured: 6.1e-4 U against 5.9e-4 U + 3.4e-4 U; 23 cycles to tol 1e-6)."""
    ps = newtonian(8, tol=1e-6)
    semi = U * np.exp(-K * ps.y) * np.sin(OMEGA * ps.t[:, None] - K * ps.y)
    assert np.max(np.abs(ps.u - semi)) < np.max(ps.u_err) + math.exp(-8) * U


def test_periodic_state_criterion_and_the_bed_s_slowest_mode():
    """change_n = max |u_n - u_{n-1}|/max |u_n| over phases and nodes: on a deep Newtonian bed it falls as the
    slowest free mode, sin(pi y/H), decays over a cycle: exp(-nu (pi/H)^2 2 pi/omega) = exp(-pi^3/(kH)^2) = 0.616
    at kH = 8.  The march stops at the first change below tol; too few cycles leave it unconverged."""
    ps = newtonian(8, tol=1e-3, error_estimate=False)
    c = ps.changes
    assert ps.converged and ps.cycles == len(c) + 1
    assert np.all(np.diff(c) < 0) and c[-1] < 1e-3 <= c[-2]
    assert c[-1] / c[-2] == pytest.approx(math.exp(-math.pi**3 / 64), rel=0.02)
    short = newtonian(8, tol=1e-3, max_cycles=4, error_estimate=False)
    assert not short.converged and short.cycles == 4 and short.changes[-1] > 1e-3
    np.testing.assert_array_equal(short.changes, c[:3])


SCENE = BedScene(8.0)
COARSE = SceneNumerics(n_cells=50)
RULE = YieldRule(eps=1e-3)
OMEGA_G = 0.5


@pytest.fixture(scope="module")
def flowing():
    """mu(I) under u_w = 2 sin(0.5 t) and under tau_w = 0.43 p_w sin(0.5 t), periodic states."""
    speed = periodic_state(MAT, SCENE, Load("speed", P_W, u_w=2.0, omega=OMEGA_G), rule=RULE, numerics=COARSE)
    stress = periodic_state(MAT, SCENE, Load("stress", P_W, mu_w=0.43, omega=OMEGA_G), rule=RULE, numerics=COARSE,
                            error_estimate=False)
    return speed, stress


def cycle_integral(ps, f):
    """The periodic trapezoid rule over the last cycle's phases."""
    return np.sum(f, axis=0) * ps.load.period / len(ps.t)


@pytest.mark.parametrize("kind", ["speed", "stress"])
def test_jacobian_is_the_rate_s_derivative_and_the_wall_is_the_load_s_at_t(kind):
    """jacobian(x, t), the band (plate row included), is d rate/dx (central differences) at a sheared state with the
    wall value of time t; the rate reads the load's wall at t (the plate row's force, or the first face's speed)."""
    load = Load(kind, P_W, omega=OMEGA_G, **({"u_w": 2.0} if kind == "speed" else {"mu_w": 0.43}))
    pb = VelocityProblem(MAT, SCENE, load, Mesh.graded(16, 2.0), rule=RULE)
    x = np.linspace(1.5, 0.1, len(pb.mass)) ** 2
    t, h = 1.0, 1e-6
    numeric = np.array([(pb.rate(x + h * e, t) - pb.rate(x - h * e, t)) / (2 * h) for e in np.eye(len(x))]).T
    np.testing.assert_allclose(pb.jacobian(x, t).sparse().toarray(), numeric, rtol=1e-6,
                               atol=1e-6 * np.max(np.abs(numeric)))
    assert pb.nodes(x, t)[0] == (load.u_w * math.sin(OMEGA_G * t) if kind == "speed" else x[0])
    if kind == "stress":  # the plate row: tau_w(t) + sigma_xy(0+), tau_w(t) = mu_w p_w sin(omega t)
        later = pb.rate(x, 2 * t)[0] - pb.rate(x, t)[0]
        assert later == pytest.approx(load.tau_w * (math.sin(2 * OMEGA_G * t) - math.sin(OMEGA_G * t)), rel=1e-12)


@pytest.mark.slow
def test_mu_i_speed_drive(flowing):
    """The plate follows the imposed speed exactly, |mu_w| < mu_d, the plate's work per cycle is positive and is
    the bed's dissipation sum over faces of sigma_xy du/dy h (the semi-discrete energy balance, up to the phase
    quadrature); mu_w is anti-periodic over half a cycle."""
    ps = flowing[0]
    np.testing.assert_allclose(ps.u_w, 2.0 * np.sin(OMEGA_G * ps.t), rtol=0, atol=1e-14)
    assert MAT.mu_s < np.max(np.abs(ps.mu_w)) < MAT.mu_d and np.max(ps.mu_w_err) < 1e-3
    work = cycle_integral(ps, ps.mu_w * P_W * ps.u_w)
    s = ps.mu * (P_W + MAT.weight_gradient * ps.y_mu)
    dissipated = cycle_integral(ps, np.sum(s * np.diff(ps.u, axis=1), axis=1))
    assert work > 0 and work == pytest.approx(dissipated, rel=3e-3)  # measured 8e-4
    half = len(ps.t) // 2
    np.testing.assert_allclose(ps.mu_w[half:], -ps.mu_w[:half], atol=1e-5)


@pytest.mark.slow
def test_mu_i_stress_drive_moves_the_plate_above_mu_s_and_creeps_below(flowing):
    """Amplitude 0.43 > mu_s: the plate flows (|u_w| ~ 2); 0.5 mu_s: it only creeps through the regularised law,
    u_w proportional to eps (a viscosity mu_s p/eps), below 1% of the flowing amplitude at eps = 1e-3."""
    moving = np.max(np.abs(flowing[1].u_w))
    times = np.pi / OMEGA_G * np.arange(1, 9) / 2
    creep = {eps: solve_oscillating(MAT, SCENE, Load("stress", P_W, mu_w=0.5 * MAT.mu_s, omega=OMEGA_G), times,
                                    rule=YieldRule(eps=eps), numerics=COARSE, error_estimate=False)
             for eps in (1e-3, 1e-2)}
    still = np.max(np.abs(creep[1e-3].u_w))
    assert moving > 1.0 and still < 1e-2 * moving
    assert np.max(np.abs(creep[1e-2].u_w)) / still == pytest.approx(10, rel=0.05)  # measured 9.9


@pytest.mark.slow
def test_ngf_speed_drive_is_periodic_after_a_few_cycles():
    """NGF (A = 0.5) under u_w = 2 sin(0.5 t): mu_w sampled at the same phases cycle after cycle settles (changes
    decreasing), and the periodic mu_w is anti-periodic over half a cycle."""
    load = Load("speed", P_W, u_w=2.0, omega=OMEGA_G)
    phases, cycles = 16, 4
    times = load.period * np.arange(1, phases * cycles + 1) / phases
    sol = solve_oscillating(MAT, SCENE, load, times, model="ngf", fluidity=NonlocalFluidity(A=0.5),
                            numerics=SceneNumerics(n_cells=24), error_estimate=False)
    mu_w = sol.mu_w.reshape(cycles, phases)
    changes = np.max(np.abs(np.diff(mu_w, axis=0)), axis=1) / np.max(np.abs(mu_w))
    assert np.all(np.diff(changes) < 0) and changes[-1] < 1e-3, changes
    assert MAT.mu_s < np.max(np.abs(mu_w[-1])) < 0.5
    np.testing.assert_allclose(mu_w[-1, phases // 2:], -mu_w[-1, :phases // 2], atol=1e-4)
