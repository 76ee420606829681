"""Exact steady state, the paper's scales and the inertial-number conventions."""
import math

import numpy as np
import pytest
from granstokes.continuum.closed_forms import UWALL_MUS_PRINTED_B2, uwall_asymp, uwall_mus
from granstokes.continuum.rheology import convert_I
from granstokes.continuum.scales import Material, Scales
from granstokes.continuum.steady import mu_w_for_speed, steady_delta, steady_velocity, steady_wall_speed
from scipy.integrate import quad


@pytest.mark.parametrize("mu_w_tilde, expected", [(0.9, 0.19940), (0.5, 1.34039), (0.1, 4.62788)])
def test_paper_steady_wall_speeds(paper_friction, mu_w_tilde, expected):
    fr = paper_friction
    mu_w = fr.mu_w_from_tilde(mu_w_tilde)
    assert steady_wall_speed(fr, mu_w) == pytest.approx(expected, abs=2e-5)
    # the closed-form antiderivative equals adaptive quadrature of eq. (3.10)
    beta = fr.beta(mu_w)
    integrand = lambda y: math.sqrt(1 + beta * y) / fr.dmu * (1 / fr.tilde(mu_w / (1 + beta * y)) - 1)
    for y0 in (0.0, 0.3, 0.9):
        assert steady_velocity(fr, mu_w, y0) == pytest.approx(quad(integrand, y0, 1, epsrel=1e-13)[0], rel=1e-10)


@pytest.mark.parametrize("u_w", [0.01, 0.198, 1.334, 4.629, 20.0])
def test_speed_inverse(paper_friction, u_w):
    mu_w = mu_w_for_speed(paper_friction, u_w)
    assert steady_wall_speed(paper_friction, mu_w) == pytest.approx(u_w, rel=1e-12)


def test_steady_delta_is_the_threshold_depth(paper_friction):
    fr = paper_friction
    mu_w = fr.mu_w_from_tilde(0.5)
    d = steady_delta(fr, mu_w)
    excess = (mu_w / (1 + fr.beta(mu_w) * d) - fr.mu_s) / (mu_w - fr.mu_s)
    assert excess == pytest.approx(1e-3, rel=1e-12)


def test_uwall_mus_expansion_orders(paper_friction):
    """Derived b2 leaves an O(beta^3) error (ratio 8 per halving); the printed -5/2 an O(beta^2) one."""
    fr = paper_friction
    betas = np.array([0.02, 0.01, 0.005])
    exact = np.array([steady_wall_speed(fr, fr.mu_s * (1 + b)) for b in betas])
    err = np.abs(uwall_mus(fr, fr.mu_s * (1 + betas)) - exact)
    err_printed = np.abs(uwall_mus(fr, fr.mu_s * (1 + betas), UWALL_MUS_PRINTED_B2) - exact)
    assert np.log2(err[:-1] / err[1:]) == pytest.approx([3, 3], abs=0.15)
    assert np.log2(err_printed[:-1] / err_printed[1:]) == pytest.approx([2, 2], abs=0.1)


def test_uwall_asymp_relative_error_is_order_beta(paper_friction):
    fr = paper_friction
    rel = []
    for b in (0.02, 0.01):
        mw = fr.mu_s * (1 + b)
        rel.append(uwall_asymp(fr, fr.tilde(mw)) / steady_wall_speed(fr, mw) - 1)
    assert rel[0] / rel[1] == pytest.approx(2.0, rel=0.05)


