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
  autocorrelation time (the MIN_BLOCKS cap can make them shorter when the window is too short).

Output (dem.layout): DIR/calibration.json, DIR/points.csv, DIR/state.json, DIR/I-K/seed-S/.
Points and seeds are tasks of the project's executor (granstokes.lib.executor: ``jobs`` LAMMPS processes at
once, longest first, a failed cell retried once); ``resume`` reruns the unfinished ones (a cell restarts from
its insertion: cells are short).
"""
from __future__ import annotations

import dataclasses
import datetime as _dt
import json
import math
import shutil
import signal
import threading
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
from .config import Config, Grains, parse
from .contact import Contact, mean_grain_volume
from .lammps_env import DEFAULT_JOBS, DEFAULT_NP
from .runner import Interrupted, RunError, _Lammps, stop_all_lammps
from .shear import COMPRESS_MAX, COMPRESS_RATE, PRE_PACKING, SQUEEZE_TIME, ShearPoint, shear_script
from .sizing import CONTENTION, OVERHEAD, PACKING, THROUGHPUT, count, duration_text, makespan

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


@dataclass(frozen=True)
class CalibrationPlan:
    """Sizes and step counts of a calibration, derived once from a validated Config."""

    config: Config
    dt: float
    n_grains: int
    points: tuple[ShearPoint, ...]

    @property
    def seeds(self) -> tuple[int, ...]:
        return self.config.calibration.seeds

    def tasks(self) -> list[tuple[int, int]]:
        """(point index, seed), longest first (smallest I), so that concurrent jobs finish together."""
        order = sorted(range(len(self.points)), key=lambda k: -self.steps(k))
        return [(k, s) for k in order for s in self.seeds]

    def steps(self, k: int) -> int:
        p = self.points[k]
        return round(SQUEEZE_TIME / self.dt) + p.start_steps + p.measure_steps

    @staticmethod
    def key(k: int, seed: int) -> str:
        """state.json's key of point ``k`` and ``seed``."""
        return f"I-{k}/seed-{seed}"

    @property
    def compress_steps(self) -> int:
        """A cell's expected compression to p: from PRE_PACKING to the material's phi at COMPRESS_RATE."""
        phi = self.config.material.phi / PRE_PACKING[self.config.grains.dimension]
        return round(min(COMPRESS_MAX, math.log(max(1.0, phi)) / COMPRESS_RATE) / self.dt)

    def task_seconds(self, k: int) -> float:
        """Expected LAMMPS wall time of one point and seed run alone at one rank (sizing.THROUGHPUT)."""
        steps = self.steps(k) + self.compress_steps
        return self.n_grains * steps / THROUGHPUT[self.config.grains.dimension]["shear"]

    def cost_seconds(self, jobs: int = DEFAULT_JOBS, np_: int = DEFAULT_NP, done=()) -> float:
        """Expected wall time of the calibration (or of the points left: ``done`` holds the complete keys)."""
        work = [self.task_seconds(k) for k, seed in self.tasks() if self.key(k, seed) not in done]
        return OVERHEAD + makespan(work, jobs, np_)

    def cost_estimate(self, jobs: int = DEFAULT_JOBS, np_: int = DEFAULT_NP, done=()) -> str:
        """One line: the calibration's size and its expected wall time on this machine."""
        rate = THROUGHPUT[self.config.grains.dimension]["shear"]
        if all(self.key(k, seed) in done for k, seed in self.tasks()):
            return "cost: none, every point is complete"
        left = " of what is left" if done else ""
        return (f"cost: {len(self.tasks())} cells of {self.n_grains} grains, each compressing ~"
                f"{count(self.compress_steps)} steps first; about {duration_text(self.cost_seconds(jobs, np_, done))}"
                f"{left} with {jobs} job(s) x {np_} rank(s) (one cell alone at one rank: {rate / 1e6:.2g} M "
                f"grain-steps/s; two at once {CONTENTION:g}x slower each; bench/RESULTS.md)")

    def summary(self, out) -> str:
        """One line: what the calibration measures, and where."""
        c = self.config.calibration
        return (f"dem calibrate: '{self.config.name}' grains, {len(self.points)} inertial numbers in [{c.I_min:g}, "
                f"{c.I_max:g}] x {len(c.seeds)} seed(s), {self.n_grains} grains at p = {self.config.p_w:g}, "
                f"{self.as_dict()['total_steps']:.3g} steps -> {out}")

    def as_dict(self) -> dict:
        cal = self.config.calibration
        return {"p": self.config.p_w, "dt": self.dt, "n_grains": self.n_grains, "width": cal.width,
                "dimension": self.config.grains.dimension, "seeds": list(cal.seeds),
                "strain_start": cal.strain_start, "strain": cal.strain, "sample_strain": cal.sample,
                "strain_max": cal.strain_max,
                "points": [{"I": p.I, "rate": p.rate, "start_steps": p.start_steps, "measure_steps": p.measure_steps,
                            "sample_steps": p.sample} for p in self.points],
                "total_steps": sum(self.steps(k) for k in range(len(self.points))) * len(cal.seeds),
                "block": f"{BLOCK_TAU:g} integrated autocorrelation times (the longer of mu's and phi's), at least "
                         f"{MIN_BLOCKS} blocks",
                "checks": f"strain >= {cal.strain:g}; drift of mu and phi between halves < {DRIFT_Z:g} s.e.; "
                          f"|<P_yy> - p| < {PRESSURE_Z:g} s.e.; velocity profile within {HOMOGENEITY_TOL:g} of linear; "
                          "blocks longer than the autocorrelation time",
                "I_convention": "dem: I = gamma_dot d/sqrt(p/rho_p), gamma_dot = |du/dy|"}


