"""The measured drive: one drive of one finished run, as its run.json describes it (what the plate imposed on which
scene, its beds' folders), the record every experiment of the comparison starts from.  The configured drive is
dem.config.Drive; this is the same drive once run, with what the run measured of its scene."""
from __future__ import annotations

import json
from dataclasses import dataclass, replace
from functools import cached_property
from pathlib import Path

import numpy as np
from granstokes.continuum.load import Load
from granstokes.continuum.scene import BedScene
from granstokes.dem import layout
from granstokes.dem.contact import Contact, rigidity
from granstokes.dem.sizing import sized_drives

from .reader import ATOMS, DriveFolder

#: transients are compared with the rigid continuum from this many shear-wave transits over the bed on: before, the
#: load is still carried down by an elastic wave that the continuum does not have
TRANSITS_BEFORE_COMPARISON = 3.0


@dataclass(frozen=True, eq=False)
class DriveSpec:
    """One drive of one run: its load (what the plate imposed, at which pressure), the scene (bed depth below the
    plate, plate mass per area, the plate's contact-plane offset), the run's numbers (steps per bed, the shear-wave
    transit time over the bed, t_s of the load's steady layer as sized, the drive's duration), its beds (count,
    grains of one, dimension) and the beds' folders (empty when read from a report's tables)."""

    run: Path
    name: str
    load: Load
    depth: float
    plate_mass: float
    surface_offset: float
    steps: int
    transit_time: float
    seeds: int
    grains: int
    dimension: int
    t_s: float = np.nan
    duration: float = np.nan
    folders: tuple[Path, ...] = ()

    @property
    def kind(self) -> str:
        return self.load.kind

    @property
    def p_w(self) -> float:
        return self.load.p_w

    @property
    def label(self) -> str:
        """Unique within a comparison: the run's path as given, then the drive."""
        return f"{self.run}/{self.name}"

    @property
    def scene(self) -> BedScene:
        """The drive's scene as the continuum models take it (with ``load``: continuum.scene_models)."""
        return BedScene(self.depth, plate_mass=self.plate_mass)

    @property
    def compared_from(self) -> float:
        """Transients are compared from this time on (TRANSITS_BEFORE_COMPARISON wave transits)."""
        return TRANSITS_BEFORE_COMPARISON * self.transit_time

    @property
    def cost(self) -> float:
        """grains x steps of the drive summed over beds (the DEM's work)."""
        return float(self.seeds * self.grains * self.steps)

    @property
    def omega_ts(self) -> float:
        """omega t_s of an oscillating load (0 for a held one)."""
        return self.load.omega * self.t_s

    @property
    def response(self) -> str:
        """The free response: u_w under an imposed stress, mu_w under an imposed speed."""
        return "u_w" if self.kind == "stress" else "mu_w"

    @cached_property
    def beds(self) -> tuple[DriveFolder, ...]:
        """The beds' folders with their snapshot streams (compare.reader; only for runs that wrote dumps)."""
        return tuple(DriveFolder(f) for f in self.folders)

    @property
    def has_dumps(self) -> bool:
        return bool(self.folders) and (self.folders[0] / ATOMS).exists()

    def as_record(self) -> dict:
        """JSON-ready, without the folders (a report's tables; ``from_record`` reads it back)."""
        return {"run": str(self.run), "name": self.name, "p_w": self.p_w, "load": self.load.as_record(),
                "depth": self.depth, "plate_mass": self.plate_mass, "surface_offset": self.surface_offset,
                "steps": self.steps, "transit_time": _json_number(self.transit_time), "seeds": self.seeds,
                "grains": self.grains, "dimension": self.dimension, "t_s": _json_number(self.t_s),
                "duration": _json_number(self.duration)}

    @classmethod
    def from_record(cls, r: dict) -> DriveSpec:
        """The record ``as_record`` wrote (a number it could not know, e.g. in tables of the oscillating plate
        written before they held the run's numbers, is NaN or 0)."""
        number = lambda key: np.nan if r.get(key) is None else float(r[key])
        return cls(Path(r["run"]), r["name"], Load.from_record(r["load"], r["p_w"]), r["depth"], r["plate_mass"],
                   r["surface_offset"], int(r.get("steps", 0)), number("transit_time"), int(r.get("seeds", 0)),
                   int(r.get("grains", 0)), int(r.get("dimension", 0)), number("t_s"), number("duration"))


def with_transit_time(drive: DriveSpec, grains: dict, p_grains: float, elasticity: dict | None = None) -> DriveSpec:
    """``drive`` with its shear-wave transit time over the bed: the bed's depth over the measured shear-wave speed
    c_s of the calibration's packing where the calibration holds it (``elasticity``: dem.modulus); else the run's
    own (the contacts' speed d sqrt(k_t/m), as dem.sizing times it), or, where the record lacks it (tables written
    before run.json held it), that speed from the calibration's ``grains``, whose rigidity kappa is stated at
    ``p_grains`` (one stiffness k_n at every pressure: dem.contact.rigidity; NaN: at the drive's p_w)."""
    if elasticity:
        return replace(drive, transit_time=drive.depth / float(elasticity["c_s"]))
    if np.isfinite(drive.transit_time):
        return drive
    p_w = drive.load.p_w
    p_grains = p_grains if np.isfinite(p_grains) else p_w
    contact = Contact(grains["contact"], int(grains["dimension"]), p_w,
                      rigidity(float(grains["kappa"]), grains["contact"], p_grains, p_w), float(grains["restitution"]),
                      float(grains["mu_p"]), float(grains["kt_over_kn"]), float(grains["polydispersity"]),
                      grains["pair_style"])
    return replace(drive, transit_time=drive.depth / contact.shear_wave_speed)


def _json_number(v: float):
    return float(v) if np.isfinite(v) else None


def drive_specs(run_dir: Path, root: Path | None = None) -> list[DriveSpec]:
    """The drives of a complete run folder (``ValueError`` naming the unfinished stages otherwise); with ``root``
    the run is named by its path relative to it."""
    run_dir = Path(run_dir)
    meta = json.loads((run_dir / layout.RUN_JSON).read_text())
    unfinished = [k for k, s in meta.get("stages", {}).items() if s.get("status") != "complete"]
    if unfinished:
        raise ValueError(f"{run_dir}: run not complete ({', '.join(unfinished)}); resume it first")
    name = run_dir.resolve().relative_to(Path(root).resolve()) if root is not None else run_dir
    sizing, plate = meta["sizing"], meta["plate"]
    specs = []
    for d in sized_drives(meta):
        folders = tuple(layout.drive_dir(run_dir, s, d.drive.name) for s in meta["seeds"])
        specs.append(DriveSpec(
            name, d.drive.name, d.load, float(sizing["depth"]), float(plate["mass_per_area"]),
            float(plate["surface_offset"]), d.steps, float(sizing.get("elastic_start", {}).get("transit_time", np.nan)),
            len(folders), len(layout.grains_table(folders[0])), int(meta["config"]["grains"]["dimension"]),
            d.scales.t_s, d.duration, folders))
    return specs


def run_loads(run_dir: Path) -> list[Load]:
    """The loads of a run folder's drives (none for a run not yet sized: its own error follows)."""
    return [d.load for d in sized_drives(json.loads((Path(run_dir) / layout.RUN_JSON).read_text()))]
