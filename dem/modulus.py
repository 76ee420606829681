"""The shear modulus G(p) and shear-wave speed c_s(p) of the calibration's static packing (a stage of dem.calibrate).

**Cell.** For each seed, the periodic plane-shear cell of dem.shear (same grains, contact law, n_grains, time step;
the same insertion and compression until the contact part of P_yy reaches p, ``shear.packing_script``), then:

1. *Rest under sigma_yy = p.*  The compression ends on a transient: its last check sees P_yy above p while grains are
   still colliding, and at fixed volume that stress vanishes as they settle (measured on the disks at p = 20: P_yy
   49 -> 0).  ``fix deform/pressure`` on L_y alone (no shear) then holds sigma_yy = p with the normalised gain
   ``relax_gain`` = RELAX_I sqrt(p/rho_p)/d: from an unjammed state it compresses at the inertial number RELAX_I
   (quasi-static, 45x slower than the compression), and at p it corrects P_yy - p over a time 1/(gain M/p), M the
   uniaxial modulus: several transits if M ~ 0.1 k_n/d^(D-2) (a guess from the compression's last step; the cells'
   P_yy settles at p without ringing or unjamming).  It ends when |P_yy -
   p| < P_TOL p and the kinetic energy per grain is below KE_STATIC p d^D/kappa (the contact energy scale), checked
   every RELAX_CHECK transits, at most RELAX_MAX_STRAIN of compression.  Then L_y is held, a viscous drag
   (``fix viscous``, rate 1/transit) drains what still moves (rattlers, slow modes) for REST_TRANSITS, and the cell
   rests undamped for SETTLE_TRANSITS: that state is the static packing (``static.csv``: phi, Z, P_yy, tau, kinetic
   energy).  Which packing it is matters: on the disks at p = 20 (seed 1) quenching the compressed packing with a
   viscous drag before a slow recompression gave phi 0.792-0.796 and G = 3400-5500, against phi 0.805 and G = 13200
   here; a frictional packing's G follows its contact network (Agnolin & Roux, PRE 76, 061304, 2007), so the protocol
   is fixed here and stated in calibration.json.
2. *Oscillatory simple shear of the box tilt* at fixed L_y: ``fix deform 1 xy wiggle A T remap v``,
   gamma(t) = xy/L_y = gamma_0 sin(omega t), the velocity profile of the rate at t = 0 given first
   (``comm_modify vel yes``), CYCLES periods at each of the two AMPLITUDES, the smaller first (the first cycle of each
   is its start-up, dropped).  The period is TRANSITS transits of the cell (its width) at SPEED_FRACTION of the
   contacts' speed d sqrt(k_t/m): quasi-static (the measured c_s is ~0.4 of that speed: ~100 transits at c_s).
   Why L_y and not sigma_yy is held while it oscillates: in an isotropic linear solid simple shear changes sigma_yy
   only at second order (gamma_0^2 <= 4e-12 here), and the controller would add its own response at omega to the
   measured stress (its time constant is a few transits, so at the period it would shift G'' most); with L_y held
   the imposed strain is exactly known.  The packing's fabric couples sigma_yy to shear at first order (measured:
   |sigma_yy first harmonic|/gamma_0 = ``normal_coupling``, 0.1-0.4 G); holding sigma_yy instead would lower G by
   coupling^2/M (M the uniaxial modulus, not measured: a few % at most if M is 3-5 G).

**Measured.** tau = -P_xy from ``compute pressure`` with ``compute temp/deform`` (as dem.shear; the grains barely
move: it is the contacts' stress), gamma = xy/L_y from the box.  Each cycle after the first: least squares of tau(t)
and gamma(t) on [1, t, sin omega t, cos omega t] (the linear term takes a slow drift of the static stress); the
complex amplitudes give G* = tau_hat/gamma_hat = G' + i G'' (storage and loss moduli).  A seed's G' is the mean over
its cycles (their spread: ``cycle_err``).  Over seeds: mean and standard error, n - 1 degrees of freedom (``G_dof``).

**Amplitudes.** gamma_0 kappa = AMPLITUDES (kappa = k_n/(p d) for Hooke: a contact's overlap is d/kappa): the
contacts' tangential displacement is a fraction of the one that makes a mean contact slide (mu_p f_n/k_t ~ 1.75
d/kappa), and gamma_0 is below 5 % of the yield strain mu_s p/G (recorded: ``linearity.gamma_0_over_yield``).
Linearity: the same seeds at 10x the amplitude (``linearity``: the per-seed ratio of G', its mean and standard error,
whether it is 1 within Student-t's 95 %, and the softening it implies at gamma_0 if it grows linearly with the
amplitude, as the contacts' microslip does).  G is the smaller amplitude's.

**Wave speed.** c_s = sqrt(G/(phi rho_p)), phi the static packing's; its error propagated from G's and phi's
(independent: phi's relative error is a few % of G's).

**Affine estimate** (``affine_modulus``): every contact strained with the mean strain (Voigt), Hooke normal and
tangential springs, contact directions isotropic, the branch vector one mean diameter d:
G_aff = phi Z (k_n + beta k_t)/(alpha pi d^(D-2)), alpha = 4, beta = 1 in 2D and alpha = 5, beta = 3/2 in 3D, Z the
contacts per grain (2 N_c/N, rattlers included: it counts contact density).  3D: the effective-medium (Walton)
modulus, Makse, Gland, Johnson & Schwartz, Phys. Rev. E 70, 061302 (2004), mu_EMT = (k_n + 3/2 k_t) Z phi/(20 pi R)
with their stiffness per half-overlap (k_n here = theirs/2, R = d/2).  2D: the uniform-strain (Voigt) estimate of
disk assemblies with constant normal and tangential stiffnesses, Agnolin & Kruyt, Int. J. Solids Struct. 45, 1101
(2008) (arXiv:0711.2894), derived here by the same average: per contact sigma_xy = (1/V) l^2 e [2 k_n n_x^2 n_y^2 +
k_t ((n_x^2 + n_y^2)/2 - 2 n_x^2 n_y^2)] for a symmetric strain e = gamma/2, <n_x^2 n_y^2> = 1/8 (2D), 1/15 (3D),
N_c/V = Z phi/(2 v_grain).  Polydispersity changes the contact-length average by <l^2>/<d^D>^(2/D) ~ 1 - w^2/6
(< 1 % for w = 0.2), neglected.  The affine estimate is an upper bound of the linear modulus (non-affine relaxation
lowers it: Makse et al.; Agnolin & Kruyt); G/G_aff measures how far from affine the packing responds.

Outputs per seed (dem.layout): DIR/modulus/seed-S/ in.lammps, log.lammps, static.csv (``STATIC_COLUMNS``),
oscillation-K.csv (``MODULUS_SERIES_COLUMNS``, K the amplitude's index).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from scipy import stats

from .config import Config
from .contact import grain_mass, grain_volume
from .layout import MODULUS_SERIES_COLUMNS, STATIC_COLUMNS, STATIC_CSV, modulus_series_csv
from .shear import packing_script

#: at least this many seeds (the calibration's, completed with the next integers after its largest): an error over
#: seeds needs n - 1 >= 2 degrees of freedom
MIN_SEEDS = 3
#: the two strain amplitudes as gamma_0 kappa (d/kappa is a contact's overlap under the force p d); G is the first's
AMPLITUDES = (0.02, 0.2)
#: the period is TRANSITS transits of the cell's width at SPEED_FRACTION of the contacts' speed d sqrt(k_t/m)
TRANSITS = 50.0
SPEED_FRACTION = 0.2
#: periods at each amplitude; the first DROPPED of them are the start-up
CYCLES, DROPPED = 4, 1
#: samples of the series per period
SAMPLES_PER_CYCLE = 100
#: rest under sigma_yy = p: the controller's normalised gain is RELAX_I sqrt(p/rho_p)/d (an unjammed packing is
#: compressed at this inertial number); it ends at |P_yy - p| < P_TOL p and a kinetic energy per grain below
#: KE_STATIC p d^D/kappa, checked every RELAX_CHECK transits, after at most RELAX_MAX_STRAIN of compression
RELAX_I = 1e-4
P_TOL = 1e-3
KE_STATIC = 1e-3
RELAX_CHECK = 2.0
RELAX_MAX_STRAIN = 0.1
#: then L_y held: REST_TRANSITS under a viscous drag of rate 1/transit, SETTLE_TRANSITS undamped
REST_TRANSITS, SETTLE_TRANSITS = 20.0, 5.0
#: the record's statement of what G and c_s are (calibration.json "elasticity"), as I_convention states I's
CONVENTION = ("G = storage modulus of the periodic cell's static packing at sigma_yy = p under small-amplitude "
              "oscillatory simple shear; c_s = sqrt(G/(phi rho_p)); DEM units: stress rho_p g d, speed sqrt(g d)")
#: affine (Voigt) modulus G_aff = phi Z (k_n + beta k_t)/(alpha pi d^(D-2)): (alpha, beta) by dimension
AFFINE = {2: (4.0, 1.0), 3: (5.0, 1.5)}
AFFINE_SOURCE = ("uniform (affine) strain of Hooke normal and tangential springs over isotropic contact directions; "
                 "3D: Makse, Gland, Johnson & Schwartz, Phys. Rev. E 70, 061302 (2004), mu_EMT = (k_n + 3/2 k_t) Z "
                 "phi/(20 pi R) with k_n per half-overlap; 2D: the uniform-strain estimate of Agnolin & Kruyt, Int. J. "
                 "Solids Struct. 45, 1101 (2008), same average (dem/modulus.py)")


@dataclass(frozen=True)
class ModulusCell:
    """The oscillation of one cell: the period, amplitudes and step counts (the same for every seed)."""

    dt: float
    period_steps: int  # steps per period (a multiple of SAMPLES_PER_CYCLE)
    sample: int  # steps between samples
    amplitudes: tuple[float, ...]  # gamma_0 of each stage
    transit: float  # the cell's width over SPEED_FRACTION of the contacts' speed
    relax_gain: float  # the rest's normalised controller gain (1/time)
    relax_check: int  # steps between the rest's checks
    relax_checks: int  # at most this many checks
    rest_steps: int
    settle_steps: int
    ke_static: float  # kinetic energy per grain that counts as static
    viscous: float  # the drag coefficient of the rest (force/velocity)

    @property
    def period(self) -> float:
        return self.period_steps * self.dt

    @property
    def omega(self) -> float:
        return 2 * math.pi / self.period

    @property
    def oscillation_steps(self) -> int:
        return CYCLES * self.period_steps * len(self.amplitudes)

    def expected_steps(self, compress_steps: int) -> int:
        """A cell's steps after its compression: the rest (``compress_steps`` stand for its recompression, which
        covers the strain the compression's transient overshot), the drained and undamped rests, the oscillations."""
        return compress_steps + self.rest_steps + self.settle_steps + self.oscillation_steps

    def as_dict(self) -> dict:
        return {"period": self.period, "omega": self.omega, "period_steps": self.period_steps,
                "sample_steps": self.sample, "gamma_0": list(self.amplitudes),
                "gamma_0_kappa": list(AMPLITUDES), "cycles": CYCLES, "dropped_cycles": DROPPED,
                "transit": self.transit, "period_transits": TRANSITS,
                "transit_speed": f"{SPEED_FRACTION:g} d sqrt(k_t/m) (m of a grain of diameter d)",
                "rest": {"gain": self.relax_gain, "I": RELAX_I, "p_tol": P_TOL, "ke_static": self.ke_static,
                         "check_steps": self.relax_check, "max_checks": self.relax_checks,
                         "drained_steps": self.rest_steps, "viscous": self.viscous,
                         "undamped_steps": self.settle_steps},
                "held": "L_y (sigma_yy = p reached at rest before the oscillation)"}


