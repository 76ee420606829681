"""DEM scene configuration: TOML schema, validation (before anything runs) and the presets.

A config is a TOML document (DEM units: d = rho_p = g = 1); this example is valid::

    name = "demo"
    seeds = [1]           # one prepared bed per seed (ensembles)
    dt = "auto"           # or a number <= t_c/20 (the default, t_c from the contact law)
    # the bed's expected mu(I) parameters (continuum.scales.Material), used for sizing
    material = {mu_s = 0.28, mu_d = 0.58, I0 = 0.3, I_convention = "dem", phi = 0.8}
    # dimension 2 (disks) or 3 (spheres); diameters uniform by number in [1-w, 1+w] d; pair_style "classic" (the
    # Hooke default, LAMMPS's gran/hooke/history) or "granular" (Hertz's only style; dem.contact)
    grains = {dimension = 2, polydispersity = 0.2, mu_p = 0.5, restitution = 0.5, contact = "hooke", kappa = 1e4}
    box = {width = 32.0}   # widths and depth in d; no depth -> max delta_s + margin (default dem.sizing.clearance)
    load = {p_w = 20.0}
    # kind "stress" (mu_w, mu_w_tilde or tau_w) or "speed" (u_w, or mu_w_tilde: the matching steady speed), held
    # from t = 0; with omega (1/time) or omega_ts (omega t_s) the load is the amplitude of a sine, run `cycles` periods
    drive = [{name = "stress", kind = "stress", mu_w_tilde = 0.5, duration_ts = 10.0},
             {name = "speed", kind = "speed", u_w = 5.0, duration = 20.0},
             {name = "wave", kind = "speed", mu_w_tilde = 0.5, omega_ts = 1.0, cycles = 4}]
    output = {plate = 0.02, thermo = 0.1, atoms = 1.0, contacts = 5.0, profiles = 0.5, restart = 2.0}
    prepare = {ke_per_grain = 1e-5, settle_ke_per_grain = 0.03}
    # mu(I) calibration by plane shear of the same grains at p = p_w (``granstokes dem calibrate``)
    # (and the shear modulus of its static packing: modulus = false leaves it out)
    calibration = {I_min = 1e-3, I_max = 0.5, points = 8, seeds = [1, 2], width = 10.0, strain = 5.0}

The drives and the ``material`` table (mu_s, mu_d, I0, I_convention, phi: no defaults, a scene's size
follows from them) are required, every other key is optional; unknown keys are errors.
"""
from __future__ import annotations

import dataclasses
import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from granstokes.continuum.scales import Material

from granstokes.lib.validate import finite, require

from .contact import Contact

MIN_WIDTH = 8.0  # d: narrower periodic boxes order the packing and correlate the plate with its image
MIN_WIDTH_Z = 4.0
MIN_DEPTH = 4.0
MIN_CYCLES = 2  # an oscillating drive: the first cycle is the start-up, the estimators need one more at least
MIN_CALIBRATION_STRAIN = 5.0  # each calibration point is measured over at least this strain
FINITE_SIZE_RTOL = 1e-4  # a calibration.finite_size entry names the point within this relative difference of its I
KAPPA_MIN = 1e4  # rigid limit: overlap under p_w d at most 1e-4 d


def _positive(name, value, minimum=0.0, strict=True):
    ok = finite(value) and (value > minimum if strict else value >= minimum)
    require(ok, name, f"a finite number {'>' if strict else '>='} {minimum:g}", value)