def plan_calibration(cfg: Config) -> CalibrationPlan:
    cal, dim, dt = cfg.calibration, cfg.grains.dimension, cfg.time_step
    lz = cal.width if dim == 3 else 1.0
    n = round(PACKING[dim] * cal.width**2 * lz / mean_grain_volume(cfg.grains.polydispersity, dim))
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
    return CalibrationPlan(cfg, dt, n, tuple(points))


# --- analysis of one point and seed ------------------------------------------------------------------
def _samples(folder: Path) -> pd.DataFrame:
    """Per-sample tau, p, phi and the shear rate from the box (xy unwrapped across flips)."""
    s = pd.read_csv(folder / layout.SHEAR_SERIES_CSV)
    dxy = np.diff(s.xy.to_numpy())
    dxy -= s.lx.to_numpy()[1:] * np.round(dxy / s.lx.to_numpy()[1:])
    ly = 0.5 * (s.ly.to_numpy()[1:] + s.ly.to_numpy()[:-1])
    out = s.iloc[1:].reset_index(drop=True)
    return pd.DataFrame({"strain": np.cumsum(dxy / ly), "rate": dxy / ly / np.diff(s.t.to_numpy()),
                         "tau": -out.p_xy, "p": out.p_yy, "phi": out.phi})


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
              "block_strain": length * cfg.calibration.sample}
    checks["blocks_ok"] = checks["block_strain"] >= checks["tau_int_strain"]
    checks["passed"] = all(checks[k] for k in ("strain_ok", "drift_ok", "pressure_ok", "homogeneous_ok", "blocks_ok"))
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
    out = Path(out)
    plan = plan_calibration(parse((out / layout.CONFIG_TOML).read_text()))
    state_path, key, d = out / layout.CALIBRATION_STATE, plan.key(k, seed), layout.point_dir(out, k, seed)
    point = plan.points[k]
    old = json.loads(state_path.read_text())["points"].get(key, {})

    def store(entry):
        staging.update_json(state_path, lambda doc: doc["points"].update({key: entry}))

    def analysed(entry):
        row, blocks, checks = analyse(d, plan.config, point, seed)
        blocks.assign(point=k)[list(layout.BLOCK_COLUMNS)].to_csv(d / layout.BLOCKS_CSV, index=False)
        return {**entry, "row": row, "checks": checks}

    if old.get("status") == "complete":
        store(analysed(old))
        return Outcome("complete")
    if d.exists():
        shutil.rmtree(d)
    d.mkdir(parents=True)
    (d / layout.SHEAR_IN).write_text(shear_script(plan.config, point, plan.n_grains, seed))
    store({"status": "running", "I_target": point.I, "started": _now()})
    entry = {"status": "interrupted", "I_target": point.I, "message": "continue with --resume"}
    try:
        info = _Lammps(np_, launcher, progress).run(layout.SHEAR_IN, d, plan, plan.steps(k), 0,
                                                    f"I={point.I:.3g} seed {seed}", position=position)
        entry = analysed({"status": "complete", "I_target": point.I, "wall_time": info["wall_time"],
                          "steps": info["last_step"]})
    except RunError as exc:
        entry = {"status": "failed", "I_target": point.I, "message": str(exc)}
    except (Interrupted, KeyboardInterrupt):
        pass
    finally:
        store(entry)
    return Outcome(entry["status"], entry.get("message", ""))


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
           "excluded": excluded, "protocol": plan.as_dict(),
           "cost": {"lammps_cpu_seconds": wall, "grain_steps": plan.n_grains * plan.as_dict()["total_steps"]},
           "law": cal.as_dict()["law"]}
    staging.write_json(out / layout.CALIBRATION_JSON, doc)
    return cal