def plan_cell(cfg: Config, dt: float) -> ModulusCell:
    """The oscillation of the config's calibration cell at its time step ``dt``."""
    c, dim, width = cfg.contact, cfg.grains.dimension, cfg.calibration.width
    transit = width / (SPEED_FRACTION * c.shear_wave_speed)
    period_steps = math.ceil(TRANSITS * transit / dt / SAMPLES_PER_CYCLE) * SAMPLES_PER_CYCLE
    gain = RELAX_I * math.sqrt(cfg.p_w)  # d = rho_p = 1
    check = max(1, round(RELAX_CHECK * transit / dt))
    checks = math.ceil(RELAX_MAX_STRAIN / gain / (check * dt))
    return ModulusCell(dt, period_steps, period_steps // SAMPLES_PER_CYCLE,
                       tuple(a / c.kappa for a in AMPLITUDES), transit, gain, check, checks,
                       round(REST_TRANSITS * transit / dt), round(SETTLE_TRANSITS * transit / dt),
                       KE_STATIC * cfg.p_w * grain_volume(1.0, dim) / c.kappa,
                       grain_mass(1.0, dim) / transit)


def modulus_seeds(seeds) -> tuple[int, ...]:
    """The calibration's seeds, completed to MIN_SEEDS with the integers after the largest."""
    seeds = tuple(seeds)
    extra = tuple(max(seeds) + 1 + i for i in range(max(0, MIN_SEEDS - len(seeds))))
    return seeds + extra


