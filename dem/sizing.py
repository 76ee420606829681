"""Scene sizing from the continuum prediction (continuum.scales): depth, grain count, durations, steps.

* bed depth (base top to plate) >= max over drives of delta_s + margin (default 10 d, about three
  creep decay lengths of 2.5-3 d measured below the flowing layer), unless the config gives it;
* duration of a drive = duration_ts * t_s (default 10 t_s, t_s = delta_s^2/nu_g), unless given;
* a speed drive with mu_w_tilde runs at the matching steady speed u_w = U u~_w^inf(mu_w).
Every choice is written into run.json with its reason.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from continuum.scales import Scales
from continuum.steady import steady_wall_speed
from granstokes.validate import require

from .config import Config, Drive
from .contact import grain_volume

#: packing fractions used to turn a bed depth into a grain count (random close packing, loose side)
PACKING = {2: 0.80, 3: 0.60}
#: LAMMPS counts the steps of a run in a 32-bit integer ("Invalid run command N value" above it)
MAX_STEPS = 2**31 - 1
#: serial LAMMPS throughput on this kind of machine, atom-steps per second (bench/RESULTS.md: 2D 10.4-10.8 M,
#: 3D 6.9 M, one rank): the cost estimate printed before a run
THROUGHPUT = {2: 10e6, 3: 7e6}


def drive_scales(cfg: Config, drive: Drive) -> Scales:
    """The paper's scales of a drive (mu_w from mu_w/mu_w_tilde, or from the imposed speed)."""
    m, fr = cfg.material, cfg.material.friction
    if drive.u_w is not None:
        return Scales.for_speed(m, cfg.p_w, drive.u_w)
    mu_w = fr.mu_w_from_tilde(drive.mu_w_tilde) if drive.mu_w_tilde is not None else drive.mu_w
    return Scales(m, cfg.p_w, mu_w)


@dataclass(frozen=True)
class DrivePlan:
    drive: Drive
    scales: Scales
    duration: float
    steps: int
    tau_w: float | None  # imposed shear stress (stress drive)
    u_w: float | None  # imposed plate speed (speed drive)
    reason: str

    def as_dict(self) -> dict:
        return {"name": self.drive.name, "kind": self.drive.kind, "duration": self.duration, "steps": self.steps,
                "tau_w": self.tau_w, "u_w": self.u_w, "expected": self.scales.as_dict(), "reason": self.reason}


@dataclass(frozen=True)
class Plan:
    """Everything the scene writer and the runner need, derived once from a validated Config."""

    config: Config
    depth: float
    n_grains: int
    dt: float
    intervals: dict  # output name -> steps
    drives: tuple[DrivePlan, ...]
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
    def atom_steps(self) -> float:
        """grains x steps of the whole run: every seed's preparation (at most) and drives."""
        c = self.config.prepare
        prepare = (c.settle_max + c.relax_max) / self.dt
        return float(len(self.config.seeds) * self.n_grains * (prepare + sum(d.steps for d in self.drives)))

    def cost_estimate(self, jobs: int = 1) -> str:
        """One line: the run's atom-steps and the expected wall time at the measured throughput."""
        minutes = self.atom_steps / THROUGHPUT[self.dimension] / max(1, jobs) / 60
        return (f"cost: {self.n_grains} grains x {len(self.config.seeds)} seed(s), {self.atom_steps:.3g} atom-steps "
                f"(preparation at most), about {minutes:.2g} min with {jobs} job(s) at "
                f"{THROUGHPUT[self.dimension]:.2g} atom-steps/s per job (bench/RESULTS.md)")

    def as_dict(self) -> dict:
        return {"depth": self.depth, "n_grains_target": self.n_grains, "width": self.config.box.width,
                "elastic_start": {"shear_wave_speed": self.config.contact.shear_wave_speed,
                                  "transit_time": self.transit_time,
                                  "derivation": "depth / c_s, c_s = d sqrt(k_t/m) with m a mean grain's mass: the "
                                                "time the shear load takes to reach the base through the elastic "
                                                "deposited bed"},
                "width_z": self.config.width_z, "plate_area": self.area, "dt": self.dt,
                "intervals_steps": self.intervals, "drives": [d.as_dict() for d in self.drives],
                "reasons": list(self.reasons)}