def grains_difference(calibrated: dict, p_calibrated: float, run: dict, p_run: float) -> dict:
    """{key: (calibrated, run)} where two grains records differ; an entry a record lacks is the config's default
    (Grains), except the pair style (a record that names none ran ``pair_style granular``, the only style it
    could have run).  The rigidity kappa = k_n/(p d) may differ with the pressure: one material has one
    stiffness k_n in rho_p g d units, so k_n is compared instead (kappa itself when a pressure is unknown)."""
    default = {**dataclasses.asdict(Grains()), "pair_style": "granular"}
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
    else:
        require(not (out.exists() and any(out.iterdir())), "--out", "a new or empty folder (or pass --resume)",
                str(out))
    return plan


def completed_points(out: str | Path, plan: CalibrationPlan) -> tuple[list[str], list[str]]:
    """The keys of a calibration folder's complete points (each seed) and of those left, in run order."""
    points = json.loads((Path(out) / layout.CALIBRATION_STATE).read_text()).get("points", {})
    done, left = [], []
    for k, seed in plan.tasks():
        key = plan.key(k, seed)
        (done if points.get(key, {}).get("status") == "complete" else left).append(key)
    return done, left


def calibrate(cfg: Config, text: str, out: str | Path, jobs: int = DEFAULT_JOBS, np: int = DEFAULT_NP,
              resume: bool = False, launcher: str | None = None, progress: bool = True,
              announce=None, executor: Executor | None = None) -> CalibrateResult:
    """Run (or with ``resume`` continue: unfinished points rerun, finished ones re-analysed, then the
    fit) the calibration of ``cfg`` into ``out`` on ``executor`` (default: a local one of ``jobs`` x ``np``
    slots); everything is validated before the folder is touched (``check_calibration``: ValueError /
    LammpsNotFound, nothing written); ``announce(line)`` then receives a summary and the cost estimate."""
    plan = check_calibration(cfg, out, jobs, np, resume, launcher)
    out = Path(out)
    state_path = out / layout.CALIBRATION_STATE
    if resume:
        state = json.loads(state_path.read_text())
        state.setdefault("resumes", []).append(_now())
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

    def save():
        staging.update_json(state_path, lambda doc: doc.update({k: v for k, v in state.items() if k != "points"}
                                                               | {"points": doc.get("points", {})}))

    save()
    tasks = [Task(plan.key(k, seed), run_cell, (str(out), k, seed, np, launcher, progress, i % jobs),
                  cost=plan.task_seconds(k), ranks=np) for i, (k, seed) in enumerate(plan.tasks())]
    in_main = threading.current_thread() is threading.main_thread()
    previous = signal.getsignal(signal.SIGTERM)
    if in_main:
        signal.signal(signal.SIGTERM, _raise_interrupted)
    t0 = time.monotonic()
    cal = None
    try:
        outcomes = (executor or Executor(jobs * np)).run(tasks, stop=stop_all_lammps)
        state["points"] = json.loads(state_path.read_text())["points"]
        stopped = [(key, o) for key, o in outcomes.items() if o.status != "complete"]
        if stopped:
            key, o = stopped[0]
            raise (RunError if o.status == "failed" else Interrupted)(f"{key}: {o.message}")
        cal = _fit_and_write(plan, out, state)
        state["status"] = "complete"
        n_out = sum(not e["checks"]["passed"] for e in state["points"].values())
        state["message"] = (f"mu_s = {cal.mu_s:.4g}, mu_d = {cal.mu_d:.4g}, I0 = {cal.I0_dem:.4g}"
                            + (f"; {n_out} point(s) failed a check and were left out" if n_out else ""))
    except RunError as exc:
        state["status"], state["message"] = "failed", str(exc)
    except (KeyboardInterrupt, Interrupted):
        state["status"], state["message"] = "interrupted", "interrupted by SIGINT/SIGTERM; continue with --resume"
    except ValueError as exc:  # too few steady points for the fit
        state["status"], state["message"] = "failed", f"fit: {exc}"
    finally:
        if in_main:
            signal.signal(signal.SIGTERM, previous)
        state["finished"] = _now()
        state["wall_time_this_invocation"] = time.monotonic() - t0
        save()
    return CalibrateResult(out, state["status"], state["message"], cal)


def _raise_interrupted(signum, frame):
    raise Interrupted(f"received signal {signum}")
