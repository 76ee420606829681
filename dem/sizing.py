"""Scene sizing from the continuum prediction (continuum.scales): depth, grain count, durations, steps.

* bed depth (base top to plate) >= max over drives of delta_s + margin (default ``clearance``, at which the
  observables were measured independent of the depth), unless the config gives it; the sizing is as good as the config's
  material (``dem run --calibration`` puts a calibration's there);
* duration of a drive = duration_ts * t_s (default 10 t_s, t_s = delta_s^2/nu_g), unless given;
* a speed drive with mu_w_tilde runs at the matching steady speed u_w = U u~_w^inf(mu_w) (the paper's
  u~_w); a stress drive with tau_w has mu_w = tau_w/p_w;
* an oscillating drive (Stokes' second problem) imposes that value as the amplitude of a sine at omega (given, or
  omega_ts/t_s) and runs ``cycles`` periods (``duration`` overrides), its depth sized from the amplitude's delta_s.
Every choice is written into run.json with its reason.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass

from granstokes.continuum.load import Load
from granstokes.continuum.scales import Material, Scales
from granstokes.continuum.steady import steady_wall_speed

from granstokes.lib.validate import require

from .config import Config, Drive
from .contact import grain_volume, mean_grain_volume
from .estimate import Estimate, duration_text
from .layout import stage_key
from .outputs import CONTACTS_PER_GRAIN, PREPARE_LOG_BYTES, PROFILE_EXTRA_BINS, ROW_BYTES
from .throughput import Throughput, measured

#: packing fractions used to turn a bed depth into a grain count (random close packing, loose side)
PACKING = {2: 0.80, 3: 0.60}
#: LAMMPS counts the steps of a run in a 32-bit integer ("Invalid run command N value" above it)
MAX_STEPS = 2**31 - 1
#: preparation's expected settling and relaxation after a grain's fall from the top of the box, in time units
#: sqrt(d/g): the mean over the beds of the shipped presets' seeds (1.8 to 7.9, bench/dem_prepare.py; settling
#: ends about one time unit before that fall, relaxing takes the rest; each stage ends on its own convergence,
#: capped by prepare.settle_max and relax_max)
SETTLE_RELAX_EXPECTED = 3.5
#: settling (which begins with the fall) is capped at this many free falls plus prepare.settle_max
FALL_MARGIN = 1.5
#: plate statistics (force, speed, slip) are sampled this many times per contact time t_c
SAMPLES_PER_CONTACT = 2
#: a run's or a calibration's fixed wall time in seconds: start-up, the LAMMPS library query, the merges
OVERHEAD = 1.0


def drive_scales(cfg: Config, drive: Drive) -> Scales:
    """The paper's scales of a drive (mu_w from mu_w, mu_w_tilde or tau_w, or from the imposed speed)."""
    m, fr = cfg.material, cfg.material.friction
    if drive.u_w is not None:
        return Scales.for_speed(m, cfg.p_w, drive.u_w)
    mu_w = (fr.mu_w_from_tilde(drive.mu_w_tilde) if drive.mu_w_tilde is not None
            else drive.tau_w / cfg.p_w if drive.tau_w is not None else drive.mu_w)
    return Scales(m, cfg.p_w, mu_w)


#: the clearance a bed leaves between the calibrated delta_s and the base, in units of delta_s (of DEPTH_STUDY_DELTA_S
#: where delta_s is smaller: ``clearance``): the shallowest clearance of the depth study (bench/creep_depth.py: one 2D
#: drive, delta_s = 10.58 d, beds 26-78 d deep, clearances 1.46-6.4 delta_s, two beds each), at which the plate's
#: steady speed, t90, the steady layer and the creep length agree with the deepest bed's within their errors; the
#: comparison's depth rule (compare.scorecard.short_bed) and the sizing's margin
BASE_CLEARANCE, DEPTH_STUDY_DELTA_S = 1.45, 10.58


