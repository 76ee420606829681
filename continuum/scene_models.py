"""The continuum models a DEM drive is predicted with, each written once, in DEM units: ``granstokes predict``
(continuum.predict_cli) and compare/ both take them from here.

A model predicts from the material (mu_s, mu_d, I0, phi: from a calibration, never from the drive it predicts), the
drive's scene (continuum.scene.BedScene: bed depth H, plate mass), its held load (continuum.load.Load: p_w and what is
imposed) and the output times:

* ``LOCAL``: local mu(I) on the DEM's scene: the velocity form (continuum.velocity: bed at rest, no-slip base, plate
  with its mass, eps-regularised, continuum.rules.YieldRule.for_layer) for the transient, the exact steady state of
  the same scene for the steady values (``local_steady``);
* ``PAPER``: the paper's stress-diffusion model (continuum.solver: semi-infinite bed, initial state tau = mu_s p,
  eq. (2.7)), scaled with continuum.scales.Scales; its steady state is the exact one of the semi-infinite bed
  (eq. (2.10));
* ``ngf_model(A)``: nonlocal granular fluidity (continuum.ngf) with amplitude A, Neumann walls, t0 = one local
  inertial time; transient from a bed at rest, steady state by Chebyshev collocation;
* ``elastic_model(G)``: elasto-plastic mu(I) (continuum.elastic) with the bed's shear modulus G: the transient from
  a stress-free bed at rest, the load carried down by an elastic wave; its steady state is local mu(I)'s.

``Steady``: a model's steady state (u_w, mu_w, delta_s, the depth profile y, u; NGF's fluidity g).  ``Transient``: its
transient at the output times (u at the depths y, mu_w, mu; NGF's g), ``SceneModel.estimated`` with Richardson's
error estimates of u_w, mu_w and delta_u.  ``Prediction``: the time series (t, u_w, mu_w, delta_u), the profiles (t,
depth, u, mu) and the steady state of one model for one drive.  The layer thickness compared with the DEM is delta_u,
the depth where u falls to U_FRACTION of u_w (the paper's threshold on mu - mu_s is far below the DEM's noise); both
sides use it.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cached_property, partial

import numpy as np
import pandas as pd
from scipy.optimize import brentq

from granstokes.lib.validate import require

from . import ngf
from .crossing import depth_at_fraction
from .elastic import ELASTIC_NUMERICS, solve_elastic
from .load import Load
from .richardson import REFINEMENT, richardson
from .rules import YieldRule
from .scales import Material, Scales
from .scene import BedScene, SceneNumerics
from .solver import Numerics, solve_speed, solve_stress
from .steady import steady_velocity
from .velocity import VELOCITY_NUMERICS, solve_velocity

#: profile points of a steady velocity (plus delta_s when it lies inside the bed)
PROFILE_POINTS = 201
#: bracket of the local steady mu_w for an imposed speed, as fractions of mu_s above mu_s and of Dmu below mu_d
_BRACKET = 1e-12


@dataclass(frozen=True, eq=False)
class Steady:
    """A model's steady state of a drive: depth profile and the plate's values, with their error estimates (0: exact
    up to rounding, or not estimated)."""

    y: np.ndarray
    u: np.ndarray
    u_w: float
    mu_w: float
    delta_s: float
    g: np.ndarray | None = None  # the fluidity gamma_dot/mu at y [1/sqrt(d/g)] (NGF)
    u_w_err: float = 0.0
    mu_w_err: float = 0.0

    @property
    def delta_u(self) -> float:
        return depth_at_fraction(self.y, self.u, self.u_w)


@dataclass(frozen=True, eq=False)
class Transient:
    """A model's transient at the times t: u at the depths y (one row per time), the plate's friction mu_w, mu at y,
    NGF's fluidity g at y (else None) and, if estimated (``SceneModel.estimated``), the errors of u_w, mu_w and
    delta_u (u_w_err, mu_w_err, delta_u_err: one per time)."""

    t: np.ndarray
    y: np.ndarray
    u: np.ndarray
    mu_w: np.ndarray
    mu: np.ndarray
    g: np.ndarray | None = None
    errors: dict = field(default_factory=dict)

    @property
    def u_w(self) -> np.ndarray:
        return self.u[:, 0]

    @cached_property
    def delta_u(self) -> np.ndarray:
        """delta_u at each time: the depth where u falls to U_FRACTION of u_w (continuum.crossing)."""
        return np.array([depth_at_fraction(self.y, uk, uk[0]) for uk in self.u])

    def series(self) -> pd.DataFrame:
        return pd.DataFrame({"t": self.t, "u_w": self.u_w, "mu_w": self.mu_w, "delta_u": self.delta_u})

    def profiles(self) -> pd.DataFrame:
        return pd.DataFrame({"t": np.repeat(self.t, len(self.y)), "depth": np.tile(self.y, len(self.t)),
                             "u": self.u.ravel(), "mu": np.asarray(self.mu).ravel()})


@dataclass(frozen=True, eq=False)
class Prediction:
    model: str                # registry key
    label: str
    series: pd.DataFrame      # t, u_w, mu_w, delta_u
    profiles: pd.DataFrame    # t, depth, u, mu
    steady: Steady
    transient_calibrated: bool = True  # False: the model's time scale was assumed, not measured (SceneModel)
    initial: str = ""                  # the state its transient starts from (SceneModel.initial)


# --- local mu(I) on the DEM's scene ------------------------------------------------------------------

def local_steady(material: Material, scene: BedScene, load: Load, estimate: bool = False) -> Steady:
    """The paper's exact steady state (continuum.steady, eq. (2.10)) scaled with continuum.scales on the scene:
    u(y) = U [u~(y/delta_s) - u~(H/delta_s)] on a bed of depth H with a no-slip base (the layer is cut at the base
    when H < delta_s: the velocity there is then zero, not U u~(H/delta_s)).  For an imposed speed mu_w is the root
    of u(0) = u_w.  Exact up to rounding (``estimate`` changes nothing)."""
    fr, p_w = material.friction, load.p_w

    def profile(mw, y):
        sc = Scales(material, p_w, mw)
        return sc.U * (steady_velocity(fr, mw, y / sc.delta_s) - steady_velocity(fr, mw, scene.depth / sc.delta_s))

    mu_w = load.mu_w
    if load.kind == "speed":
        lo, hi = fr.mu_s * (1 + _BRACKET), fr.mu_d - _BRACKET * fr.dmu
        f = lambda mw: float(profile(mw, 0.0)) - load.u_w  # noqa: E731
        require(f(hi) > 0, "u_w", f"a speed reachable with mu_w < mu_d = {fr.mu_d:.6g}", load.u_w)
        mu_w = brentq(f, lo, hi, xtol=1e-15, rtol=1e-15)
    sc = Scales(material, p_w, mu_w)
    y = np.linspace(0.0, scene.depth, PROFILE_POINTS)
    y = np.unique(np.append(y, sc.delta_s if sc.delta_s < scene.depth else []))
    u = profile(mu_w, y)
    return Steady(y, u, float(u[0]), float(mu_w), float(sc.delta_s))


def _local_transient(material: Material, scene: BedScene, load: Load, times, numerics: SceneNumerics) -> Transient:
    vel = solve_velocity(material, scene, load, times, rule=YieldRule.for_layer(load.scales(material)),
                         initial="rest", numerics=numerics, compare_steady=False)
    mu = np.array([np.interp(vel.y, vel.y_face, m) for m in vel.mu])
    return Transient(times, vel.y, vel.u, vel.mu_w, mu)


# --- the paper's stress-diffusion model --------------------------------------------------------------

def _paper_steady(material: Material, scene: BedScene, load: Load, estimate: bool = False) -> Steady:
    sc, fr = load.scales(material), material.friction
    y = np.linspace(0.0, sc.delta_s, PROFILE_POINTS)
    u = sc.U * steady_velocity(fr, sc.mu_w, y / sc.delta_s)
    return Steady(y, u, float(u[0]), sc.mu_w, sc.delta_s)


def _paper_transient(material: Material, scene: BedScene, load: Load, times, numerics: Numerics | None) -> Transient:
    sc, fr = load.scales(material), material.friction
    t_tilde = sc.t_tilde(times)
    sol = (solve_stress(fr, sc.mu_w, t_tilde, numerics) if load.kind == "stress"
           else solve_speed(fr, sc.u_tilde(load.u_w), t_tilde, numerics))
    return Transient(times, sc.y(sol.mesh.y), sc.u(sol.velocity), sol.mu_w, sol.mu)


# --- nonlocal granular fluidity --------------------------------------------------------------------

#: Chebyshev intervals per piece of the comparison's NGF steady states: below 1e-10 u_w at A >= 0.1 already
#: (tests/continuum/test_ngf.py), and the replicates' root-finding for imposed speeds costs O(n^3) per try;
#: mu_w of an imposed speed to NGF_STEADY_RTOL (the DEM's errors are percent-level), no error estimate
NGF_STEADY_N, NGF_STEADY_RTOL = 32, 1e-9


def _ngf_steady(fluidity: ngf.NonlocalFluidity, material: Material, scene: BedScene, load: Load,
                estimate: bool = False) -> Steady:
    """``estimate``: the solver's own accuracy with its error estimates (ngf.solve_steady's defaults), else the
    comparison's cheaper NGF_STEADY_N, NGF_STEADY_RTOL without."""
    cheap = {} if estimate else {"n": NGF_STEADY_N, "rtol": NGF_STEADY_RTOL, "error_estimate": False}
    st = ngf.solve_steady(material, scene, load, fluidity=fluidity, **cheap)
    return Steady(st.y, st.u, st.u_w, st.mu_w, st.delta_s, st.g, st.u_w_err, st.mu_w_err)