def modulus_script(cfg: Config, cell: ModulusCell, n_grains: int, seed: int) -> str:
    """Insert and compress as dem.shear, rest at sigma_yy = p until static, then oscillate the tilt at each amplitude;
    writes static.csv and oscillation-K.csv."""
    p = cfg.p_w
    cols = ",".join(MODULUS_SERIES_COLUMNS)
    fmt = ",".join(f"$({v})" for v in ("step", "v_t:%.10g", "lx:%.10g", "ly:%.10g", "xy:%.12g", "c_press[1]:%.10g",
                                        "c_press[2]:%.10g", "c_press[4]:%.10g", "v_phi:%.10g", "v_ke:%.6g",
                                        "v_Z:%.6g"))
    static = ",".join(f"$({v})" for v in ("step", "v_t:%.10g", "ly:%.10g", "c_press[1]:%.10g", "c_press[2]:%.10g",
                                           "c_press[4]:%.10g", "v_phi:%.10g", "v_Z:%.8g", "v_rattlers:%.8g",
                                           "v_ke:%.6g"))
    stages = []
    for k, gamma_0 in enumerate(cell.amplitudes):
        before = cell.amplitudes[k - 1] if k else 0.0
        stages.append(f"""
# --- amplitude {k}: gamma_0 = {gamma_0:.4g} ({AMPLITUDES[k]:g}/kappa), {CYCLES} periods of {cell.period:.6g} ---
print "PHASE oscillate-{k}"
velocity all ramp vx 0.0 $({(gamma_0 - before) * cell.omega:.12g}*ly) y $(ylo) $(yhi) sum yes units box
fix series all print {cell.sample} "{fmt}" file {modulus_series_csv(k)} screen no title "{cols}"
fix oscillate all deform 1 xy wiggle $({gamma_0:.12g}*ly) {cell.period:.12g} remap v
run {CYCLES * cell.period_steps}
unfix oscillate
unfix series
""")
    return (f"""# modulus cell, seed {seed}: static packing at P_yy = {p:g}, oscillatory shear; generated by dem.modulus

{packing_script(cfg, cell.dt, n_grains, seed, cell.relax_check)}
# --- rest under sigma_yy = p (L_y, normalised gain {cell.relax_gain:.4g}) until static ---
compute ke all ke
variable ke equal c_ke/atoms
compute contacts all contact/atom
compute contact_sum all reduce sum c_contacts
variable Z equal c_contact_sum/atoms
variable rattler atom c_contacts<2
compute rattler_sum all reduce sum v_rattler
variable rattlers equal c_rattler_sum/atoms
compute tdef all temp/deform
compute press all pressure tdef
thermo_style custom step v_t c_press[1] c_press[2] c_press[4] v_phi v_ke v_Z v_rattlers
thermo_modify norm no lost error flush yes format float %.10g
print "PHASE rest"
fix hold all deform/pressure 1 y pressure {p:.10g} {cell.relax_gain:.10g} normalize/pressure yes """
            f"""max/rate {10 * cell.relax_gain:.10g} remap x
variable i loop {cell.relax_checks}
label rest
run {cell.relax_check}
if "${{ke}} < {cell.ke_static:.10g} && $(abs(c_press[2]-{p:.10g})) < {P_TOL * p:.10g}" then "jump SELF static"
next i
jump SELF rest
label static
variable i delete
unfix hold

# --- L_y held: drain what still moves, then rest undamped; the static packing ---
print "PHASE drain"
fix drain all viscous {cell.viscous:.10g}
run {cell.rest_steps}
unfix drain
print "PHASE settle"
run {cell.settle_steps}
print "{",".join(STATIC_COLUMNS)}" file {STATIC_CSV} screen no
print "{static}" append {STATIC_CSV} screen no
{"".join(stages)}""")


