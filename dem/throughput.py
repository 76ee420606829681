"""LAMMPS's throughput on this machine, for the cost estimates (dem.sizing): a short probe, cached.

Each phase of a scene (a bed's preparation, a drive with its outputs, a calibration's shear cell) runs at a
fixed fraction PHASE_RATIO of LAMMPS's granular chute benchmark of its dimension on the same machine
(``bench/dem_phase_rates.py`` measures the fractions, both in one invocation).  The probe times the chute of each
dimension here (PROBE_ATOMS grains, PROBE_STEPS steps after WARMUP) alone, then two copies at once: the rates
are PHASE_RATIO x the probe, and ``contention`` is how much slower each of two processes runs than one alone.
The probe takes a few seconds; its result is cached per host, core count and LAMMPS version for MAX_AGE seconds
(a shared machine's load changes) in $XDG_CACHE_HOME/granstokes/throughput.json (``~/.cache`` by default);
``granstokes dem probe`` renews it.
"""
from __future__ import annotations

import json
import math
import os
import platform
import re
import subprocess
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from . import lammps_env

#: grain-steps per second of a phase over the probe chute of its dimension on the same machine, measured by
#: bench/dem_phase_rates.py (bench/RESULTS.md, "Cost estimates")
PHASE_RATIO = {2: {"prepare": 1.32, "drive": 0.73, "shear": 0.95},
               3: {"prepare": 0.77, "drive": 0.47, "shear": 0.66}}
PROBE_ATOMS, PROBE_STEPS, WARMUP = {2: 800, 3: 4000}, {2: 20000, 3: 3000}, 1000
#: the chute benchmark's law (gran/hooke/history, k_n = 2e5, gamma_n = 50, friction 0.5), time step 1e-4,
#: gravity tilted 26 degrees from the vertical, a frozen bottom layer, equal unit-mass grains on a lattice
CHUTE = """units lj
atom_style sphere
dimension {dim}
boundary p {boundary}
newton off
comm_modify vel yes
lattice {lattice} 1.0
region box block 0 {nx} 0 {ny} {z}
create_box 2 box
create_atoms 1 box
set type 1 diameter 1.0
set type 1 density {density}
region low {low}
group bottom region low
set group bottom type 2
group active subtract all bottom
pair_style gran/hooke/history 200000.0 NULL 50.0 NULL 0.5 0
pair_coeff * *
neighbor 0.1 bin
neigh_modify every 1 delay 0
neigh_modify exclude group bottom bottom
timestep 0.0001
fix grav all gravity 1.0 {gravity}
fix freeze bottom freeze
fix nve active nve/sphere{disc}
{enforce}
thermo 1000
thermo_modify norm no lost ignore
run {warmup}
run {steps}
"""
#: unit-mass grains: sphere density 6/pi, disk (per unit thickness) 4/pi
DENSITY = {3: 6 / math.pi, 2: 4 / math.pi}
TILT = math.radians(26.0)
LATTICE_WIDTH = 40  # lattice sites across the chute (a 2D chute of many disks gets 200)
MAX_AGE = 3600.0  # seconds a cached probe stands for this machine


def chute_script(dim: int, atoms: int, steps: int, warmup: int = WARMUP) -> str:
    """The chute benchmark with about ``atoms`` grains: ``warmup`` steps off the lattice, then ``steps``."""
    nx = LATTICE_WIDTH if dim == 3 or atoms <= 1000 else 5 * LATTICE_WIDTH
    if dim == 3:
        shape = dict(boundary="p fm", lattice="sc", nx=nx, ny=20, z=f"0 {max(1, atoms // (nx * 20))}",
                     low="block INF INF INF INF INF 0.5", gravity="chute 26.0", disc="", enforce="")
    else:
        shape = dict(boundary="fm p", lattice="sq", nx=nx, ny=atoms // nx, z="-0.5 0.5",
                     low="block INF INF INF 0.5 INF INF", disc=" disc", enforce="fix plane all enforce2d",
                     gravity=f"vector {math.sin(TILT):.10f} {-math.cos(TILT):.10f} 0")
    return CHUTE.format(dim=dim, density=DENSITY[dim], warmup=warmup, steps=steps, **shape)


