"""Solve the paper's problem: parameters in, a Solution (arrays + metadata) out."""
from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field, replace
from functools import cached_property
from pathlib import Path

import numpy as np

from granstokes.provenance import provenance

from . import observables as obs
from .mesh import MAX_STRETCH, ORDERS, Mesh
from .problems import ImposedSpeed, ImposedStress
from .rheology import Friction, finite, require
from .scales import UNITS
from .steady import SELF_SIMILAR_DELTA, mu_w_for_speed, steady_delta, steady_wall_speed
from .stepper import METHODS, TABLEAUX, StepStats, integrate

#: the default time stepper of each drive (continuum.stepper: BDF keeps its order on the speed's DAE,
#: the DIRKs' stage order 1 does not)
DEFAULT_METHOD = {"stress": "sdirk4", "speed": "bdf"}
#: the order in space of each drive (measured, tests/continuum): 4 for both; a speed's only with the
#: wall-graded map through the lift-off of mu_w from mu_d (``phases``): on one map that does not grade the
#: wall (``Numerics.remesh`` False, or a fixed stretch below WALL_STRETCH) mu_w converges at UNGRADED_SPEED_ORDER
CONVERGENCE_ORDER = {"stress": 4, "speed": 4}
UNGRADED_SPEED_ORDER = 1
#: the first output time's layer is given this fraction of the mesh (the map's xi at delta(t_min)); the
#: speed's degenerate wall layer needs more of it
LAYER_SHARE = {"stress": 0.3, "speed": 0.45}
#: default time tolerance: MATCHED_RTOL[method] on MATCHED_CELLS cells, scaled as n_cells^-order (measured:
#: the time error then stays below the space error of the mesh, bench/work_precision.py, bench/speed_solver.py)
MATCHED_RTOL, MATCHED_CELLS = dict.fromkeys(METHODS, 1e-8), 256
#: the loosest time tolerance of each method: scipy's BDF on the speed takes more steps, not fewer, above
#: it (measured: u~_w = 4.629 on 64 cells 894 steps at rtol 1e-8, 4389 at 1e-7; 1.334 on 256 cells 1432
#: and 8431); its time error there is ~1-20 rtol (landing on every output time: stepper)
MAX_RTOL = {**dict.fromkeys(TABLEAUX, 1e-3), "bdf": 1e-8}
#: atol = ATOL_PER_RTOL rtol (tau~ is O(1))
ATOL_PER_RTOL = 1e-2
#: the first time step, as a fraction of the first output time
INITIAL_STEP = 1e-5
#: the two solves of an error estimate: the coarse one has half the cells and gain(drive) times the
#: tolerance (every error gain times larger: of the drive's order in space, tolerance-proportional in time)
REFINEMENT = 2
ORDER_GAIN = REFINEMENT ** CONVERGENCE_ORDER["stress"]


def convergence_order(imposed: str, numerics: "Numerics") -> int:
    """The order in space of a drive solved with these numerics (CONVERGENCE_ORDER, UNGRADED_SPEED_ORDER)."""
    if imposed == "speed" and (not numerics.remesh if numerics.stretch is None else numerics.stretch < WALL_STRETCH):
        return UNGRADED_SPEED_ORDER
    return CONVERGENCE_ORDER[imposed]


def gain(imposed: str, numerics: "Numerics") -> int:
    """The factor by which every error grows from a solve to its coarser companion."""
    return REFINEMENT ** convergence_order(imposed, numerics)

#: the Richardson estimate times this bounds the true error (measured: the bare estimate is within a
#: factor 2 of it either way, tests/continuum/test_accuracy.py)
SAFETY = 3.0


