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
infinitely many), and its verdict the Student-t test at that dof (compare.rows.verdict).  A model's band
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
from granstokes.continuum.ngf import NonlocalFluidity
from granstokes.continuum.richardson import richardson
from granstokes.continuum.rules import YieldRule
from granstokes.continuum.scales import Material
from granstokes.continuum.scene import BedScene, SceneNumerics
from granstokes.dem import layout
from scipy import stats

from granstokes.lib.validate import require

from . import phase
from .band import Sensitivity
from .drive import TRANSITS_BEFORE_COMPARISON, DriveSpec, drive_specs
from .plate import SLIP_MAX
from .rows import LACK_OF_FIT_P, band, effective_dof, law_row, score_row, sigma

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
LABELS = {"local": "local mu(I), velocity form on the DEM scene", "ngf": "nonlocal fluidity (NGF)"}
PARAMETERS = ("mu_s", "mu_d", "I0", "phi")
#: beds whose spread is the DEM's error (one bed: its cycles as blocks)
MIN_BEDS = 2


def unit(drive: DriveSpec, observable: str) -> str:
    """An observable's unit on ``drive`` (the response amplitude's is its response's)."""
    if observable == "response_amplitude":
        return "sqrt(g d)" if drive.response == "u_w" else "1"
    return OBSERVABLES[observable]


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


def observables(rec: Record, drive: DriveSpec, mu_s: float, depth_scale: float | None = None) -> dict:
    """Every observable of one record (value, stderr over its cycles or half-cycles and its degrees of freedom,
    blocks - 1), the phase-averaged zones and the plate's loop; ``depth_scale``: the remobilization strain's length
    (default: this record's yielded depth)."""
    p, w = rec.plate, drive.load.omega
    h = phase.harmonic(p.t, p[drive.response], w, SKIP, rec.interval)
    grid = phase.phase_profile(rec.profiles, w, "mu", skip=SKIP)
    depths = grid["mean"].columns.to_numpy(float)
    yielded = phase.yielded_depth(depths, grid["mean"].to_numpy(), mu_s)
    edge = float(np.nanmean(yielded)) if len(yielded) else np.nan
    work = phase.dissipation(p.t, p.u_w, p.tau_w, w, SKIP)
    strain = phase.remobilization_strain(p.t, p.x_w, p.u_w, p[drive.response], w,
                                         depth_scale or edge, RESPONSE_FRACTION, SKIP)
    loop = phase.phase_average(p.t, p.u_w, w, skip=SKIP).assign(
        tau_w=phase.phase_average(p.t, p.tau_w, w, skip=SKIP)["mean"])
    velocity = phase.phase_profile(rec.velocity, w, "u", skip=SKIP)["mean"]
    return {"values": {"response_amplitude": (h.amplitude, h.amplitude_err, h.n_cycles - 1),
                       "phase_lag": (phase.phase_lag(h), h.phase_err, h.n_cycles - 1),
                       "yielded_depth": (edge, np.nan, np.nan),
                       "dissipation": (work["value"], work["stderr"], len(work["values"]) - 1),
                       "remobilization_strain": (strain["value"], strain["stderr"], len(strain["values"]) - 1)},
            "zones": grid["mean"], "yielded": pd.Series(yielded, index=grid["mean"].index), "loop": loop,
            "velocity": velocity,
            "n_cycles": h.n_cycles}


@dataclass(frozen=True, eq=False)
class DemOscillation:
    """A drive's DEM side: its beds' records, per observable the beds' mean and error (``values``: name -> (value,
    err, how, dof)), the beds' zones averaged, the yielded depth over the phase, the loop, the phase-averaged velocity
    profiles (mean over the beds and its error, their spread / sqrt(n)), the slip (``_slip``, mean over the beds);
    the periodic-state check per bed."""

    drive: DriveSpec
    records: tuple[Record, ...]
    values: dict
    zones: pd.DataFrame
    yielded: pd.Series
    loop: pd.DataFrame
    velocity: pd.DataFrame
    velocity_err: pd.DataFrame
    slip: float
    stationary: list
    n_cycles: int


