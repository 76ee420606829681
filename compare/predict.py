"""Continuum predictions of a DEM drive, in DEM units, from the calibrated material only.

Two models, both with no parameter beyond the calibration (mu_s, mu_d, I0) and the run's own
p_w, phi, bed depth H and plate mass:

* ``velocity form``: continuum.velocity on the DEM's scene (bed of depth H at rest, sigma_xy = 0,
  no-slip base, plate with its mass, eps-regularised mu(I), continuum.rules.YieldRule.for_layer);
* ``paper``: the stress-diffusion model (continuum.solver, semi-infinite bed truncated at delta_s,
  initial state tau = mu_s p), scaled with continuum.scales.Scales.

The layer thickness compared with the DEM is delta_u: the depth where u falls to U_FRACTION of u_w
(the paper's threshold on mu - mu_s is far below the DEM's noise); both sides use it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from continuum.crossing import crossing_depth
from continuum.rules import YieldRule
from continuum.scales import Material, Scales
from continuum.solver import solve_speed, solve_stress
from continuum.steady import steady_wall_speed
from continuum.velocity import VELOCITY_NUMERICS, BedScene, solve_velocity

U_FRACTION = 0.05


def depth_at_fraction(depth: np.ndarray, u: np.ndarray, u_w: float, frac: float = U_FRACTION) -> float:
    """delta_u: the first depth (from the plate) where u falls below frac u_w (continuum.crossing,
    linear); nan if never or if u_w is not a positive number."""
    if not (np.isfinite(u_w) and u_w > 0):
        return np.nan
    return crossing_depth(depth, np.asarray(u) / u_w, frac)


@dataclass(frozen=True, eq=False)
class Prediction:
    model: str
    series: pd.DataFrame      # t, u_w, mu_w, delta_u
    profiles: pd.DataFrame    # t, depth, u, mu
    steady: dict              # u_w, mu_w, delta_s


def _series(t, depth, u, mu_w):
    d = [depth_at_fraction(depth, ui, ui[0]) for ui in u]
    return pd.DataFrame({"t": t, "u_w": u[:, 0], "mu_w": mu_w, "delta_u": d})


def predict(material: Material, p_w: float, depth: float, plate_mass: float, kind: str, value: float,
            times) -> list[Prediction]:
    """Predictions for an imposed stress (value = tau_w) or speed (value = u_w) at ``times``."""
    times = np.asarray(times, dtype=float)
    fr = material.friction
    if kind == "stress":
        sc = Scales(material, p_w, value / p_w)
    else:
        sc = Scales.for_speed(material, p_w, value)
    rule = YieldRule.for_layer(sc)
    scene = BedScene(material, p_w, depth, plate_mass=plate_mass)
    drive = {"mu_w": value / p_w} if kind == "stress" else {"u_w": value}
    vel = solve_velocity(scene, times, rule=rule, initial="rest", numerics=VELOCITY_NUMERICS,
                         compare_steady=False, **drive)
    vel_mu_w = vel.series.set_index("t")["mu_w"].reindex(times, method="nearest").to_numpy()
    vel_prof = pd.DataFrame({"t": np.repeat(times, len(vel.y)), "depth": np.tile(vel.y, len(times)),
                             "u": vel.u.ravel(), "mu": np.concatenate([np.interp(vel.y, vel.y_face, m) for m in vel.mu])})
    steady = {"u_w": sc.U * steady_wall_speed(fr, sc.mu_w), "mu_w": sc.mu_w, "delta_s": sc.delta_s}
    out = [Prediction(f"velocity form (bed at rest, H = {scene.depth:.3g} d, m_p = {plate_mass:.3g})",
                      _series(times, vel.y, vel.u, vel_mu_w), vel_prof, steady)]
    t_tilde = sc.t_tilde(times)
    paper = (solve_stress(fr, sc.mu_w, t_tilde) if kind == "stress" else solve_speed(fr, sc.u_tilde(value), t_tilde))
    y = sc.y(paper.mesh.y)
    u = sc.u(paper.velocity)
    prof = pd.DataFrame({"t": np.repeat(times, len(y)), "depth": np.tile(y, len(times)), "u": u.ravel(),
                         "mu": paper.mu.ravel()})
    out.append(Prediction("paper (stress diffusion, tau = mu_s p at t = 0)", _series(times, y, u, paper.mu_w), prof, steady))
    return out