def plan(cfg: Config) -> Plan:
    """Size the scene; raises ValueError (naming the drive) when a load is outside mu(I)'s range."""
    dt = cfg.time_step
    c = cfg.contact
    reasons = [f"dt = {dt:.4g} ({'given' if cfg.dt else 'default'}; bound t_c/20 = {c.dt_max:.4g}, "
               f"t_c = {c.t_c:.4g}, k_n = {c.k_n:.4g} from kappa = {c.kappa:g})"]
    drives = []
    for d in cfg.drives:
        try:
            s = drive_scales(cfg, d)
        except ValueError as exc:
            raise ValueError(f"drive[{d.name}]: {exc}") from None
        if d.duration is not None:
            duration, why = d.duration, "given"
        else:
            duration = max(d.duration_ts * s.t_s, d.min_duration)
            why = f"max({d.duration_ts:g} t_s, min_duration {d.min_duration:g}), t_s = {s.t_s:.4g}"
        tau_w = s.mu_w * cfg.p_w if d.kind == "stress" else None
        u_w = None
        if d.kind == "speed":
            u_w = d.u_w if d.u_w is not None else s.U * steady_wall_speed(cfg.material.friction, s.mu_w)
        steps = max(1, round(duration / dt))
        require(steps <= MAX_STEPS, f"drive[{d.name}] duration", f"at most {MAX_STEPS * dt:.4g} time units "
                f"({MAX_STEPS} steps of dt = {dt:.4g}, LAMMPS's limit)", duration)
        reason = (f"drive {d.name}: mu_w = {s.mu_w:.4g} (mu~_w = {s.mu_w_tilde:.3g}), delta_s = {s.delta_s:.3g} d, "
                  f"t_s = {s.t_s:.3g}, U = {s.U:.3g}; duration {duration:.4g} ({why}); "
                  + (f"tau_w = {tau_w:.4g}" if tau_w is not None else f"u_w = {u_w:.4g}"))
        drives.append(DrivePlan(d, s, duration, steps, tau_w, u_w, reason))
        reasons.append(reason)
    delta_max = max(p.scales.delta_s for p in drives)
    if cfg.box.depth is not None:
        depth = cfg.box.depth
        reasons.append(f"depth {depth:g} d (given; largest delta_s = {delta_max:.3g} d)")
    else:
        depth = math.ceil(delta_max + cfg.box.margin)
        reasons.append(f"depth {depth:g} d = ceil(largest delta_s {delta_max:.3g} d + margin {cfg.box.margin:g} d)")
    dim = cfg.grains.dimension
    w = cfg.grains.polydispersity
    moment = ((1 + w) ** (dim + 1) - (1 - w) ** (dim + 1)) / ((dim + 1) * 2 * w) if w > 0 else 1.0
    mean_volume = moment * grain_volume(1.0, dim)  # <d^D> over diameters uniform by number
    total = (depth + cfg.box.base_thickness) * cfg.box.width * (cfg.width_z or 1.0)
    n_grains = max(1, round(PACKING[dim] * total / mean_volume))
    reasons.append(f"{n_grains} grains fill base ({cfg.box.base_thickness:g} d) + bed at packing {PACKING[dim]}; "
                   f"width {cfg.box.width:g} d (minimum 8 d)" + (f", width_z {cfg.width_z:g} d" if cfg.width_z else ""))
    plate_steps = max(1, round(cfg.output.plate / dt))
    intervals = {k: max(1, round(getattr(cfg.output, k) / dt / plate_steps)) * plate_steps
                 for k in ("plate", "thermo", "atoms", "contacts", "profiles")}
    # contact snapshots coincide with atom snapshots (plane stresses need the positions)
    intervals["contacts"] = max(1, round(intervals["contacts"] / intervals["atoms"])) * intervals["atoms"]
    # restarts fall on profile-window boundaries so that a resumed run loses no averaging window
    intervals["restart"] = max(1, round(cfg.output.restart / dt / intervals["profiles"])) * intervals["profiles"]
    intervals["check"] = max(1, round(cfg.prepare.check_every / dt))
    return Plan(cfg, float(depth), n_grains, dt, intervals, tuple(drives), tuple(reasons))
