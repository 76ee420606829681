"""Units, material and loading parameters, and the paper's scales (the one place they are defined).

Units
-----
* DEM units: lengths in grain diameter d, mass in rho_p d^3, time in sqrt(d/g),
  velocity in sqrt(g d), stress in rho_p g d.  Any consistent unit system (SI too) works
  for the dataclasses below; only ratios enter the paper's variables.
* The paper's dimensionless variables (tilde): y~ = y/delta_s, t~ = t nu_g/delta_s^2,
  u~ = u/U, p~ = p/p_w = 1 + beta_w y~, tau~ = tau/tau_w, mu~ = (mu_d - mu)/Delta mu.
* Inertial number: see continuum.rheology; ``Material.I0`` carries its convention.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from granstokes.lib.validate import finite, require

from .rheology import SHEAR_RATE_FACTOR, Friction, convert_I
from .steady import steady_wall_speed

UNITS = {
    "dem_units": "lengths in d, time in sqrt(d/g), velocity in sqrt(g d), stress in rho_p g d, mass in rho_p d^3",
    "tilde_variables": "y~ = y/delta_s, t~ = t nu_g/delta_s^2, u~ = u/U with U = g delta_s^2/(beta_w nu_g), "
                       "tau~ = tau/tau_w, p~ = p/p_w, mu~ = (mu_d - mu)/(mu_d - mu_s)",
    "inertial_number": "paper: I = (1/2)|du/dy| d/sqrt(p/rho_p); dem: I = |du/dy| d/sqrt(p/rho_p); I0_dem = 2 I0_paper",
}


@dataclass(frozen=True)
class Material:
    """Granular material: grain diameter d, grain density rho_p, solid fraction phi (constant,
    as in the paper), mu(I) parameters (mu_s, mu_d, I0) and gravity g.

    ``I0`` is given in ``I_convention`` ("paper" or "dem", see continuum.rheology).
    Defaults are the paper's glass beads (mu_s = tan 21 deg, mu_d = tan 33 deg) in DEM units.
    """

    mu_s: float = math.tan(math.radians(21.0))
    mu_d: float = math.tan(math.radians(33.0))
    I0: float = 0.279
    I_convention: str = "dem"
    phi: float = 0.6
    d: float = 1.0
    rho_p: float = 1.0
    g: float = 1.0

    def __post_init__(self):
        Friction(self.mu_s, self.mu_d)  # validates mu_s, mu_d
        for name in ("I0", "d", "rho_p", "g"):
            value = getattr(self, name)
            require(finite(value) and value > 0, name, "a finite number > 0", value)
        require(finite(self.phi) and 0 < self.phi < 1, "phi", "in the open interval (0, 1)", self.phi)
        require(self.I_convention in SHEAR_RATE_FACTOR, "I_convention", f"one of {sorted(SHEAR_RATE_FACTOR)}",
                self.I_convention)

    @property
    def friction(self) -> Friction:
        return Friction(self.mu_s, self.mu_d)

    @property
    def I0_paper(self) -> float:
        """I0 in the paper's convention (|gamma_dot| = 1/2 |du/dy|), the one its scales use."""
        return convert_I(self.I0, self.I_convention, "paper")

    @property
    def weight_gradient(self) -> float:
        """phi rho_p g: the bed's weight per unit volume, the hydrostatic pressure's gradient (eq. (2.6))."""
        return self.phi * self.rho_p * self.g


def pressure(material: Material, p_w: float, y):
    """Hydrostatic pressure p(y) = p_w + phi rho_p g y at the depth y below the plate (eq. (2.6))."""
    return p_w + material.weight_gradient * y


