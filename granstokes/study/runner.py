"""Run a study: its calibration (a file, or plane shear at the lowest and highest pressure), then every bed of
every pressure's run on one executor (granstokes.lib.executor: Dask, local or a scheduler), then the
comparison of all drives against every model from the calibration.

Folder: DIR/study.toml (the study as given, its files relative to DIR), DIR/study.json (status, grid, every run
with its status and path, the calibration, provenance), DIR/calibration-pP/ (dem calibrate), DIR/runs/pP/ (dem
run folders), DIR/metrics.json, DIR/index.html and the report's figures and tables.  ``resume`` continues whatever is
unfinished; a finished calibration, bed or drive is never redone.
"""
from __future__ import annotations

import dataclasses
import datetime as _dt
import json
import math
import os
import signal
import sys
import time
from pathlib import Path

from granstokes.dem import layout
from granstokes.dem.calibrate import calibrate, material_table
from granstokes.dem.estimate import duration_text
from granstokes.dem.runner import Interrupted, allow_lammps, begin, sigterm_interrupts, stop_all_lammps
from granstokes.lib import staging
from granstokes.lib.executor import Executor, Outcome
from granstokes.lib.provenance import provenance
from granstokes.lib.toml_text import with_entries
from granstokes.lib.validate import require

from .config import Study, parse
from .plan import WIDE, StudyPlan, calibration_config, calibration_folder, first_round, measured_c_s, plan_study

COMMAND = "study"
STUDY_TOML, STUDY_JSON = "study.toml", "study.json"


def _now() -> str:
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")


def adds_beds(stored: Study, study: Study) -> bool:
    """Whether ``study`` is ``stored`` with beds added: the same grid but for seeds that continue the stored ones
    and an error target (none stored, or another), so that every run takes at least the beds it had."""
    same = dataclasses.replace(study, seeds=stored.seeds, target=stored.target) == stored
    return same and study.seeds[:len(stored.seeds)] == stored.seeds and (study.seeds, study.target) != (
        stored.seeds, stored.target)


def check_folder(study: Study, out: Path, resume: bool) -> None:
    """The folder: new or empty, or with ``resume`` a study of the same grid (or it with beds added:
    ``adds_beds``) whose files, its runs' and its calibrations' included, are unchanged since written (ValueError
    naming the option)."""
    require(not out.exists() or out.is_dir(), "--out", "a folder (this path is an existing file)", str(out))
    if resume:
        stored = out / STUDY_TOML
        require(stored.is_file(), "--resume", f"given with a study folder (holding {STUDY_TOML})", str(out))
        before = parse(stored.read_text(), out)
        require(before == study or adds_beds(before, study), "--resume", f"the study stored in {stored} (or it "
                "with seeds added after its own, or another error target)", "a different study")
        staging.require_unchanged(out, "--out", nested=True)
    else:
        require(not (out.exists() and any(out.iterdir())), "--out", "a new or empty folder (or pass --resume)",
                str(out))