def timed(log: str) -> dict:
    """The last run of a LAMMPS log: atoms, steps, ranks, loop time and atom-steps/s per rank."""
    loop = re.findall(r"Loop time of (\S+) on (\d+) procs for (\d+) steps with (\d+) atoms", log)[-1]
    seconds, ranks, steps, atoms = float(loop[0]), int(loop[1]), int(loop[2]), int(loop[3])
    return {"atoms": atoms, "steps": steps, "ranks": ranks, "loop": seconds, "rate": atoms * steps / seconds / ranks}


class ProbeFailed(RuntimeError):
    """LAMMPS could not run the probe's chute (the message says where its log is)."""


def _run_chutes(dim: int, copies: int, work: Path) -> list[dict]:
    """``copies`` probe chutes of dimension ``dim`` at once, each on one rank; their timings."""
    procs = []
    for k in range(copies):
        d = work / f"chute-{dim}-{copies}-{k}"
        d.mkdir(parents=True)
        (d / "in.lammps").write_text(chute_script(dim, PROBE_ATOMS[dim], PROBE_STEPS[dim]))
        procs.append((d, subprocess.Popen([str(lammps_env.lmp_binary()), "-in", "in.lammps", "-log", "log.lammps",
                                           "-screen", "none", "-nocite"], cwd=d, env=lammps_env.child_env())))
    for d, p in procs:
        if p.wait() != 0:
            raise ProbeFailed(f"the throughput probe's LAMMPS run failed with exit code {p.returncode} "
                              f"({d / 'log.lammps'} says why)")
    return [timed((d / "log.lammps").read_text()) for d, _ in procs]


@dataclass(frozen=True)
class Throughput:
    """Grain-steps/s of one process alone at one rank, per dimension and phase, and the slowdown of each of two
    processes at once (``contention``), measured on ``host``."""

    rates: dict
    contention: float
    probe: dict
    host: str
    measured: str
    epoch: float = 0.0  # time.time() of the probe

    def rate(self, dim: int, phase: str) -> float:
        return self.rates[str(dim)][phase]

    def describe(self, dim: int) -> str:
        r = self.rates[str(dim)]
        return (f"{r['prepare'] / 1e6:.2g} M grain-steps/s preparing, {r['drive'] / 1e6:.2g} M driving, "
                f"{r['shear'] / 1e6:.2g} M shearing, two at once {self.contention:.2g}x slower each (probed on this "
                f"machine {self.measured})")


def probe(dimensions=(2, 3), together: bool = True) -> Throughput:
    """Time the chutes of ``dimensions`` alone and (``together``) two 2D ones at once (a few seconds)."""
    with tempfile.TemporaryDirectory(prefix="granstokes-probe-") as tmp:
        alone = {dim: _run_chutes(dim, 1, Path(tmp))[0]["rate"] for dim in dimensions}
        pair = [r["rate"] for r in _run_chutes(2, 2, Path(tmp))] if together else [alone.get(2, 1.0)] * 2
    contention = max(1.0, alone.get(2, 1.0) / (sum(pair) / len(pair)))
    rates = {str(dim): {phase: ratio * alone[dim] for phase, ratio in PHASE_RATIO[dim].items()}
             for dim in dimensions}
    return Throughput(rates, contention, {str(k): v for k, v in alone.items()} | {"two_at_once_2d": pair},
                      _host(), time.strftime("%Y-%m-%d %H:%M"), time.time())


def _host() -> str:
    return f"{platform.node()}/{os.cpu_count()} cores/LAMMPS {lammps_env.lammps_info()['lammps_version']}"


def cache_path() -> Path:
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "granstokes" / "throughput.json"


_KNOWN: dict[Path, Throughput] = {}  # this process's reads of the cache


def measured(renew: bool = False, announce=None) -> Throughput:
    """This machine's throughput: the cached probe of this host, core count and LAMMPS version if younger than
    MAX_AGE, else a new probe (``announce(line)`` is told first)."""
    path = cache_path()
    if not renew and path in _KNOWN and time.time() - _KNOWN[path].epoch < MAX_AGE:
        return _KNOWN[path]
    if not renew and path.is_file():
        try:
            cached = Throughput(**json.loads(path.read_text()))
            if cached.host == _host() and time.time() - cached.epoch < MAX_AGE:
                _KNOWN[path] = cached
                return cached
        except (ValueError, TypeError):
            pass
    if announce is not None:
        announce(f"probing LAMMPS's speed on this machine (a few seconds; cached for {MAX_AGE / 3600:g} h in {path})")
    result = probe()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}")
    tmp.write_text(json.dumps(asdict(result), indent=2))
    os.replace(tmp, path)
    _KNOWN[path] = result
    return result
