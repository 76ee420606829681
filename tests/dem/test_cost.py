"""The cost estimate printed before a run or a calibration (dem.sizing): the schedule, the units, what a
resume has left, and the estimate against a measured smoke run."""
import json
import math
import os
import re

import pytest
from granstokes.dem import config, scene, sizing
from granstokes.dem.calibrate import plan_calibration
from granstokes.dem.estimate import duration_text
from granstokes.dem.sizing import OVERHEAD, makespan, plan, ranks_per_bed, slowdown, speedup
from granstokes.dem.throughput import Throughput

from granstokes.lib.toml_text import with_entries

#: a machine's speed for the schedule's arithmetic (the real one is probed: dem.throughput)
SPEED = Throughput({"2": {"prepare": 10e6, "drive": 8e6, "shear": 9e6}, "3": {"prepare": 6e6, "drive": 5e6,
                                                                          "shear": 7e6}},
                   1.6, {}, "test", "test")
CONTENTION = SPEED.contention

#: preparation's expected steps hold for one bed within this fraction (its settling varies with the seed:
#: SETTLE_RELAX_EXPECTED is a mean); a drive's steps within this one (the last output interval)
PREPARE_TOLERANCE, DRIVE_TOLERANCE = 0.3, 0.01


def test_two_processes_share_two_cores_and_more_wait():
    assert slowdown(1, cores=2, contention=CONTENTION) == 1.0
    assert slowdown(2, cores=2, contention=CONTENTION) == CONTENTION
    assert slowdown(1, np_=2, cores=2, contention=CONTENTION) == 1.0  # a process's own ranks: its speedup
    # MPI ranks beyond the cores wait for time slices
    assert slowdown(1, np_=3, cores=2, contention=CONTENTION) == 1 + sizing.OVERSUBSCRIBED
    assert slowdown(2, np_=2, cores=2, contention=CONTENTION) == pytest.approx(2 * CONTENTION
                                                                               * (1 + 2 * sizing.OVERSUBSCRIBED))
    assert slowdown(4, cores=2, contention=CONTENTION) == pytest.approx(2 * CONTENTION)
    assert slowdown(2, cores=1, contention=CONTENTION) == 2.0  # one core: turns, no shared cache to fight over


def test_beds_are_whole_units_spread_over_the_jobs():
    """Three equal beds on two workers: two at once, then the third alone (not 1.5 beds' time)."""
    assert makespan([10.0] * 3, 2, cores=2, contention=CONTENTION) == pytest.approx(10 * CONTENTION + 10)
    assert makespan([10.0] * 3, 1, cores=2, contention=CONTENTION) == pytest.approx(30)
    assert makespan([10.0] * 4, 2, cores=2, contention=CONTENTION) == pytest.approx(20 * CONTENTION)
    # unequal units: the short one ends first, the long one finishes alone
    assert makespan([10.0, 4.0], 2, cores=2, contention=CONTENTION) == pytest.approx(4 * CONTENTION + 6)
    assert makespan([], 2) == 0.0


@pytest.mark.parametrize("dim", [2, 3])
def test_two_ranks_go_to_a_bed_alone_that_they_speed_up(dim):
    """The strong-scaling model breaks even at BREAK_EVEN grains; two ranks only for a bed that runs alone on two
    cores with a modelled speed-up of at least RANKS_GAIN; the user's --np always wins."""
    n_star = sizing.BREAK_EVEN[dim]
    assert speedup(n_star, dim, 2, cores=2) == pytest.approx(1.0)
    assert speedup(n_star, dim, 1, cores=2) == 1.0
    assert speedup(100 * n_star, dim, 2, cores=2) == pytest.approx(2 * 100 / 101)
    # ranks beyond the cores: their halos are paid, on the cores there are
    assert speedup(n_star, dim, 64, cores=2) == pytest.approx(2 / 64)
    enough = sizing.RANKS_GAIN / (2 - sizing.RANKS_GAIN) * n_star  # speedup(enough, 2) == RANKS_GAIN
    assert ranks_per_bed(round(1.01 * enough), dim, concurrent=1, cores=2) == 2
    assert ranks_per_bed(round(0.99 * enough), dim, concurrent=1, cores=2) == 1
    assert ranks_per_bed(100 * n_star, dim, concurrent=2, cores=2) == 1  # beside another bed
    assert ranks_per_bed(100 * n_star, dim, concurrent=1, cores=1) == 1
    assert ranks_per_bed(10, dim, concurrent=2, np_=64, cores=2) == 64


