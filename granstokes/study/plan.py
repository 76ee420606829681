"""A study's runs as DEM configs, built from its DEM preset's and recorded as TOML: one run folder per pressure and
frequency of the drives (every seed), each sized once from the calibration (dem.sizing with the calibrated material),
and the calibration stage's configs."""
from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path

from granstokes.continuum.scales import Material
from granstokes.dem import config as dem_config
from granstokes.dem.contact import rigidity
from granstokes.dem.estimate import STARTUP, Estimate, duration_text
from granstokes.dem.layout import CONFIG_TOML, RUN_JSON
from granstokes.dem.runner import adds_beds
from granstokes.dem.sizing import Plan, makespan, plan, ranks_per_bed, size_drive, speedup
from granstokes.dem.throughput import Throughput, measured
from granstokes.lib.toml_text import with_entries

from .config import Study, wave_label

RUNS = "runs"
WIDE = "-wide"  # the width check's run: label and name suffix
#: bytes of the report per scored drive: its figures, tables and predictions (the smoke study's report, 10 MB over 4
#: drives; bench/dem_costs.py)
REPORT_BYTES_PER_DRIVE = 2.5e6
#: the [calibration] entries that set its inertial numbers: a study's replace the DEM preset's
INERTIAL = ("I", "I_min", "I_max", "points")


def pressure_label(p_w: float) -> str:
    return f"p{p_w:g}"


def calibration_folder(out: Path, p_w: float) -> Path:
    """The study's plane-shear calibration at p_w (a ``granstokes dem calibrate`` folder)."""
    return out / f"calibration-{pressure_label(p_w)}"


def _grains(study: Study, grains: dem_config.Grains, p_w: float) -> dem_config.Grains:
    """The DEM preset's ``grains`` as one material at p_w: k_n of the preset's kappa at the study's stiffness pressure
    (its highest, or ``stiffness_at``)."""
    return dataclasses.replace(grains, kappa=rigidity(grains.kappa, grains.contact, study.stiffness_pressure, p_w))


def _recorded(study: Study, cfg: dem_config.Config, entries: list, header: str) -> tuple[dem_config.Config, str]:
    """``cfg``, the DEM preset changed as ``entries`` (dotted keys, granstokes.lib.toml_text) change its text, and its
    TOML for the record: the preset's text with the entries (the tables they give no longer absent from ``cfg``)."""
    given = {key.partition(".")[0] for key, value in entries if value is not None}
    return (dataclasses.replace(cfg, absent=tuple(k for k in cfg.absent if k not in given)),
            with_entries(dem_config.preset_text(study.dem), entries, header=header))


def _pressure_entries(cfg: dem_config.Config) -> list[tuple[str, object]]:
    """The entries of ``cfg``'s pressure and its grains' stiffness there."""
    return [("load.p_w", cfg.p_w), ("grains.kappa", cfg.grains.kappa)]


def calibration_config(study: Study, p_w: float) -> tuple[dem_config.Config, str]:
    """The DEM preset with its grains at p_w and the study's [calibration] entries (its inertial numbers, if it gives
    any, replace the preset's), and its TOML: ``granstokes dem calibrate`` runs its [calibration] table there."""
    base, table = dem_config.preset(study.dem)[0], dict(study.calibration_table)
    defaults = {f.name: f.default for f in dataclasses.fields(dem_config.Calibration)}
    inertial = {k: defaults[k] for k in INERTIAL if k not in table} if any(k in table for k in INERTIAL) else {}
    cfg = dataclasses.replace(base, p_w=p_w, grains=_grains(study, base.grains, p_w),
                              calibration=dataclasses.replace(base.calibration, **inertial, **table))
    entries = [*_pressure_entries(cfg),
               *((f"calibration.{k}", list(v) if isinstance(v, tuple) else v) for k, v in table.items()),
               *((f"calibration.{k}", None) for k in inertial)]
    return _recorded(study, cfg, entries,
                     f"study {study.name}: the calibration of the {study.dem} grains at p_w = {p_w:g}")


def _outputs(cfg: dem_config.Config) -> dict:
    """The output intervals that resolve the drives of ``cfg`` (as sized there) for the comparison that will read
    them (its experiment's ``outputs``)."""
    from granstokes.compare.experiment import experiment_for

    drives = [size_drive(cfg, d) for d in cfg.drives]
    return experiment_for(d.load for d in drives).outputs(drives, cfg.output)