@dataclass(frozen=True)
class Numerics:
    """Resolution and tolerances of one solve.  ``stretch=None``: the map follows the first output
    time (``stretch_for``), and an imposed speed is remeshed in time unless ``remesh`` is False
    (``phases``); ``order``: of the spatial discretisation (continuum.mesh); ``method``, ``rtol``,
    ``atol`` = None: the drive's defaults (``for_drive``)."""

    n_cells: int = 64
    stretch: float | None = None
    rtol: float | None = None
    atol: float | None = None
    method: str | None = None
    order: int = 4
    remesh: bool = True

    def __post_init__(self):
        Mesh.graded(self.n_cells, 0.0 if self.stretch is None else self.stretch)  # validates both
        require(self.order in ORDERS, "order", f"one of {ORDERS}", self.order)
        require(self.method is None or self.method in METHODS, "method", f"one of {list(METHODS)}", self.method)
        for name in ("rtol", "atol"):
            value = getattr(self, name)
            require(value is None or (finite(value) and 0 < value < 1), name, "in (0, 1)", value)

    def for_drive(self, imposed: str) -> "Numerics":
        """These numerics with the drive's defaults filled in: its method, and a time tolerance matched
        to the space error of this mesh (MATCHED_RTOL, scaled as n_cells^-order)."""
        method = self.method or DEFAULT_METHOD[imposed]
        scale = (MATCHED_CELLS / self.n_cells) ** convergence_order(imposed, self)
        rtol = self.rtol if self.rtol is not None else min(MATCHED_RTOL[method] * scale, MAX_RTOL[method])
        return replace(self, method=method, rtol=rtol, atol=self.atol if self.atol is not None else rtol * ATOL_PER_RTOL)

    def mesh(self, stretch: float | None = None) -> Mesh:
        """The mesh of ``n_cells`` with this stretch, else ``stretch`` (else uniform)."""
        return Mesh.graded(self.n_cells, self.stretch if self.stretch is not None else (stretch or 0.0))

    def coarser(self, factor: float) -> "Numerics":
        """The estimate's companion: half the cells, ``factor`` times the tolerances (resolved numerics)."""
        rtol = min(self.rtol * factor, max(MAX_RTOL[self.method], self.rtol))
        return replace(self, n_cells=self.n_cells // REFINEMENT, rtol=rtol, atol=rtol * self.atol / self.rtol)

    def finer(self, factor: float) -> "Numerics":
        return replace(self, n_cells=self.n_cells * REFINEMENT, rtol=self.rtol / factor, atol=self.atol / factor)


#: the map's wall slope y'(0) = a/(e^a - 1) (the first cell is y'(0)/N) is kept above this fraction of
#: delta(t_min): a finer wall cell adds nothing, and an imposed speed's wall unknown, fixed by u~_w less the
#: interior's share, loses the digits of the first cell's share (measured: 8 digits, and BDF failing, at
#: h_0/delta ~ 1e-8, a calibration with mu_s ~ 0 where delta(t_min) ~ 4e-10); active only for delta <~ 1e-5
WALL_SLOPE_FLOOR = 1e-2
#: most fixed-point iterations of ``stretch_for``
STRETCH_ITERATIONS = 200


def _fixed_point(step, a: float) -> float:
    """Iterate a = step(a) until it settles (at most STRETCH_ITERATIONS times)."""
    for _ in range(STRETCH_ITERATIONS):
        a, previous = step(a), a
        if a == previous:
            break
    return a


def stretch_for(fr: Friction, mu_w: float, t_min: float, share: float = LAYER_SHARE["stress"]) -> float:
    """The map's stretch a that puts ``share`` of the xi-grid inside the layer at t_min:
    ln(1 + delta (e^a - 1)) = share a, with the short-time thickness
    delta ~ SELF_SIMILAR_DELTA Dmu mu~_w sqrt(t~) (the wall diffusivity is (Dmu mu~_w)^2), unless its wall
    slope falls below WALL_SLOPE_FLOOR delta: then the a with a/(e^a - 1) = WALL_SLOPE_FLOOR delta."""
    delta = SELF_SIMILAR_DELTA * fr.dmu * max(fr.tilde(mu_w), 0.05) * np.sqrt(t_min)
    if delta >= share:
        return 0.0
    a = _fixed_point(lambda a: math.log1p(math.expm1(share * a) / delta), 1.0)
    floor = WALL_SLOPE_FLOOR * delta
    if a / math.expm1(a) < floor:  # the wall slope y'(0) = a/(e^a - 1) of this map is below the floor
        a = _fixed_point(lambda a: math.log1p(a / floor), a)
    return float(min(a, MAX_STRETCH))


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
    meshes: tuple[Mesh, ...]   # the mesh of each output time (a speed is remeshed in time: ``phases``)
    t: np.ndarray
    tau: np.ndarray             # (len(t), N+1)
    recorded: tuple             # per phase: the per-step rows, or the recorder that derives them (``steps``)
    stats: StepStats
    numerics: Numerics
    errors: dict = field(default_factory=dict)  # u_w, mu_w, delta -> absolute error estimates (aligned with t)
    accuracy: float | None = None               # the relative accuracy asked for (None: one solve)

    @cached_property
    def steps(self) -> np.ndarray:
        """Rows (t, u_w, mu_w, delta) at every accepted step, derived on first use (``series``)."""
        return np.concatenate([r.table() if isinstance(r, obs.SeriesRecorder) else r for r in self.recorded])

    @property
    def mesh(self) -> Mesh:
        """The one mesh of every output time (a ValueError if the solve was remeshed: use ``y``)."""
        if len(self.phase_meshes) > 1:
            raise ValueError("this solution was remeshed in time: its nodes are y[k] at each time")
        return self.meshes[0]

    @cached_property
    def y(self) -> np.ndarray:
        """The nodes y~ at each output time, (len(t), N+1)."""
        return np.array([m.y for m in self.meshes]).reshape(len(self.t), -1)

    @property
    def phase_meshes(self) -> list[Mesh]:
        """The solve's meshes in time order, one per phase (``phases``)."""
        return list({id(m): m for m in self.meshes}.values())

    def _per_mesh(self, derive) -> np.ndarray:
        """derive(mesh, tau rows) evaluated on the rows of each mesh (remeshing: one call per phase)."""
        groups = [(mesh, [k for k, m in enumerate(self.meshes) if m is mesh]) for mesh in self.phase_meshes]
        parts = [derive(mesh, self.tau[rows]) for mesh, rows in groups]
        out = np.empty((len(self.t), *parts[0].shape[1:]))
        for (_, rows), part in zip(groups, parts):
            out[rows] = part
        return out

    @cached_property
    def series(self):
        """The per-step series as a DataFrame: columns t, u_w, mu_w, delta."""
        import pandas as pd

        return pd.DataFrame(self.steps, columns=["t", "u_w", "mu_w", "delta"])

    @property
    def beta_w(self) -> float:
        return self.friction.beta(self.mu_w_inf)

    @cached_property
    def mu(self) -> np.ndarray:
        return self._per_mesh(lambda mesh, tau: obs.friction_profile(self.friction, self.mu_w_inf, mesh, tau))

    @property
    def mu_tilde(self) -> np.ndarray:
        return self.friction.tilde(self.mu)

    @cached_property
    def velocity(self) -> np.ndarray:
        return self._per_mesh(lambda mesh, tau: obs.velocity(self.friction, self.mu_w_inf, mesh, tau, self.numerics.order,
                                                             wall_speed=self.u_w_imposed))

    @property
    def u_w(self) -> np.ndarray:
        return self.velocity[:, 0]

    @property
    def mu_w(self) -> np.ndarray:
        return self.mu[:, 0]

    @cached_property
    def delta(self) -> np.ndarray:
        return self._per_mesh(lambda mesh, tau: obs.layer_thickness(self.friction, self.mu_w_inf, mesh, tau,
                                                                    self.numerics.order))

    @property
    def steady(self) -> dict:
        """The exact steady state (continuum.steady: closed forms, a root to 1e-15 for a speed)."""
        return {"u_w": steady_wall_speed(self.friction, self.mu_w_inf), "mu_w": self.mu_w_inf,
                "delta": steady_delta(self.friction, self.mu_w_inf),
                "u_w_err": 0.0, "mu_w_err": 0.0, "delta_err": 0.0}

    def summary(self) -> dict:
        """The CLI's JSON contract (granstokes continuum --json): values and their error estimates."""
        out = {"imposed": self.imposed, "mu_s": self.friction.mu_s, "mu_d": self.friction.mu_d,
               "mu_w_inf": self.mu_w_inf, "beta_w": self.beta_w, "t": self.t.tolist()}
        for name in QUANTITIES:
            out[name] = getattr(self, name).tolist()
            out[f"{name}_err"] = self.errors[name].tolist() if name in self.errors else None
        return {**out, "accuracy": self.accuracy, "steady": self.steady}

    def metadata(self) -> dict:
        return {**self.summary(), "u_w_imposed": self.u_w_imposed, "numerics": asdict(self.numerics),
                "stats": asdict(self.stats), "units": UNITS,
                "delta_definition": "depth where mu - mu_s falls to 1e-3 of mu_w(t) - mu_s",
                "provenance": provenance()}

    def profiles(self):
        """Long table (DataFrame): one row per (t, y~) with tau~, mu, mu~, u~."""
        import pandas as pd

        nt, ny = self.tau.shape
        return pd.DataFrame({"t": np.repeat(self.t, ny), "y": self.y.ravel(),
                             "tau": self.tau.ravel(), "mu": self.mu.ravel(),
                             "mu_tilde": self.mu_tilde.ravel(), "u": self.velocity.ravel()})

    def save(self, out: Path, stem: str = "continuum") -> None:
        """Write STEM_profiles.csv, STEM_series.csv and STEM.json into ``out``."""
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        self.profiles().to_csv(out / f"{stem}_profiles.csv", index=False)
        self.series.to_csv(out / f"{stem}_series.csv", index=False)
        (out / f"{stem}.json").write_text(json.dumps(self.metadata(), indent=2))


#: the quantities whose accuracy is estimated and controlled, and the one each drive imposes (exact)
QUANTITIES = ("u_w", "mu_w", "delta")
IMPOSED = {"stress": "mu_w", "speed": "u_w"}
#: default relative accuracy of every number returned, and the range that can be asked for
DEFAULT_ACCURACY = 1e-6
ACCURACY_RANGE = (1e-10, 1e-2)
#: refinement stops here (a request that needs more is refused with the accuracy reached): a speed on
#: 512 cells takes 3-6 s; on 1024 its wall cells (7e-8) stall BDF by round-off (bench/RESULTS.md
#: "Remeshing the speed in time")
MAX_CELLS = {"stress": 2048, "speed": 512}
#: an estimated solve has at least this many cells: the companion of a speed on 64 cells (32) is
#: pre-asymptotic through the lift-off (measured: mu_w at u~_w = 1.334, t~ = 1 underestimated 1.5x)
MIN_ESTIMATED_CELLS = {"stress": 8, "speed": 128}


#: an imposed speed is remeshed once in time (``phases``): until SWITCH_SPAN t~_mud (t~_mud = u~_w^2, eq.
#: TimeScaleMuD, the lift-off of mu_w from mu_d) on a map of stretch >= WALL_STRETCH, whose wall cells
#: resolve the sub-layer mu~ ~ a + b y + c y ln y of the lift-off (on the layer's map the first cell misses
#: the y ln y below a/b and mu_w converges at first order; measured: fourth order from stretch 11), then on
#: the map that follows the layer at the switch (on the wall-graded map the round-off eps tau~/h_0^2 of its
#: wall cells stalls the steps near the steady state); bench/RESULTS.md "Remeshing the speed in time"
WALL_STRETCH = 12.0
SWITCH_SPAN = 1.0


@dataclass(frozen=True)
class Phase:
    """Integrate on the map of this stretch from t~ = ``start`` to ``end`` (the next phase's start)."""

    start: float
    end: float
    stretch: float


def phases(friction: Friction, mu_w: float, imposed: str, t: np.ndarray, numerics: Numerics,
           switch: float | None = None) -> list[Phase]:
    """The meshes of a solve in time: one map following the layer at t[0] (``stretch_for``), or the
    given ``numerics.stretch``; with a ``switch`` time (an imposed speed, ``numerics.remesh``) a wall-graded
    map (WALL_STRETCH) until ``switch``, then, if t[-1] is later, the map following the layer at ``switch``."""
    def layer(t0):
        return stretch_for(friction, mu_w, t0, LAYER_SHARE[imposed])

    if numerics.stretch is not None:
        return [Phase(0.0, math.inf, numerics.stretch)]
    if switch is None or not numerics.remesh:
        return [Phase(0.0, math.inf, layer(t[0]))]
    graded = max(layer(t[0]), WALL_STRETCH)
    if switch >= t[-1]:
        return [Phase(0.0, math.inf, graded)]
    return [Phase(0.0, switch, graded), Phase(switch, math.inf, layer(switch))]


def _run(make_problem, t, numerics: Numerics, plan: list[Phase], fixed_times=None, record=True) -> Solution:
    """Integrate through the phases of ``plan``: each phase's final tau~ is carried to the next mesh by
    Mesh.interpolate, the wall row then projected (the constraint of an imposed speed holds again)."""
    tau, meshes, recorded, total = [], [], [], StepStats()
    problem = resume = None
    for phase in plan:
        previous, problem = problem, make_problem(numerics.mesh(phase.stretch), numerics.order)
        if previous is not None:
            carried = previous.mesh.interpolate(previous.full(resume[1]), problem.mesh.y)[:-1]
            resume = (phase.start, problem.project(carried))
        out = t[t > phase.start]
        out = out[out <= phase.end]
        target = out if phase.end == math.inf or (len(out) and out[-1] == phase.end) else np.append(out, phase.end)
        recorder = obs.SeriesRecorder(problem) if record else np.empty((0, 4))
        states, stats = integrate(problem, target, method=numerics.method, rtol=numerics.rtol, atol=numerics.atol,
                                  h0=INITIAL_STEP * (phase.start or target[0]), fixed_times=fixed_times,
                                  observer=recorder if record else None, resume=resume)
        resume = (target[-1], states[-1])
        tau += [problem.full(x) for x in states[:len(out)]]
        meshes += [problem.mesh] * len(out)
        recorded.append(recorder)
        total = total.add(stats)
    return Solution(problem.imposed, problem.friction, problem.mu_w, getattr(problem, "u_w", None), tuple(meshes),
                    t, np.array(tau), tuple(recorded), total, numerics)


#: the global time error per unit rtol of each method, the floor of an estimate (measured: SDIRK4 on a
#: stress <= 1, against the independent reference; bdf on a speed up to ~30 in delta, ~6 in mu_w, against
#: rtol 1e-11 on the same mesh; bench/RESULTS.md)
TIME_ERROR_PER_RTOL = {**dict.fromkeys(TABLEAUX, 1.0), "bdf": 30.0}
#: after a remeshing (``phases``) the state carries the new mesh's error of the old state, which converges at
#: this order (measured: the jump of mu_w at the switch, u~_w = 0.198: 3.1e-4, 8.0e-5, 2.0e-5 on 64, 128, 256 cells)
REMESHED_ORDER = 2


def _estimate(fine: Solution, coarse: Solution) -> dict:
    """Absolute error estimates of ``fine`` from its companion: SAFETY |fine - coarse|/(gain - 1), the gain
    of REMESHED_ORDER at the times after a remeshing, plus a floor at the time error,
    TIME_ERROR_PER_RTOL rtol |fine| (below it the two solves' difference no longer measures the error;
    measured against the independent reference, u~_w at t~ = 0.1 for mu~_w = 0.5 on 128 cells, error
    1.6e-8 relative where rtol = 1.6e-7, was underestimated 1.2x without it); the imposed quantity
    (IMPOSED) is exact (a speed's constraint holds to round-off)."""
    remeshed = np.array([m is not fine.meshes[0] for m in fine.meshes])
    g = np.where(remeshed, REFINEMENT ** REMESHED_ORDER, gain(fine.imposed, fine.numerics))
    floor = TIME_ERROR_PER_RTOL[fine.numerics.method] * fine.numerics.rtol
    out = {q: SAFETY * np.abs(getattr(fine, q) - getattr(coarse, q)) / (g - 1) + floor * np.abs(getattr(fine, q))
           for q in QUANTITIES}
    out[IMPOSED[fine.imposed]] = np.zeros(len(fine.t))
    return out


def _solve(make_problem, imposed, mu_w, friction, times, numerics, accuracy, estimate, fixed_times,
           switch=None) -> Solution:
    t = check_times(times)
    numerics = numerics or Numerics()
    if accuracy is not None or estimate:
        numerics = replace(numerics, n_cells=max(numerics.n_cells, MIN_ESTIMATED_CELLS[imposed]))
    numerics = numerics.for_drive(imposed)
    order, factor, most = convergence_order(imposed, numerics), gain(imposed, numerics), MAX_CELLS[imposed]

    def run(num, record=True):
        return _run(make_problem, t, num, phases(friction, mu_w, imposed, t, num, switch), fixed_times, record)

    if accuracy is None and not estimate:
        return run(numerics)
    if accuracy is not None:
        require(finite(accuracy) and ACCURACY_RANGE[0] <= accuracy <= ACCURACY_RANGE[1], "accuracy",
                f"in [{ACCURACY_RANGE[0]:g}, {ACCURACY_RANGE[1]:g}]", accuracy)
    coarse = run(numerics.coarser(factor), record=False)
    while True:
        fine = run(numerics)
        errors = _estimate(fine, coarse)
        worst = max(float(np.max(errors[q] / np.abs(getattr(fine, q)))) for q in QUANTITIES)
        if accuracy is None or worst <= accuracy:
            return replace(fine, errors=errors, accuracy=accuracy)
        needed = numerics.n_cells * (worst / accuracy) ** (1 / order)
        require(needed <= most and numerics.n_cells * REFINEMENT <= most, "accuracy",
                f">= {worst * (numerics.n_cells / most) ** order:.1e} for this request "
                f"(reachable with at most {most} cells)", accuracy)
        numerics, coarse = numerics.finer(factor), fine


def solve_stress(friction: Friction, mu_w: float, times, numerics: Numerics | None = None, *,
                 accuracy: float | None = None, estimate: bool = False, fixed_times=None) -> Solution:
    """Imposed wall stress: eq. GranularStokesEqn with tau~(0) = tau~(1) = 1.  ``accuracy``: refine
    (from ``numerics``) until every estimated relative error is below it; None: one solve as given,
    with error estimates (from the coarser companion solve) if ``estimate``."""
    mu_w = friction.check_mu_w(mu_w)
    return _solve(lambda mesh, order: ImposedStress(friction, mu_w, mesh, order), "stress", mu_w, friction, times,
                  numerics, accuracy, estimate, fixed_times)


def solve_speed(friction: Friction, u_w: float, times, numerics: Numerics | None = None, *,
                accuracy: float | None = None, estimate: bool = False, fixed_times=None) -> Solution:
    """Imposed wall speed: eq. GranularStokesEqn_muBIS with the integral condition
    eq. GranularStokesEqn_muBIS_BCs (``accuracy``, ``estimate`` as for solve_stress)."""
    mu_w = mu_w_for_speed(friction, u_w)
    return _solve(lambda mesh, order: ImposedSpeed(friction, u_w, mesh, order), "speed", mu_w, friction, times,
                  numerics, accuracy, estimate, fixed_times, None if fixed_times is not None else SWITCH_SPAN * u_w**2)