def clearance(delta_s: float) -> float:
    """The clearance in d below the layer ``delta_s``: BASE_CLEARANCE delta_s, and no less than at the delta_s it was
    measured at (whether it scales with delta_s or is a number of grains is not measured: the stricter)."""
    return BASE_CLEARANCE * max(delta_s, DEPTH_STUDY_DELTA_S)


#: grain placement: insertion column filled to this fraction of the largest grain's volume
INSERT_FRACTION = {2: 0.30, 3: 0.20}


def _omega(drive: Drive, s: Scales) -> float:
    """A drive's angular frequency: its omega, or its omega_ts over t_s of its load's scales ``s`` (0: held)."""
    if drive.omega is not None:
        return drive.omega
    return drive.omega_ts / s.t_s if drive.omega_ts is not None else 0.0


def _duration(drive: Drive, s: Scales) -> tuple[float, str]:
    """A drive's length and why: given, ``cycles`` periods of its sine, or ``duration_ts`` t_s of its load's scales
    ``s`` (each at least ``min_duration``)."""
    omega = _omega(drive, s)
    if drive.duration is not None:
        return drive.duration, "given"
    if omega:
        return (max(drive.cycles * 2 * math.pi / omega, drive.min_duration),
                f"max({drive.cycles:g} periods of omega = {omega:.4g}, min_duration {drive.min_duration:g})")
    return (max(drive.duration_ts * s.t_s, drive.min_duration),
            f"max({drive.duration_ts:g} t_s, min_duration {drive.min_duration:g}), t_s = {s.t_s:.4g}")


@dataclass(frozen=True)
class DriveSizing:
    """One drive as sized: the configured drive, the paper's scales of its load, its duration and steps; what the
    plate imposes (``load``) and why (``reason``) follow from them.  run.json records it (``as_record``) and
    ``sized_drives`` reads it back."""

    drive: Drive
    scales: Scales
    duration: float
    steps: int

    @property
    def load(self) -> Load:
        """What the plate imposes: the drive's own tau_w or u_w if it gives one, else the stress mu_w of its scales or
        the steady speed of that mu_w (the paper's u~_w); a sine at the drive's omega if it oscillates."""
        d, s, omega = self.drive, self.scales, _omega(self.drive, self.scales)
        if d.kind == "stress":
            return Load("stress", s.p_w, mu_w=d.tau_w / s.p_w if d.tau_w is not None else s.mu_w, omega=omega)
        u_w = d.u_w if d.u_w is not None else s.U * steady_wall_speed(s.material.friction, s.mu_w)
        return Load("speed", s.p_w, u_w=u_w, omega=omega)

    @property
    def reason(self) -> str:
        """The sizing's line for the drive: its scales, its duration and why, what the plate imposes."""
        d, s, load = self.drive, self.scales, self.load
        return (f"drive {d.name}: mu_w = {s.mu_w:.4g} (mu~_w = {s.mu_w_tilde:.3g}), delta_s = {s.delta_s:.3g} d, "
                f"t_s = {s.t_s:.3g}, U = {s.U:.3g}; duration {self.duration:.4g} ({_duration(d, s)[1]}); "
                + (f"tau_w = {load.tau_w:.4g}" if d.kind == "stress" else f"u_w = {load.u_w:.4g}")
                + (f" x sin(omega t), omega = {load.omega:.4g} (omega t_s = {load.omega * s.t_s:.3g})"
                   if load.omega else ""))

    def as_record(self) -> dict:
        """run.json's record of the drive: its name, load (continuum.load.Load.as_record), duration, steps, the
        paper's scales expected of it and the reason."""
        return {"name": self.drive.name, **self.load.as_record(), "duration": self.duration, "steps": self.steps,
                "expected": self.scales.as_dict(), "reason": self.reason}

    @classmethod
    def from_record(cls, record: dict, material: Material, p_w: float) -> DriveSizing:
        """The drive of a run.json record (``as_record``) of a scene of ``material`` at ``p_w``, as it ran: its load
        in DEM units (tau_w or u_w, omega) and its duration given."""
        omega = float(record.get("omega", 0.0))
        drive = Drive(record["name"], record["kind"], tau_w=record.get("tau_w"), u_w=record.get("u_w"),
                      duration=float(record["duration"]), omega=omega or None)
        return cls(drive, Scales(material, p_w, float(record["expected"]["mu_w"])), drive.duration,
                   int(record["steps"]))


