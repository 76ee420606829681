"""A study's runs as DEM configs: one run folder per pressure (every drive, every seed), sized from the
calibration (dem.sizing with the calibrated material), and the calibration stage's configs."""
from __future__ import annotations

import json
import tomllib
from dataclasses import dataclass
from pathlib import Path

from granstokes.dem import config as dem_config
from granstokes.dem.estimate import STARTUP, Estimate, duration_text
from granstokes.dem.layout import CONFIG_TOML, RUN_JSON
from granstokes.dem.sizing import Plan, makespan, plan, ranks_per_bed, speedup
from granstokes.dem.throughput import Throughput, measured
from granstokes.lib.toml_text import with_entries

from .config import Study, rigidity

RUNS = "runs"
WIDE = "-wide"  # the width check's run: label and name suffix
#: atom and contact snapshots per t_s of the fastest drive at a pressure: the layer's growth over the first t_s
#: is resolved by this many frames, and a drive of 10 t_s has 10 times as many (coarse-graining's cost)
FRAMES_PER_TS = 20
#: atom snapshots per t_s over the first t_s of the fastest drive: the growth window (compare.laws, from three
#: shear-wave transits to half a t_s) holds tens of frames
EARLY_FRAMES_PER_TS = 100
#: bytes of the report per scored drive: its figures, tables and predictions (the smoke study's report, 10 MB over 4
#: drives; bench/dem_costs.py)
REPORT_BYTES_PER_DRIVE = 2.5e6
#: an oscillating plate's run: LAMMPS's depth profiles this many times per period (the phase-resolved profiles
#: of compare.oscillation), the plate's record PLATE_PER_PROFILE times as often, atom snapshots once a period
PROFILES_PER_PERIOD, PLATE_PER_PROFILE = 24, 4


def pressure_label(p_w: float) -> str:
    return f"p{p_w:g}"


def calibration_folder(out: Path, p_w: float) -> Path:
    """The study's plane-shear calibration at p_w (a ``granstokes dem calibrate`` folder)."""
    return out / f"calibration-{pressure_label(p_w)}"


def _grains(study: Study, p_w: float) -> list[tuple[str, object]]:
    """The entries that make the DEM preset's grains one material at p_w: k_n of the highest pressure's kappa."""
    doc = tomllib.loads(dem_config.preset_text(study.dem))
    grains = doc.get("grains", {})
    defaults = dem_config.Grains()
    kappa = grains.get("kappa", defaults.kappa)
    return [("load.p_w", p_w), ("grains.kappa", rigidity(kappa, grains.get("contact", defaults.contact),
                                                           max(study.pressures), p_w))]


def calibration_text(study: Study, p_w: float) -> str:
    """The DEM preset with its grains at p_w: ``granstokes dem calibrate`` runs its [calibration] table there."""
    table = [(f"calibration.{k}", list(v) if isinstance(v, tuple) else v) for k, v in study.calibration_table]
    if any(k in dict(study.calibration_table) for k in ("I", "I_min", "I_max", "points")):
        table += [(f"calibration.{k}", None) for k in ("I", "I_min", "I_max", "points")
                  if k not in dict(study.calibration_table)]  # the study's inertial numbers replace the preset's
    return with_entries(dem_config.preset_text(study.dem), [*_grains(study, p_w), *table],
                        header=f"study {study.name}: the calibration of the {study.dem} grains at p_w = {p_w:g}")