@dataclass(frozen=True)
class Scales:
    """The paper's scales for a material loaded at the wall with pressure p_w and (steady) wall
    friction mu_w; dimensional values in the material's units.

    nu_g: the paper prints it twice, as (d/(2 phi Dmu I0)) sqrt(p_w/rho) (eq. (2.14),
    Conclusion) and as (d/(phi Dmu I0)) sqrt(p_w/rho) (below eq. (3.8)).  Only the first one makes
    eq. (3.10) follow from eq. (2.12) with U = g delta_s^2/(beta_w nu_g):
    U = 2 I0 Dmu delta_s sqrt(p_w/rho)/d needs g delta_s^2/(beta_w nu_g) with the factor 2, because
    g delta_s phi/beta_w = p_w/rho.  It is also the coefficient of eq. (2.14), so
    t~ = nu_g t/delta_s^2 turns that equation into eq. (2.15).  We use the factor 2.
    """

    material: Material
    p_w: float
    mu_w: float

    def __post_init__(self):
        require(finite(self.p_w) and self.p_w > 0, "p_w", "a finite number > 0", self.p_w)
        self.material.friction.check_mu_w(self.mu_w)

    @classmethod
    def for_speed(cls, material: Material, p_w: float, u_w: float) -> Scales:
        """Scales of an imposed dimensional wall speed u_w: mu_w is the steady mu_w^inf, the root of
        U(mu_w) u~_w^inf(mu_w) = u_w (monotone in mu_w; paper section on imposed wall velocity)."""
        require(finite(u_w) and u_w > 0, "u_w", "a finite number > 0", u_w)
        fr = material.friction  # p_w is checked by the constructor, which the residual calls first

        def residual(mu_w):  # u~_w^inf(mu_w) - u_w/U(mu_w): increasing in mu_w, one root
            return steady_wall_speed(fr, mu_w) - u_w / cls(material, p_w, mu_w).U

        lo, hi = fr.mu_s * (1 + 1e-9), fr.mu_d - 1e-12 * fr.dmu
        require(residual(lo) < 0 < residual(hi), "u_w", "a speed reachable with mu_s < mu_w < mu_d", u_w)
        from scipy.optimize import brentq  # imported here: it would cost every CLI start-up ~0.3 s

        mu_w = brentq(residual, lo, hi, xtol=1e-15)  # and brentq's default rtol, 4 eps
        return cls(material, p_w, mu_w)

    # --- derived scales -------------------------------------------------------------------------
    @property
    def dmu(self) -> float:
        return self.material.mu_d - self.material.mu_s

    @property
    def beta_w(self) -> float:
        """beta_w = mu_w/mu_s - 1 (eq. (2.11))."""
        return self.mu_w / self.material.mu_s - 1.0

    @property
    def mu_w_tilde(self) -> float:
        return (self.material.mu_d - self.mu_w) / self.dmu

    @property
    def delta_s(self) -> float:
        """Steady layer thickness delta_s = beta_w p_w/(phi rho g) (eq. (2.11))."""
        m = self.material
        return self.beta_w * self.p_w / (m.phi * m.rho_p * m.g)

    @property
    def nu_g(self) -> float:
        """Granular diffusivity nu_g = (d/(2 phi Dmu I0)) sqrt(p_w/rho_p) (eq. (2.14)),
        I0 in the paper's convention."""
        m = self.material
        return m.d / (2 * m.phi * self.dmu * m.I0_paper) * math.sqrt(self.p_w / m.rho_p)

    @property
    def t_s(self) -> float:
        """Time scale delta_s^2/nu_g (t~ = 1)."""
        return self.delta_s**2 / self.nu_g

    @property
    def U(self) -> float:
        """Velocity scale U = g delta_s^2/(beta_w nu_g) (eq. (3.8))."""
        return self.material.g * self.delta_s**2 / (self.beta_w * self.nu_g)

    # --- conversions (dimensional <-> tilde) -----------------------------------------------------
    def y_tilde(self, y):
        return y / self.delta_s

    def y(self, y_tilde):
        return y_tilde * self.delta_s

    def t_tilde(self, t):
        return t / self.t_s

    def t(self, t_tilde):
        return t_tilde * self.t_s

    def u_tilde(self, u):
        return u / self.U

    def u(self, u_tilde):
        return u_tilde * self.U

    def p_tilde(self, p):
        return p / self.p_w

    def p(self, p_tilde):
        return p_tilde * self.p_w

    def tau_tilde(self, tau):
        return tau / (self.mu_w * self.p_w)

    def tau(self, tau_tilde):
        return tau_tilde * self.mu_w * self.p_w

    def pressure(self, y):
        """Hydrostatic pressure p(y) at this load's p_w (eq. (2.6))."""
        return pressure(self.material, self.p_w, y)

    def as_dict(self) -> dict:
        return {"p_w": self.p_w, "mu_w": self.mu_w, "mu_w_tilde": self.mu_w_tilde, "beta_w": self.beta_w,
                "delta_s": self.delta_s, "nu_g": self.nu_g, "t_s": self.t_s, "U": self.U,
                "I0_paper": self.material.I0_paper, "units": UNITS}