@dataclass(frozen=True)
class Grains:
    """Grains: disks (2D) or spheres (3D) with diameters uniform by number in [1-w, 1+w] d."""

    dimension: int = 2
    polydispersity: float = 0.15
    mu_p: float = 0.5
    restitution: float = 0.5
    contact: str = "hooke"
    kappa: float = 1e4
    kt_over_kn: float = 2 / 7
    pair_style: str | None = None  # "classic" for Hooke, "granular" for Hertz (dem.contact)

    def __post_init__(self):
        require(self.dimension in (2, 3), "grains.dimension", "2 or 3", self.dimension)
        require(finite(self.polydispersity) and 0 <= self.polydispersity <= 0.3,
                "grains.polydispersity", "in [0, 0.3] (half-width of the diameter range in d)", self.polydispersity)
        _positive("grains.mu_p", self.mu_p, strict=False)
        require(finite(self.restitution) and 0 < self.restitution < 1, "grains.restitution",
                "in the open interval (0, 1)", self.restitution)
        require(self.contact in ("hooke", "hertz"), "grains.contact", "'hooke' or 'hertz'", self.contact)
        require(finite(self.kappa) and self.kappa >= KAPPA_MIN, "grains.kappa",
                f"a finite number >= {KAPPA_MIN:g} (rigid limit)", self.kappa)
        require(finite(self.kt_over_kn) and 0 < self.kt_over_kn <= 1, "grains.kt_over_kn", "in (0, 1]",
                self.kt_over_kn)
        if self.pair_style is None:
            object.__setattr__(self, "pair_style", "classic" if self.contact == "hooke" else "granular")
        require(self.pair_style == "granular" or (self.pair_style == "classic" and self.contact == "hooke"),
                "grains.pair_style", "'granular', or 'classic' with contact = 'hooke'", self.pair_style)


@dataclass(frozen=True)
class Box:
    """Periodic widths (x; z in 3D) and bed depth in d; ``depth=None`` sizes it from delta_s + margin
    (``margin=None``: dem.sizing's creep margin)."""

    width: float = 20.0
    width_z: float | None = None
    depth: float | None = None
    margin: float | None = None
    base_thickness: float = 1.5

    def __post_init__(self):
        _positive("box.width", self.width, MIN_WIDTH, strict=False)
        if self.width_z is not None:
            _positive("box.width_z", self.width_z, MIN_WIDTH_Z, strict=False)
        if self.depth is not None:
            _positive("box.depth", self.depth, MIN_DEPTH, strict=False)
        if self.margin is not None:
            _positive("box.margin", self.margin, strict=False)
        require(finite(self.base_thickness) and 0.5 <= self.base_thickness <= 5, "box.base_thickness",
                "in [0.5, 5] (d)", self.base_thickness)


#: a drive's load keys: one of them gives it
LOADS = ("mu_w_tilde", "mu_w", "tau_w", "u_w")


@dataclass(frozen=True)
class Drive:
    """One drive of the prepared bed: imposed stress (tau_w = mu_w p_w) or imposed plate speed u_w, held from t = 0
    or, with ``omega`` (angular frequency, 1/sqrt(d/g)) or ``omega_ts`` (omega t_s, t_s of the amplitude's steady
    layer), the amplitude of a sine run ``cycles`` periods (continuum.load.Load)."""

    name: str
    kind: str
    mu_w_tilde: float | None = None
    mu_w: float | None = None
    tau_w: float | None = None
    u_w: float | None = None
    duration: float | None = None
    duration_ts: float = 10.0
    min_duration: float = 0.0
    omega: float | None = None
    omega_ts: float | None = None
    cycles: float = 4.0

    def __post_init__(self):
        require(isinstance(self.name, str) and re.fullmatch(r"[A-Za-z0-9_.-]+", self.name) is not None,
                "drive.name", "a non-empty name of letters, digits, '_', '-', '.'", self.name)
        p = f"drive[{self.name}]"
        require(self.kind in ("stress", "speed"), f"{p}.kind", "'stress' or 'speed'", self.kind)
        given = [k for k in LOADS if getattr(self, k) is not None]
        valid = {"stress": ("mu_w_tilde", "mu_w", "tau_w"), "speed": ("u_w", "mu_w_tilde")}[self.kind]
        require(len(given) == 1 and given[0] in valid, f"{p} load",
                f"exactly one of {' / '.join(valid)} for a {self.kind} drive", given)
        if self.mu_w_tilde is not None:
            require(finite(self.mu_w_tilde) and 0 < self.mu_w_tilde < 1, f"{p}.mu_w_tilde", "in (0, 1)",
                    self.mu_w_tilde)
        if self.u_w is not None:
            _positive(f"{p}.u_w", self.u_w)
        if self.mu_w is not None:
            _positive(f"{p}.mu_w", self.mu_w)
        if self.tau_w is not None:
            _positive(f"{p}.tau_w", self.tau_w)
        if self.duration is not None:
            _positive(f"{p}.duration", self.duration)
        _positive(f"{p}.duration_ts", self.duration_ts)
        _positive(f"{p}.min_duration", self.min_duration, strict=False)
        require(self.omega is None or self.omega_ts is None, f"{p}.omega", "left out when omega_ts is given",
                self.omega)
        for key in ("omega", "omega_ts"):
            if getattr(self, key) is not None:
                _positive(f"{p}.{key}", getattr(self, key))
        require(finite(self.cycles) and self.cycles >= MIN_CYCLES, f"{p}.cycles",
                f"a number of periods >= {MIN_CYCLES}", self.cycles)

    @property
    def oscillating(self) -> bool:
        return self.omega is not None or self.omega_ts is not None

    def table(self) -> dict:
        """The [[drive]] table that gives this drive: its name, kind and load; its duration, or what sizes it
        (duration_ts, min_duration); an oscillating drive's omega (or omega_ts) and cycles."""
        load = next(k for k in LOADS if getattr(self, k) is not None)
        length = ({"duration": self.duration} if self.duration is not None
                  else {"duration_ts": self.duration_ts, "min_duration": self.min_duration})
        frequency = {k: v for k, v in (("omega", self.omega), ("omega_ts", self.omega_ts)) if v is not None}
        wave = {**dict(list(frequency.items())[:1]), "cycles": self.cycles} if frequency else {}
        return {"name": self.name, "kind": self.kind, load: getattr(self, load), **length, **wave}


