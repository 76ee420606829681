"""The mu(I) law's slope, the conventions of I and the bounds of the friction coefficients (continuum/rheology.py):
each is a number other modules take on trust, so each is checked against an answer computed another way."""
import pytest
from granstokes.continuum.rheology import Friction, convert_I, jop_law, jop_mu


@pytest.mark.parametrize("I", [1e-4, 0.05, 0.3, 2.0])
def test_the_law_s_slope_is_its_difference_quotient(I):
    mu_s, mu_d, I0 = 0.38, 0.64, 0.28
    h = 1e-6 * I
    quotient = (jop_mu(I + h, mu_s, mu_d, I0) - jop_mu(I - h, mu_s, mu_d, I0)) / (2 * h)
    mu, slope = jop_law(I, mu_s, mu_d, I0)
    assert mu == pytest.approx(jop_mu(I, mu_s, mu_d, I0), rel=1e-15)
    assert slope == pytest.approx(quotient, rel=1e-6)
    assert Friction(mu_s, mu_d).mu_and_slope(I, I0)[1] == pytest.approx(quotient, rel=1e-6)


def test_an_unknown_convention_is_named_in_the_error():
    assert convert_I(0.2, "paper", "dem") == pytest.approx(0.4)
    with pytest.raises(ValueError, match=r"^source convention must be one of \['dem', 'paper'\], got 'x'$"):
        convert_I(0.2, "x", "dem")
    with pytest.raises(ValueError, match=r"^target convention must be one of \['dem', 'paper'\], got 'y'$"):
        convert_I(0.2, "paper", "y")


@pytest.mark.parametrize("mu_s, mu_d, message", [
    (0.0, 0.5, r"^mu_s must be a finite number > 0, got 0\.0$"),
    (float("nan"), 0.5, r"^mu_s must be a finite number > 0, got nan$"),
    (0.4, 0.4, r"^mu_d must be a finite number > mu_s = 0\.4, got 0\.4$"),
])
def test_friction_coefficients_outside_their_range_are_refused(mu_s, mu_d, message):
    with pytest.raises(ValueError, match=message):
        Friction(mu_s, mu_d)


def test_the_wall_friction_lies_strictly_between_the_static_and_dynamic_ones():
    f = Friction(0.4, 0.6)
    assert f.check_mu_w(0.5) == 0.5
    for mu_w in (0.4, 0.6, float("inf")):
        with pytest.raises(ValueError) as err:
            f.check_mu_w(mu_w)
        assert str(err.value) == f"mu_w must be in the open interval (mu_s, mu_d) = (0.4, 0.6), got {mu_w!r}"
    assert f.mu_w_from_tilde(0.25) == pytest.approx(0.55)
    for tilde in (0.0, 1.0, 1.5, float("nan")):
        with pytest.raises(ValueError) as err:
            f.mu_w_from_tilde(tilde)
        assert str(err.value) == f"mu_w_tilde must be in the open interval (0, 1), got {tilde!r}"
