"""Derived profile fields and the profiles' band (compare.profiles ``derive``, ``_band``) and the Welch-Satterthwaite
degrees of freedom (compare.rows ``effective_dof``) against answers worked out by hand.

* derive: u_x = j_x / rho = 2 y on three nodes (dudy = 2 exactly), p = sigma_yy = 4, 0.5, 0 and tau = -sigma_xy:
  mu = tau / p where p > 0 (NaN at p = 0), gamma_dot_paper = gamma_dot_dem / 2, I = gamma_dot d / sqrt(p / rho_p),
  with the defaults d = rho_p = 1 and with d = 3, rho_p = 2.5;
* _band over two samples (1, 3) per node: central -+ t_0.975(1) std(ddof=1)/sqrt(2) = -+ t_0.975(1) (scipy);
* effective_dof: (sum e^2)^2 / sum(e^4 / dof) written out; a zero error adds nothing even with no degree of
  freedom; no error above zero gives infinitely many; integer errors are squared as floats (no integer overflow).
"""
import numpy as np
import pytest
from granstokes.compare.profiles import COMPONENTS, FIELDS, _band, derive
from granstokes.compare.rows import effective_dof
from scipy import stats

Y = np.array([0.0, 1.0, 2.0])
P = np.array([4.0, 0.5, 0.0])
TAU = np.array([1.0, 0.25, 0.3])


def _fields():
    rho = np.full(3, 2.0)
    f = {"rho": rho, "j_x": rho * 2 * Y, "j_y": np.zeros(3), "j_z": np.zeros(3), "sigma_c_yx": np.zeros(3)}
    for c in COMPONENTS:
        f[f"sigma_k_{c}"], f[f"sigma_c_{c}"] = np.zeros(3), np.zeros(3)
    f["sigma_c_yy"], f["sigma_c_xy"] = P.copy(), -TAU
    return f


def test_mu_is_tau_over_p_where_p_is_positive():
    mu = derive(_fields(), Y, 2)["mu"]
    np.testing.assert_allclose(mu[:2], TAU[:2] / P[:2], rtol=1e-12)
    assert np.isnan(mu[2])


def test_the_inertial_numbers_use_d_and_rho_p_one_by_default_and_the_paper_s_half_shear_rate():
    out = derive(_fields(), Y, 2)
    np.testing.assert_allclose(out["gamma_dot_paper"], [1.0, 1.0, 1.0], rtol=1e-12)
    np.testing.assert_allclose(out["I_dem"][:2], 2.0 / np.sqrt(P[:2]), rtol=1e-12)
    np.testing.assert_allclose(out["I_paper"][:2], 1.0 / np.sqrt(P[:2]), rtol=1e-12)
    assert np.isnan(out["I_dem"][2]) and np.isnan(out["I_paper"][2])
    out = derive(_fields(), Y, 2, d=3.0, rho_p=2.5)
    np.testing.assert_allclose(out["I_dem"][:2], 2.0 * 3.0 * np.sqrt(2.5 / P[:2]), rtol=1e-12)
    np.testing.assert_allclose(out["I_paper"][:2], 3.0 * np.sqrt(2.5 / P[:2]), rtol=1e-12)


def test_the_band_of_two_samples_is_the_student_t_of_one_dof_times_the_standard_error():
    central = {k: np.array([2.0, 5.0]) for k in FIELDS}
    samples = {k: np.array([[1.0, 4.0], [3.0, np.nan]]) for k in FIELDS}  # second node: one sample
    out = _band(central, samples, 2, "seeds")
    half = stats.t.ppf(0.975, 1) * np.std([1.0, 3.0], ddof=1) / np.sqrt(2)
    for k in ("u_x", "p", "rho"):
        assert out[f"{k}_lo"][0] == pytest.approx(2.0 - half, rel=1e-12)
        assert out[f"{k}_hi"][0] == pytest.approx(2.0 + half, rel=1e-12)
        assert np.isnan(out[f"{k}_lo"][1]) and np.isnan(out[f"{k}_hi"][1])
    assert out["n"] == 2 and out["band_over"] == "seeds"


def test_a_zero_error_adds_no_degrees_of_freedom_even_with_none_of_its_own():
    # errors 0, 1, 1 at 0, 2, 2 dof: (1 + 1)^2 / (1/2 + 1/2) = 4
    assert effective_dof([0.0, 1.0, 1.0], [0.0, 2.0, 2.0]) == pytest.approx(4.0, rel=1e-12)


def test_no_error_above_zero_has_infinitely_many_degrees_of_freedom():
    assert effective_dof([0.0, 0.0], [3.0, 5.0]) == np.inf


def test_integer_errors_are_squared_as_floats():
    e = 60000  # e^4 overflows a 64-bit integer
    assert effective_dof([e, e], [2, 2]) == pytest.approx((2.0 * e**2) ** 2 / (2 * float(e) ** 4 / 2), rel=1e-12)

