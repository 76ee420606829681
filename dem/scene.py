"""LAMMPS input scripts of the scene, written as short commented blocks.

Geometry (DEM units): gravity along -y, periodic in x (and z in 3D), shrink-wrapped in y with a
minimum extent (``boundary p m p``) so that no kicked grain is lost.  Atom types: 1 bed grains,
2 base grains (frozen, ``fix freeze``), 3 plate grains (one rigid body, ``fix rigid single``, no
rotation, so the sphere inertia that fix rigid assigns its grains never enters).  The plate grains are
spaced (``plate_pitch``) so that the bed grains nest between them: the plate grips the bed.  2D grains
are integrated as disks (``fix nve/sphere disc``: I = m r^2/2; spheres I = 2 m r^2/5); a drive needs no
``fix enforce2d``: its grains start in the plane at rest along z and every force on them lies in the plane, so
their z components stay exactly zero.  The plate is
loaded by ``fix addforce`` (p_w A downwards; no gravity on the plate, so p_w is exactly the applied
normal stress) and driven either by a constant x force tau_w A (imposed stress) or at a held x
velocity u_w (imposed speed: rigid-body x force switched off).

* ``prepare_script``: random insertion of polydisperse grains in a loose column, fall and settle under
  gravity until the pile has landed and is nearly still (``prepare.settle_ke_per_grain``), freeze the
  bottom grains as a rough base, bring the plate down at PLATE_APPROACH_SPEED, relax under p_w until the
  kinetic energy of the bed and the plate per grain is below ``prepare.ke_per_grain``, write
  ``prepared.restart`` at step 0.
* ``drive_script``: read a restart (the prepared bed or a drive restart when resuming), apply the
  drive, write the outputs, restart files every ``restart`` steps, ``run N upto``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from granstokes.continuum.load import Load

from .contact import grain_mass
from .layout import (
    ATOM_COLUMNS,
    ATOMS,
    BASE,
    BED,
    CONTACT_COLUMNS,
    CONTACTS,
    GRAIN_COLUMNS,
    GRAINS_DUMP,
    N_TYPES,
    PLATE,
    PLATE_COLUMNS,
    PLATE_CSV,
    PREPARED_RESTART,
    PROFILE_BIN,
    RESTART_DIR,
)
from .sizing import DriveSizing, Plan

SKIN = 0.3  # neighbor skin in d
PLATE_DIAMETER = 1.0  # d: the plate's glued grains, bed-like (measured slip: bench/RESULTS.md)
#: the largest grain that fits through a gap of the plate is this fraction of the smallest bed grain:
#: the bed grains nest as deep as they can without one passing through (measured slip: bench/RESULTS.md)
PLATE_GAP_FRACTION = 0.9
#: 3D: the plate's grains along z, this far apart (overlapping ridges across the flow)
PLATE_RIDGE_PITCH = 0.5
#: Coulomb friction of the bed-plate contacts (a rough, gripping plate; bed-bed contacts keep mu_p)
PLATE_FRICTION = 1.0
#: bed grains are binned up to this height above the plate's initial position (nothing is lost above it)
BIN_HEADROOM = 8.0
#: preparation: the plate starts down at this speed (sqrt(g d)), its terminal speed under p_w against the drag
PLATE_APPROACH_SPEED = 4.0


def _lines(*blocks: str) -> str:
    return "\n".join(b.strip("\n") + "\n" for b in blocks)


def _common(plan: Plan) -> str:
    """Settings that restart files do not carry."""
    excl = f"neigh_modify exclude type {BASE} {BASE} exclude type {BASE} {PLATE} exclude type {PLATE} {PLATE}"
    return f"""
# --- neighbours and communication (not stored in restart files) ---
comm_modify vel yes
neighbor {SKIN} bin
neigh_modify delay 0 every 1 check yes
{excl}
timestep {plan.dt:.10g}
"""


def _thermo(every: int, extra: str = "") -> str:
    return f"""
# --- thermo: total (not per-atom) values, stop on lost grains ---
thermo_style custom step v_t c_ke_bed atoms{extra}
thermo {every}
thermo_modify norm no lost error flush yes format float %.8g
"""


def _procs(dim: int) -> str:
    """MPI grid: never split the tall box along y (nor along z in 2D)."""
    return "* 1 1" if dim == 2 else "* 1 *"


def _box(plan: Plan) -> tuple[str, float]:
    cfg, dim = plan.config, plan.dimension
    zw = cfg.width_z or 1.0
    top = plan.box_top
    zlo, zhi = (-0.5, 0.5) if dim == 2 else (0.0, zw)
    text = f"""