# --- analysis -------------------------------------------------------------------------------------------
def harmonic(t, y, omega: float) -> complex:
    """The first harmonic of ``y(t)`` as a complex amplitude a + i b of y ~ c0 + c1 t + a sin(omega t) + b cos(omega
    t) (least squares; the linear term takes a slow drift)."""
    t = np.asarray(t, dtype=float)
    tc = t - t.mean()
    design = np.column_stack([np.ones_like(t), tc, np.sin(omega * t), np.cos(omega * t)])
    coef = np.linalg.lstsq(design, np.asarray(y, dtype=float), rcond=None)[0]
    return complex(coef[2], coef[3])


def cycle_moduli(t, gamma, tau, omega: float, cycles: int | None = None, dropped: int | None = None,
                 p_yy=None) -> pd.DataFrame:
    """G' and G'' of each cycle after the ``dropped`` first ones (default DROPPED) of ``cycles`` (default CYCLES)
    (complex G* = tau_hat/gamma_hat), the strain amplitude, and with ``p_yy`` |p_yy_hat/gamma_hat| (the normal
    stress's first-order coupling to shear).  Cycle c is t - t[0] in [c T, (c + 1) T)."""
    cycles, dropped = CYCLES if cycles is None else cycles, DROPPED if dropped is None else dropped
    t, gamma, tau = (np.asarray(x, dtype=float) for x in (t, gamma, tau))
    period, rows = 2 * math.pi / omega, []
    since = t - t[0]
    for c in range(dropped, cycles):
        m = (since >= c * period - 1e-9 * period) & (since < (c + 1) * period - 1e-9 * period)
        g_hat = harmonic(t[m], gamma[m], omega)
        G = harmonic(t[m], tau[m], omega) / g_hat
        row = {"cycle": c, "G": G.real, "G_loss": G.imag, "gamma_0": abs(g_hat), "samples": int(m.sum())}
        if p_yy is not None:
            row["normal_coupling"] = abs(harmonic(t[m], np.asarray(p_yy, dtype=float)[m], omega) / g_hat)
        rows.append(row)
    return pd.DataFrame(rows)