class StudyRunner:
    """The study folder's state; ``run`` does whatever is unfinished."""

    def __init__(self, study: Study, text: str, out: Path, jobs: int, scheduler: str | None, progress: bool,
                 announce=None):
        self.study, self.text, self.out = study, text, out.resolve()
        self.jobs, self.scheduler, self.progress = jobs, scheduler, progress
        self.announce = announce or (lambda line: print(line, file=sys.stderr))
        self.path = self.out / STUDY_JSON

    def executor(self) -> Executor:
        return Executor(self.jobs, self.scheduler)

    def record(self, change) -> dict:
        return staging.update_json(self.path, change)

    # --- stage 1: the calibration ----------------------------------------------------------------------
    def calibration(self) -> Path:
        """The calibration.json that predicts every drive: the file given, or the study's at the reference
        pressure (each calibration pressure run or resumed; their mu(I) compared in study.json)."""
        s = self.study
        if s.calibration_file is not None:
            self.record(lambda d: d.update(calibration={"source": relative(s.calibration_file, self.out),
                                                        "ran": False}))
            return Path(s.calibration_file)
        results = {}
        for p_w in s.calibration_pressures:
            folder = calibration_folder(self.out, p_w)
            state = folder / layout.CALIBRATION_STATE
            status = json.loads(state.read_text()).get("status") if state.exists() else None
            if status != "complete":
                cfg, text = calibration_config(s, p_w)
                self.announce(f"study: calibrating the {s.dem} grains at p = {p_w:g} -> {folder}")
                result = calibrate(cfg, text, folder, jobs=self.jobs, resume=status is not None, progress=False,
                                   executor=self.executor())
                if result.status != "complete":
                    raise StudyStopped(result.status, f"calibration at p = {p_w:g}: {result.message}", result.signal)
            results[p_w] = str(folder / layout.CALIBRATION_JSON)
        reference = results[s.reference_pressure]
        self.record(lambda d: d.update(calibration={
            "source": relative(reference, self.out), "ran": True,
            "files": {p_w: relative(f, self.out) for p_w, f in results.items()},
            "pressure_dependence": pressure_dependence(results)}))
        return Path(reference)

    # --- stage 2: the runs -----------------------------------------------------------------------------
    def runs(self, sp: StudyPlan) -> dict:
        """Every unfinished bed of every pressure on one executor, longest first, on the ranks of ``sp.ranks``
        (one on a scheduler, whose workers' slots are unknown here; ``sp`` as begun: a run folder already begun
        goes on with the config stored in it); each run folder's status at the end."""
        runners, tasks, ranks = {}, [], sp.ranks(self.jobs)
        for label, r in sp.runs.items():
            folder = sp.folder(self.out, label)
            resume = (folder / layout.RUN_JSON).exists()
            runner, meta = begin(r.plan, r.text, folder, np=1 if self.scheduler else ranks[label],
                                 resume=resume, progress=False, jobs=self.jobs)
            runners[label] = (runner, meta)
            tasks += runner.bed_tasks(meta, prefix=f"{label}/")

        def done(task, outcome):
            label, bed = task.key.split("/", 1)
            self.record(lambda d: d["runs"][label]["beds"].update({bed: outcome.status}))

        t0 = time.monotonic()
        try:
            outcomes = self.executor().run(tasks, on_done=done, stop=stop_all_lammps, progress=self.progress,
                                           desc=f"study {self.study.name}: beds",
                                           expected=sp.cost_seconds(self.jobs, self.out))
        except (Interrupted, KeyboardInterrupt) as exc:
            stopped = Outcome("interrupted", str(exc) or "interrupted by SIGINT")
            for label, (runner, meta) in runners.items():
                meta["signal"] = int(getattr(exc, "signum", signal.SIGINT))
                self._finish(label, runner, meta, [stopped], t0)
            raise
        return {label: self._finish(label, runner, meta, [o for k, o in outcomes.items() if k.startswith(f"{label}/")],
                                    t0)
                for label, (runner, meta) in runners.items()}

    def _finish(self, label: str, runner, meta: dict, outcomes, t0: float):
        """A run folder's status (dem.runner.Runner.finish) and its entry in study.json."""
        result = runner.finish(meta, outcomes, t0)
        self.record(lambda d: d["runs"][label].update(status=result.status, message=result.message))
        return result

    # --- stage 3: the comparison -----------------------------------------------------------------------
    def compare(self, sp: StudyPlan, calibration: Path) -> dict:
        from granstokes.compare.experiment import experiment_for_runs

        folders = [sp.folder(self.out, label) for label in sp.runs if not label.endswith(WIDE)]
        options = {"ngf_from": as_given(self.study.ngf_from)} if self.study.ngf_from is not None else {}
        experiment = experiment_for_runs(folders).create(as_given(calibration), jobs=self.jobs, progress=self.progress,
                                                          **options)
        result = experiment.run(experiment.analyse(folders, root=self.out))
        with staging.staged(self.out, COMMAND, keep=True) as work:
            metrics = experiment.write(result, work)
        checks = [width_check(sp.folder(self.out, label), sp.folder(self.out, label[:-len(WIDE)]), result,
                              self.out)
                  for label in sp.runs if label.endswith(WIDE)]
        self.record(lambda d: d.update(width_check=[row for rows in checks for row in rows]))
        return metrics

    def run(self) -> dict:
        """The three stages in order; study.json's status: complete, failed or interrupted (with why); the manifest
        records the checksums of every file of the study's own once complete, else of study.toml and its report
        (granstokes.lib.staging.seal)."""
        status, message, signum = "complete", "", None
        try:
            with sigterm_interrupts():
                calibration = self.calibration()
                material, _, _ = material_table(calibration)
                sp = plan_study(self.study, material, str(calibration),
                                measured=first_round(self.out)).as_begun(self.out)
                self.record(lambda d: d["runs"].update({
                    label: {**d["runs"].get(label, {"beds": {}}), "p_w": r.p_w,
                            "path": str(sp.folder(self.out, label).relative_to(self.out)),
                            "drives": [dp.drive.name for dp in r.plan.drives],
                            "status": d["runs"].get(label, {}).get("status", "pending")}
                    for label, r in sp.runs.items()}))
                for line in sp.lines(self.jobs, self.out, measured_c_s(calibration)):
                    self.announce(line)
                results = self.runs(sp)
                stopped = [(k, r) for k, r in results.items() if r.status != "complete"]
                if stopped:
                    raise StudyStopped(stopped[0][1].status, f"run {stopped[0][0]}: {stopped[0][1].message}")
                self.announce("study: comparing every drive with every model (about "
                              f"{duration_text(sp.comparison_seconds(self.jobs))})")
                metrics = self.compare(sp, calibration)
                message = metrics.get("verdict", "")
        except StudyStopped as exc:
            status, message, signum = exc.status, str(exc), exc.signal
        except (Interrupted, KeyboardInterrupt) as exc:
            signum = int(getattr(exc, "signum", signal.SIGINT))
            status, message = "interrupted", f"interrupted by {signal.Signals(signum).name}; continue with --resume"
        except Exception as exc:  # a drive the calibrated law cannot sustain, a lost scheduler, a bug: recorded
            status, message = "failed", f"{type(exc).__name__}: {exc}"
        record = self.record(lambda d: d.update(status=status, message=message, finished=_now(), signal=signum))
        staging.seal(self.out, COMMAND, None if status == "complete" else [STUDY_TOML])
        return record


