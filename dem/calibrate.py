"""``granstokes dem calibrate``: mu(I) and phi(I) of a config's grains by homogeneous plane shear.

Protocol (the config's ``[calibration]`` table, dem.config.Calibration; scene: dem.shear):

* the grains are the config's own ``[grains]`` table with the contact law and stiffness derived as
  for the Stokes scene (dem.contact, k_n from kappa and p_w), sheared at the normal stress p = p_w
  (so that the rigidity number is the scene's kappa) with the scene's time step;
* ``points`` inertial numbers log-spaced in [I_min, I_max] (or the list ``I``); I in the DEM convention,
  I = gamma_dot d/sqrt(p/rho_p), gamma_dot = |du/dy| (d = rho_p = 1);
* each point and seed: an independent cell (insertion with that seed), sheared ``strain_start``
  (discarded), then at least ``strain`` more, sampled every ``sample`` of strain; above
  STRAIN_REFERENCE_I the measured strain grows as I (constant cost per point) up to ``strain_max``:
  those points cost little and the fast end of the law (mu_d, I0) needs their precision;
* errors: blocks of BLOCK_TAU integrated autocorrelation times (the longer of mu's and phi's; at least
  MIN_BLOCKS blocks), and independent seeds (continuum.calibration bootstraps over both);
* checks of every point and seed (all must pass for it to enter the fit): measured strain >= strain,
  no drift (first and second halves of the blocks agree within DRIFT_Z standard errors in mu and phi),
  <P_yy> = p within PRESSURE_Z standard errors, velocity profile linear (largest deviation from the
  linear fit below HOMOGENEITY_TOL of the velocity difference across the cell), blocks longer than the
  autocorrelation time (the MIN_BLOCKS cap can make them shorter when the window is too short), and dense
  flow (``kinetic_fraction``: the kinetic part of P_yy at most KINETIC_MAX of P_yy); calibration.json lists
  the excluded cells (``excluded``) and, with their kinetic fraction, those that are not dense (``not_dense``);
* finite size (``finite_size`` of the table): at each of those points one more cell of twice the width,
  with the first seed and a start FINITE_SIZE_START times longer, compared with the same seed's cell of the
  fit (``finite_size_record``); never fitted;
* shear modulus (``modulus`` of the table, default on): per seed (the calibration's, at least dem.modulus.MIN_SEEDS)
  the same cell at rest under sigma_yy = p, sheared at two small amplitudes (dem.modulus); calibration.json's
  ``elasticity`` (G, c_s, the affine estimate, the linearity check) and DIR/modulus.png.

Output (dem.layout): DIR/calibration.json, DIR/points.csv, DIR/state.json (``points``: the shear cells, ``modulus``:
the modulus cells), DIR/I-K/seed-S/, DIR/finite-size/I-K/seed-S/, DIR/modulus/seed-S/, DIR/modulus.png.  Every cell
(the doubled and modulus ones too) is a task of the project's executor (granstokes.lib.executor: ``jobs`` LAMMPS
processes at once, longest first, a failed cell retried once); ``resume`` reruns the unfinished ones (a cell restarts
from its insertion: cells are short).  A calibration whose fit is written (calibration.json, every shear cell
complete) keeps it: a resume runs only the modulus cells it lacks (never a shear cell, nor their analysis and fit)
and rewrites calibration.json with ``elasticity`` added, every other key as it was.
"""
from __future__ import annotations

import dataclasses
import datetime as _dt
import json
import math
import shutil
import signal
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from granstokes.continuum import calibration as fitting

from granstokes.lib import staging
from granstokes.lib.executor import Executor, Outcome, Task
from granstokes.lib.provenance import provenance
from granstokes.lib.statistics import autocorrelation_time
from granstokes.lib.toml_text import with_entries
from granstokes.lib.validate import require

from . import lammps_env, layout
from . import modulus as modulus_cell
from .config import Config, Grains, parse
from .contact import Contact, mean_grain_volume
from .estimate import Estimate, duration_text
from .lammps_env import DEFAULT_JOBS, DEFAULT_NP
from .runner import Interrupted, RunError, _Lammps, allow_lammps, sigterm_interrupts, stop_all_lammps
from .shear import COMPRESS_MAX, COMPRESS_RATE, PRE_PACKING, SQUEEZE_TIME, ShearPoint, shear_script
from .sizing import OVERHEAD, PACKING, count, makespan, speedup
from .throughput import Throughput, measured

#: the command whose manifest marks a folder as this module's output (granstokes.staging)
COMMAND = "dem calibrate"

BLOCK_TAU = 3.0
MIN_BLOCKS = 6
DRIFT_Z = 3.0
PRESSURE_Z = 3.0
HOMOGENEITY_TOL = 0.1
#: the measured window is lengthened by this fraction so that the box-measured strain (L_y moves
#: under the pressure control) still reaches ``strain``
STRAIN_MARGIN = 0.03
STRAIN_REFERENCE_I = 0.05
#: dense flow: the kinetic (streaming) part of P_yy is at most this fraction of P_yy (kinetic_fraction)
KINETIC_MAX = 0.1
DENSE_CRITERION = f"kinetic part of P_yy <= {KINETIC_MAX:g} P_yy"
#: a finite-size cell discards this many times ``strain_start``: its start transient lasts longer (quick's grains at
#: I = 0.46: the dilation from the compressed packing overshoots to phi = 0.39-0.45 and phi settles after a strain of
#: 4-6 in the doubled cell, ~1 in the normal one; at I = 0.1 neither overshoots)
FINITE_SIZE_START = 5.0
#: bytes a cell's folder holds (its LAMMPS log, series, profile and blocks): a fixed part and one per step (its log
#: and series grow with the steps), from the smoke calibration's cells (2.1e5 at 3.4e5 steps) and the quick
#: preset's (3.2e5 at 7.7e5 steps); bench/dem_costs.py measures a calibration's folder against the estimate
CELL_BYTES, CELL_BYTES_PER_STEP = 1.2e5, 0.26
#: bytes of a modulus cell's folder: a fixed part (the two oscillation series of CYCLES x SAMPLES_PER_CYCLE rows, the
#: script, the log's other runs) and one per check of its rest (each a LAMMPS run's summary in the log); the committed
#: calibrations' 12 cells held 0.35-1.1 MB, 0.6-1.5 of this estimate (their steps: 0.7-1.3 of modulus_steps)
MODULUS_BYTES, MODULUS_BYTES_PER_CHECK = 1.2e5, 2.5e3
#: the strain a modulus cell's rest recompresses at its gain: the compression's last check overshoots p while the
#: grains still collide, and at rest that packing loses its stress; measured 0.02-0.03 (disks p = 20, spheres p = 10)
MODULUS_REST_STRAIN = 0.03
#: where state.json's message gives the modulus after the fit's
MODULUS_MESSAGE = "; G = "
#: seconds of the fit and its bootstrap after the cells (1-2 s for 7-14 points x 1-3 seeds, measured)
FIT_SECONDS = 2.0


