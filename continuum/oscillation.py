"""Stokes' second problem: a plate oscillating over a granular bed of depth H on a no-slip base, driven by a Load
with omega > 0 (continuum.load): tau_w(t) = mu_w p_w sin(omega t) or u_w(t) = u_w sin(omega t), from a bed at rest.

Models: the local velocity form (continuum.velocity; the rule's mu(I) or a constant viscosity, ``Newtonian``) and
NGF (continuum.ngf), both with the wall value of the load at time t and integrated by scipy's solve_ivp (Radau by
default).  ``solve_oscillating`` samples given times; ``periodic_state`` marches cycle by cycle to the periodic
state.  Signs: sigma_xy < 0 under a plate moving in +x; ``mu`` = sigma_xy/p (signed); ``mu_w`` is the plate's
friction, positive while the bed resists a +x motion (an imposed speed), or the imposed mu_w sin(omega t).
Error estimates: Richardson's from n_cells/2 on the same graded mesh (continuum.richardson, second order in
space).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp
from scipy.integrate import solve_ivp

from granstokes.lib.validate import finite, require

from .load import Load
from .mesh import Mesh
from .ngf import NonlocalFluidity, TransientNumerics, _Transient
from .richardson import REFINEMENT, richardson, richardson_on_nodes
from .rules import YieldRule
from .solver import check_times
from .velocity import BedScene, VelocityProblem

MODELS = ("local", "ngf")


@dataclass(frozen=True)
class Newtonian:
    """A constant viscosity eta on every face: sigma_xy = eta du/dy = 2 eta g (a face law, like rules.FaceLaw)."""

    eta: float

    def __post_init__(self):
        require(finite(self.eta) and self.eta > 0, "eta", "a finite number > 0", self.eta)

    def stress(self, g):
        return 2 * self.eta * np.asarray(g)

    def slope(self, g):
        return np.full(np.shape(g), 2 * self.eta)


@dataclass(frozen=True)
class OscillationNumerics:
    """Cells of the graded mesh (finest at the plate, largest/smallest cell ~ e^stretch; if even, the estimate's
    nodes are every other one), solve_ivp's method and tolerances (``atol`` on u; NGF also ``atol_lng`` on ln g and
    ``g_rest``, its bed at rest)."""

    n_cells: int = 200
    stretch: float = 2.0
    rtol: float = 1e-6
    atol: float = 1e-9
    method: str = "Radau"
    atol_lng: float = 1e-6
    g_rest: float = 1e-8

    def __post_init__(self):
        self.transient()  # validates

    def transient(self) -> TransientNumerics:
        """ngf's numerics of the same mesh and tolerances."""
        return TransientNumerics(self.n_cells, self.stretch, self.rtol, self.atol, self.atol_lng, self.g_rest,
                                 self.method)


def _wall(problem, load: Load, t: float) -> float:
    """Set the problem's imposed tau_w or u_w to the load's at time t; returns it."""
    value = load.value * float(load.wave(t))
    setattr(problem, "tau_w" if load.kind == "stress" else "u_w", value)
    return value


class OscillatingVelocity:
    """The velocity form (VelocityProblem) with the wall value of the load at time t, as solve_ivp takes it:
    dx/dt = rate(t, x) = F(x)/M and its sparse tridiagonal Jacobian jac(t, x).  ``law``: a face law (stress(g),
    slope(g)) in place of the rule's mu(I), e.g. Newtonian."""

    def __init__(self, scene: BedScene, load: Load, mesh_unit: Mesh, rule: YieldRule = YieldRule(), law=None):
        self.load, self.scene = load, scene
        self.problem = pb = VelocityProblem(scene, rule, mesh_unit, tau_w=load.tau_w, u_w=load.u_w)
        if law is not None:
            pb.law = law
        self.y, self.y_mu, self.p_mu = pb.y, pb.y[:-1] + pb.h / 2, pb.p_face
        self.inverse_mass = 1 / pb.mass

    def at(self, t):
        """Put the wall value of time t in the problem (an imposed speed: also the boundary node ``shear`` reads)."""
        value = _wall(self.problem, self.load, t)
        if self.load.kind == "speed":
            self.problem._full[0] = value

    def rate(self, t, x):
        self.at(t)
        return self.problem.rate(x) * self.inverse_mass

    def jac(self, t, x):
        self.at(t)
        n = len(x)
        band = sp.dia_matrix((self.problem.jacobian(x).bands, [1, 0, -1]), shape=(n, n))
        return (sp.diags(self.inverse_mass) @ band).tocsc()

    def start(self, numerics: OscillationNumerics):
        """The bed at rest and solve_ivp's atol and Jacobian."""
        return self.problem.initial(), {"atol": numerics.atol, "jac": self.jac}

    def sample(self, t, x):
        """u at the nodes, sigma_xy/p at the faces and mu_w at time t of the state x."""
        self.at(t)
        s = self.problem.stress(x)
        mu_w = self.load.mu_w * self.load.wave(t) if self.load.kind == "stress" else -s[0] / self.scene.p_w
        return self.problem.nodes(x), s / self.p_mu, mu_w


