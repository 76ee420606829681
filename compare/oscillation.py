"""The oscillating plate (Stokes' second problem) confronted with DEM: every drive's records (plate.csv and LAMMPS's
depth profiles, profiles.csv: no dumps are read) and every model's solution (continuum.oscillation, sampled at the
same times and depths) go through the same phase-resolved estimators (compare.phase), whole cycles after the first.

Observables of a drive (``OBSERVABLES``; the imposed wall value is A sin(omega t), A = mu_w or u_w):
* ``response_amplitude``: the fundamental of the free response, u_w [sqrt(g d)] under an imposed stress, mu_w [1]
  under an imposed speed (the DEM's interval averages undone, compare.phase.harmonic);
* ``phase_lag`` [rad]: the response's lag behind the imposed sine, in (-pi, pi] (compare.phase.phase_lag);
* ``yielded_depth`` [d]: the cycle's mean depth of the edge between the dynamic and the static zone, the deepest
  depth where the phase-averaged |mu| = |tau_xy|/p reaches the calibrated mu_s, averaged over the phase (DEM: the
  method-of-planes stresses of profiles.csv; the zones' map in the (phase, depth) plane is ``zones``).  Not its
  maximum over the phase: below the layer |mu| falls slowly with depth (tau nearly uniform, p growing), so the
  noise of mu moves the crossing by noise/|dmu/dy| and the maximum of noisy crossings is biased deep;
* ``dissipation`` [rho_p g d^2 per plate area]: the energy per cycle, the integral of tau_w u_w dt (tau_w the
  plate's stress on the bed: the loop's area in the (x_w, tau_w) plane);
* ``remobilization_strain`` [1]: the plate's displacement from a reversal of its velocity until the response
  regains RESPONSE_FRACTION of its half-cycle peak, over the DEM's yielded depth (both sides: a displacement).
DEM values are the mean over the beds with their spread / sqrt(n), n - 1 degrees of freedom (one bed: the cycles as
blocks, cycles - 1); a row's dof is its combined error's (compare.rows.effective_dof: the model's errors have
infinitely many), and its verdict the Student-t test at that dof (compare.rows.verdict).  A drive whose beds are not
in one periodic state (``unsettled``: a bed jams, drifts or sits in another state than the others) keeps its rows,
unscored.  The laws in omega (``laws``) are measured over each law's family of estimator choices (``LAW_FAMILIES``),
the same on the DEM and the models, from the per-choice rows (``choice_rows``).  A model's band
is its numerical error (Richardson, n_cells/2) and the calibration's, sqrt(J C J^T) with J from solves at each
calibrated parameter shifted (compare.band) and C the calibration's replicates' covariance (NGF: A's variance too).
Conventions: DEM units (d, rho_p, g); mu > 0 where the bed resists a plate moving in +x.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path

import numpy as np
import pandas as pd
from granstokes.continuum import oscillation as osc
from granstokes.continuum.crossing import LAYER_FRACTIONS, depth_at_fraction
from granstokes.continuum.ngf import NonlocalFluidity
from granstokes.continuum.rheology import convert_I
from granstokes.continuum.richardson import richardson
from granstokes.continuum.rules import YieldRule
from granstokes.continuum.scales import Material
from granstokes.continuum.scene import BedScene, SceneNumerics
from granstokes.dem import layout
from scipy import stats

from granstokes.lib.validate import require

from . import calibrate, phase
from .band import Sensitivity
from .drive import TRANSITS_BEFORE_COMPARISON, DriveSpec, drive_specs
from .families import Choice, entry, family_note, headline, systematic
from .plate import SLIP_MAX
from .rows import LACK_OF_FIT_P, band, effective_dof, law_row, score_row, sigma
from .scorecard import extrapolated, wall_I

OBSERVABLES = {"response_amplitude": None, "phase_lag": "rad", "yielded_depth": "d",
               "dissipation": "rho_p g d^2 per plate area", "remobilization_strain": "1"}
#: the start-up: whole cycles discarded before any estimate
SKIP = 1
#: a reversal's remobilization ends when the response regains this fraction of its half-cycle peak
RESPONSE_FRACTION = 0.9
#: model samples per period (the DEM's plate record has about as many, compare's study plan)
SAMPLES_PER_PERIOD = 96
#: the comparison's numerics: percent-level DEM errors need no more (the rows' numerical_err says what it costs;
#: continuum.oscillation's defaults verify the solver to 1e-4)
NUMERICS = SceneNumerics(n_cells=80, rtol=1e-4, atol=1e-7)
#: the models compared (continuum.oscillation.MODELS) and their labels
LABELS = {"local": "local mu(I), velocity form on the DEM scene", "ngf": "nonlocal fluidity (NGF)",
          "elastic": "elasto-plastic mu(I), the bed's measured G"}
PARAMETERS = ("mu_s", "mu_d", "I0", "phi")
#: beds whose spread is the DEM's error (one bed: its cycles as blocks)
MIN_BEDS = 2


def unit(drive: DriveSpec, observable: str) -> str:
    """An observable's unit on ``drive`` (the response amplitude's is its response's)."""
    if observable == "response_amplitude":
        return "sqrt(g d)" if drive.response == "u_w" else "1"
    return OBSERVABLES[observable]