def run_text(study: Study, p_w: float, material: dict, source: str, wide_of: Plan | None = None,
             omega_ts: float | None = None) -> str:
    """The DEM config of the run at p_w: the preset's grains (one material), the study's seeds and drives, the
    depth and durations sized from ``material`` (the calibration at ``source``), snapshots every t_s/FRAMES_PER_TS
    of its fastest drive (the plate's and the profiles' intervals no longer), every t_s/EARLY_FRAMES_PER_TS
    over its first t_s.  ``wide_of``: the width check of
    that run, its first drive alone in a box twice as wide and as deep.  ``omega_ts``: the oscillating drives at that
    frequency, their profiles PROFILES_PER_PERIOD times a period of the fastest, the plate PLATE_PER_PROFILE times as
    often, snapshots once a period (the phase-resolved analysis reads the plate and the profiles)."""
    drives = study.drives[:1] if wide_of else study.drives
    if omega_ts is not None:
        drives = tuple(d for d in drives if d.omega_ts == omega_ts)
    width = study.width or dem_config.preset(study.dem)[0].box.width
    entries = [("name", f"{study.name}-{pressure_label(p_w)}{WIDE if wide_of else ''}"), ("seeds", list(study.seeds)),
               *_grains(study, p_w), ("material", material), ("box.margin", None),
               ("box.depth", wide_of.depth if wide_of else None), ("box.width", width * (2 if wide_of else 1)),
               ("drive", [d.table(study.duration_ts, study.min_duration) for d in drives])]
    header = f"study {study.name} at p_w = {p_w:g}, sized from the calibration {source}"
    text = with_entries(dem_config.preset_text(study.dem), entries, header=header)
    cfg = dem_config.parse(text)
    if omega_ts is not None:
        period = min(d.duration / d.drive.cycles for d in plan(cfg).drives)
        profile = period / PROFILES_PER_PERIOD
        return with_entries(text, [("output.atoms", period), ("output.contacts", period),
                                   ("output.plate", min(cfg.output.plate, profile / PLATE_PER_PROFILE)),
                                   ("output.profiles", profile), ("output.restart", max(cfg.output.restart, period))],
                            header=header)
    t_s = min(d.scales.t_s for d in plan(cfg).drives)
    frame, out = t_s / FRAMES_PER_TS, cfg.output
    return with_entries(text, [("output.atoms", frame), ("output.contacts", frame), ("output.plate",
                                                                                      min(out.plate, frame)),
                               ("output.profiles", min(out.profiles, frame)), ("output.early", t_s),
                               ("output.atoms_early", t_s / EARLY_FRAMES_PER_TS)], header=header)


@dataclass(frozen=True)
class StudyRun:
    p_w: float
    text: str
    plan: Plan


