"""Solve the paper's problem: parameters in, a Solution (arrays + metadata) out."""
from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field, replace
from functools import cached_property
from pathlib import Path

import numpy as np

from granstokes.lib.provenance import provenance

from . import observables as obs
from .bdf import STALL_FRACTION, STALL_STEPS
from .integrators import METHODS as REGISTERED
from .integrators import integrate
from .mesh import MAX_STRETCH, ORDERS, Mesh
from .problems import ImposedSpeed, ImposedStress
from .rheology import Friction, finite, require
from .richardson import REFINEMENT, richardson
from .scales import UNITS
from .steady import SELF_SIMILAR_DELTA, mu_w_for_speed, steady_delta, steady_wall_speed
from .stepper import StepStats

#: the methods a solve may name: every registered one (continuum.integrators), the solve_ivp baselines included
METHODS = tuple(REGISTERED)
#: the default time stepper of each drive (continuum.stepper: BDF keeps its order on the speed's DAE,
#: the DIRKs' stage order 1 does not)
DEFAULT_METHOD = {"stress": "sdirk4", "speed": "bdf"}
#: the order in space of each drive (measured, tests/continuum): 4 for both; a speed's only on a map that
#: grades the wall through the lift-off of mu_w from mu_d (``map_for``): on an exponential map of a fixed
#: stretch below WALL_STRETCH mu_w converges at UNGRADED_SPEED_ORDER
CONVERGENCE_ORDER = {"stress": 4, "speed": 4}
UNGRADED_SPEED_ORDER = 1
#: the first output time's layer is given this fraction of the mesh (the exponential map's xi at delta(t_min))
LAYER_SHARE = 0.3
#: an imposed speed's wall sub-layer mu~ ~ a + b y + c y ln y, through the lift-off of mu_w from mu_d
#: (t~_mud = u~_w^2, eq. (3.17)), is resolved by a map of at least WALL_FOLDS e-folds in all
#: (``map_for``: the layer's stretch plus a wall cluster, continuum.mesh); on the exponential map alone by
#: a stretch of at least WALL_STRETCH (measured: fourth order from stretch 11, first order below: the first
#: cell misses the y ln y below a/b), which costs delta: its cells near delta are stretch/N of it
#: (bench/RESULTS.md "One map with a wall cluster")
WALL_FOLDS, WALL_STRETCH = 14.0, 12.0
#: ... except at an imposed speed's early output times, before EARLY_SPAN t~_mud/max(1, u~_w) (``early_until``):
#: there the wall sub-layer is thinner than WALL_FOLDS' first cell and leaves errors that N does not change
#: (measured: mu_w of 0.198 at 0.03 t~_mud 6e-6, 5e-6, 2e-6 on 128, 256, 512 cells, converging from 0.05
#: t~_mud; delta at t~ = 1e-4 at order 2.3 for every speed, its estimate 10 % short), so they are solved apart,
#: on EARLY_WALL_FOLDS (7e-9 on 256 cells; delta order 3.9), in a solve that stops at the last of them
#: (``_run``): a cluster that deep stalls BDF later on, the sooner the faster the plate (round-off in the
#: wall unknown; measured: 0.198 past 0.1 t~_mud, 1.334 0.07-0.1, 4.629 0.03-0.05), bench/RESULTS.md
#: "The early times on a deeper cluster"
EARLY_SPAN, EARLY_WALL_FOLDS = 0.04, 18.0
#: ... on at least EARLY_MIN_CELLS cells: on 64 its first cells grow up to 9x from one to the next, and BDF's
#: start fails (measured: t~_min = 1e-3, "step size less than spacing" at t~ = 8e-11 for every speed)
EARLY_MIN_CELLS = 128


def early_until(u_w: float, span: float = EARLY_SPAN) -> float:
    """The imposed speed's output times below this are solved on the map of EARLY_WALL_FOLDS (``span``: EARLY_SPAN,
    Numerics.early_span)."""
    return span * u_w**2 / max(1.0, u_w)


