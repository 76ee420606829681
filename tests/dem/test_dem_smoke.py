"""The smoke scene run through LAMMPS: physics checks on its output, and kill + resume."""
import dataclasses
import json
import os
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest
from granstokes.compare.plate import PlateRecord
from granstokes.compare.plate import slip as plate_slip
from granstokes.dem import config, contact, lammps_env, layout, outputs, scene
from granstokes.dem.sizing import plan

from granstokes.cli import main as granstokes_main  # the `granstokes` console script

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def smoke(tmp_path_factory):
    out = tmp_path_factory.mktemp("dem") / "smoke"
    assert granstokes_main(["dem", "run", "--preset", "smoke", "--out", str(out), "--quiet"]) == 0
    return out, None


def test_smoke_completes_with_metadata(smoke):
    """(Its speed is in bench/RESULTS.md: no timed tests on a shared machine.)"""
    out, _ = smoke
    meta = json.loads((out / "run.json").read_text())
    assert meta["status"] == "complete"
    assert meta["stages"]["seed-1"]["info"]["relaxed"]
    assert "inertial_number" in meta["conventions"] and "dem_units" in meta["conventions"]
    assert meta["contact"]["dt_max"] == pytest.approx(meta["contact"]["t_c"] / 20)
    assert meta["sizing"]["dt"] <= meta["contact"]["dt_max"]
    assert meta["provenance"]["lammps_version"] > 0 and meta["plate"]["mass_per_area"] > 0
    assert (out / "config.toml").read_text() == config.preset_text("smoke")


def test_no_grain_lost(smoke):
    out, _ = smoke
    grains = pd.read_csv(out / "seed-1" / "prepare" / "grains.csv")
    counts = {int(text.split("NUMBER OF ATOMS\n")[1].split()[0])
              for _, text in layout.dump_snapshots(out / "seed-1" / "speed" / "atoms.dump")}
    assert counts == {len(grains)}


def test_disks_stay_in_the_plane_without_enforce2d(smoke):
    """A 2D drive has no fix enforce2d: every grain's z and v_z stay exactly zero in every snapshot, and every
    contact's dz and tangential force along z too (forces in the plane only)."""
    out, _ = smoke
    drive = out / "seed-1" / "speed"
    assert "enforce2d" not in (drive / "in.lammps").read_text()
    atoms = [layout.snapshot_table(text) for _, text in layout.dump_snapshots(drive / "atoms.dump")]
    contacts = [layout.snapshot_table(text) for _, text in layout.dump_snapshots(drive / "contacts.dump")]
    assert len(atoms) == len(contacts) > 100
    assert all((a[["z", "vz"]].to_numpy() == 0).all() for a in atoms)
    assert all((c[["dz", "ft_z"]].to_numpy() == 0).all() and (c["fn"] != 0).all() for c in contacts)


def test_preparation_ends_with_the_plate_landed_and_still(smoke):
    """Settling ends below its own threshold once the pile has landed; relax counts the plate's kinetic energy,
    so the prepared plate (row 0 of the drive) rests on the bed grains nested in its gaps, its speed within the
    bound its share of the threshold sets: 1/2 M u_y^2 <= ke_per_grain N m."""
    out, _ = smoke
    p = plan(config.preset("smoke")[0])
    c = p.config.prepare
    log = (out / "seed-1" / "prepare" / "log.lammps").read_text()
    settling = log.split("PHASE relax\n")[0]
    ke = [float(line.split()[2]) / p.n_grains / contact.grain_mass(1.0, 2)
          for line in settling.splitlines() if re.fullmatch(r"\s*\d+\s+\S+\s+\S+\s+\d+\s*", line)]
    assert max(ke) > 100 * c.settle_ke_per_grain > 100 * ke[-1]  # the column's fall; settled at the last check
    plate = pd.read_csv(out / "seed-1" / "speed" / "plate.csv").iloc[0]
    geometry = json.loads((out / "run.json").read_text())["plate"]
    n_bed = len(pd.read_csv(out / "seed-1" / "prepare" / "grains.csv").query("type == 1"))
    bound = np.sqrt(2 * c.ke_per_grain * n_bed * contact.grain_mass(1.0, 2) / geometry["mass"])
    assert plate["step"] == 0 and abs(plate["u_y"]) <= bound, (plate["u_y"], bound)
    assert plate["n_c"] >= geometry["grains"] / 2, plate["n_c"]


