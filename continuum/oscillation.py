"""Stokes' second problem: a plate oscillating over a granular bed of depth H on a no-slip base, driven by a Load
with omega > 0 (continuum.load): tau_w(t) = mu_w p_w sin(omega t) or u_w(t) = u_w sin(omega t), from a bed at rest.

Models: the local velocity form (continuum.velocity.VelocityProblem; the rule's mu(I) or a constant viscosity,
``Newtonian``), NGF (continuum.ngf.FluidityProblem) and elasto-plastic mu(I) (continuum.elastic.ElasticProblem,
shear modulus G), all problems whose rate reads the load's wall value at time
t (``Load.wall``), integrated through the method registry (continuum.integrators; scipy's Radau by default,
``OSCILLATION_NUMERICS``).  ``solve_oscillating`` samples given times; ``periodic_state`` marches cycle by cycle to
the periodic state.  Signs: sigma_xy < 0 under a plate moving in +x; ``mu`` = sigma_xy/p (signed); ``mu_w`` is the
plate's friction, positive while the bed resists a +x motion (an imposed speed), or the imposed mu_w sin(omega t).
Error estimates: Richardson's from n_cells/2 on the same graded mesh (continuum.richardson, second order in
space).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import NamedTuple

import numpy as np

from granstokes.lib.validate import finite, require

from .elastic import ElasticProblem
from .integrators import integrate
from .load import Load
from .ngf import FluidityProblem, NonlocalFluidity
from .richardson import REFINEMENT, richardson, richardson_on_nodes
from .rules import YieldRule
from .scales import Material
from .scene import BedScene, SceneNumerics
from .solver import check_times
from .velocity import VelocityProblem

MODELS = ("local", "ngf", "elastic")
#: the oscillating plate's numerics: 200 cells of the graded mesh, scipy's Radau at rtol 1e-6 (the verification's,
#: docs/oscillation.md; compare.oscillation takes coarser ones)
OSCILLATION_NUMERICS = SceneNumerics(n_cells=200)


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


class _Model(NamedTuple):
    """A model's problem on one mesh, its absolute tolerance, the depths of its mu (the faces, local; the cell
    centres, NGF) and its sampling (x, t) -> (u at the nodes, sigma_xy/p signed, the plate's mu_w)."""

    problem: object
    atol: object
    y_mu: np.ndarray
    sample: Callable


def _local(material, scene, load, numerics, rule, law) -> _Model:
    problem = VelocityProblem(material, scene, load, numerics.mesh(), rule=rule, law=law)

    def sample(x, t):
        s = problem.stress(x, t)
        mu_w = load.mu_w * load.wave(t) if load.kind == "stress" else -s[0] / load.p_w
        return problem.nodes(x, t), s / problem.p_face, mu_w

    return _Model(problem, numerics.atol, problem.y[:-1] + problem.h / 2, sample)


def _ngf(material, scene, load, numerics, fluidity) -> _Model:
    problem = FluidityProblem(material, scene, load, fluidity, numerics, g_floor=numerics.g_rest)  # see its docstring

    def sample(x, t):
        u, _, _, tau, _ = problem.cells(x, t)
        mu_w = load.mu_w * load.wave(t) if load.kind == "stress" else tau[0] / load.p_w
        return u, -tau / problem.pc, mu_w

    return _Model(problem, problem.atol, problem.yc, sample)


def _elastic(material, scene, load, numerics, G) -> _Model:
    problem = ElasticProblem(material, scene, load, numerics.mesh(), G)

    def sample(x, t):
        s = problem.stress(x)
        mu_w = load.mu_w * load.wave(t) if load.kind == "stress" else -s[0] / load.p_w
        return problem.nodes(x, t), s / problem.p_face, mu_w

    return _Model(problem, numerics.atol, problem.y[:-1] + problem.h / 2, sample)


def _model(material: Material, scene: BedScene, load: Load, numerics: SceneNumerics, *, model, rule, fluidity,
           law, G=None) -> _Model:
    require(model in MODELS, "model", f"one of {MODELS}", model)
    require(load.oscillating, "load", "an oscillating load (omega > 0)", load)
    if model == "elastic":
        require(G is not None, "G", "the bed's shear modulus for model 'elastic'", G)
        return _elastic(material, scene, load, numerics, G)
    if model == "local":
        require(fluidity is None, "fluidity", "None for the local model", fluidity)
        return _local(material, scene, load, numerics, rule, law)
    require(isinstance(fluidity, NonlocalFluidity), "fluidity", "a NonlocalFluidity for model 'ngf'", fluidity)
    require(law is None, "law", "None for model 'ngf' (its law is the fluidity's)", law)
    return _ngf(material, scene, load, numerics, fluidity)


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


def _march(run: _Model, numerics: SceneNumerics, t, resume=None):
    """The model's states at the times t, from the bed at rest at t = 0 or from ``resume`` = (t0, x0) (t[0] = t0
    then), and scipy's evaluations of the rate (a baseline's newton_iterations)."""
    states, stats = integrate(run.problem, t, method=numerics.method, rtol=numerics.rtol, atol=run.atol,
                              resume=resume)
    return states, stats.newton_iterations


def _samples(run: _Model, t, states):
    """(u, mu, mu_w) at the times t of the states (rows)."""
    u, mu, mu_w = zip(*(run.sample(x, ti) for ti, x in zip(t, states)))
    return np.array(u), np.array(mu), np.array(mu_w, dtype=float)


def _cycles(run: _Model, load: Load, numerics: SceneNumerics, phases, tol, max_cycles):
    """Cycle by cycle from rest until the change is below tol: (t, samples of the last cycle, changes, nfev)."""
    x, previous, changes, nfev = run.problem.initial(), None, [], 0
    for n in range(max_cycles):
        t = load.period * (n + np.arange(phases + 1) / phases)
        states, evaluations = _march(run, numerics, t, (t[0], x))
        x, nfev = states[-1], nfev + evaluations
        samples = _samples(run, t[:-1], states[:-1])
        if previous is not None:
            changes.append(np.max(np.abs(samples[0] - previous)) / np.max(np.abs(samples[0])))
            if changes[-1] < tol:
                break
        previous = samples[0]
    return t[:-1], samples, np.array(changes), nfev


def _estimate(run: _Model, fine, coarse_run: _Model, coarse):
    """Richardson's estimates (continuum.richardson, second order) of u at the fine nodes and of mu_w."""
    u_err = np.array([richardson_on_nodes(run.problem.y, f, coarse_run.problem.y, c)
                      for f, c in zip(fine[0], coarse[0])])
    return u_err, richardson(fine[2], coarse[2])


def solve_oscillating(material: Material, scene: BedScene, load: Load, times, *, model: str = "local",
                      rule: YieldRule = YieldRule(), fluidity: NonlocalFluidity | None = None, law=None,
                      G: float | None = None, numerics: SceneNumerics = OSCILLATION_NUMERICS,
                      error_estimate: bool = True) -> OscillatingSolution:
    """The oscillating plate from a bed at rest, sampled at ``times``: the local velocity form (``rule``'s mu(I),
    or ``law``, e.g. Newtonian), NGF (``fluidity``) or elasto-plastic mu(I) (shear modulus ``G``);
    ``error_estimate``: rerun on n_cells/2 (else zeros)."""
    t = check_times(times)
    options = dict(model=model, rule=rule, fluidity=fluidity, law=law, G=G)
    run = _model(material, scene, load, numerics, **options)
    states, nfev = _march(run, numerics, t)
    fine = _samples(run, t, states)
    u_err, mu_w_err = np.zeros_like(fine[0]), np.zeros(len(t))
    if error_estimate:
        half = replace(numerics, n_cells=numerics.n_cells // REFINEMENT)
        coarse_run = _model(material, scene, load, half, **options)
        coarse, coarse_nfev = _march(coarse_run, half, t)
        u_err, mu_w_err = _estimate(run, fine, coarse_run, _samples(coarse_run, t, coarse))
        nfev += coarse_nfev
    return OscillatingSolution(load, model, t, run.problem.y, run.y_mu, *fine, u_err, mu_w_err, nfev)


def periodic_state(material: Material, scene: BedScene, load: Load, *, model: str = "local",
                   rule: YieldRule = YieldRule(), fluidity: NonlocalFluidity | None = None, law=None,
                   G: float | None = None, numerics: SceneNumerics = OSCILLATION_NUMERICS,
                   error_estimate: bool = True, tol: float = 1e-3, max_cycles: int = 60,
                   phases: int = 32) -> PeriodicState:
    """The periodic state, marched cycle by cycle from rest (the models as ``solve_oscillating``).

    Cycle n (time (n-1) T to n T, T = 2 pi/omega) is sampled at ``phases`` equally spaced phases,
    t = (n - 1 + k/phases) T, k = 0..phases-1.  Criterion: change_n = max over the phases k and the nodes j of
    |u_n(k, j) - u_{n-1}(k, j)|, over max_{k, j} |u_n(k, j)|; the march stops at the first n >= 2 with
    change_n < ``tol`` (converged) or after ``max_cycles`` cycles (not converged).  The estimate runs the same
    number of cycles on n_cells/2."""
    require(isinstance(max_cycles, int) and max_cycles >= 2, "max_cycles", "an integer >= 2", max_cycles)
    require(isinstance(phases, int) and phases >= 4, "phases", "an integer >= 4", phases)
    require(finite(tol) and tol > 0, "tol", "a finite number > 0", tol)
    options = dict(model=model, rule=rule, fluidity=fluidity, law=law, G=G)
    run = _model(material, scene, load, numerics, **options)
    t, fine, changes, nfev = _cycles(run, load, numerics, phases, tol, max_cycles)
    cycles = len(changes) + 1
    u_err, mu_w_err = np.zeros_like(fine[0]), np.zeros(len(t))
    if error_estimate:
        half = replace(numerics, n_cells=numerics.n_cells // REFINEMENT)
        coarse_run = _model(material, scene, load, half, **options)
        _, coarse, _, coarse_nfev = _cycles(coarse_run, load, half, phases, 0.0, cycles)
        u_err, mu_w_err = _estimate(run, fine, coarse_run, coarse)
        nfev += coarse_nfev
    return PeriodicState(load, model, t, run.problem.y, run.y_mu, *fine, u_err, mu_w_err, nfev, cycles, changes,
                         bool(changes[-1] < tol))


__all__ = ["MODELS", "Newtonian", "OSCILLATION_NUMERICS", "OscillatingSolution", "PeriodicState", "periodic_state",
           "solve_oscillating"]