def test_the_estimate_runs_each_bed_on_the_ranks_the_run_uses():
    """One bed alone on the rule's ranks: its time over the modelled speed-up; an explicit --np oversubscribing two
    cores is charged for the ranks that wait."""
    p = plan(config.preset("quick")[0])
    bed = sum(p.stage_seconds(k, SPEED) for k in p.stage_keys(1))
    one = plan(config.parse(with_entries(config.preset_text("quick"), [("seeds", [1])])))
    np_ = one.ranks(jobs=2)
    assert np_ == ranks_per_bed(one.n_grains, 2, concurrent=1)
    assert one.cost_seconds(jobs=2, speed=SPEED) == pytest.approx(OVERHEAD + bed / speedup(one.n_grains, 2, np_))
    cores = os.cpu_count()
    gain = min(64, cores) * p.n_grains / (p.n_grains + 63 * sizing.BREAK_EVEN[2])
    two, one = (slowdown(k, 64, cores, CONTENTION) for k in (2, 1))  # two beds at once, then the third
    assert p.cost_seconds(jobs=2, np_=64, speed=SPEED) == pytest.approx(OVERHEAD + (two + one) * bed / gain)
    assert p.cost_seconds(jobs=2, np_=64, speed=SPEED) > 100 * bed  # each rank beyond the cores waits


def test_a_run_takes_the_rules_ranks_unless_given(tmp_path):
    """A quick bed alone gets two ranks (885 disks: modelled 1.4x on two cores), three quick beds on two slots one
    each, a smoke bed alone one (543 disks: 1.2x); --np wins."""
    from granstokes.dem.runner import check_request

    one = with_entries(config.preset_text("quick"), [("seeds", [1])])
    two = 2 if os.cpu_count() >= 2 else 1
    assert check_request(plan(config.parse(one)), one, tmp_path / "a", jobs=2).lmp.np == two
    assert check_request(plan(config.parse(one)), one, tmp_path / "b", np=3, jobs=2).lmp.np == 3
    three = config.preset_text("quick")
    assert check_request(plan(config.parse(three)), three, tmp_path / "c", jobs=2).lmp.np == 1
    assert check_request(plan(config.parse(three)), three, tmp_path / "d", jobs=1).lmp.np == two  # one at a time
    smoke = config.preset_text("smoke")
    assert check_request(plan(config.parse(smoke)), smoke, tmp_path / "e", jobs=2).lmp.np == 1


@pytest.mark.parametrize("seconds, text", [(9.44, "9.4 s"), (89, "89 s"), (150, "2.5 min"), (5300, "88 min"),
                                           (5500, "1.5 h"), (4e5, "111 h")])
def test_durations_read_in_seconds_minutes_or_hours(seconds, text):
    assert duration_text(seconds) == text


def test_preparation_counts_its_expected_steps_not_its_cap():
    p = plan(config.preset("smoke")[0])
    c = p.config.prepare
    expected, most = p.prepare_steps
    assert expected == p.free_fall_steps + round(sizing.SETTLE_RELAX_EXPECTED / p.dt)
    assert p.settle_steps_max == math.ceil(sizing.FALL_MARGIN * p.free_fall_steps + c.settle_max / p.dt)
    assert most == p.settle_steps_max + round(c.relax_max / p.dt)
    # the script's settling loop (fall included) runs up to its cap in chunks of the check interval
    loops = [int(n) for n in re.findall(r"variable i loop (\d+)", scene.prepare_script(p, 1))]
    check = p.intervals["check"]
    assert loops[0] == math.ceil(p.settle_steps_max / check) and "\nrun " + str(p.free_fall_steps) not in \
        scene.prepare_script(p, 1)
    assert p.stage_seconds("seed-1", SPEED) == pytest.approx(p.n_grains * expected / SPEED.rate(2, "prepare"))
    assert p.stage_seconds("seed-1/speed", SPEED) == pytest.approx(p.n_grains * p.drives[0].steps
                                                                   / SPEED.rate(2, "drive"))