class OscillatingNGF(_Transient):
    """ngf's transient (state [u free nodes, ln g cells]) with the wall value of the load at time t.  Below yield
    the fluidity relaxes to the bed at rest's, g_rest, not to 0: over a slow cycle's static phase ln g would fall
    without bound (at |mu - mu_s|/t0) and the stress p gamma/g of any creep blow up (solve_ivp's step collapsed
    on the oscillating-disks study's slowest stress drive)."""

    def __init__(self, scene: BedScene, load: Load, fluidity: NonlocalFluidity, numerics: TransientNumerics):
        super().__init__(scene, fluidity, numerics, load.tau_w, load.u_w)
        self.load, self.y_mu, self.p_mu = load, self.yc, self.pc
        self.g_floor = numerics.g_rest

    def rate(self, t, x):
        _wall(self, self.load, t)
        return super().rate(t, x)

    def start(self, numerics: OscillationNumerics):
        """The bed at rest (u = 0, g = g_rest) and solve_ivp's atol and Jacobian pattern."""
        nu = self.n - self.first
        atol = np.concatenate([np.full(nu, numerics.atol), np.full(self.n, numerics.atol_lng)])
        x0 = np.concatenate([np.zeros(nu), np.full(self.n, math.log(numerics.g_rest))])
        return x0, {"atol": atol, "jac_sparsity": self.sparsity()}

    def sample(self, t, x):
        """u at the nodes, sigma_xy/p (= -tau/p) at the cells and mu_w at time t of the state x."""
        _wall(self, self.load, t)
        u, _, _, tau, _ = self.cells(x)
        mu_w = self.load.mu_w * self.load.wave(t) if self.load.kind == "stress" else tau[0] / self.scene.p_w
        return u, -tau / self.pc, mu_w


@dataclass(frozen=True, eq=False)
class OscillatingSolution:
    """u at the nodes y and mu = sigma_xy/p (signed) at ``y_mu`` (the faces, local; the cell centres, NGF) at the
    times t; the plate's friction mu_w(t) (signed, module docstring); Richardson estimates of u (``u_err``, at
    every node) and of mu_w; scipy's right-hand-side evaluations ``nfev`` (the estimate's included)."""

    load: Load
    model: str
    t: np.ndarray
    y: np.ndarray
    y_mu: np.ndarray
    u: np.ndarray
    mu: np.ndarray
    mu_w: np.ndarray
    u_err: np.ndarray
    mu_w_err: np.ndarray
    nfev: int

    @property
    def u_w(self) -> np.ndarray:
        return self.u[:, 0]

    @property
    def u_w_err(self) -> np.ndarray:
        return self.u_err[:, 0]


@dataclass(frozen=True, eq=False)
class PeriodicState(OscillatingSolution):
    """The last cycle's samples (an OscillatingSolution), the number of ``cycles`` run, the cycle-to-cycle
    ``changes`` (one per cycle after the first) and whether the last is below the tolerance (``converged``)."""

    cycles: int
    changes: np.ndarray
    converged: bool


def _problem(scene, load, model, rule, fluidity, law, numerics):
    require(model in MODELS, "model", f"one of {MODELS}", model)
    require(load.oscillating, "load", "an oscillating load (omega > 0)", load)
    require(math.isclose(load.p_w, scene.p_w, rel_tol=1e-12), "load.p_w", f"the scene's p_w = {scene.p_w}", load.p_w)
    if model == "local":
        require(fluidity is None, "fluidity", "None for the local model", fluidity)
        return OscillatingVelocity(scene, load, Mesh.graded(numerics.n_cells, numerics.stretch), rule, law)
    require(isinstance(fluidity, NonlocalFluidity), "fluidity", "a NonlocalFluidity for model 'ngf'", fluidity)
    require(law is None, "law", "None for model 'ngf' (its law is the fluidity's)", law)
    return OscillatingNGF(scene, load, fluidity, numerics.transient())


def _ivp(pb, numerics, x0, options, t0, t_eval):
    """solve_ivp from the state x0 at t0 to t_eval[-1], sampled at t_eval."""
    sol = solve_ivp(pb.rate, (t0, float(t_eval[-1])), x0, method=numerics.method, t_eval=t_eval, rtol=numerics.rtol,
                    **options)
    if not sol.success:
        raise RuntimeError(f"oscillating {type(pb).__name__} failed: {sol.message}")
    return sol


def _samples(pb, t, states):
    """(u, mu, mu_w) at the times t of the states (rows)."""
    u, mu, mu_w = zip(*(pb.sample(ti, x) for ti, x in zip(t, states)))
    return np.array(u), np.array(mu), np.array(mu_w, dtype=float)