@dataclass(frozen=True)
class CalibrationPlan:
    """Sizes and step counts of a calibration, derived once from a validated Config."""

    config: Config
    dt: float
    n_grains: int
    points: tuple[ShearPoint, ...]
    finite_size: tuple[int, ...] = ()  # the points with a doubled cell (calibration.finite_size)

    @property
    def seeds(self) -> tuple[int, ...]:
        return self.config.calibration.seeds

    @property
    def doubled_config(self) -> Config:
        """The config of the finite-size cells: the calibration's width doubled."""
        cal = self.config.calibration
        return dataclasses.replace(self.config, calibration=dataclasses.replace(cal, width=2 * cal.width))

    @property
    def n_doubled(self) -> int:
        return _grains(self.doubled_config)

    @property
    def modulus(self) -> modulus_cell.ModulusCell | None:
        """The modulus cells' oscillation (dem.modulus), None when the table leaves the modulus out."""
        return modulus_cell.plan_cell(self.config, self.dt) if self.config.calibration.modulus else None

    @property
    def modulus_seeds(self) -> tuple[int, ...]:
        """The modulus cells' seeds: the calibration's, completed to dem.modulus.MIN_SEEDS (none without modulus)."""
        return modulus_cell.modulus_seeds(self.seeds) if self.config.calibration.modulus else ()

    @staticmethod
    def modulus_key(seed: int) -> str:
        """state.json's key (under ``modulus``) of the modulus cell of ``seed``."""
        return f"{layout.MODULUS}/seed-{seed}"

    @property
    def modulus_steps(self) -> int:
        """A modulus cell's expected steps: the squeeze and compression, the rest's recompression
        (MODULUS_REST_STRAIN at its gain), the drained and undamped rests, the oscillations."""
        cell = self.modulus
        rest = round(MODULUS_REST_STRAIN / cell.relax_gain / self.dt)
        return round(SQUEEZE_TIME / self.dt) + cell.expected_steps(self.compress_steps + rest)

    @property
    def modulus_bytes(self) -> float:
        """A modulus cell's expected folder size (MODULUS_BYTES, MODULUS_BYTES_PER_CHECK)."""
        cell = self.modulus
        checks = MODULUS_REST_STRAIN / cell.relax_gain / self.dt / cell.relax_check
        return MODULUS_BYTES + MODULUS_BYTES_PER_CHECK * checks

    def modulus_seconds(self, speed: Throughput | None = None) -> float:
        """Expected LAMMPS wall time of one modulus cell alone at one rank (the shear cells' rate per grain-step)."""
        speed = speed or measured()
        return self.n_grains * self.modulus_steps / speed.rate(self.config.grains.dimension, "shear")

    def keys(self) -> list[str]:
        """Every cell's key: the shear cells' (``cells``), then the modulus cells'."""
        return [self.key(*c) for c in self.cells()] + [self.modulus_key(s) for s in self.modulus_seeds]

    def tasks(self) -> list[tuple[int, int]]:
        """The fit's cells (point index, seed), longest first (smallest I), so that concurrent jobs finish together."""
        order = sorted(range(len(self.points)), key=lambda k: -self.steps(k))
        return [(k, s) for k in order for s in self.seeds]

    def cells(self) -> list[tuple[int, int, bool]]:
        """Every cell (point index, seed, doubled): the fit's and the finite-size check's, longest first."""
        cells = [(k, s, False) for k, s in self.tasks()] + [(k, self.seeds[0], True) for k in self.finite_size]
        return sorted(cells, key=lambda c: -self.task_seconds(c[0], c[2]))

    def point(self, k: int, doubled: bool = False) -> ShearPoint:
        """Point ``k``, or its doubled cell's (the longer start, FINITE_SIZE_START)."""
        p = self.points[k]
        return dataclasses.replace(p, start_steps=round(FINITE_SIZE_START * p.start_steps)) if doubled else p

    def steps(self, k: int, doubled: bool = False) -> int:
        p = self.point(k, doubled)
        return round(SQUEEZE_TIME / self.dt) + p.start_steps + p.measure_steps

    @staticmethod
    def key(k: int, seed: int, doubled: bool = False) -> str:
        """state.json's key of point ``k`` and ``seed`` (or of its doubled cell)."""
        return f"{layout.FINITE_SIZE}/I-{k}/seed-{seed}" if doubled else f"I-{k}/seed-{seed}"

    @property
    def compress_steps(self) -> int:
        """A cell's expected compression to p: from PRE_PACKING to the material's phi at COMPRESS_RATE."""
        phi = self.config.material.phi / PRE_PACKING[self.config.grains.dimension]
        return round(min(COMPRESS_MAX, math.log(max(1.0, phi)) / COMPRESS_RATE) / self.dt)

    def task_seconds(self, k: int, doubled: bool = False, speed: Throughput | None = None) -> float:
        """Expected LAMMPS wall time of one cell of point ``k`` run alone at one rank at ``speed`` (default: this
        machine's, dem.throughput.measured)."""
        steps = self.steps(k, doubled) + self.compress_steps
        n = self.n_doubled if doubled else self.n_grains
        return n * steps / (speed or measured()).rate(self.config.grains.dimension, "shear")

    def grain_steps(self) -> int:
        """Grain-steps of every cell's shear (compression aside)."""
        return sum((self.n_doubled if dbl else self.n_grains) * self.steps(k, dbl) for k, _, dbl in self.cells())

    def cost_seconds(self, jobs: int = DEFAULT_JOBS, np_: int = DEFAULT_NP, done=(),
                     speed: Throughput | None = None) -> float:
        """Expected wall time of the calibration (or of the cells left: ``done`` holds the complete keys), each cell
        on ``np_`` ranks (its modelled speedup)."""
        speed, dim = speed or measured(), self.config.grains.dimension
        work = [self.task_seconds(k, dbl, speed) / speedup(self.n_doubled if dbl else self.n_grains, dim, np_)
                for k, seed, dbl in self.cells() if self.key(k, seed, dbl) not in done]
        work += [self.modulus_seconds(speed) / speedup(self.n_grains, dim, np_) for seed in self.modulus_seeds
                 if self.modulus_key(seed) not in done]
        return OVERHEAD + makespan(sorted(work, reverse=True), jobs, np_, contention=speed.contention)

    def estimate(self, jobs: int = DEFAULT_JOBS, np_: int = DEFAULT_NP, done=(),
                 speed: Throughput | None = None) -> Estimate:
        """The calibration's wall time (``cost_seconds`` and its fit) and the bytes of its cells left (CELL_BYTES
        each and CELL_BYTES_PER_STEP)."""
        left = [(k, dbl) for k, seed, dbl in self.cells() if self.key(k, seed, dbl) not in done]
        disk = sum(CELL_BYTES + CELL_BYTES_PER_STEP * (self.steps(k, dbl) + self.compress_steps) for k, dbl in left)
        left_modulus = sum(self.modulus_key(s) not in done for s in self.modulus_seeds)
        disk += self.modulus_bytes * left_modulus if left_modulus else 0.0
        return Estimate().plus("calibration", self.cost_seconds(jobs, np_, done, speed) + FIT_SECONDS, disk)

    def cost_estimate(self, jobs: int = DEFAULT_JOBS, np_: int = DEFAULT_NP, done=(),
                      speed: Throughput | None = None) -> str:
        """One line: the calibration's size and its expected wall time on this machine."""
        speed = speed or measured()
        if all(key in done for key in self.keys()):
            return "cost: none, every point is complete"
        left = " of what is left" if done else ""
        doubled = (f" and {len(self.finite_size)} finite-size cell(s) of {self.n_doubled}" if self.finite_size
                   else "")
        if self.modulus_seeds:
            doubled += f" and {len(self.modulus_seeds)} modulus cell(s) (~{count(self.modulus_steps)} steps each)"
        return (f"cost: {len(self.tasks())} cells of {self.n_grains} grains{doubled}, each compressing ~"
                f"{count(self.compress_steps)} steps first; about "
                f"{duration_text(self.cost_seconds(jobs, np_, done, speed))}{left} with {jobs} job(s) x {np_} rank(s) "
                f"(one process alone at one rank: {speed.describe(self.config.grains.dimension)})")

    def summary(self, out) -> str:
        """One line: what the calibration measures, and where."""
        c = self.config.calibration
        doubled = f" (+ {len(self.finite_size)} cell(s) twice as wide)" if self.finite_size else ""
        if self.modulus_seeds:
            doubled += f" (+ the shear modulus, {len(self.modulus_seeds)} seeds)"
        shape = "disks" if self.config.grains.dimension == 2 else "spheres"
        return (f"dem calibrate: '{self.config.name}' grains ({self.config.grains.dimension}D {shape}), "
                f"{len(self.points)} inertial numbers in [{c.I_min:g}, "
                f"{c.I_max:g}] x {len(c.seeds)} seed(s){doubled}, {self.n_grains} grains at p = {self.config.p_w:g}, "
                f"{self.as_dict()['total_steps']:.3g} steps -> {out}")

    def as_dict(self) -> dict:
        cal = self.config.calibration
        return {"p": self.config.p_w, "dt": self.dt, "n_grains": self.n_grains, "width": cal.width,
                "dimension": self.config.grains.dimension, "seeds": list(cal.seeds),
                "strain_start": cal.strain_start, "strain": cal.strain, "sample_strain": cal.sample,
                "strain_max": cal.strain_max,
                "points": [{"I": p.I, "rate": p.rate, "start_steps": p.start_steps, "measure_steps": p.measure_steps,
                            "sample_steps": p.sample} for p in self.points],
                "total_steps": sum(self.steps(k, dbl) for k, _, dbl in self.cells()),
                "finite_size": {"I": [self.points[k].I for k in self.finite_size], "points": list(self.finite_size),
                                "seed": self.seeds[0], "width": 2 * cal.width, "n_grains": self.n_doubled,
                                "start_steps": [self.point(k, True).start_steps for k in self.finite_size]},
                "block": f"{BLOCK_TAU:g} integrated autocorrelation times (the longer of mu's and phi's), at least "
                         f"{MIN_BLOCKS} blocks",
                "checks": f"strain >= {cal.strain:g}; drift of mu and phi between halves < {DRIFT_Z:g} s.e.; "
                          f"|<P_yy> - p| < {PRESSURE_Z:g} s.e.; velocity profile within {HOMOGENEITY_TOL:g} of linear; "
                          f"blocks longer than the autocorrelation time; dense: {DENSE_CRITERION}",
                "I_convention": "dem: I = gamma_dot d/sqrt(p/rho_p), gamma_dot = |du/dy|"}