def analyse_cell(folder: Path, cell: ModulusCell, seed: int) -> dict:
    """A seed's record: its static packing (static.csv) and, per amplitude, the cycles' G', G'' (their mean and
    standard error over cycles, ``cycle_err``), the measured gamma_0 and the normal coupling."""
    folder = Path(folder)
    static = pd.read_csv(folder / STATIC_CSV).iloc[-1]
    amplitudes = []
    for k, gamma_0 in enumerate(cell.amplitudes):
        s = pd.read_csv(folder / modulus_series_csv(k))
        cycles = cycle_moduli(s.t, s.xy / s.ly, -s.p_xy, cell.omega, p_yy=s.p_yy)
        n = len(cycles)
        amplitudes.append({"gamma_0_set": gamma_0, "gamma_0": float(cycles.gamma_0.mean()),
                           "G": float(cycles.G.mean()), "G_loss": float(cycles.G_loss.mean()),
                           "cycle_err": float(cycles.G.std(ddof=1) / math.sqrt(n)) if n > 1 else math.nan,
                           "cycles": cycles.G.tolist(), "cycles_loss": cycles.G_loss.tolist(),
                           "normal_coupling": float(cycles.normal_coupling.mean()),
                           "p_yy": float(s.p_yy.mean()), "phi": float(s.phi.mean()), "Z": float(s.Z.mean())})
    return {"seed": seed, "G": amplitudes[0]["G"], "G_loss": amplitudes[0]["G_loss"],
            "phi": float(static.phi), "Z": float(static.Z), "rattler_fraction": float(static.rattlers),
            "p_yy": float(static.p_yy), "tau": float(-static.p_xy), "ke_per_grain": float(static.ke),
            "amplitudes": amplitudes}


def affine_modulus(phi: float, Z: float, k_n: float, k_t: float, dimension: int, d: float = 1.0) -> float:
    """The affine (Voigt) shear modulus of Hooke springs, G_aff = phi Z (k_n + beta k_t)/(alpha pi d^(D-2)) (the
    module's docstring: derivation and sources); 2D stresses per unit thickness."""
    alpha, beta = AFFINE[dimension]
    return phi * Z * (k_n + beta * k_t) / (alpha * math.pi * d ** (dimension - 2))


def mean_err(values) -> tuple[float, float]:
    """Mean and standard error (standard deviation with n - 1 degrees of freedom over sqrt n); NaN error below 2."""
    x = np.asarray(values, dtype=float)
    return float(x.mean()), float(x.std(ddof=1) / math.sqrt(len(x))) if len(x) > 1 else math.nan