#: the NGF transient of the comparison: u_w within 1e-4 relative of 160 cells at rtol 1e-6 (measured on the
#: smoke scene, A = 0.02 and 0.5) at a quarter of the cost (a small A makes the fluidity equation stiff)
NGF_NUMERICS = SceneNumerics(n_cells=80, rtol=1e-4)


def _ngf_transient(fluidity: ngf.NonlocalFluidity, material: Material, scene: BedScene, load: Load, times,
                   numerics: SceneNumerics) -> Transient:
    """u, mu (interpolated from the cell centres) and g (ln g interpolated linearly) at the nodes."""
    tr = ngf.solve_transient(material, scene, load, times, fluidity=fluidity, numerics=numerics, error_estimate=False)
    mu = np.array([np.interp(tr.y, tr.y_cell, m) for m in tr.mu])
    g = np.array([np.exp(np.interp(tr.y, tr.y_cell, np.log(np.maximum(gk, np.finfo(float).tiny)))) for gk in tr.g])
    return Transient(times, tr.y, tr.u, tr.mu_w, mu, g)


@dataclass(frozen=True)
class SceneModel:
    """A registered model: ``steady(material, scene, load, estimate)`` -> Steady and ``transient(material, scene,
    load, times, numerics)`` -> Transient at its ``numerics`` (the comparison's); ``parameter``: the name of its own
    fitted parameter (beyond the material), and ``factory`` builds the model at another value of it (uncertainty
    propagation); ``half_space``: the model's bed has no base; ``transient_calibrated``: False when the model's own
    time scale is assumed rather than calibrated (its transient is then not a prediction); ``initial``: the state its
    transient starts from, in words (none starts from a DEM bed's measured stresses)."""

    key: str
    label: str
    steady: Callable
    transient: Callable
    numerics: SceneNumerics | Numerics | None = None
    parameters: dict = field(default_factory=dict)
    parameter: str | None = None
    factory: Callable | None = None
    half_space: bool = False
    transient_calibrated: bool = True
    initial: str = ""

    def at(self, values) -> SceneModel:
        """This model with its own parameter taken from ``values`` (a mapping), if it has one."""
        return self.factory(float(values[self.parameter])) if self.parameter else self

    def predict(self, material: Material, scene: BedScene, load: Load, times) -> Prediction:
        times = np.asarray(times, dtype=float)
        tr = self.transient(material, scene, load, times, self.numerics)
        return Prediction(self.key, self.label, tr.series(), tr.profiles(), self.steady(material, scene, load),
                          self.transient_calibrated, self.initial)

    def estimated(self, material: Material, scene: BedScene, load: Load, times, numerics=None) -> Transient:
        """The transient at ``numerics`` (default: the model's) with the errors of u_w, mu_w and delta_u from a
        companion on 1/REFINEMENT of the cells (continuum.richardson, second order in space)."""
        numerics = numerics or self.numerics
        fine, coarse = (self.transient(material, scene, load, times, n)
                        for n in (numerics, replace(numerics, n_cells=numerics.n_cells // REFINEMENT)))
        errors = {"u_w_err": richardson(fine.u_w, coarse.u_w), "mu_w_err": richardson(fine.mu_w, coarse.mu_w),
                  "delta_u_err": richardson(fine.delta_u, coarse.delta_u)}
        return replace(fine, errors=errors)


LOCAL = SceneModel("local", "local mu(I), velocity form on the DEM scene", local_steady, _local_transient,
                   VELOCITY_NUMERICS, initial="a bed at rest, rigid below yield: the load reaches every depth at once")
PAPER = SceneModel("paper", "paper's model (stress diffusion, tau = mu_s p at t = 0)", _paper_steady, _paper_transient,
                   half_space=True, initial="tau = mu_s p at every depth, eq. (2.7)")


def ngf_model(A: float, boundary: str = "neumann", t0_hat: float = 1.0) -> SceneModel:
    """NGF with amplitude A (the model's one parameter; calibrated on one drive's creep profile); its fluidity's
    relaxation time t0 is ``t0_hat`` local inertial times, assumed and not calibrated, so its transient is not
    scored."""
    fl = ngf.NonlocalFluidity(A=A, boundary=boundary, t0_hat=t0_hat)
    return SceneModel("ngf", f"nonlocal fluidity (NGF), A = {A:.3g}", partial(_ngf_steady, fl),
                      partial(_ngf_transient, fl), NGF_NUMERICS,
                      {"A": A, "boundary": fl.boundary, "t0_hat": fl.t0_hat}, "A",
                      partial(ngf_model, boundary=boundary, t0_hat=t0_hat), transient_calibrated=False,
                      initial="a bed at rest with its resting fluidity")


# --- elasto-plastic mu(I) on the DEM's scene ------------------------------------------------------------

def _elastic_transient(G: float, material: Material, scene: BedScene, load: Load, times,
                       numerics: SceneNumerics) -> Transient:
    sol = solve_elastic(material, scene, load, times, G, numerics=numerics)
    mu = np.array([np.interp(sol.y, sol.y_face, m) for m in sol.mu])
    return Transient(np.asarray(times, dtype=float), sol.y, sol.u, sol.mu_w, mu)


def elastic_model(G: float) -> SceneModel:
    """Elasto-plastic mu(I) with the bed's shear modulus G (rho_p g d; the model's one parameter, measured on the
    calibration's packing, never on a drive); its steady state is local mu(I)'s (``local_steady``)."""
    return SceneModel("elastic", f"elasto-plastic mu(I), G = {G:.3g}", local_steady, partial(_elastic_transient, G),
                      ELASTIC_NUMERICS, {"G": G}, "G", elastic_model,
                      initial="a stress-free bed at rest: the load travels down as an elastic wave")