def analyse_dem(drive: DriveSpec, records: list[Record], mu_s: float) -> DemOscillation:
    """The DEM side of ``drive`` from its beds' ``records`` (dem_record, or a report's tables)."""
    first = [observables(r, drive, mu_s) for r in records]
    scale = float(np.nanmean([o["values"]["yielded_depth"][0] for o in first]))
    per = [observables(r, drive, mu_s, scale) for r in records]
    values = {}
    for name in OBSERVABLES:
        v = np.array([o["values"][name][0] for o in per], dtype=float)
        if len(v) >= MIN_BEDS:
            n = int(np.isfinite(v).sum())
            values[name] = (float(np.nanmean(v)), float(np.nanstd(v, ddof=1) / np.sqrt(n)),
                            f"spread over {len(v)} beds (std/sqrt(n))", n - 1)
        else:
            _, err, dof = per[0]["values"][name]
            values[name] = (float(v[0]), float(err), "one bed: its cycles as blocks", dof)
    zones = sum(_on_depths(o["zones"], per[0]["zones"].columns) for o in per) / len(per)
    yielded = sum(o["yielded"] for o in per) / len(per)
    loop = sum(o["loop"][["phase", "mean", "tau_w"]] for o in per) / len(per)
    beds = np.array([_on_depths(o["velocity"], per[0]["velocity"].columns).to_numpy(float) for o in per])
    frame = lambda a: pd.DataFrame(a, index=per[0]["velocity"].index, columns=per[0]["velocity"].columns)
    velocity = frame(beds.mean(axis=0))
    velocity_err = frame(beds.std(axis=0, ddof=1) / np.sqrt(len(per)) if len(per) >= MIN_BEDS else np.nan * beds[0])
    checks = [phase.stationarity(r.plate.t, r.plate[drive.response], drive.load.omega, SKIP) for r in records]
    slip = float(np.mean([_slip(r.plate, drive.load.omega) for r in records]))
    stationary = [c["steady"] if np.isfinite(c["z"]) else None for c in checks]  # None: fewer than 3 cycles
    return DemOscillation(drive, tuple(records), values, zones, yielded, loop, velocity, velocity_err, slip, stationary,
                          min(o["n_cycles"] for o in per))


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
    """What every prediction shares: the calibrated material, the replicates' covariance of PARAMETERS (+ A), NGF's
    amplitude (None: no NGF rows) and its standard error, the numerics."""

    material: Material
    covariance: pd.DataFrame
    ngf_A: float | None = None
    ngf_A_err: float = 0.0
    numerics: SceneNumerics = NUMERICS

    @property
    def models(self) -> tuple[str, ...]:
        return ("local", "ngf") if self.ngf_A is not None else ("local",)


def model_record(drive: DriveSpec, material: Material, model: str, A: float | None, depths,
                 numerics: SceneNumerics, velocity_depths=None) -> Record:
    """A model's solution of ``drive`` as a Record: sampled SAMPLES_PER_PERIOD times a period over the DEM's
    duration, mu (sign as the DEM's) at the DEM's profile depths, u at ``velocity_depths`` (default: those)."""
    load = drive.load
    n = int(round(SAMPLES_PER_PERIOD * (drive.duration / load.period)))
    t = np.linspace(0.0, drive.duration, n + 1)[1:]
    scene = BedScene(drive.depth, plate_mass=drive.plate_mass)
    sol = osc.solve_oscillating(material, scene, load, t, model=model, rule=_rule(drive, material),
                                fluidity=NonlocalFluidity(A=A) if model == "ngf" else None, numerics=numerics,
                                error_estimate=False)
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
    """A model's side of a drive: per observable (predicted, numerical error, calibration sd), and the zones,
    yielded depth over the phase, loop and phase-averaged velocity profiles of its central solution."""

    model: str
    values: dict
    zones: pd.DataFrame
    yielded: pd.Series
    loop: pd.DataFrame
    velocity: pd.DataFrame