@dataclass(frozen=True)
class CycleChoice:
    """One estimator of a law's observable over the cycles (compare.families' Choice for the oscillating plate):
    ``estimator`` "fundamental" (the lag of the first harmonics) or "peak" (the lag of the phase-averaged response's
    peak, compare.phase.peak_lag); "edge" (the yielded depth: the cycle's mean depth where |mu| reaches mu_s) or a
    LAYER_FRACTIONS key (where the fundamental's amplitude of the velocity profile falls to that fraction of the
    reference speed's); ``reference`` the speed it is read against: "plate" (u_w) or "contact" (u_c, the grains
    touching the plate; a model does not slip, its u_c is its u_w), "" for the stress edge; ``skip`` the start-up
    cycles discarded."""

    estimator: str
    reference: str
    skip: int = SKIP

    def describe(self) -> str:
        """'the first harmonic's lag against the contact layer's speed, after 1 cycle'."""
        whose = {"plate": "the plate's", "contact": "the contact layer's"}.get(self.reference, "")
        what = {"fundamental": f"the first harmonic's lag against {whose} speed",
                "peak": f"the peak's lag against {whose} speed", "edge": "the depth where |mu| reaches mu_s"}.get(
            self.estimator) or (f"the depth where the speed's amplitude falls to "
                                f"{100 * LAYER_FRACTIONS[self.estimator]:g} % of {whose}")
        return f"{what}, after {self.skip} cycle{'' if self.skip == 1 else 's'}"


#: each law's observable measured over a family of choices, identically on the DEM and on the models, the primary
#: (the scorecard's row) first: the cycles kept (the start-up's one, or two), the speed the response is read
#: against (a slipping plate's or its contact layer's), and the estimator (the lag of the first harmonic or of the
#: peak; the stress edge or the velocity's depth at half and a fifth of the reference speed: not at 5 %, which in
#: the committed study lies 14 to 24 d deep in beds of 28 d, where the base, not the frequency, sets it)
LAW_FAMILIES = {
    "phase_lag": (CycleChoice("fundamental", "plate"), CycleChoice("fundamental", "plate", SKIP + 1),
                  CycleChoice("fundamental", "contact"), CycleChoice("peak", "plate")),
    "yielded_depth": (CycleChoice("edge", ""), CycleChoice("edge", "", SKIP + 1), CycleChoice("delta_50", "plate"),
                      CycleChoice("delta_50", "contact"), CycleChoice("delta_20", "plate")),
}


@dataclass(frozen=True, eq=False)
class Record:
    """One bed or one model solution of a drive: the plate's series (t, x_w, u_w, mu_w, tau_w; ``interval``: the
    samples' averaging window), the stress profiles (t, depth, mu) and the velocity profiles (t, depth, u)."""

    plate: pd.DataFrame
    profiles: pd.DataFrame
    velocity: pd.DataFrame
    interval: float = 0.0


def dem_record(folder: Path, drive: DriveSpec) -> Record:
    """A bed's plate.csv and profiles.csv as a Record: the plate's rows averaged in blocks of about a period over
    SAMPLES_PER_PERIOD (x_w at each block's end: the record's ``interval`` grows to the block's), mu = tau_mop/p_mop
    at the planes between the plate's mean contact plane and the base, u_x at the bins' centres; the profiles dated
    at the centre of the interval each averages."""
    plate = pd.read_csv(folder / layout.PLATE_CSV)
    plate = plate[plate.t > 0].reset_index(drop=True)
    step = float(np.median(np.diff(plate.t)))
    n = max(1, int(round(drive.load.period / SAMPLES_PER_PERIOD / step)))
    block = plate.index // n
    mean = plate.groupby(block)[["u_x", "mu_w", "f_x", "u_c"]].mean()
    last = plate.groupby(block)[["t", "x"]].last()
    keep = plate.groupby(block).size() == n  # whole blocks
    series = pd.DataFrame({"t": last.t, "x_w": last.x, "u_w": mean.u_x, "mu_w": mean.mu_w, "tau_w": -mean.f_x,
                           "u_c": mean.u_c})[keep]
    prof = pd.read_csv(folder / layout.PROFILES_CSV)
    # a profile row averages the interval ending at its time: dated at the interval's centre, like a model's sample
    prof = prof.assign(t=prof.t - np.median(np.diff(np.unique(prof.t))) / 2)
    surface = layout.plate_surface(plate.y.mean(), drive.surface_offset)
    inside = (surface - prof.y > 0) & (surface - prof.y <= drive.depth)
    velocity = pd.DataFrame({"t": prof.t, "depth": surface - prof.y, "u": prof.u_x})[inside]
    prof = prof.assign(depth=surface - prof.y_plane)
    prof = prof[(prof.depth > 0) & (prof.depth <= drive.depth) & (prof.p_mop > 0)]
    profiles = pd.DataFrame({"t": prof.t, "depth": prof.depth, "mu": prof.tau_mop / prof.p_mop})
    return Record(series.reset_index(drop=True), profiles.reset_index(drop=True), velocity.reset_index(drop=True),
                  n * step)


def _speed(reference: str) -> str:
    """The plate record's column of the speed a choice reads against."""
    return "u_w" if reference == "plate" else "u_c"


def estimates(rec: Record, drive: DriveSpec, mu_s: float) -> dict:
    """Every LAW_FAMILIES choice on one record: (observable, choice) -> (value, stderr over the cycles, its degrees of
    freedom); the error NaN where only the beds' spread gives one (the peak, the depths).  The lag against the
    contact layer: under an imposed stress, of u_c behind the stress; under an imposed speed, of mu_w behind u_c."""
    p, w, out = rec.plate, drive.load.omega, {}
    for c in LAW_FAMILIES["phase_lag"]:
        if c.estimator == "peak":
            out["phase_lag", c] = (phase.peak_lag(p.t, p[drive.response], w, c.skip, rec.interval), np.nan, np.nan)
            continue
        stress = drive.response == "u_w"
        response = _speed(c.reference) if stress else drive.response
        reference = None if stress or c.reference == "plate" else p[_speed(c.reference)]
        value, err, n = phase.lag(p.t, p[response], w, c.skip, rec.interval, reference)
        out["phase_lag", c] = (value, err, n - 1)
    for c in LAW_FAMILIES["yielded_depth"]:
        if c.estimator == "edge":
            grid = phase.phase_profile(rec.profiles, w, "mu", skip=c.skip)["mean"]
            edge = phase.yielded_depth(grid.columns.to_numpy(float), grid.to_numpy(), mu_s)
            value = float(np.nanmean(edge)) if len(edge) else np.nan
        else:
            amplitude = phase.amplitude_profile(rec.velocity, w, "u", c.skip)
            speed = phase.harmonic(p.t, p[_speed(c.reference)], w, c.skip, rec.interval).amplitude
            value = depth_at_fraction(amplitude.index.to_numpy(float), amplitude.to_numpy(), speed,
                                      LAYER_FRACTIONS[c.estimator])
        out["yielded_depth", c] = (value, np.nan, np.nan)
    return out


