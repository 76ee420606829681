"""The elasto-plastic mu(I) model (continuum.elastic) against answers it must reproduce.

* The exact elastic wave below yield: a stress tau_w switched on at t = 0 on a stress-free bed, the plate of mass m
  per area: the wave leaves the plate with s(0, t) = -tau_w (1 - exp(-rho c t/m)) and travels down undistorted at
  c = sqrt(G/(phi rho_p)), so until its reflection from the base returns (t < 2 H/c) the plate moves at
  u_w = tau_w/(rho c) (1 - exp(-rho c t/m)) and the stress at depth y is s(0, t - y/c) (zero ahead of the front).
  Worked out here in closed form; the plate's speed to 1e-4, the profile to a few cells' smearing of the front,
  which shrinks as the cells do.
* The rigid limit: under an imposed stress the plate of a soft bed (G = 3e3) runs ahead of local mu(I)'s early on
  (the bed's compliance), that of a bed ten times stiffer five times less, within the regularised local velocity
  form's own creep (1 %, continuum.velocity); and a realistic bed (G = 2400) ends at the exact steady speed of local
  mu(I) on the scene (continuum.scene_models.local_steady, closed form) to 1e-4.
* Convergence in space: the plate's speed at fixed times changes by less and less as the cells double (the
  differences fall by at least 2 per doubling: the scheme's first-to-second order).
* The problem's Jacobian is its rate's derivative (central finite differences), below and above yield.
"""
import numpy as np
import pytest
from granstokes.continuum.elastic import ElasticProblem, solve_elastic
from granstokes.continuum.load import Load
from granstokes.continuum.scales import Material
from granstokes.continuum.scene import BedScene, SceneNumerics
from granstokes.continuum.scene_models import LOCAL, local_steady

MATERIAL = Material(mu_s=0.274, mu_d=0.70, I0=0.24, I_convention="dem", phi=0.80)
P_W = 20.0
MU_W = MATERIAL.mu_s + 0.45 * (MATERIAL.mu_d - MATERIAL.mu_s)


def _fine(n: int, rtol: float = 1e-6) -> SceneNumerics:
    return SceneNumerics(n_cells=n, stretch=0.5, rtol=rtol, atol=rtol * 1e-3, method="tr-bdf2")


@pytest.mark.slow
def test_below_yield_the_stress_travels_down_as_the_exact_elastic_wave():
    G, H, m, tau_w = 2000.0, 40.0, 0.5, 2.0
    rho = MATERIAL.phi * MATERIAL.rho_p
    c = np.sqrt(G / rho)
    transit = H / c
    load = Load("stress", P_W, mu_w=tau_w / P_W)  # tau_w/p = 0.1 < mu_s: elastic throughout
    times = np.array([0.25, 0.5, 0.8, 1.5]) * transit
    plate = tau_w / (rho * c) * (1 - np.exp(-rho * c * times / m))
    fronts = []
    for n in (100, 200):
        sol = solve_elastic(MATERIAL, BedScene(H, m), load, times, G, numerics=_fine(n))
        assert np.allclose(sol.u_w, plate, rtol=1e-3, atol=0)
        lag = times[1] - sol.y_face / c
        exact = np.where(lag > 0, -tau_w * (1 - np.exp(-rho * c * np.maximum(lag, 0) / m)), 0.0)
        fronts.append(np.max(np.abs(sol.s[1] - exact)) / tau_w)
        assert np.max(np.abs(sol.u[1][sol.y > c * times[1] + 2.0])) < 1e-3 * plate[1]  # nothing ahead of the front
    assert fronts[1] < fronts[0] < 0.5


@pytest.mark.slow
def test_a_stiff_bed_tends_to_local_mu_i_and_every_bed_ends_in_its_steady_state():
    scene = BedScene(30.0, 0.47)
    load = Load("stress", P_W, mu_w=MU_W)
    early = np.array([1.0, 3.0, 10.0])
    local = np.interp(early, *LOCAL.predict(MATERIAL, scene, load, early).series[["t", "u_w"]].to_numpy().T)
    soft, stiff = (solve_elastic(MATERIAL, scene, load, early, G, numerics=_fine(100, 1e-5)).u_w / local - 1
                   for G in (3e3, 3e4))
    assert abs(stiff[0]) < abs(soft[0]) / 5 and soft[0] > 0.03  # early on a soft bed lets the plate run ahead
    assert np.all(np.abs(stiff) < 0.01)  # within local mu(I)'s own creep
    ends = solve_elastic(MATERIAL, scene, load, [200.0], 2400.0, numerics=_fine(100, 1e-5))
    assert ends.u_w[-1] == pytest.approx(local_steady(MATERIAL, scene, load).u_w, rel=1e-4)


@pytest.mark.slow
def test_the_plate_s_speed_converges_as_the_cells_double():
    scene = BedScene(30.0, 0.47)
    load = Load("stress", P_W, mu_w=MU_W)
    times = np.array([0.5, 1.0, 3.0])
    u = [solve_elastic(MATERIAL, scene, load, times, 2400.0, numerics=_fine(n)).u_w for n in (50, 100, 200)]
    coarse, fine = np.max(np.abs(u[1] - u[0])), np.max(np.abs(u[2] - u[1]))
    assert 0 < fine < coarse / 2 and fine < 1e-3 * np.max(u[2])


def test_the_jacobian_is_the_rate_s_derivative():
    for load in (Load("stress", P_W, mu_w=MU_W), Load("speed", P_W, u_w=2.0)):
        problem = ElasticProblem(MATERIAL, BedScene(10.0, 0.4), load, _fine(12).mesh(), 500.0)
        rng = np.random.default_rng(3)
        x = rng.normal(size=len(problem.mass))
        stresses = slice(1 - problem.first, None, 2)
        x[stresses] = rng.uniform(-0.65, 0.65, len(x[stresses])) * problem.p_face  # below and above mu_s p, < mu_d p
        assert (np.abs(x[stresses]) > MATERIAL.mu_s * problem.p_face).sum() >= 3
        dense = np.zeros((len(x), len(x)))
        bands = problem.jacobian(x, 0.3).bands
        for j in range(len(x)):
            for i in range(max(0, j - 1), min(len(x), j + 2)):
                dense[i, j] = bands[1 + i - j, j]
        h = 1e-7
        numeric = np.column_stack([(problem.rate(x + h * e, 0.3) - problem.rate(x - h * e, 0.3)) / (2 * h)
                                   for e in np.eye(len(x))])
        assert np.allclose(dense, numeric, rtol=1e-5, atol=1e-5)


def test_the_plate_s_friction_is_the_imposed_stress_or_the_bed_s_stress_on_it():
    """continuum.load.Load.plate_friction, which every scene solution reads: an imposed stress tau_w = 0.4 x 20
    sin(2 t) gives mu_w = 0.4 sin(2 t) whatever the bed; an imposed speed gives -sigma_xy(0+)/p_w."""
    t = np.array([0.1, 0.5, 1.0])
    stress = Load("stress", P_W, mu_w=0.4, omega=2.0)
    assert np.allclose(stress.plate_friction(t, [9.0, 9.0, 9.0]), 0.4 * np.sin(2 * t), rtol=1e-15, atol=0)
    held = Load("stress", P_W, mu_w=0.4)
    assert np.allclose(held.plate_friction(t, [1.0, 2.0, 3.0]), 0.4, rtol=1e-15, atol=0)
    speed = Load("speed", P_W, u_w=2.0)
    assert np.allclose(speed.plate_friction(t, [-8.0, -9.0, -10.0]), [0.4, 0.45, 0.5], rtol=1e-15, atol=0)