def test_nu_g_factor_two_makes_U_consistent():
    """Integrating the dimensional eq. (2.12) over the steady layer gives U * u~_w^inf only
    with nu_g = (d/(2 phi Dmu I0)) sqrt(p_w/rho) (the paper prints a second version without the 2)."""
    m = Material(I0=0.3, I_convention="paper", phi=0.58, d=2e-3, rho_p=2500.0, g=9.81)
    p_w, mu_w = 3000.0, m.friction.mu_w_from_tilde(0.5)
    sc = Scales(m, p_w, mu_w)

    def dudy(y):  # eq. (2.12), paper convention
        p = p_w + m.phi * m.rho_p * m.g * y
        mu = mu_w * p_w / p
        return 2 * m.I0 * math.sqrt(p / (m.rho_p * m.d**2)) * (mu - m.mu_s) / (m.mu_d - mu)

    u_w = quad(dudy, 0.0, sc.delta_s, epsrel=1e-12)[0]
    assert u_w == pytest.approx(sc.U * steady_wall_speed(m.friction, mu_w), rel=1e-9)
    assert sc.nu_g == pytest.approx(m.d / (2 * m.phi * sc.dmu * m.I0) * math.sqrt(p_w / m.rho_p), rel=1e-14)
    assert sc.delta_s == pytest.approx(sc.beta_w * p_w / (m.phi * m.rho_p * m.g), rel=1e-14)
    assert sc.t(sc.t_tilde(1.7)) == pytest.approx(1.7) and sc.y(sc.y_tilde(0.01)) == pytest.approx(0.01)


def test_inertial_number_conventions():
    """The same material, stated in both conventions, gives the same scales and mu at the same shear."""
    a = Material(I0=0.279, I_convention="dem")
    b = Material(I0=0.1395, I_convention="paper")
    assert a.I0_paper == pytest.approx(b.I0_paper)
    assert convert_I(0.1, "paper", "dem") == pytest.approx(0.2)
    fr, du_dy, p = a.friction, 0.4, 2.0
    I_dem, I_paper = du_dy / math.sqrt(p), 0.5 * du_dy / math.sqrt(p)
    assert fr.mu_of_I(I_dem, a.I0) == pytest.approx(fr.mu_of_I(I_paper, a.I0_paper))
    assert fr.I_of_mu(fr.mu_of_I(I_dem, a.I0), a.I0) == pytest.approx(I_dem)


def test_for_speed_inverts_the_velocity_scale():
    m = Material()
    sc = Scales(m, 10.0, m.friction.mu_w_from_tilde(0.3))
    u_w = sc.U * steady_wall_speed(m.friction, sc.mu_w)
    assert Scales.for_speed(m, 10.0, u_w).mu_w == pytest.approx(sc.mu_w, rel=1e-10)


@pytest.mark.parametrize("kwargs, message", [
    ({"phi": 1.0}, "phi must be in the open interval (0, 1), got 1.0"),
    ({"phi": 0.0}, "phi must be in the open interval (0, 1), got 0.0"),
    ({"phi": float("nan")}, "phi must be in the open interval (0, 1), got nan"),
    ({"d": 0.0}, "d must be a finite number > 0, got 0.0"),
    ({"rho_p": -1.0}, "rho_p must be a finite number > 0, got -1.0"),
    ({"g": float("inf")}, "g must be a finite number > 0, got inf"),
    ({"I0": float("nan")}, "I0 must be a finite number > 0, got nan"),
    ({"mu_s": 0.5, "mu_d": 0.4}, "mu_d must be a finite number > mu_s = 0.5, got 0.4"),
    ({"I_convention": "gdr"}, "I_convention must be one of ['dem', 'paper'], got 'gdr'")])
def test_a_bad_material_is_refused_naming_the_parameter_and_its_range(kwargs, message):
    with pytest.raises(ValueError) as err:
        Material(**kwargs)
    assert str(err.value) == message


def test_a_material_at_the_edges_of_its_ranges_is_accepted():
    """Strict bounds are strict on the refused side only: small positive values and phi just inside (0, 1) pass."""
    for kwargs in ({"phi": 1e-6}, {"phi": 1 - 1e-6}, {"d": 0.5}, {"rho_p": 1e-3}, {"g": 0.25}, {"I0": 1e-4}):
        assert getattr(Material(**kwargs), next(iter(kwargs))) == next(iter(kwargs.values()))


@pytest.mark.parametrize("call, message", [
    (lambda m: Scales(m, 0.0, 0.5), "p_w must be a finite number > 0, got 0.0"),
    (lambda m: Scales(m, float("nan"), 0.5), "p_w must be a finite number > 0, got nan"),
    (lambda m: Scales.for_speed(m, 10.0, 0.0), "u_w must be a finite number > 0, got 0.0"),
    (lambda m: Scales.for_speed(m, 10.0, float("inf")), "u_w must be a finite number > 0, got inf"),
    (lambda m: Scales.for_speed(m, 0.0, 1.0), "p_w must be a finite number > 0, got 0.0"),
    (lambda m: Scales.for_speed(m, float("nan"), 1.0), "p_w must be a finite number > 0, got nan"),
    (lambda m: Scales.for_speed(m, 10.0, 1e9),
     "u_w must be a speed reachable with mu_s < mu_w < mu_d, got 1000000000.0"),
])
def test_a_bad_load_is_refused_naming_the_parameter_and_its_range(call, message):
    with pytest.raises(ValueError) as err:
        call(Material())
    assert str(err.value) == message