def test_the_estimate_follows_the_schedule_and_what_is_left():
    p = plan(config.preset("quick")[0])
    bed = sum(p.stage_seconds(k, SPEED) for k in p.stage_keys(1))
    assert p.cost_seconds(jobs=2, np_=1, speed=SPEED) == pytest.approx(OVERHEAD + bed * CONTENTION + bed)
    assert p.cost_seconds(jobs=1, np_=1, speed=SPEED) == pytest.approx(OVERHEAD + 3 * bed)
    gain = speedup(p.n_grains, 2, p.ranks(1))  # one at a time: each bed alone, on the rule's ranks
    assert p.cost_seconds(jobs=1, speed=SPEED) == pytest.approx(OVERHEAD + 3 * bed / gain)
    done = {"seed-1", "seed-1/stress", "seed-1/speed", "seed-2"}
    left = bed - p.stage_seconds("seed-2", SPEED)
    assert p.cost_seconds(jobs=2, done=done, speed=SPEED) == pytest.approx(OVERHEAD + left * CONTENTION + (bed - left))
    line = p.cost_estimate(jobs=2, done=done, speed=SPEED)
    assert line.startswith(f"cost: {p.n_grains} grains x 3 bed(s)") and "of what is left" in line
    everything = {k for s in p.config.seeds for k in p.stage_keys(s)}
    assert p.cost_estimate(jobs=2, done=everything, speed=SPEED) == "cost: none, every stage is complete"


def test_a_calibration_runs_its_cells_longest_first_over_the_jobs():
    cp = plan_calibration(config.preset("smoke")[0])
    work = [cp.task_seconds(k, speed=SPEED) for k, _ in cp.tasks()]
    assert work == sorted(work, reverse=True) and len(work) == len(cp.points)
    # the shear modulus's cells (dem.modulus: at least 3 seeds, the preset's one and the next two) among them
    assert cp.modulus_seeds == (1, 2, 3) and cp.modulus_seconds(SPEED) > 0
    work = sorted(work + [cp.modulus_seconds(SPEED)] * 3, reverse=True)
    assert cp.cost_seconds(jobs=1, speed=SPEED) == pytest.approx(OVERHEAD + sum(work))
    assert cp.cost_seconds(jobs=2, speed=SPEED) == pytest.approx(OVERHEAD + makespan(work, 2, contention=CONTENTION))
    assert cp.cost_seconds(jobs=2, speed=SPEED) < cp.cost_seconds(jobs=1, speed=SPEED)
    shear = {cp.key(k, s) for k, s in cp.tasks()}
    assert cp.cost_estimate(done=shear, speed=SPEED) != "cost: none, every point is complete"
    assert cp.cost_estimate(done=set(cp.keys()), speed=SPEED) == "cost: none, every point is complete"


@pytest.mark.slow
def test_the_estimate_counts_the_steps_lammps_runs(smoke_run):
    """The smoke preset's schedule against what LAMMPS ran (run.json): the drive's steps, and preparation's
    between its free fall and its cap, near the expected count (machine-independent)."""
    meta = json.loads((smoke_run / "run.json").read_text())
    p = plan(config.parse((smoke_run / "config.toml").read_text()))
    expected, most = p.prepare_steps
    ran = meta["stages"]["seed-1"]["info"]["lammps"]["last_step"]
    assert p.free_fall_steps < ran <= most
    assert abs(ran / expected - 1) <= PREPARE_TOLERANCE, (ran, expected)
    drive = p.drives[0]
    driven = meta["stages"][f"seed-1/{drive.drive.name}"]["info"]["last_step"]
    assert abs(driven / drive.steps - 1) <= DRIVE_TOLERANCE, (driven, drive.steps)
    # the disk each stage writes, from the rows of its outputs (dem.outputs.ROW_BYTES): the drive's folder within
    # DISK_TOLERANCE (its dumps are 98 % of it), the preparation's (a restart and a log) the right size
    for key, folder in ((f"seed-1/{drive.drive.name}", drive.drive.name), ("seed-1", "prepare")):
        written = sum(f.stat().st_size for f in (smoke_run / "seed-1" / folder).rglob("*") if f.is_file())
        assert abs(p.stage_bytes(key) / written - 1) <= DISK_TOLERANCE[folder], (key, p.stage_bytes(key), written)