@dataclass(frozen=True)
class StudyPlan:
    study: Study
    runs: dict[str, StudyRun]  # label (pP, pP-wide) -> the run

    @staticmethod
    def folder(out: Path, label: str) -> Path:
        return out / RUNS / label

    def as_begun(self, out: Path) -> StudyPlan:
        """This plan with each run already begun in the study folder ``out`` as its stored config has it (a resume
        goes on as the run was planned)."""
        runs = {}
        for label, r in self.runs.items():
            stored = self.folder(out, label) / CONFIG_TOML
            text = stored.read_text() if (self.folder(out, label) / RUN_JSON).is_file() else r.text
            runs[label] = r if text == r.text else StudyRun(r.p_w, text, plan(dem_config.parse(text)))
        return StudyPlan(self.study, runs)

    def done(self, out: Path | None) -> set[str]:
        """The complete stages of the runs already begun in the study folder ``out``, as "label/stage key"."""
        if out is None:
            return set()
        keys = set()
        for label in self.runs:
            meta = self.folder(out, label) / RUN_JSON
            if meta.is_file():
                stages = json.loads(meta.read_text()).get("stages", {})
                keys |= {f"{label}/{k}" for k, st in stages.items() if st.get("status") == "complete"}
        return keys

    def ranks(self, jobs: int) -> dict[str, int]:
        """MPI ranks of each run's beds (dem.sizing.ranks_per_bed), the study's beds ``jobs`` at a time."""
        concurrent = min(jobs, sum(len(r.plan.config.seeds) for r in self.runs.values()))
        return {label: ranks_per_bed(r.plan.n_grains, r.plan.dimension, concurrent) for label, r in self.runs.items()}

    def cost_seconds(self, jobs: int, out: Path | None = None) -> float:
        """Every bed (what is left of it in the study folder ``out``) on its ``ranks``, longest first over ``jobs``
        slots, at this machine's speed (dem.throughput)."""
        speed, done, ranks = measured(), self.done(out), self.ranks(jobs)
        beds = [sum(r.plan.stage_seconds(k, speed) for k in r.plan.stage_keys(seed) if f"{label}/{k}" not in done)
                / speedup(r.plan.n_grains, r.plan.dimension, ranks[label])
                for label, r in self.runs.items() for seed in r.plan.config.seeds]
        return makespan(sorted([b for b in beds if b > 0], reverse=True), jobs, contention=speed.contention)

    def estimate(self, jobs: int, out: Path | None = None, calibration: Estimate = Estimate()) -> Estimate:
        """The whole study on this machine: ``calibration`` (its stage, if it runs), the beds and their bytes (what
        is left in the study folder ``out``), the comparison and its report, the command's start-up."""
        done = self.done(out)
        disk = sum(r.plan.stage_bytes(k) for label, r in self.runs.items() for seed in r.plan.config.seeds
                   for k in r.plan.stage_keys(seed) if f"{label}/{k}" not in done)
        return (calibration.plus("beds", self.cost_seconds(jobs, out), disk)
                .plus("comparison", self.comparison_seconds(jobs), self.scored_drives() * REPORT_BYTES_PER_DRIVE)
                .plus("start-up", STARTUP["study"]))

    def grain_frames(self) -> int:
        """Grains x atom snapshots of every drive and bed: what the comparison coarse-grains (the width check's
        runs too)."""
        return sum(r.plan.n_grains * len(r.plan.config.seeds) * r.plan.atom_frames(d)
                   for r in self.runs.values() for d in r.plan.drives)

    def experiment(self):
        """The comparison's experiment (compare.experiment's registry, by the drives' loads)."""
        from granstokes.compare.experiment import experiment_for

        return experiment_for(d.load for r in self.runs.values() for d in r.plan.drives)

    def scored_drives(self) -> int:
        """The drives compared with the models (the width check's are analysed only)."""
        return sum(len(r.plan.drives) for label, r in self.runs.items() if not label.endswith(WIDE))

    def comparison_seconds(self, jobs: int, speed: Throughput | None = None) -> float:
        """The comparison stage on this machine, as the study's experiment estimates it (compare.experiment)."""
        return self.experiment().comparison_seconds(self.scored_drives(), self.grain_frames(), jobs,
                                                    speed or measured())

    def lines(self, jobs: int, out: Path | None = None) -> list[str]:
        """Per scene: delta_s, t_s, depth, duration, grains, steps and cost; then the whole (what is left of it in
        the study folder ``out``)."""
        first = next(iter(self.runs.values())).plan.config.describe()
        lines = [f"  {first[1]}"]  # one material: the grains of every run
        for label, r in self.runs.items():
            p = r.plan
            lines.append(f"  {label}: {p.config.describe()[0]}")
            for d in p.drives:
                lines.append(f"  {label}, {d.drive.name}: delta_s = {d.scales.delta_s:.3g} d, t_s = "
                             f"{d.scales.t_s:.3g}, depth {p.depth:g} d, width {p.config.box.width:g} d, duration "
                             f"{d.duration:.4g} ({d.steps:.3g} steps), {p.n_grains} grains x "
                             f"{len(p.config.seeds)} bed(s)")
            lines.append(f"  {label}: {p.cost_estimate(1)}")
        left = " (what is left)" if self.done(out) else ""
        beds, comparison = self.cost_seconds(jobs, out), self.comparison_seconds(jobs)
        lines.append(f"  the study's beds{left}: about {duration_text(beds)} with {jobs} job(s)")
        what = self.experiment().comparison_work(self.scored_drives(), self.grain_frames())
        lines.append(f"  the comparison: about {duration_text(comparison)} ({what})")
        return lines


def plan_study(study: Study, material: dict, source: str) -> StudyPlan:
    """Every run's config and plan (ValueError naming the drive if a load is outside the calibrated law), and
    with ``study.width_check`` the first drive at the reference pressure in a box twice as wide."""
    runs = {}
    for p_w in study.pressures:
        if study.oscillating:  # one run per frequency: its outputs resolve its period
            for w in sorted({d.omega_ts for d in study.drives}):
                text = run_text(study, p_w, material, source, omega_ts=w)
                runs[f"{pressure_label(p_w)}-w{w:g}"] = StudyRun(p_w, text, plan(dem_config.parse(text)))
            continue
        text = run_text(study, p_w, material, source)
        runs[pressure_label(p_w)] = StudyRun(p_w, text, plan(dem_config.parse(text)))
    if study.width_check:
        p_w = study.reference_pressure
        text = run_text(study, p_w, material, source, wide_of=runs[pressure_label(p_w)].plan)
        runs[pressure_label(p_w) + WIDE] = StudyRun(p_w, text, plan(dem_config.parse(text)))
    return StudyPlan(study, runs)