#: the least stretch of a speed's map: the map's slope at the bottom is ~a/N (the cluster's e^(-xi/w) has
#: died out there), so below it the cells crowd the bottom (a = 0: xi in [0.5, 1] maps onto y~ in [0.9, 1])
#: and the layer starves (measured: 0.198 from t~_min = 0.1, a = 0: delta's estimate 3e-5 on 256 cells,
#: 1e-6 unreachable on 512; a = 4: 4.7e-7, 1e-6 on 256 cells from t~_min = 0.01 and 0.1 for all three speeds)
CLUSTER_MIN_STRETCH = 4.0
#: default time tolerance: MATCHED_RTOL[method] on MATCHED_CELLS cells, scaled as n_cells^-order (measured:
#: the time error then stays below the space error of the mesh, bench/work_precision.py, bench/speed_solver.py)
MATCHED_RTOL, MATCHED_CELLS = dict.fromkeys(METHODS, 1e-8), 256
#: the loosest time tolerance of each method: scipy's BDF on the speed takes more steps, not fewer, above
#: it (measured: u~_w = 4.629 on 64 cells 894 steps at rtol 1e-8, 4389 at 1e-7; 1.334 on 256 cells 1432
#: and 8431); its time error there is ~1-20 rtol (landing on every output time: stepper)
MAX_RTOL = {**dict.fromkeys(METHODS, 1e-3), "bdf": 1e-8}
#: the loosest time tolerance of an estimate's companion (``Numerics.coarser``): its time error enters the estimate
#: (x SAFETY/(gain - 1)), and bdf's in a small speed's delta is ~500 rtol, not TIME_ERROR_PER_RTOL's 30 (delta is
#: read where mu - mu_s is 1e-3 of mu_w - mu_s, which is tiny: u~_w = 0.001 (beads), 256 cells at rtol 1e-8 and
#: 1e-10 differ by 4.9e-6 in delta at t~ = 0.1), so at MAX_RTOL it alone puts that speed's estimate at 1.0-1.1e-6
#: against 1e-6 asked; at 4e-9 at 5.7e-7, for 7 % more CPU at u~_w = 1.334 (bench/RESULTS.md "The speed's cost ...")
COMPANION_MAX_RTOL = {**MAX_RTOL, "bdf": 4e-9}
#: atol = ATOL_PER_RTOL rtol (tau~ is O(1))
ATOL_PER_RTOL = 1e-2
#: the first time step, as a fraction of the first output time
INITIAL_STEP = 1e-5
#: the two solves of an error estimate: the coarse one has 1/REFINEMENT of the cells (continuum.richardson) and
#: gain(drive) times the tolerance (every error gain times larger: of the drive's order in space,
#: tolerance-proportional in time)
ORDER_GAIN = REFINEMENT ** CONVERGENCE_ORDER["stress"]


def convergence_order(imposed: str, numerics: Numerics) -> int:
    """The order in space of a drive solved with these numerics (CONVERGENCE_ORDER, UNGRADED_SPEED_ORDER)."""
    if imposed == "speed" and numerics.stretch is not None and numerics.stretch < WALL_STRETCH:
        return UNGRADED_SPEED_ORDER
    return CONVERGENCE_ORDER[imposed]


def gain(imposed: str, numerics: Numerics) -> int:
    """The factor by which every error grows from a solve to its coarser companion."""
    return REFINEMENT ** convergence_order(imposed, numerics)

#: the Richardson estimate (continuum.richardson) times this bounds the true error (measured: the bare estimate
#: is within a factor 2 of it either way, tests/continuum/test_accuracy.py)
SAFETY = 3.0


