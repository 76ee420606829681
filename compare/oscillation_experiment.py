"""The oscillating plate (Stokes' second problem) as an experiment (compare.experiment): every drive's plate record
and method-of-planes profiles (no dumps are read), the models solved on the DEM's times and depths and both put
through the same phase-resolved estimators (compare.oscillation), rendered by compare.oscillation_report.

It is the worked example of docs/experiments.md: what it adds to the base is what an experiment must say (the
loads it takes, its DEM side and tables, its setup, its unit of prediction work, its rendering); the rows, the
verdict rule, the calibration band, the parallel map and the report's shell are the base's."""
from __future__ import annotations

from pathlib import Path

import numpy as np
from granstokes.dem.sizing import makespan

from granstokes.lib.validate import require

from . import calibrate, oscillation_report, oscillation_tables
from .comparison import check_grains, run_grains
from .drive import with_transit_time
from .experiment import Experiment
from .oscillation import analyse_dem, conclude, dem_side, predict_unit, setup_of

#: an oscillating study's comparison per drive, in grain-steps of a 2D drive: its models' solves (central, coarse and
#: at each shifted calibrated parameter, local and NGF) and its share of the report, no dump read; the
#: oscillating-disks study's comparison, 4.0 min on 2 processes for 20 drives (7.2 CPU min) beside probes of 10 M
#: grain-steps/s, through the same contention model as the beds
OSCILLATION_DRIVE_STEPS = 1.6e8
#: LAMMPS's depth profiles this many times per period (the phase-resolved profiles of compare.oscillation), the
#: plate's record PLATE_PER_PROFILE times as often, atom snapshots once a period
PROFILES_PER_PERIOD, PLATE_PER_PROFILE = 24, 4


class OscillatingPlate(Experiment):
    """Sine loads, predicted blind from an independent calibration (required); ``ngf_from``: a Stokes report's
    metrics.json whose NGF amplitude (fitted on a Stokes drive of the same grains) predicts them."""

    name = "oscillating"
    title = "the oscillating plate (Stokes' second problem): DEM against the models"
    problem = "oscillating plate (Stokes' second problem)"
    tables_marker = oscillation_tables.DRIVES_JSON
    titles = oscillation_report.TITLES
    how_to_read = oscillation_report.HOW_TO_READ
    report = oscillation_report
    definitions = oscillation_report.DEFINITIONS

    def __init__(self, calibration: str | Path | None = None, *, ngf_from: str | Path | None = None, jobs: int = 1,
                 progress: bool = True):
        super().__init__(calibration, jobs=jobs, progress=progress)
        if calibration is None:
            raise ValueError("--calibration is required: a calibration.json (the oscillating drives are predicted "
                             "blind; no fit on them)")
        if ngf_from is not None and not Path(ngf_from).is_file():
            raise ValueError(f"--ngf-from: a Stokes report's metrics.json, got {ngf_from}")
        self.ngf_from = ngf_from
        self.independent = calibrate.load(calibration)

    @classmethod
    def accepts(cls, load) -> bool:
        return load.oscillating

    @classmethod
    def outputs(cls, drives, output) -> dict:
        """Profiles PROFILES_PER_PERIOD times a period of the fastest drive, the plate PLATE_PER_PROFILE times as
        often, snapshots once a period (the phase-resolved analysis reads the plate and the profiles)."""
        period = min(d.duration / d.drive.cycles for d in drives)
        profile = period / PROFILES_PER_PERIOD
        return {"atoms": period, "contacts": period, "plate": min(output.plate, profile / PLATE_PER_PROFILE),
                "profiles": profile, "restart": max(output.restart, period)}

    @classmethod
    def comparison_seconds(cls, drives: int, grain_frames: float, jobs: int, speed) -> float:
        rate = speed.rate(2, "drive")
        return makespan([OSCILLATION_DRIVE_STEPS / rate] * drives, jobs, contention=speed.contention)

    @classmethod
    def comparison_work(cls, drives: int, grain_frames: float) -> str:
        return f"{drives} drive(s), each model's solves; no dump is read"

    def analyse(self, runs, root: Path | None = None):
        check_grains(self.independent, run_grains(runs))  # other grains are refused before any work
        return dem_side(runs, root)

    def read_tables(self, folder: Path):
        return oscillation_tables.read(folder)

    @classmethod
    def merge(cls, sides: list) -> list:
        """The parts' drives together (ValueError naming --tables when a drive appears in two parts)."""
        drives = [pair for side in sides for pair in side]
        labels = [str(d.run / d.name) for d, _ in drives]
        require(len(set(labels)) == len(labels), "--tables", "tables of distinct drives (a study's parts)", labels)
        return drives

    @classmethod
    def write_tables(cls, result, folder: Path) -> None:
        oscillation_tables.write([(d.drive, list(d.records)) for d in result.drives], folder)

    def _prepare(self, dem):
        setup, ngf_note = setup_of(self.independent, self.ngf_from)
        cal = self.independent
        p_cal = float(cal.info.get("protocol", {}).get("p", np.nan))
        dems = [analyse_dem(with_transit_time(d, cal.grains, p_cal, cal.elasticity), records, setup.material.mu_s)
                for d, records in dem]
        return dem, dems, setup, ngf_note

    def _units(self, dem, setup) -> list:
        _, dems, models, _ = setup
        return [(d, m) for d in dems for m in models.models]

    def _predict(self, unit, setup):
        drive, model = unit
        return predict_unit(drive, setup[2], model)

    def _conclude(self, dem, setup, predicted):
        _, dems, models, ngf_note = setup
        return conclude(dem, dems, models, ngf_note, predicted, self.independent.source, self.ngf_from)