def observables(rec: Record, drive: DriveSpec, mu_s: float, depth_scale: float | None = None) -> dict:
    """Every observable of one record (value, stderr over its cycles or half-cycles and its degrees of freedom,
    blocks - 1; the lag and the yielded depth: their families' primary ``estimates``), the estimates, the
    phase-averaged zones, the plate's loop and the response's fundamental (a complex amplitude);
    ``depth_scale``: the remobilization strain's length (default: this record's yielded depth)."""
    p, w = rec.plate, drive.load.omega
    h = phase.harmonic(p.t, p[drive.response], w, SKIP, rec.interval)
    grid = phase.phase_profile(rec.profiles, w, "mu", skip=SKIP)
    yielded = phase.yielded_depth(grid["mean"].columns.to_numpy(float), grid["mean"].to_numpy(), mu_s)
    found = estimates(rec, drive, mu_s)
    edge = found["yielded_depth", LAW_FAMILIES["yielded_depth"][0]]
    work = phase.dissipation(p.t, p.u_w, p.tau_w, w, SKIP)
    strain = phase.remobilization_strain(p.t, p.x_w, p.u_w, p[drive.response], w,
                                         depth_scale or edge[0], RESPONSE_FRACTION, SKIP)
    loop = phase.phase_average(p.t, p.u_w, w, skip=SKIP).assign(
        tau_w=phase.phase_average(p.t, p.tau_w, w, skip=SKIP)["mean"])
    velocity = phase.phase_profile(rec.velocity, w, "u", skip=SKIP)["mean"]
    return {"values": {"response_amplitude": (h.amplitude, h.amplitude_err, h.n_cycles - 1),
                       "phase_lag": found["phase_lag", LAW_FAMILIES["phase_lag"][0]],
                       "yielded_depth": edge,
                       "dissipation": (work["value"], work["stderr"], len(work["values"]) - 1),
                       "remobilization_strain": (strain["value"], strain["stderr"], len(strain["values"]) - 1)},
            "estimates": found, "zones": grid["mean"], "yielded": pd.Series(yielded, index=grid["mean"].index),
            "loop": loop, "velocity": velocity, "n_cycles": h.n_cycles,
            "fundamental": h.amplitude * np.exp(1j * h.phase)}


@dataclass(frozen=True, eq=False)
class DemOscillation:
    """A drive's DEM side: its beds' records, per observable the beds' mean and error (``values``: name -> (value,
    err, how, dof)) and per law choice the same (``estimates``: (observable, CycleChoice) -> (value, err, how,
    dof)), the beds' zones averaged, the yielded depth over the phase, the loop, the phase-averaged velocity
    profiles (mean over the beds and its error, their spread / sqrt(n)), the slip (``_slip``, mean over the beds);
    ``beds``: each bed's periodic state (``_beds``)."""

    drive: DriveSpec
    records: tuple[Record, ...]
    values: dict
    estimates: dict
    zones: pd.DataFrame
    yielded: pd.Series
    loop: pd.DataFrame
    velocity: pd.DataFrame
    velocity_err: pd.DataFrame
    slip: float
    beds: tuple[dict, ...]
    n_cycles: int


def _over_beds(per: list[tuple]) -> tuple:
    """(value, err, how, dof) from each bed's (value, err, dof): the beds' mean and spread / sqrt(n) with n - 1
    degrees of freedom (n the beds with a value); one bed: its own error, its cycles as blocks."""
    v = np.array([b[0] for b in per], dtype=float)
    if len(v) >= MIN_BEDS:
        n = int(np.isfinite(v).sum())
        return (float(np.nanmean(v)), float(np.nanstd(v, ddof=1) / np.sqrt(n)),
                f"spread over {len(v)} beds (std/sqrt(n))", n - 1)
    _, err, dof = per[0]
    return float(v[0]), float(err), "one bed: its cycles as blocks", dof


def _beds(drive: DriveSpec, records, fundamentals) -> tuple[dict, ...]:
    """Each bed's periodic state: compare.phase.periodicity of its response (``cycles``, ``change``, ``periodic``),
    its ``fundamental`` over the kept cycles and ``same_state``: whether it is within PERIODIC_TOLERANCE
    (``phase.change``) of another bed's (None without another bed's to compare).  A bed jammed while the others
    flow is in another state; two flowing beds and a jammed one leave the flowing ones in one state (not against the
    mean of the other two, which the jammed one drags)."""
    out = []
    for k, r in enumerate(records):
        check = phase.periodicity(r.plate.t, r.plate[drive.response], drive.load.omega, SKIP, r.interval)
        apart = [x for j, z in enumerate(fundamentals) if j != k and np.isfinite(x := phase.change(z, fundamentals[k]))]
        out.append({**check, "fundamental": fundamentals[k],
                    "same_state": bool(min(apart) <= phase.PERIODIC_TOLERANCE) if apart else None})
    return tuple(out)