@dataclass(frozen=True)
class Output:
    """Output intervals in time units sqrt(d/g); each is rounded to a multiple of ``plate`` steps.  Over the
    first ``early`` time units of a drive (0: none) atom snapshots come every ``atoms_early`` (a divisor of
    ``atoms``): the layer's growth resolved."""

    plate: float = 0.02
    thermo: float = 0.1
    atoms: float = 1.0
    contacts: float = 5.0
    profiles: float = 0.5
    restart: float = 2.0
    early: float = 0.0
    atoms_early: float = 0.1

    def __post_init__(self):
        for f in dataclasses.fields(self):
            _positive(f"output.{f.name}", getattr(self, f.name), strict=f.name != "early")


#: settling's threshold at most this kinetic energy per grain (m g d): above it the pile still moves as a whole
SETTLE_KE_MAX = 0.1


@dataclass(frozen=True)
class Prepare:
    """Preparation: the fall and settling under gravity until the pile has landed (its kinetic energy past
    its peak) and the kinetic energy per grain is below ``settle_ke_per_grain``, then relaxation under the
    plate until that of the bed and the plate together is below ``ke_per_grain`` (units m g d with m the
    mean grain mass, per bed grain), each stage capped."""

    ke_per_grain: float = 1e-5
    settle_ke_per_grain: float = 0.03
    check_every: float = 0.5
    settle_max: float = 60.0
    relax_max: float = 40.0
    plate_gap: float = 0.2

    def __post_init__(self):
        for f in dataclasses.fields(self):
            _positive(f"prepare.{f.name}", getattr(self, f.name))
        require(self.ke_per_grain <= self.settle_ke_per_grain <= SETTLE_KE_MAX, "prepare.settle_ke_per_grain",
                f"in [ke_per_grain = {self.ke_per_grain:g}, {SETTLE_KE_MAX:g}] (m g d per grain: a landed pile)",
                self.settle_ke_per_grain)