def predict(dem: DemOscillation, setup: ModelSetup, model: str) -> OscPrediction:
    """The model's observables on the DEM's rows and depths: central (``setup.numerics``), on n_cells/2 (the
    numerical error, |fine - coarse|/3) and the calibration's sd by compare.band (the shifted solves on n_cells/2,
    like the coarse central one: the discretisation's bias cancels in the differences)."""
    drive, depths = dem.drive, dem.zones.columns.to_numpy(float)
    scale = dem.values["yielded_depth"][0]
    coarse_numerics = replace(setup.numerics, n_cells=setup.numerics.n_cells // 2)

    def run(material, A, numerics):
        rec = model_record(drive, material, model, A, depths, numerics, dem.velocity.columns.to_numpy(float))
        return observables(rec, drive, material.mu_s, scale)

    A = setup.ngf_A if model == "ngf" else None
    fine = run(setup.material, A, setup.numerics)
    coarse = run(setup.material, A, coarse_numerics)["values"]
    central = {**{k: getattr(setup.material, k) for k in PARAMETERS}, **({"A": A} if model == "ngf" else {})}
    cov = setup.covariance.copy()
    if model == "ngf":
        cov.loc["A", "A"] = setup.ngf_A_err ** 2
    sens = Sensitivity.of(lambda q: run(replace(setup.material, **{k: q[k] for k in PARAMETERS}), q.get("A"),
                                        coarse_numerics)["values"], central, cov)
    values = {}
    for o in OBSERVABLES:
        difference = partial(_difference, o)
        s_cal = sens.sd_of(lambda j, o=o: sens.shifted[j][o][0], coarse[o][0], difference=difference)
        values[o] = (fine["values"][o][0], float(richardson(0.0, difference(fine["values"][o][0], coarse[o][0]))),
                     s_cal)
    return OscPrediction(model, values, fine["zones"], fine["yielded"], fine["loop"], fine["velocity"])


def _difference(observable: str, a: float, b: float) -> float:
    """a - b, a phase difference wrapped into (-pi, pi]."""
    return float(phase.wrap(a - b)) if observable == "phase_lag" else a - b


def _row(dem: DemOscillation, pred: OscPrediction | None, observable: str, model: str, note: str) -> dict:
    drive = dem.drive
    v, err, how, dof = dem.values[observable]
    p, num, s_cal = pred.values[observable] if pred is not None else (np.nan, np.nan, np.nan)
    if pred is not None:
        note = _scene(dem, observable) or _unmeasurable(dem, observable) or _unpredicted(p, num, s_cal)
    elif not note.startswith("not predicted"):
        note = f"not predicted: {note}"
    scored = not note
    return score_row(
        drive=drive.label, observable=observable, unit=unit(drive, observable), dem=v, dem_err=err, dem_how=how,
        model=model, model_label=LABELS[model], predicted=float(p), band=band(p, float(np.hypot(num, s_cal))),
        numerical_err=num, calibration_sd=s_cal, sigma=sigma(_difference(observable, v, p), err, num, s_cal)
        if scored else np.nan, dof=effective_dof((err, num, s_cal), (dof, np.inf, np.inf)), note=note, blind=True,
        kind=drive.load.kind, omega=drive.load.omega,
        omega_ts=drive.omega_ts, amplitude=drive.load.amplitude, phase_lag=dem.values["phase_lag"][0],
        phase_lag_predicted=pred.values["phase_lag"][0] if pred is not None else np.nan)


#: the plate's observables (read off its speed and force), which a slipping plate falsifies
PLATE_OBSERVABLES = ("response_amplitude", "phase_lag", "dissipation")


def _scene(dem: DemOscillation, observable: str) -> str:
    """Why the scene cannot support a row against the rigid-plastic models, or "": a period shorter than
    TRANSITS_BEFORE_COMPARISON shear-wave transits over the bed (the bed answers elastically within a cycle, as the
    Stokes drives before their comparison starts), or, for the plate's observables, a plate that slips by more than
    SLIP_MAX against the grains touching it.  A drive whose tables carry no transit time is not checked for it."""
    transits = dem.drive.load.period / dem.drive.transit_time
    if transits < TRANSITS_BEFORE_COMPARISON:
        return (f"not scored: the plate's period spans {transits:.2g} shear-wave transits of the bed (fewer than "
                f"{TRANSITS_BEFORE_COMPARISON:g}): an elastic response, which rigid-plastic models do not have")
    if observable in PLATE_OBSERVABLES and dem.slip > SLIP_MAX:
        return (f"not scored: the plate slips {dem.slip:.0%} against the grains touching it (more than "
                f"{SLIP_MAX:.0%}), so its speed and force are not the bed's")
    return ""


def _unmeasurable(dem: DemOscillation, observable: str) -> str:
    v, err, *_ = dem.values[observable]
    if not (np.isfinite(v) and np.isfinite(err) and err > 0):
        return "not measurable: no error (fewer than two beds or whole cycles after the start-up)"
    if observable in ("yielded_depth", "remobilization_strain") and np.nanmax(dem.yielded) >= dem.zones.columns.max():
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
    rows = []
    for d in dems:
        for m in LABELS:
            p = predictions.get((d.drive.label, m))
            note = (p if isinstance(p, str) else "") if m in setup.models else ngf_note
            rows += [_row(d, p if isinstance(p, OscPrediction) else None, o, m, note) for o in OBSERVABLES]
    return pd.DataFrame(rows)


def laws(rows: pd.DataFrame) -> pd.DataFrame:
    """How the yielded depth and the phase lag scale with omega, per drive kind, amplitude and model: n in
    yielded_depth ~ (omega t_s)^n and s in phase_lag = a + s ln(omega t_s), weighted least squares with the DEM's
    errors (the model's slope on the same weights, its error from the per-drive bands taken as independent);
    drives not measurable are left out.

    Lack of fit: chi2, the DEM's weighted squared residuals about its line, has n - 2 degrees of freedom over n
    drives; the row quotes chi2_dof = chi2/(n - 2).  When chi2.sf(chi2, n - 2) < LACK_OF_FIT_P the DEM is not on a
    line (a step, a bend) and no slope is quoted: the row is "not measurable: not a line" with chi2/dof and p.
    Otherwise, when chi2_dof > 1 the scatter about the line exceeds the errors and the DEM slope's error is scaled by
    sqrt(chi2_dof).  The slope has n - 2 degrees of freedom (the row's dof combines them with the model's error,
    which has infinitely many).  The weights come from few beds (the per-bed spread of 3 beds has 2 degrees of
    freedom): each weight is itself uncertain, so chi2 is heavier-tailed than a chi-square and the test flags a
    true line more often than LACK_OF_FIT_P (five drives of three beds: 15 % of the time, simulated; there the 1 %
    quantile of chi2_dof is about 18, not 3.8); a chi2_dof in the hundreds is a step, not noise in the weights."""
    out = []
    for (kind, amp, model), g in rows[rows.scored].groupby(["kind", "amplitude", "model"]):
        for law, obs, fx, fy in (("yielded_depth_exponent", "yielded_depth", np.log, np.log),
                                 ("phase_lag_slope", "phase_lag", np.log, lambda v: v)):
            s = g[(g.observable == obs) & (g.dem > 0 if obs == "yielded_depth" else g.dem.notna())]
            s = s[s.predicted > 0] if obs == "yielded_depth" else s
            # one estimator per law: no family of choices (compare.families holds the Stokes drives')
            base = {"law": law, "kind": kind, "amplitude": amp, "model": model, "n_drives": len(s), "unit": "1",
                    "choices": [], "systematic": np.nan,
                    "window": f"omega t_s in [{s.omega_ts.min():.3g}, {s.omega_ts.max():.3g}]" if len(s) else "",
                    "quantity": "n in yielded_depth ~ (omega t_s)^n" if obs == "yielded_depth"
                    else "s in phase_lag = a + s ln(omega t_s) [rad]"}
            unfit = {"dem": np.nan, "dem_err": np.nan, "predicted": np.nan, "predicted_err": np.nan, "sigma": np.nan}
            if len(s) < 3:
                out.append(law_row(**base, **unfit, dof=np.nan, chi2_dof=np.nan,
                                   note=f"not measurable: {len(s)} measurable drive(s), a slope and its error need 3"))
                continue
            x = fx(s.omega_ts.to_numpy())
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
                out.append(law_row(**base, **unfit, dof=dof, chi2_dof=chi2 / dof,
                                   note=f"not measurable: not a line (chi2/dof = {chi2 / dof:.3g}, p = {p:.2g})"))
                continue
            dem_err *= np.sqrt(max(chi2 / dof, 1.0))
            pred_slope, pred_err = _weighted_slope(x, fy(s.predicted.to_numpy()), w, model_sd)
            out.append(law_row(**base, dem=dem_slope, dem_err=dem_err, predicted=pred_slope, predicted_err=pred_err,
                               sigma=sigma(dem_slope - pred_slope, dem_err, pred_err),
                               dof=effective_dof((dem_err, pred_err), (dof, np.inf)), chi2_dof=chi2 / dof, note=""))
    return pd.DataFrame(out)


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
    return ModelSetup(cal.material(), reps.cov(), ngf_A, ngf_err), ngf_note


def conclude(dem, dems: list[DemOscillation], setup: ModelSetup, ngf_note: str, predicted: list, calibration: str,
             ngf_from) -> OscillationComparison:
    """The OscillationComparison from every (drive, model)'s ``predict_unit``."""
    predictions = dict(predicted)
    rows = scorecard(dems, predictions, setup, ngf_note)
    source = (f"NGF's A = {setup.ngf_A:.3g} +- {setup.ngf_A_err:.2g} from {ngf_from}" if setup.ngf_A is not None
              else ngf_note)
    return OscillationComparison(tuple(sorted({str(d.run) for d, _ in dem})), setup, calibration, source,
                                 tuple(dems), predictions, rows, laws(rows))
