"""What a command will cost on this machine, said before any work: wall time by stage, one total, and disk.

Each stage's seconds come from its plan (dem.sizing, dem.calibrate, granstokes.study.plan) at the probed speed
(dem.throughput); ``Estimate`` adds them and the disk, and prints one line.  The estimate is for this machine as
probed; SHARED_STRETCH says how much longer the same command took beside other work: one more busy process per
core, measured by bench/dem_costs.py (bench/RESULTS.md, "DEM cost estimates").
"""
from __future__ import annotations

from dataclasses import dataclass

#: wall time of a command beside one other busy process per core over its wall time on an idle machine: the
#: smallest and largest over the presets, the quick calibration and the smoke studies (1.63-2.16 on 2 cores;
#: bench/dem_costs.py --shared, bench/RESULTS.md "DEM cost estimates")
SHARED_STRETCH = (1.6, 2.2)
#: a command's own wall time in seconds beyond its stages: Python's start, imports and inputs (0.7 s to the first
#: printed line of dem run and study, bench/dem_costs.py's logs) and, for a study, its Dask cluster's start and
#: shutdown (the smoke studies' measured wall time exceeds their stages' estimates by 4-9 s)
STARTUP = {"dem": 0.7, "study": 5.0}
#: durations up to this many seconds are printed in s, up to this many minutes in min, beyond in h
SECONDS_SHOWN, MINUTES_SHOWN = 90, 90


def duration_text(seconds: float) -> str:
    """``seconds`` as a readable duration in s, min or h (two significant digits, whole units from 100)."""
    value, unit = ((seconds, "s") if seconds < SECONDS_SHOWN else (seconds / 60, "min")
                   if seconds < MINUTES_SHOWN * 60 else (seconds / 3600, "h"))
    return f"{value:.2g} {unit}" if value < 100 else f"{value:.0f} {unit}"


def disk_text(size: float) -> str:
    """Bytes as kB, MB or GB (two significant digits, whole units from 100)."""
    value, unit = next(((size / f, u) for f, u in ((1e9, "GB"), (1e6, "MB"), (1e3, "kB")) if size >= f),
                       (size, "B"))
    return f"{value:.2g} {unit}" if value < 100 else f"{value:.0f} {unit}"


@dataclass(frozen=True)
class Estimate:
    """A command's stages as (what, seconds on this machine) and the bytes it writes."""

    stages: tuple[tuple[str, float], ...] = ()
    disk: float = 0.0

    def plus(self, what: str, seconds: float, disk: float = 0.0) -> Estimate:
        return Estimate((*self.stages, (what, seconds)), self.disk + disk)

    @property
    def seconds(self) -> float:
        return sum(s for _, s in self.stages)

    def line(self) -> str:
        """One line: the total wall time, its stages, the disk, and the stretch on shared cores."""
        parts = " + ".join(f"{what} {duration_text(s)}" for what, s in self.stages if s > 0)
        low, high = SHARED_STRETCH
        return (f"total: about {duration_text(self.seconds)} on this machine ({parts}) and {disk_text(self.disk)} "
                f"of disk; {low:g}-{high:g}x as long if another busy process shares each core")