def wave_speed(G: float, G_err: float, phi: float, phi_err: float) -> tuple[float, float]:
    """c_s = sqrt(G/(phi rho_p)) (rho_p = 1) and its error, G's and phi's relative errors independent:
    dc/c = sqrt((dG/G)^2 + (dphi/phi)^2)/2."""
    c = math.sqrt(G / phi)
    return c, 0.5 * c * math.hypot(G_err / G, phi_err / phi)


def elasticity(per_seed: list[dict], cfg: Config, cell: ModulusCell, mu_s: float | None = None,
               cost: dict | None = None) -> dict:
    """calibration.json's ``elasticity`` from the seeds' records (``analyse_cell``): G (the smaller amplitude's
    storage modulus) with its standard error over seeds and n - 1 degrees of freedom, G'' likewise, c_s, phi, Z, the
    affine estimate and G/G_aff, and the linearity check (``mu_s``: the calibration's, for the yield strain)."""
    c, dim, n = cfg.contact, cfg.grains.dimension, len(per_seed)
    G, G_err = mean_err([s["G"] for s in per_seed])
    G_loss, G_loss_err = mean_err([s["G_loss"] for s in per_seed])
    phi, phi_err = mean_err([s["phi"] for s in per_seed])
    Z, Z_err = mean_err([s["Z"] for s in per_seed])
    c_s, c_s_err = wave_speed(G, G_err, phi, phi_err)
    affine = [affine_modulus(s["phi"], s["Z"], c.k_n, c.k_t, dim) for s in per_seed]
    G_aff, G_aff_err = mean_err(affine)
    ratio = G / G_aff
    ratio_err = ratio * math.hypot(G_err / G, G_aff_err / G_aff)
    large = [s["amplitudes"][1]["G"] / s["amplitudes"][0]["G"] for s in per_seed]
    r, r_err = mean_err(large)
    small_over_step = cell.amplitudes[0] / (cell.amplitudes[1] - cell.amplitudes[0])
    t95 = float(stats.t.ppf(0.975, n - 1)) if n > 1 else math.nan
    yield_strain = mu_s * cfg.p_w / G if mu_s is not None else None
    gammas = [float(np.mean([s["amplitudes"][k]["gamma_0"] for s in per_seed])) for k in range(len(cell.amplitudes))]
    linearity = {"gamma_0": gammas,
                 "G": [mean_err([s["amplitudes"][k]["G"] for s in per_seed])[0] for k in range(len(gammas))],
                 "G_err": [mean_err([s["amplitudes"][k]["G"] for s in per_seed])[1] for k in range(len(gammas))],
                 "G_loss": [mean_err([s["amplitudes"][k]["G_loss"] for s in per_seed])[0] for k in range(len(gammas))],
                 "ratio": r, "ratio_err": r_err, "z": (r - 1) / r_err if r_err > 0 else math.nan, "t95": t95,
                 "same_within_error": bool(abs(r - 1) <= t95 * r_err) if n > 1 else None,
                 "softening_at_gamma_0": (1 - r) * small_over_step, "softening_at_gamma_0_err": r_err * small_over_step,
                 "yield_strain": yield_strain,
                 "gamma_0_over_yield": [g / yield_strain for g in gammas] if yield_strain else None,
                 "rule": "ratio: G' at the larger amplitude over G' at the smaller, per seed, mean and standard error; "
                         "same within error if |ratio - 1| <= t95 x its standard error (n - 1 degrees of freedom); "
                         "softening_at_gamma_0: the relative drop of G' at the reported gamma_0 if it grows linearly "
                         "with the amplitude (contacts' microslip, Mindlin), (1 - ratio) gamma_0/(gamma_1 - gamma_0); "
                         "yield strain mu_s p/G"}
    return {"G": G, "G_err": G_err, "G_dof": n - 1, "G_loss": G_loss, "G_loss_err": G_loss_err,
            "c_s": c_s, "c_s_err": c_s_err, "phi": phi, "phi_err": phi_err, "Z": Z, "Z_err": Z_err,
            "G_affine": G_aff, "G_affine_err": G_aff_err, "G_over_affine": ratio, "G_over_affine_err": ratio_err,
            "affine": {"formula": f"phi Z (k_n + {AFFINE[dim][1]:g} k_t)/({AFFINE[dim][0]:g} pi d^{dim - 2})",
                       "k_n": c.k_n, "k_t": c.k_t, "source": AFFINE_SOURCE},
            "gamma_0": cell.amplitudes[0], "omega": cell.omega, "period": cell.period,
            "period_over_transit": cell.period * c_s / cfg.calibration.width,
            "normal_coupling": mean_err([s["amplitudes"][0]["normal_coupling"] for s in per_seed])[0],
            "seeds": [s["seed"] for s in per_seed], "per_seed": per_seed, "linearity": linearity,
            "errors": f"mean and standard error over {n} seeds (standard deviation with n - 1 = {n - 1} degrees of "
                      "freedom over sqrt n); c_s's error propagated from G's and phi's",
            "protocol": cell.as_dict(), "cost": cost or {}, "convention": CONVENTION}