@dataclass(frozen=True)
class Numerics:
    """Resolution and tolerances of one solve.  ``stretch=None``: the map follows the first output
    time (``map_for``), else the exponential map of this stretch; ``order``: of the spatial discretisation
    (continuum.mesh); ``method``: a registered one (continuum.integrators; a solve_ivp baseline, e.g.
    "solve_ivp-BDF", takes its own first step and records no per-step rows); ``method``, ``rtol``, ``atol`` = None:
    the drive's defaults (``for_drive``); ``compiled``: the
    loop and the problem's kernels compiled by numba (continuum.integrators; False: the same loop as Python, far
    slower, a reference);
    ``repeat_cap``: the DIRKs' step cap after a repeated Newton failure (continuum.stepper; False: the baseline);
    ``initial_step``: the first time step as a fraction of the first output time; ``early_span``: an imposed speed's
    output times before early_span t~_mud/max(1, u~_w) are solved on the deeper wall cluster (0: none, EARLY_SPAN);
    ``stall``: bdf's (fraction, steps) that hand over to the DIRK (continuum.bdf)."""

    n_cells: int = 64
    stretch: float | None = None
    rtol: float | None = None
    atol: float | None = None
    method: str | None = None
    order: int = 4
    compiled: bool = True
    repeat_cap: bool = True
    initial_step: float = INITIAL_STEP
    early_span: float = EARLY_SPAN
    stall: tuple[float, int] = (STALL_FRACTION, STALL_STEPS)

    def __post_init__(self):
        Mesh.graded(self.n_cells, 0.0 if self.stretch is None else self.stretch)  # validates both
        require(self.order in ORDERS, "order", f"one of {ORDERS}", self.order)
        require(self.method is None or self.method in METHODS, "method", f"one of {list(METHODS)}", self.method)
        for name in ("rtol", "atol"):
            value = getattr(self, name)
            require(value is None or (finite(value) and 0 < value < 1), name, "in (0, 1)", value)

    def for_drive(self, imposed: str) -> Numerics:
        """These numerics with the drive's defaults filled in: its method, and a time tolerance matched
        to the space error of this mesh (MATCHED_RTOL, scaled as n_cells^-order)."""
        method = self.method or DEFAULT_METHOD[imposed]
        scale = (MATCHED_CELLS / self.n_cells) ** convergence_order(imposed, self)
        rtol = self.rtol if self.rtol is not None else min(MATCHED_RTOL[method] * scale, MAX_RTOL[method])
        return replace(self, method=method, rtol=rtol,
                       atol=self.atol if self.atol is not None else rtol * ATOL_PER_RTOL)

    def mesh(self, stretch: float = 0.0, wall_folds: float = 0.0) -> Mesh:
        """The mesh of ``n_cells`` with this stretch, else the map of ``stretch`` and ``wall_folds``."""
        if self.stretch is not None:
            return Mesh.graded(self.n_cells, self.stretch)
        return Mesh.graded(self.n_cells, stretch, wall_folds)

    def coarser(self, factor: float) -> Numerics:
        """The estimate's companion: half the cells, ``factor`` times the tolerances up to COMPANION_MAX_RTOL (resolved
        numerics)."""
        rtol = min(self.rtol * factor, max(COMPANION_MAX_RTOL[self.method], self.rtol))
        return replace(self, n_cells=self.n_cells // REFINEMENT, rtol=rtol, atol=rtol * self.atol / self.rtol)

    def finer(self, factor: float, asked: Numerics, imposed: str) -> Numerics:
        """The next refinement: twice the cells, and the tolerances matched to them if ``asked`` (these
        numerics as given) left them to the defaults (a fixed factor would tighten a capped MAX_RTOL past
        the match: a speed on 512 cells at rtol 4e-11 stalls BDF near the steady state), else ``factor``
        times tighter."""
        if asked.rtol is None and asked.atol is None:
            return replace(asked, n_cells=self.n_cells * REFINEMENT).for_drive(imposed)
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


def stretch_for(delta: float, share: float = LAYER_SHARE) -> float:
    """The exponential map's stretch a that puts ``share`` of the xi-grid inside a layer of thickness delta:
    ln(1 + delta (e^a - 1)) = share a, unless its wall slope falls below WALL_SLOPE_FLOOR delta: then the a
    with a/(e^a - 1) = WALL_SLOPE_FLOOR delta."""
    if delta >= share:
        return 0.0
    a = _fixed_point(lambda a: math.log1p(math.expm1(share * a) / delta), 1.0)
    floor = WALL_SLOPE_FLOOR * delta
    if a / math.expm1(a) < floor:  # the wall slope y'(0) = a/(e^a - 1) of this map is below the floor
        a = _fixed_point(lambda a: math.log1p(a / floor), a)
    return float(min(a, MAX_STRETCH))


def map_for(fr: Friction, mu_w: float, imposed: str, t_min: float) -> tuple[float, float]:
    """The map (stretch, wall_folds) of a solve whose first output time is t_min (continuum.mesh): the
    stretch of the layer at t_min (``stretch_for``) of the short-time thickness delta ~ SELF_SIMILAR_DELTA
    Dmu mu~_w sqrt(t~) of a stress (the wall diffusivity is (Dmu mu~_w)^2), SELF_SIMILAR_DELTA Dmu sqrt(t~)
    of a speed (eq. (3.20), while mu_w = mu_d), at least CLUSTER_MIN_STRETCH; a speed's
    map gets a wall cluster up to WALL_FOLDS e-folds in all."""
    if imposed == "stress":
        return stretch_for(SELF_SIMILAR_DELTA * fr.dmu * max(fr.tilde(mu_w), 0.05) * math.sqrt(t_min)), 0.0
    a = max(stretch_for(SELF_SIMILAR_DELTA * fr.dmu * math.sqrt(t_min)), CLUSTER_MIN_STRETCH)
    return a, max(WALL_FOLDS - a, 0.0)


def check_times(times, name: str = "times") -> np.ndarray:
    """Output times: a non-empty, strictly increasing list of finite numbers > 0 (``name`` in the error)."""
    t = np.asarray(times, dtype=float).ravel()
    require(t.size > 0 and np.all(np.isfinite(t)) and np.all(t > 0) and np.all(np.diff(t) > 0),
            name, "a non-empty, strictly increasing list of finite numbers > 0",
            [float(v) for v in np.atleast_1d(times)])
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
    recorded: np.ndarray | obs.SeriesRecorder | obs.JoinedSeries  # the per-step rows, or what derives them
    stats: StepStats
    numerics: Numerics
    errors: dict = field(default_factory=dict)  # u_w, mu_w, delta -> absolute error estimates (aligned with t)
    accuracy: float | None = None               # the relative accuracy asked for (None: one solve)
    early_mesh: Mesh | None = None              # the map of the early output times, if apart (EARLY_SPAN)

    @cached_property
    def steps(self) -> np.ndarray:
        """Rows (t, u_w, mu_w, delta) at every accepted step, derived on first use (``series``)."""
        r = self.recorded
        return r.table() if isinstance(r, (obs.SeriesRecorder, obs.JoinedSeries)) else r

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
        return obs.friction_profile(self.friction, self.mu_w_inf, self.mesh, self.tau)

    @property
    def mu_tilde(self) -> np.ndarray:
        return self.friction.tilde(self.mu)

    @cached_property
    def velocity(self) -> np.ndarray:
        return obs.velocity(self.friction, self.mu_w_inf, self.mesh, self.tau, self.numerics.order,
                            wall_speed=self.u_w_imposed)

    @property
    def u_w(self) -> np.ndarray:
        return self.velocity[:, 0]

    @property
    def mu_w(self) -> np.ndarray:
        return self.mu[:, 0]

    @cached_property
    def delta(self) -> np.ndarray:
        return obs.layer_thickness(self.friction, self.mu_w_inf, self.mesh, self.tau, self.numerics.order)

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
                "stats": asdict(self.stats), "units": UNITS, "map": self.mesh.label,
                "early_map": None if self.early_mesh is None else {
                    "label": self.early_mesh.label,
                    "times_below": early_until(self.u_w_imposed, self.numerics.early_span)},
                "delta_definition": "depth where mu - mu_s falls to 1e-3 of mu_w(t) - mu_s",
                "provenance": provenance()}

    def profiles(self):
        """Long table (DataFrame): one row per (t, y~) with tau~, mu, mu~, u~."""
        import pandas as pd

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


