"""A study's TOML schema, its validation (before anything runs) and the shipped presets.

A study is valid with these keys (DEM units; example)::

    name = "smoke"
    dem = "smoke"              # the DEM preset whose grains, box width, outputs and preparation every run takes
    seeds = [1, 2]             # beds per pressure (independent samples)
    pressures = [10.0, 20.0]   # p_w [rho_p g d]; one material: the grains' k_n is the DEM preset's at the highest
    # the independent mu(I) calibration: a calibration.json of these grains, or run = true: the DEM preset's
    # [calibration] table (with the entries given here) at the lowest and the highest pressure, the first stage
    calibration = {run = true, I = [0.005, 0.02, 0.08, 0.2, 0.4, 0.6]}
    # drives run at every pressure from the same beds: stress by mu_w_tilde, mu_w or tau_w; speed by u_w or
    # mu_w_tilde (the paper's u~_w: the steady speed of that stress)
    drive = [{kind = "stress", mu_w_tilde = 0.5}, {kind = "speed", mu_w_tilde = 0.5}]

Optional: ``duration_ts`` (drive length in calibrated t_s, default 10), ``min_duration``, ``width`` (the box's
x width in d; default the DEM preset's), ``width_check`` (default true: the first drive again at the highest
pressure in a box twice as wide).  ``omega_ts`` (a list of omega t_s) makes it a study of the oscillating plate
(Stokes' second problem): every drive's load is the amplitude of a sine, run at each frequency for ``cycles``
periods (default 4), and the comparison is compare.oscillation's; ``ngf_from``: a Stokes report's metrics.json
whose NGF amplitude A (fitted on a Stokes drive of the same grains) predicts the oscillating drives (else no NGF
rows).  ``[target]``: the error a Stokes study needs (compare.noise.Target): per scored observable the smallest
difference to decide (``u_w_inf``, ``mu_w_inf``, ``t90`` as a fraction of the expected u_w, mu_w, t_s;
``delta_u``, ``creep_length`` in d), optional ``confidence`` (default 0.95) and ``beds_max`` (default 12); each run then
takes the beds its drives need (``seeds`` the first of them, the next integers after), at least ``seeds``' count::

    target = {u_w_inf = 0.03, mu_w_inf = 0.03, creep_length = 0.3, beds_max = 8}

``stiffness_at``: the pressure at which the DEM preset's kappa holds (default the highest pressure): a study run in
parts gives each part the whole study's, so that every part has the same grains.  Unknown keys are errors.
"""
from __future__ import annotations

import dataclasses
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from granstokes.dem import config as dem_config
from granstokes.lib.toml_text import parse_assignment, with_entries
from granstokes.lib.validate import finite, require

if TYPE_CHECKING:
    from granstokes.compare.noise import Target

PRESET_DIR = Path(__file__).parent / "presets"
#: a preset's relative paths name the committed results of the granstokes repository: they are resolved against
#: its root (the folder holding the package's source), whatever the working directory
PRESET_BASE = PRESET_DIR.resolve().parents[2]
PRESETS = tuple(sorted(p.stem for p in PRESET_DIR.glob("*.toml")))
DRIVE_KEYS = ("kind", *dem_config.LOADS)
SHORT = {"mu_w_tilde": "mutilde", "mu_w": "mu", "tau_w": "tau", "u_w": "u"}  # drive names: stress-mutilde0.5
TOP = {"name", "dem", "seeds", "pressures", "calibration", "drive", "duration_ts", "min_duration", "width",
       "width_check", "omega_ts", "cycles", "ngf_from", "target", "stiffness_at"}
#: the [target] entries that are not an observable's difference
TARGET_OPTIONS = ("confidence", "beds_max")


def wave_label(omega_ts: float | None) -> str:
    """What names an oscillating drive's frequency (a held drive: nothing): -w0.5 in stress-mutilde0.5-w0.5 and in
    the run p20-w0.5 of its frequency."""
    return "" if omega_ts is None else f"-w{omega_ts:g}"


@dataclass(frozen=True)
class Study:
    name: str
    dem: str
    seeds: tuple[int, ...]
    pressures: tuple[float, ...]
    drives: tuple[dem_config.Drive, ...]  # run at every pressure, named by kind, load and frequency
    calibration_file: str | None
    calibration_table: tuple = ()  # (key, value) entries of the DEM [calibration] table when the study runs it
    width: float | None = None
    width_check: bool = True
    ngf_from: str | None = None  # an oscillating study's NGF amplitude: a Stokes report's metrics.json
    target: Target | None = None  # the error each run's beds are chosen for (compare.noise)
    stiffness_at: float | None = None  # the p_w whose kappa (the DEM preset's) sets k_n; None: the highest pressure

    @property
    def oscillating(self) -> bool:
        """A study of the oscillating plate (every drive a sine)."""
        return any(d.oscillating for d in self.drives)

    @property
    def frequencies(self) -> tuple[float | None, ...]:
        """The drives' distinct omega t_s, increasing (held drives: None): a run each at every pressure."""
        return tuple(sorted({d.omega_ts for d in self.drives}))

    @property
    def calibration_pressures(self) -> tuple[float, ...]:
        """Where the study's own calibration runs: the lowest and the highest pressure."""
        return tuple(sorted({min(self.pressures), max(self.pressures)}))

    @property
    def stiffness_pressure(self) -> float:
        """The pressure at which the DEM preset's kappa holds: k_n, one for every run, follows from it."""
        return self.stiffness_at if self.stiffness_at is not None else max(self.pressures)

    @property
    def reference_pressure(self) -> float:
        """The pressure whose calibration predicts every drive (the other tests mu(I)'s dependence on p)."""
        return max(self.pressures)