def _grains(cfg: Config) -> int:
    """Grains of a calibration cell of the config's width (square in 2D, cubic in 3D) at sizing.PACKING."""
    cal, dim = cfg.calibration, cfg.grains.dimension
    lz = cal.width if dim == 3 else 1.0
    return round(PACKING[dim] * cal.width**2 * lz / mean_grain_volume(cfg.grains.polydispersity, dim))


def plan_calibration(cfg: Config) -> CalibrationPlan:
    cal, dt = cfg.calibration, cfg.time_step
    points = []
    strain_max = cal.strain if cal.strain_max is None else cal.strain_max
    for I in cal.inertial_numbers:
        strain = min(strain_max, max(cal.strain, cal.strain * I / STRAIN_REFERENCE_I))
        rate = float(I) * math.sqrt(cfg.p_w)  # d = rho_p = 1
        per_strain = 1.0 / (rate * dt)
        sample = max(1, round(cal.sample * per_strain))
        profile = max(1, round(cal.profile / cal.sample)) * sample
        measure = math.ceil(strain * (1 + STRAIN_MARGIN) * per_strain / profile) * profile
        start = math.ceil(cal.strain_start * per_strain)
        points.append(ShearPoint(float(I), rate, dt, start, measure, sample, profile))
    doubled = tuple(min(range(len(points)), key=lambda k: abs(math.log(points[k].I / I))) for I in cal.finite_size)
    return CalibrationPlan(cfg, dt, _grains(cfg), tuple(points), doubled)