def test_pressure_grows_hydrostatically_from_p_w(smoke):
    """Time-averaged normal stress on horizontal planes (method of planes, the pressure of the paper's
    y momentum balance, eq. (2.6)) grows from p_w at the plate with slope phi rho_p g."""
    out, _ = smoke
    cfg, _ = config.preset("smoke")
    d = out / "seed-1" / "speed"
    plate, prof = pd.read_csv(d / "plate.csv"), pd.read_csv(d / "profiles.csv")
    mean = prof.groupby("y_plane").mean(numeric_only=True)
    offset = json.loads((out / "run.json").read_text())["plate"]["surface_offset"]
    surface = layout.plate_surface(plate["y"].mean(), offset)
    bins = mean[(mean.index >= cfg.box.base_thickness + 2.5) & (mean.index <= surface - 1.0)]
    depth = surface - bins.index.to_numpy()
    slope, intercept = np.polyfit(depth, bins["p_mop"], 1)
    phi = bins["phi"].mean()
    assert len(bins) >= 8
    assert slope == pytest.approx(phi * 1.0 * 1.0, rel=0.10), (slope, phi)  # phi rho_p g, DEM units
    assert intercept == pytest.approx(cfg.p_w, rel=0.10), intercept
    assert plate["f_y"].mean() == pytest.approx(cfg.p_w, rel=0.05)  # the bed carries the load p_w


def test_plate_held_at_speed_with_interval_averaged_forces(smoke):
    """The speed drive holds u_x (interval averages of a held speed: exact) and the distance follows;
    every sample averages the force over its whole interval, so its scatter is well below that of the
    single-step force (std ~ 0.7 of the mean, the plate resting on a few grains at any instant); the
    grains touching the plate move with it (slip <= 5 %, compare.plate.slip)."""
    out, _ = smoke
    meta = json.loads((out / "run.json").read_text())
    u_w, t_end = meta["sizing"]["drives"][0]["u_w"], meta["sizing"]["drives"][0]["duration"]
    plate = pd.read_csv(out / "seed-1" / "speed" / "plate.csv")
    moving = plate[plate["step"] > 0]
    assert np.allclose(moving["u_x"], u_w, rtol=1e-6)
    assert plate["x"].iloc[-1] - plate["x"].iloc[0] == pytest.approx(u_w * t_end, rel=0.01)
    assert moving["f_y"].std() < 0.35 * moving["f_y"].mean()
    slip = plate_slip(PlateRecord.read(out / "seed-1" / "speed"))
    # slip <= 5 %.  This bed slips 2.2 %; the preset's beds 1-4 slip 3.7 % on average with a
    # bed-to-bed spread of 1.4 % (bench/RESULTS.md), larger than this bed's block error (~0.9 %), so the
    # limit is asserted without a tolerance: it sits two spreads above this bed.  At p_w = 10 the beds
    # slip 5.9 +- 0.5 % and this assertion fails.
    assert -0.01 < slip["value"] <= 0.05, slip
    assert meta["sizing"]["elastic_start"]["transit_time"] == pytest.approx(
        meta["sizing"]["depth"] / meta["sizing"]["elastic_start"]["shear_wave_speed"])