def _drive(table, k: int, duration_ts: float, min_duration: float) -> dem_config.Drive:
    """The [[drive]] table ``k`` as a DEM drive (its own checks too) of ``duration_ts`` t_s, named by its kind and
    load: stress-mutilde0.5."""
    where = f"drive[{k}]"
    require(isinstance(table, dict) and set(table) <= set(DRIVE_KEYS), f"{where} keys", f"among {list(DRIVE_KEYS)}",
            table)
    loads = [key for key in DRIVE_KEYS[1:] if key in table]
    require(len(loads) == 1, f"{where} load", "exactly one of mu_w_tilde, mu_w, tau_w (stress) or u_w, mu_w_tilde "
            "(speed)", loads)
    value = table[loads[0]]
    require(finite(value) and value > 0, f"{where}.{loads[0]}", "a finite number > 0", value)
    kind, value = table.get("kind"), float(value)
    return dem_config.Drive(f"{kind}-{SHORT[loads[0]]}{value:g}", kind, **{loads[0]: value}, duration_ts=duration_ts,
                            min_duration=min_duration)


def _oscillating(drive: dem_config.Drive, omega_ts: float, cycles: float) -> dem_config.Drive:
    """``drive`` as the amplitude of a sine at ``omega_ts``, run ``cycles`` periods: stress-mutilde0.5-w1."""
    return dataclasses.replace(drive, name=drive.name + wave_label(omega_ts), omega_ts=omega_ts, cycles=cycles)


def from_dict(doc: dict, base: Path | None = None) -> Study:
    """Validated Study from a parsed TOML document (``base``: the folder a relative calibration file is in)."""
    unknown = sorted(set(doc) - TOP)
    require(not unknown, "study keys", f"among {sorted(TOP)}", unknown)
    require(doc.get("dem") in dem_config.PRESETS, "dem", f"one of the DEM presets {list(dem_config.PRESETS)}",
            doc.get("dem"))
    seeds = doc.get("seeds", [1])
    require(isinstance(seeds, list) and len(seeds) >= 1
            and all(isinstance(s, int) and not isinstance(s, bool) and 0 < s < 2**31 for s in seeds)
            and len(set(seeds)) == len(seeds), "seeds", "a list of distinct integers in [1, 2^31)", seeds)
    pressures = doc.get("pressures")
    require(isinstance(pressures, list) and len(pressures) >= 1 and all(finite(p) and p > 0 for p in pressures)
            and len(set(pressures)) == len(pressures), "pressures", "a list of distinct p_w > 0 [rho_p g d]",
            pressures)
    cal = doc.get("calibration")
    require(isinstance(cal, dict) and (set(cal) == {"file"} or cal.get("run") is True), "calibration",
            "{file = 'calibration.json'} or {run = true, ...entries of the DEM [calibration] table}", cal)
    table = tuple((k, tuple(v) if isinstance(v, list) else v) for k, v in cal.items() if k != "run")
    if cal.get("run"):
        known = {f.name for f in dataclasses.fields(dem_config.Calibration)}
        require(set(dict(table)) <= known, "calibration keys", f"run and among {sorted(known)}", sorted(dict(table)))
    file = cal.get("file")
    if file is not None:
        file = _existing(file, base, "calibration.file", "a calibration.json of granstokes dem calibrate")
    ngf_from = doc.get("ngf_from")
    if ngf_from is not None:
        require(doc.get("omega_ts") is not None, "ngf_from", "only with omega_ts (an oscillating "
                "study; a Stokes study fits NGF's A on its own drives)", ngf_from)
        ngf_from = _existing(ngf_from, base, "ngf_from", "a Stokes report's metrics.json")
    duration_ts = doc.get("duration_ts", dem_config.Drive.duration_ts)
    min_duration = doc.get("min_duration", dem_config.Drive.min_duration)
    require(finite(duration_ts) and duration_ts > 0, "duration_ts", "a finite number > 0", duration_ts)
    require(finite(min_duration) and min_duration >= 0, "min_duration", "a finite number >= 0", min_duration)
    drives = doc.get("drive")
    require(isinstance(drives, list) and drives, "drive", "an array of at least one [[drive]] table", drives)
    built = tuple(_drive(t, k, float(duration_ts), float(min_duration)) for k, t in enumerate(drives))
    omegas, cycles = doc.get("omega_ts"), doc.get("cycles", dem_config.Drive.cycles)
    require(omegas is None or (isinstance(omegas, list) and omegas and all(finite(w) and w > 0 for w in omegas)
                               and len(set(omegas)) == len(omegas)), "omega_ts",
            "a list of distinct omega t_s > 0 (an oscillating plate)", omegas)
    require(finite(cycles) and cycles >= dem_config.MIN_CYCLES, "cycles",
            f"a number of periods >= {dem_config.MIN_CYCLES}", cycles)
    if omegas is not None:
        built = tuple(_oscillating(d, float(w), float(cycles)) for d in built for w in omegas)
    require(len({d.name for d in built}) == len(built), "drive", "distinct drives", [d.name for d in built])
    width = doc.get("width")
    require(width is None or (finite(width) and width >= dem_config.MIN_WIDTH), "width",
            f"a number >= {dem_config.MIN_WIDTH:g} d", width)
    width_check = doc.get("width_check", omegas is None)
    require(isinstance(width_check, bool) and not (width_check and omegas is not None), "width_check",
            "true or false (false with omega_ts: the width check is a Stokes drive's)", width_check)
    target = _target(doc.get("target"), len(seeds), omegas is not None)
    stiffness_at = doc.get("stiffness_at")
    require(stiffness_at is None or (finite(stiffness_at) and stiffness_at > 0), "stiffness_at",
            "a pressure > 0 [rho_p g d] (a study's part: the whole study's highest)", stiffness_at)
    name = doc.get("name", "study")
    require(isinstance(name, str) and name.replace("-", "").replace("_", "").isalnum(), "name",
            "letters, digits, '-' and '_'", name)
    return Study(name, doc["dem"], tuple(seeds), tuple(float(p) for p in pressures), built, file,
                 table if file is None else (), None if width is None else float(width), width_check, ngf_from,
                 target, None if stiffness_at is None else float(stiffness_at))