def _cycles(pb, numerics, phases, tol, max_cycles):
    """Cycle by cycle from rest until the change is below tol: (t, samples of the last cycle, changes, nfev)."""
    (x, options), previous, changes, nfev = pb.start(numerics), None, [], 0
    for n in range(max_cycles):
        t = pb.load.period * (n + np.arange(phases + 1) / phases)
        sol = _ivp(pb, numerics, x, options, t[0], t)
        x, nfev = sol.y[:, -1], nfev + sol.nfev
        samples = _samples(pb, t[:-1], sol.y.T[:-1])
        if previous is not None:
            changes.append(np.max(np.abs(samples[0] - previous)) / np.max(np.abs(samples[0])))
            if changes[-1] < tol:
                break
        previous = samples[0]
    return t[:-1], samples, np.array(changes), nfev


def _estimate(pb, fine, coarse_pb, coarse):
    """Richardson's estimates (continuum.richardson, second order) of u at the fine nodes and of mu_w."""
    u_err = np.array([richardson_on_nodes(pb.y, f, coarse_pb.y, c) for f, c in zip(fine[0], coarse[0])])
    return u_err, richardson(fine[2], coarse[2])


def solve_oscillating(scene: BedScene, load: Load, times, *, model: str = "local", rule: YieldRule = YieldRule(),
                      fluidity: NonlocalFluidity | None = None, law=None,
                      numerics: OscillationNumerics = OscillationNumerics(),
                      error_estimate: bool = True) -> OscillatingSolution:
    """The oscillating plate from a bed at rest, sampled at ``times``: the local velocity form (``rule``'s mu(I),
    or ``law``, e.g. Newtonian) or NGF (``fluidity``); ``error_estimate``: rerun on n_cells/2 (else zeros)."""
    t = check_times(times)
    pb = _problem(scene, load, model, rule, fluidity, law, numerics)
    sol = _ivp(pb, numerics, *pb.start(numerics), 0.0, t)
    fine, nfev = _samples(pb, t, sol.y.T), sol.nfev
    u_err, mu_w_err = np.zeros_like(fine[0]), np.zeros(len(t))
    if error_estimate:
        half = replace(numerics, n_cells=numerics.n_cells // REFINEMENT)
        coarse_pb = _problem(scene, load, model, rule, fluidity, law, half)
        coarse = _ivp(coarse_pb, half, *coarse_pb.start(half), 0.0, t)
        u_err, mu_w_err = _estimate(pb, fine, coarse_pb, _samples(coarse_pb, t, coarse.y.T))
        nfev += coarse.nfev
    return OscillatingSolution(load, model, t, pb.y, pb.y_mu, *fine, u_err, mu_w_err, nfev)


def periodic_state(scene: BedScene, load: Load, *, model: str = "local", rule: YieldRule = YieldRule(),
                   fluidity: NonlocalFluidity | None = None, law=None,
                   numerics: OscillationNumerics = OscillationNumerics(), error_estimate: bool = True,
                   tol: float = 1e-3, max_cycles: int = 60, phases: int = 32) -> PeriodicState:
    """The periodic state, marched cycle by cycle from rest (the models as ``solve_oscillating``).

    Cycle n (time (n-1) T to n T, T = 2 pi/omega) is sampled at ``phases`` equally spaced phases,
    t = (n - 1 + k/phases) T, k = 0..phases-1.  Criterion: change_n = max over the phases k and the nodes j of
    |u_n(k, j) - u_{n-1}(k, j)|, over max_{k, j} |u_n(k, j)|; the march stops at the first n >= 2 with
    change_n < ``tol`` (converged) or after ``max_cycles`` cycles (not converged).  The estimate runs the same
    number of cycles on n_cells/2."""
    require(isinstance(max_cycles, int) and max_cycles >= 2, "max_cycles", "an integer >= 2", max_cycles)
    require(isinstance(phases, int) and phases >= 4, "phases", "an integer >= 4", phases)
    require(finite(tol) and tol > 0, "tol", "a finite number > 0", tol)
    pb = _problem(scene, load, model, rule, fluidity, law, numerics)
    t, fine, changes, nfev = _cycles(pb, numerics, phases, tol, max_cycles)
    cycles = len(changes) + 1
    u_err, mu_w_err = np.zeros_like(fine[0]), np.zeros(len(t))
    if error_estimate:
        half = replace(numerics, n_cells=numerics.n_cells // REFINEMENT)
        coarse_pb = _problem(scene, load, model, rule, fluidity, law, half)
        _, coarse, _, coarse_nfev = _cycles(coarse_pb, half, phases, 0.0, cycles)
        u_err, mu_w_err = _estimate(pb, fine, coarse_pb, coarse)
        nfev += coarse_nfev
    return PeriodicState(load, model, t, pb.y, pb.y_mu, *fine, u_err, mu_w_err, nfev, cycles, changes,
                         bool(changes[-1] < tol))


__all__ = ["MODELS", "Newtonian", "OscillatingNGF", "OscillatingSolution", "OscillatingVelocity",
           "OscillationNumerics", "PeriodicState", "periodic_state", "solve_oscillating"]