def test_bad_loading(paper_friction):
    m = Material()
    with pytest.raises(ValueError, match="^mu_w must be"):
        Scales(m, 1.0, m.mu_d)
    with pytest.raises(ValueError, match="^u_w must be"):
        mu_w_for_speed(paper_friction, -1.0)


@pytest.mark.parametrize("p_w, u_w", [(0.5, 0.3), (0.8, 0.05), (40.0, 3.0)])
def test_for_speed_solves_the_steady_speed_to_rounding(p_w, u_w):
    """Below unit pressure and speed too (no bound at 1): U(mu_w) u~_w(mu_w) reproduces u_w to 1e-13."""
    m = Material(d=1.3, rho_p=2.0, g=0.7, phi=0.55)
    sc = Scales.for_speed(m, p_w, u_w)
    assert m.mu_s < sc.mu_w < m.mu_d
    assert sc.U * steady_wall_speed(m.friction, sc.mu_w) == pytest.approx(u_w, rel=1e-13)


def test_the_scales_in_the_record_are_the_paper_s_formulas():
    """delta_s = beta_w p_w/(phi rho_p g) (eq. (2.11)), nu_g = d sqrt(p_w/rho_p)/(2 phi Dmu I0_paper) (eq. (2.14)),
    t_s = delta_s^2/nu_g, U = g delta_s^2/(beta_w nu_g) (eq. (3.8)); I0 given in the DEM convention is twice the
    paper's. Non-unit d, rho_p, g and phi so that each enters."""
    from granstokes.continuum.scales import UNITS
    mu_s, mu_d, I0_dem, phi, d, rho, g = 0.3, 0.7, 0.5, 0.55, 1.3, 2.0, 0.7
    m = Material(mu_s=mu_s, mu_d=mu_d, I0=I0_dem, I_convention="dem", phi=phi, d=d, rho_p=rho, g=g)
    p_w, mu_w = 8.0, 0.45
    beta = mu_w / mu_s - 1
    delta_s = beta * p_w / (phi * rho * g)
    nu_g = d * math.sqrt(p_w / rho) / (2 * phi * (mu_d - mu_s) * (I0_dem / 2))
    expected = {"p_w": p_w, "mu_w": mu_w, "mu_w_tilde": (mu_d - mu_w) / (mu_d - mu_s), "beta_w": beta,
                "delta_s": delta_s, "nu_g": nu_g, "t_s": delta_s**2 / nu_g, "U": g * delta_s**2 / (beta * nu_g),
                "I0_paper": I0_dem / 2}
    record = Scales(m, p_w, mu_w).as_dict()
    assert record.pop("units") == UNITS
    assert record.keys() == expected.keys()
    for key, value in expected.items():
        assert record[key] == pytest.approx(value, rel=1e-14), key


def test_conversions_are_consistent_with_hydrostatics():
    """p~ = 1 + beta_w y~ must be the hydrostatic p(y)/p_w (eq. (2.6)) given delta_s; tau~ = 1 is
    tau_w = mu_w p_w; u~ converts with U."""
    m = Material(phi=0.58)
    sc = Scales(m, 12.0, m.friction.mu_w_from_tilde(0.4))
    for y_t in (0.0, 0.3, 1.0):
        assert sc.p_tilde(sc.pressure(sc.y(y_t))) == pytest.approx(1 + sc.beta_w * y_t, rel=1e-14)
    assert sc.tau(1.0) == pytest.approx(sc.mu_w * 12.0) and sc.tau_tilde(sc.tau(0.7)) == pytest.approx(0.7)
    assert sc.u(sc.u_tilde(2.5)) == pytest.approx(2.5) and sc.p(sc.p_tilde(13.0)) == pytest.approx(13.0)
