"""The continuum models a DEM drive is predicted with, registered by key, in DEM units.

Each model takes the material (mu_s, mu_d, I0, phi: from a calibration, never from the drive it
predicts) and the drive's own scene (p_w, bed depth H, plate mass, what is imposed):

* ``local``: local mu(I) on the DEM's scene: the velocity form (continuum.velocity: bed at rest,
  no-slip base, plate with its mass, eps-regularised, continuum.rules.YieldRule.for_layer) for the
  transient, the exact steady state of the same scene (continuum.scene) for the steady values;
* ``paper``: the paper's stress-diffusion model (continuum.solver: semi-infinite bed, initial state
  tau = mu_s p), scaled with continuum.scales.Scales; its steady state is the exact one of the
  semi-infinite bed;
* ``ngf``: nonlocal granular fluidity (continuum.ngf) with amplitude A, Neumann walls, t0 = one
  local inertial time; transient from a bed at rest, steady state by Chebyshev collocation.

``Prediction``: the time series (t, u_w, mu_w, delta_u), the profiles (t, depth, u, mu) and the
steady state (u_w, mu_w, delta_s, and the steady depth profile y, u) of one model for one drive.
The layer thickness compared with the DEM is delta_u, the depth where u falls to U_FRACTION of u_w
(the paper's threshold on mu - mu_s is far below the DEM's noise); both sides use it.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from granstokes.continuum import ngf
from granstokes.continuum.crossing import depth_at_fraction
from granstokes.continuum.load import Load
from granstokes.continuum.rules import YieldRule
from granstokes.continuum.scales import Material
from granstokes.continuum.scene import scene_steady
from granstokes.continuum.solver import solve_speed, solve_stress
from granstokes.continuum.steady import steady_velocity
from granstokes.continuum.velocity import VELOCITY_NUMERICS, BedScene, solve_velocity


@dataclass(frozen=True)
class Drive:
    """What a model needs of a DEM drive: what the plate imposes (continuum.load.Load) and the scene."""

    load: Load
    depth: float
    plate_mass: float

    def scene(self, material: Material) -> BedScene:
        return BedScene(material, self.load.p_w, self.depth, plate_mass=self.plate_mass)


@dataclass(frozen=True, eq=False)
class Steady:
    """A model's steady state of a drive: depth profile and the plate's values."""

    y: np.ndarray
    u: np.ndarray
    u_w: float
    mu_w: float
    delta_s: float
    g: np.ndarray | None = None  # the fluidity gamma_dot/mu at y [1/sqrt(d/g)] (NGF)

    @property
    def delta_u(self) -> float:
        return depth_at_fraction(self.y, self.u, self.u_w)


@dataclass(frozen=True, eq=False)
class Prediction:
    model: str                # registry key
    label: str
    series: pd.DataFrame      # t, u_w, mu_w, delta_u
    profiles: pd.DataFrame    # t, depth, u, mu
    steady: Steady
    transient_calibrated: bool = True  # False: the model's time scale was assumed, not measured (SceneModel)


def _series(t, depth, u, mu_w) -> pd.DataFrame:
    d = [depth_at_fraction(depth, ui, ui[0]) for ui in u]
    return pd.DataFrame({"t": t, "u_w": u[:, 0], "mu_w": mu_w, "delta_u": d})


def _profiles(times, y, u, mu) -> pd.DataFrame:
    return pd.DataFrame({"t": np.repeat(times, len(y)), "depth": np.tile(y, len(times)), "u": u.ravel(),
                         "mu": np.asarray(mu).ravel()})


# --- local mu(I) on the DEM's scene ------------------------------------------------------------------

def _local_steady(material: Material, drive: Drive) -> Steady:
    st = scene_steady(drive.scene(material), **drive.load.imposed)
    return Steady(st.y, st.u, st.u_w, st.mu_w, st.delta_s)


def _local_transient(material: Material, drive: Drive, times) -> tuple[pd.DataFrame, pd.DataFrame]:
    vel = solve_velocity(drive.scene(material), times, rule=YieldRule.for_layer(drive.load.scales(material)),
                         initial="rest", numerics=VELOCITY_NUMERICS, compare_steady=False, **drive.load.imposed)
    mu = np.array([np.interp(vel.y, vel.y_face, m) for m in vel.mu])
    return _series(times, vel.y, vel.u, vel.mu_w), _profiles(times, vel.y, vel.u, mu)


# --- the paper's stress-diffusion model --------------------------------------------------------------

def _paper_steady(material: Material, drive: Drive) -> Steady:
    sc, fr = drive.load.scales(material), material.friction
    y = np.linspace(0.0, sc.delta_s, 201)
    u = sc.U * steady_velocity(fr, sc.mu_w, y / sc.delta_s)
    return Steady(y, u, float(u[0]), sc.mu_w, sc.delta_s)


def _paper_transient(material: Material, drive: Drive, times) -> tuple[pd.DataFrame, pd.DataFrame]:
    sc, fr = drive.load.scales(material), material.friction
    t_tilde = sc.t_tilde(times)
    sol = (solve_stress(fr, sc.mu_w, t_tilde) if drive.load.kind == "stress"
           else solve_speed(fr, sc.u_tilde(drive.load.u_w), t_tilde))
    y, u = sc.y(sol.mesh.y), sc.u(sol.velocity)
    return _series(times, y, u, sol.mu_w), _profiles(times, y, u, sol.mu)


# --- nonlocal granular fluidity --------------------------------------------------------------------

#: Chebyshev intervals per piece of the comparison's NGF steady states: below 1e-10 u_w at A >= 0.1 already
#: (tests/continuum/test_ngf.py), and the replicates' root-finding for imposed speeds costs O(n^3) per try;
#: mu_w of an imposed speed to NGF_STEADY_RTOL (the DEM's errors are percent-level), no error estimate
NGF_STEADY_N, NGF_STEADY_RTOL = 32, 1e-9


def _ngf_steady(fluidity: ngf.NonlocalFluidity, material: Material, drive: Drive) -> Steady:
    st = ngf.solve_steady(drive.scene(material), fluidity, n=NGF_STEADY_N, rtol=NGF_STEADY_RTOL,
                          error_estimate=False, **drive.load.imposed)
    return Steady(st.y, st.u, st.u_w, st.mu_w, st.delta_s, st.g)


#: the NGF transient of the comparison: u_w within 1e-4 relative of 160 cells at rtol 1e-6 (measured on the
#: smoke scene, A = 0.02 and 0.5) at a quarter of the cost (a small A makes the fluidity equation stiff)
NGF_NUMERICS = ngf.TransientNumerics(n_cells=80, rtol=1e-4)


def _ngf_transient(fluidity: ngf.NonlocalFluidity, material: Material, drive: Drive,
                   times) -> tuple[pd.DataFrame, pd.DataFrame]:
    tr = ngf.solve_transient(drive.scene(material), fluidity, times, numerics=NGF_NUMERICS, error_estimate=False,
                             **drive.load.imposed)
    mu = np.array([np.interp(tr.y, tr.y_cell, m) for m in tr.mu])
    return _series(times, tr.y, tr.u, tr.mu_w), _profiles(times, tr.y, tr.u, mu)


@dataclass(frozen=True)
class SceneModel:
    """A registered model: ``steady(material, drive)`` and ``transient(material, drive, times)``;
    ``parameter``: the name of its own fitted parameter (beyond the material), and ``factory`` builds
    the model at another value of it (uncertainty propagation); ``half_space``: the model's bed has no base;
    ``transient_calibrated``: False when the model's own time scale is assumed rather than calibrated (its
    transient is then not a prediction)."""

    key: str
    label: str
    steady: Callable
    transient: Callable
    parameters: dict = field(default_factory=dict)
    parameter: str | None = None
    factory: Callable | None = None
    half_space: bool = False
    transient_calibrated: bool = True

    def at(self, values) -> SceneModel:
        """This model with its own parameter taken from ``values`` (a mapping), if it has one."""
        return self.factory(float(values[self.parameter])) if self.parameter else self

    def predict(self, material: Material, drive: Drive, times) -> Prediction:
        times = np.asarray(times, dtype=float)
        series, profiles = self.transient(material, drive, times)
        return Prediction(self.key, self.label, series, profiles, self.steady(material, drive),
                          self.transient_calibrated)


LOCAL = SceneModel("local", "local mu(I), velocity form on the DEM scene", _local_steady, _local_transient)
PAPER = SceneModel("paper", "paper's model (stress diffusion, tau = mu_s p at t = 0)", _paper_steady, _paper_transient,
                   half_space=True)


def ngf_model(A: float) -> SceneModel:
    """NGF with amplitude A (the model's one parameter; calibrated on one drive's creep profile); its fluidity's
    relaxation time t0 is one local inertial time, assumed and not calibrated, so its transient is not scored."""
    fl = ngf.NonlocalFluidity(A=A)
    return SceneModel("ngf", f"nonlocal fluidity (NGF), A = {A:.3g}",
                      lambda m, d: _ngf_steady(fl, m, d), lambda m, d, t: _ngf_transient(fl, m, d, t),
                      {"A": A, "boundary": fl.boundary, "t0_hat": fl.t0_hat}, "A", ngf_model,
                      transient_calibrated=False)
