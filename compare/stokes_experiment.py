"""Stokes' first problem as an experiment (compare.experiment): plates set in motion by a held stress or a held
speed, coarse-grained from the beds' dumps (compare.comparison.analyse), predicted by local mu(I), the paper's
model and NGF from the calibration (compare.comparison.prepare, model_drive, conclude), scored drive by drive
(compare.scorecard) and law by law (compare.laws), rendered by compare.report and compare.metrics."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from granstokes.dem.sizing import count, makespan

from granstokes.lib.validate import require

from . import calibrate, metrics, report, tables
from .comparison import IGNORABLE, DemSide, analyse, check_grains, conclude, model_drive, prepare, run_grains, timed
from .drive import TRANSITS_BEFORE_COMPARISON
from .experiment import Experiment
from .laws import GROWTH_END, MIN_DECADES, growth_bounds
from .profiles import CGSettings

#: the comparison's cost per 2D drive grain-step/s of this machine (dem.throughput: it scales with the probe),
#: measured beside probes by bench/dem_costs.py --constants (bench/RESULTS.md, "DEM cost estimates"): the
#: grain-frames coarse-grained per grain-step of a 2D drive (bench/cg_rate.py), and the grain-steps of a 2D drive
#: worth one drive and model of the model side (its prediction, replicates and bands; bench/compare_cost.py on the
#: disks study, one process)
CG_PER_DRIVE_STEP, MODEL_DRIVE_STEPS = 0.0121, 1.76e7
#: the rest of the comparison per scored drive (its figures and tables, the NGF fit, the analysis beyond the
#: coarse-graining), in grain-steps of a 2D drive: the smoke study's comparison less the two terms above, over its
#: 4 drives (bench/dem_costs.py; checked on a subset of the disks study)
REPORT_DRIVE_STEPS = 5.9e7
#: atom and contact snapshots per t_s of the fastest drive of a run: the layer's growth over the first t_s is
#: resolved by this many frames, and a drive of 10 t_s has 10 times as many (coarse-graining's cost)
FRAMES_PER_TS = 20
#: atom snapshots per t_s over the first t_s of the fastest drive: the growth window (compare.laws, from three
#: shear-wave transits to half a t_s) holds tens of frames
EARLY_FRAMES_PER_TS = 100
#: the models every drive is compared with: local mu(I), the paper's, NGF (compare.comparison)
MODELS = 3


def planned_window(plan, drive, c_s: float | None = None) -> tuple[float, float, float]:
    """A planned drive's growth window (compare.laws.growth_bounds; its transit at the measured shear-wave speed
    ``c_s``, else the contacts'): start, end and the decades it spans (-inf when the elastic start covers it)."""
    start, end = growth_bounds(plan.depth / c_s if c_s else plan.transit_time, drive.scales.t_s, drive.duration)
    return start, end, float(np.log10(end / start)) if end > start else -np.inf