#: a stage's estimated bytes hold its folder within these fractions (a drive's rows are counted exactly; a bed's
#: preparation log varies with its settling)
DISK_TOLERANCE = {"prepare": 0.3, "speed": 0.15}


def test_the_total_sums_the_stages_and_quotes_the_shared_stretch():
    """One line: the stages' seconds added (each shown), the disk in MB, the measured stretch on shared cores."""
    from granstokes.dem.estimate import SHARED_STRETCH, Estimate, disk_text

    e = Estimate().plus("calibration", 30.0, 1.5e6).plus("beds", 80.0, 2.0e8).plus("start-up", 5.0)
    assert e.seconds == 115.0 and e.disk == pytest.approx(2.015e8)
    low, high = SHARED_STRETCH
    assert e.line() == (f"total: about {duration_text(115.0)} on this machine (calibration 30 s + beds 80 s + "
                        f"start-up 5 s) and 202 MB of disk; {low:g}-{high:g}x as long if another busy process "
                        "shares each core")
    assert [disk_text(x) for x in (512, 1.5e6, 2.5e9)] == ["512 B", "1.5 MB", "2.5 GB"]
    assert 1 < low <= high


#: the estimate from this machine's probed speed holds a measured run within this fraction of its wall time
ESTIMATE_TOLERANCE = 0.3


@pytest.mark.slow
def test_the_estimate_from_the_probe_holds_a_smoke_run(tmp_path):
    """A short smoke run's LAMMPS wall time (its stages, alone at one rank) against the estimate at this machine's
    speed probed just before and just after it (the mean of the two: the load may change): within
    ESTIMATE_TOLERANCE whatever the machine, since the probe measures it."""
    import statistics

    from granstokes.dem.runner import run
    from granstokes.dem.throughput import Throughput, probe

    text = config.preset_text("smoke").replace("duration = 7.0", "duration = 3.0")
    p = plan(config.parse(text))
    before = probe((2,), together=False)
    result = run(p, text, tmp_path / "run", progress=False, jobs=1)
    after = probe((2,), together=False)
    rates = {"2": {k: statistics.mean([before.rate(2, k), after.rate(2, k)]) for k in ("prepare", "drive")}}
    speed = Throughput(rates, 1.0, {}, "test", "test")
    wall = sum(st["wall_time"] for st in result.stages.values())
    estimate = sum(p.stage_seconds(k, speed) for k in p.stage_keys(1))
    assert result.ok and abs(estimate / wall - 1) <= ESTIMATE_TOLERANCE, (estimate, wall, before.probe, after.probe)


def test_a_fresh_cached_probe_of_this_host_is_reused(tmp_path, monkeypatch):
    """The cache stands for this host while younger than MAX_AGE (no LAMMPS run); its rates are what sizing uses."""
    import dataclasses
    import time

    from granstokes.dem import throughput

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    path = throughput.cache_path()
    path.parent.mkdir(parents=True)
    cached = dataclasses.replace(SPEED, host=throughput._host(), epoch=time.time())
    path.write_text(json.dumps(dataclasses.asdict(cached)))
    assert throughput.measured() == cached
    p = plan(config.preset("smoke")[0])
    assert p.stage_seconds("seed-1") == p.stage_seconds("seed-1", SPEED)