class StudyStopped(RuntimeError):
    """A stage ended without completing: its status (failed, interrupted), why, and the signal if any."""

    def __init__(self, status: str, message: str, signal: int | None = None):
        super().__init__(message)
        self.status, self.signal = status, signal


def width_check(wide: Path, normal: Path, comparison, root: Path) -> list[dict]:
    """The drives of the run folder ``wide`` (twice as wide) against the same drives of ``normal`` in
    ``comparison`` (its runs named relative to ``root``): the free response's steady value in both and their
    difference in units of the combined error (|z| > 2: the box's width changes the answer).  The wide drives are
    analysed, never scored."""
    from granstokes.compare.analysis import analyse_drive
    from granstokes.compare.drive import drive_specs

    normal_by_name = {dc.dem.spec.name: dc.dem for dc in comparison.drives
                      if (Path(root) / dc.dem.spec.run).resolve() == Path(normal).resolve()}
    rows = []
    for spec in drive_specs(wide):
        a, b = normal_by_name.get(spec.name), analyse_drive(spec)
        if a is None:
            continue
        key = b.response
        va, ea, vb, eb = (a.steady[key]["value"], a.steady[key]["stderr"], b.steady[key]["value"],
                          b.steady[key]["stderr"])
        err = math.hypot(ea, eb)
        rows.append({"drive": spec.name, "observable": f"{key}_inf", "normal": va, "normal_err": ea, "wide": vb,
                     "wide_err": eb, "z": (vb - va) / err if err > 0 else None})
    return rows


def pressure_dependence(files: dict) -> dict:
    """mu_s, mu_d, I0 at the lowest and the highest calibrated pressure and their difference in units of the
    combined error (half-widths of the 95 % intervals / 1.96): |z| > 2 says mu(I) depends on p beyond I."""
    if len(files) < 2:
        return {"note": "one calibration pressure: not tested"}
    lo, hi = (json.loads(Path(files[p]).read_text()) for p in sorted(files))
    out = {}
    for key in ("mu_s", "mu_d", "I0"):
        err = [(c[key][1] - c[key][0]) / 2 / 1.96 for c in (lo["ci95"], hi["ci95"])]
        z = (hi[key] - lo[key]) / (err[0] ** 2 + err[1] ** 2) ** 0.5
        out[key] = {"low_p": lo[key], "high_p": hi[key], "z": z}
    out["depends_on_p"] = any(abs(v["z"]) > 2 for v in out.values())
    return out


def relative(path, folder) -> str:
    """``path`` as the study folder ``folder`` records it: relative to the folder (which can move with what it
    names), never this machine's absolute path."""
    return os.path.relpath(Path(path).resolve(), Path(folder).resolve())


def as_given(path) -> str:
    """``path`` relative to the working directory, as paths are given on the command line: how a study's report
    names its calibration and NGF's source."""
    return os.path.relpath(path)


def run_study(study: Study, text: str, out, jobs: int = 2, scheduler: str | None = None, resume: bool = False,
              progress: bool = True, announce=None) -> dict:
    """Run (or with ``resume`` continue) ``study`` in ``out``; returns study.json's record."""
    out = Path(out)
    check_folder(study, out, resume)
    runner = StudyRunner(study, text, out, jobs, scheduler, progress, announce)
    files = [("calibration.file", study.calibration_file), ("ngf_from", study.ngf_from)]
    # relative to the study folder, where a resume reads them from
    text = with_entries(text, [(key, relative(path, out)) for key, path in files if path is not None])
    if not resume:
        staging.start(out, COMMAND)
        (out / STUDY_TOML).write_text(text)
        runner.record(lambda d: d.update(
            name=study.name, status="running", message="", started=_now(), runs={},
            grid={"dem": study.dem, "pressures": list(study.pressures), "seeds": list(study.seeds),
                  "drives": [d.name for d in study.drives], "duration_ts": study.drives[0].duration_ts},
            units="DEM units: d = rho_p = g = 1; p_w in rho_p g d, times in sqrt(d/g)",
            provenance={**provenance(), "jobs": jobs, "scheduler": scheduler or "local"}))
    else:
        added = adds_beds(parse((out / STUDY_TOML).read_text(), out), study)
        staging.resume(out, COMMAND)
        if added:  # the study with its new beds is the study from now on (dem.runner adds them to each run)
            (out / STUDY_TOML).write_text(text)
            runner.record(lambda d: d["grid"].update(seeds=list(study.seeds)))
        runner.record(lambda d: d.update(status="running", message="", resumes=[*d.get("resumes", []), _now()]))
    allow_lammps()
    return runner.run()