def analyse_dem(drive: DriveSpec, records: list[Record], mu_s: float) -> DemOscillation:
    """The DEM side of ``drive`` from its beds' ``records`` (dem_record, or a report's tables)."""
    first = [observables(r, drive, mu_s) for r in records]
    scale = float(np.nanmean([o["values"]["yielded_depth"][0] for o in first]))
    per = [observables(r, drive, mu_s, scale) for r in records]
    values = {name: _over_beds([o["values"][name] for o in per]) for name in OBSERVABLES}
    found = {key: _over_beds([o["estimates"][key] for o in per]) for key in per[0]["estimates"]}
    zones = sum(_on_depths(o["zones"], per[0]["zones"].columns) for o in per) / len(per)
    yielded = sum(o["yielded"] for o in per) / len(per)
    loop = sum(o["loop"][["phase", "mean", "tau_w"]] for o in per) / len(per)
    beds = np.array([_on_depths(o["velocity"], per[0]["velocity"].columns).to_numpy(float) for o in per])
    frame = lambda a: pd.DataFrame(a, index=per[0]["velocity"].index, columns=per[0]["velocity"].columns)
    velocity = frame(beds.mean(axis=0))
    velocity_err = frame(beds.std(axis=0, ddof=1) / np.sqrt(len(per)) if len(per) >= MIN_BEDS else np.nan * beds[0])
    slip = float(np.mean([_slip(r.plate, drive.load.omega) for r in records]))
    return DemOscillation(drive, tuple(records), values, found, zones, yielded, loop, velocity, velocity_err, slip,
                          _beds(drive, records, [o["fundamental"] for o in per]), min(o["n_cycles"] for o in per))


def unsettled(dem: DemOscillation) -> str:
    """The beds that are not in one periodic state, in words ("" when none): a bed jams (its response's amplitude
    falls below 1 - PERIODIC_TOLERANCE of its first kept cycle's by its last), is not periodic (its fundamental
    moves otherwise by more than PERIODIC_TOLERANCE), or is in another state than the other beds."""
    n, response_unit = len(dem.beds), unit(dem.drive, "response_amplitude")
    response_unit = "" if response_unit == "1" else f" {response_unit}"
    out = []
    for k, b in enumerate(dem.beds, start=1):
        if b["periodic"] is False:
            c = b["cycles"]
            a0, a1, p0, p1 = c.amplitude.iloc[0], c.amplitude.iloc[-1], c.phase.iloc[0], c.phase.iloc[-1]
            what = "jams" if a1 < (1 - phase.PERIODIC_TOLERANCE) * a0 else "is not periodic"
            out.append(f"bed {k} of {n} {what} (response amplitude {a0:.3g} -> {a1:.3g}{response_unit}, phase "
                       f"{p0:+.2f} -> {p1:+.2f} rad over the kept cycles {c.cycle.iloc[0]} to {c.cycle.iloc[-1]})")
        elif b["same_state"] is False:
            others = ", ".join(f"{abs(o['fundamental']):.3g}" for o in dem.beds if o is not b)
            out.append(f"bed {k} of {n} is in another state than the others (response amplitude "
                       f"{abs(b['fundamental']):.3g}{response_unit} against {others})")
    return "; ".join(out)


def _slip(plate: pd.DataFrame, omega: float) -> float:
    """rms(u_c - u_w)/rms(u_w) over the whole cycles after the start-up: u_c, the x velocity of the bed grains
    touching the plate (dem.scene), lagging or lagged by the plate (a scene check: the models have no slip)."""
    kept = np.concatenate(list(phase.cycles(plate.t, omega, SKIP).values()) or [np.zeros(0, int)])
    p = plate.iloc[kept]
    return float(np.sqrt(((p.u_c - p.u_w) ** 2).mean() / (p.u_w ** 2).mean())) if len(p) else np.nan


def _on_depths(zones: pd.DataFrame, depths) -> pd.DataFrame:
    """A (phase x depth) table interpolated onto ``depths`` (the beds' profile planes differ with their plate)."""
    x = zones.columns.to_numpy(float)
    values = np.array([np.interp(depths, x, row, left=np.nan, right=np.nan) for row in zones.to_numpy(float)])
    return pd.DataFrame(values, index=zones.index, columns=pd.Index(depths, name="depth"))


# --- the models ------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class ModelSetup:
    """What every prediction shares: the calibrated material, the replicates' covariance of PARAMETERS, NGF's
    amplitude (None: no NGF rows) and the bed's shear modulus (None: no elasto-plastic rows) with their standard
    errors, the numerics."""

    material: Material
    covariance: pd.DataFrame
    ngf_A: float | None = None
    ngf_A_err: float = 0.0
    numerics: SceneNumerics = NUMERICS
    calibrated_I: tuple = (np.nan, np.nan)  # the calibration's range of I (DEM convention): beyond it, extrapolated
    elastic_G: float | None = None
    elastic_G_err: float = 0.0

    @property
    def models(self) -> tuple[str, ...]:
        return ("local", *(m for m in ("ngf", "elastic") if self.own(m) is not None))

    def own(self, model: str) -> tuple[str, float, float] | None:
        """A model's own parameter beyond the material (name, value, standard error): NGF's A, the elasto-plastic
        model's G; None for local mu(I) or a model without one."""
        value, err, name = {"ngf": (self.ngf_A, self.ngf_A_err, "A"),
                            "elastic": (self.elastic_G, self.elastic_G_err, "G")}.get(model, (None, 0.0, ""))
        return None if value is None else (name, float(value), float(err))