#: the quantities whose accuracy is estimated and controlled, and the one each drive imposes (exact)
QUANTITIES = ("u_w", "mu_w", "delta")
IMPOSED = {"stress": "mu_w", "speed": "u_w"}
#: the range of relative accuracies that can be asked for
ACCURACY_RANGE = (1e-10, 1e-2)
#: refinement stops here (a request that needs more is refused with the accuracy reached): a speed on
#: 512 cells takes 0.2-0.6 s (compiled, its companion on 256 included); on 1024 its wall cells (7.6e-8) stall BDF by
#: round-off near the steady state (measured: u~_w = 0.198 not at t~ = 10 after 400 s, bench/RESULTS.md "One map
#: with a wall cluster"; compiled, 1.334 and the disks' 1.0 fail there too, "The speed compiled")
MAX_CELLS = {"stress": 2048, "speed": 512}
#: an estimated solve has at least this many cells: the companion of a speed on 64 cells (32) is
#: pre-asymptotic through the lift-off (measured: mu_w at u~_w = 1.334, t~ = 1 underestimated 1.5x)
MIN_ESTIMATED_CELLS = {"stress": 8, "speed": 128}
#: an accuracy request on the drive's own map, method and order starts from the cells that its error model (cells,
#: worst relative estimate there) predicts for it (``first_cells``), not from MIN_ESTIMATED_CELLS: the speed's worst
#: estimate on 512 cells over bench/speed_range.py's survey is 7.4-8.3e-7 (two runs of it), so 1e-6 starts there
#: (its companion on 256), and the 64- and 128-cell rungs that all but one of the survey's solves would climb
#: through from MIN_ESTIMATED_CELLS are skipped (1.2 s of 4.6 at u~_w = 1.334); a request beyond MAX_CELLS is
#: then refused after the solve on them
ERROR_MODEL = {"speed": (512, 1e-6)}