# --- analysis of one point and seed ------------------------------------------------------------------
def _samples(folder: Path) -> pd.DataFrame:
    """Per-sample tau, p, phi and the shear rate from the box (xy unwrapped across flips)."""
    s = pd.read_csv(folder / layout.SHEAR_SERIES_CSV)
    dxy = np.diff(s.xy.to_numpy())
    dxy -= s.lx.to_numpy()[1:] * np.round(dxy / s.lx.to_numpy()[1:])
    ly = 0.5 * (s.ly.to_numpy()[1:] + s.ly.to_numpy()[:-1])
    out = s.iloc[1:].reset_index(drop=True)
    return pd.DataFrame({"strain": np.cumsum(dxy / ly), "rate": dxy / ly / np.diff(s.t.to_numpy()),
                         "tau": -out.p_xy, "p": out.p_yy, "p_kin": out.p_yy_kin, "phi": out.phi})


def kinetic_fraction(samples: pd.DataFrame) -> float:
    """<kinetic part of P_yy>/<P_yy> over the measured window: the dense-flow indicator (dense if at most
    KINETIC_MAX).

    mu(I) is the law of dense flow, where the stress is carried by enduring contacts (the contact virial) and
    the grains' agitation carries little; as I grows the cell turns into a sheared granular gas whose stress is
    the streaming part n T of kinetic theory plus brief collisions, which a local mu(I) does not describe.  The
    kinetic part of the measured P_yy is exact in the cell (``compute pressure ... ke`` on the velocities
    relative to the streaming profile: the same split as p itself) and needs neither a fitted quantity (phi
    against phi_max) nor a contact criterion (a coordination number).  KINETIC_MAX = 0.1: at least 90 % of the
    normal stress passes through contacts."""
    return float(samples.p_kin.mean() / samples.p.mean())


def _profile_deviation(folder: Path, rate: float, ly: float) -> float:
    """Largest |u - linear fit| of the window-averaged velocity profile over rate * L_y."""
    rows = [line.split() for line in (folder / layout.SHEAR_PROFILE_TXT).read_text().splitlines()
            if not line.startswith("#") and len(line.split()) == 4]
    prof = pd.DataFrame(rows, columns=["chunk", "y", "count", "vx"]).astype(float).groupby("y").vx.mean()
    y, u = prof.index.to_numpy() * ly, prof.to_numpy()
    fit = np.polyval(np.polyfit(y, u, 1), y)
    return float(np.max(np.abs(u - fit)) / (rate * ly))