def model_record(drive: DriveSpec, material: Material, model: str, own: float | None, depths,
                 numerics: SceneNumerics, velocity_depths=None) -> Record:
    """A model's solution of ``drive`` as a Record (``own``: its own parameter, NGF's A or the elasto-plastic G):
    sampled SAMPLES_PER_PERIOD times a period over the DEM's duration, mu (sign as the DEM's) at the DEM's profile
    depths, u at ``velocity_depths`` (default: those)."""
    load = drive.load
    n = int(round(SAMPLES_PER_PERIOD * (drive.duration / load.period)))
    t = np.linspace(0.0, drive.duration, n + 1)[1:]
    scene = BedScene(drive.depth, plate_mass=drive.plate_mass)
    sol = osc.solve_oscillating(material, scene, load, t, model=model, rule=_rule(drive, material),
                                fluidity=NonlocalFluidity(A=own) if model == "ngf" else None,
                                G=own if model == "elastic" else None, numerics=numerics, error_estimate=False)
    u_w = sol.u_w
    x_w = np.concatenate([[0.0], np.cumsum(0.5 * (u_w[1:] + u_w[:-1]) * np.diff(t))]) + u_w[0] * t[0] / 2
    mu = -np.array([np.interp(depths, sol.y_mu, m) for m in sol.mu])
    # tau_w: the stress on the bed's top (as the DEM's plate record measures it; under an imposed stress the plate's
    # inertia makes it differ from the load within the cycle, not over it)
    top = -sol.mu[:, 0] * (load.p_w + material.weight_gradient * sol.y_mu[0])
    plate = pd.DataFrame({"t": t, "x_w": x_w, "u_w": u_w, "mu_w": sol.mu_w, "tau_w": top, "u_c": u_w})  # no slip
    profiles = pd.DataFrame({"t": np.repeat(t, len(depths)), "depth": np.tile(depths, len(t)), "mu": mu.ravel()})
    vd = depths if velocity_depths is None else np.asarray(velocity_depths, dtype=float)
    u = np.array([np.interp(vd, sol.y, row) for row in sol.u])
    velocity = pd.DataFrame({"t": np.repeat(t, len(vd)), "depth": np.tile(vd, len(t)), "u": u.ravel()})
    return Record(plate, profiles, velocity)


def _rule(drive: DriveSpec, material: Material) -> YieldRule:
    """The regularised local rule of the DEM-scene predictions, at the amplitude's steady layer."""
    return YieldRule.for_layer(drive.load.scales(material))


@dataclass(frozen=True, eq=False)
class OscPrediction:
    """A model's side of a drive: per observable and per law choice (``estimates``, keyed as the DEM's) its
    (predicted, numerical error, calibration sd), and the zones, yielded depth over the phase, loop and
    phase-averaged velocity profiles of its central solution."""

    model: str
    values: dict
    estimates: dict
    zones: pd.DataFrame
    yielded: pd.Series
    loop: pd.DataFrame
    velocity: pd.DataFrame