def _target(table, seeds: int, oscillating: bool) -> Target | None:
    """The [target] table as a compare.noise.Target (None when absent)."""
    if table is None:
        return None
    from granstokes.compare import noise  # the error law's table is read only by a study that states a target

    observables = sorted(set(noise.SCORED["stress"]) | set(noise.SCORED["speed"]))
    require(not oscillating, "target", "only in a Stokes study (the error law is the held drives')", table)
    require(isinstance(table, dict) and set(table) <= {*observables, *TARGET_OPTIONS}
            and set(table) - set(TARGET_OPTIONS), "target keys",
            f"at least one of {observables}, and optionally {list(TARGET_OPTIONS)}", table)
    for obs in set(table) & set(observables):
        require(finite(table[obs]) and table[obs] > 0, f"target.{obs}", "a difference > 0 (u_w_inf, mu_w_inf, t90: a "
                "fraction of the expected u_w, mu_w, t_s)", table[obs])
    confidence = table.get("confidence", noise.CONFIDENCE)
    require(finite(confidence) and 0.5 <= confidence < 1, "target.confidence", "a number in [0.5, 1)", confidence)
    beds_max = table.get("beds_max", max(noise.BEDS_MAX, seeds))
    require(isinstance(beds_max, int) and not isinstance(beds_max, bool) and max(seeds, noise.MIN_BEDS) <= beds_max,
            "target.beds_max", f"an integer >= {max(seeds, noise.MIN_BEDS)} (the seeds given, at least "
            f"{noise.MIN_BEDS})", beds_max)
    return noise.Target(tuple((obs, float(table[obs])) for obs in observables if obs in table), float(confidence),
                        beds_max)


def _existing(file: str, base: Path | None, name: str, what: str) -> str:
    """The absolute path of an existing ``file`` (relative to ``base``); a missing one is named as missing."""
    path = Path(file) if Path(file).is_absolute() or base is None else base / file
    require(path.is_file(), name, f"{what} (this file is missing)" if not path.exists() else what, str(path))
    return str(path.resolve())


def parse(text: str, base: Path | None = None) -> Study:
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"study is not valid TOML: {exc}") from None
    return from_dict(doc, base)


def preset_text(name: str) -> str:
    require(name in PRESETS, "--preset", f"one of {list(PRESETS)}", name)
    return (PRESET_DIR / f"{name}.toml").read_text()


def load(config: str | None, preset: str | None, sets=()) -> tuple[Study, str]:
    """The study and its text from STUDY.toml or --preset, with --set entries applied."""
    require((config is None) != (preset is None), "STUDY.toml / --preset", "exactly one of them", [config, preset])
    text = Path(config).read_text() if config is not None else preset_text(preset)
    text = with_entries(text, [parse_assignment(a) for a in sets],
                        header=f"{config or preset} with --set " + " ".join(sets))
    return parse(text, Path(config).resolve().parent if config is not None else PRESET_BASE), text