def round_up(x: float) -> float:
    """x > 0 rounded up to two significant digits (a bound printed at .1e stays a bound)."""
    scale = 10.0 ** (math.floor(math.log10(x)) - 1)
    return math.ceil(x / scale) * scale


def first_cells(imposed: str, accuracy: float) -> int:
    """The cells an accuracy request starts from: MIN_ESTIMATED_CELLS doubled while ERROR_MODEL (error ~ n^-order)
    predicts a finer mesh still too coarse for ``accuracy``."""
    n = MIN_ESTIMATED_CELLS[imposed]
    if imposed in ERROR_MODEL:
        cells, error = ERROR_MODEL[imposed]
        while n < MAX_CELLS[imposed] and error * (cells / n) ** CONVERGENCE_ORDER[imposed] > accuracy:
            n *= REFINEMENT
    return n


def _run_one(problem, t, numerics: Numerics, fixed_times=None, record=True) -> Solution:
    """One solve of ``problem`` at the output times t.  A solve_ivp baseline takes its own first step and steps
    unobserved (no per-step rows), and none of the package's options."""
    if REGISTERED[numerics.method].kind == "baseline":
        recorder, h0, options = None, None, {}
    else:
        recorder = obs.SeriesRecorder(problem) if record else None
        h0 = numerics.initial_step * t[0]
        options = {"repeat_cap": numerics.repeat_cap, **({"stall": numerics.stall} if numerics.method == "bdf" else {})}
    states, stats = integrate(problem, t, method=numerics.method, compiled=numerics.compiled, rtol=numerics.rtol,
                              atol=numerics.atol, h0=h0, fixed_times=fixed_times, observer=recorder, **options)
    tau = np.array([problem.full(x) for x in states])
    steps = recorder if recorder is not None else np.empty((0, 4))
    return Solution(problem.imposed, problem.friction, problem.mu_w,
                    getattr(problem, "u_w", None), problem.mesh, t, tau, steps, stats, numerics)


def _run(make_problem, t, numerics: Numerics, grading, early, fixed_times=None, record=True) -> Solution:
    """One solve on the map ``grading`` (stretch, wall_folds); the ``early`` output times (a mask) apart, on
    the map of EARLY_WALL_FOLDS, up to the last of them: their profiles resampled onto the solve's mesh
    (Mesh.resample: the wall node exact), their per-step rows up to it (observables.JoinedSeries)."""
    if not early.any():
        return _run_one(make_problem(numerics.mesh(*grading), numerics.order), t, numerics, fixed_times, record)
    t_early, stretch = t[early], grading[0]
    fixed_early = None if fixed_times is None else np.asarray(fixed_times)[np.asarray(fixed_times) <= t_early[-1]]
    deep = _run_one(make_problem(numerics.mesh(stretch, EARLY_WALL_FOLDS - stretch), numerics.order), t_early,
                    numerics, fixed_early, record)
    if early.all():
        return deep
    late = _run_one(make_problem(numerics.mesh(*grading), numerics.order), t[~early], numerics, fixed_times, record)
    return replace(late, t=t, tau=np.concatenate([deep.mesh.resample(deep.tau, late.mesh), late.tau]),
                   recorded=obs.JoinedSeries(deep.recorded, t_early[-1], late.recorded),
                   stats=deep.stats.add(late.stats), early_mesh=deep.mesh)


#: the global time error per unit rtol of each method, the floor of an estimate (measured: SDIRK4 on a
#: stress <= 1, against the independent reference; bdf on a speed up to ~30 in delta, ~6 in mu_w, against
#: rtol 1e-11 on the same mesh; bench/RESULTS.md)
TIME_ERROR_PER_RTOL = {**dict.fromkeys(METHODS, 1.0), "bdf": 30.0}


