"""Solve the paper's problem: parameters in, a Solution (arrays + metadata) out."""
from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from functools import cached_property
from pathlib import Path

import numpy as np
import pandas as pd

from granstokes.provenance import provenance

from . import observables as obs
from .mesh import Mesh
from .problems import ImposedSpeed, ImposedStress
from .rheology import Friction, finite, require
from .scales import UNITS
from .steady import steady_delta, steady_wall_speed
from .stepper import TABLEAUX, StepStats, integrate


@dataclass(frozen=True)
class Numerics:
    """Resolution and tolerances.  Defaults reach ~1e-6 relative accuracy in u~_w (bench/)."""

    n_cells: int = 200
    stretch: float = 6.0
    rtol: float = 1e-6
    atol: float = 1e-8
    method: str = "sdirk4"

    def __post_init__(self):
        Mesh.graded(self.n_cells, self.stretch)  # validates both
        require(self.method in TABLEAUX, "method", f"one of {sorted(TABLEAUX)}", self.method)
        require(finite(self.rtol) and 0 < self.rtol < 1, "rtol", "in (0, 1)", self.rtol)
        require(finite(self.atol) and 0 < self.atol < 1, "atol", "in (0, 1)", self.atol)

    def mesh(self) -> Mesh:
        return Mesh.graded(self.n_cells, self.stretch)


def check_times(times, name: str = "times") -> np.ndarray:
    """Output times: a non-empty, strictly increasing list of finite numbers > 0 (``name`` in the error)."""
    t = np.asarray(times, dtype=float).ravel()
    require(t.size > 0 and np.all(np.isfinite(t)) and np.all(t > 0) and np.all(np.diff(t) > 0),
            name, "a non-empty, strictly increasing list of finite numbers > 0", [float(v) for v in np.atleast_1d(times)])
    return t


@dataclass(frozen=True, eq=False)
class Solution:
    """Profiles tau~(y~) at the requested times, the per-step series and the run's metadata.

    Everything is in the paper's dimensionless variables (continuum.scales.UNITS)."""

    imposed: str                # "stress" or "speed"
    friction: Friction
    mu_w_inf: float             # imposed mu_w, or the steady mu_w^inf of the imposed speed
    u_w_imposed: float | None
    mesh: Mesh
    t: np.ndarray
    tau: np.ndarray             # (len(t), N+1)
    series: pd.DataFrame        # columns t, u_w, mu_w, delta at every accepted step
    stats: StepStats
    numerics: Numerics

    @property
    def beta_w(self) -> float:
        return self.friction.beta(self.mu_w_inf)

    @cached_property
    def mu(self) -> np.ndarray:
        return obs.friction_profile(self.friction, self.mu_w_inf, self.mesh, self.tau)

    @property
    def mu_tilde(self) -> np.ndarray:
        return self.friction.tilde(self.mu)

    @cached_property
    def velocity(self) -> np.ndarray:
        return obs.velocity(self.friction, self.mu_w_inf, self.mesh, self.tau)

    @property
    def u_w(self) -> np.ndarray:
        return self.velocity[:, 0]

    @property
    def mu_w(self) -> np.ndarray:
        return self.mu[:, 0]

    @cached_property
    def delta(self) -> np.ndarray:
        return obs.layer_thickness(self.friction, self.mu_w_inf, self.mesh, self.tau)

    @property
    def steady(self) -> dict:
        return {"u_w": steady_wall_speed(self.friction, self.mu_w_inf), "mu_w": self.mu_w_inf,
                "delta": steady_delta(self.friction, self.mu_w_inf)}

    def summary(self) -> dict:
        """The CLI's JSON contract (granstokes continuum --json)."""
        return {"imposed": self.imposed, "mu_s": self.friction.mu_s, "mu_d": self.friction.mu_d,
                "mu_w_inf": self.mu_w_inf, "beta_w": self.beta_w, "t": self.t.tolist(),
                "u_w": self.u_w.tolist(), "mu_w": self.mu_w.tolist(), "delta": self.delta.tolist(),
                "steady": self.steady}

    def metadata(self) -> dict:
        return {**self.summary(), "u_w_imposed": self.u_w_imposed, "numerics": asdict(self.numerics),
                "stats": asdict(self.stats), "units": UNITS,
                "delta_definition": "depth where mu - mu_s falls to 1e-3 of mu_w(t) - mu_s",
                "provenance": provenance()}

    def profiles(self) -> pd.DataFrame:
        """Long table: one row per (t, y~) with tau~, mu, mu~, u~."""
        nt, ny = self.tau.shape
        return pd.DataFrame({"t": np.repeat(self.t, ny), "y": np.tile(self.mesh.y, nt),
                             "tau": self.tau.ravel(), "mu": self.mu.ravel(),
                             "mu_tilde": self.mu_tilde.ravel(), "u": self.velocity.ravel()})

    def save(self, out: Path, stem: str = "continuum") -> None:
        """Write STEM_profiles.csv, STEM_series.csv and STEM.json into ``out``."""
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        self.profiles().to_csv(out / f"{stem}_profiles.csv", index=False)
        self.series.to_csv(out / f"{stem}_series.csv", index=False)
        (out / f"{stem}.json").write_text(json.dumps(self.metadata(), indent=2))


def _run(problem, times, numerics: Numerics, fixed_times=None) -> Solution:
    t = check_times(times)
    recorder = obs.SeriesRecorder(problem)
    states, stats = integrate(problem, t, method=numerics.method, rtol=numerics.rtol, atol=numerics.atol,
                              fixed_times=fixed_times, observer=recorder)
    tau = np.array([problem.full(x) for x in states])
    series = pd.DataFrame(recorder.rows, columns=["t", "u_w", "mu_w", "delta"])
    return Solution(problem.imposed, problem.friction, problem.mu_w,
                    getattr(problem, "u_w", None), problem.mesh, t, tau, series, stats, numerics)


def solve_stress(friction: Friction, mu_w: float, times, numerics: Numerics = Numerics(),
                 fixed_times=None) -> Solution:
    """Imposed wall stress: eq. GranularStokesEqn with tau~(0) = tau~(1) = 1."""
    return _run(ImposedStress(friction, mu_w, numerics.mesh()), times, numerics, fixed_times)


def solve_speed(friction: Friction, u_w: float, times, numerics: Numerics = Numerics(),
                fixed_times=None) -> Solution:
    """Imposed wall speed: eq. GranularStokesEqn_muBIS with the integral condition
    eq. GranularStokesEqn_muBIS_BCs."""
    return _run(ImposedSpeed(friction, u_w, numerics.mesh()), times, numerics, fixed_times)
