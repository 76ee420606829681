"""The DEM's own scene as the continuum models see it, apart from the material (continuum.scales.Material) and the
load (continuum.load.Load, which holds the plate pressure p_w): a bed of depth H on a no-slip base under a plate of
mass m_p per unit area; and the numerics of the finite-volume solvers on it (the velocity form, continuum.velocity;
NGF's transient, continuum.ngf; the oscillating plate, continuum.oscillation).  A solver on the scene takes
(material, scene, load, times) and these numerics.
"""
from __future__ import annotations

from dataclasses import dataclass

from granstokes.lib.validate import finite, require

from .integrators import METHODS
from .mesh import Mesh


@dataclass(frozen=True)
class BedScene:
    """A bed of depth H under a plate of mass m_p per unit area; ``body_force`` is a uniform horizontal force per
    unit volume (0 for the DEM's horizontal bed).

    The paper's initial state tau = mu_s p is a static equilibrium only with
    body_force = mu_s phi rho_p g (a bed tilted to tan(theta) = mu_s): a horizontal bed cannot hold a
    shear stress that grows with depth.  The stress-diffusion equation does not see this (it only
    involves d(du/dy)/dt, blind to a uniform acceleration), so to compare with it from that state
    the velocity form needs that body force (tests, report)."""

    depth: float
    plate_mass: float = 0.0
    body_force: float = 0.0

    def __post_init__(self):
        require(finite(self.depth) and self.depth > 0, "depth", "a finite number > 0", self.depth)
        require(finite(self.plate_mass) and self.plate_mass >= 0, "plate_mass",
                "a finite number >= 0 (mass per unit plate area)", self.plate_mass)
        require(finite(self.body_force), "body_force", "a finite number", self.body_force)


@dataclass(frozen=True)
class SceneNumerics:
    """A scene solver's numerics: the cells of a graded mesh on [0, H] (finest at the plate, largest/smallest cell
    ~ e^stretch), the registered time integrator (continuum.integrators: a DIRK, or a solve_ivp baseline) and its
    tolerances (``atol`` on velocities); NGF's also ``atol_lng`` on ln g and ``g_rest``, the fluidity of its bed at
    rest (1/time, the material's units; g > 0 is needed for tau = p gamma_dot/g)."""

    n_cells: int = 160
    stretch: float = 2.0
    rtol: float = 1e-6
    atol: float = 1e-9
    method: str = "solve_ivp-Radau"
    atol_lng: float = 1e-6
    g_rest: float = 1e-8

    def __post_init__(self):
        Mesh.graded(self.n_cells, self.stretch)
        require(self.method in METHODS, "method", f"one of {list(METHODS)}", self.method)
        for name in ("rtol", "atol", "atol_lng", "g_rest"):
            v = getattr(self, name)
            require(finite(v) and v > 0, name, "a finite number > 0", v)

    def mesh(self) -> Mesh:
        """The graded mesh on [0, 1] (a solver scales it to the bed's depth)."""
        return Mesh.graded(self.n_cells, self.stretch)
