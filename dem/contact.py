"""Contact law: stiffness from the rigidity number kappa, contact time t_c and the time step bound.

DEM units (d = rho_p = g = 1).  Grain diameters are uniform by number in [1 - w, 1 + w].

* Hooke (``pair_coeff * * hooke k_n e ... damping coeff_restitution``): F_n = k_n delta + damping,
  k_n = kappa p_w d, so the overlap under a typical contact force p_w d is d/kappa.
* Hertz (``hertz k_n e``): F_n = k_n a delta with contact radius a = sqrt(R_eff delta); equivalent to
  Hooke when the same force p_w d gives the same overlap d/kappa for two mean grains (R_eff = d/4):
  k_n = 2 kappa^(3/2) p_w.  Its time step uses the tangent stiffness at 10 d/kappa (impacts).
* Damping ``coeff_restitution`` sets the normal restitution e for every pair whatever the masses,
  damping ratio zeta = -ln e / sqrt(pi^2 + ln^2 e); t_c = pi / (omega_0 sqrt(1 - zeta^2)),
  omega_0 = sqrt(k/m_eff), m_eff = m_min/2 for the two lightest grains (shortest contact).
* ``pair_style = "classic"`` (Hooke only, the Hooke default): LAMMPS's ``gran/hooke/history``, 1.5-1.7x faster
  per step than ``granular``, with the damping force m_eff gamma_n v_n, gamma_n = 2 zeta sqrt(k_n/m_eff) for the
  mean pair (m_eff half the mean grain mass): the set restitution holds for that pair only (0.43-0.56 over 2D
  pairs at w = 0.2, e = 0.5); tangential damping gamma_n/2, as linear_history's 0.5.  Pairs with their own
  friction (the plate's) get their own sub-style of ``pair_style hybrid``.
* The time step bound is t_c/20; the default time step is that bound.
* Shear waves: the deposited bed is an elastic solid; a shear load crosses it at about the speed of
  transverse waves on a chain of mean grains coupled by the tangential spring, c_s = d sqrt(k_t/m)
  (an upper estimate: disorder and sliding contacts soften the packing).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

DT_FRACTION = 20.0  # dt <= t_c / DT_FRACTION
HERTZ_OVERLAP_FACTOR = 10.0  # Hertz t_c evaluated at an overlap of this many d/kappa


def grain_mass(diameter: float, dimension: int, rho_p: float = 1.0) -> float:
    """Mass of a disk (2D, per unit thickness: rho_p pi r^2, LAMMPS ``density/disc``) or a sphere."""
    r = diameter / 2
    return rho_p * (math.pi * r**2 if dimension == 2 else 4 / 3 * math.pi * r**3)


def grain_volume(diameter: float, dimension: int) -> float:
    return grain_mass(diameter, dimension, 1.0)


def mean_grain_volume(polydispersity: float, dimension: int) -> float:
    """<V> over diameters uniform by number in [1-w, 1+w] (the mean grain mass at rho_p = 1)."""
    w, dim = polydispersity, dimension
    moment = ((1 + w) ** (dim + 1) - (1 - w) ** (dim + 1)) / ((dim + 1) * 2 * w) if w > 0 else 1.0  # <d^D>
    return moment * grain_volume(1.0, dim)


def rigidity(kappa: float, model: str, p_from: float, p_to: float) -> float:
    """kappa at p_to of grains whose kappa is ``kappa`` at p_from: one stiffness k_n (``Contact.k_n``: Hooke
    k_n = kappa p, Hertz k_n = 2 kappa^1.5 p)."""
    ratio = p_from / p_to
    return kappa * (ratio if model == "hooke" else ratio ** (2 / 3))


@dataclass(frozen=True)
class Contact:
    """Stiffness, damping and time step of a scene; ``as_dict`` is written into run.json."""

    model: str
    dimension: int
    p_w: float
    kappa: float
    restitution: float
    mu_p: float
    kt_over_kn: float
    polydispersity: float
    pair_style: str

    @property
    def k_n(self) -> float:
        if self.model == "hooke":
            return self.kappa * self.p_w
        return 2.0 * self.kappa**1.5 * self.p_w

    @property
    def k_t(self) -> float:
        return self.kt_over_kn * self.k_n

    @property
    def k_linear(self) -> float:
        """Stiffness that sets the contact time: k_n (Hooke) or the Hertz tangent stiffness."""
        if self.model == "hooke":
            return self.k_n
        delta = HERTZ_OVERLAP_FACTOR / self.kappa
        return 1.5 * self.k_n * math.sqrt(0.25 * delta)

    @property
    def zeta(self) -> float:
        log_e = math.log(self.restitution)
        return -log_e / math.sqrt(math.pi**2 + log_e**2)

    @property
    def m_eff_min(self) -> float:
        return grain_mass(1.0 - self.polydispersity, self.dimension) / 2

    @property
    def t_c(self) -> float:
        omega0 = math.sqrt(self.k_linear / self.m_eff_min)
        return math.pi / (omega0 * math.sqrt(1.0 - self.zeta**2))

    @property
    def shear_wave_speed(self) -> float:
        """c_s = d sqrt(k_t/m), m the mass of a mean grain (d = 1)."""
        return math.sqrt(self.k_t / grain_mass(1.0, self.dimension))

    @property
    def dt_max(self) -> float:
        return self.t_c / DT_FRACTION

    def pair_coeff(self, mu_p: float | None = None) -> str:
        """The contact law in LAMMPS ``pair_coeff`` / ``fix wall/gran`` syntax (friction ``mu_p`` if given)."""
        mu = self.mu_p if mu_p is None else mu_p
        return (f"{self.model} {self.k_n:.10g} {self.restitution:.10g} "
                f"tangential linear_history {self.k_t:.10g} 0.5 {mu:.10g} damping coeff_restitution")

    @property
    def gamma_n(self) -> float:
        """The classic style's normal damping rate giving the restitution for the mean pair."""
        m_eff = mean_grain_volume(self.polydispersity, self.dimension) / 2  # rho_p = 1
        return 2 * self.zeta * math.sqrt(self.k_n / m_eff)

    def classic_coeff(self, mu_p: float | None = None) -> str:
        """The classic ``gran/hooke/history`` arguments (k_n k_t gamma_n gamma_t mu dampflag)."""
        mu = self.mu_p if mu_p is None else mu_p
        return (f"hooke/history {self.k_n:.10g} {self.k_t:.10g} {self.gamma_n:.10g} {self.gamma_n / 2:.10g} "
                f"{mu:.10g} 1")

    def pair_lines(self, special: tuple = ()) -> str:
        """``pair_style`` and ``pair_coeff`` lines: one law for every pair, ``special`` = ((i, j, mu_p), ...) pairs of
        atom types with their own friction."""
        if self.pair_style == "granular":
            return "\n".join(["pair_style granular", f"pair_coeff * * {self.pair_coeff()}",
                               *(f"pair_coeff {i} {j} {self.pair_coeff(mu)}" for i, j, mu in special)])
        if not special:
            return f"pair_style gran/{self.classic_coeff()}\npair_coeff * *"
        styles = " ".join(f"gran/{self.classic_coeff(mu)}" for mu in (self.mu_p, *(m for _, _, m in special)))
        return "\n".join([f"pair_style hybrid {styles}", "pair_coeff * * gran/hooke/history 1",
                           *(f"pair_coeff {i} {j} gran/hooke/history {k + 2}" for k, (i, j, _) in enumerate(special))])

    def restart_lines(self, special: tuple = ()) -> str:
        """The lines that follow ``read_restart``: ``pair granular`` is re-declared (it recomputes its cutoffs, its
        contact history comes back), the classic style only gets its ``pair_coeff`` lines (re-declaring
        ``gran/hooke/history`` drops the tangential history: every contact would restart unloaded)."""
        lines = self.pair_lines(special)
        return lines if self.pair_style == "granular" else lines.split("\n", 1)[1]

    def wall(self) -> str:
        """The law's ``fix wall/gran`` arguments."""
        return f"granular {self.pair_coeff()}" if self.pair_style == "granular" else self.classic_coeff()

    def as_dict(self) -> dict:
        return {
            "pair_style": self.pair_style, "pair_lines": self.pair_lines(),
            "model": (f"pair_style granular {self.model}, tangential linear_history, damping coeff_restitution"
                      if self.pair_style == "granular" else
                      f"pair_style gran/hooke/history, gamma_n = {self.gamma_n:.6g} (restitution e for the mean pair), "
                      "gamma_t = gamma_n/2"),
            "pair_coeff": self.pair_coeff(),
            "kappa": self.kappa, "k_n": self.k_n, "k_t": self.k_t, "mu_p": self.mu_p,
            "restitution": self.restitution, "damping_ratio": self.zeta,
            "t_c": self.t_c, "dt_max": self.dt_max,
            "derivation": (
                "kappa = k_n/(p_w d) (Hooke) or Hertz k_n = 2 kappa^1.5 p_w (same overlap d/kappa under a force "
                "p_w d between mean grains); t_c = pi/(omega_0 sqrt(1-zeta^2)), omega_0 = sqrt(k/m_eff), "
                "m_eff = half the lightest grain mass, zeta = -ln e/sqrt(pi^2+ln^2 e), k = k_n (Hooke) or the "
                f"Hertz tangent stiffness at overlap {HERTZ_OVERLAP_FACTOR:g} d/kappa; dt_max = t_c/{DT_FRACTION:g}"),
        }