def run_config(study: Study, base: dem_config.Config, p_w: float, drives: tuple[dem_config.Drive, ...],
               material: dict, source: str, wide_of: Plan | None = None,
               seeds: tuple[int, ...] | None = None) -> tuple[dem_config.Config, str]:
    """The DEM config of a run at p_w and its TOML: the DEM preset ``base`` with its grains as one material, the
    study's seeds (or ``seeds``), ``drives``, the depth and durations sized from ``material`` (the calibration at
    ``source``) and the outputs that resolve the drives.  ``wide_of``: the width check of that run, in a box twice
    as wide and as deep."""
    width = (study.width or base.box.width) * (2 if wide_of else 1)
    cfg = dataclasses.replace(base, name=f"{study.name}-{pressure_label(p_w)}{WIDE if wide_of else ''}",
                              seeds=seeds or study.seeds, p_w=p_w, grains=_grains(study, base.grains, p_w),
                              material=Material(**material), drives=drives,
                              box=dataclasses.replace(base.box, margin=None, depth=wide_of.depth if wide_of else None,
                                                      width=width))
    out = _outputs(cfg)
    cfg = dataclasses.replace(cfg, output=dataclasses.replace(cfg.output, **out))
    entries = [("name", cfg.name), ("seeds", list(cfg.seeds)), *_pressure_entries(cfg), ("material", material),
               ("box.margin", None), ("box.depth", cfg.box.depth), ("box.width", cfg.box.width),
               ("drive", [d.table() for d in drives]), *((f"output.{k}", v) for k, v in out.items())]
    return _recorded(study, cfg, entries, f"study {study.name} at p_w = {p_w:g}, sized from the calibration {source}")


@dataclass(frozen=True)
class StudyRun:
    """A run: its config's TOML as its folder records it, and the config's sizing, which the run runs."""

    text: str
    plan: Plan

    @property
    def p_w(self) -> float:
        return self.plan.config.p_w


@dataclass(frozen=True)
class StudyPlan:
    study: Study
    runs: dict[str, StudyRun]  # label (pP, pP-wW, pP-wide) -> the run

    @staticmethod
    def folder(out: Path, label: str) -> Path:
        return out / RUNS / label

    def as_begun(self, out: Path) -> StudyPlan:
        """This plan with each run already begun in the study folder ``out`` as its stored config has it (a resume
        goes on as the run was planned), or as planned now where that only adds beds to it (dem.runner.adds_beds:
        the resume runs the new beds)."""
        runs = {}
        for label, r in self.runs.items():
            stored = self.folder(out, label) / CONFIG_TOML
            text = stored.read_text() if (self.folder(out, label) / RUN_JSON).is_file() else r.text
            begun = r if text == r.text else StudyRun(text, plan(dem_config.parse(text)))
            runs[label] = r if adds_beds(begun.plan.config, r.plan.config) else begun
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

    def lines(self, jobs: int, out: Path | None = None, c_s: float | None = None) -> list[str]:
        """Per scene: delta_s, t_s, depth, duration, grains, steps and cost, and what each drive offers the
        experiment's laws (its ``planned``: a Stokes drive's growth window, at the measured shear-wave speed ``c_s``);
        then the whole (what is left of it in the study folder ``out``)."""
        first = next(iter(self.runs.values())).plan.config.describe()
        lines = [f"  {first[1]}"]  # one material: the grains of every run
        experiment = self.experiment()
        if experiment.plan_header(c_s):
            lines.append(f"  {experiment.plan_header(c_s)}")
        for label, r in self.runs.items():
            p = r.plan
            lines.append(f"  {label}: {p.config.describe()[0]}")
            for d in p.drives:
                offers = experiment.planned(p, d, c_s)
                lines.append(f"  {label}, {d.drive.name}: delta_s = {d.scales.delta_s:.3g} d, t_s = "
                             f"{d.scales.t_s:.3g}, depth {p.depth:g} d, width {p.config.box.width:g} d, duration "
                             f"{d.duration:.4g} ({d.steps:.3g} steps), {p.n_grains} grains x "
                             f"{len(p.config.seeds)} bed(s)" + (f", {offers}" if offers else ""))
            lines.append(f"  {label}: {p.cost_estimate(1)}")
        left = " (what is left)" if self.done(out) else ""
        beds, comparison = self.cost_seconds(jobs, out), self.comparison_seconds(jobs)
        lines.append(f"  the study's beds{left}: about {duration_text(beds)} with {jobs} job(s)")
        what = self.experiment().comparison_work(self.scored_drives(), self.grain_frames())
        lines.append(f"  the comparison: about {duration_text(comparison)} ({what})")
        return lines