def analyse(folder: Path, cfg: Config, point: ShearPoint, seed: int) -> tuple[dict, pd.DataFrame, dict]:
    """(points.csv row, block means, checks) of one point and seed."""
    s = _samples(folder)
    # the slowest of the measured quantities sets the block length (phi relaxes more slowly than mu)
    # 1 + 2 sum rho = 2 tau of granstokes.statistics (Sokal's window)
    tau_int = 2 * max(autocorrelation_time((s.tau / s.p).to_numpy()), autocorrelation_time(s.phi.to_numpy()))
    length = max(1, min(math.ceil(BLOCK_TAU * tau_int), len(s) // MIN_BLOCKS))
    nb = len(s) // length
    blocks = (s.iloc[:nb * length].groupby(np.arange(nb * length) // length)[["tau", "p", "phi", "rate"]].mean()
              .reset_index(names="block"))
    I_b, mu_b = blocks.rate / np.sqrt(blocks.p), blocks.tau / blocks.p

    def mean_err(x):
        return float(np.mean(x)), float(np.std(x, ddof=1) / math.sqrt(len(x)))

    (I, I_err), (mu, mu_err), (phi, phi_err), (p, p_err) = (mean_err(x) for x in (I_b, mu_b, blocks.phi, blocks.p))
    half = nb // 2
    drift = {}
    for name, x in (("mu", mu_b), ("phi", blocks.phi)):
        (a, ea), (b, eb) = mean_err(x[:half]), mean_err(x[half:])
        drift[name] = float(abs(a - b) / math.hypot(ea, eb))
    strain = float(s.strain.iloc[-1])
    ly = float(pd.read_csv(folder / layout.SHEAR_SERIES_CSV).ly.mean())
    deviation = _profile_deviation(folder, float(s.rate.mean()), ly)
    checks = {"strain": strain, "strain_ok": strain >= cfg.calibration.strain,
              "drift_z": drift, "drift_ok": max(drift.values()) < DRIFT_Z,
              "p_mean": p, "p_err": p_err, "pressure_ok": abs(p - cfg.p_w) < PRESSURE_Z * p_err,
              "profile_deviation": deviation, "homogeneous_ok": deviation < HOMOGENEITY_TOL,
              "tau_int_strain": tau_int * cfg.calibration.sample, "blocks": nb,
              "block_strain": length * cfg.calibration.sample, "kinetic_fraction": kinetic_fraction(s)}
    checks["blocks_ok"] = checks["block_strain"] >= checks["tau_int_strain"]
    checks["dense_ok"] = checks["kinetic_fraction"] <= KINETIC_MAX
    checks["passed"] = all(checks[k] for k in ("strain_ok", "drift_ok", "pressure_ok", "homogeneous_ok", "blocks_ok",
                                               "dense_ok"))
    row = {"I": I, "I_err": I_err, "mu": mu, "mu_err": mu_err, "phi": phi, "phi_err": phi_err, "p": p,
           "strain": strain, "seed": seed}
    return row, blocks.assign(seed=seed), checks


# --- running -----------------------------------------------------------------------------------------
def _now() -> str:
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")


def run_cell(out: str, k: int, seed: int, np_: int, launcher: str | None, progress: bool, position: int) -> Outcome:
    """The executor's task: the plane-shear cell of point ``k`` and ``seed`` of the calibration folder ``out`` (its
    plan rebuilt from the stored config); a complete cell is re-analysed from its stored series (the fit uses the
    current analysis).  Its entry in state.json is written under the folder's lock."""
    return _run_cell(Path(out), k, seed, False, np_, launcher, progress, position)


def run_finite_size_cell(out: str, k: int, seed: int, np_: int, launcher: str | None, progress: bool,
                         position: int) -> Outcome:
    """The executor's task: as ``run_cell``, the cell twice as wide of the finite-size check."""
    return _run_cell(Path(out), k, seed, True, np_, launcher, progress, position)


def _run_cell(out: Path, k: int, seed: int, doubled: bool, np_: int, launcher: str | None, progress: bool,
              position: int) -> Outcome:
    plan = plan_calibration(parse((out / layout.CONFIG_TOML).read_text()))
    cfg, n = (plan.doubled_config, plan.n_doubled) if doubled else (plan.config, plan.n_grains)
    state_path, key = out / layout.CALIBRATION_STATE, plan.key(k, seed, doubled)
    d, point = layout.point_dir(out / layout.FINITE_SIZE if doubled else out, k, seed), plan.point(k, doubled)
    old = json.loads(state_path.read_text())["points"].get(key, {})

    def store(entry):
        staging.update_json(state_path, lambda doc: doc["points"].update({key: entry}))

    def analysed(entry):
        row, blocks, checks = analyse(d, cfg, point, seed)
        blocks.assign(point=k)[list(layout.BLOCK_COLUMNS)].to_csv(d / layout.BLOCKS_CSV, index=False)
        return {**entry, "row": row, "checks": checks}

    if old.get("status") == "complete":
        store(analysed(old))
        return Outcome("complete")
    _fresh(d)
    (d / layout.SHEAR_IN).write_text(shear_script(cfg, point, n, seed))
    store({"status": "running", "I_target": point.I, "started": _now()})
    entry = {"status": "interrupted", "I_target": point.I, "message": "continue with --resume"}
    try:
        with staging.locked(d):
            desc = f"I={point.I:.3g} seed {seed}" + (" (2x wide)" if doubled else "")
            info = _Lammps(np_, launcher, progress).run(layout.SHEAR_IN, d, plan, plan.steps(k, doubled), 0, desc,
                                                        position=position)
            entry = analysed({"status": "complete", "I_target": point.I, "wall_time": info["wall_time"],
                              "steps": info["last_step"]})
    except RunError as exc:
        entry = {"status": "failed", "I_target": point.I, "message": str(exc)}
    except (Interrupted, KeyboardInterrupt):
        pass
    finally:
        store(entry)
    return Outcome(entry["status"], entry.get("message", ""))


def _fresh(d: Path) -> None:
    """An empty cell folder ``d``: a cell left running there by a stopped calibration elsewhere ends first."""
    if d.exists():
        with staging.locked(d):
            pass
        shutil.rmtree(d)
    d.mkdir(parents=True)


def run_modulus_cell(out: str, seed: int, np_: int, launcher: str | None, progress: bool, position: int) -> Outcome:
    """The executor's task: the modulus cell of ``seed`` (dem.modulus) of the calibration folder ``out``; a complete
    cell is re-analysed from its series when they are there (else its stored record stands).  Its entry in
    state.json's ``modulus`` is written under the folder's lock; a cell stopped before its end restarts from its
    insertion."""
    out = Path(out)
    plan = plan_calibration(parse((out / layout.CONFIG_TOML).read_text()))
    cell, state_path, key = plan.modulus, out / layout.CALIBRATION_STATE, plan.modulus_key(seed)
    d = layout.modulus_dir(out, seed)
    old = json.loads(state_path.read_text()).get("modulus", {}).get(key, {})

    def store(entry):
        staging.update_json(state_path, lambda doc: doc.setdefault("modulus", {}).update({key: entry}))

    def analysed(entry):
        return {**entry, "record": {**modulus_cell.analyse_cell(d, cell, seed), "wall_time": entry.get("wall_time"),
                                    "steps": entry.get("steps")}}

    if old.get("status") == "complete":
        series = [d / layout.STATIC_CSV] + [d / layout.modulus_series_csv(k) for k in range(len(cell.amplitudes))]
        if all(f.is_file() for f in series):
            store(analysed(old))
        return Outcome("complete")
    _fresh(d)
    (d / layout.SHEAR_IN).write_text(modulus_cell.modulus_script(plan.config, cell, plan.n_grains, seed))
    store({"status": "running", "started": _now()})
    entry = {"status": "interrupted", "message": "continue with --resume"}
    try:
        with staging.locked(d):
            info = _Lammps(np_, launcher, progress).run(layout.SHEAR_IN, d, plan, plan.modulus_steps, 0,
                                                        f"modulus seed {seed}", position=position)
            entry = analysed({"status": "complete", "wall_time": info["wall_time"], "steps": info["last_step"]})
    except RunError as exc:
        entry = {"status": "failed", "message": str(exc)}
    except (Interrupted, KeyboardInterrupt):
        pass
    finally:
        store(entry)
    return Outcome(entry["status"], entry.get("message", ""))


def elasticity_record(plan: CalibrationPlan, state: dict, mu_s: float) -> dict:
    """calibration.json's ``elasticity`` from state.json's complete modulus cells (dem.modulus.elasticity), with
    their cost and the code that analysed them."""
    entries = [state["modulus"][plan.modulus_key(s)] for s in plan.modulus_seeds]
    walls = [e.get("wall_time") or 0.0 for e in entries]
    cost = {"lammps_cpu_seconds": sum(walls), "seconds_per_cell": walls,
            "steps_per_cell": [e.get("steps") for e in entries], "n_grains": plan.n_grains}
    per_seed = [{k: v for k, v in e["record"].items() if k not in ("wall_time", "steps")} for e in entries]
    record = modulus_cell.elasticity(per_seed, plan.config, plan.modulus, mu_s, cost)
    return {**record, "analysed_by": provenance()["git"]}


def _write_elasticity(plan: CalibrationPlan, out: Path, state: dict, doc: dict) -> dict:
    """``doc`` (calibration.json's content) with ``elasticity`` set, written, and modulus.png beside it."""
    doc["elasticity"] = elasticity_record(plan, state, doc["mu_s"])
    staging.write_json(out / layout.CALIBRATION_JSON, doc)
    modulus_cell.modulus_figure([(plan.config.p_w, doc["elasticity"])], out / layout.MODULUS_PNG,
                                f"{plan.config.name}: shear modulus of the static packing")
    return doc["elasticity"]


def not_dense(plan: CalibrationPlan, state: dict) -> list[dict]:
    """calibration.json's ``not_dense``: every cell of the fit that is not dense flow, with its indicator and
    the threshold (``kinetic_fraction``)."""
    out = []
    for k, seed in sorted(plan.tasks()):
        key = plan.key(k, seed)
        entry = state["points"][key]
        if not entry["checks"]["dense_ok"]:
            fraction = entry["checks"]["kinetic_fraction"]
            out.append({"key": key, "I_target": plan.points[k].I, "I": entry["row"]["I"], "kinetic_fraction": fraction,
                        "threshold": KINETIC_MAX,
                        "reason": f"kinetic part of P_yy {fraction:.3g} P_yy > {KINETIC_MAX:g} P_yy: not dense flow"})
    return out


def finite_size_record(plan: CalibrationPlan, state: dict) -> dict:
    """calibration.json's ``finite_size``: at each point of the check, mu and phi (with their block errors) of the
    first seed's cell and of its doubled cell, and their differences in units of the combined error, z =
    (doubled - normal)/hypot(err_normal, err_doubled)."""
    seed, points = plan.seeds[0], []
    for k in plan.finite_size:
        record = {}
        for name, doubled in (("normal", False), ("doubled", True)):
            key = plan.key(k, seed, doubled)
            entry = state["points"][key]
            record[name] = {"key": key, "passed": entry["checks"]["passed"],
                            **{q: entry["row"][q] for q in ("I", "I_err", "mu", "mu_err", "phi", "phi_err")}}
        a, b = record["normal"], record["doubled"]
        points.append({"I_target": plan.points[k].I, **record,
                       **{f"z_{q}": (b[q] - a[q]) / math.hypot(a[f"{q}_err"], b[f"{q}_err"]) for q in ("mu", "phi")}})
    return {"seed": seed, "width": [plan.config.calibration.width, plan.doubled_config.calibration.width],
            "n_grains": [plan.n_grains, plan.n_doubled], "points": points}


def _fit_and_write(plan: CalibrationPlan, out: Path, state: dict) -> fitting.Calibration:
    rows, blocks, excluded = [], [], []
    for k, seed in sorted(plan.tasks()):
        entry = state["points"][plan.key(k, seed)]
        if entry["checks"]["passed"]:
            rows.append({**entry["row"], "point": k})
            blocks.append(pd.read_csv(layout.point_dir(out, k, seed) / layout.BLOCKS_CSV))
        else:
            excluded.append(plan.key(k, seed))
    cal = fitting.fit_blocks(pd.concat(blocks, ignore_index=True), str(out / layout.CALIBRATION_JSON))
    passed = pd.DataFrame(rows).sort_values(["point", "seed"])
    points = passed[list(layout.POINT_COLUMNS)]
    points.to_csv(out / layout.POINTS_CSV, index=False)
    wall = sum(e.get("wall_time", 0.0) for e in state["points"].values())
    doc = {**cal.contract(), "grains": plan.config.as_dict()["grains"],
           "provenance": {**state["provenance"], "seeds": list(plan.seeds),
                          "analysed_and_fitted_by": provenance()["git"]},
           "p": plan.config.p_w, "rms_mu": cal.rms_mu,
           "points": cal.points.assign(n_seeds=passed.groupby("point").size().to_numpy()).to_dict("list"),
           "excluded": excluded, "not_dense": not_dense(plan, state), "finite_size": finite_size_record(plan, state),
           "protocol": plan.as_dict(), "cost": {"lammps_cpu_seconds": wall, "grain_steps": plan.grain_steps()},
           "law": cal.as_dict()["law"]}
    staging.write_json(out / layout.CALIBRATION_JSON, doc)
    if plan.modulus_seeds:
        _write_elasticity(plan, out, state, doc)
    return cal


#: the pair style of a grains record that names none: ``pair_style granular``, the only style it could have run
RECORD_PAIR_STYLE = "granular"


def pair_style_of(grains: dict) -> str:
    """The LAMMPS pair style a grains record (a run's or a calibration's) ran in."""
    return grains.get("pair_style", RECORD_PAIR_STYLE)


def grains_difference(calibrated: dict, p_calibrated: float, run: dict, p_run: float) -> dict:
    """{key: (calibrated, run)} where two grains records differ; an entry a record lacks is the config's default
    (Grains), except the pair style (pair_style_of).  The rigidity kappa = k_n/(p d) may differ with the
    pressure: one material has one stiffness k_n in rho_p g d units, so k_n is compared instead (kappa itself when
    a pressure is unknown)."""
    default = {**dataclasses.asdict(Grains()), "pair_style": RECORD_PAIR_STYLE}
    a, b = {**default, **calibrated}, {**default, **run}
    pressures = all(math.isfinite(p) for p in (p_calibrated, p_run))
    diff = {k: (a.get(k), v) for k, v in b.items() if (k != "kappa" or not pressures) and a.get(k) != v}
    if pressures:
        k_a, k_b = (Contact(g["contact"], g["dimension"], p, g["kappa"], g["restitution"], g["mu_p"], g["kt_over_kn"],
                            g["polydispersity"], g["pair_style"]).k_n for g, p in ((a, p_calibrated), (b, p_run)))
        if not math.isclose(k_a, k_b, rel_tol=1e-9):
            diff["k_n"] = (k_a, k_b)
    return diff


def material_table(path: str | Path) -> tuple[dict, dict, float]:
    """The config's [material] table from a calibration.json (mu_s, mu_d, I0 in the DEM convention, phi =
    phi_max), its grains record and its pressure; ValueError naming ``--calibration`` if unreadable."""
    path = Path(path)
    require(path.is_file(), "--calibration", "a calibration.json written by granstokes dem calibrate", str(path))
    try:
        doc = json.loads(path.read_text())
        table = {"mu_s": float(doc["mu_s"]), "mu_d": float(doc["mu_d"]), "I0": float(doc["I0"]),
                 "I_convention": doc["I_convention"], "phi": float(doc["phi"]["phi_max"])}
        return table, doc["grains"], float(doc["p"])
    except (json.JSONDecodeError, KeyError, TypeError) as exc:
        raise ValueError(f"--calibration {path} must be a calibration.json of granstokes dem calibrate, got "
                         f"{type(exc).__name__}: {exc}") from None


def calibrated_text(text: str, path: str | Path) -> str:
    """The config ``text`` sized from the calibration at ``path``: its [material] table replaced by the calibrated
    one; refused (ValueError naming --calibration) if the calibration is of other grains."""
    table, grains, p = material_table(path)
    cfg = parse(text)
    diff = grains_difference(grains, p, dataclasses.asdict(cfg.grains), cfg.p_w)
    require(not diff, f"--calibration {path}", "a calibration of the config's grains",
            "different grains: " + ", ".join(f"{k} calibrated {a!r} vs run {b!r}" for k, (a, b) in diff.items()))
    return with_entries(text, [("material", table)], header=f"material: the calibration {Path(path).resolve()}")


@dataclass(frozen=True)
class CalibrateResult:
    out: Path
    status: str
    message: str
    calibration: fitting.Calibration | None
    signal: int | None = None  # the signal that interrupted it


def check_calibration(cfg: Config, out: str | Path, jobs: int = DEFAULT_JOBS, np: int = DEFAULT_NP,
                      resume: bool = False, launcher: str | None = None) -> CalibrationPlan:
    """Everything ``calibrate`` checks before it touches the folder (ValueError / LammpsNotFound naming the
    parameter): jobs, ranks, the launcher, the plan, the wheels, the folder and a resume's config."""
    require(isinstance(jobs, int) and not isinstance(jobs, bool) and jobs >= 1, "--jobs", "an integer >= 1", jobs)
    require(isinstance(np, int) and not isinstance(np, bool) and np >= 1, "--np", "an integer >= 1", np)
    require(launcher is None or "{np}" in launcher, "--launcher", "a command template containing {np}", launcher)
    out = Path(out)
    require(not out.exists() or out.is_dir(), "--out", "a folder (this path is an existing file)", str(out))
    plan = plan_calibration(cfg)
    lammps_env.lmp_binary(), lammps_env.mpirun()
    if resume:
        require((out / layout.CALIBRATION_STATE).exists() and (out / layout.CONFIG_TOML).is_file(), "--resume",
                f"an existing calibration folder (with {layout.CALIBRATION_STATE} and {layout.CONFIG_TOML})", str(out))
        stored = parse((out / layout.CONFIG_TOML).read_text())
        require(stored.as_dict() == cfg.as_dict(), "--resume", f"the config stored in {out / layout.CONFIG_TOML}",
                "a different config")
        staging.require_unchanged(out, "--out")
    else:
        require(not (out.exists() and any(out.iterdir())), "--out", "a new or empty folder (or pass --resume)",
                str(out))
    return plan


def completed_points(out: str | Path, plan: CalibrationPlan) -> tuple[list[str], list[str]]:
    """The keys of a calibration folder's complete cells (each point and seed, the finite-size cells, then the
    modulus cells) and of those left, in run order."""
    state = json.loads((Path(out) / layout.CALIBRATION_STATE).read_text())
    entries = {**state.get("points", {}), **state.get("modulus", {})}
    done, left = [], []
    for key in plan.keys():
        (done if entries.get(key, {}).get("status") == "complete" else left).append(key)
    return done, left


def fit_written(out: str | Path, plan: CalibrationPlan) -> bool:
    """Whether a calibration folder's fit is written: calibration.json is there and every shear cell (the fit's and
    the finite-size ones) is complete in state.json.  Such a calibration keeps its fit (``calibrate``)."""
    out = Path(out)
    if not ((out / layout.CALIBRATION_JSON).is_file() and (out / layout.CALIBRATION_STATE).is_file()):
        return False
    points = json.loads((out / layout.CALIBRATION_STATE).read_text()).get("points", {})
    return all(points.get(plan.key(*c), {}).get("status") == "complete" for c in plan.cells())


def calibrate(cfg: Config, text: str, out: str | Path, jobs: int = DEFAULT_JOBS, np: int = DEFAULT_NP,
              resume: bool = False, launcher: str | None = None, progress: bool = True,
              announce=None, executor: Executor | None = None) -> CalibrateResult:
    """Run (or with ``resume`` continue: unfinished cells rerun, finished ones re-analysed, then the fit and the
    elasticity) the calibration of ``cfg`` into ``out`` on ``executor`` (default: a local one of ``jobs`` x ``np``
    slots); everything is validated before the folder is touched (``check_calibration``: ValueError /
    LammpsNotFound, nothing written); ``announce(line)`` then receives a summary and the cost estimate.  A resumed
    calibration whose fit is written (``fit_written``) keeps it: only its modulus cells run (those not complete),
    and calibration.json is rewritten with ``elasticity`` set, its other keys as they were (the result's
    ``calibration`` is then None)."""
    plan = check_calibration(cfg, out, jobs, np, resume, launcher)
    out = Path(out)
    state_path = out / layout.CALIBRATION_STATE
    keep_fit = resume and fit_written(out, plan)
    if resume:
        state = json.loads(state_path.read_text())
        state.setdefault("resumes", []).append(_now())
        staging.resume(out, COMMAND)
    else:
        state = {"name": cfg.name, "status": "running", "message": "", "plan": plan.as_dict(),
                 "provenance": {**provenance(), **lammps_env.lammps_info(), "np": np, "jobs": jobs},
                 "points": {}, "started": _now()}
        staging.start(out, COMMAND)
        (out / layout.CONFIG_TOML).write_text(text)
    if announce is not None:
        done = completed_points(out, plan)[0] if resume else ()
        announce(plan.summary(out))
        announce(f"  {plan.cost_estimate(jobs, np, done)}")
    state["status"], state["message"] = "running", ""

    def save():  # the cells' entries are theirs (written by the tasks under the lock)
        staging.update_json(state_path, lambda doc: doc.update(
            {k: v for k, v in state.items() if k not in ("points", "modulus")} | {"points": doc.get("points", {})}))

    save()
    tasks = [] if keep_fit else [
        Task(plan.key(k, seed, doubled), run_finite_size_cell if doubled else run_cell,
             (str(out), k, seed, np, launcher, progress, i % jobs), cost=plan.task_seconds(k, doubled), ranks=np)
        for i, (k, seed, doubled) in enumerate(plan.cells())]
    tasks += [Task(plan.modulus_key(seed), run_modulus_cell, (str(out), seed, np, launcher, progress, i % jobs),
                   cost=plan.modulus_seconds(), ranks=np) for i, seed in enumerate(plan.modulus_seeds)]
    t0 = time.monotonic()
    cal, signum = None, None
    allow_lammps()
    try:
        with sigterm_interrupts():
            outcomes = (executor or Executor(jobs * np)).run(tasks, stop=stop_all_lammps) if tasks else {}
        stored = json.loads(state_path.read_text())
        state["points"], state["modulus"] = stored["points"], stored.get("modulus", {})
        # a finite-size cell's failure is its record's; the fit's and the modulus's cells must be complete
        needed = {plan.modulus_key(seed) for seed in plan.modulus_seeds}
        needed |= set() if keep_fit else {plan.key(k, seed) for k, seed in plan.tasks()}
        stopped = [(key, o) for key, o in outcomes.items() if o.status != "complete" and key in needed]
        if stopped:
            key, o = stopped[0]
            raise (RunError if o.status == "failed" else Interrupted)(f"{key}: {o.message}")
        if not keep_fit:
            cal = _fit_and_write(plan, out, state)
        elif plan.modulus_seeds:
            _write_elasticity(plan, out, state, json.loads((out / layout.CALIBRATION_JSON).read_text()))
        doc = json.loads((out / layout.CALIBRATION_JSON).read_text())
        checks = [state["points"][plan.key(k, seed)]["checks"] for k, seed in plan.tasks()]
        n_out, n_gas = sum(not c["passed"] for c in checks), sum(not c["dense_ok"] for c in checks)
        state["message"] = (f"mu_s = {doc['mu_s']:.4g}, mu_d = {doc['mu_d']:.4g}, I0 = {doc['I0']:.4g}"
                            + (f"; {n_out} point(s) failed a check and were left out" if n_out else "")
                            + (f" ({n_gas} not dense)" if n_gas else ""))
        state["status"] = "complete"
        if plan.modulus_seeds:
            e = doc["elasticity"]
            state["message"] += (f"{MODULUS_MESSAGE}{e['G']:.4g} +- {e['G_err']:.2g} ({e['G_dof']} dof), c_s = "
                                 f"{e['c_s']:.3g} +- {e['c_s_err']:.2g}, G/G_affine = {e['G_over_affine']:.2f}")
    except RunError as exc:
        state["status"], state["message"] = "failed", str(exc)
    except (KeyboardInterrupt, Interrupted) as exc:
        signum = int(getattr(exc, "signum", signal.SIGINT))
        state["status"] = "interrupted"
        state["message"] = f"interrupted by {signal.Signals(signum).name}; continue with --resume"
    except ValueError as exc:  # too few steady points for the fit
        state["status"], state["message"] = "failed", f"fit: {exc}"
    finally:
        state["finished"] = _now()
        state["wall_time_this_invocation"] = time.monotonic() - t0
        save()
        # every file recorded once complete; else the config alone (a cell stopped elsewhere may still be writing)
        staging.seal(out, COMMAND, None if state["status"] == "complete" else [layout.CONFIG_TOML])
    return CalibrateResult(out, state["status"], state["message"], cal, signum)