@dataclass(frozen=True)
class Calibration:
    """Plane-shear calibration of the config's grains (dem.calibrate) at the normal stress p = p_w, so
    that the rigidity is the Stokes scene's kappa: ``points`` inertial numbers log-spaced in [I_min,
    I_max] (DEM convention; the default's 2 decades up to 0.7 reach where mu(I) bends towards mu_d: below I ~ 0.3
    the law is nearly linear and mu_d, I0 are not determined), or the increasing list ``I`` (then I_min, I_max and
    points follow from it),
    each seed an independent cell of width ``width`` d (square in 2D, cubic in 3D), sheared
    ``strain_start`` (discarded) then ``strain`` (measured), sampled every ``sample``.  ``finite_size``: some
    of the points' inertial numbers, at each of which one more cell of twice the width (first seed) checks
    the cell size (dem.calibrate; not fitted).  ``modulus``: the shear modulus G(p) and wave speed c_s of the cell's
    static packing by oscillatory shear (dem.modulus; at least 3 seeds, the calibration's first)."""

    I_min: float = 5e-3
    I_max: float = 0.7
    points: int = 7
    seeds: tuple[int, ...] = (1,)
    width: float = 12.0
    strain_start: float = 1.0
    strain: float = 5.0
    strain_max: float | None = None
    sample: float = 0.02
    profile: float = 0.25
    I: tuple[float, ...] | None = None
    finite_size: tuple[float, ...] = ()
    modulus: bool = True

    def __post_init__(self):
        require(isinstance(self.modulus, bool), "calibration.modulus", "true or false", self.modulus)
        if self.I is not None:
            require(len(self.I) >= 3 and all(finite(v) and 0 < v <= 1.0 for v in self.I)
                    and all(a < b for a, b in zip(self.I, self.I[1:])), "calibration.I",
                    "an increasing list of >= 3 inertial numbers in (0, 1]", list(self.I))
            for name, value in (("I_min", self.I[0]), ("I_max", self.I[-1]), ("points", len(self.I))):
                object.__setattr__(self, name, value)
        _positive("calibration.I_min", self.I_min)
        require(finite(self.I_max) and self.I_min < self.I_max <= 1.0, "calibration.I_max",
                f"in (I_min = {self.I_min:g}, 1] (dense flow)", self.I_max)
        require(isinstance(self.points, int) and not isinstance(self.points, bool) and self.points >= 3,
                "calibration.points", "an integer >= 3 (three fit parameters)", self.points)
        require(len(self.seeds) >= 1 and all(isinstance(s, int) and 0 < s < 2**31 for s in self.seeds)
                and len(set(self.seeds)) == len(self.seeds), "calibration.seeds",
                "a list of distinct integers in [1, 2^31)", list(self.seeds))
        _positive("calibration.width", self.width, MIN_WIDTH, strict=False)
        _positive("calibration.strain_start", self.strain_start, strict=False)
        _positive("calibration.strain", self.strain, MIN_CALIBRATION_STRAIN, strict=False)
        if self.strain_max is not None:
            require(finite(self.strain_max) and self.strain_max >= self.strain, "calibration.strain_max",
                    f">= strain = {self.strain:g}", self.strain_max)
        _positive("calibration.sample", self.sample)
        require(finite(self.profile) and self.sample <= self.profile <= self.strain, "calibration.profile",
                f"in [sample = {self.sample:g}, strain = {self.strain:g}]", self.profile)
        require(isinstance(self.finite_size, list | tuple), "calibration.finite_size", "a list of inertial numbers",
                self.finite_size)
        object.__setattr__(self, "finite_size", tuple(self.finite_size))
        points = self.inertial_numbers
        require(all(finite(v) and any(math.isclose(v, I, rel_tol=FINITE_SIZE_RTOL) for I in points)
                    for v in self.finite_size) and len(set(self.finite_size)) == len(self.finite_size),
                "calibration.finite_size", "distinct inertial numbers among the points' "
                f"({', '.join(f'{I:.6g}' for I in points)})", list(self.finite_size))

    @property
    def inertial_numbers(self) -> tuple[float, ...]:
        """The points' inertial numbers: the list ``I``, else log-spaced in [I_min, I_max]."""
        return self.I if self.I is not None else tuple(map(float, np.geomspace(self.I_min, self.I_max, self.points)))