# --- units and box: DEM units (d = rho_p = g = 1), gravity along -y ---
units lj
dimension {dim}
boundary p m p
atom_style sphere
processors {_procs(dim)}
region box block 0 {cfg.box.width:.10g} 0 {top} {zlo} {zhi} units box
create_box {N_TYPES} box
"""
    return text, top


def _density(group: str, dim: int) -> str:
    return f"set group {group} density/disc 1.0" if dim == 2 else f"set group {group} density 1.0"


def _enforce(dim: int, after_rigid: bool = False) -> str:
    """2D preparation: keep everything in the plane (re-declared after fix rigid, which must precede it; a drive
    needs none, see the module docstring)."""
    if dim != 2:
        return ""
    return "unfix two_d\nfix two_d all enforce2d" if after_rigid else "fix two_d all enforce2d"


def _loop(phase: str, label: str, n: int, check: int, threshold: float, landed: bool = False) -> str:
    """Run in chunks of ``check`` steps until the kinetic energy per grain is below ``threshold``;
    ``landed``: and below its value at the previous check (a falling pile's energy only grows)."""
    below = f"${{ke_grain}} < {threshold:.10g}"
    start, test, step, end = ("variable ke_previous equal 0.0\n", f"{below} && ${{ke_grain}} < ${{ke_previous}}",
                              "variable ke_previous equal ${ke_grain}\n", "variable ke_previous delete\n") \
        if landed else ("", below, "", "")
    return f"""
print "PHASE {phase}"
{start}variable i loop {n}
label {phase}
run {check}
if "{test}" then "jump SELF {label}"
{step}next i
jump SELF {phase}
label {label}
variable i delete
{end}"""


def _deposit(plan: Plan, seed: int, top: float) -> str:
    w, dim = plan.config.grains.polydispersity, plan.dimension
    return f"""
# --- grains: random insertion in a loose column; diameters uniform by number in [{1 - w:g}, {1 + w:g}] ---
region column block INF INF {1 + w:.10g} {top - (1 + w):.10g} INF INF units box
create_atoms {BED} random {plan.n_grains} {seed} column overlap {1 + w:.10g} maxtry 1000
variable diameter atom {1 - w:.10g}+{2 * w:.10g}*random(0,1,{seed + 7919})
set type {BED} diameter v_diameter
{_density("all", dim)}
group bed type {BED}
group base type {BASE}
group plate type {PLATE}
"""


def _pair(plan: Plan) -> str:
    c = plan.config.contact
    return (f"""
# --- contact law: {c.model}, Coulomb friction mu_p = {c.mu_p:g} (bed-plate {PLATE_FRICTION:g}), """
            f"""restitution e = {c.restitution:g} ---
{_pair_coeffs(plan)}
""")


#: pairs of atom types with their own friction: bed-plate contacts have the plate's PLATE_FRICTION
SPECIAL_PAIRS = ((BED, PLATE, PLATE_FRICTION),)


def _pair_coeffs(plan: Plan) -> str:
    """One contact law for every pair; bed-plate contacts with the plate's friction PLATE_FRICTION."""
    return plan.config.contact.pair_lines(special=SPECIAL_PAIRS)


def _settle(plan: Plan) -> str:
    c, dt = plan.config.contact, plan.dt
    return f"""
# --- settle under gravity on a temporary flat floor ---
variable t equal step*{dt:.10g}
compute ke_bed bed ke
variable ke_grain equal c_ke_bed/count(bed)/{grain_mass(1.0, plan.dimension):.10g}
fix floor all wall/gran {c.wall()} yplane 0.0 NULL
fix gravity bed gravity 1.0 vector 0 -1 0
{integrator("bed", plan.dimension)}
{_enforce(plan.dimension)}
"""


def integrator(group: str, dim: int) -> str:
    """Translation and rotation of free grains: disks in 2D (``disc``: I = m r^2/2), spheres in 3D."""
    return f"fix integrate {group} nve/sphere" + (" disc" if dim == 2 else "")


def _freeze_base(plan: Plan) -> str:
    b = plan.config.box.base_thickness
    return f"""
# --- rough base: grains whose centre lies below {b:g} d are frozen (type {BASE}) ---
region base_region block INF INF INF {b:.10g} INF INF units box
group base_new region base_region
set group base_new type {BASE}
group base_new delete
group bed clear
group bed type {BED}
group base type {BASE}
velocity base set 0.0 0.0 0.0 units box
unfix floor
unfix integrate
unfix gravity
{integrator("bed", plan.dimension)}
fix freeze base freeze
fix gravity bed gravity 1.0 vector 0 -1 0
{_enforce(plan.dimension, after_rigid=True)}
"""


def _place_plate(plan: Plan) -> str:
    dim = plan.dimension
    nx, nz, ax, az = plate_layout(plan)
    atoms = "\n".join(
        f"create_atoms {PLATE} single {(i + 0.5) * ax:.10g} ${{y_plate}} "
        f"{0.0 if dim == 2 else (k + 0.5) * az:.10g} units box"
        for k in range(nz) for i in range(nx))
    return (f"""
# --- plate: {nx * nz} unit grains {ax:.4g} d apart (a {'row' if dim == 2 else 'ridges along z'}) glued into """
            f"""one rigid body just above the highest grain ---
variable top_atom atom y+radius
compute top bed reduce max v_top_atom
thermo_style custom step v_t c_ke_bed atoms c_top
run 0
variable y_plate equal $(c_top+{plan.config.prepare.plate_gap + PLATE_DIAMETER / 2:.10g})
{atoms}
group plate type {PLATE}
set group plate diameter {PLATE_DIAMETER:g}
{_density("plate", dim)}
velocity plate set 0.0 {-PLATE_APPROACH_SPEED:g} 0.0 units box
""")


def _load_plate(plan: Plan) -> str:
    cfg, area, n = plan.config, plan.area, plate_grains(plan)
    return (f"""
# --- load: p_w = {cfg.p_w:g} on the plate (area {area:g}), y motion only, viscous drag (terminal speed """
            f"""{PLATE_APPROACH_SPEED:g}) while relaxing; the kinetic energy per grain counts the plate's from here ---
fix plate plate rigid single force * off on off torque * off off off
fix load plate addforce 0.0 {-cfg.p_w * area / n:.10g} 0.0
fix plate_drag plate viscous {cfg.p_w * area / (n * PLATE_APPROACH_SPEED):.10g}
{_enforce(plan.dimension, after_rigid=True)}
variable plate_y equal f_plate[1][2]
compute ke_plate plate ke
variable ke_grain equal (c_ke_bed+c_ke_plate)/count(bed)/{grain_mass(1.0, plan.dimension):.10g}
""")


def _save_prepared() -> str:
    return f"""
# --- save the prepared bed at step 0 and the per-grain table (radius, mass) ---
unfix plate_drag
reset_timestep 0
write_restart {PREPARED_RESTART}
write_dump all custom {GRAINS_DUMP} {" ".join(GRAIN_COLUMNS)} modify sort id
"""


def prepare_script(plan: Plan, seed: int) -> str:
    """Deposit, fall and settle, freeze the base, load the plate, relax; writes prepared.restart."""
    c, check = plan.config.prepare, plan.intervals["check"]
    box, top = _box(plan)
    n_settle = max(1, math.ceil(plan.settle_steps_max / check))
    n_relax = max(1, math.ceil(c.relax_max / (check * plan.dt)))
    return _lines(
        f"# prepare bed: seed {seed}; generated by dem.scene",
        box, _deposit(plan, seed, top), _pair(plan), _common(plan), _settle(plan),
        _thermo(plan.intervals["thermo"]),
        _loop("settle", "settled", n_settle, check, c.settle_ke_per_grain, landed=True),
        _freeze_base(plan), _place_plate(plan), _load_plate(plan),
        _thermo(plan.intervals["thermo"], " v_plate_y"),
        _loop("relax", "relaxed", n_relax, check, c.ke_per_grain)
        + 'print "PHASE relaxed ke_grain=${ke_grain} plate_y=${plate_y}"\n',
        _save_prepared(),
    )


def _read_state(plan: Plan, restart: str) -> str:
    return f"""
# --- state: prepared bed or last drive restart; the processor grid must precede read_restart (the
#     tall box is never split along y); the contact law's coefficients are not in restart files
#     (dem.contact.Contact.restart_lines: the contact history comes back with the restart) ---
processors {_procs(plan.dimension)}
read_restart {restart}
{plan.config.contact.restart_lines(SPECIAL_PAIRS)}
"""


#: an oscillating speed drive's plate: its x velocity error decays on this many time steps (the tracking force's
#: feedback; the imposed acceleration does the tracking, the feedback only removes the integrator's round-off)
TRACKING_STEPS = 100


@dataclass(frozen=True)
class PlateForce:
    """How the plate is driven in LAMMPS: the description, fix rigid's force flags, fix addforce's x force per plate
    grain (a number or a variable), the variables it needs and the x velocity set at the drive's start."""

    what: str
    flags: str
    fx: str
    tracking: str = ""
    set_speed: str = ""


def _held_stress(plan: Plan, load: Load, fresh: bool) -> PlateForce:
    """An imposed stress: x force tau_w A spread over the plate's grains."""
    return PlateForce(f"imposed stress: x force tau_w A = {load.tau_w * plan.area:.6g} (tau_w = {load.tau_w:.6g})",
                      "force * on on off", f"{load.tau_w * plan.area / plate_grains(plan):.10g}")


def _sine_stress(plan: Plan, load: Load, fresh: bool) -> PlateForce:
    """An oscillating stress: x force tau_w A sin(omega t)."""
    fx = load.tau_w * plan.area / plate_grains(plan)
    return PlateForce(f"oscillating stress: x force tau_w A sin(omega t), tau_w = {load.tau_w:.6g}, "
                      f"omega = {load.omega:.6g}", "force * on on off", "v_fx_plate",
                      f"variable fx_plate equal {fx:.10g}*sin({load.omega:.10g}*step*{plan.dt:.10g})")


def _held_speed(plan: Plan, load: Load, fresh: bool) -> PlateForce:
    """A held speed: the rigid body's x force off, its x velocity set to u_w once (a fresh drive)."""
    return PlateForce(f"imposed speed: plate x velocity held at u_w = {load.u_w:.6g} (rigid-body x force off)",
                      "force * off on off", f"{0.0:.10g}",
                      set_speed=f"velocity plate set {load.u_w:.10g} NULL NULL units box" if fresh else "")


def _sine_speed(plan: Plan, load: Load, fresh: bool) -> PlateForce:
    """An oscillating speed: the tracking force M du_w/dt minus the bed's pull on the plate (compute plate_pull,
    summed before the load is added) plus a feedback over TRACKING_STEPS steps, so that the rigid plate moves at
    u_w(t) = u_w sin(omega t)."""
    mass, dt, w = plate_geometry(plan)["mass"], plan.dt, load.omega
    arg, half = f"{w:.10g}*step*{dt:.10g}", f"{w:.10g}*(step-0.5)*{dt:.10g}"
    tracking = f"""compute plate_pull plate reduce sum fx
variable fx_plate equal ({mass * load.u_w * w:.10g}*cos({arg})-c_plate_pull-{mass:.10g}*(f_plate[1][4]-\
{load.u_w:.10g}*sin({half}))/{TRACKING_STEPS * dt:.10g})/{plate_grains(plan)}"""
    return PlateForce(f"oscillating speed: plate x velocity u_w sin(omega t), u_w = {load.u_w:.6g}, omega = "
                      f"{w:.6g} (tracking force)", "force * on on off", "v_fx_plate", tracking)


#: the plate's drive by (load kind, whether it oscillates)
PLATE_FORCES = {("stress", False): _held_stress, ("stress", True): _sine_stress, ("speed", False): _held_speed,
                ("speed", True): _sine_speed}


def _drive_forces(plan: Plan, drive: DriveSizing, fresh: bool) -> tuple[str, str]:
    """(description, integration block) of a drive: the plate's force (PLATE_FORCES), its weight p_w A, gravity on
    the bed, the base frozen."""
    load = drive.load
    force = PLATE_FORCES[(load.kind, load.oscillating)](plan, load, fresh)
    fy = f"{-plan.config.p_w * plan.area / plate_grains(plan):.10g}"
    what, flags, fx, tracking, set_speed = force.what, force.flags, force.fx, force.tracking, force.set_speed
    dt = plan.dt
    block = f"""
# --- integration: bed grains free, base frozen, plate rigid without rotation ---
variable t equal step*{dt:.10g}
compute ke_bed bed ke
{integrator("bed", plan.dimension)}
fix freeze base freeze
fix gravity bed gravity 1.0 vector 0 -1 0
{set_speed}
fix plate plate rigid single {flags} torque * off off off
{tracking}
fix load plate addforce {fx} {fy} 0.0
"""
    return what, block


def _plate_output(plan: Plan) -> str:
    area, every, sample = plan.area, plan.intervals["plate"], plan.intervals["sample"]
    fmt = ",".join(f"$({v})" for v in ("step", "v_t:%.8g", "v_px:%.10g", "v_py:%.10g", *(
        f"v_out_{k}:%.8g" for k in ("ux", "uy", "fx", "fy", "uc", "nc"))))
    # the sampled values: fix ave/time reads computes and fixes directly (only the rigid body's array needs a
    # variable); the force's interval means are divided by the plate's area at output
    sampled = (("ux", "v_pux"), ("uy", "v_puy"), ("fx", "f_load[1]"), ("fy", "f_load[2]"), ("sc", "c_touch_sums[1]"),
               ("nc", "c_touch_sums[2]"))
    mean = {k: f"(step>0)*f_plate_mean[{i + 1}]+(step==0)*{ref}" for i, (k, ref) in enumerate(sampled)}
    averaged = "\n".join(f"variable out_{k} equal " + (f"({m})/{area:.10g}" if k in ("fx", "fy") else m)
                          for k, m in mean.items())
    return f"""
# --- plate time series: unwrapped x and y at the output step; velocity and force of the bed on the
#     plate per area (the plate grains' forces summed before the load is added: fix addforce's vector)
#     averaged over the output interval, sampled every {sample} steps (fix ave/time); u_c, n_c: x velocity
#     (sum over the samples / count) and mean number of the bed grains touching a plate grain (slip).
#     Row 0: the prepared state ---
variable px equal f_plate[1][1]+f_plate[1][13]*lx
variable py equal f_plate[1][2]
variable pux equal f_plate[1][4]
variable puy equal f_plate[1][5]
compute touching bed contact/atom plate
variable touch atom c_touching>0
variable touch_vx atom v_touch*vx
compute touch_sums bed reduce sum v_touch_vx v_touch
fix plate_mean all ave/time {sample} {every // sample} {every} {" ".join(ref for _, ref in sampled)}
{averaged}
variable out_uc equal v_out_sc/(v_out_nc+(v_out_nc==0))
fix plate_out all print {every} "{fmt}" file {PLATE_CSV} screen no title "{",".join(PLATE_COLUMNS)}"
"""


def _dumps(plan: Plan, drive: DriveSizing, fresh: bool) -> str:
    iv = plan.intervals
    names = " ".join(f"colname {i + 1} {n}" for i, n in enumerate(CONTACT_COLUMNS))
    early = "" if not iv["early"] else f"""
# every {iv["atoms_early"]} steps until step {iv["early"]} (the layer's growth), then every {iv["atoms"]}
variable atoms_next equal stride2(0,{max(drive.steps, iv["early"])},{iv["atoms"]},0,{iv["early"]},{iv["atoms_early"]})
dump_modify atoms every v_atoms_next first {"yes" if fresh else "no"}"""
    return f"""
# --- per-atom snapshots (LAMMPS text dump) and contacts (pair/local: pairs closer than r_i + r_j) ---
dump atoms all custom {iv["atoms"]} {ATOMS} {" ".join(ATOM_COLUMNS)}
dump_modify atoms sort id format float %.8g{early}
compute pair_ids all property/local patom1 patom2 cutoff radius
compute pair_forces all pair/local dist dx dy dz force p1 p2 p3 cutoff radius
dump contacts all local {iv["contacts"]} {CONTACTS} c_pair_ids[1] c_pair_ids[2] c_pair_forces[*]
dump_modify contacts format float %.8g {names}
"""


def _profiles_output(plan: Plan) -> str:
    iv = plan.intervals
    nrep = iv["profiles"] // iv["plate"]
    ybound = plan.depth + plan.config.box.base_thickness + BIN_HEADROOM
    vol = "PI*radius^2" if plan.dimension == 2 else "4.0/3.0*PI*radius^3"
    return (f"""
# --- depth profiles of the bed grains in {PROFILE_BIN:g} d bins (per-atom averages; times density/number gives
#     per-volume values): number density, grain volume, vx, contact stress (virial), and the contact
#     force on the grains (f + m g), whose sum over the grains above a plane is the force through it ---
compute bins bed chunk/atom bin/1d y 0.0 {PROFILE_BIN:g} bound y 0.0 {ybound:.10g} units box discard yes
compute stress bed stress/atom NULL pair
variable volume atom {vol}
variable contact_fy atom fy+mass
fix profiles bed ave/chunk {iv["plate"]} {nrep} {iv["profiles"]} bins density/number v_volume vx """
            """c_stress[1] c_stress[2] c_stress[3] c_stress[4] fx v_contact_fy file profiles.txt
""")


def drive_script(plan: Plan, drive: DriveSizing, restart: str, fresh: bool, outputs: bool = True) -> str:
    """Drive phase from ``restart``; ``fresh`` sets the plate speed of a speed drive (not when resuming);
    ``outputs=False`` gives the bare run used to measure the harness overhead."""
    iv = plan.intervals
    what, forces = _drive_forces(plan, drive, fresh)
    blocks = [f"# drive {drive.drive.name}: {what}; generated by dem.scene", _read_state(plan, restart),
              _common(plan), forces]
    if outputs:
        blocks += [_plate_output(plan), _dumps(plan, drive, fresh), _profiles_output(plan), f"""
# --- restart files every {iv["restart"]} steps (granular pair styles do not restart bit-exactly) ---
restart {iv["restart"]} ../../{RESTART_DIR}/drive.*.restart
"""]
    blocks.append(_thermo(iv["thermo"] if outputs else drive.steps, " f_plate[1][4]" if outputs else ""))
    blocks.append(f"""
print "PHASE drive"
run {drive.steps} upto
""")
    return _lines(*blocks)


def plate_pitch(dim: int, d_min: float) -> float:
    """Largest x spacing of the plate grains at which the largest grain fitting through a gap is
    PLATE_GAP_FRACTION of the smallest bed grain ``d_min``: 2D, the gap between neighbours; 3D, ridges
    along z (grains PLATE_RIDGE_PITCH apart, overlapping: one rigid body) whose rectangular holes have a
    half-diagonal of (D_p + f d_min)/2.  The grooves between the ridges hold the bed grains against the
    flow as the 2D gaps do (a square lattice of holes holds them 20 % slower than the plate)."""
    opening = PLATE_DIAMETER + PLATE_GAP_FRACTION * d_min
    return opening if dim == 2 else math.sqrt(opening ** 2 - PLATE_RIDGE_PITCH ** 2)


def plate_layout(plan: Plan) -> tuple[int, int, float, float]:
    """Plate grains per direction (x, z) and their spacings (<= the pitches, fitting the periodic box)."""
    pitch = plate_pitch(plan.dimension, 1.0 - plan.config.grains.polydispersity)
    nx = math.ceil(plan.config.box.width / pitch)
    zw = plan.config.width_z or 1.0
    nz = 1 if plan.dimension == 2 else math.ceil(zw / PLATE_RIDGE_PITCH)
    return nx, nz, plan.config.box.width / nx, zw / nz


def plate_grains(plan: Plan) -> int:
    nx, nz, _, _ = plate_layout(plan)
    return nx * nz


def nesting_depth(plan: Plan) -> float:
    """How far below the plate grains' centres a unit bed grain resting in a gap of the plate sits:
    it touches the two (2D) or four (3D) plate grains around the gap at centre distance (D_p + 1)/2."""
    _, _, ax, az = plate_layout(plan)
    half = ax / 2 if plan.dimension == 2 else math.hypot(ax, az) / 2
    return math.sqrt(max(0.0, ((PLATE_DIAMETER + 1) / 2) ** 2 - half ** 2))


def plate_geometry(plan: Plan) -> dict:
    """The plate as run.json records it: grains, spacing, mass (per area), area, and ``surface_offset``,
    the height of its centre of mass above its contact plane (dem.layout.plate_surface).  The contact
    plane is where a flat wall would hold the first bed layer at the height this plate holds it: half
    a grain above the centre of a unit grain nested in a gap."""
    nx, nz, ax, az = plate_layout(plan)
    n = plate_grains(plan)
    mass = n * grain_mass(PLATE_DIAMETER, plan.dimension)
    nest = nesting_depth(plan)
    return {"grains": n, "layout": [nx, nz], "spacing": [ax, az] if plan.dimension == 3 else [ax],
            "grain_diameter": PLATE_DIAMETER, "gap_fraction": PLATE_GAP_FRACTION, "friction": PLATE_FRICTION,
            "nesting_depth": nest, "mass": mass, "mass_per_area": mass / plan.area, "area": plan.area,
            "surface_offset": nest - 0.5,
            "design": "one rigid body of unit grains spaced so that the largest grain fitting through a gap is "
                      f"{PLATE_GAP_FRACTION:g} of the smallest bed grain (2D row; 3D ridges along z); unit bed "
                      "grains nest nesting_depth below the plate grains' centres; bed-plate contacts have Coulomb "
                      "friction `friction`"}