def predict(dem: DemOscillation, setup: ModelSetup, model: str) -> OscPrediction:
    """The model's observables and law choices on the DEM's rows and depths: central (``setup.numerics``), on
    n_cells/2 (the numerical error, |fine - coarse|/3) and the calibration's sd by compare.band (the shifted solves
    on n_cells/2, like the coarse central one: the discretisation's bias cancels in the differences)."""
    drive, depths = dem.drive, dem.zones.columns.to_numpy(float)
    scale = dem.values["yielded_depth"][0]
    coarse_numerics = replace(setup.numerics, n_cells=setup.numerics.n_cells // 2)

    def run(material, value, numerics) -> dict:
        rec = model_record(drive, material, model, value, depths, numerics, dem.velocity.columns.to_numpy(float))
        return observables(rec, drive, material.mu_s, scale)

    def flat(o: dict) -> dict:
        """Every observable and law choice of one solve: its key -> (value, ...)."""
        return {**o["values"], **o["estimates"]}

    own = setup.own(model)
    name, value = (own[0], own[1]) if own is not None else ("", None)
    central_solve = run(setup.material, value, setup.numerics)
    fine, coarse = flat(central_solve), flat(run(setup.material, value, coarse_numerics))
    central = {**{k: getattr(setup.material, k) for k in PARAMETERS}, **({name: value} if own is not None else {})}
    cov = setup.covariance.copy()
    if own is not None:
        cov.loc[name, name] = own[2] ** 2
    sens = Sensitivity.of(lambda q: flat(run(replace(setup.material, **{k: q[k] for k in PARAMETERS}), q.get(name),
                                             coarse_numerics)), central, cov)

    def side(key) -> tuple[float, float, float]:
        difference = partial(_difference, key if isinstance(key, str) else key[0])
        s_cal = sens.sd_of(lambda j: sens.shifted[j][key][0], coarse[key][0], difference=difference)
        return fine[key][0], float(richardson(0.0, difference(fine[key][0], coarse[key][0]))), s_cal

    o = central_solve
    return OscPrediction(model, {k: side(k) for k in OBSERVABLES}, {k: side(k) for k in o["estimates"]}, o["zones"],
                         o["yielded"], o["loop"], o["velocity"])


def _difference(observable: str, a: float, b: float) -> float:
    """a - b, a phase difference wrapped into (-pi, pi]."""
    return float(phase.wrap(a - b)) if observable == "phase_lag" else a - b


def _row(dem: DemOscillation, pred: OscPrediction | None, observable: str, model: str, note: str,
         choice: CycleChoice | None = None, beyond: str = "") -> dict:
    """The row of ``observable`` (measured by ``choice``: a law choice's row, None: the scorecard's) of a drive and
    a model; ``note``: why the model has no prediction (pred None); ``beyond``: why its prediction extrapolates the
    calibration (``_beyond``), or ""."""
    drive = dem.drive
    v, err, how, dof = dem.values[observable] if choice is None else dem.estimates[observable, choice]
    p, num, s_cal = (np.nan, np.nan, np.nan) if pred is None else (
        pred.values[observable] if choice is None else pred.estimates[observable, choice])
    if pred is not None:
        censored = observable in CENSORED and (choice is None or choice.estimator == "edge")
        note = _scene(dem, model) or beyond or _unmeasurable(dem, v, err, censored) or _unpredicted(p, num, s_cal)
    elif not note.startswith("not predicted"):
        note = f"not predicted: {note}"
    scored = not note
    how_chosen = {} if choice is None else {"estimator": choice.estimator, "reference": choice.reference,
                                            "skip": choice.skip}
    return score_row(
        drive=drive.label, observable=observable, unit=unit(drive, observable), dem=v, dem_err=err, dem_how=how,
        model=model, model_label=LABELS[model], predicted=float(p), band=band(p, float(np.hypot(num, s_cal))),
        numerical_err=num, calibration_sd=s_cal, sigma=sigma(_difference(observable, v, p), err, num, s_cal)
        if scored else np.nan, dof=effective_dof((err, num, s_cal), (dof, np.inf, np.inf)), note=note, blind=True,
        kind=drive.load.kind, omega=drive.load.omega,
        omega_ts=drive.omega_ts, amplitude=drive.load.amplitude, phase_lag=dem.values["phase_lag"][0],
        phase_lag_predicted=pred.values["phase_lag"][0] if pred is not None else np.nan, **how_chosen)


#: the observables read over the yielded depth, which the base censors when the edge reaches it
CENSORED = ("yielded_depth", "remobilization_strain")


#: the models with an elastic bed: the elastic regime of a fast cycle is theirs to predict
ELASTIC_MODELS = ("elastic",)


def _scene(dem: DemOscillation, model: str) -> str:
    """Why the scene cannot support the drive's rows against ``model``, or "": for a rigid-plastic model (not in
    ELASTIC_MODELS) a period shorter than TRANSITS_BEFORE_COMPARISON shear-wave transits over the bed (the bed answers
    elastically within a cycle, as the Stokes drives before their comparison starts; the transit at the measured
    shear-wave speed where the calibration holds it: compare.drive.with_transit_time); a bed not in one periodic
    state (``unsettled``: it jams or drifts within the kept cycles, or is in another state than the other beds, so
    the cycles' and the beds' mean is no state's: the drive's rows are kept, unscored, and the report counts it); or
    a plate that slips by more than SLIP_MAX against the grains touching it (its speed and force are not the bed's,
    and every model's plate grips: the rows read against the contact layer's speed are kept as choices, unscored, as
    in the Stokes drives).  A drive whose tables carry no transit time is not checked for it."""
    transits = dem.drive.load.period / dem.drive.transit_time
    if transits < TRANSITS_BEFORE_COMPARISON and model not in ELASTIC_MODELS:
        return (f"not scored: the plate's period spans {transits:.2g} shear-wave transits of the bed (fewer than "
                f"{TRANSITS_BEFORE_COMPARISON:g}): an elastic response, which rigid-plastic models do not have")
    if beds := unsettled(dem):
        return f"not scored: {beds}"
    if dem.slip > SLIP_MAX:
        return (f"not scored: the plate slips {dem.slip:.0%} against the grains touching it (more than "
                f"{SLIP_MAX:.0%}), so its speed and force are not the bed's")
    return ""


def _unmeasurable(dem: DemOscillation, value: float, err: float, censored: bool) -> str:
    """Why the DEM gives no number to score, or "": no value or no error, or (``censored``: a row read over the
    yielded depth) an edge that reaches the deepest plane at some phase."""
    if not (np.isfinite(value) and np.isfinite(err) and err > 0):
        return "not measurable: no error (fewer than two beds or whole cycles after the start-up)"
    if censored and np.nanmax(dem.yielded) >= dem.zones.columns.max():
        return ("not measurable: at some phase the bed yields down to its deepest plane (the edge is censored by the "
                "base)")
    return ""


def _unpredicted(predicted: float, numerical: float, calibration_sd: float) -> str:
    """Why a model's value cannot be scored, or "": it gives none, or its error is undefined (a sigma of NaN would
    otherwise be counted as a disagreement)."""
    if not np.isfinite(predicted):
        return "not predicted: the model's solution gives no value of this observable"
    if not (np.isfinite(numerical) and np.isfinite(calibration_sd)):
        return "not predicted: the model's numerical error or calibration band is undefined"
    return ""


def scorecard(dems, predictions: dict, setup: ModelSetup, ngf_note: str) -> pd.DataFrame:
    """Every drive x model x observable (predictions: (drive label, model) -> OscPrediction, or why not)."""
    return _table(dems, predictions, setup, ngf_note, [(o, None) for o in OBSERVABLES])


def choice_rows(dems, predictions: dict, setup: ModelSetup, ngf_note: str) -> pd.DataFrame:
    """Every drive x model x law choice (LAW_FAMILIES): the scorecard's row of the choice's observable measured by
    it (with its estimator, reference and skip), scored by the same rules but for the slip, which falsifies only a
    choice read against the plate's speed."""
    return _table(dems, predictions, setup, ngf_note, [(o, c) for o, family in LAW_FAMILIES.items() for c in family])


def _table(dems, predictions: dict, setup: ModelSetup, ngf_note: str, keys) -> pd.DataFrame:
    rows = []
    listed = [m for m in LABELS if m in setup.models or m == "ngf"]  # NGF's rows say why it is not predicted
    for d in dems:
        for m in listed:
            p = predictions.get((d.drive.label, m))
            note = (p if isinstance(p, str) else "") if m in setup.models else ngf_note
            pred = p if isinstance(p, OscPrediction) else None
            beyond = _beyond(d, pred, setup) if pred is not None else ""
            rows += [_row(d, pred, o, m, note, c, beyond) for o, c in keys]
    return pd.DataFrame(rows)


def _beyond(dem: DemOscillation, pred: OscPrediction, setup: ModelSetup) -> str:
    """Why a model's rows of a drive rest on mu(I) beyond the calibration, or "": the largest wall friction of its
    cycle (the phase-averaged |tau_w|/p_w of its loop) lies at an inertial number (DEM convention) beyond the
    calibration's largest (compare.scorecard.extrapolated; mu_w at or above mu_d: infinitely far; an unknown
    calibrated range is not checked)."""
    if not np.isfinite(setup.calibrated_I[1]):
        return ""
    m = setup.material
    mu = np.abs(pred.loop.tau_w.to_numpy(dtype=float)) / dem.drive.load.p_w
    return extrapolated(wall_I(m.friction, mu, convert_I(m.I0, m.I_convention, "dem")), setup.calibrated_I)


#: the laws in omega: name -> (the observable, what it fits, the observable's transform)
LAWS = {"yielded_depth_exponent": ("yielded_depth", "n in yielded_depth ~ (omega t_s)^n", np.log),
        "phase_lag_slope": ("phase_lag", "s in phase_lag = a + s ln(omega t_s) [rad]", lambda v: v)}


def laws(rows: pd.DataFrame) -> pd.DataFrame:
    """How the yielded depth and the phase lag scale with omega, per drive kind, amplitude and model, over each
    law's family of choices (LAW_FAMILIES; ``rows``: ``choice_rows``): per choice (``_fit``) n in yielded_depth ~
    (omega t_s)^n or s in phase_lag = a + s ln(omega t_s) on its scored drives, its entry (compare.families.entry,
    with its skip, chi2_dof, n_drives, window and words).  The row's numbers are its headline choice's (the primary
    when measured: the scorecard's lag and yielded depth), ``systematic`` the family's spread, and the verdict
    "depends on the estimator" when the measured choices split (compare.families.family_note)."""
    out = []
    for (kind, amp, model), g in rows[rows.scored].groupby(["kind", "amplitude", "model"]):
        for law, (obs, quantity, _) in LAWS.items():
            family = LAW_FAMILIES[obs]
            entries = []
            for c in family:
                s = g[(g.observable == obs) & (g.estimator == c.estimator) & (g.reference == c.reference)
                      & (g.skip == c.skip)]
                fit = _fit(law, s)
                entries.append({**entry(Choice(c.estimator, c.reference, None), fit["dem"], fit["dem_err"],
                                        fit["predicted"], fit["predicted_err"], fit["note"], fit["dof"]),
                                "skip": c.skip, "chi2_dof": fit["chi2_dof"], "n_drives": fit["n_drives"],
                                "window": fit["window"], "words": c.describe()})
            h = headline(entries)
            e = entries[h]
            window = e["window"] if not h else (f"the primary choice ({family[0].describe()}) is not measurable; "
                                                f"shown: {family[h].describe()}: {e['window']}")
            split = family_note(entries)
            note = e["note"] or split
            out.append(law_row(law=law, quantity=quantity, unit="1", kind=kind, model=model, dem=e["dem"],
                               dem_err=e["dem_err"], predicted=e["predicted"], predicted_err=e["predicted_err"],
                               sigma=e["sigma"] if note in ("", split) else np.nan, dof=e["dof"],
                               chi2_dof=e["chi2_dof"], n_drives=e["n_drives"], window=window, note=note,
                               choices=entries, systematic=systematic(entries), amplitude=amp))
    return pd.DataFrame(out)


def _fit(law: str, s: pd.DataFrame) -> dict:
    """One choice of ``law`` over its scored drives ``s``: weighted least squares with the DEM's errors (the model's
    slope on the same weights, its error from the per-drive bands taken as independent); the depth's drives with
    no yielded layer on either side are left out.

    Lack of fit: chi2, the DEM's weighted squared residuals about its line, has n - 2 degrees of freedom over n
    drives; the fit quotes chi2_dof = chi2/(n - 2).  When chi2.sf(chi2, n - 2) < LACK_OF_FIT_P the DEM is not on a
    line (a step, a bend) and no slope is quoted: "not measurable: not a line" with chi2/dof and p.  Otherwise,
    when chi2_dof > 1 the scatter about the line exceeds the errors and the DEM slope's error is scaled by
    sqrt(chi2_dof).  The slope has n - 2 degrees of freedom (its dof combines them with the model's error, which
    has infinitely many).  The weights come from few beds (the per-bed spread of 3 beds has 2 degrees of freedom):
    each weight is itself uncertain, so chi2 is heavier-tailed than a chi-square and the test flags a true line
    more often than LACK_OF_FIT_P (five drives of three beds: 15 % of the time, simulated; there the 1 % quantile of
    chi2_dof is about 18, not 3.8); a chi2_dof in the hundreds is a step, not noise in the weights."""
    obs, _, fy = LAWS[law]
    if obs == "yielded_depth":
        s = s[(s.dem > 0) & (s.predicted > 0)]
    s = s[s.dem.notna()]
    out = {"dem": np.nan, "dem_err": np.nan, "predicted": np.nan, "predicted_err": np.nan, "dof": np.nan,
           "chi2_dof": np.nan, "n_drives": len(s),
           "window": f"omega t_s in [{s.omega_ts.min():.3g}, {s.omega_ts.max():.3g}]" if len(s) else ""}
    if len(s) < 3:
        return {**out, "note": f"not measurable: {len(s)} measurable drive(s), a slope and its error need 3"}
    x = np.log(s.omega_ts.to_numpy())
    scale = s.dem.to_numpy() if obs == "yielded_depth" else 1.0
    dem_sd = s.dem_err.to_numpy() / scale
    model_scale = s.predicted.to_numpy() if obs == "yielded_depth" else 1.0
    model_sd = np.hypot(s.numerical_err, s.calibration_sd).to_numpy() / model_scale
    w = 1 / dem_sd ** 2
    y = fy(s.dem.to_numpy())
    dem_slope, dem_err = _weighted_slope(x, y, w, dem_sd)
    dof = len(s) - 2
    chi2 = _chi2(x, y, w, dem_slope)
    p = float(stats.chi2.sf(chi2, dof))
    if p < LACK_OF_FIT_P:
        return {**out, "dof": dof, "chi2_dof": chi2 / dof,
                "note": f"not measurable: not a line (chi2/dof = {chi2 / dof:.3g}, p = {p:.2g})"}
    dem_err *= np.sqrt(max(chi2 / dof, 1.0))
    pred_slope, pred_err = _weighted_slope(x, fy(s.predicted.to_numpy()), w, model_sd)
    return {**out, "dem": dem_slope, "dem_err": dem_err, "predicted": pred_slope, "predicted_err": pred_err,
            "dof": effective_dof((dem_err, pred_err), (dof, np.inf)), "chi2_dof": chi2 / dof, "note": ""}


def _weighted_slope(x, y, w, sd) -> tuple[float, float]:
    """The slope of y on x by least squares with weights w, and its standard error from the points' sd."""
    xm = np.sum(w * x) / np.sum(w)
    c = w * (x - xm) / np.sum(w * (x - xm) ** 2)  # slope = sum c y
    return float(np.sum(c * y)), float(np.sqrt(np.sum((c * sd) ** 2)))


def _chi2(x, y, w, slope: float) -> float:
    """The weighted squared residuals sum w r^2 about the weighted least-squares line of ``slope`` (through the
    weighted means)."""
    xm, ym = np.sum(w * x) / np.sum(w), np.sum(w * y) / np.sum(w)
    return float(np.sum(w * (y - ym - slope * (x - xm)) ** 2))


@dataclass(frozen=True, eq=False)
class OscillationComparison:
    """Everything the oscillation report renders (``verdict``: compare.oscillation_report's words)."""

    runs: tuple[str, ...]
    setup: ModelSetup
    calibration_source: str
    ngf_source: str
    drives: tuple[DemOscillation, ...]
    predictions: dict
    rows: pd.DataFrame
    laws: pd.DataFrame
    choices: pd.DataFrame


def predict_unit(dem: DemOscillation, setup: ModelSetup, model: str):
    """(drive label, model) -> its OscPrediction, or the solver's failure as a string (the rows say why)."""
    try:
        return (dem.drive.label, model), predict(dem, setup, model)
    except RuntimeError as exc:  # the solver gave up (continuum.oscillation raises it with its message)
        return (dem.drive.label, model), f"the {model} solver failed on this drive: {exc}"


def dem_side(run_dirs, root: Path | None = None) -> list[tuple[DriveSpec, list[Record]]]:
    """Every drive of ``run_dirs`` with its beds' records."""
    drives = [d for run in run_dirs for d in drive_specs(Path(run), root)]
    require(drives, "RUN_DIR", "run folders with oscillating drives", [str(r) for r in run_dirs])
    return [(d, [dem_record(f, d) for f in d.folders]) for d in drives]


def setup_of(cal, ngf_from: str | Path | None) -> tuple[ModelSetup, str]:
    """What every prediction shares, from an independent calibration (compare.calibrate.load) and NGF's A from
    ``ngf_from``, a Stokes report's metrics.json (A fitted on a Stokes drive's creep profile), else no NGF rows;
    with the note the NGF rows carry when there are none."""
    from .comparison import replicates_of

    require(not cal.failure, "--calibration", "a calibration that determines mu(I)", cal.failure)
    reps = replicates_of(cal, cal.replicates["phi_max"])
    ngf_A, ngf_err, ngf_note = None, 0.0, "no NGF amplitude: give a Stokes report's metrics.json (--ngf-from)"
    if ngf_from is not None:
        ngf = json.loads(Path(ngf_from).read_text()).get("ngf") or {}
        require("A" in ngf, "--ngf-from", "a Stokes report's metrics.json with an NGF fit", str(ngf_from))
        ngf_A, ngf_err, ngf_note = float(ngf["A"]), float(ngf.get("A_err", 0.0)), ""
    elasticity = getattr(cal, "elasticity", None) or {}
    setup = ModelSetup(cal.material(), reps.cov(), ngf_A, ngf_err, calibrated_I=calibrate.calibrated_range(cal),
                       elastic_G=elasticity.get("G"), elastic_G_err=float(elasticity.get("G_err", 0.0)))
    return setup, ngf_note


def conclude(dem, dems: list[DemOscillation], setup: ModelSetup, ngf_note: str, predicted: list, calibration: str,
             ngf_from) -> OscillationComparison:
    """The OscillationComparison from every (drive, model)'s ``predict_unit``."""
    predictions = dict(predicted)
    rows = scorecard(dems, predictions, setup, ngf_note)
    source = (f"NGF's A = {setup.ngf_A:.3g} +- {setup.ngf_A_err:.2g} from {ngf_from}" if setup.ngf_A is not None
              else ngf_note)
    choices = choice_rows(dems, predictions, setup, ngf_note)
    return OscillationComparison(tuple(sorted({str(d.run) for d, _ in dem})), setup, calibration, source,
                                 tuple(dems), predictions, rows, laws(choices), choices)