@dataclass(frozen=True)
class Config:
    name: str
    drives: tuple[Drive, ...]
    material: Material
    grains: Grains = field(default_factory=Grains)
    box: Box = field(default_factory=Box)
    p_w: float = 10.0
    output: Output = field(default_factory=Output)
    prepare: Prepare = field(default_factory=Prepare)
    seeds: tuple[int, ...] = (1,)
    dt: float | None = None
    calibration: Calibration = field(default_factory=Calibration)
    absent: tuple[str, ...] = ()  # the optional tables the document did not give: their defaults apply

    def __post_init__(self):
        require(isinstance(self.name, str) and re.fullmatch(r"[A-Za-z0-9_.-]+", self.name) is not None,
                "name", "a non-empty name of letters, digits, '_', '-', '.'", self.name)
        _positive("load.p_w", self.p_w)
        for key in ("d", "rho_p", "g"):
            require(getattr(self.material, key) == 1.0, f"material.{key}", "1 (DEM units)",
                    getattr(self.material, key))
        if self.grains.dimension == 2:
            require(self.box.width_z is None, "box.width_z", "absent for a 2D scene (grains.dimension = 2)",
                    self.box.width_z)
        require(len(self.drives) >= 1, "drive", "at least one [[drive]] table", len(self.drives))
        names = [d.name for d in self.drives]
        require(len(set(names)) == len(names), "drive.name", "unique", names)
        require(len(self.seeds) >= 1 and all(isinstance(s, int) and 0 < s < 2**31 for s in self.seeds)
                and len(set(self.seeds)) == len(self.seeds), "seeds", "a list of distinct integers in [1, 2^31)",
                list(self.seeds))
        if self.dt is not None:
            _positive("dt", self.dt)
            bound = self.contact.dt_max
            require(self.dt <= bound, "dt",
                    f"<= t_c/20 = {bound:.4g} (stability bound of this contact law)", self.dt)

    @property
    def width_z(self) -> float | None:
        if self.grains.dimension == 2:
            return None
        return 8.0 if self.box.width_z is None else self.box.width_z

    @property
    def contact(self) -> Contact:
        g = self.grains
        return Contact(g.contact, g.dimension, self.p_w, g.kappa, g.restitution, g.mu_p, g.kt_over_kn,
                       g.polydispersity, g.pair_style)

    @property
    def time_step(self) -> float:
        return self.contact.dt_max if self.dt is None else self.dt

    def describe(self) -> list[str]:
        """The resolved scene a physicist checks before any run, one line per table (the defaults named)."""
        g, b, o, p = self.grains, self.box, self.output, self.prepare
        shape = "disks" if g.dimension == 2 else "spheres"
        m = self.material
        lines = [f"{g.dimension}D {shape}, p_w = {self.p_w:g} rho_p g d, seeds {list(self.seeds)}; sized from mu_s = "
                 f"{m.mu_s:.4g}, mu_d = {m.mu_d:.4g}, I0 = {m.I0:.4g} ({m.I_convention} convention), phi = {m.phi:.3g}",
                 f"grains: diameters in [{1 - g.polydispersity:g}, {1 + g.polydispersity:g}] d, mu_p = {g.mu_p:g}, "
                 f"restitution {g.restitution:g}, {g.contact} contact (pair_style {g.pair_style}), k_n = "
                 f"{self.contact.k_n:.4g} (kappa = {g.kappa:g} at this p_w), k_t/k_n = {g.kt_over_kn:.3g}",
                 f"box: width {b.width:g} d" + (f", width_z {self.width_z:g} d" if self.width_z else "")
                 + f", base {b.base_thickness:g} d, depth " + (f"{b.depth:g} d" if b.depth is not None else "sized"),
                 f"outputs every (sqrt(d/g)): plate {o.plate:g}, thermo {o.thermo:g}, atoms {o.atoms:g}, contacts "
                 f"{o.contacts:g}, profiles {o.profiles:g}, restart {o.restart:g}"
                 + (f"; atoms every {o.atoms_early:g} over the first {o.early:g}" if o.early else ""),
                 f"preparation: settle to {p.settle_ke_per_grain:g} m g d per grain (at most {p.settle_max:g}), relax "
                 f"to {p.ke_per_grain:g} (at most {p.relax_max:g}), plate gap {p.plate_gap:g} d"]
        if self.absent:
            lines.append("defaults (no table in the config): " + ", ".join(f"[{k}]" for k in self.absent))
        return lines

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