class StokesDrives(Experiment):
    """Held loads: ``fit_on_drives`` fits mu(I) on the drives' steady windows instead of a calibration (a
    restatement, never scored as support); ``any_pair_style`` accepts a calibration run in the other LAMMPS
    implementation of the same contact law (the two styles' drives compared like for like); ``settings`` the
    coarse-graining's."""

    name = "stokes"
    title = "continuum vs DEM: Stokes' first problem"
    problem = "Stokes' first problem: a plate set in motion by a held stress or a held speed"
    tables_marker = tables.DEM_JSON
    titles = report.FIGURE_TITLES
    how_to_read = report.HOW_TO_READ
    report = report
    definitions = metrics.DEFINITIONS

    def __init__(self, calibration: str | Path | None = None, *, fit_on_drives: bool = False,
                 any_pair_style: bool = False, settings: CGSettings = CGSettings(), jobs: int = 1,
                 progress: bool = True):
        super().__init__(calibration, jobs=jobs, progress=progress)
        if (calibration is None) != fit_on_drives:
            raise ValueError("--calibration is required: a calibration.json of granstokes dem calibrate (an "
                             "independent plane-shear calibration of the same grains); or pass --fit-on-drives for a "
                             "fit on the drives that is never scored as support (not both)")
        require(not (any_pair_style and fit_on_drives), "--any-pair-style", "with --calibration (a fit on the drives "
                "has the drives' own pair style)", "--fit-on-drives")
        self.settings = settings
        self.ignore = IGNORABLE if any_pair_style else ()
        self.independent = calibrate.load(calibration) if calibration is not None else None

    @classmethod
    def accepts(cls, load) -> bool:
        return not load.oscillating

    @classmethod
    def outputs(cls, drives, output) -> dict:
        """Snapshots every t_s/FRAMES_PER_TS of the fastest drive (the plate's and the profiles' intervals no
        longer), every t_s/EARLY_FRAMES_PER_TS over its first t_s."""
        t_s = min(d.scales.t_s for d in drives)
        frame = t_s / FRAMES_PER_TS
        return {"atoms": frame, "contacts": frame, "plate": min(output.plate, frame),
                "profiles": min(output.profiles, frame), "early": t_s, "atoms_early": t_s / EARLY_FRAMES_PER_TS}

    @classmethod
    def comparison_seconds(cls, drives: int, grain_frames: float, jobs: int, speed) -> float:
        """The coarse-graining of every snapshot (one process), each drive's model side (MODELS models) as a unit
        of work over ``jobs`` processes, then its report (one process)."""
        rate = speed.rate(2, "drive")
        model = makespan([MODELS * MODEL_DRIVE_STEPS / rate] * drives, jobs, contention=speed.contention)
        return (grain_frames / CG_PER_DRIVE_STEP + drives * REPORT_DRIVE_STEPS) / rate + model

    @classmethod
    def plan_header(cls, c_s: float | None = None) -> str:
        return (f"growth windows from {TRANSITS_BEFORE_COMPARISON:g} shear-wave transits to min({GROWTH_END:g} t_s, "
                f"half the record), the growth laws' (a power law needs {MIN_DECADES:g} decade); transits at "
                + (f"the calibration's measured c_s = {c_s:.4g}" if c_s else
                   "the contacts' speed (no measured c_s: an upper bound, the windows longer than they will be)"))

    @classmethod
    def planned(cls, plan, drive, c_s: float | None = None) -> str:
        """'growth window 0.41 decade(s) [0.81, 2.1]' (compare.laws.growth_bounds at the planned depth, t_s and
        duration)."""
        start, end, decades = planned_window(plan, drive, c_s)
        return (f"growth window {decades:.2g} decade(s) [{start:.3g}, {end:.3g}]" if np.isfinite(decades)
                else f"no growth window (the elastic start, {start:.3g}, reaches past {end:.3g})")

    @classmethod
    def comparison_work(cls, drives: int, grain_frames: float) -> str:
        return f"{count(grain_frames)} grain-frames coarse-grained, {drives} drive(s) x {MODELS} models"

    def analyse(self, runs, root: Path | None = None) -> DemSide:
        if self.independent is not None:  # a calibration of other grains is refused before any coarse-graining
            check_grains(self.independent, run_grains(runs), self.ignore)
        return analyse(runs, self.settings, self.progress, root)

    def read_tables(self, folder: Path) -> DemSide:
        return tables.read(folder)

    @classmethod
    def merge(cls, sides: list[DemSide]) -> DemSide:
        return tables.merge(sides)

    @classmethod
    def write_tables(cls, result, folder: Path) -> None:
        tables.write(result.dem, folder)

    def _prepare(self, dem: DemSide):
        dem = timed(dem, self.independent)
        return dem, *prepare(dem, self.independent, self.ignore)

    def _units(self, dem, setup) -> list:
        return list(setup[0].drives)

    def _predict(self, drive, setup):
        return model_drive(drive, setup[1])

    def _conclude(self, dem, setup, predicted):
        timed_dem, side, kept = setup
        return conclude(timed_dem, side, kept, predicted, self.settings)