# --- figure ---------------------------------------------------------------------------------------------
def modulus_figure(records, path: Path, title: str) -> Path:
    """G and c_s against p (``records``: (p, elasticity) pairs, one per calibration): the measured values with their
    standard errors over seeds, each seed's G, and the affine estimate (c_s's: sqrt(G_aff/phi)); PNG at ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    records = sorted(records, key=lambda r: r[0])
    p = np.array([r[0] for r in records], dtype=float)
    e = [r[1] for r in records]
    fig, (ax_g, ax_c) = plt.subplots(1, 2, figsize=(8.0, 3.6), layout="constrained")
    step = 0.025 * (p.max() if len(p) else 1.0)
    for pk, ek in zip(p, e, strict=True):  # each seed's G beside its point
        seeds = [s["G"] for s in ek["per_seed"]]
        ax_g.plot(pk + step * (1 + np.arange(len(seeds))), seeds, ".", color="0.5", ms=6,
                  label="each seed's G" if pk == p[0] else None)
    ax_g.errorbar(p, [x["G"] for x in e], [x["G_err"] for x in e], fmt="o", color="C0", capsize=4,
                  label="G (oscillatory shear), s.e. over seeds")
    ax_g.errorbar(p, [x["G_affine"] for x in e], [x["G_affine_err"] for x in e], fmt="s", mfc="none", color="C3",
                  capsize=4, label="affine estimate G_aff")
    ax_c.errorbar(p, [x["c_s"] for x in e], [x["c_s_err"] for x in e], fmt="o", color="C0", capsize=4,
                  label="c_s = sqrt(G/(phi rho_p))")
    ax_c.plot(p, [math.sqrt(x["G_affine"] / x["phi"]) for x in e], "s", mfc="none", color="C3",
              label="sqrt(G_aff/(phi rho_p))")
    ax_g.set_ylim(bottom=0)
    ax_c.set_ylim(bottom=0)
    for ax in (ax_g, ax_c):
        ax.set_xlabel(r"normal stress $p$ [$\rho_p g d$]")
        lo, hi = (p.min(), p.max()) if len(p) else (0.0, 1.0)
        pad = max(0.25 * (hi - lo), 0.3 * hi)
        ax.set_xlim(max(0.0, lo - pad), hi + pad)
        # G lies at 0.2-0.3 of G_aff, c_s at about half of the affine speed: the legends fill the gaps
        ax.legend(fontsize=7, loc="center" if ax is ax_g else "lower right")
    ax_g.set_ylabel(r"shear modulus $G$ [$\rho_p g d$]")
    ax_c.set_ylabel(r"shear-wave speed $c_s$ [$\sqrt{g d}$]")
    if e:
        g0 = sorted({x["gamma_0"] for x in e})
        amplitude = f"{g0[0]:.2g}" if len(g0) == 1 else f"{g0[0]:.2g}-{g0[-1]:.2g}"
        transits = sorted(round(x["period_over_transit"]) for x in e)
        period = f"{transits[0]}" if len(transits) == 1 else f"{transits[0]}-{transits[-1]}"
        seeds = sorted({len(x["seeds"]) for x in e})
        title += (f"\ngamma_0 = {e[0]['protocol']['gamma_0_kappa'][0]:g}/kappa ({amplitude}), period {period} transits "
                  f"at c_s, {'/'.join(map(str, seeds))} seeds, errors over seeds ({seeds[0] - 1} dof)")
    fig.suptitle(title, fontsize=9)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return Path(path)