def sized_drives(meta: dict) -> tuple[DriveSizing, ...]:
    """The drives of a run folder's run.json record ``meta`` as sized (none before the run is sized)."""
    config = meta.get("config", {})
    return tuple(DriveSizing.from_record(d, Material(**config["material"]), float(config["p_w"]))
                 for d in meta.get("sizing", {}).get("drives", []))


@dataclass(frozen=True)
class Plan:
    """Everything the scene writer and the runner need, derived once from a validated Config."""

    config: Config
    depth: float
    n_grains: int
    dt: float
    intervals: dict  # output name -> steps
    drives: tuple[DriveSizing, ...]
    reasons: tuple[str, ...]

    @property
    def dimension(self) -> int:
        return self.config.grains.dimension

    @property
    def area(self) -> float:
        """Plate area (2D: its length) in d^(D-1)."""
        return self.config.box.width * (self.config.width_z or 1.0)

    @property
    def transit_time(self) -> float:
        """Shear-wave transit time over the bed depth (dem.contact: c_s = d sqrt(k_t/m))."""
        return self.depth / self.config.contact.shear_wave_speed

    @property
    def box_top(self) -> int:
        """Height of the box: the grains inserted loosely (INSERT_FRACTION) over the width, plus two grains."""
        cfg, dim = self.config, self.dimension
        dmax = 1.0 + cfg.grains.polydispersity
        column = self.n_grains * grain_volume(dmax, dim) / (INSERT_FRACTION[dim] * cfg.box.width * (cfg.width_z or 1.0))
        return math.ceil(column + 2 * dmax)

    @property
    def free_fall_steps(self) -> int:
        """Steps for a grain to fall from the top of the box to its floor."""
        return math.ceil(math.sqrt(2 * self.box_top) / self.dt)

    @property
    def settle_steps_max(self) -> int:
        """Settling's cap: FALL_MARGIN free falls, then ``prepare.settle_max``."""
        return math.ceil(FALL_MARGIN * self.free_fall_steps + self.config.prepare.settle_max / self.dt)

    @property
    def prepare_steps(self) -> tuple[int, int]:
        """A preparation's expected and largest number of steps: the fall, then settling and relaxing
        (SETTLE_RELAX_EXPECTED), each stage ending on its own convergence or at its cap."""
        c = self.config.prepare
        fall = self.free_fall_steps
        expected = fall + round(min(SETTLE_RELAX_EXPECTED, c.settle_max + c.relax_max) / self.dt)
        return expected, self.settle_steps_max + round(c.relax_max / self.dt)

    def atom_frames(self, drive: DriveSizing) -> int:
        """Atom snapshots of ``drive``: every ``atoms`` steps from step 0, and every ``atoms_early`` over the
        first ``early`` steps."""
        iv = self.intervals
        early = min(iv["early"], drive.steps)
        return drive.steps // iv["atoms"] + 1 + early // iv["atoms_early"] - early // iv["atoms"]

    def stage_seconds(self, key: str, speed: Throughput | None = None) -> float:
        """Expected LAMMPS wall time of one stage (dem.layout.stage_key) run alone at one rank, at ``speed``
        (default: this machine's, dem.throughput.measured)."""
        speed = speed or measured()
        drive = key.partition("/")[2]
        if not drive:
            return self.n_grains * self.prepare_steps[0] / speed.rate(self.dimension, "prepare")
        steps = next(d.steps for d in self.drives if d.drive.name == drive)
        return self.n_grains * steps / speed.rate(self.dimension, "drive")

    def stage_bytes(self, key: str) -> float:
        """Bytes one stage (dem.layout.stage_key) writes: the prepared bed and its log, or a drive's dumps,
        profiles, plate record, log and last restart (dem.outputs.ROW_BYTES)."""
        dim, n, iv, row = self.dimension, self.n_grains, self.intervals, ROW_BYTES
        drive = key.partition("/")[2]
        if not drive:
            return n * (row["restart"] + row["grain"]) + PREPARE_LOG_BYTES  # prepared.restart, grains.csv, its log
        d = next(d for d in self.drives if d.drive.name == drive)
        return (self.atom_frames(d) * n * row["atom"][dim]
                + (d.steps // iv["contacts"] + 1) * n * CONTACTS_PER_GRAIN[dim] * row["contact"][dim]
                + d.steps // iv["profiles"] * (self.depth + PROFILE_EXTRA_BINS) * row["profile"][dim]
                + (d.steps // iv["plate"] + 1) * row["plate"] + d.steps // iv["thermo"] * row["thermo"]
                + n * row["restart"])

    def estimate(self, jobs: int = 1, np_: int | None = None, done=(), speed: Throughput | None = None) -> Estimate:
        """The run's wall time (``cost_seconds``) and the bytes of its stages (what is left: not in ``done``)."""
        disk = sum(self.stage_bytes(k) for seed in self.config.seeds for k in self.stage_keys(seed) if k not in done)
        return Estimate().plus("beds", self.cost_seconds(jobs, np_, done, speed), disk)

    def stage_keys(self, seed: int) -> list[str]:
        """run.json's keys of a seed's stages in the order they run: the preparation, then each drive."""
        return [stage_key(seed)] + [stage_key(seed, d.drive.name) for d in self.drives]

    def ranks(self, jobs: int, np_: int | None = None) -> int:
        """MPI ranks of each bed with ``jobs`` beds at a time (ranks_per_bed; ``np_``: the user's --np)."""
        return ranks_per_bed(self.n_grains, self.dimension, min(jobs, len(self.config.seeds)), np_)

    def cost_seconds(self, jobs: int = 1, np_: int | None = None, done=(), speed: Throughput | None = None) -> float:
        """Expected wall time of the run (or of what is left: ``done`` holds the complete stages' keys):
        each seed's bed is one unit of work on ``ranks`` ranks (its modelled ``speedup``), ``jobs`` of them at a
        time, longest first."""
        speed = speed or measured()
        np_ = self.ranks(jobs, np_)
        gain = speedup(self.n_grains, self.dimension, np_)
        beds = [sum(self.stage_seconds(k, speed) for k in self.stage_keys(seed) if k not in done) / gain
                for seed in self.config.seeds]
        return OVERHEAD + makespan(sorted([b for b in beds if b > 0], reverse=True), jobs, np_,
                                   contention=speed.contention)

    def cost_estimate(self, jobs: int = 1, np_: int | None = None, done=(), speed: Throughput | None = None) -> str:
        """One line: the run's size and its expected wall time on this machine (``cost_seconds``)."""
        speed = speed or measured()
        np_ = self.ranks(jobs, np_)
        expected, most = self.prepare_steps
        if all(k in done for seed in self.config.seeds for k in self.stage_keys(seed)):
            return "cost: none, every stage is complete"
        left = " of what is left" if done else ""
        return (f"cost: {self.n_grains} grains x {len(self.config.seeds)} bed(s), each preparing ~{count(expected)} "
                f"steps (at most {count(most)}) and driving {count(sum(d.steps for d in self.drives))}; about "
                f"{duration_text(self.cost_seconds(jobs, np_, done, speed))}{left} with {jobs} job(s) x {np_} rank(s) "
                f"(one process alone at one rank: {speed.describe(self.dimension)})")

    def as_dict(self) -> dict:
        return {"depth": self.depth, "n_grains_target": self.n_grains, "width": self.config.box.width,
                "elastic_start": {"shear_wave_speed": self.config.contact.shear_wave_speed,
                                  "transit_time": self.transit_time,
                                  "derivation": "depth / c_s, c_s = d sqrt(k_t/m) with m a mean grain's mass: the "
                                                "time the shear load takes to reach the base through the elastic "
                                                "deposited bed"},
                "width_z": self.config.width_z, "plate_area": self.area, "dt": self.dt,
                "intervals_steps": self.intervals, "drives": [d.as_record() for d in self.drives],
                "reasons": list(self.reasons)}


def size_drive(cfg: Config, drive: Drive) -> DriveSizing:
    """One drive of ``cfg`` sized: its scales (ValueError naming the drive when its load is outside mu(I)'s range),
    its duration and steps."""
    try:
        s = drive_scales(cfg, drive)
    except ValueError as exc:
        raise ValueError(f"drive[{drive.name}]: {exc}") from None
    duration, dt = _duration(drive, s)[0], cfg.time_step
    steps = max(1, round(duration / dt))
    require(steps <= MAX_STEPS, f"drive[{drive.name}] duration", f"at most {MAX_STEPS * dt:.4g} time units "
            f"({MAX_STEPS} steps of dt = {dt:.4g}, LAMMPS's limit)", duration)
    return DriveSizing(drive, s, duration, steps)


def plan(cfg: Config) -> Plan:
    """Size the scene; raises ValueError (naming the drive) when a load is outside mu(I)'s range."""
    dt = cfg.time_step
    c = cfg.contact
    reasons = [*cfg.describe(), f"dt = {dt:.4g} ({'given' if cfg.dt else 'default'}; bound t_c/20 = {c.dt_max:.4g}, "
               f"t_c = {c.t_c:.4g}, k_n = {c.k_n:.4g} from kappa = {c.kappa:g})"]
    drives = tuple(size_drive(cfg, d) for d in cfg.drives)
    reasons += [d.reason for d in drives]
    delta_max = max(p.scales.delta_s for p in drives)
    if cfg.box.depth is not None:
        depth = cfg.box.depth
        reasons.append(f"depth {depth:g} d (given; largest delta_s = {delta_max:.3g} d)")
    else:
        margin, why = ((cfg.box.margin, "given") if cfg.box.margin is not None else
                       (clearance(delta_max),
                        f"{BASE_CLEARANCE:g} x max(delta_s, {DEPTH_STUDY_DELTA_S:g} d), the layer clear of the base"))
        depth = math.ceil(delta_max + margin)
        reasons.append(f"depth {depth:g} d = ceil(largest delta_s {delta_max:.3g} d + margin {margin:g} d, {why})")
    dim = cfg.grains.dimension
    mean_volume = mean_grain_volume(cfg.grains.polydispersity, dim)
    total = (depth + cfg.box.base_thickness) * cfg.box.width * (cfg.width_z or 1.0)
    n_grains = max(1, round(PACKING[dim] * total / mean_volume))
    reasons.append(f"{n_grains} grains fill base ({cfg.box.base_thickness:g} d) + bed at packing {PACKING[dim]}; "
                   f"width {cfg.box.width:g} d (minimum 8 d)" + (f", width_z {cfg.width_z:g} d" if cfg.width_z else ""))
    # the plate's force, speed and slip are sampled every half contact time: a contact's force is resolved,
    # and the per-step evaluation of contact/atom over the bed is not paid for (tests/dem: unbiased)
    sample = max(1, round(cfg.contact.t_c / SAMPLES_PER_CONTACT / dt))
    plate_steps = max(1, round(cfg.output.plate / dt / sample)) * sample
    intervals = {k: max(1, round(getattr(cfg.output, k) / dt / plate_steps)) * plate_steps
                 for k in ("plate", "thermo", "atoms", "contacts", "profiles")}
    # contact snapshots coincide with atom snapshots (plane stresses need the positions)
    intervals["contacts"] = max(1, round(intervals["contacts"] / intervals["atoms"])) * intervals["atoms"]
    intervals.update(_early(cfg.output, dt, intervals["atoms"], plate_steps))
    # restarts fall on profile-window boundaries so that a resumed run loses no averaging window
    intervals["restart"] = max(1, round(cfg.output.restart / dt / intervals["profiles"])) * intervals["profiles"]
    intervals["check"] = max(1, round(cfg.prepare.check_every / dt))
    intervals["sample"] = sample
    return Plan(cfg, float(depth), n_grains, dt, intervals, drives, tuple(reasons))


def _early(out, dt: float, atoms: int, plate_steps: int) -> dict:
    """The early atom snapshots in steps: ``early`` (a multiple of the atoms interval, 0: none) and
    ``atoms_early`` (plate steps times the divisor of atoms/plate_steps nearest the requested interval)."""
    n = atoms // plate_steps
    k = min((k for k in range(1, n + 1) if n % k == 0), key=lambda k: abs(k * plate_steps * dt - out.atoms_early))
    return {"early": round(out.early / dt / atoms) * atoms, "atoms_early": k * plate_steps}


#: grains at which a bed runs as fast on two MPI ranks as on one (each rank's halved work plus the halo
#: exchange), per dimension: bench/dem_schedule.py scaling (bench/RESULTS.md, "Schedule")
BREAK_EVEN = {2: 360, 3: 840}
#: a bed gets two ranks only if it runs alone and two are modelled at least this much faster than one
RANKS_GAIN = 1.3
#: MPI ranks beyond the cores: each makes every rank wait for a time slice at each exchange, about this many times
#: the time of the bed on one rank (the 2D probe chute on 2 cores: 3 ranks 112x, 4 ranks 217x slower than one;
#: bench/RESULTS.md, "Schedule")
OVERSUBSCRIBED = 110


def speedup(n_grains: int, dim: int, np_: int, cores: int | None = None) -> float:
    """Modelled wall time of a bed of ``n_grains`` alone at one rank over that at ``np_`` ranks (strong scaling:
    the grains' work plus a halo exchange worth BREAK_EVEN grains per extra rank, shared by the ranks, or by the
    cores when the ranks outnumber them)."""
    used = min(np_, cores or os.cpu_count() or 1)
    return used * n_grains / (n_grains + (np_ - 1) * BREAK_EVEN[dim])


def ranks_per_bed(n_grains: int, dim: int, concurrent: int, np_: int | None = None, cores: int | None = None) -> int:
    """MPI ranks of each bed: ``np_`` when the user gives it; else two for a bed that runs alone (``concurrent``
    beds at a time is one) on two cores or more if ``speedup`` at two is at least RANKS_GAIN, and one otherwise
    (two ranks beside another bed would take its core)."""
    if np_ is not None:
        return np_
    cores = cores or os.cpu_count() or 1
    alone = concurrent == 1 and cores >= 2
    return 2 if alone and speedup(n_grains, dim, 2, cores) >= RANKS_GAIN else 1


def slowdown(processes: int, np_: int = 1, cores: int | None = None, contention: float = 1.0) -> float:
    """Wall time of each of ``processes`` concurrent LAMMPS processes of ``np_`` ranks over that of each alone
    (a process's own ranks are in its ``speedup``): two or more processes sharing the cores each run
    ``contention`` times slower (dem.throughput), more of them than the cores hold wait in turn, and MPI ranks
    beyond the cores cost OVERSUBSCRIBED times each."""
    cores = cores or os.cpu_count() or 1
    shared = contention if min(processes, cores) > 1 else 1.0
    beyond = max(0, processes * np_ - cores) if np_ > 1 else 0
    return shared * max(1.0, processes * min(np_, cores) / cores) * (1 + OVERSUBSCRIBED * beyond)


def makespan(work, jobs: int, np_: int = 1, cores: int | None = None, contention: float = 1.0) -> float:
    """Wall time of units of work (each its seconds alone) taken in order by ``jobs`` workers, every
    running unit slowed by ``slowdown`` of how many run at once."""
    pending, running, elapsed = list(work), [], 0.0
    while pending or running:
        while pending and len(running) < jobs:
            running.append(pending.pop(0))
        factor = slowdown(len(running), np_, cores, contention)
        first = min(running)
        elapsed += first * factor
        running = [w - first for w in running if w > first]
    return elapsed


def count(n: float) -> str:
    """A large count to two significant digits, e.g. 1.6e5."""
    return f"{n:.2g}".replace("e+0", "e").replace("e+", "e")