def _estimate(fine: Solution, coarse: Solution) -> dict:
    """Absolute error estimates of ``fine`` from its companion: Richardson's at the drive's order with SAFETY
    (continuum.richardson: SAFETY |fine - coarse|/(gain - 1)), plus a floor at the time error,
    TIME_ERROR_PER_RTOL rtol |fine| (below it the two solves' difference no longer measures the error;
    measured against the independent reference, u~_w at t~ = 0.1 for mu~_w = 0.5 on 128 cells, error
    1.6e-8 relative where rtol = 1.6e-7: without the floor the estimate falls 1.2x short); the imposed quantity
    (IMPOSED) is exact (a speed's constraint holds to round-off)."""
    order = convergence_order(fine.imposed, fine.numerics)
    floor = TIME_ERROR_PER_RTOL[fine.numerics.method] * fine.numerics.rtol
    out = {q: richardson(getattr(fine, q), getattr(coarse, q), order, SAFETY) + floor * np.abs(getattr(fine, q))
           for q in QUANTITIES}
    out[IMPOSED[fine.imposed]] = np.zeros(len(fine.t))
    return out


def _solve(make_problem, imposed, mu_w, friction, times, numerics, *, accuracy, estimate, fixed_times,
           early_below=0.0) -> Solution:
    t = check_times(times)
    numerics = numerics or Numerics()
    if accuracy is not None or estimate:
        numerics = replace(numerics, n_cells=max(numerics.n_cells, MIN_ESTIMATED_CELLS[imposed]))
    if accuracy is not None:
        require(finite(accuracy) and ACCURACY_RANGE[0] <= accuracy <= ACCURACY_RANGE[1], "accuracy",
                f"in [{ACCURACY_RANGE[0]:g}, {ACCURACY_RANGE[1]:g}]", accuracy)
        if numerics.stretch is None and numerics.method is None and numerics.order == Numerics.order:  # as measured
            numerics = replace(numerics, n_cells=max(numerics.n_cells, first_cells(imposed, accuracy)))
    asked, numerics = numerics, numerics.for_drive(imposed)
    order, factor, most = convergence_order(imposed, numerics), gain(imposed, numerics), MAX_CELLS[imposed]
    grading = map_for(friction, mu_w, imposed, t[0])
    early = (t < early_below) & (asked.stretch is None) & (grading[1] > 0)  # a map with a wall cluster

    def run(num, record=True):
        return _run(make_problem, t, num, grading, early & (num.n_cells >= EARLY_MIN_CELLS), fixed_times, record)

    if accuracy is None and not estimate:
        return run(numerics)
    coarse = run(numerics.coarser(factor), record=False)
    while True:
        fine = run(numerics)
        errors = _estimate(fine, coarse)
        worst = max(float(np.max(errors[q] / np.abs(getattr(fine, q)))) for q in QUANTITIES)
        if accuracy is None or worst <= accuracy:
            return replace(fine, errors=errors, accuracy=accuracy)
        needed = numerics.n_cells * (worst / accuracy) ** (1 / order)
        require(needed <= most and numerics.n_cells * REFINEMENT <= most, "accuracy",
                f">= {round_up(worst * (numerics.n_cells / most) ** order):.1e} for this request "
                f"(reachable with at most {most} cells)", accuracy)
        numerics, coarse = numerics.finer(factor, asked, imposed), fine


def solve_stress(friction: Friction, mu_w: float, times, numerics: Numerics | None = None, *,
                 accuracy: float | None = None, estimate: bool = False, fixed_times=None) -> Solution:
    """Imposed wall stress: eq. (2.15) with tau~(0) = tau~(1) = 1.  ``accuracy``: refine
    (from ``numerics``) until every estimated relative error is below it; None: one solve as given,
    with error estimates (from the coarser companion solve) if ``estimate``."""
    mu_w = friction.check_mu_w(mu_w)
    return _solve(lambda mesh, order: ImposedStress(friction, mu_w, mesh, order), "stress", mu_w, friction, times,
                  numerics, accuracy=accuracy, estimate=estimate, fixed_times=fixed_times)


def solve_speed(friction: Friction, u_w: float, times, numerics: Numerics | None = None, *,
                accuracy: float | None = None, estimate: bool = False, fixed_times=None) -> Solution:
    """Imposed wall speed: eq. (3.14) with the integral condition
    eq. (3.15) (``accuracy``, ``estimate`` as for solve_stress)."""
    mu_w = mu_w_for_speed(friction, u_w)
    return _solve(lambda mesh, order: ImposedSpeed(friction, u_w, mesh, order), "speed", mu_w, friction, times,
                  numerics, accuracy=accuracy, estimate=estimate, fixed_times=fixed_times,
                  early_below=early_until(u_w, (numerics or Numerics()).early_span))
