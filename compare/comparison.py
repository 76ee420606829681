"""The whole comparison, built once before anything is rendered: every drive's DEM analysis, the mu(I)
calibration, the continuum predictions from it, and the checks of the coarse-graining.

``build(run_dirs, settings, calibration=...)`` -> ``Comparison`` (frozen).  With ``calibration`` (a
calibration.json of ``granstokes dem calibrate``) mu(I) and phi come from that independent plane-shear
measurement and the drives are a blind test; only with ``fit_on_drives`` is mu(I) fitted on the drives' own
steady windows instead (``Comparison.calibration.kind`` and ``calibration_source`` say so: a fit, not a
prediction, and no row of it is blind).  A calibration that does not determine its law
(``Calibration.failure``) predicts nothing; an NGF amplitude at its search bound gives no NGF rows; a calibration
that measured the bed's shear modulus (its ``elasticity``) adds the elasto-plastic model.  An independent
calibration's band carries its transfer error to the drives (``transfer_sd``: how far the drives' own steady (mu, I)
pairs lie from the plane-shear law beyond their errors; ``with_transfer``).  compare.metrics and compare.report only
render it.  DEM units throughout; I in the DEM convention.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd
from granstokes.continuum.calibration import Calibration, mu_law
from granstokes.continuum.scales import Material, Scales
from granstokes.continuum.scene_models import LOCAL, PAPER, Prediction, SceneModel, elastic_model, ngf_model
from granstokes.dem.calibrate import grains_difference, pair_style_of
from granstokes.dem.layout import RUN_JSON
from scipy import stats
from tqdm import tqdm

from granstokes.lib.validate import require

from . import calibrate
from .analysis import DriveAnalysis, analyse_drive, mass_error
from .band import Sensitivity
from .checks import CROSSCHECK_MARGIN, lammps_crosscheck, width_check
from .drive import drive_specs, with_transit_time
from .laws import laws as paper_laws
from .nonlocal_fit import A_RANGE, FluidityFit, fit_amplitude
from .plate import STEADY_WINDOW_LATEST, power_law
from .profiles import CGSettings, standard_error
from .scorecard import Scorecard, base_reach, beyond_calibration, headline, scene_checks, score

#: continuum output times per drive (log-spaced from t_end/PREDICTION_SPAN to t_end, plus the snapshots)
PREDICTION_TIMES, PREDICTION_SPAN = 60, 300
#: calibration samples pushed through every steady prediction (bootstrap replicates of the fit)
REPLICATES = 200


@dataclass(frozen=True, eq=False)
class DriveComparison:
    """One drive: the DEM analysis, the paper's scales with the calibrated material, the continuum
    predictions (empty with ``note`` saying why when the calibrated law cannot sustain the drive) and
    ``base``: why the flow reaches the base, or "" (compare.scorecard.base_reach)."""

    dem: DriveAnalysis
    scales: Scales | None
    predictions: tuple[Prediction, ...]
    note: str
    base: str = ""
    sensitivity: dict = field(default_factory=dict)  # model key -> compare.scorecard.Sensitivity

    @property
    def label(self) -> str:
        return self.dem.label


@dataclass(frozen=True)
class Checks:
    """Coarse-graining checks on the first drive: kernel-width plateau and LAMMPS's own chunk
    averages (``crosscheck_bulk``: mean |CG - LAMMPS| / mean |LAMMPS| per quantity in the bulk)."""

    drive: str
    width: pd.DataFrame
    crosscheck: pd.DataFrame
    crosscheck_bulk: dict

    @classmethod
    def of(cls, drive: str, width: pd.DataFrame, cross: pd.DataFrame, y) -> Checks:
        """The checks with the crosscheck's bulk summary (CROSSCHECK_MARGIN inside the profile's heights ``y``)."""
        bulk = cross[(cross.y > y.min() + CROSSCHECK_MARGIN) & (cross.y < y.max() - CROSSCHECK_MARGIN)]
        summary = {q: float(np.nanmean(np.abs(bulk[f"{q}_diff"])) / np.nanmean(np.abs(bulk[f"{q}_lammps"])))
                   for q in ("phi", "u_x", "p", "tau_yx", "p_mop", "tau_mop")}
        return cls(drive, width, cross, summary)

    @property
    def plateau(self) -> pd.DataFrame:
        """Fraction of heights where each field plateaus going from each width to the next."""
        w = self.width[self.width.width > self.width.width.min()]
        return w.groupby(["field", "width"]).plateau.mean().unstack()


@dataclass(frozen=True, eq=False)
class DemSide:
    """Everything the comparison takes from the DEM, before any calibration: the runs (as given), their grains
    (run label -> (config's grains table, p_w)), every drive's analysis, the coarse-graining checks on the
    first drive and its mass error.  From dumps (``analyse``) or from its tables (compare.tables)."""

    runs: tuple[Path, ...]
    grains: dict
    drives: tuple[DriveAnalysis, ...]
    checks: Checks
    mass_error: float


@dataclass(frozen=True, eq=False)
class Comparison:
    dem: DemSide                 # what the comparison took from the DEM (compare.tables writes it)
    drives: tuple[DriveComparison, ...]
    pairs: pd.DataFrame
    calibration: Calibration     # its ``kind``: independent plane shear or the in-drive fit
    calibration_source: str
    replicates: pd.DataFrame     # joint samples mu_s, mu_d, I0 (DEM convention), phi
    material: Material
    phi_bulk: float
    scorecard: Scorecard
    fluidity: FluidityFit | None  # the NGF amplitude and the drive it was fitted on
    settings: CGSettings
    law_test: dict  # the drives' steady pairs against the law (law_test); a test only when ``blind``
    laws: pd.DataFrame  # the paper's laws, one row per law x model (compare.laws)

    @property
    def runs(self) -> tuple[Path, ...]:
        return self.dem.runs

    @property
    def rows(self) -> pd.DataFrame:
        """The scorecard's rows (compare.rows)."""
        return self.scorecard.rows

    @property
    def mass_error(self) -> float:
        return self.dem.mass_error

    @property
    def checks(self) -> Checks:
        return self.dem.checks

    @property
    def blind(self) -> bool:
        """True when mu(I) and phi come from an independent calibration (a prediction, not a fit)."""
        return self.calibration.is_prediction

    @property
    def failure(self) -> str:
        """Why the calibration cannot be used ("" when it can): then nothing is predicted."""
        return self.calibration.failure

    @property
    def verdict(self) -> str:
        """The comparison's verdict in one sentence (compare.scorecard.headline)."""
        return headline(self.scorecard.rows, self.blind, self.failure, len(self.drives))


def steady_pairs(drives: list[DriveAnalysis], wall_exclusion: float = calibrate.WALL_EXCLUSION,
                 spacing: float = calibrate.PAIR_SPACING) -> pd.DataFrame:
    """(mu, I_dem, phi) of every steady window, away from plate and base, one point per ``spacing``
    in depth (the kernel correlates neighbouring grid points: the fit's intervals need independent ones),
    with the standard errors of mu and phi from the window's band."""
    rows = []
    for a in drives:
        p = a.steady_profile
        inside = p[(p.depth > wall_exclusion) & (p.depth < a.spec.depth - wall_exclusion)]
        step = max(1, int(round(spacing / abs(np.diff(inside.y.to_numpy()[:2])[0]))))
        pick = inside.iloc[::step]
        rows.append(pick[["depth", "mu", "I_dem", "phi", "p", "tau"]].assign(
            drive=a.label, **{f"{k}_err": standard_error(pick[f"{q}_lo"], pick[f"{q}_hi"], pick.n)
                              for k, q in (("mu", "mu"), ("phi", "phi"), ("I", "I_dem"))}))
    return pd.concat(rows, ignore_index=True)


#: z beyond which a drive's steady (mu, I) pair disagrees with the law, and the fraction of pairs beyond
#: it that chance gives (two-sided normal): the verdict is "beyond errors" above twice that fraction
LAW_TEST_Z, LAW_TEST_CHANCE = 2.0, 0.0455


def _residuals(pairs: pd.DataFrame, cal: Calibration) -> tuple[np.ndarray, ...]:
    """The drives' steady pairs with I > I_MIN: I, the residual mu - mu(I) from the calibration's law, the pair's
    standard error s_pair (the steady window's band) and the law's bootstrap spread s_law at that I."""
    sel = pairs[(pairs.I_dem > calibrate.I_MIN) & np.isfinite(pairs.mu)]
    I = sel.I_dem.to_numpy()
    law = mu_law(I, cal.mu_s, cal.mu_d, cal.I0_dem)
    reps = np.array([mu_law(I, a, b, c) for a, b, c in
                     zip(cal.replicates["mu_s"], cal.replicates["mu_d"], cal.replicates["I0_dem"])])
    s_law = reps.std(axis=0, ddof=1) if len(reps) > 1 else np.zeros_like(I)
    return I, sel.mu.to_numpy() - law, np.nan_to_num(sel.mu_err.to_numpy()), s_law


#: the transfer error is measured on the pairs at I (DEM convention) at or above this: the flowing range, where the
#: local law is meant to hold. Below it the drives' pairs fall ever further under the plane-shear law (in the
#: committed disks -0.056 at I in [1e-3, 3e-3), -0.032 at [3e-3, 1e-2), -0.014 at [1e-2, 3e-2), -0.009 at
#: [0.03, 0.1), +0.003 above): the deficit of a slow flow driven by its neighbours, the nonlocal physics the models
#: are tested on, which an error band must not absorb
TRANSFER_I_MIN = 0.03


def transfer_sd(I, resid, s_pair, s_law) -> float:
    """The calibration's transfer error to the drives: over the pairs at I >= TRANSFER_I_MIN, the residuals' mean
    square beyond what their own errors and the law's spread explain, sqrt(max(0, <r^2 - s_pair^2 - s_law^2>))
    (method of moments): the drives' offset from the plane-shear law and their scatter about it, which the
    calibration's bootstrap does not hold; 0 with no pair there."""
    flowing = np.asarray(I) >= TRANSFER_I_MIN
    if not flowing.any():
        return 0.0
    excess = np.mean((np.asarray(resid) ** 2 - np.asarray(s_pair) ** 2 - np.asarray(s_law) ** 2)[flowing])
    return float(np.sqrt(max(excess, 0.0)))


def law_test(pairs: pd.DataFrame, cal: Calibration) -> dict:
    """The drives' steady (mu, I) pairs (I > I_MIN) against the calibration's law (``_residuals``): residual
    mu - mu(I) and z = residual / sqrt(s_pair^2 + s_law^2); the transfer error (``transfer_sd``); with a one-sentence
    verdict."""
    I, resid, s_pair, s_law = _residuals(pairs, cal)
    z = resid / np.sqrt(s_pair**2 + s_law**2 + 1e-300)
    out = {"n_pairs": int(len(I)), "mean_residual": float(resid.mean()),
           "rms_residual": float(np.sqrt(np.mean(resid**2))),
           "fraction_beyond": float(np.mean(np.abs(z) > LAW_TEST_Z)), "z_threshold": LAW_TEST_Z,
           "I_range": [float(I.min()), float(I.max())], "transfer_sd": transfer_sd(I, resid, s_pair, s_law)}
    side = "above" if out["mean_residual"] > 0 else "below"
    out["verdict"] = (f"{out['n_pairs']} steady (mu, I) pairs of the drives (I in [{I.min():.2g}, {I.max():.2g}]) "
                      f"lie on average {abs(out['mean_residual']):.3f} {side} the {cal.kind} law "
                      f"(rms {out['rms_residual']:.3f}); "
                      f"{out['fraction_beyond']:.0%} differ by more than {LAW_TEST_Z:g} combined standard errors"
                      + (" -- a disagreement beyond errors" if out["fraction_beyond"] > 2 * LAW_TEST_CHANCE else
                         " -- consistent within errors")
                      + f"; at I >= {TRANSFER_I_MIN:g}, where the local law is meant to hold, the transfer error "
                      f"beyond those errors is {out['transfer_sd']:.3f} in mu, and it widens every model's calibration "
                      "band")
    return out


#: the seeds of the fixed orders of the transfer error's and the shear modulus' samples over the replicates
TRANSFER_SEED, MODULUS_SEED = 1, 2


def quantile_draws(n: int, seed: int, dof: float = np.inf) -> np.ndarray:
    """n draws of a standard error's distribution for the propagation: Student-t's (the normal's at infinite dof)
    quantiles at (k + 1/2)/n, in a fixed shuffled order (``seed``: any half of the replicates holds both signs)."""
    q = (np.arange(n) + 0.5) / n
    values = stats.norm.ppf(q) if not np.isfinite(dof) else stats.t.ppf(q, dof)
    return values[np.random.default_rng(seed).permutation(n)]


def with_transfer(replicates: pd.DataFrame, sd: float) -> pd.DataFrame:
    """``replicates`` with mu_s and mu_d shifted together (the law moved as a whole, as the drives' pairs move from
    it) by ``sd`` times normal draws (``quantile_draws``, TRANSFER_SEED): the calibration band then carries the
    transfer error, the replicates' covariance sd^2 more in mu_s, mu_d and their covariance."""
    shift = sd * quantile_draws(len(replicates), TRANSFER_SEED)
    return replicates.assign(mu_s=replicates.mu_s + shift, mu_d=replicates.mu_d + shift)


def with_modulus(replicates: pd.DataFrame, elasticity: dict) -> pd.DataFrame:
    """``replicates`` with the bed's shear modulus G (calibration.json's ``elasticity``: G, its standard error and
    its dof over the seeds) drawn by ``quantile_draws`` (MODULUS_SEED), independent of the material's replicates: G
    is measured on the calibration's packing at rest, apart from the law."""
    draws = quantile_draws(len(replicates), MODULUS_SEED, float(elasticity.get("G_dof", np.inf)))
    return replicates.assign(G=float(elasticity["G"]) + float(elasticity["G_err"]) * draws)


def early_exponents(a: DriveAnalysis) -> dict:
    """alpha of u_w ~ t^alpha (imposed stress) and delta_u ~ t^alpha over the early window: from the
    first output after the elastic start (spec.compared_from) to the time u_w (delta_u) reaches half its
    steady value."""
    out = {}
    t, u = a.series.t.to_numpy(), a.series.u_w.to_numpy()
    start = np.nan_to_num(a.spec.compared_from)
    if a.spec.kind == "stress":
        half = t[np.argmax(u >= 0.5 * a.steady["u_w"]["value"])]
        out["alpha_u"] = power_law(t, u, max(t[1], start), half)
    d = a.delta.dropna()
    d = d[d.t >= start]
    if len(d) >= 4:
        final = d.delta_u.iloc[-len(d) // 4:].mean()
        half = d.t.iloc[np.argmax(d.delta_u.to_numpy() >= 0.5 * final)]
        out["alpha_delta"] = power_law(d.t.to_numpy(), d.delta_u.to_numpy(), d.t.iloc[0], max(half, d.t.iloc[3]))
    return out


def _checks(a: DriveAnalysis) -> Checks:
    widths = width_check(a.spec.beds[0], STEADY_WINDOW_LATEST * a.t_end, a.t_end)
    return Checks.of(a.label, widths, lammps_crosscheck(a.profiles[0]), a.steady_profile.y)


def prediction_times(a: DriveAnalysis) -> np.ndarray:
    """The continuum's output times for drive ``a``: log-spaced up to the record's end, plus its snapshots."""
    t_end = float(a.series.t.iloc[-1])
    return np.union1d(np.geomspace(t_end / PREDICTION_SPAN, t_end, PREDICTION_TIMES), a.snapshots)


def _predict(a: DriveAnalysis, material: Material, models, failure: str) -> tuple:
    """(scales, predictions, note, base) of drive ``a``: every model's prediction, or a note saying why none."""
    if failure:
        return None, (), f"no continuum prediction: the mu(I) calibration failed ({failure})", ""
    try:
        scales = a.spec.load.scales(material)
    except ValueError as err:  # e.g. tau_w >= mu_d p_w: local mu(I) has no steady state at all
        return None, (), (f"no continuum prediction: {err} (the calibrated mu(I) cannot sustain this drive: the "
                          "plate would accelerate forever)"), ""
    times = prediction_times(a)
    preds = []
    for model in models:
        try:
            preds.append(model.predict(material, a.spec.scene, a.spec.load, times))
        except RuntimeError as err:  # a solver that gave up (continuum.stepper): said, not hidden
            return None, (), (f"no continuum prediction: the {model.key} model's solver failed ({err}) at this "
                              "calibration"), ""
    return scales, tuple(preds), "", base_reach(a, preds[0].steady.delta_s)


@dataclass(frozen=True)
class ModelSide:
    """Everything a drive's predictions and scoring need beyond the drive itself (shared by the workers)."""

    material: Material
    models: tuple
    failure: str
    replicates: pd.DataFrame
    fitted_on: dict
    independent: bool
    calibrated_I: tuple[float, float]  # the calibration's range of I (DEM convention): a model beyond it extrapolates


def replicates_of(cal: Calibration, phi: np.ndarray, n: int = REPLICATES) -> pd.DataFrame:
    """The first ``n`` joint bootstrap samples (mu_s, mu_d, I0 in the DEM convention, phi) of a
    calibration whose law is valid (mu_d > mu_s); ``phi`` the matching samples of the continuum's phi."""
    r = pd.DataFrame({"mu_s": cal.replicates["mu_s"], "mu_d": cal.replicates["mu_d"], "I0": cal.replicates["I0_dem"],
                      "phi": phi})
    return r[(r.mu_d > r.mu_s) & (r.I0 > 0)].head(n).reset_index(drop=True)


def run_grains(runs) -> dict:
    """run label -> (its config's grains table, p_w), from each run folder's run.json."""
    out = {}
    for run in runs:
        config = json.loads((Path(run) / RUN_JSON).read_text())["config"]
        out[str(run)] = (config["grains"], config.get("p_w", np.nan))
    return out


#: what ``ignore`` may leave out of the grains check: the LAMMPS implementation of the same contact law
IGNORABLE = ("pair_style",)


def check_grains(cal: Calibration, grains: dict, ignore: tuple[str, ...] = ()) -> None:
    """Refuse a calibration of other grains than the runs' (``grains``: run_grains; one-line ValueError naming the
    difference; dem.calibrate.grains_difference: one material, one stiffness k_n at any pressure), leaving out the
    entries in ``ignore`` (of IGNORABLE)."""
    p_cal = float(cal.info.get("protocol", {}).get("p", np.nan))
    for run, (table, p_w) in grains.items():
        diff = grains_difference(cal.grains, p_cal if np.isfinite(p_cal) else p_w, table, p_w)
        diff = {k: v for k, v in diff.items() if k not in ignore}
        require(not diff, f"--calibration {cal.source}", f"a calibration of the grains of {run}",
                "different grains: " + ", ".join(f"{k} calibrated {a!r} vs run {b!r}" for k, (a, b) in diff.items()))


def pair_style_clause(cal: Calibration, grains: dict) -> str:
    """'' or, where the calibration ran in another pair style than the runs (compare --any-pair-style), a clause
    saying so for the calibration's source."""
    styles = sorted({pair_style_of(table) for table, _ in grains.values()})
    calibrated = pair_style_of(cal.grains)
    return "" if styles == [calibrated] else (f", calibrated in pair style {calibrated}, the drives run in "
                                             f"{', '.join(styles)}")


def analyse(run_dirs, settings: CGSettings = CGSettings(), progress: bool = True, root: Path | None = None) -> DemSide:
    """Coarse-grain every drive of ``run_dirs`` (complete run folders of granstokes dem run); with ``root``, the
    runs are named by their paths relative to it (a study's report names its own run folders)."""
    runs = tuple(Path(r) for r in run_dirs)
    resolved = [r.resolve() for r in runs]
    require(len(set(resolved)) == len(resolved), "RUN_DIR", "distinct run folders (one was given twice)",
            [str(r) for r in runs])
    specs = [spec for run in runs for spec in drive_specs(run)]
    drives = tuple(analyse_drive(spec, settings)
                   for spec in tqdm(specs, desc="coarse-graining", disable=not progress or None))
    grains, checks = run_grains(runs), _checks(drives[0])
    if root is not None:
        rel = {str(r): r.resolve().relative_to(Path(root).resolve()) for r in runs}
        grains = {str(rel[k]): v for k, v in grains.items()}
        runs = tuple(rel[str(r)] for r in runs)
        drives = tuple(replace(a, spec=replace(a.spec, run=rel[str(a.spec.run)])) for a in drives)
        checks = replace(checks, drive=drives[0].label)
    return DemSide(runs, grains, drives, checks, mass_error(drives[0]))


def timed(dem: DemSide, independent: Calibration | None) -> DemSide:
    """``dem`` with every drive's elastic start timed by the shear-wave speed the ``independent`` calibration
    measured in its packing (compare.drive.with_transit_time), where it holds one; else as run (the contacts'
    speed d sqrt(k_t/m), dem.sizing)."""
    elasticity = getattr(independent, "elasticity", None)
    if not elasticity:
        return dem
    p_cal = float(independent.info.get("protocol", {}).get("p", np.nan))
    return replace(dem, drives=tuple(replace(a, spec=with_transit_time(a.spec, independent.grains, p_cal, elasticity))
                                     for a in dem.drives))


def prepare(dem: DemSide, independent: Calibration | None, ignore: tuple[str, ...] = ()) -> tuple[ModelSide, dict]:
    """What every drive's prediction shares: mu(I) and phi from the ``independent`` calibration (calibration.json,
    refused if its grains differ from the runs') or, without one, fitted on the drives' steady windows; the models
    (NGF when its amplitude fits within its search range).  Returns the ModelSide and what the Comparison keeps."""
    drives = list(dem.drives)
    pairs = steady_pairs(drives)
    phi = float(pairs.phi.mean())
    if independent is None:
        cal = calibrate.fit(pairs, n_boot=REPLICATES)
        source = "in-drive fit (not a blind test)"
        material = cal.material(phi=phi)
        replicates = replicates_of(cal, cal.replicates["phi_bulk"])
    else:
        # the continuum's constant phi is the calibration's phi(I -> 0) = phi_max: the bed below the layer is at rest
        check_grains(independent, dem.grains, ignore)
        cal = independent
        source = f"blind: independent plane-shear calibration {cal.source}" + pair_style_clause(cal, dem.grains)
        material = cal.material()
        replicates = replicates_of(cal, cal.replicates["phi_max"])
    tested = law_test(pairs, cal)
    if independent is not None:  # the in-drive fit is the drives' own law: nothing to transfer
        replicates = with_transfer(replicates, tested["transfer_sd"])
    failure = cal.failure
    fluidity = None if failure else _fit_fluidity(drives, material)
    ngf = fluidity is not None and not fluidity.at_bound  # an amplitude at its search bound is a failed fit
    models = [LOCAL, PAPER] + ([ngf_model(fluidity.A)] if ngf else [])
    if ngf:
        replicates = replicates.assign(A=_amplitude_samples(fluidity, len(replicates)))
    elasticity = getattr(cal, "elasticity", None) if independent is not None and not failure else None
    if elasticity:  # the bed's shear modulus, measured with the calibration: the elasto-plastic model
        models.append(elastic_model(float(elasticity["G"])))
        replicates = with_modulus(replicates, elasticity)
    calibrated_I = calibrate.calibrated_range(cal)
    side = ModelSide(material, tuple(models), failure, replicates, {"ngf": fluidity.drive} if ngf else {},
                     independent is not None, calibrated_I)
    return side, {"pairs": pairs, "calibration": cal, "calibration_source": source, "phi_bulk": phi,
                  "fluidity": fluidity, "law_test": tested}


def material_at(base: Material, row) -> Material:
    """``base`` with a replicate's (or a shifted) mu_s, mu_d, I0 (DEM convention) and phi."""
    return replace(base, mu_s=float(row["mu_s"]), mu_d=float(row["mu_d"]), I0=float(row["I0"]),
                   I_convention="dem", phi=float(row["phi"]))


def sensitivity(model: SceneModel, material: Material, a: DriveAnalysis, times, replicates: pd.DataFrame):
    """Drive ``a``'s prediction by ``model`` re-solved with each calibrated parameter (the material's, then the
    model's own) shifted (compare.band: one transient and one steady solve per parameter)."""
    central = {"mu_s": material.mu_s, "mu_d": material.mu_d, "I0": material.I0, "phi": material.phi,
               **({model.parameter: model.parameters[model.parameter]} if model.parameter else {})}
    return Sensitivity.of(lambda q: model.at(q).predict(material_at(material, q), a.spec.scene, a.spec.load, times),
                          central, replicates[list(central)].cov())


def spread(a: DriveAnalysis, model: SceneModel, material: Material, replicates: pd.DataFrame, times) -> tuple:
    """The calibration's spread of ``model``'s prediction of drive ``a``: its steady states at the replicates that
    sustain the drive (in their order) and its Sensitivity."""
    steadies = []
    for _, r in replicates.iterrows():
        try:
            steadies.append(model.at(r).steady(material_at(material, r), a.spec.scene, a.spec.load))
        except ValueError:  # a replicate that cannot sustain the drive (e.g. mu_d below mu_w)
            continue
    return tuple(steadies), sensitivity(model, material, a, times, replicates)


def model_drive(a: DriveAnalysis, side: ModelSide) -> tuple:
    """One drive's model side, every solve of it (the predictions, their spread over the calibration), then its
    scoring (compare.scorecard.score, estimation only): ((scales, predictions, note, base, sensitivities by model),
    scorecard rows, the band edges' largest relative change, bands)."""
    scales, preds, note, base = _predict(a, side.material, side.models, side.failure)
    if not preds:
        return (scales, preds, note, base, {}), pd.DataFrame(), np.nan, {}
    spreads = {p.model: spread(a, m, side.material, side.replicates, p.series.t.to_numpy())
               for m, p in zip(side.models, preds)}
    beyond = {p.model: beyond_calibration(side.material, [p.steady.mu_w], side.calibrated_I) for p in preds}
    rows, edges, bands = score(a, side.models, {p.model: p for p in preds}, spreads, len(side.replicates),
                               side.fitted_on, side.independent, beyond)
    return (scales, preds, note, base, {key: sens for key, (_, sens) in spreads.items()}), rows, edges, bands


def conclude(dem: DemSide, side: ModelSide, kept: dict, results: list, settings: CGSettings) -> Comparison:
    """The Comparison of ``dem`` from every drive's ``model_drive`` result (in the drives' order)."""
    drives = list(dem.drives)
    compared = tuple(DriveComparison(a, *model_side) for a, (model_side, *_) in zip(drives, results))
    rows = pd.concat([r[1] for r in results if len(r[1])], ignore_index=True) if any(len(r[1]) for r in results) \
        else pd.DataFrame()
    edges = [r[2] for r in results if np.isfinite(r[2])]
    bands = {k: v for r in results for k, v in r[3].items()}
    card = Scorecard.of(rows, [r for a in drives for r in scene_checks(a)], len(side.replicates),
                        float(np.max(edges)) if edges else np.nan, bands)
    return Comparison(dem, compared, kept["pairs"], kept["calibration"], kept["calibration_source"], side.replicates,
                      side.material, kept["phi_bulk"], card, kept["fluidity"], settings,
                      kept["law_test"], paper_laws(compared, side.calibrated_I))


def _fit_fluidity(drives: list[DriveAnalysis], material: Material) -> FluidityFit | None:
    """A of the NGF model, fitted on the creep of the first imposed-stress drive that local mu(I) can
    sustain (compare.nonlocal_fit); None when there is none."""
    for a in drives:
        if a.spec.kind == "stress" and a.spec.load.mu_w < material.mu_d:
            return fit_amplitude(a, material)
    return None


def _amplitude_samples(fit: FluidityFit, n: int, seed: int = 1) -> np.ndarray:
    """Samples of A for the propagation: normal with the fit's standard error (independent of the
    material's replicates: A is fitted given the central calibration), kept inside the search range."""
    err = fit.err if np.isfinite(fit.err) else 0.0
    return np.clip(np.random.default_rng(seed).normal(fit.A, err, n), *A_RANGE)