_TABLES = {"material": Material, "grains": Grains, "box": Box, "output": Output, "prepare": Prepare,
           "calibration": Calibration}
_TOP = {"name", "seeds", "dt", "material", "grains", "box", "load", "drive", "output", "prepare", "calibration"}
#: the material keys a config must give (the bed's expected mu(I) and packing: the scene is sized from them)
MATERIAL_KEYS = ("mu_s", "mu_d", "I0", "I_convention", "phi")


def _build(cls, table, where):
    require(isinstance(table, dict), where, "a table", table)
    if "seeds" in table:  # TOML arrays -> the frozen dataclasses' tuples
        require(isinstance(table["seeds"], list), f"{where}.seeds", "a list of integers", table["seeds"])
        table = {**table, "seeds": tuple(table["seeds"])}
    if "I" in table:  # the calibration's explicit inertial numbers replace the log-spaced range
        require(isinstance(table["I"], list), f"{where}.I", "a list of inertial numbers", table["I"])
        both = sorted({"I_min", "I_max", "points"} & set(table))
        require(not both, f"{where}.I", f"given without {both} (they follow from the list)", table["I"])
        table = {**table, "I": tuple(table["I"])}
    known = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(table) - known)
    require(not unknown, f"[{where}] keys", f"among {sorted(known)}", unknown)
    try:
        return cls(**table)
    except TypeError as exc:  # a missing required key
        raise ValueError(f"[{where}] {exc}") from None


def from_dict(doc: dict) -> Config:
    """Validated Config from a parsed TOML document; raises ValueError naming the bad parameter."""
    unknown = sorted(set(doc) - _TOP)
    require(not unknown, "top-level keys", f"among {sorted(_TOP)}", unknown)
    material = doc.get("material")
    missing = [k for k in MATERIAL_KEYS if not isinstance(material, dict) or k not in material]
    got = "no [material] table" if material is None else f"no {', '.join(missing)}" if isinstance(material, dict) \
        else material
    require(not missing, "[material]", f"a table giving {', '.join(MATERIAL_KEYS)} (the bed's expected mu(I) "
            "and packing, from which the scene is sized)", got)
    kwargs = {k: _build(cls, doc[k], k) for k, cls in _TABLES.items() if k in doc}
    load = doc.get("load", {})
    require(isinstance(load, dict) and set(load) <= {"p_w"}, "[load] keys", "['p_w']", load)
    if "p_w" in load:
        kwargs["p_w"] = load["p_w"]
    drives = doc.get("drive", [])
    require(isinstance(drives, list), "drive", "an array of [[drive]] tables", drives)
    kwargs["drives"] = tuple(_build(Drive, d, "drive") for d in drives)
    if "seeds" in doc:
        require(isinstance(doc["seeds"], list), "seeds", "a list of integers", doc["seeds"])
        kwargs["seeds"] = tuple(doc["seeds"])
    if "dt" in doc and doc["dt"] != "auto":
        kwargs["dt"] = doc["dt"]
    absent = tuple(k for k in (*_TABLES, "load") if k not in doc and k != "material")
    return Config(name=doc.get("name", "dem"), absent=absent, **kwargs)


def parse(text: str) -> Config:
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"config is not valid TOML: {exc}") from None
    return from_dict(doc)


def load(path: str | Path) -> tuple[Config, str]:
    """Config and its TOML text from a file."""
    text = Path(path).read_text()
    return parse(text), text


# --- presets: TOML files shipped in dem/presets/, loaded by the same validator as user configs ---
PRESET_DIR = Path(__file__).parent / "presets"
PRESETS = tuple(sorted(p.stem for p in PRESET_DIR.glob("*.toml")))


def preset_text(name: str) -> str:
    require(name in PRESETS, "preset", f"one of {list(PRESETS)}", name)
    return (PRESET_DIR / f"{name}.toml").read_text()


def preset(name: str) -> tuple[Config, str]:
    text = preset_text(name)
    return parse(text), text