def test_killed_run_resumes_with_continuous_output(tmp_path):
    """SIGKILL the whole run (runner and LAMMPS) mid-drive, resume, and find every output step once
    (the smoke scene, narrower and longer so that the kill lands mid-drive, in its denser early snapshots)."""
    text = config.preset_text("smoke").replace("duration = 7.0", "duration = 14.0").replace("width = 40.0",
                                                                                         "width = 16.0")
    text = text.replace("atoms = 0.04", "atoms = 0.4\nearly = 8.0\natoms_early = 0.04")
    cfg_path = tmp_path / "smoke-long.toml"
    cfg_path.write_text(text)
    out = tmp_path / "run"
    args = [sys.executable, "-m", "granstokes.cli", "dem", "run", str(cfg_path), "--out", str(out), "--quiet"]
    proc = subprocess.Popen(args, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    plate = out / "seed-1" / "speed" / "segments" / "000" / "plate.csv"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and proc.poll() is None:
        if plate.exists() and len(plate.read_text().splitlines()) > 300:  # past a few restarts (t ~ 6)
            break
        time.sleep(0.02)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    assert json.loads((out / "run.json").read_text())["status"] == "running"
    assert granstokes_main(["dem", "run", str(cfg_path), "--out", str(out), "--resume", "--quiet"]) == 0
    meta = json.loads((out / "run.json").read_text())
    info = meta["stages"]["seed-1/speed"]["info"]
    assert meta["status"] == "complete" and info["segments"] == 2 and info["resumed_from_step"] > 0
    df = pd.read_csv(out / "seed-1" / "speed" / "plate.csv")
    steps = df["step"].to_numpy()
    every = meta["sizing"]["intervals_steps"]["plate"]
    assert steps[0] == 0 and np.all(np.diff(steps) == every)
    assert steps[-1] == meta["sizing"]["drives"][0]["steps"] // every * every
    snaps = np.array([s for s, _ in layout.dump_snapshots(out / "seed-1" / "speed" / "atoms.dump")])
    iv = meta["sizing"]["intervals_steps"]
    assert iv["atoms"] == 10 * iv["atoms_early"] and iv["early"] > info["resumed_from_step"]
    assert snaps[0] == 0 and np.all(np.diff(snaps[snaps <= iv["early"]]) == iv["atoms_early"])
    late = snaps[snaps >= iv["early"]]
    assert late[0] == iv["early"] and np.all(np.diff(late) == iv["atoms"])
    prof = pd.read_csv(out / "seed-1" / "speed" / "profiles.csv")
    assert np.all(np.diff(np.unique(prof["step"])) == meta["sizing"]["intervals_steps"]["profiles"])
    assert not (out / "seed-1" / "speed" / "segments").exists()


def test_contact_dump_balances_the_static_bed(smoke):
    """At step 0 (the relaxed bed) the contact forces through any horizontal plane, read from the
    contact dump (normal + tangential, force on grain 1 as documented), carry the plate load p_w and
    the weight of the bed grains above the plane: checks the dump's columns and sign conventions."""
    out, _ = smoke
    d = out / "seed-1" / "speed"
    area = json.loads((out / "run.json").read_text())["plate"]["area"]
    atoms = layout.snapshot_table(next(layout.dump_snapshots(d / "atoms.dump"))[1])
    grains = pd.read_csv(out / "seed-1" / "prepare" / "grains.csv").set_index("id")
    plate_y = atoms.loc[atoms["type"] == 3, "y"].mean()
    planes = np.arange(4.0, plate_y - 2.0, 1.0)
    stress = outputs.plane_stress(d, planes, area)
    first = stress[stress["step"] == 0]
    f_y = json.loads((out / "run.json").read_text())["config"]["p_w"]  # the applied load (plate.csv's row 0
    # carries the damping of the speed drive's impulsive start: the plate is set moving at step 0)
    bed = atoms[atoms["type"] == 1]
    mass = grains["mass"].reindex(bed["id"]).to_numpy()
    weight_above = np.array([mass[bed["y"].to_numpy() > y].sum() / area for y in planes])
    assert np.allclose(first["p_yy"], f_y + weight_above, rtol=0.03)
    assert np.all(np.abs(first["tau_xy"]) < 0.05 * first["p_yy"])


def test_sigterm_interrupts_with_status_143_and_says_so(tmp_path):
    """SIGTERM to the runner mid-drive: exit status 143, run.json says interrupted (never running), the last line
    the command that continues it."""
    out = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-m", "granstokes.cli", "dem", "run", "--preset", "smoke", "--out",
                             str(out), "--quiet"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if list(out.glob("seed-*/*/segments/000/plate.csv")):
            break
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    meta = json.loads((out / "run.json").read_text())
    assert proc.returncode == 143 and meta["status"] == "interrupted" and "SIGTERM" in meta["message"], (meta, err)
    assert "Traceback" not in err and "CancelledError" not in err
    assert err.splitlines()[-1] == f"dem: interrupted (SIGTERM); continue with: granstokes dem run --resume --out {out}"


def test_seeds_run_side_by_side_under_a_launcher_template(tmp_path):
    """Two independent beds (seeds 1, 2) as concurrent LAMMPS processes (jobs 2, one rank each) under a
    launcher template (the mpich wheel's mpirun standing in for srun): both complete, and they are
    different beds (different random packings, so different plate records)."""
    text = (config.preset_text("smoke").replace("seeds = [1]", "seeds = [1, 2]").replace("width = 40.0", "width = 8.0")
            .replace("depth = 12.0", "depth = 6.0").replace("duration = 7.0", "duration = 0.35"))
    cfg_path = tmp_path / "pair.toml"
    cfg_path.write_text(text)
    out = tmp_path / "run"
    launcher = f"{lammps_env.mpirun()} -np {{np}}"
    assert granstokes_main(["dem", "run", str(cfg_path), "--out", str(out), "--quiet", "--jobs", "2", "--np", "1",
                            "--launcher", launcher]) == 0
    meta = json.loads((out / "run.json").read_text())
    assert meta["provenance"]["jobs"] == 2 and meta["provenance"]["launcher"].endswith("-np 1")
    assert all(st["status"] == "complete" for st in meta["stages"].values()) and len(meta["stages"]) == 4
    plates = [pd.read_csv(out / f"seed-{s}" / "speed" / "plate.csv") for s in (1, 2)]
    assert len(plates[0]) == len(plates[1]) and not np.allclose(plates[0]["f_x"], plates[1]["f_x"])


def test_sampled_plate_averages_are_unbiased_against_every_step(smoke, tmp_path):
    """The plate's interval means sampled every half contact time (dem.sizing SAMPLES_PER_CONTACT) against
    every-step means of the same trajectory: per interval they track each other, and over the record their
    difference is within its standard error (intervals ~ 5 contact times apart: independent)."""
    out, _ = smoke
    p = plan(config.preset("smoke")[0])
    every, sample = p.intervals["plate"], p.intervals["sample"]
    assert sample > 1 and every % sample == 0
    drive = dataclasses.replace(p.drives[0], steps=60 * every, duration=60 * every * p.dt)
    script = scene.drive_script(p, drive, str(out / "seed-1" / "prepare" / "prepared.restart"), fresh=True)
    # the drive samples the plate's velocity, its x and y force and the bed grains touching it (u_c's sum, n_c)
    assert (f"ave/time {sample} {every // sample} {every} v_pux v_puy f_load[1] f_load[2] c_touch_sums[1] "
            "c_touch_sums[2]\n") in script
    values = "f_load[1] f_load[2] c_touch_sums[2]"
    both = (f"fix every_step all ave/time 1 {every} {every} {values} file every_step.txt\n"
            f"fix sampled all ave/time {sample} {every // sample} {every} {values} file sampled.txt\n")
    head, run_line = script.rsplit("\nrun ", 1)
    work = tmp_path / "drive" / "segment"  # the script writes its restarts to ../../restart, as in a run folder
    work.mkdir(parents=True)
    (tmp_path / scene.RESTART_DIR).mkdir()
    (work / "in.lammps").write_text(f"{head}\n{both}run {run_line}")
    subprocess.run([str(lammps_env.lmp_binary()), "-in", "in.lammps", "-log", "log.lammps", "-nocite"],
                   cwd=work, env=lammps_env.child_env(), check=True, stdout=subprocess.DEVNULL)
    read = lambda name: np.loadtxt(work / name, comments="#")[:, 1:]
    full, sampled = read("every_step.txt"), read("sampled.txt")
    assert full.shape == sampled.shape == (60, 3)
    for k in range(3):
        diff = sampled[:, k] - full[:, k]
        assert abs(diff.mean()) <= 3 * diff.std(ddof=1) / np.sqrt(len(diff)), (k, diff.mean(), diff.std())
        assert np.corrcoef(sampled[:, k], full[:, k])[0, 1] > 0.8, k