def measured_c_s(path) -> float | None:
    """The shear-wave speed a calibration.json measured in its packing (its ``elasticity``), or None."""
    if path is None:
        return None
    elasticity = json.loads(Path(path).read_text()).get("elasticity") or {}
    return float(elasticity["c_s"]) if "c_s" in elasticity else None


def drive_label(label: str, drive_name: str) -> str:
    """A study drive's label in its report (metrics.json's drives): runs/p10/stress-mutilde0.6."""
    return f"{RUNS}/{label}/{drive_name}"


def first_round(out: Path | None) -> dict | None:
    """The one-bed errors the study folder's last report measured (compare.noise.measured_errors: what a resume
    that adds beds plans from), or None before any report."""
    from granstokes.compare import noise
    from granstokes.compare.experiment import METRICS_JSON

    path = None if out is None else Path(out) / METRICS_JSON
    return noise.measured_errors(json.loads(path.read_text())) if path is not None and path.is_file() else None


def target_beds(label: str, r: StudyRun, target, table: dict | None = None, measured: dict | None = None) -> int:
    """The beds run ``label`` takes for the study's error target: the most its drives need to decide what the
    target's budget can (compare.noise.Target, from a first round's ``measured`` errors where given; what it cannot
    is said, not paid for), at least the seeds it was planned with."""
    from granstokes.compare import noise

    measured = measured or {}
    needs = [n for d in r.plan.drives
             for n in target.beds(noise.drive_size(r.plan, d, r.p_w), table,
                                  measured.get(drive_label(label, d.drive.name))).values() if n is not None]
    return max([len(r.plan.config.seeds), *needs])


def extended_seeds(seeds: tuple[int, ...], beds: int) -> tuple[int, ...]:
    """``seeds`` followed by the next integers after the largest, ``beds`` in all."""
    return seeds + tuple(range(max(seeds) + 1, max(seeds) + 1 + beds - len(seeds)))


def plan_study(study: Study, material: dict, source: str, noise_table: dict | None = None,
               measured: dict | None = None) -> StudyPlan:
    """Every run's config and its sizing (ValueError naming the drive if a load is outside the calibrated law): at
    every pressure one run per frequency of the drives (held drives: one run), its outputs resolving them, its beds
    the study's seeds or, with an error target, those its drives need (``target_beds``, from a first round's
    ``measured`` errors where given, else compare.noise's laws or ``noise_table``); with ``study.width_check`` the
    first drive at the reference pressure in a box twice as wide (the study's seeds)."""
    base = dem_config.preset(study.dem)[0]

    def run(p_w: float, drives: tuple[dem_config.Drive, ...], wide_of: Plan | None = None,
            seeds: tuple[int, ...] | None = None) -> StudyRun:
        cfg, text = run_config(study, base, p_w, drives, material, source, wide_of, seeds)
        return StudyRun(text, plan(cfg))

    def targeted(label: str, p_w: float, drives: tuple[dem_config.Drive, ...]) -> StudyRun:
        first = run(p_w, drives)
        if study.target is None:
            return first
        beds = target_beds(label, first, study.target, noise_table, measured)
        return run(p_w, drives, seeds=extended_seeds(study.seeds, beds))

    runs = {pressure_label(p_w) + wave_label(w): targeted(pressure_label(p_w) + wave_label(w), p_w,
                                                           tuple(d for d in study.drives if d.omega_ts == w))
            for p_w in study.pressures for w in study.frequencies}
    if study.width_check:
        label = pressure_label(study.reference_pressure)
        runs[label + WIDE] = run(study.reference_pressure, study.drives[:1], runs[label].plan)
    return StudyPlan(study, runs)
